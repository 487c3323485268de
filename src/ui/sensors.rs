//! Live sensor readings: attitude, accelerometer, gyro and velocity, `-` until the first
//! sample. Tall panels get one centred bar gauge per value; short ones pack a triple per
//! line and drop the gyro first (the least useful while driving).

use super::text::{fit_right, num, opt, runs, unit_fraction};
use super::theme;
use crate::telemetry::Telemetry;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::Style;
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

/// Rows a panel needs for the one-gauge-per-value form.
const GAUGE_ROWS: u16 = 10;
/// Full-scale of each gauge: generous enough that driving stays off the stops.
const ATTITUDE_RANGE: f32 = 90.0;
const YAW_RANGE: f32 = 180.0;
const ACCEL_RANGE_G: f32 = 2.0;
const GYRO_RANGE: f32 = 500.0;
const SPEED_RANGE: f32 = 200.0;

/// `rates`: the streaming rate requested and measured, in the title when it fits.
pub fn render(frame: &mut Frame, area: Rect, t: &Telemetry, rates: &str) {
    let title = format!(" Sensors {rates} ");
    let title = if super::text::width(&title) + 2 <= area.width as usize {
        title
    } else {
        " Sensors ".to_string()
    };
    let block = theme::panel(title);
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let lines = if inner.height >= GAUGE_ROWS && inner.width >= 30 {
        gauges(t, inner.width as usize)
    } else {
        packed(t, inner.height)
    };
    frame.render_widget(Paragraph::new(lines), inner);
}

fn packed(t: &Telemetry, rows: u16) -> Vec<Line<'static>> {
    let trio = |name: &'static str,
                v: Option<[f32; 3]>,
                prec: usize,
                unit: &'static str|
     -> Line<'static> {
        let mut spans = vec![Span::styled(format!("{name:<5}"), theme::label())];
        match v {
            Some(v) => {
                for (axis, x) in ["x", "y", "z"].iter().zip(v) {
                    spans.push(Span::styled(format!("{axis} "), theme::dim()));
                    spans.push(Span::styled(
                        format!("{} ", num(x, prec)),
                        theme::reported(),
                    ));
                }
                spans.push(Span::styled(unit, theme::dim()));
            }
            None => spans.push(Span::styled("-", theme::dim())),
        }
        Line::from(spans)
    };
    let att = Line::from(vec![
        Span::styled("pitch ", theme::label()),
        Span::styled(opt(t.pitch, 1, "°"), theme::reported()),
        Span::styled("  roll ", theme::label()),
        Span::styled(opt(t.roll, 1, "°"), theme::reported()),
        Span::styled("  yaw ", theme::label()),
        Span::styled(opt(t.yaw, 1, "°"), theme::reported()),
    ]);
    let mut vel = vec![
        Span::styled("vel  ", theme::label()),
        Span::styled(opt(t.speed_cm_s(), 1, ""), theme::reported()),
        Span::styled(" cm/s", theme::dim()),
    ];
    // Compact layouts drop the map, so the position goes here (it matters more than the
    // velocity components).
    if let (Some(x), Some(y)) = (t.x_cm, t.y_cm) {
        vel.push(Span::styled("  pos ", theme::label()));
        vel.push(Span::styled(
            format!("x {} y {} cm", num(x, 0), num(y, 0)),
            theme::reported(),
        ));
    }
    let mut lines = vec![att, trio("acc", t.accel, 2, "g"), Line::from(vel)];
    if rows > 3 {
        lines.push(trio("gyro", t.gyro, 0, "°/s"));
    }
    lines
}

fn gauges(t: &Telemetry, width: usize) -> Vec<Line<'static>> {
    let bar_w = width.saturating_sub(17);
    let a = |i: usize| t.accel.map(|v| v[i]);
    let g = |i: usize| t.gyro.map(|v| v[i]);
    vec![
        gauge("pitch", t.pitch, 1, "°", ATTITUDE_RANGE, bar_w),
        gauge("roll", t.roll, 1, "°", ATTITUDE_RANGE, bar_w),
        gauge("yaw", t.yaw, 1, "°", YAW_RANGE, bar_w),
        gauge("acc x", a(0), 2, "g", ACCEL_RANGE_G, bar_w),
        gauge("acc y", a(1), 2, "g", ACCEL_RANGE_G, bar_w),
        gauge("acc z", a(2), 2, "g", ACCEL_RANGE_G, bar_w),
        gauge("gyr x", g(0), 0, "°/s", GYRO_RANGE, bar_w),
        gauge("gyr y", g(1), 0, "°/s", GYRO_RANGE, bar_w),
        gauge("gyr z", g(2), 0, "°/s", GYRO_RANGE, bar_w),
        speed_gauge(t.speed_cm_s(), bar_w),
    ]
}

/// `label  value  ─────┼━━━───`: a bar from the centre towards the value's sign.
fn gauge(
    label: &str,
    v: Option<f32>,
    prec: usize,
    unit: &str,
    range: f32,
    w: usize,
) -> Line<'static> {
    let mut spans = vec![
        Span::styled(format!("{label:<6}"), theme::label()),
        Span::styled(fit_right(&opt(v, prec, unit), 10), theme::reported()),
        Span::raw(" "),
    ];
    if w >= 3 {
        let centre = w / 2;
        let f = v.map_or(0.0, |v| unit_fraction(v, range));
        let reach = (f.abs() * centre as f32).round() as usize;
        let filled = |i: usize| {
            reach > 0
                && if f < 0.0 {
                    i + reach >= centre && i < centre
                } else {
                    i > centre && i <= centre + reach
                }
        };
        spans.extend(runs((0..w).map(|i| {
            if i == centre {
                ('┼', theme::label())
            } else if filled(i) {
                ('━', Style::new().fg(theme::REPORTED))
            } else {
                ('─', theme::dim())
            }
        })));
    }
    Line::from(spans)
}

/// Speed is never negative: a bar filling from the left.
fn speed_gauge(v: Option<f32>, w: usize) -> Line<'static> {
    let f = v.map_or(0.0, |v| unit_fraction(v, SPEED_RANGE).max(0.0));
    let full = ((f * w as f32).round() as usize).min(w);
    Line::from(vec![
        Span::styled(format!("{:<6}", "speed"), theme::label()),
        Span::styled(fit_right(&opt(v, 1, " cm/s"), 10), theme::reported()),
        Span::raw(" "),
        Span::styled("━".repeat(full), Style::new().fg(theme::REPORTED)),
        Span::styled("─".repeat(w - full), theme::dim()),
    ])
}
