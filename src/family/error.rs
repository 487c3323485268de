//! The families' typed errors: a packet that cannot be built by name (`packet encode`,
//! [`NamedError`]) and a reader that cannot be made or input that is not one packet
//! (`packet decode`, [`ReadError`]).
//!
//! Types rather than strings so a caller can tell a usage mistake from another without
//! reading prose; each `Display` is the exact message the CLI prints (its tests read them).

use crate::protocol::error::{EncodeError, ParamError, UnknownCommand};
use thiserror::Error;

/// Why `packet encode NAME --key value …` builds no packet.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum NamedError {
    /// A catalogue command's parameters.
    #[error(transparent)]
    Encode(#[from] EncodeError),
    #[error(transparent)]
    UnknownCommand(#[from] UnknownCommand),
    /// A header or raw option's value (`--seq`, `--did`, `--data` …).
    #[error("--{key}: {error}")]
    Option { key: String, error: ParamError },
    #[error("raw takes --did, --cid and --data, not --{0}")]
    RawParameter(String),
    /// `raw` without `--did` or `--cid`.
    #[error("raw needs --{0}")]
    RawNeeds(&'static str),
    #[error("--no-reset-timeout is an API v1 option (--protocol v1); v2 has no such bit")]
    NoResetTimeoutInV2,
    #[error("--{0}: API v1 packets have no target or source id")]
    NoIdsInV1(String),
    #[error(
        "--values: mask 0x{mask:0w$X} has {bits} bit(s) set, so it needs {bits} value byte(s), got {values}",
        w = .width * 2
    )]
    LedValues {
        mask: u32,
        /// The mask's width in bytes.
        width: usize,
        bits: u32,
        values: usize,
    },
    /// An API v1 packet that cannot be framed (its payload too long for the length byte).
    #[error("{0}")]
    V1Frame(String),
    #[error(
        "RSRCP has no command {0:?}: the Robi 42 sends the handshake and state frames, \
         and is driven by writing one velocity byte (0..=255 = 0..1 forward, \
         characteristic 0x6B2F) and one steering byte (0 left, 128 straight, 255 right, \
         0x3F4A) to the remote-control service 0xBA73; `encode --protocol rsrcp frame` or \
         `handshake` builds test input"
    )]
    NoRsrcpCommand(String),
    #[error("handshake has no parameter --{0} (expected --version --msdt)")]
    HandshakeParameter(String),
    #[error(
        "frame has no parameter --{0} (expected --frame-id --motors --poti \
         --buttons --leds --piezo)"
    )]
    FrameParameter(String),
    /// `--motors L,R` with the reason.
    #[error("--motors: {0} (expected L,R in rad/s)")]
    Motors(MotorsError),
    #[error("--piezo: {0:?} is neither on nor off (expected HZ, HZ,off or off)")]
    PiezoState(String),
    #[error("--{key}: unknown name {name:?} (expected {expected}, none or a number)")]
    UnknownBitName {
        key: String,
        name: String,
        /// The names there are, `a, b, c`.
        expected: String,
    },
}

/// What is wrong with one of `--motors L,R`.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MotorsError {
    #[error("{0:?} is not two numbers")]
    NotTwo(String),
    #[error(transparent)]
    Number(#[from] ParamError),
    #[error("{0} is out of range -300..=300")]
    Range(String),
}

/// Why `packet decode` makes no reader or decodes no packet.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ReadError {
    #[error("--frames needs the masks in effect: --sensor-mask and/or --mask2")]
    FramesWithoutMasks,
    #[error("--request: {0}")]
    Request(UnknownCommand),
    #[error("no bytes to decode")]
    NoBytes,
    /// One packet was asked for (no `--stream`) and the input holds `n` things.
    #[error("the input holds {n} {what}, not one packet; use --stream to decode a byte stream")]
    NotOne { n: usize, what: &'static str },
    #[error(
        "the input holds {0} handshakes or frames, not one; use --stream to decode a byte stream"
    )]
    NotOneFrame(usize),
}
