//! v1 sensor streaming: Set Data Streaming (Sphero 0x11) and async ID 03.
//!
//! `droid-facts.md` §4: each frame is one big-endian i16 per set bit, MASK bits from high to
//! low, then MASK2 bits from high to low; a packet holds M frames. Values are scaled to the
//! names and units the v2 side uses (`crate::protocol::v2::sensor`), so telemetry reads both
//! families alike: accel in g, gyro in °/s, angles in degrees, locator in cm, velocity in
//! cm/s. Raw-sensor values get their own `_raw` names.
//!
//! Bits and scalings beyond droid-facts.md (motor back EMF and PWM) come from the Sphero API
//! 1.50 mask table as spheropy implements it (right before left for back EMF, left before
//! right for PWM; spherov2.py has the filtered back-EMF pair the other way round). Their
//! values are shown as sent.

use super::catalog::{Command, cmd};

/// One streamable sensor component.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorField {
    pub bit: u32,
    /// In MASK2 rather than MASK.
    pub mask2: bool,
    /// snake_case name used in the packet log, JSON and telemetry.
    pub name: &'static str,
    /// Multiply the wire value by this to get the unit below.
    pub scale: f32,
    pub unit: &'static str,
}

const fn m1(bit: u32, name: &'static str, scale: f32, unit: &'static str) -> SensorField {
    SensorField {
        bit,
        mask2: false,
        name,
        scale,
        unit,
    }
}

const fn m2(bit: u32, name: &'static str, scale: f32, unit: &'static str) -> SensorField {
    SensorField {
        bit,
        mask2: true,
        name,
        scale,
        unit,
    }
}

/// MASK fields, descending bit order.
pub const MASK_FIELDS: [SensorField; 21] = [
    // Raw accelerometer, 4 mG per unit.
    m1(0x8000_0000, "accel_raw_x", 0.004, "g"),
    m1(0x4000_0000, "accel_raw_y", 0.004, "g"),
    m1(0x2000_0000, "accel_raw_z", 0.004, "g"),
    // Raw gyro, 0.068 °/s per unit.
    m1(0x1000_0000, "gyro_raw_x", 0.068, "deg/s"),
    m1(0x0800_0000, "gyro_raw_y", 0.068, "deg/s"),
    m1(0x0400_0000, "gyro_raw_z", 0.068, "deg/s"),
    m1(0x0040_0000, "back_emf_raw_right", 1.0, ""),
    m1(0x0020_0000, "back_emf_raw_left", 1.0, ""),
    m1(0x0010_0000, "pwm_raw_left", 1.0, ""),
    m1(0x0008_0000, "pwm_raw_right", 1.0, ""),
    m1(0x0004_0000, "pitch", 1.0, "deg"),
    m1(0x0002_0000, "roll", 1.0, "deg"),
    m1(0x0001_0000, "yaw", 1.0, "deg"),
    // Filtered accelerometer, 1/4096 g.
    m1(0x0000_8000, "accel_x", 1.0 / 4096.0, "g"),
    m1(0x0000_4000, "accel_y", 1.0 / 4096.0, "g"),
    m1(0x0000_2000, "accel_z", 1.0 / 4096.0, "g"),
    // Filtered gyro, 0.1 °/s.
    m1(0x0000_1000, "gyro_x", 0.1, "deg/s"),
    m1(0x0000_0800, "gyro_y", 0.1, "deg/s"),
    m1(0x0000_0400, "gyro_z", 0.1, "deg/s"),
    m1(0x0000_0040, "back_emf_right", 1.0, ""),
    m1(0x0000_0020, "back_emf_left", 1.0, ""),
];

/// MASK2 fields, descending bit order. Q0..Q3 are taken as w, x, y, z (Q0 the scalar part,
/// as the Sphero API document orders them); spherov2.py labels the same four x, y, z, w.
pub const MASK2_FIELDS: [SensorField; 9] = [
    m2(0x8000_0000, "quaternion_w", 1.0 / 10000.0, ""),
    m2(0x4000_0000, "quaternion_x", 1.0 / 10000.0, ""),
    m2(0x2000_0000, "quaternion_y", 1.0 / 10000.0, ""),
    m2(0x1000_0000, "quaternion_z", 1.0 / 10000.0, ""),
    // Odometer, cm.
    m2(0x0800_0000, "locator_x", 1.0, "cm"),
    m2(0x0400_0000, "locator_y", 1.0, "cm"),
    // Magnitude of acceleration, mG.
    m2(0x0200_0000, "accel_one", 1.0, "mG"),
    // mm/s ÷ 10 = cm/s.
    m2(0x0100_0000, "velocity_x", 0.1, "cm/s"),
    m2(0x0080_0000, "velocity_y", 0.1, "cm/s"),
];

/// Useful mask groups.
pub mod mask {
    pub const ACCEL_RAW: u32 = 0xE000_0000;
    pub const GYRO_RAW: u32 = 0x1C00_0000;
    pub const BACK_EMF_RAW: u32 = 0x0060_0000;
    pub const PWM_RAW: u32 = 0x0018_0000;
    /// Pitch, roll, yaw.
    pub const IMU: u32 = 0x0007_0000;
    pub const ACCEL: u32 = 0x0000_E000;
    pub const GYRO: u32 = 0x0000_1C00;
    pub const BACK_EMF: u32 = 0x0000_0060;
    /// MASK2: Q0..Q3.
    pub const QUATERNION: u32 = 0xF000_0000;
    /// MASK2: odometer x, y.
    pub const LOCATOR: u32 = 0x0C00_0000;
    /// MASK2.
    pub const ACCEL_ONE: u32 = 0x0200_0000;
    /// MASK2: velocity x, y.
    pub const VELOCITY: u32 = 0x0180_0000;
}

/// The Set Data Streaming parameters in effect, which determine how async ID 03 is read.
/// `Default` is "off" (all zero).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StreamingConfig {
    /// Divisor of the 400 Hz sample rate.
    pub n: u16,
    /// Frames per packet.
    pub m: u16,
    pub mask: u32,
    /// Packets to send, 0 = forever.
    pub pcnt: u8,
    pub mask2: u32,
}

/// The droid's maximum sensor sampling rate that N divides (`droid-facts.md` §4: 400/N Hz).
pub const SAMPLE_RATE_HZ: f32 = 400.0;

impl StreamingConfig {
    /// The set droidctl asks for at `n` (divisor): attitude, filtered accelerometer and gyro
    /// (MASK 0x00077C00), locator and velocity (MASK2 0x0D800000), one frame per packet,
    /// forever.
    pub fn full(n: u16) -> Self {
        StreamingConfig {
            n,
            m: 1,
            mask: mask::IMU | mask::ACCEL | mask::GYRO,
            pcnt: 0,
            mask2: mask::LOCATOR | mask::VELOCITY,
        }
    }

    /// Snoop a Set Data Streaming payload (9 bytes, or 13 with MASK2). `None` when the
    /// length is neither.
    pub fn from_command_data(data: &[u8]) -> Option<Self> {
        if data.len() != 9 && data.len() != 13 {
            return None;
        }
        let u16_at = |i: usize| u16::from_be_bytes([data[i], data[i + 1]]);
        let u32_at =
            |i: usize| u32::from_be_bytes([data[i], data[i + 1], data[i + 2], data[i + 3]]);
        Some(StreamingConfig {
            n: u16_at(0),
            m: u16_at(2),
            mask: u32_at(4),
            pcnt: data[8],
            mask2: if data.len() == 13 { u32_at(9) } else { 0 },
        })
    }

    /// The Set Data Streaming command for this configuration. MASK2 is sent only when
    /// non-zero, so droids without it still accept the 9-byte form.
    pub fn command(&self) -> Command {
        cmd::set_data_streaming(
            self.n,
            self.m,
            self.mask,
            self.pcnt,
            (self.mask2 != 0).then_some(self.mask2),
        )
    }

    /// Frames (samples) per second, 400 / N; 0 when N is 0. Packets arrive M times less often.
    pub fn rate_hz(&self) -> f32 {
        if self.n == 0 {
            0.0
        } else {
            SAMPLE_RATE_HZ / self.n as f32
        }
    }

    /// Streaming is on: a non-zero divisor and at least one bit set.
    pub fn is_streaming(&self) -> bool {
        self.n > 0 && (self.mask | self.mask2) != 0
    }

    /// The fields of one frame, in wire order. Bits without a known meaning are `None`, so
    /// the count of values stays right.
    pub fn layout(&self) -> Vec<Option<&'static SensorField>> {
        let mut out = Vec::with_capacity(self.values_per_frame());
        for (m, table) in [
            (self.mask, &MASK_FIELDS[..]),
            (self.mask2, &MASK2_FIELDS[..]),
        ] {
            for bit in (0..32).rev().map(|b| 1u32 << b) {
                if m & bit != 0 {
                    out.push(table.iter().find(|f| f.bit == bit));
                }
            }
        }
        out
    }

    pub fn values_per_frame(&self) -> usize {
        (self.mask.count_ones() + self.mask2.count_ones()) as usize
    }

    /// Bytes per frame.
    pub fn frame_len(&self) -> usize {
        self.values_per_frame() * 2
    }
}

pub use crate::protocol::notify::SensorSample;

/// Why a streaming payload does not match the masks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SampleError {
    /// Bytes per frame by the masks in effect.
    pub frame_len: usize,
    /// Frames per packet by the configuration (M).
    pub frames: u16,
    pub got_bytes: usize,
}

impl std::fmt::Display for SampleError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "sensor data of {} bytes is not a whole number of {}-byte frames (masks in effect, M = {})",
            self.got_bytes, self.frame_len, self.frames
        )
    }
}

/// Decode an async ID 03 payload into one sample per frame.
///
/// The length must be a whole, non-zero number of frames. It is deliberately NOT required to
/// be exactly M frames: the frame size is fixed by the masks alone, so a packet with a
/// different whole number of frames (a stale snooped M, a droid flushing a partial batch
/// when streaming stops) still decodes correctly frame by frame. An empty payload with no
/// bits set decodes to no samples.
pub fn decode_samples(
    cfg: &StreamingConfig,
    data: &[u8],
) -> Result<Vec<SensorSample>, SampleError> {
    let frame_len = cfg.frame_len();
    let err = || SampleError {
        frame_len,
        frames: cfg.m,
        got_bytes: data.len(),
    };
    if frame_len == 0 {
        return if data.is_empty() {
            Ok(Vec::new())
        } else {
            Err(err())
        };
    }
    if data.is_empty() || !data.len().is_multiple_of(frame_len) {
        return Err(err());
    }
    let layout = cfg.layout();
    Ok(data
        .chunks_exact(frame_len)
        .map(|frame| SensorSample {
            values: layout
                .iter()
                .zip(frame.chunks_exact(2))
                .filter_map(|(f, c)| {
                    let raw = i16::from_be_bytes([c[0], c[1]]);
                    f.map(|f| (f.name, raw as f32 * f.scale))
                })
                .collect(),
        })
        .collect())
}

/// Encode frames the way the droid does (the simulator's side): for each frame, `values`
/// looked up by name for each enabled field, divided by the scale, rounded and saturated to
/// i16; missing values and NaN are sent as 0. Never panics.
pub fn encode_samples(cfg: &StreamingConfig, frames: &[Vec<(&str, f32)>]) -> Vec<u8> {
    let layout = cfg.layout();
    let mut out = Vec::with_capacity(frames.len() * layout.len() * 2);
    for values in frames {
        for f in &layout {
            let v = f
                .and_then(|f| {
                    values
                        .iter()
                        .find(|(n, _)| *n == f.name)
                        .map(|(_, v)| to_raw(*v / f.scale))
                })
                .unwrap_or(0);
            out.extend_from_slice(&v.to_be_bytes());
        }
    }
    out
}

/// Round and saturate to i16 (`as` saturates and maps NaN to 0).
fn to_raw(v: f32) -> i16 {
    v.round() as i16
}

/// Whether `model` streams its locator and velocity in its own axes, a quarter turn from the
/// other v1 droids': Ollie.
///
/// Source: spherov2.py (`controls/v1.py`, `SensorControl`), which for robots named `2B-`
/// (Ollie) reads the streamed locator and velocity as (x, y) = (−y, x); it came with its
/// Ollie support (commit 276590a, "implements Sphero 2.0, Ollie, and BB-8", 2020-07-08) and
/// is kept to this day. Sphero's v1 documents (API 1.50, the locator note) describe the
/// locator for Sphero alone and say nothing of Ollie; sphero.js, gobot and cylon-ollie pass
/// the odometer through unchanged for every model, so they neither confirm nor refute it.
/// spherov2 is the field's reference and the only client that treats Ollie apart, so
/// droidctl takes its word: an Ollie rolling east (+x) streams (0, −d), rolling north (d, 0).
pub fn rotated_axes(model: crate::model::Model) -> bool {
    model.has(crate::model::Caps::ROTATED_AXES)
}

/// The locator and velocity pairs a rotated-axes droid streams.
const AXIS_PAIRS: [(&str, &str); 2] = [("locator_x", "locator_y"), ("velocity_x", "velocity_y")];

/// Turn each pair of `values` by `f` (x, y) → (x', y'), where both are present.
fn turn_pairs(values: &mut [(&'static str, f32)], f: impl Fn(f32, f32) -> (f32, f32)) {
    for (xn, yn) in AXIS_PAIRS {
        let xi = values.iter().position(|(n, _)| *n == xn);
        let yi = values.iter().position(|(n, _)| *n == yn);
        if let (Some(xi), Some(yi)) = (xi, yi) {
            let (x, y) = f(values[xi].1, values[yi].1);
            values[xi].1 = x;
            values[yi].1 = y;
        }
    }
}

/// What `model` streams for room-axes values (x east, y north): unchanged for BB-8 and
/// SPRK+, turned for Ollie ([`rotated_axes`]): (x, y) → (y, −x). The simulator's side.
pub fn to_droid_axes(model: crate::model::Model, values: &mut [(&'static str, f32)]) {
    if rotated_axes(model) {
        turn_pairs(values, |x, y| (y, -x));
    }
}

/// The room axes of what `model` streamed: Ollie's (x, y) → (−y, x), as spherov2 reads it;
/// the inverse of [`to_droid_axes`]. The host's side.
pub fn from_droid_axes(model: crate::model::Model, values: &mut [(&'static str, f32)]) {
    if rotated_axes(model) {
        turn_pairs(values, |x, y| (-y, x));
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn ollie_streams_its_locator_a_quarter_turn_round_and_is_read_back() {
        use crate::model::Model;
        // Rolled 30 cm east (+x) at 50 cm/s.
        let room = vec![
            ("locator_x", 30.0),
            ("locator_y", 0.0),
            ("velocity_x", 50.0),
            ("velocity_y", 0.0),
            ("yaw", 90.0),
        ];
        let mut wire = room.clone();
        super::to_droid_axes(Model::Ollie, &mut wire);
        // spherov2's reading of it, (x, y) = (−y, x), is east again.
        assert_eq!(&wire[..2], &[("locator_x", 0.0), ("locator_y", -30.0)]);
        assert_eq!(wire[4], ("yaw", 90.0), "only locator and velocity turn");
        let mut back = wire.clone();
        super::from_droid_axes(Model::Ollie, &mut back);
        assert_eq!(back, room);
        for m in [Model::BB8, Model::SprkPlus] {
            let mut same = room.clone();
            super::to_droid_axes(m, &mut same);
            super::from_droid_axes(m, &mut same);
            assert_eq!(same, room, "{m:?}");
        }
    }

    use super::*;

    #[test]
    fn tables_are_descending_and_disjoint() {
        for table in [&MASK_FIELDS[..], &MASK2_FIELDS[..]] {
            let bits: Vec<u32> = table.iter().map(|f| f.bit).collect();
            assert!(bits.windows(2).all(|w| w[0] > w[1]));
            assert!(bits.iter().all(|b| b.count_ones() == 1));
        }
    }

    #[test]
    fn full_layout_names() {
        let names: Vec<_> = StreamingConfig::full(40)
            .layout()
            .iter()
            .map(|f| f.unwrap().name)
            .collect();
        assert_eq!(
            names,
            [
                "pitch",
                "roll",
                "yaw",
                "accel_x",
                "accel_y",
                "accel_z",
                "gyro_x",
                "gyro_y",
                "gyro_z",
                "locator_x",
                "locator_y",
                "velocity_x",
                "velocity_y"
            ]
        );
        assert_eq!(StreamingConfig::full(40).rate_hz(), 10.0);
    }

    #[test]
    fn snoop_round_trips_the_command() {
        let cfg = StreamingConfig::full(20);
        assert_eq!(
            StreamingConfig::from_command_data(&cfg.command().data),
            Some(cfg)
        );
        let no_mask2 = StreamingConfig { mask2: 0, ..cfg };
        assert_eq!(no_mask2.command().data.len(), 9);
        assert_eq!(
            StreamingConfig::from_command_data(&no_mask2.command().data),
            Some(no_mask2)
        );
        assert_eq!(StreamingConfig::from_command_data(&[0; 10]), None);
    }

    #[test]
    fn encode_saturates() {
        let cfg = StreamingConfig {
            n: 40,
            m: 1,
            mask: mask::ACCEL,
            pcnt: 0,
            mask2: 0,
        };
        let data = encode_samples(
            &cfg,
            &[vec![
                ("accel_x", 100.0),
                ("accel_y", f32::NAN),
                ("accel_z", -100.0),
            ]],
        );
        assert_eq!(data, vec![0x7F, 0xFF, 0, 0, 0x80, 0x00]);
    }

    #[test]
    fn unknown_bits_keep_positions() {
        let cfg = StreamingConfig {
            n: 1,
            m: 1,
            mask: 0x0100_0000 | mask::IMU,
            pcnt: 0,
            mask2: 0,
        };
        let s = decode_samples(&cfg, &[0, 9, 0, 1, 0, 2, 0, 3]).unwrap();
        assert_eq!(
            s[0].values,
            vec![("pitch", 1.0), ("roll", 2.0), ("yaw", 3.0)]
        );
    }
}
