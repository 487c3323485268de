//! Input-to-link latency of the control loop, measured as a person drives: a key press (drive
//! forward), its release (the deadman stop), the emergency stop (Space while driving) and a
//! gamepad stick pushed forward (and let go), each timed from the moment the app receives the
//! input to the moment the link has taken the bytes of the drive command it causes (the write
//! returned). The app runs whole (`droidctl::app::run::run` with the default configuration,
//! the real UI drawn into a 160×48 test terminal, battery polling and sensor streaming on) on
//! a real-time two-worker runtime as `droidctl` does, over two links:
//!
//! - `sim`: the in-process simulated R2-D2 (`--sim`);
//! - `bluez`: btleplug on the virtual BlueZ (`sim --bluez` in this process, on a private
//!   `dbus-daemon`; Linux only): D-Bus, BlueZ's GATT calls, the droid behind them;
//! - `serial`: an RVR on a serial line (issue 41; Linux and macOS): `sim --serial rvr`'s
//!   server on a new pseudo-terminal (on a thread of its own) and the app on `--serial
//!   PATH`'s link, the write timed to its return from the port. The single-droid inputs
//!   only (RVR has no fleet case here).
//!
//! Then the emergency stop of a fleet (issue 26): four droids (R2-D2, BB-8, Robi 42, BB-9E)
//! driven by `droidctl::app::run::run` on a fleet as `droidctl --sim r2d2,bb8,robi,bb9e` or
//! `--name … ×4` does, the first chosen and driving, the other three idle (`fleet idle`) or
//! driven too in mirror mode (`fleet mirrored`); Space timed to the stop taken by each
//! droid's link, the last of the four (BB-9E, whose stop the app writes last) reported beside
//! the chosen one. For every emergency stop the time is split where it goes: the key press to
//! the link's write of the stop being called (the app's event loop, the session task waking,
//! the rest of a half-written packet) and the write itself (the link: btleplug, D-Bus, BlueZ,
//! and any pacing inside the link).
//!
//! Between inputs it waits a random 0–250 ms, so inputs land anywhere in the 100 ms control
//! tick and the 120 ms pacing slot. Prints p50, p99 and the maximum per input.
//!
//!     cargo bench --bench latency                  # both links, 100 of each input
//!     cargo bench --bench latency -- --reps 300 --only sim
//!     cargo bench --bench latency -- --reps 50 --part fleet   # the fleet's e-stop only
//!     cargo bench --bench latency -- --reps 200 --only serial  # RVR on a serial line

use droidctl::app::input::{KeyKind, TermEvent};
use droidctl::app::run::{self, AppInputs, AppOptions};
use droidctl::cli::fleet::Found;
use droidctl::config::{Config, Key};
use droidctl::family::{Found as Decoded, Reader, Side, drive_speed};
use droidctl::fleet::Fleet;
use droidctl::gatt::Endpoint;
use droidctl::link::{Connection, Link, LinkError, LinkWriter};
use droidctl::model::Model;
use droidctl::rng::Rng;
use droidctl::session::LinkState;
use droidctl::teleop::gamepad::{Axis, PadEvent};
use droidctl::teleop::held::ReleaseMode;
use futures_util::future::BoxFuture;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::{mpsc, watch};
use tokio::time::{Instant, sleep};

/// The fleet: the first is chosen and driven, the last is the one whose stop is written last.
const FLEET: [Model; 4] = [Model::R2D2, Model::BB8, Model::Robi42, Model::BB9E];

/// A drive command written to the link: when its write was called and when it returned (for
/// a packet written in several chunks, its last chunk's), and its speed.
#[derive(Debug, Clone, Copy)]
struct Drive {
    called: Instant,
    at: Instant,
    speed: u8,
}

/// One droid's drive commands as its link took them (read back with the droid's family).
struct Recorded {
    reader: Box<dyn Reader>,
    drives: Vec<Drive>,
}

type Rec = Arc<Mutex<Recorded>>;

/// A link that notes when each drive command's last byte was taken.
struct Timed {
    inner: Box<dyn Link>,
    rec: Rec,
    written: Arc<watch::Sender<usize>>,
}

struct TimedWriter {
    inner: Box<dyn LinkWriter>,
    rec: Rec,
    written: Arc<watch::Sender<usize>>,
}

/// `link` to `model`, timed; every write of a drive bumps `written`.
fn timed(
    link: Box<dyn Link>,
    model: Model,
    written: &Arc<watch::Sender<usize>>,
) -> (Box<dyn Link>, Rec) {
    let rec = Arc::new(Mutex::new(Recorded {
        reader: droidctl::family::for_model(model).side_reader(Side::Host, false),
        drives: Vec::new(),
    }));
    let link = Timed {
        inner: link,
        rec: rec.clone(),
        written: written.clone(),
    };
    (Box::new(link), rec)
}

impl TimedWriter {
    fn note(&self, to: Endpoint, chunk: &[u8], called: Instant) {
        let at = Instant::now();
        let mut speeds = Vec::new();
        let mut take = |f: &dyn Decoded| -> std::io::Result<()> {
            if let Some(s) = f.packet().as_ref().and_then(drive_speed) {
                speeds.push(s);
            }
            Ok(())
        };
        let mut r = self.rec.lock().unwrap();
        let _ = r.reader.write(to, chunk, Some(&mut take));
        if speeds.is_empty() {
            return;
        }
        for speed in speeds {
            r.drives.push(Drive { called, at, speed });
        }
        self.written.send_modify(|n| *n += 1);
    }
}

impl TimedWriter {
    /// Hand the write to the link (urgent or paced) and note when it returned.
    fn timed_write<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
        urgent: bool,
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        Box::pin(async move {
            let called = Instant::now();
            let r = if urgent {
                self.inner.write_urgent(to, chunk).await
            } else {
                self.inner.write_to(to, chunk).await
            };
            self.note(to, chunk, called);
            r
        })
    }
}

impl LinkWriter for TimedWriter {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_to(Endpoint::Api, chunk)
    }

    fn write_to<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        self.timed_write(to, chunk, false)
    }

    /// The emergency stop's write, timed the same way (and as urgent as it was asked).
    fn write_urgent<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        self.timed_write(to, chunk, true)
    }

    fn close(&mut self) -> BoxFuture<'_, ()> {
        self.inner.close()
    }
}

impl Link for Timed {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            let c = self.inner.open().await?;
            Ok(Connection {
                writer: Box::new(TimedWriter {
                    inner: c.writer,
                    rec: self.rec.clone(),
                    written: self.written.clone(),
                }),
                events: c.events,
            })
        })
    }

    /// A serial line's own framing (no BLE chunking, 5 ms pacing), which the session takes
    /// from the link as it does without the timing in between.
    fn framing(&self) -> Option<droidctl::link::Framing> {
        self.inner.framing()
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}

/// What each input is waited for: the first drive written after it with a speed above 0
/// (`go`) or of 0 (a stop).
#[derive(Clone, Copy, PartialEq)]
enum Want {
    Go,
    Stop,
}

/// One input and the drive it caused on one droid.
#[derive(Clone, Copy)]
struct Sample {
    since: Instant,
    drive: Drive,
}

impl Sample {
    fn latency(&self) -> Duration {
        self.drive.at - self.since
    }
}

struct Bench {
    term: mpsc::Sender<TermEvent>,
    pad: mpsc::Sender<PadEvent>,
    /// Every droid's drives, in fleet order.
    droids: Vec<Rec>,
    written: watch::Receiver<usize>,
    rng: Rng,
    missed: u32,
}

impl Bench {
    async fn key(&self, key: Key, kind: KeyKind) {
        self.term
            .send(TermEvent::Key { key, kind })
            .await
            .expect("the app runs");
    }

    /// Send what `send` sends, then wait for the drive it causes on every droid; each
    /// droid's (`None`: nothing within 2 s).
    async fn timed(&mut self, want: Want, send: impl AsyncFnOnce(&Self)) -> Vec<Option<Sample>> {
        let since = Instant::now();
        send(self).await;
        let deadline = since + Duration::from_secs(2);
        loop {
            let hits: Vec<Option<Sample>> = self
                .droids
                .iter()
                .map(|r| {
                    r.lock()
                        .unwrap()
                        .drives
                        .iter()
                        .find(|d| d.at >= since && (d.speed > 0) == (want == Want::Go))
                        .map(|&drive| Sample { since, drive })
                })
                .collect();
            if hits.iter().all(Option::is_some) {
                return hits;
            }
            if tokio::time::timeout_at(deadline, self.written.changed())
                .await
                .is_err()
            {
                self.missed += hits.iter().filter(|h| h.is_none()).count() as u32;
                return hits;
            }
        }
    }

    /// The one droid's drive for `send` (the single-droid measurement).
    async fn timed_one(&mut self, want: Want, send: impl AsyncFnOnce(&Self)) -> Option<Sample> {
        self.timed(want, send).await.into_iter().next().flatten()
    }

    async fn pause(&mut self, min_ms: u64, spread_ms: u64) {
        let ms = min_ms + self.rng.below(spread_ms + 1);
        sleep(Duration::from_millis(ms)).await;
    }
}

#[derive(Default)]
struct Results {
    press: Vec<Sample>,
    release: Vec<Sample>,
    estop: Vec<Sample>,
    stick: Vec<Sample>,
    stick_release: Vec<Sample>,
}

fn options(config: Config, model: Model) -> AppOptions {
    AppOptions {
        config,
        model,
        droid_name: model.display_name().into(),
        log_path: None,
        release: ReleaseMode::Reported,
        tripod_on_connect: true,
        samples: None,
        remember: None,
    }
}

/// The app's inputs, and the ends the bench sends on.
struct Inputs {
    app: AppInputs,
    term: mpsc::Sender<TermEvent>,
    pad: mpsc::Sender<PadEvent>,
    quit: mpsc::Sender<String>,
}

fn inputs() -> Inputs {
    let (term, term_rx) = mpsc::channel(64);
    let (pad, pad_rx) = mpsc::channel(64);
    let (quit, quit_rx) = mpsc::channel(4);
    Inputs {
        app: AppInputs {
            term: term_rx,
            pad: pad_rx,
            quit: quit_rx,
        },
        term,
        pad,
        quit,
    }
}

fn terminal() -> ratatui::Terminal<ratatui::backend::TestBackend> {
    ratatui::Terminal::new(ratatui::backend::TestBackend::new(160, 48)).expect("a test terminal")
}

fn space() -> Key {
    Key::parse("Space").expect("Space")
}

/// Drive the app over `link` as a person would, `reps` times each input.
async fn measure(link: Box<dyn Link>, model: Model, reps: usize) -> (Results, u32) {
    let (written_tx, written) = watch::channel(0);
    let (link, rec) = timed(link, model, &Arc::new(written_tx));
    let config = Config::defaults();
    let session = droidctl::session::start(
        link,
        droidctl::cli::fleet::session_config(model, &config, true),
    );
    let io = inputs();
    let opts = options(config, model);
    let app_session = session.clone();
    let app_inputs = io.app;
    let app = tokio::spawn(async move {
        let mut terminal = terminal();
        run::run(
            &mut terminal,
            app_session,
            opts,
            app_inputs,
            droidctl::ui::draw,
        )
        .await
    });
    // Connected, set up, standing in tripod.
    sleep(Duration::from_secs(5)).await;
    let mut b = Bench {
        term: io.term,
        pad: io.pad,
        droids: vec![rec],
        written,
        rng: Rng::new(21),
        missed: 0,
    };
    b.pad
        .send(PadEvent::Connected("bench pad".into()))
        .await
        .unwrap();
    let w = Key::ch('w');
    let space = space();
    let mut r = Results::default();
    let stick = |v: f32| PadEvent::Axis(Axis::LeftY, v);
    for _ in 0..reps {
        b.pause(0, 250).await;
        r.press.extend(
            b.timed_one(Want::Go, async |b| b.key(w, KeyKind::Press).await)
                .await,
        );
        b.pause(300, 400).await;
        r.release.extend(
            b.timed_one(Want::Stop, async |b| b.key(w, KeyKind::Release).await)
                .await,
        );
        b.pause(200, 250).await;
        b.key(w, KeyKind::Press).await;
        b.pause(300, 400).await;
        r.estop.extend(
            b.timed_one(Want::Stop, async |b| b.key(space, KeyKind::Press).await)
                .await,
        );
        b.key(space, KeyKind::Release).await;
        b.key(w, KeyKind::Release).await;
        b.pause(200, 250).await;
        r.stick.extend(
            b.timed_one(Want::Go, async |b| b.pad.send(stick(1.0)).await.unwrap())
                .await,
        );
        b.pause(300, 400).await;
        r.stick_release.extend(
            b.timed_one(Want::Stop, async |b| b.pad.send(stick(0.0)).await.unwrap())
                .await,
        );
    }
    io.quit.send("done".into()).await.unwrap();
    let exit = app.await.expect("the app ran").expect("the terminal works");
    let _ = tokio::time::timeout(
        Duration::from_secs(3),
        session.shutdown_stopped(vec![exit.stop]),
    )
    .await;
    (r, b.missed)
}

/// The emergency stop of a fleet, per droid of it (fleet order).
struct FleetResults {
    names: Vec<String>,
    stops: Vec<Vec<Sample>>,
    missed: u32,
}

/// Drive the fleet of `found` from the app, its first droid chosen (all four in mirror mode
/// when `mirrored`), and press the emergency stop `reps` times while driving.
async fn measure_fleet(found: Vec<Found>, reps: usize, mirrored: bool) -> FleetResults {
    let (written_tx, written) = watch::channel(0);
    let written_tx = Arc::new(written_tx);
    let config = Config::defaults();
    let mut recs = Vec::new();
    let specs = found
        .into_iter()
        .map(|mut f| {
            let (link, rec) = timed(f.link, f.model, &written_tx);
            f.link = link;
            recs.push(rec);
            let c = droidctl::cli::fleet::session_config(f.model, &config, true);
            f.into_spec(c)
        })
        .collect();
    let fleet = Fleet::start(specs);
    for m in fleet.members() {
        let mut st = m.session.watch_state();
        let up = tokio::time::timeout(Duration::from_secs(60), async {
            while *st.borrow_and_update() != LinkState::Connected {
                st.changed().await.expect("the session runs");
            }
        })
        .await;
        assert!(up.is_ok(), "{} did not connect within 60 s", m.name);
    }
    let io = inputs();
    let opts = options(config, fleet.members()[0].model);
    let f = fleet.clone();
    let app_inputs = io.app;
    let app = tokio::spawn(async move {
        let mut terminal = terminal();
        run::run(&mut terminal, f, opts, app_inputs, droidctl::ui::draw).await
    });
    let mut b = Bench {
        term: io.term,
        pad: io.pad,
        droids: recs.clone(),
        written,
        rng: Rng::new(26),
        missed: 0,
    };
    // Set up, R2-D2 standing in tripod.
    sleep(Duration::from_secs(4)).await;
    if mirrored {
        let y = Key::ch('y');
        b.key(y, KeyKind::Press).await;
        b.key(y, KeyKind::Release).await;
    }
    let (w, space) = (Key::ch('w'), space());
    let mut samples: Vec<Vec<Sample>> = vec![Vec::new(); recs.len()];
    for _ in 0..reps {
        b.pause(0, 250).await;
        b.key(w, KeyKind::Press).await;
        b.pause(300, 400).await;
        let hits = b
            .timed(Want::Stop, async |b| b.key(space, KeyKind::Press).await)
            .await;
        for (s, h) in samples.iter_mut().zip(hits) {
            s.extend(h);
        }
        b.key(space, KeyKind::Release).await;
        b.key(w, KeyKind::Release).await;
        b.pause(200, 250).await;
    }
    io.quit.send("done".into()).await.unwrap();
    let exit = app.await.expect("the app ran").expect("the terminal works");
    let _ = tokio::time::timeout(
        Duration::from_secs(5),
        fleet.shutdown_all(|i| vec![exit.stops[i].clone()]),
    )
    .await;
    FleetResults {
        names: fleet.members().iter().map(|m| m.name.clone()).collect(),
        stops: samples,
        missed: b.missed,
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1000.0
}

/// p50, p99 and max of `v`, in ms.
fn quantiles(mut v: Vec<Duration>) -> Option<(f64, f64, f64)> {
    v.sort();
    let last = *v.last()?;
    let at = |q: f64| v[((v.len() - 1) as f64 * q).ceil() as usize];
    Some((ms(at(0.5)), ms(at(0.99)), ms(last)))
}

fn line(what: &str, v: Vec<Duration>) {
    let n = v.len();
    match quantiles(v) {
        Some((p50, p99, max)) => {
            println!("  {what:<34} n {n:>4}  p50 {p50:>6.1}  p99 {p99:>6.1}  max {max:>6.1}")
        }
        None => println!("  {what:<34} no samples"),
    }
}

/// An emergency stop's latency and where it went: the key press to the link's write of the
/// stop being called (the app's event loop, the session task waking, the rest of a packet
/// half written), and the write (the link, with any pacing of its own).
fn stop_lines(what: &str, stops: &[Sample]) {
    line(what, stops.iter().map(Sample::latency).collect());
    let part = |f: fn(&Sample) -> Duration| {
        quantiles(stops.iter().map(f).collect()).unwrap_or((f64::NAN, f64::NAN, f64::NAN))
    };
    let called = part(|s| s.drive.called.saturating_duration_since(s.since));
    let write = part(|s| s.drive.at - s.drive.called);
    println!(
        "    where (p50 / p99 / max, ms): key to the write called {:.1} / {:.1} / {:.1}; \
         the write {:.1} / {:.1} / {:.1}",
        called.0, called.1, called.2, write.0, write.1, write.2
    );
}

fn report(link: &str, r: &Results, missed: u32) {
    println!(
        "{link}: n per input, p50 / p99 / max in ms (the target: p99 within 220 ms, one 100 ms tick plus one 120 ms slot)"
    );
    let lat = |v: &[Sample]| v.iter().map(Sample::latency).collect::<Vec<_>>();
    line("key press (drive)", lat(&r.press));
    line("key release (stop)", lat(&r.release));
    stop_lines("emergency stop", &r.estop);
    line("stick forward", lat(&r.stick));
    line("stick released (stop)", lat(&r.stick_release));
    if missed > 0 {
        println!("  {missed} inputs got no drive within 2 s");
    }
}

fn report_fleet(link: &str, how: &str, r: &FleetResults) {
    println!(
        "{link}, fleet of {} ({how}): emergency stop (Space) to the stop taken by each droid's link, p50 / p99 / max in ms (the goal: p50 under 10 ms)",
        r.names.len()
    );
    for (i, (name, stops)) in r.names.iter().zip(&r.stops).enumerate() {
        let role = match i {
            0 => " (chosen)",
            i if i + 1 == r.names.len() => " (last)",
            _ => "",
        };
        stop_lines(&format!("{name}{role}"), stops);
    }
    if r.missed > 0 {
        println!("  {} stops not written within 2 s", r.missed);
    }
}

#[cfg(target_os = "linux")]
mod bluez {
    use droidctl::model::Model;
    use droidctl::sim::bluez::{BluezOptions, BluezSim, PrivateBus, plan};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};

    /// The virtual BlueZ with `models`, on a private bus, on a thread of its own.
    pub struct Served {
        _bus: PrivateBus,
        stop: Arc<AtomicBool>,
        thread: Option<std::thread::JoinHandle<()>>,
        pub address: String,
        /// The droids' advertised names, in the order of `models`.
        pub names: Vec<String>,
    }

    impl Served {
        pub fn start(models: &[Model]) -> Served {
            let bus = PrivateBus::start().expect("a private dbus-daemon (install dbus-daemon)");
            let address = bus.address().to_string();
            let droids = plan(models, 1);
            let names = droids.iter().map(|d| d.name.clone()).collect();
            let sim = BluezSim::connect(
                &address,
                BluezOptions {
                    droids,
                    remembered: Vec::new(),
                    faults: Default::default(),
                    seed: 1,
                    trace: false,
                    json: false,
                },
                Box::new(|_| {}),
            )
            .expect("the virtual BlueZ");
            let stop = Arc::new(AtomicBool::new(false));
            let flag = stop.clone();
            let thread = std::thread::spawn(move || {
                let _ = sim.run(&flag);
            });
            Served {
                _bus: bus,
                stop,
                thread: Some(thread),
                address,
                names,
            }
        }
    }

    impl Drop for Served {
        fn drop(&mut self) {
            self.stop.store(true, Ordering::Release);
            if let Some(t) = self.thread.take() {
                let _ = t.join();
            }
        }
    }
}

#[cfg(unix)]
mod serial {
    use droidctl::model::Model;
    use std::path::PathBuf;
    use tokio::sync::oneshot;

    /// `sim --serial rvr` in this process: the simulated RVR served on a new
    /// pseudo-terminal by a thread with its own runtime, until dropped.
    pub struct Served {
        stop: Option<oneshot::Sender<()>>,
        thread: Option<std::thread::JoinHandle<()>>,
        pub path: PathBuf,
    }

    impl Served {
        pub fn start() -> Served {
            let (stop, stopped) = oneshot::channel::<()>();
            let (ready, is_ready) = std::sync::mpsc::channel();
            let thread = std::thread::spawn(move || {
                let rt = tokio::runtime::Builder::new_current_thread()
                    .enable_all()
                    .build()
                    .expect("the simulator's runtime");
                rt.block_on(async move {
                    // Opened inside the runtime (it registers with the reactor); the terminal
                    // side stays open while the simulator runs, as `sim --serial` keeps it.
                    let (pty, _peer, path) =
                        droidctl::link::serial::tty::open_pty().expect("a pseudo-terminal");
                    let _ = ready.send(path);
                    tokio::select! {
                        _ = stopped => {}
                        why = droidctl::sim::serial::serve(pty, Model::Rvr, false, |_| {}) => {
                            eprintln!("the serial simulator stopped: {why}");
                        }
                    }
                });
            });
            let path = is_ready.recv().expect("the simulator starts");
            Served {
                stop: Some(stop),
                thread: Some(thread),
                path,
            }
        }
    }

    impl Drop for Served {
        fn drop(&mut self) {
            if let Some(stop) = self.stop.take() {
                let _ = stop.send(());
            }
            if let Some(t) = self.thread.take() {
                let _ = t.join();
            }
        }
    }
}

/// The fleet's e-stop, the others idle and then mirrored, over the links `found` makes.
fn fleet_both(
    rt: &tokio::runtime::Runtime,
    link: &str,
    reps: usize,
    found: impl AsyncFn() -> Vec<Found>,
) {
    for (mirrored, how) in [
        (false, "the other three idle"),
        (true, "mirror mode: all four driving"),
    ] {
        let r = rt.block_on(async {
            let f = found().await;
            measure_fleet(f, reps, mirrored).await
        });
        report_fleet(link, how, &r);
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let mut reps = 100;
    let mut only: Option<String> = None;
    let mut part: Option<String> = None;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--reps" => reps = args.next().and_then(|v| v.parse().ok()).expect("--reps N"),
            "--only" => only = args.next(),
            "--part" => part = args.next(),
            // cargo bench passes --bench.
            _ => {}
        }
    }
    let wanted = |l: &str| only.as_deref().is_none_or(|o| o == l);
    let single = part.as_deref().is_none_or(|p| p == "single");
    let fleet = part.as_deref().is_none_or(|p| p == "fleet");
    #[cfg(target_os = "linux")]
    let served = wanted("bluez").then(|| {
        let s = bluez::Served::start(&FLEET);
        // btleplug reaches BlueZ on the system bus; ours is the private one. Set before any
        // thread of the runtime starts.
        unsafe { std::env::set_var("DBUS_SYSTEM_BUS_ADDRESS", &s.address) };
        s
    });
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("a runtime");
    let model = Model::R2D2;
    if wanted("sim") && single {
        let (r, missed) = rt.block_on(async {
            let link = droidctl::sim::SimLink::new(
                model,
                droidctl::sim::SimConfig::for_model(model),
                droidctl::sim::Faults::none(),
            );
            measure(Box::new(link), model, reps).await
        });
        report("in-process simulator", &r, missed);
    }
    if wanted("sim") && fleet {
        fleet_both(&rt, "in-process simulator", reps, async || {
            droidctl::cli::fleet::simulated(&FLEET)
        });
    }
    #[cfg(unix)]
    if wanted("serial") && single {
        // RVR on its UART (issue 41): `sim --serial rvr`'s server on a pseudo-terminal, on a
        // thread and runtime of its own as the simulator's own process would be, and the app
        // on `--serial PATH`'s link, timed to the return of the link's write on the port.
        let served = serial::Served::start();
        let model = Model::Rvr;
        let (r, missed) = rt.block_on(async {
            let link = droidctl::link::serial::SerialLink::new(&served.path, model);
            measure(Box::new(link), model, reps).await
        });
        report(
            &format!(
                "serial link (RVR on the pseudo-terminal {})",
                served.path.display()
            ),
            &r,
            missed,
        );
    }
    #[cfg(target_os = "linux")]
    if let Some(served) = served {
        if single {
            let (r, missed) = rt.block_on(async {
                let found = droidctl::link::ble::connect_link(
                    &droidctl::link::ble::DeviceSelector {
                        name: Some(served.names[0].clone()),
                        ..Default::default()
                    },
                    droidctl::family::gatt_profile,
                )
                .await
                .expect("the virtual R2-D2 is found");
                measure(Box::new(found.link), found.model, reps).await
            });
            report("btleplug on the virtual BlueZ", &r, missed);
        }
        if fleet {
            let ble = droidctl::cli::connect::BleArgs {
                name: served.names.clone(),
                scan_timeout: 10,
                ..Default::default()
            };
            fleet_both(&rt, "btleplug on the virtual BlueZ", reps, async || {
                droidctl::cli::fleet::find_all(&[], &ble, &Config::defaults())
                    .await
                    .unwrap_or_else(|e| panic!("{}", e.message))
            });
        }
        drop(served);
    }
}
