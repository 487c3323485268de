//! Which processor each command lives on, for the robots with two (BOLT, RVR).
//!
//! Source: spherov2.py 0.12.1 `toy/bolt.py` and `toy/rvr.py`, which bind each command to
//! `Processors.PRIMARY` (target 0x11) or `SECONDARY` (0x12) or leave it to the caller; the
//! rules below reproduce those bindings device by device (tests/it/spherov2_catalogue.rs checks
//! every packet spherov2 builds against them). `droid-facts.md` §6 says BOLT's power goes to
//! the primary; spherov2 sends BOLT's power commands without a target, and so does droidctl
//! (a command without a target is taken by the primary). The seeds say nothing of processors.
//!
//! BOLT+: sphero-unsw 0.1.13's `toy/boltplus.py` binds every command BOLT sends to a
//! processor (drive, sensors, lights, the matrix) to `PRIMARY` on BOLT+, and leaves power,
//! system, connection and the compass calibration without one, as for BOLT. It asks for the
//! secondary's versions (System Info 0x17, 0x24), so a secondary exists; what runs on it is not
//! described (unverified: here only the commands both processors answer).

use super::Device;
use crate::model::Model;

/// The source id a host puts on addressed commands (spherov2: 0x01).
pub const HOST_SOURCE_ID: u8 = 0x01;

/// One of a robot's processors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Processor {
    /// Bluetooth, power, lights (BOLT's front and back LEDs, all of RVR's), RVR's colour sensor.
    Primary,
    /// Motors and motion sensors, BOLT's matrix.
    Secondary,
}

impl Processor {
    /// The target id byte: `0x10 | processor` (spherov2 `nibble_to_byte(1, proc)`).
    pub fn target_id(self) -> u8 {
        match self {
            Processor::Primary => 0x11,
            Processor::Secondary => 0x12,
        }
    }

    /// The processor of a target (or source) id; any other id names none. An id is a port
    /// (high nibble) and a node (low nibble): Bluetooth hosts use port 1 (spherov2: 0x11,
    /// 0x12); Sphero's RVR SDK on RVR's UART uses port 0 (`sphero-sdk` 0.3.4's
    /// `SerialAsyncDal` addresses 0x01 and 0x02, and matches answers by those sources).
    pub fn of_id(id: u8) -> Option<Processor> {
        match id {
            0x11 | 0x01 => Some(Processor::Primary),
            0x12 | 0x02 => Some(Processor::Secondary),
            _ => None,
        }
    }

    /// The target id on RVR's UART (port 0, as Sphero's SDK addresses it there).
    pub fn uart_id(self) -> u8 {
        self.target_id() & 0x0F
    }

    pub fn name(self) -> &'static str {
        match self {
            Processor::Primary => "primary",
            Processor::Secondary => "secondary",
        }
    }
}

/// Where a command is answered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Home {
    /// The robot has one processor (no target).
    Single,
    On(Processor),
    /// Both processors answer it (versions, echo, the streaming service).
    Both,
}

impl Home {
    /// Whether a command with target `tid` reaches a processor that has it (no target: the
    /// robot's router hands it to the processor that has it).
    pub fn accepts(self, tid: Option<u8>) -> bool {
        match (self, tid.map(Processor::of_id)) {
            (_, None) => true,
            (Home::Single, Some(_)) => false,
            (_, Some(None)) => false,
            (Home::Both, Some(Some(_))) => true,
            (Home::On(p), Some(Some(q))) => p == q,
        }
    }
}

/// Where `did`/`cid` lives on `model`.
pub fn home(model: Model, did: u8, cid: u8) -> Home {
    use Processor::{Primary, Secondary};
    let Some(device) = Device::from_id(did) else {
        return Home::Single;
    };
    match model {
        Model::Bolt => match device {
            Device::Drive | Device::Sensor | Device::Animatronic => Home::On(Secondary),
            // The front/back LEDs (8-bit mask) and the LED-request release are the primary's;
            // the matrix and Set LED the secondary's.
            Device::Io if matches!(cid, 0x1C | 0x4E) => Home::On(Primary),
            Device::Io => Home::On(Secondary),
            Device::ApiAndShell | Device::SystemInfo | Device::Firmware | Device::FactoryTest => {
                Home::Both
            }
            Device::Core | Device::Power | Device::Connection | Device::SystemMode => {
                Home::On(Primary)
            }
        },
        Model::BoltPlus => match device {
            Device::ApiAndShell | Device::SystemInfo | Device::Firmware | Device::FactoryTest => {
                Home::Both
            }
            _ => Home::On(Primary),
        },
        Model::Rvr => match device {
            Device::Drive | Device::Animatronic => Home::On(Secondary),
            // RGBC, ambient light and colour detection sit by the colour sensor (primary);
            // the streaming service runs on both.
            Device::Sensor if matches!(cid, 0x23 | 0x30 | 0x35..=0x38) => Home::On(Primary),
            Device::Sensor if matches!(cid, 0x39..=0x3D) => Home::Both,
            Device::Sensor => Home::On(Secondary),
            Device::SystemInfo if matches!(cid, 0x00 | 0x01 | 0x1F | 0x30 | 0x3A..=0x3C) => {
                Home::Both
            }
            Device::Firmware if cid == 0x15 => Home::Both,
            Device::FactoryTest if cid != 0x31 => Home::Both,
            Device::ApiAndShell => Home::Both,
            _ => Home::On(Primary),
        },
        _ => Home::Single,
    }
}

/// The target a host puts on `did`/`cid` for `model` when the command names none, as
/// spherov2 does: on RVR every command carries one (the primary where both answer); on BOLT
/// drive, sensors and lights do, while power, system and the robot-to-robot IR commands go
/// without; on BOLT+ (sphero-unsw) drive, sensors, lights and infrared do, the compass
/// calibration does not.
pub fn addressed(model: Model, did: u8, cid: u8) -> Option<Processor> {
    let h = home(model, did, cid);
    match (model, h) {
        (Model::Rvr, Home::On(p)) => Some(p),
        (Model::Rvr, _) => Some(Processor::Primary),
        (Model::Bolt, Home::On(p)) => {
            let device = Device::from_id(did)?;
            let untargeted_ir =
                device == Device::Sensor && matches!(cid, 0x22 | 0x27..=0x2B | 0x32..=0x34);
            let addressed = matches!(device, Device::Drive | Device::Sensor | Device::Io);
            (addressed && !untargeted_ir).then_some(p)
        }
        (Model::BoltPlus, Home::On(p)) => {
            let device = Device::from_id(did)?;
            let addressed = matches!(device, Device::Drive | Device::Sensor | Device::Io);
            let untargeted = device == Device::Sensor && cid == 0x25;
            (addressed && !untargeted).then_some(p)
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn routes() {
        use Processor::*;
        assert_eq!(addressed(Model::Bolt, 0x16, 0x07), Some(Secondary));
        assert_eq!(addressed(Model::Bolt, 0x1A, 0x1C), Some(Primary));
        assert_eq!(addressed(Model::Bolt, 0x1A, 0x42), Some(Secondary));
        assert_eq!(addressed(Model::Bolt, 0x13, 0x0D), None);
        assert_eq!(addressed(Model::Rvr, 0x13, 0x0D), Some(Primary));
        assert_eq!(addressed(Model::Rvr, 0x16, 0x01), Some(Secondary));
        assert_eq!(addressed(Model::Mini, 0x16, 0x07), None);
        assert!(home(Model::Bolt, 0x16, 0x07).accepts(Some(0x12)));
        assert!(!home(Model::Bolt, 0x16, 0x07).accepts(Some(0x11)));
        assert!(home(Model::Bolt, 0x16, 0x07).accepts(None));
        assert!(!home(Model::Mini, 0x16, 0x07).accepts(Some(0x12)));
        assert!(!home(Model::Rvr, 0x18, 0x39).accepts(Some(0x13)));
        assert!(home(Model::Rvr, 0x18, 0x39).accepts(Some(0x11)));
        // BOLT+ drives and draws on its primary (sphero-unsw), calibrates without a target.
        assert_eq!(addressed(Model::BoltPlus, 0x16, 0x07), Some(Primary));
        assert_eq!(addressed(Model::BoltPlus, 0x1A, 0x42), Some(Primary));
        assert_eq!(addressed(Model::BoltPlus, 0x18, 0x2A), Some(Primary));
        assert_eq!(addressed(Model::BoltPlus, 0x18, 0x25), None);
        assert_eq!(addressed(Model::BoltPlus, 0x13, 0x0D), None);
        assert!(!home(Model::BoltPlus, 0x16, 0x07).accepts(Some(0x12)));
        assert!(home(Model::BoltPlus, 0x11, 0x17).accepts(Some(0x12)));
    }
}
