//! The v1 command and async-message catalogue: the single source of names, ids and payload
//! schemas. The typed constructors in [`cmd`] and the CLI's `encode_params` path are generated
//! from the same table, so they cannot disagree.
//!
//! Sources: `droid-facts.md` §4 for the commands it lists (it wins over everything else);
//! the Sphero API 1.50 document's layouts as implemented by spherov2.py
//! (`spherov2/commands/core.py`, `spherov2/commands/sphero.py`) and spheropy for the rest
//! (Get Chassis ID 0x07, Set Motion Timeout 0x34, option flags 0x35..0x38, Read Locator 0x15,
//! Get Voltage Trip Points 0x23, Poll Packet Times 0x51, Get Bluetooth Info's 16 + 12 byte
//! name and address).

use super::device::Device;
use super::packet::CommandPacket;
use super::types::*;
use crate::protocol::wire::*;
use crate::units::Heading;
use std::sync::LazyLock;

pub use crate::protocol::schema::{
    FieldDef, Schema, decode_fields, length_ok, min_len, minimal_payload,
};

/// Set Temporary Option Flags bit 0: stop when the client disconnects (Sphero API 1.50).
pub const TEMP_OPTION_STOP_ON_DISCONNECT: u32 = 0x0000_0001;

/// A command ready to be framed: device, command id and payload.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Command {
    pub did: u8,
    pub cid: u8,
    pub data: Vec<u8>,
}

impl Command {
    /// Frame with the default SOP2 (`FF`: answer, reset timeout) and the given SEQ.
    pub fn to_packet(&self, seq: u8) -> CommandPacket {
        CommandPacket::new(self.did, self.cid, seq, self.data.clone())
    }

    /// The catalogue entry for this command, if any.
    pub fn def(&self) -> Option<&'static CommandDef> {
        lookup(self.did, self.cid)
    }
}

/// One command of the catalogue.
pub use crate::protocol::table::CommandDef;
use crate::protocol::table::{CommandTable, RawCommand};

/// A catalogue command with its parameters encoded.
pub fn command(
    def: &CommandDef,
    given: &[(String, String)],
) -> Result<Command, crate::protocol::error::EncodeError> {
    Ok(Command {
        did: def.did,
        cid: def.cid,
        data: def.encode_params(given)?,
    })
}

pub trait IntoWire<T> {
    fn into_wire(self) -> T;
}

impl<T> IntoWire<T> for T {
    fn into_wire(self) -> T {
        self
    }
}

impl IntoWire<Mask<4>> for u32 {
    fn into_wire(self) -> Mask<4> {
        Mask(self)
    }
}

impl IntoWire<OptionalMask> for Option<u32> {
    fn into_wire(self) -> OptionalMask {
        OptionalMask(self)
    }
}

/// The constructor's parameter type: the plain type when one is given, else the wire type.
macro_rules! ctor_ty {
    ($wire:ty) => {
        $wire
    };
    ($wire:ty, $plain:ty) => {
        $plain
    };
}

macro_rules! catalogue {
    ($( $dev:ident { $( $cid:literal $fname:ident $spec:literal ( $($p:ident : $pty:ty $(as $cty:ty)? $(= $def:literal)?),* ) -> ( $($r:ident : $rty:ty),* ) ; )* } )*) => {
        /// Typed constructors, one per catalogue command: typed parameters in, payload out.
        pub mod cmd {
            #[allow(unused_imports)]
            use super::*;
            $( $(
                #[doc = concat!("`", $spec, "` (", stringify!($dev), ", CID ", stringify!($cid), ").")]
                pub fn $fname($($p: ctor_ty!($pty $(, $cty)?)),*) -> Command {
                    #[allow(unused_mut)]
                    let mut data = Vec::new();
                    $( Wire::put(&IntoWire::<$pty>::into_wire($p), &mut data); )*
                    Command { did: Device::$dev.id(), cid: $cid, data }
                }
            )* )*
        }

        static RAW_COMMANDS: &[RawCommand] = &[ $( $( RawCommand {
            did: Device::$dev.id(),
            cid: $cid,
            fn_name: stringify!($fname),
            spec_name: $spec,
            params: &[ $( FieldDef::of::<$pty>(stringify!($p)) $(.with_default($def))? ),* ],
            response: &[ $( FieldDef::of::<$rty>(stringify!($r)) ),* ],
        }, )* )* ];
    };
}

catalogue! {
    Core {
        0x01 ping "Ping" () -> ();
        // Sphero API 1.50: ten bytes, the last two the API version; spherov2.py reads the
        // first eight only, so the API version is optional. The bootloader, orbBasic and
        // macro versions pack major.minor in the high and low nibbles.
        0x02 get_versions "Get Versions" () -> (record_version: u8, model_number: u8,
            hardware_version: u8, main_app_version: u8, main_app_revision: u8,
            bootloader_version: u8, orb_basic_version: u8, macro_version: u8, api: ApiVersion);
        0x10 set_device_name "Set Device Name" (name: Text) -> ();
        // spheropy: 16-byte name, 12 ASCII hex digits of address, then a separator and the
        // three ID colours (kept raw).
        0x11 get_bluetooth_info "Get Bluetooth Info" () -> (name: FixedText<16>,
            address: FixedText<12>, rest: Bytes);
        // Power state 1 charging, 2 OK, 3 low, 4 critical; voltage in 1/100 V.
        0x20 get_power_state "Get Power State" () -> (record_version: u8, state: PowerState,
            voltage: CentiVolts, number_of_charges: u16, time_since_last_charge: u16);
        0x21 set_power_notification "Set Power Notification" (enable: bool = "true") -> ();
        // Wakeup seconds (0: never), macro to run on waking, orbBasic line to start at.
        0x22 sleep "Sleep" (wakeup: u16 = "0", macro_id: u8 = "0", orb_basic_line: u16 = "0") -> ();
        0x23 get_voltage_trip_points "Get Voltage Trip Points" () -> (low: CentiVolts,
            critical: CentiVolts);
        // Seconds; DID 00 in API v1 (v2 moved it).
        0x25 set_inactivity_timeout "Set Inactivity Timeout" (timeout: u16) -> ();
        // The result arrives as async ID 02.
        0x40 perform_level_1_diagnostics "Perform Level 1 Diagnostics" () -> ();
        0x50 assign_time "Assign Time" (time: u32) -> ();
        0x51 poll_packet_times "Poll Packet Times" (client_tx: u32) -> (client_tx: u32,
            sphero_rx: u32, sphero_tx: u32);
    }
    Sphero {
        0x01 set_heading "Set Heading" (heading: Heading = "0") -> ();
        0x02 set_stabilization "Set Stabilization" (enable: bool = "true") -> ();
        // Units of 0.784 °/s; 0xC8 is the firmware default.
        0x03 set_rotation_rate "Set Rotation Rate" (rate: u8 = "200") -> ();
        0x07 get_chassis_id "Get Chassis ID" () -> (chassis_id: u16);
        // N: divisor of the 400 Hz sample rate (40 = 10 Hz); M: frames per packet; PCNT:
        // packets to send (0 = forever); MASK 0 stops streaming. MASK2 is optional
        // (13- or 17-byte payloads), sent only when given.
        0x11 set_data_streaming "Set Data Streaming" (n: u16 = "40", m: u16 = "1",
            mask: Mask<4> as u32, pcnt: u8 = "0", mask2: OptionalMask as Option<u32> = "none") -> ();
        // droid-facts.md §4 order [method, Xt, Xspd, Yt, Yspd, dead] (spheropy agrees);
        // spherov2.py sends [method, Xt, Yt, Xspd, Yspd, dead]. The defaults are equal for x
        // and y, which sidesteps the dispute. Method 0 off, 1 the firmware's detector (a
        // plain number: v2's CollisionMethod names do not describe v1). Dead time in 10 ms
        // units.
        0x12 configure_collision_detection "Configure Collision Detection" (
            method: u8 = "1", x_threshold: u8 = "100", x_speed: u8 = "100",
            y_threshold: u8 = "100", y_speed: u8 = "100", dead_time: u8 = "10") -> ();
        0x13 configure_locator "Configure Locator" (flags: u8 = "0", x: i16 = "0", y: i16 = "0",
            yaw_tare: u16 = "0") -> ();
        // Position in cm, velocities in cm/s.
        0x15 read_locator "Read Locator" () -> (x: i16, y: i16, velocity_x: i16, velocity_y: i16,
            speed_over_ground: u16);
        // droid-facts.md §4: send persist = 0.
        0x20 set_rgb_led "Set RGB LED" (red: u8, green: u8, blue: u8, persist: bool = "false") -> ();
        0x21 set_back_led "Set Back LED" (brightness: u8) -> ();
        0x22 get_rgb_led "Get RGB LED" () -> (red: u8, green: u8, blue: u8);
        // droid-facts.md §4: [speed, heading u16, state]; the golden vector is 4 data bytes.
        // spherov2.py appends a fifth "reverse" byte that droidctl does not send.
        0x30 roll "Roll" (speed: u8, heading: Heading = "0", state: RollState = "go") -> ();
        0x33 set_raw_motors "Set Raw Motors" (left_mode: MotorMode, left_power: u8,
            right_mode: MotorMode, right_power: u8) -> ();
        0x34 set_motion_timeout "Set Motion Timeout" (timeout_ms: u16) -> ();
        0x35 set_permanent_option_flags "Set Permanent Option Flags" (flags: Mask<4> as u32) -> ();
        0x36 get_permanent_option_flags "Get Permanent Option Flags" () -> (flags: Mask<4>);
        // Bit 0 stops the droid when the client disconnects.
        0x37 set_temporary_option_flags "Set Temporary Option Flags" (flags: Mask<4> as u32) -> ();
        0x38 get_temporary_option_flags "Get Temporary Option Flags" () -> (flags: Mask<4>);
    }
}

static COMMANDS: LazyLock<CommandTable> = LazyLock::new(|| CommandTable::new(RAW_COMMANDS));

/// Payloads real clients send besides the catalogue's, which real droids accept: spherov2.py
/// (`commands/sphero.py`) turns the LEDs off with a 3-byte Set RGB LED (no persist flag) and
/// rolls with a fifth byte, its reverse flag (`Sphero.roll(…, roll_mode, reverse_flag)`).
/// The payload read as the catalogue's fields that it carries, plus the reverse flag; `None`
/// for any other payload.
pub fn client_variant(did: u8, cid: u8, data: &[u8]) -> Option<crate::protocol::value::Fields> {
    let def = lookup(did, cid)?;
    match (did, cid, data) {
        (0x02, 0x20, [_, _, _]) => decode_fields(&def.params[..3], data).ok(),
        (0x02, 0x30, [head @ .., reverse]) if head.len() == 4 => {
            let mut f = decode_fields(def.params, head).ok()?;
            f.push((
                "reverse",
                crate::protocol::value::Value::Bool(*reverse != 0),
            ));
            Some(f)
        }
        _ => None,
    }
}

/// Every command, in table order.
pub fn commands() -> &'static [CommandDef] {
    COMMANDS.commands()
}

/// The command with this DID/CID.
pub fn lookup(did: u8, cid: u8) -> Option<&'static CommandDef> {
    COMMANDS.lookup(did, cid)
}

/// The command with this kebab-case name.
pub fn by_name(name: &str) -> Option<&'static CommandDef> {
    COMMANDS.by_name(name)
}

/// Command names closest to `name`, for "did you mean" hints.
pub fn suggestions(name: &str) -> Vec<&'static str> {
    COMMANDS.suggestions(name)
}

// -------------------------------------------------------------------------------------------
// Async messages
// -------------------------------------------------------------------------------------------

/// Async ID codes droidctl acts on.
pub mod id {
    pub const POWER_NOTIFICATION: u8 = 0x01;
    pub const LEVEL_1_DIAGNOSTIC: u8 = 0x02;
    pub const SENSOR_DATA: u8 = 0x03;
    pub const PRE_SLEEP_WARNING: u8 = 0x05;
    pub const COLLISION: u8 = 0x07;
}

/// One async message of the seed's ID code table.
#[derive(Debug)]
pub struct AsyncDef {
    pub id_code: u8,
    /// kebab-case name, e.g. `collision-detected`.
    pub name: &'static str,
    /// The description in the seed's table.
    pub spec_name: &'static str,
    /// Payload layout. Sensor data is decoded with the masks in effect instead (see
    /// [`super::sensor::decode_samples`]); this raw list is the fallback.
    pub fields: Schema,
}

const fn def(id_code: u8, name: &'static str, spec_name: &'static str, fields: Schema) -> AsyncDef {
    AsyncDef {
        id_code,
        name,
        spec_name,
        fields,
    }
}

const RAW: Schema = &[FieldDef::of::<Bytes>("data")];

/// `sphero-v1-packets.md`, "Sphero Asynchronous Packets". Payloads the seed describes are
/// decoded; the others are kept as raw `data`.
static ASYNC_MESSAGES: &[AsyncDef] = &[
    def(
        0x01,
        "power-notification",
        "Power notifications",
        &[FieldDef::of::<PowerState>("state")],
    ),
    def(
        0x02,
        "level-1-diagnostic-response",
        "Level 1 Diagnostic response",
        &[FieldDef::of::<Text>("text")],
    ),
    def(
        0x03,
        "sensor-data-streaming",
        "Sensor data streaming",
        &[FieldDef::of::<I16List>("values")],
    ),
    def(0x04, "config-block-contents", "Config block contents", RAW),
    def(0x05, "pre-sleep-warning", "Pre-sleep warning (10 sec)", &[]),
    def(0x06, "macro-markers", "Macro markers", RAW),
    // 16 bytes (droid-facts.md §4), the v2 collision's field names minus power_z.
    def(
        0x07,
        "collision-detected",
        "Collision detected",
        &[
            FieldDef::of::<AccelRaw>("accel_x"),
            FieldDef::of::<AccelRaw>("accel_y"),
            FieldDef::of::<AccelRaw>("accel_z"),
            FieldDef::of::<CollisionAxis>("axis"),
            FieldDef::of::<i16>("power_x"),
            FieldDef::of::<i16>("power_y"),
            FieldDef::of::<u8>("speed"),
            FieldDef::of::<u32>("time_ms"),
        ],
    ),
    def(
        0x08,
        "orbbasic-print-message",
        "orbBasic PRINT message",
        &[FieldDef::of::<Text>("text")],
    ),
    def(
        0x09,
        "orbbasic-error-ascii",
        "orbBasic error message, ASCII",
        &[FieldDef::of::<Text>("text")],
    ),
    def(
        0x0A,
        "orbbasic-error-binary",
        "orbBasic error message, binary",
        RAW,
    ),
    def(0x0B, "self-level-result", "Self Level Result", RAW),
    // Bits: 0 X+, 1 X-, 2 Y+, 3 Y-, 4 Z+, 5 Z-.
    def(
        0x0C,
        "gyro-axis-limit-exceeded",
        "Gyro axis limit exceeded",
        &[FieldDef::of::<Mask<1>>("axes")],
    ),
    def(0x0D, "soul-data", "Sphero's soul data", RAW),
    def(
        0x0E,
        "level-up-notification",
        "Level up notification",
        &[
            FieldDef::of::<u16>("level"),
            FieldDef::of::<u16>("attribute_points"),
        ],
    ),
    def(
        0x0F,
        "shield-damage-notification",
        "Shield damage notification",
        &[FieldDef::of::<u8>("shield")],
    ),
    def(
        0x10,
        "xp-update-notification",
        "XP update notification",
        &[FieldDef::of::<u8>("xp")],
    ),
    def(
        0x11,
        "boost-update-notification",
        "Boost update notification",
        &[FieldDef::of::<u8>("boost")],
    ),
];

/// Every async message of the table, by ID code.
pub fn async_messages() -> &'static [AsyncDef] {
    ASYNC_MESSAGES
}

/// The async message with this ID code.
pub fn async_message(id_code: u8) -> Option<&'static AsyncDef> {
    ASYNC_MESSAGES.iter().find(|d| d.id_code == id_code)
}

/// The name of an async message, `async-NN` (hex) when unknown.
pub fn async_name(id_code: u8) -> String {
    async_message(id_code).map_or_else(|| format!("async-{id_code:02x}"), |d| d.name.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn given(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn names_derive_from_spec_names_and_are_unique() {
        let mut names = std::collections::HashSet::new();
        let mut ids = std::collections::HashSet::new();
        for c in commands() {
            assert_eq!(c.name, c.spec_name.to_ascii_lowercase().replace(' ', "-"));
            assert!(names.insert(c.name.clone()), "duplicate {}", c.name);
            assert!(ids.insert((c.did, c.cid)), "duplicate id of {}", c.name);
        }
        let mut codes = std::collections::HashSet::new();
        for a in async_messages() {
            assert!(codes.insert(a.id_code));
        }
        assert_eq!(async_messages().len(), 17);
    }

    #[test]
    fn roll_defaults_to_go() {
        let roll = by_name("roll").unwrap();
        assert_eq!(
            roll.encode_params(&given(&[("speed", "128"), ("heading", "90")])),
            Ok(vec![0x80, 0x00, 0x5A, 0x01])
        );
        assert!(roll.encode_params(&given(&[("heading", "90")])).is_err());
    }

    #[test]
    fn data_streaming_is_9_or_13_bytes() {
        let c = by_name("set-data-streaming").unwrap();
        let short = c.encode_params(&given(&[("mask", "0x00070000")])).unwrap();
        assert_eq!(short, vec![0, 40, 0, 1, 0, 7, 0, 0, 0]);
        let long = c
            .encode_params(&given(&[("mask", "0"), ("mask2", "0x0C000000")]))
            .unwrap();
        assert_eq!(long.len(), 13);
        assert!(length_ok(c.params, 9) && length_ok(c.params, 13));
    }

    #[test]
    fn suggestions_find_close_names() {
        assert!(suggestions("rgb-led").contains(&"set-rgb-led"));
        assert_eq!(async_name(0x07), "collision-detected");
        assert_eq!(async_name(0x42), "async-42");
    }
}
