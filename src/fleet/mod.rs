//! A fleet: several droids driven at once, each over its own [`SessionHandle`] (one session
//! per droid: its own SEQ, pacing, slots, reconnects and fail-safe), addressed by name.
//!
//! The fleet is the API above the sessions that the app, missions and anything else driving
//! several droids use (a bridge publishing topics per droid needs nothing of the TUI):
//!
//! - [`Fleet::start`] starts one session per [`DroidSpec`]; [`Fleet::find`] resolves a name
//!   as people write it (`R2`, `D2-0001`, `bb8`: exact name, model, or a unique part);
//! - [`Fleet::telemetry`] and [`Fleet::link_state`] are per-droid streams (`watch`: the
//!   latest value, never a backlog), [`Fleet::events`] the session's own notifications;
//! - [`Fleet::command`] sends a [`FleetCommand`] to one droid, turned into that droid's own
//!   commands by its family (a Robi steers, a BB-8 rolls);
//! - [`Fleet::estop_all`] stops every droid at once (a synchronous slot write per session, no
//!   await between them), [`Fleet::shutdown_all`] stops and disconnects every droid.
//!
//! Connection attempts on one Bluetooth adapter are serialized by [`gate`] (BlueZ allows one
//! at a time), with a cap of droids per adapter.

pub mod gate;
pub mod mission;
pub mod name;

pub use crate::mission::drive_command;

use crate::family::intent::Intent;
use crate::family::{Command, Family};
use crate::link::Link;
use crate::model::Model;
use crate::protocol::wire::LegAction;
use crate::session::{self, LinkState, SessionConfig, SessionEvent, SessionHandle, Slot};
use crate::telemetry::Telemetry;
use crate::units::{HeadAngle, Heading};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::{broadcast, watch};
use tokio::task::JoinHandle;
use tokio::time::Instant;

/// One droid to start: what it is called, what it is, its link and session settings.
pub struct DroidSpec {
    pub name: String,
    pub model: Model,
    pub link: Box<dyn Link>,
    pub session: SessionConfig,
    /// Where it is, for people: `simulated`, `Bluetooth hci0`, `relay pi.local:50004`.
    pub origin: String,
    /// Where it started in a room its fleet shares, cm, room coordinates (its locator's
    /// (0, 0) there), so a map can draw every droid in one frame. `None` when nobody knows:
    /// a real droid's locator counts from wherever that droid stood when it woke.
    pub room_origin: Option<(f32, f32)>,
}

/// Where a droid of a started session is: for people, and in the fleet's room when known.
#[derive(Debug, Clone, PartialEq)]
pub struct Seat {
    pub origin: String,
    pub room_origin: Option<(f32, f32)>,
}

/// A droid of the fleet.
pub struct Member {
    pub name: String,
    pub model: Model,
    pub family: &'static dyn Family,
    pub session: SessionHandle,
    pub origin: String,
    /// Where it started in the fleet's room, when known ([`DroidSpec::room_origin`]).
    pub room_origin: Option<(f32, f32)>,
    telemetry: watch::Receiver<Telemetry>,
}

/// What a bridge or a mission asks one droid to do. The droid's family makes the commands.
#[derive(Debug, Clone, PartialEq)]
pub enum FleetCommand {
    /// Roll at `speed` toward `heading` (a steering robot reads the heading as a turn:
    /// 0 straight, up to 90 right, 270..359 left).
    Drive {
        speed: u8,
        heading: Heading,
    },
    /// Speed 0 at the last heading.
    Stop,
    Stance(LegAction),
    Head(HeadAngle),
    /// A command built elsewhere, sent as is.
    Raw(Command),
}

/// Why a fleet request failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum FleetError {
    /// No droid of the fleet goes by that name; the names there are.
    NoSuchDroid { asked: String, names: Vec<String> },
    /// Several droids match; which ones.
    Ambiguous { asked: String, matches: Vec<String> },
    /// The droid cannot do that (no legs, no dome).
    Unsupported { droid: String, what: &'static str },
    /// The session refused the command.
    Session {
        droid: String,
        error: session::RequestError,
    },
}

impl std::fmt::Display for FleetError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FleetError::NoSuchDroid { asked, names } => write!(
                f,
                "no droid called {asked:?} in this fleet (there are: {})",
                names.join(", ")
            ),
            FleetError::Ambiguous { asked, matches } => write!(
                f,
                "{asked:?} could be any of {}: use more of the name",
                matches.join(", ")
            ),
            FleetError::Unsupported { droid, what } => write!(f, "{droid} has no {what}"),
            FleetError::Session { droid, error } => write!(f, "{droid}: {error}"),
        }
    }
}

impl std::error::Error for FleetError {}

struct Inner {
    members: Vec<Member>,
    folders: Vec<JoinHandle<()>>,
}

impl Drop for Inner {
    fn drop(&mut self) {
        for f in &self.folders {
            f.abort();
        }
    }
}

/// A handle to the fleet. Cloning is cheap; the droids stay connected until
/// [`Fleet::shutdown_all`].
#[derive(Clone)]
pub struct Fleet {
    inner: Arc<Inner>,
}

impl Fleet {
    /// Start one session per droid. Needs a tokio runtime with time enabled.
    pub fn start(specs: Vec<DroidSpec>) -> Fleet {
        let sessions = specs
            .into_iter()
            .map(|s| {
                let session = session::start(s.link, s.session);
                let seat = Seat {
                    origin: s.origin,
                    room_origin: s.room_origin,
                };
                (s.name, s.model, session, seat)
            })
            .collect();
        Fleet::from_sessions(sessions)
    }

    /// A fleet of sessions already started: name, model, session, where each is.
    pub fn from_sessions(sessions: Vec<(String, Model, SessionHandle, Seat)>) -> Fleet {
        let start = Instant::now();
        let mut members = Vec::with_capacity(sessions.len());
        let mut folders = Vec::with_capacity(sessions.len());
        for (name, model, session, seat) in sessions {
            let (tx, rx) = watch::channel(Telemetry::default());
            folders.push(tokio::spawn(fold_telemetry(session.clone(), tx, start)));
            members.push(Member {
                family: crate::family::for_model(model),
                name,
                model,
                session,
                origin: seat.origin,
                room_origin: seat.room_origin,
                telemetry: rx,
            });
        }
        Fleet {
            inner: Arc::new(Inner { members, folders }),
        }
    }

    pub fn len(&self) -> usize {
        self.inner.members.len()
    }

    pub fn is_empty(&self) -> bool {
        self.inner.members.is_empty()
    }

    pub fn members(&self) -> &[Member] {
        &self.inner.members
    }

    pub fn member(&self, i: usize) -> Option<&Member> {
        self.inner.members.get(i)
    }

    pub fn names(&self) -> Vec<String> {
        self.inner.members.iter().map(|m| m.name.clone()).collect()
    }

    /// The index of the droid `asked` names ([`name::resolve`]).
    pub fn find(&self, asked: &str) -> Result<usize, FleetError> {
        let droids: Vec<(&str, Model)> = self
            .inner
            .members
            .iter()
            .map(|m| (m.name.as_str(), m.model))
            .collect();
        name::resolve(&droids, asked)
    }

    /// The droid's telemetry as its notifications fold it, since the fleet started.
    pub fn telemetry(&self, i: usize) -> Option<watch::Receiver<Telemetry>> {
        self.member(i).map(|m| m.telemetry.clone())
    }

    /// The droid's link state (connecting, connected, reconnecting, closed).
    pub fn link_state(&self, i: usize) -> Option<watch::Receiver<LinkState>> {
        self.member(i).map(|m| m.session.watch_state())
    }

    /// The droid's notifications as its session decodes them.
    pub fn events(&self, i: usize) -> Option<broadcast::Receiver<SessionEvent>> {
        self.member(i).map(|m| m.session.subscribe())
    }

    /// Send `cmd` to the droid at `i`. Drive and stop go to the session's latest-wins slot
    /// (a continuous control: the caller re-sends within the droid's fail-safe timeout while
    /// it should keep rolling); the rest are queued requests.
    pub fn command(&self, i: usize, cmd: FleetCommand) -> Result<(), FleetError> {
        let m = self.member(i).ok_or_else(|| FleetError::NoSuchDroid {
            asked: format!("#{i}"),
            names: self.names(),
        })?;
        let unsupported = |what| FleetError::Unsupported {
            droid: m.name.clone(),
            what,
        };
        let send = |c: Command| {
            m.session.send(c).map_err(|error| FleetError::Session {
                droid: m.name.clone(),
                error,
            })
        };
        let intent = match cmd {
            FleetCommand::Stop => {
                m.session.stop_now(m.family);
                return Ok(());
            }
            FleetCommand::Raw(c) => return send(c),
            FleetCommand::Drive { speed, heading } => Intent::Drive {
                speed,
                heading,
                reverse: false,
            },
            FleetCommand::Stance(a) => Intent::Stance(a),
            FleetCommand::Head(a) => Intent::Head(a),
        };
        let cmds = m.family.lower(m.model, &intent).map_err(|_| {
            // The bridge's capability words.
            unsupported(match intent {
                Intent::Stance(_) => "legs",
                _ => "dome",
            })
        })?;
        for c in cmds {
            match intent {
                Intent::Drive { .. } => m.session.set(Slot::Drive, c),
                Intent::Head(_) => m.session.set(Slot::Head, c),
                _ => send(c)?,
            }
        }
        Ok(())
    }

    /// Emergency stop: every droid's session gets its stop (speed 0 at its last heading) in
    /// its drive slot now, one after the other without waiting, so the stops go out on every
    /// link at its next write.
    pub fn estop_all(&self) {
        for m in &self.inner.members {
            m.session.stop_now(m.family);
        }
    }

    /// Stop and disconnect every droid at once (concurrently, each within the session's own
    /// budget): `last(i)` gives droid `i`'s final commands after its stop.
    pub async fn shutdown_all(&self, last: impl Fn(usize) -> Vec<Command>) {
        let all = self
            .inner
            .members
            .iter()
            .enumerate()
            .map(|(i, m)| m.session.shutdown_stopped(last(i)));
        let _ =
            tokio::time::timeout(Duration::from_secs(3), futures_util::future::join_all(all)).await;
    }
}

/// Fold a session's notifications into its telemetry, for [`Fleet::telemetry`].
async fn fold_telemetry(session: SessionHandle, tx: watch::Sender<Telemetry>, start: Instant) {
    let mut rx = session.subscribe();
    for n in session.greeting() {
        tx.send_modify(|t| t.apply(&n, Duration::ZERO));
    }
    loop {
        match rx.recv().await {
            Ok(SessionEvent::Notification(n)) => {
                let at = start.elapsed();
                tx.send_modify(|t| t.apply(&n, at));
            }
            Ok(_) | Err(broadcast::error::RecvError::Lagged(_)) => {}
            Err(broadcast::error::RecvError::Closed) => break,
        }
    }
}
