//! `droidctl completions SHELL` and `droidctl man`, run as the built binary: every shell's
//! script and the man page name every subcommand. The list comes from the CLI definition
//! itself, so a new subcommand is covered without touching this file.

use clap::CommandFactory;
use droidctl::cli::Cli;
use std::process::{Command, Output};

fn droidctl(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_droidctl"))
        .args(args)
        .output()
        .unwrap()
}

/// Every subcommand path, e.g. `["packet"]`, `["packet", "decode"]`, `["man"]`.
fn subcommands() -> Vec<Vec<String>> {
    fn walk(cmd: &clap::Command, path: &[String], out: &mut Vec<Vec<String>>) {
        for sub in cmd.get_subcommands() {
            let mut p = path.to_vec();
            p.push(sub.get_name().to_string());
            out.push(p.clone());
            walk(sub, &p, out);
        }
    }
    let mut out = Vec::new();
    walk(&Cli::command(), &[], &mut out);
    out
}

#[test]
fn the_subcommand_list_is_complete() {
    let all = subcommands();
    for name in [
        "drive",
        "packet",
        "run",
        "scan",
        "config",
        "completions",
        "man",
    ] {
        assert!(all.contains(&vec![name.to_string()]), "{name}: {all:?}");
    }
    assert!(all.contains(&vec!["packet".to_string(), "decode".to_string()]));
}

#[test]
fn completions_for_every_shell_name_every_subcommand() {
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let out = droidctl(&["completions", shell]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{shell}: {stderr}");
        assert!(stderr.is_empty(), "{shell}: {stderr}");
        let script = String::from_utf8(out.stdout).unwrap();
        assert!(script.contains("droidctl"), "{shell}");
        for path in subcommands() {
            let name = path.last().unwrap();
            assert!(
                script.contains(name.as_str()),
                "{shell} completions do not mention `{}`",
                path.join(" ")
            );
        }
        // Options are completed too.
        assert!(script.contains("scan-timeout"), "{shell}");
    }
}

#[test]
fn bash_completions_offer_the_subcommands_first() {
    let out = droidctl(&["completions", "bash"]);
    let script = String::from_utf8(out.stdout).unwrap();
    // The word list bash offers after `droidctl `: every top-level subcommand.
    let top = script
        .lines()
        .find(|l| l.contains("opts=\"") && l.contains(" drive "))
        .unwrap_or_else(|| panic!("no top-level word list in:\n{script}"));
    for path in subcommands().iter().filter(|p| p.len() == 1) {
        assert!(
            top.split(['"', ' ']).any(|w| w == path[0]),
            "`{}` missing from {top}",
            path[0]
        );
    }
}

#[test]
fn man_prints_a_roff_page_naming_the_subcommands() {
    let out = droidctl(&["man"]);
    assert_eq!(out.status.code(), Some(0));
    let page = String::from_utf8(out.stdout).unwrap();
    assert!(page.contains(".TH droidctl 1"), "{page}");
    for section in [".SH NAME", ".SH SYNOPSIS", ".SH SUBCOMMANDS"] {
        assert!(page.contains(section), "{section}: {page}");
    }
    for path in subcommands().iter().filter(|p| p.len() == 1) {
        // clap_mangen refers to each as `droidctl\-NAME(1)`.
        assert!(
            page.contains(&format!("droidctl\\-{}(1)", path[0])),
            "{}: {page}",
            path[0]
        );
    }
}

#[test]
fn an_unknown_shell_is_a_usage_error() {
    let out = droidctl(&["completions", "tcsh"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("bash"));
}
