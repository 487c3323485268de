//! A Sphero Edu program's life on the droid's clock (issue 38 points 1–4): it starts once the
//! droid is set up and sampled (every reading a number from the first line), a timed call's
//! duration counts from when its command leaves, lights coalesce to their latest state per
//! light, and everything the program asked for is on the link before the run ends.
//!
//! What reached the link is read from the run's own capture (`--record`): its writes are
//! decoded by the family's reader (names and times) and played into a fresh simulated droid
//! of the model (what its lights end on).

use droidctl::capture::{Capture, Event};
use droidctl::family::read::{Found, ReadOptions};
use droidctl::gatt::Endpoint;
use droidctl::model::{Model, Protocol};
use droidctl::sim::{SimConfig, SimDroid, SimDroidV1};
use std::process::Output;
use std::time::Duration;

use crate::common::scratch;
use scratch::{Scratch, path, stderr, stdout};

/// Every model a Sphero Edu program runs on, by its `--sim` name.
const MODELS: [(&str, Model); 9] = [
    ("bolt", Model::Bolt),
    ("mini", Model::Mini),
    ("rvr", Model::Rvr),
    ("sprk", Model::SprkPlus),
    ("bb8", Model::BB8),
    ("bb9e", Model::BB9E),
    ("r2d2", Model::R2D2),
    ("r2q5", Model::R2Q5),
    ("ollie", Model::Ollie),
];

/// `droidctl run PROGRAM --sim MODEL --record CAP`: its output and its capture.
fn run(dir: &Scratch, name: &str, source: &str, model: &str) -> (Output, Capture) {
    let p = dir.file(&format!("{name}-{model}.js"), source);
    let cap = dir.0.join(format!("{name}-{model}.cap"));
    let out = dir.run(&["run", path(&p), "--sim", model, "--record", path(&cap)]);
    let capture = Capture::load(&cap).unwrap_or_else(|e| panic!("{model}: {e}"));
    (out, capture)
}

/// The commands the capture wrote, by the family's catalogue name, with when each went out.
fn written(model: Model, c: &Capture) -> Vec<(Duration, String)> {
    let mut reader = droidctl::family::for_model(model)
        .reader(&ReadOptions::default())
        .unwrap();
    let mut out = Vec::new();
    for t in &c.events {
        if let Event::Out(to, bytes) = &t.event {
            let mut seen = |f: &dyn Found| {
                out.push((t.at, f.line()));
                Ok(())
            };
            reader.write(*to, bytes, Some(&mut seen)).unwrap();
        }
    }
    out
}

/// The simulated droid after the capture's writes: its lights, the robot's own lights too
/// (BOLT, RVR), as values by LED.
fn lights(model: Model, c: &Capture) -> (Vec<u8>, Vec<u8>) {
    let writes = c.events.iter().filter_map(|t| match &t.event {
        Event::Out(Endpoint::Api, bytes) => Some((bytes, t.at)),
        _ => None,
    });
    if model.protocol() == Protocol::SpheroV1 {
        let mut d = SimDroidV1::new(model, SimConfig::for_model(model));
        for (bytes, at) in writes {
            d.receive(bytes, at);
        }
        return (d.state().leds.to_vec(), Vec::new());
    }
    let mut d = SimDroid::new(model, SimConfig::for_model(model));
    for (bytes, at) in writes {
        d.receive(bytes, at);
    }
    (d.state().leds.to_vec(), d.robot().leds.to_vec())
}

/// Whether a light shows `rgb` (three LED values side by side, from one of the first LEDs of
/// each of an RGB light's positions).
fn has(leds: &(Vec<u8>, Vec<u8>), rgb: [u8; 3]) -> bool {
    let all: Vec<u8> = leds.0.iter().chain(&leds.1).copied().collect();
    all.windows(3).any(|w| w == rgb)
}

#[test]
fn every_reading_is_a_number_from_the_first_line_on_every_model() {
    let dir = Scratch::new("edu-runtime", "first-line");
    let program = "async function startProgram() {\n  var g = getGyroscope(), o = getOrientation(), a = getAcceleration();\n  var l = getLocation(), v = getVelocity();\n  var all = [g.pitch, g.roll, g.yaw, o.pitch, o.roll, o.yaw, a.x, a.y, a.z, l.x, l.y, v.x, v.y];\n  for (var i = 0; i < all.length; i++) {\n    if (typeof all[i] !== \"number\") throw new Error(\"reading \" + i + \" is \" + all[i]);\n  }\n  await delay(0.1);\n}\n";
    for (name, _) in MODELS {
        let (out, _) = run(&dir, "first", program, name);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        // Every reading streamed by the simulated droid: none said missing.
        assert!(
            !stdout(&out).contains("sent no"),
            "{name}: {}",
            stdout(&out)
        );
    }
}

#[test]
fn lights_set_just_before_the_end_are_on_the_link_on_every_model() {
    let dir = Scratch::new("edu-runtime", "end-lights");
    for (name, model) in MODELS {
        // The front and back lights where the model has them as colours.
        let more = match model {
            Model::Bolt | Model::Mini | Model::Rvr | Model::R2D2 | Model::R2Q5 => {
                "  setFrontLed({ r: 0, g: 201, b: 0 });\n  setBackLed({ r: 0, g: 0, b: 202 });\n"
            }
            _ => "",
        };
        let program = format!(
            "async function startProgram() {{\n  setMainLed({{ r: 200, g: 0, b: 0 }});\n{more}  await delay(0.2);\n}}\n"
        );
        let (out, cap) = run(&dir, "end", &program, name);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        let leds = lights(model, &cap);
        if more.is_empty() {
            assert!(has(&leds, [200, 0, 0]), "{name}: main light: {leds:?}");
        } else {
            // The last calls' lights are on the droid (main is front and back on some).
            assert!(has(&leds, [0, 201, 0]), "{name}: front light: {leds:?}");
            assert!(has(&leds, [0, 0, 202]), "{name}: back light: {leds:?}");
        }
    }
}

/// The first `rawMotor(100, 100, 2)` drives 2 s from when its command leaves to when its stop
/// does, within a pacing tick (the stop may wait for the write slot).
#[test]
fn the_first_raw_motor_call_drives_its_whole_duration() {
    let dir = Scratch::new("edu-runtime", "raw");
    let program =
        "async function startProgram() {\n  await rawMotor(100, 100, 2);\n  await delay(0.5);\n}\n";
    for (name, model) in [
        ("bolt", Model::Bolt),
        ("mini", Model::Mini),
        ("rvr", Model::Rvr),
        ("sprk", Model::SprkPlus),
    ] {
        let (out, cap) = run(&dir, "raw", program, name);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        let raw: Vec<_> = written(model, &cap)
            .into_iter()
            .filter(|(_, line)| line.contains("raw-motor"))
            .collect();
        let start = raw
            .iter()
            .find(|(_, l)| !l.contains(" 00 00 00 00"))
            .unwrap_or_else(|| panic!("{name}: no raw motors written: {raw:?}"));
        let stop = raw
            .iter()
            .find(|(at, _)| *at > start.0)
            .unwrap_or_else(|| panic!("{name}: no stop written: {raw:?}"));
        let drove = stop.0 - start.0;
        let tick = model.write_pacing();
        assert!(
            drove >= Duration::from_secs(2) && drove <= Duration::from_secs(2) + tick,
            "{name}: drove {drove:?}: {raw:?}"
        );
    }
}

/// A 10 Hz light loop on R2-D2 and Mini (120 ms pacing): no "too many commands waiting", and
/// the last colour set is the one the droid ends on.
#[test]
fn a_light_loop_never_floods_the_queue_and_ends_on_its_last_colour() {
    let dir = Scratch::new("edu-runtime", "loop");
    let program = "async function startProgram() {\n  for (var i = 0; i < 150; i++) {\n    setMainLed(i % 2 ? { r: 255, g: 0, b: 0 } : { r: 0, g: 255, b: 0 });\n    await delay(0.1);\n  }\n  setMainLed({ r: 0, g: 0, b: 255 });\n}\n";
    for (name, model) in [("r2d2", Model::R2D2), ("mini", Model::Mini)] {
        let (out, cap) = run(&dir, "loop", program, name);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        let all = format!("{}{}", stdout(&out), stderr(&out));
        assert!(!all.contains("waiting"), "{name}: {all}");
        let leds = lights(model, &cap);
        // Blue, on every LED the main light sets (front and back on R2-D2), nothing else lit.
        assert!(has(&leds, [0, 0, 255]), "{name}: ends blue: {leds:?}");
        let lit: Vec<u8> = leds
            .0
            .iter()
            .chain(&leds.1)
            .copied()
            .filter(|v| *v != 0)
            .collect();
        assert!(lit.iter().all(|v| *v == 255), "{name}: {leds:?}");
    }
}
