//! Property tests of the RSRCP codec (proptest): round trips, chunking independence, garbage
//! tolerance and resynchronisation, and the framer's bounded buffer and byte accounting.

use droidctl::protocol::rsrcp::{
    Buttons, Efs, Frame, FrameError, Framer, Handshake, Item, Leds, MAX_FRAME_LEN, SOP,
    decode_frame, decode_handshake, to_json,
};
use proptest::collection::vec;
use proptest::option;
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::FileFailurePersistence;

type Event = Result<Item, FrameError>;

/// Bytes with the framing values much more likely than 1 in 256.
fn byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        3 => any::<u8>(),
        1 => prop::sample::select(vec![0x7E, 0x7F, 0x00, 0xFF, 0x43, 0x02]),
    ]
}

/// Any encodable frame: motor speeds on the wire's 0.01 grid within ±300 (so the round trip is
/// exact), every other value over its whole range.
fn arb_frame() -> impl Strategy<Value = Frame> {
    (
        any::<u32>(),
        option::of((-30000i16..=30000, -30000i16..=30000)),
        option::of(byte()),
        option::of(byte()),
        option::of(byte()),
        option::of((any::<bool>(), 0u16..=0x7FFF)),
    )
        .prop_map(|(id, motors, poti, buttons, leds, piezo)| {
            let mut f = Frame::new(id);
            if let Some((l, r)) = motors {
                f = f.with_motors(f32::from(l) / 100.0, f32::from(r) / 100.0);
            }
            if let Some(p) = poti {
                f = f.with_poti(p);
            }
            if let Some(b) = buttons {
                f = f.with_buttons(Buttons::from_bits_retain(b));
            }
            if let Some(l) = leds {
                f = f.with_leds(Leds::from_bits_retain(l));
            }
            if let Some((on, hz)) = piezo {
                f = f.with_piezo(on, hz);
            }
            f
        })
}

/// A frame enabling an unsized feature or a reserved bit, with some payload after its header.
fn arb_unframable() -> impl Strategy<Value = Vec<u8>> {
    (any::<[u8; 3]>(), any::<u16>(), vec(byte(), 0..20)).prop_map(|(id, efs, rest)| {
        let efs = efs | 0x2000; // at least the gyro
        let mut out = vec![SOP];
        out.extend_from_slice(&id);
        out.extend_from_slice(&efs.to_be_bytes());
        out.extend(rest);
        out.push(0x7F);
        out
    })
}

/// A stream segment: a frame, a handshake, an unframable frame, or garbage.
fn segment() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        4 => arb_frame().prop_map(|f| f.encode()),
        1 => (any::<u8>(), any::<u16>())
            .prop_map(|(version, msdt_ms)| Handshake { version, msdt_ms }.encode().to_vec()),
        1 => arb_unframable(),
        1 => vec(byte(), 0..24),
    ]
}

/// Frame `stream` cut at `cuts`, then finish; checks the bound after every chunk.
fn frame_in_chunks(stream: &[u8], cuts: &[usize]) -> (Vec<Event>, Framer) {
    let mut framer = Framer::new();
    let mut out = Vec::new();
    let mut start = 0;
    for &cut in cuts.iter().chain(std::iter::once(&stream.len())) {
        out.extend(framer.feed(&stream[start..cut]));
        assert!(framer.buffered() <= MAX_FRAME_LEN);
        start = cut;
    }
    out.extend(framer.finish());
    assert_eq!(framer.buffered(), 0);
    (out, framer)
}

fn cut_points(len: usize, idx: &[Index]) -> Vec<usize> {
    let mut cuts: Vec<usize> = idx.iter().map(|i| i.index(len + 1)).collect();
    cuts.sort_unstable();
    cuts
}

fn accepted_bytes(events: &[Event]) -> u64 {
    events
        .iter()
        .map(|e| match e {
            Ok(Item::Frame(f)) => f.encode().len() as u64,
            Ok(Item::Handshake(h)) => h.encode().len() as u64,
            Err(_) => 0,
        })
        .sum()
}

/// Invariants that hold for any input once `finish` has run.
fn check_accounting(stream: &[u8], events: &[Event], framer: &Framer) {
    let stats = framer.stats();
    assert_eq!(stats.bytes, stream.len() as u64);
    assert_eq!(
        accepted_bytes(events) + stats.skipped_bytes,
        stream.len() as u64,
        "every byte is in one item or skipped"
    );
    let items = events.iter().filter(|e| e.is_ok()).count() as u64;
    assert_eq!(stats.packets, items);
    let errors = events.iter().filter(|e| e.is_err()).count() as u64;
    assert_eq!(stats.total_errors(), errors);
    let offsets: Vec<u64> = events
        .iter()
        .filter_map(|e| e.as_ref().err().map(|e| e.offset))
        .collect();
    assert!(offsets.windows(2).all(|w| w[0] <= w[1]), "{offsets:?}");
    assert!(offsets.iter().all(|&o| o < stream.len() as u64));
    for e in events {
        // Describing anything never fails and always has the error keys.
        let j = to_json(e);
        assert!(j.get("error").is_some() && j.get("kind").is_some());
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 512,
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("proptest-regressions"))),
        ..ProptestConfig::default()
    })]

    #[test]
    fn frames_round_trip(f in arb_frame()) {
        let wire = f.encode();
        prop_assert_eq!(Some(wire.len()), Frame::len_for(f.efs));
        prop_assert_eq!(decode_frame(&wire), Ok(f.clone()));
        let (out, _) = frame_in_chunks(&wire, &[]);
        prop_assert_eq!(out, vec![Ok(Item::Frame(f))]);
    }

    #[test]
    fn any_efs_has_a_consistent_length(bits in any::<u16>()) {
        let efs = Efs::from_bits_retain(bits);
        let sized_only = bits & (Efs::UNSIZED.bits() | Efs::RESERVED_MASK) == 0;
        prop_assert_eq!(Frame::len_for(efs).is_some(), sized_only);
        if let Some(len) = Frame::len_for(efs) {
            prop_assert!((7..=MAX_FRAME_LEN).contains(&len));
        }
    }

    #[test]
    fn chunking_does_not_change_results(
        segments in vec(segment(), 0..24),
        idx in vec(any::<Index>(), 0..12),
    ) {
        let stream = segments.concat();
        let (whole, whole_framer) = frame_in_chunks(&stream, &[]);
        let (chunked, chunked_framer) = frame_in_chunks(&stream, &cut_points(stream.len(), &idx));
        let bytewise: Vec<usize> = (1..stream.len()).collect();
        let (single, single_framer) = frame_in_chunks(&stream, &bytewise);
        prop_assert_eq!(&whole, &chunked);
        prop_assert_eq!(&whole, &single);
        prop_assert_eq!(whole_framer.stats(), chunked_framer.stats());
        prop_assert_eq!(whole_framer.stats(), single_framer.stats());
        check_accounting(&stream, &whole, &whole_framer);
    }

    #[test]
    fn random_bytes_never_panic(stream in vec(byte(), 0..1500), idx in vec(any::<Index>(), 0..8)) {
        let (out, framer) = frame_in_chunks(&stream, &cut_points(stream.len(), &idx));
        check_accounting(&stream, &out, &framer);
        // Per-value decoders on every prefix.
        for n in 0..stream.len().min(40) {
            let _ = decode_frame(&stream[..n]);
            let _ = decode_handshake(&stream[..n]);
        }
    }

    #[test]
    fn sop_free_garbage_loses_nothing(
        garbage in vec(any::<u8>().prop_filter("no SOP", |b| *b != SOP), 1..64),
        frames in vec(arb_frame(), 1..6),
    ) {
        let mut stream = garbage.clone();
        for f in &frames {
            stream.extend(f.encode());
        }
        let (out, framer) = frame_in_chunks(&stream, &[]);
        let got: Vec<Frame> = out.iter().filter_map(|e| match e {
            Ok(Item::Frame(f)) => Some(f.clone()),
            _ => None,
        }).collect();
        prop_assert_eq!(got, frames);
        prop_assert_eq!(framer.stats().total_errors(), 1);
        prop_assert_eq!(framer.stats().skipped_bytes, garbage.len() as u64);
    }

    /// Garbage may hold SOPs that start false candidates, which can swallow the start of the
    /// real data; but a false candidate is at most `MAX_FRAME_LEN` bytes long and real frames
    /// without 7E after their SOP cannot start new ones, so every frame that starts
    /// `MAX_FRAME_LEN - 1` bytes or more into the real data is found, in order.
    #[test]
    fn frames_after_garbage_are_found(
        garbage in vec(byte(), 0..64),
        frames in vec(
            arb_frame().prop_filter("no 7E after the SOP", |f| !f.encode()[1..].contains(&SOP)),
            1..8,
        ),
        idx in vec(any::<Index>(), 0..6),
    ) {
        let mut stream = garbage.clone();
        let mut must = Vec::new();
        for f in &frames {
            if stream.len() >= garbage.len() + MAX_FRAME_LEN - 1 {
                must.push(f.clone());
            }
            stream.extend(f.encode());
        }
        let (out, framer) = frame_in_chunks(&stream, &cut_points(stream.len(), &idx));
        let got: Vec<Frame> = out.iter().filter_map(|e| match e {
            Ok(Item::Frame(f)) => Some(f.clone()),
            _ => None,
        }).collect();
        prop_assert!(got.ends_with(&must), "got {:?}\nmust end with {:?}", got, must);
        check_accounting(&stream, &out, &framer);
    }
}

#[test]
fn buffer_stays_bounded_on_adversarial_input() {
    // Nothing but SOPs: every candidate enables unsized features and is rejected at once.
    // Then headers that promise the longest frame and never end it.
    let mut longest = Vec::new();
    for i in 0..200u8 {
        longest.extend_from_slice(&[SOP, 0, 0, i, 0x43, 0xC0]);
        longest.extend(std::iter::repeat_n(0x11, 9));
    }
    for stream in [vec![SOP; 10_000], longest, vec![0x7F; 1000]] {
        let mut framer = Framer::new();
        let mut events = Vec::new();
        for chunk in stream.chunks(7) {
            events.extend(framer.feed(chunk));
            assert!(framer.buffered() <= MAX_FRAME_LEN);
        }
        events.extend(framer.finish());
        check_accounting(&stream, &events, &framer);
        assert!(events.iter().all(|e| e.is_err()));
    }
}
