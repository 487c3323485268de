//! `--remote HOST[:PORT]`: a droid behind a TCP relay (`droidctl serve`, or spherov2.py's
//! own `tcp_server`), speaking spherov2's relay protocol ([`crate::protocol::relay`]).
//!
//! [`RemoteLink`] is a [`Link`] like the BLE one: each `open()` makes a TCP connection,
//! INITs the droid (the relay connects to it), runs the model's handshake writes and
//! subscribes (SET_CALLBACK) to the profile's notify characteristics; ON_DATA becomes
//! [`LinkEvent::Data`], and a closed connection becomes [`LinkEvent::Disconnected`], so
//! the session reconnects with its backoff when the relay, the network or the droid drops.
//!
//! The protocol has no read: a handshake step that reads (Robi 42's version and announced
//! frame interval) is skipped with a warning. The start confirmation is still written, so
//! the frames flow; only the announced interval is unknown.

mod client;
mod discover;

pub use client::KEEPALIVE;
pub use discover::{RemoteDevice, RemoteSelector, find, pick, scan, select};

use crate::gatt::Endpoint;
use crate::gatt::{GattProfile, GattUuid, HandshakeStep};
use crate::link::{Connection, Link, LinkError, LinkEvent, LinkWriter};
use crate::model::Model;
use crate::protocol::relay::{DEFAULT_PORT, Request};
use client::{EVENTS, Incoming, RelayClient};
use futures_util::future::BoxFuture;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;
use tokio::time::{Instant, sleep_until};

/// A relay's address: `HOST`, `HOST:PORT`, `[v6]:PORT`; the port defaults to spherov2's.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RelayAddr {
    pub host: String,
    pub port: u16,
}

impl std::fmt::Display for RelayAddr {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.host.contains(':') {
            write!(f, "[{}]:{}", self.host, self.port)
        } else {
            write!(f, "{}:{}", self.host, self.port)
        }
    }
}

impl std::str::FromStr for RelayAddr {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        let bad = || format!("`{s}` is not HOST or HOST:PORT");
        if s.is_empty() {
            return Err(bad());
        }
        let port = |p: &str| {
            p.parse::<u16>()
                .ok()
                .filter(|p| *p > 0)
                .ok_or_else(|| format!("`{p}` is not a port (1-65535)"))
        };
        if let Some(rest) = s.strip_prefix('[') {
            let (host, after) = rest.split_once(']').ok_or_else(bad)?;
            let p = match after.strip_prefix(':') {
                Some(p) => port(p)?,
                None if after.is_empty() => DEFAULT_PORT,
                None => return Err(bad()),
            };
            return Ok(RelayAddr {
                host: host.to_string(),
                port: p,
            });
        }
        match s.matches(':').count() {
            0 => Ok(RelayAddr {
                host: s.to_string(),
                port: DEFAULT_PORT,
            }),
            1 => {
                let (h, p) = s.split_once(':').ok_or_else(bad)?;
                if h.is_empty() {
                    return Err(bad());
                }
                Ok(RelayAddr {
                    host: h.to_string(),
                    port: port(p)?,
                })
            }
            // A bare IPv6 address.
            _ => Ok(RelayAddr {
                host: s.to_string(),
                port: DEFAULT_PORT,
            }),
        }
    }
}

/// Timeouts of the relay client.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RemoteTimeouts {
    /// The TCP connection.
    pub connect: Duration,
    /// INIT: the relay connects to the droid (droidctl's relay gives up after 20 s).
    pub init: Duration,
    /// Each WRITE and SET_CALLBACK.
    pub op: Duration,
}

impl Default for RemoteTimeouts {
    fn default() -> Self {
        RemoteTimeouts {
            connect: Duration::from_secs(5),
            init: Duration::from_secs(25),
            op: Duration::from_secs(5),
        }
    }
}

/// A droid behind a relay.
pub struct RemoteLink {
    relay: RelayAddr,
    address: String,
    name: String,
    model: Model,
    profile: GattProfile,
    timeouts: RemoteTimeouts,
    warned_read: bool,
}

impl RemoteLink {
    /// The droid at `address` (as the relay names it) behind `relay`, a `model` speaking
    /// `profile`.
    pub fn new(
        relay: RelayAddr,
        address: impl Into<String>,
        name: impl Into<String>,
        model: Model,
        profile: GattProfile,
    ) -> Self {
        RemoteLink {
            relay,
            address: address.into(),
            name: name.into(),
            model,
            profile,
            timeouts: RemoteTimeouts::default(),
            warned_read: false,
        }
    }

    pub fn with_timeouts(mut self, t: RemoteTimeouts) -> Self {
        self.timeouts = t;
        self
    }

    pub fn model(&self) -> Model {
        self.model
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn address(&self) -> &str {
        &self.address
    }

    pub fn profile(&self) -> &GattProfile {
        &self.profile
    }

    async fn open_remote(&mut self) -> Result<Connection, LinkError> {
        let t = self.timeouts;
        let (client, mut incoming) = RelayClient::connect(&self.relay, t.connect).await?;
        let client = Arc::new(client);
        let who = format!("{} ({})", self.name, self.address);
        let fail = |what: &str, e: String| LinkError::transient(format!("{what} {who}: {e}"));
        let setup = async {
            let address = self.address.clone();
            client
                .call(move |seq| Request::Init { seq, address }, t.init)
                .await
                .map_err(|e| fail("the relay could not connect to", e))?;
            for step in &self.profile.handshake {
                match step {
                    HandshakeStep::Write { ch, bytes, .. } => {
                        let uuid = ch.characteristic.to_string();
                        let data = bytes.clone();
                        client
                            .call(
                                move |seq| Request::Write {
                                    seq,
                                    characteristic: uuid,
                                    data,
                                },
                                t.op,
                            )
                            .await
                            .map_err(|e| fail("handshake with", e))?;
                    }
                    HandshakeStep::Read { ch, .. } => {
                        if !self.warned_read {
                            tracing::warn!(
                                characteristic = %ch,
                                "the relay protocol cannot read: handshake read skipped"
                            );
                            self.warned_read = true;
                        }
                    }
                }
            }
            for ch in &self.profile.notify {
                let uuid = ch.characteristic.to_string();
                client
                    .call(
                        move |seq| Request::SetCallback {
                            seq,
                            characteristic: uuid,
                        },
                        t.op,
                    )
                    .await
                    .map_err(|e| fail("subscribing to", e))?;
            }
            Ok::<(), LinkError>(())
        };
        if let Err(e) = setup.await {
            client.close().await;
            return Err(e);
        }
        let notify: Vec<GattUuid> = self
            .profile
            .notify
            .iter()
            .map(|c| c.characteristic)
            .collect();
        let (tx, rx) = mpsc::channel(EVENTS);
        tokio::spawn(async move {
            loop {
                let ev = tokio::select! {
                    _ = tx.closed() => return,
                    ev = incoming.recv() => ev,
                };
                match ev {
                    Some(Incoming::Data {
                        characteristic,
                        data,
                    }) => {
                        let ours =
                            GattUuid::parse(&characteristic).is_some_and(|u| notify.contains(&u));
                        if !ours || data.is_empty() {
                            continue;
                        }
                        if tx.send(LinkEvent::Data(data)).await.is_err() {
                            return;
                        }
                    }
                    Some(Incoming::Closed(why)) => {
                        let _ = tx.send(LinkEvent::Disconnected(why)).await;
                        return;
                    }
                    None => {
                        let _ = tx
                            .send(LinkEvent::Disconnected("the relay connection ended".into()))
                            .await;
                        return;
                    }
                }
            }
        });
        Ok(Connection {
            writer: Box::new(RemoteWriter {
                client: Some(client),
                profile: self.profile.clone(),
                op: t.op,
                next_write: None,
                name: self.name.clone(),
            }),
            events: rx,
        })
    }
}

impl Link for RemoteLink {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            self.open_remote().await.inspect_err(|e| {
                tracing::warn!(error = %e, "relay open failed");
            })
        })
    }

    /// A relay closes a client silent for its idle timeout (`droidctl serve`: 60 s by
    /// default): a third of that is written in time.
    fn keepalive(&self) -> Option<Duration> {
        Some(KEEPALIVE)
    }

    fn describe(&self) -> String {
        format!(
            "{} {} ({}) via {}",
            self.model.display_name(),
            self.name,
            self.address,
            self.relay
        )
    }
}

/// WRITEs to the profile's characteristics, chunked and paced like the BLE writer.
struct RemoteWriter {
    client: Option<Arc<RelayClient>>,
    profile: GattProfile,
    op: Duration,
    next_write: Option<Instant>,
    name: String,
}

impl LinkWriter for RemoteWriter {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_to(Endpoint::Api, chunk)
    }

    fn write_to<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_paced(to, chunk, false)
    }

    /// The emergency stop: not held back by the pacing slot.
    fn write_urgent<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        self.write_paced(to, chunk, true)
    }

    fn close(&mut self) -> BoxFuture<'_, ()> {
        Box::pin(async move {
            if let Some(c) = self.client.take() {
                c.close().await;
            }
        })
    }
}

impl RemoteWriter {
    /// Write to `to`'s characteristic through the relay, paced unless `urgent`.
    fn write_paced<'a>(
        &'a mut self,
        to: Endpoint,
        chunk: &'a [u8],
        urgent: bool,
    ) -> BoxFuture<'a, Result<(), LinkError>> {
        Box::pin(async move {
            let ch = self.profile.endpoint(to).ok_or_else(|| {
                LinkError::fatal(format!("{} has no {} input", self.name, to.name()))
            })?;
            let client = self
                .client
                .clone()
                .ok_or_else(|| LinkError::transient("the relay link is closed"))?;
            let uuid = ch.characteristic.to_string();
            for piece in chunk.chunks(self.profile.chunk_size.max(1)) {
                if let Some(at) = self.next_write.filter(|_| !urgent) {
                    sleep_until(at).await;
                }
                let (u, data) = (uuid.clone(), piece.to_vec());
                let r = client
                    .call(
                        move |seq| Request::Write {
                            seq,
                            characteristic: u,
                            data,
                        },
                        self.op,
                    )
                    .await;
                self.next_write = Some(Instant::now() + self.profile.pacing);
                r.map_err(|e| LinkError::transient(format!("writing to {}: {e}", self.name)))?;
            }
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relay_addresses_parse() {
        let p = |s: &str| s.parse::<RelayAddr>();
        assert_eq!(
            p("pi.local"),
            Ok(RelayAddr {
                host: "pi.local".into(),
                port: 50004
            })
        );
        assert_eq!(p("10.0.0.2:6000").unwrap().port, 6000);
        assert_eq!(p("[::1]:7").unwrap().host, "::1");
        assert_eq!(p("[::1]").unwrap().port, 50004);
        assert_eq!(p("::1").unwrap().host, "::1");
        assert_eq!(p("[::1]:7").unwrap().to_string(), "[::1]:7");
        assert!(p("host:0").is_err());
        assert!(p("host:x").is_err());
        assert!(p(":50004").is_err());
        assert!(p("").is_err());
        assert!(p("[::1").is_err());
    }

    #[test]
    fn picking_behind_a_relay() {
        let d = |n: &str, a: &str| RemoteDevice {
            name: n.into(),
            address: a.into(),
            model: Model::from_advertised_name(n),
        };
        let all = vec![
            d("D2-0001", "5E:D0:00:00:00:01"),
            d("Q5-0002", "5E:D0:00:00:00:02"),
            d("TV", "5E:D0:00:00:00:03"),
        ];
        let sel = |name: Option<&str>, address: Option<&str>| RemoteSelector {
            name: name.map(str::to_string),
            address: address.map(str::to_string),
            scan_timeout: Duration::from_secs(1),
        };
        assert_eq!(pick(&all, &sel(Some("q5"), None)).unwrap().name, "Q5-0002");
        assert_eq!(
            pick(&all, &sel(None, Some("5e:d0:00:00:00:01")))
                .unwrap()
                .name,
            "D2-0001"
        );
        assert!(
            pick(&all, &sel(None, None))
                .unwrap_err()
                .contains("several droids")
        );
        assert!(pick(&all, &sel(Some("000"), None)).is_err());
        assert_eq!(pick(&all[..1], &sel(None, None)).unwrap().name, "D2-0001");
    }
}
