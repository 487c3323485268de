//! The seam between protocol families: Sphero API v2, Sphero API v1 and RSRCP.
//!
//! Everything that differs between the families is reached through this one interface; the
//! model picks the family ([`for_model`]), a name or a captured byte stream finds one
//! ([`by_name`], [`detect`]). A family supplies:
//! - who it is: its short and display names, its start-of-packet byte, a model that speaks
//!   it;
//! - a [`Codec`] for a live connection: framing and a streaming decoder, how a response is
//!   matched to its request, and how its asynchronous messages map onto the common
//!   [`Notification`](crate::protocol::notify::Notification)s;
//! - a [`Reader`] for traffic seen from outside (captures, traces, `packet decode`): either
//!   side's bytes into packets explained as text or JSON;
//! - packets built by name and its catalogue listed (`packet encode`, `packet list`);
//! - the commands behind each capability (drive, stop, dome, stance, LEDs, aim, sleep …),
//!   built from its own catalogue, or `None` when the family has no such thing;
//! - [`Family::lower`]: what a droid should do ([`intent::Intent`], the one vocabulary of
//!   everything above the families) as `(model, intent)` → commands, or
//!   [`intent::Unsupported`]. What the model can do is the model table's ([`crate::model::Caps`]),
//!   not something to find out by building dummy commands;
//! - [`catalog`]: the names of the animations and sounds the Star Wars droids play.
//!
//! Everything here is sans-IO: no clocks, no tokio.

pub mod catalog;
pub mod error;
pub mod intent;
pub mod listing;
pub mod named;
pub mod read;
pub mod robi;
pub mod setup;
pub mod stream;
pub mod types;
pub mod v1;
pub mod v2;

pub use read::{Found, ReadOption, ReadOptions, Reader, Side};
pub use types::{
    Command, DecodeError, DroidError, Explained, Incoming, Key, Packet, PacketKind, RobiControl,
    RobiPacket,
};

use crate::family::setup::SetupOptions;
use crate::model::{Model, Protocol};
use crate::protocol::decode::ErrorKind;
use crate::protocol::wire::LegAction;
use crate::script::Action;
use crate::units::{HeadAngle, Heading};

/// Framing, decoding and matching for one connection. One per connection: it holds the
/// decoder's partial input and what the droid was told to stream.
pub trait Codec: Send {
    fn protocol(&self) -> Protocol;
    /// The key the response to `cmd` sent with `seq` will carry.
    fn key(&self, cmd: &Command, seq: u8) -> Key;
    /// Frame `cmd` with `seq`. `want_response` false asks the droid not to answer.
    /// Also notes what the command changes in the decoding (streaming masks).
    fn encode(&mut self, cmd: &Command, seq: u8, want_response: bool) -> (Vec<u8>, Packet);
    /// The writes for `cmd`, each to its endpoint (Robi's drive command is a velocity and a
    /// steering write). Sphero families write the framed packet to the command channel.
    fn encode_writes(
        &mut self,
        cmd: &Command,
        seq: u8,
        want_response: bool,
    ) -> (Vec<(crate::gatt::Endpoint, Vec<u8>)>, Packet) {
        let (wire, packet) = self.encode(cmd, seq, want_response);
        (vec![(crate::gatt::Endpoint::Api, wire)], packet)
    }
    /// Whether the droid answers commands at all (Robi 42 only reports its state).
    fn answers(&self) -> bool {
        true
    }
    /// A new connection: drop any partial packet of the old byte stream, keep what the droid
    /// was told (streaming masks).
    fn reset_stream(&mut self) {}
    /// Bytes from the droid, in any chunking.
    fn feed(&mut self, bytes: &[u8], out: &mut Vec<Incoming>);
    /// Explain a packet for the log; `request` is the command a response answers, when known
    /// (a v1 response carries only a SEQ, so its payload is decoded by the request's schema).
    fn explain(&self, p: &Packet, request: Option<&Command>) -> Explained;
}

/// One protocol family: who it is, its codec and reader, and the commands behind each
/// capability.
pub trait Family: Sync {
    fn protocol(&self) -> Protocol;
    /// The short name on the command line and in captures (`v2`).
    fn name(&self) -> &'static str;
    /// The name for people (`Sphero API v2`).
    fn display_name(&self) -> &'static str;
    /// The first byte of every packet: how a byte stream shows its family.
    fn sop(&self) -> u8;
    /// A model that speaks the family, for a capture that names only the family.
    fn representative(&self) -> Model;
    /// The decode errors its readers report, in the order summaries list them.
    fn error_kinds(&self) -> &'static [ErrorKind];
    /// The [`ReadOptions`] its readers use; a caller refuses the others.
    fn read_options(&self) -> &'static [ReadOption];
    /// A reader of one side's bytes; `Err` says which option makes no sense.
    fn reader(&self, opts: &ReadOptions) -> Result<Box<dyn Reader>, error::ReadError>;
    /// A reader told nothing but the side (and whether values come whole), as captures and
    /// traces read: it cannot fail.
    fn side_reader(&self, side: Side, whole_values: bool) -> Box<dyn Reader>;
    /// The GATT profile of `model` (one of the family's): what a link writes, reads and
    /// subscribes to, and the handshake that unlocks the droid.
    fn gatt_profile(&self, model: Model) -> crate::gatt::GattProfile;
    /// `packet encode`: the wire bytes of the packet `name` with `--key value` parameters.
    fn encode_named(
        &self,
        name: &str,
        params: Vec<(String, String)>,
    ) -> Result<Vec<u8>, error::NamedError>;
    /// The names [`Family::encode_named`] takes, with what each is (the shell completions of
    /// `packet encode NAME`).
    fn encode_names(&self) -> Vec<(String, &'static str)>;
    /// `packet list`: the catalogue, names containing `filter` only; how many entries were
    /// listed (a heading is printed only above entries: [`listing::Listing`]).
    fn list(&self, filter: Option<&str>, out: &mut dyn std::io::Write) -> std::io::Result<usize>;
    fn codec(&self) -> Box<dyn Codec>;
    /// The codec for a connection to `model`: as [`Family::codec`], plus what the model
    /// needs of every packet (the v2 robots with two processors address each command).
    fn codec_for(&self, model: Model) -> Box<dyn Codec> {
        let _ = model;
        self.codec()
    }
    /// The command that wakes a droid from soft sleep, first after every connect.
    fn wake(&self) -> Option<Command>;
    /// Cheap activity that keeps the droid awake.
    fn ping(&self) -> Command;
    /// Something harmless to write when a link needs traffic to stay open
    /// ([`crate::link::Link::keepalive`]); `last_drive` is the drive command last written.
    fn keepalive(&self, last_drive: Option<&Command>) -> Command {
        let _ = last_drive;
        self.ping()
    }
    /// Put the droid to sleep (sent on quit when configured).
    fn sleep(&self) -> Option<Command> {
        None
    }
    /// Roll at `speed` (0..=255) toward `heading`; `reverse` backs up along that heading.
    fn drive(&self, speed: u8, heading: Heading, reverse: bool) -> Command;
    /// Whether `cmd` is a drive command (the session remembers the last one written).
    fn is_drive(&self, cmd: &Command) -> bool;
    /// Speed 0 keeping the heading of `last` (a stop at heading 0 would turn the droid).
    fn stop_after(&self, last: Option<&Command>) -> Command;
    /// Driven by velocity and steering rather than toward a heading (Robi 42).
    fn steers(&self) -> bool {
        false
    }
    /// For a steering family: forward at `speed` with `turn` in −1 (left) ..= 1 (right).
    fn steer(&self, _speed: u8, _turn: f32) -> Option<Command> {
        None
    }
    /// Whether the droid can back up.
    fn can_reverse(&self) -> bool {
        true
    }
    // Capabilities a family may lack: `None` (the default) means "this droid has none".
    fn head(&self, _angle: HeadAngle) -> Option<Command> {
        None
    }
    fn stance(&self, _action: LegAction) -> Option<Command> {
        None
    }
    /// Ask the stance, and read the answer.
    fn get_stance(&self) -> Option<Command> {
        None
    }
    /// Play animation `id` on `model` (`None`: it has none).
    fn animation(&self, _model: Model, _id: u16) -> Option<Command> {
        None
    }
    /// Play sound `id` on `model` (`None`: it cannot play sounds).
    fn sound(&self, _model: Model, _id: u16) -> Option<Command> {
        None
    }
    /// The LED command for a script's LED line on `model`.
    fn led(&self, _model: Model, _action: &Action) -> Option<Command> {
        None
    }
    /// Read the battery voltage, and parse the answer.
    fn battery_request(&self) -> Option<Command> {
        None
    }
    fn battery_volts(&self, _response: &[u8]) -> Option<f32> {
        None
    }
    /// The battery request for `model`, addressed to the processor that measures it (RVR's
    /// primary), and its answer read.
    fn battery_request_for(&self, model: Model) -> Option<Command> {
        let _ = model;
        self.battery_request()
    }
    fn battery_volts_for(&self, model: Model, response: &[u8]) -> Option<f32> {
        let _ = model;
        self.battery_volts(response)
    }
    /// The droid's own fail-safe, set on every connect: it stops by itself when the link
    /// drops or drive commands stop. Firmware that does not know it may refuse it; that is
    /// fine.
    fn fail_safe(&self) -> Option<Command> {
        None
    }
    /// What droidctl sends after every (re)connect, in order.
    fn setup(&self, model: Model, opts: &SetupOptions) -> Vec<Command>;
    /// Aim mode (rolling droids): show the back light and let turning rotate the droid in
    /// place. `None` when the family cannot aim.
    fn aim_begin(&self, _model: Model) -> Option<Vec<Command>> {
        None
    }
    /// Leave aim mode: the current facing becomes heading 0; back light off.
    fn aim_end(&self, _model: Model) -> Vec<Command> {
        Vec::new()
    }
    /// The commands of `intent` on `model` ([`intent`]); a family lowers what is its own and
    /// leaves the rest to [`intent::lower_common`], which builds from the methods above.
    fn lower(
        &self,
        model: Model,
        intent: &intent::Intent,
    ) -> Result<Vec<Command>, intent::Unsupported> {
        intent::lower_common(self, model, intent)
    }
    /// Drive each track at `left`/`right` in −255..=255 (RVR's raw motors).
    fn tank(&self, _left: i16, _right: i16) -> Option<Command> {
        None
    }
    /// What `model` can stream and how fast ([`stream`]); `None` when the droid streams by
    /// itself at its own rate (Robi 42's state frames) and nothing can be chosen.
    fn stream_caps(&self, _model: Model) -> Option<stream::StreamCaps> {
        None
    }
    /// The bytes of one sample's packet on the wire with `sensors` streaming (framing
    /// included), for the BLE budget.
    fn stream_sample_bytes(&self, _sensors: stream::SensorSet) -> usize {
        0
    }
    /// The commands that make the droid stream as `plan` says (off included).
    fn streaming(&self, _model: Model, _plan: &stream::StreamPlan) -> Vec<Command> {
        Vec::new()
    }
    /// The commands that configure collision detection (and its notification) as `cfg`.
    fn collision_detection(&self, _cfg: &crate::tuning::CollisionConfig) -> Vec<Command> {
        Vec::new()
    }
    /// What a recorded drive command asked: speed 0..=255, heading, reverse; for a steering
    /// family the steering −1..=1 as well (replay shows the commands of a capture).
    fn read_drive(&self, _cmd: &Command) -> Option<RecordedDrive> {
        None
    }
    /// The dome angle a recorded command set, degrees.
    fn read_head(&self, _cmd: &Command) -> Option<f32> {
        None
    }
    /// The lights a recorded command set: the main colour, the back light.
    fn read_leds(&self, _model: Model, _cmd: &Command) -> Option<RecordedLeds> {
        None
    }
}

/// A drive command read back from a capture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordedDrive {
    pub speed: u8,
    pub heading: Heading,
    pub reverse: bool,
    /// Steering robots: −1 full left ..= 1 full right.
    pub steer: Option<f32>,
}

/// Lights read back from a capture (`None`: that light was not set by the command).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RecordedLeds {
    pub main: Option<[u8; 3]>,
    pub back: Option<u8>,
}

/// Every family, in the order they are listed and detected.
pub fn all() -> [&'static dyn Family; 3] {
    [&v2::V2, &v1::V1, &robi::Robi]
}

/// The family with this short name (`v2`, `V1`, `rsrcp`).
pub fn by_name(name: &str) -> Option<&'static dyn Family> {
    all()
        .into_iter()
        .find(|f| f.name().eq_ignore_ascii_case(name.trim()))
}

/// The short names, for messages: `v2, v1 or rsrcp`.
pub fn names() -> String {
    let names: Vec<&str> = all().iter().map(|f| f.name()).collect();
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => names.join(""),
    }
}

/// The family of the first start-of-packet byte in `bytes`, and its offset.
pub fn detect(bytes: &[u8]) -> Option<(&'static dyn Family, usize)> {
    bytes
        .iter()
        .enumerate()
        .find_map(|(i, &b)| all().into_iter().find(|f| f.sop() == b).map(|f| (f, i)))
}

/// The family of bytes seen on a link: a write to one of a family's own inputs (Robi's remote
/// control) names it; otherwise the first byte, a start of packet, does. `to` is where the
/// host wrote them, `None` for what the droid sent.
pub fn of_traffic(to: Option<crate::gatt::Endpoint>, bytes: &[u8]) -> Option<&'static dyn Family> {
    match to {
        Some(e) if e != crate::gatt::Endpoint::Api => all().into_iter().find(|f| {
            f.gatt_profile(f.representative())
                .inputs
                .iter()
                .any(|(input, _)| *input == e)
        }),
        _ => {
            let first = *bytes.first()?;
            all().into_iter().find(|f| f.sop() == first)
        }
    }
}

/// The GATT profile of `model`, from its family.
pub fn gatt_profile(model: Model) -> crate::gatt::GattProfile {
    for_model(model).gatt_profile(model)
}

/// The family whose droids have the characteristic `uuid`, and what it is to them.
pub fn role_of(
    uuid: crate::gatt::GattUuid,
) -> Option<(&'static dyn Family, crate::gatt::CharRole)> {
    all().into_iter().find_map(|f| {
        f.gatt_profile(f.representative())
            .role_of(uuid)
            .map(|r| (f, r))
    })
}

/// The family a model speaks.
pub fn for_model(model: Model) -> &'static dyn Family {
    for_protocol(model.protocol())
}

/// A drive write's speed, as the packet's own family reads its drive commands back (`None`
/// for anything else): what tests, benchmarks and fuzzing watch on a link.
pub fn drive_speed(p: &Packet) -> Option<u8> {
    drive_read(p).map(|d| d.speed)
}

/// A drive write read back whole (speed, heading, direction, steering), as
/// [`drive_speed`] reads its speed.
pub fn drive_read(p: &Packet) -> Option<RecordedDrive> {
    let (c, _, _) = p.as_command()?;
    for_protocol(p.protocol()).read_drive(&c)
}

/// The family of a protocol.
pub fn for_protocol(p: Protocol) -> &'static dyn Family {
    match p {
        Protocol::SpheroV2 => &v2::V2,
        Protocol::SpheroV1 => &v1::V1,
        Protocol::Rsrcp => &robi::Robi,
    }
}

/// A packet explained by its own family without context (no streaming masks, no request).
pub fn explain(p: &Packet) -> Explained {
    for_protocol(p.protocol()).codec().explain(p, None)
}

/// A packet of another family than the codec's: never produced by a session (it speaks one
/// family), but explained plainly rather than trusted.
pub fn explain_foreign(p: &Packet) -> Explained {
    Explained {
        kind: PacketKind::Command,
        label: "foreign packet".into(),
        known: false,
        fields: None,
        problem: Some(format!(
            "{} bytes of another protocol family",
            p.encode().len()
        )),
        error: None,
        did: None,
        seq: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detect_takes_the_first_sop() {
        let name = |b: &[u8]| detect(b).map(|(f, at)| (f.name(), at));
        assert_eq!(name(&[]), None);
        assert_eq!(name(&[1, 2, 3]), None);
        assert_eq!(name(&[1, 0x7E, 0x8D, 0xFF]), Some(("rsrcp", 1)));
        assert_eq!(name(&[0xFF, 0x8D]), Some(("v1", 0)));
        assert_eq!(name(&[0, 0, 0x8D]), Some(("v2", 2)));
    }

    #[test]
    fn families_are_found_by_name_and_protocol() {
        for f in all() {
            assert_eq!(by_name(f.name()).map(|g| g.protocol()), Some(f.protocol()));
            assert_eq!(for_protocol(f.protocol()).name(), f.name());
            assert_eq!(f.representative().protocol(), f.protocol());
        }
        assert_eq!(by_name("V1").map(|f| f.name()), Some("v1"));
        assert!(by_name("v3").is_none());
        assert_eq!(names(), "v2, v1 or rsrcp");
    }
}
