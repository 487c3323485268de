//! The event loop and control loop under paused time: tick rate, deadman (release, emulated
//! release, focus loss, gamepad unplug), e-stop, stop on exit, link loss.

use droidctl::app::input::{KeyKind, TermEvent};
use droidctl::app::run::{self, AppInputs, AppOptions, Exit, ExitReason};
use droidctl::app::state::{AppState, Focus, Overlay};
use droidctl::config::Config;
use droidctl::config::{Key, KeyCode};
use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::model::Model;
use droidctl::protocol::v2::Packet;
use droidctl::session::{self, Direction, LogEntry, LogItem, SessionConfig, SessionHandle};
use droidctl::sim::{Faults, SimConfig, SimLink, link::SimProbe};
use droidctl::teleop::gamepad::{Axis, PadEvent};
use droidctl::teleop::held::ReleaseMode;
use ratatui::{Frame, Terminal, backend::TestBackend};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio::time::{Instant, sleep};

fn no_draw(_: &mut Frame, _: &AppState) {}

struct Harness {
    term: mpsc::Sender<TermEvent>,
    pad: mpsc::Sender<PadEvent>,
    quit: mpsc::Sender<String>,
    session: SessionHandle,
    probe: SimProbe,
    /// Outgoing drive commands: (time since start, speed, heading).
    drives: Arc<Mutex<Vec<(Duration, u8, u16)>>>,
    app: JoinHandle<Exit>,
    start: Instant,
}

async fn start(release: ReleaseMode, faults: Faults, pacing_ms: u64) -> Harness {
    start_with(release, faults, pacing_ms, Config::defaults(), true).await
}

/// `tripod_on_connect` is both the session's setup and the app's option, as `droidctl` sets
/// them.
async fn start_with(
    release: ReleaseMode,
    faults: Faults,
    pacing_ms: u64,
    config: Config,
    tripod_on_connect: bool,
) -> Harness {
    let link = SimLink::new(Model::R2D2, SimConfig::default(), faults);
    let probe = link.probe();
    let setup = SetupOptions {
        tripod: tripod_on_connect,
        ..SetupOptions::default()
    };
    let session = session::start(
        Box::new(link),
        SessionConfig {
            pacing: Duration::from_millis(pacing_ms),
            setup: connect_setup(Model::R2D2, &setup),
            ..SessionConfig::default()
        },
    );
    let drives = Arc::new(Mutex::new(Vec::new()));
    let start = Instant::now();
    {
        let mut log = session.subscribe_log();
        let drives = drives.clone();
        tokio::spawn(async move {
            while let Ok(LogEntry { dir, item, .. }) = log.recv().await {
                if let (
                    Direction::Out,
                    LogItem::Packet {
                        packet: droidctl::family::Packet::V2(p),
                        ..
                    },
                ) = (dir, item)
                    && (p.did, p.cid) == (0x16, 0x07)
                {
                    let Packet { data, .. } = p;
                    drives.lock().unwrap().push((
                        start.elapsed(),
                        data[0],
                        u16::from_be_bytes([data[1], data[2]]),
                    ));
                }
            }
        });
    }
    let (term, term_rx) = mpsc::channel(64);
    let (pad, pad_rx) = mpsc::channel(64);
    let (quit, quit_rx) = mpsc::channel(4);
    let opts = AppOptions {
        config,
        model: Model::R2D2,
        droid_name: "R2-D2 (simulated)".into(),
        log_path: None,
        release,
        tripod_on_connect,
        samples: None,
        remember: None,
    };
    let s = session.clone();
    let app = tokio::spawn(async move {
        let mut terminal = Terminal::new(TestBackend::new(80, 24)).unwrap();
        let inputs = AppInputs {
            term: term_rx,
            pad: pad_rx,
            quit: quit_rx,
        };
        run::run(&mut terminal, s, opts, inputs, no_draw)
            .await
            .unwrap()
    });
    // Let it connect and stand up in tripod (the setup asks for it; a stance takes ~2 s).
    sleep(Duration::from_secs(3)).await;
    Harness {
        term,
        pad,
        quit,
        session,
        probe,
        drives,
        app,
        start,
    }
}

fn key(c: char) -> Key {
    Key::ch(c)
}

impl Harness {
    async fn press(&self, k: Key) {
        self.term
            .send(TermEvent::Key {
                key: k,
                kind: KeyKind::Press,
            })
            .await
            .unwrap();
    }
    async fn release(&self, k: Key) {
        self.term
            .send(TermEvent::Key {
                key: k,
                kind: KeyKind::Release,
            })
            .await
            .unwrap();
    }
    fn now(&self) -> Duration {
        self.start.elapsed()
    }
    fn drives_between(&self, from: Duration, to: Duration) -> Vec<(Duration, u8, u16)> {
        self.drives
            .lock()
            .unwrap()
            .iter()
            .copied()
            .filter(|d| d.0 >= from && d.0 < to)
            .collect()
    }
    fn last_drive(&self) -> Option<(Duration, u8, u16)> {
        self.drives.lock().unwrap().last().copied()
    }
}

const REPORTED: ReleaseMode = ReleaseMode::Reported;

#[tokio::test(start_paused = true)]
async fn holding_forward_drives_at_the_tick_rate_and_release_stops() {
    let h = start(REPORTED, Faults::none(), 5).await;
    let t0 = h.now();
    h.press(key('w')).await;
    sleep(Duration::from_secs(2)).await;
    let sent = h.drives_between(t0, h.now());
    // 10 Hz for 2 s, each with the cruise speed.
    assert!(
        (19..=22).contains(&sent.len()),
        "{} drives: {sent:?}",
        sent.len()
    );
    assert!(sent.iter().all(|d| d.1 == 100));
    assert!(h.probe.state().y_cm > 30.0, "{:?}", h.probe.state());
    let released = h.now();
    h.release(key('w')).await;
    sleep(Duration::from_millis(50)).await;
    let after = h.drives_between(released, h.now());
    assert_eq!(
        after.iter().map(|d| d.1).collect::<Vec<_>>(),
        vec![0],
        "stop sent at once on release"
    );
    sleep(Duration::from_secs(1)).await;
    assert!(
        h.drives_between(released + Duration::from_millis(50), h.now())
            .is_empty(),
        "nothing while idle"
    );
    h.quit.send("test".into()).await.unwrap();
    let exit = h.app.await.unwrap();
    assert_eq!(exit.reason, ExitReason::Signal("test".into()));
}

#[tokio::test(start_paused = true)]
async fn emulated_release_stops_when_repeats_stop() {
    let mode = ReleaseMode::Emulated {
        first: Duration::from_millis(650),
        repeat: Duration::from_millis(120),
    };
    let h = start(mode, Faults::none(), 5).await;
    // One tap, no repeats: held until the first timeout, then a stop.
    let t0 = h.now();
    h.press(key('w')).await;
    sleep(Duration::from_millis(600)).await;
    assert!(
        h.last_drive().unwrap().1 > 0,
        "still driving before the first timeout"
    );
    sleep(Duration::from_millis(100)).await;
    let stop = h.last_drive().unwrap();
    assert_eq!(stop.1, 0);
    assert!(
        stop.0 - t0 >= Duration::from_millis(650) && stop.0 - t0 < Duration::from_millis(700),
        "{:?}",
        stop.0 - t0
    );
    // Auto-repeat every 33 ms keeps it going; when repeats stop it stops within ~120 ms.
    let t1 = h.now();
    h.press(key('w')).await;
    sleep(Duration::from_millis(500)).await;
    for _ in 0..45 {
        h.press(key('w')).await;
        sleep(Duration::from_millis(33)).await;
    }
    let last_repeat = h.now();
    assert!(h.drives_between(t1, last_repeat).iter().all(|d| d.1 > 0));
    sleep(Duration::from_millis(200)).await;
    let stop = h.last_drive().unwrap();
    assert_eq!(stop.1, 0);
    assert!(
        stop.0 - last_repeat <= Duration::from_millis(130),
        "{:?}",
        stop.0 - last_repeat
    );
    h.quit.send("test".into()).await.unwrap();
    h.app.await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn focus_loss_releases_every_key() {
    let h = start(REPORTED, Faults::none(), 5).await;
    h.press(key('w')).await;
    h.press(key('d')).await;
    sleep(Duration::from_millis(500)).await;
    assert!(h.last_drive().unwrap().1 > 0);
    let lost = h.now();
    h.term.send(TermEvent::FocusLost).await.unwrap();
    sleep(Duration::from_millis(20)).await;
    let stop = h.last_drive().unwrap();
    assert_eq!(stop.1, 0);
    assert!(stop.0 - lost < Duration::from_millis(20));
    sleep(Duration::from_secs(1)).await;
    assert_eq!(
        h.drives_between(lost + Duration::from_millis(20), h.now())
            .len(),
        0
    );
    h.quit.send("test".into()).await.unwrap();
    h.app.await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn estop_is_immediate_and_latched_while_held() {
    // Default R2 pacing (120 ms): the stop must still jump ahead of everything.
    let h = start(REPORTED, Faults::none(), 120).await;
    h.press(key('w')).await;
    sleep(Duration::from_secs(1)).await;
    let t = h.now();
    h.press(Key::plain(KeyCode::Space)).await;
    sleep(Duration::from_millis(130)).await;
    let after = h.drives_between(t, h.now());
    assert_eq!(after.first().map(|d| d.1), Some(0), "{after:?}");
    // Held: forward is still held but nothing drives.
    sleep(Duration::from_secs(1)).await;
    assert!(h.drives_between(t, h.now()).iter().all(|d| d.1 == 0));
    let v = h.probe.state().velocity_cm_s;
    assert!(v.abs() < 1.0, "{v}");
    // Released: forward still held, driving resumes.
    let r = h.now();
    h.release(Key::plain(KeyCode::Space)).await;
    sleep(Duration::from_millis(500)).await;
    assert!(h.drives_between(r, h.now()).iter().any(|d| d.1 > 0));
    h.quit.send("test".into()).await.unwrap();
    h.app.await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn quitting_sends_a_stop_first() {
    let mut h = start(REPORTED, Faults::none(), 120).await;
    h.press(key('w')).await;
    sleep(Duration::from_secs(1)).await;
    h.press(key('q')).await;
    let exit = (&mut h.app).await.unwrap();
    assert_eq!(exit.reason, ExitReason::Quit);
    assert_eq!(exit.stop.data()[0], 0);
    h.session
        .shutdown(run::exit_commands(Model::R2D2, Some(exit.stop), false))
        .await;
    sleep(Duration::from_millis(10)).await;
    assert_eq!(
        h.last_drive().unwrap().1,
        0,
        "the last command written is a stop"
    );
    sleep(Duration::from_secs(1)).await;
    assert!(h.probe.state().velocity_cm_s.abs() < 1.0);
}

#[tokio::test(start_paused = true)]
async fn gamepad_drives_and_unplug_stops() {
    let h = start(REPORTED, Faults::none(), 5).await;
    h.pad
        .send(PadEvent::Connected("Test Pad".into()))
        .await
        .unwrap();
    h.pad.send(PadEvent::Axis(Axis::LeftX, 1.0)).await.unwrap();
    sleep(Duration::from_millis(500)).await;
    let d = h.last_drive().unwrap();
    assert_eq!(d.2, 90, "stick right = heading 90");
    assert!(d.1 > 100);
    let t = h.now();
    h.pad.send(PadEvent::Disconnected).await.unwrap();
    sleep(Duration::from_millis(20)).await;
    assert_eq!(h.drives_between(t, h.now()).last().map(|d| d.1), Some(0));
    // Stick back in the deadzone works the same.
    h.pad
        .send(PadEvent::Connected("Test Pad".into()))
        .await
        .unwrap();
    h.pad.send(PadEvent::Axis(Axis::LeftY, 1.0)).await.unwrap();
    sleep(Duration::from_millis(300)).await;
    assert!(h.last_drive().unwrap().1 > 0);
    let t = h.now();
    h.pad.send(PadEvent::Axis(Axis::LeftY, 0.05)).await.unwrap();
    sleep(Duration::from_millis(20)).await;
    assert_eq!(h.drives_between(t, h.now()).last().map(|d| d.1), Some(0));
    h.quit.send("test".into()).await.unwrap();
    h.app.await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn link_loss_drops_speed_and_reconnects() {
    let faults = Faults {
        disconnect_at: vec![Duration::from_secs(5)],
        ..Faults::none()
    };
    let h = start(REPORTED, faults, 5).await;
    h.press(key('w')).await;
    let mut states = h.session.watch_state();
    // Wait for the drop.
    tokio::time::timeout(Duration::from_secs(5), async {
        loop {
            states.changed().await.unwrap();
            if matches!(
                *states.borrow(),
                droidctl::session::LinkState::Reconnecting { .. }
            ) {
                break;
            }
        }
    })
    .await
    .unwrap();
    sleep(Duration::from_secs(4)).await;
    assert_eq!(h.session.state(), droidctl::session::LinkState::Connected);
    assert_eq!(h.session.stats().reconnects, 1);
    h.quit.send("test".into()).await.unwrap();
    let exit = h.app.await.unwrap();
    assert_eq!(
        exit.state.droid().link,
        droidctl::session::LinkState::Connected
    );
}

#[tokio::test(start_paused = true)]
async fn quick_taps_of_one_shot_keys_each_count_with_emulated_release() {
    let mode = ReleaseMode::Emulated {
        first: Duration::from_millis(650),
        repeat: Duration::from_millis(120),
    };
    let h = start(mode, Faults::none(), 5).await;
    // `?` opens help, a second tap 100 ms later closes it, then `q` quits.
    h.press(key('?')).await;
    sleep(Duration::from_millis(100)).await;
    h.press(key('?')).await;
    sleep(Duration::from_millis(100)).await;
    h.press(key('q')).await;
    let exit = tokio::time::timeout(Duration::from_secs(2), h.app)
        .await
        .expect("quit")
        .unwrap();
    assert_eq!(exit.reason, ExitReason::Quit);
}

#[tokio::test(start_paused = true)]
async fn start_up_has_no_errors() {
    // The control loop's first drive/dome commands wait for the connect setup, so nothing
    // reaches the droid before its Wake.
    let h = start(REPORTED, Faults::none(), 120).await;
    sleep(Duration::from_secs(2)).await;
    let st = h.session.stats();
    assert_eq!(st.errors, 0, "{st:?}");
    assert_eq!(st.droid_errors, 0);
    h.quit.send("test".into()).await.unwrap();
    h.app.await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn rebound_keys_work_in_every_context_and_show_in_help() {
    let config = Config::parse_merged(
        None,
        "[keys]\nlog = [\"L\"]\n\
         [keys.packet_log]\npause = [\"P\"]\nback = [\"x\"]\n\
         [keys.help_overlay]\nnext_page = [\"n\"]\n",
    )
    .unwrap();
    let h = start_with(REPORTED, Faults::none(), 5, config, true).await;
    // `l` no longer opens the log; `L` does; there the default `p` does nothing, `P` pauses,
    // and `x` goes back to driving.
    for k in ['l', 'L', 'p', 'P', 'x', '?', 'n'] {
        h.press(key(k)).await;
        h.release(key(k)).await;
        sleep(Duration::from_millis(20)).await;
    }
    h.quit.send("test".into()).await.unwrap();
    let exit = h.app.await.unwrap();
    let s = &exit.state;
    assert!(s.log.paused, "P paused the log");
    assert_eq!(s.focus, Focus::Drive, "x went back to driving");
    assert_eq!(s.overlay, Overlay::Help);
    assert_eq!(s.help_page, 1, "n turned the help page");
    let line = |title: &str, action: &str| {
        s.help
            .iter()
            .find(|sec| sec.title == title)
            .and_then(|sec| sec.lines.iter().find(|l| l.action.starts_with(action)))
            .map(|l| l.keys.clone())
    };
    assert_eq!(line("Packet log", "pause").as_deref(), Some("P"));
    assert_eq!(line("Keyboard", "the packet log").as_deref(), Some("L"));
    assert_eq!(line("Help", "next page").as_deref(), Some("n"));
    // Help covers the footer: its border names the stop first.
    assert_eq!(s.help_nav, "Space stop");
    assert_eq!(
        droidctl::app::help::border(&s.keymap, droidctl::app::help::HELP_PAGES),
        "n/PgUp pages"
    );
}

#[tokio::test(start_paused = true)]
async fn tripod_on_connect_is_shown_only_when_the_setup_asks_for_it() {
    use droidctl::protocol::wire::LegState;
    use droidctl::telemetry::Stance;
    for (tripod, expect) in [(true, true), (false, false)] {
        let h = start_with(REPORTED, Faults::none(), 5, Config::defaults(), tripod).await;
        h.quit.send("test".into()).await.unwrap();
        let exit = h.app.await.unwrap();
        let stance = exit.state.droid().telemetry.stance;
        let tripod_shown = matches!(
            stance,
            Stance::Transitioning(LegState::Tripod) | Stance::Tripod
        );
        assert_eq!(
            tripod_shown, expect,
            "tripod_on_connect {tripod}: {stance:?}"
        );
    }
}
