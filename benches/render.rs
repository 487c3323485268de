//! Cost of drawing one full frame of the TUI at 200×60 into ratatui's `TestBackend`, with the
//! packet log full (10,000 entries) and telemetry, the 600-point track and a collision
//! populated: the worst case the event loop redraws at its frame rate. A second case adds a
//! text filter, which makes the log pane scan entries until it has a screenful of matches.
//!
//! A third and fourth case draw the scope (issue 22) with two minutes of history at 50
//! samples a second and four channels, at 200×60 and at 80×24.
//!
//! `cargo bench --bench render -- --warm-up-time 1 --measurement-time 3`

// criterion is a dev-dependency on Linux only (see Cargo.toml); elsewhere this is an empty
// program.
#![cfg_attr(not(target_os = "linux"), allow(dead_code, unused_imports))]

#[cfg(target_os = "linux")]
use criterion::{Criterion, criterion_group, criterion_main};
use droidctl::app::packet_log::{DEFAULT_CAPACITY, LogFilter, LogLine};
use droidctl::app::state::{AppState, GamepadStatus, KeyboardMode};
use droidctl::model::Model;
use droidctl::protocol::v2::wire::{AccelRaw, CollisionAxis, DriveFlags};
use droidctl::protocol::v2::{Collision, ErrorCode, Packet, cmd};
use droidctl::session::{Direction, LinkState, LogEntry, LogItem};
use droidctl::telemetry::{CollisionSeen, Stance, TRACK_LEN};
use droidctl::units::Heading;
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

fn line(at_ms: u64, dir: Direction, p: Packet) -> LogLine {
    LogLine::from_entry(&LogEntry {
        at: Duration::from_millis(at_ms),
        dir,
        item: LogItem::packet(p),
    })
}

/// A state as after a long drive: full log, full track, every gauge set.
fn state() -> AppState {
    let mut s = AppState::new(Model::R2D2, "D2-1A2B".into());
    s.now = Duration::from_secs(1200);
    s.droid_mut().link = LinkState::Connected;
    s.droid_mut().stats.errors = 12;
    s.droid_mut().rate_in = 10.0;
    s.droid_mut().rate_out = 10.0;
    s.gamepad = GamepadStatus::Connected("Xbox Wireless Controller".into());
    s.keyboard = KeyboardMode::ReleaseEvents;
    s.log_path = Some(PathBuf::from(
        "/home/pilot/.local/state/droidctl/logs/session.jsonl",
    ));
    let t = &mut s.droid_mut().telemetry;
    t.pitch = Some(1.5);
    t.roll = Some(-0.5);
    t.yaw = Some(140.0);
    t.accel = Some([0.1, -0.05, 0.99]);
    t.gyro = Some([3.0, -8.0, 40.0]);
    t.velocity_cm_s = Some([20.0, -35.0]);
    t.head_deg = Some(-45.0);
    t.battery_v = Some(3.8);
    t.battery_voltage_state = Some(1);
    t.stance = Stance::Tripod;
    t.collisions = 4;
    t.last_collision = Some(CollisionSeen {
        at: Duration::from_secs(1199),
        collision: Collision {
            accel: [AccelRaw(4096), AccelRaw(-800), AccelRaw(100)],
            axis: CollisionAxis { x: true, y: true },
            power: [150, 90, 0],
            speed: 80,
            time_ms: 1_199_000,
        },
    });
    for i in 0..TRACK_LEN {
        let a = i as f32 / 40.0;
        t.track
            .push_back((150.0 * a.sin(), 100.0 * (2.0 * a).sin()));
    }
    let (x, y) = *t.track.back().expect("track");
    (t.x_cm, t.y_cm) = (Some(x), Some(y));
    s.droid_mut().control.speed = 120;
    s.droid_mut().control.heading = Heading::new(140).expect("valid");
    s.droid_mut().control.deadman = false;
    s.droid_mut().control.head_target = -40.0;
    for i in 0..DEFAULT_CAPACITY as u64 / 2 {
        let seq = (i % 256) as u8;
        let heading = Heading::new((i % 360) as u16).expect("valid");
        let out =
            cmd::drive_with_heading((i % 200) as u8, heading, DriveFlags::empty()).to_packet(seq);
        let err = if i % 97 == 0 {
            ErrorCode::Busy
        } else {
            ErrorCode::Success
        };
        let resp = Packet::response_to(&out, err, vec![]);
        s.log.push(line(i * 100, Direction::Out, out));
        s.log.push(line(i * 100 + 40, Direction::In, resp));
    }
    assert_eq!(s.log.len(), DEFAULT_CAPACITY);
    s
}

#[cfg(target_os = "linux")]
fn render(c: &mut Criterion) {
    let mut s = state();
    let mut term = Terminal::new(TestBackend::new(200, 60)).expect("test backend");
    c.bench_function("frame_200x60_full_log", |b| {
        b.iter(|| {
            term.draw(|f| droidctl::ui::draw(f, black_box(&s)))
                .expect("draw");
        })
    });
    // "busy" matches 1 line in 194, fewer than a screenful: the pane scans the whole log.
    s.log.set_filter(LogFilter::parse("busy"));
    c.bench_function("frame_200x60_full_log_text_filter", |b| {
        b.iter(|| {
            term.draw(|f| droidctl::ui::draw(f, black_box(&s)))
                .expect("draw");
        })
    });
    let s = scope_state();
    c.bench_function("frame_200x60_scope_50hz_2min", |b| {
        b.iter(|| {
            term.draw(|f| droidctl::ui::draw(f, black_box(&s)))
                .expect("draw");
        })
    });
    let mut small = Terminal::new(TestBackend::new(80, 24)).expect("test backend");
    c.bench_function("frame_80x24_scope_50hz_2min", |b| {
        b.iter(|| {
            small
                .draw(|f| droidctl::ui::draw(f, black_box(&s)))
                .expect("draw");
        })
    });
}

/// The scope on screen over two minutes of samples at 50 a second (6,000 rows), four
/// channels, the widest window.
fn scope_state() -> AppState {
    use droidctl::protocol::notify::{Notification, SensorSample};
    use droidctl::telemetry::history::Channel;
    let mut s = state();
    for i in 0..6_000u64 {
        let t = i as f32 / 50.0;
        let n = Notification::Sensors(SensorSample {
            values: vec![
                ("pitch", 10.0 * (t * 1.3).sin()),
                ("roll", 5.0 * (t * 0.7).cos()),
                ("yaw", (t * 20.0) % 360.0 - 180.0),
                ("gyro_z", 90.0 * (t * 0.5).sin()),
                ("velocity_x", 40.0 * (t * 0.2).sin()),
                ("velocity_y", 40.0 * (t * 0.2).cos()),
            ],
        });
        s.droid_mut()
            .telemetry
            .apply(&n, Duration::from_millis(1_080_000 + i * 20));
    }
    s.now = Duration::from_millis(1_080_000 + 6_000 * 20);
    s.droid_mut().scope.visible = true;
    s.droid_mut().scope.window = 4;
    s.droid_mut().scope.channels = vec![
        Channel::Pitch,
        Channel::Roll,
        Channel::GyroZ,
        Channel::Speed,
    ];
    s
}

#[cfg(target_os = "linux")]
criterion_group!(benches, render);
#[cfg(target_os = "linux")]
criterion_main!(benches);

#[cfg(not(target_os = "linux"))]
fn main() {
    eprintln!("the benchmarks run on Linux only");
}
