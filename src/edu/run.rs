//! A Sphero Edu program on one droid: the engine's calls played on droidctl's clock.
//!
//! The mission machinery does the rest as for `run SCRIPT` ([`DroidMission`]): the wait for
//! the link, telemetry, samples (`--json`, `--csv`), the battery poll and the summary. Calls
//! become the droid's commands here, timed waits (`roll`'s duration, `spin`'s steps, `fade`,
//! `delay`) run on tokio's clock, and the droid's notifications become the program's events.

use super::api::{Act, Wait};
use super::engine::{Event, Failure, Op, Readings, Status};
use super::host::{CheckError, Engine, EngineOptions, TurnError};
use super::schedule::{Due, Schedule};
use crate::family::intent::Intent;
use crate::family::{Command, Family};
use crate::mission::{DroidMission, Emit, MissionError, MissionEvent, MissionOptions, Summary};
use crate::model::Model;
use crate::protocol::notify::{Notification, RobotEvent};
use crate::protocol::wire::LegAction;
use crate::script::{Action, Step};
use crate::session::{Latest, Mark, RequestError, SessionEvent, SessionHandle, Slot};
use crate::sync::lock;
use crate::telemetry::{Stance, Telemetry};
use crate::units::Heading;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::broadcast;
use tokio::time::{Instant, sleep_until};

mod lights;
mod paced;
mod sensed;
use sensed::Sensed;

/// A program checked and ready to run.
#[derive(Debug, Clone)]
pub struct Program {
    pub source: String,
    /// The name errors give (`square.js:3: …`).
    pub path: String,
    /// The engine it was checked with, and runs with.
    pub engine: EngineOptions,
}

impl Program {
    /// Read and check `source` (in the engine's child, [`super::host::check`]): a syntax
    /// error names its line and column.
    pub fn new(source: String, path: String) -> Result<Program, CheckError> {
        Program::new_with(source, path, &EngineOptions::default())
    }

    /// [`Program::new`] with the engine started as `engine` says.
    pub fn new_with(
        source: String,
        path: String,
        engine: &EngineOptions,
    ) -> Result<Program, CheckError> {
        super::host::check(&source, &path, engine)?;
        Ok(Program {
            source,
            path,
            engine: engine.clone(),
        })
    }
}

/// How a program runs.
#[derive(Debug, Clone)]
pub struct ProgramOptions {
    pub mission: MissionOptions,
    /// End the program after this long on droidctl's clock (simulated under `--sim`).
    pub timeout: Option<Duration>,
    /// The longest the program may compute without waiting (wall-clock time), apart from
    /// `timeout`: past it the engine's child is killed.
    pub no_yield: Duration,
    /// `timeout` is droidctl's own limit for a program under `--sim`
    /// ([`SIM_TIME_LIMIT`]), not the user's `--timeout`: its end says so, and how to change it.
    pub default_limit: bool,
    /// Where the program's status is published for a screen ([`super::progress`]).
    pub progress: Option<super::progress::Progress>,
}

/// How long a program may run in simulated time when no `--timeout` is given: a program
/// that never ends (a bounce on every collision without `exitProgram`, a `while (true)` loop
/// that waits) ends after 5 minutes of program time instead of running at full speed for
/// ever.
pub const SIM_TIME_LIMIT: Duration = Duration::from_secs(300);

/// The start of the error of a program ended by its time limit (`--timeout`, or
/// [`SIM_TIME_LIMIT`]): `run --each` tells it from other errors by it.
pub const TIME_LIMIT: &str = "time limit: ";

impl Default for ProgramOptions {
    fn default() -> Self {
        ProgramOptions {
            mission: MissionOptions::default(),
            timeout: None,
            no_yield: Duration::from_secs(5),
            default_limit: false,
            progress: None,
        }
    }
}

/// A wait on the droid rather than the clock.
enum Until {
    Distance {
        from: f32,
        cm: f32,
        then: Vec<Act>,
        fire: u64,
    },
    Stance {
        by: Instant,
        fire: u64,
    },
    Compass {
        by: Instant,
        fire: u64,
    },
}

struct Player {
    session: SessionHandle,
    model: Model,
    family: &'static dyn Family,
    emit: Emit,
    start: Instant,
    telemetry: Arc<Mutex<Telemetry>>,
    /// Timed calls pending (`roll`'s duration, `spin`, `fade`, `strobe`, `delay`).
    timed: Schedule,
    until: Vec<Until>,
    fired: Vec<u64>,
    events: Vec<Event>,
    /// The drive being held (re-sent on the heartbeat).
    drive: Option<Command>,
    last_heading: u16,
    raw: bool,
    /// Distance covered, cm (spherov2 sums the locator's steps).
    distance: f32,
    last_location: Option<[f32; 2]>,
    sensed: Sensed,
    stance_done: bool,
    /// The channel of the last infrared message heard (`getLastIRMessage`).
    last_ir: Option<u8>,
    /// The infrared behaviours running, stopped when the program ends.
    ir_running: super::infrared::Running,
    /// The tickets of the commands the program sent that may not have left yet: a timed call's
    /// clock starts when they have ([`Player::sent`]).
    marks: Vec<Mark>,
    /// Lights held back while a stop is due within a pacing slot ([`Player::light`]).
    held: lights::Held,
    /// Paced steps (`spin`'s) whose drive waits for its answer: (ticket, call, soonest next
    /// step), one per pending spin at most ([`paced`]).
    awaiting: Vec<(Mark, u64, Instant)>,
    /// The ticket of the last drive set ([`Player::act`]), for [`Player::paced`].
    drive_mark: Option<Mark>,
    /// The droid was set up and its first sample came in: a reading it never sent reads 0.
    ready: bool,
    mission: DroidMission,
    report: super::progress::Reporter,
}

/// The longest a timed call's clock waits for its command to leave (a link that stopped
/// taking writes must not hold the program for good).
const LEAVE_LIMIT: Duration = Duration::from_secs(3);
/// Why a program ended when the operator's emergency stop ended it.
const EMERGENCY_STOP: &str = "emergency stop";

/// Whether `e`, from [`run`], says the operator's emergency stop ended the program (not its
/// own error): the app does not count that as the program failing.
pub fn ended_by_emergency_stop(e: &MissionError) -> bool {
    e.0.contains(&format!(": {EMERGENCY_STOP}; "))
}

/// Tickets kept at most (the queue holds 64 requests and two slots).
const MAX_MARKS: usize = 128;
/// The longest the end of a run waits for what the program asked for to be written.
const FLUSH_LIMIT: Duration = Duration::from_secs(10);
/// The longest a call waits for room in a full request queue.
const ROOM_LIMIT: Duration = Duration::from_secs(5);

/// Run `program` on the droid behind `session`.
pub async fn run(
    session: &SessionHandle,
    model: Model,
    program: &Program,
    opts: ProgramOptions,
    emit: Emit,
    start: Instant,
) -> Result<Summary, MissionError> {
    run_to_end(session, model, program, opts, emit, start)
        .await
        .result
}

/// How a program's run ended: its result, and the run's summary even when the program
/// failed or hit its time limit (`run --json` prints it then too).
pub struct Ended {
    pub result: Result<Summary, MissionError>,
    pub summary: Option<Summary>,
}

/// [`run`], with the summary of a run that failed.
pub async fn run_to_end(
    session: &SessionHandle,
    model: Model,
    program: &Program,
    opts: ProgramOptions,
    emit: Emit,
    start: Instant,
) -> Ended {
    let ended = |result: Result<Summary, MissionError>| Ended {
        summary: result.as_ref().ok().cloned(),
        result,
    };
    let events = session.subscribe();
    let mission = match DroidMission::start(
        session,
        model,
        opts.mission.clone(),
        emit.clone(),
        start,
    )
    .await
    {
        Ok(m) => m,
        Err(e) => return ended(Err(e)),
    };
    let mut p = Player {
        session: session.clone(),
        model,
        family: crate::family::for_model(model),
        emit,
        start,
        telemetry: mission.telemetry(),
        timed: Schedule::default(),
        until: Vec::new(),
        fired: Vec::new(),
        events: Vec::new(),
        drive: None,
        last_heading: 0,
        raw: false,
        distance: 0.0,
        last_location: None,
        sensed: Sensed::default(),
        stance_done: false,
        last_ir: None,
        ir_running: Default::default(),
        marks: Vec::new(),
        held: Default::default(),
        awaiting: Vec::new(),
        drive_mark: None,
        ready: false,
        mission,
        report: super::progress::Reporter::new(opts.progress.clone()),
    };
    let r = p.play(program, &opts, events).await;
    p.report.ended(&r, EMERGENCY_STOP);
    p.stop_motion().await;
    p.release_lights(true).await;
    p.flush().await;
    let summary = p.mission.finish().await;
    match r {
        Ok(()) => ended(summary),
        Err(f) => {
            let at = f.line.map(|l| format!(":{l}")).unwrap_or_default();
            Ended {
                result: Err(MissionError(format!(
                    "{}{at}: {}; the program was ended and the droid stopped",
                    program.path, f.message
                ))),
                summary: summary.ok(),
            }
        }
    }
}

impl Player {
    fn t_ms(&self) -> u64 {
        self.start.elapsed().as_millis() as u64
    }

    async fn play(
        &mut self,
        program: &Program,
        opts: &ProgramOptions,
        mut rx: broadcast::Receiver<SessionEvent>,
    ) -> Result<(), Failure> {
        let mut engine = Engine::start(
            program.source.clone(),
            program.path.clone(),
            self.model,
            &program.engine,
        )
        .map_err(|message| Failure {
            line: None,
            message,
        })?;
        let deadline = opts.timeout.map(|t| Instant::now() + t);
        let far = Instant::now() + Duration::from_secs(86_400 * 365);
        let secs = opts.timeout.unwrap_or_default().as_secs_f64();
        let timed_out = || Failure {
            line: None,
            message: if opts.default_limit {
                format!(
                    "{TIME_LIMIT}the program ran {secs} s of simulated time, droidctl's limit \
                     under --sim (end it with exitProgram(), or give --timeout SECONDS for \
                     another limit)"
                )
            } else {
                format!("{TIME_LIMIT}--timeout: the program ran {secs} s")
            },
        };
        let mut heartbeat = tokio::time::interval(opts.mission.heartbeat);
        heartbeat.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        let mut estops = self.session.watch_estops();
        estops.mark_unchanged();
        let mut listening: Vec<&'static str> = Vec::new();
        // The program starts once the droid is set up and its first sample is in: every
        // reading is a number from its first line (issue 38).
        tokio::select! {
            missing = super::ready::wait(&self.session, &self.telemetry, self.model, &opts.mission.setup) => {
                self.ready = true;
                self.report.waiting(&[]);
                if !missing.is_empty() {
                    self.warn(0, format!(
                        "{} sent no {} since it connected: the program reads 0 for it",
                        self.model.display_name(),
                        missing.join(", ")
                    ));
                }
            }
            _ = estops.changed() => {
                return Err(Failure { line: None, message: EMERGENCY_STOP.into() });
            }
            _ = sleep_until(deadline.unwrap_or(far)) => return Err(timed_out()),
        }
        let mut first = true;
        loop {
            if first || !self.fired.is_empty() || !self.events.is_empty() {
                first = false;
                let fired = std::mem::take(&mut self.fired);
                self.report.resolved(&fired);
                let events = std::mem::take(&mut self.events);
                let readings = self.readings();
                // The emergency stop and the timeout end a program even while it computes
                // (under `--sim` a turn takes no time on the clock the timeout is on).
                let out = tokio::select! {
                    out = engine.turn(fired, events, readings, opts.no_yield) => match out {
                        Ok(out) => out,
                        Err(e) => {
                            // The engine failed or died: the droid stops first, ahead of
                            // pacing; what happened is said after.
                            self.session.stop_now(self.family);
                            return Err(match e {
                                TurnError::Failed(f) => f,
                                TurnError::Died => engine.failure().await,
                            });
                        }
                    },
                    _ = estops.changed() => {
                        return Err(Failure { line: None, message: EMERGENCY_STOP.into() });
                    }
                    _ = sleep_until(deadline.unwrap_or(far)) => return Err(timed_out()),
                };
                listening = out.listening;
                for op in out.ops {
                    self.apply(op).await;
                }
                match out.status {
                    Status::Finished => return Ok(()),
                    Status::Failed(f) => return Err(f),
                    Status::Running => self.report.waiting(&listening),
                }
                if !self.fired.is_empty() {
                    continue;
                }
            }
            let next = self.timed.next().unwrap_or(far);
            let by = deadline.unwrap_or(far);
            let paced = self.paced_waits();
            // Held lights go a pacing slot after they were held at the latest.
            let lights_by = self.held.due_by(self.session.pacing());
            tokio::select! {
                _ = sleep_until(next) => self.due().await,
                _ = sleep_until(lights_by.unwrap_or(far)), if lights_by.is_some() => self.due().await,
                in_time = async {
                    match &paced {
                        Some((session, marks)) => session.answered(marks, paced::ANSWER_LIMIT).await,
                        None => std::future::pending().await,
                    }
                }, if paced.is_some() => self.paced_answered(in_time),
                _ = sleep_until(by) => return Err(timed_out()),
                // The engine's child died while the program waited (killed, out of memory):
                // the droid stops now, not at the next turn.
                _ = engine.gone() => {
                    self.session.stop_now(self.family);
                    return Err(engine.failure().await);
                }
                _ = estops.changed() => {
                    return Err(Failure {
                        line: None,
                        message: EMERGENCY_STOP.into(),
                    });
                }
                _ = heartbeat.tick() => {
                    // A spin's step waiting for its answer keeps the drive fresh itself; a
                    // re-send would replace it unwritten and make its next step early.
                    if let Some(c) = self.drive.as_ref().filter(|_| self.awaiting.is_empty()) {
                        self.session.set(Slot::Drive, c.clone());
                    }
                    self.check_until().await;
                }
                ev = rx.recv() => match ev {
                    Ok(SessionEvent::Notification(n)) => self.notified(&n, &listening).await,
                    Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                    Err(broadcast::error::RecvError::Closed) => {
                        return Err(Failure { line: None, message: "the session ended".into() });
                    }
                },
            }
            if self.session.is_closed() {
                return Err(Failure {
                    line: None,
                    message: "the link to the droid closed".into(),
                });
            }
        }
    }

    /// What the program reads this turn.
    fn readings(&mut self) -> Readings {
        let t = lock(&self.telemetry).clone();
        self.track(&t);
        let v_acc = t
            .accel
            .map(|a| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt());
        // Once ready, a reading the droid never sent is 0, never `null` (see `play`).
        let zero = |ready: bool| ready.then_some([0.0; 3]);
        let zero2 = |ready: bool| ready.then_some([0.0; 2]);
        Readings {
            location: t
                .x_cm
                .zip(t.y_cm)
                .map(|(x, y)| [x, y])
                .or(zero2(self.ready)),
            velocity: t.velocity_cm_s.or(zero2(self.ready)),
            orientation: match (t.pitch, t.roll, t.yaw) {
                (Some(p), Some(r), Some(y)) => Some([p, r, y]),
                _ => zero(self.ready),
            },
            acceleration: t.accel.or(zero(self.ready)),
            vertical_acceleration: v_acc.or(self.ready.then_some(0.0)),
            gyroscope: t.gyro.or(zero(self.ready)),
            distance: self.distance,
            elapsed_s: self.start.elapsed().as_secs_f64(),
            luminosity: t.robot.ambient_lux,
            color: t.robot.color.map(|c| c.0),
            compass: t.robot.compass_north,
            battery_v: t.battery_v,
            ir_message: self.last_ir,
        }
    }

    /// Add the locator's latest step to the distance covered.
    fn track(&mut self, t: &Telemetry) {
        if let (Some(x), Some(y)) = (t.x_cm, t.y_cm) {
            if let Some([lx, ly]) = self.last_location {
                self.distance += ((x - lx).powi(2) + (y - ly).powi(2)).sqrt();
            }
            self.last_location = Some([x, y]);
        }
    }

    /// One call of the program: said, done now, and its wait scheduled.
    async fn apply(&mut self, op: Op) {
        (self.emit)(MissionEvent::Step {
            t_ms: self.t_ms(),
            line: op.line as usize,
            text: op.text.clone(),
        });
        if let (Some(id), Some(_)) = (op.promise, &op.effect.wait) {
            self.report.called(id, op.line, &op.text);
        }
        // A timed move leaves after the calls before it, as spherov2's (each call sends before
        // it returns): the drive's slot jumps the queue, and `registerMatrixAnimation(…);
        // await roll(0, 70, 1)` drove 1.7 s, its clock waiting for the frames (edu_twins).
        let moves = op
            .effect
            .now
            .iter()
            .any(|a| matches!(a, Act::Drive { .. } | Act::Raw(..)));
        if moves && matches!(op.effect.wait, Some(Wait::Timeline(_))) {
            self.sent().await;
        }
        for a in &op.effect.now {
            self.act(op.line, a).await;
        }
        // A timed call's clock starts when its commands, and those of the calls before it,
        // have left, as spherov2's does (each of its calls sends its command before it
        // returns): queued behind the pacing, `rawMotor(l, r, 2)` drove for less than 2 s, and
        // `playMatrixAnimation(0); await delay(1)` showed animation 0 for a pacing tick.
        let now = match &op.effect.wait {
            Some(Wait::Timeline(_)) => self.sent().await,
            _ => Instant::now(),
        };
        self.release_lights(false).await;
        match (op.effect.wait, op.promise) {
            (None, Some(id)) => self.fired.push(id),
            (None, None) => {}
            (Some(Wait::Timeline(t)), id) => self.timed.add(now, t, id),
            (Some(Wait::Distance { cm, then }), Some(fire)) => {
                self.readings();
                self.until.push(Until::Distance {
                    from: self.distance,
                    cm,
                    then,
                    fire,
                });
            }
            (Some(Wait::Stance), Some(fire)) => {
                self.stance_done = false;
                self.until.push(Until::Stance {
                    by: now + Duration::from_secs(5),
                    fire,
                });
            }
            (Some(Wait::Compass), Some(fire)) => self.until.push(Until::Compass {
                by: now + Duration::from_secs(10),
                fire,
            }),
            (Some(_), None) => {}
        }
    }

    /// The timed actions that are due, in order.
    async fn due(&mut self) {
        let mut fired = false;
        for due in self.timed.due(Instant::now()) {
            match due {
                Due::Acts(acts) => {
                    for a in &acts {
                        self.act(0, a).await;
                    }
                }
                Due::Paced { call, acts } => self.paced(call, &acts).await,
                // The call returns once its last step has left, as spherov2's: else `spin`'s
                // last heading shares the drive slot with the next call's and is replaced
                // before it goes (`await spin(360, 2); stopRoll()`, tests/it/edu_twins.rs).
                Due::Fire(id) => {
                    self.sent().await;
                    self.fired.push(id);
                    fired = true;
                }
            }
        }
        // A call ended: the program's next call sends the held lights, after its own drive.
        if !fired {
            self.release_lights(false).await;
        }
    }

    /// Waits on the droid that are over.
    async fn check_until(&mut self) {
        self.readings();
        let now = Instant::now();
        let (distance, stance_done) = (self.distance, self.stance_done);
        let compass = lock(&self.telemetry).robot.compass_north.is_some();
        let mut over = Vec::new();
        self.until.retain(|u| {
            let done = match u {
                Until::Distance { from, cm, .. } => distance - from >= *cm,
                Until::Stance { by, .. } => stance_done || now >= *by,
                Until::Compass { by, .. } => compass || now >= *by,
            };
            if done {
                over.push(match u {
                    Until::Distance { then, fire, .. } => (then.clone(), *fire),
                    Until::Stance { fire, .. } | Until::Compass { fire, .. } => (Vec::new(), *fire),
                });
            }
            !done
        });
        for (acts, fire) in over {
            for a in &acts {
                self.act(0, a).await;
            }
            self.fired.push(fire);
        }
    }

    /// A notification: telemetry is the mission's; events for the program here.
    async fn notified(&mut self, n: &Notification, listening: &[&'static str]) {
        let mut seen = Vec::new();
        match n {
            Notification::Collision(_) => seen.push(Event::Collision),
            Notification::LegActionComplete => self.stance_done = true,
            // spherov2: charging or charged is "charging", anything else "not charging"; v1's
            // power state 1 is charging. Fired when that changes (a low battery's
            // notification is not "taken off the charger").
            Notification::ChargerStateChanged(s) | Notification::BatteryStateChanged(s) => {
                seen.extend(self.charging(matches!(s, 1 | 2)));
            }
            Notification::PowerState(s) => seen.extend(self.charging(*s == 1)),
            Notification::Robot(RobotEvent::Color { .. }) => {
                let colour = lock(&self.telemetry).robot.color;
                seen.extend(self.colour(colour));
            }
            Notification::Robot(RobotEvent::IrMessage(code)) => {
                self.last_ir = Some(*code);
                seen.push(Event::IrMessage(*code));
            }
            Notification::Sensors(_) => {
                let (accel, gyro, colour) = {
                    let t = lock(&self.telemetry);
                    (t.accel, t.gyro, t.robot.color)
                };
                if let Some(a) = accel {
                    seen.extend(self.fall(a));
                }
                if let Some(g) = gyro {
                    let max = g.iter().any(|v| v.abs() >= 2000.0);
                    if max && !self.sensed.gyro_max {
                        seen.push(Event::GyroMax);
                    }
                    self.sensed.gyro_max = max;
                }
                seen.extend(self.colour(colour));
                self.check_until().await;
            }
            _ => {}
        }
        self.events
            .extend(seen.into_iter().filter(|e| listening.contains(&e.name())));
        if matches!(n, Notification::LegActionComplete) {
            self.check_until().await;
        }
    }

    /// When the commands the current call sent have left (now, if they already have).
    async fn sent(&mut self) -> Instant {
        let by = Instant::now() + LEAVE_LIMIT;
        for mark in std::mem::take(&mut self.marks) {
            let left = by.saturating_duration_since(Instant::now());
            self.session.left(mark, left).await;
        }
        Instant::now()
    }

    /// Keep `mark` for [`Self::sent`]; those already gone are forgotten now and then, so the
    /// list stays as short as the queue.
    fn keep(&mut self, mark: Mark) {
        if self.marks.len() >= MAX_MARKS {
            let session = self.session.clone();
            self.marks.retain(|m| session.holds(*m));
            if self.marks.len() >= MAX_MARKS {
                self.marks.remove(0);
            }
        }
        self.marks.push(mark);
    }

    /// Everything the program asked for written before the run ends (issue 38: lights set
    /// just before the end were dropped), bounded.
    async fn flush(&mut self) {
        if !self.session.is_closed() && !self.session.drained(FLUSH_LIMIT).await {
            let left = self.session.queued();
            self.warn(
                0,
                format!(
                    "{left} command(s) were still waiting to be sent {} s after the program \
                     ended; the link is too slow or gone",
                    FLUSH_LIMIT.as_secs()
                ),
            );
        }
    }

    /// A command for the droid, its ticket kept for [`Self::sent`]; `latest` (a light) replaces
    /// an unwritten command for the same thing. A full queue is waited on, as spherov2 waits
    /// for each command, rather than dropping what the program asked for.
    async fn send(&mut self, line: u32, c: Option<Command>, what: &str, latest: Option<Latest>) {
        match c {
            Some(c) => {
                let mut r = self.session.send_marked(c.clone(), latest);
                if matches!(r, Err(RequestError::QueueFull)) && self.session.room(ROOM_LIMIT).await
                {
                    r = self.session.send_marked(c, latest);
                }
                match r {
                    Ok(mark) => self.keep(mark),
                    Err(e) => self.warn(line, format!("{what}: {e}")),
                }
            }
            None => self.warn(
                line,
                format!(
                    "{what}: droidctl cannot do this on {}",
                    self.model.display_name()
                ),
            ),
        }
    }

    fn warn(&self, line: u32, message: String) {
        (self.emit)(MissionEvent::Warning {
            t_ms: self.t_ms(),
            line: (line > 0).then_some(line as usize),
            message,
        });
    }

    /// `intent` lowered by the droid's family and sent (`what` names the call in warnings); a
    /// model without it is warned about.
    async fn intend(&mut self, line: u32, intent: Intent, what: &str) {
        self.intend_as(line, intent, what, None).await
    }

    /// [`Self::intend`] for a light: its commands replace the unwritten ones of the same light
    /// (`light` names it), so a light loop never floods the queue and ends on its last state.
    async fn intend_as(&mut self, line: u32, intent: Intent, what: &str, light: Option<u64>) {
        match self.family.lower(self.model, &intent) {
            Ok(cmds) => {
                for (i, c) in cmds.into_iter().enumerate() {
                    let latest = light.map(|l| Latest(l << 8 | i as u64));
                    self.send(line, Some(c), what, latest).await;
                }
            }
            Err(_) => self.send(line, None, what, None).await,
        }
    }

    /// As [`Self::intend`], but a model without it does nothing (stabilisation on Robi 42,
    /// resetting the aim of a droid with no aim mode).
    async fn intend_quietly(&mut self, line: u32, intent: Intent, what: &str) {
        if let Ok(cmds) = self.family.lower(self.model, &intent) {
            for c in cmds {
                self.send(line, Some(c), what, None).await;
            }
        }
    }

    /// R2-D2 and R2-Q5 roll only in tripod: put them there first, as missions do.
    async fn tripod(&mut self, line: u32) {
        if !self.model.has_legs() {
            return;
        }
        let stance = lock(&self.telemetry).stance;
        if matches!(
            stance,
            Stance::Tripod | Stance::Transitioning(crate::protocol::wire::LegState::Tripod)
        ) {
            return;
        }
        let step = Step {
            line: line as usize,
            text: "stance tripod".into(),
            action: Action::Stance(LegAction::Tripod),
        };
        self.mission.step(&step).await;
    }

    async fn act(&mut self, line: u32, a: &Act) {
        match a {
            Act::Drive {
                speed,
                heading,
                reverse,
            } => {
                if *speed > 0 {
                    self.tripod(line).await;
                }
                let h = Heading::wrapped(*heading as f64);
                let c = crate::family::intent::drive(self.family, *speed, h, *reverse);
                self.last_heading = *heading;
                let mark = self.session.set_marked(Slot::Drive, c.clone());
                self.keep(mark);
                self.drive_mark = Some(mark);
                self.drive = (*speed > 0).then_some(c);
                self.report.drove_at(*speed, *heading, *reverse);
            }
            Act::Raw(l, r) => {
                self.drive = None;
                self.raw = *l != 0 || *r != 0;
                self.report.raw(*l, *r);
                let raw = Intent::RawMotors {
                    left: *l,
                    right: *r,
                };
                self.intend(line, raw, "rawMotor").await;
            }
            Act::Stabilization(on) => {
                self.intend_quietly(line, Intent::Stabilization(*on), "setStabilization")
                    .await
            }
            Act::ResetAim => {
                self.intend_quietly(line, Intent::ResetAim, "resetAim")
                    .await
            }
            Act::Main(_)
            | Act::Front(_)
            | Act::Back(_)
            | Act::BackBrightness(_)
            | Act::Holo(_)
            | Act::Logic(_)
            | Act::DomeLeds(_) => self.light(line, a).await,
            Act::Matrix(m) => self.intend(line, Intent::Matrix(m.clone()), "matrix").await,
            Act::Dome(deg) => {
                let head = Intent::Head(crate::units::HeadAngle::clamped(*deg));
                match self.family.lower(self.model, &head) {
                    Ok(cmds) => {
                        for c in cmds {
                            self.session.set(Slot::Head, c);
                        }
                    }
                    Err(_) => self.warn(line, "setDomePosition: no dome".into()),
                }
            }
            Act::Stance(s) => {
                self.drive = None;
                lock(&self.telemetry).stance_requested(*s);
                self.intend(line, Intent::Stance(*s), "setStance").await;
            }
            Act::Animation(id) => {
                self.drive = None;
                self.intend(line, Intent::Animation(*id), "playAnimation")
                    .await;
            }
            Act::Sound(s) => match super::sounds::droid_clip(self.model, s)
                .and_then(|id| self.family.lower(self.model, &Intent::Sound(id)).ok())
            {
                Some(cmds) => {
                    for c in cmds {
                        self.send(line, Some(c), "playSound", None).await;
                    }
                }
                None => self.say(line, format!("plays {}", super::sounds::described(s))),
            },
            Act::Rvr(light, rgb) => self.rvr_light(line, *light, *rgb).await,
            Act::Say(text) => self.say(line, format!("says {text:?}")),
            Act::CalibrateCompass => {
                self.intend(line, Intent::CalibrateCompass, "calibrateCompass")
                    .await
            }
            Act::Ir(ir) => self.infrared(line, ir).await,
        }
    }

    /// What a robot without a speaker would have said: a line of the output.
    fn say(&self, line: u32, text: String) {
        (self.emit)(MissionEvent::Step {
            t_ms: self.t_ms(),
            line: line as usize,
            text: format!("{} {text}", self.model.display_name()),
        });
    }

    /// Stop rolling and the motors (the run ends, or the program failed), and the infrared
    /// behaviours the program started (a follower or evader rolls by itself).
    async fn stop_motion(&mut self) {
        for stop in self.ir_running.stops() {
            self.infrared(0, &stop).await;
        }
        self.drive = None;
        let stop = crate::mission::drive_command(
            self.family,
            0,
            Heading::wrapped(self.last_heading as f64),
        );
        self.session.set(Slot::Drive, stop);
        if self.raw
            && let Some(c) = crate::family::intent::one_command(
                self.family,
                self.model,
                &Intent::RawMotors { left: 0, right: 0 },
            )
        {
            let _ = self.session.send(c);
        }
    }
}
