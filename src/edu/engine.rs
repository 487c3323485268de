//! The JavaScript engine: Boa on a thread of its own, driven in turns.
//!
//! Why a thread: a program that never yields (`while (true) {}`) must not hang droidctl. Boa
//! cannot be interrupted from outside, so it runs where it can spin without stopping anyone.
//! The thread runs in a child process of its own ([`super::child`]): droidctl's side
//! ([`super::host`]) keeps serving Ctrl+c, the emergency stop and `--timeout`, kills the child
//! when a turn is late, and stops the droid whatever happens to the child (a stack overflow,
//! running out of memory, a kill).
//!
//! Why turns: the program's promises are droidctl's clock. A turn hands the engine what
//! happened (promises due, events, the latest readings), the engine runs every job that
//! became ready, and hands back the calls the program made, in order, with their JS line.
//! droidctl waits for a turn in `spawn_blocking`, which holds tokio's paused clock still
//! while the program computes: under `--sim` a turn takes no simulated time at all, exactly as
//! if the program ran between two packets, and a 60 s program runs in well under a second.
//!
//! A turn hands back the calls as made ([`Call`]: name, arguments, line), not their effects:
//! droidctl's side plays each through its own [`Driver`], so what reaches the droid is what
//! the API does with the call, whatever bytes come from the child.

use super::api::{Arg, Driver, Effect, MAX_ARGS, MAX_TEXT};
use super::calls;
use crate::model::Model;
use boa_engine::object::FunctionObjectBuilder;
use boa_engine::object::builtins::{JsArray, JsFunction, JsPromise};
use boa_engine::{
    Context, JsError, JsNativeError, JsResult, JsValue, NativeFunction, Source, js_string,
};
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::mpsc;

/// The JS API as programs see it (Sphero Edu's names and shapes).
const PRELUDE: &str = include_str!("prelude.js");
const PRELUDE_PATH: &str = "droidctl-edu-prelude.js";
/// A program's loops may turn this often in one function call before it throws: the
/// engine thread of a run that was abandoned (Ctrl+c on `while (true) {}`) ends by itself.
pub(super) const LOOP_LIMIT: u64 = 50_000_000;
/// JavaScript calls deep (Boa's own bound, past which it stops the program): the engine's
/// thread has a large stack ([`super::child`]), so deep but legal recursion fits.
pub(super) const RECURSION_LIMIT: usize = 10_000;
/// Calls a program may make in one turn (between two waits), and promises it may leave
/// waiting at once: a runaway loop of calls is an error, not unbounded memory.
const MAX_CALLS_PER_TURN: usize = 1_000;
const MAX_PENDING: usize = 1_000;

type NativeFnPtr = fn(&JsValue, &[JsValue], &mut Context) -> JsResult<JsValue>;

/// A syntax error: where, and what.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SyntaxError {
    pub line: u32,
    pub column: u32,
    pub message: String,
}

/// Why a program stopped before its end.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Failure {
    /// The program's line, when known.
    pub line: Option<u32>,
    pub message: String,
}

/// What the robot measures, as the program reads it (a snapshot per turn).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Readings {
    pub location: Option<[f32; 2]>,
    pub velocity: Option<[f32; 2]>,
    pub orientation: Option<[f32; 3]>,
    pub acceleration: Option<[f32; 3]>,
    pub vertical_acceleration: Option<f32>,
    pub gyroscope: Option<[f32; 3]>,
    pub distance: f32,
    pub elapsed_s: f64,
    pub luminosity: Option<f32>,
    pub color: Option<[u8; 3]>,
    pub compass: Option<u16>,
    pub battery_v: Option<f32>,
    pub ir_message: Option<u8>,
}

/// An event a program can register for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Event {
    Collision,
    Freefall,
    Landing,
    GyroMax,
    Charging,
    NotCharging,
    IrMessage(u8),
    Color([u8; 3]),
}

impl Event {
    pub fn name(self) -> &'static str {
        match self {
            Event::Collision => "onCollision",
            Event::Freefall => "onFreefall",
            Event::Landing => "onLanding",
            Event::GyroMax => "onGyroMax",
            Event::Charging => "onCharging",
            Event::NotCharging => "onNotCharging",
            Event::IrMessage(_) => "onIRMessage",
            Event::Color(_) => "onColor",
        }
    }
}

/// One call the program made.
#[derive(Debug, Clone, PartialEq)]
pub struct Op {
    /// The program's line that made it.
    pub line: u32,
    /// The call as written (`roll(90, 100, 2)`), for the output.
    pub text: String,
    pub effect: Effect,
    /// The promise to resolve once the effect's wait is over (`None`: it returned at once).
    pub promise: Option<u64>,
}

/// Where the program stands after a turn.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Status {
    Running,
    /// `startProgram` returned and no event is registered, or `exitProgram()` was called.
    Finished,
    Failed(Failure),
}

/// A turn's result, as droidctl plays it.
#[derive(Debug, Clone, PartialEq)]
pub struct TurnOut {
    pub ops: Vec<Op>,
    pub status: Status,
    /// The events the program listens for (by name).
    pub listening: Vec<&'static str>,
}

/// One call the program made, as the engine saw it: what droidctl's side needs to play it
/// through its own [`Driver`] (the same calls in the same order give the same effects).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Call {
    pub line: u32,
    pub name: String,
    pub args: Vec<CallArg>,
    /// The promise the call returned, when it waits.
    pub promise: Option<u64>,
}

/// An argument of a [`Call`]; a number travels as its bits, so NaN and infinities arrive as
/// they left (JSON has no spelling for them).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum CallArg {
    Num(u64),
    Text(String),
}

impl From<&Arg> for CallArg {
    fn from(a: &Arg) -> CallArg {
        match a {
            Arg::Num(n) => CallArg::Num(n.to_bits()),
            Arg::Text(t) => CallArg::Text(t.clone()),
        }
    }
}

impl From<&CallArg> for Arg {
    fn from(a: &CallArg) -> Arg {
        match a {
            CallArg::Num(bits) => Arg::Num(f64::from_bits(*bits)),
            CallArg::Text(t) => Arg::Text(t.clone()),
        }
    }
}

/// A turn's result as the engine hands it back.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reply {
    pub calls: Vec<Call>,
    pub status: Status,
    pub listening: Vec<String>,
}

/// Parse `source` without running it: a syntax error with its line and column. The parser
/// recurses on the program's nesting: this runs in the engine's child
/// ([`super::host::check`]), where a stack overflow ends only the child.
pub(super) fn check(source: &str, path: &str) -> Result<(), SyntaxError> {
    let mut ctx = Context::default();
    let src = Source::from_bytes(source).with_path(std::path::Path::new(path));
    match boa_engine::Script::parse(src, None, &mut ctx) {
        Ok(_) => {}
        Err(e) => {
            let text = e.to_string();
            // `… in argument list at line 4, col 1 (native)`: the place is said apart.
            let message = text
                .rfind(" at line ")
                .map_or(text.as_str(), |at| &text[..at])
                .trim_end_matches(" (native)")
                .to_string();
            let ((line, column), message) =
                super::syntax::explained(source, &message, line_col(&text));
            return Err(SyntaxError {
                line,
                column,
                message,
            });
        }
    }
    if let Some((c, message)) = super::names::unknown_call(source) {
        return Err(SyntaxError {
            line: c.line,
            column: c.column,
            message,
        });
    }
    if !source.contains("startProgram") {
        return Err(SyntaxError {
            line: 1,
            column: 1,
            message: "a Sphero Edu program defines `async function startProgram() { … }`".into(),
        });
    }
    Ok(())
}

/// `line 3, col 7` or `:3:7` in an engine message.
fn line_col(message: &str) -> Option<(u32, u32)> {
    if let Some(at) = message.rfind("line ") {
        let rest = &message[at + 5..];
        let line: String = rest.chars().take_while(char::is_ascii_digit).collect();
        let col = rest
            .find("col")
            .map(|c| {
                rest[c..]
                    .chars()
                    .skip_while(|ch| !ch.is_ascii_digit())
                    .take_while(char::is_ascii_digit)
                    .collect::<String>()
            })
            .unwrap_or_default();
        if let (Ok(l), Ok(c)) = (line.parse(), col.parse()) {
            return Some((l, c));
        }
    }
    None
}

/// The program's line in an error's backtrace (`at startProgram (square.js:3:5)`).
fn line_in(text: &str, path: &str) -> Option<u32> {
    let key = format!("{path}:");
    let at = text.find(&key)?;
    text[at + key.len()..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect::<String>()
        .parse()
        .ok()
}

/// What the engine thread is handed: a turn.
pub(super) enum ToJs {
    Turn {
        fired: Vec<u64>,
        events: Vec<Event>,
        readings: Readings,
    },
}

/// What the engine thread hands back.
pub(super) enum FromJs {
    Done(Reply),
}

/// The engine thread's state, reached by the native functions.
struct Js {
    driver: Driver,
    path: String,
    ops: Vec<Call>,
    next_promise: u64,
    /// Each promise waiting: its resolver, whether the target speed is 0 once it resolves,
    /// and the line of the call that made it.
    pending: HashMap<u64, (JsFunction, bool, u32)>,
    /// The line of the last call whose promise resolved: where the program went on from.
    resumed: Option<u32>,
    readings: Readings,
    handlers: Vec<(&'static str, JsFunction)>,
    /// Promises of `startProgram` and of event handlers: a rejection fails the program.
    watched: Vec<JsPromise>,
    main: Option<JsPromise>,
    exit: bool,
}

thread_local! {
    static JS: RefCell<Option<Js>> = const { RefCell::new(None) };
    /// The program's source, for [`refine_line`].
    static SOURCE: RefCell<String> = const { RefCell::new(String::new()) };
}

fn with_js<T>(f: impl FnOnce(&mut Js) -> T) -> Option<T> {
    JS.with(|j| j.borrow_mut().as_mut().map(f))
}

/// The engine: `source` on `model`, one turn per [`ToJs`], until the program ends or the
/// channel closes. It runs on a thread of the engine's child process ([`super::child`]).
pub(super) fn js_thread(
    source: String,
    path: String,
    model: Model,
    to_js: mpsc::Receiver<ToJs>,
    reply: mpsc::Sender<FromJs>,
) {
    SOURCE.with(|s| *s.borrow_mut() = source.clone());
    let mut ctx = Context::builder()
        .host_hooks(super::unhandled::hooks())
        .build()
        .unwrap_or_default();
    ctx.runtime_limits_mut()
        .set_loop_iteration_limit(LOOP_LIMIT);
    ctx.runtime_limits_mut()
        .set_recursion_limit(RECURSION_LIMIT);
    JS.with(|j| {
        *j.borrow_mut() = Some(Js {
            driver: Driver::new(model),
            path: path.clone(),
            ops: Vec::new(),
            next_promise: 0,
            pending: HashMap::new(),
            resumed: None,
            readings: Readings::default(),
            handlers: Vec::new(),
            watched: Vec::new(),
            main: None,
            exit: false,
        })
    });
    let mut started = false;
    while let Ok(ToJs::Turn {
        fired,
        events,
        readings,
    }) = to_js.recv()
    {
        with_js(|js| js.readings = readings);
        let r = if started {
            turn(&mut ctx, fired, events)
        } else {
            started = true;
            start(&mut ctx, &source, &path)
        };
        let status = match r {
            Err(e) if e.as_native().is_some_and(|n| n.message() == NOT_ON_ROBOT) => {
                Status::Failed(not_on_robot(&source, model))
            }
            Ok(()) => status(&mut ctx),
            Err(e) => Status::Failed(failure(&e, &path, &mut ctx)),
        };
        let out = with_js(|js| Reply {
            calls: std::mem::take(&mut js.ops),
            status,
            listening: js.handlers.iter().map(|h| h.0.to_string()).collect(),
        });
        let Some(out) = out else { break };
        let end = out.status != Status::Running;
        if reply.send(FromJs::Done(out)).is_err() || end {
            break;
        }
    }
    // Drop the engine's objects before the engine.
    JS.with(|j| j.borrow_mut().take());
}

/// The error [`start`] ends with when the program calls something this robot does not have
/// ([`not_on_robot`] says which and where).
const NOT_ON_ROBOT: &str = "droidctl: a call not on this robot";

/// How the failure of a program calling what its robot does not have ends: nothing of the
/// program ran.
pub const FOUND_BEFORE: &str = "(found before anything was sent)";

/// The first call of `source` that `model` does not have, as a failure at its line.
fn not_on_robot(source: &str, model: Model) -> Failure {
    let called = super::names::called_from_outside(source).unwrap_or_default();
    match super::names::not_on_robot(&called, model) {
        Some((line, why)) => Failure {
            line: Some(line),
            message: format!("TypeError: {why} {FOUND_BEFORE}"),
        },
        None => Failure {
            line: None,
            message: "a call is not on this robot".into(),
        },
    }
}

fn start(ctx: &mut Context, source: &str, path: &str) -> JsResult<()> {
    // Every call the program makes by name is on this robot, or nothing runs: a call it does
    // not have is found before the first is sent, not when the program reaches it.
    let model = with_js(|js| js.driver.model).unwrap_or(Model::DEFAULT);
    if let Some(called) = super::names::called_from_outside(source)
        && super::names::not_on_robot(&called, model).is_some()
    {
        return Err(JsNativeError::typ().with_message(NOT_ON_ROBOT).into());
    }
    // The prelude is a function of the natives: they are its arguments, never globals, so a
    // program cannot call them past the prelude's checks.
    let prelude = Source::from_bytes(PRELUDE).with_path(std::path::Path::new(PRELUDE_PATH));
    let install = ctx.eval(prelude)?;
    let Some(install) = install.as_function() else {
        return Err(JsNativeError::error()
            .with_message("droidctl's prelude is not a function")
            .into());
    };
    let natives: [JsValue; 3] = [
        (js_string!("call"), 1, native_call as NativeFnPtr),
        (js_string!("read"), 1, native_read),
        (js_string!("on"), 2, native_on),
    ]
    .map(|(name, length, f)| {
        FunctionObjectBuilder::new(ctx.realm(), NativeFunction::from_fn_ptr(f))
            .name(name)
            .length(length)
            .build()
            .into()
    });
    install.call(&JsValue::undefined(), &natives, ctx)?;
    let program = Source::from_bytes(source).with_path(std::path::Path::new(path));
    ctx.eval(program)?;
    ctx.run_jobs()?;
    let start = ctx.global_object().get(js_string!("startProgram"), ctx)?;
    let Some(f) = start.as_function() else {
        return Err(JsNativeError::reference()
            .with_message("the program has no `async function startProgram()`")
            .into());
    };
    let v = f.call(&JsValue::undefined(), &[], ctx)?;
    if let Some(p) = v.as_promise() {
        with_js(|js| {
            js.main = Some(p.clone());
            js.watched.push(p);
        });
    } else {
        // A plain `function startProgram()`: done when it returned.
        let done = JsPromise::resolve(JsValue::undefined(), ctx)?;
        with_js(|js| js.main = Some(done));
    }
    ctx.run_jobs()
}

fn turn(ctx: &mut Context, fired: Vec<u64>, events: Vec<Event>) -> JsResult<()> {
    for id in fired {
        let resolve = with_js(|js| {
            let (f, stops, line) = js.pending.remove(&id)?;
            if stops {
                js.driver.stopped();
            }
            js.resumed = Some(line);
            Some(f)
        })
        .flatten();
        if let Some(resolve) = resolve {
            resolve.call(&JsValue::undefined(), &[], ctx)?;
        }
    }
    ctx.run_jobs()?;
    for e in events {
        let handlers: Vec<JsFunction> = with_js(|js| {
            js.handlers
                .iter()
                .filter(|h| h.0 == e.name())
                .map(|h| h.1.clone())
                .collect()
        })
        .unwrap_or_default();
        let arg = match e {
            Event::IrMessage(ch) => JsValue::from(ch),
            Event::Color([r, g, b]) => {
                let o = JsValue::from(boa_engine::object::ObjectInitializer::new(ctx).build());
                if let Some(obj) = o.as_object() {
                    obj.set(js_string!("r"), r, false, ctx)?;
                    obj.set(js_string!("g"), g, false, ctx)?;
                    obj.set(js_string!("b"), b, false, ctx)?;
                }
                o
            }
            _ => JsValue::undefined(),
        };
        for h in handlers {
            let v = h.call(&JsValue::undefined(), std::slice::from_ref(&arg), ctx)?;
            if let Some(p) = v.as_promise() {
                with_js(|js| js.watched.push(p));
            }
        }
        ctx.run_jobs()?;
    }
    Ok(())
}

fn status(ctx: &mut Context) -> Status {
    use boa_engine::builtins::promise::PromiseState;
    let path = with_js(|js| js.path.clone()).unwrap_or_default();
    let watched = with_js(|js| std::mem::take(&mut js.watched)).unwrap_or_default();
    let mut keep = Vec::new();
    for p in watched {
        match p.state() {
            PromiseState::Rejected(v) => {
                let e = JsError::from_opaque(v);
                return Status::Failed(failure(&e, &path, ctx));
            }
            PromiseState::Pending => keep.push(p),
            PromiseState::Fulfilled(_) => {}
        }
    }
    // An `async` call not awaited that threw: its error, and where.
    for p in super::unhandled::take() {
        let p = JsPromise::from(p);
        if let PromiseState::Rejected(v) = p.state() {
            let f = failure(&JsError::from_opaque(v), &path, ctx);
            return Status::Failed(Failure {
                line: f.line,
                message: format!(
                    "{} (in an async call that was not awaited: add `await` before it, or \
                     catch its error)",
                    f.message
                ),
            });
        }
    }
    let (exit, main_done, listening, waiting, resumed) = with_js(|js| {
        js.watched = keep;
        let done = js
            .main
            .as_ref()
            .is_some_and(|m| matches!(m.state(), PromiseState::Fulfilled(_)));
        (
            js.exit,
            done,
            !js.handlers.is_empty(),
            !js.pending.is_empty(),
            js.resumed,
        )
    })
    .unwrap_or((true, true, false, false, None));
    if exit || (main_done && !listening) {
        Status::Finished
    } else if !main_done && !listening && !waiting {
        // Nothing droidctl does can resolve what `startProgram` waits for, and no event can
        // run: the program can never go on. Either it awaits a promise nothing resolves, or
        // the engine's recursion or loop limit ended it after an `await`: Boa drops that
        // error when it resumes an async function (its `await` closures discard the
        // completion), leaving the promise pending, so which one and where is not known
        // here; the line is that of the `await` the program last went on from. Without this,
        // a run in simulated time would go on forever.
        Status::Failed(Failure {
            line: resumed,
            message: format!(
                "the program can go no further{}: it waits for a promise that nothing \
                 resolves, or the engine ended too much recursion (more than \
                 {RECURSION_LIMIT} calls deep) or a loop that ran {LOOP_LIMIT} times without \
                 an `await`",
                if resumed.is_some() {
                    " (after the `await` on this line)"
                } else {
                    ""
                }
            ),
        })
    } else {
        Status::Running
    }
}

/// An uncaught exception as the user sees it: its message and the program's line.
fn failure(e: &JsError, path: &str, ctx: &mut Context) -> Failure {
    use boa_engine::error::{EngineError, RuntimeLimitError};
    let text = e.to_string();
    if let Some(EngineError::RuntimeLimit(limit)) = e.as_engine() {
        // The engine's own limits, said as the program's mistake (their text names Boa's
        // internals); the line, when the backtrace has one.
        let message = match limit {
            RuntimeLimitError::Recursion => {
                format!("too much recursion: more than {RECURSION_LIMIT} calls deep")
            }
            RuntimeLimitError::LoopIteration => {
                format!("a loop ran {LOOP_LIMIT} times without an `await`")
            }
            RuntimeLimitError::StackSize => {
                "too much recursion: the engine's value stack is full".to_string()
            }
        };
        return Failure {
            line: line_in(&text, path).or_else(|| with_js(|js| js.resumed).flatten()),
            message,
        };
    }
    // `throw new Error("x")`: the message is the error object's; the line its stack's.
    let mut message = text.lines().next().unwrap_or("").trim().to_string();
    if let Ok(v) = e.clone().into_opaque(ctx)
        && let Some(o) = v.as_object()
        && let Ok(m) = o.get(js_string!("message"), ctx)
        && let Ok(n) = o.get(js_string!("name"), ctx)
        && !m.is_undefined()
    {
        message = format!(
            "{}: {}",
            n.to_string(ctx)
                .map(|s| s.to_std_string_escaped())
                .unwrap_or_default(),
            m.to_string(ctx)
                .map(|s| s.to_std_string_escaped())
                .unwrap_or_default()
        );
    }
    let line = line_in(&text, path).map(|l| refine_line(l, &message, path));
    // Strip the engine's own ` at path:line:col` decoration from the first line.
    if let Some(at) = message.find(&format!(" at {path}")) {
        message.truncate(at);
    }
    Failure { line, message }
}

/// Boa places the errors its VM throws (`x is not defined`) at the start of the function
/// they happened in, not at their line; the name the message gives is looked for from there
/// on in the program's source (kept by the thread), and its first use is the line.
fn refine_line(line: u32, message: &str, _path: &str) -> u32 {
    let name: String = message
        .split_once(": ")
        .map_or(message, |(_, m)| m)
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == '$' || *c == '.')
        .collect();
    let known = message.contains(" is not defined") || message.contains(" is not a");
    if name.is_empty() || !known {
        return line;
    }
    let name = name.rsplit('.').next().unwrap_or(&name).to_string();
    SOURCE.with(|s| {
        s.borrow()
            .lines()
            .enumerate()
            .skip(line.saturating_sub(1) as usize)
            .find(|(_, l)| {
                l.match_indices(name.as_str()).any(|(at, _)| {
                    let before = l[..at].chars().last();
                    let after = l[at + name.len()..].chars().next();
                    let ident =
                        |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
                    !ident(before) && !ident(after)
                })
            })
            .map_or(line, |(i, _)| i as u32 + 1)
    })
}

/// The program's line making the current native call.
fn user_line(ctx: &Context, path: &str) -> u32 {
    ctx.stack_trace()
        .map(|f| f.position())
        .find(|p| p.path.to_string() == path)
        .and_then(|p| p.position)
        .map(|p| p.line_number())
        .unwrap_or(0)
}

/// A native's first argument, the name of what is asked: a short string, or `""` (which no
/// call, reading or event has).
fn name_of(args: &[JsValue]) -> String {
    args.first()
        .and_then(JsValue::as_string)
        .filter(|s| s.len() <= 64)
        .map(|s| s.to_std_string_escaped())
        .unwrap_or_default()
}

/// Call `name`'s arguments as the prelude passes them: numbers and texts (a boolean is 1 or
/// 0). Anything else is a TypeError naming the call (a program that replaces `String` or an
/// array's iterator can make the prelude pass an object, `undefined` or a symbol; no user
/// code runs to convert it), and so are more than [`MAX_ARGS`] arguments or a text longer
/// than [`MAX_TEXT`], refused before they are copied. The numbers are checked again by
/// [`Driver::call`].
fn args_of(name: &str, args: &[JsValue]) -> JsResult<Vec<Arg>> {
    let refuse = |m: String| JsError::from(JsNativeError::typ().with_message(m));
    if args.len() > MAX_ARGS {
        return Err(refuse(format!(
            "{name}: {} arguments; a call takes at most {MAX_ARGS}",
            args.len()
        )));
    }
    args.iter()
        .enumerate()
        .map(|(i, v)| {
            if let Some(s) = v.as_string() {
                if s.len() > MAX_TEXT {
                    return Err(refuse(format!(
                        "{name}: a text of {} characters; droidctl takes at most {MAX_TEXT}",
                        s.len()
                    )));
                }
                Ok(Arg::Text(s.to_std_string_escaped()))
            } else if let Some(n) = v.as_number() {
                Ok(Arg::Num(n))
            } else if let Some(b) = v.as_boolean() {
                Ok(Arg::Num(if b { 1.0 } else { 0.0 }))
            } else {
                Err(refuse(format!(
                    "{name}: argument {} is {}, not a number or a text",
                    i + 1,
                    if v.is_null() { "null" } else { v.type_of() }
                )))
            }
        })
        .collect()
}

/// A call as the output shows it (`roll(90, 100, 2)`).
pub(super) fn shown(name: &str, args: &[Arg]) -> String {
    if name == "registerMatrixAnimation" {
        // Its arguments are every pixel of every frame: say what they amount to.
        let n = |i: usize| match args.get(i) {
            Some(Arg::Num(v)) => *v,
            _ => 0.0,
        };
        let colours = n(2);
        let frames = n(3 + 3 * colours.clamp(0.0, 16.0) as usize);
        return format!("{name}({frames} frames, {colours} colours, {} fps)", n(0));
    }
    let parts: Vec<String> = args
        .iter()
        .map(|a| match a {
            Arg::Num(n) => format!("{n}"),
            Arg::Text(t) => format!("{t:?}"),
        })
        .collect();
    let text = format!("{name}({})", parts.join(", "));
    // Bounded: 4000 numbers of 309 digits each (1e308) would be a megabyte a call.
    const MAX_SHOWN: usize = 200;
    match text.char_indices().nth(MAX_SHOWN) {
        Some((at, _)) => format!("{}…)", &text[..at]),
        None => text,
    }
}

fn native_call(_this: &JsValue, args: &[JsValue], ctx: &mut Context) -> JsResult<JsValue> {
    let name = name_of(args);
    let rest = args_of(&name, args.get(1..).unwrap_or(&[]))?;
    let (model, path) = with_js(|js| (js.driver.model, js.path.clone()))
        .ok_or_else(|| JsNativeError::error().with_message("no program"))?;
    // The table's name (`setBackLed(255)` arrives as `setBackLedBrightness`).
    let public = name.trim_end_matches("Brightness");
    if let Some(why) = calls::not_on(public, model) {
        return Err(JsNativeError::typ().with_message(why).into());
    }
    let line = user_line(ctx, &path);
    let (calls, pending) = with_js(|js| (js.ops.len(), js.pending.len())).unwrap_or_default();
    if calls >= MAX_CALLS_PER_TURN || pending >= MAX_PENDING {
        return Err(JsNativeError::range()
            .with_message(format!(
                "more than {MAX_CALLS_PER_TURN} calls without waiting, or {MAX_PENDING} \
                 waiting at once: is an `await` missing?"
            ))
            .into());
    }
    let effect = with_js(|js| js.driver.call(&name, &rest))
        .unwrap_or_else(|| Err("no program".into()))
        .map_err(|m| JsNativeError::range().with_message(m))?;
    let call = |promise| Call {
        line,
        name: name.clone(),
        args: rest.iter().map(CallArg::from).collect(),
        promise,
    };
    if effect.wait.is_none() {
        let exit = effect.exit;
        with_js(|js| {
            js.exit |= exit;
            js.ops.push(call(None))
        });
        return Ok(JsValue::undefined());
    }
    let (promise, resolvers) = JsPromise::new_pending(ctx);
    with_js(|js| {
        let id = js.next_promise;
        js.next_promise += 1;
        js.pending
            .insert(id, (resolvers.resolve, effect.stops, line));
        js.ops.push(call(Some(id)));
    });
    Ok(promise.into())
}

fn native_read(_this: &JsValue, args: &[JsValue], ctx: &mut Context) -> JsResult<JsValue> {
    let name = name_of(args);
    let model = with_js(|js| js.driver.model).unwrap_or(Model::DEFAULT);
    if let Some(why) = calls::not_on(&name, model) {
        return Err(JsNativeError::typ().with_message(why).into());
    }
    enum V {
        N(Option<f64>),
        A(Option<Vec<f64>>),
    }
    let v = with_js(|js| {
        let r = &js.readings;
        let arr = |a: Option<&[f32]>| V::A(a.map(|a| a.iter().map(|v| *v as f64).collect()));
        match name.as_str() {
            "getLocation" => arr(r.location.as_ref().map(|a| &a[..])),
            "getVelocity" => arr(r.velocity.as_ref().map(|a| &a[..])),
            "getOrientation" => arr(r.orientation.as_ref().map(|a| &a[..])),
            "getAcceleration" => arr(r.acceleration.as_ref().map(|a| &a[..])),
            "getGyroscope" => arr(r.gyroscope.as_ref().map(|a| &a[..])),
            "getVerticalAcceleration" => V::N(r.vertical_acceleration.map(f64::from)),
            "getSpeed" => V::N(Some(js.driver.speed as f64)),
            "getHeading" => V::N(Some(js.driver.heading as f64)),
            "getDistance" => V::N(Some(r.distance as f64)),
            "getElapsedTime" => V::N(Some(r.elapsed_s)),
            "getLuminosity" => V::N(r.luminosity.map(f64::from)),
            "getColor" => V::A(r.color.map(|c| c.iter().map(|v| *v as f64).collect())),
            "getCompassDirection" => V::N(r.compass.map(f64::from)),
            "getBatteryVoltage" => V::N(r.battery_v.map(f64::from)),
            "getMainLed" => V::A(Some(js.driver.main.iter().map(|v| *v as f64).collect())),
            "getFrontLed" => V::A(Some(js.driver.front.iter().map(|v| *v as f64).collect())),
            "getBackLed" => V::A(Some(js.driver.back.iter().map(|v| *v as f64).collect())),
            "getColorChannel" => V::A(r.color.map(|c| c.iter().map(|v| *v as f64).collect())),
            "getCurrentTime" => V::N(Some(r.elapsed_s)),
            "getLastIRMessage" => V::N(r.ir_message.map(f64::from)),
            _ => V::N(None),
        }
    })
    .unwrap_or(V::N(None));
    Ok(match v {
        V::N(Some(n)) => JsValue::from(n),
        V::A(Some(a)) => JsArray::from_iter(a.into_iter().map(JsValue::from), ctx).into(),
        _ => JsValue::null(),
    })
}

fn native_on(_this: &JsValue, args: &[JsValue], _ctx: &mut Context) -> JsResult<JsValue> {
    let name = name_of(args);
    let Some(event) = calls::EVENTS.iter().find(|e| e.0 == name) else {
        return Err(JsNativeError::typ()
            .with_message(format!(
                "registerEvent: {name} is not an EventType droidctl knows"
            ))
            .into());
    };
    let model = with_js(|js| js.driver.model).unwrap_or(Model::DEFAULT);
    if !event.1.applies(model) {
        return Err(JsNativeError::typ()
            .with_message(format!(
                "registerEvent: {name} is not on {} (it is on {})",
                model.display_name(),
                event.1.names()
            ))
            .into());
    }
    let Some(f) = args.get(1).and_then(JsValue::as_function) else {
        return Err(JsNativeError::typ()
            .with_message("registerEvent: needs a function to call")
            .into());
    };
    with_js(|js| js.handlers.push((event.0, f)));
    Ok(JsValue::undefined())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_syntax_error_has_its_line_and_column() {
        let e = check(
            "async function startProgram() {\n  roll(0, 50, 1;\n}\n",
            "p.js",
        )
        .unwrap_err();
        assert_eq!(e.line, 2, "{e:?}");
        assert!(e.column > 1, "{e:?}");
    }
}
