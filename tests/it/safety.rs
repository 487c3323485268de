//! The safety promises of the app's input routing, each as the sequence that broke it (issue
//! 26) and then over random sequences: nothing drives unless a drive key is held in the
//! driving place, the heading changes only while a turn key is held there, and every
//! emergency stop reaches every droid at once. The harness is `droidctl::fuzzing::app_input`
//! (also a fuzz target): a fleet of simulated droids through the whole event loop on paused
//! time, checked against an oracle that reads only the events and the place each one left
//! the app in.

use droidctl::config::{Button, Key, KeyCode};
use droidctl::fuzzing::app_input::{
    AXES, BUTTONS, EMULATED, KEYS, Step, check, decode_with_pad, run, run_with,
};
use droidctl::teleop::gamepad::Axis;
use droidctl::teleop::held::ReleaseMode;
use proptest::prelude::*;
use std::time::Duration;

const UP: Key = Key::plain(KeyCode::Up);
const DOWN: Key = Key::plain(KeyCode::Down);
const RIGHT: Key = Key::plain(KeyCode::Right);
const ESC: Key = Key::plain(KeyCode::Esc);
const ENTER: Key = Key::plain(KeyCode::Enter);
const TAB: Key = Key::plain(KeyCode::Tab);
const SPACE: Key = Key::plain(KeyCode::Space);

fn ms(n: u64) -> Step {
    Step::Pause(Duration::from_millis(n))
}

fn tap(k: Key) -> Step {
    Step::Press(k)
}

fn holds(release: ReleaseMode, steps: &[Step]) {
    if let Err(e) = check(release, steps) {
        panic!("{e}\nsteps: {steps:?}");
    }
}

/// Issue 26, item 1: an arrow typed inside an overlay does not drive once it closes
/// (emulated release: the arrow would count as held for the first-release timeout).
#[test]
fn keys_typed_in_an_overlay_never_drive_when_it_closes() {
    let k = Key::ch;
    let cases: Vec<Vec<Step>> = vec![
        // `?`, `↓`, `Esc`: help, a page down, closed.
        vec![tap(k('?')), ms(50), tap(DOWN), ms(100), tap(ESC), ms(1000)],
        // `g`, `C`, `↑`, `Esc`, `g`: the scope's channel list, up, closed, scope off.
        vec![
            tap(k('g')),
            ms(50),
            tap(k('C')),
            ms(50),
            tap(UP),
            ms(50),
            tap(ESC),
            ms(50),
            tap(k('g')),
            ms(1000),
        ],
        // `u`, `→`, `Enter`: the settings palette, a value up, applied.
        vec![
            tap(k('u')),
            ms(50),
            tap(RIGHT),
            ms(50),
            tap(ENTER),
            ms(1000),
        ],
        // `n`, `↓`, `Esc` and `l`, `↑`, `Esc`.
        vec![tap(k('n')), ms(50), tap(DOWN), ms(50), tap(ESC), ms(1000)],
        vec![tap(k('l')), ms(50), tap(UP), ms(50), tap(ESC), ms(1000)],
    ];
    for steps in &cases {
        holds(EMULATED, steps);
        holds(ReleaseMode::Reported, steps);
    }
}

/// With reported releases, a key pressed in an overlay keeps repeating after it closes:
/// the repeats must not drive.
#[test]
fn repeats_of_a_key_pressed_elsewhere_never_drive() {
    let mut steps = vec![tap(Key::ch('?')), ms(20), tap(UP), ms(20), tap(ESC)];
    for _ in 0..20 {
        steps.push(ms(30));
        steps.push(Step::Repeat(UP));
    }
    steps.push(Step::Release(UP));
    holds(ReleaseMode::Reported, &steps);
}

/// Issue 26, item 2: the emergency stop is written to every droid, idle ones too, at once.
#[test]
fn the_emergency_stop_reaches_every_droid_idle_or_not() {
    // R2-D2 chosen and rolling, the others idle; then BB-8 chosen and Space.
    holds(
        ReleaseMode::Reported,
        &[
            tap(UP),
            ms(500),
            tap(SPACE),
            ms(100),
            Step::Release(SPACE),
            Step::Release(UP),
            ms(100),
            tap(TAB),
            ms(100),
            tap(SPACE),
            ms(200),
        ],
    );
    // From the packet log, the help overlay, a palette, the settings and the scope's
    // channel list too: Space is the emergency stop there (the lists switch a row with `x`),
    // and it is one.
    let places: [&[Step]; 5] = [
        &[tap(Key::ch('l'))],
        &[tap(Key::ch('?'))],
        &[tap(Key::ch('n'))],
        &[tap(Key::ch('u'))],
        &[tap(Key::ch('g')), ms(50), tap(Key::ch('C'))],
    ];
    for open in places {
        assert_eq!(
            estops_after(open, SPACE),
            1,
            "Space over {open:?} is the emergency stop"
        );
    }
}

/// The emergency stops made when `key` is tapped in the place `open` leads to.
fn estops_after(open: &[Step], key: Key) -> usize {
    let mut steps = open.to_vec();
    steps.extend([ms(50), tap(key), ms(300)]);
    run(EMULATED, &steps)
        .unwrap_or_else(|e| panic!("{e}\nsteps: {steps:?}"))
        .estops
}

/// Issue 39, item 1: in a text prompt Space is typed, so Ctrl+Space (a terminal's NUL) is the
/// stop there, and in every other place too.
#[test]
fn ctrl_space_stops_in_every_place_prompts_included() {
    const CTRL_SPACE: Key = Key::CTRL_SPACE;
    // The log's filter prompt and the packet detail's search prompt (BOLT's matrix text is
    // the filter's place, Place::Matrix, read with the same table).
    let prompts: [&[Step]; 2] = [
        &[tap(Key::ch('l')), ms(50), tap(Key::ch('/'))],
        &[
            tap(Key::ch('l')),
            ms(50),
            tap(ENTER),
            ms(50),
            tap(Key::ch('/')),
        ],
    ];
    for open in prompts {
        // Space is text there: no stop.
        assert_eq!(estops_after(open, SPACE), 0, "Space is typed in {open:?}");
        assert_eq!(
            estops_after(open, CTRL_SPACE),
            1,
            "Ctrl+Space in {open:?} is the emergency stop"
        );
    }
    let places: [&[Step]; 6] = [
        &[],
        &[tap(Key::ch('l'))],
        &[tap(Key::ch('?'))],
        &[tap(Key::ch('n'))],
        &[tap(Key::ch('u'))],
        &[tap(Key::ch('g')), ms(50), tap(Key::ch('C'))],
    ];
    for open in places {
        assert_eq!(
            estops_after(open, CTRL_SPACE),
            1,
            "Ctrl+Space over {open:?} is the emergency stop"
        );
    }
}

/// Quick double taps of toggles count twice in every place (none is mistaken for a held
/// drive key): turbo on and off again; a filter typed with `d`, then `d` in the log.
#[test]
fn double_taps_count_twice() {
    let out = run(
        EMULATED,
        &[
            tap(Key::ch('t')),
            ms(100),
            tap(Key::ch('t')),
            ms(100),
            tap(UP),
            ms(300),
        ],
    )
    .unwrap();
    let state = out.state.expect("a frame was drawn");
    assert!(!state.droid().control.turbo, "t t leaves turbo off");
    let cruise = droidctl::config::Config::defaults().control.cruise_speed;
    assert_eq!(
        out.speeds[0].iter().max(),
        Some(&cruise),
        "{:?}",
        out.speeds[0]
    );

    let out = run(
        EMULATED,
        &[
            tap(Key::ch('l')),
            ms(50),
            tap(Key::ch('/')),
            tap(Key::ch('d')),
            tap(ENTER),
            ms(100),
            tap(Key::ch('d')),
            ms(1000),
        ],
    )
    .unwrap();
    let log = out.state.expect("a frame was drawn").log;
    assert!(
        !log.decoded,
        "d after typing a filter with d toggles the decoded view"
    );
    let out = run(
        EMULATED,
        &[
            tap(Key::ch('l')),
            tap(Key::ch('d')),
            ms(100),
            tap(Key::ch('d')),
            ms(1000),
        ],
    )
    .unwrap();
    assert!(out.state.expect("a frame").log.decoded, "d d toggles twice");
}

/// Issue 26, item 4: `Esc` on the main screen does not quit; it says how to.
#[test]
fn esc_on_the_main_screen_does_not_quit() {
    let out = run(
        EMULATED,
        &[
            tap(Key::ch('?')),
            ms(50),
            tap(ESC),
            ms(50),
            tap(ESC),
            ms(100),
            tap(ESC),
            ms(100),
        ],
    )
    .unwrap();
    assert!(!out.quit, "Esc ended the session");
    let state = out.state.expect("a frame was drawn");
    let hint = state.current_hint().unwrap_or_default().to_string();
    assert!(hint.contains("q") && hint.contains("quits"), "{hint}");
    let out = run(EMULATED, &[tap(Key::ch('q')), ms(100)]).unwrap();
    assert!(out.quit, "q quits");
}

/// Latched drive mode keeps its speed after `↑` is let go, by design; but opening a place,
/// choosing another droid or losing focus drops it: the next write is a stop.
#[test]
fn a_latched_speed_is_dropped_when_the_place_changes() {
    let config = droidctl::config::Config::parse_merged(None, "[control]\nmode = \"latched\"\n")
        .expect("a latched configuration");
    for leave in [
        tap(Key::ch('?')),
        tap(Key::ch('l')),
        Step::FocusLost,
        tap(TAB),
    ] {
        let steps = [tap(UP), ms(50), tap(UP), ms(800), leave, ms(1000)];
        let out = run_with(config.clone(), EMULATED, &steps, false).unwrap();
        let r2 = &out.drives[0];
        assert!(r2.iter().any(|(_, s)| *s > 0), "latched ↑ drives: {r2:?}");
        let left = out.steps_at[4];
        let after: Vec<_> = r2.iter().filter(|(t, _)| *t >= left).collect();
        assert!(
            !after.is_empty() && after.iter().all(|(_, s)| *s == 0),
            "{leave:?} stops it at once: {r2:?}"
        );
    }
}

const STICK_UP: Step = Step::Stick(Axis::LeftY, 80);
const CENTRED: Step = Step::Stick(Axis::LeftY, 0);

/// R2-D2's drive writes from step `from` (inclusive) to step `to` (exclusive, or the end).
fn r2_between(
    out: &droidctl::fuzzing::app_input::Outcome,
    from: usize,
    to: Option<usize>,
) -> Vec<u8> {
    let a = out.steps_at[from];
    let b = to.map(|i| out.steps_at[i]);
    out.drives[0]
        .iter()
        .filter(|(t, _)| *t >= a && b.is_none_or(|b| *t < b))
        .map(|(_, s)| *s)
        .collect()
}

/// Issue 39's gamepad in the promises: the stick is a deadman of the driving place. It
/// drives while out of its deadzone; centred, the pad lost, or another place on top (the
/// pad's help button) writes a stop at once; a pad plugged in again moves nothing until the
/// stick does.
#[test]
fn the_stick_drives_only_in_driving_and_stops_when_centred_lost_or_covered() {
    let steps = [
        Step::PadFound,
        STICK_UP, // 1
        ms(500),
        CENTRED, // 3
        ms(300),
        STICK_UP, // 5
        ms(300),
        Step::PadLost, // 7
        ms(500),
        Step::PadFound, // 9
        ms(500),
        STICK_UP, // 11
        ms(300),
        Step::PadPress(Button::Select), // 13: help
        Step::PadRelease(Button::Select),
        ms(500),
        Step::Stick(Axis::LeftX, 50), // 16: moved in help
        ms(300),
    ];
    for release in [ReleaseMode::Reported, EMULATED] {
        holds(release, &steps);
    }
    let out = run(ReleaseMode::Reported, &steps).unwrap();
    let drives = |from, to| r2_between(&out, from, to);
    let moving = |w: &[u8]| w.iter().any(|s| *s > 0);
    let stopped = |w: &[u8]| !w.is_empty() && w.iter().all(|s| *s == 0);
    assert!(
        moving(&drives(1, Some(3))),
        "the stick up drives: {:?}",
        out.drives[0]
    );
    assert!(
        stopped(&drives(3, Some(5))),
        "centred stops: {:?}",
        out.drives[0]
    );
    assert!(moving(&drives(5, Some(7))), "{:?}", out.drives[0]);
    assert!(
        stopped(&drives(7, Some(11))),
        "lost, found: still: {:?}",
        out.drives[0]
    );
    assert!(moving(&drives(11, Some(13))), "{:?}", out.drives[0]);
    assert!(
        stopped(&drives(13, None)),
        "help on top: still: {:?}",
        out.drives[0]
    );
    // The stop is written at the instant: centred, lost, covered.
    for i in [3, 7, 13] {
        let at = out.steps_at[i];
        assert!(
            out.drives[0].iter().any(|(t, s)| *t == at && *s == 0),
            "no stop at step {i}: {:?}",
            out.drives[0]
        );
    }
}

/// Found by the mixed property: a stick value reported while no pad was connected (or before
/// another pad was plugged in) drove at once when one was; now a pad plugged in has its sticks
/// at rest until they move, and the stick that drove stops at the plug-in.
#[test]
fn a_stick_value_from_before_a_plug_in_never_drives() {
    let lost_then_found = [
        Step::PadFound,
        Step::PadLost,
        Step::Stick(Axis::LeftY, 100),
        Step::PadFound, // 3
        ms(1000),
    ];
    let another_found = [
        Step::PadFound,
        Step::Stick(Axis::LeftY, 100),
        ms(500),
        Step::PadFound, // 3
        ms(1000),
    ];
    for steps in [&lost_then_found[..], &another_found[..]] {
        holds(ReleaseMode::Reported, steps);
        let out = run(ReleaseMode::Reported, steps).unwrap();
        let after = r2_between(&out, 3, None);
        assert!(
            !after.is_empty() && after.iter().all(|s| *s == 0),
            "{steps:?}: R2 drove after the plug-in: {:?}",
            out.drives[0]
        );
    }
    let out = run(ReleaseMode::Reported, &another_found).unwrap();
    assert!(r2_between(&out, 1, Some(3)).iter().any(|s| *s > 0));
}

/// The pad's stop button: an emergency stop to every droid at once from any place (the
/// property checks the instant), and every droid held at 0 while it is held, the stick up
/// or not.
#[test]
fn the_pad_stop_button_reaches_every_droid_and_holds_them() {
    let east = Button::East;
    let steps = [
        Step::PadFound,
        STICK_UP,
        ms(300),
        Step::PadPress(east), // 3
        ms(1000),
        Step::PadRelease(east), // 5
        ms(300),
        Step::PadPress(Button::Select),
        Step::PadPress(east), // 8: over the help
        ms(300),
    ];
    holds(ReleaseMode::Reported, &steps);
    let out = run(ReleaseMode::Reported, &steps).unwrap();
    assert_eq!(out.estops, 2, "a stop from driving and from the help");
    let held = r2_between(&out, 3, Some(5));
    assert!(
        !held.is_empty() && held.iter().all(|s| *s == 0),
        "{:?}",
        out.drives[0]
    );
    for (i, d) in out.drives.iter().enumerate() {
        for step in [3, 8] {
            let at = out.steps_at[step];
            assert!(
                d.iter().any(|(t, s)| *t == at && *s == 0),
                "droid {i} got no stop at step {step}: {d:?}"
            );
        }
    }
}

/// The pad's steps came in with their own bit in the input's first byte: with it, a step
/// whose kind byte has bit 3 clear reads as it did before the pad, so the keyboard's corpus
/// means what it meant; with bit 3, each kind is a pad step.
#[test]
fn the_pad_layout_leaves_the_keyboard_steps_as_they_were() {
    for kind in 0..=255u8 {
        for arg in [0u8, 1, 7, 8, 13, 100, 156, 255] {
            let pair = [kind, arg];
            let with_pad = decode_with_pad(&pair);
            if kind & 8 == 0 {
                assert_eq!(with_pad, droidctl::fuzzing::app_input::decode(&pair));
            } else {
                assert!(
                    matches!(
                        with_pad[0],
                        Step::Stick(..)
                            | Step::PadPress(_)
                            | Step::PadRelease(_)
                            | Step::PadFound
                            | Step::PadLost
                    ),
                    "{pair:?} → {with_pad:?}"
                );
            }
        }
    }
    assert_eq!(
        decode_with_pad(&[0x09, 0x9c, 0x08, 0x64, 0x0c, 0x01, 0x0e, 0x00, 0x0f, 0x00]),
        vec![
            Step::Stick(Axis::LeftY, -100),
            Step::Stick(Axis::LeftX, 100),
            Step::PadPress(Button::East),
            Step::PadFound,
            Step::PadLost,
        ]
    );
}

fn step() -> impl Strategy<Value = Step> {
    let key = (0..KEYS.len()).prop_map(|i| KEYS[i]);
    prop_oneof![
        4 => key.clone().prop_map(Step::Press),
        1 => key.clone().prop_map(Step::Repeat),
        3 => key.prop_map(Step::Release),
        3 => (0u64..800).prop_map(|n| Step::Pause(Duration::from_millis(n))),
        1 => Just(Step::FocusLost),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// The promises over random sequences of presses, repeats, releases, focus loss and
    /// pauses across every place, in both keyboard modes.
    #[test]
    fn nothing_moves_unless_a_drive_key_is_held_in_driving(
        emulated in any::<bool>(),
        steps in prop::collection::vec(step(), 1..60),
    ) {
        let release = if emulated { EMULATED } else { ReleaseMode::Reported };
        if let Err(e) = check(release, &steps) {
            return Err(TestCaseError::fail(e));
        }
    }
}

/// A pad step: a stick or the trigger moved (often centred, often inside the deadzone), a
/// button pressed or released, the pad plugged in or lost.
fn pad_step() -> impl Strategy<Value = Step> {
    let axis = (0..AXES.len()).prop_map(|i| AXES[i]);
    let value = prop_oneof![Just(0i8), -14i8..=14, -100i8..=100, Just(100), Just(-100)];
    let button = (0..BUTTONS.len()).prop_map(|i| BUTTONS[i]);
    prop_oneof![
        6 => (axis, value).prop_map(|(a, v)| Step::Stick(a, v)),
        3 => button.clone().prop_map(Step::PadPress),
        3 => button.prop_map(Step::PadRelease),
        1 => Just(Step::PadFound),
        1 => Just(Step::PadLost),
    ]
}

/// The number of cases of the mixed property: `DROIDCTL_SAFETY_CASES` for a longer search.
fn mixed_cases() -> u32 {
    std::env::var("DROIDCTL_SAFETY_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(48)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: mixed_cases(), ..ProptestConfig::default() })]

    /// The same promises with the gamepad in the sequences: keys and pad events mixed, the
    /// pad plugged in first (and lost and found again at random).
    #[test]
    fn nothing_moves_unless_a_drive_key_or_the_stick_is_held_in_driving(
        emulated in any::<bool>(),
        steps in prop::collection::vec(prop_oneof![step(), pad_step()], 1..60),
    ) {
        let release = if emulated { EMULATED } else { ReleaseMode::Reported };
        let steps: Vec<Step> = std::iter::once(Step::PadFound).chain(steps).collect();
        if let Err(e) = check(release, &steps) {
            return Err(TestCaseError::fail(e));
        }
    }
}
