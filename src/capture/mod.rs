//! Captures: what went over a link, kept for later. droidctl writes its own line-based format
//! (`--record`, [`crate::capture::record`]); it also reads the HCI snoop logs phones and BlueZ
//! write ([`btsnoop`], [`hci`]). Either way a capture becomes a list of timed [`Event`]s that
//! replay ([`replay`]) and `packet decode` ([`mirror`]) decode with the droid's family.
//!
//! # The droidctl capture format (version 1)
//!
//! UTF-8 text, one item per line, `\n` line ends:
//!
//! ```text
//! droidctl-capture 1
//! # droidctl: 0.1.0
//! # model: r2d2
//! # family: v2
//! # droid: R2-D2 (simulated)
//! # started: 2025-06-01T10:00:00.123Z
//! 0.000 connect
//! 0.000 out api 8d0a130d00d5d8
//! 0.012 in notify 8d09130d0000d6d8
//! 5000.250 disconnect simulated link loss
//! 6000.000 mark mission-end
//! 6000.000 close
//! 6000.001 end
//! ```
//!
//! The first line names the format and its version. `# key: value` lines before the first
//! event are the header (`droidctl` version, `model` id, protocol `family` v2/v1/rsrcp,
//! `droid` name, `started` UTC time); other `#` lines are comments. Every event line is
//! `T KIND [ARGS]`, `T` the time in milliseconds since the recording started (three decimals:
//! microseconds). Kinds:
//!
//! | kind | arguments | meaning |
//! |---|---|---|
//! | `connect` | | the link opened (handshake done) |
//! | `connect-failed` | reason | an attempt to open failed |
//! | `out` | endpoint, hex | a chunk written: endpoint `api` (the command channel), `velocity` or `steering` (Robi 42) |
//! | `write-failed` | reason | the write before it failed |
//! | `in` | `notify`, hex | a chunk received (a notification, or a value read while connecting) |
//! | `disconnect` | reason | the link went down |
//! | `close` | | droidctl closed the link |
//! | `mark` | text | a point droidctl noted (`mission-start`, `mission-end`) |
//! | `end` | | the recording ended cleanly (missing after a crash) |
//!
//! Hex is lower case without separators. Readers skip unknown kinds (with a warning) so later
//! versions can add some.

pub mod btsnoop;
pub mod fleet;
pub mod hci;
pub mod mirror;
pub mod record;
pub mod replay;

use crate::gatt::Endpoint;
use crate::model::{Model, Protocol};
use std::fmt::Write as _;
use std::time::Duration;

/// The first line of a droidctl capture.
pub const MAGIC: &str = "droidctl-capture";
pub const VERSION: u32 = 1;

/// The largest chunk a capture may hold, in bytes. Real ones are at most 512 (an ATT value:
/// a BLE write or notification); a line claiming more is damage or a crafted file, and one
/// such line of 1 MiB made replay build 150 times its size in decode errors (issue 27
/// point 4). Larger chunks are a counted, visible warning, and skipped.
pub const MAX_CHUNK: usize = 1024;

/// Problems met reading a file, bounded: the first [`KEPT_WARNINGS`] word for word, the rest
/// counted (a crafted file of a million bad lines gives a dozen lines, not a million).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Warnings {
    kept: Vec<String>,
    more: usize,
}

/// How many warnings a file keeps word for word.
pub const KEPT_WARNINGS: usize = 10;

impl Warnings {
    pub fn push(&mut self, w: String) {
        if self.kept.len() < KEPT_WARNINGS {
            self.kept.push(w);
        } else {
            self.more += 1;
        }
    }

    /// How many there were in all.
    pub fn count(&self) -> usize {
        self.kept.len() + self.more
    }

    /// The lines to show: the first ones, then how many more there were.
    pub fn into_lines(mut self) -> Vec<String> {
        if self.more > 0 {
            self.kept.push(format!(
                "… and {} more warning(s) like these ({} in all)",
                self.more,
                self.count()
            ));
        }
        self.kept
    }
}

/// Which way a chunk went.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Dir {
    /// Host → droid.
    Out,
    /// Droid → host.
    In,
}

/// What happened, without the time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event {
    Connect,
    ConnectFailed(String),
    Out(Endpoint, Vec<u8>),
    WriteFailed(String),
    In(Vec<u8>),
    Disconnect(String),
    Close,
    Mark(String),
    End,
}

impl Event {
    /// The family the event's bytes show (see [`crate::family::of_traffic`]).
    pub fn family(&self) -> Option<Protocol> {
        let f = match self {
            Event::Out(to, b) => crate::family::of_traffic(Some(*to), b),
            Event::In(b) => crate::family::of_traffic(None, b),
            _ => None,
        };
        f.map(|f| f.protocol())
    }
}

/// An event and when it happened (since the recording started).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Timed {
    pub at: Duration,
    pub event: Event,
}

/// What a capture says about itself.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Header {
    pub droidctl: Option<String>,
    pub model: Option<Model>,
    pub family: Option<Protocol>,
    pub droid: Option<String>,
    pub started: Option<String>,
}

fn endpoint_from_name(s: &str) -> Option<Endpoint> {
    [Endpoint::Api, Endpoint::Velocity, Endpoint::Steering]
        .into_iter()
        .find(|e| e.name() == s)
}

/// `T` as written: milliseconds with three decimals.
pub fn format_time(at: Duration) -> String {
    let us = at.as_micros();
    format!("{}.{:03}", us / 1000, us % 1000)
}

fn parse_time(s: &str) -> Option<Duration> {
    let (ms, frac) = s.split_once('.').unwrap_or((s, ""));
    if ms.is_empty()
        || frac.len() > 3
        || !ms.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit())
    {
        return None;
    }
    let ms: u64 = ms.parse().ok()?;
    let mut us: u64 = 0;
    for (i, b) in frac.bytes().enumerate() {
        us += (b - b'0') as u64 * [100, 10, 1][i];
    }
    Some(Duration::from_millis(ms) + Duration::from_micros(us))
}

/// Keep a reason on one line.
fn one_line(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

/// The header lines, from the magic line on.
pub fn header_text(h: &Header) -> String {
    let mut s = format!("{MAGIC} {VERSION}\n");
    let mut line = |k: &str, v: Option<&str>| {
        if let Some(v) = v {
            let _ = writeln!(s, "# {k}: {}", one_line(v));
        }
    };
    line("droidctl", h.droidctl.as_deref());
    line("model", h.model.map(Model::id));
    line(
        "family",
        h.family.map(|p| crate::family::for_protocol(p).name()),
    );
    line("droid", h.droid.as_deref());
    line("started", h.started.as_deref());
    s
}

/// One event line, with its line end.
pub fn event_line(t: &Timed) -> String {
    let at = format_time(t.at);
    let hex = crate::hex::compact;
    match &t.event {
        Event::Connect => format!("{at} connect\n"),
        Event::ConnectFailed(r) => format!("{at} connect-failed {}\n", one_line(r)),
        Event::Out(e, b) => format!("{at} out {} {}\n", e.name(), hex(b)),
        Event::WriteFailed(r) => format!("{at} write-failed {}\n", one_line(r)),
        Event::In(b) => format!("{at} in notify {}\n", hex(b)),
        Event::Disconnect(r) => format!("{at} disconnect {}\n", one_line(r)),
        Event::Close => format!("{at} close\n"),
        Event::Mark(m) => format!("{at} mark {}\n", one_line(m)),
        Event::End => format!("{at} end\n"),
    }
}

/// Why a line of a capture could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LineError {
    /// 1-based line number.
    pub line: usize,
    pub message: String,
}

impl std::fmt::Display for LineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

/// A droidctl capture read line by line: the header, then events. Bad lines are reported
/// and skipped; an unknown version or a missing magic line is an error at line 1.
#[derive(Debug, Default)]
pub struct TextReader {
    line: usize,
    pub header: Header,
    in_header: bool,
    /// Events are in time order; a line going back in time is an error.
    last: Duration,
}

/// What one line held.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Line {
    Nothing,
    Event(Timed),
    /// A line of an unknown kind (a later version), skipped.
    Unknown(String),
}

impl TextReader {
    pub fn new() -> Self {
        TextReader {
            in_header: true,
            ..Default::default()
        }
    }

    /// Whether `bytes` starts like a droidctl capture.
    pub fn sniff(bytes: &[u8]) -> bool {
        bytes.starts_with(MAGIC.as_bytes())
    }

    /// [`TextReader::line`] for line `n` of a file this reader sees only some lines of (a
    /// droid's lines of a capture of several droids): messages give the file's line.
    pub fn line_at(&mut self, n: usize, text: &str) -> Result<Line, LineError> {
        self.line = n.saturating_sub(1).max(1);
        self.line(text)
    }

    pub fn line(&mut self, text: &str) -> Result<Line, LineError> {
        self.line += 1;
        let err = |message: String| LineError {
            line: self.line,
            message,
        };
        let text = text.trim_end_matches(['\r', '\n']);
        if self.line == 1 {
            let mut words = text.split_whitespace();
            if words.next() != Some(MAGIC) {
                return Err(err(format!(
                    "not a droidctl capture (it does not start with {MAGIC:?})"
                )));
            }
            return match words.next().and_then(|v| v.parse::<u32>().ok()) {
                Some(VERSION) => Ok(Line::Nothing),
                Some(fleet::FLEET_VERSION) => Err(err(
                    "a capture of several droids (version 2): `droidctl replay` plays them \
                     together"
                        .into(),
                )),
                Some(v) => Err(err(format!(
                    "capture format version {v}; this droidctl reads version {VERSION}"
                ))),
                None => Err(err("the capture format version is missing".into())),
            };
        }
        if text.trim().is_empty() {
            return Ok(Line::Nothing);
        }
        if let Some(comment) = text.strip_prefix('#') {
            if self.in_header
                && let Some((k, v)) = comment.split_once(':')
            {
                let v = v.trim().to_string();
                match k.trim() {
                    "droidctl" => self.header.droidctl = Some(v),
                    "model" => {
                        self.header.model = Some(
                            Model::from_id(&v)
                                .ok_or_else(|| err(format!("unknown model {:?}", shown(&v))))?,
                        )
                    }
                    "family" => {
                        self.header.family = Some(
                            crate::family::by_name(&v)
                                .map(|f| f.protocol())
                                .ok_or_else(|| err(format!("unknown family {:?}", shown(&v))))?,
                        )
                    }
                    "droid" => self.header.droid = Some(v),
                    "started" => self.header.started = Some(v),
                    _ => {}
                }
            }
            return Ok(Line::Nothing);
        }
        self.in_header = false;
        let (t, rest) = text.split_once(' ').unwrap_or((text, ""));
        let at = parse_time(t).ok_or_else(|| err(format!("{:?} is not a time in ms", shown(t))))?;
        if at < self.last {
            return Err(err(format!(
                "time {t} goes back (the line before was at {})",
                format_time(self.last)
            )));
        }
        self.last = at;
        let (kind, args) = rest.split_once(' ').unwrap_or((rest, ""));
        let hex = |s: &str| {
            let s = s.trim();
            if s.len() > 2 * MAX_CHUNK {
                return Err(err(format!(
                    "a chunk of {} bytes: real chunks are at most 512 (the limit is {MAX_CHUNK}); skipped",
                    s.len() / 2
                )));
            }
            crate::hex::parse(s).map_err(&err)
        };
        let event = match kind {
            "connect" => Event::Connect,
            "connect-failed" => Event::ConnectFailed(args.to_string()),
            "write-failed" => Event::WriteFailed(args.to_string()),
            "disconnect" => Event::Disconnect(args.to_string()),
            "close" => Event::Close,
            "mark" => Event::Mark(args.to_string()),
            "end" => Event::End,
            "out" => {
                let (ep, data) = args.split_once(' ').unwrap_or((args, ""));
                let ep = endpoint_from_name(ep)
                    .ok_or_else(|| err(format!("unknown endpoint {:?}", shown(ep))))?;
                Event::Out(ep, hex(data)?)
            }
            "in" => {
                let (_, data) = args.split_once(' ').unwrap_or(("", args));
                Event::In(hex(data)?)
            }
            "" => return Err(err("an event without a kind".into())),
            other => return Ok(Line::Unknown(other.to_string())),
        };
        Ok(Line::Event(Timed { at, event }))
    }
}

/// A whole capture in memory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Capture {
    pub header: Header,
    pub events: Vec<Timed>,
    /// Problems met while reading (bad lines skipped, a damaged record); the capture holds
    /// what could be read.
    pub warnings: Vec<String>,
    /// The capture's kind for messages: "droidctl capture" or "btsnoop log".
    pub kind: &'static str,
}

/// The warning for a line of an unknown kind.
pub(crate) fn unknown_kind(line: usize, kind: &str) -> String {
    format!("line {line}: unknown event kind {:?} skipped", shown(kind))
}

/// A word of a file as a message shows it: at most 40 characters (a crafted line of 10 MB
/// is not copied into its warning).
pub(crate) fn shown(s: &str) -> String {
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_string(),
    }
}

impl Capture {
    /// The end of reading: the warnings, summarised, and a missing `end` line said.
    pub(crate) fn finish(&mut self, warnings: Warnings) {
        self.warnings.extend(warnings.into_lines());
        if !self.events.iter().any(|t| t.event == Event::End) && !self.events.is_empty() {
            self.warnings.push(
                "the capture has no `end` line: the recording stopped early (a crash or a kill); it holds what was flushed"
                    .into(),
            );
        }
    }

    /// The family to decode with: the header's, else detected from the traffic.
    pub fn family(&self) -> Option<Protocol> {
        self.header
            .family
            .or(self.header.model.map(Model::protocol))
            .or_else(|| self.events.iter().find_map(|t| t.event.family()))
    }

    /// The time of the last event.
    pub fn duration(&self) -> Duration {
        self.events.last().map(|t| t.at).unwrap_or_default()
    }

    /// Read a droidctl capture from text.
    pub fn from_text(text: &str) -> Result<Capture, String> {
        let mut r = TextReader::new();
        let mut c = Capture {
            kind: "droidctl capture",
            ..Default::default()
        };
        let mut warnings = Warnings::default();
        for (i, line) in text.split_inclusive('\n').enumerate() {
            match r.line(line) {
                Ok(Line::Event(t)) => c.events.push(t),
                Ok(Line::Nothing) => {}
                Ok(Line::Unknown(kind)) => warnings.push(unknown_kind(i + 1, &kind)),
                Err(e) if e.line == 1 => return Err(e.to_string()),
                Err(e) => warnings.push(e.to_string()),
            }
        }
        if r.line == 0 {
            return Err("the capture is empty".into());
        }
        c.header = r.header;
        c.finish(warnings);
        Ok(c)
    }

    /// Read a capture file of either kind (droidctl or btsnoop, told by their first bytes).
    pub fn load(path: &std::path::Path) -> Result<Capture, String> {
        Capture::load_with(path, &[])
    }

    /// [`Capture::load`]; a btsnoop log's droid characteristics are `handles` when given.
    pub fn load_with(path: &std::path::Path, handles: &[u16]) -> Result<Capture, String> {
        let bytes =
            std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        Capture::from_bytes(&bytes, handles, &path.display().to_string())
    }

    /// A capture of either kind from its bytes (`name` says what they are in messages).
    pub fn from_bytes(bytes: &[u8], handles: &[u16], name: &str) -> Result<Capture, String> {
        if btsnoop::sniff(bytes) {
            return hci::capture_from_btsnoop(bytes, handles);
        }
        if TextReader::sniff(bytes) {
            let text = String::from_utf8_lossy(bytes);
            return Capture::from_text(&text);
        }
        Err(format!(
            "{name} is neither a droidctl capture (it starts with \"{MAGIC}\") nor a btsnoop log (\"btsnoop\\0\")"
        ))
    }

    /// The whole capture as droidctl text.
    pub fn to_text(&self) -> String {
        let mut s = header_text(&self.header);
        for t in &self.events {
            s.push_str(&event_line(t));
        }
        s
    }
}

/// UTC time as RFC 3339 with milliseconds, from the system clock.
pub fn now_rfc3339() -> String {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    rfc3339(now)
}

/// `since_epoch` as `YYYY-MM-DDTHH:MM:SS.mmmZ` (the civil-from-days algorithm).
pub fn rfc3339(since_epoch: Duration) -> String {
    let secs = since_epoch.as_secs() as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (m <= 2) as i64;
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}.{:03}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60,
        since_epoch.subsec_millis()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_round_trip() {
        for us in [0u64, 1, 999, 1000, 1234567, 86_400_000_001] {
            let d = Duration::from_micros(us);
            assert_eq!(parse_time(&format_time(d)), Some(d));
        }
        assert_eq!(parse_time("12"), Some(Duration::from_millis(12)));
        assert_eq!(parse_time("1.5"), Some(Duration::from_micros(1500)));
        for bad in ["", "-1", "1.2345", "a", "1.x", ".5"] {
            assert_eq!(parse_time(bad), None, "{bad}");
        }
    }

    #[test]
    fn text_round_trip() {
        let c = Capture {
            header: Header {
                droidctl: Some("0.1.0".into()),
                model: Some(Model::Robi42),
                family: Some(Protocol::Rsrcp),
                droid: Some("Robi 42 (simulated)".into()),
                started: Some("2025-06-01T10:00:00.000Z".into()),
            },
            events: vec![
                Timed {
                    at: Duration::ZERO,
                    event: Event::Connect,
                },
                Timed {
                    at: Duration::from_micros(1500),
                    event: Event::Out(Endpoint::Velocity, vec![0x80]),
                },
                Timed {
                    at: Duration::from_millis(2),
                    event: Event::In(vec![0x7e, 1, 2]),
                },
                Timed {
                    at: Duration::from_millis(3),
                    event: Event::Disconnect("gone\nfor good".into()),
                },
                Timed {
                    at: Duration::from_millis(3),
                    event: Event::Mark("mission-end".into()),
                },
                Timed {
                    at: Duration::from_millis(4),
                    event: Event::End,
                },
            ],
            warnings: vec![],
            kind: "droidctl capture",
        };
        let text = c.to_text();
        assert!(text.contains("3.000 disconnect gone for good\n"), "{text}");
        let back = Capture::from_text(&text).unwrap();
        assert_eq!(back.header, c.header);
        assert_eq!(back.events.len(), 6);
        assert_eq!(back.events[1], c.events[1]);
        assert!(back.warnings.is_empty(), "{:?}", back.warnings);
    }

    #[test]
    fn damaged_lines_are_skipped_with_a_warning() {
        let text = "droidctl-capture 1\n# family: v2\n1.000 connect\nxyz in notify 00\n2.000 in notify 8d0\n3.000 teleport 1\n0.500 close\n4.000 in notify 8d";
        let c = Capture::from_text(text).unwrap();
        assert_eq!(c.events.len(), 2, "{:?}", c.events);
        assert_eq!(c.warnings.len(), 5, "{:?}", c.warnings);
        assert!(c.warnings[0].starts_with("line 4:"), "{:?}", c.warnings);
        assert!(c.warnings.iter().any(|w| w.contains("goes back")));
        assert!(c.warnings.iter().any(|w| w.contains("no `end` line")));
        assert_eq!(c.family(), Some(Protocol::SpheroV2));
        assert!(
            Capture::from_text("droidctl-capture 2\n")
                .unwrap_err()
                .contains("version 2")
        );
        assert!(Capture::from_text("hello\n").is_err());
    }

    #[test]
    fn civil_time() {
        assert_eq!(rfc3339(Duration::ZERO), "1970-01-01T00:00:00.000Z");
        assert_eq!(
            rfc3339(Duration::from_millis(951_782_400_123)),
            "2000-02-29T00:00:00.123Z"
        );
        assert_eq!(
            rfc3339(Duration::from_secs(1_748_772_000)),
            "2025-06-01T10:00:00.000Z"
        );
    }
}
