//! From HCI snoop records to the droid's traffic: HCI packets (H1, H4 or the Linux monitor
//! format), ACL fragments reassembled into L2CAP PDUs, the ATT channel's writes, write
//! commands, notifications, indications and reads, and the GATT discovery that says which
//! ATT handle is which of the droid's characteristics (the families' GATT profiles, [`crate::family::Family::gatt_profile`]). Out come the
//! same timed [`Event`]s as a droidctl capture: connects, chunks out and in, disconnects.
//!
//! Handles are per connection; a phone that reconnects often skips the discovery, so a
//! connection without one uses the last discovery seen. A log that starts after the discovery
//! needs the handles given (`--handle`). Sans-IO: records in, events out.

use super::btsnoop::{self, Datalink, Record};
use super::{Capture, Event, Header, Timed};
use crate::gatt::{CharRole, Endpoint, GattUuid};
use crate::model::Protocol;
use std::collections::{BTreeMap, HashMap};
use std::time::Duration;

/// The L2CAP channel of ATT on LE.
pub const ATT_CID: u16 = 0x0004;
/// The GATT characteristic declaration type.
pub const CHARACTERISTIC: u16 = 0x2803;

/// What an ATT handle is to droidctl: a characteristic's role in its family's GATT profile,
/// or a handle given with `--handle`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// A characteristic of a family's droids.
    Of(Protocol, CharRole),
    /// Given with `--handle`: writes out, notifications in, family from the bytes.
    Given,
}

impl Role {
    pub fn family(self) -> Option<Protocol> {
        match self {
            Role::Of(p, _) => Some(p),
            Role::Given => None,
        }
    }
}

/// The role of a characteristic UUID, if it is one of the droids'.
pub fn role_of(uuid: GattUuid) -> Option<Role> {
    crate::family::role_of(uuid).map(|(f, r)| Role::Of(f.protocol(), r))
}

/// A UUID as ATT carries it: 2 or 16 bytes, little-endian.
pub fn uuid_from_le(b: &[u8]) -> Option<GattUuid> {
    match b.len() {
        2 => Some(GattUuid::from_u16(u16::from_le_bytes([b[0], b[1]]))),
        16 => {
            let mut a = [0u8; 16];
            a.copy_from_slice(b);
            Some(GattUuid::from_u128(u128::from_le_bytes(a)))
        }
        _ => None,
    }
}

fn le16(b: &[u8]) -> u16 {
    u16::from_le_bytes([b[0], b[1]])
}

/// One HCI packet of a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Hci<'a> {
    Command,
    Event(&'a [u8]),
    /// ACL data: adapter index, sent (host → controller), the packet without its type byte.
    Acl(u16, bool, &'a [u8]),
    Other,
}

fn classify(datalink: Datalink, r: &Record) -> Hci<'_> {
    let d = &r.data[..];
    match datalink {
        Datalink::H4 => match d.split_first() {
            Some((1, _)) => Hci::Command,
            Some((2, rest)) => Hci::Acl(0, !r.received(), rest),
            Some((4, rest)) => Hci::Event(rest),
            _ => Hci::Other,
        },
        Datalink::H1 => match (r.command_or_event(), r.received()) {
            (true, false) => Hci::Command,
            (true, true) => Hci::Event(d),
            (false, received) => Hci::Acl(0, !received, d),
        },
        Datalink::Monitor => {
            let index = (r.flags >> 16) as u16;
            match r.flags & 0xFFFF {
                2 => Hci::Command,
                3 => Hci::Event(d),
                4 => Hci::Acl(index, true, d),
                5 => Hci::Acl(index, false, d),
                _ => Hci::Other,
            }
        }
    }
}

/// A connection, by adapter index and connection handle.
type ConnKey = (u16, u16);

#[derive(Debug, Default)]
struct Conn {
    connected_at: Option<Duration>,
    /// A connect was emitted for it (it carried droid traffic).
    announced: bool,
    roles: HashMap<u16, Role>,
    /// The type asked by the last Read By Type request, each way.
    read_by_type: Option<GattUuid>,
    /// The handle of the last Read request.
    pending_read: Option<u16>,
    /// Prepared (long) writes waiting for their execute.
    prepared: Vec<(u16, u16, Vec<u8>)>,
}

/// Counters for the summary and for the hint when nothing was found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Stats {
    pub records: u64,
    pub acl_packets: u64,
    pub att_pdus: u64,
    /// ATT values on the droid's characteristics.
    pub droid_values: u64,
    /// ATT values on other handles: (writes, notifications) per handle.
    pub other_handles: BTreeMap<u16, (u64, u64)>,
    /// Malformed HCI, ACL, L2CAP or ATT packets (skipped).
    pub malformed: u64,
}

/// The HCI-to-droid-traffic decoder.
pub struct Decoder {
    datalink: Datalink,
    partial: HashMap<(u16, u16, bool), Vec<u8>>,
    conns: HashMap<ConnKey, Conn>,
    /// The last discovery seen, for connections without one.
    last_roles: HashMap<u16, Role>,
    given: Vec<u16>,
    first_us: Option<i64>,
    last_at: Duration,
    pub stats: Stats,
    /// What went wrong and was skipped (bounded).
    pub warnings: Vec<String>,
    family: Option<Protocol>,
}

const MAX_WARNINGS: usize = 20;

impl Decoder {
    /// `given`: the droid's ATT handles when the log has no discovery.
    pub fn new(datalink: Datalink, given: &[u16]) -> Decoder {
        Decoder {
            datalink,
            partial: HashMap::new(),
            conns: HashMap::new(),
            last_roles: HashMap::new(),
            given: given.to_vec(),
            first_us: None,
            last_at: Duration::ZERO,
            stats: Stats::default(),
            warnings: Vec::new(),
            family: None,
        }
    }

    /// The family of the droid characteristics found, if any.
    pub fn family(&self) -> Option<Protocol> {
        self.family
    }

    /// Microseconds since 1970 of the first record.
    pub fn first_unix_us(&self) -> Option<i64> {
        self.first_us
    }

    fn warn(&mut self, text: String) {
        self.stats.malformed += 1;
        if self.warnings.len() < MAX_WARNINGS {
            self.warnings.push(text);
        }
    }

    /// Decode one record; what it carried of the droid's is appended to `out`.
    pub fn record(&mut self, r: &Record, out: &mut Vec<Timed>) {
        self.stats.records += 1;
        let us = r.unix_us();
        let first = *self.first_us.get_or_insert(us);
        // Records may step back a little (clock adjustments): time never goes back here.
        let at = Duration::from_micros(us.saturating_sub(first).max(0) as u64).max(self.last_at);
        self.last_at = at;
        match classify(self.datalink, r) {
            Hci::Event(e) => self.event(at, e, r.offset, out),
            Hci::Acl(index, sent, d) => self.acl(at, index, sent, d, r.offset, out),
            Hci::Command | Hci::Other => {}
        }
    }

    fn event(&mut self, at: Duration, e: &[u8], offset: u64, out: &mut Vec<Timed>) {
        let (Some(&code), Some(&len)) = (e.first(), e.get(1)) else {
            return self.warn(format!(
                "record at offset {offset}: an HCI event of {} byte(s)",
                e.len()
            ));
        };
        let p = &e[2..];
        if p.len() < len as usize {
            return self.warn(format!(
                "record at offset {offset}: HCI event 0x{code:02X} says {len} parameter bytes, has {}",
                p.len()
            ));
        }
        match code {
            // Disconnection Complete: status, handle, reason.
            0x05 if p.len() >= 4 && p[0] == 0 => {
                let key = (0, le16(&p[1..3]) & 0x0FFF);
                if let Some(c) = self.conns.remove(&key)
                    && c.announced
                {
                    out.push(Timed {
                        at,
                        event: Event::Disconnect(disconnect_reason(p[3])),
                    });
                }
                self.partial.retain(|k, _| (k.0, k.1) != key);
            }
            // LE Meta: (Enhanced) Connection Complete: status, handle.
            0x3E if p.len() >= 4 && matches!(p[0], 0x01 | 0x0A | 0x29) && p[1] == 0 => {
                let key = (0, le16(&p[2..4]) & 0x0FFF);
                self.conns.insert(
                    key,
                    Conn {
                        connected_at: Some(at),
                        ..Conn::default()
                    },
                );
            }
            _ => {}
        }
    }

    fn acl(
        &mut self,
        at: Duration,
        index: u16,
        sent: bool,
        d: &[u8],
        offset: u64,
        out: &mut Vec<Timed>,
    ) {
        if d.len() < 4 {
            return self.warn(format!(
                "record at offset {offset}: an ACL packet of {} byte(s)",
                d.len()
            ));
        }
        self.stats.acl_packets += 1;
        let hf = le16(&d[0..2]);
        let handle = hf & 0x0FFF;
        let pb = (hf >> 12) & 0x3;
        let len = le16(&d[2..4]) as usize;
        let Some(payload) = d.get(4..4 + len) else {
            return self.warn(format!(
                "record at offset {offset}: ACL data length {len}, {} byte(s) there",
                d.len() - 4
            ));
        };
        let key = (index, handle, sent);
        let pdu = match pb {
            // A continuation.
            0b01 => {
                let Some(buf) = self.partial.get_mut(&key) else {
                    return self.warn(format!(
                        "record at offset {offset}: an ACL continuation without its start (handle 0x{handle:03X})"
                    ));
                };
                buf.extend_from_slice(payload);
                buf
            }
            // The start of a PDU (or a whole one).
            _ => {
                if self.partial.contains_key(&key) {
                    self.warn(format!(
                        "record at offset {offset}: a new L2CAP PDU before the last one was complete (handle 0x{handle:03X})"
                    ));
                }
                self.partial.insert(key, payload.to_vec());
                self.partial.get_mut(&key).expect("just inserted")
            }
        };
        if pdu.len() < 4 {
            return;
        }
        let l2len = le16(&pdu[0..2]) as usize;
        if pdu.len() < 4 + l2len {
            return;
        }
        let mut pdu = self.partial.remove(&key).unwrap_or_default();
        pdu.truncate(4 + l2len);
        let cid = le16(&pdu[2..4]);
        if cid == ATT_CID {
            self.stats.att_pdus += 1;
            self.att(at, (index, handle), &pdu[4..], out);
        }
    }

    /// The roles in effect on a connection: its own discovery, the last one, `--handle`.
    fn role(&self, conn: ConnKey, handle: u16) -> Option<Role> {
        if self.given.contains(&handle) {
            return Some(Role::Given);
        }
        let c = self.conns.get(&conn);
        match c.filter(|c| !c.roles.is_empty()) {
            Some(c) => c.roles.get(&handle).copied(),
            None => self.last_roles.get(&handle).copied(),
        }
    }

    fn discovered(&mut self, conn: ConnKey, handle: u16, uuid: GattUuid) {
        if let Some(role) = role_of(uuid) {
            self.family = self.family.or(role.family());
            self.conns
                .entry(conn)
                .or_default()
                .roles
                .insert(handle, role);
            self.last_roles.insert(handle, role);
        }
    }

    /// A value on `handle`: a write (`write` true) or a notification/read.
    fn value(
        &mut self,
        at: Duration,
        conn: ConnKey,
        handle: u16,
        write: bool,
        v: &[u8],
        out: &mut Vec<Timed>,
    ) {
        let Some(role) = self.role(conn, handle) else {
            let e = self.stats.other_handles.entry(handle).or_default();
            if write {
                e.0 += 1;
            } else {
                e.1 += 1;
            }
            return;
        };
        let role = match role {
            Role::Of(_, r) => r,
            // A handle given by hand is read as a command channel.
            Role::Given => CharRole::Channel,
        };
        let event = match (role, write) {
            (CharRole::Channel, true) => Event::Out(Endpoint::Api, v.to_vec()),
            (CharRole::Channel | CharRole::ReadValue, false) => Event::In(v.to_vec()),
            (CharRole::Input(e), true) => Event::Out(e, v.to_vec()),
            (CharRole::Setup(name), _) => {
                let shown = if v.iter().all(|b| b.is_ascii_graphic()) && !v.is_empty() {
                    format!("{:?}", String::from_utf8_lossy(v))
                } else {
                    crate::hex::spaced(v)
                };
                Event::Mark(format!(
                    "{name}: {} {shown}",
                    if write { "wrote" } else { "read" }
                ))
            }
            (CharRole::ReadValue | CharRole::Input(_), _) => return,
        };
        self.stats.droid_values += 1;
        let c = self.conns.entry(conn).or_default();
        if !c.announced {
            c.announced = true;
            out.push(Timed {
                at: c.connected_at.unwrap_or(at),
                event: Event::Connect,
            });
        }
        out.push(Timed { at, event });
    }

    fn att(&mut self, at: Duration, conn: ConnKey, pdu: &[u8], out: &mut Vec<Timed>) {
        let Some((&op, p)) = pdu.split_first() else {
            return;
        };
        match op {
            // Write Request, Write Command.
            0x12 | 0x52 if p.len() >= 2 => self.value(at, conn, le16(p), true, &p[2..], out),
            // Signed Write Command: 12 bytes of signature at the end.
            0xD2 if p.len() >= 14 => self.value(at, conn, le16(p), true, &p[2..p.len() - 12], out),
            // Handle Value Notification, Indication.
            0x1B | 0x1D if p.len() >= 2 => self.value(at, conn, le16(p), false, &p[2..], out),
            // Read Request, Read Response.
            0x0A if p.len() >= 2 => {
                self.conns.entry(conn).or_default().pending_read = Some(le16(p))
            }
            0x0B => {
                if let Some(h) = self.conns.entry(conn).or_default().pending_read.take() {
                    self.value(at, conn, h, false, p, out);
                }
            }
            // Prepare Write Request: handle, offset, part; Execute Write Request: flags.
            0x16 if p.len() >= 4 => {
                let part = (le16(p), le16(&p[2..4]), p[4..].to_vec());
                self.conns.entry(conn).or_default().prepared.push(part);
            }
            0x18 if !p.is_empty() => {
                let mut parts = std::mem::take(&mut self.conns.entry(conn).or_default().prepared);
                if p[0] == 1 {
                    parts.sort_by_key(|(h, o, _)| (*h, *o));
                    let mut joined: BTreeMap<u16, Vec<u8>> = BTreeMap::new();
                    for (h, _, part) in parts {
                        joined.entry(h).or_default().extend(part);
                    }
                    for (h, v) in joined {
                        self.value(at, conn, h, true, &v, out);
                    }
                }
            }
            // Read By Type Request: start, end, type.
            0x08 if p.len() >= 6 => {
                self.conns.entry(conn).or_default().read_by_type = uuid_from_le(&p[4..]);
            }
            // Read By Type Response: length, then (handle, value) of that length.
            0x09 if !p.is_empty() => {
                let asked = self.conns.entry(conn).or_default().read_by_type;
                let len = p[0] as usize;
                let is_decl = match asked {
                    Some(t) => t == GattUuid::from_u16(CHARACTERISTIC),
                    None => len == 7 || len == 21,
                };
                if len < 2 || !is_decl {
                    return;
                }
                for entry in p[1..].chunks_exact(len) {
                    // Declaration: properties, value handle, UUID.
                    if let (Some(handle), Some(uuid)) = (
                        entry.get(3..5).map(le16),
                        entry.get(5..).and_then(uuid_from_le),
                    ) {
                        self.discovered(conn, handle, uuid);
                    }
                }
            }
            // Find Information Response: format (1: 16-bit, 2: 128-bit), (handle, type)s.
            0x05 if !p.is_empty() => {
                let size = match p[0] {
                    1 => 2,
                    2 => 16,
                    _ => return,
                };
                for entry in p[1..].chunks_exact(2 + size) {
                    if let Some(uuid) = uuid_from_le(&entry[2..]) {
                        self.discovered(conn, le16(entry), uuid);
                    }
                }
            }
            _ => {}
        }
    }
}

/// A disconnection reason for people (the common HCI error codes).
pub fn disconnect_reason(code: u8) -> String {
    let what = match code {
        0x08 => "connection timeout",
        0x13 => "the remote device ended the connection",
        0x14 => "the remote device ended the connection (low resources)",
        0x15 => "the remote device ended the connection (power off)",
        0x16 => "the host ended the connection",
        0x22 | 0x28 => "LL response timeout",
        0x3B => "unacceptable connection parameters",
        0x3D => "MIC failure",
        0x3E => "the connection failed to be established",
        _ => "disconnected",
    };
    format!("{what} (HCI reason 0x{code:02X})")
}

/// The hint for a log with no droid traffic found: the handles that carried values.
pub fn no_traffic_hint(stats: &Stats) -> String {
    if stats.other_handles.is_empty() {
        return format!(
            "no ATT writes or notifications in {} records: is this the log of a session with the droid?",
            stats.records
        );
    }
    let handles: Vec<String> = stats
        .other_handles
        .iter()
        .map(|(h, (w, n))| format!("0x{h:04X} ({w} writes, {n} notifications)"))
        .collect();
    format!(
        "no GATT discovery of a droid in the log (it may have started after the phone discovered the droid); ATT values went to {}: give the droid's with --handle N",
        handles.join(", ")
    )
}

/// A whole btsnoop log as a capture: the droid's traffic in it, with the damage (if any)
/// among the warnings. An unreadable header or no droid traffic at all is an error.
pub fn capture_from_btsnoop(bytes: &[u8], handles: &[u16]) -> Result<Capture, String> {
    let mut reader = btsnoop::Reader::new();
    reader.feed(bytes);
    let mut decoder: Option<Decoder> = None;
    let mut events = Vec::new();
    let mut warnings = Vec::new();
    let mut damage = None;
    while let Some(item) = reader.next_item() {
        match item {
            Ok(btsnoop::Item::Header(h)) => decoder = Some(Decoder::new(h.datalink, handles)),
            Ok(btsnoop::Item::Record(r)) => {
                if let Some(d) = decoder.as_mut() {
                    d.record(&r, &mut events);
                }
            }
            Err(e) => {
                damage = Some(e);
                break;
            }
        }
    }
    let damage = damage.or_else(|| reader.finish());
    let Some(decoder) = decoder else {
        return Err(damage.map_or_else(|| "an empty btsnoop log".to_string(), |e| e.to_string()));
    };
    if let Some(e) = damage {
        warnings.push(format!(
            "the log is damaged ({e}); the {} record(s) before it are read",
            reader.records()
        ));
    }
    warnings.extend(decoder.warnings.iter().cloned());
    if events.is_empty() {
        return Err(no_traffic_hint(&decoder.stats));
    }
    // Connects are emitted late (at the first droid value) with their own earlier time.
    events.sort_by_key(|t| t.at);
    let started = decoder
        .first_unix_us()
        .filter(|us| *us > 0)
        .map(|us| super::rfc3339(Duration::from_micros(us as u64)));
    Ok(Capture {
        header: Header {
            droidctl: None,
            model: None,
            family: decoder.family(),
            droid: None,
            started,
        },
        events,
        warnings,
        kind: "btsnoop log",
    })
}

/// Building HCI traffic as a phone logs it, for tests and fixtures: a droid connected, its
/// GATT discovered, values written and notified, each as a btsnoop record.
pub mod build {
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
            let mut p = vec![0x3E, 19, 0x01, 0x00];
            p.extend(handle.to_le_bytes());
            p.extend([0u8; 15]);
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
}

#[cfg(test)]
mod tests {
    use super::build::{Log, Way};
    use super::*;
    use crate::family::robi::gatt as robig;
    use crate::family::v1::gatt as v1g;
    use crate::family::v2::gatt as v2g;
    use crate::protocol::v2::{ErrorCode, Packet, cmd};

    const CONN: u16 = 0x0040;
    const API: u16 = 0x000E;
    const DOS: u16 = 0x0013;

    fn v2_session(datalink: Datalink) -> (Log, Vec<u8>, Vec<u8>) {
        let mut log = Log::new(datalink);
        log.le_connected(CONN);
        log.advance(50);
        log.declare(CONN, &[(API, v2g::V2_API), (DOS, v2g::V2_ANTI_DOS)]);
        log.write_req(CONN, DOS, v2g::V2_UNLOCK);
        log.advance(10);
        // A 20-byte-plus command cut into ACL fragments.
        let wake = cmd::wake().to_packet(0).encode();
        log.write_cmd(CONN, API, &wake);
        log.advance(12);
        let resp =
            Packet::response_to(&cmd::wake().to_packet(0), ErrorCode::Success, vec![]).encode();
        log.notify(CONN, API, &resp);
        log.advance(100);
        log.disconnected(CONN, 0x13);
        (log, wake, resp)
    }

    #[test]
    fn each_datalink_yields_the_droid_traffic() {
        for dl in [Datalink::H4, Datalink::H1, Datalink::Monitor] {
            let (log, wake, resp) = v2_session(dl);
            let c = capture_from_btsnoop(&log.bytes, &[]).unwrap();
            assert!(c.warnings.is_empty(), "{dl:?}: {:?}", c.warnings);
            assert_eq!(c.header.family, Some(Protocol::SpheroV2));
            let events: Vec<&Event> = c.events.iter().map(|t| &t.event).collect();
            assert_eq!(events[0], &Event::Connect, "{dl:?}");
            assert!(
                matches!(events[1], Event::Mark(m) if m.contains("usetheforce...band")),
                "{events:?}"
            );
            assert_eq!(events[2], &Event::Out(Endpoint::Api, wake.clone()));
            assert_eq!(events[3], &Event::In(resp.clone()));
            assert!(matches!(events[4], Event::Disconnect(r) if r.contains("0x13")));
            assert_eq!(c.events[3].at, Duration::from_millis(72));
        }
    }

    #[test]
    fn fragments_are_reassembled_at_any_size() {
        for mtu in [5, 9, 27, 251] {
            let mut log = Log::new(Datalink::H4);
            log.acl_mtu = mtu;
            log.declare(CONN, &[(API, v2g::V2_API)]);
            let long = cmd::set_all_leds_with_16_bit_mask(
                crate::protocol::v2::wire::Mask(0xFFFF),
                crate::protocol::v2::wire::Bytes(vec![0x8D; 16]),
            )
            .to_packet(3)
            .encode();
            log.write_cmd(CONN, API, &long);
            let c = capture_from_btsnoop(&log.bytes, &[]).unwrap();
            assert_eq!(
                c.events[1].event,
                Event::Out(Endpoint::Api, long),
                "mtu {mtu}"
            );
        }
    }

    #[test]
    fn find_information_discovers_too_and_handles_can_be_given() {
        let mut log = Log::new(Datalink::H4);
        // Find Information response, 128-bit format: the v1 characteristics.
        let mut rsp = vec![0x05, 0x02];
        for (h, u) in [(0x0E, v1g::V1_COMMANDS), (0x10, v1g::V1_RESPONSES)] {
            rsp.extend((h as u16).to_le_bytes());
            rsp.extend(u.as_u128().to_le_bytes());
        }
        log.att(CONN, Way::Received, &rsp);
        let ping = [0xFF, 0xFF, 0x00, 0x01, 0x00, 0x01, 0xFD];
        log.write_cmd(CONN, 0x0E, &ping);
        let c = capture_from_btsnoop(&log.bytes, &[]).unwrap();
        assert_eq!(c.header.family, Some(Protocol::SpheroV1));
        assert_eq!(c.events[1].event, Event::Out(Endpoint::Api, ping.to_vec()));

        // Without the discovery: a hint naming the handles, or --handle.
        let mut late = Log::new(Datalink::H4);
        late.write_cmd(CONN, 0x0E, &ping);
        let e = capture_from_btsnoop(&late.bytes, &[]).unwrap_err();
        assert!(
            e.contains("0x000E (1 writes, 0 notifications)") && e.contains("--handle"),
            "{e}"
        );
        let c = capture_from_btsnoop(&late.bytes, &[0x0E]).unwrap();
        assert_eq!(c.family(), Some(Protocol::SpheroV1));
    }

    #[test]
    fn robi_reads_and_inputs() {
        let mut log = Log::new(Datalink::Monitor);
        log.declare(
            CONN,
            &[
                (0x20, robig::ROBI_HANDSHAKE),
                (0x22, robig::ROBI_FRAMES),
                (0x30, robig::ROBI_VELOCITY),
                (0x32, robig::ROBI_STEERING),
            ],
        );
        log.read(CONN, 0x20, &[0x7E, 0x01, 0x00, 0x0A, 0x7F]);
        log.write_cmd(CONN, 0x30, &[200]);
        log.write_cmd(CONN, 0x32, &[128]);
        let c = capture_from_btsnoop(&log.bytes, &[]).unwrap();
        assert_eq!(c.header.family, Some(Protocol::Rsrcp));
        let ev: Vec<_> = c.events.iter().map(|t| t.event.clone()).collect();
        assert_eq!(
            ev[1..],
            [
                Event::In(vec![0x7E, 0x01, 0x00, 0x0A, 0x7F]),
                Event::Out(Endpoint::Velocity, vec![200]),
                Event::Out(Endpoint::Steering, vec![128]),
            ]
        );
    }

    #[test]
    fn damage_keeps_what_came_before() {
        let (log, _, _) = v2_session(Datalink::H4);
        let cut = &log.bytes[..log.bytes.len() - 5];
        let c = capture_from_btsnoop(cut, &[]).unwrap();
        assert!(
            c.warnings[0].contains("truncated at offset"),
            "{:?}",
            c.warnings
        );
        assert!(c.events.iter().any(|t| matches!(t.event, Event::In(_))));
        let e = capture_from_btsnoop(b"btsnoop\0\0\0\0\x02\0\0\x03\xea", &[]).unwrap_err();
        assert!(e.contains("bad_version"), "{e}");
        // A malformed ACL length is skipped with a warning.
        let mut log = Log::new(Datalink::H4);
        log.hci(2, Way::Received, &[0x40, 0x20, 0xFF, 0x00, 1, 2]);
        log.declare(CONN, &[(API, v2g::V2_API)]);
        log.notify(CONN, API, &[0x8D]);
        let c = capture_from_btsnoop(&log.bytes, &[]).unwrap();
        assert!(
            c.warnings.iter().any(|w| w.contains("ACL data length 255")),
            "{:?}",
            c.warnings
        );
    }
}
