//! `droidctl packet decode --btsnoop FILE`.

use super::{CliError, DecodeArgs};
use std::io::Write;

pub(super) fn decode(
    _path: &str,
    _args: DecodeArgs,
    _handles: &[u16],
    _json: bool,
    _summary: bool,
    _out: &mut dyn Write,
) -> Result<i32, CliError> {
    Err(CliError::failure("not yet"))
}
