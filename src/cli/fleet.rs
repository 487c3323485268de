//! Several droids from the command line: `--sim r2d2,bb8,robi` (simulated droids sharing one
//! room), repeated `--name` (droids in Bluetooth range: one scan, then each droid's link,
//! whose connection attempts take turns on the adapter, at most `fleet.max_per_adapter` per
//! adapter), repeated `--remote [NAME@]HOST[:PORT]` (droids behind relays), and mixes of
//! them. One of each is the one-droid command as it always was.

use super::CliError;
use crate::config::Config;
use crate::family::setup::connect_setup;
use crate::fleet::DroidSpec;
use crate::fleet::gate::{Adapters, GatedLink};
use crate::link::Link;
use crate::link::remote::RelayAddr;
use crate::model::Model;
use crate::session::SessionConfig;
use crate::sim::room::SharedRoom;
use crate::sim::{Faults, SimConfig, SimLink};
use std::time::Duration;

/// The most droids one command drives.
pub const MAX_DROIDS: usize = 16;

/// `--remote [NAME@]HOST[:PORT]`: a relay, and which of its droids.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RemoteSpec {
    pub name: Option<String>,
    pub relay: RelayAddr,
}

impl std::str::FromStr for RemoteSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s.split_once('@') {
            Some((name, relay)) if !name.trim().is_empty() => Ok(RemoteSpec {
                name: Some(name.trim().to_string()),
                relay: relay.parse()?,
            }),
            Some(_) => Err(format!("`{s}`: a name goes before the @ (NAME@HOST)")),
            None => Ok(RemoteSpec {
                name: None,
                relay: s.parse()?,
            }),
        }
    }
}

impl std::fmt::Display for RemoteSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.name {
            Some(n) => write!(f, "{n}@{}", self.relay),
            None => write!(f, "{}", self.relay),
        }
    }
}

/// `--sim MODEL[,MODEL…]`: the simulated models asked for.
pub fn sim_models(list: &str) -> Result<Vec<Model>, CliError> {
    let models: Vec<Model> = list
        .split(',')
        .map(str::trim)
        .filter(|m| !m.is_empty())
        .map(|m| match Model::from_id(m) {
            Some(model) if crate::sim::simulates(model) => Ok(model),
            _ => Err(CliError::usage(format!(
                "{} (several: --sim r2d2,bb8,robi)",
                Model::parse_id(m).err().unwrap_or_default()
            ))),
        })
        .collect::<Result<_, _>>()?;
    if models.is_empty() {
        return Err(CliError::usage("--sim needs a model, e.g. --sim r2d2,bb8"));
    }
    if models.len() > MAX_DROIDS {
        return Err(CliError::usage(format!(
            "at most {MAX_DROIDS} droids at once"
        )));
    }
    Ok(models)
}

/// Whether these arguments name several droids (else the one-droid path runs unchanged).
pub fn is_fleet(sims: usize, ble: &super::connect::BleArgs) -> bool {
    let named = ble.name.len();
    let remotes = ble.remote.len();
    // `--remote HOST --name NAME` is one droid behind one relay, as always.
    let one_remote = remotes == 1 && named <= 1 && ble.remote[0].name.is_none();
    sims + named + remotes > 1 && !(sims == 0 && one_remote)
}

/// The session settings for a droid of `model` under `config` (the app's: the streaming the
/// config asks for, capped to the droid's link; tripod on connect when `tripod`).
pub fn session_config(model: Model, config: &Config, tripod: bool) -> SessionConfig {
    let (mut setup, _) = crate::family::setup::from_config(model, config);
    setup.tripod = tripod;
    let pacing = match config.session.pacing_ms {
        0 => model.write_pacing(),
        ms => Duration::from_millis(ms),
    };
    SessionConfig {
        family: model.protocol(),
        model: Some(model),
        request_timeout: Duration::from_millis(config.session.request_timeout_ms),
        pacing,
        setup: connect_setup(model, &setup),
        ..SessionConfig::default()
    }
}

/// A droid found, not yet connected: its link and who it is.
pub struct Found {
    pub link: Box<dyn Link>,
    pub model: Model,
    pub name: String,
    pub origin: String,
    /// Where it starts in the room the simulated droids share ([`DroidSpec::room_origin`]).
    pub room_origin: Option<(f32, f32)>,
}

/// Record every droid of `found` into `rec` (one file, each droid's lines apart), starting
/// its clock now; nothing without a recorder.
pub fn record_all(rec: Option<&crate::capture::record::Recorder>, found: &mut [Found]) {
    let Some(rec) = rec else {
        return;
    };
    let headers: Vec<_> = found
        .iter()
        .map(|f| crate::capture::record::Recorder::header_for(f.model, &f.name))
        .collect();
    rec.start_fleet(&headers);
    for (i, f) in found.iter_mut().enumerate() {
        let link = std::mem::replace(&mut f.link, Box::new(Unplugged));
        f.link = rec.for_droid(i).wrap(link);
    }
}

/// A placeholder link while another is moved into its recorder.
struct Unplugged;

impl Link for Unplugged {
    fn open(
        &mut self,
    ) -> futures_util::future::BoxFuture<'_, Result<crate::link::Connection, crate::link::LinkError>>
    {
        Box::pin(async { Err(crate::link::LinkError::fatal("no link")) })
    }
    fn describe(&self) -> String {
        "no link".into()
    }
}

impl Found {
    pub fn into_spec(self, session: SessionConfig) -> DroidSpec {
        DroidSpec {
            name: self.name,
            model: self.model,
            link: self.link,
            session,
            origin: self.origin,
            room_origin: self.room_origin,
        }
    }
}

/// Simulated droids sharing one room, in a row, named as `serve --sim` names them
/// (`D2-0001`, `BB-0002`, `Robi 42`).
pub fn simulated(models: &[Model]) -> Vec<Found> {
    let room = SharedRoom::new();
    let origins = SharedRoom::origins(models.len());
    models
        .iter()
        .zip(origins)
        .enumerate()
        .map(|(i, (&m, origin))| {
            let mut cfg = SimConfig::for_model(m);
            cfg.place = Some(room.place(origin, cfg.radius_cm));
            Found {
                link: Box::new(SimLink::new(m, cfg, Faults::none())),
                model: m,
                name: crate::relay::sim_backend::sim_name(m, i),
                origin: "simulated".into(),
                room_origin: Some(origin),
            }
        })
        .collect()
}

/// Every droid these arguments name: the simulated ones, then the relays' (each asked in
/// turn), then those in Bluetooth range (one scan for all of them). Progress on stderr.
pub async fn find_all(
    sims: &[Model],
    ble: &super::connect::BleArgs,
    config: &Config,
) -> Result<Vec<Found>, CliError> {
    let total = sims.len() + ble.name.len() + ble.remote.len() + usize::from(ble.serial.is_some());
    if total > MAX_DROIDS {
        return Err(CliError::usage(format!(
            "{total} droids asked for: at most {MAX_DROIDS} at once"
        )));
    }
    let mut found = simulated(sims);
    if let Some(port) = &ble.serial {
        let c = super::connect::connect_serial(port).await?;
        found.push(Found {
            link: c.link,
            model: c.model,
            name: c.name,
            origin: format!("serial {}", port.display()),
            room_origin: None,
        });
    }
    let scan_timeout = Duration::from_secs(ble.scan_timeout);
    for r in &ble.remote {
        let c = super::connect::connect_remote(&r.relay, r.name.clone(), None, scan_timeout)
            .await
            .map_err(|e| CliError::failure(format!("{r}: {}", e.message)))?;
        eprintln!(
            "droidctl: {} ({}) via {}",
            c.name,
            c.model.display_name(),
            r.relay
        );
        found.push(Found {
            link: c.link,
            model: c.model,
            name: c.name,
            origin: format!("relay {}", r.relay),
            room_origin: None,
        });
    }
    if !ble.name.is_empty() {
        let cap = config.fleet.max_per_adapter;
        found.extend(bluetooth(&ble.name, &ble.adapter, scan_timeout, cap).await?);
    }
    // Two droids may not go by one name: a mission's `@NAME` must say which.
    for (i, f) in found.iter().enumerate() {
        if found[..i].iter().any(|g| g.name == f.name) {
            return Err(CliError::usage(format!(
                "{} is named twice: name each droid once",
                f.name
            )));
        }
    }
    Ok(found)
}

/// The droids `names` name, from one scan on the first adapter; each droid goes to the
/// adapter (of `adapters`, or every one that is on) holding the fewest so far, at most `cap`
/// each, and its link's connection attempts take turns there.
async fn bluetooth(
    names: &[String],
    adapters: &[String],
    scan_timeout: Duration,
    cap: usize,
) -> Result<Vec<Found>, CliError> {
    use crate::link::ble::{BleLink, DeviceSelector, open_adapters, scan};
    let fail = |e: crate::link::ble::BleError| CliError::failure(e.message);
    let centrals = open_adapters(adapters).await.map_err(fail)?;
    let selectors: Vec<DeviceSelector> = names
        .iter()
        .map(|n| DeviceSelector {
            name: Some(n.clone()),
            address: None,
            scan_timeout,
        })
        .collect();
    eprintln!(
        "droidctl: scanning for {} ({} s)…",
        names.join(", "),
        scan_timeout.as_secs()
    );
    let Some((_, first)) = centrals.first() else {
        return Err(CliError::failure("no Bluetooth adapter"));
    };
    let known = scan::scan_known(first.as_ref(), scan_timeout, |heard| {
        selectors.iter().all(|s| s.satisfied_by(heard))
    })
    .await
    .map_err(fail)?;
    let gates = Adapters::new(cap);
    let adapter_names: Vec<String> = centrals.iter().map(|(n, _)| n.clone()).collect();
    let mut out = Vec::new();
    for sel in &selectors {
        let e = scan::pick(&known, sel).map_err(fail)?;
        let model = e.model.filter(|m| m.drivable()).ok_or_else(|| {
            CliError::failure(format!("{} is not a droid droidctl drives", e.label()))
        })?;
        let name = e.label();
        let i = gates.least_loaded(&adapter_names);
        let (adapter, central) = &centrals[i];
        let gate = gates
            .admit(adapter, &name)
            .map_err(|over| CliError::failure(over.to_string()))?;
        let via = if centrals.len() > 1 {
            format!(" via {adapter}")
        } else {
            String::new()
        };
        eprintln!("droidctl: {name} ({}, {}){via}", model.display_name(), e.id);
        let link = BleLink::new(
            central.clone(),
            e.id.clone(),
            name.clone(),
            model,
            crate::family::gatt_profile(model),
        );
        out.push(Found {
            link: Box::new(GatedLink::new(Box::new(link), gate)),
            model,
            name,
            origin: format!("Bluetooth {adapter}"),
            room_origin: None,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::connect::BleArgs;

    #[test]
    fn sim_lists_and_remote_specs() {
        assert_eq!(
            sim_models("r2d2, bb8,robi").unwrap(),
            vec![Model::R2D2, Model::BB8, Model::Robi42]
        );
        assert!(sim_models("r2d2,toaster").is_err());
        assert!(sim_models(",").is_err());
        let r: RemoteSpec = "D2-0001@pi.local:6000".parse().unwrap();
        assert_eq!(r.name.as_deref(), Some("D2-0001"));
        assert_eq!(r.relay.port, 6000);
        assert_eq!(r.to_string(), "D2-0001@pi.local:6000");
        assert!("@pi".parse::<RemoteSpec>().is_err());
        assert_eq!("pi".parse::<RemoteSpec>().unwrap().name, None);
    }

    #[test]
    fn one_of_each_is_the_one_droid_path() {
        let ble = |names: &[&str], remotes: &[&str]| BleArgs {
            name: names.iter().map(|s| s.to_string()).collect(),
            remote: remotes.iter().map(|s| s.parse().unwrap()).collect(),
            ..BleArgs::default()
        };
        assert!(!is_fleet(1, &ble(&[], &[])));
        assert!(!is_fleet(0, &ble(&["D2"], &[])));
        assert!(
            !is_fleet(0, &ble(&["D2"], &["pi"])),
            "--remote pi --name D2 is one droid"
        );
        assert!(is_fleet(2, &ble(&[], &[])));
        assert!(is_fleet(0, &ble(&["A", "B"], &[])));
        assert!(is_fleet(0, &ble(&[], &["pi", "pi2"])));
        assert!(is_fleet(1, &ble(&["A"], &[])));
        assert!(is_fleet(0, &ble(&["A"], &["X@pi"])));
    }

    #[tokio::test(start_paused = true)]
    async fn simulated_droids_share_a_room_and_have_names() {
        let f = simulated(&[Model::R2D2, Model::BB8, Model::Robi42]);
        let names: Vec<&str> = f.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["D2-0001", "BB-0002", "Robi 42"]);
    }
}
