use droidctl::model::Model;
use droidctl::protocol::v2::cmd;
use droidctl::protocol::v2::wire::{DriveFlags, LegAction};
use droidctl::session::{self, SessionConfig, Slot};
use droidctl::sim::{Faults, SimConfig, SimLink};
use droidctl::units::Heading;
use std::time::Duration;

#[tokio::test(start_paused = true)]
async fn drive_forward_in_tripod() {
    let link = SimLink::new(Model::R2D2, SimConfig::default(), Faults::none());
    let probe = link.probe();
    let s = session::start(Box::new(link), SessionConfig::default());
    s.request(cmd::wake()).await.unwrap();
    s.request(cmd::perform_leg_action(LegAction::Tripod))
        .await
        .unwrap();
    tokio::time::sleep(Duration::from_millis(2500)).await;
    for _ in 0..20 {
        s.set(
            Slot::Drive,
            cmd::drive_with_heading(128, Heading::new(90).unwrap(), DriveFlags::empty()),
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let st = probe.state();
    eprintln!("{st:?} {:?}", s.stats());
    assert!(st.x_cm > 50.0, "{st:?}");
    s.shutdown(vec![]).await;
}
