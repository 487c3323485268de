//! A real MQTT broker for the bridge's tests, of two kinds: droidctl's own
//! ([`droidctl::bridge::broker`], in this process, always there) and mosquitto (Debian's;
//! `.ci/run` installs it, and `DROIDCTL_TEST_MOSQUITTO=require` there makes its absence a
//! failure), on a free loopback port, stopped when dropped. The outside client is rumqttc
//! (droidctl's own MQTT library), so no `mosquitto-clients` are needed: [`Sub`] and
//! [`publish`] take the few `mosquitto_sub` options the tests use (`-u`, `-P`, `--cafile`).

#![allow(dead_code)]

use droidctl::bridge::broker;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// A program of the mosquitto package: on PATH, or where Debian puts the broker.
pub fn find(name: &str) -> Option<PathBuf> {
    std::env::var("PATH")
        .unwrap_or_default()
        .split(':')
        .chain(["/usr/sbin", "/usr/bin"])
        .map(|dir| Path::new(dir).join(name))
        .find(|p| p.is_file())
}

/// As [`find`], or fail saying what to install.
pub fn program(name: &str) -> PathBuf {
    find(name).unwrap_or_else(|| {
        panic!("{name} is not installed: apt-get install mosquitto (.ci/run installs it)")
    })
}

/// Whether the mosquitto variant of a test runs: mosquitto is installed. Where it is not,
/// the variant says `SKIPPED` and passes, unless `DROIDCTL_TEST_MOSQUITTO=require` (CI's
/// main run) makes that a failure.
pub fn mosquitto_here() -> bool {
    if find("mosquitto").is_some() {
        return true;
    }
    assert!(
        std::env::var("DROIDCTL_TEST_MOSQUITTO").as_deref() != Ok("require"),
        "mosquitto is not installed, and DROIDCTL_TEST_MOSQUITTO=require"
    );
    eprintln!("SKIPPED: mosquitto is not installed (this test ran against droidctl's own broker)");
    false
}

/// A free loopback port (bound, then released).
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Which broker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// droidctl's own, in this process.
    Embedded,
    Mosquitto,
}

/// droidctl's own broker on its own runtime: killing it drops the runtime, and with it
/// every connection at once (as a crash would).
struct Embedded {
    rt: Option<tokio::runtime::Runtime>,
    broker: Option<broker::Broker>,
    access: broker::Access,
    tls: bool,
}

impl Embedded {
    fn start(port: u16, access: broker::Access, tls: bool) -> Embedded {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build()
            .unwrap();
        let addr = std::net::SocketAddr::from(([127, 0, 0, 1], port));
        let wrap = if tls { Some(tls_wrap()) } else { None };
        let end = Instant::now() + Duration::from_secs(10);
        let broker = loop {
            match rt.block_on(broker::start_with(addr, access.clone(), wrap.clone())) {
                Ok(b) => break b,
                // The port of a broker just killed can take a moment to be free.
                Err(e) if Instant::now() < end => {
                    let _ = e;
                    std::thread::sleep(Duration::from_millis(50));
                }
                Err(e) => panic!("droidctl's broker cannot listen on {addr}: {e}"),
            }
        };
        Embedded {
            rt: Some(rt),
            broker: Some(broker),
            access,
            tls,
        }
    }

    fn kill(&mut self) {
        if let Some(rt) = self.rt.take() {
            let _enter = rt.enter();
            self.broker.take();
            drop(_enter);
            rt.shutdown_background();
        }
    }
}

impl Drop for Embedded {
    fn drop(&mut self) {
        self.kill();
    }
}

/// The TLS handshake in front of droidctl's broker: the test certificate for 127.0.0.1
/// (tests/fixtures/tls, made once with `openssl`; valid until 2126).
#[cfg(target_os = "linux")]
fn tls_wrap() -> broker::Wrap {
    use rumqttc::tokio_rustls::{TlsAcceptor, rustls};
    use rustls::pki_types::pem::PemObject;
    use rustls::pki_types::{CertificateDer, PrivateKeyDer};
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/tls");
    let certs: Vec<CertificateDer> = CertificateDer::pem_file_iter(dir.join("server.pem"))
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    let key = PrivateKeyDer::from_pem_file(dir.join("server.key")).unwrap();
    let config = rustls::ServerConfig::builder()
        .with_no_client_auth()
        .with_single_cert(certs, key)
        .unwrap();
    let acceptor = TlsAcceptor::from(std::sync::Arc::new(config));
    std::sync::Arc::new(move |tcp| {
        let acceptor = acceptor.clone();
        Box::pin(async move {
            let s = acceptor.accept(tcp).await?;
            Ok(Box::new(s) as Box<dyn broker::Stream>)
        })
    })
}

#[cfg(not(target_os = "linux"))]
fn tls_wrap() -> broker::Wrap {
    unimplemented!("the TLS tests run on Linux")
}

/// The test CA (PEM file) the TLS brokers' certificate chains to.
pub fn test_ca() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/tls/ca.pem")
}

/// mosquitto's configuration lines for a TLS listener with the test certificate.
pub fn mosquitto_tls_config() -> String {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/tls");
    let d = d.display();
    format!("cafile {d}/ca.pem\ncertfile {d}/server.pem\nkeyfile {d}/server.key\n")
}

enum Process {
    Mosquitto(Child),
    Embedded(Box<Embedded>),
}

pub struct Broker {
    process: Process,
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
    /// An anonymous broker on loopback: droidctl's own.
    pub fn start(dir: &Path) -> Broker {
        Broker::start_kind(dir, Kind::Embedded)
    }

    /// An anonymous broker on loopback of `kind`.
    pub fn start_kind(dir: &Path, kind: Kind) -> Broker {
        match kind {
            Kind::Embedded => Broker::embedded(dir, free_port(), broker::Access::default(), false),
            Kind::Mosquitto => Broker::start_with(dir, free_port(), "allow_anonymous true\n"),
        }
    }

    /// droidctl's own broker on `port`, with `access`, behind TLS (the test certificate) if
    /// `tls`.
    pub fn embedded(dir: &Path, port: u16, access: broker::Access, tls: bool) -> Broker {
        std::fs::create_dir_all(dir).unwrap();
        Broker {
            process: Process::Embedded(Box::new(Embedded::start(port, access, tls))),
            port,
            dir: dir.to_path_buf(),
            extra: String::new(),
        }
    }

    /// mosquitto on `port` with `extra` config lines (its listener is always loopback only).
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
            process: Process::Mosquitto(child),
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
        match &mut self.process {
            Process::Mosquitto(child) => {
                let _ = child.kill();
                let _ = child.wait();
            }
            Process::Embedded(e) => e.kill(),
        }
    }

    /// Start it again on the same port.
    pub fn restart(&mut self) {
        self.kill();
        let again = match &self.process {
            Process::Mosquitto(_) => {
                let mut again = Broker::start_with(&self.dir, self.port, &self.extra.clone());
                std::mem::replace(&mut again.process, Process::Mosquitto(dead()))
            }
            Process::Embedded(e) => Process::Embedded(Box::new(Embedded::start(
                self.port,
                e.access.clone(),
                e.tls,
            ))),
        };
        self.process = again;
    }

    pub fn url(&self) -> String {
        format!("mqtt://127.0.0.1:{}", self.port)
    }
}

/// A finished process, to leave in a broker value being dropped.
fn dead() -> Child {
    let mut c = Command::new("true").spawn().expect("run true");
    let _ = c.wait();
    c
}

impl Drop for Broker {
    fn drop(&mut self) {
        self.kill();
    }
}

/// The client options for `port` from the `mosquitto_sub` options the tests use.
fn options(id: &str, port: u16, extra: &[&str]) -> rumqttc::MqttOptions {
    let mut o = rumqttc::MqttOptions::new(id, "127.0.0.1", port);
    o.set_keep_alive(Duration::from_secs(5));
    o.set_max_packet_size(1 << 20, 1 << 20);
    let (mut user, mut pass) = (None, None);
    let mut args = extra.iter();
    while let Some(a) = args.next() {
        match *a {
            "-u" => user = args.next().map(|s| s.to_string()),
            "-P" => pass = args.next().map(|s| s.to_string()),
            "--cafile" => {
                let ca = std::fs::read(args.next().expect("--cafile FILE")).unwrap();
                #[cfg(target_os = "linux")]
                let tls = rumqttc::Transport::tls(ca, None, None);
                #[cfg(not(target_os = "linux"))]
                let tls =
                    rumqttc::Transport::tls_with_config(rumqttc::TlsConfiguration::SimpleNative {
                        ca,
                        client_auth: None,
                    });
                o.set_transport(tls);
            }
            other => panic!("the test client does not take {other}"),
        }
    }
    if let Some(u) = user {
        o.set_credentials(u, pass.unwrap_or_default());
    }
    o
}

fn client_id(what: &str) -> String {
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    format!(
        "test-{what}-{}-{}",
        std::process::id(),
        N.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    )
}

/// A subscriber on `topic` (wildcards allowed), at QoS 1: (topic, payload as JSON) as they
/// come. Extra `mosquitto_sub`-style options (`--cafile`, `-u`, `-P`).
pub struct Sub {
    client: rumqttc::Client,
    pub rx: mpsc::Receiver<(String, Value)>,
}

impl Sub {
    pub fn start(port: u16, topic: &str, extra: &[&str]) -> Sub {
        let (client, mut connection) =
            rumqttc::Client::new(options(&client_id("sub"), port, extra), 256);
        client
            .subscribe(topic, rumqttc::QoS::AtLeastOnce)
            .expect("subscribe");
        let (tx, rx) = mpsc::channel();
        let (subscribed, ready) = mpsc::channel();
        std::thread::spawn(move || {
            for event in connection.iter() {
                match event {
                    Ok(rumqttc::Event::Incoming(rumqttc::Packet::SubAck(_))) => {
                        let _ = subscribed.send(Ok(()));
                    }
                    Ok(rumqttc::Event::Incoming(rumqttc::Packet::Publish(p))) => {
                        let text = String::from_utf8_lossy(&p.payload).into_owned();
                        let v: Value = serde_json::from_str(&text).unwrap_or(Value::String(text));
                        if tx.send((p.topic, v)).is_err() {
                            return;
                        }
                    }
                    Ok(_) => {}
                    Err(e) => {
                        let _ = subscribed.send(Err(e.to_string()));
                        return;
                    }
                }
            }
        });
        match ready.recv_timeout(Duration::from_secs(10)) {
            Ok(Ok(())) => {}
            other => panic!("cannot subscribe to {topic} on port {port}: {other:?}"),
        }
        Sub { client, rx }
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
        let _ = self.client.disconnect();
    }
}

/// Publish one message at QoS 1 (acknowledged by the broker); whether it was.
pub fn publish(port: u16, topic: &str, payload: &str, extra: &[&str]) -> bool {
    // `-r`: retained, as mosquitto_pub says it.
    let retain = extra.contains(&"-r");
    let extra: Vec<&str> = extra.iter().copied().filter(|a| *a != "-r").collect();
    publish_bytes(port, topic, payload.as_bytes(), retain, &extra)
}

/// [`publish`] of any bytes (payloads too large for a command line).
pub fn publish_bytes(port: u16, topic: &str, payload: &[u8], retain: bool, extra: &[&str]) -> bool {
    let (client, mut connection) = rumqttc::Client::new(options(&client_id("pub"), port, extra), 8);
    if client
        .publish(topic, rumqttc::QoS::AtLeastOnce, retain, payload)
        .is_err()
    {
        return false;
    }
    let end = Instant::now() + Duration::from_secs(10);
    while Instant::now() < end {
        match connection.recv_timeout(Duration::from_secs(1)) {
            Ok(Ok(rumqttc::Event::Incoming(rumqttc::Packet::PubAck(_)))) => {
                let _ = client.disconnect();
                // Let DISCONNECT out before the connection is dropped.
                for _ in 0..3 {
                    if connection.recv_timeout(Duration::from_millis(200)).is_err() {
                        break;
                    }
                }
                return true;
            }
            Ok(Ok(_)) => {}
            Ok(Err(_)) => return false,
            Err(_) => {}
        }
    }
    false
}
