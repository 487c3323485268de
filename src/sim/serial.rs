//! `droidctl sim --serial rvr`: the simulated RVR on a pseudo-terminal, as a real one sits on
//! a Raspberry Pi's UART — whatever speaks RVR's serial protocol (droidctl's `--serial`,
//! Sphero's `sphero-sdk` with `SerialAsyncDal`) can be tested without one.
//!
//! The droid is the same as `--sim rvr` ([`SimLink`]); the pseudo-terminal carries the bytes
//! both ways unchanged (a serial line has no 20-byte notifications: the pieces the link cuts
//! arrive back to back). Nobody reading: a UART's bytes fall on the floor, so the droid's are
//! dropped once the terminal's buffer is full rather than holding the droid up.

use super::link::SimLink;
use super::trace::{PacketTracer, TraceRecord};
use super::{Faults, SimConfig};
use crate::link::serial::tty::Tty;
use crate::link::{Link, LinkEvent};
use crate::model::Model;
use std::time::Duration;
use tokio::time::Instant;

/// How long a write to the pseudo-terminal may wait for room before its bytes are dropped.
const WRITE_WAIT: Duration = Duration::from_millis(200);
/// Bytes read from the pseudo-terminal at once, at most.
const READ_MAX: usize = 512;

/// What the server says as it runs.
pub enum SerialReport {
    /// A line for people.
    Status(String),
    /// A traced packet (with `--trace`).
    Trace { t_ms: u64, record: TraceRecord },
}

/// Serve a simulated droid of `model` on the pseudo-terminal `pty` (its controlling side)
/// until the runtime stops it; `device` names it in traces.
pub async fn serve(
    pty: Tty,
    model: Model,
    trace: bool,
    mut report: impl FnMut(SerialReport),
) -> String {
    let profile = crate::family::gatt_profile(model);
    let api = profile.write.characteristic;
    let notify = profile
        .notify
        .first()
        .map(|c| c.characteristic)
        .unwrap_or(api);
    let mut tracer = trace.then(|| PacketTracer::new(model));
    let epoch = Instant::now();
    let t_ms = move || Instant::now().duration_since(epoch).as_millis() as u64;
    let mut link = SimLink::new(model, SimConfig::for_model(model), Faults::none());
    let mut buf = vec![0u8; READ_MAX];
    let mut dropped: u64 = 0;
    // The last write found no room: the next ones only try, until one fits again.
    let mut jammed = false;
    loop {
        let mut conn = match link.open().await {
            Ok(c) => c,
            Err(e) => return format!("the simulated droid would not connect: {e}"),
        };
        if let Some(t) = tracer.as_mut() {
            t.reset();
        }
        loop {
            tokio::select! {
                n = pty.read(&mut buf) => match n {
                    // Nobody holds the terminal side but us: nothing to read, ever — the
                    // simulator keeps it open, so this is the end of the device.
                    Ok(0) => return "the pseudo-terminal closed".into(),
                    Ok(n) => {
                        let bytes = &buf[..n];
                        if let Some(t) = tracer.as_mut() {
                            for record in t.write(api, bytes) {
                                report(SerialReport::Trace { t_ms: t_ms(), record });
                            }
                        }
                        if conn.writer.write(bytes).await.is_err() {
                            break;
                        }
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => return format!("reading the pseudo-terminal: {e}"),
                },
                ev = conn.events.recv() => match ev {
                    Some(LinkEvent::Data(bytes)) => {
                        if let Some(t) = tracer.as_mut() {
                            for record in t.notify(notify, &bytes) {
                                report(SerialReport::Trace { t_ms: t_ms(), record });
                            }
                        }
                        let wait = if jammed { Duration::from_millis(1) } else { WRITE_WAIT };
                        match tokio::time::timeout(wait, pty.write_all(&bytes)).await {
                            Ok(Ok(())) => jammed = false,
                            Ok(Err(e)) => return format!("writing the pseudo-terminal: {e}"),
                            Err(_) => {
                                jammed = true;
                                dropped += bytes.len() as u64;
                                // Said once per thousand-odd bytes, not per packet.
                                if dropped == bytes.len() as u64 || dropped % 1024 < bytes.len() as u64 {
                                    report(SerialReport::Status(format!(
                                        "nobody is reading: {dropped} bytes of the droid's dropped so far"
                                    )));
                                }
                            }
                        }
                    }
                    Some(LinkEvent::Disconnected(why)) => {
                        report(SerialReport::Status(format!("{why}; the droid is back")));
                        break;
                    }
                    None => break,
                },
            }
        }
    }
}
