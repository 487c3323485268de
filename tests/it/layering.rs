//! Imports point one way: protocol ← link ← family ← session, sim ← capture, teleop ← relay ←
//! app ← ui ← cli, with the pure-data leaves (model, units, gatt, …) under everything. A lower
//! layer never names a higher one, in code or in its tests: this reads every `crate::` path
//! in `src/` (comments aside) and fails with the offending file and line.

use std::collections::BTreeMap;
use std::path::Path;

/// Each top-level module's rank: a module may use only modules of strictly lower rank.
const RANKS: &[(&str, u32)] = &[
    // Leaves: pure data and small helpers.
    ("units", 0),
    ("hex", 0),
    ("rng", 0),
    ("model", 0),
    ("gatt", 0),
    // The log file is one of droidctl's own (own_file).
    ("logging", 1),
    // The overwrite rule of the files droidctl writes.
    ("output", 0),
    // droidctl's own files at fixed paths: no FIFO, no symbolic link written through.
    ("own_file", 0),
    // The bound on the text files droidctl reads whole.
    ("text_file", 0),
    // What a user tunes about monitoring: sensor groups, collision detection.
    ("tuning", 0),
    // Outside text made safe to print on a terminal.
    ("printable", 0),
    // Which addresses are loopback.
    ("net", 0),
    // The examples built into the binary (they name the models they are for).
    ("examples", 1),
    // The one poison-tolerant lock.
    ("sync", 0),
    // The sans-IO protocol core.
    ("protocol", 10),
    // Links, and the plain data built on the protocol (scripts, telemetry, configuration).
    ("link", 20),
    ("script", 20),
    ("telemetry", 20),
    ("config", 20),
    // The seam between protocol families.
    ("family", 30),
    ("session", 40),
    ("sim", 40),
    // Missions run on a session.
    ("mission", 45),
    // Several sessions at once, and missions on them.
    ("fleet", 47),
    // Sphero Edu programs run on a droid's mission machinery.
    ("edu", 48),
    ("capture", 50),
    ("teleop", 50),
    // `serve --record` writes captures.
    ("relay", 55),
    // Other programs drive a fleet through JSON lines and MQTT.
    ("bridge", 57),
    ("app", 60),
    // `droidctl plot`: pictures of runs (samples from missions and captures).
    ("plot", 65),
    ("ui", 70),
    ("cli", 80),
    // The fuzz harnesses drive everything, the CLI's readers included.
    ("fuzzing", 90),
];

fn rank(module: &str) -> Option<u32> {
    RANKS.iter().find(|(m, _)| *m == module).map(|(_, r)| *r)
}

use crate::common::source::rust_files;

/// The top-level module a file belongs to (`src/family/v2/read.rs` → `family`).
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).expect("under src");
    let first = rel.components().next().expect("a path");
    let name = first.as_os_str().to_string_lossy();
    name.trim_end_matches(".rs").to_string()
}

/// The modules a line of code names with `crate::…`, including those inside
/// `crate::{a, b::c}` groups.
fn named_modules(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        // `droidctl::crate::` cannot happen; skip identifiers that merely end in "crate".
        let before = &rest[..at];
        let boundary = before
            .chars()
            .last()
            .is_none_or(|c| !c.is_alphanumeric() && c != '_');
        rest = &rest[at + "crate::".len()..];
        if !boundary {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.push(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            out.push(name);
        }
    }
    out
}

#[test]
fn lower_layers_never_import_higher_ones() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut violations = Vec::new();
    let mut unranked = BTreeMap::new();
    for file in &files {
        let module = module_of(&src, file);
        if module == "lib" || module == "main" {
            continue;
        }
        let Some(own) = rank(&module) else {
            unranked.insert(module, file.display().to_string());
            continue;
        };
        let text = std::fs::read_to_string(file).expect("a source file");
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for used in named_modules(code) {
                if used == module || used == "self" || used == "super" {
                    continue;
                }
                match rank(&used) {
                    Some(r) if r < own => {}
                    Some(r) => violations.push(format!(
                        "{}:{}: {module} (rank {own}) uses {used} (rank {r})",
                        file.display(),
                        i + 1
                    )),
                    None => {
                        unranked.insert(used, format!("{}:{}", file.display(), i + 1));
                    }
                }
            }
        }
    }
    assert!(
        unranked.is_empty(),
        "modules without a layer (add them to RANKS): {unranked:?}"
    );
    assert!(
        violations.is_empty(),
        "a lower layer imports a higher one:\n{}",
        violations.join("\n")
    );
}

#[test]
fn the_checker_sees_grouped_and_nested_paths() {
    assert_eq!(
        named_modules("use crate::{family::Command, link::Link};"),
        ["family", "link"]
    );
    assert_eq!(
        named_modules("let x = crate::sim::SimConfig::for_model(m); // crate::ui"),
        ["sim", "ui"]
    );
    assert!(named_modules("let my_crate::x = 1;").is_empty());
}

/// Short files with one job: no file in `src/` over 900 lines (tests included).
#[test]
fn no_source_file_is_over_900_lines() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let n = std::fs::read_to_string(f)
                .expect("a source file")
                .lines()
                .count();
            (n > 900).then(|| format!("{}: {n} lines", f.display()))
        })
        .collect();
    assert!(long.is_empty(), "split these by job:\n{}", long.join("\n"));
}

/// The files of `src/` a model's `Model::X` variant is named in outside tests (a file only
/// `#[cfg(test)] mod`-declared, a `tests.rs` or `*_tests.rs`, a file's trailing
/// `#[cfg(test)]` module, comments) and fuzz harnesses: where a robot lives. Issue 42's goal is
/// at most 4 (the model table, its family's robots file, its simulator file, one more).
fn files_naming_each_model() -> BTreeMap<&'static str, Vec<String>> {
    const MODELS: [&str; 11] = [
        "R2D2", "R2Q5", "BB9E", "BB8", "SprkPlus", "Ollie", "Robi42", "Bolt", "BoltPlus", "Mini",
        "Rvr",
    ];
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    // Files declared only for tests: `#[cfg(test)]` then `mod name;`.
    let mut test_only = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).expect("a source file");
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        for w in lines.windows(2) {
            if w[0] == "#[cfg(test)]"
                && let Some(name) = w[1].strip_prefix("mod ").and_then(|n| n.strip_suffix(';'))
            {
                let dir = if file.ends_with("mod.rs") || file.ends_with("lib.rs") {
                    file.parent().expect("a directory").to_path_buf()
                } else {
                    file.with_extension("")
                };
                test_only.push(dir.join(format!("{name}.rs")));
                test_only.push(dir.join(name).join("mod.rs"));
            }
        }
    }
    let mut named: BTreeMap<&str, Vec<String>> = MODELS.iter().map(|m| (*m, vec![])).collect();
    for file in &files {
        let rel = file
            .strip_prefix(&src)
            .expect("under src")
            .display()
            .to_string();
        let base = file.file_name().expect("a name").to_string_lossy();
        if test_only.contains(file)
            || base == "tests.rs"
            || base.ends_with("_tests.rs")
            || rel.starts_with("fuzzing")
        {
            continue;
        }
        let text = std::fs::read_to_string(file).expect("a source file");
        let code: String = text
            .lines()
            .take_while(|l| !l.starts_with("#[cfg(test)]"))
            .map(|l| l.split("//").next().unwrap_or(""))
            .collect::<Vec<_>>()
            .join("\n");
        for m in MODELS {
            let needle = format!("Model::{m}");
            let found = code.match_indices(&needle).any(|(at, _)| {
                !code[at + needle.len()..]
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_alphanumeric() || c == '_')
            });
            if found {
                named.get_mut(m).expect("a model").push(rel.clone());
            }
        }
    }
    named
}

/// A robot is named in few files outside tests. The bounds are what issue 42's work reached
/// (before it: R2-D2 12, R2-Q5 6, BB-9E 4, BB-8 3, SPRK+ 2, Ollie 4, Robi 42 5, BOLT 11,
/// Mini 7, RVR 13); BOLT and RVR were over 4 by `protocol/v2/catalog/targets.rs` (which
/// processor has each command) and a second simulator file (`sim/figures.rs` beside
/// `sim/robots.rs`), until issue 41 moved the LED masks and the animatronic rule of
/// `sim/robots.rs` into the family's robots file. Lower one when a robot's code moves into its
/// table row, family robots file or simulator file, never raise it.
#[test]
fn a_robot_is_named_in_few_files() {
    let bounds = [
        ("R2D2", 3),
        ("R2Q5", 3),
        ("BB9E", 3),
        ("BB8", 2),
        ("SprkPlus", 2),
        ("Ollie", 2),
        ("Robi42", 3),
        ("Bolt", 4),
        // Issue 41: the model table, its family's robots file, `catalog/targets.rs` (its
        // processor), `sim/figures.rs` (its size).
        ("BoltPlus", 4),
        ("Mini", 4),
        ("Rvr", 4),
    ];
    let named = files_naming_each_model();
    let over: Vec<String> = bounds
        .iter()
        .filter(|(m, bound)| named[m].len() > *bound)
        .map(|(m, bound)| {
            format!(
                "{m}: {} files (bound {bound}): {:?}",
                named[m].len(),
                named[m]
            )
        })
        .collect();
    assert!(over.is_empty(), "{}", over.join("\n"));
}
