//! A relay client's byte stream, whatever carries it (a TCP connection, or an in-process
//! pipe for tests and fuzzing): requests read into a bounded queue, replies written in
//! batches with a time limit.

use crate::protocol::relay::{DecodeError, Request, RequestDecoder};
use std::collections::VecDeque;
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
use tokio::sync::mpsc;
use tokio::time::timeout;

/// The reading half of a client's stream.
pub type ClientReader = Box<dyn AsyncRead + Send + Unpin>;
/// The writing half of a client's stream.
pub type ClientWriter = Box<dyn AsyncWrite + Send + Unpin>;

/// Read buffer size: a few requests at a time.
pub(super) const READ_CHUNK: usize = 4096;

/// Requests a client may have waiting behind the one being served: the protocol's SEQ is one
/// byte, so more outstanding requests could not be told apart. A client that sends more
/// without waiting for the answers is told so and closed.
pub const MAX_QUEUED: usize = 256;

/// Scans and finds (up to [`ServerConfig::max_scan`] each) a client may have waiting: one
/// pipelining hundreds of SCANs in one write would hold its task, and the adapter's scan,
/// for hours.
pub const MAX_QUEUED_SCANS: usize = 2;

/// Move the requests `decoder` has whole into `queue`; `Err` when more wait than the bounds
/// allow. `serving`: a request is being served; else the queue's first is the next one
/// served, not one waiting (three scans in one write are one served and two waiting, as when
/// the third arrives while the first is served).
pub(super) fn take_requests(
    decoder: &mut RequestDecoder,
    queue: &mut VecDeque<Result<Request, DecodeError>>,
    serving: bool,
) -> Result<(), String> {
    let is_scan = |r: &Result<Request, DecodeError>| {
        matches!(r, Ok(Request::Scan { .. } | Request::Find { .. }))
    };
    let next = usize::from(!serving);
    let mut scans = queue.iter().skip(next).filter(|r| is_scan(r)).count();
    while let Some(r) = decoder.next() {
        if queue.len() >= next {
            scans += is_scan(&r) as usize;
        }
        queue.push_back(r);
        if scans > MAX_QUEUED_SCANS {
            return Err(format!(
                "more than {MAX_QUEUED_SCANS} scans queued behind the one being served; wait \
                 for the answers"
            ));
        }
        if queue.len() - next.min(queue.len()) > MAX_QUEUED {
            return Err(format!(
                "more than {MAX_QUEUED} requests queued behind the one being served; wait for \
                 the answers"
            ));
        }
    }
    Ok(())
}

/// While a request is served: keep reading the client, so its departure is noticed (and
/// what it sends meanwhile queued). Resolves only with the reason to close: the client went,
/// reading failed, or it queued too much.
pub(super) async fn read_while_busy(
    rd: &mut ClientReader,
    buf: &mut [u8],
    decoder: &mut RequestDecoder,
    queue: &mut VecDeque<Result<Request, DecodeError>>,
) -> String {
    loop {
        match rd.read(buf).await {
            Ok(0) => return "the client disconnected".to_string(),
            Ok(n) => {
                decoder.push(&buf[..n]);
                if let Err(why) = take_requests(decoder, queue, true) {
                    return why;
                }
            }
            Err(e) => return format!("reading failed: {e}"),
        }
    }
}

/// Send queued frames to the client; the reason it ended.
pub(super) async fn write_loop(
    mut wr: ClientWriter,
    mut rx: mpsc::Receiver<Vec<u8>>,
    limit: Duration,
) -> String {
    let mut batch = Vec::new();
    while let Some(first) = rx.recv().await {
        batch.clear();
        batch.extend_from_slice(&first);
        // Whatever else is queued goes in the same write.
        while batch.len() < 64 * 1024 {
            match rx.try_recv() {
                Ok(more) => batch.extend_from_slice(&more),
                Err(_) => break,
            }
        }
        match timeout(limit, wr.write_all(&batch)).await {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return format!("writing to the client failed: {e}"),
            Err(_) => {
                return format!(
                    "the client cannot keep up: a write stalled for {:.0} s",
                    limit.as_secs_f64()
                );
            }
        }
    }
    let _ = timeout(limit, wr.shutdown()).await;
    "closed".to_string()
}
