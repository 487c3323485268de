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

/// A crafted capture of several droids (issue 27 point 3): 64 droids listed, then lines about
/// a droid not listed and lines naming no droid. Their warnings are counted and summarised,
/// nothing is copied per droid, and memory stays small (it was 325 MB for 1 MB of lines).
#[test]
fn a_crafted_fleet_capture_stays_small() {
    use droidctl::capture::fleet;
    let mut text = String::from("droidctl-capture 2\n# droids: 64\n");
    for k in 1..=64 {
        text += &format!("# droid-{k}: r2d2 v2 D2-{k:04}\n");
    }
    let n = 60_000;
    for _ in 0..n {
        text += "@99 0.000 connect\n";
    }
    for _ in 0..n {
        text += "0.000 in notify 8d\n";
    }
    let (split, peak, _) = measure(|| fleet::read(&text).unwrap());
    assert_eq!(split.droids.len(), 64);
    // The first lines without `@K` are every droid's (as the recorder's `end` is); no more.
    let shared = droidctl::capture::fleet::MAX_SHARED;
    assert!(split.droids.iter().all(|c| c.events.len() == shared));
    // Said once, summarised: the first few, then a count.
    assert!(split.warnings.len() <= droidctl::capture::KEPT_WARNINGS + 1);
    let last = split.warnings.last().unwrap();
    assert!(
        last.contains(&format!("{} in all", 2 * n - shared)),
        "{last}"
    );
    // Each droid: at most its missing `end`.
    assert!(
        split.droids.iter().all(|c| c.warnings.len() <= 1),
        "nothing per droid"
    );
    assert!(
        peak < 512 * 1024,
        "peak {peak} bytes for a {} byte file",
        text.len()
    );
    // The same for one droid's bad lines: kept to a dozen.
    let mut bad = String::from("droidctl-capture 2\n# droid-1: r2d2 v2 D2-0001\n");
    for _ in 0..n {
        bad += "@1 not-a-time connect\n";
    }
    let split = fleet::read(&bad).unwrap();
    assert!(split.droids[0].warnings.len() <= droidctl::capture::KEPT_WARNINGS + 2);
}

/// One huge chunk (issue 27 point 4): a line of 1 MiB of `8d` bytes made replay use 313 MB.
/// Chunks beyond [`droidctl::capture::MAX_CHUNK`] are a counted, visible warning.
#[test]
fn one_huge_chunk_is_a_warning_not_150_times_its_size() {
    use droidctl::capture::Capture;
    let mut text =
        String::from("droidctl-capture 1\n# model: r2d2\n0.000 connect\n1000.000 in notify ");
    text += &"8d".repeat(1 << 20);
    text += "\n2000.000 in notify 8d\n3000.000 end\n";
    let ((capture, samples), peak, _) = measure(|| {
        let c = Capture::from_text(&text).unwrap();
        let mut n = 0;
        droidctl::capture::replay::samples(
            &c,
            droidctl::model::Model::R2D2,
            std::time::Duration::from_millis(100),
            &mut |_| {
                n += 1;
                Ok(())
            },
            &mut |_, _| {},
        )
        .unwrap();
        (c, n)
    });
    assert!(samples > 20);
    assert_eq!(capture.events.len(), 3, "the huge chunk is skipped");
    assert!(
        capture
            .warnings
            .iter()
            .any(|w| w.starts_with("line 4:") && w.contains("1048576 bytes")),
        "{:?}",
        capture.warnings
    );
    assert!(peak < 1 << 20, "peak {peak} bytes");
}

/// `plot` streams and reduces (issue 27 point 6: 10 M samples took 3.5 GB): 300,000
/// samples of a fleet's `run --json`, generated as they are read, fit in a few MB.
#[test]
fn plot_reads_any_number_of_samples_in_flat_memory() {
    use droidctl::plot::read;
    use droidctl::plot::track::Tracks;
    struct Lines {
        i: u64,
        n: u64,
        buf: Vec<u8>,
    }
    impl Read for Lines {
        fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
            if self.buf.is_empty() {
                if self.i == self.n {
                    return Ok(0);
                }
                let i = self.i;
                self.i += 1;
                let droid = ["D2-0001", "BB-0002"][(i % 2) as usize];
                self.buf = format!(
                    "{{\"droid\":\"{droid}\",\"t_ms\":{},\"x_cm\":{},\"y_cm\":{},\"speed\":{},\"heading\":90,\"head_deg\":null,\"stance\":\"tripod\",\"battery_v\":4.1,\"collisions\":{},\"yaw_deg\":{}}}\n",
                    i * 50,
                    (i % 1000) as f32 * 0.3,
                    (i % 777) as f32 * -0.2,
                    (i % 255) as f32,
                    i / 1000,
                    ((i % 360) as f32) - 180.0
                )
                .into_bytes();
            }
            let n = out.len().min(self.buf.len());
            out[..n].copy_from_slice(&self.buf[..n]);
            self.buf.drain(..n);
            Ok(n)
        }
    }
    let n = 300_000;
    let (tracks, peak, _) = measure(|| {
        let mut tracks = Tracks::new(&[]);
        let input = std::io::BufReader::new(Lines {
            i: 0,
            n,
            buf: Vec::new(),
        });
        read::json(input, "gen.jsonl", &mut tracks).unwrap();
        tracks
    });
    assert_eq!(tracks.samples(), n);
    assert_eq!(tracks.droids.len(), 2);
    assert!(peak < 8 << 20, "peak {peak} bytes for {n} samples");
}
