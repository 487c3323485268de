//! The handshake and the state frame: types, decode of one BLE value, encode for the simulator.
//!
//! Wire formats (`robi-rsrcp.md`, big-endian per `droid-facts.md` §5):
//!
//! ```text
//! handshake  7E | version u8 | MSDT u16 | 7F                              (5 bytes)
//! frame      7E | frame id u24 | EFS u16 | payloads, highest bit first | 7F  (7..=16 bytes)
//! ```
//!
//! There is no length, escaping or checksum: the EFS alone says how long a frame is, and only
//! while every enabled feature has a defined size.

use super::efs::{Efs, Feature};
use super::error::{ErrorKind, FrameError, frame_error};
use bitflags::bitflags;

/// Start of packet, both for the handshake and frames.
pub const SOP: u8 = 0x7E;
/// End of packet.
pub const EOP: u8 = 0x7F;
/// The handshake is always 5 bytes (`robi-rsrcp.md`; the GATT profile reads 5 bytes too).
pub const HANDSHAKE_LEN: usize = 5;
/// SOP, 24-bit frame id and 16-bit EFS.
pub const HEADER_LEN: usize = 6;
/// A frame with nothing enabled: header and EOP.
pub const MIN_FRAME_LEN: usize = HEADER_LEN + 1;
/// Every sized feature enabled: header, 4 + 1 + 1 + 1 + 2 payload bytes, EOP.
pub const MAX_FRAME_LEN: usize = HEADER_LEN + 9 + 1;
/// Frame ids are 24-bit and wrap (`droid-facts.md` §5: "treat modulo 2^24").
pub const FRAME_ID_MASK: u32 = 0x00FF_FFFF;
/// The only protocol version the spec defines (1.0.0 is sent as 0x01).
pub const VERSION_1_0_0: u8 = 0x01;
/// Motor speeds are limited to ±300.0 rad/s (`robi-rsrcp.md`, "Motor States").
pub const MOTOR_LIMIT_RAD_S: f32 = 300.0;
/// Fixed-point scale of a motor speed: the wire holds rad/s × 100.
pub const MOTOR_SCALE: f32 = 100.0;
/// The piezo frequency has 15 bits.
pub const PIEZO_MAX_HZ: u16 = 0x7FFF;

/// What the robot sends once at connection (and what the GATT handshake characteristic holds).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Handshake {
    /// Protocol version byte; unknown versions are kept, see [`Handshake::version_name`].
    pub version: u8,
    /// The advertised interval between frames. Not to be trusted: the Robi42Lib firmware
    /// advertises 10 ms and sends every 100 ms (`droid-facts.md` §5), so measure the rate.
    pub msdt_ms: u16,
}

impl Handshake {
    pub fn decode(bytes: &[u8]) -> Result<Self, FrameError> {
        decode_handshake(bytes)
    }

    pub fn encode(&self) -> [u8; HANDSHAKE_LEN] {
        let [hi, lo] = self.msdt_ms.to_be_bytes();
        [SOP, self.version, hi, lo, EOP]
    }

    /// "1.0.0" for version byte 1, `None` for versions the spec does not define.
    pub fn version_name(&self) -> Option<&'static str> {
        match self.version {
            VERSION_1_0_0 => Some("1.0.0"),
            _ => None,
        }
    }
}

/// Both motor speeds in rad/s, negative for reverse (`robi-rsrcp.md`: left first, then right;
/// each a big-endian i16 of rad/s × 100).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motors {
    pub left_rad_s: f32,
    pub right_rad_s: f32,
}

impl Motors {
    pub const LEN: usize = 4;

    /// Decoded as the spec's `decode_fixed_point`. Values beyond ±300 are out of spec but kept
    /// as sent rather than clamped, so a misbehaving robot stays visible.
    fn decode(b: [u8; 4]) -> Motors {
        let left = i16::from_be_bytes([b[0], b[1]]);
        let right = i16::from_be_bytes([b[2], b[3]]);
        Motors {
            left_rad_s: f32::from(left) / MOTOR_SCALE,
            right_rad_s: f32::from(right) / MOTOR_SCALE,
        }
    }

    fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&fixed_point(self.left_rad_s).to_be_bytes());
        out.extend_from_slice(&fixed_point(self.right_rad_s).to_be_bytes());
    }
}

/// rad/s to the wire's i16. The spec's reference encoder raises on values beyond ±300 and
/// truncates (`int(value * 100)`); the simulator must always produce a frame, so this clamps to
/// ±300, maps NaN to 0 and rounds to the nearest hundredth (truncation would turn 0.29, which
/// is 28.999998 × 100 in f32, into 0.28).
fn fixed_point(rad_s: f32) -> i16 {
    if rad_s.is_nan() {
        return 0;
    }
    let clamped = rad_s.clamp(-MOTOR_LIMIT_RAD_S, MOTOR_LIMIT_RAD_S);
    (clamped * MOTOR_SCALE).round() as i16
}

bitflags! {
    /// The buttons byte (`droid-facts.md` §5; `robi-rsrcp.md` "Button States", MSB first).
    /// Bits 0x07 are unused; if set they are kept but have no name.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct Buttons: u8 {
        const CENTER = 0x80;
        const LEFT = 0x40;
        const RIGHT = 0x20;
        const TOP = 0x10;
        const BOTTOM = 0x08;
    }
}

impl Buttons {
    /// Names of the pressed buttons, MSB first.
    pub fn names(self) -> Vec<&'static str> {
        [
            (Buttons::CENTER, "center"),
            (Buttons::LEFT, "left"),
            (Buttons::RIGHT, "right"),
            (Buttons::TOP, "top"),
            (Buttons::BOTTOM, "bottom"),
        ]
        .into_iter()
        .filter(|(b, _)| self.contains(*b))
        .map(|(_, n)| n)
        .collect()
    }
}

bitflags! {
    /// The LEDs byte: the eight lamps, MSB first, as `robi-rsrcp.md` "LED States" names them
    /// (clockwise from the front left).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct Leds: u8 {
        const FRONT_LEFT_BLINKER = 0x80;
        const FRONT_LEFT_HEADLIGHT = 0x40;
        const FRONT_RIGHT_HEADLIGHT = 0x20;
        const FRONT_RIGHT_BLINKER = 0x10;
        const BACK_RIGHT_BLINKER = 0x08;
        const BACK_RIGHT_TAILLIGHT = 0x04;
        const BACK_LEFT_TAILLIGHT = 0x02;
        const BACK_LEFT_BLINKER = 0x01;
    }
}

impl Leds {
    /// Names of the lit lamps, MSB first.
    pub fn names(self) -> Vec<&'static str> {
        [
            (Leds::FRONT_LEFT_BLINKER, "front_left_blinker"),
            (Leds::FRONT_LEFT_HEADLIGHT, "front_left_headlight"),
            (Leds::FRONT_RIGHT_HEADLIGHT, "front_right_headlight"),
            (Leds::FRONT_RIGHT_BLINKER, "front_right_blinker"),
            (Leds::BACK_RIGHT_BLINKER, "back_right_blinker"),
            (Leds::BACK_RIGHT_TAILLIGHT, "back_right_taillight"),
            (Leds::BACK_LEFT_TAILLIGHT, "back_left_taillight"),
            (Leds::BACK_LEFT_BLINKER, "back_left_blinker"),
        ]
        .into_iter()
        .filter(|(b, _)| self.contains(*b))
        .map(|(_, n)| n)
        .collect()
    }
}

/// The piezo: an audible bit (the u16's MSB) and a 15-bit frequency in Hz.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Piezo {
    pub on: bool,
    pub hz: u16,
}

impl Piezo {
    pub const LEN: usize = 2;

    fn decode(b: [u8; 2]) -> Piezo {
        let raw = u16::from_be_bytes(b);
        Piezo {
            on: raw & 0x8000 != 0,
            hz: raw & PIEZO_MAX_HZ,
        }
    }

    /// Frequencies above 15 bits are clamped to 32767 Hz rather than spilling into the
    /// audible bit.
    fn encode(&self, out: &mut Vec<u8>) {
        let raw = (u16::from(self.on) << 15) | self.hz.min(PIEZO_MAX_HZ);
        out.extend_from_slice(&raw.to_be_bytes());
    }
}

/// One state frame. A feature's field is `Some` exactly when it was enabled and decoded.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Frame {
    /// 24-bit, incremented per frame, wrapping (see [`super::frame_gap`]).
    pub frame_id: u32,
    /// The EFS as sent. In a partial frame (see [`FrameError::partial`](super::FrameError::partial)) it names features
    /// that were not decoded.
    pub efs: Efs,
    pub motors: Option<Motors>,
    pub poti: Option<u8>,
    pub buttons: Option<Buttons>,
    pub leds: Option<Leds>,
    pub piezo: Option<Piezo>,
}

/// How a frame with a given EFS is laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Layout {
    /// Every enabled feature is sized: the whole frame, SOP to EOP, is this long.
    Sized(usize),
    /// Decoding must stop `prefix` bytes into the frame (header plus the sized features
    /// before the obstacle).
    Unframable { prefix: usize, stop: Stop },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stop {
    Unsized(Feature),
    Reserved,
}

pub(crate) fn layout(efs: Efs) -> Layout {
    let mut len = HEADER_LEN;
    for f in efs.features() {
        match f.size() {
            Some(n) => len += n,
            None => {
                return Layout::Unframable {
                    prefix: len,
                    stop: Stop::Unsized(f),
                };
            }
        }
    }
    if efs.reserved() != 0 {
        return Layout::Unframable {
            prefix: len,
            stop: Stop::Reserved,
        };
    }
    Layout::Sized(len + 1)
}

impl Frame {
    /// An empty frame (nothing enabled); add features with the `with_*` builders.
    pub fn new(frame_id: u32) -> Frame {
        Frame {
            frame_id: frame_id & FRAME_ID_MASK,
            ..Frame::default()
        }
    }

    pub fn with_motors(mut self, left_rad_s: f32, right_rad_s: f32) -> Frame {
        self.motors = Some(Motors {
            left_rad_s,
            right_rad_s,
        });
        self.efs |= Efs::MOTORS;
        self
    }

    pub fn with_poti(mut self, poti: u8) -> Frame {
        self.poti = Some(poti);
        self.efs |= Efs::POTI;
        self
    }

    pub fn with_buttons(mut self, buttons: Buttons) -> Frame {
        self.buttons = Some(buttons);
        self.efs |= Efs::BUTTONS;
        self
    }

    pub fn with_leds(mut self, leds: Leds) -> Frame {
        self.leds = Some(leds);
        self.efs |= Efs::LEDS;
        self
    }

    pub fn with_piezo(mut self, on: bool, hz: u16) -> Frame {
        self.piezo = Some(Piezo { on, hz });
        self.efs |= Efs::PIEZO;
        self
    }

    pub fn decode(bytes: &[u8]) -> Result<Frame, FrameError> {
        decode_frame(bytes)
    }

    /// The total length, SOP to EOP, of a frame with this EFS; `None` when it enables a
    /// feature without a defined size or sets a reserved bit (the length is then unknowable).
    pub fn len_for(efs: Efs) -> Option<usize> {
        match layout(efs) {
            Layout::Sized(len) => Some(len),
            Layout::Unframable { .. } => None,
        }
    }

    /// The EFS of the features this frame carries values for (what [`Frame::encode`] sends).
    pub fn sized_efs(&self) -> Efs {
        let mut efs = Efs::empty();
        efs.set(Efs::MOTORS, self.motors.is_some());
        efs.set(Efs::POTI, self.poti.is_some());
        efs.set(Efs::BUTTONS, self.buttons.is_some());
        efs.set(Efs::LEDS, self.leds.is_some());
        efs.set(Efs::PIEZO, self.piezo.is_some());
        efs
    }

    /// The wire bytes, for the simulator. The EFS sent is [`Frame::sized_efs`]: unsized
    /// features and reserved bits in `efs` cannot be encoded (they have no defined payload)
    /// and are left out; the frame id is masked to 24 bits.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(MAX_FRAME_LEN);
        out.push(SOP);
        let id = (self.frame_id & FRAME_ID_MASK).to_be_bytes();
        out.extend_from_slice(&id[1..]);
        out.extend_from_slice(&self.sized_efs().bits().to_be_bytes());
        if let Some(m) = &self.motors {
            m.encode(&mut out);
        }
        if let Some(p) = self.poti {
            out.push(p);
        }
        if let Some(b) = self.buttons {
            out.push(b.bits());
        }
        if let Some(l) = self.leds {
            out.push(l.bits());
        }
        if let Some(p) = &self.piezo {
            p.encode(&mut out);
        }
        out.push(EOP);
        out
    }

    /// Read the header and the sized features that precede the first unsized one. The caller
    /// has checked the length; a short slice just leaves later features `None`.
    fn read(bytes: &[u8]) -> Frame {
        let mut frame = Frame {
            frame_id: be_u24(bytes),
            efs: be_efs(bytes),
            ..Frame::default()
        };
        let mut pos = HEADER_LEN;
        for f in frame.efs.features() {
            let Some(n) = f.size() else { break };
            let Some(p) = bytes.get(pos..pos + n) else {
                break;
            };
            match (f, p) {
                (Feature::Motors, &[a, b, c, d]) => {
                    frame.motors = Some(Motors::decode([a, b, c, d]))
                }
                (Feature::Poti, &[v]) => frame.poti = Some(v),
                (Feature::Buttons, &[v]) => frame.buttons = Some(Buttons::from_bits_retain(v)),
                (Feature::Leds, &[v]) => frame.leds = Some(Leds::from_bits_retain(v)),
                (Feature::Piezo, &[a, b]) => frame.piezo = Some(Piezo::decode([a, b])),
                _ => {}
            }
            pos += n;
        }
        frame
    }
}

fn be_u24(bytes: &[u8]) -> u32 {
    match bytes.get(1..4) {
        Some(&[a, b, c]) => u32::from_be_bytes([0, a, b, c]),
        _ => 0,
    }
}

fn be_efs(bytes: &[u8]) -> Efs {
    match bytes.get(4..6) {
        Some(&[a, b]) => Efs::from_bits_retain(u16::from_be_bytes([a, b])),
        _ => Efs::empty(),
    }
}

fn err(kind: ErrorKind, at: usize, detail: String) -> FrameError {
    frame_error(kind, at, detail)
}

/// Decode one frame that arrived alone, as one BLE notification of the frames characteristic
/// does (`droid-facts.md` §5). The length must match the EFS exactly: a short value is
/// `truncated`, a long one `overlong`, then the computed last byte must be EOP. A frame that
/// enables an unsized feature or a reserved bit is an error that carries what precedes it in
/// [`FrameError::partial`](super::FrameError::partial). `offset` of the error is 0; `at` is the index in `bytes`.
pub fn decode_frame(bytes: &[u8]) -> Result<Frame, FrameError> {
    use ErrorKind::*;
    let len = bytes.len();
    match bytes.first() {
        None => return Err(err(Truncated, 0, "empty value".into())),
        Some(&SOP) => {}
        Some(&b) => {
            return Err(err(
                BadSop,
                0,
                format!("first byte 0x{b:02X}, expected SOP 0x7E"),
            ));
        }
    }
    if len < HEADER_LEN {
        return Err(err(
            Truncated,
            len,
            format!("{len} byte(s), the frame header needs {HEADER_LEN}"),
        ));
    }
    let efs = be_efs(bytes);
    match layout(efs) {
        Layout::Sized(total) => {
            if len < total {
                return Err(err(
                    Truncated,
                    len,
                    format!("{len} byte(s), EFS 0x{:04X} implies {total}", efs.bits()),
                ));
            }
            if len > total {
                return Err(err(
                    Overlong,
                    total,
                    format!("{len} byte(s), EFS 0x{:04X} implies {total}", efs.bits()),
                ));
            }
            let last = bytes[total - 1];
            if last != EOP {
                return Err(err(
                    BadEop,
                    total - 1,
                    format!(
                        "byte {} is 0x{last:02X}, expected EOP 0x7F (EFS 0x{:04X} implies {total} bytes)",
                        total - 1,
                        efs.bits()
                    ),
                ));
            }
            Ok(Frame::read(bytes))
        }
        Layout::Unframable { prefix, stop } => {
            if len < prefix {
                return Err(err(
                    Truncated,
                    len,
                    format!(
                        "{len} byte(s), the features before the first unreadable one need {prefix}"
                    ),
                ));
            }
            let frame = Frame::read(&bytes[..prefix]);
            let e = match stop {
                Stop::Unsized(f) => {
                    let e = err(
                        UnsizedFeature,
                        prefix,
                        format!(
                            "EFS 0x{:04X} enables {}, whose size the spec does not define: \
                             decoded up to byte {prefix}, not past it",
                            efs.bits(),
                            f.name()
                        ),
                    );
                    e.with_feature(f)
                }
                Stop::Reserved => err(
                    ReservedBits,
                    prefix,
                    format!(
                        "EFS 0x{:04X} sets reserved bits 0x{:02X}: defined features decoded, \
                         the frame's end is unknown",
                        efs.bits(),
                        efs.reserved()
                    ),
                ),
            };
            Err(e.with_partial(frame))
        }
    }
}

/// Decode the 5-byte handshake (the value of the handshake characteristic). Any version byte
/// is accepted and kept; see [`Handshake::version_name`].
pub fn decode_handshake(bytes: &[u8]) -> Result<Handshake, FrameError> {
    use ErrorKind::*;
    let len = bytes.len();
    match bytes {
        [] => Err(err(Truncated, 0, "empty value".into())),
        [b, ..] if *b != SOP => Err(err(
            BadSop,
            0,
            format!("first byte 0x{b:02X}, expected SOP 0x7E"),
        )),
        [SOP, version, m0, m1, last, rest @ ..] => {
            if !rest.is_empty() {
                Err(err(
                    Overlong,
                    HANDSHAKE_LEN,
                    format!("{len} bytes, a handshake has {HANDSHAKE_LEN}"),
                ))
            } else if *last != EOP {
                Err(err(
                    BadEop,
                    4,
                    format!("byte 4 is 0x{last:02X}, expected EOP 0x7F"),
                ))
            } else {
                Ok(Handshake {
                    version: *version,
                    msdt_ms: u16::from_be_bytes([*m0, *m1]),
                })
            }
        }
        _ => Err(err(
            Truncated,
            len,
            format!("{len} byte(s), a handshake has {HANDSHAKE_LEN}"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hex;

    #[test]
    fn layout_lengths() {
        assert_eq!(Frame::len_for(Efs::empty()), Some(MIN_FRAME_LEN));
        assert_eq!(Frame::len_for(Efs::SIZED), Some(MAX_FRAME_LEN));
        assert_eq!(Frame::len_for(Efs::FIRMWARE), Some(13));
        assert_eq!(Frame::len_for(Efs::GYRO), None);
        assert_eq!(Frame::len_for(Efs::from_bits_retain(0x0001)), None);
        assert_eq!(
            layout(Efs::from_bits_retain(0x6300)),
            Layout::Unframable {
                prefix: 10,
                stop: Stop::Unsized(Feature::Gyro)
            }
        );
    }

    #[test]
    fn motors_fixed_point() {
        assert_eq!(fixed_point(1.25), 125);
        assert_eq!(fixed_point(0.29), 29);
        assert_eq!(fixed_point(-300.0), -30000);
        assert_eq!(fixed_point(1e9), 30000);
        assert_eq!(fixed_point(f32::NEG_INFINITY), -30000);
        assert_eq!(fixed_point(f32::NAN), 0);
        let m = Motors::decode([0x80, 0x00, 0x7F, 0xFF]);
        assert_eq!(m.left_rad_s, -327.68);
        assert_eq!(m.right_rad_s, 327.67);
    }

    #[test]
    fn piezo_bits() {
        assert_eq!(Piezo::decode([0x81, 0xB8]), Piezo { on: true, hz: 440 });
        assert_eq!(
            Piezo::decode([0x4E, 0x20]),
            Piezo {
                on: false,
                hz: 20000
            }
        );
        let mut out = Vec::new();
        Piezo {
            on: false,
            hz: 0xFFFF,
        }
        .encode(&mut out);
        assert_eq!(out, vec![0x7F, 0xFF]);
    }

    #[test]
    fn handshake_bytes() {
        let h = decode_handshake(&hex::parse("7E 01 00 0A 7F").unwrap()).unwrap();
        assert_eq!(
            h,
            Handshake {
                version: 1,
                msdt_ms: 10
            }
        );
        assert_eq!(h.version_name(), Some("1.0.0"));
        assert_eq!(h.encode().to_vec(), hex::parse("7E 01 00 0A 7F").unwrap());
    }
}
