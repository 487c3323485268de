//! BOLT's saved 64-bit frames on the wire (IO 0x30): an 8×8 frame of palette indexes
//! (0..=15) packed into 32 bytes as spherov2.py packs it (`sphero_edu.py`
//! `register_matrix_animation`; droid-facts.md names only the command): four bit planes, bit
//! 0 of each pixel's index first; each plane eight rows, *bottom row first*; each row a byte
//! with column 0 in the top bit. The host packs ([`pack`]), the simulated BOLT unpacks
//! ([`unpack`]).

/// Decode spherov2's 32-byte packing into palette indexes `[y][x]`.
pub fn unpack(bytes: &[u8; 32]) -> [[u8; 8]; 8] {
    let mut out = [[0u8; 8]; 8];
    for (k, b) in bytes.iter().enumerate() {
        let (plane, y) = (k / 8, 7 - k % 8);
        for (x, px) in out[y].iter_mut().enumerate() {
            *px |= ((b >> (7 - x)) & 1) << plane;
        }
    }
    out
}

/// Pack palette indexes `[y][x]` (0..=15) as spherov2 does (the inverse of [`unpack`]).
pub fn pack(frame: &[[u8; 8]; 8]) -> [u8; 32] {
    let mut out = [0u8; 32];
    for plane in 0..4 {
        for (y, row) in frame.iter().enumerate() {
            let mut b = 0u8;
            for (x, px) in row.iter().enumerate() {
                b |= ((px >> plane) & 1) << (7 - x);
            }
            out[plane * 8 + (7 - y)] = b;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_unpack_as_spherov2_packs_them() {
        // spherov2's own packing of a frame whose top-left pixel is index 1, bottom-right 15.
        let mut f = [[0u8; 8]; 8];
        f[0][0] = 1;
        f[7][7] = 15;
        f[3][4] = 6;
        let packed = pack(&f);
        // Plane 0, bottom row first: row 7 is byte 0, its column 7 the lowest bit.
        assert_eq!(packed[0], 0b0000_0001);
        // Plane 0, row 0 (byte 7): column 0 is the top bit.
        assert_eq!(packed[7], 0b1000_0000);
        assert_eq!(unpack(&packed), f);
    }
}
