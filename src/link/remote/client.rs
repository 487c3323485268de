//! One TCP connection to a relay: requests out (each bounded in time, the write included),
//! replies matched to their waiters by SEQ (or, for SCAN and FIND, in order), ON_DATA and the
//! end of the connection handed to the link.

use super::RelayAddr;
use crate::link::LinkError;
use crate::protocol::relay::{Limits, Reply, ReplyDecoder, Request};
use crate::sync::lock;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::sync::{mpsc, oneshot};
use tokio::time::timeout;

/// ON_DATA and the end of the connection, for the link.
pub(super) enum Incoming {
    Data {
        characteristic: String,
        data: Vec<u8>,
    },
    Closed(String),
}

/// Waiters for replies.
#[derive(Default)]
struct Waiters {
    seq: HashMap<u8, oneshot::Sender<Result<(), String>>>,
    /// SCAN and FIND, in the order sent.
    discovery: std::collections::VecDeque<oneshot::Sender<Result<Reply, String>>>,
    /// Set when the connection is gone: why.
    closed: Option<String>,
    next_seq: u8,
}

/// The writing half of a connection to a relay.
type RelayWriter = Box<dyn tokio::io::AsyncWrite + Send + Unpin>;

/// One TCP connection to a relay: requests out, replies matched to their waiters.
pub(super) struct RelayClient {
    writer: tokio::sync::Mutex<Option<RelayWriter>>,
    decoder: Arc<Mutex<ReplyDecoder>>,
    waiters: Arc<Mutex<Waiters>>,
    reader: tokio::task::JoinHandle<()>,
    relay: RelayAddr,
}

/// Bytes read at once.
pub(super) const READ_CHUNK: usize = 4096;
/// The longest a session over a relay stays without writing (see [`Link::keepalive`]).
pub const KEEPALIVE: Duration = Duration::from_secs(20);
/// ON_DATA waiting for the link's reader.
pub(super) const EVENTS: usize = 1024;

impl RelayClient {
    pub(super) async fn connect(
        relay: &RelayAddr,
        t: Duration,
    ) -> Result<(RelayClient, mpsc::Receiver<Incoming>), LinkError> {
        let target = (relay.host.as_str(), relay.port);
        let stream = match timeout(t, TcpStream::connect(target)).await {
            Ok(Ok(s)) => s,
            Ok(Err(e)) => {
                return Err(LinkError::transient(format!(
                    "cannot reach the relay at {relay}: {e} — is `droidctl serve` (or spherov2's \
                     tcp_server) running there?"
                )));
            }
            Err(_) => {
                return Err(LinkError::transient(format!(
                    "the relay at {relay} did not answer within {:.0} s",
                    t.as_secs_f64()
                )));
            }
        };
        let _ = stream.set_nodelay(true);
        Ok(RelayClient::over(stream, relay))
    }

    /// A client over any byte stream to a relay (a TCP connection; a pipe in tests).
    pub(super) fn over(
        stream: impl tokio::io::AsyncRead + tokio::io::AsyncWrite + Send + 'static,
        relay: &RelayAddr,
    ) -> (RelayClient, mpsc::Receiver<Incoming>) {
        let (mut rd, wr) = tokio::io::split(stream);
        let decoder = Arc::new(Mutex::new(ReplyDecoder::new(Limits::default())));
        let waiters = Arc::new(Mutex::new(Waiters::default()));
        let (tx, rx) = mpsc::channel(EVENTS);
        let reader = {
            let decoder = decoder.clone();
            let waiters = waiters.clone();
            let relay = relay.clone();
            tokio::spawn(async move {
                let mut buf = vec![0u8; READ_CHUNK];
                let why = loop {
                    let n = match rd.read(&mut buf).await {
                        Ok(0) => {
                            let last = lock(&decoder).finish();
                            break match last {
                                Some(Ok(msg)) if !msg.is_empty() => {
                                    format!("the relay at {relay} closed the connection: {msg}")
                                }
                                _ => format!(
                                    "the relay at {relay} closed the connection (the droid may \
                                     have disconnected)"
                                ),
                            };
                        }
                        Ok(n) => n,
                        Err(e) => {
                            break format!("the connection to the relay at {relay} failed: {e}");
                        }
                    };
                    let mut replies = Vec::new();
                    let mut bad = None;
                    {
                        let mut d = lock(&decoder);
                        d.push(&buf[..n]);
                        while let Some(r) = d.next() {
                            match r {
                                Ok(r) => replies.push(r),
                                Err(e) if e.recoverable() => {
                                    tracing::warn!(error = %e, "relay: bad reply skipped")
                                }
                                Err(e) => {
                                    bad = Some(e);
                                    break;
                                }
                            }
                        }
                    }
                    for r in replies {
                        dispatch(r, &waiters, &tx).await;
                    }
                    if let Some(e) = bad {
                        break format!("the relay at {relay} sent something unexpected: {e}");
                    }
                };
                tracing::info!(reason = %why, "relay connection ended");
                let mut w = lock(&waiters);
                w.closed = Some(why.clone());
                for (_, s) in w.seq.drain() {
                    let _ = s.send(Err(why.clone()));
                }
                for s in w.discovery.drain(..) {
                    let _ = s.send(Err(why.clone()));
                }
                drop(w);
                let _ = tx.try_send(Incoming::Closed(why));
            })
        };
        (
            RelayClient {
                writer: tokio::sync::Mutex::new(Some(Box::new(wr))),
                decoder,
                waiters,
                reader,
                relay: relay.clone(),
            },
            rx,
        )
    }

    /// Send `req`, its expectation registered first so the reply is read right.
    pub(super) async fn send(&self, req: &Request) -> Result<(), String> {
        let bytes = req.to_bytes().map_err(|e| e.to_string())?;
        let mut w = self.writer.lock().await;
        let wr = w
            .as_mut()
            .ok_or_else(|| format!("the connection to the relay at {} is closed", self.relay))?;
        if let Some(e) = req.expect() {
            lock(&self.decoder).expect(e);
        }
        wr.write_all(&bytes)
            .await
            .map_err(|e| format!("the connection to the relay at {} failed: {e}", self.relay))
    }

    /// A request with a seq: INIT, SET_CALLBACK or WRITE (`make` gets the seq).
    pub(super) async fn call(
        &self,
        make: impl FnOnce(u8) -> Request,
        limit: Duration,
    ) -> Result<(), String> {
        let (tx, rx) = oneshot::channel();
        let seq = {
            let mut w = lock(&self.waiters);
            if let Some(why) = &w.closed {
                return Err(why.clone());
            }
            // The next seq no reply is pending for (256 in flight cannot happen: each call
            // waits for its reply).
            let mut seq = w.next_seq;
            for _ in 0..=u8::MAX {
                if !w.seq.contains_key(&seq) {
                    break;
                }
                seq = seq.wrapping_add(1);
            }
            w.next_seq = seq.wrapping_add(1);
            w.seq.insert(seq, tx);
            seq
        };
        let req = make(seq);
        let name = req.name();
        // The write is bounded too: a relay that stops reading fills the socket's buffers,
        // and an unbounded write would hang the session's writer for good.
        let answered = timeout(limit, async {
            self.send(&req).await?;
            rx.await
                .unwrap_or_else(|_| Err("the relay connection ended".into()))
        })
        .await;
        match answered {
            Ok(r) => {
                if r.is_err() {
                    lock(&self.waiters).seq.remove(&seq);
                }
                r
            }
            Err(_) => {
                lock(&self.waiters).seq.remove(&seq);
                // A request may be half written: the stream cannot be followed any more.
                self.writer.lock().await.take();
                Err(format!(
                    "the relay did not take or answer {name} within {:.0} s",
                    limit.as_secs_f64()
                ))
            }
        }
    }

    /// SCAN or FIND.
    pub(super) async fn discover(&self, req: Request, limit: Duration) -> Result<Reply, String> {
        let (tx, rx) = oneshot::channel();
        {
            let mut w = lock(&self.waiters);
            if let Some(why) = &w.closed {
                return Err(why.clone());
            }
            w.discovery.push_back(tx);
        }
        let answered = timeout(limit, async {
            self.send(&req).await?;
            rx.await
                .unwrap_or_else(|_| Err("the relay connection ended".into()))
        })
        .await;
        answered.unwrap_or_else(|_| {
            Err(format!(
                "the relay did not take or answer {} within {:.0} s",
                req.name(),
                limit.as_secs_f64()
            ))
        })
    }

    /// END, then close (best effort).
    pub(super) async fn close(&self) {
        let _ = timeout(Duration::from_secs(1), self.send(&Request::End)).await;
        if let Some(mut wr) = self.writer.lock().await.take() {
            let _ = timeout(Duration::from_secs(1), wr.shutdown()).await;
        }
    }
}

impl Drop for RelayClient {
    fn drop(&mut self) {
        self.reader.abort();
    }
}

async fn dispatch(r: Reply, waiters: &Mutex<Waiters>, tx: &mpsc::Sender<Incoming>) {
    match r {
        Reply::Ok { seq } => {
            if let Some(s) = lock(waiters).seq.remove(&seq) {
                let _ = s.send(Ok(()));
            }
        }
        Reply::Error {
            message,
            seq: Some(seq),
        } => {
            if let Some(s) = lock(waiters).seq.remove(&seq) {
                let _ = s.send(Err(message));
            }
        }
        r @ (Reply::Devices(_) | Reply::Found(_) | Reply::Error { seq: None, .. }) => {
            if let Some(s) = lock(waiters).discovery.pop_front() {
                let _ = s.send(Ok(r));
            }
        }
        Reply::Data {
            characteristic,
            data,
        } => {
            // Wait for room: the link reads continuously; TCP pushes back on the relay.
            let _ = tx
                .send(Incoming::Data {
                    characteristic,
                    data,
                })
                .await;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A relay that stops reading: a pipe whose buffer is full. A request must give up within
    /// its limit; the write used to wait for room forever, hanging the session's writer.
    #[tokio::test]
    pub(super) async fn a_write_to_a_relay_that_stops_reading_gives_up() {
        let (ours, _theirs) = tokio::io::duplex(16);
        let relay = RelayAddr {
            host: "pipe".into(),
            port: 0,
        };
        let (client, _events) = RelayClient::over(ours, &relay);
        let write = |seq| Request::Write {
            seq,
            characteristic: "00010002-574f-4f20-5370-6865726f2121".into(),
            data: vec![0x55; 20],
        };
        let r = timeout(
            Duration::from_secs(5),
            client.call(write, Duration::from_millis(200)),
        )
        .await
        .expect("the call gave up by itself");
        let e = r.unwrap_err();
        assert!(e.contains("did not take or answer WRITE"), "{e}");
        // The stream may hold half a request now: later requests fail at once.
        let e = client
            .call(write, Duration::from_millis(200))
            .await
            .unwrap_err();
        assert!(e.contains("closed"), "{e}");
    }
}
