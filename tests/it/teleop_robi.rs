//! The control loop on a steering robot (Robi 42), tick by tick: forward is velocity at cruise
//! with the steering straight, the turn keys and the stick's sideways part steer, reverse is
//! refused (speed held at 0, one "cannot reverse" hint per press), release and e-stop stop.

use droidctl::config::Action;
use droidctl::config::{Config, DriveMode};
use droidctl::family::intent::{Intent, lower};
use droidctl::family::{Command, RobiControl};
use droidctl::model::Model;
use droidctl::telemetry::Stance;
use droidctl::teleop::control::{Controller, DroidView, Inputs, Out};
use droidctl::teleop::gamepad::PadDrive;
use std::time::Duration;

const TICK: Duration = Duration::from_millis(50);

/// Robi as the app describes it to the controller: no legs, no dome, nothing to aim.
const ROBI: DroidView = DroidView {
    connected: true,
    has_legs: false,
    has_dome: false,
    can_aim: false,
    stance: Stance::Unknown,
};

fn controller() -> Controller {
    Controller::with_family(
        Config::defaults().control,
        droidctl::family::for_model(Model::Robi42),
    )
}

fn latched() -> Controller {
    let mut cfg = Config::defaults().control;
    cfg.mode = DriveMode::Latched;
    Controller::with_family(cfg, droidctl::family::for_model(Model::Robi42))
}

fn rc(velocity: u8, steering: u8) -> RobiControl {
    RobiControl { velocity, steering }
}

/// The remote-control values among the outputs; anything else driving is a failure.
fn drives(out: &[Out]) -> Vec<RobiControl> {
    out.iter()
        .filter_map(|o| match o {
            // Motion, as Robi's family lowers it.
            Out::Do(
                i @ (Intent::Drive { .. }
                | Intent::Steer { .. }
                | Intent::Stop { .. }
                | Intent::RawMotors { .. }),
            ) => match lower(Model::Robi42, i).as_deref() {
                Ok([Command::Robi(c)]) => Some(*c),
                other => panic!("a Robi controller drives with RobiControl: {i:?} {other:?}"),
            },
            _ => None,
        })
        .collect()
}

fn hints(out: &[Out]) -> Vec<String> {
    out.iter()
        .filter_map(|o| match o {
            Out::Hint(h) => Some(h.clone()),
            _ => None,
        })
        .collect()
}

fn cannot_reverse(out: &[Out]) -> usize {
    hints(out)
        .iter()
        .filter(|h| h.contains("cannot reverse"))
        .count()
}

fn keys(forward: bool, backward: bool, left: bool, right: bool) -> Inputs {
    Inputs {
        forward,
        backward,
        left,
        right,
        ..Inputs::default()
    }
}

fn pad(heading: f32, speed: u8) -> Inputs {
    Inputs {
        pad: Some((
            PadDrive {
                heading,
                magnitude: speed as f32 / 255.0,
            },
            speed,
        )),
        ..Inputs::default()
    }
}

const FWD: Inputs = Inputs {
    forward: true,
    backward: false,
    left: false,
    right: false,
    dome_left: false,
    dome_right: false,
    estop: false,
    pad: None,
    pad_dome_rate: 0.0,
    pad_tracks: None,
};

#[test]
fn forward_is_cruise_velocity_with_the_steering_straight() {
    let cruise = Config::defaults().control.cruise_speed;
    assert_eq!(cruise, 100);
    let mut c = controller();
    assert_eq!(drives(&c.tick(&FWD, TICK, &ROBI, true)), [rc(cruise, 128)]);
    // Re-sent on the heartbeat while held, unchanged.
    assert_eq!(drives(&c.tick(&FWD, TICK, &ROBI, true)), [rc(cruise, 128)]);
    assert!(drives(&c.tick(&FWD, TICK, &ROBI, false)).is_empty());
    let v = c.view();
    assert_eq!((v.speed, v.reverse, v.deadman), (cruise, false, false));
    assert_eq!(v.steer, Some(0.0));
    assert_eq!(v.source, "keyboard");
    // Faster and turbo change the velocity byte.
    c.on_press(Action::Faster, &ROBI);
    let step = Config::defaults().control.speed_step;
    assert_eq!(
        drives(&c.tick(&FWD, TICK, &ROBI, true)),
        [rc(cruise + step, 128)]
    );
    c.on_press(Action::Turbo, &ROBI);
    let turbo = Config::defaults().control.turbo_speed;
    assert_eq!(drives(&c.tick(&FWD, TICK, &ROBI, true)), [rc(turbo, 128)]);
}

#[test]
fn the_turn_keys_steer_left_below_128_and_right_above() {
    let mut c = controller();
    let left = drives(&c.tick(&keys(true, false, true, false), TICK, &ROBI, true));
    // ±0.6 of full lock: 127.5 ∓ 76.5.
    assert_eq!(left, [rc(100, 51)]);
    assert_eq!(c.view().steer, Some(-0.6));
    let right = drives(&c.tick(&keys(true, false, false, true), TICK, &ROBI, true));
    assert_eq!(right, [rc(100, 204)]);
    assert_eq!(c.view().steer, Some(0.6));
    // Both turn keys cancel out.
    assert_eq!(
        drives(&c.tick(&keys(true, false, true, true), TICK, &ROBI, true)),
        [rc(100, 128)]
    );
    // Holding a turn key for long does not steer harder (no heading to wind up).
    for _ in 0..40 {
        c.tick(&keys(true, false, false, true), TICK, &ROBI, false);
    }
    assert_eq!(
        drives(&c.tick(&keys(true, false, false, true), TICK, &ROBI, true)),
        [rc(100, 204)]
    );
    // A turn key alone does not drive: velocity 0 whatever the steering.
    let mut c = controller();
    let out = drives(&c.tick(&keys(false, false, false, true), TICK, &ROBI, true));
    assert!(out.iter().all(|d| d.velocity == 0), "{out:?}");
    assert_eq!(c.view().speed, 0);
}

#[test]
fn backward_holds_speed_0_with_one_hint_per_press() {
    let mut c = controller();
    let back = keys(false, true, false, false);
    let mut said = 0;
    for _ in 0..20 {
        let out = c.tick(&back, TICK, &ROBI, true);
        assert!(drives(&out).iter().all(|d| d.velocity == 0), "{out:?}");
        said += cannot_reverse(&out);
        let v = c.view();
        assert_eq!((v.speed, v.reverse), (0, false));
    }
    assert_eq!(said, 1, "said once while held");
    let hint = hints(&controller().tick(&back, TICK, &ROBI, true)).join("");
    assert_eq!(hint, "this robot cannot reverse — it only drives forward");
    // Steering while "reversing" does not drive either.
    let out = c.tick(&keys(false, true, true, false), TICK, &ROBI, true);
    assert!(drives(&out).iter().all(|d| d.velocity == 0), "{out:?}");
    assert_eq!(cannot_reverse(&out), 0);
    // Released, then pressed again: said again, once.
    c.tick(&Inputs::default(), TICK, &ROBI, true);
    let mut said = 0;
    for _ in 0..5 {
        said += cannot_reverse(&c.tick(&back, TICK, &ROBI, true));
    }
    assert_eq!(said, 1);
    // Forward again works at once.
    c.tick(&Inputs::default(), TICK, &ROBI, true);
    assert_eq!(drives(&c.tick(&FWD, TICK, &ROBI, true)), [rc(100, 128)]);
}

#[test]
fn backward_while_driving_forward_stops_it() {
    let mut c = controller();
    c.tick(&FWD, TICK, &ROBI, true);
    // Forward and backward together: no drive input, speed 0.
    let out = c.tick(&keys(true, true, false, false), TICK, &ROBI, true);
    assert_eq!(drives(&out), [rc(0, 128)]);
    // Forward let go, backward held: still 0, and the refusal is said.
    let out = c.tick(&keys(false, true, false, false), TICK, &ROBI, true);
    assert!(drives(&out).iter().all(|d| d.velocity == 0), "{out:?}");
    assert_eq!(cannot_reverse(&out), 1);
}

#[test]
fn release_stops_once_with_the_steering_straight() {
    let mut c = controller();
    c.tick(&keys(true, false, false, true), TICK, &ROBI, true);
    assert_eq!(
        drives(&c.tick(&Inputs::default(), TICK, &ROBI, true)),
        [rc(0, 128)]
    );
    assert!(drives(&c.tick(&Inputs::default(), TICK, &ROBI, true)).is_empty());
    assert!(c.view().deadman);
}

#[test]
fn estop_stops_at_once_and_holds_while_held() {
    let mut c = controller();
    c.tick(&keys(true, false, true, false), TICK, &ROBI, true);
    let stop = drives(&[Out::Do(c.estop_now())]);
    assert_eq!(stop, [RobiControl::STOP]);
    let held = Inputs { estop: true, ..FWD };
    for _ in 0..5 {
        let out = c.tick(&held, TICK, &ROBI, true);
        assert!(drives(&out).iter().all(|d| d.velocity == 0), "{out:?}");
        assert!(c.view().estop);
    }
    // E-stop let go: forward still held drives again.
    assert_eq!(drives(&c.tick(&FWD, TICK, &ROBI, true)), [rc(100, 128)]);
    // The e-stop key in latched mode drops the latched speed.
    let mut c = latched();
    c.on_press(Action::Forward, &ROBI);
    c.on_press(Action::Forward, &ROBI);
    let step = Config::defaults().control.speed_step;
    assert_eq!(
        drives(&c.tick(&Inputs::default(), TICK, &ROBI, true)),
        [rc(2 * step, 128)]
    );
    let out = c.on_press(Action::EStop, &ROBI);
    assert_eq!(drives(&out), [RobiControl::STOP]);
    let out = c.tick(&Inputs::default(), TICK, &ROBI, true);
    assert!(drives(&out).iter().all(|d| d.velocity == 0), "{out:?}");
}

#[test]
fn the_stick_steers_with_its_sideways_part_and_refuses_back() {
    let mut c = controller();
    // Up and to the right: speed from the stick, steering 128 + 127·sin 45°.
    assert_eq!(
        drives(&c.tick(&pad(45.0, 150), TICK, &ROBI, true)),
        [rc(150, 218)]
    );
    assert_eq!(c.view().source, "gamepad");
    // Straight left: full lock left.
    assert_eq!(
        drives(&c.tick(&pad(270.0, 120), TICK, &ROBI, true)),
        [rc(120, 0)]
    );
    // Pulled back: speed 0 and the refusal, once while held.
    let mut said = 0;
    for h in [180.0, 200.0, 160.0, 180.0] {
        let out = c.tick(&pad(h, 200), TICK, &ROBI, true);
        assert!(drives(&out).iter().all(|d| d.velocity == 0), "{h}: {out:?}");
        said += cannot_reverse(&out);
    }
    assert_eq!(said, 1);
    // Let go (deadzone): stopped and straight (already sent while pulled back); pulled back
    // again: said again.
    let out = c.tick(&Inputs::default(), TICK, &ROBI, true);
    assert!(drives(&out).iter().all(|d| *d == rc(0, 128)), "{out:?}");
    assert_eq!(c.view().speed, 0);
    assert_eq!(
        cannot_reverse(&c.tick(&pad(180.0, 200), TICK, &ROBI, true)),
        1
    );
}

#[test]
fn latched_mode_never_goes_below_0() {
    let mut c = latched();
    // A backward press from standstill: refused, said, speed stays 0.
    c.on_press(Action::Backward, &ROBI);
    let out = c.tick(&Inputs::default(), TICK, &ROBI, true);
    assert!(drives(&out).iter().all(|d| d.velocity == 0), "{out:?}");
    assert_eq!(cannot_reverse(&out), 1);
    assert_eq!(
        cannot_reverse(&c.tick(&Inputs::default(), TICK, &ROBI, true)),
        0
    );
    // A forward press then drives at one step, not back up to 0 from −1 step.
    let step = Config::defaults().control.speed_step;
    c.on_press(Action::Forward, &ROBI);
    assert_eq!(
        drives(&c.tick(&Inputs::default(), TICK, &ROBI, true)),
        [rc(step, 128)]
    );
    // Backward while moving forward slows down (no refusal), down to 0.
    c.on_press(Action::Backward, &ROBI);
    let out = c.tick(&Inputs::default(), TICK, &ROBI, true);
    assert_eq!(drives(&out), [rc(0, 128)]);
    assert_eq!(cannot_reverse(&out), 0);
    // Once more: that would be reverse; refused and said again (a new press).
    c.on_press(Action::Backward, &ROBI);
    let out = c.tick(&Inputs::default(), TICK, &ROBI, true);
    assert_eq!(cannot_reverse(&out), 1);
    assert_eq!(c.view().speed, 0);
}

#[test]
fn nothing_is_sent_while_disconnected_and_a_stop_after_the_link_returns() {
    let mut c = controller();
    c.tick(&FWD, TICK, &ROBI, true);
    let down = DroidView {
        connected: false,
        ..ROBI
    };
    assert!(c.tick(&FWD, TICK, &down, true).is_empty());
    assert_eq!(c.view().speed, 0);
    c.link_lost();
    // Back, nothing held: a stop, straight.
    assert_eq!(
        drives(&c.tick(&Inputs::default(), TICK, &ROBI, true)),
        [rc(0, 128)]
    );
}

#[test]
fn no_aim_no_legs_on_robi() {
    let mut c = controller();
    let out = c.on_press(Action::Aim, &ROBI);
    assert_eq!(hints(&out), ["this droid has no aim mode"]);
    assert!(!c.aiming());
    let out = c.on_press(Action::Tripod, &ROBI);
    assert_eq!(hints(&out), ["this droid has no legs"]);
}

/// What the robot's firmware makes of a family steer command: each wheel 0..=1.
fn wheels_for(speed: u8, turn: f32) -> (f32, f32) {
    match droidctl::family::for_model(Model::Robi42).steer(speed, turn) {
        Some(Command::Robi(c)) => droidctl::protocol::rsrcp::wheel_speeds(c.velocity, c.steering),
        other => panic!("Robi steers with RobiControl: {other:?}"),
    }
}

#[test]
fn full_lock_stops_the_inner_wheel_either_way_and_turns_mirror() {
    // Full right: the right wheel stands; full left: the left wheel stands (steering byte 0,
    // `droid-facts.md` §5: 0 full left, 1 full right).
    assert_eq!(wheels_for(255, 1.0), (1.0, 0.0));
    assert_eq!(wheels_for(255, -1.0), (0.0, 1.0));
    assert_eq!(wheels_for(100, -1.0).0, 0.0);
    // A turn to the left is the mirror image of the same turn to the right.
    for t in [0.25f32, 0.5, 0.6, 1.0] {
        let (rl, rr) = wheels_for(200, t);
        let (ll, lr) = wheels_for(200, -t);
        assert!(
            (rl - lr).abs() < 1e-6 && (rr - ll).abs() < 1e-6,
            "{t}: right ({rl}, {rr}) left ({ll}, {lr})"
        );
    }
}
