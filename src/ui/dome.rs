//! The dome panel: commanded against reported head angle on the dome's −160..180° range, as
//! two markers on one horizontal scale (`◆` commanded, `●` reported, `◉` when they agree).
//! Droids without a dome say so instead of showing a scale that means nothing.

use super::text::{num, opt, runs};
use super::theme;
use crate::app::state::AppState;
use crate::units::{HEAD_MAX_DEG, HEAD_MIN_DEG, HeadAngle};
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

const LEFT_LABEL: &str = "-160 ";
const RIGHT_LABEL: &str = " 180";

pub fn render(frame: &mut Frame, area: Rect, s: &AppState) {
    let cmd = s.droid().control.head_target;
    let rep = s.droid().telemetry.head_deg;
    if !s.droid().model.has_dome() {
        let block = theme::panel(" Dome ");
        let inner = block.inner(area);
        frame.render_widget(block, area);
        let msg = format!("{} has no dome", s.droid().model.display_name());
        frame.render_widget(Paragraph::new(Span::styled(msg, theme::dim())), inner);
        return;
    }
    let title = Line::from(vec![
        Span::raw(" Dome "),
        Span::styled(format!("◆ cmd {}° ", num(cmd, 0)), theme::commanded()),
        Span::styled(format!("● droid {} ", opt(rep, 1, "°")), theme::reported()),
    ]);
    let block = theme::panel(title);
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let bar_w = (inner.width as usize).saturating_sub(LEFT_LABEL.len() + RIGHT_LABEL.len());
    if bar_w < 5 || inner.height == 0 {
        return;
    }
    let cmd_col = column(cmd, bar_w);
    let rep_col = rep.map(|r| column(r, bar_w));
    let mut lines = Vec::new();
    if inner.height >= 3 {
        lines.push(pointer(
            cmd_col,
            bar_w,
            "▼",
            format!("cmd {}°", num(cmd, 0)),
            theme::commanded(),
        ));
    }
    lines.push(scale(cmd_col, rep_col, bar_w));
    if inner.height >= 3
        && let (Some(c), Some(r)) = (rep_col, rep)
    {
        lines.push(pointer(
            c,
            bar_w,
            "▲",
            format!("droid {}°", num(r, 1)),
            theme::reported(),
        ));
    }
    frame.render_widget(Paragraph::new(lines), inner);
}

/// Column of an angle on a bar `w` cells wide (clamped to the range; NaN sits at 0°).
fn column(deg: f32, w: usize) -> usize {
    let d = HeadAngle::clamped(deg).degrees();
    let frac = (d - HEAD_MIN_DEG) / (HEAD_MAX_DEG - HEAD_MIN_DEG);
    ((frac * (w - 1) as f32).round() as usize).min(w - 1)
}

fn scale(cmd: usize, rep: Option<usize>, w: usize) -> Line<'static> {
    let zero = column(0.0, w);
    let mut spans = vec![Span::styled(LEFT_LABEL, theme::dim())];
    spans.extend(runs((0..w).map(|i| match (i == cmd, rep == Some(i)) {
        (true, true) => ('◉', theme::reported().add_modifier(Modifier::BOLD)),
        (true, false) => ('◆', theme::commanded().add_modifier(Modifier::BOLD)),
        (false, true) => ('●', theme::reported().add_modifier(Modifier::BOLD)),
        _ if i == zero => ('┼', theme::label()),
        _ => ('─', theme::dim()),
    })));
    spans.push(Span::styled(RIGHT_LABEL, theme::dim()));
    Line::from(spans)
}

/// A marker row: the arrow over/under its column with the value beside it, on whichever side
/// has room.
fn pointer(
    col: usize,
    w: usize,
    arrow: &'static str,
    label: String,
    style: Style,
) -> Line<'static> {
    let x = LEFT_LABEL.len() + col;
    let total = LEFT_LABEL.len() + w + RIGHT_LABEL.len();
    let label_w = label.chars().count() + 1;
    let mut spans = Vec::new();
    if x + 1 + label_w <= total {
        spans.push(Span::raw(" ".repeat(x)));
        spans.push(Span::styled(arrow, style));
        spans.push(Span::styled(format!(" {label}"), style));
    } else {
        spans.push(Span::raw(" ".repeat(x.saturating_sub(label_w))));
        spans.push(Span::styled(format!("{label} "), style));
        spans.push(Span::styled(arrow, style));
    }
    Line::from(spans)
}
