//! What each Sphero Edu call does, as plain data: the program's target heading and speed and
//! its lights (what `getHeading`, `getSpeed` and `getMainLed` return), and the robot actions
//! a call asks for now and over time. Sans-IO: the engine calls [`Driver::call`] with the
//! call's numbers and strings, and droidctl's clock plays the [`Effect`] (src/edu/run.rs).
//!
//! Where spherov2.py's `SpheroEduAPI` (`sphero_edu.py`) implements a call, this does what it
//! does: `roll` sets the heading (turned 180° for a negative speed) and speed, waits, then
//! stops at that heading; the drive command of a negative speed goes backward on the heading
//! turned 180° (its `DriveControl.roll_start`); Mini's speeds are mapped as spherov2 maps them
//! (`round((speed + 126) · 2/3)`); `spin` moves the target heading in steps over at least
//! the model's time for a turn (0.45 s per revolution, 0.5 on Mini, 0.7 on R2, 0.6 on
//! Ollie, 1.5 on RVR); `fade` steps the main light; `strobe` starts dark.

use super::timeline::{Steps, Timeline};
use crate::model::{Caps, Model};
use crate::protocol::wire::LegAction;
use std::time::Duration;

/// One argument of a call.
#[derive(Debug, Clone, PartialEq)]
pub enum Arg {
    Num(f64),
    Text(String),
}

/// What BOLT's matrix draws, and what a robot is asked to do in infrared: the family's
/// vocabulary ([`crate::family::intent`]), which lowers them to each robot's commands.
pub use crate::family::intent::{Ir, Matrix};

/// Frames one program may register on BOLT (all its animations together), and colours a
/// palette holds (Sphero's docs: "up to 16 colors"). The robot's own frame limit is not
/// published; the family says how many droidctl keeps (and the simulator keeps as many).
pub const MAX_FRAMES: usize = crate::family::v2::robots::MATRIX_SAVED_MAX;
pub const MAX_COLOURS: usize = 16;
/// The most arguments a call takes: `registerMatrixAnimation`'s fps, transition, palette
/// size, colours, frame count and 64 pixels a frame.
pub const MAX_ARGS: usize = 4 + 3 * MAX_COLOURS + 64 * MAX_FRAMES;
/// The longest text a call takes, in bytes (`speak`, `playSound`; the matrix takes 25).
pub const MAX_TEXT: usize = 1_000;

/// One thing the robot is asked to do.
#[derive(Debug, Clone, PartialEq)]
pub enum Act {
    /// The drive command: speed 0..=255 toward heading, backward when `reverse`.
    Drive {
        speed: u8,
        heading: u16,
        reverse: bool,
    },
    /// Raw motor power, −255..=255 each.
    Raw(i16, i16),
    Stabilization(bool),
    ResetAim,
    Main([u8; 3]),
    Front([u8; 3]),
    Back([u8; 3]),
    BackBrightness(u8),
    Holo(u8),
    Logic(u8),
    DomeLeds(u8),
    Matrix(Matrix),
    Dome(f32),
    Stance(LegAction),
    Animation(u16),
    /// A sound by name or number ([`super::sounds`]); `secs`: how long the program waits.
    Sound(String),
    Say(String),
    /// One of RVR's own lights: its headlights and side lights (spherov2's
    /// `set_left_headlight_led` … `set_right_led`).
    Rvr(RvrLight, [u8; 3]),
    CalibrateCompass,
    /// Robot-to-robot infrared (BOLT, RVR): one wire command each ([`Ir`]).
    Ir(Ir),
}

/// RVR's lights the Edu API sets one by one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RvrLight {
    LeftHeadlight,
    RightHeadlight,
    /// The battery door's side.
    Left,
    /// The power button's side.
    Right,
}

impl RvrLight {
    /// Its bits in RVR's 32-bit LED mask (spherov2's `RVR.LEDs` and `ToyUtil`'s
    /// `set_left_front_led` … `set_power_side_led`: the side lights are the front LEDs of the
    /// battery door and of the power button).
    pub fn mask(self) -> u32 {
        match self {
            RvrLight::RightHeadlight => 0x7,
            RvrLight::LeftHeadlight => 0x7 << 3,
            RvrLight::Left => 0x7 << 15,
            RvrLight::Right => 0x7 << 18,
        }
    }
}

/// What the program waits for after the call's immediate actions.
#[derive(Debug, Clone, PartialEq)]
pub enum Wait {
    /// Steps at their times since the call, made when due; the promise resolves at its end.
    Timeline(Timeline),
    /// Until the robot has covered `cm` more, then `then` (roll by distance).
    Distance { cm: f32, then: Vec<Act> },
    /// A stance change, until the droid says it is done (bounded).
    Stance,
    /// The compass calibration, until the droid answers with north (bounded).
    Compass,
}

/// A call's effect: actions now, and what the returned promise waits for (`None`: the call
/// returns at once).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Effect {
    pub now: Vec<Act>,
    pub wait: Option<Wait>,
    /// `exitProgram()`.
    pub exit: bool,
    /// The target speed is 0 once the wait is over (`roll` stops, as spherov2's `stop_roll`).
    pub stops: bool,
}

/// Steps of `fade` (spherov2 loops as fast as its link goes; 20 a second keeps the droid's
/// link unhurried and the colour smooth). `spin` is paced by its link's answers instead, as
/// spherov2's is ([`super::timeline::spin_turned`]).
pub const STEP: Duration = Duration::from_millis(50);

/// The program's side of the robot: what it last asked.
#[derive(Debug, Clone)]
pub struct Driver {
    pub model: Model,
    /// Target heading, 0..360.
    pub heading: i64,
    /// Target speed, −255..=255 (after Mini's mapping).
    pub speed: i64,
    pub raw: (i16, i16),
    pub stabilization: bool,
    pub main: [u8; 3],
    pub front: [u8; 3],
    pub back: [u8; 3],
    /// Matrix animations and frames registered so far (the next ids, as spherov2 counts).
    pub animations: u8,
    pub frames: u16,
}

/// The longest a call may last, in seconds (24 h, as a mission script's `wait`).
///
/// A longer one (or one not finite) is refused with an error naming the call, and so the
/// program's line, rather than clamped: a clamped `roll` or `spin` would quietly do something
/// else than the program says (stop early, end on another heading), and a call lasting more
/// than a day is a slip (`delay(3600000)` for an hour in ms). spherov2 bounds nothing
/// (`time.sleep(duration)`, `for i in range(count * 2)`): its calls block for as long as
/// asked. A negative duration is 0, as droidctl always took it (spherov2's `time.sleep`
/// raises on one; its `fade` would never end).
pub const MAX_SECONDS: f64 = 86_400.0;
/// The most blinks a `strobe` takes (its time is bounded by [`MAX_SECONDS`] too; this bounds
/// one of period 0).
pub const MAX_STROBES: f64 = 1_000_000.0;

/// A call's duration: NaN, infinite or past [`MAX_SECONDS`] is refused, negative is 0.
fn secs(call: &str, what: &str, v: f64) -> Result<Duration, String> {
    if !v.is_finite() || v > MAX_SECONDS {
        return Err(format!(
            "{call}: {what} {v} s is past droidctl's limit of {MAX_SECONDS} s (24 h)"
        ));
    }
    Ok(Duration::from_secs_f64(v.max(0.0)))
}

/// A heading in degrees, 0..360 (spherov2: `heading % 360`); not finite is refused.
fn degrees(call: &str, v: f64) -> Result<i64, String> {
    if !v.is_finite() {
        return Err(format!("{call}: a heading is a number of degrees, not {v}"));
    }
    // In f64: a huge heading keeps its remainder instead of saturating as an integer.
    Ok((v.round().rem_euclid(360.0) as i64).rem_euclid(360))
}

fn byte(v: f64) -> u8 {
    v.round().clamp(0.0, 255.0) as u8
}

fn wait_for(d: Duration) -> Option<Wait> {
    Some(Wait::Timeline(Timeline::wait(d)))
}

impl Driver {
    pub fn new(model: Model) -> Driver {
        Driver {
            model,
            heading: 0,
            speed: 0,
            raw: (0, 0),
            stabilization: true,
            main: [0; 3],
            front: [0; 3],
            back: [0; 3],
            animations: 0,
            frames: 0,
        }
    }

    /// A speed −255..=255, Mini's mapped as spherov2 maps it (`set_speed`, `roll`): on Mini
    /// `round((speed ± 126) · 2/3)` for a speed not 0, then `bound_value(-255, speed, 255)`.
    /// All in f64, which does not wrap, so a huge speed is full speed its way (it once
    /// saturated to i64 and the offset wrapped: `setSpeed(1e19)` on Mini was full speed
    /// backward). The clamp comes after Mini's mapping, as in spherov2: there 255 maps to
    /// 254 and only 256 and more reach 255 (clamping first would cap Mini at 254).
    /// ±Infinity is full speed its way (spherov2's `bound_value` on every model but Mini,
    /// where Python's `round` raises); NaN is refused (spherov2's `bound_value` makes it
    /// −255, by accident of `max`, and Mini's `round` raises).
    fn mapped(&self, call: &str, speed: f64) -> Result<i64, String> {
        if speed.is_nan() {
            return Err(format!("{call}: speed is a number −255 to 255, not NaN"));
        }
        let s = if self.model.has(Caps::SCALED_SPEED) && speed != 0.0 {
            let offset = if speed > 0.0 { 126.0 } else { -126.0 };
            ((speed + offset) * 2.0 / 3.0).round()
        } else {
            speed.round()
        };
        Ok(s.clamp(-255.0, 255.0) as i64)
    }

    /// The drive command for `heading` and `speed` (spherov2's `roll_start`).
    pub fn drive(heading: i64, speed: i64) -> Act {
        let (heading, reverse) = if speed < 0 {
            ((heading + 180).rem_euclid(360), true)
        } else {
            (heading.rem_euclid(360), false)
        };
        Act::Drive {
            speed: speed.unsigned_abs().min(255) as u8,
            heading: heading as u16,
            reverse,
        }
    }

    /// A wait that stopped the robot is over: the target speed is 0 ([`Effect::stops`]).
    pub fn stopped(&mut self) {
        self.speed = 0;
    }

    fn rolling(&self) -> Act {
        Driver::drive(self.heading, self.speed)
    }

    /// The main light as spherov2 sets it on this model.
    fn main_led(&mut self, rgb: [u8; 3]) -> Act {
        self.main = rgb;
        // R2-D2, R2-Q5 and BOLT: front and back (spherov2's `LedManager` maps main to both).
        if self.model.has(Caps::MAIN_FRONT_BACK) {
            self.front = rgb;
            self.back = rgb;
        }
        Act::Main(rgb)
    }

    /// Seconds a full turn takes at the least (spherov2's `spin`).
    fn turn_time(&self) -> f64 {
        self.model.full_turn().as_secs_f64()
    }

    /// Run call `name` with `args` (as the prelude passes them). Any arguments at all come
    /// to an effect or to an error naming the call, and an error changes nothing: NaN, too
    /// many arguments or too long a text are refused here whatever the prelude checked.
    pub fn call(&mut self, name: &str, args: &[Arg]) -> Result<Effect, String> {
        self.effect(name, args).map_err(|m| {
            if m.contains(name) {
                m
            } else {
                format!("{name}: {m}")
            }
        })
    }

    fn effect(&mut self, name: &str, args: &[Arg]) -> Result<Effect, String> {
        if args.len() > MAX_ARGS {
            return Err(format!(
                "{name}: {} arguments; a call takes at most {MAX_ARGS}",
                args.len()
            ));
        }
        for (i, a) in args.iter().enumerate() {
            match a {
                Arg::Num(v) if v.is_nan() => {
                    return Err(format!("{name}: argument {} is NaN, not a number", i + 1));
                }
                Arg::Text(t) if t.len() > MAX_TEXT => {
                    return Err(format!(
                        "{name}: a text of {} bytes; droidctl takes at most {MAX_TEXT}",
                        t.len()
                    ));
                }
                _ => {}
            }
        }
        let n = |i: usize| match args.get(i) {
            Some(Arg::Num(v)) => *v,
            _ => 0.0,
        };
        let text = |i: usize| match args.get(i) {
            Some(Arg::Text(t)) => t.clone(),
            Some(Arg::Num(v)) => v.to_string(),
            None => String::new(),
        };
        let rgb = |i: usize| [byte(n(i)), byte(n(i + 1)), byte(n(i + 2))];
        let mut e = Effect::default();
        match name {
            // `rollToDistance` is Sphero Edu's name, `driveToDistance` RVR's: droidctl's
            // `rollDistance` for both.
            "roll" | "rollDistance" | "rollToDistance" | "driveToDistance" => {
                let speed = self.mapped(name, n(1))?;
                let mut heading = degrees(name, n(0))?;
                let wait = if name == "roll" {
                    None
                } else if n(2).is_finite() {
                    Some(n(2).clamp(0.0, 100_000.0) as f32)
                } else {
                    return Err(format!("{name}: a distance is in cm, not {}", n(2)));
                };
                let d = match wait {
                    None => secs(name, "duration", n(2))?,
                    Some(_) => Duration::ZERO,
                };
                if speed < 0 {
                    heading = (heading + 180).rem_euclid(360);
                }
                (self.speed, self.heading) = (speed, heading);
                e.now.push(self.rolling());
                e.stops = true;
                let stop = vec![Driver::drive(self.heading, 0)];
                e.wait = Some(match wait {
                    None => Wait::Timeline(Timeline {
                        steps: Steps::Once(d, stop),
                        end: d,
                    }),
                    Some(cm) => Wait::Distance { cm, then: stop },
                });
            }
            "setSpeed" => {
                self.speed = self.mapped(name, n(0))?;
                e.now.push(self.rolling());
            }
            "setHeading" => {
                self.heading = degrees(name, n(0))?;
                e.now.push(self.rolling());
            }
            "stopRoll" => {
                if !args.is_empty() {
                    self.heading = degrees(name, n(0))?;
                }
                self.speed = 0;
                e.now.push(Driver::drive(self.heading, 0));
            }
            // spherov2's `spin`: at least the model's time for the turn, its heading stepped
            // toward `round(elapsed / duration · |angle|)`, a step each time the one before
            // was answered ([`super::timeline::spin_turned`]); it may end past `duration`.
            "spin" => {
                if !n(0).is_finite() {
                    return Err(format!("spin: degrees is a number, not {}", n(0)));
                }
                let total = n(0).round().abs();
                if total == 0.0 {
                    return Ok(e);
                }
                let d = n(1).max(self.turn_time() * total / 360.0);
                let d = secs(name, "turning", d)?;
                // Bounded by MAX_SECONDS: at most 6.9e7 degrees.
                let angle = n(0).round() as i64;
                let from = self.heading;
                self.heading = (from + angle).rem_euclid(360);
                e.wait = Some(Wait::Timeline(Timeline {
                    steps: Steps::Spin {
                        from,
                        angle,
                        speed: self.speed,
                        d,
                    },
                    end: d,
                }));
            }
            "rawMotor" => {
                // Negative: no duration (the prelude's `undefined`), the motors keep going.
                let d = secs(name, "duration", n(2))?;
                let v = |x: f64| x.round().clamp(-255.0, 255.0) as i16;
                self.raw = (v(n(0)), v(n(1)));
                let was = self.stabilization;
                if was {
                    e.now.push(Act::Stabilization(false));
                }
                e.now.push(Act::Raw(self.raw.0, self.raw.1));
                if n(2) >= 0.0 {
                    // spherov2's order (sphero_edu.py `raw_motor`): stabilization back on,
                    // then the motors off, so the motors run for the duration and the time
                    // the first of those two commands takes to leave. Motors off first ended
                    // a field figure-eight's `rawMotor(80, 80, 0.8)` 9 cm short of its
                    // spherov2 twin's (tests/it/edu_twins.rs). Sphero's docs are silent.
                    let mut then = Vec::new();
                    if was {
                        then.push(Act::Stabilization(true));
                    }
                    then.push(Act::Raw(0, 0));
                    e.wait = Some(Wait::Timeline(Timeline {
                        steps: Steps::Once(d, then),
                        end: d,
                    }));
                    self.raw = (0, 0);
                } else {
                    self.stabilization = false;
                }
            }
            "setStabilization" => {
                self.stabilization = n(0) != 0.0;
                e.now.push(Act::Stabilization(self.stabilization));
            }
            "resetAim" => e.now.push(Act::ResetAim),
            "delay" => e.wait = wait_for(secs(name, "delay", n(0))?),
            "exitProgram" => e.exit = true,
            "setMainLed" => {
                let a = self.main_led(rgb(0));
                e.now.push(a);
            }
            "setFrontLed" => {
                self.front = rgb(0);
                e.now.push(Act::Front(self.front));
            }
            // spherov2's `set_back_led` (sphero_edu.py): a colour lights the back of the
            // robots with a coloured front light (R2-D2, R2-Q5, BOLT, RVR; Mini's user body
            // light); the others' back light takes a brightness (`setBackLed(255)`), and a
            // colour leaves it as it was (tests/it/edu_twins.rs: BB-8's lit, spherov2's not).
            "setBackLed" => {
                if self.model.has(Caps::FRONT_LED) {
                    self.back = rgb(0);
                    e.now.push(Act::Back(self.back));
                }
            }
            "setBackLedBrightness" => {
                self.back = [0, 0, byte(n(0))];
                e.now.push(Act::BackBrightness(byte(n(0))));
            }
            "fade" => {
                let (from, to) = (rgb(0), rgb(3));
                let d = secs(name, "duration", n(6))?;
                // At most 1.7e6 steps (MAX_SECONDS).
                let count = (d.as_secs_f64() / STEP.as_secs_f64()).ceil() as u64;
                e.now.push(self.main_led(from));
                self.main_led(to);
                e.wait = Some(Wait::Timeline(Timeline {
                    steps: Steps::Fade { from, to, d, count },
                    end: d,
                }));
            }
            // spherov2's `strobe`: `for i in range(count * 2)`, dark on even `i`, each held
            // `period`; a negative count blinks none (its empty range).
            "strobe" => {
                let c = rgb(0);
                let (period, count) = (n(3), n(4).round());
                if !count.is_finite() || count > MAX_STROBES {
                    return Err(format!(
                        "strobe: {count} blinks; droidctl takes at most {MAX_STROBES}"
                    ));
                }
                let count = count.max(0.0);
                if !period.is_finite() || period.max(0.0) * 2.0 * count > MAX_SECONDS {
                    return Err(format!(
                        "strobe: {count} blinks of {period} s is past droidctl's limit of \
                         {MAX_SECONDS} s (24 h)"
                    ));
                }
                let period = secs(name, "period", period)?;
                let count = count as u64;
                if count > 0 {
                    self.main_led(c);
                }
                e.wait = Some(Wait::Timeline(Timeline {
                    steps: Steps::Strobe {
                        rgb: c,
                        period,
                        count,
                    },
                    end: period.mul_f64(2.0 * count as f64),
                }));
            }
            "setHoloProjectorLed" => e.now.push(Act::Holo(byte(n(0)))),
            "setLogicDisplayLeds" => e.now.push(Act::Logic(byte(n(0)))),
            "setDomeLeds" => e
                .now
                .push(Act::DomeLeds(n(0).round().clamp(0.0, 15.0) as u8)),
            "setMatrixCharacter" => {
                let ch = text(0).chars().next().unwrap_or(' ');
                if !ch.is_ascii() {
                    return Err(format!(
                        "setMatrixCharacter shows ASCII characters, not {ch:?}"
                    ));
                }
                e.now.push(Act::Matrix(Matrix::Char(ch, rgb(1))));
            }
            "scrollMatrixText" => {
                let t = text(0);
                if t.is_empty() || t.chars().count() > 25 || !t.is_ascii() {
                    return Err("scrollMatrixText takes 1 to 25 ASCII characters".into());
                }
                // NaN is refused above; a clamp keeps ±Infinity in range (it once made fps 0,
                // a division by zero and a panic of the engine thread).
                let fps = n(4).round().clamp(1.0, 30.0) as u8;
                // Each character is 8 columns wide, scrolled one column a frame (the
                // simulator's figures, src/sim/figures.rs): the text is done after that.
                let done = Duration::from_secs_f64((t.len() * 8) as f64 / f64::from(fps.max(1)));
                e.now.push(Act::Matrix(Matrix::Text {
                    text: t,
                    rgb: rgb(1),
                    fps,
                }));
                e.wait = wait_for(if n(5) != 0.0 { done } else { Duration::ZERO });
            }
            "drawMatrixPixel" => {
                let (x, y) = (n(3), n(4));
                e.now
                    .push(Act::Matrix(Matrix::Pixel(cell(x)?, cell(y)?, rgb(0))));
            }
            "drawMatrixLine" | "drawMatrixFill" => {
                let r = [cell(n(3))?, cell(n(4))?, cell(n(5))?, cell(n(6))?];
                e.now.push(Act::Matrix(if name == "drawMatrixLine" {
                    Matrix::Line(r, rgb(0))
                } else {
                    Matrix::Fill(r, rgb(0))
                }));
            }
            // Ends an animation too (Sphero's docs: a loop plays "until interrupted by …
            // clearMatrix()"), as spherov2's `clear_matrix` does.
            "clearMatrix" => {
                e.now.push(Act::Matrix(Matrix::Reset));
                e.now.push(Act::Matrix(Matrix::Clear));
            }
            "registerMatrixAnimation" => e.now = self.register_animation(args)?,
            "playMatrixAnimation" => {
                let id = n(0);
                if !(0.0..f64::from(self.animations)).contains(&id) || id.fract() != 0.0 {
                    return Err(format!(
                        "playMatrixAnimation({id}): no such animation ({} registered)",
                        self.animations
                    ));
                }
                e.now.push(Act::Matrix(Matrix::Play(id as u8, n(1) != 0.0)));
            }
            "pauseMatrixAnimation" => e.now.push(Act::Matrix(Matrix::Pause)),
            "resumeMatrixAnimation" => e.now.push(Act::Matrix(Matrix::Resume)),
            "setMatrixRotation" => {
                let d = degrees(name, n(0))?;
                if d % 90 != 0 {
                    return Err(format!(
                        "setMatrixRotation takes 0, 90, 180 or 270, not {d}"
                    ));
                }
                e.now.push(Act::Matrix(Matrix::Rotate(d as u16)));
            }
            "speak" => {
                e.now.push(Act::Say(text(0)));
                e.wait = wait_for(Duration::ZERO);
            }
            // With `wait`, the sound's length: Sphero does not publish them, so every sound
            // takes [`super::sounds::SOUND_SECONDS`] (unverified).
            "playSound" => {
                e.now.push(Act::Sound(text(0)));
                e.wait = wait_for(if n(1) != 0.0 {
                    Duration::from_secs_f64(super::sounds::SOUND_SECONDS)
                } else {
                    Duration::ZERO
                });
            }
            "setLeftHeadlightLed" => e.now.push(Act::Rvr(RvrLight::LeftHeadlight, rgb(0))),
            "setRightHeadlightLed" => e.now.push(Act::Rvr(RvrLight::RightHeadlight, rgb(0))),
            "setLeftLed" => e.now.push(Act::Rvr(RvrLight::Left, rgb(0))),
            "setRightLed" => e.now.push(Act::Rvr(RvrLight::Right, rgb(0))),
            // Printed as the call is (its step line); nothing goes to the robot.
            "console.log" => {}
            "playAnimation" => {
                self.speed = 0;
                e.now
                    .push(Act::Animation(n(0).round().clamp(0.0, 65_535.0) as u16));
            }
            "setDomePosition" => e.now.push(Act::Dome(n(0).clamp(-160.0, 180.0) as f32)),
            "setStance" => {
                let a = if n(0) == 2.0 {
                    LegAction::Bipod
                } else {
                    LegAction::Tripod
                };
                e.now.push(Act::Stance(a));
                e.wait = Some(Wait::Stance);
            }
            "setWaddle" => {
                self.speed = 0;
                let a = if n(0) != 0.0 {
                    LegAction::Waddle
                } else {
                    LegAction::Stop
                };
                e.now.push(Act::Stance(a));
            }
            "startIRBroadcast" | "startIRFollow" | "startIREvade" => {
                let (near, far) = (channel(n(0)), channel(n(1)));
                e.now.push(Act::Ir(match name {
                    "startIRBroadcast" => Ir::Broadcast { far, near },
                    "startIRFollow" => Ir::Follow { far, near },
                    _ => Ir::Evade { far, near },
                }));
            }
            "stopIRBroadcast" => e.now.push(Act::Ir(Ir::StopBroadcast)),
            "stopIRFollow" => e.now.push(Act::Ir(Ir::StopFollow)),
            "stopIREvade" => e.now.push(Act::Ir(Ir::StopEvade)),
            "sendIRMessage" => e.now.push(Act::Ir(Ir::Send {
                channel: channel(n(0)),
                intensity: n(1).round().clamp(1.0, 64.0) as u8,
            })),
            "listenForIRMessage" => {
                let mut channels: Vec<u8> = (0..args.len()).map(|i| channel(n(i))).collect();
                channels.sort_unstable();
                channels.dedup();
                if !channels.is_empty() {
                    e.now.push(Act::Ir(Ir::Listen(channels)));
                }
            }
            "calibrateCompass" => {
                e.now.push(Act::CalibrateCompass);
                e.wait = Some(Wait::Compass);
            }
            other => return Err(format!("{other}() is not a Sphero Edu call droidctl knows")),
        }
        Ok(e)
    }
}

impl Driver {
    /// `registerMatrixAnimation`, as the prelude flattens it: fps, fade (0/1), the palette's
    /// size and its colours, the frames' count and 64 palette indexes a frame (row by row).
    /// Each frame is saved, then the animation, as spherov2's `register_matrix_animation`.
    fn register_animation(&mut self, args: &[Arg]) -> Result<Vec<Act>, String> {
        let mut it = args.iter().map(|a| match a {
            Arg::Num(v) => *v,
            Arg::Text(_) => f64::NAN,
        });
        let mut next = |what: &str| {
            it.next()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("registerMatrixAnimation: {what} is missing"))
        };
        let fps = next("fps")?;
        if !(1.0..=30.0).contains(&fps.round()) {
            return Err(format!(
                "registerMatrixAnimation: fps is 1 to 30, not {fps}"
            ));
        }
        let fade = next("transition")? != 0.0;
        let colours = next("palette")? as usize;
        if !(1..=MAX_COLOURS).contains(&colours) {
            return Err(format!(
                "registerMatrixAnimation: a palette has 1 to {MAX_COLOURS} colours, not {colours}"
            ));
        }
        let mut palette = Vec::with_capacity(colours);
        for _ in 0..colours {
            palette.push([
                byte(next("a colour")?),
                byte(next("a colour")?),
                byte(next("a colour")?),
            ]);
        }
        let count = next("frames")? as usize;
        let room = MAX_FRAMES - (self.frames as usize).min(MAX_FRAMES);
        if count == 0 || count > room {
            return Err(format!(
                "registerMatrixAnimation: {count} frames; a program registers 1 to {MAX_FRAMES} \
                 in all ({room} left)"
            ));
        }
        if self.animations == u8::MAX {
            return Err("registerMatrixAnimation: too many animations".into());
        }
        let mut acts = Vec::with_capacity(count + 1);
        let mut ids = Vec::with_capacity(count);
        for f in 0..count {
            let mut frame = [[0u8; 8]; 8];
            for (y, row) in frame.iter_mut().enumerate() {
                for (x, px) in row.iter_mut().enumerate() {
                    let i = next("a pixel")?;
                    if i.fract() != 0.0 || !(0.0..colours as f64).contains(&i) {
                        return Err(format!(
                            "registerMatrixAnimation: frame {f} row {y} column {x} is {i}, \
                             not a palette index 0 to {}",
                            colours - 1
                        ));
                    }
                    *px = i as u8;
                }
            }
            ids.push(self.frames + f as u16);
            acts.push(Act::Matrix(Matrix::SaveFrame(
                self.frames + f as u16,
                frame,
            )));
        }
        self.frames += count as u16;
        acts.push(Act::Matrix(Matrix::SaveAnimation {
            id: self.animations,
            fps: fps.round() as u8,
            fade,
            palette,
            frames: ids,
        }));
        self.animations += 1;
        Ok(acts)
    }
}

/// An infrared channel 0..=7 (spherov2 bounds it; not a number is 0).
fn channel(v: f64) -> u8 {
    if v.is_finite() {
        v.round().clamp(0.0, 7.0) as u8
    } else {
        0
    }
}

/// A matrix coordinate 0..=7.
fn cell(v: f64) -> Result<u8, String> {
    if (0.0..=7.0).contains(&v.round()) {
        Ok(v.round() as u8)
    } else {
        Err(format!("matrix coordinates are 0 to 7, not {v}"))
    }
}

#[cfg(test)]
#[path = "api_tests.rs"]
mod tests;
