//! A mission in simulated (paused) time ends where the same mission ends in real time.

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::mission::{self, MissionOptions, Summary};
use droidctl::model::Model;
use droidctl::session::{self, SessionConfig};
use droidctl::sim::{Faults, SimConfig, SimLink};
use std::sync::Arc;
use std::time::Duration;

const SCRIPT: &str = "wake\nstance tripod\ndrive 120 90 for 1.5s\ndrive 120 0 for 1s\nstop\n";

async fn mission() -> Summary {
    let steps = droidctl::script::parse(SCRIPT).unwrap();
    let link = SimLink::new(Model::R2D2, SimConfig::default(), Faults::none());
    let s = session::start(
        Box::new(link),
        SessionConfig {
            setup: connect_setup(
                Model::R2D2,
                &SetupOptions {
                    tripod: false,
                    streaming_interval_ms: 50,
                    ..Default::default()
                },
            ),
            ..SessionConfig::default()
        },
    );
    let summary = mission::run(
        &s,
        Model::R2D2,
        &steps,
        MissionOptions::default(),
        Arc::new(|_| {}),
    )
    .await
    .unwrap();
    s.shutdown_stopped(vec![]).await;
    summary
}

#[test]
fn simulated_time_matches_real_time() {
    let paused = tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .start_paused(true)
        .build()
        .unwrap()
        .block_on(mission());
    let wall = std::time::Instant::now();
    let real = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
        .block_on(mission());
    assert!(
        wall.elapsed() > Duration::from_secs(4),
        "the real-time run really took its time"
    );
    let (px, py) = (paused.x_cm.unwrap(), paused.y_cm.unwrap());
    let (rx, ry) = (real.x_cm.unwrap(), real.y_cm.unwrap());
    // Same path, to within scheduling jitter of a few ms at 75 cm/s.
    assert!(px > 50.0 && py > 30.0, "moved: ({px}, {py})");
    assert!(
        (px - rx).abs() < 6.0 && (py - ry).abs() < 6.0,
        "paused ({px}, {py}) vs real ({rx}, {ry})"
    );
    assert_eq!(paused.failed_steps, 0);
    assert_eq!(real.failed_steps, 0);
}
