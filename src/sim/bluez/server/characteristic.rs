//! Characteristic calls: ReadValue, WriteValue, StartNotify and StopNotify on a droid's GATT
//! table, with BlueZ's errors.

use super::*;

impl BluezSim {
    pub(super) fn char_call(
        &mut self,
        msg: &Message,
        (i, j, k): (usize, usize, usize),
        member: &str,
        client: &str,
        now: Duration,
    ) -> Message {
        let (uuid, flags, path) = {
            let c = &self.devices[i].services[j].chars[k];
            (c.uuid, c.flags, c.path.clone())
        };
        let offset = |opts: &PropMap| opts.get("offset").and_then(|v| v.0.as_u64()).unwrap_or(0);
        match member {
            "ReadValue" => {
                let Ok(opts) = msg.read1::<PropMap>() else {
                    return invalid_args(msg);
                };
                let value = match self.devices[i].droid.read(uuid, now) {
                    Ok(v) => v,
                    Err(e) => return gatt_error(msg, &e),
                };
                let Some(value) = usize::try_from(offset(&opts))
                    .ok()
                    .and_then(|o| value.get(o..))
                    .map(<[u8]>::to_vec)
                else {
                    return error(msg, ERR_INVALID_OFFSET, "Invalid offset");
                };
                if self.trace {
                    let records = self.devices[i].tracer.read(uuid, &value);
                    self.trace_records(i, records);
                }
                self.devices[i].services[j].chars[k].value = value.clone();
                self.changed(
                    &path,
                    CHARACTERISTIC,
                    vec![("Value", Val::Bytes(value.clone()))],
                );
                msg.method_return().append1(value)
            }
            "WriteValue" => {
                let Ok((value, opts)) = msg.read2::<Vec<u8>, PropMap>() else {
                    return invalid_args(msg);
                };
                let kind = opts.get("type").and_then(|v| cast::<String>(&v.0).cloned());
                let allowed = match kind.as_deref() {
                    None => flags.writable(),
                    Some("command") => flags.contains(CharFlags::WRITE_WITHOUT_RESPONSE),
                    Some("request") => flags.contains(CharFlags::WRITE),
                    Some(_) => false,
                };
                if !flags.writable() {
                    return error(msg, ERR_NOT_PERMITTED, "Write not permitted");
                }
                if !allowed {
                    return error(msg, ERR_NOT_SUPPORTED, "Operation is not supported");
                }
                if offset(&opts) != 0 {
                    return error(msg, ERR_INVALID_OFFSET, "Invalid offset");
                }
                if let Err(e) = self.devices[i].droid.write(uuid, &value, now) {
                    return gatt_error(msg, &e);
                }
                if self.trace {
                    let records = self.devices[i].tracer.write(uuid, &value);
                    self.trace_records(i, records);
                }
                msg.method_return()
            }
            "StartNotify" => {
                if self.devices[i].services[j].chars[k]
                    .sessions
                    .contains(client)
                {
                    return error(msg, ERR_IN_PROGRESS, "Operation already in progress");
                }
                if let Err(e) = self.devices[i].droid.start_notify(uuid, now) {
                    return gatt_error(msg, &e);
                }
                let c = &mut self.devices[i].services[j].chars[k];
                c.sessions.insert(client.to_string());
                if c.sessions.len() == 1 {
                    self.changed(&path, CHARACTERISTIC, vec![("Notifying", Val::Bool(true))]);
                }
                msg.method_return()
            }
            "StopNotify" => {
                let c = &mut self.devices[i].services[j].chars[k];
                if !c.sessions.remove(client) {
                    return error(msg, ERR_FAILED, "No notify session started");
                }
                if c.sessions.is_empty() {
                    let _ = self.devices[i].droid.stop_notify(uuid, now);
                    self.changed(&path, CHARACTERISTIC, vec![("Notifying", Val::Bool(false))]);
                }
                msg.method_return()
            }
            "AcquireWrite" | "AcquireNotify" => {
                error(msg, ERR_NOT_SUPPORTED, "Operation is not supported")
            }
            _ => error(
                msg,
                ERR_DBUS_UNKNOWN_METHOD,
                &format!("Unknown method '{member}'"),
            ),
        }
    }
}
