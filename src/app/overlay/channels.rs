//! The scope's channel list: the channels the droid reports, switched on and off with the
//! `[keys.settings]` bindings (its Enter switches the row too: nothing to apply).

use super::{Around, Component, Do, Outcome, Overlay};
use crate::app::place::Place;
use crate::config::{Action, Context, Key};
use crate::model::Model;
use crate::telemetry::history::Channel;

/// The channel list.
pub struct Channels;

/// The channels a droid of `model` reports, as the channel list shows them.
pub fn offered(model: Model) -> Vec<Channel> {
    let robi = model.reports_state_frames();
    Channel::ALL
        .iter()
        .copied()
        .filter(|c| c.reported_by(robi))
        .collect()
}

impl Component for Channels {
    const PLACE: Place = Place::Channels;

    fn on_key(o: &mut Overlay, around: &mut Around, key: Key, new_press: bool) -> Outcome<Do> {
        let Overlay::Channels { selected } = o else {
            return Outcome::Stay;
        };
        let offered = offered(around.model);
        let last = offered.len().saturating_sub(1);
        match around.keymap.action_in(Context::Settings, &key) {
            Some(Action::SettingsUp) => *selected = selected.saturating_sub(1),
            Some(Action::SettingsDown) => *selected = (*selected + 1).min(last),
            Some(Action::SettingsToggle | Action::SettingsApply) if new_press => {
                if let Some(c) = offered.get(*selected) {
                    return Outcome::Apply(Do::ToggleChannel(*c));
                }
            }
            Some(Action::SettingsClose) => return Outcome::Close,
            _ => {}
        }
        Outcome::Stay
    }

    #[cfg(test)]
    fn sample() -> Overlay {
        Overlay::Channels { selected: 0 }
    }
}
