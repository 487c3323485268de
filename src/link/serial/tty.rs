//! A terminal device opened raw, read and written on tokio's reactor (Unix): the serial port
//! of `--serial PORT`, and the pseudo-terminal `sim --serial` serves on.
//!
//! Opened by hand through `libc` (termios), not through a serial-port crate: the `serialport`
//! crate's defaults build against libudev (pkg-config and libudev-dev on the build machine),
//! and all droidctl needs is one fixed setting — 115200 baud, 8 data bits, no parity, one
//! stop bit, no flow control, raw bytes — which is a dozen lines of termios.

use super::SerialError;
use std::ffi::CString;
use std::io;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};
use std::path::{Path, PathBuf};
use tokio::io::Interest;
use tokio::io::unix::AsyncFd;

/// The one speed RVR's UART runs at (Sphero's SDK: `SerialAsyncDal(baud=115200)`).
pub const BAUD: libc::speed_t = libc::B115200;

/// An open terminal device in raw mode, registered with tokio (create it inside a runtime).
pub struct Tty {
    fd: AsyncFd<OwnedFd>,
}

impl Tty {
    /// Open `path` for reading and writing, take it for ourselves (an advisory lock, so a
    /// second program that locks as well gets "busy" instead of half the bytes),
    /// and set it raw at 115200 baud.
    pub fn open(path: &Path) -> Result<Tty, SerialError> {
        let c = CString::new(path.as_os_str().as_encoded_bytes())
            .map_err(|_| SerialError::NotFound(path.to_path_buf()))?;
        // SAFETY: `c` is a valid NUL-terminated string for the duration of the call.
        let raw = unsafe {
            libc::open(
                c.as_ptr(),
                libc::O_RDWR | libc::O_NOCTTY | libc::O_NONBLOCK | libc::O_CLOEXEC,
            )
        };
        if raw < 0 {
            return Err(SerialError::from_open(path, io::Error::last_os_error()));
        }
        // SAFETY: `open` just returned this descriptor; nothing else owns it.
        let fd = unsafe { OwnedFd::from_raw_fd(raw) };
        let path_buf = path.to_path_buf();
        // Another program that locked the port the usual way (pyserial's `exclusive=True`,
        // minicom's flock) holds it: say so rather than share the bytes.
        // SAFETY: a valid descriptor; flock takes no pointers.
        if unsafe { libc::flock(fd.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
            let e = io::Error::last_os_error();
            return Err(match e.raw_os_error() {
                Some(libc::EWOULDBLOCK) => SerialError::Busy(path_buf),
                _ => SerialError::Setup(path_buf, e.to_string()),
            });
        }
        if !is_tty(fd.as_raw_fd()) {
            return Err(SerialError::NotATerminal(path_buf));
        }
        // Not the terminal's exclusive mode (TIOCEXCL): it outlives our close while anything
        // else holds the device open (the simulator holds its pseudo-terminal), and would
        // refuse our own reconnect.
        raw_mode(fd.as_raw_fd())
            .map_err(|e| SerialError::Setup(path_buf.clone(), e.to_string()))?;
        Tty::register(fd).map_err(|e| SerialError::Setup(path_buf, e.to_string()))
    }

    fn register(fd: OwnedFd) -> io::Result<Tty> {
        // SAFETY: the `OwnedFd` is moved in and owned by the `AsyncFd` until it drops: the
        // descriptor stays open and names the same file all that time.
        let fd =
            unsafe { AsyncFd::register_with_interest(fd, Interest::READABLE | Interest::WRITABLE) }
                .map_err(|e| e.into_parts().1)?;
        Ok(Tty { fd })
    }

    /// Read what is there (at least one byte), waiting for it; `Ok(0)` is the end (the other
    /// side of a pseudo-terminal closed, or the device went away).
    pub async fn read(&self, buf: &mut [u8]) -> io::Result<usize> {
        loop {
            let mut guard = self.fd.readable().await?;
            match guard.try_io(|fd| {
                // SAFETY: `buf` is valid for `buf.len()` bytes.
                let n =
                    unsafe { libc::read(fd.as_raw_fd(), buf.as_mut_ptr().cast(), buf.len() as _) };
                if n < 0 {
                    Err(io::Error::last_os_error())
                } else {
                    Ok(n as usize)
                }
            }) {
                Ok(r) => return r,
                Err(_would_block) => continue,
            }
        }
    }

    /// Write all of `bytes`, waiting while the device's buffer is full.
    pub async fn write_all(&self, mut bytes: &[u8]) -> io::Result<()> {
        while !bytes.is_empty() {
            let mut guard = self.fd.writable().await?;
            match guard.try_io(|fd| {
                // SAFETY: `bytes` is valid for `bytes.len()` bytes.
                let n =
                    unsafe { libc::write(fd.as_raw_fd(), bytes.as_ptr().cast(), bytes.len() as _) };
                if n < 0 {
                    Err(io::Error::last_os_error())
                } else {
                    Ok(n as usize)
                }
            }) {
                Ok(Ok(0)) => return Err(io::ErrorKind::WriteZero.into()),
                Ok(Ok(n)) => bytes = &bytes[n.min(bytes.len())..],
                Ok(Err(e)) => return Err(e),
                Err(_would_block) => continue,
            }
        }
        Ok(())
    }
}

fn is_tty(fd: RawFd) -> bool {
    // SAFETY: isatty takes a descriptor and nothing else.
    unsafe { libc::isatty(fd) == 1 }
}

/// Raw bytes at [`BAUD`], 8N1, no flow control, the receiver on; what is queued is dropped.
fn raw_mode(fd: RawFd) -> io::Result<()> {
    // SAFETY: `t` is a plain C struct filled by tcgetattr before it is read.
    unsafe {
        let mut t: libc::termios = std::mem::zeroed();
        if libc::tcgetattr(fd, &mut t) != 0 {
            return Err(io::Error::last_os_error());
        }
        libc::cfmakeraw(&mut t);
        t.c_cflag |= libc::CLOCAL | libc::CREAD;
        t.c_cflag &= !(libc::CRTSCTS | libc::CSTOPB | libc::PARENB);
        t.c_iflag &= !(libc::IXON | libc::IXOFF | libc::IXANY);
        t.c_cc[libc::VMIN] = 1;
        t.c_cc[libc::VTIME] = 0;
        if libc::cfsetispeed(&mut t, BAUD) != 0 || libc::cfsetospeed(&mut t, BAUD) != 0 {
            return Err(io::Error::last_os_error());
        }
        if libc::tcsetattr(fd, libc::TCSANOW, &t) != 0 {
            return Err(io::Error::last_os_error());
        }
        libc::tcflush(fd, libc::TCIOFLUSH);
    }
    Ok(())
}

/// A new pseudo-terminal for `sim --serial`: its controlling side, raw and registered with
/// tokio; the terminal side, held open by the simulator (so the controlling side does not
/// read as ended between two clients, and the settings stay raw); and the terminal side's
/// path, which clients open as they would a serial port.
pub fn open_pty() -> io::Result<(Tty, OwnedFd, PathBuf)> {
    // SAFETY: posix_openpt/grantpt/unlockpt/ptsname take the descriptor just opened; the
    // name ptsname returns is copied out before anything else can call it on this thread.
    unsafe {
        let raw = libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY);
        if raw < 0 {
            return Err(io::Error::last_os_error());
        }
        let fd = OwnedFd::from_raw_fd(raw);
        if libc::grantpt(raw) != 0 || libc::unlockpt(raw) != 0 {
            return Err(io::Error::last_os_error());
        }
        let name = libc::ptsname(raw);
        if name.is_null() {
            return Err(io::Error::last_os_error());
        }
        let path = PathBuf::from(
            std::ffi::CStr::from_ptr(name)
                .to_string_lossy()
                .into_owned(),
        );
        let flags = libc::fcntl(raw, libc::F_GETFL);
        if flags < 0 || libc::fcntl(raw, libc::F_SETFL, flags | libc::O_NONBLOCK) != 0 {
            return Err(io::Error::last_os_error());
        }
        libc::fcntl(raw, libc::F_SETFD, libc::FD_CLOEXEC);
        // The terminal side raw as well, so a client that does not set it (or sets it after
        // its first write) gets its bytes through unchanged: no echo, no line discipline.
        let c = CString::new(path.as_os_str().as_encoded_bytes())
            .map_err(|_| io::Error::other("pseudo-terminal name with a NUL"))?;
        let peer = libc::open(c.as_ptr(), libc::O_RDWR | libc::O_NOCTTY | libc::O_CLOEXEC);
        if peer < 0 {
            return Err(io::Error::last_os_error());
        }
        let peer = OwnedFd::from_raw_fd(peer);
        raw_mode(peer.as_raw_fd())?;
        Ok((Tty::register(fd)?, peer, path))
    }
}
