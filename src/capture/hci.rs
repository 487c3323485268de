//! HCI to ATT.

use super::Capture;

pub fn capture_from_btsnoop(_bytes: &[u8], _handles: &[u16]) -> Result<Capture, String> {
    Err("btsnoop logs are not read yet".into())
}
