//! The app's colours follow `NO_COLOR` (<https://no-color.org>) and `[display] theme`: the
//! real binary in a pseudo-terminal, every cell of the screen read back.
#![cfg(unix)]

use crate::common::pty::Tui;
use std::time::Duration;

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("droidctl-theme-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The app on a simulated BOLT with `env` and the config text `config`: the coloured cells
/// once it is connected.
fn coloured(name: &str, env: &[(&str, &str)], config: &str) -> usize {
    let dir = scratch(name);
    let config_path = dir.join("config.toml");
    std::fs::write(&config_path, config).unwrap();
    let (cfg, log, state) = (
        config_path.display().to_string(),
        dir.join("droidctl.log").display().to_string(),
        dir.join("state").display().to_string(),
    );
    let mut all: Vec<(&str, &str)> = vec![
        ("DROIDCTL_CONFIG", &cfg),
        ("DROIDCTL_LOG_FILE", &log),
        ("DROIDCTL_STATE_DIR", &state),
    ];
    all.extend_from_slice(env);
    let mut tui = Tui::spawn(&["--sim", "bolt"], &all, (80, 24), Some(&dir)).unwrap();
    tui.wait_for("connected", Duration::from_secs(20));
    // The gauges have drawn a few frames.
    std::thread::sleep(Duration::from_millis(500));
    let n = tui.coloured_cells();
    tui.send(b"q");
    assert!(tui.wait_exit(Duration::from_secs(10)).success());
    let _ = std::fs::remove_dir_all(&dir);
    n
}

#[test]
fn no_color_and_theme_none_draw_without_colour_and_dark_with() {
    let dark = coloured("dark", &[("NO_COLOR", "")], "");
    assert!(dark > 50, "the default theme has colours: {dark} cells");
    assert_eq!(coloured("nocolor", &[("NO_COLOR", "1")], ""), 0);
    assert_eq!(coloured("none", &[], "[display]\ntheme = \"none\"\n"), 0);
    let light = coloured("light", &[], "[display]\ntheme = \"light\"\n");
    assert!(light > 50, "light has colours too: {light} cells");
}

/// Issue 39 point 13: the device picker shown before the app (several droids behind a relay,
/// as in Bluetooth range) is drawn in the app's colours too: none under `NO_COLOR` or
/// `theme = "none"` (it was always coloured), colours otherwise.
#[test]
fn the_device_picker_follows_no_color_and_the_theme() {
    use crate::relay_e2e::{Serve, TempDir};
    let dir = TempDir::new("theme-picker");
    let serve = Serve::start(&["r2d2", "bolt"], &[], &dir);
    let picker_cells = |name: &str, env: &[(&str, &str)], config: &str| -> usize {
        let config_path = dir.path(&format!("{name}.toml"));
        std::fs::write(&config_path, config).unwrap();
        let (log, state) = (
            dir.path(&format!("{name}.log")),
            dir.path(&format!("{name}-state")),
        );
        let mut all: Vec<(&str, &str)> = vec![
            ("DROIDCTL_CONFIG", &config_path),
            ("DROIDCTL_LOG_FILE", &log),
            ("DROIDCTL_STATE_DIR", &state),
            (
                "DBUS_SYSTEM_BUS_ADDRESS",
                "unix:path=/nonexistent/droidctl-test/bus",
            ),
        ];
        all.extend_from_slice(env);
        let mut tui = Tui::spawn(&["--remote", &serve.address], &all, (80, 24), None).unwrap();
        let screen = tui.wait_for("Several droids are in range", Duration::from_secs(20));
        assert!(screen.contains("Sphero BOLT"), "{screen}");
        let n = tui.coloured_cells();
        // q cancels the picker: nothing is driven.
        tui.send(b"q");
        let _ = tui.wait_exit(Duration::from_secs(10));
        n
    };
    let dark = picker_cells("dark", &[("NO_COLOR", "")], "");
    assert!(
        dark > 20,
        "the default theme colours the picker: {dark} cells"
    );
    assert_eq!(picker_cells("nocolor", &[("NO_COLOR", "1")], ""), 0);
    assert_eq!(
        picker_cells("none", &[], "[display]\ntheme = \"none\"\n"),
        0
    );
    serve.stop();
}
