//! The bridge over standard input/output: one JSON command per line in, one JSON object per
//! line out (`hello` first, then link states, telemetry, replies and errors as they come).
//! Any language drives a droid with a pipe.
//!
//! A bad line gets one error line and changes nothing else. A line longer than
//! [`schema::MAX_COMMAND_BYTES`] is refused without being kept (the reader holds at most that
//! much). When the input ends (the client closed its end, or died), the droids it was
//! driving are stopped and [`run`] returns.
//!
//! Replies, errors, `stopped` and `link` objects are never dropped (issue 27 point 5): the
//! next line is read only while the output keeps up with them ([`Bridge::room`]), and
//! everything is written before [`run`] returns, for as long as the reader takes it. Only
//! telemetry is dropped (counted: [`Bridge::dropped`]) for a reader that is too slow.

use super::Bridge;
use super::outbox::Outputs;
use super::schema::{self, BadCommand, ErrorCode};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;
use tokio::io::{AsyncBufRead, AsyncBufReadExt, AsyncWrite, AsyncWriteExt};

/// After the input ends, what is left is written for as long as the reader takes some of it
/// within this long; a reader that takes nothing for this long is given up on.
pub const DRAIN_STALL: Duration = Duration::from_secs(10);

/// Why the bridge over stdio ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum End {
    /// The input ended.
    InputClosed,
    /// The output ended: the reader went away (a closed pipe).
    OutputClosed(String),
    /// The output could not be written for another reason (a full disk): a failure.
    OutputFailed(String),
    /// Told to stop (a signal).
    Stopped,
}

/// One line from `input`, at most `max` bytes kept: `Ok(None)` at the end, `Err(n)` for a
/// line of `n` bytes that was too long (skipped to its end).
pub async fn read_line<R: AsyncBufRead + Unpin>(
    input: &mut R,
    max: usize,
    line: &mut Vec<u8>,
) -> std::io::Result<Option<Result<(), usize>>> {
    line.clear();
    let mut total = 0usize;
    loop {
        let buf = input.fill_buf().await?;
        if buf.is_empty() {
            return Ok(match total {
                0 => None,
                n if n > max => Some(Err(n)),
                _ => Some(Ok(())),
            });
        }
        let (chunk, done) = match memchr::memchr(b'\n', buf) {
            Some(at) => (&buf[..at], at + 1),
            None => (buf, buf.len()),
        };
        total += chunk.len();
        if total <= max {
            line.extend_from_slice(chunk);
        }
        let ended = done > chunk.len();
        input.consume(done);
        if ended {
            return Ok(Some(if total > max { Err(total) } else { Ok(()) }));
        }
    }
}

/// How long a command for a droid that has not been ready yet waits for it, by default
/// ([`run_waiting`]; the CLI gives its scan timeout).
pub const FIRST_READY: Duration = Duration::from_secs(10);

/// [`run_waiting`] with [`FIRST_READY`].
pub async fn run<R, W>(
    bridge: Arc<Bridge>,
    rx: Outputs,
    input: R,
    output: W,
    stopped: impl std::future::Future<Output = ()>,
) -> End
where
    R: AsyncBufRead + Unpin,
    W: AsyncWrite + Unpin + Send + 'static,
{
    run_waiting(bridge, rx, input, output, stopped, FIRST_READY).await
}

/// Run the bridge over `input` and `output` until the input ends, the output fails or
/// `stopped` completes; then stop the droids being driven (saying so when the input
/// ended), stop and disconnect every droid, and write what is left.
///
/// A command for a droid that has not been ready yet since the start is held, and no
/// line after it read, until the droid is ready or `first_ready` passed (issue 40 point
/// 11): a script piped in is answered the same way every time, whatever the connection
/// takes. An `estop` and a line that is no command never wait.
pub async fn run_waiting<R, W>(
    bridge: Arc<Bridge>,
    mut rx: Outputs,
    mut input: R,
    mut output: W,
    stopped: impl std::future::Future<Output = ()>,
    first_ready: Duration,
) -> End
where
    R: AsyncBufRead + Unpin,
    W: AsyncWrite + Unpin + Send + 'static,
{
    let hello = bridge.hello();
    let (finish, mut finished) = tokio::sync::oneshot::channel::<()>();
    let written = Arc::new(AtomicU64::new(0));
    let progress = written.clone();
    let mut writer = tokio::spawn(async move {
        let mut text = hello.to_json();
        text.push('\n');
        output.write_all(text.as_bytes()).await?;
        output.flush().await?;
        let mut last = false;
        loop {
            text.clear();
            tokio::select! {
                o = rx.recv() => match o {
                    Some(o) => text.push_str(&o.to_json()),
                    None => last = true,
                },
                _ = &mut finished, if !last => last = true,
            }
            if !text.is_empty() {
                text.push('\n');
            }
            // Whatever else is waiting goes in the same write.
            while (last || text.len() < 64 * 1024)
                && let Ok(o) = rx.try_recv()
            {
                text.push_str(&o.to_json());
                text.push('\n');
            }
            output.write_all(text.as_bytes()).await?;
            output.flush().await?;
            progress.fetch_add(text.len() as u64 + 1, Ordering::Relaxed);
            if last {
                return Ok::<(), std::io::Error>(());
            }
        }
    });
    let reader = async {
        let mut line = Vec::with_capacity(256);
        loop {
            // The output keeps up with the answers before another line is read.
            bridge.room().await;
            match read_line(&mut input, schema::MAX_COMMAND_BYTES, &mut line).await {
                Ok(None) => return End::InputClosed,
                Err(e) => {
                    tracing::warn!(error = %e, "bridge: stdin cannot be read");
                    return End::InputClosed;
                }
                Ok(Some(Err(n))) => bridge.emit(
                    None,
                    schema::Out::error(BadCommand {
                        id: None,
                        droid: None,
                        cmd: None,
                        code: ErrorCode::BadJson,
                        message: format!(
                            "a line of {n} bytes: a command is at most {} bytes",
                            schema::MAX_COMMAND_BYTES
                        ),
                    }),
                ),
                Ok(Some(Ok(()))) => {
                    let text = line.strip_suffix(b"\r").unwrap_or(&line);
                    // Blank lines are ignored (a client's keep-alive).
                    if !text.iter().all(u8::is_ascii_whitespace) {
                        let parsed = schema::parse(text);
                        if let Ok(req) = &parsed
                            && req.cmd != schema::Cmd::Estop
                            && let Ok(i) = bridge.target(req, None)
                        {
                            bridge.first_ready(i, first_ready).await;
                        }
                        bridge.handle_parsed(parsed, None);
                    }
                }
            }
        }
    };
    let mut writer_done = None;
    let end = tokio::select! {
        end = reader => end,
        r = &mut writer => {
            let end = match &r {
                Ok(Ok(())) => End::OutputClosed("the output ended".to_string()),
                Ok(Err(e)) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                    End::OutputClosed(e.to_string())
                }
                Ok(Err(e)) => End::OutputFailed(e.to_string()),
                Err(e) => End::OutputFailed(e.to_string()),
            };
            writer_done = Some(r);
            end
        }
        _ = stopped => End::Stopped,
    };
    if end == End::InputClosed {
        bridge.release(0..bridge.fleet().len(), "input_closed");
    }
    bridge.shutdown().await;
    if writer_done.is_none() {
        let _ = finish.send(());
        // Everything is written while the reader takes it, however slowly.
        let mut seen = written.load(Ordering::Relaxed);
        loop {
            match tokio::time::timeout(DRAIN_STALL, &mut writer).await {
                // The output failed while the input was read to its end: a full disk is a
                // failure whenever it is met (a closed pipe is the reader's choice).
                Ok(Ok(Err(e))) if e.kind() != std::io::ErrorKind::BrokenPipe => {
                    return End::OutputFailed(e.to_string());
                }
                Ok(_) => break,
                Err(_) => {
                    let now = written.load(Ordering::Relaxed);
                    if now == seen {
                        tracing::warn!(
                            "bridge: the reader took nothing for {DRAIN_STALL:?}: not waiting"
                        );
                        writer.abort();
                        break;
                    }
                    seen = now;
                }
            }
        }
    }
    end
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;
    use tokio::io::AsyncReadExt;

    /// The lines out for `script` piped into a bridge on a simulated R2-D2 whose commands
    /// wait at most `first_ready` for its first `ready` (paused time: the same every run).
    async fn piped(script: &str, first_ready: Duration) -> Vec<serde_json::Value> {
        let rig = super::super::tests::rig(&[Model::R2D2], 600).await;
        let (writer, mut out_r) = tokio::io::duplex(1 << 22);
        let input = tokio::io::BufReader::new(script.as_bytes());
        let end = run_waiting(
            rig.bridge.clone(),
            rig.rx,
            input,
            writer,
            std::future::pending(),
            first_ready,
        )
        .await;
        assert_eq!(end, End::InputClosed);
        let mut text = String::new();
        out_r.read_to_string(&mut text).await.unwrap();
        text.lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    }

    /// Issue 40 point 11: no command for a droid is read before its first `ready`, so a
    /// script piped in is answered by replies only, every time; past the bound the first
    /// lines are carried out as they come (a stop before R2 stands is answered at once).
    #[tokio::test(start_paused = true)]
    async fn a_piped_script_waits_for_the_droids_first_ready_within_a_bound() {
        let script: String = (0..500)
            .map(|n| format!("{{\"v\":1,\"cmd\":\"stop\",\"id\":{n}}}\n"))
            .collect();
        let lines = piped(&script, Duration::from_secs(10)).await;
        let at = |f: &dyn Fn(&serde_json::Value) -> bool| lines.iter().position(f);
        let ready = at(&|v| v["type"] == "link" && v["ready"] == true).expect("ready");
        let first = at(&|v| v["type"] == "reply").expect("replies");
        assert!(
            ready < first,
            "a reply before the droid was ready: {lines:?}"
        );
        let replies = lines.iter().filter(|v| v["type"] == "reply").count();
        assert_eq!(replies, 500);
        // Bounded: waiting 1 ms, the first stop is answered before R2 stands.
        let lines = piped(&script, Duration::from_millis(1)).await;
        let ready = lines
            .iter()
            .position(|v| v["type"] == "link" && v["ready"] == true);
        let first = lines.iter().position(|v| v["type"] == "reply").unwrap();
        assert!(ready.is_none_or(|r| first < r), "{lines:?}");
    }
}
