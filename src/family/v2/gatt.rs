//! The GATT profile of Sphero API v2 droids (`droid-facts.md` §1): one service, one
//! characteristic for commands and notifications, and the anti-DoS unlock written before the
//! droid answers.

use crate::gatt::{ATT_PAYLOAD, CharRef, GattProfile, GattUuid, HandshakeStep};
use crate::model::{Caps, Model};

/// `0000xxxx-574f-4f20-5370-6865726f2121` ("WOO Sphero!!").
const fn sphero_v2(short: u32) -> GattUuid {
    GattUuid::from_u128((short as u128) << 96 | 0x0000_0000_574f_4f20_5370_6865_726f_2121)
}

pub const V2_SERVICE: GattUuid = sphero_v2(0x0001_0001);
pub const V2_API: GattUuid = sphero_v2(0x0001_0002);
pub const V2_ANTI_DOS: GattUuid = sphero_v2(0x0002_0005);
/// The service the anti-DoS characteristic sits in on the droids. The sources name only the
/// characteristic, so the link matches it in any service; a simulated droid offers it here.
pub const V2_ANTI_DOS_SERVICE: GattUuid = sphero_v2(0x0002_0001);
/// What the v2 droids want written to the anti-DoS characteristic before they answer.
pub const V2_UNLOCK: &[u8] = b"usetheforce...band";

/// The profile of a v2 model, with its reference write pacing.
pub fn profile(model: Model) -> GattProfile {
    let api = CharRef::new(V2_SERVICE, V2_API);
    GattProfile {
        service: V2_SERVICE,
        write: api,
        notify: vec![api],
        inputs: Vec::new(),
        // RVR takes commands without the unlock (spherov2.py's `toy/rvr.py` writes none;
        // `droid-facts.md` §6); BOLT and Mini want it like R2-D2.
        handshake: if model.has(Caps::NO_UNLOCK) {
            Vec::new()
        } else {
            vec![HandshakeStep::Write {
                ch: CharRef::any_service(V2_ANTI_DOS, V2_ANTI_DOS_SERVICE),
                bytes: V2_UNLOCK.to_vec(),
                what: "v2 anti-DoS unlock",
            }]
        },
        chunk_size: ATT_PAYLOAD,
        pacing: model.write_pacing(),
        write_with_response: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uuids_are_the_droids() {
        assert_eq!(
            V2_SERVICE.to_string(),
            "00010001-574f-4f20-5370-6865726f2121"
        );
        assert_eq!(V2_API.to_string(), "00010002-574f-4f20-5370-6865726f2121");
        assert_eq!(
            V2_ANTI_DOS.to_string(),
            "00020005-574f-4f20-5370-6865726f2121"
        );
        let p = profile(Model::R2D2);
        assert!(
            p.handshake[0]
                .ch()
                .matches(sphero_v2(0x0002_0001), V2_ANTI_DOS)
        );
        assert!(!p.write.matches(GattUuid::from_u16(1), V2_API));
        assert!(profile(Model::Rvr).handshake.is_empty());
        assert_eq!(profile(Model::Bolt).handshake.len(), 1);
    }
}
