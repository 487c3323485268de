//! Mission scripts (`droidctl run SCRIPT`): any text parses to steps or to errors naming
//! their lines, never a panic. Every step's own text parses back to the same action; errors
//! come in line order, within the script; a script that parses is checked against every
//! model, and each line a model accepts becomes that family's command and encodes.
//!
//! Input layout: the whole input is the script (read as UTF-8, lossily, as `run` reads it).

use super::Target;
use crate::family::{Command, Family};
use crate::model::Model;
use crate::script::{Action, Step, parse};

pub const TARGET: Target = Target {
    name: "script",
    run: run_input,
    dictionary: &[
        b"wake\n",
        b"sleep\n",
        b"stance tripod\n",
        b"stance bipod\n",
        b"drive 80 90 for 2s\n",
        b"drive ",
        b" for ",
        b"stop\n",
        b"head -90\n",
        b"animation 10\n",
        b"sound 1915\n",
        b"led front 0 0 255\n",
        b"led holo 255\n",
        b"wait 1s\n",
        b"wait ",
        b"ms",
        b"s\n",
        b"# ",
        b"1e20s",
        b"1e23ms",
        b"86400s",
        b"NaNs",
        b"matrix text \"HI\" 255 0 0\n",
        b"matrix char A\n",
        b"tank 100 -100 for 1s\n",
        b"calibrate compass\n",
        b"stream 50 attitude gyro\n",
        b"stream off\n",
        b"collision 100 100 100 100 100ms\n",
    ],
};

/// The command a model's family makes of a step it accepts (`None`: a wait, or a capability
/// the family has no command for).
fn command(family: &dyn Family, model: Model, action: &Action) -> Option<Command> {
    match action {
        Action::Wake => family.wake(),
        Action::Sleep => family.sleep(),
        Action::Stance(a) => family.stance(*a),
        Action::Drive { speed, heading, .. } => Some(family.drive(*speed, *heading, false)),
        Action::Stop => Some(family.drive(0, crate::units::Heading::default(), false)),
        Action::Head(a) => family.head(*a),
        Action::Animation(id) => family.animation(model, *id),
        Action::Sound(id) => family.sound(model, *id),
        a @ (Action::LedRgb(..) | Action::LedBrightness(..)) => family.led(model, a),
        a @ (Action::Matrix(_) | Action::CalibrateCompass) => {
            let intent = crate::family::intent::Intent::of_action(a)?;
            family.lower(model, &intent).ok()?.into_iter().next()
        }
        Action::Tank { left, right, .. } => family.tank(*left, *right),
        Action::Stream { rate_hz, sensors } => {
            let request = crate::tuning::StreamRequest {
                rate_hz: *rate_hz,
                sensors: sensors.unwrap_or_else(|| crate::family::stream::all_groups(model)),
            };
            let plan = crate::family::stream::plan_for(model, request)?;
            family.streaming(model, &plan).into_iter().next()
        }
        Action::Collision(c) => family.collision_detection(c).into_iter().next(),
        Action::Wait(_) => None,
    }
}

pub fn run_input(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let lines = text.lines().count();
    let steps: Vec<Step> = match parse(&text) {
        Ok(steps) => steps,
        Err(errors) => {
            assert!(!errors.is_empty());
            assert!(errors.windows(2).all(|w| w[0].line < w[1].line));
            for e in &errors {
                assert!((1..=lines).contains(&e.line), "{e}");
                assert!(!e.message.is_empty());
            }
            // The lines that do parse go on, as the script they make would.
            text.lines()
                .enumerate()
                .filter(|(i, _)| errors.iter().all(|e| e.line != i + 1))
                .flat_map(|(i, l)| {
                    parse(l)
                        .expect("a line without an error parses")
                        .into_iter()
                        .map(move |s| Step { line: i + 1, ..s })
                })
                .collect()
        }
    };
    for s in &steps {
        assert!((1..=lines).contains(&s.line));
        let again = parse(&s.text).unwrap_or_else(|e| panic!("{:?} does not parse: {e:?}", s.text));
        assert_eq!(again.len(), 1, "{:?}", s.text);
        assert_eq!(again[0].action, s.action, "{:?}", s.text);
    }
    for model in Model::ALL.into_iter().filter(|m| crate::sim::simulates(*m)) {
        let family = crate::family::for_model(model);
        let refused: Vec<usize> = match crate::mission::validate(model, &steps) {
            Ok(()) => Vec::new(),
            Err(errors) => {
                for e in &errors {
                    assert!(steps.iter().any(|s| s.line == e.line), "{e}");
                }
                errors.iter().map(|e| e.line).collect()
            }
        };
        let mut codec = family.codec();
        for (i, s) in steps.iter().enumerate() {
            if refused.contains(&s.line) {
                continue;
            }
            if let Some(cmd) = command(family, model, &s.action) {
                let (writes, _) = codec.encode_writes(&cmd, i as u8, true);
                assert!(!writes.is_empty(), "{model:?}: {:?}", s.text);
            }
        }
    }
}
