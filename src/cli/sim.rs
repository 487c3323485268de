//! `droidctl sim --bluez [MODEL ...] [--remembered MODEL ...] [--bus ADDRESS] [--fault FAULT
//! ...] [--idle-sleep SECS] [--seed N] [--trace [--json]]`: simulated droids served on D-Bus
//! as BlueZ serves real ones (Linux only; see [`crate::sim::bluez`]).
//!
//! Prints the line to export (`DBUS_SYSTEM_BUS_ADDRESS=unix:path=…`) on stdout and nothing
//! else there; one status line per event on stderr (`--trace`: one per packet, decoded; with
//! `--json` as JSON lines). Ctrl-C, SIGTERM and SIGHUP stop it: the droids disconnect, then
//! the private `dbus-daemon` is killed and its directory removed.

use super::CliError;
use crate::model::Model;
use crate::sim::gatt::GattFaults;
use clap::Args;

#[derive(Debug, Clone, Args)]
pub struct SimArgs {
    /// Serve the droids on D-Bus as BlueZ does, for any BlueZ client (Linux).
    #[arg(long, required_unless_present = "serial")]
    pub bluez: bool,
    /// Serve one simulated droid of MODEL (rvr: the droid with a serial port) on a new
    /// pseudo-terminal, whose path is printed on stdout: for droidctl's `--serial PATH`,
    /// Sphero's RVR SDK, anything that speaks RVR's UART (Linux and macOS).
    #[arg(long, value_name = "MODEL", conflicts_with_all = ["bluez", "models", "remembered", "bus", "faults", "idle_sleep"], value_parser = super::models::ModelNames::one())]
    pub serial: Option<String>,
    /// With --serial: also make PATH a symbolic link to the pseudo-terminal, a name that
    /// stays the same from run to run (removed when the simulator stops; an existing file
    /// there is refused).
    #[arg(long, value_name = "PATH", requires = "serial")]
    pub link: Option<std::path::PathBuf>,
    /// The droids (one r2d2 without a MODEL); repeat a model for several of it.
    #[arg(value_name = "MODEL", value_parser = super::models::ModelNames::one())]
    pub models: Vec<String>,
    /// Add a device of MODEL that BlueZ remembers but that is not in range: listed without
    /// a signal strength, never advertising; connecting to it fails after a few seconds.
    /// Repeatable.
    #[arg(long, value_name = "MODEL", value_parser = super::models::ModelNames::one())]
    pub remembered: Vec<String>,
    /// A droid that receives no command for SECS sends its will-sleep warning (v2 Power
    /// will-sleep, v1 the pre-sleep async message; Robi 42 has no sleep timer and ignores
    /// this), and 5 s later, with still nothing received, falls asleep: it drops the
    /// connection and stops advertising until the simulator stops.
    #[arg(long, value_name = "SECS", value_parser = parse_idle)]
    pub idle_sleep: Option<std::time::Duration>,
    /// Serve on this D-Bus bus (e.g. unix:path=/tmp/bus) instead of a private dbus-daemon.
    #[arg(long, value_name = "ADDRESS")]
    pub bus: Option<String>,
    /// Inject a fault into every droid: disconnect-after=SECS (drop the first connection
    /// SECS after it was made), disconnect-every=SECS (every connection), refuse-connect
    /// (refuse every connection attempt), refuse-connect=N (the first N), slow-resolve=SECS
    /// (services resolve SECS after a connect). Repeatable.
    #[arg(long = "fault", value_name = "FAULT")]
    pub faults: Vec<String>,
    /// Seed for the droids' names, addresses and signal strengths.
    #[arg(long, default_value_t = 42, value_name = "N")]
    pub seed: u64,
    /// Also report every packet each droid receives and sends on stderr, decoded (writes
    /// and reads that carry no packet, such as the handshake's, in hex).
    #[arg(long)]
    pub trace: bool,
    /// With --trace: one JSON object per line, {"t_ms", "device", "dir": "in"|"out",
    /// "packet"}, where packet is what `droidctl packet decode --json` prints for it (or
    /// {"kind": "gatt-write"|"gatt-read", "uuid", "hex"}).
    #[arg(long, requires = "trace")]
    pub json: bool,
}

fn parse_idle(s: &str) -> Result<std::time::Duration, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number of seconds"))?;
    if !v.is_finite() || !(0.5..=86_400.0).contains(&v) {
        return Err(format!("`{s}`: give 0.5 to 86400 seconds"));
    }
    Ok(std::time::Duration::from_secs_f64(v))
}

/// The checked arguments (served only on Linux; elsewhere they are checked, then refused).
#[cfg_attr(not(target_os = "linux"), allow(dead_code))]
struct Plan {
    models: Vec<Model>,
    remembered: Vec<Model>,
    faults: GattFaults,
}

fn models_of(names: &[String]) -> Result<Vec<Model>, CliError> {
    let mut models = Vec::new();
    for m in names {
        match Model::from_id(m) {
            Some(model) if crate::sim::simulates(model) => models.push(model),
            _ => {
                return Err(CliError::usage(
                    Model::parse_id(m).err().unwrap_or_default(),
                ));
            }
        }
    }
    Ok(models)
}

fn check(args: &SimArgs) -> Result<Plan, CliError> {
    let mut models = models_of(&args.models)?;
    let remembered = models_of(&args.remembered)?;
    if models.is_empty() {
        models.push(Model::DEFAULT);
    }
    const MAX: usize = 16;
    if models.len() + remembered.len() > MAX {
        return Err(CliError::usage(format!("at most {MAX} droids at once")));
    }
    let mut faults = GattFaults::parse_all(&args.faults).map_err(CliError::usage)?;
    if let Some(bus) = &args.bus
        && bus.trim().is_empty()
    {
        return Err(CliError::usage(
            "--bus: give a D-Bus address such as unix:path=/tmp/bus",
        ));
    }
    faults.idle_sleep = args.idle_sleep;
    Ok(Plan {
        models,
        remembered,
        faults,
    })
}

pub fn run(args: SimArgs) -> Result<i32, CliError> {
    if let Some(model) = &args.serial {
        return super::sim_serial::run(model, args.link.as_deref(), args.trace, args.json);
    }
    let plan = check(&args)?;
    serve(args, plan)
}

#[cfg(not(target_os = "linux"))]
fn serve(_args: SimArgs, _plan: Plan) -> Result<i32, CliError> {
    Err(CliError::failure(
        "`droidctl sim --bluez` needs Linux: it serves the droids on D-Bus as BlueZ does; use \
         `--sim` to drive a simulated droid here",
    ))
}

#[cfg(target_os = "linux")]
fn serve(args: SimArgs, plan: Plan) -> Result<i32, CliError> {
    use crate::sim::bluez::{
        BluezOptions, BluezSim, MAX_DROIDS, PrivateBus, Report, plan_with_remembered,
    };
    use std::io::Write;
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};

    debug_assert!(MAX_DROIDS >= plan.models.len() + plan.remembered.len());
    let say = |line: &str| {
        let _ = writeln!(std::io::stderr(), "droidctl sim: {line}");
    };
    let (droids, remembered) = plan_with_remembered(&plan.models, &plan.remembered, args.seed);
    // The bus: the one given, or a private daemon (stopped when `private` drops).
    let private = match &args.bus {
        Some(_) => None,
        None => Some(PrivateBus::start().map_err(CliError::failure)?),
    };
    if let Some(p) = private.as_ref().filter(|p| p.kind() != "dbus-daemon") {
        say(&format!(
            "bus: {} (dbus-daemon is not installed, or not asked for)",
            p.kind()
        ));
    }
    let address = match (&args.bus, &private) {
        (Some(a), _) => a.trim().to_string(),
        (None, Some(p)) => p.address().to_string(),
        (None, None) => return Err(CliError::failure("no bus to serve on")),
    };
    let opts = BluezOptions {
        droids: droids.clone(),
        remembered: remembered.clone(),
        faults: plan.faults.clone(),
        seed: args.seed,
        trace: args.trace,
        json: args.json,
    };
    let stop = Arc::new(AtomicBool::new(false));
    let (ready_tx, ready_rx) = std::sync::mpsc::channel::<Result<(), String>>();
    let (done_tx, done_rx) = tokio::sync::oneshot::channel::<Result<(), String>>();
    let server = {
        let stop = stop.clone();
        let address = address.clone();
        std::thread::Builder::new()
            .name("bluez-sim".into())
            .spawn(move || {
                let report = Box::new(|line: Report| {
                    let _ = match line {
                        Report::Status(line) => {
                            writeln!(std::io::stderr(), "droidctl sim: {line}")
                        }
                        Report::Trace(json) => writeln!(std::io::stderr(), "{json}"),
                    };
                });
                let result = match BluezSim::connect(&address, opts, report) {
                    Ok(sim) => {
                        let _ = ready_tx.send(Ok(()));
                        sim.run(&stop)
                    }
                    Err(e) => {
                        let _ = ready_tx.send(Err(e.clone()));
                        Err(e)
                    }
                };
                let _ = done_tx.send(result);
            })
            .map_err(|e| CliError::failure(format!("cannot start a thread: {e}")))?
    };
    match ready_rx.recv_timeout(std::time::Duration::from_secs(10)) {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(CliError::failure(e)),
        Err(_) => {
            stop.store(true, Ordering::Release);
            return Err(CliError::failure(format!(
                "the bus {address} did not answer within 10 s"
            )));
        }
    }
    for d in &droids {
        say(&format!(
            "{} ({}) at {}",
            d.name,
            d.model.display_name(),
            d.address_string()
        ));
    }
    for d in &remembered {
        say(&format!(
            "{} ({}) at {}: remembered, not in range",
            d.name,
            d.model.display_name(),
            d.address_string()
        ));
    }
    let faults = plan.faults.describe();
    if !faults.is_empty() {
        say(&format!("faults: {}", faults.join(", ")));
    }
    if let Some(idle) = plan.faults.idle_sleep {
        say(&format!(
            "idle sleep: a droid warns after {} s without a command and sleeps 5 s later",
            idle.as_secs_f64()
        ));
    }
    say(&format!(
        "serving on {address}; Ctrl-C stops (export the line on stdout for droidctl, bleak …)"
    ));
    print_for_scripts(
        &format!("DBUS_SYSTEM_BUS_ADDRESS={address}"),
        "the bus address",
    )?;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| CliError::failure(format!("cannot start the runtime: {e}")))?;
    let ended = rt.block_on(async {
        tokio::select! {
            sig = super::signals::terminated() => Ok(Some(sig)),
            r = done_rx => match r {
                Ok(Ok(())) => Ok(None),
                Ok(Err(e)) => Err(e),
                Err(_) => Err("the simulator stopped unexpectedly".to_string()),
            },
        }
    });
    stop.store(true, Ordering::Release);
    let _ = server.join();
    drop(private);
    match ended {
        Ok(Some(sig)) => {
            say(&format!("{sig}: stopped"));
            Ok(0)
        }
        Ok(None) => Ok(0),
        Err(e) => Err(CliError::failure(e)),
    }
}

/// Print the one line a simulator gives scripts on stdout (the bus address, the terminal's
/// path). A full disk or another write error ends the simulator with status 1 before it
/// serves (a script reading `$(droidctl sim …)` would get nothing); a reader that went away
/// does not, since the line is said on stderr too and the simulator is still of use.
#[cfg(unix)]
pub(super) fn print_for_scripts(line: &str, what: &str) -> Result<(), CliError> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match writeln!(out, "{line}").and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(CliError::failure(format!(
            "cannot write {what} to the standard output: {e}; free the space or write it \
             elsewhere"
        ))),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct Cli {
        #[command(flatten)]
        sim: SimArgs,
    }

    fn parse(args: &[&str]) -> Result<Plan, CliError> {
        let mut all = vec!["sim"];
        all.extend_from_slice(args);
        let cli = Cli::try_parse_from(all).map_err(|e| CliError::usage(e.to_string()))?;
        check(&cli.sim)
    }

    #[test]
    fn models_and_faults() {
        let p = parse(&["--bluez"]).unwrap_or_else(|e| panic!("{}", e.message));
        assert_eq!(p.models, [Model::R2D2]);
        let p = parse(&[
            "--bluez",
            "r2d2",
            "bb8",
            "robi",
            "--fault",
            "disconnect-after=1.5",
            "--fault",
            "refuse-connect=2",
        ])
        .unwrap_or_else(|e| panic!("{}", e.message));
        assert_eq!(p.models, [Model::R2D2, Model::BB8, Model::Robi42]);
        assert_eq!(p.faults.refuse_connects, 2);
        for bad in [
            &["--bluez", "tardis"][..],
            &["--bluez", "--fault", "explode"],
            &["r2d2"],
            &["--bluez", "--bus", " "],
        ] {
            let e = parse(bad)
                .err()
                .unwrap_or_else(|| panic!("{bad:?} accepted"));
            assert_eq!(e.status, 2, "{bad:?}: {}", e.message);
        }
        let p = parse(&[
            "--bluez",
            "r2d2",
            "--remembered",
            "bb8",
            "--idle-sleep",
            "2.5",
            "--trace",
            "--json",
        ])
        .unwrap_or_else(|e| panic!("{}", e.message));
        assert_eq!(p.models, [Model::R2D2]);
        assert_eq!(p.remembered, [Model::BB8]);
        assert_eq!(
            p.faults.idle_sleep,
            Some(std::time::Duration::from_millis(2500))
        );
        for bad in [
            &["--bluez", "--json"][..],
            &["--bluez", "--idle-sleep", "0"],
            &["--bluez", "--idle-sleep", "soon"],
            &["--bluez", "--remembered", "tardis"],
        ] {
            assert!(parse(bad).is_err(), "{bad:?} accepted");
        }
        let many: Vec<&str> = std::iter::once("--bluez")
            .chain(std::iter::repeat_n("bb8", 17))
            .collect();
        assert!(parse(&many).is_err());
    }
}
