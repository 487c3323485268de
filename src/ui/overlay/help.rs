//! The `?` help overlay: every key binding and every gamepad binding, in two sections.
//!
//! Both sections go in one column when the screen is tall enough; otherwise each section gets
//! its own column(s). When the columns are too wide together the right-most ones narrow and
//! wrap their descriptions, so the keyboard section (the one you need to drive) keeps its
//! descriptions whole on 80×24. Only below that does anything get cut, and then it says so.

use super::super::layout::centered;
use super::super::text::{clean, truncate, width, wrap};
use super::super::theme;
use crate::app::state::HelpLine;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Modifier;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Paragraph};

/// Key names wider than this are cut (a binding list of five keys does not need to fit).
const MAX_KEYS_W: usize = 18;
/// A narrowed column keeps at least this much room for the description.
const MIN_ACTION_W: usize = 10;
const GAP: usize = 2;

#[derive(Clone, Copy)]
enum Item<'a> {
    Heading(&'static str),
    Bind(&'a HelpLine),
    Note(&'static str),
    Blank,
}

struct Column<'a> {
    items: Vec<Item<'a>>,
    keys_w: usize,
    width: usize,
}

impl<'a> Column<'a> {
    fn new(items: Vec<Item<'a>>) -> Column<'a> {
        let binds = || {
            items.iter().filter_map(|i| match i {
                Item::Bind(h) => Some(*h),
                _ => None,
            })
        };
        let keys_w = binds().map(|h| width(&h.keys)).max().unwrap_or(0).min(MAX_KEYS_W);
        let action_w = binds().map(|h| width(&h.action)).max().unwrap_or(0);
        let other_w = items
            .iter()
            .map(|i| match i {
                Item::Heading(t) | Item::Note(t) => width(t),
                _ => 0,
            })
            .max()
            .unwrap_or(0);
        Column {
            width: (keys_w + 1 + action_w).max(other_w),
            keys_w,
            items,
        }
    }

    fn min_width(&self) -> usize {
        self.keys_w + 1 + MIN_ACTION_W
    }

    /// The column's lines at its current width, at most `rows` (a cut ends in `…`).
    fn lines(&self, rows: usize) -> Vec<Line<'a>> {
        let mut out = Vec::new();
        let action_w = self.width.saturating_sub(self.keys_w + 1).max(1);
        for item in &self.items {
            match item {
                Item::Heading(t) => out.push(Line::from(Span::styled(*t, theme::bold().add_modifier(Modifier::UNDERLINED)))),
                Item::Note(t) => out.push(Line::from(Span::styled(*t, theme::dim()))),
                Item::Blank => out.push(Line::default()),
                Item::Bind(h) => {
                    let keys = truncate(&clean(&h.keys), self.keys_w);
                    let pad = " ".repeat(self.keys_w.saturating_sub(width(&keys)) + 1);
                    for (i, part) in wrap(&clean(&h.action), action_w).into_iter().enumerate() {
                        let lead = if i == 0 {
                            Span::styled(format!("{keys}{pad}"), theme::commanded())
                        } else {
                            Span::raw(" ".repeat(self.keys_w + 1))
                        };
                        out.push(Line::from(vec![lead, Span::raw(part)]));
                    }
                }
            }
        }
        if out.len() > rows {
            out.truncate(rows.saturating_sub(1));
            out.push(Line::from(Span::styled("…", theme::dim())));
        }
        out
    }
}

fn section<'a>(title: &'static str, lines: &'a [HelpLine]) -> Vec<Item<'a>> {
    let mut items = vec![Item::Heading(title)];
    if lines.is_empty() {
        items.push(Item::Note("no bindings"));
    }
    items.extend(lines.iter().map(Item::Bind));
    items
}

/// One column if everything fits the height, else each section split into columns of
/// `rows` items.
fn columns<'a>(sections: Vec<Vec<Item<'a>>>, rows: usize) -> Vec<Column<'a>> {
    let total: usize = sections.iter().map(Vec::len).sum::<usize>() + sections.len().saturating_sub(1);
    if total <= rows {
        let mut all = Vec::new();
        for (i, s) in sections.into_iter().enumerate() {
            if i > 0 {
                all.push(Item::Blank);
            }
            all.extend(s);
        }
        return vec![Column::new(all)];
    }
    sections
        .into_iter()
        .flat_map(|s| s.chunks(rows.max(1)).map(|c| Column::new(c.to_vec())).collect::<Vec<_>>())
        .collect()
}

/// Narrow the right-most columns until the row fits `avail`; drop columns that still do not.
/// Returns whether anything was dropped.
fn fit(cols: &mut Vec<Column>, avail: usize) -> bool {
    let total = |cols: &[Column]| cols.iter().map(|c| c.width).sum::<usize>() + GAP * cols.len().saturating_sub(1);
    let mut over = total(cols).saturating_sub(avail);
    for c in cols.iter_mut().rev() {
        let cut = over.min(c.width.saturating_sub(c.min_width()));
        c.width -= cut;
        over -= cut;
    }
    let mut dropped = false;
    while cols.len() > 1 && total(cols) > avail {
        cols.pop();
        dropped = true;
    }
    if let Some(c) = cols.first_mut() {
        c.width = c.width.min(avail);
    }
    dropped
}

pub fn render(frame: &mut Frame, area: Rect, keys: &[HelpLine], pad: &[HelpLine]) {
    let rows = area.height.saturating_sub(2) as usize;
    let avail = area.width.saturating_sub(4) as usize;
    let mut cols = columns(vec![section("Keyboard", keys), section("Gamepad", pad)], rows);
    let dropped = fit(&mut cols, avail);
    let rendered: Vec<Vec<Line>> = cols.iter().map(|c| c.lines(rows)).collect();
    let inner_w = cols.iter().map(|c| c.width).sum::<usize>() + GAP * cols.len().saturating_sub(1);
    let inner_h = rendered.iter().map(Vec::len).max().unwrap_or(0);
    let rect = centered(area, (inner_w + 4) as u16, (inner_h + 2) as u16);
    let foot = if dropped { " more: enlarge the terminal · Esc close " } else { " ? or Esc to close " };
    let block = theme::panel(Span::styled(" Help ", theme::bold()))
        .border_style(theme::label())
        .title_bottom(Line::from(Span::styled(foot, theme::dim())).centered());
    let inner = block.inner(rect);
    frame.render_widget(Clear, rect);
    frame.render_widget(block, rect);
    let mut x = inner.x.saturating_add(1);
    for (c, lines) in cols.iter().zip(rendered) {
        let w = (c.width as u16).min(inner.right().saturating_sub(x));
        frame.render_widget(Paragraph::new(lines), Rect { x, width: w, ..inner });
        x = x.saturating_add(w + GAP as u16);
        if x >= inner.right() {
            break;
        }
    }
}
