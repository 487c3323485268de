//! Carrying out a command: the droid it is for, whether its robot can do it (an
//! `unsupported` error names the robot and the capability), and the reply, at once or after
//! the droid's answer. Split from the bridge's state ([`super::Bridge`]) as its own job.

use super::motion::Motion;
use super::schema::{self, Cmd, ErrorCode, Out, Request};
use super::{Bridge, MAX_IN_FLIGHT, kinematics};
use crate::model::Model;
use crate::session::Slot;
use std::sync::Arc;

impl Bridge {
    /// One command as received (a line, a payload). `default` is the droid a transport
    /// addresses by itself (the MQTT topic's); a `droid` in the command must agree with it.
    /// Never waits: commands that need the droid's answer reply when it comes.
    pub fn handle(self: &Arc<Self>, text: &[u8], default: Option<usize>) {
        self.handle_parsed(schema::parse(text), default)
    }

    /// A command parsed by a transport's own reader ([`ros::cmd_vel`]), or why not.
    pub fn handle_parsed(
        self: &Arc<Self>,
        parsed: Result<Request, Box<schema::BadCommand>>,
        default: Option<usize>,
    ) {
        match parsed {
            Ok(req) => self.execute(req, default),
            Err(mut e) => {
                if e.droid.is_none() {
                    e.droid = default
                        .and_then(|i| self.fleet.member(i))
                        .map(|m| m.name.clone());
                }
                self.emit(default, Out::error(*e))
            }
        }
    }

    /// The droid a request is for.
    pub(super) fn target(&self, req: &Request, default: Option<usize>) -> Result<usize, String> {
        let names = || self.fleet.names().join(", ");
        match (&req.droid, default) {
            (Some(asked), d) => {
                let i = self.fleet.find(asked).map_err(|e| e.to_string())?;
                match d {
                    Some(d) if d != i => Err(format!(
                        "this is {}'s topic: {asked:?} is another droid (send it to that droid's topic)",
                        self.fleet.member(d).map_or("?", |m| m.name.as_str())
                    )),
                    _ => Ok(i),
                }
            }
            (None, Some(d)) => Ok(d),
            (None, None) if self.fleet.len() == 1 => Ok(0),
            (None, None) => Err(format!(
                "this bridge drives several droids: say which with \"droid\" (one of {})",
                names()
            )),
        }
    }

    /// Carry out a parsed request.
    pub fn execute(self: &Arc<Self>, req: Request, default: Option<usize>) {
        if req.cmd == Cmd::Estop {
            self.estop();
            self.reply(&req, default, None);
            return;
        }
        let i = match self.target(&req, default) {
            Ok(i) => i,
            Err(message) => {
                return self.emit(
                    default,
                    Out::Error {
                        id: req.id.clone(),
                        droid: req.droid.clone(),
                        cmd: Some(req.cmd.verb().into()),
                        code: ErrorCode::NoSuchDroid,
                        robot: None,
                        capability: None,
                        error: message,
                    },
                );
            }
        };
        let Some(m) = self.fleet.member(i) else {
            return;
        };
        let (family, model, name) = (m.family, m.model, m.name.clone());
        let unsupported = |capability: &'static str, what: String| {
            self.emit(
                Some(i),
                Out::Error {
                    id: req.id.clone(),
                    droid: Some(name.clone()),
                    cmd: Some(req.cmd.verb().into()),
                    code: ErrorCode::Unsupported,
                    robot: Some(model.display_name()),
                    capability: Some(capability),
                    error: format!("{} ({name}) {what}", model.display_name()),
                },
            )
        };
        // A hold latches whatever the link (a droid reconnecting comes back held).
        if let Some(refused) = self.hold_or_refuse(&req, i) {
            return self.emit(Some(i), refused);
        }
        if matches!(req.cmd, Cmd::Hold | Cmd::Release) {
            return self.reply(&req, Some(i), None);
        }
        // The bridge's own setting: nothing is sent, so the link does not matter.
        if let Cmd::Cruise(speed) = req.cmd {
            self.set_cruise(i, speed);
            return self.reply(&req, Some(i), None);
        }
        // Nothing waits for a link to come back (issue 26 point 8): a command kept until a
        // reconnect would run when nobody expects it (the session's queue keeps what is sent
        // while the link is down); the reconnect's own stop is all a droid gets then.
        if let Some(state) = self.link_down(i) {
            if req.cmd == Cmd::Stop {
                self.droids[i].lock().holder.stop();
            }
            return self.emit(
                Some(i),
                Out::Error {
                    id: req.id.clone(),
                    droid: Some(name.clone()),
                    cmd: Some(req.cmd.verb().into()),
                    code: ErrorCode::Droid,
                    robot: None,
                    capability: None,
                    error: format!(
                        "{name} is not connected ({state}): not sent, and not kept for later; \
                         send it again once its link says connected"
                    ),
                },
            );
        }
        let now = self.start.elapsed();
        match &req.cmd {
            Cmd::Drive { speed, heading } => {
                let m = Motion::Drive {
                    speed: speed.unwrap_or_else(|| self.cruise(i)),
                    heading: heading.degrees(),
                };
                let w = self.droids[i].lock().holder.command(now, m);
                match w {
                    Ok(w) => self.write_wheels(i, w),
                    Err(_) => return unsupported("reverse", "cannot roll backwards".into()),
                }
                return self.reply(&req, Some(i), self.not_ready_note(i));
            }
            Cmd::Twist { linear, angular } => {
                let m = Motion::Twist {
                    linear: *linear,
                    angular: *angular,
                };
                let w = self.droids[i].lock().holder.command(now, m);
                match w {
                    Ok(w) => self.write_wheels(i, w),
                    Err(_) => {
                        return unsupported(
                            "reverse",
                            "cannot roll backwards: its linear speed is 0 or more".into(),
                        );
                    }
                }
                let note = [
                    self.not_ready_note(i),
                    capped_note(model, *linear, *angular),
                ]
                .into_iter()
                .flatten()
                .collect::<Vec<_>>();
                return self.reply(&req, Some(i), (!note.is_empty()).then(|| note.join("; ")));
            }
            Cmd::Stop => {
                self.droids[i].lock().holder.stop();
                self.stop_here(i);
            }
            Cmd::Estop | Cmd::Hold | Cmd::Release | Cmd::Cruise(_) => {}
            Cmd::Head(_)
            | Cmd::Stance(_)
            | Cmd::Lights(_)
            | Cmd::Animation(_)
            | Cmd::Sound(_)
            | Cmd::Matrix(_) => {
                let lowered = req
                    .cmd
                    .intent()
                    .and_then(|intent| family.lower(model, &intent).ok());
                let Some(cmds) = lowered else {
                    let (capability, what) = refusal(&req.cmd);
                    return unsupported(capability, what);
                };
                if !matches!(req.cmd, Cmd::Head(_)) {
                    return self.request(req, i, cmds, None);
                }
                if let Some(m) = self.fleet.members().get(i) {
                    for c in cmds {
                        m.session.set(Slot::Head, c);
                    }
                }
            }
            Cmd::Stream { rate_hz, sensors } => {
                let ask = crate::tuning::StreamRequest {
                    rate_hz: *rate_hz,
                    sensors: sensors.unwrap_or_else(|| crate::family::stream::all_groups(model)),
                };
                let Some(plan) = crate::family::stream::plan_for(model, ask) else {
                    return unsupported(
                        "streaming",
                        "streams by itself: its rate and sensors cannot be chosen".into(),
                    );
                };
                let setup = {
                    let mut d = self.droids[i].lock();
                    d.setup = d.setup.with_plan(&plan);
                    d.setup
                };
                let cmds = crate::family::stream::reconfigure(model, &plan, &setup.collision);
                // Every reconnect keeps what the client set.
                if let Some(m) = self.fleet.member(i) {
                    m.session
                        .set_setup(crate::family::setup::connect_setup(model, &setup));
                }
                let note = plan.note.clone();
                return self.request(req, i, cmds, note);
            }
        }
        self.reply(&req, Some(i), None);
    }

    /// The reply to a command with an `id` (none without), about droid `i`.
    fn reply(&self, req: &Request, i: Option<usize>, note: Option<String>) {
        if let Some(id) = &req.id {
            let droid = i.and_then(|i| self.fleet.member(i)).map(|m| m.name.clone());
            self.emit(
                i,
                Out::Reply {
                    id: id.clone(),
                    droid,
                    cmd: req.cmd.verb(),
                    ok: true,
                    note,
                },
            );
        }
    }

    /// Send `cmds` to droid `i` in order, each waiting for the droid's answer, then reply
    /// (or say what failed).
    fn request(
        self: &Arc<Self>,
        req: Request,
        i: usize,
        cmds: Vec<crate::family::Command>,
        note: Option<String>,
    ) {
        let Some(m) = self.fleet.member(i) else {
            return;
        };
        let name = m.name.clone();
        let busy = {
            let mut d = self.droids[i].lock();
            let busy = d.in_flight >= MAX_IN_FLIGHT;
            if !busy {
                d.in_flight += 1;
            }
            busy
        };
        if busy {
            return self.emit(Some(i), Out::Error {
                id: req.id,
                droid: Some(name),
                cmd: Some(req.cmd.verb().into()),
                code: ErrorCode::Busy,
                robot: None,
                capability: None,
                error: format!(
                    "{MAX_IN_FLIGHT} commands are waiting for this droid's answers: wait for their replies"
                ),
            });
        }
        let session = m.session.clone();
        let bridge = self.clone();
        tokio::spawn(async move {
            let mut failed = None;
            for c in cmds {
                let what = c.name();
                if let Err(e) = session.request(c).await {
                    failed = Some(format!("{name}: {what}: {e}"));
                    break;
                }
            }
            {
                let mut d = bridge.droids[i].lock();
                d.in_flight = d.in_flight.saturating_sub(1);
            }
            match failed {
                None => {
                    bridge.said_played(i, &req.cmd);
                    bridge.reply(&req, Some(i), note);
                    // Its telemetry rate may have changed: the info anew (retained on MQTT).
                    if matches!(req.cmd, Cmd::Stream { .. })
                        && let Some(info) = bridge.info(i)
                    {
                        bridge.emit(Some(i), info);
                    }
                }
                Some(error) => bridge.emit(
                    Some(i),
                    Out::Error {
                        id: req.id,
                        droid: Some(name),
                        cmd: Some(req.cmd.verb().into()),
                        code: ErrorCode::Droid,
                        robot: None,
                        capability: None,
                        error,
                    },
                ),
            }
        });
    }
}

/// Why a droid refuses a command its family cannot lower: the capability word and what the
/// droid lacks, as an `unsupported` error says them.
fn refusal(cmd: &Cmd) -> (&'static str, String) {
    use crate::script::{Action, LedGroup};
    match cmd {
        Cmd::Head(_) => ("dome", "has no dome to turn".into()),
        Cmd::Stance(_) => ("legs", "has no legs to change stance".into()),
        Cmd::Lights(a) => {
            let (group, kind) = match a {
                Action::LedRgb(g, _) => (*g, "colour"),
                Action::LedBrightness(g, _) => (*g, "brightness"),
                _ => (LedGroup::Front, "brightness"),
            };
            (
                "lights",
                format!("has no {} light to set by {kind}", group_name(group)),
            )
        }
        Cmd::Animation(_) => ("animations", "has no animations".into()),
        Cmd::Sound(_) => ("sounds", "cannot play sounds".into()),
        Cmd::Matrix(_) => ("matrix", "has no LED matrix".into()),
        _ => ("", String::new()),
    }
}

/// What a reply says when a twist asked more than droid `model` does: it drives at its
/// most instead.
fn capped_note(model: Model, linear: f32, angular: f32) -> Option<String> {
    let k = kinematics(model);
    let mut said = Vec::new();
    if linear.abs() > k.top_speed_m_s {
        said.push(format!(
            "linear {linear} m/s capped to {} m/s ({}'s top speed)",
            k.top_speed_m_s.copysign(linear),
            model.display_name()
        ));
    }
    if k.steers && angular.abs() > k.full_lock_rad_s {
        said.push(format!(
            "angular {angular} rad/s capped to {} rad/s ({} steers no tighter)",
            k.full_lock_rad_s.copysign(angular),
            model.display_name()
        ));
    }
    (!said.is_empty()).then(|| said.join("; "))
}

fn group_name(g: crate::script::LedGroup) -> &'static str {
    match g {
        crate::script::LedGroup::Front => "front",
        crate::script::LedGroup::Back => "back",
        crate::script::LedGroup::Logic => "logic",
        crate::script::LedGroup::Holo => "holo",
    }
}
