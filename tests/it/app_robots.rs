//! Issue 19 point 2 through the whole app under paused time, on simulated robots: RVR in tank
//! mode drives a track per gamepad stick (and stops when they rest and on quit); BOLT's matrix
//! prompt scrolls typed text and draws a typed character, addressed to its secondary
//! processor, and its compass calibrates; Mini drives by heading like BB-8.

use droidctl::app::input::{KeyKind, TermEvent};
use droidctl::app::run::{self, AppInputs};
use droidctl::app::state::AppState;
use droidctl::config::{Key, KeyCode};
use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::model::Model;
use droidctl::protocol::v2::Packet;
use droidctl::session::{self, Direction, LogEntry, LogItem, SessionConfig};
use droidctl::sim::{Faults, SimConfig, SimLink, link::SimProbe};
use droidctl::teleop::gamepad::{Axis, PadEvent};
use ratatui::{Frame, Terminal, backend::TestBackend};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio::time::sleep;

fn no_draw(_: &mut Frame, _: &AppState) {}

struct Harness {
    term: mpsc::Sender<TermEvent>,
    pad: mpsc::Sender<PadEvent>,
    quit: mpsc::Sender<String>,
    probe: SimProbe,
    /// Every v2 packet in either direction, in order.
    packets: Arc<Mutex<Vec<(Direction, Packet)>>>,
    app: JoinHandle<run::Exit>,
}

async fn start(model: Model) -> Harness {
    let link = SimLink::new(model, SimConfig::default(), Faults::none());
    let probe = link.probe();
    let session = session::start(
        Box::new(link),
        SessionConfig {
            family: model.protocol(),
            model: Some(model),
            pacing: model.write_pacing(),
            setup: connect_setup(model, &SetupOptions::default()),
            ..SessionConfig::default()
        },
    );
    let packets = Arc::new(Mutex::new(Vec::new()));
    {
        let mut log = session.subscribe_log();
        let packets = packets.clone();
        tokio::spawn(async move {
            while let Ok(LogEntry { dir, item, .. }) = log.recv().await {
                if let LogItem::Packet {
                    packet: droidctl::family::Packet::V2(p),
                    ..
                } = item
                {
                    packets.lock().unwrap().push((dir, p));
                }
            }
        });
    }
    let (term, term_rx) = mpsc::channel(64);
    let (pad, pad_rx) = mpsc::channel(64);
    let (quit, quit_rx) = mpsc::channel(4);
    let opts = crate::common::app::simulated_options(model);
    let app = tokio::spawn(async move {
        let mut terminal = Terminal::new(TestBackend::new(80, 24)).unwrap();
        let inputs = AppInputs {
            term: term_rx,
            pad: pad_rx,
            quit: quit_rx,
        };
        run::run(&mut terminal, session, opts, inputs, no_draw)
            .await
            .unwrap()
    });
    sleep(Duration::from_secs(2)).await;
    Harness {
        term,
        pad,
        quit,
        probe,
        packets,
        app,
    }
}

impl Harness {
    async fn key(&self, k: Key) {
        for kind in [KeyKind::Press, KeyKind::Release] {
            self.term
                .send(TermEvent::Key { key: k, kind })
                .await
                .unwrap();
        }
        sleep(Duration::from_millis(20)).await;
    }

    async fn typed(&self, text: &str) {
        for c in text.chars() {
            self.key(Key::ch(c)).await;
        }
    }

    /// Commands sent with this DID/CID: (target, payload).
    fn sent(&self, did: u8, cid: u8) -> Vec<(Option<u8>, Vec<u8>)> {
        self.packets
            .lock()
            .unwrap()
            .iter()
            .filter(|(d, p)| *d == Direction::Out && (p.did, p.cid) == (did, cid))
            .map(|(_, p)| (p.tid, p.data.clone()))
            .collect()
    }

    /// Whether the robot answered a command with this DID/CID with success, or sent the
    /// notification.
    fn answered(&self, did: u8, cid: u8) -> bool {
        self.packets.lock().unwrap().iter().any(|(d, p)| {
            *d == Direction::In
                && (p.did, p.cid) == (did, cid)
                && p.err.is_none_or(|e| e.is_success())
        })
    }

    async fn quit(self) {
        self.quit.send("test".into()).await.unwrap();
        self.app.await.unwrap();
    }
}

#[tokio::test(start_paused = true)]
async fn rvr_tank_mode_drives_a_track_per_stick_and_stops() {
    let h = start(Model::Rvr).await;
    h.pad
        .send(PadEvent::Connected("Test Pad".into()))
        .await
        .unwrap();
    h.key(Key::ch('v')).await;
    let yaw0 = h.probe.state().yaw_deg;
    // Left stick forward, right stick back: the RVR spins in place.
    h.pad.send(PadEvent::Axis(Axis::LeftY, 1.0)).await.unwrap();
    h.pad
        .send(PadEvent::Axis(Axis::RightY, -1.0))
        .await
        .unwrap();
    sleep(Duration::from_secs(1)).await;
    let raw = h.sent(0x16, 0x01);
    let (target, data) = raw.last().expect("raw motors sent").clone();
    assert_eq!(target, Some(0x12), "to the secondary processor");
    assert_eq!(
        (data[0], data[2]),
        (1, 2),
        "left forward, right reverse: {data:?}"
    );
    assert!(data[1] > 100 && data[3] > 100, "{data:?}");
    assert!(h.answered(0x16, 0x01));
    let st = h.probe.state();
    let turned = (st.yaw_deg - yaw0).rem_euclid(360.0);
    assert!(
        turned > 20.0 && turned < 340.0,
        "it spun: {yaw0} → {}",
        st.yaw_deg
    );
    assert!(st.x_cm.hypot(st.y_cm) < 15.0, "in place: {st:?}");
    // Sticks rest: both tracks stop (the deadman).
    h.pad.send(PadEvent::Axis(Axis::LeftY, 0.0)).await.unwrap();
    h.pad.send(PadEvent::Axis(Axis::RightY, 0.0)).await.unwrap();
    sleep(Duration::from_millis(500)).await;
    let (_, data) = h.sent(0x16, 0x01).last().cloned().unwrap();
    assert_eq!((data[1], data[3]), (0, 0), "{data:?}");
    sleep(Duration::from_millis(500)).await;
    assert_eq!(h.probe.state().velocity_cm_s, 0.0);
    // The streaming service reports the RVR's yaw through its tokens.
    assert!(h.answered(0x18, 0x3D), "streaming-service data arrived");
    h.quit().await;
}

#[tokio::test(start_paused = true)]
async fn bolt_matrix_prompt_scrolls_text_draws_a_character_and_the_compass_calibrates() {
    let h = start(Model::Bolt).await;
    h.key(Key::ch('i')).await;
    h.typed("HI").await;
    h.key(Key::plain(KeyCode::Enter)).await;
    sleep(Duration::from_millis(300)).await;
    let text = h.sent(0x1A, 0x3B);
    assert_eq!(text.len(), 1, "{text:?}");
    assert_eq!(text[0].0, Some(0x12), "the matrix is the secondary's");
    assert!(text[0].1.ends_with(b"HI\0"), "{:?}", text[0].1);
    // Text done: the robot says so.
    sleep(Duration::from_secs(3)).await;
    assert!(h.answered(0x1A, 0x3C), "text-scrolling done notification");
    // The colour key redraws in the next colour; a single character is drawn.
    h.key(Key::ch('i')).await;
    h.typed("A").await;
    h.key(Key::plain(KeyCode::Enter)).await;
    h.key(Key::ch('k')).await;
    sleep(Duration::from_millis(500)).await;
    let chars = h.sent(0x1A, 0x42);
    assert_eq!(chars.len(), 2, "{chars:?}");
    assert_eq!(chars[0].1, vec![255, 0, 0, b'A']);
    assert_eq!(chars[1].1, vec![0, 255, 0, b'A'], "redrawn in green");
    assert!(h.answered(0x1A, 0x42));
    h.key(Key::ch('N')).await;
    sleep(Duration::from_millis(500)).await;
    assert_eq!(h.sent(0x18, 0x25).len(), 1);
    assert!(h.answered(0x18, 0x26), "north reported");
    h.quit().await;
}

#[tokio::test(start_paused = true)]
async fn mini_drives_by_heading_like_bb8() {
    let h = start(Model::Mini).await;
    h.term
        .send(TermEvent::Key {
            key: Key::ch('w'),
            kind: KeyKind::Press,
        })
        .await
        .unwrap();
    sleep(Duration::from_secs(1)).await;
    h.term
        .send(TermEvent::Key {
            key: Key::ch('w'),
            kind: KeyKind::Release,
        })
        .await
        .unwrap();
    sleep(Duration::from_secs(1)).await;
    let drives = h.sent(0x16, 0x07);
    assert!(
        drives.iter().all(|(t, _)| t.is_none()),
        "one processor: no target"
    );
    assert!(drives.iter().any(|(_, d)| d[0] > 0));
    assert_eq!(drives.last().unwrap().1[0], 0, "stopped on release");
    assert!(h.probe.state().y_cm > 20.0, "{:?}", h.probe.state());
    h.quit().await;
}

/// RVR's raw motors in the log: each command once and before its response (a report had
/// `set-raw-motors` and its response twice and out of order in the app's packet log, which
/// is this session log, seen through the app).
#[tokio::test(start_paused = true)]
async fn rvr_raw_motors_are_logged_once_each_and_before_their_response() {
    let h = start(Model::Rvr).await;
    h.key(Key::ch('v')).await;
    let up = |kind| TermEvent::Key {
        key: Key::plain(KeyCode::Up),
        kind,
    };
    h.term.send(up(KeyKind::Press)).await.unwrap();
    sleep(Duration::from_millis(800)).await;
    h.term.send(up(KeyKind::Release)).await.unwrap();
    sleep(Duration::from_millis(500)).await;
    h.key(Key::ch(' ')).await;
    sleep(Duration::from_millis(500)).await;
    let packets = h.packets.lock().unwrap().clone();
    let raw: Vec<(Direction, u8)> = packets
        .iter()
        .filter(|(_, p)| (p.did, p.cid) == (0x16, 0x01))
        .map(|(d, p)| (*d, p.seq))
        .collect();
    let outs: Vec<u8> = raw
        .iter()
        .filter(|(d, _)| *d == Direction::Out)
        .map(|(_, s)| *s)
        .collect();
    assert!(outs.len() >= 3, "tank mode drove: {raw:?}");
    for seq in &outs {
        let at = |dir: Direction| {
            raw.iter()
                .enumerate()
                .filter(|(_, (d, s))| *d == dir && s == seq)
                .map(|(i, _)| i)
                .collect::<Vec<_>>()
        };
        let (sent, answered) = (at(Direction::Out), at(Direction::In));
        assert_eq!(sent.len(), 1, "seq {seq} sent once: {raw:?}");
        assert_eq!(answered.len(), 1, "seq {seq} answered once: {raw:?}");
        assert!(
            sent[0] < answered[0],
            "seq {seq} before its answer: {raw:?}"
        );
    }
    h.quit().await;
}
