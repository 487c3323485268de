//! What the broker allows, in counts and in bytes (issue 37 points 5 and 6), and who may
//! take a connection slot.
//!
//! Every figure is a bound on what one client, or all of them together, can make the broker
//! hold: the bridge's own traffic is far below each (a command is at most 4,096 bytes, a
//! droid has a handful of retained topics, each connection one filter).

use std::collections::HashMap;
use std::net::IpAddr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The largest packet accepted after CONNECT (bytes of its remaining length): 64 times the
/// bridge's largest command. A larger one closes the connection before it is read.
pub const MAX_PACKET: usize = 256 << 10;
/// The largest CONNECT: it carries the will, which the broker keeps for the connection's
/// life, so it is held to a retained message's size.
pub const MAX_CONNECT: usize = MAX_RETAINED_MESSAGE + 1024;
/// Longest topic name or filter (bytes). A PUBLISH with a longer topic closes the connection;
/// a longer filter is refused in the SUBACK.
pub const MAX_TOPIC: usize = 1024;
/// Longest client id (bytes); MQTT 3.1.1 asks brokers to take at least 23.
pub const MAX_CLIENT_ID: usize = 256;
/// Filters in one SUBSCRIBE or UNSUBSCRIBE: more close the connection (nobody needs them; the
/// bridge subscribes one per connection).
pub const MAX_FILTERS: usize = 64;
/// Filters one client holds at once (distinct: a filter subscribed again replaces itself);
/// past it a new filter is refused in the SUBACK.
pub const MAX_CLIENT_FILTERS: usize = 64;
/// Retained topics kept.
pub const MAX_RETAINED: usize = 4096;
/// Bytes of all retained messages kept (topics and payloads).
pub const RETAINED_BYTES: usize = 4 << 20;
/// The largest retained message kept (topic and payload); a larger one is delivered, not
/// kept.
pub const MAX_RETAINED_MESSAGE: usize = 64 << 10;
/// Packets queued for one client.
pub const QUEUE: usize = 1024;
/// Bytes queued for one client (a client that does not read loses what overflows, counted).
pub const QUEUE_BYTES: usize = 1 << 20;
/// Bytes queued for all clients together.
pub const ALL_QUEUES_BYTES: usize = 16 << 20;
/// Connections at once.
pub const MAX_CONNECTIONS: usize = 256;
/// Of [`MAX_CONNECTIONS`], slots only a loopback peer may take: others filling the rest
/// never lock out the operator's own clients (a `stop` published on this machine).
pub const LOOPBACK_SLOTS: usize = 32;
/// Connections from one address beyond loopback (an IPv6 peer: from one /64).
pub const MAX_PER_ADDRESS: usize = 16;
/// How long a new connection has to send CONNECT.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);
/// The longest a client may send nothing, whatever its keep-alive (0, "none", included):
/// 1.5 times the keep-alive, at most this (1.5 times mosquitto's default of 60 s).
pub const MAX_IDLE: Duration = Duration::from_secs(90);
/// The longest one write to a client may stall (it does not read): then it is closed.
pub const WRITE_TIMEOUT: Duration = Duration::from_secs(10);

/// How long client with keep-alive `keep_alive_s` may stay silent before it is closed.
pub fn idle_deadline(keep_alive_s: u16) -> Duration {
    if keep_alive_s == 0 {
        return MAX_IDLE;
    }
    (Duration::from_secs(u64::from(keep_alive_s)) * 3 / 2).min(MAX_IDLE)
}

/// Why a connection was not given a slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// Every slot is taken.
    Full,
    /// Every slot but the loopback ones is taken, and the peer is not on loopback.
    OnlyLoopbackLeft,
    /// The peer's address has [`MAX_PER_ADDRESS`] connections already.
    PerAddress,
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::Full => write!(f, "{MAX_CONNECTIONS} connections already"),
            Refusal::OnlyLoopbackLeft => write!(
                f,
                "only the {LOOPBACK_SLOTS} slots kept for this machine's clients are left"
            ),
            Refusal::PerAddress => write!(f, "{MAX_PER_ADDRESS} connections from that address"),
        }
    }
}

/// Loopback as a connection slot sees it: an IPv4-mapped loopback (`::ffff:127.0.0.1`, a
/// dual-stack listener's view of 127.0.0.1) is loopback too.
pub fn is_loopback(ip: IpAddr) -> bool {
    ip.to_canonical().is_loopback()
}

/// The key a peer is counted under: its address; an IPv6 peer's /64 (one host has a whole
/// /64 to pick addresses from).
fn key(ip: IpAddr) -> IpAddr {
    match ip.to_canonical() {
        IpAddr::V6(v6) => {
            let bits = u128::from(v6) & !((1u128 << 64) - 1);
            IpAddr::V6(bits.into())
        }
        v4 => v4,
    }
}

/// A connection silent this long may lose its slot to a newcomer when every slot is taken:
/// idle connections cannot lock others out (issue 37 point 6), while a client that talks
/// (a keep-alive ping counts) keeps its slot.
pub const EVICT_SILENT: Duration = Duration::from_secs(10);

/// One connection holding a slot.
#[derive(Debug)]
struct Held {
    ip: IpAddr,
    /// When it last sent something.
    last: tokio::time::Instant,
    /// droidctl's own bridge: never evicted.
    own: bool,
    kick: Arc<tokio::sync::Notify>,
}

/// The connections held, in all and per address; a newcomer finding every slot taken
/// evicts the longest-silent connection (silent at least [`EVICT_SILENT`], not the
/// bridge's own; a peer beyond loopback only one beyond loopback).
#[derive(Debug, Default)]
pub struct Admission {
    total: usize,
    by_key: HashMap<IpAddr, usize>,
    held: HashMap<u64, Held>,
    next: u64,
    evicted: u64,
}

impl Admission {
    /// A slot for a connection from `ip`, or why not: its key and the signal that evicts it.
    fn admit_at(
        &mut self,
        ip: IpAddr,
        now: tokio::time::Instant,
    ) -> Result<(u64, Arc<tokio::sync::Notify>), Refusal> {
        let remote = !is_loopback(ip);
        if remote {
            if self.by_key.get(&key(ip)).copied().unwrap_or(0) >= MAX_PER_ADDRESS
                && !self.evict(now, Some(key(ip)))
            {
                return Err(Refusal::PerAddress);
            }
            if self.total >= MAX_CONNECTIONS - LOOPBACK_SLOTS && !self.evict_remote(now) {
                return Err(if self.total >= MAX_CONNECTIONS {
                    Refusal::Full
                } else {
                    Refusal::OnlyLoopbackLeft
                });
            }
        } else if self.total >= MAX_CONNECTIONS && !self.evict(now, None) {
            return Err(Refusal::Full);
        }
        if remote {
            *self.by_key.entry(key(ip)).or_insert(0) += 1;
        }
        self.total += 1;
        self.next += 1;
        let kick = Arc::new(tokio::sync::Notify::new());
        self.held.insert(
            self.next,
            Held {
                ip,
                last: now,
                own: false,
                kick: kick.clone(),
            },
        );
        Ok((self.next, kick))
    }

    /// Evict the longest-silent connection that may go (from the peers of key `only` when
    /// given): true if one went.
    fn evict(&mut self, now: tokio::time::Instant, only: Option<IpAddr>) -> bool {
        self.evict_where(now, |h| {
            only.is_none_or(|k| !is_loopback(h.ip) && key(h.ip) == k)
        })
    }

    /// Evict the longest-silent connection from beyond loopback: true if one went.
    fn evict_remote(&mut self, now: tokio::time::Instant) -> bool {
        self.evict_where(now, |h| !is_loopback(h.ip))
    }

    fn evict_where(&mut self, now: tokio::time::Instant, may: impl Fn(&Held) -> bool) -> bool {
        let victim = self
            .held
            .iter()
            .filter(|(_, h)| !h.own && now.duration_since(h.last) >= EVICT_SILENT && may(h))
            .min_by_key(|(_, h)| h.last)
            .map(|(k, _)| *k);
        let Some(k) = victim else {
            return false;
        };
        self.release_key(k);
        self.evicted += 1;
        true
    }

    /// The slot `k` is free again (once: an evicted connection's own release finds it gone).
    fn release_key(&mut self, k: u64) {
        let Some(h) = self.held.remove(&k) else {
            return;
        };
        h.kick.notify_one();
        self.total = self.total.saturating_sub(1);
        if !is_loopback(h.ip)
            && let Some(n) = self.by_key.get_mut(&key(h.ip))
        {
            *n -= 1;
            if *n == 0 {
                self.by_key.remove(&key(h.ip));
            }
        }
    }

    /// Connections held.
    pub fn total(&self) -> usize {
        self.total
    }

    /// Connections evicted so far.
    pub fn evicted(&self) -> u64 {
        self.evicted
    }
}

/// A connection's slot: given back when dropped.
pub struct Slot {
    admission: Arc<Mutex<Admission>>,
    key: u64,
    kick: Arc<tokio::sync::Notify>,
}

impl Slot {
    /// Take a slot for `ip` from `admission`.
    pub fn take(admission: &Arc<Mutex<Admission>>, ip: IpAddr) -> Result<Slot, Refusal> {
        let now = tokio::time::Instant::now();
        let (key, kick) = crate::sync::lock(admission).admit_at(ip, now)?;
        Ok(Slot {
            admission: admission.clone(),
            key,
            kick,
        })
    }

    /// The connection sent something now.
    pub fn heard(&self) {
        if let Some(h) = crate::sync::lock(&self.admission).held.get_mut(&self.key) {
            h.last = tokio::time::Instant::now();
        }
    }

    /// The connection is droidctl's own bridge's: never evicted.
    pub fn own(&self) {
        if let Some(h) = crate::sync::lock(&self.admission).held.get_mut(&self.key) {
            h.own = true;
        }
    }

    /// Completes when a newcomer took this slot: the connection must close.
    pub async fn evicted(&self) {
        self.kick.notified().await
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        crate::sync::lock(&self.admission).release_key(self.key);
    }
}

/// Bytes queued for one client, within its own and everyone's budget.
#[derive(Debug, Clone)]
pub struct QueueBytes {
    mine: Arc<AtomicUsize>,
    all: Arc<AtomicUsize>,
}

impl QueueBytes {
    pub fn new(all: Arc<AtomicUsize>) -> QueueBytes {
        QueueBytes {
            mine: Arc::new(AtomicUsize::new(0)),
            all,
        }
    }

    /// Reserve `n` bytes: false (nothing reserved) when either budget would be exceeded.
    pub fn reserve(&self, n: usize) -> bool {
        let reserved = |a: &AtomicUsize, limit: usize| {
            a.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |v| {
                (v.saturating_add(n) <= limit).then_some(v + n)
            })
            .is_ok()
        };
        if !reserved(&self.mine, QUEUE_BYTES) {
            return false;
        }
        if !reserved(&self.all, ALL_QUEUES_BYTES) {
            self.mine.fetch_sub(n, Ordering::SeqCst);
            return false;
        }
        true
    }

    /// `n` bytes reserved before have left the queue.
    pub fn release(&self, n: usize) {
        let sub = |a: &AtomicUsize| {
            let _ = a.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |v| {
                Some(v.saturating_sub(n))
            });
        };
        sub(&self.mine);
        sub(&self.all);
    }

    /// Bytes queued for this client now.
    pub fn queued(&self) -> usize {
        self.mine.load(Ordering::SeqCst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ip(s: &str) -> IpAddr {
        s.parse().unwrap()
    }

    #[test]
    fn other_machines_never_take_the_loopback_slots_nor_more_than_their_share() {
        let t0 = tokio::time::Instant::now();
        let mut a = Admission::default();
        let admit = |a: &mut Admission, s: &str| a.admit_at(ip(s), t0).map(|(k, _)| k);
        // One address: its share, then refused.
        let mut first = None;
        for _ in 0..MAX_PER_ADDRESS {
            first = first.or(Some(admit(&mut a, "192.0.2.1").unwrap()));
        }
        assert_eq!(admit(&mut a, "192.0.2.1"), Err(Refusal::PerAddress));
        // An IPv6 host picking addresses from its /64 is one address.
        for n in 0..MAX_PER_ADDRESS {
            admit(&mut a, &format!("2001:db8::{n:x}")).unwrap();
        }
        assert_eq!(admit(&mut a, "2001:db8::ffff"), Err(Refusal::PerAddress));
        // Many addresses: everything but the loopback slots.
        let mut n = 0u32;
        while admit(&mut a, &format!("198.51.{}.{}", n >> 8, n & 0xFF)).is_ok() {
            n += 1;
        }
        assert_eq!(a.total(), MAX_CONNECTIONS - LOOPBACK_SLOTS);
        assert_eq!(admit(&mut a, "203.0.113.9"), Err(Refusal::OnlyLoopbackLeft));
        // This machine's clients still get in, as ::ffff:127.0.0.1 too.
        admit(&mut a, "127.0.0.1").unwrap();
        admit(&mut a, "::ffff:127.0.0.1").unwrap();
        admit(&mut a, "::1").unwrap();
        // A slot given back is free again (for this machine: the rest is full).
        a.release_key(first.unwrap());
        admit(&mut a, "192.0.2.1").unwrap_err();
        assert_eq!(a.total(), MAX_CONNECTIONS - LOOPBACK_SLOTS + 2);
        assert_eq!(a.evicted(), 0, "nobody silent long enough to lose a slot");
    }

    #[test]
    fn a_newcomer_finding_every_slot_taken_evicts_the_longest_silent() {
        let t0 = tokio::time::Instant::now();
        let mut a = Admission::default();
        let mut kicks = Vec::new();
        for n in 0..MAX_CONNECTIONS {
            let (k, kick) = a.admit_at(ip("127.0.0.1"), t0).unwrap();
            kicks.push((k, kick));
            if n == 0 {
                a.held.get_mut(&k).unwrap().own = true;
            }
        }
        // Nobody silent long enough: refused.
        assert_eq!(
            a.admit_at(ip("127.0.0.1"), t0).map(|_| ()),
            Err(Refusal::Full)
        );
        // One spoke since; the bridge's own never goes.
        let later = t0 + EVICT_SILENT;
        for (k, _) in &kicks[1..] {
            a.held.get_mut(k).unwrap().last = later;
        }
        a.held.get_mut(&kicks[5].0).unwrap().last = t0 + Duration::from_secs(1);
        let now = t0 + EVICT_SILENT + Duration::from_secs(2);
        a.admit_at(ip("127.0.0.1"), now).unwrap();
        assert_eq!(a.evicted(), 1);
        assert!(
            !a.held.contains_key(&kicks[5].0),
            "the longest silent but the bridge's"
        );
        assert!(a.held.contains_key(&kicks[0].0));
        assert_eq!(a.total(), MAX_CONNECTIONS);
        // Other machines evict only among themselves: none of them here.
        assert!(a.admit_at(ip("192.0.2.1"), now + EVICT_SILENT).is_err());
    }

    #[test]
    fn queued_bytes_stay_within_the_clients_and_everyones_budget() {
        let all = Arc::new(AtomicUsize::new(0));
        let q = QueueBytes::new(all.clone());
        assert!(q.reserve(QUEUE_BYTES));
        assert!(!q.reserve(1), "the client's own budget");
        q.release(QUEUE_BYTES);
        let others: Vec<QueueBytes> = (0..ALL_QUEUES_BYTES / QUEUE_BYTES)
            .map(|_| QueueBytes::new(all.clone()))
            .collect();
        for o in &others {
            assert!(o.reserve(QUEUE_BYTES));
        }
        assert!(!q.reserve(1), "everyone's budget");
        assert_eq!(q.queued(), 0, "nothing reserved by a refusal");
    }

    #[test]
    fn every_client_has_an_idle_deadline() {
        assert_eq!(idle_deadline(0), MAX_IDLE);
        assert_eq!(idle_deadline(10), Duration::from_secs(15));
        assert_eq!(idle_deadline(u16::MAX), MAX_IDLE);
    }
}
