//! `droidctl bridge --stdio | --mqtt [URL] [--sim …|--name …|--remote …]`: other programs
//! drive droids through one JSON interface (see [`crate::bridge`]), over standard
//! input/output or through an MQTT broker: the one at URL, or without a URL droidctl's own
//! ([`crate::bridge::broker`]) on `--listen` (127.0.0.1:1883).
//!
//! As `serve` keeps its relay on loopback unless told otherwise, the bridge takes commands
//! only through a broker on this machine unless `--allow-remote` says so: anyone who can
//! publish to the broker can drive the droids.

use super::CliError;
use crate::bridge::mqtt::{BrokerUrl, MqttSettings};
use crate::bridge::{self, Bridge, Settings};
use crate::fleet::Fleet;
use clap::Args;
use std::path::PathBuf;
use std::time::Duration;

#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("transport").required(true).args(["stdio", "mqtt"])))]
pub struct BridgeArgs {
    /// One JSON command per line on stdin; telemetry, replies and errors as JSON lines on
    /// stdout. The droids stop when stdin ends.
    #[arg(long)]
    pub stdio: bool,
    /// Through an MQTT broker: mqtt://HOST[:PORT] (1883), mqtts://HOST[:PORT] (TLS, 8883);
    /// without a URL, droidctl's own broker on --listen (127.0.0.1:1883). Topics
    /// droidctl/DROID/cmd, …/telemetry, …/collision, …/battery, …/state, …/reply.
    #[arg(long, value_name = "URL", num_args = 0..=1)]
    pub mqtt: Option<Option<BrokerUrl>>,
    /// `--mqtt` without a URL: where droidctl's own broker listens, ADDR:PORT or ADDR (port
    /// 1883). Anything but a loopback address lets other machines publish commands: anyone
    /// who reaches the port can drive your droids (the broker has no encryption; give it a
    /// password with --username and --password-file).
    #[arg(long, value_name = "ADDR:PORT", value_parser = parse_broker_listen)]
    pub listen: Option<std::net::SocketAddr>,
    /// Bridge simulated droids (r2d2 without a MODEL); several share one room:
    /// --sim r2d2,bb8,robi.
    #[arg(long, num_args = 0..=1, default_missing_value = "r2d2", value_name = "MODEL[,MODEL…]",
          value_parser = super::models::ModelNames::list(),
          add = clap_complete::ArgValueCompleter::new(super::complete::model_list))]
    pub sim: Option<String>,
    #[command(flatten)]
    pub ble: super::connect::BleArgs,
    /// Stop a droid when no drive or twist came for this long (ms; config bridge.command_timeout_ms, 600).
    #[arg(long, value_name = "MS", value_parser = clap::value_parser!(u64).range(100..=10_000))]
    pub command_timeout: Option<u64>,
    /// Telemetry samples per second per droid (config bridge.telemetry_hz, 10).
    #[arg(long, value_name = "HZ", value_parser = clap::value_parser!(u16).range(1..=100))]
    pub rate: Option<u16>,
    /// MQTT QoS of commands, telemetry and replies: 0, 1 or 2 (config bridge.qos, 0).
    #[arg(long, value_name = "QOS", value_parser = clap::value_parser!(u8).range(0..=2))]
    pub qos: Option<u8>,
    /// MQTT: the first topic level (config bridge.topic_prefix, droidctl).
    #[arg(long, value_name = "PREFIX")]
    pub topic_prefix: Option<String>,
    /// MQTT: the client id's start (each droid's connection adds its number and name).
    #[arg(long, value_name = "ID")]
    pub client_id: Option<String>,
    /// MQTT: user name (or in the URL: mqtt://USER@HOST).
    #[arg(long, value_name = "USER")]
    pub username: Option<String>,
    /// MQTT: a file holding the password (its first line); or set DROIDCTL_MQTT_PASSWORD.
    #[arg(long, value_name = "FILE")]
    pub password_file: Option<PathBuf>,
    /// MQTT over TLS: the CA certificate (PEM) the broker's certificate must chain to
    /// (without it, the system's).
    #[arg(long, value_name = "PEM")]
    pub ca_file: Option<PathBuf>,
    /// Take commands through a broker on another machine: anyone who can publish to it can
    /// drive your droids (use TLS and a password).
    #[arg(long)]
    pub allow_remote: bool,
    /// MQTT: publish Home Assistant discovery (retained under PREFIX, homeassistant by
    /// default) so the bridge and each droid appear in Home Assistant (battery, connection,
    /// collisions, stop, motion enabled, light …); kept when the bridge ends (shown
    /// unavailable) unless --homeassistant-remove.
    #[arg(long, value_name = "PREFIX", num_args = 0..=1, default_missing_value = "homeassistant")]
    pub homeassistant: Option<String>,
    /// MQTT: remove the Home Assistant devices and entities when the bridge ends cleanly.
    #[arg(long, requires = "homeassistant")]
    pub homeassistant_remove: bool,
    /// MQTT: this bridge's id among the bridges on the broker (its hello on
    /// PREFIX/bridge/ID); the host name by default.
    #[arg(long, value_name = "ID")]
    pub bridge_id: Option<String>,
}

fn parse_broker_listen(s: &str) -> Result<std::net::SocketAddr, String> {
    super::serve::listen_addr(s, bridge::mqtt::PORT)
}

/// Where the embedded broker listens unless `--listen` says otherwise.
pub const EMBEDDED_LISTEN: std::net::SocketAddr = std::net::SocketAddr::new(
    std::net::IpAddr::V4(std::net::Ipv4Addr::LOCALHOST),
    bridge::mqtt::PORT,
);

/// The warning for an embedded broker other machines can reach (as `serve`'s).
pub fn listen_warning(addr: &std::net::SocketAddr, password: bool) -> Option<String> {
    (!crate::net::is_loopback_addr(addr)).then(|| {
        format!(
            "droidctl: warning: MQTT broker listening on {addr}: it has no encryption{} — \
             anyone who can reach this port can publish to droidctl/…/cmd and drive your \
             droids. Listen on a trusted network only.",
            if password {
                ""
            } else {
                " and no password (--username, --password-file)"
            }
        )
    })
}

/// The URL the bridge reaches its own broker at: loopback, whatever address it listens on.
/// An IPv4 address written as IPv6 (`[::ffff:127.0.0.1]`) takes IPv4 connections only:
/// reached at 127.0.0.1, not ::1.
fn embedded_url(listen: std::net::SocketAddr) -> BrokerUrl {
    let host = if listen.ip().to_canonical().is_ipv6() {
        "::1"
    } else {
        "127.0.0.1"
    };
    BrokerUrl {
        host: host.into(),
        port: listen.port(),
        tls: false,
        username: None,
        password: None,
    }
}

/// Why a broker beyond loopback is refused, or the warning when it is allowed.
pub fn exposure(url: &BrokerUrl, loopback: bool, allowed: bool) -> Result<Option<String>, String> {
    if loopback {
        return Ok(None);
    }
    if !allowed {
        return Err(format!(
            "{url} is not on this machine: anyone who can publish to that broker could drive \
             your droids. Say --allow-remote if that is what you want (with TLS, mqtts://, and \
             a password), or run a broker here (mqtt://localhost)."
        ));
    }
    let mut missing = Vec::new();
    if !url.tls {
        missing.push("encryption (mqtts://)");
    }
    if url.username.is_none() {
        missing.push("a user name and password");
    }
    Ok(Some(if missing.is_empty() {
        format!(
            "droidctl: warning: taking commands through {url}: whoever the broker lets publish \
             to droidctl/…/cmd can drive your droids."
        )
    } else {
        format!(
            "droidctl: warning: taking commands through {url} without {}: anyone who reaches \
             the broker can drive your droids. Use a trusted network only.",
            missing.join(" or ")
        )
    }))
}

fn settings(args: &BridgeArgs, config: &crate::config::Config) -> Settings {
    let b = &config.bridge;
    Settings {
        command_timeout: Duration::from_millis(
            args.command_timeout.unwrap_or(b.command_timeout_ms),
        ),
        telemetry_hz: args.rate.unwrap_or(b.telemetry_hz),
        battery_poll: Duration::from_secs(b.battery_poll_s),
        homeassistant: args.homeassistant.clone(),
        homeassistant_remove: args.homeassistant_remove,
        taken_topics: Default::default(),
    }
}

fn mqtt_settings(
    args: &BridgeArgs,
    url: &BrokerUrl,
    config: &crate::config::Config,
) -> Result<MqttSettings, CliError> {
    let b = &config.bridge;
    let prefix = args
        .topic_prefix
        .clone()
        .unwrap_or_else(|| b.topic_prefix.clone());
    crate::config::bridge::check_prefix(&prefix).map_err(CliError::usage)?;
    if let Some(ha) = &args.homeassistant {
        crate::config::bridge::check_prefix(ha)
            .map_err(|e| CliError::usage(format!("--homeassistant: {e}")))?;
    }
    let password = match &args.password_file {
        Some(p) => Some(password_file(p).map_err(CliError::usage)?),
        None => std::env::var("DROIDCTL_MQTT_PASSWORD").ok(),
    };
    let ca_pem = match &args.ca_file {
        Some(p) if url.tls => Some(
            std::fs::read(p)
                .map_err(|e| CliError::usage(format!("cannot read {}: {e}", p.display())))?,
        ),
        Some(_) => {
            return Err(CliError::usage("--ca-file is for TLS: use an mqtts:// URL"));
        }
        None => None,
    };
    let client_id = args
        .client_id
        .clone()
        .unwrap_or_else(bridge::mqtt::default_client_id);
    let bridge_id = match &args.bridge_id {
        Some(id) if bridge::topic_name(id) != *id => {
            return Err(CliError::usage(format!(
                "--bridge-id {id:?}: letters, digits, - and _ only (it is a topic level)"
            )));
        }
        Some(id) => id.clone(),
        None => bridge::presence::default_id(),
    };
    Ok(MqttSettings {
        url: url.clone(),
        qos: args.qos.unwrap_or(b.qos),
        prefix,
        client_id,
        bridge_id,
        keepalive: Duration::from_secs(b.keepalive_s),
        username: args.username.clone(),
        password,
        ca_pem,
    })
}

/// Take this bridge's place among those live on the broker (issue 40 points 1 and 2): a
/// bridge id and droid topics nobody running has. A default id taken becomes `ID-2` …, an id
/// asked for with --bridge-id is refused; a droid whose topic is taken gets `NAME-2` …;
/// each said.
async fn share_broker(
    m: &mut MqttSettings,
    settings: &mut Settings,
    fleet: &Fleet,
    asked: bool,
) -> Result<(), CliError> {
    let live = bridge::presence::probe(m, Duration::from_secs(10))
        .await
        .map_err(CliError::failure)?;
    if live.bridges.contains(&m.bridge_id) {
        if asked {
            return Err(CliError::usage(format!(
                "another bridge with id {} is online on {} ({}/bridge/{}/state): give this \
                 one another --bridge-id",
                m.bridge_id, m.url, m.prefix, m.bridge_id
            )));
        }
        let taken = live.bridges.iter().map(|b| b.to_lowercase()).collect();
        let id = bridge::presence::distinct(&m.bridge_id, &taken);
        eprintln!(
            "droidctl: bridge: another bridge with id {} is online on the broker: this one is {id} \
             (say --bridge-id to choose)",
            m.bridge_id
        );
        m.bridge_id = id;
    }
    let names = fleet.names();
    let ours = bridge::topic_names_besides(&names, &live.droids);
    for (name, (plain, t)) in names
        .iter()
        .zip(bridge::topic_names(&names).iter().zip(&ours))
    {
        if plain != t {
            eprintln!(
                "droidctl: bridge: {name} is live on the broker already ({}/{plain}/state, \
                 another bridge's): this one's topics are {}/{t}/…",
                m.prefix, m.prefix
            );
        }
    }
    settings.taken_topics = live.droids;
    Ok(())
}

/// The longest password file read (its first line is the password): `/dev/zero` or a large
/// file given by mistake is refused, not read without end (issue 27 point 8).
pub const MAX_PASSWORD_FILE_BYTES: u64 = 64 * 1024;

/// The password in `path`: its first line, read from at most [`MAX_PASSWORD_FILE_BYTES`].
fn password_file(path: &std::path::Path) -> Result<String, String> {
    use std::io::Read;
    let cannot = |e: std::io::Error| format!("cannot read {}: {e}", path.display());
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .map_err(cannot)?
        .take(MAX_PASSWORD_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    let first = match memchr::memchr(b'\n', &bytes) {
        Some(at) => &bytes[..at],
        None if bytes.len() as u64 > MAX_PASSWORD_FILE_BYTES => {
            return Err(format!(
                "{} is not a password file: no line end in its first {} KiB (the password is \
                 the file's first line)",
                path.display(),
                MAX_PASSWORD_FILE_BYTES / 1024
            ));
        }
        None => &bytes[..],
    };
    let first = first.strip_suffix(b"\r").unwrap_or(first);
    String::from_utf8(first.to_vec())
        .map_err(|_| format!("{}: the password is not UTF-8 text", path.display()))
}

/// The MQTT options given without `--mqtt`.
fn mqtt_only(args: &BridgeArgs) -> Vec<&'static str> {
    [
        ("--qos", args.qos.is_some()),
        ("--topic-prefix", args.topic_prefix.is_some()),
        ("--client-id", args.client_id.is_some()),
        ("--username", args.username.is_some()),
        ("--password-file", args.password_file.is_some()),
        ("--ca-file", args.ca_file.is_some()),
        ("--allow-remote", args.allow_remote),
        ("--listen", args.listen.is_some()),
        ("--homeassistant", args.homeassistant.is_some()),
        ("--bridge-id", args.bridge_id.is_some()),
    ]
    .into_iter()
    .filter_map(|(name, given)| given.then_some(name))
    .collect()
}

pub fn run(args: BridgeArgs) -> Result<i32, CliError> {
    let stray = mqtt_only(&args);
    if args.mqtt.is_none() && !stray.is_empty() {
        return Err(CliError::usage(format!(
            "{} {} for MQTT: add --mqtt mqtt://HOST (or --mqtt alone: droidctl's own broker)",
            stray.join(", "),
            if stray.len() == 1 { "is" } else { "are" }
        )));
    }
    let config = crate::config::Config::load(&crate::config::config_path())
        .map_err(|e| CliError::usage(e.to_string()))?;
    let sims = match &args.sim {
        Some(list) => super::fleet::sim_models(list)?,
        None => Vec::new(),
    };
    if sims.is_empty()
        && args.ble.name.is_empty()
        && args.ble.remote.is_empty()
        && args.ble.address.is_none()
        && args.ble.serial.is_none()
    {
        return Err(CliError::usage(
            "say which droids to bridge: --sim MODEL[,MODEL…], --name NAME (repeatable), \
             --remote [NAME@]HOST (repeatable), --address ADDR or --serial PORT",
        ));
    }
    let settings = settings(&args, &config);
    // `--mqtt` alone: droidctl's own broker, reached over loopback.
    let embedded = match &args.mqtt {
        Some(None) => Some(args.listen.unwrap_or(EMBEDDED_LISTEN)),
        Some(Some(_)) if args.listen.is_some() => {
            return Err(CliError::usage(
                "--listen is for droidctl's own broker: give --mqtt without a URL",
            ));
        }
        _ => None,
    };
    if embedded.is_some() && (args.ca_file.is_some() || args.allow_remote) {
        return Err(CliError::usage(
            "--ca-file and --allow-remote are for a broker elsewhere (--mqtt URL)",
        ));
    }
    let mqtt = match &args.mqtt {
        Some(Some(url)) => Some(mqtt_settings(&args, url, &config)?),
        Some(None) => Some(mqtt_settings(
            &args,
            &embedded_url(embedded.unwrap_or(EMBEDDED_LISTEN)),
            &config,
        )?),
        None => None,
    };
    let _ = crate::logging::init();
    let rts = Runtimes::start(embedded.is_some(), mqtt.is_some())?;
    // The bridge's own client ids on its own broker: nobody else may take them (issue 37
    // point 7); its connections log in with the secret that says so.
    let own = match (&embedded, &mqtt) {
        (Some(_), Some(m)) => Some(bridge::broker::OwnIds::new(&format!("{}-", m.client_id))),
        _ => None,
    };
    let login = mqtt.as_ref().and_then(|m| {
        m.username
            .clone()
            .map(|u| (u, m.password.clone().unwrap_or_default()))
    });
    let mqtt = match (mqtt, &own) {
        (Some(mut m), Some(o)) => {
            m.username = Some(o.user.clone());
            m.password = Some(o.password.clone());
            Some(m)
        }
        (m, _) => m,
    };
    let rt = &rts.main;
    let result = rt.block_on(async {
        // Kept until the bridge is done: the droids' last states go through it.
        let _broker = match (embedded, &rts.broker) {
            (Some(listen), Some(on)) => Some(start_broker(on, listen, login, own)?),
            _ => None,
        };
        if let Some(m) = &mqtt {
            let loopback = bridge::mqtt::is_loopback(&m.url.host, m.url.port)
                .await
                .map_err(CliError::failure)?;
            if let Some(w) =
                exposure(&m.url, loopback, args.allow_remote).map_err(CliError::usage)?
            {
                eprintln!("{w}");
            }
        }
        let fleet = start_fleet(&sims, &args.ble, &config).await?;
        let setups = fleet
            .members()
            .iter()
            .map(|m| crate::family::setup::from_config(m.model, &config).0)
            .collect();
        for m in fleet.members() {
            eprintln!(
                "droidctl: bridge: {} ({}, {})",
                m.name,
                m.model.display_name(),
                m.origin
            );
        }
        let mut settings = settings;
        let mut mqtt = mqtt;
        if let Some(m) = &mut mqtt {
            share_broker(m, &mut settings, &fleet, args.bridge_id.is_some()).await?;
        }
        let (bridge, rx) = Bridge::start(fleet, setups, settings);
        let stopped = async {
            let sig = super::signals::terminated().await;
            eprintln!("droidctl: {sig}: stopping every droid");
        };
        match mqtt {
            None => {
                // A droid's first commands wait for it to be ready, at most as long as
                // finding it may take.
                let end = bridge::stdio::run_waiting(
                    bridge.clone(),
                    rx,
                    tokio::io::BufReader::new(tokio::io::stdin()),
                    tokio::io::stdout(),
                    stopped,
                    Duration::from_secs(args.ble.scan_timeout),
                )
                .await;
                if let bridge::stdio::End::OutputClosed(why) = &end {
                    eprintln!("droidctl: bridge: stdout closed ({why}): every droid stopped");
                }
                // A reader that went away is the usual end (status 0); an output that cannot
                // be written (a full disk) is a failure (status 1).
                if let bridge::stdio::End::OutputFailed(why) = &end {
                    return Err(CliError::failure(format!(
                        "bridge: cannot write the output ({why}): every droid was stopped"
                    )));
                }
                let dropped = bridge.dropped();
                if dropped > 0 {
                    eprintln!(
                        "droidctl: bridge: {dropped} telemetry objects were dropped: the reader \
                         did not keep up (replies and errors never are); lower --rate"
                    );
                }
                Ok(0)
            }
            Some(m) => {
                eprintln!(
                    "droidctl: bridge: through {} as {}/DROID/cmd (command timeout {} ms)",
                    m.url,
                    m.prefix,
                    bridge.settings().command_timeout.as_millis()
                );
                // On the network's own thread: however busy the broker's traffic keeps it,
                // the droids' sessions and command timeouts run here undisturbed.
                let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
                let net = rts
                    .net
                    .as_ref()
                    .map_or_else(tokio::runtime::Handle::current, |n| n.handle().clone());
                let mut job = net.spawn(bridge::mqtt::run(
                    bridge.clone(),
                    rx,
                    m,
                    Duration::from_secs(10),
                    async move {
                        let _ = stop_rx.await;
                    },
                ));
                let r = tokio::select! {
                    r = &mut job => r,
                    _ = stopped => {
                        let _ = stop_tx.send(());
                        job.await
                    }
                };
                let r = r.unwrap_or_else(|e| Err(format!("the MQTT connections ended: {e}")));
                bridge.shutdown().await;
                r.map(|()| 0).map_err(CliError::failure)
            }
        }
    });
    // Stdin's reader thread may still wait for a line: do not wait for it.
    let Runtimes { main, broker, net } = rts;
    main.shutdown_timeout(Duration::from_millis(200));
    drop((net, broker));
    result
}

/// Where the bridge runs (issue 37 point 1): the droids' sessions, their command timeouts,
/// heartbeats and pacing on the main runtime; droidctl's own broker and the bridge's MQTT
/// connections each on a runtime of its own thread, so nothing read from the network can
/// starve the stop.
pub struct Runtimes {
    pub main: tokio::runtime::Runtime,
    pub broker: Option<bridge::thread::RuntimeThread>,
    pub net: Option<bridge::thread::RuntimeThread>,
}

impl Runtimes {
    /// The main runtime, and the broker's and the MQTT connections' when asked for.
    pub fn start(broker: bool, net: bool) -> Result<Runtimes, CliError> {
        let thread = |name: &str| {
            bridge::thread::RuntimeThread::start(name)
                .map_err(|e| CliError::failure(format!("cannot start the {name} thread: {e}")))
        };
        Ok(Runtimes {
            main: super::realtime_runtime()?,
            broker: broker.then(|| thread("droidctl-broker")).transpose()?,
            net: net.then(|| thread("droidctl-mqtt")).transpose()?,
        })
    }
}

/// droidctl's own broker on `listen`, on the runtime thread `on`, taking `login` when one is
/// given and keeping the bridge's `own` client ids.
fn start_broker(
    on: &bridge::thread::RuntimeThread,
    listen: std::net::SocketAddr,
    login: Option<(String, String)>,
    own: Option<bridge::broker::OwnIds>,
) -> Result<bridge::broker::Broker, CliError> {
    let password = login.is_some();
    let access = bridge::broker::Access { login, own };
    let broker = bridge::broker::start_on(on.handle(), listen, access, None).map_err(|e| {
        CliError::failure(if e.kind() == std::io::ErrorKind::AddrInUse {
            format!(
                "cannot listen on {listen}: {e}. Is a broker already running there? Use it \
                 with --mqtt mqtt://{listen}, or put droidctl's on another port with \
                 --listen ADDR:PORT"
            )
        } else {
            format!("cannot listen on {listen}: {e}")
        })
    })?;
    eprintln!(
        "droidctl: bridge: MQTT broker (droidctl's own) on {}",
        broker.addr()
    );
    if let Some(w) = listen_warning(&broker.addr(), password) {
        eprintln!("{w}");
    }
    Ok(broker)
}

/// The fleet the arguments name (one droid behind a relay by name, or by address, as the
/// one-droid commands find it).
async fn start_fleet(
    sims: &[crate::model::Model],
    ble: &super::connect::BleArgs,
    config: &crate::config::Config,
) -> Result<Fleet, CliError> {
    let found = if sims.is_empty()
        && !super::fleet::is_fleet(0, ble)
        && (ble.address.is_some() || !ble.remote.is_empty() || ble.serial.is_some())
    {
        let c = ble.connect(super::connect::Chooser::Prompt).await?;
        let origin = match (ble.remote.first(), &ble.serial) {
            (Some(r), _) => format!("relay {}", r.relay),
            (None, Some(port)) => format!("serial {}", port.display()),
            (None, None) => "Bluetooth".into(),
        };
        vec![super::fleet::Found {
            link: c.link,
            model: c.model,
            name: c.name,
            origin,
            room_origin: None,
        }]
    } else {
        super::fleet::find_all(sims, ble, config).await?
    };
    let specs = found
        .into_iter()
        .map(|f| {
            let s = super::fleet::session_config(f.model, config, true);
            f.into_spec(s)
        })
        .collect();
    Ok(Fleet::start(specs))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 37 point 1: droidctl's broker and the bridge's MQTT connections run where they
    /// cannot hold up the droids' runtime. Each is kept busy here by as many blocking tasks
    /// as the main runtime has workers (as a lock held across work that grew with input did:
    /// both workers blocked, the command timeout never fired); a timer on the main runtime
    /// fires on time all the same. The one place a test needs real threads blocked.
    #[test]
    fn a_blocked_broker_or_mqtt_thread_does_not_delay_the_droids_runtime() {
        let rts = Runtimes::start(true, true).unwrap();
        let broker = start_broker(
            rts.broker.as_ref().unwrap(),
            "127.0.0.1:0".parse().unwrap(),
            None,
            None,
        )
        .unwrap();
        let net = rts.net.as_ref().unwrap().handle().clone();
        let (started, blocked) = std::sync::mpsc::channel();
        for h in [broker.handle().clone(), net] {
            for _ in 0..2 {
                let started = started.clone();
                h.spawn(async move {
                    let _ = started.send(());
                    std::thread::sleep(Duration::from_millis(500));
                });
            }
        }
        blocked.recv().unwrap();
        blocked.recv().unwrap();
        let late = rts
            .main
            .block_on(rts.main.spawn(async {
                let t0 = tokio::time::Instant::now();
                tokio::time::sleep(Duration::from_millis(50)).await;
                t0.elapsed()
            }))
            .unwrap();
        assert!(late < Duration::from_millis(350), "{late:?}");
        drop(broker);
    }

    #[test]
    fn a_broker_beyond_loopback_needs_allow_remote() {
        let url: BrokerUrl = "mqtt://broker.lan".parse().unwrap();
        assert!(exposure(&url, true, false).unwrap().is_none());
        let e = exposure(&url, false, false).unwrap_err();
        assert!(e.contains("--allow-remote"), "{e}");
        let w = exposure(&url, false, true).unwrap().unwrap();
        assert!(w.contains("encryption") && w.contains("password"), "{w}");
        let safe: BrokerUrl = "mqtts://u@broker.lan".parse().unwrap();
        let w = exposure(&safe, false, true).unwrap().unwrap();
        assert!(!w.contains("without"), "{w}");
    }

    #[test]
    fn the_embedded_broker_listens_on_loopback_unless_told() {
        assert_eq!(EMBEDDED_LISTEN.to_string(), "127.0.0.1:1883");
        assert_eq!(parse_broker_listen("0.0.0.0").unwrap().port(), 1883);
        assert_eq!(
            embedded_url("0.0.0.0:1999".parse().unwrap()).to_string(),
            "mqtt://127.0.0.1:1999"
        );
        assert_eq!(
            embedded_url("[::]:1999".parse().unwrap()).to_string(),
            "mqtt://[::1]:1999"
        );
        assert_eq!(
            embedded_url("[::ffff:127.0.0.1]:1999".parse().unwrap()).to_string(),
            "mqtt://127.0.0.1:1999"
        );
        let w = listen_warning(&"0.0.0.0:1883".parse().unwrap(), false).unwrap();
        assert!(w.contains("no password") && w.contains("drive"), "{w}");
        assert!(listen_warning(&EMBEDDED_LISTEN, false).is_none());
    }

    #[test]
    fn broker_urls() {
        let u: BrokerUrl = "mqtt://127.0.0.1:1999".parse().unwrap();
        assert_eq!((u.host.as_str(), u.port, u.tls), ("127.0.0.1", 1999, false));
        let u: BrokerUrl = "mqtts://ann:secret@[::1]".parse().unwrap();
        assert_eq!((u.host.as_str(), u.port, u.tls), ("::1", 8883, true));
        assert_eq!(
            (u.username.as_deref(), u.password.as_deref()),
            (Some("ann"), Some("secret"))
        );
        assert_eq!(u.to_string(), "mqtts://[::1]:8883", "no password shown");
        let u: BrokerUrl = "localhost".parse().unwrap();
        assert_eq!((u.host.as_str(), u.port), ("localhost", 1883));
        for bad in [
            "http://x",
            "mqtt://",
            "mqtt://h:port",
            "mqtt://h:0",
            "mqtt://[::1",
        ] {
            assert!(bad.parse::<BrokerUrl>().is_err(), "{bad}");
        }
    }

    #[tokio::test]
    async fn loopback_names() {
        use crate::bridge::mqtt::is_loopback;
        assert!(is_loopback("127.0.0.1", 1883).await.unwrap());
        assert!(is_loopback("::1", 1883).await.unwrap());
        assert!(is_loopback("localhost", 1883).await.unwrap());
        assert!(!is_loopback("192.168.1.10", 1883).await.unwrap());
        assert!(!is_loopback("0.0.0.0", 1883).await.unwrap());
        // IPv4 loopback written as IPv6 (issue 37 point 15), as a broker host and as the
        // embedded broker's --listen.
        assert!(is_loopback("::ffff:127.0.0.1", 1883).await.unwrap());
        assert!(!is_loopback("::ffff:10.0.0.1", 1883).await.unwrap());
        assert!(!is_loopback("::", 1883).await.unwrap());
        let listen = parse_broker_listen("[::ffff:127.0.0.1]:1883").unwrap();
        assert_eq!(listen_warning(&listen, false), None);
        let listen = parse_broker_listen("[::ffff:10.0.0.1]:1883").unwrap();
        assert!(listen_warning(&listen, true).is_some());
    }
}
