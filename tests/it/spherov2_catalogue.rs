//! Issue 19 point 4 (and point 1): spherov2.py's own command builders, called method by
//! method for every API v2 toy (tests/spherov2_commands.py), against droidctl's catalogue and
//! encoder, byte for byte. Needs a Python with spherov2 (`pip install spherov2`): point
//! DROIDCTL_TEST_SPHEROV2_PYTHON at it (default python3); without it the test says it is
//! skipped. Issue 41: the same for sphero-unsw's BOLTPLUS (the Sphero BOLT+), with a Python
//! that has sphero-unsw (DROIDCTL_TEST_SPHERO_UNSW_PYTHON, or target/sphero-unsw-venv that
//! `.ci/run` makes).

use droidctl::family::v2::V2Codec;
use droidctl::family::{Codec, Command as FamilyCommand};
use droidctl::model::Model;
use droidctl::protocol::v2::Value;
use droidctl::protocol::v2::catalog::targets::{self, Processor};
use droidctl::protocol::v2::catalog::{self, decode_fields};
use droidctl::protocol::v2::types::{Char, ScrollText};
use droidctl::protocol::v2::wire::{DriveFlags, RawMotorMode};
use droidctl::protocol::v2::{Command, cmd};
use droidctl::units::Heading;
use serde_json::Value as Json;
use std::collections::{BTreeMap, BTreeSet};
use std::process::Command as Process;

/// The packets spherov2 builds, or why they cannot be had.
fn spherov2_packets() -> Result<Vec<Json>, String> {
    packets_of(&crate::common::python::Library::Spherov2.candidate(), &[])
}

/// The Python with sphero-unsw: DROIDCTL_TEST_SPHERO_UNSW_PYTHON, else the venv `.ci/run`
/// makes (target/sphero-unsw-venv), else python3.
pub fn sphero_unsw_python() -> String {
    crate::common::python::Library::SpheroUnsw.candidate()
}

/// The packets the helper prints with `py` and `args`, or why they cannot be had.
fn packets_of(py: &str, args: &[&str]) -> Result<Vec<Json>, String> {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/spherov2_commands.py");
    let out = Process::new(py)
        .arg(script)
        .args(args)
        .output()
        .map_err(|e| format!("cannot run {py}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{py} cannot run the spherov2 helper (set DROIDCTL_TEST_SPHEROV2_PYTHON to a Python \
             with spherov2 installed): {}",
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .last()
                .unwrap_or("")
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("helper prints JSON"))
        .collect())
}

fn model_of(toy: &str) -> Model {
    match toy {
        "R2D2" => Model::R2D2,
        "R2Q5" => Model::R2Q5,
        "BB9E" => Model::BB9E,
        "BOLT" => Model::Bolt,
        "BOLTPLUS" => Model::BoltPlus,
        "Mini" => Model::Mini,
        "RVR" => Model::Rvr,
        other => panic!("unknown toy {other}"),
    }
}

fn hex(s: &str) -> Vec<u8> {
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).unwrap())
        .collect()
}

/// A decoded value as the command line would give it.
fn as_text(v: &Value) -> String {
    match v {
        Value::Bool(b) => b.to_string(),
        Value::Int(i) => i.to_string(),
        Value::Float(f) => format!("{f}"),
        Value::Hex { value, .. } | Value::Enum { value, .. } | Value::Flags { bits: value, .. } => {
            value.to_string()
        }
        Value::Text(t) => t.clone(),
        Value::Bytes(b) => b.iter().map(|x| format!("{x:02x}")).collect(),
        Value::List(items) => items.iter().map(as_text).collect::<Vec<_>>().join(","),
    }
}

/// Every command spherov2 sends is named by droidctl's catalogue, its payload decodes by the
/// command's typed parameters, re-encodes from them to the same bytes, and droidctl frames
/// it with the same target (the processor droidctl addresses, or the one spherov2 names where
/// both answer) into the same wire bytes.
#[test]
fn every_spherov2_command_is_named_and_encoded_byte_for_byte() {
    let rows = match spherov2_packets() {
        Ok(rows) => rows,
        Err(why) => {
            println!("SKIPPED every_spherov2_command_is_named_and_encoded_byte_for_byte: {why}");
            return;
        }
    };
    let (distinct, checked) = check_named_and_encoded(&rows);
    assert!(checked > 400, "only {checked} packets checked");
    for s in rows.iter().filter(|r| r.get("summary").is_some()) {
        println!(
            "{}: {} distinct commands, all named",
            s["summary"], s["distinct"]
        );
    }
    // Every robot of the issue, and every droid, sends dozens of distinct commands.
    for (toy, min) in [("R2D2", 50), ("BOLT", 70), ("Mini", 35), ("RVR", 90)] {
        assert!(distinct[toy].len() >= min, "{toy}: {}", distinct[toy].len());
    }
}

/// Each row's packet is named, decodes and re-encodes to its bytes, is addressed as the library
/// addresses it, and frames to its wire bytes: the distinct (DID, CID) per toy, and how many
/// packets were checked.
fn check_named_and_encoded(rows: &[Json]) -> (BTreeMap<String, BTreeSet<(u64, u64)>>, usize) {
    let mut distinct: BTreeMap<String, BTreeSet<(u64, u64)>> = BTreeMap::new();
    let mut checked = 0;
    for r in rows.iter().filter(|r| r.get("toy").is_some()) {
        let toy = r["toy"].as_str().unwrap();
        let model = model_of(toy);
        let (did, cid) = (
            r["did"].as_u64().unwrap() as u8,
            r["cid"].as_u64().unwrap() as u8,
        );
        let what = format!("{toy}.{} ({did:02X}/{cid:02X})", r["method"]);
        distinct
            .entry(toy.into())
            .or_default()
            .insert((did as u64, cid as u64));
        let def = catalog::lookup(did, cid).unwrap_or_else(|| panic!("{what}: not named"));
        let data = hex(r["data"].as_str().unwrap());
        let fields = decode_fields(def.params, &data)
            .unwrap_or_else(|e| panic!("{what}: payload {data:02X?} does not decode: {e}"));
        let given: Vec<(String, String)> = fields
            .iter()
            .map(|(n, v)| (n.replace('_', "-"), as_text(v)))
            .collect();
        assert_eq!(
            def.encode_params(&given),
            Ok(data.clone()),
            "{what}: re-encoded from {given:?}"
        );
        // The processor: droidctl addresses the command as spherov2 does, or spherov2 picked
        // one of two processors that both answer it.
        let tid = r["tid"].as_u64().map(|t| t as u8);
        let ours = targets::addressed(model, did, cid).map(|p| p.target_id());
        let home = targets::home(model, did, cid);
        match tid {
            None => assert_eq!(
                ours, None,
                "{what}: droidctl addresses it, spherov2 does not"
            ),
            Some(t) => assert!(
                ours == Some(t) || home == targets::Home::Both,
                "{what}: spherov2 sends it to {t:#04x}, droidctl to {ours:?} (home {home:?})"
            ),
        }
        let mut command = Command::new(did, cid, data);
        command.target = tid;
        let mut codec = V2Codec::for_model(model);
        let seq = r["seq"].as_u64().unwrap() as u8;
        let (wire, _) = codec.encode(&FamilyCommand::V2(command), seq, true);
        assert_eq!(
            wire,
            hex(r["wire"].as_str().unwrap()),
            "{what}: wire bytes differ"
        );
        checked += 1;
    }
    (distinct, checked)
}

/// Issue 41: every command sphero-unsw builds for its BOLTPLUS is named, decodes, re-encodes
/// and goes to the processor sphero-unsw sends it to (BOLT+'s primary), byte for byte.
#[test]
fn every_sphero_unsw_boltplus_command_is_named_and_encoded_byte_for_byte() {
    let py = sphero_unsw_python();
    let rows = match packets_of(&py, &["sphero_unsw"]) {
        Ok(rows) => rows,
        Err(why) => {
            println!(
                "SKIPPED every_sphero_unsw_boltplus_command_is_named_and_encoded_byte_for_byte: \
                 {why} (set DROIDCTL_TEST_SPHERO_UNSW_PYTHON to a Python with sphero-unsw)"
            );
            return;
        }
    };
    let (distinct, checked) = check_named_and_encoded(&rows);
    let bp = &distinct["BOLTPLUS"];
    println!("BOLTPLUS: {} distinct commands, all named", bp.len());
    assert!(
        checked >= 75 && bp.len() >= 75,
        "{checked} packets, {}",
        bp.len()
    );
    // Drive and the screen on the primary (0x11), where BOLT has them on the secondary.
    for (method, did, cid) in [
        ("drive_with_heading", 0x16, 0x07),
        ("draw_compressed_frame_player_fill", 0x1A, 0x3E),
    ] {
        let r = rows
            .iter()
            .find(|r| r["toy"] == "BOLTPLUS" && r["did"] == did && r["cid"] == cid);
        let r = r.unwrap_or_else(|| panic!("{method} not built"));
        assert_eq!(r["tid"], 0x11, "{method}: {r}");
    }
}

/// The typed constructors give what spherov2 gives for the same arguments (the helper's
/// fixed ones), addressed as BOLT's and RVR's toys address them.
#[test]
fn typed_constructors_match_spherov2() {
    let rows = match spherov2_packets() {
        Ok(rows) => rows,
        Err(why) => {
            println!("SKIPPED typed_constructors_match_spherov2: {why}");
            return;
        }
    };
    let wire = |toy: &str, method: &str| -> Vec<u8> {
        let r = rows
            .iter()
            .find(|r| r["toy"] == toy && r["method"] == method)
            .unwrap_or_else(|| panic!("{toy}.{method} not built"));
        hex(r["wire"].as_str().unwrap())
    };
    let ours = |model: Model, c: Command| -> Vec<u8> {
        V2Codec::for_model(model)
            .encode(&FamilyCommand::V2(c), 0, true)
            .0
    };
    let cases: Vec<(&str, &str, Model, Command)> = vec![
        (
            "BOLT",
            "set_compressed_frame_player_single_character",
            Model::Bolt,
            cmd::set_compressed_frame_player_single_character(255, 0, 0, Char(b'A')),
        ),
        (
            "BOLT",
            "set_compressed_frame_player_text_scrolling",
            Model::Bolt,
            cmd::set_compressed_frame_player_text_scrolling(
                255,
                0,
                0,
                7,
                true,
                ScrollText("HI".into()),
            ),
        ),
        (
            "BOLT",
            "set_compressed_frame_player_one_color",
            Model::Bolt,
            cmd::set_compressed_frame_player_one_color(255, 0, 0),
        ),
        (
            "BOLT",
            "drive_with_heading",
            Model::Bolt,
            cmd::drive_with_heading(100, Heading::new(270).unwrap(), DriveFlags::BACKWARD),
        ),
        (
            "RVR",
            "set_raw_motors",
            Model::Rvr,
            cmd::set_raw_motors(RawMotorMode::Forward, 200, RawMotorMode::Reverse, 50),
        ),
        (
            "Mini",
            "drive_with_heading",
            Model::Mini,
            cmd::drive_with_heading(100, Heading::new(270).unwrap(), DriveFlags::BACKWARD),
        ),
        (
            "RVR",
            "get_rgbc_sensor_values",
            Model::Rvr,
            cmd::get_rgbc_sensor_values(),
        ),
    ];
    for (toy, method, model, c) in cases {
        assert_eq!(ours(model, c), wire(toy, method), "{toy}.{method}");
    }
    // An RVR command both processors answer goes where it is sent.
    let echo = cmd::echo(droidctl::protocol::v2::wire::Bytes(vec![1, 2])).to(Processor::Secondary);
    let secondary = rows
        .iter()
        .find(|r| r["toy"] == "RVR" && r["method"] == "ping" && r["tid"] == 0x12)
        .unwrap();
    assert_eq!(
        ours(Model::Rvr, echo),
        hex(secondary["wire"].as_str().unwrap())
    );
}
