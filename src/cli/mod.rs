//! Command-line interface. Each subcommand lives in its own module; this one only parses and
//! dispatches, and maps errors to exit codes: 2 for bad input (usage, malformed values),
//! 1 for failures at run time.

pub mod bridge;
pub mod complete;
pub mod completions;
pub mod config_cmd;
pub mod connect;
pub mod drive;
pub mod examples;
pub mod fleet;
mod fleet_run;
pub mod man;
mod mission_run;
pub mod models;
pub mod packet;
pub mod plot;
mod program;
mod program_each;
pub mod replay;
pub mod run;
mod run_output;
pub mod scan;
pub mod serve;
pub mod signals;
pub mod sim;
mod sim_serial;
pub mod term;

use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(
    name = "droidctl",
    version,
    about = "Drive Sphero droids from the terminal",
    long_about = "Drive Sphero droids from the terminal.\n\nWithout a subcommand, opens the full-screen app \
                  (the same as `droidctl drive`). Try `droidctl --sim` to drive the simulated R2-D2.",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub drive: drive::DriveArgs,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Open the full-screen app and drive (the default without a subcommand).
    Drive(drive::DriveArgs),
    /// Decode, encode and list packets: Sphero API v2 and v1, Robi 42 RSRCP.
    #[command(subcommand)]
    Packet(packet::PacketCmd),
    /// Run a mission script or a Sphero Edu JavaScript program (`PROGRAM.js`) against a droid
    /// (`--sim` for the simulator, in simulated time).
    Run(run::RunArgs),
    /// Play a capture back in the app (droidctl's `--record` files and btsnoop logs); `--json`
    /// prints its telemetry samples instead.
    Replay(replay::ReplayArgs),
    /// Draw a run as a PNG or SVG: the path from above with collisions, and chosen channels
    /// against time (from a capture or a `run --json` output).
    Plot(plot::PlotArgs),
    /// List nearby droids over Bluetooth LE, strongest signal first (`--all` for every device).
    Scan(scan::ScanArgs),
    /// Serve simulated droids on D-Bus as BlueZ does (`--bluez`), for droidctl and other
    /// Bluetooth software to find and drive (Linux).
    Sim(sim::SimArgs),
    /// Relay droids to other machines over TCP (spherov2.py's relay protocol): Bluetooth
    /// droids, or simulated ones with `--sim`. Clients use `--remote HOST`.
    Serve(serve::ServeArgs),
    /// Let other programs drive droids through JSON: lines on stdin/stdout (`--stdio`) or
    /// MQTT topics per droid (`--mqtt mqtt://HOST`); see docs/bridge.md.
    Bridge(bridge::BridgeArgs),
    /// Show or create the configuration file.
    #[command(subcommand)]
    Config(config_cmd::ConfigCmd),
    /// List the built-in missions and Sphero Edu programs with the models each is for, or
    /// print one (`droidctl examples square.js > square.js`).
    Examples(examples::ExamplesArgs),
    /// Print shell completions (`droidctl completions bash > …`).
    Completions(completions::CompletionsArgs),
    /// Print a manual page, in roff: droidctl(1), or a subcommand's (`droidctl man packet
    /// decode`); `--dir DIR` writes them all.
    Man(man::ManArgs),
}

/// The runtime for talking to a real droid (or the simulator in real time): two workers,
/// IO (Bluetooth, terminal, signals) and timers.
pub(crate) fn realtime_runtime() -> Result<tokio::runtime::Runtime, CliError> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| CliError::failure(format!("cannot start the runtime: {e}")))
}

/// The exit statuses, with what each means (droidctl(1)'s EXIT STATUS section, and the
/// table in docs/exit-status.md, which a test keeps equal to this).
pub const EXIT_STATUSES: [(i32, &str); 4] = [
    (
        0,
        "Success; also when the reader of the output went away (`droidctl … | head`).",
    ),
    (
        1,
        "A failure at run time: no usable Bluetooth, no droid found or connected, a mission \
         step that failed, an output that could not be written.",
    ),
    (
        2,
        "Bad input: an unknown command or option, a value out of range, malformed hex, a \
         malformed mission script or configuration file, an output file that exists (without \
         --force).",
    ),
    (
        130,
        "Interrupted: Ctrl+c ended `run` after every droid was stopped; \
         SIGTERM gives 143 and SIGHUP 129 (128 + the signal's number). `serve`, `bridge`, \
         `sim` and the app end normally on them (0): that is how they are stopped.",
    ),
];

/// The configuration the app runs with: the file at `path` (a bad one is bad input, with what
/// to do), its theme turned off when `NO_COLOR` asks (<https://no-color.org>).
pub(crate) fn app_config(path: &std::path::Path) -> Result<crate::config::Config, CliError> {
    let mut config = crate::config::Config::load(path).map_err(|e| {
        CliError::usage(format!(
            "{e}\nFix the file (or move it away to use the defaults) and try again."
        ))
    })?;
    let no_color = std::env::var_os("NO_COLOR");
    config.display.theme =
        crate::config::Theme::effective(config.display.theme, no_color.as_deref());
    Ok(config)
}

/// A failure with the exit status it deserves.
#[derive(Debug)]
pub struct CliError {
    pub status: i32,
    pub message: String,
}

impl CliError {
    /// Bad input from the user: status 2.
    pub fn usage(message: impl Into<String>) -> Self {
        CliError {
            status: EXIT_STATUSES[2].0,
            message: message.into(),
        }
    }

    /// An output error: a closed pipe (the reader went away) ends quietly with status 0.
    pub fn output(e: std::io::Error) -> Self {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            return CliError {
                status: 0,
                message: String::new(),
            };
        }
        CliError::failure(format!("cannot write output: {e}"))
    }

    /// A failure at run time: status 1.
    pub fn failure(message: impl Into<String>) -> Self {
        CliError {
            status: EXIT_STATUSES[1].0,
            message: message.into(),
        }
    }
}

/// Run the CLI, returning the process exit status.
pub fn main() -> i32 {
    // A shell asking for completions (`DROIDCTL_COMPLETE=bash droidctl -- …`) is answered
    // here, before anything else is read or written.
    complete::complete_if_asked();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // clap prints help/version to stdout with status 0, usage errors with status 2.
            let _ = e.print();
            return e.exit_code();
        }
    };
    let mut out = std::io::stdout().lock();
    let result = match cli.command {
        Some(Command::Packet(cmd)) => packet::run(cmd, &mut out),
        Some(Command::Run(args)) => {
            drop(out);
            run::run(args)
        }
        Some(Command::Replay(args)) => {
            drop(out);
            replay::run(args)
        }
        Some(Command::Plot(args)) => {
            drop(out);
            plot::run(args)
        }
        Some(Command::Scan(args)) => scan::run(args, &mut out),
        Some(Command::Serve(args)) => {
            drop(out);
            serve::run(args)
        }
        Some(Command::Bridge(args)) => {
            drop(out);
            bridge::run(args)
        }
        Some(Command::Sim(args)) => {
            drop(out);
            sim::run(args)
        }
        Some(Command::Config(cmd)) => config_cmd::run(cmd, &mut out),
        Some(Command::Examples(args)) => examples::run(args, &mut out),
        Some(Command::Completions(args)) => completions::completions(args, &mut out),
        Some(Command::Man(args)) => man::run(args, &mut out),
        Some(Command::Drive(args)) => {
            drop(out);
            drive::run(args)
        }
        None => {
            drop(out);
            drive::run(cli.drive)
        }
    };
    match result {
        Ok(status) => status,
        // `droidctl packet list | head`: the reader went away; that is not an error.
        Err(e) if e.status == 0 => 0,
        Err(e) => {
            eprintln!("droidctl: error: {}", e.message);
            // A run ended by Ctrl+c (or SIGTERM, SIGHUP) has stopped its droids by now; its
            // status says what ended it (130 after Ctrl+c), as shells expect.
            match signals::interrupted_status() {
                Some(s) if e.status == EXIT_STATUSES[1].0 => s,
                _ => e.status,
            }
        }
    }
}
