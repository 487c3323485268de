//! The bridge over MQTT, through a broker (mosquitto, or any MQTT 3.1.1 broker), with the
//! `rumqttc` client. Each droid has its own topics and its own connection to the broker,
//! so each has its own last will:
//!
//! | topic | direction | what |
//! |---|---|---|
//! | `PREFIX/DROID/cmd` | in | commands ([`super::schema`]); the topic names the droid |
//! | `PREFIX/DROID/telemetry` | out | samples |
//! | `PREFIX/DROID/collision` | out | collisions |
//! | `PREFIX/DROID/battery` | out | battery readings |
//! | `PREFIX/DROID/state` | out, retained | the link's state; the last will says `offline` |
//! | `PREFIX/DROID/reply` | out | replies, errors, and the bridge's own stops |
//!
//! When the broker goes, the droids driven through it are stopped and the connection is
//! retried (backoff up to 5 s) while the droids' links stay up; back, the subscriptions and
//! the retained state are made anew.

use super::feeds::{link_out, offline};
use super::schema::Out;
use super::{Bridge, topic_name};
use rumqttc::{AsyncClient, Event, EventLoop, LastWill, MqttOptions, Packet, QoS};
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::{mpsc, watch};

/// MQTT's default ports.
pub const PORT: u16 = 1883;
pub const TLS_PORT: u16 = 8883;

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

/// Whether every address `host` names is a loopback address (`localhost`, 127.0.0.1, ::1):
/// only then does nobody but this machine reach the droids through the broker.
pub async fn is_loopback(host: &str, port: u16) -> Result<bool, String> {
    if let Ok(ip) = host.parse::<std::net::IpAddr>() {
        return Ok(ip.is_loopback());
    }
    let addrs: Vec<_> = tokio::net::lookup_host((host, port))
        .await
        .map_err(|e| format!("cannot resolve {host}: {e}"))?
        .collect();
    Ok(!addrs.is_empty() && addrs.iter().all(|a| a.ip().is_loopback()))
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

/// The topic of droid topic-name `t`'s `leaf`.
pub fn topic(prefix: &str, t: &str, leaf: &str) -> String {
    format!("{prefix}/{t}/{leaf}")
}

/// Where an object goes: topic leaf and whether it is retained.
fn route(o: &Out) -> (&'static str, bool) {
    match o {
        Out::Telemetry { .. } => ("telemetry", false),
        Out::Collision { .. } => ("collision", false),
        Out::Battery { .. } => ("battery", false),
        Out::Link { .. } => ("state", true),
        Out::Hello { .. } | Out::Stopped { .. } | Out::Reply { .. } | Out::Error { .. } => {
            ("reply", false)
        }
    }
}

fn options(s: &MqttSettings, i: usize, t: &str, name: &str) -> Result<MqttOptions, String> {
    let id = format!("{}-{i}-{t}", s.client_id);
    let mut o = MqttOptions::new(id, s.url.host.clone(), s.url.port);
    o.set_keep_alive(s.keepalive.max(Duration::from_secs(1)));
    o.set_clean_session(true);
    o.set_max_packet_size(
        super::schema::MAX_COMMAND_BYTES + 1024,
        super::schema::MAX_COMMAND_BYTES * 4,
    );
    o.set_last_will(LastWill::new(
        topic(&s.prefix, t, "state"),
        offline(name).to_json(),
        QoS::AtLeastOnce,
        true,
    ));
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
    mut rx: mpsc::Receiver<Out>,
    settings: MqttSettings,
    first_connect: Duration,
    stopped: impl std::future::Future<Output = ()>,
) -> Result<(), String> {
    let members: Vec<(String, String)> = bridge
        .fleet()
        .members()
        .iter()
        .map(|m| (m.name.clone(), topic_name(&m.name)))
        .collect();
    let mut clients = Vec::new();
    let mut states = Vec::new();
    let mut loops = Vec::new();
    for (i, (name, t)) in members.iter().enumerate() {
        let (client, mut eventloop) = AsyncClient::new(options(&settings, i, t, name)?, 1024);
        // Small messages out at once: without TCP_NODELAY a reply or a state change can wait
        // for the broker's delayed ACK (tens of ms) behind the telemetry before it.
        let mut net = rumqttc::NetworkOptions::new();
        net.set_tcp_nodelay(true);
        eventloop.set_network_options(net);
        let (tx, st) = watch::channel(BrokerState::Connecting);
        loops.push(tokio::spawn(connection(
            bridge.clone(),
            i,
            client.clone(),
            eventloop,
            settings.clone(),
            t.clone(),
            tx,
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
    let index: HashMap<String, usize> = members
        .iter()
        .enumerate()
        .map(|(i, (n, _))| (n.clone(), i))
        .collect();
    let router = async {
        while let Some(o) = rx.recv().await {
            let i = o.droid().and_then(|d| index.get(d).copied()).unwrap_or(0);
            let (leaf, retain) = route(&o);
            let q = if retain {
                QoS::AtLeastOnce
            } else {
                qos(settings.qos)
            };
            let Some(((_, t), client)) = members.get(i).zip(clients.get(i)) else {
                continue;
            };
            if client
                .try_publish(topic(&settings.prefix, t, leaf), q, retain, o.to_json())
                .is_err()
            {
                tracing::debug!(droid = %t, leaf, "bridge: MQTT publish dropped (client queue full)");
            }
        }
    };
    tokio::select! {
        _ = router => {}
        _ = stopped => {}
    }
    // A clean goodbye sends no will: say offline ourselves, then disconnect.
    for ((name, t), client) in members.iter().zip(&clients) {
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
        futures_util::future::join_all(loops.iter_mut()),
    )
    .await;
    for l in &loops {
        l.abort();
    }
    Ok(())
}

/// One droid's connection: subscribe on every connect, hand commands to the bridge, stop the
/// droid and retry when the broker goes.
async fn connection(
    bridge: Arc<Bridge>,
    i: usize,
    client: AsyncClient,
    mut eventloop: EventLoop,
    settings: MqttSettings,
    t: String,
    state: watch::Sender<BrokerState>,
) {
    let cmd = topic(&settings.prefix, &t, "cmd");
    let name = bridge
        .fleet()
        .member(i)
        .map(|m| m.name.clone())
        .unwrap_or_default();
    let mut backoff = Duration::from_millis(250);
    let mut up = false;
    let mut ever = false;
    loop {
        match eventloop.poll().await {
            Ok(Event::Incoming(Packet::ConnAck(_))) => {
                up = true;
                ever = true;
                backoff = Duration::from_millis(250);
                let _ = client.try_subscribe(cmd.clone(), qos(settings.qos));
                // The retained state anew (the will may have replaced it).
                if let Some(s) = bridge.fleet().link_state(i) {
                    let now = link_out(&name, &s.borrow());
                    let _ = client.try_publish(
                        topic(&settings.prefix, &t, "state"),
                        QoS::AtLeastOnce,
                        true,
                        now.to_json(),
                    );
                }
                if *state.borrow() != BrokerState::Connecting {
                    eprintln!("droidctl: {name}: connected to the broker again");
                }
                state.send_replace(BrokerState::Connected);
            }
            Ok(Event::Incoming(Packet::Publish(p))) if p.topic == cmd => {
                bridge.handle(&p.payload, Some(i));
            }
            Ok(Event::Outgoing(rumqttc::Outgoing::Disconnect)) => return,
            Ok(_) => {}
            Err(e) => {
                let why = e.to_string();
                if up {
                    up = false;
                    bridge.release([i], "broker_lost");
                    eprintln!(
                        "droidctl: {name}: lost the broker ({why}): stopped; reconnecting, the droid stays connected"
                    );
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
