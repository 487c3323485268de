//! Monitoring in the app under paused time (issue 22 points 1, 2, 3, 5): the scope's keys
//! and screen, the streaming and collision palette against a simulated droid (what is sent,
//! the measured rate, collisions still reported), and replay showing the recorded commands
//! and playing the scope.

use droidctl::app::input::{KeyKind, TermEvent};
use droidctl::app::run::{self, AppInputs, AppOptions, Exit, Source};
use droidctl::app::state::{AppState, Overlay};
use droidctl::capture::Capture;
use droidctl::capture::replay::Replay;
use droidctl::config::{Config, Key, KeyCode};
use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::model::Model;
use droidctl::session::{self, Direction, LogItem, SessionConfig};
use droidctl::sim::{Faults, SimConfig, SimLink};
use droidctl::telemetry::history::Channel;
use droidctl::teleop::held::ReleaseMode;
use ratatui::{Terminal, backend::TestBackend};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::sleep;

fn press(k: Key) -> TermEvent {
    TermEvent::Key {
        key: k,
        kind: KeyKind::Press,
    }
}

fn release(k: Key) -> TermEvent {
    TermEvent::Key {
        key: k,
        kind: KeyKind::Release,
    }
}

fn opts(model: Model) -> AppOptions {
    AppOptions {
        config: Config::defaults(),
        model,
        droid_name: "simulated".into(),
        log_path: None,
        release: ReleaseMode::Reported,
        tripod_on_connect: true,
        samples: None,
        remember: None,
    }
}

/// The text of `state` drawn at `w`×`h`.
fn screen(state: &AppState, w: u16, h: u16) -> String {
    let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
    t.draw(|f| droidctl::ui::draw(f, state)).unwrap();
    let buf = t.backend().buffer().clone();
    let mut out = String::new();
    for y in 0..h {
        for x in 0..w {
            out.push_str(buf[(x, y)].symbol());
        }
        out.push('\n');
    }
    out
}

/// The app on a simulated R2-D2; `keys` (at their ms) then quit. How it ended, and the names
/// of the commands written, in order, with their times.
async fn live(keys: Vec<(u64, TermEvent)>) -> (Exit, Vec<(Duration, String)>) {
    live_writing(keys, None).await
}

/// [`live`], writing samples to `samples` (`drive --csv`, `--jsonl`).
async fn live_writing(
    keys: Vec<(u64, TermEvent)>,
    samples: Option<droidctl::mission::csv::SampleFiles>,
) -> (Exit, Vec<(Duration, String)>) {
    let mut o = opts(Model::R2D2);
    o.samples = samples;
    live_opts(keys, o).await
}

/// [`live`] with `o` (R2-D2's).
async fn live_opts(keys: Vec<(u64, TermEvent)>, o: AppOptions) -> (Exit, Vec<(Duration, String)>) {
    let model = Model::R2D2;
    let link = SimLink::new(model, SimConfig::default(), Faults::none());
    let session = session::start(
        Box::new(link),
        SessionConfig {
            pacing: Duration::from_millis(20),
            setup: connect_setup(model, &SetupOptions::default()),
            ..SessionConfig::default()
        },
    );
    let sent = Arc::new(Mutex::new(Vec::new()));
    {
        let mut log = session.subscribe_log();
        let sent = sent.clone();
        let t0 = tokio::time::Instant::now();
        tokio::spawn(async move {
            while let Ok(e) = log.recv().await {
                if let (Direction::Out, LogItem::Packet { explained, .. }) = (e.dir, e.item) {
                    sent.lock().unwrap().push((t0.elapsed(), explained.label));
                }
            }
        });
    }
    let (term_tx, term_rx) = mpsc::channel(64);
    let (_pad_tx, pad_rx) = mpsc::channel(1);
    let (_quit_tx, quit_rx) = mpsc::channel(1);
    let inputs = AppInputs {
        term: term_rx,
        pad: pad_rx,
        quit: quit_rx,
    };
    let driver = async move {
        let start = tokio::time::Instant::now();
        for (at, k) in keys {
            tokio::time::sleep_until(start + Duration::from_millis(at)).await;
            term_tx.send(k).await.unwrap();
        }
        sleep(Duration::from_millis(100)).await;
        term_tx.send(press(Key::ch('q'))).await.unwrap();
    };
    let mut terminal = Terminal::new(TestBackend::new(80, 24)).unwrap();
    let (exit, ()) = tokio::join!(
        run::run(
            &mut terminal,
            session.clone(),
            o,
            inputs,
            droidctl::ui::draw
        ),
        driver
    );
    session.shutdown(Vec::new()).await;
    let sent = sent.lock().unwrap().clone();
    (exit.unwrap(), sent)
}

#[tokio::test(start_paused = true)]
async fn the_scope_shows_chosen_channels_and_its_keys_work() {
    let keys = vec![
        (3000, press(Key::ch('g'))),
        // The channel list: the first channel offered is pitch; switch it on.
        (3100, press(Key::ch('C'))),
        (3200, press(Key::ch('x'))),
        (3300, press(Key::plain(KeyCode::Esc))),
        // Longer window, fixed axes, then pause: the plot stays at 6 s.
        (3400, press(Key::ch('['))),
        (3500, press(Key::ch('f'))),
        (6000, press(Key::ch('p'))),
    ];
    let (exit, _) = live(keys).await;
    let s = &exit.state;
    assert!(s.droid().scope.visible);
    assert_eq!(
        s.droid().scope.channels,
        [Channel::Pitch, Channel::Yaw, Channel::Speed]
    );
    assert_eq!(s.droid().scope.window(), Duration::from_secs(60));
    assert!(!s.droid().scope.autoscale);
    assert!(s.droid().scope.paused_at.is_some());
    assert_eq!(s.overlay, Overlay::None);
    // The droid streamed at 10/s all along, and the scope keeps it.
    let rate = s.droid().telemetry.history.measured_rate(s.now).unwrap();
    assert!((rate - 10.0).abs() < 0.6, "{rate}");
    let text = screen(s, 80, 24);
    for want in [
        "Scope",
        "last 60 s",
        "PAUSED",
        "fixed",
        "pitch (deg)",
        "yaw (deg)",
        "speed (cm/s)",
        "stream 10/s, measured",
    ] {
        assert!(text.contains(want), "{want:?} not on\n{text}");
    }
    // Data is drawn: braille dots in the chart.
    assert!(
        text.chars().any(|c| ('\u{2801}'..='\u{28FF}').contains(&c)),
        "{text}"
    );
    // Larger screens use the room.
    let big = screen(s, 160, 48);
    assert!(big.contains("speed (cm/s)"));
}

#[tokio::test(start_paused = true)]
async fn the_palette_sets_rate_sensors_and_collision_and_collisions_keep_coming() {
    let right = Key::plain(KeyCode::Right);
    let down = Key::plain(KeyCode::Down);
    let toggle = Key::ch('x');
    let mut keys = vec![(3000, press(Key::ch('u')))];
    let mut t = 3000;
    // Each key pressed and let go (the arrows are held keys while driving).
    let mut taps = Vec::new();
    let mut at = |k: Key| {
        t += 50;
        taps.push((t + 20, release(k)));
        (t, press(k))
    };
    // Rate 10 → 50; keep attitude only (rows: rate, attitude, accelerometer, gyro, locator,
    // velocity, head); x threshold down twice (100 → 80).
    keys.push(at(right));
    keys.push(at(right));
    keys.push(at(down));
    for _ in 0..5 {
        keys.push(at(down));
        keys.push(at(toggle));
    }
    keys.push(at(down));
    keys.push(at(down));
    keys.push(at(Key::plain(KeyCode::Left)));
    keys.push(at(Key::plain(KeyCode::Left)));
    keys.push(at(Key::plain(KeyCode::Enter)));
    keys.append(&mut taps);
    keys.sort_by_key(|(t, _)| *t);
    // Then drive east into the wall (2 m away at cruise speed).
    keys.push((4000, press(Key::ch('d'))));
    keys.push((6000, release(Key::ch('d'))));
    keys.push((6100, press(Key::ch('w'))));
    keys.push((11_000, release(Key::ch('w'))));
    let (exit, sent) = live(keys).await;
    let s = &exit.state;
    let plan = s.droid().monitor.plan.clone().unwrap();
    assert_eq!(
        plan.interval_ms,
        20,
        "50/s: {:?} {:?}",
        s.droid().monitor,
        s.hint
    );
    assert_eq!(plan.sensors.to_string(), "attitude");
    assert_eq!(s.droid().monitor.collision.x_threshold, 80);
    // The measured rate follows.
    let r = s.droid().telemetry.history.measured_rate(s.now).unwrap();
    assert!((r - 50.0).abs() < 2.0, "{r}");
    // Streaming went out, then collision detection again, with the new threshold.
    let names: Vec<&str> = sent
        .iter()
        .filter(|(t, _)| *t > Duration::from_secs(3))
        .map(|(_, n)| n.as_str())
        .filter(|n| n.contains("sensor") || n.contains("collision"))
        .collect();
    assert_eq!(
        &names[..5],
        [
            "set-sensor-streaming-mask",
            "set-extended-sensor-streaming-mask",
            "set-sensor-streaming-mask",
            "configure-collision-detection",
            "enable-collision-detected-notify"
        ]
    );
    // Collisions are still reported after the change.
    assert!(s.droid().telemetry.collisions >= 1, "no collision reported");
    let log = format!("{:?}", s.log);
    assert!(
        log.contains("x_threshold") && log.contains("80"),
        "the log shows the command"
    );
}

#[tokio::test(start_paused = true)]
async fn a_capped_request_says_so() {
    // 100/s with every sensor: more than R2-D2's link carries.
    let mut keys = vec![(3000, press(Key::ch('u')))];
    for i in 0..6 {
        keys.push((3100 + i * 50, press(Key::plain(KeyCode::Right))));
    }
    keys.push((3500, press(Key::plain(KeyCode::Enter))));
    let (exit, _) = live(keys).await;
    let s = &exit.state;
    assert_eq!(s.droid().monitor.request.rate_hz, 100);
    assert_eq!(
        s.droid().monitor.plan.as_ref().unwrap().interval_ms,
        100,
        "capped at 10/s"
    );
    let hint = s.hint.as_ref().map(|h| h.text.clone()).unwrap_or_default();
    assert!(hint.contains("capped at 10/s"), "{hint}");
}

#[tokio::test(start_paused = true)]
async fn the_app_writes_every_streamed_sample_as_csv_and_json_lines() {
    let dir = std::env::temp_dir().join(format!("droidctl-monapp-csv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (csv, jsonl) = (dir.join("t.csv"), dir.join("t.jsonl"));
    let files =
        droidctl::mission::csv::SampleFiles::create(Some(&csv), Some(&jsonl), false).unwrap();
    let (exit, _) = live_writing(vec![(5000, press(Key::ch('?')))], Some(files)).await;
    let (csv, jsonl) = (
        std::fs::read_to_string(&csv).unwrap(),
        std::fs::read_to_string(&jsonl).unwrap(),
    );
    let _ = std::fs::remove_dir_all(&dir);
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    // One row per sample the droid streamed (10/s for about 5 s), as many JSON objects.
    let samples = exit.state.droid().telemetry.samples as usize;
    assert!(samples >= 40, "{samples}");
    assert_eq!(rows.len(), samples);
    assert_eq!(jsonl.lines().count(), samples);
    assert!(csv.starts_with("t_s,x_cm,y_cm,speed_cm_s"));
    let yaw = csv
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "yaw_deg")
        .unwrap();
    assert!(
        rows.iter()
            .all(|r| r.split(',').nth(yaw).unwrap().parse::<f32>().is_ok())
    );
}

#[test]
fn robi_scopes_its_wheels_and_poti() {
    let s = AppState::new(Model::Robi42, "Robi 42".into());
    assert_eq!(
        s.droid().scope.channels,
        [Channel::MotorLeft, Channel::MotorRight]
    );
    assert!(Channel::Poti.reported_by(true) && !Channel::Poti.reported_by(false));
    assert_eq!(s.droid().monitor.requested(), "own rate");
}

const MISSION: &str = "stance tripod\ndrive 120 90 for 3s\nhead 30\nled front 0 0 255\nwait 2s\n";

#[tokio::test(start_paused = true)]
async fn replay_shows_the_recorded_commands_and_plays_the_scope() {
    // Record a mission on the simulator.
    let dir = std::env::temp_dir().join(format!("droidctl-monapp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (script, cap) = (dir.join("m.txt"), dir.join("m.capture"));
    std::fs::write(&script, MISSION).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["run", script.to_str().unwrap(), "--sim", "--record"])
        .arg(&cap)
        .env("DROIDCTL_LOG_FILE", dir.join("log"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let capture = Capture::load(&cap).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    // Play it: during the drive, and after the LED line.
    let mission_start = capture
        .events
        .iter()
        .find_map(|t| match &t.event {
            droidctl::capture::Event::Mark(m) if m.starts_with("step 2 ") => Some(t.at),
            _ => None,
        })
        .unwrap();
    let during = mission_start + Duration::from_millis(1500);
    let (mid, _) = replay_until(&capture, during, vec![(100, press(Key::ch('g')))]).await;
    let c = &mid.state.droid().control;
    assert_eq!((c.speed, c.heading.degrees(), c.reverse), (120, 90, false));
    assert!(!c.deadman);
    assert!(mid.state.droid().scope.visible);
    assert!(
        !mid.state.droid().telemetry.history.is_empty(),
        "the scope plays"
    );
    let text = screen(&mid.state, 80, 24);
    assert!(
        text.contains("yaw (deg)") && text.contains("Scope"),
        "{text}"
    );
    let (end, _) = replay_until(&capture, capture.duration(), Vec::new()).await;
    let c = &end.state.droid().control;
    assert_eq!(c.speed, 0, "the drive ended with a stop");
    assert_eq!(c.head_target, 30.0);
    assert_eq!(end.state.droid().leds.main, Some([0, 0, 255]));
    let text = screen(&end.state, 80, 24);
    assert!(text.contains("90°"), "the commanded heading: {text}");
}

/// Replay `capture` until capture time `until` (plus a little), pressing `keys`.
async fn replay_until(
    capture: &Capture,
    until: Duration,
    keys: Vec<(u64, TermEvent)>,
) -> (Exit, ()) {
    let (term_tx, term_rx) = mpsc::channel(64);
    let (_pad_tx, pad_rx) = mpsc::channel(1);
    let (_quit_tx, quit_rx) = mpsc::channel(1);
    let inputs = AppInputs {
        term: term_rx,
        pad: pad_rx,
        quit: quit_rx,
    };
    let replay = Replay::new(capture.clone(), Model::R2D2);
    let mut terminal = Terminal::new(TestBackend::new(80, 24)).unwrap();
    let driver = async move {
        let start = tokio::time::Instant::now();
        for (at, k) in keys {
            tokio::time::sleep_until(start + Duration::from_millis(at)).await;
            term_tx.send(k).await.unwrap();
        }
        tokio::time::sleep_until(start + until + Duration::from_millis(200)).await;
        term_tx.send(press(Key::ch('q'))).await.unwrap();
    };
    let source = Source::Replay(Box::new(replay), "m.capture".into());
    let mut o = opts(Model::R2D2);
    o.tripod_on_connect = false;
    let (exit, ()) = tokio::join!(
        run::run(&mut terminal, source, o, inputs, droidctl::ui::draw),
        driver
    );
    (exit.unwrap(), ())
}

/// Issue 30 point 4: cruise speed, the scope's channels and window, the streaming rate, the
/// log filter are remembered per model in the state directory and restored at the next
/// launch; R forgets them; a hostile file is a visible warning, never a panic.
#[tokio::test(start_paused = true)]
async fn settings_are_remembered_per_model_and_forgotten_with_r() {
    let dir = std::env::temp_dir().join(format!("droidctl-remember-app-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let with_dir = || {
        let mut o = opts(Model::R2D2);
        o.remember = Some(dir.clone());
        o
    };
    // First launch: cruise up twice, the scope with a longer window, pitch on, 20/s.
    let keys = vec![
        (3000, press(Key::ch('+'))),
        (3100, press(Key::ch('+'))),
        (3200, press(Key::ch('g'))),
        (3300, press(Key::ch('['))),
        (3400, press(Key::ch('C'))),
        (3500, press(Key::ch('x'))),
        (3600, press(Key::plain(KeyCode::Esc))),
        (3700, press(Key::ch('g'))),
        (3800, press(Key::ch('u'))),
        (3900, press(Key::plain(KeyCode::Right))),
        (4000, press(Key::plain(KeyCode::Enter))),
        (4100, press(Key::ch('l'))),
        (4200, press(Key::ch('f'))),
        (4300, press(Key::ch('i'))),
        (4400, press(Key::ch('n'))),
        (4500, press(Key::plain(KeyCode::Enter))),
        (4600, press(Key::plain(KeyCode::Esc))),
    ];
    let (first, _) = live_opts(keys, with_dir()).await;
    let d = first.state.droid();
    let (cruise, window, channels, rate) = (
        d.control.cruise,
        d.scope.window,
        d.scope.channels.clone(),
        d.monitor.request.rate_hz,
    );
    assert!(cruise > 100, "{cruise}");
    assert_ne!(rate, 10, "the rate changed");
    let file = std::fs::read_to_string(dir.join("settings-r2d2.toml")).expect("remembered");
    assert!(file.contains(&format!("cruise = {cruise}")), "{file}");
    // The next launch starts where the first ended (the rate is asked for once connected).
    let esc = || press(Key::plain(KeyCode::Esc));
    let (second, sent) = live_opts(vec![(2000, press(Key::ch('l')))], with_dir()).await;
    let d = second.state.droid();
    // Issue 39 point 9: what is remembered over the configuration is said at start.
    let hint = second
        .state
        .hint
        .as_ref()
        .map(|h| h.text.clone())
        .unwrap_or_default();
    assert!(
        hint.contains(&format!(
            "remembered for R2-D2 (R forgets): cruise {cruise} (config 100)"
        )),
        "{hint}"
    );
    assert_eq!(d.control.cruise, cruise);
    assert_eq!(
        (d.scope.window, d.scope.channels.clone()),
        (window, channels)
    );
    assert_eq!(d.monitor.request.rate_hz, rate);
    assert!(
        sent.iter().any(|(_, n)| n.contains("streaming")),
        "{sent:?}"
    );
    assert_eq!(second.state.log.filter_input(), "in");
    // R asks first: R, another key (a no), R again (asks again) forgets nothing.
    let r = || press(Key::ch('R'));
    let (asked, _) = live_opts(vec![(3000, r()), (3100, esc()), (3200, r())], with_dir()).await;
    assert_eq!(asked.state.droid().control.cruise, cruise);
    let hint = asked.state.hint.as_ref().map(|h| h.text.clone());
    assert!(
        hint.as_deref().is_some_and(
            |h| h.contains("forget R2-D2's remembered settings") && h.contains("R again: yes")
        ),
        "{hint:?}"
    );
    // R twice: back to the configuration's, the file gone.
    let (third, _) = live_opts(vec![(3000, r()), (3100, r())], with_dir()).await;
    let d = third.state.droid();
    assert_eq!(d.control.cruise, 100);
    assert_eq!(d.monitor.request.rate_hz, 10);
    assert_eq!(third.state.log.filter_input(), "");
    // (At exit the defaults are remembered again: the file says the configuration's.)
    let file = std::fs::read_to_string(dir.join("settings-r2d2.toml")).expect("rewritten");
    assert!(file.contains("cruise = 100"), "{file}");
    // A hostile file: a warning on screen, the defaults, no panic.
    std::fs::write(dir.join("settings-r2d2.toml"), "cruise = [[[\u{0}").unwrap();
    let (fourth, _) = live_opts(vec![], with_dir()).await;
    let d = fourth.state.droid();
    assert_eq!(d.control.cruise, 100);
    let hint = fourth
        .state
        .hint
        .as_ref()
        .map(|h| h.text.clone())
        .unwrap_or_default();
    assert!(hint.contains("settings-r2d2.toml"), "{hint}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 30 point 3: Enter in the packet log opens its newest line in full; `/` searches,
/// `n` and `N` go through the matches; Esc closes. Nothing drives meanwhile.
#[tokio::test(start_paused = true)]
async fn enter_opens_a_packet_in_full_with_search() {
    use droidctl::app::state::Overlay;
    let mut keys = vec![
        (3000, press(Key::ch('l'))),
        (3100, press(Key::ch('p'))),
        (3200, press(Key::plain(KeyCode::Enter))),
        (3300, press(Key::ch('/'))),
    ];
    for (i, c) in "seq".chars().enumerate() {
        keys.push((3400 + i as u64 * 10, press(Key::ch(c))));
    }
    keys.push((3500, press(Key::plain(KeyCode::Enter))));
    keys.push((3600, press(Key::ch('n'))));
    let (exit, _) = live(keys).await;
    let Overlay::Packet {
        line,
        search,
        typing,
        scroll,
        ..
    } = &exit.state.overlay
    else {
        panic!("the packet in full: {:?}", exit.state.overlay)
    };
    assert_eq!((search.as_str(), *typing), ("seq", false));
    let rows = droidctl::app::detail::rows(line);
    assert!(
        rows[*scroll].label.contains("seq") || rows[*scroll].value.contains("seq"),
        "{:?}",
        rows[*scroll]
    );
    assert!(rows.iter().any(|r| r.label == "hex" && !r.value.is_empty()));
}

/// Issue 39 point 11: the packet log has a cursor (`k`/`j` as well as the arrows) and Enter
/// opens the selected line, not only the newest.
#[tokio::test(start_paused = true)]
async fn the_log_cursor_chooses_the_line_enter_opens() {
    use droidctl::app::state::Overlay;
    let keys = vec![
        (3000, press(Key::ch('l'))),
        (3100, press(Key::ch('p'))),
        (3200, press(Key::ch('k'))),
        (3300, press(Key::ch('k'))),
        (3400, press(Key::plain(KeyCode::Up))),
        (3500, press(Key::ch('j'))),
        (3600, press(Key::plain(KeyCode::Enter))),
    ];
    let (exit, _) = live(keys).await;
    let Overlay::Packet { line, .. } = &exit.state.overlay else {
        panic!("the packet in full: {:?}", exit.state.overlay)
    };
    let log = &exit.state.log;
    assert_eq!(log.cursor, 2, "three up, one down");
    let newest_shown = log.filtered().rev().nth(log.scroll).expect("lines");
    let selected = log.filtered().rev().nth(log.scroll + 2).expect("lines");
    assert_eq!(**line, *selected);
    assert_ne!(**line, *newest_shown);
}

/// Issue 39 point 11: the log filter applies as it is typed; Esc puts back the one before.
#[tokio::test(start_paused = true)]
async fn the_log_filter_applies_as_it_is_typed() {
    let mut keys = vec![(3000, press(Key::ch('l'))), (3100, press(Key::ch('/')))];
    // (The harness ends the run with `q`, typed here: "out q" is "out" and the text "q".)
    for (i, c) in "out ".chars().enumerate() {
        keys.push((3200 + i as u64 * 10, press(Key::ch(c))));
    }
    let (typing, _) = live(keys.clone()).await;
    assert!(matches!(
        typing.state.overlay,
        droidctl::app::state::Overlay::Filter { .. }
    ));
    assert_eq!(
        typing.state.log.filter.dir,
        Some(droidctl::session::Direction::Out),
        "applied before Enter"
    );
    keys.push((3400, press(Key::plain(KeyCode::Esc))));
    let (cancelled, _) = live(keys).await;
    assert_eq!(
        cancelled.state.log.filter_input(),
        "",
        "Esc: the filter before"
    );
}
