//! Legacy sensor streaming: masks, and decoding of notification 0x18/0x02.
//!
//! `droid-facts.md` §2: values arrive as big-endian f32, all enabled standard-mask fields in
//! DESCENDING bit order, then the extended-mask fields in descending bit order. Locator and
//! velocity are ×100 to get cm and cm/s; everything else is used as sent.

/// One streamable sensor component.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorField {
    pub bit: u32,
    pub extended: bool,
    /// snake_case name used in the packet log and JSON.
    pub name: &'static str,
    /// Multiply the wire value by this to get the unit below.
    pub scale: f32,
    pub unit: &'static str,
}

const fn std_field(bit: u32, name: &'static str, scale: f32, unit: &'static str) -> SensorField {
    SensorField {
        bit,
        extended: false,
        name,
        scale,
        unit,
    }
}

const fn ext_field(bit: u32, name: &'static str, unit: &'static str) -> SensorField {
    SensorField {
        bit,
        extended: true,
        name,
        scale: 1.0,
        unit,
    }
}

/// The standard mask (`r2d2-v2-protocol.md` §7.2), descending bit order.
pub const STANDARD_FIELDS: [SensorField; 17] = [
    std_field(25, "quaternion_x", 1.0, ""),
    std_field(24, "quaternion_y", 1.0, ""),
    std_field(23, "quaternion_z", 1.0, ""),
    std_field(22, "quaternion_w", 1.0, ""),
    std_field(18, "pitch", 1.0, "deg"),
    std_field(17, "roll", 1.0, "deg"),
    std_field(16, "yaw", 1.0, "deg"),
    std_field(15, "accel_x", 1.0, "g"),
    std_field(14, "accel_y", 1.0, "g"),
    std_field(13, "accel_z", 1.0, "g"),
    std_field(9, "accel_one", 1.0, ""),
    std_field(6, "locator_x", 100.0, "cm"),
    std_field(5, "locator_y", 100.0, "cm"),
    std_field(4, "velocity_x", 100.0, "cm/s"),
    std_field(3, "velocity_y", 100.0, "cm/s"),
    std_field(2, "speed", 1.0, ""),
    std_field(1, "core_time", 1.0, ""),
];

/// The extended mask (R2-D2 specific), descending bit order. Gyro scaling is disputed
/// between clients (`droid-facts.md` §2, *unverified*): values are shown as sent.
pub const EXTENDED_FIELDS: [SensorField; 5] = [
    ext_field(26, "head_angle", "deg"),
    ext_field(25, "gyro_x", "deg/s"),
    ext_field(24, "gyro_y", "deg/s"),
    ext_field(23, "gyro_z", "deg/s"),
    // BOLT's ambient light sensor: spherov2.py `toy/bolt.py` extended bit 0x40000.
    ext_field(18, "ambient_light", "lux"),
];

pub mod mask {
    pub const ATTITUDE: u32 = 0x0007_0000;
    pub const ACCELEROMETER: u32 = 0x0000_E000;
    pub const LOCATOR: u32 = 0x0000_0060;
    pub const VELOCITY: u32 = 0x0000_0018;
    pub const SPEED: u32 = 0x0000_0004;
    /// Extended: gyro x/y/z.
    pub const EXT_GYRO: u32 = 0x0380_0000;
    /// Extended: R2 head angle (bit 26).
    pub const EXT_HEAD_ANGLE: u32 = 0x0400_0000;
}

/// The masks in effect, which determine how a streaming notification is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StreamingConfig {
    pub mask: u32,
    pub ext_mask: u32,
    pub interval_ms: u16,
}

impl StreamingConfig {
    /// The full set droidctl asks for: attitude, accelerometer, locator, velocity (standard
    /// 0x0007E078), gyro and head angle (extended 0x07800000).
    pub fn full(interval_ms: u16) -> Self {
        StreamingConfig {
            mask: mask::ATTITUDE | mask::ACCELEROMETER | mask::LOCATOR | mask::VELOCITY,
            ext_mask: mask::EXT_GYRO | mask::EXT_HEAD_ANGLE,
            interval_ms,
        }
    }

    /// The fields the masks enable, in wire order. Unknown enabled bits are included as
    /// `None` so the count of values stays right.
    pub fn layout(&self) -> Vec<Option<&'static SensorField>> {
        let mut out = Vec::new();
        for (m, table) in [
            (self.mask, &STANDARD_FIELDS[..]),
            (self.ext_mask, &EXTENDED_FIELDS[..]),
        ] {
            for bit in (0..32).rev() {
                if m & (1 << bit) != 0 {
                    out.push(table.iter().find(|f| f.bit == bit));
                }
            }
        }
        out
    }

    pub fn value_count(&self) -> usize {
        (self.mask.count_ones() + self.ext_mask.count_ones()) as usize
    }

    pub fn is_streaming(&self) -> bool {
        self.interval_ms > 0 && (self.mask | self.ext_mask) != 0
    }
}

pub use crate::protocol::notify::SensorSample;

/// Why a streaming payload does not match the masks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SampleError {
    pub expected_values: usize,
    pub got_bytes: usize,
}

impl std::fmt::Display for SampleError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "sensor data of {} bytes does not match the masks in effect ({} values = {} bytes)",
            self.got_bytes,
            self.expected_values,
            self.expected_values * 4
        )
    }
}

/// Decode a 0x18/0x02 payload with the masks in effect.
pub fn decode_sample(config: &StreamingConfig, data: &[u8]) -> Result<SensorSample, SampleError> {
    let count = config.value_count();
    if data.len() != count * 4 {
        return Err(SampleError {
            expected_values: count,
            got_bytes: data.len(),
        });
    }
    // The layout walked in place (no list of fields built per sample: this runs for every
    // sensor packet of a capture).
    let mut values = Vec::with_capacity(count);
    let mut chunks = data.chunks_exact(4);
    for (m, table) in [
        (config.mask, &STANDARD_FIELDS[..]),
        (config.ext_mask, &EXTENDED_FIELDS[..]),
    ] {
        for bit in (0..32).rev() {
            if m & (1 << bit) == 0 {
                continue;
            }
            let Some(c) = chunks.next() else { break };
            if let Some(f) = table.iter().find(|f| f.bit == bit) {
                let raw = f32::from_be_bytes([c[0], c[1], c[2], c[3]]);
                values.push((f.name, raw * f.scale));
            }
        }
    }
    Ok(SensorSample { values })
}

/// Encode a sample the way the droid does (the simulator's side): `values` looked up by name
/// for each enabled field, divided by the scale; missing values are sent as 0.
pub fn encode_sample(config: &StreamingConfig, values: &[(&str, f32)]) -> Vec<u8> {
    let mut out = Vec::with_capacity(config.value_count() * 4);
    for f in config.layout() {
        let v = f
            .and_then(|f| {
                values
                    .iter()
                    .find(|(n, _)| *n == f.name)
                    .map(|(_, v)| v / f.scale)
            })
            .unwrap_or(0.0);
        out.extend_from_slice(&v.to_be_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typical_mask_layout_is_descending() {
        // droid-facts.md §2: 0x0007E078 + extended 0x03800000.
        let cfg = StreamingConfig {
            mask: 0x0007_E078,
            ext_mask: 0x0380_0000,
            interval_ms: 150,
        };
        let names: Vec<_> = cfg.layout().iter().map(|f| f.unwrap().name).collect();
        assert_eq!(
            names,
            [
                "pitch",
                "roll",
                "yaw",
                "accel_x",
                "accel_y",
                "accel_z",
                "locator_x",
                "locator_y",
                "velocity_x",
                "velocity_y",
                "gyro_x",
                "gyro_y",
                "gyro_z"
            ]
        );
    }

    #[test]
    fn locator_and_velocity_are_scaled() {
        let cfg = StreamingConfig {
            mask: mask::LOCATOR,
            ext_mask: mask::EXT_HEAD_ANGLE,
            interval_ms: 100,
        };
        let mut data = Vec::new();
        for v in [1.5f32, -0.25, 90.0] {
            data.extend_from_slice(&v.to_be_bytes());
        }
        let s = decode_sample(&cfg, &data).unwrap();
        assert_eq!(s.get("locator_x"), Some(150.0));
        assert_eq!(s.get("locator_y"), Some(-25.0));
        assert_eq!(s.get("head_angle"), Some(90.0));
        assert_eq!(encode_sample(&cfg, &s.values), data);
    }

    #[test]
    fn bolts_ambient_light_is_named_after_the_gyro() {
        // BOLT: extended bit 18 is the ambient light (spherov2 `toy/bolt.py`).
        let cfg = StreamingConfig {
            interval_ms: 100,
            mask: mask::ATTITUDE,
            ext_mask: mask::EXT_GYRO | 0x0004_0000,
        };
        let values = [
            ("pitch", 1.0),
            ("roll", 2.0),
            ("yaw", 3.0),
            ("gyro_x", 4.0),
            ("gyro_y", 5.0),
            ("gyro_z", 6.0),
            ("ambient_light", 320.0),
        ];
        let s = decode_sample(&cfg, &encode_sample(&cfg, &values)).unwrap();
        assert_eq!(s.get("ambient_light"), Some(320.0));
        assert_eq!(s.get("gyro_z"), Some(6.0));
    }

    #[test]
    fn wrong_length_is_an_error() {
        let cfg = StreamingConfig::full(100);
        let e = decode_sample(&cfg, &[0; 7]).unwrap_err();
        assert_eq!(e.expected_values, 14);
    }

    #[test]
    fn unknown_bits_keep_positions() {
        let cfg = StreamingConfig {
            mask: 0x8000_0000 | mask::SPEED,
            ext_mask: 0,
            interval_ms: 10,
        };
        let mut data = vec![0; 4];
        data.extend_from_slice(&3.0f32.to_be_bytes());
        assert_eq!(
            decode_sample(&cfg, &data).unwrap().values,
            vec![("speed", 3.0)]
        );
    }
}
