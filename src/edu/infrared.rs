//! Sphero Edu's infrared calls ("Communications": broadcast, follow, evade, messages) as BOLT
//! and RVR each take them on the wire. The behaviours alike: start broadcasting, following or
//! evading with `[far, near]` (Sensor 0x27, 0x28, 0x33) and their stops (0x29, 0x32, 0x34).
//! A message is BOLT's robot-to-robot send (0x2A: the channel, then the intensity for each of
//! the four emitters) and listen (0x2B: once per channel, 0xFF for "without end"), and RVR's
//! send infrared message (0x3F, the same five bytes) and message notify (0x3E, on): spherov2.py
//! binds those to BOLT and to RVR respectively, and Sphero's RVR SDK sends RVR's
//! (src/sim/infrared.rs has the sources and what the unnamed bytes are taken to be). spherov2's
//! own `SpheroEduAPI` sends nothing for BOLT's messages ("TODO: BOLT").

use super::api::Ir;
use crate::model::Model;
use crate::protocol::v2::{Command, cmd};

/// The commands of `ir` on `model` (BOLT or RVR: the calls are on no other robot).
pub fn commands(model: Model, ir: &Ir) -> Vec<Command> {
    let rvr = model == Model::Rvr;
    match ir {
        Ir::Broadcast { far, near } => vec![cmd::start_robot_to_robot_ir_broadcasting(*far, *near)],
        Ir::StopBroadcast => vec![cmd::stop_robot_to_robot_ir_broadcasting()],
        Ir::Follow { far, near } => vec![cmd::start_robot_to_robot_ir_following(*far, *near)],
        Ir::StopFollow => vec![cmd::stop_robot_to_robot_ir_following()],
        Ir::Evade { far, near } => vec![cmd::start_robot_to_robot_ir_evading(*far, *near)],
        Ir::StopEvade => vec![cmd::stop_robot_to_robot_ir_evading()],
        Ir::Send { channel, intensity } => {
            let data = [*channel, *intensity, *intensity, *intensity, *intensity];
            vec![if rvr {
                cmd::send_infrared_message(data)
            } else {
                cmd::send_robot_to_robot_ir_message(data)
            }]
        }
        Ir::Listen(_) if rvr => vec![cmd::enable_robot_ir_message_notify(true)],
        Ir::Listen(channels) => channels
            .iter()
            .map(|c| cmd::listen_for_robot_to_robot_ir_message([*c, 0xFF]))
            .collect(),
    }
}

/// The infrared behaviours a program started and did not stop: a follower or evader rolls by
/// itself, and a broadcaster leads others, so each is stopped when the program ends.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Running(Vec<Ir>);

impl Running {
    /// `ir` was sent.
    pub fn note(&mut self, ir: &Ir) {
        let (stop, started) = match ir {
            Ir::Broadcast { .. } => (Ir::StopBroadcast, true),
            Ir::Follow { .. } => (Ir::StopFollow, true),
            Ir::Evade { .. } => (Ir::StopEvade, true),
            Ir::StopBroadcast | Ir::StopFollow | Ir::StopEvade => (ir.clone(), false),
            Ir::Send { .. } | Ir::Listen(_) => return,
        };
        self.0.retain(|r| *r != stop);
        if started {
            self.0.push(stop);
        }
    }

    /// The stops of what still runs (none after).
    pub fn stops(&mut self) -> Vec<Ir> {
        std::mem::take(&mut self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_robot_gets_its_own_message_commands() {
        let send = Ir::Send {
            channel: 3,
            intensity: 64,
        };
        let bolt = commands(Model::Bolt, &send);
        assert_eq!(
            (bolt[0].cid, bolt[0].data.clone()),
            (0x2A, vec![3, 64, 64, 64, 64])
        );
        let rvr = commands(Model::Rvr, &send);
        assert_eq!(
            (rvr[0].cid, rvr[0].data.clone()),
            (0x3F, vec![3, 64, 64, 64, 64])
        );
        let listen = Ir::Listen(vec![2, 5]);
        let bolt: Vec<_> = commands(Model::Bolt, &listen)
            .into_iter()
            .map(|c| (c.cid, c.data))
            .collect();
        assert_eq!(bolt, vec![(0x2B, vec![2, 0xFF]), (0x2B, vec![5, 0xFF])]);
        let rvr = commands(Model::Rvr, &listen);
        assert_eq!(
            (rvr.len(), rvr[0].cid, rvr[0].data.clone()),
            (1, 0x3E, vec![1])
        );
        let follow = commands(Model::Bolt, &Ir::Follow { far: 1, near: 0 });
        assert_eq!((follow[0].cid, follow[0].data.clone()), (0x28, vec![1, 0]));
    }

    #[test]
    fn what_was_started_and_not_stopped_is_stopped_at_the_end() {
        let mut r = Running::default();
        r.note(&Ir::Broadcast { far: 1, near: 0 });
        r.note(&Ir::Follow { far: 1, near: 0 });
        r.note(&Ir::Follow { far: 2, near: 3 });
        r.note(&Ir::StopBroadcast);
        r.note(&Ir::Listen(vec![1]));
        assert_eq!(r.stops(), vec![Ir::StopFollow]);
        assert_eq!(r.stops(), vec![]);
    }
}
