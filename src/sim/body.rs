//! The simulated droid's body: position, motion, walls, dome, legs, battery, sleep and the
//! sensor clock. It knows no protocol: a protocol front (`sim::v2`, `sim::v1`) turns wire
//! commands into calls here and the [`SimEvent`]s it emits into wire notifications, so every
//! simulated model shares one physics.

use super::SimConfig;
use super::physics::{approach, clamp_to_room, heading_vector, unwrap_toward, wrap360};
use super::sleep::{SleepStep, SleepTimer};
use crate::model::Model;
use crate::protocol::notify::Collision;
use crate::protocol::wire::{LegAction, LegState};
use crate::units::{HEAD_MAX_DEG, HEAD_MIN_DEG};
use std::time::Duration;

/// A droid warns this long before it falls asleep for inactivity.
const WARN_BEFORE_SLEEP: Duration = Duration::from_secs(10);

/// The slowest contact with a wall that counts as a collision, cm/s.
const MIN_IMPACT_CM_S: f32 = 10.0;

pub use super::impact::{CollisionThresholds, POWER_PER_CM_S};

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

/// What the body reports; the front decides what reaches the wire (and how).
#[derive(Debug, Clone, PartialEq)]
pub enum SimEvent {
    LegActionComplete,
    AnimationComplete,
    WillSleep,
    DidSleep,
    /// Battery voltage state changed: 1 ok, 2 low, 3 critical.
    VoltageState(u8),
    /// A collision, when collision detection is on.
    Collision(Collision),
    /// Put on its charger (`true`) or taken off it.
    Charger(bool),
    /// A sensor sample is due (streaming on): values by name, in the units of
    /// `droid-facts.md` (degrees, g, °/s, cm, cm/s).
    Sample(Vec<(&'static str, f32)>),
}

#[derive(Debug, Clone, Copy)]
struct Drive {
    /// Target speed magnitude, cm/s.
    speed: f32,
    /// Target facing, unwrapped: on the same count of turns as [`Body::yaw`], so the body
    /// turns toward it the way the commands went, not the short way.
    facing: f32,
    backward: bool,
    at: Duration,
}

#[derive(Debug, Clone, Copy)]
struct Transition {
    target: LegState,
    ends: Duration,
}

/// The simulated body.
#[derive(Debug, Clone)]
pub struct Body {
    model: Model,
    pub(super) cfg: SimConfig,
    now: Duration,
    pub(super) state: SimState,
    drive: Option<Drive>,
    /// Differential drive (Robi 42): left and right wheel, 0..=1 of top speed. Replaces
    /// `drive` while set; there is no motion timeout (the robot holds its last command).
    wheels: Option<(f32, f32)>,
    /// When the tracks were last commanded (RVR's raw motors), for the control timeout.
    tracks_at: Option<Duration>,
    /// Stop when drive commands stop for this long (`None`: keep the last motion).
    control_timeout: Option<Duration>,
    /// The facing counted in whole turns (not wrapped; `state.yaw_deg` is it wrapped).
    yaw: f32,
    head_target: f32,
    transition: Option<Transition>,
    /// Soft sleep on inactivity, warning 10 s before (changed by Set Inactivity Timeout).
    sleep: SleepTimer,
    /// Sensor streaming period (`None`: off).
    stream_every: Option<Duration>,
    next_sample: Duration,
    /// Collision detection on, and its dead time.
    pub(super) collision_notify: bool,
    pub(super) collision_dead_time: Duration,
    pub(super) collision_thresholds: CollisionThresholds,
    last_collision: Option<Duration>,
    voltage_state: u8,
    animation_ends: Option<Duration>,
    sound_ends: Option<Duration>,
    sounds_queued: u32,
    accel_fwd: f32,
    yaw_rate: f32,
    /// The turn rate as the gyroscope reports it: [`yaw_rate`](Self::yaw_rate) through a
    /// first-order low-pass of [`GYRO_TAU`] (issue 38 point 11: the body turns toward each
    /// new heading of a spin at its full rate, then stands until the next, so the step's rate
    /// sampled read 0 on about half the samples of a spin).
    gyro_rate: f32,
    events: Vec<SimEvent>,
    /// A hop off the floor at full raw power: lift-off and touch-down ([`HOP_AIR`]).
    hop: Option<(Duration, Duration)>,
    /// On its charger ([`Body::set_on_charger`]).
    on_charger: bool,
}

/// How fast the battery fills on the charger, V/s (*unverified*: about an hour from empty).
const CHARGE_V_S: f32 = 0.0003;
/// Full.
const FULL_V: f32 = 4.2;

/// How long a rolling robot is off the floor when both raw motors go to full power from
/// rest: Sphero's own docs for `rawMotor` say full power on both motors makes the robot
/// jump, stabilization being off (Sphero Edu JavaScript, "Movement", Raw Motor; spherov2.py's
/// `raw_motor` docstring repeats it). How high is not published: 0.45 s in the air (a hop of
/// about 25 cm) is *unverified*, chosen so that the free-fall tests of both Sphero's docs
/// ("< 0.1 g for ≥ 0.1 s") and spherov2's `SpheroEduAPI` (0.2 s) see it at a 100 ms sample
/// interval, and a program's `onFreefall` and `onLanding` can be tried in the simulator.
pub const HOP_AIR: Duration = Duration::from_millis(450);
/// The landing's jolt lasts this long in the accelerometer's readings (long enough for one
/// sample at 100 ms), at this many g.
const LANDING: Duration = Duration::from_millis(100);
const LANDING_G: f32 = 2.5;
/// The gyroscope's smoothing, s: its reading follows the turn rate like a first-order
/// low-pass of this time constant. No spec gives the droids' IMU filter; a motion IMU's
/// digital low-pass is typically tens of Hz down to a few (InvenSense MPU-6050 datasheet,
/// DLPF_CFG: 5–260 Hz), and 0.1 s (1.6 Hz) is what makes a 10 Hz sample of the simulated
/// body's step-by-step spin read its average rate: an assumption, chosen for that.
const GYRO_TAU: f32 = 0.1;

/// The most the gyroscope measures, °/s (a faster spin reads this).
const GYRO_MAX: f32 = 2000.0;
/// Full power: this share of it or more on both motors, the same way.
const HOP_POWER: f32 = 0.95;

impl Body {
    pub fn new(model: Model, cfg: SimConfig) -> Self {
        let sleep = SleepTimer::new(cfg.inactivity_timeout, WARN_BEFORE_SLEEP);
        let control_timeout = cfg.motion_timeout;
        let battery = cfg.battery_start_v;
        Body {
            model,
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
            wheels: None,
            tracks_at: None,
            control_timeout,
            yaw: 0.0,
            head_target: 0.0,
            transition: None,
            sleep,
            stream_every: None,
            next_sample: Duration::ZERO,
            collision_notify: false,
            collision_dead_time: Duration::from_millis(100),
            collision_thresholds: CollisionThresholds::default(),
            last_collision: None,
            voltage_state: 1,
            animation_ends: None,
            sound_ends: None,
            sounds_queued: 0,
            accel_fwd: 0.0,
            yaw_rate: 0.0,
            gyro_rate: 0.0,
            events: Vec::new(),
            hop: None,
            on_charger: false,
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

    /// Run the physics up to `now`.
    pub fn advance_to(&mut self, now: Duration) {
        let step = self.cfg.step.max(Duration::from_millis(1));
        while self.now + step <= now {
            self.now += step;
            self.step(step.as_secs_f32());
        }
    }

    /// When the body next has something to say: `None` while it must be stepped every step
    /// (rolling: a wall can come at any step), else the earliest time an event can come (a
    /// sample, the end of a stance change or an animation, the sleep warning, a battery level
    /// crossed; `Duration::MAX` for none). Integration does not depend on how often
    /// [`Body::advance_to`] is called, so a host may call it only then.
    pub fn next_due(&self) -> Option<Duration> {
        let rolling = self.state.velocity_cm_s != 0.0
            || self.drive.is_some_and(|d| d.speed != 0.0)
            || self.wheels.is_some_and(|(l, r)| l != 0.0 || r != 0.0);
        if rolling {
            return None;
        }
        let mut due = Duration::MAX;
        let mut at = |t: Duration| due = due.min(t);
        if let Some(t) = self.transition {
            at(t.ends);
        }
        if let Some(t) = self.animation_ends {
            at(t);
        }
        if let Some(t) = self.sound_ends {
            at(t);
        }
        if self.state.awake {
            if self.stream_every.is_some() {
                at(self.next_sample);
            }
            at(self.sleep.next_due());
            // The battery drains at the idle rate: the next level it crosses (3.6 V, 3.45 V).
            let v = self.state.battery_v;
            if self.voltage_state_now() != self.voltage_state {
                at(self.now);
            } else if let Some(threshold) = [3.6f32, 3.45].into_iter().find(|t| v >= *t)
                && self.cfg.drain_idle_v_s > 0.0
            {
                let secs = ((v - threshold) / self.cfg.drain_idle_v_s).max(0.0) as f64;
                // A step early, against rounding.
                at((self.now + Duration::from_secs_f64(secs.min(1e9)))
                    .saturating_sub(self.cfg.step));
            }
        }
        Some(due)
    }

    /// What happened since the last call.
    pub fn take_events(&mut self) -> Vec<SimEvent> {
        std::mem::take(&mut self.events)
    }

    /// A command arrived that counts as activity (resets the inactivity timer).
    pub fn activity(&mut self) {
        self.sleep.activity(self.now);
    }

    pub fn wake(&mut self) {
        if !self.state.awake {
            self.state.awake = true;
            self.sleep.activity(self.now);
        }
    }

    pub fn set_inactivity_timeout(&mut self, t: Duration) {
        self.sleep.timeout = t.max(Duration::from_secs(1));
    }

    /// Roll at `speed` (0..=255 of top speed) facing `facing` degrees; `backward` backs up.
    pub fn drive(&mut self, speed: u8, facing: f32, backward: bool) {
        // Driving by heading ends driving by tracks (RVR takes either).
        self.wheels = None;
        self.tracks_at = None;
        let facing = unwrap_toward(self.drive.map_or(self.yaw, |d| d.facing), self.yaw, facing);
        self.drive = Some(Drive {
            speed: speed as f32 / 255.0 * self.cfg.top_speed_cm_s,
            facing,
            backward,
            at: self.now,
        });
    }

    /// The control-system timeout (v2's fail-safe): stop when drive commands stop this long.
    pub fn set_control_timeout(&mut self, t: Option<Duration>) {
        self.control_timeout = t.filter(|d| !d.is_zero());
    }

    /// Stop rolling now, keeping the facing (a fail-safe firing).
    pub fn stop_motion(&mut self) {
        if let Some(d) = &mut self.drive {
            d.speed = 0.0;
        }
        if self.wheels.is_some() {
            self.wheels = Some((0.0, 0.0));
        }
    }

    /// Differential drive: each wheel at `left`/`right` (0..=1) of top speed.
    pub fn drive_wheels(&mut self, left: f32, right: f32) {
        let c = |v: f32| {
            if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        self.drive = None;
        self.wheels = Some((c(left), c(right)));
    }

    /// Tracks (RVR's raw motors): each side at `left`/`right` in −1..=1 of top speed, and
    /// like a drive command, stopped by the control timeout when not renewed.
    pub fn drive_tracks(&mut self, left: f32, right: f32) {
        let c = |v: f32| {
            if v.is_finite() {
                v.clamp(-1.0, 1.0)
            } else {
                0.0
            }
        };
        let (l, r) = (c(left), c(right));
        let from_rest = self.state.velocity_cm_s.abs() < 0.2 * self.cfg.top_speed_cm_s;
        let full = l.abs() >= HOP_POWER && r.abs() >= HOP_POWER && l.signum() == r.signum();
        let down = self.hop.is_none_or(|(_, land)| self.now >= land + LANDING);
        if self.model.hops() && full && from_rest && down && self.state.awake {
            self.hop = Some((self.now, self.now + HOP_AIR));
        }
        self.drive = None;
        self.wheels = Some((l, r));
        self.tracks_at = Some(self.now);
    }

    /// In the air now (a hop, [`HOP_AIR`]).
    pub fn airborne(&self) -> bool {
        self.hop
            .is_some_and(|(up, down)| self.now >= up && self.now < down)
    }

    /// Each wheel's commanded speed in rad/s (Robi's motor report).
    pub fn wheel_rad_s(&self) -> (f32, f32) {
        let (l, r) = if self.state.awake {
            self.wheels.unwrap_or((0.0, 0.0))
        } else {
            (0.0, 0.0)
        };
        let k = self.cfg.top_speed_cm_s / self.cfg.wheel_radius_cm.max(0.1);
        (l * k, r * k)
    }

    /// The current facing becomes heading 0 (v2 Reset Yaw, v1 Set Heading 0).
    pub fn reset_yaw(&mut self) {
        self.set_heading(0.0);
    }

    /// The current facing becomes heading `deg` (v1 Set Heading). The droid does not move:
    /// a drive in progress now holds this facing. (Fix: v1 Set Heading used to reset the yaw
    /// to 0 and then overwrite the yaw alone, leaving the drive aiming at 0, so after Set
    /// Heading 45 the droid turned itself back by 45°.)
    pub fn set_heading(&mut self, deg: f32) {
        let deg = wrap360(deg);
        self.state.yaw_deg = deg;
        self.yaw = deg;
        if let Some(dr) = &mut self.drive {
            dr.facing = deg;
        }
    }

    pub fn reset_locator(&mut self) {
        self.state.x_cm = 0.0;
        self.state.y_cm = 0.0;
    }

    pub fn set_head_target(&mut self, deg: f32) {
        self.head_target = deg.clamp(HEAD_MIN_DEG, HEAD_MAX_DEG);
    }

    /// The stance now, or transitioning.
    pub fn stance_now(&self) -> LegState {
        if self.transition.is_some() {
            LegState::Transitioning
        } else {
            self.state.stance
        }
    }

    /// Stream samples every `every` (`None`: off).
    pub fn set_streaming(&mut self, every: Option<Duration>) {
        self.stream_every = every.filter(|d| !d.is_zero());
        if let Some(d) = self.stream_every {
            self.next_sample = self.now + d;
        }
    }

    pub fn play_animation(&mut self) {
        self.animation_ends = Some(self.now + self.cfg.animation_time);
        self.state.animation_playing = true;
    }

    pub fn stop_animation(&mut self) {
        self.animation_ends = None;
        self.state.animation_playing = false;
    }

    pub fn stop_sounds(&mut self) {
        self.sound_ends = None;
        self.sounds_queued = 0;
        self.state.sound_playing = false;
    }

    pub fn play_sound(&mut self, mode: u8) {
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

    pub fn leg_action(&mut self, a: LegAction) {
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
                self.events.push(SimEvent::LegActionComplete);
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

    pub fn fall_asleep(&mut self) {
        if self.state.awake {
            self.state.awake = false;
            self.drive = None;
            // Raw motors and tracks stop too: a droid woken again holds still.
            self.wheels = None;
            self.tracks_at = None;
            self.stream_every = None;
            self.events.push(SimEvent::DidSleep);
        }
    }

    pub fn centivolts(&self) -> u16 {
        (self.state.battery_v * 100.0).round().clamp(0.0, 65535.0) as u16
    }

    pub fn battery_percent(&self) -> u8 {
        (((self.state.battery_v - 3.4) / (4.2 - 3.4)) * 100.0).clamp(0.0, 100.0) as u8
    }

    /// Battery voltage state: 1 ok, 2 low, 3 critical.
    pub fn voltage_state_now(&self) -> u8 {
        match self.state.battery_v {
            v if v < 3.45 => 3,
            v if v < 3.6 => 2,
            _ => 1,
        }
    }

    /// Battery state for Get Battery State / the state-changed notification, as spherov2's
    /// `BatteryVoltageAndStateStates`: 1 charged and 2 charging (on the charger), 3 ok
    /// (not charging), 4 low, 5 critical.
    pub fn battery_state(&self) -> u8 {
        match (self.on_charger, self.state.battery_v >= FULL_V) {
            (true, true) => 1,
            (true, false) => 2,
            _ => self.voltage_state_now() + 2,
        }
    }

    /// On its charger or off it (a person puts it there: tests and the simulator's hosts
    /// call this). The droid says so (its battery-state or power notification), its battery
    /// fills, and it does not roll while it sits there.
    pub fn set_on_charger(&mut self, on: bool) {
        if self.on_charger != on {
            self.on_charger = on;
            self.events.push(SimEvent::Charger(on));
        }
    }

    pub fn on_charger(&self) -> bool {
        self.on_charger
    }

    /// Can the droid roll now? R2 only in tripod, not mid-transition.
    fn can_roll(&self) -> bool {
        !self.on_charger
            && (!self.model.has_legs()
                || (self.state.stance == LegState::Tripod && self.transition.is_none()))
    }

    fn step(&mut self, dt: f32) {
        let now = self.now;
        // Stance transitions.
        if let Some(t) = self.transition.filter(|t| now >= t.ends) {
            self.state.stance = t.target;
            self.transition = None;
            self.events.push(SimEvent::LegActionComplete);
        }
        // Animation and sound completion. The specs define no audio-complete notification,
        // so sounds only end (and start the next queued one).
        if self.animation_ends.is_some_and(|e| now >= e) {
            self.animation_ends = None;
            self.state.animation_playing = false;
            self.events.push(SimEvent::AnimationComplete);
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
            match self.sleep.poll(now, true) {
                Some(SleepStep::Sleep { .. }) => self.fall_asleep(),
                Some(SleepStep::Warn) => self.events.push(SimEvent::WillSleep),
                None => {}
            }
        }
        self.motion(dt);
        self.dome(dt);
        self.battery(dt);
        self.stream();
    }

    fn motion(&mut self, dt: f32) {
        let now = self.now;
        // With a control-system timeout, the droid stops by itself when drive commands stop.
        if let Some(limit) = self.control_timeout
            && self.drive.is_some_and(|d| now.saturating_sub(d.at) > limit)
            && let Some(d) = &mut self.drive
        {
            d.speed = 0.0;
        }
        if let (Some(limit), Some(at)) = (self.control_timeout, self.tracks_at)
            && now.saturating_sub(at) > limit
        {
            self.wheels = Some((0.0, 0.0));
            self.tracks_at = None;
        }
        let rolling = self.can_roll() && self.state.awake;
        let (target_speed, target_facing, backward) = match (self.wheels, self.drive) {
            // Differential drive: the wheel difference turns the body at (l − r)·v / track.
            (Some((l, r)), _) if rolling => {
                let top = self.cfg.top_speed_cm_s;
                let rate = (l - r) * top / self.cfg.track_cm.max(0.1) * 57.29578;
                ((l + r) / 2.0 * top, self.yaw + rate * dt, false)
            }
            (_, Some(d)) if rolling => (d.speed, d.facing, d.backward),
            _ => (0.0, self.yaw, self.state.velocity_cm_s < 0.0),
        };
        // Turn toward the commanded facing at the model's rate. Both are unwrapped, so the
        // body goes the way the commands went (fix, issue 32 point 1: with wrapped angles a
        // body that fell more than half a turn behind a spin's target turned back). Raw
        // motor power on a ball or Ollie is open-loop: nothing holds the spin to the control
        // system's rate, so opposite full power spins it like a top, past what its gyroscope
        // measures (Sphero's docs for `onGyroMax`: "spinning the robot around like a top").
        let open_loop = self.wheels.is_some() && self.model.hops();
        let max = if open_loop {
            f32::MAX
        } else {
            self.cfg.turn_rate_deg_s * dt
        };
        let turn = (target_facing - self.yaw).clamp(-max, max);
        self.yaw += turn;
        if self.yaw.abs() > 36_000.0 {
            // Keep the count of turns small (f32 precision); the drive's target moves along.
            let whole = (self.yaw / 360.0).trunc() * 360.0;
            self.yaw -= whole;
            if let Some(d) = &mut self.drive {
                d.facing -= whole;
            }
        }
        self.state.yaw_deg = wrap360(self.yaw);
        self.yaw_rate = turn / dt;
        let k = (dt / GYRO_TAU).min(1.0);
        self.gyro_rate += (self.yaw_rate - self.gyro_rate) * k;
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
        // In a shared room the walls are where they are for everyone: the locator counts
        // from the droid's own starting place.
        let (ox, oy) = self.cfg.place.as_ref().map_or((0.0, 0.0), |p| p.origin);
        let ((cx, cy), hit_x, hit_y) = clamp_to_room(x + ox, y + oy, half_w, half_h);
        self.state.x_cm = cx - ox;
        self.state.y_cm = cy - oy;
        if hit_x || hit_y {
            let impact = (
                if hit_x { hx * new_v } else { 0.0 },
                if hit_y { hy * new_v } else { 0.0 },
            );
            self.collide(new_v.abs(), impact);
        }
        self.other_droids(cx, cy, hx * new_v, hy * new_v);
    }

    /// Collisions with the other droids of a shared room: running into one stops this droid
    /// as a wall does; being hit is reported without stopping it.
    fn other_droids(&mut self, x: f32, y: f32, vx: f32, vy: f32) {
        let Some(place) = self.cfg.place.clone() else {
            return;
        };
        let v = self.state.velocity_cm_s.abs();
        if let Some(c) = place.moved(x, y, vx, vy) {
            self.state.x_cm = c.x - place.origin.0;
            self.state.y_cm = c.y - place.origin.1;
            self.collide(v, (c.nx * v, c.ny * v));
        }
        if let Some(h) = place.take_hit() {
            // Struck: the impact comes from the other droid's side.
            self.report_collision(h.speed, (h.dx * h.speed, h.dy * h.speed));
        }
    }

    /// Stop against an obstacle: `speed` the droid's speed, `impact` the velocity it loses
    /// against it (room axes, cm/s).
    fn collide(&mut self, speed: f32, impact: (f32, f32)) {
        // A wall stops the droid; it stays stopped until the next drive command.
        self.state.velocity_cm_s = 0.0;
        if let Some(d) = &mut self.drive {
            d.speed = 0.0;
        }
        self.report_collision(speed, impact);
    }

    /// Count a collision at `speed` cm/s with `impact` (room axes, cm/s, toward the obstacle)
    /// and notify it, in the robot's axes, when detection is on.
    fn report_collision(&mut self, speed: f32, impact: (f32, f32)) {
        // Fix: the bar was 1 cm/s, below one physics step of acceleration (1.5 cm/s at
        // 150 cm/s² and 10 ms), so a droid held against a wall by a drive heartbeat counted
        // (and reported) a fresh collision on every re-sent drive command. Pushing against
        // the wall is not an impact.
        if speed.abs() < MIN_IMPACT_CM_S {
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
        let speed = (speed.abs() / self.cfg.top_speed_cm_s * 255.0).clamp(0.0, 255.0) as u8;
        if let Some(c) = super::impact::detect(
            &self.collision_thresholds,
            self.state.yaw_deg,
            impact,
            speed,
            now.as_millis() as u32,
        ) {
            self.events.push(SimEvent::Collision(c));
        }
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
        if self.on_charger {
            self.state.battery_v = (self.state.battery_v + CHARGE_V_S * dt).min(FULL_V);
        } else {
            let load = (self.state.velocity_cm_s.abs() / self.cfg.top_speed_cm_s).min(1.0);
            let drain = (self.cfg.drain_idle_v_s + self.cfg.drain_drive_v_s * load) * dt;
            self.state.battery_v = (self.state.battery_v - drain).max(3.0);
        }
        let after = self.voltage_state_now();
        if after != before_state || after != self.voltage_state {
            self.voltage_state = after;
            self.events.push(SimEvent::VoltageState(after));
        }
    }

    fn stream(&mut self) {
        let Some(every) = self.stream_every else {
            return;
        };
        if !self.state.awake || self.now < self.next_sample {
            return;
        }
        self.next_sample = self.now + every;
        let values = self.sample_values();
        self.events.push(SimEvent::Sample(values));
    }

    /// What the sensors read now, by name, in the units the streaming decoders give
    /// (degrees, g, cm, cm/s): the mask streaming's sample and the streaming service's data.
    pub fn sample_values(&self) -> Vec<(&'static str, f32)> {
        let s = &self.state;
        let (hx, hy) = heading_vector(s.yaw_deg);
        let lateral = s.velocity_cm_s * self.yaw_rate.to_radians();
        let yaw = if s.yaw_deg > 180.0 {
            s.yaw_deg - 360.0
        } else {
            s.yaw_deg
        };
        let half = s.yaw_deg.to_radians() / 2.0;
        // Gravity holds 1 g up on the floor; in the air nothing is felt (free fall); the
        // landing is a jolt.
        let (ax, ay, az) = match self.hop {
            Some((up, down)) if self.now >= up && self.now < down => (0.0, 0.0, 0.0),
            Some((_, down)) if self.now >= down && self.now < down + LANDING => {
                (lateral / 981.0, self.accel_fwd / 981.0, LANDING_G)
            }
            _ => (lateral / 981.0, self.accel_fwd / 981.0, 1.0),
        };
        vec![
            ("quaternion_w", half.cos()),
            ("quaternion_x", 0.0),
            ("quaternion_y", 0.0),
            ("quaternion_z", half.sin()),
            // The body leans against acceleration.
            ("pitch", (-self.accel_fwd / 981.0 * 30.0).clamp(-20.0, 20.0)),
            ("roll", (lateral / 981.0 * 30.0).clamp(-20.0, 20.0)),
            ("yaw", yaw),
            ("accel_x", ax),
            ("accel_y", ay),
            ("accel_z", az),
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
            // The gyroscope measures ±2000°/s at most (droid-facts' streaming range).
            ("gyro_z", self.gyro_rate.clamp(-GYRO_MAX, GYRO_MAX)),
            // BOLT's ambient light and RVR's colour sensor see a lit, grey floor.
            ("ambient_light", 320.0),
            ("color_red", 128.0),
            ("color_green", 128.0),
            ("color_blue", 128.0),
            ("color_index", 0.0),
            ("color_confidence", 0.9),
            ("core_time_lower", self.now.as_millis() as f32),
        ]
    }
}
