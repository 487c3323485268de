//! The `?` help overlay: every key binding, by where it is read (driving, the packet log,
//! palettes, …), and every gamepad binding, as the app generated them from the configuration.
//!
//! Bindings flow down columns, a section starting a fresh column when it would not fit the
//! rest of the current one, and long descriptions wrap under themselves. When the columns do
//! not all fit side by side they are split into pages ([`AppState::help_page`]).
//!
//! [`AppState::help_page`]: crate::app::state::AppState::help_page

use super::super::layout::centered;
use super::super::text::{clean, truncate, width, wrap};
use super::super::theme;
use crate::app::state::{HelpLine, HelpSection};
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Modifier;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Paragraph};

/// Key names wider than this are cut (five alternative keys need not fit).
const MAX_KEYS_W: usize = 16;
/// Columns narrower than this wrap too much to read; fewer columns and more pages instead.
const MIN_COL_W: usize = 36;
const GAP: usize = 2;

/// A run of lines that stays together in one column (a heading, or a wrapped binding).
type Unit = Vec<Line<'static>>;

/// A section's lines at column width `w`: the heading, then one unit per binding.
fn section(title: &str, binds: &[HelpLine], w: usize) -> Vec<Unit> {
    let heading = Line::from(Span::styled(
        title.to_string(),
        theme::bold().add_modifier(Modifier::UNDERLINED),
    ));
    let mut units = vec![vec![heading]];
    if binds.is_empty() {
        units.push(vec![Line::from(Span::styled("no bindings", theme::dim()))]);
    }
    let kw = binds
        .iter()
        .map(|h| width(&h.keys))
        .max()
        .unwrap_or(0)
        .min(MAX_KEYS_W)
        .min(w * 2 / 5);
    let aw = w.saturating_sub(kw + 1).max(1);
    for h in binds {
        let keys = truncate(&clean(&h.keys), kw);
        let pad = " ".repeat(kw.saturating_sub(width(&keys)) + 1);
        let unit = wrap(&clean(&h.action), aw)
            .into_iter()
            .enumerate()
            .map(|(i, part)| {
                let lead = if i == 0 {
                    Span::styled(format!("{keys}{pad}"), theme::commanded())
                } else {
                    Span::raw(" ".repeat(kw + 1))
                };
                Line::from(vec![lead, Span::raw(part)])
            })
            .collect();
        units.push(unit);
    }
    units
}

/// Natural width of a section: keys, a space, the longest description.
fn natural(binds: &[HelpLine]) -> usize {
    let kw = binds
        .iter()
        .map(|h| width(&h.keys))
        .max()
        .unwrap_or(0)
        .min(MAX_KEYS_W);
    let aw = binds.iter().map(|h| width(&h.action)).max().unwrap_or(0);
    (kw + 1 + aw).max(12)
}

/// Flow the sections into columns of at most `rows` lines.
fn flow(sections: Vec<Vec<Unit>>, rows: usize) -> Vec<Vec<Line<'static>>> {
    let rows = rows.max(1);
    let mut cols: Vec<Vec<Line>> = vec![Vec::new()];
    for units in sections {
        let len: usize = units.iter().map(Vec::len).sum();
        let cur = cols.last().map_or(0, Vec::len);
        if cur > 0 {
            if cur + 1 + len > rows && len <= rows {
                cols.push(Vec::new());
            } else if cur < rows
                && let Some(c) = cols.last_mut()
            {
                c.push(Line::default());
            }
        }
        for unit in units {
            let cur = cols.last().map_or(0, Vec::len);
            if cur > 0 && cur + unit.len() > rows {
                cols.push(Vec::new());
            }
            for line in unit {
                if cols.last().is_some_and(|c| c.len() >= rows) {
                    cols.push(Vec::new());
                }
                if let Some(c) = cols.last_mut() {
                    c.push(line);
                }
            }
        }
    }
    cols
}

/// How help is laid out in `area`: the column width, the columns, how many a page shows, and
/// the pages.
fn layout(area: Rect, sections: &[HelpSection]) -> (usize, Vec<Vec<Line<'static>>>, usize, usize) {
    let rows = area.height.saturating_sub(2) as usize;
    let avail = area.width.saturating_sub(4) as usize;
    let max_cols = ((avail + GAP) / (MIN_COL_W + GAP)).max(1);
    let natural = sections
        .iter()
        .map(|s| natural(&s.lines))
        .max()
        .unwrap_or(12);
    let build = |n: usize| {
        let w = natural.min(avail.saturating_sub(GAP * (n - 1)) / n).max(1);
        let units = sections
            .iter()
            .map(|s| section(&s.title, &s.lines, w))
            .collect();
        (w, flow(units, rows))
    };
    // The fewest columns that show everything at once, else as many as fit, paged.
    let (col_w, cols, per_page) = (1..=max_cols)
        .map(|n| (n, build(n)))
        .find(|(n, (_, cols))| cols.len() <= *n)
        .map(|(_, (w, cols))| {
            let n = cols.len();
            (w, cols, n)
        })
        .unwrap_or_else(|| {
            let (w, cols) = build(max_cols);
            (w, cols, max_cols)
        });
    let pages = cols.len().div_ceil(per_page).max(1);
    (col_w, cols, per_page, pages)
}

/// How many pages help takes in `area` (the footer offers the page keys only when there is
/// another page).
pub fn pages(area: Rect, sections: &[HelpSection]) -> usize {
    layout(area, sections).3
}

/// `nav` names the stop that works over help (`Space stop`), `page_keys` the page keys as
/// configured ([`crate::app::help::HELP_PAGES`]).
pub fn render(
    frame: &mut Frame,
    area: Rect,
    sections: &[HelpSection],
    (nav, page_keys): (&str, &str),
    page: usize,
) {
    let (col_w, cols, per_page, pages) = layout(area, sections);
    let page = page.min(pages - 1);
    let inner_h = cols.iter().map(Vec::len).max().unwrap_or(0);
    let inner_w = col_w * per_page + GAP * (per_page - 1);
    let mut rect = centered(area, (inner_w + 4) as u16, (inner_h + 2) as u16);
    // A box a column or two short of the screen would leave the panels' borders showing in a
    // sliver beside it: the whole width then.
    if area.width.saturating_sub(rect.width) <= 2 {
        rect.x = area.x;
        rect.width = area.width;
    }
    let mut foot: Vec<String> = Vec::new();
    if pages > 1 {
        foot.push(format!("page {}/{pages}", page + 1));
    }
    foot.extend((!nav.is_empty()).then(|| nav.to_string()));
    if pages > 1 {
        foot.push(page_keys.to_string());
    }
    foot.push(
        if foot.is_empty() {
            "any key closes"
        } else {
            "other keys close"
        }
        .into(),
    );
    let foot = format!(" {} ", foot.join(" · "));
    let block = theme::panel(Span::styled(" Help ", theme::bold()))
        .border_style(theme::label())
        .title_bottom(Line::from(Span::styled(foot, theme::dim())).centered());
    let inner = block.inner(rect);
    frame.render_widget(Clear, rect);
    frame.render_widget(block, rect);
    let mut x = inner.x.saturating_add(1);
    for lines in cols.into_iter().skip(page * per_page).take(per_page) {
        let w = (col_w as u16).min(inner.right().saturating_sub(x));
        frame.render_widget(
            Paragraph::new(lines),
            Rect {
                x,
                width: w,
                ..inner
            },
        );
        x = x.saturating_add(w).saturating_add(GAP as u16);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(n: usize) -> Vec<HelpLine> {
        (0..n)
            .map(|i| HelpLine {
                keys: format!("k{i}"),
                action: format!("action number {i}"),
                needs: crate::config::Needs::All,
            })
            .collect()
    }

    #[test]
    fn sections_start_a_new_column_when_they_do_not_fit() {
        let k = lines(15);
        let g = lines(8);
        let cols = flow(
            vec![section("Keyboard", &k, 30), section("Gamepad", &g, 30)],
            20,
        );
        assert_eq!(cols.len(), 2);
        assert_eq!(cols[0].len(), 16);
        assert_eq!(cols[1].len(), 9);
        // Everything fits in one column: a blank line separates the sections.
        let cols = flow(
            vec![section("Keyboard", &k, 30), section("Gamepad", &g, 30)],
            40,
        );
        assert_eq!(cols.len(), 1);
        assert_eq!(cols[0].len(), 26);
    }

    #[test]
    fn tiny_heights_still_flow() {
        let k = lines(3);
        let cols = flow(vec![section("Keyboard", &k, 5)], 0);
        assert!(cols.iter().all(|c| c.len() <= 1));
    }
}
