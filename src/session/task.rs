//! The session task: one loop that owns the link, the decoder and the pending requests.

use super::queue::{Next, Queued, Reply};
use super::{
    Direction, LinkState, LogEntry, LogItem, RequestError, SessionConfig, SessionEvent, Shared,
    lock,
};
use crate::family::{Codec, Command, Family, Incoming, Key, Packet};
use crate::gatt::Endpoint;
use crate::link::{Connection, Link, LinkEvent};
use crate::protocol::notify::Notification;
use std::collections::{HashMap, VecDeque};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::{broadcast, watch};
use tokio::time::{Instant, sleep, sleep_until, timeout};

/// How long the final commands on shutdown may take, and then closing the link. Together
/// they stay inside the callers' outer limit (3 s), so the stop is never cut short by it.
const SHUTDOWN_BUDGET: Duration = Duration::from_secs(1);
const CLOSE_BUDGET: Duration = Duration::from_millis(1500);

struct Pending {
    deadline: Instant,
    reply: Option<Reply>,
    cmd: Command,
    retries: u8,
    woken: bool,
    quiet: bool,
}

/// Setup commands are re-sent this often before giving up until the next reconnect.
const SETUP_RETRIES: u8 = 2;

pub(super) struct Task {
    link: Box<dyn Link>,
    cfg: SessionConfig,
    shared: Arc<Shared>,
    state: watch::Sender<LinkState>,
    events: broadcast::Sender<SessionEvent>,
    log: broadcast::Sender<LogEntry>,
    start: Instant,
    family: &'static dyn Family,
    seq: u8,
    pending: HashMap<Key, Pending>,
    /// Quiet commands whose refusal was already logged.
    quiet_logged: std::collections::HashSet<String>,
    /// Kept across connections (see `connected`).
    codec: Option<Box<dyn Codec>>,
}

/// Why the connected loop ended.
enum Ended {
    LinkLost(String),
    Shutdown,
}

impl Task {
    pub(super) fn new(
        link: Box<dyn Link>,
        cfg: SessionConfig,
        shared: Arc<Shared>,
        state: watch::Sender<LinkState>,
        events: broadcast::Sender<SessionEvent>,
        log: broadcast::Sender<LogEntry>,
    ) -> Self {
        Task {
            link,
            family: crate::family::for_protocol(cfg.family),
            cfg,
            shared,
            state,
            events,
            log,
            start: Instant::now(),
            seq: 0,
            pending: HashMap::new(),
            quiet_logged: Default::default(),
            codec: None,
        }
    }

    fn shutdown_requested(&self) -> bool {
        lock(&self.shared.shutdown).is_some()
    }

    pub(super) async fn run(mut self) {
        let mut attempt: u32 = 0;
        loop {
            if self.shutdown_requested() {
                break;
            }
            let opened = tokio::select! {
                r = self.link.open() => r,
                _ = self.shared.shutdown_wake.notified() => {
                    // Quitting mid-connect: cancel the attempt too, so the Bluetooth stack
                    // is not left holding a link that hides the droid from other apps.
                    let _ = timeout(CLOSE_BUDGET, self.link.abort_open()).await;
                    break;
                }
            };
            match opened {
                Ok(conn) => {
                    if attempt > 0 {
                        lock(&self.shared.stats).reconnects += 1;
                    }
                    attempt = 0;
                    tracing::info!(link = %self.link.describe(), "connected");
                    lock(&self.shared.greeting).clear();
                    self.state.send_replace(LinkState::Connected);
                    self.queue_setup();
                    match self.connected(conn).await {
                        Ended::Shutdown => break,
                        Ended::LinkLost(reason) => {
                            tracing::warn!(%reason, "link lost");
                            self.fail_all(RequestError::LinkLost);
                            attempt += 1;
                            if !self.wait_retry(attempt, reason).await {
                                break;
                            }
                        }
                    }
                }
                Err(e) if e.fatal => {
                    tracing::error!(error = %e, "link failed for good");
                    self.fail_all(RequestError::Closed);
                    self.state.send_replace(LinkState::Closed {
                        reason: Some(e.message),
                    });
                    return;
                }
                Err(e) => {
                    tracing::warn!(error = %e, attempt, "connect failed");
                    attempt += 1;
                    if !self.wait_retry(attempt, e.message).await {
                        break;
                    }
                }
            }
        }
        self.fail_all(RequestError::Closed);
        self.state.send_replace(LinkState::Closed { reason: None });
    }

    /// Show "reconnecting (attempt N)" and wait the backoff delay, or less when the link
    /// says retrying is worthwhile now (the Bluetooth adapter is back); false on shutdown.
    async fn wait_retry(&mut self, attempt: u32, reason: String) -> bool {
        self.state
            .send_replace(LinkState::Reconnecting { attempt, reason });
        let delay = self.cfg.backoff.delay(attempt);
        let go_on = tokio::select! {
            _ = sleep(delay) => true,
            _ = self.link.retry_hint() => true,
            _ = self.shared.shutdown_wake.notified() => false,
        };
        go_on && !self.shutdown_requested()
    }

    /// After a (re)connect: stop first, then set up. The wake (when the setup starts with
    /// one) and a stop at the last heading go before anything else, the droid's own
    /// fail-safe next, then the rest of the setup, taking turns with drive and dome commands
    /// so those never wait more than one pacing slot behind it.
    fn queue_setup(&mut self) {
        let setup = |cmd| Queued {
            retries: SETUP_RETRIES,
            ..Queued::new(cmd)
        };
        // A setup changed while connected (the streaming or collision settings) replaces the
        // one the session started with, for every later (re)connect.
        if let Some(new) = lock(&self.shared.setup).take() {
            self.cfg.setup = new;
        }
        let mut rest: Vec<Command> = self.cfg.setup.clone();
        let mut gate = Vec::new();
        if let Some(wake) = self.family.wake()
            && rest.first() == Some(&wake)
        {
            gate.push(setup(rest.remove(0)));
        }
        if lock(&self.shared.last_drive).is_some() {
            gate.push(setup(self.stop_command()));
        }
        let n = gate.len();
        let mut items = gate;
        let fail_safe = self.family.fail_safe();
        items.extend(rest.into_iter().map(|cmd| Queued {
            quiet: fail_safe.as_ref() == Some(&cmd),
            ..setup(cmd)
        }));
        lock(&self.shared.queue).push_front(items, n);
    }

    /// Re-send a command that timed out (setup commands, while they have retries) or found
    /// the droid asleep (any command, drive and dome included, once: after a fresh Wake).
    /// Returns the pending entry back when it is not re-sent.
    fn retry(&mut self, p: Pending, asleep: bool) -> Option<Pending> {
        let wake = if asleep { self.family.wake() } else { None };
        let (retries, woken) = match (asleep, wake.is_some()) {
            (true, true) if !p.woken => (p.retries, true),
            _ if p.retries > 0 => (p.retries - 1, p.woken),
            _ => return Some(p),
        };
        let mut items = Vec::new();
        if let Some(wake) = wake.filter(|_| woken && !p.woken) {
            items.push(Queued::new(wake));
        }
        tracing::info!(command = %p.cmd.name(), asleep, "re-sending");
        let gate = items.len();
        items.push(Queued {
            reply: p.reply,
            retries,
            woken,
            quiet: p.quiet,
            ..Queued::new(p.cmd)
        });
        // Only the Wake goes before the slots: a re-sent drive or dome command is itself the
        // newest word only if nothing newer is in its slot, so it goes in the FIFO like a
        // request.
        lock(&self.shared.queue).push_front(items, gate);
        lock(&self.shared.stats).retried += 1;
        None
    }

    /// Speed 0 at the heading of the last drive command written (heading 0 if none).
    fn stop_command(&self) -> Command {
        self.family
            .stop_after(lock(&self.shared.last_drive).as_ref())
    }

    /// Fail every pending and queued request (link lost or closed).
    fn fail_all(&mut self, why: RequestError) {
        let queued = lock(&self.shared.queue).clear();
        let n = self.pending.len() as u64 + queued.len() as u64;
        for r in self.pending.drain().filter_map(|(_, p)| p.reply) {
            let _ = r.send(Err(why.clone()));
        }
        for q in queued {
            if let Some(r) = q.reply {
                let _ = r.send(Err(why.clone()));
            }
        }
        if why == RequestError::LinkLost {
            lock(&self.shared.stats).link_lost += n;
        }
    }

    fn now(&self) -> Duration {
        Instant::now().duration_since(self.start)
    }

    fn log(&self, dir: Direction, item: LogItem) {
        let _ = self.log.send(LogEntry {
            at: self.now(),
            dir,
            item,
        });
    }

    /// The next SEQ: 0..=254, wrapping, skipping one whose response key is still pending.
    fn next_seq(&mut self, codec: &dyn Codec, cmd: &Command) -> u8 {
        for _ in 0..255 {
            let s = self.seq;
            self.seq = if self.seq >= 254 { 0 } else { self.seq + 1 };
            if !self.pending.contains_key(&codec.key(cmd, s)) {
                return s;
            }
        }
        self.seq
    }

    /// Turn the next queued item into wire chunks, registering its pending entry.
    fn take_next(&mut self, codec: &mut dyn Codec) -> Option<Vec<(Endpoint, Vec<u8>)>> {
        let next = lock(&self.shared.queue).pop()?;
        let q = match next {
            Next::Slot(_, c) => Queued::new(c),
            Next::Fifo(q) => q,
        };
        let Queued {
            cmd,
            reply,
            want_response,
            retries,
            woken,
            quiet,
        } = q;
        let want_response = want_response && codec.answers();
        let seq = self.next_seq(codec, &cmd);
        let (writes, packet) = codec.encode_writes(&cmd, seq, want_response);
        if self.family.is_drive(&cmd) {
            *lock(&self.shared.last_drive) = Some(cmd.clone());
        }
        let wire_len: usize = writes.iter().map(|(_, w)| w.len()).sum();
        let chunks = self.chunked(writes);
        if want_response {
            let extra = self.cfg.pacing * (chunks.len().saturating_sub(1) as u32);
            self.pending.insert(
                codec.key(&cmd, seq),
                Pending {
                    deadline: Instant::now() + self.cfg.request_timeout + extra,
                    reply,
                    cmd: cmd.clone(),
                    retries,
                    woken,
                    quiet,
                },
            );
        } else if let Some(r) = reply {
            // Nothing will answer: the written packet is all there is to return.
            let _ = r.send(Ok(packet.clone()));
        }
        {
            let mut st = lock(&self.shared.stats);
            st.sent += 1;
            st.bytes_out += wire_len as u64;
        }
        self.log_packet(codec, Direction::Out, packet, Some(&cmd));
        Some(chunks)
    }

    /// Cut writes into link-sized chunks, each tagged with its endpoint.
    fn chunked(&self, writes: Vec<(Endpoint, Vec<u8>)>) -> Vec<(Endpoint, Vec<u8>)> {
        writes
            .into_iter()
            .flat_map(|(to, w)| {
                w.chunks(self.cfg.chunk_size.max(1))
                    .map(|c| (to, c.to_vec()))
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    fn log_packet(
        &self,
        codec: &dyn Codec,
        dir: Direction,
        packet: Packet,
        request: Option<&Command>,
    ) {
        if self.log.receiver_count() == 0 {
            return;
        }
        let explained = codec.explain(&packet, request);
        self.log(dir, LogItem::Packet { packet, explained });
    }

    fn handle_bytes(&mut self, codec: &mut dyn Codec, bytes: &[u8]) {
        lock(&self.shared.stats).bytes_in += bytes.len() as u64;
        let mut found = Vec::new();
        codec.feed(bytes, &mut found);
        for item in found {
            self.handle_incoming(codec, item);
        }
    }

    fn handle_incoming(&mut self, codec: &mut dyn Codec, item: Incoming) {
        match item {
            Incoming::Error(e) => {
                tracing::debug!(error = %e, "decode error");
                {
                    let mut st = lock(&self.shared.stats);
                    st.decode_errors += 1;
                    st.errors += 1;
                }
                self.log(Direction::In, LogItem::DecodeError(e));
            }
            Incoming::Response { key, error, packet } => {
                lock(&self.shared.stats).received += 1;
                let Some(pending) = self.pending.remove(&key) else {
                    lock(&self.shared.stats).unmatched += 1;
                    return self.log_packet(codec, Direction::In, packet, None);
                };
                let request = pending.cmd.clone();
                // A quiet command's refusal (a fail-safe this firmware does not know) is fine:
                // said once in the log, not counted as an error.
                let quiet = pending.quiet && error.is_some_and(|e| !e.is_target_unavailable());
                {
                    let mut st = lock(&self.shared.stats);
                    st.answered += 1;
                    if error.is_some() && !quiet {
                        st.droid_errors += 1;
                        st.errors += 1;
                    }
                }
                if let Some(err) = &error {
                    if !quiet {
                        tracing::warn!(command = %request.name(), seq = key.2, error = %err, "droid error");
                    } else if self.quiet_logged.insert(request.name()) {
                        tracing::info!(command = %request.name(), error = %err, "the droid does not support this; going on without it");
                    }
                }
                // Asleep (e.g. the setup's Wake was lost): wake it and try again.
                let pending = if error.is_some_and(|e| e.is_target_unavailable()) {
                    self.retry(pending, true)
                } else {
                    Some(pending)
                };
                if let Some(reply) = pending.and_then(|p| p.reply) {
                    let _ = reply.send(match error {
                        None => Ok(packet.clone()),
                        Some(e) => Err(RequestError::Droid(e)),
                    });
                }
                self.log_packet(codec, Direction::In, packet, Some(&request));
            }
            Incoming::Async {
                notifications,
                packet,
            } => {
                lock(&self.shared.stats).received += 1;
                for n in notifications {
                    match n {
                        Ok(n) => {
                            if n.is_greeting() {
                                lock(&self.shared.greeting).push(n.clone());
                            }
                            if n == Notification::WillSleep && self.cfg.keep_awake {
                                tracing::info!("the droid wants to sleep: keeping it awake");
                                let _ =
                                    lock(&self.shared.queue).push(Queued::new(self.family.ping()));
                                self.shared.wake.notify_one();
                            }
                            let _ = self.events.send(SessionEvent::Notification(n));
                        }
                        Err(e) => {
                            lock(&self.shared.stats).errors += 1;
                            let _ = self.events.send(SessionEvent::BadNotification {
                                name: e.name,
                                reason: e.reason,
                            });
                        }
                    }
                }
                self.log_packet(codec, Direction::In, packet, None);
            }
            Incoming::Stray(packet) => {
                lock(&self.shared.stats).received += 1;
                self.log_packet(codec, Direction::In, packet, None);
            }
        }
    }

    fn expire(&mut self) {
        let now = Instant::now();
        let expired: Vec<_> = self
            .pending
            .iter()
            .filter(|(_, p)| p.deadline <= now)
            .map(|(k, _)| *k)
            .collect();
        for k in expired {
            if let Some(p) = self.pending.remove(&k) {
                lock(&self.shared.stats).timeouts += 1;
                tracing::debug!(did = k.0, cid = k.1, seq = k.2, "request timed out");
                let Some(p) = self.retry(p, false) else {
                    continue;
                };
                if let Some(r) = p.reply {
                    let _ = r.send(Err(RequestError::Timeout));
                }
            }
        }
    }

    async fn connected(&mut self, mut conn: Connection) -> Ended {
        // One codec for the whole session: what the droid was told to stream outlives a
        // dropped link (it keeps streaming with the old masks until the setup sets them
        // again), only the byte stream starts afresh.
        let mut codec = self.codec.take().unwrap_or_else(|| match self.cfg.model {
            Some(model) => self.family.codec_for(model),
            None => self.family.codec(),
        });
        codec.reset_stream();
        let ended = self.connected_with(&mut *codec, &mut conn).await;
        self.codec = Some(codec);
        ended
    }

    async fn connected_with(&mut self, codec: &mut dyn Codec, conn: &mut Connection) -> Ended {
        let mut chunks: VecDeque<(Endpoint, Vec<u8>)> = VecDeque::new();
        let mut next_write = Instant::now();
        let keepalive = self.link.keepalive();
        let mut last_write = Instant::now();
        loop {
            let last = lock(&self.shared.shutdown).take();
            if let Some(last) = last {
                self.finish(&mut *codec, conn, chunks, last).await;
                return Ended::Shutdown;
            }
            if self
                .shared
                .redo_setup
                .swap(false, std::sync::atomic::Ordering::SeqCst)
            {
                self.queue_setup();
            }
            let has_work = !chunks.is_empty() || !lock(&self.shared.queue).is_empty();
            let deadline = self.pending.values().map(|p| p.deadline).min();
            tokio::select! {
                biased;
                _ = self.shared.shutdown_wake.notified() => {
                    // Handled at the top of the loop; keep the permit semantics simple.
                    if lock(&self.shared.shutdown).is_none() {
                        continue;
                    }
                }
                _ = self.shared.urgent_wake.notified() => {
                    if let Err(e) = self.write_urgent(codec, conn, &mut chunks).await {
                        conn.writer.close().await;
                        return Ended::LinkLost(format!("write failed: {e}"));
                    }
                    next_write = Instant::now() + self.cfg.pacing;
                    last_write = Instant::now();
                }
                ev = conn.events.recv() => match ev {
                    Some(LinkEvent::Data(bytes)) => self.handle_bytes(codec, &bytes),
                    Some(LinkEvent::Disconnected(reason)) => {
                        conn.writer.close().await;
                        return Ended::LinkLost(reason);
                    }
                    None => return Ended::LinkLost("the link closed".into()),
                },
                _ = sleep_until(next_write), if has_work => {
                    if chunks.is_empty() {
                        chunks.extend(self.take_next(codec).into_iter().flatten());
                    }
                    if let Some((to, chunk)) = chunks.pop_front() {
                        if let Err(e) = conn.writer.write_to(to, &chunk).await {
                            conn.writer.close().await;
                            return Ended::LinkLost(format!("write failed: {e}"));
                        }
                        next_write = Instant::now() + self.cfg.pacing;
                        last_write = Instant::now();
                    }
                }
                // A link that closes when quiet (a relay's idle timeout) gets a harmless
                // write in time.
                _ = sleep_until(last_write + keepalive.unwrap_or_default()), if keepalive.is_some() && !has_work => {
                    let cmd = self.family.keepalive(lock(&self.shared.last_drive).as_ref());
                    tracing::debug!(command = %cmd.name(), "keepalive");
                    let _ = lock(&self.shared.queue).push(Queued {
                        quiet: true,
                        ..Queued::new(cmd)
                    });
                    last_write = Instant::now();
                }
                _ = self.shared.wake.notified(), if !has_work => {}
                _ = sleep_until(deadline.unwrap_or_else(Instant::now)), if deadline.is_some() => self.expire(),
            }
        }
    }

    /// The emergency stop, now: the rest of the packet in flight first (its framing must stay
    /// whole), then the stop, back to back with no pacing. The drive slot holds the same stop
    /// for the re-send one pacing slot later.
    async fn write_urgent(
        &mut self,
        codec: &mut dyn Codec,
        conn: &mut Connection,
        chunks: &mut VecDeque<(Endpoint, Vec<u8>)>,
    ) -> Result<(), crate::link::LinkError> {
        let Some(cmd) = lock(&self.shared.urgent).take() else {
            return Ok(());
        };
        let seq = self.next_seq(codec, &cmd);
        // Nobody waits for this answer; the re-send through the slot is matched as usual.
        let (writes, packet) = codec.encode_writes(&cmd, seq, false);
        if self.family.is_drive(&cmd) {
            *lock(&self.shared.last_drive) = Some(cmd.clone());
        }
        let wire: Vec<_> = chunks.drain(..).chain(self.chunked(writes)).collect();
        {
            let mut st = lock(&self.shared.stats);
            st.sent += 1;
            st.bytes_out += wire.iter().map(|(_, w)| w.len() as u64).sum::<u64>();
        }
        tracing::info!(command = %cmd.name(), "emergency stop written ahead of pacing");
        self.log_packet(codec, Direction::Out, packet, Some(&cmd));
        for (to, chunk) in wire {
            conn.writer.write_urgent(to, &chunk).await?;
        }
        Ok(())
    }

    /// Shutdown: finish the packet in flight, write the final commands (a stop), close.
    async fn finish(
        &mut self,
        codec: &mut dyn Codec,
        conn: &mut Connection,
        chunks: VecDeque<(Endpoint, Vec<u8>)>,
        mut last: Vec<Command>,
    ) {
        let mut wire: Vec<(Endpoint, Vec<u8>)> = chunks.into_iter().collect();
        if self
            .shared
            .stop_on_shutdown
            .load(std::sync::atomic::Ordering::SeqCst)
        {
            last.insert(0, self.stop_command());
        }
        for cmd in last {
            tracing::info!(command = %cmd.name(), data = %crate::hex::spaced(&cmd.data()), "final command");
            let seq = self.next_seq(codec, &cmd);
            // Nobody will wait for these responses.
            let (writes, packet) = codec.encode_writes(&cmd, seq, false);
            wire.extend(self.chunked(writes));
            lock(&self.shared.stats).sent += 1;
            self.log_packet(codec, Direction::Out, packet, Some(&cmd));
        }
        let writer = &mut conn.writer;
        let pacing = self.cfg.pacing;
        let _ = timeout(SHUTDOWN_BUDGET, async {
            for (i, (to, chunk)) in wire.iter().enumerate() {
                if i > 0 {
                    sleep(pacing).await;
                }
                if writer.write_to(*to, chunk).await.is_err() {
                    break;
                }
            }
        })
        .await;
        if timeout(CLOSE_BUDGET, writer.close()).await.is_err() {
            tracing::warn!("closing the link took too long; leaving it");
        }
        tracing::info!("final commands written, link closed");
    }
}
