//! Fleet missions end to end, as a user runs them: `droidctl run SCRIPT --sim r2d2,bb8,robi`
//! with `@NAME` lines and `together { }` blocks, in one simulated room (the droids collide
//! with each other, and both report it), deterministic, with a `droid` field in `--json`.

use serde_json::Value;

use crate::common::scratch;
use scratch::{Scratch, json_lines, path, stderr, stdout};

/// R2-D2 starts 60 cm west of BB-8 (the fleet stands in a row) and drives east into it;
/// meanwhile Robi 42 drives north on its own, in a block that runs it alongside BB-8.
const CRASH: &str = "\
@R2 stance tripod
@R2 drive 120 90 for 3s
together {
  @BB8 drive 60 180 for 1s
  @robi drive 80 0 for 2s
  @robi stop
}
";

#[test]
fn a_fleet_mission_addresses_droids_shares_a_room_and_is_deterministic() {
    let dir = Scratch::new("fleet-mission", "crash");
    let script = dir.file("crash.txt", CRASH);
    let args = ["run", path(&script), "--sim", "r2d2,bb8,robi", "--json"];
    let (a, _) = dir.run_timed(&args);
    assert_eq!(a.status.code(), Some(0), "stderr: {}", stderr(&a));
    let (b, _) = dir.run_timed(&args);
    assert_eq!(
        stdout(&a),
        stdout(&b),
        "the same fleet mission gives the same output"
    );

    let lines = json_lines(&stdout(&a));
    let summary = |droid: &str| {
        lines
            .iter()
            .find(|l| l["droid"] == droid && l.get("done") == Some(&Value::Bool(true)))
            .unwrap_or_else(|| panic!("a summary for {droid}"))
            .clone()
    };
    let (r2, bb8, robi) = (summary("D2-0001"), summary("BB-0002"), summary("Robi 42"));
    // R2 ran into BB-8: both report the collision; Robi, away from both, none.
    assert!(r2["collisions"].as_u64().unwrap() >= 1, "{r2:?}");
    assert!(bb8["collisions"].as_u64().unwrap() >= 1, "{bb8:?}");
    assert_eq!(robi["collisions"], Value::from(0));
    // R2 stopped touching BB-8 (their centres 6 + 3.65 cm apart by their own sizes, 60 cm at
    // the start): it went about 50 cm, not the 3 s × 75 cm/s it was told.
    let x = r2["x_cm"].as_f64().unwrap();
    assert!((40.0..56.0).contains(&x), "R2 stopped at BB-8: x = {x}");
    assert!(robi["y_cm"].as_f64().unwrap() > 5.0, "{robi:?}");
    // Every sample names its droid, all three sampled on one clock.
    let samples: Vec<&serde_json::Map<String, Value>> =
        lines.iter().filter(|l| l.get("done").is_none()).collect();
    for d in ["D2-0001", "BB-0002", "Robi 42"] {
        assert!(samples.iter().any(|s| s["droid"] == d), "samples of {d}");
    }
    assert!(samples.iter().all(|s| s.contains_key("droid")));
}

#[test]
fn lines_for_droids_the_fleet_lacks_or_cannot_do_are_refused_before_anything_is_sent() {
    let dir = Scratch::new("fleet-mission", "errors");
    let script = dir.file(
        "bad.txt",
        "@sprk drive 50 0\nstance tripod\ntogether {\n@R2 wait 1s\n",
    );
    let out = dir.run(&["run", path(&script), "--sim", "r2d2,bb8"]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains("bad.txt:3:") && err.contains("never closed"),
        "{err}"
    );
    let script = dir.file("bad2.txt", "@sprk drive 50 0\nstance tripod\n");
    let out = dir.run(&["run", path(&script), "--sim", "r2d2,bb8"]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains("bad2.txt:1: no droid called \"sprk\""),
        "{err}"
    );
    assert!(
        err.contains("bad2.txt:2: BB-0002: BB-8 has no legs"),
        "{err}"
    );
    assert!(stdout(&out).is_empty(), "nothing ran");
}

/// `--record` on a fleet mission: one file, each droid's lines apart (`@K`); `replay --json`
/// plays every droid back to the very samples the live run printed.
#[test]
fn a_recorded_fleet_mission_replays_to_the_same_samples_per_droid() {
    let dir = Scratch::new("fleet-mission", "record");
    let script = dir.file("crash.txt", CRASH);
    let capture = dir.0.join("fleet.capture");
    let live = dir.run(&[
        "run",
        path(&script),
        "--sim",
        "r2d2,bb8,robi",
        "--json",
        "--record",
        path(&capture),
    ]);
    assert_eq!(live.status.code(), Some(0), "{}", stderr(&live));
    let text = std::fs::read_to_string(&capture).unwrap();
    assert!(text.starts_with("droidctl-capture 2\n"), "{text}");
    assert!(text.contains("# droid-2: bb8 v1 BB-0002\n"), "{text}");
    for k in 1..=3 {
        assert!(text.contains(&format!("\n@{k} ")), "droid {k}'s lines");
    }
    let replayed = dir.run(&["replay", path(&capture), "--json"]);
    assert_eq!(replayed.status.code(), Some(0), "{}", stderr(&replayed));
    assert_eq!(stderr(&replayed), "", "a clean capture");
    let samples = |out: &str, droid: &str| -> Vec<String> {
        out.lines()
            .filter(|l| l.contains(&format!("\"droid\":\"{droid}\"")) && !l.contains("\"done\""))
            .map(str::to_string)
            .collect()
    };
    for d in ["D2-0001", "BB-0002", "Robi 42"] {
        let (a, b) = (samples(&stdout(&live), d), samples(&stdout(&replayed), d));
        assert!(a.len() > 50, "{d}: {} samples", a.len());
        assert_eq!(a, b, "{d}: the replay's samples are the live run's");
    }
}

/// A phone's btsnoop log of two droids at once: `packet decode --btsnoop` decodes each
/// droid's bytes with its own decoder (they used to be merged into one stream, cutting
/// packets apart) and names each line's droid; `replay --json` gives each droid's samples.
#[test]
fn a_btsnoop_log_of_two_droids_keeps_them_apart_by_connection() {
    use droidctl::capture::btsnoop::Datalink;
    use droidctl::capture::hci::build::Log;
    use droidctl::family::v2::gatt as v2g;
    use droidctl::protocol::v2::cmd;
    use droidctl::protocol::wire::DriveFlags;
    use droidctl::units::Heading;
    const A: [u8; 6] = [0xD5, 0x03, 0x52, 0x94, 0xF2, 0x06];
    const B: [u8; 6] = [0xDD, 0xA4, 0xD5, 0xAE, 0xBF, 0xBE];
    let (api, dos) = (0x000E, 0x0013);
    let mut log = Log::new(Datalink::H4);
    log.le_connected_to(0x0040, A);
    log.le_connected_to(0x0041, B);
    for h in [0x0040, 0x0041] {
        log.declare(h, &[(api, v2g::V2_API), (dos, v2g::V2_ANTI_DOS)]);
    }
    // Each droid's drive command cut in two writes, the writes of both interleaved.
    let drive = |speed, heading| {
        cmd::drive_with_heading(speed, Heading::new(heading).unwrap(), DriveFlags::empty())
    };
    let a = drive(100, 90).to_packet(1).encode();
    let b = drive(50, 270).to_packet(7).encode();
    log.write_cmd(0x0040, api, &a[..6]);
    log.advance(5);
    log.write_cmd(0x0041, api, &b[..6]);
    log.advance(5);
    log.write_cmd(0x0040, api, &a[6..]);
    log.advance(5);
    log.write_cmd(0x0041, api, &b[6..]);
    let dir = Scratch::new("fleet-mission", "btsnoop");
    let file = dir.0.join("two.btsnoop");
    std::fs::write(&file, &log.bytes).unwrap();
    let out = dir.run(&["packet", "decode", "--btsnoop", path(&file)]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = stdout(&out);
    let drives: Vec<&str> = text
        .lines()
        .filter(|l| l.contains("drive-with-heading"))
        .collect();
    assert_eq!(drives.len(), 2, "both drives decoded whole:\n{text}");
    assert!(
        drives
            .iter()
            .any(|l| l.contains("DD:A4:D5:AE:BF:BE") && l.contains("speed=50")),
        "{text}"
    );
    assert!(
        drives
            .iter()
            .any(|l| l.contains("D5:03:52:94:F2:06") && l.contains("speed=100")),
        "{text}"
    );
    assert!(text.contains("no decode errors"), "{text}");
    let replayed = dir.run(&["replay", path(&file), "--json"]);
    assert_eq!(replayed.status.code(), Some(0), "{}", stderr(&replayed));
    let lines = json_lines(&stdout(&replayed));
    let droids: std::collections::BTreeSet<&str> =
        lines.iter().filter_map(|l| l["droid"].as_str()).collect();
    assert_eq!(
        droids.into_iter().collect::<Vec<_>>(),
        ["D5:03:52:94:F2:06", "DD:A4:D5:AE:BF:BE"]
    );
}

/// `run --csv FILE` on a fleet: the file's rows start with their droid (the header with a
/// `droid` column), every droid's samples in it.
#[test]
fn csv_rows_name_their_droid() {
    let dir = Scratch::new("fleet-mission", "csv");
    let script = dir.file("crash.txt", CRASH);
    let csv = dir.0.join("fleet.csv");
    let out = dir.run(&[
        "run",
        path(&script),
        "--sim",
        "r2d2,bb8,robi",
        "--csv",
        path(&csv),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut rows = text.lines();
    let header = rows.next().unwrap();
    assert!(header.starts_with("droid,t_s,x_cm,y_cm"), "{header}");
    let width = header.split(',').count();
    let rows: Vec<Vec<&str>> = rows.map(|r| r.split(',').collect()).collect();
    assert!(
        rows.iter().all(|r| r.len() == width),
        "every row has every column"
    );
    for d in ["D2-0001", "BB-0002", "Robi 42"] {
        assert!(rows.iter().filter(|r| r[0] == d).count() > 50, "{d}'s rows");
    }
    // A one-droid file is as it was: no droid column.
    let one = dir.file("one.txt", "drive 50 0 for 1s\n");
    let csv1 = dir.0.join("one.csv");
    let out = dir.run(&["run", path(&one), "--sim", "bb8", "--csv", path(&csv1)]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = std::fs::read_to_string(&csv1).unwrap();
    assert!(text.starts_with("t_s,"), "{text}");
}
