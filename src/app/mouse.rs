//! The mouse: the wheel scrolls the packet log and pages help; a click chooses a droid on the
//! roster, or gives the keys to the pane it lands on (the log, or driving); over an overlay
//! it goes to the overlay's component (the registry's [`super::overlay::Overlay::on_mouse`]:
//! help's pages, a palette's entries, a packet's rows). It never drives, and every key stays bound (keyboard-only use is complete). Where
//! things are comes from the same [`super::layout::screen`] the UI draws with, for the
//! terminal's area at the last frame.

use super::core::App;
use super::input::MouseKind;
use super::layout;
use super::place::Place;
use super::state::Focus;
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
            Place::Driving | Place::Log | Place::Replay => self.screen_mouse(kind, at),
            // Every other place is an open overlay's: the registry hands it the event (the
            // typing places and the settings lists take none: keys only).
            _ => {
                let (overlay, mut around) = self.overlay_around();
                let out = overlay.on_mouse(&mut around, kind, at);
                self.carry_out(out);
            }
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
}

/// Whether `at` is below the status bar `status`.
fn below(status: Rect, at: Position) -> bool {
    at.y >= status.bottom()
}
