//! `droidctl packet` for every protocol family: Sphero API v1 and RSRCP next to v2, the
//! `--protocol` / `--from` options and the detection of the family by its SOP byte. Run as the
//! built binary.

use droidctl::hex;
use droidctl::protocol::rsrcp;
use droidctl::protocol::v1::{self, AsyncPacket, CommandPacket, Mrsp, Packet, Response};
use serde_json::{Value, json};

use crate::common::cli;
use cli::{droidctl, stderr, stdout};

/// Run `packet ARGS`, expect `status` and no stderr; return stdout.
fn packet_with(args: &[&str], status: i32) -> String {
    let mut full = vec!["packet"];
    full.extend_from_slice(args);
    let o = droidctl(&full);
    assert_eq!(
        o.status.code(),
        Some(status),
        "{args:?}: stdout {} stderr {}",
        stdout(&o),
        stderr(&o)
    );
    assert_eq!(stderr(&o), "", "{args:?}");
    stdout(&o)
}

fn packet(args: &[&str]) -> String {
    packet_with(args, 0)
}

fn json_lines(text: &str) -> Vec<Value> {
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l:?}: {e}")))
        .collect()
}

fn keys(v: &Value) -> Vec<&str> {
    v.as_object()
        .map(|o| o.keys().map(String::as_str).collect())
        .unwrap_or_default()
}

/// Exit status 2, exactly one line on stderr, nothing on stdout, no panic.
fn usage_error(args: &[&str]) -> String {
    let mut full = vec!["packet"];
    full.extend_from_slice(args);
    cli::usage_error(&full)
}

fn wire(p: Packet) -> String {
    hex::spaced(&p.encode().expect("frameable"))
}

// vectors.md
const PING: &str = "FF FF 00 01 52 01 AB";
const ROLL: &str = "FF FF 02 30 00 05 80 00 5A 01 ED";
const V2_WAKE: &str = "8D 0A 13 0D 00 D5 D8";
const HANDSHAKE: &str = "7E 01 00 0A 7F";
/// Frame 1234: motors 1.25 / 0.80 rad/s, poti 128, buttons center and left (EFS 0x4300).
const FRAME: &str = "7E 00 04 D2 43 00 00 7D 00 50 80 C0 7F";

/// The keys of a v1 packet's JSON object, exactly and in order.
const V1_KEYS: [&str; 11] = [
    "kind",
    "did",
    "cid",
    "seq",
    "mrsp",
    "mrsp_name",
    "id_code",
    "data",
    "checksum_ok",
    "command",
    "fields",
];

// --- v1 encode --------------------------------------------------------------------------------

#[test]
fn v1_encode_golden_vectors() {
    let roll = packet(&[
        "encode",
        "--protocol",
        "v1",
        "roll",
        "--speed",
        "128",
        "--heading",
        "90",
    ]);
    assert_eq!(roll, format!("{ROLL}\n"), "state defaults to go");
    let ping = packet(&["encode", "--protocol", "v1", "ping", "--seq", "0x52"]);
    assert_eq!(ping, format!("{PING}\n"));
    // --protocol may also follow the name, among the parameters.
    let after = packet(&["encode", "ping", "--protocol", "v1", "--seq=82"]);
    assert_eq!(after, format!("{PING}\n"));
    let raw = packet(&[
        "encode",
        "--protocol",
        "v1",
        "raw",
        "--did",
        "2",
        "--cid",
        "0x30",
        "--data",
        "8000 5a01",
    ]);
    assert_eq!(raw, format!("{ROLL}\n"));
}

#[test]
fn v1_encode_header_options_clear_sop2_bits() {
    let enc = |extra: &[&str]| {
        let mut args = vec!["encode", "--protocol", "v1", "ping", "--seq", "0x52"];
        args.extend_from_slice(extra);
        packet(&args).trim_end().to_string()
    };
    let expect = |answer, reset| {
        wire(Packet::Command(
            CommandPacket::new(0, 1, 0x52, vec![]).with_options(answer, reset),
        ))
    };
    assert_eq!(enc(&["--no-response"]), expect(false, true));
    assert_eq!(enc(&["--no-reset-timeout"]), expect(true, false));
    assert_eq!(
        enc(&["--no-response", "--no-reset-timeout"]),
        expect(false, false)
    );
    assert!(enc(&["--no-response"]).starts_with("FF FE 00 01 52"));
    // The options show in the decoded SOP2 line.
    let out = packet(&["decode", &enc(&["--no-response"])]);
    assert!(out.contains("sop2      0xFE reset_timeout\n"), "{out}");
    let out = packet(&["decode", &enc(&["--no-response", "--no-reset-timeout"])]);
    assert!(out.contains("sop2      0xFC (none)\n"), "{out}");
}

// --- v1 decode --------------------------------------------------------------------------------

#[test]
fn v1_decode_golden_roll_human() {
    let out = packet(&["decode", "--protocol", "v1", ROLL]);
    assert_eq!(
        out.lines().collect::<Vec<_>>(),
        [
            "wire      FF FF 02 30 00 05 80 00 5A 01 ED",
            "sop2      0xFF answer | reset_timeout",
            "device    sphero (0x02)",
            "command   roll (0x30)",
            "seq       0",
            "data      80 00 5A 01",
            "  speed   128",
            "  heading 90",
            "  state   go (1)",
            "checksum  0xED ok",
        ]
    );
    let out = packet(&["decode", "--protocol", "v1", PING]);
    assert!(out.contains("device    core (0x00)\n"), "{out}");
    assert!(out.contains("command   ping (0x01)\n"), "{out}");
    assert!(out.contains("seq       82\n"), "{out}");
    assert!(out.contains("checksum  0xAB ok\n"), "{out}");
}

#[test]
fn v1_decode_golden_json_has_exactly_the_keys() {
    let v = json_lines(&packet(&["decode", "--protocol", "v1", "--json", ROLL]));
    assert_eq!(v.len(), 1);
    assert_eq!(keys(&v[0]), V1_KEYS);
    assert_eq!(
        v[0],
        json!({
            "kind": "command", "did": 2, "cid": 0x30, "seq": 0, "mrsp": null,
            "mrsp_name": null, "id_code": null, "data": "80005a01", "checksum_ok": true,
            "command": "roll", "fields": {"speed": 128, "heading": 90, "state": "go"}
        })
    );
    let v = &json_lines(&packet(&["decode", "--json", PING]))[0];
    assert_eq!(keys(v), V1_KEYS);
    assert_eq!(
        (&v["command"], &v["seq"], &v["data"], &v["fields"]),
        (&json!("ping"), &json!(0x52), &json!(""), &json!({}))
    );
}

#[test]
fn v1_from_droid_response() {
    let resp = wire(Packet::Response(Response {
        mrsp: Mrsp::Ok,
        seq: 3,
        data: vec![10, 20, 30],
    }));
    let out = packet(&["decode", "--from", "droid", &resp]);
    assert!(out.contains("sop2      0xFF response\n"), "{out}");
    assert!(out.contains("response  unknown command"), "{out}");
    assert!(out.contains("seq       3\n"), "{out}");
    assert!(
        out.contains("mrsp      0x00 ok (command succeeded)\n"),
        "{out}"
    );
    assert!(out.contains("data      0A 14 1E\n"), "{out}");

    // --request names the command the response answers, which decodes its payload.
    let v = &json_lines(&packet(&[
        "decode",
        "--from",
        "droid",
        "--request",
        "get-rgb-led",
        "--json",
        &resp,
    ]))[0];
    assert_eq!(keys(v), V1_KEYS);
    assert_eq!(
        *v,
        json!({
            "kind": "response", "did": null, "cid": null, "seq": 3, "mrsp": 0,
            "mrsp_name": "ok", "id_code": null, "data": "0a141e", "checksum_ok": true,
            "command": "get-rgb-led", "fields": {"red": 10, "green": 20, "blue": 30}
        })
    );

    // An error response carries its MRSP name.
    let err = wire(Packet::Response(Response {
        mrsp: Mrsp::from_byte(0x04),
        seq: 9,
        data: vec![],
    }));
    let v = &json_lines(&packet(&["decode", "--from", "droid", "--json", &err]))[0];
    assert_eq!(
        (&v["mrsp"], &v["mrsp_name"]),
        (&json!(4), &json!("unknown_command"))
    );
}

#[test]
fn v1_from_droid_async_sensor_data() {
    // Pitch, roll, yaw (MASK 0x00070000), one frame: 10, -10, 90 degrees.
    let data = vec![0x00, 0x0A, 0xFF, 0xF6, 0x00, 0x5A];
    let sensor = wire(Packet::Async(AsyncPacket::new(0x03, data)));
    assert_eq!(sensor, "FF FE 03 00 07 00 0A FF F6 00 5A 9C");

    // Without the masks: the raw values.
    let v = &json_lines(&packet(&["decode", "--from", "droid", "--json", &sensor]))[0];
    assert_eq!(keys(v), V1_KEYS);
    assert_eq!(v["kind"], "async");
    assert_eq!(v["id_code"], 3);
    assert_eq!(v["command"], "sensor-data-streaming");
    assert_eq!(v["fields"], json!({"values": [10, -10, 90]}));
    assert!(v["did"].is_null() && v["seq"].is_null() && v["mrsp"].is_null());

    // With them: named and scaled.
    let args = [
        "decode",
        "--from",
        "droid",
        "--sensor-mask",
        "0x00070000",
        "--json",
        &sensor,
    ];
    let v = &json_lines(&packet(&args))[0];
    assert_eq!(
        v["fields"],
        json!({"pitch": 10.0, "roll": -10.0, "yaw": 90.0})
    );

    // MASK2 after MASK: yaw, then odometer x/y in cm.
    let args = [
        "decode",
        "--from",
        "droid",
        "--sensor-mask",
        "0x00010000",
        "--mask2",
        "0x0C000000",
        "--json",
        &sensor,
    ];
    let v = &json_lines(&packet(&args))[0];
    assert_eq!(
        v["fields"],
        json!({"yaw": 10.0, "locator_x": -10.0, "locator_y": 90.0})
    );

    // Two frames of yaw (M = 2): one list per name.
    let args = [
        "decode",
        "--from",
        "droid",
        "--sensor-mask",
        "0x00010000",
        "--frames",
        "2",
        "--json",
        "FF FE 03 00 05 00 0A 00 14 D9",
    ];
    let v = &json_lines(&packet(&args))[0];
    assert_eq!(v["checksum_ok"], true);
    assert_eq!(v["fields"], json!({"yaw": [10.0, 20.0]}));

    let out = packet(&[
        "decode",
        "--from",
        "droid",
        "--sensor-mask",
        "0x00070000",
        &sensor,
    ]);
    assert!(
        out.contains("async     sensor-data-streaming (id 0x03)\n"),
        "{out}"
    );
    assert!(out.contains("  pitch   10.0\n"), "{out}");
    assert!(out.contains("  yaw     90.0\n"), "{out}");
}

#[test]
fn v1_host_and_droid_read_the_same_bytes_differently() {
    // A ping with SEQ 2 is, byte for byte, also a valid response (MRSP 00, SEQ 01, one data
    // byte 01): only --from tells them apart.
    let bytes = "FF FF 00 01 02 01 FB";
    let host = &json_lines(&packet(&["decode", "--json", bytes]))[0];
    let droid = &json_lines(&packet(&["decode", "--from", "droid", "--json", bytes]))[0];
    assert_eq!(
        (&host["kind"], &host["command"], &host["seq"]),
        (&json!("command"), &json!("ping"), &json!(2))
    );
    assert_eq!(
        (
            &droid["kind"],
            &droid["mrsp_name"],
            &droid["seq"],
            &droid["data"]
        ),
        (&json!("response"), &json!("ok"), &json!(1), &json!("01"))
    );
    // --from host is the default.
    assert_eq!(
        packet(&["decode", "--from", "host", bytes]),
        packet(&["decode", bytes])
    );

    // A response read as a command does not fit: one error, a hint about --from, exit 1.
    let out = packet_with(&["decode", "FF FF 00 05 01 F9"], 1);
    assert!(
        out.starts_with("decode error: truncated at offset 0"),
        "{out}"
    );
    assert!(out.contains("--from droid"), "{out}");
    let out = packet(&["decode", "--from", "droid", "FF FF 00 05 01 F9"]);
    assert!(out.contains("response"), "{out}");
}

#[test]
fn v1_stream_with_garbage() {
    let bad_roll = "FF FF 02 30 00 05 80 00 5A 01 EE";
    let stream = format!("00 {PING} 12 {bad_roll} {ROLL} FF");
    let v = json_lines(&packet(&["decode", "--stream", "--json", &stream]));
    let kinds: Vec<&str> = v
        .iter()
        .map(|o| {
            o.get("error")
                .and_then(Value::as_str)
                .or_else(|| o["command"].as_str())
                .unwrap_or("?")
        })
        .collect();
    assert_eq!(
        kinds,
        [
            "garbage",
            "ping",
            "garbage",
            "bad_checksum",
            "roll",
            "truncated"
        ]
    );
    let offsets: Vec<u64> = v.iter().filter_map(|o| o["offset"].as_u64()).collect();
    assert_eq!(offsets, [0, 8, 9, 31]);
    for p in [&v[1], &v[4]] {
        assert_eq!(keys(p), V1_KEYS);
        assert_eq!(p["checksum_ok"], true);
    }

    let out = packet(&["decode", "--stream", &stream]);
    assert!(
        out.starts_with("decode error: garbage at offset 0: 1 byte(s) outside any packet\n"),
        "{out}"
    );
    assert!(out.contains("command   ping (0x01)"), "{out}");
    assert!(
        out.contains("decode error: bad_checksum at offset 9"),
        "{out}"
    );
    assert!(out.contains("command   roll (0x30)"), "{out}");
}

#[test]
fn v1_bad_checksum_single_packet_is_shown_with_exit_1() {
    let bad = "FF FF 02 30 00 05 80 00 5A 01 EE";
    let out = packet_with(&["decode", bad], 1);
    assert!(out.starts_with(&format!("wire      {bad}\n")), "{out}");
    assert!(out.contains("command   roll (0x30)"), "{out}");
    assert!(
        out.ends_with("checksum  BAD (the packet's checksum does not match; 0xED expected)\n"),
        "{out}"
    );
    let v = json_lines(&packet_with(&["decode", "--json", bad], 1));
    assert_eq!(v.len(), 1);
    assert_eq!(keys(&v[0]), V1_KEYS);
    assert_eq!(v[0]["checksum_ok"], false);
    assert_eq!(v[0]["command"], "roll");

    // Same for an async message.
    let v = json_lines(&packet_with(
        &["decode", "--from", "droid", "--json", "FF FE 05 00 01 FA"],
        1,
    ));
    assert_eq!(
        (&v[0]["command"], &v[0]["checksum_ok"]),
        (&json!("pre-sleep-warning"), &json!(false))
    );
}

// --- detection --------------------------------------------------------------------------------

#[test]
fn the_first_sop_byte_picks_the_family() {
    // 8D: v2.
    let v = &json_lines(&packet(&["decode", "--json", V2_WAKE]))[0];
    assert_eq!((&v["command"], &v["flags"]), (&json!("wake"), &json!(0x0A)));
    // FF: v1.
    let v = &json_lines(&packet(&["decode", "--json", ROLL]))[0];
    assert_eq!(keys(v), V1_KEYS);
    // 7E: RSRCP.
    let v = &json_lines(&packet(&["decode", "--json", HANDSHAKE]))[0];
    assert_eq!(v["kind"], "handshake");

    // Whichever comes first, after garbage.
    let v = json_lines(&packet(&[
        "decode",
        "--stream",
        "--json",
        &format!("01 02 {PING} 8D"),
    ]));
    assert_eq!(v[1]["command"], "ping");
    assert_eq!(keys(&v[1]), V1_KEYS);
    let v = json_lines(&packet(&[
        "decode",
        "--stream",
        "--json",
        &format!("00 {HANDSHAKE} {ROLL}"),
    ]));
    assert_eq!(v[1]["kind"], "handshake");
    let v = json_lines(&packet(&[
        "decode",
        "--stream",
        "--json",
        &format!("00 {V2_WAKE} {ROLL}"),
    ]));
    assert_eq!(v[1]["command"], "wake");
    assert!(v[1].get("flags").is_some(), "read as v2: {}", v[1]);

    // --protocol overrides: the v1 bytes are garbage to v2.
    let v = json_lines(&packet_with(
        &["decode", "--protocol", "v2", "--json", PING],
        1,
    ));
    assert_eq!(v[0]["error"], "garbage");
    // And a v2 packet is nothing to v1.
    let out = packet_with(&["decode", "--protocol", "V1", V2_WAKE], 1);
    assert!(out.starts_with("decode error: garbage"), "{out}");
}

// --- RSRCP ------------------------------------------------------------------------------------

#[test]
fn rsrcp_handshake_and_frame() {
    assert_eq!(
        packet(&["decode", HANDSHAKE]),
        "handshake v1 (1.0.0) msdt 10 ms\n"
    );
    assert_eq!(
        packet(&["decode", "--protocol", "rsrcp", FRAME]),
        "frame 1234 motors L 1.25 R 0.80 rad/s poti 128 buttons center,left\n"
    );
    let v = &json_lines(&packet(&["decode", "--json", FRAME]))[0];
    assert_eq!(keys(v), rsrcp::JSON_KEYS);
    assert_eq!(
        *v,
        json!({
            "kind": "frame", "version": null, "msdt_ms": null, "frame_id": 1234,
            "efs": 0x4300, "features": ["motors", "poti", "buttons"],
            "motor_left_rad_s": 1.25, "motor_right_rad_s": 0.8, "poti": 128,
            "buttons": ["center", "left"], "leds": null, "piezo_on": null, "piezo_hz": null,
            "error": null, "offset": null, "detail": null
        })
    );
    let v = &json_lines(&packet(&["decode", "--json", HANDSHAKE]))[0];
    assert_eq!(keys(v), rsrcp::JSON_KEYS);
    assert_eq!((&v["version"], &v["msdt_ms"]), (&json!(1), &json!(10)));
    assert!(v["frame_id"].is_null() && v["error"].is_null());
}

#[test]
fn rsrcp_encode_builds_what_decode_reads() {
    let built = packet(&[
        "encode",
        "--protocol",
        "rsrcp",
        "frame",
        "--frame-id",
        "1234",
        "--motors",
        "1.25,0.8",
        "--poti",
        "128",
        "--buttons",
        "center,left",
    ]);
    assert_eq!(built, format!("{FRAME}\n"));
    let built = packet(&["encode", "--protocol", "rsrcp", "handshake"]);
    assert_eq!(built, format!("{HANDSHAKE}\n"));

    let full = packet(&[
        "encode",
        "--protocol",
        "rsrcp",
        "frame",
        "--frame-id",
        "0xFFFFFF",
        "--leds",
        "front_left_headlight|back_left_blinker",
        "--piezo",
        "440",
    ]);
    let v = &json_lines(&packet(&["decode", "--json", full.trim_end()]))[0];
    assert_eq!(v["frame_id"], 0xFF_FFFF);
    assert_eq!(
        v["leds"],
        json!(["front_left_headlight", "back_left_blinker"])
    );
    assert_eq!(
        (&v["piezo_on"], &v["piezo_hz"]),
        (&json!(true), &json!(440))
    );
}

#[test]
fn rsrcp_stream() {
    let stream = format!("00 {HANDSHAKE} {FRAME} 7E 00");
    let v = json_lines(&packet(&["decode", "--stream", "--json", &stream]));
    let kinds: Vec<&str> = v
        .iter()
        .map(|o| {
            o["error"]
                .as_str()
                .or_else(|| o["kind"].as_str())
                .unwrap_or("?")
        })
        .collect();
    assert_eq!(kinds, ["garbage", "handshake", "frame", "truncated"]);
    assert_eq!(v[0]["offset"], 0);
    assert_eq!(v[3]["offset"], 19);
    for o in &v {
        assert_eq!(keys(o), rsrcp::JSON_KEYS);
    }
    let out = packet(&["decode", "--stream", &stream]);
    assert_eq!(
        out.lines().collect::<Vec<_>>(),
        [
            "decode error: garbage at offset 0: 1 byte(s) outside any frame",
            "handshake v1 (1.0.0) msdt 10 ms",
            "frame 1234 motors L 1.25 R 0.80 rad/s poti 128 buttons center,left",
            "decode error: truncated at offset 19: stream ended 2 byte(s) into a frame or handshake of 5",
        ]
    );
}

#[test]
fn rsrcp_unsized_feature_and_truncated_exit_1() {
    // EFS 0x6300: motors, then the gyro, whose size is not defined.
    let unsized_frame = "7E 00 00 01 63 00 00 7D 00 50 11 22 7F";
    let v = json_lines(&packet_with(&["decode", "--json", unsized_frame], 1));
    assert_eq!(v.len(), 1);
    assert_eq!(v[0]["error"], "unsized_feature");
    assert_eq!(v[0]["frame_id"], 1);
    assert_eq!(v[0]["motor_left_rad_s"], 1.25);
    assert_eq!(
        v[0]["features"],
        json!(["motors", "gyro", "poti", "buttons"])
    );
    let out = packet_with(&["decode", unsized_frame], 1);
    assert!(
        out.starts_with("decode error: unsized_feature at offset 0"),
        "{out}"
    );
    assert!(out.contains("gyro"), "{out}");

    let v = json_lines(&packet_with(&["decode", "--json", "7E 00 00 01 43 00"], 1));
    assert_eq!(v[0]["error"], "truncated");
    let out = packet_with(&["decode", "7E 00 00 01 43 00"], 1);
    assert_eq!(
        out,
        "decode error: truncated at offset 0: 6 byte(s), EFS 0x4300 implies 13\n"
    );
    // A bad EOP where the EFS puts the end.
    let v = json_lines(&packet_with(
        &["decode", "--json", "7E 00 04 D2 43 00 00 7D 00 50 80 C0 00"],
        1,
    ));
    assert_eq!(v[0]["error"], "bad_eop");
}

// --- list -------------------------------------------------------------------------------------

#[test]
fn list_per_family() {
    let v1_out = packet(&["list", "--protocol", "v1"]);
    assert_eq!(
        v1_out.lines().count(),
        2 + v1::catalog::commands().len() + v1::catalog::async_messages().len()
    );
    assert!(v1_out.contains("  02/30  roll "), "{v1_out}");
    assert!(v1_out.contains("--speed <u8"), "{v1_out}");
    assert!(v1_out.contains("  07     collision-detected "), "{v1_out}");
    let filtered = packet(&["list", "--protocol", "v1", "rgb"]);
    assert!(
        filtered
            .lines()
            .all(|l| l.ends_with(':') || l.contains("rgb")),
        "{filtered}"
    );

    let r = packet(&["list", "--protocol", "rsrcp"]);
    assert!(r.contains("  0x4000  motors    4 "), "{r}");
    assert!(r.contains("  0x0200  poti      1 "), "{r}");
    assert!(r.contains("  0x2000  gyro      -  size not defined"), "{r}");
    assert!(r.contains("0x6B2F  velocity"), "{r}");
    assert!(r.contains("0x3F4A  steering"), "{r}");

    let all = packet(&["list", "--protocol", "all"]);
    for header in ["== v2 ==", "== v1 ==", "== rsrcp =="] {
        assert!(all.contains(header), "{header}");
    }
    assert!(all.contains(&packet(&["list"])));
    assert!(all.contains(&v1_out));
}

// --- usage errors -----------------------------------------------------------------------------

#[test]
fn usage_errors_are_one_line_exit_2() {
    let e = usage_error(&["decode", "--protocol", "v3", V2_WAKE]);
    assert!(e.contains("unknown protocol \"v3\""), "{e}");
    let e = usage_error(&["encode", "--protocol", "sphero", "ping"]);
    assert!(e.contains("unknown protocol"), "{e}");
    let e = usage_error(&["list", "--protocol", "robi"]);
    assert!(e.contains("unknown protocol"), "{e}");

    let e = usage_error(&["encode", "--protocol", "rsrcp", "drive", "--speed", "1"]);
    assert!(e.contains("RSRCP has no command"), "{e}");
    assert!(e.contains("velocity") && e.contains("steering"), "{e}");

    let e = usage_error(&["encode", "--protocol", "v1", "rol", "--speed", "1"]);
    assert!(
        e.contains("unknown command \"rol\"; did you mean roll"),
        "{e}"
    );
    let e = usage_error(&["encode", "--protocol", "v1", "set-rgb", "--red", "1"]);
    assert!(
        e.contains("did you mean") && e.contains("set-rgb-led"),
        "{e}"
    );
    let e = usage_error(&["encode", "--protocol", "v1", "roll", "--heading", "90"]);
    assert!(e.contains("needs --speed"), "{e}");
    let e = usage_error(&["encode", "--protocol", "v1", "ping", "--seq", "256"]);
    assert!(e.contains("--seq"), "{e}");
    let e = usage_error(&["encode", "--protocol", "v1", "ping", "--tid", "1"]);
    assert!(e.contains("no target or source"), "{e}");

    let e = usage_error(&["decode", "--from", "robot", PING]);
    assert!(e.contains("--from") && e.contains("host or droid"), "{e}");
    let e = usage_error(&["decode", "--mask2", "1", V2_WAKE]);
    assert!(
        e.contains("--mask2 applies to v1") && e.contains("--protocol"),
        "{e}"
    );
    let e = usage_error(&["decode", "--sensor-mask", "1", "--ext-mask", "1", PING]);
    assert!(e.contains("--ext-mask applies to v2"), "{e}");
    let e = usage_error(&["decode", "--sensor-mask", "1", HANDSHAKE]);
    assert!(e.contains("--sensor-mask"), "{e}");
    let e = usage_error(&["decode", "--frames", "2", PING]);
    assert!(e.contains("--frames needs"), "{e}");
    let e = usage_error(&["decode", "--request", "get-rgb", PING]);
    assert!(e.contains("--request") && e.contains("get-rgb-led"), "{e}");
    let e = usage_error(&["decode", &format!("{PING} {PING}")]);
    assert!(e.contains("--stream"), "{e}");
    let e = usage_error(&["decode", &format!("{HANDSHAKE} {FRAME}")]);
    assert!(e.contains("--stream"), "{e}");
    let e = usage_error(&["decode", "--protocol", "rsrcp", ""]);
    assert!(e.contains("no bytes"), "{e}");
    let e = usage_error(&[
        "encode",
        "--protocol",
        "rsrcp",
        "frame",
        "--motors",
        "301,0",
    ]);
    assert!(e.contains("--motors"), "{e}");
}
