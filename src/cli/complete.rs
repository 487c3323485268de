//! Shell completions that know the values: `--sim r2d2,b<Tab>` offers the models that start
//! with `b` after the comma, `packet encode <Tab>` the command names of the family chosen with
//! `--protocol` (v2 without it), `plot --channels speed,<Tab>` the channel names.
//!
//! Static completion scripts cannot see inside a comma-separated value, so the shell asks
//! droidctl itself: `droidctl completions SHELL` prints a short script that calls
//! `DROIDCTL_COMPLETE=SHELL droidctl -- WORDS…` at each Tab, and [`complete_if_asked`],
//! the first thing [`super::main`] does, answers it from the one CLI definition
//! ([`super::Cli`]) and the value completers below (clap_complete's engine, as jj does).

use super::{Cli, CliError};
use crate::model::Model;
use clap::CommandFactory;
use clap_complete::engine::CompletionCandidate;
use clap_complete::env::{CompleteEnv, Shells};
use std::ffi::OsStr;

/// The environment variable that asks droidctl for completions instead of running: its own
/// name, so that a `COMPLETE` set for another program never turns droidctl into a completer.
pub const VAR: &str = "DROIDCTL_COMPLETE";

/// The shells the scripts are written for.
pub const SHELLS: [&str; 5] = ["bash", "zsh", "fish", "powershell", "elvish"];

/// Answer the shell and exit when it asked for completions (`DROIDCTL_COMPLETE` is set);
/// otherwise return at once.
pub fn complete_if_asked() {
    CompleteEnv::with_factory(Cli::command)
        .var(VAR)
        .bin("droidctl")
        .complete();
}

/// The script that registers droidctl's completions in `shell`, calling `droidctl` from the
/// PATH at each Tab.
pub fn registration(shell: &str) -> Result<Vec<u8>, CliError> {
    let shells = Shells::builtins();
    let completer = shells.completer(shell).ok_or_else(|| {
        CliError::usage(format!(
            "no completions for {shell:?}: use {}",
            SHELLS.join(", ")
        ))
    })?;
    let mut buf = Vec::new();
    completer
        .write_registration(VAR, "droidctl", "droidctl", "droidctl", &mut buf)
        .map_err(|e| CliError::failure(format!("cannot write the script: {e}")))?;
    Ok(buf)
}

/// `--sim MODEL[,MODEL…]`: the models whose id starts with what follows the last comma, each
/// after the models already typed.
pub fn model_list(current: &OsStr) -> Vec<CompletionCandidate> {
    let current = current.to_string_lossy();
    let (done, part) = match current.rfind(',') {
        Some(i) => current.split_at(i + 1),
        None => ("", current.as_ref()),
    };
    let part = part.to_ascii_lowercase();
    Model::ALL
        .into_iter()
        .filter(|m| m.id().starts_with(&part))
        .map(|m| {
            CompletionCandidate::new(format!("{done}{}", m.id()))
                .help(Some(m.display_name().into()))
        })
        .collect()
}

/// `plot --channels`: every channel name (the engine completes after the last comma, as the
/// argument is comma-delimited).
pub fn channels() -> Vec<CompletionCandidate> {
    crate::telemetry::history::Channel::ALL
        .iter()
        .map(|c| CompletionCandidate::new(c.name()))
        .collect()
}

/// `packet encode NAME`: the names the family given with `--protocol` takes (v2 without it),
/// with what each is. The shell passes the whole command line to droidctl, so `--protocol`
/// is read from it, before or after NAME.
pub fn encode_names(current: &OsStr) -> Vec<CompletionCandidate> {
    let words: Vec<String> = std::env::args_os()
        .map(|w| w.to_string_lossy().into_owned())
        .collect();
    encode_names_for(&words, &current.to_string_lossy())
}

fn encode_names_for(words: &[String], current: &str) -> Vec<CompletionCandidate> {
    let protocol = words.iter().enumerate().find_map(|(i, w)| {
        w.strip_prefix("--protocol=")
            .map(str::to_string)
            .or_else(|| (w == "--protocol").then(|| words.get(i + 1).cloned().unwrap_or_default()))
    });
    let family = protocol
        .as_deref()
        .and_then(crate::family::by_name)
        .unwrap_or(crate::family::all()[0]);
    family
        .encode_names()
        .into_iter()
        .filter(|(n, _)| n.starts_with(current))
        .map(|(n, what)| CompletionCandidate::new(n).help(Some(what.into())))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::OsString;

    /// What the engine offers for the last word of `line`, as the shell would show it.
    fn offered(line: &str) -> Vec<String> {
        let mut args: Vec<OsString> = line.split(' ').map(OsString::from).collect();
        if line.ends_with(' ') {
            args.pop();
            args.push(OsString::new());
        }
        let index = args.len() - 1;
        let mut cmd = Cli::command();
        clap_complete::engine::complete(&mut cmd, args, index, None)
            .unwrap_or_default()
            .into_iter()
            .map(|c| c.get_value().to_string_lossy().into_owned())
            .collect()
    }

    #[test]
    fn a_list_of_models_completes_after_its_last_comma() {
        assert_eq!(
            offered("droidctl --sim r2d2,b"),
            ["r2d2,bb9e", "r2d2,bb8", "r2d2,bolt", "r2d2,boltplus"]
        );
        assert_eq!(offered("droidctl run tour.txt --sim bb8,r"), {
            ["bb8,r2d2", "bb8,r2q5", "bb8,robi", "bb8,rvr"]
        });
        assert_eq!(offered("droidctl bridge --stdio --sim m"), ["mini"]);
        // `--sim` may go without a value: the subcommands are offered too.
        let after = offered("droidctl --sim ");
        assert!(
            Model::ALL.iter().all(|m| after.iter().any(|c| c == m.id())),
            "{after:?}"
        );
        // One model: its own parser's values.
        assert_eq!(offered("droidctl sim --bluez r2"), ["r2d2", "r2q5"]);
    }

    #[test]
    fn channels_complete_after_a_comma() {
        let got = offered("droidctl plot run.json --channels speed,gy");
        assert!(!got.is_empty());
        assert!(got.iter().all(|c| c.starts_with("speed,gy")), "{got:?}");
        assert!(got.contains(&"speed,gyro_z".to_string()), "{got:?}");
    }

    #[test]
    fn encode_names_follow_the_family() {
        let names = |words: &[&str], cur: &str| -> Vec<String> {
            let words: Vec<String> = words.iter().map(|w| w.to_string()).collect();
            encode_names_for(&words, cur)
                .into_iter()
                .map(|c| c.get_value().to_string_lossy().into_owned())
                .collect()
        };
        let v2 = names(&["droidctl", "packet", "encode"], "drive-w");
        assert_eq!(v2, ["drive-with-heading"]);
        assert!(names(&["droidctl", "packet", "encode"], "").contains(&"raw".to_string()));
        let robi = names(&["droidctl", "packet", "encode", "--protocol", "rsrcp"], "");
        assert_eq!(robi, ["frame", "handshake"]);
        let v1 = names(&["droidctl", "packet", "encode", "--protocol=v1"], "roll");
        assert_eq!(v1, ["roll"]);
        // Through the engine: the command's NAME takes them.
        assert!(offered("droidctl packet encode wa").contains(&"wake".to_string()));
    }

    #[test]
    fn every_shell_gets_a_script_that_calls_droidctl_back() {
        for shell in SHELLS {
            let script = String::from_utf8(registration(shell).unwrap()).unwrap();
            assert!(script.contains("droidctl"), "{shell}");
            assert!(script.contains(VAR), "{shell}: {script}");
        }
        assert_eq!(registration("tcsh").unwrap_err().status, 2);
    }
}
