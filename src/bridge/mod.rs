//! A bridge for other programs (issue 20): one versioned JSON interface at the level of
//! "drive", "lights" and "telemetry", over standard input/output ([`stdio`]) and MQTT
//! ([`mqtt`]), driving a [`Fleet`].
//!
//! - [`schema`] (sans-IO): commands parsed into typed values, what goes out serialized; the
//!   same contract is `assets/bridge.schema.json`.
//! - [`motion`] (sans-IO): each droid's held drive or twist and the command timeout.
//! - This module: the [`Bridge`], each droid's state, and the tick of the command timeout
//!   under `tokio::time`; `execute` carries commands to the droids through their families
//!   (a command a robot cannot do is an error naming the robot and the capability);
//!   [`feeds`] what each droid reports (samples, collisions, battery, link state).
//! - The transports at the edges hand lines or payloads to [`Bridge::handle`] and take
//!   [`Out`] values from the channel [`Bridge::start`] returns.

pub mod broker;
mod cruise;
mod execute;
pub mod feeds;
pub mod ha_light;
pub mod hold;
pub mod homeassistant;
pub mod inbox;
pub mod kept;
pub mod motion;
pub mod mqtt;
pub mod msgpack;
pub mod outbox;
mod played;
pub mod presence;
pub mod ready;
pub mod ros;
pub mod schema;
pub mod stdio;
pub mod takeover;
pub mod thread;
mod topics;

pub use topics::{topic_name, topic_names, topic_names_besides};

use crate::family::intent::{Intent, one_command};
use crate::fleet::Fleet;
use crate::model::Model;
use crate::session::Slot;
use crate::sync::lock;
use crate::units::Heading;
use motion::{Holder, Kinematics, Tick, Wheels};
use outbox::{Outbox, Outputs};
use schema::Out;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::task::JoinHandle;
use tokio::time::Instant;

/// Requests (lights, sounds …) waiting for one droid's answer at most; more are refused
/// as `busy`.
pub const MAX_IN_FLIGHT: usize = 32;

/// What the bridge is told by the command line and the config's `[bridge]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// A droid driven over the bridge stops when no drive or twist came for this long.
    pub command_timeout: Duration,
    /// Telemetry samples per second per droid.
    pub telemetry_hz: u16,
    /// How often the battery is read.
    pub battery_poll: Duration,
    /// MQTT: Home Assistant's discovery prefix, to publish discovery under
    /// ([`homeassistant`]); `None`: none published.
    pub homeassistant: Option<String>,
    /// MQTT: clear the Home Assistant discovery at a clean exit (kept by default: the
    /// entities stay, unavailable, as Zigbee2MQTT's and ESPHome's do).
    pub homeassistant_remove: bool,
    /// MQTT: droid topic levels live on the broker already (another bridge's, lowercase:
    /// [`presence::probe`]); a droid of the same name takes a distinct one.
    pub taken_topics: std::collections::HashSet<String>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            command_timeout: Duration::from_millis(600),
            telemetry_hz: 10,
            battery_poll: Duration::from_secs(10),
            homeassistant: None,
            homeassistant_remove: false,
            taken_topics: Default::default(),
        }
    }
}

/// A droid's speed at 255 and, for a steering robot, its yaw rate at full lock. No spec
/// gives either: these are the simulator's figures (`sim::SimConfig`: 160 cm/s for the
/// Spheros, 30 cm/s for Robi 42), so a twist on a simulated droid moves as asked; a real
/// droid's may differ.
pub fn kinematics(model: Model) -> Kinematics {
    let family = crate::family::for_model(model);
    Kinematics {
        steers: family.steers(),
        can_reverse: family.can_reverse(),
        top_speed_m_s: if family.steers() { 0.30 } else { 1.60 },
        full_lock_rad_s: 1.0,
    }
}

/// Everything the bridge keeps about one droid, in one place: its topic level (fixed at
/// start) and its changing state behind one lock. (It used to be five vectors side by side,
/// under mutexes and atomics of their own, that every change had to keep in step.)
struct Droid {
    /// The droid's MQTT topic level ([`topic_names`]).
    topic: String,
    state: Mutex<DroidState>,
    /// Ready at least once since the bridge started ([`ready`]: the stdio reader waits for it).
    was_ready: tokio::sync::watch::Sender<bool>,
}

struct DroidState {
    /// The held drive or twist and the command timeout.
    holder: Holder,
    setup: crate::family::setup::SetupOptions,
    /// Requests (lights, sounds …) waiting for the droid's answer ([`MAX_IN_FLIGHT`]).
    in_flight: usize,
    /// The latest battery reading, for samples (the fleet's fold has only what the droid
    /// notifies).
    battery: Option<f32>,
    /// Connected and its connect setup done ([`ready`]).
    ready: bool,
    /// Held (`hold`, issue 40 point 6): what would move it is refused until `release`.
    held: bool,
    /// The speed of a `drive` that gives none ([`Cmd::Cruise`](schema::Cmd::Cruise)).
    cruise: u8,
    /// The last animation and sound played ([`Out::Played`]), retained on MQTT.
    played: [Option<Out>; 2],
}

/// The bridge's capability words, each with the flags of the model table it stands for
/// (an `unsupported` error's `capability` is one of these words; `screen` only says that the
/// matrix commands draw on BOLT+'s screen, it has no commands of its own).
pub const CAPABILITY_WORDS: [(&str, crate::model::Caps); 9] = {
    use crate::model::Caps;
    [
        ("dome", Caps::DOME),
        ("legs", Caps::LEGS),
        ("lights", Caps::LIGHTS),
        ("animations", Caps::ANIMATIONS),
        ("sounds", Caps::ANIMATIONS),
        ("matrix", Caps::MATRIX),
        ("screen", Caps::SCREEN),
        ("streaming", Caps::STREAMING),
        ("reverse", Caps::HEADING),
    ]
};

/// What droid `model` can do, in the words of an `unsupported` error's `capability`: read
/// from the model table, not probed from the family.
pub fn capabilities(model: Model) -> Vec<&'static str> {
    CAPABILITY_WORDS
        .into_iter()
        .filter_map(|(word, caps)| model.has(caps).then_some(word))
        .collect()
}

/// New samples a second droid `model` offers with `setup`: the bridge's rate `hz`, or its
/// streaming rate when slower (0: it streams nothing). A droid that streams by itself
/// (Robi 42's state frames) is sampled at the bridge's rate.
pub fn offered_hz(model: Model, setup: &crate::family::setup::SetupOptions, hz: u16) -> u16 {
    if crate::family::for_model(model).stream_caps(model).is_none() {
        return hz;
    }
    let plan = setup.stream_plan(model);
    if !plan.is_on() {
        return 0;
    }
    (plan.rate_hz().floor() as u16).clamp(1, hz.max(1))
}

/// The bridge: a fleet, each droid's held motion and setup, and where objects go out.
pub struct Bridge {
    fleet: Fleet,
    settings: Settings,
    start: Instant,
    /// One per fleet member, in the fleet's order.
    droids: Vec<Droid>,
    out: Outbox,
    tasks: Mutex<Vec<JoinHandle<()>>>,
}

impl Droid {
    /// The droid's state, for one short step (never held across an `await` or a send).
    fn lock(&self) -> std::sync::MutexGuard<'_, DroidState> {
        crate::sync::lock(&self.state)
    }
}

impl Bridge {
    /// Start the bridge on `fleet` (each droid's connect setup in `setups`, in the fleet's
    /// order): its control tick and each droid's feeds. What goes out arrives on the
    /// receiver, a link object per droid first.
    pub fn start(
        fleet: Fleet,
        setups: Vec<crate::family::setup::SetupOptions>,
        settings: Settings,
    ) -> (Arc<Bridge>, Outputs) {
        let (tx, rx) = outbox::channel();
        let topics = topic_names_besides(&fleet.names(), &settings.taken_topics);
        let droids = fleet
            .members()
            .iter()
            .zip(topics)
            .enumerate()
            .map(|(i, (m, topic))| Droid {
                topic,
                state: Mutex::new(DroidState {
                    holder: Holder::new(kinematics(m.model), settings.command_timeout),
                    setup: setups.get(i).copied().unwrap_or_default(),
                    in_flight: 0,
                    battery: None,
                    ready: false,
                    held: false,
                    cruise: 0,
                    played: [None, None],
                }),
                was_ready: tokio::sync::watch::Sender::new(false),
            })
            .collect();
        let n = fleet.len();
        let bridge = Arc::new(Bridge {
            fleet,
            settings,
            start: Instant::now(),
            droids,
            out: tx,
            tasks: Mutex::new(Vec::new()),
        });
        let mut tasks = vec![tokio::spawn(control(Arc::downgrade(&bridge)))];
        for i in 0..n {
            tasks.extend(feeds::spawn(&bridge, i));
            tasks.push(tokio::spawn(ready::watch(Arc::downgrade(&bridge), i)));
        }
        *lock(&bridge.tasks) = tasks;
        (bridge, rx)
    }

    pub fn fleet(&self) -> &Fleet {
        &self.fleet
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Milliseconds since the bridge started (the `t_ms` of what it sends).
    pub fn t_ms(&self) -> u64 {
        self.start.elapsed().as_millis() as u64
    }

    /// Telemetry objects dropped because the transport did not keep up (replies, errors,
    /// `stopped` and `link` objects never are).
    pub fn dropped(&self) -> u64 {
        self.out.dropped()
    }

    /// Droid `i`'s MQTT topic level (distinct per droid).
    pub fn topic(&self, i: usize) -> Option<&str> {
        self.droids.get(i).map(|d| d.topic.as_str())
    }

    /// Wait until the transport has taken enough of what waits for it: a transport reads
    /// its next command only then, so answers are never dropped and never pile up.
    pub async fn room(&self) {
        self.out.room().await
    }

    /// The `hello` object: the droids and the settings that bind a client. Its
    /// `telemetry_hz` is the most any droid offers ([`offered_hz`]).
    pub fn hello(&self) -> Out {
        let droids: Vec<schema::DroidInfo> = (0..self.fleet.len())
            .filter_map(|i| self.droid_info(i))
            .collect();
        Out::Hello {
            droidctl: env!("CARGO_PKG_VERSION"),
            telemetry_hz: droids
                .iter()
                .map(|d| d.telemetry_hz)
                .max()
                .unwrap_or(self.settings.telemetry_hz)
                .max(1),
            droids,
            command_timeout_ms: self.settings.command_timeout.as_millis() as u64,
        }
    }

    /// The samples a second droid `i` offers now ([`offered_hz`] of its setup as the last
    /// `stream` left it): the one value `hello`, `info` and the sampler ([`feeds`]) read,
    /// so they always agree (issue 40 point 9).
    pub fn telemetry_hz(&self, i: usize) -> u16 {
        match (self.fleet.member(i), self.droids.get(i)) {
            (Some(m), Some(d)) => {
                let setup = d.lock().setup;
                offered_hz(m.model, &setup, self.settings.telemetry_hz)
            }
            _ => 0,
        }
    }

    /// Droid `i` as `hello` lists it.
    pub fn droid_info(&self, i: usize) -> Option<schema::DroidInfo> {
        let m = self.fleet.member(i)?;
        let d = self.droids.get(i)?;
        Some(schema::DroidInfo {
            droid: m.name.clone(),
            model: m.model.id(),
            robot: m.model.display_name(),
            origin: m.origin.clone(),
            topic: d.topic.clone(),
            capabilities: capabilities(m.model),
            telemetry_hz: self.telemetry_hz(i),
            top_speed_m_s: kinematics(m.model).top_speed_m_s,
        })
    }

    /// The `info` object of droid `i` (its MQTT `info` topic, retained).
    pub fn info(&self, i: usize) -> Option<Out> {
        Some(Out::Info {
            droidctl: env!("CARGO_PKG_VERSION"),
            info: self.droid_info(i)?,
            command_timeout_ms: self.settings.command_timeout.as_millis() as u64,
        })
    }

    /// Whether droid `i` is ready: a drive sent now moves it.
    pub fn is_ready(&self, i: usize) -> bool {
        self.droids.get(i).is_some_and(|d| d.lock().ready)
    }

    /// Send `o`, about droid `droid` (its index), to the transport: telemetry is dropped
    /// (counted) when the transport does not keep up, anything else is kept.
    pub fn emit(&self, droid: Option<usize>, o: Out) {
        self.out.send(droid, o)
    }

    /// Droid `i`'s link state when it is not connected.
    pub(super) fn link_down(&self, i: usize) -> Option<String> {
        let s = self.fleet.link_state(i)?;
        let s = s.borrow();
        (*s != crate::session::LinkState::Connected).then(|| s.label())
    }

    pub(super) fn connected(&self, i: usize) -> bool {
        self.fleet
            .link_state(i)
            .is_some_and(|s| *s.borrow() == crate::session::LinkState::Connected)
    }

    /// Write the wheels' command into droid `i`'s drive slot.
    fn write_wheels(&self, i: usize, w: Wheels) {
        let Some(m) = self.fleet.member(i) else {
            return;
        };
        let drive = |speed, heading, reverse| Intent::Drive {
            speed,
            heading,
            reverse,
        };
        // Lowered by the droid's family; a robot driven toward a heading has no steering
        // (`motion` gives it only to steering robots): it rolls straight ahead instead.
        let c = match w {
            Wheels::Roll {
                speed,
                heading,
                reverse,
            } => one_command(
                m.family,
                m.model,
                &drive(speed, Heading::new(heading).unwrap_or_default(), reverse),
            ),
            Wheels::Steer { speed, turn } => {
                one_command(m.family, m.model, &Intent::Steer { speed, turn }).or_else(|| {
                    one_command(m.family, m.model, &drive(speed, Heading::default(), false))
                })
            }
        };
        if let Some(c) = c {
            m.session.set(Slot::Drive, c);
        }
    }

    /// Every droid stops now; nothing stays held.
    pub fn estop(&self) {
        self.fleet.estop_all();
        for d in &self.droids {
            d.lock().holder.stop();
        }
    }

    /// Stop the droids of `which` that are being driven over the bridge (the client's
    /// stream or the broker is gone), saying why.
    pub fn release(&self, which: impl IntoIterator<Item = usize>, reason: &'static str) {
        for i in which {
            if self.fleet.member(i).is_none() {
                continue;
            }
            let driving = {
                let mut d = self.droids[i].lock();
                let was = d.holder.is_driving();
                d.holder.stop();
                was
            };
            if driving {
                self.stop_here(i);
                self.said_stopped(i, reason);
            }
        }
    }

    /// The `stopped` object for droid `i`.
    fn said_stopped(&self, i: usize, reason: &'static str) {
        let Some(m) = self.fleet.member(i) else {
            return;
        };
        let message = match reason {
            "input_closed" => "the command stream ended: stopped".into(),
            "broker_lost" => "the connection to the broker was lost: stopped".into(),
            "link_lost" => "the droid's link went down: what it was told to do is dropped \
                            (it stops by its own fail-safe and on reconnecting); drive it \
                            again once its link says connected"
                .into(),
            _ => "stopped".into(),
        };
        self.emit(
            Some(i),
            Out::Stopped {
                droid: m.name.clone(),
                reason,
                message,
            },
        );
    }

    /// One tick of every droid's command timeout and held motion.
    fn tick(&self) {
        let now = self.start.elapsed();
        for (i, d) in self.droids.iter().enumerate() {
            // A droid whose link is down holds nothing: a held drive re-sent meanwhile
            // would wait in its session's queue and drive it after the reconnect.
            if !self.connected(i) {
                let was = {
                    let mut d = d.lock();
                    let was = d.holder.is_driving();
                    d.holder.stop();
                    was
                };
                if was {
                    self.said_stopped(i, "link_lost");
                }
                continue;
            }
            let t = d.lock().holder.tick(now);
            match t {
                Tick::Nothing => {}
                Tick::Send(w) => self.write_wheels(i, w),
                Tick::TimedOut => {
                    if let Some(m) = self.fleet.member(i) {
                        self.stop_here(i);
                        self.emit(
                            Some(i),
                            Out::Stopped {
                                droid: m.name.clone(),
                                reason: "timeout",
                                message: format!(
                                    "no drive or twist for {} ms: stopped",
                                    self.settings.command_timeout.as_millis()
                                ),
                            },
                        );
                    }
                }
            }
        }
    }

    /// Stop the feeds and the tick, then stop and disconnect every droid.
    pub async fn shutdown(&self) {
        for t in lock(&self.tasks).drain(..) {
            t.abort();
        }
        for d in &self.droids {
            d.lock().holder.stop();
        }
        self.fleet.shutdown_all(|_| Vec::new()).await;
    }

    fn set_battery(&self, i: usize, v: f32) {
        if let Some(d) = self.droids.get(i) {
            d.lock().battery = Some(v);
        }
    }

    fn battery(&self, i: usize) -> Option<f32> {
        self.droids.get(i).and_then(|d| d.lock().battery)
    }

    /// Say whether droid `i` is ready ([`ready`]); its link's feed says not at every change.
    fn set_ready(&self, i: usize, ready: bool) {
        if let Some(d) = self.droids.get(i) {
            d.lock().ready = ready;
        }
    }

    /// Let the commands held for droid `i`'s first `ready` go ([`Bridge::first_ready`]).
    /// Called after the link object saying ready has been emitted, so no answer to them can
    /// be said before it.
    fn release_first_commands(&self, i: usize) {
        if let Some(d) = self.droids.get(i) {
            d.was_ready.send_replace(true);
        }
    }
}

/// The control tick: every [`motion::TICK`] while the bridge lives.
async fn control(bridge: std::sync::Weak<Bridge>) {
    let mut every = tokio::time::interval(motion::TICK);
    every.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        every.tick().await;
        match bridge.upgrade() {
            Some(b) => b.tick(),
            None => return,
        }
    }
}

#[cfg(test)]
mod cruise_tests;
#[cfg(test)]
mod hostile_tests;
#[cfg(test)]
mod integrator_tests;
#[cfg(test)]
mod safety_tests;
#[cfg(test)]
mod tests;
