//! Frame-id arithmetic for link quality: frame ids are 24-bit counters that wrap
//! (`droid-facts.md` §5: "treat modulo 2^24"; the spec only says "incremented").

use super::frame::FRAME_ID_MASK;

/// Frame ids count modulo 2^24.
pub const FRAME_ID_MODULUS: u32 = 1 << 24;

/// How far `next` is ahead of `prev`, modulo 2^24: 1 for consecutive frames (including
/// 0xFFFFFF → 0), 0 for a repeated id. Bits above 24 in either argument are ignored.
pub fn frame_delta(prev: u32, next: u32) -> u32 {
    next.wrapping_sub(prev) & FRAME_ID_MASK
}

/// How many frames were lost between `prev` and `next`: `frame_delta − 1`, so 0 for
/// consecutive ids and across the wrap 0xFFFFFF → 0. A repeated id (delta 0) also counts 0;
/// tell it apart with [`frame_delta`]. A robot restart or reordering shows as a delta near
/// 2^24; deciding when a gap is too large to be loss is the caller's policy.
pub fn frame_gap(prev: u32, next: u32) -> u32 {
    frame_delta(prev, next).saturating_sub(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps() {
        assert_eq!(frame_gap(0xFF_FFFF, 0), 0);
        assert_eq!(frame_gap(0xFF_FFFE, 1), 2);
        assert_eq!(frame_gap(5, 6), 0);
        assert_eq!(frame_gap(5, 9), 3);
        assert_eq!(frame_gap(5, 5), 0);
        assert_eq!(frame_delta(5, 5), 0);
        assert_eq!(frame_delta(6, 5), FRAME_ID_MODULUS - 1);
        assert_eq!(frame_delta(0xFF00_0000, 0x0100_0001), 1);
    }
}
