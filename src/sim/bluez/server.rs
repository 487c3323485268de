//! The virtual BlueZ itself: one D-Bus connection owning `org.bluez`, one loop answering
//! method calls and advancing the droids on the wall clock.
//!
//! Nothing a client sends can panic it: arguments of the wrong type get
//! `org.freedesktop.DBus.Error.InvalidArgs`, unknown objects and methods the standard errors,
//! GATT failures the `org.bluez.Error.*` BlueZ answers with.

use super::xml::{
    self, ADAPTER, AGENT_MANAGER, CHARACTERISTIC, DEVICE, INTROSPECTABLE, OBJECT_MANAGER, PEER,
    PROPERTIES, SERVICE,
};
use super::{BluezOptions, DroidSpec, Report};
use crate::gatt::GattUuid;
use crate::rng::Rng;
use crate::sim::SimConfig;
use crate::sim::gatt::{CharFlags, GattDroid, GattError, GattEvent, SLEEP_GRACE};
use crate::sim::trace::{PacketTracer, TraceRecord};
use dbus::arg::{PropMap, RefArg, Variant, cast};
use dbus::blocking::Connection;
use dbus::blocking::stdintf::org_freedesktop_dbus::{
    ObjectManagerInterfacesAdded, ObjectManagerInterfacesRemoved, PropertiesPropertiesChanged,
    RequestNameReply,
};
use dbus::message::{MessageType, SignalArgs};
use dbus::strings::{ErrorName, Interface, Member};
use dbus::{Message, Path};
use std::collections::{BTreeSet, HashMap};
use std::ffi::CString;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

const BUS_NAME: &str = "org.bluez";
const ADAPTER_PATH: &str = "/org/bluez/hci0";
/// The virtual adapter's address and name.
const ADAPTER_ADDRESS: &str = "00:D2:0C:51:17:00";
const ADAPTER_NAME: &str = "droidctl-sim";
/// Linux Foundation, BlueZ (what a BlueZ adapter reports when it has no better modalias).
const ADAPTER_MODALIAS: &str = "usb:v1D6Bp0246d0540";
/// The loop's step: droids advance, notifications go out.
const TICK: Duration = Duration::from_millis(10);
/// A refused connection fails after this long, as an aborted connection attempt does.
const REFUSE_AFTER: Duration = Duration::from_millis(300);
/// A connection to a device that is not advertising (remembered but out of range, or
/// asleep) fails after this long, as BlueZ gives up on an LE connection nobody answers.
const ABSENT_AFTER: Duration = Duration::from_secs(3);
/// How long after a disconnect the simulator says whether the droid still rolls (its
/// fail-safe stops it, or nothing does).
const MOTION_REPORT_AFTER: Duration = Duration::from_secs(3);
/// While discovering, signal strengths are heard again this often.
const RSSI_EVERY: Duration = Duration::from_secs(1);
/// The default ATT MTU.
const MTU: u16 = 23;

const ERR_FAILED: &str = "org.bluez.Error.Failed";
const ERR_IN_PROGRESS: &str = "org.bluez.Error.InProgress";
const ERR_NOT_READY: &str = "org.bluez.Error.NotReady";
const ERR_NOT_CONNECTED: &str = "org.bluez.Error.NotConnected";
const ERR_NOT_SUPPORTED: &str = "org.bluez.Error.NotSupported";
const ERR_NOT_PERMITTED: &str = "org.bluez.Error.NotPermitted";
const ERR_DOES_NOT_EXIST: &str = "org.bluez.Error.DoesNotExist";
const ERR_INVALID_ARGUMENTS: &str = "org.bluez.Error.InvalidArguments";
const ERR_INVALID_OFFSET: &str = "org.bluez.Error.InvalidOffset";
const ERR_INVALID_LENGTH: &str = "org.bluez.Error.InvalidValueLength";
const ERR_DBUS_INVALID_ARGS: &str = "org.freedesktop.DBus.Error.InvalidArgs";
const ERR_DBUS_UNKNOWN_OBJECT: &str = "org.freedesktop.DBus.Error.UnknownObject";
const ERR_DBUS_UNKNOWN_METHOD: &str = "org.freedesktop.DBus.Error.UnknownMethod";
const ERR_DBUS_READ_ONLY: &str = "org.freedesktop.DBus.Error.PropertyReadOnly";
/// What BlueZ says when a connection attempt is aborted.
const ABORTED: &str = "le-connection-abort-by-local";

/// A property value.
#[derive(Debug, Clone, PartialEq)]
enum Val {
    Str(String),
    Bool(bool),
    I16(i16),
    U16(u16),
    U32(u32),
    Obj(String),
    Strs(Vec<String>),
    Objs(Vec<String>),
    Bytes(Vec<u8>),
}

type Props = Vec<(&'static str, Val)>;

fn obj_path(p: &str) -> Path<'static> {
    Path::new(p.to_string()).unwrap_or_else(|_| Path::from("/"))
}

impl Val {
    fn variant(&self) -> Variant<Box<dyn RefArg>> {
        Variant(match self {
            Val::Str(s) => Box::new(s.clone()),
            Val::Bool(b) => Box::new(*b),
            Val::I16(n) => Box::new(*n),
            Val::U16(n) => Box::new(*n),
            Val::U32(n) => Box::new(*n),
            Val::Obj(p) => Box::new(obj_path(p)),
            Val::Strs(v) => Box::new(v.clone()),
            Val::Objs(v) => Box::new(v.iter().map(|p| obj_path(p)).collect::<Vec<_>>()),
            Val::Bytes(b) => Box::new(b.clone()),
        })
    }
}

fn strs(v: &[&str]) -> Val {
    Val::Strs(v.iter().map(|s| s.to_string()).collect())
}

fn propmap(props: &Props) -> PropMap {
    props
        .iter()
        .map(|(k, v)| (k.to_string(), v.variant()))
        .collect()
}

/// An error reply.
fn error(msg: &Message, name: &'static str, text: &str) -> Message {
    let name = ErrorName::new(name)
        .unwrap_or_else(|_| ErrorName::from("org.freedesktop.DBus.Error.Failed"));
    let text = CString::new(text.replace('\0', " ")).unwrap_or_default();
    msg.error(&name, &text)
}

fn invalid_args(msg: &Message) -> Message {
    error(
        msg,
        ERR_DBUS_INVALID_ARGS,
        "Invalid arguments in method call",
    )
}

/// The D-Bus answer to a GATT failure, as BlueZ words it.
fn gatt_error(msg: &Message, e: &GattError) -> Message {
    let (name, text) = match e {
        GattError::NotConnected | GattError::NotResolved => (ERR_FAILED, "Not connected"),
        GattError::AlreadyConnected | GattError::Refused => (ERR_FAILED, ABORTED),
        GattError::UnknownCharacteristic(_) => (ERR_DBUS_UNKNOWN_OBJECT, "Unknown characteristic"),
        GattError::ReadNotPermitted => (ERR_NOT_PERMITTED, "Read not permitted"),
        GattError::WriteNotPermitted => (ERR_NOT_PERMITTED, "Write not permitted"),
        GattError::NotifyNotSupported => (ERR_NOT_SUPPORTED, "Operation is not supported"),
        GattError::NotNotifying => (ERR_FAILED, "No notify session started"),
        GattError::InvalidLength(_) => (ERR_INVALID_LENGTH, "Invalid Length"),
        GattError::Asleep => (ERR_FAILED, ABORTED),
    };
    error(msg, name, text)
}

/// An object on the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Obj {
    Root,
    Org,
    Bluez,
    Adapter,
    Device(usize),
    Service(usize, usize),
    Char(usize, usize, usize),
}

fn interfaces(obj: Obj) -> &'static [&'static str] {
    match obj {
        Obj::Root => &[OBJECT_MANAGER, INTROSPECTABLE],
        Obj::Org => &[INTROSPECTABLE],
        Obj::Bluez => &[AGENT_MANAGER, INTROSPECTABLE],
        Obj::Adapter => &[ADAPTER, PROPERTIES, INTROSPECTABLE],
        Obj::Device(_) => &[DEVICE, PROPERTIES, INTROSPECTABLE],
        Obj::Service(..) => &[SERVICE, PROPERTIES, INTROSPECTABLE],
        Obj::Char(..) => &[CHARACTERISTIC, PROPERTIES, INTROSPECTABLE],
    }
}

struct CharObj {
    uuid: GattUuid,
    flags: CharFlags,
    path: String,
    handle: u16,
    /// Clients with a notify session.
    sessions: BTreeSet<String>,
    /// The cached value (last read or notification).
    value: Vec<u8>,
}

struct ServiceObj {
    uuid: GattUuid,
    path: String,
    handle: u16,
    chars: Vec<CharObj>,
}

struct Device {
    spec: DroidSpec,
    path: String,
    droid: GattDroid,
    /// Heard by a discovery (or remembered): on the bus.
    known: bool,
    /// Remembered by BlueZ but not in range: on the bus from the start, never advertising.
    remembered: bool,
    /// Its falling asleep was reported.
    asleep_said: bool,
    /// When to say whether it still rolls, after a disconnect.
    motion_report: Option<Instant>,
    tracer: PacketTracer,
    /// The GATT objects are on the bus.
    exported: bool,
    /// The client that connected.
    owner: Option<String>,
    /// A refused connection attempt is under way.
    refusing: bool,
    services: Vec<ServiceObj>,
    /// Heard in the current discovery at this strength; `None` when it was not (BlueZ
    /// invalidates RSSI when discovery stops).
    rssi: Option<i16>,
    alias: Option<String>,
    trusted: bool,
    blocked: bool,
}

impl Device {
    fn new(spec: DroidSpec, faults: &crate::sim::gatt::GattFaults, remembered: bool) -> Device {
        let droid = GattDroid::new(spec.model, SimConfig::for_model(spec.model), faults.clone());
        let path = format!(
            "{ADAPTER_PATH}/dev_{}",
            spec.address_string().replace(':', "_")
        );
        // Handles as a GATT server numbers them: the service, then per characteristic its
        // declaration and value (and the notification descriptor).
        let mut handle: u16 = 0x000a;
        let mut services = Vec::new();
        for s in droid.table() {
            let spath = format!("{path}/service{handle:04x}");
            let shandle = handle;
            handle += 1;
            let mut chars = Vec::new();
            for c in &s.characteristics {
                chars.push(CharObj {
                    uuid: c.uuid,
                    flags: c.flags,
                    path: format!("{spath}/char{handle:04x}"),
                    handle: handle + 1,
                    sessions: BTreeSet::new(),
                    value: Vec::new(),
                });
                handle += if c.flags.contains(CharFlags::NOTIFY) {
                    3
                } else {
                    2
                };
            }
            services.push(ServiceObj {
                uuid: s.uuid,
                path: spath,
                handle: shandle,
                chars,
            });
            handle += 1;
        }
        Device {
            rssi: None,
            tracer: PacketTracer::new(spec.model),
            spec,
            path,
            droid,
            known: remembered,
            remembered,
            // Remembered devices are never there to fall asleep.
            asleep_said: remembered,
            motion_report: None,
            exported: false,
            owner: None,
            refusing: false,
            services,
            alias: None,
            trusted: false,
            blocked: false,
        }
    }

    fn name(&self) -> &str {
        &self.spec.name
    }

    fn connected(&self) -> bool {
        self.droid.status().connected
    }

    /// In range and advertising (so a discovery hears it).
    fn advertising(&self) -> bool {
        !self.remembered && !self.droid.status().asleep && !self.connected()
    }
}

/// A connection attempt answered later.
struct Delayed {
    at: Instant,
    dev: usize,
    client: String,
    call: Message,
}

struct AdapterState {
    powered: bool,
    alias: String,
    discoverable: bool,
    pairable: bool,
    /// Clients with a discovery session.
    discovering: BTreeSet<String>,
}

/// The virtual BlueZ on one bus. [`BluezSim::connect`] takes the name, [`BluezSim::run`]
/// serves until told to stop.
pub struct BluezSim {
    conn: Connection,
    epoch: Instant,
    adapter: AdapterState,
    devices: Vec<Device>,
    delayed: Vec<Delayed>,
    rng: Rng,
    next_rssi: Instant,
    trace: bool,
    json: bool,
    report: Box<dyn FnMut(Report) + Send>,
}

impl BluezSim {
    /// Connect to the bus at `address` and own `org.bluez` there. `report` receives one line
    /// per event (connections, disconnections, faults; with `trace` every packet received
    /// and sent, decoded, as text or JSON lines).
    pub fn connect(
        address: &str,
        opts: BluezOptions,
        report: Box<dyn FnMut(Report) + Send>,
    ) -> Result<BluezSim, String> {
        let why = |e: dbus::Error| {
            e.message()
                .or(e.name())
                .unwrap_or("no reason given")
                .to_string()
        };
        let conn = Connection::new_address(address)
            .map_err(|e| format!("cannot connect to the D-Bus bus {address}: {}", why(e)))?;
        let owned = conn
            .request_name(BUS_NAME, false, false, true)
            .map_err(|e| format!("cannot own {BUS_NAME} on {address}: {}", why(e)))?;
        if owned != RequestNameReply::PrimaryOwner {
            return Err(format!(
                "{BUS_NAME} already has an owner on {address} (a real BlueZ?) — leave out --bus \
                 to serve on a private bus"
            ));
        }
        // Clients that leave the bus end their discovery, notify sessions and connections.
        conn.add_match_no_cb(
            "type='signal',sender='org.freedesktop.DBus',interface='org.freedesktop.DBus',\
             member='NameOwnerChanged'",
        )
        .map_err(|e| format!("cannot watch the bus: {}", why(e)))?;
        let devices = opts
            .droids
            .into_iter()
            .map(|spec| Device::new(spec, &opts.faults, false))
            .chain(
                opts.remembered
                    .into_iter()
                    .map(|spec| Device::new(spec, &opts.faults, true)),
            )
            .collect();
        let now = Instant::now();
        Ok(BluezSim {
            conn,
            epoch: now,
            adapter: AdapterState {
                powered: true,
                alias: ADAPTER_NAME.to_string(),
                discoverable: false,
                pairable: false,
                discovering: BTreeSet::new(),
            },
            devices,
            delayed: Vec::new(),
            rng: Rng::new(opts.seed),
            next_rssi: now,
            trace: opts.trace,
            json: opts.json,
            report,
        })
    }

    /// Serve until `stop` is set (then disconnect every droid) or the bus goes away (an
    /// error).
    pub fn run(mut self, stop: &AtomicBool) -> Result<(), String> {
        while !stop.load(Ordering::Acquire) {
            let wait = self
                .delayed
                .iter()
                .map(|d| d.at.saturating_duration_since(Instant::now()))
                .min()
                .unwrap_or(TICK)
                .min(TICK);
            if self.conn.channel().read_write(Some(wait)).is_err() {
                return Err("the D-Bus connection was lost (did the bus stop?)".into());
            }
            while let Some(msg) = self.conn.channel().pop_message() {
                self.on_message(msg);
            }
            self.tick();
            self.conn.channel().flush();
        }
        for i in 0..self.devices.len() {
            if self.devices[i].connected() {
                self.teardown(i, "org.bluez.Reason.Local");
                let line = format!(
                    "{}: disconnected (the simulator stopped)",
                    self.devices[i].name()
                );
                self.say(line);
            }
        }
        self.conn.channel().flush();
        Ok(())
    }

    fn now(&self) -> Duration {
        self.epoch.elapsed()
    }

    fn say(&mut self, line: String) {
        (self.report)(Report::Status(line));
    }

    /// Trace what device `i` received or sent (with `trace`).
    fn trace_records(&mut self, i: usize, records: Vec<TraceRecord>) {
        let t_ms = self.now().as_millis() as u64;
        for r in records {
            let name = self.devices[i].name().to_string();
            let line = if self.json {
                Report::Trace(r.json_line(t_ms, &name).to_string())
            } else {
                Report::Status(format!("{name}: {:<3} {}", r.dir.name(), r.text))
            };
            (self.report)(line);
        }
    }

    fn send(&self, m: Message) {
        let _ = self.conn.channel().send(m);
    }

    // ---------------------------------------------------------------------------------------
    // Objects and properties
    // ---------------------------------------------------------------------------------------

    fn find(&self, path: &str) -> Option<Obj> {
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

    fn path_of(&self, obj: Obj) -> String {
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
    fn children(&self, obj: Obj) -> Vec<String> {
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
    fn objects(&self) -> Vec<Obj> {
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

    fn adapter_props(&self) -> Props {
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
    fn uuids(d: &Device) -> Val {
        if d.exported {
            Val::Strs(d.services.iter().map(|s| s.uuid.to_string()).collect())
        } else {
            Val::Strs(vec![d.droid.profile().service.to_string()])
        }
    }

    fn device_props(&self, i: usize) -> Props {
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

    fn service_props(&self, i: usize, j: usize) -> Props {
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

    fn char_props(&self, i: usize, j: usize, k: usize) -> Props {
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
    fn props(&self, obj: Obj, iface: &str) -> Option<Props> {
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

    fn all_props(&self, obj: Obj) -> HashMap<String, PropMap> {
        interfaces(obj)
            .iter()
            .filter(|i| **i != OBJECT_MANAGER)
            .filter_map(|i| self.props(obj, i).map(|p| (i.to_string(), propmap(&p))))
            .collect()
    }

    // ---------------------------------------------------------------------------------------
    // Signals
    // ---------------------------------------------------------------------------------------

    fn changed(&self, path: &str, iface: &str, props: Props) {
        let sig = PropertiesPropertiesChanged {
            interface_name: iface.to_string(),
            changed_properties: propmap(&props),
            invalidated_properties: Vec::new(),
        };
        self.send(sig.to_emit_message(&obj_path(path)));
    }

    /// Properties that no longer exist (BlueZ's way of saying an RSSI is gone).
    fn invalidated(&self, path: &str, iface: &str, names: &[&str]) {
        let sig = PropertiesPropertiesChanged {
            interface_name: iface.to_string(),
            changed_properties: PropMap::new(),
            invalidated_properties: names.iter().map(|s| s.to_string()).collect(),
        };
        self.send(sig.to_emit_message(&obj_path(path)));
    }

    fn added(&self, obj: Obj) {
        let sig = ObjectManagerInterfacesAdded {
            object: obj_path(&self.path_of(obj)),
            interfaces: self.all_props(obj),
        };
        self.send(sig.to_emit_message(&Path::from("/")));
    }

    fn removed(&self, path: &str, obj: Obj) {
        let sig = ObjectManagerInterfacesRemoved {
            object: obj_path(path),
            interfaces: interfaces(obj).iter().map(|s| s.to_string()).collect(),
        };
        self.send(sig.to_emit_message(&Path::from("/")));
    }

    // ---------------------------------------------------------------------------------------
    // Messages
    // ---------------------------------------------------------------------------------------

    fn on_message(&mut self, msg: Message) {
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
                let is_owner_change = msg.interface().as_deref() == Some("org.freedesktop.DBus")
                    && msg.member().as_deref() == Some("NameOwnerChanged");
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
    fn on_call(&mut self, msg: Message) -> Option<Message> {
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

    fn properties_call(&mut self, msg: &Message, obj: Obj, member: &str) -> Message {
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

    fn set_property(
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

    fn set_powered(&mut self, on: bool) {
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
    fn discovery_ended(&mut self) {
        for i in 0..self.devices.len() {
            if self.devices[i].rssi.take().is_some() && self.devices[i].known {
                let path = self.devices[i].path.clone();
                self.invalidated(&path, DEVICE, &["RSSI"]);
            }
        }
    }

    fn adapter_call(&mut self, msg: &Message, member: &str, client: &str) -> Message {
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
    fn hear_devices(&mut self) {
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

    fn device_call(
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

    fn connect_device(
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
    fn answer_refusals(&mut self, i: usize, cancelled: Option<&str>) {
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

    fn char_call(
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

    // ---------------------------------------------------------------------------------------
    // Connections, time, clients
    // ---------------------------------------------------------------------------------------

    /// End device `i`'s connection: the droid first, then what BlueZ signals.
    fn teardown(&mut self, i: usize, reason: &str) {
        let now = self.now();
        let _ = self.devices[i].droid.disconnect(now);
        self.link_down(i, reason);
    }

    /// Signal a connection gone (the droid already knows).
    fn link_down(&mut self, i: usize, reason: &str) {
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

    fn on_event(&mut self, i: usize, e: GattEvent) {
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

    fn tick(&mut self) {
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
    fn client_gone(&mut self, name: &str) {
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
