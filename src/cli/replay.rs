//! `--record FILE` (on `drive` and `run`) and `droidctl replay FILE`.

use super::CliError;
use crate::link::record::Recorder;
use clap::Args;
use std::path::PathBuf;

/// `--record FILE [--force]`.
#[derive(Debug, Clone, Default, Args)]
pub struct RecordArgs {
    /// Record everything over the link to FILE, in droidctl's capture format (see README,
    /// "Captures"). An existing FILE is kept unless --force.
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// With --record: replace FILE if it exists.
    #[arg(long, requires = "record")]
    pub force: bool,
}

impl RecordArgs {
    /// Create the capture file now, so a refusal comes before anything connects.
    pub fn open(&self) -> Result<Option<Recorder>, CliError> {
        self.record
            .as_deref()
            .map(|p| Recorder::create(p, self.force).map_err(CliError::usage))
            .transpose()
    }
}

/// Finish a recording; a failure to write it is reported, not fatal to the exit status.
pub fn finish(rec: Option<&Recorder>) {
    if let Some(r) = rec
        && let Err(e) = r.finish()
    {
        eprintln!("droidctl: {e}");
    }
}
