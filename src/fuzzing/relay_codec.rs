//! Fuzz the relay protocol's decoders (spherov2's TCP relay): arbitrary bytes in arbitrary
//! chunks must never panic, never buffer more than one request plus the chunk pushed, never
//! yield more items than bytes, and every request that comes out must encode back to bytes
//! that decode to the same request.
//!
//! Input layout: the first byte's low nibble says how many of the following bytes are chunk
//! sizes (cycled); its high bits choose the reply expectations queued; the rest is the stream.

use super::Target;
use crate::protocol::relay::{Expect, Limits, Reply, ReplyDecoder, Request, RequestDecoder};

pub const TARGET: Target = Target {
    name: "relay",
    run: run_input,
    dictionary: &[
        &[0x00],
        &[0x01],
        &[0x02],
        &[0x03],
        &[0x04],
        &[0x05],
        b"00010002-574f-4f20-5370-6865726f2121",
        b"D2-1A2B",
        b"5E:D0:00:00:00:01",
    ],
};

fn same(a: &Request, b: &Request) -> bool {
    // NaN timeouts are equal by their bits.
    match (a, b) {
        (Request::Scan { timeout: x }, Request::Scan { timeout: y }) => x.to_bits() == y.to_bits(),
        (
            Request::Find {
                name: n,
                timeout: x,
            },
            Request::Find {
                name: m,
                timeout: y,
            },
        ) => n == m && x.to_bits() == y.to_bits(),
        _ => a == b,
    }
}

/// The harness (layout above).
pub fn run_input(data: &[u8]) {
    let Some((&head, rest)) = data.split_first() else {
        return;
    };
    let n = (head & 0x0f) as usize;
    let (sizes, stream) = rest.split_at(n.min(rest.len()));
    let limits = Limits::default();
    let bound = 1 + 1 + 2 + limits.text + 2 + limits.data;
    let mut chunks = Vec::new();
    let mut at = 0;
    let mut i = 0;
    while at < stream.len() {
        let size = if sizes.is_empty() {
            stream.len()
        } else {
            (sizes[i % sizes.len()] as usize).max(1)
        };
        let end = (at + size).min(stream.len());
        chunks.push(&stream[at..end]);
        at = end;
        i += 1;
    }

    let mut requests = RequestDecoder::new(limits);
    let mut count = 0;
    for c in &chunks {
        requests.push(c);
        while let Some(r) = requests.next() {
            count += 1;
            assert!(count <= stream.len());
            match r {
                Ok(req) => {
                    let wire = req.to_bytes().expect("a decoded request encodes");
                    let mut again = RequestDecoder::new(limits);
                    again.push(&wire);
                    let back = again.next().expect("whole").expect("valid");
                    assert!(same(&req, &back), "{req:?} vs {back:?}");
                }
                Err(e) => {
                    let _ = e.to_string();
                }
            }
        }
        assert!(requests.buffered() <= bound + c.len());
    }
    let _ = requests.finish();

    let mut replies = ReplyDecoder::new(limits);
    for k in 0..4 {
        replies.expect(match (head >> (4 + k)) & 1 {
            0 => Expect::Seq,
            _ if k % 2 == 0 => Expect::Scan,
            _ => Expect::Find,
        });
    }
    let mut count = 0;
    for c in &chunks {
        replies.push(c);
        while let Some(r) = replies.next() {
            count += 1;
            assert!(count <= stream.len());
            if let Ok(Reply::Data { data, .. }) = &r {
                assert!(data.len() <= 255);
            }
        }
    }
    let _ = replies.finish();
}
