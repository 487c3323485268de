//! Every model everywhere: one table of models ([`Model::ALL`]) feeds the `--help` of every
//! subcommand that takes a model, the shell completions (model names, never file names), the
//! man pages and the error for an unknown name, which offers `robi` as every document says.

use droidctl::model::Model;
use std::process::{Command, Output};

use crate::common::cli;

fn droidctl(args: &[&str]) -> Output {
    cli::droidctl_isolated(args, "droidctl-cli-models.log")
}

fn stdout(args: &[&str]) -> String {
    let out = droidctl(args);
    assert_eq!(out.status.code(), Some(0), "{args:?}");
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn every_help_that_takes_a_model_lists_every_model() {
    for args in [
        &["--help"][..],
        &["drive", "--help"],
        &["run", "--help"],
        &["sim", "--help"],
        &["serve", "--help"],
        &["replay", "--help"],
        &["plot", "--help"],
        &["bridge", "--help"],
    ] {
        let help = stdout(args);
        for m in Model::ALL {
            let line = format!("- {}:", m.id());
            assert!(
                help.lines()
                    .any(|l| l.trim_start().starts_with(&line) && l.contains(m.display_name())),
                "{args:?} does not list {} ({line} {}):\n{help}",
                m.display_name(),
                m.display_name()
            );
        }
        assert!(!help.contains("robi42"), "{args:?}:\n{help}");
    }
}

#[test]
fn an_unknown_model_is_a_usage_error_offering_every_id() {
    let listed = "r2d2, r2q5, bb9e, bb8, sprk, ollie, robi, bolt, boltplus, mini, rvr";
    assert_eq!(
        Model::ALL.map(Model::id).join(", "),
        listed,
        "the table's order"
    );
    for args in [
        &["--sim", "robbi"][..],
        &["drive", "--sim", "r2d2,robbi"],
        &["run", "assets/missions/square.txt", "--sim", "robbi"],
        &["run", "--sim", "robbi", "assets/missions/square.txt"],
        &["sim", "--bluez", "robbi"],
        &["sim", "--bluez", "--remembered", "robbi"],
        &["serve", "--sim", "r2d2", "robbi"],
        &["replay", "x.capture", "--model", "robbi"],
        &["plot", "x.jsonl", "--model", "robbi"],
        &["bridge", "--stdio", "--sim", "robbi"],
    ] {
        let out = droidctl(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("\"robbi\"") || err.contains("'robbi'"),
            "{args:?}: {err}"
        );
        assert!(err.contains(listed), "{args:?} must offer every id: {err}");
        assert!(!err.contains("robi42"), "{args:?}: {err}");
    }
}

#[test]
fn older_and_longer_names_are_still_taken() {
    // `robi42` was Robi 42's id before (older captures say so); names as displayed work too.
    for sim in ["robi42", "Robi 42", "R2-D2,BB-8", "sprk+,bolt+"] {
        let out = droidctl(&["bridge", "--stdio", "--sim", sim]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "--sim {sim:?}: {err}");
    }
}

#[test]
fn completions_offer_the_models_and_no_file_names() {
    // The shell asks droidctl itself (`DROIDCTL_COMPLETE`), in a directory with a file in it:
    // an option naming a model offers every model and never a file name.
    let dir = std::env::temp_dir().join(format!("droidctl-models-compl-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("zz-a-file.txt"), "").unwrap();
    let lines: &[&[&str]] = &[
        &["droidctl", "--sim", ""],
        &["droidctl", "drive", "--sim", ""],
        &["droidctl", "run", "x.txt", "--sim", ""],
        &["droidctl", "serve", "--sim", ""],
        &["droidctl", "bridge", "--stdio", "--sim", ""],
        &["droidctl", "replay", "x.drc", "--model", ""],
        &["droidctl", "plot", "x.json", "--model", ""],
        &["droidctl", "sim", "--bluez", ""],
    ];
    for words in lines {
        let out = Command::new(env!("CARGO_BIN_EXE_droidctl"))
            .arg("--")
            .args(*words)
            .current_dir(&dir)
            .env("DROIDCTL_COMPLETE", "fish")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{words:?}");
        let offered = String::from_utf8_lossy(&out.stdout);
        let values: Vec<&str> = offered
            .lines()
            .map(|l| l.split('\t').next().unwrap_or(""))
            .collect();
        for m in Model::ALL {
            assert!(
                values.contains(&m.id()),
                "{words:?}: {m:?} not in {values:?}"
            );
        }
        // fish shows each model's name beside its id.
        assert!(offered.contains("r2d2\tR2-D2"), "{words:?}: {offered}");
        // `run --sim SCRIPT` is a script when it is not a model: files are offered there.
        let takes_a_file = words[1] == "run";
        assert_eq!(
            offered.contains("zz-a-file"),
            takes_a_file,
            "{words:?}: {offered}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
