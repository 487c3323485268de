//! The v2 family's commands for BOLT, Mini and RVR: their lights (BOLT's 8-bit mask, Mini's
//! 16-bit one, RVR's 32-bit one, as spherov2.py's `toy/*.py` LEDs enums number them), aim
//! mode, BOLT's matrix and compass, RVR's tracks and streaming service.

use crate::family::Command;
use crate::model::Model;
use crate::protocol::v2::catalog::targets::Processor;
use crate::protocol::v2::stream::sensor_by_name;
use crate::protocol::v2::types::{Char, FrameRotation, ScrollText, StreamSlots, StreamWidth};
use crate::protocol::v2::wire::{Bytes, Mask, RawMotorMode, VoltageReadingType};
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

/// RVR's battery: volts (calibrated, filtered) from the primary, the processor that measures
/// it (spherov2's `toy/rvr.py` binds Get Battery Voltage In Volts there and not Power 0x03).
pub fn battery_request(model: Model) -> Option<Command> {
    (model == Model::Rvr).then(|| {
        cmd::get_battery_voltage_in_volts(VoltageReadingType::CalibratedFiltered)
            .to(Processor::Primary)
            .into()
    })
}

/// The volts of Get Battery Voltage In Volts: a big-endian f32, believed when plausible.
pub fn battery_volts(response: &[u8]) -> Option<f32> {
    let v = f32::from_be_bytes(response.try_into().ok()?);
    (v.is_finite() && (0.0..=30.0).contains(&v)).then_some(v)
}

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

/// RVR's streaming service stopped on both processors.
pub fn rvr_streaming_off() -> Vec<Command> {
    [Processor::Primary, Processor::Secondary]
        .into_iter()
        .map(|p| cmd::stop_streaming_service().to(p).into())
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_star_wars_droids_play_animations_and_sounds() {
        use crate::family::Family;
        let f = &super::super::V2;
        for m in [Model::R2D2, Model::R2Q5, Model::BB9E] {
            assert!(
                f.animation(m, 3).is_some() && f.sound(m, 1915).is_some(),
                "{m:?}"
            );
        }
        // No speaker, and spherov2 binds neither: refused here, not by the robot.
        for m in [Model::Bolt, Model::Mini, Model::Rvr] {
            assert!(
                f.animation(m, 3).is_none() && f.sound(m, 1915).is_none(),
                "{m:?}"
            );
        }
    }

    #[test]
    fn rvr_battery_is_read_from_the_primary() {
        let Some(Command::V2(c)) = battery_request(Model::Rvr) else {
            panic!("RVR has a battery request");
        };
        assert_eq!(
            (c.did, c.cid, c.target, &c.data[..]),
            (0x13, 0x25, Some(0x11), &[0][..])
        );
        assert!(battery_request(Model::Bolt).is_none());
        assert_eq!(battery_volts(&3.9f32.to_be_bytes()), Some(3.9));
        assert_eq!(battery_volts(&f32::NAN.to_be_bytes()), None);
        assert_eq!(battery_volts(&[1, 2]), None);
    }

    #[test]
    fn rvr_streams_motion_on_the_secondary_and_colour_on_the_primary() {
        let cmds = rvr_streaming(100);
        let v2: Vec<_> = cmds.iter().filter_map(|c| c.as_v2()).collect();
        let configure: Vec<_> = v2.iter().filter(|c| c.cid == 0x39).collect();
        assert_eq!(configure.len(), 4);
        // Colour detection (id 3) at 8 bits on the primary.
        assert!(
            configure
                .iter()
                .any(|c| c.target == Some(0x11) && c.data == [1, 0, 3, 0])
        );
        // Each processor is stopped and cleared before it is configured, then started.
        for t in [0x11, 0x12] {
            let seq: Vec<u8> = v2
                .iter()
                .filter(|c| c.target == Some(t))
                .map(|c| c.cid)
                .collect();
            assert_eq!(seq.first(), Some(&0x3B));
            assert_eq!(seq.get(1), Some(&0x3C));
            assert_eq!(seq.last(), Some(&0x3A));
        }
    }
}
