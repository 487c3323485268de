//! A private D-Bus bus for the virtual BlueZ, listening on a unix socket in a temporary
//! directory: `dbus-daemon` with a session-like configuration written there, or, where
//! `dbus-daemon` is not installed (containers, fresh machines), busd, a bus written in Rust,
//! run on a thread of this process. `DROIDCTL_DBUS_DAEMON=embedded` asks for busd even where
//! `dbus-daemon` is installed (the tests use it to try both). Dropping it stops the bus and
//! removes the directory.

use std::fs;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// How long the daemon may take to say where it listens.
const START_TIMEOUT: Duration = Duration::from_secs(5);

/// The longest unix socket path the kernel takes (`sun_path` holds 108 bytes with its NUL).
const MAX_SOCKET_PATH: usize = 107;

/// A bus of our own.
pub struct PrivateBus {
    daemon: Daemon,
    dir: PathBuf,
    address: String,
}

enum Daemon {
    /// `dbus-daemon`, a child process.
    Child(Child),
    /// busd on a thread of ours.
    Embedded(Embedded),
}

/// The environment variable that picks the bus: `embedded` for busd.
pub const DAEMON_ENV: &str = "DROIDCTL_DBUS_DAEMON";

/// Whether busd is asked for though `dbus-daemon` may be installed.
fn embedded_asked() -> bool {
    std::env::var(DAEMON_ENV).as_deref() == Ok("embedded")
}

impl PrivateBus {
    /// Start the daemon and wait until it listens.
    /// Start the daemon. It dies with this process (`PR_SET_PDEATHSIG`, which follows the
    /// starting *thread*: call this from the one that lives as long as the simulator).
    pub fn start() -> Result<PrivateBus, String> {
        let dir = make_dir()?;
        let started = if embedded_asked() {
            Err(Missing)
        } else {
            Self::start_in(&dir)
        };
        let started = match started {
            Ok((child, address)) => Ok((Daemon::Child(child), address)),
            Err(Missing) => Embedded::start(&dir).map(|(e, a)| (Daemon::Embedded(e), a)),
            Err(Failed(why)) => Err(why),
        };
        match started {
            Ok((daemon, address)) => Ok(PrivateBus {
                daemon,
                dir,
                address,
            }),
            Err(e) => {
                let _ = fs::remove_dir_all(&dir);
                Err(e)
            }
        }
    }

    /// Which bus runs: `dbus-daemon` or `busd (embedded)`.
    pub fn kind(&self) -> &'static str {
        match self.daemon {
            Daemon::Child(_) => "dbus-daemon",
            Daemon::Embedded(_) => "busd (embedded)",
        }
    }

    fn start_in(dir: &Path) -> Result<(Child, String), Start> {
        let socket_text = socket_path(dir).map_err(Failed)?;
        let config = dir.join("bus.conf");
        fs::write(&config, config_xml(&socket_text))
            .map_err(|e| Failed(format!("cannot write {}: {e}", config.display())))?;
        let mut cmd = Command::new("dbus-daemon");
        cmd.arg(format!("--config-file={}", config.display()))
            .arg("--nofork")
            .arg("--nopidfile")
            .arg("--print-address=1")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        // Its own process group: Ctrl-C in the terminal reaches droidctl, which stops the
        // daemon after the droids, not the daemon first.
        {
            use std::os::unix::process::CommandExt;
            cmd.process_group(0);
            // And it dies with droidctl, however droidctl ends: a SIGKILL gives droidctl no
            // chance to stop it, and a daemon left behind keeps the bus (and its socket)
            // alive for nothing.
            let parent = std::process::id();
            // SAFETY: between fork and exec only async-signal-safe calls are made (prctl,
            // getppid, _exit), touching no memory of the parent's.
            unsafe {
                cmd.pre_exec(move || {
                    if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                        return Err(std::io::Error::last_os_error());
                    }
                    // The parent may have died before the call: then nobody would signal.
                    if libc::getppid() as u32 != parent {
                        libc::_exit(1);
                    }
                    Ok(())
                });
            }
        }
        let mut child = cmd.spawn().map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                Missing
            } else {
                Failed(format!("cannot start dbus-daemon: {e}"))
            }
        })?;
        let (tx, rx) = mpsc::channel();
        if let Some(stdout) = child.stdout.take() {
            std::thread::spawn(move || {
                let mut line = String::new();
                let r = BufReader::new(stdout).read_line(&mut line).map(|_| line);
                let _ = tx.send(r);
            });
        }
        let printed = rx.recv_timeout(START_TIMEOUT);
        let listening = matches!(&printed, Ok(Ok(line)) if !line.trim().is_empty());
        if !listening {
            let _ = child.kill();
            let _ = child.wait();
            let mut why = String::new();
            if let Some(mut err) = child.stderr.take() {
                let _ = err.read_to_string(&mut why);
            }
            let why = why.split_whitespace().collect::<Vec<_>>().join(" ");
            return Err(Failed(if why.is_empty() {
                format!(
                    "dbus-daemon did not start within {} s",
                    START_TIMEOUT.as_secs()
                )
            } else {
                format!("dbus-daemon did not start: {why}")
            }));
        }
        // Whatever it says from now on goes nowhere (unread, a full pipe would stall it).
        if let Some(mut err) = child.stderr.take() {
            std::thread::spawn(move || {
                let _ = std::io::copy(&mut err, &mut std::io::sink());
            });
        }
        Ok((child, format!("unix:path={}", escape_address(&socket_text))))
    }

    /// The bus address clients use (`unix:path=/tmp/droidctl-bluez-…/bus`).
    pub fn address(&self) -> &str {
        &self.address
    }

    /// Whether the bus still runs.
    pub fn running(&mut self) -> bool {
        match &mut self.daemon {
            Daemon::Child(child) => matches!(child.try_wait(), Ok(None)),
            Daemon::Embedded(e) => !e.thread.as_ref().is_none_or(|t| t.is_finished()),
        }
    }
}

impl Drop for PrivateBus {
    fn drop(&mut self) {
        match &mut self.daemon {
            Daemon::Child(child) => {
                let _ = child.kill();
                let _ = child.wait();
            }
            Daemon::Embedded(e) => e.stop(),
        }
        let _ = fs::remove_dir_all(&self.dir);
    }
}

/// Why `dbus-daemon` did not start: not installed (then busd runs instead), or another
/// failure (said as it is).
enum Start {
    Missing,
    Failed(String),
}
use Start::{Failed, Missing};

/// The socket's path in `dir`, checked to fit a unix socket address.
fn socket_path(dir: &Path) -> Result<String, String> {
    let socket = dir.join("bus");
    match socket.to_str() {
        Some(s) if s.len() <= MAX_SOCKET_PATH => Ok(s.to_string()),
        _ => Err(format!(
            "the temporary directory {} makes too long a socket path: set TMPDIR to a \
             shorter one",
            dir.display()
        )),
    }
}

/// busd on a thread of its own, with its own (zbus's) runtime: independent of the tokio
/// runtime of the simulator it carries. It dies with the process whatever way the process
/// ends (nothing is left behind to keep the bus alive); dropping it stops it first.
struct Embedded {
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Embedded {
    fn start(dir: &Path) -> Result<(Embedded, String), String> {
        let socket = socket_path(dir)?;
        let address = format!("unix:path={}", escape_address(&socket));
        let (ready_tx, ready) = mpsc::channel();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let listen = address.clone();
        let thread = std::thread::Builder::new()
            .name("busd".into())
            .spawn(move || {
                zruntime::block_on(async move {
                    let mut bus = match busd::bus::Bus::for_address(Some(&listen)).await {
                        Ok(bus) => bus,
                        Err(e) => {
                            let _ = ready_tx.send(Err(format!("{e:#}")));
                            return;
                        }
                    };
                    let _ = ready_tx.send(Ok(()));
                    {
                        let run = std::pin::pin!(bus.run());
                        if let futures_util::future::Either::Left((Err(e), _)) =
                            futures_util::future::select(run, stopped).await
                        {
                            tracing::warn!("the embedded D-Bus bus stopped: {e:#}")
                        }
                    }
                    let _ = bus.cleanup().await;
                })
            })
            .map_err(|e| format!("cannot start the embedded D-Bus bus: {e}"))?;
        match ready.recv_timeout(START_TIMEOUT) {
            Ok(Ok(())) => Ok((
                Embedded {
                    stop: Some(stop),
                    thread: Some(thread),
                },
                address,
            )),
            Ok(Err(why)) => Err(format!(
                "the embedded D-Bus bus (busd) did not start: {why}"
            )),
            Err(_) => Err(format!(
                "the embedded D-Bus bus (busd) did not start within {} s",
                START_TIMEOUT.as_secs()
            )),
        }
    }

    fn stop(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Names [`make_dir_in`] tries before giving up: a random one is taken only if someone
/// made it already, so a second try is near certain to do.
const DIR_TRIES: u32 = 16;

/// A fresh directory only we may use, in the temporary directory.
fn make_dir() -> Result<PathBuf, String> {
    make_dir_in(&std::env::temp_dir(), random_name)
}

/// `droidctl-bluez-` and 64 random bits from the kernel: a name another local user cannot
/// make first (issue 37 point 14: `droidctl-bluez-PID-N` could be, and `sim --bluez` then
/// failed). Not [`crate::rng`], which is seeded to be repeatable, not unguessable.
fn random_name() -> Result<String, String> {
    let mut bits = [0u8; 8];
    fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut bits))
        .map_err(|e| format!("cannot read /dev/urandom: {e}"))?;
    Ok(format!("droidctl-bluez-{:016x}", u64::from_ne_bytes(bits)))
}

/// A directory of `name()`'s in `base`, created by us now (never one that was there, which
/// someone else may own or watch), mode 0700 whatever the umask, checked to be ours.
fn make_dir_in(
    base: &Path,
    mut name: impl FnMut() -> Result<String, String>,
) -> Result<PathBuf, String> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    let cannot =
        |e: &dyn std::fmt::Display| format!("cannot create a directory in {}: {e}", base.display());
    let mut last = None;
    for _ in 0..DIR_TRIES {
        let dir = base.join(name()?);
        match fs::DirBuilder::new().mode(0o700).create(&dir) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                last = Some(e);
                continue;
            }
            Err(e) => return Err(cannot(&e)),
        }
        // Made just now by this mkdir: ours. The umask may have taken bits away; none more
        // are given than 0700.
        let checked = fs::set_permissions(&dir, fs::Permissions::from_mode(0o700))
            .and_then(|()| fs::symlink_metadata(&dir));
        // SAFETY: geteuid has no preconditions and cannot fail.
        let me = unsafe { libc::geteuid() };
        return match checked {
            Ok(m) if m.is_dir() && m.uid() == me && m.mode() & 0o777 == 0o700 => Ok(dir),
            Ok(_) => {
                let _ = fs::remove_dir(&dir);
                Err(cannot(&format!("{} is not ours alone", dir.display())))
            }
            Err(e) => {
                let _ = fs::remove_dir(&dir);
                Err(cannot(&e))
            }
        };
    }
    Err(cannot(&last.map(|e| e.to_string()).unwrap_or_default()))
}

/// A minimal session-like configuration: one unix socket, anyone on it may own any name and
/// talk to anyone (the socket's directory is private to this user).
fn config_xml(socket: &str) -> String {
    format!(
        r#"<!DOCTYPE busconfig PUBLIC "-//freedesktop//DTD D-Bus Bus Configuration 1.0//EN"
 "http://www.freedesktop.org/standards/dbus/1.0/busconfig.dtd">
<busconfig>
  <type>session</type>
  <listen>unix:path={}</listen>
  <auth>EXTERNAL</auth>
  <policy context="default">
    <allow send_destination="*" eavesdrop="true"/>
    <allow eavesdrop="true"/>
    <allow own="*"/>
  </policy>
</busconfig>
"#,
        escape_xml(&escape_address(socket))
    )
}

fn escape_xml(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

/// A D-Bus address value: bytes outside `[-0-9A-Za-z_/.\*]` as `%XX`.
fn escape_address(s: &str) -> String {
    s.bytes()
        .map(|b| {
            if b.is_ascii_alphanumeric() || b"-_/.\\*".contains(&b) {
                (b as char).to_string()
            } else {
                format!("%{b:02x}")
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_and_config_are_escaped() {
        assert_eq!(escape_address("/tmp/a b/bus"), "/tmp/a%20b/bus");
        assert_eq!(escape_address("/tmp/x,y=z"), "/tmp/x%2cy%3dz");
        let xml = config_xml("/tmp/a&b/bus");
        assert!(
            xml.contains("<listen>unix:path=/tmp/a%26b/bus</listen>"),
            "{xml}"
        );
        assert!(config_xml("/tmp/<b>").contains("unix:path=/tmp/%3cb%3e<"));
    }

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("droidctl-daemon-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn ours_alone(dir: &Path) {
        use std::os::unix::fs::MetadataExt;
        let m = fs::symlink_metadata(dir).unwrap();
        assert!(m.is_dir());
        assert_eq!(m.mode() & 0o777, 0o700, "{}", dir.display());
        // SAFETY: no preconditions.
        assert_eq!(m.uid(), unsafe { libc::geteuid() });
    }

    /// Issue 37 point 14: the names the old scheme would take, made first by someone else,
    /// do not stop the bus's directory being made.
    #[test]
    fn the_old_predictable_names_taken_first_do_not_stop_it() {
        let base = std::env::temp_dir();
        let pid = std::process::id();
        let taken: Vec<PathBuf> = (0..100)
            .map(|n| base.join(format!("droidctl-bluez-{pid}-{n}")))
            .collect();
        for d in &taken {
            let _ = fs::create_dir(d);
        }
        let made = make_dir();
        for d in &taken {
            let _ = fs::remove_dir(d);
        }
        let dir = made.unwrap();
        assert!(!taken.contains(&dir));
        let name = dir.file_name().unwrap().to_string_lossy().into_owned();
        let suffix = name.strip_prefix("droidctl-bluez-").unwrap();
        assert_eq!(suffix.len(), 16, "{name}");
        assert!(suffix.bytes().all(|b| b.is_ascii_hexdigit()), "{name}");
        ours_alone(&dir);
        assert_ne!(make_dir().unwrap(), dir, "a new name each time");
        let _ = fs::remove_dir(&dir);
    }

    #[test]
    fn an_existing_directory_is_never_reused_and_tries_are_bounded() {
        let base = scratch("reuse");
        let theirs = base.join("droidctl-bluez-taken");
        fs::create_dir(&theirs).unwrap();
        fs::write(theirs.join("bus"), "theirs").unwrap();
        let mut names = ["droidctl-bluez-taken", "droidctl-bluez-fresh"].into_iter();
        let dir = make_dir_in(&base, || Ok(names.next().unwrap_or("x").into())).unwrap();
        assert_eq!(dir, base.join("droidctl-bluez-fresh"));
        ours_alone(&dir);
        assert_eq!(fs::read_to_string(theirs.join("bus")).unwrap(), "theirs");
        let mut asked = 0;
        let e = make_dir_in(&base, || {
            asked += 1;
            Ok("droidctl-bluez-taken".into())
        })
        .unwrap_err();
        assert_eq!(asked, DIR_TRIES);
        assert!(e.contains("cannot create a directory"), "{e}");
        let _ = fs::remove_dir_all(&base);
    }
}
