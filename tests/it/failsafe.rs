//! Issue 15, in-process part: stop first then set up, the droids' own fail-safes, and a
//! sleeping droid woken for a drive command. All on tokio's paused clock against the
//! simulated droids (the same checks through btleplug run against `sim --bluez`).

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::family::{self, Command};
use droidctl::link::{Connection, Link, LinkError, LinkWriter};
use droidctl::model::Model;
use droidctl::protocol::v1;
use droidctl::protocol::v2::cmd;
use droidctl::protocol::v2::wire::DriveFlags;
use droidctl::session::{self, Direction, LinkState, LogEntry, LogItem, SessionConfig, Slot};
use droidctl::sim::{Faults, SimConfig, SimLink};
use droidctl::units::Heading;
use futures_util::future::BoxFuture;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::time::{Instant, sleep};

fn secs(s: f64) -> Duration {
    Duration::from_secs_f64(s)
}

fn config(model: Model, setup: Vec<Command>) -> SessionConfig {
    SessionConfig {
        family: model.protocol(),
        pacing: model.write_pacing(),
        setup,
        ..SessionConfig::default()
    }
}

fn setup_of(model: Model) -> Vec<Command> {
    connect_setup(
        model,
        &SetupOptions {
            tripod: false,
            streaming_interval_ms: 0,
            ..Default::default()
        },
    )
}

/// What the session wrote: when, the command's name, its payload.
type Written = Arc<Mutex<Vec<(Duration, String, Vec<u8>)>>>;

/// Every command the session wrote, by name, with when.
fn record_out(s: &session::SessionHandle) -> Written {
    let out = Arc::new(Mutex::new(Vec::new()));
    let mut rx = s.subscribe_log();
    let seen = out.clone();
    tokio::spawn(async move {
        while let Ok(LogEntry { at, dir, item }) = rx.recv().await {
            if let (Direction::Out, LogItem::Packet { packet, explained }) = (dir, item) {
                seen.lock()
                    .unwrap()
                    .push((at, explained.label, packet.data().to_vec()));
            }
        }
    });
    out
}

async fn connected(s: &session::SessionHandle) {
    let mut rx = s.watch_state();
    while *rx.borrow_and_update() != LinkState::Connected {
        rx.changed().await.unwrap();
    }
}

/// Drive a droid through a session for 2 s, then lose the host without a stop (the session
/// ends with nothing written); how fast is the droid 3 s later?
async fn speed_after_host_vanishes(model: Model, setup: Vec<Command>) -> f32 {
    // A big hall: no wall stops the droid in these 6 s.
    let cfg = SimConfig {
        room_cm: (4000.0, 4000.0),
        ..SimConfig::default()
    };
    let link = SimLink::new(model, cfg, Faults::none());
    let probe = link.probe();
    let s = session::start(Box::new(link), config(model, setup));
    connected(&s).await;
    sleep(secs(1.0)).await;
    let fam = family::for_model(model);
    let t0 = Instant::now();
    while t0.elapsed() < secs(2.0) {
        s.set(Slot::Drive, fam.drive(100, Heading::default(), false));
        sleep(secs(0.2)).await;
    }
    let before = probe.state().velocity_cm_s;
    assert!(
        before > 40.0,
        "{model:?} was driving: {before} {:?}",
        probe.state()
    );
    // The host is gone: no stop, the link just closes.
    s.shutdown(Vec::new()).await;
    sleep(secs(3.0)).await;
    probe.state().velocity_cm_s
}

#[tokio::test(start_paused = true)]
async fn v1_fail_safe_stops_at_once_when_the_link_drops() {
    let with = speed_after_host_vanishes(Model::BB8, setup_of(Model::BB8)).await;
    assert_eq!(with, 0.0, "stop-on-disconnect set on connect");
    let fs = family::for_model(Model::BB8).fail_safe().unwrap();
    assert_eq!(fs, v1::cmd::set_temporary_option_flags(1).into());
    let without: Vec<Command> = setup_of(Model::BB8)
        .into_iter()
        .filter(|c| *c != fs)
        .collect();
    let rolling = speed_after_host_vanishes(Model::BB8, without).await;
    assert!(
        rolling > 40.0,
        "without it the droid keeps rolling: {rolling}"
    );
}

#[tokio::test(start_paused = true)]
async fn v2_fail_safe_stops_when_its_timeout_runs_out() {
    let with = speed_after_host_vanishes(Model::BB9E, setup_of(Model::BB9E)).await;
    assert_eq!(with, 0.0, "control-system timeout set on connect");
    let fs = family::for_model(Model::BB9E).fail_safe().unwrap();
    assert_eq!(fs, cmd::set_custom_control_system_timeout(2000).into());
    let without: Vec<Command> = setup_of(Model::BB9E)
        .into_iter()
        .filter(|c| *c != fs)
        .collect();
    let rolling = speed_after_host_vanishes(Model::BB9E, without).await;
    assert!(
        rolling > 40.0,
        "without it the droid keeps rolling: {rolling}"
    );
}

#[tokio::test(start_paused = true)]
async fn after_a_reconnect_the_stop_goes_before_any_setup_command() {
    let model = Model::R2D2;
    let faults = Faults {
        disconnect_at: vec![secs(6.0)],
        ..Faults::none()
    };
    let link = SimLink::new(model, SimConfig::default(), faults);
    let s = session::start(
        Box::new(link),
        config(model, connect_setup(model, &SetupOptions::default())),
    );
    let out = record_out(&s);
    connected(&s).await;
    // Drive at heading 135 until the link drops.
    let t0 = Instant::now();
    while t0.elapsed() < secs(5.5) {
        s.set(
            Slot::Drive,
            cmd::drive_with_heading(150, Heading::new(135).unwrap(), DriveFlags::empty()),
        );
        sleep(secs(0.2)).await;
    }
    sleep(secs(3.0)).await;
    assert_eq!(s.stats().reconnects, 1);
    let out = out.lock().unwrap().clone();
    let after: Vec<&(Duration, String, Vec<u8>)> =
        out.iter().filter(|(t, _, _)| *t > secs(6.0)).collect();
    let names: Vec<&str> = after.iter().map(|(_, n, _)| n.as_str()).collect();
    assert_eq!(names[0], "wake", "{names:?}");
    assert_eq!(names[1], "drive-with-heading", "{names:?}");
    assert_eq!(after[1].2, [0, 0, 135, 0], "speed 0 at the last heading");
    assert_eq!(names[2], "set-custom-control-system-timeout", "{names:?}");
    assert!(
        names.contains(&"perform-leg-action"),
        "then the rest of the setup"
    );
    s.shutdown(Vec::new()).await;
}

#[tokio::test(start_paused = true)]
async fn driving_never_waits_more_than_one_slot_behind_the_setup() {
    let model = Model::R2D2;
    let link = SimLink::new(model, SimConfig::default(), Faults::none());
    let s = session::start(
        Box::new(link),
        config(model, connect_setup(model, &SetupOptions::default())),
    );
    let out = record_out(&s);
    // A drive set before the connect goes out right after the wake, not after ten setup
    // commands.
    s.set(
        Slot::Drive,
        cmd::drive_with_heading(0, Heading::new(10).unwrap(), DriveFlags::empty()),
    );
    connected(&s).await;
    sleep(secs(0.2)).await;
    s.set(
        Slot::Drive,
        cmd::drive_with_heading(90, Heading::new(10).unwrap(), DriveFlags::empty()),
    );
    sleep(secs(3.0)).await;
    let out = out.lock().unwrap().clone();
    let names: Vec<&str> = out.iter().map(|(_, n, _)| n.as_str()).collect();
    assert_eq!(names[0], "wake", "{names:?}");
    let drives: Vec<usize> = names
        .iter()
        .enumerate()
        .filter(|(_, n)| **n == "drive-with-heading")
        .map(|(i, _)| i)
        .collect();
    assert_eq!(drives[0], 1, "the stop right after the wake: {names:?}");
    // The second drive, set while the setup was still going out, waited at most one slot.
    let set_at = out
        .iter()
        .position(|(t, _, _)| *t >= secs(0.2))
        .expect("writes after 0.2 s");
    assert!(drives[1] <= set_at + 1, "{names:?}");
    let setup_len = connect_setup(model, &SetupOptions::default()).len();
    assert!(
        drives[1] < setup_len,
        "the drive did not wait for the whole setup: {names:?}"
    );
    s.shutdown(Vec::new()).await;
}

#[tokio::test(start_paused = true)]
async fn a_sleeping_droid_is_woken_and_the_drive_resent() {
    let model = Model::BB9E;
    let link = SimLink::new(model, SimConfig::default(), Faults::none());
    let probe = link.probe();
    let s = session::start(Box::new(link), config(model, setup_of(model)));
    connected(&s).await;
    sleep(secs(2.0)).await;
    s.request(cmd::sleep()).await.expect("asleep");
    assert!(!probe.state().awake);
    // One drive command, no retries of its own: target_unavailable → Wake → the drive again.
    s.set(
        Slot::Drive,
        cmd::drive_with_heading(150, Heading::default(), DriveFlags::empty()),
    );
    sleep(secs(2.0)).await;
    let st = probe.state();
    assert!(st.awake, "woken");
    assert!(st.velocity_cm_s > 50.0, "the drive was re-sent: {st:?}");
    assert!(s.stats().retried >= 1);
    s.shutdown(Vec::new()).await;
}

/// A BB-8 whose firmware does not know Set Temporary Option Flags: the write is turned
/// into an unknown command (same SEQ), which the simulated droid refuses.
struct OldFirmware(SimLink);

struct Rewriter(Box<dyn LinkWriter>);

impl LinkWriter for Rewriter {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        let mut d = v1::Decoder::new(v1::Source::Host);
        let packets: Vec<_> = d.feed(chunk).collect();
        let rewritten = match packets.as_slice() {
            [Ok(v1::Packet::Command(c))] if (c.did, c.cid) == (0x02, 0x37) => {
                let mut c = c.clone();
                c.cid = 0x7E;
                v1::Packet::Command(c).encode().ok()
            }
            _ => None,
        };
        match rewritten {
            Some(bytes) => Box::pin(async move { self.0.write(&bytes).await }),
            None => self.0.write(chunk),
        }
    }
    fn close(&mut self) -> BoxFuture<'_, ()> {
        self.0.close()
    }
}

impl Link for OldFirmware {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            let c = self.0.open().await?;
            Ok(Connection {
                writer: Box::new(Rewriter(c.writer)),
                events: c.events,
            })
        })
    }
    fn describe(&self) -> String {
        self.0.describe()
    }
}

#[tokio::test(start_paused = true)]
async fn a_refused_fail_safe_is_no_error() {
    let model = Model::BB8;
    let link = OldFirmware(SimLink::new(model, SimConfig::default(), Faults::none()));
    let s = session::start(Box::new(link), config(model, setup_of(model)));
    connected(&s).await;
    sleep(secs(2.0)).await;
    let st = s.stats();
    assert_eq!(st.answered as usize, setup_of(model).len(), "{st:?}");
    assert_eq!(
        (st.errors, st.droid_errors),
        (0, 0),
        "refused, and fine: {st:?}"
    );
    // An ordinary command refused the same way is an error.
    let odd: Command = v1::Command {
        did: 0x02,
        cid: 0x7E,
        data: vec![],
    }
    .into();
    assert!(s.request(odd).await.is_err());
    assert_eq!(s.stats().errors, 1);
    s.shutdown(Vec::new()).await;
}

/// The droid warns 10 s before it sleeps; the session answers with a ping.
async fn awake_after(keep_awake: bool) -> bool {
    let model = Model::BB9E;
    let cfg = SimConfig {
        inactivity_timeout: secs(15.0),
        ..SimConfig::default()
    };
    let link = SimLink::new(model, cfg, Faults::none());
    let probe = link.probe();
    let s = session::start(
        Box::new(link),
        SessionConfig {
            keep_awake,
            ..config(model, setup_of(model))
        },
    );
    connected(&s).await;
    // Three inactivity timeouts with nothing from the host.
    sleep(secs(45.0)).await;
    let awake = probe.state().awake;
    s.shutdown(Vec::new()).await;
    awake
}

#[tokio::test(start_paused = true)]
async fn an_idle_connected_droid_is_kept_awake() {
    assert!(awake_after(true).await, "pinged on every will-sleep");
    assert!(!awake_after(false).await, "without the pings it sleeps");
}

/// The droid keeps streaming across a dropped link, with the masks it was told before; the
/// samples that arrive before the setup sets them again are still understood.
#[tokio::test(start_paused = true)]
async fn sensor_data_right_after_a_reconnect_is_not_an_error() {
    let model = Model::R2D2;
    let faults = Faults {
        disconnect_at: vec![secs(4.0)],
        ..Faults::none()
    };
    let link = SimLink::new(model, SimConfig::default(), faults);
    let s = session::start(
        Box::new(link),
        config(model, connect_setup(model, &SetupOptions::default())),
    );
    connected(&s).await;
    sleep(secs(8.0)).await;
    let st = s.stats();
    assert_eq!(st.reconnects, 1);
    assert_eq!((st.errors, st.decode_errors), (0, 0), "{st:?}");
    s.shutdown(Vec::new()).await;
}
