//! No import circle of more than three files: a circle is a set of files each of which reaches
//! every other through `use` (and inline `crate::`/`super::`/`self::` paths), so none of them
//! can be read, changed or tested without the others. This reads every such path in `src/`
//! (comments and string literals aside) at file granularity, computes the strongly connected
//! components of the file graph (Tarjan), and fails listing every component of more than
//! [`BOUND`] files.
//!
//! A path is resolved to the file of its longest module prefix: `crate::app::core::App` is
//! `src/app/core.rs`, `crate::app::App` (a re-export) is `src/app/mod.rs`. A module naming its
//! own parts is no edge (`mod x;`, `pub use x::…`, `self::x::…`, `pub mod cmd { pub use
//! super::x::cmd::*; }`): a module's list of its parts and of what it re-exports is its table
//! of contents, not a use; counted, every `super::T` in a child would close a circle through
//! its parent (22 circles, 91 files on the tree this test was written on). A part naming its
//! parent (`super::T`) is an edge.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The most files one import circle may hold.
const BOUND: usize = 3;

use crate::common::source::rust_files;

/// The module path of a file: `src/app/core.rs` → `app::core`, `src/app/mod.rs` → `app`,
/// `src/lib.rs` → the crate root (empty).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).expect("under src");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    if !(stem == "mod" || (parts.is_empty() && stem == "lib")) {
        parts.push(stem.to_string());
    }
    parts
}

/// The code of a file with comments, string and character literals blanked out (lengths and
/// line breaks kept), so that braces and paths inside them are not read.
fn code_only(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(b[i]));
                    i += 1;
                }
            }
        } else if c == 'r'
            && (next == Some('"') || next == Some('#'))
            && (i == 0 || !(b[i - 1].is_alphanumeric() || b[i - 1] == '_'))
        {
            // A raw string: r"…", r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                match b.get(j) {
                    None => break,
                    Some('"') if (1..=hashes).all(|k| b.get(j + k) == Some(&'#')) => {
                        j += 1 + hashes;
                        break;
                    }
                    _ => j += 1,
                }
            }
            for &ch in &b[i..j.min(b.len())] {
                out.push(blank(ch));
            }
            i = j;
        } else if c == '"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != '"' {
                j += if b[j] == '\\' { 2 } else { 1 };
            }
            for &ch in &b[i..(j + 1).min(b.len())] {
                out.push(blank(ch));
            }
            i = j + 1;
        } else if c == '\'' {
            // A character literal ('x', '\n', '\u{..}'), not a lifetime ('a).
            let end = if next == Some('\\') {
                (i + 2..b.len()).find(|&k| b[k] == '\'')
            } else if b.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(e) => {
                    for _ in i..=e {
                        out.push(' ');
                    }
                    i = e + 1;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The paths of a use tree starting at `at` (`a::b::{c, d::e}` → `a::b::c`, `a::b::d::e`).
fn use_tree(b: &[char], mut at: usize, prefix: &[String], out: &mut Vec<Vec<String>>) -> usize {
    let mut path = prefix.to_vec();
    loop {
        while at < b.len() && b[at].is_whitespace() {
            at += 1;
        }
        if b.get(at) == Some(&'{') {
            at += 1;
            loop {
                while at < b.len() && (b[at].is_whitespace() || b[at] == ',') {
                    at += 1;
                }
                if at >= b.len() || b[at] == '}' {
                    return at + 1;
                }
                at = use_tree(b, at, &path, out);
            }
        }
        let start = at;
        while at < b.len() && (is_ident(b[at]) || b[at] == '*') {
            at += 1;
        }
        if at > start {
            path.push(b[start..at].iter().collect());
        }
        let mut k = at;
        while k < b.len() && b[k].is_whitespace() {
            k += 1;
        }
        if b.get(k) == Some(&':') && b.get(k + 1) == Some(&':') {
            at = k + 2;
            continue;
        }
        // `as name`, generics, a call: the path ends here; skip to the end of this item.
        let mut depth = 0i32;
        while at < b.len() {
            match b[at] {
                '{' | '(' | '<' | '[' => depth += 1,
                '}' | ')' | '>' | ']' if depth > 0 => depth -= 1,
                ',' | '}' | ';' if depth == 0 => break,
                _ if depth == 0 && !(is_ident(b[at]) || b[at].is_whitespace()) => break,
                _ => {}
            }
            at += 1;
        }
        out.push(path);
        return at;
    }
}

/// Every module path a file names, each as (the inline module it is written in, the path as
/// written): `crate::…`, `super::…`, `self::…`, in `use` items and anywhere in code.
fn named_paths(code: &str) -> Vec<(Vec<String>, Vec<String>)> {
    let b: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    // Inline modules (`mod tests { … }`): (name, brace depth inside it).
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut i = 0;
    let word_at = |i: usize, w: &str| {
        let n = w.chars().count();
        b.len() >= i + n
            && b[i..i + n].iter().copied().eq(w.chars())
            && (i == 0 || !is_ident(b[i - 1]))
            && b.get(i + n).is_none_or(|&c| !is_ident(c))
    };
    while i < b.len() {
        match b[i] {
            '{' => {
                depth += 1;
                i += 1;
                continue;
            }
            '}' => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
                i += 1;
                continue;
            }
            _ => {}
        }
        if word_at(i, "mod") {
            let mut j = i + 3;
            while j < b.len() && b[j].is_whitespace() {
                j += 1;
            }
            let start = j;
            while j < b.len() && is_ident(b[j]) {
                j += 1;
            }
            let name: String = b[start..j].iter().collect();
            while j < b.len() && b[j].is_whitespace() {
                j += 1;
            }
            if b.get(j) == Some(&'{') {
                depth += 1;
                inline.push((name, depth));
                i = j + 1;
                continue;
            }
            i = j;
            continue;
        }
        let here: Vec<String> = inline.iter().map(|(n, _)| n.clone()).collect();
        if word_at(i, "use") {
            let mut j = i + 3;
            while j < b.len() && b[j].is_whitespace() {
                j += 1;
            }
            let mut paths = Vec::new();
            let end = use_tree(&b, j, &[], &mut paths);
            out.extend(
                paths
                    .into_iter()
                    .filter(|p| {
                        matches!(
                            p.first().map(String::as_str),
                            Some("crate" | "super" | "self")
                        )
                    })
                    .map(|p| (here.clone(), p)),
            );
            i = end.max(i + 1);
            continue;
        }
        let root = ["crate", "super", "self"].into_iter().find(|w| {
            word_at(i, w)
                && b.get(i + w.len()) == Some(&':')
                && b.get(i + w.len() + 1) == Some(&':')
        });
        if let Some(root) = root {
            let mut paths = Vec::new();
            use_tree(&b, i, &[], &mut paths);
            out.extend(paths.into_iter().map(|p| (here.clone(), p)));
            i += root.len();
            continue;
        }
        i += 1;
    }
    out
}

/// The absolute module path a written path names, seen from `module` (the file's module plus
/// the inline modules it is written in).
fn absolute(module: &[String], path: &[String]) -> Vec<String> {
    let mut at: Vec<String> = module.to_vec();
    let mut rest = path;
    match rest.first().map(String::as_str) {
        Some("crate") => {
            at.clear();
            rest = &rest[1..];
        }
        Some("self") => rest = &rest[1..],
        _ => {}
    }
    while rest.first().map(String::as_str) == Some("super") {
        at.pop();
        rest = &rest[1..];
    }
    at.extend(rest.iter().cloned());
    at
}

/// The file graph of `src/`: each file and the files it names.
fn graph(src: &Path) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    // `main.rs` is another crate (the binary): its `crate::` is not the library's.
    files.retain(|f| f.file_name().is_none_or(|n| n != "main.rs") || f.parent() != Some(src));
    files.sort();
    let modules: BTreeMap<Vec<String>, PathBuf> = files
        .iter()
        .map(|f| (module_path(src, f), f.clone()))
        .collect();
    let mut edges = BTreeMap::new();
    for file in &files {
        let own = module_path(src, file);
        let code = code_only(&std::fs::read_to_string(file).expect("a source file"));
        let mut to = BTreeSet::new();
        for (inline, path) in named_paths(&code) {
            let from: Vec<String> = own.iter().chain(&inline).cloned().collect();
            let target = absolute(&from, &path);
            let hit = (0..=target.len())
                .rev()
                .find_map(|n| modules.get(&target[..n]));
            // A module naming its own parts (`pub mod cmd { pub use super::api::cmd::*; }` in
            // `catalog/mod.rs`) is its table of contents, as `mod x;` and `pub use x::…` are.
            let own_part = |h: &&PathBuf| {
                let m = module_path(src, h);
                m.len() > own.len() && m.starts_with(&own)
            };
            if let Some(hit) = hit.filter(|h| *h != file && !own_part(h)) {
                to.insert(hit.clone());
            }
        }
        edges.insert(file.clone(), to);
    }
    edges
}

/// The strongly connected components of a graph (Tarjan's algorithm, iterative).
fn components(edges: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> Vec<Vec<PathBuf>> {
    let nodes: Vec<&PathBuf> = edges.keys().collect();
    let index_of: BTreeMap<&PathBuf, usize> =
        nodes.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let succ: Vec<Vec<usize>> = nodes
        .iter()
        .map(|n| {
            edges[*n]
                .iter()
                .filter_map(|t| index_of.get(t).copied())
                .collect()
        })
        .collect();
    let n = nodes.len();
    let (mut index, mut low, mut on_stack) = (vec![usize::MAX; n], vec![0; n], vec![false; n]);
    let (mut stack, mut out, mut next) = (Vec::new(), Vec::new(), 0);
    for root in 0..n {
        if index[root] != usize::MAX {
            continue;
        }
        let mut work = vec![(root, 0usize)];
        while let Some(&mut (v, ref mut child)) = work.last_mut() {
            if *child == 0 {
                index[v] = next;
                low[v] = next;
                next += 1;
                stack.push(v);
                on_stack[v] = true;
            }
            if let Some(&w) = succ[v].get(*child) {
                *child += 1;
                if index[w] == usize::MAX {
                    work.push((w, 0));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            work.pop();
            if let Some(&(parent, _)) = work.last() {
                low[parent] = low[parent].min(low[v]);
            }
            if low[v] == index[v] {
                let mut component = Vec::new();
                while let Some(w) = stack.pop() {
                    on_stack[w] = false;
                    component.push(nodes[w].clone());
                    if w == v {
                        break;
                    }
                }
                component.sort();
                out.push(component);
            }
        }
    }
    out
}

#[test]
fn no_import_circle_is_over_three_files() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let edges = graph(&src);
    let mut circles: Vec<Vec<PathBuf>> = components(&edges)
        .into_iter()
        .filter(|c| c.len() > 1)
        .collect();
    circles.sort_by_key(|c| std::cmp::Reverse(c.len()));
    let files: usize = circles.iter().map(Vec::len).sum();
    let report: Vec<String> = circles
        .iter()
        .map(|c| {
            let names: Vec<String> = c
                .iter()
                .map(|f| f.strip_prefix(&src).unwrap_or(f).display().to_string())
                .collect();
            let mut line = format!("{} files: {}", c.len(), names.join(", "));
            if c.len() > BOUND {
                // The edges inside the circle: where to cut.
                let short = |f: &PathBuf| f.strip_prefix(&src).unwrap_or(f).display().to_string();
                for from in c {
                    let inside: Vec<String> = edges[from]
                        .iter()
                        .filter(|t| c.contains(t))
                        .map(short)
                        .collect();
                    line.push_str(&format!("\n    {} -> {}", short(from), inside.join(", ")));
                }
            }
            line
        })
        .collect();
    eprintln!(
        "{} circles, {files} files:\n{}",
        circles.len(),
        report.join("\n")
    );
    let over: Vec<&String> = circles
        .iter()
        .zip(&report)
        .filter(|(c, _)| c.len() > BOUND)
        .map(|(_, r)| r)
        .collect();
    assert!(
        over.is_empty(),
        "import circles of more than {BOUND} files (break them: move what both sides use \
         below both, or pass it in):\n{}",
        over.iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join("\n")
    );
}

#[test]
fn the_reader_resolves_paths_as_rust_does() {
    let code = code_only(
        "use super::{a::B, c};\nuse crate::x::{y::{self, Z}};\n// crate::no\nlet s = \"crate::no\";\n\
         mod tests { use super::*; fn f() { crate::q::r(); } }\nmod child;\npub use child::T;\n",
    );
    let paths: Vec<String> = named_paths(&code)
        .into_iter()
        .map(|(inline, p)| format!("{}|{}", inline.join("::"), p.join("::")))
        .collect();
    assert_eq!(
        paths,
        [
            "|super::a::B",
            "|super::c",
            "|crate::x::y::self",
            "|crate::x::y::Z",
            "tests|super::*",
            "tests|crate::q::r",
        ]
    );
    let m = |s: &str| s.split("::").map(String::from).collect::<Vec<_>>();
    assert_eq!(
        absolute(&m("app::core"), &m("super::place::Place")),
        m("app::place::Place")
    );
    assert_eq!(
        absolute(&m("app::core::tests"), &m("super::*")),
        m("app::core::*")
    );
}

#[test]
fn tarjan_finds_the_circles() {
    let p = |s: &str| PathBuf::from(s);
    let mut edges = BTreeMap::new();
    edges.insert(p("a"), [p("b")].into_iter().collect());
    edges.insert(p("b"), [p("c")].into_iter().collect());
    edges.insert(p("c"), [p("a"), p("d")].into_iter().collect());
    edges.insert(p("d"), BTreeSet::new());
    let mut found: Vec<Vec<PathBuf>> = components(&edges)
        .into_iter()
        .filter(|c| c.len() > 1)
        .collect();
    found.sort();
    assert_eq!(found, [vec![p("a"), p("b"), p("c")]]);
}
