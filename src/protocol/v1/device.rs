//! Device IDs of API v1 (`droid-facts.md` §4: Core 0x00, Sphero 0x02; the bootloader is 0x01
//! in the Sphero API documents).

/// The virtual devices of API v1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Device {
    Core,
    Bootloader,
    Sphero,
}

impl Device {
    pub const ALL: [Device; 3] = [Device::Core, Device::Bootloader, Device::Sphero];

    pub const fn id(self) -> u8 {
        match self {
            Device::Core => 0x00,
            Device::Bootloader => 0x01,
            Device::Sphero => 0x02,
        }
    }

    pub fn from_id(did: u8) -> Option<Device> {
        Device::ALL.into_iter().find(|d| d.id() == did)
    }

    pub fn name(self) -> &'static str {
        match self {
            Device::Core => "core",
            Device::Bootloader => "bootloader",
            Device::Sphero => "sphero",
        }
    }

    /// A device name for any DID, `0xNN` when unknown.
    pub fn describe(did: u8) -> String {
        match Device::from_id(did) {
            Some(d) => d.name().to_string(),
            None => format!("0x{did:02X}"),
        }
    }
}
