//! A virtual droid's trace (`sim --bluez --trace --json`) carries, for every packet, exactly
//! the object `droidctl packet decode --json` prints: both come from the family's reader.

use droidctl::family::robi::gatt::{ROBI_FRAMES, ROBI_HANDSHAKE, ROBI_VELOCITY};
use droidctl::family::v1::gatt::{V1_COMMANDS, V1_RESPONSES};
use droidctl::family::v2::gatt::V2_API;
use droidctl::hex;
use droidctl::model::Model;
use droidctl::protocol::v2::wire::DriveFlags;
use droidctl::protocol::{v1, v2};
use droidctl::sim::trace::{PacketTracer, TraceDir};
use droidctl::units::Heading;
use serde_json::Value;

/// What `droidctl packet decode --json --protocol P [--from SIDE] HEX` prints.
fn decoded(protocol: &str, from: Option<&str>, wire: &[u8]) -> Value {
    let cmd = droidctl::cli::packet::PacketCmd::Decode {
        hex: vec![hex::spaced(wire)],
        file: None,
        btsnoop: None,
        handle: Vec::new(),
        summary: false,
        protocol: Some(protocol.into()),
        from: from.map(String::from),
        stream: false,
        json: true,
        sensor_mask: None,
        ext_mask: None,
        mask2: None,
        frames: None,
        request: None,
    };
    let mut out = Vec::new();
    droidctl::cli::packet::run(cmd, &mut out).unwrap();
    serde_json::from_slice(&out).unwrap()
}

/// The trace's `packet` is exactly the object `packet decode --json` prints, for every
/// family and both directions.
#[test]
fn packets_are_what_packet_decode_json_prints() {
    use droidctl::protocol::rsrcp::{Frame, Handshake};
    let mut t = PacketTracer::new(Model::R2D2);
    let cmd = v2::cmd::drive_with_heading(60, Heading::default(), DriveFlags::empty()).to_packet(3);
    let resp = v2::Packet::response_to(&cmd, v2::ErrorCode::Success, vec![]);
    let note = v2::Packet::notification(0x13, 0x19, vec![]);
    for (dir, wire) in [
        (TraceDir::In, cmd.encode()),
        (TraceDir::Out, resp.encode()),
        (TraceDir::Out, note.encode()),
    ] {
        let r = match dir {
            TraceDir::In => t.write(V2_API, &wire),
            TraceDir::Out => t.notify(V2_API, &wire),
        };
        assert_eq!(r[0].packet_value(), decoded("v2", None, &wire));
    }
    let mut t = PacketTracer::new(Model::BB8);
    let c = v1::cmd::ping().to_packet(9);
    let wire_in = v1::Packet::Command(c.clone()).encode().unwrap();
    let wire_out = v1::Packet::Response(v1::Response::to(&c, v1::Mrsp::Ok, vec![]))
        .encode()
        .unwrap();
    let wire_async = v1::Packet::Async(v1::AsyncPacket::new(0x05, vec![]))
        .encode()
        .unwrap();
    assert_eq!(
        t.write(V1_COMMANDS, &wire_in)[0].packet_value(),
        decoded("v1", Some("host"), &wire_in)
    );
    assert_eq!(
        t.notify(V1_RESPONSES, &wire_out)[0].packet_value(),
        decoded("v1", Some("droid"), &wire_out)
    );
    assert_eq!(
        t.notify(V1_RESPONSES, &wire_async)[0].packet_value(),
        decoded("v1", Some("droid"), &wire_async)
    );
    let mut t = PacketTracer::new(Model::Robi42);
    let hs = Handshake {
        version: 1,
        msdt_ms: 10,
    }
    .encode()
    .to_vec();
    assert_eq!(
        t.read(ROBI_HANDSHAKE, &hs)[0].packet_value(),
        decoded("rsrcp", None, &hs)
    );
    let frame = Frame::default().encode();
    assert_eq!(
        t.notify(ROBI_FRAMES, &frame)[0].packet_value(),
        decoded("rsrcp", None, &frame)
    );
    let w = t.write(ROBI_VELOCITY, &[200]);
    assert_eq!(w[0].packet_value()["kind"], "gatt-write");
    assert_eq!(w[0].packet_value()["hex"], "c8");
}

/// Issue 32: spherov2's v1 Roll carries a fifth byte, its reverse flag (and it turns the LEDs
/// off with a 3-byte Set RGB LED): the trace decodes both with their fields, as `packet
/// decode` does, instead of leaving `fields` empty.
#[test]
fn spherov2s_roll_and_led_are_traced_with_their_fields() {
    let mut t = PacketTracer::new(Model::Ollie);
    let frame = |cid: u8, seq: u8, data: Vec<u8>| {
        v1::Packet::Command(v1::CommandPacket::new(0x02, cid, seq, data))
            .encode()
            .unwrap()
    };
    // spherov2 `Sphero.roll(toy, 60, 90, RollModes.GO, ReverseFlags.OFF)`.
    let roll = frame(0x30, 6, vec![60, 0, 90, 1, 0]);
    let traced = t.write(V1_COMMANDS, &roll)[0].packet_value();
    assert_eq!(traced, decoded("v1", Some("host"), &roll));
    assert_eq!(traced["command"], "roll");
    assert_eq!(
        traced["fields"],
        serde_json::json!({"speed": 60, "heading": 90, "state": "go", "reverse": false}),
        "{traced}"
    );
    let back = frame(0x30, 7, vec![60, 0, 90, 1, 1]);
    assert_eq!(
        t.write(V1_COMMANDS, &back)[0].packet_value()["fields"]["reverse"],
        true
    );
    let leds_off = frame(0x20, 8, vec![0, 0, 0]);
    let traced = t.write(V1_COMMANDS, &leds_off)[0].packet_value();
    assert_eq!(
        traced["fields"],
        serde_json::json!({"red": 0, "green": 0, "blue": 0}),
        "{traced}"
    );
    // Other wrong lengths still decode to nothing.
    let short = frame(0x30, 9, vec![60, 0, 90]);
    assert!(t.write(V1_COMMANDS, &short)[0].packet_value()["fields"].is_null());
}
