//! Issue 31 on simulated droids under paused time: readiness (a drive sent once the link
//! says ready moves the droid), a stop that does not turn the droid, samples only when the
//! droid reported something new and the rate said, ROS's twist shape, capped speeds and
//! odometry.

use super::schema::{self, Cmd, Odom, Out};
use super::tests::{RigOptions, rig, rig_with, run_for};
use super::*;

/// Everything out so far.
fn all(r: &mut super::tests::Rig) -> Vec<Out> {
    std::iter::from_fn(|| r.rx.try_recv().ok()).collect()
}

fn note_of(said: &[Out], want: i64) -> Option<String> {
    said.iter().find_map(|o| match o {
        Out::Reply { id, note, .. } if *id == want => Some(note.clone().unwrap_or_default()),
        _ => None,
    })
}

/// The droid's position and heading as its telemetry says.
fn pose(b: &Bridge, i: usize) -> (f32, f32, Option<u16>) {
    let t = b.fleet().telemetry(i).unwrap();
    let t = t.borrow();
    (
        t.x_cm.unwrap_or(0.0),
        t.y_cm.unwrap_or(0.0),
        t.heading().map(|h| h.degrees()),
    )
}

#[tokio::test(start_paused = true)]
async fn r2d2_is_ready_once_on_three_legs_and_a_drive_then_moves_it() {
    let mut r = rig(&[Model::R2D2], 10_000).await;
    let t0 = r.now();
    // Just connected: not ready, and a drive now is held (said in its reply).
    assert!(!r.bridge.is_ready(0));
    r.send(r#"{"v":1,"cmd":"drive","speed":120,"heading":90,"id":1}"#);
    run_for(20).await;
    let note = note_of(&r.said(), 1).expect("a reply");
    assert!(
        note.contains("not ready") && note.contains("three legs"),
        "{note}"
    );
    // It does not move until it is ready, however long the drive is held.
    let mut ready_at = None;
    for _ in 0..600 {
        run_for(10).await;
        if r.bridge.is_ready(0) {
            ready_at = Some(r.now() - t0);
            break;
        }
        let (x, _, _) = pose(&r.bridge, 0);
        assert!(x.abs() < 0.5, "moved before ready: x {x}");
    }
    let ready_at = ready_at.expect("ready within 6 s");
    // The stance change takes 2 s after the setup's first commands.
    assert!(
        ready_at >= Duration::from_millis(1800) && ready_at <= Duration::from_millis(4500),
        "ready after {ready_at:?}"
    );
    let objs = all(&mut r);
    assert!(
        objs.iter().any(|o| matches!(
            o,
            Out::Link {
                state: "connected",
                ready: true,
                ..
            }
        )),
        "no ready link object: {objs:?}"
    );
    // The held drive moves it at once.
    run_for(600).await;
    let (x, _, _) = pose(&r.bridge, 0);
    assert!(x > 5.0, "not moving 0.6 s after ready: x {x}");
    // Stopped, then one drive sent now moves it within half a second.
    r.send(r#"{"v":1,"cmd":"stop"}"#);
    run_for(1500).await;
    let (x0, _, _) = pose(&r.bridge, 0);
    r.send(r#"{"v":1,"cmd":"drive","speed":120,"heading":90,"id":2}"#);
    run_for(500).await;
    let (x1, _, _) = pose(&r.bridge, 0);
    assert!(
        x1 - x0 > 3.0,
        "a drive once ready did not move it: {x0} → {x1}"
    );
    assert_eq!(
        note_of(&r.said(), 2),
        Some(String::new()),
        "no note once ready"
    );
}

#[tokio::test(start_paused = true)]
async fn a_droid_without_legs_is_ready_after_its_setup() {
    let mut r = rig(&[Model::Bolt, Model::BB8, Model::Robi42], 600).await;
    run_for(1500).await;
    assert!((0..3).all(|i| r.bridge.is_ready(i)));
    let ready: Vec<_> = all(&mut r)
        .into_iter()
        .filter(|o| matches!(o, Out::Link { ready: true, .. }))
        .collect();
    assert_eq!(ready.len(), 3, "{ready:?}");
}

fn turned(a: u16, b: u16) -> u16 {
    let d = (i32::from(a) - i32::from(b)).rem_euclid(360) as u16;
    d.min(360 - d)
}

#[tokio::test(start_paused = true)]
async fn after_a_timeout_stop_the_droid_does_not_turn_on_to_the_last_heading() {
    let mut r = rig(&[Model::R2D2], 600).await;
    run_for(3500).await;
    assert!(r.bridge.is_ready(0));
    // Spinning faster than the droid turns (4 rad/s, 229°/s; the simulator turns 180°/s):
    // the integrated heading runs ahead of the droid's, more and more.
    for _ in 0..10 {
        r.send(r#"{"v":1,"cmd":"twist","linear":0,"angular":4}"#);
        run_for(100).await;
    }
    // The timeout stops it.
    let mut stopped = false;
    for _ in 0..100 {
        run_for(10).await;
        if r.said().iter().any(|o| {
            matches!(
                o,
                Out::Stopped {
                    reason: "timeout",
                    ..
                }
            )
        }) {
            stopped = true;
            break;
        }
    }
    assert!(stopped, "no timeout stop");

    // Where it is when stopped, it stays.
    let (_, _, h0) = pose(&r.bridge, 0);
    run_for(2000).await;
    let (_, _, h1) = pose(&r.bridge, 0);
    let (h0, h1) = (h0.expect("a heading"), h1.expect("a heading"));
    assert!(
        turned(h0, h1) <= 5,
        "turned from {h0} to {h1} after stopping"
    );
}

#[tokio::test(start_paused = true)]
async fn samples_go_out_only_when_the_droid_reported_something_new() {
    let o = RigOptions {
        telemetry_hz: Some(100),
        ..RigOptions::default()
    };
    // BOLT streams at 10/s (the setup's 100 ms): 100/s asked, 10 offered.
    let mut r = rig_with(&[Model::Bolt], 600, o).await;
    let Out::Hello {
        telemetry_hz,
        droids,
        ..
    } = r.bridge.hello()
    else {
        panic!("hello")
    };
    assert_eq!((telemetry_hz, droids[0].telemetry_hz), (10, 10));
    run_for(1000).await;
    let _ = all(&mut r);
    run_for(2000).await;
    let samples: Vec<u64> = all(&mut r)
        .into_iter()
        .filter_map(|o| match o {
            Out::Telemetry { sample, .. } => Some(sample.t_ms),
            _ => None,
        })
        .collect();
    assert!(
        (15..=25).contains(&samples.len()),
        "{} samples in 2 s: {samples:?}",
        samples.len()
    );
    // A rate not offered says which are.
    r.send(r#"{"v":1,"cmd":"stream","rate_hz":5,"id":1}"#);
    run_for(2000).await;
    let said = all(&mut r);
    let note = note_of(&said, 1).expect("a reply");
    assert!(note.contains("offered") && note.contains("10"), "{note}");
    // The new rate is said in an info object.
    let info = said.iter().find_map(|o| match o {
        Out::Info { info, .. } => Some(info.telemetry_hz),
        _ => None,
    });
    assert_eq!(info, Some(1), "{said:?}");
}

#[test]
fn the_ros_twist_shape_is_the_flat_one_and_sideways_is_refused() {
    let flat = schema::parse(br#"{"v":1,"cmd":"twist","linear":0.3,"angular":-0.5}"#).unwrap();
    let ros = schema::parse(
        br#"{"v":1,"cmd":"twist","linear":{"x":0.3,"y":0,"z":0.0},"angular":{"x":0,"y":0,"z":-0.5}}"#,
    )
    .unwrap();
    assert_eq!(flat, ros);
    let short = schema::parse(br#"{"v":1,"cmd":"twist","linear":{"x":0.3},"angular":{}}"#);
    assert!(matches!(
        short.unwrap().cmd,
        Cmd::Twist { linear, angular } if linear == 0.3 && angular == 0.0
    ));
    for (bad, says) in [
        (
            r#"{"linear":{"x":0,"y":0.2,"z":0},"angular":0}"#,
            "linear.y",
        ),
        (
            r#"{"linear":0,"angular":{"x":0.1,"y":0,"z":0}}"#,
            "angular.x",
        ),
        (r#"{"linear":{"x":9},"angular":0}"#, "linear.x"),
        (r#"{"linear":{"w":1},"angular":0}"#, "`w`"),
        (r#"{"linear":{"x":"1"},"angular":0}"#, "linear.x"),
    ] {
        let line = format!(r#"{{"v":1,"cmd":"twist",{}"#, &bad[1..]);
        let e = schema::parse(line.as_bytes()).unwrap_err();
        assert_eq!(e.code, schema::ErrorCode::BadField, "{line}");
        assert!(e.message.contains(says), "{line}: {}", e.message);
    }
}

#[tokio::test(start_paused = true)]
async fn a_twist_beyond_the_droids_top_speed_is_capped_and_said() {
    let mut r = rig(&[Model::BB8], 600).await;
    run_for(1500).await;
    r.send(r#"{"v":1,"cmd":"twist","linear":{"x":3.0},"angular":{"z":0},"id":1}"#);
    run_for(300).await;
    let w = r.writes(0);
    assert!(w.iter().any(|(_, s)| *s == 255), "{w:?}");
    r.send(r#"{"v":1,"cmd":"twist","linear":1.0,"angular":0,"id":2}"#);
    run_for(20).await;
    let said = r.said();
    let capped = note_of(&said, 1).expect("a reply");
    assert!(capped.contains("capped to 1.6"), "{capped}");
    assert_eq!(note_of(&said, 2), Some(String::new()));
}

#[test]
fn odometry_is_rep_103() {
    // 1 m along heading 0 (+y), 10 cm to its right (+x), facing right (90° clockwise).
    let o = Odom::from_droid(10.0, 100.0, Some(90.0));
    assert!(
        (o.x_m - 1.0).abs() < 1e-6 && (o.y_m + 0.1).abs() < 1e-6,
        "{o:?}"
    );
    let yaw = o.yaw_rad.unwrap();
    assert!((yaw + std::f32::consts::FRAC_PI_2).abs() < 1e-5, "{yaw}");
    // 270° clockwise is 90° to the left: +π/2.
    let left = Odom::from_droid(0.0, 0.0, Some(270.0)).yaw_rad.unwrap();
    assert!((left - std::f32::consts::FRAC_PI_2).abs() < 1e-5, "{left}");
}

#[tokio::test(start_paused = true)]
async fn samples_carry_odometry_of_the_droids_position() {
    let mut r = rig(&[Model::BB8], 600).await;
    run_for(1500).await;
    for _ in 0..10 {
        r.send(r#"{"v":1,"cmd":"drive","speed":100,"heading":0}"#);
        run_for(100).await;
    }
    let last = all(&mut r)
        .into_iter()
        .filter_map(|o| match o {
            Out::Telemetry { sample, odom, .. } => Some((sample, odom)),
            _ => None,
        })
        .next_back()
        .expect("samples");
    let (s, odom) = last;
    let odom = odom.expect("odom");
    assert!(s.y_cm.unwrap() > 10.0, "{s:?}");
    assert!((odom.x_m - s.y_cm.unwrap() / 100.0).abs() < 1e-6);
    assert!((odom.y_m + s.x_cm.unwrap() / 100.0).abs() < 1e-6);
}
