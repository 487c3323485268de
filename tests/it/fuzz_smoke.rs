//! Every fuzz target's harness (`droidctl::fuzzing`) on stable Rust: over its seed corpus in
//! `fuzz/corpus/NAME/`, then over inputs the seeded mutator makes of it (a few thousand,
//! fewer for the two that start a server per input), so CI exercises what libFuzzer runs.
//!
//! `DROIDCTL_FUZZ_SECS=600 DROIDCTL_FUZZ_TARGETS=capture,hci cargo test --release --test
//! fuzz_smoke -- --ignored long_run --nocapture` runs targets for as long as asked (the
//! stable engine of README's "Reliability" section). `write_seed_corpus` (ignored) writes
//! the generated seeds again.

use droidctl::capture::btsnoop::Datalink;
use droidctl::capture::hci::build::Log;
use droidctl::capture::{Capture, Event, Header, Timed};
use droidctl::family::{self, Command};
use droidctl::fuzzing::{self, runner};
use droidctl::gatt::{Endpoint, GattUuid};
use droidctl::model::Model;
use droidctl::protocol::relay::Request;
use droidctl::units::Heading;
use std::path::PathBuf;
use std::time::Duration;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn corpus_dir(name: &str) -> PathBuf {
    root().join("fuzz").join("corpus").join(name)
}

fn failures() -> PathBuf {
    std::env::temp_dir().join("droidctl-fuzz-failures")
}

/// The harness over its corpus and `generated` inputs made from it.
fn smoke(name: &str, generated: u64) {
    let target = fuzzing::target(name).expect("a target of that name");
    let corpus = runner::load_corpus(&corpus_dir(name));
    assert!(!corpus.is_empty(), "fuzz/corpus/{name} holds no seeds");
    let stats = runner::run(
        target,
        &corpus,
        runner::Budget::Inputs(generated),
        0x5EED ^ name.len() as u64,
        &failures(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(stats.generated, generated);
}

#[test]
fn decoder() {
    smoke("decoder", 4000);
}

#[test]
fn relay() {
    smoke("relay", 4000);
}

#[test]
fn btsnoop() {
    smoke("btsnoop", 3000);
}

#[test]
fn hci() {
    smoke("hci", 3000);
}

#[test]
fn capture() {
    smoke("capture", 3000);
}

#[test]
fn fleet_capture() {
    smoke("fleet_capture", 1000);
}

#[test]
fn plot() {
    smoke("plot", 500);
}

#[test]
fn script() {
    smoke("script", 4000);
}

#[test]
fn edu_wire() {
    smoke("edu_wire", 4000);
}

#[test]
fn config() {
    smoke("config", 2000);
}

#[test]
fn packet_file() {
    smoke("packet_file", 3000);
}

#[test]
fn relay_server() {
    smoke("relay_server", 1000);
}

#[test]
fn bridge() {
    smoke("bridge", 300);
}

#[test]
fn bridge_mqtt() {
    smoke("bridge_mqtt", 200);
}

#[test]
fn ros() {
    smoke("ros", 4000);
}

#[test]
fn broker() {
    smoke("broker", 300);
}

#[test]
fn session_core() {
    smoke("session_core", 4000);
}

/// Each input runs the whole app on three simulated droids: fewer inputs.
#[test]
fn app_input() {
    smoke("app_input", 40);
}

/// Each input starts a JavaScript engine: fewer inputs.
#[test]
fn edu() {
    smoke("edu", 60);
}

#[cfg(target_os = "linux")]
#[test]
fn bluez() {
    smoke("bluez", 300);
}

/// Each target has its seeds, its libFuzzer binary and its entry in the fuzz crate.
#[test]
fn every_target_has_a_corpus_and_a_binary() {
    let manifest = std::fs::read_to_string(root().join("fuzz/Cargo.toml")).unwrap();
    for t in fuzzing::targets() {
        let size: usize = runner::load_corpus(&corpus_dir(t.name))
            .iter()
            .map(Vec::len)
            .sum();
        assert!(size > 0, "{}: no seeds", t.name);
        assert!(
            size < 64 * 1024,
            "{}: {size} bytes of seeds: keep it small",
            t.name
        );
        let bin = root().join(format!("fuzz/fuzz_targets/{}.rs", t.name));
        assert!(bin.exists(), "{} is missing", bin.display());
        assert!(
            manifest.contains(&format!("name = \"{}\"", t.name)),
            "fuzz/Cargo.toml lacks {}",
            t.name
        );
    }
}

/// The stable engine for as long as asked: `DROIDCTL_FUZZ_SECS` per target (default 60),
/// the targets in `DROIDCTL_FUZZ_TARGETS` (default all), seed `DROIDCTL_FUZZ_SEED`.
#[test]
#[ignore]
fn long_run() {
    let secs: u64 = std::env::var("DROIDCTL_FUZZ_SECS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    let seed: u64 = std::env::var("DROIDCTL_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let only = std::env::var("DROIDCTL_FUZZ_TARGETS").ok();
    for t in fuzzing::targets() {
        if only
            .as_deref()
            .is_some_and(|o| !o.split(',').any(|n| n == t.name))
        {
            continue;
        }
        let corpus = runner::load_corpus(&corpus_dir(t.name));
        let stats = runner::run(
            t,
            &corpus,
            runner::Budget::Time(Duration::from_secs(secs)),
            seed,
            &failures(),
        );
        match stats {
            Ok(s) => println!(
                "{}: {} seeds + {} generated inputs in {:.0} s ({:.0}/s), no failure",
                t.name,
                s.corpus,
                s.generated,
                s.elapsed.as_secs_f64(),
                s.generated as f64 / s.elapsed.as_secs_f64()
            ),
            Err(e) => panic!("{e}"),
        }
    }
}

// -------------------------------------------------------------------------------------------
// The generated seeds
// -------------------------------------------------------------------------------------------

fn write(target: &str, name: &str, bytes: &[u8]) {
    let dir = corpus_dir(target);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// The wire bytes of `cmd` for `model` (each write with its endpoint).
fn wire(model: Model, cmd: &Command, seq: u8) -> Vec<(Endpoint, Vec<u8>)> {
    family::for_model(model)
        .codec()
        .encode_writes(cmd, seq, true)
        .0
}

/// A short session with the simulated droid: the setup, a drive, a stop, with what the
/// droid answered and notified, as capture events.
fn session_events(model: Model) -> Vec<Timed> {
    let f = family::for_model(model);
    let mut droid = droidctl::sim::wire_droid(model, droidctl::sim::SimConfig::for_model(model));
    let mut events = vec![Timed {
        at: Duration::ZERO,
        event: Event::Connect,
    }];
    for v in droid.connect(Duration::ZERO) {
        events.push(Timed {
            at: Duration::ZERO,
            event: Event::In(v),
        });
    }
    let setup = droidctl::family::setup::connect_setup(model, &Default::default());
    let h = Heading::new(90).unwrap();
    let cmds: Vec<Command> = setup
        .into_iter()
        .chain([f.drive(120, h, false), f.drive(0, h, false)])
        .collect();
    let mut at = Duration::ZERO;
    for (i, cmd) in cmds.iter().enumerate() {
        at += Duration::from_millis(120);
        for (to, bytes) in wire(model, cmd, i as u8) {
            events.push(Timed {
                at,
                event: Event::Out(to, bytes.clone()),
            });
            for answer in droid.receive_at(to, &bytes, at) {
                events.push(Timed {
                    at,
                    event: Event::In(answer),
                });
            }
        }
        for n in droid.advance(at + Duration::from_millis(60)) {
            events.push(Timed {
                at: at + Duration::from_millis(60),
                event: Event::In(n),
            });
        }
    }
    events.push(Timed {
        at: at + Duration::from_millis(200),
        event: Event::Close,
    });
    events.push(Timed {
        at: at + Duration::from_millis(201),
        event: Event::End,
    });
    events
}

fn capture_text(model: Model, marks: bool) -> Vec<u8> {
    let mut events = session_events(model);
    if marks {
        let end = events.last().unwrap().at;
        events.insert(
            1,
            Timed {
                at: Duration::from_millis(1),
                event: Event::Mark("mission-start".into()),
            },
        );
        events.insert(
            2,
            Timed {
                at: Duration::from_millis(2),
                event: Event::Mark("step 2 drive 120 90 for 1s".into()),
            },
        );
        events.insert(
            events.len() - 2,
            Timed {
                at: end,
                event: Event::Mark("mission-end".into()),
            },
        );
        events.sort_by_key(|t| t.at);
    }
    let c = Capture {
        header: Header {
            droidctl: Some("0.1.0".into()),
            model: Some(model),
            family: Some(model.protocol()),
            droid: Some(model.display_name().into()),
            started: Some("2025-06-01T10:00:00.123Z".into()),
        },
        events,
        warnings: Vec::new(),
        kind: "droidctl capture",
    };
    c.to_text().into_bytes()
}

/// A phone's log of a session with `model`: connected, discovered, the session's writes and
/// what the droid sent, disconnected.
fn phone_log(model: Model, datalink: Datalink) -> Log {
    let mut log = Log::new(datalink);
    let conn = 0x0040;
    log.le_connected(conn);
    let profile = family::gatt_profile(model);
    let chars: Vec<(u16, GattUuid)> = profile
        .characteristics()
        .iter()
        .enumerate()
        .map(|(i, c)| (0x0010 + 3 * i as u16, c.characteristic))
        .collect();
    log.declare(conn, &chars);
    let handle_of = |uuid: GattUuid| chars.iter().find(|(_, u)| *u == uuid).unwrap().0;
    let api = handle_of(profile.write.characteristic);
    let notify = profile.notify.first().map(|c| handle_of(c.characteristic));
    for t in session_events(model).into_iter().take(24) {
        log.advance(20);
        match t.event {
            Event::Out(Endpoint::Api, b) => log.write_cmd(conn, api, &b),
            Event::Out(e, b) => {
                if let Some(c) = profile.endpoint(e) {
                    log.write_req(conn, handle_of(c.characteristic), &b)
                }
            }
            Event::In(b) => match notify {
                Some(h) => log.notify(conn, h, &b),
                None => log.read(conn, api, &b),
            },
            _ => {}
        }
    }
    log.disconnected(conn, 0x13);
    log
}

/// Relay requests as bytes.
fn requests(rs: &[Request]) -> Vec<u8> {
    rs.iter().flat_map(|r| r.to_bytes().unwrap()).collect()
}

/// A spherov2 client's session through the relay with the `i`-th simulated droid.
fn relay_session(model: Model, i: usize) -> Vec<u8> {
    let address = droidctl::relay::sim_backend::sim_address(i);
    let profile = family::gatt_profile(model);
    let f = family::for_model(model);
    let mut rs = vec![Request::Init { seq: 1, address }];
    let mut seq = 2;
    for step in &profile.handshake {
        if let droidctl::gatt::HandshakeStep::Write { ch, bytes, .. } = step {
            rs.push(Request::Write {
                seq,
                characteristic: ch.characteristic.to_string(),
                data: bytes.clone(),
            });
            seq += 1;
        }
    }
    for c in &profile.notify {
        rs.push(Request::SetCallback {
            seq,
            characteristic: c.characteristic.to_string(),
        });
        seq += 1;
    }
    let h = Heading::new(45).unwrap();
    for cmd in [f.drive(100, h, false), f.drive(100, h, false)] {
        for (to, bytes) in wire(model, &cmd, seq) {
            let ch = profile.endpoint(to).unwrap().characteristic;
            rs.push(Request::Write {
                seq,
                characteristic: ch.to_string(),
                data: bytes,
            });
            seq += 1;
        }
    }
    requests(&rs)
}

#[test]
#[ignore]
fn write_seed_corpus() {
    let r2 = Model::R2D2;
    let h = Heading::new(90).unwrap();
    // decoder: each family's packets, whole and cut (1 size byte: 3).
    for (name, model) in [("v2", r2), ("v1", Model::BB8), ("rsrcp", Model::Robi42)] {
        let events = session_events(model);
        let mut stream = Vec::new();
        for t in events.iter().take(12) {
            if let Event::Out(Endpoint::Api, b) | Event::In(b) = &t.event {
                stream.extend(b);
            }
        }
        write(
            "decoder",
            &format!("{name}-whole"),
            &[[0x00].as_slice(), &stream].concat(),
        );
        write(
            "decoder",
            &format!("{name}-cut"),
            &[[0x01, 3].as_slice(), &stream].concat(),
        );
        // packet_file: the same bytes as binary and as hex text.
        let hex = droidctl::hex::spaced(&stream) + "\n";
        write(
            "packet_file",
            &format!("{name}-binary"),
            &[[0x00, 0x00].as_slice(), &stream].concat(),
        );
        write(
            "packet_file",
            &format!("{name}-hex"),
            &[[0x40, 0x01].as_slice(), hex.as_bytes()].concat(),
        );
    }
    write(
        "packet_file",
        "hex-spellings",
        b"\x00\x00 0x8D,0x0A:13 0d-00 d5d8\n",
    );
    // relay codec: requests, and replies.
    let reqs = requests(&[
        Request::Scan { timeout: 2.0 },
        Request::Find {
            name: "D2-0001".into(),
            timeout: 1.5,
        },
        Request::End,
    ]);
    write("relay", "requests", &[[0x00].as_slice(), &reqs].concat());
    write(
        "relay",
        "session",
        &[[0x02, 5, 9].as_slice(), &relay_session(r2, 0)].concat(),
    );
    let replies: Vec<u8> = [
        droidctl::protocol::relay::Reply::Ok { seq: 1 },
        droidctl::protocol::relay::Reply::Devices(vec![droidctl::protocol::relay::Device {
            name: "D2-0001".into(),
            address: "5E:D0:00:00:00:01".into(),
        }]),
        droidctl::protocol::relay::Reply::Data {
            characteristic: "00010002-574f-4f20-5370-6865726f2121".into(),
            data: vec![0x8D, 0x09, 0xD8],
        },
    ]
    .iter()
    .flat_map(|r| r.to_bytes().unwrap())
    .collect();
    write("relay", "replies", &[[0x20].as_slice(), &replies].concat());
    // relay server: each family's session, one in pieces with pauses; scans and finds.
    for (i, model) in [r2, Model::BB8, Model::Robi42].into_iter().enumerate() {
        let s = relay_session(model, i);
        write(
            "relay_server",
            &format!("session-{}", model.id()),
            &[[0x00].as_slice(), &s].concat(),
        );
    }
    let s = relay_session(r2, 0);
    write(
        "relay_server",
        "session-paced",
        &[[0x52, 7, 30].as_slice(), &s].concat(),
    );
    let scans = requests(&[
        Request::Scan { timeout: 1.0 },
        Request::Find {
            name: "BB-0002".into(),
            timeout: 1.0,
        },
        Request::Find {
            name: "nobody".into(),
            timeout: 0.5,
        },
        Request::End,
    ]);
    write(
        "relay_server",
        "scan-find-end",
        &[[0x00].as_slice(), &scans].concat(),
    );
    // btsnoop and hci: phone logs of each family, each datalink; one cut short.
    for (model, dl) in [
        (r2, Datalink::H4),
        (Model::BB8, Datalink::H1),
        (Model::Robi42, Datalink::Monitor),
    ] {
        let log = phone_log(model, dl);
        write(
            "btsnoop",
            &format!("{}-{:?}", model.id(), dl).to_lowercase(),
            &[[0x02, 16, 200].as_slice(), &log.bytes].concat(),
        );
    }
    let log = phone_log(r2, Datalink::H4);
    write(
        "btsnoop",
        "r2d2-cut-short",
        &[[0x20].as_slice(), &log.bytes[..log.bytes.len() - 5]].concat(),
    );
    // hci: operations (see droidctl::fuzzing::hci::op).
    for (model, dl) in [(r2, 0u8), (Model::BB8, 1), (Model::Robi42, 2)] {
        let profile = family::gatt_profile(model);
        let uuids: Vec<GattUuid> = [Model::R2D2, Model::BB8, Model::Robi42]
            .into_iter()
            .flat_map(|m| family::gatt_profile(m).characteristics())
            .map(|c| c.characteristic)
            .collect();
        let mut ops = vec![dl, 0xF0, 0x40, 0x00, 0xF2, 0x40, 0x00];
        let chars = profile.characteristics();
        ops.push(chars.len() as u8);
        for (i, c) in chars.iter().enumerate() {
            let at = 0x0010 + 3 * i as u16;
            ops.extend(at.to_le_bytes());
            ops.push(uuids.iter().position(|u| *u == c.characteristic).unwrap() as u8);
        }
        for (i, cmd) in [family::for_model(model).drive(80, h, false)]
            .iter()
            .enumerate()
        {
            for (_, bytes) in wire(model, cmd, i as u8) {
                ops.extend([0xF3, 0x40, 0x00, 0x10, 0x00, bytes.len() as u8]);
                ops.extend(&bytes);
            }
        }
        ops.extend([0xF5, 0x40, 0x00, 0x13, 0x00, 3, 0x8D, 0x09, 0xD8]);
        ops.extend([0xF8, 0xE8, 0x03, 0xF1, 0x40, 0x00, 0x13]);
        write("hci", &format!("session-{}", model.id()), &ops);
    }
    // capture: sessions of two families, one a mission with its marks.
    write(
        "capture",
        "r2d2-mission",
        &[[0x00, 100, 0].as_slice(), &capture_text(r2, true)].concat(),
    );
    write(
        "capture",
        "robi42",
        &[
            [0x01, 0xF4, 0x01].as_slice(),
            &capture_text(Model::Robi42, false),
        ]
        .concat(),
    );
    write(
        "capture",
        "silence",
        b"\x00\x64\x00droidctl-capture 1\n0.000 connect\n700000.000 in notify 8d09130d00d5d8\n700001.000 end\n",
    );
    // script: the shipped mission, every command.
    let square = std::fs::read(root().join("assets/missions/square.txt")).unwrap();
    write("script", "square", &square);
    write(
        "script",
        "every-command",
        b"wake\nstance bipod\ndrive 50 180\nstop\nhead -45.5\nanimation 3\nsound 1915\n\
          led back 0 0 255\nled logic 200\nwait 500ms\nsleep # done\n",
    );
    // config: the defaults, and small user files.
    write(
        "config",
        "default",
        droidctl::config::DEFAULT_TOML.as_bytes(),
    );
    write(
        "config",
        "user",
        b"[control]\nrate_hz = 20\nmode = \"latched\"\n[session]\npacing_ms = 60\n\
          [keys]\nquit = [\"Ctrl+q\"]\nforward = [\"F5\", \"k\"]\n[gamepad]\naim = \"West\"\n",
    );
    // bluez: discovery, connect, the GATT calls, properties (see droidctl::fuzzing::bluez:
    // objects by kind, 0 the adapter, 1 a device, 3 a characteristic, 4 the root).
    let calls: Vec<u8> = vec![
        0x00, // no trace
        0, 5, 0, 0, // Adapter1.StartDiscovery
        0, 1, 0, 2, 0, 0, 0, 4, // Properties.Get(Adapter1, Powered)
        0, 1, 2, 3, 0, 0, 0, 4, 9, 1, 1, // Properties.Set(Adapter1, Powered, true)
        4, 2, 0, 0, // "/": GetManagedObjects
        0, 3, 0, 0, // Peer.Ping
        1, 6, 0, 0, // the first device: Connect
        3, 8, 1, 2, 7, 3, 1, 2, 3, 10, 1, 18, 0, 20, // WriteValue([1 2 3], type: request)
        3, 8, 0, 1, 10, 0, // ReadValue({})
        9, 8, 2, 0, // another characteristic: StartNotify
        1, 6, 1, 0, // Disconnect
        0, 5, 1, 0,    // StopDiscovery
        0xFF, // a forged NameOwnerChanged
    ];
    write("bluez", "discover-connect", &calls);
    write(
        "bluez",
        "traced",
        &[[0x03].as_slice(), &calls[1..]].concat(),
    );
    // bridge: a session of every verb and some bad lines, whole and in 7-byte pieces 50 ms
    // apart; a drive left to time out; a line over the limit.
    let session: &[u8] = b"{\"v\":1,\"cmd\":\"drive\",\"speed\":120,\"heading\":90,\"id\":1}\n\
        {\"v\":1,\"cmd\":\"twist\",\"droid\":\"robi\",\"linear\":0.2,\"angular\":0.5}\n\
        {\"v\":1,\"cmd\":\"lights\",\"droid\":\"D2-0001\",\"group\":\"front\",\"rgb\":[0,0,255],\"id\":\"l\"}\n\
        {\"v\":1,\"cmd\":\"head\",\"droid\":\"D2-0001\",\"angle\":-30}\n\
        {\"v\":1,\"cmd\":\"stance\",\"droid\":\"D2-0001\",\"stance\":\"bipod\",\"id\":2}\n\
        {\"v\":1,\"cmd\":\"sound\",\"droid\":\"robi\",\"sound\":3,\"id\":3}\n\
        {\"v\":1,\"cmd\":\"stream\",\"droid\":\"D2-0001\",\"rate_hz\":50,\"sensors\":[\"attitude\"],\"id\":4}\n\
        {\"v\":1,\"cmd\":\"matrix\",\"droid\":\"D2-0001\",\"op\":\"fill\",\"rgb\":[1,2,3]}\n\
        not json\n{\"v\":2,\"cmd\":\"stop\"}\n{\"v\":1,\"cmd\":\"drive\",\"speed\":300,\"heading\":0,\"id\":5}\n\
        {\"v\":1,\"cmd\":\"stop\",\"droid\":\"D2-0001\"}\n{\"v\":1,\"cmd\":\"estop\",\"id\":\"e\"}\n";
    write("bridge", "session", &[[0x00].as_slice(), session].concat());
    write(
        "bridge",
        "session-paced",
        &[[0x51, 7].as_slice(), session].concat(),
    );
    let drive: &[u8] =
        b"{\"v\":1,\"droid\":\"D2-0001\",\"cmd\":\"drive\",\"speed\":200,\"heading\":180}\n";
    write(
        "bridge",
        "drive-then-silence",
        &[&[0x00], drive, drive, drive].concat(),
    );
    let long = [
        b"\0{\"v\":1,\"cmd\":\"stop\",\"id\":\"".as_slice(),
        &[b'x'; 5000],
        b"\"}\n{\"v\":1,\"cmd\":\"stop\",\"id\":6}\n",
    ]
    .concat();
    write("bridge", "long-line", &long);
    // bridge_mqtt: publishes as a broker delivers them (flags, then a length-prefixed
    // payload): a retained drive waiting on R2's topic, live commands on both droids'
    // topics, a payload over the limit, one on another topic, a huge one.
    let publish = |flags: u8, payload: &[u8]| [&[flags, payload.len() as u8][..], payload].concat();
    let drive: &[u8] = b"{\"v\":1,\"cmd\":\"drive\",\"speed\":255,\"heading\":90}";
    let stop: &[u8] = b"{\"v\":1,\"cmd\":\"stop\",\"id\":1}";
    let twist: &[u8] = b"{\"v\":1,\"cmd\":\"twist\",\"linear\":0.2,\"angular\":0.5,\"id\":\"t\"}";
    let sound: &[u8] = b"\xEF\xBB\xBF{\"v\":1.0,\"cmd\":\"sound\",\"sound\":3,\"id\":2}";
    write(
        "bridge_mqtt",
        "retained-drive",
        &[publish(0x01, drive), publish(0x21, drive)].concat(),
    );
    write(
        "bridge_mqtt",
        "live",
        &[
            publish(0x20, drive),
            publish(0x22, twist),
            publish(0x40, sound),
            publish(0x00, b"not json"),
            publish(0x02, stop),
        ]
        .concat(),
    );
    write(
        "bridge_mqtt",
        "large",
        &[
            publish(0x08, stop),
            publish(0x09, drive),
            [&[0x10u8, 2, b'{', b'x', 0x00, 0x10][..]].concat(),
            publish(0x04, drive),
            [&[0x06u8, 3][..], b"a/b", &[drive.len() as u8], drive].concat(),
        ]
        .concat(),
    );
}
