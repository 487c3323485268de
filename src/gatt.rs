//! GATT as data: UUIDs, characteristics, handshakes, the profile a link runs, and where a
//! write goes ([`Endpoint`]). A leaf: the families describe their droids' profiles with these
//! types ([`crate::family::Family::gatt_profile`]), the links run whatever profile they are
//! given, and the simulators serve one.

use std::fmt;
use std::time::Duration;

/// Where a write goes. Sphero droids take everything on one command channel; Robi 42 is
/// driven through two one-byte remote-control inputs beside its (read-only) state frames.
/// The droid's GATT profile maps each endpoint to a characteristic.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Endpoint {
    /// The command channel (Sphero API v1/v2).
    Api,
    /// Robi 42 remote control: velocity, 0..=255 = 0..1, forward only.
    Velocity,
    /// Robi 42 remote control: steering, 0..=255, 128 ≈ straight.
    Steering,
}

impl Endpoint {
    pub const ALL: [Endpoint; 3] = [Endpoint::Api, Endpoint::Velocity, Endpoint::Steering];

    pub fn name(self) -> &'static str {
        match self {
            Endpoint::Api => "api",
            Endpoint::Velocity => "velocity",
            Endpoint::Steering => "steering",
        }
    }
}

/// A 128-bit GATT UUID.
///
/// Our own type rather than the `uuid` crate's so profiles can be `const`-built and compared
/// without an extra dependency; the BLE backend converts at its edge with [`GattUuid::as_u128`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GattUuid(u128);

/// The Bluetooth base UUID `0000xxxx-0000-1000-8000-00805f9b34fb` that 16-bit UUIDs expand into.
const BLUETOOTH_BASE: u128 = 0x0000_0000_0000_1000_8000_0080_5f9b_34fb;

impl GattUuid {
    /// A UUID as people and clients write it: `00010002-574f-4f20-5370-6865726f2121` (any
    /// case), the same without hyphens, or a 16-bit `2a00` / `0x2A00` on the Bluetooth base.
    pub fn parse(s: &str) -> Option<GattUuid> {
        let t = s.trim();
        let t = t
            .strip_prefix("0x")
            .or_else(|| t.strip_prefix("0X"))
            .unwrap_or(t);
        if t.len() == 4 && t.chars().all(|c| c.is_ascii_hexdigit()) {
            return u16::from_str_radix(t, 16).ok().map(GattUuid::from_u16);
        }
        let hex: String = if t.len() == 36 {
            let b = t.as_bytes();
            if [8, 13, 18, 23].iter().any(|&i| b[i] != b'-') {
                return None;
            }
            t.chars().filter(|c| *c != '-').collect()
        } else {
            t.to_string()
        };
        if hex.len() != 32 || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
            return None;
        }
        u128::from_str_radix(&hex, 16).ok().map(GattUuid::from_u128)
    }

    pub const fn from_u128(v: u128) -> Self {
        GattUuid(v)
    }

    /// A 16-bit UUID (Robi 42 uses custom ones) expanded on the Bluetooth base UUID, as BlueZ
    /// reports them.
    pub const fn from_u16(short: u16) -> Self {
        GattUuid(BLUETOOTH_BASE | ((short as u128) << 96))
    }

    pub const fn as_u128(self) -> u128 {
        self.0
    }

    /// The 16-bit form, if this is a UUID on the Bluetooth base.
    pub const fn as_u16(self) -> Option<u16> {
        const MASK: u128 = 0xffff_0000_ffff_ffff_ffff_ffff_ffff_ffff;
        if self.0 & MASK == BLUETOOTH_BASE {
            Some((self.0 >> 96) as u16)
        } else {
            None
        }
    }
}

impl fmt::Display for GattUuid {
    /// Hyphenated lower-case, the way BlueZ and `bluetoothctl` print UUIDs.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        write!(
            f,
            "{:08x}-{:04x}-{:04x}-{:04x}-{:012x}",
            (v >> 96) as u32,
            (v >> 80) as u16,
            (v >> 64) as u16,
            (v >> 48) as u16,
            v & 0xffff_ffff_ffff
        )
    }
}

/// One characteristic, and the service it lives in when we know it.
///
/// `service` is `None` when the sources name only the characteristic (the v2 anti-DoS one):
/// matching on the characteristic alone is then the honest choice. `usual_service` is where
/// the droids seen so far keep such a characteristic: what a simulated droid offers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CharRef {
    pub service: Option<GattUuid>,
    pub characteristic: GattUuid,
    pub usual_service: Option<GattUuid>,
}

impl CharRef {
    pub const fn new(service: GattUuid, characteristic: GattUuid) -> Self {
        CharRef {
            service: Some(service),
            characteristic,
            usual_service: None,
        }
    }

    /// A characteristic matched in any service; `usual` is where droids keep it.
    pub const fn any_service(characteristic: GattUuid, usual: GattUuid) -> Self {
        CharRef {
            service: None,
            characteristic,
            usual_service: Some(usual),
        }
    }

    /// The service a simulated droid offers it in (`default` when the profile says nothing).
    pub fn home(&self, default: GattUuid) -> GattUuid {
        self.service.or(self.usual_service).unwrap_or(default)
    }

    /// Whether a discovered (service, characteristic) pair is this one.
    pub fn matches(&self, service: GattUuid, characteristic: GattUuid) -> bool {
        self.characteristic == characteristic && self.service.is_none_or(|s| s == service)
    }
}

impl fmt::Display for CharRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.service {
            Some(s) => write!(f, "{} (service {s})", self.characteristic),
            None => write!(f, "{}", self.characteristic),
        }
    }
}

/// One step of a connection handshake, run in order after service discovery.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HandshakeStep {
    /// Write these bytes (with response, so a refusal is noticed); `what` names the step
    /// for people ("v2 anti-DoS unlock").
    Write {
        ch: CharRef,
        bytes: Vec<u8>,
        what: &'static str,
    },
    /// Read the characteristic. `expect_len` is what the sources say comes back; a different
    /// length is logged, not fatal, because those figures come from a single source.
    Read {
        ch: CharRef,
        expect_len: Option<usize>,
    },
}

impl HandshakeStep {
    pub fn ch(&self) -> CharRef {
        match self {
            HandshakeStep::Write { ch, .. } | HandshakeStep::Read { ch, .. } => *ch,
        }
    }
}

/// Everything the BLE link needs to know about one model.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GattProfile {
    /// The main service, for scan filters and error messages.
    pub service: GattUuid,
    /// Where commands are written.
    pub write: CharRef,
    /// Other inputs written by endpoint (Robi 42's remote control).
    pub inputs: Vec<(Endpoint, CharRef)>,
    /// Subscribed after the handshake; their values form the incoming byte stream.
    pub notify: Vec<CharRef>,
    /// Run in order after service discovery and before subscribing.
    pub handshake: Vec<HandshakeStep>,
    /// Largest single write: the 20-byte ATT payload of the default MTU.
    pub chunk_size: usize,
    /// Minimum time between writes (`Model::write_pacing`).
    pub pacing: Duration,
    /// Write commands with response: the droid acknowledges each write, so a lost link shows
    /// up as a failed write instead of silence.
    pub write_with_response: bool,
}

/// The ATT payload with the default MTU of 23.
pub const ATT_PAYLOAD: usize = 20;

/// What a characteristic of a profile is to someone reading the traffic (a phone's log, a
/// virtual droid's trace).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CharRole {
    /// A command channel: writes are the host's packets, notifications the droid's.
    Channel,
    /// Read while connecting (Robi's handshake): the value read is the droid's.
    ReadValue,
    /// A one-byte input (Robi's velocity and steering).
    Input(Endpoint),
    /// A connection-setup characteristic (anti-DoS unlock, wake, start), by its step's name.
    Setup(&'static str),
}

impl GattProfile {
    /// The role of `uuid` in this profile: inputs first (Robi's velocity input is also
    /// where its "commands" go), then the command and notification channels, then the
    /// handshake's steps.
    pub fn role_of(&self, uuid: GattUuid) -> Option<CharRole> {
        if let Some((e, _)) = self.inputs.iter().find(|(_, c)| c.characteristic == uuid) {
            return Some(CharRole::Input(*e));
        }
        if self.write.characteristic == uuid || self.notify.iter().any(|c| c.characteristic == uuid)
        {
            return Some(CharRole::Channel);
        }
        self.handshake
            .iter()
            .find(|s| s.ch().characteristic == uuid)
            .map(|s| match s {
                HandshakeStep::Write { what, .. } => CharRole::Setup(what),
                HandshakeStep::Read { .. } => CharRole::ReadValue,
            })
    }

    /// The characteristic API packets are written to; `None` for a droid driven only by
    /// one-byte inputs (Robi 42), whose writes are not packets.
    pub fn api(&self) -> Option<GattUuid> {
        self.inputs.is_empty().then_some(self.write.characteristic)
    }

    /// The characteristic behind an endpoint.
    pub fn endpoint(&self, to: Endpoint) -> Option<CharRef> {
        match to {
            Endpoint::Api => Some(self.write),
            other => self
                .inputs
                .iter()
                .find(|(e, _)| *e == other)
                .map(|(_, c)| *c),
        }
    }

    /// Every characteristic the profile touches, for checking them after discovery.
    pub fn characteristics(&self) -> Vec<CharRef> {
        let mut all = vec![self.write];
        all.extend(self.inputs.iter().map(|(_, c)| *c));
        all.extend(self.notify.iter().copied());
        all.extend(self.handshake.iter().map(HandshakeStep::ch));
        all.dedup();
        all
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uuids_print_like_bluez() {
        let u = GattUuid::from_u128(0x0001_0002_574f_4f20_5370_6865_726f_2121);
        assert_eq!(u.to_string(), "00010002-574f-4f20-5370-6865726f2121");
        assert_eq!(u.as_u16(), None);
        let short = GattUuid::from_u16(0x8765);
        assert_eq!(short.to_string(), "00008765-0000-1000-8000-00805f9b34fb");
        assert_eq!(short.as_u16(), Some(0x8765));
    }

    #[test]
    fn uuids_parse_in_every_form() {
        let api = GattUuid::from_u128(0x0001_0002_574f_4f20_5370_6865_726f_2121);
        let frames = GattUuid::from_u16(0x8765);
        let p = GattUuid::parse;
        assert_eq!(p("00010002-574f-4f20-5370-6865726f2121"), Some(api));
        assert_eq!(p("00010002-574F-4F20-5370-6865726F2121"), Some(api));
        assert_eq!(p("00010002574f4f2053706865726f2121"), Some(api));
        assert_eq!(p("8765"), Some(frames));
        assert_eq!(p("0x8765"), Some(frames));
        assert_eq!(p("00010002-574f-4f20-5370-6865726f212"), None);
        assert_eq!(p("00010002+574f-4f20-5370-6865726f2121"), None);
        assert_eq!(p("zz"), None);
        assert_eq!(p("é"), None);
    }

    #[test]
    fn char_matching() {
        let (s1, s2, c) = (
            GattUuid::from_u16(1),
            GattUuid::from_u16(2),
            GattUuid::from_u16(3),
        );
        let any = CharRef::any_service(c, s2);
        assert!(any.matches(s1, c) && any.matches(s2, c));
        assert_eq!(any.home(s1), s2);
        let fixed = CharRef::new(s1, c);
        assert!(!fixed.matches(s2, c));
        assert_eq!(fixed.home(s2), s1);
    }

    #[test]
    fn roles_come_from_the_profile() {
        let u = GattUuid::from_u16;
        let p = GattProfile {
            service: u(1),
            write: CharRef::new(u(1), u(2)),
            inputs: vec![(Endpoint::Velocity, CharRef::new(u(1), u(2)))],
            notify: vec![CharRef::new(u(1), u(3))],
            handshake: vec![
                HandshakeStep::Write {
                    ch: CharRef::new(u(1), u(4)),
                    bytes: vec![1],
                    what: "start",
                },
                HandshakeStep::Read {
                    ch: CharRef::new(u(1), u(5)),
                    expect_len: None,
                },
            ],
            chunk_size: ATT_PAYLOAD,
            pacing: Duration::from_millis(20),
            write_with_response: true,
        };
        assert_eq!(p.role_of(u(2)), Some(CharRole::Input(Endpoint::Velocity)));
        assert_eq!(p.role_of(u(3)), Some(CharRole::Channel));
        assert_eq!(p.role_of(u(4)), Some(CharRole::Setup("start")));
        assert_eq!(p.role_of(u(5)), Some(CharRole::ReadValue));
        assert_eq!(p.role_of(u(9)), None);
        assert_eq!(p.api(), None);
    }
}
