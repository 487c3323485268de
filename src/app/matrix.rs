//! BOLT's LED matrix in the app: what droidctl drew on it (the robot does not report it:
//! the panel follows the matrix commands that went out, from the keys, a mission or a Sphero
//! Edu program alike), the prompt that types on it (one character is drawn, more scroll), the
//! colour key, and the compass calibration key. Every command is the family's
//! (`Family::matrix`).

use super::core::App;
use super::state::{MAIN_LED_CYCLE, Overlay};
use crate::config::{Action, Context, Key};
use crate::protocol::v2::types::SCROLL_TEXT_MAX;
use crate::script::MatrixAction;

/// What the matrix shows, as last drawn.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum MatrixShows {
    #[default]
    Unknown,
    Fill,
    Char(char),
    Text(String),
    /// Pixels, lines or rectangles (a program's or a mission's drawing).
    Drawing,
    /// A saved animation playing (its index).
    Animation(u8),
}

/// The matrix as droidctl drew it: its colour and what is on it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MatrixView {
    pub colour: [u8; 3],
    pub shows: MatrixShows,
}

impl Default for MatrixView {
    fn default() -> Self {
        MatrixView {
            colour: MAIN_LED_CYCLE[0],
            shows: MatrixShows::Unknown,
        }
    }
}

impl MatrixView {
    /// The drawing that shows `shows` in the current colour.
    fn action(&self) -> MatrixAction {
        match &self.shows {
            MatrixShows::Char(ch) => MatrixAction::Char {
                ch: *ch,
                rgb: self.colour,
            },
            MatrixShows::Text(text) => MatrixAction::Text {
                text: text.clone(),
                rgb: self.colour,
            },
            MatrixShows::Unknown
            | MatrixShows::Fill
            | MatrixShows::Drawing
            | MatrixShows::Animation(_) => MatrixAction::Fill(self.colour),
        }
    }

    /// A matrix command that went out to the droid (IO 0x1A; its cid and payload): what the
    /// matrix shows now. Other commands change nothing.
    pub fn sent(&mut self, did: u8, cid: u8, data: &[u8]) {
        if did != 0x1A {
            return;
        }
        match (cid, data) {
            (0x2F, &[r, g, b, ..]) => {
                self.colour = [r, g, b];
                self.shows = MatrixShows::Fill;
            }
            (0x42, &[r, g, b, c, ..]) => {
                self.colour = [r, g, b];
                self.shows = MatrixShows::Char(c as char);
            }
            (0x3B, &[r, g, b, _, _, ref text @ ..]) => {
                self.colour = [r, g, b];
                let end = text.iter().position(|c| *c == 0).unwrap_or(text.len());
                self.shows = MatrixShows::Text(String::from_utf8_lossy(&text[..end]).into_owned());
            }
            (0x2D, &[_, _, r, g, b, ..]) | (0x3D | 0x3E, &[_, _, _, _, r, g, b, ..]) => {
                self.colour = [r, g, b];
                self.shows = MatrixShows::Drawing;
            }
            (0x32 | 0x43, &[id, ..]) => self.shows = MatrixShows::Animation(id),
            (0x38, _) => {
                self.colour = [0, 0, 0];
                self.shows = MatrixShows::Fill;
            }
            _ => {}
        }
    }

    /// What typed `input` draws: a character, text to scroll, or nothing.
    pub fn typed(input: &str) -> Option<MatrixShows> {
        let t = input.trim();
        let mut chars = t.chars();
        match (chars.next(), chars.next()) {
            (None, _) => None,
            (Some(c), None) => Some(MatrixShows::Char(c)),
            _ => Some(MatrixShows::Text(t.to_string())),
        }
    }
}

impl App {
    /// The robot-only keys of the drive table; `false` when `a` is not one of them.
    pub fn robot_action(&mut self, a: Action) -> bool {
        let model = self.state.droid().model;
        match a {
            Action::Matrix | Action::MatrixColour if !model.has_matrix() => {
                self.hint("this droid has no LED matrix")
            }
            Action::Matrix => {
                self.state.overlay = Overlay::Matrix {
                    input: String::new(),
                }
            }
            Action::MatrixColour => {
                let m = &mut self.state.droid_mut().matrix;
                let next = MAIN_LED_CYCLE
                    .iter()
                    .position(|c| *c == m.colour)
                    .map_or(0, |i| (i + 1) % MAIN_LED_CYCLE.len());
                m.colour = MAIN_LED_CYCLE[next];
                self.draw_matrix();
            }
            Action::Calibrate => {
                let chosen = self.chosen();
                let calibrate = crate::family::intent::Intent::CalibrateCompass;
                match self.io[chosen].family.lower(model, &calibrate) {
                    Ok(cmds) => {
                        if let Some(mut d) = self.droid(chosen) {
                            for c in cmds {
                                d.send(c, "compass calibration");
                            }
                        }
                        self.hint("calibrating the compass: north is reported when done");
                    }
                    _ => self.hint("this droid has no compass"),
                }
            }
            _ => return false,
        }
        true
    }

    /// Send what the chosen droid's matrix view says it shows.
    fn draw_matrix(&mut self) {
        let Some(mut d) = self.droid(self.chosen()) else {
            return;
        };
        let action = d.view.matrix.action();
        if matches!(d.view.matrix.shows, MatrixShows::Unknown) {
            d.view.matrix.shows = MatrixShows::Fill;
        }
        let draw = crate::family::intent::Intent::Matrix((&action).into());
        if let Ok(cmds) = d.io.family.lower(d.view.model, &draw) {
            for c in cmds {
                d.send(c, "matrix");
            }
        }
    }

    /// A key while the matrix prompt is open (the filter table's apply and cancel keys).
    pub fn matrix_key(&mut self, key: Key) {
        let action = self.keymap.action_in(Context::Filter, &key);
        let Overlay::Matrix { input } = &mut self.state.overlay else {
            return;
        };
        match action {
            Some(Action::FilterCancel) => self.state.overlay = Overlay::None,
            Some(Action::FilterApply) => {
                let typed = MatrixView::typed(input);
                self.state.overlay = Overlay::None;
                if let Some(shows) = typed {
                    self.state.droid_mut().matrix.shows = shows;
                    self.draw_matrix();
                }
            }
            _ => super::keys::edit(input, key, SCROLL_TEXT_MAX, |c| c.is_ascii_graphic()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_panel_follows_what_went_out_whoever_sent_it() {
        let mut m = MatrixView::default();
        m.sent(0x1A, 0x42, &[255, 0, 0, b'A']);
        assert_eq!(
            (m.shows.clone(), m.colour),
            (MatrixShows::Char('A'), [255, 0, 0])
        );
        m.sent(0x1A, 0x3B, &[0, 9, 0, 10, 0, b'H', b'I', 0]);
        assert_eq!(m.shows, MatrixShows::Text("HI".into()));
        m.sent(0x1A, 0x3D, &[0, 0, 7, 0, 0, 0, 255]);
        assert_eq!(
            (m.shows.clone(), m.colour),
            (MatrixShows::Drawing, [0, 0, 255])
        );
        m.sent(0x1A, 0x43, &[2, 1]);
        assert_eq!(m.shows, MatrixShows::Animation(2));
        // Not the matrix, or a short payload: nothing changes.
        m.sent(0x16, 0x07, &[1, 2, 3]);
        m.sent(0x1A, 0x42, &[1]);
        assert_eq!(m.shows, MatrixShows::Animation(2));
        m.sent(0x1A, 0x38, &[]);
        assert_eq!((m.shows.clone(), m.colour), (MatrixShows::Fill, [0, 0, 0]));
    }

    #[test]
    fn typing_draws_a_character_or_scrolls() {
        assert_eq!(MatrixView::typed(""), None);
        assert_eq!(MatrixView::typed(" A "), Some(MatrixShows::Char('A')));
        assert_eq!(
            MatrixView::typed("HI THERE"),
            Some(MatrixShows::Text("HI THERE".into()))
        );
        let v = MatrixView {
            shows: MatrixShows::Char('Z'),
            ..Default::default()
        };
        assert_eq!(
            v.action(),
            MatrixAction::Char {
                ch: 'Z',
                rgb: MAIN_LED_CYCLE[0]
            }
        );
    }
}
