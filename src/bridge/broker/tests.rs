//! The broker: its MQTT over real sockets (a rumqttc client against it), and under hostile
//! input (issue 37) over in-memory connections on paused time, each from the address a test
//! says (another machine, or this one).

use super::*;
use rumqttc::mqttbytes::v4::{Subscribe, SubscribeFilter, SubscribeReasonCode};
use rumqttc::{AsyncClient, Event, MqttOptions};
use tokio::io::{AsyncReadExt, AsyncWriteExt, DuplexStream};

async fn client(addr: SocketAddr, id: &str) -> (AsyncClient, rumqttc::EventLoop) {
    let mut o = MqttOptions::new(id, addr.ip().to_string(), addr.port());
    o.set_keep_alive(Duration::from_secs(5));
    AsyncClient::new(o, 64)
}

/// The next PUBLISH the event loop receives.
async fn next_publish(el: &mut rumqttc::EventLoop) -> Publish {
    loop {
        match tokio::time::timeout(Duration::from_secs(5), el.poll()).await {
            Ok(Ok(Event::Incoming(Packet::Publish(p)))) => return p,
            Ok(Ok(_)) => {}
            other => panic!("no publish: {other:?}"),
        }
    }
}

async fn until_suback(el: &mut rumqttc::EventLoop) {
    loop {
        if let Event::Incoming(Packet::SubAck(_)) = el.poll().await.unwrap() {
            return;
        }
    }
}

#[tokio::test]
async fn retained_wildcards_qos_and_wills() {
    let b = start("127.0.0.1:0".parse().unwrap(), Access::default())
        .await
        .unwrap();
    let (pubc, mut pub_el) = client(b.addr(), "pub").await;
    pubc.publish("a/x/state", QoS::AtLeastOnce, true, "kept")
        .await
        .unwrap();
    // Drive the publisher until its PUBACK.
    loop {
        if let Event::Incoming(Packet::PubAck(_)) = pub_el.poll().await.unwrap() {
            break;
        }
    }
    let pub_task = tokio::spawn(async move {
        loop {
            if pub_el.poll().await.is_err() {
                break;
            }
        }
    });
    let (sub, mut el) = client(b.addr(), "sub").await;
    sub.subscribe("a/+/state", QoS::ExactlyOnce).await.unwrap();
    until_suback(&mut el).await;
    let p = next_publish(&mut el).await;
    assert_eq!(
        (p.topic.as_str(), &p.payload[..], p.retain, p.qos),
        ("a/x/state", &b"kept"[..], true, QoS::AtLeastOnce)
    );
    pubc.publish("a/y/state", QoS::ExactlyOnce, false, "live")
        .await
        .unwrap();
    pubc.publish("b/y/state", QoS::AtMostOnce, false, "other")
        .await
        .unwrap();
    let p = next_publish(&mut el).await;
    assert_eq!(
        (p.topic.as_str(), &p.payload[..], p.retain, p.qos),
        ("a/y/state", &b"live"[..], false, QoS::ExactlyOnce)
    );
    // A client that goes without DISCONNECT leaves its will.
    let mut o = MqttOptions::new("dies", "127.0.0.1", b.addr().port());
    o.set_last_will(rumqttc::LastWill::new(
        "a/dies/state",
        "offline",
        QoS::AtLeastOnce,
        true,
    ));
    let (_dies, mut dies_el) = AsyncClient::new(o, 8);
    loop {
        if let Event::Incoming(Packet::ConnAck(_)) = dies_el.poll().await.unwrap() {
            break;
        }
    }
    drop(dies_el);
    let p = next_publish(&mut el).await;
    assert_eq!(
        (p.topic.as_str(), &p.payload[..]),
        ("a/dies/state", &b"offline"[..])
    );
    pub_task.abort();
}

#[tokio::test]
async fn a_wrong_password_is_refused() {
    let b = start(
        "127.0.0.1:0".parse().unwrap(),
        Access {
            login: Some(("u".into(), "right".into())),
            ..Access::default()
        },
    )
    .await
    .unwrap();
    let mut o = MqttOptions::new("c", "127.0.0.1", b.addr().port());
    o.set_credentials("u", "wrong");
    let (_c, mut el) = AsyncClient::new(o, 8);
    match el.poll().await {
        Err(rumqttc::ConnectionError::ConnectionRefused(code)) => {
            assert_eq!(code, ConnectReturnCode::BadUserNamePassword)
        }
        other => panic!("{other:?}"),
    }
    let mut o = MqttOptions::new("c", "127.0.0.1", b.addr().port());
    o.set_credentials("u", "right");
    let (_c, mut el) = AsyncClient::new(o, 8);
    assert!(matches!(
        el.poll().await,
        Ok(Event::Incoming(Packet::ConnAck(ConnAck {
            code: ConnectReturnCode::Success,
            ..
        })))
    ));
}

#[tokio::test]
async fn malformed_bytes_close_the_connection_not_the_broker() {
    let b = start("127.0.0.1:0".parse().unwrap(), Access::default())
        .await
        .unwrap();
    let mut raw = tokio::net::TcpStream::connect(b.addr()).await.unwrap();
    raw.write_all(&[0xF0, 0xFF, 0xFF, 0xFF, 0xFF, 0x7F])
        .await
        .unwrap();
    let mut sink = Vec::new();
    let n = tokio::time::timeout(Duration::from_secs(5), raw.read_to_end(&mut sink))
        .await
        .expect("closed")
        .unwrap_or(0);
    assert_eq!(n, 0, "nothing answered to garbage");
    // Still serving.
    let (_c, mut el) = client(b.addr(), "after").await;
    assert!(matches!(
        el.poll().await,
        Ok(Event::Incoming(Packet::ConnAck(_)))
    ));
}

// ---- Hostile input, in memory, on paused time ----

pub(crate) const LOOPBACK: &str = "127.0.0.1:50000";
pub(crate) const ELSEWHERE: &str = "198.51.100.7:50000";

/// A client's end of an in-memory connection, speaking raw MQTT.
pub(crate) struct Raw {
    io: DuplexStream,
    buf: BytesMut,
}

impl Raw {
    /// A connection from `peer` with `capacity` bytes of pipe each way; `None` if refused.
    pub(crate) fn open(b: &Broker, peer: &str, capacity: usize) -> Option<Raw> {
        let (mine, theirs) = tokio::io::duplex(capacity);
        b.connect_stream(Box::new(theirs), peer.parse().unwrap())
            .ok()?;
        Some(Raw {
            io: mine,
            buf: BytesMut::new(),
        })
    }

    pub(crate) async fn send_bytes(&mut self, bytes: &[u8]) -> bool {
        self.io.write_all(bytes).await.is_ok()
    }

    pub(crate) async fn send(&mut self, p: &Packet) -> bool {
        self.send_bytes(&wire::encode(p)).await
    }

    /// The next packet within 5 s; `None`: closed (or nothing came).
    pub(crate) async fn recv(&mut self) -> Option<Packet> {
        loop {
            if let Ok(p) = Packet::read(&mut self.buf, usize::MAX) {
                return Some(p);
            }
            self.buf.reserve(4096);
            let n = tokio::time::timeout(Duration::from_secs(5), self.io.read_buf(&mut self.buf))
                .await
                .ok()?
                .ok()?;
            if n == 0 {
                return None;
            }
        }
    }

    /// Whether the broker closed the connection (reading what it still sends).
    pub(crate) async fn closed(&mut self) -> bool {
        let mut sink = [0u8; 4096];
        loop {
            match tokio::time::timeout(Duration::from_secs(1), self.io.read(&mut sink)).await {
                Ok(Ok(0)) | Ok(Err(_)) => return true,
                Ok(Ok(_)) => {}
                Err(_) => return false,
            }
        }
    }

    /// CONNECT as `id` with `keep_alive` s; the CONNACK's code.
    pub(crate) async fn connect(&mut self, id: &str, keep_alive: u16) -> Option<ConnectReturnCode> {
        let mut c = Connect::new(id);
        c.keep_alive = keep_alive;
        self.connect_with(c).await
    }

    pub(crate) async fn connect_with(&mut self, c: Connect) -> Option<ConnectReturnCode> {
        self.send(&Packet::Connect(c)).await;
        match self.recv().await? {
            Packet::ConnAck(a) => Some(a.code),
            _ => None,
        }
    }

    pub(crate) async fn subscribe(&mut self, filters: &[&str]) -> Option<Vec<SubscribeReasonCode>> {
        let s = Subscribe::new_many(
            filters
                .iter()
                .map(|f| SubscribeFilter::new(f.to_string(), QoS::AtMostOnce)),
        );
        self.send(&Packet::Subscribe(s)).await;
        match self.recv().await? {
            Packet::SubAck(a) => Some(a.return_codes),
            _ => None,
        }
    }

    pub(crate) async fn publish(&mut self, topic: &str, payload: &[u8], retain: bool) -> bool {
        let mut p = Publish::new(topic, QoS::AtMostOnce, payload.to_vec());
        p.retain = retain;
        self.send(&Packet::Publish(p)).await
    }
}

/// A connected client from this machine.
async fn connected(b: &Broker, id: &str) -> Raw {
    let mut c = Raw::open(b, LOOPBACK, 1 << 20).expect("a slot");
    assert_eq!(c.connect(id, 30).await, Some(ConnectReturnCode::Success));
    c
}

/// Whether `c` gets a PUBLISH on `topic` (reading past anything else).
async fn gets(c: &mut Raw, topic: &str) -> bool {
    while let Some(p) = c.recv().await {
        if let Packet::Publish(p) = p
            && p.topic == topic
        {
            return true;
        }
    }
    false
}

/// Issue 37 point 1: one SUBSCRIBE of 120,000 filters (1.7 MB) is refused at its header,
/// unread; one of more than 64 filters closes its connection; either way the others are
/// served at once.
#[tokio::test(start_paused = true)]
async fn a_subscribe_of_120000_filters_is_refused_and_the_broker_goes_on() {
    let b = Broker::in_memory(Access::default());
    let mut bridge = connected(&b, "bridge").await;
    assert!(bridge.subscribe(&["droidctl/+/cmd"]).await.is_some());
    let mut hostile = connected(&b, "hostile").await;
    let filters: Vec<SubscribeFilter> = (0..120_000)
        .map(|n| SubscribeFilter::new(format!("fl/{n:08}"), QoS::AtMostOnce))
        .collect();
    let huge = wire::encode(&Packet::Subscribe(Subscribe::new_many(filters)));
    assert!(huge.len() > 1_500_000);
    // Written while the broker reads: it closes after the header, so the rest may not go.
    let _ = hostile.send_bytes(&huge).await;
    assert!(hostile.closed().await);
    let mut other = connected(&b, "other").await;
    let many: Vec<String> = (0..65).map(|n| format!("y/{n}")).collect();
    let many: Vec<&str> = many.iter().map(String::as_str).collect();
    assert_eq!(other.subscribe(&many).await, None);
    assert!(other.closed().await);
    // The bridge's connection is served as before.
    let mut operator = connected(&b, "operator").await;
    operator
        .publish("droidctl/D2-0001/cmd", b"stop", false)
        .await;
    assert!(gets(&mut bridge, "droidctl/D2-0001/cmd").await);
    assert_eq!(b.stats().counters.closed, 2);
}

/// Issue 37 point 5: retained messages and what waits for a client are bounded in bytes: a
/// 4 MiB retained message closes its connection unread, 300 of 60 KiB keep at most 4 MiB,
/// `#` listed many times is one filter, and a subscriber that never reads holds at most its
/// queue's budget.
#[tokio::test(start_paused = true)]
async fn retained_and_queued_bytes_stay_within_their_budgets() {
    let b = Broker::in_memory(Access::default());
    let mut p = connected(&b, "pub").await;
    let _ = p.publish("big", &vec![b'x'; 4 << 20], true).await;
    assert!(p.closed().await);
    assert_eq!(b.stats().retained, 0);
    let mut p = connected(&b, "pub").await;
    for n in 0..300 {
        assert!(p.publish(&format!("r/{n}"), &[b'x'; 60 << 10], true).await);
    }
    // A ping answered: everything before it was handled.
    p.send(&Packet::PingReq).await;
    assert_eq!(p.recv().await, Some(Packet::PingResp));
    let s = b.stats();
    assert!(s.retained_bytes <= limits::RETAINED_BYTES, "{s:?}");
    assert!(s.retained >= 60, "{s:?}");
    assert_eq!(s.counters.not_retained, 300 - s.retained as u64);
    // `#` 64 times: one filter; each retained topic sent once.
    let mut sub = Raw::open(&b, LOOPBACK, 8 << 20).unwrap();
    assert_eq!(
        sub.connect("sub", 30).await,
        Some(ConnectReturnCode::Success)
    );
    let codes = sub.subscribe(&["#"; 64]).await.unwrap();
    assert_eq!(codes.len(), 64);
    let mut got = 0;
    while let Some(Packet::Publish(_)) = sub.recv().await {
        got += 1;
        if got == s.retained {
            break;
        }
    }
    assert_eq!(got, s.retained);
    drop(sub);
    tokio::time::sleep(Duration::from_millis(10)).await;
    // A subscriber that never reads, through a small pipe.
    let mut slow = Raw::open(&b, LOOPBACK, 1024).unwrap();
    slow.send(&Packet::Connect(Connect::new("slow"))).await;
    slow.send(&Packet::Subscribe(Subscribe::new(
        "live/#",
        QoS::AtMostOnce,
    )))
    .await;
    for _ in 0..200 {
        p.publish("live/x", &[0u8; 200 << 10], false).await;
    }
    p.send(&Packet::PingReq).await;
    assert_eq!(p.recv().await, Some(Packet::PingResp));
    let s = b.stats();
    assert!(s.queued_bytes <= limits::QUEUE_BYTES, "{s:?}");
    assert!(s.counters.dropped > 150, "{s:?}");
}

/// Issue 37 point 6: other machines' idle connections never take this machine's slots, one
/// address gets its share only, every client has an idle deadline (keep-alive 0 included),
/// and a client that never reads is closed when a write stalls.
#[tokio::test(start_paused = true)]
async fn idle_and_never_reading_clients_lock_nobody_out() {
    let b = Broker::in_memory(Access::default());
    let mut held = Vec::new();
    let mut refused = 0;
    for n in 0..255u32 {
        let peer = format!("198.51.{}.{}:40000", n / 16, n % 16);
        match Raw::open(&b, &peer, 4096) {
            Some(mut c) => {
                assert_eq!(
                    c.connect(&format!("idle-{n}"), 0).await,
                    Some(ConnectReturnCode::Success)
                );
                held.push(c);
            }
            None => refused += 1,
        }
    }
    assert_eq!(held.len(), MAX_CONNECTIONS - limits::LOOPBACK_SLOTS);
    assert!(Raw::open(&b, ELSEWHERE, 4096).is_none());
    let same: Vec<Raw> = (0..limits::MAX_PER_ADDRESS + 1)
        .filter_map(|_| Raw::open(&b, "203.0.113.1:1", 4096))
        .collect();
    assert!(same.is_empty(), "the remote slots are full");
    // The operator's stop still gets through.
    let mut bridge = connected(&b, "bridge").await;
    bridge.subscribe(&["droidctl/+/cmd"]).await.unwrap();
    let mut operator = connected(&b, "operator").await;
    operator
        .publish("droidctl/D2-0001/cmd", b"stop", false)
        .await;
    assert!(gets(&mut bridge, "droidctl/D2-0001/cmd").await);
    // Keep-alive 0 is no licence to idle: closed at the idle deadline.
    tokio::time::sleep(limits::MAX_IDLE).await;
    for c in &mut held {
        assert!(c.closed().await);
    }
    let s = b.stats();
    assert!(s.counters.idle >= held.len() as u64, "{s:?}");
    assert!(s.counters.refused > refused, "{s:?}");
    // A client that never reads: closed when a write stalls past the write timeout.
    let mut fresh = connected(&b, "fresh").await;
    let mut slow = Raw::open(&b, LOOPBACK, 1024).unwrap();
    slow.send(&Packet::Connect(Connect::new("slow"))).await;
    slow.send(&Packet::Subscribe(Subscribe::new("#", QoS::AtMostOnce)))
        .await;
    tokio::time::sleep(Duration::from_millis(10)).await;
    for _ in 0..4 {
        fresh.publish("t", &[0u8; 60 << 10], false).await;
    }
    tokio::time::sleep(limits::WRITE_TIMEOUT + Duration::from_secs(1)).await;
    assert_eq!(b.stats().counters.stalled, 1);
    assert!(slow.closed().await);
}

/// Issue 37 point 7: the bridge's own client ids cannot be taken over, not even with the
/// broker's password; the bridge's connection stays and is served.
#[tokio::test(start_paused = true)]
async fn the_bridges_own_client_ids_cannot_be_taken_over() {
    let own = OwnIds::new("room1-");
    let b = Broker::in_memory(Access {
        login: Some(("pupil".into(), "r2-d2".into())),
        own: Some(own.clone()),
    });
    let mut bridge = Raw::open(&b, LOOPBACK, 1 << 20).unwrap();
    let mut c = Connect::new("room1-0-D2-0001");
    c.set_login(&own.user, &own.password);
    assert_eq!(
        bridge.connect_with(c).await,
        Some(ConnectReturnCode::Success)
    );
    bridge.subscribe(&["droidctl/D2-0001/cmd"]).await.unwrap();
    for login in [None, Some(("pupil", "r2-d2"))] {
        for _ in 0..3 {
            let mut thief = Raw::open(&b, LOOPBACK, 4096).unwrap();
            let mut c = Connect::new("room1-0-D2-0001");
            if let Some((u, p)) = login {
                c.set_login(u, p);
            }
            assert_eq!(
                thief.connect_with(c).await,
                Some(ConnectReturnCode::BadClientId)
            );
            assert!(thief.closed().await);
        }
    }
    assert_eq!(b.stats().counters.own_id_refused, 6);
    // Other ids are as before: the login, and a later connection takes over an earlier one.
    let mut op = Raw::open(&b, LOOPBACK, 4096).unwrap();
    let mut c = Connect::new("op");
    c.set_login("pupil", "r2-d2");
    assert_eq!(op.connect_with(c).await, Some(ConnectReturnCode::Success));
    op.publish("droidctl/D2-0001/cmd", b"{}", false).await;
    assert!(gets(&mut bridge, "droidctl/D2-0001/cmd").await);
}

/// Issue 37 point 15: what MQTT 3.1.1 says a server refuses: a SUBSCRIBE with reserved
/// flags 0 closes the connection unanswered, a topic with U+0000 is never published, an
/// MQTT 5 or 3.1 CONNECT gets CONNACK return code 1.
#[tokio::test(start_paused = true)]
async fn what_mqtt_3_1_1_refuses_is_refused() {
    let b = Broker::in_memory(Access::default());
    let mut watcher = connected(&b, "watcher").await;
    watcher.subscribe(&["#"]).await.unwrap();
    let mut c = connected(&b, "flags").await;
    let mut sub = wire::encode(&Packet::Subscribe(Subscribe::new("#", QoS::AtMostOnce)));
    sub[0] = 0x80;
    c.send_bytes(&sub).await;
    assert_eq!(c.recv().await, None, "no SUBACK");
    let mut c = connected(&b, "nul").await;
    c.publish("a/\0/b", b"x", false).await;
    assert!(c.closed().await);
    c = connected(&b, "fine").await;
    c.publish("a/b", b"x", false).await;
    match watcher.recv().await {
        Some(Packet::Publish(p)) => assert_eq!(p.topic, "a/b", "the U+0000 topic never went"),
        other => panic!("{other:?}"),
    }
    let v4 = wire::encode(&Packet::Connect(Connect::new("v")));
    let mut v5 = v4.clone();
    v5[8] = 5;
    let mut v31 = vec![0x10, 0, 0, 6];
    v31.extend_from_slice(b"MQIsdp");
    v31.extend_from_slice(&[3, 2, 0, 60, 0, 1, b'v']);
    v31[1] = (v31.len() - 2) as u8;
    for old_or_new in [v5, v31] {
        let mut c = Raw::open(&b, LOOPBACK, 4096).unwrap();
        c.send_bytes(&old_or_new).await;
        match c.recv().await {
            Some(Packet::ConnAck(a)) => {
                assert_eq!(a.code, ConnectReturnCode::RefusedProtocolVersion)
            }
            other => panic!("{other:?}"),
        }
        assert!(c.closed().await);
    }
    assert_eq!(b.stats().counters.closed, 4);
}

/// A client with `clean_session = 0`, as `id`; its CONNACK's `session_present`.
async fn persistent(
    addr: SocketAddr,
    id: &str,
    clean: bool,
) -> (AsyncClient, rumqttc::EventLoop, bool) {
    let mut o = MqttOptions::new(id, addr.ip().to_string(), addr.port());
    o.set_keep_alive(Duration::from_secs(5));
    o.set_clean_session(clean);
    let (c, mut el) = AsyncClient::new(o, 64);
    loop {
        match tokio::time::timeout(Duration::from_secs(5), el.poll()).await {
            Ok(Ok(Event::Incoming(Packet::ConnAck(a)))) => return (c, el, a.session_present),
            Ok(Ok(_)) => {}
            other => panic!("no CONNACK: {other:?}"),
        }
    }
}

/// Issue 40 point 8: `clean_session = 0` is kept, both ways a client notices: its
/// reconnection's CONNACK says `session_present`, and the QoS 1 messages published while it
/// was away arrive, in order, without subscribing again (QoS 0 ones do not: MQTT 3.1.1,
/// 3.1.2.4); a clean CONNECT ends the session.
#[tokio::test]
async fn a_persistent_session_keeps_subscriptions_and_qos1_messages_while_away() {
    let b = start("127.0.0.1:0".parse().unwrap(), Access::default())
        .await
        .unwrap();
    let (c, mut el, present) = persistent(b.addr(), "ros-node", false).await;
    assert!(!present, "no session yet");
    c.subscribe("droidctl/+/odom", QoS::AtLeastOnce)
        .await
        .unwrap();
    until_suback(&mut el).await;
    c.disconnect().await.unwrap();
    while el.poll().await.is_ok() {}
    // Away: two QoS 1 messages and a QoS 0 one.
    let (pubc, mut pub_el) = client(b.addr(), "pub").await;
    for (n, q) in [
        ("1", QoS::AtLeastOnce),
        ("0", QoS::AtMostOnce),
        ("2", QoS::AtLeastOnce),
    ] {
        pubc.publish("droidctl/BB-0001/odom", q, false, n)
            .await
            .unwrap();
    }
    let mut acked = 0;
    while acked < 2 {
        if let Event::Incoming(Packet::PubAck(_)) = pub_el.poll().await.unwrap() {
            acked += 1;
        }
    }
    // The broker has handled the QoS 0 one before the second PUBACK (one connection, in order).
    assert_eq!(b.stats().sessions, 1);
    let (_c, mut el, present) = persistent(b.addr(), "ros-node", false).await;
    assert!(present, "CONNACK says the session is there");
    let got: Vec<_> = [next_publish(&mut el).await, next_publish(&mut el).await]
        .into_iter()
        .map(|p| (p.payload.to_vec(), p.qos))
        .collect();
    assert_eq!(
        got,
        [
            (b"1".to_vec(), QoS::AtLeastOnce),
            (b"2".to_vec(), QoS::AtLeastOnce)
        ]
    );
    // Still subscribed, without a SUBSCRIBE.
    pubc.publish("droidctl/BB-0001/odom", QoS::AtLeastOnce, false, "live")
        .await
        .unwrap();
    let pub_task = tokio::spawn(async move { while pub_el.poll().await.is_ok() {} });
    assert_eq!(&next_publish(&mut el).await.payload[..], b"live");
    drop(el);
    // A clean CONNECT under the id ends the session: nothing present, nothing kept.
    let (_c, _el, present) = persistent(b.addr(), "ros-node", true).await;
    assert!(!present);
    assert_eq!((b.stats().sessions, b.stats().session_bytes), (0, 0));
    pub_task.abort();
}
