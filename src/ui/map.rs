//! A small top-down map of the locator track. Bounds start room-sized (±200 cm) and grow to
//! keep the whole track in view; one centimetre is the same length across and down, so a
//! square driven by the droid looks square.
//!
//! A locator counts from where its droid started. Where that start is known in a room the
//! fleet shares (simulated droids), every droid is drawn in room coordinates, so droids
//! standing apart are apart on the map; else (a real droid) from its own start.

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

/// Where a droid's locator reading `(x, y)` is on the map: shifted by where the droid
/// started in the room (`room_origin`), when known; `None` when not finite (a bad sample is
/// skipped, not drawn).
pub fn in_room(room_origin: Option<(f32, f32)>, (x, y): (f32, f32)) -> Option<(f64, f64)> {
    let (ox, oy) = room_origin.unwrap_or((0.0, 0.0));
    let (x, y) = (f64::from(x) + f64::from(ox), f64::from(y) + f64::from(oy));
    (x.is_finite() && y.is_finite()).then_some((x, y))
}

/// Bounds covering the room and `points` (the track, the droid, a fleet's other droids),
/// widened on one axis to keep cm square on screen (a cell is about twice as tall as wide).
fn bounds_with(
    points: impl Iterator<Item = (f64, f64)>,
    cols: u16,
    rows: u16,
) -> ([f64; 2], [f64; 2]) {
    let (mut x0, mut x1, mut y0, mut y1) = (-ROOM_CM, ROOM_CM, -ROOM_CM, ROOM_CM);
    for (x, y) in points {
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

/// Another droid of a fleet on the map: its number in the roster and where it is, in room
/// coordinates when its start in the room is known ([`in_room`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Other {
    pub number: usize,
    pub at: (f64, f64),
}

/// The map of the droid reporting `t`, which started at `room_origin` in its fleet's room
/// (when known); a fleet's other droids are marked by their roster numbers.
pub fn render_with(
    frame: &mut Frame,
    area: Rect,
    t: &Telemetry,
    room_origin: Option<(f32, f32)>,
    others: &[Other],
) {
    // The title says what the droid's locator reports; the drawing is in the room.
    let reported = t
        .x_cm
        .zip(t.y_cm)
        .filter(|(x, y)| x.is_finite() && y.is_finite());
    let pos = reported.and_then(|p| in_room(room_origin, p));
    let title = match reported {
        Some((x, y)) => Line::from(vec![
            Span::raw(" Map "),
            Span::styled(
                format!("x {} y {} cm ", num(x, 0), num(y, 0)),
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
    let points: Vec<(f64, f64)> = t
        .track
        .iter()
        .filter_map(|&p| in_room(room_origin, p))
        .collect();
    let all = points.iter().copied().chain(pos);
    let (xb, yb) = bounds_with(
        all.chain(others.iter().map(|o| o.at)),
        inner.width,
        inner.height,
    );
    let extent = format!(
        " {}×{} cm ",
        num((xb[1] - xb[0]) as f32, 0),
        num((yb[1] - yb[0]) as f32, 0)
    );
    let block = block.title_bottom(Line::from(Span::styled(extent, theme::dim())).right_aligned());
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
