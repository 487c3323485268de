//! Sphero Edu JavaScript programs (`droidctl run PROGRAM.js`, `droidctl --program
//! PROGRAM.js`): the programs people write in Sphero's own app, run on any droid droidctl
//! drives, real or simulated, alone or in a fleet, under the operator's emergency stop.
//!
//! - [`calls`]: the API's calls and the robots each applies to (one table: the engine's "not
//!   on this robot" errors and the docs' list come from it);
//! - [`api`]: what each call does, sans-IO, as spherov2.py's `SpheroEduAPI` does it;
//! - [`engine`]: the JavaScript engine, on a thread of its own, driven in turns;
//! - [`child`]: the engine's own process (droidctl started again), bounded in stack, memory
//!   and time; [`wire`]: the turns across its pipe; [`host`]: droidctl's side of it, which
//!   stops the droid whatever happens to the child;
//! - [`sounds`]: Sphero Edu's sounds on droids with a speaker, and said on the others;
//! - [`names`]: the names a program calls, checked before anything is sent;
//! - [`infrared`]: the infrared calls as BOLT and RVR each take them on the wire;
//! - [`run`]: a program on one droid, on droidctl's clock; [`ready`]: when it may start;
//! - [`timeline`]: a timed call's steps, made when due (a few numbers however long);
//! - [`schedule`]: the timed calls pending, by when each is next due;
//! - [`progress`]: what a running program is doing, for a screen;
//! - [`probe`]: a program run for its calls alone, and the bounds each call's effect keeps
//!   (for tests and the fuzz target `edu`).
//!
//! The engine is Boa (`boa_engine`), not QuickJS (`rquickjs`): Boa is pure Rust, so the
//! Windows and macOS cross checks build it with no C compiler (rquickjs-sys compiles QuickJS's
//! C in its build script, which fails there), and its promises and job queue are plain Rust
//! to drive from droidctl's clock. Built without default features (no Temporal, no ICU data)
//! it is still the biggest crate in the tree: a cold release build of `boa_engine` alone took
//! 7.5 min on the shared two-core development machine (other builds running; measured while
//! choosing, issue 29). What it lacks next to QuickJS (speed) matters little to programs that
//! mostly wait for the robot.
//!
//! Layering: above missions and fleets (a program reuses a mission's telemetry, samples and
//! summary), below the app and the CLI.

pub mod api;
pub mod calls;
pub mod child;
pub mod engine;
pub mod host;
#[cfg(test)]
mod hostile;
pub mod infrared;
mod names;
pub mod probe;
pub mod progress;
pub mod ready;
pub mod run;
pub mod schedule;
pub mod sounds;
mod syntax;
pub mod timeline;
mod unhandled;
pub mod wire;

pub use host::{CheckError, EngineOptions};
pub use run::{Program, ProgramOptions, run};

/// Whether the file at `path` holding `text` is a Sphero Edu program rather than a mission
/// script: a `.js` name, or a `startProgram` function in it.
pub fn is_program(path: &std::path::Path, text: &str) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("js") || e.eq_ignore_ascii_case("mjs"))
        || (text.contains("function startProgram") && text.contains('('))
}
