//! Fuzz the streaming v2 decoder: arbitrary bytes in arbitrary chunks must never panic,
//! never buffer more than the bound, keep the stats consistent, and every packet that comes
//! out must describe without panicking and survive an encode/decode round trip.
//!
//! Input layout: the first byte's low nibble says how many of the following bytes are chunk
//! sizes (cycled); the rest is the byte stream. No sizes means one single feed.

#![no_main]

use droidctl::protocol::v2::decoder::DEFAULT_MAX_BODY;
use droidctl::protocol::v2::packet::{checksum, parse_body};
use droidctl::protocol::v2::{Decoder, Notification, Packet, StreamingConfig, describe};
use libfuzzer_sys::fuzz_target;

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
    let mut handle = |event: Result<Packet, droidctl::protocol::v2::DecodeError>| match event {
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
    let mut pos = 0;
    let mut i = 0;
    while pos < stream.len() {
        let size = if sizes.is_empty() {
            stream.len()
        } else {
            sizes[i % sizes.len()] as usize
        };
        i += 1;
        // A zero size is an empty feed (allowed), then at least one byte to make progress.
        if size == 0 {
            for e in decoder.feed(&[]) {
                handle(e);
            }
        }
        let end = (pos + size.max(1)).min(stream.len());
        for e in decoder.feed(&stream[pos..end]) {
            handle(e);
        }
        assert!(decoder.buffered() <= bound);
        pos = end;
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

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else {
        return;
    };
    let n = ((head & 0x0F) as usize).min(rest.len());
    let (sizes, stream) = rest.split_at(n);
    run(&mut Decoder::new(), DEFAULT_MAX_BODY, sizes, stream);
    run(
        &mut Decoder::with_max_body(SMALL_BOUND),
        SMALL_BOUND,
        sizes,
        stream,
    );
});
