//! Golden vectors and per-entry checks of the Sphero API v2 core: every vector of
//! `vectors.md` in both directions, every typed command constructor, every response schema and
//! every notification of the catalogue, the 18-byte collision and sensor streaming with masks.

use droidctl::hex;
use droidctl::protocol::notify::RobotEvent;
use droidctl::protocol::v2::catalog::{self, Command, cmd};
use droidctl::protocol::v2::packet::{self, BodyError, parse_body};
use droidctl::protocol::v2::sensor::{self, StreamingConfig, decode_sample, mask};
use droidctl::protocol::v2::types::{
    Char, FadeOverride, FrameList, FrameRotation, Palette, ScrollText, StreamSlots, StreamWidth,
    U16List,
};
use droidctl::protocol::v2::wire::*;
use droidctl::protocol::v2::{
    Collision, Decoder, ErrorCode, ErrorKind, Fields, Flags, Kind, Notification, Packet, Value,
    describe,
};
use droidctl::units::{HeadAngle, Heading};
use std::collections::BTreeSet;

fn h(s: &str) -> Vec<u8> {
    hex::parse(s).unwrap()
}

fn int(v: i64) -> Value {
    Value::Int(v)
}

fn float(v: f64) -> Value {
    Value::Float(v)
}

fn boolean(v: bool) -> Value {
    Value::Bool(v)
}

fn en(value: u64, name: &'static str) -> Value {
    Value::Enum {
        value,
        name: Some(name),
    }
}

fn hexv(value: u64, width: u8) -> Value {
    Value::Hex { value, width }
}

fn text(s: &str) -> Value {
    Value::Text(s.to_string())
}

fn bytes(b: &[u8]) -> Value {
    Value::Bytes(b.to_vec())
}

fn f32s(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_be_bytes()).collect()
}

fn heading(deg: u16) -> Heading {
    Heading::new(deg).unwrap()
}

fn head(deg: f32) -> HeadAngle {
    HeadAngle::new(deg).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Golden vectors (vectors.md, "Sphero v2").
// ---------------------------------------------------------------------------------------------

struct Vector {
    what: &'static str,
    packet: Packet,
    wire: Vec<u8>,
}

fn golden() -> Vec<Vector> {
    vec![
        Vector {
            what: "wake",
            packet: Packet {
                flags: Flags::from_bits_retain(0x0A),
                ext_flags: None,
                tid: None,
                sid: None,
                did: 0x13,
                cid: 0x0D,
                seq: 0x00,
                err: None,
                data: vec![],
            },
            wire: h("8D 0A 13 0D 00 D5 D8"),
        },
        Vector {
            what: "wake response",
            packet: Packet {
                flags: Flags::from_bits_retain(0x09),
                ext_flags: None,
                tid: None,
                sid: None,
                did: 0x13,
                cid: 0x0D,
                seq: 0x00,
                err: Some(ErrorCode::Success),
                data: vec![],
            },
            wire: h("8D 09 13 0D 00 00 D6 D8"),
        },
        Vector {
            what: "set head position 0.5",
            packet: Packet {
                flags: Flags::from_bits_retain(0x3A),
                ext_flags: None,
                tid: Some(0x12),
                sid: Some(0x01),
                did: 0x17,
                cid: 0x0F,
                seq: 0x00,
                err: None,
                data: h("3F 00 00 00"),
            },
            wire: h("8D 3A 12 01 17 0F 00 3F 00 00 00 4D D8"),
        },
        Vector {
            what: "escaping in header and data",
            packet: Packet {
                flags: Flags::from_bits_retain(0x0A),
                ext_flags: None,
                tid: None,
                sid: None,
                did: 0x1A,
                cid: 0x0E,
                seq: 0x8D,
                err: None,
                data: h("00 AB D8"),
            },
            wire: h("8D 0A 1A 0E AB 05 00 AB 23 AB 50 BD D8"),
        },
    ]
}

#[test]
fn golden_vectors_encode() {
    for v in golden() {
        assert_eq!(v.packet.encode(), v.wire, "{}", v.what);
        // encode_into appends after what the buffer already holds.
        let mut buf = vec![0x42];
        v.packet.encode_into(&mut buf);
        assert_eq!(buf[0], 0x42, "{}", v.what);
        assert_eq!(&buf[1..], &v.wire[..], "{}", v.what);
        // The vectors' flags already agree with their fields.
        assert_eq!(v.packet.clone().normalized(), v.packet, "{}", v.what);
    }
}

#[test]
fn golden_vectors_checksums() {
    let expected = [0xD5, 0xD6, 0x4D, 0xBD];
    for (v, chk) in golden().into_iter().zip(expected) {
        assert_eq!(packet::checksum(&v.packet.body()), chk, "{}", v.what);
        // The checksum byte sits just before EOP on the wire (none of these needs escaping).
        assert_eq!(v.wire[v.wire.len() - 2], chk, "{}", v.what);
    }
}

#[test]
fn golden_vectors_bodies() {
    assert_eq!(golden()[0].packet.body(), h("0A 13 0D 00"));
    assert_eq!(golden()[1].packet.body(), h("09 13 0D 00 00"));
    assert_eq!(
        golden()[2].packet.body(),
        h("3A 12 01 17 0F 00 3F 00 00 00")
    );
    // The unescaped body holds the raw SEQ 0x8D and data 00 AB D8.
    assert_eq!(golden()[3].packet.body(), h("0A 1A 0E 8D 00 AB D8"));
}

#[test]
fn golden_vectors_decode_whole() {
    for v in golden() {
        let mut d = Decoder::new();
        let out = d.decode_all(&v.wire);
        assert_eq!(out, vec![Ok(v.packet.clone())], "{}", v.what);
        assert!(d.finish().is_empty(), "{}", v.what);
        let s = d.stats();
        assert_eq!(s.packets, 1, "{}", v.what);
        assert_eq!(s.bytes, v.wire.len() as u64, "{}", v.what);
        assert_eq!(s.skipped_bytes, 0, "{}", v.what);
        assert_eq!(s.total_errors(), 0, "{}", v.what);
        assert_eq!(d.buffered(), 0, "{}", v.what);
    }
}

#[test]
fn golden_vectors_decode_byte_at_a_time_and_split_everywhere() {
    for v in golden() {
        let mut d = Decoder::new();
        let mut out = Vec::new();
        for b in &v.wire {
            out.extend(d.feed(std::slice::from_ref(b)));
        }
        assert_eq!(out, vec![Ok(v.packet.clone())], "{} byte at a time", v.what);
        for split in 0..=v.wire.len() {
            let mut d = Decoder::new();
            let mut out: Vec<_> = d.feed(&v.wire[..split]).collect();
            out.extend(d.feed(&v.wire[split..]));
            assert_eq!(
                out,
                vec![Ok(v.packet.clone())],
                "{} split at {split}",
                v.what
            );
        }
    }
}

#[test]
fn golden_vectors_parse_body() {
    for v in golden() {
        let mut body = v.packet.body();
        body.push(packet::checksum(&body));
        assert_eq!(parse_body(&body), Ok(v.packet.clone()), "{}", v.what);
        // Break the checksum: the error carries the packet as read.
        let last = body.len() - 1;
        body[last] ^= 0x01;
        let (err, p) = parse_body(&body).unwrap_err();
        assert!(matches!(err, BodyError::BadChecksum { .. }), "{}", v.what);
        assert_eq!(p, Some(v.packet.clone()), "{}", v.what);
    }
    // Unescaped vectors: the wire between SOP and EOP is the body.
    for v in &golden()[..3] {
        assert_eq!(
            parse_body(&v.wire[1..v.wire.len() - 1]),
            Ok(v.packet.clone()),
            "{}",
            v.what
        );
    }
}

#[test]
fn golden_vectors_in_one_stream() {
    let all = golden();
    let stream: Vec<u8> = all.iter().flat_map(|v| v.wire.clone()).collect();
    let out = Decoder::new().decode_all(&stream);
    let expected: Vec<_> = all.iter().map(|v| Ok(v.packet.clone())).collect();
    assert_eq!(out, expected);
}

#[test]
fn golden_vectors_from_constructors() {
    // Wake (and droid-facts.md §2's captured frame).
    assert_eq!(cmd::wake().to_packet(0).encode(), golden()[0].wire);
    // Wake response: echo of DID/CID/SEQ with is_response | is_activity.
    let resp = Packet::response_to(&cmd::wake().to_packet(0), ErrorCode::Success, vec![]);
    assert_eq!(resp, golden()[1].packet);
    assert_eq!(resp.encode(), golden()[1].wire);
    // Set head position 0.5 degrees with TID 0x12, SID 0x01.
    let mut p = cmd::set_head_position(head(0.5)).to_packet(0);
    p.tid = Some(0x12);
    p.sid = Some(0x01);
    assert_eq!(p.normalized().encode(), golden()[2].wire);
    // Escaping: the 16-bit LED mask command with mask 0x00AB and value 0xD8, SEQ 0x8D.
    let c = cmd::set_all_leds_with_16_bit_mask(Mask(0x00AB), Bytes(vec![0xD8]));
    assert_eq!(c.to_packet(0x8D).encode(), golden()[3].wire);
}

#[test]
fn golden_vectors_describe() {
    let v = golden();
    let d = describe(&v[0].packet, None);
    assert_eq!((d.kind, d.name), (Kind::Command, Some("wake")));
    assert_eq!(d.fields, Some(vec![]));
    assert_eq!(d.problem, None);

    let d = describe(&v[1].packet, None);
    assert_eq!((d.kind, d.name), (Kind::Response, Some("wake")));
    assert_eq!(d.fields, Some(vec![]));
    assert_eq!(d.problem, None);

    let d = describe(&v[2].packet, None);
    assert_eq!((d.kind, d.name), (Kind::Command, Some("set-head-position")));
    assert_eq!(d.fields, Some(vec![("degrees", float(0.5))]));

    let d = describe(&v[3].packet, None);
    assert_eq!(
        (d.kind, d.name),
        (Kind::Command, Some("set-all-leds-with-16-bit-mask"))
    );
    assert_eq!(
        d.fields,
        Some(vec![("mask", hexv(0xAB, 2)), ("values", bytes(&[0xD8]))])
    );
}

// ---------------------------------------------------------------------------------------------
// Typed command constructors: one test each, payload bytes asserted, ids checked against the
// catalogue table by name and by id.
// ---------------------------------------------------------------------------------------------

fn check_constructor(fn_name: &str, c: Command, did: u8, cid: u8, data: &[u8]) {
    assert_eq!((c.did, c.cid), (did, cid), "{fn_name}: DID/CID");
    assert_eq!(c.data, data, "{fn_name}: payload");

    let name = fn_name.replace('_', "-");
    let def = catalog::by_name(&name).unwrap_or_else(|| panic!("{name} not in the catalogue"));
    assert_eq!((def.did, def.cid), (did, cid), "{name}: by_name ids");
    let by_id = catalog::lookup(did, cid).unwrap_or_else(|| panic!("{did:02X}/{cid:02X} unknown"));
    assert_eq!(by_id.name, name, "{name}: lookup by id");
    assert_eq!(c.def().map(|d| d.name.as_str()), Some(name.as_str()));

    // The constructor's payload fits the table's parameter schema.
    assert!(
        catalog::length_ok(def.params, c.data.len()),
        "{name}: length"
    );
    let fields = catalog::decode_fields(def.params, &c.data)
        .unwrap_or_else(|e| panic!("{name}: params do not decode: {e}"));
    let names: Vec<&str> = fields.iter().map(|(n, _)| *n).collect();
    let schema_names: Vec<&str> = def.params.iter().map(|f| f.name).collect();
    assert_eq!(names, schema_names, "{name}: field names");

    // Framed and decoded again, it is described as this command with the same fields.
    let wire = c.to_packet(7).encode();
    let out = Decoder::new().decode_all(&wire);
    let [Ok(p)] = &out[..] else {
        panic!("{name}: {out:?}")
    };
    assert_eq!((p.did, p.cid, p.seq, &p.data), (did, cid, 7, &c.data));
    assert_eq!(p.flags, Flags::DEFAULT_COMMAND);
    let d = describe(p, None);
    assert_eq!(d.kind, Kind::Command);
    assert_eq!(d.name, Some(name.as_str()));
    assert_eq!(d.fields, Some(fields), "{name}: describe");
}

macro_rules! constructors {
    ($( $f:ident ( $($arg:expr),* ) => $did:literal / $cid:literal [ $($b:expr),* $(,)? ] ; )*) => {
        mod constructors {
            use super::*;
            $(
                #[test]
                fn $f() {
                    check_constructor(stringify!($f), cmd::$f($($arg),*), $did, $cid, &[$($b),*]);
                }
            )*
        }

        /// Every constructor the module above tests.
        const CONSTRUCTORS_TESTED: &[&str] = &[$(stringify!($f)),*];
    };
}

constructors! {
    // Core (0x00)
    ping() => 0x00/0x01 [];
    get_versions() => 0x00/0x02 [];
    set_bluetooth_name(Text("R2".into())) => 0x00/0x10 [b'R', b'2', 0];
    get_bluetooth_info() => 0x00/0x11 [];
    get_power_state() => 0x00/0x20 [];
    enable_battery_changed_notify(true) => 0x00/0x21 [1];
    core_sleep(0x1234, 7, 0xABCD) => 0x00/0x22 [0x12, 0x34, 7, 0xAB, 0xCD];
    set_inactivity_timeout(300) => 0x00/0x25 [0x01, 0x2C];
    core_get_charger_state() => 0x00/0x26 [];
    get_factory_config_block_crc() => 0x00/0x27 [];
    jump_to_bootloader() => 0x00/0x30 [];
    // System info (0x11)
    get_main_app_version() => 0x11/0x00 [];
    get_bootloader_version() => 0x11/0x01 [];
    get_board_revision() => 0x11/0x03 [];
    get_mac_address() => 0x11/0x06 [];
    get_model_number() => 0x11/0x12 [];
    get_stats_id() => 0x11/0x13 [];
    get_secondary_main_app_version() => 0x11/0x17 [];
    get_processor_name() => 0x11/0x1F [];
    get_boot_reason() => 0x11/0x20 [];
    get_last_error_info() => 0x11/0x21 [];
    get_secondary_mcu_bootloader_version() => 0x11/0x24 [];
    get_three_character_sku() => 0x11/0x28 [];
    write_config_block() => 0x11/0x2B [];
    get_config_block() => 0x11/0x2C [];
    set_config_block(1, 0x0102_0304, Bytes(vec![0xAA, 0xBB])) => 0x11/0x2D [0, 0, 0, 1, 1, 2, 3, 4, 0xAA, 0xBB];
    erase_config_block(0xDEAD_BEEF) => 0x11/0x2E [0xDE, 0xAD, 0xBE, 0xEF];
    get_swd_locking_status() => 0x11/0x30 [];
    get_manufacturing_date() => 0x11/0x33 [];
    get_sku() => 0x11/0x38 [];
    get_core_up_time() => 0x11/0x39 [];
    get_event_log_status() => 0x11/0x3A [];
    get_event_log_data(16, 256) => 0x11/0x3B [0, 0, 0, 16, 0, 0, 1, 0];
    clear_event_log() => 0x11/0x3C [];
    enable_sos_message_notify(false) => 0x11/0x3D [0];
    get_sos_message() => 0x11/0x3F [];
    clear_sos_message() => 0x11/0x44 [];
    // Power (0x13)
    enter_deep_sleep(2) => 0x13/0x00 [2];
    sleep() => 0x13/0x01 [];
    get_battery_voltage() => 0x13/0x03 [];
    get_battery_state() => 0x13/0x04 [];
    enable_battery_state_changed_notify(true) => 0x13/0x05 [1];
    force_battery_refresh() => 0x13/0x0C [];
    wake() => 0x13/0x0D [];
    get_battery_percentage() => 0x13/0x10 [];
    get_battery_voltage_state() => 0x13/0x17 [];
    enable_battery_voltage_state_change_notify(true) => 0x13/0x1B [1];
    get_charger_state() => 0x13/0x1F [];
    enable_charger_state_changed_notify(false) => 0x13/0x20 [0];
    get_battery_adc_reading() => 0x13/0x22 [];
    set_battery_calibration(10, 20) => 0x13/0x23 [10, 20];
    get_battery_calibration() => 0x13/0x24 [];
    get_battery_voltage_in_volts(VoltageReadingType::Uncalibrated) => 0x13/0x25 [2];
    get_battery_voltage_state_thresholds() => 0x13/0x26 [];
    get_current_sense_amplifier_current(AmplifierId::RightMotor) => 0x13/0x27 [1];
    get_efuse_fault_status(3) => 0x13/0x28 [3];
    enable_efuse(1) => 0x13/0x2A [1];
    // Drive (0x16)
    set_raw_motors(RawMotorMode::Forward, 100, RawMotorMode::Reverse, 200) => 0x16/0x01 [1, 100, 2, 200];
    reset_yaw() => 0x16/0x06 [];
    drive_with_heading(100, heading(180), DriveFlags::empty()) => 0x16/0x07 [100, 0, 180, 0];
    generic_raw_motor(MotorIndex::Head, RawMotorMode::Forward, Bytes(vec![0x00, 0x80])) => 0x16/0x0B [2, 1, 0x00, 0x80];
    set_stabilization(StabilizationIndex::Full) => 0x16/0x0C [1];
    set_control_system_type(3, 1) => 0x16/0x0E [3, 1];
    set_pitch_torque_modification(5) => 0x16/0x0F [5];
    set_component_parameters(1, 2, F32List(vec![1.0, -2.5])) => 0x16/0x20 [1, 2, 0x3F, 0x80, 0, 0, 0xC0, 0x20, 0, 0];
    get_component_parameters(1, 2) => 0x16/0x21 [1, 2];
    set_custom_control_system_timeout(500) => 0x16/0x22 [0x01, 0xF4];
    enable_motor_stall_notify(true) => 0x16/0x25 [1];
    enable_motor_fault_notify(true) => 0x16/0x27 [1];
    get_motor_fault_state() => 0x16/0x29 [];
    // Animatronic (0x17)
    play_animation(10) => 0x17/0x05 [0, 10];
    perform_leg_action(LegAction::Tripod) => 0x17/0x0D [1];
    // Degrees as big-endian f32: 90.0 = 0x42B40000.
    set_head_position(head(90.0)) => 0x17/0x0F [0x42, 0xB4, 0x00, 0x00];
    get_head_position() => 0x17/0x14 [];
    set_leg_position(0.25) => 0x17/0x15 [0x3E, 0x80, 0, 0];
    get_leg_position() => 0x17/0x16 [];
    get_leg_action() => 0x17/0x25 [];
    enable_leg_action_notify(true) => 0x17/0x2A [1];
    stop_animation() => 0x17/0x2B [];
    enable_idle_animations(false) => 0x17/0x2C [0];
    enable_trophy_mode(true) => 0x17/0x2D [1];
    get_trophy_mode_enabled() => 0x17/0x2E [];
    enable_head_reset_to_zero_notify(true) => 0x17/0x39 [1];
    // Sensor (0x18)
    set_sensor_streaming_mask(150, 0, Mask(0x0007_E078)) => 0x18/0x00 [0x00, 0x96, 0, 0x00, 0x07, 0xE0, 0x78];
    get_sensor_streaming_mask() => 0x18/0x01 [];
    set_extended_sensor_streaming_mask(Mask(0x0380_0000)) => 0x18/0x0C [0x03, 0x80, 0, 0];
    get_extended_sensor_streaming_mask() => 0x18/0x0D [];
    enable_gyro_max_notify(true) => 0x18/0x0F [1];
    configure_collision_detection(CollisionMethod::Accelerometer, 90, 130, 90, 130, 1) => 0x18/0x11 [1, 90, 130, 90, 130, 1];
    reset_locator_x_and_y() => 0x18/0x13 [];
    enable_collision_detected_notify(true) => 0x18/0x14 [1];
    set_locator_flags(false) => 0x18/0x17 [0];
    set_accelerometer_activity_threshold(1.5) => 0x18/0x18 [0x3F, 0xC0, 0, 0];
    enable_accelerometer_activity_notify(true) => 0x18/0x19 [1];
    set_gyro_activity_threshold(-1.0) => 0x18/0x1B [0xBF, 0x80, 0, 0];
    enable_gyro_activity_notify(false) => 0x18/0x1C [0];
    get_bot_to_bot_infrared_readings() => 0x18/0x22 [];
    get_rgbc_sensor_values() => 0x18/0x23 [];
    magnetometer_calibrate_to_north() => 0x18/0x25 [];
    start_robot_to_robot_ir_broadcasting(1, 2) => 0x18/0x27 [1, 2];
    start_robot_to_robot_ir_following(3, 4) => 0x18/0x28 [3, 4];
    stop_robot_to_robot_ir_broadcasting() => 0x18/0x29 [];
    send_robot_to_robot_ir_message([1, 2, 3, 4, 5]) => 0x18/0x2A [1, 2, 3, 4, 5];
    listen_for_robot_to_robot_ir_message([0xAB, 0xCD]) => 0x18/0x2B [0xAB, 0xCD];
    get_ambient_light_sensor_value() => 0x18/0x30 [];
    stop_robot_to_robot_ir_following() => 0x18/0x32 [];
    start_robot_to_robot_ir_evading(5, 6) => 0x18/0x33 [5, 6];
    stop_robot_to_robot_ir_evading() => 0x18/0x34 [];
    enable_color_detection_notify(true, 250, 80) => 0x18/0x35 [1, 0x00, 0xFA, 80];
    get_current_detected_color_reading() => 0x18/0x37 [];
    enable_color_detection(true) => 0x18/0x38 [1];
    configure_streaming_service(1, StreamSlots(vec![(6, StreamWidth::Bits32)])) => 0x18/0x39 [1, 0, 6, 2];
    start_streaming_service(100) => 0x18/0x3A [0, 100];
    stop_streaming_service() => 0x18/0x3B [];
    clear_streaming_service() => 0x18/0x3C [];
    enable_robot_ir_message_notify(true) => 0x18/0x3E [1];
    send_infrared_message([9, 8, 7, 6, 5]) => 0x18/0x3F [9, 8, 7, 6, 5];
    enable_motor_current_notify(true) => 0x18/0x41 [1];
    get_motor_temperature(2) => 0x18/0x42 [2];
    configure_sensitivity_based_collision(1, 2, 0x0304) => 0x18/0x47 [1, 2, 3, 4];
    enable_sensitivity_based_collision_notify(true) => 0x18/0x48 [1];
    get_motor_thermal_protection_status() => 0x18/0x4B [];
    enable_motor_thermal_protection_notify(false) => 0x18/0x4C [0];
    // IO (0x1A)
    set_led([1, 2, 3, 4, 5]) => 0x1A/0x04 [1, 2, 3, 4, 5];
    play_audio_file(1915, AudioMode::Immediate) => 0x1A/0x07 [0x07, 0x7B, 0];
    set_audio_volume(200) => 0x1A/0x08 [200];
    get_audio_volume() => 0x1A/0x09 [];
    stop_all_audio() => 0x1A/0x0A [];
    set_all_leds_with_16_bit_mask(Mask(0x0080), Bytes(vec![0xFF])) => 0x1A/0x0E [0x00, 0x80, 0xFF];
    start_idle_led_animation() => 0x1A/0x19 [];
    set_all_leds_with_32_bit_mask(Mask(0x0000_0007), Bytes(vec![255, 0, 0])) => 0x1A/0x1A [0, 0, 0, 7, 255, 0, 0];
    set_all_leds_with_8_bit_mask(Mask(0x03), Bytes(vec![10, 20])) => 0x1A/0x1C [3, 10, 20];
    enable_color_tap_notify(true) => 0x1A/0x1D [1];
    // BOLT's matrix and RVR's palettes (IO 0x2D..=0x4E, spherov2 `commands/io.py`)
    set_compressed_frame_player_pixel(2, 3, 255, 0, 0) => 0x1A/0x2D [2, 3, 255, 0, 0];
    set_compressed_frame_player(Bytes(vec![1, 2, 3])) => 0x1A/0x2E [1, 2, 3];
    set_compressed_frame_player_one_color(255, 0, 0) => 0x1A/0x2F [255, 0, 0];
    save_compressed_frame_player_64_bit_frame(1, Bytes(vec![1, 2, 3, 4])) => 0x1A/0x30 [0, 1, 1, 2, 3, 4];
    save_compressed_frame_player_animation(2, 10, true, Palette(vec![[255, 0, 0], [0, 255, 0]]), FrameList(vec![1, 2]))
        => 0x1A/0x31 [2, 10, 1, 2, 255, 0, 0, 0, 255, 0, 0, 2, 0, 1, 0, 2];
    play_compressed_frame_player_animation(2) => 0x1A/0x32 [2];
    play_compressed_frame_player_frame(7) => 0x1A/0x33 [0, 7];
    get_compressed_frame_player_list_of_frames() => 0x1A/0x34 [];
    delete_all_compressed_frame_player_animations_and_frames() => 0x1A/0x35 [];
    pause_compressed_frame_player_animation() => 0x1A/0x36 [];
    resume_compressed_frame_player_animation() => 0x1A/0x37 [];
    reset_compressed_frame_player_animation() => 0x1A/0x38 [];
    override_compressed_frame_player_animation_global_settings(10, FadeOverride::NoFading) => 0x1A/0x39 [10, 1];
    set_compressed_frame_player_frame_rotation(FrameRotation::Rotate90) => 0x1A/0x3A [1];
    set_compressed_frame_player_text_scrolling(255, 0, 0, 7, true, ScrollText("HI".into())) => 0x1A/0x3B [255, 0, 0, 7, 1, b'H', b'I', 0];
    draw_compressed_frame_player_line(0, 1, 7, 6, 255, 0, 0) => 0x1A/0x3D [0, 1, 7, 6, 255, 0, 0];
    draw_compressed_frame_player_fill(0, 1, 7, 6, 255, 0, 0) => 0x1A/0x3E [0, 1, 7, 6, 255, 0, 0];
    assign_compressed_frame_player_frames_to_animation(1, U16List(vec![7, 4, 5])) => 0x1A/0x40 [1, 0, 7, 0, 4, 0, 5];
    save_compressed_frame_player_animation_without_frames(1, 2, true, Bytes(vec![3, 1, 2, 3, 0, 7])) => 0x1A/0x41 [1, 2, 1, 3, 1, 2, 3, 0, 7];
    set_compressed_frame_player_single_character(255, 0, 0, Char(b'A')) => 0x1A/0x42 [255, 0, 0, b'A'];
    play_compressed_frame_player_animation_with_loop_option(2, true) => 0x1A/0x43 [2, 1];
    get_active_color_palette() => 0x1A/0x44 [];
    set_active_color_palette(Bytes(vec![1, 2, 3])) => 0x1A/0x45 [1, 2, 3];
    get_color_identification_report(10, 20, 30, 50) => 0x1A/0x46 [10, 20, 30, 50];
    load_color_palette(1) => 0x1A/0x47 [1];
    save_color_palette(1) => 0x1A/0x48 [1];
    get_compressed_frame_player_frame_info_type() => 0x1A/0x4C [];
    save_compressed_frame_player_16_bit_frame(U16List(vec![7, 8, 9, 10, 11])) => 0x1A/0x4D [0, 7, 0, 8, 0, 9, 0, 10, 0, 11];
    release_led_requests() => 0x1A/0x4E [];
    // API and Shell, System Mode, Connection, Firmware, Factory Test (spherov2 `commands/*.py`)
    echo(Bytes(vec![1, 2])) => 0x10/0x00 [1, 2];
    get_api_protocol_version() => 0x10/0x01 [];
    send_command_to_shell(Text("hi".into())) => 0x10/0x02 [b'h', b'i', 0];
    get_supported_dids() => 0x10/0x05 [];
    get_supported_cids(1) => 0x10/0x06 [1];
    enable_desktoy_mode(true) => 0x12/0x29 [1];
    get_out_of_box_state() => 0x12/0x2B [];
    enable_out_of_box_state(false) => 0x12/0x2C [0];
    connection_set_bluetooth_name(Text("BOLT".into())) => 0x19/0x03 [b'B', b'O', b'L', b'T', 0];
    get_bluetooth_name() => 0x19/0x04 [];
    get_bluetooth_advertising_name() => 0x19/0x05 [];
    get_pending_update_flags() => 0x1D/0x0D [];
    get_current_application_id() => 0x1D/0x15 [];
    get_all_updatable_processors() => 0x1D/0x16 [];
    get_version_for_updatable_processors() => 0x1D/0x18 [];
    set_pending_update_for_processors(Bytes(vec![1, 2])) => 0x1D/0x1A [1, 2];
    get_pending_update_for_processors() => 0x1D/0x1B [];
    reset_with_parameters(1) => 0x1D/0x1C [1];
    clear_pending_update_processors(Bytes(vec![1, 2])) => 0x1D/0x26 [1, 2];
    get_factory_mode_challenge() => 0x1F/0x13 [];
    enter_factory_mode(0x0A0B_0C0D) => 0x1F/0x14 [0x0A, 0x0B, 0x0C, 0x0D];
    exit_factory_mode() => 0x1F/0x15 [];
    get_chassis_id() => 0x1F/0x27 [];
    enable_extended_life_test(true) => 0x1F/0x31 [1];
    get_factory_mode_status() => 0x1F/0x34 [];
}

#[test]
fn every_constructor_is_tested() {
    let tested: BTreeSet<String> = CONSTRUCTORS_TESTED
        .iter()
        .map(|n| n.replace('_', "-"))
        .collect();
    assert_eq!(
        tested.len(),
        CONSTRUCTORS_TESTED.len(),
        "a constructor is listed twice"
    );
    let catalogue: BTreeSet<String> = catalog::commands().iter().map(|c| c.name.clone()).collect();
    assert_eq!(catalogue.len(), 133 + 54);
    let missing: Vec<_> = catalogue.difference(&tested).collect();
    let extra: Vec<_> = tested.difference(&catalogue).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "missing {missing:?}, extra {extra:?}"
    );
}

#[test]
fn drive_with_heading_variants() {
    let c = cmd::drive_with_heading(255, heading(359), DriveFlags::BACKWARD | DriveFlags::TURBO);
    assert_eq!(c.data, [255, 0x01, 0x67, 0x03]);
    let c = cmd::drive_with_heading(0, heading(0), DriveFlags::all());
    assert_eq!(c.data, [0, 0, 0, 0x3F]);
    // Reversing: reference clients add 180° and set BACKWARD.
    let c = cmd::drive_with_heading(60, heading(90).reversed(), DriveFlags::BACKWARD);
    assert_eq!(c.data, [60, 0x01, 0x0E, 0x01]);
    assert!(Heading::new(360).is_none());
}

#[test]
fn set_head_position_is_big_endian_degrees() {
    for (deg, be) in [
        (0.0f32, [0x00, 0x00, 0x00, 0x00]),
        (0.5, [0x3F, 0x00, 0x00, 0x00]),
        (90.0, [0x42, 0xB4, 0x00, 0x00]),
        (180.0, [0x43, 0x34, 0x00, 0x00]),
        (-160.0, [0xC3, 0x20, 0x00, 0x00]),
    ] {
        assert_eq!(cmd::set_head_position(head(deg)).data, be, "{deg}");
    }
    assert!(HeadAngle::new(180.5).is_none());
    assert!(HeadAngle::new(-160.5).is_none());
}

#[test]
fn constructors_match_text_parameters() {
    // The CLI path (encode_params from text) and the typed path agree.
    let given = |pairs: &[(&str, &str)]| -> Vec<(String, String)> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    type Case = (&'static str, Vec<(String, String)>, Command);
    let cases: Vec<Case> = vec![
        (
            "drive-with-heading",
            given(&[("speed", "100"), ("heading", "180"), ("flags", "0")]),
            cmd::drive_with_heading(100, heading(180), DriveFlags::empty()),
        ),
        (
            "drive-with-heading",
            given(&[
                ("flags", "backward,turbo"),
                ("heading", "0x10"),
                ("speed", "255"),
            ]),
            cmd::drive_with_heading(255, heading(16), DriveFlags::BACKWARD | DriveFlags::TURBO),
        ),
        (
            "set-head-position",
            given(&[("degrees", "90")]),
            cmd::set_head_position(head(90.0)),
        ),
        (
            "perform-leg-action",
            given(&[("action", "tripod")]),
            cmd::perform_leg_action(LegAction::Tripod),
        ),
        (
            "play-animation",
            given(&[("id", "10")]),
            cmd::play_animation(10),
        ),
        (
            "play-audio-file",
            given(&[("sound", "1915"), ("mode", "immediate")]),
            cmd::play_audio_file(1915, AudioMode::Immediate),
        ),
        (
            "set-all-leds-with-16-bit-mask",
            given(&[("mask", "0x0080"), ("values", "ff")]),
            cmd::set_all_leds_with_16_bit_mask(Mask(0x0080), Bytes(vec![0xFF])),
        ),
        (
            "configure-collision-detection",
            given(&[
                ("method", "accelerometer"),
                ("x-threshold", "90"),
                ("y-threshold", "130"),
                ("x-speed", "90"),
                ("y-speed", "130"),
                ("dead-time", "1"),
            ]),
            cmd::configure_collision_detection(CollisionMethod::Accelerometer, 90, 130, 90, 130, 1),
        ),
        (
            "set-sensor-streaming-mask",
            given(&[
                ("interval-ms", "150"),
                ("count", "0"),
                ("mask", "0x0007E078"),
            ]),
            cmd::set_sensor_streaming_mask(150, 0, Mask(0x0007_E078)),
        ),
        (
            "set-bluetooth-name",
            given(&[("name", "R2")]),
            cmd::set_bluetooth_name(Text("R2".into())),
        ),
        ("wake", given(&[]), cmd::wake()),
    ];
    for (name, params, typed) in cases {
        let def = catalog::by_name(name).unwrap();
        assert_eq!(def.encode_params(&params), Ok(typed.data), "{name}");
    }
}

// ---------------------------------------------------------------------------------------------
// Response decoders: every catalogue command with a response schema.
// ---------------------------------------------------------------------------------------------

fn response_cases() -> Vec<(&'static str, Vec<u8>, Fields)> {
    let mut last_error = b"main.c".to_vec();
    last_error.resize(32, 0);
    last_error.extend([0x01, 0xF4]);
    last_error.extend(0u8..12);
    vec![
        // Core
        (
            "get-versions",
            h("01 02 03 04 05 06 07 08"),
            vec![
                ("record_version", int(1)),
                ("model_number", int(2)),
                ("hardware_version", int(3)),
                ("main_app_major", int(4)),
                ("main_app_minor", int(5)),
                ("bootloader_version", int(6)),
                ("orb_basic_version", int(7)),
                ("overlay_version", int(8)),
            ],
        ),
        (
            "get-bluetooth-info",
            b"D2-55E3\0c7:11:e0\0".to_vec(),
            vec![("name_and_address", text("D2-55E3 / c7:11:e0"))],
        ),
        (
            "get-power-state",
            h("01 02 01 A4 00 05 01 00"),
            vec![
                ("record_version", int(1)),
                ("state", en(2, "ok")),
                ("voltage", float(4.2)),
                ("number_of_charges", int(5)),
                ("time_since_last_charge", int(256)),
            ],
        ),
        (
            "core-get-charger-state",
            h("01"),
            vec![("state", en(1, "in"))],
        ),
        (
            "get-factory-config-block-crc",
            h("DE AD BE EF"),
            vec![("crc", hexv(0xDEAD_BEEF, 4))],
        ),
        // System info
        (
            "get-main-app-version",
            h("00 04 00 0B 00 02"),
            vec![("major", int(4)), ("minor", int(11)), ("revision", int(2))],
        ),
        (
            "get-bootloader-version",
            h("00 01 00 00 01 09"),
            vec![("major", int(1)), ("minor", int(0)), ("revision", int(265))],
        ),
        ("get-board-revision", h("07"), vec![("revision", int(7))]),
        (
            "get-mac-address",
            h("C7 11 E0 55 E3 01"),
            vec![("address", bytes(&h("C7 11 E0 55 E3 01")))],
        ),
        (
            "get-model-number",
            h("00 04"),
            vec![("model", bytes(&[0, 4]))],
        ),
        (
            "get-stats-id",
            h("12 34"),
            vec![("stats_id", bytes(&[0x12, 0x34]))],
        ),
        (
            "get-processor-name",
            b"nRF52832\0".to_vec(),
            vec![("name", text("nRF52832"))],
        ),
        (
            "get-boot-reason",
            h("04"),
            vec![("reason", en(4, "from-sleep"))],
        ),
        (
            "get-last-error-info",
            last_error,
            vec![
                ("file_name", text("main.c")),
                ("line_number", int(500)),
                ("data", bytes(&(0u8..12).collect::<Vec<_>>())),
            ],
        ),
        (
            "get-three-character-sku",
            b"R2D\0".to_vec(),
            vec![("sku", text("R2D"))],
        ),
        (
            "get-config-block",
            h("00 00 00 01 00 00 00 02 AA BB"),
            vec![
                ("metadata_version", int(1)),
                ("config_block_version", int(2)),
                ("application_data", bytes(&[0xAA, 0xBB])),
            ],
        ),
        (
            "get-swd-locking-status",
            h("01"),
            vec![("locked", boolean(true))],
        ),
        (
            "get-manufacturing-date",
            h("07 E1 09 1E"),
            vec![("year", int(2017)), ("month", int(9)), ("day", int(30))],
        ),
        (
            "get-sku",
            b"R201RW\0".to_vec(),
            vec![("sku", text("R201RW"))],
        ),
        (
            "get-core-up-time",
            h("00 01 E2 40"),
            vec![("uptime_ms", int(123_456))],
        ),
        (
            "get-event-log-status",
            h("00 00 00 01 00 00 00 02 FF FF FF FF"),
            vec![
                ("word_0", int(1)),
                ("word_1", int(2)),
                ("word_2", int(0xFFFF_FFFF)),
            ],
        ),
        (
            "get-event-log-data",
            h("01 02 03"),
            vec![("data", bytes(&[1, 2, 3]))],
        ),
        // Power
        (
            "get-battery-voltage",
            h("01 9A"),
            vec![("voltage", float(4.1))],
        ),
        (
            "get-battery-state",
            h("05"),
            vec![("state", en(5, "critical"))],
        ),
        (
            "get-battery-percentage",
            h("57"),
            vec![("percent", int(87))],
        ),
        (
            "get-battery-voltage-state",
            h("02"),
            vec![("state", en(2, "low"))],
        ),
        (
            "get-charger-state",
            h("02"),
            vec![("state", en(2, "charging"))],
        ),
        (
            "get-battery-adc-reading",
            h("C8"),
            vec![("reading", int(200))],
        ),
        (
            "get-battery-calibration",
            h("03"),
            vec![("calibration", int(3))],
        ),
        (
            "get-battery-voltage-in-volts",
            f32s(&[3.75]),
            vec![("volts", float(3.75))],
        ),
        (
            "get-battery-voltage-state-thresholds",
            f32s(&[3.25, 3.5, 0.125]),
            vec![
                ("critical", float(3.25)),
                ("low", float(3.5)),
                ("hysteresis", float(0.125)),
            ],
        ),
        (
            "get-current-sense-amplifier-current",
            f32s(&[0.5]),
            vec![("amps", float(0.5))],
        ),
        ("get-efuse-fault-status", h("01"), vec![("status", int(1))]),
        // Drive
        (
            "get-component-parameters",
            h("3F 80 00 00 C0 20 00 00"),
            vec![("values", Value::List(vec![float(1.0), float(-2.5)]))],
        ),
        (
            "get-motor-fault-state",
            h("00"),
            vec![("fault", boolean(false))],
        ),
        // Animatronic
        (
            "get-head-position",
            h("C2 36 00 00"),
            vec![("degrees", float(-45.5))],
        ),
        (
            "get-leg-position",
            h("3E 80 00 00"),
            vec![("position", float(0.25))],
        ),
        (
            "get-leg-action",
            h("04"),
            vec![("state", en(4, "transitioning"))],
        ),
        (
            "get-trophy-mode-enabled",
            h("01"),
            vec![("enabled", boolean(true))],
        ),
        // Sensor
        (
            "get-sensor-streaming-mask",
            h("00 96 00 00 07 E0 78"),
            vec![
                ("interval_ms", int(150)),
                ("count", int(0)),
                ("mask", hexv(0x0007_E078, 4)),
            ],
        ),
        (
            "get-extended-sensor-streaming-mask",
            h("03 80 00 00"),
            vec![("mask", hexv(0x0380_0000, 4))],
        ),
        (
            "get-bot-to-bot-infrared-readings",
            h("01 02 03 04"),
            vec![("readings", bytes(&[1, 2, 3, 4]))],
        ),
        (
            "get-rgbc-sensor-values",
            h("00 10 00 20 00 30 FF FF"),
            vec![
                ("red", int(16)),
                ("green", int(32)),
                ("blue", int(48)),
                ("clear", int(65535)),
            ],
        ),
        (
            "get-ambient-light-sensor-value",
            h("43 48 00 00"),
            vec![("lux", float(200.0))],
        ),
        (
            "get-current-detected-color-reading",
            h("10 20 30"),
            vec![("data", bytes(&[0x10, 0x20, 0x30]))],
        ),
        (
            "get-motor-temperature",
            h("42 20 00 00 42 48 00 00"),
            vec![
                ("case_temperature", float(40.0)),
                ("winding_temperature", float(50.0)),
            ],
        ),
        (
            "get-motor-thermal-protection-status",
            h("00 01 02 03 04 05 06 07 08 09"),
            vec![("data", bytes(&h("00 01 02 03 04 05 06 07 08 09")))],
        ),
        // IO
        ("get-audio-volume", h("80"), vec![("volume", int(128))]),
        (
            "get-compressed-frame-player-list-of-frames",
            h("00 01 00 02"),
            vec![("frames", Value::List(vec![int(1), int(2)]))],
        ),
        (
            "get-active-color-palette",
            h("01 02"),
            vec![("data", bytes(&[1, 2]))],
        ),
        (
            "get-color-identification-report",
            h("03"),
            vec![("data", bytes(&[3]))],
        ),
        (
            "get-compressed-frame-player-frame-info-type",
            h("03"),
            vec![("info_type", en(3, "64-bit"))],
        ),
        (
            "save-compressed-frame-player-16-bit-frame",
            h("09"),
            vec![("data", bytes(&[9]))],
        ),
        // API and Shell, System Mode, Connection, Firmware, Factory Test
        ("echo", h("01 02"), vec![("data", bytes(&[1, 2]))]),
        (
            "get-api-protocol-version",
            h("02 01"),
            vec![("major", int(2)), ("minor", int(1))],
        ),
        (
            "get-supported-dids",
            h("10 11"),
            vec![("dids", bytes(&[0x10, 0x11]))],
        ),
        (
            "get-supported-cids",
            h("01 02"),
            vec![("cids", bytes(&[1, 2]))],
        ),
        (
            "get-out-of-box-state",
            h("01"),
            vec![("enabled", boolean(true))],
        ),
        (
            "get-bluetooth-name",
            h("53 42 00"),
            vec![("name", text("SB"))],
        ),
        (
            "get-bluetooth-advertising-name",
            h("53 42 00"),
            vec![("name", text("SB"))],
        ),
        (
            "get-pending-update-flags",
            h("00 01"),
            vec![("flags", bytes(&[0, 1]))],
        ),
        (
            "get-current-application-id",
            h("01"),
            vec![("application", int(1))],
        ),
        (
            "get-all-updatable-processors",
            h("01"),
            vec![("data", bytes(&[1]))],
        ),
        (
            "get-version-for-updatable-processors",
            h("01"),
            vec![("data", bytes(&[1]))],
        ),
        (
            "set-pending-update-for-processors",
            h("01"),
            vec![("reset_strategy", int(1))],
        ),
        (
            "get-pending-update-for-processors",
            h("01"),
            vec![("data", bytes(&[1]))],
        ),
        (
            "get-factory-mode-challenge",
            h("01 02 03 04"),
            vec![("challenge", int(0x01020304))],
        ),
        (
            "get-chassis-id",
            h("00 07"),
            vec![("chassis_id", bytes(&[0, 7]))],
        ),
        (
            "get-factory-mode-status",
            h("00"),
            vec![("enabled", boolean(false))],
        ),
    ]
}

#[test]
fn every_response_schema_has_a_case() {
    let cases: BTreeSet<&str> = response_cases().iter().map(|(n, _, _)| *n).collect();
    assert_eq!(
        cases.len(),
        response_cases().len(),
        "a response case is listed twice"
    );
    let with_response: BTreeSet<&str> = catalog::commands()
        .iter()
        .filter(|c| !c.response.is_empty())
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(cases, with_response);
    assert_eq!(with_response.len(), 48 + 21);
}

#[test]
fn response_decoders() {
    for (name, payload, expected) in response_cases() {
        let def = catalog::by_name(name).unwrap();
        assert_eq!(
            catalog::decode_fields(def.response, &payload).as_ref(),
            Ok(&expected),
            "{name}: decode_fields"
        );
        // Through the whole path: request, response on the wire, decoder, describe.
        let request = Command::new(def.did, def.cid, vec![]).to_packet(42);
        let response = Packet::response_to(&request, ErrorCode::Success, payload.clone());
        let out = Decoder::new().decode_all(&response.encode());
        let [Ok(p)] = &out[..] else {
            panic!("{name}: {out:?}")
        };
        assert_eq!(p, &response, "{name}");
        let d = describe(p, None);
        assert_eq!(d.kind, Kind::Response, "{name}");
        assert_eq!(d.name, Some(name), "{name}");
        assert_eq!(d.fields.as_ref(), Some(&expected), "{name}: describe");
        assert_eq!(d.problem, None, "{name}");
    }
}

#[test]
fn response_decoders_reject_wrong_lengths() {
    let mut rejected = 0;
    for (name, payload, _) in response_cases() {
        let def = catalog::by_name(name).unwrap();
        let fixed_only = def
            .response
            .iter()
            .all(|f| matches!(f.size, Size::Fixed(_)));
        let mut candidates: Vec<Vec<u8>> =
            (0..payload.len()).map(|n| payload[..n].to_vec()).collect();
        candidates.push([payload.as_slice(), &[0xEE]].concat());
        candidates.push([payload.as_slice(), &[0xEE, 0xEE, 0xEE, 0xEE]].concat());
        for data in candidates {
            let result = catalog::decode_fields(def.response, &data);
            if !catalog::length_ok(def.response, data.len()) {
                assert!(
                    result.is_err(),
                    "{name}: {} bytes accepted: {result:?}",
                    data.len()
                );
                let request = Packet::command(def.did, def.cid, 1, vec![]);
                let d = describe(
                    &Packet::response_to(&request, ErrorCode::Success, data),
                    None,
                );
                assert_eq!(d.fields, None, "{name}");
                assert!(d.problem.is_some(), "{name}");
                rejected += 1;
            }
        }
        if fixed_only {
            // Every shorter and every longer payload of a fixed layout is an error.
            assert!(catalog::decode_fields(def.response, &payload[..payload.len() - 1]).is_err());
            assert_eq!(
                catalog::decode_fields(def.response, &[payload.as_slice(), &[0]].concat()),
                Err(FieldError::Trailing(1)),
                "{name}"
            );
        }
    }
    assert!(rejected > 100, "only {rejected} wrong lengths checked");
    // f32 lists must be whole values.
    let def = catalog::by_name("get-component-parameters").unwrap();
    assert!(matches!(
        catalog::decode_fields(def.response, &[0x3F, 0x80, 0x00]),
        Err(FieldError::Invalid {
            field: "values",
            ..
        })
    ));
    // A short field is named.
    let def = catalog::by_name("get-battery-voltage").unwrap();
    assert_eq!(
        catalog::decode_fields(def.response, &[0x01]),
        Err(FieldError::Short {
            field: "voltage",
            needed: 1
        })
    );
}

#[test]
fn error_responses_are_described_not_decoded() {
    let request = cmd::get_battery_voltage().to_packet(3);
    for err in [
        ErrorCode::BadDataLength,
        ErrorCode::TargetUnavailable,
        ErrorCode::Unknown(0x42),
    ] {
        let p = Packet::response_to(&request, err, vec![]);
        let d = describe(&p, None);
        assert_eq!(d.kind, Kind::Response);
        assert_eq!(d.name, Some("get-battery-voltage"));
        assert_eq!(d.fields, None);
        assert!(
            d.problem.as_deref().unwrap().contains(&err.name()),
            "{err:?}"
        );
    }
}

#[test]
fn unknown_ids_are_described_as_unknown() {
    let d = describe(&Packet::command(0x42, 0x01, 0, vec![1, 2]), None);
    assert_eq!((d.kind, d.name, d.fields), (Kind::Command, None, None));
    assert!(d.problem.unwrap().contains("unknown command"));
    let d = describe(&Packet::notification(0x18, 0x7F, vec![]), None);
    assert_eq!((d.kind, d.name, d.fields), (Kind::Notification, None, None));
    assert!(d.problem.unwrap().contains("unknown notification"));
}

// ---------------------------------------------------------------------------------------------
// Notification decoders: every catalogue notification, every typed variant.
// ---------------------------------------------------------------------------------------------

/// accel (4096, -2048, -4096) raw = (1, -0.5, -1) g, axis x only, power (100, -5, 32767),
/// speed 200, time 0x89ABCDEF ms (the 0xAB needs escaping on the wire).
fn collision_bytes() -> Vec<u8> {
    h("10 00 F8 00 F0 00 01 00 64 FF FB 7F FF C8 89 AB CD EF")
}

fn collision_fields() -> Fields {
    vec![
        ("accel_x", float(1.0)),
        ("accel_y", float(-0.5)),
        ("accel_z", float(-1.0)),
        ("x_axis", boolean(true)),
        ("y_axis", boolean(false)),
        ("power_x", int(100)),
        ("power_y", int(-5)),
        ("power_z", int(32767)),
        ("speed", int(200)),
        ("time_ms", int(0x89AB_CDEF)),
    ]
}

fn notification_cases() -> Vec<(u8, u8, &'static str, Vec<u8>, Fields)> {
    vec![
        (
            0x11,
            0x18,
            "secondary-main-app-version",
            h("00 01 00 02 00 03"),
            vec![("major", int(1)), ("minor", int(2)), ("revision", int(3))],
        ),
        (
            0x11,
            0x25,
            "secondary-mcu-bootloader-version",
            h("00 04 00 05 01 00"),
            vec![("major", int(4)), ("minor", int(5)), ("revision", int(256))],
        ),
        (
            0x11,
            0x3E,
            "sos-message",
            h("09"),
            vec![("message", int(9))],
        ),
        (
            0x13,
            0x06,
            "battery-state-changed",
            h("01"),
            vec![("state", en(1, "charging"))],
        ),
        (0x13, 0x19, "will-sleep", vec![], vec![]),
        (0x13, 0x1A, "did-sleep", vec![], vec![]),
        (
            0x13,
            0x1C,
            "battery-voltage-state-changed",
            h("03"),
            vec![("state", en(3, "critical"))],
        ),
        (
            0x13,
            0x21,
            "charger-state-changed",
            h("02"),
            vec![("state", int(2))],
        ),
        (
            0x13,
            0x29,
            "efuse-fault-occurred",
            h("01"),
            vec![("efuse", int(1))],
        ),
        (
            0x16,
            0x26,
            "motor-stall",
            h("01 01"),
            vec![("motor", int(1)), ("stalled", boolean(true))],
        ),
        (
            0x16,
            0x28,
            "motor-fault",
            h("00"),
            vec![("fault", boolean(false))],
        ),
        (
            0x17,
            0x11,
            "play-animation-complete",
            h("00 0A"),
            vec![("data", bytes(&[0, 10]))],
        ),
        (
            0x17,
            0x26,
            "leg-action-complete",
            h("01"),
            vec![("data", bytes(&[1]))],
        ),
        (0x17, 0x3A, "head-reset-to-zero", vec![], vec![]),
        (
            0x18,
            0x02,
            "sensor-streaming-data",
            f32s(&[1.0, -2.5]),
            vec![("values", Value::List(vec![float(1.0), float(-2.5)]))],
        ),
        (0x18, 0x10, "gyro-max", h("03"), vec![("flags", int(3))]),
        (
            0x18,
            0x12,
            "collision-detected",
            collision_bytes(),
            collision_fields(),
        ),
        (0x18, 0x1A, "accelerometer-activity", vec![], vec![]),
        (0x18, 0x1D, "gyro-activity", vec![], vec![]),
        (
            0x18,
            0x26,
            "magnetometer-north-yaw",
            h("01 0E"),
            vec![("yaw", int(270))],
        ),
        (
            0x18,
            0x2C,
            "robot-to-robot-ir-message",
            h("05"),
            vec![("code", int(5))],
        ),
        (
            0x18,
            0x36,
            "color-detection",
            h("FF 80 00 03 5A"),
            vec![
                ("red", int(255)),
                ("green", int(128)),
                ("blue", int(0)),
                ("index", int(3)),
                ("confidence", int(90)),
            ],
        ),
        (
            0x18,
            0x3D,
            "streaming-service-data",
            h("07 01 02 03"),
            vec![("token", int(7)), ("data", bytes(&[1, 2, 3]))],
        ),
        (
            0x18,
            0x40,
            "motor-current",
            (0u8..16).collect(),
            vec![("data", bytes(&(0u8..16).collect::<Vec<_>>()))],
        ),
        (
            0x18,
            0x49,
            "sensitivity-collision",
            h("01 02 03 04"),
            vec![("data", bytes(&[1, 2, 3, 4]))],
        ),
        (
            0x18,
            0x4D,
            "motor-thermal-protection",
            (10u8..20).collect(),
            vec![("data", bytes(&(10u8..20).collect::<Vec<_>>()))],
        ),
        (0x1A, 0x1E, "color-tap", h("04"), vec![("data", int(4))]),
        (
            0x1A,
            0x3C,
            "text-scrolling",
            h("00"),
            vec![("reason", en(0, "done"))],
        ),
        (
            0x1A,
            0x3F,
            "compressed-frame-player-animation-complete",
            h("02"),
            vec![("animation_id", int(2))],
        ),
        (
            0x10,
            0x03,
            "send-string-to-console",
            h("68 69 00"),
            vec![("text", text("hi"))],
        ),
    ]
}

#[test]
fn every_notification_has_a_case() {
    let cases: BTreeSet<(u8, u8, &str)> = notification_cases()
        .iter()
        .map(|(d, c, n, _, _)| (*d, *c, *n))
        .collect();
    assert_eq!(cases.len(), notification_cases().len());
    let catalogue: BTreeSet<(u8, u8, &str)> = catalog::notifications()
        .iter()
        .map(|n| (n.device.id(), n.cid, n.name.as_str()))
        .collect();
    assert_eq!(cases, catalogue);
    assert_eq!(catalogue.len(), 27 + 3);
}

#[test]
fn notification_decoders() {
    for (did, cid, name, payload, expected) in notification_cases() {
        let def = catalog::notification(did, cid).unwrap();
        assert_eq!(def.name, name);
        assert_eq!(
            catalog::decode_fields(def.fields, &payload).as_ref(),
            Ok(&expected),
            "{name}: decode_fields"
        );
        // On the wire as a notification (SEQ 0xFF, no response flag), then described.
        let n = Packet::notification(did, cid, payload.clone());
        let wire = n.encode();
        assert_eq!(wire[1], 0x00, "{name}: notification flags");
        let out = Decoder::new().decode_all(&wire);
        let [Ok(p)] = &out[..] else {
            panic!("{name}: {out:?}")
        };
        assert_eq!(p, &n);
        assert!(p.is_notification());
        let d = describe(p, None);
        assert_eq!(d.kind, Kind::Notification, "{name}");
        assert_eq!(d.name, Some(name), "{name}");
        assert_eq!(d.fields.as_ref(), Some(&expected), "{name}: describe");
        assert_eq!(d.problem, None, "{name}");
    }
}

#[test]
fn notification_decoders_reject_wrong_lengths() {
    let mut rejected = 0;
    for (did, cid, name, payload, _) in notification_cases() {
        let def = catalog::notification(did, cid).unwrap();
        let mut candidates: Vec<Vec<u8>> =
            (0..payload.len()).map(|n| payload[..n].to_vec()).collect();
        candidates.push([payload.as_slice(), &[0xEE]].concat());
        for data in candidates {
            if !catalog::length_ok(def.fields, data.len()) {
                assert!(
                    catalog::decode_fields(def.fields, &data).is_err(),
                    "{name}: {data:?}"
                );
                let d = describe(&Packet::notification(did, cid, data), None);
                assert_eq!(d.fields, None, "{name}");
                assert!(d.problem.is_some(), "{name}");
                rejected += 1;
            }
        }
    }
    assert!(rejected > 40, "only {rejected} wrong lengths checked");
}

#[test]
fn collision_is_18_bytes_with_named_fields() {
    let data = collision_bytes();
    assert_eq!(data.len(), Collision::LEN);
    let c = Collision::decode(&data).unwrap();
    assert_eq!(c.accel, [AccelRaw(4096), AccelRaw(-2048), AccelRaw(-4096)]);
    assert_eq!(
        [c.accel[0].g(), c.accel[1].g(), c.accel[2].g()],
        [1.0, -0.5, -1.0]
    );
    assert_eq!(c.axis, CollisionAxis { x: true, y: false });
    assert_eq!(c.power, [100, -5, 32767]);
    assert_eq!(c.speed, 200);
    assert_eq!(c.time_ms, 0x89AB_CDEF);
    assert_eq!(c.encode(), data);

    // Both axes, and the y bit alone.
    let mut both = data.clone();
    both[6] = 0x03;
    assert_eq!(
        Collision::decode(&both).unwrap().axis,
        CollisionAxis { x: true, y: true }
    );
    let mut y = data.clone();
    y[6] = 0x02;
    let def = catalog::notification(0x18, 0x12).unwrap();
    let fields = catalog::decode_fields(def.fields, &y).unwrap();
    assert_eq!(fields[3], ("x_axis", boolean(false)));
    assert_eq!(fields[4], ("y_axis", boolean(true)));

    // The seed's 17 bytes, and 19, are errors.
    assert!(Collision::decode(&data[..17]).is_err());
    assert!(Collision::decode(&[data.as_slice(), &[0]].concat()).is_err());
    assert!(catalog::decode_fields(def.fields, &data[..17]).is_err());
}

#[test]
fn collision_through_the_decoder() {
    let wire = Packet::notification(0x18, 0x12, collision_bytes()).encode();
    // SOP, 4 header bytes, 18 data bytes (the 0xAB in time_ms escaped as AB 23), CHK, EOP.
    assert_eq!(wire.len(), 1 + 4 + (18 + 1) + 1 + 1);
    assert!(wire.windows(3).any(|w| w == [0x89, 0xAB, 0x23]));
    let mut d = Decoder::new();
    let mut packets = Vec::new();
    // 20-byte BLE notifications are not packet boundaries.
    for chunk in wire.chunks(20) {
        packets.extend(d.feed(chunk).map(Result::unwrap));
    }
    let [p] = &packets[..] else {
        panic!("{packets:?}")
    };
    let n = Notification::decode(p, &StreamingConfig::default()).unwrap();
    assert_eq!(
        n,
        Notification::Collision(Collision::decode(&collision_bytes()).unwrap())
    );
    assert_eq!(n.name(), "collision-detected");
    let d = describe(p, None);
    assert_eq!(d.fields, Some(collision_fields()));
}

/// The typical full set of droid-facts.md §2: standard 0x0007E078, extended 0x03800000.
fn typical_config() -> StreamingConfig {
    StreamingConfig {
        mask: 0x0007_E078,
        ext_mask: 0x0380_0000,
        interval_ms: 150,
    }
}

/// Wire values of the typical set, in wire order, and the decoded (scaled) values.
fn typical_sample() -> (Vec<u8>, Vec<(&'static str, f32)>) {
    let wire = [
        1.5f32, -2.25, 90.0, 0.5, -0.25, 1.0, 0.125, -0.5, 0.25, 0.0, 10.0, -20.0, 30.0,
    ];
    let decoded = vec![
        ("pitch", 1.5),
        ("roll", -2.25),
        ("yaw", 90.0),
        ("accel_x", 0.5),
        ("accel_y", -0.25),
        ("accel_z", 1.0),
        ("locator_x", 12.5),
        ("locator_y", -50.0),
        ("velocity_x", 25.0),
        ("velocity_y", 0.0),
        ("gyro_x", 10.0),
        ("gyro_y", -20.0),
        ("gyro_z", 30.0),
    ];
    (f32s(&wire), decoded)
}

#[test]
fn sensor_streaming_typical_full_set() {
    let cfg = typical_config();
    assert_eq!(
        cfg.mask,
        mask::ATTITUDE | mask::ACCELEROMETER | mask::LOCATOR | mask::VELOCITY
    );
    assert_eq!(cfg.ext_mask, mask::EXT_GYRO);
    assert_eq!(cfg.value_count(), 13);
    assert!(cfg.is_streaming());
    let (data, decoded) = typical_sample();
    assert_eq!(data.len(), 13 * 4);
    let s = decode_sample(&cfg, &data).unwrap();
    assert_eq!(s.values, decoded);
    assert_eq!(s.get("locator_x"), Some(12.5));
    assert_eq!(s.get("head_angle"), None);
    // The simulator's encoder is the inverse.
    assert_eq!(sensor::encode_sample(&cfg, &decoded), data);

    // Through the wire and describe, with and without the masks.
    let p = Packet::notification(0x18, 0x02, data.clone());
    let out = Decoder::new().decode_all(&p.encode());
    let [Ok(p)] = &out[..] else { panic!("{out:?}") };
    let with = describe(p, Some(&cfg));
    assert_eq!(with.name, Some("sensor-streaming-data"));
    let expected: Fields = decoded
        .iter()
        .map(|(n, v)| (*n, float(*v as f64)))
        .collect();
    assert_eq!(with.fields, Some(expected));
    let without = describe(p, None);
    let raw: Vec<Value> = [
        1.5f32, -2.25, 90.0, 0.5, -0.25, 1.0, 0.125, -0.5, 0.25, 0.0, 10.0, -20.0, 30.0,
    ]
    .iter()
    .map(|v| float(*v as f64))
    .collect();
    assert_eq!(without.fields, Some(vec![("values", Value::List(raw))]));

    match Notification::decode(p, &cfg).unwrap() {
        Notification::Sensors(sample) => assert_eq!(sample.values, decoded),
        other => panic!("{other:?}"),
    }
}

#[test]
fn sensor_streaming_full_config_has_head_angle_first_in_extended() {
    let cfg = StreamingConfig::full(150);
    assert_eq!(cfg.mask, 0x0007_E078);
    assert_eq!(cfg.ext_mask, 0x0780_0000);
    let names: Vec<&str> = cfg.layout().iter().map(|f| f.unwrap().name).collect();
    assert_eq!(
        names,
        [
            "pitch",
            "roll",
            "yaw",
            "accel_x",
            "accel_y",
            "accel_z",
            "locator_x",
            "locator_y",
            "velocity_x",
            "velocity_y",
            "head_angle",
            "gyro_x",
            "gyro_y",
            "gyro_z"
        ]
    );
    let mut wire: Vec<f32> = vec![0.0; 14];
    wire[10] = -162.0;
    wire[6] = 1.0;
    wire[9] = -0.01;
    let s = decode_sample(&cfg, &f32s(&wire)).unwrap();
    assert_eq!(s.get("head_angle"), Some(-162.0));
    assert_eq!(s.get("locator_x"), Some(100.0));
    assert!((s.get("velocity_y").unwrap() + 1.0).abs() < 1e-5);
}

#[test]
fn sensor_streaming_partial_masks() {
    // Only yaw and speed (standard), head angle (extended): descending bit order.
    let cfg = StreamingConfig {
        mask: 0x0001_0000 | mask::SPEED,
        ext_mask: mask::EXT_HEAD_ANGLE,
        interval_ms: 50,
    };
    let s = decode_sample(&cfg, &f32s(&[45.0, 3.0, -90.0])).unwrap();
    assert_eq!(
        s.values,
        vec![("yaw", 45.0), ("speed", 3.0), ("head_angle", -90.0)]
    );
    // Extended only.
    let cfg = StreamingConfig {
        mask: 0,
        ext_mask: mask::EXT_GYRO,
        interval_ms: 50,
    };
    let s = decode_sample(&cfg, &f32s(&[1.0, 2.0, 3.0])).unwrap();
    assert_eq!(
        s.values,
        vec![("gyro_x", 1.0), ("gyro_y", 2.0), ("gyro_z", 3.0)]
    );
    // Nothing enabled: an empty payload is an empty sample.
    let off = StreamingConfig::default();
    assert!(!off.is_streaming());
    assert_eq!(decode_sample(&off, &[]).unwrap().values, vec![]);
}

#[test]
fn sensor_streaming_wrong_length_is_an_error() {
    let cfg = typical_config();
    let (data, _) = typical_sample();
    for n in [0, 4, 51, 53, 56] {
        let payload: Vec<u8> = data.iter().copied().cycle().take(n).collect();
        let e = decode_sample(&cfg, &payload).unwrap_err();
        assert_eq!((e.expected_values, e.got_bytes), (13, n));
        let p = Packet::notification(0x18, 0x02, payload);
        assert!(Notification::decode(&p, &cfg).is_err());
        let d = describe(&p, Some(&cfg));
        assert_eq!(d.fields, None);
        assert!(d.problem.unwrap().contains("does not match the masks"));
    }
}

/// The name of each variant; a new variant makes this fail to compile until it is tested.
fn variant(n: &Notification) -> &'static str {
    match n {
        Notification::Collision(_) => "Collision",
        Notification::Sensors(_) => "Sensors",
        Notification::BatteryStateChanged(_) => "BatteryStateChanged",
        Notification::BatteryVoltageStateChanged(_) => "BatteryVoltageStateChanged",
        Notification::ChargerStateChanged(_) => "ChargerStateChanged",
        Notification::WillSleep => "WillSleep",
        Notification::DidSleep => "DidSleep",
        Notification::LegActionComplete => "LegActionComplete",
        Notification::AnimationComplete => "AnimationComplete",
        Notification::HeadResetToZero => "HeadResetToZero",
        Notification::Other { .. } => "Other",
        Notification::Robot(_) => "Robot",
        // Sent by v1 droids only (tests/it/v1_vectors.rs); a v2 packet never decodes to them.
        Notification::PowerState(_) | Notification::OtherAsync { .. } => "v1 only",
        Notification::RobiHandshake(_) | Notification::RobiFrame(_) => "RSRCP only",
    }
}

#[test]
fn every_notification_variant_decodes() {
    let cfg = typical_config();
    let (sensor_data, decoded) = typical_sample();
    let cases: Vec<(u8, u8, Vec<u8>, Notification, &str)> = vec![
        (
            0x18,
            0x12,
            collision_bytes(),
            Notification::Collision(Collision::decode(&collision_bytes()).unwrap()),
            "collision-detected",
        ),
        (
            0x18,
            0x02,
            sensor_data,
            Notification::Sensors(droidctl::protocol::v2::SensorSample { values: decoded }),
            "sensor-streaming-data",
        ),
        (
            0x13,
            0x06,
            vec![3],
            Notification::BatteryStateChanged(3),
            "battery-state-changed",
        ),
        (
            0x13,
            0x1C,
            vec![2],
            Notification::BatteryVoltageStateChanged(2),
            "battery-voltage-state-changed",
        ),
        (
            0x13,
            0x21,
            vec![1],
            Notification::ChargerStateChanged(1),
            "charger-state-changed",
        ),
        (0x13, 0x19, vec![], Notification::WillSleep, "will-sleep"),
        (0x13, 0x1A, vec![], Notification::DidSleep, "did-sleep"),
        (
            0x17,
            0x26,
            vec![1],
            Notification::LegActionComplete,
            "leg-action-complete",
        ),
        (
            0x17,
            0x11,
            vec![0, 10],
            Notification::AnimationComplete,
            "play-animation-complete",
        ),
        (
            0x17,
            0x3A,
            vec![],
            Notification::HeadResetToZero,
            "head-reset-to-zero",
        ),
        (
            0x16,
            0x26,
            vec![1, 1],
            Notification::Robot(RobotEvent::MotorStall {
                motor: 1,
                stalled: true,
            }),
            "motor-stall",
        ),
        (
            0x18,
            0x10,
            vec![3],
            Notification::Other {
                did: 0x18,
                cid: 0x10,
                data: vec![3],
            },
            "gyro-max",
        ),
        (
            0x42,
            0x01,
            vec![9],
            Notification::Other {
                did: 0x42,
                cid: 0x01,
                data: vec![9],
            },
            "notification-42-01",
        ),
    ];
    let mut seen = BTreeSet::new();
    for (did, cid, data, expected, name) in cases {
        let p = Packet::notification(did, cid, data);
        let n = Notification::decode(&p, &cfg).unwrap();
        assert_eq!(n, expected, "{name}");
        assert_eq!(n.name(), name);
        seen.insert(variant(&n));
    }
    assert_eq!(seen.len(), 12, "{seen:?}");
}

#[test]
fn typed_notifications_reject_malformed_payloads() {
    let cfg = typical_config();
    let bad = |did: u8, cid: u8, data: Vec<u8>, name: &str| {
        let e = Notification::decode(&Packet::notification(did, cid, data), &cfg).unwrap_err();
        assert_eq!(e.name, name);
        assert!(!e.reason.is_empty());
    };
    bad(
        0x18,
        0x12,
        collision_bytes()[..17].to_vec(),
        "collision-detected",
    );
    bad(0x18, 0x12, vec![], "collision-detected");
    bad(0x18, 0x02, vec![0; 7], "sensor-streaming-data");
    for (cid, name) in [
        (0x06, "battery-state-changed"),
        (0x1C, "battery-voltage-state-changed"),
        (0x21, "charger-state-changed"),
    ] {
        bad(0x13, cid, vec![], name);
        bad(0x13, cid, vec![1, 2], name);
    }
    bad(0x13, 0x19, vec![1], "will-sleep");
    bad(0x13, 0x1A, vec![0], "did-sleep");
    bad(0x17, 0x3A, vec![0], "head-reset-to-zero");
}

#[test]
fn notifications_in_a_mixed_stream() {
    // A response, a collision, sensor data and a will-sleep notification in 20-byte BLE
    // chunks: every packet comes out in order, nothing counted as an error.
    let cfg = typical_config();
    let (sensor_data, decoded) = typical_sample();
    let packets = vec![
        Packet::response_to(&cmd::wake().to_packet(0), ErrorCode::Success, vec![]),
        Packet::notification(0x18, 0x12, collision_bytes()),
        Packet::notification(0x18, 0x02, sensor_data),
        Packet::notification(0x13, 0x19, vec![]),
    ];
    let stream: Vec<u8> = packets.iter().flat_map(Packet::encode).collect();
    let mut d = Decoder::new();
    let mut out = Vec::new();
    for chunk in stream.chunks(20) {
        out.extend(d.feed(chunk).map(Result::unwrap));
    }
    assert_eq!(out, packets);
    assert_eq!(d.stats().total_errors(), 0);
    assert_eq!(d.stats().errors(ErrorKind::Garbage), 0);
    let typed: Vec<Notification> = out[1..]
        .iter()
        .map(|p| Notification::decode(p, &cfg).unwrap())
        .collect();
    assert!(matches!(typed[0], Notification::Collision(_)));
    assert_eq!(
        typed[1],
        Notification::Sensors(droidctl::protocol::v2::SensorSample { values: decoded })
    );
    assert_eq!(typed[2], Notification::WillSleep);
}
