//! The simulated Robi 42: the shared [`Body`] as a differential-drive robot behind RSRCP.
//!
//! As the real robot (`droid-facts.md` §5): the host reads the handshake (version 1, MSDT
//! 10 ms) and confirms the start; only then do frames flow, one per notification, carrying
//! motors, poti and buttons (EFS 0x4300) at the robot's real rate (100 ms by default, not the
//! announced 10 ms), with an occasional frame lost on the air (a gap in the 24-bit frame
//! id, which starts near the wrap so the wrap is exercised early). The remote control is two
//! bytes: velocity v and steering s, mixed as the firmware does — left = v(1 + s'),
//! right = v(1 − s'), s' = 2(s − 0.5), each clamped to 0..1. The motors stop when the host
//! disconnects. The poti turns slowly and the buttons are pressed now and then, as a pupil
//! would.

use super::SimConfig;
use super::body::{Body, SimState};
use crate::gatt::Endpoint;
use crate::model::Model;
use crate::protocol::rsrcp::{self, Buttons, Frame, Handshake};
use std::time::Duration;

/// Where frame ids start: 64 frames before the 24-bit wrap.
pub const FIRST_FRAME_ID: u32 = 0xFF_FFC0;

/// The simulated Robi 42.
#[derive(Debug, Clone)]
pub struct SimRobi {
    body: Body,
    started: bool,
    velocity: u8,
    steering: u8,
    frame_id: u32,
    next_frame: Duration,
    /// Frames produced (sent or lost), for the loss pattern.
    produced: u64,
    out: Vec<Vec<u8>>,
}

impl SimRobi {
    /// The Robi 42's figures: a slow, small differential-drive robot.
    pub fn config() -> SimConfig {
        SimConfig {
            top_speed_cm_s: 30.0,
            accel_cm_s2: 60.0,
            brake_cm_s2: 120.0,
            radius_cm: 8.0,
            ..SimConfig::default()
        }
    }

    pub fn new(cfg: SimConfig) -> Self {
        let mut body = Body::new(Model::Robi42, cfg);
        body.wake();
        // Robi has no sleep timer.
        body.set_inactivity_timeout(Duration::from_secs(u32::MAX as u64));
        SimRobi {
            body,
            started: false,
            velocity: 0,
            steering: rsrcp::STEERING_STRAIGHT,
            frame_id: FIRST_FRAME_ID,
            next_frame: Duration::ZERO,
            produced: 0,
            out: Vec::new(),
        }
    }

    pub fn state(&self) -> &SimState {
        self.body.state()
    }

    /// The handshake characteristic's value.
    pub fn handshake(&self) -> Handshake {
        Handshake {
            version: rsrcp::VERSION_1_0_0,
            msdt_ms: self.body.cfg.robi_msdt_ms,
        }
    }

    /// The start confirmation: frames flow from now on.
    pub fn start(&mut self, now: Duration) {
        self.body.advance_to(now);
        self.started = true;
        self.next_frame = now;
    }

    /// The remote-control bytes last written.
    pub fn control(&self) -> (u8, u8) {
        (self.velocity, self.steering)
    }

    /// The wheel speeds the firmware derives from the remote control, 0..=1 each.
    pub fn wheels(&self) -> (f32, f32) {
        let (l, r) = rsrcp::wheel_speeds(self.velocity, self.steering);
        // Fix: the firmware switches a side's stepper off below 100 Hz (`droid-facts.md` §5);
        // the mix alone left a slow inner wheel creeping (velocity 100, steering 254: 92 Hz).
        let stepper = |side: f32| {
            if rsrcp::stepper_hz(side) > 0.0 {
                side
            } else {
                0.0
            }
        };
        (stepper(l), stepper(r))
    }

    /// A write to the remote-control service at `now`.
    pub fn write(&mut self, to: Endpoint, bytes: &[u8], now: Duration) {
        self.advance_to(now);
        // One byte each; anything longer is what a confused client sends: take the last.
        let Some(&b) = bytes.last() else { return };
        match to {
            Endpoint::Velocity => self.velocity = b,
            Endpoint::Steering => self.steering = b,
            Endpoint::Api => return,
        }
        self.body.state.commands += 1;
        let (l, r) = self.wheels();
        self.body.drive_wheels(l, r);
    }

    /// The host went away: the robot disables both motors.
    pub fn host_gone(&mut self, now: Duration) {
        self.advance_to(now);
        // Fix: frames due up to now were kept and handed to the next host right after its
        // handshake, reporting the motors running on a robot that had stopped. Nobody
        // received them: they are lost.
        self.out.clear();
        self.started = false;
        self.velocity = 0;
        self.steering = rsrcp::STEERING_STRAIGHT;
        self.body.drive_wheels(0.0, 0.0);
    }

    /// When the robot next has something to send: its next frame while frames flow, else
    /// what its body has due; `None` while it rolls (stepped every physics step). Frames are
    /// made at their own times however often the robot is advanced, so a host that steps it
    /// only then sees the same frames at the same times (issue 21: it was stepped at the full
    /// physics rate, 100 times a second, when idle).
    pub fn next_due(&self) -> Option<Duration> {
        let body = self.body.next_due()?;
        Some(if self.started {
            body.min(self.next_frame)
        } else {
            body
        })
    }

    /// Let time pass; returns the frames due, each one notification.
    pub fn advance(&mut self, now: Duration) -> Vec<Vec<u8>> {
        self.advance_to(now);
        std::mem::take(&mut self.out)
    }

    fn advance_to(&mut self, now: Duration) {
        let every = self
            .body
            .cfg
            .robi_frame_interval
            .max(Duration::from_millis(1));
        while self.started && self.next_frame <= now {
            let at = self.next_frame;
            self.body.advance_to(at);
            self.frame(at);
            self.next_frame += every;
        }
        self.body.advance_to(now);
        // Collisions and the rest are physics only: RSRCP has no way to report them.
        let _ = self.body.take_events();
    }

    fn frame(&mut self, at: Duration) {
        let id = self.frame_id;
        self.frame_id = (self.frame_id + 1) & rsrcp::FRAME_ID_MASK;
        self.produced += 1;
        let drop_every = self.body.cfg.robi_drop_every as u64;
        if drop_every > 0 && self.produced.is_multiple_of(drop_every) {
            return;
        }
        let (l, r) = self.body.wheel_rad_s();
        let t = at.as_secs_f32();
        // The poti turns back and forth over 20 s; a button is pressed 0.5 s in every 7 s,
        // a different one each time.
        let poti = (127.5 + 120.0 * (t * std::f32::consts::TAU / 20.0).sin()).round() as u8;
        let period = (t / 7.0) as u32;
        let buttons = if t % 7.0 >= 6.5 {
            [
                Buttons::CENTER,
                Buttons::LEFT,
                Buttons::RIGHT,
                Buttons::TOP,
                Buttons::BOTTOM,
            ][(period % 5) as usize]
        } else {
            Buttons::empty()
        };
        let f = Frame::new(id)
            .with_motors(l, r)
            .with_poti(poti)
            .with_buttons(buttons);
        self.out.push(f.encode());
    }
}

impl super::WireDroid for SimRobi {
    /// Robi has no command channel.
    fn receive(&mut self, _bytes: &[u8], now: Duration) -> Vec<Vec<u8>> {
        self.advance(now)
    }

    fn receive_at(&mut self, to: Endpoint, bytes: &[u8], now: Duration) -> Vec<Vec<u8>> {
        self.write(to, bytes, now);
        std::mem::take(&mut self.out)
    }

    fn advance(&mut self, now: Duration) -> Vec<Vec<u8>> {
        SimRobi::advance(self, now)
    }

    fn state(&self) -> &SimState {
        SimRobi::state(self)
    }

    /// Read the handshake, write the start confirmation.
    fn connect(&mut self, now: Duration) -> Vec<Vec<u8>> {
        let hs = self.handshake().encode().to_vec();
        self.start(now);
        vec![hs]
    }

    fn disconnected(&mut self, now: Duration) {
        self.host_gone(now);
    }

    fn whole_notifications(&self) -> bool {
        true
    }

    /// Robi has no sleep timer.
    fn will_sleep(&self) -> Option<Vec<u8>> {
        None
    }

    fn handshake_value(&self) -> Vec<u8> {
        self.handshake().encode().to_vec()
    }

    fn next_due(&self) -> Option<Duration> {
        SimRobi::next_due(self)
    }
}
