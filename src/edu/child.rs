//! The engine's child process: droidctl started again as `droidctl __droidctl-edu-engine
//! MEMORY_MIB`, running one program's engine ([`super::engine`]) or one syntax check, and
//! speaking the turn protocol ([`super::wire`]) on its stdin and stdout.
//!
//! Why a process: what a program does inside Boa can end the process it runs in. Deep
//! nesting (`String()` of an array nested 20,000 deep, `eval` of a million parentheses)
//! overflows the native stack and aborts; a program that keeps what it allocates runs out of
//! memory and aborts. In a child, that ends only the child: droidctl, which owns the droids,
//! the capture and the terminal, stops the droid and says what happened ([`super::host`]).
//!
//! What bounds the child:
//! - its stack: the engine runs on a thread of [`STACK`] bytes (reserved, not used), so deep
//!   but legal programs fit;
//! - its memory (Linux): `RLIMIT_DATA` of the memory asked for (`--program-memory`, 512 MiB by
//!   default) plus the stack and a margin for the runtime; past it an allocation fails and
//!   the child aborts;
//! - its time: droidctl kills it when a turn is late, and it ends by itself when droidctl's
//!   end of the pipe closes (droidctl gone, even by SIGKILL), however busy the engine is.
//!
//! Windows and macOS run the same child, bounded in stack and time but not in memory
//! (docs/edu-programs.md says so).

use super::engine::{self, FromJs, Status, ToJs};
use super::wire::{self, FromChild, ToChild};
use crate::model::Model;
use std::sync::mpsc;

/// The argument that makes droidctl the engine (checked first thing in `main`).
pub const ENGINE_ARG: &str = "__droidctl-edu-engine";
/// The engine thread's stack: reserved address space, touched only as deep as a program
/// nests.
pub const STACK: usize = 256 << 20;
/// The memory a program may use by default, MiB.
pub const DEFAULT_MEMORY_MIB: u64 = 512;
/// Room in the memory limit for what is not the program's: the runtime's own threads and
/// allocations, the binary's writable data.
const MARGIN: u64 = 64 << 20;

/// The child's `main`: `args` are those after [`ENGINE_ARG`]. Returns the exit status.
pub fn serve(args: &[String]) -> i32 {
    let memory_mib = args
        .first()
        .and_then(|a| a.parse::<u64>().ok())
        .unwrap_or(DEFAULT_MEMORY_MIB);
    limit_memory(memory_mib);
    let mut out = std::io::stdout();
    let hello = FromChild::Ready {
        version: wire::VERSION,
    };
    if wire::write(&mut out, &hello, wire::MAX_FROM_CHILD).is_err() {
        return 1;
    }
    let mut input = std::io::stdin();
    let first: ToChild = match wire::read(&mut input, wire::MAX_TO_CHILD) {
        Ok(m) => m,
        Err(_) => return 1,
    };
    match first {
        ToChild::Check { source, path } => {
            let Some(r) = on_engine_stack(move || engine::check(&source, &path)) else {
                return 1;
            };
            match wire::write(&mut out, &FromChild::Checked(r.err()), wire::MAX_FROM_CHILD) {
                Ok(()) => 0,
                Err(_) => 1,
            }
        }
        ToChild::Start {
            source,
            path,
            model,
        } => {
            let Some(model) = Model::from_id(&model) else {
                return 2;
            };
            run(source, path, model, input, out)
        }
        ToChild::Turn { .. } => 2,
    }
}

/// The program's engine: turns read from `input` on a thread of their own, replies written
/// to `out` here.
fn run(
    source: String,
    path: String,
    model: Model,
    mut input: std::io::Stdin,
    mut out: std::io::Stdout,
) -> i32 {
    let (tx, to_js) = mpsc::channel::<ToJs>();
    let (reply, from_js) = mpsc::channel::<FromJs>();
    let spawned = std::thread::Builder::new()
        .name("edu-program".into())
        .stack_size(STACK)
        .spawn(move || engine::js_thread(source, path, model, to_js, reply));
    if spawned.is_err() {
        return 1;
    }
    // The pipe closing ends the child at once, even with the engine in a loop: droidctl has
    // ended the run, or is gone.
    let reader = std::thread::Builder::new()
        .name("edu-pipe".into())
        .spawn(move || {
            loop {
                match wire::read::<ToChild>(&mut input, wire::MAX_TO_CHILD) {
                    Ok(ToChild::Turn {
                        fired,
                        events,
                        readings,
                    }) => {
                        let turn = ToJs::Turn {
                            fired,
                            events,
                            readings,
                        };
                        if tx.send(turn).is_err() {
                            std::process::exit(0);
                        }
                    }
                    Ok(_) => std::process::exit(2),
                    Err(_) => std::process::exit(0),
                }
            }
        });
    if reader.is_err() {
        return 1;
    }
    for FromJs::Done(r) in from_js {
        let end = r.status != Status::Running;
        let listening = r.listening.clone();
        match wire::write(&mut out, &FromChild::Done(r), wire::MAX_FROM_CHILD) {
            Ok(()) => {}
            Err(wire::FrameError::TooLong(n, max)) => {
                let failed = FromChild::Done(engine::Reply {
                    calls: Vec::new(),
                    status: Status::Failed(engine::Failure {
                        line: None,
                        message: format!(
                            "the program did more in one turn than droidctl takes ({n} bytes \
                             of calls, at most {max}): is an `await` missing?"
                        ),
                    }),
                    listening,
                });
                let _ = wire::write(&mut out, &failed, wire::MAX_FROM_CHILD);
                return 1;
            }
            Err(_) => return 1,
        }
        if end {
            break;
        }
    }
    0
}

/// `f` on a thread with the engine's stack; `None` when it could not start or panicked.
fn on_engine_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> Option<T> {
    std::thread::Builder::new()
        .name("edu-check".into())
        .stack_size(STACK)
        .spawn(f)
        .ok()?
        .join()
        .ok()
}

/// Bound the process's memory: `RLIMIT_DATA` counts the heap and every private writable
/// mapping (the engine's stack among them), not the binary's code, so the program gets
/// `mib` MiB and the stack and margin come on top.
#[cfg(target_os = "linux")]
fn limit_memory(mib: u64) {
    let bytes = mib
        .saturating_mul(1 << 20)
        .saturating_add(STACK as u64)
        .saturating_add(MARGIN);
    let limit = libc::rlimit {
        rlim_cur: bytes as libc::rlim_t,
        rlim_max: bytes as libc::rlim_t,
    };
    // SAFETY: setrlimit reads the struct it is given; a failure leaves the limit as it was.
    unsafe {
        libc::setrlimit(libc::RLIMIT_DATA, &limit);
    }
}

/// Not bounded here (docs/edu-programs.md).
#[cfg(not(target_os = "linux"))]
fn limit_memory(_mib: u64) {
    let _ = MARGIN;
}
