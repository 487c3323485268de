//! The bridge over standard input/output (`droidctl bridge --stdio`): a client's byte stream,
//! cut and paced as the input says, against a bridge with a simulated R2-D2 and Robi 42, in
//! one process on paused time. Whatever the stream: nothing panics; every object out is one
//! JSON line with `"v":1` and a known type; every line the schema refuses gets exactly one
//! error and every command with an `id` exactly one reply or error; and once the command
//! timeout has passed without input, and again when the input ends, no droid is being driven
//! (the last drive written to each is a stop).
//!
//! Input layout: the first byte's low nibble counts chunk sizes (as the decoder target), its
//! high nibble is the pause between chunks in tens of ms; the rest is the stream.

use super::{Target, feeds, split};
use crate::bridge::schema::{self, ErrorCode};
use crate::bridge::{Bridge, Settings, stdio};
use crate::family::setup::SetupOptions;
use crate::fleet::Fleet;
use crate::model::Model;
use crate::session::{Direction, LinkState, LogItem};
use crate::sync::lock;
use serde_json::Value;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncBufReadExt, AsyncWriteExt};
use tokio::time::sleep;

pub const TARGET: Target = Target {
    name: "bridge",
    run: run_input,
    dictionary: &[
        b"{\"v\":1,\"cmd\":\"drive\",\"speed\":120,\"heading\":90}\n",
        b"{\"v\":1,\"cmd\":\"twist\",\"linear\":0.3,\"angular\":-0.5,\"droid\":\"robi\"}\n",
        b"{\"v\":1,\"cmd\":\"stop\",\"id\":1}\n",
        b"{\"v\":1,\"cmd\":\"estop\",\"id\":\"e\"}\n",
        b"{\"v\":1,\"cmd\":\"lights\",\"group\":\"front\",\"rgb\":[1,2,3],\"id\":2}\n",
        b"{\"v\":1,\"cmd\":\"stream\",\"rate_hz\":50,\"sensors\":[\"gyro\"]}\n",
        b"{\"v\":1,\"cmd\":\"matrix\",\"op\":\"text\",\"text\":\"HI\"}\n",
        b"\"droid\":\"D2-0001\",",
        b"\"droid\":\"Robi 42\",",
        b"\"id\":",
        b"1e400",
        b"-0.0",
        b"\\u0000",
        b"\n",
    ],
};

/// The droids' drive writes (the speed of each, in order).
pub(super) type Writes = Arc<Mutex<Vec<Vec<u8>>>>;

pub fn run_input(data: &[u8]) {
    let Some((pause, sizes, stream)) = split(data) else {
        return;
    };
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .expect("a runtime");
    rt.block_on(session(pause, sizes, stream));
}

/// The droids as `droidctl bridge --sim r2d2,robi` starts them.
pub(super) fn fleet() -> (Fleet, Vec<SetupOptions>) {
    let config = crate::config::Config::defaults();
    let models = [Model::R2D2, Model::Robi42];
    let specs = crate::cli::fleet::simulated(&models)
        .into_iter()
        .map(|f| {
            let s = crate::cli::fleet::session_config(f.model, &config, true);
            f.into_spec(s)
        })
        .collect();
    let setups = models
        .iter()
        .map(|m| crate::family::setup::from_config(*m, &config).0)
        .collect();
    (Fleet::start(specs), setups)
}

pub(super) fn watch_writes(fleet: &Fleet) -> Writes {
    let writes: Writes = Arc::new(Mutex::new(vec![Vec::new(); fleet.len()]));
    for (i, m) in fleet.members().iter().enumerate() {
        let mut log = m.session.subscribe_log();
        let w = writes.clone();
        tokio::spawn(async move {
            while let Ok(e) = log.recv().await {
                if e.dir == Direction::Out
                    && let LogItem::Packet { packet, .. } = &e.item
                    && let Some(speed) = crate::family::drive_speed(packet)
                    && let Ok(mut w) = w.lock()
                {
                    w[i].push(speed);
                }
            }
        });
    }
    writes
}

pub(super) fn still(writes: &Writes, when: &str) {
    let w = lock(writes);
    for (i, speeds) in w.iter().enumerate() {
        assert!(
            speeds.last().is_none_or(|s| *s == 0),
            "droid {i} left driving {when}: its drive writes {speeds:?}"
        );
    }
}

async fn session(pause: u8, sizes: &[u8], stream: &[u8]) {
    let (fleet, setups) = fleet();
    let writes = watch_writes(&fleet);
    for i in 0..fleet.len() {
        if let Some(mut st) = fleet.link_state(i) {
            let _ = st.wait_for(|s| *s == LinkState::Connected).await;
        }
    }
    let settings = Settings::default();
    let timeout = settings.command_timeout;
    let (bridge, rx) = Bridge::start(fleet, setups, settings);
    let (client, server) = tokio::io::duplex(1 << 16);
    let (server_in, server_out) = tokio::io::split(server);
    let running = tokio::spawn(stdio::run(
        bridge,
        rx,
        tokio::io::BufReader::new(server_in),
        server_out,
        std::future::pending(),
    ));
    let (client_in, mut client_out) = tokio::io::split(client);
    let reader = tokio::spawn(async move {
        let mut out = Vec::new();
        let mut r = tokio::io::BufReader::new(client_in);
        let mut l = String::new();
        while r.read_line(&mut l).await.unwrap_or(0) > 0 {
            out.push(std::mem::take(&mut l));
        }
        out
    });
    for chunk in feeds(sizes, stream) {
        if client_out.write_all(chunk).await.is_err() {
            break;
        }
        sleep(Duration::from_millis(pause as u64 * 10)).await;
    }
    // A last line's end, then time for every answer and the timeout.
    let _ = client_out.write_all(b"\n").await;
    sleep(timeout + Duration::from_secs(10)).await;
    still(&writes, "after the command timeout");
    let _ = client_out.shutdown().await;
    let end = running.await.expect("the bridge's stdio ends");
    assert_eq!(end, stdio::End::InputClosed);
    still(&writes, "after the input ended");
    let lines = reader.await.expect("the reader");
    check(stream, &lines);
}

/// What the lines out say of the lines in.
fn check(stream: &[u8], lines: &[String]) {
    let mut refused = 0usize;
    let mut with_id = 0usize;
    for line in stream.split(|b| *b == b'\n') {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        match schema::parse(line) {
            Err(_) => refused += 1,
            Ok(r) if r.id.is_some() => with_id += 1,
            Ok(_) => {}
        }
    }
    let (mut parse_errors, mut answered) = (0usize, 0usize);
    for l in lines {
        let v: Value = serde_json::from_str(l).unwrap_or_else(|e| panic!("{l:?}: {e}"));
        assert_eq!(v["v"], 1, "{l}");
        let kind = v["type"].as_str().unwrap_or("");
        assert!(
            [
                "hello",
                "info",
                "telemetry",
                "collision",
                "battery",
                "link",
                "stopped",
                "reply",
                "error"
            ]
            .contains(&kind),
            "{l}"
        );
        let code = v["code"].as_str().unwrap_or("");
        let parse = [
            ErrorCode::BadJson,
            ErrorCode::BadVersion,
            ErrorCode::UnknownCmd,
            ErrorCode::BadField,
        ]
        .iter()
        .any(|c| serde_json::to_value(c).is_ok_and(|c| c == code));
        match kind {
            "error" if parse => parse_errors += 1,
            "error" | "reply" if !v["id"].is_null() => answered += 1,
            _ => {}
        }
    }
    assert_eq!(parse_errors, refused, "one error per refused line");
    assert_eq!(
        answered, with_id,
        "one reply or error per command with an id"
    );
}
