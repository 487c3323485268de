//! Building HCI traffic as a phone logs it, for tests and fixtures: a droid connected, its
//! GATT discovered, values written and notified, each as a btsnoop record.

use super::*;
use crate::capture::btsnoop::write;

/// Records of a log in one datalink, on a clock that starts at 2020-01-01.
pub struct Log {
    pub datalink: Datalink,
    pub bytes: Vec<u8>,
    pub t_us: i64,
    /// The ACL payload size per fragment (27: the LE default).
    pub acl_mtu: usize,
}

/// Which way a packet goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Way {
    /// Host → controller.
    Sent,
    Received,
}

impl Log {
    pub fn new(datalink: Datalink) -> Log {
        Log {
            datalink,
            bytes: write::header(datalink),
            t_us: btsnoop::UNIX_EPOCH_US + 1_577_836_800_000_000,
            acl_mtu: 27,
        }
    }

    pub fn advance(&mut self, ms: u64) {
        self.t_us += ms as i64 * 1000;
    }

    /// One HCI packet: `kind` 1 command, 2 ACL, 4 event.
    pub fn hci(&mut self, kind: u8, way: Way, packet: &[u8]) {
        let received = (way == Way::Received) as u32;
        let (flags, data) = match self.datalink {
            Datalink::H4 => {
                let mut d = vec![kind];
                d.extend_from_slice(packet);
                (received | if kind == 2 { 0 } else { 2 }, d)
            }
            Datalink::H1 => (received | if kind == 2 { 0 } else { 2 }, packet.to_vec()),
            Datalink::Monitor => {
                let op = match (kind, way) {
                    (1, _) => 2,
                    (4, _) => 3,
                    (_, Way::Sent) => 4,
                    (_, Way::Received) => 5,
                };
                (op, packet.to_vec())
            }
        };
        self.bytes.extend(write::record(flags, self.t_us, &data));
    }

    pub fn le_connected(&mut self, handle: u16) {
        self.le_connected_to(handle, [0; 6]);
    }

    /// An LE Connection Complete from the peer at `addr` (as written, most significant first).
    pub fn le_connected_to(&mut self, handle: u16, addr: [u8; 6]) {
        let mut p = vec![0x3E, 19, 0x01, 0x00];
        p.extend(handle.to_le_bytes());
        // Role (central), peer address type (random), the address little-endian.
        p.extend([0x00, 0x01]);
        p.extend(addr.iter().rev());
        p.extend([0u8; 7]);
        self.hci(4, Way::Received, &p);
    }

    pub fn disconnected(&mut self, handle: u16, reason: u8) {
        let mut p = vec![0x05, 4, 0x00];
        p.extend(handle.to_le_bytes());
        p.push(reason);
        self.hci(4, Way::Received, &p);
    }

    /// An ATT PDU over L2CAP, cut into ACL fragments of `acl_mtu`.
    pub fn att(&mut self, handle: u16, way: Way, pdu: &[u8]) {
        let mut l2 = (pdu.len() as u16).to_le_bytes().to_vec();
        l2.extend(ATT_CID.to_le_bytes());
        l2.extend_from_slice(pdu);
        for (i, part) in l2.chunks(self.acl_mtu.max(1)).enumerate() {
            let pb: u16 = if i == 0 { 0b10 } else { 0b01 };
            let mut acl = (handle | (pb << 12)).to_le_bytes().to_vec();
            acl.extend((part.len() as u16).to_le_bytes());
            acl.extend_from_slice(part);
            self.hci(2, way, &acl);
        }
    }

    /// Characteristic discovery: a Read By Type request and its response declaring
    /// `chars` (value handle, UUID).
    pub fn declare(&mut self, handle: u16, chars: &[(u16, GattUuid)]) {
        self.att(
            handle,
            Way::Sent,
            &[0x08, 0x01, 0x00, 0xFF, 0xFF, 0x03, 0x28],
        );
        // One response per UUID size, as a server answers.
        for size in [2usize, 16] {
            let of_size: Vec<_> = chars
                .iter()
                .filter(|(_, u)| (u.as_u16().is_some()) == (size == 2))
                .collect();
            if of_size.is_empty() {
                continue;
            }
            let mut rsp = vec![0x09, (5 + size) as u8];
            for (h, u) in of_size {
                rsp.extend((h - 1).to_le_bytes());
                rsp.push(0x1A); // read, write without response, notify
                rsp.extend(h.to_le_bytes());
                match u.as_u16() {
                    Some(short) if size == 2 => rsp.extend(short.to_le_bytes()),
                    _ => rsp.extend(u.as_u128().to_le_bytes()),
                }
            }
            self.att(handle, Way::Received, &rsp);
        }
    }

    pub fn write_cmd(&mut self, handle: u16, att_handle: u16, value: &[u8]) {
        let mut p = vec![0x52];
        p.extend(att_handle.to_le_bytes());
        p.extend_from_slice(value);
        self.att(handle, Way::Sent, &p);
    }

    pub fn write_req(&mut self, handle: u16, att_handle: u16, value: &[u8]) {
        let mut p = vec![0x12];
        p.extend(att_handle.to_le_bytes());
        p.extend_from_slice(value);
        self.att(handle, Way::Sent, &p);
        self.att(handle, Way::Received, &[0x13]);
    }

    pub fn notify(&mut self, handle: u16, att_handle: u16, value: &[u8]) {
        let mut p = vec![0x1B];
        p.extend(att_handle.to_le_bytes());
        p.extend_from_slice(value);
        self.att(handle, Way::Received, &p);
    }

    pub fn read(&mut self, handle: u16, att_handle: u16, value: &[u8]) {
        let mut p = vec![0x0A];
        p.extend(att_handle.to_le_bytes());
        self.att(handle, Way::Sent, &p);
        let mut r = vec![0x0B];
        r.extend_from_slice(value);
        self.att(handle, Way::Received, &r);
    }
}
