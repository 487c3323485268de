//! Finding a droid behind a relay: SCAN and FIND, and the choice among what the relay
//! heard.

use super::client::RelayClient;
use super::{RelayAddr, RemoteLink, RemoteTimeouts};
use crate::gatt::GattProfile;
use crate::link::LinkError;
use crate::model::Model;
use crate::protocol::relay::{Device, Reply, Request};
use std::time::Duration;

/// A device behind a relay, as its scan lists it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RemoteDevice {
    pub name: String,
    /// As the relay names it; INIT takes it back unchanged.
    pub address: String,
    pub model: Option<Model>,
}

impl RemoteDevice {
    fn from_device(d: Device) -> Self {
        RemoteDevice {
            model: Model::from_advertised_name(&d.name),
            name: d.name,
            address: d.address,
        }
    }

    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "name": self.name,
            "model": self.model.map(Model::id),
            "model_name": self.model.map(Model::display_name),
            "address": self.address,
            "rssi": null,
            // The relay lists what its scan heard.
            "heard": true,
        })
    }
}

/// Every device the relay hears within `scan` (SCAN).
pub async fn scan(relay: &RelayAddr, scan: Duration) -> Result<Vec<RemoteDevice>, LinkError> {
    let t = RemoteTimeouts::default();
    let (client, _events) = RelayClient::connect(relay, t.connect).await?;
    let r = client
        .discover(
            Request::Scan {
                timeout: scan.as_secs_f32(),
            },
            scan + t.op + Duration::from_secs(5),
        )
        .await;
    client.close().await;
    match r.map_err(LinkError::transient)? {
        Reply::Devices(ds) => Ok(ds.into_iter().map(RemoteDevice::from_device).collect()),
        Reply::Error { message, .. } => Err(LinkError::transient(format!(
            "the relay at {relay} could not scan: {message}"
        ))),
        other => Err(LinkError::transient(format!(
            "the relay at {relay} answered SCAN with {other:?}"
        ))),
    }
}

/// The device advertising exactly `name` (FIND); `None` when the relay did not hear it.
pub async fn find(
    relay: &RelayAddr,
    name: &str,
    scan: Duration,
) -> Result<Option<RemoteDevice>, LinkError> {
    let t = RemoteTimeouts::default();
    let (client, _events) = RelayClient::connect(relay, t.connect).await?;
    let r = client
        .discover(
            Request::Find {
                name: name.to_string(),
                timeout: scan.as_secs_f32(),
            },
            scan + t.op + Duration::from_secs(5),
        )
        .await;
    client.close().await;
    match r.map_err(LinkError::transient)? {
        Reply::Found(d) => Ok(Some(RemoteDevice::from_device(d))),
        Reply::Error { message, .. } if message.is_empty() => Ok(None),
        Reply::Error { message, .. } => Err(LinkError::transient(format!(
            "the relay at {relay} could not scan: {message}"
        ))),
        other => Err(LinkError::transient(format!(
            "the relay at {relay} answered FIND with {other:?}"
        ))),
    }
}

/// How to choose the droid behind a relay.
#[derive(Debug, Clone, Default)]
pub struct RemoteSelector {
    /// Advertised name: exact (FIND first), or a unique part (case-insensitive).
    pub name: Option<String>,
    /// The address as the relay lists it (case-insensitive).
    pub address: Option<String>,
    pub scan_timeout: Duration,
}

/// Find the droid `sel` asks for behind `relay` and build the link to it (not connected yet),
/// with the GATT profile `profile_of` gives for its model.
pub async fn select(
    relay: &RelayAddr,
    sel: &RemoteSelector,
    profile_of: fn(Model) -> GattProfile,
) -> Result<RemoteLink, LinkError> {
    let secs = sel.scan_timeout.as_secs_f64();
    let mut chosen = None;
    if let (Some(name), None) = (&sel.name, &sel.address) {
        // FIND answers as soon as the droid is heard.
        chosen = find(relay, name, sel.scan_timeout).await?;
    }
    let chosen = match chosen {
        Some(d) => d,
        None => {
            let all = scan(relay, sel.scan_timeout).await?;
            pick(&all, sel).map_err(|e| {
                LinkError::transient(format!("{e} (the relay at {relay} scanned {secs:.0} s)"))
            })?
        }
    };
    let model = chosen.model.ok_or_else(|| {
        LinkError::fatal(format!(
            "{} ({}) behind the relay is not a droid droidctl knows",
            chosen.name, chosen.address
        ))
    })?;
    tracing::info!(name = %chosen.name, address = %chosen.address, %relay, "chose droid behind relay");
    Ok(RemoteLink::new(
        relay.clone(),
        chosen.address,
        chosen.name,
        model,
        profile_of(model),
    ))
}

/// Choose among the devices a relay listed.
pub fn pick(all: &[RemoteDevice], sel: &RemoteSelector) -> Result<RemoteDevice, String> {
    let droids: Vec<&RemoteDevice> = all.iter().filter(|d| d.model.is_some()).collect();
    let names = |ds: &[&RemoteDevice]| {
        ds.iter()
            .map(|d| format!("{} ({})", d.name, d.address))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if let Some(a) = &sel.address {
        let want = a.trim();
        let same = |d: &&RemoteDevice| {
            d.address.eq_ignore_ascii_case(want)
                || matches!(
                    (
                        d.address.parse::<crate::link::ble::BleAddress>(),
                        want.parse::<crate::link::ble::BleAddress>()
                    ),
                    (Ok(x), Ok(y)) if x == y
                )
        };
        return all
            .iter()
            .find(same)
            .cloned()
            .ok_or_else(|| format!("no device at {want} behind the relay"));
    }
    if let Some(n) = &sel.name {
        let lower = n.to_lowercase();
        if let Some(d) = all.iter().find(|d| d.name.to_lowercase() == lower) {
            return Ok(d.clone());
        }
        let parts: Vec<&RemoteDevice> = all
            .iter()
            .filter(|d| d.name.to_lowercase().contains(&lower))
            .collect();
        return match parts.as_slice() {
            [one] => Ok((*one).clone()),
            [] => Err(format!("no droid named like {n:?} behind the relay")),
            many => Err(format!(
                "{n:?} matches several devices behind the relay: {} — give more of the name",
                names(many)
            )),
        };
    }
    match droids.as_slice() {
        [one] => Ok((*one).clone()),
        [] => Err("no droid behind the relay — wake it (tap it or put it on its charger)".into()),
        many => Err(format!(
            "several droids behind the relay: {} — choose one with --name or --address",
            names(many)
        )),
    }
}
