//! The newer robots' panels, in the dome's place (panels by capability): BOLT's LED matrix as
//! droidctl drew it, in colour, beside its compass and ambient light; RVR's colour sensor,
//! motors and tracks. Both fall back to one summary line when the rect is short.

use super::layout::Plan;
use super::text::{clean, truncate};
use super::theme;
use crate::app::state::AppState;
use crate::app::view::matrix::MatrixShows;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

fn rgb(c: [u8; 3]) -> Color {
    Color::Rgb(c[0], c[1], c[2])
}

fn title<'a>(name: &'a str, s: &AppState) -> Line<'a> {
    let mut spans = vec![Span::raw(format!(" {name} "))];
    if s.droid().control.aiming {
        spans.push(Span::styled("AIMING ", theme::attention()));
    }
    if s.droid().control.tank.is_some() {
        spans.push(Span::styled("TANK ", theme::attention()));
    }
    Line::from(spans)
}

/// The 8×8 matrix as four rows of half blocks (eight columns), or what it shows on them.
fn matrix_rows(s: &AppState) -> Vec<Line<'static>> {
    let m = &s.droid().matrix;
    let lit = Style::new().fg(rgb(m.colour)).bg(rgb(m.colour));
    let off = theme::dim();
    let row = |text: String, style: Style| Line::from(Span::styled(text, style));
    match &m.shows {
        MatrixShows::Unknown => (0..4).map(|_| row("· · · · ".into(), off)).collect(),
        MatrixShows::Fill => (0..4).map(|_| row("▀".repeat(8), lit)).collect(),
        // What was drawn is not kept pixel by pixel here: a pattern in its colour says so.
        MatrixShows::Drawing | MatrixShows::Animation(_) => {
            let pattern = Style::new().fg(rgb(m.colour));
            ["▚ ▚ ▚ ▚ ", " ▞ ▞ ▞ ▞", "▚ ▚ ▚ ▚ ", " ▞ ▞ ▞ ▞"]
                .iter()
                .map(|r| row((*r).into(), pattern))
                .collect()
        }
        MatrixShows::Char(c) => {
            let glyph = Style::new().fg(rgb(m.colour)).add_modifier(Modifier::BOLD);
            vec![
                row("        ".into(), off),
                row(format!("   {c}    "), glyph),
                row("        ".into(), off),
                row("        ".into(), off),
            ]
        }
        MatrixShows::Text(t) => {
            // A marquee: the text moves left a character every 150 ms.
            let padded: Vec<char> = format!("{}        ", clean(t)).chars().collect();
            let at = (s.now.as_millis() / 150) as usize % padded.len().max(1);
            let window: String = padded.iter().cycle().skip(at).take(8).collect();
            let glyph = Style::new().fg(rgb(m.colour)).add_modifier(Modifier::BOLD);
            vec![
                row("        ".into(), off),
                row(window, glyph),
                row("        ".into(), off),
                row("        ".into(), off),
            ]
        }
    }
}

fn what_it_shows(s: &AppState) -> String {
    let [r, g, b] = s.droid().matrix.colour;
    let what = match &s.droid().matrix.shows {
        MatrixShows::Unknown => "not drawn yet".to_string(),
        MatrixShows::Fill => "filled".to_string(),
        MatrixShows::Char(c) => format!("{c:?}"),
        MatrixShows::Text(t) => format!("scrolling {:?}", truncate(t, 12)),
        MatrixShows::Drawing => "pixels drawn".to_string(),
        MatrixShows::Animation(n) => format!("animation {n}"),
    };
    format!("{what} #{r:02x}{g:02x}{b:02x}")
}

/// BOLT: the matrix, the compass and the light. BOLT+: its screen in the matrix's place, drawn
/// as the 8×8 picture the frame-player commands make of it (all sphero-unsw describes of the
/// screen; how the real screen scales it is unverified).
pub fn bolt(frame: &mut Frame, area: Rect, s: &AppState) {
    let name = if s.droid().model.has_screen() {
        "Screen (8×8)"
    } else {
        "Matrix"
    };
    let block = theme::panel(title(name, s));
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let r = &s.droid().telemetry.robot;
    // The compass heading: how far clockwise from north the robot faces (yaw grows
    // clockwise; north's yaw is what the calibration reported).
    let heading = r
        .compass_north
        .zip(s.droid().telemetry.yaw.filter(|y| y.is_finite()));
    let heading = heading.map(|(n, yaw)| (n, (yaw - n as f32).rem_euclid(360.0)));
    let (compass, short) = match (heading, r.compass_north) {
        (Some((n, h)), _) => (
            format!("heading {h:.0}° (north at yaw {n}°)"),
            format!("compass {h:.0}°"),
        ),
        (None, Some(n)) => (format!("north at yaw {n}°"), format!("north at yaw {n}°")),
        (None, None) => ("not calibrated".into(), "compass not calibrated".into()),
    };
    let light = match r.ambient_lux {
        Some(l) if l.is_finite() => format!("light {l:.0} lx"),
        _ => "light -".to_string(),
    };
    let swatch = Span::styled("■ ", Style::new().fg(rgb(s.droid().matrix.colour)));
    if inner.height < 4 || inner.width < 30 {
        let lines = vec![
            Line::from(vec![
                Span::styled("shows ", theme::label()),
                swatch,
                Span::raw(what_it_shows(s)),
            ]),
            Line::from(Span::styled(format!("{short} · {light}"), theme::dim())),
        ];
        frame.render_widget(Paragraph::new(lines), inner);
        return;
    }
    let (grid, side) = (
        Rect { width: 9, ..inner },
        Rect {
            x: inner.x + 10,
            width: inner.width - 10,
            ..inner
        },
    );
    frame.render_widget(Paragraph::new(matrix_rows(s)), grid);
    let lines = vec![
        Line::from(vec![
            Span::styled("shows ", theme::label()),
            swatch,
            Span::raw(what_it_shows(s)),
        ]),
        Line::from(vec![
            Span::styled("compass ", theme::label()),
            Span::raw(compass),
        ]),
        Line::from(vec![
            Span::styled("ambient ", theme::label()),
            Span::raw(light),
        ]),
        // The keys as bound (a rebound key shows here as in the footer).
        Line::from(Span::styled(s.borders.matrix_panel.as_str(), theme::dim())),
    ];
    frame.render_widget(Paragraph::new(lines), side);
}

/// The floor colour's words after `floor ■`, the longest form that fits `width` cells.
fn floor_words(c: [u8; 3], index: u8, confidence: f32, width: usize) -> String {
    let rgb = format!("{},{},{}", c[0], c[1], c[2]);
    let sure = confidence * 100.0;
    let forms = [
        format!(" rgb {rgb} · colour {index} ({sure:.0}% sure)"),
        format!(" {rgb} · colour {index} ({sure:.0}% sure)"),
        format!(" {rgb} · colour {index} {sure:.0}%"),
        format!(" {rgb} · #{index}"),
    ];
    let room = width.saturating_sub(super::text::width("floor ■"));
    forms
        .iter()
        .find(|f| super::text::width(f) <= room)
        .unwrap_or(&forms[3])
        .clone()
}

/// RVR: the colour under it, its motors, its tracks.
pub fn rvr(frame: &mut Frame, area: Rect, s: &AppState) {
    let block = theme::panel(title("Rover", s));
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let r = &s.droid().telemetry.robot;
    let colour = match r.color {
        Some((c, index, confidence)) => vec![
            Span::styled("floor ", theme::label()),
            Span::styled("■", Style::new().fg(rgb(c))),
            // RVR's own words: the colour read (RGB), which of its known colours that is
            // (an index), and how sure it is; in fewer words where the panel is narrow (at
            // 80×24 the full line was cut mid-word: "(90% su").
            Span::raw(floor_words(c, index, confidence, inner.width as usize)),
        ],
        None => vec![
            Span::styled("floor ", theme::label()),
            Span::styled("-", theme::dim()),
        ],
    };
    let motors = if r.motor_fault {
        Span::styled("MOTOR FAULT", theme::alarm())
    } else {
        match r.stalled {
            [false, false] => Span::raw("motors ok"),
            [true, true] => Span::styled("both motors stalled", theme::alarm()),
            [true, false] => Span::styled("left motor stalled", theme::alarm()),
            [false, true] => Span::styled("right motor stalled", theme::alarm()),
        }
    };
    let tracks = match s.droid().control.tank {
        Some((l, rt)) => format!("tracks L {l:+} R {rt:+}"),
        None => s.borders.tank_panel.clone(),
    };
    let mut lines = vec![
        Line::from(colour),
        Line::from(vec![
            motors,
            Span::raw("  "),
            Span::styled(tracks, theme::dim()),
        ]),
    ];
    if inner.height >= 3 {
        // RVR's battery is read from its primary processor.
        let volts = match s.droid().telemetry.battery_v {
            Some(v) if v.is_finite() => format!("{v:.2} V"),
            _ => "-".to_string(),
        };
        lines.push(Line::from(vec![
            Span::styled("battery ", theme::label()),
            Span::raw(volts),
            Span::styled(" (primary processor)", theme::dim()),
        ]));
    }
    frame.render_widget(Paragraph::new(lines), inner);
}

/// The plan with the dome's place `want` rows tall where the panels around it can give
/// them: the sensors below (keeping their three lines) and the collisions below them (keeping
/// one) in the compact layout; the drive dial and the map above in the wide one.
pub fn make_room(mut p: Plan, want: u16) -> Plan {
    let Some(d) = p.dome.filter(|d| want > d.height) else {
        return p;
    };
    let need = want - d.height;
    if let (Some(s), Some(c)) = (p.sensors, p.collisions) {
        let (s, c) = grow(s, c, s.height + need, 3);
        let (d, s) = grow(d, s, want, 5);
        (p.dome, p.sensors, p.collisions) = (Some(d), Some(s), Some(c));
    }
    // Wide: the dial and the map sit side by side right above, both taller than needed.
    if let (Some(d), Some(dr), Some(m)) = (p.dome, p.drive, p.map)
        && want > d.height
        && dr.bottom() == d.y
        && m.bottom() == d.y
    {
        let k = (want - d.height)
            .min(dr.height.saturating_sub(16))
            .min(m.height.saturating_sub(8));
        p.drive = Some(Rect {
            height: dr.height - k,
            ..dr
        });
        p.map = Some(Rect {
            height: m.height - k,
            ..m
        });
        p.dome = Some(Rect {
            y: d.y - k,
            height: d.height + k,
            ..d
        });
    }
    p
}

/// Rows moved from `below` to `above` so `above` gets `want` rows, when they are one column
/// (the dome's place over the sensors') and `below` keeps at least `keep`.
pub fn grow(above: Rect, below: Rect, want: u16, keep: u16) -> (Rect, Rect) {
    let stacked = above.x == below.x && above.width == below.width && above.bottom() == below.y;
    let extra = want
        .saturating_sub(above.height)
        .min(below.height.saturating_sub(keep));
    if !stacked || extra == 0 {
        return (above, below);
    }
    (
        Rect {
            height: above.height + extra,
            ..above
        },
        Rect {
            y: below.y + extra,
            height: below.height - extra,
            ..below
        },
    )
}
