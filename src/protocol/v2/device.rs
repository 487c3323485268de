//! Device IDs (`r2d2-v2-protocol.md` §4.1; API and Shell, System Mode, Connection, Firmware
//! and Factory Test from spherov2.py's `commands/*.py`, `droid-facts.md` §6).

/// The virtual devices ("command groups") of API v2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Device {
    Core,
    SystemInfo,
    Power,
    Drive,
    Animatronic,
    Sensor,
    Io,
    ApiAndShell,
    SystemMode,
    Connection,
    Firmware,
    FactoryTest,
}

impl Device {
    pub const ALL: [Device; 12] = [
        Device::Core,
        Device::SystemInfo,
        Device::Power,
        Device::Drive,
        Device::Animatronic,
        Device::Sensor,
        Device::Io,
        Device::ApiAndShell,
        Device::SystemMode,
        Device::Connection,
        Device::Firmware,
        Device::FactoryTest,
    ];

    pub const fn id(self) -> u8 {
        match self {
            Device::Core => 0x00,
            Device::SystemInfo => 0x11,
            Device::Power => 0x13,
            Device::Drive => 0x16,
            Device::Animatronic => 0x17,
            Device::Sensor => 0x18,
            Device::Io => 0x1A,
            Device::ApiAndShell => 0x10,
            Device::SystemMode => 0x12,
            Device::Connection => 0x19,
            Device::Firmware => 0x1D,
            Device::FactoryTest => 0x1F,
        }
    }

    pub fn from_id(did: u8) -> Option<Device> {
        Device::ALL.into_iter().find(|d| d.id() == did)
    }

    pub fn name(self) -> &'static str {
        match self {
            Device::Core => "core",
            Device::SystemInfo => "system-info",
            Device::Power => "power",
            Device::Drive => "drive",
            Device::Animatronic => "animatronic",
            Device::Sensor => "sensor",
            Device::Io => "io",
            Device::ApiAndShell => "api-and-shell",
            Device::SystemMode => "system-mode",
            Device::Connection => "connection",
            Device::Firmware => "firmware",
            Device::FactoryTest => "factory-test",
        }
    }

    /// A device name for any DID, `0xNN` when unknown.
    pub fn describe(did: u8) -> String {
        match Device::from_id(did) {
            Some(d) => d.name().to_string(),
            None => format!("0x{did:02X}"),
        }
    }

    /// Parse a device by name or number (for filters).
    pub fn parse(text: &str) -> Option<u8> {
        let t = text.trim().to_ascii_lowercase();
        if let Some(d) = Device::ALL.into_iter().find(|d| d.name() == t) {
            return Some(d.id());
        }
        super::wire::parse_uint(&t, 255).ok().map(|v| v as u8)
    }
}
