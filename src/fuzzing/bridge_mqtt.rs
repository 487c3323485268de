//! The bridge's MQTT payload path (issue 27, issue 26 points 5 and 6): what a broker
//! delivers to each droid's connection — publishes retained or not, of any size, on the
//! droids' `cmd` topics and on others — handed to each droid's [`Inbox`] as the connection
//! does, against a bridge with a simulated R2-D2 and Robi 42, in one process on paused
//! time (no broker). Whatever arrives: nothing panics; every object out is of a known type
//! and goes to the droid it names; a payload on a droid's `cmd` topic that the schema
//! refuses gets exactly one error on that droid's topic, and a command with an `id`
//! exactly one reply or error; a retained publish is never executed (each droid says so
//! once, and a droid that got no live drive or twist is never driven); other topics
//! change nothing; once the command timeout has passed no droid is being driven.
//!
//! Input layout, per publish until the input ends: a flags byte (bit 0 retained; bits 1-2
//! the topic: R2's `cmd`, Robi's `cmd`, R2's `reply`, or a topic read from the input; bits
//! 3-4 the size: the payload as read, padded past the command limit, or padded to a
//! length of up to 1 MiB read from the input; bits 5-7 the pause after it in 20 ms
//! steps), then the payload as a length-prefixed piece.

use super::bridge::{Writes, fleet, still, watch_writes};
use super::{Bytes, Target};
use crate::bridge::inbox::Inbox;
use crate::bridge::outbox::Routed;
use crate::bridge::schema::{self, ErrorCode, Out};
use crate::bridge::{Bridge, Settings};
use crate::session::LinkState;
use crate::sync::lock;
use std::time::Duration;
use tokio::time::sleep;

pub const TARGET: Target = Target {
    name: "bridge_mqtt",
    run: run_input,
    dictionary: &[
        b"{\"v\":1,\"cmd\":\"drive\",\"speed\":255,\"heading\":90}",
        b"{\"v\":1,\"cmd\":\"twist\",\"linear\":0.3,\"angular\":-0.5}",
        b"{\"v\":1,\"cmd\":\"stop\",\"id\":1}",
        b"{\"v\":1.0,\"cmd\":\"estop\",\"id\":\"e\"}",
        b"{\"v\":1,\"cmd\":\"sound\",\"sound\":3,\"id\":2}",
        b"\"droid\":\"D2-0001\",",
        b"\"droid\":\"Robi 42\",",
        b"droidctl/D2-0001/cmd",
        b"droidctl/Robi-42/cmd",
        b"\xEF\xBB\xBF",
        b"\"id\":",
    ],
};

pub fn run_input(data: &[u8]) {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .expect("a runtime");
    rt.block_on(session(data));
}

/// One publish as the broker delivers it.
struct Publish {
    topic: String,
    retain: bool,
    payload: Vec<u8>,
    pause: Duration,
}

/// The publishes `data` spells (at most 64: each runs through the bridge).
fn publishes(data: &[u8], cmd: &[String; 2]) -> Vec<Publish> {
    let mut b = Bytes::new(data);
    let mut out = Vec::new();
    while !b.is_empty() && out.len() < 64 {
        let flags = b.u8();
        let topic = match (flags >> 1) & 3 {
            0 => cmd[0].clone(),
            1 => cmd[1].clone(),
            2 => "droidctl/D2-0001/reply".to_string(),
            _ => String::from_utf8_lossy(b.piece()).into_owned(),
        };
        let mut payload = b.piece().to_vec();
        let fill = payload.last().copied().unwrap_or(b' ');
        match (flags >> 3) & 3 {
            0 => {}
            1 => payload.resize(schema::MAX_COMMAND_BYTES + 1 + fill as usize, fill),
            _ => payload.resize((b.u16() as usize) << 4, fill),
        }
        out.push(Publish {
            topic,
            retain: flags & 1 == 1,
            payload,
            pause: Duration::from_millis(((flags >> 5) as u64) * 20),
        });
    }
    out
}

async fn session(data: &[u8]) {
    let (fleet, setups) = fleet();
    let writes: Writes = watch_writes(&fleet);
    for i in 0..fleet.len() {
        if let Some(mut st) = fleet.link_state(i) {
            let _ = st.wait_for(|s| *s == LinkState::Connected).await;
        }
    }
    let settings = Settings::default();
    let timeout = settings.command_timeout;
    let (bridge, mut rx) = Bridge::start(fleet, setups, settings);
    let mut inboxes: Vec<Inbox> = (0..2)
        .map(|i| Inbox::new(bridge.clone(), i, "droidctl"))
        .collect();
    let cmd = [0, 1].map(|i| inboxes[i].cmd_topic().to_string());
    let list = publishes(data, &cmd);
    let collector = tokio::spawn(async move {
        let mut out = Vec::new();
        while let Some(r) = rx.recv_routed().await {
            out.push(r);
        }
        out
    });
    for p in &list {
        for inbox in inboxes.iter_mut() {
            // Each connection gets what matches its subscription (its own `cmd` topic)
            // from the broker; handing it everything checks the others are ignored.
            inbox.publish(&p.topic, p.retain, &p.payload);
        }
        sleep(p.pause).await;
    }
    sleep(timeout + Duration::from_secs(10)).await;
    still(&writes, "after the command timeout");
    let retained: Vec<u64> = inboxes.iter().map(Inbox::retained).collect();
    let names: Vec<String> = bridge.fleet().names();
    drop(inboxes);
    bridge.shutdown().await;
    drop(bridge);
    let out = collector.await.expect("the collector");
    check(&list, &cmd, &names, &retained, &out, &writes);
}

/// What came out, against what went in.
fn check(
    list: &[Publish],
    cmd: &[String; 2],
    names: &[String],
    retained: &[u64],
    out: &[Routed],
    writes: &Writes,
) {
    let mut refused = [0usize; 2];
    let mut with_id = 0usize;
    let mut drove = [false; 2];
    let mut expected_retained = [0u64; 2];
    for p in list {
        let Some(i) = cmd.iter().position(|c| *c == p.topic) else {
            continue;
        };
        if p.retain {
            expected_retained[i] += 1;
            continue;
        }
        match schema::parse(&p.payload) {
            Err(_) => refused[i] += 1,
            Ok(r) => {
                if r.id.is_some() {
                    with_id += 1;
                }
                // A live drive or twist may drive some droid (the one it names).
                if r.cmd.is_motion() {
                    drove = [true; 2];
                }
            }
        }
    }
    assert_eq!(
        retained, expected_retained,
        "every retained command counted"
    );
    let (mut parse_errors, mut retained_said, mut answered) = ([0usize; 2], [0usize; 2], 0);
    for r in out {
        let v: serde_json::Value =
            serde_json::from_str(&r.out.to_json()).expect("every object is JSON");
        assert_eq!(v["v"], 1);
        // An error about what the payload asked names what it asked (a `droid` of any
        // name), and goes back to the topic it came on; anything else goes to its droid.
        let asked = matches!(
            &r.out,
            Out::Error {
                code: ErrorCode::BadJson
                    | ErrorCode::BadVersion
                    | ErrorCode::UnknownCmd
                    | ErrorCode::BadField
                    | ErrorCode::NoSuchDroid,
                ..
            }
        );
        if let (Some(i), Some(name), false) = (r.droid, r.out.droid(), asked) {
            assert_eq!(names[i], name, "routed to the droid it names: {v}");
        }
        let Out::Error { code, id, .. } = &r.out else {
            if let Out::Reply { .. } = &r.out {
                answered += 1;
            }
            continue;
        };
        let parse = matches!(
            code,
            ErrorCode::BadJson
                | ErrorCode::BadVersion
                | ErrorCode::UnknownCmd
                | ErrorCode::BadField
        );
        match (code, r.droid) {
            (ErrorCode::Retained, Some(i)) => retained_said[i] += 1,
            (ErrorCode::Retained, None) => panic!("a retained notice for no droid: {v}"),
            (_, Some(i)) if parse => parse_errors[i] += 1,
            (_, None) if parse => panic!("a payload's error routed to no droid: {v}"),
            _ if id.is_some() => answered += 1,
            _ => {}
        }
    }
    assert_eq!(
        parse_errors, refused,
        "one error per refused payload, on its droid"
    );
    assert_eq!(
        answered, with_id,
        "one reply or error per command with an id"
    );
    for i in 0..2 {
        assert_eq!(
            retained_said[i],
            usize::from(expected_retained[i] > 0),
            "droid {i}: retained commands said once"
        );
    }
    let w = lock(writes);
    for (i, speeds) in w.iter().enumerate() {
        if !drove[i] {
            assert!(
                speeds.iter().all(|s| *s == 0),
                "droid {i} driven with no live drive or twist: {speeds:?}"
            );
        }
    }
}
