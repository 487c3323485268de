//! The simulated droid (issue 3): protocol behaviour, physics, notifications and fault
//! injection. Most tests drive [`SimDroid`] directly with explicit times; the end-to-end ones
//! go through [`SimLink`] and a session under paused tokio time.

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::link::{Link, LinkEvent};
use droidctl::model::Model;
use droidctl::protocol::v2::catalog::{self, Schema};
use droidctl::protocol::v2::sensor::{StreamingConfig, mask};
use droidctl::protocol::v2::wire::{AudioMode, DriveFlags, LegAction, LegState, Mask, Size};
use droidctl::protocol::v2::{
    Collision, Command, Decoder, Device, ErrorCode, Flags, Notification, Packet, cmd,
};
use droidctl::session::{self, LinkState, SessionConfig, SessionEvent, SessionHandle, Slot};
use droidctl::sim::{Faults, SimConfig, SimDroid, SimLink, SimState};
use droidctl::units::{HeadAngle, Heading};
use std::time::Duration;
use tokio::time::{Instant, sleep, timeout};

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn secs(n: f64) -> Duration {
    Duration::from_secs_f64(n)
}

fn drive(speed: u8, heading: u16) -> Command {
    cmd::drive_with_heading(speed, Heading::new(heading).unwrap(), DriveFlags::empty())
}

fn head(deg: f32) -> Command {
    cmd::set_head_position(HeadAngle::new(deg).unwrap())
}

fn f32s(data: &[u8]) -> Vec<f32> {
    data.chunks_exact(4)
        .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

// ---------------------------------------------------------------------------------------------
// A bench for the sans-IO droid: explicit time in 10 ms steps, notifications recorded.
// ---------------------------------------------------------------------------------------------

struct Bench {
    droid: SimDroid,
    now: Duration,
    seq: u8,
    /// Notifications with the time they came out.
    notes: Vec<(Duration, Packet)>,
}

const STEP: Duration = Duration::from_millis(10);

impl Bench {
    fn new(model: Model) -> Self {
        Bench::with(model, SimConfig::default())
    }

    fn with(model: Model, cfg: SimConfig) -> Self {
        Bench {
            droid: SimDroid::new(model, cfg),
            now: Duration::ZERO,
            seq: 0,
            notes: Vec::new(),
        }
    }

    /// A room so large no wall is ever reached.
    fn open_field(model: Model) -> Self {
        Bench::with(
            model,
            SimConfig {
                room_cm: (100_000.0, 100_000.0),
                ..SimConfig::default()
            },
        )
    }

    fn state(&self) -> &SimState {
        self.droid.state()
    }

    fn take(&mut self, out: Vec<Packet>) -> Vec<Packet> {
        let mut responses = Vec::new();
        for p in out {
            if p.is_response() {
                responses.push(p);
            } else {
                assert_eq!(p.seq, 0xFF, "notifications use SEQ 0xFF: {p:?}");
                self.notes.push((self.now, p));
            }
        }
        responses
    }

    /// Send raw bytes now; the responses that come back.
    fn send_bytes(&mut self, bytes: &[u8]) -> Vec<Packet> {
        let out = self.droid.receive(bytes, self.now);
        self.take(out)
    }

    fn send_packet(&mut self, p: &Packet) -> Vec<Packet> {
        self.send_bytes(&p.encode())
    }

    fn next_seq(&mut self) -> u8 {
        let s = self.seq;
        self.seq = if s >= 254 { 0 } else { s + 1 };
        s
    }

    /// Send a command asking for a response; returns it (checked to match DID/CID/SEQ).
    fn send(&mut self, c: Command) -> Packet {
        let seq = self.next_seq();
        let req = c.to_packet(seq);
        let mut r = self.send_packet(&req);
        assert_eq!(r.len(), 1, "one response to {req:?}, got {r:?}");
        let r = r.remove(0);
        assert_eq!((r.did, r.cid, r.seq), (req.did, req.cid, req.seq));
        r
    }

    fn ok(&mut self, c: Command) -> Packet {
        let r = self.send(c.clone());
        assert_eq!(r.err, Some(ErrorCode::Success), "{c:?}");
        r
    }

    fn err(&mut self, c: Command) -> ErrorCode {
        self.send(c).err.unwrap()
    }

    fn run_for(&mut self, d: Duration) {
        let end = self.now + d;
        while self.now < end {
            self.now += STEP;
            let out = self.droid.advance(self.now);
            self.take(out);
        }
    }

    /// Advance until `f` holds (checked every step) or `limit` passes; true if it held.
    fn run_until(&mut self, limit: Duration, mut f: impl FnMut(&Bench) -> bool) -> bool {
        let end = self.now + limit;
        while self.now < end {
            if f(self) {
                return true;
            }
            self.now += STEP;
            let out = self.droid.advance(self.now);
            self.take(out);
        }
        f(self)
    }

    /// Keep re-sending a drive command every 500 ms for `d` (a heartbeat, as the app does).
    fn hold_drive(&mut self, c: Command, d: Duration) {
        let end = self.now + d;
        while self.now < end {
            self.ok(c.clone());
            self.run_for(ms(500).min(end - self.now));
        }
    }

    fn notes_of(&self, did: u8, cid: u8) -> Vec<(Duration, Packet)> {
        self.notes
            .iter()
            .filter(|(_, p)| (p.did, p.cid) == (did, cid))
            .cloned()
            .collect()
    }

    fn awake_r2_in_tripod() -> Bench {
        let mut b = Bench::open_field(Model::R2D2);
        b.ok(cmd::wake());
        b.ok(cmd::perform_leg_action(LegAction::Tripod));
        b.run_for(ms(2100));
        assert_eq!(b.state().stance, LegState::Tripod);
        b.notes.clear();
        b
    }
}

/// A payload of the right length for a schema: zeros (valid for every enum, heading and dome
/// angle in the catalogue), variable-length fields at their minimum.
fn payload_for(schema: Schema) -> Vec<u8> {
    droidctl::protocol::v2::catalog::minimal_payload(schema)
}

/// A well-formed payload for `def`: the shortest, except where zeros are not a valid value
/// (a streaming token, a period, a matrix character).
fn valid_payload(model: Model, def: &droidctl::protocol::v2::CommandDef) -> Vec<u8> {
    match (def.did, def.cid) {
        // RVR takes it on the primary (the one both answer): its ambient light.
        (0x18, 0x39) if model == Model::Rvr => vec![1, 0, 10, 2],
        (0x18, 0x39) => vec![1, 0, 1, 2],
        (0x18, 0x3A) => vec![0, 100],
        (0x1A, 0x42) => vec![255, 0, 0, b'A'],
        _ => payload_for(def.params),
    }
}

fn wrong_length(schema: Schema) -> Option<Vec<u8>> {
    let n = payload_for(schema).len();
    let variable = schema.iter().any(|f| matches!(f.size, Size::Rest { .. }));
    if variable {
        // Only too short is wrong for a variable payload.
        n.checked_sub(1).map(|n| vec![0; n])
    } else {
        Some(vec![0; n + 1])
    }
}

/// Which commands a model rejects as unknown: BB-9E has no legs or dome; BOLT, Mini and
/// RVR no animatronic device at all; only BOLT and RVR have infrared, each its own commands.
fn model_knows(model: Model, did: u8, cid: u8) -> bool {
    if did == 0x18
        && let Some(has) = droidctl::sim::infrared::has(model, cid)
    {
        return has;
    }
    if matches!(model, Model::Bolt | Model::Mini | Model::Rvr) {
        return Device::from_id(did) != Some(Device::Animatronic);
    }
    model.has_legs()
        || Device::from_id(did) != Some(Device::Animatronic)
        || matches!(cid, 0x05 | 0x2B | 0x2C)
}

/// What a model answers a command it lacks.
fn unknown_error(model: Model, did: u8) -> ErrorCode {
    if matches!(model, Model::Bolt | Model::Mini | Model::Rvr) && did == 0x17 {
        ErrorCode::BadDeviceId
    } else {
        ErrorCode::BadCommandId
    }
}

/// A command packet as a client addresses it on `model` (RVR and BOLT name the processor).
fn addressed_packet(model: Model, did: u8, cid: u8, seq: u8, data: Vec<u8>) -> Packet {
    let mut c = Command::new(did, cid, data);
    c.target =
        droidctl::protocol::v2::catalog::targets::addressed(model, did, cid).map(|p| p.target_id());
    c.to_packet(seq)
}

// ---------------------------------------------------------------------------------------------
// Protocol behaviour
// ---------------------------------------------------------------------------------------------

#[test]
fn answers_every_catalogue_command() {
    let commands = catalog::commands();
    assert!(commands.len() > 100);
    for model in [
        Model::R2D2,
        Model::R2Q5,
        Model::BB9E,
        Model::Bolt,
        Model::Mini,
        Model::Rvr,
    ] {
        for def in commands {
            let mut b = Bench::new(model);
            b.send_packet(&addressed_packet(model, 0x13, 0x0D, 1, vec![]));
            let req = addressed_packet(model, def.did, def.cid, 77, valid_payload(model, def));
            let responses = b.send_packet(&req);
            assert_eq!(responses.len(), 1, "{model:?} {}: {responses:?}", def.name);
            let r = &responses[0];
            assert!(r.is_response());
            assert_eq!(
                (r.did, r.cid, r.seq),
                (req.did, req.cid, 77),
                "{}",
                def.name
            );
            if model_knows(model, def.did, def.cid) {
                assert_eq!(r.err, Some(ErrorCode::Success), "{model:?} {}", def.name);
                // Getters (and everything else) answer with a payload their schema accepts.
                let fields = catalog::decode_fields(def.response, &r.data);
                assert!(
                    fields.is_ok(),
                    "{model:?} {}: {:?} for {:02X?}",
                    def.name,
                    fields,
                    r.data
                );
            } else {
                assert_eq!(
                    r.err,
                    Some(unknown_error(model, def.did)),
                    "{model:?} {}",
                    def.name
                );
            }
            // A payload of the wrong length is refused before anything else.
            if let Some(bad) = wrong_length(def.params) {
                let mut b = Bench::new(model);
                b.send_packet(&addressed_packet(model, 0x13, 0x0D, 1, vec![]));
                let r = b
                    .send_packet(&addressed_packet(model, def.did, def.cid, 9, bad))
                    .remove(0);
                let want = if model_knows(model, def.did, def.cid) {
                    ErrorCode::BadDataLength
                } else {
                    unknown_error(model, def.did)
                };
                assert_eq!(
                    r.err,
                    Some(want),
                    "{model:?} {} with a wrong length",
                    def.name
                );
            }
        }
    }
}

#[test]
fn getters_report_real_state() {
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    b.ok(cmd::set_audio_volume(42));
    assert_eq!(b.ok(cmd::get_audio_volume()).data, [42]);
    let v = b.ok(cmd::get_battery_voltage()).data;
    assert_eq!(u16::from_be_bytes([v[0], v[1]]), 410);
    b.ok(cmd::set_sensor_streaming_mask(150, 0, Mask(0x0007_E078)));
    b.ok(cmd::set_extended_sensor_streaming_mask(Mask(0x0380_0000)));
    assert_eq!(
        b.ok(cmd::get_sensor_streaming_mask()).data,
        [0, 150, 0, 0x00, 0x07, 0xE0, 0x78]
    );
    assert_eq!(
        b.ok(cmd::get_extended_sensor_streaming_mask()).data,
        [0x03, 0x80, 0, 0]
    );
    b.ok(cmd::set_all_leds_with_16_bit_mask(
        Mask(0x0081),
        droidctl::protocol::v2::wire::Bytes(vec![7, 9]),
    ));
    assert_eq!((b.state().leds[0], b.state().leds[7]), (7, 9));
    // One value per set bit.
    assert_eq!(
        b.err(cmd::set_all_leds_with_16_bit_mask(
            Mask(0x0003),
            droidctl::protocol::v2::wire::Bytes(vec![1])
        )),
        ErrorCode::BadDataLength
    );
}

#[test]
fn unknown_ids_and_wrong_lengths_are_errors() {
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    let r = b
        .send_packet(&Packet::command(0x42, 0x01, 5, vec![]))
        .remove(0);
    assert_eq!((r.seq, r.err), (5, Some(ErrorCode::BadDeviceId)));
    let r = b
        .send_packet(&Packet::command(0x13, 0x7E, 6, vec![]))
        .remove(0);
    assert_eq!(
        (r.did, r.cid, r.err),
        (0x13, 0x7E, Some(ErrorCode::BadCommandId))
    );
    for len in [0usize, 3, 5] {
        let r = b
            .send_packet(&Packet::command(0x16, 0x07, 7, vec![10; len]))
            .remove(0);
        assert_eq!(
            r.err,
            Some(ErrorCode::BadDataLength),
            "drive with {len} bytes"
        );
    }
    // A heading past 359 is a bad parameter, not a length problem.
    let r = b
        .send_packet(&Packet::command(0x16, 0x07, 8, vec![10, 0x01, 0x68, 0]))
        .remove(0);
    assert_eq!(r.err, Some(ErrorCode::BadParameterValue));
    // Error responses carry no data.
    assert!(r.data.is_empty());
}

#[test]
fn honours_response_flags() {
    let mut b = Bench::new(Model::R2D2);
    // Requests-response off: executed, not answered.
    let mut wake = cmd::wake().to_packet(1);
    wake.flags.remove(Flags::REQUESTS_RESPONSE);
    assert!(b.send_packet(&wake).is_empty());
    assert!(b.state().awake, "the command still ran");
    let mut vol = cmd::set_audio_volume(9).to_packet(2);
    vol.flags.remove(Flags::REQUESTS_RESPONSE);
    assert!(b.send_packet(&vol).is_empty());
    assert_eq!(b.state().volume, 9);
    // Errors are not answered either when no response is wanted.
    let mut bad = Packet::command(0x42, 0x01, 3, vec![]);
    bad.flags.remove(Flags::REQUESTS_RESPONSE);
    assert!(b.send_packet(&bad).is_empty());

    // Only-error-response: silence on success...
    let mut ping = cmd::ping().to_packet(4);
    ping.flags.insert(Flags::REQUESTS_ONLY_ERROR_RESPONSE);
    assert!(b.send_packet(&ping).is_empty());
    let mut vol = cmd::set_audio_volume(11).to_packet(5);
    vol.flags.insert(Flags::REQUESTS_ONLY_ERROR_RESPONSE);
    assert!(b.send_packet(&vol).is_empty());
    assert_eq!(b.state().volume, 11);
    // ...an answer on error.
    let mut bad = Packet::command(0x16, 0x07, 6, vec![10, 0x01, 0x68, 0]);
    bad.flags.insert(Flags::REQUESTS_ONLY_ERROR_RESPONSE);
    let r = b.send_packet(&bad);
    assert_eq!(r.len(), 1);
    assert_eq!(
        (r[0].seq, r[0].err),
        (6, Some(ErrorCode::BadParameterValue))
    );
    let mut unknown = Packet::command(0x13, 0x7E, 7, vec![]);
    unknown.flags.insert(Flags::REQUESTS_ONLY_ERROR_RESPONSE);
    assert_eq!(
        b.send_packet(&unknown)[0].err,
        Some(ErrorCode::BadCommandId)
    );
}

#[test]
fn responses_mirror_addressing_and_activity() {
    let mut b = Bench::new(Model::R2D2);
    let mut req = Packet::command(0x13, 0x0D, 0, vec![]);
    req.tid = Some(0x12);
    req.sid = Some(0x01);
    let req = req.normalized();
    let r = b.send_packet(&req).remove(0);
    assert_eq!((r.tid, r.sid), (Some(0x01), Some(0x12)));
    assert!(r.flags.contains(Flags::IS_RESPONSE | Flags::IS_ACTIVITY));
    // The captured wake response (droid-facts.md §2).
    let r = Bench::new(Model::R2D2)
        .send_bytes(&[0x8D, 0x0A, 0x13, 0x0D, 0x00, 0xD5, 0xD8])
        .remove(0);
    assert_eq!(r.encode(), [0x8D, 0x09, 0x13, 0x0D, 0x00, 0x00, 0xD6, 0xD8]);
}

#[test]
fn asleep_until_wake() {
    let mut b = Bench::new(Model::R2D2);
    assert!(!b.state().awake);
    assert_eq!(b.err(drive(100, 0)), ErrorCode::TargetUnavailable);
    assert_eq!(b.err(cmd::play_animation(7)), ErrorCode::TargetUnavailable);
    assert_eq!(
        b.err(cmd::play_audio_file(1915, AudioMode::Immediate)),
        ErrorCode::TargetUnavailable
    );
    assert_eq!(
        b.err(cmd::set_sensor_streaming_mask(100, 0, Mask(mask::LOCATOR))),
        ErrorCode::TargetUnavailable
    );
    // Core, power and system info answer while asleep.
    b.ok(cmd::ping());
    b.ok(cmd::get_battery_voltage());
    b.ok(cmd::get_main_app_version());
    assert!(!b.state().awake, "only Wake wakes it");
    b.ok(cmd::wake());
    assert!(b.state().awake);
    b.ok(drive(100, 0));
    // Sleep puts it back, with a did-sleep notification.
    b.ok(cmd::sleep());
    assert!(!b.state().awake);
    assert_eq!(b.notes_of(0x13, 0x1A).len(), 1);
    assert_eq!(b.err(drive(100, 0)), ErrorCode::TargetUnavailable);
}

#[test]
fn warns_10_s_before_sleeping_on_inactivity() {
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    b.ok(cmd::set_inactivity_timeout(30));
    b.run_for(secs(40.0));
    let will = b.notes_of(0x13, 0x19);
    let did = b.notes_of(0x13, 0x1A);
    assert_eq!(will.len(), 1, "{:?}", b.notes);
    assert_eq!(did.len(), 1);
    assert!(
        will[0].0 >= secs(20.0) && will[0].0 <= secs(20.02),
        "will-sleep at {:?}",
        will[0].0
    );
    assert!(
        did[0].0 >= secs(30.0) && did[0].0 <= secs(30.02),
        "did-sleep at {:?}",
        did[0].0
    );
    assert!(will[0].1.data.is_empty() && did[0].1.data.is_empty());
    assert!(!b.state().awake);
    assert_eq!(b.err(drive(10, 0)), ErrorCode::TargetUnavailable);

    // Activity after the warning keeps it awake (droid-facts.md §2: answer with a ping).
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    b.ok(cmd::set_inactivity_timeout(30));
    b.run_for(secs(25.0));
    assert_eq!(b.notes_of(0x13, 0x19).len(), 1);
    b.ok(cmd::ping());
    b.run_for(secs(10.0));
    assert!(b.state().awake, "a ping at 25 s postpones sleep");
    assert!(b.notes_of(0x13, 0x1A).is_empty());
    b.run_for(secs(25.0));
    let will = b.notes_of(0x13, 0x19);
    let did = b.notes_of(0x13, 0x1A);
    assert_eq!(will.len(), 2);
    assert!(
        close(will[1].0.as_secs_f32(), 45.0, 0.03),
        "{:?}",
        will[1].0
    );
    assert!(close(did[0].0.as_secs_f32(), 55.0, 0.03), "{:?}", did[0].0);
}

fn centivolts(b: &mut Bench) -> u16 {
    let d = b.ok(cmd::get_battery_voltage()).data;
    u16::from_be_bytes([d[0], d[1]])
}

#[test]
fn battery_drains_slowly() {
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    b.ok(cmd::set_inactivity_timeout(3600));
    let v0 = centivolts(&mut b);
    b.run_for(secs(60.0));
    let v1 = centivolts(&mut b);
    b.run_for(secs(540.0));
    let v10 = centivolts(&mut b);
    assert!((380..=420).contains(&v0), "{v0}");
    assert!(v0 - v1 <= 3, "one minute: {v0} → {v1}");
    assert!(v10 < v0, "ten minutes: {v0} → {v10}");
    assert!(
        v0 - v10 <= 50,
        "ten minutes drained {} cV: not slow",
        v0 - v10
    );
    // Driving drains faster than idling.
    let mut idle = Bench::awake_r2_in_tripod();
    idle.ok(cmd::set_inactivity_timeout(3600));
    let mut busy = Bench::awake_r2_in_tripod();
    busy.ok(cmd::set_inactivity_timeout(3600));
    idle.run_for(secs(60.0));
    busy.hold_drive(drive(255, 90), secs(60.0));
    assert!(busy.state().battery_v < idle.state().battery_v);
    // Asleep, the battery holds.
    let mut b = Bench::new(Model::R2D2);
    b.run_for(secs(600.0));
    assert_eq!(b.state().battery_v, SimConfig::default().battery_start_v);
}

#[test]
fn battery_notifications_when_enabled() {
    let fast = SimConfig {
        drain_idle_v_s: 0.02,
        ..SimConfig::default()
    };
    let mut b = Bench::with(Model::R2D2, fast.clone());
    b.ok(cmd::wake());
    b.ok(cmd::enable_battery_state_changed_notify(true));
    b.ok(cmd::enable_battery_voltage_state_change_notify(true));
    b.run_for(secs(60.0));
    let vstate: Vec<(f32, u8)> = b
        .notes_of(0x13, 0x1C)
        .iter()
        .map(|(t, p)| (t.as_secs_f32(), p.data[0]))
        .collect();
    let bstate: Vec<u8> = b
        .notes_of(0x13, 0x06)
        .iter()
        .map(|(_, p)| p.data[0])
        .collect();
    assert_eq!(
        vstate.iter().map(|v| v.1).collect::<Vec<_>>(),
        [2, 3],
        "low then critical"
    );
    // 4.10 V − 0.02 V/s: below 3.6 V after 25 s, below 3.45 V after 32.5 s.
    assert!(close(vstate[0].0, 25.0, 0.1), "{vstate:?}");
    assert!(close(vstate[1].0, 32.5, 0.1), "{vstate:?}");
    assert_eq!(bstate, [4, 5], "battery state low then critical");
    let d = b.ok(cmd::get_battery_voltage_state()).data;
    assert_eq!(d, [3]);
    // Each decodes as the session will see it.
    for (_, p) in b.notes_of(0x13, 0x1C) {
        assert!(matches!(
            Notification::decode(&p, &StreamingConfig::default()),
            Ok(Notification::BatteryVoltageStateChanged(_))
        ));
    }

    // Not enabled: none sent.
    let mut quiet = Bench::with(Model::R2D2, fast);
    quiet.ok(cmd::wake());
    quiet.run_for(secs(60.0));
    assert!(quiet.notes_of(0x13, 0x1C).is_empty() && quiet.notes_of(0x13, 0x06).is_empty());
    assert!(quiet.state().battery_v < 3.45);
}

// ---------------------------------------------------------------------------------------------
// Physics
// ---------------------------------------------------------------------------------------------

#[test]
fn full_speed_is_about_160_cm_s_after_finite_acceleration() {
    let mut b = Bench::awake_r2_in_tripod();
    b.ok(drive(255, 0));
    b.run_for(ms(100));
    let v = b.state().velocity_cm_s;
    assert!(v > 0.0 && v < 30.0, "not instant: {v} cm/s after 100 ms");
    b.run_for(ms(400));
    let v = b.state().velocity_cm_s;
    assert!(v > 50.0 && v < 110.0, "{v} cm/s after 500 ms");
    b.hold_drive(drive(255, 0), ms(1500));
    let v = b.state().velocity_cm_s;
    assert!(close(v, 160.0, 1.0), "top speed {v}");
    // Speed scales with the speed byte.
    let mut half = Bench::awake_r2_in_tripod();
    half.hold_drive(drive(128, 0), ms(2000));
    assert!(
        close(half.state().velocity_cm_s, 80.3, 1.0),
        "{}",
        half.state().velocity_cm_s
    );
}

#[test]
fn heading_0_is_plus_y_and_90_is_plus_x() {
    for (heading, dir) in [
        (0u16, (0.0f32, 1.0f32)),
        (90, (1.0, 0.0)),
        (180, (0.0, -1.0)),
        (270, (-1.0, 0.0)),
    ] {
        let mut b = Bench::awake_r2_in_tripod();
        b.hold_drive(drive(255, heading), ms(2000));
        let (x0, y0) = (b.state().x_cm, b.state().y_cm);
        b.hold_drive(drive(255, heading), ms(1000));
        let (dx, dy) = (b.state().x_cm - x0, b.state().y_cm - y0);
        assert!(
            close(dx, dir.0 * 160.0, 2.0) && close(dy, dir.1 * 160.0, 2.0),
            "heading {heading}: moved ({dx}, {dy}) in 1 s"
        );
        assert!(close(b.state().yaw_deg, heading as f32, 0.01));
    }
}

#[test]
fn heading_turns_at_a_finite_rate() {
    let mut b = Bench::awake_r2_in_tripod();
    b.ok(drive(50, 180));
    b.run_for(ms(250));
    let yaw = b.state().yaw_deg;
    assert!(yaw > 20.0 && yaw < 70.0, "after 250 ms: {yaw}");
    b.run_for(ms(250));
    let yaw = b.state().yaw_deg;
    assert!(yaw > 70.0 && yaw < 110.0, "after 500 ms: {yaw}");
    b.run_for(ms(700));
    assert!(close(b.state().yaw_deg, 180.0, 0.01));
    // The short way round: 180 → 270 turns clockwise, 270 → 10 through 0.
    b.ok(drive(50, 270));
    b.run_for(ms(250));
    assert!(b.state().yaw_deg > 180.0 && b.state().yaw_deg < 270.0);
    b.run_for(ms(500));
    b.ok(drive(50, 10));
    b.run_for(ms(250));
    let yaw = b.state().yaw_deg;
    assert!(yaw > 270.0 && yaw < 360.0, "{yaw}");
    b.run_for(ms(400));
    assert!(close(b.state().yaw_deg, 10.0, 0.01));
}

#[test]
fn reversing_keeps_the_facing() {
    // Backing up: the heading is the direction of travel plus 180 with BACKWARD.
    let mut b = Bench::awake_r2_in_tripod();
    let back = cmd::drive_with_heading(100, Heading::new(180).unwrap(), DriveFlags::BACKWARD);
    b.hold_drive(back, ms(2000));
    let s = b.state();
    assert_eq!(s.yaw_deg, 0.0, "still facing forward");
    assert!(
        s.velocity_cm_s < -50.0 && s.y_cm < -50.0 && s.x_cm.abs() < 0.1,
        "{s:?}"
    );
}

#[test]
fn keeps_rolling_without_its_fail_safe() {
    // Issue 15: a droid whose host never set the control-system timeout keeps its last
    // motion when drive commands stop (the worst case droidctl guards against).
    assert_eq!(SimConfig::default().motion_timeout, None);
    let mut b = Bench::awake_r2_in_tripod();
    b.ok(drive(255, 0));
    b.run_for(ms(5000));
    assert!(b.state().velocity_cm_s > 150.0, "{:?}", b.state());
}

#[test]
fn stops_by_itself_when_drive_commands_stop() {
    let mut b = Bench::awake_r2_in_tripod();
    // The fail-safe droidctl sets on connect (Drive 0x22, 2000 ms).
    b.ok(cmd::set_custom_control_system_timeout(2000));
    b.ok(drive(255, 0));
    b.run_for(ms(1900));
    let before = b.state().velocity_cm_s;
    assert!(before > 150.0, "{before}");
    b.run_for(ms(200));
    assert!(
        b.state().velocity_cm_s < before,
        "braking after the motion timeout"
    );
    b.run_for(ms(600));
    assert_eq!(b.state().velocity_cm_s, 0.0);
    let y = b.state().y_cm;
    b.run_for(ms(1000));
    assert_eq!(b.state().y_cm, y, "stays stopped");

    // With a heartbeat it keeps going.
    let mut b = Bench::awake_r2_in_tripod();
    b.ok(cmd::set_custom_control_system_timeout(2000));
    b.hold_drive(drive(255, 0), ms(4000));
    assert!(close(b.state().velocity_cm_s, 160.0, 1.0));
}

#[test]
fn r2_rolls_only_in_tripod_bb9e_without_legs() {
    let mut b = Bench::open_field(Model::R2D2);
    b.ok(cmd::wake());
    assert_eq!(b.state().stance, LegState::Bipod);
    b.hold_drive(drive(255, 90), ms(2000));
    assert_eq!(
        (b.state().x_cm, b.state().y_cm, b.state().velocity_cm_s),
        (0.0, 0.0, 0.0)
    );
    // Not during the stance change either.
    b.ok(cmd::perform_leg_action(LegAction::Tripod));
    b.hold_drive(drive(255, 90), ms(1500));
    assert_eq!(b.state().x_cm, 0.0, "rolled mid-transition");
    b.run_for(ms(600));
    assert_eq!(b.state().stance, LegState::Tripod);
    b.hold_drive(drive(255, 90), ms(1500));
    assert!(b.state().x_cm > 50.0);
    // Waddle is not rolling either.
    b.ok(cmd::perform_leg_action(LegAction::Bipod));
    b.run_for(ms(3000));
    let x = b.state().x_cm;
    b.hold_drive(drive(255, 90), ms(1000));
    assert_eq!(b.state().x_cm, x);

    let mut bb = Bench::open_field(Model::BB9E);
    bb.ok(cmd::wake());
    bb.hold_drive(drive(255, 90), ms(1500));
    assert!(
        bb.state().x_cm > 50.0 && bb.state().velocity_cm_s > 150.0,
        "{:?}",
        bb.state()
    );
}

#[test]
fn stance_change_takes_about_2_s() {
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    b.ok(cmd::perform_leg_action(LegAction::Tripod));
    let t0 = b.now;
    b.run_for(ms(1000));
    assert_eq!(
        b.ok(cmd::get_leg_action()).data,
        [LegState::Transitioning.to_byte()]
    );
    assert!(b.run_until(secs(3.0), |b| !b.notes_of(0x17, 0x26).is_empty()));
    let done = b.notes_of(0x17, 0x26)[0].0 - t0;
    assert!(
        done >= ms(1900) && done <= ms(2100),
        "leg-action-complete after {done:?}"
    );
    assert_eq!(
        b.ok(cmd::get_leg_action()).data,
        [LegState::Tripod.to_byte()]
    );
    // Back to two legs, again ~2 s.
    b.ok(cmd::perform_leg_action(LegAction::Bipod));
    let t1 = b.now;
    assert!(b.run_until(secs(3.0), |b| b.notes_of(0x17, 0x26).len() == 2));
    let done = b.notes_of(0x17, 0x26)[1].0 - t1;
    assert!(done >= ms(1900) && done <= ms(2100), "{done:?}");
    assert_eq!(b.state().stance, LegState::Bipod);
    // An unknown leg action is a bad parameter.
    let r = b
        .send_packet(&Packet::command(0x17, 0x0D, 100, vec![9]))
        .remove(0);
    assert_eq!(r.err, Some(ErrorCode::BadParameterValue));
}

#[test]
fn dome_moves_at_a_finite_rate_and_is_clamped() {
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    b.ok(head(90.0));
    b.run_for(ms(250));
    let h = b.state().head_deg;
    assert!(h > 20.0 && h < 70.0, "after 250 ms: {h}");
    b.run_for(ms(500));
    assert_eq!(b.state().head_deg, 90.0);
    let read = b.ok(cmd::get_head_position()).data;
    assert_eq!(f32s(&read), [90.0]);
    // Out-of-range targets (sent raw: the typed constructor cannot make them) are clamped.
    b.ok(Command::new(0x17, 0x0F, 500.0f32.to_be_bytes().to_vec()));
    b.run_for(ms(1500));
    assert_eq!(b.state().head_deg, 180.0);
    b.ok(Command::new(0x17, 0x0F, (-500.0f32).to_be_bytes().to_vec()));
    b.run_for(ms(1000));
    let h = b.state().head_deg;
    assert!(h > -160.0 && h < 180.0, "still moving: {h}");
    b.run_for(ms(1500));
    assert_eq!(b.state().head_deg, -160.0);
    assert_eq!(
        b.err(Command::new(0x17, 0x0F, f32::NAN.to_be_bytes().to_vec())),
        ErrorCode::BadParameterValue
    );
    // BB-9E has no dome.
    let mut bb = Bench::new(Model::BB9E);
    bb.ok(cmd::wake());
    assert_eq!(bb.err(head(10.0)), ErrorCode::BadCommandId);
}

// ---------------------------------------------------------------------------------------------
// Sensor streaming
// ---------------------------------------------------------------------------------------------

#[test]
fn sensor_streaming_follows_the_mask_rules() {
    let mut b = Bench::awake_r2_in_tripod();
    b.ok(head(90.0));
    // Yaw (bit 16), locator x/y (6, 5), core time (1); extended head angle (26), gyro z (23).
    let std_mask = 0x0001_0000 | mask::LOCATOR | 0x0000_0002;
    let ext_mask = mask::EXT_HEAD_ANGLE | 0x0080_0000;
    // The reference sequence: mask with interval 0, extended mask, mask with the interval.
    b.ok(cmd::set_sensor_streaming_mask(0, 0, Mask(std_mask)));
    b.ok(cmd::set_extended_sensor_streaming_mask(Mask(ext_mask)));
    b.run_for(ms(500));
    assert!(
        b.notes_of(0x18, 0x02).is_empty(),
        "interval 0 streams nothing"
    );
    b.ok(cmd::set_sensor_streaming_mask(100, 0, Mask(std_mask)));
    let t_on = b.now;
    b.ok(drive(200, 90));
    // Check every sample against the state at the moment it was sent.
    let mut checked = 0;
    let end = b.now + secs(1.5);
    while b.now < end {
        let before = b.notes.len();
        b.run_for(STEP);
        for (t, p) in &b.notes[before..] {
            if (p.did, p.cid) != (0x18, 0x02) {
                continue;
            }
            let s = b.state();
            let v = f32s(&p.data);
            assert_eq!(p.data.len(), 6 * 4);
            // Standard fields in descending bit order, then extended ones, descending.
            let yaw = if s.yaw_deg > 180.0 {
                s.yaw_deg - 360.0
            } else {
                s.yaw_deg
            };
            assert_eq!(v[0], yaw, "yaw");
            assert!(
                close(v[1] * 100.0, s.x_cm, 0.01),
                "locator x {} vs {}",
                v[1] * 100.0,
                s.x_cm
            );
            assert!(close(v[2] * 100.0, s.y_cm, 0.01), "locator y");
            assert_eq!(v[3], t.as_millis() as f32, "core time");
            assert_eq!(v[4], s.head_deg, "head angle");
            assert!(v[5].abs() <= 181.0, "gyro z {}", v[5]);
            checked += 1;
        }
    }
    let samples = b.notes_of(0x18, 0x02);
    assert_eq!(checked, samples.len());
    assert_eq!(samples.len(), 15, "every 100 ms for 1.5 s");
    assert_eq!(samples[0].0 - t_on, ms(100));
    assert!(samples.windows(2).all(|w| w[1].0 - w[0].0 == ms(100)));
    // While turning toward 90 the gyro shows the turn rate.
    let first = f32s(&samples[1].1.data);
    // (The streamed rate is low-pass filtered as an IMU's is, τ = 0.1 s, src/sim/body.rs:
    // 0.2 s into the turn it shows ~86 % of 180°/s, and never more.)
    assert!(
        (150.0..=180.5).contains(&first[5]),
        "turning at 180°/s: {first:?}"
    );
    // The last sample: moving along +x, facing 90, dome at 90.
    let last = f32s(&samples.last().unwrap().1.data);
    assert!(close(last[0], 90.0, 0.01) && last[4] == 90.0, "{last:?}");
    assert!(last[1] > 0.5);

    // Decoding with the same masks gives the named, scaled values.
    let cfg = StreamingConfig {
        mask: std_mask,
        ext_mask,
        interval_ms: 100,
    };
    let Ok(Notification::Sensors(s)) = Notification::decode(&samples.last().unwrap().1, &cfg)
    else {
        panic!()
    };
    let names: Vec<&str> = s.values.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        [
            "yaw",
            "locator_x",
            "locator_y",
            "core_time",
            "head_angle",
            "gyro_z"
        ]
    );

    // A new interval is honoured.
    b.ok(cmd::set_sensor_streaming_mask(250, 0, Mask(std_mask)));
    b.notes.clear();
    b.run_for(ms(1000));
    let times: Vec<Duration> = b.notes_of(0x18, 0x02).iter().map(|(t, _)| *t).collect();
    assert_eq!(times.len(), 4);
    assert!(times.windows(2).all(|w| w[1] - w[0] == ms(250)));
    // The mask with interval 0 stops it.
    b.ok(cmd::set_sensor_streaming_mask(0, 0, Mask(std_mask)));
    b.notes.clear();
    b.run_for(ms(2000));
    assert!(b.notes_of(0x18, 0x02).is_empty());
}

#[test]
fn full_streaming_set_matches_physics() {
    let mut b = Bench::awake_r2_in_tripod();
    let cfg = StreamingConfig::full(100);
    b.ok(cmd::set_sensor_streaming_mask(0, 0, Mask(cfg.mask)));
    b.ok(cmd::set_extended_sensor_streaming_mask(Mask(cfg.ext_mask)));
    b.ok(cmd::set_sensor_streaming_mask(100, 0, Mask(cfg.mask)));
    b.ok(head(-45.0));
    b.hold_drive(drive(160, 135), ms(2000));
    let (_, p) = b.notes_of(0x18, 0x02).pop().unwrap();
    let Ok(Notification::Sensors(s)) = Notification::decode(&p, &cfg) else {
        panic!()
    };
    assert_eq!(s.values.len(), cfg.value_count());
    let st = b.state().clone();
    // The last sample is at most one interval old.
    let v = st.velocity_cm_s;
    let tol = v.abs() * 0.1 + 0.5;
    assert!(close(s.get("locator_x").unwrap(), st.x_cm, tol));
    assert!(close(s.get("locator_y").unwrap(), st.y_cm, tol));
    assert!(close(s.get("yaw").unwrap(), 135.0, 0.01));
    assert_eq!(s.get("head_angle"), Some(-45.0));
    let (vx, vy) = (s.get("velocity_x").unwrap(), s.get("velocity_y").unwrap());
    // Heading 135: +x and −y.
    assert!(
        vx > 0.0 && vy < 0.0 && close((vx * vx + vy * vy).sqrt(), v, 1.0),
        "{vx} {vy} {v}"
    );
    assert!(close(s.get("accel_z").unwrap(), 1.0, 0.01));
}

// ---------------------------------------------------------------------------------------------
// The room, collisions, animations, sounds
// ---------------------------------------------------------------------------------------------

fn drive_into_wall(heading: u16, notify: bool) -> Bench {
    let mut b = Bench::new(Model::R2D2);
    let cfg = SimConfig::default();
    assert_eq!(cfg.room_cm, (400.0, 400.0));
    assert_eq!(
        (b.state().x_cm, b.state().y_cm),
        (0.0, 0.0),
        "starts in the middle"
    );
    b.ok(cmd::wake());
    b.ok(cmd::perform_leg_action(LegAction::Tripod));
    b.run_for(ms(2100));
    if notify {
        b.ok(cmd::enable_collision_detected_notify(true));
    }
    let mut hit = false;
    for _ in 0..10 {
        b.ok(drive(255, heading));
        if b.run_until(ms(500), |b| b.state().collisions > 0) {
            hit = true;
            break;
        }
    }
    assert!(hit, "never reached the wall: {:?}", b.state());
    b
}

#[test]
fn walls_stop_the_droid_with_a_collision_notification() {
    let wall = 200.0 - SimConfig::default().radius_cm;
    for heading in [90u16, 0, 270, 180] {
        let mut b = drive_into_wall(heading, true);
        let t_hit = b.now;
        let s = b.state().clone();
        // Along the direction of travel it is at the wall (minus its radius); a turn on the
        // way may have moved it sideways.
        let reached = match heading {
            90 => s.x_cm,
            0 => s.y_cm,
            270 => -s.x_cm,
            _ => -s.y_cm,
        };
        assert!(close(reached, wall, 0.01), "heading {heading}: {s:?}");
        assert!(s.x_cm.abs() <= wall && s.y_cm.abs() <= wall);
        assert_eq!(s.velocity_cm_s, 0.0);
        let notes = b.notes_of(0x18, 0x12);
        assert_eq!(notes.len(), 1);
        let (at, p) = &notes[0];
        assert_eq!(p.data.len(), 18, "18 bytes, not the seed's 17");
        let c = Collision::decode(&p.data).unwrap();
        // In the robot's axes (issue 32 point 2): head-on is on its forward axis, y, braking,
        // whichever wall it is (it used to be x at the east and west walls).
        assert_eq!(
            (c.axis.x, c.axis.y),
            (false, true),
            "heading {heading}: {c:?}"
        );
        assert!(c.accel[1].g() < -1.0, "braking ahead: {c:?}");
        assert!(c.accel[0].g().abs() < 0.2, "nothing across: {c:?}");
        assert!(
            c.power[1] > 0 && c.power[0].abs() < c.power[1] / 10,
            "{c:?}"
        );
        assert!(c.speed > 200, "hit at full speed: {}", c.speed);
        assert_eq!(c.time_ms as u128, at.as_millis());
        // It stays stopped (no more drive commands) and reports nothing more.
        b.run_for(ms(1500));
        let s2 = b.state();
        assert_eq!((s2.x_cm, s2.y_cm, s2.velocity_cm_s), (s.x_cm, s.y_cm, 0.0));
        assert_eq!(b.notes_of(0x18, 0x12).len(), 1);
        assert_eq!(s2.collisions, 1);
        assert!(b.now > t_hit);
    }
}

#[test]
fn no_collision_notification_unless_enabled() {
    let mut b = drive_into_wall(90, false);
    b.run_for(ms(500));
    assert_eq!(b.state().collisions, 1, "the collision happened");
    assert!(b.notes_of(0x18, 0x12).is_empty(), "but was not reported");
    // Configure Collision Detection with a method turns the notification on too.
    let mut b = Bench::new(Model::BB9E);
    b.ok(cmd::wake());
    b.ok(cmd::configure_collision_detection(
        droidctl::protocol::v2::wire::CollisionMethod::Accelerometer,
        100,
        100,
        100,
        100,
        10,
    ));
    for _ in 0..10 {
        b.ok(drive(255, 0));
        if b.run_until(ms(500), |b| b.state().collisions > 0) {
            break;
        }
    }
    assert_eq!(b.notes_of(0x18, 0x12).len(), 1);
}

#[test]
fn animation_completes_with_a_notification() {
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    b.ok(cmd::play_animation(7));
    let t0 = b.now;
    assert!(b.state().animation_playing);
    assert!(b.run_until(secs(10.0), |b| !b.notes_of(0x17, 0x11).is_empty()));
    let took = b.notes_of(0x17, 0x11)[0].0 - t0;
    assert!(
        took >= secs(1.0) && took <= secs(6.0),
        "animation took {took:?}"
    );
    assert!(!b.state().animation_playing);
    // Stopped early: no completion.
    b.ok(cmd::play_animation(8));
    b.run_for(ms(500));
    b.ok(cmd::stop_animation());
    b.run_for(secs(5.0));
    assert_eq!(b.notes_of(0x17, 0x11).len(), 1);
    // BB-9E plays animations too.
    let mut bb = Bench::new(Model::BB9E);
    bb.ok(cmd::wake());
    bb.ok(cmd::play_animation(3));
    assert!(bb.run_until(secs(10.0), |b| !b.notes_of(0x17, 0x11).is_empty()));
}

#[test]
fn sound_modes() {
    let play = |b: &mut Bench, mode| b.ok(cmd::play_audio_file(1915, mode));
    let sound_time = SimConfig::default().sound_time;
    assert_eq!(sound_time, ms(1500));

    // If idle: ignored while another sound plays.
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    play(&mut b, AudioMode::Immediate);
    assert!(b.state().sound_playing);
    b.run_for(ms(500));
    play(&mut b, AudioMode::IfIdle);
    b.run_for(ms(1100));
    assert!(
        !b.state().sound_playing,
        "the if-idle sound was ignored: done at 1.5 s"
    );
    // ...and played when idle.
    play(&mut b, AudioMode::IfIdle);
    assert!(b.state().sound_playing);

    // After current: queued behind the playing one.
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    play(&mut b, AudioMode::Immediate);
    b.run_for(ms(500));
    play(&mut b, AudioMode::AfterCurrent);
    b.run_for(ms(1100));
    assert!(b.state().sound_playing, "the queued sound follows");
    b.run_for(ms(1300));
    assert!(b.state().sound_playing);
    b.run_for(ms(200));
    assert!(!b.state().sound_playing, "both done at 3 s");

    // Immediate: restarts at once.
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    play(&mut b, AudioMode::Immediate);
    b.run_for(ms(500));
    play(&mut b, AudioMode::Immediate);
    b.run_for(ms(1100));
    assert!(b.state().sound_playing);
    b.run_for(ms(500));
    assert!(!b.state().sound_playing);

    // Stop all audio drops the queue too.
    let mut b = Bench::new(Model::R2D2);
    b.ok(cmd::wake());
    play(&mut b, AudioMode::Immediate);
    play(&mut b, AudioMode::AfterCurrent);
    b.ok(cmd::stop_all_audio());
    assert!(!b.state().sound_playing);
    b.run_for(ms(2000));
    assert!(!b.state().sound_playing);
}

#[test]
fn corrupt_bytes_are_rejected_by_the_droid() {
    let mut b = Bench::new(Model::R2D2);
    let mut wire = cmd::wake().to_packet(0).encode();
    wire[3] ^= 0x40;
    assert!(b.send_bytes(&wire).is_empty());
    assert!(!b.state().awake);
    assert_eq!(b.state().decode_errors, 1);
    // And the stream resynchronises: a good packet split in two still works.
    let wire = cmd::wake().to_packet(1).encode();
    assert!(b.send_bytes(&wire[..3]).is_empty());
    assert_eq!(b.send_bytes(&wire[3..]).len(), 1);
    assert!(b.state().awake);
}

// ---------------------------------------------------------------------------------------------
// SimLink: fault injection, end to end
// ---------------------------------------------------------------------------------------------

/// What came out of a raw SimLink connection: (time since open, piece) and the disconnect.
struct Capture {
    pieces: Vec<(Duration, Vec<u8>)>,
    disconnected: Option<Duration>,
}

/// Open a link, write a wake, full streaming at 50 ms and a few requests (each twice, in case a
/// fault eats one), and record every piece that arrives for `dur`.
async fn capture(faults: Faults, dur: Duration) -> Capture {
    let mut link = SimLink::new(Model::R2D2, SimConfig::default(), faults);
    let t0 = Instant::now();
    let conn = link.open().await.expect("open");
    let mut writer = conn.writer;
    let mut events = conn.events;
    let cfg = StreamingConfig::full(50);
    let cmds = [
        cmd::wake(),
        cmd::set_sensor_streaming_mask(0, 0, Mask(cfg.mask)),
        cmd::set_extended_sensor_streaming_mask(Mask(cfg.ext_mask)),
        cmd::set_sensor_streaming_mask(50, 0, Mask(cfg.mask)),
        cmd::get_battery_voltage(),
        cmd::get_bluetooth_info(),
    ];
    let sender = tokio::spawn(async move {
        for (i, c) in cmds.iter().chain(cmds.iter()).enumerate() {
            for chunk in c.to_packet(i as u8).encode().chunks(20) {
                if writer.write(chunk).await.is_err() {
                    return;
                }
                sleep(ms(120)).await;
            }
        }
        // Keep the connection open.
        sleep(Duration::from_secs(3600)).await;
        drop(writer);
    });
    let mut out = Capture {
        pieces: Vec::new(),
        disconnected: None,
    };
    let end = t0 + dur;
    while let Ok(ev) = tokio::time::timeout_at(end, events.recv()).await {
        match ev {
            Some(LinkEvent::Data(b)) => out.pieces.push((t0.elapsed(), b)),
            Some(LinkEvent::Disconnected(_)) => {
                out.disconnected = Some(t0.elapsed());
                break;
            }
            None => break,
        }
    }
    sender.abort();
    out
}

fn decode_stream(pieces: &[(Duration, Vec<u8>)]) -> (Vec<Packet>, usize) {
    let mut d = Decoder::new();
    let mut packets = Vec::new();
    let mut errors = 0;
    for (_, b) in pieces {
        for r in d.feed(b) {
            match r {
                Ok(p) => packets.push(p),
                Err(_) => errors += 1,
            }
        }
    }
    (packets, errors)
}

fn noisy(seed: u64) -> Faults {
    Faults {
        seed,
        split: true,
        drop_rate: 0.005,
        corrupt_rate: 0.01,
        latency: ms(15),
        jitter: ms(20),
        ..Faults::none()
    }
}

#[tokio::test(start_paused = true)]
async fn same_seed_same_bytes_different_seed_different_bytes() {
    let a = capture(noisy(7), secs(5.0)).await;
    let b = capture(noisy(7), secs(5.0)).await;
    let c = capture(noisy(8), secs(5.0)).await;
    assert!(a.pieces.len() > 100, "{} pieces", a.pieces.len());
    assert_eq!(
        a.pieces, b.pieces,
        "same seed: identical stream, piece boundaries and times"
    );
    assert_ne!(a.pieces, c.pieces);
    let bytes = |c: &Capture| {
        c.pieces
            .iter()
            .flat_map(|(_, b)| b.clone())
            .collect::<Vec<u8>>()
    };
    assert_ne!(
        bytes(&a),
        bytes(&c),
        "different seed: different bytes, not only timing"
    );
    // The faults were real: the host's decoder sees errors, and still most packets.
    let (packets, errors) = decode_stream(&a.pieces);
    assert!(errors > 0);
    assert!(packets.len() > 50);
}

#[tokio::test(start_paused = true)]
async fn split_pieces_are_at_most_20_bytes_and_lose_nothing() {
    let split = capture(
        Faults {
            seed: 3,
            split: true,
            ..Faults::none()
        },
        secs(3.0),
    )
    .await;
    let whole = capture(
        Faults {
            seed: 3,
            ..Faults::none()
        },
        secs(3.0),
    )
    .await;
    assert!(
        split
            .pieces
            .iter()
            .all(|(_, p)| !p.is_empty() && p.len() <= 20)
    );
    assert!(
        whole
            .pieces
            .iter()
            .all(|(_, p)| !p.is_empty() && p.len() <= 20)
    );
    // Split pieces cut packets at random points, so many are smaller than any packet.
    assert!(split.pieces.iter().filter(|(_, p)| p.len() < 7).count() > 10);
    // Without split, one notification per packet: each starts a packet unless it continues
    // one longer than 20 bytes.
    assert!(
        whole
            .pieces
            .windows(2)
            .all(|w| w[1].1[0] == 0x8D || w[0].1.len() == 20)
    );
    assert!(split.pieces.len() > whole.pieces.len());
    // The same packets come through either way, without a single decode error.
    let (a, ea) = decode_stream(&split.pieces);
    let (b, eb) = decode_stream(&whole.pieces);
    assert_eq!((ea, eb), (0, 0));
    assert!(a.len() > 50);
    assert_eq!(a, b);
}

async fn session_decode_errors(faults: Faults) -> droidctl::session::SessionStats {
    let link = SimLink::new(Model::R2D2, SimConfig::default(), faults);
    let config = SessionConfig {
        setup: connect_setup(Model::R2D2, &SetupOptions::default()),
        ..SessionConfig::default()
    };
    let s = session::start(Box::new(link), config);
    sleep(secs(20.0)).await;
    let st = s.stats();
    s.shutdown(vec![]).await;
    st
}

#[tokio::test(start_paused = true)]
async fn corruption_and_drops_show_as_decode_errors() {
    let clean = session_decode_errors(Faults::none()).await;
    assert_eq!((clean.decode_errors, clean.errors), (0, 0), "{clean:?}");
    assert!(
        clean.received > 150,
        "streaming at 100 ms for 20 s: {clean:?}"
    );
    let corrupt = session_decode_errors(Faults {
        seed: 1,
        corrupt_rate: 0.02,
        ..Faults::none()
    })
    .await;
    assert!(corrupt.decode_errors > 0, "{corrupt:?}");
    let dropped = session_decode_errors(Faults {
        seed: 2,
        drop_rate: 0.02,
        ..Faults::none()
    })
    .await;
    assert!(dropped.decode_errors > 0, "{dropped:?}");
}

#[tokio::test(start_paused = true)]
async fn latency_delays_delivery() {
    async fn first_response_after(faults: Faults) -> Duration {
        let mut link = SimLink::new(Model::R2D2, SimConfig::default(), faults);
        let mut conn = link.open().await.unwrap();
        let t0 = Instant::now();
        conn.writer
            .write(&cmd::ping().to_packet(0).encode())
            .await
            .unwrap();
        match conn.events.recv().await {
            Some(LinkEvent::Data(b)) => {
                assert_eq!(b, [0x8D, 0x09, 0x00, 0x01, 0x00, 0x00, 0xF5, 0xD8])
            }
            other => panic!("{other:?}"),
        }
        t0.elapsed()
    }
    let direct = first_response_after(Faults::none()).await;
    assert!(direct < ms(5), "{direct:?}");
    let slow = first_response_after(Faults {
        latency: ms(200),
        ..Faults::none()
    })
    .await;
    // 200 ms each way.
    assert!(slow >= ms(400) && slow < ms(405), "{slow:?}");
    for seed in 0..5 {
        let jittery = first_response_after(Faults {
            seed,
            latency: ms(200),
            jitter: ms(100),
            ..Faults::none()
        })
        .await;
        assert!(jittery >= ms(400) && jittery <= ms(605), "{jittery:?}");
    }
}

#[tokio::test(start_paused = true)]
async fn disconnect_at_drops_the_link_at_that_time() {
    let faults = Faults {
        disconnect_at: vec![secs(3.0), secs(5.0)],
        ..Faults::none()
    };
    let c = capture(faults.clone(), secs(10.0)).await;
    assert_eq!(c.disconnected, Some(secs(3.0)));
    assert!(!c.pieces.is_empty());

    // Through a session: it reconnects after each drop.
    let link = SimLink::new(Model::R2D2, SimConfig::default(), faults);
    let probe = link.probe();
    let t0 = Instant::now();
    let s = session::start(Box::new(link), SessionConfig::default());
    let mut states = s.watch_state();
    let mut changes = Vec::new();
    while t0.elapsed() < secs(8.0) {
        if timeout(secs(8.0), states.changed()).await.is_err() {
            break;
        }
        let st = states.borrow_and_update().clone();
        changes.push((t0.elapsed(), st.label()));
    }
    let drops: Vec<Duration> = changes
        .iter()
        .filter(|(_, l)| l.starts_with("reconnecting"))
        .map(|(t, _)| *t)
        .collect();
    assert_eq!(drops, [secs(3.0), secs(5.0)], "{changes:?}");
    assert_eq!(s.state(), LinkState::Connected);
    assert_eq!(s.stats().reconnects, 2);
    assert_eq!(probe.opens(), 3);
    assert!(probe.connected());
}

#[tokio::test(start_paused = true)]
async fn failed_opens_follow_the_backoff() {
    let link = SimLink::new(
        Model::R2D2,
        SimConfig::default(),
        Faults {
            fail_opens: 3,
            ..Faults::none()
        },
    );
    let probe = link.probe();
    let t0 = Instant::now();
    let s = session::start(Box::new(link), SessionConfig::default());
    s.watch_state()
        .wait_for(|st| *st == LinkState::Connected)
        .await
        .unwrap();
    // Attempts at 0, 0.5, 1.5 and 3.5 s.
    assert_eq!(t0.elapsed(), secs(3.5));
    assert_eq!(probe.opens(), 4);
    s.request(cmd::ping()).await.unwrap();
}

/// Wait for the next sensor sample on the session.
async fn next_sample(
    rx: &mut tokio::sync::broadcast::Receiver<SessionEvent>,
) -> droidctl::protocol::v2::SensorSample {
    loop {
        match timeout(secs(1.0), rx.recv())
            .await
            .expect("a sample")
            .expect("open")
        {
            SessionEvent::Notification(Notification::Sensors(s)) => return s,
            _ => continue,
        }
    }
}

async fn r2_session(faults: Faults) -> (SessionHandle, droidctl::sim::link::SimProbe) {
    let link = SimLink::new(Model::R2D2, SimConfig::default(), faults);
    let probe = link.probe();
    let config = SessionConfig {
        setup: connect_setup(Model::R2D2, &SetupOptions::default()),
        ..SessionConfig::default()
    };
    let s = session::start(Box::new(link), config);
    (s, probe)
}

#[tokio::test(start_paused = true)]
async fn end_to_end_telemetry_matches_the_droid() {
    let (s, probe) = r2_session(Faults::none()).await;
    let mut rx = s.subscribe();
    // Setup puts R2 in tripod; wait for it.
    sleep(secs(3.5)).await;
    assert_eq!(probe.state().stance, LegState::Tripod);
    s.set(Slot::Head, head(60.0));
    for _ in 0..15 {
        s.set(Slot::Drive, drive(200, 45));
        sleep(ms(100)).await;
    }
    s.set(Slot::Drive, drive(0, 45));
    sleep(secs(2.0)).await;
    let st = probe.state();
    assert_eq!(st.velocity_cm_s, 0.0);
    assert!(
        st.x_cm > 50.0 && close(st.x_cm, st.y_cm, 5.0),
        "heading 45: {st:?}"
    );
    // Skip what was buffered; take a fresh sample.
    loop {
        match rx.try_recv() {
            Err(tokio::sync::broadcast::error::TryRecvError::Empty) => break,
            Err(tokio::sync::broadcast::error::TryRecvError::Closed) => panic!("closed"),
            _ => {}
        }
    }
    let sample = next_sample(&mut rx).await;
    let st = probe.state();
    assert!(
        close(sample.get("locator_x").unwrap(), st.x_cm, 0.05),
        "{sample:?} vs {st:?}"
    );
    assert!(close(sample.get("locator_y").unwrap(), st.y_cm, 0.05));
    assert!(close(sample.get("yaw").unwrap(), 45.0, 0.01));
    assert_eq!(sample.get("head_angle"), Some(60.0));
    assert_eq!(st.head_deg, 60.0);
    s.shutdown(vec![drive(0, 45).into()]).await;
}

#[tokio::test(start_paused = true)]
async fn end_to_end_every_catalogue_command_through_a_session() {
    // One client paces R2-D2 writes at 12 ms (droid-facts.md §1). BOLT and RVR get each
    // command addressed by the session's codec to the processor that has it.
    for model in [Model::R2D2, Model::Bolt, Model::Rvr] {
        let config = SessionConfig {
            pacing: ms(12),
            model: Some(model),
            ..SessionConfig::default()
        };
        let link = SimLink::new(model, SimConfig::default(), Faults::none());
        let s = session::start(Box::new(link), config);
        for def in catalog::commands() {
            if !model_knows(model, def.did, def.cid) {
                continue;
            }
            s.request(cmd::wake()).await.unwrap();
            let c = Command::new(def.did, def.cid, valid_payload(model, def));
            let r = s
                .request(c)
                .await
                .unwrap_or_else(|e| panic!("{model:?} {}: {e}", def.name));
            let r = r.as_v2().unwrap();
            if model != Model::R2D2 && (def.did, def.cid) == (0x00, 0x01) {
                // The newer robots are pinged with API and Shell's Echo.
                assert_eq!((r.did, r.cid), (0x10, 0x00));
                continue;
            }
            assert_eq!((r.did, r.cid), (def.did, def.cid));
            assert!(
                catalog::decode_fields(def.response, &r.data).is_ok(),
                "{model:?} {}",
                def.name
            );
        }
        let st = s.stats();
        assert_eq!(
            (st.timeouts, st.errors, st.unmatched),
            (0, 0, 0),
            "{model:?}"
        );
    }
}

#[tokio::test(start_paused = true)]
async fn shutdown_stop_reaches_the_simulated_droid() {
    let (s, probe) = r2_session(Faults::none()).await;
    sleep(secs(3.5)).await;
    // 1.2 s toward +y at half speed: far enough from the wall that only the stop can stop it.
    for _ in 0..12 {
        s.set(Slot::Drive, drive(128, 0));
        sleep(ms(100)).await;
    }
    assert!(probe.state().velocity_cm_s > 70.0, "{:?}", probe.state());
    // The stop is the last thing written before the link closes: it must still arrive (the
    // droid's own motion timeout would only stop it after 2 s).
    s.shutdown(vec![drive(0, 0).into()]).await;
    assert!(!probe.connected());
    sleep(ms(700)).await;
    let st = probe.state();
    assert_eq!(st.velocity_cm_s, 0.0, "{st:?}");
    assert_eq!(st.collisions, 0, "stopped by the stop, not by a wall");
}

/// Issue 19 point 3: BOLT's and RVR's processors are honoured: a command sent to the
/// processor that has it is answered, to the other one it gets the robot's bad-command
/// error, to a target that is no processor bad-target; RVR takes nothing without a target;
/// Mini, with one processor, takes no target at all.
#[test]
fn processor_targets_are_honoured() {
    let err = |model: Model, did: u8, cid: u8, tid: Option<u8>, data: Vec<u8>| {
        let mut b = Bench::new(model);
        b.send_packet(&addressed_packet(model, 0x13, 0x0D, 1, vec![]));
        let mut c = Command::new(did, cid, data);
        c.target = tid;
        b.send_packet(&c.to_packet(5)).remove(0).err
    };
    let drive = || vec![50, 0, 90, 0];
    assert_eq!(
        err(Model::Bolt, 0x16, 0x07, Some(0x12), drive()),
        Some(ErrorCode::Success)
    );
    assert_eq!(
        err(Model::Bolt, 0x16, 0x07, Some(0x11), drive()),
        Some(ErrorCode::BadCommandId)
    );
    assert_eq!(
        err(Model::Bolt, 0x16, 0x07, Some(0x15), drive()),
        Some(ErrorCode::BadTargetId)
    );
    assert_eq!(
        err(Model::Bolt, 0x16, 0x07, None, drive()),
        Some(ErrorCode::Success)
    );
    // The matrix is the secondary's, the front/back LEDs the primary's.
    assert_eq!(
        err(Model::Bolt, 0x1A, 0x2F, Some(0x11), vec![1, 2, 3]),
        Some(ErrorCode::BadCommandId)
    );
    assert_eq!(
        err(Model::Bolt, 0x1A, 0x1C, Some(0x11), vec![1, 9]),
        Some(ErrorCode::Success)
    );
    assert_eq!(
        err(Model::Rvr, 0x16, 0x07, None, drive()),
        Some(ErrorCode::BadTargetId)
    );
    assert_eq!(
        err(Model::Rvr, 0x16, 0x07, Some(0x12), drive()),
        Some(ErrorCode::Success)
    );
    // RVR's colour sensor is the primary's; the streaming service runs on both.
    assert_eq!(
        err(Model::Rvr, 0x18, 0x38, Some(0x12), vec![1]),
        Some(ErrorCode::BadCommandId)
    );
    assert_eq!(
        err(Model::Rvr, 0x18, 0x38, Some(0x11), vec![1]),
        Some(ErrorCode::Success)
    );
    assert_eq!(
        err(Model::Rvr, 0x18, 0x3B, Some(0x12), vec![]),
        Some(ErrorCode::Success)
    );
    assert_eq!(
        err(Model::Rvr, 0x18, 0x3B, Some(0x11), vec![]),
        Some(ErrorCode::Success)
    );
    assert_eq!(
        err(Model::Mini, 0x16, 0x07, Some(0x12), drive()),
        Some(ErrorCode::BadTargetId)
    );
    assert_eq!(
        err(Model::Mini, 0x16, 0x07, None, drive()),
        Some(ErrorCode::Success)
    );
}

/// Issue 19 point 3: RVR's streaming service as the robot runs it: a configuration per token
/// and processor (at most four sensors), started with a period, data from the processor that
/// measures them, no reconfiguration while streaming, stopped and cleared.
#[test]
fn rvr_streaming_service_streams_named_values() {
    use droidctl::protocol::v2::catalog::targets::Processor;
    use droidctl::protocol::v2::stream::{ServiceConfig, decode};
    let mut b = Bench::new(Model::Rvr);
    let to = |c: Command, p: Processor| c.to(p);
    b.ok(to(cmd::wake(), Processor::Primary));
    let config = to(
        Command::new(0x18, 0x39, vec![1, 0, 1, 2, 0, 6, 2]),
        Processor::Secondary,
    );
    b.ok(config.clone());
    b.ok(to(cmd::start_streaming_service(100), Processor::Secondary));
    // No reconfiguration while streaming.
    let busy = to(
        Command::new(0x18, 0x39, vec![2, 0, 7, 2]),
        Processor::Secondary,
    );
    assert_eq!(b.err(busy), ErrorCode::Busy);
    b.ok(to(
        cmd::drive_with_heading(100, Heading::new(90).unwrap(), DriveFlags::empty()),
        Processor::Secondary,
    ));
    b.notes.clear();
    b.run_for(ms(1000));
    let out: Vec<Packet> = b.notes.iter().map(|(_, p)| p.clone()).collect();
    let mut host = ServiceConfig::default();
    host.snoop(&config);
    let data: Vec<_> = out
        .iter()
        .filter(|p| (p.did, p.cid) == (0x18, 0x3D))
        .collect();
    assert!(
        (8..=11).contains(&data.len()),
        "every 100 ms: {}",
        data.len()
    );
    assert!(
        data.iter().all(|p| p.sid == Some(0x12)),
        "from the secondary"
    );
    let last = decode(
        &host,
        Some(Processor::Secondary),
        &data[data.len() - 1].data,
    )
    .unwrap();
    assert!((last.get("yaw").unwrap() - 90.0).abs() < 1.0, "{last:?}");
    assert!(last.get("locator_x").unwrap() > 5.0, "{last:?}");
    b.ok(to(cmd::stop_streaming_service(), Processor::Secondary));
    b.notes.clear();
    b.run_for(ms(500));
    assert!(b.notes.iter().all(|(_, p)| (p.did, p.cid) != (0x18, 0x3D)));
    b.ok(to(
        Command::new(0x18, 0x39, vec![2, 0, 7, 2]),
        Processor::Secondary,
    ));
}
