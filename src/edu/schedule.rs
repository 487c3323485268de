//! The timed calls waiting to play, by when each is next due: a priority queue of one entry
//! per pending call ([`Timeline`]s make their steps when due), so a wake costs a heap pop per
//! call due, not a scan of every step of every call (issue 37: 990 pending `strobe`s once kept
//! 20 million steps in a list and took each out with `Vec::remove`, and `--timeout` waited
//! behind them). Sans-IO: [`super::run`] sleeps until [`Schedule::next`] and plays what
//! [`Schedule::due`] returns. A paced call (`spin`) waits out of the queue between its steps
//! until the player says its last step was answered ([`Schedule::answered`]).

use super::api::Act;
use super::timeline::Timeline;
use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;
use tokio::time::Instant;

/// What is due, in time order.
#[derive(Debug, Clone, PartialEq)]
pub enum Due {
    /// A step's actions.
    Acts(Vec<Act>),
    /// A paced call's step (`spin`): its actions, then [`Schedule::answered`] with `call`
    /// once they are answered, for its next step (or its end).
    Paced { call: u64, acts: Vec<Act> },
    /// A call is over: resolve its promise.
    Fire(u64),
}

/// One pending call: its timeline from `start`, the next step to play and when it is due.
#[derive(Debug)]
struct Entry {
    at: Instant,
    /// The order calls were made in: of two due at once, the earlier call plays first.
    seq: u64,
    start: Instant,
    next: u64,
    timeline: Timeline,
    fire: Option<u64>,
    /// A paced call whose last step was played: once answered, it ends.
    over: bool,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        (self.at, self.seq).cmp(&(other.at, other.seq))
    }
}

/// The pending timed calls.
#[derive(Debug, Default)]
pub struct Schedule {
    heap: BinaryHeap<Reverse<Entry>>,
    /// Paced calls waiting for their last step's answer (one entry each, out of the heap).
    waiting: Vec<Entry>,
    seq: u64,
}

impl Schedule {
    /// A call made at `start`: its steps, then `fire` (its promise) at its end.
    pub fn add(&mut self, start: Instant, timeline: Timeline, fire: Option<u64>) {
        let at = if timeline.is_empty() {
            start + timeline.end
        } else {
            start + timeline.at(0)
        };
        self.seq += 1;
        self.heap.push(Reverse(Entry {
            at,
            seq: self.seq,
            start,
            next: 0,
            timeline,
            fire,
            over: false,
        }));
    }

    /// The step a paced call played (`call`, from [`Due::Paced`]) was answered: its next
    /// step (or its end) is due at `at`. An unknown call is no one's.
    pub fn answered(&mut self, call: u64, at: Instant) {
        if let Some(i) = self.waiting.iter().position(|e| e.seq == call) {
            let mut e = self.waiting.swap_remove(i);
            e.at = at;
            self.heap.push(Reverse(e));
        }
    }

    /// When the next step or end is due (`None`: nothing pending).
    pub fn next(&self) -> Option<Instant> {
        self.heap.peek().map(|e| e.0.at)
    }

    /// When the next one-off move is due (`roll`'s or `rawMotor`'s stop; `None`: none
    /// pending). Spin's steps are not counted: a light that waited for them would wait for
    /// the whole spin.
    pub fn next_stop(&self) -> Option<Instant> {
        self.heap
            .iter()
            .filter(|e| {
                e.0.next == 0
                    && matches!(&e.0.timeline.steps, super::timeline::Steps::Once(_, acts)
                        if acts.iter().any(|a| matches!(a, Act::Drive { .. } | Act::Raw(..))))
            })
            .map(|e| e.0.at)
            .min()
    }

    /// How many calls are pending (one entry each, however many steps they have left).
    pub fn len(&self) -> usize {
        self.heap.len() + self.waiting.len()
    }

    pub fn is_empty(&self) -> bool {
        self.heap.is_empty() && self.waiting.is_empty()
    }

    /// What is due by `now`, in time order. A call late by several steps plays only the
    /// last of them (each step sets the whole state: [`super::timeline`]), so a wake plays
    /// at most one step and one end per pending call, however late it is.
    pub fn due(&mut self, now: Instant) -> Vec<Due> {
        let mut out = Vec::new();
        while self.heap.peek().is_some_and(|e| e.0.at <= now) {
            let Some(Reverse(mut e)) = self.heap.pop() else {
                break;
            };
            if e.timeline.paced() {
                if e.over {
                    if let Some(id) = e.fire {
                        out.push(Due::Fire(id));
                    }
                    continue;
                }
                let (acts, last) = e.timeline.spin_step(now.saturating_duration_since(e.start));
                e.over = last;
                out.push(Due::Paced { call: e.seq, acts });
                self.waiting.push(e);
                continue;
            }
            let len = e.timeline.len();
            if e.next >= len {
                if let Some(id) = e.fire {
                    out.push(Due::Fire(id));
                }
                continue;
            }
            let elapsed = now.saturating_duration_since(e.start);
            let step = e.timeline.last_due(e.next, elapsed).unwrap_or(e.next);
            out.push(Due::Acts(e.timeline.acts(step)));
            e.next = step.saturating_add(1);
            e.at = e.start
                + if e.next < len {
                    e.timeline.at(e.next)
                } else {
                    e.timeline.end
                };
            self.heap.push(Reverse(e));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edu::api::{Arg, Driver, Wait};
    use crate::model::Model;
    use std::time::Duration;

    fn timeline(d: &mut Driver, call: &str, args: &[f64]) -> Timeline {
        let args: Vec<Arg> = args.iter().map(|v| Arg::Num(*v)).collect();
        match d.call(call, &args).unwrap().wait {
            Some(Wait::Timeline(t)) => t,
            w => panic!("{call}: {w:?}"),
        }
    }

    #[tokio::test(start_paused = true)]
    async fn steps_play_in_time_order_and_each_call_ends_after_its_last_step() {
        let mut d = Driver::new(Model::Bolt);
        let mut s = Schedule::default();
        let t0 = Instant::now();
        s.add(
            t0,
            timeline(&mut d, "strobe", &[9.0, 0.0, 0.0, 0.1, 1.0]),
            Some(1),
        );
        s.add(t0, timeline(&mut d, "delay", &[0.1]), Some(2));
        let mut seen = Vec::new();
        while let Some(at) = s.next() {
            tokio::time::sleep_until(at).await;
            for due in s.due(Instant::now()) {
                seen.push((at - t0, due));
            }
        }
        let ms = Duration::from_millis;
        assert_eq!(
            seen,
            vec![
                (ms(0), Due::Acts(vec![Act::Main([0, 0, 0])])),
                // Both due at 100 ms: the strobe's step first (it was called first).
                (ms(100), Due::Acts(vec![Act::Main([9, 0, 0])])),
                (ms(100), Due::Fire(2)),
                (ms(200), Due::Fire(1)),
            ]
        );
        assert!(s.is_empty());
    }

    /// A light set just before a roll's stop is held for it (src/edu/run/lights.rs): the
    /// schedule tells when the next stop is due, and neither a spin's headings nor a
    /// strobe's or a delay's steps count as one.
    #[tokio::test(start_paused = true)]
    async fn the_next_stop_is_a_rolls_or_raw_motors_end_not_a_spins_step() {
        let mut d = Driver::new(Model::Mini);
        let mut s = Schedule::default();
        let t0 = Instant::now();
        s.add(t0, timeline(&mut d, "spin", &[360.0, 0.5]), Some(1));
        s.add(t0, timeline(&mut d, "delay", &[0.2]), Some(2));
        s.add(
            t0,
            timeline(&mut d, "strobe", &[9.0, 0.0, 0.0, 0.1, 3.0]),
            Some(3),
        );
        assert_eq!(s.next_stop(), None);
        s.add(t0, timeline(&mut d, "roll", &[0.0, 70.0, 1.5]), Some(4));
        s.add(
            t0,
            timeline(&mut d, "rawMotor", &[80.0, 80.0, 2.0]),
            Some(5),
        );
        assert_eq!(s.next_stop(), Some(t0 + Duration::from_millis(1_500)));
        tokio::time::advance(Duration::from_millis(1_500)).await;
        s.due(Instant::now());
        assert_eq!(s.next_stop(), Some(t0 + Duration::from_secs(2)));
        tokio::time::advance(Duration::from_millis(500)).await;
        s.due(Instant::now());
        assert_eq!(s.next_stop(), None);
    }

    /// spherov2's `spin` on a link with a 121 ms round trip (Mini's): a first step at once
    /// turned 0°, each next only once the one before was answered, its heading the turn at
    /// that time; the last once the turn rounds to the whole angle (past the 2 s asked), and
    /// the promise once that last step is answered.
    #[tokio::test(start_paused = true)]
    async fn a_spin_steps_once_per_answer_and_ends_after_its_last_step_is_answered() {
        let mut d = Driver::new(Model::Mini);
        let mut s = Schedule::default();
        let t0 = Instant::now();
        s.add(t0, timeline(&mut d, "spin", &[360.0, 2.0]), Some(7));
        let rtt = Duration::from_millis(121);
        let mut headings = Vec::new();
        let mut fired = None;
        for _ in 0..40 {
            let now = Instant::now();
            for due in s.due(now) {
                match due {
                    Due::Paced { call, acts } => {
                        let [Act::Drive { heading, .. }] = acts[..] else {
                            panic!("{acts:?}")
                        };
                        headings.push(((now - t0).as_millis(), heading));
                        // Nothing more until this step is answered, however late.
                        tokio::time::advance(rtt / 2).await;
                        assert!(s.due(Instant::now()).is_empty());
                        tokio::time::advance(rtt - rtt / 2).await;
                        s.answered(call, Instant::now());
                    }
                    Due::Fire(id) => fired = Some((id, (now - t0).as_millis())),
                    Due::Acts(a) => panic!("{a:?}"),
                }
            }
            if fired.is_some() {
                break;
            }
        }
        // round(k · 0.121 / 2 · 360), half to even: 0, 22 (21.78), 44 (43.56), …
        assert_eq!(headings[..4], [(0, 0), (121, 22), (242, 44), (363, 65)]);
        // 16 · 121 ms = 1.936 s turns 348°; 17 · 121 = 2.057 s is past 2 s: the whole turn.
        assert_eq!(headings[16], (1_936, 348));
        assert_eq!(headings.len(), 18);
        assert_eq!(headings[17], (2_057, 0));
        assert_eq!(fired, Some((7, 2_178)));
        assert!(s.is_empty());
    }

    /// One wake: what is due, each paced step answered at once (as a link with no round
    /// trip would).
    fn wake(s: &mut Schedule) -> Vec<Due> {
        let now = Instant::now();
        let due = s.due(now);
        for d in &due {
            if let Due::Paced { call, .. } = d {
                s.answered(*call, now);
            }
        }
        due
    }

    /// Issue 37: 990 pending hour-long spins and strobes are 1980 entries, not millions of
    /// steps, and a wake an hour late plays one step per call.
    #[tokio::test(start_paused = true)]
    async fn many_long_calls_pending_are_one_entry_each_and_a_late_wake_is_one_step_each() {
        let mut d = Driver::new(Model::Bolt);
        let mut s = Schedule::default();
        let t0 = Instant::now();
        for i in 0..990 {
            s.add(
                t0,
                timeline(&mut d, "spin", &[360.0 * 8_000.0, 1.0]),
                Some(i),
            );
            s.add(
                t0,
                timeline(&mut d, "strobe", &[255.0, 0.0, 0.0, 0.05, 36_000.0]),
                Some(1_000 + i),
            );
        }
        assert_eq!(s.len(), 1_980);
        // Ten simulated seconds in steps: at most one step per call each time.
        for _ in 0..200 {
            tokio::time::advance(Duration::from_millis(50)).await;
            let due = wake(&mut s);
            assert!(due.len() <= 1_980, "{}", due.len());
            assert_eq!(s.len(), 1_980);
        }
        // An hour late: one step per call, nothing over (the spins take 3600 s, the
        // strobes 3600 s).
        tokio::time::advance(Duration::from_secs(3_000)).await;
        let due = wake(&mut s);
        assert_eq!(due.len(), 1_980);
        assert_eq!(s.len(), 1_980);
        // Past the end: the strobes end; each spin plays its last step, and ends once it is
        // answered.
        tokio::time::advance(Duration::from_secs(600)).await;
        let due = wake(&mut s);
        let fired = due.iter().filter(|d| matches!(d, Due::Fire(_))).count();
        let last = due
            .iter()
            .filter(|d| matches!(d, Due::Paced { .. }))
            .count();
        assert_eq!((fired, last, s.len()), (990, 990, 990));
        tokio::time::advance(Duration::from_millis(1)).await;
        let due = wake(&mut s);
        let fired = due.iter().filter(|d| matches!(d, Due::Fire(_))).count();
        assert_eq!((fired, s.len()), (990, 0));
    }
}
