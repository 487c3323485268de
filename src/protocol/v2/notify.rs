//! Typed notifications: what the session, simulator and UI act on. Everything else in the
//! catalogue is still decoded generically for display (see [`super::describe`]).

use super::catalog;
use super::catalog::targets::Processor;
use super::device::Device;
use super::packet::Packet;
use super::sensor::{StreamingConfig, decode_sample};
use super::stream::ServiceConfig;
pub use crate::protocol::notify::{Collision, Notification, NotificationError, RobotEvent};

/// The v2 side of the common [`Notification`]: decoding from v2 packets and v2 names.
impl Notification {
    /// Decode a v2 notification packet. `streaming` gives the masks in effect for sensor data.
    /// Known notifications with a malformed payload are errors (counted by the caller);
    /// unknown ones are `Other`.
    pub fn decode(
        p: &Packet,
        streaming: &StreamingConfig,
    ) -> Result<Notification, NotificationError> {
        Self::decode_with(p, streaming, &ServiceConfig::default())
    }

    /// [`Notification::decode`], with what the streaming service was told too (RVR): its
    /// data are named by the token and the processor that sent them.
    pub fn decode_with(
        p: &Packet,
        streaming: &StreamingConfig,
        service: &ServiceConfig,
    ) -> Result<Notification, NotificationError> {
        let bad = |name: &'static str, reason: String| NotificationError { name, reason };
        let byte = |name: &'static str| {
            p.data
                .first()
                .copied()
                .filter(|_| p.data.len() == 1)
                .ok_or_else(|| bad(name, format!("expected 1 byte, got {}", p.data.len())))
        };
        let empty = |name: &'static str, n: Notification| {
            if p.data.is_empty() {
                Ok(n)
            } else {
                Err(bad(
                    name,
                    format!("expected no data, got {} byte(s)", p.data.len()),
                ))
            }
        };
        match (Device::from_id(p.did), p.cid) {
            (Some(Device::Sensor), 0x12) => Collision::decode(&p.data)
                .map(Notification::Collision)
                .map_err(|e| bad("collision-detected", e.to_string())),
            (Some(Device::Sensor), 0x02) => decode_sample(streaming, &p.data)
                .map(Notification::Sensors)
                .map_err(|e| bad("sensor-streaming-data", e.to_string())),
            (Some(Device::Power), 0x06) => {
                byte("battery-state-changed").map(Notification::BatteryStateChanged)
            }
            (Some(Device::Power), 0x1C) => {
                byte("battery-voltage-state-changed").map(Notification::BatteryVoltageStateChanged)
            }
            (Some(Device::Power), 0x21) => {
                byte("charger-state-changed").map(Notification::ChargerStateChanged)
            }
            (Some(Device::Power), 0x19) => empty("will-sleep", Notification::WillSleep),
            (Some(Device::Power), 0x1A) => empty("did-sleep", Notification::DidSleep),
            (Some(Device::Animatronic), 0x26) => Ok(Notification::LegActionComplete),
            (Some(Device::Animatronic), 0x11) => Ok(Notification::AnimationComplete),
            (Some(Device::Animatronic), 0x3A) => {
                empty("head-reset-to-zero", Notification::HeadResetToZero)
            }
            (Some(Device::Sensor), 0x3D) => {
                super::stream::decode(service, p.sid.and_then(Processor::of_id), &p.data)
                    .map(Notification::Sensors)
                    .map_err(|e| bad("streaming-service-data", e.to_string()))
            }
            (Some(Device::Drive), 0x26) => match p.data[..] {
                [motor, stalled] => Ok(Notification::Robot(RobotEvent::MotorStall {
                    motor,
                    stalled: stalled != 0,
                })),
                _ => Err(bad(
                    "motor-stall",
                    format!("expected 2 bytes, got {}", p.data.len()),
                )),
            },
            (Some(Device::Drive), 0x28) => {
                byte("motor-fault").map(|b| Notification::Robot(RobotEvent::MotorFault(b != 0)))
            }
            (Some(Device::Sensor), 0x26) => match p.data[..] {
                [a, b] => Ok(Notification::Robot(RobotEvent::CompassHeading(
                    u16::from_be_bytes([a, b]),
                ))),
                _ => Err(bad(
                    "magnetometer-north-yaw",
                    format!("expected 2 bytes, got {}", p.data.len()),
                )),
            },
            (Some(Device::Sensor), 0x2C) => byte("robot-to-robot-ir-message")
                .map(|code| Notification::Robot(RobotEvent::IrMessage(code))),
            (Some(Device::Sensor), 0x36) => match p.data[..] {
                [r, g, b, index, confidence] => Ok(Notification::Robot(RobotEvent::Color {
                    rgb: [r, g, b],
                    index,
                    confidence,
                })),
                _ => Err(bad(
                    "color-detection",
                    format!("expected 5 bytes, got {}", p.data.len()),
                )),
            },
            (Some(Device::Io), 0x3C) => match p.data[..] {
                [0] => Ok(Notification::Robot(RobotEvent::MatrixTextDone)),
                _ => Ok(Notification::Other {
                    did: p.did,
                    cid: p.cid,
                    data: p.data.clone(),
                }),
            },
            _ => Ok(Notification::Other {
                did: p.did,
                cid: p.cid,
                data: p.data.clone(),
            }),
        }
    }

    /// The catalogue name of this notification.
    pub fn name(&self) -> String {
        let (did, cid) = match self {
            Notification::Collision(_) => (0x18, 0x12),
            Notification::Sensors(_) => (0x18, 0x02),
            Notification::BatteryStateChanged(_) => (0x13, 0x06),
            Notification::BatteryVoltageStateChanged(_) => (0x13, 0x1C),
            Notification::ChargerStateChanged(_) => (0x13, 0x21),
            Notification::WillSleep => (0x13, 0x19),
            Notification::DidSleep => (0x13, 0x1A),
            Notification::LegActionComplete => (0x17, 0x26),
            Notification::AnimationComplete => (0x17, 0x11),
            Notification::HeadResetToZero => (0x17, 0x3A),
            Notification::Other { did, cid, .. } => (*did, *cid),
            other => return other.common_name().to_string(),
        };
        catalog::notification(did, cid)
            .map(|n| n.name.clone())
            .unwrap_or_else(|| format!("notification-{did:02x}-{cid:02x}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::v2::value::Value;

    fn collision_bytes() -> Vec<u8> {
        // accel (4096, -2048, 0) = (1 g, -0.5 g, 0), axis x|y, power (100, -5, 7), speed 80,
        // time 0x00012345.
        vec![
            0x10, 0x00, 0xF8, 0x00, 0x00, 0x00, 0x03, 0x00, 0x64, 0xFF, 0xFB, 0x00, 0x07, 0x50,
            0x00, 0x01, 0x23, 0x45,
        ]
    }

    #[test]
    fn collision_18_bytes() {
        let c = Collision::decode(&collision_bytes()).unwrap();
        assert_eq!(c.accel[0].g(), 1.0);
        assert_eq!(c.accel[1].g(), -0.5);
        assert!(c.axis.x && c.axis.y);
        assert_eq!(c.power, [100, -5, 7]);
        assert_eq!(c.speed, 80);
        assert_eq!(c.time_ms, 0x12345);
        assert_eq!(c.encode(), collision_bytes());
        // The seed's 17 bytes is rejected.
        assert!(Collision::decode(&collision_bytes()[..17]).is_err());
        // BOLT+'s 16 as sphero-unsw reads them: the time a 16-bit count.
        let mut short = collision_bytes()[..14].to_vec();
        short.extend_from_slice(&0x0123u16.to_be_bytes());
        let c = Collision::decode(&short[..16]).unwrap();
        assert_eq!((c.speed, c.time_ms), (80, 0x0123));
    }

    #[test]
    fn collision_generic_fields_have_issue_names() {
        let def = catalog::notification(0x18, 0x12).unwrap();
        let fields = catalog::decode_fields(def.fields, &collision_bytes()).unwrap();
        let names: Vec<_> = fields.iter().map(|(n, _)| *n).collect();
        assert_eq!(
            names,
            [
                "accel_x", "accel_y", "accel_z", "x_axis", "y_axis", "power_x", "power_y",
                "power_z", "speed", "time_ms"
            ]
        );
        assert_eq!(fields[0].1, Value::Float(1.0));
        assert_eq!(fields[3].1, Value::Bool(true));
    }

    #[test]
    fn decodes_power_notifications() {
        let cfg = StreamingConfig::default();
        let n =
            |cid, data: Vec<u8>| Notification::decode(&Packet::notification(0x13, cid, data), &cfg);
        assert_eq!(n(0x19, vec![]), Ok(Notification::WillSleep));
        assert_eq!(n(0x1A, vec![]), Ok(Notification::DidSleep));
        assert_eq!(n(0x06, vec![3]), Ok(Notification::BatteryStateChanged(3)));
        assert_eq!(
            n(0x1C, vec![2]),
            Ok(Notification::BatteryVoltageStateChanged(2))
        );
        assert_eq!(n(0x21, vec![1]), Ok(Notification::ChargerStateChanged(1)));
        assert!(n(0x06, vec![]).is_err());
        assert!(n(0x19, vec![1]).is_err());
        assert_eq!(Notification::WillSleep.name(), "will-sleep");
    }

    #[test]
    fn decodes_animatronic_and_unknown() {
        let cfg = StreamingConfig::default();
        let n =
            |did, cid| Notification::decode(&Packet::notification(did, cid, vec![]), &cfg).unwrap();
        assert_eq!(n(0x17, 0x26), Notification::LegActionComplete);
        assert_eq!(n(0x17, 0x11), Notification::AnimationComplete);
        assert_eq!(n(0x17, 0x3A), Notification::HeadResetToZero);
        assert!(matches!(
            n(0x42, 0x01),
            Notification::Other { did: 0x42, .. }
        ));
        assert_eq!(n(0x42, 0x01).name(), "notification-42-01");
    }

    #[test]
    fn decodes_sensor_stream_with_masks() {
        let cfg = StreamingConfig::full(100);
        let data = super::super::sensor::encode_sample(&cfg, &[("yaw", 45.0), ("locator_x", 12.0)]);
        let Notification::Sensors(s) =
            Notification::decode(&Packet::notification(0x18, 0x02, data), &cfg).unwrap()
        else {
            panic!()
        };
        assert_eq!(s.get("yaw"), Some(45.0));
        assert!((s.get("locator_x").unwrap() - 12.0).abs() < 1e-4);
    }
}
