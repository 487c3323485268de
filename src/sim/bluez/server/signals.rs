//! The signals clients follow: properties changed or invalidated, interfaces added or
//! removed.

use super::*;

impl BluezSim {
    pub(super) fn changed(&self, path: &str, iface: &str, props: Props) {
        let sig = PropertiesPropertiesChanged {
            interface_name: iface.to_string(),
            changed_properties: propmap(&props),
            invalidated_properties: Vec::new(),
        };
        self.send(sig.to_emit_message(&obj_path(path)));
    }

    /// Properties that no longer exist (BlueZ's way of saying an RSSI is gone).
    pub(super) fn invalidated(&self, path: &str, iface: &str, names: &[&str]) {
        let sig = PropertiesPropertiesChanged {
            interface_name: iface.to_string(),
            changed_properties: PropMap::new(),
            invalidated_properties: names.iter().map(|s| s.to_string()).collect(),
        };
        self.send(sig.to_emit_message(&obj_path(path)));
    }

    pub(super) fn added(&self, obj: Obj) {
        let sig = ObjectManagerInterfacesAdded {
            object: obj_path(&self.path_of(obj)),
            interfaces: self.all_props(obj),
        };
        self.send(sig.to_emit_message(&Path::from("/")));
    }

    pub(super) fn removed(&self, path: &str, obj: Obj) {
        let sig = ObjectManagerInterfacesRemoved {
            object: obj_path(path),
            interfaces: interfaces(obj).iter().map(|s| s.to_string()).collect(),
        };
        self.send(sig.to_emit_message(&Path::from("/")));
    }
}
