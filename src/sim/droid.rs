//! The simulated v2 droid (R2-D2, R2-Q5, BB-9E, BOLT, Mini, RVR): the shared [`Body`] behind
//! a Sphero API v2 front, with the newer robots' parts ([`RobotParts`]: BOLT's matrix, RVR's
//! streaming service, the processors). Sans-IO: wire bytes and time in, packets out.

use super::SimConfig;
pub use super::body::SimState;
use super::body::{Body, SimEvent};
use super::infrared::{self, Infrared};
use super::robots::{self, RobotParts};
use crate::model::Model;
use crate::protocol::v2::catalog;
use crate::protocol::v2::catalog::targets::Processor;
use crate::protocol::v2::sensor::{StreamingConfig, encode_sample};
use crate::protocol::v2::wire::{DriveFlags, LegAction};
use crate::protocol::v2::{Decoder, Device, ErrorCode, Flags, Packet};
use std::time::Duration;

/// The simulated v2 droid.
#[derive(Debug, Clone)]
pub struct SimDroid {
    body: Body,
    decoder: Decoder,
    streaming: StreamingConfig,
    battery_state_notify: bool,
    voltage_state_notify: bool,
    /// BOLT's matrix, RVR's LEDs and streaming service.
    robot: RobotParts,
    /// BOLT's and RVR's robot-to-robot infrared.
    ir: Infrared,
    out: Vec<Packet>,
    /// The port nibble of the host's last addressed command: 0x10 over Bluetooth, 0x00 on
    /// RVR's UART (Sphero's SDK there addresses 0x01/0x02 and matches notifications by those
    /// sources). Notifications come from the processor on that port (unverified on hardware:
    /// what the SDK expects, not a capture).
    host_port: u8,
}

/// Devices that answer while asleep; the rest say target_unavailable until Wake.
fn answers_asleep(did: u8) -> bool {
    matches!(
        Device::from_id(did),
        Some(
            Device::Core
                | Device::Power
                | Device::SystemInfo
                | Device::ApiAndShell
                | Device::Connection
                | Device::Firmware
                | Device::FactoryTest
                | Device::SystemMode
        )
    )
}

impl SimDroid {
    pub fn new(model: Model, cfg: SimConfig) -> Self {
        SimDroid {
            body: Body::new(model, cfg),
            decoder: Decoder::new(),
            streaming: StreamingConfig::default(),
            battery_state_notify: false,
            voltage_state_notify: false,
            robot: RobotParts::new(model),
            ir: Infrared::default(),
            out: Vec::new(),
            host_port: 0x10,
        }
    }

    pub fn model(&self) -> Model {
        self.body.model()
    }

    /// A person puts the droid on its charger or takes it off ([`Body::set_on_charger`]).
    pub fn set_on_charger(&mut self, on: bool) {
        self.body.set_on_charger(on);
    }

    /// When the droid next has something to send ([`super::body::Body::next_due`]).
    pub fn next_due(&self) -> Option<Duration> {
        // A robot that follows or evades steers itself at every step.
        if self.ir.behaviour.is_some() {
            return None;
        }
        let body = self.body.next_due()?;
        let due = self.robot.next_due().map_or(body, |r| r.min(body));
        // One that listens in a shared room looks for messages every few steps.
        let listens = self.ir.listens() != 0 && self.body.cfg.place.is_some();
        Some(if listens {
            due.min(self.body.now() + infrared::LISTEN_POLL)
        } else {
            due
        })
    }

    /// BOLT's and RVR's infrared: what they broadcast, follow or evade, listen for.
    pub fn infrared(&self) -> &Infrared {
        &self.ir
    }

    /// BOLT's matrix, RVR's LEDs and streaming service, as the trace shows them.
    pub fn robot(&self) -> &RobotParts {
        &self.robot
    }

    pub fn state(&self) -> &SimState {
        self.body.state()
    }

    pub fn now(&self) -> Duration {
        self.body.now()
    }

    /// Wire bytes from the host at time `now`; returns the packets the droid sends back
    /// (responses, and any notifications due up to `now`).
    pub fn receive(&mut self, bytes: &[u8], now: Duration) -> Vec<Packet> {
        self.advance_to(now);
        let packets: Vec<_> = self.decoder.feed(bytes).collect();
        for r in packets {
            match r {
                Ok(p) => self.handle(p),
                Err(_) => self.body.state.decode_errors += 1,
            }
        }
        std::mem::take(&mut self.out)
    }

    /// Let time pass; returns the notifications due.
    pub fn advance(&mut self, now: Duration) -> Vec<Packet> {
        self.advance_to(now);
        std::mem::take(&mut self.out)
    }

    fn notify(&mut self, did: u8, cid: u8, data: Vec<u8>) {
        let mut p = Packet::notification(did, cid, data);
        // A robot with processors says which one speaks (spherov2 reads the source of
        // streaming-service data); the secondary has the motors and motion sensors.
        if self.body.model().processors() > 1 {
            let from = match targets_home(self.body.model(), did, cid) {
                Some(Processor::Primary) => 0x11,
                _ => 0x12,
            };
            p.flags |= Flags::HAS_SOURCE_ID | Flags::HAS_TARGET_ID;
            p.sid = Some(self.host_port | (from & 0x0F));
            p.tid = Some(0x01);
        }
        self.out.push(p);
    }

    fn advance_to(&mut self, now: Duration) {
        self.advance_body(now);
        self.flush_events();
        self.infrared_heard();
        if self.robot.text_done(now) {
            self.notify(0x1A, 0x3C, vec![0]);
        }
        if let Some(id) = self.robot.animate(now) {
            self.notify(0x1A, 0x3F, vec![id]);
        }
        for cid in self.robot.versions_now(now) {
            self.notify(0x11, cid, version_bytes());
        }
        if !self.robot.service.running.is_empty() && self.body.state.awake {
            let values = self.body.sample_values();
            for (p, data) in self.robot.stream_due(now, &values) {
                let mut packet = Packet::notification(0x18, 0x3D, data);
                if self.body.model().processors() > 1 {
                    packet.flags |= Flags::HAS_SOURCE_ID | Flags::HAS_TARGET_ID;
                    packet.sid = Some(self.host_port | (p.target_id() & 0x0F));
                    packet.tid = Some(0x01);
                }
                self.out.push(packet);
            }
        }
    }

    /// The body's physics up to `now`, a step at a time while it follows or evades (it
    /// steers itself before each step).
    fn advance_body(&mut self, now: Duration) {
        if self.ir.behaviour.is_none() {
            self.body.advance_to(now);
            return;
        }
        let step = self.body.cfg.step.max(Duration::from_millis(1));
        while self.body.now() + step <= now {
            let seen = self.ir.sighting(self.body.cfg.place.as_ref());
            let (yaw, at) = (self.body.state.yaw_deg, self.body.now());
            if let Some((speed, facing)) = self.ir.steer(seen, yaw, at, step)
                && self.body.state.awake
            {
                self.body.drive(speed, facing, false);
            }
            self.body.advance_to(at + step);
        }
    }

    /// The infrared messages that reached this robot, notified when it listens for them
    /// (Sensor 0x2C, the code).
    fn infrared_heard(&mut self) {
        if self.ir.listens() == 0 {
            return;
        }
        let Some(place) = self.body.cfg.place.clone() else {
            return;
        };
        for code in place.take_ir() {
            if self.ir.hear(code, Some(&place)) {
                self.notify(0x18, 0x2C, vec![code]);
            }
        }
    }

    /// The body's events as v2 notifications.
    fn flush_events(&mut self) {
        for e in self.body.take_events() {
            match e {
                SimEvent::LegActionComplete => self.notify(0x17, 0x26, vec![]),
                SimEvent::AnimationComplete => self.notify(0x17, 0x11, vec![]),
                SimEvent::WillSleep => self.notify(0x13, 0x19, vec![]),
                SimEvent::DidSleep => {
                    self.streaming = StreamingConfig::default();
                    self.robot.service.running.clear();
                    // Asleep, a robot neither broadcasts, listens nor steers.
                    self.ir = Infrared::default();
                    if let Some(place) = &self.body.cfg.place {
                        place.show_ir(None, 0);
                    }
                    self.notify(0x13, 0x1A, vec![]);
                }
                SimEvent::VoltageState(s) => {
                    if self.voltage_state_notify {
                        self.notify(0x13, 0x1C, vec![s]);
                    }
                    if self.battery_state_notify {
                        let b = self.body.battery_state();
                        self.notify(0x13, 0x06, vec![b]);
                    }
                }
                SimEvent::Charger(_) => {
                    if self.battery_state_notify {
                        let b = self.body.battery_state();
                        self.notify(0x13, 0x06, vec![b]);
                    }
                }
                SimEvent::Collision(c) => self.notify(0x18, 0x12, c.encode()),
                SimEvent::Sample(values) => {
                    let data = encode_sample(&self.streaming, &values);
                    self.notify(0x18, 0x02, data);
                }
            }
        }
    }

    /// The body samples at the interval of the masks in effect.
    fn sync_streaming(&mut self) {
        let every = self
            .streaming
            .is_streaming()
            .then(|| Duration::from_millis(self.streaming.interval_ms as u64));
        self.body.set_streaming(every);
    }

    fn handle(&mut self, p: Packet) {
        if p.is_response() || p.is_notification() {
            return;
        }
        self.body.state.commands += 1;
        if let Some(t) = p.tid.filter(|t| Processor::of_id(*t).is_some()) {
            self.host_port = t & 0xF0;
        }
        if p.flags.contains(Flags::IS_ACTIVITY) {
            self.body.activity();
        }
        let (err, data) = self.execute(&p);
        self.flush_events();
        let wants = p.flags.contains(Flags::REQUESTS_RESPONSE);
        let only_errors = p.flags.contains(Flags::REQUESTS_ONLY_ERROR_RESPONSE);
        if wants && (!only_errors || !err.is_success()) {
            let data = if err.is_success() { data } else { Vec::new() };
            self.out.push(Packet::response_to(&p, err, data));
        }
    }

    /// Run one command: the error code and the response payload.
    fn execute(&mut self, p: &Packet) -> (ErrorCode, Vec<u8>) {
        let Some(device) = Device::from_id(p.did) else {
            return (ErrorCode::BadDeviceId, vec![]);
        };
        let Some(def) = catalog::lookup(p.did, p.cid) else {
            return (ErrorCode::BadCommandId, vec![]);
        };
        if device == Device::Animatronic && !super::robots::has_animatronic(self.body.model()) {
            // The newer robots have no animatronic device at all.
            return (ErrorCode::BadDeviceId, vec![]);
        }
        if !self.body.model().has_legs()
            && device == Device::Animatronic
            && !matches!(p.cid, 0x05 | 0x2B | 0x2C)
        {
            // BB-9E has no legs and no dome to command.
            return (ErrorCode::BadCommandId, vec![]);
        }
        if let Err(e) = robots::route(self.body.model(), p.did, p.cid, p.tid) {
            return (e, vec![]);
        }
        if device == Device::Sensor && infrared::has(self.body.model(), p.cid) == Some(false) {
            // Robot-to-robot infrared: BOLT's and RVR's own commands only (src/sim/infrared.rs).
            return (ErrorCode::BadCommandId, vec![]);
        }
        if !catalog::length_ok(def.params, p.data.len()) {
            return (ErrorCode::BadDataLength, vec![]);
        }
        if !self.body.state.awake && !answers_asleep(p.did) {
            return (ErrorCode::TargetUnavailable, vec![]);
        }
        let d = &p.data;
        let u16_at = |i: usize| u16::from_be_bytes([d[i], d[i + 1]]);
        let f32_at = |i: usize| f32::from_be_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]]);
        let u32_at = |i: usize| u32::from_be_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]]);
        let ok = (ErrorCode::Success, vec![]);
        let now = self.body.now();
        let answer = |r: Result<Vec<u8>, ErrorCode>| match r {
            Ok(data) => (ErrorCode::Success, data),
            Err(e) => (e, vec![]),
        };
        if device == Device::Io
            && let Some(r) = self.robot.matrix(p.cid, d, now)
        {
            return answer(r);
        }
        match (device, p.cid) {
            (Device::Power, 0x0D) => {
                self.body.wake();
                ok
            }
            (Device::Power, 0x01) | (Device::Power, 0x00) | (Device::Core, 0x22) => {
                self.body.fall_asleep();
                ok
            }
            (Device::Power, 0x03) => (
                ErrorCode::Success,
                self.body.centivolts().to_be_bytes().to_vec(),
            ),
            (Device::Power, 0x04) => (ErrorCode::Success, vec![self.body.battery_state()]),
            (Device::Power, 0x05) => {
                self.battery_state_notify = d[0] != 0;
                ok
            }
            (Device::Power, 0x10) => (ErrorCode::Success, vec![self.body.battery_percent()]),
            (Device::Power, 0x17) => (ErrorCode::Success, vec![self.body.voltage_state_now()]),
            (Device::Power, 0x1B) => {
                self.voltage_state_notify = d[0] != 0;
                ok
            }
            (Device::Power, 0x25) => (
                ErrorCode::Success,
                self.body.state.battery_v.to_be_bytes().to_vec(),
            ),
            (Device::Core, 0x25) => {
                self.body
                    .set_inactivity_timeout(Duration::from_secs(u16_at(0) as u64));
                ok
            }
            (Device::Core, 0x11) => {
                let mut info = self.advertised_name().into_bytes();
                info.push(0);
                info.extend_from_slice(b"00:00:00:5E:D2:D2\0");
                (ErrorCode::Success, info)
            }
            (Device::SystemInfo, 0x00) | (Device::SystemInfo, 0x01) => {
                (ErrorCode::Success, version_bytes())
            }
            (Device::SystemInfo, 0x17 | 0x24) if self.robot.owe_version(p.cid, now).is_some() => ok,
            (Device::SystemInfo, 0x1F) => (ErrorCode::Success, b"droidctl-sim\0".to_vec()),
            (Device::SystemInfo, 0x39) => (
                ErrorCode::Success,
                (self.body.now().as_millis() as u32).to_be_bytes().to_vec(),
            ),
            (Device::Drive, 0x07) => {
                let heading = u16_at(1);
                if heading > 359 {
                    return (ErrorCode::BadParameterValue, vec![]);
                }
                let flags = DriveFlags::from_bits_retain(d[3]);
                let backward = flags.contains(DriveFlags::BACKWARD);
                // Reference clients add 180° when reversing: the heading is the direction of
                // travel, and a droid backing up faces the other way.
                let facing = if backward {
                    heading as f32 + 180.0
                } else {
                    heading as f32
                };
                self.body.drive(d[0], facing, backward);
                ok
            }
            // Set Custom Control System Timeout: the fail-safe droidctl sets on connect.
            (Device::Drive, 0x22) => {
                self.body
                    .set_control_timeout(Some(Duration::from_millis(u16_at(0) as u64)));
                ok
            }
            (Device::Drive, 0x06) => {
                // Reset Yaw: the current facing becomes heading 0.
                self.body.reset_yaw();
                ok
            }
            (Device::Animatronic, 0x05) => {
                self.body.play_animation();
                ok
            }
            (Device::Animatronic, 0x2B) => {
                self.body.stop_animation();
                ok
            }
            (Device::Animatronic, 0x0D) => match LegAction::from_byte(d[0]) {
                Some(a) => {
                    self.body.leg_action(a);
                    ok
                }
                None => (ErrorCode::BadParameterValue, vec![]),
            },
            (Device::Animatronic, 0x0F) => {
                let deg = f32_at(0);
                if !deg.is_finite() {
                    return (ErrorCode::BadParameterValue, vec![]);
                }
                self.body.set_head_target(deg);
                ok
            }
            (Device::Animatronic, 0x14) => (
                ErrorCode::Success,
                self.body.state.head_deg.to_be_bytes().to_vec(),
            ),
            (Device::Animatronic, 0x25) => {
                (ErrorCode::Success, vec![self.body.stance_now().to_byte()])
            }
            (Device::Sensor, 0x00) => {
                self.streaming.interval_ms = u16_at(0);
                self.streaming.mask = u32_at(3);
                self.sync_streaming();
                ok
            }
            (Device::Sensor, 0x01) => {
                let mut out = self.streaming.interval_ms.to_be_bytes().to_vec();
                out.push(0);
                out.extend_from_slice(&self.streaming.mask.to_be_bytes());
                (ErrorCode::Success, out)
            }
            (Device::Sensor, 0x0C) => {
                self.streaming.ext_mask = u32_at(0);
                self.sync_streaming();
                ok
            }
            (Device::Sensor, 0x0D) => (
                ErrorCode::Success,
                self.streaming.ext_mask.to_be_bytes().to_vec(),
            ),
            // Configure Collision Detection: method, x and y thresholds, x and y speeds, dead
            // time (10 ms), as spherov2 sends them (`droid-facts.md` §2).
            (Device::Sensor, 0x11) => {
                self.body.collision_notify = d[0] != 0;
                self.body.collision_thresholds = super::body::CollisionThresholds {
                    x_threshold: d[1],
                    y_threshold: d[2],
                    x_speed: d[3],
                    y_speed: d[4],
                };
                self.body.collision_dead_time = Duration::from_millis(d[5] as u64 * 10);
                ok
            }
            (Device::Sensor, 0x14) => {
                self.body.collision_notify = d[0] != 0;
                ok
            }
            (Device::Sensor, 0x13) => {
                self.body.reset_locator();
                ok
            }
            (Device::Io, 0x07) => {
                self.body.play_sound(d[2]);
                ok
            }
            (Device::Io, 0x08) => {
                self.body.state.volume = d[0];
                ok
            }
            (Device::Io, 0x09) => (ErrorCode::Success, vec![self.body.state.volume]),
            (Device::Io, 0x0A) => {
                self.body.stop_sounds();
                ok
            }
            (Device::Drive, 0x01) => {
                // Raw motors: mode 0 off, 1 forward, 2 reverse, and a speed each.
                let side = |mode: u8, speed: u8| match mode {
                    1 => Some(speed as f32 / 255.0),
                    2 => Some(-(speed as f32) / 255.0),
                    0 => Some(0.0),
                    _ => None,
                };
                match (side(d[0], d[1]), side(d[2], d[3])) {
                    (Some(l), Some(r)) => {
                        self.body.drive_tracks(l, r);
                        ok
                    }
                    _ => (ErrorCode::BadParameterValue, vec![]),
                }
            }
            (Device::Drive, 0x25) => {
                self.robot.motor_stall_notify = d[0] != 0;
                ok
            }
            (Device::Drive, 0x27) => {
                self.robot.motor_fault_notify = d[0] != 0;
                ok
            }
            (Device::Sensor, 0x39..=0x3C) => {
                let processor = p
                    .tid
                    .and_then(Processor::of_id)
                    .unwrap_or(Processor::Primary);
                match self.robot.streaming(p.cid, d, processor, now) {
                    Ok(()) => ok,
                    Err(e) => (e, vec![]),
                }
            }
            (Device::Sensor, 0x25) => {
                // Calibrated at once: north is the room's +y, reported as a yaw.
                self.robot.compass_calibrating = false;
                let north = (360.0 - self.body.state.yaw_deg).rem_euclid(360.0) as u16 % 360;
                self.notify(0x18, 0x26, north.to_be_bytes().to_vec());
                ok
            }
            (Device::Sensor, 0x30) => (ErrorCode::Success, 320.0f32.to_be_bytes().to_vec()),
            (Device::Sensor, 0x27..=0x2B | 0x32..=0x34 | 0x3E | 0x3F) => {
                let steering = self.ir.behaviour.is_some();
                let place = self.body.cfg.place.as_ref();
                let r = self.ir.command(p.cid, d, place, self.body.state.yaw_deg);
                if steering && self.ir.behaviour.is_none() {
                    // The behaviour ended: the robot stops where it is.
                    self.body.stop_motion();
                }
                answer(r.map(|()| Vec::new()))
            }
            (Device::Sensor, 0x23) => (
                ErrorCode::Success,
                [128u16, 128, 128, 384]
                    .iter()
                    .flat_map(|v| v.to_be_bytes())
                    .collect(),
            ),
            (Device::Sensor, 0x38) => {
                self.robot.color_detection = d[0] != 0;
                ok
            }
            (Device::Sensor, 0x35) => {
                if d[0] != 0 {
                    self.notify(0x18, 0x36, vec![128, 128, 128, 0, 230]);
                }
                ok
            }
            (Device::Sensor, 0x37) => {
                self.notify(0x18, 0x36, vec![128, 128, 128, 0, 230]);
                ok
            }
            (Device::ApiAndShell, 0x00) => (ErrorCode::Success, d.to_vec()),
            (Device::ApiAndShell, 0x01) => (ErrorCode::Success, vec![2, 0]),
            (Device::Connection, 0x04 | 0x05) => {
                let mut name = self.advertised_name().into_bytes();
                name.push(0);
                (ErrorCode::Success, name)
            }
            (Device::Io, 0x0E) => self.set_leds(u16_at(0) as u32, &d[2..]),
            (Device::Io, 0x1C) => self.set_leds(d[0] as u32, &d[1..]),
            (Device::Io, 0x1A) => self.set_leds(u32_at(0), &d[4..]),
            // Everything else is accepted; getters answer with a well-formed payload.
            _ => (ErrorCode::Success, catalog::minimal_payload(def.response)),
        }
    }

    fn advertised_name(&self) -> String {
        format!("{}5117", self.body.model().name_prefix().unwrap_or("SIM-"))
    }

    fn set_leds(&mut self, mask: u32, values: &[u8]) -> (ErrorCode, Vec<u8>) {
        let valid = super::robots::led_mask(self.body.model());
        if mask & !valid != 0 {
            return (ErrorCode::BadParameterValue, vec![]);
        }
        if values.len() != mask.count_ones() as usize {
            return (ErrorCode::BadDataLength, vec![]);
        }
        let mut v = values.iter();
        for bit in 0..32 {
            if mask & (1 << bit) != 0
                && let Some(val) = v.next()
            {
                if bit < 16 {
                    self.body.state.leds[bit] = *val;
                }
                self.robot.leds[bit] = *val;
            }
        }
        (ErrorCode::Success, vec![])
    }
}

/// The simulator's firmware version, major, minor, revision (System Info's version answers).
fn version_bytes() -> Vec<u8> {
    [4u16, 0, 1].iter().flat_map(|v| v.to_be_bytes()).collect()
}

/// The processor a notification comes from on a two-processor robot.
fn targets_home(model: Model, did: u8, cid: u8) -> Option<Processor> {
    match crate::protocol::v2::catalog::targets::home(model, did, cid) {
        crate::protocol::v2::catalog::targets::Home::On(p) => Some(p),
        _ => None,
    }
}
