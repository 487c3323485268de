//! The Sphero Edu program beside the app (`--program`, issue 38 point 10): its segment of the
//! status bar (name, and the line it waits on or how it ended) and the banner of its end or
//! error, which stays until a key. A fleet's banner has a line per droid whose program is
//! over.

use super::text::{clean, truncate, truncate_words, width};
use super::theme;
use crate::app::program_status::{ProgramView, end_words, file_name, state_words};
use crate::app::state::AppState;
use crate::edu::progress::ProgramState;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui::style::{Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Clear, Paragraph};

/// The status bar's words for the chosen droid's program: `▶ square.js line 4 delay(1)`,
/// cut to `room` cells (the name first, the call last).
pub fn segment(p: &ProgramView, room: usize) -> Vec<Span<'static>> {
    let (mark, style) = match &p.status.state {
        ProgramState::Failed { .. } => ("✗ ", Style::new().fg(theme::ALERT)),
        ProgramState::Stopped => ("■ ", Style::new().fg(theme::WARN)),
        ProgramState::Ended => ("■ ", theme::dim()),
        _ => ("▶ ", Style::new().fg(theme::OK)),
    };
    let name = truncate(&clean(file_name(&p.status)), 20);
    let state = clean(&state_words(&p.status));
    let left = room.saturating_sub(width(mark) + width(&name) + 1);
    vec![
        Span::styled(mark, style),
        Span::styled(name, theme::bold()),
        Span::raw(" "),
        Span::styled(truncate(&state, left), style),
    ]
}

/// The banner of the programs that are over and not yet seen, over the panels below the
/// status bar (`below` is the row it starts on).
pub fn banner(frame: &mut Frame, s: &AppState, below: u16) {
    let fleet = s.droids.len() > 1;
    let over: Vec<(&str, &ProgramView)> = s
        .droids
        .iter()
        .filter_map(|d| Some((d.droid_name.as_str(), d.program.as_ref()?)))
        .filter(|(_, p)| p.banner())
        .collect();
    let Some(worst) = over.iter().map(|(_, p)| rank(&p.status.state)).max() else {
        return;
    };
    let area = frame.area();
    let w = area.width.saturating_sub(4).min(76);
    if w < 20 || area.height < below + 4 {
        return;
    }
    let inner = usize::from(w - 4);
    let mut lines: Vec<Line> = Vec::new();
    for (name, p) in &over {
        let text = if fleet {
            format!("{}: {}", clean(name), end_words(&p.status))
        } else {
            end_words(&p.status)
        };
        for l in super::text::wrap(&clean(&text), inner).into_iter().take(4) {
            lines.push(Line::from(Span::raw(l)));
        }
    }
    let room = usize::from(area.height - below).saturating_sub(3);
    lines.truncate(room.max(1));
    lines.push(Line::from(Span::styled(
        truncate_words(
            "any key closes this; the program's lines are in the log",
            inner,
        ),
        theme::dim(),
    )));
    let (title, style) = match worst {
        2 => (" program failed ", theme::alarm()),
        1 => (" program stopped ", Style::new().fg(theme::WARN)),
        _ => (" program ended ", Style::new().fg(theme::OK)),
    };
    let rect = Rect {
        x: area.x + (area.width - w) / 2,
        y: area.y + below,
        width: w,
        height: lines.len() as u16 + 2,
    }
    .intersection(area);
    frame.render_widget(Clear, rect);
    let block =
        theme::panel(Span::styled(title, style.add_modifier(Modifier::BOLD))).border_style(style);
    frame.render_widget(
        Paragraph::new(lines).block(block.padding(ratatui::widgets::Padding::horizontal(1))),
        rect,
    );
}

/// How bad an end is: failed over stopped over ended.
fn rank(s: &ProgramState) -> u8 {
    match s {
        ProgramState::Failed { .. } => 2,
        ProgramState::Stopped => 1,
        _ => 0,
    }
}
