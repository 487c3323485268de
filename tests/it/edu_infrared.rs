//! Sphero Edu's infrared between robots, end to end: programs on simulated BOLTs (and RVR)
//! sharing one room send and hear messages (`sendIRMessage`, `listenForIRMessage`,
//! `onIRMessage`, `getLastIRMessage`), and follow or evade a broadcaster
//! (`startIRBroadcast`, `startIRFollow`, `startIREvade`). Follow and evade need a program per
//! droid: `droidctl run beacon.js follow.js --sim bolt,bolt` gives each its own (tested
//! below), and the behaviours' finer points run here in process, each droid's session and
//! program as `run` starts them, in simulated time.

use droidctl::mission::Summary;
use droidctl::model::Model;
use droidctl::sim::link::SimProbe;
use droidctl::sim::room::SharedRoom;
use droidctl::sim::{Faults, SimConfig, SimLink};
use std::time::Duration;

use crate::common::edu_run;
use crate::common::scratch;
use edu_run::run_program;
use scratch::{Scratch, path, stderr, stdout};

fn example(name: &str) -> String {
    format!("{}/examples/edu/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The lines of `droid` (`SB-0001`) saying it heard a message.
fn heard<'a>(text: &'a str, droid: &str) -> Vec<&'a str> {
    text.lines()
        .filter(|l| l.contains(droid) && l.contains("says \"heard channel 3\""))
        .collect()
}

#[test]
fn two_bolts_hear_each_other_and_one_alone_hears_nothing() {
    let dir = Scratch::new("edu", "infrared");
    let out = dir.run(&["run", &example("infrared.js"), "--sim", "bolt,bolt"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    for droid in ["SB-0001", "SB-0002"] {
        assert_eq!(heard(&text, droid).len(), 1, "{droid}: {text}");
        // The handler lit it green: the step is there, after the message was sent.
        assert!(
            text.lines()
                .any(|l| l.contains(droid) && l.contains("line 7: setMainLed(0, 255, 0)")),
            "{text}"
        );
    }
    // Alone, the robot does not hear its own message.
    let out = dir.run(&["run", &example("infrared.js"), "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(!text.contains("heard channel"), "{text}");
    assert!(!text.contains("setMainLed(0, 255, 0)"), "{text}");
}

#[test]
fn a_weak_message_falls_short_and_rvr_hears_a_bolt() {
    let dir = Scratch::new("edu", "infrared-reach");
    // Intensity 8 carries 37.5 cm; the two BOLTs are 52.7 cm apart, edge to edge.
    let p = dir.file(
        "weak.js",
        "registerEvent(EventType.onIRMessage, (ch) => speak(\"heard channel \" + ch, false));\n\
         async function startProgram() {\n  listenForIRMessage(3);\n  await delay(0.5);\n  \
         sendIRMessage(3, 8);\n  await delay(1);\n  exitProgram();\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "bolt,bolt"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(!stdout(&out).contains("heard channel"), "{}", stdout(&out));
    // A BOLT and an RVR: RVR listens and sends with its own commands; each hears the other.
    let out = dir.run(&["run", &example("infrared.js"), "--sim", "bolt,rvr"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    assert_eq!(heard(&text, "SB-0001").len(), 1, "{text}");
    assert_eq!(heard(&text, "RV-0002").len(), 1, "{text}");
    // Not on a Mini: the event and the calls name the robots they are on.
    let out = dir.run(&["run", &example("infrared.js"), "--sim", "mini"]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        // The calls are checked before anything runs: the first not on Mini is named.
        err.contains("is not on Sphero Mini (it is on Sphero BOLT, Sphero BOLT+, Sphero RVR)"),
        "{err}"
    );
    let p = dir.file(
        "send.js",
        "async function startProgram() {\n  sendIRMessage(3, 64);\n}\n",
    );
    let out = dir.run(&["run", path(&p), "--sim", "mini"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("send.js:2: TypeError: sendIRMessage() is not on Sphero Mini"),
        "{}",
        stderr(&out)
    );
}

/// One droid's run: its summary (its final position is from its own start), what it
/// said, and its simulator.
struct Run {
    summary: Summary,
    said: Vec<String>,
    probe: SimProbe,
}

/// Run `programs` at once on simulated `models` sharing one room, each droid's session and
/// program as `droidctl run` starts a fleet's.
async fn fleet(models: &[Model], programs: &[&str]) -> Vec<Run> {
    let room = SharedRoom::new();
    let start = tokio::time::Instant::now();
    let runs = models
        .iter()
        .zip(SharedRoom::origins(models.len()))
        .zip(programs)
        .enumerate()
        .map(|(i, ((m, origin), text))| {
            let mut cfg = SimConfig::for_model(*m);
            cfg.place = Some(room.place(origin, cfg.radius_cm));
            let link = SimLink::new(*m, cfg, Faults::none());
            let probe = link.probe();
            async move {
                let name = format!("droid{i}.js");
                let (summary, said) = run_program(link, *m, text, &name, start).await;
                Run {
                    summary,
                    said,
                    probe,
                }
            }
        });
    futures_util::future::join_all(runs).await
}

/// The gap between two BOLTs of a two-droid fleet at the end, edge to edge (they start
/// 60 cm apart along x, 52.7 cm edge to edge).
fn gap(s: &[Run]) -> f32 {
    let origins = SharedRoom::origins(2);
    let at = |i: usize| {
        let m = &s[i].summary;
        (
            origins[i].0 + m.x_cm.unwrap(),
            origins[i].1 + m.y_cm.unwrap(),
        )
    };
    let (a, b) = (at(0), at(1));
    let r = SimConfig::for_model(Model::Bolt).radius_cm;
    (a.0 - b.0).hypot(a.1 - b.1) - 2.0 * r
}

fn x(r: &Run) -> f32 {
    r.summary.x_cm.unwrap()
}

const BROADCASTER: &str =
    "async function startProgram() {\n  startIRBroadcast(0, 1);\n  await delay(8);\n}\n";

#[tokio::test(start_paused = true)]
async fn a_follower_rolls_up_to_the_broadcaster() {
    let follower =
        "async function startProgram() {\n  startIRFollow(0, 1);\n  await delay(8);\n}\n";
    let s = fleet(&[Model::Bolt, Model::Bolt], &[BROADCASTER, follower]).await;
    let g = gap(&s);
    assert!(g < 25.0 && g > 0.0, "from 52.7 cm to {g} cm");
    // The broadcaster stayed; the follower moved toward it (along −x).
    assert!(
        x(&s[0]).abs() < 1.0 && x(&s[1]) < -25.0,
        "{} {}",
        x(&s[0]),
        x(&s[1])
    );
    // Another pair of channels is not followed: it searches in place.
    let other = "async function startProgram() {\n  startIRFollow(2, 3);\n  await delay(8);\n}\n";
    let s = fleet(&[Model::Bolt, Model::Bolt], &[BROADCASTER, other]).await;
    assert!((gap(&s) - 52.7).abs() < 1.0, "{}", gap(&s));
}

#[tokio::test(start_paused = true)]
async fn an_evader_rolls_away_and_stops_when_told_or_when_the_program_ends() {
    // Evading 3 s, then stopped by the program: it holds still after.
    let evader = "async function startProgram() {\n  startIREvade(0, 1);\n  await delay(3);\n  \
                  stopIREvade();\n  await delay(0.5);\n  const a = getLocation();\n  \
                  await delay(2);\n  const b = getLocation();\n  \
                  speak(\"moved \" + Math.round(Math.hypot(b.x - a.x, b.y - a.y)), false);\n}\n";
    let s = fleet(&[Model::Bolt, Model::Bolt], &[BROADCASTER, evader]).await;
    let g = gap(&s);
    assert!(g > 100.0, "from 52.7 cm to {g} cm");
    assert!(x(&s[1]) > 45.0, "away along +x: {}", x(&s[1]));
    assert!(
        s[1].said.iter().any(|l| l.contains("says \"moved 0\"")),
        "{:?}",
        s[1].said
    );
    // Evading when the program ends: droidctl stops it, the robot stays where it ended.
    let evader = "async function startProgram() {\n  startIREvade(0, 1);\n  await delay(1);\n}\n";
    let broadcaster =
        "async function startProgram() {\n  startIRBroadcast(0, 1);\n  await delay(1);\n}\n";
    let s = fleet(&[Model::Bolt, Model::Bolt], &[broadcaster, evader]).await;
    assert!(x(&s[1]) > 5.0, "it was evading: {}", x(&s[1]));
    let end = s[1].probe.state();
    tokio::time::sleep(Duration::from_secs(3)).await;
    let later = s[1].probe.state();
    assert!(
        (later.x_cm - end.x_cm).abs() < 2.0 && later.velocity_cm_s == 0.0,
        "{end:?} then {later:?}"
    );
}

#[test]
fn channels_and_intensity_are_bounded_as_spherov2_bounds_them() {
    use droidctl::edu::api::{Act, Arg, Driver, Ir};
    let mut d = Driver::new(Model::Bolt);
    let n = |v: &[f64]| v.iter().map(|x| Arg::Num(*x)).collect::<Vec<_>>();
    let e = d.call("sendIRMessage", &n(&[9.0, 100.0])).unwrap();
    assert_eq!(
        e.now,
        vec![Act::Ir(Ir::Send {
            channel: 7,
            intensity: 64
        })]
    );
    let e = d.call("sendIRMessage", &n(&[-1.0, 0.0])).unwrap();
    assert_eq!(
        e.now,
        vec![Act::Ir(Ir::Send {
            channel: 0,
            intensity: 1
        })]
    );
    // Sphero Edu's order is (near, far); the wire's is [far, near].
    let e = d.call("startIRFollow", &n(&[0.0, 1.0])).unwrap();
    assert_eq!(e.now, vec![Act::Ir(Ir::Follow { far: 1, near: 0 })]);
    let e = d.call("listenForIRMessage", &n(&[4.0, 2.0, 4.0])).unwrap();
    assert_eq!(e.now, vec![Act::Ir(Ir::Listen(vec![2, 4]))]);
    assert!(d.call("listenForIRMessage", &[]).unwrap().now.is_empty());
}

/// `run A.js B.js --sim bolt,bolt`: each droid its own program, in order: the second BOLT
/// follows the first's broadcast (examples/edu/beacon.js and follow.js, as docs/edu-programs.md
/// shows them). A count that does not match the fleet, or a mission given programs, is a
/// usage error before anything is sent.
#[test]
fn each_droid_of_a_fleet_runs_its_own_program() {
    let dir = Scratch::new("edu-ir", "one-each");
    let (beacon, follow) = (example("beacon.js"), example("follow.js"));
    let out = dir.run(&["run", &beacon, &follow, "--sim", "bolt,bolt"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    // The follower says how far it went; the beacon says nothing.
    let said: Vec<&str> = text
        .lines()
        .filter(|l| l.contains("says \"followed "))
        .collect();
    assert_eq!(said.len(), 1, "{text}");
    assert!(
        said[0].contains("SB-0002"),
        "the second droid follows: {text}"
    );
    let cm: f64 = said[0]
        .split("followed ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or(0.0);
    assert!(
        cm > 20.0 && cm < 53.0,
        "rolled up to the beacon: {cm} cm in {text}"
    );
    // Three programs for two droids; two for one; a mission with a program.
    let out = dir.run(&["run", &beacon, &follow, &follow, "--sim", "bolt,bolt"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("3 programs for 2 droids"),
        "{}",
        stderr(&out)
    );
    let out = dir.run(&["run", &beacon, &follow, "--sim", "bolt"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("2 programs for one droid"),
        "{}",
        stderr(&out)
    );
    let m = dir.file("m.txt", "drive 0 50 for 1s\n");
    let out = dir.run(&["run", path(&m), &follow, "--sim", "bolt,bolt"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("is a mission script"),
        "{}",
        stderr(&out)
    );
    // A syntax error in the second program: exit 2 naming it, before anything is sent.
    let bad = dir.file(
        "bad.js",
        "async function startProgram() {\n  roll(0, 50, 1\n}\n",
    );
    let out = dir.run(&["run", &beacon, path(&bad), "--sim", "bolt,bolt"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("bad.js:3:"), "{}", stderr(&out));
}
