//! Response error codes (`sphero-v2-api.md`, "Error Codes").

use std::fmt;

/// The ERR byte of a response. Codes the spec leaves unused are kept, not lost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorCode {
    Success,
    BadDeviceId,
    BadCommandId,
    NotYetImplemented,
    CommandIsRestricted,
    BadDataLength,
    CommandFailed,
    BadParameterValue,
    Busy,
    BadTargetId,
    TargetUnavailable,
    Unknown(u8),
}

impl ErrorCode {
    pub fn from_byte(b: u8) -> Self {
        use ErrorCode::*;
        match b {
            0x00 => Success,
            0x01 => BadDeviceId,
            0x02 => BadCommandId,
            0x03 => NotYetImplemented,
            0x04 => CommandIsRestricted,
            0x05 => BadDataLength,
            0x06 => CommandFailed,
            0x07 => BadParameterValue,
            0x08 => Busy,
            0x09 => BadTargetId,
            0x0A => TargetUnavailable,
            other => Unknown(other),
        }
    }

    pub fn to_byte(self) -> u8 {
        use ErrorCode::*;
        match self {
            Success => 0x00,
            BadDeviceId => 0x01,
            BadCommandId => 0x02,
            NotYetImplemented => 0x03,
            CommandIsRestricted => 0x04,
            BadDataLength => 0x05,
            CommandFailed => 0x06,
            BadParameterValue => 0x07,
            Busy => 0x08,
            BadTargetId => 0x09,
            TargetUnavailable => 0x0A,
            Unknown(b) => b,
        }
    }

    pub fn is_success(self) -> bool {
        self == ErrorCode::Success
    }

    /// The spec's snake-case name (`bad_device_id`), or `unknown_0xNN`.
    pub fn name(self) -> String {
        self.name_cow().into_owned()
    }

    /// [`ErrorCode::name`], allocating only for an unknown code (JSON output, per packet).
    pub fn name_cow(self) -> std::borrow::Cow<'static, str> {
        use ErrorCode::*;
        std::borrow::Cow::Borrowed(match self {
            Success => "success",
            BadDeviceId => "bad_device_id",
            BadCommandId => "bad_command_id",
            NotYetImplemented => "not_yet_implemented",
            CommandIsRestricted => "command_is_restricted",
            BadDataLength => "bad_data_length",
            CommandFailed => "command_failed",
            BadParameterValue => "bad_parameter_value",
            Busy => "busy",
            BadTargetId => "bad_target_id",
            TargetUnavailable => "target_unavailable",
            Unknown(b) => return std::borrow::Cow::Owned(format!("unknown_0x{b:02x}")),
        })
    }

    /// A sentence for people.
    pub fn message(self) -> String {
        use ErrorCode::*;
        match self {
            Success => "command executed successfully".into(),
            BadDeviceId => "device ID is invalid (or invisible with current permissions)".into(),
            BadCommandId => "command ID is invalid (or invisible with current permissions)".into(),
            NotYetImplemented => "command is not yet implemented or has a null handler".into(),
            CommandIsRestricted => "command cannot be executed in the current state or mode".into(),
            BadDataLength => "payload data length is invalid".into(),
            CommandFailed => "command failed to execute for a command-specific reason".into(),
            BadParameterValue => "at least one data parameter is invalid".into(),
            Busy => "the operation is already in progress or the module is busy".into(),
            BadTargetId => "target does not exist".into(),
            TargetUnavailable => "target exists but is unavailable (asleep or disconnected)".into(),
            Unknown(b) => format!("unknown error code 0x{b:02X}"),
        }
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.name(), self.message())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_byte_round_trips() {
        for b in 0..=255u8 {
            assert_eq!(ErrorCode::from_byte(b).to_byte(), b);
        }
        assert_eq!(ErrorCode::from_byte(5), ErrorCode::BadDataLength);
        assert_eq!(ErrorCode::from_byte(0x0B), ErrorCode::Unknown(0x0B));
        assert_eq!(ErrorCode::from_byte(0x0B).name(), "unknown_0x0b");
        assert!(ErrorCode::TargetUnavailable.message().contains("asleep"));
    }
}
