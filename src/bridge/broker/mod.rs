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
//! What it does: clean and persistent sessions (`clean_session = 0` keeps a client's
//! subscriptions and queues its QoS 1 and 2 messages while it is away, bounded:
//! [`session`]), QoS 0, 1 and 2 both ways (delivered at the lower of the publisher's and
//! the subscription's QoS, acknowledged as the protocol says; nothing written is
//! retransmitted), retained messages (an empty one clears its topic),
//! last wills (sent when a client goes without DISCONNECT, or stays silent past its idle
//! deadline), `+`/`#` filters, a second connection with a client's id closing the first
//! (except droidctl's own ids: [`OwnIds`]), and an optional user name and password.
//!
//! Nothing a client sends can hold it (issue 37): every count is bounded in bytes too
//! ([`limits`]: packets, filters, retained messages, each client's queue and all of them),
//! every client has an idle deadline and a write timeout, slots per address with some kept
//! for this machine, and MQTT 3.1.1's refusals ([`wire`]). No lock is held across work that
//! grows with input ([`state`]). The CLI runs it on a runtime of its own
//! ([`super::thread::RuntimeThread`], [`start_on`]), so even a broker kept busy cannot
//! delay the droids' command timeouts. A refused or closed client is logged and counted
//! ([`Broker::stats`]); the broker goes on.

pub mod limits;
pub mod session;
pub mod state;
pub mod wire;

pub use limits::{MAX_CONNECTIONS, MAX_PACKET, MAX_RETAINED, Refusal};
pub use state::Counters;

use crate::sync::lock;
use bytes::BytesMut;
use limits::{Admission, CONNECT_TIMEOUT, Slot, idle_deadline};
use rumqttc::mqttbytes::QoS;
use rumqttc::mqttbytes::v4::{
    ConnAck, Connect, ConnectReturnCode, Packet, PubAck, PubComp, PubRec, PubRel, Publish, SubAck,
    UnsubAck,
};
use state::{Out, Queued, State};
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncWrite};
use tokio::net::TcpListener;
use tokio::runtime::Handle;
use tokio::sync::{mpsc, watch};
use wire::WireError;

/// Who may connect.
#[derive(Debug, Clone, Default)]
pub struct Access {
    /// `Some((user, password))`: only that login; `None`: anyone.
    pub login: Option<(String, String)>,
    /// The client ids of droidctl's own bridge, which nobody else may take (issue 37
    /// point 7).
    pub own: Option<OwnIds>,
}

/// Client ids kept for droidctl's own bridge: an id starting with `prefix` is accepted only
/// with this login (a secret made per process, known to the bridge in the same process).
/// Anyone else asking for such an id gets CONNACK 2 (identifier rejected) and the bridge's
/// connection stays: with a predictable `--client-id`, taking the id over cannot knock the
/// bridge off its own broker.
#[derive(Clone)]
pub struct OwnIds {
    pub prefix: String,
    pub user: String,
    pub password: String,
}

impl std::fmt::Debug for OwnIds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OwnIds")
            .field("prefix", &self.prefix)
            .field("user", &self.user)
            .finish_non_exhaustive()
    }
}

impl OwnIds {
    /// The ids starting with `prefix`, with a fresh secret.
    pub fn new(prefix: &str) -> OwnIds {
        use std::hash::BuildHasher;
        let secret: String = (0..4)
            .map(|i| {
                let h = std::collections::hash_map::RandomState::new().hash_one((
                    i,
                    std::process::id(),
                    std::time::SystemTime::now(),
                ));
                format!("{h:016x}")
            })
            .collect();
        OwnIds {
            prefix: prefix.to_string(),
            user: "droidctl-bridge".into(),
            password: secret,
        }
    }

    fn is_own(&self, id: &str) -> bool {
        id.starts_with(&self.prefix)
    }

    fn logs_in(&self, c: &Connect) -> bool {
        c.login
            .as_ref()
            .is_some_and(|l| l.username == self.user && l.password == self.password)
    }
}

/// What the broker holds now, and what it refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stats {
    pub connections: usize,
    pub clients: usize,
    pub retained: usize,
    pub retained_bytes: usize,
    pub queued_bytes: usize,
    /// Sessions kept for clients away, and the bytes queued for them.
    pub sessions: usize,
    pub session_bytes: usize,
    pub counters: Counters,
}

struct Shared {
    state: Mutex<State>,
    access: Access,
    admission: Arc<Mutex<Admission>>,
    wrap: Option<Wrap>,
    shutdown: watch::Receiver<bool>,
}

/// The running broker: stops when dropped.
pub struct Broker {
    addr: SocketAddr,
    shared: Arc<Shared>,
    handle: Handle,
    accept: Option<tokio::task::JoinHandle<()>>,
    shutdown: watch::Sender<bool>,
}

impl Broker {
    /// The address it listens on (the port the system chose, for port 0); `0.0.0.0:0` for
    /// one that does not listen ([`Broker::in_memory`]).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The runtime it runs on (the CLI's: a thread of its own).
    pub fn handle(&self) -> &Handle {
        &self.handle
    }

    /// A broker that does not listen: connections are handed to it
    /// ([`Broker::connect_stream`]), for tests and the fuzz harness. Runs on the current
    /// runtime.
    pub fn in_memory(access: Access) -> Broker {
        Broker::new(
            Handle::current(),
            SocketAddr::from(([0, 0, 0, 0], 0)),
            access,
            None,
        )
    }

    fn new(handle: Handle, addr: SocketAddr, access: Access, wrap: Option<Wrap>) -> Broker {
        let (shutdown, stopping) = watch::channel(false);
        Broker {
            addr,
            shared: Arc::new(Shared {
                state: Mutex::new(State::default()),
                access,
                admission: Arc::new(Mutex::new(Admission::default())),
                wrap,
                shutdown: stopping,
            }),
            handle,
            accept: None,
            shutdown,
        }
    }

    /// Serve a connection from `peer` over `stream` (as if accepted), or refuse it a slot.
    pub fn connect_stream(&self, stream: Box<dyn Stream>, peer: SocketAddr) -> Result<(), Refusal> {
        let slot = admit(&self.shared, peer)?;
        let shared = self.shared.clone();
        self.handle
            .spawn(connection(shared, Conn::Stream(stream), peer, slot));
        Ok(())
    }

    /// What it holds and what it refused so far.
    pub fn stats(&self) -> Stats {
        let connections = lock(&self.shared.admission).total();
        let st = lock(&self.shared.state);
        Stats {
            connections,
            clients: st.clients(),
            retained: st.retained_count(),
            retained_bytes: st.retained_bytes(),
            queued_bytes: st.queued_bytes(),
            sessions: st.sessions.count(),
            session_bytes: st.sessions.bytes(),
            counters: st.counters,
        }
    }
}

impl Drop for Broker {
    fn drop(&mut self) {
        let _ = self.shutdown.send(true);
        if let Some(a) = self.accept.take() {
            a.abort();
        }
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

/// Listen on `addr` and serve, on the current runtime, until the returned [`Broker`] is
/// dropped.
pub async fn start(addr: SocketAddr, access: Access) -> std::io::Result<Broker> {
    start_with(addr, access, None).await
}

/// As [`start`], each connection first passed through `wrap` (e.g. a TLS handshake).
pub async fn start_with(
    addr: SocketAddr,
    access: Access,
    wrap: Option<Wrap>,
) -> std::io::Result<Broker> {
    start_on(&Handle::current(), addr, access, wrap)
}

/// Listen on `addr` and serve on the runtime of `handle` (the CLI gives it a
/// [`super::thread::RuntimeThread`] of its own) until the returned [`Broker`] is dropped.
pub fn start_on(
    handle: &Handle,
    addr: SocketAddr,
    access: Access,
    wrap: Option<Wrap>,
) -> std::io::Result<Broker> {
    let std_listener = std::net::TcpListener::bind(addr)?;
    std_listener.set_nonblocking(true)?;
    let addr = std_listener.local_addr()?;
    let listener = {
        let _in = handle.enter();
        TcpListener::from_std(std_listener)?
    };
    let mut broker = Broker::new(handle.clone(), addr, access, wrap);
    let shared = broker.shared.clone();
    broker.accept = Some(handle.spawn(accept(listener, shared)));
    Ok(broker)
}

async fn accept(listener: TcpListener, shared: Arc<Shared>) {
    loop {
        let Ok((tcp, peer)) = listener.accept().await else {
            // Out of file descriptors, say: try again shortly rather than spin.
            tokio::time::sleep(Duration::from_millis(50)).await;
            continue;
        };
        let Ok(slot) = admit(&shared, peer) else {
            continue;
        };
        let _ = tcp.set_nodelay(true);
        tokio::spawn(connection(shared.clone(), Conn::Tcp(tcp), peer, slot));
    }
}

/// A slot for `peer`, or its refusal logged and counted.
fn admit(shared: &Shared, peer: SocketAddr) -> Result<Slot, Refusal> {
    Slot::take(&shared.admission, peer.ip()).inspect_err(|why| {
        lock(&shared.state).counters.refused += 1;
        tracing::warn!("mqtt broker: {peer} refused: {why}");
    })
}

/// A connection as accepted.
enum Conn {
    Tcp(tokio::net::TcpStream),
    Stream(Box<dyn Stream>),
}

/// Why a connection ended other than by DISCONNECT or its peer closing.
#[derive(Debug)]
enum Why {
    Wire(WireError),
    NoConnect,
    Idle(Duration),
    Refused(&'static str),
    /// Silent while a newcomer needed its slot.
    Evicted,
    /// The broker was dropped.
    Shutdown,
}

impl std::fmt::Display for Why {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Why::Wire(e) => write!(f, "{e}"),
            Why::NoConnect => write!(f, "no CONNECT within {} s", CONNECT_TIMEOUT.as_secs()),
            Why::Idle(d) => write!(f, "nothing received for {} s", d.as_secs()),
            Why::Refused(why) => write!(f, "refused: {why}"),
            Why::Evicted => write!(
                f,
                "silent for {} s while every slot was taken: its slot went to a newcomer",
                limits::EVICT_SILENT.as_secs()
            ),
            Why::Shutdown => write!(f, "the broker stopped"),
        }
    }
}

impl From<WireError> for Why {
    fn from(e: WireError) -> Why {
        Why::Wire(e)
    }
}

/// One connection from accept to close: logged and counted when it ends badly.
async fn connection(shared: Arc<Shared>, conn: Conn, peer: SocketAddr, slot: Slot) {
    let stream: Box<dyn Stream> = match (conn, &shared.wrap) {
        (Conn::Tcp(tcp), Some(w)) => match tokio::time::timeout(CONNECT_TIMEOUT, w(tcp)).await {
            Ok(Ok(s)) => s,
            Ok(Err(e)) => {
                tracing::info!("mqtt broker: {peer}: {e}");
                return;
            }
            Err(_) => {
                tracing::info!("mqtt broker: {peer}: no handshake");
                return;
            }
        },
        (Conn::Tcp(tcp), None) => Box::new(tcp),
        (Conn::Stream(s), _) => s,
    };
    if let Err(why) = serve(stream, &shared, &slot).await {
        let mut st = lock(&shared.state);
        match &why {
            Why::Idle(_) | Why::Evicted => st.counters.idle += 1,
            Why::Wire(WireError::WriteTimeout) => st.counters.stalled += 1,
            Why::Wire(WireError::Io(_)) | Why::Shutdown => {}
            _ => st.counters.closed += 1,
        }
        drop(st);
        match why {
            Why::Wire(WireError::Io(_)) | Why::Shutdown => {
                tracing::debug!("mqtt broker: {peer}: {why}")
            }
            _ => tracing::info!("mqtt broker: {peer}: closed: {why}"),
        }
    }
    drop(slot);
}

/// A client's CONNECT, or why it is refused: the CONNACK code to answer with.
fn check_connect(c: &Connect, access: &Access) -> Result<(), (ConnectReturnCode, &'static str)> {
    let own = access.own.as_ref();
    let own_login = own.is_some_and(|o| o.logs_in(c));
    if own.is_some_and(|o| o.is_own(&c.client_id)) && !own_login {
        return Err((
            ConnectReturnCode::BadClientId,
            "a client id kept for droidctl's own bridge",
        ));
    }
    if let Some((user, password)) = &access.login {
        let ok = c
            .login
            .as_ref()
            .is_some_and(|l| &l.username == user && &l.password == password);
        if !ok && !own_login {
            return Err((
                ConnectReturnCode::BadUserNamePassword,
                "wrong user name or password",
            ));
        }
    }
    if c.client_id.is_empty() && !c.clean_session {
        return Err((
            ConnectReturnCode::BadClientId,
            "an empty client id needs a clean session",
        ));
    }
    Ok(())
}

/// One client's connection, from CONNECT to close. `Ok`: DISCONNECT, the peer closing, or
/// taken over.
async fn serve(mut s: Box<dyn Stream>, shared: &Shared, slot: &Slot) -> Result<(), Why> {
    let mut shutdown = shared.shutdown.clone();
    let mut buf = BytesMut::with_capacity(256);
    let first = tokio::time::timeout(CONNECT_TIMEOUT, wire::read(&mut s, &mut buf, true)).await;
    let connect = match first {
        Ok(Ok(Some(Packet::Connect(c)))) => c,
        Ok(Ok(None)) => return Ok(()),
        Ok(Ok(Some(_))) => return Err(WireError::Malformed("not CONNECT".into()).into()),
        Ok(Err(e @ WireError::Protocol { .. })) => {
            let refuse = ConnAck::new(ConnectReturnCode::RefusedProtocolVersion, false);
            let _ = wire::write(&mut s, &Packet::ConnAck(refuse)).await;
            return Err(e.into());
        }
        Ok(Err(e)) => return Err(e.into()),
        Err(_) => return Err(Why::NoConnect),
    };
    if connect
        .last_will
        .as_ref()
        .is_some_and(|w| w.topic.contains(['+', '#']))
    {
        return Err(WireError::Wildcard.into());
    }
    if let Err((code, why)) = check_connect(&connect, &shared.access) {
        if code == ConnectReturnCode::BadClientId && why.contains("droidctl") {
            lock(&shared.state).counters.own_id_refused += 1;
            tracing::warn!(
                client_id = %connect.client_id,
                "mqtt broker: a client asked for the bridge's own client id: refused"
            );
        }
        wire::write(&mut s, &Packet::ConnAck(ConnAck::new(code, false))).await?;
        return Err(Why::Refused(why));
    }
    if shared
        .access
        .own
        .as_ref()
        .is_some_and(|o| o.logs_in(&connect))
    {
        slot.own();
    }
    let (tx, mut rx) = mpsc::channel::<Queued>(state::queue_capacity());
    let (client_id, me, budget, present) = {
        let mut st = lock(&shared.state);
        let me = st.next_conn();
        let id = if connect.client_id.is_empty() {
            format!("droidctl-broker-{me}")
        } else {
            connect.client_id.clone()
        };
        let now = tokio::time::Instant::now();
        let (budget, present) = st.connect_session(&id, me, tx, connect.clean_session, now);
        (id, me, budget, present)
    };
    let acked = wire::write(
        &mut s,
        &Packet::ConnAck(ConnAck::new(ConnectReturnCode::Success, present)),
    )
    .await;
    let idle = idle_deadline(connect.keep_alive);
    let mut deadline = tokio::time::Instant::now() + idle;
    let mut next_pkid = 0u16;
    let outcome: Result<(), Why> = match acked {
        Err(e) => Err(e.into()),
        Ok(()) => loop {
            tokio::select! {
                got = wire::read(&mut s, &mut buf, false) => match got {
                    Ok(Some(Packet::Disconnect)) => break Ok(()),
                    Ok(Some(p)) => {
                        deadline = tokio::time::Instant::now() + idle;
                        slot.heard();
                        let retained = match on_packet(&mut s, shared, &client_id, me, p).await {
                            Ok(r) => r,
                            Err(e) => break Err(e),
                        };
                        // After SUBACK, each with a packet id as everything else.
                        let mut failed = None;
                        for (p, q) in retained {
                            let mut p = Publish::clone(&p);
                            p.qos = state::lower(p.qos, q);
                            if let Err(e) = send_publish(&mut s, &mut next_pkid, p).await {
                                failed = Some(e);
                                break;
                            }
                        }
                        if let Some(e) = failed {
                            break Err(e.into());
                        }
                    }
                    Ok(None) => break Err(WireError::Io("closed without DISCONNECT".into()).into()),
                    Err(e) => break Err(e.into()),
                },
                out = rx.recv() => match out {
                    Some(Queued { out: Out::Packet(p), bytes }) => {
                        budget.release(bytes);
                        let sent = match p {
                            Packet::Publish(p) => send_publish(&mut s, &mut next_pkid, p).await,
                            p => wire::write(&mut s, &p).await,
                        };
                        if let Err(e) = sent {
                            break Err(e.into());
                        }
                    }
                    // Taken over: the new connection is the client now; no will.
                    Some(Queued { out: Out::TakenOver, .. }) | None => return Ok(()),
                },
                _ = tokio::time::sleep_until(deadline) => break Err(Why::Idle(idle)),
                _ = shutdown.changed() => break Err(Why::Shutdown),
                _ = slot.evicted() => break Err(Why::Evicted),
            }
        },
    };
    // What was queued and not sent gives its bytes back (and stays in a persistent
    // client's session).
    rx.close();
    let mut left = Vec::new();
    while let Ok(q) = rx.try_recv() {
        budget.release(q.bytes);
        if let Out::Packet(Packet::Publish(p)) = q.out {
            left.push(p);
        }
    }
    let now = tokio::time::Instant::now();
    lock(&shared.state).disconnect_session(&client_id, me, left, now);
    if outcome.is_err()
        && !matches!(outcome, Err(Why::Shutdown))
        && let Some(will) = connect.last_will
    {
        let mut p = Publish::from_bytes(will.topic, will.qos, will.message);
        p.retain = will.retain;
        lock(&shared.state).publish(p);
    }
    outcome
}

/// Write PUBLISH `p` to a client, with the connection's next packet id above QoS 0.
async fn send_publish(
    s: &mut Box<dyn Stream>,
    next_pkid: &mut u16,
    mut p: Publish,
) -> Result<(), WireError> {
    if p.qos != QoS::AtMostOnce {
        *next_pkid = next_pkid.checked_add(1).unwrap_or(1);
        p.pkid = *next_pkid;
    }
    wire::write(s, &Packet::Publish(p)).await
}

/// One packet from a client after CONNECT; the retained messages a SUBSCRIBE matched, for
/// the connection to send.
async fn on_packet(
    s: &mut Box<dyn Stream>,
    shared: &Shared,
    client_id: &str,
    me: u64,
    p: Packet,
) -> Result<Vec<state::Matched>, Why> {
    match p {
        Packet::Publish(p) => {
            if p.topic.contains(['+', '#']) {
                return Err(WireError::Wildcard.into());
            }
            let (qos, pkid) = (p.qos, p.pkid);
            let dropped = lock(&shared.state).publish(p);
            if dropped > 0 {
                tracing::warn!(
                    "mqtt broker: {dropped} message(s) dropped: a client is not reading"
                );
            }
            match qos {
                QoS::AtMostOnce => {}
                QoS::AtLeastOnce => wire::write(s, &Packet::PubAck(PubAck::new(pkid))).await?,
                QoS::ExactlyOnce => wire::write(s, &Packet::PubRec(PubRec::new(pkid))).await?,
            }
        }
        Packet::PubRel(r) => wire::write(s, &Packet::PubComp(PubComp::new(r.pkid))).await?,
        Packet::PubRec(r) => wire::write(s, &Packet::PubRel(PubRel::new(r.pkid))).await?,
        Packet::PubAck(_) | Packet::PubComp(_) => {}
        Packet::Subscribe(sub) => {
            if sub.filters.len() > limits::MAX_FILTERS {
                return Err(Why::Refused("more than 64 filters in one SUBSCRIBE"));
            }
            let filters = sub.filters.into_iter().map(|f| (f.path, f.qos)).collect();
            let done = lock(&shared.state).subscribe(client_id, me, filters);
            let Some((codes, retained)) = done else {
                return Ok(Vec::new());
            };
            wire::write(s, &Packet::SubAck(SubAck::new(sub.pkid, codes))).await?;
            return Ok(retained);
        }
        Packet::Unsubscribe(u) => {
            if u.topics.len() > limits::MAX_FILTERS {
                return Err(Why::Refused("more than 64 filters in one UNSUBSCRIBE"));
            }
            lock(&shared.state).unsubscribe(client_id, me, &u.topics);
            wire::write(s, &Packet::UnsubAck(UnsubAck::new(u.pkid))).await?;
        }
        Packet::PingReq => wire::write(s, &Packet::PingResp).await?,
        Packet::Connect(_) => return Err(WireError::Malformed("a second CONNECT".into()).into()),
        _ => {
            return Err(WireError::Malformed("a server's packet from a client".into()).into());
        }
    }
    Ok(Vec::new())
}

#[cfg(test)]
mod tests;
