//! `droidctl packet decode --file -` on a mixed v2 stream, its output pinned byte for byte
//! (JSON with and without masks, and text), so the decoder's and the JSON writer's speed-ups
//! (issue 42 point 6) cannot change a byte of what users and scripts read.
//!
//! The stream is the shape of `benches/spherov2_mixed.py` (sensor notifications of 17 f32
//! values given without masks, drive commands, responses, LED commands whose values are the
//! framing bytes), plus what a fast path could get wrong: full-mask sensor samples, payloads
//! longer than 64 bytes, addressed packets, error responses, unknown commands, floats f32
//! holds only approximately (NaN, infinities, -0, subnormals), a bad checksum, garbage and a
//! packet cut short at the end.

use droidctl::protocol::v2::sensor::encode_sample;
use droidctl::protocol::v2::{ErrorCode, Flags, Packet, StreamingConfig};
use std::io::Write;
use std::process::{Command, Stdio};

/// Deterministic pseudo-random numbers (xorshift64*), so every run pins the same stream.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next() >> 40) as f32 / (1u64 << 24) as f32)
    }
}

/// f32 values a float printer can get wrong.
const AWKWARD: [f32; 12] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    -0.0,
    0.0,
    1.0e-45,
    1.0e-7,
    3.402_823_5e38,
    -125.694_3,
    0.1,
    16_777_216.0,
    100.0,
];

fn stream() -> Vec<u8> {
    let mut r = Rng(0x5EED_0042_0006_D8AB);
    let cfg = StreamingConfig::full(150);
    let mut out = Vec::new();
    for i in 0..60u8 {
        let p = match i % 10 {
            0..=3 => {
                let values: Vec<f32> = (0..17).map(|_| r.range(-300.0, 300.0)).collect();
                let data = values.iter().flat_map(|v| v.to_be_bytes()).collect();
                Packet::notification(0x18, 0x02, data)
            }
            4 => {
                // The full configuration's fields, in its order (v2_vectors pins that order).
                let names: Vec<&str> = cfg.layout().iter().flatten().map(|f| f.name).collect();
                let values: Vec<(&str, f32)> =
                    names.iter().map(|n| (*n, r.range(-200.0, 200.0))).collect();
                Packet::notification(0x18, 0x02, encode_sample(&cfg, &values))
            }
            5 => {
                let heading = (r.next() % 360) as u16;
                let [h0, h1] = heading.to_be_bytes();
                Packet::command(0x16, 0x07, i, vec![(r.next() % 256) as u8, h0, h1, i % 2])
            }
            6 => {
                let request = Packet::command(0x13, 0x03, 0x8D ^ i, vec![]);
                let err = if i == 16 {
                    ErrorCode::from_byte(0x03)
                } else {
                    ErrorCode::Success
                };
                Packet::response_to(&request, err, (380 + i as u16).to_be_bytes().to_vec())
            }
            7 => {
                let mut p = Packet::command(0x1A, 0x0E, 0xAB, vec![0x00, 0xFF]);
                p.data
                    .extend([0x8D, 0xAB, 0xD8, 0x00, 0xFF, 0x8D, 0xD8, 0xAB]);
                p.tid = Some(0x12);
                p.sid = Some(0x01);
                p.normalized()
            }
            8 => {
                // Floats printed at f32's precision, and some no printer should round.
                let start = (i as usize / 10) * 2 % AWKWARD.len();
                let values = AWKWARD.iter().cycle().skip(start).take(17);
                let data = values.flat_map(|v| v.to_be_bytes()).collect();
                Packet::notification(0x18, 0x02, data)
            }
            _ => {
                // Unknown ids, a long payload, extended flags.
                let mut p = Packet::command(0x3E, 0x7F, i, (0..90).map(|b| b as u8).collect());
                p.flags |= Flags::UNUSED;
                p.ext_flags = Some(0x01);
                p.normalized()
            }
        };
        out.extend(p.encode());
        if i == 23 {
            out.extend([0x00, 0x11, 0x22]);
        }
        if i == 37 {
            // A bad checksum.
            let mut bad = Packet::command(0x13, 0x0D, 7, vec![]).encode();
            let n = bad.len();
            bad[n - 2] ^= 0x01;
            out.extend(bad);
        }
    }
    out.extend(&Packet::command(0x13, 0x0D, 9, vec![1, 2, 3]).encode()[..5]);
    out
}

fn decode(input: &[u8], extra: &[&str]) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["packet", "decode", "--file", "-"])
        .args(extra)
        .env_remove("RUST_LOG")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run droidctl");
    let mut stdin = child.stdin.take().expect("stdin");
    let bytes = input.to_vec();
    let writer = std::thread::spawn(move || stdin.write_all(&bytes));
    let o = child.wait_with_output().expect("droidctl ends");
    writer.join().expect("writer").expect("write stdin");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{extra:?}: {stderr}");
    assert_eq!(stderr, "", "{extra:?}");
    String::from_utf8(o.stdout).expect("utf-8 output")
}

#[test]
fn a_mixed_stream_decodes_to_the_same_json_byte_for_byte() {
    let out = decode(&stream(), &["--json"]);
    // What the pin holds, said plainly, so a wrong snapshot cannot be accepted unseen.
    assert_eq!(
        out.lines().count(),
        60 + 1 + 2 + 1,
        "packets, bad checksum, 2 errors, summary"
    );
    assert!(out.contains(r#""values":[null,null,null,0.0,0.0,1e-45,1e-7,3.4028235e+38,-125.6943,0.1,16777216.0,100.0,null"#), "{out}");
    insta::assert_snapshot!("mixed_stream_json", out);
}

#[test]
fn a_mixed_stream_with_masks_decodes_to_the_same_json_byte_for_byte() {
    let cfg = StreamingConfig::full(150);
    let (mask, ext) = (
        format!("0x{:08X}", cfg.mask),
        format!("0x{:08X}", cfg.ext_mask),
    );
    let out = decode(
        &stream(),
        &["--json", "--sensor-mask", &mask, "--ext-mask", &ext],
    );
    assert!(out.contains(r#""fields":{"pitch":"#), "{out}");
    insta::assert_snapshot!("mixed_stream_json_masks", out);
}

#[test]
fn a_mixed_stream_decodes_to_the_same_text_byte_for_byte() {
    let out = decode(&stream(), &[]);
    assert!(out.contains("summary: v2 binary"), "{out}");
    insta::assert_snapshot!("mixed_stream_text", out);
}
