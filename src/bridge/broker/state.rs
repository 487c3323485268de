//! What the broker holds between packets: the clients and their filters, the retained
//! messages, and the counters (sans-IO: the connections hand it packets' contents).
//!
//! Every call does work bounded by the limits, never by what came before from the wire: a
//! client's filters are a map (a filter subscribed again replaces itself, at most
//! [`MAX_CLIENT_FILTERS`]); a SUBSCRIBE finds the retained messages it matches by their
//! topics' common prefix in an ordered map and sends each topic once; a PUBLISH visits each
//! client's filters once. The callers hold the lock only for these calls.

use super::limits::{
    MAX_CLIENT_FILTERS, MAX_RETAINED, MAX_RETAINED_MESSAGE, MAX_TOPIC, QUEUE, QueueBytes,
    RETAINED_BYTES,
};
use bytes::Bytes;
use rumqttc::mqttbytes::v4::{Packet, Publish, SubscribeReasonCode};
use rumqttc::mqttbytes::{QoS, valid_filter};
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::sync::atomic::AtomicUsize;
use tokio::sync::mpsc;

/// What a client's connection is told to send.
pub enum Out {
    Packet(Packet),
    /// Another connection took this client id: close without the will.
    TakenOver,
}

/// One message waiting for a client, with the bytes it holds of the client's budget.
pub struct Queued {
    pub out: Out,
    pub bytes: usize,
}

/// Where a client's messages go.
pub struct Client {
    /// Which connection holds the id (a later one with the same id takes it over).
    pub conn: u64,
    pub tx: mpsc::Sender<Queued>,
    pub budget: QueueBytes,
    /// Filters and their granted QoS.
    subs: BTreeMap<String, QoS>,
    /// Connected with `clean_session = 0`: its session is kept when it goes
    /// ([`super::session`]).
    persistent: bool,
}

/// Counters, for the log and the tests.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Connections refused a slot (too many, too many from one address).
    pub refused: u64,
    /// Connections closed for breaking the protocol or a limit (the log says which).
    pub closed: u64,
    /// Closed for sending nothing past their idle deadline.
    pub idle: u64,
    /// Closed for not reading (a write stalled).
    pub stalled: u64,
    /// CONNECTs refused for taking a client id kept for droidctl's own bridge.
    pub own_id_refused: u64,
    /// Messages not queued for a client that does not keep up.
    pub dropped: u64,
    /// Retained messages not kept (over a budget).
    pub not_retained: u64,
    /// Filters refused in a SUBACK (invalid, too long, one too many).
    pub filters_refused: u64,
}

/// What the broker holds.
#[derive(Default)]
pub struct State {
    next: u64,
    /// By client id.
    clients: HashMap<String, Client>,
    retained: BTreeMap<String, Arc<Publish>>,
    retained_bytes: usize,
    /// Bytes queued for every client together.
    queued: Arc<AtomicUsize>,
    /// The sessions of clients away ([`super::session`]).
    pub sessions: super::session::Sessions,
    pub counters: Counters,
}

/// A retained message a SUBSCRIBE matched, shared, and the QoS granted for its topic.
pub type Matched = (Arc<Publish>, QoS);

/// Bytes a message holds: topic and payload, plus the packet's own.
pub fn size(p: &Publish) -> usize {
    p.topic.len() + p.payload.len() + 16
}

/// The lower of two QoS levels (what a subscriber gets of a publisher's message).
pub fn lower(a: QoS, b: QoS) -> QoS {
    if (a as u8) <= (b as u8) { a } else { b }
}

impl State {
    /// A new connection's number.
    pub fn next_conn(&mut self) -> u64 {
        self.next += 1;
        self.next
    }

    /// Client `id` is now connection `conn`, sending to `tx`; a connection that held the id
    /// before is told it was taken over. The client's queue budget.
    pub fn connect(&mut self, id: &str, conn: u64, tx: mpsc::Sender<Queued>) -> QueueBytes {
        self.connect_session(id, conn, tx, true, tokio::time::Instant::now())
            .0
    }

    /// [`State::connect`] with `clean_session`: whether a session was present (a client
    /// away with `clean_session = 0`, or one connected now, taken over); its subscriptions
    /// are the client's again and what was queued for it is queued for the connection.
    /// A clean session ends any kept under the id.
    pub fn connect_session(
        &mut self,
        id: &str,
        conn: u64,
        tx: mpsc::Sender<Queued>,
        clean: bool,
        now: tokio::time::Instant,
    ) -> (QueueBytes, bool) {
        let budget = QueueBytes::new(self.queued.clone());
        let mut client = Client {
            conn,
            tx,
            budget: budget.clone(),
            subs: BTreeMap::new(),
            persistent: !clean,
        };
        let old = self.clients.remove(id);
        let mut kept = None;
        if clean {
            self.sessions.end(id);
        } else {
            match &old {
                Some(o) if o.persistent => client.subs = o.subs.clone(),
                _ => kept = self.sessions.take(id, now),
            }
        }
        let present = !clean && (old.as_ref().is_some_and(|o| o.persistent) || kept.is_some());
        if let Some(k) = kept {
            client.subs = k.subs;
            for p in k.queue {
                if !queue(&client, p) {
                    self.counters.dropped += 1;
                }
            }
        }
        self.clients.insert(id.to_string(), client);
        if let Some(old) = old {
            let _ = old.tx.try_send(Queued {
                out: Out::TakenOver,
                bytes: 0,
            });
        }
        (budget, present)
    }

    /// Whether connection `conn` holds client id `id`.
    pub fn holds(&self, id: &str, conn: u64) -> bool {
        self.clients.get(id).is_some_and(|c| c.conn == conn)
    }

    /// Connection `conn` ends: its client id is free (unless taken over meanwhile).
    pub fn disconnect(&mut self, id: &str, conn: u64) {
        self.disconnect_session(id, conn, Vec::new(), tokio::time::Instant::now());
    }

    /// [`State::disconnect`]; a persistent client's session is kept, with `left`, what its
    /// connection had queued and not written.
    pub fn disconnect_session(
        &mut self,
        id: &str,
        conn: u64,
        left: Vec<Publish>,
        now: tokio::time::Instant,
    ) {
        if self.holds(id, conn)
            && let Some(c) = self.clients.remove(id)
            && c.persistent
        {
            self.sessions.keep(id, c.subs, left, now);
        }
    }

    /// Subscribe connection `conn` (client `id`) to `filters`: the return codes, and the
    /// retained messages they match (each topic once, with the highest QoS granted for it),
    /// shared, not copied: the connection writes them after its SUBACK. `None`: the
    /// connection no longer holds the id.
    pub fn subscribe(
        &mut self,
        id: &str,
        conn: u64,
        filters: Vec<(String, QoS)>,
    ) -> Option<(Vec<SubscribeReasonCode>, Vec<Matched>)> {
        let c = self.clients.get_mut(id).filter(|c| c.conn == conn)?;
        let mut codes = Vec::with_capacity(filters.len());
        let mut granted: Vec<(String, QoS)> = Vec::new();
        let mut refused = 0;
        for (path, qos) in filters {
            let fits = c.subs.contains_key(&path) || c.subs.len() < MAX_CLIENT_FILTERS;
            if path.len() > MAX_TOPIC || !valid_filter(&path) || !fits {
                codes.push(SubscribeReasonCode::Failure);
                refused += 1;
                continue;
            }
            codes.push(SubscribeReasonCode::Success(qos));
            c.subs.insert(path.clone(), qos);
            granted.push((path, qos));
        }
        self.counters.filters_refused += refused;
        // Each retained topic once: the highest QoS any granted filter gives it.
        let mut found: BTreeMap<&str, QoS> = BTreeMap::new();
        for (path, qos) in &granted {
            for topic in matching(&self.retained, path) {
                let q = found.entry(topic).or_insert(*qos);
                if (*qos as u8) > (*q as u8) {
                    *q = *qos;
                }
            }
        }
        let retained = found
            .into_iter()
            .filter_map(|(topic, q)| Some((self.retained.get(topic)?.clone(), q)))
            .collect();
        Some((codes, retained))
    }

    /// Drop connection `conn`'s (client `id`'s) `filters`.
    pub fn unsubscribe(&mut self, id: &str, conn: u64, filters: &[String]) {
        if let Some(c) = self.clients.get_mut(id).filter(|c| c.conn == conn) {
            for f in filters {
                c.subs.remove(f);
            }
        }
    }

    /// Filters client `id` holds.
    pub fn filters(&self, id: &str) -> usize {
        self.clients.get(id).map_or(0, |c| c.subs.len())
    }

    /// Keep `p` if retained (within the budgets), and queue it for every client subscribed
    /// to its topic. The payload is copied once, so nothing here keeps a reader's buffer
    /// alive. Messages that did not fit a client's queue: counted, and returned.
    pub fn publish(&mut self, mut p: Publish) -> u64 {
        p.payload = Bytes::copy_from_slice(&p.payload);
        if p.retain {
            self.retain(&p);
        }
        // Delivered to established subscribers: retain is 0 (MQTT 3.1.1, 3.3.1.3).
        p.retain = false;
        p.dup = false;
        let mut dropped = 0;
        for c in self.clients.values() {
            let granted = c
                .subs
                .iter()
                .filter(|(f, _)| matches(&p.topic, f))
                .map(|(_, q)| *q)
                .max_by_key(|q| *q as u8);
            if let Some(q) = granted {
                let mut copy = p.clone();
                copy.qos = lower(copy.qos, q);
                if !queue(c, copy) {
                    dropped += 1;
                }
            }
        }
        self.sessions.offer(&p);
        self.counters.dropped += dropped;
        dropped
    }

    /// Keep (or with an empty payload, clear) a retained message, within [`MAX_RETAINED`],
    /// [`RETAINED_BYTES`] and [`MAX_RETAINED_MESSAGE`].
    fn retain(&mut self, p: &Publish) {
        let old = self.retained.get(&p.topic).map_or(0, |p| size(p));
        if p.payload.is_empty() {
            if self.retained.remove(&p.topic).is_some() {
                self.retained_bytes -= old;
            }
            return;
        }
        let new = size(p);
        let count_ok = old > 0 || self.retained.len() < MAX_RETAINED;
        let bytes_ok = self.retained_bytes - old + new <= RETAINED_BYTES;
        if new > MAX_RETAINED_MESSAGE || !count_ok || !bytes_ok {
            self.counters.not_retained += 1;
            tracing::warn!(
                topic = %p.topic,
                bytes = new,
                "mqtt broker: a retained message not kept (at most {MAX_RETAINED} topics, \
                 {RETAINED_BYTES} bytes in all, {MAX_RETAINED_MESSAGE} bytes each); delivered"
            );
            return;
        }
        let mut kept = p.clone();
        kept.dup = false;
        kept.retain = true;
        self.retained_bytes = self.retained_bytes - old + new;
        self.retained.insert(p.topic.clone(), Arc::new(kept));
    }

    /// Bytes of the retained messages kept.
    pub fn retained_bytes(&self) -> usize {
        self.retained_bytes
    }

    /// Retained topics kept.
    pub fn retained_count(&self) -> usize {
        self.retained.len()
    }

    /// Bytes queued for all clients.
    pub fn queued_bytes(&self) -> usize {
        self.queued.load(std::sync::atomic::Ordering::SeqCst)
    }

    /// Clients connected.
    pub fn clients(&self) -> usize {
        self.clients.len()
    }
}

/// Whether `topic` matches `filter` (MQTT 3.1.1, 4.7). Not rumqttc's `matches`: it slices
/// the topic's first byte, and panics on a topic that starts with a character of more than
/// one byte (found by the `broker` fuzz target). A filter starting with a wildcard does not
/// match a `$` topic (4.7.2-1); `$SYS/#` does.
pub fn matches(topic: &str, filter: &str) -> bool {
    if topic.starts_with('$') && filter.starts_with(['+', '#']) {
        return false;
    }
    let mut topics = topic.split('/');
    for f in filter.split('/') {
        if f == "#" {
            return true;
        }
        match topics.next() {
            Some(_) if f == "+" => {}
            Some(t) if t == f => {}
            _ => return false,
        }
    }
    topics.next().is_none()
}

/// Queue `p` for client `c` within its budgets.
fn queue(c: &Client, p: Publish) -> bool {
    let bytes = size(&p);
    if !c.budget.reserve(bytes) {
        return false;
    }
    let q = Queued {
        out: Out::Packet(Packet::Publish(p)),
        bytes,
    };
    if c.tx.try_send(q).is_err() {
        c.budget.release(bytes);
        return false;
    }
    true
}

/// The capacity of a client's queue, in packets.
pub fn queue_capacity() -> usize {
    QUEUE
}

/// The retained topics `filter` matches: those under its literal start (the levels before
/// the first wildcard), found by range in the ordered map, then matched whole.
fn matching<'a>(
    retained: &'a BTreeMap<String, Arc<Publish>>,
    filter: &'a str,
) -> impl Iterator<Item = &'a str> + 'a {
    let wild = filter.find(['+', '#']).unwrap_or(filter.len());
    let prefix = &filter[..wild];
    retained
        .range::<str, _>((
            std::ops::Bound::Included(prefix),
            std::ops::Bound::Unbounded,
        ))
        .take_while(move |(t, _)| t.starts_with(prefix))
        .filter(move |(t, _)| matches(t, filter))
        .map(|(t, _)| t.as_str())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn client(st: &mut State, id: &str) -> mpsc::Receiver<Queued> {
        let (tx, rx) = mpsc::channel(queue_capacity());
        let conn = st.next_conn();
        st.connect(id, conn, tx);
        rx
    }

    fn retained(topic: &str, size: usize) -> Publish {
        let mut p = Publish::new(topic, QoS::AtMostOnce, vec![b'x'; size]);
        p.retain = true;
        p
    }

    #[test]
    fn retained_messages_are_kept_within_their_byte_budget() {
        let mut st = State::default();
        // 4 MiB messages never reach here (the packet limit); the largest kept is 64 KiB.
        st.publish(retained("big", MAX_RETAINED_MESSAGE));
        assert_eq!(st.retained_count(), 0);
        let each = MAX_RETAINED_MESSAGE - 100;
        for n in 0..300 {
            st.publish(retained(&format!("t/{n}"), each));
        }
        assert!(
            st.retained_bytes() <= RETAINED_BYTES,
            "{}",
            st.retained_bytes()
        );
        let kept = st.retained_count();
        assert!((60..70).contains(&kept), "{kept}");
        assert_eq!(st.counters.not_retained, 1 + 300 - kept as u64);
        // Replacing a kept topic fits in its own room; clearing frees it.
        st.publish(retained("t/0", each));
        assert_eq!(st.counters.not_retained, 1 + 300 - kept as u64);
        let before = st.retained_bytes();
        st.publish(retained("t/0", 0));
        assert_eq!(st.retained_bytes(), before - (each + 16 + 3));
    }

    #[test]
    fn a_filter_subscribed_again_replaces_itself_and_retained_topics_go_once() {
        let mut st = State::default();
        for n in 0..10 {
            st.publish(retained(&format!("a/{n}"), 10));
        }
        st.publish(retained("b/1", 10));
        let mut rx = client(&mut st, "c");
        let conn = 1;
        // `#` a thousand times: one filter, each retained topic sent once.
        let filters = vec![("#".to_string(), QoS::AtMostOnce); 1000];
        let (codes, sent) = st.subscribe("c", conn, filters).unwrap();
        assert_eq!(codes.len(), 1000);
        assert_eq!(st.filters("c"), 1);
        assert_eq!(sent.len(), 11);
        let (_, sent) = st
            .subscribe("c", conn, vec![("a/+".into(), QoS::AtLeastOnce)])
            .unwrap();
        assert_eq!(sent.len(), 10, "a/+ matches a/0 … a/9 only");
        // Past the client's filters: refused.
        let many: Vec<(String, QoS)> = (0..100)
            .map(|n| (format!("x/{n}"), QoS::AtMostOnce))
            .collect();
        let (codes, _) = st.subscribe("c", conn, many).unwrap();
        let failed = codes
            .iter()
            .filter(|c| **c == SubscribeReasonCode::Failure)
            .count();
        assert_eq!(st.filters("c"), MAX_CLIENT_FILTERS);
        assert_eq!(failed, 100 - (MAX_CLIENT_FILTERS - 2));
        assert!(rx.try_recv().is_err(), "nothing queued by subscribing here");
    }

    #[test]
    fn topics_match_filters_whatever_their_first_character() {
        for (topic, filter, m) in [
            ("a/b", "a/+", true),
            ("a/b/c", "a/#", true),
            ("a", "a/#", true),
            ("a/b", "a/b/c", false),
            ("a/b/c", "a/+", false),
            ("$SYS/x", "#", false),
            ("$SYS/x", "$SYS/#", true),
            ("\u{fffd}liv", "+/+", false),
            ("\u{fffd}liv", "#", true),
            ("é/x", "é/+", true),
        ] {
            assert_eq!(matches(topic, filter), m, "{topic} {filter}");
        }
    }

    #[test]
    fn a_client_that_does_not_read_holds_at_most_its_budget() {
        let mut st = State::default();
        let _rx = client(&mut st, "slow");
        st.subscribe("slow", 1, vec![("#".into(), QoS::AtMostOnce)])
            .unwrap();
        for _ in 0..100 {
            st.publish(Publish::new("t", QoS::AtMostOnce, vec![0u8; 200 << 10]));
        }
        assert!(st.queued_bytes() <= super::super::limits::QUEUE_BYTES);
        assert!(st.counters.dropped >= 95);
    }
}
