//! One v2 packet: header fields, payload, and its wire encoding (escaping and checksum).

use super::error::ErrorCode;
use super::flags::Flags;

pub const SOP: u8 = 0x8D;
pub const EOP: u8 = 0xD8;
pub const ESC: u8 = 0xAB;
/// Escaped forms: the original value is the escaped value | 0x88. `sphero-v2-api.md` writes
/// ESC_ESC as "Ox23"; it is 0x23 (`droid-facts.md` §3).
pub const ESC_ESC: u8 = 0x23;
pub const ESC_SOP: u8 = 0x05;
pub const ESC_EOP: u8 = 0x50;

/// SEQ value of unsolicited notifications; never used for a request.
pub const NOTIFICATION_SEQ: u8 = 0xFF;

/// A decoded (unescaped) v2 packet.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Packet {
    pub flags: Flags,
    /// The extended-flags byte, present exactly when `flags` has EXTENDED_FLAGS.
    pub ext_flags: Option<u8>,
    /// Target ID, present exactly when `flags` has HAS_TARGET_ID.
    pub tid: Option<u8>,
    /// Source ID, present exactly when `flags` has HAS_SOURCE_ID.
    pub sid: Option<u8>,
    pub did: u8,
    pub cid: u8,
    pub seq: u8,
    /// Error code, present exactly when `flags` has IS_RESPONSE.
    pub err: Option<ErrorCode>,
    pub data: Vec<u8>,
}

impl Packet {
    /// A command with the default flags (0x0A) and no TID/SID.
    pub fn command(did: u8, cid: u8, seq: u8, data: Vec<u8>) -> Self {
        Packet {
            flags: Flags::DEFAULT_COMMAND,
            ext_flags: None,
            tid: None,
            sid: None,
            did,
            cid,
            seq,
            err: None,
            data,
        }
    }

    /// The response a droid sends to `request`: same DID/CID/SEQ, addressing swapped, and the
    /// activity flag copied (the captured wake response is `8D 09 …`: response | activity).
    pub fn response_to(request: &Packet, err: ErrorCode, data: Vec<u8>) -> Self {
        let mut flags = Flags::IS_RESPONSE | (request.flags & Flags::IS_ACTIVITY);
        if request.sid.is_some() {
            flags |= Flags::HAS_TARGET_ID;
        }
        if request.tid.is_some() {
            flags |= Flags::HAS_SOURCE_ID;
        }
        Packet {
            flags,
            ext_flags: None,
            tid: request.sid,
            sid: request.tid,
            did: request.did,
            cid: request.cid,
            seq: request.seq,
            err: Some(err),
            data,
        }
    }

    /// An unsolicited notification (SEQ 0xFF).
    pub fn notification(did: u8, cid: u8, data: Vec<u8>) -> Self {
        Packet {
            flags: Flags::empty(),
            ext_flags: None,
            tid: None,
            sid: None,
            did,
            cid,
            seq: NOTIFICATION_SEQ,
            err: None,
            data,
        }
    }

    pub fn is_response(&self) -> bool {
        self.flags.contains(Flags::IS_RESPONSE)
    }

    /// A notification: not a response, and SEQ 0xFF (`r2d2-v2-protocol.md` §5.3).
    pub fn is_notification(&self) -> bool {
        !self.is_response() && self.seq == NOTIFICATION_SEQ
    }

    /// Make the optional header fields agree with the flags, so a hand-built packet encodes
    /// to something its own decoder accepts: set fields imply their flag.
    pub fn normalized(mut self) -> Self {
        self.flags
            .set(Flags::EXTENDED_FLAGS, self.ext_flags.is_some());
        self.flags.set(Flags::HAS_TARGET_ID, self.tid.is_some());
        self.flags.set(Flags::HAS_SOURCE_ID, self.sid.is_some());
        self.flags.set(Flags::IS_RESPONSE, self.err.is_some());
        self
    }

    /// The unescaped body between SOP and EOP, without the checksum.
    pub fn body(&self) -> Vec<u8> {
        let mut body = Vec::with_capacity(8 + self.data.len());
        self.write_body(&mut body);
        body
    }

    fn write_body(&self, out: &mut Vec<u8>) {
        let p = self.clone().normalized();
        out.push(p.flags.bits());
        out.extend(p.ext_flags);
        out.extend(p.tid);
        out.extend(p.sid);
        out.extend([p.did, p.cid, p.seq]);
        out.extend(p.err.map(ErrorCode::to_byte));
        out.extend_from_slice(&p.data);
    }

    /// The wire bytes: SOP, escaped body and checksum, EOP.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(12 + self.data.len() * 2);
        self.encode_into(&mut out);
        out
    }

    /// Append the wire bytes to `out` (lets a caller reuse one buffer).
    pub fn encode_into(&self, out: &mut Vec<u8>) {
        let body = self.body();
        let chk = checksum(&body);
        out.push(SOP);
        for &b in body.iter().chain(std::iter::once(&chk)) {
            push_escaped(out, b);
        }
        out.push(EOP);
    }
}

/// The v2 checksum: the byte sum of everything between SOP and CHK, mod 256, bit-inverted.
///
/// Summed in 16 lanes, 16 bytes at a time, then the lanes: the plain fold compiled to a loop
/// of 4 bytes a step, a sixth of the decoder's time on a busy stream (issue 42 point 6).
#[inline]
pub fn checksum(body: &[u8]) -> u8 {
    let mut chunks = body.chunks_exact(16);
    let mut lanes = [0u8; 16];
    for chunk in &mut chunks {
        for (lane, &b) in lanes.iter_mut().zip(chunk) {
            *lane = lane.wrapping_add(b);
        }
    }
    let sum = lanes
        .iter()
        .chain(chunks.remainder())
        .fold(0u8, |acc, &b| acc.wrapping_add(b));
    !sum
}

fn push_escaped(out: &mut Vec<u8>, b: u8) {
    match b {
        ESC => out.extend([ESC, ESC_ESC]),
        SOP => out.extend([ESC, ESC_SOP]),
        EOP => out.extend([ESC, ESC_EOP]),
        _ => out.push(b),
    }
}

/// Why an unescaped body is not a packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyError {
    /// Fewer bytes than the flags require.
    TooShort {
        needed: usize,
        got: usize,
    },
    BadChecksum {
        expected: u8,
        got: u8,
    },
}

/// A decoded packet whose payload borrows the decoder's buffer: what
/// [`Decoder::feed_with`](super::Decoder::feed_with) hands out, so decoding allocates nothing
/// per packet. [`PacketRef::to_packet`] makes an owned [`Packet`] when one is needed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PacketRef<'a> {
    pub flags: Flags,
    pub ext_flags: Option<u8>,
    pub tid: Option<u8>,
    pub sid: Option<u8>,
    pub did: u8,
    pub cid: u8,
    pub seq: u8,
    pub err: Option<ErrorCode>,
    pub data: &'a [u8],
}

impl PacketRef<'_> {
    pub fn to_packet(&self) -> Packet {
        self.to_packet_in(Vec::new())
    }

    /// The owned packet with its payload copied into `data` (cleared first): a caller that
    /// makes one packet after another reuses one allocation.
    pub fn to_packet_in(&self, mut data: Vec<u8>) -> Packet {
        data.clear();
        data.extend_from_slice(self.data);
        Packet {
            flags: self.flags,
            ext_flags: self.ext_flags,
            tid: self.tid,
            sid: self.sid,
            did: self.did,
            cid: self.cid,
            seq: self.seq,
            err: self.err,
            data,
        }
    }

    pub fn is_response(&self) -> bool {
        self.flags.contains(Flags::IS_RESPONSE)
    }

    /// A notification: not a response, and SEQ 0xFF.
    pub fn is_notification(&self) -> bool {
        !self.is_response() && self.seq == NOTIFICATION_SEQ
    }
}

/// A body [`parse_body_ref`] accepted, read again without checking its checksum.
pub(crate) fn body_ref_unchecked(body: &[u8]) -> Option<PacketRef<'_>> {
    header_ref(body).ok()
}

/// Parse an unescaped body (everything between SOP and EOP, checksum included) without
/// copying the payload. On a bad checksum the packet as read comes back with the error.
#[inline]
pub fn parse_body_ref(body: &[u8]) -> Result<PacketRef<'_>, (BodyError, Option<PacketRef<'_>>)> {
    let packet = header_ref(body).map_err(|e| (e, None))?;
    let got = body.len();
    let expected = checksum(&body[..got - 1]);
    let chk = body[got - 1];
    if expected != chk {
        return Err((BodyError::BadChecksum { expected, got: chk }, Some(packet)));
    }
    Ok(packet)
}

/// The header fields and payload of a body, its length checked against its flags (the
/// checksum is not looked at).
#[inline]
fn header_ref(body: &[u8]) -> Result<PacketRef<'_>, BodyError> {
    let got = body.len();
    let Some(&flag_byte) = body.first() else {
        return Err(BodyError::TooShort { needed: 5, got });
    };
    let flags = Flags::from_bits_retain(flag_byte);
    let ext = flags.contains(Flags::EXTENDED_FLAGS) as usize;
    let tid = flags.contains(Flags::HAS_TARGET_ID) as usize;
    let sid = flags.contains(Flags::HAS_SOURCE_ID) as usize;
    let err = flags.contains(Flags::IS_RESPONSE) as usize;
    // flags + optional bytes + DID CID SEQ + optional ERR + CHK
    let header = 1 + ext + tid + sid + 3 + err;
    let needed = header + 1;
    if got < needed {
        return Err(BodyError::TooShort { needed, got });
    }
    let mut i = 1;
    let mut take = |present: usize| {
        if present == 1 {
            i += 1;
            Some(body[i - 1])
        } else {
            None
        }
    };
    let ext_flags = take(ext);
    let tid_v = take(tid);
    let sid_v = take(sid);
    Ok(PacketRef {
        flags,
        ext_flags,
        tid: tid_v,
        sid: sid_v,
        did: body[i],
        cid: body[i + 1],
        seq: body[i + 2],
        err: (err == 1).then(|| ErrorCode::from_byte(body[i + 3])),
        data: &body[header..got - 1],
    })
}

/// Parse an unescaped body (everything between SOP and EOP, checksum included).
/// The checksum is verified; a packet whose checksum fails is still returned alongside the
/// error so a diagnostic tool can show what it held.
pub fn parse_body(body: &[u8]) -> Result<Packet, (BodyError, Option<Packet>)> {
    parse_body_ref(body)
        .map(|p| p.to_packet())
        .map_err(|(e, p)| (e, p.map(|p| p.to_packet())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hex;

    #[test]
    fn wake_vector() {
        let p = Packet::command(0x13, 0x0D, 0, vec![]);
        assert_eq!(p.encode(), hex::parse("8D 0A 13 0D 00 D5 D8").unwrap());
    }

    #[test]
    fn wake_response_vector() {
        let req = Packet::command(0x13, 0x0D, 0, vec![]);
        let resp = Packet::response_to(&req, ErrorCode::Success, vec![]);
        assert_eq!(
            resp.encode(),
            hex::parse("8D 09 13 0D 00 00 D6 D8").unwrap()
        );
    }

    #[test]
    fn checksum_is_inverted_sum() {
        assert_eq!(checksum(&[0x0A, 0x13, 0x0D, 0x00]), 0xD5);
        assert_eq!(checksum(&[]), 0xFF);
        // Every length around the 16-byte lanes, against the plain sum.
        let bytes: Vec<u8> = (0..100u32).map(|i| (i * 37 + 201) as u8).collect();
        for n in 0..bytes.len() {
            let plain = !bytes[..n].iter().fold(0u8, |a, &b| a.wrapping_add(b));
            assert_eq!(checksum(&bytes[..n]), plain, "{n} bytes");
        }
    }

    #[test]
    fn response_swaps_addresses() {
        let mut req = Packet::command(0x17, 0x0F, 3, vec![]);
        req.tid = Some(0x12);
        req.sid = Some(0x01);
        let req = req.normalized();
        let resp = Packet::response_to(&req, ErrorCode::Success, vec![]);
        assert_eq!(resp.tid, Some(0x01));
        assert_eq!(resp.sid, Some(0x12));
        assert_eq!(resp.seq, 3);
        let wire = resp.encode();
        let body = &wire[1..wire.len() - 1];
        assert_eq!(parse_body(body).unwrap(), resp.normalized());
    }

    #[test]
    fn short_body_rejected() {
        // Response flag demands an ERR byte.
        assert_eq!(
            parse_body(&[0x09, 0x13, 0x0D, 0x00, 0x00]).unwrap_err().0,
            BodyError::TooShort { needed: 6, got: 5 }
        );
        assert!(parse_body(&[]).is_err());
    }
}
