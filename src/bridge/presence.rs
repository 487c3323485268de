//! Several bridges on one broker (issue 40 points 1 and 2): each bridge has an id of its
//! own, and what it says about itself lives under it — its `hello` retained on
//! `PREFIX/bridge/ID`, its availability retained on `PREFIX/bridge/ID/state` (its last will
//! says offline) — so one bridge neither overwrites nor, leaving, deletes another's.
//!
//! Before its droids take their topics, a bridge looks at what is live on the broker
//! ([`probe`]): a droid topic whose retained `state` is anything but `offline` belongs to a
//! bridge that is running, so this bridge's droid of the same name takes a distinct topic
//! (`SB-0001-2`), and says so; likewise a bridge id already online. Two bridges started at
//! the very same moment can still both see nothing: the probe narrows the race to the
//! probe's own round trip, it cannot close it (MQTT has no lock).

use super::mqtt::MqttSettings;
use super::topics::topic;
use rumqttc::{AsyncClient, Event, LastWill, Packet, QoS};
use serde_json::{Value, json};
use std::collections::HashSet;
use std::time::Duration;

/// Where bridge `id` retains its `hello`.
pub fn hello_topic(prefix: &str, id: &str) -> String {
    format!("{prefix}/bridge/{id}")
}

/// Where bridge `id` retains whether it is online (its last will says offline).
pub fn state_topic(prefix: &str, id: &str) -> String {
    format!("{prefix}/bridge/{id}/state")
}

/// The `bridge_state` object of bridge `id`.
pub fn state_json(id: &str, online: bool) -> String {
    json!({
        "v": super::schema::VERSION,
        "type": "bridge_state",
        "bridge": id,
        "state": if online { "online" } else { "offline" },
    })
    .to_string()
}

/// The default bridge id: this machine's host name as a topic level (a Raspberry Pi per
/// table has one each), `droidctl` when none can be read.
pub fn default_id() -> String {
    let host = ["HOSTNAME", "COMPUTERNAME"]
        .iter()
        .find_map(|k| std::env::var(k).ok())
        .or_else(|| {
            crate::text_file::read("/etc/hostname".as_ref(), 256)
                .ok()
                .map(|s| s.trim().to_string())
        })
        .filter(|h| !h.is_empty());
    super::topic_name(host.as_deref().unwrap_or("droidctl"))
}

/// What is live on the broker: droid topic levels (lowercase) and bridge ids.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Live {
    pub droids: HashSet<String>,
    pub bridges: HashSet<String>,
}

impl Live {
    /// One retained message under `prefix` (sans-IO): a droid's `state` or a bridge's.
    /// Anything that does not read as one is ignored.
    pub fn read(&mut self, prefix: &str, t: &str, payload: &[u8]) {
        let Some(rest) = t.strip_prefix(prefix).and_then(|r| r.strip_prefix('/')) else {
            return;
        };
        let state = serde_json::from_slice::<Value>(payload)
            .ok()
            .and_then(|v| v.get("state").and_then(Value::as_str).map(str::to_string));
        let live = state.is_some_and(|s| s != "offline");
        match rest.split('/').collect::<Vec<_>>()[..] {
            ["bridge", id, "state"] if live => {
                self.bridges.insert(id.to_string());
            }
            [droid, "state"] if live && droid != "bridge" => {
                self.droids.insert(droid.to_lowercase());
            }
            _ => {}
        }
    }
}

/// `base`, or the first of `base-2`, `base-3` … that `taken` does not hold (compared in
/// lowercase).
pub fn distinct(base: &str, taken: &HashSet<String>) -> String {
    let mut t = base.to_string();
    let mut k = 2usize;
    while taken.contains(&t.to_lowercase()) {
        t = format!("{base}-{k}");
        k += 1;
    }
    t
}

/// What is live on the broker now: the retained states under the prefix, read through a
/// short connection of its own. A second SUBSCRIBE marks the end: a broker sends the
/// retained messages of the first right after its SUBACK, before it reads the next packet
/// (mosquitto and droidctl's own do), so the second SUBACK comes after all of them.
pub async fn probe(s: &MqttSettings, within: Duration) -> Result<Live, String> {
    let mut o = super::mqtt::options(s, &format!("{}-probe", s.client_id))?;
    o.set_last_will(LastWill::new(
        format!("{}/bridge/probe", s.prefix),
        Vec::new(),
        QoS::AtMostOnce,
        false,
    ));
    let (client, mut ev) = AsyncClient::new(o, 64);
    let prefix = s.prefix.clone();
    let work = async {
        let mut live = Live::default();
        let mut acks = 0;
        loop {
            match ev.poll().await {
                Ok(Event::Incoming(Packet::ConnAck(_))) => {
                    let filters = [topic(&prefix, "+", "state"), state_topic(&prefix, "+")];
                    for f in filters {
                        let _ = client.try_subscribe(f, QoS::AtMostOnce);
                    }
                    // The mark: nothing is retained there.
                    let _ =
                        client.try_subscribe(format!("{prefix}/bridge/+/probe"), QoS::AtMostOnce);
                }
                Ok(Event::Incoming(Packet::Publish(p))) if p.retain => {
                    live.read(&prefix, &p.topic, &p.payload)
                }
                Ok(Event::Incoming(Packet::SubAck(_))) => {
                    acks += 1;
                    if acks == 3 {
                        return Ok(live);
                    }
                }
                Ok(_) => {}
                Err(e) => return Err(e.to_string()),
            }
        }
    };
    let got = tokio::time::timeout(within, work).await;
    let _ = client.try_disconnect();
    // The DISCONNECT out before the connection goes.
    let _ = tokio::time::timeout(Duration::from_millis(500), async {
        while ev.poll().await.is_ok() {}
    })
    .await;
    match got {
        Ok(Ok(live)) => Ok(live),
        Ok(Err(e)) => Err(format!(
            "cannot connect to the broker at {}: {e} (check the URL, --username and \
             --password-file)",
            s.url
        )),
        Err(_) => Err(format!(
            "the broker at {} did not answer within {} s",
            s.url,
            within.as_secs()
        )),
    }
}

/// Bridge `id`'s own connection to the broker: it keeps the bridge's `hello` and
/// availability (its last will says offline), and the bridge's Home Assistant device,
/// published again at each connection and at Home Assistant's birth message.
pub struct Presence {
    client: AsyncClient,
    prefix: String,
    id: String,
    homeassistant: Option<String>,
    task: tokio::task::JoinHandle<()>,
}

impl Presence {
    /// Connect bridge `id` (its `hello` from `hello`, called at each connection).
    pub fn start(
        s: &MqttSettings,
        homeassistant: Option<String>,
        hello: impl Fn() -> String + Send + Sync + 'static,
    ) -> Result<Presence, String> {
        let id = s.bridge_id.clone();
        let cid = format!("{}-bridge", s.client_id);
        let mut o = super::mqtt::options(s, &cid)?;
        o.set_last_will(LastWill::new(
            state_topic(&s.prefix, &id),
            state_json(&id, false),
            QoS::AtLeastOnce,
            true,
        ));
        let (client, mut ev) = AsyncClient::new(o, 64);
        let (c, prefix, ha, bid) = (
            client.clone(),
            s.prefix.clone(),
            homeassistant.clone(),
            id.clone(),
        );
        let task = tokio::spawn(async move {
            let birth = ha.as_ref().map(|h| format!("{h}/status"));
            let announce = |c: &AsyncClient| {
                let mut out = vec![
                    (hello_topic(&prefix, &bid), hello()),
                    (state_topic(&prefix, &bid), state_json(&bid, true)),
                ];
                if let Some(h) = &ha {
                    out.extend(super::homeassistant::bridge_configs(h, &prefix, &bid));
                }
                for (t, p) in out {
                    let _ = c.try_publish(t, QoS::AtLeastOnce, true, p);
                }
            };
            let mut takeovers = super::takeover::Takeovers::default();
            loop {
                match ev.poll().await {
                    Ok(Event::Incoming(Packet::ConnAck(_))) => {
                        takeovers.connected(tokio::time::Instant::now());
                        if let Some(b) = &birth {
                            let _ = c.try_subscribe(b.clone(), QoS::AtMostOnce);
                        }
                        announce(&c);
                    }
                    Ok(Event::Incoming(Packet::Publish(p)))
                        if Some(&p.topic) == birth.as_ref()
                            && &p.payload[..] == b"online"
                            && !p.retain =>
                    {
                        announce(&c)
                    }
                    Ok(Event::Outgoing(rumqttc::Outgoing::Disconnect)) => {
                        // Let the broker read everything before: wait for its close.
                        while ev.poll().await.is_ok() {}
                        return;
                    }
                    Ok(_) => {}
                    // Said as a droid's connection says it (issue 37 point 7), never the
                    // end of the bridge.
                    Err(_) if takeovers.lost(tokio::time::Instant::now()) => {
                        eprintln!(
                            "droidctl: bridge {bid}: the broker ended the connection right \
                             after accepting it, {} times in a row: most likely another client \
                             is connected with the same client id ({cid}); give each bridge its \
                             own --client-id (or leave it out: the default is unique). Trying \
                             again in {} s",
                            super::takeover::TAKEOVERS,
                            super::takeover::TAKEOVER_BACKOFF.as_secs()
                        );
                        tokio::time::sleep(super::takeover::TAKEOVER_BACKOFF).await;
                    }
                    Err(_) => tokio::time::sleep(Duration::from_secs(1)).await,
                }
            }
        });
        Ok(Presence {
            client,
            prefix: s.prefix.clone(),
            id,
            homeassistant,
            task,
        })
    }

    /// The bridge's `hello` anew (a droid's telemetry rate changed).
    pub fn hello(&self, hello: String) {
        let _ = self.client.try_publish(
            hello_topic(&self.prefix, &self.id),
            QoS::AtLeastOnce,
            true,
            hello,
        );
    }

    /// A clean end: the `hello` cleared, offline said, the Home Assistant device removed
    /// only when `remove` (else kept: availability says offline), then disconnected.
    pub async fn goodbye(self, remove: bool) {
        let mut gone = vec![hello_topic(&self.prefix, &self.id)];
        if let (true, Some(h)) = (remove, &self.homeassistant) {
            gone.extend(
                super::homeassistant::bridge_configs(h, &self.prefix, &self.id)
                    .into_iter()
                    .map(|(t, _)| t),
            );
        }
        for t in gone {
            let _ = self
                .client
                .try_publish(t, QoS::AtLeastOnce, true, Vec::new());
        }
        let _ = self.client.try_publish(
            state_topic(&self.prefix, &self.id),
            QoS::AtLeastOnce,
            true,
            state_json(&self.id, false),
        );
        let _ = self.client.try_disconnect();
        let mut task = self.task;
        if tokio::time::timeout(Duration::from_secs(2), &mut task)
            .await
            .is_err()
        {
            task.abort();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_states_that_are_not_offline_are_live() {
        let mut l = Live::default();
        l.read(
            "droidctl",
            "droidctl/SB-0001/state",
            br#"{"v":1,"type":"link","droid":"SB-0001","state":"connected","ready":true}"#,
        );
        l.read(
            "droidctl",
            "droidctl/D2-0001/state",
            br#"{"v":1,"type":"link","droid":"D2-0001","state":"offline","ready":false}"#,
        );
        l.read(
            "droidctl",
            "droidctl/bridge/pi-1/state",
            state_json("pi-1", true).as_bytes(),
        );
        l.read(
            "droidctl",
            "droidctl/bridge/pi-2/state",
            state_json("pi-2", false).as_bytes(),
        );
        l.read("droidctl", "droidctl/X/state", b"not json");
        l.read("droidctl", "other/Y/state", br#"{"state":"connected"}"#);
        assert_eq!(l.droids, HashSet::from(["sb-0001".to_string()]));
        assert_eq!(l.bridges, HashSet::from(["pi-1".to_string()]));
        assert_eq!(distinct("SB-0001", &l.droids), "SB-0001-2");
        assert_eq!(distinct("D2-0001", &l.droids), "D2-0001");
        let mut taken = l.droids.clone();
        taken.insert("sb-0001-2".into());
        assert_eq!(distinct("SB-0001", &taken), "SB-0001-3");
    }
}
