//! The simulated v1 droid (BB-8, SPRK+, Ollie): the shared [`Body`] behind a Sphero API v1
//! front. Sans-IO: wire bytes and time in, packets out.
//!
//! As a real v1 droid it answers every command of its catalogue (echoing the SEQ, only when
//! the command's answer bit is set), resets its inactivity timer only on commands with the
//! reset-timeout bit, streams M frames per async packet at 400/N Hz for PCNT packets,
//! reports collisions (ID 07), power changes (ID 01, when enabled) and the pre-sleep warning
//! (ID 05) 10 s before it sleeps (`sphero-v1-packets.md`, `droid-facts.md` §4).

use super::SimConfig;
use super::body::{Body, SimEvent, SimState};
use crate::model::Model;
use crate::protocol::schema;
use crate::protocol::v1::{
    self, AsyncPacket, CommandPacket, Decoder, Mrsp, Packet, Response, Source, StreamingConfig,
    catalog,
};
use std::time::Duration;

/// Index of the back LED in [`SimState::leds`]; 0..=2 hold the main RGB LED.
pub const BACK_LED: usize = 3;

/// Async ID codes (`sphero-v1-packets.md`).
const ID_POWER: u8 = 0x01;
const ID_SENSORS: u8 = 0x03;
const ID_PRE_SLEEP: u8 = 0x05;
const ID_COLLISION: u8 = 0x07;

/// The simulated v1 droid.
#[derive(Debug, Clone)]
pub struct SimDroidV1 {
    body: Body,
    decoder: Decoder,
    streaming: StreamingConfig,
    /// Frames collected for the next sensor packet (M per packet).
    frames: Vec<Vec<(&'static str, f32)>>,
    /// Sensor packets still to send (PCNT; `None` = forever).
    packets_left: Option<u32>,
    power_notify: bool,
    stabilization: bool,
    rotation_rate: u8,
    /// The raw motors' last power per side, −1..=1 (Set Raw Motors' "ignore" keeps a side).
    raw_motors: (f32, f32),
    /// Set Temporary Option Flags (bit 0: stop on disconnect).
    option_flags: u32,
    out: Vec<Packet>,
}

impl SimDroidV1 {
    pub fn new(model: Model, cfg: SimConfig) -> Self {
        let mut body = Body::new(model, cfg);
        // The link's wake sequence (`droid-facts.md` §4) has woken it by the time bytes flow.
        body.wake();
        SimDroidV1 {
            body,
            decoder: Decoder::new(Source::Host),
            streaming: StreamingConfig::default(),
            frames: Vec::new(),
            packets_left: None,
            power_notify: false,
            stabilization: true,
            rotation_rate: 0xC8,
            raw_motors: (0.0, 0.0),
            option_flags: 0,
            out: Vec::new(),
        }
    }

    pub fn model(&self) -> Model {
        self.body.model()
    }

    /// A person puts the droid on its charger or takes it off ([`Body::set_on_charger`]).
    pub fn set_on_charger(&mut self, on: bool) {
        self.body.set_on_charger(on);
    }

    /// When the droid next has something to send ([`super::body::Body::next_due`]).
    pub fn next_due(&self) -> Option<Duration> {
        self.body.next_due()
    }

    pub fn state(&self) -> &SimState {
        self.body.state()
    }

    pub fn now(&self) -> Duration {
        self.body.now()
    }

    /// Whether the droid is stabilised (aim mode keeps it on).
    pub fn stabilization(&self) -> bool {
        self.stabilization
    }

    /// The temporary option flags in effect.
    pub fn option_flags(&self) -> u32 {
        self.option_flags
    }

    /// The host's link dropped: with stop-on-disconnect set (Set Temporary Option Flags bit
    /// 0) the droid stops at once; without it, it keeps its last motion. Temporary flags last
    /// until the droid sleeps, so they are cleared with the link, as on a reconnect they are
    /// set again.
    pub fn host_gone(&mut self, now: Duration) {
        self.advance_to(now);
        if self.option_flags & crate::protocol::v1::catalog::TEMP_OPTION_STOP_ON_DISCONNECT != 0 {
            self.body.stop_motion();
            self.raw_motors = (0.0, 0.0);
        }
    }

    /// Wire bytes from the host at time `now`; returns the packets the droid sends back.
    pub fn receive(&mut self, bytes: &[u8], now: Duration) -> Vec<Packet> {
        self.advance_to(now);
        let packets: Vec<_> = self.decoder.feed(bytes).collect();
        for r in packets {
            match r {
                Ok(Packet::Command(c)) => self.handle(c),
                Ok(_) => {}
                Err(_) => self.body.state.decode_errors += 1,
            }
        }
        std::mem::take(&mut self.out)
    }

    /// Let time pass; returns the async messages due.
    pub fn advance(&mut self, now: Duration) -> Vec<Packet> {
        self.advance_to(now);
        std::mem::take(&mut self.out)
    }

    fn advance_to(&mut self, now: Duration) {
        self.body.advance_to(now);
        self.flush_events();
    }

    fn send_async(&mut self, id_code: u8, data: Vec<u8>) {
        self.out
            .push(Packet::Async(AsyncPacket::new(id_code, data)));
    }

    fn flush_events(&mut self) {
        for e in self.body.take_events() {
            match e {
                SimEvent::WillSleep => self.send_async(ID_PRE_SLEEP, vec![]),
                SimEvent::DidSleep => {
                    self.streaming = StreamingConfig::default();
                    self.frames.clear();
                }
                SimEvent::VoltageState(s) if self.power_notify => {
                    // Body: 1 ok, 2 low, 3 critical; v1: 2 OK, 3 low, 4 critical.
                    self.send_async(ID_POWER, vec![s.saturating_add(1).min(4)]);
                }
                // v1 power states: 1 charging, 2 OK (droid-facts' Get Power State).
                SimEvent::Charger(on) if self.power_notify => {
                    let state = if on {
                        1
                    } else {
                        self.body.voltage_state_now().saturating_add(1).min(4)
                    };
                    self.send_async(ID_POWER, vec![state]);
                }
                SimEvent::Collision(c) => {
                    self.send_async(ID_COLLISION, v1::encode_collision(&c));
                }
                SimEvent::Sample(values) => self.sample(values),
                SimEvent::VoltageState(_)
                | SimEvent::Charger(_)
                | SimEvent::LegActionComplete
                | SimEvent::AnimationComplete => {}
            }
        }
    }

    /// One sensor frame; every M frames make a packet, for PCNT packets.
    fn sample(&mut self, mut values: Vec<(&'static str, f32)>) {
        // Ollie streams its locator and velocity in its own axes (spherov2, see
        // `v1::sensor::rotated_axes`).
        v1::sensor::to_droid_axes(self.body.model(), &mut values);
        self.frames.push(values);
        if self.frames.len() < self.streaming.m.max(1) as usize {
            return;
        }
        let frames = std::mem::take(&mut self.frames);
        let data = v1::encode_samples(&self.streaming, &frames);
        self.send_async(ID_SENSORS, data);
        if let Some(left) = &mut self.packets_left {
            *left = left.saturating_sub(1);
            if *left == 0 {
                self.packets_left = None;
                self.streaming = StreamingConfig::default();
                self.body.set_streaming(None);
            }
        }
    }

    fn handle(&mut self, p: CommandPacket) {
        self.body.state.commands += 1;
        if !self.body.state.awake {
            // Asleep, the real droid drops the link; the host's reconnect (the wake sequence)
            // wakes it, which is what the next command stands for here.
            self.body.wake();
        }
        if p.reset_timeout() {
            self.body.activity();
        }
        let (mrsp, data) = self.execute(&p);
        self.flush_events();
        if p.answer() {
            let data = if mrsp.is_success() { data } else { Vec::new() };
            self.out
                .push(Packet::Response(Response::to(&p, mrsp, data)));
        }
    }

    /// Run one command: the response code and payload.
    fn execute(&mut self, p: &CommandPacket) -> (Mrsp, Vec<u8>) {
        let Some(def) = catalog::lookup(p.did, p.cid) else {
            let known_device = matches!(p.did, 0x00 | 0x02);
            return (
                if known_device {
                    Mrsp::from_byte(0x04)
                } else {
                    Mrsp::from_byte(0x09)
                },
                vec![],
            );
        };
        // Payloads real clients send besides the catalogue's are accepted as real droids
        // accept them (fix: the simulator refused them with "bad message format", so
        // spherov2.py could not get through its connect routine nor drive).
        if !schema::length_ok(def.params, p.data.len())
            && catalog::client_variant(p.did, p.cid, &p.data).is_none()
        {
            return (Mrsp::from_byte(0x06), vec![]);
        }
        let d = &p.data;
        let u16_at = |i: usize| u16::from_be_bytes([d[i], d[i + 1]]);
        let ok = (Mrsp::from_byte(0x00), vec![]);
        match (p.did, p.cid) {
            // Core: Set Power Notification.
            (0x00, 0x21) => {
                self.power_notify = d[0] != 0;
                ok
            }
            // Core: Get Power State: record version, state, volts × 100, charges, time.
            (0x00, 0x20) => {
                let state = self.body.voltage_state_now().saturating_add(1).min(4);
                let mut out = vec![1, state];
                out.extend_from_slice(&self.body.centivolts().to_be_bytes());
                out.extend_from_slice(&3u16.to_be_bytes());
                out.extend_from_slice(&(self.body.now().as_secs() as u16).to_be_bytes());
                (Mrsp::from_byte(0x00), out)
            }
            // Core: Sleep.
            (0x00, 0x22) => {
                self.body.fall_asleep();
                ok
            }
            // Core: Set Inactivity Timeout (seconds).
            (0x00, 0x25) => {
                self.body
                    .set_inactivity_timeout(Duration::from_secs(u16_at(0) as u64));
                ok
            }
            // Set Heading: the current facing becomes this heading.
            (0x02, 0x01) => {
                let h = u16_at(0);
                if h > 359 {
                    return (Mrsp::from_byte(0x07), vec![]);
                }
                self.body.set_heading(h as f32);
                ok
            }
            (0x02, 0x02) => {
                self.stabilization = d[0] != 0;
                ok
            }
            (0x02, 0x03) => {
                self.rotation_rate = d[0];
                ok
            }
            // Set Data Streaming: 400/N Hz, M frames a packet, PCNT packets (0: forever).
            (0x02, 0x11) => match StreamingConfig::from_command_data(d) {
                Some(cfg) => {
                    let on = cfg.mask != 0 || cfg.mask2 != 0;
                    let every =
                        (on && cfg.n > 0).then(|| Duration::from_micros(cfg.n as u64 * 2500));
                    self.packets_left = (cfg.pcnt > 0).then_some(cfg.pcnt as u32);
                    self.streaming = cfg;
                    self.frames.clear();
                    self.body.set_streaming(every);
                    ok
                }
                None => (Mrsp::from_byte(0x07), vec![]),
            },
            // Configure Collision Detection: method, Xt, Xspd, Yt, Yspd, dead time (10 ms).
            (0x02, 0x12) => {
                self.body.collision_notify = d[0] != 0;
                self.body.collision_thresholds = super::body::CollisionThresholds {
                    x_threshold: d[1],
                    x_speed: d[2],
                    y_threshold: d[3],
                    y_speed: d[4],
                };
                self.body.collision_dead_time = Duration::from_millis(d[5] as u64 * 10);
                ok
            }
            (0x02, 0x20) => {
                self.body.state.leds[..3].copy_from_slice(&d[..3]);
                ok
            }
            (0x02, 0x21) => {
                self.body.state.leds[BACK_LED] = d[0];
                ok
            }
            (0x02, 0x22) => (Mrsp::from_byte(0x00), self.body.state.leds[..3].to_vec()),
            // Roll: speed, heading, state (0 stop).
            (0x02, 0x30) => {
                let heading = u16_at(1);
                if heading > 359 {
                    return (Mrsp::from_byte(0x07), vec![]);
                }
                let speed = if d[3] == 0 { 0 } else { d[0] };
                // spherov2.py's fifth byte: 1 backs up along the heading.
                let reverse = d.get(4).is_some_and(|&r| r != 0);
                // The control system takes the motors back.
                self.raw_motors = (0.0, 0.0);
                self.body.drive(speed, heading as f32, reverse);
                ok
            }
            // Set Raw Motors: [left mode, left power, right mode, right power]; modes 0 off,
            // 1 forward, 2 reverse, 3 brake, 4 ignore (keep that side as it is). The control
            // system lets go and the motors run open-loop: no stabilisation, each side at its
            // power's share of top speed, the body turning by the difference of the two
            // (fix, issue 32 point 3: the simulator stopped the body instead, so spherov2's
            // `raw_motor` moved a v1 droid 0 cm).
            (0x02, 0x33) => {
                let side = |mode: u8, power: u8, was: f32| match mode {
                    0 | 3 => Some(0.0),
                    1 => Some(power as f32 / 255.0),
                    2 => Some(-(power as f32) / 255.0),
                    4 => Some(was),
                    _ => None,
                };
                let (was_l, was_r) = self.raw_motors;
                match (side(d[0], d[1], was_l), side(d[2], d[3], was_r)) {
                    (Some(l), Some(r)) => {
                        self.raw_motors = (l, r);
                        self.stabilization = false;
                        self.body.drive_tracks(l, r);
                        ok
                    }
                    _ => (Mrsp::from_byte(0x07), vec![]),
                }
            }
            (0x02, 0x37) => {
                self.option_flags = u32::from_be_bytes([d[0], d[1], d[2], d[3]]);
                ok
            }
            // Everything else is accepted; getters answer with a well-formed payload.
            _ => (Mrsp::from_byte(0x00), schema::minimal_payload(def.response)),
        }
    }
}
