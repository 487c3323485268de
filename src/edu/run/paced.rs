//! A paced call's steps (`spin`): each played, then its answer waited for before the next is
//! made, as spherov2's `spin` sends a heading and waits for the droid's answer before it
//! computes the next ([`crate::edu::timeline::spin_turned`]). On droidctl's links the answer
//! comes within the pacing slot the next write waits for anyway, so its steps go once per
//! slot, as spherov2's go once per round trip. The next step is made no sooner than one
//! pacing slot after the one before was played: where nothing answers (a step counts as
//! answered once written), and where a step was replaced in the drive slot before it left
//! (several spins at once, issue 37's 990 pending spins), the steps still go once per slot
//! rather than in a loop that takes no time.

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
        let next = Instant::now() + self.session.pacing();
        match self.drive_mark.take() {
            Some(mark) => self.awaiting.push((mark, call, next)),
            None => self.timed.answered(call, next),
        }
    }

    /// What the play loop waits on for paced steps: the session and the tickets of their
    /// drives (`None`: no step waits).
    pub(super) fn paced_waits(&self) -> Option<(SessionHandle, Vec<Mark>)> {
        (!self.awaiting.is_empty()).then(|| {
            let marks = self.awaiting.iter().map(|(m, ..)| *m).collect();
            (self.session.clone(), marks)
        })
    }

    /// Steps answered (`in_time`), or given up on after [`LEAVE_LIMIT`] (a link that stopped
    /// answering must not hold a spin for good): their calls' next steps are due now, or a
    /// pacing slot after the step was played if that is later.
    pub(super) fn paced_answered(&mut self, in_time: bool) {
        let now = Instant::now();
        let session = self.session.clone();
        let timed = &mut self.timed;
        self.awaiting.retain(|(mark, call, next)| {
            let done = !in_time || !session.awaits(*mark);
            if done {
                timed.answered(*call, now.max(*next));
            }
            !done
        });
    }
}

/// How long the play loop waits on paced steps' answers before it gives up on them.
pub(super) const ANSWER_LIMIT: std::time::Duration = LEAVE_LIMIT;
