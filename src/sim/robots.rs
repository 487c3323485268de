//! What the simulated BOLT and RVR keep beyond the shared body: BOLT's 8×8 matrix (what it
//! shows, its rotation, saved frames and animations, scrolling text), RVR's 32 LEDs and its
//! streaming service (tokens per processor, a period, the configuration rules), and the
//! processor each command is answered by. Sans-IO, part of the v2 simulator front.

use super::animation::{Player, Refused};
use crate::model::Model;
use crate::protocol::v2::ErrorCode;
use crate::protocol::v2::catalog::targets::{self, Processor};
use crate::protocol::v2::stream::{self, MIN_PERIOD_MS, SENSORS_PER_TOKEN, Slot, TOKENS};
use crate::protocol::v2::types::{SCROLL_TEXT_MAX, StreamWidth};
use std::time::Duration;

/// The matrix is 8×8.
pub const MATRIX: usize = 8;
/// Columns one scrolled character takes: a cell of the 8×8 font (the simulator's glyphs are
/// 8 columns wide; the real font is not public).
const SCROLL_CHAR_COLUMNS: u32 = MATRIX as u32;

/// How long scrolling `chars` characters takes at `fps` frames a second: the speed byte is
/// frames per second (spherov2 `sphero_edu.py`, `scroll_matrix_text(text, color, fps, …)`,
/// "fps 1 to 30"), and each frame moves the text one column, so every column of the text
/// takes a frame. (Fix, issue 29 point 5: the simulator took 600 ms per character divided
/// by the speed, and said done after 0.19 s where one character's 8 columns at 10 frames/s
/// take 0.8 s.)
pub fn scroll_time(chars: usize, fps: u8) -> Duration {
    let columns = SCROLL_CHAR_COLUMNS * chars as u32;
    Duration::from_millis(1000) * columns / fps.max(1) as u32
}

/// BOLT's LED matrix.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Matrix {
    /// Row-major colours, `pixels[y][x]`.
    pub pixels: [[[u8; 3]; MATRIX]; MATRIX],
    /// 0, 90, 180 or 270 degrees.
    pub rotation: u16,
    /// The text scrolling now, its colour, and when it is done (`None`: repeating).
    pub scrolling: Option<(String, [u8; 3], Option<Duration>)>,
    /// The single character shown, if the last drawing was one.
    pub character: Option<char>,
    /// Saved frames and animations, and the one playing ([`super::animation`]).
    pub player: Player,
}

impl Matrix {
    /// Fill a rectangle (inclusive corners, any order); coordinates past 7 are refused.
    fn fill(&mut self, x1: u8, y1: u8, x2: u8, y2: u8, rgb: [u8; 3]) -> bool {
        if [x1, y1, x2, y2].iter().any(|v| *v as usize >= MATRIX) {
            return false;
        }
        for y in y1.min(y2)..=y1.max(y2) {
            for x in x1.min(x2)..=x1.max(x2) {
                self.pixels[y as usize][x as usize] = rgb;
            }
        }
        true
    }

    /// A straight line (Bresenham).
    fn line(&mut self, x1: u8, y1: u8, x2: u8, y2: u8, rgb: [u8; 3]) -> bool {
        if [x1, y1, x2, y2].iter().any(|v| *v as usize >= MATRIX) {
            return false;
        }
        let (mut x, mut y) = (x1 as i32, y1 as i32);
        let (dx, dy) = ((x2 as i32 - x).abs(), -(y2 as i32 - y).abs());
        let (sx, sy) = (
            if x < x2 as i32 { 1 } else { -1 },
            if y < y2 as i32 { 1 } else { -1 },
        );
        let mut err = dx + dy;
        for _ in 0..2 * MATRIX {
            self.pixels[y as usize][x as usize] = rgb;
            if x == x2 as i32 && y == y2 as i32 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
        true
    }

    /// Show an animation's frame (`None`: nothing new).
    fn show(&mut self, pixels: Option<[[[u8; 3]; MATRIX]; MATRIX]>) {
        if let Some(px) = pixels {
            self.pixels = px;
            self.character = None;
            self.scrolling = None;
        }
    }

    /// One line of text for the trace: what the matrix shows.
    pub fn summary(&self) -> String {
        if let Some((text, rgb, _)) = &self.scrolling {
            return format!(
                "scrolling {text:?} in #{:02x}{:02x}{:02x}",
                rgb[0], rgb[1], rgb[2]
            );
        }
        if let Some(c) = self.character {
            let lit = self.pixels.iter().flatten().find(|p| **p != [0, 0, 0]);
            let rgb = lit.copied().unwrap_or_default();
            return format!(
                "character {c:?} in #{:02x}{:02x}{:02x}",
                rgb[0], rgb[1], rgb[2]
            );
        }
        let lit = self
            .pixels
            .iter()
            .flatten()
            .filter(|p| **p != [0, 0, 0])
            .count();
        format!("{lit} of 64 pixels lit")
    }
}

/// The streaming service of one simulated robot.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Service {
    pub config: stream::ServiceConfig,
    /// Per processor: the period and the next time data are due.
    pub running: Vec<(Processor, Duration, Duration)>,
}

/// The robot-specific state of a simulated v2 robot.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotParts {
    pub model: Model,
    pub matrix: Matrix,
    /// RVR's 31 LEDs (32-bit mask; bit 30 the undercarriage white), or BOLT's 8-bit ones.
    pub leds: [u8; 32],
    pub service: Service,
    pub compass_calibrating: bool,
    pub color_detection: bool,
    pub motor_stall_notify: bool,
    pub motor_fault_notify: bool,
    /// System Info notifications owed, and when: the secondary's versions (CID 0x18, 0x25)
    /// follow their request's response (see [`RobotParts::owe_version`]).
    pub versions_due: Vec<(Duration, u8)>,
}

/// How long after its response a secondary's version notification comes (unverified: the
/// firmware's timing is not published; after the response, so that a client waiting for it
/// once the response came, as spherov2's `_wait_packet` does, hears it).
pub const VERSION_NOTICE_DELAY: Duration = Duration::from_millis(20);

/// Most version notifications owed at once (each request owes one; a host that floods
/// requests loses the oldest).
const VERSIONS_DUE_MAX: usize = 16;

pub use crate::family::v2::robots::led_mask;

/// The newer robots (those without a Core device) have no animatronic device at all.
pub fn has_animatronic(model: Model) -> bool {
    !crate::family::v2::robots::has_no_core(model)
}

/// Where a packet's target sends it on `model`; the robot's answer to a wrong one.
pub fn route(model: Model, did: u8, cid: u8, tid: Option<u8>) -> Result<(), ErrorCode> {
    let home = targets::home(model, did, cid);
    if let Some(t) = tid
        && model.processors() > 1
        && Processor::of_id(t).is_none()
    {
        return Err(ErrorCode::BadTargetId);
    }
    if tid.is_none() && model.requires_target() {
        // RVR routes by target only (spherov2 refuses to build an RVR command without one).
        return Err(ErrorCode::BadTargetId);
    }
    if home.accepts(tid) {
        Ok(())
    } else if model.processors() == 1 {
        Err(ErrorCode::BadTargetId)
    } else {
        // The other processor has no such command: it answers as for any it lacks.
        Err(ErrorCode::BadCommandId)
    }
}

impl RobotParts {
    pub fn new(model: Model) -> Self {
        RobotParts {
            model,
            matrix: Matrix::default(),
            leds: [0; 32],
            service: Service::default(),
            compass_calibrating: false,
            color_detection: false,
            motor_stall_notify: false,
            motor_fault_notify: false,
            versions_due: Vec::new(),
        }
    }

    /// Get Secondary Main App Version (System Info 0x17) and Get Secondary MCU Bootloader
    /// Version (0x24) on a two-processor robot: an empty response now, the version as a
    /// notification (0x18, 0x25) after it (spherov2 and sphero-unsw `commands/system_info.py`
    /// wait for it). `None` when `cid` is neither or the robot has one processor.
    pub fn owe_version(&mut self, cid: u8, now: Duration) -> Option<()> {
        let notice = match cid {
            0x17 => 0x18,
            0x24 => 0x25,
            _ => return None,
        };
        if self.model.processors() < 2 {
            return None;
        }
        if self.versions_due.len() >= VERSIONS_DUE_MAX {
            self.versions_due.remove(0);
        }
        self.versions_due.push((now + VERSION_NOTICE_DELAY, notice));
        Some(())
    }

    /// The version notifications due by `now` (their CIDs), taken.
    pub fn versions_now(&mut self, now: Duration) -> Vec<u8> {
        let (due, later): (Vec<_>, Vec<_>) =
            self.versions_due.iter().partition(|(at, _)| *at <= now);
        self.versions_due = later;
        due.into_iter().map(|(_, cid)| cid).collect()
    }

    /// A matrix command (IO 0x2D..=0x4E); `None` when `cid` is not one.
    pub fn matrix(
        &mut self,
        cid: u8,
        d: &[u8],
        now: Duration,
    ) -> Option<Result<Vec<u8>, ErrorCode>> {
        if !self.model.has_matrix() && !matches!(cid, 0x2F | 0x31..=0x38 | 0x40..=0x4E) {
            return None;
        }
        let m = &mut self.matrix;
        let ok = Ok(Vec::new());
        let bad = Err(ErrorCode::BadParameterValue);
        let rgb = |i: usize| [d[i], d[i + 1], d[i + 2]];
        if matches!(cid, 0x2D | 0x2F | 0x3B | 0x3D | 0x3E | 0x42) {
            // Drawing ends an animation, or its next frame would draw over the drawing
            // (unverified on a real BOLT; the firmware's rule is not published).
            m.player.reset();
        }
        Some(match cid {
            0x2D => {
                let (x, y) = (d[0] as usize, d[1] as usize);
                if x >= MATRIX || y >= MATRIX {
                    return Some(bad);
                }
                m.scrolling = None;
                m.character = None;
                m.pixels[y][x] = rgb(2);
                ok
            }
            0x2F => {
                m.scrolling = None;
                m.character = None;
                m.pixels = [[rgb(0); MATRIX]; MATRIX];
                ok
            }
            0x3D | 0x3E => {
                m.scrolling = None;
                m.character = None;
                let drawn = if cid == 0x3D {
                    m.line(d[0], d[1], d[2], d[3], rgb(4))
                } else {
                    m.fill(d[0], d[1], d[2], d[3], rgb(4))
                };
                if drawn { ok } else { bad }
            }
            0x3A => match d[0] {
                r @ 0..=3 => {
                    m.rotation = r as u16 * 90;
                    ok
                }
                _ => bad,
            },
            0x3B => {
                let text = &d[5..d.len() - 1];
                if d.last() != Some(&0) || text.len() > SCROLL_TEXT_MAX || d[3] > 0x1F {
                    return Some(bad);
                }
                let text = String::from_utf8_lossy(text).into_owned();
                let done = (d[4] == 0).then(|| now + scroll_time(text.chars().count(), d[3]));
                m.character = None;
                m.pixels = [[[0; 3]; MATRIX]; MATRIX];
                m.scrolling = Some((text, rgb(0), done));
                ok
            }
            0x42 => {
                let c = d[3];
                if !c.is_ascii_graphic() && c != b' ' {
                    return Some(bad);
                }
                m.scrolling = None;
                m.pixels = [[[0; 3]; MATRIX]; MATRIX];
                // A stand-in glyph: the character's bits as rows (the font is not public).
                for (y, row) in m.pixels.iter_mut().enumerate() {
                    for (x, px) in row.iter_mut().enumerate() {
                        if (c.rotate_left(y as u32) >> x) & 1 == 1 {
                            *px = rgb(0);
                        }
                    }
                }
                m.character = Some(c as char);
                ok
            }
            0x30 | 0x31 => {
                let r = if cid == 0x30 {
                    m.player.save_frame(d)
                } else {
                    m.player.save_animation(d)
                };
                match r {
                    Ok(()) => ok,
                    Err(Refused::BadParameter) => bad,
                    Err(Refused::Full) => Err(ErrorCode::CommandFailed),
                }
            }
            // Saved without frames: spherov2 cannot name its fields; accepted, nothing to play.
            0x41 => ok,
            // 0x32 has no loop flag: it loops (unverified; Sphero Edu's default is a loop).
            0x32 | 0x43 => {
                let looping = cid == 0x32 || d.get(1).is_none_or(|v| *v != 0);
                let t = m.player.play(d[0], looping, now);
                m.show(t.show);
                ok
            }
            0x33 => ok,
            0x34 => Ok(m
                .player
                .frames
                .iter()
                .flat_map(|f| f.0.to_be_bytes())
                .collect()),
            0x35 => {
                m.player.delete_all();
                ok
            }
            0x36 => {
                m.player.pause(now);
                ok
            }
            0x37 => {
                m.player.resume(now);
                ok
            }
            // Reset: the animation ends and the matrix goes dark (spherov2's `clear_matrix`
            // sends only this).
            0x38 => {
                m.player.reset();
                m.pixels = [[[0; 3]; MATRIX]; MATRIX];
                m.character = None;
                m.scrolling = None;
                ok
            }
            0x39 => {
                m.player.fps_override = d[0];
                ok
            }
            0x4C => Ok(vec![3]),
            _ => return None,
        })
    }

    /// The matrix's scrolling text ends: true once when a one-shot text is done.
    pub fn text_done(&mut self, now: Duration) -> bool {
        match &self.matrix.scrolling {
            Some((_, _, Some(done))) if now >= *done => {
                self.matrix.scrolling = None;
                true
            }
            _ => false,
        }
    }

    /// The animation playing moves on to `now`: the id of a one-shot animation that ended.
    pub fn animate(&mut self, now: Duration) -> Option<u8> {
        let t = self.matrix.player.advance(now);
        self.matrix.show(t.show);
        t.complete
    }

    /// When the scrolling text ends, the animation's next frame or streamed data are due.
    pub fn next_due(&self) -> Option<Duration> {
        let text = match &self.matrix.scrolling {
            Some((_, _, Some(done))) => Some(*done),
            _ => None,
        };
        let frame = self.matrix.player.next_due();
        let data = self.service.running.iter().map(|(_, _, at)| *at).min();
        let version = self.versions_due.iter().map(|(at, _)| *at).min();
        [text, frame, data, version].into_iter().flatten().min()
    }

    /// A streaming-service command (Sensor 0x39..=0x3C) sent to processor `p` (on a robot
    /// with one processor, every sensor is its).
    pub fn streaming(
        &mut self,
        cid: u8,
        d: &[u8],
        p: Processor,
        now: Duration,
    ) -> Result<(), ErrorCode> {
        let one_processor = self.model.processors() == 1;
        let running = self.service.running.iter().any(|(q, _, _)| *q == p);
        match cid {
            0x39 => {
                // No reconfiguration while the processor streams (Sphero's SDK stops first).
                if running {
                    return Err(ErrorCode::Busy);
                }
                let token = d[0];
                let sensors: Vec<&[u8]> = d[1..].chunks(3).collect();
                if !TOKENS.contains(&token)
                    || sensors.is_empty()
                    || sensors.len() > SENSORS_PER_TOKEN
                    || sensors.iter().any(|s| s.len() != 3)
                {
                    return Err(ErrorCode::BadParameterValue);
                }
                for s in &sensors {
                    let id = u16::from_be_bytes([s[0], s[1]]);
                    let ok = stream::sensor_by_id(id)
                        .is_some_and(|x| one_processor || x.processor == p)
                        && StreamWidth::from_byte(s[2]).is_some();
                    if !ok {
                        return Err(ErrorCode::BadParameterValue);
                    }
                }
                let mut c = crate::protocol::v2::Command::new(0x18, 0x39, d.to_vec());
                c.target = Some(p.target_id());
                self.service.config.snoop(&c);
                Ok(())
            }
            0x3A => {
                let period = u16::from_be_bytes([d[0], d[1]]);
                // Started without a configuration, it streams nothing.
                if period < MIN_PERIOD_MS {
                    return Err(ErrorCode::BadParameterValue);
                }
                let every = Duration::from_millis(period as u64);
                self.service.running.retain(|(q, _, _)| *q != p);
                self.service.running.push((p, every, now + every));
                Ok(())
            }
            0x3B => {
                self.service.running.retain(|(q, _, _)| *q != p);
                Ok(())
            }
            0x3C => {
                self.service.running.retain(|(q, _, _)| *q != p);
                self.service.config.slots.retain(|s| s.processor != Some(p));
                Ok(())
            }
            _ => Err(ErrorCode::BadCommandId),
        }
    }

    /// The streamed data due by `now`: (processor, payload) for each configured token.
    pub fn stream_due(
        &mut self,
        now: Duration,
        values: &[(&str, f32)],
    ) -> Vec<(Processor, Vec<u8>)> {
        let mut out = Vec::new();
        for (p, every, at) in self.service.running.iter_mut() {
            if now < *at {
                continue;
            }
            while *at <= now {
                *at += *every;
            }
            let slots: Vec<&Slot> = self
                .service
                .config
                .slots
                .iter()
                .filter(|s| s.processor == Some(*p))
                .collect();
            for slot in slots {
                out.push((*p, stream::encode(slot, values)));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn routes_follow_the_processors() {
        assert_eq!(route(Model::Bolt, 0x16, 0x07, Some(0x12)), Ok(()));
        assert_eq!(
            route(Model::Bolt, 0x16, 0x07, Some(0x11)),
            Err(ErrorCode::BadCommandId)
        );
        assert_eq!(
            route(Model::Bolt, 0x16, 0x07, Some(0x13)),
            Err(ErrorCode::BadTargetId)
        );
        assert_eq!(route(Model::Bolt, 0x13, 0x0D, None), Ok(()));
        assert_eq!(
            route(Model::Rvr, 0x13, 0x0D, None),
            Err(ErrorCode::BadTargetId)
        );
        assert_eq!(
            route(Model::Mini, 0x16, 0x07, Some(0x12)),
            Err(ErrorCode::BadTargetId)
        );
        assert_eq!(route(Model::R2D2, 0x16, 0x07, None), Ok(()));
    }

    #[test]
    fn matrix_draws() {
        let mut r = RobotParts::new(Model::Bolt);
        assert_eq!(r.matrix(0x2F, &[1, 2, 3], Duration::ZERO), Some(Ok(vec![])));
        assert_eq!(r.matrix.pixels[7][7], [1, 2, 3]);
        assert_eq!(
            r.matrix(0x2D, &[8, 0, 1, 1, 1], Duration::ZERO),
            Some(Err(ErrorCode::BadParameterValue))
        );
        assert!(
            r.matrix(0x3D, &[0, 0, 7, 7, 9, 9, 9], Duration::ZERO)
                .is_some()
        );
        assert_eq!(r.matrix.pixels[3][3], [9, 9, 9]);
        r.matrix(0x42, &[255, 0, 0, b'A'], Duration::ZERO);
        assert_eq!(r.matrix.summary(), "character 'A' in #ff0000");
        r.matrix(0x3B, &[0, 255, 0, 10, 0, b'H', b'I', 0], Duration::ZERO);
        assert!(r.matrix.summary().starts_with("scrolling \"HI\""));
        assert!(!r.text_done(Duration::from_millis(10)));
        assert!(r.text_done(Duration::from_secs(5)));
        assert!(!r.text_done(Duration::from_secs(6)));
        // One character's 8 columns at 10 frames/s: 0.8 s, not sooner.
        r.matrix(0x3B, &[0, 255, 0, 10, 0, b'A', 0], Duration::ZERO);
        assert!(!r.text_done(Duration::from_millis(790)));
        assert!(r.text_done(Duration::from_millis(800)));
        assert_eq!(scroll_time(8, 10), Duration::from_millis(6400));
        assert_eq!(
            scroll_time(1, 0),
            Duration::from_secs(8),
            "speed 0 is read as 1"
        );
    }

    #[test]
    fn streaming_rules() {
        let mut r = RobotParts::new(Model::Rvr);
        let s = Processor::Secondary;
        let now = Duration::ZERO;
        // Too many sensors under one token; a sensor of the other processor; bad token.
        let five: Vec<u8> = [1u8, 0, 1, 2, 0, 2, 2, 0, 4, 2, 0, 6, 2, 0, 7, 2].to_vec();
        assert_eq!(
            r.streaming(0x39, &five, s, now),
            Err(ErrorCode::BadParameterValue)
        );
        assert_eq!(
            r.streaming(0x39, &[1, 0, 3, 0], s, now),
            Err(ErrorCode::BadParameterValue)
        );
        assert_eq!(
            r.streaming(0x39, &[9, 0, 1, 2], s, now),
            Err(ErrorCode::BadParameterValue)
        );
        assert_eq!(r.streaming(0x39, &[1, 0, 1, 2], s, now), Ok(()));
        assert_eq!(
            r.streaming(0x3A, &[0, 10], s, now),
            Err(ErrorCode::BadParameterValue)
        );
        assert_eq!(r.streaming(0x3A, &[0, 100], s, now), Ok(()));
        assert_eq!(
            r.streaming(0x39, &[2, 0, 6, 2], s, now),
            Err(ErrorCode::Busy)
        );
        let out = r.stream_due(Duration::from_millis(100), &[("yaw", 90.0)]);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].1.len(), 1 + 3 * 4);
        assert_eq!(r.streaming(0x3B, &[], s, now), Ok(()));
        assert_eq!(r.streaming(0x39, &[2, 0, 6, 2], s, now), Ok(()));
    }

    #[test]
    fn a_secondary_version_follows_its_response() {
        let t = Duration::from_secs(1);
        let mut r = RobotParts::new(Model::BoltPlus);
        assert_eq!(r.owe_version(0x17, t), Some(()));
        assert!(r.versions_now(t).is_empty(), "not with the response");
        assert_eq!(r.next_due(), Some(t + VERSION_NOTICE_DELAY));
        assert_eq!(r.versions_now(t + VERSION_NOTICE_DELAY), vec![0x18]);
        assert!(r.versions_due.is_empty());
        for _ in 0..100 {
            r.owe_version(0x24, t);
        }
        assert_eq!(r.versions_due.len(), VERSIONS_DUE_MAX, "bounded");
        // One processor: no secondary to ask.
        assert!(RobotParts::new(Model::Mini).owe_version(0x17, t).is_none());
    }
}
