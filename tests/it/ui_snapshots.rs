//! Snapshot tests of the terminal UI: deterministic application states (no clocks) rendered
//! into ratatui's `TestBackend` at 80×24 and 160×48 (plus a few extra sizes and overlays),
//! compared with the committed `.snap` files under `tests/snapshots/`. Snapshots hold the text
//! only, so a few assertion tests below also check the styles that carry meaning (E-STOP,
//! error lines), the help overlay's completeness, and that odd states and sizes never panic.
//!
//! Update after an intended change: `INSTA_UPDATE=always cargo test --test it ui_snapshots::`, then
//! read every changed `.snap`.

use droidctl::app::packet_log::{LogFilter, LogLine};
use droidctl::app::state::{AppState, Focus, GamepadStatus, KeyboardMode, Overlay};
use droidctl::model::Model;
use droidctl::protocol::v2::notify::Collision;
use droidctl::protocol::v2::wire::{
    AccelRaw, AudioMode, CollisionAxis, DriveFlags, LegAction, LegState,
};
use droidctl::protocol::v2::{Device, ErrorCode, Packet, cmd};
use droidctl::session::{Direction, LinkState, LogEntry, LogItem};
use droidctl::telemetry::{CollisionSeen, Stance};
use droidctl::units::{HeadAngle, Heading};
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::buffer::Buffer;
use ratatui::style::Color;
use std::path::PathBuf;
use std::time::Duration;

fn ms(v: u64) -> Duration {
    Duration::from_millis(v)
}

/// Help exactly as the app builds it from the shipped config.
fn with_help(s: &mut AppState) {
    let config = droidctl::config::Config::defaults();
    s.help = droidctl::app::help::live(&config);
    s.help_nav = droidctl::app::help::nav(&config.keymap, true);
    s.footer = droidctl::app::help::footer(&config.keymap, true);
}

fn entry(at_ms: u64, dir: Direction, p: Packet) -> LogLine {
    LogLine::from_entry(&LogEntry {
        at: ms(at_ms),
        dir,
        item: LogItem::packet(p),
    })
}

/// Builds a log with advancing time and SEQ numbers.
#[derive(Default)]
struct Script {
    t: u64,
    seq: u8,
    lines: Vec<LogLine>,
}

impl Script {
    /// A command out and its response in, 35 ms later.
    fn exchange(&mut self, c: droidctl::protocol::v2::Command, err: ErrorCode, data: Vec<u8>) {
        let p = c.to_packet(self.seq);
        self.seq = self.seq.wrapping_add(1);
        self.t += 120;
        self.lines.push(entry(self.t, Direction::Out, p.clone()));
        self.t += 35;
        self.lines.push(entry(
            self.t,
            Direction::In,
            Packet::response_to(&p, err, data),
        ));
    }

    fn ok(&mut self, c: droidctl::protocol::v2::Command) {
        self.exchange(c, ErrorCode::Success, vec![]);
    }

    fn notify(&mut self, p: Packet) {
        self.t += 20;
        self.lines.push(entry(self.t, Direction::In, p));
    }
}

/// A realistic session: setup, driving, dome, sound, sensor stream, one error response.
fn session_log() -> Vec<LogLine> {
    let mut s = Script::default();
    s.ok(cmd::wake());
    s.ok(cmd::perform_leg_action(LegAction::Tripod));
    s.ok(cmd::set_sensor_streaming_mask(
        100,
        0,
        droidctl::protocol::v2::wire::Mask(0x0007_0000),
    ));
    let h90 = Heading::new(90).expect("valid heading");
    s.ok(cmd::drive_with_heading(100, h90, DriveFlags::empty()));
    s.ok(cmd::set_head_position(
        HeadAngle::new(30.0).expect("in range"),
    ));
    s.ok(cmd::play_audio_file(1915, AudioMode::Immediate));
    // The droid refuses an animation id it does not have.
    s.exchange(
        cmd::play_animation(999),
        ErrorCode::BadParameterValue,
        vec![],
    );
    let sensor = Device::parse("sensor").expect("sensor device");
    let mut data = Vec::new();
    for f in [2.5f32, -1.25, 87.0] {
        data.extend_from_slice(&f.to_be_bytes());
    }
    s.notify(Packet::notification(sensor, 0x02, data));
    s.notify(Packet::notification(sensor, 0x12, collision().encode()));
    s.ok(cmd::drive_with_heading(120, h90, DriveFlags::TURBO));
    s.exchange(
        cmd::get_head_position(),
        ErrorCode::Success,
        25.4f32.to_be_bytes().to_vec(),
    );
    s.lines
}

fn collision() -> Collision {
    Collision {
        accel: [AccelRaw(5120), AccelRaw(-1230), AccelRaw(300)],
        axis: CollisionAxis { x: true, y: false },
        power: [180, -40, 0],
        speed: 92,
        time_ms: 123_456,
    }
}

/// Connected, driving at 100 towards 90°, telemetry and log populated.
fn driving() -> AppState {
    let mut s = AppState::new(Model::R2D2, "D2-1A2B".into());
    with_help(&mut s);
    s.now = Duration::from_secs(42);
    s.droid_mut().link = LinkState::Connected;
    s.droid_mut().stats.sent = 812;
    s.droid_mut().stats.received = 1604;
    s.droid_mut().stats.errors = 1;
    s.droid_mut().rate_in = 9.8;
    s.droid_mut().rate_out = 10.0;
    s.gamepad = GamepadStatus::Connected("Xbox Wireless Controller".into());
    s.keyboard = KeyboardMode::ReleaseEvents;
    s.log_path = Some(PathBuf::from(
        "/home/pilot/.local/state/droidctl/logs/2025-01-01T12-00-00-D2-1A2B.jsonl",
    ));
    let t = &mut s.droid_mut().telemetry;
    t.pitch = Some(2.5);
    t.roll = Some(-1.25);
    t.yaw = Some(87.0);
    t.accel = Some([0.02, -0.01, 0.98]);
    t.gyro = Some([1.5, -3.0, 12.0]);
    t.velocity_cm_s = Some([30.0, 40.0]);
    t.head_deg = Some(25.4);
    t.battery_v = Some(3.92);
    t.battery_voltage_state = Some(1);
    t.stance = Stance::Tripod;
    t.samples = 400;
    // An L-shaped run: 120 cm north, then curving east.
    for i in 0..=40 {
        t.track.push_back((0.0, i as f32 * 3.0));
    }
    for i in 1..=30 {
        let a = (i as f32 / 30.0) * std::f32::consts::FRAC_PI_2;
        t.track
            .push_back((60.0 - 60.0 * a.cos(), 120.0 + 60.0 * a.sin()));
    }
    let (x, y) = *t.track.back().expect("track");
    t.x_cm = Some(x);
    t.y_cm = Some(y);
    let c = &mut s.droid_mut().control;
    c.speed = 100;
    c.heading = Heading::new(90).expect("valid");
    c.deadman = false;
    c.head_target = 30.0;
    c.source = "keyboard";
    for l in session_log() {
        s.log.push(l);
    }
    s
}

fn reconnecting() -> AppState {
    let mut s = driving();
    s.droid_mut().link = LinkState::Reconnecting {
        attempt: 2,
        reason: "device disconnected".into(),
    };
    s.droid_mut().rate_in = 0.0;
    s.droid_mut().rate_out = 0.0;
    s.droid_mut().control.speed = 0;
    s.droid_mut().control.deadman = true;
    s.show_hint(
        "link lost: the droid stops by itself; reconnecting",
        Duration::from_secs(5),
    );
    s
}

/// 0.3 s after a bump, e-stop latched, battery low.
fn collision_flash() -> AppState {
    let mut s = driving();
    s.droid_mut().telemetry.collisions = 3;
    s.droid_mut().telemetry.last_collision = Some(CollisionSeen {
        at: s.now - ms(300),
        collision: collision(),
    });
    s.droid_mut().control.estop = true;
    s.droid_mut().control.speed = 0;
    s.droid_mut().telemetry.battery_v = Some(3.55);
    s.droid_mut().telemetry.battery_voltage_state = Some(2);
    s.droid_mut().telemetry.stance = Stance::Transitioning(LegState::Bipod);
    s
}

fn help() -> AppState {
    let mut s = driving();
    s.overlay = Overlay::Help;
    s
}

/// Log focused, paused, filtered on the animatronic device (commands out, responses in,
/// one error response).
fn filtered() -> AppState {
    let mut s = driving();
    s.focus = Focus::Log;
    s.log.set_filter(LogFilter::parse("dev:animatronic"));
    s.log.paused = true;
    s
}

fn render(state: &AppState, w: u16, h: u16) -> Terminal<TestBackend> {
    let mut term = Terminal::new(TestBackend::new(w, h)).expect("test backend");
    term.draw(|f| droidctl::ui::draw(f, state)).expect("draw");
    term
}

fn rows(buf: &Buffer) -> Vec<String> {
    let w = buf.area.width as usize;
    buf.content
        .chunks(w.max(1))
        .map(|row| row.iter().map(|c| c.symbol()).collect())
        .collect()
}

macro_rules! snap {
    ($name:ident, $state:expr, $w:expr, $h:expr) => {
        #[test]
        fn $name() {
            let term = render(&$state, $w, $h);
            insta::assert_snapshot!(stringify!($name), term.backend());
        }
    };
}

snap!(driving_80x24, driving(), 80, 24);
snap!(driving_160x48, driving(), 160, 48);
snap!(reconnecting_80x24, reconnecting(), 80, 24);
snap!(reconnecting_160x48, reconnecting(), 160, 48);
snap!(collision_80x24, collision_flash(), 80, 24);
snap!(collision_160x48, collision_flash(), 160, 48);
snap!(help_80x24, help(), 80, 24);
snap!(help_160x48, help(), 160, 48);
snap!(filtered_log_80x24, filtered(), 80, 24);
snap!(filtered_log_160x48, filtered(), 160, 48);
snap!(driving_120x36, driving(), 120, 36);
snap!(driving_200x60, driving(), 200, 60);
snap!(
    help_page2_80x24,
    {
        let mut s = help();
        s.help_page = 1;
        s
    },
    80,
    24
);
snap!(
    animations_palette_80x24,
    {
        let mut s = driving();
        s.overlay = Overlay::Animations { selected: 20 };
        s
    },
    80,
    24
);
snap!(
    filter_prompt_80x24,
    {
        let mut s = filtered();
        s.overlay = Overlay::Filter {
            input: "in dev:power batt".into(),
            before: Default::default(),
        };
        s
    },
    80,
    24
);
snap!(
    bb9e_hex_log_80x24,
    {
        let mut s = driving();
        s.droid_mut().model = Model::BB9E;
        s.droid_mut().droid_name = "GB-77AA".into();
        s.droid_mut().telemetry.stance = Stance::Unknown;
        s.log.decoded = false;
        s
    },
    80,
    24
);
snap!(tiny_40x12, driving(), 40, 12);

/// The scope over 30 s of samples at 10/s: yaw turning, speed rising and falling, paused.
fn scope() -> AppState {
    use droidctl::protocol::notify::{Notification, SensorSample};
    let mut s = driving();
    for i in 0..300u64 {
        let t = i as f32 / 10.0;
        let v = 40.0 * (t / 30.0 * std::f32::consts::PI).sin();
        s.droid_mut().telemetry.apply(
            &Notification::Sensors(SensorSample {
                values: vec![
                    ("yaw", (t * 12.0) % 360.0 - 180.0),
                    ("velocity_x", v),
                    ("velocity_y", 0.0),
                ],
            }),
            ms(12_000 + i * 100),
        );
    }
    s.droid_mut().scope.visible = true;
    s.droid_mut().scope.paused_at = Some(s.now);
    s
}

snap!(scope_80x24, scope(), 80, 24);
snap!(scope_160x48, scope(), 160, 48);
snap!(
    scope_channels_80x24,
    {
        let mut s = scope();
        s.overlay = Overlay::Channels { selected: 2 };
        s
    },
    80,
    24
);
snap!(
    tuning_palette_80x24,
    {
        let mut s = driving();
        s.overlay = Overlay::Tuning {
            selected: 0,
            draft: droidctl::app::view::scope::TuningDraft {
                rate_hz: 10,
                sensors: droidctl::family::stream::all_groups(Model::R2D2),
                collision: Default::default(),
            },
        };
        s
    },
    80,
    24
);
snap!(
    empty_state_80x24,
    AppState::new(Model::R2D2, "D2-0000".into()),
    80,
    24
);

/// Words of `needle` appear in order in `hay` (a description wrapped over lines, with
/// another column's text between its pieces, still counts).
fn words_in_order(hay: &[String], needle: &str) -> bool {
    let text = hay.join(" ");
    let mut words = text.split_whitespace();
    needle.split_whitespace().all(|w| words.any(|h| h == w))
}

#[test]
fn help_overlay_lists_every_binding_at_80x24() {
    let s = help();
    // Page by page until the pages repeat (the UI clamps to the last one).
    let mut pages: Vec<Vec<String>> = Vec::new();
    for page in 0..10 {
        let mut p = s.clone();
        p.help_page = page;
        let text = rows(render(&p, 80, 24).backend().buffer());
        if pages.last() == Some(&text) {
            break;
        }
        pages.push(text);
    }
    assert!(pages.len() >= 2, "80x24 needs more than one page");
    assert!(
        pages[0].iter().any(|r| r.contains("page 1/")),
        "the footer says so"
    );
    // Help lists what applies to this droid (an R2-D2 alone): no BOLT, RVR or fleet keys.
    let all: String = pages.iter().flatten().cloned().collect();
    for absent in [
        "type on the matrix",
        "tank mode",
        "fleet: drive",
        "aim mode",
    ] {
        assert!(!all.contains(absent), "{absent} listed for R2-D2");
    }
    let r2: Vec<_> = s
        .help
        .iter()
        .map(|sec| sec.applying(Model::R2D2, false))
        .collect();
    for section in &r2 {
        for h in &section.lines {
            assert!(
                pages
                    .iter()
                    .any(|p| words_in_order(p, &h.action) && p.iter().any(|r| r.contains(&h.keys))),
                "missing {:?} ({:?}) on every page",
                h.action,
                h.keys
            );
        }
    }
    // Descriptions that fit their column stay on one line.
    assert!(pages[0].iter().any(|r| r.contains("drive forward (hold)")));
    // At 200×60 everything is on one page (160×48 since the packet detail's keys: two).
    let big = rows(render(&s, 200, 60).backend().buffer());
    for h in r2.iter().flat_map(|sec| &sec.lines) {
        assert!(
            big.iter().any(|r| r.contains(&h.action)),
            "missing {:?}",
            h.action
        );
    }
}

#[test]
fn alarms_are_styled() {
    // (80×25: the context footer takes a row of the log at 24, and the error line with it)
    let term = render(&collision_flash(), 80, 25);
    let buf = term.backend().buffer();
    let text = rows(buf);
    let (y, row) = text
        .iter()
        .enumerate()
        .find(|(_, r)| r.contains("E-STOP"))
        .expect("E-STOP shown");
    let x = row.chars().take_while(|_| true).collect::<Vec<_>>();
    let col = x.iter().position(|&c| c == 'E').expect("E") as u16;
    assert_eq!(buf[(col, y as u16)].bg, Color::Red);
    let (y, row) = text
        .iter()
        .enumerate()
        .find(|(_, r)| r.contains("COLLISION!"))
        .expect("flash");
    let col = row.chars().position(|c| c == 'C').expect("C") as u16;
    assert_eq!(buf[(col, y as u16)].bg, Color::Red);
    // The error response in the log is red.
    let (y, row) = text
        .iter()
        .enumerate()
        .find(|(_, r)| r.contains("bad_param"))
        .expect("error line");
    let col = row.chars().position(|c| c == '<').expect("arrow") as u16;
    assert_eq!(buf[(col, y as u16)].fg, Color::Red);
}

#[test]
fn reconnecting_is_highlighted() {
    let term = render(&reconnecting(), 80, 24);
    let buf = term.backend().buffer();
    let row = &rows(buf)[0];
    assert!(row.contains("reconnecting (attempt 2)"));
    let col = row.chars().position(|c| c == 'r').expect("r") as u16;
    assert_eq!(buf[(col, 0)].bg, Color::Yellow);
}

/// A state with every number out of range: NaN, infinities, huge values, indexes past the end.
fn hostile() -> AppState {
    let mut s = driving();
    let t = &mut s.droid_mut().telemetry;
    t.pitch = Some(f32::NAN);
    t.roll = Some(f32::INFINITY);
    t.yaw = Some(f32::NEG_INFINITY);
    t.accel = Some([f32::NAN, f32::MAX, f32::MIN]);
    t.gyro = Some([f32::INFINITY, f32::NAN, 1e30]);
    t.velocity_cm_s = Some([f32::NAN, f32::INFINITY]);
    t.x_cm = Some(f32::MAX);
    t.y_cm = Some(f32::NAN);
    t.head_deg = Some(f32::NEG_INFINITY);
    t.battery_v = Some(f32::NAN);
    t.battery_voltage_state = Some(200);
    t.track.push_back((f32::NAN, 1.0));
    t.track.push_back((f32::MAX, f32::MIN));
    t.track.push_back((f32::INFINITY, 0.0));
    t.last_collision = Some(CollisionSeen {
        at: Duration::MAX,
        collision: Collision {
            accel: [AccelRaw(i16::MIN), AccelRaw(i16::MAX), AccelRaw(0)],
            power: [i16::MIN, i16::MAX, 0],
            ..collision()
        },
    });
    t.collisions = u32::MAX;
    s.droid_mut().control.head_target = f32::NAN;
    s.droid_mut().rate_in = f32::INFINITY;
    s.droid_mut().rate_out = f32::NAN;
    s.droid_mut().stats.errors = u64::MAX;
    s.droid_mut().droid_name = "\u{1b}[2J evil\nname \u{7}".repeat(10);
    s.droid_mut().link = LinkState::Closed {
        reason: Some("x".repeat(500)),
    };
    s.log.scroll = usize::MAX;
    s.help_page = usize::MAX;
    s
}

#[test]
fn never_panics_at_any_size_or_state() {
    let mut states = vec![
        AppState::new(Model::R2D2, String::new()),
        driving(),
        hostile(),
    ];
    for base in [
        driving(),
        hostile(),
        AppState::new(Model::BB9E, "GB".into()),
    ] {
        for overlay in [
            Overlay::Help,
            Overlay::Animations {
                selected: usize::MAX,
            },
            Overlay::Sounds { selected: 3 },
            Overlay::Filter {
                input: "in dev:x ".repeat(40),
                before: Default::default(),
            },
        ] {
            let mut s = base.clone();
            s.overlay = overlay;
            states.push(s);
        }
    }
    let mut empty_palette = driving();
    empty_palette.animations.clear();
    empty_palette.overlay = Overlay::Animations { selected: 5 };
    states.push(empty_palette);
    let sizes = [
        (1, 1),
        (2, 2),
        (20, 5),
        (5, 20),
        (40, 10),
        (59, 15),
        (60, 16),
        (79, 23),
        (80, 24),
        (149, 39),
        (150, 40),
        (300, 3),
        (3, 100),
        (250, 80),
    ];
    for s in &states {
        for (w, h) in sizes {
            render(s, w, h);
        }
    }
}

#[test]
fn hostile_values_print_bounded() {
    let text = rows(render(&hostile(), 160, 48).backend().buffer()).join("\n");
    assert!(text.contains("NaN"));
    assert!(!text.contains('\u{1b}'));
}

// ---------------------------------------------------------------------------------------------
// A Sphero API v1 droid (BB-8): the Lights panel in the dome's place, aim mode on.
// ---------------------------------------------------------------------------------------------

/// A v1 packet-log line, explained by the v1 family (a response by its request, sensor data
/// by the streaming configuration).
fn v1_entry(
    at_ms: u64,
    dir: Direction,
    p: droidctl::protocol::v1::Packet,
    request: Option<&droidctl::protocol::v1::Command>,
    streaming: Option<&droidctl::protocol::v1::StreamingConfig>,
) -> LogLine {
    let request = request.cloned().map(droidctl::family::Command::from);
    LogLine::from_entry(&LogEntry {
        at: ms(at_ms),
        dir,
        item: LogItem::Packet {
            explained: droidctl::family::v1::explain(&p, streaming, request.as_ref()),
            packet: droidctl::family::Packet::V1(p),
        },
    })
}

/// The v1 connect setup, the colour and aim keys, and a sensor frame, as the app logs them.
fn bb8_log() -> Vec<LogLine> {
    use droidctl::protocol::v1::{self, Mrsp, Packet as P, Response, cmd};
    let streaming = v1::StreamingConfig::full(40);
    let aim = Heading::new(35).expect("valid heading");
    let commands = [
        cmd::ping(),
        cmd::set_stabilization(true),
        cmd::configure_collision_detection(1, 100, 100, 100, 100, 10),
        streaming.command(),
        cmd::set_power_notification(true),
        cmd::set_rgb_led(255, 140, 0, false),
        cmd::set_back_led(255),
        cmd::roll(0, aim, v1::RollState::Go),
    ];
    let mut lines = Vec::new();
    let mut t = 0;
    for (seq, c) in commands.iter().enumerate() {
        let p = c.to_packet(seq as u8);
        t += 60;
        lines.push(v1_entry(
            t,
            Direction::Out,
            P::Command(p.clone()),
            None,
            None,
        ));
        let r = P::Response(Response::to(&p, Mrsp::Ok, vec![]));
        lines.push(v1_entry(t + 4, Direction::In, r, Some(c), None));
    }
    let frame = [
        ("pitch", 0.0),
        ("roll", 0.0),
        ("yaw", 35.0),
        ("accel_z", 1.0),
        ("locator_x", 12.0),
        ("locator_y", 48.0),
    ];
    let data = v1::encode_samples(&streaming, &[frame.to_vec()]);
    lines.push(v1_entry(
        t + 40,
        Direction::In,
        P::Async(v1::AsyncPacket::new(0x03, data)),
        None,
        Some(&streaming),
    ));
    lines
}

/// BB-8 stopped and aiming: turned to 35°, back light on, main LED orange.
fn bb8_aiming() -> AppState {
    let mut s = AppState::new(Model::BB8, "BB-1A2B".into());
    with_help(&mut s);
    s.now = Duration::from_secs(12);
    s.droid_mut().link = LinkState::Connected;
    s.droid_mut().stats.sent = 96;
    s.droid_mut().stats.received = 240;
    s.droid_mut().rate_in = 11.0;
    s.droid_mut().rate_out = 2.0;
    s.gamepad = GamepadStatus::NoPad;
    s.keyboard = KeyboardMode::Emulated;
    let t = &mut s.droid_mut().telemetry;
    t.pitch = Some(0.0);
    t.roll = Some(0.0);
    t.yaw = Some(35.0);
    t.accel = Some([0.0, 0.0, 1.0]);
    t.gyro = Some([0.0, 0.0, 0.0]);
    t.velocity_cm_s = Some([0.0, 0.0]);
    t.battery_v = Some(4.05);
    t.stance = Stance::Unknown;
    t.samples = 120;
    for i in 0..=16 {
        t.track.push_back((i as f32 * 0.75, i as f32 * 3.0));
    }
    t.x_cm = Some(12.0);
    t.y_cm = Some(48.0);
    let c = &mut s.droid_mut().control;
    c.speed = 0;
    c.heading = Heading::new(35).expect("valid");
    c.deadman = true;
    c.source = "aim";
    c.aiming = true;
    s.droid_mut().leds.main = Some([255, 140, 0]);
    s.droid_mut().leds.back = Some(255);
    s.show_hint(
        "aim: ←/→ turn the droid, press the aim key again to set heading 0",
        Duration::from_secs(5),
    );
    for l in bb8_log() {
        s.log.push(l);
    }
    s
}

snap!(bb8_lights_aiming_80x24, bb8_aiming(), 80, 24);

#[test]
fn bb8_has_the_lights_panel_in_colour_not_the_dome() {
    for (w, h) in [(80, 24), (160, 48)] {
        let term = render(&bb8_aiming(), w, h);
        let buf = term.backend().buffer();
        let text = rows(buf);
        assert!(!text.iter().any(|r| r.contains(" Dome ")), "{text:#?}");
        let (y, row) = text
            .iter()
            .enumerate()
            .find(|(_, r)| r.contains("Lights") && r.contains("AIMING"))
            .unwrap_or_else(|| panic!("Lights panel, aiming, at {w}×{h}: {text:#?}"));
        let col = row.chars().position(|c| c == 'A').expect("A") as u16;
        assert_ne!(buf[(col, y as u16)].fg, Color::Reset, "AIMING stands out");
        // The swatch is painted in the commanded colour.
        let (y, row) = text
            .iter()
            .enumerate()
            .find(|(_, r)| r.contains("main") && r.contains("255,140,0"))
            .expect("main LED line");
        let col = row.chars().position(|c| c == '█').expect("swatch") as u16;
        assert_eq!(buf[(col, y as u16)].fg, Color::Rgb(255, 140, 0));
        assert!(row.contains("back 255/255"), "{row}");
    }
    // Not aiming: no AIMING, the lights stay.
    let mut s = bb8_aiming();
    s.droid_mut().control.aiming = false;
    let term = render(&s, 80, 24);
    let text = rows(term.backend().buffer());
    assert!(text.iter().any(|r| r.contains("Lights")));
    assert!(!text.iter().any(|r| r.contains("AIMING")));
}

/// Robi 42's traffic as the app logs it: the handshake, frames and remote-control writes.
fn robi_log() -> Vec<LogLine> {
    use droidctl::family::{Packet as Any, RobiControl, RobiPacket};
    use droidctl::protocol::rsrcp::{self, Item};
    let line = |at_ms: u64, dir: Direction, p: RobiPacket| {
        LogLine::from_entry(&LogEntry {
            at: ms(at_ms),
            dir,
            item: LogItem::Packet {
                explained: droidctl::family::robi::explain(&p),
                packet: Any::Robi(p),
            },
        })
    };
    let mut lines = vec![line(
        40,
        Direction::In,
        RobiPacket::Item(Item::Handshake(rsrcp::Handshake {
            version: 1,
            msdt_ms: 10,
        })),
    )];
    for (i, id) in [0xFF_FFFEu32, 0xFF_FFFF, 1].into_iter().enumerate() {
        let t = 100 + 100 * i as u64;
        lines.push(line(
            t,
            Direction::Out,
            RobiPacket::Control(RobiControl {
                velocity: 180,
                steering: 179,
            }),
        ));
        lines.push(line(
            t + 3,
            Direction::In,
            RobiPacket::Item(Item::Frame(
                rsrcp::Frame::new(id)
                    .with_motors(7.06, 4.24)
                    .with_poti(200)
                    .with_buttons(rsrcp::Buttons::LEFT | rsrcp::Buttons::CENTER),
            )),
        ));
    }
    lines
}

/// Robi 42 driving and bending right: wheels 7.06 and 4.24 rad/s, the left and centre
/// buttons held, headlights and the left blinkers lit, the piezo sounding, one frame lost
/// across the 24-bit wrap, 10 frames/s measured against the 100 announced.
fn robi_driving() -> AppState {
    use droidctl::protocol::notify::Notification;
    use droidctl::protocol::rsrcp::{Buttons, Frame, Handshake, Leds};
    let mut s = AppState::new(Model::Robi42, "Robi 42".into());
    with_help(&mut s);
    s.now = Duration::from_secs(31);
    s.droid_mut().link = LinkState::Connected;
    s.droid_mut().stats.sent = 140;
    s.droid_mut().stats.received = 302;
    s.droid_mut().rate_in = 10.0;
    s.droid_mut().rate_out = 10.0;
    s.gamepad = GamepadStatus::NoPad;
    s.keyboard = KeyboardMode::Emulated;
    let t = &mut s.droid_mut().telemetry;
    t.apply(
        &Notification::RobiHandshake(Handshake {
            version: 1,
            msdt_ms: 10,
        }),
        ms(0),
    );
    let leds = Leds::FRONT_LEFT_HEADLIGHT
        | Leds::FRONT_RIGHT_HEADLIGHT
        | Leds::FRONT_LEFT_BLINKER
        | Leds::BACK_LEFT_BLINKER;
    // 30 frames 100 ms apart, speeding up, then bending right; id 0 is lost.
    let mut id = 0xFF_FFF0u32;
    for i in 0..30u64 {
        if id == 0 {
            id = 1;
        }
        let v = (i as f32 / 10.0).min(1.0);
        let (l, r) = if i < 20 {
            (7.06 * v, 7.06 * v)
        } else {
            (7.06, 4.24)
        };
        let buttons = if i >= 27 {
            Buttons::LEFT | Buttons::CENTER
        } else {
            Buttons::empty()
        };
        let f = Frame::new(id)
            .with_motors(l, r)
            .with_poti(120 + i as u8 * 4)
            .with_buttons(buttons)
            .with_leds(leds)
            .with_piezo(true, 440);
        t.apply(&Notification::RobiFrame(f), ms(1_000 + 100 * i));
        id = (id + 1) & 0xFF_FFFF;
    }
    let c = &mut s.droid_mut().control;
    c.speed = 180;
    c.cruise = 100;
    c.deadman = false;
    c.steer = Some(0.4);
    c.source = "keyboard";
    for l in robi_log() {
        s.log.push(l);
    }
    s
}

snap!(robi_driving_80x24, robi_driving(), 80, 24);
snap!(robi_driving_160x48, robi_driving(), 160, 48);

/// The cell where `needle` starts on the first row containing it.
fn find_cell(text: &[String], needle: &str) -> Option<(u16, u16)> {
    find_after(text, "", needle)
}

/// The cell of the first `needle` after `anchor`, on the first row where both are.
fn find_after(text: &[String], anchor: &str, needle: &str) -> Option<(u16, u16)> {
    text.iter().enumerate().find_map(|(y, r)| {
        let from = r.find(anchor)? + anchor.len();
        let at = from + r[from..].find(needle)?;
        Some((r[..at].chars().count() as u16, y as u16))
    })
}

#[test]
fn robi_panels_light_pressed_buttons_and_lit_lamps_and_never_cut_the_lost_count() {
    // (31 rows: the context footer takes one, the panels keep the room 30 rows had)
    for (w, h) in [(60, 16), (80, 24), (100, 31), (160, 48)] {
        let term = render(&robi_driving(), w, h);
        let buf = term.backend().buffer();
        let text = rows(buf);
        let all = text.join("\n");
        assert!(!all.contains(" Dome ") && !all.contains("pitch"), "{all}");
        assert!(
            all.contains("Motors") && all.contains("Robi · frame 14"),
            "{all}"
        );
        // Pressed: left and centre lit, the others not.
        let lit = |(x, y): (u16, u16)| buf[(x, y)].bg == Color::Yellow;
        // The short labels where the panel has no room for the long ones (Robi's I/O panel
        // takes the collisions' place too: 80×24 has the room since issue 30).
        let short = all.contains("[L]");
        // Issue 30: panels that do not apply are hidden (no collisions, no turbo on Robi).
        assert!(
            !all.contains("Collisions") && !all.contains("turbo"),
            "{all}"
        );
        assert_eq!(short, w < 80, "{w}×{h}:\n{all}");
        let (left, ok, top) = if short {
            ("[L]", "[ok]", "[T]")
        } else {
            ("[left]", "[ok]", "[top]")
        };
        for (label, on) in [(left, true), (ok, true), (top, false)] {
            let cell =
                find_cell(&text, label).unwrap_or_else(|| panic!("{label} at {w}×{h}:\n{all}"));
            assert_eq!(lit(cell), on, "{label} at {w}×{h}");
        }
        // Headlights lit, taillights dark.
        let lamps = if short { "[R]" } else { "lamps" };
        let head = find_after(&text, lamps, "●").expect("headlight");
        assert!(lit(head), "headlight at {w}×{h}");
        let tail = find_after(&text, "", "■").expect("taillight");
        assert!(!lit(tail), "taillight at {w}×{h}");
        // All eight lamps, also at 60 columns: the back right blinker is the last.
        let back = find_after(&text, "■■", "▶").or_else(|| find_after(&text, "■ ■", "▶"));
        assert!(back.is_some(), "back lamps whole at {w}×{h}:\n{all}");
        assert!(all.contains("440"), "the piezo at {w}×{h}:\n{all}");
        // Panels with the room show the lamps as on the robot, front and back.
        if !short {
            assert!(
                all.contains("lamps front") && all.contains("piezo on 440 Hz"),
                "{w}×{h}:\n{all}"
            );
        }
    }
    // A long session's lost count is shown whole, also at 80×24.
    for lost in [12u64, 1234, 987_654] {
        let mut s = robi_driving();
        s.droid_mut().telemetry.robi.as_mut().expect("robi").lost = lost;
        for (w, h) in [(60, 16), (80, 24), (100, 30), (160, 48)] {
            let text = rows(render(&s, w, h).backend().buffer());
            let line = text
                .iter()
                .find(|r| r.contains(" lost "))
                .unwrap_or_else(|| panic!("link line at {w}×{h}: {text:#?}"));
            assert!(
                line.contains(&format!(" lost {lost}│"))
                    || line.contains(&format!(" lost {lost} ")),
                "{w}×{h}: {line}"
            );
            // Rates in the one form every panel uses: 10/s, not 10.0/s.
            assert!(line.contains(" 10/s") && line.contains("100/s"), "{line}");
        }
    }
}

/// A fleet of four on screen: the roster strip above the one-droid screen (the chosen one's
/// gauges), the other droids on its map by number, the log naming each line's droid.
fn fleet() -> AppState {
    use droidctl::app::state::DroidState;
    use std::sync::Arc;
    let mut s = driving();
    s.droid_mut().droid_name = "D2-0001".into();
    let other = |name: &str, model, link, battery_v, moving: bool, position: Option<(f32, f32)>| {
        let mut d = DroidState::new(model, name.into());
        d.link = link;
        d.telemetry.battery_v = battery_v;
        d.rate_in = 12.0;
        d.rate_out = 10.0;
        d.control.speed = if moving { 80 } else { 0 };
        if let Some((x, y)) = position {
            d.telemetry.x_cm = Some(x);
            d.telemetry.y_cm = Some(y);
        }
        d
    };
    // The chosen droid is the driving screen's own (the roster reads the same state).
    s.droids.extend([
        other(
            "BB-0002",
            Model::BB8,
            LinkState::Connected,
            Some(4.1),
            true,
            Some((0.0, 0.0)),
        ),
        other(
            "GB-0003",
            Model::BB9E,
            LinkState::Reconnecting {
                attempt: 2,
                reason: "the droid disconnected".into(),
            },
            None,
            false,
            Some((120.0, -40.0)),
        ),
        other(
            "Robi 42",
            Model::Robi42,
            LinkState::Connecting,
            None,
            false,
            None,
        ),
    ]);
    s.chosen = 0;
    s.mirror = true;
    let names: [Arc<str>; 2] = [Arc::from("D2-0001"), Arc::from("BB-0002")];
    let lines = session_log();
    s.log = Default::default();
    for (i, mut l) in lines.into_iter().enumerate() {
        l.droid = Some(names[i % 2].clone());
        s.log.push(l);
    }
    s
}

snap!(fleet_80x24, fleet(), 80, 24);
snap!(fleet_160x48, fleet(), 160, 48);
snap!(
    fleet_log_filtered_by_droid_160x48,
    {
        let mut s = fleet();
        s.log.set_filter(LogFilter::parse("droid:d2"));
        s
    },
    160,
    48
);

#[test]
fn the_log_filters_by_droid() {
    let s = fleet();
    let mut log = s.log.clone();
    let all = log.visible(1000).len();
    log.set_filter(LogFilter::parse("droid:bb-0002"));
    let bb: Vec<_> = log.visible(1000).into_iter().cloned().collect();
    assert!(!bb.is_empty() && bb.len() < all);
    assert!(bb.iter().all(|l| l.droid.as_deref() == Some("BB-0002")));
    assert_eq!(log.filter_input(), "droid:bb-0002");
    log.set_filter(LogFilter::parse("droid:nobody"));
    assert!(log.visible(1000).is_empty());
}
