//! Gamepads: gilrs on its own thread (gilrs is not async) sends [`PadEvent`]s over a bounded
//! channel; [`PadState`] maps them to driving input. No gamepad, or no /dev/input, is
//! normal: the thread reports `Unavailable` once and ends.

use crate::config::Gamepad as PadConfig;
pub use crate::config::{Button, PadAction};
use std::collections::HashSet;
use std::time::Duration;
use tokio::sync::mpsc;

/// gilrs's button as one droidctl maps (`None` for the rest).
fn button_from_gilrs(b: gilrs::Button) -> Option<Button> {
    use gilrs::Button as G;
    Some(match b {
        G::South => Button::South,
        G::East => Button::East,
        G::North => Button::North,
        G::West => Button::West,
        G::Start => Button::Start,
        G::Select => Button::Select,
        G::LeftTrigger => Button::LeftBumper,
        G::RightTrigger => Button::RightBumper,
        G::DPadUp => Button::DPadUp,
        G::DPadDown => Button::DPadDown,
        G::DPadLeft => Button::DPadLeft,
        G::DPadRight => Button::DPadRight,
        _ => return None,
    })
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    LeftX,
    LeftY,
    RightX,
    RightY,
    /// Analog right trigger, 0..1.
    RightTrigger,
}

/// What the gamepad thread reports.
#[derive(Debug, Clone, PartialEq)]
pub enum PadEvent {
    /// No gamepad support on this machine; the reason is for the status bar.
    Unavailable(String),
    Connected(String),
    Disconnected,
    Axis(Axis, f32),
    Pressed(Button),
    Released(Button),
}

/// What a button press asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PadCommand {
    /// A bound action.
    Action(PadAction),
    /// A D-pad button: play this sound.
    Sound(u16),
}

/// Driving input from the sticks, after deadzone and expo.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PadDrive {
    /// Compass heading the left stick points to (stick up = 0°, right = 90°).
    pub heading: f32,
    /// 0..=1 after the expo curve.
    pub magnitude: f32,
}

/// The mapping layer: raw axis values in, driving input out.
#[derive(Debug, Clone)]
pub struct PadState {
    cfg: PadConfig,
    axes: [f32; 5],
    pub connected: bool,
    pressed: HashSet<Button>,
}

fn axis_index(a: Axis) -> usize {
    match a {
        Axis::LeftX => 0,
        Axis::LeftY => 1,
        Axis::RightX => 2,
        Axis::RightY => 3,
        Axis::RightTrigger => 4,
    }
}

/// Radial deadzone then expo: 0 inside the deadzone, rescaled to 0..1 outside, curved.
pub fn shape(magnitude: f32, deadzone: f32, expo: f32) -> f32 {
    let m = magnitude.clamp(0.0, 1.0);
    if m <= deadzone {
        return 0.0;
    }
    ((m - deadzone) / (1.0 - deadzone)).powf(expo)
}

impl PadState {
    pub fn new(cfg: PadConfig) -> Self {
        PadState {
            cfg,
            axes: [0.0; 5],
            connected: false,
            pressed: HashSet::new(),
        }
    }

    /// Fold in one event; returns the command a button press asks for.
    pub fn apply(&mut self, e: &PadEvent) -> Option<PadCommand> {
        match e {
            PadEvent::Connected(_) => {
                // A pad plugged in has its sticks at rest until it reports them moved (gilrs
                // reports changes only): a value from before, from a pad since lost, must not
                // drive ("plugged in again, nothing moves until the stick does"). Buttons
                // stay: a stop button held on another pad keeps holding.
                self.connected = true;
                self.axes = [0.0; 5];
            }
            PadEvent::Disconnected | PadEvent::Unavailable(_) => {
                // Unplugged: everything back to rest (the deadman stops the droid).
                self.connected = false;
                self.axes = [0.0; 5];
                self.pressed.clear();
            }
            PadEvent::Axis(a, v) => {
                self.axes[axis_index(*a)] = if v.is_finite() {
                    v.clamp(-1.0, 1.0)
                } else {
                    0.0
                }
            }
            PadEvent::Released(b) => {
                self.pressed.remove(b);
            }
            PadEvent::Pressed(b) => {
                self.pressed.insert(*b);
                let c = &self.cfg;
                return match b {
                    Button::DPadUp => Some(PadCommand::Sound(c.sound_up)),
                    Button::DPadDown => Some(PadCommand::Sound(c.sound_down)),
                    Button::DPadLeft => Some(PadCommand::Sound(c.sound_left)),
                    Button::DPadRight => Some(PadCommand::Sound(c.sound_right)),
                    _ => c.buttons.action(*b).map(PadCommand::Action),
                };
            }
        }
        None
    }

    /// The e-stop button is held.
    pub fn estop_held(&self) -> bool {
        self.pressed
            .contains(&self.cfg.buttons.button(PadAction::EStop))
    }

    /// Left stick as polar driving input; `None` inside the deadzone (deadman).
    pub fn drive(&self) -> Option<PadDrive> {
        if !self.connected {
            return None;
        }
        let (x, y) = (self.axes[0], self.axes[1]);
        let m = shape((x * x + y * y).sqrt(), self.cfg.deadzone, self.cfg.expo);
        if m <= 0.0 {
            return None;
        }
        // gilrs: stick up is +y. Compass: up = 0°, right = 90°.
        let heading = x.atan2(y).to_degrees().rem_euclid(360.0);
        Some(PadDrive {
            heading,
            magnitude: m,
        })
    }

    /// Speed 0..=255 for a drive input: the stick scales up to `max_speed`, the right trigger
    /// adds up to `turbo`.
    pub fn speed(&self, d: &PadDrive, turbo: u8) -> u8 {
        let base = self.cfg.max_speed as f32;
        let trigger = self.axes[4].clamp(0.0, 1.0);
        let top = base + (turbo as f32 - base).max(0.0) * trigger;
        (d.magnitude * top).round().clamp(0.0, 255.0) as u8
    }

    /// Tank mode: each stick's Y (up = forward) as a track after the deadzone and curve, full
    /// deflection the configured `max_speed` (as a fraction of 255); `None` when both sticks
    /// rest (deadman).
    pub fn tracks(&self) -> Option<(f32, f32)> {
        if !self.connected {
            return None;
        }
        let top = self.cfg.max_speed as f32 / 255.0;
        let track = |y: f32| shape(y.abs(), self.cfg.deadzone, self.cfg.expo) * y.signum() * top;
        let (l, r) = (track(self.axes[1]), track(self.axes[3]));
        (l != 0.0 || r != 0.0).then_some((l, r))
    }

    /// Dome rate from the right stick X, °/s (0 inside the deadzone).
    pub fn dome_rate(&self) -> f32 {
        if !self.connected {
            return 0.0;
        }
        let x = self.axes[2];
        shape(x.abs(), self.cfg.deadzone, self.cfg.expo) * x.signum() * self.cfg.dome_rate_deg_s
    }
}

/// What droidctl reads of one gilrs event: the element gilrs named and its value. gilrs's
/// `Event` also carries a `GamepadId` and a `Code`, which gilrs makes only for a device; this
/// is what both the device thread ([`Named::from_gilrs`]) and the SDL mapping layer
/// ([`super::gamepad_map::SdlPad`], for tests and checked mappings) produce, so one function,
/// [`pad_event`], maps both.
#[derive(Debug, Clone, PartialEq)]
pub enum Named {
    Connected(String),
    Disconnected,
    Pressed(gilrs::Button),
    Released(gilrs::Button),
    /// A button's value 0..1 (analog triggers), sent after its press or release.
    Value(gilrs::Button, f32),
    Axis(gilrs::Axis, f32),
}

impl Named {
    /// gilrs's event as droidctl reads it; `name` is the pad's, asked only on a connection.
    pub fn from_gilrs(e: gilrs::EventType, name: impl FnOnce() -> String) -> Option<Named> {
        use gilrs::EventType as E;
        Some(match e {
            E::Connected => Named::Connected(name()),
            E::Disconnected => Named::Disconnected,
            E::ButtonPressed(b, _) => Named::Pressed(b),
            E::ButtonReleased(b, _) => Named::Released(b),
            E::ButtonChanged(b, v, _) => Named::Value(b, v),
            E::AxisChanged(a, v, _) => Named::Axis(a, v),
            _ => return None,
        })
    }
}

/// The one mapping from gilrs's names to droidctl's pad events: the sticks, the analog right
/// trigger (turbo), and the buttons droidctl binds.
pub fn pad_event(n: Named) -> Option<PadEvent> {
    Some(match n {
        Named::Connected(name) => PadEvent::Connected(name),
        Named::Disconnected => PadEvent::Disconnected,
        Named::Axis(a, v) => PadEvent::Axis(
            match a {
                gilrs::Axis::LeftStickX => Axis::LeftX,
                gilrs::Axis::LeftStickY => Axis::LeftY,
                gilrs::Axis::RightStickX => Axis::RightX,
                gilrs::Axis::RightStickY => Axis::RightY,
                _ => return None,
            },
            v,
        ),
        Named::Value(gilrs::Button::RightTrigger2, v) => PadEvent::Axis(Axis::RightTrigger, v),
        Named::Value(..) => return None,
        Named::Pressed(b) => PadEvent::Pressed(button_from_gilrs(b)?),
        Named::Released(b) => PadEvent::Released(button_from_gilrs(b)?),
    })
}

/// Start the gamepad thread. It sends events until the receiver is dropped. When gilrs cannot
/// start (no udev, no /dev/input) it sends one `Unavailable` and ends.
/// `mappings`: SDL controller-database lines (checked when the configuration loaded) added to
/// gilrs's own database.
pub fn spawn(
    tx: mpsc::Sender<PadEvent>,
    mappings: Vec<String>,
) -> std::io::Result<std::thread::JoinHandle<()>> {
    std::thread::Builder::new()
        .name("gamepad".into())
        .spawn(move || {
            // libudev is loaded now, on the first look for a gamepad (crates/libudev-sys).
            if let Err(why) = udev() {
                let _ = tx.blocking_send(PadEvent::Unavailable(why));
                return;
            }
            let mut builder = gilrs::GilrsBuilder::new();
            for line in &mappings {
                builder = builder.add_mappings(line);
            }
            let mut gilrs = match builder.build() {
                Ok(g) => g,
                Err(e) => {
                    let _ = tx.blocking_send(PadEvent::Unavailable(describe_error(&e)));
                    return;
                }
            };
            for (_, pad) in gilrs.gamepads() {
                if tx
                    .blocking_send(PadEvent::Connected(pad.name().to_string()))
                    .is_err()
                {
                    return;
                }
            }
            loop {
                if tx.is_closed() {
                    return;
                }
                let Some(ev) = gilrs.next_event_blocking(Some(Duration::from_millis(200))) else {
                    continue;
                };
                let name = || gilrs.gamepad(ev.id).name().to_string();
                let out = Named::from_gilrs(ev.event, name).and_then(pad_event);
                if let Some(out) = out
                    && tx.blocking_send(out).is_err()
                {
                    return;
                }
            }
        })
}

/// What the status line says where libudev cannot be loaded.
pub const NO_LIBUDEV: &str = "gamepads need libudev (systemd's udev library)";

/// Whether gilrs can look for gamepads: on Linux it needs libudev, loaded at run time; why
/// not, for the status line (the reason dlopen gave goes to the log).
fn udev() -> Result<(), String> {
    #[cfg(target_os = "linux")]
    if let Err(e) = libudev_sys::available() {
        tracing::warn!("cannot load {:?}: {e}", libudev_sys::LIBRARY);
        return Err(NO_LIBUDEV.into());
    }
    Ok(())
}

fn describe_error(e: &gilrs::Error) -> String {
    match e {
        gilrs::Error::NotImplemented(_) => "no gamepad support on this platform".into(),
        gilrs::Error::InvalidAxisToBtn => "gamepad mapping error".into(),
        gilrs::Error::Other(inner) => format!("no gamepad input ({inner})"),
        other => format!("no gamepad input ({other})"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    fn pad() -> PadState {
        let mut p = PadState::new(Config::defaults().gamepad);
        p.apply(&PadEvent::Connected("Test Pad".into()));
        p
    }

    #[test]
    fn deadzone_and_expo() {
        assert_eq!(shape(0.1, 0.15, 2.0), 0.0);
        assert_eq!(shape(1.0, 0.15, 2.0), 1.0);
        let half = shape(0.575, 0.15, 2.0);
        assert!((half - 0.25).abs() < 1e-3, "{half}");
    }

    #[test]
    fn stick_is_polar() {
        let mut p = pad();
        assert!(p.drive().is_none());
        p.apply(&PadEvent::Axis(Axis::LeftX, 1.0));
        let d = p.drive().unwrap();
        assert!((d.heading - 90.0).abs() < 1e-3);
        assert_eq!(p.speed(&d, 255), 160);
        p.apply(&PadEvent::Axis(Axis::RightTrigger, 1.0));
        assert_eq!(p.speed(&d, 255), 255);
        p.apply(&PadEvent::Axis(Axis::LeftX, 0.0));
        p.apply(&PadEvent::Axis(Axis::LeftY, -1.0));
        assert!((p.drive().unwrap().heading - 180.0).abs() < 1e-3);
        // Back inside the deadzone: no drive input.
        p.apply(&PadEvent::Axis(Axis::LeftY, -0.05));
        assert!(p.drive().is_none());
    }

    #[test]
    fn unplug_resets() {
        let mut p = pad();
        p.apply(&PadEvent::Axis(Axis::LeftY, 1.0));
        p.apply(&PadEvent::Pressed(Button::East));
        assert!(p.drive().is_some() && p.estop_held());
        p.apply(&PadEvent::Disconnected);
        assert!(p.drive().is_none() && !p.estop_held());
        assert_eq!(p.dome_rate(), 0.0);
    }

    /// Found by the app_input safety property: a stick value reported while no pad was
    /// connected drove at once when one was plugged in.
    #[test]
    fn a_pad_plugged_in_has_its_sticks_at_rest() {
        let mut p = pad();
        p.apply(&PadEvent::Disconnected);
        p.apply(&PadEvent::Axis(Axis::LeftY, 1.0));
        p.apply(&PadEvent::Pressed(Button::East));
        p.apply(&PadEvent::Connected("Another Pad".into()));
        assert!(p.drive().is_none(), "the old stick value drives");
        assert!(p.estop_held(), "the stop held is let go by a plug-in");
        p.apply(&PadEvent::Axis(Axis::LeftY, 1.0));
        assert!(p.drive().is_some());
        p.apply(&PadEvent::Connected("A Third Pad".into()));
        assert!(p.drive().is_none());
    }

    #[test]
    fn buttons_map_to_commands() {
        let mut p = pad();
        assert_eq!(
            p.apply(&PadEvent::Pressed(Button::South)),
            Some(PadCommand::Action(PadAction::Tripod))
        );
        assert_eq!(
            p.apply(&PadEvent::Pressed(Button::North)),
            Some(PadCommand::Action(PadAction::Bipod))
        );
        assert_eq!(
            p.apply(&PadEvent::Pressed(Button::East)),
            Some(PadCommand::Action(PadAction::EStop))
        );
        assert_eq!(
            p.apply(&PadEvent::Pressed(Button::West)),
            Some(PadCommand::Action(PadAction::Animation))
        );
        assert_eq!(
            p.apply(&PadEvent::Pressed(Button::DPadUp)),
            Some(PadCommand::Sound(1915))
        );
        assert_eq!(
            p.apply(&PadEvent::Pressed(Button::RightBumper)),
            Some(PadCommand::Action(PadAction::Aim))
        );
        assert_eq!(p.apply(&PadEvent::Pressed(Button::Start)), None);
        p.apply(&PadEvent::Axis(Axis::RightX, -1.0));
        assert_eq!(p.dome_rate(), -180.0);
    }
}
