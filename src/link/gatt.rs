//! Each model's GATT profile as data (`droid-facts.md` §1, §4, §5): which characteristic
//! commands are written to, which ones notify, and the handshake that unlocks the droid.
//!
//! Keeping this as data means a new model is a new table entry, not new link code: the BLE link
//! ([`crate::link::ble::BleLink`]) runs whatever profile it is given.

use crate::model::{Model, Protocol};
use std::fmt;
use std::time::Duration;

/// A 128-bit GATT UUID.
///
/// Our own type rather than the `uuid` crate's so profiles can be `const`-built and compared
/// without an extra dependency; the BLE backend converts at its edge with [`GattUuid::as_u128`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GattUuid(u128);

/// The Bluetooth base UUID `0000xxxx-0000-1000-8000-00805f9b34fb` that 16-bit UUIDs expand into.
const BLUETOOTH_BASE: u128 = 0x0000_0000_0000_1000_8000_0080_5f9b_34fb;

impl GattUuid {
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
/// matching on the characteristic alone is then the honest choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CharRef {
    pub service: Option<GattUuid>,
    pub characteristic: GattUuid,
}

impl CharRef {
    pub const fn new(service: GattUuid, characteristic: GattUuid) -> Self {
        CharRef {
            service: Some(service),
            characteristic,
        }
    }

    pub const fn any_service(characteristic: GattUuid) -> Self {
        CharRef {
            service: None,
            characteristic,
        }
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
    /// Write these bytes (with response, so a refusal is noticed).
    Write { ch: CharRef, bytes: Vec<u8> },
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
    pub inputs: Vec<(crate::link::Endpoint, CharRef)>,
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

// Sphero API v2 (R2-D2, R2-Q5, BB-9E): `droid-facts.md` §1.
const fn sphero_v2(short: u32) -> GattUuid {
    // 0000xxxx-574f-4f20-5370-6865726f2121 ("WOO Sphero!!")
    GattUuid((short as u128) << 96 | 0x0000_0000_574f_4f20_5370_6865_726f_2121)
}
pub const V2_SERVICE: GattUuid = sphero_v2(0x0001_0001);
pub const V2_API: GattUuid = sphero_v2(0x0001_0002);
pub const V2_ANTI_DOS: GattUuid = sphero_v2(0x0002_0005);
/// What the v2 droids want written to the anti-DoS characteristic before they answer.
pub const V2_UNLOCK: &[u8] = b"usetheforce...band";

// Sphero API v1 over BLE (BB-8, SPRK+, Ollie): `droid-facts.md` §4.
const fn sphero_v1(short: u16) -> GattUuid {
    // 22bb746f-XXXX-7554-2d6f-726568705327
    GattUuid(0x22bb_746f_0000_7554_2d6f_7265_6870_5327 | (short as u128) << 80)
}
pub const V1_RADIO_SERVICE: GattUuid = sphero_v1(0x2bb0);
pub const V1_ANTI_DOS: GattUuid = sphero_v1(0x2bbd);
pub const V1_TX_POWER: GattUuid = sphero_v1(0x2bb2);
pub const V1_WAKE: GattUuid = sphero_v1(0x2bbf);
pub const V1_CONTROL_SERVICE: GattUuid = sphero_v1(0x2ba0);
pub const V1_COMMANDS: GattUuid = sphero_v1(0x2ba1);
pub const V1_RESPONSES: GattUuid = sphero_v1(0x2ba6);

// Robi 42: `droid-facts.md` §5.
pub const ROBI_RSRC_SERVICE: GattUuid = GattUuid::from_u16(0x2579);
pub const ROBI_FRAMES: GattUuid = GattUuid::from_u16(0x8765);
pub const ROBI_HANDSHAKE: GattUuid = GattUuid::from_u16(0x4744);
pub const ROBI_START: GattUuid = GattUuid::from_u16(0x4234);
pub const ROBI_RC_SERVICE: GattUuid = GattUuid::from_u16(0xBA73);
pub const ROBI_VELOCITY: GattUuid = GattUuid::from_u16(0x6B2F);
pub const ROBI_STEERING: GattUuid = GattUuid::from_u16(0x3F4A);

impl GattProfile {
    /// The profile of `model`, with its reference write pacing.
    pub fn for_model(model: Model) -> GattProfile {
        let pacing = model.write_pacing();
        match model.protocol() {
            Protocol::SpheroV2 => {
                let api = CharRef::new(V2_SERVICE, V2_API);
                GattProfile {
                    service: V2_SERVICE,
                    write: api,
                    notify: vec![api],
                    inputs: Vec::new(),
                    handshake: vec![HandshakeStep::Write {
                        ch: CharRef::any_service(V2_ANTI_DOS),
                        bytes: V2_UNLOCK.to_vec(),
                    }],
                    chunk_size: ATT_PAYLOAD,
                    pacing,
                    write_with_response: true,
                }
            }
            Protocol::SpheroV1 => {
                // ASCII "011i3" unlocks, then TX power 7 and wake 1 are single bytes.
                let radio = |c, bytes: &[u8]| HandshakeStep::Write {
                    ch: CharRef::new(V1_RADIO_SERVICE, c),
                    bytes: bytes.to_vec(),
                };
                let handshake = vec![
                    radio(V1_ANTI_DOS, b"011i3"),
                    radio(V1_TX_POWER, &[0x07]),
                    radio(V1_WAKE, &[0x01]),
                ];
                GattProfile {
                    service: V1_CONTROL_SERVICE,
                    write: CharRef::new(V1_CONTROL_SERVICE, V1_COMMANDS),
                    inputs: Vec::new(),
                    notify: vec![CharRef::new(V1_CONTROL_SERVICE, V1_RESPONSES)],
                    handshake,
                    chunk_size: ATT_PAYLOAD,
                    pacing,
                    write_with_response: true,
                }
            }
            Protocol::Rsrcp => GattProfile {
                service: ROBI_RSRC_SERVICE,
                // The RSRC service has no command channel; the remote-control characteristics
                // (velocity, steering) take one byte each and are the only things we write.
                write: CharRef::new(ROBI_RC_SERVICE, ROBI_VELOCITY),
                inputs: vec![
                    (
                        crate::link::Endpoint::Velocity,
                        CharRef::new(ROBI_RC_SERVICE, ROBI_VELOCITY),
                    ),
                    (
                        crate::link::Endpoint::Steering,
                        CharRef::new(ROBI_RC_SERVICE, ROBI_STEERING),
                    ),
                ],
                notify: vec![CharRef::new(ROBI_RSRC_SERVICE, ROBI_FRAMES)],
                handshake: vec![
                    HandshakeStep::Read {
                        ch: CharRef::new(ROBI_RSRC_SERVICE, ROBI_HANDSHAKE),
                        expect_len: Some(5),
                    },
                    HandshakeStep::Write {
                        ch: CharRef::new(ROBI_RSRC_SERVICE, ROBI_START),
                        bytes: vec![0x01],
                    },
                ],
                chunk_size: ATT_PAYLOAD,
                pacing,
                write_with_response: true,
            },
        }
    }

    /// The characteristic behind an endpoint.
    pub fn endpoint(&self, to: crate::link::Endpoint) -> Option<CharRef> {
        match to {
            crate::link::Endpoint::Api => Some(self.write),
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
        assert_eq!(
            V2_SERVICE.to_string(),
            "00010001-574f-4f20-5370-6865726f2121"
        );
        assert_eq!(V2_API.to_string(), "00010002-574f-4f20-5370-6865726f2121");
        assert_eq!(
            V2_ANTI_DOS.to_string(),
            "00020005-574f-4f20-5370-6865726f2121"
        );
        assert_eq!(
            V1_ANTI_DOS.to_string(),
            "22bb746f-2bbd-7554-2d6f-726568705327"
        );
        assert_eq!(
            V1_RESPONSES.to_string(),
            "22bb746f-2ba6-7554-2d6f-726568705327"
        );
        assert_eq!(
            ROBI_FRAMES.to_string(),
            "00008765-0000-1000-8000-00805f9b34fb"
        );
        assert_eq!(ROBI_FRAMES.as_u16(), Some(0x8765));
        assert_eq!(V2_API.as_u16(), None);
    }

    #[test]
    fn v1_handshake_bytes() {
        let p = GattProfile::for_model(Model::BB8);
        let writes: Vec<(GattUuid, Vec<u8>)> = p
            .handshake
            .iter()
            .map(|s| match s {
                HandshakeStep::Write { ch, bytes } => (ch.characteristic, bytes.clone()),
                HandshakeStep::Read { ch, .. } => (ch.characteristic, vec![]),
            })
            .collect();
        assert_eq!(
            writes,
            [
                (V1_ANTI_DOS, b"011i3".to_vec()),
                (V1_TX_POWER, vec![7]),
                (V1_WAKE, vec![1]),
            ]
        );
        assert_eq!(p.pacing, Duration::from_millis(60));
    }

    #[test]
    fn char_matching() {
        let any = CharRef::any_service(V2_ANTI_DOS);
        assert!(any.matches(V2_SERVICE, V2_ANTI_DOS));
        assert!(any.matches(sphero_v2(0x0002_0001), V2_ANTI_DOS));
        let api = CharRef::new(V2_SERVICE, V2_API);
        assert!(!api.matches(V1_CONTROL_SERVICE, V2_API));
    }
}
