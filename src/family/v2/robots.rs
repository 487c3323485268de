//! The v2 family's commands for BOLT, BOLT+, Mini and RVR: their lights (BOLT's 8-bit mask,
//! Mini's 16-bit one, RVR's 32-bit one, as spherov2.py's `toy/*.py` LEDs enums number them;
//! BOLT+'s as BOLT's, sphero-unsw's `toy/boltplus.py`), aim mode, main light, BOLT's matrix
//! (BOLT+'s screen) and compass, BOLT's and RVR's infrared, RVR's tracks and streaming service.

use crate::family::Command;
use crate::family::intent::{Intent, Ir, Matrix};
use crate::model::Model;
use crate::protocol::v2::catalog::targets::Processor;
use crate::protocol::v2::stream::sensor_by_name;
use crate::protocol::v2::types::{
    Char, FrameList, FrameRotation, Palette, ScrollText, StreamSlots, StreamWidth,
};
use crate::protocol::v2::wire::{Bytes, Mask, RawMotorMode, VoltageReadingType};
use crate::protocol::v2::{self, cmd};
use crate::script::{Action, LedGroup};

/// The LED command of a script's LED line on BOLT, Mini or RVR; `None` for other models or
/// LEDs they do not have.
pub fn led(model: Model, action: &Action) -> Option<Option<Command>> {
    let c = match (model, action) {
        // BOLT and BOLT+: bits 0..2 front RGB, 3..5 back RGB (8-bit mask; sphero-unsw's
        // BOLTPLUS.LEDs numbers them as BOLT's).
        (Model::Bolt | Model::BoltPlus, Action::LedRgb(LedGroup::Front, rgb)) => {
            cmd::set_all_leds_with_8_bit_mask(Mask(0x07), Bytes(rgb.to_vec()))
        }
        (Model::Bolt | Model::BoltPlus, Action::LedRgb(LedGroup::Back, rgb)) => {
            cmd::set_all_leds_with_8_bit_mask(Mask(0x38), Bytes(rgb.to_vec()))
        }
        // The back light as a brightness: BOLT's back LED in blue (its aiming colour here).
        (Model::Bolt | Model::BoltPlus, Action::LedBrightness(LedGroup::Back, v)) => {
            cmd::set_all_leds_with_8_bit_mask(Mask(0x38), Bytes(vec![0, 0, *v]))
        }
        // Mini: bit 0 aiming (back) light, 1..3 body RGB, 4..6 the user body RGB (16-bit
        // mask). Its one light is both: spherov2.py's `ToyUtil.set_main_led` sets the body and
        // the user body together (utils.py), and a field program's last colour on Mini was
        // half its spherov2 twin's (tests/it/edu_twins.rs).
        (Model::Mini, Action::LedRgb(LedGroup::Front, rgb)) => {
            cmd::set_all_leds_with_16_bit_mask(Mask(0x7E), Bytes([*rgb, *rgb].concat()))
        }
        // A colour for Mini's back is its user body light, as spherov2.py's
        // `ToyUtil.set_back_led` sets it (utils.py); the aiming light takes a brightness.
        (Model::Mini, Action::LedRgb(LedGroup::Back, rgb)) => {
            cmd::set_all_leds_with_16_bit_mask(Mask(0x70), Bytes(rgb.to_vec()))
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
        (Model::Bolt | Model::BoltPlus | Model::Mini | Model::Rvr, _) => return Some(None),
        _ => return None,
    };
    Some(Some(c.into()))
}

/// RVR's coloured lights, bits 0..29 of its 32-bit mask (bit 30 is the white undercarriage
/// light): its main light, as spherov2.py's `ToyUtil.set_main_led` sets it.
pub const RVR_MAIN_LIGHTS: u32 = 0x3FFF_FFFF;

/// RVR's main light: every one of its coloured lights (headlights, status, battery door,
/// power button, brake lights), as spherov2.py's `ToyUtil.set_main_led` maps it (utils.py);
/// `None` for the others ([`main_light`]).
pub fn all_lights(model: Model, rgb: [u8; 3]) -> Option<Command> {
    (model == Model::Rvr).then(|| rvr_leds(RVR_MAIN_LIGHTS, rgb))
}

/// RVR's LEDs of `mask` (its 32-bit mask, three bits a light) all set to `rgb`: the Edu API's
/// headlights and side lights, one by one.
pub fn rvr_leds(mask: u32, rgb: [u8; 3]) -> Command {
    let lights = mask.count_ones() / 3;
    let values: Vec<u8> = (0..lights).flat_map(|_| rgb).collect();
    cmd::set_all_leds_with_32_bit_mask(Mask(mask), Bytes(values)).into()
}

/// Whether `model` has the command `did`/`cid`: R2's dome and legs, BOLT's matrix and
/// RVR's palettes and streaming service are theirs alone (spherov2.py's `toy/*.py`).
pub fn model_has(model: Model, did: u8, cid: u8) -> bool {
    match (did, cid) {
        (0x17, 0x05 | 0x11 | 0x2B | 0x2C) => {
            matches!(model, Model::R2D2 | Model::R2Q5 | Model::BB9E)
        }
        (0x17, _) => model.has_legs(),
        (0x1A, 0x07..=0x0A) => matches!(model, Model::R2D2 | Model::R2Q5 | Model::BB9E),
        (0x1A, 0x0E) => !matches!(model, Model::Bolt | Model::BoltPlus | Model::Rvr),
        (0x1A, 0x1A) => model == Model::Rvr,
        (0x1A, 0x1C) => matches!(model, Model::Bolt | Model::BoltPlus),
        (0x1A, 0x2D..=0x4E) => model.has_matrix() || model == Model::Rvr,
        (0x18, 0x39..=0x3D) | (0x18, 0x35..=0x38) | (0x16, 0x25..=0x29) => {
            model.streams_by_service()
        }
        (0x18, 0x25 | 0x26 | 0x30) => model.has_compass() || model == Model::Rvr,
        _ => true,
    }
}

/// The newer robots have no Core device: Core's Ping goes as API and Shell's Echo
/// (spherov2.py pings them with 0x10/0x00).
pub fn has_no_core(model: Model) -> bool {
    matches!(
        model,
        Model::Bolt | Model::BoltPlus | Model::Mini | Model::Rvr
    )
}

/// The LEDs a model's Set All LEDs may address: R2 8; BB-9E body RGB, aiming, head
/// (`droid-facts.md` §2); BOLT and BOLT+ front and back RGB, Mini aiming, body and user RGB,
/// RVR 31 (spherov2 `toy/*.py` LEDs, sphero-unsw `toy/boltplus.py`).
pub fn led_mask(model: Model) -> u32 {
    match model {
        m if m.has_legs() => 0xFF,
        Model::Bolt | Model::BoltPlus => 0x3F,
        Model::Mini => 0x7F,
        Model::Rvr => 0x7FFF_FFFF,
        _ => 0x1F,
    }
}

/// The aiming light on or off: BOLT's back LED blue, Mini's aiming LED, RVR's brake lights.
fn aim_light(model: Model, on: bool) -> Option<v2::Command> {
    let v = if on { 255 } else { 0 };
    Some(match model {
        Model::Bolt | Model::BoltPlus => {
            cmd::set_all_leds_with_8_bit_mask(Mask(0x38), Bytes(vec![0, 0, v]))
        }
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

/// Frames (and animations) BOLT keeps: its own limit is not published, so the simulator keeps
/// this many and a Sphero Edu program may register as many (all its animations together).
pub const MATRIX_SAVED_MAX: usize = 64;

/// BOLT's matrix command for what it is to draw.
pub fn matrix(m: &Matrix) -> Command {
    let c = match m {
        Matrix::Text { text, rgb, fps } => cmd::set_compressed_frame_player_text_scrolling(
            rgb[0],
            rgb[1],
            rgb[2],
            *fps,
            false,
            ScrollText(text.clone()),
        ),
        Matrix::Char(ch, [r, g, b]) => {
            cmd::set_compressed_frame_player_single_character(*r, *g, *b, Char(*ch as u8))
        }
        Matrix::OneColour([r, g, b]) => cmd::set_compressed_frame_player_one_color(*r, *g, *b),
        Matrix::Pixel(x, y, [r, g, b]) => {
            cmd::set_compressed_frame_player_pixel(*x, *y, *r, *g, *b)
        }
        Matrix::Clear => cmd::set_compressed_frame_player_one_color(0, 0, 0),
        Matrix::Rotate(deg) => cmd::set_compressed_frame_player_frame_rotation(
            FrameRotation::from_byte((deg / 90) as u8).unwrap_or(FrameRotation::Normal),
        ),
        Matrix::Line([x1, y1, x2, y2], [r, g, b]) => {
            cmd::draw_compressed_frame_player_line(*x1, *y1, *x2, *y2, *r, *g, *b)
        }
        Matrix::Fill([x1, y1, x2, y2], [r, g, b]) => {
            cmd::draw_compressed_frame_player_fill(*x1, *y1, *x2, *y2, *r, *g, *b)
        }
        Matrix::SaveFrame(i, frame) => cmd::save_compressed_frame_player_64_bit_frame(
            *i,
            Bytes(v2::frame::pack(frame).to_vec()),
        ),
        // spherov2 sends `fps % 31`; fps is 1..=30 here.
        Matrix::SaveAnimation {
            id,
            fps,
            fade,
            palette,
            frames,
        } => cmd::save_compressed_frame_player_animation(
            *id,
            *fps,
            *fade,
            Palette(palette.clone()),
            FrameList(frames.clone()),
        ),
        Matrix::Play(id, looping) => {
            cmd::play_compressed_frame_player_animation_with_loop_option(*id, *looping)
        }
        Matrix::Pause => cmd::pause_compressed_frame_player_animation(),
        Matrix::Resume => cmd::resume_compressed_frame_player_animation(),
        Matrix::Reset => cmd::reset_compressed_frame_player_animation(),
    };
    c.into()
}

/// The main light as each v2 robot shows it: spherov2 lights BOLT's whole matrix
/// (`set_led_matrix_one_colour`), sphero-unsw fills BOLT+'s screen (`set_matrix_fill(0, 0, 7,
/// 7, …)`), R2-D2 and R2-Q5 light front and back, the others their front (or body) light;
/// RVR's is all its lights ([`all_lights`]).
pub fn main_light(model: Model, rgb: [u8; 3]) -> Vec<Intent> {
    match model {
        m if m.has_matrix() => vec![Intent::Matrix(Matrix::Fill([0, 0, 7, 7], rgb))],
        Model::R2D2 | Model::R2Q5 => vec![
            Intent::LedRgb(LedGroup::Front, rgb),
            Intent::LedRgb(LedGroup::Back, rgb),
        ],
        _ => vec![Intent::LedRgb(LedGroup::Front, rgb)],
    }
}

/// Sphero Edu's infrared calls ("Communications": broadcast, follow, evade, messages) as BOLT
/// and RVR each take them on the wire. The behaviours alike: start broadcasting, following or
/// evading with `[far, near]` (Sensor 0x27, 0x28, 0x33) and their stops (0x29, 0x32, 0x34).
/// A message is BOLT's robot-to-robot send (0x2A: the channel, then the intensity for each of
/// the four emitters) and listen (0x2B: once per channel, 0xFF for "without end"), and RVR's
/// send infrared message (0x3F, the same five bytes) and message notify (0x3E, on): spherov2.py
/// binds those to BOLT and to RVR respectively, and Sphero's RVR SDK sends RVR's
/// (src/sim/infrared.rs has the sources and what the unnamed bytes are taken to be). spherov2's
/// own `SpheroEduAPI` sends nothing for BOLT's messages ("TODO: BOLT").
pub fn infrared(model: Model, ir: &Ir) -> Vec<v2::Command> {
    let rvr = model == Model::Rvr;
    match ir {
        Ir::Broadcast { far, near } => vec![cmd::start_robot_to_robot_ir_broadcasting(*far, *near)],
        Ir::StopBroadcast => vec![cmd::stop_robot_to_robot_ir_broadcasting()],
        Ir::Follow { far, near } => vec![cmd::start_robot_to_robot_ir_following(*far, *near)],
        Ir::StopFollow => vec![cmd::stop_robot_to_robot_ir_following()],
        Ir::Evade { far, near } => vec![cmd::start_robot_to_robot_ir_evading(*far, *near)],
        Ir::StopEvade => vec![cmd::stop_robot_to_robot_ir_evading()],
        Ir::Send { channel, intensity } => {
            let data = [*channel, *intensity, *intensity, *intensity, *intensity];
            vec![if rvr {
                cmd::send_infrared_message(data)
            } else {
                cmd::send_robot_to_robot_ir_message(data)
            }]
        }
        Ir::Listen(_) if rvr => vec![cmd::enable_robot_ir_message_notify(true)],
        Ir::Listen(channels) => channels
            .iter()
            .map(|c| cmd::listen_for_robot_to_robot_ir_message([*c, 0xFF]))
            .collect(),
    }
}

/// Whether `model` has infrared Sensor command `cid` (BOLT the behaviours and its
/// robot-to-robot messages, RVR the behaviours and its own messages); `None` when `cid` is no infrared command.
pub fn infrared_has(model: Model, cid: u8) -> Option<bool> {
    let behaviours = matches!(cid, 0x27..=0x29 | 0x32..=0x34);
    let robot_to_robot = matches!(cid, 0x2A | 0x2B);
    let newer = matches!(cid, 0x3E | 0x3F);
    if !(behaviours || robot_to_robot || newer) {
        return None;
    }
    Some(match model {
        // sphero-unsw binds BOLT's robot-to-robot commands to BOLT+ (on its primary).
        Model::Bolt | Model::BoltPlus => behaviours || robot_to_robot,
        Model::Rvr => behaviours || newer,
        _ => false,
    })
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
        for m in [Model::Bolt, Model::BoltPlus, Model::Mini, Model::Rvr] {
            assert!(
                f.animation(m, 3).is_none() && f.sound(m, 1915).is_none(),
                "{m:?}"
            );
        }
    }

    #[test]
    fn each_robot_gets_its_own_message_commands() {
        let send = Ir::Send {
            channel: 3,
            intensity: 64,
        };
        let bolt = infrared(Model::Bolt, &send);
        assert_eq!(
            (bolt[0].cid, bolt[0].data.clone()),
            (0x2A, vec![3, 64, 64, 64, 64])
        );
        let rvr = infrared(Model::Rvr, &send);
        assert_eq!(
            (rvr[0].cid, rvr[0].data.clone()),
            (0x3F, vec![3, 64, 64, 64, 64])
        );
        let listen = Ir::Listen(vec![2, 5]);
        let bolt: Vec<_> = infrared(Model::Bolt, &listen)
            .into_iter()
            .map(|c| (c.cid, c.data))
            .collect();
        assert_eq!(bolt, vec![(0x2B, vec![2, 0xFF]), (0x2B, vec![5, 0xFF])]);
        let rvr = infrared(Model::Rvr, &listen);
        assert_eq!(
            (rvr.len(), rvr[0].cid, rvr[0].data.clone()),
            (1, 0x3E, vec![1])
        );
        let follow = infrared(Model::Bolt, &Ir::Follow { far: 1, near: 0 });
        assert_eq!((follow[0].cid, follow[0].data.clone()), (0x28, vec![1, 0]));
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
