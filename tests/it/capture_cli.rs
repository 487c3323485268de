//! `droidctl packet decode --file` and `--btsnoop`, and `droidctl replay`, run as the built
//! binary.

use droidctl::protocol::v2::Packet;
use serde_json::Value;
use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

fn droidctl_in(args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .env_remove("RUST_LOG")
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run droidctl");
    if let Some(bytes) = stdin {
        let mut pipe = child.stdin.take().expect("stdin");
        let bytes = bytes.to_vec();
        // Written from a thread: the child's output could fill its pipe before it reads all.
        std::thread::spawn(move || {
            let _ = pipe.write_all(&bytes);
        });
    }
    child.wait_with_output().expect("wait")
}

fn droidctl(args: &[&str]) -> Output {
    droidctl_in(args, None)
}

fn out(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json_lines(o: &Output) -> Vec<Value> {
    out(o)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

/// A fresh directory for one test.
fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("droidctl-capture-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp dir");
    d
}

fn wake() -> Vec<u8> {
    Packet::command(0x13, 0x0D, 0, vec![]).encode()
}

#[test]
fn file_decode_reads_binary_and_hex_files_and_stdin() {
    let dir = tmp("file");
    let mut bin = vec![0x01, 0x02];
    for _ in 0..3 {
        bin.extend(wake());
    }
    let bin_path = dir.join("stream.bin");
    std::fs::write(&bin_path, &bin).unwrap();
    let hex_path = dir.join("stream.txt");
    std::fs::write(&hex_path, droidctl::hex::spaced(&bin)).unwrap();

    for path in [&bin_path, &hex_path] {
        let o = droidctl(&[
            "packet",
            "decode",
            "--file",
            path.to_str().unwrap(),
            "--json",
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", err(&o));
        let lines = json_lines(&o);
        assert_eq!(lines[0]["error"], "garbage");
        assert_eq!(lines[1]["offset"], 2);
        assert_eq!(lines[1]["command"], "wake");
        let summary = &lines.last().unwrap()["summary"];
        assert_eq!(summary["packets"], 3);
        assert_eq!(summary["errors"]["garbage"], 1);
        assert_eq!(summary["error_total"], 1);
    }

    // Standard input, binary and human-readable.
    let o = droidctl_in(&["packet", "decode", "--file", "-"], Some(&bin));
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let text = out(&o);
    assert!(text.contains("command   wake (0x0D)"), "{text}");
    assert!(
        text.trim_end()
            .ends_with("summary: v2 binary, 23 bytes, 3 packets (command 3), 1 errors: garbage 1"),
        "{text}"
    );

    // --summary alone.
    let o = droidctl_in(
        &["packet", "decode", "--file", "-", "--summary"],
        Some(&bin),
    );
    assert_eq!(out(&o).lines().count(), 1, "{}", out(&o));
}

#[test]
fn file_decode_detects_v1_and_rsrcp() {
    let v1 = b"FF FF 02 30 00 05 64 00 5A 01 09 FF FF 00 01 00 01 FD";
    let o = droidctl_in(
        &["packet", "decode", "--file", "-", "--summary", "--json"],
        Some(v1),
    );
    let s = &json_lines(&o)[0]["summary"];
    assert_eq!(s["protocol"], "v1");
    assert_eq!(s["kinds"]["command"], 2);

    let rsrcp = b"7E 00 00 00 40 00 00 80 3F 00 00 00 40 7F";
    let o = droidctl_in(
        &["packet", "decode", "--file", "-", "--summary", "--json"],
        Some(rsrcp),
    );
    let s = &json_lines(&o)[0]["summary"];
    assert_eq!(s["protocol"], "rsrcp", "{}", out(&o));
}

#[test]
fn damaged_hex_shows_what_came_before_and_names_the_offset() {
    let mut text = droidctl::hex::spaced(&wake());
    text.push_str(" 8D 0A 1G");
    let o = droidctl_in(&["packet", "decode", "--file", "-"], Some(text.as_bytes()));
    assert_eq!(o.status.code(), Some(1));
    assert!(out(&o).contains("command   wake (0x0D)"), "{}", out(&o));
    assert!(out(&o).contains("summary: v2 hex text"), "{}", out(&o));
    assert!(
        err(&o).contains("malformed hex at offset 28"),
        "{}",
        err(&o)
    );
}

#[test]
fn file_decode_refuses_what_makes_no_sense() {
    let o = droidctl(&[
        "packet",
        "decode",
        "--file",
        "/nonexistent/droidctl-capture",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(err(&o).contains("cannot read /nonexistent/droidctl-capture"));
    let o = droidctl_in(&["packet", "decode", "--file", "-"], Some(b""));
    assert_eq!(o.status.code(), Some(2));
    assert!(err(&o).contains("empty"), "{}", err(&o));
    let o = droidctl(&["packet", "decode", "8D", "--summary"]);
    assert_eq!(o.status.code(), Some(2));
}

mod btsnoop {
    use super::*;
    use droidctl::capture::btsnoop::Datalink;
    use droidctl::capture::hci::build::Log;
    use droidctl::capture::{Capture, Event};
    use droidctl::family::robi::gatt as robi;
    use droidctl::family::v1::gatt as v1;
    use droidctl::family::v2::gatt as v2;
    use droidctl::gatt::Endpoint;

    const CONN: u16 = 0x0041;

    /// A droidctl capture as a phone's HCI log of the same session: discovery at the connect,
    /// writes as Write Commands, what came in as notifications (Robi's handshake as a read).
    pub fn as_btsnoop(c: &Capture, datalink: Datalink, acl_mtu: usize) -> Vec<u8> {
        let mut log = Log::new(datalink);
        log.acl_mtu = acl_mtu;
        let t0 = log.t_us;
        let robi = c.header.family == Some(droidctl::model::Protocol::Rsrcp);
        let chars = if robi {
            vec![
                (0x20, robi::ROBI_HANDSHAKE),
                (0x22, robi::ROBI_FRAMES),
                (0x30, robi::ROBI_VELOCITY),
                (0x32, robi::ROBI_STEERING),
            ]
        } else if c.header.family == Some(droidctl::model::Protocol::SpheroV1) {
            vec![(0x0E, v1::V1_COMMANDS), (0x10, v1::V1_RESPONSES)]
        } else {
            vec![(0x0E, v2::V2_API)]
        };
        let (write_h, notify_h) = (chars[0].0, chars[chars.len().min(2) - 1].0);
        let mut read_handshake = robi;
        for t in &c.events {
            log.t_us = t0 + t.at.as_micros() as i64;
            match &t.event {
                Event::Connect => {
                    log.le_connected(CONN);
                    log.declare(CONN, &chars);
                }
                Event::Out(Endpoint::Velocity, v) => log.write_cmd(CONN, 0x30, v),
                Event::Out(Endpoint::Steering, v) => log.write_cmd(CONN, 0x32, v),
                Event::Out(_, v) => log.write_cmd(CONN, if robi { 0x30 } else { write_h }, v),
                Event::In(v) if read_handshake => {
                    read_handshake = false;
                    log.read(CONN, 0x20, v);
                }
                Event::In(v) => log.notify(CONN, if robi { 0x22 } else { notify_h }, v),
                Event::Disconnect(_) => log.disconnected(CONN, 0x13),
                _ => {}
            }
        }
        log.bytes
    }

    fn record(dir: &std::path::Path, model: &str, script: &str) -> PathBuf {
        let s = dir.join(format!("{model}.txt"));
        std::fs::write(&s, script).unwrap();
        let cap = dir.join(format!("{model}.capture"));
        let o = droidctl(&[
            "run",
            s.to_str().unwrap(),
            "--sim",
            model,
            "--record",
            cap.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", err(&o));
        cap
    }

    #[test]
    fn a_phone_log_of_a_session_decodes_and_replays_like_its_capture() {
        let dir = tmp("btsnoop");
        for (model, script, datalink, mtu) in [
            (
                "r2d2",
                "wake\nstance tripod\ndrive 80 0 for 2s\nstop\n",
                Datalink::H4,
                27,
            ),
            ("bb8", "wake\ndrive 100 90 for 2s\n", Datalink::H1, 23),
            ("robi", "drive 100 0 for 2s\nstop\n", Datalink::Monitor, 251),
        ] {
            let cap = record(&dir, model, script);
            let c = Capture::load(&cap).unwrap();
            let snoop = dir.join(format!("{model}.btsnoop"));
            std::fs::write(&snoop, as_btsnoop(&c, datalink, mtu)).unwrap();

            // Decoded: the same packets as the capture's own replay logs, with time and way.
            let o = droidctl(&[
                "packet",
                "decode",
                "--btsnoop",
                snoop.to_str().unwrap(),
                "--json",
            ]);
            assert_eq!(o.status.code(), Some(0), "{model}: {}", err(&o));
            let lines = json_lines(&o);
            let summary = &lines.last().unwrap()["summary"];
            assert_eq!(summary["decode_errors"], serde_json::json!({}), "{model}");
            // One vocabulary: the catalogue entry is `command`, as `packet decode --json` says.
            let packets: Vec<_> = lines.iter().filter(|l| l["dir"] == "out").collect();
            assert!(
                packets.iter().all(|l| l.get("name").is_none())
                    && packets.iter().any(|l| l["command"].is_string()),
                "{model}: {:?}",
                packets.first()
            );
            let outs = lines.iter().filter(|l| l["dir"] == "out").count();
            let ins = lines.iter().filter(|l| l["dir"] == "in").count();
            assert!(outs >= 3 && ins >= 10, "{model}: {outs} out, {ins} in");
            assert_eq!(summary["packets_out"], outs);
            assert!(lines.iter().any(|l| l["note"] == "connected"), "{model}");

            // Replayed: the samples of the capture it was made from, from the connect on.
            let from_capture = json_lines(&droidctl(&["replay", cap.to_str().unwrap(), "--json"]));
            let from_snoop = json_lines(&droidctl(&[
                "replay",
                snoop.to_str().unwrap(),
                "--json",
                "--model",
                model,
            ]));
            assert!(from_snoop.len() > 10, "{model}");
            // The log has no mission marks: compare the samples that do not depend on them,
            // those of a capture replayed without its marks.
            let unmarked = dir.join(format!("{model}-unmarked.capture"));
            let mut plain = c.clone();
            plain.events.retain(|t| !matches!(t.event, Event::Mark(_)));
            std::fs::write(&unmarked, plain.to_text()).unwrap();
            let from_plain =
                json_lines(&droidctl(&["replay", unmarked.to_str().unwrap(), "--json"]));
            assert_eq!(from_snoop.len(), from_plain.len(), "{model}");
            for (a, b) in from_snoop
                .iter()
                .zip(&from_plain)
                .take(from_plain.len() - 1)
            {
                assert_eq!(a, b, "{model}");
            }
            assert!(!from_capture.is_empty());
        }
    }

    #[test]
    fn damaged_logs_show_what_came_before_and_name_the_offset() {
        let dir = tmp("btsnoop-damaged");
        let cap = record(&dir, "r2d2", "wake\ndrive 80 0 for 1s\n");
        let c = Capture::load(&cap).unwrap();
        let whole = as_btsnoop(&c, Datalink::H4, 27);
        let cut = dir.join("cut.btsnoop");
        std::fs::write(&cut, &whole[..whole.len() - 10]).unwrap();
        let o = droidctl(&["packet", "decode", "--btsnoop", cut.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1));
        let e = err(&o);
        assert!(e.contains("is damaged: truncated at offset"), "{e}");
        assert!(out(&o).contains("-> wake"), "{}", out(&o));
        assert!(out(&o).contains("summary:"), "{}", out(&o));
        // Replay takes what could be read, with a warning.
        let o = droidctl(&["replay", cut.to_str().unwrap(), "--json"]);
        assert_eq!(o.status.code(), Some(0), "{}", err(&o));
        assert!(err(&o).contains("damaged"), "{}", err(&o));

        let bad = dir.join("bad.btsnoop");
        let mut b = whole.clone();
        b[3] = b'X';
        std::fs::write(&bad, &b).unwrap();
        let o = droidctl(&["packet", "decode", "--btsnoop", bad.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1));
        assert!(err(&o).contains("bad_magic at offset 0"), "{}", err(&o));

        // An impossible length in the first record (included > original).
        let mut b = whole.clone();
        b[20..24].copy_from_slice(&[0x7F, 0, 0, 0]);
        let path = dir.join("long.btsnoop");
        std::fs::write(&path, &b).unwrap();
        let o = droidctl(&["packet", "decode", "--btsnoop", path.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1));
        assert!(
            err(&o).contains("impossible_length at offset"),
            "{}",
            err(&o)
        );

        // A log that starts after the discovery: the hint, then --handle.
        let mut late = Log::new(Datalink::H4);
        late.write_cmd(CONN, 0x0E, &Packet::command(0x13, 0x0D, 0, vec![]).encode());
        let path = dir.join("late.btsnoop");
        std::fs::write(&path, &late.bytes).unwrap();
        let o = droidctl(&["packet", "decode", "--btsnoop", path.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1));
        assert!(err(&o).contains("--handle"), "{}", err(&o));
        let o = droidctl(&[
            "packet",
            "decode",
            "--btsnoop",
            path.to_str().unwrap(),
            "--handle",
            "0x0e",
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", err(&o));
        assert!(out(&o).contains("-> wake"), "{}", out(&o));
    }
}
