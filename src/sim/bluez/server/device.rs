//! Device calls: Connect (one attempt at a time per adapter, as BlueZ allows: another
//! device's Connect meanwhile gets `org.bluez.Error.InProgress`; refusals and aborts as BlueZ
//! gives them) and Disconnect.

use super::*;

impl BluezSim {
    pub(super) fn device_call(
        &mut self,
        msg: Message,
        i: usize,
        member: &str,
        client: String,
        now: Duration,
    ) -> Option<Message> {
        match member {
            "Connect" => self.connect_device(msg, i, client, now),
            "Disconnect" => {
                if self.devices[i].refusing {
                    // Cancels the attempt under way.
                    self.answer_refusals(i, Some("Operation was cancelled"));
                    return Some(msg.method_return());
                }
                if !self.devices[i].connected() {
                    return Some(error(&msg, ERR_NOT_CONNECTED, "Not Connected"));
                }
                self.teardown(i, "org.bluez.Reason.Local");
                let line = format!(
                    "{}: disconnected by the client ({client})",
                    self.devices[i].name()
                );
                self.say(line);
                Some(msg.method_return())
            }
            "Pair" | "ConnectProfile" | "DisconnectProfile" => {
                Some(error(&msg, ERR_NOT_SUPPORTED, "Operation is not supported"))
            }
            "CancelPairing" => Some(error(&msg, ERR_DOES_NOT_EXIST, "Does Not Exist")),
            _ => Some(error(
                &msg,
                ERR_DBUS_UNKNOWN_METHOD,
                &format!("Unknown method '{member}'"),
            )),
        }
    }

    pub(super) fn connect_device(
        &mut self,
        msg: Message,
        i: usize,
        client: String,
        now: Duration,
    ) -> Option<Message> {
        if !self.adapter.powered {
            return Some(error(&msg, ERR_NOT_READY, "Resource Not Ready"));
        }
        let d = &self.devices[i];
        if d.refusing {
            return Some(error(&msg, ERR_IN_PROGRESS, "In Progress"));
        }
        if d.blocked {
            return Some(error(&msg, ERR_FAILED, "Device is blocked"));
        }
        // One LE connection attempt at a time per adapter, as BlueZ has it.
        if let Some(other) = self.devices.iter().find(|o| o.refusing) {
            let line = format!(
                "{}: connection attempt from {client} while {}'s is under way: {ERR_IN_PROGRESS}",
                self.devices[i].name(),
                other.name()
            );
            self.say(line);
            return Some(error(
                &msg,
                ERR_IN_PROGRESS,
                "Operation already in progress",
            ));
        }
        let d = &self.devices[i];
        if d.remembered || d.droid.status().asleep {
            // Nobody answers: BlueZ gives up after a while.
            let why = if d.remembered {
                "remembered, not in range"
            } else {
                "asleep"
            };
            let line = format!(
                "{}: connection attempt from {client}: {why}, it fails in {} s",
                d.name(),
                ABSENT_AFTER.as_secs()
            );
            self.say(line);
            self.devices[i].refusing = true;
            self.delayed.push(Delayed {
                at: Instant::now() + ABSENT_AFTER,
                dev: i,
                client,
                call: msg,
            });
            return None;
        }
        if d.connected() {
            if d.owner.as_deref() == Some(client.as_str()) {
                return Some(msg.method_return());
            }
            // The droid holds one connection.
            let line = format!(
                "{}: refused a connection from {client}: it is connected to {}",
                d.name(),
                d.owner.as_deref().unwrap_or("another client")
            );
            self.say(line);
            return Some(error(&msg, ERR_FAILED, ABORTED));
        }
        match self.devices[i].droid.connect(now) {
            Ok(()) => {
                let d = &mut self.devices[i];
                d.tracer.reset();
                d.motion_report = None;
                d.owner = Some(client.clone());
                let path = d.path.clone();
                let slow = d.droid.faults().slow_resolve;
                self.changed(&path, DEVICE, vec![("Connected", Val::Bool(true))]);
                let mut line = format!("{}: connected ({client})", self.devices[i].name());
                if !slow.is_zero() {
                    line.push_str(&format!(
                        "; fault slow-resolve: services resolve in {:.1} s",
                        slow.as_secs_f64()
                    ));
                }
                self.say(line);
                Some(msg.method_return())
            }
            Err(GattError::Refused) => {
                let line = format!(
                    "{}: fault refuse-connect: refusing the connection from {client}",
                    self.devices[i].name()
                );
                self.say(line);
                self.devices[i].refusing = true;
                self.delayed.push(Delayed {
                    at: Instant::now() + REFUSE_AFTER,
                    dev: i,
                    client,
                    call: msg,
                });
                None
            }
            Err(e) => Some(gatt_error(&msg, &e)),
        }
    }

    /// Answer the refused connection attempts to device `i` (all of them, or those due).
    pub(super) fn answer_refusals(&mut self, i: usize, cancelled: Option<&str>) {
        let now = Instant::now();
        let (due, keep): (Vec<Delayed>, Vec<Delayed>) = std::mem::take(&mut self.delayed)
            .into_iter()
            .partition(|d| d.dev == i && (cancelled.is_some() || d.at <= now));
        self.delayed = keep;
        for d in due {
            let text = cancelled.unwrap_or(ABORTED);
            self.send(error(&d.call, ERR_FAILED, text));
        }
        self.devices[i].refusing = self.delayed.iter().any(|d| d.dev == i);
    }
}
