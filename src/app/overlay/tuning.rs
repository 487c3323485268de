//! The streaming and collision settings: a draft edited row by row with the
//! `[keys.settings]` bindings, sent to the droid on apply.

use super::{Around, Component, Do, Outcome, Overlay};
use crate::app::place::Place;
use crate::app::view::scope::tuning_rows;
use crate::config::{Action, Context, Key};

/// The settings palette.
pub struct Tuning;

impl Component for Tuning {
    const PLACE: Place = Place::Tuning;

    fn on_key(o: &mut Overlay, around: &mut Around, key: Key, new_press: bool) -> Outcome<Do> {
        let rows = tuning_rows(around.monitor);
        let caps = around.monitor.caps;
        let Overlay::Tuning { selected, draft } = o else {
            return Outcome::Stay;
        };
        let row = rows.get(*selected).copied();
        match around.keymap.action_in(Context::Settings, &key) {
            Some(Action::SettingsUp) => *selected = selected.saturating_sub(1),
            Some(Action::SettingsDown) => {
                *selected = (*selected + 1).min(rows.len().saturating_sub(1))
            }
            Some(Action::SettingsLess) => {
                if let Some(r) = row {
                    draft.change(caps.as_ref(), r, Some(false));
                }
            }
            Some(Action::SettingsMore) => {
                if let Some(r) = row {
                    draft.change(caps.as_ref(), r, Some(true));
                }
            }
            Some(Action::SettingsToggle) if new_press => {
                if let Some(r) = row {
                    draft.change(caps.as_ref(), r, None);
                }
            }
            Some(Action::SettingsApply) if new_press => {
                return Outcome::Done(Do::Tune(draft.clone()));
            }
            Some(Action::SettingsClose) => return Outcome::Close,
            _ => {}
        }
        Outcome::Stay
    }

    #[cfg(test)]
    fn sample() -> Overlay {
        let model = crate::model::Model::DEFAULT;
        Overlay::Tuning {
            selected: 0,
            draft: crate::app::view::scope::TuningDraft {
                rate_hz: 10,
                sensors: crate::family::stream::all_groups(model),
                collision: Default::default(),
            },
        }
    }
}
