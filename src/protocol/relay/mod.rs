//! spherov2.py's TCP relay of GATT operations, sans-IO: typed requests and replies, encoders,
//! and incremental decoders that take bytes in any chunking.
//!
//! The wire format, as spherov2 0.12 speaks it (`spherov2/adapter/tcp_server.py`,
//! `tcp_adapter.py`, `tcp_consts.py`); every integer is big-endian:
//!
//! | request | bytes |
//! | --- | --- |
//! | SCAN | `00`, f32 timeout (s) |
//! | FIND | `04`, u16 n, name (UTF-8, n bytes), f32 timeout (s) |
//! | INIT | `01`, seq, u16 n, address (ASCII) |
//! | SET_CALLBACK | `02`, seq, u16 n, characteristic UUID (ASCII) |
//! | WRITE | `03`, seq, u16 n, characteristic UUID (ASCII), u16 m, data (m bytes) |
//! | END | `FF` |
//!
//! | reply | bytes |
//! | --- | --- |
//! | OK to INIT, SET_CALLBACK, WRITE | `00`, seq |
//! | OK to SCAN | `00`, u16 count, then per device: u16 n, name (UTF-8), u16 m, address |
//! | OK to FIND | `00`, u16 n, name, u16 m, address (one device, no count) |
//! | ON_DATA | `01`, u16 n, characteristic UUID, u8 m, data (m bytes) |
//! | ERROR to a request with a seq | `FF`, u16 n, message (UTF-8), seq |
//! | ERROR to SCAN or FIND | `FF`, u16 n, message (no seq); to FIND with n = 0: not found |
//!
//! An OK or ERROR reply does not say which request it answers: its layout depends on it.
//! The server answers requests in order, so [`ReplyDecoder`] keeps a queue of what each
//! request sent expects ([`Expect`]); ON_DATA may come at any time.
//!
//! INIT only connects (spherov2's server calls bleak's `connect`); the client runs the toy's
//! handshake itself with WRITEs and subscribes with SET_CALLBACK. There is no request to read
//! a characteristic, and no message for a droid that disconnects.
//!
//! Decoding never panics and never allocates more than the [`Limits`] allow: a length prefix
//! above its limit is an error as soon as it is read, before its bytes arrive.

mod decode;

pub use decode::{Expect, ReplyDecoder, RequestDecoder};

use std::fmt;

/// spherov2's port (`tcp_server.py` and `get_tcp_adapter` both default to it).
pub const DEFAULT_PORT: u16 = 50004;

/// Opcodes of requests (client → server).
pub mod req {
    pub const SCAN: u8 = 0x00;
    pub const INIT: u8 = 0x01;
    pub const SET_CALLBACK: u8 = 0x02;
    pub const WRITE: u8 = 0x03;
    pub const FIND: u8 = 0x04;
    pub const END: u8 = 0xff;
}

/// Opcodes of replies (server → client).
pub mod rep {
    pub const OK: u8 = 0x00;
    pub const ON_DATA: u8 = 0x01;
    pub const ERROR: u8 = 0xff;
}

/// Largest field each side accepts. A length prefix above its limit fails decoding at once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Addresses and characteristic UUIDs (a UUID is 36 characters; a macOS identifier too).
    pub text: usize,
    /// Device names (BLE names are at most 248 bytes).
    pub name: usize,
    /// One WRITE's data (an ATT value is at most 512 bytes).
    pub data: usize,
    /// An ERROR's message.
    pub message: usize,
    /// Devices in one SCAN answer: as many as the format's u16 count can say, as many as a
    /// server may send (a crowded room must not break a client's scan).
    pub devices: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            text: 64,
            name: 248,
            data: 512,
            message: 4096,
            devices: u16::MAX as usize,
        }
    }
}

/// A request from a client.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// List the devices heard within `timeout` seconds.
    Scan { timeout: f32 },
    /// Find the device advertising `name` within `timeout` seconds.
    Find { name: String, timeout: f32 },
    /// Connect to the device at `address`.
    Init { seq: u8, address: String },
    /// Forward notifications of `characteristic` as ON_DATA.
    SetCallback { seq: u8, characteristic: String },
    /// Write `data` to `characteristic` (with response).
    Write {
        seq: u8,
        characteristic: String,
        data: Vec<u8>,
    },
    /// The client is done; the server closes the connection.
    End,
}

impl Request {
    /// The sequence number a reply to this request carries (SCAN, FIND and END have none).
    pub fn seq(&self) -> Option<u8> {
        match self {
            Request::Init { seq, .. }
            | Request::SetCallback { seq, .. }
            | Request::Write { seq, .. } => Some(*seq),
            _ => None,
        }
    }

    /// The name of the request, for logs.
    pub fn name(&self) -> &'static str {
        match self {
            Request::Scan { .. } => "SCAN",
            Request::Find { .. } => "FIND",
            Request::Init { .. } => "INIT",
            Request::SetCallback { .. } => "SET_CALLBACK",
            Request::Write { .. } => "WRITE",
            Request::End => "END",
        }
    }

    /// What the reply to this request looks like.
    pub fn expect(&self) -> Option<Expect> {
        match self {
            Request::Scan { .. } => Some(Expect::Scan),
            Request::Find { .. } => Some(Expect::Find),
            Request::End => None,
            _ => Some(Expect::Seq),
        }
    }

    /// Append the request's bytes to `out` (nothing is appended on error).
    pub fn encode(&self, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        let mut b = Vec::new();
        match self {
            Request::Scan { timeout } => {
                b.push(req::SCAN);
                b.extend_from_slice(&timeout.to_be_bytes());
            }
            Request::Find { name, timeout } => {
                b.push(req::FIND);
                put_u16_bytes(&mut b, Field::Name, name.as_bytes())?;
                b.extend_from_slice(&timeout.to_be_bytes());
            }
            Request::Init { seq, address } => {
                b.extend_from_slice(&[req::INIT, *seq]);
                put_ascii(&mut b, Field::Address, address)?;
            }
            Request::SetCallback {
                seq,
                characteristic,
            } => {
                b.extend_from_slice(&[req::SET_CALLBACK, *seq]);
                put_ascii(&mut b, Field::Characteristic, characteristic)?;
            }
            Request::Write {
                seq,
                characteristic,
                data,
            } => {
                b.extend_from_slice(&[req::WRITE, *seq]);
                put_ascii(&mut b, Field::Characteristic, characteristic)?;
                put_u16_bytes(&mut b, Field::Data, data)?;
            }
            Request::End => b.push(req::END),
        }
        out.extend_from_slice(&b);
        Ok(())
    }

    pub fn to_bytes(&self) -> Result<Vec<u8>, EncodeError> {
        let mut out = Vec::new();
        self.encode(&mut out)?;
        Ok(out)
    }
}

/// A device in a SCAN or FIND answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Device {
    pub name: String,
    /// As the relay's Bluetooth stack names it (`AA:BB:CC:DD:EE:FF`, or an identifier on
    /// macOS); INIT takes it back unchanged.
    pub address: String,
}

/// A reply from the server.
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    /// Success of the request with `seq`.
    Ok { seq: u8 },
    /// The answer to SCAN.
    Devices(Vec<Device>),
    /// The answer to FIND when the device was found.
    Found(Device),
    /// A notification from a characteristic the client asked for with SET_CALLBACK.
    Data {
        characteristic: String,
        data: Vec<u8>,
    },
    /// Failure: of the request with `seq`, or of SCAN/FIND (`seq` none). An empty message
    /// answering FIND means "not found".
    Error { message: String, seq: Option<u8> },
}

impl Reply {
    /// Append the reply's bytes to `out` (nothing is appended on error). ON_DATA carries at
    /// most 255 bytes: split longer notifications.
    pub fn encode(&self, out: &mut Vec<u8>) -> Result<(), EncodeError> {
        let mut b = Vec::new();
        match self {
            Reply::Ok { seq } => b.extend_from_slice(&[rep::OK, *seq]),
            Reply::Devices(devices) => {
                b.push(rep::OK);
                let n = u16::try_from(devices.len()).map_err(|_| EncodeError::TooLong {
                    field: Field::Devices,
                    len: devices.len(),
                })?;
                b.extend_from_slice(&n.to_be_bytes());
                for d in devices {
                    put_device(&mut b, d)?;
                }
            }
            Reply::Found(d) => {
                b.push(rep::OK);
                put_device(&mut b, d)?;
            }
            Reply::Data {
                characteristic,
                data,
            } => {
                b.push(rep::ON_DATA);
                put_ascii(&mut b, Field::Characteristic, characteristic)?;
                let n = u8::try_from(data.len()).map_err(|_| EncodeError::TooLong {
                    field: Field::Data,
                    len: data.len(),
                })?;
                b.push(n);
                b.extend_from_slice(data);
            }
            Reply::Error { message, seq } => {
                b.push(rep::ERROR);
                put_u16_bytes(&mut b, Field::Message, message.as_bytes())?;
                if let Some(s) = seq {
                    b.push(*s);
                }
            }
        }
        out.extend_from_slice(&b);
        Ok(())
    }

    pub fn to_bytes(&self) -> Result<Vec<u8>, EncodeError> {
        let mut out = Vec::new();
        self.encode(&mut out)?;
        Ok(out)
    }

    /// An ERROR whose message is cut to what the length prefix can carry (at a character
    /// boundary), so it always encodes.
    pub fn error(message: &str, seq: Option<u8>) -> Reply {
        let mut end = message.len().min(u16::MAX as usize);
        while !message.is_char_boundary(end) {
            end -= 1;
        }
        Reply::Error {
            message: message[..end].to_string(),
            seq,
        }
    }
}

fn put_device(b: &mut Vec<u8>, d: &Device) -> Result<(), EncodeError> {
    put_u16_bytes(b, Field::Name, d.name.as_bytes())?;
    put_ascii(b, Field::Address, &d.address)
}

fn put_u16_bytes(b: &mut Vec<u8>, field: Field, bytes: &[u8]) -> Result<(), EncodeError> {
    let n = u16::try_from(bytes.len()).map_err(|_| EncodeError::TooLong {
        field,
        len: bytes.len(),
    })?;
    b.extend_from_slice(&n.to_be_bytes());
    b.extend_from_slice(bytes);
    Ok(())
}

fn put_ascii(b: &mut Vec<u8>, field: Field, s: &str) -> Result<(), EncodeError> {
    if !s.is_ascii() {
        return Err(EncodeError::NotAscii { field });
    }
    put_u16_bytes(b, field, s.as_bytes())
}

/// A field of a request or reply, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    Name,
    Address,
    Characteristic,
    Data,
    Message,
    Devices,
}

impl Field {
    /// What a length of this field counts.
    fn unit(self) -> &'static str {
        match self {
            Field::Devices => "devices",
            _ => "bytes",
        }
    }
}

impl fmt::Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Field::Name => "the device name",
            Field::Address => "the address",
            Field::Characteristic => "the characteristic UUID",
            Field::Data => "the data",
            Field::Message => "the error message",
            Field::Devices => "the device list",
        })
    }
}

/// Why a request or reply could not be encoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EncodeError {
    #[error("{field} is too long for the relay protocol ({len})")]
    TooLong { field: Field, len: usize },
    #[error("{field} must be ASCII in the relay protocol")]
    NotAscii { field: Field },
}

/// Why bytes could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The stream cannot be followed past this byte.
    #[error("unknown {side} opcode 0x{op:02x}")]
    UnknownOpcode { side: Side, op: u8 },
    /// A length prefix above the limit: rejected before its bytes are read.
    #[error("{field} is {len} {} long, more than the {max} accepted", field.unit())]
    TooLong {
        field: Field,
        len: usize,
        max: usize,
        seq: Option<u8>,
    },
    /// A whole request or reply whose text is not what the protocol says (UTF-8 for names
    /// and messages, ASCII for addresses and UUIDs). The stream goes on after it.
    #[error("{field} is not valid {}", if *ascii { "ASCII" } else { "UTF-8" })]
    BadText {
        field: Field,
        ascii: bool,
        seq: Option<u8>,
    },
    /// The stream ended inside a request or reply.
    #[error("the connection ended {have} byte(s) into a {what}")]
    Truncated { what: &'static str, have: usize },
}

impl DecodeError {
    /// Whether decoding can go on after this error (only a whole request with bad text).
    pub fn recoverable(&self) -> bool {
        matches!(self, DecodeError::BadText { .. })
    }

    /// The sequence number of the request that failed, when it was read.
    pub fn seq(&self) -> Option<u8> {
        match self {
            DecodeError::TooLong { seq, .. } | DecodeError::BadText { seq, .. } => *seq,
            _ => None,
        }
    }
}

/// Which side's opcodes, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    Request,
    Reply,
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Side::Request => "request",
            Side::Reply => "reply",
        })
    }
}
