//! Messages in: method calls dispatched by interface, the standard Properties interface, and
//! the bus's own NameOwnerChanged (a client leaving).

use super::*;

impl BluezSim {
    pub(super) fn on_message(&mut self, msg: Message) {
        match msg.msg_type() {
            MessageType::MethodCall => {
                let no_reply = msg.get_no_reply();
                if let Some(reply) = self.on_call(msg)
                    && !no_reply
                {
                    self.send(reply);
                }
            }
            MessageType::Signal => {
                // Only the bus itself says who left: a unicast signal reaches us whatever our
                // match rules, so one client could otherwise tear down another's connection.
                let is_owner_change = msg.interface().as_deref() == Some("org.freedesktop.DBus")
                    && msg.member().as_deref() == Some("NameOwnerChanged")
                    && msg.sender().as_deref() == Some("org.freedesktop.DBus");
                if is_owner_change
                    && let Ok((name, _old, new)) = msg.read3::<&str, &str, &str>()
                    && name.starts_with(':')
                    && new.is_empty()
                {
                    let name = name.to_string();
                    self.client_gone(&name);
                }
            }
            _ => {}
        }
    }

    /// Answer a method call; `None` when the answer comes later (a refused connection).
    pub(super) fn on_call(&mut self, msg: Message) -> Option<Message> {
        let path = msg.path().map(|p| p.to_string()).unwrap_or_default();
        let member = msg.member().map(|m| m.to_string()).unwrap_or_default();
        let client = msg.sender().map(|s| s.to_string()).unwrap_or_default();
        let iface = msg.interface().map(|i| i.to_string());
        if iface.as_deref() == Some(PEER) {
            return Some(match member.as_str() {
                "Ping" => msg.method_return(),
                "GetMachineId" => msg
                    .method_return()
                    .append1("d201d201d201d201d201d201d201d201"),
                _ => error(&msg, ERR_DBUS_UNKNOWN_METHOD, "Unknown method"),
            });
        }
        let Some(obj) = self.find(&path) else {
            return Some(error(
                &msg,
                ERR_DBUS_UNKNOWN_OBJECT,
                &format!("Unknown object '{path}'"),
            ));
        };
        let ifaces = interfaces(obj);
        // A call may leave the interface out: the member says which it means.
        let iface = iface.unwrap_or_else(|| {
            match member.as_str() {
                "Introspect" => INTROSPECTABLE,
                "Get" | "GetAll" | "Set" => PROPERTIES,
                "GetManagedObjects" => OBJECT_MANAGER,
                _ => ifaces[0],
            }
            .to_string()
        });
        if !ifaces.contains(&iface.as_str()) {
            return Some(error(
                &msg,
                ERR_DBUS_UNKNOWN_METHOD,
                &format!("Unknown interface '{iface}' on '{path}'"),
            ));
        }
        let now = self.now();
        match (iface.as_str(), obj) {
            (INTROSPECTABLE, _) if member == "Introspect" => Some(
                msg.method_return()
                    .append1(xml::introspect(ifaces, &self.children(obj))),
            ),
            (PROPERTIES, _) => Some(self.properties_call(&msg, obj, &member)),
            (OBJECT_MANAGER, _) if member == "GetManagedObjects" => {
                let tree: HashMap<Path<'static>, HashMap<String, PropMap>> = self
                    .objects()
                    .into_iter()
                    .map(|o| (obj_path(&self.path_of(o)), self.all_props(o)))
                    .collect();
                Some(msg.method_return().append1(tree))
            }
            // Agents are for pairing, which the droids do not do: accepted and never called.
            (AGENT_MANAGER, _)
                if matches!(
                    member.as_str(),
                    "RegisterAgent" | "UnregisterAgent" | "RequestDefaultAgent"
                ) =>
            {
                Some(msg.method_return())
            }
            (ADAPTER, _) => Some(self.adapter_call(&msg, &member, &client)),
            (DEVICE, Obj::Device(i)) => self.device_call(msg, i, &member, client, now),
            (CHARACTERISTIC, Obj::Char(i, j, k)) => {
                Some(self.char_call(&msg, (i, j, k), &member, &client, now))
            }
            _ => Some(error(
                &msg,
                ERR_DBUS_UNKNOWN_METHOD,
                &format!("Unknown method '{member}' on '{iface}'"),
            )),
        }
    }

    pub(super) fn properties_call(&mut self, msg: &Message, obj: Obj, member: &str) -> Message {
        match member {
            "Get" => {
                let Ok((iface, name)) = msg.read2::<&str, &str>() else {
                    return invalid_args(msg);
                };
                let Some(props) = self.props(obj, iface) else {
                    return error(
                        msg,
                        ERR_DBUS_INVALID_ARGS,
                        &format!("No such interface '{iface}'"),
                    );
                };
                match props.iter().find(|(k, _)| *k == name) {
                    Some((_, v)) => msg.method_return().append1(v.variant()),
                    None => error(
                        msg,
                        ERR_DBUS_INVALID_ARGS,
                        &format!("No such property '{name}'"),
                    ),
                }
            }
            "GetAll" => {
                let Ok(iface) = msg.read1::<&str>() else {
                    return invalid_args(msg);
                };
                match self.props(obj, iface) {
                    Some(p) => msg.method_return().append1(propmap(&p)),
                    None => error(
                        msg,
                        ERR_DBUS_INVALID_ARGS,
                        &format!("No such interface '{iface}'"),
                    ),
                }
            }
            "Set" => {
                let Ok((iface, name, value)) = msg.read3::<&str, &str, Variant<Box<dyn RefArg>>>()
                else {
                    return invalid_args(msg);
                };
                let (iface, name) = (iface.to_string(), name.to_string());
                self.set_property(msg, obj, &iface, &name, &*value.0)
            }
            _ => error(msg, ERR_DBUS_UNKNOWN_METHOD, "Unknown method"),
        }
    }

    pub(super) fn set_property(
        &mut self,
        msg: &Message,
        obj: Obj,
        iface: &str,
        name: &str,
        value: &(dyn RefArg + 'static),
    ) -> Message {
        let Some(props) = self.props(obj, iface) else {
            return error(
                msg,
                ERR_DBUS_INVALID_ARGS,
                &format!("No such interface '{iface}'"),
            );
        };
        if !props.iter().any(|(k, _)| *k == name) {
            return error(
                msg,
                ERR_DBUS_INVALID_ARGS,
                &format!("No such property '{name}'"),
            );
        }
        let as_bool = || cast::<bool>(value).copied();
        let as_str = || cast::<String>(value).cloned();
        let bad = || {
            error(
                msg,
                ERR_INVALID_ARGUMENTS,
                "Invalid arguments in method call",
            )
        };
        match (obj, name) {
            (Obj::Adapter, "Powered") => {
                let Some(on) = as_bool() else { return bad() };
                self.set_powered(on);
            }
            (Obj::Adapter, "Alias") => {
                let Some(alias) = as_str() else { return bad() };
                self.adapter.alias = if alias.is_empty() {
                    ADAPTER_NAME.to_string()
                } else {
                    alias
                };
                self.changed(
                    ADAPTER_PATH,
                    ADAPTER,
                    vec![("Alias", Val::Str(self.adapter.alias.clone()))],
                );
            }
            (Obj::Adapter, "Discoverable" | "Pairable") => {
                let Some(on) = as_bool() else { return bad() };
                if name == "Discoverable" {
                    self.adapter.discoverable = on;
                } else {
                    self.adapter.pairable = on;
                }
                let prop = if name == "Discoverable" {
                    "Discoverable"
                } else {
                    "Pairable"
                };
                self.changed(ADAPTER_PATH, ADAPTER, vec![(prop, Val::Bool(on))]);
            }
            (Obj::Device(i), "Alias") => {
                let Some(alias) = as_str() else { return bad() };
                let d = &mut self.devices[i];
                d.alias = (!alias.is_empty()).then_some(alias);
                let shown = d.alias.clone().unwrap_or_else(|| d.spec.name.clone());
                let path = d.path.clone();
                self.changed(&path, DEVICE, vec![("Alias", Val::Str(shown))]);
            }
            (Obj::Device(i), "Trusted" | "Blocked") => {
                let Some(on) = as_bool() else { return bad() };
                let d = &mut self.devices[i];
                let prop = if name == "Trusted" {
                    d.trusted = on;
                    "Trusted"
                } else {
                    d.blocked = on;
                    "Blocked"
                };
                let path = d.path.clone();
                self.changed(&path, DEVICE, vec![(prop, Val::Bool(on))]);
                if prop == "Blocked" && on && self.devices[i].connected() {
                    self.teardown(i, "org.bluez.Reason.Local");
                    let line = format!("{}: disconnected (blocked)", self.devices[i].name());
                    self.say(line);
                }
            }
            _ => {
                return error(
                    msg,
                    ERR_DBUS_READ_ONLY,
                    &format!("Property '{name}' is not writable"),
                );
            }
        }
        msg.method_return()
    }
}
