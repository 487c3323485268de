//! `droidctl sim --bluez`: simulated droids served on D-Bus as BlueZ serves real ones, so any
//! BlueZ client (droidctl itself, Python's bleak, other tools) scans, connects and drives them
//! through its ordinary Bluetooth code.
//!
//! The service owns `org.bluez` on a bus and exports what BlueZ exports for an adapter with
//! droids in range:
//! - `/org/bluez/hci0`: `org.bluez.Adapter1` (Address, Name, Alias, Powered, Discovering …;
//!   StartDiscovery, StopDiscovery, SetDiscoveryFilter, GetDiscoveryFilters, RemoveDevice),
//!   with BlueZ's per-client discovery sessions;
//! - one `org.bluez.Device1` per droid, appearing once a client starts discovery (Address,
//!   Name, Alias, RSSI, Connected, ServicesResolved, UUIDs …; Connect, Disconnect). As in
//!   BlueZ, a device has an RSSI only while a discovery hears it: it goes (invalidated) when
//!   discovery stops, and a connected or sleeping droid does not advertise. Remembered
//!   devices (`--remembered`) are on the bus from the start, never advertise, and a Connect
//!   to them (or to a droid that fell asleep, `--idle-sleep`) fails after a few seconds with
//!   `le-connection-abort-by-local`;
//! - `Powered` can be set as `bluetoothctl power off|on` does: powering off fails pending
//!   connection attempts, disconnects every droid, ends discovery and signals it all;
//! - while a connection's services are resolved, the droid's GATT table below its device:
//!   `org.bluez.GattService1` (UUID, Primary, Device) and `org.bluez.GattCharacteristic1`
//!   (UUID, Service, Flags, Value, Notifying; ReadValue, WriteValue, StartNotify, StopNotify),
//!   notifications as `PropertiesChanged` on `Value`;
//! - `org.freedesktop.DBus.ObjectManager` on `/` (GetManagedObjects, InterfacesAdded and
//!   InterfacesRemoved), `org.freedesktop.DBus.Properties` (Get, GetAll, Set,
//!   PropertiesChanged) and `org.freedesktop.DBus.Introspectable` on every object.
//!
//! Behind each device is a [`GattDroid`](super::gatt::GattDroid): the `--sim` droid with its
//! handshake, notification cutting, faults and idle sleep; `--trace` decodes what it receives
//! and sends with [`PacketTracer`](super::trace::PacketTracer). The service runs on one thread of its own,
//! on the wall clock. Without `--bus`, [`PrivateBus`] starts a `dbus-daemon` for it.
//!
//! Differences from BlueZ worth knowing: a second client asking to connect a droid someone
//! else has connected is refused (the droid holds one connection); a client that leaves the
//! bus drops the connection it made; the GATT objects exist only while a connection's
//! services are resolved (as without BlueZ's cache); `AcquireNotify`, `AcquireWrite` and
//! pairing are not supported (clients fall back to `StartNotify` and `WriteValue`).

mod daemon;
mod server;
mod xml;

pub use daemon::PrivateBus;
pub use server::BluezSim;

use crate::model::Model;
use crate::rng::Rng;
use crate::sim::gatt::GattFaults;

/// The most droids one service serves.
pub const MAX_DROIDS: usize = 16;

/// One virtual droid: what it is, and how it advertises.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DroidSpec {
    pub model: Model,
    /// The advertised name (`D2-5117`, `BB-3A0F`, `Robi 42`).
    pub name: String,
    /// A random static address, as the droids use.
    pub address: [u8; 6],
    /// The signal strength it is heard at (it varies by ±3 dBm around this).
    pub rssi: i16,
}

impl DroidSpec {
    /// `F1:22:33:44:51:17`.
    pub fn address_string(&self) -> String {
        self.address
            .iter()
            .map(|b| format!("{b:02X}"))
            .collect::<Vec<_>>()
            .join(":")
    }
}

/// Names, addresses and signal strengths for `models`, from `seed`: distinct addresses, names
/// as the droids make them (the model's prefix and the address's last two bytes), the
/// first droid the strongest.
pub fn plan(models: &[Model], seed: u64) -> Vec<DroidSpec> {
    let mut rng = Rng::new(seed);
    let mut out: Vec<DroidSpec> = Vec::new();
    for (i, &model) in models.iter().enumerate() {
        let address = loop {
            let mut a = [0u8; 6];
            for b in &mut a {
                *b = rng.byte();
            }
            // Random static: the two top bits set.
            a[0] |= 0xC0;
            if out.iter().all(|d| d.address != a) {
                break a;
            }
        };
        let name = match model.name_prefix() {
            Some(prefix) => format!("{prefix}{:02X}{:02X}", address[4], address[5]),
            None => model.display_name().to_string(),
        };
        // 8 dBm apart: more than the ±3 dBm they vary by, so the order holds.
        let rssi = (-45 - 8 * i as i16).max(-90);
        out.push(DroidSpec {
            model,
            name,
            address,
            rssi,
        });
    }
    out
}

/// Split a plan of droids in range followed by `remembered` remembered ones.
pub fn plan_with_remembered(
    models: &[Model],
    remembered: &[Model],
    seed: u64,
) -> (Vec<DroidSpec>, Vec<DroidSpec>) {
    let all: Vec<Model> = models.iter().chain(remembered).copied().collect();
    let mut droids = plan(&all, seed);
    let remembered = droids.split_off(models.len());
    (droids, remembered)
}

/// A line the service reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Report {
    /// A status line for people (connections, faults; the text trace).
    Status(String),
    /// One JSON line of the trace (`--trace --json`).
    Trace(String),
}

/// What to serve.
#[derive(Debug, Clone)]
pub struct BluezOptions {
    /// The droids in range.
    pub droids: Vec<DroidSpec>,
    /// Devices BlueZ remembers that are not in range: on the bus from the start, no RSSI,
    /// never advertising; connecting to them fails after a few seconds.
    pub remembered: Vec<DroidSpec>,
    /// The same faults for every droid.
    pub faults: GattFaults,
    /// Seed for the signal-strength jitter.
    pub seed: u64,
    /// Report every packet received and sent, decoded.
    pub trace: bool,
    /// The trace as JSON lines.
    pub json: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_addresses_look_real() {
        let droids = plan(&[Model::R2D2, Model::R2D2, Model::BB8, Model::Robi42], 42);
        assert_eq!(
            plan(&[Model::R2D2], 42)[0],
            droids[0],
            "same seed, same droid"
        );
        for d in &droids {
            assert!(
                d.address[0] >= 0xC0,
                "random static: {}",
                d.address_string()
            );
            assert_eq!(
                Model::from_advertised_name(&d.name),
                Some(d.model),
                "{}",
                d.name
            );
            assert!((-90..=-40).contains(&d.rssi));
        }
        assert!(droids[0].name.starts_with("D2-") && droids[0].name.len() == 7);
        assert!(droids[0].name.ends_with(&format!(
            "{:02X}{:02X}",
            droids[0].address[4], droids[0].address[5]
        )));
        assert_ne!(droids[0].name, droids[1].name);
        assert_ne!(droids[0].address, droids[1].address);
        assert_eq!(droids[3].name, "Robi 42");
        assert!(droids[0].rssi > droids[1].rssi);
    }
}
