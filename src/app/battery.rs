//! The battery poller: a background task asks a live droid its battery voltage every
//! [`BATTERY_EVERY`] (on families that can say) and sends the readings to the event loop.

use crate::family::Family;
use crate::session::SessionHandle;
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::task::JoinHandle;

pub const BATTERY_EVERY: Duration = Duration::from_secs(10);

/// Start polling; the task ends when the receiver goes or the family has no battery reading.
/// A replay (`None`) gets a receiver that closes at once.
pub fn spawn(
    session: Option<SessionHandle>,
    family: &'static dyn Family,
    model: crate::model::Model,
) -> (JoinHandle<()>, mpsc::Receiver<f32>) {
    let (tx, rx) = mpsc::channel::<f32>(4);
    let task = tokio::spawn(async move {
        let Some(session) = session else {
            return;
        };
        let Some(battery) = family.battery_request_for(model) else {
            return;
        };
        loop {
            let reading = match session.request(battery.clone()).await {
                Ok(p) => family.battery_volts_for(model, p.data()),
                Err(_) => None,
            };
            if let Some(v) = reading
                && tx.send(v).await.is_err()
            {
                return;
            }
            tokio::time::sleep(BATTERY_EVERY).await;
        }
    });
    (task, rx)
}
