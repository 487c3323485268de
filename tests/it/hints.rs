//! Issue 39 point 3: hints that cannot lie. Every place keys are read in is reached through the
//! whole app (simulated droids, paused time: [`droidctl::fuzzing::app_input`]), its screen is
//! read — the footer and the overlay's bottom edge — and every key a hint names is pressed
//! there: it must do what the hint's word says (a stop stops, a close closes, a key that says
//! it changes something changes it, and nothing but a stop stops the droid).

use droidctl::app::place::Place;
use droidctl::app::state::AppState;
use droidctl::config::{Key, KeyCode};
use droidctl::fuzzing::app_input::{EMULATED, Outcome, Step, run_with};
use ratatui::Terminal;
use ratatui::backend::TestBackend;
use std::time::Duration;

fn tap(k: Key) -> Step {
    Step::Press(k)
}

fn pause() -> Step {
    Step::Pause(Duration::from_millis(100))
}

/// The keys a hint's key text names (`↑↓`, `x/Enter`, `Ctrl+Space`, `PgDn`).
fn keys_of(text: &str) -> Option<Vec<Key>> {
    let named = |s: &str| -> Option<Key> {
        Some(match s {
            "Ctrl+Space" => Key::CTRL_SPACE,
            "Space" => Key::plain(KeyCode::Space),
            "Enter" => Key::plain(KeyCode::Enter),
            "Esc" => Key::plain(KeyCode::Esc),
            "Tab" => Key::plain(KeyCode::Tab),
            "Home" => Key::plain(KeyCode::Home),
            "End" => Key::plain(KeyCode::End),
            "PgDn" => Key::plain(KeyCode::PageDown),
            "PgUp" => Key::plain(KeyCode::PageUp),
            "Backspace" => Key::plain(KeyCode::Backspace),
            _ => return None,
        })
    };
    let single = |c: char| -> Key {
        match c {
            '↑' => Key::plain(KeyCode::Up),
            '↓' => Key::plain(KeyCode::Down),
            '←' => Key::plain(KeyCode::Left),
            '→' => Key::plain(KeyCode::Right),
            c => Key::ch(c),
        }
    };
    let mut keys = Vec::new();
    for part in text.split('/').filter(|p| !p.is_empty()) {
        if let Some(k) = named(part) {
            keys.push(k);
        } else if part
            .chars()
            .all(|c| !c.is_alphanumeric() || part.chars().count() == 1)
        {
            // One printable key, or arrows run together (`↑↓`, `←→`).
            keys.extend(part.chars().map(single));
        } else {
            return None;
        }
    }
    // `/` alone is the search key, not a separator.
    if text == "/" {
        keys = vec![Key::ch('/')];
    }
    (!keys.is_empty()).then_some(keys)
}

/// The hints a screen shows: `(keys text, word)` from the footer (the last row) and from
/// every bottom edge of a box (a row drawn with `─` that holds ` · `).
fn hints(rows: &[String]) -> Vec<(String, String)> {
    let mut found = Vec::new();
    let last = rows.len().saturating_sub(1);
    for (i, row) in rows.iter().enumerate() {
        let edge = row.contains('─') && row.contains(" · ");
        if i != last && !edge {
            continue;
        }
        let text: String = row
            .chars()
            .map(|c| {
                if "─│┌┐└┘╭╮╰╯┤├".contains(c) {
                    ' '
                } else {
                    c
                }
            })
            .collect();
        for segment in text.split(" · ").flat_map(|s| s.split("  ")) {
            let segment = segment.trim();
            let Some((keys, word)) = segment.split_once(' ') else {
                continue;
            };
            // A search prompt shows what is typed (`/seq▏`): not a hint.
            if keys.contains('▏') || word.is_empty() {
                continue;
            }
            if keys_of(keys).is_some() {
                found.push((keys.to_string(), word.trim().to_string()));
            }
        }
    }
    found
}

fn screen(s: &AppState) -> Vec<String> {
    let (w, h) = (100u16, 30u16);
    let mut term = Terminal::new(TestBackend::new(w, h)).expect("test backend");
    term.draw(|f| droidctl::ui::draw(f, s)).expect("draw");
    let buf = term.backend().buffer();
    (0..h)
        .map(|y| (0..w).map(|x| buf[(x, y)].symbol()).collect())
        .collect()
}

fn outcome(steps: &[Step]) -> Outcome {
    run_with(droidctl::config::Config::defaults(), EMULATED, steps, false).expect("the app ran")
}

/// What the screen shows that a key can change (not the clock).
fn looks(s: &AppState) -> String {
    let d = s.droid();
    format!(
        "{:?} {:?} {:?} {} {} {:?} {} {} {} {:?} {:?} {:?} {} {:?}",
        s.overlay,
        s.focus,
        s.log.filter,
        s.log.scroll,
        s.log.cursor,
        (s.log.paused, s.log.decoded),
        s.help_page,
        s.chosen,
        s.mirror,
        d.scope,
        d.control.cruise,
        d.control.turbo,
        d.control.estop,
        d.monitor.collision,
    )
}

fn place(s: &AppState) -> Place {
    Place::of(s, false)
}

/// The place, finer: the scope on screen in driving, a search being typed in a packet.
fn whereabouts(s: &AppState) -> (Place, bool, bool) {
    let typing = matches!(
        s.overlay,
        droidctl::app::state::Overlay::Packet { typing: true, .. }
    );
    (place(s), s.droid().scope.visible, typing)
}

/// Each place: how it is reached from driving (R2-D2 first in a fleet with BB-8 and Robi, its
/// log full after the setup), and the place it is in.
fn places() -> Vec<(&'static str, Vec<Step>, Place)> {
    let k = Key::ch;
    let enter = Key::plain(KeyCode::Enter);
    vec![
        ("packet log", vec![tap(k('l')), pause()], Place::Log),
        (
            "filter prompt",
            vec![tap(k('l')), pause(), tap(k('/')), pause()],
            Place::Filter,
        ),
        (
            "packet in full",
            vec![tap(k('l')), pause(), tap(enter), pause()],
            Place::Packet,
        ),
        (
            "packet search",
            vec![
                tap(k('l')),
                pause(),
                tap(enter),
                pause(),
                tap(k('/')),
                pause(),
            ],
            Place::Packet,
        ),
        // On its second page, so that both page keys have somewhere to go.
        (
            "help",
            vec![
                tap(k('?')),
                pause(),
                tap(Key::plain(KeyCode::PageDown)),
                pause(),
            ],
            Place::Help,
        ),
        ("animations", vec![tap(k('n')), pause()], Place::Palette),
        ("scope", vec![tap(k('g')), pause()], Place::Driving),
        (
            "scope channels",
            vec![tap(k('g')), pause(), tap(k('C')), pause()],
            Place::Channels,
        ),
        ("settings", vec![tap(k('u')), pause()], Place::Tuning),
    ]
}

/// Words that say the key leaves the place (or closes what is typed).
const LEAVES: &[&str] = &["close", "back", "apply", "play", "send", "more keys"];

#[test]
fn every_hinted_key_does_what_its_hint_says() {
    let mut checked = 0;
    let mut lies = Vec::new();
    for (name, reach, expected) in places() {
        let at = outcome(&reach);
        let state = at.state.clone().expect("a frame");
        assert_eq!(place(&state), expected, "{name}: reached");
        let shown = hints(&screen(&state));
        assert!(shown.len() >= 2, "{name}: hints {shown:?}");
        for (keys, word) in shown {
            let before = looks(&state);
            let mut changed_any = false;
            for key in keys_of(&keys).expect("parsed") {
                let mut steps = reach.clone();
                steps.push(tap(key));
                steps.push(pause());
                let after = outcome(&steps);
                checked += 1;
                let stopped = after.estops > at.estops;
                let lie = |why: &str| format!("{name}: `{keys} {word}` ({key}): {why}");
                if word == "quit" {
                    if !after.quit {
                        lies.push(lie("did not quit"));
                    }
                    continue;
                }
                let Some(s) = after.state.as_ref() else {
                    lies.push(lie("no frame after it"));
                    continue;
                };
                if word == "stop" {
                    if !stopped {
                        lies.push(lie("did not stop the droid"));
                    }
                    continue;
                }
                if stopped {
                    lies.push(lie("stopped the droid instead"));
                }
                if word == "more keys" && place(s) != Place::Help {
                    lies.push(lie("did not open help"));
                }
                let left = whereabouts(s) != whereabouts(&state);
                if LEAVES.contains(&word.as_str()) && !left {
                    lies.push(lie("stayed"));
                }
                changed_any |= looks(s) != before;
            }
            if word != "stop" && word != "quit" && !changed_any {
                lies.push(format!("{name}: `{keys} {word}` changed nothing"));
            }
        }
    }
    assert!(lies.is_empty(), "hints that lie:\n{}", lies.join("\n"));
    assert!(checked > 30, "{checked} keys checked");
}

#[test]
fn the_key_text_of_hints_is_read_as_the_app_binds_it() {
    assert_eq!(
        keys_of("↑↓"),
        Some(vec![Key::plain(KeyCode::Up), Key::plain(KeyCode::Down)])
    );
    assert_eq!(
        keys_of("x/Enter"),
        Some(vec![Key::ch('x'), Key::plain(KeyCode::Enter)])
    );
    assert_eq!(keys_of("/"), Some(vec![Key::ch('/')]));
    assert_eq!(keys_of("Ctrl+Space"), Some(vec![Key::CTRL_SPACE]));
    assert_eq!(keys_of("other"), None);
    let rows = vec![
        "╰── ↑↓ choose · x/Enter switch · Esc close ──╯".to_string(),
        " Space stop  p pause  ? more keys".to_string(),
    ];
    assert_eq!(
        hints(&rows),
        [
            ("↑↓", "choose"),
            ("x/Enter", "switch"),
            ("Esc", "close"),
            ("Space", "stop"),
            ("p", "pause"),
            ("?", "more keys")
        ]
        .map(|(k, w)| (k.to_string(), w.to_string()))
    );
}
