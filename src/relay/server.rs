//! `droidctl serve`: the relay server. Clients speak spherov2's protocol
//! ([`super::protocol`]); droids sit behind a [`GattBackend`].
//!
//! Each client is a task with its own decoder, a bounded send queue and a writer task; it
//! holds at most one droid, and a droid belongs to one client at a time. Whatever ends a
//! client (END, a closed or silent connection, a protocol error, a reader too slow for its
//! notifications, the server stopping) releases its droid: the family's stop command is
//! written first, so a droid never keeps rolling for a client that is gone.
//!
//! Nothing a client sends can make the server panic or grow without bound: lengths are
//! checked before anything is allocated ([`Limits`]), a request must arrive whole within
//! [`ServerConfig::request_timeout`] of its first byte, replies queue up to
//! [`ServerConfig::send_queue`] and a write to the client may stall at most
//! [`ServerConfig::write_timeout`], and at most [`ServerConfig::max_clients`] are served at
//! once (the next one gets an ERROR and is closed).

use super::backend::{Connected, DroidEvent, GattBackend, GattConnection};
pub use super::events::ServerEvent;
use super::stream::{
    ClientReader, ClientWriter, READ_CHUNK, read_while_busy, take_requests, write_loop,
};
pub use super::stream::{MAX_QUEUED, MAX_QUEUED_SCANS};
use crate::gatt::{CharRole, Endpoint, GattUuid};
use crate::model::Model;
use crate::protocol::relay::{DecodeError, Device, Limits, Reply, Request, RequestDecoder};
use crate::sync::lock;
use std::collections::{HashMap, VecDeque};
use std::future::Future;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite};
use tokio::net::{TcpListener, TcpSocket};
use tokio::sync::{Semaphore, mpsc, watch};
use tokio::time::{Instant, sleep_until, timeout};

/// The server's limits and timeouts.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// Clients served at once; the next one is told so and closed.
    pub max_clients: usize,
    /// A client that sends nothing for this long is closed and its droid stopped (`None`:
    /// never). droidctl polls the battery every 10 s; spherov2 programs write as they go.
    pub idle_timeout: Option<Duration>,
    /// A request must arrive whole within this long of its first byte.
    pub request_timeout: Duration,
    /// Replies and notifications waiting for a client; a client that lets more pile up
    /// cannot keep up and is dropped.
    pub send_queue: usize,
    /// Longest a write to a client may stall before it is dropped.
    pub write_timeout: Duration,
    /// Longest SCAN or FIND, whatever the client asks.
    pub max_scan: Duration,
    /// Connecting to a droid.
    pub connect_timeout: Duration,
    /// Each write and subscribe.
    pub op_timeout: Duration,
    pub limits: Limits,
    /// The kernel's send buffer for client sockets (`None`: the system's default). Small
    /// buffers make a slow reader show up sooner; tests use them.
    pub send_buffer: Option<u32>,
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            max_clients: 16,
            idle_timeout: Some(Duration::from_secs(60)),
            request_timeout: Duration::from_secs(10),
            send_queue: 512,
            write_timeout: Duration::from_secs(5),
            max_scan: Duration::from_secs(30),
            connect_timeout: Duration::from_secs(20),
            op_timeout: Duration::from_secs(5),
            limits: Limits::default(),
            send_buffer: None,
        }
    }
}

/// Where events go: the CLI prints them, tests collect them.
pub type EventSink = Arc<dyn Fn(&ServerEvent) + Send + Sync>;

/// Bind `addr` for [`serve`], with the socket options of `cfg`.
pub async fn bind(addr: SocketAddr, cfg: &ServerConfig) -> std::io::Result<TcpListener> {
    let socket = if addr.is_ipv4() {
        TcpSocket::new_v4()?
    } else {
        TcpSocket::new_v6()?
    };
    // Restarting the server must not wait for old connections' TIME_WAIT (on Windows the
    // option would let another program take the port, so it stays off there).
    #[cfg(unix)]
    socket.set_reuseaddr(true)?;
    if let Some(n) = cfg.send_buffer {
        socket.set_send_buffer_size(n)?;
    }
    socket.bind(addr)?;
    socket.listen(128)
}

struct Holder {
    client: u64,
    peer: SocketAddr,
}

struct Shared {
    cfg: ServerConfig,
    backend: Arc<dyn GattBackend>,
    sink: EventSink,
    /// Droids held, by upper-case address.
    held: Mutex<HashMap<String, Holder>>,
    next_id: AtomicU64,
    slots: Arc<Semaphore>,
}

impl Shared {
    fn new(backend: Arc<dyn GattBackend>, cfg: ServerConfig, sink: EventSink) -> Arc<Shared> {
        Arc::new(Shared {
            slots: Arc::new(Semaphore::new(cfg.max_clients)),
            cfg,
            backend,
            sink,
            held: Mutex::new(HashMap::new()),
            next_id: AtomicU64::new(1),
        })
    }

    /// A new client's task, announced.
    fn client(self: &Arc<Self>, peer: SocketAddr) -> ClientTask {
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        self.emit(ServerEvent::ClientConnected {
            client: id,
            peer: peer.to_string(),
            clients: self.connected(),
        });
        ClientTask::new(self.clone(), id, peer)
    }

    fn emit(&self, e: ServerEvent) {
        match &e {
            ServerEvent::ProtocolError { .. }
            | ServerEvent::ClientRejected { .. }
            | ServerEvent::RequestFailed { .. } => tracing::warn!(event = ?e, "relay"),
            _ => tracing::info!(event = ?e, "relay"),
        }
        (self.sink)(&e);
    }

    fn connected(&self) -> usize {
        self.cfg.max_clients - self.slots.available_permits()
    }
}

/// Serve clients on `listener` until `shutdown` completes; then every client is closed and
/// its droid stopped and released (within a few seconds).
pub async fn serve(
    listener: TcpListener,
    backend: Arc<dyn GattBackend>,
    cfg: ServerConfig,
    sink: EventSink,
    shutdown: impl Future<Output = ()>,
) {
    let shared = Shared::new(backend, cfg, sink);
    if let Ok(a) = listener.local_addr() {
        shared.emit(ServerEvent::Listening {
            address: a.to_string(),
            backend: shared.backend.describe(),
        });
    }
    let (stop_tx, stop_rx) = watch::channel(false);
    let mut tasks = tokio::task::JoinSet::new();
    tokio::pin!(shutdown);
    loop {
        let accepted = tokio::select! {
            _ = &mut shutdown => break,
            a = listener.accept() => a,
            // Reap finished clients so the set stays small.
            Some(_) = tasks.join_next(), if !tasks.is_empty() => continue,
        };
        let (stream, peer) = match accepted {
            Ok(a) => a,
            Err(e) => {
                // Out of file descriptors and the like: do not spin.
                tracing::warn!(error = %e, "accept failed");
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            }
        };
        let Ok(permit) = shared.slots.clone().try_acquire_owned() else {
            let reason = format!(
                "the relay serves {} clients already; try again later",
                shared.cfg.max_clients
            );
            // Best effort and without waiting: a flood must not tie up the accept loop.
            if let Ok(b) = Reply::error(&reason, None).to_bytes() {
                let _ = stream.try_write(&b);
            }
            drop(stream);
            shared.emit(ServerEvent::ClientRejected {
                peer: peer.to_string(),
                reason,
            });
            continue;
        };
        let _ = stream.set_nodelay(true);
        let (rd, wr) = stream.into_split();
        let client = shared.client(peer);
        let stop = stop_rx.clone();
        tasks.spawn(async move {
            client.run(Box::new(rd), Box::new(wr), stop).await;
            drop(permit);
        });
    }
    let _ = stop_tx.send(true);
    // Each client stops its droid (bounded by the op timeout) and closes.
    let _ = timeout(Duration::from_secs(10), async {
        while tasks.join_next().await.is_some() {}
    })
    .await;
}

/// Serve one client over any byte stream (`peer` names it in events) until it ends, as
/// [`serve`] serves each TCP connection: for tests and fuzzing in one process, no sockets.
pub async fn serve_stream(
    stream: impl AsyncRead + AsyncWrite + Send + 'static,
    peer: SocketAddr,
    backend: Arc<dyn GattBackend>,
    cfg: ServerConfig,
    sink: EventSink,
) {
    let shared = Shared::new(backend, cfg, sink);
    let (rd, wr) = tokio::io::split(stream);
    // Nobody stops this server: the client ends it.
    let (_stop, never) = watch::channel(false);
    let _slot = shared.slots.clone().try_acquire_owned();
    shared
        .client(peer)
        .run(Box::new(rd), Box::new(wr), never)
        .await;
}

/// The droid a client holds.
struct Held {
    conn: Box<dyn GattConnection>,
    events: mpsc::Receiver<DroidEvent>,
    name: String,
    address: String,
    key: String,
    /// The model whose stop command is written when the client goes.
    stop_as: Option<Model>,
    /// The client's writes read as its family's commands, to know the last drive: the stop
    /// keeps its heading (a stop at heading 0 would turn the droid on the spot).
    writes: Option<Box<dyn crate::family::Reader>>,
    last_drive: Option<crate::family::Command>,
    /// Characteristics subscribed to, with the UUID as the client wrote it (ON_DATA echoes
    /// it, so a client that subscribed to `2a00` hears about `2a00`).
    subscribed: HashMap<GattUuid, String>,
}

/// Why the client task ends.
struct Close(String);

struct ClientTask {
    shared: Arc<Shared>,
    id: u64,
    peer: SocketAddr,
    tx: Option<mpsc::Sender<Vec<u8>>>,
    droid: Option<Held>,
    requests: u64,
    writes: u64,
    notifications: u64,
}

impl ClientTask {
    fn new(shared: Arc<Shared>, id: u64, peer: SocketAddr) -> Self {
        ClientTask {
            shared,
            id,
            peer,
            tx: None,
            droid: None,
            requests: 0,
            writes: 0,
            notifications: 0,
        }
    }

    fn cfg(&self) -> &ServerConfig {
        &self.shared.cfg
    }

    async fn run(
        mut self,
        mut rd: ClientReader,
        wr: ClientWriter,
        mut stop: watch::Receiver<bool>,
    ) {
        let (tx, rx) = mpsc::channel(self.cfg().send_queue.max(1));
        self.tx = Some(tx);
        let mut writer = tokio::spawn(write_loop(wr, rx, self.cfg().write_timeout));
        let mut decoder = RequestDecoder::new(self.cfg().limits);
        let mut buf = vec![0u8; READ_CHUNK];
        let mut last_heard = Instant::now();
        let mut partial_since: Option<Instant> = None;
        let mut writer_done = false;
        // Requests decoded and waiting their turn, at most `MAX_QUEUED`.
        let mut queue: VecDeque<Result<Request, DecodeError>> = VecDeque::new();
        let reason = 'client: loop {
            // Whole requests first, in order. Time spent serving them (a scan, a connect) is
            // not the client's silence; while one runs, the server's stop and the client's
            // departure are still heard, so a droid is never left to a long scan.
            let mut served = false;
            loop {
                if let Err(why) = take_requests(&mut decoder, &mut queue, false) {
                    self.protocol_error(why.clone());
                    let _ = self.send(&Reply::error(&why, None));
                    break 'client why;
                }
                let Some(r) = queue.pop_front() else { break };
                served = true;
                let flow = match r {
                    Ok(req) => {
                        self.requests += 1;
                        let busy = read_while_busy(&mut rd, &mut buf, &mut decoder, &mut queue);
                        // The request first: one answered at once never lets the client's
                        // backlog be read into the queue; a slow one does.
                        tokio::select! {
                            biased;
                            flow = self.handle(req) => flow,
                            _ = stop.changed() => Err(Close("the server is stopping".into())),
                            why = busy => {
                                if why.starts_with("more than") {
                                    self.protocol_error(why.clone());
                                    let _ = self.send(&Reply::error(&why, None));
                                }
                                Err(Close(why))
                            }
                        }
                    }
                    Err(e) => self.decode_error(e),
                };
                if let Err(Close(why)) = flow {
                    break 'client why;
                }
            }
            if served {
                last_heard = Instant::now();
                // What is buffered now is a new request: its own time runs from here (the
                // first partial read of a steady stream is long gone).
                partial_since = None;
            }
            partial_since = match (decoder.buffered(), partial_since) {
                (0, _) => None,
                (_, Some(t)) => Some(t),
                (_, None) => Some(Instant::now()),
            };
            // Checked: a configured timeout too long for the clock means "never".
            let idle_at = self
                .cfg()
                .idle_timeout
                .and_then(|d| last_heard.checked_add(d));
            let partial_at = partial_since.and_then(|t| t.checked_add(self.cfg().request_timeout));
            let deadline = match (idle_at, partial_at) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            };
            tokio::select! {
                r = rd.read(&mut buf) => match r {
                    Ok(0) => {
                        if let Some(e) = decoder.finish() {
                            self.protocol_error(e.to_string());
                        }
                        break 'client "the client disconnected".to_string();
                    }
                    Ok(n) => {
                        last_heard = Instant::now();
                        decoder.push(&buf[..n]);
                    }
                    Err(e) => break 'client format!("reading failed: {e}"),
                },
                ev = next_event(&mut self.droid) => {
                    if let Err(Close(why)) = self.on_droid_event(ev) {
                        break 'client why;
                    }
                }
                _ = sleep_until(deadline.unwrap_or_else(Instant::now)), if deadline.is_some() => {
                    if partial_at.is_some_and(|t| t <= Instant::now()) {
                        self.protocol_error(format!(
                            "a request did not arrive whole within {:.0} s",
                            self.cfg().request_timeout.as_secs_f64()
                        ));
                        break 'client "incomplete request".to_string();
                    }
                    break 'client format!(
                        "silent for {:.0} s",
                        self.cfg().idle_timeout.unwrap_or_default().as_secs_f64()
                    );
                }
                w = &mut writer => {
                    writer_done = true;
                    break 'client w.unwrap_or_else(|e| format!("writer failed: {e}"));
                }
                _ = stop.changed() => break 'client "the server is stopping".to_string(),
            }
        };
        self.release(&reason).await;
        // Let queued replies (a last ERROR) go out, then close.
        self.tx = None;
        if !writer_done {
            match timeout(self.cfg().write_timeout, &mut writer).await {
                Ok(_) => {}
                Err(_) => writer.abort(),
            }
        }
        self.shared.emit(ServerEvent::ClientClosed {
            client: self.id,
            peer: self.peer.to_string(),
            reason,
            requests: self.requests,
            writes: self.writes,
            notifications: self.notifications,
        });
    }

    /// Queue a reply; a client whose queue is full cannot keep up and is closed.
    fn send(&mut self, reply: &Reply) -> Result<(), Close> {
        let bytes = match reply.to_bytes() {
            Ok(b) => b,
            Err(e) => {
                // Our own replies always fit; if one did not, say so rather than panic.
                tracing::error!(error = %e, ?reply, "cannot encode a reply");
                return Ok(());
            }
        };
        let Some(tx) = &self.tx else {
            return Err(Close("the connection is closing".into()));
        };
        match tx.try_send(bytes) {
            Ok(()) => Ok(()),
            Err(mpsc::error::TrySendError::Full(_)) => Err(Close(format!(
                "the client cannot keep up: {} replies waiting",
                self.cfg().send_queue
            ))),
            Err(mpsc::error::TrySendError::Closed(_)) => {
                Err(Close("the connection to the client failed".into()))
            }
        }
    }

    fn protocol_error(&self, error: String) {
        self.shared.emit(ServerEvent::ProtocolError {
            client: self.id,
            peer: self.peer.to_string(),
            error,
        });
    }

    fn failed(
        &mut self,
        request: &'static str,
        error: String,
        seq: Option<u8>,
    ) -> Result<(), Close> {
        self.shared.emit(ServerEvent::RequestFailed {
            client: self.id,
            peer: self.peer.to_string(),
            request,
            error: error.clone(),
        });
        self.send(&Reply::error(&error, seq))
    }

    fn decode_error(&mut self, e: crate::protocol::relay::DecodeError) -> Result<(), Close> {
        let msg = e.to_string();
        self.protocol_error(msg.clone());
        self.send(&Reply::error(&msg, e.seq()))?;
        if e.recoverable() {
            Ok(())
        } else {
            Err(Close(format!("protocol error: {msg}")))
        }
    }

    fn scan_time(&self, t: f32) -> Duration {
        let max = self.cfg().max_scan;
        if !t.is_finite() || t <= 0.0 {
            return Duration::ZERO;
        }
        Duration::try_from_secs_f32(t).unwrap_or(max).min(max)
    }

    async fn handle(&mut self, req: Request) -> Result<(), Close> {
        tracing::debug!(client = self.id, request = req.name(), "request");
        let op = self.cfg().op_timeout;
        match req {
            Request::Scan { timeout: t } => {
                let t = self.scan_time(t);
                match timeout(t + op, self.shared.backend.scan(t)).await {
                    Ok(Ok(devices)) => {
                        let list: Vec<Device> = devices
                            .into_iter()
                            .take(u16::MAX as usize)
                            .map(|d| Device {
                                name: d.name,
                                address: d.address,
                            })
                            .filter(|d| d.address.is_ascii())
                            .collect();
                        self.send(&Reply::Devices(list))
                    }
                    Ok(Err(e)) => self.failed("SCAN", e.0, None),
                    Err(_) => self.failed("SCAN", "the scan did not finish".into(), None),
                }
            }
            Request::Find { name, timeout: t } => {
                let t = self.scan_time(t);
                match timeout(t + op, self.shared.backend.find(&name, t)).await {
                    Ok(Ok(Some(d))) if d.address.is_ascii() => self.send(&Reply::Found(Device {
                        name: d.name,
                        address: d.address,
                    })),
                    // An empty message: "not found" to spherov2's client.
                    Ok(Ok(_)) => self.send(&Reply::error("", None)),
                    Ok(Err(e)) => self.failed("FIND", e.0, None),
                    Err(_) => self.failed("FIND", "the scan did not finish".into(), None),
                }
            }
            Request::Init { seq, address } => self.init(seq, address).await,
            Request::SetCallback {
                seq,
                characteristic,
            } => {
                let Some(uuid) = GattUuid::parse(&characteristic) else {
                    return self.failed(
                        "SET_CALLBACK",
                        format!("{characteristic:?} is not a characteristic UUID"),
                        Some(seq),
                    );
                };
                let Some(held) = &mut self.droid else {
                    return self.failed("SET_CALLBACK", no_droid(), Some(seq));
                };
                if let Some(name) = held.subscribed.get_mut(&uuid) {
                    // Already notifying: only the name echoed in ON_DATA changes.
                    *name = characteristic;
                    return self.send(&Reply::Ok { seq });
                }
                match timeout(op, held.conn.subscribe(uuid)).await {
                    Ok(Ok(())) => {
                        held.subscribed.insert(uuid, characteristic);
                        self.send(&Reply::Ok { seq })
                    }
                    Ok(Err(e)) => self.failed("SET_CALLBACK", e.0, Some(seq)),
                    Err(_) => {
                        self.failed("SET_CALLBACK", "subscribing timed out".into(), Some(seq))
                    }
                }
            }
            Request::Write {
                seq,
                characteristic,
                data,
            } => {
                let Some(uuid) = GattUuid::parse(&characteristic) else {
                    return self.failed(
                        "WRITE",
                        format!("{characteristic:?} is not a characteristic UUID"),
                        Some(seq),
                    );
                };
                let Some(held) = &mut self.droid else {
                    return self.failed("WRITE", no_droid(), Some(seq));
                };
                match timeout(op, held.conn.write(uuid, &data)).await {
                    Ok(Ok(())) => {
                        self.writes += 1;
                        held.note_write(uuid, &data);
                        self.send(&Reply::Ok { seq })
                    }
                    Ok(Err(e)) => self.failed("WRITE", e.0, Some(seq)),
                    Err(_) => self.failed("WRITE", "the write timed out".into(), Some(seq)),
                }
            }
            Request::End => Err(Close("the client ended the session".into())),
        }
    }

    async fn init(&mut self, seq: u8, address: String) -> Result<(), Close> {
        if let Some(h) = &self.droid {
            let msg = format!(
                "this connection holds {} ({}) already; open another connection for another droid",
                h.name, h.address
            );
            return self.failed("INIT", msg, Some(seq));
        }
        let key = address.trim().to_ascii_uppercase();
        {
            let mut held = lock(&self.shared.held);
            if let Some(h) = held.get(&key) {
                let msg = format!(
                    "{address} is in use by client {} ({}); it is released when that client \
                     disconnects",
                    h.client, h.peer
                );
                drop(held);
                return self.failed("INIT", msg, Some(seq));
            }
            held.insert(
                key.clone(),
                Holder {
                    client: self.id,
                    peer: self.peer,
                },
            );
        }
        let limit = self.cfg().connect_timeout;
        let result = timeout(limit, self.shared.backend.connect(&address)).await;
        let c: Connected = match result {
            Ok(Ok(c)) => c,
            Ok(Err(e)) => {
                self.unhold(&key);
                return self.failed("INIT", e.0, Some(seq));
            }
            Err(_) => {
                self.unhold(&key);
                return self.failed(
                    "INIT",
                    format!(
                        "connecting to {address} timed out after {:.0} s",
                        limit.as_secs_f64()
                    ),
                    Some(seq),
                );
            }
        };
        let name = if c.name.is_empty() {
            address.clone()
        } else {
            c.name
        };
        self.shared.emit(ServerEvent::DroidConnected {
            client: self.id,
            peer: self.peer.to_string(),
            name: name.clone(),
            address: address.clone(),
            model: c.model.map(Model::id),
        });
        self.droid = Some(Held {
            conn: c.connection,
            events: c.events,
            name,
            address,
            key,
            stop_as: c.stop_as,
            writes: c
                .stop_as
                .map(|m| crate::family::for_model(m).side_reader(crate::family::Side::Host, false)),
            last_drive: None,
            subscribed: HashMap::new(),
        });
        self.send(&Reply::Ok { seq })
    }

    fn unhold(&self, key: &str) {
        let mut held = lock(&self.shared.held);
        if held.get(key).is_some_and(|h| h.client == self.id) {
            held.remove(key);
        }
    }

    fn on_droid_event(&mut self, ev: Option<DroidEvent>) -> Result<(), Close> {
        let ev = ev.unwrap_or_else(|| DroidEvent::Disconnected("the droid's link ended".into()));
        match ev {
            DroidEvent::Notification {
                characteristic,
                value,
            } => {
                let Some(name) = self
                    .droid
                    .as_ref()
                    .and_then(|h| h.subscribed.get(&characteristic))
                    .cloned()
                else {
                    return Ok(());
                };
                // ON_DATA carries at most 255 bytes.
                for piece in value.chunks(u8::MAX as usize) {
                    self.notifications += 1;
                    self.send(&Reply::Data {
                        characteristic: name.clone(),
                        data: piece.to_vec(),
                    })?;
                }
                Ok(())
            }
            DroidEvent::Disconnected(reason) => {
                // spherov2's protocol has no message for this: closing the connection is the
                // one signal every client understands (droidctl reconnects).
                Err(Close(format!("the droid disconnected: {reason}")))
            }
        }
    }

    /// Stop the droid (when its model is known and it is still there), disconnect, release.
    async fn release(&mut self, reason: &str) {
        let Some(mut held) = self.droid.take() else {
            return;
        };
        let gone = reason.starts_with("the droid disconnected");
        let pose = held.conn.pose();
        let stopped = match held.stop_as {
            Some(model) if !gone => {
                let last = held.last_drive.take();
                stop(&mut *held.conn, model, last.as_ref(), self.cfg().op_timeout).await
            }
            _ => false,
        };
        let _ = timeout(self.cfg().op_timeout, held.conn.disconnect()).await;
        self.unhold(&held.key);
        self.shared.emit(ServerEvent::DroidReleased {
            client: self.id,
            name: held.name,
            address: held.address,
            stopped,
            reason: reason.to_string(),
            pose,
        });
    }
}

fn no_droid() -> String {
    "no droid: send INIT with its address first".to_string()
}

/// The held droid's next event; pending forever without one.
async fn next_event(droid: &mut Option<Held>) -> Option<DroidEvent> {
    match droid {
        Some(h) => h.events.recv().await,
        None => std::future::pending().await,
    }
}

impl Held {
    /// Read what the client wrote as its family's commands and keep the last drive.
    fn note_write(&mut self, uuid: GattUuid, data: &[u8]) {
        let (Some(model), Some(reader)) = (self.stop_as, self.writes.as_mut()) else {
            return;
        };
        let family = crate::family::for_model(model);
        let to = match crate::family::gatt_profile(model).role_of(uuid) {
            Some(CharRole::Channel) => Endpoint::Api,
            Some(CharRole::Input(e)) => e,
            // Handshake writes are not commands.
            _ => return,
        };
        let mut last = None;
        // Reading into memory cannot fail.
        let _ = reader.write(
            to,
            data,
            Some(&mut |f| {
                if let Some((cmd, _, _)) = f.packet().and_then(|p| p.as_command())
                    && family.is_drive(&cmd)
                {
                    last = Some(cmd);
                }
                Ok(())
            }),
        );
        if last.is_some() {
            self.last_drive = last;
        }
    }
}

/// Write the family's stop (speed 0, at the heading of `last`, the client's last drive) to
/// the droid, to the characteristics its profile names.
pub async fn stop(
    conn: &mut dyn GattConnection,
    model: Model,
    last: Option<&crate::family::Command>,
    op: Duration,
) -> bool {
    let family = crate::family::for_model(model);
    let cmd = family.stop_after(last);
    let (writes, _) = family.codec_for(model).encode_writes(&cmd, 0, false);
    let profile = crate::family::gatt_profile(model);
    let mut ok = true;
    for (endpoint, bytes) in writes {
        let Some(ch) = profile.endpoint(endpoint) else {
            ok = false;
            continue;
        };
        for chunk in bytes.chunks(profile.chunk_size.max(1)) {
            match timeout(op, conn.write(ch.characteristic, chunk)).await {
                Ok(Ok(())) => {}
                _ => {
                    ok = false;
                    break;
                }
            }
        }
    }
    ok
}
