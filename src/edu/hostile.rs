//! Programs against droidctl's side of the engine (issue 37): the natives are not theirs to
//! call, and hostile values that reach them anyway are errors naming the call, not a panic
//! of the engine thread. The fuzz target `edu` (src/fuzzing/edu.rs) tries every call.

use crate::edu::api::{Act, Matrix};
use crate::edu::engine::{Op, Status};
use crate::edu::probe::run;
use crate::model::Model;

fn run_program(model: Model, body: &str) -> (Vec<Op>, Status) {
    let source = format!("async function startProgram() {{\n{body}\n}}\n");
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .unwrap();
    rt.block_on(run(&source, model, 8))
        .unwrap_or_else(|f| panic!("the engine died or hung: {f:?}"))
}

#[test]
fn the_natives_are_not_globals_and_calling_one_is_a_reference_or_type_error() {
    let (ops, status) = run_program(
        Model::Bolt,
        r#"
  const expect = (what, f, kinds) => {
    try { f(); } catch (e) {
      if (!kinds.some((k) => e instanceof k)) throw new Error(what + " threw " + e);
      return;
    }
    throw new Error(what + " did not throw");
  };
  for (const n of ["__call", "__read", "__on"]) {
    if (typeof globalThis[n] !== "undefined" || n in globalThis) throw new Error(n + " is a global");
    if (Object.getOwnPropertyNames(globalThis).includes(n)) throw new Error(n + " is listed");
    expect(n, () => eval(n)("scrollMatrixText", "HI", 1, 2, 3, NaN, 1), [ReferenceError]);
    expect("globalThis." + n, () => globalThis[n]("setSpeed", 1e19), [TypeError]);
  }
  expect("__call", () => __call("scrollMatrixText", "HI", 1, 2, 3, NaN, 1), [ReferenceError]);
  expect("__read", () => __read("getSpeed"), [ReferenceError]);
  expect("__on", () => __on("onCollision", () => 0), [ReferenceError]);
  // No global function of droidctl's is anything but the API (no natives under other names).
  for (const n of Object.getOwnPropertyNames(globalThis)) {
    if (n.startsWith("__")) throw new Error(n + " is a global");
  }
  // The API is still there.
  setSpeed(10);
"#,
    );
    assert_eq!(status, Status::Finished);
    assert_eq!(ops.len(), 1, "{ops:?}");
}

/// Once a NaN fps panicked the engine thread (fps 0, a division by zero) and the run waited
/// 5 s to blame a loop without `await`. A program that disables the prelude's check now gets
/// a RangeError naming the call, and Infinity is the fastest scroll.
#[test]
fn hostile_values_past_the_prelude_are_errors_naming_the_call_not_a_dead_engine() {
    let (ops, status) = run_program(
        Model::Bolt,
        r#"
  Number.isFinite = () => true;
  const named = (call, f) => {
    try { f(); } catch (e) {
      if (!(e instanceof RangeError || e instanceof TypeError) || !e.message.includes(call)) throw e;
      return;
    }
    throw new Error(call + " did not throw");
  };
  named("scrollMatrixText", () => scrollMatrixText("HI", { r: 1, g: 2, b: 3 }, NaN));
  named("setSpeed", () => setSpeed(NaN));
  named("roll", () => roll(NaN, 10, 1));
  named("spin", () => spin(Infinity, 1));
  named("delay", () => delay(Infinity));
  named("strobe", () => strobe({ r: 1, g: 2, b: 3 }, 0.05, 1e12));
  named("speak", () => speak("x".repeat(1 << 20)));
  String = (v) => v;
  named("setMatrixCharacter", () => setMatrixCharacter({ toString: () => "A" }, { r: 1, g: 2, b: 3 }));
  await scrollMatrixText("HI", { r: 1, g: 2, b: 3 }, Infinity);
"#,
    );
    assert_eq!(status, Status::Finished);
    let texts: Vec<&Act> = ops.iter().flat_map(|o| &o.effect.now).collect();
    assert_eq!(
        texts,
        vec![&Act::Matrix(Matrix::Text {
            text: "HI".into(),
            rgb: [1, 2, 3],
            fps: 30
        })]
    );
}

/// Issue 37's `setSpeed(1e19)` on Mini, through the engine: full speed forward.
#[test]
fn a_huge_speed_on_mini_is_full_speed_forward() {
    let (ops, status) = run_program(
        Model::Mini,
        r#"
  setSpeed(1e19);
  if (getSpeed() !== 255) throw new Error("getSpeed() is " + getSpeed());
  setSpeed(-1e19);
  if (getSpeed() !== -255) throw new Error("getSpeed() is " + getSpeed());
"#,
    );
    assert_eq!(status, Status::Finished, "{ops:?}");
    assert_eq!(
        ops[0].effect.now,
        vec![Act::Drive {
            speed: 255,
            heading: 0,
            reverse: false
        }]
    );
}
