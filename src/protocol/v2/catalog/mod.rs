//! The command and notification catalogue: the single source of truth for names, ids and
//! payload schemas. The CLI (`packet encode`, `packet decode`), the packet log and the
//! simulator's length checks all read it; the typed constructors in [`cmd`] are generated from
//! the same table, so the two can never disagree.
//!
//! Sources: `r2d2-v2-protocol.md` §4 for ids and sizes, corrected by `droid-facts.md` §2
//! (head position is degrees, collision is 18 bytes). Where the seed gives only a size
//! ("2 bytes"), field names and types follow spherov2.py's command modules; names marked
//! there as unknown are kept generic (`data`).

pub(super) use super::device::Device;
use super::packet::Packet;
#[allow(unused_imports)]
pub(super) use super::types::*;
#[allow(unused_imports)]
pub(super) use crate::protocol::wire::*;
#[allow(unused_imports)]
pub(super) use crate::units::{HeadAngle, Heading};
use std::collections::HashMap;
use std::sync::LazyLock;

/// A command ready to be framed: device, command id and payload.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Command {
    pub did: u8,
    pub cid: u8,
    pub data: Vec<u8>,
    /// The processor the command is addressed to (target id `0x11` primary, `0x12`
    /// secondary), on robots with two (BOLT, RVR); `None` sends no target, or lets the
    /// connection's router pick the command's own ([`targets`]).
    pub target: Option<u8>,
}

impl Command {
    /// A command without a target.
    pub fn new(did: u8, cid: u8, data: Vec<u8>) -> Command {
        Command {
            did,
            cid,
            data,
            target: None,
        }
    }

    /// The same command addressed to `processor`.
    pub fn to(mut self, processor: targets::Processor) -> Command {
        self.target = Some(processor.target_id());
        self
    }

    /// Frame with the default flags (0x0A) and the given SEQ; a command with a target also
    /// carries has-target and has-source (source 0x01, as spherov2.py sends).
    pub fn to_packet(&self, seq: u8) -> Packet {
        let mut p = Packet::command(self.did, self.cid, seq, self.data.clone());
        if let Some(t) = self.target {
            p.flags |= super::flags::Flags::HAS_TARGET_ID | super::flags::Flags::HAS_SOURCE_ID;
            p.tid = Some(t);
            p.sid = Some(targets::HOST_SOURCE_ID);
        }
        p
    }

    /// The catalogue entry for this command, if any.
    pub fn def(&self) -> Option<&'static CommandDef> {
        lookup(self.did, self.cid)
    }
}

pub use crate::protocol::schema::{
    FieldDef, Schema, decode_fields, length_ok, min_len, minimal_payload,
};

pub use crate::protocol::table::CommandDef;
pub(super) use crate::protocol::table::{CommandTable, RawCommand};

/// One notification of the catalogue.
#[derive(Debug)]
pub struct NotificationDef {
    pub name: String,
    pub spec_name: &'static str,
    pub device: Device,
    pub cid: u8,
    pub fields: Schema,
}

pub(super) struct RawNotification {
    device: Device,
    cid: u8,
    fn_name: &'static str,
    spec_name: &'static str,
    fields: Schema,
}

macro_rules! catalogue {
    ($( $dev:ident { $( $cid:literal $fname:ident $spec:literal ( $($p:ident : $pty:ty $(= $def:literal)?),* ) -> ( $($r:ident : $rty:ty),* ) ; )* } )*) => {
        /// Typed constructors, one per catalogue command: typed parameters in, payload out.
        pub mod cmd {
            #[allow(unused_imports)]
            use super::*;
            $( $(
                #[doc = concat!("`", $spec, "` (", stringify!($dev), ", CID ", stringify!($cid), ").")]
                pub fn $fname($($p: $pty),*) -> Command {
                    #[allow(unused_mut)]
                    let mut data = Vec::new();
                    $( Wire::put(&$p, &mut data); )*
                    Command { did: Device::$dev.id(), cid: $cid, data, target: None }
                }
            )* )*
        }

        pub(super) static RAW_COMMANDS: &[RawCommand] = &[ $( $( RawCommand {
            did: Device::$dev.id(),
            cid: $cid,
            fn_name: stringify!($fname),
            spec_name: $spec,
            params: &[ $( FieldDef::of::<$pty>(stringify!($p)) $(.with_default($def))? ),* ],
            response: &[ $( FieldDef::of::<$rty>(stringify!($r)) ),* ],
        }, )* )* ];
    };
}

macro_rules! notifications {
    ($( $dev:ident { $( $cid:literal $fname:ident $spec:literal ( $($f:ident : $fty:ty),* ) ; )* } )*) => {
        pub(super) static RAW_NOTIFICATIONS: &[RawNotification] = &[ $( $( RawNotification {
            device: Device::$dev,
            cid: $cid,
            fn_name: stringify!($fname),
            spec_name: $spec,
            fields: &[ $( FieldDef::of::<$fty>(stringify!($f)) ),* ],
        }, )* )* ];
    };
}

// The rows, one file per group of devices; each declares its constructors and rows.
mod api;
mod drive;
mod io;
mod notices;
mod power;
mod sensor;
mod system;
pub mod targets;

/// Typed constructors, one per catalogue command: typed parameters in, payload out.
pub mod cmd {
    pub use super::api::cmd::*;
    pub use super::drive::cmd::*;
    pub use super::io::cmd::*;
    pub use super::power::cmd::*;
    pub use super::sensor::cmd::*;
    pub use super::system::cmd::*;
}

/// Every row, in table order.
const PARTS: [&[RawCommand]; 6] = [
    system::RAW_COMMANDS,
    power::RAW_COMMANDS,
    drive::RAW_COMMANDS,
    sensor::RAW_COMMANDS,
    io::RAW_COMMANDS,
    api::RAW_COMMANDS,
];

/// The notifications, indexed by id.
struct Notifications {
    all: Vec<NotificationDef>,
    by_id: HashMap<(u8, u8), usize>,
}

static COMMANDS: LazyLock<CommandTable> = LazyLock::new(|| CommandTable::from_parts(&PARTS));

static NOTIFICATIONS: LazyLock<Notifications> = LazyLock::new(|| {
    let all: Vec<NotificationDef> = notices::RAW_NOTIFICATIONS
        .iter()
        .map(|r| NotificationDef {
            name: r.fn_name.replace('_', "-"),
            spec_name: r.spec_name,
            device: r.device,
            cid: r.cid,
            fields: r.fields,
        })
        .collect();
    let by_id = all
        .iter()
        .enumerate()
        .map(|(i, n)| ((n.device.id(), n.cid), i))
        .collect();
    Notifications { all, by_id }
});

/// Every command, in table order.
pub fn commands() -> &'static [CommandDef] {
    COMMANDS.commands()
}

/// Every notification, in table order.
pub fn notifications() -> &'static [NotificationDef] {
    &NOTIFICATIONS.all
}

/// The command with this DID/CID.
pub fn lookup(did: u8, cid: u8) -> Option<&'static CommandDef> {
    COMMANDS.lookup(did, cid)
}

/// The command with this kebab-case name.
pub fn by_name(name: &str) -> Option<&'static CommandDef> {
    COMMANDS.by_name(name)
}

/// The notification with this DID/CID.
pub fn notification(did: u8, cid: u8) -> Option<&'static NotificationDef> {
    NOTIFICATIONS
        .by_id
        .get(&(did, cid))
        .map(|&i| &NOTIFICATIONS.all[i])
}

/// Command names closest to `name`, for "did you mean" hints.
pub fn suggestions(name: &str) -> Vec<&'static str> {
    COMMANDS.suggestions(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kebab(spec: &str) -> String {
        spec.to_ascii_lowercase().replace(' ', "-")
    }

    #[test]
    fn names_derive_from_spec_names_and_are_unique() {
        let mut seen = std::collections::HashSet::new();
        for c in commands() {
            let derived = kebab(c.spec_name);
            assert!(
                c.name == derived
                    || c.name == format!("core-{derived}")
                    || c.name == format!("connection-{derived}"),
                "{} vs {}",
                c.name,
                c.spec_name
            );
            assert!(seen.insert(c.name.clone()), "duplicate {}", c.name);
            assert!(seen.len() <= commands().len());
        }
        let ids: std::collections::HashSet<_> = commands().iter().map(|c| (c.did, c.cid)).collect();
        assert_eq!(ids.len(), commands().len(), "duplicate DID/CID");
        for n in notifications() {
            assert_eq!(n.name, kebab(n.spec_name));
        }
    }

    #[test]
    fn catalogue_covers_every_seed_table_row() {
        // Counts of rows in r2d2-v2-protocol.md §4.2–§4.8.
        let count = |d: Device| {
            commands()
                .iter()
                .filter(|c| Device::from_id(c.did) == Some(d))
                .count()
        };
        assert_eq!(count(Device::Core), 11);
        assert_eq!(count(Device::SystemInfo), 26);
        assert_eq!(count(Device::Power), 20);
        assert_eq!(count(Device::Drive), 13);
        assert_eq!(count(Device::Animatronic), 13);
        assert_eq!(count(Device::Sensor), 40);
        assert_eq!(
            count(Device::Io),
            10 + 29,
            "the seed's 10 and BOLT's and RVR's 29"
        );
        // The devices spherov2.py adds for BOLT, Mini and RVR (`catalog/api.rs`).
        assert_eq!(count(Device::ApiAndShell), 5);
        assert_eq!(count(Device::SystemMode), 3);
        assert_eq!(count(Device::Connection), 3);
        assert_eq!(count(Device::Firmware), 8);
        assert_eq!(count(Device::FactoryTest), 6);
    }

    #[test]
    fn issue_examples_encode() {
        let c = by_name("drive-with-heading").unwrap();
        let given = |pairs: &[(&str, &str)]| -> Vec<(String, String)> {
            pairs
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        };
        assert_eq!(
            c.encode_params(&given(&[
                ("speed", "100"),
                ("heading", "180"),
                ("flags", "0")
            ])),
            Ok(vec![100, 0, 180, 0])
        );
        let err = c
            .encode_params(&given(&[
                ("speed", "100"),
                ("heading", "360"),
                ("flags", "0"),
            ]))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("--heading") && err.contains("0..=359"),
            "{err}"
        );
        let err = c
            .encode_params(&given(&[("speed", "100")]))
            .unwrap_err()
            .to_string();
        assert!(err.contains("needs --heading"), "{err}");
        // Flags default to none (issue 8), so speed and heading are enough.
        assert_eq!(
            c.encode_params(&given(&[("speed", "100"), ("heading", "180")])),
            Ok(vec![100, 0, 180, 0])
        );
        // Collision detection defaults to the common reference-client values.
        assert_eq!(
            by_name("configure-collision-detection")
                .unwrap()
                .encode_params(&[]),
            Ok(vec![1, 90, 130, 90, 130, 1])
        );
        let err = by_name("wake")
            .unwrap()
            .encode_params(&given(&[("x", "1")]))
            .unwrap_err()
            .to_string();
        assert!(err.contains("takes no parameters"));
    }

    #[test]
    fn length_rules() {
        let drive = by_name("drive-with-heading").unwrap();
        assert!(length_ok(drive.params, 4));
        assert!(!length_ok(drive.params, 3));
        assert!(!length_ok(drive.params, 5));
        let leds = by_name("set-all-leds-with-16-bit-mask").unwrap();
        assert!(length_ok(leds.params, 3));
        assert!(!length_ok(leds.params, 1));
    }

    #[test]
    fn suggestions_find_close_names() {
        assert!(suggestions("drive-heading").contains(&"drive-with-heading"));
    }
}
