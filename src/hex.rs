//! Hex text in and out, forgiving about how people paste bytes: spaces, colons, commas,
//! `0x` prefixes and mixed case are all accepted.

/// Parse hex text into bytes. Separators (whitespace, `:`, `,`, `-`) and `0x` prefixes are
/// ignored; an odd number of digits or a non-hex character is an error naming the position.
pub fn parse(text: &str) -> Result<Vec<u8>, String> {
    let mut digits = Vec::with_capacity(text.len());
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c == b'0' && i + 1 < bytes.len() && (bytes[i + 1] == b'x' || bytes[i + 1] == b'X') {
            // A `0x` prefix only counts at the start of a token.
            let at_token_start = digits.len() % 2 == 0
                && (i == 0
                    || matches!(
                        bytes[i - 1],
                        b' ' | b'\t' | b'\n' | b'\r' | b':' | b',' | b'-'
                    ));
            if at_token_start {
                i += 2;
                continue;
            }
        }
        match c {
            b' ' | b'\t' | b'\n' | b'\r' | b':' | b',' | b'-' => {}
            _ => match (c as char).to_digit(16) {
                Some(d) => digits.push(d as u8),
                None => {
                    return Err(format!(
                        "malformed hex: {:?} at character {} is not a hex digit",
                        c as char,
                        i + 1
                    ));
                }
            },
        }
        i += 1;
    }
    if digits.len() % 2 != 0 {
        return Err(format!(
            "malformed hex: odd number of hex digits ({}); every byte needs two",
            digits.len()
        ));
    }
    Ok(digits.chunks(2).map(|p| (p[0] << 4) | p[1]).collect())
}

/// Upper-case hex with a space between bytes, as the specs write packets.
pub fn spaced(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len() * 3);
    for (i, &b) in bytes.iter().enumerate() {
        if i > 0 {
            s.push(' ');
        }
        s.push(UPPER[(b >> 4) as usize] as char);
        s.push(UPPER[(b & 0xF) as usize] as char);
    }
    s
}

const UPPER: &[u8; 16] = b"0123456789ABCDEF";
const LOWER: &[u8; 16] = b"0123456789abcdef";

/// Write `bytes` as lower-case hex digits into `out`, two per byte (`out` must hold
/// `2 * bytes.len()`): a digit table, not a `format!` per byte, which was most of the cost of
/// `packet decode --json` on long payloads (issue 42 point 6).
pub fn compact_into(bytes: &[u8], out: &mut [u8]) {
    for (pair, &b) in out.chunks_exact_mut(2).zip(bytes) {
        pair[0] = LOWER[(b >> 4) as usize];
        pair[1] = LOWER[(b & 0xF) as usize];
    }
}

/// Lower-case hex with no separators, for JSON.
pub fn compact(bytes: &[u8]) -> String {
    let mut digits = vec![0u8; bytes.len() * 2];
    compact_into(bytes, &mut digits);
    // Only ASCII hex digits were written.
    String::from_utf8(digits).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_common_spellings() {
        assert_eq!(parse("8D 0A 13").unwrap(), vec![0x8d, 0x0a, 0x13]);
        assert_eq!(parse("8d:0a:13").unwrap(), vec![0x8d, 0x0a, 0x13]);
        assert_eq!(parse("0x8D 0x0A").unwrap(), vec![0x8d, 0x0a]);
        assert_eq!(parse("0x8d0a13").unwrap(), vec![0x8d, 0x0a, 0x13]);
        assert_eq!(parse("8D0A13").unwrap(), vec![0x8d, 0x0a, 0x13]);
        assert_eq!(parse("").unwrap(), Vec::<u8>::new());
    }

    #[test]
    fn rejects_bad_hex() {
        assert!(parse("8D 0").unwrap_err().contains("odd"));
        assert!(parse("8G").unwrap_err().contains("'G'"));
    }

    #[test]
    fn formats() {
        assert_eq!(spaced(&[0x8d, 0x0a]), "8D 0A");
        assert_eq!(compact(&[0x8d, 0x0a]), "8d0a");
    }
}
