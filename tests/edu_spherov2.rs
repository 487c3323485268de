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
    let venv = format!("{}/target/spherov2-venv/bin/python", root());
    let py = std::env::var("DROIDCTL_TEST_SPHEROV2_PYTHON").unwrap_or_else(|_| {
        if Path::new(&venv).exists() {
            venv
        } else {
            "python3".into()
        }
    });
    let ok = Command::new(&py)
        .args([
            "-c",
            "import spherov2.sphero_edu, spherov2.adapter.tcp_adapter",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if ok {
        Ok(py)
    } else {
        Err(format!(
            "{py} cannot import spherov2 (set DROIDCTL_TEST_SPHEROV2_PYTHON)"
        ))
    }
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

fn finish(mut child: Child, limit: Duration, what: &str) -> std::process::Output {
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!(
                "{what} did not finish: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}

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

/// spherov2's run of the Python: the final position it read, and serve's capture.
fn run_py(py: &str, program: &str, dir: &Dir) -> ([f64; 2], String) {
    let cap = dir.path(&format!("{program}-py.cap"));
    let mut serve = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args([
            "serve",
            "--listen",
            "127.0.0.1:0",
            "--json",
            "--sim",
            "bolt",
            "--record",
            &cap,
        ])
        .env("DROIDCTL_LOG_FILE", dir.path("serve.log"))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let events = Arc::new(Mutex::new(Vec::<Value>::new()));
    {
        let events = events.clone();
        let out = serve.stdout.take().unwrap();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines() {
                let Ok(line) = line else { break };
                if let Ok(v) = serde_json::from_str(&line) {
                    events.lock().unwrap().push(v);
                }
            }
        });
    }
    let wait = |f: &dyn Fn(&Value) -> bool, what: &str| -> Value {
        let start = Instant::now();
        loop {
            if let Some(e) = events.lock().unwrap().iter().find(|e| f(e)) {
                return e.clone();
            }
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "no {what} from serve"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    };
    let listening = wait(&|e| e["event"] == "listening", "listening");
    let port = listening["address"]
        .as_str()
        .unwrap()
        .rsplit(':')
        .next()
        .unwrap()
        .to_string();
    let script = format!("{}/tests/edu_judge.py", root());
    let child = Command::new(py)
        .args([&script, &port, "SB-0001", program])
        .current_dir(format!("{}/tests", root()))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = finish(child, Duration::from_secs(120), "spherov2");
    assert!(
        out.status.success(),
        "{program}.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    wait(&|e| e["event"] == "droid_released", "droid_released");
    let _ = Command::new("kill")
        .args(["-TERM", &serve.id().to_string()])
        .status();
    let _ = finish(serve, Duration::from_secs(20), "serve");
    let seen: Value = serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).unwrap();
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
