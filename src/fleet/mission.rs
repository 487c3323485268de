//! Missions on a fleet: each line goes to the droid it names (or to every droid), a
//! `together { … }` block runs every droid's lines at once, and the mission goes on when all
//! of them are done (`crate::script::fleet` has the language). Every droid samples from one
//! start, so `t_ms` lines up across droids; in the simulator, under paused time, the same
//! mission gives the same output every run.

use super::Fleet;
use crate::mission::{self, DroidMission, MissionError, MissionEvent, MissionOptions, Summary};
use crate::script::{Item, ScriptError, Step};
use futures_util::future::join_all;
use std::sync::Arc;
use tokio::time::Instant;

/// Where a fleet mission's events go: the droid's index in the fleet, and the event.
pub type FleetEmit = Arc<dyn Fn(usize, MissionEvent) + Send + Sync>;

/// The mission's lines with their droids resolved: for each item, (droid index, step) pairs.
pub struct Plan {
    /// Each item's lines: one item runs every droid's lines at once (each droid's in order)
    /// and ends when all are done; a plain line is an item of its own.
    items: Vec<Vec<(usize, Step)>>,
}

/// Resolve every `@NAME` against the fleet and check each line against its droid's model
/// (as [`mission::validate`] does for one droid): every problem, by line, before anything
/// is sent.
pub fn plan(fleet: &Fleet, items: &[Item]) -> Result<Plan, Vec<ScriptError>> {
    let mut errors = Vec::new();
    let mut plan = Plan { items: Vec::new() };
    let all: Vec<usize> = (0..fleet.len()).collect();
    for item in items {
        let mut pairs = Vec::new();
        for a in item.lines() {
            let targets = match &a.droid {
                None => all.clone(),
                Some(name) => match fleet.find(name) {
                    Ok(i) => vec![i],
                    Err(e) => {
                        errors.push(ScriptError {
                            line: a.step.line,
                            message: e.to_string(),
                        });
                        continue;
                    }
                },
            };
            for i in targets {
                let model = fleet.members()[i].model;
                match mission::validate(model, std::slice::from_ref(&a.step)) {
                    Ok(()) => pairs.push((i, a.step.clone())),
                    Err(e) => errors.extend(e.into_iter().map(|mut e| {
                        e.message = format!("{}: {}", fleet.members()[i].name, e.message);
                        e
                    })),
                }
            }
        }
        plan.items.push(pairs);
    }
    if errors.is_empty() {
        Ok(plan)
    } else {
        Err(errors)
    }
}

/// Run a planned mission on every droid of the fleet, each with its own options (`opts` in
/// fleet order; the last one's for droids past its end); one summary per droid, in fleet
/// order. A droid that cannot connect within its `connect_timeout` fails the mission before
/// a line is sent.
pub async fn run(
    fleet: &Fleet,
    plan: &Plan,
    opts: &[MissionOptions],
    emit: FleetEmit,
) -> Result<Vec<Summary>, MissionError> {
    let opts_of = |i: usize| opts.get(i).or(opts.last()).cloned().unwrap_or_default();
    // Connect everyone first (in parallel; a Bluetooth adapter's attempts take turns in
    // its gate), then start every droid's clock at once.
    let connected = join_all(fleet.members().iter().enumerate().map(|(i, m)| {
        let s = m.session.clone();
        let limit = opts_of(i).connect_timeout;
        async move { mission::await_connected(&s, limit).await }
    }))
    .await;
    for (m, r) in fleet.members().iter().zip(connected) {
        r.map_err(|e| MissionError(format!("{}: {e}", m.name)))?;
    }
    let start = Instant::now();
    let mut droids = Vec::with_capacity(fleet.len());
    for (i, m) in fleet.members().iter().enumerate() {
        let emit = emit.clone();
        let one: mission::Emit = Arc::new(move |e| emit(i, e));
        let d = DroidMission::start(&m.session, m.model, opts_of(i), one, start)
            .await
            .map_err(|e| MissionError(format!("{}: {e}", m.name)))?;
        droids.push(d);
    }
    for pairs in &plan.items {
        // Each droid's lines of this item, in order; the droids at once.
        let mut per: Vec<Vec<&Step>> = vec![Vec::new(); droids.len()];
        for (i, s) in pairs {
            per[*i].push(s);
        }
        join_all(droids.iter_mut().zip(per).map(|(d, steps)| async move {
            for s in steps {
                if d.closed() {
                    break;
                }
                d.step(s).await;
            }
        }))
        .await;
    }
    let finished = join_all(droids.into_iter().map(DroidMission::finish)).await;
    finished
        .into_iter()
        .zip(fleet.members())
        .map(|(r, m)| r.map_err(|e| MissionError(format!("{}: {e}", m.name))))
        .collect()
}
