//! Golden vectors and per-entry checks of the Sphero API v1 codec: both vectors of
//! `vectors.md` in both directions, the checksum rule for every packet shape, every catalogue
//! command (typed constructor = the CLI's `encode_params` path), responses with MRSP codes,
//! async messages (two-byte DLEN, sensor frames with MASK/MASK2 and M > 1, the 16-byte
//! collision, power, pre-sleep, unknown ids), `FF FF` inside data and resynchronisation on
//! the checksum, and the truncated tail.

use droidctl::hex;
use droidctl::protocol::v1::catalog::{self, Command, cmd};
use droidctl::protocol::v1::packet::{self, Kind};
use droidctl::protocol::v1::{
    AsyncPacket, Collision, CommandPacket, DecodeError, Decoder, ErrorKind, MotorMode, Mrsp,
    Notification, Packet, Response, RollState, Source, StreamingConfig, Value, decode_async,
    decode_samples, describe, encode_async, encode_samples, to_json,
};
use droidctl::protocol::wire::{AccelRaw, CollisionAxis, Text};
use droidctl::units::Heading;
use std::collections::BTreeSet;

fn h(s: &str) -> Vec<u8> {
    hex::parse(s).unwrap()
}

fn heading(deg: u16) -> Heading {
    Heading::new(deg).unwrap()
}

fn given(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

fn decode(source: Source, bytes: &[u8]) -> Vec<Result<Packet, DecodeError>> {
    let mut d = Decoder::new(source);
    let mut out = d.decode_all(bytes);
    out.extend(d.finish());
    out
}

fn only_packet(source: Source, bytes: &[u8]) -> Packet {
    let out = decode(source, bytes);
    assert_eq!(out.len(), 1, "{out:?}");
    out.into_iter().next().unwrap().unwrap()
}

fn kinds(events: &[Result<Packet, DecodeError>]) -> Vec<Result<Kind, ErrorKind>> {
    events
        .iter()
        .map(|e| match e {
            Ok(p) => Ok(p.kind()),
            Err(e) => Err(e.kind),
        })
        .collect()
}

fn approx(a: f32, b: f32) -> bool {
    (a - b).abs() < 1e-4
}

// -------------------------------------------------------------------------------------------
// Golden vectors (vectors.md, "Sphero v1").
// -------------------------------------------------------------------------------------------

fn golden() -> Vec<(&'static str, CommandPacket, Vec<u8>)> {
    vec![
        (
            "ping seq 0x52",
            CommandPacket::new(0x00, 0x01, 0x52, vec![]),
            h("FF FF 00 01 52 01 AB"),
        ),
        (
            "roll speed 0x80 heading 90 state 1 seq 0",
            CommandPacket::new(0x02, 0x30, 0x00, h("80 00 5A 01")),
            h("FF FF 02 30 00 05 80 00 5A 01 ED"),
        ),
    ]
}

#[test]
fn golden_vectors_encode() {
    for (what, c, wire) in golden() {
        let p = Packet::Command(c);
        assert_eq!(p.encode().unwrap(), wire, "{what}");
        assert_eq!(p.wire_len(), wire.len(), "{what}");
        let mut buf = vec![0x42];
        p.encode_into(&mut buf).unwrap();
        assert_eq!(buf[0], 0x42);
        assert_eq!(&buf[1..], &wire[..], "{what}");
    }
}

#[test]
fn golden_vectors_decode_whole_and_split_everywhere() {
    for (what, c, wire) in golden() {
        assert_eq!(
            only_packet(Source::Host, &wire),
            Packet::Command(c.clone()),
            "{what}"
        );
        for split in 0..=wire.len() {
            let mut d = Decoder::new(Source::Host);
            let mut out = d.decode_all(&wire[..split]);
            out.extend(d.feed(&wire[split..]));
            out.extend(d.finish());
            assert_eq!(
                out,
                vec![Ok(Packet::Command(c.clone()))],
                "{what} split {split}"
            );
            let s = d.stats();
            assert_eq!((s.packets, s.skipped_bytes), (1, 0));
            assert_eq!(s.bytes, wire.len() as u64);
        }
        // Default SOP2 FF: answer and reset timeout.
        assert!(c.answer() && c.reset_timeout(), "{what}");
    }
}

#[test]
fn golden_roll_comes_from_the_typed_constructor_and_the_cli_defaults() {
    let wire = h("FF FF 02 30 00 05 80 00 5A 01 ED");
    let typed = cmd::roll(0x80, heading(90), RollState::Go);
    assert_eq!(typed.to_packet(0).sop2, 0xFF);
    assert_eq!(Packet::Command(typed.to_packet(0)).encode().unwrap(), wire);
    // `packet encode --protocol v1 roll --speed 128 --heading 90`: the state defaults to go.
    let roll = catalog::by_name("roll").unwrap();
    let cli = catalog::command(roll, &given(&[("speed", "128"), ("heading", "90")])).unwrap();
    assert_eq!(cli, typed);
    assert_eq!(Packet::Command(cli.to_packet(0)).encode().unwrap(), wire);
    // Heading and state default too; speed is required.
    assert_eq!(
        catalog::by_name("roll")
            .unwrap()
            .encode_params(&given(&[("speed", "1")])),
        Ok(vec![1, 0, 0, 1])
    );
    let err = catalog::by_name("roll")
        .unwrap()
        .encode_params(&given(&[("speed", "1"), ("heading", "360")]))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("--heading") && err.contains("0..=359"),
        "{err}"
    );
}

// -------------------------------------------------------------------------------------------
// Checksum rule: NOT of the byte sum from DID / MRSP / ID code through the data, the SEQ and
// DLEN (both async DLEN bytes) included.
// -------------------------------------------------------------------------------------------

#[test]
fn checksum_rule_for_every_shape() {
    // Seed example: 00 + 01 + 52 + 01 = 54, inverted AB.
    assert_eq!(packet::checksum(&h("00 01 52 01")), 0xAB);
    assert_eq!(packet::checksum(&[]), 0xFF);
    // Sums wrap mod 256: 02+20+00+05+FF+FF+00+00 = 0x225 → 25 → DA.
    let rgb = Packet::Command(cmd::set_rgb_led(0xFF, 0xFF, 0x00, false).to_packet(0));
    assert_eq!(rgb.encode().unwrap(), h("FF FF 02 20 00 05 FF FF 00 00 DA"));
    // Response: MRSP SEQ DLEN summed: 00 + 52 + 01 = 53 → AC.
    let ping = CommandPacket::new(0x00, 0x01, 0x52, vec![]);
    let ok = Packet::Response(Response::to(&ping, Mrsp::Ok, vec![]));
    assert_eq!(ok.encode().unwrap(), h("FF FF 00 52 01 AC"));
    // Async: ID and both DLEN bytes summed: 01 + 00 + 02 + 02 = 05 → FA.
    let power = Packet::Async(AsyncPacket::new(0x01, vec![0x02]));
    assert_eq!(power.encode().unwrap(), h("FF FE 01 00 02 02 FA"));
    // A wrong checksum is never accepted.
    for wire in [h("FF FF 00 52 01 AD"), h("FF FE 01 00 02 02 FB")] {
        let out = decode(Source::Droid, &wire);
        assert_eq!(kinds(&out)[0], Err(ErrorKind::BadChecksum));
        assert!(out.iter().all(|e| e.is_err()));
    }
}

#[test]
fn sop2_option_bits() {
    let c = CommandPacket::new(0x00, 0x01, 0x52, vec![]).with_options(false, true);
    let wire = Packet::Command(c.clone()).encode().unwrap();
    assert_eq!(wire, h("FF FE 00 01 52 01 AB"));
    // From the host FE is a command without answer; the checksum does not cover SOP2.
    let Packet::Command(back) = only_packet(Source::Host, &wire) else {
        panic!()
    };
    assert!(!back.answer() && back.reset_timeout());
    assert_eq!(back, c);
    // F8: neither bit (the seed's "F8 to FFh").
    let Packet::Command(f8) = only_packet(Source::Host, &h("FF F8 00 01 52 01 AB")) else {
        panic!()
    };
    assert!(!f8.answer() && !f8.reset_timeout());
    // Below F8 is not a command.
    assert!(
        decode(Source::Host, &h("FF F7 00 01 52 01 AB"))
            .iter()
            .all(|e| e.is_err())
    );
}

#[test]
fn over_long_payloads_are_refused_not_panicked() {
    let c = Packet::Command(CommandPacket::new(0, 0x10, 0, vec![b'a'; 255]));
    let e = c.encode().unwrap_err();
    assert_eq!((e.len, e.max), (255, 254));
    assert!(e.to_string().contains("254"));
    let r = Packet::Response(Response {
        mrsp: Mrsp::Ok,
        seq: 0,
        data: vec![0; 255],
    });
    assert!(r.encode().is_err());
    let a = Packet::Async(AsyncPacket::new(3, vec![0; 0xFFFF]));
    assert!(a.encode().is_err());
    assert!(
        Packet::Async(AsyncPacket::new(3, vec![0; 0xFFFE]))
            .encode()
            .is_ok()
    );
}

// -------------------------------------------------------------------------------------------
// Every catalogue command: typed constructor = CLI path.
// -------------------------------------------------------------------------------------------

/// A typed command, the same as CLI (option, text) pairs, and its expected payload in hex.
type Case = (Command, Vec<(&'static str, &'static str)>, &'static str);

fn command_cases() -> Vec<Case> {
    vec![
        (cmd::ping(), vec![], ""),
        (cmd::get_versions(), vec![], ""),
        (
            cmd::set_device_name(Text("BB-8".into())),
            vec![("name", "BB-8")],
            "42 42 2D 38 00",
        ),
        (cmd::get_bluetooth_info(), vec![], ""),
        (cmd::get_power_state(), vec![], ""),
        (cmd::set_power_notification(true), vec![], "01"),
        (
            cmd::set_power_notification(false),
            vec![("enable", "off")],
            "00",
        ),
        (cmd::sleep(0, 0, 0), vec![], "00 00 00 00 00"),
        (
            cmd::sleep(60, 2, 10),
            vec![
                ("wakeup", "60"),
                ("macro-id", "2"),
                ("orb-basic-line", "10"),
            ],
            "00 3C 02 00 0A",
        ),
        (cmd::get_voltage_trip_points(), vec![], ""),
        (
            cmd::set_inactivity_timeout(600),
            vec![("timeout", "600")],
            "02 58",
        ),
        (cmd::perform_level_1_diagnostics(), vec![], ""),
        (
            cmd::assign_time(0x0102_0304),
            vec![("time", "0x01020304")],
            "01 02 03 04",
        ),
        (
            cmd::poll_packet_times(1000),
            vec![("client-tx", "1000")],
            "00 00 03 E8",
        ),
        (cmd::set_heading(heading(0)), vec![], "00 00"),
        (
            cmd::set_heading(heading(270)),
            vec![("heading", "270")],
            "01 0E",
        ),
        (cmd::set_stabilization(true), vec![], "01"),
        (cmd::set_rotation_rate(0xC8), vec![], "C8"),
        (cmd::get_chassis_id(), vec![], ""),
        (
            cmd::set_data_streaming(40, 1, 0x0007_0000, 0, None),
            vec![("mask", "0x00070000")],
            "00 28 00 01 00 07 00 00 00",
        ),
        (
            cmd::set_data_streaming(20, 2, 0x0000_E000, 5, Some(0x0C00_0000)),
            vec![
                ("n", "20"),
                ("m", "2"),
                ("mask", "0xE000"),
                ("pcnt", "5"),
                ("mask2", "0x0C000000"),
            ],
            "00 14 00 02 00 00 E0 00 05 0C 00 00 00",
        ),
        (
            cmd::configure_collision_detection(1, 100, 100, 100, 100, 10),
            vec![],
            "01 64 64 64 64 0A",
        ),
        (
            cmd::configure_locator(0, 0, 0, 0),
            vec![],
            "00 00 00 00 00 00 00",
        ),
        (
            cmd::configure_locator(1, -5, 300, 90),
            vec![
                ("flags", "1"),
                ("x", "-5"),
                ("y", "300"),
                ("yaw-tare", "90"),
            ],
            "01 FF FB 01 2C 00 5A",
        ),
        (cmd::read_locator(), vec![], ""),
        (
            cmd::set_rgb_led(255, 0, 16, false),
            vec![("red", "255"), ("green", "0"), ("blue", "16")],
            "FF 00 10 00",
        ),
        (cmd::set_back_led(255), vec![("brightness", "255")], "FF"),
        (cmd::get_rgb_led(), vec![], ""),
        (
            cmd::roll(128, heading(90), RollState::Go),
            vec![("speed", "128"), ("heading", "90")],
            "80 00 5A 01",
        ),
        (
            cmd::roll(0, heading(10), RollState::Calibrate),
            vec![("speed", "0"), ("heading", "10"), ("state", "calibrate")],
            "00 00 0A 02",
        ),
        (
            cmd::set_raw_motors(MotorMode::Forward, 100, MotorMode::Reverse, 50),
            vec![
                ("left-mode", "forward"),
                ("left-power", "100"),
                ("right-mode", "reverse"),
                ("right-power", "50"),
            ],
            "01 64 02 32",
        ),
        (
            cmd::set_motion_timeout(2000),
            vec![("timeout-ms", "2000")],
            "07 D0",
        ),
        (
            cmd::set_permanent_option_flags(0x10),
            vec![("flags", "0x10")],
            "00 00 00 10",
        ),
        (cmd::get_permanent_option_flags(), vec![], ""),
        (
            cmd::set_temporary_option_flags(catalog::TEMP_OPTION_STOP_ON_DISCONNECT),
            vec![("flags", "1")],
            "00 00 00 01",
        ),
        (cmd::get_temporary_option_flags(), vec![], ""),
    ]
}

#[test]
fn every_command_typed_constructor_equals_cli_path() {
    let mut covered = BTreeSet::new();
    for (typed, pairs, bytes) in command_cases() {
        let def = typed
            .def()
            .expect("typed constructor has a catalogue entry");
        covered.insert(def.name.clone());
        let cli = catalog::command(def, &given(&pairs)).unwrap();
        assert_eq!(cli, typed, "{}", def.name);
        assert_eq!(typed.data, h(bytes), "{}", def.name);
        // The payload fits its schema and describes without a problem.
        assert!(
            catalog::length_ok(def.params, typed.data.len()),
            "{}",
            def.name
        );
        let p = Packet::Command(typed.to_packet(7));
        let d = describe(&p, None, None);
        assert_eq!(d.name, Some(def.name.as_str()));
        assert_eq!(d.problem, None, "{}", def.name);
        // Framed and decoded back unchanged.
        assert_eq!(only_packet(Source::Host, &p.encode().unwrap()), p);
    }
    let all: BTreeSet<String> = catalog::commands().iter().map(|c| c.name.clone()).collect();
    assert_eq!(covered, all, "every catalogue command has a case");
}

#[test]
fn catalogue_ids() {
    let id = |n: &str| {
        let c = catalog::by_name(n).unwrap();
        (c.did, c.cid)
    };
    assert_eq!(id("ping"), (0x00, 0x01));
    assert_eq!(id("set-power-notification"), (0x00, 0x21));
    assert_eq!(id("sleep"), (0x00, 0x22));
    assert_eq!(id("set-inactivity-timeout"), (0x00, 0x25));
    assert_eq!(id("set-heading"), (0x02, 0x01));
    assert_eq!(id("set-stabilization"), (0x02, 0x02));
    assert_eq!(id("set-data-streaming"), (0x02, 0x11));
    assert_eq!(id("configure-collision-detection"), (0x02, 0x12));
    assert_eq!(id("set-rgb-led"), (0x02, 0x20));
    assert_eq!(id("set-back-led"), (0x02, 0x21));
    assert_eq!(id("roll"), (0x02, 0x30));
    assert_eq!(id("set-raw-motors"), (0x02, 0x33));
    assert_eq!(id("set-temporary-option-flags"), (0x02, 0x37));
    assert!(catalog::lookup(0x02, 0x30).is_some());
    assert!(catalog::lookup(0x02, 0x99).is_none());
    assert!(catalog::suggestions("set-led-rgb").contains(&"set-rgb-led"));
    let err = catalog::by_name("ping")
        .unwrap()
        .encode_params(&given(&[("x", "1")]))
        .unwrap_err()
        .to_string();
    assert!(err.contains("takes no parameters"), "{err}");
    let err = catalog::by_name("set-rgb-led")
        .unwrap()
        .encode_params(&given(&[("red", "1")]))
        .unwrap_err()
        .to_string();
    assert!(err.contains("needs --green"), "{err}");
}

// -------------------------------------------------------------------------------------------
// Responses.
// -------------------------------------------------------------------------------------------

#[test]
fn responses_with_mrsp_codes() {
    let request = cmd::ping().to_packet(0x52);
    let ok = Response::to(&request, Mrsp::Ok, vec![]);
    let wire = Packet::Response(ok.clone()).encode().unwrap();
    assert_eq!(wire, h("FF FF 00 52 01 AC"));
    assert_eq!(only_packet(Source::Droid, &wire), Packet::Response(ok));

    // MRSP 07, SEQ 3: 07 + 03 + 01 = 0B → F4.
    let Packet::Response(bad) = only_packet(Source::Droid, &h("FF FF 07 03 01 F4")) else {
        panic!()
    };
    assert_eq!(bad.mrsp, Mrsp::ParameterInvalid);
    assert_eq!(bad.mrsp.name(), "parameter_invalid");
    assert!(!bad.mrsp.is_success());
    let d = describe(
        &Packet::Response(bad.clone()),
        None,
        Some(&cmd::set_heading(heading(1))),
    );
    assert_eq!(d.name, Some("set-heading"));
    assert_eq!(d.fields, None);
    assert!(d.problem.unwrap().starts_with("parameter_invalid"));

    for (b, name) in [
        (0x00, "ok"),
        (0x01, "general_error"),
        (0x02, "checksum_failure"),
        (0x03, "fragmented_command"),
        (0x04, "unknown_command"),
        (0x05, "command_unsupported"),
        (0x06, "bad_message_format"),
        (0x07, "parameter_invalid"),
        (0x08, "failed_to_execute"),
        (0x09, "unknown_device"),
        (0x0A, "ram_busy"),
        (0x0B, "bad_password"),
        (0x31, "voltage_too_low"),
        (0x32, "illegal_page"),
        (0x33, "flash_fail"),
        (0x34, "main_app_corrupt"),
        (0x35, "msg_timeout"),
        (0x36, "unknown_0x36"),
    ] {
        let m = Mrsp::from_byte(b);
        assert_eq!(m.name(), name);
        assert_eq!(m.to_byte(), b);
        // Every code survives the wire.
        let p = Packet::Response(Response {
            mrsp: m,
            seq: b,
            data: vec![b],
        });
        assert_eq!(only_packet(Source::Droid, &p.encode().unwrap()), p);
    }
    assert_eq!(Mrsp::from_byte(0x36), Mrsp::Other(0x36));
}

#[test]
fn response_fields_come_from_the_request() {
    // Get Power State: record 1, state 2 (OK), 7.52 V, 16 charges, 256 s. Checksum EB.
    let wire = h("FF FF 00 05 09 01 02 02 F0 00 10 01 00 EB");
    let p = only_packet(Source::Droid, &wire);
    let d = describe(&p, None, Some(&cmd::get_power_state()));
    assert_eq!(d.name, Some("get-power-state"));
    let f = d.fields.unwrap();
    let names: Vec<_> = f.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        [
            "record_version",
            "state",
            "voltage",
            "number_of_charges",
            "time_since_last_charge"
        ]
    );
    assert_eq!(
        f[1].1,
        Value::Enum {
            value: 2,
            name: Some("ok")
        }
    );
    assert_eq!(f[2].1.as_f64(), Some(7.52));
    assert_eq!(f[3].1, Value::Int(16));

    // Without the request the payload stays raw (in `data`).
    let d = describe(&p, None, None);
    assert_eq!((d.name, d.fields, d.problem), (None, None, None));

    // Get Versions with and without the trailing API version.
    let req = cmd::get_versions();
    for (data, fields) in [
        (h("02 07 01 03 02 43 21 04"), 8),
        (h("02 07 01 03 02 43 21 04 01 32"), 10),
    ] {
        let p = Packet::Response(Response {
            mrsp: Mrsp::Ok,
            seq: 1,
            data,
        });
        let d = describe(&p, None, Some(&req));
        assert_eq!(d.fields.map(|f| f.len()), Some(fields));
    }
    // A payload that does not fit is a problem, not a panic.
    let p = Packet::Response(Response {
        mrsp: Mrsp::Ok,
        seq: 1,
        data: vec![1, 2],
    });
    let d = describe(&p, None, Some(&cmd::get_rgb_led()));
    assert!(d.fields.is_none() && d.problem.is_some());
}

// -------------------------------------------------------------------------------------------
// Async messages.
// -------------------------------------------------------------------------------------------

#[test]
fn async_dlen_is_two_bytes() {
    let data: Vec<u8> = (0..300u16).map(|i| i as u8).collect();
    let p = Packet::Async(AsyncPacket::new(0x03, data.clone()));
    let wire = p.encode().unwrap();
    assert_eq!(&wire[..5], &h("FF FE 03 01 2D")[..]);
    assert_eq!(wire.len(), 5 + 300 + 1);
    assert_eq!(only_packet(Source::Droid, &wire), p);
    // A bound below it is reported as oversize, without buffering the rest.
    let mut d = Decoder::with_max_async_dlen(Source::Droid, 100);
    let out = d.decode_all(&wire);
    assert_eq!(kinds(&out)[0], Err(ErrorKind::Oversize));
    assert!(out.iter().all(|e| e.is_err()));
}

fn two_frame_config() -> StreamingConfig {
    StreamingConfig {
        n: 40,
        m: 2,
        mask: 0x0004_0000 | 0x0000_8000, // pitch, accel_x
        pcnt: 0,
        mask2: 0x0800_0000 | 0x0100_0000, // locator_x, velocity_x
    }
}

#[test]
fn sensor_frames_mask_then_mask2_high_to_low_m_frames() {
    let cfg = two_frame_config();
    // Frame 1: pitch 10°, accel_x 2048 (0.5 g), locator_x -3 cm, velocity_x 255 mm/s.
    // Frame 2: pitch -90°, accel_x -4096 (-1 g), locator_x 100 cm, velocity_x -10 mm/s.
    let data = h("00 0A 08 00 FF FD 00 FF  FF A6 F0 00 00 64 FF F6");
    let wire = h("FF FE 03 00 11 00 0A 08 00 FF FD 00 FF FF A6 F0 00 00 64 FF F6 F0");
    let Packet::Async(a) = only_packet(Source::Droid, &wire) else {
        panic!()
    };
    assert_eq!((a.id_code, &a.data), (0x03, &data));

    let frames = decode_samples(&cfg, &data).unwrap();
    assert_eq!(frames.len(), 2);
    let names: Vec<_> = frames[0].values.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["pitch", "accel_x", "locator_x", "velocity_x"]);
    let f0 = &frames[0];
    assert_eq!(f0.get("pitch"), Some(10.0));
    assert_eq!(f0.get("accel_x"), Some(0.5));
    assert_eq!(f0.get("locator_x"), Some(-3.0));
    assert!(approx(f0.get("velocity_x").unwrap(), 25.5));
    let f1 = &frames[1];
    assert_eq!(f1.get("pitch"), Some(-90.0));
    assert_eq!(f1.get("accel_x"), Some(-1.0));
    assert_eq!(f1.get("locator_x"), Some(100.0));
    assert!(approx(f1.get("velocity_x").unwrap(), -1.0));

    // The inverse, for the simulator.
    let values: Vec<Vec<(&str, f32)>> = frames
        .iter()
        .map(|f| f.values.iter().map(|(n, v)| (*n, *v)).collect())
        .collect();
    assert_eq!(encode_samples(&cfg, &values), data);

    // One Notification::Sensors per frame.
    let n = decode_async(&a, &cfg).unwrap();
    assert_eq!(n.len(), 2);
    assert!(matches!(&n[1], Notification::Sensors(s) if s.get("pitch") == Some(-90.0)));

    // describe: one list per name when M > 1.
    let d = describe(&Packet::Async(a.clone()), Some(&cfg), None);
    assert_eq!(d.name, Some("sensor-data-streaming"));
    let f = d.fields.unwrap();
    assert_eq!(f[0].0, "pitch");
    assert_eq!(
        f[0].1,
        Value::List(vec![Value::Float(10.0), Value::Float(-90.0)])
    );
    // Without the configuration the values are shown raw.
    let d = describe(&Packet::Async(a), None, None);
    assert_eq!(
        d.fields.unwrap()[0],
        (
            "values",
            Value::List(
                [10, 2048, -3, 255, -90, -4096, 100, -10]
                    .map(Value::Int)
                    .to_vec()
            )
        )
    );
}

#[test]
fn sensor_lengths_are_checked_but_whole_frames_tolerated() {
    let cfg = two_frame_config();
    let data = h("00 0A 08 00 FF FD 00 FF  FF A6 F0 00 00 64 FF F6");
    // Not a whole number of 8-byte frames.
    let e = decode_samples(&cfg, &data[..15]).unwrap_err();
    assert_eq!((e.frame_len, e.frames, e.got_bytes), (8, 2, 15));
    assert!(decode_samples(&cfg, &[]).is_err());
    assert!(decode_async(&AsyncPacket::new(3, data[..15].to_vec()), &cfg).is_err());
    // One whole frame although M = 2: accepted (documented tolerance).
    assert_eq!(decode_samples(&cfg, &data[..8]).unwrap().len(), 1);
    // Streaming off: sensor data cannot be read.
    assert!(decode_async(&AsyncPacket::new(3, data), &StreamingConfig::default()).is_err());
}

#[test]
fn sensor_scalings_of_every_group() {
    let cfg = StreamingConfig {
        n: 10,
        m: 1,
        mask: 0x8000_0000 | 0x1000_0000 | 0x0000_1000, // accel_raw_x, gyro_raw_x, gyro_x
        pcnt: 0,
        mask2: 0x8000_0000 | 0x4000_0000 | 0x0200_0000, // quaternion_w, quaternion_x, accel_one
    };
    // accel raw 250 × 4 mG = 1 g; gyro raw 1000 × 0.068 = 68 °/s; gyro 455 × 0.1 = 45.5 °/s;
    // Q0 10000 → 1.0, Q1 -5000 → -0.5; accel_one 1000 mG.
    let data = h("00 FA 03 E8 01 C7 27 10 EC 78 03 E8");
    let s = &decode_samples(&cfg, &data).unwrap()[0];
    assert!(approx(s.get("accel_raw_x").unwrap(), 1.0));
    assert!(approx(s.get("gyro_raw_x").unwrap(), 68.0));
    assert!(approx(s.get("gyro_x").unwrap(), 45.5));
    assert!(approx(s.get("quaternion_w").unwrap(), 1.0));
    assert!(approx(s.get("quaternion_x").unwrap(), -0.5));
    assert_eq!(s.get("accel_one"), Some(1000.0));
    assert_eq!(cfg.rate_hz(), 40.0);
    // The snooped Set Data Streaming payload gives the same configuration back.
    assert_eq!(
        StreamingConfig::from_command_data(&cfg.command().data),
        Some(cfg)
    );
}

fn collision_data() -> Vec<u8> {
    // accel (4096, -2048, 0) = (1 g, -0.5 g, 0), axis x, x_mag 100, y_mag -5, speed 80,
    // time 0x00012345.
    h("10 00 F8 00 00 00 01 00 64 FF FB 50 00 01 23 45")
}

#[test]
fn collision_is_16_bytes_with_v2_names() {
    let wire = h("FF FE 07 00 11 10 00 F8 00 00 00 01 00 64 FF FB 50 00 01 23 45 C7");
    let Packet::Async(a) = only_packet(Source::Droid, &wire) else {
        panic!()
    };
    assert_eq!(a.data, collision_data());
    let n = decode_async(&a, &StreamingConfig::default()).unwrap();
    let expected = Collision {
        accel: [AccelRaw(4096), AccelRaw(-2048), AccelRaw(0)],
        axis: CollisionAxis { x: true, y: false },
        power: [100, -5, 0],
        speed: 80,
        time_ms: 0x12345,
    };
    assert_eq!(n, vec![Notification::Collision(expected)]);
    assert_eq!(encode_async(&n[0], &StreamingConfig::default()).unwrap(), a);

    let d = describe(&Packet::Async(a.clone()), None, None);
    assert_eq!(d.name, Some("collision-detected"));
    let f = d.fields.unwrap();
    let names: Vec<_> = f.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        [
            "accel_x", "accel_y", "accel_z", "x_axis", "y_axis", "power_x", "power_y", "speed",
            "time_ms"
        ]
    );
    assert_eq!(f[0].1, Value::Float(1.0));
    assert_eq!(f[1].1, Value::Float(-0.5));
    assert_eq!(f[3].1, Value::Bool(true));
    assert_eq!(f[4].1, Value::Bool(false));
    assert_eq!(f[6].1, Value::Int(-5));
    assert_eq!(f[8].1, Value::Int(0x12345));

    // v2's 18 bytes or anything but 16 is an error.
    for len in [15, 17, 18] {
        let mut data = collision_data();
        data.resize(len, 0);
        assert!(decode_async(&AsyncPacket::new(7, data), &StreamingConfig::default()).is_err());
    }
}

#[test]
fn power_pre_sleep_and_unknown_async() {
    let cfg = StreamingConfig::default();
    let Packet::Async(power) = only_packet(Source::Droid, &h("FF FE 01 00 02 03 F9")) else {
        panic!()
    };
    assert_eq!(
        decode_async(&power, &cfg),
        Ok(vec![Notification::PowerState(3)])
    );
    let d = describe(&Packet::Async(power), None, None);
    assert_eq!(d.name, Some("power-notification"));
    assert_eq!(
        d.fields.unwrap()[0].1,
        Value::Enum {
            value: 3,
            name: Some("low")
        }
    );
    assert!(decode_async(&AsyncPacket::new(1, vec![]), &cfg).is_err());

    // Pre-sleep: 05 + 00 + 01 = 06 → F9.
    let Packet::Async(sleep) = only_packet(Source::Droid, &h("FF FE 05 00 01 F9")) else {
        panic!()
    };
    assert_eq!(
        decode_async(&sleep, &cfg),
        Ok(vec![Notification::WillSleep])
    );
    assert_eq!(
        describe(&Packet::Async(sleep), None, None).name,
        Some("pre-sleep-warning")
    );

    // Unknown ID: kept raw, bytes and all.
    let unknown = AsyncPacket::new(0x42, vec![1, 2, 3]);
    let p = Packet::Async(unknown.clone());
    assert_eq!(only_packet(Source::Droid, &p.encode().unwrap()), p);
    assert_eq!(
        decode_async(&unknown, &cfg),
        Ok(vec![Notification::OtherAsync {
            id_code: 0x42,
            data: vec![1, 2, 3]
        }])
    );
    let d = describe(&p, None, None);
    assert_eq!(d.name, None);
    assert_eq!(d.fields, Some(vec![("data", Value::Bytes(vec![1, 2, 3]))]));
    // Known ids without a payload layout are raw too.
    let d = describe(&Packet::Async(AsyncPacket::new(0x04, vec![9])), None, None);
    assert_eq!(d.name, Some("config-block-contents"));
    assert_eq!(d.fields, Some(vec![("data", Value::Bytes(vec![9]))]));
}

#[test]
fn async_catalogue_covers_the_seed_table() {
    let names: Vec<String> = (0x01..=0x11).map(catalog::async_name).collect();
    assert_eq!(names[0], "power-notification");
    assert_eq!(names[2], "sensor-data-streaming");
    assert_eq!(names[4], "pre-sleep-warning");
    assert_eq!(names[6], "collision-detected");
    assert!(names.iter().all(|n| !n.starts_with("async-")));
    assert_eq!(catalog::async_name(0x12), "async-12");
}

// -------------------------------------------------------------------------------------------
// FF FF inside data, resynchronisation on the checksum, truncation.
// -------------------------------------------------------------------------------------------

#[test]
fn ff_ff_inside_data_is_data() {
    let rgb = Packet::Command(cmd::set_rgb_led(0xFF, 0xFF, 0x00, false).to_packet(0));
    let wire = rgb.encode().unwrap();
    assert_eq!(wire, h("FF FF 02 20 00 05 FF FF 00 00 DA"));
    let ping = Packet::Command(cmd::ping().to_packet(1));
    let mut stream = wire.clone();
    stream.extend(ping.encode().unwrap());
    for split in 0..=stream.len() {
        let mut d = Decoder::new(Source::Host);
        let mut out = d.decode_all(&stream[..split]);
        out.extend(d.feed(&stream[split..]));
        out.extend(d.finish());
        assert_eq!(
            out,
            vec![Ok(rgb.clone()), Ok(ping.clone())],
            "split {split}"
        );
    }
    // The same from the droid: a response carrying FF FF.
    let resp = Packet::Response(Response {
        mrsp: Mrsp::Ok,
        seq: 9,
        data: h("FF FF FE FF"),
    });
    assert_eq!(only_packet(Source::Droid, &resp.encode().unwrap()), resp);
}

#[test]
fn corrupted_checksum_then_valid_packet_is_recovered() {
    let ping = Packet::Command(cmd::ping().to_packet(1));
    let ping_wire = ping.encode().unwrap();

    // Simple case: the next packet is found as soon as it is complete.
    let mut stream = h("FF FF 02 21 00 02 10 CB"); // Set Back LED, checksum CA off by one
    stream.extend(&ping_wire);
    let mut d = Decoder::new(Source::Host);
    let out = d.decode_all(&stream);
    assert_eq!(
        kinds(&out),
        vec![Err(ErrorKind::BadChecksum), Ok(Kind::Command)]
    );
    let Err(e) = &out[0] else { panic!() };
    assert_eq!(e.offset, 0);
    assert!(
        e.detail.contains("0xCB") && e.detail.contains("0xCA"),
        "{}",
        e.detail
    );
    assert!(e.packet.is_some());
    assert_eq!(out[1], Ok(ping.clone()));
    assert_eq!(d.stats().skipped_bytes, 8);

    // FF FF inside the damaged packet's data starts a bogus candidate whose DLEN (the
    // ping's SOP1, FF) swallows the ping: it is still recovered, once the stream ends.
    let mut stream = h("FF FF 02 20 00 05 FF FF 00 00 DB");
    stream.extend(&ping_wire);
    let mut d = Decoder::new(Source::Host);
    let mut out = d.decode_all(&stream);
    assert_eq!(kinds(&out), vec![Err(ErrorKind::BadChecksum)]);
    out.extend(d.finish());
    // One error for the damaged packet (the bogus candidate inside it is not reported
    // again), then the ping.
    assert_eq!(
        kinds(&out),
        vec![Err(ErrorKind::BadChecksum), Ok(Kind::Command)]
    );
    assert_eq!(out[1], Ok(ping.clone()));
    let s = d.stats();
    assert_eq!(s.skipped_bytes, 11);
    assert_eq!(s.total_errors(), 1);

    // A real packet starting inside the rejected one (not after it) is found: the damaged
    // packet's DLEN claims more than it has, so the ping lies inside its extent.
    // DLEN 10 but only 1 data byte follows: its 16-byte extent ends with two zeros, the
    // last of which is read as its (wrong, C5 expected) checksum.
    let mut stream = h("FF FF 02 21 00 0A 10");
    stream.extend(&ping_wire);
    stream.extend(h("00 00"));
    let mut d = Decoder::new(Source::Host);
    let mut out = d.decode_all(&stream);
    out.extend(d.finish());
    assert_eq!(
        kinds(&out),
        vec![Err(ErrorKind::BadChecksum), Ok(Kind::Command)]
    );
    assert_eq!(out[1], Ok(ping));
}

#[test]
fn truncated_tail_reported_by_finish() {
    let wire = h("FF FF 02 30 00 05 80 00 5A 01 ED");
    let mut d = Decoder::new(Source::Host);
    assert!(d.decode_all(&wire[..10]).is_empty());
    assert_eq!(d.buffered(), 10);
    let tail = d.finish();
    assert_eq!(kinds(&tail), vec![Err(ErrorKind::Truncated)]);
    let Err(e) = &tail[0] else { panic!() };
    assert_eq!(e.offset, 0);
    assert_eq!(d.buffered(), 0);
    assert_eq!(d.stats().skipped_bytes, 10);
    // A lone SOP1 at the end is a truncated packet too; after finish the decoder goes on.
    assert_eq!(kinds(&d.decode_all(&[0xFF])), vec![]);
    assert_eq!(kinds(&d.finish()), vec![Err(ErrorKind::Truncated)]);
    assert_eq!(kinds(&d.decode_all(&wire)), vec![Ok(Kind::Command)]);
    assert!(d.finish().is_empty());
}

#[test]
fn garbage_runs_and_bad_lengths() {
    // Garbage, a DLEN 0 response, garbage, a good response.
    let stream = h("01 02 FF 00 FF FF 00 01 00 33 FF FF 00 52 01 AC");
    let out = decode(Source::Droid, &stream);
    // The rejected header (4..9) is dropped silently after its one report; the 33 after it
    // is a new garbage run, reported before the packet that ends it.
    assert_eq!(
        kinds(&out),
        vec![
            Err(ErrorKind::Garbage),
            Err(ErrorKind::BadLength),
            Err(ErrorKind::Garbage),
            Ok(Kind::Response)
        ]
    );
    let offsets: Vec<u64> = out
        .iter()
        .filter_map(|e| e.as_ref().err().map(|e| e.offset))
        .collect();
    assert_eq!(offsets, vec![0, 4, 9]);
    let Err(g) = &out[0] else { panic!() };
    assert_eq!(g.detail, "4 byte(s) outside any packet");
}

// -------------------------------------------------------------------------------------------
// JSON.
// -------------------------------------------------------------------------------------------

#[test]
fn json_per_kind() {
    let roll = Packet::Command(cmd::roll(128, heading(90), RollState::Go).to_packet(0));
    let j = to_json(&roll, &describe(&roll, None, None), true);
    assert_eq!(j["kind"], "command");
    assert_eq!(
        (j["did"].as_u64(), j["cid"].as_u64(), j["seq"].as_u64()),
        (Some(2), Some(0x30), Some(0))
    );
    assert!(j["mrsp"].is_null() && j["mrsp_name"].is_null() && j["id_code"].is_null());
    assert_eq!(j["data"], "80005a01");
    assert_eq!(j["checksum_ok"], true);
    assert_eq!(j["command"], "roll");
    assert_eq!(
        j["fields"],
        serde_json::json!({"speed": 128, "heading": 90, "state": "go"})
    );

    let resp = Packet::Response(Response {
        mrsp: Mrsp::from_byte(0x04),
        seq: 7,
        data: vec![],
    });
    let j = to_json(&resp, &describe(&resp, None, Some(&cmd::ping())), false);
    assert_eq!(j["kind"], "response");
    assert_eq!((j["mrsp"].as_u64(), j["seq"].as_u64()), (Some(4), Some(7)));
    assert_eq!(j["mrsp_name"], "unknown_command");
    assert!(j["did"].is_null() && j["cid"].is_null() && j["id_code"].is_null());
    assert_eq!(j["checksum_ok"], false);
    assert_eq!(j["command"], "ping");
    assert!(j["fields"].is_null());

    let coll = Packet::Async(AsyncPacket::new(0x07, collision_data()));
    let j = to_json(&coll, &describe(&coll, None, None), true);
    assert_eq!(j["kind"], "async");
    assert_eq!(j["id_code"], 7);
    assert!(j["seq"].is_null() && j["did"].is_null() && j["mrsp"].is_null());
    assert_eq!(j["command"], "collision-detected");
    assert_eq!(j["fields"]["power_x"], 100);
    assert_eq!(j["fields"]["x_axis"], true);
    assert_eq!(j["data"], hex::compact(&collision_data()));
}
