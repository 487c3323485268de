//! The v2 FLAGS byte (`sphero-v2-api.md`, "Flags").

use bitflags::bitflags;

bitflags! {
    /// Packet flags. Bit 7 announces one extended-flags byte after FLAGS.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct Flags: u8 {
        const IS_RESPONSE = 0x01;
        const REQUESTS_RESPONSE = 0x02;
        const REQUESTS_ONLY_ERROR_RESPONSE = 0x04;
        const IS_ACTIVITY = 0x08;
        const HAS_TARGET_ID = 0x10;
        const HAS_SOURCE_ID = 0x20;
        const UNUSED = 0x40;
        const EXTENDED_FLAGS = 0x80;
    }
}

impl Flags {
    /// What droidctl sends by default: requests-response | is-activity (0x0A), the
    /// combination every reference client uses.
    pub const DEFAULT_COMMAND: Flags = Flags::REQUESTS_RESPONSE.union(Flags::IS_ACTIVITY);

    /// The flag names in snake case, lowest bit first, for humans and JSON.
    pub fn names(self) -> Vec<&'static str> {
        self.name_iter().collect()
    }

    /// [`Flags::names`] without collecting them (JSON output writes them as they come).
    pub fn name_iter(self) -> impl Iterator<Item = &'static str> {
        [
            (Flags::IS_RESPONSE, "is_response"),
            (Flags::REQUESTS_RESPONSE, "requests_response"),
            (
                Flags::REQUESTS_ONLY_ERROR_RESPONSE,
                "requests_only_error_response",
            ),
            (Flags::IS_ACTIVITY, "is_activity"),
            (Flags::HAS_TARGET_ID, "has_target_id"),
            (Flags::HAS_SOURCE_ID, "has_source_id"),
            (Flags::UNUSED, "unused_bit6"),
            (Flags::EXTENDED_FLAGS, "extended_flags"),
        ]
        .into_iter()
        .filter(move |(bit, _)| self.contains(*bit))
        .map(|(_, name)| name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_command_is_0x0a() {
        assert_eq!(Flags::DEFAULT_COMMAND.bits(), 0x0A);
        assert_eq!(
            Flags::from_bits_retain(0x3A).names(),
            vec![
                "requests_response",
                "is_activity",
                "has_target_id",
                "has_source_id"
            ]
        );
    }
}
