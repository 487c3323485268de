//! Issue 39, the gamepad proven without a device: the whole app (paused time, a simulated
//! droid, the real event loop) driven by a real controller's raw events — an Xbox 360 pad and
//! a DualShock 4, each read through its own line of SDL's controller database by droidctl's
//! SDL layer ([`droidctl::teleop::gamepad_map`]) into gilrs's named events, then through
//! [`droidctl::teleop::gamepad::pad_event`], the function the gilrs device thread uses too.
//! What is checked is on the link (drive-with-heading bytes) and on the screen.

use droidctl::app::input::{KeyKind, TermEvent};
use droidctl::app::place::Place;
use droidctl::app::run::{self, AppInputs, Exit};
use droidctl::app::state::AppState;
use droidctl::config::{Config, Key, KeyCode};
use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::model::Model;
use droidctl::protocol::v2::Packet;
use droidctl::session::{self, Direction, LogEntry, LogItem, SessionConfig};
use droidctl::sim::{Faults, SimConfig, SimLink, link::SimProbe};
use droidctl::teleop::gamepad::{Named, PadEvent, pad_event};
use droidctl::teleop::gamepad_map::{RawInput, SdlMapping, SdlPad};
use ratatui::{Frame, Terminal, backend::TestBackend};
use std::cell::RefCell;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio::time::{Instant, sleep};

/// SDL_GameControllerDB's Linux line for the Xbox 360 controller (USB 045e:028e), as vendored
/// in gilrs 0.11.2 (`SDL_GameControllerDB/gamecontrollerdb.txt`, from
/// github.com/mdqinc/SDL_GameControllerDB).
const XBOX_360: &str = "030000005e0400008e02000010010000,Xbox 360 Controller,a:b0,b:b1,back:b6,dpdown:h0.4,dpleft:h0.8,dpright:h0.2,dpup:h0.1,guide:b8,leftshoulder:b4,leftstick:b9,lefttrigger:a2,leftx:a0,lefty:a1,rightshoulder:b5,rightstick:b10,righttrigger:a5,rightx:a3,righty:a4,start:b7,x:b2,y:b3,platform:Linux,";
/// The same database's Linux line for Sony's DualShock 4 (USB 054c:05c4, the hid-sony
/// layout): cross is b1, circle b2, the right stick a2/a5, the triggers a3/a4.
const DUALSHOCK_4: &str = "030000004c050000c405000011010000,PS4 Controller,a:b1,b:b2,back:b8,dpdown:h0.4,dpleft:h0.8,dpright:h0.2,dpup:h0.1,guide:b12,leftshoulder:b4,leftstick:b10,lefttrigger:a3,leftx:a0,lefty:a1,rightshoulder:b5,rightstick:b11,righttrigger:a4,rightx:a2,righty:a5,start:b9,touchpad:b13,x:b0,y:b3,platform:Linux,";

thread_local! {
    /// The last frame's state (the paused runtime runs the app on the test's thread).
    static SEEN: RefCell<Option<AppState>> = const { RefCell::new(None) };
}

fn keep(_: &mut Frame, s: &AppState) {
    SEEN.with(|seen| *seen.borrow_mut() = Some(s.clone()));
}

/// The last frame's state, once the app has drawn what happened.
async fn state() -> AppState {
    sleep(Duration::from_millis(100)).await;
    SEEN.with(|s| s.borrow().clone())
        .expect("a frame was drawn")
}

/// The screen as a user sees it at 100×30, once the app has drawn what happened (it draws
/// at its frame pace, not at each event).
async fn screen() -> String {
    sleep(Duration::from_millis(100)).await;
    let (w, h) = (100u16, 30u16);
    let mut term = Terminal::new(TestBackend::new(w, h)).expect("test backend");
    let s = SEEN
        .with(|s| s.borrow().clone())
        .expect("a frame was drawn");
    term.draw(|f| droidctl::ui::draw(f, &s)).expect("draw");
    let buf = term.backend().buffer();
    (0..h)
        .map(|y| (0..w).map(|x| buf[(x, y)].symbol()).collect::<String>() + "\n")
        .collect()
}

/// A drive-with-heading command on the link: when, speed, heading.
type Drive = (Instant, u8, u16);

struct Rig {
    term: mpsc::Sender<TermEvent>,
    pad: mpsc::Sender<PadEvent>,
    quit: mpsc::Sender<String>,
    controller: SdlPad,
    drives: Arc<Mutex<Vec<Drive>>>,
    probe: SimProbe,
    app: JoinHandle<Exit>,
}

impl Rig {
    /// `model` simulated, connected and standing; the controller read through `mapping`, not
    /// yet plugged in.
    async fn start(model: Model, mapping: &str) -> Rig {
        let link = SimLink::new(model, SimConfig::default(), Faults::none());
        let probe = link.probe();
        let session = session::start(
            Box::new(link),
            SessionConfig {
                pacing: Duration::ZERO,
                setup: connect_setup(model, &SetupOptions::default()),
                ..SessionConfig::default()
            },
        );
        let drives = Arc::new(Mutex::new(Vec::new()));
        let mut log = session.subscribe_log();
        let seen = drives.clone();
        tokio::spawn(async move {
            while let Ok(LogEntry { dir, item, .. }) = log.recv().await {
                if let (
                    Direction::Out,
                    LogItem::Packet {
                        packet: droidctl::family::Packet::V2(Packet { did, cid, data, .. }),
                        ..
                    },
                ) = (dir, item)
                    && (did, cid) == (0x16, 0x07)
                    && data.len() >= 3
                {
                    let heading = u16::from_be_bytes([data[1], data[2]]);
                    seen.lock()
                        .expect("drives")
                        .push((Instant::now(), data[0], heading));
                }
            }
        });
        let (term, term_rx) = mpsc::channel(64);
        let (pad, pad_rx) = mpsc::channel(64);
        let (quit, quit_rx) = mpsc::channel(4);
        let opts = crate::common::app::simulated_options(model);
        let app = tokio::spawn(async move {
            let mut terminal = Terminal::new(TestBackend::new(100, 30)).expect("test backend");
            let inputs = AppInputs {
                term: term_rx,
                pad: pad_rx,
                quit: quit_rx,
            };
            run::run(&mut terminal, session, opts, inputs, keep)
                .await
                .expect("the app ran")
        });
        sleep(Duration::from_secs(2)).await;
        let controller = SdlPad::new(SdlMapping::parse(mapping).expect("SDL's own line reads"));
        Rig {
            term,
            pad,
            quit,
            controller,
            drives,
            probe,
            app,
        }
    }

    /// gilrs's named events to the app, as the device thread sends them.
    async fn send(&self, named: Vec<Named>) {
        for e in named.into_iter().filter_map(pad_event) {
            self.pad.send(e).await.expect("the app reads the pad");
        }
        sleep(Duration::from_millis(5)).await;
    }

    async fn plug(&self) {
        self.send(vec![self.controller.connected()]).await;
    }

    async fn unplug(&mut self) {
        let gone = self.controller.disconnected();
        self.send(vec![gone]).await;
    }

    async fn raw(&mut self, r: RawInput) {
        let named = self.controller.feed(r);
        self.send(named).await;
    }

    async fn stick(&mut self, x: i16, y: i16) {
        self.raw(RawInput::Axis { index: 0, value: x }).await;
        self.raw(RawInput::Axis { index: 1, value: y }).await;
    }

    async fn button(&mut self, index: u8, pressed: bool) {
        self.raw(RawInput::Button { index, pressed }).await;
    }

    async fn key(&self, k: Key) {
        for kind in [KeyKind::Press, KeyKind::Release] {
            self.term
                .send(TermEvent::Key { key: k, kind })
                .await
                .expect("the app reads keys");
        }
        sleep(Duration::from_millis(50)).await;
    }

    fn drives_since(&self, t: Instant) -> Vec<(u8, u16)> {
        let d = self.drives.lock().expect("drives");
        d.iter().filter(|d| d.0 >= t).map(|d| (d.1, d.2)).collect()
    }

    fn last_drive(&self) -> (u8, u16) {
        let d = self.drives.lock().expect("drives");
        d.last().map(|d| (d.1, d.2)).expect("a drive was written")
    }

    async fn quit(self) {
        self.quit.send("test".into()).await.expect("quit");
        self.app.await.expect("the app ended");
    }
}

/// The speed droidctl must write for a stick at `x`, `y` (-1..1 each), computed here from the
/// documented curve (docs/app.md): a radial deadzone, the rest rescaled to 0..1, raised to
/// `expo`, times `max_speed` — or up to the turbo speed as the right trigger goes down.
fn expected_speed(x: f32, y: f32, trigger: f32) -> u8 {
    let c = Config::defaults();
    let (dz, expo) = (c.gamepad.deadzone, c.gamepad.expo);
    let m = (x * x + y * y).sqrt().min(1.0);
    if m <= dz {
        return 0;
    }
    let base = c.gamepad.max_speed as f32;
    let top = base + (c.control.turbo_speed as f32 - base) * trigger;
    (((m - dz) / (1.0 - dz)).powf(expo) * top).round() as u8
}

#[tokio::test(start_paused = true)]
async fn xbox_stick_drives_with_heading_after_deadzone_and_expo() {
    let mut rig = Rig::start(Model::R2D2, XBOX_360).await;
    rig.plug().await;
    assert!(
        screen().await.contains("Xbox 360 Controller"),
        "{}",
        screen().await
    );

    // Inside the deadzone (0.12 of the travel): nothing is written.
    let t = Instant::now();
    rig.stick(0, -4000).await;
    sleep(Duration::from_millis(500)).await;
    assert!(
        rig.drives_since(t).iter().all(|d| d.0 == 0),
        "{:?}",
        rig.drives_since(t)
    );

    // Three quarters up (SDL's up is negative): heading 0, the curved speed.
    rig.stick(0, -24576).await;
    sleep(Duration::from_millis(300)).await;
    let want = expected_speed(0.0, 0.75, 0.0);
    assert_eq!(want, 80, "the curve itself: ((0.75-0.15)/0.85)² × 160");
    assert_eq!(rig.last_drive(), (want, 0));

    // Half right, half up: heading 45, the radius through the curve.
    rig.stick(16384, -16384).await;
    sleep(Duration::from_millis(300)).await;
    assert_eq!(
        rig.last_drive(),
        (expected_speed(16384.0 / 32767.0, 0.5, 0.0), 45)
    );

    // Full left: heading 270 at the full stick speed; the right trigger (a5) adds turbo.
    rig.stick(-32768, 0).await;
    sleep(Duration::from_millis(300)).await;
    assert_eq!(rig.last_drive(), (160, 270));
    rig.raw(RawInput::Axis {
        index: 5,
        value: 32767,
    })
    .await;
    sleep(Duration::from_millis(300)).await;
    assert_eq!(rig.last_drive(), (expected_speed(1.0, 0.0, 1.0), 270));
    assert_eq!(rig.last_drive().0, 255);

    // Back into the deadzone: a stop at once, then nothing.
    let t = Instant::now();
    rig.stick(1000, -1000).await;
    let after = rig.drives_since(t);
    assert_eq!(after.first().map(|d| d.0), Some(0), "{after:?}");
    sleep(Duration::from_millis(500)).await;
    assert!(rig.drives_since(t).iter().all(|d| d.0 == 0));
    rig.quit().await;
}

#[tokio::test(start_paused = true)]
async fn dualshock_is_read_through_its_own_layout() {
    let mut rig = Rig::start(Model::R2D2, DUALSHOCK_4).await;
    rig.plug().await;
    rig.stick(0, -32768).await;
    sleep(Duration::from_millis(300)).await;
    assert_eq!(rig.last_drive(), (160, 0));
    // The DualShock's right trigger is a4 (the Xbox's a5 is its right stick Y here).
    rig.raw(RawInput::Axis {
        index: 5,
        value: 32767,
    })
    .await;
    sleep(Duration::from_millis(300)).await;
    assert_eq!(rig.last_drive(), (160, 0), "a5 is no trigger on this pad");
    rig.raw(RawInput::Axis { index: 4, value: 0 }).await;
    sleep(Duration::from_millis(300)).await;
    assert_eq!(rig.last_drive(), (expected_speed(0.0, 1.0, 0.5), 0));

    // b1 is cross (South, the tripod button): no stop. b2 is circle (East, the stop).
    rig.button(1, true).await;
    rig.button(1, false).await;
    sleep(Duration::from_millis(200)).await;
    assert!(rig.last_drive().0 > 0, "cross does not stop");
    assert!(!screen().await.contains("E-STOP"));
    let t = Instant::now();
    rig.button(2, true).await;
    assert_eq!(rig.drives_since(t).first().map(|d| d.0), Some(0));
    sleep(Duration::from_millis(300)).await;
    assert!(
        rig.drives_since(t).iter().all(|d| d.0 == 0),
        "held stop, stick still up: {:?}",
        rig.drives_since(t)
    );
    assert!(screen().await.contains("E-STOP"), "{}", screen().await);
    rig.quit().await;
}

/// The places the keyboard opens, each with how to get there (issue 39: help, palettes,
/// settings, the prompts, the packet detail).
fn places() -> Vec<(Model, &'static str, Vec<Key>, Place)> {
    let k = Key::ch;
    let enter = Key::plain(KeyCode::Enter);
    vec![
        (Model::R2D2, "driving", vec![], Place::Driving),
        (Model::R2D2, "log", vec![k('l')], Place::Log),
        (Model::R2D2, "help", vec![k('?')], Place::Help),
        (Model::R2D2, "animations", vec![k('n')], Place::Palette),
        (Model::R2D2, "sounds", vec![k('m')], Place::Palette),
        (Model::R2D2, "settings", vec![k('u')], Place::Tuning),
        (
            Model::R2D2,
            "channels",
            vec![k('g'), k('C')],
            Place::Channels,
        ),
        (
            Model::R2D2,
            "filter prompt",
            vec![k('l'), k('/')],
            Place::Filter,
        ),
        (
            Model::R2D2,
            "packet detail",
            vec![k('l'), enter],
            Place::Packet,
        ),
        (
            Model::R2D2,
            "detail search prompt",
            vec![k('l'), enter, k('/')],
            Place::Packet,
        ),
        (Model::Bolt, "matrix prompt", vec![k('i')], Place::Matrix),
    ]
}

#[tokio::test(start_paused = true)]
async fn the_stop_button_stops_over_every_place() {
    for (model, name, keys, place) in places() {
        let mut rig = Rig::start(model, XBOX_360).await;
        rig.plug().await;
        // Driving first, so there is something to stop.
        rig.stick(0, -32768).await;
        sleep(Duration::from_millis(300)).await;
        for k in keys {
            rig.key(k).await;
        }
        assert_eq!(Place::of(&state().await, false), place, "{name}");
        sleep(Duration::from_millis(300)).await;
        assert!(!screen().await.contains("E-STOP"), "{name}");
        let t = Instant::now();
        // The Xbox's B (b1, East): the stop.
        rig.button(1, true).await;
        assert_eq!(
            rig.drives_since(t).first().map(|d| d.0),
            Some(0),
            "{name}: the stop is written at once"
        );
        assert!(
            screen().await.contains("E-STOP"),
            "{name}:\n{}",
            screen().await
        );
        // Held, it holds every droid at 0 (the stick is still pushed up).
        sleep(Duration::from_millis(300)).await;
        assert!(
            rig.drives_since(t).iter().all(|d| d.0 == 0),
            "{name}: {:?}",
            rig.drives_since(t)
        );
        rig.button(1, false).await;
        rig.quit().await;
    }
}

#[tokio::test(start_paused = true)]
async fn the_help_button_opens_help_and_the_stop_works_over_it() {
    let mut rig = Rig::start(Model::R2D2, DUALSHOCK_4).await;
    rig.plug().await;
    // DualShock's share button (b8, SDL's back, gilrs's Select): help.
    rig.button(8, true).await;
    rig.button(8, false).await;
    assert_eq!(Place::of(&state().await, false), Place::Help);
    let t = Instant::now();
    rig.button(2, true).await;
    assert_eq!(rig.drives_since(t).first().map(|d| d.0), Some(0));
    assert!(screen().await.contains("E-STOP"), "{}", screen().await);
    rig.quit().await;
}

#[tokio::test(start_paused = true)]
async fn a_pad_unplugged_mid_drive_stops_the_droid_and_says_so() {
    let mut rig = Rig::start(Model::R2D2, XBOX_360).await;
    rig.plug().await;
    rig.stick(0, -32768).await;
    sleep(Duration::from_secs(1)).await;
    assert_eq!(rig.last_drive(), (160, 0));
    assert!(rig.probe.state().velocity_cm_s > 10.0, "it rolls");
    let t = Instant::now();
    rig.unplug().await;
    assert_eq!(
        rig.drives_since(t).first().map(|d| d.0),
        Some(0),
        "the stop is written at once"
    );
    let shown = screen().await;
    assert!(shown.contains("gamepad unplugged"), "{shown}");
    assert!(shown.contains("no pad"), "{shown}");
    sleep(Duration::from_secs(1)).await;
    assert!(rig.drives_since(t).iter().all(|d| d.0 == 0));
    assert!(
        rig.probe.state().velocity_cm_s.abs() < 1.0,
        "{:?}",
        rig.probe.state()
    );
    // Plugged in again: nothing moves until the stick does.
    let t = Instant::now();
    rig.plug().await;
    sleep(Duration::from_millis(500)).await;
    assert!(rig.drives_since(t).iter().all(|d| d.0 == 0));
    rig.quit().await;
}

/// A pad gilrs does not know is given its SDL line in `gamepad.mappings`: a line that reads is
/// kept for gilrs, a mistyped one stops the configuration from loading, with its key and what
/// to write instead.
#[test]
fn configured_mappings_are_read_when_the_configuration_loads() {
    use droidctl::config::Config;
    let good = format!("[gamepad]\nmappings = [{DUALSHOCK_4:?}]\n");
    let c = Config::parse_merged(None, &good).expect("SDL's own line loads");
    assert_eq!(c.gamepad.mappings, vec![DUALSHOCK_4.to_string()]);
    assert!(Config::defaults().gamepad.mappings.is_empty());

    let typo = DUALSHOCK_4.replace("b:b2", "b:2");
    let bad = format!("[gamepad]\nmappings = [{DUALSHOCK_4:?}, {typo:?}]\n");
    let e = Config::parse_merged(None, &bad).expect_err("a mistyped line is refused");
    assert_eq!(e.key.as_deref(), Some("gamepad.mappings"), "{e}");
    let shown = e.to_string();
    assert!(
        shown.contains("line 2 of the list") && shown.contains("\"b:2\"") && shown.contains("bN"),
        "{shown}"
    );
}

/// The pad's stance and aim buttons do what their keys do, where their keys do it: in driving.
/// Over help, a palette or the log they do nothing (R2 would change stance behind the help
/// page); the stop button is the one that works everywhere (above).
#[tokio::test(start_paused = true)]
async fn the_stance_buttons_act_only_where_the_keyboard_drives() {
    use droidctl::protocol::wire::LegState;
    let mut rig = Rig::start(Model::R2D2, XBOX_360).await;
    rig.plug().await;
    let stance = |rig: &Rig| rig.probe.state().stance;
    let first = stance(&rig);
    // The Xbox's A (b0, South) asks for the tripod, Y (b3, North) for the bipod: press the one
    // that changes what R2 stands on now.
    let (button, wanted) = if first == LegState::Tripod {
        (3, LegState::Bipod)
    } else {
        (0, LegState::Tripod)
    };
    for (name, open) in [
        ("help", Key::ch('?')),
        ("animations", Key::ch('n')),
        ("log", Key::ch('l')),
    ] {
        rig.key(open).await;
        assert_ne!(Place::of(&state().await, false), Place::Driving, "{name}");
        rig.button(button, true).await;
        rig.button(button, false).await;
        sleep(Duration::from_secs(3)).await;
        assert_eq!(stance(&rig), first, "{name}: the stance changed behind it");
        rig.key(Key::plain(KeyCode::Esc)).await;
        assert_eq!(Place::of(&state().await, false), Place::Driving, "{name}");
    }
    rig.button(button, true).await;
    rig.button(button, false).await;
    sleep(Duration::from_secs(3)).await;
    assert_eq!(
        stance(&rig),
        wanted,
        "in driving the button changes the stance"
    );
    rig.quit().await;
}
