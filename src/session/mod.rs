//! A session over a [`Link`]: SEQ numbering, request/response matching with timeouts,
//! notification fan-out, write pacing and chunking, latest-wins coalescing of continuous
//! controls, a packet log, and automatic reconnection.
//!
//! The rules (what to write when, SEQ numbers, retries, expiry, keep-alive, the urgent stop)
//! are [`core::SessionCore`]'s, which does no I/O and reads no clock: time is passed in, so
//! they are unit-tested on plain instants. A small tokio task ([`task`]) owns the link and
//! drives the core; callers hold a cheap, cloneable [`SessionHandle`], which reaches the core
//! through one short lock. The driver's clock is `tokio::time`, so tests run with paused time.

pub(crate) mod core;
pub mod queue;
mod task;

pub use queue::{Latest, Mark, Slot};

use self::core::SessionCore;
use crate::family::{Command, DecodeError, DroidError, Explained, Packet};
use crate::link::Link;
use crate::link::backoff::Backoff;
use crate::model::Protocol;
use crate::protocol::notify::Notification;
use crate::sync::lock;
use queue::Reply;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::{Notify, broadcast, oneshot, watch};

/// Session settings. Defaults follow `droid-facts.md` §1 for R2-D2.
#[derive(Debug, Clone)]
pub struct SessionConfig {
    /// The protocol family spoken on the link (from the model).
    pub family: Protocol,
    /// How long a written request waits for its response.
    pub request_timeout: Duration,
    /// Minimum interval between writes to the link.
    pub pacing: Duration,
    /// Largest write (the 20-byte ATT payload).
    pub chunk_size: usize,
    pub backoff: Backoff,
    /// Commands run after every (re)connect, in order: wake, stance, streaming, …
    pub setup: Vec<Command>,
    /// Bound of the discrete request queue.
    pub queue_capacity: usize,
    /// Capacity of the log and notification broadcast channels.
    pub event_capacity: usize,
    /// Answer the droid's will-sleep warning with a ping, so it stays awake while droidctl
    /// holds the connection (as spherov2's SpheroEduAPI does).
    pub keep_awake: bool,
    /// The model on the link, when known: its family's codec then addresses each command
    /// to the processor that has it (BOLT, RVR).
    pub model: Option<crate::model::Model>,
}

impl Default for SessionConfig {
    fn default() -> Self {
        SessionConfig {
            family: Protocol::SpheroV2,
            request_timeout: Duration::from_secs(2),
            pacing: Duration::from_millis(120),
            chunk_size: 20,
            backoff: Backoff::default(),
            setup: Vec::new(),
            queue_capacity: 64,
            event_capacity: 4096,
            keep_awake: true,
            model: None,
        }
    }
}

/// Why a request did not get a successful response.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RequestError {
    /// No response within the timeout.
    Timeout,
    /// The droid answered with an error code.
    Droid(DroidError),
    /// The link went down before the response came.
    LinkLost,
    /// Too many requests waiting to be written.
    QueueFull,
    /// The session has ended.
    Closed,
    /// A newer drive command (an e-stop) replaced this drive before it was written.
    Superseded,
}

impl std::fmt::Display for RequestError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RequestError::Timeout => write!(f, "no response from the droid in time"),
            RequestError::Droid(e) => write!(f, "the droid answered {e}"),
            RequestError::LinkLost => write!(f, "the connection was lost"),
            RequestError::QueueFull => write!(f, "too many commands waiting to be sent"),
            RequestError::Closed => write!(f, "the session has ended"),
            RequestError::Superseded => {
                write!(f, "a newer drive command replaced it before it was sent")
            }
        }
    }
}

impl std::error::Error for RequestError {}

/// The connection as the user sees it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinkState {
    Connecting,
    Connected,
    /// Down and retrying; `attempt` counts from 1.
    Reconnecting {
        attempt: u32,
        reason: String,
    },
    /// Ended: by request (`None`) or for good (a fatal link error).
    Closed {
        reason: Option<String>,
    },
}

impl LinkState {
    pub fn label(&self) -> String {
        match self {
            LinkState::Connecting => "connecting".into(),
            LinkState::Connected => "connected".into(),
            // Waiting for the adapter says so: reconnecting would be misleading.
            LinkState::Reconnecting { reason, .. }
                if reason == crate::link::ADAPTER_OFF_WAITING =>
            {
                reason.clone()
            }
            LinkState::Reconnecting { attempt, .. } => format!("reconnecting (attempt {attempt})"),
            LinkState::Closed { reason: None } => "closed".into(),
            LinkState::Closed { reason: Some(r) } => format!("closed: {r}"),
        }
    }
}

/// Direction of a logged packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    In,
    Out,
}

impl Direction {
    pub fn arrow(self) -> &'static str {
        match self {
            Direction::In => "<-",
            Direction::Out => "->",
        }
    }
}

/// One packet-log entry.
#[derive(Debug, Clone, PartialEq)]
pub struct LogEntry {
    /// Time since the session started.
    pub at: Duration,
    pub dir: Direction,
    pub item: LogItem,
}

#[derive(Debug, Clone, PartialEq)]
pub enum LogItem {
    /// A packet, explained by its family's catalogue when it was logged (a v1 response can
    /// only be explained then: its payload layout is the request's).
    Packet {
        packet: Packet,
        explained: Explained,
    },
    DecodeError(DecodeError),
}

impl LogItem {
    /// A packet of any family explained without context (no streaming masks, no request):
    /// for tools and tests that build log entries by hand.
    pub fn packet(p: impl Into<Packet>) -> LogItem {
        let packet = p.into();
        LogItem::Packet {
            explained: crate::family::explain(&packet),
            packet,
        }
    }
}

/// Something the application acts on.
#[derive(Debug, Clone, PartialEq)]
pub enum SessionEvent {
    Notification(Notification),
    /// A known notification whose payload did not fit.
    BadNotification {
        name: &'static str,
        reason: String,
    },
}

/// Counters for the status bar and the run summary.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SessionStats {
    pub sent: u64,
    pub received: u64,
    pub bytes_out: u64,
    pub bytes_in: u64,
    /// Decode errors, error responses and malformed notifications.
    pub errors: u64,
    pub decode_errors: u64,
    pub droid_errors: u64,
    pub timeouts: u64,
    pub answered: u64,
    /// Responses that matched no pending request.
    pub unmatched: u64,
    pub coalesced: u64,
    pub reconnects: u64,
    /// Requests failed because the link went down.
    pub link_lost: u64,
    pub rejected: u64,
    /// Setup commands re-sent after a timeout or a sleeping droid.
    pub retried: u64,
}

/// What the handle and the driver share: the core behind one lock (held only for the core's
/// own pure steps, never across I/O), with the channels of those who wait for answers.
pub(crate) struct Inner {
    pub core: SessionCore,
    replies: HashMap<Reply, oneshot::Sender<Result<Packet, RequestError>>>,
}

impl Inner {
    /// Hand the core's answers to their waiters.
    fn deliver(&mut self) {
        while let Some((id, answer)) = self.core.poll_answer() {
            if let Some(tx) = self.replies.remove(&id) {
                let _ = tx.send(answer);
            }
        }
    }
}

/// How often an emergency stop tries the core's lock before leaving the stop to the driver:
/// the driver holds it only for short pure steps, so a few yields find it free.
const TRY_LOCK_TRIES: u32 = 1000;

/// State shared between the handle and the task.
pub(crate) struct Shared {
    inner: Mutex<Inner>,
    /// Something new for the core (a command, a stop, a setup to redo): the driver looks.
    pub wake: Notify,
    pub shutdown: Mutex<Option<Vec<Command>>>,
    pub shutdown_wake: Notify,
    /// An emergency stop the caller could not hand to the core because its lock was taken
    /// (the panic hook, on the thread that panicked holding it): the driver applies it.
    /// `None` inside means "at the last heading written".
    pub urgent: Mutex<Option<Option<Command>>>,
    /// Emergency stops so far: whatever drives the droid besides the operator (a Sphero Edu
    /// program, `crate::edu`) watches it and ends.
    pub estops: watch::Sender<u64>,
    /// Writes, answers and link losses so far: who waits for a command to leave or be
    /// answered ([`SessionHandle::left`], [`SessionHandle::answered`]) looks again at each
    /// change.
    pub written: watch::Sender<u64>,
}

impl Shared {
    /// Run one step of the core, then hand out the answers it made.
    pub fn with<T>(&self, f: impl FnOnce(&mut SessionCore) -> T) -> T {
        let mut inner = lock(&self.inner);
        let out = f(&mut inner.core);
        inner.deliver();
        out
    }

    /// The core if its lock comes free within a few tries (or is poisoned): never waits for
    /// good, for the emergency paths. The panic hook runs on the thread that panicked, which
    /// may hold this very lock; waiting on it there would never end.
    fn try_with<T>(&self, f: impl FnOnce(&mut SessionCore) -> T) -> Option<T> {
        let mut tries = 0;
        let mut inner = loop {
            match self.inner.try_lock() {
                Ok(g) => break g,
                Err(std::sync::TryLockError::Poisoned(e)) => break e.into_inner(),
                Err(std::sync::TryLockError::WouldBlock) if tries < TRY_LOCK_TRIES => {
                    tries += 1;
                    std::thread::yield_now();
                }
                Err(std::sync::TryLockError::WouldBlock) => return None,
            }
        };
        let out = f(&mut inner.core);
        inner.deliver();
        Some(out)
    }
}

/// A handle to a running session. Cloning is cheap.
#[derive(Clone)]
pub struct SessionHandle {
    shared: Arc<Shared>,
    state: watch::Receiver<LinkState>,
    events: broadcast::Sender<SessionEvent>,
    log: broadcast::Sender<LogEntry>,
    done: Arc<Mutex<Option<tokio::task::JoinHandle<()>>>>,
}

/// Start a session over `link`. Needs a tokio runtime with time enabled.
pub fn start(link: Box<dyn Link>, mut config: SessionConfig) -> SessionHandle {
    // A link with its own framing (a serial line) writes as it needs, whatever the model's
    // Bluetooth chunking and pacing.
    if let Some(f) = link.framing() {
        config.chunk_size = f.chunk_size.max(1);
        config.pacing = f.pacing;
    }
    let now = tokio::time::Instant::now();
    let shared = Arc::new(Shared {
        inner: Mutex::new(Inner {
            core: SessionCore::new(config.clone(), now.into_std()),
            replies: HashMap::new(),
        }),
        wake: Notify::new(),
        shutdown: Mutex::new(None),
        shutdown_wake: Notify::new(),
        urgent: Mutex::new(None),
        estops: watch::channel(0).0,
        written: watch::channel(0).0,
    });
    let (state_tx, state_rx) = watch::channel(LinkState::Connecting);
    let (events, _) = broadcast::channel(config.event_capacity.max(16));
    let (log, _) = broadcast::channel(config.event_capacity.max(16));
    let task = task::Task::new(
        link,
        config,
        shared.clone(),
        state_tx,
        events.clone(),
        log.clone(),
    );
    let join = tokio::spawn(task.run());
    SessionHandle {
        shared,
        state: state_rx,
        events,
        log,
        done: Arc::new(Mutex::new(Some(join))),
    }
}

impl SessionHandle {
    /// Send a request and wait for its response (or a typed error).
    pub async fn request(&self, cmd: impl Into<Command>) -> Result<Packet, RequestError> {
        let (tx, rx) = oneshot::channel();
        self.enqueue(cmd.into(), Some(tx))?;
        rx.await.unwrap_or(Err(RequestError::Closed))
    }

    /// Send a request without waiting. Its response (or error) is still matched and counted.
    pub fn send(&self, cmd: impl Into<Command>) -> Result<(), RequestError> {
        self.enqueue(cmd.into(), None)
    }

    fn enqueue(
        &self,
        cmd: Command,
        tx: Option<oneshot::Sender<Result<Packet, RequestError>>>,
    ) -> Result<(), RequestError> {
        if self.is_closed() {
            return Err(RequestError::Closed);
        }
        {
            let mut inner = lock(&self.shared.inner);
            let reply = inner.core.handle_request(cmd, tx.is_some())?;
            if let (Some(id), Some(tx)) = (reply, tx) {
                inner.replies.insert(id, tx);
            }
        }
        self.shared.wake.notify_one();
        Ok(())
    }

    /// [`Self::send`], with a ticket to learn when it leaves ([`Self::left`]); with `latest`
    /// it replaces the unwritten command with the same key (what one light is set to, say),
    /// so a loop faster than the pacing neither fills the queue nor delays its last state.
    pub fn send_marked(
        &self,
        cmd: impl Into<Command>,
        latest: Option<Latest>,
    ) -> Result<Mark, RequestError> {
        if self.is_closed() {
            return Err(RequestError::Closed);
        }
        let mark = self
            .shared
            .with(|core| core.handle_request_marked(cmd.into(), false, latest))
            .map(|(_, mark)| mark)?;
        self.shared.wake.notify_one();
        Ok(mark)
    }

    /// [`Self::set`], with a ticket to learn when it leaves ([`Self::left`]).
    pub fn set_marked(&self, slot: Slot, cmd: impl Into<Command>) -> Mark {
        let cmd = cmd.into();
        let mark = self
            .shared
            .with(|core| core.handle_write_marked(slot, cmd, true));
        self.shared.wake.notify_one();
        mark.unwrap_or(Mark(0))
    }

    /// The time between two paced writes (a Sphero Edu program holds a light that would
    /// take the slot a timed stop needs, [`crate::edu`]).
    pub fn pacing(&self) -> Duration {
        self.shared.with(|core| core.pacing())
    }

    /// Whether the command with ticket `mark` is still waiting to be written.
    pub fn holds(&self, mark: Mark) -> bool {
        self.shared.with(|core| core.holds(mark))
    }

    /// Wait until the command with ticket `mark` has left the queue (written, replaced by a
    /// newer one, or dropped with the link), at most `limit`; whether it did.
    pub async fn left(&self, mark: Mark, limit: Duration) -> bool {
        self.wait_written(limit, |core| !core.holds(mark)).await
    }

    /// Wait until one of the commands with tickets `marks` no longer awaits anything
    /// (written and answered, or written where nothing answers, or replaced, or dropped with
    /// the link), at most `limit`; whether one did.
    pub async fn answered(&self, marks: &[Mark], limit: Duration) -> bool {
        self.wait_written(limit, |core| marks.iter().any(|m| !core.awaits(*m)))
            .await
    }

    /// Whether the command with ticket `mark` still waits to be written or answered.
    pub fn awaits(&self, mark: Mark) -> bool {
        self.shared.with(|core| core.awaits(mark))
    }

    /// Wait until the request queue has room again, at most `limit`; whether it has.
    pub async fn room(&self, limit: Duration) -> bool {
        self.wait_written(limit, |core| !core.is_full()).await
    }

    /// Wait until nothing is left to write (everything asked for is on the link), at most
    /// `limit`; whether it is so.
    pub async fn drained(&self, limit: Duration) -> bool {
        self.wait_written(limit, |core| !core.has_work()).await
    }

    async fn wait_written(&self, limit: Duration, done: impl Fn(&SessionCore) -> bool) -> bool {
        let mut written = self.shared.written.subscribe();
        let wait = async {
            loop {
                written.mark_unchanged();
                if self.is_closed() || self.shared.with(|core| done(core)) {
                    return;
                }
                if written.changed().await.is_err() {
                    return;
                }
            }
        };
        tokio::time::timeout(limit, wait).await.is_ok() && self.shared.with(|core| done(core))
    }

    /// Set the latest value of a continuous control (drive or head): replaces any older
    /// unwritten one, and a drive the drive commands queued before it. Never blocks, never
    /// queues more than one per slot.
    pub fn set(&self, slot: Slot, cmd: impl Into<Command>) {
        let cmd = cmd.into();
        self.shared.with(|core| core.handle_write(slot, cmd));
        self.shared.wake.notify_one();
    }

    /// Commands waiting to be written (slots included).
    pub fn queued(&self) -> usize {
        self.shared.with(|core| core.queued())
    }

    pub fn state(&self) -> LinkState {
        self.state.borrow().clone()
    }

    /// A receiver of link-state changes.
    pub fn watch_state(&self) -> watch::Receiver<LinkState> {
        self.state.clone()
    }

    pub fn subscribe(&self) -> broadcast::Receiver<SessionEvent> {
        self.events.subscribe()
    }

    pub fn subscribe_log(&self) -> broadcast::Receiver<LogEntry> {
        self.log.subscribe()
    }

    /// Stop now, at the heading of the last drive command written (a stop at heading 0
    /// would turn the droid), as an [emergency stop](Self::emergency_stop): ahead of pacing,
    /// and again one slot later. Synchronous and lock-free of the task, for the panic hook.
    pub fn stop_now(&self, family: &dyn crate::family::Family) {
        let done = self.shared.try_with(|core| {
            let stop = family.stop_after(core.last_drive());
            core.emergency_stop(stop);
        });
        if done.is_none() {
            // The core is busy (or this thread panicked holding it): the driver stops the
            // droid at its own last heading as soon as it can.
            *lock(&self.shared.urgent) = Some(None);
        }
        self.after_estop();
    }

    /// An emergency stop: `stop` is written at once, ahead of pacing and of everything
    /// queued (after the rest of a packet already half written, so its framing stays whole),
    /// and again one pacing slot later through the drive slot (stops go first), in case the
    /// droid dropped the first. Drives queued before it are superseded. While the link is
    /// down it waits for the reconnect, whose own first write is a stop too.
    pub fn emergency_stop(&self, stop: impl Into<Command>) {
        let stop = stop.into();
        if let Err(stop) = self
            .shared
            .try_with(|core| core.emergency_stop(stop.clone()))
            .ok_or(stop)
        {
            *lock(&self.shared.urgent) = Some(Some(stop));
        }
        self.after_estop();
    }

    fn after_estop(&self) {
        self.shared.wake.notify_one();
        self.shared.estops.send_modify(|n| *n += 1);
    }

    /// The count of emergency stops, changing with each ([`SessionHandle::emergency_stop`]).
    pub fn watch_estops(&self) -> watch::Receiver<u64> {
        self.shared.estops.subscribe()
    }

    /// Write the connect setup again, ahead of everything queued: a droid woken from sleep
    /// has forgotten its streaming, collision and notification settings.
    pub fn redo_setup(&self) {
        self.shared.with(|core| core.redo_setup());
        self.shared.wake.notify_one();
    }

    /// Replace the connect setup run after every later (re)connect (and by
    /// [`SessionHandle::redo_setup`]): what the operator changed while connected — streaming,
    /// collision detection — survives a reconnect. Nothing is sent now.
    pub fn set_setup(&self, setup: Vec<Command>) {
        self.shared.with(|core| core.set_setup(setup));
    }

    /// What the droid announced once when the current connection opened (Robi 42's
    /// handshake: version and frame interval). A subscriber that starts after the connect
    /// folds these in first; later ones arrive as notifications too.
    pub fn greeting(&self) -> Vec<Notification> {
        self.shared.with(|core| core.greeting().to_vec())
    }

    pub fn stats(&self) -> SessionStats {
        self.shared.with(|core| core.stats())
    }

    pub fn is_closed(&self) -> bool {
        matches!(*self.state.borrow(), LinkState::Closed { .. })
    }

    /// End the session with a stop: speed 0 at the last heading the session wrote (so the
    /// droid does not turn), then `last`, then close. Waits for the task to finish.
    pub async fn shutdown_stopped(&self, last: Vec<Command>) {
        self.shared.with(|core| core.stop_on_shutdown());
        self.shutdown(last).await;
    }

    /// End the session: write `last` (e.g. a stop) first, best effort and bounded in time,
    /// then close the link. Waits for the task to finish.
    pub async fn shutdown(&self, last: Vec<Command>) {
        *lock(&self.shared.shutdown) = Some(last);
        self.shared.shutdown_wake.notify_one();
        let join = lock(&self.done).take();
        if let Some(join) = join {
            let _ = join.await;
        }
    }
}
