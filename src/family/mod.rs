//! The seam between protocol families (Sphero v2, Sphero v1, later RSRCP).
//!
//! The session, packet log, telemetry, mission runner and UI serve every family through
//! this one interface; the model picks the family ([`for_model`]). A family supplies:
//! - a [`Codec`]: framing and a streaming decoder, how a response is matched to its
//!   request, and how its asynchronous messages map onto the common [`Notification`]s;
//! - the commands behind each capability (drive, stop, dome, stance, LEDs, aim, sleep …),
//!   built from its own catalogue, or `None` when the family has no such thing.
//!
//! Everything here is sans-IO: no clocks, no tokio.

pub mod robi;
pub mod types;
pub mod v1;
pub mod v2;

pub use types::{
    Command, DecodeError, DroidError, Explained, Incoming, Key, Packet, PacketKind, RobiControl,
    RobiPacket,
};

use crate::model::{Model, Protocol};
use crate::protocol::wire::LegAction;
use crate::script::Action;
use crate::setup::SetupOptions;
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
    ) -> (Vec<(crate::link::Endpoint, Vec<u8>)>, Packet) {
        let (wire, packet) = self.encode(cmd, seq, want_response);
        (vec![(crate::link::Endpoint::Api, wire)], packet)
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

/// One protocol family: its codec and the commands behind each capability.
pub trait Family: Sync {
    fn protocol(&self) -> Protocol;
    fn codec(&self) -> Box<dyn Codec>;
    /// The command that wakes a droid from soft sleep, first after every connect.
    fn wake(&self) -> Option<Command>;
    /// Cheap activity that keeps the droid awake.
    fn ping(&self) -> Command;
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
    fn animation(&self, _id: u16) -> Option<Command> {
        None
    }
    fn sound(&self, _id: u16) -> Option<Command> {
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
}

/// The family a model speaks.
pub fn for_model(model: Model) -> &'static dyn Family {
    for_protocol(model.protocol())
}

/// The family of a protocol.
pub fn for_protocol(p: Protocol) -> &'static dyn Family {
    match p {
        Protocol::SpheroV2 => &v2::V2,
        Protocol::SpheroV1 => &v1::V1,
        Protocol::Rsrcp => &robi::Robi,
    }
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
