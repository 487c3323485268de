//! The bridge's safety promises of issues 26 and 27 on simulated droids under paused time:
//! nothing waits for a droid's link to come back (26.8), a retained MQTT command never
//! drives and a large payload is an error (26.5, 26.6, through [`super::inbox::Inbox`], the MQTT
//! transport without its connection), two droids never share a topic (26.7), and answers
//! are never dropped for a slow reader (27.5).

use super::inbox::Inbox;
use super::schema::{ErrorCode, Out};
use super::tests::{RigOptions, rig, rig_with, run_for};
use super::*;
use crate::session::LinkState;
use crate::sim::Faults;

fn codes(said: &[Out]) -> Vec<(Option<serde_json::Value>, ErrorCode)> {
    said.iter()
        .filter_map(|o| match o {
            Out::Error { id, code, .. } => Some((id.clone(), *code)),
            _ => None,
        })
        .collect()
}

#[tokio::test(start_paused = true)]
async fn a_request_for_a_droid_whose_link_is_down_is_answered_at_once_and_never_runs_later() {
    // R2-D2's link drops 2 s in and stays down for 20 s (the reconnect's backoff).
    let faults = Faults {
        disconnect_at: vec![Duration::from_secs(2)],
        ..Faults::none()
    };
    let backoff = crate::link::backoff::Backoff {
        initial: Duration::from_secs(20),
        max: Duration::from_secs(20),
    };
    let mut r = rig_with(
        &[Model::R2D2],
        5000,
        RigOptions {
            faults: vec![faults],
            backoff: Some(backoff),
            ..RigOptions::default()
        },
    )
    .await;
    // Driving when the link drops: the held drive is let go, said once.
    r.send(r#"{"v":1,"cmd":"drive","speed":90,"heading":0}"#);
    let mut st = r.bridge.fleet().link_state(0).unwrap();
    tokio::time::timeout(
        Duration::from_secs(5),
        st.wait_for(|s| matches!(s, LinkState::Reconnecting { .. })),
    )
    .await
    .expect("the link drops")
    .unwrap();
    run_for(100).await;
    let said = r.said();
    assert!(
        matches!(
            &said[..],
            [Out::Stopped {
                reason: "link_lost",
                ..
            }]
        ),
        "{said:?}"
    );
    let down = r.now();
    // Requests for the droid now: each answered at once with the `droid` error, none `busy`.
    for n in 0..40 {
        r.send(&format!(r#"{{"v":1,"cmd":"sound","sound":3,"id":{n}}}"#));
    }
    r.send(r#"{"v":1,"cmd":"drive","speed":120,"heading":90,"id":"d"}"#);
    r.send(r#"{"v":1,"cmd":"head","angle":30,"id":"h"}"#);
    r.send(r#"{"v":1,"cmd":"stop","id":"s"}"#);
    let said = r.said();
    assert_eq!(said.len(), 43, "{said:?}");
    for (id, code) in codes(&said) {
        assert_eq!(code, ErrorCode::Droid, "{id:?}: {said:?}");
    }
    let Out::Error { error, .. } = &said[0] else {
        unreachable!()
    };
    assert!(error.contains("not connected"), "{error}");
    // Back 20 s later: only the reconnect's own setup and stop are written, nothing asked
    // while it was down, and it does not move.
    tokio::time::timeout(
        Duration::from_secs(30),
        st.wait_for(|s| *s == LinkState::Connected),
    )
    .await
    .expect("the link comes back")
    .unwrap();
    run_for(3000).await;
    let sound = r
        .bridge
        .fleet()
        .member(0)
        .and_then(|m| m.family.sound(m.model, 3))
        .unwrap()
        .name();
    let after: Vec<_> = r.labels(0).into_iter().filter(|(t, _)| *t > down).collect();
    assert!(!after.is_empty(), "the reconnect's setup is written");
    assert!(
        after.iter().all(|(_, l)| *l != sound),
        "a sound asked while the link was down was played after the reconnect: {after:?}"
    );
    let w: Vec<_> = r.writes(0).into_iter().filter(|(t, _)| *t > down).collect();
    assert!(w.iter().all(|(_, s)| *s == 0), "it drove again: {w:?}");
    assert!(r.said().is_empty());
    // Connected again, requests work.
    r.send(r#"{"v":1,"cmd":"sound","sound":3,"id":"again"}"#);
    run_for(1000).await;
    let said = r.said();
    assert!(
        matches!(&said[..], [Out::Played { what: "sound", id: 3, .. }, Out::Reply { id, .. }] if id == "again"),
        "{said:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn a_retained_mqtt_command_never_drives_and_is_said_once() {
    let mut r = rig(&[Model::BB8], 600).await;
    let mut inbox = Inbox::new(r.bridge.clone(), 0, "droidctl");
    assert_eq!(inbox.cmd_topic(), "droidctl/BB-0001/cmd");
    let t0 = r.now();
    let drive = br#"{"v":1,"cmd":"drive","speed":255,"heading":90,"id":1}"#;
    // As the broker delivers it at each (re)subscription.
    for n in 0..5 {
        let said = inbox.publish("droidctl/BB-0001/cmd", true, drive);
        assert_eq!(said.is_some(), n == 0, "said on the terminal once");
        run_for(300).await;
    }
    let said = r.said();
    assert_eq!(codes(&said), [(None, ErrorCode::Retained)], "{said:?}");
    let Out::Error { error, droid, .. } = &said[0] else {
        unreachable!()
    };
    assert!(error.contains("mosquitto_pub -r -n"), "{error}");
    assert_eq!(droid.as_deref(), Some("BB-0001"));
    assert_eq!(inbox.retained(), 5);
    // A new connection to the broker (the reply said on the last one may have been lost with
    // it): the next retained delivery is said again, once.
    inbox.connected();
    assert!(inbox.publish("droidctl/BB-0001/cmd", true, drive).is_some());
    assert!(inbox.publish("droidctl/BB-0001/cmd", true, drive).is_none());
    run_for(300).await;
    assert_eq!(codes(&r.said()), [(None, ErrorCode::Retained)]);
    let w: Vec<_> = r.writes(0).into_iter().filter(|(t, _)| *t >= t0).collect();
    assert!(
        w.iter().all(|(_, s)| *s == 0),
        "a retained drive drove: {w:?}"
    );
    // Other topics are not commands; a live one is.
    inbox.publish("droidctl/BB-0001/reply", false, drive);
    inbox.publish("droidctl/other/cmd", false, drive);
    assert!(r.said().is_empty());
    inbox.publish("droidctl/BB-0001/cmd", false, drive);
    run_for(300).await;
    assert!(matches!(&r.said()[..], [Out::Reply { .. }]));
    assert!(r.writes(0).iter().any(|(t, s)| *t >= t0 && *s == 255));
}

#[tokio::test(start_paused = true)]
async fn a_payload_over_the_command_limit_is_a_bad_json_error() {
    let mut r = rig(&[Model::R2D2], 600).await;
    let mut inbox = Inbox::new(r.bridge.clone(), 0, "droidctl");
    for size in [schema::MAX_COMMAND_BYTES + 1, 6000, 200_000] {
        let mut big = br#"{"v":1,"cmd":"stop","id":"big","pad":""#.to_vec();
        big.resize(size - 2, b'x');
        big.extend_from_slice(b"\"}");
        inbox.publish("droidctl/D2-0001/cmd", false, &big);
        let said = r.said();
        assert_eq!(
            codes(&said),
            [(None, ErrorCode::BadJson)],
            "{size}: {said:?}"
        );
    }
    // The client takes packets far larger than a command, so the connection stays.
    const { assert!(mqtt::MAX_INCOMING_BYTES >= 100 * schema::MAX_COMMAND_BYTES) };
}

#[tokio::test(start_paused = true)]
async fn two_droids_with_the_same_name_get_distinct_topics() {
    let names = ["Robi 42", "Robi 42", "Robi/42", "robi-42-2"].map(String::from);
    let topics = topic_names(&names);
    assert_eq!(topics, ["Robi-42", "Robi-42-2", "Robi-42-3", "robi-42-2-2"]);
    // A bridge of two robots both called "Robi 42": hello lists distinct topics, and what
    // each reports is routed by the droid, not by its name.
    let mut r = rig_with(
        &[Model::Robi42, Model::Robi42],
        600,
        RigOptions {
            names: vec!["Robi 42".into(), "Robi 42".into()],
            ..RigOptions::default()
        },
    )
    .await;
    let Out::Hello { droids, .. } = r.bridge.hello() else {
        unreachable!()
    };
    let t: Vec<_> = droids.iter().map(|d| d.topic.as_str()).collect();
    assert_eq!(t, ["Robi-42", "Robi-42-2"]);
    let mut inbox = Inbox::new(r.bridge.clone(), 1, "droidctl");
    assert_eq!(inbox.cmd_topic(), "droidctl/Robi-42-2/cmd");
    while r.rx.try_recv().is_ok() {}
    inbox.publish(
        "droidctl/Robi-42-2/cmd",
        false,
        br#"{"v":1,"cmd":"stop","id":7}"#,
    );
    let got = r.rx.try_recv_routed().expect("a reply");
    assert!(matches!(got.out, Out::Reply { .. }), "{got:?}");
    assert_eq!(got.droid, Some(1), "the second droid's reply");
}

#[tokio::test(start_paused = true)]
async fn integral_float_versions_and_a_byte_order_mark_are_accepted() {
    for text in [
        &br#"{"v":1.0,"cmd":"stop"}"#[..],
        b"\xEF\xBB\xBF{\"v\":1,\"cmd\":\"stop\"}",
    ] {
        let r = schema::parse(text);
        assert!(
            r.is_ok(),
            "{}: {r:?}",
            String::from_utf8_lossy(text).escape_debug()
        );
    }
    for text in [
        &br#"{"v":1.5,"cmd":"stop"}"#[..],
        br#"{"v":2.0,"cmd":"stop"}"#,
    ] {
        let e = schema::parse(text).unwrap_err();
        assert_eq!(e.code, ErrorCode::BadVersion);
    }
}

/// `lines` into the stdio bridge at once, its output read by a reader that waits 1 s before
/// it starts; every line out.
async fn through_a_slow_reader(lines: Vec<u8>) -> Vec<String> {
    use tokio::io::{AsyncBufReadExt, AsyncWriteExt};
    let r = rig(&[Model::R2D2], 600).await;
    let (client, server) = tokio::io::duplex(8 * 1024);
    let (server_in, server_out) = tokio::io::split(server);
    let task = tokio::spawn(stdio::run(
        r.bridge.clone(),
        r.rx,
        tokio::io::BufReader::new(server_in),
        server_out,
        std::future::pending(),
    ));
    let (client_in, mut client_out) = tokio::io::split(client);
    let writer = tokio::spawn(async move {
        client_out.write_all(&lines).await.unwrap();
        client_out.shutdown().await.unwrap();
    });
    tokio::time::sleep(Duration::from_secs(1)).await;
    let mut out = Vec::new();
    let mut reader = tokio::io::BufReader::new(client_in);
    let mut l = String::new();
    while reader.read_line(&mut l).await.unwrap() > 0 {
        out.push(std::mem::take(&mut l));
    }
    writer.await.unwrap();
    assert_eq!(task.await.unwrap(), stdio::End::InputClosed);
    out
}

fn count(lines: &[String], kind: &str) -> usize {
    lines
        .iter()
        .filter(|l| l.contains(&format!("\"type\":\"{kind}\"")))
        .count()
}

#[tokio::test(start_paused = true)]
async fn a_slow_reader_gets_every_reply_and_the_stopped_notice() {
    let mut input = b"{\"v\":1,\"cmd\":\"drive\",\"speed\":50,\"heading\":0}\n".to_vec();
    for n in 0..10_000 {
        input.extend_from_slice(format!("{{\"v\":1,\"cmd\":\"stop\",\"id\":{n}}}\n").as_bytes());
    }
    input.extend_from_slice(b"{\"v\":1,\"cmd\":\"drive\",\"speed\":50,\"heading\":0}\n");
    let out = through_a_slow_reader(input).await;
    assert_eq!(count(&out, "reply"), 10_000);
    assert_eq!(count(&out, "error"), 0);
    assert!(
        out.iter()
            .any(|l| l.contains("\"stopped\"") && l.contains("\"input_closed\"")),
        "the input_closed notice"
    );
    assert!(out[0].contains("\"hello\""));
}

#[tokio::test(start_paused = true)]
async fn a_slow_reader_gets_one_error_per_garbage_line() {
    let input = b"garbage\n".repeat(200_000);
    let out = through_a_slow_reader(input).await;
    assert_eq!(count(&out, "error"), 200_000);
}
