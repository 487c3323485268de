//! The names a program calls, checked before anything is sent: a misspelt call
//! (`setMainLED`) is found before the robot moves, with "did you mean", instead of when the
//! program reaches it; a call this robot does not have is found before the first call is
//! made ([`not_on_robot`]).
//!
//! A name is checked when the program calls it by itself (`name(…)`, not `obj.name(…)`) and
//! never names it anywhere else: a function, variable or parameter of the program is named
//! where it is declared, so only names the program takes from outside are left. Those must be
//! droidctl's calls or the engine's own globals (`parseInt`, `Number`, …).

use super::calls;
use crate::model::Model;
use boa_engine::ast::expression::access::{PropertyAccess, PropertyAccessField};
use boa_engine::ast::expression::{Call, Identifier};
use boa_engine::ast::visitor::{VisitWith, Visitor};
use boa_engine::ast::{Expression, Spanned};
use boa_engine::interner::{Interner, Sym};
use boa_engine::parser::Parser;
use boa_engine::{Context, Source};
use std::collections::HashMap;
use std::convert::Infallible;
use std::ops::ControlFlow;

/// A name the program calls from outside itself, and where (1-based). An event it registers
/// (`registerEvent(EventType.onColor, …)`) is one too, as `EventType.onColor`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Called {
    pub name: String,
    pub line: u32,
    pub column: u32,
}

/// How an event registered is named among [`Called`]'s names.
const EVENT: &str = "EventType.";

#[derive(Default)]
struct Names {
    /// How often each name appears anywhere.
    seen: HashMap<Sym, u32>,
    /// Each plain call `name(…)`: its name and place.
    calls: Vec<(Sym, u32, u32)>,
    /// Each plain call whose first argument is `A.B` (`registerEvent(EventType.onColor, …)`):
    /// the call's name, `A`, `B` and the place.
    member_args: Vec<(Sym, Sym, Sym, u32, u32)>,
}

impl<'ast> Visitor<'ast> for Names {
    type BreakTy = Infallible;

    fn visit_identifier(&mut self, id: &'ast Identifier) -> ControlFlow<Infallible> {
        *self.seen.entry(id.sym()).or_default() += 1;
        ControlFlow::Continue(())
    }

    fn visit_call(&mut self, call: &'ast Call) -> ControlFlow<Infallible> {
        if let Expression::Identifier(id) = call.function() {
            let at = id.span().start();
            self.calls
                .push((id.sym(), at.line_number(), at.column_number()));
            if let Some(Expression::PropertyAccess(PropertyAccess::Simple(arg))) =
                call.args().first()
                && let Expression::Identifier(target) = arg.target()
                && let PropertyAccessField::Const(field) = arg.field()
            {
                self.member_args.push((
                    id.sym(),
                    target.sym(),
                    field.sym(),
                    at.line_number(),
                    at.column_number(),
                ));
            }
        }
        call.visit_with(self)
    }
}

/// The names `source` calls that it never declares nor names otherwise, each at its first
/// call. `None`: the program does not parse (the syntax check says why).
pub(super) fn called_from_outside(source: &str) -> Option<Vec<Called>> {
    let mut interner = Interner::default();
    let scope = boa_engine::ast::scope::Scope::new_global();
    let script = Parser::new(Source::from_bytes(source))
        .parse_script(&scope, &mut interner)
        .ok()?;
    let mut names = Names::default();
    let _ = script.visit_with(&mut names);
    let mut calls_of: HashMap<Sym, u32> = HashMap::new();
    for (sym, _, _) in &names.calls {
        *calls_of.entry(*sym).or_default() += 1;
    }
    let mut out: Vec<Called> = Vec::new();
    for (sym, line, column) in &names.calls {
        if names.seen.get(sym) != calls_of.get(sym) {
            continue;
        }
        let name = interner.resolve_expect(*sym).to_string();
        if out.iter().all(|c| c.name != name) {
            out.push(Called {
                name,
                line: *line,
                column: *column,
            });
        }
    }
    for (call, target, field, line, column) in &names.member_args {
        if interner.resolve_expect(*call).to_string() == "registerEvent"
            && interner.resolve_expect(*target).to_string() == "EventType"
        {
            out.push(Called {
                name: format!("{EVENT}{}", interner.resolve_expect(*field)),
                line: *line,
                column: *column,
            });
        }
    }
    Some(out)
}

/// The engine's own globals (`parseInt`, `Math`, …), as a fresh context has them.
fn engine_globals() -> Vec<String> {
    let mut ctx = Context::default();
    let names = ctx.eval(Source::from_bytes(
        "Object.getOwnPropertyNames(globalThis).join(',')",
    ));
    names
        .ok()
        .and_then(|v| v.as_string().map(|s| s.to_std_string_escaped()))
        .map(|s| s.split(',').map(str::to_string).collect())
        .unwrap_or_default()
}

/// Sphero Edu calls droidctl knows but cannot carry out, each refused with its own reason when
/// reached (the prelude throws it): not misspellings.
const REFUSED: &[&str] = &["setDisplayImage"];

/// The calls droidctl's API defines (the calls table's plain names), and those it refuses.
fn api_names() -> impl Iterator<Item = &'static str> {
    calls::CALLS
        .iter()
        .map(|c| c.name)
        .filter(|n| !n.contains('.'))
        .chain(REFUSED.iter().copied())
}

/// The first name `source` calls that is neither the program's, droidctl's nor the engine's:
/// where, and what it may have meant. Run in the engine's child (the parser recurses).
pub(super) fn unknown_call(source: &str) -> Option<(Called, String)> {
    let called = called_from_outside(source)?;
    let globals = engine_globals();
    let known = |n: &str| api_names().any(|a| a == n) || globals.iter().any(|g| g == n);
    let c = called
        .into_iter()
        .find(|c| !c.name.starts_with(EVENT) && !known(&c.name))?;
    let mut candidates: Vec<&str> = Vec::new();
    for a in api_names() {
        candidates.push(a);
    }
    for g in &globals {
        candidates.push(g);
    }
    let message = match did_you_mean(&c.name, &candidates) {
        Some(m) => format!(
            "{}() is not a Sphero Edu call nor defined in the program: did you mean {m}()?",
            c.name
        ),
        None => format!(
            "{}() is not a Sphero Edu call nor defined in the program (docs/edu-programs.md \
             lists the calls)",
            c.name
        ),
    };
    Some((c, message))
}

/// The first call of `called` that `model` does not have, said as the engine says it when a
/// program reaches one.
pub(super) fn not_on_robot(called: &[Called], model: Model) -> Option<(u32, String)> {
    called
        .iter()
        .find_map(|c| match c.name.strip_prefix(EVENT) {
            Some(event) => calls::event(event)
                .filter(|robots| !robots.applies(model))
                .map(|robots| {
                    (
                        c.line,
                        format!(
                            "registerEvent: {event} is not on {} (it is on {})",
                            model.display_name(),
                            robots.names()
                        ),
                    )
                }),
            None => calls::not_on(&c.name, model).map(|why| (c.line, why)),
        })
}

/// The closest of `candidates` to `name`: the same but for case, or at most two edits away
/// (a third of a long name).
fn did_you_mean<'a>(name: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let lower = name.to_ascii_lowercase();
    if let Some(c) = candidates.iter().find(|c| c.to_ascii_lowercase() == lower) {
        return Some(c);
    }
    let most = (name.chars().count() / 3).clamp(1, 3);
    candidates
        .iter()
        .map(|c| (edits(&lower, &c.to_ascii_lowercase()), *c))
        .filter(|(d, _)| *d <= most)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// Levenshtein distance (names are short: at most 64 characters are compared).
fn edits(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().take(64).collect();
    let b: Vec<char> = b.chars().take(64).collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = if ca == cb {
                prev
            } else {
                1 + prev.min(cur).min(row[j])
            };
            prev = cur;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_misspelt_call_is_found_with_what_it_meant() {
        let src = "async function startProgram() {\n  await roll(0, 50, 1);\n  setMainLED({ r: 1, g: 2, b: 3 });\n}\n";
        let (c, m) = unknown_call(src).expect("found");
        assert_eq!((c.name.as_str(), c.line, c.column), ("setMainLED", 3, 3));
        assert!(m.contains("did you mean setMainLed()?"), "{m}");
        // The program's own functions, parameters and the engine's globals are not.
        let ok = "function helper(f) { return f(1) + parseInt('2'); }\nasync function startProgram() {\n  const g = (x) => x;\n  helper(g);\n  await delay(Number('1'));\n  console.log(buildString('a', 1));\n}\n";
        assert_eq!(unknown_call(ok), None);
        assert_eq!(did_you_mean("rol", &["roll", "spin"]), Some("roll"));
        assert_eq!(did_you_mean("dance", &["roll", "spin"]), None);
    }

    #[test]
    fn a_call_not_on_the_robot_is_found_before_it_is_reached() {
        let src = "async function startProgram() {\n  await delay(2);\n  setMatrixCharacter('A', { r: 1, g: 0, b: 0 });\n}\n";
        let called = called_from_outside(src).unwrap();
        let (line, why) = not_on_robot(&called, Model::R2D2).expect("not on R2-D2");
        assert_eq!(line, 3);
        assert!(why.contains("not on R2-D2"), "{why}");
        assert_eq!(not_on_robot(&called, Model::Bolt), None);
        // An event registered is checked too.
        let src = "registerEvent(EventType.onColor, () => {});\nasync function startProgram() {}\n";
        let called = called_from_outside(src).unwrap();
        let (line, why) = not_on_robot(&called, Model::Bolt).expect("onColor is RVR's");
        assert_eq!(line, 1);
        assert!(why.contains("onColor is not on Sphero BOLT"), "{why}");
        assert_eq!(not_on_robot(&called, Model::Rvr), None);
    }
}
