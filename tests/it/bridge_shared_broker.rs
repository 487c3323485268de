//! Several bridges on one broker (issue 40 points 1, 2, 4 and 6), as a lab runs them: two
//! `--sim` bridges as separate processes, through droidctl's own broker and through
//! mosquitto. Each keeps its `hello` under its own id, the second sees the first's droid
//! live and takes a distinct topic (saying so), a command gets one reply and drives one
//! droid, and one bridge's clean end leaves the other's topics and Home Assistant device
//! alone.

use crate::common::bridge_proc;
use crate::common::mosquitto;

use bridge_proc::{BridgeProc, gather, interrupt, scratch};
use mosquitto::{Broker, Kind, Sub, mosquitto_here, publish};
use serde_json::Value;
use std::time::Duration;

fn two_bridges_keep_apart(kind: Kind) {
    let dir = scratch(&format!("two-bridges-{kind:?}"));
    let broker = Broker::start_kind(&dir, kind);
    let p = broker.port;
    let url = broker.url();
    let sub = Sub::start(p, "droidctl/#", &[]);
    let args = ["--mqtt", &url, "--sim", "r2d2", "--homeassistant"];
    let mut first = BridgeProc::start(&dir, &args);
    sub.wait(20, "droidctl/D2-0001/state", |v| v["ready"] == true);
    let mut second = BridgeProc::start(&dir, &args);
    sub.wait(20, "droidctl/D2-0001-2/state", |v| v["ready"] == true);
    let said = second.stderr();
    assert!(
        said.contains("D2-0001 is live on the broker already") && said.contains("D2-0001-2"),
        "the second bridge says which name it took: {said}"
    );
    // Two bridges, two ids, two hellos, each with its own droid.
    let late = Sub::start(p, "droidctl/bridge/#", &[]);
    let got = gather(&late, 5, |got| got.len() >= 4);
    let states: Vec<&(String, Value)> = got
        .iter()
        .filter(|(t, v)| t.ends_with("/state") && v["state"] == "online")
        .collect();
    assert_eq!(states.len(), 2, "{got:?}");
    assert_ne!(states[0].0, states[1].0);
    let mut topics: Vec<String> = got
        .iter()
        .filter(|(_, v)| v["type"] == "hello")
        .map(|(_, v)| v["droids"][0]["topic"].as_str().unwrap_or("").to_string())
        .collect();
    topics.sort();
    assert_eq!(topics, ["D2-0001", "D2-0001-2"], "{got:?}");
    // One command, one reply, from the droid of that topic only.
    let _ = sub.drain();
    assert!(publish(
        p,
        "droidctl/D2-0001/cmd",
        r#"{"v":1,"cmd":"stop","id":"once"}"#,
        &[]
    ));
    sub.wait(5, "droidctl/D2-0001/reply", |v| v["id"] == "once");
    std::thread::sleep(Duration::from_millis(500));
    let replies: Vec<_> = sub
        .drain()
        .into_iter()
        .filter(|(t, v)| t.ends_with("/reply") && v["id"] == "once")
        .collect();
    assert!(replies.is_empty(), "a second reply: {replies:?}");
    // The second bridge's clean end: its own topics cleared, the first's untouched.
    interrupt(&mut second);
    std::thread::sleep(Duration::from_millis(500));
    let after = Sub::start(p, "#", &[]);
    let got = gather(&after, 2, |_| false);
    let at = |t: &str| got.iter().find(|(x, _)| x == t).map(|(_, v)| v.clone());
    assert_eq!(
        at("droidctl/D2-0001/state").map(|v| v["state"].clone()),
        Some("connected".into()),
        "{got:?}"
    );
    assert!(at("droidctl/D2-0001/info").is_some(), "{got:?}");
    assert!(at("droidctl/D2-0001-2/info").is_none(), "{got:?}");
    assert_eq!(
        at("droidctl/D2-0001-2/state").map(|v| v["state"].clone()),
        Some("offline".into())
    );
    let hellos = got.iter().filter(|(_, v)| v["type"] == "hello").count();
    assert_eq!(hellos, 1, "the first bridge's hello stays: {got:?}");
    // Home Assistant keeps both devices (the second's shown unavailable).
    for node in ["droidctl_D2-0001", "droidctl_D2-0001-2"] {
        let t = format!("homeassistant/button/{node}/stop/config");
        assert!(at(&t).is_some(), "{t} removed: {got:?}");
    }
    // The first still takes commands.
    assert!(publish(
        p,
        "droidctl/D2-0001/cmd",
        r#"{"v":1,"cmd":"stop","id":"still"}"#,
        &[]
    ));
    sub.wait(5, "droidctl/D2-0001/reply", |v| v["id"] == "still");
    interrupt(&mut first);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn two_bridges_on_droidctls_own_broker_keep_apart() {
    two_bridges_keep_apart(Kind::Embedded);
}

#[test]
fn two_bridges_on_mosquitto_keep_apart() {
    if !mosquitto_here() {
        return;
    }
    two_bridges_keep_apart(Kind::Mosquitto);
}

/// A bridge id asked for that another running bridge has is refused, with what to do.
#[test]
fn an_id_asked_for_that_is_online_is_refused() {
    let dir = scratch("bridge-id");
    let broker = Broker::start_kind(&dir, Kind::Embedded);
    let sub = Sub::start(broker.port, "droidctl/#", &[]);
    let args = [
        "--mqtt",
        &broker.url(),
        "--sim",
        "bb8",
        "--bridge-id",
        "table-3",
    ];
    let mut first = BridgeProc::start(&dir, &args);
    sub.wait(20, "droidctl/bridge/table-3/state", |v| {
        v["state"] == "online"
    });
    let mut second = BridgeProc::start(&dir, &args);
    assert_eq!(second.wait(20), Some(2), "{}", second.stderr());
    let said = second.stderr();
    assert!(
        said.contains("another bridge with id table-3 is online") && said.contains("--bridge-id"),
        "{said}"
    );
    interrupt(&mut first);
    let _ = std::fs::remove_dir_all(&dir);
}
