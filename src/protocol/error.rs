//! The protocol core's typed errors: a parameter's text that does not parse ([`ParamError`]),
//! a command's parameters that do not fit its schema ([`EncodeError`]) and a name that is not
//! in a catalogue ([`UnknownCommand`]).
//!
//! They are types rather than strings so callers can tell the cases apart (and tests can match
//! them) without reading prose; each one's `Display` is the exact message `packet encode` and
//! the other users print, which the CLI tests and people's scripts read.

use crate::units::{HEAD_MAX_DEG, HEAD_MIN_DEG};
use thiserror::Error;

/// Command-line text that is not a value of a wire type ([`Wire::parse`](super::wire::Wire)).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ParamError {
    #[error("{text:?} is not a number (decimal or 0x hex)")]
    NotUint { text: String },
    #[error("{value} is out of range 0..={max}")]
    UintRange { value: u64, max: u64 },
    #[error("{text:?} is not a number")]
    NotNumber { text: String },
    #[error("{text:?} is not a finite number")]
    NotFinite { text: String },
    #[error("{text:?} is not an integer in -32768..=32767")]
    NotI16 { text: String },
    #[error("{text:?} is not a boolean (true/false, on/off, 1/0)")]
    NotBool { text: String },
    #[error("heading {0} is out of range 0..=359")]
    Heading(u64),
    #[error("dome angle {0} is out of range {min}..={max}", min = HEAD_MIN_DEG, max = HEAD_MAX_DEG)]
    DomeAngle(f32),
    #[error("{0} V is out of range 0..=655.35")]
    Volts(f32),
    #[error("{0} g is out of range")]
    Accel(f32),
    #[error("expected exactly {expected} byte(s), got {got}")]
    ByteCount { expected: usize, got: usize },
    /// The hex parser's own message ([`crate::hex::parse`] reports a string).
    #[error("{0}")]
    Hex(String),
    #[error("text must not contain NUL")]
    TextNul,
    #[error("text longer than {max} bytes")]
    TextBytes { max: usize },
    #[error("{text:?} is not one of: {choices}")]
    NotOneOf { text: String, choices: String },
    #[error("{part:?} is not a drive flag ({description})")]
    NotDriveFlag {
        part: String,
        description: &'static str,
    },
    #[error("{text:?} is not one printable ASCII character")]
    NotPrintableChar { text: String },
    #[error("text must be printable ASCII")]
    NotPrintableText,
    #[error("text longer than {max} characters")]
    TextChars { max: usize },
    #[error("{text:?} is not RRGGBB")]
    NotRgb { text: String },
    #[error("{text:?} is not ID:WIDTH")]
    NotIdWidth { text: String },
    #[error("{text:?} is not major.minor")]
    NotVersion { text: String },
}

/// `--key value` pairs that do not make a command's payload
/// ([`schema::encode_params`](super::schema::encode_params)).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EncodeError {
    #[error("{command} takes no parameters, got --{given}")]
    NoParameters { command: String, given: String },
    #[error("{command} has no parameter --{given} (expected {expected})")]
    UnknownParameter {
        command: String,
        given: String,
        /// The options it has, `--a --b`.
        expected: String,
    },
    #[error("{command} needs --{option} ({description})")]
    Missing {
        command: String,
        option: String,
        description: &'static str,
    },
    #[error("--{option}: {error}")]
    Invalid { option: String, error: ParamError },
}

/// "unknown command X; did you mean …?": a name not in a catalogue, with the catalogue's
/// suggestions; `list` is what follows `droidctl packet list` to see that catalogue
/// (` --protocol v1`).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("unknown command {name:?}; {}", hint(.suggestions, .list))]
pub struct UnknownCommand {
    pub name: String,
    pub suggestions: Vec<String>,
    pub list: &'static str,
}

fn hint(suggestions: &[String], list: &str) -> String {
    if suggestions.is_empty() {
        format!("see `droidctl packet list{list}`")
    } else {
        format!("did you mean {}?", suggestions.join(", "))
    }
}
