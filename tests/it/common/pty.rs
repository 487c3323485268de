//! The app in a pseudo-terminal for end-to-end tests that drive `droidctl` as a person
//! would (shared by `relay_e2e.rs`, `sim_bluez.rs`, `edu_app.rs` and `docs_commands.rs`).

#![allow(dead_code)]

use portable_pty::{CommandBuilder, PtySize, native_pty_system};
use std::io::{Read, Write};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

pub struct Tui {
    screen: Arc<Mutex<vt100::Parser>>,
    writer: Arc<Mutex<Box<dyn Write + Send>>>,
    child: Box<dyn portable_pty::Child + Send + Sync>,
}

impl Tui {
    pub fn start(args: &[&str], env: &[(&str, &str)]) -> Tui {
        Tui::spawn(args, env, (100, 30), None).unwrap()
    }

    /// The app in a `cols`×`rows` terminal, started in `cwd` when given.
    pub fn spawn(
        args: &[&str],
        env: &[(&str, &str)],
        (cols, rows): (u16, u16),
        cwd: Option<&std::path::Path>,
    ) -> Result<Tui, String> {
        let pty = native_pty_system()
            .openpty(PtySize {
                rows,
                cols,
                pixel_width: 0,
                pixel_height: 0,
            })
            .map_err(|e| e.to_string())?;
        let mut cmd = CommandBuilder::new(env!("CARGO_BIN_EXE_droidctl"));
        cmd.args(args);
        if let Some(dir) = cwd {
            cmd.cwd(dir);
        }
        cmd.env("TERM", "xterm-256color");
        for (k, v) in env {
            cmd.env(k, v);
        }
        let child = pty.slave.spawn_command(cmd).map_err(|e| e.to_string())?;
        drop(pty.slave);
        let mut reader = pty.master.try_clone_reader().map_err(|e| e.to_string())?;
        let writer = Arc::new(Mutex::new(
            pty.master.take_writer().map_err(|e| e.to_string())?,
        ));
        let size = |v: u16| {
            v.try_into()
                .map_err(|_| "a terminal has rows and columns".to_string())
        };
        let screen = Arc::new(Mutex::new(vt100::Parser::new(size(rows)?, size(cols)?, 0)));
        let (screen2, answer) = (screen.clone(), writer.clone());
        std::thread::spawn(move || {
            let _keep_master = pty.master;
            let mut buf = [0u8; 8192];
            while let Ok(n) = reader.read(&mut buf) {
                if n == 0 {
                    break;
                }
                let chunk = &buf[..n];
                screen2.lock().unwrap().process(chunk);
                // Answer crossterm's capability probe as a legacy terminal.
                if chunk.windows(4).any(|w| w == b"\x1b[?u") {
                    let mut w = answer.lock().unwrap();
                    let _ = w.write_all(b"\x1b[?62;c");
                    let _ = w.flush();
                }
            }
        });
        Ok(Tui {
            screen,
            writer,
            child,
        })
    }

    /// Its exit status, if it has ended.
    pub fn try_wait(&mut self) -> Option<portable_pty::ExitStatus> {
        self.child.try_wait().ok().flatten()
    }

    /// The app's process id.
    pub fn pid(&self) -> Option<u32> {
        self.child.process_id()
    }

    /// Whether the terminal shows the alternate screen (the app's) rather than the normal one.
    pub fn alternate_screen(&self) -> bool {
        self.screen.lock().unwrap().screen().alternate_screen()
    }

    /// How many cells of the screen have a colour (foreground or background) of their own.
    pub fn coloured_cells(&self) -> usize {
        let parser = self.screen.lock().unwrap();
        let screen = parser.screen();
        let (rows, cols) = screen.size();
        let (rows, cols) = (rows.get(), cols.get());
        (0..rows)
            .flat_map(|r| (0..cols).map(move |c| (r, c)))
            .filter_map(|(r, c)| screen.cell(r, c))
            .filter(|cell| {
                cell.fgcolor() != vt100::Color::Default || cell.bgcolor() != vt100::Color::Default
            })
            .count()
    }

    pub fn text(&self) -> String {
        self.screen.lock().unwrap().screen().contents()
    }

    pub fn wait_for(&self, what: &str, limit: Duration) -> String {
        let start = Instant::now();
        loop {
            let t = self.text();
            if t.contains(what) {
                return t;
            }
            assert!(
                start.elapsed() < limit,
                "timed out waiting for {what:?}; screen:\n{t}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    pub fn send(&mut self, bytes: &[u8]) {
        let mut w = self.writer.lock().unwrap();
        let _ = w.write_all(bytes);
        let _ = w.flush();
    }

    /// A key held the way a legacy terminal reports it: press, then auto-repeats.
    pub fn hold(&mut self, key: &[u8], for_: Duration) {
        let start = Instant::now();
        while start.elapsed() < for_ {
            self.send(key);
            std::thread::sleep(Duration::from_millis(40));
        }
    }

    pub fn wait_exit(&mut self, limit: Duration) -> portable_pty::ExitStatus {
        let start = Instant::now();
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                return status;
            }
            assert!(
                start.elapsed() < limit,
                "droidctl did not exit; screen:\n{}",
                self.text()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Tui {
    fn drop(&mut self) {
        let _ = self.child.kill();
    }
}
