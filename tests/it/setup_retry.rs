//! A connect setup whose Wake is lost still ends with the droid awake, in tripod and
//! streaming: setup commands are re-sent on timeout, and after a Wake when the droid answers
//! target_unavailable.

use droidctl::family::setup::{SetupOptions, connect_setup};
use droidctl::link::{Connection, Link, LinkError, LinkWriter};
use droidctl::model::Model;
use droidctl::protocol::v2::Notification;
use droidctl::protocol::v2::wire::LegState;
use droidctl::session::{self, SessionConfig, SessionEvent};
use droidctl::sim::{Faults, SimConfig, SimLink};
use futures_util::future::BoxFuture;
use std::time::Duration;

/// Loses the first chunk ever written (the Wake).
struct LoseFirstWrite(SimLink);

struct Writer {
    inner: Box<dyn LinkWriter>,
    lost: bool,
}

impl LinkWriter for Writer {
    fn write<'a>(&'a mut self, chunk: &'a [u8]) -> BoxFuture<'a, Result<(), LinkError>> {
        if !self.lost {
            self.lost = true;
            return Box::pin(async { Ok(()) });
        }
        self.inner.write(chunk)
    }
    fn close(&mut self) -> BoxFuture<'_, ()> {
        self.inner.close()
    }
}

impl Link for LoseFirstWrite {
    fn open(&mut self) -> BoxFuture<'_, Result<Connection, LinkError>> {
        Box::pin(async move {
            let c = self.0.open().await?;
            Ok(Connection {
                writer: Box::new(Writer {
                    inner: c.writer,
                    lost: false,
                }),
                events: c.events,
            })
        })
    }
    fn describe(&self) -> String {
        self.0.describe()
    }
}

#[tokio::test(start_paused = true)]
async fn lost_wake_is_recovered() {
    let sim = SimLink::new(Model::R2D2, SimConfig::default(), Faults::none());
    let probe = sim.probe();
    let s = session::start(
        Box::new(LoseFirstWrite(sim)),
        SessionConfig {
            setup: connect_setup(Model::R2D2, &SetupOptions::default()),
            ..SessionConfig::default()
        },
    );
    let mut events = s.subscribe();
    tokio::time::sleep(Duration::from_secs(12)).await;
    let st = probe.state();
    assert!(st.awake, "{st:?}");
    assert_eq!(st.stance, LegState::Tripod);
    assert!(s.stats().retried > 0);
    let mut samples = 0;
    while let Ok(e) = events.try_recv() {
        if let SessionEvent::Notification(Notification::Sensors(_)) = e {
            samples += 1;
        }
    }
    assert!(samples > 10, "streaming is on: {samples} samples");
}
