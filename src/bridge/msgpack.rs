//! A MessagePack reader, only as much as a ROS message needs (issue 40 point 7): groove-x
//! `mqtt_bridge` sends each ROS message as `msgpack.dumps` of its fields by default, so a
//! `geometry_msgs/Twist` arrives as a map of maps of floats. Read into a
//! [`serde_json::Value`], so the same checks as a JSON command apply afterwards.
//!
//! Written here rather than taking a crate: the format's part used is small (the spec:
//! <https://github.com/msgpack/msgpack/blob/master/spec.md>), and every byte of it comes
//! from the wire, so this reader is bounded by construction: at most [`MAX_DEPTH`] nested
//! containers, a container's announced length is checked against the bytes left before
//! anything is allocated for it (each element takes at least one byte), and every malformed
//! input is an [`Error`], never a panic (unit tests below feed it every truncation and a
//! stream of random inputs).
//!
//! Taken: nil, booleans, integers of every width, float 32 and 64 (finite only: JSON has no
//! NaN), strings (UTF-8), arrays, maps with string keys. Refused with a reason: binary and
//! extension types (no ROS message field of a Twist is one), non-string map keys, trailing
//! bytes after the value.

use serde_json::{Map, Number, Value};

/// Containers nested deeper than this are refused (a Twist is 2 deep, an Odometry 4).
pub const MAX_DEPTH: usize = 16;

/// Why a payload is not MessagePack this reader takes.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Error {
    #[error("MessagePack ends inside a value (at byte {0})")]
    Truncated(usize),
    #[error("MessagePack type 0x{0:02x} at byte {1} is not taken (binary or extension data)")]
    Unsupported(u8, usize),
    #[error("MessagePack nested deeper than {MAX_DEPTH} containers")]
    TooDeep,
    #[error("a MessagePack map key at byte {0} is not a string")]
    KeyNotString(usize),
    #[error("a MessagePack string at byte {0} is not UTF-8")]
    NotUtf8(usize),
    #[error("a MessagePack float at byte {0} is not finite")]
    NotFinite(usize),
    #[error("{0} bytes after the MessagePack value")]
    Trailing(usize),
}

/// The one value `bytes` holds, all of them.
pub fn decode(bytes: &[u8]) -> Result<Value, Error> {
    let mut r = Reader { bytes, at: 0 };
    let v = r.value(0)?;
    match bytes.len() - r.at {
        0 => Ok(v),
        n => Err(Error::Trailing(n)),
    }
}

/// Whether `bytes` look like MessagePack rather than JSON text: a map's first byte (JSON
/// text starts with `{`, a space or a BOM, none of which is a MessagePack map).
pub fn looks_like_map(bytes: &[u8]) -> bool {
    matches!(bytes.first(), Some(0x80..=0x8f | 0xde | 0xdf))
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], Error> {
        let end = self
            .at
            .checked_add(n)
            .filter(|e| *e <= self.bytes.len())
            .ok_or(Error::Truncated(self.at))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn byte(&mut self) -> Result<u8, Error> {
        Ok(self.take(1)?[0])
    }

    /// A big-endian unsigned number of `n` (1, 2, 4, 8) bytes.
    fn uint(&mut self, n: usize) -> Result<u64, Error> {
        Ok(self
            .take(n)?
            .iter()
            .fold(0u64, |acc, b| (acc << 8) | u64::from(*b)))
    }

    /// A length of `n` bytes, no more than the bytes left (each element or byte of what it
    /// counts takes at least one): nothing is allocated for a length the input cannot hold.
    fn len(&mut self, n: usize) -> Result<usize, Error> {
        let at = self.at;
        let l = self.uint(n)?;
        let left = (self.bytes.len() - self.at) as u64;
        if l > left {
            return Err(Error::Truncated(at));
        }
        Ok(l as usize)
    }

    fn value(&mut self, depth: usize) -> Result<Value, Error> {
        let at = self.at;
        let b = self.byte()?;
        Ok(match b {
            0x00..=0x7f => Value::from(b),
            0xe0..=0xff => Value::from(b as i8),
            0xc0 => Value::Null,
            0xc2 => Value::Bool(false),
            0xc3 => Value::Bool(true),
            0xcc => Value::from(self.uint(1)?),
            0xcd => Value::from(self.uint(2)?),
            0xce => Value::from(self.uint(4)?),
            0xcf => Value::from(self.uint(8)?),
            0xd0 => Value::from(self.uint(1)? as u8 as i8),
            0xd1 => Value::from(self.uint(2)? as u16 as i16),
            0xd2 => Value::from(self.uint(4)? as u32 as i32),
            0xd3 => Value::from(self.uint(8)? as i64),
            0xca => float(f64::from(f32::from_bits(self.uint(4)? as u32)), at)?,
            0xcb => float(f64::from_bits(self.uint(8)?), at)?,
            0xa0..=0xbf => self.string(usize::from(b & 0x1f), at)?,
            0xd9 => {
                let n = self.len(1)?;
                self.string(n, at)?
            }
            0xda => {
                let n = self.len(2)?;
                self.string(n, at)?
            }
            0xdb => {
                let n = self.len(4)?;
                self.string(n, at)?
            }
            0x90..=0x9f => self.array(usize::from(b & 0x0f), depth)?,
            0xdc => {
                let n = self.len(2)?;
                self.array(n, depth)?
            }
            0xdd => {
                let n = self.len(4)?;
                self.array(n, depth)?
            }
            0x80..=0x8f => self.map(usize::from(b & 0x0f), depth)?,
            0xde => {
                let n = self.len(2)?;
                self.map(n, depth)?
            }
            0xdf => {
                let n = self.len(4)?;
                self.map(n, depth)?
            }
            // 0xc1 (never used), bin 8/16/32, ext and fixext.
            _ => return Err(Error::Unsupported(b, at)),
        })
    }

    fn string(&mut self, n: usize, at: usize) -> Result<Value, Error> {
        let s = std::str::from_utf8(self.take(n)?).map_err(|_| Error::NotUtf8(at))?;
        Ok(Value::String(s.to_string()))
    }

    fn array(&mut self, n: usize, depth: usize) -> Result<Value, Error> {
        if depth >= MAX_DEPTH {
            return Err(Error::TooDeep);
        }
        // `n` was checked against the bytes left (a fixarray's is at most 15).
        let mut out = Vec::with_capacity(n.min(self.bytes.len() - self.at));
        for _ in 0..n {
            out.push(self.value(depth + 1)?);
        }
        Ok(Value::Array(out))
    }

    fn map(&mut self, n: usize, depth: usize) -> Result<Value, Error> {
        if depth >= MAX_DEPTH {
            return Err(Error::TooDeep);
        }
        let mut out = Map::new();
        for _ in 0..n {
            let at = self.at;
            let Value::String(k) = self.value(depth + 1)? else {
                return Err(Error::KeyNotString(at));
            };
            let v = self.value(depth + 1)?;
            out.insert(k, v);
        }
        Ok(Value::Object(out))
    }
}

fn float(f: f64, at: usize) -> Result<Value, Error> {
    Number::from_f64(f)
        .map(Value::Number)
        .ok_or(Error::NotFinite(at))
}

/// `msgpack.dumps({"linear": {"x": 0.3, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0,
/// "y": 0.0, "z": -0.5}})` as Python's msgpack 1.0 writes it (floats as float 64,
/// strings as fixstr), built byte by byte from the spec: the one encoder of the unit tests
/// and the integration tests (`tests/it/bridge_ros.rs`), which publish it on `cmd_vel`.
/// The bridge itself only reads MessagePack; this is public (not behind `test-hooks`) so that
/// the integration tests, built with and without that feature, share it.
pub fn twist_bytes(linear_x: f64, angular_z: f64) -> Vec<u8> {
    let mut b = vec![0x82];
    for (name, v) in [
        ("linear", [linear_x, 0.0, 0.0]),
        ("angular", [0.0, 0.0, angular_z]),
    ] {
        b.push(0xa0 | name.len() as u8);
        b.extend_from_slice(name.as_bytes());
        b.push(0x83);
        for (axis, x) in ["x", "y", "z"].iter().zip(v) {
            b.push(0xa1);
            b.extend_from_slice(axis.as_bytes());
            b.push(0xcb);
            b.extend_from_slice(&x.to_be_bytes());
        }
    }
    b
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_twist_as_python_msgpack_writes_it() {
        let v = decode(&twist_bytes(0.3, -0.5)).unwrap();
        assert_eq!(
            v,
            json!({"linear":{"x":0.3,"y":0.0,"z":0.0},"angular":{"x":0.0,"y":0.0,"z":-0.5}})
        );
        assert!(looks_like_map(&twist_bytes(0.0, 0.0)));
        assert!(!looks_like_map(b"{\"linear\":{}}"));
    }

    #[test]
    fn every_width_of_number_and_string() {
        let cases: Vec<(Vec<u8>, Value)> = vec![
            (vec![0x05], json!(5)),
            (vec![0xff], json!(-1)),
            (vec![0xcc, 0xc8], json!(200)),
            (vec![0xcd, 0x01, 0x00], json!(256)),
            (vec![0xce, 0, 1, 0, 0], json!(65536)),
            (vec![0xcf, 0, 0, 0, 1, 0, 0, 0, 0], json!(1u64 << 32)),
            (vec![0xd0, 0x80], json!(-128)),
            (vec![0xd1, 0xff, 0x00], json!(-256)),
            (vec![0xd2, 0xff, 0xff, 0xff, 0xfe], json!(-2)),
            (
                vec![0xd3, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xfd],
                json!(-3),
            ),
            ([&[0xca][..], &1.5f32.to_be_bytes()].concat(), json!(1.5)),
            (vec![0xc0], Value::Null),
            (vec![0xc3], json!(true)),
            (vec![0xd9, 2, b'h', b'i'], json!("hi")),
            (vec![0xda, 0, 1, b'x'], json!("x")),
            (vec![0x92, 0x01, 0xa1, b'a'], json!([1, "a"])),
            (vec![0xdc, 0, 1, 0xc2], json!([false])),
            (vec![0xde, 0, 1, 0xa1, b'k', 0x07], json!({"k": 7})),
        ];
        for (bytes, want) in cases {
            assert_eq!(decode(&bytes), Ok(want.clone()), "{bytes:02x?}");
        }
    }

    #[test]
    fn malformed_input_is_an_error_naming_why() {
        assert_eq!(decode(&[]), Err(Error::Truncated(0)));
        assert_eq!(decode(&[0xc4, 1, 0]), Err(Error::Unsupported(0xc4, 0)));
        assert_eq!(decode(&[0xc1]), Err(Error::Unsupported(0xc1, 0)));
        assert_eq!(decode(&[0x81, 0x01, 0x02]), Err(Error::KeyNotString(1)));
        assert_eq!(decode(&[0xa1, 0xff]), Err(Error::NotUtf8(0)));
        let nan = [&[0xcb][..], &f64::NAN.to_be_bytes()].concat();
        assert_eq!(decode(&nan), Err(Error::NotFinite(0)));
        assert_eq!(decode(&[0x01, 0x02]), Err(Error::Trailing(1)));
        // A length far beyond the input: refused before anything is allocated for it.
        assert_eq!(
            decode(&[0xdd, 0xff, 0xff, 0xff, 0xff, 0x01]),
            Err(Error::Truncated(1))
        );
        assert_eq!(decode(&[0xdb, 0x7f, 0, 0, 0]), Err(Error::Truncated(1)));
        let deep = vec![0x91; MAX_DEPTH + 1];
        assert_eq!(decode(&deep), Err(Error::TooDeep));
        let mut ok = vec![0x91; MAX_DEPTH - 1];
        ok.push(0x90);
        assert!(decode(&ok).is_ok());
    }

    #[test]
    fn no_input_panics_every_truncation_and_random_bytes() {
        let twist = twist_bytes(0.25, 1.0);
        for n in 0..twist.len() {
            assert!(decode(&twist[..n]).is_err(), "{n}");
        }
        // A small xorshift: the same inputs every run.
        let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut decoded = 0;
        for _ in 0..50_000 {
            let len = (next() % 48) as usize;
            let mut bytes: Vec<u8> = (0..len).map(|_| next() as u8).collect();
            // Often start as a map, as a Twist does, so the inside gets exercised.
            if next() % 2 == 0 && !bytes.is_empty() {
                bytes[0] = 0x80 | (bytes[0] & 0x0f);
            }
            if decode(&bytes).is_ok() {
                decoded += 1;
            }
            // Mutations of a real Twist.
            let mut t = twist.clone();
            let at = (next() as usize) % t.len();
            t[at] = next() as u8;
            let _ = decode(&t);
        }
        assert!(decoded > 0, "some random inputs are valid MessagePack");
    }
}
