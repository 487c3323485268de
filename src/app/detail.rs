//! A packet in full (issue 30 point 3): `Enter` in the packet log opens its newest line shown
//! with every field, the frame's parts (start, flags, device, command, seq, data, checksum,
//! end) and hex, its time, direction and droid. A search (`/`) marks the rows that contain
//! the text; `n` and `N` go to the next and previous match. The rows are made here, once,
//! for the screen and the search alike; its keys are a component,
//! [`super::overlay::packet`], and `App::open_detail` (in [`super::keys`], the log's keys)
//! opens it.

use super::packet_log::LogLine;

/// One row of the detail: a label and its value (never cut: the screen wraps it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Row {
    pub label: String,
    pub value: String,
    /// A heading ("Fields", "Frame"): no value.
    pub heading: bool,
}

fn row(label: impl Into<String>, value: impl Into<String>) -> Row {
    Row {
        label: label.into(),
        value: value.into(),
        heading: false,
    }
}

fn heading(label: &str) -> Row {
    Row {
        label: label.into(),
        value: String::new(),
        heading: true,
    }
}

/// The rows of `l`'s detail.
pub fn rows(l: &LogLine) -> Vec<Row> {
    let mut v = vec![
        row("time", format!("{:.3} s", l.at.as_secs_f64())),
        row(
            "direction",
            format!(
                "{} {}",
                l.dir.arrow(),
                if l.dir == crate::session::Direction::In {
                    "from the droid"
                } else {
                    "to the droid"
                }
            ),
        ),
    ];
    if let Some(d) = &l.droid {
        v.push(row("droid", d.to_string()));
    }
    v.push(row("packet", l.name.clone()));
    if let Some(s) = l.seq {
        v.push(row("seq", s.to_string()));
    }
    if let Some(e) = l.err {
        v.push(row("error", format!("{} — {}", e.name(), e.message())));
    }
    v.push(heading("Fields"));
    if l.fields.is_empty() {
        let text = if l.decoded.is_empty() {
            "none"
        } else {
            &l.decoded
        };
        v.push(row("", text));
    }
    v.extend(l.fields.iter().map(|(n, val)| row(*n, val.clone())));
    v.push(heading("Frame"));
    v.extend(l.parts.iter().map(|(n, val)| row(*n, val.clone())));
    v.push(row("hex", l.hex.clone()));
    v
}

/// The rows of `rows` that contain `search` (case-insensitive); none for an empty search.
pub fn matches(rows: &[Row], search: &str) -> Vec<usize> {
    let s = search.trim().to_lowercase();
    if s.is_empty() {
        return Vec::new();
    }
    rows.iter()
        .enumerate()
        .filter(|(_, r)| r.label.to_lowercase().contains(&s) || r.value.to_lowercase().contains(&s))
        .map(|(i, _)| i)
        .collect()
}
