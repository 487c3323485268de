//! Every simulated model as spherov2's Sphero Edu API drives it (issue 32), in process and in
//! simulated time: the commands droidctl's own family layer builds, encoded by the model's
//! codec, straight into the simulated droid; what comes back read by the same codec.
//!
//! - `spin(360, 1)` turns one whole revolution and never turns back (each model at its own
//!   turn rate; the body follows the commanded heading unwrapped);
//! - a head-on hit is reported on the robot's forward axis (y), v2 and v1 alike;
//! - v1 raw motors drive, open-loop, turning with the difference of the two sides;
//! - Ollie streams its locator a quarter turn round (as spherov2 reads it) and droidctl reads
//!   it back in the room's axes.
//!
//! tests/sphero_edu_models.rs runs spherov2 itself against the same simulators.

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::family::{self, Codec, Command, Family, Incoming};
use droidctl::model::Model;
use droidctl::protocol::notify::{Collision, Notification};
use droidctl::protocol::v1;
use droidctl::sim::{SimConfig, WireDroid, wire_droid};
use droidctl::units::Heading;
use std::time::Duration;

const STEP: Duration = Duration::from_millis(10);

/// The simulated models spherov2's Edu API drives: every Sphero (all but Robi 42).
fn spheros() -> Vec<Model> {
    Model::ALL
        .into_iter()
        .filter(|m| droidctl::sim::simulates(*m) && *m != Model::Robi42)
        .collect()
}

/// One simulated droid with its host's codec.
struct Host {
    model: Model,
    family: &'static dyn Family,
    codec: Box<dyn Codec>,
    droid: Box<dyn WireDroid>,
    now: Duration,
    seq: u8,
    notes: Vec<(Duration, Notification)>,
    /// The body's facing after every step, unwrapped (turns counted).
    turned: Vec<f32>,
}

impl Host {
    fn new(model: Model, cfg: SimConfig) -> Host {
        let family = family::for_model(model);
        let mut h = Host {
            model,
            family,
            codec: family.codec_for(model),
            droid: wire_droid(model, cfg),
            now: Duration::ZERO,
            seq: 0,
            notes: Vec::new(),
            turned: vec![0.0],
        };
        let conn = h.droid.connect(h.now);
        assert!(conn.is_empty(), "a Sphero reads nothing on connect");
        h
    }

    /// The droid as `--sim MODEL` has it, after droidctl's own connect setup (wake, tripod,
    /// streaming every 100 ms, collision detection), settled.
    fn connected(model: Model) -> Host {
        let mut h = Host::new(model, SimConfig::for_model(model));
        for c in connect_setup(model, &SetupOptions::default()) {
            h.send(&c);
        }
        h.run(Duration::from_millis(2500));
        h.notes.clear();
        h.turned = vec![0.0];
        h
    }

    fn take(&mut self, packets: Vec<Vec<u8>>) {
        for p in packets {
            let mut found = Vec::new();
            self.codec.feed(&p, &mut found);
            for f in found {
                if let Incoming::Async { notifications, .. } = f {
                    for n in notifications.into_iter().flatten() {
                        self.notes.push((self.now, n));
                    }
                }
            }
        }
    }

    fn send(&mut self, c: &Command) {
        self.seq = self.seq.wrapping_add(1);
        let (wire, _) = self.codec.encode(c, self.seq, true);
        let out = self.droid.receive(&wire, self.now);
        self.take(out);
    }

    fn run(&mut self, d: Duration) {
        let end = self.now + d;
        while self.now < end {
            self.now += STEP;
            let out = self.droid.advance(self.now);
            self.take(out);
            let yaw = self.droid.state().yaw_deg;
            let last = *self.turned.last().unwrap();
            let step = (yaw - last).rem_euclid(360.0);
            let step = if step > 180.0 { step - 360.0 } else { step };
            self.turned.push(last + step);
        }
    }

    /// spherov2's `SpheroEduAPI.spin(angle, duration)`: from heading `start`, the target
    /// heading moves by round(elapsed / duration × angle) at every write it can make (the
    /// model's write pacing), with the duration at least its `time_pre_rev` per turn.
    fn spin(&mut self, start: u16, angle: i32, duration: f32) {
        let pre_rev = match self.model {
            Model::Rvr => 1.5,
            Model::R2D2 | Model::R2Q5 => 0.7,
            Model::Mini => 0.5,
            // spherov2's BB8 and Sprk2 classes derive from its Ollie.
            Model::Ollie | Model::BB8 | Model::SprkPlus => 0.6,
            _ => 0.45,
        };
        let duration = duration.max(pre_rev * angle.unsigned_abs() as f32 / 360.0);
        let pace = self.model.write_pacing();
        let (mut heading, mut gone, mut t) = (start as i32, 0i32, 0.0f32);
        while gone < angle.abs() {
            let delta = ((t / duration).min(1.0) * angle.abs() as f32).round() as i32 - gone;
            heading += delta * angle.signum();
            gone += delta;
            let c = self
                .family
                .drive(0, Heading::wrapped(heading as f64), false);
            self.send(&c);
            self.run(pace);
            t += pace.as_secs_f32();
        }
    }

    fn collisions(&self) -> Vec<Collision> {
        self.notes
            .iter()
            .filter_map(|(_, n)| match n {
                Notification::Collision(c) => Some(*c),
                _ => None,
            })
            .collect()
    }

    fn last_sample(&self, name: &str) -> f32 {
        self.notes
            .iter()
            .rev()
            .find_map(|(_, n)| match n {
                Notification::Sensors(s) => s.get(name),
                _ => None,
            })
            .unwrap_or_else(|| panic!("{:?} streamed no {name}", self.model))
    }
}

/// Issue 32 point 1 (issue 29 point 5): `spin(360, 1)` turns one revolution on every model,
/// and the body never turns back on the way.
#[test]
fn spin_360_turns_a_whole_revolution_on_every_model_without_turning_back() {
    for model in spheros() {
        let mut h = Host::connected(model);
        h.spin(0, 360, 1.0);
        h.run(Duration::from_millis(1500));
        let turned = *h.turned.last().unwrap();
        assert!(
            (turned - 360.0).abs() < 3.0,
            "{model:?} turned {turned}° for a spin of 360°"
        );
        let back = h
            .turned
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(0.0f32, f32::min);
        assert!(back > -0.01, "{model:?} turned back by {back}° in a step");
        // And the other way round.
        let mut h = Host::connected(model);
        h.spin(0, -360, 1.0);
        h.run(Duration::from_millis(1500));
        let turned = *h.turned.last().unwrap();
        assert!((turned + 360.0).abs() < 3.0, "{model:?} turned {turned}°");
    }
}

/// Issue 32 point 1: the body tracks the commanded heading unwrapped, so even a droid
/// turning at a generic 180°/s (slower than spherov2's spin pace, which then runs more than
/// half a turn ahead of it) finishes the revolution instead of taking the short way back.
#[test]
fn a_body_that_falls_half_a_turn_behind_a_spin_keeps_turning_the_same_way() {
    for model in [Model::Bolt, Model::BB8] {
        let cfg = SimConfig {
            turn_rate_deg_s: 180.0,
            ..SimConfig::for_model(model)
        };
        let mut h = Host::new(model, cfg);
        for c in connect_setup(model, &SetupOptions::default()) {
            h.send(&c);
        }
        h.run(Duration::from_millis(500));
        h.turned = vec![0.0];
        h.spin(0, 360, 1.0);
        h.run(Duration::from_secs(2));
        let turned = *h.turned.last().unwrap();
        assert!((turned - 360.0).abs() < 3.0, "{model:?} turned {turned}°");
        let min_step = h.turned.windows(2).map(|w| w[1] - w[0]).fold(0.0, f32::min);
        assert!(min_step > -0.01, "{model:?} turned back");
    }
}

/// Issue 32 point 2: rolling at heading 90 into the east wall (and at 0 into the north one)
/// is a head-on hit: on the robot's forward axis, y, braking; v2 `collision-detected` and
/// v1 async 0x07 alike.
#[test]
fn a_head_on_hit_is_on_the_forward_axis_on_every_model() {
    for model in spheros() {
        if model == Model::Rvr {
            // RVR has no collision detection (spherov2 binds none to it).
            continue;
        }
        for heading in [90u16, 0, 270] {
            let mut h = Host::connected(model);
            let mut hit = None;
            for _ in 0..20 {
                let c = h.family.drive(200, Heading::new(heading).unwrap(), false);
                h.send(&c);
                h.run(Duration::from_millis(400));
                if let Some(c) = h.collisions().first() {
                    hit = Some(*c);
                    break;
                }
            }
            let c = hit.unwrap_or_else(|| panic!("{model:?} at {heading}: no collision"));
            assert!(
                c.axis.y && !c.axis.x,
                "{model:?} heading {heading}: head-on is on y: {c:?}"
            );
            assert!(c.accel[1].g() < -1.0, "{model:?}: braking ahead: {c:?}");
            assert!(c.accel[0].g().abs() < 0.3, "{model:?}: {c:?}");
        }
    }
}

/// Issue 32 point 3: on BB-8, SPRK+ and Ollie, stabilisation off and Set Raw Motors forward
/// 80 / forward 80 drive the droid forward; unequal sides turn it toward the slower one.
#[test]
fn v1_raw_motors_drive_open_loop() {
    use v1::MotorMode::{Forward, Off};
    for model in [Model::BB8, Model::SprkPlus, Model::Ollie] {
        let mut h = Host::connected(model);
        h.send(&v1::cmd::set_stabilization(false).into());
        for _ in 0..3 {
            h.send(&v1::cmd::set_raw_motors(Forward, 80, Forward, 80).into());
            h.run(Duration::from_millis(500));
        }
        let s = h.droid.state().clone();
        assert!(s.y_cm > 40.0, "{model:?} drove ahead: {s:?}");
        assert!(s.x_cm.abs() < 1.0, "{model:?} straight on: {s:?}");
        assert!(s.yaw_deg.abs() < 0.01, "{model:?}: {s:?}");
        // The left side faster: the droid turns right (clockwise), and keeps moving.
        h.send(&v1::cmd::set_raw_motors(Forward, 120, Forward, 60).into());
        h.run(Duration::from_millis(300));
        let turned = *h.turned.last().unwrap();
        assert!(turned > 20.0, "{model:?} turned {turned}° to the right");
        let t = h.droid.state().clone();
        assert!(t.x_cm > s.x_cm && t.y_cm > s.y_cm, "{model:?}: {t:?}");
        // Off stops the motors: the droid coasts to a stop.
        h.send(&v1::cmd::set_raw_motors(Off, 0, Off, 0).into());
        h.run(Duration::from_secs(1));
        assert_eq!(h.droid.state().velocity_cm_s, 0.0, "{model:?}");
        // Motors left running stop when the droid sleeps, and stay stopped once it wakes.
        h.send(&v1::cmd::set_raw_motors(Forward, 80, Forward, 80).into());
        h.run(Duration::from_millis(500));
        h.send(&v1::cmd::sleep(0, 0, 0).into());
        h.send(&v1::cmd::ping().into());
        h.run(Duration::from_secs(1));
        let at = h.droid.state().clone();
        h.run(Duration::from_secs(1));
        assert_eq!(
            h.droid.state().y_cm,
            at.y_cm,
            "{model:?} still after waking"
        );
    }
}

/// Issue 32 point 4: an Ollie rolling east streams its locator a quarter turn round, as
/// spherov2 reads a `2B-` robot ((x, y) → (−y, x)); droidctl's codec for an Ollie reads it
/// back east. BB-8 streams the room's axes as they are.
#[test]
fn ollie_streams_its_locator_turned_and_droidctl_reads_it_back() {
    for model in [Model::Ollie, Model::BB8] {
        let mut h = Host::connected(model);
        // A model-less codec beside it reads the wire as it is.
        let mut raw = family::for_model(model).codec();
        for c in connect_setup(model, &SetupOptions::default()) {
            raw.encode(&c, 0, true);
        }
        let c = h.family.drive(100, Heading::new(90).unwrap(), false);
        h.send(&c);
        h.run(Duration::from_millis(1500));
        let (x, y) = (h.last_sample("locator_x"), h.last_sample("locator_y"));
        let (vx, vy) = (h.last_sample("velocity_x"), h.last_sample("velocity_y"));
        assert!(x > 50.0 && y.abs() < 2.0, "{model:?} read east: ({x}, {y})");
        assert!(vx > 40.0 && vy.abs() < 2.0, "{model:?}: ({vx}, {vy})");
        let out = h.droid.advance(h.now + Duration::from_millis(200));
        let mut found = Vec::new();
        for p in &out {
            raw.feed(p, &mut found);
        }
        let wire = found
            .iter()
            .filter_map(|f| match f {
                Incoming::Async { notifications, .. } => Some(notifications),
                _ => None,
            })
            .flatten()
            .find_map(|n| match n {
                Ok(Notification::Sensors(s)) => Some((s.get("locator_x")?, s.get("locator_y")?)),
                _ => None,
            })
            .expect("a sample");
        if model == Model::Ollie {
            assert!(
                wire.0.abs() < 2.0 && wire.1 < -50.0,
                "an Ollie rolling east streams (0, -d): {wire:?}"
            );
        } else {
            assert!(wire.0 > 50.0 && wire.1.abs() < 2.0, "{wire:?}");
        }
    }
}

/// The figures each model simulates with (issue 32 point 1): the Mini is 4.2 cm across, not
/// 20, so it rolls up to 2.1 cm from a wall.
#[test]
fn each_model_meets_the_wall_at_its_own_radius() {
    for (model, radius) in [
        (Model::Mini, 2.1f32),
        (Model::Bolt, 3.65),
        (Model::R2D2, 6.0),
    ] {
        let mut h = Host::connected(model);
        for _ in 0..20 {
            let c = h.family.drive(200, Heading::new(0).unwrap(), false);
            h.send(&c);
            h.run(Duration::from_millis(400));
        }
        let y = h.droid.state().y_cm;
        assert!((y - (200.0 - radius)).abs() < 0.01, "{model:?} at y {y}");
    }
}

/// Issue 29 point 5: BOLT says its scrolling text is done when every column has scrolled,
/// one a frame at the speed's frames per second: one character's 8 columns at 10 frames/s
/// take 0.8 s (it said done after 0.19 s for three), eight characters 6.4 s.
#[test]
fn bolt_says_scrolling_text_is_done_after_a_frame_per_column() {
    use droidctl::protocol::notify::RobotEvent;
    use droidctl::protocol::v2::{cmd, types::ScrollText};
    for (text, fps, takes) in [
        ("A", 10u8, 800u64),
        ("ABC", 10, 2400),
        ("DROIDCTL", 10, 6400),
    ] {
        let mut h = Host::connected(Model::Bolt);
        let sent = h.now;
        let scroll = cmd::set_compressed_frame_player_text_scrolling(
            0,
            255,
            0,
            fps,
            false,
            ScrollText(text.into()),
        );
        h.send(&scroll.into());
        h.run(Duration::from_secs(8));
        let done: Vec<Duration> = h
            .notes
            .iter()
            .filter(|(_, n)| matches!(n, Notification::Robot(RobotEvent::MatrixTextDone)))
            .map(|(at, _)| *at - sent)
            .collect();
        assert_eq!(done.len(), 1, "{text}: {done:?}");
        let ms = done[0].as_millis() as u64;
        assert!(
            (takes..takes + 20).contains(&ms),
            "{text} at {fps} frames/s: done after {ms} ms, not {takes}"
        );
    }
}
