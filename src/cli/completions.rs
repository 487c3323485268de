//! `droidctl completions SHELL`: shell completions, generated from the one CLI definition
//! ([`super::Cli`]), so they never fall behind it (the man pages: [`super::man`]).

use super::{Cli, CliError};
use clap::{Args, CommandFactory};
use clap_complete::Shell;
use std::io::Write;

#[derive(Debug, Clone, Args)]
pub struct CompletionsArgs {
    /// The shell to complete for.
    #[arg(value_enum, value_name = "SHELL")]
    pub shell: Shell,
}

/// The completion script for `shell`.
pub fn completion_script(shell: Shell) -> Vec<u8> {
    let mut cmd = Cli::command();
    let mut buf = Vec::new();
    clap_complete::generate(shell, &mut cmd, "droidctl", &mut buf);
    buf
}

/// Run `droidctl completions SHELL`.
pub fn completions(args: CompletionsArgs, out: &mut dyn Write) -> Result<i32, CliError> {
    // Rendered in memory first: the generators panic on a write error, such as a closed pipe.
    out.write_all(&completion_script(args.shell))
        .and_then(|()| out.flush())
        .map_err(CliError::output)?;
    Ok(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shell_gets_a_script_naming_the_program() {
        for shell in [
            Shell::Bash,
            Shell::Zsh,
            Shell::Fish,
            Shell::PowerShell,
            Shell::Elvish,
        ] {
            let script = String::from_utf8(completion_script(shell)).unwrap();
            assert!(script.contains("droidctl"), "{shell}");
            assert!(script.contains("completions"), "{shell}");
        }
    }
}
