//! One connection attempt at a time per Bluetooth adapter, and a cap of droids per adapter.
//!
//! BlueZ runs one LE connection attempt per adapter at a time: a second `Connect` while one
//! is under way fails with `org.bluez.Error.InProgress`, and an attempt that collides with
//! another is often aborted (`le-connection-abort-by-local`). An adapter holds about six LE
//! links, of which about four stay stable. So every droid's link on one adapter goes through
//! one [`Gate`]: its `open` (first connect and every reconnect) waits for the adapter's
//! previous attempt to finish, and the session's backoff retries what still fails. A droid
//! that drops reconnects alone: the others' connections are not touched, only their
//! *attempts* take turns.
//!
//! [`Adapters::admit`] counts droids per adapter and refuses the one over the cap with a
//! message saying what to do.

use crate::link::{Connection, Link, LinkError};
use crate::sync::lock;
use futures_util::future::BoxFuture;
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::Mutex as AsyncMutex;

/// The default number of droids per adapter (`fleet.max_per_adapter`).
pub const DEFAULT_MAX_PER_ADAPTER: usize = 4;

/// An adapter's turn-taking: held by one connection attempt at a time.
#[derive(Debug, Default)]
pub struct Gate {
    turn: AsyncMutex<()>,
    /// Attempts made through this gate, and the most that ever overlapped (tests, logs).
    stats: Mutex<GateStats>,
}

#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct GateStats {
    pub attempts: u64,
    pub in_progress: u32,
    pub max_in_progress: u32,
}

impl Gate {
    pub fn stats(&self) -> GateStats {
        *lock(&self.stats)
    }

    fn count(&self, delta: i32) {
        let mut s = lock(&self.stats);
        if delta > 0 {
            s.attempts += 1;
            s.in_progress += 1;
            s.max_in_progress = s.max_in_progress.max(s.in_progress);
        } else {
            s.in_progress = s.in_progress.saturating_sub(1);
        }
    }
}

/// An adapter's gate and the droids admitted to it.
type Admitted = (Arc<Gate>, Vec<String>);

/// Droids per adapter and each adapter's gate.
#[derive(Debug)]
pub struct Adapters {
    cap: usize,
    admitted: Mutex<BTreeMap<String, Admitted>>,
}

/// A droid refused because its adapter is full.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OverCap {
    pub adapter: String,
    pub cap: usize,
    pub droid: String,
    pub holding: Vec<String>,
}

impl std::fmt::Display for OverCap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} not connected: the adapter {} already holds {} droids ({}), its limit — an \
             adapter keeps about four LE links stable; drive the others through `droidctl \
             serve` on another machine near them (--remote HOST), or raise \
             fleet.max_per_adapter in the config",
            self.droid,
            self.adapter,
            self.cap,
            self.holding.join(", ")
        )
    }
}

impl Adapters {
    pub fn new(cap: usize) -> Adapters {
        Adapters {
            cap: cap.max(1),
            admitted: Mutex::new(BTreeMap::new()),
        }
    }

    /// Count `droid` on `adapter` and hand out the adapter's gate, or refuse it over the cap.
    pub fn admit(&self, adapter: &str, droid: &str) -> Result<Arc<Gate>, OverCap> {
        let mut all = lock(&self.admitted);
        let (gate, holding) = all.entry(adapter.to_string()).or_default();
        if holding.len() >= self.cap {
            return Err(OverCap {
                adapter: adapter.to_string(),
                cap: self.cap,
                droid: droid.to_string(),
                holding: holding.clone(),
            });
        }
        holding.push(droid.to_string());
        Ok(gate.clone())
    }
}

impl Adapters {
    /// Which of `adapters` (by index) takes the next droid: the one holding the fewest, the
    /// first on a tie (an adapter over the cap is then full everywhere, and `admit` says so).
    pub fn least_loaded(&self, adapters: &[String]) -> usize {
        let all = lock(&self.admitted);
        adapters
            .iter()
            .enumerate()
            .min_by_key(|(i, n)| (all.get(*n).map_or(0, |(_, h)| h.len()), *i))
            .map_or(0, |(i, _)| i)
    }
}

/// A link whose connection attempts take turns on their adapter's [`Gate`].
pub struct GatedLink {
    inner: Box<dyn Link>,
    gate: Arc<Gate>,
}

impl GatedLink {
    pub fn new(inner: Box<dyn Link>, gate: Arc<Gate>) -> GatedLink {
        GatedLink { inner, gate }
    }
}

/// Longest a connection attempt may hold its adapter's turn, whatever the link does: the
/// others must get theirs (the Bluetooth link bounds its own attempt well within this).
const TURN_LIMIT: Duration = Duration::from_secs(30);

impl Link for GatedLink {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            let _turn = self.gate.turn.lock().await;
            self.gate.count(1);
            let r = tokio::time::timeout(TURN_LIMIT, self.inner.open()).await;
            self.gate.count(-1);
            match r {
                Ok(r) => r,
                Err(_) => {
                    self.inner.abort_open().await;
                    Err(LinkError::transient(format!(
                        "the connection attempt took over {} s",
                        TURN_LIMIT.as_secs()
                    )))
                }
            }
        })
    }

    fn abort_open(&mut self) -> BoxFuture<'_, ()> {
        self.inner.abort_open()
    }

    fn retry_hint(&mut self) -> BoxFuture<'_, ()> {
        self.inner.retry_hint()
    }

    fn keepalive(&self) -> Option<Duration> {
        self.inner.keepalive()
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::time::{Instant, sleep};

    /// A link whose connect takes a second and fails the first `fail` times with BlueZ's
    /// "busy" answer.
    struct Slow {
        fail: u32,
    }

    impl Link for Slow {
        fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
            Box::pin(async move {
                sleep(Duration::from_secs(1)).await;
                if self.fail > 0 {
                    self.fail -= 1;
                    return Err(LinkError::transient("org.bluez.Error.InProgress"));
                }
                // Connected (the test needs no connection object, only the turn it took).
                Err(LinkError::transient("opened"))
            })
        }
        fn describe(&self) -> String {
            "slow".into()
        }
    }

    #[tokio::test(start_paused = true)]
    async fn attempts_on_one_adapter_take_turns_and_other_adapters_do_not_wait() {
        let adapters = Adapters::new(4);
        let a = adapters.admit("hci0", "A").unwrap();
        let b = adapters.admit("hci0", "B").unwrap();
        let c = adapters.admit("hci1", "C").unwrap();
        let mut links = [
            GatedLink::new(Box::new(Slow { fail: 1 }), a.clone()),
            GatedLink::new(Box::new(Slow { fail: 0 }), b),
            GatedLink::new(Box::new(Slow { fail: 0 }), c.clone()),
        ];
        let t0 = Instant::now();
        let [l1, l2, l3] = &mut links;
        let (r1, r2, r3) = tokio::join!(l1.open(), l2.open(), l3.open());
        assert!(r1.is_err() && r2.is_err() && r3.is_err());
        // hci0's two attempts one after the other; hci1's alongside.
        assert_eq!(t0.elapsed(), Duration::from_secs(2));
        assert_eq!(a.stats().max_in_progress, 1);
        assert_eq!(a.stats().attempts, 2);
        assert_eq!(c.stats().attempts, 1);
        // The retry after InProgress takes its turn again.
        let r = links[0].open().await;
        assert!(r.is_err_and(|e| e.message.starts_with("opened")));
        assert_eq!(a.stats().attempts, 3);
    }

    #[test]
    fn over_the_cap_is_refused_with_what_to_do() {
        let adapters = Adapters::new(2);
        adapters.admit("hci0", "A").unwrap();
        adapters.admit("hci0", "B").unwrap();
        let e = adapters.admit("hci0", "C").unwrap_err();
        let m = e.to_string();
        assert!(m.starts_with("C not connected: the adapter hci0 already holds 2 droids (A, B)"));
        assert!(
            m.contains("fleet.max_per_adapter") && m.contains("--remote"),
            "{m}"
        );
        // Another adapter has room, and takes the next droid.
        let names = ["hci0".to_string(), "hci1".to_string()];
        assert_eq!(adapters.least_loaded(&names), 1);
        assert!(adapters.admit("hci1", "C").is_ok());
        assert!(adapters.admit("hci1", "D").is_ok());
        // Both full: the first, where admit refuses with the message.
        assert_eq!(adapters.least_loaded(&names), 0);
        assert_eq!(Adapters::new(0).cap, 1);
    }
}
