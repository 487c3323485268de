//! Monitoring end to end (issue 22), as a user runs it: missions choose the streaming rate
//! and sensors and tune collision detection, `--csv` writes telemetry a spreadsheet opens,
//! `replay --csv` gives the same rows, and `droidctl plot` draws a run where its telemetry
//! says. What went over the link is read back from the recorded capture with the same
//! mirror replay uses.

use droidctl::capture::Capture;
use droidctl::capture::mirror::{Mirror, Output};
use droidctl::model::Model;
use droidctl::protocol::notify::Notification;
use std::path::Path;
use std::time::Duration;

use crate::common::scratch;
use scratch::{Scratch, json_lines, path, stderr, stdout};

/// Everything the mirror makes of a capture, with times.
fn mirrored(capture: &Path, model: Model) -> Vec<(Duration, Output)> {
    let c = Capture::load(capture).unwrap();
    let mut m = Mirror::new(model);
    let mut out = Vec::new();
    for t in &c.events {
        let mut o = Vec::new();
        m.event(t, &mut o);
        out.extend(o.into_iter().map(|o| (t.at, o)));
    }
    out
}

/// When the mission's step on `line` started (its `step LINE …` mark).
fn step_at(outs: &[(Duration, Output)], line: usize) -> Duration {
    outs.iter()
        .find_map(|(at, o)| match o {
            Output::Mark(m) if m.starts_with(&format!("step {line} ")) => Some(*at),
            _ => None,
        })
        .unwrap_or_else(|| panic!("no mark for line {line}"))
}

/// Sensor samples between `from` and `to`: how many, and the value names of the last.
fn samples_between(
    outs: &[(Duration, Output)],
    from: Duration,
    to: Duration,
) -> (usize, Vec<&'static str>) {
    let mut n = 0;
    let mut names = Vec::new();
    for (at, o) in outs {
        if let Output::Notification(Notification::Sensors(s)) = o
            && *at >= from
            && *at < to
        {
            n += 1;
            names = s.values.iter().map(|(k, _)| *k).collect();
        }
    }
    (n, names)
}

#[test]
fn mission_lines_choose_rate_and_sensors_cap_to_the_link_and_never_silence_collisions() {
    let dir = Scratch::new("monitoring", "stream");
    let script = dir.file(
        "m.txt",
        "stance tripod\n\
         stream 50 attitude\n\
         wait 2s\n\
         stream 100\n\
         wait 2s\n\
         stream off\n\
         wait 1s\n\
         drive 255 90 for 3s\n\
         wait 1s\n",
    );
    let cap = dir.0.join("m.capture");
    let o = dir.run(&["run", path(&script), "--sim", "--record", path(&cap)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // 100/s with every sensor does not fit R2-D2's link: capped, and said.
    assert!(
        stderr(&o).contains("line 4: streaming:") && stderr(&o).contains("capped at 10/s"),
        "{}",
        stderr(&o)
    );
    let outs = mirrored(&cap, Model::R2D2);
    let (s50, s100, off, drive) = (
        step_at(&outs, 2),
        step_at(&outs, 4),
        step_at(&outs, 6),
        step_at(&outs, 8),
    );
    let sec = Duration::from_secs(1);
    // A second well inside each stretch.
    let (n, names) = samples_between(&outs, s50 + Duration::from_millis(500), s50 + sec * 3 / 2);
    assert!((48..=52).contains(&n), "50/s asked, {n} in a second");
    assert_eq!(names, ["pitch", "roll", "yaw"], "attitude only");
    let (n, names) = samples_between(&outs, s100 + Duration::from_millis(500), s100 + sec * 3 / 2);
    assert!((9..=11).contains(&n), "capped to 10/s, {n} in a second");
    assert!(
        names.contains(&"gyro_z") && names.contains(&"locator_x"),
        "{names:?}"
    );
    let (n, _) = samples_between(&outs, off + Duration::from_millis(300), Duration::MAX);
    assert_eq!(n, 0, "streaming off");
    // Each streaming change was followed by collision detection again, and the wall at full
    // speed was reported with streaming off.
    let cmds: Vec<(Duration, String)> = outs
        .iter()
        .filter_map(|(at, o)| match o {
            Output::Command(c) => Some((*at, c.name())),
            _ => None,
        })
        .collect();
    for t in [s50, s100, off] {
        let after: Vec<&str> = cmds
            .iter()
            .filter(|(at, _)| *at >= t)
            .map(|(_, n)| n.as_str())
            .take(5)
            .collect();
        assert_eq!(
            after,
            [
                "set-sensor-streaming-mask",
                "set-extended-sensor-streaming-mask",
                "set-sensor-streaming-mask",
                "configure-collision-detection",
                "enable-collision-detected-notify"
            ],
            "at {t:?}"
        );
    }
    let hit = outs.iter().any(|(at, o)| {
        *at > drive && matches!(o, Output::Notification(Notification::Collision(_)))
    });
    assert!(hit, "the collision was reported with streaming off");
}

/// Run `script` on the simulated `model` with `--json`; the summary's collision count.
fn collisions(dir: &Scratch, model: &str, script: &str) -> u64 {
    let f = dir.file(&format!("{model}.txt"), script);
    let o = dir.run(&["run", path(&f), "--sim", model, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let lines = json_lines(&stdout(&o));
    lines.last().unwrap()["collisions"].as_u64().unwrap()
}

#[test]
fn collision_thresholds_are_honoured_by_the_simulator_on_v2_and_v1() {
    let dir = Scratch::new("monitoring", "collision");
    // A gentle bump: speed 40 (25 cm/s) into the wall 2 m away.
    for (model, prefix) in [("r2d2", "stance tripod\n"), ("bb8", "")] {
        let gentle = "drive 40 90 for 12s\n";
        let default = collisions(&dir, model, &format!("{prefix}{gentle}"));
        assert!(
            default >= 1,
            "{model}: the default thresholds report the bump"
        );
        let hard = collisions(
            &dir,
            model,
            &format!("{prefix}collision 250 250 0 0 100ms\n{gentle}"),
        );
        assert_eq!(hard, 0, "{model}: a harder threshold ignores it");
        // A hard hit still counts under the hard threshold.
        let fast = collisions(
            &dir,
            model,
            &format!("{prefix}collision 250 250 0 0 100ms\ndrive 255 90 for 3s\n"),
        );
        assert!(fast >= 1, "{model}: a hit at full speed exceeds 250");
    }
    // The configure command is in the log, with the values of the line (v1 order: Xt, Xspd,
    // Yt, Yspd, dead in 10 ms).
    let f = dir.file("log.txt", "collision 200 150 20 30 250ms\nwait 1s\n");
    let cap = dir.0.join("log.capture");
    let o = dir.run(&["run", path(&f), "--sim", "bb8", "--record", path(&cap)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let logged = mirrored(&cap, Model::BB8).into_iter().any(|(_, o)| {
        matches!(&o, Output::Log(e) if format!("{e:?}").contains("configure-collision-detection"))
    });
    assert!(logged, "the packet log shows the configure command");
    let sent = mirrored(&cap, Model::BB8)
        .into_iter()
        .filter_map(|(_, o)| match o {
            Output::Command(c) if c.name() == "configure-collision-detection" => {
                Some(c.data().to_vec())
            }
            _ => None,
        })
        .next_back();
    assert_eq!(sent, Some(vec![1, 200, 20, 150, 30, 25]));
}

/// A CSV file as header and rows of cells.
fn csv(p: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

#[test]
fn run_and_replay_write_the_same_csv_a_spreadsheet_opens() {
    let dir = Scratch::new("monitoring", "csv");
    let script = dir.file(
        "m.txt",
        "stance tripod\ndrive 120 90 for 2s\nhead 30\nwait 1s\n",
    );
    let (run_csv, cap) = (dir.0.join("run.csv"), dir.0.join("m.capture"));
    let o = dir.run(&[
        "run",
        path(&script),
        "--sim",
        "--json",
        "--csv",
        path(&run_csv),
        "--record",
        path(&cap),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let json = json_lines(&stdout(&o));
    let (header, rows) = csv(&run_csv);
    // One row per sample, every row as wide as the header, columns named with units.
    assert_eq!(rows.len(), json.len() - 1, "the summary is not a sample");
    assert!(rows.iter().all(|r| r.len() == header.len()));
    for name in [
        "t_s",
        "x_cm",
        "speed_cm_s",
        "yaw_deg",
        "accel_x_g",
        "gyro_z_deg_s",
        "battery_v",
    ] {
        assert!(header.iter().any(|h| h == name), "{name} in {header:?}");
    }
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    for (row, j) in rows.iter().zip(&json) {
        let t: f64 = row[col("t_s")].parse().unwrap();
        assert!((t * 1000.0 - j["t_ms"].as_f64().unwrap()).abs() < 0.5);
        match j["x_cm"].as_f64() {
            Some(x) => assert!((row[col("x_cm")].parse::<f64>().unwrap() - x).abs() < 0.01),
            None => assert_eq!(row[col("x_cm")], ""),
        }
    }
    let last = rows.last().unwrap();
    assert!(last[col("head_deg")].parse::<f64>().unwrap() > 25.0);
    assert!(
        last[col("yaw_deg")].parse::<f64>().is_ok(),
        "streamed yaw: {last:?}"
    );
    // Replay writes the same rows from the capture.
    let replay_csv = dir.0.join("replay.csv");
    let o = dir.run(&["replay", path(&cap), "--csv", path(&replay_csv)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&replay_csv).unwrap(),
        std::fs::read_to_string(&run_csv).unwrap()
    );
}

/// The pixel at (x, y) of a decoded RGB PNG.
fn rgb(img: &[u8], w: u32, (x, y): (i32, i32)) -> [u8; 3] {
    let i = (y as usize * w as usize + x as usize) * 3;
    [img[i], img[i + 1], img[i + 2]]
}

fn close_to(c: [u8; 3], want: [u8; 3]) -> bool {
    c.iter().zip(want).all(|(a, b)| a.abs_diff(b) <= 40)
}

#[test]
fn plot_draws_the_path_where_the_telemetry_says() {
    let dir = Scratch::new("monitoring", "plot");
    // Out east 1.5 s, then north, then into the west wall at full speed.
    let script = dir.file(
        "m.txt",
        "stance tripod\ndrive 100 90 for 1.5s\ndrive 100 0 for 1.5s\ndrive 255 270 for 3s\n",
    );
    let o = dir.run(&["run", path(&script), "--sim", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let jsonl = dir.file("run.jsonl", &stdout(&o));
    let (png, svg) = (dir.0.join("run.png"), dir.0.join("run.svg"));
    let o = dir.run(&[
        "plot",
        path(&jsonl),
        "-o",
        path(&png),
        "-o",
        path(&svg),
        "--channels",
        "speed,gyro_z",
        "--size",
        "900x700",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let svg = std::fs::read_to_string(&svg).unwrap();
    for text in [
        "path from above",
        "x (cm)",
        "y (cm)",
        "speed (cm/s)",
        "time (s)",
        "collision (1)",
    ] {
        assert!(svg.contains(text), "the SVG says {text:?}");
    }
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut img = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut img).unwrap();
    assert_eq!((info.width, info.height), (900, 700));
    assert_eq!(info.color_type, png::ColorType::Rgb);

    // Where each sample must be drawn, from the same run rendered in-process.
    let samples: Vec<droidctl::mission::Sample> = json_lines(&stdout_of(&jsonl))
        .into_iter()
        .filter(|j| j.get("done").is_none())
        .map(|j| serde_json::from_value(serde_json::Value::Object(j)).unwrap())
        .collect();
    let run = droidctl::plot::Run::of_samples(
        "run.jsonl",
        &samples,
        &[
            droidctl::telemetry::history::Channel::Speed,
            droidctl::telemetry::history::Channel::GyroZ,
        ],
    );
    let frame = droidctl::plot::png(&run, (900, 700), std::io::sink()).unwrap();
    let path_colour = [
        droidctl::plot::PATH.0,
        droidctl::plot::PATH.1,
        droidctl::plot::PATH.2,
    ];
    let near = |p: (i32, i32), colour: [u8; 3]| {
        (-2..=2).any(|dx| (-2..=2).any(|dy| close_to(rgb(&img, 900, (p.0 + dx, p.1 + dy)), colour)))
    };
    let positions: Vec<(f64, f64)> = samples
        .iter()
        .filter_map(|s| Some((s.x_cm? as f64, s.y_cm? as f64)))
        .collect();
    assert!(positions.len() > 30);
    let (mut east, mut north, mut west) = (0.0f64, 0.0f64, 0.0f64);
    // The start, the end and the collision have their own marks over the path (the
    // collision's at the first sample that counts it, which may be short of the wall).
    let start = frame.pixel(positions[0].0, positions[0].1);
    let last = positions.last().unwrap();
    let end = frame.pixel(last.0, last.1);
    let hit = samples
        .windows(2)
        .find(|w| w[1].collisions > w[0].collisions)
        .and_then(|w| Some(frame.pixel(w[1].x_cm? as f64, w[1].y_cm? as f64)))
        .unwrap_or(end);
    let marked = |p: (i32, i32)| {
        [start, end, hit]
            .iter()
            .any(|m| (m.0 - p.0).abs() <= 10 && (m.1 - p.1).abs() <= 10)
    };
    for (x, y) in &positions {
        let p = frame.pixel(*x, *y);
        assert!(frame.pixels_x.contains(&p.0) && frame.pixels_y.contains(&p.1));
        assert!(
            marked(p) || near(p, path_colour),
            "no path drawn at ({x}, {y}) = pixel {p:?}"
        );
        east = east.max(*x);
        north = north.max(*y);
        west = west.min(*x);
    }
    // The picture agrees with the telemetry's shape: the path went east, then north (up on
    // the image), then west into the wall.
    let origin = frame.pixel(0.0, 0.0);
    assert!(frame.pixel(east, 0.0).0 > origin.0 + 20);
    assert!(frame.pixel(0.0, north).1 < origin.1 - 20);
    assert!(frame.pixel(west, 0.0).0 < origin.0 - 20);
    // Far from the path (a corner of the floor plot) there is no path colour.
    let corner = (frame.pixels_x.end - 5, frame.pixels_y.end - 5);
    assert!(!near(corner, path_colour));
    // The collision is marked at the west wall.
    let red = [
        droidctl::plot::COLLISION.0,
        droidctl::plot::COLLISION.1,
        droidctl::plot::COLLISION.2,
    ];
    let hit = samples
        .windows(2)
        .find(|w| w[1].collisions > w[0].collisions)
        .map(|w| (w[1].x_cm.unwrap() as f64, w[1].y_cm.unwrap() as f64))
        .expect("the run hit the wall");
    assert!(hit.0 < -150.0);
    assert!(
        near(frame.pixel(hit.0, hit.1), red),
        "collision mark at {hit:?}"
    );
}

fn stdout_of(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap()
}
