//! The bridge over MQTT, through a broker (mosquitto, or any MQTT 3.1.1 broker), with the
//! `rumqttc` client. Each droid has its own topics and its own connection to the broker,
//! so each has its own last will:
//!
//! | topic | direction | what |
//! |---|---|---|
//! | `PREFIX/DROID/cmd` | in | commands ([`super::schema`]); the topic names the droid |
//! | `PREFIX/DROID/cmd_vel` | in | a ROS `geometry_msgs/Twist`, MessagePack or JSON ([`super::ros`]) |
//! | `PREFIX/DROID/odom` | out | each sample as a ROS `nav_msgs/Odometry` ([`super::ros`]) |
//! | `PREFIX/DROID/telemetry` | out | samples |
//! | `PREFIX/DROID/collision` | out | collisions |
//! | `PREFIX/DROID/battery` | out | battery readings |
//! | `PREFIX/DROID/state` | out, retained | the link's state; the last will says `offline` |
//! | `PREFIX/DROID/info` | out, retained | the droid as `hello` says it on stdio (`info`) |
//! | `PREFIX/DROID/reply` | out | replies, errors, and the bridge's own stops |
//! | `PREFIX/DROID/hold` | out, retained | whether the droid is held ([`super::hold`]) |
//! | `PREFIX/DROID/cruise` | out, retained | the cruise speed ([`super::cruise`]) |
//! | `PREFIX/DROID/animation`, `…/sound` | out, retained | what it played last ([`super::played`]) |
//! | `PREFIX/DROID/collisions` | out, retained | the collision count ([`super::kept`]) |
//! | `PREFIX/DROID/light`, `…/light/set` | out retained, in | Home Assistant's light ([`super::ha_light`]) |
//! | `PREFIX/bridge/ID` | out, retained | the `hello` object: every droid of bridge `ID` ([`super::presence`]) |
//! | `PREFIX/bridge/ID/state` | out, retained | the bridge online or offline (its own last will) |
//!
//! The retained `info`, `hold`, `cruise`, `animation`, `sound`, `collisions`, `light` and
//! `bridge/ID` topics are cleared when the bridge ends cleanly; `state` says offline.
//!
//! When the broker goes, the droids driven through it are stopped and the connection is
//! retried (backoff up to 5 s) while the droids' links stay up; back, the subscriptions and
//! the retained topics are made anew. Telemetry (samples, collisions, battery readings) that
//! could not be delivered meanwhile is dropped, never replayed late (issue 31 point 1): the
//! router drops it while the droid's connection is down, and what the client still held
//! for the broker is taken out of its queue; `stopped`, `link` objects, replies and errors
//! are kept and delivered after the reconnect.
//!
//! What arrives is handled by an [`Inbox`] ([`super::inbox`]) (no connection in it: the fuzz target drives
//! it): a command the broker hands over flagged retained (kept, at a (re)subscription)
//! never drives (issue 26 point 5; one published retained while the bridge is subscribed
//! arrives live, unflagged, and runs once: issue 40 point 10), a payload over the command
//! limit is a `bad_json` error (the client takes payloads far larger than that, so one
//! large message does not end the connection: point 6), and a connection the broker ends
//! right after making it, again and again, is another client with the same client id
//! ([`Takeovers`]: [`super::takeover`], point 7): said, and tried again after
//! [`TAKEOVER_BACKOFF`], never the end
//! of the bridge (issue 37 point 7: whoever took the id over would end it at will).

use super::Bridge;
use super::cruise::CRUISE_LEAF;
use super::feeds::{link_out, offline};
use super::inbox::Inbox;
use super::outbox::Outputs;
use super::played::PLAYED_LEAVES;
use super::schema::{ErrorCode, Out};
use super::takeover::{TAKEOVER_BACKOFF, TAKEOVERS, Takeovers};
pub use super::topics::topic;
use rumqttc::{AsyncClient, Event, EventLoop, LastWill, MqttOptions, Packet, QoS};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::watch;
use tokio::time::Instant;

/// MQTT's default ports.
pub const PORT: u16 = 1883;
pub const TLS_PORT: u16 = 8883;

/// The largest packet the client takes from the broker: far above the command limit
/// ([`super::schema::MAX_COMMAND_BYTES`]), so a large payload gets a `bad_json` error
/// instead of ending the connection. MQTT 3.1.1 has no way to tell the broker a limit: a
/// packet larger than this still ends it (a broker's `message_size_limit` prevents that).
pub const MAX_INCOMING_BYTES: usize = 1 << 20;

/// The default client id's start: unique per process (the process id and a random part,
/// as two machines or containers may run bridges with the same process id).
pub fn default_client_id() -> String {
    use std::hash::BuildHasher;
    let nonce = std::collections::hash_map::RandomState::new()
        .hash_one((std::process::id(), std::time::SystemTime::now()));
    format!("droidctl-{}-{:08x}", std::process::id(), nonce as u32)
}

/// `mqtt://[USER[:PASSWORD]@]HOST[:PORT]` or `mqtts://…` (TLS).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BrokerUrl {
    pub host: String,
    pub port: u16,
    pub tls: bool,
    pub username: Option<String>,
    pub password: Option<String>,
}

impl std::str::FromStr for BrokerUrl {
    type Err = String;

    fn from_str(s: &str) -> Result<BrokerUrl, String> {
        let usage = || {
            format!("`{s}` is not a broker URL: mqtt://HOST[:PORT] or mqtts://HOST[:PORT] (TLS)")
        };
        let (tls, rest) = if let Some(r) = s.strip_prefix("mqtts://") {
            (true, r)
        } else if let Some(r) = s.strip_prefix("mqtt://") {
            (false, r)
        } else if s.contains("://") {
            return Err(usage());
        } else {
            (false, s)
        };
        let rest = rest.trim_end_matches('/');
        let (user, hostport) = match rest.rsplit_once('@') {
            Some((u, h)) => (Some(u), h),
            None => (None, rest),
        };
        let (username, password) = match user {
            Some(u) => match u.split_once(':') {
                Some((n, p)) => (Some(n.to_string()), Some(p.to_string())),
                None => (Some(u.to_string()), None),
            },
            None => (None, None),
        };
        let default = if tls { TLS_PORT } else { PORT };
        let (host, port) = if let Some(v6) = hostport.strip_prefix('[') {
            let (h, after) = v6.split_once(']').ok_or_else(usage)?;
            let port = match after.strip_prefix(':') {
                Some(p) => p.parse().map_err(|_| usage())?,
                None if after.is_empty() => default,
                None => return Err(usage()),
            };
            (h.to_string(), port)
        } else {
            match hostport.rsplit_once(':') {
                Some((h, p)) => (h.to_string(), p.parse().map_err(|_| usage())?),
                None => (hostport.to_string(), default),
            }
        };
        if host.is_empty() || host.contains('/') || port == 0 {
            return Err(usage());
        }
        Ok(BrokerUrl {
            host,
            port,
            tls,
            username,
            password,
        })
    }
}

impl std::fmt::Display for BrokerUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let scheme = if self.tls { "mqtts" } else { "mqtt" };
        if self.host.contains(':') {
            write!(f, "{scheme}://[{}]:{}", self.host, self.port)
        } else {
            write!(f, "{scheme}://{}:{}", self.host, self.port)
        }
    }
}

/// Whether every address `host` names is a loopback address (`localhost`, 127.0.0.1, ::1,
/// ::ffff:127.0.0.1: [`crate::net::is_loopback`]):
/// only then does nobody but this machine reach the droids through the broker.
pub async fn is_loopback(host: &str, port: u16) -> Result<bool, String> {
    if let Ok(ip) = host.parse::<std::net::IpAddr>() {
        return Ok(crate::net::is_loopback(ip));
    }
    let addrs: Vec<_> = tokio::net::lookup_host((host, port))
        .await
        .map_err(|e| format!("cannot resolve {host}: {e}"))?
        .collect();
    Ok(!addrs.is_empty() && addrs.iter().all(crate::net::is_loopback_addr))
}

/// What the MQTT transport needs.
#[derive(Debug, Clone)]
pub struct MqttSettings {
    pub url: BrokerUrl,
    /// QoS of commands, telemetry, replies (the retained state is always sent at least once).
    pub qos: u8,
    /// The first topic level (`droidctl`).
    pub prefix: String,
    /// The client id's start; each droid's connection adds its topic name.
    pub client_id: String,
    /// This bridge's id among the bridges on the broker ([`super::presence`]).
    pub bridge_id: String,
    pub keepalive: Duration,
    pub username: Option<String>,
    pub password: Option<String>,
    /// A CA certificate (PEM) the broker's certificate must chain to (TLS); without it, the
    /// system's.
    pub ca_pem: Option<Vec<u8>>,
}

fn qos(q: u8) -> QoS {
    match q {
        0 => QoS::AtMostOnce,
        1 => QoS::AtLeastOnce,
        _ => QoS::ExactlyOnce,
    }
}

/// The topic leaves of telemetry: dropped, never replayed, when the broker was away.
pub const TELEMETRY_LEAVES: [&str; 4] = ["telemetry", "collision", "battery", "odom"];

/// Whether a request the MQTT client still holds is telemetry (to be dropped when the
/// connection was lost, not replayed late).
fn is_telemetry(r: &rumqttc::Request) -> bool {
    match r {
        rumqttc::Request::Publish(p) => TELEMETRY_LEAVES
            .iter()
            .any(|l| p.topic.rsplit('/').next() == Some(*l)),
        _ => false,
    }
}

/// Where an object goes: topic leaf and whether it is retained.
fn route(o: &Out) -> (&'static str, bool) {
    match o {
        Out::Telemetry { .. } => ("telemetry", false),
        Out::Collision { .. } => ("collision", false),
        Out::Battery { .. } => ("battery", false),
        Out::Link { .. } => ("state", true),
        Out::Info { .. } => ("info", true),
        Out::Hold { .. } => ("hold", true),
        Out::Cruise { .. } => (CRUISE_LEAF, true),
        Out::Played { what, .. } => (what, true),
        Out::Hello { .. } | Out::Stopped { .. } | Out::Reply { .. } | Out::Error { .. } => {
            ("reply", false)
        }
    }
}

fn droid_options(s: &MqttSettings, i: usize, t: &str, name: &str) -> Result<MqttOptions, String> {
    let mut o = options(s, &format!("{}-{i}-{t}", s.client_id))?;
    o.set_last_will(LastWill::new(
        topic(&s.prefix, t, "state"),
        offline(name).to_json(),
        QoS::AtLeastOnce,
        true,
    ));
    Ok(o)
}

/// A connection's options as client `id`: the broker, keepalive, credentials, TLS.
pub(super) fn options(s: &MqttSettings, id: &str) -> Result<MqttOptions, String> {
    let mut o = MqttOptions::new(id, s.url.host.clone(), s.url.port);
    o.set_keep_alive(s.keepalive.max(Duration::from_secs(1)));
    o.set_clean_session(true);
    o.set_max_packet_size(MAX_INCOMING_BYTES, super::schema::MAX_COMMAND_BYTES * 4);
    if let Some(u) = s.username.clone().or_else(|| s.url.username.clone()) {
        let p = s
            .password
            .clone()
            .or_else(|| s.url.password.clone())
            .unwrap_or_default();
        o.set_credentials(u, p);
    }
    if s.url.tls {
        o.set_transport(rumqttc::Transport::tls_with_config(tls(s
            .ca_pem
            .as_deref())?));
    }
    Ok(o)
}

/// TLS on Linux: rustls (ring), trusting `ca_pem` when given, else the platform's root
/// certificates (the files under /etc/ssl, read by rustls-native-certs). No OpenSSL.
#[cfg(target_os = "linux")]
fn tls(ca_pem: Option<&[u8]>) -> Result<rumqttc::TlsConfiguration, String> {
    use rustls::RootCertStore;
    use rustls::pki_types::CertificateDer;
    use rustls::pki_types::pem::PemObject;
    let mut roots = RootCertStore::empty();
    match ca_pem {
        Some(pem) => {
            let certs: Vec<CertificateDer> = CertificateDer::pem_slice_iter(pem)
                .collect::<Result<_, _>>()
                .map_err(|e| format!("the CA certificate is not PEM: {e}"))?;
            let (added, _) = roots.add_parsable_certificates(certs);
            if added == 0 {
                return Err("the CA file holds no usable certificate".into());
            }
        }
        None => {
            let found = rustls_native_certs::load_native_certs();
            let (added, _) = roots.add_parsable_certificates(found.certs);
            if added == 0 {
                return Err(format!(
                    "no root certificates found on this machine ({}): give the broker's CA \
                     with --ca-file FILE, or install the ca-certificates package",
                    found
                        .errors
                        .first()
                        .map(|e| e.to_string())
                        .unwrap_or_else(|| "none installed".into())
                ));
            }
        }
    }
    let config = rustls::ClientConfig::builder_with_provider(std::sync::Arc::new(
        rustls::crypto::ring::default_provider(),
    ))
    .with_safe_default_protocol_versions()
    .map_err(|e| format!("TLS: {e}"))?
    .with_root_certificates(roots)
    .with_no_client_auth();
    Ok(rumqttc::TlsConfiguration::Rustls(std::sync::Arc::new(
        config,
    )))
}

/// TLS on Windows and macOS: the system's own (native-tls: SChannel, Security.framework).
#[cfg(not(target_os = "linux"))]
fn tls(ca_pem: Option<&[u8]>) -> Result<rumqttc::TlsConfiguration, String> {
    Ok(match ca_pem {
        Some(ca) => rumqttc::TlsConfiguration::SimpleNative {
            ca: ca.to_vec(),
            client_auth: None,
        },
        None => rumqttc::TlsConfiguration::Native,
    })
}

/// A droid's connection to the broker: what it tells the others.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BrokerState {
    Connecting,
    Connected,
    /// Lost (or never made), retrying; why.
    Lost(String),
    /// The broker refused the first connection (credentials, authorization, TLS): not
    /// retried before the bridge has ever been connected.
    Refused(String),
}

/// Run the bridge through the broker until `stopped` completes: a connection per droid,
/// the objects routed to their topics. Fails when a droid's first connection to the broker
/// does not come within `first_connect` (a wrong host, port, password or certificate).
pub async fn run(
    bridge: Arc<Bridge>,
    mut rx: Outputs,
    settings: MqttSettings,
    first_connect: Duration,
    stopped: impl std::future::Future<Output = ()>,
) -> Result<(), String> {
    let members: Vec<(String, String)> = bridge
        .fleet()
        .members()
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let t = bridge.topic(i).unwrap_or("droid").to_string();
            (m.name.clone(), t)
        })
        .collect();
    let kept = Arc::new(super::kept::Kept::new(members.len()));
    let presence = {
        let b = bridge.clone();
        super::presence::Presence::start(
            &settings,
            bridge.settings().homeassistant.clone(),
            move || b.hello().to_json(),
        )?
    };
    let mut clients = Vec::new();
    let mut states = Vec::new();
    let mut loops = Vec::new();
    for (i, (name, t)) in members.iter().enumerate() {
        let (client, mut eventloop) = AsyncClient::new(droid_options(&settings, i, t, name)?, 1024);
        // Small messages out at once: without TCP_NODELAY a reply or a state change can wait
        // for the broker's delayed ACK (tens of ms) behind the telemetry before it.
        let mut net = rumqttc::NetworkOptions::new();
        net.set_tcp_nodelay(true);
        eventloop.set_network_options(net);
        let (tx, st) = watch::channel(BrokerState::Connecting);
        loops.push(tokio::spawn(connection(
            bridge.clone(),
            i,
            (client.clone(), eventloop),
            settings.clone(),
            tx,
            kept.clone(),
        )));
        clients.push(client);
        states.push(st);
    }
    // Each droid's first connection, or the reason it failed.
    for (st, (name, _)) in states.iter_mut().zip(&members) {
        let first = tokio::time::timeout(
            first_connect,
            st.wait_for(|s| matches!(s, BrokerState::Connected | BrokerState::Refused(_))),
        )
        .await
        .map(|r| r.is_ok());
        let connected = matches!(&*st.borrow(), BrokerState::Connected);
        if first != Ok(true) || !connected {
            let why = match &*st.borrow() {
                BrokerState::Lost(e) | BrokerState::Refused(e) => e.clone(),
                _ => format!("no answer within {} s", first_connect.as_secs()),
            };
            for l in &loops {
                l.abort();
            }
            return Err(format!(
                "cannot connect {name} to the broker at {}: {why}",
                settings.url
            ));
        }
    }
    let epoch = std::time::SystemTime::now() - Duration::from_millis(bridge.t_ms());
    let mut odom: Vec<_> = (0..members.len())
        .map(|_| super::ros::OdomTrack::new(epoch))
        .collect();
    let router = async {
        // By the droid's index: two droids may share a name, never a topic.
        while let Some(r) = rx.recv_routed().await {
            let (i, o) = (r.droid.unwrap_or(0), r.out);
            // Telemetry nobody can receive now is dropped: kept, it would arrive after the
            // reconnect as if the droid were doing it then.
            if super::outbox::droppable(&o)
                && states
                    .get(i)
                    .is_some_and(|s| *s.borrow() != BrokerState::Connected)
            {
                continue;
            }
            let (leaf, retain) = route(&o);
            let q = if retain {
                QoS::AtLeastOnce
            } else {
                qos(settings.qos)
            };
            let Some(((_, t), client)) = members.get(i).zip(clients.get(i)) else {
                continue;
            };
            // Each sample also as ROS odometry, beside it.
            if let Some(od) = odom.get_mut(i).and_then(|od| od.odometry(&o))
                && let Ok(json) = serde_json::to_string(&od)
            {
                let ros = topic(&settings.prefix, t, super::ros::ODOM);
                let _ = client.try_publish(ros, q, false, json);
            }
            if client
                .try_publish(topic(&settings.prefix, t, leaf), q, retain, o.to_json())
                .is_err()
            {
                tracing::debug!(droid = %t, leaf, "bridge: MQTT publish dropped (client queue full)");
            }
            // The retained count and light beside it; the bridge's hello with a new info.
            if let Some((leaf, payload)) = kept.after(i, &o) {
                let at = topic(&settings.prefix, t, leaf);
                let _ = client.try_publish(at, QoS::AtLeastOnce, true, payload);
            }
            if matches!(o, Out::Info { .. }) {
                presence.hello(bridge.hello().to_json());
            }
        }
    };
    tokio::select! {
        _ = router => {}
        _ = stopped => {}
    }
    // A clean goodbye sends no will: say offline ourselves, clear what describes a running
    // bridge (its own topics only), then disconnect. Home Assistant's entities stay unless
    // asked (issue 40 point 4): availability says they are gone.
    let remove = bridge.settings().homeassistant_remove;
    for (i, ((name, t), client)) in members.iter().zip(&clients).enumerate() {
        let mut gone: Vec<String> = ["info", "hold", CRUISE_LEAF, super::kept::COLLISIONS_LEAF]
            .into_iter()
            .chain(PLAYED_LEAVES)
            .chain(
                bridge
                    .settings()
                    .homeassistant
                    .as_ref()
                    .map(|_| super::ha_light::STATE_LEAF),
            )
            .map(|leaf| topic(&settings.prefix, t, leaf))
            .collect();
        if remove {
            gone.extend(discovery(&bridge, &settings, i).into_iter().map(|(t, _)| t));
        }
        for g in gone {
            let _ = client.try_publish(g, QoS::AtLeastOnce, true, Vec::new());
        }
        let _ = client.try_publish(
            topic(&settings.prefix, t, "state"),
            QoS::AtLeastOnce,
            true,
            offline(name).to_json(),
        );
        let _ = client.try_disconnect();
    }
    let _ = tokio::time::timeout(
        Duration::from_secs(2),
        futures_util::future::join(
            futures_util::future::join_all(loops.iter_mut()),
            presence.goodbye(remove),
        ),
    )
    .await;
    for l in &loops {
        l.abort();
    }
    Ok(())
}

/// Droid `i`'s Home Assistant discovery messages, when the bridge was asked for them.
fn discovery(bridge: &Bridge, s: &MqttSettings, i: usize) -> Vec<(String, String)> {
    let (Some(ha), Some(m), Some(t)) = (
        bridge.settings().homeassistant.as_deref(),
        bridge.fleet().member(i),
        bridge.topic(i),
    ) else {
        return Vec::new();
    };
    super::homeassistant::configs(
        ha,
        &super::homeassistant::Droid {
            prefix: &s.prefix,
            topic: t,
            name: &m.name,
            model: m.model,
            bridge: &s.bridge_id,
        },
    )
}

/// One droid's connection: subscribe on every connect, hand commands to the bridge, stop the
/// droid and retry when the broker goes.
async fn connection(
    bridge: Arc<Bridge>,
    i: usize,
    (client, mut eventloop): (AsyncClient, EventLoop),
    settings: MqttSettings,
    state: watch::Sender<BrokerState>,
    kept: Arc<super::kept::Kept>,
) {
    let t = bridge.topic(i).unwrap_or("droid").to_string();
    let ha = super::homeassistant::Topics::new(&bridge, &settings.prefix, i);
    let mut inbox = Inbox::new(bridge.clone(), i, &settings.prefix);
    let cmd = inbox.cmd_topic().to_string();
    let cmd_vel = inbox.cmd_vel_topic().to_string();
    let mut takeovers = Takeovers::default();
    let name = bridge
        .fleet()
        .member(i)
        .map(|m| m.name.clone())
        .unwrap_or_default();
    let mut backoff = Duration::from_millis(250);
    let mut up = false;
    let mut ever = false;
    let mut closing = false;
    loop {
        match eventloop.poll().await {
            Ok(Event::Incoming(Packet::ConnAck(_))) => {
                up = true;
                inbox.connected();
                let again = ever;
                ever = true;
                takeovers.connected(Instant::now());
                backoff = Duration::from_millis(250);
                // Telemetry held from before the loss goes, the rest is delivered.
                eventloop.pending.retain(|r| !is_telemetry(r));
                let _ = client.try_subscribe(cmd.clone(), qos(settings.qos));
                for f in ha.filters() {
                    let _ = client.try_subscribe(f, QoS::AtMostOnce);
                }
                let _ = client.try_subscribe(cmd_vel.clone(), qos(settings.qos));
                // The retained state anew (the will may have replaced it); at the first
                // connection the droid's link feed says it (once).
                if again && let Some(s) = bridge.fleet().link_state(i) {
                    let now = link_out(&name, &s.borrow(), bridge.is_ready(i));
                    let _ = client.try_publish(
                        topic(&settings.prefix, &t, "state"),
                        QoS::AtLeastOnce,
                        true,
                        now.to_json(),
                    );
                }
                // What the droid and the bridge are, retained (a broker restarted without
                // persistence forgot them).
                let mut retained: Vec<(String, String)> =
                    [bridge.info(i), bridge.hold_state(i), bridge.cruise_state(i)]
                        .into_iter()
                        .flatten()
                        .chain(bridge.played_state(i))
                        .map(|o| (topic(&settings.prefix, &t, route(&o).0), o.to_json()))
                        .collect();
                retained.extend(
                    kept.at_connect(i, &name, ha.light.is_some())
                        .into_iter()
                        .map(|(leaf, p)| (topic(&settings.prefix, &t, leaf), p)),
                );
                retained.extend(discovery(&bridge, &settings, i));
                for (topic, payload) in retained {
                    let _ = client.try_publish(topic, QoS::AtLeastOnce, true, payload);
                }
                if *state.borrow() != BrokerState::Connecting {
                    eprintln!("droidctl: {name}: connected to the broker again");
                }
                state.send_replace(BrokerState::Connected);
            }
            Ok(Event::Incoming(Packet::Publish(p))) if ha.owns(&p.topic) => {
                // Home Assistant started: everything it reads of this droid anew.
                if ha.birth.as_deref() == Some(&p.topic) && &p.payload[..] == b"online" {
                    for (topic, payload) in discovery(&bridge, &settings, i) {
                        let _ = client.try_publish(topic, QoS::AtLeastOnce, true, payload);
                    }
                } else if let (Some((set, group)), false) = (&ha.light, p.retain)
                    && *set == p.topic
                {
                    match kept.light_set(i, group, &p.payload) {
                        Ok(cmd) => bridge.handle(cmd.as_bytes(), Some(i)),
                        Err(error) => bridge.emit(
                            Some(i),
                            Out::Error {
                                id: None,
                                droid: Some(name.clone()),
                                cmd: Some("lights".into()),
                                code: ErrorCode::BadJson,
                                robot: None,
                                capability: None,
                                error: format!("{set}: {error}"),
                            },
                        ),
                    }
                }
            }
            Ok(Event::Incoming(Packet::Publish(p))) => {
                if let Some(said) = inbox.publish(&p.topic, p.retain, &p.payload) {
                    eprintln!("{said}");
                }
            }
            // Said goodbye: wait for the broker to close the connection, so it has read
            // everything before (a process that ends with unread data on its socket resets
            // the connection, and the broker may drop what it had not read yet: the
            // retained clears of a clean end).
            Ok(Event::Outgoing(rumqttc::Outgoing::Disconnect)) => closing = true,
            Ok(_) => {}
            Err(_) if closing => return,
            Err(e) => {
                let why = e.to_string();
                // Telemetry that did not go out before the loss is not sent late.
                eventloop.pending.retain(|r| !is_telemetry(r));
                if up {
                    up = false;
                    bridge.release([i], "broker_lost");
                    eprintln!(
                        "droidctl: {name}: lost the broker ({why}): stopped; reconnecting, the droid stays connected"
                    );
                }
                if takeovers.lost(Instant::now()) {
                    // Not the end of the bridge (issue 37 point 7): whoever takes the id
                    // over would end it at will. Said, then retried slowly, so two bridges
                    // given the same id do not knock each other off every second.
                    let message = format!(
                        "{name}: the broker ended the connection right after accepting it, \
                         {TAKEOVERS} times in a row: most likely another client is connected \
                         with the same client id ({}-{i}-{t}); give each bridge its own \
                         --client-id (or leave it out: the default is unique). Trying again \
                         in {} s; the droid stays stopped meanwhile",
                        settings.client_id,
                        TAKEOVER_BACKOFF.as_secs()
                    );
                    tracing::error!("bridge: {message}");
                    eprintln!("droidctl: {message}");
                    state.send_replace(BrokerState::Lost(message));
                    tokio::time::sleep(TAKEOVER_BACKOFF).await;
                    continue;
                }
                // A refusal or an untrusted certificate will not mend by itself.
                if !ever
                    && matches!(
                        e,
                        rumqttc::ConnectionError::ConnectionRefused(_)
                            | rumqttc::ConnectionError::Tls(_)
                    )
                {
                    state.send_replace(BrokerState::Refused(why));
                    return;
                }
                state.send_replace(BrokerState::Lost(why));
                tokio::time::sleep(backoff).await;
                backoff = (backoff * 2).min(Duration::from_secs(5));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_client_id_is_unique_per_process() {
        let (a, b) = (default_client_id(), default_client_id());
        let pid = format!("droidctl-{}-", std::process::id());
        assert!(a.starts_with(&pid) && b.starts_with(&pid), "{a} {b}");
        assert_ne!(a, b, "a random part besides the process id");
    }

    #[test]
    fn the_client_takes_payloads_far_over_the_command_limit() {
        let s = MqttSettings {
            url: "mqtt://localhost".parse().unwrap(),
            qos: 0,
            prefix: "droidctl".into(),
            client_id: "x".into(),
            bridge_id: "b".into(),
            keepalive: Duration::from_secs(5),
            username: None,
            password: None,
            ca_pem: None,
        };
        let o = droid_options(&s, 0, "D2-0001", "D2-0001").unwrap();
        assert!(o.max_packet_size() >= MAX_INCOMING_BYTES);
        const { assert!(MAX_INCOMING_BYTES >= 100 * super::super::schema::MAX_COMMAND_BYTES) };
    }
}
