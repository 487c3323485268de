//! Faithful simulated droids: R2-D2, R2-Q5 and BB-9E speaking API v2, BB-8, SPRK+ and Ollie
//! speaking API v1, through the same protocol core as the real thing. One [`body::Body`]
//! (motion, walls, battery, sleep, sensors) sits behind a protocol front per family
//! ([`droid::SimDroid`] for v2, [`v1::SimDroidV1`]); both are sans-IO state machines driven
//! by explicit time. [`link::SimLink`] runs either behind the [`crate::link::Link`] trait with
//! fault injection, so the session, UI and scripts cannot tell it from a droid.

pub mod animation;
pub mod body;
// The virtual BlueZ of `droidctl sim --bluez`: D-Bus exists only on Linux.
#[cfg(target_os = "linux")]
pub mod bluez;
pub mod droid;
pub mod faults;
pub mod figures;
pub mod gatt;
pub mod impact;
pub mod infrared;
pub mod link;
mod physics;
pub mod robi;
pub mod robots;
pub mod room;
#[cfg(unix)]
pub mod serial;
pub mod sleep;
pub mod trace;
pub mod v1;

pub use body::SimState;
pub use droid::SimDroid;
pub use robi::SimRobi;
pub use v1::SimDroidV1;

/// A simulated droid seen from the link: bytes in, whole encoded packets out (the link cuts
/// them into notifications).
pub trait WireDroid: Send {
    fn receive(&mut self, bytes: &[u8], now: Duration) -> Vec<Vec<u8>>;
    /// A write to another input than the command channel (Robi's remote control).
    fn receive_at(&mut self, to: Endpoint, bytes: &[u8], now: Duration) -> Vec<Vec<u8>> {
        match to {
            Endpoint::Api => self.receive(bytes, now),
            _ => Vec::new(),
        }
    }
    /// What the host reads and confirms while connecting (Robi: the handshake, then the
    /// start confirmation that starts the frames). Returns the values read.
    fn connect(&mut self, _now: Duration) -> Vec<Vec<u8>> {
        Vec::new()
    }
    /// The link is gone (Robi disables its motors).
    fn disconnected(&mut self, _now: Duration) {}
    /// Every packet is one notification, never split (RSRCP over BLE).
    fn whole_notifications(&self) -> bool {
        false
    }
    fn advance(&mut self, now: Duration) -> Vec<Vec<u8>>;
    fn state(&self) -> &SimState;
    /// A person puts the droid on its charger, or takes it off (the rolling robots; Robi 42
    /// has no charger the protocol reports).
    fn set_on_charger(&mut self, _on: bool) {}
    /// The packet that warns of sleep, as the family sends it; `None` for a droid that never
    /// sleeps (Robi 42).
    fn will_sleep(&self) -> Option<Vec<u8>>;
    /// What a read of the handshake characteristic returns (Robi: version and interval);
    /// empty for droids with nothing to read.
    fn handshake_value(&self) -> Vec<u8> {
        Vec::new()
    }
    /// When [`WireDroid::advance`] next has something to return: `None` to be advanced every
    /// physics step (the default), else the earliest time (`Duration::MAX`: nothing pending).
    /// The link steps the droid no more often than that.
    fn next_due(&self) -> Option<Duration> {
        None
    }
    /// What the droid shows that no packet says, for traces: BOLT's matrix. `None` for
    /// droids without such a thing.
    fn shows(&self) -> Option<String> {
        None
    }
}

impl WireDroid for SimDroid {
    fn receive(&mut self, bytes: &[u8], now: Duration) -> Vec<Vec<u8>> {
        SimDroid::receive(self, bytes, now)
            .iter()
            .map(|p| p.encode())
            .collect()
    }
    fn advance(&mut self, now: Duration) -> Vec<Vec<u8>> {
        SimDroid::advance(self, now)
            .iter()
            .map(|p| p.encode())
            .collect()
    }
    fn state(&self) -> &SimState {
        SimDroid::state(self)
    }
    fn set_on_charger(&mut self, on: bool) {
        SimDroid::set_on_charger(self, on);
    }
    /// Power / Will Sleep (13h/19h).
    fn will_sleep(&self) -> Option<Vec<u8>> {
        Some(crate::protocol::v2::Packet::notification(0x13, 0x19, Vec::new()).encode())
    }
    fn next_due(&self) -> Option<Duration> {
        SimDroid::next_due(self)
    }
    /// BOLT's matrix, or BOLT+'s screen (the same 8×8 picture, `Caps::SCREEN`).
    fn shows(&self) -> Option<String> {
        let what = if self.model().has_screen() {
            "screen"
        } else {
            "matrix"
        };
        self.model()
            .has_matrix()
            .then(|| format!("{what}: {}", self.robot().matrix.summary()))
    }
}

/// The simulator only builds packets that fit their DLEN; one that did not would be dropped.
impl WireDroid for SimDroidV1 {
    /// With stop-on-disconnect set, the droid stops the moment the link drops.
    fn disconnected(&mut self, now: Duration) {
        SimDroidV1::host_gone(self, now);
    }

    fn receive(&mut self, bytes: &[u8], now: Duration) -> Vec<Vec<u8>> {
        SimDroidV1::receive(self, bytes, now)
            .iter()
            .filter_map(|p| p.encode().ok())
            .collect()
    }
    fn advance(&mut self, now: Duration) -> Vec<Vec<u8>> {
        SimDroidV1::advance(self, now)
            .iter()
            .filter_map(|p| p.encode().ok())
            .collect()
    }
    fn state(&self) -> &SimState {
        SimDroidV1::state(self)
    }
    fn set_on_charger(&mut self, on: bool) {
        SimDroidV1::set_on_charger(self, on);
    }
    /// The pre-sleep warning (async ID 05h).
    fn will_sleep(&self) -> Option<Vec<u8>> {
        use crate::protocol::v1::{AsyncPacket, Packet};
        Packet::Async(AsyncPacket::new(0x05, Vec::new()))
            .encode()
            .ok()
    }
    fn next_due(&self) -> Option<Duration> {
        SimDroidV1::next_due(self)
    }
}

/// A simulator front: the droid of a family, and its own physical figures.
struct Front {
    config: fn() -> SimConfig,
    build: fn(Model, SimConfig) -> Box<dyn WireDroid>,
}

/// The one place a model's protocol picks its simulator front.
fn front(model: Model) -> Front {
    match model.protocol() {
        Protocol::SpheroV2 => Front {
            config: SimConfig::default,
            build: |m, cfg| Box::new(SimDroid::new(m, cfg)),
        },
        Protocol::SpheroV1 => Front {
            config: SimConfig::default,
            build: |m, cfg| Box::new(SimDroidV1::new(m, cfg)),
        },
        Protocol::Rsrcp => Front {
            config: SimRobi::config,
            build: |_, cfg| Box::new(SimRobi::new(cfg)),
        },
    }
}

/// The simulated droid of a model, speaking its family's protocol.
pub fn wire_droid(model: Model, cfg: SimConfig) -> Box<dyn WireDroid> {
    (front(model).build)(model, cfg)
}
pub use faults::Faults;
pub use link::SimLink;

use crate::gatt::Endpoint;
use crate::model::{Model, Protocol};
use std::time::Duration;

/// Whether `--sim MODEL` can simulate this model.
pub fn simulates(model: Model) -> bool {
    model.drivable()
}

/// The ids of the simulated models, for messages.
pub fn simulated_ids() -> Vec<&'static str> {
    Model::ALL
        .into_iter()
        .filter(|m| simulates(*m))
        .map(Model::id)
        .collect()
}

/// The simulated world and the droid's physical figures. Figures marked *unverified* in
/// `droid-facts.md` are here so they can be changed.
#[derive(Debug, Clone)]
pub struct SimConfig {
    /// Speed 255 in cm/s. About 1.6 m/s for R2-D2 (issue 3; no better figure found).
    pub top_speed_cm_s: f32,
    /// Acceleration and braking limits, cm/s².
    pub accel_cm_s2: f32,
    pub brake_cm_s2: f32,
    /// How fast the body turns toward the commanded heading, °/s (the model's own rate in
    /// [`SimConfig::for_model`]; the default is a generic 180°/s).
    pub turn_rate_deg_s: f32,
    /// How fast the dome moves, °/s.
    pub head_rate_deg_s: f32,
    /// The droid stops by itself when drive commands stop for this long, from the start
    /// (*unverified*: a reference client re-sends at least every 0.8 s, `droid-facts.md` §2).
    /// `None` by default: a droid keeps its last motion until the host sets a fail-safe
    /// (v2 Set Custom Control System Timeout; v1 stop-on-disconnect), the worst case the
    /// host must guard against.
    pub motion_timeout: Option<Duration>,
    /// A stance change takes this long (`droid-facts.md` §2: about 2 s).
    pub stance_time: Duration,
    /// Room size in cm; the droid starts in the middle, at locator (0, 0).
    pub room_cm: (f32, f32),
    /// The droid's radius: how close its centre gets to a wall.
    pub radius_cm: f32,
    /// Inactivity timeout before sleep (changed by Set Inactivity Timeout).
    pub inactivity_timeout: Duration,
    /// Battery at start, and drain while awake (V/s), and extra at full speed.
    pub battery_start_v: f32,
    pub drain_idle_v_s: f32,
    pub drain_drive_v_s: f32,
    pub animation_time: Duration,
    pub sound_time: Duration,
    /// Physics step.
    pub step: Duration,
    /// Differential drive (Robi 42; raw motors of the others, [`figures`]): distance between
    /// the wheels, and wheel radius
    /// (motor rad/s = wheel speed / radius). *Unverified* figures for a small school robot.
    pub track_cm: f32,
    pub wheel_radius_cm: f32,
    /// Robi 42: the interval its handshake announces (MSDT), the interval it really sends
    /// frames at (they differ on real robots: 10 ms announced, 100 ms sent, `droid-facts.md`
    /// §5), and one frame in this many is lost on the air (0: none).
    pub robi_msdt_ms: u16,
    pub robi_frame_interval: Duration,
    pub robi_drop_every: u32,
    /// A room shared with other simulated droids (`None`: alone in its own room).
    pub place: Option<room::Place>,
}

impl SimConfig {
    /// The defaults with the model's own figures: its size and turn rate ([`figures`]), as
    /// its simulator front has them (Robi 42 is a slow differential-drive robot).
    pub fn for_model(model: Model) -> SimConfig {
        let mut cfg = (front(model).config)();
        if let Some(f) = figures::of(model) {
            cfg.radius_cm = f.radius_cm;
            cfg.turn_rate_deg_s = f.turn_rate_deg_s;
            cfg.track_cm = f.track_cm;
        }
        cfg
    }
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            top_speed_cm_s: 160.0,
            accel_cm_s2: 150.0,
            brake_cm_s2: 300.0,
            turn_rate_deg_s: 180.0,
            head_rate_deg_s: 180.0,
            motion_timeout: None,
            stance_time: Duration::from_secs(2),
            room_cm: (400.0, 400.0),
            radius_cm: 10.0,
            inactivity_timeout: Duration::from_secs(300),
            battery_start_v: 4.10,
            drain_idle_v_s: 0.0002,
            drain_drive_v_s: 0.0008,
            animation_time: Duration::from_secs(3),
            sound_time: Duration::from_millis(1500),
            step: Duration::from_millis(10),
            track_cm: crate::telemetry::ROBI_TRACK_CM,
            wheel_radius_cm: crate::telemetry::ROBI_WHEEL_RADIUS_CM,
            robi_msdt_ms: 10,
            robi_frame_interval: Duration::from_millis(100),
            robi_drop_every: 40,
            place: None,
        }
    }
}
