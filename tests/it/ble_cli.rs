//! `droidctl scan` as a process, on machines without Bluetooth: it must exit 1 quickly with
//! one line that names what is missing and mentions `--sim`.
//!
//! Beyond this machine's own "no system bus", the other cases run against a private bus
//! standing in for the system bus (`dbus-daemon` where installed, else busd in this process),
//! with a tiny fake BlueZ on it. That exercises the real btleplug path end to end.

// BlueZ and D-Bus exist only on Linux.
#![cfg(target_os = "linux")]

use dbus::arg::{PropMap, RefArg, Variant};
use dbus::blocking::Connection;
use dbus::channel::{Channel, MatchingReceiver, Sender};
use dbus::message::MatchRule;
use dbus::strings::ErrorName;
use dbus::{Message, Path};
use std::collections::HashMap;
use std::process::{Command, Output, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

fn droidctl(args: &[&str], system_bus: Option<&str>) -> (Output, Duration) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_droidctl"));
    cmd.args(args).stdin(Stdio::null());
    if let Some(addr) = system_bus {
        cmd.env("DBUS_SYSTEM_BUS_ADDRESS", addr);
    }
    let t0 = Instant::now();
    let out = cmd.output().expect("run droidctl");
    (out, t0.elapsed())
}

/// Exit 1, one line on stderr mentioning `--sim` and `want`, nothing on stdout, under 10 s.
fn assert_no_bluetooth(out: &Output, took: Duration, want: &str) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(took < Duration::from_secs(10), "took {took:?}");
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr:?}");
    assert!(stderr.contains("--sim"), "{stderr}");
    assert!(stderr.contains(want), "want {want:?} in {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(out.stdout.is_empty());
    stderr
}

#[test]
fn scan_without_a_system_bus_fails_fast() {
    let (out, took) = droidctl(
        &["scan", "--timeout", "1"],
        Some("unix:path=/nonexistent/droidctl-test/system_bus_socket"),
    );
    assert_no_bluetooth(&out, took, "no D-Bus system bus");
}

/// Exactly `droidctl scan --timeout 1` as run here (no Bluetooth, no system bus). Skipped on a
/// machine that has a system bus, where the answer depends on its Bluetooth.
#[test]
fn scan_on_this_machine_fails_fast() {
    if std::env::var_os("DBUS_SYSTEM_BUS_ADDRESS").is_some()
        || std::path::Path::new("/run/dbus/system_bus_socket").exists()
    {
        eprintln!("skipped: this machine has a D-Bus system bus");
        return;
    }
    let (out, took) = droidctl(&["scan", "--timeout", "1"], None);
    let line = assert_no_bluetooth(&out, took, "no D-Bus system bus");
    eprintln!("droidctl said: {line}");
}

#[test]
fn bad_timeouts_are_usage_errors() {
    let (out, _) = droidctl(&["scan", "--timeout", "0"], None);
    assert_eq!(out.status.code(), Some(2));
}

// -------------------------------------------------------------------------------------------
// A private bus with a fake BlueZ
// -------------------------------------------------------------------------------------------

/// A bus of our own: `sim --bluez`'s private bus (`dbus-daemon` where installed, else busd
/// in this process), stopped on drop.
struct Bus {
    _bus: droidctl::sim::bluez::PrivateBus,
    address: String,
}

impl Bus {
    fn start() -> Bus {
        let bus = droidctl::sim::bluez::PrivateBus::start().expect("a private D-Bus bus");
        let address = bus.address().to_string();
        Bus { _bus: bus, address }
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Bluez {
    NoAdapter,
    AdapterOff,
    Denied,
    /// One powered adapter that hears one R2-D2 and one other device.
    Working,
}

const ADAPTER: &str = "/org/bluez/hci0";
const DROID: &str = "/org/bluez/hci0/dev_F1_22_33_44_55_66";
const OTHER: &str = "/org/bluez/hci0/dev_0A_0B_0C_0D_0E_0F";

fn v<T: RefArg + 'static>(x: T) -> Variant<Box<dyn RefArg>> {
    Variant(Box::new(x))
}

fn adapter_props(powered: bool) -> PropMap {
    let mut p = PropMap::new();
    p.insert("Address".into(), v("00:11:22:33:44:55".to_string()));
    p.insert("AddressType".into(), v("public".to_string()));
    p.insert("Name".into(), v("fake".to_string()));
    p.insert("Alias".into(), v("fake".to_string()));
    p.insert("Modalias".into(), v("usb:v1D6Bp0246d0540".to_string()));
    p.insert("Powered".into(), v(powered));
    p.insert("Discovering".into(), v(false));
    p
}

fn device_props(address: &str, name: &str, rssi: i16) -> PropMap {
    let mut p = PropMap::new();
    p.insert("Address".into(), v(address.to_string()));
    p.insert("AddressType".into(), v("random".to_string()));
    p.insert("Name".into(), v(name.to_string()));
    // A renamed alias must not hide the advertised name.
    p.insert("Alias".into(), v(format!("my {name}")));
    p.insert("Adapter".into(), v(Path::from(ADAPTER)));
    p.insert("RSSI".into(), v(rssi));
    for flag in [
        "Paired",
        "Connected",
        "ServicesResolved",
        "Trusted",
        "Blocked",
        "LegacyPairing",
    ] {
        p.insert(flag.into(), v(false));
    }
    p
}

fn objects(mode: Bluez) -> HashMap<Path<'static>, HashMap<String, PropMap>> {
    let mut tree = HashMap::new();
    if mode == Bluez::NoAdapter {
        return tree;
    }
    let one = |iface: &str, p: PropMap| HashMap::from([(iface.to_string(), p)]);
    tree.insert(
        Path::from(ADAPTER),
        one(
            "org.bluez.Adapter1",
            adapter_props(mode != Bluez::AdapterOff),
        ),
    );
    if mode == Bluez::Working {
        tree.insert(
            Path::from(DROID),
            one(
                "org.bluez.Device1",
                device_props("F1:22:33:44:55:66", "D2-1A2B", -52),
            ),
        );
        tree.insert(
            Path::from(OTHER),
            one(
                "org.bluez.Device1",
                device_props("0A:0B:0C:0D:0E:0F", "Speaker", -40),
            ),
        );
    }
    tree
}

fn answer(mode: Bluez, msg: &Message) -> Message {
    let member = msg.member().map(|m| m.to_string()).unwrap_or_default();
    let path = msg.path().map(|p| p.to_string()).unwrap_or_default();
    let error = |name: &str, text: &str| {
        let text = std::ffi::CString::new(text).unwrap_or_default();
        msg.error(&ErrorName::from(name.to_string()), &text)
    };
    if mode == Bluez::Denied {
        return error(
            "org.freedesktop.DBus.Error.AccessDenied",
            "Rejected send message",
        );
    }
    match member.as_str() {
        "GetManagedObjects" => msg.method_return().append1(objects(mode)),
        "GetAll" => {
            let tree = objects(mode);
            let props = tree
                .get(&Path::from(path.clone()))
                .and_then(|ifaces| ifaces.values().next())
                .map(|p| {
                    p.iter()
                        .map(|(k, v)| (k.clone(), Variant(v.0.box_clone())))
                        .collect::<PropMap>()
                });
            match props {
                Some(p) => msg.method_return().append1(p),
                None => error("org.freedesktop.DBus.Error.UnknownObject", "no such object"),
            }
        }
        "Set" | "SetDiscoveryFilter" | "StartDiscovery" | "StopDiscovery" => msg.method_return(),
        _ => error("org.freedesktop.DBus.Error.UnknownMethod", "not faked"),
    }
}

/// Owns `org.bluez` on `bus` and answers like BlueZ in `mode`, until dropped.
struct FakeBluez {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FakeBluez {
    fn start(bus: &Bus, mode: Bluez) -> FakeBluez {
        let mut ch = Channel::open_private(&bus.address).expect("connect to the private bus");
        ch.register().expect("register");
        let conn = Connection::from(ch);
        conn.request_name("org.bluez", false, true, true)
            .expect("own org.bluez");
        conn.start_receive(
            MatchRule::new_method_call(),
            Box::new(move |msg, c| {
                let _ = c.send(answer(mode, &msg));
                true
            }),
        );
        let stop = Arc::new(AtomicBool::new(false));
        let stop2 = stop.clone();
        let thread = std::thread::spawn(move || {
            while !stop2.load(Ordering::Relaxed) {
                let _ = conn.process(Duration::from_millis(50));
            }
        });
        FakeBluez {
            stop,
            thread: Some(thread),
        }
    }
}

impl Drop for FakeBluez {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn with_bus(f: impl FnOnce(&Bus)) {
    f(&Bus::start())
}

#[test]
fn scan_with_a_bus_but_no_bluez() {
    with_bus(|bus| {
        let (out, took) = droidctl(&["scan", "--timeout", "1"], Some(&bus.address));
        assert_no_bluetooth(&out, took, "BlueZ (bluetoothd) is not running");
    });
}

#[test]
fn scan_with_bluez_but_no_adapter() {
    with_bus(|bus| {
        let _bluez = FakeBluez::start(bus, Bluez::NoAdapter);
        let (out, took) = droidctl(&["scan", "--timeout", "1"], Some(&bus.address));
        assert_no_bluetooth(&out, took, "no Bluetooth adapter found");
    });
}

#[test]
fn scan_with_the_adapter_off() {
    with_bus(|bus| {
        let _bluez = FakeBluez::start(bus, Bluez::AdapterOff);
        let (out, took) = droidctl(&["scan", "--timeout", "1"], Some(&bus.address));
        assert_no_bluetooth(&out, took, "bluetoothctl power on");
    });
}

#[test]
fn scan_when_bluez_says_no() {
    with_bus(|bus| {
        let _bluez = FakeBluez::start(bus, Bluez::Denied);
        let (out, took) = droidctl(&["scan", "--timeout", "1"], Some(&bus.address));
        assert_no_bluetooth(&out, took, "`bluetooth` group");
    });
}

#[test]
fn scan_through_btleplug_lists_the_droid() {
    with_bus(|bus| {
        let _bluez = FakeBluez::start(bus, Bluez::Working);
        let (out, took) = droidctl(&["scan", "--timeout", "1"], Some(&bus.address));
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{stderr}");
        assert!(took < Duration::from_secs(10));
        assert_eq!(
            stdout,
            "NAME     MODEL  ADDRESS            RSSI\n\
             D2-1A2B  R2-D2  F1:22:33:44:55:66  -52 dBm\n"
        );
        let (out, _) = droidctl(
            &["scan", "--timeout", "0.5", "--all", "--json"],
            Some(&bus.address),
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        let lines: Vec<&str> = stdout.lines().collect();
        assert_eq!(lines.len(), 2, "{stdout}");
        assert!(
            lines[0].contains(r#""name":"Speaker","model":null"#),
            "{stdout}"
        );
        assert!(lines[1].contains(r#""model":"r2d2""#), "{stdout}");
    });
}
