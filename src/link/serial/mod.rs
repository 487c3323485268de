//! `--serial PORT`: a droid on a serial port — RVR on a Raspberry Pi's UART (or a USB serial
//! adapter), the way Sphero's own RVR SDK reaches it.
//!
//! The wire is the same Sphero API v2 byte stream as over Bluetooth, at 115200 baud, 8N1, no
//! flow control (Sphero's `sphero-sdk` 0.3.4, `SerialAsyncDal(device='/dev/ttyS0',
//! baud=115200)` over pyserial's defaults). There is no GATT here: no characteristics, no
//! anti-DoS handshake (RVR has none over Bluetooth either, `droid-facts.md` §6), no 20-byte
//! notifications — the session's writes go out as they come and the droid's bytes come back
//! in whatever pieces the port delivers, which the v2 reader reassembles as it does BLE's.
//!
//! Link loss: a USB adapter pulled out, or the simulator's pseudo-terminal closed, ends the
//! reads; that is a [`LinkEvent::Disconnected`] as a Bluetooth drop is, and the session
//! stops the droid and reopens the port with its backoff. A UART on the Pi's pins gives no
//! such sign when RVR is switched off (unverified on hardware: we have no RVR); the
//! session's unanswered requests are what shows it then.

#[cfg(unix)]
pub mod tty;

use crate::link::{Connection, Framing, Link, LinkError};
#[cfg(unix)]
use crate::link::{LinkEvent, LinkWriter};
use crate::model::Model;
use futures_util::future::BoxFuture;
use std::path::{Path, PathBuf};

/// Why a serial port could not be used, in words that say what to do.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SerialError {
    #[error(
        "no serial port {0}: check the name and the cable (a Raspberry Pi's UART is /dev/serial0 \
         once enabled, see docs/serial.md; a USB adapter is /dev/ttyUSB0 or /dev/ttyACM0)"
    )]
    NotFound(PathBuf),
    #[error(
        "permission denied on {0}: on Linux, add yourself to the group that owns it \
         (`sudo usermod -aG dialout $USER`, then log out and in again)"
    )]
    Permission(PathBuf),
    #[error(
        "{0} is in use by another program (a login console on the port, ModemManager, another \
         droidctl or terminal program): stop it, then try again"
    )]
    Busy(PathBuf),
    #[error("{0} is not a serial port (not a terminal device)")]
    NotATerminal(PathBuf),
    #[error("cannot set up the serial port {0}: {1}")]
    Setup(PathBuf, String),
    #[error(
        "--serial needs Linux or macOS: droidctl opens serial ports there only (on Windows, use \
         `droidctl serve` on the machine with the port and `--remote` here)"
    )]
    Unsupported,
}

impl SerialError {
    /// The error `open(2)` on `path` failed with, in words.
    pub fn from_open(path: &Path, e: std::io::Error) -> SerialError {
        use std::io::ErrorKind;
        let path = path.to_path_buf();
        match e.kind() {
            ErrorKind::NotFound => SerialError::NotFound(path),
            ErrorKind::PermissionDenied => SerialError::Permission(path),
            ErrorKind::ResourceBusy => SerialError::Busy(path),
            _ => match e.raw_os_error() {
                // A device node whose device is gone (an unplugged adapter's leftover).
                #[cfg(unix)]
                Some(libc::ENXIO | libc::ENODEV) => SerialError::NotFound(path),
                #[cfg(unix)]
                Some(libc::EBUSY) => SerialError::Busy(path),
                _ => SerialError::Setup(path, e.to_string()),
            },
        }
    }

    /// Retrying cannot help (the user has to act first); a port that is missing or busy may
    /// come back (an adapter plugged in again, the other program ending).
    pub fn fatal(&self) -> bool {
        matches!(
            self,
            SerialError::Permission(_) | SerialError::NotATerminal(_) | SerialError::Unsupported
        )
    }
}

impl From<SerialError> for LinkError {
    fn from(e: SerialError) -> LinkError {
        let fatal = e.fatal();
        LinkError {
            message: e.to_string(),
            fatal,
        }
    }
}

/// The serial link's writes: a whole packet at once (v2 packets of what droidctl sends are far
/// shorter), and a short gap between writes — Sphero's SDK sends back to back with none; the
/// gap only keeps a burst (the connect setup) from filling RVR's receive buffer, whose size
/// no public source gives (unverified on hardware).
pub const FRAMING: Framing = Framing {
    chunk_size: 512,
    pacing: std::time::Duration::from_millis(5),
};

/// Bytes read from the port at once, at most.
#[cfg(unix)]
const READ_MAX: usize = 512;
/// Pieces of the droid's bytes waiting for the session; beyond, reading waits (the port's
/// own buffer holds the rest).
#[cfg(unix)]
const EVENTS: usize = 256;

/// A droid on a serial port.
pub struct SerialLink {
    path: PathBuf,
    model: Model,
}

impl SerialLink {
    /// The droid of `model` on the serial port at `path` (opened by [`Link::open`]).
    pub fn new(path: impl Into<PathBuf>, model: Model) -> Self {
        SerialLink {
            path: path.into(),
            model,
        }
    }

    pub fn model(&self) -> Model {
        self.model
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The name a droid on a serial port goes by: RVR's `RV-` and the port's file name (its
    /// Bluetooth name is not asked for: Sphero's SDK can, droidctl does not need it).
    pub fn droid_name(&self) -> String {
        let file = self
            .path
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.path.display().to_string());
        match self.model.name_prefix() {
            Some(p) => format!("{p}{file}"),
            None => format!("{} {file}", self.model.display_name()),
        }
    }

    /// Open the port once and close it again: its errors at once, before anything starts.
    pub async fn check(&self) -> Result<(), SerialError> {
        #[cfg(unix)]
        {
            tty::Tty::open(&self.path).map(drop)
        }
        #[cfg(not(unix))]
        {
            Err(SerialError::Unsupported)
        }
    }
}

impl Link for SerialLink {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move { open(&self.path).await })
    }

    fn framing(&self) -> Option<Framing> {
        Some(FRAMING)
    }

    fn describe(&self) -> String {
        format!("{} on {}", self.model.display_name(), self.path.display())
    }
}

#[cfg(not(unix))]
async fn open(_path: &Path) -> Result<Connection, LinkError> {
    Err(SerialError::Unsupported.into())
}

#[cfg(unix)]
async fn open(path: &Path) -> Result<Connection, LinkError> {
    use std::sync::Arc;
    use tokio::sync::{mpsc, oneshot};
    let tty = Arc::new(tty::Tty::open(path)?);
    let (tx, rx) = mpsc::channel(EVENTS);
    let (stop_tx, mut stop_rx) = oneshot::channel::<()>();
    let reader = tty.clone();
    let shown = path.display().to_string();
    tokio::spawn(async move {
        let mut buf = vec![0u8; READ_MAX];
        loop {
            let n = tokio::select! {
                _ = &mut stop_rx => return,
                _ = tx.closed() => return,
                n = reader.read(&mut buf) => n,
            };
            let why = match n {
                Ok(0) => format!("the serial port {shown} closed"),
                Ok(n) => {
                    if tx.send(LinkEvent::Data(buf[..n].to_vec())).await.is_err() {
                        return;
                    }
                    continue;
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                // EIO: the device went away (an adapter unplugged; the other side of a
                // pseudo-terminal closed).
                Err(e) => format!("the serial port {shown} went away ({e})"),
            };
            let _ = tx.send(LinkEvent::Disconnected(why)).await;
            return;
        }
    });
    Ok(Connection {
        writer: Box::new(SerialWriter {
            tty: Some(tty),
            _stop: Some(stop_tx),
            shown: path.display().to_string(),
        }),
        events: rx,
    })
}

/// `chunk` readdressed for RVR's UART, when it is one whole v2 packet addressed as over
/// Bluetooth: the target's port 1 (0x11, 0x12) becomes port 0 (0x01, 0x02) and the source id
/// goes — what Sphero's `sphero-sdk` 0.3.4 sends on the UART (`SerialAsyncDal`: target 1 or
/// 2, no source). Over the UART, source 0x01 would name RVR's own primary processor, whose
/// answers would not come back to us (unverified on hardware: the SDK's addressing is the
/// one known to work). Anything else is written as it is (`None`).
#[cfg(unix)]
fn uart_addressed(chunk: &[u8]) -> Option<Vec<u8>> {
    use crate::protocol::v2::catalog::targets::Processor;
    use crate::protocol::v2::packet::{EOP, SOP};
    if chunk.first() != Some(&SOP) || chunk.last() != Some(&EOP) {
        return None;
    }
    let mut decoded = crate::protocol::v2::Decoder::new().decode_all(chunk);
    let Some(Ok(mut p)) = decoded.pop() else {
        return None;
    };
    if !decoded.is_empty() || p.is_response() {
        return None;
    }
    let target = Processor::of_id(p.tid?)?;
    p.tid = Some(target.uart_id());
    p.sid = None;
    Some(p.normalized().encode())
}

/// The writing half: whole writes, as they come (no chunking on a serial line).
#[cfg(unix)]
struct SerialWriter {
    tty: Option<std::sync::Arc<tty::Tty>>,
    /// Dropped with the writer (or on close): the reader stops, the port closes.
    _stop: Option<tokio::sync::oneshot::Sender<()>>,
    shown: String,
}

#[cfg(unix)]
impl LinkWriter for SerialWriter {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        Box::pin(async move {
            let tty = self
                .tty
                .as_ref()
                .ok_or_else(|| LinkError::transient("the serial port is closed"))?;
            let bytes = uart_addressed(chunk);
            let bytes = bytes.as_deref().unwrap_or(chunk);
            tty.write_all(bytes).await.map_err(|e| {
                LinkError::transient(format!("writing to the serial port {}: {e}", self.shown))
            })
        })
    }

    fn close(&mut self) -> BoxFuture<'_, ()> {
        self.tty = None;
        self._stop = None;
        Box::pin(async {})
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn commands_are_addressed_as_sphero_sdk_addresses_them_on_the_uart() {
        use crate::protocol::v2::{Flags, Packet};
        let mut p = Packet::command(0x16, 0x07, 3, vec![60, 0, 90, 0]);
        p.flags |= Flags::REQUESTS_RESPONSE;
        p.tid = Some(0x12);
        p.sid = Some(0x01);
        let out = uart_addressed(&p.clone().normalized().encode()).expect("readdressed");
        let back = crate::protocol::v2::Decoder::new().decode_all(&out);
        let [Ok(q)] = back.as_slice() else {
            panic!("{back:?}")
        };
        assert_eq!((q.tid, q.sid), (Some(0x02), None));
        assert_eq!(
            (q.did, q.cid, q.seq, &q.data),
            (0x16, 0x07, 3, &vec![60, 0, 90, 0])
        );
        assert!(q.flags.contains(Flags::REQUESTS_RESPONSE));
        // Without a target, a piece of a packet, or two packets: as they are.
        let plain = Packet::command(0x13, 0x0D, 1, vec![]).normalized().encode();
        assert_eq!(uart_addressed(&plain), None);
        let whole = p.normalized().encode();
        assert_eq!(uart_addressed(&whole[..whole.len() - 1]), None);
        assert_eq!(uart_addressed(&[whole.clone(), whole].concat()), None);
    }

    #[test]
    fn errors_say_what_to_do() {
        let p = Path::new("/dev/ttyX");
        let e = |k: std::io::ErrorKind| SerialError::from_open(p, std::io::Error::from(k));
        assert!(matches!(
            e(std::io::ErrorKind::NotFound),
            SerialError::NotFound(_)
        ));
        let perm = e(std::io::ErrorKind::PermissionDenied);
        assert!(perm.to_string().contains("usermod -aG dialout"), "{perm}");
        assert!(perm.fatal());
        let busy = SerialError::from_open(p, std::io::Error::from_raw_os_error(libc::EBUSY));
        assert!(matches!(busy, SerialError::Busy(_)), "{busy:?}");
        assert!(!busy.fatal());
        let gone = SerialError::from_open(p, std::io::Error::from_raw_os_error(libc::ENXIO));
        assert!(matches!(gone, SerialError::NotFound(_)));
    }

    #[tokio::test]
    async fn a_missing_port_and_a_file_that_is_no_terminal() {
        let dir = std::env::temp_dir().join(format!("droidctl-serial-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        let missing = SerialLink::new(dir.join("ttyNONE"), Model::ON_SERIAL);
        assert!(matches!(
            missing.check().await,
            Err(SerialError::NotFound(_))
        ));
        let file = dir.join("plain");
        std::fs::write(&file, b"x").unwrap();
        let plain = SerialLink::new(&file, Model::ON_SERIAL);
        assert!(matches!(
            plain.check().await,
            Err(SerialError::NotATerminal(_))
        ));
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Bytes both ways through a pseudo-terminal, a second opener refused as busy, and the
    /// controlling side closing is a disconnect.
    #[tokio::test]
    async fn bytes_both_ways_busy_and_loss() {
        let (master, peer, path) = tty::open_pty().unwrap();
        let mut link = SerialLink::new(&path, Model::ON_SERIAL);
        assert_eq!(
            link.droid_name(),
            format!("RV-{}", path.file_name().unwrap().to_string_lossy())
        );
        let mut conn = link.open().await.unwrap();
        assert!(matches!(link.check().await, Err(SerialError::Busy(_))));
        conn.writer.write(&[0x8D, 1, 2, 0xD8]).await.unwrap();
        let mut got = Vec::new();
        let mut buf = [0u8; 16];
        while got.len() < 4 {
            let n = master.read(&mut buf).await.unwrap();
            got.extend_from_slice(&buf[..n]);
        }
        assert_eq!(got, [0x8D, 1, 2, 0xD8]);
        master.write_all(&[0x8D, 9, 0xD8]).await.unwrap();
        let mut back = Vec::new();
        while back.len() < 3 {
            match conn.events.recv().await {
                Some(LinkEvent::Data(d)) => back.extend(d),
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(back, [0x8D, 9, 0xD8]);
        drop(master);
        drop(peer);
        loop {
            match conn.events.recv().await {
                Some(LinkEvent::Disconnected(why)) => {
                    assert!(why.contains(&path.display().to_string()), "{why}");
                    break;
                }
                Some(LinkEvent::Data(_)) => continue,
                None => panic!("ended without a disconnect"),
            }
        }
    }
}
