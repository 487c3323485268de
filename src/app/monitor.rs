//! Monitoring in the app (issue 22 points 1-3): the keys of the scope, opening its channel
//! list and the settings palette (their keys are components: [`super::overlay::channels`],
//! [`super::overlay::tuning`]), and sending the settings. What they change is view state ([`super::view::scope`]: the scope's
//! window and channels, the streaming and collision settings in effect), one per droid in
//! [`AppState`], so it follows the droid shown.
//!
//! Applying the settings sends the family's streaming commands followed by collision
//! detection ([`crate::family::stream::reconfigure`]), and hands the session a new connect
//! setup so a reconnect keeps them.
//!
//! [`AppState`]: super::state::AppState

use super::core::App;
use super::state::Overlay;
use super::view::scope::{TuningDraft, WINDOWS, tuning_rows};
use crate::config::{Action, Context, Key};
use crate::family::setup::{SetupOptions, connect_setup};
use crate::family::stream;
use crate::tuning::StreamRequest;

impl App {
    /// The scope on or off.
    pub fn toggle_scope(&mut self) {
        let s = &mut self.state.droid_mut().scope;
        s.visible = !s.visible;
        self.dirty = true;
    }

    /// A key the scope binds, while it is on screen (the keys it does not bind drive).
    pub fn scope_key(&mut self, key: Key, new_press: bool) {
        let Some(a) = self.keymap.action_in(Context::Scope, &key) else {
            return;
        };
        if !new_press {
            return;
        }
        let now = self.clock();
        let s = &mut self.state.droid_mut().scope;
        match a {
            Action::ScopePause => {
                s.paused_at = match s.paused_at {
                    Some(_) => None,
                    None => Some(now),
                }
            }
            Action::ScopeZoomIn => s.window = s.window.saturating_sub(1),
            Action::ScopeZoomOut => s.window = (s.window + 1).min(WINDOWS.len() - 1),
            Action::ScopeAutoscale => s.autoscale = !s.autoscale,
            Action::ScopeChannels => self.state.overlay = Overlay::Channels { selected: 0 },
            _ => {}
        }
        self.dirty = true;
    }

    /// Open the streaming and collision settings.
    pub fn open_tuning(&mut self) {
        let m = &self.state.droid().monitor;
        if !m.live {
            return self.hint("replay: nothing is sent (the settings are the capture's)");
        }
        if tuning_rows(m).is_empty() {
            return self.hint(format!(
                "{} sends its state by itself: nothing to set",
                self.state.droid().model.display_name()
            ));
        }
        let draft = TuningDraft {
            rate_hz: m.plan.as_ref().map_or(0, |p| p.rate_hz().round() as u16),
            sensors: m
                .plan
                .as_ref()
                .filter(|p| p.is_on())
                .map_or(m.request.sensors, |p| p.sensors),
            collision: m.collision,
        };
        self.state.overlay = Overlay::Tuning { selected: 0, draft };
    }
}

impl super::droid::DroidMut<'_> {
    /// Send the settings: streaming (capped to the link) then collision detection, and make
    /// them the setup of every later reconnect.
    pub fn apply_tuning(&mut self, draft: TuningDraft) {
        let model = self.view.model;
        let request = StreamRequest {
            rate_hz: draft.rate_hz,
            sensors: draft.sensors,
        };
        let plan = stream::plan_for(model, request);
        let family = self.io.family;
        let mut cmds = match &plan {
            Some(p) => stream::reconfigure(model, p, &draft.collision),
            None => family.collision_detection(&draft.collision),
        };
        // The session writes them in order; a full queue is said once.
        let mut failed = None;
        if let Some(session) = &self.io.session {
            for c in cmds.drain(..) {
                if let Err(e) = session.send(c) {
                    failed = Some(e);
                    break;
                }
            }
            let setup = SetupOptions {
                tripod: self.tripod_on_connect,
                collision: draft.collision,
                ..SetupOptions::default()
            };
            let setup = match &plan {
                Some(p) => setup.with_plan(p),
                None => setup,
            };
            session.set_setup(connect_setup(model, &setup));
        }
        let m = &mut self.view.monitor;
        m.request = request;
        m.plan = plan;
        m.collision = draft.collision;
        let streaming = match &m.plan {
            Some(p) if p.is_on() => format!("streaming {} at {}", p.sensors, m.requested()),
            Some(_) => "streaming off".into(),
            None => String::new(),
        };
        let mut text = [streaming, format!("collision {}", m.collision.describe())]
            .into_iter()
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join(" · ");
        if let Some(note) = m.plan.as_ref().and_then(|p| p.note.clone()) {
            text = format!("{note} — {text}");
        }
        if let Some(e) = failed {
            text = format!("settings not all sent: {e}");
        }
        self.hint(text);
    }
}
