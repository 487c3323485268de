//! What a droid should do, said once for everything above the families: the app's controller,
//! missions, Sphero Edu programs, the bridge and fleets each turn their own vocabulary into an
//! [`Intent`], and the droid's family turns `(model, intent)` into its commands
//! ([`super::Family::lower`]). What differs per robot (BOLT's main light is its matrix, RVR's
//! messages are its own command) is the family's business, not the caller's; a model without
//! the capability gets [`Unsupported`] rather than another family's bytes.

use super::{Command, Family};
use crate::model::{Caps, Model};
use crate::protocol::wire::LegAction;
use crate::script::{Action, LedGroup, MatrixAction};
use crate::units::{HeadAngle, Heading};

/// What a droid is asked to do, independent of its protocol.
#[derive(Debug, Clone, PartialEq)]
pub enum Intent {
    /// Roll at `speed` (0..=255) toward `heading`; `reverse` backs up along it (a family that
    /// cannot back up rolls toward the opposite heading).
    Drive {
        speed: u8,
        heading: Heading,
        reverse: bool,
    },
    /// Forward at `speed` (0..=255) steering `turn`, −1 full left ..= 1 full right, for a
    /// robot driven by velocity and steering (Robi 42). A fraction, not a heading: the app's
    /// keys steer 0.6 of full lock and a stick any fraction, which [`Intent::Drive`]'s
    /// whole-degree heading would round (Robi's steering byte has 255 steps over the range,
    /// `droid-facts.md` §5). A robot driven toward a heading cannot do it ([`Unsupported`]).
    Steer {
        speed: u8,
        turn: f32,
    },
    /// Speed 0, still facing `heading` (the one it was last told, or where it is measured to
    /// face, so it does not turn back to 0): the control loop's emergency stop, the app's stop
    /// on exit, the bridge's stop where the droid is. Each family lowers it to its own drive
    /// at speed 0 (Robi: velocity 0, steering straight). Not the session's
    /// [`super::Family::stop_after`], which knows the last command written (after raw motors,
    /// the motors off) and stays the session's own.
    Stop {
        heading: Heading,
    },
    /// Each motor's raw power, −255..=255 (RVR's tracks, spherov2's `raw_motor`).
    RawMotors {
        left: i16,
        right: i16,
    },
    /// The control system on or off.
    Stabilization(bool),
    /// Enter aim mode: the back light on, and turning rotates the droid in place
    /// (stabilised, a drive at speed 0 turns it). The end is [`Intent::ResetAim`].
    StartAim,
    /// Leave aim mode: where the droid faces becomes heading 0.
    ResetAim,
    /// The main light as the robot shows it (BOLT: its whole matrix; R2 and RVR: front and
    /// back; the others: the front or body light).
    MainLight([u8; 3]),
    /// One light group a colour.
    LedRgb(LedGroup, [u8; 3]),
    /// One light group a brightness.
    LedBrightness(LedGroup, u8),
    /// BOLT's matrix.
    Matrix(Matrix),
    /// R2's dome.
    Head(HeadAngle),
    /// R2's legs.
    Stance(LegAction),
    Animation(u16),
    Sound(u16),
    /// Calibrate the compass to north (BOLT).
    CalibrateCompass,
    /// Robot-to-robot infrared (BOLT, RVR).
    Ir(Ir),
}

impl Intent {
    /// The intent's name in messages (`matrix: droidctl cannot do this on R2-D2`).
    pub fn what(&self) -> &'static str {
        match self {
            Intent::Drive { .. } => "drive",
            Intent::Steer { .. } => "steering",
            Intent::Stop { .. } => "stop",
            Intent::RawMotors { .. } => "raw motors",
            Intent::Stabilization(_) => "stabilization",
            Intent::StartAim => "aim",
            Intent::ResetAim => "reset aim",
            Intent::MainLight(_) | Intent::LedRgb(..) | Intent::LedBrightness(..) => "light",
            Intent::Matrix(_) => "matrix",
            Intent::Head(_) => "dome",
            Intent::Stance(_) => "stance",
            Intent::Animation(_) => "animation",
            Intent::Sound(_) => "sound",
            Intent::CalibrateCompass => "compass",
            Intent::Ir(_) => "infrared",
        }
    }

    /// A mission line's intent, for the lines that are one (`None`: waits, wake, sleep,
    /// stop, streaming and collision set-up, which the mission runs itself).
    pub fn of_action(action: &Action) -> Option<Intent> {
        Some(match action {
            Action::Stance(a) => Intent::Stance(*a),
            Action::Drive { speed, heading, .. } => Intent::Drive {
                speed: *speed,
                heading: *heading,
                reverse: false,
            },
            Action::Head(a) => Intent::Head(*a),
            Action::Animation(id) => Intent::Animation(*id),
            Action::Sound(id) => Intent::Sound(*id),
            Action::LedRgb(g, rgb) => Intent::LedRgb(*g, *rgb),
            Action::LedBrightness(g, b) => Intent::LedBrightness(*g, *b),
            Action::Matrix(m) => Intent::Matrix(Matrix::from(m)),
            Action::Tank { left, right, .. } => Intent::RawMotors {
                left: *left,
                right: *right,
            },
            Action::CalibrateCompass => Intent::CalibrateCompass,
            Action::Wake
            | Action::Sleep
            | Action::Stop
            | Action::Wait(_)
            | Action::Stream { .. }
            | Action::Collision(_) => return None,
        })
    }
}

/// The model has no such capability (or its family builds no such command).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("{what}: droidctl cannot do this on {}", model.display_name())]
pub struct Unsupported {
    pub model: Model,
    /// [`Intent::what`].
    pub what: &'static str,
}

impl Unsupported {
    pub fn of(model: Model, intent: &Intent) -> Unsupported {
        Unsupported {
            model,
            what: intent.what(),
        }
    }
}

/// What BOLT's matrix draws.
#[derive(Debug, Clone, PartialEq)]
pub enum Matrix {
    Char(char, [u8; 3]),
    /// Scroll text once at `fps`.
    Text {
        text: String,
        rgb: [u8; 3],
        fps: u8,
    },
    Pixel(u8, u8, [u8; 3]),
    Line([u8; 4], [u8; 3]),
    /// A rectangle `[x1, y1, x2, y2]` one colour.
    Fill([u8; 4], [u8; 3]),
    /// The whole matrix one colour.
    OneColour([u8; 3]),
    Clear,
    Rotate(u16),
    /// A frame to keep: its index and palette indexes `[y][x]` (spherov2's
    /// `save_compressed_frame_player64_bit_frame`).
    SaveFrame(u16, [[u8; 8]; 8]),
    /// An animation to keep (spherov2's `save_compressed_frame_player_animation`).
    SaveAnimation {
        id: u8,
        fps: u8,
        fade: bool,
        palette: Vec<[u8; 3]>,
        frames: Vec<u16>,
    },
    /// Play a kept animation, once or in a loop.
    Play(u8, bool),
    Pause,
    Resume,
    /// End the animation (spherov2's `clear_matrix` sends only this).
    Reset,
}

/// A mission's `matrix` line: text scrolls at 7 frames a second, 25 characters at most.
impl From<&MatrixAction> for Matrix {
    fn from(a: &MatrixAction) -> Matrix {
        match a {
            MatrixAction::Text { text, rgb } => Matrix::Text {
                text: text.chars().take(25).collect(),
                rgb: *rgb,
                fps: 7,
            },
            MatrixAction::Char { ch, rgb } => Matrix::Char(*ch, *rgb),
            MatrixAction::Fill(rgb) => Matrix::OneColour(*rgb),
            MatrixAction::Pixel { x, y, rgb } => Matrix::Pixel(*x, *y, *rgb),
            MatrixAction::Clear => Matrix::Clear,
            MatrixAction::Rotate(d) => Matrix::Rotate(*d),
        }
    }
}

/// What a robot is asked to do in infrared; channels 0..=7 and intensity 1..=64, bounded as
/// spherov2's `SpheroEduAPI` bounds them (`bound_value`).
#[derive(Debug, Clone, PartialEq)]
pub enum Ir {
    Broadcast {
        far: u8,
        near: u8,
    },
    StopBroadcast,
    Follow {
        far: u8,
        near: u8,
    },
    StopFollow,
    Evade {
        far: u8,
        near: u8,
    },
    StopEvade,
    Send {
        channel: u8,
        intensity: u8,
    },
    /// Hear the next message on each of these channels (none: nothing is sent, as spherov2).
    Listen(Vec<u8>),
}

/// The commands of `intent` on `model` through the family's capability methods: what every
/// family shares. A family lowers what is its own (v2's matrix, compass and infrared, each
/// family's stabilisation) and hands the rest here.
pub fn lower_common<F: Family + ?Sized>(
    f: &F,
    model: Model,
    intent: &Intent,
) -> Result<Vec<Command>, Unsupported> {
    let one = |c: Option<Command>| c.map(|c| vec![c]);
    let out = match intent {
        Intent::Drive {
            speed,
            heading,
            reverse,
        } => Some(vec![drive(f, *speed, *heading, *reverse)]),
        // Only a steering family builds a steering command.
        Intent::Steer { speed, turn } => one(f.steer(*speed, *turn)),
        // The family's drive at speed 0 toward the heading, not its `stop_after`: these are
        // the bytes the control loop always sent (v1's Roll keeps state Go).
        Intent::Stop { heading } => Some(vec![f.drive(0, *heading, false)]),
        Intent::RawMotors { .. } if !model.has(Caps::RAW_MOTORS) => None,
        Intent::RawMotors { left, right } => one(f.tank(*left, *right)),
        Intent::StartAim => f.aim_begin(model),
        Intent::ResetAim => Some(f.aim_end(model)).filter(|c| !c.is_empty()),
        Intent::MainLight(rgb) => one(f.led(model, &Action::LedRgb(LedGroup::Front, *rgb))),
        Intent::LedRgb(g, rgb) => one(f.led(model, &Action::LedRgb(*g, *rgb))),
        Intent::LedBrightness(g, b) => one(f.led(model, &Action::LedBrightness(*g, *b))),
        // The table says which droids have legs and a dome; the family builds the command.
        Intent::Head(_) if !model.has(Caps::DOME) => None,
        Intent::Head(a) => one(f.head(*a)),
        Intent::Stance(_) if !model.has(Caps::LEGS) => None,
        Intent::Stance(a) => one(f.stance(*a)),
        Intent::Animation(id) => one(f.animation(model, *id)),
        Intent::Sound(id) => one(f.sound(model, *id)),
        Intent::Stabilization(_) | Intent::Matrix(_) | Intent::Ir(_) | Intent::CalibrateCompass => {
            None
        }
    };
    out.ok_or_else(|| Unsupported::of(model, intent))
}

/// The drive command of `f` at `speed` toward `heading`. A steering robot (Robi 42) reads
/// the heading as a turn relative to straight ahead: 0 straight, 1..=180 to the right (90 or
/// more is full lock), 359..=180 to the left; `reverse` backs up only a droid that can.
pub fn drive<F: Family + ?Sized>(f: &F, speed: u8, heading: Heading, reverse: bool) -> Command {
    if reverse && f.can_reverse() {
        return f.drive(speed, heading, true);
    }
    if f.steers() {
        let d = heading.degrees() as f32;
        let signed = if d > 180.0 { d - 360.0 } else { d };
        if let Some(c) = f.steer(speed, (signed / 90.0).clamp(-1.0, 1.0)) {
            return c;
        }
    }
    f.drive(speed, heading, false)
}

/// The commands of `intent` on `model`, from the model's family.
pub fn lower(model: Model, intent: &Intent) -> Result<Vec<Command>, Unsupported> {
    super::for_model(model).lower(model, intent)
}

/// The one command `intent` lowers to on `model` through `f`, for what takes exactly one: a
/// latest-wins slot (drive, dome) or a request waited for (a stance). `None` when the model
/// cannot do it.
pub fn one_command<F: Family + ?Sized>(f: &F, model: Model, intent: &Intent) -> Option<Command> {
    match f.lower(model, intent) {
        Ok(mut commands) if commands.len() == 1 => commands.pop(),
        _ => None,
    }
}

/// The one command of [`Intent::Stop`] toward `heading` on `model`, for the urgent stop and
/// the stop on exit. Every family lowers a stop to one command; should one ever not, its own
/// stop goes instead: a stop is never dropped.
pub fn stop_command<F: Family + ?Sized>(f: &F, model: Model, heading: Heading) -> Command {
    one_command(f, model, &Intent::Stop { heading }).unwrap_or_else(|| f.stop_after(None))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_without_the_capability_is_refused_by_name() {
        let e = lower(Model::R2D2, &Intent::Matrix(Matrix::Clear)).unwrap_err();
        assert_eq!(e.to_string(), "matrix: droidctl cannot do this on R2-D2");
        assert!(lower(Model::Bolt, &Intent::Matrix(Matrix::Clear)).is_ok());
        assert!(lower(Model::Robi42, &Intent::Stabilization(true)).is_err());
        assert!(lower(Model::BB8, &Intent::Stabilization(false)).is_ok());
        assert!(lower(Model::Mini, &Intent::Ir(Ir::StopFollow)).is_err());
        assert!(lower(Model::Rvr, &Intent::Ir(Ir::StopFollow)).is_ok());
    }

    #[test]
    fn the_main_light_is_each_robots_own() {
        let bolt = lower(Model::Bolt, &Intent::MainLight([1, 2, 3])).unwrap();
        let fill = lower(
            Model::Bolt,
            &Intent::Matrix(Matrix::Fill([0, 0, 7, 7], [1, 2, 3])),
        )
        .unwrap();
        assert_eq!(bolt, fill);
        assert_eq!(
            lower(Model::R2D2, &Intent::MainLight([1, 2, 3]))
                .unwrap()
                .len(),
            2,
            "front and back"
        );
        assert_eq!(
            lower(Model::BB8, &Intent::MainLight([1, 2, 3]))
                .unwrap()
                .len(),
            1
        );
    }
}
