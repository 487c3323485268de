//! The control loop's outputs lowered by the droid's family ([`Intent`]): the wire bytes are
//! the ones the family's own drive, steer, tank and aim commands make — what the controller
//! and the app built themselves before the lowering. Over models × speeds × headings × turns
//! × tracks, and through the controller for every model over random key, stick, tank, aim
//! and e-stop input (that check was written against the controller that still built the
//! commands, and passed there). Kept as the lowering's guard.

use droidctl::config::{Action, Config};
use droidctl::family::intent::Intent;
use droidctl::family::{self, Command, Family};
use droidctl::model::{MODELS, Model};
use droidctl::telemetry::Stance;
use droidctl::teleop::control::{Controller, DroidView, Inputs, Out};
use droidctl::teleop::gamepad::PadDrive;
use droidctl::units::Heading;
use proptest::prelude::*;
use std::time::Duration;

/// What one command is on the wire: each write with its endpoint.
fn wire(f: &dyn Family, model: Model, c: &Command) -> Vec<(droidctl::gatt::Endpoint, Vec<u8>)> {
    f.codec_for(model).encode_writes(c, 7, true).0
}

/// The one command `intent` lowers to on `model` (the app's drive slot takes one).
fn lowered(model: Model, intent: &Intent) -> Command {
    match family::intent::lower(model, intent).as_deref() {
        Ok([c]) => c.clone(),
        other => panic!("{model:?}: {intent:?} lowered to {other:?}"),
    }
}

/// The drive commands of the controller's outputs, as the droid gets them: its motion
/// intents lowered by the model's family.
fn drive_commands(model: Model, outs: &[Out]) -> Vec<Command> {
    outs.iter()
        .filter_map(|o| match o {
            Out::Do(
                i @ (Intent::Drive { .. }
                | Intent::Steer { .. }
                | Intent::RawMotors { .. }
                | Intent::Stop { .. }),
            ) => Some(lowered(model, i)),
            _ => None,
        })
        .collect()
}

/// The e-stop's command, as the droid gets it.
fn estop_command(model: Model, c: &mut Controller) -> Command {
    lowered(model, &c.estop_now())
}

/// The command the controller built itself before the lowering, from what it says it
/// commands: the tracks in tank mode, the steering on a steering robot, else the heading.
fn old_drive(f: &dyn Family, c: &Controller) -> Option<Command> {
    let v = c.view();
    match (v.tank, v.steer) {
        (Some((l, r)), _) => f.tank(l, r),
        (None, Some(turn)) => f.steer(v.speed, turn),
        (None, None) => Some(f.drive(v.speed, v.heading, v.reverse)),
    }
}

#[derive(Debug, Clone)]
enum Step {
    Keys {
        forward: bool,
        backward: bool,
        left: bool,
        right: bool,
    },
    Stick {
        heading: f32,
        speed: u8,
    },
    Tracks(f32, f32),
    Press(Action),
    EStop,
}

fn step() -> impl Strategy<Value = (Step, u16, bool)> {
    let s = prop_oneof![
        4 => (any::<bool>(), any::<bool>(), any::<bool>(), any::<bool>()).prop_map(
            |(forward, backward, left, right)| Step::Keys { forward, backward, left, right }
        ),
        2 => (0.0f32..360.0, any::<u8>()).prop_map(|(heading, speed)| Step::Stick { heading, speed }),
        2 => (-1.0f32..=1.0, -1.0f32..=1.0).prop_map(|(l, r)| Step::Tracks(l, r)),
        2 => prop::sample::select(vec![
            Action::Tank, Action::Aim, Action::Faster, Action::Slower, Action::Turbo
        ]).prop_map(Step::Press),
        1 => Just(Step::EStop),
    ];
    (s, 0u16..400, any::<bool>())
}

/// Run `steps` on a controller for `model`; every drive output's bytes checked against the
/// family's own command for the view it left.
fn check(model: Model, steps: &[(Step, u16, bool)]) -> Result<usize, String> {
    let f = family::for_model(model);
    let mut c = Controller::with_family(Config::defaults().control, f);
    c.set_tracks(model.has_tracks());
    let droid = DroidView {
        connected: true,
        has_legs: model.has_legs(),
        has_dome: model.has_dome(),
        can_aim: model.can_aim(),
        stance: Stance::Tripod,
    };
    let mut checked = 0;
    for (s, dt_ms, heartbeat) in steps {
        let mut inp = Inputs::default();
        match s {
            Step::Keys {
                forward,
                backward,
                left,
                right,
            } => {
                inp.forward = *forward;
                inp.backward = *backward;
                inp.left = *left;
                inp.right = *right;
            }
            Step::Stick { heading, speed } => {
                inp.pad = Some((
                    PadDrive {
                        heading: *heading,
                        magnitude: 0.5,
                    },
                    *speed,
                ))
            }
            Step::Tracks(l, r) => inp.pad_tracks = Some((*l, *r)),
            Step::Press(a) => {
                // A press's own outputs are hints and one-shot intents, never a drive.
                let outs = c.on_press(*a, &droid);
                if !drive_commands(model, &outs).is_empty() {
                    return Err(format!("{a:?} drove: {outs:?}"));
                }
                continue;
            }
            Step::EStop => {
                let stop = estop_command(model, &mut c);
                // Speed 0 where the droid was last told to face: the family's drive at
                // speed 0, not its stop after the last command (v1's Roll state stays Go).
                let read = f
                    .read_drive(&stop)
                    .ok_or_else(|| format!("the e-stop is not a drive: {stop:?}"))?;
                let want = f.drive(0, read.heading, false);
                if read.speed != 0 || wire(f, model, &stop) != wire(f, model, &want) {
                    return Err(format!("e-stop {stop:?}, the family's stop {want:?}"));
                }
                checked += 1;
                continue;
            }
        }
        let outs = c.tick(
            &inp,
            Duration::from_millis(*dt_ms as u64),
            &droid,
            *heartbeat,
        );
        let sent = drive_commands(model, &outs);
        if sent.len() > 1 {
            return Err(format!("{} drive commands in one tick", sent.len()));
        }
        if let Some(got) = sent.first() {
            let want = old_drive(f, &c).ok_or_else(|| {
                format!("{model:?}: the family has no command for {:?}", c.view())
            })?;
            if wire(f, model, got) != wire(f, model, &want) {
                return Err(format!(
                    "{model:?} after {s:?}: sent {got:?}, the family's own {want:?} ({:?})",
                    c.view()
                ));
            }
            checked += 1;
        }
    }
    Ok(checked)
}

/// The commands the control loop and the app built from the family's own methods before
/// the lowering (`None`: the droid has no such thing, and the controller never asked it).
fn old_path(f: &dyn Family, model: Model, intent: &Intent) -> Option<Vec<Command>> {
    match *intent {
        Intent::Drive {
            speed,
            heading,
            reverse,
        } if !f.steers() => Some(vec![f.drive(speed, heading, reverse)]),
        Intent::Steer { speed, turn } if f.steers() => f.steer(speed, turn).map(|c| vec![c]),
        Intent::Stop { heading } => Some(vec![f.drive(0, heading, false)]),
        Intent::RawMotors { left, right } if model.has_tracks() => {
            f.tank(left, right).map(|c| vec![c])
        }
        Intent::StartAim if model.can_aim() => f.aim_begin(model),
        _ => None,
    }
}

fn all_wire(
    f: &dyn Family,
    model: Model,
    cs: &[Command],
) -> Vec<(droidctl::gatt::Endpoint, Vec<u8>)> {
    cs.iter().flat_map(|c| wire(f, model, c)).collect()
}

fn models() -> impl Strategy<Value = Model> {
    prop::sample::select(MODELS.iter().map(|s| s.model).collect::<Vec<_>>())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Models × speeds × headings × turns × tracks: what the controller says lowers to the
    /// bytes the family's own methods made, wherever the controller says it.
    #[test]
    fn every_models_motion_intents_lower_to_the_bytes_of_the_old_path(
        model in models(),
        speed in any::<u8>(),
        degrees in 0u16..360,
        reverse in any::<bool>(),
        turn in prop_oneof![8 => -1.0f32..=1.0, 1 => -3.0f32..3.0, 1 => Just(f32::NAN)],
        left in -255i16..=255,
        right in -255i16..=255,
    ) {
        let f = family::for_model(model);
        let heading = Heading::wrapped(degrees as f64);
        let intents = [
            Intent::Drive { speed, heading, reverse: reverse && f.can_reverse() },
            Intent::Steer { speed, turn },
            Intent::Stop { heading },
            Intent::RawMotors { left, right },
            Intent::StartAim,
        ];
        for i in &intents {
            let Some(old) = old_path(f, model, i) else { continue };
            let new = family::intent::lower(model, i)
                .map_err(|e| TestCaseError::fail(format!("{i:?}: {e}")))?;
            prop_assert_eq!(
                all_wire(f, model, &new),
                all_wire(f, model, &old),
                "{:?} on {:?}",
                i,
                model
            );
        }
        // A robot driven toward a heading has no steering, and the others no tracks.
        prop_assert_eq!(
            family::intent::lower(model, &Intent::Steer { speed, turn }).is_ok(),
            f.steers()
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    /// Every model, random input: the bytes are the family's own.
    #[test]
    fn the_controllers_drive_is_the_familys_own_command_on_every_model(
        model in models(),
        steps in prop::collection::vec(step(), 1..50),
    ) {
        if let Err(e) = check(model, &steps) {
            return Err(TestCaseError::fail(e));
        }
    }
}

/// The checks above see real drives on every model: a steering robot steers, RVR's tracks
/// turn, a stop after a drive is sent (a run that compared nothing would pass anything).
#[test]
fn the_check_compares_steering_tracks_and_headings() {
    let keys = |forward, right| Step::Keys {
        forward,
        backward: false,
        left: false,
        right,
    };
    for spec in MODELS.iter() {
        let mut steps = vec![
            (keys(true, false), 100, true),
            (keys(true, true), 100, true),
            (keys(false, false), 100, true),
            (Step::EStop, 0, false),
        ];
        if spec.model.has_tracks() {
            steps.push((Step::Press(Action::Tank), 0, false));
            steps.push((Step::Tracks(0.5, -0.5), 100, true));
        }
        let n = check(spec.model, &steps).unwrap();
        assert!(n >= 4, "{:?}: {n} commands compared", spec.model);
    }
    // The steering robot's turn is a fraction: 0.6 of full lock is not a whole degree.
    let robi = family::for_model(Model::Robi42);
    assert!(robi.steers());
    assert_ne!(robi.steer(100, 0.6), robi.steer(100, 0.61));
}
