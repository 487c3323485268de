//! Issue 19 point 2: the newer robots' panels by capability — BOLT's matrix panel shows what
//! the matrix shows, in colour, beside the compass heading and ambient light; RVR's shows its
//! colour sensor, motor faults and, in tank mode, its tracks; Mini keeps the lights panel.
//! Snapshots at 80×24 and 160×48 (`INSTA_UPDATE=always cargo test --test it ui_robots::` after an
//! intended change, then read every changed `.snap`).

use droidctl::app::state::{AppState, Overlay};
use droidctl::app::view::matrix::{MatrixShows, MatrixView};
use droidctl::model::Model;
use droidctl::session::LinkState;
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::buffer::Buffer;
use ratatui::style::Color;
use std::time::Duration;

fn render(state: &AppState, w: u16, h: u16) -> Terminal<TestBackend> {
    let mut term = Terminal::new(TestBackend::new(w, h)).unwrap();
    term.draw(|f| droidctl::ui::draw(f, state)).unwrap();
    term
}

fn rows(buf: &Buffer) -> Vec<String> {
    (0..buf.area.height)
        .map(|y| {
            (0..buf.area.width)
                .map(|x| buf[(x, y)].symbol().to_string())
                .collect()
        })
        .collect()
}

fn connected(model: Model, name: &str) -> AppState {
    let mut s = AppState::new(model, name.into());
    s.now = Duration::from_secs(20);
    s.droid_mut().link = LinkState::Connected;
    let t = &mut s.droid_mut().telemetry;
    t.yaw = Some(90.0);
    t.x_cm = Some(40.0);
    t.y_cm = Some(3.0);
    t.battery_v = Some(3.9);
    s
}

fn bolt() -> AppState {
    bolt_like(Model::Bolt, "SB-5A1C")
}

/// BOLT, or BOLT+, showing a red 'A', calibrated, in 320 lx.
fn bolt_like(model: Model, name: &str) -> AppState {
    let mut s = connected(model, name);
    s.droid_mut().matrix = MatrixView {
        colour: [255, 0, 0],
        shows: MatrixShows::Char('A'),
    };
    s.droid_mut().telemetry.robot.compass_north = Some(270);
    s.droid_mut().telemetry.robot.ambient_lux = Some(320.0);
    s
}

fn rvr() -> AppState {
    let mut s = connected(Model::Rvr, "RV-F00D");
    s.droid_mut().telemetry.robot.color = Some(([0, 200, 40], 3, 0.9));
    s.droid_mut().telemetry.robot.stalled = [true, false];
    s.droid_mut().control.tank = Some((200, -100));
    s.droid_mut().control.source = "tank";
    s
}

#[test]
fn bolt_matrix_panel_shows_the_character_in_its_colour_and_the_compass() {
    for (w, h) in [(80, 24), (160, 48)] {
        let term = render(&bolt(), w, h);
        let buf = term.backend().buffer();
        let text = rows(buf);
        let all = text.join("\n");
        assert!(all.contains("Matrix"), "{w}×{h}: {all}");
        assert!(all.contains("'A' #ff0000"), "{w}×{h}: {all}");
        // Facing yaw 90 with north at yaw 270: heading 180.
        assert!(all.contains("180°"), "the compass: {all}");
        assert!(all.contains("320 lx"), "the light: {all}");
        assert!(!all.contains(" Dome "), "{all}");
        // The character (or its swatch) is painted in the matrix's colour.
        let (y, row) = text
            .iter()
            .enumerate()
            .find(|(_, r)| r.contains("'A'"))
            .expect("the shows line");
        let col = row.chars().position(|c| c == '■').expect("swatch") as u16;
        assert_eq!(buf[(col, y as u16)].fg, Color::Rgb(255, 0, 0));
    }
    // With room, the matrix itself: scrolling text in green.
    let mut s = bolt();
    s.droid_mut().matrix = MatrixView {
        colour: [0, 255, 0],
        shows: MatrixShows::Text("HELLO".into()),
    };
    let term = render(&s, 160, 48);
    let all = rows(term.backend().buffer()).join("\n");
    assert!(all.contains("scrolling \"HELLO\""), "{all}");
}

/// Issue 41: BOLT+ has a screen where BOLT has its matrix: the panel in the matrix's place is
/// the screen, showing the 8×8 picture the frame-player commands drew (all sphero-unsw
/// describes of the screen), with BOLT's compass and light.
#[test]
fn boltplus_shows_its_screen_not_a_matrix() {
    for (w, h) in [(80, 24), (160, 48)] {
        let s = bolt_like(Model::BoltPlus, "BP-81C4");
        let all = rows(render(&s, w, h).backend().buffer()).join("\n");
        assert!(all.contains("Screen"), "{w}×{h}: {all}");
        assert!(!all.contains(" Matrix "), "{w}×{h}: {all}");
        assert!(all.contains("'A' #ff0000"), "{w}×{h}: {all}");
        assert!(all.contains("320 lx"), "the light: {all}");
    }
}

#[test]
fn rvr_panel_shows_the_floor_colour_a_stalled_motor_and_the_tracks() {
    for (w, h) in [(80, 24), (160, 48)] {
        let term = render(&rvr(), w, h);
        let buf = term.backend().buffer();
        let text = rows(buf);
        let all = text.join("\n");
        assert!(all.contains("Rover") && all.contains("TANK"), "{all}");
        assert!(all.contains("left motor stalled"), "{all}");
        assert!(all.contains("0,200,40"), "{all}");
        let (y, row) = text
            .iter()
            .enumerate()
            .find(|(_, r)| r.contains("floor"))
            .expect("floor line");
        let col = row.chars().position(|c| c == '■').expect("swatch") as u16;
        assert_eq!(buf[(col, y as u16)].fg, Color::Rgb(0, 200, 40));
    }
    let term = render(&rvr(), 160, 48);
    let all = rows(term.backend().buffer()).join("\n");
    assert!(all.contains("tracks L +200 R -100"), "{all}");
}

/// Issue 39 point 13, seen at 80×24: RVR's floor line was cut mid-word ("(90% su"); it says
/// the colour in fewer words where the panel is narrow, never cut.
#[test]
fn rvr_floor_words_are_never_cut() {
    let mut s = rvr();
    s.droid_mut().telemetry.robot.color = Some(([128, 128, 128], 12, 1.0));
    for (w, h) in [(80, 24), (100, 30), (120, 40), (160, 48)] {
        let text = rows(render(&s, w, h).backend().buffer());
        let row = text
            .iter()
            .find(|r| r.contains("floor"))
            .unwrap_or_else(|| panic!("floor line at {w}×{h}"));
        let cell = row
            .split('│')
            .find(|c| c.contains("floor"))
            .expect("the panel's cell");
        assert!(cell.contains("128,128,128 · colour 12"), "{w}×{h}: {cell}");
        assert!(
            cell.trim_end().ends_with("100% sure)") || cell.trim_end().ends_with("100%"),
            "{w}×{h}: {cell}"
        );
        assert!(!cell.contains('…'), "{w}×{h}: {cell}");
    }
}

#[test]
fn mini_keeps_the_lights_panel_and_the_matrix_prompt_says_what_it_draws() {
    let term = render(&connected(Model::Mini, "SM-0B12"), 80, 24);
    let all = rows(term.backend().buffer()).join("\n");
    assert!(all.contains("Lights"), "{all}");
    let mut s = bolt();
    s.overlay = Overlay::Matrix { input: "Z".into() };
    let all = rows(render(&s, 80, 24).backend().buffer()).join("\n");
    assert!(
        all.contains("On the matrix") && all.contains("draws 'Z'"),
        "{all}"
    );
}

#[test]
fn snapshots() {
    for (name, s) in [("bolt", bolt()), ("rvr", rvr())] {
        for (w, h) in [(80u16, 24u16), (160, 48)] {
            let term = render(&s, w, h);
            insta::assert_snapshot!(format!("{name}_{w}x{h}"), term.backend());
        }
    }
}
