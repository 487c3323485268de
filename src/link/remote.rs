//! `--remote HOST[:PORT]`: a droid behind a TCP relay (`droidctl serve`, or spherov2.py's
//! own `tcp_server`), speaking spherov2's relay protocol ([`crate::protocol::relay`]).
//!
//! [`RemoteLink`] is a [`Link`] like the BLE one: each `open()` makes a TCP connection,
//! INITs the droid (the relay connects to it), runs the model's handshake writes and
//! subscribes (SET_CALLBACK) to the profile's notify characteristics; ON_DATA becomes
//! [`LinkEvent::Data`], and a closed connection becomes [`LinkEvent::Disconnected`], so
//! the session reconnects with its backoff when the relay, the network or the droid drops.
//!
//! The protocol has no read: a handshake step that reads (Robi 42's version and announced
//! frame interval) is skipped with a warning. The start confirmation is still written, so
//! the frames flow; only the announced interval is unknown.

use crate::gatt::Endpoint;
use crate::gatt::{GattProfile, GattUuid, HandshakeStep};
use crate::link::{Connection, Link, LinkError, LinkEvent, LinkWriter};
use crate::model::Model;
use crate::protocol::relay::{DEFAULT_PORT, Device, Limits, Reply, ReplyDecoder, Request};
use futures_util::future::BoxFuture;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::sync::{mpsc, oneshot};
use tokio::time::{Instant, sleep_until, timeout};

/// A relay's address: `HOST`, `HOST:PORT`, `[v6]:PORT`; the port defaults to spherov2's.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RelayAddr {
    pub host: String,
    pub port: u16,
}

impl std::fmt::Display for RelayAddr {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.host.contains(':') {
            write!(f, "[{}]:{}", self.host, self.port)
        } else {
            write!(f, "{}:{}", self.host, self.port)
        }
    }
}

impl std::str::FromStr for RelayAddr {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        let bad = || format!("`{s}` is not HOST or HOST:PORT");
        if s.is_empty() {
            return Err(bad());
        }
        let port = |p: &str| {
            p.parse::<u16>()
                .ok()
                .filter(|p| *p > 0)
                .ok_or_else(|| format!("`{p}` is not a port (1-65535)"))
        };
        if let Some(rest) = s.strip_prefix('[') {
            let (host, after) = rest.split_once(']').ok_or_else(bad)?;
            let p = match after.strip_prefix(':') {
                Some(p) => port(p)?,
                None if after.is_empty() => DEFAULT_PORT,
                None => return Err(bad()),
            };
            return Ok(RelayAddr {
                host: host.to_string(),
                port: p,
            });
        }
        match s.matches(':').count() {
            0 => Ok(RelayAddr {
                host: s.to_string(),
                port: DEFAULT_PORT,
            }),
            1 => {
                let (h, p) = s.split_once(':').ok_or_else(bad)?;
                if h.is_empty() {
                    return Err(bad());
                }
                Ok(RelayAddr {
                    host: h.to_string(),
                    port: port(p)?,
                })
            }
            // A bare IPv6 address.
            _ => Ok(RelayAddr {
                host: s.to_string(),
                port: DEFAULT_PORT,
            }),
        }
    }
}

/// Timeouts of the relay client.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RemoteTimeouts {
    /// The TCP connection.
    pub connect: Duration,
    /// INIT: the relay connects to the droid (droidctl's relay gives up after 20 s).
    pub init: Duration,
    /// Each WRITE and SET_CALLBACK.
    pub op: Duration,
}

impl Default for RemoteTimeouts {
    fn default() -> Self {
        RemoteTimeouts {
            connect: Duration::from_secs(5),
            init: Duration::from_secs(25),
            op: Duration::from_secs(5),
        }
    }
}

/// ON_DATA and the end of the connection, for the link.
enum Incoming {
    Data {
        characteristic: String,
        data: Vec<u8>,
    },
    Closed(String),
}

/// Waiters for replies.
#[derive(Default)]
struct Waiters {
    seq: HashMap<u8, oneshot::Sender<Result<(), String>>>,
    /// SCAN and FIND, in the order sent.
    discovery: std::collections::VecDeque<oneshot::Sender<Result<Reply, String>>>,
    /// Set when the connection is gone: why.
    closed: Option<String>,
    next_seq: u8,
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// The writing half of a connection to a relay.
type RelayWriter = Box<dyn tokio::io::AsyncWrite + Send + Unpin>;

/// One TCP connection to a relay: requests out, replies matched to their waiters.
struct RelayClient {
    writer: tokio::sync::Mutex<Option<RelayWriter>>,
    decoder: Arc<Mutex<ReplyDecoder>>,
    waiters: Arc<Mutex<Waiters>>,
    reader: tokio::task::JoinHandle<()>,
    relay: RelayAddr,
}

/// Bytes read at once.
const READ_CHUNK: usize = 4096;
/// The longest a session over a relay stays without writing (see [`Link::keepalive`]).
pub const KEEPALIVE: Duration = Duration::from_secs(20);
/// ON_DATA waiting for the link's reader.
const EVENTS: usize = 1024;

impl RelayClient {
    async fn connect(
        relay: &RelayAddr,
        t: Duration,
    ) -> Result<(RelayClient, mpsc::Receiver<Incoming>), LinkError> {
        let target = (relay.host.as_str(), relay.port);
        let stream = match timeout(t, TcpStream::connect(target)).await {
            Ok(Ok(s)) => s,
            Ok(Err(e)) => {
                return Err(LinkError::transient(format!(
                    "cannot reach the relay at {relay}: {e} — is `droidctl serve` (or spherov2's \
                     tcp_server) running there?"
                )));
            }
            Err(_) => {
                return Err(LinkError::transient(format!(
                    "the relay at {relay} did not answer within {:.0} s",
                    t.as_secs_f64()
                )));
            }
        };
        let _ = stream.set_nodelay(true);
        Ok(RelayClient::over(stream, relay))
    }

    /// A client over any byte stream to a relay (a TCP connection; a pipe in tests).
    fn over(
        stream: impl tokio::io::AsyncRead + tokio::io::AsyncWrite + Send + 'static,
        relay: &RelayAddr,
    ) -> (RelayClient, mpsc::Receiver<Incoming>) {
        let (mut rd, wr) = tokio::io::split(stream);
        let decoder = Arc::new(Mutex::new(ReplyDecoder::new(Limits::default())));
        let waiters = Arc::new(Mutex::new(Waiters::default()));
        let (tx, rx) = mpsc::channel(EVENTS);
        let reader = {
            let decoder = decoder.clone();
            let waiters = waiters.clone();
            let relay = relay.clone();
            tokio::spawn(async move {
                let mut buf = vec![0u8; READ_CHUNK];
                let why = loop {
                    let n = match rd.read(&mut buf).await {
                        Ok(0) => {
                            let last = lock(&decoder).finish();
                            break match last {
                                Some(Ok(msg)) if !msg.is_empty() => {
                                    format!("the relay at {relay} closed the connection: {msg}")
                                }
                                _ => format!(
                                    "the relay at {relay} closed the connection (the droid may \
                                     have disconnected)"
                                ),
                            };
                        }
                        Ok(n) => n,
                        Err(e) => {
                            break format!("the connection to the relay at {relay} failed: {e}");
                        }
                    };
                    let mut replies = Vec::new();
                    let mut bad = None;
                    {
                        let mut d = lock(&decoder);
                        d.push(&buf[..n]);
                        while let Some(r) = d.next() {
                            match r {
                                Ok(r) => replies.push(r),
                                Err(e) if e.recoverable() => {
                                    tracing::warn!(error = %e, "relay: bad reply skipped")
                                }
                                Err(e) => {
                                    bad = Some(e);
                                    break;
                                }
                            }
                        }
                    }
                    for r in replies {
                        dispatch(r, &waiters, &tx).await;
                    }
                    if let Some(e) = bad {
                        break format!("the relay at {relay} sent something unexpected: {e}");
                    }
                };
                tracing::info!(reason = %why, "relay connection ended");
                let mut w = lock(&waiters);
                w.closed = Some(why.clone());
                for (_, s) in w.seq.drain() {
                    let _ = s.send(Err(why.clone()));
                }
                for s in w.discovery.drain(..) {
                    let _ = s.send(Err(why.clone()));
                }
                drop(w);
                let _ = tx.try_send(Incoming::Closed(why));
            })
        };
        (
            RelayClient {
                writer: tokio::sync::Mutex::new(Some(Box::new(wr))),
                decoder,
                waiters,
                reader,
                relay: relay.clone(),
            },
            rx,
        )
    }

    /// Send `req`, its expectation registered first so the reply is read right.
    async fn send(&self, req: &Request) -> Result<(), String> {
        let bytes = req.to_bytes().map_err(|e| e.to_string())?;
        let mut w = self.writer.lock().await;
        let wr = w
            .as_mut()
            .ok_or_else(|| format!("the connection to the relay at {} is closed", self.relay))?;
        if let Some(e) = req.expect() {
            lock(&self.decoder).expect(e);
        }
        wr.write_all(&bytes)
            .await
            .map_err(|e| format!("the connection to the relay at {} failed: {e}", self.relay))
    }

    /// A request with a seq: INIT, SET_CALLBACK or WRITE (`make` gets the seq).
    async fn call(&self, make: impl FnOnce(u8) -> Request, limit: Duration) -> Result<(), String> {
        let (tx, rx) = oneshot::channel();
        let seq = {
            let mut w = lock(&self.waiters);
            if let Some(why) = &w.closed {
                return Err(why.clone());
            }
            // The next seq no reply is pending for (256 in flight cannot happen: each call
            // waits for its reply).
            let mut seq = w.next_seq;
            for _ in 0..=u8::MAX {
                if !w.seq.contains_key(&seq) {
                    break;
                }
                seq = seq.wrapping_add(1);
            }
            w.next_seq = seq.wrapping_add(1);
            w.seq.insert(seq, tx);
            seq
        };
        let req = make(seq);
        let name = req.name();
        // The write is bounded too: a relay that stops reading fills the socket's buffers,
        // and an unbounded write would hang the session's writer for good.
        let answered = timeout(limit, async {
            self.send(&req).await?;
            rx.await
                .unwrap_or_else(|_| Err("the relay connection ended".into()))
        })
        .await;
        match answered {
            Ok(r) => {
                if r.is_err() {
                    lock(&self.waiters).seq.remove(&seq);
                }
                r
            }
            Err(_) => {
                lock(&self.waiters).seq.remove(&seq);
                // A request may be half written: the stream cannot be followed any more.
                self.writer.lock().await.take();
                Err(format!(
                    "the relay did not take or answer {name} within {:.0} s",
                    limit.as_secs_f64()
                ))
            }
        }
    }

    /// SCAN or FIND.
    async fn discover(&self, req: Request, limit: Duration) -> Result<Reply, String> {
        let (tx, rx) = oneshot::channel();
        {
            let mut w = lock(&self.waiters);
            if let Some(why) = &w.closed {
                return Err(why.clone());
            }
            w.discovery.push_back(tx);
        }
        let answered = timeout(limit, async {
            self.send(&req).await?;
            rx.await
                .unwrap_or_else(|_| Err("the relay connection ended".into()))
        })
        .await;
        answered.unwrap_or_else(|_| {
            Err(format!(
                "the relay did not take or answer {} within {:.0} s",
                req.name(),
                limit.as_secs_f64()
            ))
        })
    }

    /// END, then close (best effort).
    async fn close(&self) {
        let _ = timeout(Duration::from_secs(1), self.send(&Request::End)).await;
        if let Some(mut wr) = self.writer.lock().await.take() {
            let _ = timeout(Duration::from_secs(1), wr.shutdown()).await;
        }
    }
}

impl Drop for RelayClient {
    fn drop(&mut self) {
        self.reader.abort();
    }
}

async fn dispatch(r: Reply, waiters: &Mutex<Waiters>, tx: &mpsc::Sender<Incoming>) {
    match r {
        Reply::Ok { seq } => {
            if let Some(s) = lock(waiters).seq.remove(&seq) {
                let _ = s.send(Ok(()));
            }
        }
        Reply::Error {
            message,
            seq: Some(seq),
        } => {
            if let Some(s) = lock(waiters).seq.remove(&seq) {
                let _ = s.send(Err(message));
            }
        }
        r @ (Reply::Devices(_) | Reply::Found(_) | Reply::Error { seq: None, .. }) => {
            if let Some(s) = lock(waiters).discovery.pop_front() {
                let _ = s.send(Ok(r));
            }
        }
        Reply::Data {
            characteristic,
            data,
        } => {
            // Wait for room: the link reads continuously; TCP pushes back on the relay.
            let _ = tx
                .send(Incoming::Data {
                    characteristic,
                    data,
                })
                .await;
        }
    }
}

/// A device behind a relay, as its scan lists it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RemoteDevice {
    pub name: String,
    /// As the relay names it; INIT takes it back unchanged.
    pub address: String,
    pub model: Option<Model>,
}

impl RemoteDevice {
    fn from_device(d: Device) -> Self {
        RemoteDevice {
            model: Model::from_advertised_name(&d.name),
            name: d.name,
            address: d.address,
        }
    }

    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "name": self.name,
            "model": self.model.map(Model::id),
            "model_name": self.model.map(Model::display_name),
            "address": self.address,
            "rssi": null,
            // The relay lists what its scan heard.
            "heard": true,
        })
    }
}

/// Every device the relay hears within `scan` (SCAN).
pub async fn scan(relay: &RelayAddr, scan: Duration) -> Result<Vec<RemoteDevice>, LinkError> {
    let t = RemoteTimeouts::default();
    let (client, _events) = RelayClient::connect(relay, t.connect).await?;
    let r = client
        .discover(
            Request::Scan {
                timeout: scan.as_secs_f32(),
            },
            scan + t.op + Duration::from_secs(5),
        )
        .await;
    client.close().await;
    match r.map_err(LinkError::transient)? {
        Reply::Devices(ds) => Ok(ds.into_iter().map(RemoteDevice::from_device).collect()),
        Reply::Error { message, .. } => Err(LinkError::transient(format!(
            "the relay at {relay} could not scan: {message}"
        ))),
        other => Err(LinkError::transient(format!(
            "the relay at {relay} answered SCAN with {other:?}"
        ))),
    }
}

/// The device advertising exactly `name` (FIND); `None` when the relay did not hear it.
pub async fn find(
    relay: &RelayAddr,
    name: &str,
    scan: Duration,
) -> Result<Option<RemoteDevice>, LinkError> {
    let t = RemoteTimeouts::default();
    let (client, _events) = RelayClient::connect(relay, t.connect).await?;
    let r = client
        .discover(
            Request::Find {
                name: name.to_string(),
                timeout: scan.as_secs_f32(),
            },
            scan + t.op + Duration::from_secs(5),
        )
        .await;
    client.close().await;
    match r.map_err(LinkError::transient)? {
        Reply::Found(d) => Ok(Some(RemoteDevice::from_device(d))),
        Reply::Error { message, .. } if message.is_empty() => Ok(None),
        Reply::Error { message, .. } => Err(LinkError::transient(format!(
            "the relay at {relay} could not scan: {message}"
        ))),
        other => Err(LinkError::transient(format!(
            "the relay at {relay} answered FIND with {other:?}"
        ))),
    }
}

/// How to choose the droid behind a relay.
#[derive(Debug, Clone, Default)]
pub struct RemoteSelector {
    /// Advertised name: exact (FIND first), or a unique part (case-insensitive).
    pub name: Option<String>,
    /// The address as the relay lists it (case-insensitive).
    pub address: Option<String>,
    pub scan_timeout: Duration,
}

/// Find the droid `sel` asks for behind `relay` and build the link to it (not connected yet),
/// with the GATT profile `profile_of` gives for its model.
pub async fn select(
    relay: &RelayAddr,
    sel: &RemoteSelector,
    profile_of: fn(Model) -> GattProfile,
) -> Result<RemoteLink, LinkError> {
    let secs = sel.scan_timeout.as_secs_f64();
    let mut chosen = None;
    if let (Some(name), None) = (&sel.name, &sel.address) {
        // FIND answers as soon as the droid is heard.
        chosen = find(relay, name, sel.scan_timeout).await?;
    }
    let chosen = match chosen {
        Some(d) => d,
        None => {
            let all = scan(relay, sel.scan_timeout).await?;
            pick(&all, sel).map_err(|e| {
                LinkError::transient(format!("{e} (the relay at {relay} scanned {secs:.0} s)"))
            })?
        }
    };
    let model = chosen.model.ok_or_else(|| {
        LinkError::fatal(format!(
            "{} ({}) behind the relay is not a droid droidctl knows",
            chosen.name, chosen.address
        ))
    })?;
    tracing::info!(name = %chosen.name, address = %chosen.address, %relay, "chose droid behind relay");
    Ok(RemoteLink::new(
        relay.clone(),
        chosen.address,
        chosen.name,
        model,
        profile_of(model),
    ))
}

/// Choose among the devices a relay listed.
pub fn pick(all: &[RemoteDevice], sel: &RemoteSelector) -> Result<RemoteDevice, String> {
    let droids: Vec<&RemoteDevice> = all.iter().filter(|d| d.model.is_some()).collect();
    let names = |ds: &[&RemoteDevice]| {
        ds.iter()
            .map(|d| format!("{} ({})", d.name, d.address))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(a) = &sel.address {
        let want = a.trim();
        let same = |d: &&RemoteDevice| {
            d.address.eq_ignore_ascii_case(want)
                || matches!(
                    (
                        d.address.parse::<crate::link::ble::BleAddress>(),
                        want.parse::<crate::link::ble::BleAddress>()
                    ),
                    (Ok(x), Ok(y)) if x == y
                )
        };
        return all
            .iter()
            .find(same)
            .cloned()
            .ok_or_else(|| format!("no device at {want} behind the relay"));
    }
    if let Some(n) = &sel.name {
        let lower = n.to_lowercase();
        if let Some(d) = all.iter().find(|d| d.name.to_lowercase() == lower) {
            return Ok(d.clone());
        }
        let parts: Vec<&RemoteDevice> = all
            .iter()
            .filter(|d| d.name.to_lowercase().contains(&lower))
            .collect();
        return match parts.as_slice() {
            [one] => Ok((*one).clone()),
            [] => Err(format!("no droid named like {n:?} behind the relay")),
            many => Err(format!(
                "{n:?} matches several devices behind the relay: {} — give more of the name",
                names(many)
            )),
        };
    }
    match droids.as_slice() {
        [one] => Ok((*one).clone()),
        [] => Err("no droid behind the relay — wake it (tap it or put it on its charger)".into()),
        many => Err(format!(
            "several droids behind the relay: {} — choose one with --name or --address",
            names(many)
        )),
    }
}

/// A droid behind a relay.
pub struct RemoteLink {
    relay: RelayAddr,
    address: String,
    name: String,
    model: Model,
    profile: GattProfile,
    timeouts: RemoteTimeouts,
    warned_read: bool,
}

impl RemoteLink {
    /// The droid at `address` (as the relay names it) behind `relay`, a `model` speaking
    /// `profile`.
    pub fn new(
        relay: RelayAddr,
        address: impl Into<String>,
        name: impl Into<String>,
        model: Model,
        profile: GattProfile,
    ) -> Self {
        RemoteLink {
            relay,
            address: address.into(),
            name: name.into(),
            model,
            profile,
            timeouts: RemoteTimeouts::default(),
            warned_read: false,
        }
    }

    pub fn with_timeouts(mut self, t: RemoteTimeouts) -> Self {
        self.timeouts = t;
        self
    }

    pub fn model(&self) -> Model {
        self.model
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn address(&self) -> &str {
        &self.address
    }

    pub fn profile(&self) -> &GattProfile {
        &self.profile
    }

    async fn open_remote(&mut self) -> Result<Connection, LinkError> {
        let t = self.timeouts;
        let (client, mut incoming) = RelayClient::connect(&self.relay, t.connect).await?;
        let client = Arc::new(client);
        let who = format!("{} ({})", self.name, self.address);
        let fail = |what: &str, e: String| LinkError::transient(format!("{what} {who}: {e}"));
        let setup = async {
            let address = self.address.clone();
            client
                .call(move |seq| Request::Init { seq, address }, t.init)
                .await
                .map_err(|e| fail("the relay could not connect to", e))?;
            for step in &self.profile.handshake {
                match step {
                    HandshakeStep::Write { ch, bytes, .. } => {
                        let uuid = ch.characteristic.to_string();
                        let data = bytes.clone();
                        client
                            .call(
                                move |seq| Request::Write {
                                    seq,
                                    characteristic: uuid,
                                    data,
                                },
                                t.op,
                            )
                            .await
                            .map_err(|e| fail("handshake with", e))?;
                    }
                    HandshakeStep::Read { ch, .. } => {
                        if !self.warned_read {
                            tracing::warn!(
                                characteristic = %ch,
                                "the relay protocol cannot read: handshake read skipped"
                            );
                            self.warned_read = true;
                        }
                    }
                }
            }
            for ch in &self.profile.notify {
                let uuid = ch.characteristic.to_string();
                client
                    .call(
                        move |seq| Request::SetCallback {
                            seq,
                            characteristic: uuid,
                        },
                        t.op,
                    )
                    .await
                    .map_err(|e| fail("subscribing to", e))?;
            }
            Ok::<(), LinkError>(())
        };
        if let Err(e) = setup.await {
            client.close().await;
            return Err(e);
        }
        let notify: Vec<GattUuid> = self
            .profile
            .notify
            .iter()
            .map(|c| c.characteristic)
            .collect();
        let (tx, rx) = mpsc::channel(EVENTS);
        tokio::spawn(async move {
            loop {
                let ev = tokio::select! {
                    _ = tx.closed() => return,
                    ev = incoming.recv() => ev,
                };
                match ev {
                    Some(Incoming::Data {
                        characteristic,
                        data,
                    }) => {
                        let ours =
                            GattUuid::parse(&characteristic).is_some_and(|u| notify.contains(&u));
                        if !ours || data.is_empty() {
                            continue;
                        }
                        if tx.send(LinkEvent::Data(data)).await.is_err() {
                            return;
                        }
                    }
                    Some(Incoming::Closed(why)) => {
                        let _ = tx.send(LinkEvent::Disconnected(why)).await;
                        return;
                    }
                    None => {
                        let _ = tx
                            .send(LinkEvent::Disconnected("the relay connection ended".into()))
                            .await;
                        return;
                    }
                }
            }
        });
        Ok(Connection {
            writer: Box::new(RemoteWriter {
                client: Some(client),
                profile: self.profile.clone(),
                op: t.op,
                next_write: None,
                name: self.name.clone(),
            }),
            events: rx,
        })
    }
}

impl Link for RemoteLink {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            self.open_remote().await.inspect_err(|e| {
                tracing::warn!(error = %e, "relay open failed");
            })
        })
    }

    /// A relay closes a client silent for its idle timeout (`droidctl serve`: 60 s by
    /// default): a third of that is written in time.
    fn keepalive(&self) -> Option<Duration> {
        Some(KEEPALIVE)
    }

    fn describe(&self) -> String {
        format!(
            "{} {} ({}) via {}",
            self.model.display_name(),
            self.name,
            self.address,
            self.relay
        )
    }
}

/// WRITEs to the profile's characteristics, chunked and paced like the BLE writer.
struct RemoteWriter {
    client: Option<Arc<RelayClient>>,
    profile: GattProfile,
    op: Duration,
    next_write: Option<Instant>,
    name: String,
}

impl LinkWriter for RemoteWriter {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_to(Endpoint::Api, chunk)
    }

    fn write_to<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        Box::pin(async move {
            let ch = self.profile.endpoint(to).ok_or_else(|| {
                LinkError::fatal(format!("{} has no {} input", self.name, to.name()))
            })?;
            let client = self
                .client
                .clone()
                .ok_or_else(|| LinkError::transient("the relay link is closed"))?;
            let uuid = ch.characteristic.to_string();
            for piece in chunk.chunks(self.profile.chunk_size.max(1)) {
                if let Some(at) = self.next_write {
                    sleep_until(at).await;
                }
                let (u, data) = (uuid.clone(), piece.to_vec());
                let r = client
                    .call(
                        move |seq| Request::Write {
                            seq,
                            characteristic: u,
                            data,
                        },
                        self.op,
                    )
                    .await;
                self.next_write = Some(Instant::now() + self.profile.pacing);
                r.map_err(|e| LinkError::transient(format!("writing to {}: {e}", self.name)))?;
            }
            Ok(())
        })
    }

    fn close(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async move {
            if let Some(c) = self.client.take() {
                c.close().await;
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A relay that stops reading: a pipe whose buffer is full. A request must give up within
    /// its limit; the write used to wait for room forever, hanging the session's writer.
    #[tokio::test]
    async fn a_write_to_a_relay_that_stops_reading_gives_up() {
        let (ours, _theirs) = tokio::io::duplex(16);
        let relay = RelayAddr {
            host: "pipe".into(),
            port: 0,
        };
        let (client, _events) = RelayClient::over(ours, &relay);
        let write = |seq| Request::Write {
            seq,
            characteristic: "00010002-574f-4f20-5370-6865726f2121".into(),
            data: vec![0x55; 20],
        };
        let r = timeout(
            Duration::from_secs(5),
            client.call(write, Duration::from_millis(200)),
        )
        .await
        .expect("the call gave up by itself");
        let e = r.unwrap_err();
        assert!(e.contains("did not take or answer WRITE"), "{e}");
        // The stream may hold half a request now: later requests fail at once.
        let e = client
            .call(write, Duration::from_millis(200))
            .await
            .unwrap_err();
        assert!(e.contains("closed"), "{e}");
    }

    #[test]
    fn relay_addresses_parse() {
        let p = |s: &str| s.parse::<RelayAddr>();
        assert_eq!(
            p("pi.local"),
            Ok(RelayAddr {
                host: "pi.local".into(),
                port: 50004
            })
        );
        assert_eq!(p("10.0.0.2:6000").unwrap().port, 6000);
        assert_eq!(p("[::1]:7").unwrap().host, "::1");
        assert_eq!(p("[::1]").unwrap().port, 50004);
        assert_eq!(p("::1").unwrap().host, "::1");
        assert_eq!(p("[::1]:7").unwrap().to_string(), "[::1]:7");
        assert!(p("host:0").is_err());
        assert!(p("host:x").is_err());
        assert!(p(":50004").is_err());
        assert!(p("").is_err());
        assert!(p("[::1").is_err());
    }

    #[test]
    fn picking_behind_a_relay() {
        let d = |n: &str, a: &str| RemoteDevice {
            name: n.into(),
            address: a.into(),
            model: Model::from_advertised_name(n),
        };
        let all = vec![
            d("D2-0001", "5E:D0:00:00:00:01"),
            d("Q5-0002", "5E:D0:00:00:00:02"),
            d("TV", "5E:D0:00:00:00:03"),
        ];
        let sel = |name: Option<&str>, address: Option<&str>| RemoteSelector {
            name: name.map(str::to_string),
            address: address.map(str::to_string),
            scan_timeout: Duration::from_secs(1),
        };
        assert_eq!(pick(&all, &sel(Some("q5"), None)).unwrap().name, "Q5-0002");
        assert_eq!(
            pick(&all, &sel(None, Some("5e:d0:00:00:00:01")))
                .unwrap()
                .name,
            "D2-0001"
        );
        assert!(
            pick(&all, &sel(None, None))
                .unwrap_err()
                .contains("several droids")
        );
        assert!(pick(&all, &sel(Some("000"), None)).is_err());
        assert_eq!(pick(&all[..1], &sel(None, None)).unwrap().name, "D2-0001");
    }
}
