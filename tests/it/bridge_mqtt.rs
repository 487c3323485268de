//! `droidctl bridge --mqtt` through a real broker (issue 20 points 3 and 4): droidctl's own
//! broker, and mosquitto where it is installed (issue 28), on a free loopback port, simulated
//! droids behind the bridge, a rumqttc client as the outside client. Topics per droid, the
//! retained state and the last will, replies and errors, the command timeout, the broker
//! going away and coming back while the droids stay connected, a password, TLS; and
//! `--mqtt` without a URL, the bridge hosting its own broker.

use crate::common::bridge_proc;
use crate::common::mosquitto;

use bridge_proc::{BridgeProc, gather, interrupt, scratch, speed};
use mosquitto::{Broker, Kind, Sub, mosquitto_here, publish};
use serde_json::Value;
use std::process::Command;
use std::time::{Duration, Instant};

/// Every `state` received so far says `connected`: neither the droid's link nor the
/// bridge's connection to the broker went down.
fn stayed_connected(sub: &Sub) {
    let states: Vec<_> = sub
        .drain()
        .into_iter()
        .filter(|(t, _)| t.ends_with("/state"))
        .collect();
    assert!(
        states.iter().all(|(_, v)| v["state"] == "connected"),
        "a state changed: {states:?}"
    );
}

const DRIVE: &str = r#"{"v":1,"cmd":"drive","speed":120,"heading":90}"#;

#[test]
fn simulated_droids_through_droidctls_broker() {
    simulated_droids_through_a_real_broker(Kind::Embedded);
}

#[test]
fn simulated_droids_through_mosquitto() {
    if mosquitto_here() {
        simulated_droids_through_a_real_broker(Kind::Mosquitto);
    }
}

fn simulated_droids_through_a_real_broker(kind: Kind) {
    let dir = scratch(&format!("topics-{kind:?}"));
    let broker = Broker::start_kind(&dir, kind);
    let p = broker.port;
    let sub = Sub::start(p, "droidctl/#", &[]);
    let mut bridge = BridgeProc::start(
        &dir,
        &["--mqtt", &broker.url(), "--sim", "r2d2,bb8", "--rate", "10"],
    );
    // Each droid's retained state, then samples with values (the connect setup done).
    let states = ["D2-0001", "BB-0002"].map(|d| format!("droidctl/{d}/state"));
    sub.wait_all(15, &states, |v| v["v"] == 1 && v["state"] == "connected");
    let samples = ["D2-0001", "BB-0002"].map(|d| format!("droidctl/{d}/telemetry"));
    sub.wait_all(15, &samples, |v| v["x_cm"].is_number());
    // A late subscriber gets the retained state at once.
    let late = Sub::start(p, "droidctl/BB-0002/state", &[]);
    late.wait(3, "droidctl/BB-0002/state", |v| v["state"] == "connected");
    // Drive R2 for 2 s: its telemetry shows it rolling; BB-8's does not.
    for _ in 0..8 {
        assert!(publish(p, "droidctl/D2-0001/cmd", DRIVE, &[]));
        std::thread::sleep(Duration::from_millis(250));
    }
    let t = sub.wait(5, "droidctl/D2-0001/telemetry", |v| speed(v) > 20.0);
    assert_eq!(t["droid"], "D2-0001");
    let bb = sub.wait(5, "droidctl/BB-0002/telemetry", |_| true);
    assert!(speed(&bb) < 1.0, "{bb}");
    // Silence: the command timeout stops R2, said on its reply topic.
    let s = sub.wait(5, "droidctl/D2-0001/reply", |v| v["type"] == "stopped");
    assert_eq!(s["reason"], "timeout");
    // A command with an id is answered; one the robot cannot do names robot and capability.
    assert!(publish(
        p,
        "droidctl/D2-0001/cmd",
        r#"{"v":1,"cmd":"lights","group":"front","rgb":[255,0,0],"id":"red"}"#,
        &[]
    ));
    let r = sub.wait(5, "droidctl/D2-0001/reply", |v| v["type"] == "reply");
    assert_eq!(
        (r["id"].as_str(), r["cmd"].as_str()),
        (Some("red"), Some("lights"))
    );
    assert!(publish(
        p,
        "droidctl/BB-0002/cmd",
        r#"{"v":1,"cmd":"head","angle":30,"id":4}"#,
        &[]
    ));
    let e = sub.wait(5, "droidctl/BB-0002/reply", |v| v["type"] == "error");
    assert_eq!(
        (
            e["code"].as_str(),
            e["robot"].as_str(),
            e["capability"].as_str(),
            e["id"].as_u64()
        ),
        (Some("unsupported"), Some("BB-8"), Some("dome"), Some(4))
    );
    // A bad payload: one error, nothing else changes.
    assert!(publish(p, "droidctl/BB-0002/cmd", "drive fast", &[]));
    let e = sub.wait(5, "droidctl/BB-0002/reply", |v| v["type"] == "error");
    assert_eq!(e["code"], "bad_json");
    // The e-stop on any droid's topic stops every droid.
    for _ in 0..4 {
        assert!(publish(p, "droidctl/D2-0001/cmd", DRIVE, &[]));
        assert!(publish(p, "droidctl/BB-0002/cmd", DRIVE, &[]));
        std::thread::sleep(Duration::from_millis(200));
    }
    sub.wait(5, "droidctl/BB-0002/telemetry", |v| speed(v) > 20.0);
    assert!(publish(
        p,
        "droidctl/BB-0002/cmd",
        r#"{"v":1,"cmd":"estop","id":"all"}"#,
        &[]
    ));
    sub.wait(5, "droidctl/BB-0002/reply", |v| {
        v["type"] == "reply" && v["id"] == "all"
    });
    std::thread::sleep(Duration::from_millis(1500));
    let _ = sub.drain();
    for d in ["D2-0001", "BB-0002"] {
        let t = sub.wait(3, &format!("droidctl/{d}/telemetry"), |_| true);
        assert!(speed(&t) < 3.0, "{d} still rolls after the e-stop: {t}");
    }
    // The bridge dies: the broker sends each droid's last will.
    let _ = bridge.child.kill();
    let states = ["D2-0001", "BB-0002"].map(|d| format!("droidctl/{d}/state"));
    sub.wait_all(10, &states, |v| v["state"] == "offline");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn losing_droidctls_broker_stops_the_droid_and_keeps_its_link() {
    losing_the_broker_stops_the_droid_and_keeps_its_link(Kind::Embedded);
}

#[test]
fn losing_mosquitto_stops_the_droid_and_keeps_its_link() {
    if mosquitto_here() {
        losing_the_broker_stops_the_droid_and_keeps_its_link(Kind::Mosquitto);
    }
}

fn losing_the_broker_stops_the_droid_and_keeps_its_link(kind: Kind) {
    let dir = scratch(&format!("lost-{kind:?}"));
    let mut broker = Broker::start_kind(&dir, kind);
    let p = broker.port;
    let sub = Sub::start(p, "droidctl/#", &[]);
    // A long command timeout: only the broker's loss can stop the droid in this test.
    let bridge = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &broker.url(),
            "--sim",
            "r2d2",
            "--command-timeout",
            "10000",
        ],
    );
    sub.wait(15, "droidctl/D2-0001/state", |v| v["state"] == "connected");
    sub.wait(15, "droidctl/D2-0001/telemetry", |v| v["x_cm"].is_number());
    assert!(publish(
        p,
        "droidctl/D2-0001/cmd",
        r#"{"v":1,"cmd":"drive","speed":60,"heading":90}"#,
        &[]
    ));
    sub.wait(5, "droidctl/D2-0001/telemetry", |v| speed(v) > 10.0);
    drop(sub);
    broker.kill();
    std::thread::sleep(Duration::from_millis(2500));
    broker.restart();
    let sub = Sub::start(p, "droidctl/#", &[]);
    // Back: the retained state is made anew, and the droid's link never went down.
    let s = sub.wait(15, "droidctl/D2-0001/state", |_| true);
    assert_eq!(s["state"], "connected", "{s}");
    let a = sub.wait(5, "droidctl/D2-0001/telemetry", |_| true);
    std::thread::sleep(Duration::from_millis(1000));
    let b = sub.wait(5, "droidctl/D2-0001/telemetry", |_| true);
    assert!(speed(&b) < 2.0, "still rolling after the broker went: {b}");
    assert_eq!(a["x_cm"], b["x_cm"], "it moved: {a} {b}");
    let err = bridge.stderr();
    assert!(err.contains("lost the broker"), "{err}");
    assert!(err.contains("connected to the broker again"), "{err}");
    // Commands work again.
    assert!(publish(p, "droidctl/D2-0001/cmd", DRIVE, &[]));
    sub.wait(5, "droidctl/D2-0001/telemetry", |v| speed(v) > 10.0);
    stayed_connected(&sub);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn droidctls_broker_with_a_password() {
    a_broker_with_a_password(Kind::Embedded);
}

#[test]
fn mosquitto_with_a_password() {
    if mosquitto_here() {
        a_broker_with_a_password(Kind::Mosquitto);
    }
}

fn a_broker_with_a_password(kind: Kind) {
    let dir = scratch(&format!("password-{kind:?}"));
    let broker = match kind {
        Kind::Embedded => Broker::embedded(
            &dir,
            mosquitto::free_port(),
            droidctl::bridge::broker::Access {
                login: Some(("pupil".into(), "r2-d2".into())),
                ..Default::default()
            },
            false,
        ),
        Kind::Mosquitto => {
            let pw = dir.join("passwd");
            let ok = Command::new(mosquitto::program("mosquitto_passwd"))
                .args(["-c", "-b"])
                .arg(&pw)
                .args(["pupil", "r2-d2"])
                .status()
                .expect("mosquitto_passwd");
            assert!(ok.success());
            Broker::start_with(
                &dir,
                mosquitto::free_port(),
                &format!("allow_anonymous false\npassword_file {}\n", pw.display()),
            )
        }
    };
    let p = broker.port;
    std::fs::write(dir.join("wrong"), "c-3po\n").unwrap();
    let mut wrong = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &broker.url(),
            "--sim",
            "r2d2",
            "--username",
            "pupil",
            "--password-file",
        ],
    );
    // (--password-file needs its value: a usage error, status 2.)
    assert_eq!(wrong.wait(10), Some(2));
    let wrong_file = dir.join("wrong");
    let mut wrong = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &broker.url(),
            "--sim",
            "r2d2",
            "--username",
            "pupil",
            "--password-file",
            wrong_file.to_str().unwrap(),
        ],
    );
    assert_eq!(wrong.wait(20), Some(1));
    let err = wrong.stderr();
    assert!(err.contains("cannot connect to the broker at"), "{err}");
    let sub = Sub::start(p, "droidctl/#", &["-u", "pupil", "-P", "r2-d2"]);
    let url = format!("mqtt://pupil:r2-d2@127.0.0.1:{p}");
    let _right = BridgeProc::start(&dir, &["--mqtt", &url, "--sim", "bb8"]);
    sub.wait(15, "droidctl/BB-0001/state", |v| v["state"] == "connected");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn droidctls_broker_over_tls() {
    a_broker_over_tls(Kind::Embedded);
}

#[test]
fn mosquitto_over_tls() {
    if mosquitto_here() {
        a_broker_over_tls(Kind::Mosquitto);
    }
}

/// The test certificate (tests/fixtures/tls: a CA, and a certificate for 127.0.0.1 it
/// signed), so no `openssl` is needed to run this.
fn a_broker_over_tls(kind: Kind) {
    let dir = scratch(&format!("tls-{kind:?}"));
    let port = mosquitto::free_port();
    let broker = match kind {
        Kind::Embedded => Broker::embedded(&dir, port, Default::default(), true),
        Kind::Mosquitto => Broker::start_with(
            &dir,
            port,
            &format!(
                "allow_anonymous true\n{}",
                mosquitto::mosquitto_tls_config()
            ),
        ),
    };
    let p = broker.port;
    let ca = mosquitto::test_ca();
    let sub = Sub::start(p, "droidctl/#", &["--cafile", ca.to_str().unwrap()]);
    let url = format!("mqtts://127.0.0.1:{p}");
    let _bridge = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &url,
            "--ca-file",
            ca.to_str().unwrap(),
            "--sim",
            "r2d2",
        ],
    );
    sub.wait(15, "droidctl/D2-0001/state", |v| v["state"] == "connected");
    sub.wait(15, "droidctl/D2-0001/telemetry", |v| v["x_cm"].is_number());
    for _ in 0..8 {
        assert!(publish(
            p,
            "droidctl/D2-0001/cmd",
            DRIVE,
            &["--cafile", ca.to_str().unwrap()]
        ));
        std::thread::sleep(Duration::from_millis(250));
    }
    sub.wait(5, "droidctl/D2-0001/telemetry", |v| speed(v) > 10.0);
    // Without the CA, the broker's certificate is not trusted: refused, said.
    let mut untrusted = BridgeProc::start(&dir, &["--mqtt", &url, "--sim", "r2d2"]);
    assert_eq!(untrusted.wait(20), Some(1));
    assert!(
        untrusted.stderr().contains("cannot connect"),
        "{}",
        untrusted.stderr()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A payload too large for a command line, published (retained or not).
fn publish_file(port: u16, topic: &str, payload: &[u8], retain: bool) {
    assert!(
        mosquitto::publish_bytes(port, topic, payload, retain, &[]),
        "publish {} bytes",
        payload.len()
    );
}

/// A command padded to `size` bytes.
fn padded(size: usize) -> Vec<u8> {
    let mut p = br#"{"v":1,"cmd":"stop","pad":""#.to_vec();
    p.resize(size - 2, b'x');
    p.extend_from_slice(b"\"}");
    p
}

/// Issue 26 points 5 and 6: a retained command waiting on the broker never drives (said
/// once on the error topic and on stderr), and payloads over the command limit (6,000 and
/// 200,000 bytes, live and retained) are `bad_json` errors while the connection stays.
#[test]
fn a_retained_command_never_drives_and_a_large_payload_keeps_the_connection() {
    let dir = scratch("retained");
    let broker = Broker::start(&dir);
    let p = broker.port;
    let full = r#"{"v":1,"cmd":"drive","speed":255,"heading":90}"#;
    assert!(publish(p, "droidctl/BB-0001/cmd", full, &["-r"]));
    let sub = Sub::start(p, "droidctl/BB-0001/+", &[]);
    let bridge = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &broker.url(),
            "--sim",
            "bb8",
            "--command-timeout",
            "5000",
        ],
    );
    sub.wait(15, "droidctl/BB-0001/state", |v| v["state"] == "connected");
    let e = sub.wait(10, "droidctl/BB-0001/reply", |v| v["type"] == "error");
    assert_eq!(e["code"], "retained", "{e}");
    sub.wait(10, "droidctl/BB-0001/telemetry", |v| v["x_cm"].is_number());
    std::thread::sleep(Duration::from_millis(1500));
    for (_, v) in sub.drain() {
        assert!(speed(&v) < 1.0, "the retained drive drove: {v}");
    }
    // Large payloads: an error each, and the connection stays.
    publish_file(p, "droidctl/BB-0001/cmd", &padded(6000), false);
    let e = sub.wait(5, "droidctl/BB-0001/reply", |v| v["type"] == "error");
    assert_eq!(e["code"], "bad_json", "{e}");
    publish_file(p, "droidctl/BB-0001/cmd", &padded(200_000), false);
    let e = sub.wait(5, "droidctl/BB-0001/reply", |v| v["type"] == "error");
    assert_eq!(e["code"], "bad_json", "{e}");
    // A large retained one replaces the retained drive: ignored too, no loop.
    publish_file(p, "droidctl/BB-0001/cmd", &padded(6000), true);
    std::thread::sleep(Duration::from_millis(1500));
    // Live commands still work over the same connection.
    for _ in 0..6 {
        assert!(publish(p, "droidctl/BB-0001/cmd", DRIVE, &[]));
        std::thread::sleep(Duration::from_millis(250));
    }
    sub.wait(5, "droidctl/BB-0001/telemetry", |v| speed(v) > 10.0);
    stayed_connected(&sub);
    let err = bridge.stderr();
    assert!(!err.contains("lost the broker"), "{err}");
    assert_eq!(
        err.matches("retained message").count(),
        1,
        "said once: {err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 26 point 7 and issue 37 point 7: two bridges with the same client id are told so,
/// and neither ends: with a predictable `--client-id`, whoever takes the id over could
/// otherwise end a bridge at will. Each backs off after saying so.
#[test]
fn two_bridges_with_the_same_client_id_are_told_and_neither_ends() {
    let dir = scratch("clientid");
    let broker = Broker::start(&dir);
    let p = broker.port;
    let sub = Sub::start(p, "droidctl/#", &[]);
    let args = [
        "--mqtt",
        &broker.url(),
        "--sim",
        "r2d2",
        "--client-id",
        "room1",
    ];
    let mut a = BridgeProc::start(&dir, &args);
    sub.wait(15, "droidctl/D2-0001/state", |v| v["state"] == "connected");
    let mut b = BridgeProc::start(&dir, &args);
    let end = Instant::now() + Duration::from_secs(30);
    let told = |p: &BridgeProc| p.stderr().contains("same client id");
    while !(told(&a) || told(&b)) {
        assert!(
            Instant::now() < end,
            "nobody told: {}\n{}",
            a.stderr(),
            b.stderr()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    std::thread::sleep(Duration::from_secs(3));
    for bridge in [&mut a, &mut b] {
        assert!(
            bridge.child.try_wait().unwrap().is_none(),
            "a bridge ended: {}",
            bridge.stderr()
        );
    }
    let err = if told(&a) { a.stderr() } else { b.stderr() };
    assert!(
        err.contains("--client-id") && err.contains("Trying again"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 26 point 7: two robots with the same name (two Robi 42 behind relays, say; the
/// command line's `--sim` refuses that, so the bridge is made here) get topics of their own,
/// and what each reports goes to its own.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_droids_with_the_same_name_get_their_own_topics() {
    use droidctl::bridge::{Bridge, Settings, mqtt};
    use droidctl::model::Model;
    let dir = scratch("names");
    // The broker runs its own runtime: started (and dropped below) off this one's threads.
    let broker = tokio::task::block_in_place(|| Broker::start(&dir));
    let p = broker.port;
    let config = droidctl::config::Config::defaults();
    let models = [Model::Robi42, Model::Robi42];
    let specs = droidctl::cli::fleet::simulated(&models)
        .into_iter()
        .map(|f| {
            assert_eq!(f.name, "Robi 42");
            let s = droidctl::cli::fleet::session_config(f.model, &config, true);
            f.into_spec(s)
        })
        .collect();
    let fleet = droidctl::fleet::Fleet::start(specs);
    let setups = vec![Default::default(); 2];
    let (bridge, rx) = Bridge::start(fleet, setups, Settings::default());
    let settings = mqtt::MqttSettings {
        url: broker.url().parse().unwrap(),
        qos: 0,
        prefix: "droidctl".into(),
        client_id: mqtt::default_client_id(),
        bridge_id: "test".into(),
        keepalive: Duration::from_secs(5),
        username: None,
        password: None,
        ca_pem: None,
    };
    let running = tokio::spawn(mqtt::run(
        bridge.clone(),
        rx,
        settings,
        Duration::from_secs(10),
        std::future::pending(),
    ));
    tokio::task::spawn_blocking(move || {
        let sub = Sub::start(p, "droidctl/#", &[]);
        let states = ["Robi-42", "Robi-42-2"].map(|d| format!("droidctl/{d}/state"));
        sub.wait_all(15, &states, |v| v["state"] == "connected");
        let drive = r#"{"v":1,"cmd":"drive","speed":255,"heading":0}"#;
        for _ in 0..8 {
            assert!(publish(p, "droidctl/Robi-42-2/cmd", drive, &[]));
            std::thread::sleep(Duration::from_millis(250));
        }
        sub.wait(5, "droidctl/Robi-42-2/telemetry", |v| speed(v) > 5.0);
        let _ = sub.drain();
        let first = sub.wait(5, "droidctl/Robi-42/telemetry", |_| true);
        assert!(speed(&first) < 1.0, "the other Robi moved: {first}");
    })
    .await
    .unwrap();
    running.abort();
    bridge.shutdown().await;
    tokio::task::block_in_place(move || drop(broker));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--mqtt` without a URL: the bridge hosts droidctl's own broker (here on a free port with
/// `--listen`; 127.0.0.1:1883 without it), and other programs drive through it.
#[test]
fn the_bridge_hosts_its_own_broker() {
    let dir = scratch("own");
    let p = mosquitto::free_port();
    let listen = format!("127.0.0.1:{p}");
    let bridge = BridgeProc::start(&dir, &["--mqtt", "--listen", &listen, "--sim", "r2d2"]);
    let end = Instant::now() + Duration::from_secs(15);
    while std::net::TcpStream::connect(("127.0.0.1", p)).is_err() {
        assert!(Instant::now() < end, "no broker: {}", bridge.stderr());
        std::thread::sleep(Duration::from_millis(50));
    }
    let sub = Sub::start(p, "droidctl/#", &[]);
    sub.wait(15, "droidctl/D2-0001/state", |v| v["state"] == "connected");
    sub.wait(15, "droidctl/D2-0001/telemetry", |v| v["x_cm"].is_number());
    for _ in 0..8 {
        assert!(publish(p, "droidctl/D2-0001/cmd", DRIVE, &[]));
        std::thread::sleep(Duration::from_millis(250));
    }
    sub.wait(5, "droidctl/D2-0001/telemetry", |v| speed(v) > 20.0);
    let err = bridge.stderr();
    assert!(
        err.contains(&format!("MQTT broker (droidctl's own) on {listen}")),
        "{err}"
    );
    assert!(!err.contains("warning"), "loopback needs no warning: {err}");
}

/// Shared on the network with a password: the warning says who can drive; a client without
/// the password is refused, one with it drives.
#[test]
fn the_bridges_own_broker_shared_with_a_password() {
    let dir = scratch("own-shared");
    let p = mosquitto::free_port();
    let listen = format!("0.0.0.0:{p}");
    std::fs::write(dir.join("pw"), "r2-d2\n").unwrap();
    let pw = dir.join("pw");
    let bridge = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            "--listen",
            &listen,
            "--username",
            "pupil",
            "--password-file",
            pw.to_str().unwrap(),
            "--sim",
            "r2d2",
        ],
    );
    let end = Instant::now() + Duration::from_secs(15);
    while std::net::TcpStream::connect(("127.0.0.1", p)).is_err() {
        assert!(Instant::now() < end, "no broker: {}", bridge.stderr());
        std::thread::sleep(Duration::from_millis(50));
    }
    let sub = Sub::start(p, "droidctl/#", &["-u", "pupil", "-P", "r2-d2"]);
    sub.wait(15, "droidctl/D2-0001/state", |v| v["state"] == "connected");
    sub.wait(15, "droidctl/D2-0001/telemetry", |v| v["x_cm"].is_number());
    assert!(!publish(
        p,
        "droidctl/D2-0001/cmd",
        DRIVE,
        &["-u", "pupil", "-P", "c-3po"]
    ));
    for _ in 0..8 {
        let login = ["-u", "pupil", "-P", "r2-d2"];
        assert!(publish(p, "droidctl/D2-0001/cmd", DRIVE, &login));
        std::thread::sleep(Duration::from_millis(250));
    }
    sub.wait(5, "droidctl/D2-0001/telemetry", |v| speed(v) > 20.0);
    let err = bridge.stderr();
    assert!(
        err.contains("warning: MQTT broker listening on 0.0.0.0")
            && err.contains("drive your droids"),
        "{err}"
    );
    assert!(!err.contains("no password"), "{err}");
}

/// A broker already on the port: said, with what to do instead.
#[test]
fn the_bridges_own_broker_on_a_taken_port() {
    let dir = scratch("own-taken");
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let listen = taken.local_addr().unwrap().to_string();
    let mut bridge = BridgeProc::start(&dir, &["--mqtt", "--listen", &listen, "--sim", "r2d2"]);
    assert_eq!(bridge.wait(20), Some(1), "{}", bridge.stderr());
    let err = bridge.stderr();
    assert!(
        err.contains(&format!("cannot listen on {listen}")) && err.contains("--mqtt mqtt://"),
        "{err}"
    );
}

/// Issue 31 point 1: samples the bridge could not deliver while the broker was gone are
/// dropped, not replayed after it came back as if the droid were doing that now; the
/// `stopped` notice of the loss is delivered.
#[test]
fn telemetry_from_a_broker_outage_is_dropped_and_its_stop_delivered() {
    let dir = scratch("stale");
    let mut broker = Broker::start_kind(&dir, Kind::Embedded);
    let p = broker.port;
    let sub = Sub::start(p, "droidctl/#", &[]);
    let bridge = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &broker.url(),
            "--sim",
            "bb8",
            "--rate",
            "100",
            "--command-timeout",
            "10000",
        ],
    );
    let tel = "droidctl/BB-0001/telemetry";
    sub.wait(15, "droidctl/BB-0001/state", |v| v["ready"] == true);
    assert!(publish(p, "droidctl/BB-0001/cmd", DRIVE, &[]));
    sub.wait(5, tel, |v| speed(v) > 10.0);
    std::thread::sleep(Duration::from_millis(300));
    let before = sub
        .drain()
        .into_iter()
        .filter(|(t, _)| t == tel)
        .filter_map(|(_, v)| v["t_ms"].as_u64())
        .max()
        .expect("samples while driving");
    drop(sub);
    broker.kill();
    let outage = 2500;
    std::thread::sleep(Duration::from_millis(outage));
    broker.restart();
    let sub = Sub::start(p, "droidctl/#", &[]);
    let got = gather(&sub, 20, |got| {
        got.iter().filter(|(t, _)| t == tel).count() >= 20
    });
    let stopped = got
        .iter()
        .find(|(t, v)| t == "droidctl/BB-0001/reply" && v["type"] == "stopped");
    assert!(
        stopped.is_some_and(|(_, v)| v["reason"] == "broker_lost"),
        "no stopped notice after the reconnect: {got:?}"
    );
    let samples: Vec<u64> = got
        .iter()
        .filter(|(t, _)| t == tel)
        .filter_map(|(_, v)| v["t_ms"].as_u64())
        .collect();
    assert!(samples.len() >= 20, "{got:?}");
    let stale: Vec<_> = samples.iter().filter(|t| **t < before + outage).collect();
    assert!(
        stale.is_empty(),
        "samples from the outage (last before it at {before} ms) replayed: {stale:?}"
    );
    drop(bridge);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 31 point 4: a retained `info` topic per droid (what `hello` says on stdio) and a
/// retained `bridge` topic listing the droids, both cleared on a clean end; `connected`
/// said once per droid at the start, then `ready`.
#[test]
fn info_and_bridge_topics_are_retained_and_connected_is_said_once() {
    let dir = scratch("info");
    let broker = Broker::start_kind(&dir, Kind::Embedded);
    let p = broker.port;
    let sub = Sub::start(p, "droidctl/#", &[]);
    let mut bridge = BridgeProc::start(
        &dir,
        &[
            "--mqtt",
            &broker.url(),
            "--sim",
            "r2d2,bolt",
            "--rate",
            "50",
            "--bridge-id",
            "lab-1",
        ],
    );
    let ready = |got: &[(String, Value)], d: &str| {
        got.iter()
            .any(|(t, v)| *t == format!("droidctl/{d}/state") && v["ready"] == true)
    };
    let got = gather(&sub, 20, |got| {
        ready(got, "D2-0001") && ready(got, "SB-0002")
    });
    for d in ["D2-0001", "SB-0002"] {
        let states: Vec<_> = got
            .iter()
            .filter(|(t, _)| *t == format!("droidctl/{d}/state"))
            .map(|(_, v)| (v["state"].as_str().unwrap_or(""), v["ready"] == true))
            .collect();
        let connected = states
            .iter()
            .filter(|s| **s == ("connected", false))
            .count();
        assert_eq!(connected, 1, "{d}: {states:?}");
        assert_eq!(states.last(), Some(&("connected", true)), "{d}: {states:?}");
    }
    // A late subscriber finds the bridge and each droid.
    let late = Sub::start(p, "droidctl/+/info", &[]);
    let info = late.wait(5, "droidctl/D2-0001/info", |_| true);
    assert_eq!(
        (info["type"].as_str(), info["model"].as_str()),
        (Some("info"), Some("r2d2"))
    );
    assert_eq!(info["command_timeout_ms"], 600);
    // R2 streams at 10/s: 50 asked, 10 offered.
    assert_eq!(info["telemetry_hz"], 10);
    let caps: Vec<&str> = info["capabilities"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .collect();
    assert!(caps.contains(&"dome") && caps.contains(&"legs"), "{caps:?}");
    let bolt = late.wait(5, "droidctl/SB-0002/info", |_| true);
    assert!(
        bolt["capabilities"].to_string().contains("matrix"),
        "{bolt}"
    );
    // Under the bridge's own id (issue 40 point 1).
    let late = Sub::start(p, "droidctl/bridge/+", &[]);
    let hello = late.wait(5, "droidctl/bridge/lab-1", |_| true);
    assert_eq!(hello["type"], "hello");
    let topics: Vec<&str> = hello["droids"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|d| d["topic"].as_str())
        .collect();
    assert_eq!(topics, ["D2-0001", "SB-0002"]);
    // A clean end clears them (the state says offline).
    interrupt(&mut bridge);
    // The broker takes the bridge's last packets after its end.
    std::thread::sleep(Duration::from_millis(500));
    let after = Sub::start(p, "droidctl/#", &[]);
    let got = gather(&after, 2, |_| false);
    assert!(
        got.iter()
            .all(|(t, _)| t.ends_with("/state") && !t.ends_with("/info")),
        "retained after a clean end: {got:?}"
    );
    assert!(got.iter().any(|(_, v)| v["state"] == "offline"), "{got:?}");
    assert!(
        got.iter()
            .any(|(t, v)| t == "droidctl/bridge/lab-1/state" && v["state"] == "offline"),
        "{got:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
