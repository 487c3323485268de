//! The control loop's logic: input state in, intents out, once per tick. Sans-IO: the caller
//! supplies elapsed time, lowers the outputs through the droid's family and sends them (drive
//! and head through the session's latest-wins slots, so a change goes out at once and never
//! queues behind stale commands). Everything the droid should do is said as an [`Intent`]
//! (driving toward a heading, steering, the tracks, the stop, the dome, the legs, aiming), the
//! vocabulary missions, Edu programs, fleets and the bridge use; the controller builds no
//! family command. It asks its family only how the droid is driven ([`Family::steers`],
//! [`Family::can_reverse`]).
//!
//! Safety rules: speed is 0 unless drive input is present right now (deadman: key released,
//! emulated release timed out, stick in its deadzone, pad unplugged, focus lost, link down);
//! an e-stop forces 0 immediately and stays latched while held.

use super::gamepad::PadDrive;
use crate::config::{Control as ControlConfig, DriveMode};
use crate::family::Family;
use crate::family::intent::Intent;
use crate::protocol::wire::{LegAction, LegState};
use crate::telemetry::Stance;
use crate::units::{HEAD_MAX_DEG, HEAD_MIN_DEG, HeadAngle, Heading};
use std::time::Duration;

/// What the control loop is commanding (the control loop writes it every tick; the app shows it).
#[derive(Debug, Clone, PartialEq)]
pub struct ControlView {
    /// Commanded speed 0..=255 (magnitude).
    pub speed: u8,
    /// Commanded heading (direction of travel).
    pub heading: Heading,
    pub reverse: bool,
    pub turbo: bool,
    /// Cruise speed used while a drive key is held.
    pub cruise: u8,
    /// Emergency stop latched.
    pub estop: bool,
    /// No drive input: the deadman holds speed at 0.
    pub deadman: bool,
    /// Commanded dome angle, degrees.
    pub head_target: f32,
    /// "hold" or "latched".
    pub mode: &'static str,
    /// Where the drive input comes from now: "keyboard", "gamepad", "aim" or "-".
    pub source: &'static str,
    /// Aim mode is on.
    pub aiming: bool,
    /// On a steering robot (Robi 42): the steering commanded, −1 full left ..= 1 full right
    /// (`None` on droids driven toward a heading).
    pub steer: Option<f32>,
    /// Tank mode (RVR): the tracks commanded, −255..=255 each.
    pub tank: Option<(i16, i16)>,
}

impl Default for ControlView {
    fn default() -> Self {
        ControlView {
            speed: 0,
            heading: Heading::default(),
            reverse: false,
            turbo: false,
            cruise: 100,
            estop: false,
            deadman: true,
            head_target: 0.0,
            mode: "hold",
            source: "-",
            aiming: false,
            steer: None,
            tank: None,
        }
    }
}

/// Input state at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Inputs {
    pub forward: bool,
    pub backward: bool,
    pub left: bool,
    pub right: bool,
    pub dome_left: bool,
    pub dome_right: bool,
    pub estop: bool,
    /// Left stick outside its deadzone, and the speed it asks for.
    pub pad: Option<(PadDrive, u8)>,
    /// Right stick dome rate, °/s.
    pub pad_dome_rate: f32,
    /// Tank mode: the sticks' tracks, −1..=1 each (`None` when both rest).
    pub pad_tracks: Option<(f32, f32)>,
}

/// What the controller needs to know about the droid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DroidView {
    pub connected: bool,
    pub has_legs: bool,
    pub has_dome: bool,
    /// A rolling droid that can be aimed (BB-8, SPRK+, Ollie, BB-9E).
    pub can_aim: bool,
    pub stance: Stance,
}

/// What to send or show.
#[derive(Debug, Clone, PartialEq)]
pub enum Out {
    /// What the droid should do, for its family to lower: the motion (latest wins, the drive
    /// slot) as [`Intent::Drive`] toward a heading, [`Intent::Steer`] on a steering robot
    /// (its turn a fraction), [`Intent::RawMotors`] in tank mode or [`Intent::Stop`];
    /// [`Intent::Head`] (the dome: latest wins, the head slot); [`Intent::Stance`] (the
    /// legs); [`Intent::StartAim`] and [`Intent::ResetAim`] (entering and leaving aim mode).
    Do(Intent),
    /// Tell the operator something.
    Hint(String),
}

pub struct Controller {
    cfg: ControlConfig,
    family: &'static dyn Family,
    /// In aim mode: speed is held at 0 while turning rotates the droid.
    aiming: bool,
    /// "Cannot reverse" was said for the reverse input now held (said once per press).
    reverse_refused: bool,
    heading: f32,
    cruise: u8,
    turbo: bool,
    /// Latched mode: signed speed.
    latched: i16,
    head_target: f32,
    estop: bool,
    last_drive: Option<(u8, u16, u8)>,
    last_head: Option<i32>,
    /// When tripod was last requested automatically (so it is asked once, not every tick).
    tripod_asked: Option<Duration>,
    now: Duration,
    view: ControlView,
    /// Tank mode, on a robot with tracks.
    tank: super::tank::TankMode,
}

const TRIPOD_RETRY: Duration = Duration::from_secs(4);

/// How hard a held turn key steers a steering robot (1 = full lock, which pivots on one
/// wheel).
const KEY_STEER: f32 = 0.6;

impl Controller {
    /// A controller for a v2 droid; see [`Controller::with_family`].
    pub fn new(cfg: ControlConfig) -> Self {
        Self::with_family(
            cfg,
            crate::family::for_protocol(crate::model::Protocol::SpheroV2),
        )
    }

    /// A controller whose commands are built by `family`.
    pub fn with_family(cfg: ControlConfig, family: &'static dyn Family) -> Self {
        let cruise = cfg.cruise_speed;
        let mode = match cfg.mode {
            DriveMode::Hold => "hold",
            DriveMode::Latched => "latched",
        };
        Controller {
            cfg,
            family,
            aiming: false,
            reverse_refused: false,
            heading: 0.0,
            cruise,
            turbo: false,
            latched: 0,
            head_target: 0.0,
            estop: false,
            last_drive: None,
            last_head: None,
            tripod_asked: None,
            tank: Default::default(),
            now: Duration::ZERO,
            view: ControlView {
                cruise,
                mode,
                ..ControlView::default()
            },
        }
    }

    pub fn view(&self) -> &ControlView {
        &self.view
    }

    pub fn aiming(&self) -> bool {
        self.aiming
    }

    /// Set the cruise speed (remembered settings forgotten).
    pub fn set_cruise(&mut self, cruise: u8) {
        self.cruise = cruise;
        self.view.cruise = cruise;
    }

    /// The robot has tracks (RVR): tank mode is offered.
    pub fn set_tracks(&mut self, has: bool) {
        self.tank.available = has;
    }

    /// Emergency stop, now: the stop to write at once (speed 0 at the heading last
    /// commanded), for the caller to lower and hand to the session's urgent path.
    pub fn estop_now(&mut self) -> Intent {
        self.estop = true;
        self.latched = 0;
        let heading = Heading::wrapped(self.heading as f64);
        self.last_drive = Some((0, heading.degrees(), 0));
        self.view.estop = true;
        self.view.speed = 0;
        Intent::Stop { heading }
    }

    /// The operator's input went away (the place on top changed, another droid was chosen,
    /// mirror mode switched, focus was lost): a latched speed is dropped too, so in latched
    /// mode as in hold mode the next write is a stop.
    pub fn let_go(&mut self) {
        self.latched = 0;
    }

    /// The link went down: forget what was sent, drop latched speed.
    pub fn link_lost(&mut self) {
        self.latched = 0;
        self.aiming = false;
        self.view.aiming = false;
        self.turbo = false;
        self.last_drive = None;
        self.last_head = None;
    }

    /// A one-shot action (key or button press).
    pub fn on_press(&mut self, a: crate::config::Action, droid: &DroidView) -> Vec<Out> {
        use crate::config::Action as A;
        let step = self.cfg.speed_step as i16;
        match a {
            A::Faster => self.cruise = self.cruise.saturating_add(self.cfg.speed_step),
            A::Slower => self.cruise = self.cruise.saturating_sub(self.cfg.speed_step),
            A::Turbo => self.turbo = !self.turbo,
            A::Forward if self.cfg.mode == DriveMode::Latched => {
                self.latched = (self.latched + step).min(255)
            }
            A::Backward if self.cfg.mode == DriveMode::Latched => {
                self.latched = (self.latched - step).max(-255)
            }
            A::EStop => return vec![Out::Do(self.estop_now())],
            A::Tank => {
                let out = self.tank.toggle();
                self.latched = 0;
                self.view.tank = self.tank.on.then_some((0, 0));
                return out;
            }
            A::Aim => {
                if !droid.can_aim {
                    return vec![Out::Hint("this droid has no aim mode".into())];
                }
                self.aiming = !self.aiming;
                self.view.aiming = self.aiming;
                self.latched = 0;
                return if self.aiming {
                    vec![
                        Out::Do(Intent::StartAim),
                        Out::Hint(
                            "aim: ←/→ turn the droid, press the aim key again to set heading 0"
                                .into(),
                        ),
                    ]
                } else {
                    // The droid's facing is the new heading 0.
                    self.heading = 0.0;
                    // As if "stopped at heading 0" had been sent: a fresh stop would overtake
                    // the queued Set Heading (stops go first) and turn the droid back.
                    self.last_drive = Some((0, 0, 0));
                    vec![
                        Out::Do(Intent::ResetAim),
                        Out::Hint("heading set: forward is where it faces".into()),
                    ]
                };
            }
            A::Tripod | A::Bipod | A::Waddle | A::StanceStop => {
                if !droid.has_legs {
                    return vec![Out::Hint("this droid has no legs".into())];
                }
                let leg = match a {
                    A::Tripod => LegAction::Tripod,
                    A::Bipod => LegAction::Bipod,
                    A::Waddle => LegAction::Waddle,
                    _ => LegAction::Stop,
                };
                return vec![Out::Do(Intent::Stance(leg))];
            }
            _ => {}
        }
        self.view.cruise = self.cruise;
        self.view.turbo = self.turbo;
        Vec::new()
    }

    /// One control tick. `dt` is the time since the last tick (0 for an immediate update after
    /// a release); `heartbeat` re-sends the drive command while moving so the droid's motion
    /// timeout never stops it.
    pub fn tick(
        &mut self,
        inp: &Inputs,
        dt: Duration,
        droid: &DroidView,
        heartbeat: bool,
    ) -> Vec<Out> {
        self.now += dt;
        let dt_s = dt.as_secs_f32();
        let mut out = Vec::new();
        self.estop = inp.estop;

        // Heading: held turn keys turn it (also while stopped, to aim); the stick sets it.
        let turn = (inp.right as i8 - inp.left as i8) as f32;
        self.heading = (self.heading + turn * self.cfg.turn_rate_deg_s * dt_s).rem_euclid(360.0);
        if let Some((pad, _)) = inp.pad {
            self.heading = pad.heading;
        }

        // Dome.
        if droid.has_dome {
            let rate = (inp.dome_right as i8 - inp.dome_left as i8) as f32
                * self.cfg.dome_rate_deg_s
                + inp.pad_dome_rate;
            let t = self.head_target + rate * dt_s;
            self.head_target = if t.is_finite() {
                t.clamp(HEAD_MIN_DEG, HEAD_MAX_DEG)
            } else {
                0.0
            };
        }

        // Speed: only while input says so right now.
        if !droid.connected {
            self.latched = 0;
        }
        let (mut speed, mut reverse, source) = if self.estop || !droid.connected {
            (0u8, false, "-")
        } else if self.aiming {
            (0u8, false, "aim")
        } else if let Some((_, s)) = inp.pad {
            (s, false, "gamepad")
        } else {
            match self.cfg.mode {
                DriveMode::Hold if inp.forward != inp.backward => (
                    if self.turbo {
                        self.cfg.turbo_speed
                    } else {
                        self.cruise
                    },
                    inp.backward,
                    "keyboard",
                ),
                DriveMode::Hold => (0, false, "-"),
                DriveMode::Latched => (
                    self.latched.unsigned_abs().min(255) as u8,
                    self.latched < 0,
                    "keyboard",
                ),
            }
        };
        if self.estop {
            self.latched = 0;
        }
        // A steering robot's stick: pulled back asks to reverse.
        if self.family.steers()
            && let Some((pad, _)) = inp.pad
            && pad.heading.to_radians().cos() < -0.5
        {
            reverse = true;
        }

        // Robi cannot back up: hold still and say so, rather than ignore the key.
        if reverse && !self.family.can_reverse() {
            speed = 0;
            reverse = false;
            self.latched = self.latched.max(0);
            if !self.reverse_refused {
                self.reverse_refused = true;
                out.push(Out::Hint(
                    "this robot cannot reverse — it only drives forward".into(),
                ));
            }
        } else if !(inp.backward || self.latched < 0) {
            self.reverse_refused = false;
        }

        // R2 rolls only in tripod.
        if speed > 0 && droid.has_legs {
            match droid.stance {
                Stance::Tripod | Stance::Unknown => {}
                Stance::Transitioning(LegState::Tripod) => speed = 0,
                _ => {
                    speed = 0;
                    let asked_recently = self
                        .tripod_asked
                        .is_some_and(|t| self.now.saturating_sub(t) < TRIPOD_RETRY);
                    if self.cfg.auto_tripod {
                        if !asked_recently {
                            self.tripod_asked = Some(self.now);
                            out.push(Out::Do(Intent::Stance(LegAction::Tripod)));
                            out.push(Out::Hint(
                                "R2 can't roll on two legs — switching to tripod".into(),
                            ));
                        }
                    } else if !asked_recently {
                        self.tripod_asked = Some(self.now);
                        out.push(Out::Hint(
                            "R2 can't roll on two legs — press 1 for tripod".into(),
                        ));
                    }
                }
            }
        }

        // Tank mode: the tracks instead of a heading (RVR).
        if self.tank.on {
            let live = droid.connected && !self.estop && !self.aiming;
            let cruise = if self.turbo {
                self.cfg.turbo_speed
            } else {
                self.cruise
            };
            if let Some((left, right)) =
                self.tank
                    .tick(inp, live, cruise, heartbeat, droid.connected)
            {
                self.last_drive = None;
                self.view.tank = Some((left, right));
                out.push(Out::Do(Intent::RawMotors { left, right }));
            }
            self.view.speed = 0;
            self.view.estop = self.estop;
            self.view.turbo = self.turbo;
            self.view.source = if self.tank.moving() { "tank" } else { "-" };
            self.view.deadman = !self.tank.moving() && !self.estop;
            return out;
        }
        // Drive: while moving (heartbeat) and whenever it changes.
        let travel = Heading::wrapped(self.heading as f64);
        let mut steer = None;
        if self.family.steers() {
            // Velocity and steering: the turn keys (or the stick's sideways part) steer.
            let turn = match inp.pad {
                Some((pad, _)) => pad.heading.to_radians().sin(),
                None => (inp.right as i8 - inp.left as i8) as f32 * KEY_STEER,
            };
            steer = Some(turn);
            let key = (speed, ((turn + 1.0) * 100.0).round() as u16, 0);
            if droid.connected && ((speed > 0 && heartbeat) || self.last_drive != Some(key)) {
                self.last_drive = Some(key);
                out.push(Out::Do(Intent::Steer { speed, turn }));
            }
        } else {
            let key = (speed, travel.degrees(), reverse as u8);
            if droid.connected && ((speed > 0 && heartbeat) || self.last_drive != Some(key)) {
                self.last_drive = Some(key);
                out.push(Out::Do(Intent::Drive {
                    speed,
                    heading: travel,
                    reverse,
                }));
            }
        }

        // Dome: when the target changes by a degree or more.
        let head = self.head_target.round() as i32;
        if droid.connected && droid.has_dome && self.last_head != Some(head) {
            self.last_head = Some(head);
            out.push(Out::Do(Intent::Head(HeadAngle::clamped(head as f32))));
        }

        self.view = ControlView {
            speed,
            heading: travel,
            reverse,
            turbo: self.turbo,
            cruise: self.cruise,
            estop: self.estop,
            deadman: speed == 0 && !self.estop,
            head_target: self.head_target,
            mode: self.view.mode,
            source,
            aiming: self.aiming,
            steer,
            tank: None,
        };
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Action;
    use crate::config::Config;
    use crate::model::Model;

    const R2: DroidView = DroidView {
        connected: true,
        has_legs: true,
        has_dome: true,
        can_aim: false,
        stance: Stance::Tripod,
    };
    const TICK: Duration = Duration::from_millis(100);

    fn controller() -> Controller {
        Controller::new(Config::defaults().control)
    }

    /// The drive bytes (speed, heading, flags or state) of the motion in `out`, as R2's
    /// family lowers it.
    fn drives(out: &[Out]) -> Vec<(u8, u16, u8)> {
        drives_on(Model::R2D2, out)
    }

    /// As [`drives`], lowered by `model`'s family.
    fn drives_on(model: Model, out: &[Out]) -> Vec<(u8, u16, u8)> {
        out.iter()
            .filter_map(|o| match o {
                Out::Do(i @ (Intent::Drive { .. } | Intent::Stop { .. })) => {
                    let c = crate::family::intent::lower(model, i).unwrap().remove(0);
                    Some((
                        c.data()[0],
                        u16::from_be_bytes([c.data()[1], c.data()[2]]),
                        c.data()[3],
                    ))
                }
                _ => None,
            })
            .collect()
    }

    #[test]
    fn hold_forward_then_release_stops() {
        let mut c = controller();
        let fwd = Inputs {
            forward: true,
            ..Inputs::default()
        };
        assert_eq!(drives(&c.tick(&fwd, TICK, &R2, true)), vec![(100, 0, 0)]);
        // Heartbeat: sent every tick while moving.
        assert_eq!(drives(&c.tick(&fwd, TICK, &R2, true)), vec![(100, 0, 0)]);
        // Released: one stop, then nothing.
        assert_eq!(
            drives(&c.tick(&Inputs::default(), TICK, &R2, true)),
            vec![(0, 0, 0)]
        );
        assert!(drives(&c.tick(&Inputs::default(), TICK, &R2, true)).is_empty());
        assert!(c.view().deadman);
    }

    #[test]
    fn reverse_uses_backward_flag_and_opposite_heading() {
        let mut c = controller();
        let back = Inputs {
            backward: true,
            ..Inputs::default()
        };
        assert_eq!(
            drives(&c.tick(&back, TICK, &R2, true)),
            vec![(100, 180, 0x01)]
        );
        assert!(c.view().reverse);
    }

    #[test]
    fn turning_aims_while_stopped() {
        let mut c = controller();
        let right = Inputs {
            right: true,
            ..Inputs::default()
        };
        // 90 °/s for 0.5 s.
        let mut last = Vec::new();
        for _ in 0..5 {
            last = drives(&c.tick(&right, TICK, &R2, true));
        }
        assert_eq!(last, vec![(0, 45, 0)]);
        let left = Inputs {
            left: true,
            ..Inputs::default()
        };
        for _ in 0..10 {
            c.tick(&left, TICK, &R2, true);
        }
        assert_eq!(c.view().heading.degrees(), 315);
    }

    #[test]
    fn aim_mode_turns_in_place_and_ends_without_a_drive_that_overtakes_set_heading() {
        let mut c = Controller::with_family(
            Config::defaults().control,
            crate::family::for_model(crate::model::Model::BB8),
        );
        let bb8 = DroidView {
            has_legs: false,
            has_dome: false,
            can_aim: true,
            ..R2
        };
        assert!(
            matches!(c.on_press(Action::Aim, &R2)[0], Out::Hint(_)),
            "R2 cannot aim"
        );
        assert!(
            c.on_press(Action::Aim, &bb8)
                .contains(&Out::Do(Intent::StartAim))
        );
        // Forward is ignored while aiming; turning rotates the droid in place (speed 0).
        let fwd_right = Inputs {
            forward: true,
            right: true,
            ..Inputs::default()
        };
        let mut last = Vec::new();
        for _ in 0..5 {
            last = drives_on(Model::BB8, &c.tick(&fwd_right, TICK, &bb8, true));
        }
        assert_eq!(
            last,
            vec![(0, 45, 1)],
            "v1 Roll: speed 0, heading 45, state go"
        );
        assert_eq!(c.view().source, "aim");
        assert!(
            c.on_press(Action::Aim, &bb8)
                .contains(&Out::Do(Intent::ResetAim))
        );
        // The next ticks send nothing: a stop at heading 0 would jump the queue ahead of
        // Set Heading 0 and turn the droid back.
        assert!(drives_on(Model::BB8, &c.tick(&Inputs::default(), TICK, &bb8, true)).is_empty());
        assert_eq!(c.view().heading.degrees(), 0);
    }

    #[test]
    fn estop_is_immediate_and_latched_while_held() {
        let mut c = controller();
        let fwd = Inputs {
            forward: true,
            ..Inputs::default()
        };
        c.tick(&fwd, TICK, &R2, true);
        let stop = c.estop_now();
        assert_eq!(
            stop,
            Intent::Stop {
                heading: Heading::default()
            }
        );
        assert_eq!(drives(&[Out::Do(stop)]), vec![(0, 0, 0)]);
        let held = Inputs {
            forward: true,
            estop: true,
            ..Inputs::default()
        };
        for _ in 0..5 {
            assert!(
                drives(&c.tick(&held, TICK, &R2, true))
                    .iter()
                    .all(|d| d.0 == 0)
            );
            assert!(c.view().estop);
        }
        // Released: driving resumes only because forward is still held.
        assert_eq!(drives(&c.tick(&fwd, TICK, &R2, true)), vec![(100, 0, 0)]);
    }

    #[test]
    fn cruise_and_turbo() {
        let mut c = controller();
        c.on_press(Action::Faster, &R2);
        c.on_press(Action::Faster, &R2);
        let fwd = Inputs {
            forward: true,
            ..Inputs::default()
        };
        assert_eq!(drives(&c.tick(&fwd, TICK, &R2, true))[0].0, 130);
        c.on_press(Action::Turbo, &R2);
        assert_eq!(drives(&c.tick(&fwd, TICK, &R2, true))[0].0, 255);
        assert!(c.view().turbo);
    }

    #[test]
    fn latched_mode_steps_and_space_stops() {
        let mut cfg = Config::defaults().control;
        cfg.mode = DriveMode::Latched;
        let mut c = Controller::new(cfg);
        c.on_press(Action::Forward, &R2);
        c.on_press(Action::Forward, &R2);
        assert_eq!(
            drives(&c.tick(&Inputs::default(), TICK, &R2, true)),
            vec![(30, 0, 0)]
        );
        c.on_press(Action::EStop, &R2);
        assert_eq!(
            drives(&c.tick(&Inputs::default(), TICK, &R2, true)),
            Vec::<(u8, u16, u8)>::new()
        );
        assert_eq!(c.view().speed, 0);
        // Link loss drops latched speed too.
        c.on_press(Action::Forward, &R2);
        c.link_lost();
        assert_eq!(
            drives(&c.tick(&Inputs::default(), TICK, &R2, true)),
            vec![(0, 0, 0)]
        );
    }

    #[test]
    fn bipod_switches_to_tripod_first() {
        let mut c = controller();
        let bipod = DroidView {
            stance: Stance::Bipod,
            ..R2
        };
        let fwd = Inputs {
            forward: true,
            ..Inputs::default()
        };
        let out = c.tick(&fwd, TICK, &bipod, true);
        assert!(out.contains(&Out::Do(Intent::Stance(LegAction::Tripod))));
        assert!(
            out.iter()
                .any(|o| matches!(o, Out::Hint(h) if h.contains("tripod")))
        );
        assert!(drives(&out).iter().all(|d| d.0 == 0));
        // Asked once, not every tick.
        let out = c.tick(&fwd, TICK, &bipod, true);
        assert!(!out.contains(&Out::Do(Intent::Stance(LegAction::Tripod))));
        // Transitioning: still held at 0; tripod: drives.
        let trans = DroidView {
            stance: Stance::Transitioning(LegState::Tripod),
            ..R2
        };
        assert!(
            drives(&c.tick(&fwd, TICK, &trans, true))
                .iter()
                .all(|d| d.0 == 0)
        );
        assert_eq!(drives(&c.tick(&fwd, TICK, &R2, true)), vec![(100, 0, 0)]);
    }

    #[test]
    fn bipod_hint_only_when_auto_tripod_off() {
        let mut cfg = Config::defaults().control;
        cfg.auto_tripod = false;
        let mut c = Controller::new(cfg);
        let bipod = DroidView {
            stance: Stance::Bipod,
            ..R2
        };
        let out = c.tick(
            &Inputs {
                forward: true,
                ..Inputs::default()
            },
            TICK,
            &bipod,
            true,
        );
        assert!(!out.iter().any(|o| matches!(o, Out::Do(Intent::Stance(_)))));
        assert!(
            out.iter()
                .any(|o| matches!(o, Out::Hint(h) if h.contains("press 1")))
        );
    }

    #[test]
    fn dome_moves_and_is_clamped() {
        let mut c = controller();
        let right = Inputs {
            dome_right: true,
            ..Inputs::default()
        };
        let mut heads = 0;
        for _ in 0..30 {
            heads += c
                .tick(&right, TICK, &R2, true)
                .iter()
                .filter(|o| matches!(o, Out::Do(Intent::Head(_))))
                .count();
        }
        assert_eq!(c.view().head_target, 180.0);
        assert!(heads > 1);
        // No change, no command.
        assert!(
            !c.tick(&right, TICK, &R2, true)
                .iter()
                .any(|o| matches!(o, Out::Do(Intent::Head(_))))
        );
    }

    #[test]
    fn disconnected_sends_nothing_and_holds_zero() {
        let mut c = controller();
        let down = DroidView {
            connected: false,
            ..R2
        };
        let out = c.tick(
            &Inputs {
                forward: true,
                ..Inputs::default()
            },
            TICK,
            &down,
            true,
        );
        assert!(out.is_empty());
        assert_eq!(c.view().speed, 0);
    }

    #[test]
    fn gamepad_drives_polar() {
        let mut c = controller();
        let pad = PadDrive {
            heading: 90.0,
            magnitude: 0.5,
        };
        let inp = Inputs {
            pad: Some((pad, 80)),
            ..Inputs::default()
        };
        assert_eq!(drives(&c.tick(&inp, TICK, &R2, true)), vec![(80, 90, 0)]);
        assert_eq!(c.view().source, "gamepad");
        // Stick back in the deadzone: stop.
        assert_eq!(
            drives(&c.tick(&Inputs::default(), TICK, &R2, true)),
            vec![(0, 90, 0)]
        );
    }
}
