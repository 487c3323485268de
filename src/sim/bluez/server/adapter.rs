//! The adapter: power, discovery sessions, and the devices a discovery hears.

use super::*;

impl BluezSim {
    pub(super) fn set_powered(&mut self, on: bool) {
        if self.adapter.powered == on {
            return;
        }
        self.adapter.powered = on;
        let mut props = vec![
            ("Powered", Val::Bool(on)),
            ("PowerState", Val::Str(if on { "on" } else { "off" }.into())),
        ];
        if !on {
            // As BlueZ powering the controller off: attempts under way fail, connections
            // drop, discovery ends (and with it every RSSI).
            for i in 0..self.devices.len() {
                if self.devices[i].refusing {
                    self.answer_refusals(i, Some("Software caused connection abort"));
                }
                if self.devices[i].connected() {
                    self.teardown(i, "org.bluez.Reason.Local");
                    let line = format!("{}: disconnected (adapter off)", self.devices[i].name());
                    self.say(line);
                }
            }
            if !self.adapter.discovering.is_empty() {
                self.adapter.discovering.clear();
                props.push(("Discovering", Val::Bool(false)));
                self.discovery_ended();
            }
        }
        self.say(format!("adapter powered {}", if on { "on" } else { "off" }));
        self.changed(ADAPTER_PATH, ADAPTER, props);
    }

    /// The adapter's discovery stopped: BlueZ forgets what it heard (the RSSIs).
    pub(super) fn discovery_ended(&mut self) {
        for i in 0..self.devices.len() {
            if self.devices[i].rssi.take().is_some() && self.devices[i].known {
                let path = self.devices[i].path.clone();
                self.invalidated(&path, DEVICE, &["RSSI"]);
            }
        }
    }

    pub(super) fn adapter_call(&mut self, msg: &Message, member: &str, client: &str) -> Message {
        match member {
            "StartDiscovery" => {
                if !self.adapter.powered {
                    return error(msg, ERR_NOT_READY, "Resource Not Ready");
                }
                if !self.adapter.discovering.insert(client.to_string()) {
                    return error(msg, ERR_IN_PROGRESS, "Operation already in progress");
                }
                if self.adapter.discovering.len() == 1 {
                    self.changed(
                        ADAPTER_PATH,
                        ADAPTER,
                        vec![("Discovering", Val::Bool(true))],
                    );
                    // Droids advertise several times a second: heard at once.
                    self.hear_devices();
                    self.next_rssi = Instant::now() + RSSI_EVERY;
                }
                msg.method_return()
            }
            "StopDiscovery" => {
                if !self.adapter.powered {
                    return error(msg, ERR_NOT_READY, "Resource Not Ready");
                }
                if !self.adapter.discovering.remove(client) {
                    return error(msg, ERR_FAILED, "No discovery started");
                }
                if self.adapter.discovering.is_empty() {
                    self.changed(
                        ADAPTER_PATH,
                        ADAPTER,
                        vec![("Discovering", Val::Bool(false))],
                    );
                    self.discovery_ended();
                }
                msg.method_return()
            }
            "SetDiscoveryFilter" => match msg.read1::<PropMap>() {
                // Every droid matches any filter a droid client sets; others are ignored.
                Ok(_) => msg.method_return(),
                Err(_) => invalid_args(msg),
            },
            "GetDiscoveryFilters" => msg.method_return().append1(
                [
                    "UUIDs",
                    "RSSI",
                    "Pathloss",
                    "Transport",
                    "DuplicateData",
                    "Discoverable",
                    "Pattern",
                ]
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>(),
            ),
            "RemoveDevice" => {
                let Ok(target) = msg.read1::<Path>() else {
                    return invalid_args(msg);
                };
                let target = target.to_string();
                let Some(i) = self
                    .devices
                    .iter()
                    .position(|d| d.known && d.path == target)
                else {
                    return error(msg, ERR_DOES_NOT_EXIST, "Does Not Exist");
                };
                if self.devices[i].connected() {
                    self.teardown(i, "org.bluez.Reason.Local");
                    let line = format!("{}: disconnected (removed)", self.devices[i].name());
                    self.say(line);
                }
                self.devices[i].known = false;
                let path = self.devices[i].path.clone();
                self.removed(&path, Obj::Device(i));
                msg.method_return()
            }
            _ => error(
                msg,
                ERR_DBUS_UNKNOWN_METHOD,
                &format!("Unknown method '{member}'"),
            ),
        }
    }

    /// A discovery hears every droid that advertises: new ones appear on the bus, the
    /// others' signal strength varies a little. Connected, asleep and remembered ones are
    /// not heard.
    pub(super) fn hear_devices(&mut self) {
        for i in 0..self.devices.len() {
            if !self.devices[i].advertising() {
                continue;
            }
            let jitter = self.rng.below(7) as i16 - 3;
            let d = &mut self.devices[i];
            let rssi = d.spec.rssi + jitter;
            d.rssi = Some(rssi);
            if !d.known {
                d.known = true;
                self.added(Obj::Device(i));
            } else {
                let path = d.path.clone();
                self.changed(&path, DEVICE, vec![("RSSI", Val::I16(rssi))]);
            }
        }
    }
}
