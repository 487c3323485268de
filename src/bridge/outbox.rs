//! Where the bridge's objects wait for the transport (issue 27 point 5). Two queues:
//!
//! - what a client counts on (replies, errors, `stopped` and `link` objects, `hello`) is
//!   never dropped: the queue has no fixed end, and the stdio transport reads its next
//!   command only while fewer than [`PENDING_LIMIT`] of them wait ([`Outbox::room`]), so
//!   it stays bounded by the client's own pace: a line in makes at most a few objects out;
//! - telemetry (samples, collisions, battery readings) waits in a bounded queue of
//!   [`TELEMETRY_CAPACITY`]; past that it is dropped and counted ([`Outbox::dropped`]): a
//!   slow reader gets fewer samples, never fewer answers.
//!
//! Each object carries the index of the droid it is about (the MQTT transport routes by it:
//! two droids may share a name, never a topic).

use super::schema::Out;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use tokio::sync::{Notify, mpsc};

/// Telemetry objects waiting for the transport at most; past that they are dropped.
pub const TELEMETRY_CAPACITY: usize = 4096;

/// Objects that are never dropped: while this many wait, the stdio transport reads no
/// further command.
pub const PENDING_LIMIT: usize = 1024;

/// An object and the droid (its index in the fleet) it is about.
#[derive(Debug, Clone, PartialEq)]
pub struct Routed {
    pub droid: Option<usize>,
    pub out: Out,
}

struct Shared {
    pending: AtomicUsize,
    room: Notify,
    dropped: AtomicU64,
}

/// The sending side, held by the bridge.
pub struct Outbox {
    kept: mpsc::UnboundedSender<Routed>,
    telemetry: mpsc::Sender<Routed>,
    shared: Arc<Shared>,
}

/// The receiving side, held by the transport.
pub struct Outputs {
    kept: mpsc::UnboundedReceiver<Routed>,
    telemetry: mpsc::Receiver<Routed>,
    shared: Arc<Shared>,
}

/// A new pair.
pub fn channel() -> (Outbox, Outputs) {
    let (kt, kr) = mpsc::unbounded_channel();
    let (tt, tr) = mpsc::channel(TELEMETRY_CAPACITY);
    let shared = Arc::new(Shared {
        pending: AtomicUsize::new(0),
        room: Notify::new(),
        dropped: AtomicU64::new(0),
    });
    (
        Outbox {
            kept: kt,
            telemetry: tt,
            shared: shared.clone(),
        },
        Outputs {
            kept: kr,
            telemetry: tr,
            shared,
        },
    )
}

/// Whether an object may be dropped when the transport does not keep up.
pub fn droppable(o: &Out) -> bool {
    matches!(
        o,
        Out::Telemetry { .. } | Out::Collision { .. } | Out::Battery { .. }
    )
}

impl Outbox {
    /// Queue `out` (about droid `droid`): telemetry is dropped (counted) when its queue is
    /// full; anything else is kept.
    pub fn send(&self, droid: Option<usize>, out: Out) {
        let r = Routed { droid, out };
        if droppable(&r.out) {
            if self.telemetry.try_send(r).is_err() {
                let n = self.shared.dropped.fetch_add(1, Ordering::Relaxed) + 1;
                if n.is_power_of_two() {
                    tracing::warn!(
                        dropped = n,
                        "bridge: the transport does not keep up: telemetry dropped"
                    );
                }
            }
            return;
        }
        self.shared.pending.fetch_add(1, Ordering::Relaxed);
        if self.kept.send(r).is_err() {
            // The transport is gone: nobody waits for it.
            self.shared.pending.fetch_sub(1, Ordering::Relaxed);
        }
    }

    /// Telemetry objects dropped so far.
    pub fn dropped(&self) -> u64 {
        self.shared.dropped.load(Ordering::Relaxed)
    }

    /// Kept objects waiting for the transport.
    pub fn pending(&self) -> usize {
        self.shared.pending.load(Ordering::Relaxed)
    }

    /// Wait until fewer than [`PENDING_LIMIT`] kept objects wait for the transport.
    pub async fn room(&self) {
        while self.pending() >= PENDING_LIMIT {
            self.shared.room.notified().await;
        }
    }
}

impl Outputs {
    fn took(&self) {
        self.shared.pending.fetch_sub(1, Ordering::Relaxed);
        // A permit is kept when nobody waits, so a wake is never lost.
        self.shared.room.notify_one();
    }

    /// The next object and its droid, kept objects first; `None` once both queues are
    /// closed and empty.
    pub async fn recv_routed(&mut self) -> Option<Routed> {
        let r = tokio::select! {
            biased;
            Some(r) = self.kept.recv() => {
                self.took();
                r
            }
            Some(r) = self.telemetry.recv() => r,
            else => return None,
        };
        Some(r)
    }

    /// The next object.
    pub async fn recv(&mut self) -> Option<Out> {
        self.recv_routed().await.map(|r| r.out)
    }

    /// The next object waiting, without waiting.
    pub fn try_recv_routed(&mut self) -> Result<Routed, mpsc::error::TryRecvError> {
        match self.kept.try_recv() {
            Ok(r) => {
                self.took();
                Ok(r)
            }
            Err(kept) => match self.telemetry.try_recv() {
                Ok(r) => Ok(r),
                Err(mpsc::error::TryRecvError::Disconnected)
                    if kept == mpsc::error::TryRecvError::Disconnected =>
                {
                    Err(mpsc::error::TryRecvError::Disconnected)
                }
                Err(_) => Err(mpsc::error::TryRecvError::Empty),
            },
        }
    }

    /// The next object waiting, without waiting.
    pub fn try_recv(&mut self) -> Result<Out, mpsc::error::TryRecvError> {
        self.try_recv_routed().map(|r| r.out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stopped(n: usize) -> Out {
        Out::Stopped {
            droid: format!("D{n}"),
            reason: "timeout",
            message: String::new(),
        }
    }

    fn sample() -> Out {
        Out::Battery {
            droid: "D".into(),
            t_ms: 0,
            volts: 4.0,
        }
    }

    #[tokio::test(start_paused = true)]
    async fn telemetry_is_dropped_and_counted_answers_are_kept_and_hold_the_reader() {
        let (tx, mut rx) = channel();
        for _ in 0..TELEMETRY_CAPACITY + 10 {
            tx.send(Some(0), sample());
        }
        assert_eq!(tx.dropped(), 10);
        for n in 0..PENDING_LIMIT * 3 {
            tx.send(Some(1), stopped(n));
        }
        assert_eq!(tx.pending(), PENDING_LIMIT * 3);
        // No room until the transport takes enough of them.
        let waiting = tokio::time::timeout(std::time::Duration::from_secs(1), tx.room()).await;
        assert!(waiting.is_err(), "room while 3 × the limit wait");
        // Kept objects come first, in order, each with its droid.
        for n in 0..PENDING_LIMIT * 2 + 1 {
            let r = rx.recv_routed().await.unwrap();
            assert_eq!(
                r,
                Routed {
                    droid: Some(1),
                    out: stopped(n)
                }
            );
        }
        tokio::time::timeout(std::time::Duration::from_secs(1), tx.room())
            .await
            .expect("room once fewer than the limit wait");
        let mut kept = PENDING_LIMIT * 2 + 1;
        let mut telemetry = 0;
        while let Ok(o) = rx.try_recv() {
            if droppable(&o) {
                telemetry += 1;
            } else {
                kept += 1;
            }
        }
        assert_eq!((kept, telemetry), (PENDING_LIMIT * 3, TELEMETRY_CAPACITY));
        drop(tx);
        assert_eq!(rx.try_recv(), Err(mpsc::error::TryRecvError::Disconnected));
        assert_eq!(rx.recv().await, None);
    }
}
