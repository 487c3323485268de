//! The virtual BlueZ itself: one D-Bus connection owning `org.bluez`, one loop answering
//! method calls and advancing the droids on the wall clock.
//!
//! Nothing a client sends can panic it: arguments of the wrong type get
//! `org.freedesktop.DBus.Error.InvalidArgs`, unknown objects and methods the standard errors,
//! GATT failures the `org.bluez.Error.*` BlueZ answers with.

mod adapter;
mod calls;
mod characteristic;
mod device;
mod links;
mod objects;
mod signals;

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
    /// What the droid showed when last traced (BOLT's matrix).
    shown: Option<String>,
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
    /// `place`: where it stands in the room it shares with the other droids served.
    fn new(
        spec: DroidSpec,
        faults: &crate::sim::gatt::GattFaults,
        remembered: bool,
        place: Option<crate::sim::room::Place>,
    ) -> Device {
        let mut cfg = SimConfig::for_model(spec.model);
        cfg.place = place;
        let droid = GattDroid::new(spec.model, cfg, faults.clone());
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
            shown: None,
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
        // The droids in range share one room (they see the same walls and collide);
        // remembered ones are elsewhere.
        let room = crate::sim::room::SharedRoom::new();
        let origins = crate::sim::room::SharedRoom::origins(opts.droids.len());
        let devices = opts
            .droids
            .into_iter()
            .zip(origins)
            .map(|(spec, origin)| {
                let radius = SimConfig::for_model(spec.model).radius_cm;
                let place = room.place(origin, radius);
                Device::new(spec, &opts.faults, false, Some(place))
            })
            .chain(
                opts.remembered
                    .into_iter()
                    .map(|spec| Device::new(spec, &opts.faults, true, None)),
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

    /// Trace what device `i` received or sent (with `trace`), then what it shows when that
    /// changed (BOLT's matrix).
    fn trace_records(&mut self, i: usize, mut records: Vec<TraceRecord>) {
        let shows = self.devices[i].droid.shows();
        if shows != self.devices[i].shown {
            if let Some(text) = &shows {
                records.push(TraceRecord::state(text));
            }
            self.devices[i].shown = shows;
        }
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
}
