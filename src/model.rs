//! The droids droidctl knows (`droid-facts.md` §1): how to recognise them by advertised name,
//! which protocol they speak, and how fast they may be written to.

use std::time::Duration;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Model {
    R2D2,
    R2Q5,
    BB9E,
    BB8,
    SprkPlus,
    Ollie,
    Robi42,
    /// Sphero BOLT (and BOLT+, which advertises the same way): two processors, an 8×8 LED
    /// matrix, compass, ambient light, robot-to-robot IR (`droid-facts.md` §6).
    Bolt,
    /// Sphero Mini: one processor, BB-8-like on API v2.
    Mini,
    /// Sphero RVR: a tracked rover, every command addressed to one of two processors.
    Rvr,
}

/// The wire protocol a model speaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Protocol {
    SpheroV2,
    SpheroV1,
    Rsrcp,
}

impl Model {
    /// Sphero's rolling robots that raw motor power can throw off the floor (the balls and
    /// Ollie; not RVR, the Star Wars droids' legs or Robi 42).
    pub fn hops(self) -> bool {
        matches!(
            self,
            Model::Bolt | Model::Mini | Model::BB8 | Model::SprkPlus | Model::Ollie
        )
    }
    pub const ALL: [Model; 10] = [
        Model::R2D2,
        Model::R2Q5,
        Model::BB9E,
        Model::BB8,
        Model::SprkPlus,
        Model::Ollie,
        Model::Robi42,
        Model::Bolt,
        Model::Mini,
        Model::Rvr,
    ];

    /// Recognise a model from its advertised BLE name (`D2-1234` → R2-D2).
    pub fn from_advertised_name(name: &str) -> Option<Model> {
        let n = name.trim();
        if n == "Robi 42" {
            return Some(Model::Robi42);
        }
        Model::ALL
            .into_iter()
            .find(|m| m.name_prefix().is_some_and(|p| n.starts_with(p)))
    }

    /// The advertised-name prefix (`None` for Robi 42, which uses a full local name).
    pub fn name_prefix(self) -> Option<&'static str> {
        match self {
            Model::R2D2 => Some("D2-"),
            Model::R2Q5 => Some("Q5-"),
            Model::BB9E => Some("GB-"),
            Model::BB8 => Some("BB-"),
            Model::SprkPlus => Some("SK-"),
            Model::Ollie => Some("2B-"),
            Model::Robi42 => None,
            Model::Bolt => Some("SB-"),
            Model::Mini => Some("SM-"),
            Model::Rvr => Some("RV-"),
        }
    }

    pub fn display_name(self) -> &'static str {
        match self {
            Model::R2D2 => "R2-D2",
            Model::R2Q5 => "R2-Q5",
            Model::BB9E => "BB-9E",
            Model::BB8 => "BB-8",
            Model::SprkPlus => "SPRK+",
            Model::Ollie => "Ollie",
            Model::Robi42 => "Robi 42",
            Model::Bolt => "Sphero BOLT",
            Model::Mini => "Sphero Mini",
            Model::Rvr => "Sphero RVR",
        }
    }

    /// Short lower-case id: what the command line takes (`--sim r2d2`), what every document
    /// says, and what captures and JSON outputs name the model with. Robi 42's is `robi`
    /// (earlier versions wrote `robi42`, which [`Model::from_id`] still reads).
    pub fn id(self) -> &'static str {
        match self {
            Model::R2D2 => "r2d2",
            Model::R2Q5 => "r2q5",
            Model::BB9E => "bb9e",
            Model::BB8 => "bb8",
            Model::SprkPlus => "sprk",
            Model::Ollie => "ollie",
            Model::Robi42 => "robi",
            Model::Bolt => "bolt",
            Model::Mini => "mini",
            Model::Rvr => "rvr",
        }
    }

    /// The model an id names: its [`Model::id`], its display name in any case, with or
    /// without `-`, `_` and spaces (`R2-D2`, `Robi 42`), or a short form people type.
    pub fn from_id(id: &str) -> Option<Model> {
        let id = id.trim().to_ascii_lowercase().replace(['-', '_', ' '], "");
        // Short forms people type.
        let id = match id.as_str() {
            "robi42" => "robi".to_string(),
            "sprkplus" | "sprk+" => "sprk".to_string(),
            "boltplus" | "bolt+" | "spherobolt" => "bolt".to_string(),
            "spherorvr" | "rvr+" => "rvr".to_string(),
            "spheromini" => "mini".to_string(),
            _ => id,
        };
        Model::ALL.into_iter().find(|m| {
            m.id() == id
                || m.display_name()
                    .to_ascii_lowercase()
                    .replace(['-', ' '], "")
                    == id
        })
    }

    /// Every model's id, in the table's order, for messages: `r2d2, r2q5, …, rvr`.
    pub fn ids_listed() -> String {
        Model::ALL.map(Model::id).join(", ")
    }

    /// [`Model::from_id`], or the message that says what the command line takes:
    /// `unknown model "c3po": use one of r2d2, r2q5, …, rvr`.
    pub fn parse_id(id: &str) -> Result<Model, String> {
        Model::from_id(id)
            .ok_or_else(|| format!("unknown model {id:?}: use one of {}", Model::ids_listed()))
    }

    pub fn protocol(self) -> Protocol {
        match self {
            Model::R2D2 | Model::R2Q5 | Model::BB9E | Model::Bolt | Model::Mini | Model::Rvr => {
                Protocol::SpheroV2
            }
            Model::BB8 | Model::SprkPlus | Model::Ollie => Protocol::SpheroV1,
            Model::Robi42 => Protocol::Rsrcp,
        }
    }

    /// Minimum interval between writes used by reference clients (`droid-facts.md` §1).
    /// One client uses 12 ms for R2-D2: this is only a default, configurable.
    pub fn write_pacing(self) -> Duration {
        match self {
            // spherov2.py's `cmd_safe_interval` (`droid-facts.md` §6): BOLT and RVR 75 ms,
            // Mini 120 ms.
            Model::Bolt | Model::Rvr => return Duration::from_millis(75),
            Model::Mini => return Duration::from_millis(120),
            _ => {}
        }
        match self.protocol() {
            Protocol::SpheroV2 => Duration::from_millis(120),
            Protocol::SpheroV1 => Duration::from_millis(60),
            Protocol::Rsrcp => Duration::from_millis(20),
        }
    }

    /// Whether the droid has R2's legs (stances).
    pub fn has_legs(self) -> bool {
        matches!(self, Model::R2D2 | Model::R2Q5)
    }

    /// Reports its state as RSRCP frames (motor speeds, poti, buttons, lamps, piezo) rather
    /// than Sphero sensor streaming.
    pub fn reports_state_frames(self) -> bool {
        self.protocol() == Protocol::Rsrcp
    }

    /// Whether this build can drive the model (its protocol family is implemented).
    pub fn drivable(self) -> bool {
        true
    }

    /// A rolling droid with an aim mode (back light, turn in place, set heading 0): BB-8,
    /// SPRK+, Ollie, and BB-9E (its aiming LED, `droid-facts.md` §2).
    pub fn can_aim(self) -> bool {
        matches!(
            self,
            Model::BB8
                | Model::SprkPlus
                | Model::Ollie
                | Model::BB9E
                | Model::Bolt
                | Model::Mini
                | Model::Rvr
        )
    }

    /// How many processors take commands: BOLT and RVR have a primary (0x11: power, lights,
    /// RVR's colour sensor) and a secondary (0x12: drive, sensors, BOLT's matrix); the others
    /// one, addressed without a target (`droid-facts.md` §6).
    pub fn processors(self) -> u8 {
        match self {
            Model::Bolt | Model::Rvr => 2,
            _ => 1,
        }
    }

    /// Whether every command must name its processor (RVR; spherov2's `_require_target`).
    pub fn requires_target(self) -> bool {
        self == Model::Rvr
    }

    /// BOLT's 8×8 LED matrix.
    pub fn has_matrix(self) -> bool {
        self == Model::Bolt
    }

    /// A magnetometer to calibrate to north, and an ambient light sensor (BOLT).
    pub fn has_compass(self) -> bool {
        self == Model::Bolt
    }

    /// Driven by its two tracks as well as by heading (RVR's raw motors).
    pub fn has_tracks(self) -> bool {
        self == Model::Rvr
    }

    /// Sensors through the streaming service (tokens, periods) rather than masks (RVR).
    pub fn streams_by_service(self) -> bool {
        self == Model::Rvr
    }

    /// A colour sensor underneath (RVR).
    pub fn has_color_sensor(self) -> bool {
        self == Model::Rvr
    }

    /// The Star Wars droids' animations and sounds (IO 0x17 `play_animation`,
    /// `play_audio_file`); spherov2 binds neither to BOLT, Mini or RVR, which have no speaker.
    pub fn plays_animations(self) -> bool {
        matches!(self, Model::R2D2 | Model::R2Q5 | Model::BB9E)
    }

    /// Whether the droid has R2's rotating dome.
    pub fn has_dome(self) -> bool {
        matches!(self, Model::R2D2 | Model::R2Q5)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_to_models() {
        assert_eq!(Model::from_advertised_name("D2-1A2B"), Some(Model::R2D2));
        assert_eq!(Model::from_advertised_name("Q5-0000"), Some(Model::R2Q5));
        assert_eq!(Model::from_advertised_name("GB-77"), Some(Model::BB9E));
        assert_eq!(Model::from_advertised_name("BB-8A"), Some(Model::BB8));
        assert_eq!(Model::from_advertised_name("SK-1"), Some(Model::SprkPlus));
        assert_eq!(Model::from_advertised_name("2B-9"), Some(Model::Ollie));
        assert_eq!(Model::from_advertised_name("Robi 42"), Some(Model::Robi42));
        assert_eq!(Model::from_advertised_name("SB-5A1C"), Some(Model::Bolt));
        assert_eq!(Model::from_advertised_name("SM-0B12"), Some(Model::Mini));
        assert_eq!(Model::from_advertised_name("RV-F00D"), Some(Model::Rvr));
        assert_eq!(Model::from_advertised_name("JBL Flip"), None);
        assert_eq!(Model::from_advertised_name("d2-lower"), None);
    }

    #[test]
    fn ids() {
        assert_eq!(Model::from_id("r2d2"), Some(Model::R2D2));
        assert_eq!(Model::from_id("R2-Q5"), Some(Model::R2Q5));
        assert_eq!(Model::from_id("bb9e"), Some(Model::BB9E));
        assert_eq!(Model::from_id("c3po"), None);
        assert_eq!(Model::from_id("robi"), Some(Model::Robi42));
        assert_eq!(
            Model::from_id("robi42"),
            Some(Model::Robi42),
            "older captures' id"
        );
        // Every id names its own model.
        for m in Model::ALL {
            assert_eq!(Model::from_id(m.id()), Some(m));
        }
        assert_eq!(
            Model::parse_id("c3po"),
            Err("unknown model \"c3po\": use one of r2d2, r2q5, bb9e, bb8, sprk, ollie, robi, bolt, mini, rvr".into())
        );
        assert_eq!(Model::from_id("Robi 42"), Some(Model::Robi42));
        assert_eq!(Model::from_id("sprk+"), Some(Model::SprkPlus));
        assert_eq!(Model::R2D2.write_pacing(), Duration::from_millis(120));
        assert_eq!(Model::from_id("bolt+"), Some(Model::Bolt));
        assert_eq!(Model::from_id("Sphero RVR"), Some(Model::Rvr));
        assert_eq!(Model::from_id("mini"), Some(Model::Mini));
        assert_eq!(Model::Bolt.write_pacing(), Duration::from_millis(75));
        assert_eq!(Model::Rvr.write_pacing(), Duration::from_millis(75));
        assert_eq!(Model::Mini.write_pacing(), Duration::from_millis(120));
    }
}
