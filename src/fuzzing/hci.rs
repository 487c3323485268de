//! The HCI/ATT decoder behind `packet decode --btsnoop` and replay of phone logs, fed logs
//! whose framing is sound and whose content is not: HCI events, ACL fragments and ATT PDUs
//! made from the input, mixed with the GATT discovery, writes and notifications of a real
//! droid session (so the decoder gets past the discovery into the droid's traffic). Any log
//! decodes without panicking; counters agree (ATT PDUs come from ACL packets, droid values
//! from ATT PDUs, at most one of each per record); warnings stay bounded; events come out in
//! time order once sorted; `packet decode --btsnoop` prints only whole JSON lines with
//! `--json` and ends with its summary or one error.
//!
//! Input layout: the first byte picks the datalink, `--handle`, `--json` and the ACL
//! fragment size; then operations, each a byte and its arguments (see [`op`]).

use super::{Bytes, Target};
use crate::capture::btsnoop::{self, Datalink, Item, Reader};
use crate::capture::hci::build::{Log, Way};
use crate::capture::hci::{self, Decoder};
use crate::gatt::GattUuid;
use crate::model::Model;

pub const TARGET: Target = Target {
    name: "hci",
    run: run_input,
    dictionary: &[
        &[0xF0, 0x40, 0x00],
        &[0xF1, 0x40, 0x00, 0x13],
        &[0xF2, 0x40, 0x00, 0x03],
        &[0xF3, 0x40, 0x00],
        &[0xF4, 0x40, 0x00],
        &[0x52],
        &[0x1B],
        &[0x09, 0x07],
        &[0x16],
        &[0x18, 0x01],
        &[0x04, 0x00],
    ],
};

/// The droid characteristics a discovery may declare: every family's.
fn droid_uuids() -> Vec<GattUuid> {
    [Model::R2D2, Model::BB8, Model::Robi42]
        .into_iter()
        .flat_map(|m| crate::family::gatt_profile(m).characteristics())
        .map(|c| c.characteristic)
        .collect()
}

/// One operation of the input on the log.
///
/// - `F0 h`: LE connection complete for connection handle `h` (u16);
/// - `F1 h r`: disconnection complete, reason `r`;
/// - `F2 h n (a i)*n`: a discovery declaring `n` characteristics: value handle `a` (u16),
///   `i` an index into the droids' UUIDs (beyond them: a random 16-bit UUID);
/// - `F3 h a v` / `F4 h a v` / `F5 h a v` / `F6 h a v`: write command, write request,
///   notification, read of `a` with value `v` (a length-prefixed piece);
/// - `F7 h w p`: any ATT PDU `p`, sent (`w` even) or received;
/// - `F8 t`: time goes on `t` ms (u16); `F9 t`: the clock jumps to `t` µs (i64);
/// - anything else `k`: a raw record, flags from `k` and the next byte (the monitor's
///   adapter index in the high bits), its data a piece.
fn op(log: &mut Log, b: &mut Bytes, uuids: &[GattUuid]) {
    let code = b.u8();
    match code {
        0xF0 => log.le_connected(b.u16()),
        0xF1 => {
            let (h, r) = (b.u16(), b.u8());
            log.disconnected(h, r)
        }
        0xF2 => {
            let h = b.u16();
            let n = (b.u8() % 8) as usize;
            let chars: Vec<(u16, GattUuid)> = (0..n)
                .map(|_| {
                    // The declaration sits one handle below the value.
                    let at = b.u16().max(1);
                    let i = b.u8() as usize;
                    let uuid = uuids
                        .get(i)
                        .copied()
                        .unwrap_or_else(|| GattUuid::from_u16(b.u16()));
                    (at, uuid)
                })
                .collect();
            log.declare(h, &chars)
        }
        0xF3..=0xF6 => {
            let (h, a) = (b.u16(), b.u16());
            let v = b.piece();
            match code {
                0xF3 => log.write_cmd(h, a, v),
                0xF4 => log.write_req(h, a, v),
                0xF5 => log.notify(h, a, v),
                _ => log.read(h, a, v),
            }
        }
        0xF7 => {
            let (h, w) = (b.u16(), b.u8());
            let way = if w % 2 == 0 { Way::Sent } else { Way::Received };
            log.att(h, way, b.piece())
        }
        0xF8 => log.advance(b.u16() as u64),
        0xF9 => log.t_us = b.u64() as i64,
        k => {
            let flags = (k as u32 & 0x3F) | ((b.u8() as u32) << 16);
            let data = b.piece();
            log.bytes
                .extend(btsnoop::write::record(flags, log.t_us, data));
        }
    }
}

pub fn run_input(data: &[u8]) {
    let mut b = Bytes::new(data);
    let opts = b.u8();
    let datalink = [Datalink::H4, Datalink::H1, Datalink::Monitor][(opts % 3) as usize];
    let handles: &[u16] = if opts & 0x04 != 0 { &[0x0012] } else { &[] };
    let json = opts & 0x08 != 0;
    let mut log = Log::new(datalink);
    log.acl_mtu = 1 + (opts >> 4) as usize * 4;
    let uuids = droid_uuids();
    let mut ops = 0;
    while !b.is_empty() && ops < 4096 {
        op(&mut log, &mut b, &uuids);
        log.advance(1);
        ops += 1;
    }
    check_decoder(&log.bytes, datalink, handles);
    check_cli(&log.bytes, handles, json);
}

/// The decoder record by record, as `packet decode --btsnoop` and replay run it.
fn check_decoder(bytes: &[u8], datalink: Datalink, handles: &[u16]) {
    let mut reader = Reader::new();
    reader.feed(bytes);
    let mut d = Decoder::new(datalink, handles);
    let mut events = Vec::new();
    let mut records = 0u64;
    while let Some(item) = reader.next_item() {
        match item {
            Ok(Item::Header(h)) => assert_eq!(h.datalink, datalink),
            Ok(Item::Record(r)) => {
                let before = d.stats.clone();
                let n = events.len();
                d.record(&r, &mut events);
                records += 1;
                let s = &d.stats;
                assert_eq!(s.records, records);
                assert!(s.acl_packets - before.acl_packets <= 1);
                assert!(s.att_pdus - before.att_pdus <= 1);
                // A connect is announced with a connection's first droid value.
                assert!(
                    events.len() - n <= 2 * (s.droid_values - before.droid_values) as usize + 1
                );
            }
            Err(e) => panic!("a log written whole is damaged: {e}"),
        }
    }
    assert!(reader.finish().is_none());
    let s = &d.stats;
    assert!(s.acl_packets <= s.records);
    assert!(s.att_pdus <= s.acl_packets);
    assert!(d.warnings.len() <= 20, "{} warnings kept", d.warnings.len());
    events.sort_by_key(|t| t.at);
    match hci::capture_from_btsnoop(bytes, handles) {
        Ok(c) => assert_eq!(c.events, events),
        Err(e) => {
            assert!(events.is_empty(), "{e}");
            assert!(!e.is_empty());
        }
    }
}

/// `droidctl packet decode --btsnoop LOG [--json]`.
fn check_cli(bytes: &[u8], handles: &[u16], json: bool) {
    let mut out = Vec::new();
    let mut input: &[u8] = bytes;
    let result = crate::cli::packet::decode_btsnoop_reader(
        &mut input, "the log", None, handles, json, false, &mut out,
    );
    let text = String::from_utf8(out).expect("the output is UTF-8");
    if let Err(e) = &result {
        assert!(!e.message.is_empty());
    }
    assert!(
        text.ends_with('\n'),
        "the output ends with its summary line"
    );
    if json {
        for line in text.lines() {
            serde_json::from_str::<serde_json::Value>(line)
                .unwrap_or_else(|e| panic!("not a JSON line ({e}): {line}"));
        }
        let last = text.lines().last().unwrap_or("");
        assert!(last.starts_with("{\"summary\""), "{last}");
    } else {
        assert!(text.lines().any(|l| l.starts_with("summary: ")), "{text}");
    }
}
