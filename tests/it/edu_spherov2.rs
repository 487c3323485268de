//! Judged by spherov2 (issue 29 point 4): the same Sphero Edu programs written twice, in
//! JavaScript run by `droidctl run PROGRAM.js --sim bolt` and in Python run by spherov2.py's
//! own `SpheroEduAPI` against `droidctl serve --sim bolt` (tests/edu_judge.py). Where the
//! droid ends up must agree within a few centimetres, and so must its lights and matrix: both
//! runs are recorded (`--record`), and the commands each capture sent are played into a fresh
//! simulated BOLT, whose lights and matrix are compared.
//!
//! Skipped, with a message, only where no Python with spherov2 is at hand (`.ci/run` makes
//! target/spherov2-venv; DROIDCTL_TEST_SPHEROV2_PYTHON names another).

use droidctl::capture::{Capture, Event};
use droidctl::gatt::Endpoint;
use droidctl::model::Model;
use droidctl::sim::{SimConfig, SimDroid};
use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

fn root() -> &'static str {
    env!("CARGO_MANIFEST_DIR")
}

/// A Python that imports spherov2's Sphero Edu API, or why not.
fn python() -> Result<String, String> {
    crate::common::python::Library::Spherov2
        .python("spherov2.sphero_edu, spherov2.adapter.tcp_adapter")
}

struct Dir(PathBuf);

impl Dir {
    fn new(name: &str) -> Dir {
        let d =
            std::env::temp_dir().join(format!("droidctl-edu-judge-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Dir(d)
    }
    fn path(&self, f: &str) -> String {
        self.0.join(f).to_string_lossy().into_owned()
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

use crate::common::cli::finish;

/// droidctl's run of the JavaScript: the final position, and the capture.
fn run_js(program: &str, dir: &Dir) -> ([f64; 2], String) {
    let cap = dir.path(&format!("{program}-js.cap"));
    let js = format!("{}/tests/fixtures/edu/{program}.js", root());
    let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["run", &js, "--sim", "bolt", "--json", "--record", &cap])
        .env("DROIDCTL_LOG_FILE", dir.path("run.log"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{program}.js: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = text
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .find(|v| v["done"] == true)
        .expect("a summary");
    let xy = [
        summary["x_cm"].as_f64().unwrap(),
        summary["y_cm"].as_f64().unwrap(),
    ];
    (xy, cap)
}

/// `droidctl serve --sim MODELS…` on a free port, recording to `cap`: the child, its port,
/// and the events it printed so far (read on a thread).
struct Serve {
    child: Child,
    port: String,
    events: Arc<Mutex<Vec<Value>>>,
}

impl Serve {
    fn start(models: &[&str], cap: &str, dir: &Dir) -> Serve {
        let mut args = vec!["serve", "--listen", "127.0.0.1:0", "--json", "--sim"];
        args.extend(models);
        args.extend(["--record", cap]);
        let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .args(&args)
            .env("DROIDCTL_LOG_FILE", dir.path("serve.log"))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let events = Arc::new(Mutex::new(Vec::<Value>::new()));
        {
            let events = events.clone();
            let out = child.stdout.take().unwrap();
            std::thread::spawn(move || {
                for line in BufReader::new(out).lines() {
                    let Ok(line) = line else { break };
                    if let Ok(v) = serde_json::from_str(&line) {
                        events.lock().unwrap().push(v);
                    }
                }
            });
        }
        let mut serve = Serve {
            child,
            port: String::new(),
            events,
        };
        let listening = serve.wait(&|e| e["event"] == "listening", "listening");
        serve.port = listening["address"]
            .as_str()
            .unwrap()
            .rsplit(':')
            .next()
            .unwrap()
            .to_string();
        serve
    }

    fn wait(&self, f: &dyn Fn(&Value) -> bool, what: &str) -> Value {
        let start = Instant::now();
        loop {
            if let Some(e) = self.events.lock().unwrap().iter().find(|e| f(e)) {
                return e.clone();
            }
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "no {what} from serve"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The judge script with `args` after the port: its output, once it succeeded; then
    /// serve is stopped once it released the droids.
    fn judge(self, py: &str, args: &[&str], what: &str) -> Value {
        let script = format!("{}/tests/edu_judge.py", root());
        let child = Command::new(py)
            .arg(&script)
            .arg(&self.port)
            .args(args)
            .current_dir(format!("{}/tests", root()))
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let out = finish(child, Duration::from_secs(120), "spherov2");
        assert!(
            out.status.success(),
            "{what}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        self.wait(&|e| e["event"] == "droid_released", "droid_released");
        let _ = Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status();
        let _ = finish(self.child, Duration::from_secs(20), "serve");
        serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).unwrap()
    }
}

/// spherov2's run of the Python: the final position it read, and serve's capture.
fn run_py(py: &str, program: &str, dir: &Dir) -> ([f64; 2], String) {
    let cap = dir.path(&format!("{program}-py.cap"));
    let serve = Serve::start(&["bolt"], &cap, dir);
    let seen = serve.judge(py, &["SB-0001", program], &format!("{program}.py"));
    let xy = [
        seen["location"]["x"].as_f64().unwrap(),
        seen["location"]["y"].as_f64().unwrap(),
    ];
    (xy, cap)
}

/// What BOLT shows after the commands of a capture: its lights and its matrix, taken while
/// awake (spherov2 puts the droid to sleep as its API closes).
#[derive(Debug, PartialEq)]
struct Shows {
    leds: [u8; 16],
    pixels: [[[u8; 3]; 8]; 8],
    character: Option<char>,
}

fn shows(cap: &str) -> Shows {
    let c = Capture::load(Path::new(cap)).unwrap();
    let mut d = SimDroid::new(Model::Bolt, SimConfig::for_model(Model::Bolt));
    let mut last = None;
    for t in &c.events {
        if let Event::Out(Endpoint::Api, bytes) = &t.event {
            d.receive(bytes, t.at);
            if d.state().awake {
                last = Some(Shows {
                    leds: d.state().leds,
                    pixels: d.robot().matrix.pixels,
                    character: d.robot().matrix.character,
                });
            }
        }
    }
    last.expect("the droid was awake")
}

fn judge(program: &str, tolerance_cm: f64) -> Option<Shows> {
    let py = match python() {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED edu_spherov2 {program}: {why}");
            return None;
        }
    };
    let dir = Dir::new(program);
    let (js_xy, js_cap) = run_js(program, &dir);
    let (py_xy, py_cap) = run_py(&py, program, &dir);
    eprintln!("{program}: droidctl {js_xy:?}, spherov2 {py_xy:?}");
    let d = ((js_xy[0] - py_xy[0]).powi(2) + (js_xy[1] - py_xy[1]).powi(2)).sqrt();
    assert!(
        d <= tolerance_cm,
        "{program}: droidctl ends at {js_xy:?}, spherov2 at {py_xy:?} ({d:.1} cm apart)"
    );
    let js = shows(&js_cap);
    assert_eq!(js, shows(&py_cap), "{program}: lights and matrix");
    Some(js)
}

#[test]
fn a_square_goes_where_spherov2_goes() {
    judge("square", 5.0);
}

#[test]
fn pong_turns_on_each_hit_as_with_spherov2() {
    judge("pong", 8.0);
}

#[test]
fn a_spin_moves_the_heading_as_spherov2_does() {
    // Three rolls in a row: each of spherov2's runs a few hundredths of a second longer in real
    // time (its stop goes out after its sleep and the link's latency), ~2 cm a roll.
    judge("spin", 8.0);
}

#[test]
fn the_matrix_shows_what_spherov2_draws() {
    judge("matrix", 5.0);
}

#[test]
fn a_matrix_animation_ends_on_the_frame_spherov2_ends_on() {
    let Some(shown) = judge("animation", 5.0) else {
        return;
    };
    // Both ran the one-shot animation to its last frame: STRIPES in the 16-colour palette
    // (tests/fixtures/edu/animation.js), row 0 at the top, column 0 at the left.
    const STRIPES: [[u8; 8]; 8] = [
        [0, 1, 2, 3, 4, 5, 6, 7],
        [8, 9, 10, 11, 12, 13, 14, 15],
        [15, 14, 13, 12, 11, 10, 9, 8],
        [7, 6, 5, 4, 3, 2, 1, 0],
        [0, 0, 0, 0, 15, 15, 15, 15],
        [9, 0, 9, 0, 9, 0, 9, 0],
        [0, 0, 0, 0, 0, 0, 0, 0],
        [3, 3, 3, 3, 3, 3, 3, 12],
    ];
    let colour = |i: u8| [i * 16, 255 - i * 16, ((i as u16 * 37) % 256) as u8];
    let want = STRIPES.map(|row| row.map(colour));
    assert_eq!(shown.pixels, want);
}

/// Infrared judged by spherov2's own API on three robots of one `serve --sim rvr rvr bolt`
/// room: an RVR's `send_ir_message` (0x3F) reaches the other RVR, which listens
/// (`listen_for_ir_message`: 0x3E), and its `on_ir_message` fires with the channel, which
/// `get_last_ir_message` returns; then that RVR follows the BOLT's broadcast (0x27, 0x28)
/// and rolls up to it. spherov2 sends nothing for BOLT's messages (its `send_ir_message` and
/// `listen_for_ir_message` are "TODO: BOLT"), so BOLT's are judged by droidctl's own tests
/// (tests/it/edu_infrared.rs).
#[test]
fn infrared_between_robots_as_spherov2_drives_it() {
    let py = match python() {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED edu_spherov2 infrared: {why}");
            return;
        }
    };
    let dir = Dir::new("infrared");
    let serve = Serve::start(&["rvr", "rvr", "bolt"], &dir.path("ir.cap"), &dir);
    let seen = serve.judge(
        &py,
        &["infrared", "RV-0001", "RV-0002", "SB-0003"],
        "infrared",
    );
    eprintln!("infrared: {seen}");
    assert_eq!(seen["heard"], serde_json::json!([[3, 3]]), "{seen}");
    let at = |k: &str| {
        (
            seen[k]["x"].as_f64().unwrap(),
            seen[k]["y"].as_f64().unwrap(),
        )
    };
    let ((x0, y0), (x1, y1)) = (at("start"), at("end"));
    let moved = (x1 - x0).hypot(y1 - y0);
    // 45.4 cm apart edge to edge; a follower stops 15 cm short.
    assert!(moved > 15.0 && moved < 45.0, "{seen}");
}
