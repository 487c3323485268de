//! The v2 family's commands for BOLT, Mini and RVR: their lights (BOLT's 8-bit mask, Mini's
//! 16-bit one, RVR's 32-bit one, as spherov2.py's `toy/*.py` LEDs enums number them), aim
//! mode, BOLT's matrix and compass, RVR's tracks and streaming service.

use crate::family::Command;
use crate::model::Model;
use crate::protocol::v2::catalog::targets::Processor;
use crate::protocol::v2::stream::sensor_by_name;
use crate::protocol::v2::types::{Char, FrameRotation, ScrollText, StreamSlots, StreamWidth};
use crate::protocol::v2::wire::{Bytes, Mask, RawMotorMode};
use crate::protocol::v2::{self, cmd};
use crate::script::{Action, LedGroup, MatrixAction};

/// The LED command of a script's LED line on BOLT, Mini or RVR; `None` for other models or
/// LEDs they do not have.
pub fn led(model: Model, action: &Action) -> Option<Option<Command>> {
    let c = match (model, action) {
        // BOLT: bits 0..2 front RGB, 3..5 back RGB (8-bit mask).
        (Model::Bolt, Action::LedRgb(LedGroup::Front, rgb)) => {
            cmd::set_all_leds_with_8_bit_mask(Mask(0x07), Bytes(rgb.to_vec()))
        }
        (Model::Bolt, Action::LedRgb(LedGroup::Back, rgb)) => {
            cmd::set_all_leds_with_8_bit_mask(Mask(0x38), Bytes(rgb.to_vec()))
        }
        // The back light as a brightness: BOLT's back LED in blue (its aiming colour here).
        (Model::Bolt, Action::LedBrightness(LedGroup::Back, v)) => {
            cmd::set_all_leds_with_8_bit_mask(Mask(0x38), Bytes(vec![0, 0, *v]))
        }
        // Mini: bit 0 aiming (back) light, 1..3 body RGB (16-bit mask).
        (Model::Mini, Action::LedRgb(LedGroup::Front, rgb)) => {
            cmd::set_all_leds_with_16_bit_mask(Mask(0x0E), Bytes(rgb.to_vec()))
        }
        (Model::Mini, Action::LedRgb(LedGroup::Back, [r, g, b])) => {
            cmd::set_all_leds_with_16_bit_mask(Mask(0x01), Bytes(vec![*r.max(g).max(b)]))
        }
        (Model::Mini, Action::LedBrightness(LedGroup::Back, v)) => {
            cmd::set_all_leds_with_16_bit_mask(Mask(0x01), Bytes(vec![*v]))
        }
        // RVR: headlights are bits 0..5 (right, left), brake lights 24..29 (32-bit mask).
        (Model::Rvr, Action::LedRgb(LedGroup::Front, rgb)) => {
            cmd::set_all_leds_with_32_bit_mask(Mask(0x3F), Bytes([*rgb, *rgb].concat()))
        }
        (Model::Rvr, Action::LedRgb(LedGroup::Back, rgb)) => {
            cmd::set_all_leds_with_32_bit_mask(Mask(0x3F00_0000), Bytes([*rgb, *rgb].concat()))
        }
        (Model::Rvr, Action::LedBrightness(LedGroup::Back, v)) => {
            cmd::set_all_leds_with_32_bit_mask(Mask(0x3F00_0000), Bytes(vec![*v, 0, 0, *v, 0, 0]))
        }
        (Model::Bolt | Model::Mini | Model::Rvr, _) => return Some(None),
        _ => return None,
    };
    Some(Some(c.into()))
}

/// The aiming light on or off: BOLT's back LED blue, Mini's aiming LED, RVR's brake lights.
fn aim_light(model: Model, on: bool) -> Option<v2::Command> {
    let v = if on { 255 } else { 0 };
    Some(match model {
        Model::Bolt => cmd::set_all_leds_with_8_bit_mask(Mask(0x38), Bytes(vec![0, 0, v])),
        Model::Mini => cmd::set_all_leds_with_16_bit_mask(Mask(0x01), Bytes(vec![v])),
        Model::Rvr => {
            cmd::set_all_leds_with_32_bit_mask(Mask(0x3F00_0000), Bytes(vec![v, 0, 0, v, 0, 0]))
        }
        _ => return None,
    })
}

/// Aim mode's first commands on the newer robots, `None` for the others.
pub fn aim_begin(model: Model) -> Option<Vec<Command>> {
    Some(vec![aim_light(model, true)?.into()])
}

/// Leaving aim mode: heading 0 is where the robot faces; the light off.
pub fn aim_end(model: Model) -> Option<Vec<Command>> {
    let off = aim_light(model, false)?;
    Some(vec![cmd::reset_yaw().into(), off.into()])
}

/// BOLT's matrix commands for a `matrix` line.
pub fn matrix(action: &MatrixAction) -> Command {
    let c = match action {
        MatrixAction::Text {
            text,
            rgb: [r, g, b],
        } => cmd::set_compressed_frame_player_text_scrolling(
            *r,
            *g,
            *b,
            7,
            false,
            ScrollText(text.chars().take(25).collect()),
        ),
        MatrixAction::Char { ch, rgb: [r, g, b] } => {
            cmd::set_compressed_frame_player_single_character(*r, *g, *b, Char(*ch as u8))
        }
        MatrixAction::Fill([r, g, b]) => cmd::set_compressed_frame_player_one_color(*r, *g, *b),
        MatrixAction::Pixel {
            x,
            y,
            rgb: [r, g, b],
        } => cmd::set_compressed_frame_player_pixel(*x, *y, *r, *g, *b),
        MatrixAction::Clear => cmd::set_compressed_frame_player_one_color(0, 0, 0),
        MatrixAction::Rotate(deg) => cmd::set_compressed_frame_player_frame_rotation(
            FrameRotation::from_byte((deg / 90) as u8).unwrap_or(FrameRotation::Normal),
        ),
    };
    c.into()
}

/// Raw motors for tracks at `left`/`right` in −255..=255.
pub fn tank(left: i16, right: i16) -> Command {
    let side = |v: i16| match v {
        0 => (RawMotorMode::Off, 0),
        v if v > 0 => (RawMotorMode::Forward, v.min(255) as u8),
        v => (RawMotorMode::Reverse, v.unsigned_abs().min(255) as u8),
    };
    let ((lm, ls), (rm, rs)) = (side(left), side(right));
    cmd::set_raw_motors(lm, ls, rm, rs).into()
}

/// The sensors droidctl streams from an RVR, per processor and token (at most four a
/// token): motion on the secondary, colour and light on the primary.
const RVR_STREAMS: [(Processor, u8, &[&str]); 4] = [
    (
        Processor::Secondary,
        1,
        &["imu", "accelerometer", "gyroscope"],
    ),
    (Processor::Secondary, 2, &["locator", "velocity", "speed"]),
    (Processor::Primary, 1, &["color_detection"]),
    (Processor::Primary, 2, &["ambient_light"]),
];

/// RVR's streaming: stop and clear each processor, configure its tokens, start it at
/// `period_ms` (spherov2's StreamingControl order).
pub fn rvr_streaming(period_ms: u16) -> Vec<Command> {
    let mut out = Vec::new();
    for p in [Processor::Primary, Processor::Secondary] {
        out.push(cmd::stop_streaming_service().to(p));
        out.push(cmd::clear_streaming_service().to(p));
        for (q, token, names) in RVR_STREAMS {
            if q != p {
                continue;
            }
            let slots = names
                .iter()
                .filter_map(|n| sensor_by_name(n))
                .map(|s| {
                    let w = if s.name == "color_detection" {
                        StreamWidth::Bits8
                    } else {
                        StreamWidth::Bits32
                    };
                    (s.id, w)
                })
                .collect();
            out.push(cmd::configure_streaming_service(token, StreamSlots(slots)).to(p));
        }
        out.push(cmd::start_streaming_service(period_ms.max(33)).to(p));
    }
    out.into_iter().map(Command::from).collect()
}

/// What the newer robots add to the connect setup: RVR's motor notifications, colour
/// detection and streaming service; BOLT's ambient light rides on the extended mask.
pub fn setup_extra(model: Model, streaming_interval_ms: u16) -> Vec<Command> {
    match model {
        Model::Rvr => {
            let mut out: Vec<Command> = vec![
                cmd::enable_motor_stall_notify(true).into(),
                cmd::enable_motor_fault_notify(true).into(),
                cmd::enable_color_detection(true).into(),
            ];
            if streaming_interval_ms > 0 {
                out.extend(rvr_streaming(streaming_interval_ms));
            }
            out
        }
        _ => Vec::new(),
    }
}
