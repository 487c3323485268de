//! `droidctl completions SHELL`: the script that gives a shell droidctl's completions. The
//! script asks droidctl at each Tab ([`super::complete`]), so the completions come from the
//! one CLI definition ([`super::Cli`]) and never fall behind it, and they know the values:
//! models in a list, command names per family, channel names (the man pages: [`super::man`]).

use super::CliError;
use clap::Args;
use clap_complete::Shell;
use std::io::Write;

#[derive(Debug, Clone, Args)]
pub struct CompletionsArgs {
    /// The shell to complete for. Load the script at the shell's start, e.g. in ~/.bashrc:
    /// `source <(droidctl completions bash)`.
    #[arg(value_enum, value_name = "SHELL")]
    pub shell: Shell,
}

/// Run `droidctl completions SHELL`.
pub fn completions(args: CompletionsArgs, out: &mut dyn Write) -> Result<i32, CliError> {
    let script = super::complete::registration(&args.shell.to_string())?;
    out.write_all(&script)
        .and_then(|()| out.flush())
        .map_err(CliError::output)?;
    Ok(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shell_clap_names_has_a_script() {
        for shell in [
            Shell::Bash,
            Shell::Zsh,
            Shell::Fish,
            Shell::PowerShell,
            Shell::Elvish,
        ] {
            let mut out = Vec::new();
            let args = CompletionsArgs { shell };
            assert_eq!(completions(args, &mut out).ok(), Some(0), "{shell}");
            let script = String::from_utf8(out).unwrap();
            assert!(script.contains("droidctl"), "{shell}");
        }
    }
}
