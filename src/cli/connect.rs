//! Connecting to a real droid for `droidctl`/`drive` and `run`: scan, pick, check the model
//! speaks what droidctl drives, and build the link. Errors are one line saying what to do.

use super::CliError;
use crate::link::Link;
use crate::link::ble::{DeviceId, DeviceSelector, ScanEntry, connect_link_with};
use crate::model::Model;
use std::io::{BufRead, IsTerminal, Write};
use std::time::Duration;

/// How to choose a real droid (the commands that take `--sim` also take these).
#[derive(Debug, Clone, Default, clap::Args)]
pub struct BleArgs {
    /// Connect to the droid with this advertised name (e.g. D2-1A2B; a unique part is enough).
    /// Repeat it to drive several droids at once (a fleet).
    #[arg(long, value_name = "NAME")]
    pub name: Vec<String>,
    /// Connect to the droid with this Bluetooth address (on macOS, the device identifier
    /// `droidctl scan` shows in its place).
    #[arg(long, value_name = "ADDR", conflicts_with_all = ["sim", "name"])]
    pub address: Option<String>,
    /// How long to scan for droids, in seconds.
    #[arg(long, default_value_t = 5, value_name = "SECS", value_parser = clap::value_parser!(u64).range(1..=120))]
    pub scan_timeout: u64,
    /// Drive a droid behind a relay on another machine: `droidctl serve` or spherov2.py's
    /// tcp_server at HOST[:PORT] (port 50004 by default); NAME@HOST picks one of its droids.
    /// Repeat it for several relays (a fleet).
    #[arg(long, value_name = "[NAME@]HOST[:PORT]")]
    pub remote: Vec<super::fleet::RemoteSpec>,
    /// Use this Bluetooth adapter (hci0, hci1 …); repeat it to share a fleet's droids between
    /// several. Without it: the first adapter for one droid, every adapter that is on for
    /// several.
    #[arg(long, value_name = "NAME")]
    pub adapter: Vec<String>,
    /// Drive an RVR on this serial port instead of over Bluetooth: a Raspberry Pi's UART
    /// (/dev/serial0) or a USB serial adapter, at 115200 baud (see docs/serial.md).
    #[arg(long, value_name = "PORT", conflicts_with_all = ["sim", "name", "address", "remote", "adapter"])]
    pub serial: Option<std::path::PathBuf>,
}

/// How to ask which droid, when several answer and none was named.
#[derive(Debug, Clone, PartialEq)]
pub enum Chooser {
    /// A numbered list on stderr and an answer on stdin (`run`).
    Prompt,
    /// A full-screen list (the app), read with these bindings and drawn in the app's theme
    /// (`[display] theme`, `NO_COLOR`).
    Screen(crate::config::KeyMap, crate::config::Theme),
}

impl BleArgs {
    /// Scan, pick and build the link to the droid these arguments select.
    pub async fn connect(&self, chooser: Chooser) -> Result<Connected, CliError> {
        if let Some(port) = &self.serial {
            return connect_serial(port).await;
        }
        if let Some(r) = self.remote.first() {
            let name = r.name.clone().or_else(|| self.name.first().cloned());
            let timeout = Duration::from_secs(self.scan_timeout);
            if name.is_none() && self.address.is_none() && std::io::stdin().is_terminal() {
                return connect_remote_picked(&r.relay, timeout, chooser).await;
            }
            return connect_remote(&r.relay, name, self.address.clone(), timeout).await;
        }
        connect(
            self.name.first().cloned(),
            self.address.clone(),
            Duration::from_secs(self.scan_timeout),
            chooser,
            self.adapter.first().cloned(),
        )
        .await
    }
}

/// The droid to drive, ready for `session::start`.
pub struct Connected {
    pub link: Box<dyn Link>,
    pub model: Model,
    pub name: String,
    pub pacing: Duration,
    pub chunk_size: usize,
    /// The other droids marked in the picker, to drive with it (a fleet).
    pub others: Vec<Connected>,
}

/// Find and connect to a droid. With several supported droids in range and neither `name` nor
/// `address` given, ask which one (when standard input is a terminal).
pub async fn connect(
    name: Option<String>,
    address: Option<String>,
    scan_timeout: Duration,
    chooser: Chooser,
    adapter: Option<String>,
) -> Result<Connected, CliError> {
    if let Some(a) = &address
        && !DeviceId::is_query(a)
    {
        return Err(CliError::usage(format!(
            "--address: `{a}` is not a Bluetooth address like AA:BB:CC:DD:EE:FF (or, on macOS, \
             a device identifier as `droidctl scan` shows)"
        )));
    }
    let explicit = name.is_some() || address.is_some();
    let sel = DeviceSelector {
        name,
        address,
        scan_timeout,
    };
    // Progress for people only: piped stderr gets just the outcome.
    let chatty = std::io::stderr().is_terminal();
    if chatty {
        eprintln!(
            "droidctl: scanning for droids ({} s)…",
            scan_timeout.as_secs()
        );
    }
    // The adapter asked for, else the system's first.
    let central = match &adapter {
        Some(a) => crate::link::ble::open_adapters(std::slice::from_ref(a)).await,
        None => crate::link::ble::open_central()
            .await
            .map(|c| vec![(String::new(), c)]),
    }
    .map_err(|e| CliError::failure(e.message))?
    .remove(0)
    .1;
    let mut found = connect_link_with(central.clone(), &sel, crate::family::gatt_profile)
        .await
        .map_err(|e| CliError::failure(e.message))?;
    let drivable: Vec<&ScanEntry> = found
        .candidates
        .iter()
        .filter(|c| c.model.is_some_and(Model::drivable))
        .collect();
    let chosen: Vec<DeviceId> = if !explicit && drivable.len() > 1 && std::io::stdin().is_terminal()
    {
        match chooser {
            Chooser::Prompt => pick(&drivable)?.into_iter().collect(),
            Chooser::Screen(keys, theme) => {
                let entries: Vec<ScanEntry> = drivable.iter().map(|e| (*e).clone()).collect();
                tokio::task::spawn_blocking(move || pick_on_screen(entries, keys, theme))
                    .await
                    .map_err(|e| CliError::failure(format!("picker failed: {e}")))??
            }
        }
    } else {
        Vec::new()
    };
    // Several marked in the picker: the first is connected as one droid is, the others
    // alongside on the same adapter, every connection attempt taking its turn.
    let others: Vec<ScanEntry> = chosen
        .iter()
        .skip(1)
        .filter_map(|id| drivable.iter().find(|e| e.id == *id).map(|e| (*e).clone()))
        .collect();
    let choice = chosen.first().cloned();
    if let Some(choice) = choice.filter(|c| *c != found.id) {
        let sel = DeviceSelector {
            name: None,
            address: Some(choice.key().to_string()),
            scan_timeout,
        };
        found = connect_link_with(central.clone(), &sel, crate::family::gatt_profile)
            .await
            .map_err(|e| CliError::failure(e.message))?;
    }
    if chatty {
        eprintln!(
            "droidctl: connecting to {} ({}, {})",
            crate::printable::clean(&found.name),
            found.model.display_name(),
            found.id
        );
    }
    let profile = found.link.profile().clone();
    if others.is_empty() {
        return Ok(Connected {
            model: found.model,
            name: found.name.clone(),
            pacing: profile.pacing,
            chunk_size: profile.chunk_size,
            link: Box::new(found.link),
            others: Vec::new(),
        });
    }
    let cap = crate::config::Config::load(&crate::config::config_path())
        .map(|c| c.fleet.max_per_adapter)
        .unwrap_or(crate::fleet::gate::DEFAULT_MAX_PER_ADAPTER);
    let adapters = crate::fleet::gate::Adapters::new(cap);
    let adapter = adapter.unwrap_or_else(|| "the Bluetooth adapter".into());
    let gated = |link: Box<dyn Link>, name: &str| -> Result<Box<dyn Link>, CliError> {
        let gate = adapters
            .admit(&adapter, name)
            .map_err(|over| CliError::failure(over.to_string()))?;
        Ok(Box::new(crate::fleet::gate::GatedLink::new(link, gate)))
    };
    let mut rest = Vec::new();
    for e in others {
        let Some(model) = e.model else { continue };
        let name = e.label();
        let link = crate::link::ble::BleLink::new(
            central.clone(),
            e.id.clone(),
            name.clone(),
            model,
            crate::family::gatt_profile(model),
        );
        let profile = link.profile().clone();
        if chatty {
            eprintln!(
                "droidctl: connecting to {} ({}, {})",
                crate::printable::clean(&name),
                model.display_name(),
                e.id
            );
        }
        rest.push(Connected {
            link: gated(Box::new(link), &name)?,
            model,
            name,
            pacing: profile.pacing,
            chunk_size: profile.chunk_size,
            others: Vec::new(),
        });
    }
    Ok(Connected {
        model: found.model,
        name: found.name.clone(),
        pacing: profile.pacing,
        chunk_size: profile.chunk_size,
        link: gated(Box::new(found.link), &found.name)?,
        others: rest,
    })
}

/// Find the droid behind a relay and build the link to it (`--remote`).
pub async fn connect_remote(
    relay: &crate::link::remote::RelayAddr,
    name: Option<String>,
    address: Option<String>,
    scan_timeout: Duration,
) -> Result<Connected, CliError> {
    use crate::link::remote::{RemoteSelector, select};
    if std::io::stderr().is_terminal() {
        eprintln!("droidctl: asking the relay at {relay} for droids…");
    }
    let sel = RemoteSelector {
        name,
        address,
        scan_timeout,
    };
    let link = select(relay, &sel, crate::family::gatt_profile)
        .await
        .map_err(|e| CliError::failure(e.message))?;
    let profile = link.profile().clone();
    Ok(Connected {
        model: link.model(),
        name: link.name().to_string(),
        pacing: profile.pacing,
        chunk_size: profile.chunk_size,
        link: Box::new(link),
        others: Vec::new(),
    })
}

/// `--remote HOST` with nothing named, at a terminal: the relay's droids are listed; with
/// several, the same picker as for Bluetooth (the full-screen list in the app, the numbered
/// prompt elsewhere) chooses one or, marked, several (a fleet behind the relay).
async fn connect_remote_picked(
    relay: &crate::link::remote::RelayAddr,
    scan_timeout: Duration,
    chooser: Chooser,
) -> Result<Connected, CliError> {
    use crate::link::remote::{RemoteLink, RemoteSelector, pick as pick_remote, scan};
    eprintln!("droidctl: asking the relay at {relay} for droids…");
    let all = scan(relay, scan_timeout)
        .await
        .map_err(|e| CliError::failure(e.message))?;
    let droids: Vec<_> = all
        .iter()
        .filter(|d| d.model.is_some_and(Model::drivable))
        .collect();
    let chosen: Vec<_> = if droids.len() > 1 {
        // The picker's entries: a relay's address is its key (as INIT takes it back).
        let entries: Vec<ScanEntry> = droids
            .iter()
            .map(|d| {
                let address = d.address.parse().ok();
                ScanEntry {
                    name: Some(d.name.clone()),
                    model: d.model,
                    id: DeviceId::new(d.address.clone(), address),
                    address: address.unwrap_or(crate::link::ble::BleAddress([0; 6])),
                    rssi: None,
                    heard: true,
                }
            })
            .collect();
        let ids: Vec<DeviceId> = match chooser {
            Chooser::Prompt => {
                let refs: Vec<&ScanEntry> = entries.iter().collect();
                pick(&refs)?.into_iter().collect()
            }
            Chooser::Screen(keys, theme) => {
                tokio::task::spawn_blocking(move || pick_on_screen(entries, keys, theme))
                    .await
                    .map_err(|e| CliError::failure(format!("picker failed: {e}")))??
            }
        };
        ids.iter()
            .filter_map(|id| droids.iter().find(|d| d.address == id.key()).copied())
            .cloned()
            .collect()
    } else {
        // One or none: the relay's own words (none says how to wake one).
        let sel = RemoteSelector {
            scan_timeout,
            ..RemoteSelector::default()
        };
        vec![pick_remote(&all, &sel).map_err(CliError::failure)?]
    };
    let mut links = chosen.into_iter().filter_map(|d| {
        let model = d.model?;
        let profile = crate::family::gatt_profile(model);
        Some(Connected {
            model,
            name: d.name.clone(),
            pacing: profile.pacing,
            chunk_size: profile.chunk_size,
            link: Box::new(RemoteLink::new(
                relay.clone(),
                d.address.clone(),
                d.name.clone(),
                model,
                profile,
            )),
            others: Vec::new(),
        })
    });
    let Some(mut first) = links.next() else {
        return Err(CliError::failure("no droid chosen".to_string()));
    };
    first.others = links.collect();
    eprintln!(
        "droidctl: connecting to {} ({}) behind {relay}",
        crate::printable::clean(&first.name),
        first.model.display_name()
    );
    Ok(first)
}

/// The RVR on a serial port (`--serial`): the port opened once to say at once what is wrong
/// with it (missing, not ours to open, held by another program), then the link that the
/// session opens and reopens.
pub async fn connect_serial(port: &std::path::Path) -> Result<Connected, CliError> {
    use crate::link::serial::SerialLink;
    // RVR is the droid with a serial port (its UART); nothing else answers on one.
    let link = SerialLink::new(port, Model::ON_SERIAL);
    link.check()
        .await
        .map_err(|e| CliError::failure(e.to_string()))?;
    if std::io::stderr().is_terminal() {
        eprintln!("droidctl: {}", link.describe());
    }
    let model = link.model();
    Ok(Connected {
        name: link.droid_name(),
        model,
        pacing: crate::link::serial::FRAMING.pacing,
        chunk_size: crate::link::serial::FRAMING.chunk_size,
        link: Box::new(link),
        others: Vec::new(),
    })
}

/// A numbered list on stderr, an answer on stdin; Enter takes the strongest.
fn pick(entries: &[&ScanEntry]) -> Result<Option<DeviceId>, CliError> {
    let mut err = std::io::stderr();
    use crate::app::picker::{cells, line, widths};
    let _ = writeln!(err, "Several droids are in range:");
    // Columns as wide as their content (a model name like "Sphero BOLT" included).
    let rows: Vec<[String; 4]> = entries.iter().map(|e| cells(e)).collect();
    let w = widths(&rows);
    let digits = entries.len().max(1).to_string().len();
    for (i, r) in rows.iter().enumerate() {
        let _ = writeln!(err, "  {:>digits$}. {}", i + 1, line(r, &w));
    }
    let _ = write!(err, "Which one? [1-{}, Enter = 1] ", entries.len());
    let _ = err.flush();
    let mut line = String::new();
    if std::io::stdin().lock().read_line(&mut line).is_err() {
        return Ok(None);
    }
    let t = line.trim();
    if t.is_empty() {
        return Ok(entries.first().map(|e| e.id.clone()));
    }
    match t.parse::<usize>() {
        Ok(n) if (1..=entries.len()).contains(&n) => Ok(Some(entries[n - 1].id.clone())),
        _ => Err(CliError::usage(format!(
            "{t:?} is not one of 1..={}",
            entries.len()
        ))),
    }
}

/// The full-screen picker: the `[keys.picker]` bindings (or a digit), in the app's `theme`.
fn pick_on_screen(
    entries: Vec<ScanEntry>,
    keys: crate::config::KeyMap,
    theme: crate::config::Theme,
) -> Result<Vec<DeviceId>, CliError> {
    use crate::app::input::key_from_crossterm;
    use crate::app::picker::{Picked, Picker};
    use crossterm::event::{Event, KeyEventKind, read};
    let fail = |what: &str, e: &dyn std::fmt::Display| CliError::failure(format!("{what}: {e}"));
    let mut guard =
        super::term::TerminalGuard::enter().map_err(|e| fail("cannot use this terminal", &e))?;
    let mut terminal =
        ratatui::Terminal::new(ratatui::backend::CrosstermBackend::new(std::io::stdout()))
            .map_err(|e| fail("cannot use this terminal", &e))?;
    let mut picker = Picker::new(entries, keys);
    let result = loop {
        if let Err(e) = terminal.draw(|f| crate::ui::picker::draw_themed(f, &picker, theme)) {
            break Err(fail("cannot draw", &e));
        }
        let ev = match read() {
            Ok(ev) => ev,
            Err(e) => break Err(fail("cannot read the keyboard", &e)),
        };
        let Event::Key(k) = ev else { continue };
        if k.kind == KeyEventKind::Release {
            continue;
        }
        if let Some((key, _)) = key_from_crossterm(&k) {
            match picker.on_key(key) {
                Picked::Pending => {}
                Picked::Chosen(e) => break Ok(vec![e.id]),
                Picked::Several(v) => break Ok(v.into_iter().map(|e| e.id).collect()),
                Picked::Cancelled => break Err(CliError::failure("no droid chosen")),
            }
        }
    };
    guard.restore();
    result
}
