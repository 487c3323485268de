//! SDL game-controller mappings applied: a controller's raw events (button N, axis N, hat N)
//! through its mapping line ([`crate::config::pad_mapping`]) into gilrs's named events, with
//! gilrs's conventions (stick Y up is +1, a trigger is a button with a 0..1 value, pressed at
//! 0.75 and released at 0.65; a trigger fed by a whole axis spans it, -1 → 0 and +1 → 1).
//!
//! Why our own: gilrs applies these lines inside itself and makes neither a `GamepadId` nor a
//! `Code` without a device, so nothing can put a raw controller event through gilrs's mapping
//! in a test. gilrs stays the device reader (given the configured lines too); this layer
//! produces the [`Named`] events gilrs's do, and [`super::gamepad::pad_event`] maps both the
//! same way.

use super::gamepad::Named;
pub use crate::config::pad_mapping::{Element, Half, MappingError, SdlMapping, Target};
use gilrs::{Axis, Button};

/// gilrs's thresholds for a button fed by an axis (`GilrsBuilder` defaults).
const PRESSED_AT: f32 = 0.75;
const RELEASED_AT: f32 = 0.65;

/// One raw controller event, as a joystick layer reports it (SDL's ranges).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RawInput {
    Button {
        index: u8,
        pressed: bool,
    },
    /// -32768..=32767, 0 at rest.
    Axis {
        index: u8,
        value: i16,
    },
    /// The hat's directions held (1 up, 2 right, 4 down, 8 left).
    Hat {
        index: u8,
        mask: u8,
    },
}

/// A controller seen through its mapping: raw events in, gilrs's named events out, with the
/// pressed state gilrs keeps to make edges of buttons fed by axes and hats.
#[derive(Debug, Clone)]
pub struct SdlPad {
    map: SdlMapping,
    pressed: Vec<Button>,
    /// Buttons' last values (absent: 0, at rest): an unchanged one is not reported again.
    values: Vec<(Button, f32)>,
}

/// -1..=1 from SDL's range, exactly 0 at rest.
fn unit(v: i16) -> f32 {
    if v >= 0 {
        v as f32 / 32767.0
    } else {
        v as f32 / 32768.0
    }
}

impl SdlPad {
    pub fn new(map: SdlMapping) -> SdlPad {
        SdlPad {
            map,
            pressed: Vec::new(),
            values: Vec::new(),
        }
    }

    pub fn name(&self) -> &str {
        &self.map.name
    }

    /// What gilrs reports when this controller is plugged in.
    pub fn connected(&self) -> Named {
        Named::Connected(self.map.name.clone())
    }

    /// What gilrs reports when it is unplugged; its buttons and axes are at rest after.
    pub fn disconnected(&mut self) -> Named {
        self.pressed.clear();
        self.values.clear();
        Named::Disconnected
    }

    /// One raw event, as gilrs's named events (none for an element the line does not bind).
    pub fn feed(&mut self, raw: RawInput) -> Vec<Named> {
        let mut out = Vec::new();
        let binds = self.map.binds().to_vec();
        for (el, t) in binds {
            // The element's reading: 0..1 for a press or a half axis, -1..1 for a whole axis.
            let v = match (el, raw) {
                (Element::Button(i), RawInput::Button { index, pressed }) if i == index => {
                    if pressed {
                        1.0
                    } else {
                        0.0
                    }
                }
                (Element::Hat { index: i, mask: m }, RawInput::Hat { index, mask })
                    if i == index =>
                {
                    if mask & m != 0 {
                        1.0
                    } else {
                        0.0
                    }
                }
                (
                    Element::Axis {
                        index: i,
                        half,
                        inverted,
                    },
                    RawInput::Axis { index, value },
                ) if i == index => {
                    let u = unit(value) * if inverted { -1.0 } else { 1.0 };
                    match half {
                        Half::Whole => u,
                        Half::Positive => u.max(0.0),
                        Half::Negative => (-u).max(0.0),
                    }
                }
                _ => continue,
            };
            let whole_axis = matches!(
                el,
                Element::Axis {
                    half: Half::Whole,
                    ..
                }
            );
            match t {
                Target::Button(b) => {
                    // A whole axis spans the button's travel (a trigger at rest reads -1).
                    let value = if whole_axis { (v + 1.0) / 2.0 } else { v };
                    self.button(b, value, &mut out);
                }
                Target::Axis(a, half) => {
                    let value = match half {
                        // A half element fills the whole axis (SDL: 0..1 → -1..1).
                        Half::Whole if !whole_axis => v * 2.0 - 1.0,
                        Half::Whole => v,
                        Half::Positive => v.abs(),
                        Half::Negative => -v.abs(),
                    };
                    // gilrs: stick Y up is +1 (SDL's and evdev's down is +).
                    let value = match a {
                        Axis::LeftStickY | Axis::RightStickY => -value,
                        _ => value,
                    };
                    out.push(Named::Axis(a, value.clamp(-1.0, 1.0)));
                }
            }
        }
        out
    }

    /// A button's new value: the edge (as gilrs's thresholds make it) then the value.
    fn button(&mut self, b: Button, value: f32, out: &mut Vec<Named>) {
        let last = self
            .values
            .iter()
            .find(|(x, _)| *x == b)
            .map_or(0.0, |v| v.1);
        if last == value {
            return;
        }
        self.values.retain(|(x, _)| *x != b);
        self.values.push((b, value));
        let was = self.pressed.contains(&b);
        if value >= PRESSED_AT && !was {
            self.pressed.push(b);
            out.push(Named::Pressed(b));
        } else if value <= RELEASED_AT && was {
            self.pressed.retain(|x| *x != b);
            out.push(Named::Released(b));
        }
        out.push(Named::Value(b, value));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SDL_GameControllerDB's Linux line for the Xbox 360 controller (045e:028e), as vendored
    /// in gilrs 0.11.2 (`SDL_GameControllerDB/gamecontrollerdb.txt`).
    const XBOX: &str = "030000005e0400008e02000010010000,Xbox 360 Controller,a:b0,b:b1,back:b6,dpdown:h0.4,dpleft:h0.8,dpright:h0.2,dpup:h0.1,guide:b8,leftshoulder:b4,leftstick:b9,lefttrigger:a2,leftx:a0,lefty:a1,rightshoulder:b5,rightstick:b10,righttrigger:a5,rightx:a3,righty:a4,start:b7,x:b2,y:b3,platform:Linux,";
    /// The same database's macOS line for it: D-pad as buttons, Y axes inverted (`a1~`).
    const XBOX_MAC: &str = "030000005e0400008e02000010010000,Xbox 360 Controller,a:b0,b:b1,back:b9,dpdown:b12,dpleft:b13,dpright:b14,dpup:b11,guide:b10,leftshoulder:b4,leftstick:b6,lefttrigger:a2,leftx:a0,lefty:a1~,rightshoulder:b5,rightstick:b7,righttrigger:a5,rightx:a3,righty:a4~,start:b8,x:b2,y:b3,platform:Mac OS X,";

    fn pad(line: &str) -> SdlPad {
        SdlPad::new(SdlMapping::parse(line).unwrap())
    }

    #[test]
    fn sticks_hats_and_triggers_as_gilrs_names_them() {
        let mut p = pad(XBOX);
        // Stick pushed up: SDL's -32768 on a1 is gilrs's +1 on LeftStickY.
        assert_eq!(
            p.feed(RawInput::Axis {
                index: 1,
                value: -32768
            }),
            vec![Named::Axis(Axis::LeftStickY, 1.0)]
        );
        assert_eq!(
            p.feed(RawInput::Hat { index: 0, mask: 2 }),
            vec![
                Named::Pressed(Button::DPadRight),
                Named::Value(Button::DPadRight, 1.0)
            ]
        );
        // The trigger at rest reads -32768: value 0, as before; pressed from 0.75, released
        // at 0.65.
        let t = |p: &mut SdlPad, v| p.feed(RawInput::Axis { index: 5, value: v });
        assert_eq!(t(&mut p, -32768), vec![]);
        assert_eq!(t(&mut p, 32767)[0], Named::Pressed(Button::RightTrigger2));
        assert_eq!(t(&mut p, 13107).len(), 1, "0.7: still pressed");
        assert_eq!(t(&mut p, 0)[0], Named::Released(Button::RightTrigger2));
    }

    #[test]
    fn inverted_axes_and_button_dpads() {
        let mut p = pad(XBOX_MAC);
        // macOS reports the stick up as +: `a1~` makes it gilrs's +1 all the same.
        assert_eq!(
            p.feed(RawInput::Axis {
                index: 1,
                value: 32767
            }),
            vec![Named::Axis(Axis::LeftStickY, 1.0)]
        );
        assert_eq!(
            p.feed(RawInput::Button {
                index: 11,
                pressed: true
            })[0],
            Named::Pressed(Button::DPadUp)
        );
        assert!(
            p.feed(RawInput::Button {
                index: 30,
                pressed: true
            })
            .is_empty(),
            "an unbound button is nothing"
        );
    }

    #[test]
    fn half_axes() {
        let line = "030000005e0400008e02000010010000,Pad,-leftx:-a0,+leftx:+a0,dpup:-a1";
        let mut p = pad(line);
        assert_eq!(
            p.feed(RawInput::Axis {
                index: 0,
                value: -16384
            }),
            vec![
                Named::Axis(Axis::LeftStickX, -0.5),
                Named::Axis(Axis::LeftStickX, 0.0)
            ]
        );
        assert_eq!(
            p.feed(RawInput::Axis {
                index: 1,
                value: -32768
            })[0],
            Named::Pressed(Button::DPadUp)
        );
    }
}
