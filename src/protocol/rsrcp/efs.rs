//! The enabled feature set (EFS): which feature payloads a frame carries, and how long they are.
//!
//! The spec numbers the bits from the MSB ("bit position 0 (MSB) = voltages"); the bit values
//! below are `droid-facts.md` §5's, which state the same thing as masks. Payloads follow the
//! header in the spec's listing order, which is the same as highest bit first
//! (`robi-rsrcp.md`, "Frame Message Format": "in the order they are defined above").

use bitflags::bitflags;

bitflags! {
    /// The 16-bit EFS of a frame. Unknown (reserved) bits are kept, never dropped: see
    /// [`Efs::RESERVED_MASK`].
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct Efs: u16 {
        const VOLTAGES = 0x8000;
        const MOTORS = 0x4000;
        const GYRO = 0x2000;
        const ACCEL = 0x1000;
        const LASER = 0x0800;
        const IR = 0x0400;
        const POTI = 0x0200;
        const BUTTONS = 0x0100;
        const LEDS = 0x0080;
        const PIEZO = 0x0040;
        const LCD = 0x0020;
    }
}

impl Efs {
    /// Bits the spec does not assign (`droid-facts.md` §5: "0x001F reserved"). They sit after
    /// LCD in wire order, so every defined feature can still be read when one is set, but the
    /// frame cannot be framed past them: their payload size is unknown.
    pub const RESERVED_MASK: u16 = 0x001F;

    /// The features with a defined payload size (motors 4, poti 1, buttons 1, LEDs 1,
    /// piezo 2; `droid-facts.md` §5).
    pub const SIZED: Efs = Efs::MOTORS
        .union(Efs::POTI)
        .union(Efs::BUTTONS)
        .union(Efs::LEDS)
        .union(Efs::PIEZO);

    /// The features the spec leaves "[Yet to be defined]": a frame enabling one cannot be
    /// decoded past it.
    pub const UNSIZED: Efs = Efs::VOLTAGES
        .union(Efs::GYRO)
        .union(Efs::ACCEL)
        .union(Efs::LASER)
        .union(Efs::IR)
        .union(Efs::LCD);

    /// What the Robi42Lib firmware sends today: motors, poti and buttons
    /// (`droid-facts.md` §5).
    pub const FIRMWARE: Efs = Efs::MOTORS.union(Efs::POTI).union(Efs::BUTTONS);

    /// The reserved bits that are set.
    pub fn reserved(self) -> u16 {
        self.bits() & Self::RESERVED_MASK
    }

    /// The enabled features in wire order.
    pub fn features(self) -> impl Iterator<Item = Feature> {
        Feature::ALL
            .into_iter()
            .filter(move |f| self.contains(f.flag()))
    }

    /// Names of the enabled features in wire order (reserved bits have no name; they show in
    /// the raw number).
    pub fn names(self) -> Vec<&'static str> {
        self.features().map(Feature::name).collect()
    }

    /// The first enabled feature without a defined size, if any.
    pub fn first_unsized(self) -> Option<Feature> {
        self.features().find(|f| f.size().is_none())
    }
}

/// One feature of the EFS, in wire order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Feature {
    Voltages,
    Motors,
    Gyro,
    Accel,
    Laser,
    Ir,
    Poti,
    Buttons,
    Leds,
    Piezo,
    Lcd,
}

impl Feature {
    /// Every feature in wire order (highest EFS bit first).
    pub const ALL: [Feature; 11] = [
        Feature::Voltages,
        Feature::Motors,
        Feature::Gyro,
        Feature::Accel,
        Feature::Laser,
        Feature::Ir,
        Feature::Poti,
        Feature::Buttons,
        Feature::Leds,
        Feature::Piezo,
        Feature::Lcd,
    ];

    pub fn flag(self) -> Efs {
        match self {
            Feature::Voltages => Efs::VOLTAGES,
            Feature::Motors => Efs::MOTORS,
            Feature::Gyro => Efs::GYRO,
            Feature::Accel => Efs::ACCEL,
            Feature::Laser => Efs::LASER,
            Feature::Ir => Efs::IR,
            Feature::Poti => Efs::POTI,
            Feature::Buttons => Efs::BUTTONS,
            Feature::Leds => Efs::LEDS,
            Feature::Piezo => Efs::PIEZO,
            Feature::Lcd => Efs::LCD,
        }
    }

    /// Snake-case name for humans and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Feature::Voltages => "voltages",
            Feature::Motors => "motors",
            Feature::Gyro => "gyro",
            Feature::Accel => "accel",
            Feature::Laser => "laser",
            Feature::Ir => "ir",
            Feature::Poti => "poti",
            Feature::Buttons => "buttons",
            Feature::Leds => "leds",
            Feature::Piezo => "piezo",
            Feature::Lcd => "lcd",
        }
    }

    /// Payload size in bytes, `None` where the spec has "[Yet to be defined]". Guessing a size
    /// would silently misread every later feature, so there is no fallback.
    pub fn size(self) -> Option<usize> {
        match self {
            Feature::Motors => Some(4),
            Feature::Poti | Feature::Buttons | Feature::Leds => Some(1),
            Feature::Piezo => Some(2),
            Feature::Voltages
            | Feature::Gyro
            | Feature::Accel
            | Feature::Laser
            | Feature::Ir
            | Feature::Lcd => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_are_msb_first_in_wire_order() {
        let bits: Vec<u16> = Feature::ALL.iter().map(|f| f.flag().bits()).collect();
        let expected: Vec<u16> = (0..11).map(|i| 0x8000 >> i).collect();
        assert_eq!(bits, expected);
        assert_eq!(Efs::all().bits() | Efs::RESERVED_MASK, 0xFFFF);
        assert_eq!(Efs::SIZED | Efs::UNSIZED, Efs::all());
        assert!((Efs::SIZED & Efs::UNSIZED).is_empty());
    }

    #[test]
    fn names_and_sizes() {
        assert_eq!(Efs::FIRMWARE.bits(), 0x4300);
        assert_eq!(Efs::FIRMWARE.names(), vec!["motors", "poti", "buttons"]);
        assert_eq!(
            Efs::from_bits_retain(0x6300).first_unsized(),
            Some(Feature::Gyro)
        );
        assert_eq!(Efs::from_bits_retain(0x001F).names(), Vec::<&str>::new());
        assert_eq!(Efs::from_bits_retain(0x0021).reserved(), 0x01);
        let sized: usize = Efs::SIZED.features().filter_map(Feature::size).sum();
        assert_eq!(sized, 9);
    }
}
