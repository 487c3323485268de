//! `droidctl plot` with fleets and careless or hostile inputs (issue 27 point 6): a fleet's
//! `run --json` and a fleet capture are drawn one droid per colour, named in the legend;
//! `--channels` is deduplicated and limited to what stays legible; `plot X.png` never writes
//! over its input; an empty file is exit 1, bad input exit 2; yaw wrapping at ±180° is no
//! vertical stroke.

use droidctl::telemetry::history::Channel;

use crate::common::scratch;
use scratch::{Scratch, path, stderr, stdout};

const FLEET: &str = "@D2-0001 stance tripod\ntogether {\n  @D2-0001 drive 100 0 for 2s\n  @BB-0002 drive 100 180 for 2s\n}\n";

fn hex(c: plotters::style::RGBColor) -> String {
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

fn plot_svg(dir: &Scratch, input: &std::path::Path, extra: &[&str]) -> String {
    let svg = dir.0.join("out.svg");
    // Each call draws over the last picture.
    let mut args = vec!["plot", path(input), "-o", path(&svg), "--force"];
    args.extend(extra);
    let o = dir.run(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    std::fs::read_to_string(&svg).unwrap()
}

#[test]
fn a_fleet_is_drawn_one_droid_per_colour_named_in_the_legend() {
    let dir = Scratch::new("plot", "fleet");
    let script = dir.file("m.txt", FLEET);
    let cap = dir.0.join("cap.txt");
    let o = dir.run(&[
        "run",
        path(&script),
        "--sim",
        "r2d2,bb8",
        "--json",
        "--record",
        path(&cap),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let jsonl = dir.file("run.jsonl", &stdout(&o));
    // From the fleet's JSON lines, and from its capture.
    for input in [&jsonl, &cap] {
        let svg = plot_svg(&dir, input, &[]);
        for (i, name) in ["D2-0001", "BB-0002"].iter().enumerate() {
            assert!(svg.contains(name), "{input:?}: the legend names {name}");
            let colour = hex(droidctl::plot::DROID_COLOURS[i]);
            assert!(
                svg.contains(&format!("stroke=\"{colour}\"")),
                "{input:?}: {name} in {colour}"
            );
        }
        // No path joins the two droids: each droid's path stays on its own side.
        assert!(
            !svg.contains(">path<"),
            "{input:?}: no anonymous path in a fleet"
        );
    }
}

#[test]
fn channels_are_deduplicated_and_limited_to_what_stays_legible() {
    let dir = Scratch::new("plot", "channels");
    let script = dir.file("m.txt", "stance tripod\ndrive 100 0 for 1s\n");
    let o = dir.run(&["run", path(&script), "--sim", "--json"]);
    let jsonl = dir.file("run.jsonl", &stdout(&o));
    let many = vec!["speed"; 5000].join(",");
    let svg = plot_svg(&dir, &jsonl, &["--channels", &many]);
    assert_eq!(svg.matches("speed (cm/s)").count(), 1, "one strip");
    assert!(svg.len() < 2_000_000, "{} bytes", svg.len());
    // At 1200x900 five strips fit; six are refused, saying how many fit.
    let fit = droidctl::plot::strips_that_fit(900);
    assert_eq!(fit, 5);
    let six = "speed,yaw,pitch,roll,gyro_x,gyro_y";
    let o = dir.run(&["plot", path(&jsonl), "--channels", six, "-o", "x.svg"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("5 fit"), "{}", stderr(&o));
    let five = "speed,yaw,pitch,roll,gyro_x";
    plot_svg(&dir, &jsonl, &["--channels", five]);
    // Taller pictures hold more.
    plot_svg(&dir, &jsonl, &["--channels", six, "--size", "1200x1200"]);
}

#[test]
fn plot_never_writes_over_its_input() {
    let dir = Scratch::new("plot", "own-input");
    let script = dir.file("m.txt", "stance tripod\ndrive 100 0 for 1s\n");
    let o = dir.run(&["run", path(&script), "--sim", "--json"]);
    let data = stdout(&o);
    let input = dir.file("run.png", &data);
    let o = dir.run(&["plot", path(&input)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&input).unwrap(),
        data,
        "the input is kept"
    );
    assert!(dir.0.join("run.plot.png").exists());
    let o = dir.run(&["plot", path(&input), "-o", path(&input)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("overwrite"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&input).unwrap(), data);
}

#[test]
fn an_empty_file_and_bad_input_are_both_exit_2() {
    let dir = Scratch::new("plot", "exit");
    // An input with nothing to plot is bad input, as every command says of its inputs
    // (docs/exit-status.md).
    for (text, code) in [
        ("", 2),
        ("\n\n", 2),
        ("hello\n", 2),
        ("{\"t_ms\": \n", 2),
        ("{\"x\": 1}\n", 2),
        ("droidctl-capture 9\n", 2),
        ("droidctl-capture 2\n@1 0.000 connect\n", 2),
    ] {
        let f = dir.file("in.txt", text);
        let o = dir.run(&["plot", path(&f), "-o", "o.svg"]);
        assert_eq!(o.status.code(), Some(code), "{text:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
    }
    // A line of megabytes is bad input, said with its line, not read whole.
    let f = dir.file(
        "long.txt",
        &format!("{{\"t_ms\": {}}}\n", "1".repeat(200_000)),
    );
    let o = dir.run(&["plot", path(&f), "-o", "o.svg"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains(":1:"), "{}", stderr(&o));
}

#[test]
fn yaw_wrapping_at_180_is_no_vertical_stroke() {
    let mut samples = Vec::new();
    for i in 0..40u64 {
        let mut s =
            droidctl::mission::sample_of(&droidctl::telemetry::Telemetry::default(), i * 100);
        // Turning steadily: 160° up through 180° to -160°.
        let yaw = 160.0 + i as f32 * 1.0;
        s.yaw_deg = Some(if yaw > 180.0 { yaw - 360.0 } else { yaw });
        s.x_cm = Some(0.0);
        s.y_cm = Some(0.0);
        samples.push(s);
    }
    let run = droidctl::plot::Run::of_samples("yaw", &samples, &[Channel::Yaw]);
    let svg = droidctl::plot::svg(&run, (900, 700)).unwrap();
    let colour = hex(droidctl::plot::CHANNEL_COLOURS[0]);
    let lines: Vec<&str> = svg
        .lines()
        .filter(|l| l.contains("<polyline") && l.contains(&colour))
        .collect();
    assert_eq!(lines.len(), 2, "one run each side of the wrap: {lines:?}");
}
