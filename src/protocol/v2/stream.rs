//! The streaming service (RVR): sensors are grouped under tokens per processor, configured
//! with Configure Streaming Service (0x18/0x39: token, then id u16 and width per sensor),
//! started with a period (0x3A), stopped (0x3B) and cleared (0x3C); data arrive as 0x18/0x3D
//! whose source id names the processor and whose first byte is the token, then each
//! configured sensor's components in order, each an unsigned integer of the sensor's width
//! scaled linearly from 0..=MAX onto the component's range.
//!
//! Sensor ids, components, ranges and the ×100 of locator, velocity and speed (metres to
//! centimetres) are spherov2.py's `controls/v2.py` StreamingControl; the limits (tokens 1–4,
//! four sensors a token, 33 ms shortest period) are Sphero's SDK's (`SensorStreamingControl`
//! in sphero-sdk-raspberrypi-python). The seeds say nothing of the service.

use super::catalog::Command;
use super::catalog::targets::Processor;
use super::types::StreamWidth;
use crate::protocol::notify::SensorSample;

/// Tokens run 1..=4.
pub const TOKENS: std::ops::RangeInclusive<u8> = 1..=4;
/// At most this many sensors under one token.
pub const SENSORS_PER_TOKEN: usize = 4;
/// The shortest period the service accepts, ms.
pub const MIN_PERIOD_MS: u16 = 33;

/// One streamable sensor of the service.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamSensor {
    pub id: u16,
    pub name: &'static str,
    /// The processor that measures it.
    pub processor: Processor,
    /// Its components: the name they take in a [`SensorSample`], and their range.
    pub components: &'static [(&'static str, f32, f32)],
    /// Multiply each decoded value by this (metres → cm for locator, velocity and speed).
    pub scale: f32,
}

const fn sensor(
    id: u16,
    name: &'static str,
    processor: Processor,
    components: &'static [(&'static str, f32, f32)],
    scale: f32,
) -> StreamSensor {
    StreamSensor {
        id,
        name,
        processor,
        components,
        scale,
    }
}

/// The service's sensors, by id.
pub const SENSORS: [StreamSensor; 11] = [
    sensor(
        0,
        "quaternion",
        Processor::Secondary,
        &[
            ("quaternion_w", -1.0, 1.0),
            ("quaternion_x", -1.0, 1.0),
            ("quaternion_y", -1.0, 1.0),
            ("quaternion_z", -1.0, 1.0),
        ],
        1.0,
    ),
    sensor(
        1,
        "imu",
        Processor::Secondary,
        &[
            ("pitch", -180.0, 180.0),
            ("roll", -90.0, 90.0),
            ("yaw", -180.0, 180.0),
        ],
        1.0,
    ),
    sensor(
        2,
        "accelerometer",
        Processor::Secondary,
        &[
            ("accel_x", -16.0, 16.0),
            ("accel_y", -16.0, 16.0),
            ("accel_z", -16.0, 16.0),
        ],
        1.0,
    ),
    sensor(
        3,
        "color_detection",
        Processor::Primary,
        &[
            ("color_red", 0.0, 255.0),
            ("color_green", 0.0, 255.0),
            ("color_blue", 0.0, 255.0),
            ("color_index", 0.0, 255.0),
            ("color_confidence", 0.0, 1.0),
        ],
        1.0,
    ),
    sensor(
        4,
        "gyroscope",
        Processor::Secondary,
        &[
            ("gyro_x", -2000.0, 2000.0),
            ("gyro_y", -2000.0, 2000.0),
            ("gyro_z", -2000.0, 2000.0),
        ],
        1.0,
    ),
    sensor(
        5,
        "core_time_lower",
        Processor::Secondary,
        &[("core_time_lower", 0.0, 4_294_967_295.0)],
        1.0,
    ),
    sensor(
        6,
        "locator",
        Processor::Secondary,
        &[
            ("locator_x", -16000.0, 16000.0),
            ("locator_y", -16000.0, 16000.0),
        ],
        100.0,
    ),
    sensor(
        7,
        "velocity",
        Processor::Secondary,
        &[("velocity_x", -5.0, 5.0), ("velocity_y", -5.0, 5.0)],
        100.0,
    ),
    sensor(
        8,
        "speed",
        Processor::Secondary,
        &[("speed", 0.0, 5.0)],
        100.0,
    ),
    sensor(
        9,
        "core_time_upper",
        Processor::Secondary,
        &[("core_time_upper", 0.0, 4_294_967_295.0)],
        1.0,
    ),
    sensor(
        10,
        "ambient_light",
        Processor::Primary,
        &[("ambient_light", 0.0, 120_000.0)],
        1.0,
    ),
];

/// The sensor with this id.
pub fn sensor_by_id(id: u16) -> Option<&'static StreamSensor> {
    SENSORS.iter().find(|s| s.id == id)
}

/// The sensor with this name (`imu`, `locator`, …).
pub fn sensor_by_name(name: &str) -> Option<&'static StreamSensor> {
    SENSORS.iter().find(|s| s.name == name)
}

/// One token's configuration on one processor.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Slot {
    pub processor: Option<Processor>,
    pub token: u8,
    pub sensors: Vec<(u16, StreamWidth)>,
}

/// What a processor was told to stream, as a host or a robot keeps it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ServiceConfig {
    pub slots: Vec<Slot>,
    /// The period each processor streams at, ms, while started.
    pub started: Vec<(Option<Processor>, u16)>,
}

/// What a streaming-service command does to a configuration.
fn processor_of(c: &Command) -> Option<Processor> {
    c.target.and_then(Processor::of_id)
}

impl ServiceConfig {
    /// Follow a streaming-service command sent to the droid (configure, start, stop,
    /// clear); anything else is ignored. Bounded: a token is configured at most once.
    pub fn snoop(&mut self, c: &Command) {
        let p = processor_of(c);
        match (c.cid, c.data.as_slice()) {
            (0x39, [token, rest @ ..]) if rest.len() % 3 == 0 && TOKENS.contains(token) => {
                let sensors: Vec<(u16, StreamWidth)> = rest
                    .chunks_exact(3)
                    .take(SENSORS_PER_TOKEN)
                    .filter_map(|s| {
                        StreamWidth::from_byte(s[2]).map(|w| (u16::from_be_bytes([s[0], s[1]]), w))
                    })
                    .collect();
                self.slots
                    .retain(|s| !(s.processor == p && s.token == *token));
                self.slots.push(Slot {
                    processor: p,
                    token: *token,
                    sensors,
                });
            }
            (0x3A, [a, b]) => {
                self.started.retain(|(q, _)| *q != p);
                self.started.push((p, u16::from_be_bytes([*a, *b])));
            }
            (0x3B, []) => self.started.retain(|(q, _)| *q != p),
            (0x3C, []) => {
                self.started.retain(|(q, _)| *q != p);
                self.slots.retain(|s| s.processor != p);
            }
            _ => {}
        }
    }

    /// The sensors configured under `token` on `processor`.
    pub fn slot(&self, processor: Option<Processor>, token: u8) -> Option<&Slot> {
        self.slots.iter().find(|s| {
            s.token == token
                && (s.processor == processor || s.processor.is_none() || processor.is_none())
        })
    }
}

/// Why streaming-service data could not be named.
#[derive(Debug, Clone, PartialEq)]
pub enum StreamError {
    Empty,
    /// No configuration for this token on this processor.
    UnknownToken(u8),
    UnknownSensor(u16),
    /// The data do not fill the configured sensors exactly.
    Length {
        expected: usize,
        got: usize,
    },
}

impl std::fmt::Display for StreamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StreamError::Empty => write!(f, "no token"),
            StreamError::UnknownToken(t) => write!(f, "token {t} was not configured"),
            StreamError::UnknownSensor(id) => write!(f, "unknown sensor id {id}"),
            StreamError::Length { expected, got } => {
                write!(f, "expected {expected} data bytes, got {got}")
            }
        }
    }
}

/// Bytes of one sensor's components at its width.
fn sensor_len(s: &StreamSensor, w: StreamWidth) -> usize {
    s.components.len() * w.bytes()
}

/// Name the values of a 0x18/0x3D payload sent by `processor`.
pub fn decode(
    config: &ServiceConfig,
    processor: Option<Processor>,
    data: &[u8],
) -> Result<SensorSample, StreamError> {
    let (&token, mut rest) = data.split_first().ok_or(StreamError::Empty)?;
    let slot = config
        .slot(processor, token)
        .ok_or(StreamError::UnknownToken(token))?;
    let mut expected = 0;
    for (id, w) in &slot.sensors {
        expected += sensor_len(
            sensor_by_id(*id).ok_or(StreamError::UnknownSensor(*id))?,
            *w,
        );
    }
    if expected != rest.len() {
        return Err(StreamError::Length {
            expected,
            got: rest.len(),
        });
    }
    let mut values = Vec::new();
    for (id, w) in &slot.sensors {
        let s = sensor_by_id(*id).ok_or(StreamError::UnknownSensor(*id))?;
        let n = w.bytes();
        let max = ((1u64 << (8 * n)) - 1) as f64;
        for (name, lo, hi) in s.components {
            let (raw, more) = rest.split_at(n);
            rest = more;
            let v = raw.iter().fold(0u64, |a, b| (a << 8) | *b as u64) as f64;
            let scaled = v / max * (*hi as f64 - *lo as f64) + *lo as f64;
            values.push((*name, (scaled * s.scale as f64) as f32));
        }
    }
    Ok(SensorSample { values })
}

/// Encode values (in the units [`decode`] gives) for `slot`: the robot's side.
pub fn encode(slot: &Slot, values: &[(&str, f32)]) -> Vec<u8> {
    let mut out = vec![slot.token];
    for (id, w) in &slot.sensors {
        let Some(s) = sensor_by_id(*id) else { continue };
        let n = w.bytes();
        let max = ((1u64 << (8 * n)) - 1) as f64;
        for (name, lo, hi) in s.components {
            let v = values
                .iter()
                .find(|(k, _)| k == name)
                .map_or(0.0, |(_, v)| *v as f64 / s.scale as f64);
            let frac = ((v - *lo as f64) / (*hi as f64 - *lo as f64)).clamp(0.0, 1.0);
            let raw = (frac * max).round() as u64;
            out.extend_from_slice(&raw.to_be_bytes()[8 - n..]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::v2::cmd;
    use crate::protocol::v2::types::StreamSlots;

    #[test]
    fn configure_then_decode_round_trips() {
        let mut cfg = ServiceConfig::default();
        let c = cmd::configure_streaming_service(
            2,
            StreamSlots(vec![(6, StreamWidth::Bits32), (7, StreamWidth::Bits32)]),
        )
        .to(Processor::Secondary);
        cfg.snoop(&c);
        let slot = cfg.slot(Some(Processor::Secondary), 2).unwrap().clone();
        let data = encode(&slot, &[("locator_x", 120.0), ("velocity_y", -30.0)]);
        assert_eq!(data.len(), 1 + 4 * 4);
        let s = decode(&cfg, Some(Processor::Secondary), &data).unwrap();
        assert!((s.get("locator_x").unwrap() - 120.0).abs() < 0.01, "{s:?}");
        assert!((s.get("velocity_y").unwrap() + 30.0).abs() < 0.01, "{s:?}");
        assert_eq!(
            decode(&cfg, Some(Processor::Primary), &data),
            Err(StreamError::UnknownToken(2))
        );
        assert!(matches!(
            decode(&cfg, Some(Processor::Secondary), &data[..5]),
            Err(StreamError::Length { .. })
        ));
        cfg.snoop(&cmd::clear_streaming_service().to(Processor::Secondary));
        assert!(cfg.slots.is_empty());
    }
}
