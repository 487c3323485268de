//! Every model everywhere: one table of models ([`Model::ALL`]) feeds the `--help` of every
//! subcommand that takes a model, the shell completions (model names, never file names), the
//! man pages and the error for an unknown name, which offers `robi` as every document says.

use droidctl::model::Model;
use std::process::Output;

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
    let listed = "r2d2, r2q5, bb9e, bb8, sprk, ollie, robi, bolt, mini, rvr";
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
    let ids = Model::ALL.map(Model::id).join(" ");
    let bash = stdout(&["completions", "bash"]);
    let lines: Vec<&str> = bash.lines().collect();
    let mut cases = 0;
    for (i, l) in lines.iter().enumerate() {
        if matches!(l.trim(), "--sim)" | "--model)" | "--remembered)") {
            cases += 1;
            let next = lines[i + 1];
            assert!(
                next.contains(&format!("compgen -W \"{ids}\"")),
                "bash {}: {next}",
                l.trim()
            );
            assert!(!next.contains("compgen -f"), "bash {}: {next}", l.trim());
        }
    }
    // --sim: the app, drive, run, serve, bridge; --model: replay, plot; --remembered.
    assert!(cases >= 8, "only {cases} model options in the bash script");

    let fish = stdout(&["completions", "fish"]);
    // One `complete` per option; a value list may span lines.
    let entries: Vec<&str> = fish.split("\ncomplete ").collect();
    let model_entries: Vec<&str> = entries
        .iter()
        .copied()
        .filter(|e| {
            e.contains(" -l sim ") || e.contains(" -l model ") || e.contains(" -l remembered ")
        })
        .collect();
    assert!(model_entries.len() >= 8, "{model_entries:?}");
    for e in model_entries {
        // `-f`: no file names; `-a`: the models.
        assert!(
            e.contains(" -f ") && e.contains("-a \"r2d2\\t'R2-D2'"),
            "fish: {e}"
        );
        assert!(e.contains("rvr\\t'Sphero RVR'"), "fish: {e}");
    }

    let zsh = stdout(&["completions", "zsh"]);
    let sims: Vec<&str> = zsh.lines().filter(|l| l.starts_with("'--sim=")).collect();
    assert!(!sims.is_empty());
    for l in sims {
        assert!(l.contains("((r2d2\\:\"R2-D2\""), "zsh: {l}");
        assert!(!l.contains("_files"), "zsh: {l}");
    }
}
