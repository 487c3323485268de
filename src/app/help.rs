//! The help overlay's text, generated from the bindings as configured: one section per place
//! keys are read (driving, the packet log, palettes, the filter prompt, help itself, replay),
//! then the gamepad. A rebound key shows in help because help is built from the same
//! [`KeyMap`] the key dispatch reads.

use super::state::{HelpLine, HelpSection};
use crate::config::{Action, Config, Context, KeyMap};

/// Help for a live session: every context a live app reads keys in, then the gamepad.
pub fn live(config: &Config) -> Vec<HelpSection> {
    let km = &config.keymap;
    let mut drive = section(km, Context::Drive);
    drive.lines.push(HelpLine {
        keys: "Ctrl+c".into(),
        action: "quit (stops the droid first), whatever the bindings".into(),
    });
    let mut sections = vec![drive];
    sections.extend(
        [
            Context::Log,
            Context::Scope,
            Context::Settings,
            Context::Palette,
            Context::Filter,
            Context::Help,
        ]
        .into_iter()
        .map(|c| section(km, c)),
    );
    sections.push(gamepad(config));
    sections
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

/// The help overlay's page keys, for its footer (`PgDn/PgUp`).
pub fn nav(km: &KeyMap) -> String {
    let first = |a| km.keys(a).first().map(ToString::to_string);
    match (first(Action::HelpNext), first(Action::HelpPrevious)) {
        (Some(n), Some(p)) => format!("{n}/{p}"),
        (Some(k), None) | (None, Some(k)) => k,
        (None, None) => String::new(),
    }
}

fn section(km: &KeyMap, ctx: Context) -> HelpSection {
    HelpSection {
        title: ctx.title().into(),
        lines: km
            .help(ctx)
            .into_iter()
            .map(|(keys, action)| HelpLine {
                keys,
                action: action.into(),
            })
            .collect(),
    }
}

fn gamepad(config: &Config) -> HelpSection {
    let g = &config.gamepad;
    let line = |keys: &str, action: &str| HelpLine {
        keys: keys.into(),
        action: action.into(),
    };
    let mut lines = vec![
        line("left stick", "heading and speed (polar)"),
        line("right stick X", "turn the dome"),
        line("sticks Y", "tank mode: left and right track (RVR)"),
        line("right trigger", "more speed, up to turbo"),
    ];
    lines.extend(
        g.buttons
            .iter()
            .map(|(b, a)| line(b.name(), a.description())),
    );
    lines.push(line(
        "D-pad",
        &format!(
            "sounds {} / {} / {} / {}",
            g.sound_up, g.sound_down, g.sound_left, g.sound_right
        ),
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
                "Packet log",
                "Scope (other keys drive)",
                "Channels, streaming and collision",
                "Palettes",
                "Log filter",
                "Help",
                "Gamepad"
            ]
        );
        assert_eq!(keys_of(find(&h, "Keyboard"), "drive forward"), ["↑ / w"]);
        assert_eq!(keys_of(find(&h, "Packet log"), "pause"), ["p"]);
        assert_eq!(keys_of(find(&h, "Keyboard"), "the scope"), ["g"]);
        assert_eq!(
            keys_of(find(&h, "Scope (other keys drive)"), "choose the channels"),
            ["Tab"]
        );
        assert_eq!(keys_of(find(&h, "Gamepad"), "aim mode"), ["RightBumper"]);
        let r = replay(&c.keymap);
        assert_eq!(keys_of(find(&r, "Replay"), "pause / play"), ["Space / p"]);
        assert_eq!(keys_of(find(&r, "Replay"), "quit"), ["q"]);
        assert_eq!(nav(&c.keymap), "PgDn/PgUp");
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
