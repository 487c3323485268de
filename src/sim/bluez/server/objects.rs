//! The object tree BlueZ shows: which paths exist, their children and interfaces, and the
//! properties of the adapter, the devices, their services and characteristics.

use super::*;

impl BluezSim {
    pub(super) fn find(&self, path: &str) -> Option<Obj> {
        match path {
            "/" => return Some(Obj::Root),
            "/org" => return Some(Obj::Org),
            "/org/bluez" => return Some(Obj::Bluez),
            ADAPTER_PATH => return Some(Obj::Adapter),
            _ => {}
        }
        for (i, d) in self.devices.iter().enumerate() {
            if !d.known || !path.starts_with(&d.path) {
                continue;
            }
            if path == d.path {
                return Some(Obj::Device(i));
            }
            if !d.exported {
                return None;
            }
            for (j, s) in d.services.iter().enumerate() {
                if path == s.path {
                    return Some(Obj::Service(i, j));
                }
                if let Some(k) = s.chars.iter().position(|c| c.path == path) {
                    return Some(Obj::Char(i, j, k));
                }
            }
        }
        None
    }

    pub(super) fn path_of(&self, obj: Obj) -> String {
        match obj {
            Obj::Root => "/".into(),
            Obj::Org => "/org".into(),
            Obj::Bluez => "/org/bluez".into(),
            Obj::Adapter => ADAPTER_PATH.into(),
            Obj::Device(i) => self.devices[i].path.clone(),
            Obj::Service(i, j) => self.devices[i].services[j].path.clone(),
            Obj::Char(i, j, k) => self.devices[i].services[j].chars[k].path.clone(),
        }
    }

    /// Relative names of an object's children, for introspection.
    pub(super) fn children(&self, obj: Obj) -> Vec<String> {
        let last = |p: &str| p.rsplit('/').next().unwrap_or_default().to_string();
        match obj {
            Obj::Root => vec!["org".into()],
            Obj::Org => vec!["bluez".into()],
            Obj::Bluez => vec!["hci0".into()],
            Obj::Adapter => self
                .devices
                .iter()
                .filter(|d| d.known)
                .map(|d| last(&d.path))
                .collect(),
            Obj::Device(i) => {
                let d = &self.devices[i];
                if d.exported {
                    d.services.iter().map(|s| last(&s.path)).collect()
                } else {
                    Vec::new()
                }
            }
            Obj::Service(i, j) => self.devices[i].services[j]
                .chars
                .iter()
                .map(|c| last(&c.path))
                .collect(),
            Obj::Char(..) => Vec::new(),
        }
    }

    /// Every object `GetManagedObjects` lists.
    pub(super) fn objects(&self) -> Vec<Obj> {
        let mut out = vec![Obj::Bluez, Obj::Adapter];
        for (i, d) in self.devices.iter().enumerate() {
            if !d.known {
                continue;
            }
            out.push(Obj::Device(i));
            if d.exported {
                for (j, s) in d.services.iter().enumerate() {
                    out.push(Obj::Service(i, j));
                    out.extend((0..s.chars.len()).map(|k| Obj::Char(i, j, k)));
                }
            }
        }
        out
    }

    pub(super) fn adapter_props(&self) -> Props {
        let a = &self.adapter;
        vec![
            ("Address", Val::Str(ADAPTER_ADDRESS.into())),
            ("AddressType", Val::Str("public".into())),
            ("Name", Val::Str(ADAPTER_NAME.into())),
            ("Alias", Val::Str(a.alias.clone())),
            ("Class", Val::U32(0)),
            ("Powered", Val::Bool(a.powered)),
            (
                "PowerState",
                Val::Str(if a.powered { "on" } else { "off" }.into()),
            ),
            ("Discoverable", Val::Bool(a.discoverable)),
            ("DiscoverableTimeout", Val::U32(180)),
            ("Pairable", Val::Bool(a.pairable)),
            ("PairableTimeout", Val::U32(0)),
            ("Discovering", Val::Bool(!a.discovering.is_empty())),
            ("UUIDs", Val::Strs(Vec::new())),
            ("Modalias", Val::Str(ADAPTER_MODALIAS.into())),
            ("Roles", strs(&["central", "peripheral"])),
        ]
    }

    /// The device's service UUIDs: what it advertises (its main service) until its services
    /// are resolved, then all of them.
    pub(super) fn uuids(d: &Device) -> Val {
        if d.exported {
            Val::Strs(d.services.iter().map(|s| s.uuid.to_string()).collect())
        } else {
            Val::Strs(vec![d.droid.profile().service.to_string()])
        }
    }

    pub(super) fn device_props(&self, i: usize) -> Props {
        let d = &self.devices[i];
        vec![
            ("Address", Val::Str(d.spec.address_string())),
            ("AddressType", Val::Str("random".into())),
            ("Name", Val::Str(d.spec.name.clone())),
            (
                "Alias",
                Val::Str(d.alias.clone().unwrap_or_else(|| d.spec.name.clone())),
            ),
            ("UUIDs", Self::uuids(d)),
            ("Paired", Val::Bool(false)),
            ("Bonded", Val::Bool(false)),
            ("Connected", Val::Bool(d.connected())),
            ("Trusted", Val::Bool(d.trusted)),
            ("Blocked", Val::Bool(d.blocked)),
            ("LegacyPairing", Val::Bool(false)),
            ("Adapter", Val::Obj(ADAPTER_PATH.into())),
            ("ServicesResolved", Val::Bool(d.exported)),
        ]
        .into_iter()
        // BlueZ has an RSSI only for a device heard in the current discovery.
        .chain(d.rssi.map(|r| ("RSSI", Val::I16(r))))
        .collect()
    }

    pub(super) fn service_props(&self, i: usize, j: usize) -> Props {
        let d = &self.devices[i];
        let s = &d.services[j];
        vec![
            ("UUID", Val::Str(s.uuid.to_string())),
            ("Device", Val::Obj(d.path.clone())),
            ("Primary", Val::Bool(true)),
            ("Includes", Val::Objs(Vec::new())),
            ("Handle", Val::U16(s.handle)),
        ]
    }

    pub(super) fn char_props(&self, i: usize, j: usize, k: usize) -> Props {
        let s = &self.devices[i].services[j];
        let c = &s.chars[k];
        let mut p = vec![
            ("UUID", Val::Str(c.uuid.to_string())),
            ("Service", Val::Obj(s.path.clone())),
            ("Value", Val::Bytes(c.value.clone())),
            ("Flags", strs(&c.flags.names())),
            ("Handle", Val::U16(c.handle)),
            ("MTU", Val::U16(MTU)),
        ];
        if c.flags.contains(CharFlags::NOTIFY) {
            p.push(("Notifying", Val::Bool(!c.sessions.is_empty())));
        }
        p
    }

    /// The properties of `iface` on `obj`; `None` when the object lacks the interface.
    pub(super) fn props(&self, obj: Obj, iface: &str) -> Option<Props> {
        if !interfaces(obj).contains(&iface) {
            return None;
        }
        Some(match (obj, iface) {
            (Obj::Adapter, ADAPTER) => self.adapter_props(),
            (Obj::Device(i), DEVICE) => self.device_props(i),
            (Obj::Service(i, j), SERVICE) => self.service_props(i, j),
            (Obj::Char(i, j, k), CHARACTERISTIC) => self.char_props(i, j, k),
            _ => Vec::new(),
        })
    }

    pub(super) fn all_props(&self, obj: Obj) -> HashMap<String, PropMap> {
        interfaces(obj)
            .iter()
            .filter(|i| **i != OBJECT_MANAGER)
            .filter_map(|i| self.props(obj, i).map(|p| (i.to_string(), propmap(&p))))
            .collect()
    }
}
