//! The latched stop (issue 40 point 6): `{"v":1,"cmd":"hold"}` stops a droid and keeps it
//! stopped, whoever drives it next (another client's drive 100 ms after a plain `stop`
//! undid it), until `{"v":1,"cmd":"release"}`. Each refused command is answered with an
//! error of code `held`, so a client sees why its droid does not move; each change is said
//! with a `hold` object (retained on MQTT's `PREFIX/DROID/hold`, which Home Assistant's
//! "Motion enabled" switch reads).

use super::Bridge;
use super::schema::{Cmd, ErrorCode, Out, Request};

impl Bridge {
    /// Whether droid `i` is held ([`Cmd::Hold`]).
    pub fn is_held(&self, i: usize) -> bool {
        self.droids.get(i).is_some_and(|d| d.lock().held)
    }

    /// Droid `i`'s `hold` object: whether it is held now.
    pub fn hold_state(&self, i: usize) -> Option<Out> {
        Some(Out::Hold {
            droid: self.fleet.member(i)?.name.clone(),
            held: self.is_held(i),
        })
    }

    /// A latched stop: `hold` stops droid `i` and latches, `release` unlatches (each said
    /// with a `hold` object at a change); while held, what moves the droid is refused, the
    /// refusal returned (code `held`, in the reply to each such command, so a client that
    /// drives on sees why it does not move). `None`: go on with the command.
    pub(super) fn hold_or_refuse(&self, req: &Request, i: usize) -> Option<Out> {
        let name = self.fleet.member(i)?.name.clone();
        match req.cmd {
            Cmd::Hold | Cmd::Release => {
                let held = req.cmd == Cmd::Hold;
                let was = {
                    let mut d = self.droids[i].lock();
                    let was = d.held;
                    d.held = held;
                    if held {
                        d.holder.stop();
                    }
                    was
                };
                if held && self.connected(i) {
                    self.stop_here(i);
                }
                if was != held {
                    self.emit(Some(i), Out::Hold { droid: name, held });
                }
                None
            }
            ref c if c.moves() && self.is_held(i) => Some(Out::Error {
                id: req.id.clone(),
                droid: Some(name.clone()),
                cmd: Some(req.cmd.verb().into()),
                code: ErrorCode::Held,
                robot: None,
                capability: None,
                error: format!(
                    "{name} is held (a latched stop): {} refused until {{\"v\":1,\"cmd\":\"release\"}} \
                     (Home Assistant: switch its Motion enabled on)",
                    req.cmd.verb()
                ),
            }),
            _ => None,
        }
    }
}
