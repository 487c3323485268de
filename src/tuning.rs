//! What a user tunes about monitoring, as plain values: the sensor groups a droid streams
//! (issue 22 point 2) and the collision detector's parameters (point 3). The families turn
//! them into commands (`crate::family::stream`); the config file, mission scripts and the app
//! hold them. A leaf: no protocol, no IO.
//!
//! ## Collision detection
//! The same for Sphero API v1 and v2: a threshold and a speed term per axis, and a dead time.
//! As Sphero's collision-detection note describes them: `x_threshold`/`y_threshold` (0..=255)
//! are the impact power an axis must exceed (0 turns the axis off; x is left/right, y is
//! forward/back); `x_speed`/`y_speed` (0..=255) are added to the threshold scaled by the
//! droid's speed (0..=255 of its top speed), so a fast droid needs a harder hit; `dead_time`
//! keeps the detector quiet for a while after a collision (sent in 10 ms units, so 0..=2550 ms).
//! The families send them in their own parameter order (`droid-facts.md` §2, §4: v2 sends
//! x and y thresholds, then x and y speeds; v1's catalogue takes Xt, Xspd, Yt, Yspd).

use std::fmt;

/// A group of sensor values streamed together.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SensorGroup {
    /// Pitch, roll, yaw (degrees).
    Attitude,
    /// Accelerometer x, y, z (g).
    Accelerometer,
    /// Gyro x, y, z (°/s).
    Gyro,
    /// Locator x, y (cm).
    Locator,
    /// Velocity x, y (cm/s).
    Velocity,
    /// R2's dome angle (degrees).
    HeadAngle,
}

impl SensorGroup {
    pub const ALL: [SensorGroup; 6] = [
        SensorGroup::Attitude,
        SensorGroup::Accelerometer,
        SensorGroup::Gyro,
        SensorGroup::Locator,
        SensorGroup::Velocity,
        SensorGroup::HeadAngle,
    ];

    /// The name in the config file and mission scripts.
    pub fn name(self) -> &'static str {
        match self {
            SensorGroup::Attitude => "attitude",
            SensorGroup::Accelerometer => "accelerometer",
            SensorGroup::Gyro => "gyro",
            SensorGroup::Locator => "locator",
            SensorGroup::Velocity => "velocity",
            SensorGroup::HeadAngle => "head",
        }
    }

    pub fn parse(name: &str) -> Option<SensorGroup> {
        let n = name.trim().to_ascii_lowercase();
        SensorGroup::ALL
            .into_iter()
            .find(|g| g.name() == n || (n == "accel" && *g == SensorGroup::Accelerometer))
    }

    fn bit(self) -> u8 {
        1 << (self as u8)
    }
}

/// A set of sensor groups.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SensorSet(u8);

impl SensorSet {
    pub const EMPTY: SensorSet = SensorSet(0);

    pub fn of(groups: &[SensorGroup]) -> SensorSet {
        SensorSet(groups.iter().fold(0, |m, g| m | g.bit()))
    }

    pub fn contains(self, g: SensorGroup) -> bool {
        self.0 & g.bit() != 0
    }

    pub fn insert(&mut self, g: SensorGroup) {
        self.0 |= g.bit();
    }

    pub fn remove(&mut self, g: SensorGroup) {
        self.0 &= !g.bit();
    }

    pub fn toggle(&mut self, g: SensorGroup) {
        self.0 ^= g.bit();
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Only the groups also in `other`.
    pub fn intersect(self, other: SensorSet) -> SensorSet {
        SensorSet(self.0 & other.0)
    }

    pub fn iter(self) -> impl Iterator<Item = SensorGroup> {
        SensorGroup::ALL
            .into_iter()
            .filter(move |g| self.contains(*g))
    }

    /// Parse names (`attitude gyro`); an unknown one is an error naming it.
    pub fn parse<'a>(names: impl IntoIterator<Item = &'a str>) -> Result<SensorSet, String> {
        let mut s = SensorSet::EMPTY;
        for n in names {
            let g = SensorGroup::parse(n).ok_or_else(|| {
                let all: Vec<&str> = SensorGroup::ALL.iter().map(|g| g.name()).collect();
                format!("unknown sensor group {n:?}: use {}", all.join(", "))
            })?;
            s.insert(g);
        }
        Ok(s)
    }
}

impl fmt::Display for SensorSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.iter().map(SensorGroup::name).collect();
        if names.is_empty() {
            write!(f, "none")
        } else {
            write!(f, "{}", names.join(" "))
        }
    }
}

/// What a user asks for: samples per second (0: streaming off) and the groups.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamRequest {
    pub rate_hz: u16,
    pub sensors: SensorSet,
}

/// Collision detection as configured (also the config file's `[collision]` table, checked
/// when it loads).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CollisionConfig {
    /// Off: method 0 (no detection, no notifications).
    pub enabled: bool,
    pub x_threshold: u8,
    pub y_threshold: u8,
    pub x_speed: u8,
    pub y_speed: u8,
    /// Quiet time after a collision, ms (sent in 10 ms units, rounded down).
    pub dead_time_ms: u16,
}

/// The longest dead time the command can carry.
pub const MAX_DEAD_TIME_MS: u16 = 2550;

impl Default for CollisionConfig {
    /// What droidctl has always sent: 100 on every axis, 100 ms dead time (equal x and y
    /// values sidestep the disputed parameter order).
    fn default() -> Self {
        CollisionConfig {
            enabled: true,
            x_threshold: 100,
            y_threshold: 100,
            x_speed: 100,
            y_speed: 100,
            dead_time_ms: 100,
        }
    }
}

impl CollisionConfig {
    /// The method byte: 1 (accelerometer) when on, 0 off.
    pub fn method(&self) -> u8 {
        u8::from(self.enabled)
    }

    /// The dead time in the command's 10 ms units.
    pub fn dead_time_units(&self) -> u8 {
        (self.dead_time_ms.min(MAX_DEAD_TIME_MS) / 10) as u8
    }

    /// For the log, the palette and messages.
    pub fn describe(&self) -> String {
        if !self.enabled {
            return "off".into();
        }
        format!(
            "x {}+{} y {}+{} dead {} ms",
            self.x_threshold, self.x_speed, self.y_threshold, self.y_speed, self.dead_time_ms
        )
    }

    /// Parse a mission line's arguments: `off`, or `XT YT XSPD YSPD DEAD_MS`.
    pub fn parse_args(words: &[&str]) -> Result<CollisionConfig, String> {
        const USAGE: &str =
            "collision off | collision XT YT XSPEED YSPEED DEADTIME (e.g. 100 100 100 100 100ms)";
        if let [w] = words
            && w.eq_ignore_ascii_case("off")
        {
            return Ok(CollisionConfig {
                enabled: false,
                ..CollisionConfig::default()
            });
        }
        let [xt, yt, xs, ys, dead] = words else {
            return Err(format!("expected `{USAGE}`"));
        };
        let byte = |w: &str, what: &str| -> Result<u8, String> {
            w.parse::<u8>()
                .map_err(|_| format!("{what} {w:?} is not a whole number in 0..=255"))
        };
        let dead_ms = parse_ms(dead)
            .ok_or_else(|| format!("dead time {dead:?} is not a duration (100ms, 0.5s)"))?;
        if dead_ms > MAX_DEAD_TIME_MS as u128 {
            return Err(format!(
                "dead time {dead_ms} ms is longer than {MAX_DEAD_TIME_MS} ms"
            ));
        }
        Ok(CollisionConfig {
            enabled: true,
            x_threshold: byte(xt, "x threshold")?,
            y_threshold: byte(yt, "y threshold")?,
            x_speed: byte(xs, "x speed")?,
            y_speed: byte(ys, "y speed")?,
            dead_time_ms: dead_ms as u16,
        })
    }
}

/// `250ms`, `0.25s` or `250` (ms) in whole ms.
fn parse_ms(text: &str) -> Option<u128> {
    let (num, scale) = if let Some(n) = text.strip_suffix("ms") {
        (n, 1.0)
    } else if let Some(n) = text.strip_suffix('s') {
        (n, 1000.0)
    } else {
        (text, 1.0)
    };
    let v: f64 = num.parse().ok()?;
    (v.is_finite() && v >= 0.0 && v * scale < 1e9).then(|| (v * scale).round() as u128)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sensor_sets_parse_and_print() {
        let s = SensorSet::parse(["gyro", "Attitude", "accel"]).unwrap();
        assert_eq!(s.to_string(), "attitude accelerometer gyro");
        assert!(SensorSet::parse(["sonar"]).unwrap_err().contains("sonar"));
        assert_eq!(SensorSet::EMPTY.to_string(), "none");
    }

    #[test]
    fn mission_arguments_parse() {
        let c = CollisionConfig::parse_args(&["200", "150", "50", "60", "250ms"]).unwrap();
        assert_eq!(
            (c.x_threshold, c.y_threshold, c.x_speed, c.y_speed),
            (200, 150, 50, 60)
        );
        assert_eq!((c.dead_time_ms, c.dead_time_units()), (250, 25));
        assert!(!CollisionConfig::parse_args(&["off"]).unwrap().enabled);
        assert!(
            CollisionConfig::parse_args(&["300", "1", "1", "1", "0"])
                .unwrap_err()
                .contains("x threshold")
        );
        assert!(
            CollisionConfig::parse_args(&["1", "1", "1", "1", "3s"])
                .unwrap_err()
                .contains("2550")
        );
        assert!(CollisionConfig::parse_args(&["1"]).is_err());
    }
}
