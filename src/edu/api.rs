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

use crate::model::Model;
use crate::protocol::wire::LegAction;
use std::time::Duration;

/// One argument of a call.
#[derive(Debug, Clone, PartialEq)]
pub enum Arg {
    Num(f64),
    Text(String),
}

/// What BOLT's matrix draws.
#[derive(Debug, Clone, PartialEq)]
pub enum Matrix {
    Char(char, [u8; 3]),
    Text {
        text: String,
        rgb: [u8; 3],
        fps: u8,
    },
    Pixel(u8, u8, [u8; 3]),
    Line([u8; 4], [u8; 3]),
    Fill([u8; 4], [u8; 3]),
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

/// Frames one program may register on BOLT (all its animations together), and colours a
/// palette holds (Sphero's docs: "up to 16 colors"). The robot's own frame limit is not
/// published; the simulator keeps as many (src/sim/animation.rs).
pub const MAX_FRAMES: usize = crate::sim::animation::SAVED_MAX;
pub const MAX_COLOURS: usize = 16;

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
    Sound(String),
    Say(String),
    CalibrateCompass,
    /// Robot-to-robot infrared (BOLT, RVR): one wire command each ([`Ir`]).
    Ir(Ir),
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

/// What the program waits for after the call's immediate actions.
#[derive(Debug, Clone, PartialEq)]
pub enum Wait {
    /// Each step's actions at its time since the call; the promise resolves at `end`.
    Timeline {
        steps: Vec<(Duration, Vec<Act>)>,
        end: Duration,
    },
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

/// Steps of `spin` and `fade` (spherov2 loops as fast as its link goes; 20 a second keeps
/// the droid's link unhurried and the turn smooth).
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

fn secs(v: f64) -> Duration {
    Duration::from_secs_f64(if v.is_finite() {
        v.clamp(0.0, 86_400.0)
    } else {
        0.0
    })
}

fn byte(v: f64) -> u8 {
    v.round().clamp(0.0, 255.0) as u8
}

fn wait_for(d: Duration) -> Option<Wait> {
    Some(Wait::Timeline {
        steps: Vec::new(),
        end: d,
    })
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

    /// Mini's speed scale, as spherov2 maps it.
    fn mapped(&self, speed: f64) -> i64 {
        let s = speed.round() as i64;
        let s = if self.model == Model::Mini && s != 0 {
            if s > 0 {
                ((s + 126) as f64 * 2.0 / 3.0).round() as i64
            } else {
                ((s - 126) as f64 * 2.0 / 3.0).round() as i64
            }
        } else {
            s
        };
        s.clamp(-255, 255)
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
        if matches!(self.model, Model::R2D2 | Model::R2Q5 | Model::Bolt) {
            self.front = rgb;
            self.back = rgb;
        }
        Act::Main(rgb)
    }

    /// Seconds a full turn takes at the least (spherov2's `spin`).
    fn turn_time(&self) -> f64 {
        match self.model {
            Model::Rvr => 1.5,
            Model::R2D2 | Model::R2Q5 => 0.7,
            Model::Mini => 0.5,
            Model::Ollie => 0.6,
            _ => 0.45,
        }
    }

    /// Run call `name` with `args` (as the prelude passes them).
    pub fn call(&mut self, name: &str, args: &[Arg]) -> Result<Effect, String> {
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
            "roll" | "rollDistance" => {
                let speed = self.mapped(n(1));
                self.speed = speed;
                self.heading = (n(0).round() as i64).rem_euclid(360);
                if speed < 0 {
                    self.heading = (self.heading + 180).rem_euclid(360);
                }
                e.now.push(self.rolling());
                e.stops = true;
                let stop = vec![Driver::drive(self.heading, 0)];
                e.wait = Some(if name == "roll" {
                    Wait::Timeline {
                        steps: vec![(secs(n(2)), stop)],
                        end: secs(n(2)),
                    }
                } else {
                    Wait::Distance {
                        cm: n(2).clamp(0.0, 100_000.0) as f32,
                        then: stop,
                    }
                });
            }
            "setSpeed" => {
                self.speed = self.mapped(n(0));
                e.now.push(self.rolling());
            }
            "setHeading" => {
                self.heading = (n(0).round() as i64).rem_euclid(360);
                e.now.push(self.rolling());
            }
            "stopRoll" => {
                if !args.is_empty() {
                    self.heading = (n(0).round() as i64).rem_euclid(360);
                }
                self.speed = 0;
                e.now.push(Driver::drive(self.heading, 0));
            }
            "spin" => {
                let angle = n(0).round() as i64;
                if angle == 0 {
                    return Ok(e);
                }
                let total = angle.unsigned_abs() as f64;
                let d = n(1).max(self.turn_time() * total / 360.0).min(86_400.0);
                let count = ((d / STEP.as_secs_f64()).ceil() as u64).max(1);
                let mut steps = Vec::with_capacity(count.min(100_000) as usize);
                let mut gone = 0i64;
                for k in 1..=count.min(100_000) {
                    let frac = (k as f64 / count as f64).min(1.0);
                    let delta = (frac * total).round() as i64 - gone;
                    gone += delta;
                    self.heading = (self.heading + angle.signum() * delta).rem_euclid(360);
                    steps.push((STEP * k as u32, vec![self.rolling()]));
                }
                e.wait = Some(Wait::Timeline {
                    steps,
                    end: secs(d),
                });
            }
            "rawMotor" => {
                let v = |x: f64| x.round().clamp(-255.0, 255.0) as i16;
                self.raw = (v(n(0)), v(n(1)));
                let was = self.stabilization;
                if was {
                    e.now.push(Act::Stabilization(false));
                }
                e.now.push(Act::Raw(self.raw.0, self.raw.1));
                if n(2) >= 0.0 {
                    let mut then = vec![Act::Raw(0, 0)];
                    if was {
                        then.push(Act::Stabilization(true));
                    }
                    e.wait = Some(Wait::Timeline {
                        steps: vec![(secs(n(2)), then)],
                        end: secs(n(2)),
                    });
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
            "delay" => e.wait = wait_for(secs(n(0))),
            "exitProgram" => e.exit = true,
            "setMainLed" => {
                let a = self.main_led(rgb(0));
                e.now.push(a);
            }
            "setFrontLed" => {
                self.front = rgb(0);
                e.now.push(Act::Front(self.front));
            }
            "setBackLed" => {
                self.back = rgb(0);
                e.now.push(Act::Back(self.back));
            }
            "setBackLedBrightness" => {
                self.back = [0, 0, byte(n(0))];
                e.now.push(Act::BackBrightness(byte(n(0))));
            }
            "fade" => {
                let (from, to) = (rgb(0), rgb(3));
                let d = secs(n(6));
                let count = (d.as_secs_f64() / STEP.as_secs_f64()).ceil().min(100_000.0) as u32;
                let mut steps = Vec::new();
                e.now.push(self.main_led(from));
                for k in 1..count {
                    let f = (STEP * k).as_secs_f64() / d.as_secs_f64();
                    let mix = |a: u8, b: u8| byte(a as f64 * (1.0 - f) + b as f64 * f);
                    let c = [
                        mix(from[0], to[0]),
                        mix(from[1], to[1]),
                        mix(from[2], to[2]),
                    ];
                    steps.push((STEP * k, vec![Act::Main(c)]));
                }
                steps.push((d, vec![self.main_led(to)]));
                e.wait = Some(Wait::Timeline { steps, end: d });
            }
            "strobe" => {
                let c = rgb(0);
                let period = secs(n(3));
                let count = n(4).round().clamp(0.0, 10_000.0) as u32;
                let mut steps = Vec::new();
                for i in 0..count * 2 {
                    let colour = if i & 1 == 1 { c } else { [0, 0, 0] };
                    steps.push((period * i, vec![self.main_led(colour)]));
                }
                e.wait = Some(Wait::Timeline {
                    steps,
                    end: period * (count * 2),
                });
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
                let fps = n(4).round().clamp(1.0, 30.0) as u8;
                // Each character is 8 columns wide, scrolled one column a frame (the
                // simulator's figures, src/sim/figures.rs): the text is done after that.
                let done = Duration::from_secs_f64((t.len() * 8) as f64 / fps as f64);
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
                let d = (n(0).round() as i64).rem_euclid(360);
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
            "playSound" => {
                e.now.push(Act::Sound(text(0)));
                e.wait = wait_for(Duration::ZERO);
            }
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
mod tests {
    use super::*;

    fn num(v: &[f64]) -> Vec<Arg> {
        v.iter().map(|x| Arg::Num(*x)).collect()
    }

    #[test]
    fn roll_backward_turns_the_heading_and_drives_backward_as_spherov2_does() {
        let mut d = Driver::new(Model::Bolt);
        let e = d.call("roll", &num(&[90.0, -100.0, 1.0])).unwrap();
        assert_eq!(d.heading, 270);
        assert_eq!(
            e.now,
            vec![Act::Drive {
                speed: 100,
                heading: 90,
                reverse: true
            }]
        );
    }

    #[test]
    fn mini_speeds_are_mapped() {
        let mut d = Driver::new(Model::Mini);
        d.call("setSpeed", &num(&[100.0])).unwrap();
        assert_eq!(d.speed, 151);
    }

    #[test]
    fn spin_ends_a_whole_turn_later_in_steps() {
        let mut d = Driver::new(Model::Bolt);
        d.heading = 10;
        let e = d.call("spin", &num(&[360.0, 1.0])).unwrap();
        assert_eq!(d.heading, 10);
        let Some(Wait::Timeline { steps, end }) = e.wait else {
            panic!("a timeline")
        };
        assert_eq!(end, Duration::from_secs(1));
        assert_eq!(steps.len(), 20);
        // Halfway: 180° on.
        assert_eq!(steps[9].1, vec![Driver::drive(190, 0)]);
    }

    #[test]
    fn an_animation_registers_its_frames_then_itself_and_plays_only_once_registered() {
        let mut d = Driver::new(Model::Bolt);
        assert!(d.call("playMatrixAnimation", &num(&[0.0, 1.0])).is_err());
        let mut a = vec![2.0, 0.0, 2.0, 255.0, 0.0, 0.0, 0.0, 0.0, 255.0, 2.0];
        a.extend(std::iter::repeat_n(0.0, 64));
        a.extend(std::iter::repeat_n(1.0, 64));
        let e = d.call("registerMatrixAnimation", &num(&a)).unwrap();
        assert_eq!(e.now.len(), 3);
        assert_eq!(e.now[1], Act::Matrix(Matrix::SaveFrame(1, [[1; 8]; 8])));
        assert_eq!(
            e.now[2],
            Act::Matrix(Matrix::SaveAnimation {
                id: 0,
                fps: 2,
                fade: false,
                palette: vec![[255, 0, 0], [0, 0, 255]],
                frames: vec![0, 1],
            })
        );
        let e = d.call("playMatrixAnimation", &num(&[0.0, 0.0])).unwrap();
        assert_eq!(e.now, vec![Act::Matrix(Matrix::Play(0, false))]);
        // A second animation's frames follow the first's.
        a[9] = 1.0;
        a.truncate(10 + 64);
        let e = d.call("registerMatrixAnimation", &num(&a)).unwrap();
        assert_eq!(e.now[0], Act::Matrix(Matrix::SaveFrame(2, [[0; 8]; 8])));
        // A pixel past the palette, a missing pixel, 17 colours: errors, nothing registered.
        let mut bad = a.clone();
        bad[12] = 2.0;
        assert!(
            d.call("registerMatrixAnimation", &num(&bad))
                .unwrap_err()
                .contains("row 0 column 2")
        );
        let mut bad = a.clone();
        bad.truncate(20);
        assert!(
            d.call("registerMatrixAnimation", &num(&bad))
                .unwrap_err()
                .contains("missing")
        );
        bad[2] = 17.0;
        assert!(d.call("registerMatrixAnimation", &num(&bad)).is_err());
        assert_eq!((d.animations, d.frames), (2, 3));
    }

    #[test]
    fn strobe_starts_dark() {
        let mut d = Driver::new(Model::Bolt);
        let e = d
            .call("strobe", &num(&[255.0, 0.0, 0.0, 0.1, 2.0]))
            .unwrap();
        let Some(Wait::Timeline { steps, end }) = e.wait else {
            panic!("a timeline")
        };
        assert_eq!(steps.len(), 4);
        assert_eq!(steps[0].1, vec![Act::Main([0, 0, 0])]);
        assert_eq!(steps[1].1, vec![Act::Main([255, 0, 0])]);
        assert_eq!(end, Duration::from_millis(400));
    }
}
