//! The mouse: the wheel scrolls the packet log and pages help; a click chooses a droid on the
//! roster, gives the keys to the pane it lands on (the log, or driving), or picks a palette
//! entry. It never drives, and every key stays bound (keyboard-only use is complete). Where
//! things are comes from the same [`super::layout::screen`] the UI draws with, for the
//! terminal's area at the last frame.

use super::core::App;
use super::input::MouseKind;
use super::layout;
use super::place::Place;
use super::state::{Focus, Overlay};
use crate::config::Action;
use ratatui::layout::{Position, Rect};

/// Log lines one wheel step scrolls.
const WHEEL_LINES: usize = 3;

impl App {
    /// A mouse event at column `col`, row `row`. When it changes the place on top or the
    /// droid, every held key is let go (as for a key).
    pub(super) fn on_mouse(&mut self, kind: MouseKind, col: u16, row: u16) {
        let before = (self.place(), self.chosen(), self.mirroring());
        let at = Position::new(col, row);
        match before.0 {
            Place::Help => match kind {
                MouseKind::ScrollDown => self.state.help_page += 1,
                MouseKind::ScrollUp => {
                    self.state.help_page = self.state.help_page.saturating_sub(1)
                }
                MouseKind::Click => self.state.overlay = Overlay::None,
            },
            Place::Palette => self.palette_mouse(kind, at),
            Place::Driving | Place::Log | Place::Replay => self.screen_mouse(kind, at),
            // Typing places and the settings lists: keys only.
            Place::Packet => match kind {
                MouseKind::ScrollDown => self.detail_scroll(3, true),
                MouseKind::ScrollUp => self.detail_scroll(3, false),
                MouseKind::Click => {}
            },
            Place::Filter | Place::Matrix | Place::Channels | Place::Tuning => {}
        }
        if (self.place(), self.chosen(), self.mirroring()) != before {
            self.clear_held();
        }
    }

    /// Lines of packets the log pane shows at the last frame's size (its borders and header
    /// off): the window the log's cursor moves in.
    pub(super) fn log_rows(&self) -> usize {
        let log = layout::screen(self.area, self.len() > 1).plan.log;
        usize::from(log.height.saturating_sub(3))
    }

    /// The main screen: the roster, the log, the panels.
    fn screen_mouse(&mut self, kind: MouseKind, at: Position) {
        let fleet = self.len() > 1;
        let screen = layout::screen(self.area, fleet);
        let log = (!self.state.droid().scope.visible).then_some(screen.plan.log);
        let on_log = log.is_some_and(|r| r.contains(at));
        match kind {
            MouseKind::ScrollUp if on_log => self.state.log.scroll_up(WHEEL_LINES),
            MouseKind::ScrollDown if on_log => self.state.log.scroll_down(WHEEL_LINES),
            MouseKind::ScrollUp | MouseKind::ScrollDown => {}
            MouseKind::Click => {
                if let Some(strip) = screen.roster.filter(|r| r.contains(at)) {
                    let n = self.len();
                    let x = at.x - strip.x;
                    if let Some(i) = layout::roster_entry_at(strip.width, n, self.mirroring(), x) {
                        self.choose(i);
                    }
                } else if on_log {
                    self.state.focus = Focus::Log;
                } else if below(screen.plan.status, at) {
                    // The panels (or the scope): the keys drive again.
                    self.state.focus = Focus::Drive;
                }
            }
        }
    }

    /// The palette: the wheel moves the selection, a click on an entry plays it (as Enter
    /// does), a click outside closes it.
    fn palette_mouse(&mut self, kind: MouseKind, at: Position) {
        let (selected, entries) = match &self.state.overlay {
            Overlay::Animations { selected } => (*selected, &self.state.animations),
            Overlay::Sounds { selected } => (*selected, &self.state.sounds),
            _ => return,
        };
        let len = entries.len();
        let rect = layout::palette_rect(
            self.area,
            entries
                .iter()
                .map(|e| ratatui::text::Span::raw(e.name.as_str()).width()),
            len,
        );
        let inner = Rect {
            x: rect.x + 1,
            y: rect.y + 1,
            width: rect.width.saturating_sub(2),
            height: rect.height.saturating_sub(2),
        };
        let sel = match kind {
            MouseKind::ScrollUp => selected.saturating_sub(1),
            MouseKind::ScrollDown => (selected + 1).min(len.saturating_sub(1)),
            MouseKind::Click if inner.contains(at) => {
                let first = layout::list_offset(selected, len, inner.height as usize);
                let i = first + (at.y - inner.y) as usize;
                if i >= len {
                    return;
                }
                i
            }
            MouseKind::Click => {
                self.state.overlay = Overlay::None;
                return;
            }
        };
        match &mut self.state.overlay {
            Overlay::Animations { selected } | Overlay::Sounds { selected } => *selected = sel,
            _ => {}
        }
        if kind == MouseKind::Click
            && let Some(play) = self.keymap.keys(Action::PalettePlay).first().copied()
        {
            // The same path as the play key.
            self.palette_key(play, true);
        }
    }
}

/// Whether `at` is below the status bar `status`.
fn below(status: Rect, at: Position) -> bool {
    at.y >= status.bottom()
}
