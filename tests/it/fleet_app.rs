//! The app on a fleet, under paused time: four simulated droids in one room, mirrored and
//! rolling. Safety first: one emergency stop reaches all four; a droid whose link is lost for
//! good is stopped by its own fail-safe while the others go on; quitting stops and
//! disconnects every droid. Then the roster, choosing a droid, and the fleet's packet log.

use droidctl::app::input::{KeyKind, TermEvent};
use droidctl::app::run::{self, AppInputs, AppOptions, Exit, ExitReason};
use droidctl::app::state::AppState;
use droidctl::cli::fleet::session_config;
use droidctl::config::{Config, Key, KeyCode};
use droidctl::fleet::{DroidSpec, Fleet};
use droidctl::link::{Connection, Link, LinkError};
use droidctl::model::Model;
use droidctl::session::LinkState;
use droidctl::sim::room::SharedRoom;
use droidctl::sim::{Faults, SimConfig, SimLink, link::SimProbe};
use droidctl::teleop::held::ReleaseMode;
use futures_util::future::BoxFuture;
use ratatui::{Frame, Terminal, backend::TestBackend};
use std::cell::RefCell;
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio::time::{Instant, sleep};

const MODELS: [Model; 4] = [Model::R2D2, Model::BB8, Model::SprkPlus, Model::Robi42];

thread_local! {
    /// The last frame's state, kept by the draw function (the roster is made for drawing).
    /// Per thread: each test's runtime runs on its own.
    static SEEN: RefCell<Option<AppState>> = const { RefCell::new(None) };
}

fn keep(_: &mut Frame, s: &AppState) {
    SEEN.with(|seen| *seen.borrow_mut() = Some(s.clone()));
}

fn seen() -> AppState {
    SEEN.with(|s| s.borrow().clone())
        .expect("a frame was drawn")
}

/// A link that, from `cut_at` on, cannot be opened (the droid went out of range): with a
/// scheduled disconnect at the same time, the droid is on its own from then on.
struct OutOfRange {
    inner: SimLink,
    cut_at: Option<Instant>,
}

impl Link for OutOfRange {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            if self.cut_at.is_some_and(|t| Instant::now() >= t) {
                return Err(LinkError::transient("out of range"));
            }
            self.inner.open().await
        })
    }
    fn describe(&self) -> String {
        self.inner.describe()
    }
}

/// The app's inputs for a test: the key channel to type into, and what the app reads (the
/// pad and signal senders kept alive with it).
fn inputs() -> (mpsc::Sender<TermEvent>, AppInputs, impl Send + 'static) {
    let (term, term_rx) = mpsc::channel(64);
    let (pad, pad_rx) = mpsc::channel(4);
    let (quit, quit_rx) = mpsc::channel(4);
    let inputs = AppInputs {
        term: term_rx,
        pad: pad_rx,
        quit: quit_rx,
    };
    (term, inputs, (pad, quit))
}

fn opts(config: Config, tripod_on_connect: bool) -> AppOptions {
    AppOptions {
        config,
        model: Model::R2D2,
        droid_name: String::new(),
        log_path: None,
        release: ReleaseMode::Reported,
        samples: None,
        remember: None,
        tripod_on_connect,
    }
}

fn terminal() -> Terminal<TestBackend> {
    Terminal::new(TestBackend::new(120, 40)).unwrap()
}

struct Harness {
    term: mpsc::Sender<TermEvent>,
    fleet: Fleet,
    probes: Vec<SimProbe>,
    app: JoinHandle<Exit>,
}

/// The app on `fleet` (tripod on connect): the key channel to type into, and the app's task.
fn launch(fleet: &Fleet, config: Config) -> (mpsc::Sender<TermEvent>, JoinHandle<Exit>) {
    let (term, inputs, keep_alive) = inputs();
    let opts = opts(config, true);
    let f = fleet.clone();
    let app = tokio::spawn(async move {
        let _keep = keep_alive;
        run::run(&mut terminal(), f, opts, inputs, keep)
            .await
            .unwrap()
    });
    (term, app)
}

/// Four droids in one room; droid `lost` (if any) loses its link for good at `lost_at`.
async fn start(lost: Option<(usize, Duration)>) -> Harness {
    let config = Config::defaults();
    let room = SharedRoom::new();
    let origins = SharedRoom::origins(MODELS.len());
    let mut probes = Vec::new();
    let mut specs = Vec::new();
    let t0 = Instant::now();
    for (i, (&m, origin)) in MODELS.iter().zip(origins).enumerate() {
        let mut cfg = SimConfig::for_model(m);
        cfg.place = Some(room.place(origin, cfg.radius_cm));
        let cut = lost.filter(|(j, _)| *j == i).map(|(_, at)| at);
        let faults = Faults {
            disconnect_at: cut.into_iter().collect(),
            ..Faults::none()
        };
        let link = SimLink::new(m, cfg, faults);
        probes.push(link.probe());
        specs.push(DroidSpec {
            name: format!("droid-{i}"),
            model: m,
            link: Box::new(OutOfRange {
                inner: link,
                cut_at: cut.map(|d| t0 + d),
            }),
            session: session_config(m, &config, true),
            origin: "simulated".into(),
            room_origin: Some(origin),
        });
    }
    let fleet = Fleet::start(specs);
    let (term, app) = launch(&fleet, config);
    // Connected, and R2 up on three legs.
    sleep(Duration::from_secs(3)).await;
    Harness {
        term,
        fleet,
        probes,
        app,
    }
}

impl Harness {
    async fn key(&self, key: Key, kind: KeyKind) {
        self.term.send(TermEvent::Key { key, kind }).await.unwrap();
    }
    async fn tap(&self, key: Key) {
        self.key(key, KeyKind::Press).await;
        self.key(key, KeyKind::Release).await;
    }
    fn speeds(&self) -> Vec<f32> {
        self.probes
            .iter()
            .map(|p| p.state().velocity_cm_s.abs())
            .collect()
    }
    /// Mirror on, cruise speed down to 40 on all four (slow enough to stay off the walls
    /// for several seconds), forward held.
    async fn mirrored_and_rolling(&self) {
        self.tap(Key::ch('y')).await;
        for _ in 0..4 {
            self.tap(Key::ch('-')).await;
        }
        self.key(Key::ch('w'), KeyKind::Press).await;
        sleep(Duration::from_secs(2)).await;
        let v = self.speeds();
        assert!(v.iter().all(|v| *v > 1.0), "all four roll: {v:?}");
    }
}

#[tokio::test(start_paused = true)]
async fn one_emergency_stop_reaches_all_four_mirrored_droids() {
    let h = start(None).await;
    h.mirrored_and_rolling().await;
    // Space: e-stop, latched while held; forward is still held.
    h.key(Key::plain(KeyCode::Space), KeyKind::Press).await;
    sleep(Duration::from_millis(800)).await;
    let v = h.speeds();
    assert!(v.iter().all(|v| *v == 0.0), "all four stopped: {v:?}");
    // It holds: nothing rolls again while forward stays held under the e-stop.
    sleep(Duration::from_secs(2)).await;
    assert!(h.speeds().iter().all(|v| *v == 0.0));
    h.key(Key::plain(KeyCode::Space), KeyKind::Release).await;
    h.key(Key::ch('w'), KeyKind::Release).await;
    h.tap(Key::ch('q')).await;
    let exit = h.app.await.unwrap();
    assert_eq!(exit.reason, ExitReason::Quit);
}

#[tokio::test(start_paused = true)]
async fn without_mirror_only_the_chosen_droid_drives_and_the_e_stop_still_reaches_all() {
    let h = start(None).await;
    h.key(Key::ch('w'), KeyKind::Press).await;
    sleep(Duration::from_secs(2)).await;
    let v = h.speeds();
    assert!(v[0] > 5.0 && v[1..].iter().all(|v| *v == 0.0), "{v:?}");
    // Tab: the next droid. Choosing another droid lets go of every held key: nothing
    // drives until a drive key is pressed again (issue 26), then only the second droid.
    h.tap(Key::plain(KeyCode::Tab)).await;
    sleep(Duration::from_secs(2)).await;
    let v = h.speeds();
    assert!(
        v.iter().all(|v| *v == 0.0),
        "w held across Tab drives nothing: {v:?}"
    );
    h.key(Key::ch('w'), KeyKind::Release).await;
    h.key(Key::ch('w'), KeyKind::Press).await;
    sleep(Duration::from_secs(2)).await;
    let v = h.speeds();
    assert!(v[0] == 0.0 && v[1] > 5.0 && v[2] == 0.0, "{v:?}");
    let seen = seen();
    let roster = seen.roster().expect("a roster with four droids");
    assert_eq!(roster.droids.len(), 4);
    assert_eq!(roster.chosen, 1);
    assert_eq!(
        seen.droid().droid_name,
        "droid-1",
        "the screen follows the chosen droid"
    );
    assert!(roster.droids.iter().all(|d| d.link == LinkState::Connected));
    assert!(roster.droids[1].moving && !roster.droids[0].moving);
    // The fleet's log names every droid's lines.
    let droids: std::collections::BTreeSet<String> = seen
        .log
        .visible(10_000)
        .into_iter()
        .filter_map(|l| l.droid.as_deref().map(str::to_string))
        .collect();
    assert_eq!(droids.len(), 4, "{droids:?}");
    h.key(Key::plain(KeyCode::Space), KeyKind::Press).await;
    sleep(Duration::from_millis(800)).await;
    assert!(h.speeds().iter().all(|v| *v == 0.0));
    h.tap(Key::ch('q')).await;
    h.app.await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn a_droid_that_loses_its_link_is_stopped_by_its_own_fail_safe() {
    // R2-D2 (v2: the 2 s control-system timeout) goes out of range at 6 s, mid-drive.
    let h = start(Some((0, Duration::from_secs(6)))).await;
    h.mirrored_and_rolling().await;
    sleep(Duration::from_millis(1500)).await;
    assert!(!h.probes[0].connected(), "R2's link is gone");
    // Nothing reaches it any more; its own timeout stops it within 2 s (+ braking).
    sleep(Duration::from_millis(2500)).await;
    let v = h.speeds();
    assert_eq!(v[0], 0.0, "R2 stopped by its fail-safe: {v:?}");
    assert!(v[1..].iter().all(|v| *v > 1.0), "the others roll on: {v:?}");
    let seen = seen();
    let r = seen.roster().unwrap();
    assert!(
        matches!(r.droids[0].link, LinkState::Reconnecting { .. }),
        "{:?}",
        r.droids[0].link
    );
    assert!(r.droids[1..].iter().all(|d| d.link == LinkState::Connected));
    h.key(Key::ch('w'), KeyKind::Release).await;
    h.tap(Key::ch('q')).await;
    h.app.await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn quitting_stops_and_disconnects_every_droid() {
    let h = start(None).await;
    h.mirrored_and_rolling().await;
    // Quit while still holding forward: every droid gets its stop, then its link closes.
    h.tap(Key::ch('q')).await;
    let exit = h.app.await.unwrap();
    assert_eq!(exit.stops.len(), 4);
    let before = Instant::now();
    h.fleet.shutdown_all(|i| vec![exit.stops[i].clone()]).await;
    assert!(before.elapsed() <= Duration::from_secs(3));
    sleep(Duration::from_millis(800)).await;
    for (i, p) in h.probes.iter().enumerate() {
        assert!(!p.connected(), "droid {i} disconnected");
        assert_eq!(p.state().velocity_cm_s, 0.0, "droid {i} stopped");
    }
    for m in h.fleet.members() {
        assert!(matches!(m.session.state(), LinkState::Closed { .. }));
    }
}

#[tokio::test(start_paused = true)]
async fn the_fleet_api_addresses_droids_by_name_without_the_app() {
    use droidctl::fleet::FleetCommand;
    use droidctl::units::Heading;
    let config = Config::defaults();
    let found = droidctl::cli::fleet::simulated(&[Model::R2D2, Model::Robi42]);
    let specs = found
        .into_iter()
        .map(|f| {
            let c = session_config(f.model, &config, true);
            f.into_spec(c)
        })
        .collect();
    let fleet = Fleet::start(specs);
    // Connected, R2 up on three legs.
    sleep(Duration::from_secs(3)).await;
    let r2 = fleet.find("r2").unwrap();
    let robi = fleet.find("robi").unwrap();
    assert!(fleet.find("bb8").is_err());
    let mut t = fleet.telemetry(robi).unwrap();
    for i in [r2, robi] {
        fleet
            .command(
                i,
                FleetCommand::Drive {
                    speed: 120,
                    heading: Heading::new(0).unwrap(),
                },
            )
            .unwrap();
    }
    // A bridge keeps re-sending within the fail-safe's 2 s.
    for _ in 0..4 {
        sleep(Duration::from_millis(500)).await;
        fleet
            .command(
                r2,
                FleetCommand::Drive {
                    speed: 120,
                    heading: Heading::new(0).unwrap(),
                },
            )
            .unwrap();
    }
    t.changed().await.unwrap();
    assert!(t.borrow().robi.is_some(), "Robi's telemetry streams");
    let r2_t = fleet.telemetry(r2).unwrap().borrow().clone();
    assert!(r2_t.y_cm.unwrap_or(0.0) > 20.0, "{:?}", r2_t.y_cm);
    fleet.estop_all();
    fleet.shutdown_all(|_| Vec::new()).await;
    assert!(fleet.members().iter().all(|m| m.session.is_closed()));
}

/// `replay` of a fleet's capture in the app: every droid plays back on one clock, the roster
/// lists them, Tab shows another droid's gauges, the log names each line's droid.
#[tokio::test(start_paused = true)]
async fn a_fleet_capture_replays_every_droid_together() {
    use droidctl::capture::replay::Replay;
    // Record a short fleet mission with the real binary.
    let dir = std::env::temp_dir().join(format!("droidctl-fleet-replay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("m.txt");
    std::fs::write(
        &script,
        "@R2 stance tripod\ntogether {\n@R2 drive 80 0 for 2s\n@BB-8 drive 80 180 for 2s\n}\n",
    )
    .unwrap();
    let capture = dir.join("fleet.capture");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args([
            "run",
            script.to_str().unwrap(),
            "--sim",
            "r2d2,bb8",
            "--record",
        ])
        .arg(&capture)
        .env("DROIDCTL_LOG_FILE", dir.join("log"))
        .env("DROIDCTL_CONFIG", "/dev/null")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&capture).unwrap();
    let replays: Vec<(Replay, String)> = droidctl::capture::fleet::split(&text)
        .unwrap()
        .into_iter()
        .map(|c| {
            let model = c.header.model.unwrap();
            let name = c.header.droid.clone().unwrap();
            (Replay::new(c, model), name)
        })
        .collect();
    let (term, inputs, keep_alive) = inputs();
    let opts = opts(Config::defaults(), false);
    let app = tokio::spawn(async move {
        let _keep = keep_alive;
        let file = "fleet.capture".to_string();
        run::run(
            &mut terminal(),
            run::Source::FleetReplay(replays, file),
            opts,
            inputs,
            keep,
        )
        .await
        .unwrap()
    });
    // Past the end of the mission (7 s), at 1×.
    sleep(Duration::from_secs(9)).await;
    let s = seen();
    let r = s.roster().expect("a roster");
    let names: Vec<&str> = r.droids.iter().map(|d| d.name.as_str()).collect();
    assert_eq!(names, ["D2-0001", "BB-0002"]);
    assert_eq!(s.droid().droid_name, "D2-0001");
    let r2_y = s.droid().telemetry.y_cm.unwrap();
    assert!(r2_y > 20.0, "R2 went north in the replay: {r2_y}");
    // BB-8's position is in the roster too, south.
    let (_, bb_y) = r.droids[1].position.expect("BB-8's position");
    assert!(bb_y < -20.0, "BB-8 went south: {bb_y}");
    let named: std::collections::BTreeSet<String> = s
        .log
        .visible(10_000)
        .into_iter()
        .filter_map(|l| l.droid.as_deref().map(str::to_string))
        .collect();
    assert_eq!(named.len(), 2, "{named:?}");
    // Tab: BB-8's gauges.
    term.send(TermEvent::Key {
        key: Key::plain(KeyCode::Tab),
        kind: KeyKind::Press,
    })
    .await
    .unwrap();
    sleep(Duration::from_millis(300)).await;
    let s = seen();
    assert_eq!(s.droid().droid_name, "BB-0002");
    assert!(s.droid().telemetry.y_cm.unwrap() < -20.0);
    assert!(s.droid().replay.is_some(), "still a replay");
    term.send(TermEvent::Key {
        key: Key::ch('q'),
        kind: KeyKind::Press,
    })
    .await
    .unwrap();
    app.await.unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 30 point 5: each droid's view is its own and kept when it is chosen again; `Tab`
/// means "next droid" with the scope on screen too (the scope's channel list is `C`).
#[tokio::test(start_paused = true)]
async fn each_droid_keeps_its_view_and_tab_means_the_next_droid_everywhere() {
    let h = start(None).await;
    // The scope on droid 0, a longer window.
    h.tap(Key::ch('g')).await;
    h.tap(Key::ch('[')).await;
    sleep(Duration::from_millis(300)).await;
    let window = seen().droid().scope.window;
    assert!(seen().droid().scope.visible);
    // Tab with the scope on screen: the next droid (its own view: no scope), no channel list.
    h.tap(Key::plain(KeyCode::Tab)).await;
    sleep(Duration::from_millis(300)).await;
    let s = seen();
    assert_eq!(s.chosen, 1);
    assert_eq!(s.overlay, droidctl::app::state::Overlay::None);
    assert!(!s.droid().scope.visible);
    // Back to droid 0 (` is the previous droid): its scope as it was left.
    h.tap(Key::ch('`')).await;
    sleep(Duration::from_millis(300)).await;
    let s = seen();
    assert_eq!(s.chosen, 0);
    assert!(s.droid().scope.visible);
    assert_eq!(s.droid().scope.window, window);
    h.tap(Key::ch('q')).await;
    h.app.await.unwrap();
}

impl Harness {
    async fn mouse(&self, kind: droidctl::app::input::MouseKind, col: u16, row: u16) {
        self.term
            .send(TermEvent::Mouse { kind, col, row })
            .await
            .unwrap();
        sleep(Duration::from_millis(100)).await;
    }
}

/// Issue 30 point 2: the mouse, with synthetic events on the 120×40 test terminal. A click
/// on the roster chooses that droid (and lets go of held keys: it stops driving); the wheel
/// scrolls the log; a click gives the keys to the log or back to driving; the wheel pages
/// help and a click closes it; a click on a palette entry plays it. Nothing drives.
#[tokio::test(start_paused = true)]
async fn the_mouse_chooses_droids_scrolls_focuses_and_picks() {
    use droidctl::app::input::MouseKind::{Click, ScrollDown, ScrollUp};
    use droidctl::app::state::{Focus, Overlay};
    let h = start(None).await;
    let screen = droidctl::app::layout::screen(ratatui::layout::Rect::new(0, 0, 120, 40), true);
    let strip = screen.roster.expect("a roster strip");
    let (_, room) = droidctl::app::layout::roster_room(strip.width, 4, false);
    // w held drives droid 0; a click on droid 2's entry chooses it and stops droid 0.
    h.key(Key::ch('w'), KeyKind::Press).await;
    sleep(Duration::from_secs(1)).await;
    assert!(h.speeds()[0] > 1.0);
    h.mouse(Click, (2 * room + 3) as u16, strip.y).await;
    assert_eq!(seen().chosen, 2);
    sleep(Duration::from_secs(1)).await;
    assert!(h.speeds().iter().all(|v| *v == 0.0), "{:?}", h.speeds());
    h.key(Key::ch('w'), KeyKind::Release).await;
    // The wheel over the log scrolls it; over the panels it does nothing.
    let log = screen.plan.log;
    let drive = screen.plan.drive.expect("the drive panel");
    h.mouse(ScrollUp, drive.x + 2, drive.y + 2).await;
    assert_eq!(seen().log.scroll, 0);
    h.mouse(ScrollUp, log.x + 5, log.y + 2).await;
    // (Lines that arrive while scrolled back keep the view: the count grows with them.)
    assert!(seen().log.scroll >= 3, "{}", seen().log.scroll);
    for _ in 0..40 {
        let e = TermEvent::Mouse {
            kind: ScrollDown,
            col: log.x + 5,
            row: log.y + 2,
        };
        h.term.send(e).await.unwrap();
    }
    sleep(Duration::from_millis(300)).await;
    assert_eq!(seen().log.scroll, 0, "back to following");
    // A click on the log: the log has the keys; on the panels: driving again.
    h.mouse(Click, log.x + 5, log.y + 2).await;
    assert_eq!(seen().focus, Focus::Log);
    h.mouse(Click, drive.x + 2, drive.y + 2).await;
    assert_eq!(seen().focus, Focus::Drive);
    // Help: the wheel pages, a click closes.
    h.tap(Key::ch('?')).await;
    sleep(Duration::from_millis(100)).await;
    h.mouse(ScrollDown, 60, 20).await;
    assert_eq!(seen().help_page, 1);
    h.mouse(Click, 60, 20).await;
    assert_eq!(seen().overlay, Overlay::None);
    // Back to R2 (droid 0): its animation palette; a click on the third entry plays it.
    h.mouse(Click, 3, strip.y).await;
    assert_eq!(seen().chosen, 0);
    h.tap(Key::ch('n')).await;
    sleep(Duration::from_millis(100)).await;
    let s = seen();
    let rect = droidctl::app::layout::palette_rect(
        ratatui::layout::Rect::new(0, 0, 120, 40),
        s.animations
            .iter()
            .map(|e| ratatui::text::Span::raw(e.name.as_str()).width()),
        s.animations.len(),
    );
    h.mouse(Click, rect.x + 4, rect.y + 3).await;
    let s = seen();
    assert_eq!(s.overlay, Overlay::None, "played and closed");
    let wanted = &s.animations[2].name;
    assert!(
        s.current_hint()
            .is_some_and(|t| t.contains(wanted.as_str()))
            || s.log
                .visible(50)
                .iter()
                .any(|l| l.name.contains("animation")),
        "{:?}",
        s.current_hint()
    );
    assert!(
        h.speeds().iter().all(|v| *v == 0.0),
        "the mouse never drives"
    );
    h.tap(Key::ch('q')).await;
    h.app.await.unwrap();
}

/// The map's box on a drawn screen, as rows of text inside its border (found by its title).
fn map_box(buf: &ratatui::buffer::Buffer) -> Vec<String> {
    let area = buf.area;
    let row = |y: u16| -> Vec<&str> { (0..area.width).map(|x| buf[(x, y)].symbol()).collect() };
    for y in 0..area.height {
        let cells = row(y);
        let line: String = cells.concat();
        let Some(at) = line.find("╭ Map") else {
            continue;
        };
        // The column of the corner (cells, not bytes).
        let x0 = line[..at].chars().count();
        let x1 = (x0 + 1..cells.len())
            .find(|&x| cells[x] == "╮")
            .expect("the map's right corner");
        let y1 = (y + 1..area.height)
            .find(|&yy| buf[(x0 as u16, yy)].symbol() == "╰")
            .expect("the map's bottom corner");
        return (y..=y1).map(|yy| row(yy)[x0..=x1].concat()).collect();
    }
    panic!("no map on the screen");
}

/// Issue 39 point 13: `--sim r2d2,bb8,robi` stand 60 cm apart in one room; the map draws
/// them in room coordinates (the origins `cli::fleet::simulated` gives each droid), so R2
/// (the chosen one, ●) and Robi (3) are on different cells, in the room's order left to
/// right, where they were all drawn on one cell (Robi's 3 hidden under R2's ●).
#[tokio::test(start_paused = true)]
async fn a_simulated_fleet_stands_apart_on_the_map_in_room_coordinates() {
    let config = Config::defaults();
    let models = [Model::R2D2, Model::BB8, Model::Robi42];
    let specs: Vec<DroidSpec> = droidctl::cli::fleet::simulated(&models)
        .into_iter()
        .map(|f| {
            let session = session_config(f.model, &config, true);
            f.into_spec(session)
        })
        .collect();
    assert!(specs.iter().all(|s| s.room_origin.is_some()));
    let fleet = Fleet::start(specs);
    let (term, app) = launch(&fleet, config);
    sleep(Duration::from_secs(3)).await;
    let state = seen();
    assert_eq!(state.chosen, 0, "R2 is the chosen droid");
    let mut t = terminal();
    t.draw(|f| droidctl::ui::draw(f, &state)).unwrap();
    let map = map_box(t.backend().buffer());
    let find = |mark: char| -> Vec<(usize, usize)> {
        map.iter()
            .enumerate()
            .skip(1)
            .take(map.len().saturating_sub(2))
            .flat_map(|(y, l)| {
                l.chars()
                    .enumerate()
                    .skip(1)
                    .filter(move |(_, c)| *c == mark)
                    .map(move |(x, _)| (x, y))
            })
            .collect()
    };
    let (r2, bb8, robi) = (find('●'), find('2'), find('3'));
    let text = map.join("\n");
    assert_eq!(r2.len(), 1, "R2 once:\n{text}");
    assert_eq!(bb8.len(), 1, "BB-8 (2) once:\n{text}");
    assert_eq!(robi.len(), 1, "Robi (3) once:\n{text}");
    assert_ne!(r2[0], robi[0], "{text}");
    assert!(
        r2[0].0 < bb8[0].0 && bb8[0].0 < robi[0].0,
        "R2, BB-8, Robi left to right, as they stand:\n{text}"
    );
    assert_eq!(r2[0].1, robi[0].1, "in one row:\n{text}");
    insta::assert_snapshot!("fleet_map_in_room_coordinates", text);
    term.send(TermEvent::Key {
        key: Key::ch('q'),
        kind: KeyKind::Press,
    })
    .await
    .unwrap();
    app.await.unwrap();
}
