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
        "examples",
    ] {
        assert!(all.contains(&vec![name.to_string()]), "{name}: {all:?}");
    }
    assert!(all.contains(&vec!["packet".to_string(), "decode".to_string()]));
}

/// What bash offers for the last word of `words` with droidctl's script loaded, run in `dir`:
/// the real shell calling the real binary, as at a prompt.
pub fn bash_offers(words: &[&str], dir: &std::path::Path) -> Vec<String> {
    let bin = std::path::Path::new(env!("CARGO_BIN_EXE_droidctl"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let quoted: Vec<String> = words.iter().map(|w| format!("'{w}'")).collect();
    let script = format!(
        "source <(droidctl completions bash)\n\
         COMP_WORDS=({words})\nCOMP_CWORD={cword}\nCOMP_TYPE=9\n\
         _clap_complete_droidctl droidctl {last}\n\
         printf '%s\\n' \"${{COMPREPLY[@]}}\"\n",
        words = quoted.join(" "),
        cword = words.len() - 1,
        last = quoted.last().unwrap(),
    );
    let out = Command::new("bash")
        .arg("-c")
        .arg(script)
        .current_dir(dir)
        .env("PATH", path)
        .output()
        .expect("bash runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.is_empty())
        .map(|l| l.trim_end().to_string())
        .collect()
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("droidctl-compl-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn every_shell_gets_a_script_that_asks_droidctl() {
    for shell in ["bash", "zsh", "fish", "powershell", "elvish"] {
        let out = droidctl(&["completions", shell]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{shell}: {stderr}");
        assert!(stderr.is_empty(), "{shell}: {stderr}");
        let script = String::from_utf8(out.stdout).unwrap();
        assert!(script.contains("droidctl"), "{shell}");
        assert!(script.contains("DROIDCTL_COMPLETE"), "{shell}: {script}");
    }
}

#[test]
fn bash_offers_every_subcommand_and_option() {
    let dir = scratch("subcommands");
    let top = bash_offers(&["droidctl", ""], &dir);
    for path in subcommands().iter().filter(|p| p.len() == 1) {
        assert!(top.contains(&path[0]), "`{}` missing from {top:?}", path[0]);
    }
    for path in subcommands().iter().filter(|p| p.len() == 2) {
        let offered = bash_offers(&["droidctl", &path[0], ""], &dir);
        assert!(
            offered.contains(&path[1]),
            "`{}`: {offered:?}",
            path.join(" ")
        );
    }
    // Options are completed too.
    assert_eq!(
        bash_offers(&["droidctl", "scan", "--scan-t"], &dir),
        ["--scan-timeout"]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bash_completes_the_values_models_commands_channels_and_examples() {
    let dir = scratch("values");
    assert_eq!(
        bash_offers(&["droidctl", "--sim", "r2d2,b"], &dir),
        ["r2d2,bb9e", "r2d2,bb8", "r2d2,bolt", "r2d2,boltplus"]
    );
    assert_eq!(
        bash_offers(&["droidctl", "run", "x.txt", "--sim", "bolt,m"], &dir),
        ["bolt,mini"]
    );
    let v2 = bash_offers(
        &["droidctl", "packet", "encode", "set-all-leds-with-"],
        &dir,
    );
    assert_eq!(v2.len(), 3, "{v2:?}");
    assert!(
        v2.iter().all(|n| n.starts_with("set-all-leds-with-")),
        "{v2:?}"
    );
    // Robi's family: its two names (beside the options), none of v2's.
    let rsrcp = bash_offers(
        &["droidctl", "packet", "encode", "--protocol", "rsrcp", ""],
        &dir,
    );
    let names: Vec<&String> = rsrcp.iter().filter(|w| !w.starts_with('-')).collect();
    assert_eq!(names, ["frame", "handshake"], "{rsrcp:?}");
    let channels = bash_offers(
        &["droidctl", "plot", "a.json", "--channels", "speed,ya"],
        &dir,
    );
    assert_eq!(channels, ["speed,yaw"]);
    assert_eq!(
        bash_offers(&["droidctl", "examples", "to"], &dir),
        ["tour.txt"]
    );
    let _ = std::fs::remove_dir_all(&dir);
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
