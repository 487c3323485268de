//! The simulated Robi 42 (`droid-facts.md` §5): the sans-IO [`SimRobi`] with explicit times
//! (handshake, start confirmation, frames at the real rate rather than the announced one,
//! the firmware's differential mix, lost frames and the 24-bit wrap, the host going away,
//! walls), then end to end through [`SimLink`] and a session under paused tokio time
//! (handshake first, measured link quality, drive controls as velocity and steering writes,
//! latest-wins, a dropped link that stops the robot and resumes at speed 0).

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::family::{Command as AnyCommand, Packet, RobiControl, RobiPacket};
use droidctl::gatt::Endpoint;
use droidctl::model::{Model, Protocol};
use droidctl::protocol::notify::Notification;
use droidctl::protocol::rsrcp::{self, Buttons, Efs, Frame, Handshake};
use droidctl::session::{
    self, Direction, LinkState, LogEntry, LogItem, SessionConfig, SessionEvent, SessionHandle, Slot,
};
use droidctl::sim::link::SimProbe;
use droidctl::sim::robi::FIRST_FRAME_ID;
use droidctl::sim::{Faults, SimConfig, SimLink, SimRobi, SimState, WireDroid};
use droidctl::telemetry::Telemetry;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::broadcast;
use tokio::time::{Instant, sleep};

fn ms(n: u64) -> Duration {
    Duration::from_millis(n)
}

fn secs(n: f64) -> Duration {
    Duration::from_secs_f64(n)
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

/// The Robi 42 figures: 30 cm/s at full speed, wheels of 3 cm radius, so a wheel at full
/// speed turns at 10 rad/s.
fn robi_cfg() -> SimConfig {
    SimConfig::for_model(Model::Robi42)
}

/// Full speed of one wheel in rad/s, by the simulator's own figures.
fn full_rad_s() -> f32 {
    let c = robi_cfg();
    c.top_speed_cm_s / c.wheel_radius_cm
}

// ---------------------------------------------------------------------------------------------
// A bench for the sans-IO robot: explicit time in 10 ms steps (the physics step), every
// notification decoded as the host would, with the time it came out.
// ---------------------------------------------------------------------------------------------

const STEP: Duration = Duration::from_millis(10);

struct Bench {
    robi: SimRobi,
    now: Duration,
    /// Frames with the time they came out.
    frames: Vec<(Duration, Frame)>,
}

impl Bench {
    fn new() -> Self {
        Bench::with(robi_cfg())
    }

    fn with(cfg: SimConfig) -> Self {
        Bench {
            robi: SimRobi::new(cfg),
            now: Duration::ZERO,
            frames: Vec::new(),
        }
    }

    /// A room so large no wall is ever reached.
    fn open_field() -> Self {
        Bench::with(SimConfig {
            room_cm: (100_000.0, 100_000.0),
            ..robi_cfg()
        })
    }

    /// No frame lost on the air.
    fn lossless() -> Self {
        Bench::with(SimConfig {
            robi_drop_every: 0,
            ..robi_cfg()
        })
    }

    fn state(&self) -> &SimState {
        self.robi.state()
    }

    fn take(&mut self, out: Vec<Vec<u8>>) {
        for v in out {
            let f = rsrcp::decode_frame(&v)
                .unwrap_or_else(|e| panic!("the robot's notification {v:02X?} is a frame: {e}"));
            // One frame per notification: the value is exactly the frame's bytes.
            assert_eq!(f.encode(), v);
            self.frames.push((self.now, f));
        }
    }

    /// Connect as the host does: read the handshake, confirm the start (and take the frame
    /// due at once).
    fn connect(&mut self) -> Vec<Vec<u8>> {
        let read = WireDroid::connect(&mut self.robi, self.now);
        let out = self.robi.advance(self.now);
        self.take(out);
        read
    }

    /// A remote-control write at the current time.
    fn write(&mut self, to: Endpoint, byte: u8) {
        self.robi.write(to, &[byte], self.now);
    }

    /// Velocity then steering, as the family writes a drive.
    fn control(&mut self, velocity: u8, steering: u8) {
        self.write(Endpoint::Velocity, velocity);
        self.write(Endpoint::Steering, steering);
    }

    fn run_for(&mut self, d: Duration) {
        let end = self.now + d;
        while self.now < end {
            self.now += STEP;
            let out = self.robi.advance(self.now);
            self.take(out);
        }
    }

    fn ids(&self) -> Vec<u32> {
        self.frames.iter().map(|(_, f)| f.frame_id).collect()
    }

    fn last_frame(&self) -> &Frame {
        &self.frames.last().expect("a frame").1
    }
}

#[test]
fn no_frames_flow_before_the_start_confirmation() {
    let mut b = Bench::new();
    b.run_for(secs(3.0));
    assert!(b.frames.is_empty(), "{:?}", b.frames);
    // Remote-control writes are taken (the robot listens) but start no frames either.
    b.control(200, 128);
    b.run_for(secs(1.0));
    assert!(b.frames.is_empty());
    b.robi.start(b.now);
    b.run_for(secs(1.0));
    assert!(b.frames.len() >= 9, "{}", b.frames.len());
    assert!(b.frames.iter().all(|(t, _)| *t >= secs(4.0)));
}

#[test]
fn the_handshake_is_version_1_and_announces_10_ms() {
    let mut b = Bench::new();
    assert_eq!(
        b.robi.handshake(),
        Handshake {
            version: 1,
            msdt_ms: 10
        }
    );
    // Connecting reads exactly the handshake's five bytes, then frames start.
    let read = b.connect();
    assert_eq!(read, vec![vec![0x7E, 0x01, 0x00, 0x0A, 0x7F]]);
    assert_eq!(
        Handshake::decode(&read[0]).unwrap().version_name(),
        Some("1.0.0")
    );
    b.run_for(ms(500));
    assert!(!b.frames.is_empty());
}

#[test]
fn frames_come_at_the_real_100_ms_not_the_announced_10_ms() {
    let mut b = Bench::lossless();
    b.connect();
    b.run_for(secs(10.0));
    // 10 s at 100 ms: 100 frames (plus the one at the start confirmation); at the announced
    // 10 ms it would be 1000.
    let n = b.frames.len();
    assert!((100..=101).contains(&n), "{n} frames in 10 s");
    let gaps: Vec<Duration> = b.frames.windows(2).map(|w| w[1].0 - w[0].0).collect();
    assert!(gaps.iter().all(|g| *g == ms(100)), "{gaps:?}");
    // What the firmware sends: motors, poti and buttons, nothing else.
    for (_, f) in &b.frames {
        assert_eq!(f.efs.bits(), 0x4300, "{f:?}");
        assert_eq!(f.efs, Efs::FIRMWARE);
        assert!(f.motors.is_some() && f.poti.is_some() && f.buttons.is_some());
        assert!(f.leds.is_none() && f.piezo.is_none());
    }
    // The configured interval is the one used.
    let mut b = Bench::with(SimConfig {
        robi_frame_interval: ms(250),
        robi_drop_every: 0,
        ..robi_cfg()
    });
    b.connect();
    b.run_for(secs(5.0));
    assert!((20..=21).contains(&b.frames.len()), "{}", b.frames.len());
}

#[test]
fn the_poti_turns_and_buttons_are_pressed_now_and_then() {
    let mut b = Bench::lossless();
    b.connect();
    b.run_for(secs(36.0));
    let potis: Vec<u8> = b.frames.iter().filter_map(|(_, f)| f.poti).collect();
    let (lo, hi) = (potis.iter().min().unwrap(), potis.iter().max().unwrap());
    assert!(*lo < 20 && *hi > 235, "poti {lo}..{hi}");
    let mut pressed = Buttons::empty();
    for (_, f) in &b.frames {
        let bt = f.buttons.unwrap();
        // One button at a time, a pupil's finger.
        assert!(bt.bits().count_ones() <= 1, "{bt:?}");
        pressed |= bt;
    }
    assert_eq!(pressed, Buttons::all(), "every button pressed once in 35 s");
}

#[test]
fn the_firmware_mix_turns_velocity_and_steering_into_wheel_speeds() {
    let mut b = Bench::lossless();
    b.connect();
    // Straight: steering 128 is 0.502 of the range, the nearest byte to the middle, so the
    // wheels are equal to within the firmware's own rounding (1/255 of full).
    b.control(255, 128);
    let (l, r) = b.robi.wheels();
    assert!(close(l, 1.0, 1e-6) && close(r, 1.0, 0.01), "{l} {r}");
    assert_eq!(b.robi.control(), (255, 128));
    // Full right: the left wheel at full, the right one stopped; full left the reverse.
    b.control(255, 255);
    assert_eq!(b.robi.wheels(), (1.0, 0.0));
    b.control(255, 0);
    assert_eq!(b.robi.wheels(), (0.0, 1.0));
    // Half velocity, half right: s' = 2(191/255 − 0.5) ≈ 0.498; left clamps at 1·v·1.5.
    b.control(128, 191);
    let (l, r) = b.robi.wheels();
    let v = 128.0 / 255.0;
    let sp = 2.0 * (191.0 / 255.0 - 0.5);
    assert!(close(l, v * (1.0 + sp), 1e-5) && close(r, v * (1.0 - sp), 1e-5));
    // Nothing reverses a wheel: velocity 0 is still, whatever the steering.
    b.control(0, 0);
    assert_eq!(b.robi.wheels(), (0.0, 0.0));

    // The frames report each wheel in rad/s.
    let full = full_rad_s();
    assert!(close(full, 10.0, 1e-4));
    for (vel, steer, left, right) in [
        (255, 255, full, 0.0),
        (255, 0, 0.0, full),
        (255, 128, full, full * 254.0 / 255.0),
        (0, 128, 0.0, 0.0),
    ] {
        b.control(vel, steer);
        b.run_for(ms(200));
        let m = b.last_frame().motors.unwrap();
        assert!(
            close(m.left_rad_s, left, 0.011) && close(m.right_rad_s, right, 0.011),
            "v {vel} s {steer}: {m:?}"
        );
    }
}

#[test]
fn a_side_below_the_stepper_minimum_is_switched_off() {
    // droid-facts §5: each side drives its stepper at side × 30 000 Hz and is switched off
    // below 100 Hz. Velocity 100 and steering 254: the inner side is 0.392 × 0.0078 of full,
    // 92 Hz, so that wheel stands still.
    let mut b = Bench::lossless();
    b.connect();
    b.control(100, 254);
    let (l, r) = b.robi.wheels();
    assert!(l > 0.7, "{l}");
    assert_eq!(r, 0.0, "92 Hz is below the stepper's 100 Hz");
    b.run_for(ms(200));
    assert_eq!(b.last_frame().motors.unwrap().right_rad_s, 0.0);
    // Above the minimum the side turns (255/254: 235 Hz).
    b.control(255, 254);
    assert!(b.robi.wheels().1 > 0.0);
}

#[test]
fn steering_right_while_driving_bends_the_path_right() {
    let mut b = Bench::open_field();
    b.connect();
    // Straight ahead first: along +y, heading 0.
    b.control(200, 128);
    b.run_for(secs(2.0));
    let st = b.state().clone();
    assert!(st.y_cm > 25.0, "{st:?}");
    // (Steering 128 is 1/255 right of the middle: the firmware drifts right by ~1 °/s.)
    assert!(st.x_cm.abs() < 2.0 && st.yaw_deg < 5.0, "{st:?}");
    // Steering right: the heading grows (clockwise) and the robot drifts to +x.
    b.control(200, 200);
    let mut yaws = Vec::new();
    for _ in 0..8 {
        b.run_for(ms(100));
        yaws.push(b.state().yaw_deg);
    }
    assert!(
        yaws.windows(2).all(|w| w[1] > w[0]) && yaws[0] > 2.0 && *yaws.last().unwrap() < 180.0,
        "{yaws:?}"
    );
    let right = b.state().clone();
    assert!(right.x_cm > st.x_cm + 3.0, "{right:?}");
    assert!(right.y_cm > st.y_cm, "still going forward: {right:?}");

    // The mirror image: steering left turns the heading the other way, to −x.
    let mut b = Bench::open_field();
    b.connect();
    b.control(200, 128);
    b.run_for(secs(2.0));
    b.control(200, 55);
    b.run_for(ms(800));
    let left = b.state().clone();
    assert!(left.yaw_deg > 180.0 && left.yaw_deg < 358.0, "{left:?}");
    assert!(left.x_cm < -3.0, "{left:?}");
}

#[test]
fn full_lock_pivots_on_the_inner_wheel() {
    let mut b = Bench::open_field();
    b.connect();
    // Full right: the right wheel stands, the left one runs: the body turns about the right
    // wheel at (30 cm/s / 10 cm) rad/s ≈ 172 °/s, its centre on a 5 cm circle.
    b.control(255, 255);
    b.run_for(secs(1.0));
    let st = b.state().clone();
    assert!(st.yaw_deg > 120.0 && st.yaw_deg < 200.0, "{st:?}");
    assert!(
        st.x_cm.hypot(st.y_cm) < 11.0,
        "stays near where it was: {st:?}"
    );
    assert!(st.x_cm > 0.0);
}

#[test]
fn lost_frames_leave_gaps_in_the_frame_ids() {
    let mut b = Bench::new();
    assert_eq!(robi_cfg().robi_drop_every, 40);
    b.connect();
    b.run_for(secs(20.0));
    let ids = b.ids();
    // 201 produced in 20 s (one at the start), one in 40 lost.
    let produced = 201;
    assert_eq!(ids.len(), produced - produced / 40, "{}", ids.len());
    let gaps: Vec<(usize, u32)> = ids
        .windows(2)
        .enumerate()
        .map(|(i, w)| (i, rsrcp::frame_gap(w[0], w[1])))
        .filter(|(_, g)| *g > 0)
        .collect();
    assert_eq!(gaps.len(), produced / 40, "{gaps:?}");
    assert!(
        gaps.iter().all(|(_, g)| *g == 1),
        "one frame each: {gaps:?}"
    );
    // The lost ones are the 40th, 80th, … produced.
    let lost: Vec<u32> = gaps.iter().map(|(i, _)| ids[*i] + 1).collect();
    let expect: Vec<u32> = (1..=(produced / 40) as u32)
        .map(|k| (FIRST_FRAME_ID + 40 * k - 1) & rsrcp::FRAME_ID_MASK)
        .collect();
    assert_eq!(lost, expect);
    // A lost frame also leaves a gap in time: 200 ms between the neighbours.
    for (i, _) in &gaps {
        assert_eq!(b.frames[i + 1].0 - b.frames[*i].0, ms(200));
    }
}

#[test]
fn frame_ids_wrap_from_0xffffff_to_0() {
    let mut b = Bench::lossless();
    b.connect();
    b.run_for(secs(10.0));
    let ids = b.ids();
    assert_eq!(ids[0], FIRST_FRAME_ID);
    assert_eq!(FIRST_FRAME_ID, 0xFF_FFC0);
    let at = ids
        .windows(2)
        .position(|w| w == [0xFF_FFFF, 0])
        .expect("0xFFFFFF then 0");
    assert_eq!(at, 63, "the wrap comes 64 frames (6.4 s) in");
    // Every id is the previous one plus one, modulo 2^24.
    assert!(
        ids.windows(2)
            .all(|w| rsrcp::frame_delta(w[0], w[1]) == 1 && w[1] <= rsrcp::FRAME_ID_MASK),
        "{ids:X?}"
    );
}

#[test]
fn the_motors_stop_when_the_host_goes_away() {
    let mut b = Bench::open_field();
    b.connect();
    b.control(255, 200);
    b.run_for(secs(1.0));
    assert!(b.state().velocity_cm_s > 20.0, "{:?}", b.state());
    // A frame is due exactly when the host goes.
    b.run_for(ms(90));
    let sent = b.frames.len();
    b.robi.host_gone(b.now + STEP);
    b.now += STEP;
    assert_eq!(b.robi.control(), (0, 128), "the remote control is reset");
    assert_eq!(b.robi.wheels(), (0.0, 0.0));
    // Nothing is sent while nobody listens; the robot brakes to a stop.
    b.run_for(secs(2.0));
    assert_eq!(b.frames.len(), sent);
    let st = b.state().clone();
    assert_eq!(st.velocity_cm_s, 0.0, "{st:?}");
    let rest = (st.x_cm, st.y_cm);
    b.run_for(secs(1.0));
    assert_eq!((b.state().x_cm, b.state().y_cm), rest);
    // A new host: the handshake again, and frames that report the motors stopped: none from
    // before the disconnect is delivered late.
    let read = b.connect();
    assert_eq!(read.len(), 1);
    assert!(Handshake::decode(&read[0]).is_ok());
    b.run_for(ms(500));
    let after = &b.frames[sent..];
    assert!(after.len() >= 5, "{}", after.len());
    for (t, f) in after {
        let m = f.motors.unwrap();
        assert_eq!((m.left_rad_s, m.right_rad_s), (0.0, 0.0), "at {t:?}: {f:?}");
    }
    // Ids go on from where they were (the robot did not restart).
    assert_eq!(
        rsrcp::frame_delta(b.frames[sent - 1].1.frame_id, after[0].1.frame_id),
        2
    );
}

#[test]
fn a_wall_stops_it_and_counts_one_collision() {
    // 4 m room, robot radius 8 cm: its centre stops 192 cm from the middle.
    let mut b = Bench::new();
    b.connect();
    b.control(255, 128);
    b.run_for(secs(10.0));
    let st = b.state().clone();
    assert!(close(st.y_cm, 192.0, 0.01), "{st:?}");
    assert_eq!(st.velocity_cm_s, 0.0, "{st:?}");
    // Pushing against the wall for seconds more is not another impact.
    b.run_for(secs(3.0));
    assert_eq!(b.state().collisions, 1, "{:?}", b.state());
    // The wheels still turn (a stepper robot does not know it is stuck): the frames say so.
    let m = b.last_frame().motors.unwrap();
    assert!(m.left_rad_s > 9.9, "{m:?}");
    // Backing off is impossible; steering away from the wall frees it.
    b.control(255, 255);
    b.run_for(secs(1.0));
    b.control(255, 128);
    b.run_for(secs(1.0));
    assert!(b.state().y_cm < 185.0, "{:?}", b.state());
}

#[test]
fn writes_to_the_command_channel_are_ignored() {
    let mut b = Bench::new();
    b.connect();
    b.robi
        .write(Endpoint::Api, &[0x8D, 0x0A, 0x16, 0x07], b.now);
    assert_eq!(b.robi.control(), (0, 128));
    assert_eq!(b.state().commands, 0);
    // A longer write to a remote-control input takes its last byte.
    b.robi.write(Endpoint::Velocity, &[1, 2, 90], b.now);
    assert_eq!(b.robi.control(), (90, 128));
}

// ---------------------------------------------------------------------------------------------
// Through SimLink and a session, under paused tokio time
// ---------------------------------------------------------------------------------------------

fn robi_config() -> SessionConfig {
    let model = Model::Robi42;
    SessionConfig {
        family: Protocol::Rsrcp,
        pacing: model.write_pacing(),
        setup: connect_setup(model, &SetupOptions::default()),
        ..SessionConfig::default()
    }
}

fn robi_session(cfg: SimConfig, faults: Faults) -> (SessionHandle, SimProbe) {
    let link = SimLink::new(Model::Robi42, cfg, faults);
    let probe = link.probe();
    let s = session::start(Box::new(link), robi_config());
    (s, probe)
}

/// Every notification with its time since `t0`, folded into a [`Telemetry`] as the app does.
#[derive(Clone)]
struct Collected {
    notes: Vec<(Duration, Notification)>,
    telemetry: Telemetry,
}

fn spawn_collector(s: &SessionHandle) -> Arc<Mutex<Collected>> {
    let seen = Arc::new(Mutex::new(Collected {
        notes: Vec::new(),
        telemetry: Telemetry::default(),
    }));
    let out = seen.clone();
    let mut rx = s.subscribe();
    let t0 = Instant::now();
    tokio::spawn(async move {
        loop {
            match rx.recv().await {
                Ok(SessionEvent::Notification(n)) => {
                    let at = t0.elapsed();
                    let mut c = out.lock().unwrap();
                    c.telemetry.apply(&n, at);
                    c.notes.push((at, n));
                }
                Ok(SessionEvent::BadNotification { name, reason }) => {
                    panic!("{name}: {reason}")
                }
                Err(broadcast::error::RecvError::Lagged(n)) => panic!("lagged {n}"),
                Err(broadcast::error::RecvError::Closed) => break,
            }
        }
    });
    seen
}

/// The remote-control writes the session logged, with their time.
fn spawn_out_log(s: &SessionHandle) -> Arc<Mutex<Vec<(Duration, RobiControl)>>> {
    let seen = Arc::new(Mutex::new(Vec::new()));
    let out = seen.clone();
    let mut rx = s.subscribe_log();
    tokio::spawn(async move {
        loop {
            match rx.recv().await {
                Ok(LogEntry {
                    at,
                    dir: Direction::Out,
                    item: LogItem::Packet { packet, .. },
                }) => {
                    let Packet::Robi(RobiPacket::Control(c)) = packet else {
                        panic!("a Robi session writes remote-control values: {packet:?}")
                    };
                    out.lock().unwrap().push((at, c));
                }
                Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => break,
            }
        }
    });
    seen
}

fn steer(speed: u8, turn: f32) -> AnyCommand {
    droidctl::family::for_model(Model::Robi42)
        .steer(speed, turn)
        .expect("Robi steers")
}

fn frames_of(notes: &[(Duration, Notification)]) -> Vec<(Duration, Frame)> {
    notes
        .iter()
        .filter_map(|(t, n)| match n {
            Notification::RobiFrame(f) => Some((*t, f.clone())),
            _ => None,
        })
        .collect()
}

#[tokio::test(start_paused = true)]
async fn the_handshake_arrives_first_then_frames_at_the_measured_rate() {
    let (s, probe) = robi_session(robi_cfg(), Faults::none());
    let seen = spawn_collector(&s);
    s.watch_state()
        .wait_for(|st| *st == LinkState::Connected)
        .await
        .unwrap();
    assert!(probe.connected());
    // Robi needs no setup: nothing is written on connect.
    assert!(robi_config().setup.is_empty());
    sleep(secs(10.0)).await;
    let c = seen.lock().unwrap().clone();
    let (first_at, first) = &c.notes[0];
    assert_eq!(
        *first,
        Notification::RobiHandshake(Handshake {
            version: 1,
            msdt_ms: 10
        })
    );
    let handshakes = c
        .notes
        .iter()
        .filter(|(_, n)| matches!(n, Notification::RobiHandshake(_)))
        .count();
    assert_eq!(handshakes, 1);
    let frames = frames_of(&c.notes);
    assert_eq!(frames.len() + 1, c.notes.len(), "handshake and frames only");
    assert!(frames[0].0 >= *first_at);
    // The session read them whole: no decode errors.
    let st = s.stats();
    assert_eq!((st.decode_errors, st.errors), (0, 0), "{st:?}");

    // Link quality as the panel shows it: ≈ 10 frames/s measured against the 100 announced,
    // the lost frames counted, and the 24-bit wrap (6.4 s in) not taken for a loss.
    let r = c.telemetry.robi.as_ref().expect("Robi telemetry");
    assert_eq!(r.announced_fps(), Some(100.0));
    let fps = r.measured_fps().unwrap();
    assert!(close(fps, 10.0, 0.3), "measured {fps}/s");
    assert_eq!(r.frames, frames.len() as u64);
    let produced = frames.len() as u64 + r.lost;
    assert!((100..=102).contains(&produced), "{produced}");
    assert_eq!(r.lost, produced / 40, "{r:?}");
    let last = r.frame_id.unwrap();
    assert!(last < 0x100, "the ids wrapped: last {last:#X}");
    assert!(
        frames
            .windows(2)
            .any(|w| w[0].1.frame_id == 0xFF_FFFF && w[1].1.frame_id == 0),
        "0xFFFFFF then 0 arrived"
    );
    // Standing still: odometry stays at the origin.
    assert_eq!((c.telemetry.x_cm, c.telemetry.y_cm), (Some(0.0), Some(0.0)));
    s.shutdown_stopped(vec![]).await;
}

#[tokio::test(start_paused = true)]
async fn a_drive_goes_out_as_velocity_then_steering_and_moves_the_robot() {
    let cfg = SimConfig {
        room_cm: (10_000.0, 10_000.0),
        ..robi_cfg()
    };
    let (s, probe) = robi_session(cfg, Faults::none());
    let seen = spawn_collector(&s);
    let written = spawn_out_log(&s);
    s.watch_state()
        .wait_for(|st| *st == LinkState::Connected)
        .await
        .unwrap();
    sleep(ms(300)).await;
    assert_eq!(probe.state().commands, 0);

    // Straight ahead at full speed for 2 s (no heartbeat needed: Robi holds its command).
    s.set(Slot::Drive, steer(255, 0.0));
    sleep(secs(2.0)).await;
    let st = probe.state();
    // One control is two writes, one per remote-control input.
    assert_eq!(st.commands, 2, "{st:?}");
    assert!(st.y_cm > 40.0 && st.x_cm.abs() < 2.0, "{st:?}");
    assert_eq!(
        written.lock().unwrap().last().unwrap().1,
        RobiControl {
            velocity: 255,
            steering: 128
        }
    );
    // The frames carry the wheel speeds: full on both sides.
    {
        let c = seen.lock().unwrap();
        let m = c.telemetry.robi.as_ref().unwrap().motors.unwrap();
        assert!(
            close(m.left_rad_s, 10.0, 0.01) && close(m.right_rad_s, 10.0, 0.05),
            "{m:?}"
        );
    }

    // Then right: the heading grows, x grows.
    s.set(Slot::Drive, steer(255, 0.6));
    sleep(secs(1.0)).await;
    let turned = probe.state();
    assert!(
        turned.yaw_deg > 20.0 && turned.yaw_deg < 180.0,
        "{turned:?}"
    );
    assert!(turned.x_cm > st.x_cm + 2.0, "{turned:?}");
    // Telemetry odometry follows the robot from the motor speeds in the frames, a frame
    // interval or two behind it while it turns (≈ 100 °/s here).
    let odometry_yaw = |c: &Collected| c.telemetry.heading().unwrap().degrees() as f32;
    {
        let c = seen.lock().unwrap();
        let yaw = odometry_yaw(&c);
        assert!(
            (yaw - turned.yaw_deg).abs() < 25.0,
            "odometry {yaw}° vs {}°",
            turned.yaw_deg
        );
        assert!(c.telemetry.x_cm.unwrap() > 2.0, "{:?}", c.telemetry.x_cm);
    }

    // Stop: velocity 0, straight; the robot comes to rest and reports its motors still.
    s.set(
        Slot::Drive,
        droidctl::family::for_model(Model::Robi42).stop_after(None),
    );
    sleep(secs(1.0)).await;
    let rest = probe.state();
    assert_eq!(rest.velocity_cm_s, 0.0);
    assert_eq!(written.lock().unwrap().last().unwrap().1, RobiControl::STOP);
    // At rest, odometry agrees with where the robot is: within a frame interval of turning,
    // and the few centimetres its speed ramps take (the frames report the wheels'
    // commanded speed).
    {
        let c = seen.lock().unwrap();
        let (x, y, yaw) = (
            c.telemetry.x_cm.unwrap(),
            c.telemetry.y_cm.unwrap(),
            odometry_yaw(&c),
        );
        assert!(
            (yaw - rest.yaw_deg).abs() < 12.0,
            "odometry {yaw}° vs {rest:?}"
        );
        assert!(
            (x - rest.x_cm).abs() < 12.0 && (y - rest.y_cm).abs() < 12.0,
            "odometry ({x}, {y}) vs {rest:?}"
        );
    }
    let c = seen.lock().unwrap().clone();
    let m = c.telemetry.robi.as_ref().unwrap().motors.unwrap();
    assert_eq!((m.left_rad_s, m.right_rad_s), (0.0, 0.0));
    s.shutdown_stopped(vec![]).await;
}

#[tokio::test(start_paused = true)]
async fn drive_controls_coalesce_latest_wins() {
    let (s, probe) = robi_session(robi_cfg(), Faults::none());
    let written = spawn_out_log(&s);
    s.watch_state()
        .wait_for(|st| *st == LinkState::Connected)
        .await
        .unwrap();
    sleep(ms(200)).await;
    // A storm of drive values faster than anything can be written: only the latest goes out.
    for i in 0..200u32 {
        s.set(Slot::Drive, steer((i % 200) as u8 + 10, -1.0));
    }
    s.set(Slot::Drive, steer(180, 1.0));
    sleep(ms(500)).await;
    let w = written.lock().unwrap().clone();
    assert_eq!(
        w.iter().map(|(_, c)| *c).collect::<Vec<_>>(),
        [RobiControl {
            velocity: 180,
            steering: 255
        }],
        "one write, the latest"
    );
    assert!(s.stats().coalesced >= 200, "{:?}", s.stats());
    assert_eq!(probe.state().commands, 2);
    // The robot does what the last value says: pivots right on its right wheel.
    let st = probe.state();
    assert!(st.yaw_deg > 30.0 && st.yaw_deg < 180.0, "{st:?}");
    // Under a steady stream (a control loop at 50 Hz) every write reaches the robot in order,
    // paced, and the last one wins.
    for i in 0..50u8 {
        s.set(Slot::Drive, steer(100 + i, 0.0));
        sleep(ms(20)).await;
    }
    sleep(ms(200)).await;
    let w = written.lock().unwrap().clone();
    assert_eq!(w.last().unwrap().1.velocity, 149);
    let times: Vec<Duration> = w.iter().map(|(t, _)| *t).collect();
    assert!(times.windows(2).all(|p| p[1] >= p[0]));
    s.shutdown_stopped(vec![]).await;
}

#[tokio::test(start_paused = true)]
async fn a_dropped_link_stops_the_robot_and_the_session_resumes_at_speed_0() {
    let cfg = SimConfig {
        room_cm: (10_000.0, 10_000.0),
        ..robi_cfg()
    };
    let faults = Faults {
        disconnect_at: vec![secs(3.0)],
        ..Faults::none()
    };
    // Times below count from here, as the session's log and the collector do.
    let t0 = Instant::now();
    let (s, probe) = robi_session(cfg, faults);
    let seen = spawn_collector(&s);
    let written = spawn_out_log(&s);
    let mut states = s.watch_state();
    states
        .wait_for(|st| *st == LinkState::Connected)
        .await
        .unwrap();
    sleep(ms(500)).await;
    // Driving with a control loop's heartbeat until just before the link drops at 3 s.
    while t0.elapsed() < secs(2.9) {
        s.set(Slot::Drive, steer(255, 0.0));
        sleep(ms(100)).await;
    }
    assert!(probe.state().velocity_cm_s > 25.0, "{:?}", probe.state());
    states
        .wait_for(|st| matches!(st, LinkState::Reconnecting { .. }))
        .await
        .unwrap();
    let dropped_at = t0.elapsed();
    assert!(
        close(dropped_at.as_secs_f32(), 3.0, 0.011),
        "{dropped_at:?}"
    );
    // The robot disabled its motors when the host went: it brakes to a stop on its own.
    sleep(ms(300)).await;
    assert!(!probe.connected());
    assert_eq!(probe.state().velocity_cm_s, 0.0, "{:?}", probe.state());
    states
        .wait_for(|st| *st == LinkState::Connected)
        .await
        .unwrap();
    let back_at = t0.elapsed();
    sleep(secs(2.0)).await;
    assert_eq!(s.stats().reconnects, 1);
    assert_eq!(probe.opens(), 2);
    // The session's resume after the reconnect: speed 0, straight, the only thing written.
    let w = written.lock().unwrap().clone();
    assert!(w.iter().any(|(t, _)| *t < dropped_at), "{w:?}");
    let after: Vec<RobiControl> = w
        .iter()
        .filter(|(t, _)| *t >= dropped_at)
        .map(|(_, c)| *c)
        .collect();
    assert_eq!(after, [RobiControl::STOP], "{w:?}");
    let st = probe.state();
    assert_eq!(st.velocity_cm_s, 0.0, "{st:?}");
    // The new connection starts with a handshake too, and its frames say the motors are off.
    let c = seen.lock().unwrap().clone();
    let hs: Vec<Duration> = c
        .notes
        .iter()
        .filter(|(_, n)| matches!(n, Notification::RobiHandshake(_)))
        .map(|(t, _)| *t)
        .collect();
    assert_eq!(hs.len(), 2, "{hs:?}");
    assert!(hs[1] >= back_at, "{hs:?} {back_at:?}");
    let later: Vec<_> = frames_of(&c.notes)
        .into_iter()
        .filter(|(t, _)| *t >= back_at)
        .collect();
    assert!(later.len() >= 15, "{}", later.len());
    for (t, f) in &later {
        let m = f.motors.unwrap();
        assert_eq!((m.left_rad_s, m.right_rad_s), (0.0, 0.0), "at {t:?}: {f:?}");
    }
    // The wrap and the reconnect are no lost frames beyond the air's one in 40, and the
    // measured rate is this connection's: the outage is not averaged in.
    let r = c.telemetry.robi.as_ref().unwrap();
    assert!(r.lost <= 3, "{r:?}");
    let fps = r.measured_fps().unwrap();
    assert!(
        close(fps, 10.0, 0.6),
        "measured {fps}/s after the reconnect"
    );
    s.shutdown_stopped(vec![]).await;
}

/// Link quality across a reconnect to a robot that restarted meanwhile: its frame ids begin
/// again from 0. The new handshake starts a new sequence: nothing is lost between the two,
/// and the measured rate is the new connection's.
#[test]
fn a_new_handshake_starts_a_new_frame_sequence() {
    let hs = Notification::RobiHandshake(Handshake {
        version: 1,
        msdt_ms: 10,
    });
    let frame = |id: u32| Notification::RobiFrame(Frame::new(id).with_motors(0.0, 0.0));
    let mut t = Telemetry::default();
    t.apply(&hs, ms(0));
    for (i, id) in (5_000..5_030).enumerate() {
        // One lost on the air: 5 010 never arrives.
        if id != 5_010 {
            t.apply(&frame(id), ms(100 + 100 * i as u64));
        }
    }
    let r = t.robi.as_ref().unwrap();
    assert_eq!((r.frames, r.lost), (29, 1));
    // Link down for 4 s; the robot restarted: ids from 0.
    t.apply(&hs, ms(7_000));
    for i in 0..10u32 {
        t.apply(&frame(i), ms(7_100 + 100 * i as u64));
    }
    let r = t.robi.as_ref().unwrap();
    assert_eq!(r.frames, 39);
    assert_eq!(r.lost, 1, "nothing lost across the reconnect: {r:?}");
    let fps = r.measured_fps().unwrap();
    assert!(close(fps, 10.0, 1e-3), "the new connection's rate: {fps}");
    assert_eq!(r.frame_id, Some(9));
    // Within the new connection, gaps count again.
    t.apply(&frame(12), ms(8_100));
    assert_eq!(t.robi.as_ref().unwrap().lost, 3);
}

// ---------------------------------------------------------------------------------------------
// Stepped only when due (issue 21): the same frames at the same times, far fewer steps idle.
// ---------------------------------------------------------------------------------------------

/// A simulator front with its steps counted; `every_step` hides when it is due, so the link
/// steps it at the full physics rate (as before).
struct Counted {
    inner: Box<dyn WireDroid>,
    every_step: bool,
    advances: Arc<Mutex<u64>>,
}

impl WireDroid for Counted {
    fn receive(&mut self, bytes: &[u8], now: Duration) -> Vec<Vec<u8>> {
        self.inner.receive(bytes, now)
    }
    fn receive_at(&mut self, to: Endpoint, bytes: &[u8], now: Duration) -> Vec<Vec<u8>> {
        self.inner.receive_at(to, bytes, now)
    }
    fn connect(&mut self, now: Duration) -> Vec<Vec<u8>> {
        self.inner.connect(now)
    }
    fn disconnected(&mut self, now: Duration) {
        self.inner.disconnected(now)
    }
    fn whole_notifications(&self) -> bool {
        self.inner.whole_notifications()
    }
    fn advance(&mut self, now: Duration) -> Vec<Vec<u8>> {
        *self.advances.lock().unwrap() += 1;
        self.inner.advance(now)
    }
    fn state(&self) -> &SimState {
        self.inner.state()
    }
    fn will_sleep(&self) -> Option<Vec<u8>> {
        self.inner.will_sleep()
    }
    fn handshake_value(&self) -> Vec<u8> {
        self.inner.handshake_value()
    }
    fn next_due(&self) -> Option<Duration> {
        if self.every_step {
            None
        } else {
            self.inner.next_due()
        }
    }
}

/// Idle 1 s, drive 1 s, stop, idle 4 s, through the link: every notification with when it
/// came out, and how often the robot was stepped.
async fn robi_run(every_step: bool) -> (Vec<(Duration, Vec<u8>)>, u64) {
    use droidctl::link::Link;
    let advances = Arc::new(Mutex::new(0));
    let cfg = robi_cfg();
    let droid = Counted {
        inner: Box::new(SimRobi::new(cfg.clone())),
        every_step,
        advances: advances.clone(),
    };
    let mut link = SimLink::with_droid(Model::Robi42, Box::new(droid), &cfg, Faults::none());
    let t0 = Instant::now();
    let mut conn = link.open().await.expect("open");
    let seen = Arc::new(Mutex::new(Vec::new()));
    let recorder = {
        let seen = seen.clone();
        tokio::spawn(async move {
            while let Some(ev) = conn.events.recv().await {
                if let droidctl::link::LinkEvent::Data(b) = ev {
                    seen.lock().unwrap().push((t0.elapsed(), b));
                }
            }
        })
    };
    let w = &mut conn.writer;
    sleep(secs(1.0)).await;
    w.write_to(Endpoint::Velocity, &[200]).await.unwrap();
    w.write_to(Endpoint::Steering, &[160]).await.unwrap();
    sleep(secs(1.0)).await;
    w.write_to(Endpoint::Velocity, &[0]).await.unwrap();
    sleep(secs(4.0)).await;
    w.close().await;
    sleep(ms(50)).await;
    recorder.abort();
    let seen = seen.lock().unwrap().clone();
    let n = *advances.lock().unwrap();
    (seen, n)
}

#[tokio::test(start_paused = true)]
async fn an_idle_robi_is_stepped_only_when_a_frame_is_due_with_identical_output() {
    let (due, due_steps) = robi_run(false).await;
    let (every, every_steps) = robi_run(true).await;
    assert!(due.len() > 50, "{} notifications", due.len());
    assert_eq!(due, every, "the same frames at the same times");
    // 6 s: 600 physics steps; stepped when due, one per frame (100 ms) idle, every step only
    // while it rolls (about 1.5 s with braking).
    assert!(every_steps >= 590, "{every_steps}");
    assert!(
        due_steps * 2 < every_steps,
        "stepped {due_steps} times (every step: {every_steps})"
    );
}
