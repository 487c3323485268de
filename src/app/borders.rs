//! The border and panel hints (`↑↓ select · Enter play · Esc close`): which actions each
//! overlay and panel names, the one function that words them from the bindings, and every
//! one of them built once ([`Borders`]) when the app is set up, as the footer is, so a frame
//! only reads them. Below the state: [`super::state::AppState`] keeps the built set.

use crate::config::{Action, KeyMap};

/// Help's page keys.
pub const HELP_PAGES: &[Hint] = &[(&[Action::HelpNext, Action::HelpPrevious], "pages")];

/// One entry of an overlay's border hint: the actions whose first keys are shown, and the
/// word for what they do there.
pub type Hint = (&'static [Action], &'static str);

/// The palettes' border.
pub const PALETTE: &[Hint] = &[
    (&[Action::PaletteUp, Action::PaletteDown], "select"),
    (&[Action::PalettePlay], "play"),
    (&[Action::PaletteClose], "close"),
];
/// The scope's channel list: both the toggle and the apply key switch the row there.
pub const CHANNELS: &[Hint] = &[
    (&[Action::SettingsUp, Action::SettingsDown], "choose"),
    (&[Action::SettingsToggle, Action::SettingsApply], "switch"),
    (&[Action::SettingsClose], "close"),
];
/// The streaming and collision settings.
pub const TUNING: &[Hint] = &[
    (&[Action::SettingsUp, Action::SettingsDown], "choose"),
    (&[Action::SettingsLess, Action::SettingsMore], "value"),
    (&[Action::SettingsToggle], "on/off"),
    (&[Action::SettingsApply], "apply"),
    (&[Action::SettingsClose], "close"),
];
/// The text prompts (the log filter, BOLT's matrix).
pub const PROMPT: &[Hint] = &[
    (&[Action::FilterApply], "apply"),
    (&[Action::FilterCancel], "cancel"),
];
/// A packet in full, browsing.
pub const DETAIL: &[Hint] = &[
    (&[Action::DetailSearch], "search"),
    (&[Action::DetailUp, Action::DetailDown], "scroll"),
    (&[Action::DetailClose], "close"),
];
/// A packet in full, typing the search (the prompts' keys).
pub const DETAIL_TYPING: &[Hint] = &[
    (&[Action::FilterApply], "find"),
    (&[Action::FilterCancel], "cancel"),
];
/// A packet in full, going through the matches.
pub const DETAIL_MATCHES: &[Hint] = &[
    (&[Action::DetailNext], "next"),
    (&[Action::DetailPrevious], "previous"),
    (&[Action::DetailClose], "close"),
];

/// BOLT's matrix panel: its own keys.
pub const MATRIX_PANEL: &[Hint] = &[
    (&[Action::Matrix], "type"),
    (&[Action::MatrixColour], "colour"),
    (&[Action::Calibrate], "calibrate"),
];

/// The lights panel of a rolling droid.
pub const LIGHTS_PANEL: &[Hint] = &[
    (&[Action::Aim], "aim (heading 0)"),
    (&[Action::Colour], "main colour"),
    (&[Action::BackLight], "back light"),
];
/// Aiming: the aim key again ends it.
pub const AIM_AGAIN: &[Hint] = &[(&[Action::Aim], "again")];

/// RVR's panel, out of tank mode.
pub const TANK_PANEL: &[Hint] = &[(&[Action::Tank], "tank mode")];

/// A border hint from the bindings as configured (`↑↓ select · Enter play · Esc close`): each
/// entry's actions by their first keys (run together when each is one character, as `↑↓`,
/// else with `/`); an entry none of whose actions has a key is left out, so a hint never names
/// a key that does not do it.
pub fn border(km: &KeyMap, hints: &[Hint]) -> String {
    hints
        .iter()
        .filter_map(|(actions, word)| {
            let keys: Vec<String> = actions
                .iter()
                .filter_map(|a| km.keys(*a).first().map(ToString::to_string))
                .collect();
            if keys.is_empty() {
                return None;
            }
            let short = keys.iter().all(|k| k.chars().count() == 1);
            let keys = keys.join(if short { "" } else { "/" });
            Some(format!("{keys} {word}"))
        })
        .collect::<Vec<_>>()
        .join(" · ")
}

/// Every border and panel hint worded from one key map: what a frame draws, built once.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Borders {
    pub help_pages: String,
    pub palette: String,
    pub channels: String,
    pub tuning: String,
    pub prompt: String,
    pub detail: String,
    pub detail_typing: String,
    pub detail_matches: String,
    pub matrix_panel: String,
    pub lights_panel: String,
    pub aim_again: String,
    pub tank_panel: String,
}

impl Borders {
    /// The hints as `km` binds their keys.
    pub fn new(km: &KeyMap) -> Borders {
        Borders {
            help_pages: border(km, HELP_PAGES),
            palette: border(km, PALETTE),
            channels: border(km, CHANNELS),
            tuning: border(km, TUNING),
            prompt: border(km, PROMPT),
            detail: border(km, DETAIL),
            detail_typing: border(km, DETAIL_TYPING),
            detail_matches: border(km, DETAIL_MATCHES),
            matrix_panel: border(km, MATRIX_PANEL),
            lights_panel: border(km, LIGHTS_PANEL),
            aim_again: border(km, AIM_AGAIN),
            tank_panel: border(km, TANK_PANEL),
        }
    }
}
