//! Throughput of the v2 codec on a realistic mixed stream: sensor-streaming notifications of the
//! full mask set, responses, drive commands, collisions and LED commands whose payloads need
//! escaping. Reported in bytes/s; the stream's packet count is printed so packets/s follows.
//!
//! `cargo bench --bench codec -- --warm-up-time 1 --measurement-time 3`
//!
//! `v2/decode_borrowed*` is the borrowing decoder `packet decode --file` uses (nothing
//! allocated per packet); `capture/file_summary` is all of `packet decode --file --summary`
//! (64 KiB blocks from a reader, the decoder, the counts) over a 16 MiB capture;
//! `capture/file_json` the same printed as JSON lines (packets/s); `capture/btsnoop_load`
//! loads a generated multi-megabyte phone log for replay (HCI and ATT decoded, events out). With
//! `DROIDCTL_CODEC_STREAM=PATH` the stream is also written to PATH, for
//! `benches/spherov2_compare.sh` to time another parser on the same bytes.

// criterion is a dev-dependency on Linux only (see Cargo.toml); elsewhere this is an empty
// program.
#![cfg_attr(not(target_os = "linux"), allow(dead_code, unused_imports))]

#[cfg(target_os = "linux")]
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use droidctl::protocol::v2::sensor::encode_sample;
use droidctl::protocol::v2::wire::{AccelRaw, Bytes, CollisionAxis};
use droidctl::protocol::v2::wire::{DriveFlags, LegState, Mask};
use droidctl::protocol::v2::{
    Collision, Decoded, Decoder, ErrorCode, Packet, StreamingConfig, cmd,
};
use droidctl::units::Heading;
use std::hint::black_box;

/// Deterministic pseudo-random numbers (xorshift64*), so every run measures the same stream.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }

    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
}

/// About one second of a busy session: mostly sensor data at the full mask set, with the
/// commands and responses of a driver steering the droid.
fn mixed_packets() -> Vec<Packet> {
    let mut r = Rng(0x00C0_FFEE_D401_D5EE);
    let cfg = StreamingConfig::full(150);
    let mut seq = 0u8;
    let mut next_seq = || {
        let s = seq;
        seq = if seq == 254 { 0 } else { seq + 1 };
        s
    };
    let mut out = Vec::new();
    for i in 0..1000 {
        match i % 10 {
            // 50 %: sensor streaming, 14 f32 values.
            0..=4 => {
                let values = [
                    ("pitch", r.range(-10.0, 10.0)),
                    ("roll", r.range(-10.0, 10.0)),
                    ("yaw", r.range(-180.0, 180.0)),
                    ("accel_x", r.range(-0.3, 0.3)),
                    ("accel_y", r.range(-0.3, 0.3)),
                    ("accel_z", r.range(0.8, 1.2)),
                    ("locator_x", r.range(-300.0, 300.0)),
                    ("locator_y", r.range(-300.0, 300.0)),
                    ("velocity_x", r.range(-80.0, 80.0)),
                    ("velocity_y", r.range(-80.0, 80.0)),
                    ("head_angle", r.range(-160.0, 180.0)),
                    ("gyro_x", r.range(-200.0, 200.0)),
                    ("gyro_y", r.range(-200.0, 200.0)),
                    ("gyro_z", r.range(-200.0, 200.0)),
                ];
                out.push(Packet::notification(
                    0x18,
                    0x02,
                    encode_sample(&cfg, &values),
                ));
            }
            // 20 %: drive commands (SEQ runs through 0x8D, 0xAB and 0xD8, which get escaped).
            5 | 6 => {
                let heading = Heading::new((r.next() % 360) as u16).unwrap_or_default();
                let speed = (r.next() % 256) as u8;
                let flags = if r.next().is_multiple_of(4) {
                    DriveFlags::BACKWARD
                } else {
                    DriveFlags::empty()
                };
                out.push(cmd::drive_with_heading(speed, heading, flags).to_packet(next_seq()));
            }
            // 20 %: responses to earlier commands.
            7 | 8 => {
                let request = match r.next() % 4 {
                    0 => cmd::drive_with_heading(0, Heading::default(), DriveFlags::empty()),
                    1 => cmd::get_battery_voltage(),
                    2 => cmd::get_head_position(),
                    _ => cmd::get_leg_action(),
                }
                .to_packet(next_seq());
                let data = match request.cid {
                    0x03 => (380 + (r.next() % 40) as u16).to_be_bytes().to_vec(),
                    0x14 => r.range(-160.0, 180.0).to_be_bytes().to_vec(),
                    0x25 => vec![LegState::Tripod.to_byte()],
                    _ => vec![],
                };
                out.push(Packet::response_to(&request, ErrorCode::Success, data));
            }
            // 10 %: collisions and LED commands whose values are the framing bytes.
            _ => {
                if r.next().is_multiple_of(2) {
                    let c = Collision {
                        accel: [AccelRaw(4096), AccelRaw(-2048), AccelRaw(512)],
                        axis: CollisionAxis { x: true, y: false },
                        power: [120, -40, 8],
                        speed: 90,
                        time_ms: r.next() as u32,
                    };
                    out.push(Packet::notification(0x18, 0x12, c.encode()));
                } else {
                    let leds = cmd::set_all_leds_with_16_bit_mask(
                        Mask(0x00FF),
                        Bytes(vec![0x8D, 0xAB, 0xD8, 0x00, 0xFF, 0x8D, 0xD8, 0xAB]),
                    );
                    out.push(leds.to_packet(next_seq()));
                }
            }
        }
    }
    out
}

/// A btsnoop log (HCI H4) of a connection whose droid notifies `packets` over and over, until
/// the log holds about `size` bytes.
fn btsnoop_log(packets: &[Packet], size: usize) -> Vec<u8> {
    use droidctl::capture::btsnoop::Datalink;
    use droidctl::capture::hci::build::Log;
    let (conn, api) = (0x0040, 0x000E);
    let mut log = Log::new(Datalink::H4);
    log.le_connected(conn);
    log.declare(conn, &[(api, droidctl::family::v2::gatt::V2_API)]);
    'fill: loop {
        for p in packets {
            log.advance(1);
            log.notify(conn, api, &p.encode());
            if log.bytes.len() >= size {
                break 'fill;
            }
        }
    }
    log.bytes
}

#[cfg(target_os = "linux")]
fn codec(c: &mut Criterion) {
    let packets = mixed_packets();
    let stream: Vec<u8> = packets.iter().flat_map(Packet::encode).collect();
    let unescaped: usize = packets.iter().map(|p| p.body().len() + 3).sum();
    eprintln!(
        "codec stream: {} packets, {} wire bytes ({} escape bytes), {:.1} bytes/packet",
        packets.len(),
        stream.len(),
        stream.len() - unescaped,
        stream.len() as f64 / packets.len() as f64
    );

    if let Some(path) = std::env::var_os("DROIDCTL_CODEC_STREAM") {
        std::fs::write(&path, &stream).expect("write the stream");
    }
    // Only the full-mask sensor notifications (half of the mixed stream), and the masks
    // `packet decode --sensor-mask M --ext-mask E` decodes them with (issue 27 point 10:
    // `benches/spherov2_compare.sh` times `packet decode --json` on them against spherov2).
    if let Some(path) = std::env::var_os("DROIDCTL_SENSOR_STREAM") {
        let sensors: Vec<u8> = packets
            .iter()
            .enumerate()
            .filter(|(i, _)| i % 10 < 5)
            .flat_map(|(_, p)| p.encode())
            .collect();
        std::fs::write(&path, &sensors).expect("write the sensor stream");
        let cfg = StreamingConfig::full(150);
        let masks = format!("0x{:08X} 0x{:08X}\n", cfg.mask, cfg.ext_mask);
        let mut masks_path = path.clone();
        masks_path.push(".masks");
        std::fs::write(masks_path, masks).expect("write the masks");
    }

    let mut group = c.benchmark_group("v2");
    group.throughput(Throughput::Bytes(stream.len() as u64));

    // The borrowing API: packets borrow the decoder's buffer, nothing is allocated.
    group.bench_function("decode_borrowed", |b| {
        b.iter(|| {
            let mut d = Decoder::new();
            let mut n = 0;
            d.feed_with(black_box(&stream), |e| {
                if let Decoded::Packet { packet, .. } = e {
                    n += 1;
                    black_box(packet.data);
                }
            });
            assert_eq!(n, packets.len());
            n
        })
    });

    group.bench_function("decode_borrowed_ble_chunks", |b| {
        b.iter(|| {
            let mut d = Decoder::new();
            let mut n = 0;
            for chunk in black_box(&stream).chunks(20) {
                d.feed_with(chunk, |e| {
                    if let Decoded::Packet { .. } = e {
                        n += 1;
                    }
                });
            }
            assert_eq!(n, packets.len());
            n
        })
    });

    group.bench_function("decode", |b| {
        b.iter(|| {
            let mut d = Decoder::new();
            let n = d.feed(black_box(&stream)).filter(Result::is_ok).count();
            assert_eq!(n, packets.len());
            n
        })
    });

    // As the bytes arrive over BLE: 20-byte notifications.
    group.bench_function("decode_ble_chunks", |b| {
        b.iter(|| {
            let mut d = Decoder::new();
            let mut n = 0;
            for chunk in black_box(&stream).chunks(20) {
                n += d.feed(chunk).filter(Result::is_ok).count();
            }
            assert_eq!(n, packets.len());
            n
        })
    });

    group.bench_function("encode", |b| {
        let mut buf = Vec::with_capacity(stream.len());
        b.iter(|| {
            buf.clear();
            for p in black_box(&packets) {
                p.encode_into(&mut buf);
            }
            assert_eq!(buf.len(), stream.len());
            buf.len()
        })
    });
    group.finish();

    // A large capture through `packet decode --file --summary`, from memory.
    let big: Vec<u8> = stream
        .iter()
        .copied()
        .cycle()
        .take(stream.len() * ((16 << 20) / stream.len()))
        .collect();
    let mut group = c.benchmark_group("capture");
    group.throughput(Throughput::Bytes(big.len() as u64));
    group.sample_size(20);
    group.bench_function("file_summary", |b| {
        b.iter(|| {
            let mut input = std::io::Cursor::new(black_box(&big));
            let summary = droidctl::cli::packet::decode_reader(
                &mut input,
                Default::default(),
                false,
                true,
                &mut std::io::sink(),
            )
            .expect("decodes");
            assert_eq!(summary.error_total(), 0);
            summary.packets
        })
    });
    group.finish();

    // The same stream printed as JSON lines (`packet decode --file - --json`), one object per
    // packet written straight into the output buffer; 2 MiB per iteration.
    let json_input: Vec<u8> = stream
        .iter()
        .copied()
        .cycle()
        .take(stream.len() * ((2 << 20) / stream.len()))
        .collect();
    let packets_per_iter = packets.len() as u64 * ((2 << 20) / stream.len()) as u64;
    let mut group = c.benchmark_group("capture");
    group.throughput(Throughput::Elements(packets_per_iter));
    group.sample_size(20);
    group.bench_function("file_json", |b| {
        b.iter(|| {
            let mut input = std::io::Cursor::new(black_box(&json_input));
            let summary = droidctl::cli::packet::decode_reader(
                &mut input,
                droidctl::cli::packet::DecodeArgs {
                    sensor_mask: Some(format!("0x{:08X}", StreamingConfig::full(150).mask)),
                    ext_mask: Some(format!("0x{:08X}", StreamingConfig::full(150).ext_mask)),
                    ..Default::default()
                },
                true,
                false,
                &mut std::io::sink(),
            )
            .expect("decodes");
            assert_eq!(summary.packets, packets_per_iter);
            summary.packets
        })
    });
    group.finish();

    // A phone's log of a long session: every packet of the stream notified as the droid
    // sends it, repeated to about 8 MB of btsnoop records, loaded as replay loads it.
    let log = btsnoop_log(&packets, 8 << 20);
    eprintln!("btsnoop log: {} bytes", log.len());
    let mut group = c.benchmark_group("capture");
    group.throughput(Throughput::Bytes(log.len() as u64));
    group.sample_size(10);
    group.bench_function("btsnoop_load", |b| {
        b.iter(|| {
            let c = droidctl::capture::hci::capture_from_btsnoop(black_box(&log), &[])
                .expect("a droid's traffic");
            c.events.len()
        })
    });
    group.finish();
}

#[cfg(target_os = "linux")]
criterion_group!(benches, codec);
#[cfg(target_os = "linux")]
criterion_main!(benches);

#[cfg(not(target_os = "linux"))]
fn main() {
    eprintln!("the benchmarks run on Linux only");
}
