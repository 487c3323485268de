//! Sessions that outlive their connection (issue 40 point 8): a client that connects with
//! `clean_session = 0` keeps its subscriptions when it goes, and the QoS 1 and 2 messages
//! they match are queued for it until it comes back (MQTT 3.1.1, 3.1.2.4); its CONNACK then
//! says `session_present`, and what was queued is delivered after it, in order. A CONNECT
//! with `clean_session = 1` ends any session kept under its id.
//!
//! Bounded like everything else the broker holds ([`MAX_SESSIONS`], [`SESSION_MESSAGES`],
//! [`SESSION_BYTES`], [`ALL_SESSIONS_BYTES`], [`SESSION_EXPIRY`]): a message past a session's
//! budget is dropped for it (counted, logged once per session); with [`MAX_SESSIONS`] kept,
//! the one away longest gives its place. What the connection still held for the client when
//! it went (queued, not written) is kept in the session too; a QoS 1 or 2 message written
//! but not acknowledged is not sent again (the broker keeps no in-flight window).
//!
//! Sans-IO: the times are given.

use super::state::{lower, matches, size};
use rumqttc::mqttbytes::QoS;
use rumqttc::mqttbytes::v4::Publish;
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::time::Duration;
use tokio::time::Instant;

/// Sessions kept for clients away.
pub const MAX_SESSIONS: usize = 256;
/// Messages queued for one client away.
pub const SESSION_MESSAGES: usize = 1000;
/// Bytes queued for one client away (topics and payloads).
pub const SESSION_BYTES: usize = 256 << 10;
/// Bytes queued for all clients away together.
pub const ALL_SESSIONS_BYTES: usize = 8 << 20;
/// A session whose client stays away this long is ended.
pub const SESSION_EXPIRY: Duration = Duration::from_secs(3600);

/// A session kept while its client is away.
#[derive(Debug)]
pub struct Kept {
    pub subs: BTreeMap<String, QoS>,
    pub queue: VecDeque<Publish>,
    bytes: usize,
    since: Instant,
    /// Messages dropped for it (past its budget) while away.
    pub dropped: u64,
}

/// Every session kept.
#[derive(Debug, Default)]
pub struct Sessions {
    kept: HashMap<String, Kept>,
    bytes: usize,
    /// Messages dropped for clients away (over a budget), and sessions ended for room or
    /// age.
    pub dropped: u64,
    pub ended: u64,
}

impl Sessions {
    /// Client `id` went at `now` with `subs`; `left` what its connection had not written
    /// (only QoS 1 and 2 kept).
    pub fn keep(
        &mut self,
        id: &str,
        subs: BTreeMap<String, QoS>,
        left: Vec<Publish>,
        now: Instant,
    ) {
        self.expire(now);
        if !self.kept.contains_key(id) && self.kept.len() >= MAX_SESSIONS {
            let oldest = self
                .kept
                .iter()
                .min_by_key(|(_, k)| k.since)
                .map(|(id, _)| id.clone());
            if let Some(o) = oldest {
                tracing::warn!(
                    client_id = %o,
                    "mqtt broker: {MAX_SESSIONS} sessions kept: the one away longest ended"
                );
                self.end(&o);
            }
        }
        self.end(id);
        self.kept.insert(
            id.to_string(),
            Kept {
                subs,
                queue: VecDeque::new(),
                bytes: 0,
                since: now,
                dropped: 0,
            },
        );
        for p in left {
            if p.qos != QoS::AtMostOnce {
                self.push(id, p);
            }
        }
    }

    /// The session of client `id`, taken out (it is connecting again); `None` when none is
    /// kept or it expired.
    pub fn take(&mut self, id: &str, now: Instant) -> Option<Kept> {
        self.expire(now);
        let k = self.kept.remove(id)?;
        self.bytes -= k.bytes;
        Some(k)
    }

    /// End client `id`'s session (a clean CONNECT, or room for another).
    pub fn end(&mut self, id: &str) {
        if let Some(k) = self.kept.remove(id) {
            self.bytes -= k.bytes;
            self.ended += 1;
        }
    }

    /// Queue `p` (as delivered: retain 0) for every client away subscribed to its topic at
    /// QoS 1 or 2.
    pub fn offer(&mut self, p: &Publish) {
        if p.qos == QoS::AtMostOnce || self.kept.is_empty() {
            return;
        }
        let ids: Vec<(String, QoS)> = self
            .kept
            .iter()
            .filter_map(|(id, k)| {
                let q = k
                    .subs
                    .iter()
                    .filter(|(f, _)| matches(&p.topic, f))
                    .map(|(_, q)| *q)
                    .max_by_key(|q| *q as u8)?;
                (q != QoS::AtMostOnce).then(|| (id.clone(), q))
            })
            .collect();
        for (id, q) in ids {
            let mut copy = p.clone();
            copy.qos = lower(copy.qos, q);
            self.push(&id, copy);
        }
    }

    fn push(&mut self, id: &str, p: Publish) {
        let bytes = size(&p);
        let Some(k) = self.kept.get_mut(id) else {
            return;
        };
        let fits = k.queue.len() < SESSION_MESSAGES
            && k.bytes + bytes <= SESSION_BYTES
            && self.bytes + bytes <= ALL_SESSIONS_BYTES;
        if !fits {
            if k.dropped == 0 {
                tracing::warn!(
                    client_id = %id,
                    "mqtt broker: a message for a client away dropped: its session holds at most \
                     {SESSION_MESSAGES} messages, {SESSION_BYTES} bytes"
                );
            }
            k.dropped += 1;
            self.dropped += 1;
            return;
        }
        k.bytes += bytes;
        self.bytes += bytes;
        k.queue.push_back(p);
    }

    /// End the sessions away past [`SESSION_EXPIRY`].
    pub fn expire(&mut self, now: Instant) {
        let old: Vec<String> = self
            .kept
            .iter()
            .filter(|(_, k)| now.duration_since(k.since) >= SESSION_EXPIRY)
            .map(|(id, _)| id.clone())
            .collect();
        for id in old {
            self.end(&id);
        }
    }

    /// Sessions kept.
    pub fn count(&self) -> usize {
        self.kept.len()
    }

    /// Bytes queued for clients away.
    pub fn bytes(&self) -> usize {
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn subs(f: &str, q: QoS) -> BTreeMap<String, QoS> {
        BTreeMap::from([(f.to_string(), q)])
    }

    #[test]
    fn a_session_keeps_qos1_messages_in_order_and_ends_when_asked() {
        let t0 = Instant::now();
        let mut s = Sessions::default();
        s.keep("a", subs("x/#", QoS::AtLeastOnce), Vec::new(), t0);
        s.offer(&Publish::new("x/1", QoS::AtLeastOnce, "one"));
        s.offer(&Publish::new("x/2", QoS::AtMostOnce, "zero: not kept"));
        s.offer(&Publish::new("y/1", QoS::AtLeastOnce, "no filter"));
        s.offer(&Publish::new(
            "x/3",
            QoS::ExactlyOnce,
            "two, lowered to one",
        ));
        let k = s.take("a", t0).unwrap();
        let got: Vec<(&str, QoS)> = k.queue.iter().map(|p| (p.topic.as_str(), p.qos)).collect();
        assert_eq!(got, [("x/1", QoS::AtLeastOnce), ("x/3", QoS::AtLeastOnce)]);
        assert_eq!(s.bytes(), 0);
        assert!(s.take("a", t0).is_none(), "taken once");
        s.keep("b", subs("#", QoS::AtLeastOnce), Vec::new(), t0);
        s.end("b");
        assert_eq!((s.count(), s.bytes()), (0, 0));
    }

    #[test]
    fn sessions_are_bounded_in_messages_bytes_count_and_age() {
        let t0 = Instant::now();
        let mut s = Sessions::default();
        s.keep("a", subs("#", QoS::AtLeastOnce), Vec::new(), t0);
        for _ in 0..SESSION_MESSAGES + 10 {
            s.offer(&Publish::new("t", QoS::AtLeastOnce, "x"));
        }
        assert_eq!(s.dropped, 10);
        s.keep("b", subs("#", QoS::AtLeastOnce), Vec::new(), t0);
        s.offer(&Publish::new(
            "t",
            QoS::AtLeastOnce,
            vec![0u8; SESSION_BYTES],
        ));
        assert!(s.bytes() <= ALL_SESSIONS_BYTES);
        assert_eq!(s.dropped, 12, "too large for either session");
        for n in 0..MAX_SESSIONS + 5 {
            s.keep(
                &format!("c{n}"),
                BTreeMap::new(),
                Vec::new(),
                t0 + Duration::from_secs(1),
            );
        }
        assert_eq!(s.count(), MAX_SESSIONS);
        assert!(s.take("a", t0).is_none(), "the oldest gave its place");
        let later = t0 + SESSION_EXPIRY + Duration::from_secs(2);
        s.expire(later);
        assert_eq!((s.count(), s.bytes()), (0, 0));
    }
}
