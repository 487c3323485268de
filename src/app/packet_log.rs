//! The packet log: a bounded ring buffer of formatted entries plus the pane's view state
//! (scroll, pause, filter, decoded/hex). Entries are formatted once, when they arrive, so
//! drawing a full log costs the same as drawing an empty one.

use crate::family::{DroidError, PacketKind};
use crate::hex;
use crate::protocol::v2::Device;
use crate::protocol::value;
use crate::session::{Direction, LogEntry, LogItem};
use std::collections::VecDeque;
use std::time::Duration;

/// Default bound of the log.
pub const DEFAULT_CAPACITY: usize = 10_000;

/// One formatted line of the log.
#[derive(Debug, Clone, PartialEq)]
pub struct LogLine {
    pub at: Duration,
    pub dir: Direction,
    /// Catalogue name, or `power/0x42`, or the decode error kind.
    pub name: String,
    pub did: Option<u8>,
    pub seq: Option<u8>,
    pub err: Option<DroidError>,
    /// A decode error, an error response, or a malformed payload.
    pub is_error: bool,
    pub hex: String,
    /// Decoded fields (`speed=100 heading=90 …`) or the problem.
    pub decoded: String,
    /// Name, fields and hex in lower case, made once so filtering 10,000 lines per frame does
    /// not lower-case them again every time.
    search: String,
    /// The droid the line is about, in a fleet (`None` with one droid).
    pub droid: Option<std::sync::Arc<str>>,
    /// Every decoded field, name and value, for the detail view.
    pub fields: Vec<(&'static str, String)>,
    /// The frame's parts in wire order (`start 8D`, `flags 0A`, …, `data …`, `checksum`),
    /// for the detail view; one `bytes` part where the family's frame is not taken apart.
    pub parts: Vec<(&'static str, String)>,
}

/// The parts of `p`'s frame, unescaped, in wire order.
pub fn frame_parts(p: &crate::family::Packet) -> Vec<(&'static str, String)> {
    use crate::protocol::v2::packet as v2;
    let b = |x: u8| format!("{x:02X}");
    match p {
        crate::family::Packet::V2(p) => {
            let mut parts = vec![("start", b(v2::SOP)), ("flags", b(p.flags.bits()))];
            parts.extend(p.ext_flags.map(|x| ("ext flags", b(x))));
            parts.extend(p.tid.map(|x| ("target", b(x))));
            parts.extend(p.sid.map(|x| ("source", b(x))));
            parts.extend([
                ("device", b(p.did)),
                ("command", b(p.cid)),
                ("seq", b(p.seq)),
            ]);
            parts.extend(p.err.map(|e| ("error", b(e.to_byte()))));
            if !p.data.is_empty() {
                parts.push(("data", hex::spaced(&p.data)));
            }
            let mut body = Vec::new();
            p.encode_into(&mut body);
            // The checksum is the last byte before EOP, unescaped.
            let inner = &body[1..body.len().saturating_sub(1)];
            let chk = v2::checksum(&unescaped_body(inner));
            parts.extend([("checksum", b(chk)), ("end", b(v2::EOP))]);
            parts
        }
        other => vec![("bytes", hex::spaced(&other.encode()))],
    }
}

/// The body of an escaped v2 frame without its checksum (for the detail view).
fn unescaped_body(escaped: &[u8]) -> Vec<u8> {
    use crate::protocol::v2::packet as v2;
    let mut out = Vec::with_capacity(escaped.len());
    let mut it = escaped.iter();
    while let Some(&x) = it.next() {
        out.push(if x == v2::ESC {
            match it.next() {
                Some(&v2::ESC_SOP) => v2::SOP,
                Some(&v2::ESC_EOP) => v2::EOP,
                _ => v2::ESC,
            }
        } else {
            x
        });
    }
    out.pop();
    out
}

impl LogLine {
    pub fn from_entry(e: &LogEntry) -> LogLine {
        let mut line = Self::format(e);
        let err = line.err.map(|e| e.name()).unwrap_or_default();
        line.search =
            format!("{}\n{}\n{}\n{err}", line.name, line.decoded, line.hex).to_ascii_lowercase();
        line
    }

    /// The line of `e`, about the fleet's droid `droid`.
    pub fn from_droid_entry(e: &LogEntry, droid: std::sync::Arc<str>) -> LogLine {
        let mut line = Self::from_entry(e);
        line.droid = Some(droid);
        line
    }

    fn format(e: &LogEntry) -> LogLine {
        match &e.item {
            LogItem::Packet {
                packet,
                explained: d,
            } => {
                let err = d.error;
                let decoded = match (&d.fields, &d.problem) {
                    (Some(f), _) if f.is_empty() => String::new(),
                    (Some(f), _) => value::fields_line(f),
                    (None, Some(problem)) => problem.clone(),
                    (None, None) => String::new(),
                };
                let is_error = err.is_some()
                    || (d.fields.is_none() && d.kind != PacketKind::Command && d.known);
                let fields = d
                    .fields
                    .iter()
                    .flatten()
                    .map(|(n, v)| (*n, v.to_string()))
                    .collect();
                LogLine {
                    at: e.at,
                    dir: e.dir,
                    name: d.label.clone(),
                    did: d.did,
                    seq: d.seq,
                    err,
                    is_error,
                    hex: hex::spaced(&packet.encode()),
                    decoded,
                    search: String::new(),
                    droid: None,
                    fields,
                    parts: frame_parts(packet),
                }
            }
            LogItem::DecodeError(de) => LogLine {
                at: e.at,
                dir: e.dir,
                name: format!("decode error: {}", de.kind.name()),
                did: None,
                seq: None,
                err: None,
                is_error: true,
                hex: String::new(),
                decoded: de.detail.clone(),
                search: String::new(),
                droid: None,
                fields: Vec::new(),
                parts: Vec::new(),
            },
        }
    }
}

/// Which lines the pane shows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LogFilter {
    pub dir: Option<Direction>,
    pub did: Option<u8>,
    /// Case-insensitive text that must appear in the name, decoded fields, hex or error name.
    pub text: String,
    /// `text` in lower case.
    lower: String,
    /// `droid:NAME`: only lines about a droid whose name contains this (lower case).
    pub droid: Option<String>,
}

impl LogFilter {
    pub fn matches(&self, l: &LogLine) -> bool {
        if self.dir.is_some_and(|d| d != l.dir) {
            return false;
        }
        if self.did.is_some() && self.did != l.did {
            return false;
        }
        if let Some(d) = &self.droid
            && !l
                .droid
                .as_deref()
                .is_some_and(|n| n.to_ascii_lowercase().contains(d.as_str()))
        {
            return false;
        }
        if self.text.is_empty() {
            return true;
        }
        l.search.contains(&self.lower)
    }

    pub fn is_active(&self) -> bool {
        self.dir.is_some() || self.did.is_some() || self.droid.is_some() || !self.text.is_empty()
    }

    /// Parse the filter prompt: words `in`/`out`, `dev:NAME` (or a device name), free text.
    pub fn parse(input: &str) -> LogFilter {
        let mut f = LogFilter::default();
        let mut text = Vec::new();
        for w in input.split_whitespace() {
            match w.to_ascii_lowercase().as_str() {
                "in" | "<-" => f.dir = Some(Direction::In),
                "out" | "->" => f.dir = Some(Direction::Out),
                lw if lw.len() > 6 && lw.starts_with("droid:") => {
                    f.droid = Some(lw["droid:".len()..].to_string())
                }
                lw => match lw.strip_prefix("dev:").and_then(Device::parse) {
                    Some(did) => f.did = Some(did),
                    None => text.push(w),
                },
            }
        }
        f.text = text.join(" ");
        f.lower = f.text.to_ascii_lowercase();
        f
    }

    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if let Some(d) = self.dir {
            parts.push(if d == Direction::In {
                "in".to_string()
            } else {
                "out".to_string()
            });
        }
        if let Some(did) = self.did {
            parts.push(format!("dev:{}", Device::describe(did)));
        }
        if let Some(d) = &self.droid {
            parts.push(format!("droid:{d}"));
        }
        if !self.text.is_empty() {
            parts.push(format!("{:?}", self.text));
        }
        parts.join(" ")
    }
}

/// The log and its view state.
#[derive(Debug, Clone)]
pub struct PacketLog {
    lines: VecDeque<LogLine>,
    capacity: usize,
    /// Lines scrolled up from the newest (0 = follow the tail).
    pub scroll: usize,
    /// The selected line, counted up from the bottom of the window (0: the bottom line). The
    /// cursor moves inside the window and the window scrolls only at its edges, as in lazygit's
    /// lists; Enter opens the selected line.
    pub cursor: usize,
    /// Paused: the view holds still while lines keep arriving.
    pub paused: bool,
    /// Show decoded fields (true) or raw hex (false).
    pub decoded: bool,
    pub filter: LogFilter,
    /// Lines dropped off the front since the start.
    pub dropped: u64,
    pub total: u64,
}

impl Default for PacketLog {
    fn default() -> Self {
        Self::with_capacity(DEFAULT_CAPACITY)
    }
}

impl PacketLog {
    pub fn with_capacity(capacity: usize) -> Self {
        PacketLog {
            lines: VecDeque::with_capacity(capacity.min(1024)),
            capacity: capacity.max(1),
            scroll: 0,
            cursor: 0,
            paused: false,
            decoded: true,
            filter: LogFilter::default(),
            dropped: 0,
            total: 0,
        }
    }

    pub fn push(&mut self, line: LogLine) {
        if self.lines.len() >= self.capacity {
            self.lines.pop_front();
            self.dropped += 1;
        }
        // While paused, scrolled back or with a line selected above the newest, keep the same
        // lines in view (the selection stays on its line).
        if (self.paused || self.scroll > 0 || self.cursor > 0) && self.filter.matches(&line) {
            self.scroll += 1;
        }
        self.lines.push_back(line);
        self.total += 1;
    }

    pub fn len(&self) -> usize {
        self.lines.len()
    }

    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// The lines passing the filter, oldest first.
    pub fn filtered(&self) -> impl DoubleEndedIterator<Item = &LogLine> {
        self.lines.iter().filter(|l| self.filter.matches(l))
    }

    /// The `height` lines to show, oldest first, honouring scroll.
    pub fn visible(&self, height: usize) -> Vec<&LogLine> {
        // Scrolled back to the oldest line: a full page of the oldest, not one line.
        let skip = self
            .scroll
            .min(self.filtered().count().saturating_sub(height));
        let mut v: Vec<&LogLine> = self.filtered().rev().skip(skip).take(height).collect();
        v.reverse();
        v
    }

    pub fn scroll_up(&mut self, n: usize) {
        let max = self.filtered().count().saturating_sub(1);
        self.scroll = (self.scroll + n).min(max);
    }

    pub fn scroll_down(&mut self, n: usize) {
        self.scroll = self.scroll.saturating_sub(n);
    }

    /// The selected line in a window of `rows` lines.
    pub fn selected(&self, rows: usize) -> Option<&LogLine> {
        let v = self.visible(rows);
        v.get(self.selected_index(v.len())?).copied()
    }

    /// Where the selected line is among `shown` lines in view (a window made smaller since
    /// keeps its top line selected).
    pub fn selected_index(&self, shown: usize) -> Option<usize> {
        let last = shown.checked_sub(1)?;
        Some(last - self.cursor.min(last))
    }

    /// The window's real offset: scrolled past the oldest page, the view shows that page.
    fn settle(&mut self, rows: usize) {
        let count = self.filtered().count();
        self.scroll = self.scroll.min(count.saturating_sub(rows));
        let shown = count.min(rows);
        self.cursor = self.cursor.min(shown.saturating_sub(1));
    }

    /// Cursor one line up (older) in a window of `rows` lines; at the window's top edge the
    /// window scrolls.
    pub fn cursor_up(&mut self, rows: usize) {
        self.settle(rows);
        let count = self.filtered().count();
        let shown = count.min(rows);
        if self.cursor + 1 < shown {
            self.cursor += 1;
        } else if self.scroll + shown < count {
            self.scroll += 1;
        }
    }

    /// Cursor one line down (newer); at the bottom edge the window scrolls.
    pub fn cursor_down(&mut self, rows: usize) {
        self.settle(rows);
        if self.cursor > 0 {
            self.cursor -= 1;
        } else {
            self.scroll = self.scroll.saturating_sub(1);
        }
    }

    /// To the oldest line (selected).
    pub fn cursor_top(&mut self, rows: usize) {
        self.scroll = usize::MAX / 2;
        self.cursor = usize::MAX / 2;
        self.settle(rows);
    }

    /// To the newest line, following the tail again.
    pub fn cursor_bottom(&mut self) {
        self.scroll = 0;
        self.cursor = 0;
    }

    pub fn toggle_pause(&mut self) {
        self.paused = !self.paused;
        if !self.paused {
            self.scroll = 0;
            self.cursor = 0;
        }
    }

    pub fn set_filter(&mut self, f: LogFilter) {
        self.filter = f;
        self.scroll = 0;
        self.cursor = 0;
    }

    /// The filter as text, to edit it again in the prompt.
    pub fn filter_input(&self) -> String {
        let mut parts = Vec::new();
        if let Some(d) = self.filter.dir {
            parts.push(if d == Direction::In {
                "in".to_string()
            } else {
                "out".to_string()
            });
        }
        if let Some(did) = self.filter.did {
            parts.push(format!("dev:{}", Device::describe(did)));
        }
        if let Some(d) = &self.filter.droid {
            parts.push(format!("droid:{d}"));
        }
        if !self.filter.text.is_empty() {
            parts.push(self.filter.text.clone());
        }
        parts.join(" ")
    }

    pub fn errors(&self) -> usize {
        self.lines.iter().filter(|l| l.is_error).count()
    }
}

/// Re-exported for the UI: direction arrows.
pub fn arrow(d: Direction) -> &'static str {
    d.arrow()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::v2::{ErrorCode, Packet, cmd};

    fn entry(dir: Direction, p: Packet, ms: u64) -> LogEntry {
        LogEntry {
            at: Duration::from_millis(ms),
            dir,
            item: LogItem::Packet {
                explained: crate::family::v2::explain(&p, None),
                packet: crate::family::Packet::V2(p),
            },
        }
    }

    fn line(dir: Direction, p: Packet) -> LogLine {
        LogLine::from_entry(&entry(dir, p, 0))
    }

    #[test]
    fn formats_commands_responses_and_errors() {
        let wake = cmd::wake().to_packet(7);
        let l = line(Direction::Out, wake.clone());
        assert_eq!(l.name, "wake");
        assert_eq!(l.seq, Some(7));
        assert_eq!(l.hex, "8D 0A 13 0D 07 CE D8");
        assert!(!l.is_error);
        let bad = Packet::response_to(&wake, ErrorCode::BadDataLength, vec![]);
        let l = line(Direction::In, bad);
        assert!(l.is_error);
        assert_eq!(l.err, Some(DroidError::V2(ErrorCode::BadDataLength)));
        let de = crate::protocol::v2::Decoder::new().decode_all(&[0x8D, 0x0A, 0x13, 0xD8]);
        let Err(e) = de[0].clone() else { panic!() };
        let l = LogLine::from_entry(&LogEntry {
            at: Duration::ZERO,
            dir: Direction::In,
            item: LogItem::DecodeError(crate::family::v2::read::seam_error(e)),
        });
        assert!(l.is_error && l.name.contains("too_short"));
    }

    #[test]
    fn ring_buffer_is_bounded() {
        let mut log = PacketLog::with_capacity(100);
        for i in 0..1000u32 {
            log.push(line(
                Direction::Out,
                cmd::play_animation(i as u16).to_packet(0),
            ));
        }
        assert_eq!(log.len(), 100);
        assert_eq!(log.dropped, 900);
        assert_eq!(log.total, 1000);
    }

    #[test]
    fn filter_by_direction_device_text() {
        let mut log = PacketLog::default();
        log.push(line(Direction::Out, cmd::wake().to_packet(0)));
        log.push(line(Direction::Out, cmd::play_animation(3).to_packet(1)));
        log.push(line(
            Direction::In,
            Packet::response_to(&cmd::wake().to_packet(0), ErrorCode::Success, vec![]),
        ));
        log.set_filter(LogFilter::parse("out"));
        assert_eq!(log.filtered().count(), 2);
        log.set_filter(LogFilter::parse("dev:animatronic"));
        assert_eq!(log.filtered().count(), 1);
        log.set_filter(LogFilter::parse("in wake"));
        assert_eq!(log.filtered().count(), 1);
        assert_eq!(
            LogFilter::parse("in dev:power wake").describe(),
            "in dev:power \"wake\""
        );
        log.set_filter(LogFilter::parse("ANIMATION"));
        assert_eq!(log.filtered().count(), 1);
    }

    #[test]
    fn pause_and_scroll_hold_the_view() {
        let mut log = PacketLog::default();
        for i in 0..10u16 {
            log.push(line(
                Direction::Out,
                cmd::play_animation(i).to_packet(i as u8),
            ));
        }
        assert_eq!(log.visible(3).last().unwrap().seq, Some(9));
        log.toggle_pause();
        log.push(line(Direction::Out, cmd::play_animation(10).to_packet(10)));
        assert_eq!(log.visible(3).last().unwrap().seq, Some(9));
        log.toggle_pause();
        assert_eq!(log.visible(3).last().unwrap().seq, Some(10));
        log.scroll_up(2);
        assert_eq!(log.visible(3).last().unwrap().seq, Some(8));
        log.scroll_up(1000);
        assert_eq!(log.visible(3).first().unwrap().seq, Some(0));
        log.scroll_down(1000);
        assert_eq!(log.scroll, 0);
    }

    fn numbered(n: u16) -> PacketLog {
        let mut log = PacketLog::default();
        for i in 0..n {
            log.push(line(
                Direction::Out,
                cmd::play_animation(i).to_packet(i as u8),
            ));
        }
        log
    }

    #[test]
    fn the_cursor_moves_inside_the_window_and_scrolls_at_its_edges() {
        let mut log = numbered(10);
        assert_eq!(log.selected(3).unwrap().seq, Some(9));
        log.cursor_up(3);
        log.cursor_up(3);
        // The top of a three-line window: the window has not moved.
        assert_eq!(log.selected(3).unwrap().seq, Some(7));
        assert_eq!(log.visible(3).last().unwrap().seq, Some(9));
        log.cursor_up(3);
        assert_eq!(log.selected(3).unwrap().seq, Some(6));
        assert_eq!(log.visible(3).first().unwrap().seq, Some(6));
        log.cursor_down(3);
        assert_eq!(log.selected(3).unwrap().seq, Some(7));
        assert_eq!(log.visible(3).first().unwrap().seq, Some(6), "window holds");
        // New lines keep the selection on its line.
        log.push(line(Direction::Out, cmd::play_animation(10).to_packet(10)));
        assert_eq!(log.selected(3).unwrap().seq, Some(7));
        log.cursor_top(3);
        assert_eq!(log.selected(3).unwrap().seq, Some(0));
        log.cursor_up(3);
        assert_eq!(
            log.selected(3).unwrap().seq,
            Some(0),
            "nothing above the oldest"
        );
        log.cursor_bottom();
        assert_eq!(log.selected(3).unwrap().seq, Some(10));
        log.push(line(Direction::Out, cmd::play_animation(11).to_packet(11)));
        assert_eq!(
            log.selected(3).unwrap().seq,
            Some(11),
            "following the tail again"
        );
    }

    #[test]
    fn a_short_log_selects_only_lines_that_exist() {
        let mut log = numbered(2);
        for _ in 0..5 {
            log.cursor_up(10);
        }
        assert_eq!(log.selected(10).unwrap().seq, Some(0));
        assert!(PacketLog::default().selected(10).is_none());
    }
}
