//! Sphero Edu's infrared calls ("Communications": broadcast, follow, evade, messages): what a
//! program started and must stop at its end. Their commands, BOLT's and RVR's own, are the
//! family's (`family::v2::robots::infrared`, reached through [`crate::family::intent::Intent::Ir`]).

use super::api::Ir;

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
