//! The three Sphero API v1 packet shapes and their wire encoding (`sphero-v1-packets.md`,
//! `droid-facts.md` §4):
//!
//! ```text
//! command   FF SOP2 DID  CID  SEQ     DLEN  data CHK    SOP2 = F8..FF (option bits)
//! response  FF FF   MRSP SEQ  DLEN          data CHK
//! async     FF FE   ID   DLEN_hi DLEN_lo    data CHK
//! ```
//!
//! DLEN counts the data plus the checksum byte. CHK is the bitwise NOT of the byte sum (mod
//! 256) of everything after SOP2 up to the end of the data: DID, CID, SEQ and DLEN for a
//! command (`FF FF 00 01 52 01 AB`: 00+01+52+01 = 54, !54 = AB); MRSP, SEQ and DLEN for a
//! response; the ID code and both DLEN bytes for an async message. There is no escaping, so
//! `FF FF` can occur inside data; see [`super::decoder`] for how the stream is resynchronised.

use std::fmt;

/// Start of packet 1, on every packet.
pub const SOP1: u8 = 0xFF;
/// SOP2 of a response (acknowledgement).
pub const SOP2_RESPONSE: u8 = 0xFF;
/// SOP2 of an asynchronous message.
pub const SOP2_ASYNC: u8 = 0xFE;
/// The lowest command SOP2: bits 7..3 are always set (`sphero-v1-packets.md`: "F8 to FFh").
pub const SOP2_COMMAND_BASE: u8 = 0xF8;
/// SOP2 bit 0: act and send a response.
pub const SOP2_ANSWER: u8 = 0x01;
/// SOP2 bit 1: reset the inactivity timeout after executing.
pub const SOP2_RESET_TIMEOUT: u8 = 0x02;

/// Header bytes before the data: SOP1 SOP2 DID CID SEQ DLEN.
pub const COMMAND_HEADER: usize = 6;
/// Header bytes before the data: SOP1 SOP2 MRSP SEQ DLEN, or SOP1 SOP2 ID DLEN_hi DLEN_lo.
pub const RESPONSE_HEADER: usize = 5;
pub const ASYNC_HEADER: usize = 5;

/// Most data bytes a one-byte DLEN can frame (255 minus the checksum). The seed mentions a
/// special DLEN FF meaning "a fixed length greater than 254 for certain DID/CID": no command
/// droidctl knows uses it, so FF is read as 254 data bytes and longer payloads are refused.
pub const MAX_DATA: usize = 254;
/// Most data bytes a two-byte async DLEN can frame.
pub const MAX_ASYNC_DATA: usize = 0xFFFE;

/// The v1 checksum over the bytes after SOP2 up to the end of the data.
pub fn checksum(bytes: &[u8]) -> u8 {
    !bytes.iter().fold(0u8, |acc, &b| acc.wrapping_add(b))
}

/// A payload too long for its packet's DLEN field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameError {
    pub kind: Kind,
    pub len: usize,
    pub max: usize,
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} data of {} bytes cannot be framed (at most {})",
            self.kind.name(),
            self.len,
            self.max
        )
    }
}

impl std::error::Error for FrameError {}

/// The packet shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    Command,
    Response,
    Async,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Command => "command",
            Kind::Response => "response",
            Kind::Async => "async",
        }
    }
}

/// A command, client → droid.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct CommandPacket {
    /// SOP2 as sent: F8..FF, option bits in 0..=2. Encoding forces bits 7..3 on.
    pub sop2: u8,
    pub did: u8,
    pub cid: u8,
    pub seq: u8,
    pub data: Vec<u8>,
}

impl CommandPacket {
    /// What droidctl sends: answer and reset-timeout (`FF`, as the seed's Ping example).
    pub const DEFAULT_SOP2: u8 = 0xFF;

    pub fn new(did: u8, cid: u8, seq: u8, data: Vec<u8>) -> Self {
        CommandPacket {
            sop2: Self::DEFAULT_SOP2,
            did,
            cid,
            seq,
            data,
        }
    }

    /// The same command with the SOP2 option bits set as given (bit 2 kept on, as the seed's
    /// bit table shows it: `0xFC | reset_timeout << 1 | answer`).
    pub fn with_options(mut self, answer: bool, reset_timeout: bool) -> Self {
        self.sop2 = 0xFC | (reset_timeout as u8) << 1 | answer as u8;
        self
    }

    /// Whether the droid is asked to answer.
    pub fn answer(&self) -> bool {
        self.sop2 & SOP2_ANSWER != 0
    }

    /// Whether the droid resets its inactivity timeout on this command.
    pub fn reset_timeout(&self) -> bool {
        self.sop2 & SOP2_RESET_TIMEOUT != 0
    }

    fn write(&self, out: &mut Vec<u8>) -> Result<(), FrameError> {
        if self.data.len() > MAX_DATA {
            return Err(FrameError {
                kind: Kind::Command,
                len: self.data.len(),
                max: MAX_DATA,
            });
        }
        let start = out.len();
        out.extend([
            SOP1,
            SOP2_COMMAND_BASE | self.sop2,
            self.did,
            self.cid,
            self.seq,
            self.data.len() as u8 + 1,
        ]);
        out.extend_from_slice(&self.data);
        let chk = checksum(&out[start + 2..]);
        out.push(chk);
        Ok(())
    }
}

/// A response, droid → client.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Response {
    pub mrsp: Mrsp,
    pub seq: u8,
    pub data: Vec<u8>,
}

impl Response {
    /// The response a droid sends to `request`: its SEQ echoed.
    pub fn to(request: &CommandPacket, mrsp: Mrsp, data: Vec<u8>) -> Self {
        Response {
            mrsp,
            seq: request.seq,
            data,
        }
    }

    fn write(&self, out: &mut Vec<u8>) -> Result<(), FrameError> {
        if self.data.len() > MAX_DATA {
            return Err(FrameError {
                kind: Kind::Response,
                len: self.data.len(),
                max: MAX_DATA,
            });
        }
        let start = out.len();
        out.extend([
            SOP1,
            SOP2_RESPONSE,
            self.mrsp.to_byte(),
            self.seq,
            self.data.len() as u8 + 1,
        ]);
        out.extend_from_slice(&self.data);
        let chk = checksum(&out[start + 2..]);
        out.push(chk);
        Ok(())
    }
}

/// An asynchronous message, droid → client, unsolicited.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct AsyncPacket {
    pub id_code: u8,
    pub data: Vec<u8>,
}

impl AsyncPacket {
    pub fn new(id_code: u8, data: Vec<u8>) -> Self {
        AsyncPacket { id_code, data }
    }

    fn write(&self, out: &mut Vec<u8>) -> Result<(), FrameError> {
        if self.data.len() > MAX_ASYNC_DATA {
            return Err(FrameError {
                kind: Kind::Async,
                len: self.data.len(),
                max: MAX_ASYNC_DATA,
            });
        }
        let start = out.len();
        let dlen = (self.data.len() as u16 + 1).to_be_bytes();
        out.extend([SOP1, SOP2_ASYNC, self.id_code, dlen[0], dlen[1]]);
        out.extend_from_slice(&self.data);
        let chk = checksum(&out[start + 2..]);
        out.push(chk);
        Ok(())
    }
}

/// Any v1 packet.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Packet {
    Command(CommandPacket),
    Response(Response),
    Async(AsyncPacket),
}

impl Packet {
    pub fn kind(&self) -> Kind {
        match self {
            Packet::Command(_) => Kind::Command,
            Packet::Response(_) => Kind::Response,
            Packet::Async(_) => Kind::Async,
        }
    }

    pub fn data(&self) -> &[u8] {
        match self {
            Packet::Command(c) => &c.data,
            Packet::Response(r) => &r.data,
            Packet::Async(a) => &a.data,
        }
    }

    /// The number of wire bytes this packet takes (header, data, checksum).
    pub fn wire_len(&self) -> usize {
        let header = match self {
            Packet::Command(_) => COMMAND_HEADER,
            Packet::Response(_) => RESPONSE_HEADER,
            Packet::Async(_) => ASYNC_HEADER,
        };
        header + self.data().len() + 1
    }

    /// The wire bytes. Fails only when the data is longer than DLEN can count.
    pub fn encode(&self) -> Result<Vec<u8>, FrameError> {
        let mut out = Vec::with_capacity(self.wire_len());
        self.encode_into(&mut out)?;
        Ok(out)
    }

    /// Append the wire bytes to `out` (lets a caller reuse one buffer). On error nothing is
    /// appended.
    pub fn encode_into(&self, out: &mut Vec<u8>) -> Result<(), FrameError> {
        match self {
            Packet::Command(c) => c.write(out),
            Packet::Response(r) => r.write(out),
            Packet::Async(a) => a.write(out),
        }
    }
}

impl From<CommandPacket> for Packet {
    fn from(c: CommandPacket) -> Self {
        Packet::Command(c)
    }
}

impl From<Response> for Packet {
    fn from(r: Response) -> Self {
        Packet::Response(r)
    }
}

impl From<AsyncPacket> for Packet {
    fn from(a: AsyncPacket) -> Self {
        Packet::Async(a)
    }
}

/// The MRSP byte of a response (Sphero API v1 message response codes; names as in the
/// seed's appendix list, values not listed there are kept as `Other`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mrsp {
    Ok,
    GeneralError,
    ChecksumFailure,
    FragmentedCommand,
    UnknownCommand,
    CommandUnsupported,
    BadMessageFormat,
    ParameterInvalid,
    FailedToExecute,
    UnknownDevice,
    RamBusy,
    BadPassword,
    VoltageTooLow,
    IllegalPage,
    FlashFail,
    MainAppCorrupt,
    MsgTimeout,
    Other(u8),
}

impl Mrsp {
    const TABLE: [(Mrsp, u8, &'static str, &'static str); 17] = [
        (Mrsp::Ok, 0x00, "ok", "command succeeded"),
        (
            Mrsp::GeneralError,
            0x01,
            "general_error",
            "general, non-specific error",
        ),
        (
            Mrsp::ChecksumFailure,
            0x02,
            "checksum_failure",
            "received checksum failure",
        ),
        (
            Mrsp::FragmentedCommand,
            0x03,
            "fragmented_command",
            "received command fragment",
        ),
        (
            Mrsp::UnknownCommand,
            0x04,
            "unknown_command",
            "unknown command ID",
        ),
        (
            Mrsp::CommandUnsupported,
            0x05,
            "command_unsupported",
            "command currently unsupported",
        ),
        (
            Mrsp::BadMessageFormat,
            0x06,
            "bad_message_format",
            "bad message format",
        ),
        (
            Mrsp::ParameterInvalid,
            0x07,
            "parameter_invalid",
            "parameter value(s) invalid",
        ),
        (
            Mrsp::FailedToExecute,
            0x08,
            "failed_to_execute",
            "failed to execute command",
        ),
        (
            Mrsp::UnknownDevice,
            0x09,
            "unknown_device",
            "unknown device ID",
        ),
        (
            Mrsp::RamBusy,
            0x0A,
            "ram_busy",
            "generic RAM access needed but it is busy",
        ),
        (
            Mrsp::BadPassword,
            0x0B,
            "bad_password",
            "supplied password incorrect",
        ),
        (
            Mrsp::VoltageTooLow,
            0x31,
            "voltage_too_low",
            "voltage too low for reflash operation",
        ),
        (
            Mrsp::IllegalPage,
            0x32,
            "illegal_page",
            "illegal page number provided",
        ),
        (
            Mrsp::FlashFail,
            0x33,
            "flash_fail",
            "page did not reprogram correctly",
        ),
        (
            Mrsp::MainAppCorrupt,
            0x34,
            "main_app_corrupt",
            "main application corrupt",
        ),
        (
            Mrsp::MsgTimeout,
            0x35,
            "msg_timeout",
            "message state machine timed out",
        ),
    ];

    pub fn from_byte(b: u8) -> Self {
        Self::TABLE
            .iter()
            .find(|(_, v, _, _)| *v == b)
            .map_or(Mrsp::Other(b), |(m, _, _, _)| *m)
    }

    pub fn to_byte(self) -> u8 {
        match self {
            Mrsp::Other(b) => b,
            known => Self::TABLE
                .iter()
                .find(|(m, _, _, _)| *m == known)
                .map_or(0xFF, |(_, v, _, _)| *v),
        }
    }

    /// The droid accepted and executed the command.
    pub fn is_success(self) -> bool {
        self.to_byte() == 0x00
    }

    /// snake_case name, or `unknown_0xNN`.
    pub fn name(self) -> String {
        match Self::TABLE.iter().find(|(_, v, _, _)| *v == self.to_byte()) {
            Some((_, _, n, _)) => (*n).to_string(),
            None => format!("unknown_0x{:02x}", self.to_byte()),
        }
    }

    /// A sentence for people.
    pub fn message(self) -> String {
        match Self::TABLE.iter().find(|(_, v, _, _)| *v == self.to_byte()) {
            Some((_, _, _, m)) => (*m).to_string(),
            None => format!("unknown response code 0x{:02X}", self.to_byte()),
        }
    }
}

impl fmt::Display for Mrsp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.name(), self.message())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hex;

    #[test]
    fn golden_ping_and_roll() {
        let ping = Packet::Command(CommandPacket::new(0x00, 0x01, 0x52, vec![]));
        assert_eq!(
            ping.encode().unwrap(),
            hex::parse("FF FF 00 01 52 01 AB").unwrap()
        );
        let roll = Packet::Command(CommandPacket::new(0x02, 0x30, 0, vec![0x80, 0, 0x5A, 1]));
        assert_eq!(
            roll.encode().unwrap(),
            hex::parse("FF FF 02 30 00 05 80 00 5A 01 ED").unwrap()
        );
    }

    #[test]
    fn sop2_options() {
        let c = CommandPacket::new(0, 1, 0, vec![]);
        assert!(c.answer() && c.reset_timeout());
        let c = c.with_options(false, true);
        assert_eq!(c.sop2, 0xFE);
        assert!(!c.answer() && c.reset_timeout());
        assert_eq!(c.clone().with_options(true, false).sop2, 0xFD);
    }

    #[test]
    fn async_dlen_is_two_bytes_and_summed() {
        let a = Packet::Async(AsyncPacket::new(0x01, vec![0x02]));
        // 01 + 00 + 02 + 02 = 05, !05 = FA
        assert_eq!(
            a.encode().unwrap(),
            hex::parse("FF FE 01 00 02 02 FA").unwrap()
        );
    }

    #[test]
    fn oversize_is_an_error_not_a_panic() {
        let c = Packet::Command(CommandPacket::new(2, 0x20, 0, vec![0; 255]));
        let mut out = vec![1];
        assert_eq!(
            c.encode_into(&mut out),
            Err(FrameError {
                kind: Kind::Command,
                len: 255,
                max: 254
            })
        );
        assert_eq!(out, vec![1]);
        assert!(
            Packet::Command(CommandPacket::new(2, 0x20, 0, vec![0; 254]))
                .encode()
                .is_ok()
        );
    }

    #[test]
    fn mrsp_bytes_round_trip() {
        for b in 0..=255u8 {
            assert_eq!(Mrsp::from_byte(b).to_byte(), b);
        }
        assert_eq!(Mrsp::from_byte(0x07).name(), "parameter_invalid");
        assert_eq!(Mrsp::from_byte(0x35), Mrsp::MsgTimeout);
        assert_eq!(Mrsp::from_byte(0x0C).name(), "unknown_0x0c");
        assert!(Mrsp::Ok.is_success() && !Mrsp::Other(0x0C).is_success());
    }
}
