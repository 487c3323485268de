//! Where `droidctl run` writes, one or several droids (issue 27 points 1 and 2): its lines on
//! stdout and the `--csv` file. Every output the user asked for is a promise: kept, or an
//! error that says so. A closed stdout (`run … | head -1`) ends the mission quietly with the
//! droid stopped; any other failure of stdout (a full disk) ends it too, with one line and
//! exit 1; a `--csv` file that could not be written fully is exit 1 once the mission is over.
//! Nothing here panics: stderr is written with `writeln!`, its failures ignored.

use super::CliError;
use crate::mission::Sample;
use crate::mission::csv::SampleFiles;
use crate::sync::lock;
use std::io::Write;
use std::sync::Mutex;

/// A mission's outputs.
pub struct RunOutput {
    /// Why stdout failed, when it did (nothing more is written to it).
    stdout_error: Mutex<Option<std::io::Error>>,
    /// The `--csv` file, until it fails.
    csv: Mutex<Option<SampleFiles>>,
    /// Why the `--csv` file is incomplete.
    csv_error: Mutex<Option<String>>,
    /// Told when stdout fails: the mission ends.
    gone: tokio::sync::Notify,
}

/// A line on stderr; a failure to write it is ignored (there is nowhere left to say it).
pub fn note(text: std::fmt::Arguments) {
    let _ = writeln!(std::io::stderr(), "{text}");
}

impl RunOutput {
    pub fn new(csv: Option<SampleFiles>) -> RunOutput {
        RunOutput {
            stdout_error: Mutex::new(None),
            csv: Mutex::new(csv),
            csv_error: Mutex::new(None),
            gone: tokio::sync::Notify::new(),
        }
    }

    /// Write to stdout with `f` (nothing once stdout has failed); a failure ends the mission.
    pub fn stdout(&self, f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) {
        let mut failed = lock(&self.stdout_error);
        if failed.is_some() {
            return;
        }
        let mut out = std::io::stdout().lock();
        if let Err(e) = f(&mut out).and_then(|_| out.flush()) {
            *failed = Some(e);
            // A permit is stored: `closed` returns even when it starts waiting later.
            self.gone.notify_one();
        }
    }

    /// Whether stdout has failed.
    pub fn stdout_failed(&self) -> bool {
        lock(&self.stdout_error).is_some()
    }

    /// A sample into the `--csv` file (`droid` names it in a fleet's file). The first failure
    /// is said at once, no more rows are written, and the run's exit status will be 1.
    pub fn csv_sample(&self, droid: Option<&str>, s: &Sample) {
        let mut files = lock(&self.csv);
        let Some(w) = files.as_mut() else {
            return;
        };
        let r = match droid {
            Some(d) => w.write_for(d, s),
            None => w.write(s),
        };
        if let Err(e) = r {
            *files = None;
            self.csv_failed(e);
        }
    }

    fn csv_failed(&self, e: std::io::Error) {
        // Said at once (a real mission may go on for long); the exit status says it again.
        note(format_args!(
            "droidctl: --csv: {e}; no more rows are written"
        ));
        *lock(&self.csv_error) = Some(format!("--csv: the file is incomplete ({e})"));
    }

    /// Resolves once stdout has failed (the mission ends: the droid is stopped).
    pub async fn closed(&self) {
        if self.stdout_failed() {
            return;
        }
        self.gone.notified().await;
    }

    /// Flush the `--csv` file (a failure makes the run fail).
    pub fn flush_csv(&self) {
        let mut files = lock(&self.csv);
        if let Some(w) = files.as_mut()
            && let Err(e) = w.flush()
        {
            *files = None;
            self.csv_failed(e);
        }
    }

    /// The run's end: the exit status the outputs call for. A closed stdout is a quiet end
    /// (status 0, nothing said); any other failure of stdout or of the `--csv` file is
    /// status 1 with one line.
    pub fn result(&self) -> Result<(), CliError> {
        self.flush_csv();
        if let Some(e) = lock(&self.stdout_error).as_ref() {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                return Err(CliError {
                    status: 0,
                    message: String::new(),
                });
            }
            return Err(CliError::failure(format!(
                "cannot write the output: {e}; the run was ended and the droid stopped"
            )));
        }
        match lock(&self.csv_error).as_ref() {
            Some(m) => Err(CliError::failure(m.clone())),
            None => Ok(()),
        }
    }
}

/// A run (mission or program) interrupted because its output went away.
pub const OUTPUT_GONE: &str = "the output went away: run ended, the droid was stopped";

/// A JSON line naming its droid first (`run --json` and `replay --json` of a fleet).
#[derive(serde::Serialize)]
pub(super) struct Tagged<'a, T: serde::Serialize> {
    pub droid: &'a str,
    #[serde(flatten)]
    pub inner: &'a T,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_csv_is_a_failure_of_the_run() {
        let files = SampleFiles::create(Some(std::path::Path::new("/dev/full")), None, false);
        // The header fits the buffer: the failure comes with the rows or the flush.
        let Ok(files) = files else {
            return;
        };
        let out = RunOutput::new(Some(files));
        let s = crate::mission::sample_of(&crate::telemetry::Telemetry::default(), 0);
        for _ in 0..1000 {
            out.csv_sample(None, &s);
        }
        let e = out.result().unwrap_err();
        assert_eq!(e.status, 1);
        assert!(e.message.contains("--csv"), "{}", e.message);
    }
}
