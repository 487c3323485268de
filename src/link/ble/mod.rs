//! Bluetooth LE: scanning for droids and [`BleLink`], the [`crate::link::Link`] to a real one.
//!
//! Layers, each testable without the one below:
//! - [`crate::gatt`]: GATT profiles as data (each family describes its droids');
//! - [`backend`]: the radio-free interface ([`BleCentral`], [`BlePeripheral`]);
//! - [`BleLink`] and [`scan`]: the generic logic, written against that interface;
//! - `btleplug_backend` (the real radio: BlueZ, CoreBluetooth or WinRT) and [`fake`] (tests):
//!   its two implementations.
//!
//! Entry points for commands: [`open_central`] + [`scan::scan`] for `droidctl scan`, and
//! [`connect_link`] for everything that drives a droid.

pub mod backend;
mod btleplug_backend;
pub mod error;
pub mod fake;
mod link;
pub mod scan;

pub use backend::{
    Advertisement, BleAddress, BleCentral, BlePeripheral, DeviceId, DiscoveredChar, KnownDevice,
    PeripheralEvent,
};
pub use btleplug_backend::{open_adapters, open_central};
pub use error::{BleError, BleErrorKind, Os};
pub use link::{BleLink, BleTimeouts};
pub use scan::{DeviceSelector, ScanEntry};

use crate::gatt::GattProfile;
use crate::model::Model;
use std::sync::Arc;

/// The droid [`connect_link`] chose, and what else was heard.
pub struct FoundDroid {
    /// Not yet connected: hand it to `session::start`, which calls `open()` (and again on
    /// every reconnect). `Box::new(found.link)` makes it a `Box<dyn Link>`.
    pub link: BleLink,
    pub model: Model,
    pub name: String,
    /// Who it is: what `--address` matches.
    pub id: DeviceId,
    /// Its address (the stand-in where the platform hides it).
    pub address: BleAddress,
    /// Every device heard, strongest first, unsupported ones included (`model: None`): what a
    /// picker would offer. Devices only remembered by the computer are not in it.
    pub candidates: Vec<ScanEntry>,
}

/// Find the droid `sel` asks for and build a [`BleLink`] to it, with the GATT profile
/// `profile_of` gives for its model (`crate::family::gatt_profile`: the link layer runs a
/// profile, the families know them).
///
/// Opens the system's Bluetooth adapter, scans for up to `sel.scan_timeout` (stopping early
/// once a droid asked for by `--name` or `--address` is heard), then picks among the devices
/// heard (advertising during the scan, or connected): `sel.address`, else `sel.name`
/// (case-insensitive, exact or a unique part such as `1A2B`), else the strongest droid this
/// build can drive. A name or address matching only a device the computer remembers fails
/// with one line saying it is not in range. The returned link is not connected yet; the
/// session connects it.
///
/// Errors are one line for the user, ending in what to do. `BleError::fatal()` is true for
/// "no Bluetooth here" (no D-Bus system bus, BlueZ not running, no adapter, adapter off,
/// permission denied) and for a device that is not a droid; the messages mention `--sim`.
/// `NotFound` (nothing matching heard) is not fatal: scanning again may find a droid that
/// was asleep. Example:
///
/// ```no_run
/// # async fn f() -> Result<(), droidctl::link::ble::BleError> {
/// use droidctl::link::ble::{DeviceSelector, connect_link};
/// use droidctl::session::{self, SessionConfig};
/// let found = connect_link(&DeviceSelector::default(), droidctl::family::gatt_profile).await?;
/// let profile = found.link.profile().clone();
/// let cfg = SessionConfig { pacing: profile.pacing, chunk_size: profile.chunk_size, ..Default::default() };
/// let session = session::start(Box::new(found.link), cfg);
/// # Ok(()) }
/// ```
pub async fn connect_link(
    sel: &DeviceSelector,
    profile_of: fn(Model) -> GattProfile,
) -> Result<FoundDroid, BleError> {
    let central = open_central().await?;
    connect_link_with(central, sel, profile_of).await
}

/// [`connect_link`] on a given adapter (the fake one in tests).
pub async fn connect_link_with(
    central: Arc<dyn BleCentral>,
    sel: &DeviceSelector,
    profile_of: fn(Model) -> GattProfile,
) -> Result<FoundDroid, BleError> {
    let mut known =
        scan::scan_known(central.as_ref(), sel.scan_timeout, |e| sel.satisfied_by(e)).await?;
    let chosen = scan::pick(&known, sel)?.clone();
    let model = chosen.model.ok_or_else(|| {
        BleError::new(BleErrorKind::Selection, "the chosen device is not a droid")
    })?;
    let name = chosen.label();
    tracing::info!(%name, device = %chosen.id, model = model.display_name(), "chose droid");
    known.retain(|e| e.heard);
    Ok(FoundDroid {
        link: BleLink::new(
            central,
            chosen.id.clone(),
            name.clone(),
            model,
            profile_of(model),
        ),
        model,
        name,
        id: chosen.id,
        address: chosen.address,
        candidates: known,
    })
}
