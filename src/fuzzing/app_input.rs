//! The app's input routing against its safety promises: a fleet of simulated droids (R2-D2,
//! BB-8, Robi 42) driven through the whole event loop on paused time by a sequence of key
//! presses, repeats, releases, focus changes and pauses, in either keyboard mode, mixed with
//! a gamepad's events (sticks moved or centred, the right trigger, buttons pressed and
//! released, the pad plugged in and lost). Whatever the sequence:
//!
//! 1. a drive with speed above 0 is written to a droid only while a drive key is held in the
//!    driving place for that droid (pressed there, not released, not expired, and no place
//!    change, droid change, mirror switch or focus loss since), or while the pad's left stick
//!    is out of its deadzone with the driving place on top and that droid driven (the stick
//!    is a deadman: centred, or the pad lost, is let go; a pad plugged in has its sticks at
//!    rest until they move), and never while the pad's stop button is held;
//! 2. a droid's heading changes between two drive writes only while a turn key is held there
//!    in the same sense, or the left stick drives it (the stick points the heading), or the
//!    aim key or button was pressed (which makes the facing heading 0);
//! 3. every emergency stop raised (a key or the pad's stop button) is written to every
//!    connected droid at that same instant.
//!
//! The oracle knows only the default key map and pad bindings and, after each event, the
//! place the app says the event left it in ([`InputTrace`]); it does not share the app's
//! held-key or stick code. Its reading of the pad is the manual's (docs/app.md, "Gamepad"):
//! the stick drives while its distance from centre is above `gamepad.deadzone`, the pad is
//! read whatever has the terminal's focus (focus loss lets go of keys, whose releases are
//! lost then, not of the stick, whose position gilrs keeps reporting), and "plugged in
//! again, nothing moves until the stick does".
//!
//! Sessions write with no pacing here, so a write happens at the instant the app decides it;
//! pacing is the session's business and is tested there.
//!
//! Input layout: the first byte's low bit chooses the keyboard mode (reported releases or
//! emulated), and its bit 1 (`0x02`) lets pad steps in; then two bytes a step. The first byte
//! of a step picks the kind; the second the key, the pause length, the button or the stick's
//! value. Without bit 1 (the layout before the pad, which the existing corpus uses) the kind
//! is the first byte modulo 8: 0–2 press, 3 repeat, 4–5 release, 6 pause of 8 ms per unit,
//! 7 focus lost (second byte below 8) or a pause of 1 ms per unit. With bit 1, a step whose
//! first byte has bit 3 (`0x08`) clear reads as before, and one with it set is a pad step by
//! the first byte modulo 8: 0 left stick X, 1 left stick Y, 2 right stick X, 3 right trigger
//! (the second byte as a signed value in hundredths, clamped to ±100), 4 a button pressed,
//! 5 released ([`BUTTONS`], the second byte modulo their count), 6 the pad plugged in, 7 the
//! pad lost.

use super::Target;
use crate::app::input::{KeyKind, TermEvent};
use crate::app::run::{self, AppInputs, AppOptions};
use crate::app::{AppState, InputTrace, Place};
use crate::config::{Action, Config, Key, KeyCode};
use crate::config::{Button, PadAction};
use crate::fleet::Fleet;
use crate::model::Model;
use crate::session::{Direction, LinkState, LogItem};
use crate::sync::lock;
use crate::teleop::gamepad::{Axis, PadEvent};
use crate::teleop::held::ReleaseMode;
use ratatui::{Frame, Terminal, backend::TestBackend};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::{mpsc, watch};
use tokio::time::{Instant, sleep};

pub const TARGET: Target = Target {
    name: "app_input",
    run: run_input,
    dictionary: &[
        b"\x00\x00",
        b"\x00\x01",
        b"\x02\x00",
        b"\x03\x20",
        b"\x00\x08",
        b"\x00\x0c",
        b"\x00\x0d",
        b"\x00\x0e",
        b"\x00\x0f",
        b"\x00\x10",
        b"\x0e\x00",
        b"\x0f\x00",
        b"\x09\x64",
        b"\x09\x00",
        b"\x08\x9c",
        b"\x0c\x01",
        b"\x0d\x01",
        b"\x0c\x05",
    ],
};

/// The pad's buttons a sequence presses: every bindable one (the stop, help, aim, stances,
/// animation, and those bound to nothing by default) then the D-pad's sounds.
pub const BUTTONS: [Button; 12] = {
    const DPAD: [Button; 4] = [
        Button::DPadUp,
        Button::DPadDown,
        Button::DPadLeft,
        Button::DPadRight,
    ];
    let bindable = Button::BINDABLE;
    let mut all = [Button::South; 12];
    let mut i = 0;
    while i < all.len() {
        all[i] = if i < bindable.len() {
            bindable[i]
        } else {
            DPAD[i - bindable.len()]
        };
        i += 1;
    }
    all
};

/// The pad's axes a sequence moves (the right stick's Y is RVR's tank track only).
pub const AXES: [Axis; 4] = [Axis::LeftX, Axis::LeftY, Axis::RightX, Axis::RightTrigger];

/// The keys a sequence is made of: every place's way in and out, typing, and the drive keys.
pub const KEYS: [Key; 33] = [
    Key::plain(KeyCode::Up),
    Key::plain(KeyCode::Down),
    Key::plain(KeyCode::Left),
    Key::plain(KeyCode::Right),
    Key::ch('w'),
    Key::ch('s'),
    Key::ch('a'),
    Key::ch('d'),
    Key::plain(KeyCode::Esc),
    Key::plain(KeyCode::Enter),
    Key::plain(KeyCode::Tab),
    Key::plain(KeyCode::Space),
    Key::ch('?'),
    Key::ch('g'),
    Key::ch('l'),
    Key::ch('u'),
    Key::ch('n'),
    Key::ch('m'),
    Key::ch('/'),
    Key::ch('y'),
    Key::ch('t'),
    Key::ch('o'),
    Key::ch('1'),
    Key::ch('2'),
    Key::ch('p'),
    Key::ch('+'),
    Key::plain(KeyCode::PageDown),
    Key::plain(KeyCode::Backspace),
    Key::ch('`'),
    Key::ch('c'),
    Key::ch('f'),
    Key::ch('x'),
    // The stop that works in every place, the text prompts included.
    Key::CTRL_SPACE,
];

/// One step of a sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    Press(Key),
    Repeat(Key),
    Release(Key),
    FocusLost,
    /// Nothing happens for this long (ticks, emulated releases, the droids move).
    Pause(Duration),
    /// A pad axis moved to this value in hundredths (-100..=100; 0 is centred, the trigger
    /// at rest).
    Stick(Axis, i8),
    PadPress(Button),
    PadRelease(Button),
    /// A pad is plugged in (its sticks at rest until they move).
    PadFound,
    /// The pad is unplugged.
    PadLost,
}

/// The emulated release timeouts the rig uses (the config's defaults are of this order).
pub const EMULATED: ReleaseMode = ReleaseMode::Emulated {
    first: Duration::from_millis(650),
    repeat: Duration::from_millis(150),
};

pub fn run_input(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let release = if mode & 1 == 0 {
        ReleaseMode::Reported
    } else {
        EMULATED
    };
    let steps = if mode & 2 == 0 {
        decode(rest)
    } else {
        decode_with_pad(rest)
    };
    if let Err(v) = check(release, &steps) {
        panic!("{v}");
    }
}

/// Two bytes a step (at most 200 steps: the harness runs the whole app for each).
pub fn decode(data: &[u8]) -> Vec<Step> {
    data.chunks_exact(2)
        .take(200)
        .map(|c| key_step(c[0], c[1]))
        .collect()
}

/// A keyboard step from its two bytes (the layout before the pad).
fn key_step(kind: u8, arg: u8) -> Step {
    let key = KEYS[arg as usize % KEYS.len()];
    match kind % 8 {
        0..=2 => Step::Press(key),
        3 => Step::Repeat(key),
        4 | 5 => Step::Release(key),
        6 => Step::Pause(Duration::from_millis(arg as u64 * 8)),
        _ if arg < 8 => Step::FocusLost,
        _ => Step::Pause(Duration::from_millis(arg as u64)),
    }
}

/// Two bytes a step, the pad's among the keys' (see the module's layout).
pub fn decode_with_pad(data: &[u8]) -> Vec<Step> {
    data.chunks_exact(2)
        .take(200)
        .map(|c| {
            if c[0] & 8 == 0 {
                return key_step(c[0], c[1]);
            }
            let value = (c[1] as i8).clamp(-100, 100);
            let button = BUTTONS[c[1] as usize % BUTTONS.len()];
            match c[0] % 8 {
                k @ 0..=3 => Step::Stick(AXES[k as usize], value),
                4 => Step::PadPress(button),
                5 => Step::PadRelease(button),
                6 => Step::PadFound,
                _ => Step::PadLost,
            }
        })
        .collect()
}

/// Run `steps` against the app and check the promises; the first one broken, explained.
pub fn check(release: ReleaseMode, steps: &[Step]) -> Result<(), String> {
    run(release, steps).map(|_| ())
}

/// What a run left: the speeds written to each droid, and the last frame's state.
pub struct Outcome {
    pub speeds: Vec<Vec<u8>>,
    /// Each droid's drive writes: when (since the first step) and at what speed.
    pub drives: Vec<Vec<(Duration, u8)>>,
    /// When each step was taken, since the first.
    pub steps_at: Vec<Duration>,
    pub state: Option<AppState>,
    /// The app ended before the sequence did (a quit key).
    pub quit: bool,
    /// Emergency stops the app made (each reaches every droid: the promises check that).
    pub estops: usize,
}

/// [`check`], keeping what the run left for a test's own assertions.
pub fn run(release: ReleaseMode, steps: &[Step]) -> Result<Outcome, String> {
    run_with(Config::defaults(), release, steps, true)
}

/// [`run`] with another configuration; `promises`: check the hold-mode promises (a latched
/// drive mode keeps its speed after the key is let go, by design, so they do not apply).
pub fn run_with(
    config: Config,
    release: ReleaseMode,
    steps: &[Step],
    promises: bool,
) -> Result<Outcome, String> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .map_err(|e| e.to_string())?;
    SEEN.with(|s| s.borrow_mut().take());
    rt.block_on(rig(config, release, steps, promises))
}

thread_local! {
    /// The last frame's state (the runtime runs on this thread).
    static SEEN: std::cell::RefCell<Option<AppState>> = const { std::cell::RefCell::new(None) };
}

fn keep(_: &mut Frame, s: &AppState) {
    SEEN.with(|seen| *seen.borrow_mut() = Some(s.clone()));
}

const MODELS: [Model; 3] = [Model::R2D2, Model::BB8, Model::Robi42];

/// A step's event, for the terminal's channel or the pad's.
enum Event {
    Term(TermEvent),
    Pad(PadEvent),
}

/// A drive write seen on a droid's link.
#[derive(Debug, Clone, Copy)]
struct Write {
    at: Instant,
    speed: u8,
    /// Degrees (`None`: a steering robot, which has no heading).
    heading: Option<u16>,
}

type Writes = Arc<Mutex<Vec<Vec<Write>>>>;

async fn rig(
    config: Config,
    release: ReleaseMode,
    steps: &[Step],
    promises: bool,
) -> Result<Outcome, String> {
    let specs = crate::cli::fleet::simulated(&MODELS)
        .into_iter()
        .map(|f| {
            let mut s = crate::cli::fleet::session_config(f.model, &config, true);
            s.pacing = Duration::ZERO;
            f.into_spec(s)
        })
        .collect();
    let fleet = Fleet::start(specs);
    let writes = watch_writes(&fleet);
    for i in 0..fleet.len() {
        if let Some(mut st) = fleet.link_state(i) {
            let _ = st.wait_for(|s| *s == LinkState::Connected).await;
        }
    }
    let (term, term_rx) = mpsc::channel(8);
    let (pad, pad_rx) = mpsc::channel(8);
    let (_quit, quit_rx) = mpsc::channel(1);
    let (trace_tx, mut trace) = watch::channel(InputTrace::default());
    let opts = AppOptions {
        config: config.clone(),
        model: MODELS[0],
        droid_name: String::new(),
        log_path: None,
        release,
        tripod_on_connect: true,
        samples: None,
        remember: None,
    };
    let f = fleet.clone();
    let app = tokio::spawn(async move {
        let Ok(mut terminal) = Terminal::new(TestBackend::new(80, 24));
        let inputs = AppInputs {
            term: term_rx,
            pad: pad_rx,
            quit: quit_rx,
        };
        let _ = run::run(
            &mut terminal,
            run::Source::Fleet(f, Some(trace_tx)),
            opts,
            inputs,
            keep,
        )
        .await;
    });
    // R2 up on three legs before the keys start.
    sleep(Duration::from_secs(3)).await;
    let mut oracle = Oracle::new(release, &config);
    let mut quit = false;
    let first = Instant::now();
    let mut steps_at = Vec::with_capacity(steps.len());
    for step in steps {
        steps_at.push(Instant::now() - first);
        let event = match *step {
            Step::Pause(d) => {
                sleep(d).await;
                continue;
            }
            Step::FocusLost => Event::Term(TermEvent::FocusLost),
            Step::Press(key) => Event::Term(TermEvent::Key {
                key,
                kind: KeyKind::Press,
            }),
            Step::Repeat(key) => Event::Term(TermEvent::Key {
                key,
                kind: KeyKind::Repeat,
            }),
            Step::Release(key) => Event::Term(TermEvent::Key {
                key,
                kind: KeyKind::Release,
            }),
            Step::Stick(axis, at) => Event::Pad(PadEvent::Axis(axis, at as f32 / 100.0)),
            Step::PadPress(b) => Event::Pad(PadEvent::Pressed(b)),
            Step::PadRelease(b) => Event::Pad(PadEvent::Released(b)),
            Step::PadFound => Event::Pad(PadEvent::Connected("fuzz pad".into())),
            Step::PadLost => Event::Pad(PadEvent::Disconnected),
        };
        let before = *trace.borrow_and_update();
        let sent = match event {
            Event::Term(e) => term.send(e).await.is_ok(),
            Event::Pad(e) => pad.send(e).await.is_ok(),
        };
        if !sent {
            quit = true;
            break;
        }
        let after = match trace.wait_for(|t| t.handled > before.handled).await {
            Ok(t) => *t,
            // The app ended (the sequence quit): nothing more to check against.
            Err(_) => {
                quit = true;
                break;
            }
        };
        oracle.step(Instant::now(), step, &before, &after);
    }
    let end = Instant::now();
    // A quit key ends the app after its event was traced: its input channel is closed then.
    quit |= term.is_closed();
    drop(term);
    drop(pad);
    let _ = app.await;
    fleet.shutdown_all(|_| Vec::new()).await;
    let w = lock(&writes).clone();
    let estops = oracle.estops.len();
    if promises {
        oracle.verify(&w, if quit { None } else { Some(end) })?;
    }
    Ok(Outcome {
        speeds: w
            .iter()
            .map(|w| w.iter().map(|x| x.speed).collect())
            .collect(),
        drives: w
            .iter()
            .map(|w| {
                w.iter()
                    .map(|x| (x.at.saturating_duration_since(first), x.speed))
                    .collect()
            })
            .collect(),
        steps_at,
        state: SEEN.with(|s| s.borrow_mut().take()),
        quit,
        estops,
    })
}

fn watch_writes(fleet: &Fleet) -> Writes {
    let writes: Writes = Arc::new(Mutex::new(vec![Vec::new(); fleet.len()]));
    for (i, m) in fleet.members().iter().enumerate() {
        let mut log = m.session.subscribe_log();
        let w = writes.clone();
        let steers = crate::family::for_model(m.model).steers();
        tokio::spawn(async move {
            while let Ok(e) = log.recv().await {
                if e.dir == Direction::Out
                    && let LogItem::Packet { packet, .. } = &e.item
                    && let Some(d) = crate::family::drive_read(packet)
                    && let Ok(mut w) = w.lock()
                {
                    w[i].push(Write {
                        at: Instant::now(),
                        speed: d.speed,
                        heading: (!steers).then(|| d.heading.degrees()),
                    });
                }
            }
        });
    }
    writes
}

/// What the operator holds in the driving place, by the promises' own reading of the events.
struct Oracle {
    release: ReleaseMode,
    keymap: crate::config::KeyMap,
    /// Keys held in driving: (pressed at, last press or repeat, repeats), and the droids they
    /// drive (the chosen one, or all mirrored).
    held: HashMap<Key, (Instant, Instant, u32, Vec<usize>)>,
    /// Spans in which a key of each kind was held in driving, per droid.
    drive_spans: Vec<Vec<(Instant, Instant)>>,
    turn_spans: Vec<Vec<(Instant, Instant)>>,
    /// When the aim key was pressed in driving (the facing becomes heading 0).
    aims: Vec<Instant>,
    /// When an emergency stop was raised.
    estops: Vec<Instant>,
    /// The pad as the oracle reads it (see [`PadReading`]).
    pad: PadReading,
}

/// The pad by the oracle's own reading of the manual and the default bindings: where the left
/// stick was last reported, whether a pad is plugged in, and when the stick or the stop
/// button held each droid.
struct PadReading {
    deadzone: f32,
    stop: Button,
    aim: Button,
    connected: bool,
    /// The left stick, hundredths (x right, y up).
    left: (i8, i8),
    /// Since when the stick has driven each droid (out of its deadzone, driving on top, the
    /// droid driven), while it does.
    driving: Vec<Option<Instant>>,
    /// When the stick let go of each droid (centred, the pad lost, another place on top,
    /// another droid driven): a stop is written then, at once, unless a key drives on.
    let_go: Vec<Vec<Instant>>,
    /// Since when the stop button has been held, while it is.
    stop_from: Option<Instant>,
    /// Spans in which the stop button was held (every droid is held at 0 then).
    stop_spans: Vec<(Instant, Instant)>,
}

impl PadReading {
    fn new(config: &Config) -> PadReading {
        let pad = &config.gamepad;
        PadReading {
            deadzone: pad.deadzone,
            stop: pad.buttons.button(PadAction::EStop),
            aim: pad.buttons.button(PadAction::Aim),
            connected: false,
            left: (0, 0),
            driving: vec![None; MODELS.len()],
            let_go: vec![Vec::new(); MODELS.len()],
            stop_from: None,
            stop_spans: Vec::new(),
        }
    }

    /// The left stick out of its deadzone (a hair's width at the edge counts as out: the
    /// oracle allows, it does not ask for, a drive there).
    fn out(&self) -> bool {
        let (x, y) = (self.left.0 as f64 / 100.0, self.left.1 as f64 / 100.0);
        self.connected && (x * x + y * y).sqrt() > self.deadzone as f64 - 1e-4
    }

    fn let_go_stop(&mut self, at: Instant) {
        if let Some(from) = self.stop_from.take() {
            self.stop_spans.push((from, at));
        }
    }
}

impl Oracle {
    fn new(release: ReleaseMode, config: &Config) -> Oracle {
        Oracle {
            release,
            keymap: config.keymap.clone(),
            held: HashMap::new(),
            drive_spans: vec![Vec::new(); MODELS.len()],
            turn_spans: vec![Vec::new(); MODELS.len()],
            aims: Vec::new(),
            estops: Vec::new(),
            pad: PadReading::new(config),
        }
    }

    /// When an emulated release lets go of a key last seen at `last`.
    fn expiry(&self, last: Instant, repeats: u32) -> Option<Instant> {
        match self.release {
            ReleaseMode::Reported => None,
            ReleaseMode::Emulated { first, repeat } => {
                Some(last + if repeats == 0 { first } else { repeat })
            }
        }
    }

    /// Let go of `key` at `at` (or when it expired, if sooner).
    fn let_go(&mut self, key: Key, at: Instant) {
        if let Some((from, last, repeats, droids)) = self.held.remove(&key) {
            let to = self.expiry(last, repeats).map_or(at, |e| e.min(at));
            let spans = match self.keymap.action(&key) {
                Some(Action::Forward | Action::Backward) => &mut self.drive_spans,
                _ => &mut self.turn_spans,
            };
            for d in droids {
                spans[d].push((from, to));
            }
        }
    }

    fn let_go_all(&mut self, at: Instant) {
        let keys: Vec<Key> = self.held.keys().copied().collect();
        for k in keys {
            self.let_go(k, at);
        }
    }

    fn step(&mut self, now: Instant, step: &Step, before: &InputTrace, after: &InputTrace) {
        // Emulated releases that came due before this event.
        let due: Vec<Key> = self
            .held
            .iter()
            .filter(|(_, (_, last, r, _))| self.expiry(*last, *r).is_some_and(|e| e <= now))
            .map(|(k, _)| *k)
            .collect();
        for k in due {
            self.let_go(k, now);
        }
        if after.estops > before.estops {
            self.estops.push(now);
        }
        let stayed = before.place == Place::Driving
            && after.place == Place::Driving
            && after.clears == before.clears;
        match *step {
            Step::Press(key) | Step::Repeat(key) if stayed => {
                let action = self.keymap.action(&key);
                if action == Some(Action::Aim) && matches!(step, Step::Press(_)) {
                    self.aims.push(now);
                }
                let moves = matches!(
                    action,
                    Some(Action::Forward | Action::Backward | Action::Left | Action::Right)
                );
                match self.held.get_mut(&key) {
                    Some(h) => {
                        h.1 = now;
                        h.2 += 1;
                    }
                    None if moves && matches!(step, Step::Press(_)) => {
                        let droids = if after.mirror {
                            (0..MODELS.len()).collect()
                        } else {
                            vec![after.chosen]
                        };
                        self.held.insert(key, (now, now, 0, droids));
                    }
                    None => {}
                }
            }
            Step::Release(key) => {
                for k in case_pair(key) {
                    self.let_go(k, now);
                }
            }
            _ => {}
        }
        if after.clears != before.clears {
            self.let_go_all(now);
        }
        self.pad_step(now, step, after, stayed);
    }

    /// A pad step read, then which droids the stick drives from now on.
    fn pad_step(&mut self, now: Instant, step: &Step, after: &InputTrace, stayed: bool) {
        let pad = &mut self.pad;
        match *step {
            Step::Stick(Axis::LeftX, v) => pad.left.0 = v,
            Step::Stick(Axis::LeftY, v) => pad.left.1 = v,
            Step::PadPress(b) if b == pad.stop => {
                pad.stop_from.get_or_insert(now);
            }
            // The aim button does what the aim key does, where the aim key does it: in
            // driving (docs/app.md's gamepad table); over any other place it does nothing.
            Step::PadPress(b) if b == pad.aim && stayed => self.aims.push(now),
            Step::PadRelease(b) if b == pad.stop => pad.let_go_stop(now),
            Step::PadFound => {
                pad.connected = true;
                // "Plugged in again, nothing moves until the stick does."
                pad.left = (0, 0);
            }
            Step::PadLost => {
                pad.connected = false;
                pad.left = (0, 0);
                pad.let_go_stop(now);
            }
            _ => {}
        }
        let out = self.pad.out() && after.place == Place::Driving;
        for i in 0..MODELS.len() {
            let drives = out && (after.mirror || after.chosen == i);
            match (drives, self.pad.driving[i]) {
                (true, None) => self.pad.driving[i] = Some(now),
                (false, Some(from)) => {
                    self.pad.driving[i] = None;
                    self.pad.let_go[i].push(now);
                    // The stick points the heading: it drives and turns.
                    self.drive_spans[i].push((from, now));
                    self.turn_spans[i].push((from, now));
                }
                _ => {}
            }
        }
    }

    /// Check every write against what was held; `end`: when the sequence ended with the app
    /// still running (held keys count until then).
    fn verify(mut self, writes: &[Vec<Write>], end: Option<Instant>) -> Result<(), String> {
        let end = end.unwrap_or_else(Instant::now);
        self.let_go_all(end);
        for i in 0..MODELS.len() {
            if let Some(from) = self.pad.driving[i].take() {
                self.drive_spans[i].push((from, end));
                self.turn_spans[i].push((from, end));
            }
        }
        self.pad.let_go_stop(end);
        let within = |spans: &[(Instant, Instant)], t: Instant| {
            spans.iter().any(|(a, b)| *a <= t && t <= *b)
        };
        let overlaps = |spans: &[(Instant, Instant)], t1: Instant, t2: Instant| {
            spans.iter().any(|(a, b)| *a <= t2 && t1 <= *b)
        };
        for (i, w) in writes.iter().enumerate() {
            for x in w.iter().filter(|x| x.speed > 0 && x.at <= end) {
                if !within(&self.drive_spans[i], x.at) {
                    return Err(format!(
                        "droid {i} ({}) was written speed {} at {:?} with no drive key held in \
                         driving and the stick not driving it: drive spans {:?}",
                        MODELS[i].display_name(),
                        x.speed,
                        x.at,
                        self.drive_spans[i]
                    ));
                }
                // Strictly inside: a tick at the press's instant may come before the press.
                if let Some((a, b)) = self
                    .pad
                    .stop_spans
                    .iter()
                    .find(|(a, b)| *a < x.at && x.at < *b)
                {
                    return Err(format!(
                        "droid {i} ({}) was written speed {} at {:?} while the pad's stop \
                         button was held ({a:?} to {b:?})",
                        MODELS[i].display_name(),
                        x.speed,
                        x.at,
                    ));
                }
            }
            for pair in w.windows(2) {
                let (a, b) = (pair[0], pair[1]);
                if b.at > end || a.heading == b.heading {
                    continue;
                }
                let aimed = self.aims.iter().any(|t| a.at <= *t && *t <= b.at);
                // A v1 droid backs up by rolling the other way: half a turn while a drive
                // key is held (and back when it is let go) is the reverse, not a turn.
                let reversed = a
                    .heading
                    .zip(b.heading)
                    .is_some_and(|(x, y)| x.abs_diff(y) == 180)
                    && overlaps(&self.drive_spans[i], a.at, b.at);
                if !aimed && !reversed && !overlaps(&self.turn_spans[i], a.at, b.at) {
                    return Err(format!(
                        "droid {i} ({}) turned from {:?} to {:?} between {:?} and {:?} with no \
                         turn key held in driving and the stick not driving it",
                        MODELS[i].display_name(),
                        a.heading,
                        b.heading,
                        a.at,
                        b.at
                    ));
                }
            }
            // "Unplugging the pad, or the stick back in its deadzone, writes a stop at once":
            // when the stick lets go and no key drives on, the last write by then is a stop.
            for t in &self.pad.let_go[i] {
                let keys_drive_on = self.drive_spans[i].iter().any(|(a, b)| a <= t && t < b);
                let last = w.iter().rfind(|x| x.at <= *t);
                if let Some(x) = last.filter(|x| x.speed > 0 && !keys_drive_on) {
                    return Err(format!(
                        "the stick let go of droid {i} ({}) at {t:?} but its last write then \
                         was speed {} at {:?}, not a stop",
                        MODELS[i].display_name(),
                        x.speed,
                        x.at
                    ));
                }
            }
            for t in &self.estops {
                if !w.iter().any(|x| x.at == *t && x.speed == 0) {
                    return Err(format!(
                        "the emergency stop at {t:?} was not written to droid {i} ({}) at once",
                        MODELS[i].display_name()
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A character key's two cases (Shift may be let go first); other keys alone.
fn case_pair(key: Key) -> Vec<Key> {
    match key.code {
        KeyCode::Char(c) => {
            let mut v = vec![key];
            for c in [c.to_ascii_lowercase(), c.to_ascii_uppercase()] {
                let k = Key {
                    code: KeyCode::Char(c),
                    ctrl: key.ctrl,
                };
                if !v.contains(&k) {
                    v.push(k);
                }
            }
            v
        }
        _ => vec![key],
    }
}
