//! The two-row status bar. Row 1 is the droid and whether it is safe (identity, link, e-stop,
//! battery, errors, packet rates); row 2 is the environment (hint, gamepad, keyboard mode, log
//! file). Segments carry a priority and the least important ones are dropped whole when the
//! row is too narrow, so 80 columns shows fewer facts rather than half-cut ones.

use super::text::{clean, num, truncate, truncate_left, truncate_words, width};
use super::theme;
use crate::app::state::{AppState, GamepadStatus, KeyboardMode};
use crate::session::LinkState;
use crate::telemetry::Telemetry;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

const SEP: &str = " │ ";

/// One fact of the status bar; `prio` 0 is never dropped, higher numbers go first.
struct Seg {
    spans: Vec<Span<'static>>,
    prio: u8,
}

impl Seg {
    fn new(prio: u8, spans: Vec<Span<'static>>) -> Seg {
        Seg { spans, prio }
    }

    fn width(&self) -> usize {
        self.spans.iter().map(Span::width).sum()
    }
}

fn total(segs: &[Seg]) -> usize {
    segs.iter().map(Seg::width).sum::<usize>() + width(SEP) * segs.len().saturating_sub(1)
}

/// Drop the least important segments until the row fits `w` cells.
fn fit(mut segs: Vec<Seg>, w: usize) -> Vec<Seg> {
    while total(&segs) > w {
        let Some(i) = segs
            .iter()
            .enumerate()
            .filter(|(_, s)| s.prio > 0)
            .max_by_key(|(i, s)| (s.prio, *i))
            .map(|(i, _)| i)
        else {
            break;
        };
        segs.remove(i);
    }
    segs
}

fn join(segs: Vec<Seg>) -> Line<'static> {
    let mut spans = vec![Span::raw(" ")];
    for (i, s) in segs.into_iter().enumerate() {
        if i > 0 {
            spans.push(Span::styled(SEP, theme::dim()));
        }
        spans.extend(s.spans);
    }
    Line::from(spans)
}

pub fn render(frame: &mut Frame, area: Rect, state: &AppState) {
    let w = (area.width as usize).saturating_sub(1);
    let row1 = join(fit(first_row(state), w));
    let mut segs = fit(second_row(state, w), w);
    // The log path takes whatever is left, cut from the left so the file name stays.
    let used = total(&segs) + if segs.is_empty() { 0 } else { width(SEP) };
    let room = w.saturating_sub(used);
    if room >= 12 {
        segs.push(Seg::new(1, log_path(state, room)));
    }
    let row2 = join(segs);
    frame.render_widget(Paragraph::new(vec![row1, row2]), area);
}

fn first_row(s: &AppState) -> Vec<Seg> {
    let name = clean(&s.droid().droid_name);
    let model = s.droid().model.display_name();
    let mut id = vec![Span::styled(truncate(&name, 28), theme::bold())];
    if !name.contains(model) {
        id.push(Span::styled(format!(" {model}"), theme::label()));
    }
    let drive = if s.droid().control.estop {
        Span::styled(" E-STOP ", theme::alarm())
    } else if s.droid().control.source == "program" {
        // A Sphero Edu program drives (`--program`).
        Span::styled("program", Style::new().fg(theme::OK))
    } else if s.droid().control.deadman {
        Span::styled("deadman", theme::dim())
    } else {
        Span::styled("driving", Style::new().fg(theme::OK))
    };
    let errors = Span::styled(
        format!("err {}", s.droid().stats.errors),
        if s.droid().stats.errors > 0 {
            Style::new().fg(theme::ALERT)
        } else {
            theme::dim()
        },
    );
    // Replaying: say so first; nothing is driven, so no drive state.
    let (replay, drive) = match &s.droid().replay {
        Some(r) => (Some(Seg::new(0, replay_spans(r))), None),
        None => (None, Some(Seg::new(0, vec![drive]))),
    };
    [
        Some(Seg::new(0, id)),
        replay,
        Some(Seg::new(0, vec![link(&s.droid().link)])),
        drive,
    ]
    .into_iter()
    .flatten()
    .chain([
        Seg::new(1, battery(&s.droid().telemetry)),
        // No errors is the least news; errors are kept before the rates.
        Seg::new(if s.droid().stats.errors > 0 { 1 } else { 3 }, vec![errors]),
        Seg::new(
            2,
            vec![
                Span::styled("in ", theme::label()),
                Span::raw(super::text::per_second(s.droid().rate_in)),
                Span::styled(" out ", theme::label()),
                Span::raw(super::text::per_second(s.droid().rate_out)),
            ],
        ),
    ])
    .collect()
}

/// `REPLAY ▶ 2× 0:12.3/1:40.0`: paused shows ‖.
fn replay_spans(r: &crate::app::state::ReplayView) -> Vec<Span<'static>> {
    let speed = if r.speed < 1.0 {
        format!("{}×", r.speed)
    } else {
        format!("{}×", r.speed as u32)
    };
    vec![
        Span::styled(" REPLAY ", theme::attention()),
        Span::raw(format!(
            " {} {speed} {}/{}",
            if r.paused { "‖" } else { "▶" },
            clock(r.position),
            clock(r.duration)
        )),
    ]
}

/// m:ss.t
fn clock(d: std::time::Duration) -> String {
    let tenths = d.as_millis() / 100;
    format!("{}:{:02}.{}", tenths / 600, tenths / 10 % 60, tenths % 10)
}

fn link(l: &LinkState) -> Span<'static> {
    let style = match l {
        LinkState::Connecting => Style::new().fg(theme::WARN),
        LinkState::Connected => Style::new().fg(theme::OK),
        LinkState::Reconnecting { .. } => theme::attention(),
        LinkState::Closed { .. } => Style::new().fg(theme::ALERT),
    };
    let label = truncate(&clean(&l.label()), 40);
    match l {
        LinkState::Reconnecting { .. } => Span::styled(format!(" {label} "), style),
        _ => Span::styled(label, style),
    }
}

/// Battery level 1 ok, 2 low, 3 critical: from the droid when it said so, else from the
/// voltage (thresholds as the simulator uses, 3.6 V and 3.45 V).
fn battery_level(t: &Telemetry) -> Option<u8> {
    t.battery_voltage_state.or_else(|| {
        t.battery_v.filter(|v| v.is_finite()).map(|v| match v {
            v if v < 3.45 => 3,
            v if v < 3.6 => 2,
            _ => 1,
        })
    })
}

fn battery(t: &Telemetry) -> Vec<Span<'static>> {
    const CELLS: usize = 5;
    let level = battery_level(t);
    let color = match level {
        Some(3) => theme::ALERT,
        Some(2) => theme::WARN,
        Some(_) => theme::OK,
        None => theme::DIM,
    };
    // The gauge says "battery" by itself; the label only appears while there is no reading.
    let mut spans = Vec::new();
    match t.battery_v {
        Some(v) => {
            // A one-cell LiPo: 3.4 V empty, 4.2 V full.
            let frac = if v.is_finite() {
                ((v - 3.4) / 0.8).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let full = (frac * CELLS as f32).round() as usize;
            spans.push(Span::styled(
                format!("{}V ", num(v, 2)),
                Style::new().fg(color),
            ));
            spans.push(Span::styled("█".repeat(full), Style::new().fg(color)));
            spans.push(Span::styled("░".repeat(CELLS - full), theme::dim()));
        }
        None => spans.push(Span::styled("bat -", theme::dim())),
    }
    match level {
        Some(3) => spans.push(Span::styled(" CRITICAL", theme::alarm())),
        Some(2) => spans.push(Span::styled(" LOW", Style::new().fg(theme::WARN))),
        _ => {}
    }
    spans
}

fn second_row(s: &AppState, width: usize) -> Vec<Seg> {
    let mut segs = Vec::new();
    // The program running (`--program`) first: what it does now is what the operator needs.
    if let Some(p) = &s.droid().program {
        let room = (width / 2).clamp(24, 56);
        segs.push(Seg::new(0, super::program::segment(p, room)));
    }
    if let Some(h) = s.current_hint() {
        // Too long for the row: cut between words, never inside one (issue 30).
        let taken = total(&segs)
            + if segs.is_empty() {
                0
            } else {
                super::text::width(SEP)
            };
        let room = width.saturating_sub(2 + taken);
        segs.push(Seg::new(
            0,
            vec![Span::styled(
                format!("» {}", truncate_words(&clean(h), room)),
                theme::commanded(),
            )],
        ));
    }
    let pad = match &s.gamepad {
        GamepadStatus::Disabled => Span::styled("pad off", theme::dim()),
        GamepadStatus::Unavailable(why) => Span::styled(
            format!("pad n/a: {}", truncate(&clean(why), 24)),
            theme::dim(),
        ),
        GamepadStatus::NoPad => Span::styled("no pad", theme::label()),
        GamepadStatus::Connected(name) => Span::styled(
            format!("pad {}", truncate(&clean(name), 24)),
            Style::new().fg(theme::OK),
        ),
    };
    if let Some(r) = &s.droid().replay {
        // No pad or keyboard mode in a replay: the capture's name instead.
        segs.push(Seg::new(
            2,
            vec![
                Span::styled("capture ", theme::label()),
                Span::raw(truncate_left(&clean(&r.file), 40)),
            ],
        ));
        return segs;
    }
    segs.push(Seg::new(2, vec![pad]));
    let keys = match s.keyboard {
        KeyboardMode::ReleaseEvents => "keys: release events",
        KeyboardMode::Emulated => "keys: emulated release",
    };
    segs.push(Seg::new(3, vec![Span::styled(keys, theme::label())]));
    segs
}

fn log_path(s: &AppState, room: usize) -> Vec<Span<'static>> {
    let label = "log ";
    let path = match &s.log_path {
        Some(p) => clean(&p.display().to_string()),
        None => "off".into(),
    };
    let path = truncate_left(&path, room.saturating_sub(width(label)));
    vec![
        Span::styled(label, theme::label()),
        Span::styled(path, Style::new().fg(Color::Gray)),
    ]
}
