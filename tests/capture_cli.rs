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
