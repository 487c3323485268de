//! The packet log pane: one row per packet with time, direction, name, SEQ, error code and the
//! decoded fields or raw hex. Only the rows in view are formatted (the log pre-formats each
//! entry once), so a full 10,000-entry log draws as fast as an empty one.

use super::text::{clean, fit, fit_right, truncate};
use super::theme;
use crate::app::packet_log::{LogLine, PacketLog};
use crate::app::state::{AppState, Focus};
use crate::session::Direction;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{BorderType, Paragraph};

/// Column widths for one pane width; `err` is 0 when the pane is too narrow for it.
struct Cols {
    time: usize,
    /// A fleet's droid column (0: one droid).
    droid: usize,
    name: usize,
    err: usize,
    rest: usize,
}

impl Cols {
    const DIR: usize = 2;
    const SEQ: usize = 3;

    fn for_width(w: usize, fleet: bool) -> Cols {
        let time = 8;
        let droid = if fleet { DROID_COL } else { 0 };
        // The droid column and its gap come off the rest, so every column keeps its place
        // under its heading.
        let w = w.saturating_sub(if fleet { DROID_COL + 1 } else { 0 });
        let (name, err) = if w >= 50 {
            ((w * 28 / 100).clamp(10, 30), (w * 15 / 100).clamp(6, 19))
        } else {
            ((w / 3).max(4), 0)
        };
        let gaps = if err > 0 { 5 } else { 4 };
        let used = time + Self::DIR + name + Self::SEQ + err + gaps;
        Cols {
            time,
            droid,
            name,
            err,
            rest: w.saturating_sub(used),
        }
    }
}

pub fn render(frame: &mut Frame, area: Rect, s: &AppState) {
    let log = &s.log;
    let focused = s.focus == Focus::Log;
    let mut block = theme::panel(title(log, focused));
    if focused {
        block = block
            .border_type(BorderType::Thick)
            .border_style(Style::new().fg(theme::COMMANDED));
    }
    let inner = block.inner(area);
    frame.render_widget(block, area);
    if inner.height == 0 || inner.width == 0 {
        return;
    }
    let cols = Cols::for_width(inner.width as usize, s.droids.len() > 1);
    let mut lines = vec![header(&cols, log.decoded)];
    let rows = inner.height.saturating_sub(1) as usize;
    let visible = log.visible(rows);
    if visible.is_empty() {
        let msg = if log.filter.is_active() && !log.is_empty() {
            "no packets match the filter"
        } else {
            "no packets yet"
        };
        lines.push(Line::from(Span::styled(msg, theme::dim())));
    }
    // With the keys, the selected line (the one Enter opens in full) is marked.
    let chosen = focused.then(|| log.selected_index(visible.len())).flatten();
    lines.extend(visible.into_iter().enumerate().map(|(i, l)| {
        let r = row(l, &cols, log.decoded);
        if Some(i) == chosen {
            r.style(theme::selected())
        } else {
            r
        }
    }));
    frame.render_widget(Paragraph::new(lines), inner);
}

fn title(log: &PacketLog, focused: bool) -> Line<'static> {
    let mut spans = vec![
        Span::styled(
            if focused {
                " ▶ Packets "
            } else {
                " Packets "
            },
            if focused { theme::bold() } else { Style::new() },
        ),
        Span::styled(format!("{}/{} ", log.len(), log.capacity()), theme::label()),
        Span::styled(
            if log.decoded {
                "· decoded "
            } else {
                "· hex "
            },
            theme::dim(),
        ),
    ];
    if log.paused {
        spans.push(Span::styled(" PAUSED ", theme::attention()));
        spans.push(Span::raw(" "));
    }
    if log.scroll > 0 {
        spans.push(Span::styled(
            format!("↑{} ", log.scroll),
            theme::commanded(),
        ));
    }
    if log.filter.is_active() {
        spans.push(Span::styled("· filter: ", theme::dim()));
        spans.push(Span::styled(
            format!("{} ", truncate(&clean(&log.filter.describe()), 40)),
            theme::commanded(),
        ));
    }
    Line::from(spans)
}

fn header(c: &Cols, decoded: bool) -> Line<'static> {
    let droid = if c.droid > 0 {
        format!("{} ", fit("droid", c.droid))
    } else {
        String::new()
    };
    let mut s = format!(
        "{} {droid}{} {} {}",
        fit_right("time s", c.time),
        fit("", Cols::DIR),
        fit("name", c.name),
        fit("seq", Cols::SEQ)
    );
    if c.err > 0 {
        s.push(' ');
        s.push_str(&fit("error", c.err));
    }
    s.push(' ');
    s.push_str(if decoded { "fields" } else { "hex" });
    Line::from(Span::styled(
        s,
        theme::dim().add_modifier(Modifier::UNDERLINED),
    ))
}

/// Width of the droid column of a fleet's log.
const DROID_COL: usize = 8;

fn row(l: &LogLine, c: &Cols, decoded: bool) -> Line<'static> {
    let base = if l.is_error {
        Style::new().fg(theme::ALERT)
    } else {
        Style::new()
    };
    let dir_style = match (l.is_error, l.dir) {
        (true, _) => base.add_modifier(Modifier::BOLD),
        (false, Direction::In) => theme::reported(),
        (false, Direction::Out) => theme::commanded(),
    };
    let secs = l.at.as_secs_f64();
    let seq = l.seq.map_or("-".to_string(), |s| s.to_string());
    let mut spans = vec![
        Span::styled(
            fit_right(&format!("{secs:.3}"), c.time),
            if l.is_error { base } else { theme::dim() },
        ),
        Span::raw(" "),
    ];
    // In a fleet, which droid the line is about.
    if c.droid > 0 {
        let d = l.droid.as_deref().unwrap_or("");
        spans.push(Span::styled(fit(&clean(d), c.droid), theme::label()));
        spans.push(Span::raw(" "));
    }
    spans.extend([
        Span::styled(l.dir.arrow(), dir_style),
        Span::raw(" "),
        Span::styled(fit(&clean(&l.name), c.name), base),
        Span::raw(" "),
        Span::styled(
            fit_right(&seq, Cols::SEQ),
            if l.is_error { base } else { theme::label() },
        ),
    ]);
    if c.err > 0 {
        let err = l.err.map(|e| e.name()).unwrap_or_default();
        spans.push(Span::raw(" "));
        spans.push(Span::styled(
            fit(&err, c.err),
            base.add_modifier(Modifier::BOLD),
        ));
    }
    // An error response's decoded text repeats the code's name, already in its own column:
    // show the explanation instead.
    let detail = match (decoded, l.err) {
        (true, Some(e)) if c.err > 0 => e.message(),
        (true, _) => clean(&l.decoded),
        (false, _) => clean(&l.hex),
    };
    spans.push(Span::raw(" "));
    spans.push(Span::styled(
        truncate(&detail, c.rest),
        if l.is_error { base } else { Style::new() },
    ));
    Line::from(spans)
}
