//! The virtual BlueZ's method-call handling (`droidctl sim --bluez`): a client on the bus
//! calls every method the service exports — on every object it exports, the droids' GATT
//! tables included once a droid is connected, and on objects and interfaces that are not
//! there — with arguments made from the input (any number of strings, booleans, integers,
//! byte arrays, object paths, variants and option dictionaries), and forges the bus's
//! `NameOwnerChanged` now and then. Every call is answered, by a return or by one of the
//! errors BlueZ and D-Bus answer with; the service neither panics nor stops; a connection
//! the client left is dropped.
//!
//! The droids are in range and without faults, so every answer comes at once (a remembered
//! droid's Connect is answered after 3 s: too slow to fuzz).
//!
//! Input layout: the first byte turns tracing (text or JSON) on; then calls, each a byte
//! choosing the object, one the method and one the number of arguments, then the arguments.
//! A private `dbus-daemon` is started once per process; each input gets a fresh service.

use super::{Bytes, Target};
use crate::model::Model;
use crate::sim::bluez::{BluezOptions, BluezSim, PrivateBus, Report, plan};
use dbus::arg::{IterAppend, PropMap, RefArg, Variant};
use dbus::blocking::Connection;
use dbus::{Message, Path};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::Duration;

pub const TARGET: Target = Target {
    name: "bluez",
    run: run_input,
    dictionary: &[
        &[0x00],
        &[0x01],
        &[0x02],
        &[0x03],
        &[0xFF],
        b"offset",
        b"type",
    ],
};

/// Every method the service exports, by interface.
const METHODS: &[(&str, &[&str])] = &[
    ("org.freedesktop.DBus.Introspectable", &["Introspect"]),
    ("org.freedesktop.DBus.Properties", &["Get", "GetAll", "Set"]),
    ("org.freedesktop.DBus.ObjectManager", &["GetManagedObjects"]),
    ("org.freedesktop.DBus.Peer", &["Ping", "GetMachineId"]),
    (
        "org.bluez.AgentManager1",
        &["RegisterAgent", "UnregisterAgent", "RequestDefaultAgent"],
    ),
    (
        "org.bluez.Adapter1",
        &[
            "StartDiscovery",
            "StopDiscovery",
            "SetDiscoveryFilter",
            "GetDiscoveryFilters",
            "RemoveDevice",
        ],
    ),
    (
        "org.bluez.Device1",
        &[
            "Connect",
            "Disconnect",
            "ConnectProfile",
            "DisconnectProfile",
            "Pair",
            "CancelPairing",
        ],
    ),
    ("org.bluez.GattService1", &[]),
    (
        "org.bluez.GattCharacteristic1",
        &[
            "ReadValue",
            "WriteValue",
            "StartNotify",
            "StopNotify",
            "AcquireWrite",
            "AcquireNotify",
        ],
    ),
    ("org.example.Nothing1", &["Frob"]),
];

/// Strings the arguments are made of: interfaces, property names, options.
const WORDS: &[&str] = &[
    "org.bluez.Adapter1",
    "org.bluez.Device1",
    "org.bluez.GattCharacteristic1",
    "org.bluez.GattService1",
    "Powered",
    "Alias",
    "Discoverable",
    "Pairable",
    "Trusted",
    "Blocked",
    "Connected",
    "RSSI",
    "Value",
    "Notifying",
    "UUIDs",
    "Transport",
    "le",
    "offset",
    "type",
    "command",
    "request",
    "reliable",
    "",
    "usetheforce...band",
];

/// The bus of this process: started once, on a thread that lives as long as the process
/// (the daemon dies with the thread that started it), its directory removed at exit.
fn bus() -> Result<&'static str, String> {
    static BUS: OnceLock<Result<String, String>> = OnceLock::new();
    BUS.get_or_init(|| {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || match PrivateBus::start() {
            Ok(bus) => {
                let _ = tx.send(Ok(bus.address().to_string()));
                remove_at_exit(bus.address());
                loop {
                    std::thread::park();
                }
            }
            Err(e) => {
                let _ = tx.send(Err(e));
            }
        });
        rx.recv()
            .unwrap_or_else(|_| Err("the bus thread ended".into()))
    })
    .as_deref()
    .map_err(Clone::clone)
}

/// Remove the bus's directory when the process exits (its daemon is killed then).
fn remove_at_exit(address: &str) {
    static DIR: OnceLock<std::path::PathBuf> = OnceLock::new();
    extern "C" fn remove() {
        if let Some(dir) = DIR.get() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
    let path = address.trim_start_matches("unix:path=");
    if let Some(dir) = std::path::Path::new(path).parent()
        && DIR.set(dir.to_path_buf()).is_ok()
    {
        // SAFETY: `remove` is a plain function that touches only the static set above.
        unsafe {
            libc::atexit(remove);
        }
    }
}

/// The service on the bus, on a thread of its own, until dropped.
struct Service {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<Result<(), String>>>,
}

impl Service {
    fn start(address: &str, trace: bool, json: bool) -> Service {
        let opts = BluezOptions {
            droids: plan(&[Model::R2D2, Model::BB8, Model::Robi42], 7),
            remembered: Vec::new(),
            faults: Default::default(),
            seed: 7,
            trace,
            json,
        };
        // The last input's service may still hold the name for a moment.
        let mut sim = None;
        for _ in 0..500 {
            match BluezSim::connect(address, opts.clone(), Box::new(|r: Report| drop(r))) {
                Ok(s) => {
                    sim = Some(s);
                    break;
                }
                Err(e) if e.contains("already has an owner") => {
                    std::thread::sleep(Duration::from_millis(2))
                }
                Err(e) => panic!("the virtual BlueZ cannot start: {e}"),
            }
        }
        let sim = sim.expect("org.bluez is free again within a second");
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::spawn(move || sim.run(&flag));
        Service {
            stop,
            thread: Some(thread),
        }
    }

    fn alive(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }

    /// Stop it; how it ended.
    fn finish(mut self) -> std::thread::Result<Result<(), String>> {
        self.stop.store(true, Ordering::Release);
        self.thread.take().expect("running").join()
    }
}

impl Drop for Service {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// One argument made from the input.
fn append_arg(b: &mut Bytes, paths: &[String], out: &mut IterAppend) {
    match b.u8() % 12 {
        0 => out.append(WORDS[b.u8() as usize % WORDS.len()]),
        1 => out.append(String::from_utf8_lossy(b.piece()).replace('\0', "")),
        2 => out.append(b.u8() & 1 == 1),
        3 => out.append(b.u16()),
        4 => out.append(b.u32()),
        5 => out.append(b.u64()),
        6 => out.append(b.u16() as i16),
        7 => out.append(b.piece().to_vec()),
        8 => out.append(object(b, paths)),
        9 => out.append(variant(b, paths)),
        _ => out.append(options(b, paths)),
    }
}

fn variant(b: &mut Bytes, paths: &[String]) -> Variant<Box<dyn RefArg>> {
    Variant(match b.u8() % 8 {
        0 => Box::new(WORDS[b.u8() as usize % WORDS.len()].to_string()),
        1 => Box::new(b.u8() & 1 == 1),
        2 => Box::new(b.u16()),
        3 => Box::new(b.u64()),
        4 => Box::new(b.u16() as i16),
        5 => Box::new(b.piece().to_vec()),
        6 => Box::new(object(b, paths)),
        _ => Box::new(vec![WORDS[b.u8() as usize % WORDS.len()].to_string()]),
    })
}

fn options(b: &mut Bytes, paths: &[String]) -> PropMap {
    let n = b.u8() % 4;
    (0..n)
        .map(|_| {
            (
                WORDS[b.u8() as usize % WORDS.len()].to_string(),
                variant(b, paths),
            )
        })
        .collect()
}

fn object(b: &mut Bytes, paths: &[String]) -> Path<'static> {
    let i = b.u8() as usize;
    let p = paths
        .get(i % (paths.len() + 2))
        .cloned()
        .unwrap_or_else(|| "/org/bluez/hci0/dev_00_00_00_00_00_00".into());
    Path::new(p).unwrap_or_else(|_| Path::from("/"))
}

/// The object a call goes to: `pick % 6` says which kind (the adapter, a device, a service,
/// a characteristic, the root and its parents, one that is not there), `pick / 6` which one.
fn pick_object(pick: u8, paths: &[String]) -> String {
    let i = (pick / 6) as usize;
    let of = |f: &dyn Fn(&str) -> bool| -> Option<String> {
        let v: Vec<&String> = paths.iter().filter(|p| f(p)).collect();
        (!v.is_empty()).then(|| v[i % v.len()].clone())
    };
    let found = match pick % 6 {
        0 => Some("/org/bluez/hci0".to_string()),
        1 => of(&|p| p.contains("/dev_") && !p.contains("/service")),
        2 => of(&|p| p.contains("/service") && !p.contains("/char")),
        3 => of(&|p| p.contains("/char")),
        4 => Some(["/", "/org", "/org/bluez"][i % 3].to_string()),
        _ => None,
    };
    found.unwrap_or_else(|| "/org/bluez/hci0/dev_00_00_00_00_00_00".into())
}

/// The objects the service exports now, and a few it does not.
fn objects(conn: &Connection) -> Vec<String> {
    let proxy = conn.with_proxy("org.bluez", "/", Duration::from_secs(5));
    let (tree,): (HashMap<Path<'static>, HashMap<String, PropMap>>,) = proxy
        .method_call(
            "org.freedesktop.DBus.ObjectManager",
            "GetManagedObjects",
            (),
        )
        .expect("GetManagedObjects answers");
    let mut v: Vec<String> = tree.keys().map(|p| p.to_string()).collect();
    v.sort();
    v
}

fn known_error(name: &str) -> bool {
    name.starts_with("org.bluez.Error.") || name.starts_with("org.freedesktop.DBus.Error.")
}

pub fn run_input(data: &[u8]) {
    let address = bus().unwrap_or_else(|e| panic!("no private bus for the virtual BlueZ: {e}"));
    let mut b = Bytes::new(data);
    let opts = b.u8();
    let service = Service::start(address, opts & 1 == 1, opts & 2 == 2);
    let conn = Connection::new_address(address).expect("a client connection");
    let mut paths = objects(&conn);
    let mut calls = 0;
    while !b.is_empty() && calls < 64 {
        calls += 1;
        let pick = b.u8();
        if pick == 0xFF {
            // A forged NameOwnerChanged: someone else's connection must not go.
            let me = conn.unique_name().to_string();
            let forged = Message::new_signal(
                "/org/freedesktop/DBus",
                "org.freedesktop.DBus",
                "NameOwnerChanged",
            )
            .expect("a signal")
            .append3(me.as_str(), me.as_str(), "");
            let mut forged = forged;
            forged.set_destination(Some("org.bluez".into()));
            let _ = conn.channel().send(forged);
            continue;
        }
        let path = pick_object(pick, &paths);
        let (iface, members) = METHODS[b.u8() as usize % METHODS.len()];
        let m = b.u8() as usize;
        let member = members
            .get(m % (members.len() + 1))
            .copied()
            .unwrap_or("Frob");
        let mut msg = Message::new_method_call("org.bluez", path.as_str(), iface, member)
            .expect("a method call");
        {
            let mut args = IterAppend::new(&mut msg);
            for _ in 0..b.u8() % 5 {
                append_arg(&mut b, &paths, &mut args);
            }
        }
        match conn
            .channel()
            .send_with_reply_and_block(msg, Duration::from_secs(5))
        {
            Ok(_) => {}
            Err(e) => {
                let name = e.name().unwrap_or("");
                assert!(
                    known_error(name) && name != "org.freedesktop.DBus.Error.NoReply",
                    "{iface}.{member} on {path}: {name}: {:?}",
                    e.message()
                );
            }
        }
        assert!(
            service.alive(),
            "the virtual BlueZ stopped after {iface}.{member}"
        );
        if iface == "org.bluez.Adapter1" || iface == "org.bluez.Device1" {
            // Devices come with a discovery, the GATT objects with a connection (its
            // services resolve at the service's next step).
            if member == "Connect" {
                std::thread::sleep(Duration::from_millis(12));
            }
            paths = objects(&conn);
        }
    }
    drop(conn);
    let ended = service.finish();
    match ended {
        Ok(Ok(())) => {}
        Ok(Err(e)) => panic!("the virtual BlueZ failed: {e}"),
        Err(_) => panic!("the virtual BlueZ panicked"),
    }
}
