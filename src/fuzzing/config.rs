//! The configuration file: any text is a configuration or one error naming the file (and its
//! line and key when there is one), never a panic. A configuration that loads is one the app
//! runs with: every button it names exists, and the app drives a simulated droid through a
//! session with its timing: the stick drives it within 8 s (the connect setup and R2's stance
//! may come first), letting go stops it within 2 s;
//! every key it binds and every gamepad button pressed; then it quits with the droid
//! stopped.
//!
//! Input layout: the whole input is the file (read as UTF-8, lossily).

use super::Target;
use crate::app::input::{KeyKind, TermEvent};
use crate::app::run::{self, AppInputs, AppOptions, ExitReason};
use crate::config::Config;
use crate::config::{Action, Context, Key, PadAction};
use crate::model::Model;
use crate::session::{Direction, LogEntry, LogItem};
use crate::sim::{Faults, SimConfig, SimLink};
use crate::teleop::gamepad::{Axis, Button, PadEvent};
use crate::teleop::held::ReleaseMode;
use std::path::Path;
use std::time::Duration;
use tokio::sync::{broadcast, mpsc};
use tokio::time::sleep;

pub const TARGET: Target = Target {
    name: "config",
    run: run_input,
    dictionary: &[
        b"[control]\n",
        b"[keyboard]\n",
        b"[session]\n",
        b"[keys]\n",
        b"[gamepad]\n",
        b"rate_hz = ",
        b"request_timeout_ms = ",
        b"pacing_ms = ",
        b"release_first_ms = ",
        b"turn_rate_deg_s = ",
        b"deadzone = ",
        b"expo = ",
        b"streaming_interval_ms = ",
        b"aim = \"",
        b"estop = [\"Space\"]\n",
        b"forward = [\"",
        b"Ctrl+",
        b"\"]\n",
        b"mode = \"latched\"\n",
        b"nan",
        b"inf",
        b"18446744073709551615",
    ],
};

const PATH: &str = "/home/u/.config/droidctl/config.toml";

pub fn run_input(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let path = Path::new(PATH);
    let config = match Config::parse_merged(Some(path), &text) {
        Ok(c) => c,
        Err(e) => {
            assert_eq!(e.path.as_deref(), Some(path));
            assert!(!e.message.is_empty());
            let shown = e.to_string();
            assert!(shown.starts_with(PATH), "{shown}");
            if let Some(line) = e.line {
                assert!(line >= 1 && line <= text.lines().count() + 1, "{shown}");
            }
            return;
        }
    };
    let g = &config.gamepad;
    for a in PadAction::ALL {
        let b = g.buttons.button(a);
        assert!(
            Button::BINDABLE.contains(&b) && g.buttons.action(b) == Some(a),
            "gamepad.{} was accepted but its button {b} does not do it",
            a.config_name()
        );
    }
    let model = [Model::R2D2, Model::BB8, Model::Robi42][text.len() % 3];
    drive(config, model);
}

/// The app on a simulated droid with `config`, in paused time: every bound key pressed and
/// released, every button, the sticks; then quit. The last drive written is a stop.
fn drive(config: Config, model: Model) {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .expect("a runtime");
    rt.block_on(async move {
        let link = SimLink::new(model, SimConfig::for_model(model), Faults::none());
        let session = crate::session::start(
            Box::new(link),
            crate::cli::fleet::session_config(model, &config, true),
        );
        let family = crate::family::for_model(model);
        let mut log = session.subscribe_log();
        // The driving table's keys, as the app reads them.
        let keys: Vec<Key> = Action::ALL
            .iter()
            .filter(|a| a.context() == Context::Drive)
            .flat_map(|a| config.keymap.keys(*a).to_vec())
            .collect();
        let k = &config.keyboard;
        let max_speed = config.gamepad.max_speed;
        let opts = AppOptions {
            release: ReleaseMode::Emulated {
                first: Duration::from_millis(k.release_first_ms),
                repeat: Duration::from_millis(k.release_repeat_ms),
            },
            config,
            model,
            droid_name: "fuzz".into(),
            log_path: None,
            tripod_on_connect: true,
            samples: None,
            remember: None,
        };
        let (term, term_rx) = mpsc::channel(64);
        let (pad, pad_rx) = mpsc::channel(64);
        let (quit, quit_rx) = mpsc::channel(4);
        let app_session = session.clone();
        let app = tokio::spawn(async move {
            let backend = ratatui::backend::TestBackend::new(80, 24);
            let mut terminal = ratatui::Terminal::new(backend).expect("a test terminal");
            let inputs = AppInputs {
                term: term_rx,
                pad: pad_rx,
                quit: quit_rx,
            };
            run::run(&mut terminal, app_session, opts, inputs, crate::ui::draw).await
        });
        // Connected and standing (R2's stance takes about 2 s): the stick drives, letting go
        // stops, whatever the configuration.
        sleep(Duration::from_secs(3)).await;
        let _ = last_drive(&mut log, family);
        let stick = |v: f32| PadEvent::Axis(Axis::LeftY, v);
        // Forward (gilrs: up is +1).
        for e in [PadEvent::Connected("pad".into()), stick(1.0)] {
            pad.send(e).await.expect("the app reads the pad");
        }
        // The drive may wait for the connect setup and R2's stance (at the slowest pacing a
        // second per write), not longer.
        if max_speed > 0 {
            let mut driven = false;
            for _ in 0..80 {
                sleep(Duration::from_millis(100)).await;
                if last_drive(&mut log, family).is_some_and(|c| !c.is_stop()) {
                    driven = true;
                    break;
                }
            }
            assert!(driven, "8 s after the stick went forward nothing drove");
        }
        pad.send(stick(0.0)).await.expect("the app reads the pad");
        sleep(Duration::from_secs(2)).await;
        if let Some(cmd) = last_drive(&mut log, family) {
            assert!(
                cmd.is_stop(),
                "2 s after letting go the last drive is {cmd:?}"
            );
        }
        'input: for key in keys {
            for kind in [KeyKind::Press, KeyKind::Release] {
                if term.send(TermEvent::Key { key, kind }).await.is_err() {
                    break 'input;
                }
                sleep(Duration::from_millis(30)).await;
            }
        }
        let buttons: Vec<Button> = Button::BINDABLE
            .into_iter()
            .chain([Button::DPadUp])
            .collect();
        let mut events = Vec::new();
        for b in buttons {
            events.extend([PadEvent::Pressed(b), PadEvent::Released(b)]);
        }
        events.extend([
            PadEvent::Axis(Axis::LeftY, 1.0),
            PadEvent::Axis(Axis::RightTrigger, 1.0),
            PadEvent::Axis(Axis::RightX, 0.5),
            PadEvent::Axis(Axis::LeftX, 0.7),
        ]);
        // Then the operator lets go of everything.
        events.extend([
            PadEvent::Axis(Axis::LeftY, 0.0),
            PadEvent::Axis(Axis::LeftX, 0.0),
            PadEvent::Axis(Axis::RightX, 0.0),
            PadEvent::Axis(Axis::RightTrigger, 0.0),
        ]);
        let mut running = true;
        for e in events {
            if pad.send(e).await.is_err() {
                running = false;
                break;
            }
            sleep(Duration::from_millis(30)).await;
        }
        if running {
            // Whatever the configuration, letting go stops the droid within 2 s.
            sleep(Duration::from_secs(2)).await;
            if let Some(cmd) = last_drive(&mut log, family) {
                assert!(
                    cmd.is_stop(),
                    "2 s after letting go the last drive is {cmd:?}"
                );
            }
        }
        let _ = quit.send("fuzz".into()).await;
        let exit = app
            .await
            .expect("the app does not panic")
            .expect("a test terminal does not fail");
        assert!(
            matches!(exit.reason, ExitReason::Signal(_) | ExitReason::Quit),
            "{:?}",
            exit.reason
        );
        assert!(exit.stop.is_stop());
        let stop = run::exit_commands(model, Some(exit.stop.clone()), false);
        tokio::time::timeout(Duration::from_secs(5), session.shutdown_stopped(stop))
            .await
            .expect("the session ends within its budget");
        // The last drive command written is a stop.
        if let Some(cmd) = last_drive(&mut log, family) {
            assert!(cmd.is_stop(), "the last drive written is {cmd:?}");
        }
    });
}

/// The last drive command the session wrote since the log was last read.
fn last_drive(
    log: &mut broadcast::Receiver<LogEntry>,
    family: &dyn crate::family::Family,
) -> Option<crate::family::Command> {
    let mut last = None;
    loop {
        let (dir, item) = match log.try_recv() {
            Ok(LogEntry { dir, item, .. }) => (dir, item),
            Err(broadcast::error::TryRecvError::Lagged(_)) => continue,
            Err(_) => return last,
        };
        if let (Direction::Out, LogItem::Packet { packet, .. }) = (dir, item)
            && let Some((cmd, _, _)) = packet.as_command()
            && family.is_drive(&cmd)
        {
            last = Some(cmd);
        }
    }
}
