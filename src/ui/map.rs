//! A small top-down map of the locator track. Bounds start room-sized (±200 cm) and grow to
//! keep the whole track in view; one centimetre is the same length across and down, so a
//! square driven by the droid looks square.

use super::text::num;
use super::theme;
use crate::telemetry::Telemetry;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::canvas::{Canvas, Line as Segment};

/// Half the side of the default view, cm.
const ROOM_CM: f64 = 200.0;
const TRACK: Color = Color::Blue;

/// Finite points of the track, as f64 (NaN or inf from a bad sample is skipped, not drawn).
fn finite(t: &Telemetry) -> impl Iterator<Item = (f64, f64)> + '_ {
    t.track
        .iter()
        .map(|&(x, y)| (f64::from(x), f64::from(y)))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
}

fn position(t: &Telemetry) -> Option<(f64, f64)> {
    let (x, y) = (f64::from(t.x_cm?), f64::from(t.y_cm?));
    (x.is_finite() && y.is_finite()).then_some((x, y))
}

/// Bounds covering the room, the track and `others` (a fleet's other droids), widened on one
/// axis to keep cm square on screen (a cell is about twice as tall as wide).
fn bounds_with(t: &Telemetry, others: &[Other], cols: u16, rows: u16) -> ([f64; 2], [f64; 2]) {
    let (mut x0, mut x1, mut y0, mut y1) = (-ROOM_CM, ROOM_CM, -ROOM_CM, ROOM_CM);
    let more = others.iter().map(|o| o.at);
    for (x, y) in finite(t).chain(position(t)).chain(more) {
        x0 = x0.min(x * 1.1);
        x1 = x1.max(x * 1.1);
        y0 = y0.min(y * 1.1);
        y1 = y1.max(y * 1.1);
    }
    let cols = f64::from(cols.max(1));
    let rows = f64::from(rows.max(1)) * 2.0;
    let (w, h) = (x1 - x0, y1 - y0);
    if w / cols > h / rows {
        let pad = (w / cols * rows - h) / 2.0;
        (y0, y1) = (y0 - pad, y1 + pad);
    } else {
        let pad = (h / rows * cols - w) / 2.0;
        (x0, x1) = (x0 - pad, x1 + pad);
    }
    ([x0, x1], [y0, y1])
}

/// Another droid of a fleet on the map: its number in the roster and where its locator puts
/// it (each droid's locator counts from where that droid started).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Other {
    pub number: usize,
    pub at: (f64, f64),
}

/// The map; a fleet's other droids are marked by their roster numbers.
pub fn render_with(frame: &mut Frame, area: Rect, t: &Telemetry, others: &[Other]) {
    let pos = position(t);
    let title = match pos {
        Some((x, y)) => Line::from(vec![
            Span::raw(" Map "),
            Span::styled(
                format!("x {} y {} cm ", num(x as f32, 0), num(y as f32, 0)),
                theme::reported(),
            ),
        ]),
        None => Line::from(vec![
            Span::raw(" Map "),
            Span::styled("no position ", theme::dim()),
        ]),
    };
    let block = theme::panel(title);
    let inner = block.inner(area);
    let (xb, yb) = bounds_with(t, others, inner.width, inner.height);
    let extent = format!(
        " {}×{} cm ",
        num((xb[1] - xb[0]) as f32, 0),
        num((yb[1] - yb[0]) as f32, 0)
    );
    let block = block.title_bottom(Line::from(Span::styled(extent, theme::dim())).right_aligned());
    let points: Vec<(f64, f64)> = finite(t).collect();
    let others = others.to_vec();
    let canvas = Canvas::default()
        .block(block)
        .marker(Marker::Braille)
        .x_bounds(xb)
        .y_bounds(yb)
        .paint(move |ctx| {
            ctx.draw(&Segment::new(xb[0], 0.0, xb[1], 0.0, theme::DIM));
            ctx.draw(&Segment::new(0.0, yb[0], 0.0, yb[1], theme::DIM));
            ctx.layer();
            for w in points.windows(2) {
                ctx.draw(&Segment::new(w[0].0, w[0].1, w[1].0, w[1].1, TRACK));
            }
            for o in &others {
                let mark = char::from_digit((o.number % 10) as u32, 10).unwrap_or('?');
                ctx.print(
                    o.at.0,
                    o.at.1,
                    Span::styled(mark.to_string(), theme::label()),
                );
            }
            if let Some((x, y)) = pos {
                ctx.print(
                    x,
                    y,
                    Span::styled(
                        "●",
                        theme::reported().add_modifier(ratatui::style::Modifier::BOLD),
                    ),
                );
            }
        });
    frame.render_widget(canvas, area);
}
