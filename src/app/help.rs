//! The help overlay's text and the context footer, generated from the bindings as configured
//! and the one table of key definitions ([`crate::config::KEY_TABLE`]): help has one section
//! per place keys are read (driving, the packet log, palettes, the filter prompt, help itself,
//! replay), then the gamepad; the footer has the few keys that matter in the place on top,
//! then `?` for the rest. Both leave out what does not apply to the chosen droid (its
//! [`Needs`]). A rebound key shows in both because they are built from the same [`KeyMap`] the
//! key dispatch reads.

pub use super::borders::{
    AIM_AGAIN, Borders, CHANNELS, DETAIL, DETAIL_MATCHES, DETAIL_TYPING, HELP_PAGES, Hint,
    LIGHTS_PANEL, MATRIX_PANEL, PALETTE, PROMPT, TANK_PANEL, TUNING, border,
};
use super::place::Place;
use super::state::{AppState, FooterKey, HelpLine, HelpSection};
use crate::config::{Action, Config, Context, KeyMap, Needs};

/// Help for a live session: every context a live app reads keys in, then the gamepad.
pub fn live(config: &Config) -> Vec<HelpSection> {
    let km = &config.keymap;
    let mut sections = vec![section(km, Context::Drive), everywhere()];
    sections.extend(
        [
            Context::Log,
            Context::Scope,
            Context::Settings,
            Context::Palette,
            Context::Filter,
            Context::Detail,
            Context::Help,
        ]
        .into_iter()
        .map(|c| section(km, c)),
    );
    sections.push(gamepad(config));
    sections
}

/// The keys no binding changes, read in every place.
fn everywhere() -> HelpSection {
    HelpSection {
        title: "Everywhere".into(),
        lines: vec![
            HelpLine {
                keys: crate::config::Key::CTRL_SPACE.to_string(),
                action: "emergency stop, text prompts included".into(),
                needs: Needs::All,
            },
            HelpLine {
                keys: "Ctrl+c".into(),
                action: "quit (stops the droid first)".into(),
                needs: Needs::All,
            },
        ],
    }
}

/// Help for a replay: the replay keys and the drive table's quit, help and log keys (nothing
/// drives a replay), the packet log and help itself. No gamepad section.
pub fn replay(km: &KeyMap) -> Vec<HelpSection> {
    let mut replay = section(km, Context::Replay);
    for a in [Action::Log, Action::Scope, Action::Help, Action::Quit] {
        if let Some(keys) = km.shown(a) {
            replay.lines.push(HelpLine {
                keys,
                action: a.description().into(),
                needs: a.needs(),
            });
        }
    }
    vec![
        replay,
        section(km, Context::Log),
        section(km, Context::Scope),
        section(km, Context::Settings),
        section(km, Context::Help),
    ]
}

/// The help overlay's stop, for its bottom edge (`Space stop`; empty in a replay, which
/// drives nothing): help covers the footer, and the stop works over it. The page keys come
/// from [`HELP_PAGES`] as bound, shown only when there is another page.
pub fn nav(km: &KeyMap, live: bool) -> String {
    match km.keys(Action::EStop).first().filter(|_| live) {
        Some(stop) => format!("{stop} stop"),
        None => String::new(),
    }
}

/// The context footer's keys for every place keys are read: the keys the table gives a
/// footer word, the first key bound to each, then (kept however narrow the row) the keys that
/// leave the place or show the rest. A drive-specific key comes before the general ones, so
/// on a narrow row what this droid can do stays and the general keys go first.
pub fn footer(km: &KeyMap, live: bool) -> Vec<(Context, Vec<FooterKey>)> {
    let first = |a: Action| km.keys(a).first().map(ToString::to_string);
    let entry = |a: Action, word: &str, keep: bool| {
        first(a).map(|key| FooterKey {
            key,
            word: word.into(),
            needs: a.needs(),
            keep,
            action: Some(a),
        })
    };
    let words = |ctx: Context| -> Vec<FooterKey> {
        let own: Vec<Action> = Action::ALL
            .iter()
            .copied()
            .filter(|a| a.context() == ctx && !a.short().is_empty())
            .filter(|a| !matches!(a, Action::Help | Action::Quit))
            .collect();
        // EStop first, then the fleet's keys, what this droid alone can do, then the rest,
        // each in table order.
        let (stop, rest): (Vec<Action>, Vec<Action>) =
            own.into_iter().partition(|a| *a == Action::EStop);
        let (fleet, rest): (Vec<Action>, Vec<Action>) =
            rest.into_iter().partition(|a| a.needs() == Needs::Fleet);
        let (special, general): (Vec<Action>, Vec<Action>) =
            rest.into_iter().partition(|a| a.needs() != Needs::All);
        stop.into_iter()
            .chain(fleet)
            .chain(special)
            .chain(general)
            .filter_map(|a| entry(a, a.short(), false))
            .collect()
    };
    let tail = |extra: &[(Action, &str)]| -> Vec<FooterKey> {
        extra
            .iter()
            .filter_map(|(a, w)| entry(*a, w, true))
            .collect()
    };
    let more = Action::Help.short();
    // Every footer shows the stop first: the driving table's own stop entry, elsewhere the
    // stop's key that works there (in a text prompt the one held with Ctrl, as Space is
    // typed), kept however narrow the row.
    // A replay drives nothing: no stop to show (Space pauses it).
    let stop = |text: bool| {
        if !live {
            return None;
        }
        let key = match text {
            true => Some(crate::config::Key::CTRL_SPACE),
            false => km.keys(Action::EStop).first().copied(),
        };
        key.map(|k| FooterKey {
            key: k.to_string(),
            word: Action::EStop.short().into(),
            needs: Needs::All,
            keep: true,
            action: Some(Action::EStop),
        })
    };
    let with = |ctx: Context, extra: &[(Action, &str)]| {
        let mut v: Vec<FooterKey> = match ctx {
            Context::Drive | Context::Replay => Vec::new(),
            // The packet detail has a search prompt of its own: the stop that works while
            // typing there works outside it too.
            _ => stop(matches!(ctx, Context::Filter | Context::Detail))
                .into_iter()
                .collect(),
        };
        v.extend(words(ctx));
        v.extend(tail(extra));
        (ctx, v)
    };
    let mut help: Vec<FooterKey> = stop(false).into_iter().collect();
    help.extend(words(Context::Help));
    help.push(FooterKey {
        key: "other keys".into(),
        word: "close".into(),
        needs: Needs::All,
        keep: true,
        action: None,
    });
    vec![
        with(
            Context::Drive,
            &[(Action::Help, more), (Action::Quit, "quit")],
        ),
        with(
            Context::Log,
            &[(Action::Help, more), (Action::Quit, "quit")],
        ),
        with(
            Context::Scope,
            &[(Action::Scope, "close"), (Action::Help, more)],
        ),
        with(
            Context::Replay,
            &[
                (Action::Log, "log"),
                (Action::Help, more),
                (Action::Quit, "quit"),
            ],
        ),
        with(Context::Palette, &[]),
        with(Context::Filter, &[]),
        with(Context::Settings, &[]),
        with(Context::Detail, &[]),
        (Context::Help, help),
    ]
}

/// When the footer leaves keys of its place's table out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unless {
    /// Never offered there.
    Never,
    /// Only once a search was made (a packet in full).
    Searched,
    /// Only when help takes more than one page.
    Paged,
}

/// The footer's exceptions, per place: the keys of the place's table ([`Place::context`])
/// that the footer does not offer there, and when they come back. Everything else the footer
/// shows is the table's own; a place not named here has no exception.
pub const FOOTER_EXCEPTIONS: &[(Place, &[Action], Unless)] = &[
    // The channel list shares the settings' table, but there the apply key switches the
    // row: its word is in the border, not "apply" here.
    (Place::Channels, &[Action::SettingsApply], Unless::Never),
    // A packet in full goes through matches only once there is a search.
    (
        Place::Packet,
        &[Action::DetailNext, Action::DetailPrevious],
        Unless::Searched,
    ),
    // Help on one page: no page keys to offer (they would do nothing).
    (
        Place::Help,
        &[Action::HelpNext, Action::HelpPrevious],
        Unless::Paged,
    ),
];

/// The footer's keys now: for the place on top and the chosen droid. `help_paged`: help, if
/// it is on top, takes more than one page of the screen (the UI knows its size).
pub fn footer_now(state: &AppState, help_paged: bool) -> Vec<&FooterKey> {
    let replay = state.droid().replay.is_some();
    let place = Place::of(state, replay);
    let searched = matches!(
        &state.overlay,
        super::state::Overlay::Packet { search, .. } if !search.is_empty()
    );
    // An open overlay's table is the registry's (a packet's search types with the prompts').
    let ctx = (state.overlay.context())
        .unwrap_or_else(|| place.context(state.droid().scope.visible, false));
    let hidden = |a: Option<Action>| {
        FOOTER_EXCEPTIONS.iter().any(|(p, actions, unless)| {
            *p == place
                && a.is_some_and(|a| actions.contains(&a))
                && match unless {
                    Unless::Never => true,
                    Unless::Searched => !searched,
                    Unless::Paged => !help_paged,
                }
        })
    };
    let (model, fleet) = (state.droid().model, state.droids.len() > 1);
    state
        .footer
        .iter()
        .find(|(c, _)| *c == ctx)
        .map(|(_, keys)| {
            keys.iter()
                .filter(|k| k.needs.applies(model, fleet) && !hidden(k.action))
                .collect()
        })
        .unwrap_or_default()
}

fn section(km: &KeyMap, ctx: Context) -> HelpSection {
    HelpSection {
        title: ctx.title().into(),
        lines: km
            .help(ctx)
            .into_iter()
            .map(|(keys, a)| HelpLine {
                keys,
                action: a.description().into(),
                needs: a.needs(),
            })
            .collect(),
    }
}

fn gamepad(config: &Config) -> HelpSection {
    let g = &config.gamepad;
    let line = |keys: &str, action: &str, needs| HelpLine {
        keys: keys.into(),
        action: action.into(),
        needs,
    };
    let mut lines = vec![
        line("left stick", "heading and speed (polar)", Needs::All),
        line("right stick X", "turn the dome", Needs::Dome),
        line(
            "sticks Y",
            "tank mode: left and right track (RVR)",
            Needs::Tracks,
        ),
        line("right trigger", "more speed, up to turbo", Needs::Turbo),
    ];
    lines.extend(
        g.buttons
            .iter()
            .map(|(b, a)| line(b.name(), a.description(), a.needs())),
    );
    lines.push(line(
        "D-pad",
        &format!(
            "sounds {} / {} / {} / {}",
            g.sound_up, g.sound_down, g.sound_left, g.sound_right
        ),
        Needs::Animations,
    ));
    HelpSection {
        title: "Gamepad".into(),
        lines,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn find<'a>(sections: &'a [HelpSection], title: &str) -> &'a HelpSection {
        sections
            .iter()
            .find(|s| s.title == title)
            .unwrap_or_else(|| panic!("no section {title}"))
    }

    fn keys_of<'a>(s: &'a HelpSection, action: &str) -> Vec<&'a str> {
        s.lines
            .iter()
            .filter(|l| l.action.starts_with(action))
            .map(|l| l.keys.as_str())
            .collect()
    }

    #[test]
    fn every_binding_is_listed_where_it_is_read() {
        let c = Config::defaults();
        let h = live(&c);
        let titles: Vec<&str> = h.iter().map(|s| s.title.as_str()).collect();
        assert_eq!(
            titles,
            [
                "Keyboard",
                "Everywhere",
                "Packet log",
                "Scope (other keys drive)",
                "Channels, streaming and collision",
                "Palettes",
                "Log filter",
                "A packet in full",
                "Help",
                "Gamepad"
            ]
        );
        assert_eq!(keys_of(find(&h, "Keyboard"), "drive forward"), ["↑ / w"]);
        assert_eq!(
            keys_of(find(&h, "Everywhere"), "emergency stop"),
            ["Ctrl+Space"]
        );
        assert_eq!(keys_of(find(&h, "Packet log"), "pause"), ["p"]);
        assert_eq!(keys_of(find(&h, "Keyboard"), "the scope"), ["g"]);
        assert_eq!(
            keys_of(find(&h, "Scope (other keys drive)"), "choose the channels"),
            ["C"]
        );
        assert_eq!(keys_of(find(&h, "Gamepad"), "aim mode"), ["RightBumper"]);
        let r = replay(&c.keymap);
        assert_eq!(keys_of(find(&r, "Replay"), "pause / play"), ["Space / p"]);
        assert_eq!(keys_of(find(&r, "Replay"), "quit"), ["q"]);
        assert_eq!(nav(&c.keymap, true), "Space stop");
        assert_eq!(nav(&c.keymap, false), "");
        assert_eq!(border(&c.keymap, HELP_PAGES), "PgDn/PgUp pages");
    }

    #[test]
    fn a_rebound_key_shows_in_help() {
        let c = Config::parse_merged(
            None,
            "[keys.packet_log]\npause = [\"P\"]\n[keys.replay]\nstep = [\"n\"]\n[gamepad]\naim = \"Start\"\n",
        )
        .unwrap();
        let h = live(&c);
        assert_eq!(keys_of(find(&h, "Packet log"), "pause"), ["P"]);
        assert_eq!(keys_of(find(&h, "Gamepad"), "aim mode"), ["Start"]);
        let r = replay(&c.keymap);
        assert_eq!(keys_of(find(&r, "Replay"), "single step"), ["n"]);
    }
}
