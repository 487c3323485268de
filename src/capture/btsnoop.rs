//! btsnoop files.

/// Whether `bytes` start with the btsnoop magic.
pub fn sniff(bytes: &[u8]) -> bool {
    bytes.starts_with(b"btsnoop\0")
}
