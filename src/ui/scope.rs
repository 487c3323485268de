//! The scope (issue 22 point 1): the chosen channels against time over the last 10 s to
//! 2 min, in place of the panels and the log. A header says the window, paused or live, the
//! axes' mode and the streaming rate requested beside the one measured; a legend names each
//! channel with its colour and unit; the chart plots them with a time axis in seconds before
//! now.
//!
//! Each channel is reduced to two points per braille column before drawing
//! ([`crate::telemetry::history::History::series`]), so a frame costs the same at 1 and at
//! 100 samples a second.

use super::theme;
use crate::app::state::AppState;
use crate::telemetry::history::Channel;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Axis, Chart, Dataset, GraphType, Paragraph};

/// Colours of the channels, in the order they are listed.
const COLOURS: [Color; 8] = [
    Color::Cyan,
    Color::Yellow,
    Color::Magenta,
    Color::Green,
    Color::LightRed,
    Color::LightBlue,
    Color::White,
    Color::LightGreen,
];

pub fn colour(i: usize) -> Color {
    COLOURS[i % COLOURS.len()]
}

/// The streaming rate requested and measured: `10/s, measured 9.8/s`.
pub fn rates(s: &AppState) -> String {
    let measured = s
        .droid()
        .telemetry
        .history
        .measured_rate(s.now)
        .map_or("-".to_string(), super::text::per_second);
    format!("{}, measured {measured}", s.droid().monitor.requested())
}

pub fn render(frame: &mut Frame, area: Rect, s: &AppState) {
    let v = &s.droid().scope;
    let window = v.window();
    let mut title = vec![
        Span::styled(" Scope ", theme::bold()),
        Span::styled(format!("last {} s ", window.as_secs()), theme::label()),
    ];
    if v.paused_at.is_some() {
        title.push(Span::styled(" PAUSED ", theme::attention()));
        title.push(Span::raw(" "));
    }
    title.push(Span::styled(
        if v.autoscale { "auto " } else { "fixed " },
        theme::dim(),
    ));
    let block = theme::panel(Line::from(title)).title_bottom(
        Line::from(Span::styled(
            format!(" stream {} ", rates(s)),
            theme::reported(),
        ))
        .right_aligned(),
    );
    let inner = block.inner(area);
    frame.render_widget(block, area);
    if inner.height < 3 || inner.width < 20 {
        return;
    }
    let legend = Rect { height: 1, ..inner };
    let chart = Rect {
        y: inner.y + 1,
        height: inner.height - 1,
        ..inner
    };
    let mut spans = Vec::new();
    for (i, c) in v.channels.iter().enumerate() {
        spans.push(Span::styled("■ ", Style::new().fg(colour(i))));
        spans.push(Span::raw(c.label()));
        spans.push(Span::raw("  "));
    }
    if spans.is_empty() {
        spans.push(Span::styled(
            "no channels chosen: the channels key (C) opens the list",
            theme::dim(),
        ));
    }
    frame.render_widget(Paragraph::new(Line::from(spans)), legend);

    let end = v.end(s.now);
    let from = end.saturating_sub(window);
    // A bucket per cell column: its lowest and highest point fill the cell top to bottom.
    let columns = chart.width.saturating_sub(8).max(1) as usize;
    let series: Vec<Series> = v
        .channels
        .iter()
        .copied()
        .zip(
            s.droid()
                .telemetry
                .history
                .series_of(&v.channels, from, end, columns),
        )
        .enumerate()
        .map(|(i, (c, pts))| (i, c, pts))
        .collect();
    // One chart per unit, stacked: yaw (deg) and speed (cm/s) never share a y axis. Charts
    // too short to read (under 4 rows) share the last one's rows instead.
    let mut units: Vec<&str> = Vec::new();
    for (_, c, _) in &series {
        if !units.contains(&c.unit()) {
            units.push(c.unit());
        }
    }
    let n = units.len().clamp(1, (chart.height as usize / 4).max(1)) as u16;
    let secs = window.as_secs_f64();
    for g in 0..n {
        let h = chart.height / n;
        let rect = Rect {
            y: chart.y + g * h,
            height: if g + 1 == n { chart.height - g * h } else { h },
            ..chart
        };
        let last = g + 1 == n;
        let group: Vec<&Series> = series
            .iter()
            .filter(|(_, c, _)| {
                let k = units.iter().position(|u| *u == c.unit()).unwrap_or(0) as u16;
                k == g || (last && k > g)
            })
            .collect();
        plot(frame, rect, v.autoscale, &group, secs, last);
    }
}

/// One chart: `group`'s channels (by their legend index) on one y axis; the time axis's
/// labels only under the last chart. No axis titles: ratatui draws them inside the plot,
/// over the data (the units are in the legend, the seconds in the labels).
fn plot(frame: &mut Frame, rect: Rect, autoscale: bool, group: &[&Series], secs: f64, last: bool) {
    let pairs: Vec<(Channel, Vec<(f64, f64)>)> =
        group.iter().map(|(_, c, p)| (*c, p.clone())).collect();
    let (lo, hi) = y_bounds(autoscale, &pairs);
    let datasets: Vec<Dataset> = group
        .iter()
        .map(|(i, _, pts)| {
            Dataset::default()
                .marker(Marker::Braille)
                .graph_type(GraphType::Line)
                .style(Style::new().fg(colour(*i)))
                .data(pts)
        })
        .collect();
    let mut x = Axis::default().style(theme::dim()).bounds([-secs, 0.0]);
    if last {
        x = x.labels([
            Span::raw(format!("-{} s", secs as u64)),
            Span::raw(format!("-{} s", (secs / 2.0) as u64)),
            Span::raw("0 s"),
        ]);
    }
    let y = Axis::default()
        .style(theme::dim())
        .bounds([lo, hi])
        // Padded to one width: the stacked charts' time axes line up.
        .labels([
            Span::raw(format!("{:>6}", short(lo))),
            Span::raw(format!("{:>6}", short((lo + hi) / 2.0))),
            Span::raw(format!("{:>6}", short(hi))),
        ]);
    frame.render_widget(Chart::new(datasets).x_axis(x).y_axis(y), rect);
}

/// A channel's points, with its index in the legend (its colour).
type Series = (usize, Channel, Vec<(f64, f64)>);

/// A number for an axis label, at most 6 cells.
fn short(v: f64) -> String {
    let a = v.abs();
    let prec = if a >= 1000.0 {
        0
    } else if a >= 10.0 {
        1
    } else {
        2
    };
    crate::units::fixed(v, prec)
}

/// The y range: the data's (with a margin) when autoscaled, else the channels' sensor spans.
fn y_bounds(autoscale: bool, series: &[(Channel, Vec<(f64, f64)>)]) -> (f64, f64) {
    let fixed = || {
        series.iter().fold(None, |acc: Option<(f64, f64)>, (c, _)| {
            let (a, b) = c.range();
            Some(acc.map_or((a, b), |(lo, hi)| (lo.min(a), hi.max(b))))
        })
    };
    let data = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|(_, v)| *v))
        .filter(|v| v.is_finite())
        .fold(None, |acc: Option<(f64, f64)>, v| {
            Some(acc.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))))
        });
    let (lo, hi) = match (autoscale, data) {
        (true, Some((lo, hi))) => {
            let pad = ((hi - lo) * 0.05).max(if hi == lo { 1.0 } else { 0.0 });
            (lo - pad, hi + pad)
        }
        _ => fixed().unwrap_or((-1.0, 1.0)),
    };
    if hi > lo {
        (lo, hi)
    } else {
        (lo - 1.0, lo + 1.0)
    }
}
