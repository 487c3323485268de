//! Robot-to-robot infrared in the simulator (BOLT and RVR): messages, broadcasting, following
//! and evading between the droids of one shared room ([`super::room`]). Sans-IO, on the
//! simulator's clock: the v2 front ([`super::droid::SimDroid`]) hands the Sensor commands here,
//! steers its body with [`Infrared::steer`] at each physics step while it follows or evades,
//! and turns the codes that reached it into robot-to-robot IR message notifications
//! (Sensor 0x2C, one byte: the code).
//!
//! Which commands each robot has. spherov2.py 0.12 binds BOLT (`toy/bolt.py`, no target) to
//! start/stop broadcasting, following and evading (0x27, 0x28, 0x29, 0x32, 0x33, 0x34) and to
//! the robot-to-robot send (0x2A) and listen (0x2B) commands; RVR (`toy/rvr.py`, on the
//! secondary processor) to the same behaviours but to the newer send infrared message (0x3F)
//! and enable IR message notify (0x3E) instead, which is what Sphero's own RVR SDK
//! (`sphero-sdk-raspberrypi-python`, `common/commands/sensor.py`) sends. `droid-facts.md` §6
//! gives BOLT 0x27–0x2B and 0x32–0x34, which agrees. The simulator answers each robot's own and
//! refuses the others' as a robot refuses any command it lacks (bad command id); no other
//! model has infrared.
//!
//! The wire. 0x27/0x28/0x33 take `[far, near]` codes (spherov2 and the RVR SDK agree).
//! 0x3F is `[code, front, left, right, rear]` strengths (the RVR SDK's names). 0x2A's five
//! bytes are unnamed in spherov2 ("Untested / Unknown param names"); the RVR SDK's first
//! releases sent the same fields under it (`send_robot_to_robot_infrared_message(code, front,
//! left, right, rear)`) and spherov2's commented-out BOLT line does too, so they are read as
//! 0x3F's. 0x2B's two bytes are unnamed as well: the first is the code listened for (those
//! first RVR SDK releases: `listen_for_robot_to_robot_infrared_message(code, duration)`); the
//! second is taken as that listen's duration and ignored (droidctl sends 0xFF: without end).
//! A listen is heard once: the code is notified and that listen is over, as the programs
//! Sphero Edu writes for its IR message events listen again in the handler (*unverified* on a
//! BOLT; a program that listens again works either way). 0x3E's one byte enables
//! notifications of every code until disabled (the RVR SDK's examples enable it once).
//!
//! The physics, from Sphero Edu's "Communications" page: four emitter/receiver pairs around
//! the robot, an effective range of about 3 m; a broadcaster's near code carries under 1 m, its
//! far code 1 to 3 m. A message's strength ("intensity", 1..=64, "proportional to proximity, 1
//! the closest, 64 the farthest") scales its reach linearly: strength s reaches
//! [`RANGE_CM`]·s/64 between the two robots' edges (64: 3 m; 32: 1.5 m; 1: under 5 cm, about
//! touching). Each of the four strengths is one emitter's: the front, left, right or rear
//! quarter around the sender's facing, whichever the receiver is in; 0 is that emitter off,
//! above 64 counts as 64. Nothing blocks the light (no line of sight is modelled).
//!
//! The behaviours (Sphero's words: a follower "will adjust its heading and speed to follow the
//! broadcaster", an evader "will adjust its heading to roll away", and either "will spin in
//! place to search" when it sees none; an evader "may stop if it is in the far range for a
//! period of time"), with figures of the simulator's own (*unverified*): a follower rolls
//! toward the nearest broadcaster of its pair at [`FOLLOW_FAR_SPEED`] while it is in the far
//! range, [`FOLLOW_NEAR_SPEED`] in the near range, and holds still once within
//! [`FOLLOW_STOP_CM`] of it; an evader rolls away at [`EVADE_NEAR_SPEED`] in the near range,
//! [`EVADE_FAR_SPEED`] in the far range for [`EVADE_FAR_FOR`], then stops there; with none in
//! range both turn in place at [`SEARCH_DEG_S`]. While a robot follows or evades it steers
//! itself: the host's drive commands are overridden at the next step (*unverified*); stopping
//! the behaviour stops the robot.

use super::physics::{angle_diff, wrap360};
use super::room::Place;
use crate::protocol::v2::ErrorCode;
use std::collections::VecDeque;
use std::time::Duration;

/// The farthest infrared carries, edge to edge, cm.
pub const RANGE_CM: f32 = 300.0;
/// A broadcaster's near code carries this far, cm; its far code beyond, to [`RANGE_CM`].
pub const NEAR_CM: f32 = 100.0;
/// The strongest a message is sent (Sphero Edu's intensity 1..=64).
pub const MAX_STRENGTH: u8 = 64;
/// Codes (channels) 0..=7.
pub const CHANNELS: u8 = 8;
/// Messages a robot keeps between two of its steps (more drop the oldest).
const INBOX_MAX: usize = 16;
/// How often a robot that listens looks for messages when nothing else wakes it.
pub const LISTEN_POLL: Duration = Duration::from_millis(20);
/// Drive speeds (0..=255) of the behaviours.
pub const FOLLOW_FAR_SPEED: u8 = 90;
pub const FOLLOW_NEAR_SPEED: u8 = 45;
pub const EVADE_NEAR_SPEED: u8 = 90;
pub const EVADE_FAR_SPEED: u8 = 45;
/// A follower holds still this close to the broadcaster, edge to edge, cm.
pub const FOLLOW_STOP_CM: f32 = 15.0;
/// An evader in the far range rolls on this long, then stops.
pub const EVADE_FAR_FOR: Duration = Duration::from_secs(2);
/// How fast a robot that sees no broadcaster turns in place, °/s.
pub const SEARCH_DEG_S: f32 = 120.0;

/// A broadcaster's pair of codes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Codes {
    pub far: u8,
    pub near: u8,
}

impl Codes {
    /// `[far, near]`, each 0..=7.
    fn from_wire(d: &[u8]) -> Result<Codes, ErrorCode> {
        match d {
            [far, near] if *far < CHANNELS && *near < CHANNELS => Ok(Codes {
                far: *far,
                near: *near,
            }),
            _ => Err(ErrorCode::BadParameterValue),
        }
    }
}

/// What a robot does about the broadcasters of its pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Behaviour {
    Follow,
    Evade,
}

/// What one robot of a room shows the others (kept in the room).
#[derive(Debug, Clone, Default)]
pub(super) struct Station {
    beacon: Option<Codes>,
    /// Codes listened for, a bit each.
    listening: u8,
    inbox: VecDeque<u8>,
}

/// Where a robot sees a broadcaster: the gap between them (edge to edge, cm) and its bearing
/// (degrees clockwise from +y, the body's heading frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sighting {
    pub gap_cm: f32,
    pub bearing_deg: f32,
}

/// One robot's infrared, as its front keeps it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Infrared {
    pub broadcasting: Option<Codes>,
    pub behaviour: Option<(Behaviour, Codes)>,
    /// Codes listened for once each (0x2B), a bit each.
    pub listening: u8,
    /// Every code notified (0x3E).
    pub notify: bool,
    /// Messages sent, and messages heard (notified).
    pub sent: u32,
    pub heard: u32,
    /// An evader entered the far range then.
    far_since: Option<Duration>,
}

/// Whether a model has an infrared Sensor command: the family's word
/// ([`crate::family::v2::robots::infrared_has`]).
pub use crate::family::v2::robots::infrared_has as has;

/// How far a message of `strength` carries, edge to edge, cm.
pub fn reach(strength: u8) -> f32 {
    RANGE_CM * strength.min(MAX_STRENGTH) as f32 / MAX_STRENGTH as f32
}

/// The bearing of (`dx`, `dy`), degrees clockwise from +y.
fn bearing(dx: f32, dy: f32) -> f32 {
    wrap360(dx.atan2(dy).to_degrees())
}

/// Which emitter of a robot facing `facing_deg` faces (`dx`, `dy`): 0 front, 1 left, 2
/// right, 3 rear (the order of 0x3F's strengths).
fn emitter(facing_deg: f32, dx: f32, dy: f32) -> usize {
    let rel = angle_diff(facing_deg, bearing(dx, dy));
    if rel.abs() <= 45.0 {
        0
    } else if (-135.0..-45.0).contains(&rel) {
        1
    } else if rel > 45.0 && rel < 135.0 {
        2
    } else {
        3
    }
}

impl Infrared {
    /// Sensor command `cid` (one [`has`] names) with payload `d` (of the catalogue's length),
    /// by a robot at `place` (`None`: alone) facing `facing_deg`.
    pub fn command(
        &mut self,
        cid: u8,
        d: &[u8],
        place: Option<&Place>,
        facing_deg: f32,
    ) -> Result<(), ErrorCode> {
        let code = |i: usize| match d.get(i) {
            Some(c) if *c < CHANNELS => Ok(*c),
            _ => Err(ErrorCode::BadParameterValue),
        };
        match cid {
            0x27 => self.broadcasting = Some(Codes::from_wire(d)?),
            0x29 => self.broadcasting = None,
            0x28 | 0x33 => {
                let b = if cid == 0x28 {
                    Behaviour::Follow
                } else {
                    Behaviour::Evade
                };
                self.behaviour = Some((b, Codes::from_wire(d)?));
                self.far_since = None;
            }
            0x32 | 0x34 => {
                let b = if cid == 0x32 {
                    Behaviour::Follow
                } else {
                    Behaviour::Evade
                };
                if self.behaviour.is_some_and(|(x, _)| x == b) {
                    self.behaviour = None;
                }
            }
            0x2A | 0x3F => {
                let c = code(0)?;
                let at = |i: usize| d.get(i).copied().unwrap_or(0);
                let strengths = [at(1), at(2), at(3), at(4)];
                self.sent += 1;
                if let Some(p) = place {
                    p.send_ir(c, strengths, facing_deg);
                }
            }
            0x2B => self.listening |= 1 << code(0)?,
            0x3E => self.notify = d.first().is_some_and(|b| *b != 0),
            _ => return Err(ErrorCode::BadCommandId),
        }
        self.show(place);
        Ok(())
    }

    /// The codes heard, a bit each.
    pub fn listens(&self) -> u8 {
        if self.notify { 0xFF } else { self.listening }
    }

    fn show(&self, place: Option<&Place>) {
        if let Some(p) = place {
            p.show_ir(self.broadcasting, self.listens());
        }
    }

    /// A message of `code` reached this robot at `place`: whether it is heard (notified). A
    /// listen (0x2B) is over once heard.
    pub fn hear(&mut self, code: u8, place: Option<&Place>) -> bool {
        if code >= CHANNELS || self.listens() & (1 << code) == 0 {
            return false;
        }
        self.heard += 1;
        if !self.notify {
            self.listening &= !(1 << code);
            self.show(place);
        }
        true
    }

    /// The drive a following or evading robot gives itself now: speed 0..=255 and facing
    /// (degrees, the body's frame); `None` when it does neither. `seen` is the nearest
    /// broadcaster of its pair in range, `yaw_deg` where it faces, `dt` the physics step.
    pub fn steer(
        &mut self,
        seen: Option<Sighting>,
        yaw_deg: f32,
        now: Duration,
        dt: Duration,
    ) -> Option<(u8, f32)> {
        let (behaviour, _) = self.behaviour?;
        let Some(s) = seen else {
            self.far_since = None;
            return Some((0, wrap360(yaw_deg + SEARCH_DEG_S * dt.as_secs_f32())));
        };
        Some(match behaviour {
            Behaviour::Follow if s.gap_cm > NEAR_CM => (FOLLOW_FAR_SPEED, s.bearing_deg),
            Behaviour::Follow if s.gap_cm > FOLLOW_STOP_CM => (FOLLOW_NEAR_SPEED, s.bearing_deg),
            Behaviour::Follow => (0, s.bearing_deg),
            Behaviour::Evade => {
                let away = wrap360(s.bearing_deg + 180.0);
                if s.gap_cm < NEAR_CM {
                    self.far_since = None;
                    (EVADE_NEAR_SPEED, away)
                } else if now.saturating_sub(*self.far_since.get_or_insert(now)) < EVADE_FAR_FOR {
                    (EVADE_FAR_SPEED, away)
                } else {
                    (0, yaw_deg)
                }
            }
        })
    }

    /// The nearest broadcaster this robot's behaviour looks for, from `place`.
    pub fn sighting(&self, place: Option<&Place>) -> Option<Sighting> {
        let (_, codes) = self.behaviour?;
        place?.nearest_beacon(codes)
    }
}

/// The infrared side of a robot's place in a shared room.
impl Place {
    /// What this robot shows the room: its beacon, and the codes it listens for (none: what
    /// reached it and was not yet taken is dropped).
    pub fn show_ir(&self, beacon: Option<Codes>, listening: u8) {
        if let Some(o) = self.room.lock().get_mut(self.id) {
            o.ir.beacon = beacon;
            o.ir.listening = listening;
            if listening == 0 {
                o.ir.inbox.clear();
            }
        }
    }

    /// Send `code` from here, facing `facing_deg`, each emitter at its strength (front, left,
    /// right, rear): every other robot listening for it within reach of the emitter facing it
    /// gets it. Returns how many did.
    pub fn send_ir(&self, code: u8, strengths: [u8; 4], facing_deg: f32) -> usize {
        if code >= CHANNELS {
            return 0;
        }
        let mut all = self.room.lock();
        let Some(me) = all.get(self.id) else {
            return 0;
        };
        let (x, y, radius) = (me.x, me.y, me.radius);
        let mut reached = 0;
        for (i, o) in all.iter_mut().enumerate() {
            if i == self.id || o.ir.listening & (1 << code) == 0 {
                continue;
            }
            let (dx, dy) = (o.x - x, o.y - y);
            let gap = (dx.hypot(dy) - radius - o.radius).max(0.0);
            let strength = strengths[emitter(facing_deg, dx, dy)];
            if strength > 0 && gap <= reach(strength) {
                if o.ir.inbox.len() >= INBOX_MAX {
                    o.ir.inbox.pop_front();
                }
                o.ir.inbox.push_back(code);
                reached += 1;
            }
        }
        reached
    }

    /// The codes that reached this robot since the last call, oldest first.
    pub fn take_ir(&self) -> Vec<u8> {
        self.room
            .lock()
            .get_mut(self.id)
            .map(|o| o.ir.inbox.drain(..).collect())
            .unwrap_or_default()
    }

    /// The nearest other robot broadcasting `codes` within [`RANGE_CM`], seen from here.
    pub fn nearest_beacon(&self, codes: Codes) -> Option<Sighting> {
        let all = self.room.lock();
        let me = all.get(self.id)?;
        all.iter()
            .enumerate()
            .filter(|(i, o)| *i != self.id && o.ir.beacon == Some(codes))
            .map(|(_, o)| {
                let (dx, dy) = (o.x - me.x, o.y - me.y);
                Sighting {
                    gap_cm: (dx.hypot(dy) - me.radius - o.radius).max(0.0),
                    bearing_deg: bearing(dx, dy),
                }
            })
            .filter(|s| s.gap_cm <= RANGE_CM)
            .min_by(|a, b| a.gap_cm.total_cmp(&b.gap_cm))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Model;
    use crate::protocol::v2::catalog::targets;
    use crate::protocol::v2::{Command, Packet};
    use crate::sim::room::SharedRoom;
    use crate::sim::{SimConfig, SimDroid};

    const S: Duration = Duration::from_secs(1);

    /// Robots of `models` in one room, at `origins`, awake at time 0.
    fn room(models: &[Model], origins: &[(f32, f32)]) -> (SharedRoom, Vec<SimDroid>) {
        let room = SharedRoom::new();
        let droids = models
            .iter()
            .zip(origins)
            .map(|(m, o)| {
                let mut cfg = SimConfig::for_model(*m);
                cfg.place = Some(room.place(*o, cfg.radius_cm));
                let mut d = SimDroid::new(*m, cfg);
                assert_eq!(
                    send(&mut d, 0x13, 0x0D, &[], Duration::ZERO).0,
                    ErrorCode::Success
                );
                d
            })
            .collect();
        (room, droids)
    }

    /// A command as a client addresses it: its answer, and the notifications that came with it.
    fn send(
        d: &mut SimDroid,
        did: u8,
        cid: u8,
        data: &[u8],
        now: Duration,
    ) -> (ErrorCode, Vec<Packet>) {
        let mut c = Command::new(did, cid, data.to_vec());
        c.target = targets::addressed(d.model(), did, cid).map(|p| p.target_id());
        let out = d.receive(&c.to_packet(7).encode(), now);
        let err = out
            .iter()
            .find(|p| p.is_response())
            .and_then(|p| p.err)
            .expect("an answer");
        (
            err,
            out.into_iter().filter(|p| p.is_notification()).collect(),
        )
    }

    fn ir(d: &mut SimDroid, cid: u8, data: &[u8], now: Duration) -> ErrorCode {
        send(d, 0x18, cid, data, now).0
    }

    /// The IR message codes `d` notified by `now`.
    fn heard(d: &mut SimDroid, now: Duration) -> Vec<u8> {
        d.advance(now)
            .iter()
            .filter(|p| (p.did, p.cid) == (0x18, 0x2C))
            .map(|p| p.data[0])
            .collect()
    }

    fn gap(room: &SharedRoom) -> f32 {
        let p = room.positions();
        let r = SimConfig::for_model(Model::Bolt).radius_cm;
        (p[0].0 - p[1].0).hypot(p[0].1 - p[1].1) - 2.0 * r
    }

    #[test]
    fn a_message_reaches_a_listening_robot_in_range_only() {
        // Three BOLTs 60 cm apart in a row: a sends; b listens for 3; c listens for nothing.
        let (_room, mut d) = room(
            &[Model::Bolt, Model::Bolt, Model::Bolt],
            &[(-60.0, 0.0), (0.0, 0.0), (60.0, 0.0)],
        );
        let t = Duration::from_millis(100);
        let all = [64, 64, 64, 64];
        let mut at = t;
        // a sends `code` at `strengths` while b listens for 3: what b hears.
        fn exchange(
            d: &mut [SimDroid],
            at: &mut Duration,
            code: u8,
            strengths: [u8; 4],
        ) -> Vec<u8> {
            assert_eq!(ir(&mut d[1], 0x2B, &[3, 0xFF], *at), ErrorCode::Success);
            let mut m = vec![code];
            m.extend(strengths);
            assert_eq!(ir(&mut d[0], 0x2A, &m, *at), ErrorCode::Success);
            *at += Duration::from_millis(100);
            heard(&mut d[1], *at)
        }
        assert_eq!(exchange(&mut d, &mut at, 3, all), vec![3]);
        assert_eq!(heard(&mut d[2], at), Vec::<u8>::new(), "c does not listen");
        // A listen is heard once: without listening again, nothing more.
        ir(&mut d[0], 0x2A, &[3, 64, 64, 64, 64], at);
        assert_eq!(heard(&mut d[1], at + t), Vec::<u8>::new(), "heard once");
        // Another code is not heard.
        assert_eq!(exchange(&mut d, &mut at, 4, all), Vec::<u8>::new());
        // Out of reach: strength 8 carries 37.5 cm, the gap is 52.7 cm; 16 carries 75 cm.
        assert_eq!(
            exchange(&mut d, &mut at, 3, [8; 4]),
            Vec::<u8>::new(),
            "too weak"
        );
        assert_eq!(exchange(&mut d, &mut at, 3, [16; 4]), vec![3]);
        // Only the emitter facing the receiver counts: b is to a's right (a faces +y).
        assert_eq!(
            exchange(&mut d, &mut at, 3, [64, 64, 0, 64]),
            Vec::<u8>::new()
        );
        assert_eq!(exchange(&mut d, &mut at, 3, [0, 0, 64, 0]), vec![3]);
        // The farther robot hears a's message once it listens (gap 112.7 cm).
        ir(&mut d[2], 0x2B, &[3, 0xFF], at);
        ir(&mut d[0], 0x2A, &[3, 64, 64, 64, 64], at);
        assert_eq!(heard(&mut d[2], at + t), vec![3]);
        assert_eq!(d[0].infrared().sent, 8);
        assert_eq!(d[2].infrared().heard, 1);
    }

    #[test]
    fn three_metres_is_the_farthest() {
        let (_room, mut d) = room(&[Model::Bolt, Model::Bolt], &[(-170.0, 0.0), (170.0, 0.0)]);
        let t = Duration::from_millis(100);
        ir(&mut d[1], 0x2B, &[0, 0xFF], t);
        ir(&mut d[0], 0x2A, &[0, 255, 255, 255, 255], t);
        assert_eq!(heard(&mut d[1], t * 2), Vec::<u8>::new(), "332.7 cm apart");
        assert_eq!(reach(64), 300.0);
        assert_eq!(reach(255), 300.0);
        assert_eq!(reach(32), 150.0);
    }

    #[test]
    fn rvr_listens_with_its_notify_and_hears_a_bolt() {
        let (_room, mut d) = room(&[Model::Bolt, Model::Rvr], &[(-60.0, 0.0), (60.0, 0.0)]);
        let t = Duration::from_millis(100);
        assert_eq!(ir(&mut d[1], 0x3E, &[1], t), ErrorCode::Success);
        ir(&mut d[0], 0x2A, &[6, 64, 64, 64, 64], t);
        let out = d[1].advance(t * 2);
        let n = out
            .iter()
            .find(|p| (p.did, p.cid) == (0x18, 0x2C))
            .expect("RVR notified");
        assert_eq!(
            (n.data.clone(), n.sid),
            (vec![6], Some(0x12)),
            "from the secondary"
        );
        // And the BOLT hears RVR's newer send.
        ir(&mut d[0], 0x2B, &[2, 0xFF], t * 2);
        assert_eq!(
            ir(&mut d[1], 0x3F, &[2, 64, 64, 64, 64], t * 2),
            ErrorCode::Success
        );
        assert_eq!(heard(&mut d[0], t * 5), vec![2]);
    }

    #[test]
    fn each_robot_answers_its_own_commands_and_refuses_the_rest() {
        let (_room, mut d) = room(
            &[Model::Bolt, Model::Rvr, Model::Mini, Model::R2D2],
            &[(-90.0, 0.0), (-30.0, 0.0), (30.0, 0.0), (90.0, 0.0)],
        );
        let t = Duration::from_millis(10);
        let five = [1, 64, 64, 64, 64];
        assert_eq!(ir(&mut d[0], 0x27, &[1, 0], t), ErrorCode::Success);
        assert_eq!(ir(&mut d[0], 0x3F, &five, t), ErrorCode::BadCommandId);
        assert_eq!(ir(&mut d[0], 0x3E, &[1], t), ErrorCode::BadCommandId);
        assert_eq!(ir(&mut d[1], 0x2A, &five, t), ErrorCode::BadCommandId);
        assert_eq!(ir(&mut d[1], 0x2B, &[1, 0xFF], t), ErrorCode::BadCommandId);
        assert_eq!(ir(&mut d[1], 0x33, &[1, 0], t), ErrorCode::Success);
        for m in [2, 3] {
            for (cid, data) in [(0x27, &[1u8, 0][..]), (0x2A, &five[..]), (0x3E, &[1][..])] {
                assert_eq!(ir(&mut d[m], cid, data, t), ErrorCode::BadCommandId);
            }
        }
        // Codes are 0..=7.
        assert_eq!(
            ir(&mut d[0], 0x27, &[8, 0], t),
            ErrorCode::BadParameterValue
        );
        assert_eq!(
            ir(&mut d[0], 0x2A, &[9, 1, 1, 1, 1], t),
            ErrorCode::BadParameterValue
        );
        assert_eq!(
            ir(&mut d[0], 0x2B, &[8, 0], t),
            ErrorCode::BadParameterValue
        );
    }

    #[test]
    fn a_follower_closes_the_distance_and_stops_near() {
        let (room, mut d) = room(&[Model::Bolt, Model::Bolt], &[(-100.0, 0.0), (100.0, 50.0)]);
        let t = Duration::from_millis(10);
        ir(&mut d[0], 0x27, &[1, 0], t);
        ir(&mut d[1], 0x28, &[1, 0], t);
        let start = gap(&room);
        assert!(start > 190.0, "{start}");
        for k in 1..=100 {
            d[0].advance(t + S * k / 10);
            d[1].advance(t + S * k / 10);
        }
        let end = gap(&room);
        assert!(end < FOLLOW_STOP_CM + 5.0, "{start} cm, then {end} cm");
        assert!(end > 0.0, "stopped short of it: {end}");
        assert!(d[1].state().velocity_cm_s.abs() < 1.0, "{:?}", d[1].state());
        // Another pair of codes is not followed: the follower searches, turning in place.
        ir(&mut d[1], 0x28, &[2, 3], S * 11);
        let before = (room.positions()[1], d[1].state().yaw_deg);
        d[1].advance(S * 11 + S / 2);
        let after = (room.positions()[1], d[1].state().yaw_deg);
        assert_eq!(before.0, after.0, "it does not roll");
        let turned = angle_diff(before.1, after.1);
        assert!(
            (turned - SEARCH_DEG_S / 2.0).abs() < 5.0,
            "turned {turned}°"
        );
        // Stopping the behaviour stops the robot.
        assert_eq!(ir(&mut d[1], 0x32, &[], S * 12), ErrorCode::Success);
        assert_eq!(d[1].infrared().behaviour, None);
        let yaw = d[1].state().yaw_deg;
        d[1].advance(S * 13);
        assert_eq!(d[1].state().yaw_deg, yaw);
    }

    #[test]
    fn an_evader_opens_the_distance_then_stops_in_the_far_range() {
        let (room, mut d) = room(&[Model::Bolt, Model::Bolt], &[(-30.0, 0.0), (30.0, 0.0)]);
        let t = Duration::from_millis(10);
        ir(&mut d[0], 0x27, &[5, 4], t);
        ir(&mut d[1], 0x33, &[5, 4], t);
        let start = gap(&room);
        for k in 1..=60 {
            d[0].advance(t + S * k / 10);
            d[1].advance(t + S * k / 10);
        }
        let end = gap(&room);
        assert!(end > NEAR_CM, "{start} cm, then {end} cm");
        assert!(
            room.positions()[1].0 > 100.0,
            "away along +x: {:?}",
            room.positions()
        );
        // In the far range for more than EVADE_FAR_FOR: it holds still.
        assert!(d[1].state().velocity_cm_s.abs() < 1.0, "{:?}", d[1].state());
        assert_eq!(gap(&room), end);
        // The broadcaster stops: the evader, seeing none, searches in place.
        ir(&mut d[0], 0x29, &[], S * 7);
        let yaw = d[1].state().yaw_deg;
        d[1].advance(S * 8);
        assert_ne!(d[1].state().yaw_deg, yaw);
        assert_eq!(gap(&room), end);
    }

    #[test]
    fn asleep_a_robot_forgets_its_infrared() {
        let (_room, mut d) = room(&[Model::Bolt, Model::Bolt], &[(-30.0, 0.0), (30.0, 0.0)]);
        let t = Duration::from_millis(10);
        ir(&mut d[1], 0x2B, &[3, 0xFF], t);
        ir(&mut d[1], 0x28, &[1, 0], t);
        assert_eq!(d[1].next_due(), None, "steering: stepped every step");
        send(&mut d[1], 0x13, 0x01, &[], t);
        assert_eq!(d[1].infrared(), &Infrared::default());
        ir(&mut d[0], 0x2A, &[3, 64, 64, 64, 64], t);
        assert_eq!(heard(&mut d[1], S), Vec::<u8>::new());
    }

    #[test]
    fn a_listener_is_woken_for_messages() {
        let (_room, mut d) = room(&[Model::Bolt, Model::Bolt], &[(-30.0, 0.0), (30.0, 0.0)]);
        let due = d[1].next_due().unwrap();
        assert!(due > S, "idle: nothing due soon ({due:?})");
        ir(&mut d[1], 0x2B, &[3, 0xFF], Duration::ZERO);
        assert!(d[1].next_due().unwrap() <= LISTEN_POLL);
    }

    #[test]
    fn emitters_by_quarter() {
        assert_eq!(emitter(0.0, 0.0, 1.0), 0);
        assert_eq!(emitter(0.0, 1.0, 0.0), 2);
        assert_eq!(emitter(0.0, -1.0, 0.0), 1);
        assert_eq!(emitter(0.0, 0.0, -1.0), 3);
        assert_eq!(emitter(90.0, 1.0, 0.0), 0);
    }
}
