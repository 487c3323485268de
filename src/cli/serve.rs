//! `droidctl serve [--listen ADDR:PORT] [--sim [MODEL ...]] [--json]`: relay GATT operations
//! from TCP clients (droidctl's `--remote`, spherov2.py's `tcp_adapter`) to droids over
//! Bluetooth LE, or to simulated droids. See [`crate::relay`].

use super::CliError;
use crate::model::Model;
use crate::protocol::relay::DEFAULT_PORT;
use crate::relay::backend::GattBackend;
use crate::relay::ble_backend::BleBackend;
use crate::relay::serial_backend::SerialBackend;
use crate::relay::server::{self, EventSink, ServerConfig, ServerEvent};
use crate::relay::sim_backend::SimBackend;
use crate::sim::gatt::GattFaults;
use clap::Args;
use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Debug, Args)]
pub struct ServeArgs {
    /// Where to listen: ADDR:PORT, or ADDR for port 50004 (spherov2's). Anything but a
    /// loopback address lets other machines drive your droids: the protocol has no
    /// authentication.
    #[arg(long, value_name = "ADDR:PORT", default_value = "127.0.0.1:50004", value_parser = parse_listen)]
    pub listen: SocketAddr,
    /// Relay to simulated droids instead of Bluetooth: one per MODEL given, one R2-D2 without.
    #[arg(long, num_args = 0.., value_name = "MODEL", value_parser = super::models::ModelNames::one())]
    pub sim: Option<Vec<String>>,
    /// Relay to the RVR on this serial port (a Raspberry Pi's UART, /dev/serial0; see
    /// docs/serial.md) instead of Bluetooth.
    #[arg(long, value_name = "PORT", conflicts_with = "sim")]
    pub serial: Option<std::path::PathBuf>,
    /// A fault for the simulated droids, as `droidctl sim --bluez` takes them
    /// (e.g. disconnect-after=5); repeatable.
    #[arg(long = "fault", value_name = "FAULT", requires = "sim")]
    pub faults: Vec<String>,
    /// One JSON object per event on stdout (clients, droids, errors), for scripts.
    #[arg(long)]
    pub json: bool,
    /// Close a client that sends nothing for this long, stopping its droid (0: never; at
    /// most a week).
    #[arg(long, value_name = "SECS", default_value_t = 60, value_parser = clap::value_parser!(u64).range(0..=604_800))]
    pub idle_timeout: u64,
    /// Most clients served at once.
    #[arg(long, value_name = "N", default_value_t = 16, value_parser = clap::value_parser!(u16).range(1..=1024))]
    pub max_clients: u16,
    /// Record every droid session in droidctl's capture format: FILE for the first, then
    /// FILE-2, FILE-3 … (see docs/captures.md). Existing files are kept unless --force.
    #[command(flatten)]
    pub record: super::replay::RecordArgs,
}

fn parse_listen(s: &str) -> Result<SocketAddr, String> {
    listen_addr(s, DEFAULT_PORT)
}

/// A listening address: ADDR:PORT, or ADDR (an IP address or `localhost`) for `port`.
pub fn listen_addr(s: &str, port: u16) -> Result<SocketAddr, String> {
    if let Ok(a) = s.parse::<SocketAddr>() {
        return Ok(a);
    }
    if let Ok(ip) = s.trim_matches(['[', ']']).parse::<IpAddr>() {
        return Ok(SocketAddr::new(ip, port));
    }
    if s == "localhost" {
        return Ok(SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), port));
    }
    Err(format!(
        "`{s}` is not ADDR:PORT or ADDR (e.g. 127.0.0.1:{port}, 0.0.0.0, [::1]:{port})"
    ))
}

/// The simulated models asked for: none given is one R2-D2.
fn sim_models(ids: &[String]) -> Result<Vec<Model>, CliError> {
    if ids.is_empty() {
        return Ok(vec![Model::DEFAULT]);
    }
    ids.iter()
        .map(|m| match Model::from_id(m) {
            Some(model) if crate::sim::simulates(model) => Ok(model),
            _ => Err(CliError::usage(
                Model::parse_id(m).err().unwrap_or_default(),
            )),
        })
        .collect()
}

/// The warning for a listener other machines can reach.
pub fn exposure_warning(addr: &SocketAddr) -> Option<String> {
    (!crate::net::is_loopback_addr(addr)).then(|| {
        format!(
            "droidctl: warning: listening on {addr}: the relay protocol has no authentication or \
             encryption — anyone who can reach this port can drive your droids. Listen on a \
             trusted network only."
        )
    })
}

pub fn run(args: ServeArgs) -> Result<i32, CliError> {
    let models = args.sim.as_deref().map(sim_models).transpose()?;
    let faults = GattFaults::parse_all(&args.faults).map_err(CliError::usage)?;
    let _ = crate::logging::init();
    let cfg = ServerConfig {
        max_clients: args.max_clients as usize,
        idle_timeout: (args.idle_timeout > 0).then(|| Duration::from_secs(args.idle_timeout)),
        ..ServerConfig::default()
    };
    let json = args.json;
    let listen = args.listen;
    let rt = super::realtime_runtime()?;
    rt.block_on(async move {
        let backend: Arc<dyn GattBackend> = match (models, &args.serial) {
            (Some(models), _) => Arc::new(SimBackend::new(&models, faults)),
            (None, Some(port)) => {
                // What is wrong with the port, said now rather than to the first client.
                crate::link::serial::SerialLink::new(port, Model::ON_SERIAL)
                    .check()
                    .await
                    .map_err(|e| CliError::failure(e.to_string()))?;
                Arc::new(SerialBackend::new(port, Model::ON_SERIAL))
            }
            (None, None) => {
                let central = crate::link::ble::open_central()
                    .await
                    .map_err(|e| CliError::failure(e.message))?;
                Arc::new(BleBackend::new(central))
            }
        };
        let backend: Arc<dyn GattBackend> = match &args.record.record {
            Some(path) => Arc::new(
                crate::relay::record::RecordingBackend::new(backend, path, args.record.force)
                    .map_err(CliError::usage)?,
            ),
            None => backend,
        };
        let listener = server::bind(listen, &cfg)
            .await
            .map_err(|e| CliError::failure(format!("cannot listen on {listen}: {e}")))?;
        if let Some(w) = exposure_warning(&listen) {
            eprintln!("{w}");
        }
        let start = Instant::now();
        let sink: EventSink = Arc::new(move |e: &ServerEvent| print_event(e, json, start));
        let stopped = async {
            let sig = super::signals::terminated().await;
            eprintln!("droidctl: {sig}: stopping every droid and closing");
        };
        server::serve(listener, backend, cfg, sink, stopped).await;
        Ok(0)
    })
}

/// A status line on stderr; with `json`, the event as one JSON object on stdout too.
fn print_event(e: &ServerEvent, json: bool, start: Instant) {
    eprintln!("{}", e.status_line());
    if json {
        let mut v = serde_json::to_value(e).unwrap_or_default();
        if let Some(o) = v.as_object_mut() {
            o.insert(
                "time_ms".into(),
                serde_json::Value::from(start.elapsed().as_millis() as u64),
            );
        }
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "{v}");
        let _ = out.flush();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn listen_addresses() {
        assert_eq!(
            parse_listen("0.0.0.0").unwrap(),
            "0.0.0.0:50004".parse().unwrap()
        );
        assert_eq!(
            parse_listen("[::1]:6000").unwrap(),
            "[::1]:6000".parse().unwrap()
        );
        assert_eq!(parse_listen("::1").unwrap().port(), 50004);
        assert!(parse_listen("pi.local:1").is_err());
        assert!(exposure_warning(&"0.0.0.0:50004".parse().unwrap()).is_some());
        assert!(exposure_warning(&"127.0.0.1:50004".parse().unwrap()).is_none());
        assert!(exposure_warning(&"[::1]:50004".parse().unwrap()).is_none());
        // IPv4 loopback written as IPv6 is loopback (issue 37 point 15); other mapped
        // addresses are not.
        let mapped = parse_listen("[::ffff:127.0.0.1]:50004").unwrap();
        assert!(exposure_warning(&mapped).is_none());
        assert!(exposure_warning(&parse_listen("::ffff:127.5.5.5").unwrap()).is_none());
        assert!(exposure_warning(&parse_listen("::ffff:10.0.0.1").unwrap()).is_some());
        assert!(exposure_warning(&parse_listen("::").unwrap()).is_some());
    }

    #[test]
    fn an_idle_timeout_the_clock_cannot_hold_is_refused() {
        use clap::Parser;
        #[derive(Parser)]
        struct T {
            #[command(flatten)]
            serve: ServeArgs,
        }
        assert!(T::try_parse_from(["t", "--idle-timeout", "604800"]).is_ok());
        for v in ["604801", "18446744073709551615"] {
            let e = T::try_parse_from(["t", "--idle-timeout", v]).err().unwrap();
            assert_eq!(e.exit_code(), 2, "{v}: {e}");
        }
    }

    #[test]
    fn sim_models_default_to_one_r2d2() {
        assert_eq!(sim_models(&[]).unwrap(), [Model::R2D2]);
        let m = sim_models(&["bb8".into(), "r2q5".into()]).unwrap();
        assert_eq!(m, [Model::BB8, Model::R2Q5]);
        assert!(sim_models(&["c3po".into()]).is_err());
    }
}
