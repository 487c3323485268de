//! A real MQTT broker for the bridge's tests: `mosquitto` (Debian's; `.ci/run` installs it
//! with `mosquitto-clients`) on a free loopback port with a temporary config, stopped when
//! dropped; `mosquitto_sub` and `mosquitto_pub` as the outside client.

#![allow(dead_code)]

use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// A program of the mosquitto packages: on PATH, or where Debian puts the broker.
pub fn program(name: &str) -> PathBuf {
    for dir in std::env::var("PATH")
        .unwrap_or_default()
        .split(':')
        .chain(["/usr/sbin", "/usr/bin"])
    {
        let p = Path::new(dir).join(name);
        if p.is_file() {
            return p;
        }
    }
    panic!(
        "{name} is not installed: the bridge's MQTT tests need a real broker \
         (apt-get install mosquitto mosquitto-clients; .ci/run installs them)"
    );
}

/// A free loopback port (bound, then released).
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

pub struct Broker {
    child: Child,
    pub port: u16,
    pub dir: PathBuf,
    extra: String,
}

fn am_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

impl Broker {
    /// An anonymous broker on loopback.
    pub fn start(dir: &Path) -> Broker {
        Broker::start_with(dir, free_port(), "allow_anonymous true\n")
    }

    /// A broker on `port` with `extra` config lines (its listener is always loopback only).
    pub fn start_with(dir: &Path, port: u16, extra: &str) -> Broker {
        std::fs::create_dir_all(dir).unwrap();
        let conf = dir.join(format!("mosquitto-{port}.conf"));
        // As root, mosquitto would drop to its own user and lose the test's files.
        let user = if am_root() { "user root\n" } else { "" };
        std::fs::write(
            &conf,
            format!("{user}persistence false\nlog_dest stderr\nlistener {port} 127.0.0.1\n{extra}"),
        )
        .unwrap();
        let child = Command::new(program("mosquitto"))
            .arg("-c")
            .arg(&conf)
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(dir.join(format!("mosquitto-{port}.log"))).unwrap())
            .spawn()
            .expect("start mosquitto");
        let b = Broker {
            child,
            port,
            dir: dir.to_path_buf(),
            extra: extra.to_string(),
        };
        b.wait_listening();
        b
    }

    fn wait_listening(&self) {
        let end = Instant::now() + Duration::from_secs(10);
        while std::net::TcpStream::connect(("127.0.0.1", self.port)).is_err() {
            assert!(
                Instant::now() < end,
                "mosquitto does not listen on {}: {}",
                self.port,
                std::fs::read_to_string(self.dir.join(format!("mosquitto-{}.log", self.port)))
                    .unwrap_or_default()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Kill the broker (as a crash would: no goodbye to its clients).
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Start it again on the same port.
    pub fn restart(&mut self) {
        self.kill();
        let mut again = Broker::start_with(&self.dir, self.port, &self.extra.clone());
        std::mem::swap(&mut self.child, &mut again.child);
        // `again` now holds the dead broker: dropping it only waits for it.
    }

    pub fn url(&self) -> String {
        format!("mqtt://127.0.0.1:{}", self.port)
    }
}

impl Drop for Broker {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `mosquitto_sub -v` on `topic` (wildcards allowed): (topic, payload as JSON) as they
/// come. Extra arguments (`--cafile`, `-u`) go before the topic.
pub struct Sub {
    child: Child,
    pub rx: mpsc::Receiver<(String, Value)>,
}

impl Sub {
    pub fn start(port: u16, topic: &str, extra: &[&str]) -> Sub {
        let mut child = Command::new(program("mosquitto_sub"))
            .args(["-h", "127.0.0.1", "-p", &port.to_string(), "-v", "-q", "1"])
            .args(extra)
            .args(["-t", topic])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start mosquitto_sub");
        let out = child.stdout.take().unwrap();
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for l in BufReader::new(out).lines() {
                let Ok(l) = l else { return };
                let Some((t, p)) = l.split_once(' ') else {
                    continue;
                };
                let v: Value = serde_json::from_str(p).unwrap_or(Value::String(p.into()));
                if tx.send((t.to_string(), v)).is_err() {
                    return;
                }
            }
        });
        // mosquitto_sub says nothing when it has subscribed: give it a moment.
        std::thread::sleep(Duration::from_millis(300));
        Sub { child, rx }
    }

    /// The next message on `topic` for which `f` holds, within `secs`.
    pub fn wait(&self, secs: u64, topic: &str, f: impl Fn(&Value) -> bool) -> Value {
        let end = Instant::now() + Duration::from_secs(secs);
        let mut seen = Vec::new();
        while let Some(left) = end.checked_duration_since(Instant::now()) {
            match self.rx.recv_timeout(left) {
                Ok((t, v)) if t == topic && f(&v) => return v,
                Ok((t, v)) => {
                    if seen.len() < 20 {
                        seen.push(format!("{t} {v}"));
                    }
                }
                Err(_) => break,
            }
        }
        panic!("no matching message on {topic} within {secs} s; among others: {seen:#?}");
    }

    /// A message for which `f` holds on each of `topics` (in any order), within `secs`.
    pub fn wait_all(&self, secs: u64, topics: &[String], f: impl Fn(&Value) -> bool) {
        let end = Instant::now() + Duration::from_secs(secs);
        let mut missing: Vec<&String> = topics.iter().collect();
        while !missing.is_empty() {
            let Some(left) = end.checked_duration_since(Instant::now()) else {
                break;
            };
            match self.rx.recv_timeout(left) {
                Ok((t, v)) if f(&v) => missing.retain(|m| **m != t),
                Ok(_) => {}
                Err(_) => break,
            }
        }
        assert!(
            missing.is_empty(),
            "nothing matching on {missing:?} within {secs} s"
        );
    }

    /// Everything received so far.
    pub fn drain(&self) -> Vec<(String, Value)> {
        self.rx.try_iter().collect()
    }
}

impl Drop for Sub {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `mosquitto_pub` one message.
pub fn publish(port: u16, topic: &str, payload: &str, extra: &[&str]) -> bool {
    Command::new(program("mosquitto_pub"))
        .args(["-h", "127.0.0.1", "-p", &port.to_string(), "-q", "1"])
        .args(extra)
        .args(["-t", topic, "-m", payload])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}
