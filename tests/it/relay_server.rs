//! `droidctl serve` in-process, over loopback TCP, with simulated droids at the GATT level:
//! droidctl's own relay link against it, ownership of droids, stopping and releasing a droid
//! whose client goes, and hostile or broken clients (unknown opcodes, oversized lengths,
//! invalid text, truncated and dribbled requests, slow readers, connection floods), then a
//! soak of several clients with one killed mid-drive.
//!
//! Real time (TCP and paused clocks do not mix); every wait is bounded.

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::family::v2::gatt::{V2_ANTI_DOS, V2_API, V2_UNLOCK};
use droidctl::family::{self, Codec};
use droidctl::link::remote::{RelayAddr, RemoteLink, RemoteSelector, select};
use droidctl::model::Model;
use droidctl::protocol::relay::{Expect, Limits, Reply, ReplyDecoder, Request};
use droidctl::relay::backend::GattBackend;
use droidctl::relay::server::{self, EventSink, ServerConfig, ServerEvent};
use droidctl::relay::sim_backend::SimBackend;
use droidctl::session::{self, LinkState, SessionConfig, Slot};
use droidctl::sim::gatt::GattFaults;
use droidctl::units::Heading;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::sync::oneshot;
use tokio::time::{Instant, sleep, timeout};

const WAIT: Duration = Duration::from_secs(5);

struct Relay {
    addr: SocketAddr,
    sim: Arc<SimBackend>,
    events: Arc<Mutex<Vec<ServerEvent>>>,
    stop: Option<oneshot::Sender<()>>,
    done: tokio::task::JoinHandle<()>,
}

impl Relay {
    async fn start(models: &[Model], cfg: ServerConfig) -> Relay {
        Relay::start_with(models, cfg, |sim| sim).await
    }

    /// A relay whose backend is `wrap` around the simulated droids.
    async fn start_with(
        models: &[Model],
        cfg: ServerConfig,
        wrap: impl FnOnce(Arc<SimBackend>) -> Arc<dyn GattBackend>,
    ) -> Relay {
        let sim = Arc::new(SimBackend::new(models, GattFaults::none()));
        let events: Arc<Mutex<Vec<ServerEvent>>> = Arc::default();
        let sink: EventSink = {
            let events = events.clone();
            Arc::new(move |e: &ServerEvent| {
                let mut v = events.lock().unwrap();
                if v.len() < 100_000 {
                    v.push(e.clone());
                }
            })
        };
        let listener = server::bind("127.0.0.1:0".parse().unwrap(), &cfg)
            .await
            .unwrap();
        let addr = listener.local_addr().unwrap();
        let (stop, stopped) = oneshot::channel::<()>();
        let backend = wrap(sim.clone());
        let done = tokio::spawn(server::serve(listener, backend, cfg, sink, async {
            let _ = stopped.await;
        }));
        Relay {
            addr,
            sim,
            events,
            stop: Some(stop),
            done,
        }
    }

    fn relay_addr(&self) -> RelayAddr {
        RelayAddr {
            host: "127.0.0.1".into(),
            port: self.addr.port(),
        }
    }

    fn address(&self, i: usize) -> String {
        self.sim.devices()[i].1.clone()
    }

    fn events(&self) -> Vec<ServerEvent> {
        self.events.lock().unwrap().clone()
    }

    fn any(&self, f: impl Fn(&ServerEvent) -> bool) -> bool {
        self.events.lock().unwrap().iter().any(f)
    }

    async fn wait_event(&self, what: &str, f: impl Fn(&ServerEvent) -> bool) {
        let deadline = Instant::now() + WAIT;
        while !self.any(&f) {
            assert!(
                Instant::now() < deadline,
                "no {what} event; events: {:#?}",
                self.events()
            );
            sleep(Duration::from_millis(10)).await;
        }
    }

    fn speed(&self, i: usize) -> f32 {
        self.sim.state(&self.address(i)).unwrap().velocity_cm_s
    }

    async fn stop(mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        timeout(Duration::from_secs(15), &mut self.done)
            .await
            .expect("the server stops")
            .unwrap();
    }
}

fn cfg() -> ServerConfig {
    ServerConfig::default()
}

/// A server on a free loopback port that runs until aborted.
async fn serve_forever(
    backend: Arc<dyn GattBackend>,
    cfg: ServerConfig,
    sink: EventSink,
) -> (std::net::SocketAddr, tokio::task::JoinHandle<()>) {
    let listener = server::bind("127.0.0.1:0".parse().unwrap(), &cfg)
        .await
        .unwrap();
    let addr = listener.local_addr().unwrap();
    let server = tokio::spawn(server::serve(
        listener,
        backend,
        cfg,
        sink,
        std::future::pending(),
    ));
    (addr, server)
}

/// Wait until the fake droid's connection is gone, and return everything written to `ch`.
async fn written_after_release(
    droid: &droidctl::link::ble::fake::FakePeripheral,
    ch: droidctl::gatt::GattUuid,
) -> Vec<u8> {
    let deadline = Instant::now() + WAIT;
    while droid.is_connected() {
        assert!(Instant::now() < deadline, "still connected");
        sleep(Duration::from_millis(10)).await;
    }
    droid
        .writes_to(ch)
        .into_iter()
        .flat_map(|(_, d)| d)
        .collect()
}

/// A client speaking the protocol by hand.
struct Raw {
    s: TcpStream,
    dec: ReplyDecoder,
    seq: u8,
    data: Vec<(String, Vec<u8>)>,
    codec: Box<dyn Codec>,
}

impl Raw {
    async fn connect(addr: SocketAddr) -> Raw {
        Raw {
            s: TcpStream::connect(addr).await.unwrap(),
            dec: ReplyDecoder::new(Limits::default()),
            seq: 0,
            data: Vec::new(),
            codec: family::for_model(Model::BB9E).codec(),
        }
    }

    async fn send_raw(&mut self, bytes: &[u8]) {
        self.s.write_all(bytes).await.unwrap();
    }

    async fn send(&mut self, r: &Request) {
        if let Some(e) = r.expect() {
            self.dec.expect(e);
        }
        let b = r.to_bytes().unwrap();
        self.send_raw(&b).await;
    }

    /// The next reply that is not ON_DATA (those are kept); `None` at the end of the stream.
    async fn reply(&mut self) -> Option<Reply> {
        let deadline = Instant::now() + WAIT;
        let mut buf = [0u8; 4096];
        loop {
            while let Some(r) = self.dec.next() {
                match r {
                    Ok(Reply::Data {
                        characteristic,
                        data,
                    }) => self.data.push((characteristic, data)),
                    Ok(r) => return Some(r),
                    Err(e) => panic!("bad reply: {e}"),
                }
            }
            let left = deadline.saturating_duration_since(Instant::now());
            match timeout(left, self.s.read(&mut buf)).await {
                Ok(Ok(0)) | Ok(Err(_)) => return None,
                Ok(Ok(n)) => self.dec.push(&buf[..n]),
                Err(_) => panic!("no reply within {WAIT:?}"),
            }
        }
    }

    /// A request with a seq; its OK or ERROR message.
    async fn call(&mut self, make: impl FnOnce(u8) -> Request) -> Result<(), String> {
        let seq = self.seq;
        self.seq = self.seq.wrapping_add(1);
        self.send(&make(seq)).await;
        match self.reply().await {
            Some(Reply::Ok { seq: s }) if s == seq => Ok(()),
            Some(Reply::Error {
                message,
                seq: Some(s),
            }) if s == seq => Err(message),
            other => panic!("unexpected reply to seq {seq}: {other:?}"),
        }
    }

    async fn init(&mut self, address: &str) -> Result<(), String> {
        let address = address.to_string();
        self.call(|seq| Request::Init { seq, address }).await
    }

    async fn write(&mut self, ch: &str, data: &[u8]) -> Result<(), String> {
        let (characteristic, data) = (ch.to_string(), data.to_vec());
        self.call(|seq| Request::Write {
            seq,
            characteristic,
            data,
        })
        .await
    }

    /// INIT, the v2 unlock, notifications on the API characteristic, and the wake (a BB-9E:
    /// an R2 would need its tripod stance before it rolls).
    async fn v2_ready(&mut self, address: &str) {
        self.init(address).await.unwrap();
        self.write(&V2_ANTI_DOS.to_string(), V2_UNLOCK)
            .await
            .unwrap();
        let ch = V2_API.to_string();
        self.call(|seq| Request::SetCallback {
            seq,
            characteristic: ch,
        })
        .await
        .unwrap();
        // Wake it, as spherov2's toys do first.
        let wake = family::for_model(Model::BB9E).wake().unwrap();
        let (bytes, _) = self.codec.encode(&wake, 0xf0, true);
        for chunk in bytes.chunks(20) {
            self.write(&V2_API.to_string(), chunk).await.unwrap();
        }
    }

    /// Roll at `speed` toward 0°, in 20-byte writes as a BLE client would.
    async fn drive(&mut self, speed: u8) {
        let f = family::for_model(Model::BB9E);
        let cmd = f.drive(speed, Heading::new(0).unwrap(), false);
        let (bytes, _) = self.codec.encode(&cmd, self.seq, false);
        for chunk in bytes.chunks(20) {
            self.write(&V2_API.to_string(), chunk).await.unwrap();
        }
    }

    /// The stream ends (the server closed it) within the wait.
    async fn closed(&mut self) -> bool {
        let mut buf = [0u8; 4096];
        let deadline = Instant::now() + WAIT;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match timeout(left, self.s.read(&mut buf)).await {
                Ok(Ok(0)) | Ok(Err(_)) => return true,
                Ok(Ok(n)) => self.dec.push(&buf[..n]),
                Err(_) => return false,
            }
        }
    }
}

async fn wait_until(what: &str, mut f: impl FnMut() -> bool) {
    let deadline = Instant::now() + WAIT;
    while !f() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        sleep(Duration::from_millis(10)).await;
    }
}

fn session_config(model: Model) -> SessionConfig {
    SessionConfig {
        family: model.protocol(),
        pacing: Duration::from_millis(20),
        setup: connect_setup(model, &SetupOptions::default()),
        ..SessionConfig::default()
    }
}

// ---------------------------------------------------------------------------------------------
// droidctl's relay link against droidctl's relay.
// ---------------------------------------------------------------------------------------------

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn remote_link_drives_a_simulated_droid() {
    let relay = Relay::start(&[Model::R2D2, Model::BB8], cfg()).await;
    let sel = RemoteSelector {
        name: Some("D2-0001".into()),
        address: None,
        scan_timeout: Duration::from_secs(1),
    };
    let link = select(&relay.relay_addr(), &sel, droidctl::family::gatt_profile)
        .await
        .unwrap();
    assert_eq!(link.model(), Model::R2D2);
    assert!(link.address().eq_ignore_ascii_case(&relay.address(0)));
    let session = session::start(Box::new(link), session_config(Model::R2D2));
    let f = family::for_model(Model::R2D2);
    // The wake answers through the relay: the handshake unlocked the droid and the
    // notifications come back.
    let wake = timeout(WAIT, session.request(f.wake().unwrap()))
        .await
        .unwrap();
    assert!(wake.is_ok(), "{wake:?}");
    assert_eq!(session.state(), LinkState::Connected);
    session.set(Slot::Drive, f.drive(120, Heading::new(90).unwrap(), false));
    wait_until("the droid rolls toward 90°", || {
        let s = relay.sim.state(&relay.address(0)).unwrap();
        s.velocity_cm_s > 20.0 && (s.yaw_deg - 90.0).abs() < 2.0
    })
    .await;
    // Sensor streaming (the connect setup) arrives as notifications.
    let mut events = session.subscribe();
    let got = timeout(WAIT, async {
        loop {
            if let Ok(droidctl::session::SessionEvent::Notification(_)) = events.recv().await {
                return;
            }
        }
    })
    .await;
    assert!(got.is_ok(), "no notification through the relay");
    session.shutdown_stopped(Vec::new()).await;
    wait_until("the droid stops", || relay.speed(0).abs() < 0.5).await;
    relay
        .wait_event("release", |e| {
            matches!(e, ServerEvent::DroidReleased { .. })
        })
        .await;
    assert!(!relay.sim.connected(&relay.address(0)));
    let stats = session.stats();
    assert_eq!(stats.reconnects, 0);
    relay.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn remote_link_reconnects_when_the_relay_drops_the_droid() {
    // The droid drops its link after 1 s: the relay closes the client's connection, the
    // session reconnects with backoff through a new INIT and handshake.
    let mut faults = GattFaults::none();
    faults.add("disconnect-after=1").unwrap();
    let sim = Arc::new(SimBackend::new(&[Model::R2D2], faults));
    let backend: Arc<dyn GattBackend> = sim.clone();
    let (addr, server) = serve_forever(backend, cfg(), Arc::new(|_| {})).await;
    let port = addr.port();
    let relay = RelayAddr {
        host: "127.0.0.1".into(),
        port,
    };
    let link = RemoteLink::new(
        relay,
        sim.devices()[0].1.clone(),
        "D2-0001",
        Model::R2D2,
        droidctl::family::gatt_profile(Model::R2D2),
    );
    let session = session::start(Box::new(link), session_config(Model::R2D2));
    let mut states = session.watch_state();
    let saw_reconnecting = timeout(Duration::from_secs(5), async {
        loop {
            if matches!(*states.borrow_and_update(), LinkState::Reconnecting { .. }) {
                return;
            }
            states.changed().await.unwrap();
        }
    })
    .await;
    assert!(saw_reconnecting.is_ok(), "no reconnect after the drop");
    wait_until("reconnected", || session.stats().reconnects >= 1).await;
    let f = family::for_model(Model::R2D2);
    let wake = timeout(WAIT, session.request(f.wake().unwrap()))
        .await
        .unwrap();
    assert!(wake.is_ok(), "{wake:?}");
    session.shutdown(Vec::new()).await;
    server.abort();
}

// ---------------------------------------------------------------------------------------------
// Ownership, release and stop.
// ---------------------------------------------------------------------------------------------

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_droid_belongs_to_one_client_at_a_time() {
    let relay = Relay::start(&[Model::R2D2], cfg()).await;
    let addr = relay.address(0);
    let mut a = Raw::connect(relay.addr).await;
    a.init(&addr).await.unwrap();
    let a_port = a.s.local_addr().unwrap().to_string();
    let mut b = Raw::connect(relay.addr).await;
    let err = b.init(&addr).await.unwrap_err();
    assert!(err.contains("in use by client 1"), "{err}");
    assert!(err.contains(&a_port), "{err} should name {a_port}");
    // Case does not get around it.
    let err = b.init(&addr.to_lowercase()).await.unwrap_err();
    assert!(err.contains("in use"), "{err}");
    // One droid per connection.
    let err = a.init(&addr).await.unwrap_err();
    assert!(err.contains("holds"), "{err}");
    // Once A says END, B gets it.
    a.send(&Request::End).await;
    assert!(a.closed().await);
    relay
        .wait_event("release", |e| {
            matches!(e, ServerEvent::DroidReleased { .. })
        })
        .await;
    b.init(&addr).await.unwrap();
    relay.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_that_disconnects_mid_drive_leaves_its_droid_stopped() {
    let relay = Relay::start(&[Model::BB9E], cfg()).await;
    let addr = relay.address(0);
    let mut a = Raw::connect(relay.addr).await;
    a.v2_ready(&addr).await;
    a.drive(150).await;
    wait_until("rolling", || relay.speed(0) > 50.0).await;
    drop(a);
    // Well before the droid's own 2 s motion timeout.
    let t0 = Instant::now();
    wait_until("stopped", || relay.speed(0).abs() < 0.5).await;
    assert!(
        t0.elapsed() < Duration::from_millis(1500),
        "{:?}",
        t0.elapsed()
    );
    relay
        .wait_event("release with stop", |e| {
            matches!(e, ServerEvent::DroidReleased { stopped: true, .. })
        })
        .await;
    assert!(!relay.sim.connected(&addr));
    // Released: another client may take it.
    let mut b = Raw::connect(relay.addr).await;
    b.init(&addr).await.unwrap();
    relay.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_silent_client_is_dropped_and_its_droid_stopped() {
    let relay = Relay::start(
        &[Model::BB9E],
        ServerConfig {
            idle_timeout: Some(Duration::from_millis(400)),
            ..cfg()
        },
    )
    .await;
    let addr = relay.address(0);
    let mut a = Raw::connect(relay.addr).await;
    a.v2_ready(&addr).await;
    a.drive(150).await;
    wait_until("rolling", || relay.speed(0) > 50.0).await;
    // Silent, connection open.
    assert!(a.closed().await, "the idle client was not closed");
    wait_until("stopped", || relay.speed(0).abs() < 0.5).await;
    relay
        .wait_event(
            "idle close",
            |e| matches!(e, ServerEvent::ClientClosed { reason, .. } if reason.contains("silent")),
        )
        .await;
    assert!(relay.any(|e| matches!(e, ServerEvent::DroidReleased { stopped: true, .. })));
    relay.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stopping_the_server_stops_every_droid() {
    let relay = Relay::start(&[Model::BB9E, Model::BB9E], cfg()).await;
    let mut a = Raw::connect(relay.addr).await;
    a.v2_ready(&relay.address(0)).await;
    a.drive(150).await;
    let mut b = Raw::connect(relay.addr).await;
    b.v2_ready(&relay.address(1)).await;
    b.drive(150).await;
    wait_until("both roll", || {
        relay.speed(0) > 50.0 && relay.speed(1) > 50.0
    })
    .await;
    let sim = relay.sim.clone();
    let (a0, a1) = (relay.address(0), relay.address(1));
    let t0 = Instant::now();
    relay.stop().await;
    assert!(a.closed().await && b.closed().await);
    wait_until("both stopped", || {
        sim.state(&a0).unwrap().velocity_cm_s.abs() < 0.5
            && sim.state(&a1).unwrap().velocity_cm_s.abs() < 0.5
    })
    .await;
    // By the relay's stop, not by the droids' own 2 s motion timeout.
    assert!(
        t0.elapsed() < Duration::from_millis(1200),
        "{:?}",
        t0.elapsed()
    );
}

// ---------------------------------------------------------------------------------------------
// Hostile and broken clients: each answered or closed, logged, and nobody else hurt.
// ---------------------------------------------------------------------------------------------

/// A second client that must keep working whatever the first does.
async fn bystander_works(relay: &Relay) {
    let mut c = Raw::connect(relay.addr).await;
    c.send(&Request::Scan { timeout: 0.1 }).await;
    match c.reply().await {
        Some(Reply::Devices(d)) => assert!(!d.is_empty()),
        other => panic!("scan: {other:?}"),
    }
}

fn protocol_error(relay: &Relay, needle: &str) -> bool {
    relay.any(|e| matches!(e, ServerEvent::ProtocolError { error, .. } if error.contains(needle)))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn unknown_opcode_is_answered_and_closed() {
    let relay = Relay::start(&[Model::R2D2], cfg()).await;
    let mut c = Raw::connect(relay.addr).await;
    c.dec.expect(Expect::Scan); // an ERROR without seq
    c.send_raw(&[0x42, 1, 2, 3]).await;
    match c.reply().await {
        Some(Reply::Error { message, .. }) => assert!(message.contains("0x42"), "{message}"),
        other => panic!("{other:?}"),
    }
    assert!(c.closed().await);
    assert!(protocol_error(&relay, "unknown request opcode 0x42"));
    bystander_works(&relay).await;
    relay.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn oversized_lengths_are_refused_before_the_bytes() {
    let relay = Relay::start(&[Model::R2D2], cfg()).await;
    // A WRITE claiming 65 535 bytes of data: refused at once (the bytes never come), with
    // its seq, then closed.
    let mut c = Raw::connect(relay.addr).await;
    c.dec.expect(Expect::Seq);
    let mut b = vec![0x03, 0x07, 0x00, 0x04];
    b.extend_from_slice(b"2a00");
    b.extend_from_slice(&[0xff, 0xff]);
    c.send_raw(&b).await;
    match c.reply().await {
        Some(Reply::Error {
            message,
            seq: Some(7),
        }) => assert!(message.contains("65535"), "{message}"),
        other => panic!("{other:?}"),
    }
    assert!(c.closed().await);
    // An INIT with a 60 000-byte address, likewise.
    let mut c = Raw::connect(relay.addr).await;
    c.dec.expect(Expect::Seq);
    c.send_raw(&[0x01, 0x02, 0xea, 0x60, b'x']).await;
    assert!(matches!(
        c.reply().await,
        Some(Reply::Error { seq: Some(2), .. })
    ));
    assert!(c.closed().await);
    assert!(protocol_error(&relay, "more than the"));
    bystander_works(&relay).await;
    relay.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn invalid_text_is_answered_and_the_connection_goes_on() {
    let relay = Relay::start(&[Model::R2D2], cfg()).await;
    let mut c = Raw::connect(relay.addr).await;
    // FIND with a name that is not UTF-8: ERROR without seq.
    c.dec.expect(Expect::Find);
    c.send_raw(&[0x04, 0x00, 0x02, 0xc3, 0x28, 0, 0, 0, 0])
        .await;
    match c.reply().await {
        Some(Reply::Error { message, seq: None }) => {
            assert!(message.contains("UTF-8"), "{message}")
        }
        other => panic!("{other:?}"),
    }
    // INIT with a non-ASCII address: ERROR with its seq.
    c.dec.expect(Expect::Seq);
    c.send_raw(&[0x01, 0x05, 0x00, 0x02, 0xc3, 0xa9]).await;
    match c.reply().await {
        Some(Reply::Error {
            message,
            seq: Some(5),
        }) => assert!(message.contains("ASCII"), "{message}"),
        other => panic!("{other:?}"),
    }
    // A UUID that is not one, and a WRITE before INIT: errors with their seq.
    let err = c.write("not-a-uuid", &[1]).await.unwrap_err();
    assert!(err.contains("not a characteristic UUID"), "{err}");
    let err = c.write(&V2_API.to_string(), &[1]).await.unwrap_err();
    assert!(err.contains("INIT"), "{err}");
    // Still served.
    c.v2_ready(&relay.address(0)).await;
    assert!(protocol_error(&relay, "not valid UTF-8"));
    assert!(protocol_error(&relay, "not valid ASCII"));
    relay.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn truncated_and_dribbled_requests_are_closed() {
    let relay = Relay::start(
        &[Model::R2D2],
        ServerConfig {
            request_timeout: Duration::from_millis(300),
            ..cfg()
        },
    )
    .await;
    // Half a WRITE, then the connection ends.
    let mut c = Raw::connect(relay.addr).await;
    c.send_raw(&[0x03, 0x01, 0x00, 0x24, b'0', b'0']).await;
    c.s.shutdown().await.unwrap();
    relay
        .wait_event("truncated", |e| {
            matches!(e, ServerEvent::ProtocolError { error, .. } if error.contains("6 byte(s) into a request"))
        })
        .await;
    // Half a request, then nothing: closed after the request timeout, not the idle one.
    let mut c = Raw::connect(relay.addr).await;
    c.send_raw(&[0x04, 0x00]).await;
    let t0 = Instant::now();
    assert!(c.closed().await);
    assert!(t0.elapsed() < Duration::from_secs(3));
    assert!(protocol_error(&relay, "did not arrive whole"));
    bystander_works(&relay).await;
    relay.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_reader_that_cannot_keep_up_is_dropped() {
    let relay = Relay::start(
        &[Model::R2D2, Model::BB9E],
        ServerConfig {
            send_queue: 64,
            write_timeout: Duration::from_millis(500),
            send_buffer: Some(4096),
            ..cfg()
        },
    )
    .await;
    // A client that drives normally the whole time.
    let mut good = Raw::connect(relay.addr).await;
    good.v2_ready(&relay.address(1)).await;
    // The flooder: a small receive buffer, WRITEs pipelined and no reply ever read.
    let sock = tokio::net::TcpSocket::new_v4().unwrap();
    sock.set_recv_buffer_size(4096).unwrap();
    let mut flood = sock.connect(relay.addr).await.unwrap();
    let mut one = Vec::new();
    Request::Write {
        seq: 1,
        characteristic: "not-a-uuid-but-long-enough-to-make-errors".into(),
        data: vec![0; 8],
    }
    .encode(&mut one)
    .unwrap();
    // Batches within the server's bound on queued requests: what fills up is the send
    // queue, answers the flooder never reads.
    let batch: Vec<u8> = one.repeat(droidctl::relay::server::MAX_QUEUED / 8);
    let mut sent = 0usize;
    let flooding = async {
        // At most ~5 MB: the server drops us long before.
        for _ in 0..5000 {
            if flood.write_all(&batch).await.is_err() {
                return true;
            }
            sent += batch.len();
            tokio::task::yield_now().await;
        }
        false
    };
    let driving = async {
        for i in 0..20 {
            good.drive(60 + i).await;
            sleep(Duration::from_millis(20)).await;
        }
    };
    let (refused, ()) = tokio::join!(timeout(Duration::from_secs(20), flooding), driving);
    assert!(
        matches!(refused, Ok(true)),
        "the flooder was never dropped ({sent} bytes sent)"
    );
    relay
        .wait_event("slow reader dropped", |e| {
            matches!(e, ServerEvent::ClientClosed { reason, .. } if reason.contains("cannot keep up"))
        })
        .await;
    assert!(relay.speed(1) > 20.0, "the good client's droid rolls");
    good.drive(0).await;
    relay.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_connection_flood_meets_the_limit() {
    let relay = Relay::start(
        &[Model::R2D2],
        ServerConfig {
            max_clients: 4,
            ..cfg()
        },
    )
    .await;
    let mut held = Vec::new();
    for _ in 0..4 {
        held.push(Raw::connect(relay.addr).await);
    }
    // Make sure all four are counted before the flood.
    relay
        .wait_event("four clients", |e| {
            matches!(e, ServerEvent::ClientConnected { clients: 4, .. })
        })
        .await;
    for _ in 0..50 {
        let mut c = Raw::connect(relay.addr).await;
        c.dec.expect(Expect::Scan);
        match c.reply().await {
            Some(Reply::Error { message, .. }) => {
                assert!(message.contains("4 clients already"), "{message}")
            }
            None => {} // closed before the message was read: also a refusal
            other => panic!("{other:?}"),
        }
        assert!(c.closed().await);
    }
    let rejected = relay
        .events()
        .iter()
        .filter(|e| matches!(e, ServerEvent::ClientRejected { .. }))
        .count();
    assert_eq!(rejected, 50);
    // The ones inside are served; one leaving makes room.
    held[0].v2_ready(&relay.address(0)).await;
    let mut last = held.pop().unwrap();
    last.send(&Request::End).await;
    assert!(last.closed().await);
    wait_until("room again", || {
        relay
            .events()
            .iter()
            .filter(|e| matches!(e, ServerEvent::ClientClosed { .. }))
            .count()
            >= 1
    })
    .await;
    bystander_works(&relay).await;
    relay.stop().await;
}

// ---------------------------------------------------------------------------------------------
// Soak: several clients, several droids, one client killed mid-drive.
// ---------------------------------------------------------------------------------------------

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn soak_several_clients_one_killed() {
    let models = [Model::BB9E, Model::R2Q5, Model::BB9E, Model::BB8];
    let relay = Relay::start(&models, cfg()).await;
    let ra = relay.relay_addr();
    // Three droidctl sessions through the relay link…
    let mut sessions = Vec::new();
    for (i, m) in models.iter().enumerate().skip(1) {
        let link = RemoteLink::new(
            ra.clone(),
            relay.address(i),
            format!("droid {i}"),
            *m,
            droidctl::family::gatt_profile(*m),
        );
        sessions.push((i, *m, session::start(Box::new(link), session_config(*m))));
    }
    // …and one raw client that will be killed.
    let mut victim = Raw::connect(relay.addr).await;
    victim.v2_ready(&relay.address(0)).await;
    let run = Duration::from_secs(3);
    let t0 = Instant::now();
    let mut killed = None;
    let mut stopped = None;
    let mut victim = Some(victim);
    let mut step = 0u32;
    while t0.elapsed() < run {
        step += 1;
        for (_, m, s) in &sessions {
            let f = family::for_model(*m);
            let heading = Heading::new(((step * 7) % 360) as u16).unwrap();
            s.set(Slot::Drive, f.drive(90, heading, false));
        }
        if let Some(v) = victim.as_mut() {
            v.drive(150).await;
        }
        if killed.is_none() && t0.elapsed() > Duration::from_millis(1200) {
            assert!(relay.speed(0) > 50.0, "the victim's droid rolls");
            // Killed: the socket goes without END.
            victim = None;
            killed = Some(Instant::now());
        }
        if let Some(k) = killed
            && stopped.is_none()
            && relay.speed(0).abs() < 0.5
        {
            stopped = Some(k.elapsed());
        }
        sleep(Duration::from_millis(50)).await;
    }
    // The orphan stopped (well before the droid's own 2 s motion timeout would have stopped
    // it) and was released…
    let stopped = stopped.expect("the orphan stopped");
    assert!(
        stopped < Duration::from_millis(1000),
        "stopped {stopped:?} after the kill"
    );
    assert!(
        relay.speed(0).abs() < 0.5,
        "orphan speed {}",
        relay.speed(0)
    );
    let orphan = relay.address(0);
    assert!(relay.any(
        |e| matches!(e, ServerEvent::DroidReleased { stopped: true, address, .. } if *address == orphan)
    ));
    // …while the others drove on, undisturbed.
    for (i, _, s) in &sessions {
        assert!(
            relay.speed(*i) > 20.0,
            "droid {i} rolls: {}",
            relay.speed(*i)
        );
        assert_eq!(s.state(), LinkState::Connected);
        let st = s.stats();
        assert_eq!(st.reconnects, 0, "droid {i}: {st:?}");
        assert_eq!(st.link_lost, 0, "droid {i}: {st:?}");
    }
    for (_, _, s) in sessions {
        s.shutdown_stopped(Vec::new()).await;
    }
    let errors: Vec<ServerEvent> = relay
        .events()
        .into_iter()
        .filter(|e| {
            matches!(
                e,
                ServerEvent::ProtocolError { .. } | ServerEvent::RequestFailed { .. }
            )
        })
        .collect();
    assert!(errors.is_empty(), "{errors:#?}");
    relay.stop().await;
}

// ---------------------------------------------------------------------------------------------
// The Bluetooth backend, over droidctl's BLE layer (its fake peripheral here).
// ---------------------------------------------------------------------------------------------

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_ble_backend_relays_gatt_operations() {
    use droidctl::link::ble::fake::{FakeCentral, FakeOp, FakePeripheral};
    use droidctl::link::ble::{Advertisement, BleAddress};
    use droidctl::relay::ble_backend::BleBackend;

    let central = FakeCentral::new();
    let droid = FakePeripheral::for_profile(&droidctl::family::gatt_profile(Model::R2D2));
    let address = BleAddress([0xD2, 0, 0, 0, 0x1A, 0x2B]);
    central.add_device(
        Advertisement {
            address,
            name: Some("D2-1A2B".into()),
            rssi: Some(-60),
        },
        droid.clone(),
    );
    let backend: Arc<dyn GattBackend> = Arc::new(BleBackend::new(Arc::new(central)));
    let events: Arc<Mutex<Vec<ServerEvent>>> = Arc::default();
    let sink: EventSink = {
        let events = events.clone();
        Arc::new(move |e: &ServerEvent| events.lock().unwrap().push(e.clone()))
    };
    let (addr, server) = serve_forever(backend, cfg(), sink).await;

    let mut c = Raw::connect(addr).await;
    // FIND answers as soon as the name is heard.
    c.send(&Request::Find {
        name: "D2-1A2B".into(),
        timeout: 2.0,
    })
    .await;
    let found = match c.reply().await {
        Some(Reply::Found(d)) => d,
        other => panic!("{other:?}"),
    };
    assert_eq!(found.address, "D2:00:00:00:1A:2B");
    // Unknown names: ERROR with an empty message, spherov2's "not found".
    c.send(&Request::Find {
        name: "nobody".into(),
        timeout: 0.2,
    })
    .await;
    assert_eq!(
        c.reply().await,
        Some(Reply::Error {
            message: String::new(),
            seq: None
        })
    );
    c.init(&found.address).await.unwrap();
    c.write(&V2_ANTI_DOS.to_string(), V2_UNLOCK).await.unwrap();
    let ch = V2_API.to_string();
    c.call(|seq| Request::SetCallback {
        seq,
        characteristic: ch,
    })
    .await
    .unwrap();
    // A notification from the droid reaches the client as ON_DATA.
    droid.notify(V2_API, &[0x8d, 0x0a, 0xd8]);
    let deadline = Instant::now() + WAIT;
    while c.data.is_empty() {
        assert!(Instant::now() < deadline, "no ON_DATA");
        c.send(&Request::Scan { timeout: 0.0 }).await;
        let _ = c.reply().await;
    }
    assert_eq!(c.data[0], (V2_API.to_string(), vec![0x8d, 0x0a, 0xd8]));
    // Writes reach the characteristic the client named.
    let anti_dos: Vec<Vec<u8>> = droid
        .writes_to(V2_ANTI_DOS)
        .into_iter()
        .map(|(_, d)| d)
        .collect();
    assert_eq!(anti_dos, [V2_UNLOCK.to_vec()]);
    // The client goes: the family's stop is written to the API characteristic, then the
    // droid is disconnected.
    drop(c);
    let api = written_after_release(&droid, V2_API).await;
    let f = family::for_model(Model::R2D2);
    let (stop, _) = f.codec().encode(&f.stop_after(None), 0, false);
    assert_eq!(api, stop);
    assert!(matches!(droid.ops().last(), Some(FakeOp::Disconnect)));
    assert!(events.lock().unwrap().iter().any(|e| matches!(
        e,
        ServerEvent::DroidConnected { model: Some("r2d2"), name, .. } if name == "D2-1A2B"
    )));
    server.abort();
}

/// A droid whose name does not say its model (no name heard, say) is still stopped when its
/// client goes: the family is read from its GATT table.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_droid_without_a_known_name_is_stopped_by_its_family() {
    use droidctl::family::v1::gatt::V1_COMMANDS;
    use droidctl::link::ble::fake::{FakeCentral, FakePeripheral};
    use droidctl::link::ble::{Advertisement, BleAddress};
    use droidctl::relay::ble_backend::BleBackend;

    let central = FakeCentral::new();
    let droid = FakePeripheral::for_profile(&droidctl::family::gatt_profile(Model::BB8));
    central.add_device(
        Advertisement {
            address: BleAddress([0xBB, 8, 0, 0, 0, 1]),
            name: None,
            rssi: Some(-50),
        },
        droid.clone(),
    );
    let backend: Arc<dyn GattBackend> = Arc::new(BleBackend::new(Arc::new(central)));
    let (addr, server) = serve_forever(backend, cfg(), Arc::new(|_| {})).await;
    let mut c = Raw::connect(addr).await;
    c.init("BB:08:00:00:00:01").await.unwrap();
    drop(c);
    let written = written_after_release(&droid, V1_COMMANDS).await;
    let f = family::for_model(Model::BB8);
    let (stop, _) = f.codec().encode(&f.stop_after(None), 0, false);
    assert_eq!(written, stop);
    server.abort();
}

/// A backend whose scans take a while, and which has no droids.
struct SlowScans;

impl GattBackend for SlowScans {
    fn scan(
        &self,
        t: Duration,
    ) -> futures_util::future::BoxFuture<
        '_,
        Result<
            Vec<droidctl::relay::backend::BackendDevice>,
            droidctl::relay::backend::BackendError,
        >,
    > {
        Box::pin(async move {
            sleep(t).await;
            Ok(vec![droidctl::relay::backend::BackendDevice {
                name: "D2-SLOW".into(),
                address: "AA:BB:CC:DD:EE:FF".into(),
            }])
        })
    }
    fn find<'a>(
        &'a self,
        _name: &'a str,
        _t: Duration,
    ) -> futures_util::future::BoxFuture<
        'a,
        Result<
            Option<droidctl::relay::backend::BackendDevice>,
            droidctl::relay::backend::BackendError,
        >,
    > {
        Box::pin(async { Ok(None) })
    }
    fn connect<'a>(
        &'a self,
        _address: &'a str,
    ) -> futures_util::future::BoxFuture<
        'a,
        Result<droidctl::relay::backend::Connected, droidctl::relay::backend::BackendError>,
    > {
        Box::pin(async { Err("no droids here".into()) })
    }
    fn describe(&self) -> String {
        "slow scans".into()
    }
}

/// A client waiting for a long scan is not silent: the idle timeout counts from the answer.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn waiting_for_a_scan_is_not_silence() {
    let cfg = ServerConfig {
        idle_timeout: Some(Duration::from_millis(400)),
        ..cfg()
    };
    let (addr, server) = serve_forever(Arc::new(SlowScans), cfg, Arc::new(|_| {})).await;
    let mut c = Raw::connect(addr).await;
    c.send(&Request::Scan { timeout: 0.8 }).await;
    match c.reply().await {
        Some(Reply::Devices(d)) => assert_eq!(d[0].name, "D2-SLOW"),
        other => panic!("{other:?}"),
    }
    // Still served right after the answer…
    let t0 = Instant::now();
    c.send(&Request::Find {
        name: "x".into(),
        timeout: 0.0,
    })
    .await;
    assert!(matches!(c.reply().await, Some(Reply::Error { .. })));
    // …and closed once silent for the timeout.
    assert!(c.closed().await);
    assert!(
        t0.elapsed() >= Duration::from_millis(300),
        "{:?}",
        t0.elapsed()
    );
    server.abort();
}

/// The simulated droids, with scans that take as long as the client asks (a real adapter's).
struct SlowScanSim(Arc<SimBackend>);

impl GattBackend for SlowScanSim {
    fn scan(
        &self,
        t: Duration,
    ) -> futures_util::future::BoxFuture<
        '_,
        Result<
            Vec<droidctl::relay::backend::BackendDevice>,
            droidctl::relay::backend::BackendError,
        >,
    > {
        Box::pin(async move {
            sleep(t).await;
            self.0.scan(t).await
        })
    }
    fn find<'a>(
        &'a self,
        name: &'a str,
        t: Duration,
    ) -> futures_util::future::BoxFuture<
        'a,
        Result<
            Option<droidctl::relay::backend::BackendDevice>,
            droidctl::relay::backend::BackendError,
        >,
    > {
        self.0.find(name, t)
    }
    fn connect<'a>(
        &'a self,
        address: &'a str,
    ) -> futures_util::future::BoxFuture<
        'a,
        Result<droidctl::relay::backend::Connected, droidctl::relay::backend::BackendError>,
    > {
        self.0.connect(address)
    }
    fn describe(&self) -> String {
        "simulated droids, slow scans".into()
    }
}

async fn slow_relay() -> Relay {
    Relay::start_with(&[Model::BB9E], cfg(), |sim| Arc::new(SlowScanSim(sim))).await
}

/// A server stopping while a client waits for a 25 s scan does not wait for the scan: the
/// client's droid is stopped and released within a second (it used to wait 10 s, then abort
/// the client before the stop was written).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stopping_the_server_mid_scan_stops_the_droid_within_a_second() {
    let relay = slow_relay().await;
    let addr = relay.address(0);
    let mut a = Raw::connect(relay.addr).await;
    a.v2_ready(&addr).await;
    a.drive(150).await;
    wait_until("rolling", || relay.speed(0) > 50.0).await;
    a.send(&Request::Scan { timeout: 25.0 }).await;
    sleep(Duration::from_millis(200)).await;
    let sim = relay.sim.clone();
    let events = relay.events.clone();
    let t0 = Instant::now();
    relay.stop().await;
    assert!(
        t0.elapsed() < Duration::from_secs(1),
        "the server took {:?} to stop",
        t0.elapsed()
    );
    assert!(
        events
            .lock()
            .unwrap()
            .iter()
            .any(|e| matches!(e, ServerEvent::DroidReleased { stopped: true, .. })),
        "the droid was not stopped on release"
    );
    wait_until("stopped", || {
        sim.state(&addr).unwrap().velocity_cm_s.abs() < 0.5
    })
    .await;
    assert!(a.closed().await);
}

/// A client that goes while its 25 s scan runs is noticed at once: its droid is stopped.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_leaving_mid_scan_is_noticed_and_its_droid_stopped() {
    let relay = slow_relay().await;
    let addr = relay.address(0);
    let mut a = Raw::connect(relay.addr).await;
    a.v2_ready(&addr).await;
    a.drive(150).await;
    wait_until("rolling", || relay.speed(0) > 50.0).await;
    a.send(&Request::Scan { timeout: 25.0 }).await;
    sleep(Duration::from_millis(200)).await;
    let t0 = Instant::now();
    drop(a);
    relay
        .wait_event("release with stop", |e| {
            matches!(e, ServerEvent::DroidReleased { stopped: true, .. })
        })
        .await;
    assert!(t0.elapsed() < Duration::from_secs(1), "{:?}", t0.elapsed());
    wait_until("stopped", || relay.speed(0).abs() < 0.5).await;
    relay.stop().await;
}

/// Hundreds of SCANs pipelined in one write would keep a client's task (and the adapter's
/// scan) busy for hours: past the queue bound the client is told so and closed, and others
/// are served.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pipelined_requests_beyond_the_bound_close_the_client() {
    let relay = slow_relay().await;
    let mut greedy = Raw::connect(relay.addr).await;
    let mut burst = Vec::new();
    for _ in 0..500 {
        burst.extend(Request::Scan { timeout: 30.0 }.to_bytes().unwrap());
    }
    greedy.send_raw(&burst).await;
    let t0 = Instant::now();
    relay
        .wait_event("queue bound", |e| {
            matches!(e, ServerEvent::ProtocolError { error, .. } if error.contains("scans queued"))
        })
        .await;
    assert!(greedy.closed().await, "the greedy client was not closed");
    assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
    // Someone else is answered.
    let mut other = Raw::connect(relay.addr).await;
    other.send(&Request::Scan { timeout: 0.1 }).await;
    assert!(matches!(other.reply().await, Some(Reply::Devices(_))));
    relay.stop().await;
}

/// The bound counts what waits behind the request being served, however the requests
/// arrive: three scans in one write (one served, two waiting) are all answered, as when the
/// third comes while the first is served; a fourth is one too many. (Found by the
/// relay_server fuzz target: in one write, the first was counted as waiting.)
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn three_pipelined_scans_in_one_write_are_answered() {
    let relay = Relay::start(&[Model::R2D2], cfg()).await;
    let mut c = Raw::connect(relay.addr).await;
    let request = Request::Scan { timeout: 0.1 };
    let scan = request.to_bytes().unwrap();
    for _ in 0..3 {
        c.dec.expect(request.expect().unwrap());
    }
    c.send_raw(&scan.repeat(3)).await;
    for i in 0..3 {
        assert!(
            matches!(c.reply().await, Some(Reply::Devices(_))),
            "scan {} of 3 not answered",
            i + 1
        );
    }
    c.send_raw(&scan.repeat(4)).await;
    relay
        .wait_event("queue bound", |e| {
            matches!(e, ServerEvent::ProtocolError { error, .. } if error.contains("scans queued"))
        })
        .await;
    relay.stop().await;
}

/// A client that goes mid-drive leaves its droid stopped at the heading it last drove: the
/// relay reads the client's writes with the droid's family (a stop at heading 0 turned the
/// droid on the spot as it stopped).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_departed_clients_droid_stops_at_its_last_heading() {
    use droidctl::link::ble::fake::{FakeCentral, FakePeripheral};
    use droidctl::link::ble::{Advertisement, BleAddress};
    use droidctl::protocol::v2::cmd;
    use droidctl::protocol::v2::wire::DriveFlags;
    use droidctl::relay::ble_backend::BleBackend;

    let central = FakeCentral::new();
    let droid = FakePeripheral::for_profile(&droidctl::family::gatt_profile(Model::R2D2));
    let address = BleAddress([0xD2, 0, 0, 0, 0x1A, 0x2C]);
    central.add_device(
        Advertisement {
            address,
            name: Some("D2-1A2C".into()),
            rssi: Some(-60),
        },
        droid.clone(),
    );
    let backend: Arc<dyn GattBackend> = Arc::new(BleBackend::new(Arc::new(central)));
    let (addr, server) = serve_forever(backend, cfg(), Arc::new(|_| {})).await;
    let mut c = Raw::connect(addr).await;
    c.init("D2:00:00:00:1A:2C").await.unwrap();
    c.write(&V2_ANTI_DOS.to_string(), V2_UNLOCK).await.unwrap();
    let api = V2_API.to_string();
    // Two drives, the last toward 135°, each cut into 20-byte writes as BLE carries them.
    let heading = Heading::new(135).unwrap();
    let last = cmd::drive_with_heading(90, heading, DriveFlags::empty());
    for (seq, c2) in [
        cmd::drive_with_heading(60, Heading::new(20).unwrap(), DriveFlags::empty()),
        last.clone(),
    ]
    .into_iter()
    .enumerate()
    {
        for chunk in c2.to_packet(seq as u8).encode().chunks(20) {
            c.write(&api, chunk).await.unwrap();
        }
    }
    let before = droid.writes_to(V2_API).len();
    drop(c);
    written_after_release(&droid, V2_API).await;
    let written: Vec<u8> = droid
        .writes_to(V2_API)
        .into_iter()
        .skip(before)
        .flat_map(|(_, d)| d)
        .collect();
    let f = family::for_model(Model::R2D2);
    let stop = f.stop_after(Some(&last.into()));
    let (expected, _) = f.codec().encode(&stop, 0, false);
    assert_eq!(written, expected, "the stop keeps heading 135");
    assert_eq!(&stop.data()[..3], &[0, 0, 135]);
    server.abort();
}

/// An idle timeout too long for the clock means "never", not a panic in every client task.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_idle_timeout_beyond_the_clock_is_never() {
    let relay = Relay::start(
        &[Model::R2D2],
        ServerConfig {
            idle_timeout: Some(Duration::MAX),
            request_timeout: Duration::MAX,
            ..cfg()
        },
    )
    .await;
    let mut c = Raw::connect(relay.addr).await;
    c.send(&Request::Scan { timeout: 0.0 }).await;
    assert!(matches!(c.reply().await, Some(Reply::Devices(_))));
    // A partial request arms the request timer too: a SCAN in two pieces.
    let scan = Request::Scan { timeout: 0.0 };
    let bytes = scan.to_bytes().unwrap();
    c.dec.expect(scan.expect().unwrap());
    c.send_raw(&bytes[..1]).await;
    sleep(Duration::from_millis(100)).await;
    c.send_raw(&bytes[1..]).await;
    assert!(matches!(c.reply().await, Some(Reply::Devices(_))));
    relay.stop().await;
}

/// A client streaming requests without pause, each read ending inside the next request, is
/// not "a request that did not arrive whole": the 10 s limit runs from the request that is
/// partial, not from the first partial read of a run of them (such a client was closed after
/// 10 s although every request came whole in 50 ms; found reading the timer while checking a
/// relay_server fuzz report, whose own input was a request rightly given up on).
/// In process on paused time (`server::serve_stream`).
#[tokio::test(start_paused = true)]
async fn a_steady_stream_of_requests_cut_mid_request_is_not_timed_out() {
    let backend = Arc::new(SimBackend::new(&[Model::R2D2], GattFaults::default()));
    let events: Arc<Mutex<Vec<ServerEvent>>> = Arc::default();
    let sink: EventSink = {
        let events = events.clone();
        Arc::new(move |e: &ServerEvent| events.lock().unwrap().push(e.clone()))
    };
    let (client, stream) = tokio::io::duplex(64 * 1024);
    let peer = "127.0.0.1:1".parse().unwrap();
    let served = tokio::spawn(server::serve_stream(stream, peer, backend, cfg(), sink));
    let (mut rd, mut wr) = tokio::io::split(client);
    // WRITEs without a droid: each answered with an ERROR at once.
    let write = |seq: u8| {
        Request::Write {
            seq,
            characteristic: V2_API.to_string(),
            data: vec![0x8D, 0x0A, 0xD8],
        }
        .to_bytes()
        .unwrap()
    };
    let n = 300u32;
    let reader = tokio::spawn(async move {
        let mut dec = ReplyDecoder::new(Limits::default());
        for _ in 0..n {
            dec.expect(Expect::Seq);
        }
        let (mut answers, mut buf) = (0u32, [0u8; 4096]);
        while answers < n {
            match rd.read(&mut buf).await {
                Ok(0) | Err(_) => break,
                Ok(k) => dec.push(&buf[..k]),
            }
            while let Some(r) = dec.next() {
                assert!(matches!(r, Ok(Reply::Error { .. })), "{r:?}");
                answers += 1;
            }
        }
        answers
    });
    // Every 50 ms: the end of one request and the start of the next.
    let first = write(0);
    let half = first.len() / 2;
    wr.write_all(&first[..half]).await.unwrap();
    for i in 0..n {
        sleep(Duration::from_millis(50)).await;
        let this = write(i as u8);
        let next = write(i.wrapping_add(1) as u8);
        let mut piece = this[half..].to_vec();
        if i + 1 < n {
            piece.extend_from_slice(&next[..half]);
        }
        wr.write_all(&piece).await.unwrap();
    }
    let answers = timeout(Duration::from_secs(5), reader)
        .await
        .unwrap()
        .unwrap();
    assert_eq!(
        answers,
        n,
        "closed early: {:?}",
        events.lock().unwrap().last()
    );
    wr.shutdown().await.unwrap();
    served.await.unwrap();
    assert!(
        !events
            .lock()
            .unwrap()
            .iter()
            .any(|e| matches!(e, ServerEvent::ProtocolError { .. })),
        "{:?}",
        events.lock().unwrap()
    );
}
