//! Four virtual droids on the virtual BlueZ (`droidctl sim --bluez r2d2 bb8 bb9e robi`), driven
//! at once by the app through btleplug, as `droidctl --name A --name B --name C --name D`
//! does: the time to connect all four, the control loop's jitter per droid (p50/p99 of the
//! gap between consecutive drive writes while all four are mirrored and rolling), the CPU
//! of the app (this process: app, sessions, btleplug; the simulator is another process),
//! and the time from one emergency-stop key press to the stop written to the last of the
//! four.
//!
//! `cargo bench --bench fleet` (Linux, needs `dbus-daemon`); `FLEET_BENCH_SECS` sets how long
//! the four roll (default 20). Wall-clock figures on a shared machine: run it a few times.

#[cfg(not(target_os = "linux"))]
fn main() {
    eprintln!("the fleet benchmark needs the virtual BlueZ, which runs on Linux only");
}

#[cfg(target_os = "linux")]
fn main() {
    linux::main();
}

#[cfg(target_os = "linux")]
#[path = "common/stats.rs"]
mod stats;

#[cfg(target_os = "linux")]
mod linux {
    use droidctl::app::input::{KeyKind, TermEvent};
    use droidctl::app::run::{self, AppInputs, AppOptions};
    use droidctl::cli::connect::BleArgs;
    use droidctl::config::{Config, Key, KeyCode};
    use droidctl::fleet::Fleet;
    use droidctl::session::{Direction, LinkState, LogItem};
    use droidctl::teleop::held::ReleaseMode;
    use ratatui::{Terminal, backend::TestBackend};
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    use std::sync::{Arc, Mutex};
    use std::time::Duration;
    use tokio::sync::mpsc;
    use tokio::time::{Instant, sleep};

    use droidctl::family::drive_speed;

    /// Each droid's drive writes: when (as the session logged them), and the speed.
    type Writes = Arc<Mutex<Vec<Vec<(Instant, u8)>>>>;

    use super::stats::{clock_ticks_per_s, cpu_ticks, percentile};

    pub fn main() {
        let secs: u64 = std::env::var("FLEET_BENCH_SECS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(20);
        let dir = std::env::temp_dir().join(format!("droidctl-fleet-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a scratch directory");
        let mut sim = Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .args(["sim", "--bluez", "r2d2", "bb8", "bb9e", "robi"])
            .env("DROIDCTL_LOG_FILE", dir.join("sim.log"))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start droidctl sim --bluez (is dbus-daemon installed?)");
        let mut out = BufReader::new(sim.stdout.take().expect("stdout"));
        let mut export = String::new();
        out.read_line(&mut export).expect("the export line");
        let address = export
            .trim()
            .strip_prefix("DBUS_SYSTEM_BUS_ADDRESS=")
            .expect("DBUS_SYSTEM_BUS_ADDRESS=…")
            .to_string();
        let mut names = Vec::new();
        for line in BufReader::new(sim.stderr.take().expect("stderr")).lines() {
            let line = line.expect("a line");
            if line.contains("serving on") {
                break;
            }
            if let Some(rest) = line.strip_prefix("droidctl sim: ")
                && let Some((name, _)) = rest.split_once(" (")
                && rest.contains(") at ")
            {
                names.push(name.to_string());
            }
        }
        assert_eq!(names.len(), 4, "four droids served: {names:?}");
        // SAFETY: set before any thread of ours reads the environment (the runtime starts
        // below).
        unsafe {
            std::env::set_var("DBUS_SYSTEM_BUS_ADDRESS", &address);
            std::env::set_var("DROIDCTL_CONFIG", dir.join("config.toml"));
        }
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .expect("a runtime");
        rt.block_on(bench(names, secs));
        let _ = Command::new("kill")
            .args(["-TERM", &sim.id().to_string()])
            .status();
        let _ = sim.wait();
        let _ = std::fs::remove_dir_all(&dir);
    }

    async fn bench(names: Vec<String>, secs: u64) {
        let config = Config::defaults();
        let ble = BleArgs {
            name: names.clone(),
            scan_timeout: 10,
            ..BleArgs::default()
        };
        let t0 = Instant::now();
        let found = droidctl::cli::fleet::find_all(&[], &ble, &config)
            .await
            .unwrap_or_else(|e| panic!("{}", e.message));
        let scanned = t0.elapsed();
        let specs = found
            .into_iter()
            .map(|f| {
                let c = droidctl::cli::fleet::session_config(f.model, &config, true);
                f.into_spec(c)
            })
            .collect();
        let t1 = Instant::now();
        let fleet = Fleet::start(specs);
        let writes: Writes = Arc::new(Mutex::new(vec![Vec::new(); fleet.len()]));
        for (i, m) in fleet.members().iter().enumerate() {
            let mut log = m.session.subscribe_log();
            let writes = writes.clone();
            tokio::spawn(async move {
                while let Ok(e) = log.recv().await {
                    if e.dir == Direction::Out
                        && let LogItem::Packet { packet, .. } = &e.item
                        && let Some(speed) = drive_speed(packet)
                    {
                        writes.lock().unwrap()[i].push((Instant::now(), speed));
                    }
                }
            });
        }
        let mut connected = Vec::new();
        for m in fleet.members() {
            let mut st = m.session.watch_state();
            while *st.borrow_and_update() != LinkState::Connected {
                st.changed().await.expect("the session runs");
            }
            connected.push(t1.elapsed());
        }
        let all_connected = connected.iter().max().copied().unwrap_or_default();

        // The app, drawing every frame into a 160×48 screen.
        let (term, term_rx) = mpsc::channel(64);
        let (_pad, pad_rx) = mpsc::channel(4);
        let (_quit, quit_rx) = mpsc::channel(4);
        let opts = AppOptions {
            config,
            model: fleet.members()[0].model,
            droid_name: String::new(),
            log_path: None,
            release: ReleaseMode::Reported,
            tripod_on_connect: true,
            samples: None,
            remember: None,
        };
        let f = fleet.clone();
        let app = tokio::spawn(async move {
            let _keep = (_pad, _quit);
            let mut terminal = Terminal::new(TestBackend::new(160, 48)).expect("a terminal");
            let inputs = AppInputs {
                term: term_rx,
                pad: pad_rx,
                quit: quit_rx,
            };
            run::run(&mut terminal, f, opts, inputs, droidctl::ui::draw).await
        });
        let key = |key: Key, kind: KeyKind| TermEvent::Key { key, kind };
        // R2 stands up on three legs (about 2 s) before it rolls.
        sleep(Duration::from_secs(3)).await;
        term.send(key(Key::ch('y'), KeyKind::Press)).await.ok();
        term.send(key(Key::ch('y'), KeyKind::Release)).await.ok();
        for _ in 0..4 {
            term.send(key(Key::ch('-'), KeyKind::Press)).await.ok();
        }
        term.send(key(Key::ch('w'), KeyKind::Press)).await.ok();
        // Measure once the control loop runs steadily.
        sleep(Duration::from_secs(1)).await;
        let (c0, w0) = (cpu_ticks(), Instant::now());
        sleep(Duration::from_secs(secs)).await;
        let (c1, w1) = (cpu_ticks(), Instant::now());
        let cpu = (c1 - c0) as f64 / clock_ticks_per_s() / (w1 - w0).as_secs_f64() * 100.0;

        // One e-stop press; the stop written to each droid.
        let pressed = Instant::now();
        term.send(key(Key::plain(KeyCode::Space), KeyKind::Press))
            .await
            .ok();
        let deadline = pressed + Duration::from_secs(5);
        let stops = loop {
            let w = writes.lock().unwrap().clone();
            let stops: Vec<Option<Duration>> = w
                .iter()
                .map(|d| {
                    d.iter()
                        .find(|(t, s)| *t >= pressed && *s == 0)
                        .map(|(t, _)| *t - pressed)
                })
                .collect();
            if stops.iter().all(Option::is_some) || Instant::now() > deadline {
                break stops;
            }
            sleep(Duration::from_millis(1)).await;
        };
        term.send(key(Key::ch('q'), KeyKind::Press)).await.ok();
        let exit = app.await.expect("the app ran").expect("the app ended well");
        fleet.shutdown_all(|i| vec![exit.stops[i].clone()]).await;

        println!(
            "fleet of 4 on the virtual BlueZ: scan {:.0} ms; all four connected (handshake and \
             setup sent) {:.0} ms after the sessions started; each: {}",
            scanned.as_secs_f64() * 1000.0,
            all_connected.as_secs_f64() * 1000.0,
            connected
                .iter()
                .map(|d| format!("{:.0} ms", d.as_secs_f64() * 1000.0))
                .collect::<Vec<_>>()
                .join(", ")
        );
        println!("app CPU while the four roll mirrored ({secs} s): {cpu:.2} % of one core");
        println!(
            "{:<10} {:>8} {:>10} {:>10} {:>10}",
            "droid", "writes", "gap p50", "gap p99", "gap max"
        );
        let w = writes.lock().unwrap().clone();
        for (m, d) in fleet.members().iter().zip(&w) {
            let times: Vec<Instant> = d
                .iter()
                .filter(|(t, s)| *t >= w0 && *t <= w1 && *s > 0)
                .map(|(t, _)| *t)
                .collect();
            let mut gaps: Vec<f64> = times
                .windows(2)
                .map(|p| (p[1] - p[0]).as_secs_f64() * 1000.0)
                .collect();
            gaps.sort_by(|a, b| a.total_cmp(b));
            println!(
                "{:<10} {:>8} {:>8.1} ms {:>7.1} ms {:>7.1} ms",
                m.name,
                times.len(),
                percentile(&gaps, 0.5),
                percentile(&gaps, 0.99),
                gaps.last().copied().unwrap_or(f64::NAN)
            );
        }
        let shown: Vec<String> = stops
            .iter()
            .map(|s| match s {
                Some(d) => format!("{:.1} ms", d.as_secs_f64() * 1000.0),
                None => "none within 5 s".into(),
            })
            .collect();
        let last = stops.iter().flatten().max().copied();
        println!(
            "e-stop key press to the stop written: {} (last of the four: {})",
            shown.join(", "),
            last.map(|d| format!("{:.1} ms", d.as_secs_f64() * 1000.0))
                .unwrap_or_else(|| "missing".into())
        );
    }
}
