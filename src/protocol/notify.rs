//! What droids report, in one form for every protocol family: the session, telemetry,
//! simulator and UI act on these, whichever wire format they came in.

use super::wire::*;

/// A collision as the droids report it. v2 sends it as Sensor 0x12, 18 bytes
/// (`droid-facts.md` §2); v1 as async ID 07, 16 bytes without `power_z` (§4), which is 0 here.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Collision {
    pub accel: [AccelRaw; 3],
    pub axis: CollisionAxis,
    pub power: [i16; 3],
    pub speed: u8,
    pub time_ms: u32,
}

impl Collision {
    pub const LEN: usize = 18;

    pub fn decode(data: &[u8]) -> Result<Self, FieldError> {
        let r = &mut Reader::new(data);
        let c = Collision {
            accel: [
                AccelRaw::get(r, "accel_x")?,
                AccelRaw::get(r, "accel_y")?,
                AccelRaw::get(r, "accel_z")?,
            ],
            axis: CollisionAxis::get(r, "axis")?,
            power: [
                i16::get(r, "power_x")?,
                i16::get(r, "power_y")?,
                i16::get(r, "power_z")?,
            ],
            speed: u8::get(r, "speed")?,
            // sphero-unsw 0.1.13 reads BOLT+'s collisions in 16 bytes as well as 18, the time
            // then a 16-bit count (`>3hB3hBh`: "Changed original 3hB3hBL to 3hB3hBh");
            // unverified, so both are taken.
            time_ms: if data.len() == Self::LEN - 2 {
                u16::get(r, "time_ms")?.into()
            } else {
                u32::get(r, "time_ms")?
            },
        };
        r.finish()?;
        Ok(c)
    }

    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(Self::LEN);
        for a in &self.accel {
            a.put(&mut out);
        }
        self.axis.put(&mut out);
        for p in &self.power {
            p.put(&mut out);
        }
        self.speed.put(&mut out);
        self.time_ms.put(&mut out);
        out
    }
}

/// A notification the application understands.
#[derive(Debug, Clone, PartialEq)]
pub enum Notification {
    Collision(Collision),
    /// Sensor streaming decoded with the masks in effect.
    Sensors(SensorSample),
    BatteryStateChanged(u8),
    BatteryVoltageStateChanged(u8),
    ChargerStateChanged(u8),
    /// The droid will sleep in about 10 s unless there is activity.
    WillSleep,
    DidSleep,
    LegActionComplete,
    AnimationComplete,
    HeadResetToZero,
    /// v1 power notification (async ID 01): 1 charging, 2 OK, 3 low, 4 critical.
    PowerState(u8),
    /// Robi 42's handshake: protocol version and the frame interval it announces.
    RobiHandshake(super::rsrcp::Handshake),
    /// A Robi 42 state frame.
    RobiFrame(super::rsrcp::Frame),
    /// Any other v1 async message, bytes kept.
    OtherAsync {
        id_code: u8,
        data: Vec<u8>,
    },
    /// What the newer v2 robots report beyond the droids (BOLT, RVR).
    Robot(RobotEvent),
    /// Any other v2 (DID, CID), or a known one whose payload did not fit: bytes kept.
    Other {
        did: u8,
        cid: u8,
        data: Vec<u8>,
    },
}

/// What BOLT, Mini and RVR report that the Star Wars droids do not (spherov2.py's
/// `commands/{drive,sensor,io}.py` notifications).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RobotEvent {
    /// Drive 0x26: a motor stalled or recovered (RVR).
    MotorStall { motor: u8, stalled: bool },
    /// Drive 0x28: the motors' fault state (RVR).
    MotorFault(bool),
    /// Sensor 0x26: compass calibration done; the yaw of north (BOLT).
    CompassHeading(u16),
    /// Sensor 0x2C: a robot-to-robot infrared message arrived; its code, 0..=7 (BOLT, RVR).
    IrMessage(u8),
    /// Sensor 0x36: the colour under the robot, its palette index and confidence (RVR).
    Color {
        rgb: [u8; 3],
        index: u8,
        confidence: u8,
    },
    /// IO 0x3C: the matrix's scrolling text is done (BOLT).
    MatrixTextDone,
}

impl RobotEvent {
    pub fn name(&self) -> &'static str {
        match self {
            RobotEvent::MotorStall { .. } => "motor-stall",
            RobotEvent::MotorFault(_) => "motor-fault",
            RobotEvent::CompassHeading(_) => "magnetometer-north-yaw",
            RobotEvent::IrMessage(_) => "robot-to-robot-ir-message",
            RobotEvent::Color { .. } => "color-detection",
            RobotEvent::MatrixTextDone => "text-scrolling",
        }
    }
}

/// Why a known notification could not be decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct NotificationError {
    pub name: &'static str,
    pub reason: String,
}

impl Notification {
    /// What a droid says about itself once per connection (Robi's handshake: version and
    /// interval): the session keeps it for whoever asks after the fact.
    pub fn is_greeting(&self) -> bool {
        matches!(self, Notification::RobiHandshake(_))
    }

    /// A family-independent name, for notifications every family can send.
    pub fn common_name(&self) -> &'static str {
        match self {
            Notification::Collision(_) => "collision",
            Notification::Sensors(_) => "sensors",
            Notification::BatteryStateChanged(_) => "battery-state-changed",
            Notification::BatteryVoltageStateChanged(_) => "battery-voltage-state-changed",
            Notification::ChargerStateChanged(_) => "charger-state-changed",
            Notification::WillSleep => "will-sleep",
            Notification::DidSleep => "did-sleep",
            Notification::LegActionComplete => "leg-action-complete",
            Notification::AnimationComplete => "animation-complete",
            Notification::HeadResetToZero => "head-reset-to-zero",
            Notification::PowerState(_) => "power-state",
            Notification::RobiHandshake(_) => "rsrcp-handshake",
            Notification::RobiFrame(_) => "rsrcp-frame",
            Notification::Robot(e) => e.name(),
            Notification::OtherAsync { .. } | Notification::Other { .. } => "other",
        }
    }
}

/// Sensor values by name, scaled to their units (the names and units of `droid-facts.md` §2:
/// degrees, g, °/s, cm, cm/s), whichever family streamed them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SensorSample {
    pub values: Vec<(&'static str, f32)>,
}

impl SensorSample {
    pub fn get(&self, name: &str) -> Option<f32> {
        self.values
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
    }

    pub fn fields(&self) -> super::value::Fields {
        self.values
            .iter()
            .map(|(n, v)| (*n, super::value::Value::Float(*v as f64)))
            .collect()
    }
}
