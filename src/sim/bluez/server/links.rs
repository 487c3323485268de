//! Connections and time: links going down, the droids' events (notifications, drops, sleep),
//! the wall-clock tick, and clients leaving the bus.

use super::*;

impl BluezSim {
    /// End device `i`'s connection: the droid first, then what BlueZ signals.
    pub(super) fn teardown(&mut self, i: usize, reason: &str) {
        let now = self.now();
        let _ = self.devices[i].droid.disconnect(now);
        self.link_down(i, reason);
    }

    /// Signal a connection gone (the droid already knows).
    pub(super) fn link_down(&mut self, i: usize, reason: &str) {
        let d = &mut self.devices[i];
        d.owner = None;
        d.motion_report = Some(Instant::now() + MOTION_REPORT_AFTER);
        for s in &mut d.services {
            for c in &mut s.chars {
                c.sessions.clear();
                c.value.clear();
            }
        }
        let exported = std::mem::replace(&mut d.exported, false);
        let path = d.path.clone();
        if exported {
            self.changed(&path, DEVICE, vec![("ServicesResolved", Val::Bool(false))]);
        }
        self.changed(&path, DEVICE, vec![("Connected", Val::Bool(false))]);
        if let (Ok(iface), Ok(member)) = (Interface::new(DEVICE), Member::new("Disconnected")) {
            let message = match reason {
                "org.bluez.Reason.Remote" => "Connection terminated by remote host",
                _ => "Connection terminated by local host",
            };
            self.send(Message::signal(&obj_path(&path), &iface, &member).append2(reason, message));
        }
        if exported {
            let d = &self.devices[i];
            let mut gone = Vec::new();
            for (j, s) in d.services.iter().enumerate() {
                for (k, c) in s.chars.iter().enumerate() {
                    gone.push((c.path.clone(), Obj::Char(i, j, k)));
                }
                gone.push((s.path.clone(), Obj::Service(i, j)));
            }
            for (p, o) in gone {
                self.removed(&p, o);
            }
        }
    }

    pub(super) fn on_event(&mut self, i: usize, e: GattEvent) {
        match e {
            GattEvent::Notification {
                characteristic,
                value,
            } => {
                let d = &mut self.devices[i];
                if !d.exported {
                    return;
                }
                let Some(c) = d
                    .services
                    .iter_mut()
                    .flat_map(|s| s.chars.iter_mut())
                    .find(|c| c.uuid == characteristic)
                else {
                    return;
                };
                c.value = value.clone();
                let path = c.path.clone();
                if self.trace {
                    let records = self.devices[i].tracer.notify(characteristic, &value);
                    self.trace_records(i, records);
                }
                self.changed(&path, CHARACTERISTIC, vec![("Value", Val::Bytes(value))]);
            }
            GattEvent::ServicesResolved => {
                let d = &mut self.devices[i];
                d.exported = true;
                let slow = !d.droid.faults().slow_resolve.is_zero();
                let objs: Vec<Obj> = d
                    .services
                    .iter()
                    .enumerate()
                    .flat_map(|(j, s)| {
                        std::iter::once(Obj::Service(i, j))
                            .chain((0..s.chars.len()).map(move |k| Obj::Char(i, j, k)))
                    })
                    .collect();
                for o in objs {
                    self.added(o);
                }
                let d = &self.devices[i];
                let path = d.path.clone();
                self.changed(
                    &path,
                    DEVICE,
                    vec![
                        ("UUIDs", Self::uuids(d)),
                        ("ServicesResolved", Val::Bool(true)),
                    ],
                );
                if slow {
                    let line = format!("{}: services resolved", self.devices[i].name());
                    self.say(line);
                }
            }
            GattEvent::Dropped { after } if self.devices[i].droid.status().asleep => {
                let line = format!(
                    "{}: fell asleep after {:.1} s without a command: dropped the connection \
                     after {:.2} s; no longer advertising",
                    self.devices[i].name(),
                    (self.devices[i]
                        .droid
                        .faults()
                        .idle_sleep
                        .unwrap_or_default()
                        + SLEEP_GRACE)
                        .as_secs_f64(),
                    after.as_secs_f64()
                );
                self.devices[i].asleep_said = true;
                self.link_down(i, "org.bluez.Reason.Remote");
                self.say(line);
            }
            GattEvent::Dropped { after } => {
                let d = &self.devices[i];
                let fault = if d.droid.faults().disconnect_every {
                    "disconnect-every"
                } else {
                    "disconnect-after"
                };
                let line = format!(
                    "{}: fault {fault}: dropped the connection after {:.2} s",
                    d.name(),
                    after.as_secs_f64()
                );
                self.link_down(i, "org.bluez.Reason.Remote");
                self.say(line);
            }
        }
    }

    pub(super) fn tick(&mut self) {
        for i in 0..self.devices.len() {
            if self.devices[i].refusing {
                self.answer_refusals(i, None);
            }
        }
        let now = self.now();
        for i in 0..self.devices.len() {
            let events = self.devices[i].droid.advance(now);
            for e in events {
                self.on_event(i, e);
            }
        }
        // A while after a disconnect: does the droid still roll? (Its fail-safe, if the host
        // set it, has stopped it by then.)
        for i in 0..self.devices.len() {
            let d = &mut self.devices[i];
            if d.motion_report.is_some_and(|t| Instant::now() >= t) {
                d.motion_report = None;
                if !d.connected() && !d.droid.status().asleep {
                    let v = d.droid.state().velocity_cm_s.abs();
                    let motion = if v >= 1.0 {
                        format!("still rolling at {v:.0} cm/s")
                    } else {
                        "stopped".to_string()
                    };
                    let line = format!(
                        "{}: {:.1} s after the disconnect: {motion}",
                        d.name(),
                        MOTION_REPORT_AFTER.as_secs_f64()
                    );
                    self.say(line);
                }
            }
        }
        for i in 0..self.devices.len() {
            let d = &self.devices[i];
            if d.droid.status().asleep && !d.asleep_said {
                let line = format!(
                    "{}: fell asleep after {:.1} s without a command; no longer advertising",
                    d.name(),
                    (d.droid.faults().idle_sleep.unwrap_or_default() + SLEEP_GRACE).as_secs_f64()
                );
                self.devices[i].asleep_said = true;
                self.say(line);
            }
        }
        if !self.adapter.discovering.is_empty() && Instant::now() >= self.next_rssi {
            self.next_rssi = Instant::now() + RSSI_EVERY;
            // Removed devices are heard again; the others' signal varies a little.
            self.hear_devices();
        }
    }

    /// A client left the bus: its discovery and notify sessions end, and so does the
    /// connection it made.
    pub(super) fn client_gone(&mut self, name: &str) {
        if self.adapter.discovering.remove(name) && self.adapter.discovering.is_empty() {
            self.changed(
                ADAPTER_PATH,
                ADAPTER,
                vec![("Discovering", Val::Bool(false))],
            );
            self.discovery_ended();
        }
        let now = self.now();
        for i in 0..self.devices.len() {
            let mut stopped = Vec::new();
            for s in &mut self.devices[i].services {
                for c in &mut s.chars {
                    if c.sessions.remove(name) && c.sessions.is_empty() {
                        stopped.push((c.uuid, c.path.clone()));
                    }
                }
            }
            for (uuid, path) in stopped {
                let _ = self.devices[i].droid.stop_notify(uuid, now);
                self.changed(&path, CHARACTERISTIC, vec![("Notifying", Val::Bool(false))]);
            }
            if self.devices[i].connected() && self.devices[i].owner.as_deref() == Some(name) {
                self.teardown(i, "org.bluez.Reason.Local");
                let line = format!(
                    "{}: disconnected (its client {name} left the bus)",
                    self.devices[i].name()
                );
                self.say(line);
            }
        }
        self.delayed.retain(|d| d.client != name);
        for i in 0..self.devices.len() {
            self.devices[i].refusing = self.delayed.iter().any(|d| d.dev == i);
        }
    }
}
