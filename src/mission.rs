//! Runs a parsed mission script against a droid through a [`SessionHandle`], sampling
//! telemetry at a fixed interval. Against the simulator under paused tokio time a 60 s
//! mission takes well under a second of wall time with the same results as in real time.

pub mod csv;

use crate::family::intent::Intent;
use crate::family::{Command, Family};
use crate::model::{Caps, Model};
use crate::protocol::notify::Notification;
use crate::protocol::wire::{LegAction, LegState};
use crate::script::{Action, Step};
use crate::session::{LinkState, SessionEvent, SessionHandle, Slot};
use crate::sync::lock;
use crate::telemetry::{Stance, Telemetry};
use crate::units::Heading;
use serde::Serialize;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::broadcast;
use tokio::time::{Instant, sleep, timeout};

#[derive(Debug, Clone)]
pub struct MissionOptions {
    /// Telemetry sample interval.
    pub interval: Duration,
    /// While driving, the drive command is re-sent this often so the droid's motion timeout
    /// never stops it (a reference client re-sends at least every 0.8 s).
    pub heartbeat: Duration,
    /// How long to wait for the link before giving up.
    pub connect_timeout: Duration,
    /// How long a stance change may take before the mission goes on anyway.
    pub stance_timeout: Duration,
    /// How often the battery voltage is read.
    pub battery_poll: Duration,
    /// The connect setup the session was started with: a `stream` or `collision` line
    /// changes it, so a reconnect keeps what the mission set.
    pub setup: crate::family::setup::SetupOptions,
}

impl Default for MissionOptions {
    fn default() -> Self {
        MissionOptions {
            interval: Duration::from_millis(100),
            heartbeat: Duration::from_millis(500),
            connect_timeout: Duration::from_secs(20),
            stance_timeout: Duration::from_secs(5),
            battery_poll: Duration::from_secs(10),
            setup: crate::family::setup::SetupOptions {
                tripod: false,
                ..Default::default()
            },
        }
    }
}

/// One telemetry sample (`--json` prints these; `--csv` writes them as rows, [`csv`]).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Sample {
    pub t_ms: u64,
    pub x_cm: Option<f32>,
    pub y_cm: Option<f32>,
    /// Measured speed, cm/s.
    pub speed: Option<f32>,
    /// Measured heading, degrees 0..=359.
    pub heading: Option<u16>,
    pub head_deg: Option<f32>,
    /// `tripod`, `bipod` or `waddle`; null for a droid without legs, while unknown, and
    /// while a change is in progress (then `stance_to` says where to).
    pub stance: Option<String>,
    /// The stance a change in progress goes to (null when none is).
    #[serde(default)]
    pub stance_to: Option<String>,
    pub battery_v: Option<f32>,
    pub collisions: u32,
    /// Robi 42's wheel speeds, rad/s (absent for other droids).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motor_left_rad_s: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motor_right_rad_s: Option<f32>,
    /// Robi 42's frames received and lost so far.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lost_frames: Option<u64>,
    /// What the droid streams (null until it has streamed it, and on Robi 42).
    #[serde(default)]
    pub pitch_deg: Option<f32>,
    #[serde(default)]
    pub roll_deg: Option<f32>,
    #[serde(default)]
    pub yaw_deg: Option<f32>,
    /// Accelerometer x, y, z in g.
    #[serde(default)]
    pub accel_g: Option<[f32; 3]>,
    /// Gyro x, y, z in °/s.
    #[serde(default)]
    pub gyro_deg_s: Option<[f32; 3]>,
    /// Velocity x, y in cm/s.
    #[serde(default)]
    pub velocity_cm_s: Option<[f32; 2]>,
    /// Robi 42's potentiometer, 0..=255.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poti: Option<u8>,
}

/// The end of a mission (`--json` prints it with `"done": true`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    pub done: bool,
    pub t_ms: u64,
    pub sent: u64,
    pub received: u64,
    pub errors: u64,
    pub timeouts: u64,
    pub collisions: u32,
    pub failed_steps: u32,
    pub x_cm: Option<f32>,
    pub y_cm: Option<f32>,
}

/// What the runner reports as it goes.
#[derive(Debug, Clone, PartialEq)]
pub enum MissionEvent {
    Step {
        t_ms: u64,
        line: usize,
        text: String,
    },
    Sample(Sample),
    Warning {
        t_ms: u64,
        line: Option<usize>,
        message: String,
    },
}

/// A mission that could not go on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MissionError(pub String);

impl std::fmt::Display for MissionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// Check a script against a model before anything is sent (e.g. BB-9E has no legs, BB-8
/// no dome, sounds or animations): every line the model cannot do is an error naming it.
pub fn validate(model: Model, steps: &[Step]) -> Result<(), Vec<crate::script::ScriptError>> {
    let family = crate::family::for_model(model);
    let name = model.display_name();
    let errors: Vec<_> = steps
        .iter()
        .filter_map(|s| {
            let problem = match &s.action {
                // A steering robot (Robi 42) only drives, stops and waits.
                Action::Drive { .. } | Action::Stop | Action::Wait(_) => None,
                _ if family.steers() => {
                    Some(format!("{name} only takes drive, stop and wait lines"))
                }
                Action::Stance(_) if !model.has_legs() => Some(format!("{name} has no legs")),
                Action::Matrix(_) if !model.has_matrix() => {
                    Some(format!("{name} has no LED matrix"))
                }
                Action::Tank { .. } if !model.has_tracks() => Some(format!("{name} has no tracks")),
                Action::CalibrateCompass if !model.has_compass() => {
                    Some(format!("{name} has no compass"))
                }
                Action::Head(_) if !model.has_dome() => Some(format!("{name} has no dome to turn")),
                Action::Animation(_) if !model.has(Caps::ANIMATIONS) => {
                    Some(format!("{name} has no animations"))
                }
                Action::Sound(_) if !model.has(Caps::ANIMATIONS) => {
                    Some(format!("{name} cannot play sounds"))
                }
                Action::Stream { .. } if !model.has(Caps::STREAMING) => Some(format!(
                    "{name} streams by itself: its rate and sensors cannot be chosen"
                )),
                Action::Collision(c) if family.collision_detection(c).is_empty() => {
                    Some(format!("{name} has no collision detection to configure"))
                }
                a @ (Action::LedRgb(..) | Action::LedBrightness(..))
                    if Intent::of_action(a).is_none_or(|i| family.lower(model, &i).is_err()) =>
                {
                    Some(format!("{name} has no such LED"))
                }
                _ => None,
            };
            problem.map(|message| crate::script::ScriptError {
                line: s.line,
                message,
            })
        })
        .collect();
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors)
    }
}

/// Both tracks still (a `tank` line's end, or a stop after one).
const TRACKS_STOPPED: Intent = Intent::RawMotors { left: 0, right: 0 };

/// Where a mission's steps, samples and warnings go.
pub type Emit = Arc<dyn Fn(MissionEvent) + Send + Sync>;

/// The command that drives `family`'s droid at `speed` toward `heading` (a steering robot
/// reads the heading as a turn: [`crate::family::intent::drive`]).
pub fn drive_command(family: &dyn Family, speed: u8, heading: Heading) -> Command {
    crate::family::intent::drive(family, speed, heading, false)
}

struct Runner {
    session: SessionHandle,
    model: Model,
    family: &'static dyn Family,
    opts: MissionOptions,
    telemetry: Arc<Mutex<Telemetry>>,
    start: Instant,
    emit: Emit,
    /// The drive being held: speed, heading.
    driving: Option<(u8, Heading)>,
    /// The tracks being held (RVR): left, right.
    tracking: Option<(i16, i16)>,
    last_heading: Heading,
    events: broadcast::Receiver<SessionEvent>,
    failed: u32,
    /// A `sleep` line ran: the next `wake` re-runs the connect setup.
    slept: bool,
    /// The connect setup as the mission has changed it.
    setup: crate::family::setup::SetupOptions,
}

impl Runner {
    fn t_ms(&self) -> u64 {
        self.start.elapsed().as_millis() as u64
    }

    fn warn(&mut self, line: Option<usize>, message: String) {
        self.failed += 1;
        (self.emit)(MissionEvent::Warning {
            t_ms: self.t_ms(),
            line,
            message,
        });
    }

    /// The drive for a script's `drive SPEED HEADING` ([`drive_command`]).
    fn drive_cmd(&self, speed: u8, heading: Heading) -> Command {
        drive_command(self.family, speed, heading)
    }

    /// The one command `intent` is on this droid, as its family lowers it (`None`: it cannot;
    /// [`validate`] refused such a line before the run).
    fn one(&self, intent: &Intent) -> Option<Command> {
        crate::family::intent::one_command(self.family, self.model, intent)
    }

    /// Let `d` pass, re-sending the held drive command on the heartbeat.
    async fn hold(&mut self, d: Duration) {
        let end = Instant::now() + d;
        loop {
            let now = Instant::now();
            if now >= end {
                return;
            }
            let step = (end - now).min(self.opts.heartbeat);
            sleep(step).await;
            if let Some((speed, heading)) = self.driving
                && Instant::now() < end
            {
                self.session
                    .set(Slot::Drive, self.drive_cmd(speed, heading));
            }
            if let Some((left, right)) = self.tracking
                && Instant::now() < end
                && let Some(c) = self.one(&Intent::RawMotors { left, right })
            {
                self.session.set(Slot::Drive, c);
            }
        }
    }

    async fn request(&mut self, line: usize, c: Command) -> bool {
        let name = c.name();
        match self.session.request(c).await {
            Ok(_) => true,
            Err(e) => {
                self.warn(Some(line), format!("{name}: {e}"));
                false
            }
        }
    }

    /// Wait for the stance change to finish (leg-action-complete), bounded.
    async fn await_stance(&mut self) {
        let deadline = Instant::now() + self.opts.stance_timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match timeout(left, self.events.recv()).await {
                Ok(Ok(SessionEvent::Notification(Notification::LegActionComplete))) => return,
                Ok(Ok(_)) | Ok(Err(broadcast::error::RecvError::Lagged(_))) => continue,
                Ok(Err(broadcast::error::RecvError::Closed)) | Err(_) => {
                    self.warn(None, "stance change did not complete in time".into());
                    return;
                }
            }
        }
    }

    /// R2-D2 and R2-Q5 roll only in tripod, and wake on two legs: a drive on two legs would
    /// do nothing, silently (issue 26 point 9). As the app does, the mission puts the droid
    /// in tripod first, saying so (a note on stderr, and a step `stance tripod` of the same
    /// line, which a recording marks so replay sees the stance change when it came). The
    /// stance is read from the droid when the mission does not know it yet.
    async fn ensure_tripod(&mut self, line: usize) {
        if !self.model.has_legs() || self.family.steers() {
            return;
        }
        let mut known = lock(&self.telemetry).stance;
        if known == Stance::Unknown
            && let Some(c) = self.family.get_stance()
            && let Ok(p) = self.session.request(c).await
            && let Some(s) = p.data().first().and_then(|b| LegState::from_byte(*b))
        {
            known = Stance::from_state(s);
            let mut t = lock(&self.telemetry);
            if t.stance == Stance::Unknown {
                t.stance = known;
            }
        }
        // On its way to tripod: the mission's own `stance tripod`, already waited for.
        if matches!(
            known,
            Stance::Tripod | Stance::Transitioning(LegState::Tripod)
        ) {
            return;
        }
        let what = match known {
            Stance::Unknown => "its stance is unknown".to_string(),
            other => format!("it stands in {}", other.label()),
        };
        (self.emit)(MissionEvent::Warning {
            t_ms: self.t_ms(),
            line: Some(line),
            message: format!(
                "{} rolls only in tripod and {what}: putting it in tripod first",
                self.model.display_name()
            ),
        });
        (self.emit)(MissionEvent::Step {
            t_ms: self.t_ms(),
            line,
            text: "stance tripod".into(),
        });
        self.stance(line, LegAction::Tripod).await;
    }

    /// A stance change, waited for (bounded).
    async fn stance(&mut self, line: usize, a: LegAction) {
        self.driving = None;
        lock(&self.telemetry).stance_requested(a);
        // Subscribe fresh so an old completion is not taken for this one.
        self.events = self.events.resubscribe();
        if let Some(c) = self.one(&Intent::Stance(a))
            && self.request(line, c).await
            && a != LegAction::Stop
        {
            self.await_stance().await;
        }
    }

    /// A line that is an [`Intent`]: lowered by the droid's family and each command requested
    /// in order. `false` when the model has no such thing (nothing is sent).
    async fn lowered(&mut self, line: usize, a: &Action) -> bool {
        let Some(Ok(cmds)) = Intent::of_action(a).map(|i| self.family.lower(self.model, &i)) else {
            return false;
        };
        for c in cmds {
            if !self.request(line, c).await {
                break;
            }
        }
        true
    }

    async fn step(&mut self, s: &Step) {
        (self.emit)(MissionEvent::Step {
            t_ms: self.t_ms(),
            line: s.line,
            text: s.text.clone(),
        });
        match &s.action {
            Action::Wake => {
                // A v1 droid has no Wake command (it wakes at the GATT level): any activity,
                // a ping, keeps it awake.
                let wake = self.family.wake().unwrap_or_else(|| self.family.ping());
                if self.request(s.line, wake).await {
                    lock(&self.telemetry).woke();
                    // After a sleep the droid forgot its streaming and collision settings.
                    if std::mem::take(&mut self.slept) {
                        self.session.redo_setup();
                    }
                }
            }
            Action::Sleep => {
                self.driving = None;
                self.slept = true;
                if let Some(c) = self.family.sleep() {
                    self.request(s.line, c).await;
                }
            }
            Action::Stance(a) => self.stance(s.line, *a).await,
            Action::Drive {
                speed,
                heading,
                duration,
            } => {
                if *speed > 0 {
                    self.ensure_tripod(s.line).await;
                }
                self.last_heading = *heading;
                self.session
                    .set(Slot::Drive, self.drive_cmd(*speed, *heading));
                self.driving = (*speed > 0).then_some((*speed, *heading));
                if let Some(d) = duration {
                    self.hold(*d).await;
                    self.driving = None;
                    self.session.set(Slot::Drive, self.drive_cmd(0, *heading));
                }
            }
            Action::Stop => {
                self.driving = None;
                if self.tracking.take().is_some()
                    && let Some(c) = self.one(&TRACKS_STOPPED)
                {
                    self.session.set(Slot::Drive, c);
                }
                self.session
                    .set(Slot::Drive, self.drive_cmd(0, self.last_heading));
            }
            Action::Head(a) => {
                if let Some(c) = self.one(&Intent::Head(*a)) {
                    self.session.set(Slot::Head, c);
                }
            }
            a @ (Action::Animation(_) | Action::Sound(_)) => {
                self.lowered(s.line, a).await;
            }
            a @ (Action::LedRgb(..) | Action::LedBrightness(..)) => {
                if !self.lowered(s.line, a).await {
                    self.warn(
                        Some(s.line),
                        format!("{} has no such LED", self.model.display_name()),
                    );
                }
            }
            Action::Wait(d) => self.hold(*d).await,
            a @ (Action::Matrix(_) | Action::CalibrateCompass) => {
                self.lowered(s.line, a).await;
            }
            Action::Tank {
                left,
                right,
                duration,
            } => {
                self.driving = None;
                let tracks = Intent::RawMotors {
                    left: *left,
                    right: *right,
                };
                if let Some(c) = self.one(&tracks) {
                    self.session.set(Slot::Drive, c);
                }
                self.tracking = (*left != 0 || *right != 0).then_some((*left, *right));
                if let Some(d) = duration {
                    self.hold(*d).await;
                    self.tracking = None;
                    if let Some(c) = self.one(&TRACKS_STOPPED) {
                        self.session.set(Slot::Drive, c);
                    }
                }
            }
            Action::Stream { rate_hz, sensors } => {
                let request = crate::tuning::StreamRequest {
                    rate_hz: *rate_hz,
                    sensors: sensors
                        .unwrap_or_else(|| crate::family::stream::all_groups(self.model)),
                };
                if let Some(plan) = crate::family::stream::plan_for(self.model, request) {
                    if let Some(note) = &plan.note {
                        // Capped, not failed: said, and the mission goes on.
                        (self.emit)(MissionEvent::Warning {
                            t_ms: self.t_ms(),
                            line: Some(s.line),
                            message: format!("streaming: {note}"),
                        });
                    }
                    self.setup = self.setup.with_plan(&plan);
                    let cmds = crate::family::stream::reconfigure(
                        self.model,
                        &plan,
                        &self.setup.collision,
                    );
                    self.reconfigure(s.line, cmds).await;
                }
            }
            Action::Collision(c) => {
                self.setup.collision = *c;
                let cmds = self.family.collision_detection(c);
                self.reconfigure(s.line, cmds).await;
            }
        }
    }

    /// Send streaming or collision commands in order, and make the changed setup the one
    /// every reconnect runs.
    async fn reconfigure(&mut self, line: usize, cmds: Vec<Command>) {
        for c in cmds {
            if !self.request(line, c).await {
                break;
            }
        }
        self.session
            .set_setup(crate::family::setup::connect_setup(self.model, &self.setup));
    }
}

/// Wait until the session is connected, or fail.
pub async fn await_connected(session: &SessionHandle, limit: Duration) -> Result<(), MissionError> {
    let mut state = session.watch_state();
    let wait = async {
        loop {
            match state.borrow_and_update().clone() {
                LinkState::Connected => return Ok(()),
                LinkState::Closed { reason } => {
                    return Err(MissionError(
                        reason.unwrap_or_else(|| "the session closed".into()),
                    ));
                }
                _ => {}
            }
            if state.changed().await.is_err() {
                return Err(MissionError("the session ended".into()));
            }
        }
    };
    timeout(limit, wait).await.unwrap_or_else(|_| {
        Err(MissionError(format!(
            "no connection within {} s",
            limit.as_secs()
        )))
    })
}

/// The sample of `t` at `t_ms` since the mission started (replay makes them too).
pub fn sample_of(t: &Telemetry, t_ms: u64) -> Sample {
    // No negative zeros in the text or JSON the sample becomes.
    let z = |v: Option<f32>| v.map(crate::units::signless32);
    let z3 = |v: Option<[f32; 3]>| v.map(|a| a.map(crate::units::signless32));
    Sample {
        t_ms,
        x_cm: z(t.x_cm),
        y_cm: z(t.y_cm),
        speed: z(t.speed_cm_s()),
        heading: t.heading().map(Heading::degrees),
        head_deg: z(t.head_deg),
        stance: t.stance.settled().map(str::to_string),
        stance_to: t.stance.changing_to().map(str::to_string),
        battery_v: t.battery_v,
        collisions: t.collisions,
        motor_left_rad_s: t.robi.as_ref().and_then(|r| r.motors).map(|m| m.left_rad_s),
        motor_right_rad_s: t
            .robi
            .as_ref()
            .and_then(|r| r.motors)
            .map(|m| m.right_rad_s),
        frames: t.robi.as_ref().map(|r| r.frames),
        lost_frames: t.robi.as_ref().map(|r| r.lost),
        pitch_deg: z(t.pitch),
        roll_deg: z(t.roll),
        // Robi's yaw is dead reckoning, already in the heading.
        yaw_deg: z(t.yaw.filter(|_| t.robi.is_none())),
        accel_g: z3(t.accel),
        gyro_deg_s: z3(t.gyro),
        velocity_cm_s: t
            .velocity_cm_s
            .filter(|_| t.robi.is_none())
            .map(|a| a.map(crate::units::signless32)),
        poti: t.robi.as_ref().and_then(|r| r.poti),
    }
}

/// Run `steps`; `emit` receives steps, samples and warnings as they happen.
pub async fn run(
    session: &SessionHandle,
    model: Model,
    steps: &[Step],
    opts: MissionOptions,
    emit: Emit,
) -> Result<Summary, MissionError> {
    let events = session.subscribe();
    await_connected(session, opts.connect_timeout).await?;
    let mut m = DroidMission::begin(session, model, opts, emit, Instant::now(), events);
    for s in steps {
        if session.is_closed() {
            break;
        }
        m.step(s).await;
    }
    m.finish().await
}

/// A mission on one droid taken step by step: what [`run`] does, and what a fleet mission
/// does on each of its droids (`crate::fleet::mission`), all sampled from one start.
pub struct DroidMission {
    runner: Runner,
    sampler: tokio::task::JoinHandle<()>,
    poller: tokio::task::JoinHandle<()>,
    collector: tokio::task::JoinHandle<()>,
}

impl DroidMission {
    /// Wait for `session` to connect (bounded by `opts.connect_timeout`), then start its
    /// telemetry, battery poll and samples from `start` (when it is already past, the first
    /// sample comes at once).
    pub async fn start(
        session: &SessionHandle,
        model: Model,
        opts: MissionOptions,
        emit: Emit,
        start: Instant,
    ) -> Result<DroidMission, MissionError> {
        let events = session.subscribe();
        await_connected(session, opts.connect_timeout).await?;
        Ok(DroidMission::begin(
            session, model, opts, emit, start, events,
        ))
    }

    fn begin(
        session: &SessionHandle,
        model: Model,
        opts: MissionOptions,
        emit: Emit,
        start: Instant,
        events: broadcast::Receiver<SessionEvent>,
    ) -> DroidMission {
        let telemetry = Arc::new(Mutex::new(Telemetry::default()));

        // Notifications → telemetry; then what the droid announced at connect, before we
        // subscribed (Robi's handshake; folding it twice is harmless).
        let collector = {
            let mut rx = session.subscribe();
            let telemetry = telemetry.clone();
            tokio::spawn(async move {
                loop {
                    match rx.recv().await {
                        Ok(SessionEvent::Notification(n)) => {
                            lock(&telemetry).apply(&n, start.elapsed())
                        }
                        Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                        Err(broadcast::error::RecvError::Closed) => break,
                    }
                }
            })
        };
        for n in session.greeting() {
            lock(&telemetry).apply(&n, Duration::ZERO);
        }
        let family = crate::family::for_model(model);
        // Battery and stance read-back.
        let poller = {
            let session = session.clone();
            let telemetry = telemetry.clone();
            let every = opts.battery_poll;
            tokio::spawn(async move {
                if model.has_legs()
                    && let Some(c) = family.get_stance()
                    && let Ok(p) = session.request(c).await
                    && let Some(s) = p.data().first().and_then(|b| LegState::from_byte(*b))
                {
                    let mut t = lock(&telemetry);
                    if t.stance == Stance::Unknown {
                        t.stance = Stance::from_state(s);
                    }
                }
                let Some(battery) = family.battery_request_for(model) else {
                    return;
                };
                loop {
                    if let Ok(p) = session.request(battery.clone()).await
                        && let Some(v) = family.battery_volts_for(model, p.data())
                    {
                        lock(&telemetry).battery_v = Some(v);
                    }
                    sleep(every).await;
                }
            })
        };
        // Samples on a fixed interval.
        let sampler = {
            let telemetry = telemetry.clone();
            let emit = emit.clone();
            let every = opts.interval.max(Duration::from_millis(1));
            tokio::spawn(async move {
                let mut tick = tokio::time::interval_at(start, every);
                tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
                loop {
                    tick.tick().await;
                    let s = sample_of(&lock(&telemetry), start.elapsed().as_millis() as u64);
                    emit(MissionEvent::Sample(s));
                }
            })
        };

        let runner = Runner {
            session: session.clone(),
            model,
            family,
            opts: opts.clone(),
            telemetry: telemetry.clone(),
            start,
            emit: emit.clone(),
            driving: None,
            tracking: None,
            setup: opts.setup,
            last_heading: Heading::default(),
            events,
            failed: 0,
            slept: false,
        };
        DroidMission {
            runner,
            sampler,
            poller,
            collector,
        }
    }

    /// Run one step.
    pub async fn step(&mut self, s: &Step) {
        self.runner.step(s).await;
    }

    /// The droid's telemetry as the mission folds it (a Sphero Edu program reads its sensors
    /// from it, `crate::edu`).
    pub fn telemetry(&self) -> Arc<Mutex<Telemetry>> {
        self.runner.telemetry.clone()
    }

    /// Whether the session has ended (a fatal link error): the rest is skipped.
    pub fn closed(&self) -> bool {
        self.runner.session.is_closed()
    }

    /// Stop the droid, give the stop time to go out, and sum up.
    pub async fn finish(mut self) -> Result<Summary, MissionError> {
        let start = self.runner.start;
        let emit = self.runner.emit.clone();
        let telemetry = self.runner.telemetry.clone();
        let (sampler, poller, collector) = (&self.sampler, &self.poller, &self.collector);
        // Stop, and give the stop time to go out before the summary.
        if self.runner.driving.take().is_some() {
            self.runner.session.set(
                Slot::Drive,
                self.runner.drive_cmd(0, self.runner.last_heading),
            );
        }
        self.runner.hold(Duration::from_millis(300)).await;
        sampler.abort();
        poller.abort();
        collector.abort();

        let t_ms = start.elapsed().as_millis() as u64;
        let t = lock(&telemetry).clone();
        emit(MissionEvent::Sample(sample_of(&t, t_ms)));
        let st = self.runner.session.stats();
        let closed = self.runner.session.is_closed();
        let summary = Summary {
            done: true,
            t_ms,
            sent: st.sent,
            received: st.received,
            errors: st.errors,
            timeouts: st.timeouts,
            collisions: t.collisions,
            failed_steps: self.runner.failed,
            x_cm: t.x_cm,
            y_cm: t.y_cm,
        };
        if closed && let LinkState::Closed { reason: Some(r) } = self.runner.session.state() {
            return Err(MissionError(r));
        }
        Ok(summary)
    }
}
