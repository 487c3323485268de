//! The relay protocol codec (spherov2's TCP relay): byte layouts checked against what
//! spherov2's `tcp_adapter.py` and `tcp_server.py` write, round trips, decoding independent
//! of chunking, length limits enforced before the bytes arrive, and garbage never panicking.

use droidctl::protocol::relay::{
    DecodeError, Device, Expect, Field, Limits, Reply, ReplyDecoder, Request, RequestDecoder,
};
use proptest::collection::vec;
use proptest::prelude::*;

fn ascii(max: usize) -> impl Strategy<Value = String> {
    vec(0x20u8..0x7f, 0..=max).prop_map(|b| String::from_utf8(b).unwrap())
}

/// UTF-8 text of at most `max` bytes.
fn utf8(max: usize) -> impl Strategy<Value = String> {
    ".{0,40}".prop_map(move |s: String| {
        let mut end = s.len().min(max);
        while !s.is_char_boundary(end) {
            end -= 1;
        }
        s[..end].to_string()
    })
}

/// Timeouts: any f32 but NaN (NaN ≠ NaN; its bits are checked separately).
fn secs() -> impl Strategy<Value = f32> {
    any::<f32>().prop_filter("not NaN", |f| !f.is_nan())
}

fn request() -> impl Strategy<Value = Request> {
    let l = Limits::default();
    prop_oneof![
        secs().prop_map(|timeout| Request::Scan { timeout }),
        (utf8(l.name), secs()).prop_map(|(name, timeout)| Request::Find { name, timeout }),
        (any::<u8>(), ascii(l.text)).prop_map(|(seq, address)| Request::Init { seq, address }),
        (any::<u8>(), ascii(l.text)).prop_map(|(seq, characteristic)| Request::SetCallback {
            seq,
            characteristic
        }),
        (any::<u8>(), ascii(l.text), vec(any::<u8>(), 0..=64)).prop_map(
            |(seq, characteristic, data)| Request::Write {
                seq,
                characteristic,
                data
            }
        ),
        Just(Request::End),
    ]
}

fn device() -> impl Strategy<Value = Device> {
    (utf8(Limits::default().name), ascii(17)).prop_map(|(name, address)| Device { name, address })
}

/// A reply and what its request expected.
fn reply() -> impl Strategy<Value = (Option<Expect>, Reply)> {
    prop_oneof![
        any::<u8>().prop_map(|seq| (Some(Expect::Seq), Reply::Ok { seq })),
        vec(device(), 0..5).prop_map(|d| (Some(Expect::Scan), Reply::Devices(d))),
        device().prop_map(|d| (Some(Expect::Find), Reply::Found(d))),
        (ascii(40), vec(any::<u8>(), 0..=255)).prop_map(|(characteristic, data)| (
            None,
            Reply::Data {
                characteristic,
                data
            }
        )),
        (utf8(100), any::<u8>()).prop_map(|(message, seq)| (
            Some(Expect::Seq),
            Reply::Error {
                message,
                seq: Some(seq)
            }
        )),
        (
            utf8(100),
            prop_oneof![Just(Expect::Scan), Just(Expect::Find)]
        )
            .prop_map(|(message, e)| (Some(e), Reply::Error { message, seq: None })),
    ]
}

/// Split `bytes` at the given fractions (any order, duplicates allowed).
fn chunks(bytes: &[u8], cuts: &[f64]) -> Vec<Vec<u8>> {
    let mut at: Vec<usize> = cuts
        .iter()
        .map(|c| ((bytes.len() as f64) * c) as usize)
        .collect();
    at.push(0);
    at.push(bytes.len());
    at.sort_unstable();
    at.windows(2).map(|w| bytes[w[0]..w[1]].to_vec()).collect()
}

fn decode_requests(pieces: &[Vec<u8>]) -> Vec<Result<Request, DecodeError>> {
    let mut d = RequestDecoder::new(Limits::default());
    let mut out = Vec::new();
    for p in pieces {
        d.push(p);
        while let Some(r) = d.next() {
            out.push(r);
        }
    }
    out
}

fn decode_replies(expect: &[Expect], pieces: &[Vec<u8>]) -> Vec<Result<Reply, DecodeError>> {
    let mut d = ReplyDecoder::new(Limits::default());
    for e in expect {
        d.expect(*e);
    }
    let mut out = Vec::new();
    for p in pieces {
        d.push(p);
        while let Some(r) = d.next() {
            out.push(r);
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn requests_round_trip_in_any_chunking(
        reqs in vec(request(), 1..8),
        cuts in vec(0.0f64..1.0, 0..12),
    ) {
        let mut stream = Vec::new();
        for r in &reqs {
            r.encode(&mut stream).unwrap();
        }
        let whole = decode_requests(&[stream.clone()]);
        let expected: Vec<Result<Request, DecodeError>> = reqs.iter().cloned().map(Ok).collect();
        prop_assert_eq!(&whole, &expected);
        prop_assert_eq!(decode_requests(&chunks(&stream, &cuts)), expected);
        // Byte by byte too.
        let bytes: Vec<Vec<u8>> = stream.iter().map(|b| vec![*b]).collect();
        prop_assert_eq!(decode_requests(&bytes), whole);
    }

    #[test]
    fn replies_round_trip_in_any_chunking(
        reps in vec(reply(), 1..8),
        cuts in vec(0.0f64..1.0, 0..12),
    ) {
        let mut stream = Vec::new();
        let mut expect = Vec::new();
        for (e, r) in &reps {
            r.encode(&mut stream).unwrap();
            expect.extend(e);
        }
        let expected: Vec<Result<Reply, DecodeError>> =
            reps.iter().map(|(_, r)| Ok(r.clone())).collect();
        prop_assert_eq!(decode_replies(&expect, &[stream.clone()]), expected.clone());
        prop_assert_eq!(decode_replies(&expect, &chunks(&stream, &cuts)), expected);
    }

    #[test]
    fn garbage_never_panics_and_stays_bounded(
        bytes in vec(any::<u8>(), 0..2048),
        cuts in vec(0.0f64..1.0, 0..16),
        expect in vec(prop_oneof![Just(Expect::Seq), Just(Expect::Scan), Just(Expect::Find)], 0..4),
    ) {
        let pieces = chunks(&bytes, &cuts);
        let mut d = RequestDecoder::new(Limits::default());
        let mut n = 0;
        for p in &pieces {
            d.push(p);
            while let Some(r) = d.next() {
                n += 1;
                prop_assert!(n <= bytes.len());
                if let Err(e) = r {
                    let _ = e.to_string();
                }
            }
            // Never more than one request's worth plus the chunk just pushed.
            prop_assert!(d.buffered() <= 2 + 2 + 64 + 2 + 512 + p.len());
        }
        let _ = d.finish();
        let mut r = ReplyDecoder::new(Limits::default());
        for e in &expect {
            r.expect(*e);
        }
        let mut m = 0;
        for p in &pieces {
            r.push(p);
            while let Some(x) = r.next() {
                m += 1;
                prop_assert!(m <= bytes.len());
                let _ = x.map_err(|e| e.to_string());
            }
        }
        let _ = r.finish();
    }

    #[test]
    fn mutated_streams_never_panic(
        reqs in vec(request(), 1..6),
        flips in vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
        cuts in vec(0.0f64..1.0, 0..8),
    ) {
        let mut stream = Vec::new();
        for r in &reqs {
            r.encode(&mut stream).unwrap();
        }
        for (i, b) in flips {
            let at = i.index(stream.len());
            stream[at] = b;
        }
        let out = decode_requests(&chunks(&stream, &cuts));
        prop_assert!(out.len() <= stream.len());
    }
}

#[test]
fn spherov2_adapter_bytes() {
    // tcp_adapter.TCPAdapter.__init__: INIT + seq + u16 len + ASCII address.
    let init = Request::Init {
        seq: 0,
        address: "F1:22:33:44:55:66".into(),
    };
    let mut want = vec![0x01, 0x00, 0x00, 17];
    want.extend_from_slice(b"F1:22:33:44:55:66");
    assert_eq!(init.to_bytes().unwrap(), want);
    // scan_toy: FIND + u16 len + name + '!f' timeout.
    let find = Request::Find {
        name: "D2-1A2B".into(),
        timeout: 5.0,
    };
    let mut want = vec![0x04, 0x00, 7];
    want.extend_from_slice(b"D2-1A2B");
    want.extend_from_slice(&[0x40, 0xa0, 0x00, 0x00]);
    assert_eq!(find.to_bytes().unwrap(), want);
    // write: WRITE + seq + u16 len + uuid + u16 len + data.
    let w = Request::Write {
        seq: 255,
        characteristic: "00020005-574f-4f20-5370-6865726f2121".into(),
        data: b"usetheforce...band".to_vec(),
    };
    let b = w.to_bytes().unwrap();
    assert_eq!(&b[..4], &[0x03, 0xff, 0x00, 36]);
    assert_eq!(&b[40..42], &[0x00, 18]);
    assert_eq!(&b[42..], b"usetheforce...band");
    assert_eq!(Request::End.to_bytes().unwrap(), [0xff]);
}

#[test]
fn spherov2_server_bytes() {
    // process_connection: OK + seq.
    assert_eq!(Reply::Ok { seq: 9 }.to_bytes().unwrap(), [0x00, 9]);
    // callback: ON_DATA + u16 len + uuid + u8 len + data.
    let d = Reply::Data {
        characteristic: "ab".into(),
        data: vec![0x8d, 0x0a],
    };
    assert_eq!(
        d.to_bytes().unwrap(),
        [0x01, 0x00, 0x02, b'a', b'b', 0x02, 0x8d, 0x0a]
    );
    // ERROR + u16 len + message + seq.
    let e = Reply::Error {
        message: "no".into(),
        seq: Some(3),
    };
    assert_eq!(e.to_bytes().unwrap(), [0xff, 0x00, 0x02, b'n', b'o', 3]);
    // FIND not found: ERROR + 00 00, no seq.
    assert_eq!(Reply::error("", None).to_bytes().unwrap(), [0xff, 0, 0]);
    // SCAN: OK + u16 count + (u16 len, name, u16 len, address) each; FIND: no count.
    let dev = Device {
        name: "D2".into(),
        address: "A".into(),
    };
    assert_eq!(
        Reply::Devices(vec![dev.clone()]).to_bytes().unwrap(),
        [0x00, 0x00, 0x01, 0x00, 0x02, b'D', b'2', 0x00, 0x01, b'A']
    );
    assert_eq!(
        Reply::Found(dev).to_bytes().unwrap(),
        [0x00, 0x00, 0x02, b'D', b'2', 0x00, 0x01, b'A']
    );
    // ON_DATA holds at most 255 bytes.
    assert!(
        Reply::Data {
            characteristic: "x".into(),
            data: vec![0; 256]
        }
        .to_bytes()
        .is_err()
    );
    // Addresses and UUIDs are ASCII (the Python side decodes them so).
    assert!(
        Request::Init {
            seq: 0,
            address: "é".into()
        }
        .to_bytes()
        .is_err()
    );
}

#[test]
fn every_length_is_checked_before_its_bytes() {
    let lim = Limits::default();
    let cases: Vec<(Vec<u8>, Field)> = vec![
        (vec![0x04, 0xff, 0xff], Field::Name),
        (vec![0x01, 0x01, 0x00, 65], Field::Address),
        (vec![0x02, 0x01, 0x00, 65], Field::Characteristic),
        (vec![0x03, 0x01, 0x00, 65], Field::Characteristic),
        (vec![0x03, 0x01, 0x00, 0x01, b'x', 0x02, 0x01], Field::Data),
    ];
    for (bytes, field) in cases {
        let mut d = RequestDecoder::new(lim);
        d.push(&bytes);
        match d.next() {
            Some(Err(DecodeError::TooLong { field: f, .. })) => assert_eq!(f, field),
            other => panic!("{bytes:?}: {other:?}"),
        }
        // Nothing more after a fatal error, whatever comes.
        d.push(&[0xff]);
        assert_eq!(d.next(), None);
    }
    // Replies: a message, a UUID, a device list (against a smaller device limit: the
    // default is all a u16 count can say).
    let few = Limits {
        devices: 256,
        ..lim
    };
    let cases: Vec<(Expect, Vec<u8>, Field, Limits)> = vec![
        (Expect::Seq, vec![0xff, 0x10, 0x01], Field::Message, lim),
        (
            Expect::Seq,
            vec![0x01, 0x00, 65],
            Field::Characteristic,
            lim,
        ),
        (Expect::Scan, vec![0x00, 0x01, 0x01], Field::Devices, few),
        (Expect::Find, vec![0x00, 0x01, 0x00], Field::Name, lim),
    ];
    for (e, bytes, field, lim) in cases {
        let mut d = ReplyDecoder::new(lim);
        d.expect(e);
        d.push(&bytes);
        match d.next() {
            Some(Err(DecodeError::TooLong { field: f, .. })) => assert_eq!(f, field),
            other => panic!("{bytes:?}: {other:?}"),
        }
    }
}

/// A crowded room: a server may list up to 65,535 devices, and a client with the default
/// limits reads them all (it used to refuse more than 256, saying "bytes" for a count).
#[test]
fn a_scan_of_a_crowded_room_is_read_whole() {
    let devices: Vec<Device> = (0..1000)
        .map(|i| Device {
            name: format!("D2-{i:04X}"),
            address: format!("5E:D0:00:00:{:02X}:{:02X}", i / 256, i % 256),
        })
        .collect();
    let mut d = ReplyDecoder::new(Limits::default());
    d.expect(Expect::Scan);
    d.push(&Reply::Devices(devices.clone()).to_bytes().unwrap());
    assert_eq!(d.next(), Some(Ok(Reply::Devices(devices))));
    let few = Limits {
        devices: 10,
        ..Limits::default()
    };
    let mut d = ReplyDecoder::new(few);
    d.expect(Expect::Scan);
    d.push(&[0x00, 0x00, 0x0B]);
    let e = d.next().unwrap().unwrap_err();
    assert_eq!(
        e.to_string(),
        "the device list is 11 devices long, more than the 10 accepted"
    );
}

#[test]
fn unknown_opcodes_and_truncation() {
    let mut d = RequestDecoder::new(Limits::default());
    d.push(&[0x42, 0x00]);
    assert!(matches!(
        d.next(),
        Some(Err(DecodeError::UnknownOpcode { op: 0x42, .. }))
    ));
    let mut d = RequestDecoder::new(Limits::default());
    d.push(&[0x03, 0x01, 0x00, 0x02, b'a']);
    assert_eq!(d.next(), None);
    assert!(matches!(
        d.finish(),
        Some(DecodeError::Truncated { have: 5, .. })
    ));
    // NaN and infinite timeouts decode: the server decides what they mean.
    let mut d = RequestDecoder::new(Limits::default());
    d.push(&[0x00, 0x7f, 0xc0, 0x00, 0x00]);
    assert!(matches!(d.next(), Some(Ok(Request::Scan { timeout })) if timeout.is_nan()));
}

#[test]
fn invalid_text_is_answered_and_skipped() {
    // WRITE with a non-ASCII UUID: an error carrying its seq, then the next request.
    let mut b = vec![0x03, 0x07, 0x00, 0x02, 0xc3, 0xa9, 0x00, 0x01, 0x55];
    b.extend_from_slice(&Request::End.to_bytes().unwrap());
    // FIND with invalid UTF-8: an error without seq.
    b.extend_from_slice(&[0x04, 0x00, 0x01, 0xff, 0, 0, 0, 0]);
    let out = decode_requests(&[b]);
    assert_eq!(out.len(), 3);
    assert!(matches!(
        out[0],
        Err(DecodeError::BadText {
            seq: Some(7),
            ascii: true,
            ..
        })
    ));
    assert_eq!(out[1], Ok(Request::End));
    assert!(matches!(
        out[2],
        Err(DecodeError::BadText { seq: None, .. })
    ));
}
