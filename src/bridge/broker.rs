//! An MQTT 3.1.1 broker inside droidctl: `droidctl bridge --mqtt` without a URL hosts the
//! bridge's topics itself, so a machine with nothing installed can bridge droids, and the
//! tests have a broker where mosquitto is not installed.
//!
//! Written here on rumqttc's own packet codec (`rumqttc::mqttbytes::v4`, already built for
//! the client) instead of taking `rumqttd`: rumqttd brings an HTTP console (axum, hyper), a
//! metrics exporter and a configuration library, 79 crates this project does not otherwise
//! build, which would nearly double the build on a 2-core machine (README, "What a build
//! costs").
//!
//! What it does: clean sessions only (every CONNECT starts afresh; `session_present` is
//! always false), QoS 0, 1 and 2 both ways (delivered at the lower of the publisher's and
//! the subscription's QoS, acknowledged as the protocol says; nothing is retransmitted, as
//! no session outlives its connection), retained messages (an empty one clears its topic),
//! last wills (sent when a client goes without DISCONNECT, or stays silent past 1.5× its
//! keep-alive), `+`/`#` filters, a second connection with a client's id closing the first,
//! and an optional user name and password. Bounded: connections, retained topics, packet
//! size, and each client's queue (a client that does not read loses what overflows, counted
//! in the log).

use bytes::BytesMut;
use rumqttc::mqttbytes::v4::{
    ConnAck, ConnectReturnCode, Packet, PubAck, PubComp, PubRec, PubRel, Publish, SubAck,
    SubscribeReasonCode, UnsubAck,
};
use rumqttc::mqttbytes::{QoS, matches, valid_filter, valid_topic};
use std::collections::{BTreeMap, HashMap};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::net::TcpListener;
use tokio::sync::mpsc;

/// The largest packet accepted (bytes): far above the bridge's own, far below memory trouble.
pub const MAX_PACKET: usize = 4 << 20;
/// Connections at once; more are closed at once.
pub const MAX_CONNECTIONS: usize = 256;
/// Retained topics kept; past it a new retained topic is not kept (the message is still
/// delivered).
pub const MAX_RETAINED: usize = 10_000;
/// Packets queued for one client.
const QUEUE: usize = 4096;
/// How long a new connection has to send CONNECT.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);

/// Who may connect.
#[derive(Debug, Clone, Default)]
pub struct Access {
    /// `Some((user, password))`: only that login; `None`: anyone.
    pub login: Option<(String, String)>,
}

/// What a client's connection is told to send.
enum Out {
    Packet(Packet),
    /// Another connection took this client id: close without the will.
    TakenOver,
}

struct Client {
    id: u64,
    tx: mpsc::Sender<Out>,
    /// Filters and their granted QoS.
    subs: Vec<(String, QoS)>,
}

#[derive(Default)]
struct State {
    next: u64,
    /// By client id.
    clients: HashMap<String, Client>,
    retained: BTreeMap<String, Publish>,
    dropped: u64,
}

/// The running broker: stops when dropped.
pub struct Broker {
    addr: SocketAddr,
    task: tokio::task::JoinHandle<()>,
}

impl Broker {
    /// The address it listens on (the port the system chose, for port 0).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }
}

impl Drop for Broker {
    fn drop(&mut self) {
        self.task.abort();
    }
}

/// Something that turns an accepted TCP stream into the stream MQTT flows over (TLS, in the
/// tests that try the bridge's TLS client against this broker).
pub type Wrap = Arc<
    dyn Fn(
            tokio::net::TcpStream,
        )
            -> std::pin::Pin<Box<dyn Future<Output = std::io::Result<Box<dyn Stream>>> + Send>>
        + Send
        + Sync,
>;

/// A byte stream a client connects over.
pub trait Stream: AsyncRead + AsyncWrite + Unpin + Send {}
impl<T: AsyncRead + AsyncWrite + Unpin + Send> Stream for T {}

/// Listen on `addr` and serve until the returned [`Broker`] is dropped.
pub async fn start(addr: SocketAddr, access: Access) -> std::io::Result<Broker> {
    start_with(addr, access, None).await
}

/// As [`start`], each connection first passed through `wrap` (e.g. a TLS handshake).
pub async fn start_with(
    addr: SocketAddr,
    access: Access,
    wrap: Option<Wrap>,
) -> std::io::Result<Broker> {
    let listener = TcpListener::bind(addr).await?;
    let addr = listener.local_addr()?;
    let state = Arc::new(Mutex::new(State::default()));
    let access = Arc::new(access);
    let live = Arc::new(tokio::sync::Semaphore::new(MAX_CONNECTIONS));
    let task = tokio::spawn(async move {
        loop {
            let Ok((tcp, peer)) = listener.accept().await else {
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            };
            let Ok(permit) = live.clone().try_acquire_owned() else {
                tracing::warn!("mqtt broker: {peer} refused: {MAX_CONNECTIONS} connections");
                continue;
            };
            let _ = tcp.set_nodelay(true);
            let (state, access, wrap) = (state.clone(), access.clone(), wrap.clone());
            tokio::spawn(async move {
                let stream: Box<dyn Stream> = match wrap {
                    Some(w) => match w(tcp).await {
                        Ok(s) => s,
                        Err(e) => {
                            tracing::info!("mqtt broker: {peer}: {e}");
                            return;
                        }
                    },
                    None => Box::new(tcp),
                };
                if let Err(e) = serve(stream, &state, &access).await {
                    tracing::info!("mqtt broker: {peer}: {e}");
                }
                drop(permit);
            });
        }
    });
    Ok(Broker { addr, task })
}

fn lock(state: &Mutex<State>) -> std::sync::MutexGuard<'_, State> {
    state.lock().unwrap_or_else(|p| p.into_inner())
}

/// Read one packet, reading more bytes as needed. `Ok(None)`: the peer closed.
async fn read_packet<S: AsyncRead + Unpin>(
    s: &mut S,
    buf: &mut BytesMut,
) -> Result<Option<Packet>, String> {
    loop {
        match Packet::read(buf, MAX_PACKET) {
            Ok(p) => return Ok(Some(p)),
            Err(rumqttc::mqttbytes::Error::InsufficientBytes(_)) => {}
            Err(e) => return Err(format!("malformed packet: {e:?}")),
        }
        buf.reserve(4096);
        if s.read_buf(buf).await.map_err(|e| e.to_string())? == 0 {
            return Ok(None);
        }
    }
}

async fn write_packet<S: AsyncWrite + Unpin>(s: &mut S, p: &Packet) -> Result<(), String> {
    let mut b = BytesMut::new();
    p.write(&mut b, MAX_PACKET)
        .map_err(|e| format!("cannot encode: {e:?}"))?;
    s.write_all(&b).await.map_err(|e| e.to_string())
}

/// One client's connection, from CONNECT to close.
async fn serve(
    mut s: Box<dyn Stream>,
    state: &Mutex<State>,
    access: &Access,
) -> Result<(), String> {
    let mut buf = BytesMut::with_capacity(4096);
    let connect = match tokio::time::timeout(CONNECT_TIMEOUT, read_packet(&mut s, &mut buf)).await {
        Ok(Ok(Some(Packet::Connect(c)))) => c,
        Ok(Ok(None)) => return Ok(()),
        Ok(Ok(Some(_))) => return Err("the first packet is not CONNECT".into()),
        Ok(Err(e)) => return Err(e),
        Err(_) => return Err("no CONNECT".into()),
    };
    let refuse = |code| Packet::ConnAck(ConnAck::new(code, false));
    if let Some((user, password)) = &access.login {
        let ok = connect
            .login
            .as_ref()
            .is_some_and(|l| &l.username == user && &l.password == password);
        if !ok {
            write_packet(&mut s, &refuse(ConnectReturnCode::BadUserNamePassword)).await?;
            return Err("wrong user name or password".into());
        }
    }
    if connect.client_id.is_empty() && !connect.clean_session {
        write_packet(&mut s, &refuse(ConnectReturnCode::BadClientId)).await?;
        return Err("an empty client id needs a clean session".into());
    }
    let (tx, mut rx) = mpsc::channel(QUEUE);
    let (client_id, me) = {
        let mut st = lock(state);
        st.next += 1;
        let me = st.next;
        let id = if connect.client_id.is_empty() {
            format!("droidctl-broker-{me}")
        } else {
            connect.client_id.clone()
        };
        let old = st.clients.insert(
            id.clone(),
            Client {
                id: me,
                tx,
                subs: Vec::new(),
            },
        );
        if let Some(old) = old {
            let _ = old.tx.try_send(Out::TakenOver);
        }
        (id, me)
    };
    write_packet(
        &mut s,
        &Packet::ConnAck(ConnAck::new(ConnectReturnCode::Success, false)),
    )
    .await?;
    let keepalive = (connect.keep_alive > 0)
        .then(|| Duration::from_millis(u64::from(connect.keep_alive) * 1500));
    let mut next_pkid = 0u16;
    let outcome: Result<bool, String> = loop {
        let idle = async {
            match keepalive {
                Some(k) => tokio::time::sleep(k).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            got = read_packet(&mut s, &mut buf) => match got {
                Ok(Some(Packet::Disconnect)) => break Ok(true),
                Ok(Some(p)) => {
                    if let Err(e) = on_packet(&mut s, state, &client_id, me, p).await {
                        break Err(e);
                    }
                }
                Ok(None) => break Err("closed without DISCONNECT".into()),
                Err(e) => break Err(e),
            },
            out = rx.recv() => match out {
                Some(Out::Packet(mut p)) => {
                    if let Packet::Publish(ref mut p) = p && p.qos != QoS::AtMostOnce {
                        next_pkid = next_pkid.checked_add(1).unwrap_or(1);
                        p.pkid = next_pkid;
                    }
                    if let Err(e) = write_packet(&mut s, &p).await {
                        break Err(e);
                    }
                }
                Some(Out::TakenOver) | None => {
                    // Taken over: the new connection is the client now; no will.
                    return Ok(());
                }
            },
            _ = idle => break Err("keep-alive expired".into()),
        }
    };
    {
        let mut st = lock(state);
        if st.clients.get(&client_id).is_some_and(|c| c.id == me) {
            st.clients.remove(&client_id);
        }
    }
    match outcome {
        Ok(_) => Ok(()),
        Err(e) => {
            if let Some(will) = connect.last_will {
                let mut p = Publish::from_bytes(will.topic, will.qos, will.message);
                p.retain = will.retain;
                publish(state, p);
            }
            Err(e)
        }
    }
}

async fn on_packet(
    s: &mut Box<dyn Stream>,
    state: &Mutex<State>,
    client_id: &str,
    me: u64,
    p: Packet,
) -> Result<(), String> {
    match p {
        Packet::Publish(p) => {
            if !valid_topic(&p.topic) {
                return Err(format!("invalid topic `{}`", p.topic));
            }
            let (qos, pkid) = (p.qos, p.pkid);
            publish(state, p);
            match qos {
                QoS::AtMostOnce => {}
                QoS::AtLeastOnce => write_packet(s, &Packet::PubAck(PubAck::new(pkid))).await?,
                QoS::ExactlyOnce => write_packet(s, &Packet::PubRec(PubRec::new(pkid))).await?,
            }
        }
        Packet::PubRel(r) => write_packet(s, &Packet::PubComp(PubComp::new(r.pkid))).await?,
        Packet::PubRec(r) => write_packet(s, &Packet::PubRel(PubRel::new(r.pkid))).await?,
        Packet::PubAck(_) | Packet::PubComp(_) => {}
        Packet::Subscribe(sub) => {
            let mut codes = Vec::with_capacity(sub.filters.len());
            let mut retained = Vec::new();
            {
                let mut st = lock(state);
                let st = &mut *st;
                let Some(c) = st.clients.get_mut(client_id).filter(|c| c.id == me) else {
                    return Err("taken over".into());
                };
                for f in sub.filters {
                    if !valid_filter(&f.path) {
                        codes.push(SubscribeReasonCode::Failure);
                        continue;
                    }
                    codes.push(SubscribeReasonCode::Success(f.qos));
                    for (topic, p) in &st.retained {
                        if matches(topic, &f.path) {
                            let mut p = p.clone();
                            p.qos = lower(p.qos, f.qos);
                            p.retain = true;
                            retained.push(p);
                        }
                    }
                    c.subs.retain(|(path, _)| *path != f.path);
                    c.subs.push((f.path, f.qos));
                }
            }
            write_packet(s, &Packet::SubAck(SubAck::new(sub.pkid, codes))).await?;
            // After SUBACK, through the queue (so they get packet ids as everything else).
            let tx = lock(state).clients.get(client_id).map(|c| c.tx.clone());
            if let Some(tx) = tx {
                for p in retained {
                    let _ = tx.try_send(Out::Packet(Packet::Publish(p)));
                }
            }
        }
        Packet::Unsubscribe(u) => {
            if let Some(c) = lock(state).clients.get_mut(client_id) {
                c.subs.retain(|(path, _)| !u.topics.contains(path));
            }
            write_packet(s, &Packet::UnsubAck(UnsubAck::new(u.pkid))).await?;
        }
        Packet::PingReq => write_packet(s, &Packet::PingResp).await?,
        Packet::Connect(_) => return Err("a second CONNECT".into()),
        other => return Err(format!("unexpected {other:?} from a client")),
    }
    Ok(())
}

/// The lower of two QoS levels (what a subscriber gets of a publisher's message).
fn lower(a: QoS, b: QoS) -> QoS {
    if (a as u8) <= (b as u8) { a } else { b }
}

/// Keep `p` if retained, and queue it for every client subscribed to its topic.
fn publish(state: &Mutex<State>, mut p: Publish) {
    let mut st = lock(state);
    if p.retain {
        if p.payload.is_empty() {
            st.retained.remove(&p.topic);
        } else if st.retained.len() < MAX_RETAINED || st.retained.contains_key(&p.topic) {
            st.retained.insert(p.topic.clone(), p.clone());
        } else {
            tracing::warn!(
                "mqtt broker: {MAX_RETAINED} retained topics: {} not kept",
                p.topic
            );
        }
    }
    // Delivered to established subscribers: retain is 0 (MQTT 3.1.1, 3.3.1.3).
    p.retain = false;
    p.dup = false;
    let mut dropped = 0;
    for c in st.clients.values() {
        let granted = c
            .subs
            .iter()
            .filter(|(f, _)| matches(&p.topic, f))
            .map(|(_, q)| *q)
            .max_by_key(|q| *q as u8);
        if let Some(q) = granted {
            let mut copy = p.clone();
            copy.qos = lower(copy.qos, q);
            if c.tx.try_send(Out::Packet(Packet::Publish(copy))).is_err() {
                dropped += 1;
            }
        }
    }
    if dropped > 0 {
        st.dropped += dropped;
        tracing::warn!(
            "mqtt broker: {dropped} message(s) to {} dropped: a client is not reading ({} in all)",
            p.topic,
            st.dropped
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rumqttc::{AsyncClient, Event, MqttOptions};

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
}
