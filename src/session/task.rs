//! The session's driver: one small tokio task that owns the link and feeds the I/O-free
//! [`SessionCore`](super::core::SessionCore): it opens and reopens the link, writes what
//! the core says, sleeps until the core's next deadline, and forwards its notifications,
//! log entries and answers. Every rule (what to write when, retries, expiry) is the core's.

use super::core::{SessionCore, Transmit};
use super::{LinkState, LogEntry, SessionConfig, SessionEvent, Shared, lock};
use crate::family::Command;
use crate::gatt::Endpoint;
use crate::link::{Connection, Link, LinkEvent};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::{broadcast, watch};
use tokio::time::{Instant, sleep, sleep_until, timeout};

/// How long the final commands on shutdown may take, and then closing the link. Together
/// they stay inside the callers' outer limit (3 s), so the stop is never cut short by it.
const SHUTDOWN_BUDGET: Duration = Duration::from_secs(1);
const CLOSE_BUDGET: Duration = Duration::from_millis(1500);

pub(super) struct Task {
    link: Box<dyn Link>,
    cfg: SessionConfig,
    shared: Arc<Shared>,
    state: watch::Sender<LinkState>,
    events: broadcast::Sender<SessionEvent>,
    log: broadcast::Sender<LogEntry>,
}

/// Why the connected loop ended.
enum Ended {
    LinkLost(String),
    Shutdown,
}

/// The core's clock is plain `std` time; the driver's is tokio's (paused in tests).
fn now() -> std::time::Instant {
    Instant::now().into_std()
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
            cfg,
            shared,
            state,
            events,
            log,
        }
    }

    fn shutdown_requested(&self) -> bool {
        lock(&self.shared.shutdown).is_some()
    }

    /// One step of the core, then out with what it produced: notifications and log entries
    /// to their subscribers (answers go out inside [`Shared::with`]).
    fn step<T>(&self, f: impl FnOnce(&mut SessionCore) -> T) -> T {
        let log_wanted = self.log.receiver_count() > 0;
        let (out, events, log) = self.shared.with(|core| {
            core.log_wanted = log_wanted;
            // A stop left by a caller that found the core's lock taken.
            if let Some(stop) = lock(&self.shared.urgent).take() {
                let stop = stop.unwrap_or_else(|| core.stop_command());
                core.emergency_stop(stop);
            }
            let out = f(core);
            let events: Vec<_> = std::iter::from_fn(|| core.poll_event()).collect();
            let log: Vec<_> = std::iter::from_fn(|| core.poll_log()).collect();
            (out, events, log)
        });
        for e in events {
            let _ = self.events.send(e);
        }
        for l in log {
            let _ = self.log.send(l);
        }
        out
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
                    let reconnect = attempt > 0;
                    attempt = 0;
                    tracing::info!(link = %self.link.describe(), "connected");
                    let keepalive = self.link.keepalive();
                    self.step(|core| core.handle_connected(now(), keepalive, reconnect));
                    self.state.send_replace(LinkState::Connected);
                    match self.connected(conn).await {
                        Ended::Shutdown => break,
                        Ended::LinkLost(reason) => {
                            tracing::warn!(%reason, "link lost");
                            self.step(|core| core.handle_link_lost());
                            self.shared.written.send_modify(|n| *n += 1);
                            attempt += 1;
                            if !self.wait_retry(attempt, reason).await {
                                break;
                            }
                        }
                    }
                }
                Err(e) if e.fatal => {
                    tracing::error!(error = %e, "link failed for good");
                    self.step(|core| core.close());
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
        self.step(|core| core.close());
        self.state.send_replace(LinkState::Closed { reason: None });
        self.shared.written.send_modify(|n| *n += 1);
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

    async fn connected(&mut self, mut conn: Connection) -> Ended {
        let conn = &mut conn;
        loop {
            let last = lock(&self.shared.shutdown).take();
            if let Some(last) = last {
                self.finish(conn, last).await;
                return Ended::Shutdown;
            }
            // Everything due now: the emergency stop's chunks back to back, or one paced chunk.
            while let Some(t) = self.step(|core| core.poll_transmit(now())) {
                if let Err(e) = write(conn, &t).await {
                    conn.writer.close().await;
                    return Ended::LinkLost(format!("write failed: {e}"));
                }
                self.step(|core| core.handle_written(now()));
                self.shared.written.send_modify(|n| *n += 1);
                if !t.urgent {
                    break;
                }
            }
            let deadline = self.step(|core| core.poll_timeout()).map(Instant::from_std);
            tokio::select! {
                biased;
                _ = self.shared.shutdown_wake.notified() => {
                    // Handled at the top of the loop; keep the permit semantics simple.
                    if lock(&self.shared.shutdown).is_none() {
                        continue;
                    }
                }
                // New work (an emergency stop first of all): the top of the loop writes it.
                _ = self.shared.wake.notified() => {}
                ev = conn.events.recv() => match ev {
                    Some(LinkEvent::Data(bytes)) => {
                        self.step(|core| core.handle_bytes(&bytes, now()));
                        // An answer: whoever waits on one ([`SessionHandle::answered`]) looks.
                        self.shared.written.send_modify(|n| *n += 1);
                    }
                    Some(LinkEvent::Disconnected(reason)) => {
                        conn.writer.close().await;
                        return Ended::LinkLost(reason);
                    }
                    None => return Ended::LinkLost("the link closed".into()),
                },
                _ = sleep_until(deadline.unwrap_or_else(Instant::now)), if deadline.is_some() => {
                    self.step(|core| core.handle_timeout(now()));
                }
            }
        }
    }

    /// Shutdown: finish the packet in flight, write the final commands (a stop), close.
    async fn finish(&mut self, conn: &mut Connection, last: Vec<Command>) {
        let wire: Vec<(Endpoint, Vec<u8>)> = self.step(|core| core.finish(last, now()));
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

/// One write as the core asked: the emergency stop with the link's urgent write.
async fn write(conn: &mut Connection, t: &Transmit) -> Result<(), crate::link::LinkError> {
    if t.urgent {
        conn.writer.write_urgent(t.to, &t.bytes).await
    } else {
        conn.writer.write_to(t.to, &t.bytes).await
    }
}
