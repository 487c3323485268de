//! The simulated Sphero API v1 droid (BB-8, SPRK+, Ollie): protocol behaviour, physics and
//! async messages with explicit times, then end to end through [`SimLink`] and a session
//! under paused tokio time (`droid-facts.md` §4, `sphero-v1-packets.md`).

use droidctl::family::Command as AnyCommand;
use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::model::{Model, Protocol};
use droidctl::protocol::v1::catalog;
use droidctl::protocol::v1::sensor::mask;
use droidctl::protocol::v1::{
    AsyncPacket, Command, CommandPacket, Decoder, Mrsp, Notification, Packet, Response, RollState,
    Source, StreamingConfig, cmd, decode_async,
};
use droidctl::session::{
    self, Direction, LinkState, LogEntry, LogItem, SessionConfig, SessionEvent, SessionHandle, Slot,
};
use droidctl::sim::link::SimProbe;
use droidctl::sim::{Faults, SimConfig, SimDroidV1, SimLink, SimState};
use droidctl::units::Heading;
use std::time::Duration;
use tokio::sync::broadcast;
use tokio::time::{Instant, sleep, timeout};

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn secs(n: f64) -> Duration {
    Duration::from_secs_f64(n)
}

fn h(deg: u16) -> Heading {
    Heading::new(deg).unwrap()
}

fn roll(speed: u8, heading: u16) -> Command {
    cmd::roll(speed, h(heading), RollState::Go)
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

/// The angle between two headings, 0..=180.
fn angle_between(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

// ---------------------------------------------------------------------------------------------
// A bench for the sans-IO droid: explicit time in 10 ms steps (the simulator's physics step),
// every packet re-decoded from its wire bytes, the droid's state recorded after every step.
// ---------------------------------------------------------------------------------------------

const STEP: Duration = Duration::from_millis(10);

struct Bench {
    droid: SimDroidV1,
    now: Duration,
    seq: u8,
    /// Async messages with the time they came out.
    asyncs: Vec<(Duration, AsyncPacket)>,
    /// The droid's state after each step.
    history: Vec<(Duration, SimState)>,
    /// Reads the droid's side of the wire, as a host would.
    decoder: Decoder,
}

impl Bench {
    fn new() -> Self {
        Bench::with(SimConfig::default())
    }

    fn with(cfg: SimConfig) -> Self {
        Bench {
            droid: SimDroidV1::new(Model::BB8, cfg),
            now: Duration::ZERO,
            seq: 0,
            asyncs: Vec::new(),
            history: Vec::new(),
            decoder: Decoder::new(Source::Droid),
        }
    }

    /// A room so large no wall is ever reached.
    fn open_field() -> Self {
        Bench::with(SimConfig {
            room_cm: (100_000.0, 100_000.0),
            ..SimConfig::default()
        })
    }

    fn state(&self) -> &SimState {
        self.droid.state()
    }

    /// The state recorded at `t`.
    fn state_at(&self, t: Duration) -> &SimState {
        &self
            .history
            .iter()
            .find(|(at, _)| *at == t)
            .unwrap_or_else(|| panic!("no state recorded at {t:?}"))
            .1
    }

    /// Packets out of the droid: each is encoded and decoded again as the host would see it
    /// (so what the tests read is what the wire carries). Responses are returned, async
    /// messages recorded.
    fn take(&mut self, out: Vec<Packet>) -> Vec<Response> {
        let wire: Vec<u8> = out
            .iter()
            .flat_map(|p| p.encode().expect("the droid frames what it sends"))
            .collect();
        let decoded: Vec<Packet> = self
            .decoder
            .feed(&wire)
            .map(|r| r.expect("the droid's bytes decode"))
            .collect();
        assert_eq!(decoded, out, "the wire carries exactly what the droid sent");
        let mut responses = Vec::new();
        for p in decoded {
            match p {
                Packet::Response(r) => responses.push(r),
                Packet::Async(a) => self.asyncs.push((self.now, a)),
                Packet::Command(c) => panic!("a droid sends no commands: {c:?}"),
            }
        }
        responses
    }

    fn next_seq(&mut self) -> u8 {
        let s = self.seq;
        self.seq = self.seq.wrapping_add(1);
        s
    }

    /// Write a framed command now; the responses that come back.
    fn write(&mut self, p: &CommandPacket) -> Vec<Response> {
        let bytes = Packet::Command(p.clone()).encode().unwrap();
        let out = self.droid.receive(&bytes, self.now);
        self.take(out)
    }

    /// Send `c` with the answer and reset-timeout bits as given.
    fn send_with(&mut self, c: &Command, answer: bool, reset_timeout: bool) -> Vec<Response> {
        let seq = self.next_seq();
        let p = c.to_packet(seq).with_options(answer, reset_timeout);
        self.write(&p)
    }

    /// Send `c` asking for an answer; returns it, checked to echo the SEQ.
    fn send(&mut self, c: &Command) -> Response {
        let seq = self.next_seq();
        let p = c.to_packet(seq);
        let mut r = self.write(&p);
        assert_eq!(r.len(), 1, "one response to {p:?}, got {r:?}");
        let r = r.remove(0);
        assert_eq!(r.seq, seq, "the response echoes the SEQ");
        r
    }

    fn ok(&mut self, c: &Command) -> Response {
        let r = self.send(c);
        assert_eq!(r.mrsp, Mrsp::Ok, "{c:?} → {r:?}");
        r
    }

    fn step(&mut self) {
        self.now += STEP;
        let out = self.droid.advance(self.now);
        self.take(out);
        self.history.push((self.now, self.state().clone()));
    }

    fn run_for(&mut self, d: Duration) {
        let end = self.now + d;
        while self.now < end {
            self.step();
        }
    }

    /// Re-send `c` every 500 ms for `d` (a heartbeat, as the app and missions do).
    fn hold(&mut self, c: &Command, d: Duration) {
        let end = self.now + d;
        while self.now < end {
            self.ok(c);
            self.run_for(ms(500).min(end - self.now));
        }
    }

    fn asyncs_of(&self, id_code: u8) -> Vec<(Duration, AsyncPacket)> {
        self.asyncs
            .iter()
            .filter(|(_, a)| a.id_code == id_code)
            .cloned()
            .collect()
    }
}

const ID_POWER: u8 = 0x01;
const ID_SENSORS: u8 = 0x03;
const ID_PRE_SLEEP: u8 = 0x05;
const ID_COLLISION: u8 = 0x07;

// ---------------------------------------------------------------------------------------------
// Responses
// ---------------------------------------------------------------------------------------------

#[test]
fn ping_is_answered_with_its_seq_and_mrsp_ok() {
    let mut b = Bench::new();
    // The seed's Ping example, SEQ 52h: FF FF 00 01 52 01 AB.
    let p = cmd::ping().to_packet(0x52);
    assert_eq!(
        Packet::Command(p.clone()).encode().unwrap(),
        [0xFF, 0xFF, 0x00, 0x01, 0x52, 0x01, 0xAB]
    );
    let out = b
        .droid
        .receive(&[0xFF, 0xFF, 0x00, 0x01, 0x52, 0x01, 0xAB], b.now);
    let wire: Vec<u8> = out.iter().flat_map(|p| p.encode().unwrap()).collect();
    // Simple response: FF FF MRSP=00 SEQ=52 DLEN=01 CHK=!(00+52+01).
    assert_eq!(wire, [0xFF, 0xFF, 0x00, 0x52, 0x01, 0xAC]);
    // Any SEQ is echoed, on every command.
    for seq in [0u8, 1, 0x7F, 0xFE, 0xFF] {
        let r = b.write(&cmd::ping().to_packet(seq));
        assert_eq!(r.len(), 1);
        assert_eq!((r[0].seq, r[0].mrsp, r[0].data.len()), (seq, Mrsp::Ok, 0));
    }
    assert_eq!(b.state().decode_errors, 0);
}

#[test]
fn no_answer_when_the_answer_bit_is_clear_but_the_command_still_acts() {
    let mut b = Bench::new();
    assert!(b.send_with(&cmd::ping(), false, true).is_empty());
    assert!(
        b.send_with(&cmd::set_rgb_led(10, 20, 30, false), false, false)
            .is_empty()
    );
    assert_eq!(&b.state().leds[..3], &[10, 20, 30], "acted upon");
    // Nor for an error: a refused command without the answer bit is silent too.
    let unknown = Command {
        did: 0x02,
        cid: 0x7F,
        data: vec![],
    };
    assert!(b.send_with(&unknown, false, true).is_empty());
    // With the bit set, the getter reads back what the silent setter did.
    let r = b.ok(&cmd::get_rgb_led());
    assert_eq!(r.data, [10, 20, 30]);
    assert_eq!(b.state().commands, 4);
}

#[test]
fn unknown_commands_and_bad_payloads_are_refused_with_an_mrsp() {
    let mut b = Bench::new();
    for (did, cid) in [(0x02u8, 0x7Fu8), (0x00, 0x7E), (0x02, 0x00)] {
        assert!(catalog::lookup(did, cid).is_none());
        let r = b.send(&Command {
            did,
            cid,
            data: vec![1, 2],
        });
        assert_eq!(r.mrsp, Mrsp::UnknownCommand, "{did:02X}/{cid:02X}");
        assert!(r.data.is_empty());
    }
    // A device the droid does not have.
    let r = b.send(&Command {
        did: 0x17,
        cid: 0x01,
        data: vec![],
    });
    assert!(!r.mrsp.is_success(), "{r:?}");
    // Wrong lengths: Roll takes 4 bytes (or 5, see below), Set Heading 2, Ping none.
    for (c, len) in [
        (roll(100, 90), 3usize),
        (roll(100, 90), 6),
        (cmd::set_heading(h(0)), 1),
        (cmd::ping(), 1),
    ] {
        let mut data = c.data.clone();
        data.resize(len, 0);
        let r = b.send(&Command { data, ..c });
        assert_eq!(r.mrsp, Mrsp::BadMessageFormat, "{len} bytes");
        assert!(r.data.is_empty());
    }
    // A heading of 360 or more is a bad parameter, and does nothing.
    let r = b.send(&Command {
        did: 0x02,
        cid: 0x30,
        data: vec![200, 0x01, 0x68, 1],
    });
    assert_eq!(r.mrsp, Mrsp::ParameterInvalid);
    b.run_for(ms(500));
    assert_eq!(b.state().velocity_cm_s, 0.0);
    // The droid was not confused by any of it.
    b.ok(&cmd::ping());
    assert_eq!(b.state().decode_errors, 0);
}

#[test]
fn corrupt_bytes_are_not_commands() {
    let mut b = Bench::new();
    let mut wire = Packet::Command(roll(200, 0).to_packet(1)).encode().unwrap();
    let last = wire.len() - 1;
    wire[last] ^= 0x55;
    assert!(b.droid.receive(&wire, b.now).is_empty());
    assert_eq!(b.state().decode_errors, 1);
    b.run_for(ms(500));
    assert_eq!(b.state().velocity_cm_s, 0.0, "a bad checksum does not roll");
    // And the stream recovers at the next packet, even split into single bytes.
    let ping = Packet::Command(cmd::ping().to_packet(9)).encode().unwrap();
    let mut out = Vec::new();
    for byte in ping {
        out.extend(b.droid.receive(&[byte], b.now));
    }
    assert_eq!(b.take(out).len(), 1);
}

/// The simulator is judged by real clients (spherov2.py's connect routines send many of the
/// catalogue's commands): every documented command, with a minimal well-formed payload, is
/// answered with success and a payload its response schema reads.
#[test]
fn every_catalogue_command_gets_a_success_answer() {
    let mut together = Bench::new();
    for def in catalog::commands() {
        let c = Command {
            did: def.did,
            cid: def.cid,
            data: catalog::minimal_payload(def.params),
        };
        // Alone on a fresh droid, and one after another on the same droid.
        let mut alone = Bench::new();
        for b in [&mut alone, &mut together] {
            let r = b.send(&c);
            assert_eq!(r.mrsp, Mrsp::Ok, "{} ({:?})", def.name, r);
            assert!(
                catalog::decode_fields(def.response, &r.data).is_ok(),
                "{}: response {:02X?} does not fit {:?}",
                def.name,
                r.data,
                def.response
            );
        }
    }
    assert_eq!(together.state().decode_errors, 0);
}

/// What spherov2.py writes to a v1 droid, byte for byte (`spherov2/commands/sphero.py`,
/// `core.py`): its connect routine (locator flags, collision detection, power notifications,
/// streaming, LEDs off, locator reset), then driving. Two payloads differ from the
/// catalogue's: Set RGB LED without the persist flag (3 bytes) and Roll with a trailing
/// reverse flag (5 bytes). Real droids take them, so the simulator must.
#[test]
fn accepts_what_spherov2_py_sends() {
    let mut b = Bench::open_field();
    let raw = |did: u8, cid: u8, data: &[u8]| Command {
        did,
        cid,
        data: data.to_vec(),
    };
    let connect = [
        // Locator flags, collision detection, power notifications.
        raw(0x02, 0x13, &[0, 0, 0, 0, 0, 0, 0]),
        raw(0x02, 0x12, &[1, 90, 130, 90, 130, 1]),
        raw(0x00, 0x21, &[1]),
        // Streaming, always with MASK2 (13 bytes).
        raw(0x02, 0x11, &[0, 60, 0, 1, 0, 7, 0, 0, 0, 0, 0, 0, 0]),
        // Main LED off without the persist flag, back LED off, locator reset.
        raw(0x02, 0x20, &[0, 0, 0]),
        raw(0x02, 0x21, &[0]),
        raw(0x02, 0x13, &[0, 0, 0, 0, 0, 0, 0]),
        // Power state, versions.
        raw(0x00, 0x20, &[]),
        raw(0x00, 0x02, &[]),
    ];
    for c in &connect {
        let r = b.send(c);
        assert_eq!(r.mrsp, Mrsp::Ok, "{c:02X?} → {r:?}");
    }
    // spherov2.py unpacks these answers as '>2B3H' and '>8B'.
    assert_eq!(b.ok(&cmd::get_power_state()).data.len(), 8);
    assert_eq!(b.ok(&cmd::get_versions()).data.len(), 8);
    // Its main LED colour, three bytes.
    b.ok(&raw(0x02, 0x20, &[0, 255, 0]));
    assert_eq!(&b.state().leds[..3], &[0, 255, 0]);
    // Its Roll: speed, heading, mode (1 go), reverse flag 0.
    b.hold(&raw(0x02, 0x30, &[128, 0, 90, 1, 0]), secs(2.0));
    let st = b.state().clone();
    assert!(st.x_cm > 50.0 && st.velocity_cm_s > 70.0, "{st:?}");
    // Reverse flag 1: backs up, still facing 90.
    b.hold(&raw(0x02, 0x30, &[128, 0, 90, 1, 1]), secs(3.0));
    let back = b.state().clone();
    assert!(back.velocity_cm_s < -70.0, "{back:?}");
    assert!(close(back.yaw_deg, 90.0, 0.01), "{back:?}");
    assert!(back.x_cm < st.x_cm, "{back:?}");
    // Mode 0 stops.
    b.ok(&raw(0x02, 0x30, &[0, 0, 90, 0, 0]));
    b.run_for(secs(1.0));
    assert_eq!(b.state().velocity_cm_s, 0.0);
}

#[test]
fn getters_report_the_droids_state() {
    let mut b = Bench::new();
    b.ok(&cmd::set_rgb_led(255, 128, 0, false));
    b.ok(&cmd::set_back_led(200));
    assert_eq!(b.ok(&cmd::get_rgb_led()).data, [255, 128, 0]);
    assert_eq!(b.state().leds[3], 200, "the back LED");
    let r = b.ok(&cmd::get_power_state());
    let fields = catalog::decode_fields(
        catalog::by_name("get-power-state").unwrap().response,
        &r.data,
    )
    .unwrap();
    assert!(!fields.is_empty());
    let volts = u16::from_be_bytes([r.data[2], r.data[3]]) as f32 / 100.0;
    assert!(close(volts, b.state().battery_v, 0.01), "{volts}");
    assert_eq!(r.data[1], 2, "power state OK");
    // The family reads the same number from the same answer.
    let family = droidctl::family::for_model(Model::BB8);
    assert_eq!(family.battery_volts(&r.data), Some(volts));
}

// ---------------------------------------------------------------------------------------------
// Motion
// ---------------------------------------------------------------------------------------------

#[test]
fn roll_moves_the_droid_along_its_heading_0_is_plus_y_90_is_plus_x() {
    for (heading, dir) in [
        (0u16, (0.0f32, 1.0f32)),
        (90, (1.0, 0.0)),
        (180, (0.0, -1.0)),
        (270, (-1.0, 0.0)),
    ] {
        let mut b = Bench::open_field();
        b.hold(&roll(128, heading), secs(3.0));
        let st = b.state().clone();
        assert!(close(st.yaw_deg, heading as f32, 0.01), "{st:?}");
        assert!(st.velocity_cm_s > 70.0, "about half of 160 cm/s: {st:?}");
        // Over the last second (the turn toward the heading is long over): along it only.
        let before = b.state_at(secs(2.0));
        let (dx, dy) = (st.x_cm - before.x_cm, st.y_cm - before.y_cm);
        let along = dx * dir.0 + dy * dir.1;
        let across = dx * dir.1 - dy * dir.0;
        assert!(
            close(along, st.velocity_cm_s, 1.0),
            "heading {heading}: {dx}, {dy}"
        );
        assert!(across.abs() < 0.01, "heading {heading}: {dx}, {dy}");
    }
    // Heading 0, no turning: straight up the y axis.
    let mut b = Bench::open_field();
    b.hold(&roll(255, 0), secs(2.0));
    assert!(close(b.state().x_cm, 0.0, 0.01), "{:?}", b.state());
    assert!(b.state().y_cm > 150.0);
}

#[test]
fn roll_state_0_stops_keeping_the_heading() {
    let mut b = Bench::open_field();
    b.hold(&roll(200, 90), secs(2.0));
    assert!(b.state().velocity_cm_s > 100.0);
    b.ok(&cmd::roll(0, h(90), RollState::Stop));
    b.run_for(ms(800));
    let st = b.state().clone();
    assert_eq!(st.velocity_cm_s, 0.0, "{st:?}");
    assert!(
        close(st.yaw_deg, 90.0, 0.01),
        "the stop does not turn: {st:?}"
    );
    b.run_for(ms(500));
    assert_eq!((b.state().x_cm, b.state().y_cm), (st.x_cm, st.y_cm));
    // State 0 stops whatever speed it carries.
    b.hold(&roll(200, 90), secs(1.0));
    b.ok(&cmd::roll(200, h(90), RollState::Stop));
    b.run_for(ms(800));
    assert_eq!(b.state().velocity_cm_s, 0.0);
}

#[test]
fn speed_0_turns_in_place() {
    let mut b = Bench::open_field();
    b.ok(&roll(0, 90));
    b.run_for(secs(1.0));
    let st = b.state();
    assert!(close(st.yaw_deg, 90.0, 0.01), "{st:?}");
    assert_eq!((st.x_cm, st.y_cm), (0.0, 0.0), "aiming does not roll");
}

#[test]
fn set_heading_makes_the_current_facing_the_new_heading() {
    // Aim: turn in place to 90, then call that facing 0 (the app's aim mode ends this way).
    let mut b = Bench::open_field();
    b.ok(&roll(0, 90));
    b.run_for(secs(1.0));
    assert!(close(b.state().yaw_deg, 90.0, 0.01));
    b.ok(&cmd::set_heading(h(0)));
    assert_eq!(b.state().yaw_deg, 0.0);
    b.run_for(secs(1.0));
    assert_eq!(
        b.state().yaw_deg,
        0.0,
        "the droid does not turn after Set Heading"
    );
    assert_eq!((b.state().x_cm, b.state().y_cm), (0.0, 0.0));

    // Any heading: the facing becomes it, and the droid stays put.
    for new in [45u16, 270, 359] {
        b.ok(&cmd::set_heading(h(new)));
        b.run_for(secs(1.0));
        let st = b.state().clone();
        assert!(
            close(st.yaw_deg, new as f32, 0.01),
            "Set Heading {new}: the facing is now {new}, not {}",
            st.yaw_deg
        );
        assert_eq!((st.x_cm, st.y_cm), (0.0, 0.0), "{st:?}");
    }

    // While rolling: the droid keeps going the same way, now called 90.
    let mut b = Bench::open_field();
    b.hold(&roll(150, 0), secs(1.5));
    let before = b.state().clone();
    b.ok(&cmd::set_heading(h(90)));
    b.run_for(ms(300));
    let st = b.state().clone();
    assert!(close(st.yaw_deg, 90.0, 0.01), "{st:?}");
    // It rolls on along the facing it had: the new frame's 90 (no swerve).
    assert!(st.velocity_cm_s > 0.8 * before.velocity_cm_s, "{st:?}");
    // Rolling toward the new heading 90 is rolling straight on: no turn.
    b.hold(&roll(150, 90), secs(1.0));
    assert!(close(b.state().yaw_deg, 90.0, 0.01), "{:?}", b.state());
}

// ---------------------------------------------------------------------------------------------
// Sensor streaming
// ---------------------------------------------------------------------------------------------

fn stream_cfg(n: u16, m: u16, pcnt: u8) -> StreamingConfig {
    StreamingConfig {
        n,
        m,
        mask: mask::IMU,
        pcnt,
        mask2: mask::LOCATOR | mask::VELOCITY,
    }
}

#[test]
fn streaming_n40_m2_sends_two_frames_every_200_ms_matching_the_droid() {
    let mut b = Bench::open_field();
    let cfg = stream_cfg(40, 2, 0);
    b.ok(&cfg.command());
    b.hold(&roll(120, 90), secs(3.0));
    let packets = b.asyncs_of(ID_SENSORS);
    // 3 s at 2 × (40/400) s.
    assert!((14..=15).contains(&packets.len()), "{}", packets.len());
    for w in packets.windows(2) {
        assert_eq!(w[1].0 - w[0].0, ms(200), "2 × (N/400) s apart");
    }
    let mut moving = 0;
    for (t, p) in &packets {
        let notes = decode_async(p, &cfg).expect("decodes with the masks in effect");
        assert_eq!(notes.len(), 2, "M = 2 frames per packet");
        // The frames were sampled 100 ms apart, the second one now.
        for (note, at) in notes.iter().zip([*t - ms(100), *t]) {
            let Notification::Sensors(s) = note else {
                panic!("{note:?}")
            };
            let names: Vec<&str> = s.values.iter().map(|(n, _)| *n).collect();
            assert_eq!(
                names,
                [
                    "pitch",
                    "roll",
                    "yaw",
                    "locator_x",
                    "locator_y",
                    "velocity_x",
                    "velocity_y"
                ]
            );
            let st = b.state_at(at);
            let (hx, hy) = (st.yaw_deg.to_radians().sin(), st.yaw_deg.to_radians().cos());
            // cm (whole cm on the wire) and cm/s (whole mm/s on the wire).
            assert!(
                close(s.get("locator_x").unwrap(), st.x_cm, 0.51),
                "{s:?} {st:?}"
            );
            assert!(
                close(s.get("locator_y").unwrap(), st.y_cm, 0.51),
                "{s:?} {st:?}"
            );
            let v = st.velocity_cm_s;
            assert!(
                close(s.get("velocity_x").unwrap(), hx * v, 0.051),
                "{s:?} {st:?}"
            );
            assert!(
                close(s.get("velocity_y").unwrap(), hy * v, 0.051),
                "{s:?} {st:?}"
            );
            let yaw = s.get("yaw").unwrap();
            assert!(angle_between(yaw, st.yaw_deg) <= 0.51, "{yaw} vs {st:?}");
            if v > 50.0 {
                moving += 1;
            }
        }
    }
    assert!(moving > 15, "the droid was rolling during most frames");
    // Streaming off: MASK 0.
    b.ok(&cmd::set_data_streaming(40, 1, 0, 0, None));
    let n = b.asyncs_of(ID_SENSORS).len();
    b.run_for(secs(1.0));
    assert_eq!(b.asyncs_of(ID_SENSORS).len(), n);
}

#[test]
fn streaming_rate_is_400_over_n() {
    for (n, every) in [(20u16, 50u64), (40, 100), (100, 250)] {
        let mut b = Bench::new();
        b.ok(&stream_cfg(n, 1, 0).command());
        b.run_for(secs(2.0));
        let times: Vec<Duration> = b.asyncs_of(ID_SENSORS).iter().map(|(t, _)| *t).collect();
        assert_eq!(times.len() as u64, 2000 / every, "N = {n}");
        assert_eq!(times[0], ms(every));
        assert!(
            times.windows(2).all(|w| w[1] - w[0] == ms(every)),
            "N = {n}"
        );
    }
}

#[test]
fn pcnt_3_stops_after_three_packets() {
    let mut b = Bench::new();
    let cfg = stream_cfg(40, 1, 3);
    b.ok(&cfg.command());
    b.run_for(secs(2.0));
    let packets = b.asyncs_of(ID_SENSORS);
    let times: Vec<Duration> = packets.iter().map(|(t, _)| *t).collect();
    assert_eq!(times, [ms(100), ms(200), ms(300)]);
    for (_, p) in &packets {
        assert_eq!(decode_async(p, &cfg).unwrap().len(), 1);
    }
    // With M = 2, three packets of two frames.
    b.ok(&stream_cfg(40, 2, 3).command());
    b.asyncs.clear();
    b.run_for(secs(2.0));
    let packets = b.asyncs_of(ID_SENSORS);
    assert_eq!(packets.len(), 3);
    for (_, p) in &packets {
        assert_eq!(decode_async(p, &stream_cfg(40, 2, 3)).unwrap().len(), 2);
    }
}

// ---------------------------------------------------------------------------------------------
// Collisions, power, sleep
// ---------------------------------------------------------------------------------------------

#[test]
fn hitting_a_wall_sends_a_collision_async_07() {
    let mut b = Bench::new();
    b.ok(&cmd::configure_collision_detection(
        1, 100, 100, 100, 100, 10,
    ));
    // 4 m room, radius 10 cm: the wall ahead is 190 cm away.
    b.hold(&roll(200, 0), secs(4.0));
    let st = b.state().clone();
    assert!(st.collisions >= 1, "{st:?}");
    assert!(close(st.y_cm, 190.0, 0.01), "{st:?}");
    let hits = b.asyncs_of(ID_COLLISION);
    assert!(!hits.is_empty());
    let (at, p) = &hits[0];
    assert_eq!(p.data.len(), 16, "droid-facts.md §4: 16 data bytes");
    let notes = decode_async(p, &StreamingConfig::default()).unwrap();
    let [Notification::Collision(c)] = &notes[..] else {
        panic!("{notes:?}")
    };
    assert!(c.axis.y && !c.axis.x, "a wall ahead on +y: {c:?}");
    assert!(c.speed > 100, "hit at speed: {c:?}");
    assert_eq!(c.time_ms as u128, at.as_millis(), "{c:?}");
    // It stopped at the wall.
    let hit_state = b.state_at(*at);
    assert_eq!(hit_state.velocity_cm_s, 0.0);

    // Without Configure Collision Detection the wall still stops it, silently.
    let mut quiet = Bench::new();
    quiet.hold(&roll(200, 0), secs(4.0));
    assert!(quiet.state().collisions >= 1);
    assert!(quiet.asyncs_of(ID_COLLISION).is_empty());
    // Method 0 turns detection off again.
    b.ok(&cmd::configure_collision_detection(
        0, 100, 100, 100, 100, 10,
    ));
    b.asyncs.clear();
    b.hold(&roll(200, 0), secs(2.0));
    assert!(b.asyncs_of(ID_COLLISION).is_empty());
}

/// Holding the drive key against a wall re-sends the Roll on the heartbeat: the droid pushes
/// against the wall, which is the one impact, not a new collision every 500 ms.
#[test]
fn pushing_against_a_wall_is_one_collision() {
    let mut b = Bench::new();
    b.ok(&cmd::configure_collision_detection(
        1, 100, 100, 100, 100, 10,
    ));
    b.hold(&roll(200, 0), secs(8.0));
    assert!(close(b.state().y_cm, 190.0, 0.01));
    assert_eq!(b.state().collisions, 1, "{:?}", b.state());
    assert_eq!(b.asyncs_of(ID_COLLISION).len(), 1);
    // Backing off and hitting it again is a second collision.
    b.hold(&roll(200, 180), secs(1.5));
    b.hold(&roll(200, 0), secs(3.0));
    assert_eq!(b.state().collisions, 2, "{:?}", b.state());
    assert_eq!(b.asyncs_of(ID_COLLISION).len(), 2);
}

fn fast_drain() -> SimConfig {
    SimConfig {
        // 4.10 V → low (3.6 V) after 2.5 s, critical (3.45 V) after 3.25 s.
        drain_idle_v_s: 0.2,
        ..SimConfig::default()
    }
}

#[test]
fn power_notifications_only_when_enabled() {
    let mut on = Bench::with(fast_drain());
    on.ok(&cmd::set_power_notification(true));
    on.run_for(secs(4.0));
    let states: Vec<(Duration, Vec<u8>)> = on
        .asyncs_of(ID_POWER)
        .into_iter()
        .map(|(t, p)| (t, p.data))
        .collect();
    let data: Vec<Vec<u8>> = states.iter().map(|(_, d)| d.clone()).collect();
    // droid-facts.md §4: 3 low, 4 critical.
    assert_eq!(data, [vec![3], vec![4]], "{states:?}");
    assert!(close(states[0].0.as_secs_f32(), 2.5, 0.05), "{states:?}");
    assert!(close(states[1].0.as_secs_f32(), 3.25, 0.05), "{states:?}");
    for (_, p) in on.asyncs_of(ID_POWER) {
        let n = decode_async(&p, &StreamingConfig::default()).unwrap();
        assert!(matches!(n[..], [Notification::PowerState(3 | 4)]), "{n:?}");
    }
    // Get Power State agrees.
    assert_eq!(on.ok(&cmd::get_power_state()).data[1], 4);

    let mut off = Bench::with(fast_drain());
    off.run_for(secs(4.0));
    assert!(off.state().battery_v < 3.45);
    assert!(off.asyncs_of(ID_POWER).is_empty());
    // Turned on, then off again.
    let mut toggled = Bench::with(fast_drain());
    toggled.ok(&cmd::set_power_notification(true));
    toggled.run_for(secs(3.0));
    toggled.ok(&cmd::set_power_notification(false));
    toggled.run_for(secs(1.0));
    let data: Vec<Vec<u8>> = toggled
        .asyncs_of(ID_POWER)
        .into_iter()
        .map(|(_, p)| p.data)
        .collect();
    assert_eq!(data, [vec![3]]);
}

#[test]
fn inactivity_warns_10_s_before_sleeping_then_sleeps() {
    let mut b = Bench::open_field();
    b.ok(&cmd::set_inactivity_timeout(30));
    b.ok(&stream_cfg(40, 1, 0).command());
    // Roll without the reset-timeout bit: that is not activity.
    while b.now < secs(29.5) {
        assert!(b.send_with(&roll(100, 0), true, false).len() == 1);
        b.run_for(ms(500));
    }
    assert!(b.state().velocity_cm_s > 50.0, "{:?}", b.state());
    b.run_for(ms(500));
    let warnings: Vec<Duration> = b.asyncs_of(ID_PRE_SLEEP).iter().map(|(t, _)| *t).collect();
    assert_eq!(warnings, [secs(20.0)], "once, 10 s before the timeout");
    assert!(!b.state().awake, "asleep at 30 s: {:?}", b.state());
    let p = &b.asyncs_of(ID_PRE_SLEEP)[0].1;
    assert_eq!(
        decode_async(p, &StreamingConfig::default()).unwrap(),
        [Notification::WillSleep]
    );
    // Asleep: motion stops, streaming stops.
    b.run_for(secs(1.0));
    let st = b.state().clone();
    assert_eq!(st.velocity_cm_s, 0.0, "{st:?}");
    let streamed = b.asyncs_of(ID_SENSORS).len();
    b.run_for(secs(2.0));
    assert_eq!((b.state().x_cm, b.state().y_cm), (st.x_cm, st.y_cm));
    assert_eq!(
        b.asyncs_of(ID_SENSORS).len(),
        streamed,
        "no streaming asleep"
    );
    assert!(
        b.asyncs_of(ID_SENSORS)
            .iter()
            .all(|(t, _)| *t <= secs(30.0))
    );
    // The host's reconnect (wake sequence, then any command) wakes it.
    b.ok(&cmd::ping());
    assert!(b.state().awake);
}

#[test]
fn commands_with_the_reset_timeout_bit_keep_it_awake() {
    let mut b = Bench::new();
    b.ok(&cmd::set_inactivity_timeout(30));
    b.run_for(secs(15.0));
    // Activity at 15 s: the warning moves to 35 s, the sleep to 45 s.
    b.ok(&cmd::ping());
    b.run_for(secs(25.0));
    assert!(b.state().awake);
    let warnings: Vec<Duration> = b.asyncs_of(ID_PRE_SLEEP).iter().map(|(t, _)| *t).collect();
    assert_eq!(warnings, [secs(35.0)]);
    b.run_for(secs(5.0));
    assert!(!b.state().awake);
}

#[test]
fn sleep_command_sleeps_at_once() {
    let mut b = Bench::open_field();
    b.ok(&stream_cfg(40, 1, 0).command());
    b.hold(&roll(100, 0), secs(1.0));
    b.ok(&cmd::sleep(0, 0, 0));
    assert!(!b.state().awake);
    b.run_for(secs(1.0));
    assert_eq!(b.state().velocity_cm_s, 0.0);
    let n = b.asyncs_of(ID_SENSORS).len();
    b.run_for(secs(1.0));
    assert_eq!(b.asyncs_of(ID_SENSORS).len(), n);
}

// ---------------------------------------------------------------------------------------------
// Through SimLink and a session, under paused tokio time
// ---------------------------------------------------------------------------------------------

fn v1_config(model: Model) -> SessionConfig {
    SessionConfig {
        family: model.protocol(),
        pacing: model.write_pacing(),
        setup: connect_setup(model, &SetupOptions::default()),
        ..SessionConfig::default()
    }
}

/// The v1 commands the session wrote, as (time, did, cid), from its packet log.
fn spawn_out_log(s: &SessionHandle) -> std::sync::Arc<std::sync::Mutex<Vec<(Duration, u8, u8)>>> {
    let seen = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let out = seen.clone();
    let mut rx = s.subscribe_log();
    tokio::spawn(async move {
        loop {
            match rx.recv().await {
                Ok(LogEntry {
                    at,
                    dir: Direction::Out,
                    item: LogItem::Packet { packet, .. },
                }) => {
                    let Some(Packet::Command(c)) = packet.as_v1() else {
                        panic!("a v1 session writes v1 commands: {packet:?}")
                    };
                    out.lock().unwrap().push((at, c.did, c.cid));
                }
                Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => break,
            }
        }
    });
    seen
}

/// The (did, cid) of each command of the BB-8 connect setup.
fn setup_ids() -> Vec<(u8, u8)> {
    connect_setup(Model::BB8, &SetupOptions::default())
        .iter()
        .map(|c| (c.did(), c.cid()))
        .collect()
}

/// The next sensor sample on the session, skipping anything buffered before now.
async fn fresh_sample(
    rx: &mut broadcast::Receiver<SessionEvent>,
) -> droidctl::protocol::notify::SensorSample {
    *rx = rx.resubscribe();
    loop {
        match timeout(secs(2.0), rx.recv())
            .await
            .expect("a sensor sample within 2 s")
        {
            Ok(SessionEvent::Notification(Notification::Sensors(s))) => return s,
            Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => continue,
            Err(e) => panic!("{e}"),
        }
    }
}

async fn bb8_session(faults: Faults) -> (SessionHandle, SimProbe) {
    let link = SimLink::new(Model::BB8, SimConfig::default(), faults);
    let probe = link.probe();
    let s = session::start(Box::new(link), v1_config(Model::BB8));
    (s, probe)
}

#[tokio::test(start_paused = true)]
async fn session_connects_runs_the_v1_setup_answers_and_streams() {
    let (s, probe) = bb8_session(Faults::none()).await;
    let written = spawn_out_log(&s);
    let mut rx = s.subscribe();
    s.watch_state()
        .wait_for(|st| *st == LinkState::Connected)
        .await
        .unwrap();
    assert_eq!(v1_config(Model::BB8).family, Protocol::SpheroV1);
    // Requests are answered (the SEQ matches the request).
    let pong = s.request(cmd::ping()).await.expect("ping answered");
    assert!(matches!(pong.as_v1(), Some(Packet::Response(r)) if r.mrsp == Mrsp::Ok));
    let power = s.request(cmd::get_power_state()).await.unwrap();
    let family = droidctl::family::for_model(Model::BB8);
    let volts = family.battery_volts(power.data()).expect("battery volts");
    assert!(close(volts, probe.state().battery_v, 0.01), "{volts}");
    // The setup went out first, in order, each once.
    let ids: Vec<(u8, u8)> = written
        .lock()
        .unwrap()
        .iter()
        .map(|(_, d, c)| (*d, *c))
        .collect();
    let setup = setup_ids();
    assert_eq!(ids[..setup.len()], setup[..], "{ids:02X?}");
    assert!(setup.contains(&(0x02, 0x11)) && setup.contains(&(0x00, 0x21)));
    // Writes are paced at the model's 60 ms.
    let times: Vec<Duration> = written.lock().unwrap().iter().map(|(t, ..)| *t).collect();
    assert!(times.windows(2).all(|w| w[1] - w[0] >= ms(60)), "{times:?}");

    // Drive east for 1.5 s, then stop.
    for _ in 0..15 {
        s.set(Slot::Drive, roll(150, 90));
        sleep(ms(100)).await;
    }
    s.set(
        Slot::Drive,
        family.stop_after(Some(&AnyCommand::from(roll(150, 90)))),
    );
    sleep(secs(1.5)).await;
    let st = probe.state();
    assert_eq!(st.velocity_cm_s, 0.0, "{st:?}");
    assert!(st.x_cm > 80.0 && st.y_cm.abs() < 30.0, "{st:?}");
    assert!(close(st.yaw_deg, 90.0, 0.01), "{st:?}");
    // The stream carries the droid's position and heading.
    let sample = fresh_sample(&mut rx).await;
    let st = probe.state();
    assert!(
        close(sample.get("locator_x").unwrap(), st.x_cm, 0.51),
        "{sample:?} vs {st:?}"
    );
    assert!(
        close(sample.get("locator_y").unwrap(), st.y_cm, 0.51),
        "{sample:?} vs {st:?}"
    );
    assert!(close(sample.get("yaw").unwrap(), 90.0, 0.51), "{sample:?}");
    assert_eq!(sample.get("velocity_x"), Some(0.0));
    let stats = s.stats();
    assert_eq!(
        (
            stats.timeouts,
            stats.errors,
            stats.unmatched,
            stats.decode_errors
        ),
        (0, 0, 0, 0),
        "{stats:?}"
    );
    assert!(stats.received > 20, "{stats:?}");
    s.shutdown_stopped(vec![]).await;
    assert!(!probe.connected());
}

#[tokio::test(start_paused = true)]
async fn session_collision_and_power_notifications_arrive() {
    let link = SimLink::new(Model::BB8, fast_drain(), Faults::none());
    let s = session::start(Box::new(link), v1_config(Model::BB8));
    let mut rx = s.subscribe();
    s.watch_state()
        .wait_for(|st| *st == LinkState::Connected)
        .await
        .unwrap();
    for _ in 0..40 {
        s.set(Slot::Drive, roll(220, 0));
        sleep(ms(100)).await;
    }
    let mut collisions = 0;
    let mut power = Vec::new();
    while let Ok(ev) = rx.try_recv() {
        match ev {
            SessionEvent::Notification(Notification::Collision(c)) => {
                assert!(c.axis.y, "{c:?}");
                collisions += 1;
            }
            SessionEvent::Notification(Notification::PowerState(p)) => power.push(p),
            SessionEvent::BadNotification { name, reason } => panic!("{name}: {reason}"),
            _ => {}
        }
    }
    assert!(collisions >= 1);
    assert_eq!(power, [3, 4], "low, then critical");
    s.shutdown_stopped(vec![]).await;
}

#[tokio::test(start_paused = true)]
async fn session_over_a_faulty_link_reconnects_and_reruns_the_setup() {
    let faults = Faults {
        seed: 11,
        split: true,
        latency: ms(15),
        jitter: ms(25),
        disconnect_at: vec![secs(4.0), secs(9.0)],
        ..Faults::none()
    };
    let (s, probe) = bb8_session(faults).await;
    let written = spawn_out_log(&s);
    let mut rx = s.subscribe();
    let t0 = Instant::now();
    let mut states = s.watch_state();
    let mut drops = Vec::new();
    while t0.elapsed() < secs(14.0) {
        if timeout(secs(14.0) - t0.elapsed(), states.changed())
            .await
            .is_err()
        {
            break;
        }
        let st = states.borrow_and_update().clone();
        if matches!(st, LinkState::Reconnecting { .. }) {
            drops.push(t0.elapsed());
        }
    }
    assert_eq!(drops, [secs(4.0), secs(9.0)]);
    assert_eq!(s.state(), LinkState::Connected);
    assert_eq!(s.stats().reconnects, 2);
    assert_eq!(probe.opens(), 3);
    // The setup ran once per connection, in order, each time first thing.
    let log = written.lock().unwrap().clone();
    let setup = setup_ids();
    for (d, c) in &setup {
        let n = log.iter().filter(|(_, dd, cc)| (dd, cc) == (d, c)).count();
        // Ping is also the setup's first command; nothing else sends these.
        assert_eq!(
            n, 3,
            "{d:02X}/{c:02X} written once per connection: {log:02X?}"
        );
    }
    for start in [Duration::ZERO, secs(4.5), secs(9.5)] {
        let ids: Vec<(u8, u8)> = log
            .iter()
            .filter(|(t, ..)| *t >= start)
            .take(setup.len())
            .map(|(_, d, c)| (*d, *c))
            .collect();
        assert_eq!(ids, setup, "after the (re)connect at {start:?}");
    }
    // The link works again: answers, and a stream that follows the droid.
    s.request(cmd::ping())
        .await
        .expect("answered after reconnecting");
    for _ in 0..20 {
        s.set(Slot::Drive, roll(120, 90));
        sleep(ms(100)).await;
    }
    s.set(Slot::Drive, cmd::roll(0, h(90), RollState::Stop));
    sleep(secs(1.5)).await;
    let sample = fresh_sample(&mut rx).await;
    let st = probe.state();
    assert!(st.x_cm > 60.0, "{st:?}");
    assert!(
        close(sample.get("locator_x").unwrap(), st.x_cm, 0.51),
        "{sample:?} vs {st:?}"
    );
    assert!(
        close(sample.get("locator_y").unwrap(), st.y_cm, 0.51),
        "{sample:?} vs {st:?}"
    );
    let stats = s.stats();
    // Split and delayed bytes are still whole packets to the decoder, and every message
    // reads right, also the sensor data the droid streams on between a reconnect and the
    // setup's Set Data Streaming.
    assert_eq!((stats.decode_errors, stats.errors), (0, 0), "{stats:?}");
    s.shutdown_stopped(vec![]).await;
}

#[tokio::test(start_paused = true)]
async fn session_survives_corruption_with_decode_errors_counted() {
    let faults = Faults {
        seed: 5,
        split: true,
        corrupt_rate: 0.01,
        ..Faults::none()
    };
    let (s, probe) = bb8_session(faults).await;
    let mut rx = s.subscribe();
    s.watch_state()
        .wait_for(|st| *st == LinkState::Connected)
        .await
        .unwrap();
    for _ in 0..100 {
        s.set(Slot::Drive, roll(60, 0));
        sleep(ms(200)).await;
    }
    let stats = s.stats();
    assert!(stats.decode_errors > 0, "{stats:?}");
    assert!(stats.received > 100, "{stats:?}");
    assert!(
        probe.state().y_cm > 100.0,
        "drove despite lost commands: {:?}",
        probe.state()
    );
    // The stream resynchronises: samples still arrive, most of them right.
    s.set(Slot::Drive, cmd::roll(0, h(0), RollState::Stop));
    sleep(secs(1.0)).await;
    let mut good = 0;
    for _ in 0..5 {
        let sample = fresh_sample(&mut rx).await;
        let st = probe.state();
        if close(sample.get("locator_y").unwrap_or(f32::NAN), st.y_cm, 0.51) {
            good += 1;
        }
    }
    assert!(good >= 3, "{good} of 5 samples read right");
    // Requests get through (a corrupted one times out; the next is answered).
    let mut answered = false;
    for _ in 0..5 {
        if s.request(cmd::ping()).await.is_ok() {
            answered = true;
            break;
        }
    }
    assert!(answered);
    s.shutdown(vec![]).await;
}

/// The app's drive path: the family's drive command for a v1 droid is Roll, reversing rolls
/// the other way, and `AnyCommand` carries it to the session.
#[test]
fn family_drive_commands_are_rolls() {
    let f = droidctl::family::for_model(Model::BB8);
    let fwd = f.drive(100, h(90), false);
    assert_eq!(fwd, AnyCommand::from(roll(100, 90)));
    assert_eq!(f.drive(100, h(90), true), AnyCommand::from(roll(100, 270)));
    let mut b = Bench::open_field();
    let AnyCommand::V1(c) = f.drive(128, h(180), true) else {
        panic!()
    };
    b.hold(&c, secs(2.0));
    assert!(
        b.state().y_cm > 80.0,
        "reverse of 180 is +y: {:?}",
        b.state()
    );
}
