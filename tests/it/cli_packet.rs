//! `droidctl packet decode|encode|list`, run as the built binary.

use droidctl::hex;
use droidctl::protocol::v2::{Flags, Packet};
use serde_json::{Value, json};

use crate::common::cli;
use cli::{droidctl, stderr, stdout, usage_error};

/// Run, expect `status`, no stderr; return stdout.
fn ok_with(args: &[&str], status: i32) -> String {
    let o = droidctl(args);
    assert_eq!(
        o.status.code(),
        Some(status),
        "{args:?}: stderr {}",
        stderr(&o)
    );
    assert_eq!(stderr(&o), "", "{args:?}");
    stdout(&o)
}

fn ok(args: &[&str]) -> String {
    ok_with(args, 0)
}

/// One JSON object per line.
fn json_lines(text: &str) -> Vec<Value> {
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l:?}: {e}")))
        .collect()
}

const WAKE: &str = "8D 0A 13 0D 00 D5 D8";
const WAKE_RESPONSE: &str = "8D 09 13 0D 00 00 D6 D8";
const HEAD: &str = "8D 3A 12 01 17 0F 00 3F 00 00 00 4D D8";
const ESCAPED: &str = "8D 0A 1A 0E AB 05 00 AB 23 AB 50 BD D8";

// --- decode -----------------------------------------------------------------------------------

#[test]
fn decode_human_wake() {
    let out = ok(&["packet", "decode", WAKE]);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(
        lines,
        [
            "wire      8D 0A 13 0D 00 D5 D8",
            "flags     0x0A requests_response | is_activity",
            "device    power (0x13)",
            "command   wake (0x0D)",
            "seq       0",
            "data      (none)",
            "checksum  0xD5 ok",
        ]
    );
}

#[test]
fn decode_human_accepts_separate_words_and_prefixes() {
    let words: Vec<&str> = WAKE.split(' ').collect();
    let mut args = vec!["packet", "decode"];
    args.extend(&words);
    let a = ok(&args);
    assert_eq!(
        a,
        ok(&["packet", "decode", "0x8d:0x0a:0x13:0x0d:0x00:0xd5:0xd8"])
    );
    assert_eq!(a, ok(&["packet", "decode", "8d0a130d00d5d8"]));
}

#[test]
fn decode_human_response_and_addressed_command() {
    let out = ok(&["packet", "decode", WAKE_RESPONSE]);
    assert!(out.contains("response  wake (0x0D)"), "{out}");
    assert!(out.contains("error     0x00 success"), "{out}");
    assert!(out.contains("checksum  0xD6 ok"), "{out}");

    let out = ok(&["packet", "decode", HEAD]);
    assert!(out.contains("command   set-head-position (0x0F)"), "{out}");
    assert!(out.contains("target    0x12"), "{out}");
    assert!(out.contains("source    0x01"), "{out}");
    assert!(out.contains("data      3F 00 00 00"), "{out}");
    assert!(
        out.lines()
            .any(|l| l.trim_start().starts_with("degrees") && l.ends_with("0.5")),
        "{out}"
    );
}

#[test]
fn decode_json_wake_has_every_key() {
    let out = ok(&["packet", "decode", "--json", WAKE]);
    let v = json_lines(&out);
    assert_eq!(v.len(), 1);
    let v = &v[0];
    for key in [
        "did",
        "cid",
        "seq",
        "flags",
        "tid",
        "sid",
        "err",
        "data",
        "checksum_ok",
        "command",
        "fields",
    ] {
        assert!(v.get(key).is_some(), "missing {key}: {v}");
    }
    assert_eq!(v["did"], 0x13);
    assert_eq!(v["cid"], 0x0D);
    assert_eq!(v["seq"], 0);
    assert_eq!(v["flags"], 0x0A);
    assert_eq!(v["tid"], Value::Null);
    assert_eq!(v["sid"], Value::Null);
    assert_eq!(v["err"], Value::Null, "err is null on commands");
    assert_eq!(v["data"], "");
    assert_eq!(v["checksum_ok"], true);
    assert_eq!(v["command"], "wake");
    assert_eq!(v["fields"], json!({}));
    assert_eq!(v["kind"], "command");
}

#[test]
fn decode_json_response_addressed_and_escaped() {
    let v = &json_lines(&ok(&["packet", "decode", "--json", WAKE_RESPONSE]))[0];
    assert_eq!(v["kind"], "response");
    assert_eq!(v["flags"], 0x09);
    assert_eq!(v["err"], 0);
    assert_eq!(v["command"], "wake");

    let v = &json_lines(&ok(&["packet", "decode", "--json", HEAD]))[0];
    assert_eq!(
        (v["did"].clone(), v["cid"].clone()),
        (json!(0x17), json!(0x0F))
    );
    assert_eq!(v["flags"], 0x3A);
    assert_eq!(v["tid"], 0x12);
    assert_eq!(v["sid"], 0x01);
    assert_eq!(v["data"], "3f000000");
    assert_eq!(v["command"], "set-head-position");
    assert_eq!(v["fields"], json!({"degrees": 0.5}));

    // Data hex is lower case and unescaped.
    let v = &json_lines(&ok(&["packet", "decode", "--json", ESCAPED]))[0];
    assert_eq!(v["seq"], 0x8D);
    assert_eq!(v["data"], "00abd8");
    assert_eq!(v["command"], "set-all-leds-with-16-bit-mask");
    assert_eq!(v["fields"], json!({"mask": 0xAB, "values": "d8"}));
    assert_eq!(v["checksum_ok"], true);
}

#[test]
fn decode_bad_checksum_shows_packet_with_checksum_ok_false() {
    let bad = "8D 0A 13 0D 00 D4 D8";
    let v = json_lines(&ok_with(&["packet", "decode", "--json", bad], 1));
    assert_eq!(v.len(), 1);
    assert_eq!(v[0]["checksum_ok"], false);
    assert_eq!(v[0]["command"], "wake");
    assert_eq!(v[0]["did"], 0x13);

    let out = ok_with(&["packet", "decode", bad], 1);
    // The wire line shows the bytes as received, not a re-encoding with a fixed checksum.
    assert!(out.starts_with("wire      8D 0A 13 0D 00 D4 D8\n"), "{out}");
    assert!(out.contains("checksum  BAD"), "{out}");
    assert!(out.contains("0xD5 expected"), "{out}");
}

#[test]
fn decode_notification_fields() {
    // Collision notification, 18 bytes; the 0xAB in time_ms is escaped.
    let data = hex::parse("10 00 F8 00 F0 00 01 00 64 FF FB 7F FF C8 89 AB CD EF").unwrap();
    let wire = hex::spaced(&Packet::notification(0x18, 0x12, data).encode());
    let v = &json_lines(&ok(&["packet", "decode", "--json", &wire]))[0];
    assert_eq!(v["kind"], "notification");
    assert_eq!(v["seq"], 255);
    assert_eq!(v["command"], "collision-detected");
    assert_eq!(
        v["fields"],
        json!({
            "accel_x": 1.0, "accel_y": -0.5, "accel_z": -1.0, "x_axis": true, "y_axis": false,
            "power_x": 100, "power_y": -5, "power_z": 32767, "speed": 200, "time_ms": 0x89AB_CDEFu32
        })
    );
}

#[test]
fn decode_sensor_stream_with_masks() {
    let values = [
        1.5f32, -2.25, 90.0, 0.5, -0.25, 1.0, 0.125, -0.5, 0.25, 0.0, 10.0, -20.0, 30.0,
    ];
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
    let wire = hex::spaced(&Packet::notification(0x18, 0x02, data).encode());
    let args = [
        "packet",
        "decode",
        "--json",
        "--sensor-mask",
        "0x0007E078",
        "--ext-mask",
        "0x03800000",
        wire.as_str(),
    ];
    let v = &json_lines(&ok(&args))[0];
    assert_eq!(
        v["fields"],
        json!({
            "pitch": 1.5, "roll": -2.25, "yaw": 90.0, "accel_x": 0.5, "accel_y": -0.25,
            "accel_z": 1.0, "locator_x": 12.5, "locator_y": -50.0, "velocity_x": 25.0,
            "velocity_y": 0.0, "gyro_x": 10.0, "gyro_y": -20.0, "gyro_z": 30.0
        })
    );
    // Without the masks: the plain list.
    let v = &json_lines(&ok(&["packet", "decode", "--json", &wire]))[0];
    assert_eq!(v["fields"]["values"].as_array().map(Vec::len), Some(13));
}

#[test]
fn decode_stream_json_with_garbage() {
    let stream = format!("01 02 {WAKE} FF {HEAD} 77");
    let v = json_lines(&ok(&["packet", "decode", "--stream", "--json", &stream]));
    assert_eq!(v.len(), 5, "{v:?}");
    assert_eq!(v[0]["error"], "garbage");
    assert_eq!(v[0]["offset"], 0);
    assert_eq!(v[1]["command"], "wake");
    assert_eq!(v[1]["checksum_ok"], true);
    assert_eq!(v[2]["error"], "garbage");
    assert_eq!(v[2]["offset"], 9);
    assert_eq!(v[3]["command"], "set-head-position");
    assert_eq!(v[4]["error"], "garbage");
    assert_eq!(v[4]["offset"], 23);
    for e in [&v[0], &v[2], &v[4]] {
        assert!(e.get("error").is_some() && e["offset"].is_u64(), "{e}");
        assert!(e.get("did").is_none(), "{e}");
    }
}

#[test]
fn decode_stream_json_reports_every_error_kind_with_offsets() {
    // Bad checksum, SOP inside a packet, bad escape, too short, a good packet, truncated.
    let stream =
        format!("8D 0A 13 0D 00 D4 D8 8D 0A 13 8D 0A AB 11 D8 8D 0A D8 {ESCAPED} 8D 0A 13");
    let v = json_lines(&ok(&["packet", "decode", "--stream", "--json", &stream]));
    let kinds: Vec<&str> = v
        .iter()
        .map(|o| o.get("error").and_then(Value::as_str).unwrap_or("packet"))
        .collect();
    assert_eq!(
        kinds,
        [
            "bad_checksum",
            "sop_inside_packet",
            "bad_escape",
            "too_short",
            "packet",
            "truncated"
        ]
    );
    let offsets: Vec<u64> = v.iter().filter_map(|o| o["offset"].as_u64()).collect();
    assert_eq!(offsets, [0, 7, 10, 15, 31]);
}

#[test]
fn decode_stream_human_with_garbage() {
    let out = ok(&["packet", "decode", "--stream", &format!("01 02 {WAKE} FF")]);
    assert!(
        out.contains("decode error: garbage at offset 0: 2 byte(s) outside any packet"),
        "{out}"
    );
    assert!(out.contains("command   wake (0x0D)"), "{out}");
    assert!(out.contains("decode error: garbage at offset 9"), "{out}");
}

#[test]
fn decode_single_error_exits_1() {
    let v = json_lines(&ok_with(&["packet", "decode", "--json", "8D 0A"], 1));
    assert_eq!(
        v,
        [
            json!({"error": "truncated", "offset": 0, "detail": "1 body bytes before the stream ended, no end byte (D8): cut short, or its end byte is wrong (the last byte is 0A)"})
        ]
    );
    // Issue 39 point 13: a wrong end byte is named, not only "truncated".
    let out = ok_with(&["packet", "decode", "8D 0A 13 0D 00 D5 D9"], 1);
    assert!(
        out.contains("no end byte (D8)") && out.contains("the last byte is D9"),
        "{out}"
    );
    let out = ok_with(&["packet", "decode", "01 02"], 1);
    assert!(
        out.starts_with("decode error: garbage at offset 0"),
        "{out}"
    );
}

// --- encode -----------------------------------------------------------------------------------

/// The examples with their wire bytes (checksums worked out by hand).
const ENCODE_EXAMPLES: &[(&[&str], &str)] = &[
    (
        &[
            "drive-with-heading",
            "--speed",
            "100",
            "--heading",
            "180",
            "--flags",
            "0",
        ],
        "8D 0A 16 07 00 64 00 B4 00 C0 D8",
    ),
    (
        &["set-head-position", "--degrees", "90"],
        "8D 0A 17 0F 00 42 B4 00 00 D9 D8",
    ),
    (
        &["perform-leg-action", "--action", "tripod"],
        "8D 0A 17 0D 00 01 D0 D8",
    ),
    (
        &["play-animation", "--id", "10"],
        "8D 0A 17 05 00 00 0A CF D8",
    ),
    (
        &["play-audio-file", "--sound", "1915", "--mode", "immediate"],
        "8D 0A 1A 07 00 07 7B 00 52 D8",
    ),
    (
        &[
            "set-all-leds-with-16-bit-mask",
            "--mask",
            "0x0080",
            "--values",
            "ff",
        ],
        "8D 0A 1A 0E 00 00 80 FF 4E D8",
    ),
    (&["wake"], WAKE),
    (
        &[
            "raw", "--did", "0x16", "--cid", "0x07", "--data", "6400b400",
        ],
        "8D 0A 16 07 00 64 00 B4 00 C0 D8",
    ),
];

#[test]
fn encode_examples() {
    for (args, wire) in ENCODE_EXAMPLES {
        let mut full = vec!["packet", "encode"];
        full.extend_from_slice(args);
        assert_eq!(ok(&full), format!("{wire}\n"), "{args:?}");
    }
}

#[test]
fn encode_examples_decode_back() {
    let expected = [
        (
            "drive-with-heading",
            json!({"speed": 100, "heading": 180, "flags": []}),
        ),
        ("set-head-position", json!({"degrees": 90.0})),
        ("perform-leg-action", json!({"action": "tripod"})),
        ("play-animation", json!({"id": 10})),
        (
            "play-audio-file",
            json!({"sound": 1915, "mode": "immediate"}),
        ),
        (
            "set-all-leds-with-16-bit-mask",
            json!({"mask": 0x80, "values": "ff"}),
        ),
        ("wake", json!({})),
        (
            "drive-with-heading",
            json!({"speed": 100, "heading": 180, "flags": []}),
        ),
    ];
    for ((_, wire), (name, fields)) in ENCODE_EXAMPLES.iter().zip(expected) {
        let v = &json_lines(&ok(&["packet", "decode", "--json", wire]))[0];
        assert_eq!(v["command"], name);
        assert_eq!(v["fields"], fields, "{name}");
        assert_eq!(v["checksum_ok"], true);
    }
}

#[test]
fn encode_header_options() {
    let enc = |args: &[&str]| {
        let mut full = vec!["packet", "encode"];
        full.extend_from_slice(args);
        ok(&full).trim_end().to_string()
    };
    assert_eq!(
        enc(&["wake", "--seq", "7", "--tid", "0x12", "--sid", "0x01"]),
        "8D 3A 12 01 13 0D 07 8B D8"
    );
    assert_eq!(enc(&["wake", "--no-response"]), "8D 08 13 0D 00 D7 D8");
    assert_eq!(enc(&["wake", "--seq=254"]), "8D 0A 13 0D FE D7 D8");
    // The 0.5 vector of vectors.md, from the command line.
    assert_eq!(
        enc(&[
            "set-head-position",
            "--degrees",
            "0.5",
            "--tid",
            "18",
            "--sid",
            "1"
        ]),
        HEAD
    );
    // Escaping: SEQ 0x8D and data needing escapes.
    assert_eq!(
        enc(&[
            "raw", "--did", "0x1a", "--cid", "0x0e", "--seq", "0x8d", "--data", "00abd8"
        ]),
        ESCAPED
    );

    // Each combination agrees with the library's encoder.
    for (seq, tid, sid, no_response) in [
        (0u8, None, None, false),
        (9, Some(0x12u8), None, false),
        (200, None, Some(0x01u8), true),
        (254, Some(0xFF), Some(0x00), true),
    ] {
        let seq_s = seq.to_string();
        let tid_s = tid.map(|t: u8| t.to_string());
        let sid_s = sid.map(|s: u8| s.to_string());
        let mut args = vec!["play-animation", "--id", "10", "--seq", seq_s.as_str()];
        if let Some(t) = &tid_s {
            args.extend(["--tid", t.as_str()]);
        }
        if let Some(s) = &sid_s {
            args.extend(["--sid", s.as_str()]);
        }
        if no_response {
            args.push("--no-response");
        }
        let mut p = Packet::command(0x17, 0x05, seq, vec![0, 10]);
        p.tid = tid;
        p.sid = sid;
        if no_response {
            p.flags.remove(Flags::REQUESTS_RESPONSE);
        }
        assert_eq!(
            enc(&args),
            hex::spaced(&p.normalized().encode()),
            "{args:?}"
        );
    }
}

// --- errors -----------------------------------------------------------------------------------

#[test]
fn error_unknown_command() {
    let e = usage_error(&["packet", "encode", "fly-to-the-moon"]);
    assert!(e.contains("unknown command \"fly-to-the-moon\""), "{e}");
    let e = usage_error(&["packet", "encode", "drive-heading"]);
    assert!(
        e.contains("did you mean") && e.contains("drive-with-heading"),
        "{e}"
    );
}

#[test]
fn error_missing_parameter() {
    let e = usage_error(&["packet", "encode", "drive-with-heading", "--speed", "100"]);
    assert!(e.contains("needs --heading"), "{e}");
    let e = usage_error(&["packet", "encode", "drive-with-heading", "--speed"]);
    assert!(e.contains("--speed needs a value"), "{e}");
    let e = usage_error(&["packet", "encode", "raw", "--cid", "1"]);
    assert!(e.contains("raw needs --did"), "{e}");
}

#[test]
fn error_heading_360() {
    let e = usage_error(&[
        "packet",
        "encode",
        "drive-with-heading",
        "--speed",
        "100",
        "--heading",
        "360",
        "--flags",
        "0",
    ]);
    assert!(e.contains("--heading") && e.contains("0..=359"), "{e}");
}

#[test]
fn error_malformed_hex() {
    let e = usage_error(&["packet", "decode", "8D 0G"]);
    assert!(e.contains("malformed hex"), "{e}");
    let e = usage_error(&["packet", "decode", "8D 0"]);
    assert!(e.contains("odd number"), "{e}");
    let e = usage_error(&[
        "packet", "encode", "raw", "--did", "1", "--cid", "2", "--data", "zz",
    ]);
    assert!(e.contains("--data") && e.contains("malformed hex"), "{e}");
    let e = usage_error(&["packet", "encode", "set-led", "--data", "01 02"]);
    assert!(e.contains("--data"), "{e}");
}

#[test]
fn error_seq_255() {
    let e = usage_error(&["packet", "encode", "wake", "--seq", "255"]);
    assert!(e.contains("--seq") && e.contains("0..=254"), "{e}");
}

#[test]
fn error_led_value_count_mismatch() {
    let e = usage_error(&[
        "packet",
        "encode",
        "set-all-leds-with-16-bit-mask",
        "--mask",
        "0x0081",
        "--values",
        "ff",
    ]);
    assert!(e.contains("needs 2 value byte(s), got 1"), "{e}");
    let e = usage_error(&[
        "packet",
        "encode",
        "set-all-leds-with-8-bit-mask",
        "--mask",
        "0x01",
        "--values",
        "ff00",
    ]);
    assert!(e.contains("needs 1 value byte(s), got 2"), "{e}");
}

#[test]
fn error_other_usage_mistakes() {
    let e = usage_error(&["packet", "encode", "wake", "--speed", "1"]);
    assert!(e.contains("takes no parameters"), "{e}");
    let e = usage_error(&["packet", "encode", "play-animation", "--id", "70000"]);
    assert!(e.contains("--id") && e.contains("out of range"), "{e}");
    let e = usage_error(&["packet", "encode", "perform-leg-action", "--action", "fly"]);
    assert!(e.contains("tripod"), "{e}");
    let e = usage_error(&["packet", "encode", "play-animation", "10"]);
    assert!(e.contains("unexpected argument"), "{e}");
    let e = usage_error(&["packet", "decode", &format!("{WAKE} {WAKE}")]);
    assert!(e.contains("--stream"), "{e}");
    let e = usage_error(&["packet", "decode", "--sensor-mask", "zz", WAKE]);
    assert!(e.contains("--sensor-mask"), "{e}");
}

// --- list -------------------------------------------------------------------------------------

#[test]
fn list_shows_every_command_and_notification() {
    let out = ok(&["packet", "list"]);
    let commands = droidctl::protocol::v2::catalog::commands();
    let notifications = droidctl::protocol::v2::catalog::notifications();
    assert_eq!(
        out.lines().count(),
        2 + commands.len() + notifications.len()
    );
    assert!(out.contains("16/07  drive-with-heading"), "{out}");
    assert!(
        out.contains("--heading <u16 heading in degrees 0..=359>"),
        "{out}"
    );
    assert!(out.contains("18/12  collision-detected"), "{out}");
    let filtered = ok(&["packet", "list", "leg"]);
    assert!(
        filtered
            .lines()
            .all(|l| l.ends_with(':') || l.contains("leg")),
        "{filtered}"
    );
    assert!(filtered.contains("perform-leg-action"));
}
