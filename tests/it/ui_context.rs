//! Issue 30: the context footer and contextual help (point 1), from the one key table. The
//! footer shows the few keys that matter in the place on top and for the chosen droid, then
//! `?` for the rest; help lists only what applies to the chosen droid.

use droidctl::app::state::{AppState, Focus, Overlay};
use droidctl::model::Model;
use ratatui::Terminal;
use ratatui::backend::TestBackend;

fn state(models: &[Model]) -> AppState {
    let droids = models
        .iter()
        .enumerate()
        .map(|(i, m)| droidctl::app::state::DroidState::new(*m, format!("D-{i}")))
        .collect();
    let mut s = AppState::for_droids(droids);
    let config = droidctl::config::Config::defaults();
    s.help = droidctl::app::help::live(&config);
    s.help_nav = droidctl::app::help::nav(&config.keymap, true);
    s.footer = droidctl::app::help::footer(&config.keymap, true);
    s
}

fn screen(s: &AppState, w: u16, h: u16) -> Vec<String> {
    let mut term = Terminal::new(TestBackend::new(w, h)).expect("test backend");
    term.draw(|f| droidctl::ui::draw(f, s)).expect("draw");
    let buf = term.backend().buffer();
    (0..h)
        .map(|y| (0..w).map(|x| buf[(x, y)].symbol()).collect())
        .collect()
}

fn footer(s: &AppState) -> String {
    screen(s, 80, 24).pop().expect("a bottom row")
}

#[test]
fn the_footer_follows_the_place_and_the_droid() {
    let r2 = state(&[Model::R2D2]);
    let f = footer(&r2);
    assert!(f.contains("Space stop") && f.contains("1 tripod"), "{f}");
    assert!(f.contains("? more keys") && f.contains("q quit"), "{f}");
    assert!(!f.contains("matrix") && !f.contains("tank"), "{f}");
    let f = footer(&state(&[Model::Bolt]));
    assert!(f.contains("i matrix") && !f.contains("tripod"), "{f}");
    let f = footer(&state(&[Model::Rvr]));
    assert!(f.contains("v tank") && !f.contains("matrix"), "{f}");
    let f = footer(&state(&[Model::Robi42]));
    assert!(!f.contains("turbo") && f.contains("l log"), "{f}");
    let f = footer(&state(&[Model::R2D2, Model::BB8]));
    assert!(
        f.contains("Tab next droid") && f.contains("y mirror"),
        "{f}"
    );
    // Each place its own keys.
    let mut log = r2.clone();
    log.focus = Focus::Log;
    let f = footer(&log);
    assert!(f.contains("p pause") && f.contains("Esc back"), "{f}");
    // Every footer shows the stop (issue 39, item 1): Space is the stop in the log too.
    assert!(f.starts_with(" Space stop"), "{f}");
    let mut scope = r2.clone();
    scope.droid_mut().scope.visible = true;
    let f = footer(&scope);
    assert!(f.contains("C channels") && f.contains("g close"), "{f}");
    let mut tuning = r2.clone();
    tuning.overlay = Overlay::Channels { selected: 0 };
    let f = footer(&tuning);
    // The channel list's Enter switches the row (issue 39 point 3): no "apply" there.
    assert!(f.contains("x on/off") && f.contains("Esc close"), "{f}");
    assert!(!f.contains("apply"), "{f}");
    assert!(f.starts_with(" Space stop"), "{f}");
    // In a text prompt Space is typed: the footer names the stop that works there.
    let mut prompt = r2.clone();
    prompt.overlay = Overlay::Filter {
        input: String::new(),
        before: Default::default(),
    };
    let f = footer(&prompt);
    assert!(f.starts_with(" Ctrl+Space stop"), "{f}");
    assert!(f.contains("Esc cancel"), "{f}");
    let mut help = r2.clone();
    help.overlay = Overlay::Help;
    let f = footer(&help);
    assert!(f.contains("Space stop"), "{f}");
}

#[test]
fn the_footer_never_cuts_an_entry_and_keeps_help() {
    let s = state(&[Model::R2D2, Model::BB8]);
    for w in [60u16, 70, 80, 100, 200] {
        let rows = screen(&s, w, 24);
        let f = rows.last().expect("bottom row");
        assert!(f.contains("? more keys"), "{w}: {f}");
        assert!(!f.contains('…'), "{w}: {f}");
    }
}

#[test]
fn help_lists_what_applies_to_the_chosen_droid() {
    let all = |s: &AppState| -> String {
        let mut s = s.clone();
        s.overlay = Overlay::Help;
        let mut text = String::new();
        for page in 0..8 {
            s.help_page = page;
            text.push_str(&screen(&s, 80, 24).join("\n"));
        }
        text
    };
    let r2 = all(&state(&[Model::R2D2]));
    assert!(
        r2.contains("dome left") && r2.contains("stance: bipod"),
        "{r2}"
    );
    for absent in ["matrix", "tank mode", "fleet:", "calibrate", "aim mode"] {
        assert!(!r2.contains(absent), "R2's help lists {absent}");
    }
    let bolt = all(&state(&[Model::Bolt]));
    assert!(bolt.contains("type on the matrix") && !bolt.contains("dome left"));
    let fleet = all(&state(&[Model::R2D2, Model::Rvr]));
    assert!(fleet.contains("fleet: drive the next droid"), "{fleet}");
}

fn fleet4() -> AppState {
    let mut s = state(&[Model::R2D2, Model::BB8, Model::Bolt, Model::Rvr]);
    for (i, d) in s.droids.iter_mut().enumerate() {
        d.droid_name = format!("A-rather-long-droid-name-{i}");
        d.link = droidctl::session::LinkState::Connected;
    }
    s
}

/// Issue 30 point 5: the roster cuts names the same way every frame, and each entry starts
/// at the same column whatever its state or rates say.
#[test]
fn the_roster_does_not_jitter() {
    let mut a = fleet4();
    a.mirror = true;
    let mut b = a.clone();
    b.droids[0].control.speed = 120;
    b.droids[0].rate_in = 123.4;
    b.droids[1].link = droidctl::session::LinkState::Connecting;
    b.droids[2].telemetry.battery_v = Some(3.9);
    for w in [80u16, 120, 200] {
        let ra = screen(&a, w, 24).remove(0);
        let rb = screen(&b, w, 24).remove(0);
        for i in 2..=4 {
            let at = |r: &str| r.find(&format!("»{i}")).map(|x| r[..x].chars().count());
            assert!(at(&ra).is_some(), "{ra}");
            assert_eq!(at(&ra), at(&rb), "entry {i} moved at {w}:\n{ra}\n{rb}");
        }
        let names = |r: &str| -> Vec<String> {
            r.split_whitespace()
                .filter(|t| t.contains("name-") || t.starts_with('…'))
                .map(String::from)
                .collect()
        };
        assert_eq!(names(&ra).len(), 4, "{ra}");
        assert_eq!(names(&ra), names(&rb), "names cut differently at {w}");
    }
}

/// Issue 30 point 5: the fleet log's header has a droid column over the droids' names.
#[test]
fn the_fleet_log_header_has_a_droid_column() {
    let mut s = fleet4();
    s.log
        .push(droidctl::app::packet_log::LogLine::from_droid_entry(
            &droidctl::session::LogEntry {
                at: std::time::Duration::from_millis(1200),
                dir: droidctl::session::Direction::Out,
                item: droidctl::session::LogItem::packet(
                    droidctl::protocol::v2::cmd::wake().to_packet(7),
                ),
            },
            "D2-0001".into(),
        ));
    let rows = screen(&s, 80, 24);
    let head = rows
        .iter()
        .find(|r| r.contains("time s"))
        .expect("a header");
    let line = rows.iter().find(|r| r.contains("D2-0001")).expect("a line");
    let col = |r: &str, w: &str| r.find(w).map(|x| r[..x].chars().count());
    assert_eq!(col(head, "droid"), col(line, "D2-0001"), "{head}\n{line}");
    assert_eq!(col(head, "name"), col(line, "wake"), "{head}\n{line}");
}

/// Issue 30 point 6: at 80×24 nothing is cut inside a word: the status row keeps the packet
/// rates beside the battery (no errors is what goes), a long hint loses whole words, the
/// settings list shows its whole title and its keys end with "Esc close".
#[test]
fn at_80x24_no_word_is_cut() {
    let mut s = state(&[Model::R2D2]);
    s.droid_mut().droid_name = "R2-D2 (simulated)".into();
    s.droid_mut().link = droidctl::session::LinkState::Connected;
    s.droid_mut().telemetry.battery_v = Some(3.92);
    s.droid_mut().rate_in = 9.8;
    s.droid_mut().rate_out = 10.0;
    let hint = "10/s × 40 B exceeds the BLE budget (20 notifications/s): capped at 10/s — \
                stream fewer sensors";
    s.show_hint(hint, std::time::Duration::from_secs(4));
    let rows = screen(&s, 80, 24);
    assert!(
        rows[0].contains("3.92V") && rows[0].contains("in 9.8/s out 10/s"),
        "{}",
        rows[0]
    );
    let shown = rows[1].trim_start().trim_start_matches("» ");
    let shown = shown.split('…').next().expect("the hint");
    assert!(hint.starts_with(shown.trim_end()), "{}", rows[1]);
    let next = hint[shown.trim_end().len()..].chars().next();
    assert!(
        next.is_none_or(char::is_whitespace),
        "a word cut: {}",
        rows[1]
    );
    s.hint = None;
    s.overlay = Overlay::Tuning {
        selected: 0,
        draft: droidctl::app::view::scope::TuningDraft {
            rate_hz: 10,
            sensors: droidctl::family::stream::all_groups(Model::R2D2),
            collision: Default::default(),
        },
    };
    let rows = screen(&s, 80, 24);
    let all = rows.join("\n");
    assert!(
        all.contains("Streaming and collision · now 10/s, measured - "),
        "{all}"
    );
    assert!(all.contains("Enter apply · Esc close "), "{all}");
    insta::assert_snapshot!("context_tuning_80x24", all);
}

/// Issue 30 point 6: the scope plots channels of different units on their own y axes, and
/// draws no axis title over the data.
#[test]
fn the_scope_gives_each_unit_its_own_axis() {
    use droidctl::telemetry::history::Channel;
    let mut s = state(&[Model::R2D2]);
    s.droid_mut().scope.visible = true;
    s.droid_mut().scope.channels = vec![Channel::Yaw, Channel::Speed];
    let rows = screen(&s, 80, 24);
    let all = rows.join("\n");
    // Two y axes: two plots' vertical axis lines, one time axis with seconds.
    let axes = rows.iter().filter(|r| r.contains('└')).count();
    assert_eq!(axes, 1, "{all}");
    assert!(!all.contains("deg,cm") && all.contains("0 s"), "{all}");
    insta::assert_snapshot!("context_scope_two_units_80x24", all);
}

fn collision_line() -> droidctl::app::packet_log::LogLine {
    use droidctl::protocol::v2::notify::Collision;
    use droidctl::protocol::v2::wire::{AccelRaw, CollisionAxis};
    use droidctl::protocol::v2::{Device, Packet};
    let c = Collision {
        accel: [AccelRaw(5120), AccelRaw(-1230), AccelRaw(300)],
        axis: CollisionAxis { x: true, y: false },
        power: [180, -40, 0],
        speed: 92,
        time_ms: 123_456,
    };
    let sensor = Device::parse("sensor").expect("sensor device");
    droidctl::app::packet_log::LogLine::from_droid_entry(
        &droidctl::session::LogEntry {
            at: std::time::Duration::from_millis(1125),
            dir: droidctl::session::Direction::In,
            item: droidctl::session::LogItem::packet(Packet::notification(
                sensor,
                0x12,
                c.encode(),
            )),
        },
        "D2-0001".into(),
    )
}

/// Issue 30 point 3: a packet in full at 80×24: every field whole (not `accel_x=0.…`), the
/// frame's parts named, the hex, time and droid; a search marks its matches.
#[test]
fn a_packet_in_full_at_80x24() {
    let mut s = state(&[Model::R2D2]);
    let line = collision_line();
    assert!(line.fields.len() >= 6, "{:?}", line.fields);
    s.overlay = Overlay::Packet {
        line: Box::new(line.clone()),
        search: "accel".into(),
        typing: false,
        matched: 1,
        scroll: 0,
    };
    let rows = screen(&s, 80, 24);
    let all = rows.join("\n");
    for (name, value) in &line.fields {
        assert!(all.contains(*name), "{name}\n{all}");
        assert!(
            all.contains(value.as_str()) || value.len() > 60,
            "{value}\n{all}"
        );
    }
    for part in [
        "start", "flags", "device", "command", "seq", "data", "checksum", "end",
    ] {
        let found = droidctl::app::detail::rows(&line)
            .iter()
            .any(|r| r.label == part);
        assert!(found, "no {part}");
    }
    assert!(all.contains("1.125 s") && all.contains("D2-0001"), "{all}");
    assert!(all.contains("match 2/"), "{all}");
    assert!(!all.contains('…'), "nothing cut:\n{all}");
    insta::assert_snapshot!("context_packet_detail_80x24", all);
}

/// Issue 30 point 3: Home (to the oldest line) shows a full page, not one line.
#[test]
fn home_shows_a_full_page() {
    let mut s = state(&[Model::R2D2]);
    for _ in 0..30 {
        s.log.push(collision_line());
    }
    s.log.scroll_up(usize::MAX / 2);
    let page = s.log.visible(7);
    assert_eq!(page.len(), 7);
}

/// Issue 39, item 2: an overlay covers the status bar, so the E-STOP badge is drawn over it
/// while a droid is stopped (and only then).
#[test]
fn the_estop_badge_shows_over_every_overlay() {
    let overlays = [
        Overlay::Help,
        Overlay::Filter {
            input: String::new(),
            before: Default::default(),
        },
        Overlay::Channels { selected: 0 },
        Overlay::Animations { selected: 0 },
    ];
    for overlay in overlays {
        let mut s = state(&[Model::R2D2, Model::BB8]);
        s.overlay = overlay.clone();
        let calm = screen(&s, 80, 24).join("\n");
        assert!(!calm.contains("E-STOP"), "{overlay:?}\n{calm}");
        // The other droid of the fleet is the one stopped: the badge still shows.
        s.droids[1].control.estop = true;
        let stopped = screen(&s, 80, 24);
        assert!(
            stopped[0].trim_end().ends_with("E-STOP"),
            "{overlay:?}\n{}",
            stopped.join("\n")
        );
    }
}

/// Issue 39 point 13 at 120×40: help on one page offers no page keys (in its edge or the
/// footer) and covers the screen's width rather than leaving a sliver of the panels beside
/// it; BB-8's lights panel names its keys whole.
#[test]
fn at_120x40_help_and_the_lights_panel_say_only_what_is_true() {
    let mut s = state(&[Model::BB8]);
    let rows = screen(&s, 120, 40);
    let all = rows.join("\n");
    assert!(all.contains("o aim (heading 0)"), "{all}");
    assert!(!all.contains("cycles the mai"), "{all}");
    s.overlay = Overlay::Help;
    let rows = screen(&s, 120, 40);
    let footer = rows.last().expect("a footer");
    assert!(!footer.contains("PgDn"), "one page, no page keys: {footer}");
    assert!(footer.contains("Space stop"), "{footer}");
    assert!(
        rows.iter().all(|r| !r.contains("PgDn/PgUp pages")),
        "{}",
        rows.join("\n")
    );
    // No panel border shows beside the help box.
    for r in &rows {
        assert!(
            !["││", "│╯", "│╮"].iter().any(|t| r.trim_end().ends_with(t)),
            "{r}"
        );
    }
    // On 80×24 help has pages, and the footer offers their keys.
    let rows = screen(&s, 80, 24);
    assert!(rows.last().is_some_and(|f| f.contains("PgDn")), "{rows:?}");
}

/// Issue 39 point 13, seen again at 120×40: BB-8's lights panel had room for its keys on two
/// lines but cut the last one on the first (`b back li…`); every hint is whole, none cut.
#[test]
fn bb8_lights_panel_names_every_key_whole_at_120x40() {
    let s = state(&[Model::BB8]);
    let rows = screen(&s, 120, 40);
    let all = rows.join("\n");
    let panel: Vec<&String> = rows
        .iter()
        .skip_while(|r| !r.contains("╭ Lights"))
        .take_while(|r| !r.contains("╰"))
        .collect();
    assert!(panel.len() > 2, "{all}");
    let text: String = panel.iter().map(|r| r.as_str()).collect();
    for hint in ["o aim (heading 0)", "c main colour", "b back light"] {
        assert!(text.contains(hint), "{hint:?} whole:\n{all}");
    }
    assert!(!text.contains('…'), "nothing cut:\n{all}");
}
