//! Mission scripts for `droidctl run`: a line-based language parsed up front, so a malformed
//! script is rejected before anything is sent.
//!
//! ```text
//! wake · sleep · stance tripod|bipod|waddle|stop · drive SPEED HEADING [for DURATION] · stop
//! head DEGREES · animation ID · sound ID · led front|back R G B · led logic|holo BRIGHTNESS
//! wait DURATION          (durations: 500ms, 2s, 1.5s)
//! stream off · stream RATE [SENSOR…]       (rate in samples/s; sensors: attitude, gyro, …)
//! collision off · collision XT YT XSPEED YSPEED DEADTIME
//! ```
//! Blank lines and `#` comments are ignored. Missions for several droids address lines
//! (`@R2 drive 100 90 for 2s`) and group them (`together { … }`): see [`fleet`].

pub mod fleet;

pub use fleet::{Addressed, Item, is_fleet, parse_fleet, plain_steps};

mod robots;
use crate::protocol::v2::wire::LegAction;
use crate::units::{HeadAngle, Heading};
pub use robots::MatrixAction;
use std::fmt;
use std::time::Duration;

/// Longest duration a script may ask for in one step (a day): keeps arithmetic finite.
const MAX_DURATION: Duration = Duration::from_secs(86_400);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LedGroup {
    Front,
    Back,
    Logic,
    Holo,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    Wake,
    Sleep,
    Stance(LegAction),
    Drive {
        speed: u8,
        heading: Heading,
        duration: Option<Duration>,
    },
    Stop,
    Head(HeadAngle),
    Animation(u16),
    Sound(u16),
    LedRgb(LedGroup, [u8; 3]),
    LedBrightness(LedGroup, u8),
    Wait(Duration),
    /// BOLT's LED matrix.
    Matrix(MatrixAction),
    /// RVR's tracks, each −255..=255, held for `duration` (then stopped) or until changed.
    Tank {
        left: i16,
        right: i16,
        duration: Option<Duration>,
    },
    /// Calibrate the compass to north (BOLT).
    CalibrateCompass,
    /// Streaming: samples per second (0 off) and the groups (`None`: all the droid has).
    Stream {
        rate_hz: u16,
        sensors: Option<crate::tuning::SensorSet>,
    },
    /// Collision detection's parameters.
    Collision(crate::tuning::CollisionConfig),
}

/// One step with the line it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    pub line: usize,
    pub text: String,
    pub action: Action,
}

/// A parse error: line number (1-based) and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScriptError {
    pub line: usize,
    pub message: String,
}

impl fmt::Display for ScriptError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

/// Parse a whole script; every malformed line is reported.
pub fn parse(text: &str) -> Result<Vec<Step>, Vec<ScriptError>> {
    let mut steps = Vec::new();
    let mut errors = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        match parse_line(content) {
            Ok(action) => steps.push(Step {
                line,
                text: content.to_string(),
                action,
            }),
            Err(message) => errors.push(ScriptError { line, message }),
        }
    }
    if errors.is_empty() {
        Ok(steps)
    } else {
        Err(errors)
    }
}

/// Parse `500ms`, `2s`, `1.5s`.
pub fn parse_duration(text: &str) -> Result<Duration, String> {
    let t = text.trim();
    let (num, scale) = if let Some(n) = t.strip_suffix("ms") {
        (n, 0.001)
    } else if let Some(n) = t.strip_suffix('s') {
        (n, 1.0)
    } else {
        return Err(format!("duration {t:?} needs a unit: 500ms, 2s or 1.5s"));
    };
    let v: f64 = num
        .parse()
        .map_err(|_| format!("duration {t:?} is not a number followed by ms or s"))?;
    // `inf` and `NaN` parse as f64 but are no length of time (issue 27 point 8).
    if !v.is_finite() {
        return Err(format!(
            "duration {t:?} is not a length of time: a number followed by ms or s (at most 86400s)"
        ));
    }
    if v < 0.0 {
        return Err(format!("duration {t:?} must be zero or more"));
    }
    // Checked before converting: `Duration::from_secs_f64` panics on what it cannot hold
    // (a script line `wait 1e20s`).
    let secs = v * scale;
    if secs > MAX_DURATION.as_secs_f64() {
        return Err(format!(
            "duration {t:?} is longer than a day (the limit is 86400s)"
        ));
    }
    Ok(Duration::from_secs_f64(secs))
}

fn int<T: TryFrom<i64>>(text: &str, what: &str, min: i64, max: i64) -> Result<T, String> {
    let v: i64 = text
        .parse()
        .map_err(|_| format!("{what} {text:?} is not a whole number"))?;
    if v < min || v > max {
        return Err(format!("{what} {v} is out of range {min}..={max}"));
    }
    T::try_from(v).map_err(|_| format!("{what} {v} is out of range"))
}

/// The optional `for DURATION` ending a 5-word line (`drive`, `tank`).
fn for_duration(words: &[&str], usage: &str) -> Result<Option<Duration>, String> {
    if words.len() != 5 {
        return Ok(None);
    }
    if !words[3].eq_ignore_ascii_case("for") {
        return Err(format!("expected `for` before the duration in `{usage}`"));
    }
    parse_duration(words[4]).map(Some)
}

fn arity(words: &[&str], n: usize, usage: &str) -> Result<(), String> {
    if words.len() != n {
        return Err(format!("expected `{usage}`"));
    }
    Ok(())
}

/// Every command a mission line may start with, for the message naming them (each is parsed
/// below; a test keeps the two together).
pub const COMMANDS: &[&str] = &[
    "wake",
    "sleep",
    "stance",
    "drive",
    "stop",
    "head",
    "animation",
    "sound",
    "led",
    "wait",
    "matrix",
    "tank",
    "calibrate",
    "stream",
    "collision",
];

fn parse_line(content: &str) -> Result<Action, String> {
    let words: Vec<&str> = content.split_whitespace().collect();
    let keyword = words[0].to_ascii_lowercase();
    match keyword.as_str() {
        "wake" => arity(&words, 1, "wake").map(|_| Action::Wake),
        "sleep" => arity(&words, 1, "sleep").map(|_| Action::Sleep),
        "stop" => arity(&words, 1, "stop").map(|_| Action::Stop),
        "stance" => {
            arity(&words, 2, "stance tripod|bipod|waddle|stop")?;
            let a = match words[1].to_ascii_lowercase().as_str() {
                "tripod" => LegAction::Tripod,
                "bipod" => LegAction::Bipod,
                "waddle" => LegAction::Waddle,
                "stop" => LegAction::Stop,
                other => {
                    return Err(format!(
                        "unknown stance {other:?}: use tripod, bipod, waddle or stop"
                    ));
                }
            };
            Ok(Action::Stance(a))
        }
        "drive" => {
            let usage = "drive SPEED HEADING [for DURATION]";
            if words.len() != 3 && words.len() != 5 {
                return Err(format!("expected `{usage}`"));
            }
            let speed = int(words[1], "speed", 0, 255)?;
            let h: u16 = int(words[2], "heading", 0, 359)?;
            let heading =
                Heading::new(h).ok_or_else(|| format!("heading {h} is out of range 0..=359"))?;
            let duration = for_duration(&words, usage)?;
            Ok(Action::Drive {
                speed,
                heading,
                duration,
            })
        }
        "head" => {
            arity(&words, 2, "head DEGREES")?;
            let v: f32 = words[1]
                .parse()
                .map_err(|_| format!("head angle {:?} is not a number", words[1]))?;
            HeadAngle::new(v)
                .map(Action::Head)
                .ok_or_else(|| format!("head angle {v} is out of range -160..=180"))
        }
        "animation" => {
            arity(&words, 2, "animation ID")?;
            Ok(Action::Animation(int(words[1], "animation id", 0, 65535)?))
        }
        "sound" => {
            arity(&words, 2, "sound ID")?;
            Ok(Action::Sound(int(words[1], "sound id", 0, 65535)?))
        }
        "led" => {
            if words.len() < 2 {
                return Err(
                    "expected `led front|back R G B` or `led logic|holo BRIGHTNESS`".into(),
                );
            }
            match words[1].to_ascii_lowercase().as_str() {
                g @ ("front" | "back") => {
                    arity(&words, 5, &format!("led {g} R G B"))?;
                    let group = if g == "front" {
                        LedGroup::Front
                    } else {
                        LedGroup::Back
                    };
                    let mut rgb = [0u8; 3];
                    for (i, name) in ["red", "green", "blue"].iter().enumerate() {
                        rgb[i] = int(words[2 + i], name, 0, 255)?;
                    }
                    Ok(Action::LedRgb(group, rgb))
                }
                g @ ("logic" | "holo") => {
                    arity(&words, 3, &format!("led {g} BRIGHTNESS"))?;
                    let group = if g == "logic" {
                        LedGroup::Logic
                    } else {
                        LedGroup::Holo
                    };
                    Ok(Action::LedBrightness(
                        group,
                        int(words[2], "brightness", 0, 255)?,
                    ))
                }
                other => Err(format!(
                    "unknown LED {other:?}: use front, back, logic or holo"
                )),
            }
        }
        "wait" => {
            arity(&words, 2, "wait DURATION")?;
            Ok(Action::Wait(parse_duration(words[1])?))
        }
        "matrix" => robots::parse_matrix(content, &words),
        "tank" => robots::parse_tank(&words),
        "calibrate" => {
            arity(&words, 2, "calibrate compass")?;
            match words[1].to_ascii_lowercase().as_str() {
                "compass" => Ok(Action::CalibrateCompass),
                other => Err(format!("unknown calibration {other:?}: use compass")),
            }
        }
        "stream" => {
            let usage = "stream off | stream RATE [SENSOR...]";
            match words.get(1).map(|w| w.to_ascii_lowercase()) {
                None => Err(format!("expected `{usage}`")),
                Some(w) if w == "off" => {
                    arity(&words, 2, usage)?;
                    Ok(Action::Stream {
                        rate_hz: 0,
                        sensors: None,
                    })
                }
                Some(_) => {
                    let rate_hz = int(words[1], "streaming rate", 0, 100)?;
                    let sensors = if words.len() > 2 {
                        Some(crate::tuning::SensorSet::parse(words[2..].iter().copied())?)
                    } else {
                        None
                    };
                    Ok(Action::Stream { rate_hz, sensors })
                }
            }
        }
        "collision" => Ok(Action::Collision(
            crate::tuning::CollisionConfig::parse_args(&words[1..])?,
        )),
        other => Err(format!(
            "unknown command {other:?}; expected one of {}",
            COMMANDS.join(", ")
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unknown_command_message_names_every_command_there_is() {
        let e = parse_line("fly 1 2").unwrap_err();
        for c in COMMANDS {
            assert!(e.contains(c), "{c} missing from: {e}");
            // Each one named is a command: its line is read (maybe wrongly used), not unknown.
            let e = parse_line(c).err().unwrap_or_default();
            assert!(!e.starts_with("unknown command"), "{c}: {e}");
        }
        assert!(
            e.contains("matrix") && e.contains("tank") && e.contains("calibrate"),
            "{e}"
        );
    }

    #[test]
    fn parses_stream_and_collision_lines() {
        use crate::tuning::{SensorGroup, SensorSet};
        let steps = parse("stream 50 attitude gyro\nstream off\nstream 10\ncollision 200 200 50 50 300ms\ncollision off\n").unwrap();
        assert_eq!(
            steps[0].action,
            Action::Stream {
                rate_hz: 50,
                sensors: Some(SensorSet::of(&[SensorGroup::Attitude, SensorGroup::Gyro]))
            }
        );
        assert_eq!(
            steps[1].action,
            Action::Stream {
                rate_hz: 0,
                sensors: None
            }
        );
        assert!(
            matches!(steps[3].action, Action::Collision(c) if c.x_threshold == 200 && c.dead_time_ms == 300)
        );
        assert!(matches!(steps[4].action, Action::Collision(c) if !c.enabled));
        let errs = parse("stream 500\nstream 10 sonar\ncollision 1 2\n").unwrap_err();
        assert_eq!(errs.len(), 3);
        assert!(errs[1].message.contains("sonar"), "{errs:?}");
    }

    #[test]
    fn parses_every_command() {
        let text = "\
# a mission
wake
stance tripod   # stand up
drive 100 90 for 1.5s
drive 50 180
stop
head -45.5
animation 10
sound 1915
led front 255 0 0
led back 0 0 255
led logic 200
led holo 0
wait 500ms
wait 2s
sleep
";
        let steps = parse(text).unwrap();
        assert_eq!(steps.len(), 15);
        assert_eq!(steps[0].line, 2);
        assert_eq!(steps[1].action, Action::Stance(LegAction::Tripod));
        assert_eq!(
            steps[2].action,
            Action::Drive {
                speed: 100,
                heading: Heading::new(90).unwrap(),
                duration: Some(Duration::from_millis(1500))
            }
        );
        assert_eq!(
            steps[3].action,
            Action::Drive {
                speed: 50,
                heading: Heading::new(180).unwrap(),
                duration: None
            }
        );
        assert_eq!(
            steps[5].action,
            Action::Head(HeadAngle::new(-45.5).unwrap())
        );
        assert_eq!(
            steps[8].action,
            Action::LedRgb(LedGroup::Front, [255, 0, 0])
        );
        assert_eq!(
            steps[10].action,
            Action::LedBrightness(LedGroup::Logic, 200)
        );
        assert_eq!(steps[12].action, Action::Wait(Duration::from_millis(500)));
        assert_eq!(steps[14].action, Action::Sleep);
    }

    fn err(line: &str) -> String {
        let e = parse(line).unwrap_err();
        assert_eq!(e.len(), 1);
        assert_eq!(e[0].line, 1);
        e[0].message.clone()
    }

    #[test]
    fn every_error_path() {
        assert!(err("fly 10").contains("unknown command \"fly\""));
        assert!(err("wake now").contains("expected `wake`"));
        assert!(err("sleep 1").contains("expected `sleep`"));
        assert!(err("stop 1").contains("expected `stop`"));
        assert!(err("stance").contains("stance tripod|bipod"));
        assert!(err("stance sideways").contains("unknown stance"));
        assert!(err("drive 100").contains("drive SPEED HEADING"));
        assert!(err("drive 256 0").contains("speed 256 is out of range 0..=255"));
        assert!(err("drive -1 0").contains("out of range"));
        assert!(err("drive fast 0").contains("not a whole number"));
        assert!(err("drive 10 360").contains("heading 360 is out of range 0..=359"));
        assert!(err("drive 10 0 during 2s").contains("expected `for`"));
        assert!(err("drive 10 0 for 2").contains("needs a unit"));
        assert!(err("drive 10 0 for xs").contains("not a number"));
        assert!(err("head").contains("head DEGREES"));
        assert!(err("head left").contains("not a number"));
        assert!(err("head 181").contains("-160..=180"));
        assert!(err("animation").contains("animation ID"));
        assert!(err("animation 70000").contains("out of range"));
        assert!(err("sound x").contains("not a whole number"));
        assert!(err("led").contains("led front|back R G B"));
        assert!(err("led front 1 2").contains("led front R G B"));
        assert!(err("led back 1 2 300").contains("blue 300"));
        assert!(err("led logic").contains("led logic BRIGHTNESS"));
        assert!(err("led side 1").contains("unknown LED"));
        assert!(err("wait").contains("wait DURATION"));
        assert!(err("wait -1s").contains("zero or more"));
        assert!(err("wait 100000s").contains("longer than a day"));
        for w in ["wait NaNs", "wait infs", "wait -infms", "wait infinitys"] {
            let e = err(w);
            assert!(
                e.contains("not a length of time") && !e.contains("zero or more"),
                "{w}: {e}"
            );
        }
    }

    #[test]
    fn reports_all_bad_lines_with_numbers() {
        let e = parse("wake\nfly\n\n# ok\ndrive 1 999\n").unwrap_err();
        let lines: Vec<usize> = e.iter().map(|e| e.line).collect();
        assert_eq!(lines, [2, 5]);
        assert_eq!(
            e[1].to_string(),
            "line 5: heading 999 is out of range 0..=359"
        );
    }

    #[test]
    fn durations() {
        assert_eq!(parse_duration("500ms"), Ok(Duration::from_millis(500)));
        assert_eq!(parse_duration("2s"), Ok(Duration::from_secs(2)));
        assert_eq!(parse_duration("1.5s"), Ok(Duration::from_millis(1500)));
        assert_eq!(parse_duration("0s"), Ok(Duration::ZERO));
        assert_eq!(parse_duration("86400s"), Ok(MAX_DURATION));
    }

    #[test]
    fn huge_durations_are_refused_not_a_panic() {
        for t in ["1e20s", "1e23ms", "86401s", "1e300s"] {
            let e = parse_duration(t).unwrap_err();
            assert!(
                e.contains("longer than a day") && e.contains("86400s"),
                "{t}: {e}"
            );
        }
        let e = parse(&["drive 1 1 for 1e20s".to_string()].join("\n")).unwrap_err();
        assert!(e[0].to_string().starts_with("line 1:"), "{}", e[0]);
    }
}
