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
    /// Which connection of the log it is (from 1; 0 until it carries droid traffic or its
    /// Connection Complete is seen).
    serial: usize,
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
    /// The connection of each event pushed to `out`, in order (see [`Decoder::record_tagged`]).
    tags: Vec<usize>,
    /// Each connection's peer address, when its Connection Complete was in the log (by serial).
    peers: BTreeMap<usize, [u8; 6]>,
    next_serial: usize,
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
            tags: Vec::new(),
            peers: BTreeMap::new(),
            next_serial: 1,
        }
    }

    /// Most connections told apart (a bound on what a log can make us keep).
    pub const MAX_CONNECTIONS: usize = 4096;

    fn new_serial(&mut self) -> usize {
        let s = self.next_serial.min(Self::MAX_CONNECTIONS);
        self.next_serial = (self.next_serial + 1).min(Self::MAX_CONNECTIONS + 1);
        s
    }

    /// [`Decoder::record`], each event with the connection it came on (a serial from 1; see
    /// [`Decoder::peer`]).
    pub fn record_tagged(&mut self, r: &Record, out: &mut Vec<(usize, Timed)>) {
        let mut events = Vec::new();
        self.tags.clear();
        self.record(r, &mut events);
        out.extend(self.tags.drain(..).zip(events));
    }

    /// The peer address of connection `serial`, when the log holds its Connection Complete.
    pub fn peer(&self, serial: usize) -> Option<[u8; 6]> {
        self.peers.get(&serial).copied()
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
                    self.tags.push(c.serial);
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
                let serial = self.new_serial();
                // Role, peer address type, then the peer's address (little-endian).
                if let Some(a) = p.get(6..12) {
                    let mut addr = [0u8; 6];
                    addr.copy_from_slice(a);
                    addr.reverse();
                    // All zeros: a platform that hides addresses.
                    if addr != [0; 6] && self.peers.len() < Self::MAX_CONNECTIONS {
                        self.peers.insert(serial, addr);
                    }
                }
                self.conns.insert(
                    key,
                    Conn {
                        serial,
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
        if v.len() > super::MAX_CHUNK {
            self.warn(format!(
                "an ATT value of {} bytes on handle 0x{handle:04X} at {:.3} s: real chunks are at most 512 (the limit is {}); skipped",
                v.len(),
                at.as_secs_f64(),
                super::MAX_CHUNK
            ));
            return;
        }
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
        if self.conns.get(&conn).is_none_or(|c| c.serial == 0) {
            let serial = self.new_serial();
            self.conns.entry(conn).or_default().serial = serial;
        }
        let c = self.conns.entry(conn).or_default();
        let serial = c.serial;
        if !c.announced {
            c.announced = true;
            out.push(Timed {
                at: c.connected_at.unwrap_or(at),
                event: Event::Connect,
            });
            self.tags.push(serial);
        }
        out.push(Timed { at, event });
        self.tags.push(serial);
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
    let (decoder, events, warnings) = read_btsnoop(bytes, handles)?;
    Ok(capture_of(
        &decoder,
        events.into_iter().map(|(_, t)| t).collect(),
        warnings,
    ))
}

/// The droids of a btsnoop log kept apart: one capture per droid, told apart by connection
/// (a droid's reconnections, known by its address, stay one capture), each with a name for
/// people (its address, or `connection N`). In the order they first carried droid traffic.
pub fn captures_by_connection(
    bytes: &[u8],
    handles: &[u16],
) -> Result<Vec<(String, Capture)>, String> {
    let (decoder, events, warnings) = read_btsnoop(bytes, handles)?;
    // Group by peer address when known, else by connection.
    let mut groups: Vec<(String, Vec<Timed>)> = Vec::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    for (serial, t) in events {
        let key = match decoder.peer(serial) {
            Some(a) => crate::hex::spaced(&a).replace(' ', ":"),
            None => format!("connection {serial}"),
        };
        let i = *index.entry(key.clone()).or_insert_with(|| {
            groups.push((key, Vec::new()));
            groups.len() - 1
        });
        groups[i].1.push(t);
    }
    Ok(groups
        .into_iter()
        .map(|(name, events)| {
            let mut c = capture_of(&decoder, events, warnings.clone());
            c.header.droid = Some(name.clone());
            (name, c)
        })
        .collect())
}

/// Read a whole btsnoop log: the decoder, its tagged events in time order, the warnings.
type Read = (Decoder, Vec<(usize, Timed)>, Vec<String>);

fn read_btsnoop(bytes: &[u8], handles: &[u16]) -> Result<Read, String> {
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
                    d.record_tagged(&r, &mut events);
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
    events.sort_by_key(|(_, t)| t.at);
    Ok((decoder, events, warnings))
}

fn capture_of(decoder: &Decoder, events: Vec<Timed>, warnings: Vec<String>) -> Capture {
    let started = decoder
        .first_unix_us()
        .filter(|us| *us > 0)
        .map(|us| super::rfc3339(Duration::from_micros(us as u64)));
    Capture {
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
    }
}

pub mod build;

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

    #[test]
    fn several_droids_connections_are_kept_apart() {
        const A: [u8; 6] = [0xD5, 0x03, 0x52, 0x94, 0xF2, 0x06];
        const B: [u8; 6] = [0xDD, 0xA4, 0xD5, 0xAE, 0xBF, 0xBE];
        let mut log = Log::new(Datalink::H4);
        let wake = cmd::wake().to_packet(0).encode();
        let sleep = cmd::sleep().to_packet(1).encode();
        // Two R2s at once, their traffic interleaved; the first reconnects on a new handle.
        log.le_connected_to(0x0040, A);
        log.le_connected_to(0x0041, B);
        log.advance(10);
        for h in [0x0040, 0x0041] {
            log.declare(h, &[(API, v2g::V2_API), (DOS, v2g::V2_ANTI_DOS)]);
        }
        log.write_cmd(0x0040, API, &wake[..5]);
        log.write_cmd(0x0041, API, &sleep);
        log.write_cmd(0x0040, API, &wake[5..]);
        log.advance(10);
        log.disconnected(0x0040, 0x08);
        log.advance(10);
        log.le_connected_to(0x0042, A);
        log.declare(0x0042, &[(API, v2g::V2_API), (DOS, v2g::V2_ANTI_DOS)]);
        log.write_cmd(0x0042, API, &wake);
        let split = captures_by_connection(&log.bytes, &[]).unwrap();
        let names: Vec<&str> = split.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "D5 03 52 94 F2 06".replace(' ', ":"),
                "DD:A4:D5:AE:BF:BE".into()
            ]
        );
        let outs = |c: &Capture| -> Vec<u8> {
            c.events
                .iter()
                .filter_map(|t| match &t.event {
                    Event::Out(_, b) => Some(b.clone()),
                    _ => None,
                })
                .flatten()
                .collect()
        };
        // Each droid's bytes whole and alone; A's two connections are one droid.
        assert_eq!(outs(&split[0].1), [wake.clone(), wake.clone()].concat());
        assert_eq!(outs(&split[1].1), sleep);
        let connects = |c: &Capture| {
            c.events
                .iter()
                .filter(|t| t.event == Event::Connect)
                .count()
        };
        assert_eq!((connects(&split[0].1), connects(&split[1].1)), (2, 1));
        // The merged capture interleaves them (what one stream used to be).
        let merged = capture_from_btsnoop(&log.bytes, &[]).unwrap();
        assert_ne!(outs(&merged)[..wake.len()], wake[..]);
        // Without addresses (hidden by the platform), connections are told apart by handle.
        let mut log = Log::new(Datalink::H4);
        log.le_connected(0x0040);
        log.le_connected(0x0041);
        for h in [0x0040, 0x0041] {
            log.declare(h, &[(API, v2g::V2_API), (DOS, v2g::V2_ANTI_DOS)]);
            log.write_cmd(h, API, &wake);
        }
        let split = captures_by_connection(&log.bytes, &[]).unwrap();
        let names: Vec<&str> = split.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["connection 1", "connection 2"]);
    }
}
