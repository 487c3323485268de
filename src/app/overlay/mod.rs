//! The overlays as components, in the shape [`super::picker`] has: each overlay's file holds
//! its state's keys (and mouse), reads its own table of the key map and returns an
//! [`Outcome`]; the app carries the outcome out ([`Do`]: play, filter, toggle a channel,
//! send settings, draw on the matrix), so an overlay never reaches into the app.
//!
//! **The registry is the one place an overlay is registered.** The `registry!` list below
//! makes the [`Overlay`] enum (a variant per overlay, its state as its fields), and from the
//! same list its place ([`Overlay::place`], which [`super::place::Place::of`] reads), its key
//! context ([`Overlay::context`]), the key dispatch ([`Overlay::on_key`], all
//! [`super::keys`] calls) and the mouse dispatch ([`Overlay::on_mouse`], all
//! [`super::mouse`] calls). To add an overlay:
//!
//! 1. its component file here: a marker type implementing [`Component`] (its `PLACE`, its
//!    keys → [`Outcome`], its mouse if any, a `sample` of it for the registry's tests);
//! 2. its line in `registry!` (the variant, its fields, its component);
//! 3. its drawing in `ui::overlay` (the UI sits above the app by the layering rule, so
//!    drawing cannot live here; the UI's `match` over [`Overlay`] is exhaustive, so the
//!    compiler asks for it).
//!
//! A new *kind* of place (a new key table) is also a [`super::place::Place`] variant with its
//! name and its [`super::place::Place::context`] arm; an overlay reading an existing table
//! (as both palettes read one) needs none. The registry's tests (`tests` below and
//! `ui::overlay`'s) walk every registered overlay: each has a place that `Place::of` finds, a
//! key context whose keys the footer and help list, keys that reach it, and a drawing.
//!
//! - [`palette`]: the animation and sound palettes;
//! - [`help`]: help's pages;
//! - [`filter`]: the packet-log filter prompt (its own outcome, [`filter::Prompted`]: it
//!   tells the log what to show as it is typed) and the prompts' typing;
//! - [`matrix`]: typing what BOLT's matrix shows;
//! - [`channels`]: the scope's channel list;
//! - [`tuning`]: the streaming and collision settings;
//! - [`packet`]: a packet in full and its search.

pub mod channels;
pub mod filter;
pub mod help;
pub mod matrix;
pub mod packet;
pub mod palette;
pub mod tuning;

use super::input::MouseKind;
use super::packet_log::{LogFilter, LogLine};
use super::place::Place;
use super::view::matrix::MatrixShows;
use super::view::scope::{MonitorView, TuningDraft};
use crate::config::{Context, Key, KeyMap};
use crate::family::catalog::Entry;
use crate::model::Model;
use crate::telemetry::history::Channel;
use ratatui::layout::{Position, Rect};

/// What a key did in an overlay.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome<T = ()> {
    /// The overlay stays open (its state may have changed).
    Stay,
    /// The overlay closes, nothing else happens.
    Close,
    /// The overlay closes with what was chosen.
    Done(T),
    /// The overlay stays open, and the app carries `T` out (the log follows the filter as it
    /// is typed; a channel switches on or off in the list).
    Apply(T),
}

/// What the app carries out for an overlay (the part of an outcome that reaches beyond the
/// overlay's own state: the droid, the log, the scope).
#[derive(Debug, Clone, PartialEq)]
pub enum Do {
    /// Play the palette's entry `index` on the chosen droid (`animation`: the animation
    /// palette, else the sound one).
    Play { animation: bool, index: usize },
    /// The packet log shows this filter.
    Filter(LogFilter),
    /// The scope's channel on or off (the chosen droid's scope).
    ToggleChannel(Channel),
    /// Send these streaming and collision settings to the chosen droid.
    Tune(TuningDraft),
    /// BOLT's matrix shows this.
    Matrix(MatrixShows),
}

/// What an overlay reads beside its own state, lent by the app for one key or click: the
/// bindings, the chosen droid's model and monitoring, the palettes' lists, help's page
/// (kept in [`super::state::AppState::help_page`], where the UI clamps it) and the screen.
pub struct Around<'a> {
    pub keymap: &'a KeyMap,
    pub model: Model,
    pub monitor: &'a MonitorView,
    pub animations: &'a [Entry],
    pub sounds: &'a [Entry],
    pub help_page: &'a mut usize,
    /// The terminal's area at the last frame (where a click lands).
    pub area: Rect,
}

/// An overlay: its place, its key context, its keys and its mouse over its own state (its
/// variant of [`Overlay`]). Implemented by a marker type per overlay, registered once in
/// `registry!`; each function is handed the [`Overlay`] of its own variant (the dispatch
/// matched it).
pub trait Component {
    /// Where keys are read while it is open.
    const PLACE: Place;

    /// The key table read now (a place's own, unless the overlay switches tables: a packet's
    /// search types with the prompts' keys).
    fn context(_overlay: &Overlay) -> Context {
        Self::PLACE.context(false, false)
    }

    /// A key pressed (`new_press`) or repeated while it is open.
    fn on_key(overlay: &mut Overlay, around: &mut Around, key: Key, new_press: bool)
    -> Outcome<Do>;

    /// A mouse event at `at` while it is open (none by default: keys only).
    fn on_mouse(
        _overlay: &mut Overlay,
        _around: &mut Around,
        _kind: MouseKind,
        _at: Position,
    ) -> Outcome<Do> {
        Outcome::Stay
    }

    /// One of it as it opens, for the registry's tests.
    #[cfg(test)]
    fn sample() -> Overlay;
}

/// Makes [`Overlay`] and its dispatch from one list: `Variant { fields } => Component`.
macro_rules! registry {
    ($(
        $(#[$doc:meta])*
        $name:ident $({ $($(#[$fdoc:meta])* $field:ident : $ty:ty),* $(,)? })? => $comp:ty
    ),* $(,)?) => {
        /// What overlays the main screen: nothing, or one registered overlay's state.
        #[derive(Debug, Clone, PartialEq)]
        pub enum Overlay {
            None,
            $( $(#[$doc])* $name $({ $($(#[$fdoc])* $field: $ty),* })? ),*
        }

        impl Overlay {
            /// Every registered overlay's name, in the registry's order.
            pub const REGISTERED: &'static [&'static str] = &[$(stringify!($name)),*];

            /// Its name in the registry (`None`: no overlay).
            pub fn name(&self) -> Option<&'static str> {
                match self {
                    Overlay::None => None,
                    $( Overlay::$name { .. } => Some(stringify!($name)), )*
                }
            }

            /// Where keys are read while it is open (`None`: no overlay).
            pub fn place(&self) -> Option<Place> {
                match self {
                    Overlay::None => None,
                    $( Overlay::$name { .. } => Some(<$comp as Component>::PLACE), )*
                }
            }

            /// The key table it reads now (`None`: no overlay).
            pub fn context(&self) -> Option<Context> {
                match self {
                    Overlay::None => None,
                    $( Overlay::$name { .. } => Some(<$comp as Component>::context(self)), )*
                }
            }

            /// A key to the overlay open.
            pub fn on_key(&mut self, around: &mut Around, key: Key, new_press: bool) -> Outcome<Do> {
                match self {
                    Overlay::None => Outcome::Stay,
                    $( Overlay::$name { .. } => <$comp as Component>::on_key(self, around, key, new_press), )*
                }
            }

            /// A mouse event to the overlay open.
            pub fn on_mouse(&mut self, around: &mut Around, kind: MouseKind, at: Position) -> Outcome<Do> {
                match self {
                    Overlay::None => Outcome::Stay,
                    $( Overlay::$name { .. } => <$comp as Component>::on_mouse(self, around, kind, at), )*
                }
            }

            /// One of every registered overlay, as it opens.
            #[cfg(test)]
            pub fn samples() -> Vec<Overlay> {
                vec![$(<$comp as Component>::sample()),*]
            }
        }
    };
}

registry! {
    /// Help's pages (the page is [`super::state::AppState::help_page`]).
    Help => help::Help,
    /// Picking an animation; `selected` indexes [`super::state::AppState::animations`].
    Animations { selected: usize } => palette::Animations,
    /// Picking a sound; `selected` indexes [`super::state::AppState::sounds`].
    Sounds { selected: usize } => palette::Sounds,
    /// Typing a packet-log filter. It applies as it is typed; `before` is the filter to go
    /// back to on cancel.
    Filter { input: String, before: Box<LogFilter> } => filter::Filter,
    /// Typing what BOLT's matrix shows: one character is drawn, more scroll.
    Matrix { input: String } => matrix::Matrix,
    /// Choosing the scope's channels; `selected` indexes the channels the droid reports.
    Channels { selected: usize } => channels::Channels,
    /// A packet in full: its fields, its frame's parts and hex, its time and droid; a search
    /// through them (`typing`: the search is being typed), the view scrolled by `scroll` rows.
    Packet {
        line: Box<LogLine>,
        search: String,
        typing: bool,
        /// The match shown (an index into the matching rows).
        matched: usize,
        scroll: usize,
    } => packet::Packet,
    /// The streaming and collision settings being edited (sent on apply).
    Tuning { selected: usize, draft: TuningDraft } => tuning::Tuning,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::state::{AppState, DroidState};
    use crate::config::Config;

    /// The registry is the one place an overlay is registered: every overlay it lists has a
    /// place `Place::of` finds (over a replay too), a key table the footer and help list in
    /// full, and keys of that table that reach it through the registry's dispatch. (An
    /// overlay cannot exist outside the registry: the registry makes the enum; the `sample`
    /// a component must give makes it walked here.)
    #[test]
    fn every_registered_overlay_has_a_place_a_listed_key_table_and_keys_that_reach_it() {
        let config = Config::defaults();
        let km = &config.keymap;
        let samples = Overlay::samples();
        let names: Vec<_> = samples.iter().filter_map(Overlay::name).collect();
        assert_eq!(
            names,
            Overlay::REGISTERED,
            "one of each, in the registry's order"
        );
        assert_eq!(Overlay::None.place(), None);
        let footer = crate::app::help::footer(km, true);
        let help = crate::app::help::live(&config);
        for open in samples {
            let name = open.name().unwrap_or_default();
            let place = open.place().unwrap_or_else(|| panic!("{name}: no place"));
            let mut state = AppState::new(Model::R2D2, "R2-D2".into());
            state.overlay = open.clone();
            assert_eq!(Place::of(&state, false), place, "{name}");
            assert_eq!(Place::of(&state, true), place, "{name}: over a replay");
            let ctx = open.context().unwrap_or_else(|| panic!("{name}: no keys"));
            assert_eq!(ctx, place.context(false, false), "{name}: as it opens");
            let bound = km.help(ctx);
            assert!(!bound.is_empty(), "{name}: {ctx:?} binds nothing");
            let shown = footer.iter().find(|(c, _)| *c == ctx);
            assert!(
                shown.is_some_and(|(_, keys)| !keys.is_empty()),
                "{name}: the footer lists no key of {ctx:?}"
            );
            let section = help.iter().find(|s| s.title == ctx.title());
            let section = section.unwrap_or_else(|| panic!("{name}: help has no {ctx:?}"));
            for (keys, a) in &bound {
                assert!(
                    section.lines.iter().any(|l| l.keys == *keys),
                    "{name}: help does not list {a:?} ({keys})"
                );
            }
            // Through the registry's dispatch, some key of its table changes it, closes it or
            // asks the app for something.
            let droid = DroidState::new(Model::R2D2, "R2-D2".into());
            let reached = bound.iter().flat_map(|(_, a)| km.keys(*a)).any(|&key| {
                let mut o = open.clone();
                let mut page = 0;
                let mut around = Around {
                    keymap: km,
                    model: droid.model,
                    monitor: &droid.monitor,
                    animations: &state.animations,
                    sounds: &state.sounds,
                    help_page: &mut page,
                    area: Rect::new(0, 0, 80, 24),
                };
                let out = o.on_key(&mut around, key, true);
                out != Outcome::Stay || o != open || page != 0
            });
            assert!(reached, "{name}: no key of {ctx:?} reaches it");
        }
    }

    /// A key to `o` through the registry, with R2-D2's monitoring and the shipped keys.
    fn press(o: &mut Overlay, action: crate::config::Action, new_press: bool) -> Outcome<Do> {
        let km = Config::defaults().keymap;
        let droid = DroidState::new(Model::DEFAULT, String::new());
        let mut page = 0;
        let key = km.keys(action)[0];
        let mut around = Around {
            keymap: &km,
            model: droid.model,
            monitor: &droid.monitor,
            animations: &[],
            sounds: &[],
            help_page: &mut page,
            area: Rect::new(0, 0, 80, 24),
        };
        o.on_key(&mut around, key, new_press)
    }

    /// What reaches beyond an overlay is an outcome the app carries out, never done by the
    /// overlay itself: the channel switched (the list stays), the settings sent (it closes),
    /// the matrix drawn (it closes; nothing typed just closes), the filter restored.
    #[test]
    fn the_overlays_outcomes_name_what_the_app_does() {
        use crate::config::Action as A;
        let mut channels = Overlay::Channels { selected: 0 };
        let first = channels::offered(Model::DEFAULT)[0];
        assert_eq!(
            press(&mut channels, A::SettingsToggle, false),
            Outcome::Stay
        );
        assert_eq!(
            press(&mut channels, A::SettingsToggle, true),
            Outcome::Apply(Do::ToggleChannel(first))
        );
        assert_eq!(press(&mut channels, A::SettingsClose, true), Outcome::Close);

        let mut tuning = <tuning::Tuning as Component>::sample();
        let Overlay::Tuning { draft, .. } = tuning.clone() else {
            panic!("the settings' sample is the settings");
        };
        assert_eq!(press(&mut tuning, A::SettingsApply, false), Outcome::Stay);
        assert_eq!(
            press(&mut tuning, A::SettingsApply, true),
            Outcome::Done(Do::Tune(draft))
        );

        let mut matrix = <matrix::Matrix as Component>::sample();
        assert_eq!(press(&mut matrix, A::FilterApply, true), Outcome::Close);
        let mut matrix = Overlay::Matrix { input: "R2".into() };
        assert_eq!(
            press(&mut matrix, A::FilterApply, true),
            Outcome::Done(Do::Matrix(MatrixShows::Text("R2".into())))
        );

        let before = LogFilter::parse("ack");
        let mut filter = Overlay::Filter {
            input: "ack r".into(),
            before: Box::new(before.clone()),
        };
        assert_eq!(
            press(&mut filter, A::FilterCancel, true),
            Outcome::Done(Do::Filter(before))
        );

        let mut packet = <packet::Packet as Component>::sample();
        assert_eq!(press(&mut packet, A::DetailClose, false), Outcome::Stay);
        assert_eq!(press(&mut packet, A::DetailClose, true), Outcome::Close);
    }

    #[test]
    fn a_packet_being_searched_reads_the_prompts_keys() {
        let Overlay::Packet { line, .. } = <packet::Packet as Component>::sample() else {
            panic!("the packet's sample is a packet");
        };
        let typing = Overlay::Packet {
            line,
            search: "sp".into(),
            typing: true,
            matched: 0,
            scroll: 0,
        };
        assert_eq!(typing.context(), Some(Context::Filter));
        assert_eq!(typing.place(), Some(Place::Packet));
    }
}
