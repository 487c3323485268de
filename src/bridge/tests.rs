//! The bridge on simulated droids under paused time: the command timeout, e-stop, the
//! capabilities a robot lacks, replies and errors, stdin's end; and the schema's parser
//! under property tests.

use super::schema::{self, ErrorCode, Out};
use super::*;
use crate::family::setup::{SetupOptions, connect_setup};
use crate::fleet::DroidSpec;
use crate::session::{Direction, LinkState, LogItem, SessionConfig};
use crate::sim::{Faults, SimConfig, SimLink};
use proptest::prelude::*;
use tokio::time::{Instant, sleep};

use crate::family::drive_speed;

/// A droid's drive writes: when (since the rig started) and the speed.
type Writes = Arc<Mutex<Vec<(Duration, u8)>>>;

/// Every packet written to a droid: when (since the rig started) and its catalogue label.
type Labels = Arc<Mutex<Vec<(Duration, String)>>>;

/// Simulated droids in a bridge, each connected; the drive writes of each droid (time since
/// the bridge started, speed) are collected.
pub(super) struct Rig {
    pub(super) bridge: Arc<Bridge>,
    pub(super) rx: outbox::Outputs,
    writes: Vec<Writes>,
    labels: Vec<Labels>,
    pub(super) start: Instant,
}

/// How the rig's droids are made, beyond their models.
#[derive(Default)]
pub(super) struct RigOptions {
    /// Each droid's faults (none when absent).
    pub(super) faults: Vec<Faults>,
    /// The sessions' reconnect backoff (the session's default when absent).
    pub(super) backoff: Option<crate::link::backoff::Backoff>,
    /// Each droid's name (the simulator's when absent).
    pub(super) names: Vec<String>,
    /// The bridge's telemetry rate (the default's when absent).
    pub(super) telemetry_hz: Option<u16>,
}

pub(super) async fn rig(models: &[Model], timeout_ms: u64) -> Rig {
    rig_with(models, timeout_ms, RigOptions::default()).await
}

pub(super) async fn rig_with(models: &[Model], timeout_ms: u64, o: RigOptions) -> Rig {
    let specs = models
        .iter()
        .enumerate()
        .map(|(i, &m)| DroidSpec {
            name: o
                .names
                .get(i)
                .cloned()
                .unwrap_or_else(|| crate::relay::sim_backend::sim_name(m, i)),
            model: m,
            link: Box::new(SimLink::new(
                m,
                SimConfig::for_model(m),
                o.faults.get(i).cloned().unwrap_or_else(Faults::none),
            )),
            session: SessionConfig {
                family: m.protocol(),
                model: Some(m),
                pacing: m.write_pacing(),
                setup: connect_setup(m, &SetupOptions::default()),
                backoff: o.backoff.unwrap_or_default(),
                ..SessionConfig::default()
            },
            origin: "simulated".into(),
            room_origin: None,
        })
        .collect();
    let fleet = Fleet::start(specs);
    let start = Instant::now();
    let mut writes = Vec::new();
    let mut labels = Vec::new();
    for m in fleet.members() {
        let w = Arc::new(Mutex::new(Vec::new()));
        let l = Arc::new(Mutex::new(Vec::new()));
        let mut log = m.session.subscribe_log();
        let (sink, names) = (w.clone(), l.clone());
        tokio::spawn(async move {
            while let Ok(e) = log.recv().await {
                if e.dir == Direction::Out
                    && let LogItem::Packet { packet, explained } = &e.item
                {
                    lock(&names).push((start.elapsed(), explained.label.clone()));
                    if let Some(s) = drive_speed(packet) {
                        lock(&sink).push((start.elapsed(), s));
                    }
                }
            }
        });
        writes.push(w);
        labels.push(l);
    }
    for i in 0..fleet.len() {
        let mut st = fleet.link_state(i).unwrap();
        let _ = st.wait_for(|s| *s == LinkState::Connected).await;
    }
    let settings = Settings {
        command_timeout: Duration::from_millis(timeout_ms),
        telemetry_hz: o.telemetry_hz.unwrap_or(Settings::default().telemetry_hz),
        ..Settings::default()
    };
    let setups = vec![SetupOptions::default(); fleet.len()];
    let (bridge, rx) = Bridge::start(fleet, setups, settings);
    Rig {
        bridge,
        rx,
        writes,
        labels,
        start,
    }
}

impl Rig {
    pub(super) fn send(&self, line: &str) {
        self.bridge.handle(line.as_bytes(), None);
    }

    /// Every object out so far, but telemetry, battery and link states.
    pub(super) fn said(&mut self) -> Vec<Out> {
        let mut out = Vec::new();
        while let Ok(o) = self.rx.try_recv() {
            if !matches!(
                o,
                Out::Telemetry { .. } | Out::Battery { .. } | Out::Link { .. }
            ) {
                out.push(o);
            }
        }
        out
    }

    pub(super) fn writes(&self, i: usize) -> Vec<(Duration, u8)> {
        lock(&self.writes[i]).clone()
    }

    /// The labels of the packets written to droid `i`.
    pub(super) fn labels(&self, i: usize) -> Vec<(Duration, String)> {
        lock(&self.labels[i]).clone()
    }

    pub(super) fn now(&self) -> Duration {
        self.start.elapsed()
    }
}

pub(super) async fn run_for(ms: u64) {
    let end = Instant::now() + Duration::from_millis(ms);
    while Instant::now() < end {
        sleep(Duration::from_millis(10)).await;
    }
}

#[tokio::test(start_paused = true)]
async fn a_droid_with_no_drive_for_the_timeout_is_stopped_once() {
    let mut r = rig(&[Model::R2D2], 600).await;
    run_for(500).await;
    let t0 = r.now();
    r.send(r#"{"v":1,"cmd":"drive","speed":100,"heading":90}"#);
    run_for(550).await;
    let w = r.writes(0);
    assert!(
        w.iter().any(|(t, s)| *t >= t0 && *s == 100),
        "the drive went out: {w:?}"
    );
    assert!(
        !w.iter().any(|(t, s)| *t >= t0 && *s == 0),
        "no stop before the timeout: {w:?}"
    );
    assert!(r.said().is_empty());
    run_for(300).await;
    let w = r.writes(0);
    let stop = w
        .iter()
        .find(|(t, s)| *t >= t0 && *s == 0)
        .map(|(t, _)| *t - t0)
        .expect("a stop after the timeout");
    assert!(
        stop >= Duration::from_millis(600) && stop <= Duration::from_millis(600 + 50 + 130),
        "stopped {stop:?} after the last drive (timeout 600 ms, a tick, the pacing)"
    );
    let said = r.said();
    assert!(
        matches!(&said[..], [Out::Stopped { droid, reason: "timeout", .. }] if droid == "D2-0001"),
        "{said:?}"
    );
    run_for(2000).await;
    assert!(r.said().is_empty(), "stopped once");
    let w = r.writes(0);
    assert!(
        w.iter()
            .filter(|(t, _)| *t > t0 + stop)
            .all(|(_, s)| *s == 0),
        "nothing drives it after the stop: {w:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn drives_within_the_timeout_keep_it_rolling_with_heartbeats() {
    let mut r = rig(&[Model::BB8], 600).await;
    let t0 = r.now();
    for _ in 0..10 {
        r.send(r#"{"v":1,"cmd":"drive","speed":80,"heading":0}"#);
        run_for(400).await;
    }
    assert!(r.said().is_empty(), "no timeout while drives come");
    let w: Vec<_> = r.writes(0).into_iter().filter(|(t, _)| *t >= t0).collect();
    assert!(w.iter().all(|(_, s)| *s == 80), "{w:?}");
    // Then one drive and a longer timeout: the held drive is re-sent within the droid's
    // own 2 s fail-safe.
    let mut r = rig(&[Model::R2D2], 3000).await;
    let t0 = r.now();
    r.send(r#"{"v":1,"cmd":"drive","speed":60,"heading":0}"#);
    run_for(2900).await;
    let w: Vec<_> = r.writes(0).into_iter().filter(|(t, _)| *t >= t0).collect();
    assert!(w.len() >= 5, "re-sent on the heartbeat: {w:?}");
    assert!(w.iter().all(|(_, s)| *s == 60), "{w:?}");
    run_for(300).await;
    assert!(matches!(&r.said()[..], [Out::Stopped { .. }]));
}

#[tokio::test(start_paused = true)]
async fn estop_stops_every_droid_and_drops_what_was_held() {
    let mut r = rig(&[Model::R2D2, Model::BB8, Model::Robi42], 5000).await;
    r.send(r#"{"v":1,"cmd":"drive","droid":"D2-0001","speed":120,"heading":0}"#);
    r.send(r#"{"v":1,"cmd":"drive","droid":"bb8","speed":120,"heading":180}"#);
    r.send(r#"{"v":1,"cmd":"twist","droid":"robi","linear":0.2,"angular":0.0}"#);
    run_for(300).await;
    let t0 = r.now();
    r.send(r#"{"v":1,"cmd":"estop","id":"e1"}"#);
    run_for(400).await;
    for i in 0..3 {
        let w = r.writes(i);
        assert!(
            w.iter().any(|(t, s)| *t >= t0 && *s == 0),
            "droid {i} stopped: {w:?}"
        );
    }
    let said = r.said();
    assert!(
        matches!(&said[..], [Out::Reply { id, cmd: "estop", ok: true, .. }] if id == "e1"),
        "{said:?}"
    );
    // Nothing held: no heartbeat drives them again, and no timeout fires later.
    run_for(6000).await;
    for i in 0..3 {
        let w = r.writes(i);
        assert!(
            w.iter().filter(|(t, _)| *t > t0).all(|(_, s)| *s == 0),
            "droid {i}: {w:?}"
        );
    }
    assert!(r.said().is_empty());
}

fn unsupported(line: &str, said: &[Out]) -> (String, &'static str, &'static str) {
    match said {
        [
            Out::Error {
                code: ErrorCode::Unsupported,
                robot: Some(robot),
                capability: Some(cap),
                error,
                ..
            },
        ] => (error.clone(), robot, cap),
        other => panic!("{line}: expected one unsupported error, got {other:?}"),
    }
}

#[tokio::test(start_paused = true)]
async fn a_command_a_robot_cannot_do_names_the_robot_and_the_capability() {
    let mut r = rig(&[Model::R2D2, Model::BB8, Model::Robi42, Model::Bolt], 600).await;
    let cases = [
        (
            r#"{"v":1,"cmd":"head","droid":"BB-0002","angle":30}"#,
            "BB-8",
            "dome",
        ),
        (
            r#"{"v":1,"cmd":"stance","droid":"bb8","stance":"bipod"}"#,
            "BB-8",
            "legs",
        ),
        (
            r#"{"v":1,"cmd":"matrix","droid":"D2-0001","op":"fill","rgb":[0,0,255]}"#,
            "R2-D2",
            "matrix",
        ),
        (
            r#"{"v":1,"cmd":"lights","droid":"robi","group":"front","rgb":[255,0,0]}"#,
            "Robi 42",
            "lights",
        ),
        (
            r#"{"v":1,"cmd":"lights","droid":"BB-0002","group":"logic","brightness":9}"#,
            "BB-8",
            "lights",
        ),
        (
            r#"{"v":1,"cmd":"stream","droid":"robi","rate_hz":10}"#,
            "Robi 42",
            "streaming",
        ),
        (
            r#"{"v":1,"cmd":"twist","droid":"robi","linear":-0.1,"angular":0}"#,
            "Robi 42",
            "reverse",
        ),
        (
            r#"{"v":1,"cmd":"sound","droid":"robi","sound":1}"#,
            "Robi 42",
            "sounds",
        ),
        (
            r#"{"v":1,"cmd":"animation","droid":"robi","animation":1}"#,
            "Robi 42",
            "animations",
        ),
        (
            r#"{"v":1,"cmd":"head","droid":"bolt","angle":10}"#,
            "Sphero BOLT",
            "dome",
        ),
    ];
    for (line, robot, cap) in cases {
        r.send(line);
        let (error, got_robot, got_cap) = unsupported(line, &r.said());
        assert_eq!((got_robot, got_cap), (robot, cap), "{line}");
        assert!(error.starts_with(robot), "{line}: {error}");
    }
    // What they can do works and replies.
    r.send(r#"{"v":1,"cmd":"matrix","droid":"bolt","op":"fill","rgb":[0,0,255],"id":7}"#);
    r.send(r#"{"v":1,"cmd":"head","droid":"D2-0001","angle":-45,"id":8}"#);
    r.send(r#"{"v":1,"cmd":"lights","droid":"D2-0001","group":"logic","brightness":200,"id":9}"#);
    r.send(r#"{"v":1,"cmd":"sound","droid":"D2-0001","sound":3,"id":10}"#);
    run_for(2000).await;
    let mut ids: Vec<_> = r
        .said()
        .into_iter()
        .filter_map(|o| match o {
            Out::Reply { id, ok: true, .. } => Some(id),
            // The sound, said played once the droid answered it (issue 40 point 5).
            Out::Played {
                what: "sound",
                id: 3,
                ..
            } => None,
            other => panic!("{other:?}"),
        })
        .collect();
    ids.sort_by_key(|v| v.as_i64());
    assert_eq!(ids, [7, 8, 9, 10]);
}

#[tokio::test(start_paused = true)]
async fn bad_commands_get_one_error_and_change_nothing() {
    let mut r = rig(&[Model::R2D2, Model::BB8], 600).await;
    let t0 = r.now();
    for (line, code) in [
        ("not json", ErrorCode::BadJson),
        ("[1,2]", ErrorCode::BadJson),
        (r#"{"cmd":"stop"}"#, ErrorCode::BadVersion),
        (r#"{"v":2,"cmd":"stop"}"#, ErrorCode::BadVersion),
        (r#"{"v":1,"cmd":"fly"}"#, ErrorCode::UnknownCmd),
        (
            r#"{"v":1,"cmd":"drive","droid":"D2-0001","speed":300,"heading":0}"#,
            ErrorCode::BadField,
        ),
        (
            r#"{"v":1,"cmd":"drive","droid":"D2-0001","speed":30}"#,
            ErrorCode::BadField,
        ),
        (
            r#"{"v":1,"cmd":"drive","droid":"D2-0001","sped":30,"heading":0}"#,
            ErrorCode::BadField,
        ),
        (
            r#"{"v":1,"cmd":"drive","speed":30,"heading":0}"#,
            ErrorCode::NoSuchDroid,
        ),
        (
            r#"{"v":1,"cmd":"drive","droid":"C-3PO","speed":30,"heading":0}"#,
            ErrorCode::NoSuchDroid,
        ),
    ] {
        r.send(line);
        let said = r.said();
        assert!(
            matches!(&said[..], [Out::Error { code: c, .. }] if *c == code),
            "{line}: {said:?}"
        );
    }
    // The id of a refused command is echoed.
    r.send(r#"{"v":1,"cmd":"drive","id":"x","droid":"D2-0001","speed":-1,"heading":0}"#);
    assert!(matches!(&r.said()[..], [Out::Error { id: Some(id), .. }] if id == "x"));
    run_for(1000).await;
    for i in 0..2 {
        let w = r.writes(i);
        assert!(w.iter().all(|(t, _)| *t < t0), "nothing was driven: {w:?}");
    }
}

#[tokio::test(start_paused = true)]
async fn a_twist_turns_the_heading_at_its_yaw_rate() {
    let mut r = rig(&[Model::R2D2], 600).await;
    // 0.4 m/s, 90°/s to the left, for 1 s: heading 0 → 270.
    for _ in 0..10 {
        r.send(r#"{"v":1,"cmd":"twist","linear":0.4,"angular":1.5707964}"#);
        run_for(100).await;
    }
    let h = r.bridge.droids[0].lock().holder.heading();
    assert!((265..=275).contains(&h), "heading {h}");
    let w = r.writes(0);
    assert!(
        w.iter().any(|(_, s)| *s == 64),
        "0.4 m/s of 1.6 at 255: {w:?}"
    );
    r.send(r#"{"v":1,"cmd":"stop","id":1}"#);
    assert!(matches!(&r.said()[..], [Out::Reply { cmd: "stop", .. }]));
}

#[tokio::test(start_paused = true)]
async fn stdin_ending_stops_the_droids_it_drove() {
    let r = rig(&[Model::R2D2, Model::BB8], 5000).await;
    let (mut client, server) = tokio::io::duplex(64 * 1024);
    let (server_in, server_out) = tokio::io::split(server);
    let bridge = r.bridge.clone();
    let task = tokio::spawn(stdio::run(
        bridge,
        r.rx,
        tokio::io::BufReader::new(server_in),
        server_out,
        std::future::pending(),
    ));
    use tokio::io::{AsyncBufReadExt, AsyncWriteExt};
    client
        .write_all(b"{\"v\":1,\"cmd\":\"drive\",\"droid\":\"BB-0002\",\"speed\":90,\"heading\":0}\n\n   \nnope\n")
        .await
        .unwrap();
    run_for(300).await;
    let t0 = r.start.elapsed();
    client.shutdown().await.unwrap();
    let end = task.await.unwrap();
    assert_eq!(end, stdio::End::InputClosed);
    let mut lines = Vec::new();
    let mut reader = tokio::io::BufReader::new(client);
    let mut l = String::new();
    while reader.read_line(&mut l).await.unwrap() > 0 {
        lines.push(std::mem::take(&mut l));
    }
    let kinds: Vec<String> = lines
        .iter()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            assert_eq!(v["v"], 1, "{l}");
            v["type"].as_str().unwrap().to_string()
        })
        .filter(|t| t != "telemetry" && t != "link" && t != "battery")
        .collect();
    assert_eq!(kinds, ["hello", "error", "stopped"], "{lines:?}");
    assert!(
        lines
            .iter()
            .any(|l| l.contains("\"input_closed\"") && l.contains("BB-0002"))
    );
    let w = r.writes[1].lock().unwrap().clone();
    assert!(
        w.iter().any(|(t, s)| *t >= t0 && *s == 0),
        "BB-8 stopped: {w:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn a_line_too_long_is_refused_without_being_kept() {
    let mut input: &[u8] = b"0123456789abcdef\nshort\nlast";
    let mut line = Vec::new();
    let r = stdio::read_line(&mut input, 8, &mut line).await.unwrap();
    assert_eq!(r, Some(Err(16)));
    assert!(line.len() <= 8);
    assert_eq!(
        stdio::read_line(&mut input, 8, &mut line).await.unwrap(),
        Some(Ok(()))
    );
    assert_eq!(line, b"short");
    assert_eq!(
        stdio::read_line(&mut input, 8, &mut line).await.unwrap(),
        Some(Ok(()))
    );
    assert_eq!(line, b"last");
    assert_eq!(
        stdio::read_line(&mut input, 8, &mut line).await.unwrap(),
        None
    );
}

#[test]
fn out_objects_carry_the_version_and_type_first() {
    let o = Out::Stopped {
        droid: "D2-0001".into(),
        reason: "timeout",
        message: "m".into(),
    };
    assert!(
        o.to_json()
            .starts_with(r#"{"v":1,"type":"stopped","droid":"D2-0001""#)
    );
    assert_eq!(topic_name("Robi 42"), "Robi-42");
    assert_eq!(topic_name("a/b+#"), "a-b--");
}

/// Generated valid commands.
fn command() -> impl Strategy<Value = String> {
    let droid = prop_oneof![
        Just(String::new()),
        Just(r#","droid":"D2-0001""#.to_string())
    ];
    let id = prop_oneof![
        Just(String::new()),
        (0i64..1_000_000).prop_map(|n| format!(r#","id":{n}"#)),
        "[a-z0-9]{1,12}".prop_map(|s| format!(r#","id":"{s}""#)),
    ];
    let verb = prop_oneof![
        (0u16..=255, 0u16..=359)
            .prop_map(|(s, h)| format!(r#""cmd":"drive","speed":{s},"heading":{h}"#)),
        (-5.0f64..5.0, -20.0f64..20.0)
            .prop_map(|(l, a)| format!(r#""cmd":"twist","linear":{l},"angular":{a}"#)),
        Just(r#""cmd":"stop""#.to_string()),
        Just(r#""cmd":"estop""#.to_string()),
        (-160i32..=180).prop_map(|a| format!(r#""cmd":"head","angle":{a}"#)),
        prop_oneof![Just("tripod"), Just("bipod"), Just("waddle"), Just("stop")]
            .prop_map(|s| format!(r#""cmd":"stance","stance":"{s}""#)),
        (0u16..=255, 0u16..=255, 0u16..=255)
            .prop_map(|(r, g, b)| format!(r#""cmd":"lights","group":"front","rgb":[{r},{g},{b}]"#)),
        (0u16..=255).prop_map(|b| format!(r#""cmd":"lights","group":"holo","brightness":{b}"#)),
        (0u16..100).prop_map(|n| format!(r#""cmd":"animation","animation":{n}"#)),
        (0u16..100).prop_map(|n| format!(r#""cmd":"sound","sound":{n}"#)),
        "[A-Za-z0-9 !]{1,25}".prop_map(|t| format!(r#""cmd":"matrix","op":"text","text":"{t}""#)),
        (0u8..8, 0u8..8).prop_map(|(x, y)| format!(
            r#""cmd":"matrix","op":"pixel","x":{x},"y":{y},"rgb":[1,2,3]"#
        )),
        (0u16..=100)
            .prop_map(|r| format!(r#""cmd":"stream","rate_hz":{r},"sensors":["attitude","gyro"]"#)),
    ];
    (verb, droid, id).prop_map(|(v, d, i)| format!(r#"{{"v":1,{v}{d}{i}}}"#))
}

proptest! {
    #[test]
    fn any_bytes_parse_or_are_refused_without_panicking(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = schema::parse(&bytes);
    }

    #[test]
    fn any_json_object_parses_or_is_refused_with_a_message(
        keys in proptest::collection::vec(prop_oneof![
            Just("v"), Just("cmd"), Just("speed"), Just("heading"), Just("droid"), Just("id"),
            Just("rgb"), Just("op"), Just("group"), Just("x")
        ], 0..6),
        vals in proptest::collection::vec(prop_oneof![
            Just("1".to_string()), Just("\"drive\"".to_string()), Just("-3".to_string()),
            Just("1e308".to_string()), Just("[1,2,3]".to_string()), Just("null".to_string()),
            Just("\"fill\"".to_string()), Just("{}".to_string()),
        ], 6),
    ) {
        let body: Vec<String> = keys.iter().zip(&vals).map(|(k, v)| format!("\"{k}\":{v}")).collect();
        let text = format!("{{{}}}", body.join(","));
        if let Err(e) = schema::parse(text.as_bytes()) {
            prop_assert!(!e.message.is_empty());
        }
    }

    #[test]
    fn generated_commands_parse(line in command()) {
        let r = schema::parse(line.as_bytes());
        prop_assert!(r.is_ok(), "{}: {:?}", line, r);
        let r = r.unwrap();
        let verb = format!("\"cmd\":\"{}\"", r.cmd.verb());
        prop_assert!(line.contains(&verb), "{} parsed as {:?}", line, r.cmd);
        prop_assert_eq!(r.droid.is_some(), line.contains("droid"));
        prop_assert_eq!(r.id.is_some(), line.contains("\"id\""));
    }
}

/// Every refusal of a dome angle names the dome's own range, whatever side it is past.
#[test]
fn a_dome_angle_out_of_range_names_one_range() {
    for angle in ["-170", "-190", "200", "1e300", "\"x\""] {
        let line = format!(r#"{{"v":1,"cmd":"head","angle":{angle}}}"#);
        let e = schema::parse(line.as_bytes()).expect_err(&line);
        assert!(e.message.contains("-160..=180"), "{line}: {}", e.message);
        assert!(!e.message.contains("-180"), "{line}: {}", e.message);
    }
    assert!(schema::parse(br#"{"v":1,"cmd":"head","angle":-160}"#).is_ok());
}

/// The bridge's capabilities, read from the model table, agree with what each family can
/// build for the model (the probe `capabilities` used to make with dummy commands).
#[test]
fn capabilities_agree_with_the_families() {
    use crate::script::{Action, LedGroup};
    for model in Model::ALL {
        let family = crate::family::for_model(model);
        let lights = [
            LedGroup::Front,
            LedGroup::Back,
            LedGroup::Logic,
            LedGroup::Holo,
        ]
        .iter()
        .any(|g| family.led(model, &Action::LedRgb(*g, [0, 0, 0])).is_some());
        let probed: Vec<&str> = [
            ("dome", model.has_dome()),
            ("legs", model.has_legs()),
            ("lights", lights),
            ("animations", family.animation(model, 0).is_some()),
            ("sounds", family.sound(model, 0).is_some()),
            ("matrix", model.has_matrix()),
            ("screen", model.has_screen()),
            ("streaming", family.stream_caps(model).is_some()),
            ("reverse", family.can_reverse()),
        ]
        .into_iter()
        .filter_map(|(c, has)| has.then_some(c))
        .collect();
        assert_eq!(super::capabilities(model), probed, "{model:?}");
    }
}
