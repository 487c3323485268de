//! The outgoing queue: a bounded FIFO for discrete requests plus latest-wins slots for
//! continuous controls (drive, dome). A newer drive command replaces a queued older one, so
//! under any input rate there is at most one drive and one head command waiting.

use crate::family::Command;
use std::collections::VecDeque;

/// Continuous controls whose latest value is all that matters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    Drive,
    Head,
}

/// A command's ticket, to learn when it has left the queue ([`OutQueue::holds`]): a Sphero
/// Edu program's timed call counts its duration from when its command leaves, not from when
/// it was queued (issue 38; spherov2 sends each command before its call's clock starts).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Mark(pub u64);

/// What a state-setting command sets (one light, say): a newer request with the same key
/// replaces an unwritten older one, so a loop that sets a light faster than the pacing
/// never fills the queue, and the light ends on its last state (issue 38).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Latest(pub u64);

/// Who waits for a request's answer. The queue and the core hold only this number (they do
/// no I/O); the handle keeps the channel it stands for and is given the answer under it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Reply(pub u64);

/// A discrete request waiting to be written.
#[derive(Debug)]
pub struct Queued {
    pub cmd: Command,
    /// Set when the caller waits for the response.
    pub reply: Option<Reply>,
    /// Ask the droid for a response (the default); fire-and-forget sends also ask, so that
    /// errors are seen and counted.
    pub want_response: bool,
    /// How often to re-send on a timeout, or after a wake when the droid answers
    /// target_unavailable (asleep). Connect setup uses this; ordinary requests do not.
    pub retries: u8,
    /// Already woken and re-sent once after a target_unavailable answer.
    pub woken: bool,
    /// An error answer is expected on some firmware (a fail-safe the droid may not know):
    /// logged once, not counted as an error.
    pub quiet: bool,
    /// Its ticket, when someone wants to know it left.
    pub mark: Option<Mark>,
    /// What it sets, when only its latest value matters.
    pub latest: Option<Latest>,
}

impl Queued {
    /// A request with the defaults: answered, no retries, errors counted.
    pub fn new(cmd: Command) -> Queued {
        Queued {
            cmd,
            reply: None,
            want_response: true,
            retries: 0,
            woken: false,
            quiet: false,
            mark: None,
            latest: None,
        }
    }
}

/// What to write next.
#[derive(Debug)]
pub enum Next {
    Slot(Slot, Command),
    Fifo(Queued),
}

#[derive(Debug)]
pub struct OutQueue {
    drive: Option<(Command, Option<Mark>)>,
    head: Option<(Command, Option<Mark>)>,
    fifo: VecDeque<Queued>,
    capacity: usize,
    slots_turn: bool,
    /// Items at the front of the FIFO that must go before any drive or dome command: the
    /// wake and the stop at the last heading after a (re)connect. A drive before the Wake
    /// reaches a sleeping droid and fails. The rest of the setup then takes turns with the
    /// slots, so driving never waits more than one pacing slot behind it.
    setup_left: usize,
    /// Between the two slots, whose turn it is: a drive storm must not starve the dome.
    head_turn: bool,
    /// Continuous commands replaced before they were written.
    pub coalesced: u64,
}

impl OutQueue {
    pub fn new(capacity: usize) -> Self {
        OutQueue {
            drive: None,
            head: None,
            fifo: VecDeque::new(),
            capacity: capacity.max(1),
            slots_turn: true,
            setup_left: 0,
            head_turn: false,
            coalesced: 0,
        }
    }

    /// Put the latest value of a continuous control; replaces any unwritten older one. A
    /// drive also supersedes the drive commands waiting in the FIFO (a request's drive, or
    /// one re-sent after a Wake): written after it, an older drive would undo it (an e-stop
    /// followed by the drive it stopped). They are returned, for their callers to be told.
    pub fn set_slot(&mut self, slot: Slot, cmd: impl Into<Command>) -> Vec<Queued> {
        self.set_slot_marked(slot, cmd, None)
    }

    /// [`Self::set_slot`] with a ticket for the command ([`Self::holds`]).
    pub fn set_slot_marked(
        &mut self,
        slot: Slot,
        cmd: impl Into<Command>,
        mark: Option<Mark>,
    ) -> Vec<Queued> {
        let cmd = cmd.into();
        let mut superseded = Vec::new();
        if slot == Slot::Drive && self.fifo.iter().any(|q| q.cmd.is_drive()) {
            let mut kept = VecDeque::with_capacity(self.fifo.len());
            for (i, q) in std::mem::take(&mut self.fifo).into_iter().enumerate() {
                // The connect setup's own stop (ahead of the slots) stays.
                if q.cmd.is_drive() && !q.cmd.is_stop() {
                    if i < self.setup_left {
                        self.setup_left -= 1;
                    }
                    superseded.push(q);
                } else {
                    kept.push_back(q);
                }
            }
            self.fifo = kept;
        }
        let s = match slot {
            Slot::Drive => &mut self.drive,
            Slot::Head => &mut self.head,
        };
        if s.replace((cmd, mark)).is_some() {
            self.coalesced += 1;
        }
        self.coalesced += superseded.len() as u64;
        superseded
    }

    /// Queue a discrete request; a full queue hands it back. A request with a [`Latest`] key
    /// replaces the unwritten one with the same key (returned, for its caller to be told),
    /// and goes at the back: the order of what the droid is told stays the order it was
    /// asked, so the last state asked for is the last written.
    pub fn push(&mut self, q: Queued) -> Result<Option<Queued>, Queued> {
        let mut replaced = None;
        if let Some(key) = q.latest
            && let Some(i) = self
                .fifo
                .iter()
                .skip(self.setup_left)
                .position(|old| old.latest == Some(key))
        {
            replaced = self.fifo.remove(self.setup_left + i);
            self.coalesced += 1;
        }
        if self.fifo.len() >= self.capacity {
            return Err(q);
        }
        self.fifo.push_back(q);
        Ok(replaced)
    }

    /// Whether the FIFO takes no more requests now.
    pub fn is_full(&self) -> bool {
        self.fifo.len() >= self.capacity
    }

    /// Whether the command with ticket `mark` is still waiting to be written.
    pub fn holds(&self, mark: Mark) -> bool {
        let slot =
            |s: &Option<(Command, Option<Mark>)>| s.as_ref().is_some_and(|(_, m)| *m == Some(mark));
        slot(&self.drive) || slot(&self.head) || self.fifo.iter().any(|q| q.mark == Some(mark))
    }

    /// Queue ahead of everything else (connect setup, retries). The first `gate` items go
    /// before any drive or dome command; the others take turns with them.
    pub fn push_front(&mut self, items: Vec<Queued>, gate: usize) {
        self.setup_left += gate.min(items.len());
        for q in items.into_iter().rev() {
            self.fifo.push_front(q);
        }
    }

    /// Queue ahead of everything else, all of it before any drive or dome command.
    pub fn push_front_all(&mut self, items: Vec<Queued>) {
        let n = items.len();
        self.push_front(items, n);
    }

    pub fn is_empty(&self) -> bool {
        self.drive.is_none() && self.head.is_none() && self.fifo.is_empty()
    }

    pub fn len(&self) -> usize {
        self.fifo.len() + self.drive.is_some() as usize + self.head.is_some() as usize
    }

    /// The next thing to write. A drive command with speed 0 (a stop) always goes first;
    /// otherwise slots and the FIFO take turns so neither starves the other, and so do the
    /// drive and head slots.
    pub fn pop(&mut self) -> Option<Next> {
        self.pop_marked().map(|(next, _)| next)
    }

    /// [`Self::pop`], with the ticket of a slot's command (a FIFO item carries its own), so
    /// the session can tell when that command is answered ([`super::core::SessionCore::awaits`]).
    pub fn pop_marked(&mut self) -> Option<(Next, Option<Mark>)> {
        if self.setup_left > 0 {
            if let Some(q) = self.fifo.pop_front() {
                self.setup_left -= 1;
                let mark = q.mark;
                return Some((Next::Fifo(q), mark));
            }
            self.setup_left = 0;
        }
        if self.drive.as_ref().is_some_and(|(c, _)| is_stop(c)) {
            return self
                .drive
                .take()
                .map(|(c, mark)| (Next::Slot(Slot::Drive, c), mark));
        }
        let slot_first = self.slots_turn || self.fifo.is_empty();
        self.slots_turn = !self.slots_turn;
        if slot_first {
            let order = if self.head_turn {
                [Slot::Head, Slot::Drive]
            } else {
                [Slot::Drive, Slot::Head]
            };
            for slot in order {
                let taken = match slot {
                    Slot::Drive => self.drive.take(),
                    Slot::Head => self.head.take(),
                };
                if let Some((c, mark)) = taken {
                    self.head_turn = slot == Slot::Drive;
                    return Some((Next::Slot(slot, c), mark));
                }
            }
        }
        self.fifo.pop_front().map(|q| {
            let mark = q.mark;
            (Next::Fifo(q), mark)
        })
    }

    /// Drop everything (link lost); the discrete requests are returned so their callers can
    /// be told.
    pub fn clear(&mut self) -> Vec<Queued> {
        self.drive = None;
        self.head = None;
        self.setup_left = 0;
        self.fifo.drain(..).collect()
    }
}

/// A drive command whose speed is 0, in any family.
pub fn is_stop(c: &Command) -> bool {
    c.is_stop()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::v2::cmd;
    use crate::protocol::v2::wire::DriveFlags;
    use crate::units::Heading;

    fn drive(speed: u8) -> Command {
        cmd::drive_with_heading(speed, Heading::new(90).unwrap(), DriveFlags::empty()).into()
    }

    fn req(c: impl Into<Command>) -> Queued {
        Queued::new(c.into())
    }

    #[test]
    fn latest_drive_wins() {
        let mut q = OutQueue::new(8);
        for s in 1..=100 {
            q.set_slot(Slot::Drive, drive(s));
            assert!(q.len() <= 1);
        }
        assert_eq!(q.coalesced, 99);
        let Some(Next::Slot(Slot::Drive, c)) = q.pop() else {
            panic!()
        };
        assert_eq!(c.data()[0], 100);
        assert!(q.pop().is_none());
    }

    #[test]
    fn stop_jumps_the_queue() {
        let mut q = OutQueue::new(8);
        q.push(req(cmd::wake())).unwrap();
        q.push(req(cmd::ping())).unwrap();
        q.set_slot(Slot::Drive, drive(0));
        let Some(Next::Slot(Slot::Drive, c)) = q.pop() else {
            panic!()
        };
        assert!(is_stop(&c));
    }

    #[test]
    fn slots_and_fifo_alternate() {
        let mut q = OutQueue::new(8);
        q.push(req(cmd::wake())).unwrap();
        q.push(req(cmd::ping())).unwrap();
        q.set_slot(Slot::Drive, drive(50));
        let mut order = Vec::new();
        while let Some(n) = q.pop() {
            order.push(match n {
                Next::Slot(..) => "slot",
                Next::Fifo(_) => "fifo",
            });
            if order.len() == 2 {
                q.set_slot(Slot::Drive, drive(60));
            }
        }
        assert_eq!(order, ["slot", "fifo", "slot", "fifo"]);
    }

    #[test]
    fn drive_storm_does_not_starve_the_head() {
        let mut q = OutQueue::new(8);
        q.set_slot(
            Slot::Head,
            cmd::set_head_position(crate::units::HeadAngle::clamped(45.0)),
        );
        let mut popped = Vec::new();
        for s in 1..=4 {
            q.set_slot(Slot::Drive, drive(s));
            popped.push(match q.pop() {
                Some(Next::Slot(slot, _)) => slot,
                other => panic!("{other:?}"),
            });
        }
        assert_eq!(popped[..2], [Slot::Drive, Slot::Head]);
    }

    #[test]
    fn a_drive_supersedes_the_drives_queued_before_it() {
        let mut q = OutQueue::new(8);
        q.push_front(vec![req(cmd::wake()), req(drive(100))], 1);
        q.push(req(cmd::ping())).unwrap();
        let gone = q.set_slot(Slot::Drive, drive(0));
        assert_eq!(gone.len(), 1);
        assert_eq!(gone[0].cmd.data()[0], 100);
        let order: Vec<u8> = std::iter::from_fn(|| q.pop())
            .map(|n| match n {
                Next::Fifo(q) => q.cmd.cid(),
                Next::Slot(..) => 0xD0,
            })
            .collect();
        // The Wake, the stop, the ping; the old drive never.
        assert_eq!(order, [0x0D, 0xD0, 0x01]);
        // The setup's own stop stays ahead of the slots.
        let mut q = OutQueue::new(8);
        q.push_front_all(vec![req(cmd::wake()), req(drive(0))]);
        assert!(q.set_slot(Slot::Drive, drive(30)).is_empty());
        assert_eq!(q.len(), 3);
    }

    #[test]
    fn a_newer_light_replaces_the_unwritten_one_and_goes_last() {
        let mut q = OutQueue::new(2);
        let light = |c: Command, k: u64| Queued {
            latest: Some(Latest(k)),
            ..Queued::new(c)
        };
        // A hundred colours for one light and one for another: never full, two waiting.
        q.push(light(cmd::wake().into(), 1)).unwrap();
        for _ in 0..100 {
            q.push(light(cmd::ping().into(), 2)).unwrap();
        }
        let last = q.push(light(cmd::reset_yaw().into(), 1)).unwrap();
        assert_eq!(last.map(|r| r.cmd.cid()), Some(0x0D));
        assert_eq!(q.coalesced, 100);
        let order: Vec<u8> = std::iter::from_fn(|| q.pop())
            .map(|n| match n {
                Next::Fifo(q) => q.cmd.cid(),
                Next::Slot(..) => 0,
            })
            .collect();
        assert_eq!(order, [0x01, 0x06]);
    }

    #[test]
    fn a_marked_command_is_held_until_it_is_taken() {
        let mut q = OutQueue::new(4);
        q.push(Queued {
            mark: Some(Mark(1)),
            ..Queued::new(cmd::ping().into())
        })
        .unwrap();
        q.set_slot_marked(Slot::Drive, drive(50), Some(Mark(2)));
        assert!(q.holds(Mark(1)) && q.holds(Mark(2)) && !q.holds(Mark(3)));
        q.pop();
        assert!(!q.holds(Mark(2)) && q.holds(Mark(1)));
        q.pop();
        assert!(!q.holds(Mark(1)));
        // Replaced before it left: not held either (the newer command stands for it).
        q.set_slot_marked(Slot::Drive, drive(50), Some(Mark(4)));
        q.set_slot(Slot::Drive, drive(60));
        assert!(!q.holds(Mark(4)));
    }

    #[test]
    fn fifo_is_bounded() {
        let mut q = OutQueue::new(2);
        assert!(q.push(req(cmd::wake())).is_ok());
        assert!(q.push(req(cmd::wake())).is_ok());
        assert!(q.push(req(cmd::wake())).is_err());
        assert_eq!(q.clear().len(), 2);
        assert!(q.is_empty());
    }

    #[test]
    fn slots_wait_for_the_setup() {
        let mut q = OutQueue::new(8);
        q.set_slot(Slot::Drive, drive(0));
        q.set_slot(
            Slot::Head,
            cmd::set_head_position(crate::units::HeadAngle::clamped(10.0)),
        );
        q.push_front_all(vec![req(cmd::wake()), req(cmd::reset_yaw())]);
        q.push(req(cmd::ping())).unwrap();
        let order: Vec<u8> = std::iter::from_fn(|| q.pop())
            .map(|n| match n {
                Next::Fifo(q) => q.cmd.cid(),
                Next::Slot(Slot::Drive, _) => 0xD0,
                Next::Slot(Slot::Head, _) => 0xE0,
            })
            .collect();
        // Wake and reset-yaw first; then the stop, and the rest take turns.
        assert_eq!(&order[..3], &[0x0D, 0x06, 0xD0]);
        assert_eq!(order.len(), 5);
    }

    #[test]
    fn setup_goes_first() {
        let mut q = OutQueue::new(8);
        q.push(req(cmd::ping())).unwrap();
        q.push_front_all(vec![req(cmd::wake()), req(cmd::reset_yaw())]);
        let names: Vec<u8> = std::iter::from_fn(|| q.pop())
            .map(|n| match n {
                Next::Fifo(q) => q.cmd.cid(),
                Next::Slot(..) => 0xFF,
            })
            .collect();
        assert_eq!(names, [0x0D, 0x06, 0x01]);
    }
}
