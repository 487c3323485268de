//! Property tests of the v1 codec (proptest): round trips of every packet shape, decoding
//! independent of chunking, garbage tolerance (never a panic, every byte accounted for, clean
//! packets after garbage found) and the bounded buffer; plus a seeded stress run over
//! mutated streams.

use droidctl::protocol::v1::decoder::DEFAULT_MAX_ASYNC_DLEN;
use droidctl::protocol::v1::packet::{self, SOP1};
use droidctl::protocol::v1::{
    AsyncPacket, CommandPacket, DecodeError, Decoder, ErrorKind, Mrsp, Packet, Response, Source,
    StreamingConfig, decode_async, describe, to_json,
};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::FileFailurePersistence;

type Event = Result<Packet, DecodeError>;

/// Bytes with the framing values much more likely than 1 in 256.
fn byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        3 => any::<u8>(),
        1 => prop::sample::select(vec![0xFF, 0xFE, 0xF8, 0x00, 0x01]),
    ]
}

fn arb_command() -> impl Strategy<Value = Packet> {
    (0xF8..=0xFFu8, byte(), byte(), byte(), vec(byte(), 0..=64)).prop_map(
        |(sop2, did, cid, seq, data)| {
            Packet::Command(CommandPacket {
                sop2,
                did,
                cid,
                seq,
                data,
            })
        },
    )
}

fn arb_response() -> impl Strategy<Value = Packet> {
    (byte(), byte(), vec(byte(), 0..=64)).prop_map(|(mrsp, seq, data)| {
        Packet::Response(Response {
            mrsp: Mrsp::from_byte(mrsp),
            seq,
            data,
        })
    })
}

/// Async messages, some longer than a one-byte DLEN could count.
fn arb_async() -> impl Strategy<Value = Packet> {
    (
        byte(),
        prop_oneof![4 => vec(byte(), 0..=48), 1 => vec(byte(), 250..=400)],
    )
        .prop_map(|(id, data)| Packet::Async(AsyncPacket::new(id, data)))
}

fn arb_droid_packet() -> impl Strategy<Value = Packet> {
    prop_oneof![arb_response(), arb_async()]
}

fn arb_source() -> impl Strategy<Value = Source> {
    prop_oneof![Just(Source::Host), Just(Source::Droid)]
}

fn wire(p: &Packet) -> Vec<u8> {
    p.encode().expect("generated packets fit")
}

/// Sorted cut positions in `0..=len` from proptest indices.
fn cut_points(len: usize, idx: &[Index]) -> Vec<usize> {
    let mut cuts: Vec<usize> = idx.iter().map(|i| i.index(len + 1)).collect();
    cuts.sort_unstable();
    cuts
}

/// Decode in chunks, checking the buffer bound after every chunk; `finish` included.
fn decode_chunked(d: &mut Decoder, stream: &[u8], cuts: &[usize]) -> Vec<Event> {
    let mut out = Vec::new();
    let mut start = 0;
    for &cut in cuts.iter().chain(std::iter::once(&stream.len())) {
        out.extend(d.feed(&stream[start..cut]));
        assert!(d.buffered() <= d.max_packet_len(), "{}", d.buffered());
        start = cut;
    }
    out.extend(d.finish());
    out
}

fn ok_packets(events: &[Event]) -> Vec<Packet> {
    events
        .iter()
        .filter_map(|e| e.as_ref().ok().cloned())
        .collect()
}

/// After `finish`: every byte fed is in a decoded packet or counted as skipped, and the
/// counters match the events.
fn assert_accounting(d: &Decoder, events: &[Event], fed: usize) {
    let s = d.stats();
    assert_eq!(s.bytes, fed as u64, "bytes fed");
    let ok = ok_packets(events);
    assert_eq!(s.packets, ok.len() as u64, "packets");
    let packet_bytes: u64 = ok.iter().map(|p| p.wire_len() as u64).sum();
    assert_eq!(
        packet_bytes + s.skipped_bytes,
        s.bytes,
        "packet bytes {packet_bytes} + skipped {} != fed {}",
        s.skipped_bytes,
        s.bytes
    );
    for kind in droidctl::protocol::v1::ERROR_KINDS {
        let n = events
            .iter()
            .filter(|e| matches!(e, Err(err) if err.kind == kind))
            .count() as u64;
        assert_eq!(s.errors(kind), n, "{kind:?}");
    }
    assert_eq!(s.total_errors(), (events.len() - ok.len()) as u64);
    assert_eq!(d.buffered(), 0);
}

/// Whether some valid packet other than the expected one starts before `at` and reaches
/// into it: the only way (a checksum collision in garbage, 1 in 256 per candidate) a clean
/// packet can be lost. Checked by decoding each suffix's first candidate on its own.
fn accidental_packet_overlaps(source: Source, stream: &[u8], from: usize, at: usize) -> bool {
    (from..at).any(|c| {
        stream[c] == SOP1 && {
            let mut d = Decoder::new(source);
            let end = stream.len().min(c + d.max_packet_len());
            matches!(d.feed(&stream[c..end]).next(), Some(Ok(p)) if c + p.wire_len() > at
                && stream[c..c + p.wire_len()] == wire(&p)[..])
        }
    })
}

fn check_described(p: &Packet) {
    let cfg = StreamingConfig::full(40);
    for streaming in [None, Some(&cfg)] {
        let d = describe(p, streaming, None);
        let _ = to_json(p, &d, true);
        let d = describe(
            p,
            streaming,
            Some(&droidctl::protocol::v1::cmd::get_power_state()),
        );
        let _ = to_json(p, &d, false);
    }
    if let Packet::Async(a) = p {
        let _ = decode_async(a, &cfg);
        let _ = decode_async(a, &StreamingConfig::default());
    }
}

proptest! {
    // Failures are saved beside this file (tests/v1_props.proptest-regressions).
    #![proptest_config(ProptestConfig {
        cases: 512,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn command_round_trip(p in arb_command()) {
        let w = wire(&p);
        prop_assert_eq!(w.len(), p.wire_len());
        prop_assert_eq!(w[5] as usize, p.data().len() + 1);
        let mut d = Decoder::new(Source::Host);
        let mut events = d.decode_all(&w);
        events.extend(d.finish());
        prop_assert_eq!(&events, &vec![Ok(p.clone())]);
        assert_accounting(&d, &events, w.len());
        prop_assert_eq!(d.stats().skipped_bytes, 0);
        // Any change to the checksummed bytes is caught (a one-byte change of the sum).
        let mut bad = w.clone();
        let last = bad.len() - 1;
        bad[last] = bad[last].wrapping_add(1);
        let events = Decoder::new(Source::Host).decode_all(&bad);
        prop_assert!(!events.contains(&Ok(p.clone())));
        check_described(&p);
    }

    #[test]
    fn droid_round_trip(p in arb_droid_packet()) {
        let w = wire(&p);
        prop_assert_eq!(w.len(), p.wire_len());
        if let Packet::Async(a) = &p {
            prop_assert_eq!(u16::from_be_bytes([w[3], w[4]]) as usize, a.data.len() + 1);
        }
        let mut d = Decoder::new(Source::Droid);
        let mut events = d.decode_all(&w);
        events.extend(d.finish());
        prop_assert_eq!(&events, &vec![Ok(p.clone())]);
        assert_accounting(&d, &events, w.len());
        // The checksum is the inverted sum of everything after SOP2.
        prop_assert_eq!(w[w.len() - 1], packet::checksum(&w[2..w.len() - 1]));
        check_described(&p);
    }

    #[test]
    fn decoding_is_independent_of_chunking(
        source in arb_source(),
        segments in vec(prop_oneof![2 => Just(None), 1 => vec(byte(), 0..24).prop_map(Some)], 1..8),
        packets in vec(arb_droid_packet(), 8),
        commands in vec(arb_command(), 8),
        idx in vec(any::<Index>(), 0..12),
        small_bound in any::<bool>(),
    ) {
        let mut stream = Vec::new();
        for (i, seg) in segments.iter().enumerate() {
            match seg {
                Some(junk) => stream.extend_from_slice(junk),
                None if source == Source::Host => stream.extend(wire(&commands[i])),
                None => stream.extend(wire(&packets[i])),
            }
        }
        let make = || if small_bound {
            Decoder::with_max_async_dlen(source, 24)
        } else {
            Decoder::new(source)
        };

        let mut whole = make();
        let mut a = whole.decode_all(&stream);
        a.extend(whole.finish());

        let mut chunked = make();
        let b = decode_chunked(&mut chunked, &stream, &cut_points(stream.len(), &idx));

        let mut bytewise = make();
        let mut c = Vec::new();
        for byte in &stream {
            c.extend(bytewise.feed(std::slice::from_ref(byte)));
            prop_assert!(bytewise.buffered() <= bytewise.max_packet_len());
        }
        c.extend(bytewise.finish());

        prop_assert_eq!(&a, &b);
        prop_assert_eq!(&a, &c);
        prop_assert_eq!(whole.stats(), chunked.stats());
        prop_assert_eq!(whole.stats(), bytewise.stats());
        assert_accounting(&whole, &a, stream.len());
    }

    #[test]
    fn random_bytes_never_panic_and_are_accounted_for(
        source in arb_source(),
        stream in vec(byte(), 0..600),
        idx in vec(any::<Index>(), 0..16),
        bound in prop_oneof![Just(1usize), Just(16), Just(DEFAULT_MAX_ASYNC_DLEN), Just(70_000)],
    ) {
        let mut d = Decoder::with_max_async_dlen(source, bound);
        let events = decode_chunked(&mut d, &stream, &cut_points(stream.len(), &idx));
        assert_accounting(&d, &events, stream.len());
        for e in &events {
            match e {
                Ok(p) => check_described(p),
                Err(e) => { let _ = e.to_string(); }
            }
        }
    }

    #[test]
    fn garbage_without_sop_loses_nothing(
        source in arb_source(),
        items in vec((vec(any::<u8>().prop_map(|b| if b == SOP1 { 0x7F } else { b }), 0..32), any::<Index>()), 1..6),
        packets in vec(arb_droid_packet(), 6),
        commands in vec(arb_command(), 6),
        tail in vec(any::<u8>().prop_map(|b| if b == SOP1 { 0 } else { b }), 0..16),
        idx in vec(any::<Index>(), 0..8),
    ) {
        let mut stream = Vec::new();
        let mut expected = Vec::new();
        let mut garbage = 0;
        for (i, (junk, _)) in items.iter().enumerate() {
            stream.extend_from_slice(junk);
            garbage += junk.len();
            let p = if source == Source::Host { &commands[i] } else { &packets[i] };
            stream.extend(wire(p));
            expected.push(p.clone());
        }
        stream.extend_from_slice(&tail);
        garbage += tail.len();

        let mut d = Decoder::new(source);
        let events = decode_chunked(&mut d, &stream, &cut_points(stream.len(), &idx));
        prop_assert_eq!(ok_packets(&events), expected);
        let only_garbage = events.iter().all(|e| match e {
            Ok(_) => true,
            Err(e) => e.kind == ErrorKind::Garbage,
        });
        prop_assert!(only_garbage, "{:?}", events);
        prop_assert!(d.stats().errors(ErrorKind::Garbage) <= items.len() as u64 + 1);
        prop_assert_eq!(d.stats().skipped_bytes, garbage as u64);
        assert_accounting(&d, &events, stream.len());
    }

    #[test]
    fn clean_packet_after_arbitrary_garbage_is_found(
        source in arb_source(),
        junk in vec(byte(), 0..64),
        packet_seed in any::<Index>(),
        packets in vec(arb_droid_packet(), 4),
        commands in vec(arb_command(), 4),
        idx in vec(any::<Index>(), 0..8),
    ) {
        let p = match source {
            Source::Host => commands[packet_seed.index(4)].clone(),
            Source::Droid => packets[packet_seed.index(4)].clone(),
        };
        let mut stream = junk.clone();
        stream.extend(wire(&p));
        let mut d = Decoder::new(source);
        let events = decode_chunked(&mut d, &stream, &cut_points(stream.len(), &idx));
        assert_accounting(&d, &events, stream.len());
        // Found, unless garbage plus the packet's first bytes happen to form another valid
        // packet (a checksum collision), which v1 framing cannot tell from a real one.
        if !accidental_packet_overlaps(source, &stream, 0, junk.len()) {
            let found = ok_packets(&events);
            prop_assert_eq!(found.last(), Some(&p), "{:?}", events);
        }
    }

    #[test]
    fn buffer_stays_bounded(
        bound in 1usize..300,
        hi in any::<u8>(),
        lo in any::<u8>(),
        filler in vec(byte(), 0..2000),
        idx in vec(any::<Index>(), 0..32),
    ) {
        // An async header announcing up to 65535 bytes, then a long run.
        let mut stream = vec![0xFF, 0xFE, 0x03, hi, lo];
        stream.extend(filler);
        let mut d = Decoder::with_max_async_dlen(Source::Droid, bound);
        let events = decode_chunked(&mut d, &stream, &cut_points(stream.len(), &idx));
        prop_assert!(d.max_packet_len() <= 5 + 255.max(bound));
        assert_accounting(&d, &events, stream.len());
    }
}

// -------------------------------------------------------------------------------------------
// Stress: mutated streams, random chunking, seeded.
// -------------------------------------------------------------------------------------------

/// splitmix64: tiny, seedable, good enough to drive a stress test.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn byte(&mut self) -> u8 {
        if self.below(4) == 0 {
            [0xFF, 0xFE, 0x00, 0x01][self.below(4)]
        } else {
            self.next() as u8
        }
    }

    fn packet(&mut self) -> Packet {
        let len = if self.below(8) == 0 {
            self.below(300)
        } else {
            self.below(24)
        };
        let data: Vec<u8> = (0..len).map(|_| self.byte()).collect();
        if self.below(3) == 0 {
            Packet::Async(AsyncPacket::new(self.byte(), data))
        } else {
            let mut data = data;
            data.truncate(254);
            Packet::Response(Response {
                mrsp: Mrsp::from_byte(self.byte()),
                seq: self.byte(),
                data,
            })
        }
    }
}

#[test]
fn stress_mutated_droid_stream() {
    const TOTAL: usize = 300_000;
    let mut r = SplitMix(0x5EED_0001);
    let mut stream = Vec::with_capacity(TOTAL + 1024);
    while stream.len() < TOTAL {
        match r.below(10) {
            0..=4 => stream.extend(wire(&r.packet())),
            5..=7 => {
                let mut w = wire(&r.packet());
                let at = r.below(w.len());
                match r.below(4) {
                    0 => w[at] ^= 1 << r.below(8),
                    1 => {
                        w.remove(at);
                    }
                    2 => w.truncate(at),
                    _ => w.insert(at, r.byte()),
                }
                stream.extend(w);
            }
            _ => stream.extend((0..r.below(64)).map(|_| r.byte())),
        }
    }
    for bound in [DEFAULT_MAX_ASYNC_DLEN, 40] {
        let mut d = Decoder::with_max_async_dlen(Source::Droid, bound);
        let mut events = Vec::new();
        let mut pos = 0;
        while pos < stream.len() {
            let end = (pos + r.below(40)).min(stream.len());
            events.extend(d.feed(&stream[pos..end]));
            assert!(d.buffered() <= d.max_packet_len());
            pos = end;
        }
        events.extend(d.finish());
        assert_accounting(&d, &events, stream.len());
        assert!(d.stats().packets > 1000, "{:?}", d.stats());
    }
}
