//! Property tests of the v2 codec (proptest), and a seeded stress test of the streaming
//! decoder over more than a million random and mutated bytes.

use droidctl::protocol::v2::decoder::DEFAULT_MAX_BODY;
use droidctl::protocol::v2::packet::{self, EOP, ESC, SOP, parse_body};
use droidctl::protocol::v2::{DecodeError, Decoder, ErrorCode, ErrorKind, Flags, Packet, describe};
use proptest::collection::vec;
use proptest::option;
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::FileFailurePersistence;

/// Bytes with the framing values (and their escaped forms) much more likely than 1 in 256.
fn byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        3 => any::<u8>(),
        1 => prop::sample::select(vec![SOP, EOP, ESC, 0x23, 0x05, 0x50, 0x00, 0xFF]),
    ]
}

/// Any packet: any flags byte (ext-flags/TID/SID/response bits included), optional header
/// fields independent of the flags, any DID/CID/SEQ/ERR and up to 64 data bytes.
fn arb_packet() -> impl Strategy<Value = Packet> {
    (
        any::<u8>(),
        option::of(byte()),
        option::of(byte()),
        option::of(byte()),
        (byte(), byte(), byte()),
        option::of(byte()),
        vec(byte(), 0..=64),
    )
        .prop_map(
            |(flags, ext_flags, tid, sid, (did, cid, seq), err, data)| Packet {
                flags: Flags::from_bits_retain(flags),
                ext_flags,
                tid,
                sid,
                did,
                cid,
                seq,
                err: err.map(ErrorCode::from_byte),
                data,
            },
        )
}

/// A stream segment: an encoded packet, or garbage that may hold framing bytes.
fn segment() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        2 => arb_packet().prop_map(|p| p.encode()),
        1 => vec(byte(), 0..24),
    ]
}

fn decode_in_chunks(
    decoder: &mut Decoder,
    stream: &[u8],
    cuts: &[usize],
) -> Vec<Result<Packet, DecodeError>> {
    let mut out = Vec::new();
    let mut start = 0;
    for &cut in cuts {
        out.extend(decoder.feed(&stream[start..cut]));
        start = cut;
    }
    out.extend(decoder.feed(&stream[start..]));
    out
}

/// Sorted cut positions in `0..=len` from proptest indices.
fn cut_points(len: usize, idx: &[Index]) -> Vec<usize> {
    let mut cuts: Vec<usize> = idx.iter().map(|i| i.index(len + 1)).collect();
    cuts.sort_unstable();
    cuts
}

/// Is `wanted` a subsequence of `got`, in order?
fn is_subsequence(wanted: &[Packet], got: &[Packet]) -> bool {
    let mut it = got.iter();
    wanted.iter().all(|w| it.any(|g| g == w))
}

fn ok_packets(events: &[Result<Packet, DecodeError>]) -> Vec<Packet> {
    events
        .iter()
        .filter_map(|e| e.as_ref().ok().cloned())
        .collect()
}

/// After `finish`, every byte fed is either part of a decoded packet or counted as skipped,
/// and the counters match the events.
fn assert_accounting(d: &Decoder, events: &[Result<Packet, DecodeError>], fed: usize) {
    let s = d.stats();
    assert_eq!(s.bytes, fed as u64, "bytes fed");
    let ok = ok_packets(events);
    assert_eq!(s.packets, ok.len() as u64, "packets");
    let packet_bytes: u64 = ok.iter().map(|p| p.encode().len() as u64).sum();
    assert_eq!(
        packet_bytes + s.skipped_bytes,
        s.bytes,
        "packet bytes {packet_bytes} + skipped {} != fed {}",
        s.skipped_bytes,
        s.bytes
    );
    for kind in ErrorKind::ALL {
        let n = events
            .iter()
            .filter(|e| matches!(e, Err(err) if err.kind == kind))
            .count() as u64;
        assert_eq!(s.errors(kind), n, "{kind:?}");
    }
    assert_eq!(s.total_errors(), (events.len() - ok.len()) as u64);
    assert_eq!(d.buffered(), 0);
}

proptest! {
    // Failures are saved beside this file (tests/v2_props.proptest-regressions).
    #![proptest_config(ProptestConfig {
        cases: 512,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn encode_decode_round_trip(p in arb_packet()) {
        let expected = p.clone().normalized();
        let wire = p.encode();
        // Framing: SOP and EOP only at the ends, everything inside escaped.
        prop_assert_eq!(wire[0], SOP);
        prop_assert_eq!(*wire.last().unwrap(), EOP);
        prop_assert!(!wire[1..wire.len() - 1].iter().any(|&b| b == SOP || b == EOP));
        // Normalizing does not change the encoding.
        prop_assert_eq!(expected.encode(), wire.clone());

        let mut d = Decoder::new();
        let mut events = d.decode_all(&wire);
        events.extend(d.finish().into_iter().map(Err));
        prop_assert_eq!(&events, &vec![Ok(expected.clone())]);
        assert_accounting(&d, &events, wire.len());
        prop_assert_eq!(d.stats().skipped_bytes, 0);

        // The unescaped body parses to the same packet, and a wrong checksum is caught.
        let mut body = expected.body();
        body.push(packet::checksum(&body));
        prop_assert_eq!(parse_body(&body), Ok(expected.clone()));
        let last = body.len() - 1;
        body[last] = body[last].wrapping_add(1);
        prop_assert!(parse_body(&body).is_err());

        // Describing never panics, whatever the ids and payload.
        let _ = describe(&expected, None);
    }

    #[test]
    fn decoding_is_independent_of_chunking(
        segments in vec(segment(), 1..8),
        idx in vec(any::<Index>(), 0..12),
        small_bound in any::<bool>(),
    ) {
        let stream: Vec<u8> = segments.concat();
        let cuts = cut_points(stream.len(), &idx);
        let make = || if small_bound { Decoder::with_max_body(24) } else { Decoder::new() };

        let mut whole = make();
        let mut a = whole.decode_all(&stream);
        a.extend(whole.finish().into_iter().map(Err));

        let mut chunked = make();
        let mut b = decode_in_chunks(&mut chunked, &stream, &cuts);
        b.extend(chunked.finish().into_iter().map(Err));

        let mut bytewise = make();
        let mut c = Vec::new();
        for byte in &stream {
            c.extend(bytewise.feed(std::slice::from_ref(byte)));
        }
        c.extend(bytewise.finish().into_iter().map(Err));

        prop_assert_eq!(&a, &b);
        prop_assert_eq!(&a, &c);
        prop_assert_eq!(whole.stats(), chunked.stats());
        prop_assert_eq!(whole.stats(), bytewise.stats());
        assert_accounting(&whole, &a, stream.len());
    }

    #[test]
    fn garbage_without_sop_loses_nothing(
        items in vec((vec(any::<u8>().prop_map(|b| if b == SOP { 0x8C } else { b }), 0..32), arb_packet()), 1..6),
        tail in vec(any::<u8>().prop_map(|b| if b == SOP { EOP } else { b }), 0..16),
        idx in vec(any::<Index>(), 0..8),
    ) {
        let mut stream = Vec::new();
        let mut expected = Vec::new();
        let mut garbage = 0;
        for (junk, p) in &items {
            stream.extend_from_slice(junk);
            stream.extend(p.encode());
            expected.push(p.clone().normalized());
            garbage += junk.len();
        }
        stream.extend_from_slice(&tail);
        garbage += tail.len();

        let mut d = Decoder::new();
        let mut events = decode_in_chunks(&mut d, &stream, &cut_points(stream.len(), &idx));
        events.extend(d.finish().into_iter().map(Err));
        prop_assert_eq!(ok_packets(&events), expected);
        // Only garbage errors, one per run at most.
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
    fn arbitrary_garbage_then_clean_packet_is_decoded(
        items in vec((vec(byte(), 0..48), arb_packet()), 1..6),
        idx in vec(any::<Index>(), 0..8),
    ) {
        let mut stream = Vec::new();
        let mut expected = Vec::new();
        for (junk, p) in &items {
            stream.extend_from_slice(junk);
            stream.extend(p.encode());
            expected.push(p.clone().normalized());
        }
        let mut d = Decoder::new();
        let mut events = decode_in_chunks(&mut d, &stream, &cut_points(stream.len(), &idx));
        // Each clean packet ends the stream segment it closes: the last event is the last one.
        prop_assert_eq!(events.last(), Some(&Ok(expected.last().unwrap().clone())));
        events.extend(d.finish().into_iter().map(Err));
        let got = ok_packets(&events);
        prop_assert!(is_subsequence(&expected, &got), "expected {:?}\n got {:?}", expected, got);
        assert_accounting(&d, &events, stream.len());
    }
}

// -------------------------------------------------------------------------------------------
// Stress: a million random and mutated bytes, random chunking, seeded.
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

    /// Uniform-ish in `0..n` (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn byte(&mut self) -> u8 {
        // One in four is a framing byte or an escaped form.
        if self.below(4) == 0 {
            [SOP, EOP, ESC, 0x23, 0x05, 0x50][self.below(6)]
        } else {
            self.next() as u8
        }
    }

    fn chance(&mut self, one_in: usize) -> bool {
        self.below(one_in) == 0
    }

    fn packet(&mut self) -> Packet {
        let opt = |r: &mut Self| if r.chance(3) { Some(r.byte()) } else { None };
        let len = if self.chance(8) {
            self.below(65)
        } else {
            self.below(20)
        };
        let p = Packet {
            flags: Flags::from_bits_retain(self.next() as u8),
            ext_flags: opt(self),
            tid: opt(self),
            sid: opt(self),
            did: self.byte(),
            cid: self.byte(),
            seq: self.byte(),
            err: opt(self).map(ErrorCode::from_byte),
            data: (0..len).map(|_| self.byte()).collect(),
        };
        p.normalized()
    }
}

/// One way to damage an encoded packet.
fn mutate(r: &mut SplitMix, wire: &mut Vec<u8>) {
    let at = r.below(wire.len());
    match r.below(7) {
        0 => {
            for _ in 0..=r.below(3) {
                let i = r.below(wire.len());
                wire[i] ^= 1 << r.below(8);
            }
        }
        1 => {
            wire.remove(at);
        }
        2 => {
            let b = wire[at];
            wire.insert(at, b);
        }
        3 => {
            let b = [SOP, EOP, ESC][r.below(3)];
            wire.insert(at, b);
        }
        4 => wire.truncate(at),
        5 => {
            let j = r.below(wire.len());
            wire.swap(at, j);
        }
        _ => {
            let extra: Vec<u8> = (0..r.below(8)).map(|_| r.byte()).collect();
            wire.splice(at..at, extra);
        }
    }
}

#[test]
fn stress_million_mutated_bytes() {
    const TOTAL: usize = 1_200_000;
    const SMALL_BOUND: usize = 40;
    let started = std::time::Instant::now();
    let mut r = SplitMix(0x5EED_D401D_u64);

    // Build the stream, remembering the clean packets in order.
    let mut stream = Vec::with_capacity(TOTAL + 1024);
    let mut clean = Vec::new();
    while stream.len() < TOTAL {
        match r.below(20) {
            0..=7 => {
                let p = r.packet();
                stream.extend(p.encode());
                clean.push(p);
            }
            8..=15 => {
                let mut wire = r.packet().encode();
                for _ in 0..=r.below(2) {
                    if !wire.is_empty() {
                        mutate(&mut r, &mut wire);
                    }
                }
                stream.extend(wire);
            }
            16 | 17 => stream.extend((0..r.below(64)).map(|_| r.next() as u8)),
            18 => stream.extend((0..r.below(16)).map(|_| [SOP, EOP, ESC, 0x23][r.below(4)])),
            _ => {
                // A long run without EOP: overflows the small decoder's bound.
                stream.push(SOP);
                stream.extend((0..SMALL_BOUND + r.below(600)).map(|_| 0x11 + r.below(0x60) as u8));
            }
        }
    }

    let mut big = Decoder::new();
    let mut small = Decoder::with_max_body(SMALL_BOUND);
    let mut big_events = Vec::new();
    let mut small_events = Vec::new();
    let mut pos = 0;
    let mut chunks = 0;
    while pos < stream.len() {
        let n = if r.chance(4) {
            r.below(300)
        } else {
            r.below(21)
        };
        let end = (pos + n).min(stream.len());
        big_events.extend(big.feed(&stream[pos..end]));
        small_events.extend(small.feed(&stream[pos..end]));
        assert!(big.buffered() <= DEFAULT_MAX_BODY, "{}", big.buffered());
        assert!(small.buffered() <= SMALL_BOUND, "{}", small.buffered());
        pos = end;
        chunks += 1;
    }
    big_events.extend(big.finish().into_iter().map(Err));
    small_events.extend(small.finish().into_iter().map(Err));

    assert!(stream.len() >= 1_000_000);
    assert_accounting(&big, &big_events, stream.len());
    assert_accounting(&small, &small_events, stream.len());

    // Every clean packet survives whatever came before it (those that fit the bound, for the
    // small decoder).
    let got = ok_packets(&big_events);
    assert!(is_subsequence(&clean, &got), "a clean packet was lost");
    let fits: Vec<Packet> = clean
        .iter()
        .filter(|p| p.body().len() < SMALL_BOUND)
        .cloned()
        .collect();
    assert!(is_subsequence(&fits, &ok_packets(&small_events)));

    // The stream exercised every error kind.
    for kind in droidctl::protocol::v2::ERROR_KINDS {
        if kind != ErrorKind::Truncated {
            assert!(
                big.stats().errors(kind) > 0 || small.stats().errors(kind) > 0,
                "{kind:?}"
            );
        }
    }
    assert!(small.stats().errors(ErrorKind::Oversize) > 0);
    eprintln!(
        "stress: {} bytes in {chunks} chunks, {} clean packets, decoded {} (bound {}) / {} (bound \
         {SMALL_BOUND}), {} / {} errors, {:?}",
        stream.len(),
        clean.len(),
        big.stats().packets,
        DEFAULT_MAX_BODY,
        small.stats().packets,
        big.stats().total_errors(),
        small.stats().total_errors(),
        started.elapsed()
    );
}
