//! [`GattBackend`] over simulated droids at the GATT level ([`GattDroid`], the same core as
//! `droidctl sim --bluez`): `droidctl serve --sim`. Each droid enforces its model's
//! handshake, so a client must unlock it as it would a real one; its notifications are cut
//! as a droid cuts them. Time is tokio's, so tests may pause it.

use super::backend::{
    BackendDevice, BackendError, Connected, DroidEvent, GattBackend, GattConnection, Pose,
};
use crate::gatt::GattUuid;
use crate::model::Model;
use crate::sim::gatt::{GattDroid, GattEvent, GattFaults};
use crate::sim::{SimConfig, SimState};
use crate::sync::lock;
use futures_util::future::BoxFuture;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::Instant;

/// How often a connected droid is advanced (its notifications collected).
const STEP: Duration = Duration::from_millis(10);
/// Longest wait for service resolution (the `slow-resolve` fault).
const RESOLVE_MAX: Duration = Duration::from_secs(10);
/// Notifications waiting for the client task; beyond, the oldest news is dropped.
const EVENTS: usize = 1024;

struct SimSlot {
    name: String,
    address: String,
    model: Model,
    droid: Mutex<GattDroid>,
}

/// Simulated droids, found by scans and connected by address.
pub struct SimBackend {
    slots: Vec<Arc<SimSlot>>,
    epoch: Instant,
}

/// The advertised name of the `i`-th simulated droid of `model` (`D2-0001`).
pub fn sim_name(model: Model, i: usize) -> String {
    match model.name_prefix() {
        Some(p) => format!("{p}{:04X}", i + 1),
        None => model.display_name().to_string(),
    }
}

/// The address of the `i`-th simulated droid: `5E:D0:00:00:00:01` and on.
pub fn sim_address(i: usize) -> String {
    format!("5E:D0:00:00:{:02X}:{:02X}", (i >> 8) & 0xff, (i + 1) & 0xff)
}

impl SimBackend {
    /// One simulated droid per model, in order, all in one room (as a `--sim` fleet's: they
    /// see the same walls, collide, and reach each other in infrared). Create it inside the
    /// runtime that serves.
    pub fn new(models: &[Model], faults: GattFaults) -> Self {
        let room = crate::sim::room::SharedRoom::new();
        let origins = crate::sim::room::SharedRoom::origins(models.len());
        let slots = models
            .iter()
            .zip(origins)
            .enumerate()
            .map(|(i, (&model, origin))| {
                let mut cfg = SimConfig::for_model(model);
                cfg.place = Some(room.place(origin, cfg.radius_cm));
                Arc::new(SimSlot {
                    name: sim_name(model, i),
                    address: sim_address(i),
                    model,
                    droid: Mutex::new(GattDroid::new(model, cfg, faults.clone())),
                })
            })
            .collect();
        SimBackend {
            slots,
            epoch: Instant::now(),
        }
    }

    /// The droids: name, address, model.
    pub fn devices(&self) -> Vec<(String, String, Model)> {
        self.slots
            .iter()
            .map(|s| (s.name.clone(), s.address.clone(), s.model))
            .collect()
    }

    fn now(&self) -> Duration {
        self.epoch.elapsed()
    }

    /// The droid at `address`, its body brought up to now when nobody is connected (the
    /// connection's pump advances it otherwise).
    pub fn state(&self, address: &str) -> Option<SimState> {
        let slot = self.slot(address)?;
        let mut d = lock(&slot.droid);
        if !d.status().connected {
            let _ = d.advance(self.now());
        }
        Some(d.state().clone())
    }

    /// Whether a client holds the droid at `address`.
    pub fn connected(&self, address: &str) -> bool {
        self.slot(address)
            .is_some_and(|s| lock(&s.droid).status().connected)
    }

    fn slot(&self, address: &str) -> Option<&Arc<SimSlot>> {
        self.slots
            .iter()
            .find(|s| s.address.eq_ignore_ascii_case(address.trim()))
    }

    fn device(s: &SimSlot) -> BackendDevice {
        BackendDevice {
            name: s.name.clone(),
            address: s.address.clone(),
        }
    }

    async fn connect_sim(&self, address: &str) -> Result<Connected, BackendError> {
        let slot = self
            .slot(address)
            .ok_or_else(|| BackendError(format!("no simulated droid at {address}")))?
            .clone();
        lock(&slot.droid)
            .connect(self.now())
            .map_err(|e| BackendError(format!("{}: {e}", slot.name)))?;
        // Service discovery, as BlueZ waits for ServicesResolved.
        let deadline = Instant::now() + RESOLVE_MAX;
        loop {
            let resolved = {
                let mut d = lock(&slot.droid);
                let evs = d.advance(self.now());
                if evs.iter().any(|e| matches!(e, GattEvent::Dropped { .. })) {
                    return Err(format!("{} dropped the connection", slot.name).into());
                }
                d.status().services_resolved
            };
            if resolved {
                break;
            }
            if Instant::now() >= deadline {
                let _ = lock(&slot.droid).disconnect(self.now());
                return Err(format!("{}: service discovery timed out", slot.name).into());
            }
            tokio::time::sleep(STEP).await;
        }
        let (tx, rx) = mpsc::channel(EVENTS);
        let pump = tokio::spawn(pump(slot.clone(), self.epoch, tx.clone()));
        Ok(Connected {
            connection: Box::new(SimConnection {
                slot: slot.clone(),
                epoch: self.epoch,
                tx,
                pump,
                open: true,
            }),
            events: rx,
            name: slot.name.clone(),
            model: Some(slot.model),
            stop_as: Some(slot.model),
        })
    }
}

/// Forward what the droid reports to the connection's events.
fn forward(events: Vec<GattEvent>, tx: &mpsc::Sender<DroidEvent>) -> bool {
    for e in events {
        match e {
            GattEvent::Notification {
                characteristic,
                value,
            } => {
                if tx
                    .try_send(DroidEvent::Notification {
                        characteristic,
                        value,
                    })
                    .is_err()
                {
                    tracing::debug!("simulated droid: notification dropped (nobody reading)");
                }
            }
            GattEvent::ServicesResolved => {}
            GattEvent::Dropped { after } => {
                let _ = tx.try_send(DroidEvent::Disconnected(format!(
                    "the simulated droid dropped the link after {:.1} s",
                    after.as_secs_f64()
                )));
                return false;
            }
        }
    }
    true
}

/// Advance a connected droid every [`STEP`] until it drops the link or the connection ends.
async fn pump(slot: Arc<SimSlot>, epoch: Instant, tx: mpsc::Sender<DroidEvent>) {
    let mut tick = tokio::time::interval(STEP);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tick.tick().await;
        let events = {
            let mut d = lock(&slot.droid);
            if !d.status().connected {
                return;
            }
            d.advance(epoch.elapsed())
        };
        if !forward(events, &tx) || tx.is_closed() {
            return;
        }
    }
}

struct SimConnection {
    slot: Arc<SimSlot>,
    epoch: Instant,
    tx: mpsc::Sender<DroidEvent>,
    pump: tokio::task::JoinHandle<()>,
    open: bool,
}

impl SimConnection {
    fn check(&self) -> Result<(), BackendError> {
        if self.open {
            Ok(())
        } else {
            Err("the connection is closed".into())
        }
    }
}

impl GattConnection for SimConnection {
    fn write<'a>(
        &'a mut self,
        ch: GattUuid,
        data: &'a [u8],
    ) -> BoxFuture<'a, Result<(), BackendError>> {
        Box::pin(async move {
            self.check()?;
            let events = {
                let mut d = lock(&self.slot.droid);
                let now = self.epoch.elapsed();
                d.write(ch, data, now)
                    .map_err(|e| BackendError(e.to_string()))?;
                // The answer at once rather than at the next step.
                d.advance(now)
            };
            forward(events, &self.tx);
            Ok(())
        })
    }

    fn subscribe(&mut self, ch: GattUuid) -> BoxFuture<'_, Result<(), BackendError>> {
        Box::pin(async move {
            self.check()?;
            lock(&self.slot.droid)
                .start_notify(ch, self.epoch.elapsed())
                .map_err(|e| BackendError(e.to_string()))
        })
    }

    fn pose(&mut self) -> Option<Pose> {
        let mut d = lock(&self.slot.droid);
        // Brought up to now: the pump may be a step behind.
        forward(d.advance(self.epoch.elapsed()), &self.tx);
        let s = d.state();
        Some(Pose {
            x_cm: s.x_cm,
            y_cm: s.y_cm,
            yaw_deg: s.yaw_deg,
        })
    }

    fn disconnect(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async move {
            if std::mem::replace(&mut self.open, false) {
                self.pump.abort();
                let _ = lock(&self.slot.droid).disconnect(self.epoch.elapsed());
            }
        })
    }
}

impl Drop for SimConnection {
    fn drop(&mut self) {
        if self.open {
            self.pump.abort();
            let _ = lock(&self.slot.droid).disconnect(self.epoch.elapsed());
        }
    }
}

impl GattBackend for SimBackend {
    fn scan(&self, _t: Duration) -> BoxFuture<'_, Result<Vec<BackendDevice>, BackendError>> {
        // Simulated droids are heard at once.
        Box::pin(async move { Ok(self.slots.iter().map(|s| Self::device(s)).collect()) })
    }

    fn find<'a>(
        &'a self,
        name: &'a str,
        _t: Duration,
    ) -> BoxFuture<'a, Result<Option<BackendDevice>, BackendError>> {
        Box::pin(async move {
            Ok(self
                .slots
                .iter()
                .find(|s| s.name == name)
                .map(|s| Self::device(s)))
        })
    }

    fn connect<'a>(&'a self, address: &'a str) -> BoxFuture<'a, Result<Connected, BackendError>> {
        Box::pin(self.connect_sim(address))
    }

    fn describe(&self) -> String {
        let names: Vec<String> = self
            .slots
            .iter()
            .map(|s| format!("{} {} ({})", s.model.display_name(), s.name, s.address))
            .collect();
        format!("simulated droids: {}", names.join(", "))
    }
}
