//! The documents never lie: every `droidctl …` command line shown in README.md and docs/*.md is
//! run here against the built binary (as trycmd and snapbox test documentation).
//!
//! The convention (what a document writer needs to know):
//! - Commands sit in fenced blocks tagged `console`, one per line starting with `$ droidctl `.
//!   Lines without `$ ` are expected output and are not checked; `$ ` lines of other programs
//!   (`$ export …`) are shown, not run. A line ending in ` \` goes on on the next line.
//! - A command must exit 0, or the status a line `# exit N` after it (before the next `$ `
//!   line) documents.
//! - Commands run as from the repository root (relative paths such as `assets/…`, `examples/…`
//!   reach the checkout), each block in its own scratch directory: files the commands write
//!   land there, so a block may write a file and read it back; `~` is a scratch home. `> FILE`
//!   at the end sends standard output to FILE, `< FILE` reads standard input from it; pipes,
//!   `&`, `;` and `$(…)` are refused (split the example, or show it in prose).
//! - The configuration is /dev/null, the state and log directories are scratch ones, and there
//!   is no D-Bus system bus (so no Bluetooth): use `--sim` and files committed in the repository.
//! - An HTML comment on the line just before a block says how its commands are run:
//!   `<!-- doc-test: until-killed -->` the command is started, must still run (or have exited 0)
//!   after 2 s, then is stopped; `<!-- doc-test: needs-hardware -->` the command is run and may
//!   fail for want of Bluetooth (exit 1), or wait for it, but never with a usage error (exit 2)
//!   or a crash; `<!-- doc-test: tty -->` the app runs in an 80×24 pseudo-terminal, is sent `q`
//!   once it has drawn, and must exit 0.
//! - A `droidctl` command line in any other fenced block (`sh`, `text`, untagged) is an error:
//!   every command shown is a command tested.

// Scratch directories are linked to the checkout with Unix symbolic links, and stopped
// commands get SIGTERM.
#![cfg(unix)]

use crate::common::pty;

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Exits,
    UntilKilled,
    NeedsHardware,
    Tty,
}

#[derive(Debug, Clone, PartialEq, Eq)]
struct DocCommand {
    line: usize,
    args: Vec<String>,
    stdin: Option<String>,
    stdout: Option<String>,
    exit: i32,
}

#[derive(Debug)]
struct Block {
    file: String,
    line: usize,
    mode: Mode,
    commands: Vec<DocCommand>,
}

/// Split a command line as a POSIX shell would for the words droidctl sees: quotes, `\`
/// escapes, a trailing `# comment`, `~/` at a word's start, and `>`/`<` redirections.
/// A command line's words, its standard input file and its standard output file.
type Words = (Vec<String>, Option<String>, Option<String>);

fn split_words(line: &str) -> Result<Words, String> {
    let mut words: Vec<String> = Vec::new();
    let (mut word, mut in_word, mut quote) = (String::new(), false, None::<char>);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some('"'), '\\') => word.extend(chars.next()),
            (Some(_), c) => word.push(c),
            (None, '\'' | '"') => (quote, in_word) = (Some(c), true),
            (None, '\\') => {
                word.extend(chars.next());
                in_word = true;
            }
            (None, ' ' | '\t') => {
                if in_word {
                    words.push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            (None, '#') if !in_word => break,
            (None, '|' | '&' | ';' | '`') => {
                return Err(format!(
                    "`{c}` is shell syntax the documents' tests do not run: split the example"
                ));
            }
            (None, '$') if chars.peek() == Some(&'(') => {
                return Err("`$(…)` is shell syntax the documents' tests do not run".into());
            }
            (None, '>' | '<') => {
                if in_word {
                    words.push(std::mem::take(&mut word));
                    in_word = false;
                }
                words.push(c.to_string());
            }
            (None, c) => {
                word.push(c);
                in_word = true;
            }
        }
    }
    if quote.is_some() {
        return Err("an unclosed quote".into());
    }
    if in_word {
        words.push(word);
    }
    let (mut args, mut stdin, mut stdout) = (Vec::new(), None, None);
    let mut it = words.into_iter();
    while let Some(w) = it.next() {
        match w.as_str() {
            ">" | "<" => {
                let Some(target) = it.next().filter(|t| t != ">" && t != "<") else {
                    return Err(format!("`{w}` without a file"));
                };
                let slot = if w == ">" { &mut stdout } else { &mut stdin };
                if slot.replace(target).is_some() {
                    return Err(format!("two `{w}` redirections"));
                }
            }
            _ if stdout.is_some() || stdin.is_some() => {
                return Err("words after a redirection".into());
            }
            _ => args.push(w),
        }
    }
    Ok((args, stdin, stdout))
}

/// Whether a line shows a droidctl command (not output such as `droidctl sim: …` or
/// `droidctl: error: …`), after an optional prompt.
fn shows_a_droidctl_command(line: &str) -> bool {
    let line = line.trim_start();
    let line = line.strip_prefix("$ ").unwrap_or(line);
    let mut words = line.split_whitespace();
    words.next() == Some("droidctl") && words.next().is_none_or(|w| !w.ends_with(':'))
}

/// The blocks of one document, or what breaks the convention, by line.
fn parse(file: &str, text: &str) -> (Vec<Block>, Vec<String>) {
    let (mut blocks, mut errors) = (Vec::new(), Vec::new());
    let lines: Vec<&str> = text.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let n = i + 1;
        let fence = line.trim_start();
        if let Some(rest) = line.trim().strip_prefix("<!-- doc-test:") {
            let what = rest.trim_end_matches("-->").trim();
            let opens_console = lines.get(i + 1).is_some_and(|l| l.trim() == "```console");
            if !["until-killed", "needs-hardware", "tty"].contains(&what) {
                errors.push(format!("{file}:{n}: unknown annotation `{what}`"));
            } else if !opens_console {
                errors.push(format!(
                    "{file}:{n}: `doc-test: {what}` must be on the line just before a ```console block"
                ));
            }
        }
        if !fence.starts_with("```") {
            i += 1;
            continue;
        }
        let tag = fence.trim_start_matches('`').trim();
        let body_start = i + 1;
        let mut end = body_start;
        while end < lines.len() && !lines[end].trim_start().starts_with("```") {
            end += 1;
        }
        if tag == "console" {
            let mode = match i.checked_sub(1).map(|p| lines[p].trim()) {
                Some("<!-- doc-test: until-killed -->") => Mode::UntilKilled,
                Some("<!-- doc-test: needs-hardware -->") => Mode::NeedsHardware,
                Some("<!-- doc-test: tty -->") => Mode::Tty,
                _ => Mode::Exits,
            };
            let mut commands: Vec<DocCommand> = Vec::new();
            let mut j = body_start;
            while j < end {
                let start = j;
                let mut cmd = lines[j].to_string();
                while cmd.ends_with('\\') && j + 1 < end {
                    cmd.pop();
                    j += 1;
                    cmd.push_str(lines[j].trim_start());
                }
                j += 1;
                let at = format!("{file}:{}", start + 1);
                if let Some(status) = cmd.trim().strip_prefix("# exit ") {
                    match (status.trim().parse::<i32>(), commands.last_mut()) {
                        (Ok(code), Some(last)) => last.exit = code,
                        (Err(_), _) => errors.push(format!("{at}: `# exit` needs a number")),
                        (_, None) => errors.push(format!("{at}: `# exit` before any command")),
                    }
                    continue;
                }
                if !cmd.starts_with("$ droidctl ") && cmd != "$ droidctl" {
                    if shows_a_droidctl_command(&cmd) {
                        errors.push(format!("{at}: a command line starts `$ droidctl `"));
                    }
                    continue;
                }
                match split_words(&cmd[2..]) {
                    Ok((words, stdin, stdout)) => commands.push(DocCommand {
                        line: start + 1,
                        args: words[1..].to_vec(),
                        stdin,
                        stdout,
                        exit: 0,
                    }),
                    Err(e) => errors.push(format!("{at}: {e}")),
                }
            }
            if mode == Mode::Tty && commands.len() != 1 {
                errors.push(format!(
                    "{file}:{n}: a `tty` block holds exactly one command"
                ));
            }
            if !commands.is_empty() {
                blocks.push(Block {
                    file: file.to_string(),
                    line: n,
                    mode,
                    commands,
                });
            }
        } else {
            for (k, l) in lines[body_start..end].iter().enumerate() {
                if shows_a_droidctl_command(l) {
                    errors.push(format!(
                        "{file}:{}: a droidctl command outside a ```console block (tag `{tag}`)",
                        body_start + k + 1
                    ));
                }
            }
        }
        i = end + 1;
    }
    (blocks, errors)
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn documents() -> Vec<(String, String)> {
    let mut names = vec!["README.md".to_string()];
    let mut docs: Vec<String> = std::fs::read_dir(repo().join("docs"))
        .expect("docs/")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".md"))
        .map(|n| format!("docs/{n}"))
        .collect();
    docs.sort();
    names.extend(docs);
    names
        .into_iter()
        .map(|n| {
            let text = std::fs::read_to_string(repo().join(&n)).unwrap();
            (n, text)
        })
        .collect()
}

/// A scratch directory that looks like the checkout (every top-level entry but `target` and
/// `.git` linked in), with its own home.
struct Scratch(PathBuf);

impl Scratch {
    fn new(k: usize) -> Scratch {
        let dir = std::env::temp_dir().join(format!("droidctl-docs-{}-{k}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("home")).unwrap();
        for entry in std::fs::read_dir(repo()).unwrap() {
            let name = entry.unwrap().file_name();
            if name != "target" && name != ".git" {
                std::os::unix::fs::symlink(repo().join(&name), dir.join(&name)).unwrap();
            }
        }
        Scratch(dir)
    }

    fn path(&self, p: &str) -> PathBuf {
        match p.strip_prefix("~/") {
            Some(rest) => self.0.join("home").join(rest),
            None => self.0.join(p),
        }
    }

    fn env(&self) -> Vec<(String, PathBuf)> {
        let home = self.0.join("home");
        [
            ("HOME", home.clone()),
            ("XDG_CONFIG_HOME", home.join(".config")),
            ("XDG_STATE_HOME", home.join(".local/state")),
            ("XDG_DATA_HOME", home.join(".local/share")),
            ("XDG_CACHE_HOME", home.join(".cache")),
            ("DROIDCTL_CONFIG", PathBuf::from("/dev/null")),
            ("DROIDCTL_LOG_FILE", self.0.join("droidctl.log")),
            (
                "DBUS_SYSTEM_BUS_ADDRESS",
                PathBuf::from(format!(
                    "unix:path={}",
                    self.0.join("no-system-bus").display()
                )),
            ),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }

    fn command(&self, c: &DocCommand) -> Command {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_droidctl"));
        cmd.args(c.args.iter().map(|a| match a.strip_prefix("~/") {
            Some(_) => self.path(a).into_os_string(),
            None => a.into(),
        }));
        cmd.current_dir(&self.0);
        for (k, v) in self.env() {
            cmd.env(k, v);
        }
        for k in [
            "DROIDCTL_LOG",
            "DROIDCTL_MQTT_PASSWORD",
            "DROIDCTL_DBUS_DAEMON",
        ] {
            cmd.env_remove(k);
        }
        cmd
    }

    fn spawn(&self, c: &DocCommand) -> Result<Child, String> {
        let mut cmd = self.command(c);
        cmd.stdin(match &c.stdin {
            Some(f) => {
                Stdio::from(std::fs::File::open(self.path(f)).map_err(|e| format!("< {f}: {e}"))?)
            }
            None => Stdio::null(),
        });
        cmd.stdout(match &c.stdout {
            Some(f) => {
                let p = self.path(f);
                std::fs::create_dir_all(p.parent().unwrap()).unwrap();
                Stdio::from(std::fs::File::create(&p).map_err(|e| format!("> {f}: {e}"))?)
            }
            None => Stdio::null(),
        });
        cmd.stderr(std::fs::File::create(self.0.join("stderr")).unwrap());
        cmd.spawn().map_err(|e| e.to_string())
    }

    fn stderr(&self) -> String {
        let text = std::fs::read_to_string(self.0.join("stderr")).unwrap_or_default();
        let lines: Vec<&str> = text.lines().collect();
        lines[lines.len().saturating_sub(6)..].join("\n")
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

use crate::common::cli::exited_within as wait;

/// SIGTERM (so a `sim --bluez` removes its bus), then SIGKILL if it does not end.
fn stop(child: &mut Child) {
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    if wait(child, Duration::from_secs(5)).is_none() {
        let _ = child.kill();
        let _ = child.wait();
    }
}

/// How long a command may take: missions against the simulator run in simulated time, so a
/// minute is far beyond any, even in a debug build on a busy machine.
const LIMIT: Duration = Duration::from_secs(60);
/// How long a command that waits for hardware is watched.
const HARDWARE_WATCH: Duration = Duration::from_secs(15);

fn run_one(scratch: &Scratch, mode: Mode, c: &DocCommand) -> Result<(), String> {
    if mode == Mode::Tty {
        return run_in_a_terminal(scratch, c);
    }
    let mut child = scratch.spawn(c)?;
    let status = match mode {
        Mode::Exits => wait(&mut child, LIMIT),
        Mode::UntilKilled => wait(&mut child, Duration::from_secs(2)),
        Mode::NeedsHardware | Mode::Tty => wait(&mut child, HARDWARE_WATCH),
    };
    let Some(status) = status else {
        stop(&mut child);
        return match mode {
            Mode::Exits => Err(format!("still running after {LIMIT:?}")),
            _ => Ok(()),
        };
    };
    let code = status.code();
    let ok = match mode {
        Mode::Exits => code == Some(c.exit),
        Mode::UntilKilled => code == Some(0),
        Mode::NeedsHardware | Mode::Tty => matches!(code, Some(0 | 1)),
    };
    if ok {
        return Ok(());
    }
    let wanted = match mode {
        Mode::Exits => format!("exit {}", c.exit),
        Mode::UntilKilled => "to keep running, or exit 0".into(),
        _ => "exit 0 or 1 (no Bluetooth), never 2 (usage) or a crash".into(),
    };
    Err(format!(
        "ended with {status}, wanted {wanted}; stderr:\n{}",
        scratch.stderr()
    ))
}

/// The app in an 80×24 pseudo-terminal: once it has drawn, `q` must end it with status 0.
fn run_in_a_terminal(scratch: &Scratch, c: &DocCommand) -> Result<(), String> {
    let plain = scratch.command(c);
    let args: Vec<String> = plain
        .get_args()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let env: Vec<(String, String)> = scratch
        .env()
        .into_iter()
        .map(|(k, v)| (k, v.to_string_lossy().into_owned()))
        .collect();
    let env: Vec<(&str, &str)> = env.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
    let mut tui = pty::Tui::spawn(&args, &env, (80, 24), Some(&scratch.0))?;
    let start = Instant::now();
    // Drawn: a few lines of the app are on screen.
    let drawn = |t: &pty::Tui| t.text().lines().filter(|l| !l.trim().is_empty()).count() >= 3;
    while !drawn(&tui) {
        if let Some(status) = tui.try_wait() {
            return Err(format!(
                "exited ({status:?}) before drawing:\n{}",
                tui.text()
            ));
        }
        if start.elapsed() > LIMIT {
            return Err(format!("drew nothing in {LIMIT:?}:\n{}", tui.text()));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    tui.send(b"q");
    let start = Instant::now();
    loop {
        if let Some(status) = tui.try_wait() {
            return if status.success() {
                Ok(())
            } else {
                Err(format!("`q` ended it with {status:?}:\n{}", tui.text()))
            };
        }
        if start.elapsed() > Duration::from_secs(20) {
            return Err(format!("`q` did not end it:\n{}", tui.text()));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn run_block(k: usize, block: &Block) -> Vec<String> {
    let scratch = Scratch::new(k);
    for c in &block.commands {
        if let Err(e) = run_one(&scratch, block.mode, c) {
            let shown = c.args.join(" ");
            return vec![format!(
                "{}:{}: `droidctl {shown}` ({:?}): {e}",
                block.file, c.line, block.mode
            )];
        }
    }
    Vec::new()
}

#[test]
fn every_command_in_the_documents_runs() {
    let mut blocks = Vec::new();
    let mut failures = Vec::new();
    for (file, text) in documents() {
        let (b, errors) = parse(&file, &text);
        blocks.extend(b);
        failures.extend(errors);
    }
    let commands: usize = blocks.iter().map(|b| b.commands.len()).sum();
    assert!(
        commands >= 40,
        "only {commands} commands found: is the convention still `$ droidctl ` in ```console?"
    );
    // Long-lived commands (relays, bridges, waits for hardware) take turns: they listen on the
    // documented ports. The rest run on every core.
    let (blocks, failures) = (Arc::new(blocks), Arc::new(Mutex::new(failures)));
    let (next, one_at_a_time) = (Arc::new(AtomicUsize::new(0)), Arc::new(Mutex::new(())));
    let workers = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .max(2)
        * 2;
    let handles: Vec<_> = (0..workers)
        .map(|_| {
            let (blocks, failures) = (blocks.clone(), failures.clone());
            let (next, one_at_a_time) = (next.clone(), one_at_a_time.clone());
            std::thread::spawn(move || {
                loop {
                    let k = next.fetch_add(1, Ordering::SeqCst);
                    let Some(block) = blocks.get(k) else { break };
                    let found = if matches!(block.mode, Mode::UntilKilled | Mode::NeedsHardware) {
                        let _turn = one_at_a_time.lock().unwrap_or_else(|e| e.into_inner());
                        run_block(k, block)
                    } else {
                        run_block(k, block)
                    };
                    failures.lock().unwrap().extend(found);
                }
            })
        })
        .collect();
    for h in handles {
        h.join().unwrap();
    }
    let failures = failures.lock().unwrap();
    assert!(
        failures.is_empty(),
        "{} of the documents' commands fail:\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}

#[test]
fn the_convention_is_read_as_documented() {
    let doc = "\
text `droidctl scan` in prose is not a command line\n\
```console\n\
$ droidctl packet decode 8D 0A # the wake\n\
wire 8D 0A\n\
$ droidctl run 'a b.txt' --sim > out.jsonl\n\
# exit 1\n\
$ export X=1\n\
```\n\
<!-- doc-test: until-killed -->\n\
```console\n\
$ droidctl serve --sim r2d2 \\\n\
    bb8\n\
```\n\
<!-- doc-test: tty -->\n\
```console\n\
$ droidctl --sim\n\
```\n\
```sh\n\
droidctl scan\n\
droidctl sim: D2-F206 (R2-D2) at D5:03:52:94:F2:06\n\
```\n\
```console\n\
$ droidctl run m.txt --sim | head -1\n\
droidctl packet list\n\
```\n\
<!-- doc-test: sometimes -->\n\
```console\n\
$ droidctl --sim < keys.txt\n\
```\n";
    let (blocks, errors) = parse("x.md", doc);
    let shape: Vec<(usize, Mode, Vec<DocCommand>)> = blocks
        .into_iter()
        .map(|b| (b.line, b.mode, b.commands))
        .collect();
    let cmd =
        |line: usize, args: &str, stdin: Option<&str>, stdout: Option<&str>, exit| DocCommand {
            line,
            args: args.split(' ').map(String::from).collect(),
            stdin: stdin.map(String::from),
            stdout: stdout.map(String::from),
            exit,
        };
    let mut run = cmd(5, "run a b.txt --sim", None, Some("out.jsonl"), 1);
    run.args = vec!["run".into(), "a b.txt".into(), "--sim".into()];
    assert_eq!(
        shape,
        vec![
            (
                2,
                Mode::Exits,
                vec![cmd(3, "packet decode 8D 0A", None, None, 0), run]
            ),
            (
                10,
                Mode::UntilKilled,
                vec![cmd(11, "serve --sim r2d2 bb8", None, None, 0)]
            ),
            (15, Mode::Tty, vec![cmd(16, "--sim", None, None, 0)]),
            (
                27,
                Mode::Exits,
                vec![cmd(28, "--sim", Some("keys.txt"), None, 0)]
            ),
        ]
    );
    assert_eq!(
        errors,
        vec![
            "x.md:19: a droidctl command outside a ```console block (tag `sh`)",
            "x.md:23: `|` is shell syntax the documents' tests do not run: split the example",
            "x.md:24: a command line starts `$ droidctl `",
            "x.md:26: unknown annotation `sometimes`",
        ]
    );
}

/// Every relative link in README and docs/ names a file of the checkout (a chapter renamed or
/// a file moved would otherwise send the reader nowhere).
#[test]
fn every_relative_link_in_the_documents_names_a_file() {
    let mut broken = Vec::new();
    for (name, text) in documents() {
        let dir = repo().join(&name).parent().unwrap().to_path_buf();
        let mut rest = text.as_str();
        while let Some(at) = rest.find("](") {
            rest = &rest[at + 2..];
            let Some(end) = rest.find(')') else { break };
            let target = &rest[..end];
            rest = &rest[end..];
            let file = target.split('#').next().unwrap_or("");
            if file.is_empty()
                || file.contains(char::is_whitespace)
                || file.starts_with("http://")
                || file.starts_with("https://")
                || file.starts_with("mailto:")
            {
                continue;
            }
            if !dir.join(file).exists() {
                broken.push(format!("{name}: {target}"));
            }
        }
    }
    assert!(
        broken.is_empty(),
        "links to nothing:\n{}",
        broken.join("\n")
    );
}
