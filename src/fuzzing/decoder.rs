//! Fuzz the streaming decoders, v2, v1 (both sides) and the RSRCP framer, plus RSRCP's
//! one-value-per-notification decoding: arbitrary bytes in arbitrary chunks
//! must never panic, never buffer more than the bound, keep the stats consistent, and every
//! packet that comes out must describe without panicking and survive an encode/decode round
//! trip.
//!
//! Input layout: the first byte's low nibble says how many of the following bytes are chunk
//! sizes (cycled); the rest is the byte stream. No sizes means one single feed.

use super::{Target, feeds};
use crate::protocol::rsrcp;
use crate::protocol::v1;
use crate::protocol::v2::decoder::DEFAULT_MAX_BODY;
use crate::protocol::v2::packet::{checksum, parse_body};
use crate::protocol::v2::{Decoder, Notification, Packet, StreamingConfig, describe};

pub const TARGET: Target = Target {
    name: "decoder",
    run: run_input,
    dictionary: &[
        &[0x8D],
        &[0xD8],
        &[0xAB, 0x05],
        &[0xAB, 0x50],
        &[0xFF, 0xFF],
        &[0xFF, 0xFE],
        &[0x7E],
        &[0x8D, 0x0A, 0x13, 0x0D, 0x00, 0xD5, 0xD8],
    ],
};

/// A small bound as well as the default one, so the oversize path is reached often.
const SMALL_BOUND: usize = 24;

fn check_packet(p: &Packet, streaming: &StreamingConfig) {
    let _ = describe(p, None);
    let _ = describe(p, Some(streaming));
    if p.is_notification() {
        let _ = Notification::decode(p, streaming);
    }
    // What was decoded encodes back to something that decodes to the same packet.
    let wire = p.encode();
    let again = Decoder::new().decode_all(&wire);
    assert_eq!(again.len(), 1, "re-encoded packet decodes to {again:?}");
    assert_eq!(again[0].as_ref().ok(), Some(p));
    let mut body = p.body();
    body.push(checksum(&body));
    assert_eq!(parse_body(&body).as_ref().ok(), Some(p));
}

fn run(decoder: &mut Decoder, bound: usize, sizes: &[u8], stream: &[u8]) {
    let streaming = StreamingConfig::full(100);
    let mut packet_bytes = 0u64;
    let mut packets = 0u64;
    let mut errors = 0u64;
    let mut handle = |event: Result<Packet, crate::protocol::v2::DecodeError>| match event {
        Ok(p) => {
            check_packet(&p, &streaming);
            packet_bytes += p.encode().len() as u64;
            packets += 1;
        }
        Err(e) => {
            errors += 1;
            let _ = e.to_string();
            if let Some(p) = &e.packet {
                let _ = describe(p, None);
            }
        }
    };
    for feed in feeds(sizes, stream) {
        for e in decoder.feed(feed) {
            handle(e);
        }
        assert!(decoder.buffered() <= bound);
    }
    for e in decoder.finish() {
        handle(Err(e));
    }
    let s = decoder.stats();
    assert_eq!(s.bytes, stream.len() as u64);
    assert_eq!(s.packets, packets);
    assert_eq!(s.total_errors(), errors);
    assert_eq!(packet_bytes + s.skipped_bytes, s.bytes);
    assert_eq!(decoder.buffered(), 0);
}

fn check_v1_packet(p: &v1::Packet, source: v1::Source, streaming: &v1::StreamingConfig) {
    for cfg in [None, Some(streaming)] {
        for request in [None, Some(&v1::cmd::get_power_state())] {
            let d = v1::describe(p, cfg, request);
            let _ = v1::to_json(p, &d, true);
            let _ = d.label(p);
        }
    }
    if let v1::Packet::Async(a) = p {
        let _ = v1::decode_async(a, streaming);
        let _ = v1::decode_async(a, &v1::StreamingConfig::default());
    }
    // What was decoded encodes back to exactly one packet equal to it.
    let wire = p.encode().expect("a decoded packet fits its DLEN");
    assert_eq!(wire.len(), p.wire_len());
    let mut d = v1::Decoder::new(source);
    let mut again = d.decode_all(&wire);
    again.extend(d.finish());
    assert_eq!(again.len(), 1, "re-encoded packet decodes to {again:?}");
    assert_eq!(again[0].as_ref().ok(), Some(p));
}

/// The v1 decoder reading one side of the link, with the given async bound.
fn run_v1(source: v1::Source, max_async: usize, sizes: &[u8], stream: &[u8]) {
    let streaming = v1::StreamingConfig {
        m: 2,
        ..v1::StreamingConfig::full(40)
    };
    let mut decoder = v1::Decoder::with_max_async_dlen(source, max_async);
    let bound = decoder.max_packet_len();
    let mut packet_bytes = 0u64;
    let mut packets = 0u64;
    let mut errors = 0u64;
    let mut handle = |event: Result<v1::Packet, v1::DecodeError>| match event {
        Ok(p) => {
            check_v1_packet(&p, source, &streaming);
            packet_bytes += p.wire_len() as u64;
            packets += 1;
        }
        Err(e) => {
            errors += 1;
            let _ = e.to_string();
            if let Some(p) = &e.packet {
                let _ = v1::describe(p, Some(&streaming), None);
            }
        }
    };
    for feed in feeds(sizes, stream) {
        for e in decoder.feed(feed) {
            handle(e);
        }
        assert!(decoder.buffered() <= bound);
    }
    for e in decoder.finish() {
        handle(e);
    }
    let s = decoder.stats();
    assert_eq!(s.bytes, stream.len() as u64);
    assert_eq!(s.packets, packets);
    assert_eq!(s.total_errors(), errors);
    assert_eq!(packet_bytes + s.skipped_bytes, s.bytes);
    assert_eq!(decoder.buffered(), 0);
}

/// An RSRCP item: describes without panicking, and a frame (which only holds sized
/// features) encodes back to bytes that decode to it.
fn check_rsrcp_item(item: &rsrcp::Item) {
    let _ = rsrcp::to_json(&Ok(item.clone()));
    match item {
        rsrcp::Item::Handshake(h) => {
            assert_eq!(rsrcp::decode_handshake(&h.encode()).as_ref(), Ok(h));
        }
        rsrcp::Item::Frame(f) => {
            let _ = (f.summary(), f.fields(), f.sensor_sample());
            // Encoding clamps motor speeds to the robot's ±300 rad/s; decoding keeps what was
            // sent (up to ±327.67), so only in-range frames must survive unchanged.
            let in_range = f.motors.is_none_or(|m| {
                m.left_rad_s.abs() <= rsrcp::frame::MOTOR_LIMIT_RAD_S
                    && m.right_rad_s.abs() <= rsrcp::frame::MOTOR_LIMIT_RAD_S
            });
            let again = rsrcp::decode_frame(&f.encode());
            if in_range {
                assert_eq!(again.as_ref(), Ok(f));
            } else {
                assert!(again.is_ok());
            }
        }
    }
}

/// The RSRCP stream framer: bounded, every byte accounted for, never panics.
fn run_rsrcp(sizes: &[u8], stream: &[u8]) {
    let mut framer = rsrcp::Framer::new();
    let mut items = 0u64;
    let mut handle = |r: Result<rsrcp::Item, rsrcp::FrameError>| {
        let _ = rsrcp::to_json(&r);
        match r {
            Ok(item) => {
                items += 1;
                check_rsrcp_item(&item);
            }
            Err(e) => {
                let _ = (e.to_string(), e.to_json());
            }
        }
    };
    for feed in feeds(sizes, stream) {
        for r in framer.feed(feed) {
            handle(r);
        }
        assert!(framer.buffered() <= rsrcp::MAX_FRAME_LEN);
    }
    for r in framer.finish() {
        handle(r);
    }
    let s = framer.stats();
    assert_eq!(s.bytes, stream.len() as u64);
    assert_eq!(s.packets, items);
    assert_eq!(framer.buffered(), 0);
    // Over BLE each notification is one value: the same bytes as one notification.
    match rsrcp::decode_frame(stream) {
        Ok(f) => check_rsrcp_item(&rsrcp::Item::Frame(f)),
        Err(e) => {
            let _ = e.to_json();
        }
    }
    if let Ok(h) = rsrcp::decode_handshake(stream) {
        check_rsrcp_item(&rsrcp::Item::Handshake(h));
    }
}

/// The harness: the first byte's low nibble counts chunk sizes, the rest is the stream.
pub fn run_input(data: &[u8]) {
    let Some((_, sizes, stream)) = super::split(data) else {
        return;
    };
    run(&mut Decoder::new(), DEFAULT_MAX_BODY, sizes, stream);
    run(
        &mut Decoder::with_max_body(SMALL_BOUND),
        SMALL_BOUND,
        sizes,
        stream,
    );
    for source in [v1::Source::Host, v1::Source::Droid] {
        run_v1(source, v1::decoder::DEFAULT_MAX_ASYNC_DLEN, sizes, stream);
        run_v1(source, SMALL_BOUND, sizes, stream);
    }
    run_rsrcp(sizes, stream);
}
