//! `droidctl config path|init|check`, and an invalid config keeping the app from starting.

use std::process::{Command, Output, Stdio};

fn droidctl(dir: &std::path::Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .env("DROIDCTL_CONFIG", dir.join("droidctl/config.toml"))
        .env("DROIDCTL_LOG_FILE", dir.join("log"))
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn tmp(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("droidctl-cfg-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn path_init_check() {
    let d = tmp("init");
    // No file yet in the usual place: check says the defaults are in use, not `ok`.
    let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["config", "check"])
        .env_remove("DROIDCTL_CONFIG")
        .env("XDG_CONFIG_HOME", &d)
        .env("HOME", &d)
        .env("DROIDCTL_LOG_FILE", d.join("log"))
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let said = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(said.contains("no file; the defaults are in use"), "{said}");
    assert!(!said.contains(": ok"), "{said}");
    let out = droidctl(&d, &["config", "path"]);
    assert!(out.status.success());
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        d.join("droidctl/config.toml").to_str().unwrap()
    );

    let out = droidctl(&d, &["config", "init"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let written = std::fs::read_to_string(d.join("droidctl/config.toml")).unwrap();
    assert_eq!(written, droidctl::config::DEFAULT_TOML);

    // An existing file without --force is bad input, as for every file droidctl writes.
    let out = droidctl(&d, &["config", "init"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--force"));
    assert!(
        droidctl(&d, &["config", "init", "--force"])
            .status
            .success()
    );

    let out = droidctl(&d, &["config", "check"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains(": ok"));
}

#[test]
fn an_invalid_file_is_reported_and_the_app_refuses_to_start() {
    let d = tmp("bad");
    std::fs::create_dir_all(d.join("droidctl")).unwrap();
    std::fs::write(
        d.join("droidctl/config.toml"),
        "[control]\ncruise_speed = 50\nrate_hz = 500\n",
    )
    .unwrap();
    for args in [
        &["config", "check"][..],
        &["--sim"][..],
        &["drive", "--sim"][..],
    ] {
        let out = droidctl(&d, args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("config.toml:3: key `control.rate_hz`"),
            "{args:?}: {err}"
        );
        assert!(err.contains("1..=50"), "{err}");
        // Refused before taking over the terminal.
        assert!(!String::from_utf8_lossy(&out.stdout).contains("\x1b[?1049h"));
    }
    std::fs::write(
        d.join("droidctl/config.toml"),
        "[keys]\nforward = [\"Hyper+w\"]\n",
    )
    .unwrap();
    let out = droidctl(&d, &["--sim"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err.contains(":2: key `keys.forward`") && err.contains("Hyper+w"),
        "{err}"
    );
}

/// `config check` on `text` fails with status 2 and says each of `expect`.
fn check_refuses(tag: &str, text: &str, expect: &[&str]) {
    let d = tmp(tag);
    std::fs::create_dir_all(d.join("droidctl")).unwrap();
    std::fs::write(d.join("droidctl/config.toml"), text).unwrap();
    let out = droidctl(&d, &["config", "check"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for e in expect {
        assert!(err.contains(e), "{e:?} not in {err}");
    }
}

#[test]
fn every_gamepad_button_is_checked_aim_included() {
    check_refuses(
        "aim",
        "[gamepad]\ndeadzone = 0.2\naim = \"RightBumpr\"\n",
        &[
            "config.toml:3: key `gamepad.aim`",
            "unknown button \"RightBumpr\"",
        ],
    );
}

#[test]
fn context_bindings_are_checked_with_their_line() {
    check_refuses(
        "ctx",
        "[keys]\nforward = [\"Up\"]\n\n[keys.replay]\nstep = [\"Right\"]\n",
        &["config.toml:5: key `keys.replay.step`", "replay.forward"],
    );
}

#[test]
fn droidctl_config_naming_a_missing_file_is_an_error() {
    let d = tmp("missing");
    let out = droidctl(&d, &["config", "check"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!String::from_utf8_lossy(&out.stdout).contains("ok"));
    assert!(
        err.contains("droidctl/config.toml") && err.contains("no such file"),
        "{err}"
    );
    // /dev/null asks for the defaults.
    let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["config", "check"])
        .env("DROIDCTL_CONFIG", "/dev/null")
        .output()
        .unwrap();
    assert!(out.status.success());
}

/// `config show`: every value in effect with where it came from, then what the app
/// remembers per model (it wins over both).
#[test]
fn show_says_where_each_value_comes_from() {
    let d = tmp("show");
    std::fs::create_dir_all(d.join("droidctl")).unwrap();
    std::fs::write(
        d.join("droidctl/config.toml"),
        "[control]\ncruise_speed = 60\n",
    )
    .unwrap();
    let state = d.join("state");
    std::fs::create_dir_all(&state).unwrap();
    std::fs::write(state.join("settings-r2d2.toml"), "cruise = 145\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(["config", "show"])
        .env("DROIDCTL_CONFIG", d.join("droidctl/config.toml"))
        .env("DROIDCTL_LOG_FILE", d.join("log"))
        .env("DROIDCTL_STATE_DIR", &state)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("cruise_speed = 60  # file"), "{text}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("speed_step = ") && l.ends_with("# default")),
        "{text}"
    );
    assert!(text.contains("[remembered.r2d2]"), "{text}");
    assert!(text.contains("cruise = 145  # remembered"), "{text}");
    // The configuration part is the configuration: it reads back as the same one.
    let config_part = text.split("\n# remembered").next().unwrap();
    let back = droidctl::config::Config::parse_merged(None, config_part).unwrap();
    let direct =
        droidctl::config::Config::parse_merged(None, "[control]\ncruise_speed = 60\n").unwrap();
    assert_eq!(back, direct);
}
