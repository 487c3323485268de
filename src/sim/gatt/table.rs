//! A droid's GATT table as its profile describes it: every characteristic the profile
//! writes, reads or subscribes to, with the properties a client sees, in the service it lives
//! in.

use crate::gatt::{CharRef, GattUuid, HandshakeStep};
use crate::model::Model;

bitflags::bitflags! {
    /// What a characteristic allows, as its GATT properties say.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub struct CharFlags: u8 {
        const READ = 0x02;
        const WRITE_WITHOUT_RESPONSE = 0x04;
        const WRITE = 0x08;
        const NOTIFY = 0x10;
    }
}

impl CharFlags {
    /// The flag names BlueZ uses (`org.bluez.GattCharacteristic1.Flags`).
    pub fn names(self) -> Vec<&'static str> {
        [
            (CharFlags::READ, "read"),
            (CharFlags::WRITE_WITHOUT_RESPONSE, "write-without-response"),
            (CharFlags::WRITE, "write"),
            (CharFlags::NOTIFY, "notify"),
        ]
        .into_iter()
        .filter(|(f, _)| self.contains(*f))
        .map(|(_, n)| n)
        .collect()
    }

    pub fn writable(self) -> bool {
        self.intersects(CharFlags::WRITE | CharFlags::WRITE_WITHOUT_RESPONSE)
    }
}

/// One characteristic of the table.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CharDef {
    pub uuid: GattUuid,
    pub flags: CharFlags,
}

/// One primary service and its characteristics, in the order a droid lists them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceDef {
    pub uuid: GattUuid,
    pub characteristics: Vec<CharDef>,
}

/// The GATT table of `model`, as its profile describes it: every characteristic the profile
/// writes, reads or subscribes to, in the service it lives in.
pub fn gatt_table(model: Model) -> Vec<ServiceDef> {
    let profile = crate::family::gatt_profile(model);
    let writable = CharFlags::WRITE | CharFlags::WRITE_WITHOUT_RESPONSE;
    let mut chars: Vec<(CharRef, CharFlags)> = Vec::new();
    let mut add = |c: CharRef, f: CharFlags| match chars
        .iter_mut()
        .find(|(x, _)| x.characteristic == c.characteristic)
    {
        Some((_, flags)) => *flags |= f,
        None => chars.push((c, f)),
    };
    add(profile.write, writable);
    for (_, c) in &profile.inputs {
        add(*c, writable);
    }
    for c in &profile.notify {
        add(*c, CharFlags::NOTIFY);
    }
    for step in &profile.handshake {
        match step {
            HandshakeStep::Write { ch, .. } => add(*ch, writable),
            HandshakeStep::Read { ch, .. } => add(*ch, CharFlags::READ),
        }
    }
    let mut table: Vec<ServiceDef> = Vec::new();
    for (c, flags) in chars {
        let service = c.home(profile.service);
        let def = CharDef {
            uuid: c.characteristic,
            flags,
        };
        match table.iter_mut().find(|s| s.uuid == service) {
            Some(s) => s.characteristics.push(def),
            None => table.push(ServiceDef {
                uuid: service,
                characteristics: vec![def],
            }),
        }
    }
    // The main service first, as droids list it.
    table.sort_by_key(|s| s.uuid != profile.service);
    table
}
