//! A paced call's steps (`spin`): each played, then its answer waited for before the next is
//! made, as spherov2's `spin` sends a heading and waits for the droid's answer before it
//! computes the next ([`crate::edu::timeline::spin_turned`]). On droidctl's links the answer
//! comes within the pacing slot the next write waits for anyway, so its steps go once per
//! slot, as spherov2's go once per round trip; where nothing answers, a step counts as
//! answered once it is written.

use super::super::api::Act;
use super::{LEAVE_LIMIT, Player};
use crate::session::{Mark, SessionHandle};
use tokio::time::Instant;

impl Player {
    /// Play a paced call's step (`call`, from the schedule) and wait for its drive's answer
    /// ([`Self::paced_answered`]); a step that sent nothing is answered at once.
    pub(super) async fn paced(&mut self, call: u64, acts: &[Act]) {
        self.drive_mark = None;
        for a in acts {
            self.act(0, a).await;
        }
        match self.drive_mark.take() {
            Some(mark) => self.awaiting.push((mark, call)),
            None => self.timed.answered(call, Instant::now()),
        }
    }

    /// What the play loop waits on for paced steps: the session and the tickets of their
    /// drives (`None`: no step waits).
    pub(super) fn paced_waits(&self) -> Option<(SessionHandle, Vec<Mark>)> {
        (!self.awaiting.is_empty()).then(|| {
            let marks = self.awaiting.iter().map(|(m, _)| *m).collect();
            (self.session.clone(), marks)
        })
    }

    /// Steps answered (`in_time`), or given up on after [`LEAVE_LIMIT`] (a link that stopped
    /// answering must not hold a spin for good): their calls' next steps are due now.
    pub(super) fn paced_answered(&mut self, in_time: bool) {
        let now = Instant::now();
        let session = self.session.clone();
        let timed = &mut self.timed;
        self.awaiting.retain(|(mark, call)| {
            let done = !in_time || !session.awaits(*mark);
            if done {
                timed.answered(*call, now);
            }
            !done
        });
    }
}

/// How long the play loop waits on paced steps' answers before it gives up on them.
pub(super) const ANSWER_LIMIT: std::time::Duration = LEAVE_LIMIT;
