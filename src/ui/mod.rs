//! The terminal UI: a pure function of [`AppState`]. [`draw`] reads the state and paints one
//! frame; it never mutates anything, so the event loop can redraw whenever it likes and the
//! snapshot tests can render any state they can build.
//!
//! Each panel lives in its own file and draws into the rect [`layout`] gives it, adapting its
//! content to that size. Nothing here may panic on odd input: values are clamped, NaN and
//! infinity print as such and are left out of gauges and canvases, and every rect is
//! clipped to the frame.

mod collisions;
mod compass;
mod dome;
mod drive;
mod footer;
/// Where the panels go: in the app (the mouse finds what it points at with the same plan).
pub use crate::app::layout;
mod leds;
mod log_pane;
mod map;
mod overlay;
pub mod picker;
mod program;
mod robi;
mod robots;
mod roster;
mod scope;
mod sensors;
mod status;
mod text;
mod theme;

use crate::app::state::AppState;
use layout::{MIN_HEIGHT, MIN_WIDTH};
use ratatui::Frame;
use ratatui::text::Span;
use ratatui::widgets::Paragraph;

/// Draw the whole screen for `state`, in its theme's colours.
pub fn draw(frame: &mut Frame, state: &AppState) {
    draw_panels(frame, state);
    theme::apply(frame.buffer_mut(), state.theme);
}

fn draw_panels(frame: &mut Frame, state: &AppState) {
    // A fleet's roster strip takes the top row; the rest is the one-droid screen.
    let fleet = state.roster();
    let screen = layout::screen(frame.area(), fleet.is_some());
    if let (Some(roster), Some(strip)) = (&fleet, screen.roster) {
        roster::render(frame, strip, roster);
    }
    if let Some(row) = screen.footer {
        footer::render(frame, row, state);
    }
    let p = screen.plan;
    // The newer robots' panels want a few more rows in the dome's place (BOLT's matrix 4
    // rows of half blocks, RVR two lines): taken from the panels around it.
    let want = if state.droid().model.has_matrix() {
        6
    } else if state.droid().model.has_tracks() {
        4
    } else {
        0
    };
    let p = robots::make_room(p, want);
    status::render(frame, p.status, state);
    if state.droid().scope.visible {
        // The scope takes everything below the status bar.
        let body = ratatui::layout::Rect {
            y: p.status.bottom(),
            height: p.log.bottom().saturating_sub(p.status.bottom()),
            ..p.status
        };
        scope::render(frame, body, state);
        program::banner(frame, state, p.status.bottom());
        overlay::render(frame, state);
        return;
    }
    if let Some(r) = p.drive {
        drive::render(frame, r, state);
    }
    if let Some(r) = p.map {
        // A fleet's other droids are on the chosen droid's map, by roster number.
        let others: Vec<map::Other> = fleet
            .iter()
            .flat_map(|roster| {
                roster.droids.iter().enumerate().filter_map(|(i, d)| {
                    let at = map::in_room(d.room_origin, d.position?)?;
                    (i != roster.chosen).then_some(map::Other { number: i + 1, at })
                })
            })
            .collect();
        let droid = state.droid();
        map::render_with(frame, r, &droid.telemetry, droid.room_origin, &others);
    }
    // Panels by capability: the dome's place shows the dome, Robi's motors, BOLT's matrix,
    // RVR's rover panel or the lights; the sensors' place shows Sphero sensors or Robi's I/O
    // and link quality.
    let frames = state.droid().model.reports_state_frames();
    let (dome_rect, mut sensors_rect, mut collisions_rect) = (p.dome, p.sensors, p.collisions);
    // Robi reports no collisions: its I/O panel takes the collisions' place too.
    if frames && let (Some(s), Some(c)) = (sensors_rect, collisions_rect) {
        sensors_rect = Some(s.union(c));
        collisions_rect = None;
    }
    if let Some(r) = dome_rect {
        if state.droid().model.has_dome() {
            dome::render(frame, r, state);
        } else if frames {
            robi::motors(frame, r, state);
        } else if state.droid().model.has_matrix() {
            robots::bolt(frame, r, state);
        } else if state.droid().model.has_tracks() {
            robots::rvr(frame, r, state);
        } else {
            leds::render(frame, r, state);
        }
    }
    if let Some(r) = sensors_rect {
        if frames {
            robi::io(frame, r, state);
        } else {
            sensors::render(frame, r, &state.droid().telemetry, &scope::rates(state));
        }
    }
    if let Some(r) = collisions_rect {
        collisions::render(frame, r, state);
    }
    if let Some(r) = p.notice {
        let msg = format!("panels need {MIN_WIDTH}×{MIN_HEIGHT}");
        frame.render_widget(Paragraph::new(Span::styled(msg, theme::dim())), r);
    }
    log_pane::render(frame, p.log, state);
    program::banner(frame, state, p.status.bottom());
    overlay::render(frame, state);
}
