//! The stable-Rust engine: a harness over its seed corpus, then over inputs from the
//! [`Mutator`], for a number of inputs or a length of time. A failing input is written to a
//! file (so it can be replayed, and added to the corpus with its fix) and reported with the
//! panic's message.

use super::Target;
use super::mutate::Mutator;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// What a run did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunStats {
    /// Corpus entries run.
    pub corpus: usize,
    /// Generated inputs run.
    pub generated: u64,
    pub elapsed: Duration,
}

/// How long a run goes on.
#[derive(Debug, Clone, Copy)]
pub enum Budget {
    Inputs(u64),
    Time(Duration),
}

/// The files of a corpus directory, in name order (a missing directory is an empty corpus).
pub fn load_corpus(dir: &Path) -> Vec<Vec<u8>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    paths.retain(|p| p.is_file());
    paths.sort();
    paths.iter().filter_map(|p| std::fs::read(p).ok()).collect()
}

/// Run `input` through the harness; a panic becomes an error naming the file the input was
/// saved to (in `failures`).
pub fn run_one(target: &Target, input: &[u8], failures: &Path) -> Result<(), String> {
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| (target.run)(input)));
    let Err(panic) = outcome else { return Ok(()) };
    let message = panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "a panic without a message".into());
    let _ = std::fs::create_dir_all(failures);
    let file = failures.join(format!("{}-{:016x}", target.name, fnv(input)));
    let saved = match std::fs::write(&file, input) {
        Ok(()) => format!("saved to {}", file.display()),
        Err(e) => format!("could not be saved to {}: {e}", file.display()),
    };
    let shown = if input.len() <= 256 {
        format!(" ({})", crate::hex::compact(input))
    } else {
        String::new()
    };
    Err(format!(
        "{} failed on a {}-byte input{shown}, {saved}: {message}",
        target.name,
        input.len()
    ))
}

/// The corpus, then generated inputs until the budget is spent; stops at the first failure.
pub fn run(
    target: &Target,
    corpus: &[Vec<u8>],
    budget: Budget,
    seed: u64,
    failures: &Path,
) -> Result<RunStats, String> {
    let start = Instant::now();
    for input in corpus {
        run_one(target, input, failures)?;
    }
    let mut mutator = Mutator::new(seed, corpus, target.dictionary);
    let mut generated = 0u64;
    loop {
        let more = match budget {
            Budget::Inputs(n) => generated < n,
            Budget::Time(t) => start.elapsed() < t,
        };
        if !more {
            break;
        }
        let input = mutator.next_input();
        run_one(target, &input, failures)?;
        generated += 1;
    }
    Ok(RunStats {
        corpus: corpus.len(),
        generated,
        elapsed: start.elapsed(),
    })
}

/// FNV-1a, to name a failing input's file by its content.
fn fnv(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}
