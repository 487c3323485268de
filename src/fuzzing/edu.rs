//! Sphero Edu programs (`droidctl run PROGRAM.js`): every call of the API (the table in
//! `src/edu/calls.rs`), and the engine's natives the prelude hides, with hostile arguments
//! (NaN, ±Infinity, 1e308, −0, a 1 MiB text, objects, arrays, `undefined`, symbols), on any
//! model, run through the JavaScript engine with each promise resolved at once. Whatever
//! the program:
//!
//! 1. the engine never dies or hangs (a panic in a native once ended its thread, and the run
//!    waited 5 s to blame "a loop without `await`");
//! 2. each call comes to an effect within droidctl's bounds (a timeline of at most 24 h
//!    whose steps are due within it, a finite distance, a matrix text of 1 to 30 fps, texts
//!    of at most 1000 bytes) or to an error that names the call (the natives' names too:
//!    they are not globals, so calling one is a ReferenceError naming it);
//! 3. a program may also replace what the prelude relies on (`Number.isFinite`, `Math`,
//!    `String`, an array's iterator) so that hostile values reach the natives past its
//!    checks: then its errors need not name a call (the program broke the prelude), but 1
//!    and 2's bounds hold.
//!
//! Input layout: the first byte's low 3 bits pick the replacement ([`PATCHES`], 0: none) and
//! the rest the model; then, per call (48 at most), a byte for the call (the table's, then
//! the natives), a byte whose value modulo 5 is the argument count, and a byte per argument
//! ([`VALUES`]).

use super::Target;
use crate::edu::calls::CALLS;
use crate::edu::engine::Status;
use crate::edu::probe::{check_effect, run};
use crate::model::Model;

pub const TARGET: Target = Target {
    name: "edu",
    run: run_input,
    dictionary: &[b"\x00", b"\x01", b"\x04", b"\x00\x04\x00\x01\x02\x03"],
};

/// Hostile arguments, as JavaScript.
pub const VALUES: &[&str] = &[
    "NaN",
    "Infinity",
    "-Infinity",
    "1e308",
    "-1e308",
    "-0",
    "0",
    "1",
    "0.5",
    "-1",
    "255",
    "-255",
    "360",
    "1e19",
    "9007199254740993",
    "\"HI\"",
    "\"\"",
    "\"x\".repeat(1 << 20)",
    "\"\\u00e9\\u{1F600}\"",
    "{}",
    "[]",
    "[1, 2, 3]",
    "[NaN, Infinity, {}]",
    "undefined",
    "null",
    "true",
    "Symbol()",
    "{ r: NaN, g: 1e308, b: -Infinity }",
    "{ r: 255, g: 0, b: 0 }",
    "{ x: NaN, y: 1e308 }",
    "{ x: 3, y: 4 }",
    "{ valueOf() { return NaN; } }",
    "() => 1",
    "EventType.onCollision",
    "\"onColor\"",
    "Stance.Bipod",
    "{ frames: [[[0, 0, 0, 0, 0, 0, 0, 0]]], palette: [{ r: 1, g: 2, b: 3 }], fps: NaN }",
    "{ frames: [Array(8).fill(Array(8).fill(1e308))], palette: [{}], fps: 1e308 }",
];

/// What a program may replace to get hostile values past the prelude's checks (0: nothing).
pub const PATCHES: &[&str] = &[
    "",
    "Number.isFinite = () => true;",
    "Number.isFinite = () => true; Math.round = (v) => v; \
     Math.max = (a, b) => b; Math.min = (a, b) => b;",
    "String = (v) => v; Number = (v) => v; Number.isFinite = () => true;",
    "Array.prototype[Symbol.iterator] = function* () { yield {}; yield undefined; \
     yield NaN; yield Symbol(); yield \"x\".repeat(1 << 20); };",
];

/// The natives, which no program can name.
pub const NATIVES: &[&str] = &["__call", "__read", "__on"];

/// The program `data` spells, the model it runs on and whether it replaces builtins.
pub fn program(data: &[u8]) -> (String, Model, bool) {
    let mut it = data.iter().copied();
    let head = it.next().unwrap_or(0);
    let patch = PATCHES[usize::from(head & 7) % PATCHES.len()];
    let model = Model::ALL[usize::from(head >> 3) % Model::ALL.len()];
    let mut body = String::new();
    for _ in 0..48 {
        let Some(c) = it.next() else { break };
        let k = usize::from(c) % (CALLS.len() + NATIVES.len());
        let name = CALLS
            .get(k)
            .map_or_else(|| NATIVES[k - CALLS.len()], |c| c.name);
        let n = it.next().unwrap_or(0) % 5;
        let args: Vec<&str> = (0..n)
            .map(|_| VALUES[usize::from(it.next().unwrap_or(0)) % VALUES.len()])
            .collect();
        body.push_str(&format!(
            "  __try({name:?}, () => {name}({}));\n",
            args.join(", ")
        ));
    }
    let source = format!(
        "const __S = String, __includes = String.prototype.includes, __bad = [];\n\
         function __try(name, f) {{\n\
         \x20 try {{ f(); }} catch (e) {{\n\
         \x20   let m = \"?\";\n\
         \x20   try {{ m = __S(e && e.message); }} catch (_) {{}}\n\
         \x20   if (!__includes.call(m, name)) __bad.push(name + \": \" + m);\n\
         \x20 }}\n\
         }}\n\
         async function startProgram() {{\n\
         \x20 {patch}\n\
         {body}\
         \x20 if (__bad.length > 0) throw new Error(\"unnamed: \" + __bad.join(\" | \"));\n\
         }}\n"
    );
    (source, model, !patch.is_empty())
}

pub fn run_input(data: &[u8]) {
    let (source, model, patched) = program(data);
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .expect("a runtime");
    let r = rt.block_on(run(&source, model, 4));
    let (ops, status) = r.unwrap_or_else(|f| panic!("the engine died or hung: {f:?}\n{source}"));
    for op in &ops {
        check_effect(&op.text, &op.effect.now, op.effect.wait.as_ref());
        assert!(op.text.chars().count() <= 202, "{}", op.text);
    }
    // A call not on the model fails the program before it starts, naming the call.
    if let Status::Failed(f) = status
        && !patched
        && !(f.message.contains(crate::edu::engine::FOUND_BEFORE) && f.message.contains("()"))
    {
        panic!("{model:?}: {f:?}\n{source}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Every call, and every native, with each hostile value in all its places, on a model
    /// it is on (a JavaScript engine per call: in a debug build each takes about a second,
    /// so every model is the sans-IO sweep's, `edu::api`'s tests).
    #[test]
    fn every_call_with_each_hostile_value() {
        for k in 0..CALLS.len() + NATIVES.len() {
            let on = |m: &Model| CALLS.get(k).is_none_or(|c| c.robots.applies(*m));
            let m = (0..Model::ALL.len())
                .map(|i| (i + k) % Model::ALL.len())
                .find(|i| on(&Model::ALL[*i]))
                .expect("a model the call is on");
            let mut data = vec![(m as u8) << 3];
            for v in 0..VALUES.len() {
                data.extend([k as u8, 3, v as u8, v as u8, v as u8]);
            }
            run_input(&data);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

        /// Random calls, arguments, models and replaced builtins.
        #[test]
        fn any_program_of_hostile_calls(data in prop::collection::vec(any::<u8>(), 0..160)) {
            run_input(&data);
        }
    }
}
