//! Soak: ten simulated minutes of seeded random driving over a noisy link (2 % byte
//! corruption both ways, random splits, a disconnect every minute), with discrete requests
//! mixed in. Nothing may panic or hang; the session must keep reconnecting and answering.

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::model::Model;
use droidctl::protocol::v2::wire::{AudioMode, DriveFlags};
use droidctl::protocol::v2::{Command, cmd};
use droidctl::rng::Rng;
use droidctl::session::{self, LinkState, RequestError, SessionConfig, Slot};
use droidctl::sim::{Faults, SimConfig, SimLink};
use droidctl::units::{HeadAngle, Heading};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::time::{Instant, sleep, timeout};

static PANICS: AtomicUsize = AtomicUsize::new(0);

/// How one discrete request ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    Answered,
    Timeout,
    Droid(u8),
    LinkLost,
    QueueFull,
    /// Not acceptable while the session runs.
    Closed,
    /// Only drives are superseded, and none is asked for here.
    Superseded,
    /// The generous outer timeout fired: the request hung.
    Hung,
}

fn discrete(rng: &mut Rng, n: u64) -> (&'static str, Command) {
    match n % 3 {
        0 => ("get-battery-voltage", cmd::get_battery_voltage()),
        1 => {
            let deg = rng.below(341) as f32 - 160.0;
            (
                "set-head-position",
                cmd::set_head_position(HeadAngle::new(deg).unwrap()),
            )
        }
        _ => {
            let mode = [
                AudioMode::Immediate,
                AudioMode::IfIdle,
                AudioMode::AfterCurrent,
            ][rng.below(3) as usize];
            (
                "play-audio-file",
                cmd::play_audio_file(1704 + rng.below(2000) as u16, mode),
            )
        }
    }
}

#[tokio::test(start_paused = true)]
async fn ten_minutes_noisy_driving_with_a_disconnect_every_minute() {
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        PANICS.fetch_add(1, Ordering::SeqCst);
        default_hook(info);
    }));
    let wall = std::time::Instant::now();

    let minutes = 10u64;
    let faults = Faults {
        seed: 0x5EED_50AC,
        split: true,
        corrupt_rate: 0.02,
        disconnect_at: (1..=minutes).map(|m| Duration::from_secs(60 * m)).collect(),
        ..Faults::none()
    };
    let link = SimLink::new(Model::R2D2, SimConfig::default(), faults);
    let probe = link.probe();
    let config = SessionConfig {
        setup: connect_setup(Model::R2D2, &SetupOptions::default()),
        ..SessionConfig::default()
    };
    let s = session::start(Box::new(link), config);

    let outcomes: Arc<Mutex<BTreeMap<(&'static str, Outcome), u32>>> = Arc::default();
    let mut requests = Vec::new();
    let mut rng = Rng::new(2024);
    let t0 = Instant::now();
    // A few seconds past the last disconnect, so the last reconnect is done.
    let end = t0 + Duration::from_secs(60 * minutes + 10);
    let mut tick = 0u64;
    while Instant::now() < end {
        let speed = rng.below(256) as u8;
        let heading = Heading::new(rng.below(360) as u16).unwrap();
        s.set(
            Slot::Drive,
            cmd::drive_with_heading(speed, heading, DriveFlags::empty()),
        );
        if tick % 7 == 3 {
            let (name, c) = discrete(&mut rng, tick / 7);
            let s = s.clone();
            let outcomes = outcomes.clone();
            requests.push(tokio::spawn(async move {
                let outcome = match timeout(Duration::from_secs(60), s.request(c)).await {
                    Err(_) => Outcome::Hung,
                    Ok(Ok(_)) => Outcome::Answered,
                    Ok(Err(RequestError::Timeout)) => Outcome::Timeout,
                    Ok(Err(RequestError::Droid(e))) => Outcome::Droid(e.code()),
                    Ok(Err(RequestError::LinkLost)) => Outcome::LinkLost,
                    Ok(Err(RequestError::QueueFull)) => Outcome::QueueFull,
                    Ok(Err(RequestError::Closed)) => Outcome::Closed,
                    Ok(Err(RequestError::Superseded)) => Outcome::Superseded,
                };
                *outcomes.lock().unwrap().entry((name, outcome)).or_default() += 1;
            }));
        }
        tick += 1;
        sleep(Duration::from_millis(100)).await;
    }
    for r in requests.drain(..) {
        r.await.expect("request task panicked");
    }
    let stats = s.stats();
    let state = s.state();
    let droid = probe.state();
    // One last request on a healthy link.
    let last = timeout(Duration::from_secs(10), async {
        loop {
            match s.request(cmd::ping()).await {
                Ok(_) => return true,
                Err(RequestError::Closed) => return false,
                Err(_) => {}
            }
        }
    })
    .await;
    s.shutdown(vec![
        cmd::drive_with_heading(0, Heading::default(), DriveFlags::empty()).into(),
    ])
    .await;
    let wall = wall.elapsed();

    let outcomes = outcomes.lock().unwrap().clone();
    eprintln!(
        "soak: {} simulated s in {wall:?} wall",
        (Instant::now() - t0).as_secs()
    );
    eprintln!("soak: {stats:?}");
    eprintln!("soak: droid {droid:?}");
    for ((name, o), n) in &outcomes {
        eprintln!("soak: {name:<20} {o:?}: {n}");
    }

    let count = |f: &dyn Fn(Outcome) -> bool| -> u32 {
        outcomes
            .iter()
            .filter(|((_, o), _)| f(*o))
            .map(|(_, n)| *n)
            .sum()
    };
    let total = count(&|_| true);
    let issued = (0..tick).filter(|t| t % 7 == 3).count();
    assert_eq!(total as usize, issued, "every request accounted for");
    assert_eq!(
        count(&|o| o == Outcome::Hung),
        0,
        "a request hung: {outcomes:?}"
    );
    assert_eq!(
        count(&|o| o == Outcome::Closed),
        0,
        "session closed under load: {outcomes:?}"
    );
    assert_eq!(count(&|o| o == Outcome::Superseded), 0, "{outcomes:?}");
    let answered = count(&|o| o == Outcome::Answered);
    assert!(answered > 0, "{outcomes:?}");
    assert!(
        answered * 2 > total,
        "most requests should get through: {outcomes:?}"
    );
    assert!(count(&|o| o == Outcome::LinkLost) + count(&|o| o == Outcome::Timeout) > 0);
    // Droid errors happen (target_unavailable while a lost setup wake leaves the droid asleep
    // until the next reconnect) but are not the rule.
    assert!(
        count(&|o| matches!(o, Outcome::Droid(_))) * 10 < total,
        "{outcomes:?}"
    );

    assert_eq!(state, LinkState::Connected);
    assert_eq!(stats.reconnects, minutes, "one reconnect per disconnect");
    assert!(
        stats.decode_errors > 0,
        "2 % corruption must show: {stats:?}"
    );
    assert!(stats.timeouts > 0);
    assert!(stats.link_lost > 0);
    assert!(stats.coalesced > 0);
    assert_eq!(last, Ok(true), "the session still works at the end");
    assert!(droid.awake && droid.commands > 1000, "{droid:?}");
    assert_eq!(PANICS.load(Ordering::SeqCst), 0, "something panicked");
}
