//! BOLT's frame player as the simulator keeps it: saved 64-bit frames (four bit planes of
//! palette indexes), saved animations (a palette, a frame rate, a fade flag and a list of
//! frames), and the animation playing now, on the simulator's clock. Sans-IO, part of
//! [`super::robots`].
//!
//! The wire is spherov2.py's (`commands/io.py`, `sphero_edu.py`
//! `register_matrix_animation`); droid-facts.md names only the command range ("saved frames
//! and animations 0x30–0x38, 0x43"):
//! - 0x30 save frame: `[index u16 BE, 32 bytes]`, the 32 bytes packed as
//!   [`crate::protocol::v2::frame`] says.
//! - 0x31 save animation: `[id, fps, fade, n, n × RGB, count u16 BE, count × frame u16 BE]`.
//! - 0x32 play, 0x43 play with a loop flag, 0x36 pause, 0x37 resume, 0x38 reset, 0x39
//!   override fps (0: the animation's own) and fade; 0x35 deletes everything.
//! - Notification 0x3F "animation complete" `[id]` when a one-shot animation has shown its
//!   last frame for a frame's time (spherov2 binds the listener on BOLT; the firmware's
//!   exact moment is not published).
//!
//! Unpublished, chosen here and marked so: a one-shot animation leaves its last frame shown;
//! 0x32 (no loop flag) loops, as Sphero Edu's "perpetual loop" default does; a fade between
//! frames is not drawn (each frame is shown whole for its time), so what the matrix shows at
//! a frame's time is exact and the fade's in-between colours are not simulated.

use crate::protocol::v2::frame::unpack;
use std::time::Duration;

/// Frames and animations kept (bounded; the real limits are unpublished).
pub const SAVED_MAX: usize = crate::family::v2::robots::MATRIX_SAVED_MAX;

/// One saved animation.
#[derive(Debug, Clone, PartialEq)]
pub struct Animation {
    pub id: u8,
    pub fps: u8,
    pub fade: bool,
    pub palette: Vec<[u8; 3]>,
    pub frames: Vec<u16>,
}

/// The animation playing (or paused) now.
#[derive(Debug, Clone, PartialEq)]
pub struct Playing {
    pub id: u8,
    pub looping: bool,
    /// When its frame 0 was (moved on by pauses).
    pub since: Duration,
    /// Paused at this time.
    pub paused: Option<Duration>,
    /// The frame step last shown (not wrapped).
    pub shown: u64,
}

/// The frame player.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Player {
    /// Saved frames: index and palette indexes `[y][x]` (y 0 the top row).
    pub frames: Vec<(u16, [[u8; 8]; 8])>,
    pub animations: Vec<Animation>,
    pub playing: Option<Playing>,
    /// 0x39's frame rate (0: each animation's own).
    pub fps_override: u8,
}

/// What the player did when time passed.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Tick {
    /// The pixels to show now (`None`: unchanged).
    pub show: Option<[[[u8; 3]; 8]; 8]>,
    /// A one-shot animation ended (its id).
    pub complete: Option<u8>,
}

/// Why a command was refused (the simulator answers Bad Parameter Value or Command Failed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refused {
    BadParameter,
    Full,
}

impl Player {
    /// 0x30: keep a frame (a saved index again replaces it). A frame shorter than 32 bytes
    /// is padded with zeros (what the firmware answers to one is not published; the
    /// simulator accepts it, as it accepts every command of its catalogue).
    pub fn save_frame(&mut self, d: &[u8]) -> Result<(), Refused> {
        let Some(i) = d.get(..2) else {
            return Err(Refused::BadParameter);
        };
        let index = u16::from_be_bytes([i[0], i[1]]);
        let mut raw = [0u8; 32];
        for (r, b) in raw.iter_mut().zip(&d[2..]) {
            *r = *b;
        }
        let frame = unpack(&raw);
        if let Some(f) = self.frames.iter_mut().find(|f| f.0 == index) {
            f.1 = frame;
        } else if self.frames.len() >= SAVED_MAX {
            return Err(Refused::Full);
        } else {
            self.frames.push((index, frame));
        }
        Ok(())
    }

    /// 0x31: keep an animation.
    pub fn save_animation(&mut self, d: &[u8]) -> Result<(), Refused> {
        let bad = Refused::BadParameter;
        let (&id, &fps, &fade, &n) = match d {
            [id, fps, fade, n, ..] => (id, fps, fade, n),
            _ => return Err(bad),
        };
        let colours = d.get(4..4 + 3 * n as usize).ok_or(bad)?;
        if n > 16 || fade > 1 {
            return Err(bad);
        }
        let palette: Vec<[u8; 3]> = colours.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        let rest = &d[4 + 3 * n as usize..];
        let count = rest.get(..2).ok_or(bad)?;
        let count = u16::from_be_bytes([count[0], count[1]]) as usize;
        let list = rest.get(2..2 + 2 * count).ok_or(bad)?;
        if rest.len() != 2 + 2 * count || count > SAVED_MAX {
            return Err(bad);
        }
        let frames: Vec<u16> = list
            .chunks(2)
            .map(|c| u16::from_be_bytes([c[0], c[1]]))
            .collect();
        let a = Animation {
            id,
            fps,
            fade: fade == 1,
            palette,
            frames,
        };
        if let Some(old) = self.animations.iter_mut().find(|x| x.id == id) {
            *old = a;
        } else if self.animations.len() >= SAVED_MAX {
            return Err(Refused::Full);
        } else {
            self.animations.push(a);
        }
        Ok(())
    }

    /// 0x32 / 0x43: play animation `id` from its first frame. Playing what was never saved
    /// shows nothing (no published error for it).
    pub fn play(&mut self, id: u8, looping: bool, now: Duration) -> Tick {
        self.playing = self
            .animations
            .iter()
            .any(|a| a.id == id)
            .then_some(Playing {
                id,
                looping,
                since: now,
                paused: None,
                shown: 0,
            });
        self.advance(now)
    }

    pub fn pause(&mut self, now: Duration) {
        if let Some(p) = &mut self.playing
            && p.paused.is_none()
        {
            p.paused = Some(now);
        }
    }

    pub fn resume(&mut self, now: Duration) {
        if let Some(p) = &mut self.playing
            && let Some(at) = p.paused.take()
        {
            p.since += now.saturating_sub(at);
        }
    }

    /// 0x38: stop the animation.
    pub fn reset(&mut self) {
        self.playing = None;
    }

    /// 0x35: forget every frame and animation.
    pub fn delete_all(&mut self) {
        *self = Player {
            fps_override: self.fps_override,
            ..Player::default()
        };
    }

    fn animation(&self) -> Option<(&Playing, &Animation)> {
        let p = self.playing.as_ref()?;
        Some((p, self.animations.iter().find(|a| a.id == p.id)?))
    }

    fn fps(&self, a: &Animation) -> u32 {
        let f = if self.fps_override > 0 {
            self.fps_override
        } else {
            a.fps
        };
        f.clamp(1, 30) as u32
    }

    /// The frame number due at `now` (not wrapped).
    fn step_at(&self, now: Duration) -> Option<u64> {
        let (p, a) = self.animation()?;
        let t = p.paused.unwrap_or(now).saturating_sub(p.since);
        Some((t.as_micros() as u64 * self.fps(a) as u64) / 1_000_000)
    }

    /// What the matrix shows at `now`, and whether a one-shot animation ended.
    pub fn advance(&mut self, now: Duration) -> Tick {
        let (Some(step), Some((p, a))) = (self.step_at(now), self.animation()) else {
            return Tick::default();
        };
        let n = a.frames.len() as u64;
        if n == 0 {
            // Saved without frames: nothing to show, and done at once when played once.
            let (id, looping) = (p.id, p.looping);
            if looping {
                return Tick::default();
            }
            self.playing = None;
            return Tick {
                show: None,
                complete: Some(id),
            };
        }
        let (k, ended) = if p.looping {
            (step % n, false)
        } else {
            // The last frame is shown for its own frame time, then the animation is done.
            (step.min(n - 1), step >= n)
        };
        let (id, frame, palette) = (p.id, a.frames[k as usize], a.palette.clone());
        let show = self.frames.iter().find(|f| f.0 == frame).map(|(_, idx)| {
            let mut px = [[[0u8; 3]; 8]; 8];
            for (y, row) in idx.iter().enumerate() {
                for (x, i) in row.iter().enumerate() {
                    px[y][x] = palette.get(*i as usize).copied().unwrap_or([0, 0, 0]);
                }
            }
            px
        });
        if let Some(p) = &mut self.playing {
            p.shown = step;
        }
        let complete = ended.then(|| {
            self.playing = None;
            id
        });
        Tick { show, complete }
    }

    /// When the next frame is due (`None`: nothing is playing or it is paused).
    pub fn next_due(&self) -> Option<Duration> {
        let (p, a) = self.animation()?;
        if p.paused.is_some() || a.frames.is_empty() {
            return None;
        }
        let fps = self.fps(a) as u64;
        let k = p.shown + 1;
        Some(p.since + Duration::from_micros((k * 1_000_000).div_ceil(fps)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::v2::frame::pack;

    fn ms(v: u64) -> Duration {
        Duration::from_millis(v)
    }

    fn saved() -> Player {
        let mut p = Player::default();
        let mut a = [[0u8; 8]; 8];
        a[0][0] = 1;
        let b = [[2u8; 8]; 8];
        let mut d = vec![0, 0];
        d.extend(pack(&a));
        p.save_frame(&d).unwrap();
        let mut d = vec![0, 1];
        d.extend(pack(&b));
        p.save_frame(&d).unwrap();
        let mut d = vec![7, 2, 0, 3, 0, 0, 0, 255, 0, 0, 0, 0, 255, 0, 2, 0, 0, 0, 1];
        p.save_animation(&d).unwrap();
        d[0] = 8;
        d.truncate(d.len() - 1);
        assert_eq!(p.save_animation(&d), Err(Refused::BadParameter));
        p
    }

    #[test]
    fn a_one_shot_animation_shows_each_frame_then_completes_on_its_last() {
        let mut p = saved();
        let t = p.play(7, false, ms(1000));
        let show = t.show.unwrap();
        assert_eq!(show[0][0], [255, 0, 0]);
        assert_eq!(show[1][1], [0, 0, 0]);
        assert_eq!(p.next_due(), Some(ms(1500)));
        let t = p.advance(ms(1600));
        assert_eq!(t.show.unwrap()[5][5], [0, 0, 255]);
        assert_eq!(t.complete, None);
        let t = p.advance(ms(2000));
        assert_eq!(t.complete, Some(7));
        assert_eq!(t.show.unwrap()[5][5], [0, 0, 255], "the last frame stays");
        assert_eq!(p.playing, None);
        assert_eq!(p.advance(ms(3000)), Tick::default());
    }

    #[test]
    fn a_loop_wraps_and_a_pause_holds_its_frame() {
        let mut p = saved();
        p.play(7, true, ms(0));
        assert_eq!(p.advance(ms(2100)).show.unwrap()[0][0], [255, 0, 0]);
        p.pause(ms(2600));
        assert_eq!(p.next_due(), None);
        // Paused on frame 1 however long it waits.
        assert_eq!(p.advance(ms(9000)).show.unwrap()[0][0], [0, 0, 255]);
        p.resume(ms(9000));
        // 0.4 s of frame 1 were left... it moves on at 9.4 s.
        assert_eq!(p.advance(ms(9300)).show.unwrap()[0][0], [0, 0, 255]);
        assert_eq!(p.advance(ms(9450)).show.unwrap()[0][0], [255, 0, 0]);
        p.fps_override = 10;
        p.reset();
        assert_eq!(p.playing, None);
        assert_eq!(p.play(9, true, ms(0)), Tick::default(), "never saved");
    }
}
