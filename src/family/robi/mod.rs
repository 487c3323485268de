//! Robi 42 behind the family seam: RSRCP state frames in, remote-control writes out.
//!
//! Robi is not a command/response droid: it never answers, it reports its state as one
//! RSRCP frame per BLE notification (`droid-facts.md` §5), and it is driven by writing two
//! one-byte characteristics, velocity and steering. So its "commands" are
//! [`RobiControl`]s, written to [`Endpoint::Velocity`] and [`Endpoint::Steering`], and its
//! capabilities are few: drive forward and steer; no reverse, heading, dome, legs, lights,
//! sounds or battery reading.

pub mod gatt;
pub mod named;
pub mod read;

use super::types::{RobiControl, RobiPacket};
use super::{
    Codec, Command, Explained, Family, Incoming, Key, Packet, PacketKind, ReadOption, ReadOptions,
    Reader,
};
use crate::family::setup::SetupOptions;
use crate::gatt::Endpoint;
use crate::model::{Model, Protocol};
use crate::protocol::decode::ErrorKind;
use crate::protocol::notify::Notification;
use crate::protocol::rsrcp::{self, Item};
use crate::protocol::value::{Fields, Value};
use crate::units::Heading;

/// The Robi 42 family.
pub struct Robi;

/// Steering byte for a turn in −1 (full left) ..= 1 (full right); 0 is straight (128).
///
/// Fix: this was 128 + 127·turn, so full left was byte 1, which the firmware reads as
/// s' = −0.992: the inner wheel kept turning (235 Hz at full speed) where full right stops it,
/// and every left turn was a little weaker than the same right turn. The codec's
/// [`rsrcp::steering_byte`] maps −1..1 onto the whole 0..=255 (full left 0, full right 255,
/// mirror images about the firmware's 127.5); a non-finite turn steers straight.
pub fn steering_for(turn: f32) -> u8 {
    if turn.is_finite() {
        rsrcp::steering_byte(turn)
    } else {
        rsrcp::STEERING_STRAIGHT
    }
}

/// A Robi connection's codec. Over BLE every notification is exactly one frame (or, first,
/// the handshake the link read), so each `feed` is decoded as one value, not as a stream.
#[derive(Default)]
pub struct RobiCodec;

fn control_of(c: &Command) -> RobiControl {
    match c {
        Command::Robi(c) => *c,
        other => {
            tracing::error!(command = %other.name(), "a non-Robi command reached the Robi codec");
            RobiControl::STOP
        }
    }
}

/// Explain Robi traffic for the log.
pub fn explain(p: &RobiPacket) -> Explained {
    let (kind, label, fields) = match p {
        RobiPacket::Control(c) => (
            PacketKind::Command,
            "remote-control".to_string(),
            vec![
                ("velocity", Value::Int(c.velocity as i64)),
                ("steering", Value::Int(c.steering as i64)),
            ] as Fields,
        ),
        RobiPacket::Item(Item::Handshake(h)) => (
            PacketKind::Notification,
            "handshake".to_string(),
            h.fields(),
        ),
        RobiPacket::Item(Item::Frame(f)) => (
            PacketKind::Notification,
            format!("frame {}", f.frame_id),
            f.fields(),
        ),
    };
    Explained {
        kind,
        label,
        known: true,
        fields: Some(fields),
        problem: None,
        error: None,
        did: None,
        seq: None,
    }
}

impl Codec for RobiCodec {
    fn protocol(&self) -> Protocol {
        Protocol::Rsrcp
    }

    /// Nothing is ever answered; the key is unused.
    fn key(&self, _c: &Command, seq: u8) -> Key {
        (0, 0, seq)
    }

    fn encode(&mut self, c: &Command, _seq: u8, _want_response: bool) -> (Vec<u8>, Packet) {
        let c = control_of(c);
        (
            vec![c.velocity, c.steering],
            Packet::Robi(RobiPacket::Control(c)),
        )
    }

    /// Velocity first: a stop (velocity 0) takes effect before the steering changes.
    fn encode_writes(
        &mut self,
        c: &Command,
        _seq: u8,
        _want_response: bool,
    ) -> (Vec<(Endpoint, Vec<u8>)>, Packet) {
        let c = control_of(c);
        (
            vec![
                (Endpoint::Velocity, vec![c.velocity]),
                (Endpoint::Steering, vec![c.steering]),
            ],
            Packet::Robi(RobiPacket::Control(c)),
        )
    }

    fn answers(&self) -> bool {
        false
    }

    fn feed(&mut self, bytes: &[u8], out: &mut Vec<Incoming>) {
        out.push(match read::decode_value(bytes) {
            Ok(item) => {
                let n = match &item {
                    Item::Handshake(h) => Notification::RobiHandshake(*h),
                    Item::Frame(f) => Notification::RobiFrame(f.clone()),
                };
                Incoming::Async {
                    notifications: vec![Ok(n)],
                    packet: Packet::Robi(RobiPacket::Item(item)),
                }
            }
            Err(e) => Incoming::Error(read::seam_error(e)),
        });
    }

    fn explain(&self, p: &Packet, _request: Option<&Command>) -> Explained {
        match p {
            Packet::Robi(p) => explain(p),
            other => super::explain_foreign(other),
        }
    }
}

impl Family for Robi {
    fn protocol(&self) -> Protocol {
        Protocol::Rsrcp
    }

    fn name(&self) -> &'static str {
        "rsrcp"
    }

    fn display_name(&self) -> &'static str {
        "RSRCP"
    }

    fn sop(&self) -> u8 {
        rsrcp::SOP
    }

    fn representative(&self) -> Model {
        Model::first_speaking(self.protocol())
    }

    fn error_kinds(&self) -> &'static [ErrorKind] {
        &rsrcp::ERROR_KINDS
    }

    /// RSRCP frames say what they carry: nothing to be told.
    fn read_options(&self) -> &'static [ReadOption] {
        &[]
    }

    fn reader(&self, opts: &ReadOptions) -> Result<Box<dyn Reader>, super::error::ReadError> {
        Ok(Box::new(read::RobiReader::new(opts)))
    }

    fn side_reader(&self, side: super::Side, whole_values: bool) -> Box<dyn Reader> {
        let opts = ReadOptions {
            side: Some(side),
            whole_values,
            ..ReadOptions::default()
        };
        Box::new(read::RobiReader::new(&opts))
    }

    fn gatt_profile(&self, model: Model) -> crate::gatt::GattProfile {
        gatt::profile(model)
    }

    fn encode_named(
        &self,
        name: &str,
        params: Vec<(String, String)>,
    ) -> Result<Vec<u8>, super::error::NamedError> {
        named::encode(name, params)
    }

    fn encode_names(&self) -> Vec<(String, &'static str)> {
        named::NAMES
            .iter()
            .map(|&(n, what)| (n.to_string(), what))
            .collect()
    }

    fn list(&self, filter: Option<&str>, out: &mut dyn std::io::Write) -> std::io::Result<usize> {
        named::list(filter, out)
    }

    fn codec(&self) -> Box<dyn Codec> {
        Box::new(RobiCodec)
    }

    /// Robi needs no wake; the link's start confirmation starts the frames.
    fn wake(&self) -> Option<Command> {
        None
    }

    /// Robi has no ping; the nearest harmless write is "stand still".
    fn ping(&self) -> Command {
        Command::Robi(RobiControl::STOP)
    }

    /// The remote control as it was last written: the robot goes on doing what it does.
    fn keepalive(&self, last_drive: Option<&Command>) -> Command {
        last_drive
            .cloned()
            .unwrap_or(Command::Robi(RobiControl::STOP))
    }

    /// Forward at `speed`, straight: Robi has no heading to steer to. The controller uses
    /// [`Family::steer`] instead; this serves stops and scripts.
    fn drive(&self, speed: u8, _heading: Heading, reverse: bool) -> Command {
        Command::Robi(RobiControl {
            velocity: if reverse { 0 } else { speed },
            steering: rsrcp::STEERING_STRAIGHT,
        })
    }

    fn is_drive(&self, c: &Command) -> bool {
        matches!(c, Command::Robi(_))
    }

    /// Velocity 0 and steering straight.
    fn stop_after(&self, _last: Option<&Command>) -> Command {
        Command::Robi(RobiControl::STOP)
    }

    fn steers(&self) -> bool {
        true
    }

    fn steer(&self, speed: u8, turn: f32) -> Option<Command> {
        Some(Command::Robi(RobiControl {
            velocity: speed,
            steering: steering_for(turn),
        }))
    }

    fn can_reverse(&self) -> bool {
        false
    }

    /// Nothing to set up: the link's handshake (read, start confirmation) is all.
    fn setup(&self, _model: Model, _opts: &SetupOptions) -> Vec<Command> {
        Vec::new()
    }

    /// The remote control as written: velocity, and the steering byte back to −1..=1
    /// (the firmware's s' = 2(s/255 − 0.5), `droid-facts.md` §5).
    fn read_drive(&self, c: &Command) -> Option<super::RecordedDrive> {
        let Command::Robi(c) = c else { return None };
        Some(super::RecordedDrive {
            speed: c.velocity,
            heading: Heading::default(),
            reverse: false,
            steer: Some(2.0 * (c.steering as f32 / 255.0 - 0.5)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steering_bytes() {
        assert_eq!(steering_for(0.0), 128);
        assert_eq!(steering_for(-1.0), 0);
        assert_eq!(steering_for(f32::INFINITY), 128);
        // Mirror images about the firmware's middle, 127.5.
        assert_eq!(steering_for(0.6), 204);
        assert_eq!(steering_for(-0.6), 51);
        assert_eq!(steering_for(1.0), 255);
        assert_eq!(steering_for(5.0), 255);
        assert_eq!(steering_for(f32::NAN), 128);
    }

    #[test]
    fn a_drive_is_a_velocity_then_a_steering_write() {
        let mut c = RobiCodec;
        let cmd = Robi.steer(200, -0.5).unwrap();
        let (writes, _) = c.encode_writes(&cmd, 0, true);
        assert_eq!(
            writes,
            [
                (Endpoint::Velocity, vec![200]),
                (Endpoint::Steering, vec![64])
            ]
        );
        assert!(!c.answers());
        assert!(Robi.stop_after(Some(&cmd)).is_stop());
        assert_eq!(
            Robi.stop_after(Some(&cmd)),
            Command::Robi(RobiControl {
                velocity: 0,
                steering: 128
            })
        );
    }

    #[test]
    fn keepalive_repeats_the_remote_control_as_it_was() {
        let moving = Robi.steer(120, 0.3).unwrap();
        assert_eq!(Robi.keepalive(Some(&moving)), moving);
        assert!(Robi.keepalive(None).is_stop());
    }

    #[test]
    fn notifications_decode_one_value_each() {
        let mut c = RobiCodec;
        let mut out = Vec::new();
        let hs = rsrcp::Handshake {
            version: 1,
            msdt_ms: 10,
        };
        c.feed(&hs.encode(), &mut out);
        let f = rsrcp::Frame::new(0x7E7F7E)
            .with_motors(1.25, -0.5)
            .with_poti(0x7E)
            .with_buttons(rsrcp::Buttons::CENTER);
        c.feed(&f.encode(), &mut out);
        c.feed(&[0x7E, 0, 0], &mut out);
        assert!(matches!(
            &out[0],
            Incoming::Async { notifications, .. } if notifications == &[Ok(Notification::RobiHandshake(hs))]
        ));
        assert!(matches!(
            &out[1],
            Incoming::Async { notifications, .. } if notifications == &[Ok(Notification::RobiFrame(f.clone()))]
        ));
        assert!(matches!(&out[2], Incoming::Error(_)));
    }
}
