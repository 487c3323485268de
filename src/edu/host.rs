//! droidctl's side of the engine: the child process ([`super::child`]) started, fed turns and
//! read, killed when a turn is late or the run ends, and what happened to it said in one line
//! when it dies.
//!
//! Three threads per child, none of them the runtime's: one writes frames to its stdin (a
//! child that stops reading cannot block droidctl), one reads frames from its stdout (and says
//! when the pipe closes: the child is gone), one keeps the last few KiB of its stderr (Rust's
//! own words when it aborts: a stack overflow, a failed allocation). A turn is awaited in
//! `spawn_blocking`, which holds tokio's paused clock still while the program computes.

use super::api::{Arg, Driver};
use super::child::{DEFAULT_MEMORY_MIB, ENGINE_ARG};
use super::engine::{Call, Event, Failure, Op, Readings, SyntaxError, TurnOut};
use super::wire::{self, FrameError, FromChild, ToChild};
use crate::model::Model;
use crate::sync::lock;
use std::collections::HashMap;
use std::io::Read;
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex, mpsc};
use std::time::Duration;

/// How the engine's child is started.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EngineOptions {
    /// The droidctl binary to start as the engine; `None`: `DROIDCTL_ENGINE_EXE`, else this
    /// executable (library users whose executable is not droidctl, tests among them, say).
    pub exe: Option<PathBuf>,
    /// The memory the program may use, MiB (bounded on Linux).
    pub memory_mib: u64,
}

impl Default for EngineOptions {
    fn default() -> Self {
        EngineOptions {
            exe: None,
            memory_mib: DEFAULT_MEMORY_MIB,
        }
    }
}

impl EngineOptions {
    fn exe(&self) -> Result<PathBuf, String> {
        if let Some(p) = &self.exe {
            return Ok(p.clone());
        }
        if let Some(p) = std::env::var_os("DROIDCTL_ENGINE_EXE") {
            return Ok(PathBuf::from(p));
        }
        std::env::current_exe()
            .map_err(|e| format!("cannot find droidctl's own executable to run the program: {e}"))
    }
}

/// Why a program could not be checked.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CheckError {
    /// A syntax error, with its place.
    #[error("{}:{}: {}", .0.line, .0.column, .0.message)]
    Syntax(SyntaxError),
    /// The parser itself could not get through it (the check's child died).
    #[error("{0}")]
    Unparsable(String),
    /// The engine could not be started.
    #[error("{0}")]
    Engine(String),
}

/// The longest a syntax check may take (a 4 MiB program parses in well under a second).
const CHECK_LIMIT: Duration = Duration::from_secs(60);
/// The bytes of the child's stderr kept for the message when it dies.
const STDERR_TAIL: usize = 4096;
/// A call as the output and the log show it, at most (`speak` of a megabyte says less).
const MAX_TEXT: usize = 1000;
/// Promises droidctl keeps track of at once (the engine allows 1,000 waiting).
const MAX_TRACKED: usize = 10_000;

/// Parse `source` in a child of its own: a syntax error with its place, and a program too
/// deeply nested for the parser an error rather than the end of droidctl.
pub fn check(source: &str, path: &str, opts: &EngineOptions) -> Result<(), CheckError> {
    let proc = Proc::spawn(opts).map_err(CheckError::Engine)?;
    proc.send(ToChild::Check {
        source: source.to_string(),
        path: path.to_string(),
    });
    let got = proc.receive(CHECK_LIMIT);
    let r = checked(&proc, got, opts);
    // Ended (or killed now) and reaped: no zombie left behind.
    proc.kill();
    r
}

/// What a check's child answered, as droidctl says it.
fn checked(proc: &Proc, got: Got, opts: &EngineOptions) -> Result<(), CheckError> {
    match got {
        Got::Message(FromChild::Checked(None)) => Ok(()),
        Got::Message(FromChild::Checked(Some(e))) => Err(CheckError::Syntax(e)),
        Got::Late => Err(CheckError::Unparsable(format!(
            "the program could not be parsed in {} s",
            CHECK_LIMIT.as_secs()
        ))),
        Got::Message(_) | Got::Gone(_) => {
            let (status, said) = proc.ended();
            match why(&said, opts.memory_mib) {
                Some(why) => Err(CheckError::Unparsable(format!(
                    "the program cannot be parsed: {why} ({})",
                    how(status)
                ))),
                None if !proc.ready() => Err(CheckError::Engine(not_engine(opts))),
                None => Err(CheckError::Unparsable(format!(
                    "the program cannot be parsed: the engine ended ({}){}",
                    how(status),
                    last_line(&said)
                ))),
            }
        }
    }
}

/// The calls a child reports, played through droidctl's own [`Driver`]: the same calls in
/// the same order give the effects the engine saw, and bytes from the child can ask for
/// nothing the API would not do.
pub struct Calls {
    driver: Driver,
    /// The promises waiting, and whether each stops the target speed when it resolves.
    stops: HashMap<u64, bool>,
}

/// The engine, seen from droidctl's side.
pub struct Engine {
    proc: Proc,
    calls: Calls,
    memory_mib: u64,
    exe_shown: String,
}

impl Engine {
    /// Start the engine's child for `source` on `model`. Nothing runs until the first turn.
    pub fn start(
        source: String,
        path: String,
        model: Model,
        opts: &EngineOptions,
    ) -> Result<Engine, String> {
        let proc = Proc::spawn(opts)?;
        proc.send(ToChild::Start {
            source,
            path,
            model: model.id().to_string(),
        });
        Ok(Engine {
            proc,
            calls: Calls::new(model),
            memory_mib: opts.memory_mib,
            exe_shown: not_engine(opts),
        })
    }

    /// Run one turn. `limit` bounds how long the program may compute without waiting (wall
    /// clock): past it the child is killed and the run fails.
    pub async fn turn(
        &mut self,
        fired: Vec<u64>,
        events: Vec<Event>,
        readings: Readings,
        limit: Duration,
    ) -> Result<TurnOut, TurnError> {
        self.calls.fired(&fired);
        self.proc.send(ToChild::Turn {
            fired,
            events,
            readings: wire::finite(readings),
        });
        let proc = self.proc.clone();
        // In `spawn_blocking`: tokio's paused clock stands still while the program computes.
        let got = tokio::task::spawn_blocking(move || proc.receive(limit))
            .await
            .unwrap_or(Got::Gone(FrameError::Closed));
        match got {
            Got::Message(FromChild::Done(reply)) => {
                let ops = self.calls.play(reply.calls).map_err(TurnError::Failed)?;
                let listening = reply
                    .listening
                    .iter()
                    .filter_map(|name| {
                        super::calls::EVENTS
                            .iter()
                            .find(|e| e.0 == name)
                            .map(|e| e.0)
                    })
                    .collect();
                Ok(TurnOut {
                    ops,
                    status: reply.status,
                    listening,
                })
            }
            Got::Late => {
                // Killed, so no thread and no core stays busy with it.
                self.proc.kill();
                Err(TurnError::Failed(Failure {
                    line: None,
                    message: format!(
                        "the program computed for {} s without waiting: a loop without `await` \
                         (e.g. `await delay(0.1)`) never lets the robot move",
                        limit.as_secs_f64()
                    ),
                }))
            }
            Got::Message(_) => {
                self.proc.kill();
                Err(TurnError::Died)
            }
            Got::Gone(e @ (FrameError::TooLong(..) | FrameError::Garbled(_)))
                if self.proc.ready() =>
            {
                // Alive but not making sense (its memory damaged?): it goes.
                self.proc.kill();
                Err(TurnError::Failed(Failure {
                    line: None,
                    message: format!("the program's engine sent {e}"),
                }))
            }
            Got::Gone(_) => Err(TurnError::Died),
        }
    }

    /// Wait until the child is gone (it died, or was killed): the run must stop the droid.
    pub async fn gone(&self) {
        let mut gone = self.proc.gone.clone();
        let _ = gone.wait_for(|g| *g).await;
    }

    /// What happened to the child, in one line (it is gone, or is killed now).
    pub async fn failure(&self) -> Failure {
        let proc = self.proc.clone();
        let (status, said) = tokio::task::spawn_blocking(move || proc.ended())
            .await
            .unwrap_or((None, String::new()));
        let message = match why(&said, self.memory_mib) {
            Some(why) => format!("the program's engine crashed ({}): {why}", how(status)),
            None if !self.proc.ready() => self.exe_shown.clone(),
            None if killed(status) => format!("the program's engine was killed ({})", how(status)),
            None => format!(
                "the program's engine crashed ({}){}",
                how(status),
                last_line(&said)
            ),
        };
        Failure {
            line: None,
            message,
        }
    }
}

impl Calls {
    pub fn new(model: Model) -> Calls {
        Calls {
            driver: Driver::new(model),
            stops: HashMap::new(),
        }
    }

    /// The promises a turn resolves: those of calls that stop leave the target speed at 0.
    pub fn fired(&mut self, ids: &[u64]) {
        for id in ids {
            if self.stops.remove(id) == Some(true) {
                self.driver.stopped();
            }
        }
    }

    /// The calls of a turn as effects, through droidctl's own [`Driver`].
    pub fn play(&mut self, calls: Vec<Call>) -> Result<Vec<Op>, Failure> {
        let mut ops = Vec::with_capacity(calls.len());
        for call in calls {
            let args: Vec<Arg> = call.args.iter().map(Arg::from).collect();
            let public = call.name.trim_end_matches("Brightness");
            let effect = self.driver.call(&call.name, &args).map_err(|m| Failure {
                line: Some(call.line),
                message: format!("the engine made a call droidctl refuses: {public}: {m}"),
            })?;
            if let (Some(id), Some(_)) = (call.promise, &effect.wait) {
                if self.stops.len() >= MAX_TRACKED {
                    return Err(Failure {
                        line: Some(call.line),
                        message: format!("more than {MAX_TRACKED} calls waiting at once"),
                    });
                }
                self.stops.insert(id, effect.stops);
            }
            let mut text = super::engine::shown(public, &args);
            if text.len() > MAX_TEXT {
                let cut = (0..=MAX_TEXT)
                    .rev()
                    .find(|&i| text.is_char_boundary(i))
                    .unwrap_or(0);
                text.truncate(cut);
                text.push('…');
            }
            ops.push(Op {
                line: call.line,
                text,
                effect,
                promise: call.promise,
            });
        }
        Ok(ops)
    }
}

impl Drop for Engine {
    fn drop(&mut self) {
        // The run is over: the child goes with it, however busy.
        self.proc.kill();
    }
}

/// Why a turn gave no calls.
#[derive(Debug)]
pub enum TurnError {
    /// The run fails for this reason.
    Failed(Failure),
    /// The child is gone: stop the droid, then ask [`Engine::failure`] what happened (it
    /// waits for the child's status and last words, a few milliseconds).
    Died,
}

/// What a wait for the child's next message gave.
enum Got {
    Message(FromChild),
    Late,
    Gone(FrameError),
}

/// One child process and the threads that talk to it.
#[derive(Clone)]
struct Proc {
    child: Arc<Mutex<Child>>,
    to: mpsc::Sender<ToChild>,
    from: Arc<Mutex<mpsc::Receiver<Result<FromChild, FrameError>>>>,
    /// Whether the first frame said this is droidctl's engine.
    ready: Arc<std::sync::atomic::AtomicBool>,
    gone: tokio::sync::watch::Receiver<bool>,
    /// The end of the child's stderr, and whether it has closed.
    stderr: Arc<Mutex<(Vec<u8>, bool)>>,
}

impl Proc {
    fn spawn(opts: &EngineOptions) -> Result<Proc, String> {
        let exe = opts.exe()?;
        let mut cmd = Command::new(&exe);
        cmd.arg(ENGINE_ARG)
            .arg(opts.memory_mib.to_string())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        // Its own process group: Ctrl+c at the terminal is droidctl's to handle (it stops the
        // droid, then ends the child), not the child's to die of first.
        #[cfg(unix)]
        std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
        let mut child = cmd
            .spawn()
            .map_err(|e| format!("cannot start the program's engine ({}): {e}", exe.display()))?;
        let (Some(mut stdin), Some(mut stdout), Some(mut stderr)) =
            (child.stdin.take(), child.stdout.take(), child.stderr.take())
        else {
            let _ = child.kill();
            let _ = child.wait();
            return Err("cannot talk to the program's engine".into());
        };
        let (to, to_rx) = mpsc::channel::<ToChild>();
        // Bounded: a child sending frames faster than turns take them waits for droidctl.
        let (from_tx, from) = mpsc::sync_channel(2);
        let (gone_tx, gone) = tokio::sync::watch::channel(false);
        let tail = Arc::new(Mutex::new((Vec::new(), false)));
        let threads = [
            std::thread::Builder::new()
                .name("edu-engine-in".into())
                .spawn(move || write_all(&mut stdin, to_rx)),
            std::thread::Builder::new()
                .name("edu-engine-out".into())
                .spawn(move || {
                    loop {
                        let m = wire::read::<FromChild>(&mut stdout, wire::MAX_FROM_CHILD);
                        let end = m.is_err();
                        if from_tx.send(m).is_err() || end {
                            break;
                        }
                    }
                    let _ = gone_tx.send(true);
                }),
            {
                let tail = tail.clone();
                std::thread::Builder::new()
                    .name("edu-engine-err".into())
                    .spawn(move || keep_tail(&mut stderr, &tail))
            },
        ];
        let proc = Proc {
            child: Arc::new(Mutex::new(child)),
            to,
            from: Arc::new(Mutex::new(from)),
            ready: Default::default(),
            gone,
            stderr: tail,
        };
        if threads.iter().any(Result::is_err) {
            proc.kill();
            return Err("cannot start the threads that talk to the program's engine".into());
        }
        Ok(proc)
    }

    fn send(&self, m: ToChild) {
        // A child gone is found when its answer is waited for.
        let _ = self.to.send(m);
    }

    fn ready(&self) -> bool {
        self.ready.load(std::sync::atomic::Ordering::SeqCst)
    }

    /// The child's next message (after its `Ready`), within `limit`. Blocking.
    fn receive(&self, limit: Duration) -> Got {
        let from = lock(&self.from);
        let end = std::time::Instant::now() + limit;
        loop {
            let left = end.saturating_duration_since(std::time::Instant::now());
            match from.recv_timeout(left) {
                Ok(Ok(FromChild::Ready { version })) if !self.ready() => {
                    if version != wire::VERSION {
                        return Got::Gone(FrameError::Garbled(format!(
                            "an engine of protocol {version}, not {}",
                            wire::VERSION
                        )));
                    }
                    self.ready.store(true, std::sync::atomic::Ordering::SeqCst);
                }
                Ok(Ok(m)) if self.ready() => return Got::Message(m),
                Ok(Ok(_)) => {
                    return Got::Gone(FrameError::Garbled("a message before `Ready`".into()));
                }
                Ok(Err(e)) => return Got::Gone(e),
                Err(mpsc::RecvTimeoutError::Timeout) => return Got::Late,
                Err(mpsc::RecvTimeoutError::Disconnected) => return Got::Gone(FrameError::Closed),
            }
        }
    }

    /// Kill the child (SIGKILL) and reap it on a thread of its own.
    fn kill(&self) {
        let _ = lock(&self.child).kill();
        let child = self.child.clone();
        let _ = std::thread::Builder::new()
            .name("edu-engine-reap".into())
            .spawn(move || {
                let _ = lock(&child).wait();
            });
    }

    /// How the child ended and the end of what it wrote to stderr: its status is waited for
    /// briefly (its pipe closes just before it is reaped), then it is killed. Blocking.
    fn ended(&self) -> (Option<ExitStatus>, String) {
        let end = std::time::Instant::now() + Duration::from_millis(500);
        let status = loop {
            if let Ok(Some(s)) = lock(&self.child).try_wait() {
                break Some(s);
            }
            if std::time::Instant::now() >= end {
                let mut c = lock(&self.child);
                let _ = c.kill();
                break c.wait().ok();
            }
            std::thread::sleep(Duration::from_millis(1));
        };
        // The stderr reader reaches the end of the pipe once the child is gone.
        let until = std::time::Instant::now() + Duration::from_millis(100);
        let said = loop {
            let t = lock(&self.stderr);
            if t.1 || std::time::Instant::now() >= until {
                break String::from_utf8_lossy(&t.0).into_owned();
            }
            drop(t);
            std::thread::sleep(Duration::from_millis(1));
        };
        (status, said)
    }
}

fn write_all(stdin: &mut ChildStdin, rx: mpsc::Receiver<ToChild>) {
    for m in rx {
        if wire::write(stdin, &m, wire::MAX_TO_CHILD).is_err() {
            break;
        }
    }
}

/// Keep the last [`STDERR_TAIL`] bytes the child writes to stderr.
fn keep_tail(stderr: &mut impl Read, tail: &Mutex<(Vec<u8>, bool)>) {
    let mut buf = [0u8; 1024];
    loop {
        match stderr.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => {
                let mut t = lock(tail);
                t.0.extend_from_slice(&buf[..n]);
                let over = t.0.len().saturating_sub(STDERR_TAIL);
                t.0.drain(..over);
            }
        }
    }
    lock(tail).1 = true;
}

/// What Rust said before the child aborted, as the program's mistake.
fn why(said: &str, memory_mib: u64) -> Option<String> {
    if said.contains("has overflowed its stack") {
        Some("the program is too deeply nested or recursive (the engine's stack overflowed)".into())
    } else if said.contains("memory allocation of") || said.contains("out of memory") {
        Some(format!(
            "the program used more than its {memory_mib} MiB of memory (--program-memory)"
        ))
    } else {
        None
    }
}

/// `signal 6, SIGABRT` or `exit status 3`.
fn how(status: Option<ExitStatus>) -> String {
    let Some(status) = status else {
        return "no exit status".into();
    };
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(n) = status.signal() {
            let name = match n {
                2 => "SIGINT",
                4 => "SIGILL",
                6 => "SIGABRT",
                7 => "SIGBUS",
                9 => "SIGKILL",
                11 => "SIGSEGV",
                15 => "SIGTERM",
                24 => "SIGXCPU",
                _ => "",
            };
            return if name.is_empty() {
                format!("signal {n}")
            } else {
                format!("signal {n}, {name}")
            };
        }
    }
    match status.code() {
        Some(c) => format!("exit status {c}"),
        None => "no exit status".into(),
    }
}

/// Ended by SIGKILL: by droidctl, the kernel's OOM killer, or someone else.
fn killed(status: Option<ExitStatus>) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        status.and_then(|s| s.signal()) == Some(9)
    }
    #[cfg(not(unix))]
    {
        let _ = status;
        false
    }
}

/// `: <the child's last line>` when it said anything.
fn last_line(said: &str) -> String {
    said.lines()
        .rev()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .map(|l| format!(": {}", l.chars().take(200).collect::<String>()))
        .unwrap_or_default()
}

fn not_engine(opts: &EngineOptions) -> String {
    let exe = opts
        .exe()
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    format!(
        "the program's engine did not start: {exe} is not droidctl (set DROIDCTL_ENGINE_EXE \
         to droidctl's executable)"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_abort_is_said_as_the_programs_mistake() {
        let overflow = "\nthread 'edu-program' has overflowed its stack\nfatal runtime error: stack overflow\n";
        assert!(why(overflow, 512).unwrap().contains("too deeply nested"));
        let oom = "memory allocation of 8388608 bytes failed\n";
        assert!(why(oom, 64).unwrap().contains("64 MiB"));
        assert_eq!(why("anything else", 512), None);
        assert_eq!(last_line("a\nlast words\n\n"), ": last words");
    }
}
