//! Ending a session while it is reconnecting (Ctrl-C during a reconnect) is prompt and clean,
//! and `shutdown_stopped` stops at the last heading.

use droidctl::link::{Connection, Link, LinkError, LinkEvent, LinkWriter};
use droidctl::protocol::v2::cmd;
use droidctl::protocol::v2::wire::DriveFlags;
use droidctl::session::{self, LinkState, SessionConfig, Slot};
use droidctl::units::Heading;
use futures_util::future::BoxFuture;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::{Instant, sleep};

/// Connects once, drops the link at 1 s, then every reconnect fails.
struct FlakyLink {
    opens: Arc<Mutex<u32>>,
    writes: Arc<Mutex<Vec<Vec<u8>>>>,
}

struct Writer(Arc<Mutex<Vec<Vec<u8>>>>);

impl LinkWriter for Writer {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        self.0.lock().unwrap().push(chunk.to_vec());
        Box::pin(async { Ok(()) })
    }
    fn close(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async {})
    }
}

impl Link for FlakyLink {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        let n = {
            let mut o = self.opens.lock().unwrap();
            *o += 1;
            *o
        };
        let writes = self.writes.clone();
        Box::pin(async move {
            if n > 1 {
                return Err(LinkError::transient("droid asleep"));
            }
            let (tx, rx) = mpsc::channel(8);
            tokio::spawn(async move {
                sleep(Duration::from_secs(1)).await;
                let _ = tx.send(LinkEvent::Disconnected("gone".into())).await;
            });
            Ok(Connection {
                writer: Box::new(Writer(writes)),
                events: rx,
            })
        })
    }
    fn describe(&self) -> String {
        "flaky".into()
    }
}

#[tokio::test(start_paused = true)]
async fn shutdown_while_reconnecting_is_prompt() {
    let opens = Arc::new(Mutex::new(0));
    let link = FlakyLink {
        opens: opens.clone(),
        writes: Arc::new(Mutex::new(Vec::new())),
    };
    let s = session::start(Box::new(link), SessionConfig::default());
    sleep(Duration::from_secs(10)).await;
    assert!(
        matches!(s.state(), LinkState::Reconnecting { attempt, .. } if attempt >= 3),
        "{:?}",
        s.state()
    );
    let t = Instant::now();
    s.shutdown_stopped(vec![]).await;
    assert!(
        t.elapsed() < Duration::from_millis(10),
        "shutdown waited for the backoff: {:?}",
        t.elapsed()
    );
    assert_eq!(s.state(), LinkState::Closed { reason: None });
    let attempts = *opens.lock().unwrap();
    sleep(Duration::from_secs(60)).await;
    assert_eq!(
        *opens.lock().unwrap(),
        attempts,
        "no reconnect attempts after shutdown"
    );
    assert_eq!(
        s.request(cmd::ping()).await,
        Err(droidctl::session::RequestError::Closed)
    );
}

/// Always connected; records writes.
struct GoodLink(Arc<Mutex<Vec<Vec<u8>>>>);

impl Link for GoodLink {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        let writes = self.0.clone();
        Box::pin(async move {
            let (tx, rx) = mpsc::channel(8);
            tokio::spawn(async move {
                let _keep = tx;
                std::future::pending::<()>().await;
            });
            Ok(Connection {
                writer: Box::new(Writer(writes)),
                events: rx,
            })
        })
    }
    fn describe(&self) -> String {
        "good".into()
    }
}

#[tokio::test(start_paused = true)]
async fn shutdown_stopped_stops_at_the_last_heading() {
    let writes = Arc::new(Mutex::new(Vec::new()));
    let s = session::start(Box::new(GoodLink(writes.clone())), SessionConfig::default());
    s.set(
        Slot::Drive,
        cmd::drive_with_heading(120, Heading::new(270).unwrap(), DriveFlags::empty()),
    );
    sleep(Duration::from_millis(500)).await;
    s.shutdown_stopped(vec![cmd::sleep().into()]).await;
    let all: Vec<u8> = writes.lock().unwrap().concat();
    let packets: Vec<_> = droidctl::protocol::v2::Decoder::new()
        .decode_all(&all)
        .into_iter()
        .map(Result::unwrap)
        .collect();
    let n = packets.len();
    assert!(n >= 3);
    let stop = &packets[n - 2];
    assert_eq!((stop.did, stop.cid), (0x16, 0x07));
    assert_eq!(stop.data, vec![0, 0x01, 0x0E, 0], "speed 0 at heading 270");
    assert_eq!(
        (packets[n - 1].did, packets[n - 1].cid),
        (0x13, 0x01),
        "then the extra command"
    );
}

// Sends SIGINT with `kill`.
#[cfg(unix)]
#[test]
fn ctrl_c_stops_a_running_mission() {
    let dir = std::env::temp_dir().join(format!("droidctl-sigint-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("long.txt");
    std::fs::write(&script, "wake\nstance tripod\ndrive 50 90\nwait 3000s\n").unwrap();
    let log = dir.join("log");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["run", script.to_str().unwrap(), "--sim"])
        .env("DROIDCTL_LOG_FILE", &log)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1000));
    let _ = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    // 128 + SIGINT, once the droid is stopped (docs/exit-status.md).
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(
        err.contains("SIGINT: mission interrupted, the droid was stopped"),
        "{err}"
    );
    let log = std::fs::read_to_string(&log).unwrap();
    // Speed 0 at the mission's heading (90 = 00 5A), not heading 0.
    assert!(
        log.lines()
            .any(|l| l.contains("final command") && l.contains("data=00 00 5A 00")),
        "{log}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
