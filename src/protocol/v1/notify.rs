//! v1 async messages decoded into the common [`Notification`] type, which the session,
//! telemetry, simulator and UI consume whatever the family; and the inverse, for the
//! simulator.

use super::catalog::id;
use super::packet::AsyncPacket;
use super::sensor::{StreamingConfig, decode_samples, encode_samples};
pub use crate::protocol::notify::{Collision, Notification, NotificationError};
use crate::protocol::wire::{AccelRaw, CollisionAxis, FieldError, Reader, Wire};

/// Length of the v1 collision payload (`droid-facts.md` §4), two bytes shorter than v2's.
pub const COLLISION_LEN: usize = 16;

/// Decode async ID 07: `i16 x, i16 y, i16 z, u8 axis, i16 x_mag, i16 y_mag, u8 speed,
/// u32 time_ms`. x/y/z become `accel`, x_mag/y_mag `power[0..2]`, and `power[2]` (v2's
/// power_z, which v1 lacks) is 0.
///
/// The sources are silent on the scale of x/y/z: they are read as 1/4096 g like v2's
/// collision and v1's filtered accelerometer (`AccelRaw`), which is an assumption.
pub fn decode_collision(data: &[u8]) -> Result<Collision, FieldError> {
    let r = &mut Reader::new(data);
    let c = Collision {
        accel: [
            AccelRaw::get(r, "accel_x")?,
            AccelRaw::get(r, "accel_y")?,
            AccelRaw::get(r, "accel_z")?,
        ],
        axis: CollisionAxis::get(r, "axis")?,
        power: [i16::get(r, "power_x")?, i16::get(r, "power_y")?, 0],
        speed: u8::get(r, "speed")?,
        time_ms: u32::get(r, "time_ms")?,
    };
    r.finish()?;
    Ok(c)
}

/// The 16-byte payload of async ID 07; `power[2]` is not sent.
pub fn encode_collision(c: &Collision) -> Vec<u8> {
    let mut out = Vec::with_capacity(COLLISION_LEN);
    for a in &c.accel {
        a.put(&mut out);
    }
    c.axis.put(&mut out);
    c.power[0].put(&mut out);
    c.power[1].put(&mut out);
    c.speed.put(&mut out);
    c.time_ms.put(&mut out);
    out
}

/// Decode an async message. `streaming` is the Set Data Streaming configuration in effect
/// (sensor data cannot be read without it). One sensor packet holds M frames, hence a list.
/// Known messages with a malformed payload are errors (the caller counts them); unknown ID
/// codes are kept as `OtherAsync`.
pub fn decode_async(
    p: &AsyncPacket,
    streaming: &StreamingConfig,
) -> Result<Vec<Notification>, NotificationError> {
    let bad = |name: &'static str, reason: String| NotificationError { name, reason };
    match p.id_code {
        id::SENSOR_DATA => decode_samples(streaming, &p.data)
            .map(|frames| frames.into_iter().map(Notification::Sensors).collect())
            .map_err(|e| bad("sensor-data-streaming", e.to_string())),
        id::COLLISION => decode_collision(&p.data)
            .map(|c| vec![Notification::Collision(c)])
            .map_err(|e| bad("collision-detected", e.to_string())),
        id::POWER_NOTIFICATION => match p.data[..] {
            [state] => Ok(vec![Notification::PowerState(state)]),
            _ => Err(bad(
                "power-notification",
                format!("expected 1 byte, got {}", p.data.len()),
            )),
        },
        // The seed defines no payload; anything sent is ignored rather than refused, so the
        // warning (the droid sleeps in 10 s without activity) is never lost.
        id::PRE_SLEEP_WARNING => Ok(vec![Notification::WillSleep]),
        other => Ok(vec![Notification::OtherAsync {
            id_code: other,
            data: p.data.clone(),
        }]),
    }
}

/// The async message a droid would send for `n` (the simulator's side). Sensor samples are
/// sent as one frame with the masks of `streaming`. `None` for notifications v1 has no
/// message for (the v2-only ones).
pub fn encode_async(n: &Notification, streaming: &StreamingConfig) -> Option<AsyncPacket> {
    Some(match n {
        Notification::Collision(c) => AsyncPacket::new(id::COLLISION, encode_collision(c)),
        Notification::Sensors(s) => AsyncPacket::new(
            id::SENSOR_DATA,
            encode_samples(streaming, std::slice::from_ref(&s.values)),
        ),
        Notification::PowerState(b) => AsyncPacket::new(id::POWER_NOTIFICATION, vec![*b]),
        Notification::WillSleep => AsyncPacket::new(id::PRE_SLEEP_WARNING, Vec::new()),
        Notification::OtherAsync { id_code, data } => AsyncPacket::new(*id_code, data.clone()),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collision_round_trip_drops_power_z() {
        let c = Collision {
            accel: [AccelRaw(4096), AccelRaw(-2048), AccelRaw(0)],
            axis: CollisionAxis { x: true, y: false },
            power: [100, -5, 0],
            speed: 80,
            time_ms: 0x12345,
        };
        let data = encode_collision(&c);
        assert_eq!(data.len(), COLLISION_LEN);
        assert_eq!(decode_collision(&data), Ok(c));
        assert!(decode_collision(&data[..15]).is_err());
        let mut long = data.clone();
        long.push(0);
        assert!(decode_collision(&long).is_err());
    }

    #[test]
    fn power_needs_one_byte() {
        let cfg = StreamingConfig::default();
        let p = |data: Vec<u8>| decode_async(&AsyncPacket::new(0x01, data), &cfg);
        assert_eq!(p(vec![3]), Ok(vec![Notification::PowerState(3)]));
        assert!(p(vec![]).is_err());
    }

    #[test]
    fn encode_inverts_decode() {
        let cfg = StreamingConfig::full(40);
        for n in [
            Notification::WillSleep,
            Notification::PowerState(1),
            Notification::OtherAsync {
                id_code: 0x0F,
                data: vec![200],
            },
        ] {
            let p = encode_async(&n, &cfg).unwrap();
            assert_eq!(decode_async(&p, &cfg), Ok(vec![n]));
        }
        assert_eq!(encode_async(&Notification::DidSleep, &cfg), None);
    }
}
