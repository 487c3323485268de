//! `droidctl examples`: the built-in examples work from any directory (as after `cargo
//! install`, with no checkout around), and each one's `Models:` line is the truth: it runs on
//! every model it names and is refused on every other.

use crate::common::scratch;
use droidctl::examples::{EXAMPLES, Fits};
use droidctl::model::Model;
use scratch::{Scratch, stderr, stdout};

#[test]
fn every_example_is_saved_and_runs_on_the_models_it_names_and_no_other() {
    let dir = Scratch::new("examples", "run");
    let listed = dir.run(&["examples"]);
    assert_eq!(listed.status.code(), Some(0), "{}", stderr(&listed));
    let mut wrong = Vec::new();
    for e in EXAMPLES {
        // Saved from the binary into a directory with nothing else in it.
        let out = dir.run(&["examples", e.name]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        assert_eq!(stdout(&out), e.text, "{}", e.name);
        dir.file(e.name, &stdout(&out));
        assert!(stdout(&listed).contains(e.name), "{}", stdout(&listed));
        let fits = e.fits().unwrap_or_else(|err| panic!("{err}"));
        let (runs, refused): (Vec<String>, Vec<String>) = match &fits {
            Fits::Together(ms) => (
                vec![ms.iter().map(|m| m.id()).collect::<Vec<_>>().join(",")],
                Vec::new(),
            ),
            Fits::Each(ms) => (
                ms.iter().map(|m| m.id().to_string()).collect(),
                Model::ALL
                    .into_iter()
                    .filter(|m| !ms.contains(m))
                    .map(|m| m.id().to_string())
                    .collect(),
            ),
        };
        for sim in &runs {
            let out = dir.run(&["run", e.name, "--sim", sim]);
            if out.status.code() != Some(0) {
                wrong.push(format!("{} on {sim}: {}", e.name, stderr(&out)));
            }
        }
        // A mission is refused whole before anything is sent (2), and so is a program
        // calling what the model does not have (its calls and events are checked first).
        let refusal = 2;
        for sim in &refused {
            let out = dir.run(&["run", e.name, "--sim", sim]);
            if out.status.code() != Some(refusal) {
                wrong.push(format!(
                    "{} on {sim}: {:?}, not {refusal}: its Models line leaves {sim} out",
                    e.name,
                    out.status.code()
                ));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn the_comment_of_each_example_shows_how_to_run_it_from_the_saved_file() {
    for e in EXAMPLES {
        let run_line = e
            .text
            .lines()
            .find(|l| l.contains("droidctl run ") && l.contains(e.name))
            .unwrap_or_else(|| panic!("{}: no line runs it", e.name));
        assert!(
            !run_line.contains("examples/"),
            "{}: a checkout path",
            e.name
        );
    }
}
