//! BOLT's LED matrix as droidctl drew it (the robot does not report it: the panel follows the
//! matrix commands that went out, from the keys, a mission or a Sphero Edu program alike), and
//! the colours the colour key cycles through. View state only: the keys that change it are
//! [`crate::app::matrix`]'s, the UI reads it.

use crate::script::MatrixAction;

/// The colours the colour key cycles through.
pub const MAIN_LED_CYCLE: [[u8; 3]; 6] = [
    [255, 0, 0],
    [0, 255, 0],
    [0, 0, 255],
    [255, 255, 255],
    [255, 140, 0],
    [0, 0, 0],
];

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
    pub(in crate::app) fn action(&self) -> MatrixAction {
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
