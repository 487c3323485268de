//! Command-line interface. Each subcommand lives in its own module; this one only parses and
//! dispatches, and maps errors to exit codes: 2 for bad input (usage, malformed values),
//! 1 for failures at run time.

pub mod packet;
pub mod run;

use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(name = "droidctl", version, about = "Drive Sphero droids from the terminal", long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Decode and encode Sphero API v2 packets.
    #[command(subcommand)]
    Packet(packet::PacketCmd),
    /// Run a mission script against a droid (`--sim` for the simulator, in simulated time).
    Run(run::RunArgs),
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
            status: 2,
            message: message.into(),
        }
    }

    /// A failure at run time: status 1.
    pub fn failure(message: impl Into<String>) -> Self {
        CliError {
            status: 1,
            message: message.into(),
        }
    }
}

/// Run the CLI, returning the process exit status.
pub fn main() -> i32 {
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
        None => {
            use clap::CommandFactory;
            let _ = Cli::command().print_help();
            Ok(0)
        }
    };
    match result {
        Ok(status) => status,
        Err(e) => {
            eprintln!("droidctl: error: {}", e.message);
            e.status
        }
    }
}
