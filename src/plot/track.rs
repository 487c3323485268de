//! What a plot draws of each droid, gathered sample by sample in bounded memory: the path on
//! the floor, the collisions, the channels against time — each reduced as it comes
//! ([`super::decimate`]). One droid or a fleet: samples name their droid (a fleet's
//! `run --json` lines, a capture of several droids), and each droid is drawn in its own
//! colour with its name in the legend.

use super::decimate::Decimated;
use crate::mission::Sample;
use crate::telemetry::history::Channel;

/// Most droids one plot tells apart (a capture of several droids lists at most as many).
pub const MAX_DROIDS: usize = crate::capture::fleet::MAX_DROIDS;

/// Most collision marks drawn per droid (all are counted).
pub const MAX_HITS: usize = 500;

/// The channels gathered when none are asked for: the defaults of every kind of droid
/// (speed and yaw; Robi's wheels), chosen from once the data is in ([`Tracks::defaults`]).
const DEFAULT_POOL: [Channel; 4] = [
    Channel::Speed,
    Channel::Yaw,
    Channel::MotorLeft,
    Channel::MotorRight,
];

/// One droid's run, reduced.
#[derive(Debug, Clone)]
pub struct Track {
    /// The droid's name (`None`: the only droid of an output that does not name it).
    pub name: Option<String>,
    /// Floor positions: v = [x, y] cm.
    pub path: Decimated,
    /// Where collisions were counted (at most [`MAX_HITS`] kept).
    pub hits: Vec<(f64, f64)>,
    pub hit_count: u64,
    collisions: Option<u32>,
    /// Each gathered channel's values against time.
    pub channels: Vec<(Channel, Decimated)>,
    pub t_end_ms: u64,
    pub samples: u64,
}

impl Track {
    fn new(name: Option<String>, channels: &[Channel]) -> Track {
        Track {
            name,
            path: Decimated::default(),
            hits: Vec::new(),
            hit_count: 0,
            collisions: None,
            channels: channels
                .iter()
                .map(|c| (*c, Decimated::default()))
                .collect(),
            t_end_ms: 0,
            samples: 0,
        }
    }

    fn push(&mut self, s: &Sample) {
        self.samples += 1;
        self.t_end_ms = self.t_end_ms.max(s.t_ms);
        let before = *self.collisions.get_or_insert(s.collisions);
        if let (Some(x), Some(y)) = (s.x_cm, s.y_cm)
            && x.is_finite()
            && y.is_finite()
        {
            self.path.push(s.t_ms, [x, y]);
            if s.collisions > before {
                self.hit_count += 1;
                if self.hits.len() < MAX_HITS {
                    self.hits.push((x as f64, y as f64));
                }
            }
        }
        self.collisions = Some(before.max(s.collisions));
        for (c, d) in &mut self.channels {
            if let Some(v) = super::value(*c, s) {
                d.push(s.t_ms, [v, 0.0]);
            }
        }
    }

    /// The values of channel `c`, if gathered.
    pub fn channel(&self, c: Channel) -> Option<&Decimated> {
        self.channels.iter().find(|(k, _)| *k == c).map(|(_, d)| d)
    }
}

/// Every droid's track, in the order they first appear.
#[derive(Debug, Clone)]
pub struct Tracks {
    pub droids: Vec<Track>,
    /// The channels gathered.
    gathered: Vec<Channel>,
    /// Whether the channels were asked for (else the defaults are chosen from the data).
    asked: bool,
}

impl Tracks {
    /// Tracks gathering `channels` (none: the defaults).
    pub fn new(channels: &[Channel]) -> Tracks {
        let asked = !channels.is_empty();
        Tracks {
            droids: Vec::new(),
            gathered: if asked {
                channels.to_vec()
            } else {
                DEFAULT_POOL.to_vec()
            },
            asked,
        }
    }

    /// A sample of `droid` (`None`: the only droid). More than [`MAX_DROIDS`] droids is an
    /// error.
    pub fn push(&mut self, droid: Option<&str>, s: &Sample) -> Result<(), String> {
        let i = match self.droids.iter().position(|t| t.name.as_deref() == droid) {
            Some(i) => i,
            None => {
                if self.droids.len() >= MAX_DROIDS {
                    return Err(format!("more than {MAX_DROIDS} droids in one plot"));
                }
                self.droids
                    .push(Track::new(droid.map(str::to_string), &self.gathered));
                self.droids.len() - 1
            }
        };
        self.droids[i].push(s);
        Ok(())
    }

    /// Samples in all.
    pub fn samples(&self) -> u64 {
        self.droids.iter().map(|t| t.samples).sum()
    }

    /// Whether several droids are drawn (each in its own colour, named).
    pub fn is_fleet(&self) -> bool {
        self.droids.len() > 1 || self.droids.iter().any(|t| t.name.is_some())
    }

    /// The channels to draw: those asked for, else speed and yaw where a droid has them and
    /// Robi's wheels where a droid has those.
    pub fn channels(&self) -> Vec<Channel> {
        if self.asked {
            return self.gathered.clone();
        }
        let has = |c: Channel| {
            self.droids
                .iter()
                .any(|t| t.channel(c).is_some_and(|d| !d.is_empty()))
        };
        let robi = has(Channel::MotorLeft) || has(Channel::MotorRight);
        let sphero = self.droids.iter().any(|t| {
            t.channel(Channel::MotorLeft).is_none_or(|d| d.is_empty())
                && t.channel(Channel::MotorRight).is_none_or(|d| d.is_empty())
        });
        let mut out = Vec::new();
        if sphero || !robi {
            out.extend([Channel::Speed, Channel::Yaw]);
        }
        if robi {
            out.extend([Channel::MotorLeft, Channel::MotorRight]);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t_ms: u64, x: f32, collisions: u32) -> Sample {
        let mut s = crate::mission::sample_of(&crate::telemetry::Telemetry::default(), t_ms);
        s.x_cm = Some(x);
        s.y_cm = Some(0.0);
        s.speed = Some(x);
        s.collisions = collisions;
        s
    }

    #[test]
    fn droids_are_kept_apart_and_bounded() {
        let mut t = Tracks::new(&[]);
        for i in 0..100_000u64 {
            t.push(
                Some("D2-0001"),
                &sample(i * 100, i as f32, (i / 1000) as u32),
            )
            .unwrap();
            t.push(Some("BB-0002"), &sample(i * 100, -(i as f32), 0))
                .unwrap();
        }
        assert_eq!(t.droids.len(), 2);
        assert!(t.is_fleet());
        assert_eq!(t.droids[0].hit_count, 99);
        assert_eq!(t.droids[1].hit_count, 0);
        assert_eq!(t.droids[1].path.range(0), Some((-99_999.0, 0.0)));
        assert!(t.droids[0].path.points().len() <= 6 * super::super::decimate::MAX_BUCKETS);
        assert_eq!(t.channels(), vec![Channel::Speed, Channel::Yaw]);
        for k in 2..MAX_DROIDS {
            t.push(Some(&format!("d{k}")), &sample(0, 0.0, 0)).unwrap();
        }
        assert!(t.push(Some("one too many"), &sample(0, 0.0, 0)).is_err());
    }
}
