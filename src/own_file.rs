//! droidctl's own files at fixed paths (issue 37 point 13): the remembered settings and the
//! log in the state directory, the configuration at its usual place. Whatever is found at
//! such a path is not trusted to be a file:
//!
//! - a FIFO there would hang the program in `open` (nobody writes to it, or reads it), so
//!   files are opened without blocking and only a regular file is used;
//! - a symbolic link there would have its target written, so droidctl's own state files are
//!   opened without following one ([`Links::Refuse`]), and written by a rename over the path
//!   ([`write_atomic`]), which replaces a link itself rather than writing where it points.
//!
//! The user's configuration may be a symbolic link (dotfile managers make them):
//! [`Links::Follow`] reads it, still only a regular file.

use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

/// Whether a symbolic link at the path is followed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Links {
    /// Follow it to a regular file (the user's configuration).
    Follow,
    /// Refuse it (droidctl's own state files).
    Refuse,
}

/// What was found instead of a regular file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum NotRegular {
    #[error("a FIFO, not a regular file")]
    Fifo,
    #[error("a symbolic link, not followed")]
    Symlink,
    #[error("a directory, not a regular file")]
    Directory,
    #[error("a device or socket, not a regular file")]
    Special,
}

impl From<NotRegular> for io::Error {
    fn from(n: NotRegular) -> io::Error {
        io::Error::new(io::ErrorKind::InvalidInput, n)
    }
}

/// Which [`NotRegular`] a file type is; `None` for a regular file.
fn not_regular(t: std::fs::FileType) -> Option<NotRegular> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some(NotRegular::Fifo);
        }
    }
    if t.is_file() {
        None
    } else if t.is_symlink() {
        Some(NotRegular::Symlink)
    } else if t.is_dir() {
        Some(NotRegular::Directory)
    } else {
        Some(NotRegular::Special)
    }
}

/// Open `path` with `options` when it is a regular file (a symbolic link to one too with
/// [`Links::Follow`]), never blocking on what is there: anything else is a [`NotRegular`]
/// error (kind `InvalidInput`). A missing file is `NotFound` as usual (or created, when
/// `options` say so).
pub fn open(path: &Path, options: &OpenOptions, links: Links) -> io::Result<File> {
    let mut options = options.clone();
    os_flags(&mut options, links);
    let file = match options.open(path) {
        Ok(f) => f,
        // Refused by the flags (a link, a FIFO nobody reads): say what is there.
        Err(e) => {
            let found = match links {
                Links::Refuse => std::fs::symlink_metadata(path),
                Links::Follow => std::fs::metadata(path),
            };
            return Err(match found.ok().and_then(|m| not_regular(m.file_type())) {
                Some(n) => n.into(),
                None => e,
            });
        }
    };
    // What was opened, not what is at the path now: nothing can be swapped in between.
    match not_regular(file.metadata()?.file_type()) {
        Some(n) => Err(n.into()),
        None => Ok(file),
    }
}

/// Unix: `O_NONBLOCK` (opening a FIFO returns at once; it changes nothing for a regular
/// file) and `O_NOFOLLOW` (a link is an error, `ELOOP`).
#[cfg(unix)]
fn os_flags(options: &mut OpenOptions, links: Links) {
    use std::os::unix::fs::OpenOptionsExt;
    let nofollow = match links {
        Links::Refuse => libc::O_NOFOLLOW,
        Links::Follow => 0,
    };
    options.custom_flags(libc::O_NONBLOCK | nofollow);
}

/// Windows: `FILE_FLAG_OPEN_REPARSE_POINT` opens a link itself, which [`open`] then refuses
/// (there are no FIFOs in the file system).
#[cfg(windows)]
fn os_flags(options: &mut OpenOptions, links: Links) {
    use std::os::windows::fs::OpenOptionsExt;
    /// From the Win32 API (`winbase.h`).
    const FILE_FLAG_OPEN_REPARSE_POINT: u32 = 0x0020_0000;
    if links == Links::Refuse {
        options.custom_flags(FILE_FLAG_OPEN_REPARSE_POINT);
    }
}

#[cfg(not(any(unix, windows)))]
fn os_flags(_: &mut OpenOptions, _: Links) {}

/// The temporary files [`write_atomic`] has made in this process.
static TEMPORARIES: AtomicU64 = AtomicU64::new(0);

/// Names [`write_atomic`] tries before giving up.
const TEMPORARY_TRIES: u32 = 16;

/// Write `bytes` to `path` whole or not at all: to a new file beside it (created, never
/// reused) then renamed over it. A symbolic link, a FIFO or a file at `path` is replaced,
/// never written through; a reader sees the old text or the new, never half.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "no file name"))?
        .to_string_lossy();
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut last = None;
    for _ in 0..TEMPORARY_TRIES {
        let n = TEMPORARIES.fetch_add(1, Ordering::Relaxed);
        let temporary = dir.join(format!(".{name}.{}-{n}.tmp", std::process::id()));
        let mut file = match OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temporary)
        {
            Ok(f) => f,
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {
                last = Some(e);
                continue;
            }
            Err(e) => return Err(e),
        };
        let written = file
            .write_all(bytes)
            .and_then(|()| file.sync_all())
            .and_then(|()| {
                drop(file);
                std::fs::rename(&temporary, path)
            });
        if written.is_err() {
            let _ = std::fs::remove_file(&temporary);
        }
        return written;
    }
    Err(last.unwrap_or_else(|| io::Error::other("no temporary file name was free")))
}

/// Test support shared by the tests of droidctl's own files (config, log, remembered
/// settings): a FIFO in a file's place, and what is done with it, bounded in time.
#[cfg(all(test, unix))]
pub(crate) mod testing {
    use std::path::Path;

    /// Make a FIFO at `path`, then run `f` on a thread of its own: its result, or a panic
    /// naming `what` when it blocked (on the FIFO) for 5 s.
    pub fn with_fifo<T: Send + 'static>(
        path: &Path,
        what: &str,
        f: impl FnOnce() -> T + Send + 'static,
    ) -> T {
        let made = std::process::Command::new("mkfifo")
            .arg(path)
            .status()
            .unwrap();
        assert!(made.success());
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(f());
        });
        rx.recv_timeout(std::time::Duration::from_secs(5))
            .unwrap_or_else(|_| panic!("{what} blocked on the FIFO"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        let d =
            std::env::temp_dir().join(format!("droidctl-own-file-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn read() -> OpenOptions {
        let mut o = OpenOptions::new();
        o.read(true);
        o
    }

    #[test]
    fn a_regular_file_opens_and_a_directory_or_nothing_does_not() {
        let d = scratch("regular");
        let p = d.join("f");
        std::fs::write(&p, "x").unwrap();
        assert!(open(&p, &read(), Links::Refuse).is_ok());
        let e = open(&d, &read(), Links::Follow).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert_eq!(e.to_string(), NotRegular::Directory.to_string());
        let missing = open(&d.join("missing"), &read(), Links::Refuse).unwrap_err();
        assert_eq!(missing.kind(), io::ErrorKind::NotFound);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn write_atomic_replaces_and_leaves_no_temporary() {
        let d = scratch("atomic");
        let p = d.join("settings.toml");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let names: Vec<_> = std::fs::read_dir(&d).unwrap().flatten().collect();
        assert_eq!(names.len(), 1, "{names:?}");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[cfg(unix)]
    fn mkfifo(p: &Path) {
        use std::os::unix::ffi::OsStrExt;
        let c = std::ffi::CString::new(p.as_os_str().as_bytes()).unwrap();
        // SAFETY: a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    }

    /// `f` on another thread, or a failure after a few seconds rather than a hung test.
    #[cfg(unix)]
    fn within<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(f());
        });
        rx.recv_timeout(std::time::Duration::from_secs(5))
            .expect("blocked on a FIFO")
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_at_once_for_reading_and_appending() {
        let d = scratch("fifo");
        let p = d.join("fifo");
        mkfifo(&p);
        for links in [Links::Refuse, Links::Follow] {
            let q = p.clone();
            let e = within(move || open(&q, &read(), links)).unwrap_err();
            assert_eq!(e.to_string(), NotRegular::Fifo.to_string());
            let q = p.clone();
            let e = within(move || {
                open(
                    &q,
                    OpenOptions::new().create(true).append(true),
                    Links::Refuse,
                )
            })
            .unwrap_err();
            assert_eq!(e.to_string(), NotRegular::Fifo.to_string());
        }
        // Written over: the FIFO is replaced by a file.
        let q = p.clone();
        within(move || write_atomic(&q, b"x")).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"x");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[cfg(unix)]
    #[test]
    fn a_link_is_refused_or_followed_and_replaced_never_written_through() {
        let d = scratch("link");
        let target = d.join("precious");
        std::fs::write(&target, "precious").unwrap();
        let p = d.join("settings.toml");
        std::os::unix::fs::symlink(&target, &p).unwrap();
        let e = open(&p, &read(), Links::Refuse).unwrap_err();
        assert_eq!(e.to_string(), NotRegular::Symlink.to_string());
        let e = open(
            &p,
            OpenOptions::new().create(true).append(true),
            Links::Refuse,
        )
        .unwrap_err();
        assert_eq!(e.to_string(), NotRegular::Symlink.to_string());
        assert!(open(&p, &read(), Links::Follow).is_ok());
        write_atomic(&p, b"mine").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"precious");
        assert!(std::fs::symlink_metadata(&p).unwrap().is_file());
        assert_eq!(std::fs::read(&p).unwrap(), b"mine");
        // A dangling link is not created through either.
        let dangling = d.join("log");
        std::os::unix::fs::symlink(d.join("elsewhere"), &dangling).unwrap();
        assert!(
            open(
                &dangling,
                OpenOptions::new().create(true).append(true),
                Links::Refuse
            )
            .is_err()
        );
        assert!(!d.join("elsewhere").exists());
        let _ = std::fs::remove_dir_all(&d);
    }
}
