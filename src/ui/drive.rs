//! The drive panel: the compass dial plus what is commanded against what is measured (heading,
//! speed), cruise, turbo/reverse and R2's stance. The dial goes beside the text when the panel
//! is short and above it when it is tall.

use super::text::opt;
use super::{compass, theme};
use crate::app::state::{AppState, Focus};
use crate::telemetry::Stance;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::Paragraph;

/// Columns the text block wants when it sits beside the dial.
const TEXT_W: u16 = 18;

pub fn render(frame: &mut Frame, area: Rect, s: &AppState) {
    // Keys drive the droid unless the log has focus; say so where the eye is.
    let title = match s.focus {
        Focus::Drive => Span::styled(" Drive ", theme::bold()),
        Focus::Log => Span::styled(" Drive (held: log has focus) ", theme::dim()),
    };
    let block = theme::panel(title);
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let lines = text(s);
    let n = lines.len() as u16;
    let (dial, info) = if inner.height >= n + 8 {
        // A round dial is about half as tall as wide; more height would only be blank rows.
        let dial_h = (inner.height - n).min(inner.width / 2 + 2);
        (
            Rect {
                height: dial_h,
                ..inner
            },
            Rect {
                y: inner.y + dial_h,
                height: n,
                ..inner
            },
        )
    } else {
        let dial_w = inner
            .width
            .saturating_sub(TEXT_W)
            .min(inner.height.saturating_mul(2) + 1);
        (
            Rect {
                width: dial_w,
                ..inner
            },
            Rect {
                x: inner.x + dial_w + u16::from(dial_w > 0),
                width: inner.width.saturating_sub(dial_w + u16::from(dial_w > 0)),
                ..inner
            },
        )
    };
    // A steering robot has no commanded heading: the marker shows where the steering points,
    // relative to where the robot faces (45° per full lock).
    let commanded = match s.droid().control.steer {
        Some(turn) => crate::units::Heading::wrapped(
            s.droid()
                .telemetry
                .heading()
                .map_or(0.0, |h| h.degrees() as f64)
                + turn as f64 * 45.0,
        ),
        None => s.droid().control.heading,
    };
    compass::render(frame, dial, commanded, s.droid().telemetry.heading());
    frame.render_widget(Paragraph::new(lines), info);
}

/// How a drive flag (turbo, reverse) stands. One rule for both (issue 39 point 13: turbo
/// stayed lit while the droid stood still, reverse went dim): lit only while it shapes what
/// is sent; set but with nothing sent (stopped, e-stop) named in capitals but not lit; off
/// dim and in lower case, so it reads as off without colour too.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Flag {
    Off,
    Set,
    Lit,
}

impl Flag {
    fn of(on: bool, c: &crate::teleop::control::ControlView) -> Flag {
        let sending = c.speed > 0 || c.tank.is_some_and(|(l, r)| l != 0 || r != 0);
        match (on, sending && !c.estop) {
            (false, _) => Flag::Off,
            (true, false) => Flag::Set,
            (true, true) => Flag::Lit,
        }
    }
}

fn flag(state: Flag, name: &'static str) -> Span<'static> {
    match state {
        Flag::Lit => Span::styled(
            name,
            theme::commanded().add_modifier(Modifier::REVERSED | Modifier::BOLD),
        ),
        Flag::Set => Span::styled(name, theme::commanded()),
        Flag::Off => Span::styled(name.to_ascii_lowercase(), theme::dim()),
    }
}

/// The flags line: turbo and reverse where the droid has them (Robi has no turbo and cannot
/// reverse: only what applies is shown).
fn flags(c: &crate::teleop::control::ControlView, turbo: bool, reverse: bool) -> Line<'static> {
    let mut spans = Vec::new();
    if turbo {
        spans.push(flag(Flag::of(c.turbo, c), "TURBO"));
    }
    if reverse {
        if !spans.is_empty() {
            spans.push(Span::raw(" "));
        }
        spans.push(flag(Flag::of(c.reverse, c), "REVERSE"));
    }
    Line::from(spans)
}

fn text(s: &AppState) -> Vec<Line<'static>> {
    let c = &s.droid().control;
    let t = &s.droid().telemetry;
    let droid = t
        .heading()
        .map_or("-".to_string(), |h| format!("{}°", h.degrees()));
    let commanded = match c.steer {
        Some(t) if t < -0.01 => format!("← {:.0}%", -t * 100.0),
        Some(t) if t > 0.01 => format!("→ {:.0}%", t * 100.0),
        Some(_) => "straight".to_string(),
        None => format!("{}°", c.heading.degrees()),
    };
    let mut lines = vec![
        Line::from(vec![
            Span::styled(
                if c.steer.is_some() {
                    "◆ steer "
                } else {
                    "◆ cmd   "
                },
                theme::commanded(),
            ),
            Span::styled(commanded, theme::commanded().add_modifier(Modifier::BOLD)),
        ]),
        Line::from(vec![
            Span::styled("● droid ", theme::reported()),
            Span::styled(droid, theme::reported().add_modifier(Modifier::BOLD)),
        ]),
        // In tank mode the tracks are driven, not a speed: their speeds are what is asked.
        match c.tank {
            Some((l, r)) => Line::from(vec![
                Span::styled("tank ", theme::label()),
                Span::styled(format!("L{l:+} R{r:+}"), theme::commanded()),
            ]),
            None => Line::from(vec![
                Span::styled("speed ", theme::label()),
                Span::styled(format!("{:>3}", c.speed), theme::commanded()),
                Span::styled("/255", theme::dim()),
            ]),
        },
        Line::from(vec![
            Span::styled(" meas ", theme::label()),
            Span::styled(opt(t.speed_cm_s(), 1, ""), theme::reported()),
            Span::styled(
                if t.speed_cm_s().is_some() {
                    " cm/s"
                } else {
                    ""
                },
                theme::dim(),
            ),
        ]),
        Line::from(vec![
            Span::styled("cruise ", theme::label()),
            Span::raw(c.cruise.to_string()),
            Span::styled(format!(" {}", c.mode), theme::dim()),
        ]),
        flags(
            c,
            crate::config::Needs::Turbo.applies(s.droid().model, false),
            crate::family::for_model(s.droid().model).can_reverse(),
        ),
    ];
    if s.droid().model.has_legs() {
        let style = match t.stance {
            Stance::Transitioning(_) => Style::new().fg(theme::WARN).add_modifier(Modifier::BOLD),
            Stance::Unknown => theme::dim(),
            _ => Style::new(),
        };
        lines.push(Line::from(vec![
            Span::styled("stance ", theme::label()),
            Span::styled(t.stance.label(), style),
        ]));
    }
    if c.estop {
        lines.push(Line::from(Span::styled(" E-STOP ", theme::alarm())));
    } else if t.asleep {
        lines.push(Line::from(Span::styled(
            "asleep",
            Style::new().fg(theme::WARN),
        )));
    } else if c.source != "-" {
        lines.push(Line::from(vec![
            Span::styled("input ", theme::label()),
            Span::raw(c.source),
        ]));
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::teleop::control::ControlView;

    fn styles(c: &ControlView) -> Vec<(String, Style)> {
        flags(c, true, true)
            .spans
            .iter()
            .filter(|s| !s.content.trim().is_empty())
            .map(|s| (s.content.to_string(), s.style))
            .collect()
    }

    /// Issue 39 point 13: turbo and reverse follow one rule. Off, both are dim lower case
    /// alike; set while nothing is sent (standing, e-stop), turbo is named but not lit (it
    /// was lit, reverse dim); lit only while driving with it.
    #[test]
    fn turbo_and_reverse_dim_by_one_rule() {
        let off = ControlView::default();
        let s = styles(&off);
        assert_eq!(s[0], ("turbo".into(), theme::dim()));
        assert_eq!(s[1], ("reverse".into(), theme::dim()));
        let lit = theme::commanded().add_modifier(Modifier::REVERSED | Modifier::BOLD);
        let standing = ControlView {
            turbo: true,
            reverse: true,
            ..ControlView::default()
        };
        assert_eq!(
            styles(&standing),
            [
                ("TURBO".to_string(), theme::commanded()),
                ("REVERSE".to_string(), theme::commanded())
            ]
        );
        let driving = ControlView {
            speed: 200,
            ..standing.clone()
        };
        assert_eq!(
            styles(&driving),
            [("TURBO".to_string(), lit), ("REVERSE".to_string(), lit)]
        );
        let stopped = ControlView {
            estop: true,
            ..driving.clone()
        };
        assert_eq!(styles(&stopped), styles(&standing));
        // Turbo on, driving forward: turbo lit, reverse off as when standing.
        let forward = ControlView {
            reverse: false,
            ..driving
        };
        assert_eq!(styles(&forward)[1], ("reverse".into(), theme::dim()));
        // Only what applies: Robi shows neither.
        assert!(flags(&forward, false, false).spans.is_empty());
    }
}
