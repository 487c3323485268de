//! The bridge through a real broker (issue 20 point 5): four simulated droids (R2-D2, BB-8,
//! BB-9E, Robi 42) behind `droidctl bridge --mqtt`, in this process as the command runs it,
//! and mosquitto on a free loopback port. An outside MQTT client (rumqttc, another
//! connection) publishes a drive to each droid five times a second, each with a new speed, and
//! subscribes to every droid's telemetry. Measured: the time from a drive's publish to its
//! write on the droid's link (the session's packet log), p50/p99 per model; the telemetry
//! the client receives per droid per second at the asked rate; this process's CPU
//! (droids, bridge, client; the broker is another process).
//!
//! `cargo bench --bench bridge` (Linux, needs `mosquitto`); `BRIDGE_BENCH_SECS` sets how long
//! (default 20), `BRIDGE_BENCH_HZ` the telemetry rate asked (default 100, the most). Wall-clock
//! figures on a shared machine: run it a few times.

#[cfg(not(target_os = "linux"))]
fn main() {
    eprintln!("the bridge benchmark runs on Linux only");
}

#[cfg(target_os = "linux")]
fn main() {
    linux::main();
}

#[cfg(target_os = "linux")]
#[path = "common/stats.rs"]
mod stats;

#[cfg(target_os = "linux")]
mod linux {
    use super::stats::{clock_ticks_per_s, cpu_ticks, percentile};
    use droidctl::bridge::mqtt::{BrokerUrl, MqttSettings};
    use droidctl::bridge::{Bridge, Settings, topic_name};
    use droidctl::fleet::Fleet;
    use droidctl::model::Model;
    use droidctl::session::{Direction, LinkState, LogItem};
    use rumqttc::{AsyncClient, Event, MqttOptions, Packet as MqttPacket, QoS};
    use std::collections::HashMap;
    use std::process::{Command, Stdio};
    use std::sync::{Arc, Mutex};
    use std::time::Duration;
    use tokio::time::{Instant, sleep};

    use droidctl::family::drive_speed;

    fn mosquitto() -> Option<std::path::PathBuf> {
        [
            "/usr/sbin/mosquitto",
            "/usr/bin/mosquitto",
            "/usr/local/sbin/mosquitto",
        ]
        .iter()
        .map(std::path::PathBuf::from)
        .find(|p| p.is_file())
    }

    pub fn main() {
        let secs: u64 = std::env::var("BRIDGE_BENCH_SECS")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(20);
        let hz: u16 = std::env::var("BRIDGE_BENCH_HZ")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(100)
            .clamp(1, 100);
        let Some(broker) = mosquitto() else {
            eprintln!("bridge benchmark: SKIPPED: mosquitto is not installed");
            return;
        };
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .and_then(|l| l.local_addr())
            .map(|a| a.port())
            .expect("a free port");
        let dir =
            std::env::temp_dir().join(format!("droidctl-bridge-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let conf = dir.join("mosquitto.conf");
        std::fs::write(
            &conf,
            format!(
                "user root\npersistence false\nlistener {port} 127.0.0.1\nallow_anonymous true\n"
            ),
        )
        .unwrap();
        let mut child = Command::new(broker)
            .arg("-c")
            .arg(&conf)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("start mosquitto");
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            std::thread::sleep(Duration::from_millis(20));
        }
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        rt.block_on(bench(port, secs, hz));
        let _ = child.kill();
        let _ = child.wait();
        let _ = std::fs::remove_dir_all(&dir);
    }

    type Writes = Arc<Mutex<Vec<(Instant, u8)>>>;

    async fn bench(port: u16, secs: u64, hz: u16) {
        let models = [Model::R2D2, Model::BB8, Model::BB9E, Model::Robi42];
        let config = droidctl::config::Config::defaults();
        let specs = droidctl::cli::fleet::simulated(&models)
            .into_iter()
            .map(|f| {
                let s = droidctl::cli::fleet::session_config(f.model, &config, true);
                f.into_spec(s)
            })
            .collect();
        let fleet = Fleet::start(specs);
        let mut writes: Vec<Writes> = Vec::new();
        for m in fleet.members() {
            let w: Writes = Arc::default();
            let sink = w.clone();
            let mut log = m.session.subscribe_log();
            tokio::spawn(async move {
                while let Ok(e) = log.recv().await {
                    if e.dir == Direction::Out
                        && let LogItem::Packet { packet, .. } = &e.item
                        && let Some(s) = drive_speed(packet)
                    {
                        sink.lock().unwrap().push((Instant::now(), s));
                    }
                }
            });
            writes.push(w);
        }
        for i in 0..fleet.len() {
            let mut st = fleet.link_state(i).unwrap();
            let _ = st.wait_for(|s| *s == LinkState::Connected).await;
        }
        // The connect setup (R2's tripod, streaming).
        sleep(Duration::from_secs(2)).await;
        let setups = models
            .iter()
            .map(|m| droidctl::family::setup::from_config(*m, &config).0)
            .collect();
        let settings = Settings {
            telemetry_hz: hz,
            ..Settings::default()
        };
        let (bridge, rx) = Bridge::start(fleet.clone(), setups, settings);
        let url: BrokerUrl = format!("mqtt://127.0.0.1:{port}").parse().unwrap();
        let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
        let mqtt = MqttSettings {
            url,
            qos: 0,
            prefix: "droidctl".into(),
            client_id: "bench-bridge".into(),
            bridge_id: "bench".into(),
            keepalive: Duration::from_secs(5),
            username: None,
            password: None,
            ca_pem: None,
        };
        let running = tokio::spawn(droidctl::bridge::mqtt::run(
            bridge.clone(),
            rx,
            mqtt,
            Duration::from_secs(10),
            async {
                let _ = stop_rx.await;
            },
        ));
        // The outside client.
        let topics: Vec<String> = fleet.names().iter().map(|n| topic_name(n)).collect();
        let mut o = MqttOptions::new("bench-client", "127.0.0.1", port);
        o.set_max_packet_size(1 << 16, 1 << 16);
        let (client, mut eventloop) = AsyncClient::new(o, 4096);
        // A control client sends each command at once (BRIDGE_BENCH_NAGLE=1: as rumqttc does
        // by default, Nagle's algorithm holding a command until the broker's next segment).
        let mut net = rumqttc::NetworkOptions::new();
        net.set_tcp_nodelay(std::env::var_os("BRIDGE_BENCH_NAGLE").is_none());
        eventloop.set_network_options(net);
        client
            .subscribe("droidctl/+/telemetry", QoS::AtMostOnce)
            .await
            .unwrap();
        let counts: Arc<Mutex<HashMap<String, u64>>> = Arc::default();
        let counting = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let (c2, on) = (counts.clone(), counting.clone());
        let receiver = tokio::spawn(async move {
            loop {
                match eventloop.poll().await {
                    Ok(Event::Incoming(MqttPacket::Publish(p))) => {
                        if on.load(std::sync::atomic::Ordering::Relaxed) {
                            *c2.lock().unwrap().entry(p.topic.clone()).or_default() += 1;
                        }
                    }
                    Ok(_) => {}
                    Err(_) => sleep(Duration::from_millis(100)).await,
                }
            }
        });
        sleep(Duration::from_secs(2)).await;
        // Drive every droid five times a second, a new speed each time; count telemetry.
        let (c0, w0) = (cpu_ticks(), Instant::now());
        counting.store(true, std::sync::atomic::Ordering::Relaxed);
        let mut sent: Vec<(usize, u8, Instant)> = Vec::new();
        let mut k: u8 = 20;
        let mut tick = tokio::time::interval(Duration::from_millis(200));
        let end = Instant::now() + Duration::from_secs(secs);
        while Instant::now() < end {
            tick.tick().await;
            k = if k >= 250 { 20 } else { k + 1 };
            for (i, t) in topics.iter().enumerate() {
                let heading = (k as u32 * 37) % 360;
                let cmd = format!(r#"{{"v":1,"cmd":"drive","speed":{k},"heading":{heading}}}"#);
                sent.push((i, k, Instant::now()));
                client
                    .publish(format!("droidctl/{t}/cmd"), QoS::AtMostOnce, false, cmd)
                    .await
                    .unwrap();
            }
        }
        counting.store(false, std::sync::atomic::Ordering::Relaxed);
        let (c1, w1) = (cpu_ticks(), Instant::now());
        let wall = (w1 - w0).as_secs_f64();
        let cpu = (c1 - c0) as f64 / clock_ticks_per_s() / wall * 100.0;
        let _ = stop_tx.send(());
        let _ = running.await;
        bridge.shutdown().await;
        receiver.abort();

        println!(
            "bridge through mosquitto: 4 simulated droids, {secs} s, drives at 5/s per droid (QoS 0), telemetry asked at {hz}/s"
        );
        let mut all = Vec::new();
        for (i, m) in fleet.members().iter().enumerate() {
            let w = writes[i].lock().unwrap().clone();
            let mut lat: Vec<f64> = Vec::new();
            let mut missed = 0;
            for (j, &(d, speed, at)) in sent.iter().enumerate() {
                if d != i {
                    continue;
                }
                let next = sent[j + 1..]
                    .iter()
                    .find(|(d2, _, _)| *d2 == i)
                    .map(|(_, _, t)| *t);
                match w.iter().find(|(t, s)| {
                    *t >= at && *s == speed && next.is_none_or(|n| *t < n + Duration::from_secs(1))
                }) {
                    Some((t, _)) => lat.push((*t - at).as_secs_f64() * 1000.0),
                    None => missed += 1,
                }
            }
            lat.sort_by(f64::total_cmp);
            all.extend_from_slice(&lat);
            let got = counts
                .lock()
                .unwrap()
                .get(&format!("droidctl/{}/telemetry", topics[i]))
                .copied()
                .unwrap_or(0);
            println!(
                "  {:<8} {:<8} publish → link write: p50 {:6.1} ms, p99 {:6.1} ms ({} drives, {missed} not written: superseded); telemetry received {:6.1}/s",
                m.name,
                m.model.id(),
                percentile(&lat, 0.5),
                percentile(&lat, 0.99),
                lat.len(),
                got as f64 / wall
            );
        }
        all.sort_by(f64::total_cmp);
        let total: u64 = counts.lock().unwrap().values().sum();
        println!(
            "  all      publish → link write: p50 {:6.1} ms, p99 {:6.1} ms; telemetry received {:.0}/s in all; objects dropped by the bridge: {}",
            percentile(&all, 0.5),
            percentile(&all, 0.99),
            total as f64 / wall,
            bridge.dropped()
        );
        println!("  this process's CPU (droids, bridge, client): {cpu:.1} % of one core");
    }
}
