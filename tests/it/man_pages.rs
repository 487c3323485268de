//! The man pages are a manual: a page for droidctl and for every subcommand (every
//! `droidctl-NAME(1)` a page names is one `droidctl man --dir` writes), and droidctl(1) has
//! KEYS (the app's help table with the default bindings), CONFIGURATION (the shipped
//! defaults), FILES, ENVIRONMENT and EXIT STATUS, generated from the definitions the program
//! uses, and sends readers to the manual in docs/, not to a README that `cargo install` does
//! not install.

use droidctl::cli::man::key_sections;
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::process::Output;

use crate::common::cli;

fn droidctl(args: &[&str]) -> Output {
    cli::droidctl_isolated(args, "droidctl-man-pages.log")
}

fn page(args: &[&str]) -> String {
    let out = droidctl(args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// A section's roff, from its `.SH` to the next.
fn section<'a>(page: &'a str, name: &str) -> &'a str {
    let start = page
        .find(&format!(".SH {name}\n"))
        .unwrap_or_else(|| panic!("no {name} section:\n{page}"));
    let rest = &page[start + 4..];
    &page[start..start + 4 + rest.find("\n.SH ").unwrap_or(rest.len())]
}

/// Roff text as it reads: `\-` is `-`, `\e` a backslash.
fn plain(roff: &str) -> String {
    roff.replace("\\-", "-")
        .replace("\\e", "\\")
        .replace("\\&", "")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("droidctl-man-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn every_page_named_is_written_and_each_subcommand_has_one() {
    let dir = scratch("dir");
    let d = dir.to_str().unwrap();
    page(&["man", "--dir", d]);
    let written: BTreeSet<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    for name in [
        "droidctl.1",
        "droidctl-drive.1",
        "droidctl-run.1",
        "droidctl-packet-decode.1",
    ] {
        assert!(written.contains(name), "{name}: {written:?}");
    }
    // Every reference in every page is a page written.
    let mut named = BTreeSet::new();
    for file in &written {
        let text = plain(&std::fs::read_to_string(dir.join(file)).unwrap());
        assert!(text.starts_with(".ie") || text.contains(".TH "), "{file}");
        for (i, _) in text.match_indices("droidctl-") {
            let rest = &text[i..];
            if let Some(end) = rest.find("(1)") {
                let name = &rest[..end];
                if name.chars().all(|c| c.is_ascii_lowercase() || c == '-') {
                    named.insert(format!("{name}.1"));
                }
            }
        }
        assert!(text.contains(".SH EXIT STATUS"), "{file}");
        assert!(text.contains(".SH SEE ALSO"), "{file}");
        assert!(
            !text.replace("docs/README.md", "").contains("README"),
            "{file}"
        );
    }
    assert!(named.len() > 10, "{named:?}");
    let missing: Vec<_> = named.difference(&written).collect();
    assert!(missing.is_empty(), "named but never written: {missing:?}");
    // The one page a subcommand asks for is the one written for it.
    let decode = page(&["man", "packet", "decode"]);
    assert_eq!(
        decode,
        std::fs::read_to_string(dir.join("droidctl-packet-decode.1")).unwrap()
    );
    assert!(decode.contains(".TH droidctl-packet-decode 1"), "{decode}");
    // droidctl's own pages (of any version: here an older one) are brought up to date
    // without --force, as after an upgrade.
    let run = dir.join("droidctl-run.1");
    let old =
        std::fs::read_to_string(&run)
            .unwrap()
            .replacen(env!("CARGO_PKG_VERSION"), "0.0.1", 1);
    std::fs::write(&run, &old).unwrap();
    let again = droidctl(&["man", "--dir", d]);
    assert_eq!(
        again.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(&run).unwrap(),
        page(&["man", "run"]),
        "the old page was replaced"
    );
    // Another file of a page's name is kept unless --force, as every output droidctl writes.
    std::fs::write(&run, "my own notes\n").unwrap();
    let again = droidctl(&["man", "--dir", d]);
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    assert_eq!(std::fs::read_to_string(&run).unwrap(), "my own notes\n");
    page(&["man", "--dir", d, "--force"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unknown_page_is_a_usage_error_listing_the_pages() {
    let out = droidctl(&["man", "nosuch"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("packet decode") && err.contains("drive"),
        "{err}"
    );
}

#[test]
fn the_keys_are_the_apps_help_with_the_default_bindings() {
    let keys = plain(section(&page(&["man"]), "KEYS"));
    let sections = key_sections();
    let titles: Vec<&str> = sections.iter().map(|s| s.title.as_str()).collect();
    for want in ["Keyboard", "Packet log", "Gamepad", "Replay"] {
        assert!(titles.contains(&want), "{want}: {titles:?}");
    }
    for s in &sections {
        assert!(
            keys.contains(&format!(".SS {}", s.title)),
            "{}:\n{keys}",
            s.title
        );
        assert!(!s.lines.is_empty(), "{}", s.title);
        for l in &s.lines {
            let entry = format!("\\fB{}\\fR\n{}\n", l.keys, l.action);
            assert!(keys.contains(&entry), "{} / {}:\n{keys}", l.keys, l.action);
        }
    }
    // What the app's `?` shows first: hold ↑ or w to drive.
    assert!(keys.contains("\\fB↑ / w\\fR\ndrive forward"), "{keys}");
}

#[test]
fn configuration_files_environment_and_exit_status_come_from_the_program() {
    let man = page(&["man"]);
    let conf = plain(section(&man, "CONFIGURATION"));
    // The shipped defaults, every line of them (comments included).
    for line in droidctl::config::DEFAULT_TOML
        .lines()
        .filter(|l| !l.is_empty())
    {
        assert!(conf.contains(line), "{line:?} missing from CONFIGURATION");
    }
    let files = plain(section(&man, "FILES"));
    assert!(
        files.contains("config.toml") && files.contains("droidctl.log"),
        "{files}"
    );
    assert!(files.contains("DROIDCTL_CONFIG"), "{files}");
    let env = plain(section(&man, "ENVIRONMENT"));
    for var in [
        "DROIDCTL_CONFIG",
        "DROIDCTL_LOG_FILE",
        "DROIDCTL_MQTT_PASSWORD",
    ] {
        assert!(env.contains(var), "{var}: {env}");
    }
    let exit = plain(section(&man, "EXIT STATUS"));
    for (status, what) in droidctl::cli::EXIT_STATUSES {
        assert!(
            exit.contains(&format!("\\fB{status}\\fR\n")),
            "{status}: {exit}"
        );
        let first = what
            .split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" ");
        assert!(exit.contains(&first), "{first}: {exit}");
    }
    // A usage error is the status the page gives bad input.
    assert_eq!(droidctl(&["packet", "nosuch"]).status.code(), Some(2));
    let run = plain(&page(&["man", "run"]));
    let missions = section(&run, "MISSION SCRIPTS");
    for c in droidctl::script::COMMANDS {
        assert!(missions.contains(c), "{c}: {missions}");
    }
}

#[test]
fn the_model_lists_reach_the_pages() {
    for sub in ["drive", "run", "serve", "sim", "replay"] {
        let text = plain(&page(&["man", sub]));
        for m in droidctl::model::Model::ALL {
            assert!(
                text.contains(&format!("{}: {}", m.id(), m.display_name())),
                "droidctl-{sub}(1) does not list {}",
                m.id()
            );
        }
    }
}
