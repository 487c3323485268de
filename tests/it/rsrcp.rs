//! RSRCP (Robi 42) codec vectors: handshake, every combination of the sized features, `7E`/`7F`
//! inside frames, truncated and over-long frames, unsized features, frame-id wrap, JSON, the
//! remote-control mix.

use droidctl::hex;
use droidctl::protocol::rsrcp::{
    Buttons, Efs, ErrorKind, Feature, Frame, FrameError, Framer, Handshake, Item, JSON_KEYS, Leds,
    MAX_FRAME_LEN, Motors, Piezo, decode_frame, decode_handshake, frame_delta, frame_gap,
    steering_byte, to_json, velocity_byte, wheel_speeds,
};
use serde_json::json;

fn bytes(s: &str) -> Vec<u8> {
    hex::parse(s).expect("test hex")
}

/// Every item and error, `finish` included, with the input fed one byte at a time.
fn frame_stream(stream: &[u8]) -> (Vec<Result<Item, FrameError>>, Framer) {
    let mut f = Framer::new();
    let mut out = Vec::new();
    for b in stream {
        out.extend(f.feed(std::slice::from_ref(b)));
        assert!(f.buffered() <= MAX_FRAME_LEN);
    }
    out.extend(f.finish());
    (out, f)
}

fn kinds(events: &[Result<Item, FrameError>]) -> Vec<&'static str> {
    events
        .iter()
        .map(|e| match e {
            Ok(i) => i.kind(),
            Err(e) => e.kind.name(),
        })
        .collect()
}

fn frames(events: &[Result<Item, FrameError>]) -> Vec<Frame> {
    events
        .iter()
        .filter_map(|e| match e {
            Ok(Item::Frame(f)) => Some(f.clone()),
            _ => None,
        })
        .collect()
}

/// The firmware's frame (EFS 0x4300): id 1234, motors 1.25 / 0.80 rad/s, poti 128, center and
/// left pressed.
const FIRMWARE_FRAME: &str = "7E 00 04 D2 43 00 00 7D 00 50 80 C0 7F";

#[test]
fn handshake_decodes_and_encodes() {
    let h = decode_handshake(&bytes("7E 01 00 0A 7F")).unwrap();
    assert_eq!(
        h,
        Handshake {
            version: 1,
            msdt_ms: 10
        }
    );
    assert_eq!(h.version_name(), Some("1.0.0"));
    assert_eq!(h.summary(), "handshake v1 (1.0.0) msdt 10 ms");
    // Big-endian MSDT; unknown versions are kept.
    let h = decode_handshake(&bytes("7E 02 01 2C 7F")).unwrap();
    assert_eq!((h.version, h.msdt_ms, h.version_name()), (2, 300, None));
    assert_eq!(h.encode().to_vec(), bytes("7E 02 01 2C 7F"));

    let kind = |s: &str| decode_handshake(&bytes(s)).unwrap_err().kind;
    assert_eq!(kind(""), ErrorKind::Truncated);
    assert_eq!(kind("7E 01 00 0A"), ErrorKind::Truncated);
    assert_eq!(kind("7F 01 00 0A 7F"), ErrorKind::BadSop);
    assert_eq!(kind("7E 01 00 0A 7E"), ErrorKind::BadEop);
    assert_eq!(kind("7E 01 00 0A 7F 00"), ErrorKind::Overlong);
}

#[test]
fn firmware_frame() {
    let f = decode_frame(&bytes(FIRMWARE_FRAME)).unwrap();
    assert_eq!(f.frame_id, 1234);
    assert_eq!(f.efs, Efs::FIRMWARE);
    assert_eq!(f.efs.bits(), 0x4300);
    assert_eq!(
        f.motors,
        Some(Motors {
            left_rad_s: 1.25,
            right_rad_s: 0.8
        })
    );
    assert_eq!(f.poti, Some(128));
    assert_eq!(f.buttons, Some(Buttons::CENTER | Buttons::LEFT));
    assert_eq!((f.leds, f.piezo), (None, None));
    assert_eq!(
        f.summary(),
        "frame 1234 motors L 1.25 R 0.80 rad/s poti 128 buttons center,left"
    );
    assert_eq!(f.encode(), bytes(FIRMWARE_FRAME));
    assert_eq!(Frame::len_for(f.efs), Some(13));
}

#[test]
fn hand_written_frames() {
    // Everything sized: motors -2.00 / 3.00, poti 0x7E, top, four lamps, piezo on at 440 Hz.
    let all = bytes("7E 12 34 56 43 C0 FF 38 01 2C 7E 10 A5 81 B8 7F");
    let f = decode_frame(&all).unwrap();
    assert_eq!(f.frame_id, 0x123456);
    assert_eq!(
        f.efs.names(),
        ["motors", "poti", "buttons", "leds", "piezo"]
    );
    assert_eq!(
        f.motors,
        Some(Motors {
            left_rad_s: -2.0,
            right_rad_s: 3.0
        })
    );
    assert_eq!(f.poti, Some(0x7E));
    assert_eq!(f.buttons.unwrap().names(), ["top"]);
    assert_eq!(
        f.leds.unwrap().names(),
        [
            "front_left_blinker",
            "front_right_headlight",
            "back_right_taillight",
            "back_left_blinker"
        ]
    );
    assert_eq!(f.piezo, Some(Piezo { on: true, hz: 440 }));
    assert_eq!(all.len(), MAX_FRAME_LEN);
    assert_eq!(f.encode(), all);

    // LEDs only, all lit.
    let f = decode_frame(&bytes("7E 00 00 00 00 80 FF 7F")).unwrap();
    assert_eq!(f.leds, Some(Leds::all()));
    assert_eq!(f.leds.unwrap().names().len(), 8);
    assert_eq!(f.motors, None);

    // Piezo only, silent at 20 kHz, frame id full of 7F.
    let f = decode_frame(&bytes("7E 7F 7F 7F 00 40 4E 20 7F")).unwrap();
    assert_eq!(f.frame_id, 0x7F7F7F);
    assert_eq!(
        f.piezo,
        Some(Piezo {
            on: false,
            hz: 20000
        })
    );

    // Nothing enabled: header and EOP.
    let f = decode_frame(&bytes("7E FF FF FF 00 00 7F")).unwrap();
    assert_eq!((f.frame_id, f.efs), (0xFFFFFF, Efs::empty()));
    assert_eq!(f.summary(), "frame 16777215 (no features)");

    // Unused button bits are kept, not named.
    let f = decode_frame(&bytes("7E 00 00 01 01 00 87 7F")).unwrap();
    assert_eq!(f.buttons.unwrap().bits(), 0x87);
    assert_eq!(f.buttons.unwrap().names(), ["center"]);
}

/// A frame with the sized features of `mask` (bit 0 motors .. bit 4 piezo), values chosen to
/// put 7E and 7F in the payload.
fn subset_frame(mask: u8, id: u32) -> Frame {
    let mut f = Frame::new(id);
    if mask & 1 != 0 {
        f = f.with_motors(1.26, 1.27); // 00 7E 00 7F
    }
    if mask & 2 != 0 {
        f = f.with_poti(0x7E);
    }
    if mask & 4 != 0 {
        f = f.with_buttons(Buttons::RIGHT | Buttons::BOTTOM);
    }
    if mask & 8 != 0 {
        f = f.with_leds(Leds::from_bits_retain(0x7F));
    }
    if mask & 16 != 0 {
        f = f.with_piezo(false, 0x7E7F);
    }
    f
}

#[test]
fn every_subset_of_sized_features_round_trips() {
    let mut stream = Vec::new();
    let mut expected = Vec::new();
    for mask in 0..32u8 {
        let f = subset_frame(mask, 0x7F7E00 + u32::from(mask));
        let wire = f.encode();
        let n = mask.count_ones() as usize;
        let payload: usize = [4, 1, 1, 1, 2]
            .iter()
            .enumerate()
            .filter(|(i, _)| mask & (1 << i) != 0)
            .map(|(_, s)| s)
            .sum();
        assert_eq!(wire.len(), 7 + payload, "mask {mask:05b}");
        assert_eq!(Frame::len_for(f.efs), Some(wire.len()));
        assert_eq!(f.efs.features().count(), n);
        assert_eq!(wire[0], 0x7E);
        assert_eq!(wire[wire.len() - 1], 0x7F);
        assert_eq!(
            u16::from_be_bytes([wire[4], wire[5]]),
            f.efs.bits(),
            "mask {mask:05b}"
        );
        let back = decode_frame(&wire).unwrap_or_else(|e| panic!("mask {mask:05b}: {e}"));
        assert_eq!(back, f, "mask {mask:05b}");
        assert_eq!(back.encode(), wire);
        stream.extend_from_slice(&wire);
        expected.push(f);
    }
    // The same frames back to back as one stream, byte by byte: all found, nothing skipped.
    let (out, framer) = frame_stream(&stream);
    assert_eq!(frames(&out), expected);
    assert_eq!(out.len(), 32);
    assert_eq!(framer.stats().packets, 32);
    assert_eq!(framer.stats().skipped_bytes, 0);
    assert_eq!(framer.stats().total_errors(), 0);
}

#[test]
fn sop_and_eop_values_inside_frames_are_data() {
    // Frame id 7F 7E 7F and poti 7E; then a full frame whose poti 7E is followed four bytes
    // later by 7F (a handshake look-alike inside it); then a handshake.
    let a = bytes("7E 7F 7E 7F 02 00 7E 7F");
    let b = bytes("7E 00 7E 7F 43 C0 7E 7F 7F 7E 7E 10 A5 81 7F 7F");
    assert_eq!(b.len(), MAX_FRAME_LEN);
    let h = bytes("7E 01 00 0A 7F");
    let stream = [a.clone(), b.clone(), h.clone(), a.clone()].concat();
    let (out, framer) = frame_stream(&stream);
    assert_eq!(
        kinds(&out),
        ["frame", "frame", "handshake", "frame"],
        "{out:?}"
    );
    let got = frames(&out);
    assert_eq!(got[0].frame_id, 0x7F7E7F);
    assert_eq!(got[0].poti, Some(0x7E));
    assert_eq!(got[1], decode_frame(&b).unwrap());
    assert_eq!(got[1].poti, Some(0x7E));
    assert_eq!(framer.stats().skipped_bytes, 0);
}

#[test]
fn truncated_and_overlong_single_frames() {
    let good = bytes(FIRMWARE_FRAME);
    let short = &good[..good.len() - 1];
    let e = decode_frame(short).unwrap_err();
    assert_eq!((e.kind, e.at()), (ErrorKind::Truncated, 12));
    assert!(e.detail.contains("implies 13"), "{}", e.detail);
    let e = decode_frame(&good[..4]).unwrap_err();
    assert_eq!(e.kind, ErrorKind::Truncated);

    let mut long = good.clone();
    long.push(0x7F);
    let e = decode_frame(&long).unwrap_err();
    assert_eq!((e.kind, e.at()), (ErrorKind::Overlong, 13));

    let mut bad = good.clone();
    bad[12] = 0x7E;
    let e = decode_frame(&bad).unwrap_err();
    assert_eq!((e.kind, e.at()), (ErrorKind::BadEop, 12));

    let e = decode_frame(&bytes("00 7E 00 04 D2")).unwrap_err();
    assert_eq!(e.kind, ErrorKind::BadSop);
    assert_eq!(decode_frame(&[]).unwrap_err().kind, ErrorKind::Truncated);
}

#[test]
fn truncated_and_overlong_frames_in_a_stream() {
    let good = bytes(FIRMWARE_FRAME);
    // A byte lost inside a frame: the computed end lands on the next frame's SOP.
    let mut dropped = good.clone();
    dropped.remove(8);
    // A byte too many inside a frame.
    let mut extra = good.clone();
    extra.insert(8, 0x55);
    let stream = [
        dropped.clone(),
        good.clone(),
        extra.clone(),
        good.clone(),
        good[..7].to_vec(),
    ]
    .concat();
    let (out, framer) = frame_stream(&stream);
    assert_eq!(
        kinds(&out),
        [
            "bad_eop",
            "frame",
            "bad_eop",
            "garbage",
            "frame",
            "truncated"
        ],
        "{out:?}"
    );
    let Err(e) = &out[0] else { unreachable!() };
    assert_eq!(e.offset, 0);
    let Err(e) = &out[2] else { unreachable!() };
    assert_eq!(e.offset, (dropped.len() + good.len()) as u64);
    // The extra frame claimed 13 bytes; its 14th (the EOP) is garbage, reported once.
    let Err(e) = &out[3] else { unreachable!() };
    assert_eq!(e.offset, (dropped.len() + good.len() + 13) as u64);
    let Err(e) = &out[5] else { unreachable!() };
    assert_eq!(e.offset, (stream.len() - 7) as u64);
    assert_eq!(framer.stats().packets, 2);
    assert_eq!(framer.stats().errors(ErrorKind::BadEop), 2);
    assert_eq!(framer.stats().errors(ErrorKind::Truncated), 1);
    // Every byte is in a frame or skipped.
    assert_eq!(
        framer.stats().skipped_bytes + 2 * good.len() as u64,
        stream.len() as u64
    );
}

#[test]
fn unsized_features_stop_decoding() {
    // 0x4300 decodes; 0x6300 adds the gyro after the motors: motors decoded, poti and buttons
    // (after the gyro) not.
    assert!(decode_frame(&bytes(FIRMWARE_FRAME)).is_ok());
    let gyro = bytes("7E 00 04 D2 63 00 00 7D 00 50 01 02 03 04 80 C0 7F");
    let e = decode_frame(&gyro).unwrap_err();
    assert_eq!(e.kind, ErrorKind::UnsizedFeature);
    assert_eq!(e.kind.name(), "unsized_feature");
    assert_eq!(e.feature(), Some(Feature::Gyro));
    assert_eq!(e.at(), 10);
    assert!(e.detail.contains("gyro"), "{}", e.detail);
    let p = e.partial().unwrap();
    assert_eq!(p.frame_id, 1234);
    assert_eq!(p.efs.bits(), 0x6300);
    assert_eq!(
        p.motors,
        Some(Motors {
            left_rad_s: 1.25,
            right_rad_s: 0.8
        })
    );
    assert_eq!((p.poti, p.buttons), (None, None));
    assert_eq!(Frame::len_for(p.efs), None);

    // Each unsized feature, alone with everything sized.
    for (bit, feature, decoded) in [
        (0x8000, Feature::Voltages, 0),
        (0x2000, Feature::Gyro, 1),
        (0x1000, Feature::Accel, 1),
        (0x0800, Feature::Laser, 1),
        (0x0400, Feature::Ir, 1),
        (0x0020, Feature::Lcd, 5),
    ] {
        let efs = Efs::from_bits_retain(0x43C0 | bit);
        let mut wire = bytes("7E 00 00 01");
        wire.extend_from_slice(&efs.bits().to_be_bytes());
        wire.extend_from_slice(&[0x11; 12]);
        wire.push(0x7F);
        let e = decode_frame(&wire).unwrap_err();
        assert_eq!(e.feature(), Some(feature), "{bit:04X}");
        let p = e.partial().unwrap();
        let got = [
            p.motors.is_some(),
            p.poti.is_some(),
            p.buttons.is_some(),
            p.leds.is_some(),
            p.piezo.is_some(),
        ];
        assert_eq!(got.iter().filter(|x| **x).count(), decoded, "{bit:04X}");
    }

    // Reserved bits: all defined features read, then stop.
    let e = decode_frame(&bytes("7E 00 04 D2 43 01 00 7D 00 50 80 C0 99 7F")).unwrap_err();
    assert_eq!(e.kind, ErrorKind::ReservedBits);
    assert_eq!(
        e.partial().unwrap().buttons,
        Some(Buttons::CENTER | Buttons::LEFT)
    );
    assert_eq!(Frame::len_for(Efs::from_bits_retain(0x4301)), None);
    assert_eq!(Frame::len_for(Efs::from_bits_retain(0x4300)), Some(13));
}

#[test]
fn unsized_features_in_a_stream() {
    let gyro = bytes("7E 00 04 D2 63 00 00 7D 00 50 01 02 03 04 80 C0 7F");
    let good = bytes(FIRMWARE_FRAME);
    let (out, _) = frame_stream(&[gyro.clone(), good.clone()].concat());
    assert_eq!(
        kinds(&out),
        ["unsized_feature", "garbage", "frame"],
        "{out:?}"
    );
    let Err(e) = &out[0] else { unreachable!() };
    assert_eq!(e.offset, 0);
    assert!(e.partial().unwrap().motors.is_some());
    let Err(g) = &out[1] else { unreachable!() };
    assert_eq!(g.offset, 10);
    assert_eq!(frames(&out)[0], decode_frame(&good).unwrap());
}

#[test]
fn garbage_before_between_and_after() {
    let good = bytes(FIRMWARE_FRAME);
    let stream = [
        bytes("00 01 02"),
        good.clone(),
        bytes("7F 7F"),
        bytes("7E 01 00 64 7F"),
        bytes("AA"),
    ]
    .concat();
    let (out, framer) = frame_stream(&stream);
    assert_eq!(
        kinds(&out),
        ["garbage", "frame", "garbage", "handshake", "garbage"]
    );
    let offsets: Vec<u64> = out
        .iter()
        .filter_map(|e| e.as_ref().err().map(|e| e.offset))
        .collect();
    assert_eq!(offsets, [0, 16, 23]);
    assert_eq!(framer.stats().packets, 2);
    assert_eq!(framer.stats().skipped_bytes, 6);
    assert_eq!(framer.stats().errors(ErrorKind::Garbage), 3);
}

#[test]
fn frame_ids_wrap_modulo_2_pow_24() {
    assert_eq!(frame_gap(0xFF_FFFF, 0), 0);
    assert_eq!(frame_delta(0xFF_FFFF, 0), 1);
    assert_eq!(frame_gap(0xFF_FFFD, 2), 4);
    assert_eq!(frame_gap(10, 11), 0);
    assert_eq!(frame_gap(10, 15), 4);
    assert_eq!(frame_gap(10, 10), 0);
    assert_eq!(frame_delta(10, 10), 0);
    // Encoding wraps the id to 24 bits too.
    let f = Frame::new(0x0100_0000 + 5).with_poti(1);
    assert_eq!(decode_frame(&f.encode()).unwrap().frame_id, 5);
    let mut f = Frame::new(0).with_poti(1);
    f.frame_id = 0xFFFF_FFFF;
    assert_eq!(decode_frame(&f.encode()).unwrap().frame_id, 0xFF_FFFF);
    // Counting losses over a wrapping run of ids.
    let ids = [0xFF_FFFE, 0xFF_FFFF, 0, 3, 4];
    let lost: u32 = ids.windows(2).map(|w| frame_gap(w[0], w[1])).sum();
    assert_eq!(lost, 2);
}

#[test]
fn json_has_every_key() {
    let keys =
        |v: &serde_json::Value| -> Vec<String> { v.as_object().unwrap().keys().cloned().collect() };
    let f = decode_frame(&bytes(FIRMWARE_FRAME)).unwrap();
    let j = to_json(&Ok(Item::Frame(f.clone())));
    assert_eq!(keys(&j), JSON_KEYS);
    assert_eq!(
        j,
        json!({
            "kind": "frame",
            "version": null,
            "msdt_ms": null,
            "frame_id": 1234,
            "efs": 0x4300,
            "features": ["motors", "poti", "buttons"],
            "motor_left_rad_s": 1.25,
            "motor_right_rad_s": 0.8,
            "poti": 128,
            "buttons": ["center", "left"],
            "leds": null,
            "piezo_on": null,
            "piezo_hz": null,
            "error": null,
            "offset": null,
            "detail": null,
        })
    );

    let h = Handshake {
        version: 1,
        msdt_ms: 10,
    };
    let j = to_json(&Ok(Item::Handshake(h)));
    assert_eq!(keys(&j), JSON_KEYS);
    assert_eq!(j["kind"], "handshake");
    assert_eq!(j["version"], 1);
    assert_eq!(j["msdt_ms"], 10);
    assert_eq!(j["frame_id"], serde_json::Value::Null);

    let all = decode_frame(&bytes("7E 12 34 56 43 C0 FF 38 01 2C 7E 10 A5 81 B8 7F")).unwrap();
    let j = all.to_json();
    assert_eq!(j["leds"].as_array().unwrap().len(), 4);
    assert_eq!(
        (j["piezo_on"].clone(), j["piezo_hz"].clone()),
        (json!(true), json!(440))
    );
    assert_eq!(j["motor_left_rad_s"], -2.0);

    // A partial frame: what was decoded, plus the error.
    let e = decode_frame(&bytes("7E 00 04 D2 63 00 00 7D 00 50 01 02 7F")).unwrap_err();
    let j = to_json(&Err(e.clone()));
    assert_eq!(keys(&j), JSON_KEYS);
    assert_eq!(j["kind"], "frame");
    assert_eq!(j["frame_id"], 1234);
    assert_eq!(j["features"], json!(["motors", "gyro", "poti", "buttons"]));
    assert_eq!(j["motor_right_rad_s"], 0.8);
    assert_eq!(j["poti"], serde_json::Value::Null);
    assert_eq!(j["error"], "unsized_feature");
    assert_eq!(j["offset"], 0);
    assert!(j["detail"].as_str().unwrap().contains("gyro"));
    assert!(
        e.summary().contains("frame 1234 motors L 1.25"),
        "{}",
        e.summary()
    );

    // Garbage: only the error keys.
    let (out, _) = frame_stream(&bytes("01 02"));
    let j = to_json(&out[0]);
    assert_eq!(keys(&j), JSON_KEYS);
    assert_eq!(j["kind"], serde_json::Value::Null);
    assert_eq!(j["error"], "garbage");
    assert_eq!(j["offset"], 0);
}

#[test]
fn fields_for_the_packet_log() {
    let f = decode_frame(&bytes(FIRMWARE_FRAME)).unwrap();
    let names: Vec<&str> = f.fields().iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        [
            "frame_id",
            "efs",
            "motor_left_rad_s",
            "motor_right_rad_s",
            "poti",
            "buttons"
        ]
    );
    let line = droidctl::protocol::value::fields_line(&f.fields());
    assert!(line.contains("buttons=center|left (0xC0)"), "{line}");
    assert!(line.contains("efs=motors|poti|buttons (0x4300)"), "{line}");
    let h = Item::Handshake(Handshake {
        version: 1,
        msdt_ms: 10,
    });
    assert_eq!(
        droidctl::protocol::value::fields_line(&h.fields()),
        "version=1 msdt_ms=10"
    );
    assert_eq!(f.sensor_sample().get("poti"), Some(128.0));
}

#[test]
fn remote_control_bytes_and_mix() {
    assert_eq!(velocity_byte(1.0), 255);
    assert_eq!(velocity_byte(0.0), 0);
    assert_eq!(velocity_byte(-1.0), 0);
    assert_eq!(velocity_byte(f32::NAN), 0);
    assert_eq!(steering_byte(0.0), 128);
    assert_eq!(steering_byte(-1.0), 0);
    assert_eq!(steering_byte(1.0), 255);
    assert_eq!(steering_byte(2.0), 255);
    // droid-facts §5: s' = 2(s - 0.5); left = clamp01(v(1 + s')), right = clamp01(v(1 - s')).
    assert_eq!(wheel_speeds(255, 0), (0.0, 1.0));
    assert_eq!(wheel_speeds(255, 255), (1.0, 0.0));
    assert_eq!(wheel_speeds(0, 200), (0.0, 0.0));
    let (l, r) = wheel_speeds(102, 191);
    let (v, sp) = (102.0 / 255.0, 2.0 * (191.0 / 255.0 - 0.5));
    assert!((l - (v * (1.0 + sp)) as f32).abs() < 1e-6);
    assert!((r - (v * (1.0 - sp)) as f32).abs() < 1e-6);
    for (vb, sb) in [(0, 0), (17, 99), (255, 128), (128, 255), (255, 3)] {
        let (l, r) = wheel_speeds(vb, sb);
        assert!((0.0..=1.0).contains(&l) && (0.0..=1.0).contains(&r));
    }
}

#[test]
fn gatt_uuids_are_the_facts_sheets() {
    let short = |u: droidctl::gatt::GattUuid| u.as_u16().unwrap();
    assert_eq!(
        short(droidctl::family::robi::gatt::ROBI_RSRC_SERVICE),
        0x2579
    );
    assert_eq!(short(droidctl::family::robi::gatt::ROBI_FRAMES), 0x8765);
    assert_eq!(short(droidctl::family::robi::gatt::ROBI_HANDSHAKE), 0x4744);
    assert_eq!(short(droidctl::family::robi::gatt::ROBI_START), 0x4234);
    assert_eq!(short(droidctl::family::robi::gatt::ROBI_RC_SERVICE), 0xBA73);
    assert_eq!(short(droidctl::family::robi::gatt::ROBI_VELOCITY), 0x6B2F);
    assert_eq!(short(droidctl::family::robi::gatt::ROBI_STEERING), 0x3F4A);
}
