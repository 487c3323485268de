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
//!   `dbus-daemon`; Linux only): D-Bus, BlueZ's GATT calls, the droid behind them.
//!
//! Between inputs it waits a random 0–250 ms, so inputs land anywhere in the 100 ms control
//! tick and the 120 ms pacing slot. Prints p50, p99 and the maximum per input.
//!
//!     cargo bench --bench latency                  # both links, 100 of each input
//!     cargo bench --bench latency -- --reps 300 --only sim

use droidctl::app::input::{KeyKind, TermEvent};
use droidctl::app::run::{self, AppInputs, AppOptions};
use droidctl::config::Config;
use droidctl::config::Key;
use droidctl::gatt::Endpoint;
use droidctl::link::{Connection, Link, LinkError, LinkWriter};
use droidctl::model::Model;
use droidctl::protocol::v2::Decoder;
use droidctl::rng::Rng;
use droidctl::teleop::gamepad::{Axis, PadEvent};
use droidctl::teleop::held::ReleaseMode;
use futures_util::future::BoxFuture;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::{mpsc, watch};
use tokio::time::{Instant, sleep};

/// A drive command written to the link: when the write returned, and its speed.
#[derive(Debug, Clone, Copy)]
struct Drive {
    at: Instant,
    speed: u8,
}

#[derive(Default)]
struct Recorded {
    decoder: Decoder,
    drives: Vec<Drive>,
}

/// A link that notes when each drive command's last byte was taken.
struct Timed {
    inner: Box<dyn Link>,
    rec: Arc<Mutex<Recorded>>,
    written: Arc<watch::Sender<usize>>,
}

struct TimedWriter {
    inner: Box<dyn LinkWriter>,
    rec: Arc<Mutex<Recorded>>,
    written: Arc<watch::Sender<usize>>,
}

impl TimedWriter {
    fn note(&self, to: Endpoint, chunk: &[u8]) {
        if to != Endpoint::Api {
            return;
        }
        let at = Instant::now();
        let mut r = self.rec.lock().unwrap();
        let packets = r.decoder.decode_all(chunk);
        for p in packets.into_iter().flatten() {
            if (p.did, p.cid) == (0x16, 0x07) {
                r.drives.push(Drive {
                    at,
                    speed: p.data[0],
                });
                let n = r.drives.len();
                self.written.send_replace(n);
            }
        }
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
        Box::pin(async move {
            let r = self.inner.write_to(to, chunk).await;
            self.note(to, chunk);
            r
        })
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

struct Bench {
    term: mpsc::Sender<TermEvent>,
    pad: mpsc::Sender<PadEvent>,
    rec: Arc<Mutex<Recorded>>,
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

    /// Send what `send` sends, then wait for the drive it causes; its latency.
    async fn timed(&mut self, want: Want, send: impl AsyncFnOnce(&Self)) -> Option<Duration> {
        let since = Instant::now();
        send(self).await;
        let deadline = since + Duration::from_secs(2);
        loop {
            let hit = self
                .rec
                .lock()
                .unwrap()
                .drives
                .iter()
                .find(|d| d.at >= since && (d.speed > 0) == (want == Want::Go))
                .map(|d| d.at - since);
            if hit.is_some() {
                return hit;
            }
            if tokio::time::timeout_at(deadline, self.written.changed())
                .await
                .is_err()
            {
                self.missed += 1;
                return None;
            }
        }
    }

    async fn pause(&mut self, min_ms: u64, spread_ms: u64) {
        let ms = min_ms + self.rng.below(spread_ms + 1);
        sleep(Duration::from_millis(ms)).await;
    }
}

#[derive(Default)]
struct Results {
    press: Vec<Duration>,
    release: Vec<Duration>,
    estop: Vec<Duration>,
    stick: Vec<Duration>,
    stick_release: Vec<Duration>,
}

/// Drive the app over `link` as a person would, `reps` times each input.
async fn measure(link: Box<dyn Link>, model: Model, reps: usize) -> (Results, u32) {
    let rec = Arc::new(Mutex::new(Recorded::default()));
    let (written_tx, written) = watch::channel(0);
    let link = Timed {
        inner: link,
        rec: rec.clone(),
        written: Arc::new(written_tx),
    };
    let config = Config::defaults();
    let session = droidctl::session::start(
        Box::new(link),
        droidctl::cli::fleet::session_config(model, &config, true),
    );
    let (term, term_rx) = mpsc::channel(64);
    let (pad, pad_rx) = mpsc::channel(64);
    let (quit, quit_rx) = mpsc::channel(4);
    let opts = AppOptions {
        config,
        model,
        droid_name: model.display_name().into(),
        log_path: None,
        release: ReleaseMode::Reported,
        tripod_on_connect: true,
        samples: None,
    };
    let app_session = session.clone();
    let app = tokio::spawn(async move {
        let backend = ratatui::backend::TestBackend::new(160, 48);
        let mut terminal = ratatui::Terminal::new(backend).expect("a test terminal");
        let inputs = AppInputs {
            term: term_rx,
            pad: pad_rx,
            quit: quit_rx,
        };
        run::run(&mut terminal, app_session, opts, inputs, droidctl::ui::draw).await
    });
    // Connected, set up, standing in tripod.
    sleep(Duration::from_secs(5)).await;
    let mut b = Bench {
        term,
        pad,
        rec,
        written,
        rng: Rng::new(21),
        missed: 0,
    };
    b.pad
        .send(PadEvent::Connected("bench pad".into()))
        .await
        .unwrap();
    let w = Key::ch('w');
    let space = Key::parse("Space").expect("Space");
    let mut r = Results::default();
    let stick = |v: f32| PadEvent::Axis(Axis::LeftY, v);
    for _ in 0..reps {
        b.pause(0, 250).await;
        r.press.extend(
            b.timed(Want::Go, async |b| b.key(w, KeyKind::Press).await)
                .await,
        );
        b.pause(300, 400).await;
        r.release.extend(
            b.timed(Want::Stop, async |b| b.key(w, KeyKind::Release).await)
                .await,
        );
        b.pause(200, 250).await;
        b.key(w, KeyKind::Press).await;
        b.pause(300, 400).await;
        r.estop.extend(
            b.timed(Want::Stop, async |b| b.key(space, KeyKind::Press).await)
                .await,
        );
        b.key(space, KeyKind::Release).await;
        b.key(w, KeyKind::Release).await;
        b.pause(200, 250).await;
        r.stick.extend(
            b.timed(Want::Go, async |b| b.pad.send(stick(1.0)).await.unwrap())
                .await,
        );
        b.pause(300, 400).await;
        r.stick_release.extend(
            b.timed(Want::Stop, async |b| b.pad.send(stick(0.0)).await.unwrap())
                .await,
        );
    }
    quit.send("done".into()).await.unwrap();
    let exit = app.await.expect("the app ran").expect("the terminal works");
    let _ = tokio::time::timeout(
        Duration::from_secs(3),
        session.shutdown_stopped(vec![exit.stop]),
    )
    .await;
    (r, b.missed)
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1000.0
}

fn report(link: &str, r: &Results, missed: u32) {
    println!(
        "{link}: n per input, p50 / p99 / max in ms (the target: p99 within 220 ms, one 100 ms tick plus one 120 ms slot)"
    );
    for (what, v) in [
        ("key press (drive)", &r.press),
        ("key release (stop)", &r.release),
        ("emergency stop", &r.estop),
        ("stick forward", &r.stick),
        ("stick released (stop)", &r.stick_release),
    ] {
        let mut v = v.clone();
        v.sort();
        if v.is_empty() {
            println!("  {what:<22} no samples");
            continue;
        }
        let at = |q: f64| v[((v.len() - 1) as f64 * q).ceil() as usize];
        println!(
            "  {what:<22} n {:>4}  p50 {:>6.1}  p99 {:>6.1}  max {:>6.1}",
            v.len(),
            ms(at(0.5)),
            ms(at(0.99)),
            ms(*v.last().unwrap())
        );
    }
    if missed > 0 {
        println!("  {missed} inputs got no drive within 2 s");
    }
}

#[cfg(target_os = "linux")]
mod bluez {
    use droidctl::model::Model;
    use droidctl::sim::bluez::{BluezOptions, BluezSim, PrivateBus, plan};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};

    /// The virtual BlueZ with one R2-D2, on a private bus, on a thread of its own.
    pub struct Served {
        _bus: PrivateBus,
        stop: Arc<AtomicBool>,
        thread: Option<std::thread::JoinHandle<()>>,
        pub address: String,
    }

    impl Served {
        pub fn start() -> Served {
            let bus = PrivateBus::start().expect("a private dbus-daemon (install dbus-daemon)");
            let address = bus.address().to_string();
            let sim = BluezSim::connect(
                &address,
                BluezOptions {
                    droids: plan(&[Model::R2D2], 1),
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

fn main() {
    let mut args = std::env::args().skip(1);
    let mut reps = 100;
    let mut only: Option<String> = None;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--reps" => reps = args.next().and_then(|v| v.parse().ok()).expect("--reps N"),
            "--only" => only = args.next(),
            // cargo bench passes --bench.
            _ => {}
        }
    }
    let wanted = |l: &str| only.as_deref().is_none_or(|o| o == l);
    #[cfg(target_os = "linux")]
    let served = wanted("bluez").then(|| {
        let s = bluez::Served::start();
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
    if wanted("sim") {
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
    #[cfg(target_os = "linux")]
    if let Some(served) = served {
        let (r, missed) = rt.block_on(async {
            let found = droidctl::link::ble::connect_link(
                &droidctl::link::ble::DeviceSelector::default(),
                droidctl::family::gatt_profile,
            )
            .await
            .expect("the virtual R2-D2 is found");
            measure(Box::new(found.link), found.model, reps).await
        });
        report("btleplug on the virtual BlueZ", &r, missed);
        drop(served);
    }
}
