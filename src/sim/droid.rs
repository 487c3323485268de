//! The simulated droid as a sans-IO state machine: wire bytes and time in, packets out.

use super::SimConfig;
use super::physics::{angle_diff, approach, clamp_to_room, heading_vector, wrap360};
use crate::model::Model;
use crate::protocol::v2::catalog;
use crate::protocol::v2::notify::Collision;
use crate::protocol::v2::sensor::{StreamingConfig, encode_sample};
use crate::protocol::v2::wire::{AccelRaw, CollisionAxis, DriveFlags, LegAction, LegState};
use crate::protocol::v2::{Decoder, Device, ErrorCode, Flags, Packet};
use crate::units::{HEAD_MAX_DEG, HEAD_MIN_DEG};
use std::time::Duration;

/// Everything observable about the simulated droid (for tests, `run` and the UI's sim panel).
#[derive(Debug, Clone, PartialEq)]
pub struct SimState {
    pub awake: bool,
    pub x_cm: f32,
    pub y_cm: f32,
    /// Where the body faces, 0..360, clockwise from +y.
    pub yaw_deg: f32,
    /// Signed speed along the facing (negative when backing up), cm/s.
    pub velocity_cm_s: f32,
    pub stance: LegState,
    pub head_deg: f32,
    pub battery_v: f32,
    pub collisions: u32,
    pub animation_playing: bool,
    pub sound_playing: bool,
    /// LED values by mask bit (R2: front RGB, logic, back RGB, holo).
    pub leds: [u8; 16],
    pub volume: u8,
    /// Commands received, and bytes the droid's decoder rejected.
    pub commands: u64,
    pub decode_errors: u64,
}

#[derive(Debug, Clone, Copy)]
struct Drive {
    /// Target speed magnitude, cm/s.
    speed: f32,
    /// Target facing.
    facing: f32,
    backward: bool,
    at: Duration,
}

#[derive(Debug, Clone, Copy)]
struct Transition {
    target: LegState,
    ends: Duration,
}

/// The simulated droid.
#[derive(Debug, Clone)]
pub struct SimDroid {
    model: Model,
    cfg: SimConfig,
    decoder: Decoder,
    now: Duration,
    state: SimState,
    drive: Option<Drive>,
    head_target: f32,
    transition: Option<Transition>,
    last_activity: Duration,
    inactivity_timeout: Duration,
    will_sleep_sent: bool,
    streaming: StreamingConfig,
    next_sample: Duration,
    collision_notify: bool,
    collision_dead_time: Duration,
    last_collision: Option<Duration>,
    battery_state_notify: bool,
    voltage_state_notify: bool,
    voltage_state: u8,
    animation_ends: Option<Duration>,
    sound_ends: Option<Duration>,
    sounds_queued: u32,
    accel_fwd: f32,
    yaw_rate: f32,
    out: Vec<Packet>,
}

/// Devices that answer while asleep; the rest say target_unavailable until Wake.
fn answers_asleep(did: u8) -> bool {
    matches!(
        Device::from_id(did),
        Some(Device::Core | Device::Power | Device::SystemInfo)
    )
}

impl SimDroid {
    pub fn new(model: Model, cfg: SimConfig) -> Self {
        let inactivity_timeout = cfg.inactivity_timeout;
        let battery = cfg.battery_start_v;
        SimDroid {
            model,
            decoder: Decoder::new(),
            now: Duration::ZERO,
            state: SimState {
                awake: false,
                x_cm: 0.0,
                y_cm: 0.0,
                yaw_deg: 0.0,
                velocity_cm_s: 0.0,
                // Assumption: R2 rests on two legs until told otherwise; BB-9E has none.
                stance: if model.has_legs() {
                    LegState::Bipod
                } else {
                    LegState::Unknown
                },
                head_deg: 0.0,
                battery_v: battery,
                collisions: 0,
                animation_playing: false,
                sound_playing: false,
                leds: [0; 16],
                volume: 128,
                commands: 0,
                decode_errors: 0,
            },
            cfg,
            drive: None,
            head_target: 0.0,
            transition: None,
            last_activity: Duration::ZERO,
            inactivity_timeout,
            will_sleep_sent: false,
            streaming: StreamingConfig::default(),
            next_sample: Duration::ZERO,
            collision_notify: false,
            collision_dead_time: Duration::from_millis(100),
            last_collision: None,
            battery_state_notify: false,
            voltage_state_notify: false,
            voltage_state: 1,
            animation_ends: None,
            sound_ends: None,
            sounds_queued: 0,
            accel_fwd: 0.0,
            yaw_rate: 0.0,
            out: Vec::new(),
        }
    }

    pub fn model(&self) -> Model {
        self.model
    }

    pub fn state(&self) -> &SimState {
        &self.state
    }

    pub fn now(&self) -> Duration {
        self.now
    }

    /// Wire bytes from the host at time `now`; returns the packets the droid sends back
    /// (responses, and any notifications due up to `now`).
    pub fn receive(&mut self, bytes: &[u8], now: Duration) -> Vec<Packet> {
        self.advance_to(now);
        let packets: Vec<_> = self.decoder.feed(bytes).collect();
        for r in packets {
            match r {
                Ok(p) => self.handle(p),
                Err(_) => self.state.decode_errors += 1,
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
        self.out.push(Packet::notification(did, cid, data));
    }

    fn advance_to(&mut self, now: Duration) {
        let step = self.cfg.step.max(Duration::from_millis(1));
        while self.now + step <= now {
            self.now += step;
            self.step(step.as_secs_f32());
        }
    }

    fn handle(&mut self, p: Packet) {
        if p.is_response() || p.is_notification() {
            return;
        }
        self.state.commands += 1;
        if p.flags.contains(Flags::IS_ACTIVITY) {
            self.last_activity = self.now;
            self.will_sleep_sent = false;
        }
        let (err, data) = self.execute(&p);
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
        if !self.model.has_legs()
            && device == Device::Animatronic
            && !matches!(p.cid, 0x05 | 0x2B | 0x2C)
        {
            // BB-9E has no legs and no dome to command.
            return (ErrorCode::BadCommandId, vec![]);
        }
        if !catalog::length_ok(def.params, p.data.len()) {
            return (ErrorCode::BadDataLength, vec![]);
        }
        if !self.state.awake && !answers_asleep(p.did) {
            return (ErrorCode::TargetUnavailable, vec![]);
        }
        let d = &p.data;
        let u16_at = |i: usize| u16::from_be_bytes([d[i], d[i + 1]]);
        let f32_at = |i: usize| f32::from_be_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]]);
        let u32_at = |i: usize| u32::from_be_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]]);
        let ok = (ErrorCode::Success, vec![]);
        match (device, p.cid) {
            (Device::Power, 0x0D) => {
                if !self.state.awake {
                    self.state.awake = true;
                    self.last_activity = self.now;
                }
                ok
            }
            (Device::Power, 0x01) | (Device::Power, 0x00) | (Device::Core, 0x22) => {
                self.fall_asleep();
                ok
            }
            (Device::Power, 0x03) => (ErrorCode::Success, self.centivolts().to_be_bytes().to_vec()),
            (Device::Power, 0x04) => (ErrorCode::Success, vec![self.battery_state()]),
            (Device::Power, 0x05) => {
                self.battery_state_notify = d[0] != 0;
                ok
            }
            (Device::Power, 0x10) => (ErrorCode::Success, vec![self.battery_percent()]),
            (Device::Power, 0x17) => (ErrorCode::Success, vec![self.voltage_state_now()]),
            (Device::Power, 0x1B) => {
                self.voltage_state_notify = d[0] != 0;
                ok
            }
            (Device::Power, 0x25) => (
                ErrorCode::Success,
                self.state.battery_v.to_be_bytes().to_vec(),
            ),
            (Device::Core, 0x25) => {
                self.inactivity_timeout = Duration::from_secs(u16_at(0).max(1) as u64);
                ok
            }
            (Device::Core, 0x11) => {
                let mut info = self.advertised_name().into_bytes();
                info.push(0);
                info.extend_from_slice(b"00:00:00:5E:D2:D2\0");
                (ErrorCode::Success, info)
            }
            (Device::SystemInfo, 0x00) | (Device::SystemInfo, 0x01) => (
                ErrorCode::Success,
                [4u16, 0, 1].iter().flat_map(|v| v.to_be_bytes()).collect(),
            ),
            (Device::SystemInfo, 0x1F) => (ErrorCode::Success, b"droidctl-sim\0".to_vec()),
            (Device::SystemInfo, 0x39) => (
                ErrorCode::Success,
                (self.now.as_millis() as u32).to_be_bytes().to_vec(),
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
                    wrap360(heading as f32 + 180.0)
                } else {
                    heading as f32
                };
                self.drive = Some(Drive {
                    speed: d[0] as f32 / 255.0 * self.cfg.top_speed_cm_s,
                    facing,
                    backward,
                    at: self.now,
                });
                ok
            }
            (Device::Drive, 0x06) => {
                // Reset Yaw: the current facing becomes heading 0.
                self.state.yaw_deg = 0.0;
                if let Some(dr) = &mut self.drive {
                    dr.facing = 0.0;
                }
                ok
            }
            (Device::Animatronic, 0x05) => {
                self.animation_ends = Some(self.now + self.cfg.animation_time);
                self.state.animation_playing = true;
                ok
            }
            (Device::Animatronic, 0x2B) => {
                self.animation_ends = None;
                self.state.animation_playing = false;
                ok
            }
            (Device::Animatronic, 0x0D) => match LegAction::from_byte(d[0]) {
                Some(a) => {
                    self.leg_action(a);
                    ok
                }
                None => (ErrorCode::BadParameterValue, vec![]),
            },
            (Device::Animatronic, 0x0F) => {
                let deg = f32_at(0);
                if !deg.is_finite() {
                    return (ErrorCode::BadParameterValue, vec![]);
                }
                self.head_target = deg.clamp(HEAD_MIN_DEG, HEAD_MAX_DEG);
                ok
            }
            (Device::Animatronic, 0x14) => (
                ErrorCode::Success,
                self.state.head_deg.to_be_bytes().to_vec(),
            ),
            (Device::Animatronic, 0x25) => {
                let s = if self.transition.is_some() {
                    LegState::Transitioning
                } else {
                    self.state.stance
                };
                (ErrorCode::Success, vec![s.to_byte()])
            }
            (Device::Sensor, 0x00) => {
                self.streaming.interval_ms = u16_at(0);
                self.streaming.mask = u32_at(3);
                self.next_sample =
                    self.now + Duration::from_millis(self.streaming.interval_ms as u64);
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
                ok
            }
            (Device::Sensor, 0x0D) => (
                ErrorCode::Success,
                self.streaming.ext_mask.to_be_bytes().to_vec(),
            ),
            (Device::Sensor, 0x11) => {
                self.collision_notify = d[0] != 0;
                self.collision_dead_time = Duration::from_millis(d[5] as u64 * 10);
                ok
            }
            (Device::Sensor, 0x14) => {
                self.collision_notify = d[0] != 0;
                ok
            }
            (Device::Sensor, 0x13) => {
                self.state.x_cm = 0.0;
                self.state.y_cm = 0.0;
                ok
            }
            (Device::Io, 0x07) => {
                self.play_sound(d[2]);
                ok
            }
            (Device::Io, 0x08) => {
                self.state.volume = d[0];
                ok
            }
            (Device::Io, 0x09) => (ErrorCode::Success, vec![self.state.volume]),
            (Device::Io, 0x0A) => {
                self.sound_ends = None;
                self.sounds_queued = 0;
                self.state.sound_playing = false;
                ok
            }
            (Device::Io, 0x0E) => self.set_leds(u16_at(0) as u32, &d[2..]),
            (Device::Io, 0x1C) => self.set_leds(d[0] as u32, &d[1..]),
            (Device::Io, 0x1A) => self.set_leds(u32_at(0), &d[4..]),
            // Everything else is accepted; getters answer with a well-formed payload.
            _ => (ErrorCode::Success, catalog::minimal_payload(def.response)),
        }
    }

    fn advertised_name(&self) -> String {
        format!("{}5117", self.model.name_prefix().unwrap_or("SIM-"))
    }

    fn set_leds(&mut self, mask: u32, values: &[u8]) -> (ErrorCode, Vec<u8>) {
        // R2: 8 LEDs; BB-9E: body RGB, aiming, head (`droid-facts.md` §2).
        let valid: u32 = if self.model.has_legs() { 0xFF } else { 0x1F };
        if mask & !valid != 0 {
            return (ErrorCode::BadParameterValue, vec![]);
        }
        if values.len() != mask.count_ones() as usize {
            return (ErrorCode::BadDataLength, vec![]);
        }
        let mut v = values.iter();
        for bit in 0..16 {
            if mask & (1 << bit) != 0
                && let Some(val) = v.next()
            {
                self.state.leds[bit] = *val;
            }
        }
        (ErrorCode::Success, vec![])
    }

    fn play_sound(&mut self, mode: u8) {
        let playing = self.sound_ends.is_some();
        match mode {
            // Only if idle: ignored while a sound plays.
            1 if playing => {}
            // After current: queued.
            2 if playing => self.sounds_queued += 1,
            _ => {
                self.sound_ends = Some(self.now + self.cfg.sound_time);
                self.state.sound_playing = true;
            }
        }
    }

    fn leg_action(&mut self, a: LegAction) {
        let current = self
            .transition
            .map(|t| t.target)
            .unwrap_or(self.state.stance);
        let (target, time) = match a {
            LegAction::Stop => {
                // Stop ends a waddle at once, standing on two legs.
                if current == LegState::Waddle {
                    self.transition = None;
                    self.state.stance = LegState::Bipod;
                }
                self.notify(0x17, 0x26, vec![]);
                return;
            }
            LegAction::Tripod => (LegState::Tripod, self.cfg.stance_time),
            LegAction::Bipod => (LegState::Bipod, self.cfg.stance_time),
            // Waddle starts from bipod: from tripod it first has to stand up.
            LegAction::Waddle if current == LegState::Tripod => {
                (LegState::Waddle, self.cfg.stance_time)
            }
            LegAction::Waddle => (LegState::Waddle, Duration::from_millis(300)),
        };
        let time = if current == target {
            Duration::from_millis(50)
        } else {
            time
        };
        self.transition = Some(Transition {
            target,
            ends: self.now + time,
        });
    }

    fn fall_asleep(&mut self) {
        if self.state.awake {
            self.state.awake = false;
            self.drive = None;
            self.streaming = StreamingConfig::default();
            self.notify(0x13, 0x1A, vec![]);
        }
    }

    fn centivolts(&self) -> u16 {
        (self.state.battery_v * 100.0).round().clamp(0.0, 65535.0) as u16
    }

    fn battery_percent(&self) -> u8 {
        (((self.state.battery_v - 3.4) / (4.2 - 3.4)) * 100.0).clamp(0.0, 100.0) as u8
    }

    /// Battery voltage state: 1 ok, 2 low, 3 critical.
    fn voltage_state_now(&self) -> u8 {
        match self.state.battery_v {
            v if v < 3.45 => 3,
            v if v < 3.6 => 2,
            _ => 1,
        }
    }

    /// Battery state for Get Battery State / the state-changed notification: 3 ok, 4 low,
    /// 5 critical.
    fn battery_state(&self) -> u8 {
        self.voltage_state_now() + 2
    }

    /// Can the droid roll now? R2 only in tripod, not mid-transition.
    fn can_roll(&self) -> bool {
        !self.model.has_legs()
            || (self.state.stance == LegState::Tripod && self.transition.is_none())
    }

    fn step(&mut self, dt: f32) {
        let now = self.now;
        // Stance transitions.
        if let Some(t) = self.transition.filter(|t| now >= t.ends) {
            self.state.stance = t.target;
            self.transition = None;
            self.notify(0x17, 0x26, vec![]);
        }
        // Animation and sound completion. The specs define no audio-complete notification,
        // so sounds only end (and start the next queued one).
        if self.animation_ends.is_some_and(|e| now >= e) {
            self.animation_ends = None;
            self.state.animation_playing = false;
            self.notify(0x17, 0x11, vec![]);
        }
        if self.sound_ends.is_some_and(|e| now >= e) {
            if self.sounds_queued > 0 {
                self.sounds_queued -= 1;
                self.sound_ends = Some(now + self.cfg.sound_time);
            } else {
                self.sound_ends = None;
                self.state.sound_playing = false;
            }
        }
        // Sleep on inactivity, warning 10 s before.
        if self.state.awake {
            let idle = now.saturating_sub(self.last_activity);
            let warn_at = self
                .inactivity_timeout
                .saturating_sub(Duration::from_secs(10));
            if idle >= self.inactivity_timeout {
                self.fall_asleep();
            } else if idle >= warn_at && !self.will_sleep_sent {
                self.will_sleep_sent = true;
                self.notify(0x13, 0x19, vec![]);
            }
        }
        self.motion(dt);
        self.dome(dt);
        self.battery(dt);
        self.stream();
    }

    fn motion(&mut self, dt: f32) {
        let now = self.now;
        // The droid stops by itself when drive commands stop.
        if self
            .drive
            .is_some_and(|d| now.saturating_sub(d.at) > self.cfg.motion_timeout)
            && let Some(d) = &mut self.drive
        {
            d.speed = 0.0;
        }
        let rolling = self.can_roll() && self.state.awake;
        let (target_speed, target_facing, backward) = match self.drive {
            Some(d) if rolling => (d.speed, d.facing, d.backward),
            _ => (0.0, self.state.yaw_deg, self.state.velocity_cm_s < 0.0),
        };
        // Turn toward the commanded facing at a finite rate.
        let before = self.state.yaw_deg;
        let diff = angle_diff(before, target_facing);
        let turn = diff.clamp(
            -self.cfg.turn_rate_deg_s * dt,
            self.cfg.turn_rate_deg_s * dt,
        );
        self.state.yaw_deg = wrap360(before + turn);
        self.yaw_rate = turn / dt;
        // Speed with acceleration limits; signed along the facing.
        let target_v = if backward {
            -target_speed
        } else {
            target_speed
        };
        let v = self.state.velocity_cm_s;
        let limit = if target_v.abs() < v.abs() || target_v.signum() != v.signum() {
            self.cfg.brake_cm_s2
        } else {
            self.cfg.accel_cm_s2
        };
        let new_v = approach(v, target_v, limit * dt);
        self.accel_fwd = (new_v - v) / dt;
        self.state.velocity_cm_s = new_v;
        // Dead reckoning.
        let (hx, hy) = heading_vector(self.state.yaw_deg);
        let x = self.state.x_cm + hx * new_v * dt;
        let y = self.state.y_cm + hy * new_v * dt;
        let half_w = self.cfg.room_cm.0 / 2.0 - self.cfg.radius_cm;
        let half_h = self.cfg.room_cm.1 / 2.0 - self.cfg.radius_cm;
        let ((cx, cy), hit_x, hit_y) = clamp_to_room(x, y, half_w, half_h);
        self.state.x_cm = cx;
        self.state.y_cm = cy;
        if hit_x || hit_y {
            self.collide(new_v, hx, hy, hit_x, hit_y);
        }
    }

    fn collide(&mut self, v: f32, hx: f32, hy: f32, hit_x: bool, hit_y: bool) {
        // A wall stops the droid; it stays stopped until the next drive command.
        self.state.velocity_cm_s = 0.0;
        if let Some(d) = &mut self.drive {
            d.speed = 0.0;
        }
        if v.abs() < 1.0 {
            return;
        }
        let now = self.now;
        if self.last_collision.is_some_and(|t| {
            now.saturating_sub(t) < self.collision_dead_time.max(Duration::from_millis(10))
        }) {
            return;
        }
        self.last_collision = Some(now);
        self.state.collisions += 1;
        if !self.collision_notify {
            return;
        }
        // Impact deceleration over ~50 ms, in g (÷4096 on the wire).
        let g = |comp: f32| {
            AccelRaw((-(comp * v) / 0.05 / 981.0 * 4096.0).clamp(-32768.0, 32767.0) as i16)
        };
        let c = Collision {
            accel: [g(hx), g(hy), AccelRaw(4096)],
            axis: CollisionAxis { x: hit_x, y: hit_y },
            power: [
                (hx * v * 2.0).clamp(-32768.0, 32767.0) as i16,
                (hy * v * 2.0).clamp(-32768.0, 32767.0) as i16,
                0,
            ],
            speed: (v.abs() / self.cfg.top_speed_cm_s * 255.0).clamp(0.0, 255.0) as u8,
            time_ms: now.as_millis() as u32,
        };
        self.notify(0x18, 0x12, c.encode());
    }

    fn dome(&mut self, dt: f32) {
        if self.model.has_dome() && self.state.awake {
            self.state.head_deg = approach(
                self.state.head_deg,
                self.head_target,
                self.cfg.head_rate_deg_s * dt,
            );
        }
    }

    fn battery(&mut self, dt: f32) {
        if !self.state.awake {
            return;
        }
        let before_state = self.voltage_state_now();
        let load = (self.state.velocity_cm_s.abs() / self.cfg.top_speed_cm_s).min(1.0);
        let drain = (self.cfg.drain_idle_v_s + self.cfg.drain_drive_v_s * load) * dt;
        self.state.battery_v = (self.state.battery_v - drain).max(3.0);
        let after = self.voltage_state_now();
        if after != before_state || after != self.voltage_state {
            self.voltage_state = after;
            if self.voltage_state_notify {
                self.notify(0x13, 0x1C, vec![after]);
            }
            if self.battery_state_notify {
                let s = self.battery_state();
                self.notify(0x13, 0x06, vec![s]);
            }
        }
    }

    fn stream(&mut self) {
        if !self.state.awake || !self.streaming.is_streaming() || self.now < self.next_sample {
            return;
        }
        self.next_sample = self.now + Duration::from_millis(self.streaming.interval_ms as u64);
        let s = &self.state;
        let (hx, hy) = heading_vector(s.yaw_deg);
        let lateral = s.velocity_cm_s * self.yaw_rate.to_radians();
        let yaw = if s.yaw_deg > 180.0 {
            s.yaw_deg - 360.0
        } else {
            s.yaw_deg
        };
        let half = s.yaw_deg.to_radians() / 2.0;
        let values = [
            ("quaternion_w", half.cos()),
            ("quaternion_x", 0.0),
            ("quaternion_y", 0.0),
            ("quaternion_z", half.sin()),
            // The body leans against acceleration.
            ("pitch", (-self.accel_fwd / 981.0 * 30.0).clamp(-20.0, 20.0)),
            ("roll", (lateral / 981.0 * 30.0).clamp(-20.0, 20.0)),
            ("yaw", yaw),
            ("accel_x", lateral / 981.0),
            ("accel_y", self.accel_fwd / 981.0),
            ("accel_z", 1.0),
            ("accel_one", 1000.0),
            ("locator_x", s.x_cm),
            ("locator_y", s.y_cm),
            ("velocity_x", hx * s.velocity_cm_s),
            ("velocity_y", hy * s.velocity_cm_s),
            ("speed", s.velocity_cm_s.abs()),
            ("core_time", self.now.as_millis() as f32),
            ("head_angle", s.head_deg),
            ("gyro_x", 0.0),
            ("gyro_y", 0.0),
            ("gyro_z", self.yaw_rate),
        ];
        let data = encode_sample(&self.streaming, &values);
        self.notify(0x18, 0x02, data);
    }
}
