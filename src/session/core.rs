//! The session's rules without I/O, in the manner of quinn-proto's `Connection`: events go in
//! (a command to write, bytes from the droid, the link up or down, a deadline reached), and
//! writes, the next deadline, notifications, log entries and answers come out. It owns the
//! SEQ numbers, the pending requests with their retries and expiry, the slot queue, pacing,
//! keep-alive, chunking and the urgent stop.
//!
//! Nothing here reads a clock or awaits: time is a plain [`Instant`] passed in, so every
//! timing rule is a unit test on made-up instants (`core_tests.rs`) and a fuzz target
//! (`crate::fuzzing::session_core`). [`super::task`] is the small tokio driver that feeds it.

use super::queue::{Latest, Mark, Next, OutQueue, Queued, Reply, Slot};
use super::{
    Direction, LogEntry, LogItem, RequestError, SessionConfig, SessionEvent, SessionStats,
};
use crate::family::{Codec, Command, Family, Incoming, Key, Packet};
use crate::gatt::Endpoint;
use crate::protocol::notify::Notification;
use std::collections::{HashMap, HashSet, VecDeque};
use std::time::{Duration, Instant};

/// Setup commands are re-sent this often before giving up until the next reconnect.
const SETUP_RETRIES: u8 = 2;

/// One write to the link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Transmit {
    pub to: Endpoint,
    pub bytes: Vec<u8>,
    /// Part of an emergency stop: written at once, ahead of pacing, with the link's urgent
    /// write (which may skip its own queue).
    pub urgent: bool,
}

/// An answer for whoever waits on [`Reply`].
pub type Answer = (Reply, Result<Packet, RequestError>);

struct Pending {
    deadline: Instant,
    reply: Option<Reply>,
    cmd: Command,
    retries: u8,
    woken: bool,
    quiet: bool,
    /// Its ticket, kept until the answer ([`SessionCore::awaits`]).
    mark: Option<Mark>,
}

/// What is only true while a connection is up.
struct Connected {
    /// The rest of the packet being written, one chunk per pacing slot.
    chunks: VecDeque<(Endpoint, Vec<u8>)>,
    /// The emergency stop (and the rest of the packet it cut in), written back to back.
    urgent: VecDeque<(Endpoint, Vec<u8>)>,
    next_write: Instant,
    last_write: Instant,
    /// The link closes when quiet for this long (a relay's idle timeout).
    keepalive: Option<Duration>,
}

pub struct SessionCore {
    cfg: SessionConfig,
    family: &'static dyn Family,
    start: Instant,
    seq: u8,
    pending: HashMap<Key, Pending>,
    /// Quiet commands whose refusal was already logged.
    quiet_logged: HashSet<String>,
    /// One codec for the whole session: what the droid was told to stream outlives a dropped
    /// link (it keeps streaming with the old masks until the setup sets them again); only the
    /// byte stream starts afresh at each connect.
    codec: Box<dyn Codec>,
    queue: OutQueue,
    stats: SessionStats,
    /// What the droid said once at connect (Robi's handshake), for late subscribers.
    greeting: Vec<Notification>,
    /// The last drive command written: the stop after a reconnect, on shutdown and in an
    /// emergency keeps its heading (a stop at heading 0 would turn the droid).
    last_drive: Option<Command>,
    /// A connect setup for the next (re)connect ([`SessionCore::set_setup`]).
    new_setup: Option<Vec<Command>>,
    /// An emergency stop not yet written; it waits for a connection if there is none.
    urgent: Option<Command>,
    redo_setup: bool,
    stop_on_shutdown: bool,
    link: Option<Connected>,
    closed: bool,
    next_reply: u64,
    next_mark: u64,
    events: VecDeque<SessionEvent>,
    log: VecDeque<LogEntry>,
    answers: VecDeque<Answer>,
    /// Explain and keep log entries only while someone reads them: explaining costs.
    pub log_wanted: bool,
}

impl SessionCore {
    /// `start` is the session's time zero, the origin of the log's timestamps.
    pub fn new(cfg: SessionConfig, start: Instant) -> Self {
        let family = crate::family::for_protocol(cfg.family);
        let codec = match cfg.model {
            Some(model) => family.codec_for(model),
            None => family.codec(),
        };
        SessionCore {
            queue: OutQueue::new(cfg.queue_capacity),
            cfg,
            family,
            start,
            seq: 0,
            pending: HashMap::new(),
            quiet_logged: HashSet::new(),
            codec,
            stats: SessionStats::default(),
            greeting: Vec::new(),
            last_drive: None,
            new_setup: None,
            urgent: None,
            redo_setup: false,
            stop_on_shutdown: false,
            link: None,
            closed: false,
            next_reply: 0,
            next_mark: 0,
            events: VecDeque::new(),
            log: VecDeque::new(),
            answers: VecDeque::new(),
            log_wanted: false,
        }
    }

    // ----- inputs from the handle -----

    /// Queue a discrete request; `wait` asks for its answer through [`Self::poll_answer`].
    pub fn handle_request(
        &mut self,
        cmd: Command,
        wait: bool,
    ) -> Result<Option<Reply>, RequestError> {
        self.handle_request_marked(cmd, wait, None)
            .map(|(reply, _)| reply)
    }

    /// [`Self::handle_request`], with a ticket to learn when it leaves ([`Self::holds`]);
    /// with `latest`, it replaces the unwritten request with the same key (whose waiter is
    /// told `Superseded`).
    pub fn handle_request_marked(
        &mut self,
        cmd: Command,
        wait: bool,
        latest: Option<Latest>,
    ) -> Result<(Option<Reply>, Mark), RequestError> {
        if self.closed {
            return Err(RequestError::Closed);
        }
        let reply = wait.then(|| {
            self.next_reply += 1;
            Reply(self.next_reply)
        });
        let mark = self.new_mark();
        let q = Queued {
            reply,
            mark: Some(mark),
            latest,
            ..Queued::new(cmd)
        };
        match self.queue.push(q) {
            Ok(replaced) => {
                self.stats.coalesced = self.queue.coalesced;
                if let Some(r) = replaced.and_then(|q| q.reply) {
                    self.answers.push_back((r, Err(RequestError::Superseded)));
                }
                Ok((reply, mark))
            }
            Err(_) => {
                self.stats.rejected += 1;
                Err(RequestError::QueueFull)
            }
        }
    }

    /// Whether the request queue is full (a request now would be refused).
    pub fn is_full(&self) -> bool {
        self.queue.is_full()
    }

    fn new_mark(&mut self) -> Mark {
        self.next_mark += 1;
        Mark(self.next_mark)
    }

    /// Whether the command with ticket `mark` is still waiting to be written: neither taken
    /// for writing nor replaced by a newer one nor dropped with the link.
    pub fn holds(&self, mark: Mark) -> bool {
        self.queue.holds(mark)
    }

    /// Whether the command with ticket `mark` still waits: to be written, or, written, for
    /// its answer (a command nothing answers waits only to be written). A Sphero Edu `spin`
    /// makes its next step once its last one is answered, as spherov2's does ([`crate::edu`]).
    pub fn awaits(&self, mark: Mark) -> bool {
        self.queue.holds(mark) || self.pending.values().any(|p| p.mark == Some(mark))
    }

    /// The latest value of a continuous control: replaces any older unwritten one, and a
    /// drive the drive commands queued before it (their waiters are told `Superseded`).
    pub fn handle_write(&mut self, slot: Slot, cmd: Command) {
        self.handle_write_marked(slot, cmd, false);
    }

    /// [`Self::handle_write`], with a ticket to learn when it leaves ([`Self::holds`]).
    pub fn handle_write_marked(&mut self, slot: Slot, cmd: Command, mark: bool) -> Option<Mark> {
        let mark = mark.then(|| self.new_mark());
        let superseded = self.queue.set_slot_marked(slot, cmd, mark);
        self.stats.coalesced = self.queue.coalesced;
        for r in superseded.into_iter().filter_map(|q| q.reply) {
            self.answers.push_back((r, Err(RequestError::Superseded)));
        }
        mark
    }

    /// Stop now: `stop` is the next write, ahead of pacing and of everything queued (after
    /// the rest of a packet already half written, so its framing stays whole), and again one
    /// pacing slot later through the drive slot, in case the droid dropped the first. Without
    /// a connection it waits for the next one, ahead of that connection's setup.
    pub fn emergency_stop(&mut self, stop: Command) {
        self.handle_write(Slot::Drive, stop.clone());
        self.urgent = Some(stop);
    }

    /// The stop at the heading of the last drive command written (heading 0 if none).
    pub fn stop_command(&self) -> Command {
        self.family.stop_after(self.last_drive.as_ref())
    }

    pub fn last_drive(&self) -> Option<&Command> {
        self.last_drive.as_ref()
    }

    /// Write the connect setup again at the next write, ahead of everything queued.
    pub fn redo_setup(&mut self) {
        self.redo_setup = true;
    }

    /// Replace the connect setup for every later (re)connect; nothing is sent now.
    pub fn set_setup(&mut self, setup: Vec<Command>) {
        self.new_setup = Some(setup);
    }

    /// On shutdown, write a stop at the last heading before the final commands.
    pub fn stop_on_shutdown(&mut self) {
        self.stop_on_shutdown = true;
    }

    pub fn queued(&self) -> usize {
        self.queue.len()
    }

    pub fn stats(&self) -> SessionStats {
        self.stats
    }

    pub fn greeting(&self) -> &[Notification] {
        &self.greeting
    }

    // ----- inputs from the link -----

    /// The link is up: stop first, then set up (see [`Self::queue_setup`]); pacing starts now.
    pub fn handle_connected(&mut self, now: Instant, keepalive: Option<Duration>, reconnect: bool) {
        if reconnect {
            self.stats.reconnects += 1;
        }
        self.greeting.clear();
        self.codec.reset_stream();
        self.link = Some(Connected {
            chunks: VecDeque::new(),
            urgent: VecDeque::new(),
            next_write: now,
            last_write: now,
            keepalive,
        });
        self.queue_setup();
    }

    /// The link went down: what was half written is gone, and every request waiting fails.
    pub fn handle_link_lost(&mut self) {
        self.link = None;
        self.fail_all(RequestError::LinkLost);
    }

    /// The session is over: every waiting request fails and no new one is taken.
    pub fn close(&mut self) {
        self.link = None;
        self.closed = true;
        self.fail_all(RequestError::Closed);
    }

    /// The time between two paced writes: what a command queued behind another waits.
    pub fn pacing(&self) -> std::time::Duration {
        self.cfg.pacing
    }

    /// A write finished at `now`: the next paced write waits one pacing interval from here,
    /// and the keep-alive counts quiet time from here.
    pub fn handle_written(&mut self, now: Instant) {
        if let Some(link) = &mut self.link {
            link.next_write = now + self.cfg.pacing;
            link.last_write = now;
        }
    }

    /// Bytes from the droid.
    pub fn handle_bytes(&mut self, bytes: &[u8], now: Instant) {
        self.stats.bytes_in += bytes.len() as u64;
        let mut found = Vec::new();
        self.codec.feed(bytes, &mut found);
        for item in found {
            self.handle_incoming(item, now);
        }
    }

    /// A deadline from [`Self::poll_timeout`] came: expire requests, queue a keep-alive.
    pub fn handle_timeout(&mut self, now: Instant) {
        self.expire(now);
        let idle = self.queue.is_empty();
        if let Some(link) = &mut self.link
            && let Some(ka) = link.keepalive
            && link.chunks.is_empty()
            && idle
            && now >= link.last_write + ka
        {
            // A harmless write in time, for a link that closes when quiet.
            let cmd = self.family.keepalive(self.last_drive.as_ref());
            tracing::debug!(command = %cmd.name(), "keepalive");
            link.last_write = now;
            let _ = self.queue.push(Queued {
                quiet: true,
                ..Queued::new(cmd)
            });
        }
    }

    // ----- outputs -----

    /// The next write, if one is due at `now`: the emergency stop at once, otherwise one
    /// chunk per pacing interval. Call until `None`, reporting each finished write with
    /// [`Self::handle_written`].
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Transmit> {
        self.link.as_ref()?;
        if self.redo_setup {
            self.redo_setup = false;
            self.queue_setup();
        }
        if let Some(cmd) = self.urgent.take() {
            self.encode_urgent(cmd, now);
        }
        let link = self.link.as_mut()?;
        if let Some((to, bytes)) = link.urgent.pop_front() {
            return Some(Transmit {
                to,
                bytes,
                urgent: true,
            });
        }
        if now < link.next_write {
            return None;
        }
        if link.chunks.is_empty() {
            // Popping an empty queue would still pass the slots' turn to the FIFO.
            if self.queue.is_empty() {
                return None;
            }
            let chunks = self.take_next(now)?;
            self.link.as_mut()?.chunks.extend(chunks);
        }
        let link = self.link.as_mut()?;
        let (to, bytes) = link.chunks.pop_front()?;
        // Nothing more until the write is reported done, one pacing interval later.
        link.next_write = now + self.cfg.pacing;
        Some(Transmit {
            to,
            bytes,
            urgent: false,
        })
    }

    /// When to call [`Self::handle_timeout`] or [`Self::poll_transmit`] next, if nothing
    /// else happens first: the next paced write, the first request deadline, or the
    /// keep-alive.
    pub fn poll_timeout(&self) -> Option<Instant> {
        let has_work = self.has_work();
        let link = self.link.as_ref();
        let write = link.filter(|_| has_work).map(|l| l.next_write);
        let keepalive = link
            .filter(|_| !has_work)
            .and_then(|l| Some(l.last_write + l.keepalive?));
        let expiry = self.pending.values().map(|p| p.deadline).min();
        [write, keepalive, expiry].into_iter().flatten().min()
    }

    /// Something to write: queued commands, the rest of a packet, a stop, a setup to redo.
    pub fn has_work(&self) -> bool {
        self.urgent.is_some()
            || self.redo_setup
            || !self.queue.is_empty()
            || self
                .link
                .as_ref()
                .is_some_and(|l| !l.chunks.is_empty() || !l.urgent.is_empty())
    }

    pub fn poll_event(&mut self) -> Option<SessionEvent> {
        self.events.pop_front()
    }

    pub fn poll_log(&mut self) -> Option<LogEntry> {
        self.log.pop_front()
    }

    pub fn poll_answer(&mut self) -> Option<Answer> {
        self.answers.pop_front()
    }

    /// Shutdown: the rest of the packet in flight, a stop at the last heading when asked
    /// for, then `last`, all encoded now; the driver writes them paced, best effort.
    pub fn finish(&mut self, mut last: Vec<Command>, now: Instant) -> Vec<(Endpoint, Vec<u8>)> {
        let mut wire: Vec<(Endpoint, Vec<u8>)> = match self.link.take() {
            Some(l) => l.urgent.into_iter().chain(l.chunks).collect(),
            None => Vec::new(),
        };
        if self.stop_on_shutdown {
            last.insert(0, self.stop_command());
        }
        for cmd in last {
            tracing::info!(command = %cmd.name(), data = %crate::hex::spaced(&cmd.data()), "final command");
            let seq = self.next_seq(&cmd);
            // Nobody will wait for these responses.
            let (writes, packet) = self.codec.encode_writes(&cmd, seq, false);
            wire.extend(self.chunked(writes));
            self.stats.sent += 1;
            self.log_packet(now, Direction::Out, packet, Some(&cmd));
        }
        wire
    }

    // ----- the rules -----

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
        if let Some(new) = self.new_setup.take() {
            self.cfg.setup = new;
        }
        let mut rest: Vec<Command> = self.cfg.setup.clone();
        let mut gate = Vec::new();
        if let Some(wake) = self.family.wake()
            && rest.first() == Some(&wake)
        {
            gate.push(setup(rest.remove(0)));
        }
        if self.last_drive.is_some() {
            gate.push(setup(self.stop_command()));
        }
        let n = gate.len();
        let mut items = gate;
        let fail_safe = self.family.fail_safe();
        items.extend(rest.into_iter().map(|cmd| Queued {
            quiet: fail_safe.as_ref() == Some(&cmd),
            ..setup(cmd)
        }));
        self.queue.push_front(items, n);
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
        self.queue.push_front(items, gate);
        self.stats.retried += 1;
        None
    }

    /// Fail every pending and queued request (link lost or closed).
    fn fail_all(&mut self, why: RequestError) {
        let queued = self.queue.clear();
        let n = self.pending.len() as u64 + queued.len() as u64;
        let waiting = self.pending.drain().filter_map(|(_, p)| p.reply);
        let waiting: Vec<Reply> = waiting
            .chain(queued.into_iter().filter_map(|q| q.reply))
            .collect();
        for r in waiting {
            self.answers.push_back((r, Err(why.clone())));
        }
        if why == RequestError::LinkLost {
            self.stats.link_lost += n;
        }
    }

    /// The next SEQ: 0..=254, wrapping, skipping one whose response key is still pending.
    fn next_seq(&mut self, cmd: &Command) -> u8 {
        for _ in 0..255 {
            let s = self.seq;
            self.seq = if self.seq >= 254 { 0 } else { self.seq + 1 };
            if !self.pending.contains_key(&self.codec.key(cmd, s)) {
                return s;
            }
        }
        self.seq
    }

    /// Turn the next queued item into wire chunks, registering its pending entry.
    fn take_next(&mut self, now: Instant) -> Option<Vec<(Endpoint, Vec<u8>)>> {
        let (next, mark) = self.queue.pop_marked()?;
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
            ..
        } = q;
        let want_response = want_response && self.codec.answers();
        let seq = self.next_seq(&cmd);
        let (writes, packet) = self.codec.encode_writes(&cmd, seq, want_response);
        if self.family.is_drive(&cmd) {
            self.last_drive = Some(cmd.clone());
        }
        let wire_len: usize = writes.iter().map(|(_, w)| w.len()).sum();
        let chunks = self.chunked(writes);
        if want_response {
            let extra = self.cfg.pacing * (chunks.len().saturating_sub(1) as u32);
            self.pending.insert(
                self.codec.key(&cmd, seq),
                Pending {
                    deadline: now + self.cfg.request_timeout + extra,
                    reply,
                    cmd: cmd.clone(),
                    retries,
                    woken,
                    quiet,
                    mark,
                },
            );
        } else if let Some(r) = reply {
            // Nothing will answer: the written packet is all there is to return.
            self.answers.push_back((r, Ok(packet.clone())));
        }
        self.stats.sent += 1;
        self.stats.bytes_out += wire_len as u64;
        self.log_packet(now, Direction::Out, packet, Some(&cmd));
        Some(chunks)
    }

    /// The emergency stop: the rest of the packet in flight first (its framing must stay
    /// whole), then the stop, back to back with no pacing. The drive slot holds the same
    /// stop for the re-send one pacing slot later.
    fn encode_urgent(&mut self, cmd: Command, now: Instant) {
        let seq = self.next_seq(&cmd);
        // Nobody waits for this answer; the re-send through the slot is matched as usual.
        let (writes, packet) = self.codec.encode_writes(&cmd, seq, false);
        if self.family.is_drive(&cmd) {
            self.last_drive = Some(cmd.clone());
        }
        let stop = self.chunked(writes);
        let Some(link) = self.link.as_mut() else {
            return;
        };
        let wire: Vec<_> = link.chunks.drain(..).chain(stop).collect();
        self.stats.sent += 1;
        self.stats.bytes_out += wire.iter().map(|(_, w)| w.len() as u64).sum::<u64>();
        link.urgent.extend(wire);
        tracing::info!(command = %cmd.name(), "emergency stop written ahead of pacing");
        self.log_packet(now, Direction::Out, packet, Some(&cmd));
    }

    /// Cut writes into link-sized chunks, each tagged with its endpoint.
    fn chunked(&self, writes: Vec<(Endpoint, Vec<u8>)>) -> Vec<(Endpoint, Vec<u8>)> {
        let size = self.cfg.chunk_size.max(1);
        writes
            .into_iter()
            .flat_map(|(to, w)| w.chunks(size).map(|c| (to, c.to_vec())).collect::<Vec<_>>())
            .collect()
    }

    fn log(&mut self, now: Instant, dir: Direction, item: LogItem) {
        if !self.log_wanted {
            return;
        }
        self.log.push_back(LogEntry {
            at: now.saturating_duration_since(self.start),
            dir,
            item,
        });
    }

    fn log_packet(
        &mut self,
        now: Instant,
        dir: Direction,
        packet: Packet,
        request: Option<&Command>,
    ) {
        if !self.log_wanted {
            return;
        }
        let explained = self.codec.explain(&packet, request);
        self.log(now, dir, LogItem::Packet { packet, explained });
    }

    fn handle_incoming(&mut self, item: Incoming, now: Instant) {
        match item {
            Incoming::Error(e) => {
                tracing::debug!(error = %e, "decode error");
                self.stats.decode_errors += 1;
                self.stats.errors += 1;
                self.log(now, Direction::In, LogItem::DecodeError(e));
            }
            Incoming::Response { key, error, packet } => {
                self.stats.received += 1;
                let Some(pending) = self.pending.remove(&key) else {
                    self.stats.unmatched += 1;
                    return self.log_packet(now, Direction::In, packet, None);
                };
                let request = pending.cmd.clone();
                // A quiet command's refusal (a fail-safe this firmware does not know) is fine:
                // said once in the log, not counted as an error.
                let quiet = pending.quiet && error.is_some_and(|e| !e.is_target_unavailable());
                self.stats.answered += 1;
                if error.is_some() && !quiet {
                    self.stats.droid_errors += 1;
                    self.stats.errors += 1;
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
                    let answer = match error {
                        None => Ok(packet.clone()),
                        Some(e) => Err(RequestError::Droid(e)),
                    };
                    self.answers.push_back((reply, answer));
                }
                self.log_packet(now, Direction::In, packet, Some(&request));
            }
            Incoming::Async {
                notifications,
                packet,
            } => {
                self.stats.received += 1;
                for n in notifications {
                    match n {
                        Ok(n) => {
                            if n.is_greeting() {
                                self.greeting.push(n.clone());
                            }
                            if n == Notification::WillSleep && self.cfg.keep_awake {
                                tracing::info!("the droid wants to sleep: keeping it awake");
                                let _ = self.queue.push(Queued::new(self.family.ping()));
                            }
                            self.events.push_back(SessionEvent::Notification(n));
                        }
                        Err(e) => {
                            self.stats.errors += 1;
                            self.events.push_back(SessionEvent::BadNotification {
                                name: e.name,
                                reason: e.reason,
                            });
                        }
                    }
                }
                self.log_packet(now, Direction::In, packet, None);
            }
            Incoming::Stray(packet) => {
                self.stats.received += 1;
                self.log_packet(now, Direction::In, packet, None);
            }
        }
    }

    /// Requests whose deadline has come: re-sent while they have retries, else answered
    /// `Timeout`.
    fn expire(&mut self, now: Instant) {
        let expired: Vec<_> = self
            .pending
            .iter()
            .filter(|(_, p)| p.deadline <= now)
            .map(|(k, _)| *k)
            .collect();
        for k in expired {
            let Some(p) = self.pending.remove(&k) else {
                continue;
            };
            self.stats.timeouts += 1;
            tracing::debug!(did = k.0, cid = k.1, seq = k.2, "request timed out");
            if let Some(reply) = self.retry(p, false).and_then(|p| p.reply) {
                self.answers.push_back((reply, Err(RequestError::Timeout)));
            }
        }
    }
}

#[cfg(test)]
#[path = "core_tests.rs"]
mod tests;
