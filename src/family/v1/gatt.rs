//! The GATT profile of Sphero API v1 droids over BLE (`droid-facts.md` §4): commands and
//! responses on the control service, and the radio service's wake sequence (anti-DoS unlock,
//! TX power, wake) written before anything else.

use crate::gatt::{ATT_PAYLOAD, CharRef, GattProfile, GattUuid, HandshakeStep};
use crate::model::Model;

/// `22bb746f-XXXX-7554-2d6f-726568705327`.
const fn sphero_v1(short: u16) -> GattUuid {
    GattUuid::from_u128(0x22bb_746f_0000_7554_2d6f_7265_6870_5327 | (short as u128) << 80)
}

pub const V1_RADIO_SERVICE: GattUuid = sphero_v1(0x2bb0);
pub const V1_ANTI_DOS: GattUuid = sphero_v1(0x2bbd);
pub const V1_TX_POWER: GattUuid = sphero_v1(0x2bb2);
pub const V1_WAKE: GattUuid = sphero_v1(0x2bbf);
pub const V1_CONTROL_SERVICE: GattUuid = sphero_v1(0x2ba0);
pub const V1_COMMANDS: GattUuid = sphero_v1(0x2ba1);
pub const V1_RESPONSES: GattUuid = sphero_v1(0x2ba6);

/// The profile of a v1 model, with its reference write pacing.
pub fn profile(model: Model) -> GattProfile {
    // ASCII "011i3" unlocks, then TX power 7 and wake 1 are single bytes.
    let radio = |c, bytes: &[u8], what| HandshakeStep::Write {
        ch: CharRef::new(V1_RADIO_SERVICE, c),
        bytes: bytes.to_vec(),
        what,
    };
    GattProfile {
        service: V1_CONTROL_SERVICE,
        write: CharRef::new(V1_CONTROL_SERVICE, V1_COMMANDS),
        inputs: Vec::new(),
        notify: vec![CharRef::new(V1_CONTROL_SERVICE, V1_RESPONSES)],
        handshake: vec![
            radio(V1_ANTI_DOS, b"011i3", "v1 anti-DoS unlock"),
            radio(V1_TX_POWER, &[0x07], "v1 TX power"),
            radio(V1_WAKE, &[0x01], "v1 wake"),
        ],
        chunk_size: ATT_PAYLOAD,
        pacing: model.write_pacing(),
        write_with_response: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn handshake_bytes() {
        let p = profile(Model::BB8);
        let writes: Vec<(GattUuid, Vec<u8>)> = p
            .handshake
            .iter()
            .map(|s| match s {
                HandshakeStep::Write { ch, bytes, .. } => (ch.characteristic, bytes.clone()),
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
        assert_eq!(
            V1_ANTI_DOS.to_string(),
            "22bb746f-2bbd-7554-2d6f-726568705327"
        );
        assert_eq!(
            V1_RESPONSES.to_string(),
            "22bb746f-2ba6-7554-2d6f-726568705327"
        );
    }
}
