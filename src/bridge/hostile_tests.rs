//! Issue 37: under random sequences of hostile broker input — SUBSCRIBEs of many filters,
//! huge retained messages, idle and never-reading clients, takeovers of the bridge's own id
//! — a drive that is not refreshed is stopped within the command timeout + 100 ms.
//!
//! In real time, as the CLI runs it: the droid's session and the bridge on a 2-worker
//! runtime, droidctl's broker on a runtime thread of its own ([`super::thread`]), the
//! hostile clients on OS threads over loopback (port 0). Paused time could not show this:
//! a busy broker on the droids' runtime would stop the paused clock too.

use super::broker::wire::encode;
use super::broker::{self, Access, OwnIds};
use super::tests::rig;
use super::thread::RuntimeThread;
use crate::model::Model;
use proptest::prelude::*;
use rumqttc::mqttbytes::QoS;
use rumqttc::mqttbytes::v4::{Connect, Packet, Publish, Subscribe, SubscribeFilter};
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::Duration;

const TIMEOUT_MS: u64 = 300;

#[derive(Debug, Clone)]
enum Attack {
    /// One SUBSCRIBE of this many distinct filters.
    Subscribe(usize),
    /// This many retained messages of this many KiB.
    Retained(usize, usize),
    /// This many connections that send CONNECT (keep-alive 0) and nothing more.
    Idle(usize),
    /// A subscriber to `#` that never reads, and this many 200 KiB messages.
    NeverReading(usize),
    /// Connections taking the bridge's own client id, this many times.
    Takeover(usize),
}

fn attack() -> impl Strategy<Value = Attack> {
    prop_oneof![
        (1usize..150_000).prop_map(Attack::Subscribe),
        (1usize..300, 1usize..4200).prop_map(|(n, k)| Attack::Retained(n, k)),
        (1usize..255).prop_map(Attack::Idle),
        (1usize..100).prop_map(Attack::NeverReading),
        (1usize..20).prop_map(Attack::Takeover),
    ]
}

fn client(addr: SocketAddr, id: &str, keep_alive: u16) -> Option<TcpStream> {
    let mut s = TcpStream::connect(addr).ok()?;
    s.set_read_timeout(Some(Duration::from_secs(2))).ok()?;
    let mut c = Connect::new(id);
    c.keep_alive = keep_alive;
    s.write_all(&encode(&Packet::Connect(c))).ok()?;
    let mut ack = [0u8; 4];
    s.read_exact(&mut ack).ok()?;
    Some(s)
}

/// Carry `a` out against the broker at `addr` (blocking; errors are the broker refusing).
fn run(a: &Attack, addr: SocketAddr) -> Vec<TcpStream> {
    let mut held = Vec::new();
    match *a {
        Attack::Subscribe(n) => {
            if let Some(mut s) = client(addr, "subscribe", 60) {
                let f = (0..n).map(|i| SubscribeFilter::new(format!("fl/{i:08}"), QoS::AtMostOnce));
                let _ = s.write_all(&encode(&Packet::Subscribe(Subscribe::new_many(f))));
                held.push(s);
            }
        }
        Attack::Retained(n, kib) => {
            if let Some(mut s) = client(addr, "retained", 60) {
                for i in 0..n {
                    let mut p =
                        Publish::new(format!("r/{i}"), QoS::AtMostOnce, vec![7u8; kib << 10]);
                    p.retain = true;
                    if s.write_all(&encode(&Packet::Publish(p))).is_err() {
                        break;
                    }
                }
                held.push(s);
            }
        }
        Attack::Idle(n) => held.extend((0..n).filter_map(|i| client(addr, &format!("i{i}"), 0))),
        Attack::NeverReading(n) => {
            if let Some(mut slow) = client(addr, "slow", 60) {
                let s = Subscribe::new("#", QoS::AtMostOnce);
                let _ = slow.write_all(&encode(&Packet::Subscribe(s)));
                held.push(slow);
            }
            if let Some(mut s) = client(addr, "pub", 60) {
                for _ in 0..n {
                    let p = Publish::new("live", QoS::AtMostOnce, vec![0u8; 200 << 10]);
                    if s.write_all(&encode(&Packet::Publish(p))).is_err() {
                        break;
                    }
                }
            }
        }
        Attack::Takeover(n) => {
            held.extend((0..n).filter_map(|_| client(addr, "bridge-0-BB-0001", 60)))
        }
    }
    held
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    #[test]
    fn a_drive_not_refreshed_stops_on_time_whatever_the_broker_is_sent(
        attacks in proptest::collection::vec(attack(), 1..4)
    ) {
        let net = RuntimeThread::start("droidctl-test-broker").unwrap();
        let access = Access { login: None, own: Some(OwnIds::new("bridge-")) };
        let b = broker::start_on(net.handle(), "127.0.0.1:0".parse().unwrap(), access, None)
            .unwrap();
        let addr = b.addr();
        let main = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        let (lateness, writes) = main.block_on(async {
            let r = rig(&[Model::BB8], TIMEOUT_MS).await;
            let hostile = std::thread::spawn(move || {
                attacks.iter().flat_map(|a| run(a, addr)).collect::<Vec<_>>()
            });
            // Let the attack get going, then one drive, never refreshed.
            tokio::time::sleep(Duration::from_millis(20)).await;
            let t0 = r.now();
            r.send(r#"{"v":1,"cmd":"drive","speed":120,"heading":90}"#);
            tokio::time::sleep(Duration::from_millis(TIMEOUT_MS + 500)).await;
            let writes = r.writes(0);
            let stop = writes
                .iter()
                .find(|(at, s)| *at > t0 && *s == 0 && writes.iter().any(|(d, s)| d < at && *d >= t0 && *s > 0))
                .map(|(at, _)| *at);
            r.bridge.shutdown().await;
            drop(hostile);
            (stop.map(|at| at.saturating_sub(t0 + Duration::from_millis(TIMEOUT_MS))), writes)
        });
        let late = lateness.unwrap_or_else(|| panic!("never stopped: {writes:?}"));
        prop_assert!(late <= Duration::from_millis(100), "stopped {late:?} late: {writes:?}");
        drop(main);
        drop(b);
    }
}
