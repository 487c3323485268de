//! The GATT profile of the Robi 42 (`droid-facts.md` §5): the RSRC service's frames
//! (notified after the handshake is read and the start confirmed) and the remote-control
//! service's two one-byte inputs, velocity and steering. 16-bit custom UUIDs.

use crate::gatt::{ATT_PAYLOAD, CharRef, Endpoint, GattProfile, GattUuid, HandshakeStep};
use crate::model::Model;

pub const ROBI_RSRC_SERVICE: GattUuid = GattUuid::from_u16(0x2579);
pub const ROBI_FRAMES: GattUuid = GattUuid::from_u16(0x8765);
pub const ROBI_HANDSHAKE: GattUuid = GattUuid::from_u16(0x4744);
pub const ROBI_START: GattUuid = GattUuid::from_u16(0x4234);
pub const ROBI_RC_SERVICE: GattUuid = GattUuid::from_u16(0xBA73);
pub const ROBI_VELOCITY: GattUuid = GattUuid::from_u16(0x6B2F);
pub const ROBI_STEERING: GattUuid = GattUuid::from_u16(0x3F4A);

/// The Robi 42's profile.
pub fn profile(model: Model) -> GattProfile {
    GattProfile {
        service: ROBI_RSRC_SERVICE,
        // The RSRC service has no command channel; the remote-control characteristics
        // (velocity, steering) take one byte each and are the only things we write.
        write: CharRef::new(ROBI_RC_SERVICE, ROBI_VELOCITY),
        inputs: vec![
            (
                Endpoint::Velocity,
                CharRef::new(ROBI_RC_SERVICE, ROBI_VELOCITY),
            ),
            (
                Endpoint::Steering,
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
                what: "Robi start",
            },
        ],
        chunk_size: ATT_PAYLOAD,
        pacing: model.write_pacing(),
        write_with_response: true,
    }
}
