//! The compass dial (ratatui's Canvas): commanded heading as a long yellow needle ending in
//! `◆`, the heading the droid reports as a short cyan needle ending in `●`, so the two stay
//! distinguishable without colour too. 0° (the droid's forward after Reset Yaw) is up,
//! clockwise like the protocol.

use super::theme;
use crate::units::Heading;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Style;
use ratatui::symbols::Marker;
use ratatui::text::Span;
use ratatui::widgets::canvas::{Canvas, Circle, Context, Line};

/// Canvas bounds that keep the dial round: a cell is about twice as tall as it is wide.
fn bounds(area: Rect, r: f64) -> ([f64; 2], [f64; 2]) {
    let cols = f64::from(area.width.max(1));
    let rows = f64::from(area.height.max(1));
    let aspect = cols / (2.0 * rows);
    if aspect >= 1.0 {
        ([-r * aspect, r * aspect], [-r, r])
    } else {
        ([-r, r], [-r / aspect, r / aspect])
    }
}

/// Point at `deg` on a circle of radius `r` (compass: 0 up, clockwise).
fn polar(deg: f64, r: f64) -> (f64, f64) {
    let t = deg.to_radians();
    (r * t.sin(), r * t.cos())
}

fn needle(ctx: &mut Context, deg: f64, len: f64, style: Style) {
    let (x, y) = polar(deg, len);
    ctx.draw(&Line::new(0.0, 0.0, x, y, style.fg.unwrap_or_default()));
}

pub fn render(frame: &mut Frame, area: Rect, commanded: Heading, reported: Option<Heading>) {
    if area.width < 3 || area.height < 2 {
        return;
    }
    let labels = area.width >= 20 && area.height >= 9;
    let tips = area.width >= 9 && area.height >= 4;
    let (xb, yb) = bounds(area, if labels { 1.35 } else { 1.05 });
    // One cell in canvas units, to place multi-character labels.
    let cell = (xb[1] - xb[0]) / f64::from(area.width.max(2) - 1);
    let canvas = Canvas::default()
        .marker(Marker::Braille)
        .x_bounds(xb)
        .y_bounds(yb)
        .paint(move |ctx| {
            ctx.draw(&Circle::new(0.0, 0.0, 1.0, theme::DIM));
            for q in [0.0, 90.0, 180.0, 270.0] {
                let (x1, y1) = polar(q, 0.82);
                let (x2, y2) = polar(q, 1.0);
                ctx.draw(&Line::new(x1, y1, x2, y2, theme::DIM));
            }
            ctx.layer();
            if let Some(r) = reported {
                needle(ctx, f64::from(r.degrees()), 0.62, theme::reported());
            }
            ctx.layer();
            needle(
                ctx,
                f64::from(commanded.degrees()),
                0.92,
                theme::commanded(),
            );
            if labels {
                let tick = theme::dim();
                ctx.print(-0.5 * cell, 1.18, Span::styled("0", tick));
                ctx.print(1.12, 0.0, Span::styled("90", tick));
                ctx.print(-1.5 * cell, -1.3, Span::styled("180", tick));
                ctx.print(-1.12 - 3.0 * cell, 0.0, Span::styled("270", tick));
            }
            if tips {
                if let Some(r) = reported {
                    let (x, y) = polar(f64::from(r.degrees()), 0.62);
                    ctx.print(x, y, Span::styled("●", theme::reported()));
                }
                let (x, y) = polar(f64::from(commanded.degrees()), 0.92);
                ctx.print(x, y, Span::styled("◆", theme::commanded()));
            }
        });
    frame.render_widget(canvas, area);
}
