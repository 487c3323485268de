//! When a program may start: once its droid is set up and its first sensor sample is in.
//!
//! Sphero's own examples read `getGyroscope().yaw` or `getAcceleration()` on their first
//! line; spherov2's `SpheroEduAPI` has its sensors streaming before the program's first call.
//! Started at once, a program read `null` for the first 0.35–1.1 s (the connect setup still
//! being paced out, issue 38). So the run waits until the setup is written and a sample holds
//! every reading the droid streams, bounded: a reading the droid never sends reads 0.

use crate::family::setup::SetupOptions;
use crate::model::Model;
use crate::session::SessionHandle;
use crate::sync::lock;
use crate::telemetry::Telemetry;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::time::{Instant, sleep};

/// The longest the connect setup may take to be written (eleven commands on R2-D2 at the
/// 120 ms pacing take 1.3 s).
const SETUP_LIMIT: Duration = Duration::from_secs(10);
/// The longest the first complete sample may take once the setup is written.
const SAMPLE_LIMIT: Duration = Duration::from_secs(5);
/// How often the telemetry is looked at while waiting.
const LOOK: Duration = Duration::from_millis(10);

/// The readings a program asks for by name, and whether `t` has each.
fn readings(t: &Telemetry) -> [(&'static str, bool); 5] {
    [
        ("location", t.x_cm.is_some() && t.y_cm.is_some()),
        ("velocity", t.velocity_cm_s.is_some()),
        (
            "orientation",
            t.pitch.is_some() && t.roll.is_some() && t.yaw.is_some(),
        ),
        ("acceleration", t.accel.is_some()),
        ("gyroscope", t.gyro.is_some()),
    ]
}

/// Wait until the droid behind `session` is set up and its telemetry holds every reading, or
/// a few sample intervals after its first sample (what is missing then is not streamed), or
/// the limits. Returns the readings still missing (empty for a droid that streams nothing:
/// there is nothing to wait for, and nothing is said).
pub async fn wait(
    session: &SessionHandle,
    telemetry: &Arc<Mutex<Telemetry>>,
    model: Model,
    setup: &SetupOptions,
) -> Vec<&'static str> {
    session.drained(SETUP_LIMIT).await;
    let plan = setup.stream_plan(model);
    if !plan.is_on() {
        return Vec::new();
    }
    // Two notifications a period on some droids (R2-D2's two masks): three periods hold a
    // whole sample, whatever its phase.
    let settle = Duration::from_millis(u64::from(plan.interval_ms) * 3 + 50);
    let end = Instant::now() + SAMPLE_LIMIT;
    let mut first: Option<Instant> = None;
    loop {
        let (samples, missing): (u64, Vec<&'static str>) = {
            let t = lock(telemetry);
            let missing = readings(&t)
                .into_iter()
                .filter(|(_, has)| !has)
                .map(|(name, _)| name)
                .collect();
            (t.samples, missing)
        };
        let now = Instant::now();
        if samples > 0 && first.is_none() {
            first = Some(now);
        }
        let settled = first.is_some_and(|f| now >= f + settle);
        if missing.is_empty() || settled || now >= end || session.is_closed() {
            return missing;
        }
        sleep(LOOK).await;
    }
}
