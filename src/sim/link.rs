//! The simulated droid behind the [`Link`] trait: an in-process connection that delivers the
//! droid's bytes in pieces of at most 20 bytes, with the configured faults, on tokio time.

use super::{Faults, SimConfig, SimState, WireDroid, wire_droid};
use crate::gatt::Endpoint;
use crate::link::{Connection, Link, LinkError, LinkEvent, LinkWriter};
use crate::model::Model;
use crate::rng::Rng;
use crate::sync::lock;
use futures_util::future::BoxFuture;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::{Instant, sleep_until};

/// The ATT payload: no notification carries more.
const NOTIFY_MAX: usize = 20;

struct Shared {
    droid: Box<dyn WireDroid>,
    rng: Rng,
    /// Index of the next scheduled disconnect.
    next_disconnect: usize,
    opens: u32,
    connected: bool,
}

/// Read access to the simulated droid, for tests and the `run` command.
#[derive(Clone)]
pub struct SimProbe {
    shared: Arc<Mutex<Shared>>,
    epoch: Instant,
}

impl SimProbe {
    /// The droid's state, brought up to the current time.
    pub fn state(&self) -> SimState {
        let mut s = lock(&self.shared);
        let now = Instant::now().duration_since(self.epoch);
        // Advancing here only integrates physics; any notifications it produces are not lost
        // for a connected host because the pump advances the same droid and they are kept
        // only when nobody is connected.
        if !s.connected {
            let _ = s.droid.advance(now);
        }
        s.droid.state().clone()
    }

    pub fn connected(&self) -> bool {
        lock(&self.shared).connected
    }

    /// Put the droid on its charger or take it off, now (what a person does; the droid
    /// reports it at its next step).
    pub fn set_on_charger(&self, on: bool) {
        let mut s = lock(&self.shared);
        let now = Instant::now().duration_since(self.epoch);
        if !s.connected {
            let _ = s.droid.advance(now);
        }
        s.droid.set_on_charger(on);
    }

    pub fn opens(&self) -> u32 {
        lock(&self.shared).opens
    }
}

/// A link to a simulated droid.
pub struct SimLink {
    shared: Arc<Mutex<Shared>>,
    faults: Arc<Faults>,
    epoch: Instant,
    model: Model,
    step: Duration,
}

impl SimLink {
    /// A simulated droid of `model`. Create it inside the tokio runtime that will drive it.
    pub fn new(model: Model, cfg: SimConfig, faults: Faults) -> Self {
        let droid = wire_droid(model, cfg.clone());
        SimLink::with_droid(model, droid, &cfg, faults)
    }

    /// A link to `droid` (a simulator front of `model`, perhaps wrapped to watch it), stepped
    /// at `cfg`'s physics step.
    pub fn with_droid(
        model: Model,
        droid: Box<dyn WireDroid>,
        cfg: &SimConfig,
        faults: Faults,
    ) -> Self {
        let step = cfg.step.max(Duration::from_millis(1));
        let rng = Rng::new(faults.seed);
        SimLink {
            shared: Arc::new(Mutex::new(Shared {
                droid,
                rng,
                next_disconnect: 0,
                opens: 0,
                connected: false,
            })),
            faults: Arc::new(faults),
            epoch: Instant::now(),
            model,
            step,
        }
    }

    pub fn probe(&self) -> SimProbe {
        SimProbe {
            shared: self.shared.clone(),
            epoch: self.epoch,
        }
    }
}

struct SimWriter {
    tx: Option<mpsc::Sender<(Endpoint, Vec<u8>)>>,
}

impl LinkWriter for SimWriter {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_to(Endpoint::Api, chunk)
    }

    fn write_to<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        Box::pin(async move {
            let tx = self
                .tx
                .as_ref()
                .ok_or_else(|| LinkError::transient("the simulated link is closed"))?;
            tx.send((to, chunk.to_vec()))
                .await
                .map_err(|_| LinkError::transient("the simulated droid disconnected"))
        })
    }

    fn close(&mut self) -> BoxFuture<'_, ()> {
        self.tx = None;
        Box::pin(async {})
    }
}

impl Link for SimLink {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            {
                let mut s = lock(&self.shared);
                s.opens += 1;
                if s.opens <= self.faults.fail_opens {
                    return Err(LinkError::transient(format!(
                        "simulated connect failure ({} of {})",
                        s.opens, self.faults.fail_opens
                    )));
                }
                s.connected = true;
                // Scheduled drops that fell while the link was down are gone, not pending.
                let now = Instant::now().duration_since(self.epoch);
                while self
                    .faults
                    .disconnect_at
                    .get(s.next_disconnect)
                    .is_some_and(|d| *d <= now)
                {
                    s.next_disconnect += 1;
                }
            }
            let (write_tx, write_rx) = mpsc::channel(64);
            let (event_tx, event_rx) = mpsc::channel(1024);
            // What the host reads while connecting (Robi's handshake) comes first.
            let read = {
                let mut s = lock(&self.shared);
                let now = Instant::now().duration_since(self.epoch);
                s.droid.connect(now)
            };
            for v in read {
                let _ = event_tx.try_send(LinkEvent::Data(v));
            }
            let pump = Pump {
                shared: self.shared.clone(),
                faults: self.faults.clone(),
                epoch: self.epoch,
                step: self.step,
                inbound: VecDeque::new(),
                outbound: VecDeque::new(),
                last_in: Instant::now(),
                last_out: Instant::now(),
            };
            tokio::spawn(pump.run(write_rx, event_tx));
            Ok(Connection {
                writer: Box::new(SimWriter { tx: Some(write_tx) }),
                events: event_rx,
            })
        })
    }

    fn describe(&self) -> String {
        format!("{} (simulated)", self.model.display_name())
    }
}

/// Moves bytes between one connection and the droid, and keeps its clock running.
struct Pump {
    shared: Arc<Mutex<Shared>>,
    faults: Arc<Faults>,
    epoch: Instant,
    step: Duration,
    inbound: VecDeque<(Instant, Endpoint, Vec<u8>)>,
    outbound: VecDeque<(Instant, Vec<u8>)>,
    last_in: Instant,
    last_out: Instant,
}

impl Pump {
    fn sim_time(&self) -> Duration {
        Instant::now().duration_since(self.epoch)
    }

    /// Mangle, cut and schedule the droid's encoded packets.
    fn deliver(&mut self, packets: Vec<Vec<u8>>, s: &mut Shared) {
        if packets.is_empty() {
            return;
        }
        let now = Instant::now();
        let bytes = packets.concat();
        let bytes = self.faults.mangle(&mut s.rng, &bytes);
        let pieces = if s.droid.whole_notifications() {
            // One notification per packet, never cut (RSRCP over BLE).
            let mut out = Vec::new();
            let mut rest = bytes.as_slice();
            for p in &packets {
                let len = p.len().min(rest.len());
                out.push(rest[..len].to_vec());
                rest = &rest[len..];
            }
            out
        } else if self.faults.split {
            self.faults.pieces(&mut s.rng, &bytes, NOTIFY_MAX)
        } else {
            // One notification per packet, each cut at 20 bytes.
            let mut out = Vec::new();
            let mut bytes = bytes.as_slice();
            for p in &packets {
                let len = p.len().min(bytes.len());
                out.extend(self.faults.pieces(&mut s.rng, &bytes[..len], NOTIFY_MAX));
                bytes = &bytes[len..];
            }
            if !bytes.is_empty() {
                out.extend(self.faults.pieces(&mut s.rng, bytes, NOTIFY_MAX));
            }
            out
        };
        for piece in pieces {
            let at = (now + self.faults.delay(&mut s.rng)).max(self.last_out);
            self.last_out = at;
            self.outbound.push_back((at, piece));
        }
    }

    fn next_disconnect(&self) -> Option<Instant> {
        let s = lock(&self.shared);
        self.faults
            .disconnect_at
            .get(s.next_disconnect)
            .map(|d| self.epoch + *d)
    }

    async fn run(
        mut self,
        mut writes: mpsc::Receiver<(Endpoint, Vec<u8>)>,
        events: mpsc::Sender<LinkEvent>,
    ) {
        let mut next_tick = Instant::now() + self.step;
        let reason = loop {
            // Step the droid only when it has something to say: at rest, the next physics
            // step on the same grid at or after its next event (a sample, a stance change
            // ending); rolling, every step. Its notifications come out at the same times.
            let now = Instant::now();
            if next_tick < now {
                // Slept past ticks at rest: back onto the grid.
                let behind = (now - next_tick).as_nanos().div_ceil(self.step.as_nanos());
                next_tick += self.step * behind.min(u32::MAX as u128) as u32;
            }
            let due = lock(&self.shared).droid.next_due();
            let wake = match due {
                None => next_tick,
                Some(d) => {
                    let at = self
                        .epoch
                        .checked_add(d)
                        .unwrap_or(next_tick + self.step * 1000);
                    if at <= next_tick {
                        next_tick
                    } else {
                        let steps = (at - next_tick).as_nanos().div_ceil(self.step.as_nanos());
                        next_tick + self.step * steps.min(u32::MAX as u128) as u32
                    }
                }
            };
            let disconnect = self.next_disconnect();
            let next_in = self.inbound.front().map(|(t, _, _)| *t);
            let next_out = self.outbound.front().map(|(t, _)| *t);
            tokio::select! {
                biased;
                _ = sleep_until(disconnect.unwrap_or_else(Instant::now)), if disconnect.is_some() => {
                    lock(&self.shared).next_disconnect += 1;
                    break Some("simulated link loss".to_string());
                }
                w = writes.recv() => match w {
                    Some((to, bytes)) => {
                        let mut s = lock(&self.shared);
                        let bytes = self.faults.mangle(&mut s.rng, &bytes);
                        let at = (Instant::now() + self.faults.delay(&mut s.rng)).max(self.last_in);
                        drop(s);
                        self.last_in = at;
                        self.inbound.push_back((at, to, bytes));
                    }
                    None => {
                        // The host closed the link: what it wrote before still reaches the
                        // droid (a final stop must not be lost).
                        let now = self.sim_time();
                        let mut s = lock(&self.shared);
                        for (_, to, bytes) in self.inbound.drain(..) {
                            let _ = s.droid.receive_at(to, &bytes, now);
                        }
                        break None;
                    }
                },
                _ = sleep_until(next_in.unwrap_or_else(Instant::now)), if next_in.is_some() => {
                    if let Some((_, to, bytes)) = self.inbound.pop_front() {
                        let now = self.sim_time();
                        let shared = self.shared.clone();
                        let mut s = lock(&shared);
                        let out = s.droid.receive_at(to, &bytes, now);
                        self.deliver(out, &mut s);
                    }
                }
                _ = sleep_until(next_out.unwrap_or_else(Instant::now)), if next_out.is_some() => {
                    if let Some((_, piece)) = self.outbound.pop_front()
                        && events.send(LinkEvent::Data(piece)).await.is_err() {
                            break None;
                        }
                }
                _ = sleep_until(wake) => {
                    next_tick = wake + self.step;
                    let now = self.sim_time();
                    let shared = self.shared.clone();
                    let mut s = lock(&shared);
                    let out = s.droid.advance(now);
                    self.deliver(out, &mut s);
                }
            }
        };
        {
            let now = self.sim_time();
            let mut s = lock(&self.shared);
            s.connected = false;
            s.droid.disconnected(now);
        }
        if let Some(reason) = reason {
            let _ = events.send(LinkEvent::Disconnected(reason)).await;
        }
    }
}
