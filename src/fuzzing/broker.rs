//! droidctl's own MQTT broker (issue 37): hostile clients' byte streams against it, in one
//! process on paused time (in-memory connections, each from this machine or another). Up to
//! 16 connections open, write raw bytes or well-formed packets made from the input (CONNECT
//! with any id and keep-alive, the bridge's own ids included; SUBSCRIBEs of up to 200
//! filters, `#` repeated; retained PUBLISHes up to 300 KiB), pause, read or never read, and
//! close. Whatever arrives: nothing panics; after every step the retained messages stay
//! within their count and byte budgets, what waits for clients within its byte budget, and
//! the connections within their limit; the bridge's own client id is never taken; once
//! every deadline has passed (the idle deadline, the write timeout) no connection is left
//! open, and a fresh client connects, subscribes and gets what is published.
//!
//! Input layout, per step until the input ends (at most 96 steps): an op byte (low 3 bits
//! the op, the rest its connection), then the op's bytes: open (a byte: bit 0 another
//! machine, bit 1 a small pipe), raw (a length-prefixed piece), packet (a kind byte and its
//! fields), pause (a byte: 100 ms steps), read, close.

use super::{Bytes, Target};
use crate::bridge::broker::limits::{
    ALL_QUEUES_BYTES, MAX_IDLE, MAX_RETAINED, RETAINED_BYTES, WRITE_TIMEOUT,
};
use crate::bridge::broker::wire::encode;
use crate::bridge::broker::{Access, Broker, OwnIds};
use bytes::BytesMut;
use rumqttc::mqttbytes::QoS;
use rumqttc::mqttbytes::v4::{
    Connect, ConnectReturnCode, Packet, Publish, Subscribe, SubscribeFilter,
};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt, DuplexStream};

pub const TARGET: Target = Target {
    name: "broker",
    run: run_input,
    dictionary: &[
        b"\x10\x0c\x00\x04MQTT\x04\x02\x00\x00\x00\x00",
        b"\x82",
        b"\x80",
        b"\x30",
        b"\x31",
        b"\xc0\x00",
        b"\xe0\x00",
        b"droidctl/D2-0001/cmd",
        b"own-0-D2-0001",
        b"#",
        b"+/+",
        b"\x00",
    ],
};

/// The bridge's own ids in the harness's broker.
const OWN: &str = "own-";

pub fn run_input(data: &[u8]) {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .expect("a runtime");
    rt.block_on(session(data));
}

/// A client's end of an in-memory connection.
struct Conn {
    io: DuplexStream,
}

fn open(b: &Broker, remote: bool, small: bool) -> Option<Conn> {
    let (mine, theirs) = tokio::io::duplex(if small { 256 } else { 64 << 10 });
    let peer = if remote {
        "198.51.100.7:4000"
    } else {
        "127.0.0.1:4000"
    };
    b.connect_stream(Box::new(theirs), peer.parse().ok()?)
        .ok()?;
    Some(Conn { io: mine })
}

/// Write within 1 s (a pipe the broker no longer reads does not hold the harness).
async fn write(c: &mut Conn, bytes: &[u8]) {
    let _ = tokio::time::timeout(Duration::from_secs(1), c.io.write_all(bytes)).await;
}

/// Read what is there within 100 ms.
async fn drain(c: &mut Conn) {
    let mut sink = vec![0u8; 64 << 10];
    while let Ok(Ok(n)) =
        tokio::time::timeout(Duration::from_millis(100), c.io.read(&mut sink)).await
    {
        if n == 0 {
            break;
        }
    }
}

/// The bridge keeps its connection: pinging, reading.
async fn keep(bridge: &mut Conn) {
    write(bridge, &encode(&Packet::PingReq)).await;
    drain(bridge).await;
}

/// A well-formed packet the input describes.
fn packet(b: &mut Bytes) -> Packet {
    match b.u8() % 6 {
        0 => {
            let id = String::from_utf8_lossy(b.piece()).into_owned();
            let mut c = Connect::new(id);
            c.keep_alive = b.u16();
            Packet::Connect(c)
        }
        1 => {
            let n = 1 + (b.u8() as usize % 200);
            let pattern = String::from_utf8_lossy(b.piece()).into_owned();
            let repeat = b.u8() & 1 == 1;
            let filters = (0..n).map(|i| {
                let f = if repeat || pattern.is_empty() {
                    if pattern.is_empty() {
                        "#".into()
                    } else {
                        pattern.clone()
                    }
                } else {
                    format!("{pattern}/{i}")
                };
                SubscribeFilter::new(f, QoS::AtMostOnce)
            });
            Packet::Subscribe(Subscribe::new_many(filters))
        }
        2 | 3 => {
            let topic = String::from_utf8_lossy(b.piece()).into_owned();
            let size = (b.u16() as usize % 300) << 10;
            let fill = b.u8();
            let mut p = Publish::new(topic, QoS::AtMostOnce, vec![fill; size]);
            p.retain = b.u8() & 1 == 1;
            Packet::Publish(p)
        }
        4 => Packet::PingReq,
        _ => Packet::Disconnect,
    }
}

/// The budgets hold now.
fn bounded(b: &Broker, when: &str) {
    let s = b.stats();
    assert!(s.retained <= MAX_RETAINED, "{when}: {s:?}");
    assert!(s.retained_bytes <= RETAINED_BYTES, "{when}: {s:?}");
    assert!(s.queued_bytes <= ALL_QUEUES_BYTES, "{when}: {s:?}");
    assert!(
        s.connections <= crate::bridge::broker::MAX_CONNECTIONS,
        "{when}: {s:?}"
    );
}

async fn session(data: &[u8]) {
    let own = OwnIds {
        prefix: OWN.into(),
        user: "droidctl-bridge".into(),
        password: "secret".into(),
    };
    let b = Broker::in_memory(Access {
        login: None,
        own: Some(own.clone()),
    });
    // The bridge's own connection, as the bridge makes it.
    let mut bridge = open(&b, false, false).expect("a slot");
    let mut c = Connect::new(format!("{OWN}0-D2-0001"));
    c.keep_alive = 5;
    c.set_login(&own.user, &own.password);
    write(&mut bridge, &encode(&Packet::Connect(c))).await;
    let mut conns: Vec<Option<Conn>> = Vec::new();
    let mut input = Bytes::new(data);
    let mut steps = 0;
    while !input.is_empty() && steps < 96 {
        steps += 1;
        let op = input.u8();
        let k = (op >> 3) as usize;
        let n = conns.len().max(1);
        match op & 7 {
            0 => {
                let how = input.u8();
                if conns.len() < 16 {
                    conns.push(open(&b, how & 1 == 1, how & 2 == 2));
                }
            }
            1 => {
                let piece = input.piece().to_vec();
                if let Some(Some(c)) = conns.get_mut(k % n) {
                    write(c, &piece).await;
                }
            }
            2 | 3 => {
                let p = encode(&packet(&mut input));
                if let Some(Some(c)) = conns.get_mut(k % n) {
                    write(c, &p).await;
                }
            }
            4 => {
                let mut left = Duration::from_millis(100 * u64::from(input.u8()));
                while !left.is_zero() {
                    let d = left.min(Duration::from_secs(2));
                    tokio::time::sleep(d).await;
                    left -= d;
                    keep(&mut bridge).await;
                }
            }
            5 => {
                if let Some(Some(c)) = conns.get_mut(k % n) {
                    drain(c).await;
                }
            }
            _ => {
                if let Some(c) = conns.get_mut(k % n) {
                    *c = None;
                }
            }
        }
        bounded(&b, "after a step");
        keep(&mut bridge).await;
    }
    // Every deadline past: nobody left but the bridge, which went on pinging.
    let all_past = MAX_IDLE + WRITE_TIMEOUT + Duration::from_secs(2);
    let mut waited = Duration::ZERO;
    while waited < all_past {
        tokio::time::sleep(Duration::from_secs(2)).await;
        waited += Duration::from_secs(2);
        keep(&mut bridge).await;
    }
    let s = b.stats();
    assert_eq!(s.connections, 1, "only the bridge's connection left: {s:?}");
    assert_eq!(s.clients, 1, "{s:?}");
    bounded(&b, "at the end");
    // A fresh client is served.
    let mut fresh = open(&b, false, false).expect("a slot after the deadlines");
    write(&mut fresh, &encode(&Packet::Connect(Connect::new("fresh")))).await;
    let s = Subscribe::new("fuzz/end", QoS::AtMostOnce);
    write(&mut fresh, &encode(&Packet::Subscribe(s))).await;
    let p = Publish::new("fuzz/end", QoS::AtMostOnce, b"ok".to_vec());
    write(&mut fresh, &encode(&Packet::Publish(p))).await;
    let mut buf = BytesMut::new();
    let mut got = Vec::new();
    while got.len() < 3 {
        match Packet::read(&mut buf, usize::MAX) {
            Ok(p) => got.push(p),
            Err(_) => {
                buf.reserve(4096);
                let n = tokio::time::timeout(Duration::from_secs(5), fresh.io.read_buf(&mut buf))
                    .await
                    .expect("the broker answers a fresh client")
                    .unwrap_or(0);
                assert!(n > 0, "the fresh client was closed: {got:?}");
            }
        }
    }
    assert!(
        matches!(&got[0], Packet::ConnAck(a) if a.code == ConnectReturnCode::Success),
        "{got:?}"
    );
    assert!(matches!(&got[1], Packet::SubAck(_)), "{got:?}");
    assert!(
        matches!(&got[2], Packet::Publish(p) if p.topic == "fuzz/end"),
        "{got:?}"
    );
}
