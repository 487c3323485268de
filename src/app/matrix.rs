//! BOLT's LED matrix in the app: opening the prompt that types on it (its keys are a
//! component, [`super::overlay::matrix`]), drawing what it shows, the colour key, and the
//! compass calibration key. Every command is the family's
//! (`Family::matrix`). What droidctl drew on it is view state, [`super::view::matrix`].

use super::core::App;
use super::state::Overlay;
use super::view::matrix::{MAIN_LED_CYCLE, MatrixShows};
use crate::config::Action;

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
    pub(super) fn draw_matrix(&mut self) {
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
}
