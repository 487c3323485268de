//! The tests stay one binary (issue 42 point 4): a new `tests/NAME.rs` would be a new binary
//! linking the whole library again, and a file in `tests/it/` that `main.rs` does not name is
//! never compiled, its tests silently never run. Both fail here, with what to do.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The test binaries beside `it`, and why each needs a process of its own.
const OWN_PROCESS: &[(&str, &str)] = &[
    (
        "capture_memory.rs",
        "counts allocations with its own #[global_allocator]",
    ),
    (
        "edu_engine.rs",
        "finds and kills its engine children among this process's children",
    ),
];

fn tests_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests")
}

fn names(dir: &Path, keep: impl Fn(&Path) -> bool) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .expect("tests/ is readable")
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| keep(p))
        .filter_map(|p| Some(p.file_name()?.to_str()?.to_string()))
        .collect()
}

#[test]
fn only_the_binaries_that_need_a_process_of_their_own() {
    let is_rs = |p: &Path| p.is_file() && p.extension().is_some_and(|e| e == "rs");
    let found = names(&tests_dir(), is_rs);
    let allowed: BTreeSet<String> = OWN_PROCESS.iter().map(|(n, _)| n.to_string()).collect();
    let extra: Vec<&String> = found.difference(&allowed).collect();
    assert!(
        extra.is_empty(),
        "move these into tests/it/ as modules (`git mv tests/X.rs tests/it/X.rs`, then \
         `mod X;` in tests/it/main.rs): {extra:?}"
    );
    // A directory with a main.rs is a test binary too.
    let binaries = names(&tests_dir(), |p| p.join("main.rs").is_file());
    assert_eq!(binaries, BTreeSet::from(["it".to_string()]));
}

#[test]
fn every_file_of_it_is_a_module_of_it() {
    let dir = tests_dir().join("it");
    let main = std::fs::read_to_string(dir.join("main.rs")).expect("tests/it/main.rs");
    let declared: BTreeSet<String> = main
        .lines()
        .filter_map(|l| l.trim().strip_prefix("mod ")?.strip_suffix(';'))
        .map(|m| format!("{m}.rs"))
        .collect();
    let is_rs = |p: &Path| p.is_file() && p.extension().is_some_and(|e| e == "rs");
    let mut files = names(&dir, is_rs);
    files.remove("main.rs");
    // `common` is a directory module.
    let undeclared: Vec<&String> = files.difference(&declared).collect();
    assert!(
        undeclared.is_empty(),
        "never compiled: add `mod NAME;` to tests/it/main.rs for {undeclared:?}"
    );
}
