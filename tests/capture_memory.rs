//! Memory of big decodes, measured by a counting allocator (this test binary's own global
//! allocator, counting only on the thread that asks): `packet decode --file` keeps memory
//! flat whatever the input's size, and the v2 decoder's borrowing API allocates nothing per
//! packet.

use droidctl::cli::packet::{DecodeArgs, decode_reader};
use droidctl::protocol::v2::{Decoded, Decoder, Packet};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::Read;

struct Counting;

thread_local! {
    static TRACK: Cell<bool> = const { Cell::new(false) };
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
}

fn note(delta: isize, alloc: bool) {
    let _ = TRACK.try_with(|t| {
        if t.get() {
            LIVE.with(|l| {
                let v = l.get() + delta;
                l.set(v);
                PEAK.with(|p| p.set(p.get().max(v)));
            });
            if alloc {
                ALLOCS.with(|a| a.set(a.get() + 1));
            }
        }
    });
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size() as isize, true);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        note(-(layout.size() as isize), false);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size as isize - layout.size() as isize, true);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Run `f` counting this thread's heap: (peak live bytes above the start, allocations).
fn measure<T>(f: impl FnOnce() -> T) -> (T, isize, u64) {
    LIVE.with(|l| l.set(0));
    PEAK.with(|p| p.set(0));
    ALLOCS.with(|a| a.set(0));
    TRACK.with(|t| t.set(true));
    let r = f();
    TRACK.with(|t| t.set(false));
    (r, PEAK.with(Cell::get), ALLOCS.with(Cell::get))
}

/// A v2 stream: commands, responses and notifications, some needing escapes.
fn packets() -> Vec<u8> {
    let mut out = Vec::new();
    for i in 0..64u8 {
        out.extend(Packet::command(0x16, 0x07, i, vec![100, 0, i, 0]).encode());
        let req = Packet::command(0x13, 0x0D, i, vec![]);
        out.extend(
            Packet::response_to(&req, droidctl::protocol::v2::ErrorCode::Success, vec![]).encode(),
        );
        out.extend(
            Packet::notification(0x18, 0x02, vec![0x8D, 0xAB, 0xD8, i, 1, 2, 3, 4]).encode(),
        );
    }
    out
}

/// `total` bytes of the stream repeated, produced on the fly (never held whole).
struct Repeat {
    pattern: Vec<u8>,
    at: usize,
    left: usize,
}

impl Read for Repeat {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let mut n = 0;
        while n < buf.len() && self.left > 0 {
            let take = (self.pattern.len() - self.at)
                .min(buf.len() - n)
                .min(self.left);
            buf[n..n + take].copy_from_slice(&self.pattern[self.at..self.at + take]);
            self.at = (self.at + take) % self.pattern.len();
            self.left -= take;
            n += take;
        }
        Ok(n)
    }
}

#[test]
fn a_multi_megabyte_file_decodes_in_flat_memory() {
    let pattern = packets();
    let per_pass = pattern.len();
    for (total, summary_only, json) in [
        (8 << 20, true, false),
        (2 << 20, false, false),
        (2 << 20, false, true),
    ] {
        let whole_passes = total / per_pass;
        let mut input = Repeat {
            pattern: pattern.clone(),
            at: 0,
            left: whole_passes * per_pass,
        };
        let mut out = std::io::sink();
        let (summary, peak, _) = measure(|| {
            decode_reader(
                &mut input,
                DecodeArgs::default(),
                json,
                summary_only,
                &mut out,
            )
        });
        let summary = summary.expect("decodes");
        assert_eq!(summary.packets, whole_passes as u64 * 192);
        assert_eq!(summary.error_total(), 0);
        // Two 64 KiB blocks and the decoder; nothing that grows with the input.
        assert!(
            peak < 512 * 1024,
            "peak heap {peak} bytes for {total} bytes of input (summary only: {summary_only})"
        );
    }
}

#[test]
fn hex_input_of_megabytes_is_flat_too() {
    let mut text: Vec<u8> = droidctl::hex::spaced(&packets()).into_bytes();
    text.push(b'\n');
    let mut input = Repeat {
        left: text.len() * 200,
        pattern: text,
        at: 0,
    };
    let (summary, peak, _) = measure(|| {
        decode_reader(
            &mut input,
            DecodeArgs::default(),
            false,
            true,
            &mut std::io::sink(),
        )
    });
    let summary = summary.expect("decodes");
    assert!(summary.hex);
    assert!(summary.packets >= 192 * 199);
    assert!(peak < 512 * 1024, "peak heap {peak}");
}

#[test]
fn feed_with_allocates_nothing_per_packet() {
    let pattern = packets();
    let stream: Vec<u8> = pattern
        .iter()
        .copied()
        .cycle()
        .take(pattern.len() * 500)
        .collect();
    let mut d = Decoder::new();
    // Warm up: the first packet sizes nothing, but be fair to lazy statics.
    d.feed_with(&pattern, |_| {});
    let mut n = 0u64;
    let ((), _, allocs) = measure(|| {
        for chunk in stream.chunks(20) {
            d.feed_with(chunk, |e| {
                if let Decoded::Packet { packet, .. } = e {
                    n += packet.data.len() as u64 + 1;
                }
            });
        }
    });
    assert_eq!(d.stats().total_errors(), 0);
    assert!(n > 0);
    assert_eq!(
        allocs,
        0,
        "heap allocations while decoding {} packets",
        192 * 500
    );
}
