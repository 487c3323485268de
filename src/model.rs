//! The droids droidctl knows (`droid-facts.md` §1): one row per model in [`MODELS`] — how to
//! recognise it by advertised name, which protocol it speaks, how fast it may be written to,
//! and what it can do ([`Caps`]). Everything that asks "can this droid …" (the key table's
//! `Needs`, the Edu calls table, the bridge's capabilities, the families) reads the row, so
//! adding a robot is adding its row here, not another arm in each of those places.

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
    /// Sphero BOLT: two processors, an 8×8 LED matrix, compass, ambient light,
    /// robot-to-robot IR (`droid-facts.md` §6).
    Bolt,
    /// Sphero BOLT+, the BOLT sold to classrooms now: a screen instead of the 8×8 matrix,
    /// advertised as `BP-`, everything addressed to its primary processor. `droid-facts.md` is
    /// silent on it; the row follows sphero-unsw 0.1.13's `toy/boltplus.py` (a spherov2 fork,
    /// MIT), whose guesses are marked unverified where they are used.
    BoltPlus,
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

/// What a model can do, as flags: a small hand-written bit set (no crate needed for a
/// `u32`). A capability is a flag here and nowhere else; consumers ask [`Model::has`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Caps(u32);

impl Caps {
    pub const NONE: Caps = Caps(0);
    /// R2's legs (stances, waddle).
    pub const LEGS: Caps = Caps(1 << 0);
    /// R2's rotating dome.
    pub const DOME: Caps = Caps(1 << 1);
    /// The Star Wars droids' animations and sounds (IO 0x17 `play_animation`,
    /// `play_audio_file`); spherov2 binds neither to BOLT, Mini or RVR, which have no speaker.
    pub const ANIMATIONS: Caps = Caps(1 << 2);
    /// Takes BOLT's 8×8 frame-player commands (IO 0x2D..0x43): BOLT's LED matrix, and
    /// BOLT+'s screen, which sphero-unsw draws with exactly those commands (an 8×8 picture,
    /// `set_main_led` as a fill of it).
    pub const MATRIX: Caps = Caps(1 << 3);
    /// A magnetometer to calibrate to north, and an ambient light sensor (BOLT).
    pub const COMPASS: Caps = Caps(1 << 4);
    /// Driven by its two tracks as well as by heading (RVR's raw motors).
    pub const TRACKS: Caps = Caps(1 << 5);
    /// A colour sensor underneath (RVR).
    pub const COLOR_SENSOR: Caps = Caps(1 << 6);
    /// Robot-to-robot infrared (BOLT, RVR; Sphero Edu's "Communications").
    pub const IR: Caps = Caps(1 << 7);
    /// A luminosity reading (BOLT, RVR).
    pub const LIGHT_SENSOR: Caps = Caps(1 << 8);
    /// An aim mode: back light, turn in place, set heading 0 (the rolling droids, BB-9E's
    /// aiming LED, `droid-facts.md` §2).
    pub const AIM: Caps = Caps(1 << 9);
    /// Lights droidctl can set (the Sphero droids).
    pub const LIGHTS: Caps = Caps(1 << 10);
    /// A front light of its own (R2-D2, R2-Q5, BOLT, RVR, Mini).
    pub const FRONT_LED: Caps = Caps(1 << 11);
    /// BB-9E's dome lights.
    pub const DOME_LIGHTS: Caps = Caps(1 << 12);
    /// Rolls toward a heading, with a turbo, and can back up (the Sphero robots; Robi 42
    /// only steers forward).
    pub const HEADING: Caps = Caps(1 << 13);
    /// Sensors streamed at a rate droidctl chooses (not Robi 42's own state frames).
    pub const STREAMING: Caps = Caps(1 << 14);
    /// Two motors droidctl drives raw (spherov2's `raw_motor`): BOLT, Mini, RVR and the API
    /// v1 robots through their Set Raw Motors.
    pub const RAW_MOTORS: Caps = Caps(1 << 15);
    /// Raw motor power can throw it off the floor (the balls and Ollie; not RVR, the Star
    /// Wars droids' legs or Robi 42).
    pub const HOPS: Caps = Caps(1 << 16);
    /// Every command must name its processor (RVR; spherov2's `_require_target`).
    pub const TARGETED: Caps = Caps(1 << 17);
    /// Sensors through the streaming service (tokens, periods) rather than masks (RVR).
    pub const STREAM_SERVICE: Caps = Caps(1 << 18);
    /// The main light is front and back at once (spherov2's `LedManager` on R2-D2, R2-Q5 and
    /// BOLT: what Sphero Edu's front and back lights read after `setMainLed`).
    pub const MAIN_FRONT_BACK: Caps = Caps(1 << 19);
    /// Sphero Edu's speeds are scaled onto its range (spherov2's Mini: (speed ± 126) × 2⁄3).
    pub const SCALED_SPEED: Caps = Caps(1 << 20);
    /// Streams its locator and velocity a quarter turn from the other v1 droids' axes
    /// (spherov2.py's Ollie: `protocol::v1::sensor::rotated_axes` has the sources).
    pub const ROTATED_AXES: Caps = Caps(1 << 21);
    /// Takes commands without the v2 anti-DoS unlock (RVR: spherov2.py's `toy/rvr.py`
    /// writes none; `droid-facts.md` §6).
    pub const NO_UNLOCK: Caps = Caps(1 << 22);
    /// A screen where BOLT has its 8×8 LED matrix (BOLT+). What it shows is what the matrix
    /// commands draw: sphero-unsw describes nothing else of it (no image, text or resolution
    /// commands of its own), so how the real screen scales the 8×8 picture is unverified.
    pub const SCREEN: Caps = Caps(1 << 23);

    /// Every flag with its name, for `Debug` and documents.
    pub const NAMED: [(Caps, &'static str); 24] = [
        (Caps::LEGS, "legs"),
        (Caps::DOME, "dome"),
        (Caps::ANIMATIONS, "animations"),
        (Caps::MATRIX, "matrix"),
        (Caps::COMPASS, "compass"),
        (Caps::TRACKS, "tracks"),
        (Caps::COLOR_SENSOR, "color sensor"),
        (Caps::IR, "infrared"),
        (Caps::LIGHT_SENSOR, "light sensor"),
        (Caps::AIM, "aim"),
        (Caps::LIGHTS, "lights"),
        (Caps::FRONT_LED, "front led"),
        (Caps::DOME_LIGHTS, "dome lights"),
        (Caps::HEADING, "heading"),
        (Caps::STREAMING, "streaming"),
        (Caps::RAW_MOTORS, "raw motors"),
        (Caps::HOPS, "hops"),
        (Caps::TARGETED, "targeted"),
        (Caps::STREAM_SERVICE, "stream service"),
        (Caps::MAIN_FRONT_BACK, "main is front and back"),
        (Caps::SCALED_SPEED, "scaled speed"),
        (Caps::ROTATED_AXES, "rotated axes"),
        (Caps::NO_UNLOCK, "no unlock"),
        (Caps::SCREEN, "screen"),
    ];

    /// Both sets' flags (usable in the `const` table).
    pub const fn with(self, other: Caps) -> Caps {
        Caps(self.0 | other.0)
    }

    /// Whether every flag of `other` is set.
    pub const fn contains(self, other: Caps) -> bool {
        self.0 & other.0 == other.0
    }
}

impl std::ops::BitOr for Caps {
    type Output = Caps;
    fn bitor(self, rhs: Caps) -> Caps {
        self.with(rhs)
    }
}

impl std::fmt::Debug for Caps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = Caps::NAMED
            .iter()
            .filter(|(c, _)| self.contains(*c))
            .map(|(_, n)| *n)
            .collect();
        write!(f, "Caps({})", names.join(" | "))
    }
}

/// How a model shows itself in a scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Advertised {
    /// Its advertised name starts with this (`D2-1234`).
    Prefix(&'static str),
    /// Its advertised name is exactly this (Robi 42's full local name).
    Name(&'static str),
}

/// One row of the model table.
#[derive(Debug, Clone, Copy)]
pub struct ModelSpec {
    pub model: Model,
    /// Short lower-case id ([`Model::id`]).
    pub id: &'static str,
    /// Other spellings people type for it, lower case without `-`, `_` and spaces.
    pub aliases: &'static [&'static str],
    pub advertised: Advertised,
    /// The name for people.
    pub name: &'static str,
    pub protocol: Protocol,
    /// Minimum interval between writes, ms ([`Model::write_pacing`]).
    pub pacing_ms: u64,
    /// How many processors take commands ([`Model::processors`]).
    pub processors: u8,
    /// The least time a full turn in place takes, ms (spherov2's `spin`, which Sphero Edu's
    /// `spin` follows).
    pub full_turn_ms: u16,
    pub caps: Caps,
}

/// What every Sphero robot has (not Robi 42).
const SPHERO: Caps = Caps::LIGHTS.with(Caps::HEADING).with(Caps::STREAMING);
/// R2-D2 and R2-Q5.
const R2: Caps = SPHERO
    .with(Caps::MAIN_FRONT_BACK)
    .with(Caps::LEGS)
    .with(Caps::DOME)
    .with(Caps::ANIMATIONS)
    .with(Caps::FRONT_LED);
/// The API v1 balls and Ollie.
const V1_BALL: Caps = SPHERO
    .with(Caps::AIM)
    .with(Caps::RAW_MOTORS)
    .with(Caps::HOPS);

/// R2-D2's row, which the other API v2 rows change.
const R2D2_ROW: ModelSpec = ModelSpec {
    model: Model::R2D2,
    id: "r2d2",
    aliases: &[],
    advertised: Advertised::Prefix("D2-"),
    name: "R2-D2",
    protocol: Protocol::SpheroV2,
    pacing_ms: 120,
    processors: 1,
    full_turn_ms: 700,
    caps: R2,
};

/// BB-8's row, which the other API v1 rows change.
const BB8_ROW: ModelSpec = ModelSpec {
    model: Model::BB8,
    id: "bb8",
    aliases: &[],
    advertised: Advertised::Prefix("BB-"),
    name: "BB-8",
    protocol: Protocol::SpheroV1,
    pacing_ms: 60,
    processors: 1,
    full_turn_ms: 450,
    caps: V1_BALL,
};

/// What BOLT and BOLT+ share: the matrix, compass, light sensor, infrared and raw motors.
const BOLT_CAPS: Caps = SPHERO
    .with(Caps::AIM)
    .with(Caps::FRONT_LED)
    .with(Caps::MATRIX)
    .with(Caps::COMPASS)
    .with(Caps::LIGHT_SENSOR)
    .with(Caps::IR)
    .with(Caps::RAW_MOTORS)
    .with(Caps::HOPS);

/// BOLT's row, which BOLT+'s changes.
const BOLT_ROW: ModelSpec = ModelSpec {
    model: Model::Bolt,
    id: "bolt",
    aliases: &["spherobolt"],
    advertised: Advertised::Prefix("SB-"),
    name: "Sphero BOLT",
    pacing_ms: 75,
    processors: 2,
    full_turn_ms: 450,
    caps: BOLT_CAPS.with(Caps::MAIN_FRONT_BACK),
    ..R2D2_ROW
};

/// The model table, in [`Model::ALL`]'s order (a test holds the two together). Pacing is
/// the reference clients' minimum write interval (`droid-facts.md` §1; spherov2.py's
/// `cmd_safe_interval` for BOLT, RVR and Mini, §6): only a default, configurable. BOLT and
/// RVR have a primary processor (0x11: power, lights, RVR's colour sensor) and a secondary
/// (0x12: drive, sensors, BOLT's matrix); BOLT+ is addressed on its primary alone.
pub const MODELS: [ModelSpec; 11] = [
    R2D2_ROW,
    ModelSpec {
        model: Model::R2Q5,
        id: "r2q5",
        advertised: Advertised::Prefix("Q5-"),
        name: "R2-Q5",
        ..R2D2_ROW
    },
    ModelSpec {
        model: Model::BB9E,
        id: "bb9e",
        advertised: Advertised::Prefix("GB-"),
        name: "BB-9E",
        full_turn_ms: 450,
        caps: SPHERO
            .with(Caps::ANIMATIONS)
            .with(Caps::AIM)
            .with(Caps::DOME_LIGHTS),
        ..R2D2_ROW
    },
    BB8_ROW,
    ModelSpec {
        model: Model::SprkPlus,
        id: "sprk",
        aliases: &["sprkplus", "sprk+"],
        advertised: Advertised::Prefix("SK-"),
        name: "SPRK+",
        ..BB8_ROW
    },
    ModelSpec {
        model: Model::Ollie,
        id: "ollie",
        advertised: Advertised::Prefix("2B-"),
        name: "Ollie",
        full_turn_ms: 600,
        caps: V1_BALL.with(Caps::ROTATED_AXES),
        ..BB8_ROW
    },
    ModelSpec {
        model: Model::Robi42,
        // Earlier versions wrote `robi42`, which [`Model::from_id`] still reads.
        id: "robi",
        aliases: &["robi42"],
        advertised: Advertised::Name("Robi 42"),
        name: "Robi 42",
        protocol: Protocol::Rsrcp,
        pacing_ms: 20,
        processors: 1,
        full_turn_ms: 450,
        caps: Caps::NONE,
    },
    BOLT_ROW,
    // sphero-unsw's `BOLTPLUS`: `ToyType('Sphero BOLT', 'BP-', 'BP', .075)` (its display
    // name says BOLT; the prefix and the 75 ms pacing are its own), BOLT's LEDs, sensors and
    // robot-to-robot infrared, no anti-DoS unlock (its `_handshake` is commented out, "TODO:
    // find correct info here"; its users drive real BOLT+s without one). A second
    // description, `sphero-bolt-plus` 1.0.1 (PyPI), disagrees: it scans for `SB+` and writes
    // JSON to the Nordic UART service, which its own comments call "a simplified
    // implementation"; nothing is taken from it. Size and turn pace are BOLT's (unverified).
    ModelSpec {
        model: Model::BoltPlus,
        id: "boltplus",
        aliases: &["bolt+", "spheroboltplus", "spherobolt+"],
        advertised: Advertised::Prefix("BP-"),
        name: "Sphero BOLT+",
        // Its own LED map (no main light that is front and back at once), a screen, no unlock.
        caps: BOLT_CAPS.with(Caps::SCREEN).with(Caps::NO_UNLOCK),
        ..BOLT_ROW
    },
    ModelSpec {
        model: Model::Mini,
        id: "mini",
        aliases: &["spheromini"],
        advertised: Advertised::Prefix("SM-"),
        name: "Sphero Mini",
        full_turn_ms: 500,
        caps: SPHERO
            .with(Caps::AIM)
            .with(Caps::FRONT_LED)
            .with(Caps::SCALED_SPEED)
            .with(Caps::RAW_MOTORS)
            .with(Caps::HOPS),
        ..R2D2_ROW
    },
    ModelSpec {
        model: Model::Rvr,
        id: "rvr",
        aliases: &["spherorvr", "rvr+"],
        advertised: Advertised::Prefix("RV-"),
        name: "Sphero RVR",
        pacing_ms: 75,
        processors: 2,
        full_turn_ms: 1500,
        caps: SPHERO
            .with(Caps::AIM)
            .with(Caps::FRONT_LED)
            .with(Caps::TRACKS)
            .with(Caps::COLOR_SENSOR)
            .with(Caps::LIGHT_SENSOR)
            .with(Caps::IR)
            .with(Caps::RAW_MOTORS)
            .with(Caps::TARGETED)
            .with(Caps::STREAM_SERVICE)
            .with(Caps::NO_UNLOCK),
        ..R2D2_ROW
    },
];

impl Model {
    pub const ALL: [Model; 11] = [
        Model::R2D2,
        Model::R2Q5,
        Model::BB9E,
        Model::BB8,
        Model::SprkPlus,
        Model::Ollie,
        Model::Robi42,
        Model::Bolt,
        Model::BoltPlus,
        Model::Mini,
        Model::Rvr,
    ];

    /// The model droidctl assumes when none is named (a simulator without a model, a
    /// placeholder droid before one is chosen).
    pub const DEFAULT: Model = Model::R2D2;

    /// The droid with a serial port: RVR's UART, for a computer riding on it (Sphero's RVR
    /// SDK). What `--serial PORT` drives and `sim --serial` simulates.
    pub const ON_SERIAL: Model = Model::Rvr;

    /// The first model of the table that speaks `protocol`: its family's representative, for
    /// a capture that names only the family.
    pub fn first_speaking(protocol: Protocol) -> Model {
        MODELS
            .iter()
            .find(|s| s.protocol == protocol)
            .map_or(Model::DEFAULT, |s| s.model)
    }

    /// This model's row of [`MODELS`].
    pub const fn spec(self) -> &'static ModelSpec {
        &MODELS[self as usize]
    }

    /// What the model can do.
    pub const fn caps(self) -> Caps {
        self.spec().caps
    }

    /// Whether the model has every capability in `caps`.
    pub const fn has(self, caps: Caps) -> bool {
        self.caps().contains(caps)
    }

    /// Sphero's rolling robots that raw motor power can throw off the floor.
    pub fn hops(self) -> bool {
        self.has(Caps::HOPS)
    }

    /// Recognise a model from its advertised BLE name (`D2-1234` → R2-D2).
    pub fn from_advertised_name(name: &str) -> Option<Model> {
        let n = name.trim();
        MODELS
            .iter()
            .find(|s| match s.advertised {
                Advertised::Prefix(p) => n.starts_with(p),
                Advertised::Name(full) => n == full,
            })
            .map(|s| s.model)
    }

    /// The advertised-name prefix (`None` for Robi 42, which uses a full local name).
    pub fn name_prefix(self) -> Option<&'static str> {
        match self.spec().advertised {
            Advertised::Prefix(p) => Some(p),
            Advertised::Name(_) => None,
        }
    }

    pub fn display_name(self) -> &'static str {
        self.spec().name
    }

    /// Short lower-case id: what the command line takes (`--sim r2d2`), what every document
    /// says, and what captures and JSON outputs name the model with.
    pub fn id(self) -> &'static str {
        self.spec().id
    }

    /// The model an id names: its [`Model::id`], its display name in any case, with or
    /// without `-`, `_` and spaces (`R2-D2`, `Robi 42`), or a short form people type (the
    /// row's aliases).
    pub fn from_id(id: &str) -> Option<Model> {
        let id = id.trim().to_ascii_lowercase().replace(['-', '_', ' '], "");
        MODELS
            .iter()
            .find(|s| {
                s.id == id
                    || s.aliases.contains(&id.as_str())
                    || s.name.to_ascii_lowercase().replace(['-', ' '], "") == id
            })
            .map(|s| s.model)
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
        self.spec().protocol
    }

    /// Minimum interval between writes used by reference clients (`droid-facts.md` §1).
    /// One client uses 12 ms for R2-D2: this is only a default, configurable.
    pub fn write_pacing(self) -> Duration {
        Duration::from_millis(self.spec().pacing_ms)
    }

    /// Whether the droid has R2's legs (stances).
    pub fn has_legs(self) -> bool {
        self.has(Caps::LEGS)
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

    /// A rolling droid with an aim mode (back light, turn in place, set heading 0).
    pub fn can_aim(self) -> bool {
        self.has(Caps::AIM)
    }

    /// The least time a full turn in place takes (spherov2's `spin`).
    pub fn full_turn(self) -> Duration {
        Duration::from_millis(self.spec().full_turn_ms.into())
    }

    /// How many processors take commands: BOLT and RVR have a primary (0x11: power, lights,
    /// RVR's colour sensor) and a secondary (0x12: drive, sensors, BOLT's matrix); the others
    /// one, addressed without a target (`droid-facts.md` §6).
    pub fn processors(self) -> u8 {
        self.spec().processors
    }

    /// Whether every command must name its processor (RVR; spherov2's `_require_target`).
    pub fn requires_target(self) -> bool {
        self.has(Caps::TARGETED)
    }

    /// Takes BOLT's 8×8 frame-player commands: BOLT's matrix, BOLT+'s screen.
    pub fn has_matrix(self) -> bool {
        self.has(Caps::MATRIX)
    }

    /// A screen instead of BOLT's LED matrix (BOLT+): the app shows the frame-player picture
    /// as the screen's, not as 64 LEDs.
    pub fn has_screen(self) -> bool {
        self.has(Caps::SCREEN)
    }

    /// A magnetometer to calibrate to north, and an ambient light sensor (BOLT).
    pub fn has_compass(self) -> bool {
        self.has(Caps::COMPASS)
    }

    /// Driven by its two tracks as well as by heading (RVR's raw motors).
    pub fn has_tracks(self) -> bool {
        self.has(Caps::TRACKS)
    }

    /// Sensors through the streaming service (tokens, periods) rather than masks (RVR).
    pub fn streams_by_service(self) -> bool {
        self.has(Caps::STREAM_SERVICE)
    }

    /// A colour sensor underneath (RVR).
    pub fn has_color_sensor(self) -> bool {
        self.has(Caps::COLOR_SENSOR)
    }

    /// The Star Wars droids' animations and sounds.
    pub fn plays_animations(self) -> bool {
        self.has(Caps::ANIMATIONS)
    }

    /// Whether the droid has R2's rotating dome.
    pub fn has_dome(self) -> bool {
        self.has(Caps::DOME)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_in_all_order() {
        for (i, m) in Model::ALL.into_iter().enumerate() {
            assert_eq!(MODELS[i].model, m);
            assert_eq!(m.spec().model, m);
        }
        let mut ids: Vec<&str> = MODELS.iter().map(|s| s.id).collect();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), MODELS.len(), "ids are unique");
        assert_eq!(
            format!("{:?}", Caps::LEGS | Caps::DOME),
            "Caps(legs | dome)"
        );
    }

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
        assert_eq!(
            Model::from_advertised_name("BP-81C4"),
            Some(Model::BoltPlus)
        );
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
            Err("unknown model \"c3po\": use one of r2d2, r2q5, bb9e, bb8, sprk, ollie, robi, bolt, boltplus, mini, rvr".into())
        );
        assert_eq!(Model::from_id("Robi 42"), Some(Model::Robi42));
        assert_eq!(Model::from_id("sprk+"), Some(Model::SprkPlus));
        assert_eq!(Model::R2D2.write_pacing(), Duration::from_millis(120));
        assert_eq!(Model::from_id("bolt+"), Some(Model::BoltPlus));
        assert_eq!(Model::from_id("Sphero BOLT+"), Some(Model::BoltPlus));
        assert_eq!(Model::from_id("boltplus"), Some(Model::BoltPlus));
        assert_eq!(Model::BoltPlus.write_pacing(), Duration::from_millis(75));
        assert_eq!(Model::from_id("Sphero RVR"), Some(Model::Rvr));
        assert_eq!(Model::from_id("mini"), Some(Model::Mini));
        assert_eq!(Model::Bolt.write_pacing(), Duration::from_millis(75));
        assert_eq!(Model::Rvr.write_pacing(), Duration::from_millis(75));
        assert_eq!(Model::Mini.write_pacing(), Duration::from_millis(120));
    }
}
