//! End to end: the real binary with `--sim` in a pseudo-terminal. Keys go in, the screen is
//! read back through a VT100 emulator; the simulated droid must move, the packet log must show
//! the drive commands, `q` must quit with a stop and the terminal must be restored.

// Unix pseudo-terminals and `kill`.
#![cfg(unix)]

use portable_pty::{CommandBuilder, PtySize, native_pty_system};
use std::io::{Read, Write};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

struct Tui {
    raw: Arc<Mutex<Vec<u8>>>,
    screen: Arc<Mutex<vt100::Parser>>,
    writer: Arc<Mutex<Box<dyn Write + Send>>>,
    child: Box<dyn portable_pty::Child + Send + Sync>,
    _dir: TempDir,
}

/// A scratch directory removed on drop.
struct TempDir(std::path::PathBuf);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        let p = std::env::temp_dir().join(format!("droidctl-e2e-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        TempDir(p)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

impl Tui {
    /// Start `droidctl --sim` at `cols`×`rows`. `kitty`: answer the keyboard-protocol query
    /// as a terminal that supports it.
    fn start(cols: u16, rows: u16, kitty: bool) -> Tui {
        Self::start_with(cols, rows, kitty, &[])
    }

    /// As [`Tui::start`], with extra environment variables.
    fn start_with(cols: u16, rows: u16, kitty: bool, env: &[(&str, &str)]) -> Tui {
        Self::start_full(cols, rows, kitty, env, &[])
    }

    /// As [`Tui::start_with`], with arguments after `--sim` (e.g. the model: `bb8`).
    fn start_full(cols: u16, rows: u16, kitty: bool, env: &[(&str, &str)], args: &[&str]) -> Tui {
        let tag = if kitty { "kitty" } else { "legacy" };
        // One directory per app started: tests run in parallel in one process, and two that
        // shared a directory deleted each other's log (the SIGTERM test then read no log).
        static STARTED: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let n = STARTED.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = TempDir::new(&format!("{tag}{}{}-{n}", env.len(), args.join("-")));
        let pty = native_pty_system()
            .openpty(PtySize {
                rows,
                cols,
                pixel_width: 0,
                pixel_height: 0,
            })
            .unwrap();
        let mut cmd = CommandBuilder::new(env!("CARGO_BIN_EXE_droidctl"));
        cmd.arg("--sim");
        cmd.args(args);
        cmd.env("TERM", "xterm-256color");
        cmd.env("DROIDCTL_LOG_FILE", dir.0.join("droidctl.log"));
        cmd.env("DROIDCTL_CONFIG", "/dev/null");
        // Remembered settings stay in the test's directory (each run starts from defaults).
        cmd.env("DROIDCTL_STATE_DIR", dir.0.join("state"));
        for (k, v) in env {
            cmd.env(k, v);
        }
        let child = pty.slave.spawn_command(cmd).unwrap();
        drop(pty.slave);
        let mut reader = pty.master.try_clone_reader().unwrap();
        // One writer, shared: the test types on it and the reader thread answers queries.
        let writer = Arc::new(Mutex::new(pty.master.take_writer().unwrap()));
        let raw = Arc::new(Mutex::new(Vec::new()));
        let screen = Arc::new(Mutex::new(vt100::Parser::new(
            rows.try_into().unwrap(),
            cols.try_into().unwrap(),
            0,
        )));
        let answer = writer.clone();
        {
            let (raw, screen) = (raw.clone(), screen.clone());
            std::thread::spawn(move || {
                let _keep_master = pty.master;
                let mut buf = [0u8; 8192];
                while let Ok(n) = reader.read(&mut buf) {
                    if n == 0 {
                        break;
                    }
                    let chunk = &buf[..n];
                    raw.lock().unwrap().extend_from_slice(chunk);
                    screen.lock().unwrap().process(chunk);
                    // Play the terminal's part in crossterm's capability probe.
                    if chunk.windows(4).any(|w| w == b"\x1b[?u") {
                        let mut w = answer.lock().unwrap();
                        if kitty {
                            let _ = w.write_all(b"\x1b[?0u");
                        }
                        let _ = w.write_all(b"\x1b[?62;c");
                        let _ = w.flush();
                    }
                }
            });
        }
        Tui {
            raw,
            screen,
            writer,
            child,
            _dir: dir,
        }
    }

    fn text(&self) -> String {
        self.screen.lock().unwrap().screen().contents()
    }

    fn wait_for(&self, what: &str, limit: Duration) -> String {
        let start = Instant::now();
        loop {
            let t = self.text();
            if t.contains(what) {
                return t;
            }
            assert!(
                start.elapsed() < limit,
                "timed out waiting for {what:?}; screen:\n{t}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn send(&mut self, bytes: &[u8]) {
        let mut w = self.writer.lock().unwrap();
        w.write_all(bytes).unwrap();
        w.flush().unwrap();
    }

    /// Hold a key the way a legacy terminal reports it: a press, then auto-repeats.
    fn hold(&mut self, key: &[u8], for_: Duration) {
        let start = Instant::now();
        while start.elapsed() < for_ {
            self.send(key);
            std::thread::sleep(Duration::from_millis(40));
        }
    }

    fn wait_exit(&mut self, limit: Duration) -> portable_pty::ExitStatus {
        let start = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                // Let the reader thread take the last bytes.
                std::thread::sleep(Duration::from_millis(200));
                return status;
            }
            assert!(
                start.elapsed() < limit,
                "droidctl did not exit; screen:\n{}",
                self.text()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn raw(&self) -> Vec<u8> {
        self.raw.lock().unwrap().clone()
    }
}

fn pos(bytes: &[u8], needle: &[u8]) -> Option<usize> {
    bytes.windows(needle.len()).rposition(|w| w == needle)
}

/// The droid's y position as shown in the sensors panel ("pos x … y … cm").
fn shown_y(screen: &str) -> Option<f32> {
    let line = screen.lines().find(|l| l.contains("pos x"))?;
    let after = &line[line.find(" y ")? + 3..];
    after.split_whitespace().next()?.parse().ok()
}

#[test]
fn drive_the_simulated_droid_and_quit() {
    let mut tui = Tui::start(100, 30, false);
    tui.wait_for("connected", Duration::from_secs(20));
    tui.wait_for("stance tripod", Duration::from_secs(10));
    let before = shown_y(&tui.text()).unwrap_or(0.0);
    // Hold w for 2.5 s (press plus auto-repeat), then let go.
    tui.hold(b"w", Duration::from_millis(2500));
    std::thread::sleep(Duration::from_millis(800));
    let screen = tui.text();
    let after = shown_y(&screen).expect("position on screen");
    assert!(
        after > before + 30.0,
        "the droid moved forward: {before} → {after}\n{screen}"
    );
    assert!(
        screen.contains("drive-with-heading"),
        "the packet log shows drive commands:\n{screen}"
    );
    assert!(
        screen.contains("emulated"),
        "keyboard mode shown:\n{screen}"
    );
    // Help overlay lists the keys.
    tui.send(b"?");
    let help = tui.wait_for("EMERGENCY STOP", Duration::from_secs(5));
    assert!(
        help.contains("drive forward (hold)") && help.contains("quit"),
        "{help}"
    );
    tui.send(b"?");
    std::thread::sleep(Duration::from_millis(300));
    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
    let raw = tui.raw();
    // Terminal restored: alternate screen left after it was entered, cursor shown.
    let entered = pos(&raw, b"\x1b[?1049h").expect("entered the alternate screen");
    let left = pos(&raw, b"\x1b[?1049l").expect("left the alternate screen");
    assert!(left > entered);
    assert!(
        pos(&raw, b"\x1b[?25h").is_some_and(|p| p > entered),
        "cursor shown again"
    );
    assert!(
        pos(&raw, b"\x1b[?1004l").is_some(),
        "focus reporting turned off"
    );
}

#[test]
fn kitty_terminal_gets_release_events_and_flags_are_popped() {
    let mut tui = Tui::start(100, 30, true);
    tui.wait_for("connected", Duration::from_secs(20));
    tui.wait_for("release events", Duration::from_secs(5));
    tui.wait_for("stance tripod", Duration::from_secs(10));
    // Press w once (kitty: no auto-repeat needed while held) ...
    tui.send(b"\x1b[119u");
    std::thread::sleep(Duration::from_millis(1500));
    let moving = tui.text();
    assert!(
        moving.contains("speed 100/255"),
        "driving while held:\n{moving}"
    );
    // ... release it: the deadman stops the droid.
    tui.send(b"\x1b[119;1:3u");
    std::thread::sleep(Duration::from_millis(800));
    let stopped = tui.text();
    assert!(
        stopped.contains("speed   0/255"),
        "stopped on release:\n{stopped}"
    );
    tui.send(b"\x1b[113u");
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
    let raw = tui.raw();
    let pushed = pos(&raw, b"\x1b[>").expect("keyboard flags pushed");
    let popped = pos(&raw, b"\x1b[<1u").expect("keyboard flags popped");
    assert!(popped > pushed);
}

impl Tui {
    fn pid(&self) -> u32 {
        self.child.process_id().expect("pid")
    }

    fn log(&self) -> String {
        std::fs::read_to_string(self._dir.0.join("droidctl.log")).unwrap_or_default()
    }
}

/// The final stop written by the session on the way out, per the log.
fn final_stop_logged(log: &str) -> bool {
    log.lines().any(|l| {
        l.contains("final command") && l.contains("drive-with-heading") && l.contains("data=00 ")
    }) && log.contains("final commands written")
}

#[test]
fn sigterm_stops_the_droid_then_restores_the_terminal() {
    let mut tui = Tui::start(100, 30, false);
    tui.wait_for("stance tripod", Duration::from_secs(20));
    tui.hold(b"w", Duration::from_millis(800));
    let pid = tui.pid();
    let _ = std::process::Command::new("kill")
        .args(["-TERM", &pid.to_string()])
        .status();
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
    assert!(final_stop_logged(&tui.log()), "log:\n{}", tui.log());
    let raw = tui.raw();
    assert!(pos(&raw, b"\x1b[?1049l") > pos(&raw, b"\x1b[?1049h"));
    assert!(String::from_utf8_lossy(&raw).contains("SIGTERM: stopped the droid"));
}

#[test]
#[cfg_attr(
    not(feature = "test-hooks"),
    ignore = "the crash hook is built only with `--features test-hooks` (as .ci/run tests)"
)]
fn a_crash_stops_the_droid_then_restores_the_terminal() {
    let mut tui = Tui::start_with(100, 30, false, &[("DROIDCTL_TEST_PANIC_AFTER_MS", "4000")]);
    tui.wait_for("stance tripod", Duration::from_secs(20));
    // Drive into the crash.
    let start = Instant::now();
    let status = loop {
        // The child may already be gone: a failed write is fine here.
        let _ = tui.writer.lock().unwrap().write_all(b"w");
        if let Some(s) = tui.child.try_wait().unwrap() {
            std::thread::sleep(Duration::from_millis(200));
            break s;
        }
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "no exit after the crash"
        );
        std::thread::sleep(Duration::from_millis(40));
    };
    assert_eq!(status.exit_code(), 101, "{status:?}");
    assert!(final_stop_logged(&tui.log()), "log:\n{}", tui.log());
    let raw = tui.raw();
    let text = String::from_utf8_lossy(&raw);
    let left = pos(&raw, b"\x1b[?1049l").expect("left the alternate screen");
    let message = text
        .find("internal error, the droid was sent a stop")
        .expect("crash message");
    assert!(pos(&raw, b"\x1b[?1049h").unwrap() < left);
    // The message comes after the terminal was restored, so it stays readable.
    assert!(message > String::from_utf8_lossy(&raw[..left]).len());
}

/// The droid's yaw as shown in the sensors panel ("… yaw 63.0°").
fn shown_yaw(screen: &str) -> Option<f32> {
    let line = screen.lines().find(|l| l.contains("pitch"))?;
    let after = &line[line.find("yaw ")? + 4..];
    after.split('°').next()?.trim().parse().ok()
}

/// A v1 droid in the app: BB-8 has no dome, so the Lights panel takes its place; `c` sets
/// the main LED; aim mode (`o`) turns the back light on and, pressed again, sets heading 0
/// (v1 Set Heading); `w` drives it forward.
#[test]
fn bb8_shows_lights_aims_and_drives() {
    let mut tui = Tui::start_full(100, 30, false, &[], &["bb8"]);
    tui.wait_for("connected", Duration::from_secs(20));
    let screen = tui.wait_for("Lights", Duration::from_secs(10));
    assert!(
        !screen.contains(" Dome "),
        "no Dome panel on BB-8:\n{screen}"
    );
    assert!(screen.contains("BB-8"), "{screen}");
    // Telemetry streams: the position readout appears.
    tui.wait_for("pos x", Duration::from_secs(10));
    // The colour key sets the main LED: red first.
    assert!(screen.contains("not set"), "{screen}");
    tui.send(b"c");
    tui.wait_for("255,0,0", Duration::from_secs(5));
    tui.wait_for("set-rgb-led", Duration::from_secs(5));

    // Aim mode on: the Lights panel says so, the back light is lit.
    tui.send(b"o");
    let aiming = tui.wait_for("AIMING", Duration::from_secs(5));
    assert!(aiming.contains("aim"), "{aiming}");
    tui.wait_for("back 255/255", Duration::from_secs(5));
    // Turning while aiming rotates the droid in place.
    tui.hold(b"d", Duration::from_millis(600));
    std::thread::sleep(Duration::from_millis(500));
    let turned = tui.text();
    let yaw = shown_yaw(&turned).expect("yaw on screen");
    assert!(yaw > 20.0, "turned right in place: yaw {yaw}\n{turned}");
    assert_eq!(shown_y(&turned), Some(0.0), "without rolling:\n{turned}");
    // Aim mode off: the facing becomes heading 0.
    tui.send(b"o");
    let set = tui.wait_for("heading set", Duration::from_secs(5));
    assert!(!set.contains("AIMING"), "{set}");
    let log = tui.wait_for("set-heading", Duration::from_secs(5));
    assert!(
        log.contains("back off"),
        "back light off after aiming:\n{log}"
    );
    // The droid's facing is now its heading 0.
    std::thread::sleep(Duration::from_millis(400));
    let zeroed = tui.text();
    let yaw = shown_yaw(&zeroed).expect("yaw on screen");
    assert!(yaw.abs() < 1.0, "yaw {yaw} after Set Heading 0\n{zeroed}");

    // Forward is where it faced: y grows.
    let before = shown_y(&tui.text()).unwrap_or(0.0);
    tui.hold(b"w", Duration::from_millis(2500));
    std::thread::sleep(Duration::from_millis(800));
    let screen = tui.text();
    let after = shown_y(&screen).expect("position on screen");
    assert!(
        after > before + 30.0,
        "the droid moved forward: {before} → {after}\n{screen}"
    );
    assert!(
        screen.contains("roll"),
        "the packet log shows v1 Roll commands:\n{screen}"
    );
    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
}

/// A wheel's speed as shown in the Motors panel ("L  3.92 ████░░ …"), rad/s; `side` is
/// "L" or "R".
fn shown_motor(screen: &str, side: &str) -> Option<f32> {
    let line = screen
        .lines()
        .find(|l| l.contains("L ") && l.contains(" R ") && l.contains('░'))?;
    let at = line.find(&format!("{side} "))? + side.len() + 1;
    line[at..].split_whitespace().next()?.parse().ok()
}

/// The frame id in the Robi panel's title (" Robi · frame 16777167 ").
fn shown_frame_id(screen: &str) -> Option<u32> {
    let at = screen.find("Robi · frame ")? + "Robi · frame ".len();
    screen[at..].split_whitespace().next()?.parse().ok()
}

/// The measured link rate in the Robi panel ("link 10/s announced …").
fn shown_link_rate(screen: &str) -> Option<f32> {
    let line = screen.lines().find(|l| l.contains("announced"))?;
    let at = line.find("link ")? + 5;
    line[at..].split("/s").next()?.trim().parse().ok()
}

/// Robi 42 in the app: the Motors panel in the dome's place and the Robi panel (frame id,
/// poti, buttons, link quality measured against the announced rate, lost frames) in the
/// sensors' place; `w` turns both wheels, `s` is refused ("cannot reverse"), `q` quits with
/// a final stop.
#[test]
fn robi_shows_motors_and_io_drives_forward_refuses_reverse() {
    let mut tui = Tui::start_full(100, 30, false, &[], &["robi"]);
    tui.wait_for("connected", Duration::from_secs(20));
    let screen = tui.wait_for("Robi · frame ", Duration::from_secs(10));
    assert!(screen.contains("Motors"), "{screen}");
    assert!(
        !screen.contains(" Dome ") && !screen.contains("pitch"),
        "no dome or Sphero sensors on Robi:\n{screen}"
    );
    // The link quality: about 10 frames/s measured, 100/s announced (MSDT 10 ms).
    std::thread::sleep(Duration::from_millis(1500));
    let screen = tui.text();
    assert!(screen.contains("announced 100/s (10 ms)"), "{screen}");
    let rate = shown_link_rate(&screen).expect("measured rate on screen");
    assert!((7.0..13.0).contains(&rate), "measured {rate}/s\n{screen}");
    assert!(screen.contains(" lost "), "{screen}");
    assert!(screen.contains("poti "), "{screen}");
    let first = shown_frame_id(&screen).expect("frame id on screen");
    assert_eq!(shown_motor(&screen, "L"), Some(0.0), "{screen}");
    assert_eq!(shown_motor(&screen, "R"), Some(0.0), "{screen}");

    // Forward: both wheels turn at cruise (100/255 of 10 rad/s).
    tui.hold(b"w", Duration::from_millis(1200));
    let driving = tui.text();
    let (l, r) = (
        shown_motor(&driving, "L").expect("left wheel"),
        shown_motor(&driving, "R").expect("right wheel"),
    );
    assert!(l > 3.5 && r > 3.5, "wheels turning: {l} {r}\n{driving}");
    assert!(driving.contains("speed 100/255"), "{driving}");
    assert!(
        driving.contains("velocity=100 steering=128"),
        "the packet log shows the remote-control writes:\n{driving}"
    );
    let later = shown_frame_id(&driving).expect("frame id");
    assert_ne!(later, first, "frames keep coming");
    // Let go: the deadman stops the wheels.
    std::thread::sleep(Duration::from_millis(1500));
    let stopped = tui.text();
    assert_eq!(shown_motor(&stopped, "L"), Some(0.0), "{stopped}");

    // Backward: refused and said, the wheels stay still.
    tui.hold(b"s", Duration::from_millis(600));
    let refused = tui.wait_for("cannot reverse", Duration::from_secs(3));
    assert!(refused.contains("only drives forward"), "{refused}");
    assert!(refused.contains("speed   0/255"), "{refused}");
    assert_eq!(shown_motor(&refused, "L"), Some(0.0), "{refused}");
    assert_eq!(shown_motor(&refused, "R"), Some(0.0), "{refused}");

    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
    // The way out writes a stop: velocity 0, steering straight.
    let log = tui.log();
    assert!(
        log.lines()
            .any(|l| l.contains("final command") && l.contains("remote-control data=00 80")),
        "log:\n{log}"
    );
    let raw = tui.raw();
    assert!(pos(&raw, b"\x1b[?1049l") > pos(&raw, b"\x1b[?1049h"));
}

/// Issue 28: where libudev cannot be loaded (here: a library name that does not exist), the
/// status line says gamepads need it, and the keyboard drives as ever.
#[test]
fn without_libudev_the_status_line_says_so_and_the_keyboard_drives() {
    let mut tui = Tui::start_with(
        100,
        30,
        true,
        &[("DROIDCTL_LIBUDEV", "libudev-not-installed.so.1")],
    );
    tui.wait_for(
        "gamepads need libudev (systemd's udev library)",
        Duration::from_secs(20),
    );
    tui.wait_for("connected", Duration::from_secs(20));
    tui.wait_for("stance tripod", Duration::from_secs(10));
    assert!(
        tui.text().contains("pad n/a: gamepads need"),
        "{}",
        tui.text()
    );
    tui.send(b"\x1b[119u");
    std::thread::sleep(Duration::from_millis(1500));
    let moving = tui.text();
    assert!(
        moving.contains("speed 100/255"),
        "driving with the keyboard:\n{moving}"
    );
    tui.send(b"\x1b[119;1:3u");
    tui.send(b"\x1b[113u");
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
}

/// Issue 37 point 13: a FIFO where the remembered settings are hung the app before it drew
/// (nothing shown, `q` unanswered). Now the app starts with a warning, quits on `q`, and
/// the settings it remembers at exit replace the FIFO.
#[test]
fn a_fifo_for_remembered_settings_is_a_warning_not_a_hang() {
    let dir = TempDir::new("fifo-state");
    let state = dir.0.join("state");
    std::fs::create_dir_all(&state).unwrap();
    let settings = state.join("settings-r2d2.toml");
    let made = std::process::Command::new("mkfifo")
        .arg(&settings)
        .status()
        .unwrap();
    assert!(made.success());
    let state_env = state.to_str().unwrap();
    let mut tui = Tui::start_with(200, 30, false, &[("DROIDCTL_STATE_DIR", state_env)]);
    let screen = tui.wait_for("a FIFO, not a regular file", Duration::from_secs(20));
    assert!(screen.contains("settings-r2d2.toml"), "{screen}");
    tui.wait_for("connected", Duration::from_secs(20));
    tui.send(b"q");
    let status = tui.wait_exit(Duration::from_secs(10));
    assert!(status.success(), "{status:?}");
    let saved = std::fs::symlink_metadata(&settings).unwrap();
    assert!(saved.is_file(), "the FIFO was replaced: {saved:?}");
}
