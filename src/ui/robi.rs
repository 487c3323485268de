//! Robi 42's panels, shown by capability ("reports motor speeds and I/O in state frames"):
//! [`motors`] in the dome's place (left and right wheel speed as gauges plus a short
//! history), [`io`] in the sensors' place (poti, the five buttons lit when pressed, the eight
//! lamps laid out as on the robot, the piezo, and link quality: frames per second measured
//! against the interval the handshake announced, and frames lost by frame-id gaps).

use super::theme;
use crate::app::state::AppState;
use crate::protocol::rsrcp::{Buttons, Leds};
use crate::telemetry::RobiTelemetry;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

/// Full scale of the motor gauges, rad/s (the simulated Robi tops out at 10).
const MOTOR_SCALE: f32 = 12.0;
const SPARKS: [char; 8] = ['▁', '▂', '▃', '▄', '▅', '▆', '▇', '█'];

fn empty(frame: &mut Frame, area: Rect, title: &'static str, what: &str) {
    let block = theme::panel(title);
    let inner = block.inner(area);
    frame.render_widget(block, area);
    frame.render_widget(
        Paragraph::new(Span::styled(what.to_string(), theme::dim())),
        inner,
    );
}

/// A gauge bar of `width` cells for `v` in 0..=`full`.
fn bar(v: f32, full: f32, width: usize) -> String {
    let frac = if v.is_finite() {
        (v.abs() / full).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let n = (frac * width as f32).round() as usize;
    format!("{}{}", "█".repeat(n), "░".repeat(width - n))
}

/// The last `width` values as a sparkline scaled to `full`.
fn spark(values: impl Iterator<Item = f32>, full: f32, width: usize) -> String {
    let v: Vec<f32> = values.collect();
    v[v.len().saturating_sub(width)..]
        .iter()
        .map(|x| {
            let f = if x.is_finite() {
                (x.abs() / full).clamp(0.0, 1.0)
            } else {
                0.0
            };
            SPARKS[((f * 7.0).round() as usize).min(7)]
        })
        .collect()
}

/// Wheel speeds: gauges and a history line per side.
pub fn motors(frame: &mut Frame, area: Rect, s: &AppState) {
    let Some(r) = &s.droid().telemetry.robi else {
        return empty(frame, area, " Motors ", "waiting for the first frame");
    };
    let block = theme::panel(" Motors (rad/s) ");
    let inner = block.inner(area);
    frame.render_widget(block, area);
    // "L  1.25 ██████░░░░ ▁▂▃▅▆": the gauge now, then the recent history, on one line so
    // the panel fits the dome's three rows.
    let room = (inner.width as usize).saturating_sub(10);
    let gauge_w = (room / 2).max(3);
    let spark_w = room.saturating_sub(gauge_w + 1);
    let (l, rr) = r
        .motors
        .map(|m| (m.left_rad_s, m.right_rad_s))
        .unwrap_or((0.0, 0.0));
    if inner.height < 2 {
        // One row (80×24): both wheels side by side, gauges only.
        let w = (inner.width as usize).saturating_sub(18) / 2;
        let line = Line::from(vec![
            Span::styled("L ", theme::label()),
            Span::styled(format!("{l:>5.2} "), theme::bold()),
            Span::styled(bar(l, MOTOR_SCALE, w.max(2)), theme::reported()),
            Span::styled("  R ", theme::label()),
            Span::styled(format!("{rr:>5.2} "), theme::bold()),
            Span::styled(bar(rr, MOTOR_SCALE, w.max(2)), theme::reported()),
        ]);
        frame.render_widget(Paragraph::new(line), inner);
        return;
    }
    let mut lines = Vec::new();
    for (name, v, hist) in [
        (
            "L",
            l,
            spark(r.history.iter().map(|h| h.0), MOTOR_SCALE, spark_w),
        ),
        (
            "R",
            rr,
            spark(r.history.iter().map(|h| h.1), MOTOR_SCALE, spark_w),
        ),
    ] {
        lines.push(Line::from(vec![
            Span::styled(format!("{name} "), theme::label()),
            Span::styled(format!("{v:>6.2} "), theme::bold()),
            Span::styled(bar(v, MOTOR_SCALE, gauge_w), theme::reported()),
            Span::raw(" "),
            Span::styled(hist, theme::dim()),
        ]));
    }
    frame.render_widget(Paragraph::new(lines), inner);
}

fn lamp(on: bool, label: &'static str) -> Span<'static> {
    if on {
        Span::styled(
            label,
            Style::new()
                .fg(Color::Black)
                .bg(Color::Yellow)
                .add_modifier(Modifier::BOLD),
        )
    } else {
        Span::styled(label, theme::dim())
    }
}

/// "link 10/s announced 100/s (10 ms) lost 3", shortened to fit `width` columns.
///
/// Fix: the line was one fixed text that just fit an 80×24 panel with a one-digit count, so
/// "lost 12" was cut to "lost 1". Now the interval in ms goes first, then "announced"
/// becomes "of", then the "link" label: the lost count is not cut.
fn link_quality(r: &RobiTelemetry, width: usize) -> Line<'static> {
    let measured = r
        .measured_fps()
        .map(super::text::per_second)
        .unwrap_or_else(|| "-/s".into());
    let announced = r
        .announced_fps()
        .map(super::text::per_second)
        .unwrap_or_else(|| "-".into());
    let ms = r
        .handshake
        .map(|h| format!(" ({} ms)", h.msdt_ms))
        .unwrap_or_default();
    let lost = r.lost.to_string();
    // (label, between, interval), longest first.
    let forms = [
        ("link ", " announced ", ms.as_str()),
        ("link ", " announced ", ""),
        ("link ", " of ", ""),
        ("", " of ", ""),
    ];
    let len = |(label, between, ms): (&str, &str, &str)| {
        label.len()
            + measured.chars().count()
            + between.len()
            + announced.chars().count()
            + ms.len()
            + " lost ".len()
            + lost.len()
    };
    let (label, between, ms) = forms
        .into_iter()
        .find(|f| len(*f) <= width)
        .unwrap_or(forms[forms.len() - 1]);
    Line::from(vec![
        Span::styled(label, theme::label()),
        Span::raw(measured),
        Span::styled(between, theme::label()),
        Span::raw(format!("{announced}{ms}")),
        Span::styled(" lost ", theme::label()),
        Span::styled(
            lost,
            if r.lost > 0 {
                theme::attention()
            } else {
                Style::new()
            },
        ),
    ])
}

/// Poti, buttons, lamps, piezo and link quality.
pub fn io(frame: &mut Frame, area: Rect, s: &AppState) {
    let Some(r) = &s.droid().telemetry.robi else {
        return empty(
            frame,
            area,
            " Robi ",
            "waiting for the handshake and frames",
        );
    };
    let title = match r.frame_id {
        Some(id) => format!(" Robi · frame {id} "),
        None => " Robi ".to_string(),
    };
    let block = theme::panel(title);
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let poti = r.poti.unwrap_or(0);
    let b = r.buttons.unwrap_or_default();
    let l = r.leds.unwrap_or_default();
    let poti_w = (inner.width as usize).saturating_sub(16).clamp(4, 24);
    let mut lines = vec![
        Line::from(vec![
            Span::styled("poti ", theme::label()),
            Span::raw(match r.poti {
                Some(p) => format!("{p:>3} "),
                None => "  - ".into(),
            }),
            Span::styled(bar(poti as f32, 255.0, poti_w), theme::reported()),
        ]),
        // The buttons as on the robot: top above, left centre right, bottom below.
        Line::from(vec![
            Span::styled("buttons    ", theme::label()),
            lamp(b.contains(Buttons::TOP), "[top]"),
        ]),
        Line::from(vec![
            Span::raw("       "),
            lamp(b.contains(Buttons::LEFT), "[left]"),
            lamp(b.contains(Buttons::CENTER), "[ok]"),
            lamp(b.contains(Buttons::RIGHT), "[right]"),
        ]),
        Line::from(vec![
            Span::raw("           "),
            lamp(b.contains(Buttons::BOTTOM), "[bot]"),
        ]),
        // The lamps as seen from above, front at the top.
        Line::from(vec![
            Span::styled("lamps front ", theme::label()),
            lamp(l.contains(Leds::FRONT_LEFT_BLINKER), "◀"),
            lamp(l.contains(Leds::FRONT_LEFT_HEADLIGHT), "●"),
            Span::raw(" "),
            lamp(l.contains(Leds::FRONT_RIGHT_HEADLIGHT), "●"),
            lamp(l.contains(Leds::FRONT_RIGHT_BLINKER), "▶"),
        ]),
        Line::from(vec![
            Span::styled("      back  ", theme::label()),
            lamp(l.contains(Leds::BACK_LEFT_BLINKER), "◀"),
            lamp(l.contains(Leds::BACK_LEFT_TAILLIGHT), "■"),
            Span::raw(" "),
            lamp(l.contains(Leds::BACK_RIGHT_TAILLIGHT), "■"),
            lamp(l.contains(Leds::BACK_RIGHT_BLINKER), "▶"),
            Span::styled("  piezo ", theme::label()),
            Span::raw(match r.piezo {
                Some(p) if p.on => format!("on {} Hz", p.hz),
                Some(_) => "off".into(),
                None => "-".into(),
            }),
        ]),
        link_quality(r, inner.width as usize),
    ];
    let h = inner.height as usize;
    // "buttons [left][top][ok][bot][right]" wide.
    if lines.len() > h && h >= 5 && inner.width >= 35 {
        // Fix: a panel a row or two short of the full layout (100×30 gives 6 rows) fell back
        // to the 3-row one and left half of it empty. The buttons go on one row instead.
        lines = vec![
            lines[0].clone(),
            Line::from(vec![
                Span::styled("buttons ", theme::label()),
                lamp(b.contains(Buttons::LEFT), "[left]"),
                lamp(b.contains(Buttons::TOP), "[top]"),
                lamp(b.contains(Buttons::CENTER), "[ok]"),
                lamp(b.contains(Buttons::BOTTOM), "[bot]"),
                lamp(b.contains(Buttons::RIGHT), "[right]"),
            ]),
            lines[4].clone(),
            lines[5].clone(),
            lines[6].clone(),
        ];
    } else if lines.len() > h {
        // Short panels (80×24): poti, then buttons and lamps on one row, then the link
        // quality.
        let piezo = match r.piezo {
            Some(p) if p.on => format!(" ♪{}", p.hz),
            _ => String::new(),
        };
        // "[L][T][ok][B][R]" and "◀●●▶/◀■■▶" with the piezo: the label goes when the panel
        // is too narrow for it (60 columns), rather than the back lamps and the piezo.
        let glyphs = 16 + 9 + piezo.chars().count();
        let label = if glyphs + " lamps ".len() <= inner.width as usize {
            " lamps "
        } else {
            " "
        };
        lines = vec![
            lines[0].clone(),
            Line::from(vec![
                lamp(b.contains(Buttons::LEFT), "[L]"),
                lamp(b.contains(Buttons::TOP), "[T]"),
                lamp(b.contains(Buttons::CENTER), "[ok]"),
                lamp(b.contains(Buttons::BOTTOM), "[B]"),
                lamp(b.contains(Buttons::RIGHT), "[R]"),
                Span::styled(label, theme::label()),
                lamp(l.contains(Leds::FRONT_LEFT_BLINKER), "◀"),
                lamp(l.contains(Leds::FRONT_LEFT_HEADLIGHT), "●"),
                lamp(l.contains(Leds::FRONT_RIGHT_HEADLIGHT), "●"),
                lamp(l.contains(Leds::FRONT_RIGHT_BLINKER), "▶"),
                Span::raw("/"),
                lamp(l.contains(Leds::BACK_LEFT_BLINKER), "◀"),
                lamp(l.contains(Leds::BACK_LEFT_TAILLIGHT), "■"),
                lamp(l.contains(Leds::BACK_RIGHT_TAILLIGHT), "■"),
                lamp(l.contains(Leds::BACK_RIGHT_BLINKER), "▶"),
                Span::styled(piezo, theme::attention()),
            ]),
            link_quality(r, inner.width as usize),
        ];
        if h < 3 {
            // Keep the link quality last.
            let last = lines.pop().unwrap_or_default();
            lines.truncate(h.saturating_sub(1));
            lines.push(last);
        }
    }
    frame.render_widget(Paragraph::new(lines), inner);
}
