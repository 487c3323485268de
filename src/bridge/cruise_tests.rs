//! Home Assistant's Speed number and selects on the bridge's side (issue 40 point 5): the
//! cruise speed moves nothing by itself and is what a drive without a speed rolls at (the
//! command timeout and the hold still rule), and an animation or a sound played by its
//! catalogue name is said and kept for the retained topics.

use super::schema::{ErrorCode, Out};
use super::tests::{rig, run_for};
use crate::model::Model;

#[tokio::test(start_paused = true)]
async fn the_cruise_speed_moves_nothing_and_a_drive_without_speed_rolls_at_it() {
    let mut r = rig(&[Model::BB8], 600).await;
    run_for(500).await;
    let t0 = r.now();
    // At cruise 0 (the default) a drive without a speed turns in place.
    r.send(r#"{"v":1,"cmd":"drive","heading":90}"#);
    run_for(300).await;
    let w: Vec<_> = r.writes(0).into_iter().filter(|(t, _)| *t >= t0).collect();
    assert!(!w.is_empty() && w.iter().all(|(_, s)| *s == 0), "{w:?}");
    run_for(1000).await;
    r.said();
    // The cruise speed alone: said, and nothing rolls.
    let t1 = r.now();
    r.send(r#"{"v":1,"cmd":"cruise","speed":70,"id":1}"#);
    r.send(r#"{"v":1,"cmd":"cruise","speed":70}"#);
    run_for(1500).await;
    assert!(
        r.writes(0).iter().all(|(t, s)| *t < t1 || *s == 0),
        "the cruise speed drove the droid: {:?}",
        r.writes(0)
    );
    let said = r.said();
    assert!(
        matches!(&said[..], [Out::Cruise { droid, speed: 70 }, Out::Reply { cmd: "cruise", .. }] if droid == "BB-0001"),
        "said once, at the change: {said:?}"
    );
    assert_eq!(r.bridge.cruise(0), 70);
    // A drive without a speed rolls at it, until the command timeout stops it.
    let t2 = r.now();
    r.send(r#"{"v":1,"cmd":"drive","heading":180}"#);
    run_for(1200).await;
    let w: Vec<_> = r.writes(0).into_iter().filter(|(t, _)| *t >= t2).collect();
    assert!(w.first().is_some_and(|(_, s)| *s == 70), "{w:?}");
    assert!(
        w.last().is_some_and(|(_, s)| *s == 0),
        "stopped by the timeout: {w:?}"
    );
    assert!(r.said().iter().any(|o| matches!(
        o,
        Out::Stopped {
            reason: "timeout",
            ..
        }
    )));
    // A held droid keeps its cruise speed and refuses the drive that would use it.
    r.send(r#"{"v":1,"cmd":"hold"}"#);
    run_for(200).await;
    r.said();
    let t3 = r.now();
    r.send(r#"{"v":1,"cmd":"drive","heading":0,"id":"d"}"#);
    run_for(500).await;
    assert!(r.writes(0).iter().all(|(t, s)| *t < t3 || *s == 0));
    let said = r.said();
    assert!(
        matches!(
            &said[..],
            [Out::Error {
                code: ErrorCode::Held,
                ..
            }]
        ),
        "{said:?}"
    );
    assert_eq!(r.bridge.cruise(0), 70);
}

#[tokio::test(start_paused = true)]
async fn an_animation_by_its_name_plays_and_is_kept_as_played() {
    let mut r = rig(&[Model::R2D2], 600).await;
    run_for(3000).await;
    r.said();
    assert!(r.bridge.played_state(0).is_empty());
    let t0 = r.now();
    r.send(r#"{"v":1,"cmd":"animation","animation":"Frustrated","id":"a"}"#);
    r.send(r#"{"v":1,"cmd":"sound","sound":"R2 BURNOUT"}"#);
    run_for(1500).await;
    let written: Vec<String> = r
        .labels(0)
        .into_iter()
        .filter(|(t, _)| *t >= t0)
        .map(|(_, l)| l)
        .collect();
    assert!(
        written
            .iter()
            .any(|l| l.to_lowercase().contains("animation"))
            && written.iter().any(|l| l.to_lowercase().contains("audio")),
        "{written:?}"
    );
    let said = r.said();
    let played: Vec<(&str, u16, Option<&str>)> = said
        .iter()
        .filter_map(|o| match o {
            Out::Played { what, id, name, .. } => Some((*what, *id, *name)),
            _ => None,
        })
        .collect();
    assert_eq!(
        played,
        [
            ("animation", 10, Some("Frustrated")),
            ("sound", 1915, Some("R2 Burnout"))
        ],
        "{said:?}"
    );
    assert_eq!(r.bridge.played_state(0).len(), 2);
    // A name the catalogue lacks is a bad field, and nothing is played.
    r.send(r#"{"v":1,"cmd":"animation","animation":"Moonwalk","id":"b"}"#);
    run_for(500).await;
    let said = r.said();
    assert!(
        matches!(&said[..], [Out::Error { code: ErrorCode::BadField, error, .. }] if error.contains("Moonwalk") && error.contains("Frustrated")),
        "{said:?}"
    );
}
