//! ROS over MQTT (issue 40 point 7), as the ROS-to-MQTT bridges send and read it, through
//! droidctl's own broker and mosquitto: a bare `geometry_msgs/Twist` on
//! `droidctl/DROID/cmd_vel` in groove-x `mqtt_bridge`'s two serializations (its default
//! MessagePack, `msgpack.dumps` of the message's fields, and `json:dumps`) and rosbridge's
//! `{"op":"publish",…}` drives a simulated droid, and `droidctl/DROID/odom` says so as a
//! `nav_msgs/Odometry` (valid against the schema's `ros_odometry`).

use crate::common::bridge_proc::{BridgeProc, scratch};
use crate::common::mosquitto::{self, Broker, Kind, Sub, mosquitto_here, publish};
use serde_json::{Value, json};
use std::time::{Duration, Instant, SystemTime};

/// groove-x `mqtt_bridge` with `serializer: json:dumps`: Python's `json.dumps` of the
/// fields (floats written with a point, spaces after separators).
fn json_twist(linear_x: f64, angular_z: f64) -> String {
    format!(
        "{{\"linear\": {{\"x\": {linear_x:?}, \"y\": 0.0, \"z\": 0.0}}, \"angular\": {{\"x\": 0.0, \"y\": 0.0, \"z\": {angular_z:?}}}}}"
    )
}

fn lin(v: &Value) -> f64 {
    v["twist"]["twist"]["linear"]["x"].as_f64().unwrap_or(0.0)
}

fn ang(v: &Value) -> f64 {
    v["twist"]["twist"]["angular"]["z"].as_f64().unwrap_or(0.0)
}

/// Send `payload` to `topic` at 10 Hz for `ms`, as a ROS node publishes `cmd_vel`.
fn stream(port: u16, topic: &str, payload: &[u8], ms: u64) {
    let end = Instant::now() + Duration::from_millis(ms);
    while Instant::now() < end {
        assert!(mosquitto::publish_bytes(port, topic, payload, false, &[]));
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn ros_twists_drive_and_odometry_follows_through_droidctls_broker() {
    ros_twists_drive_and_odometry_follows(Kind::Embedded);
}

#[test]
fn ros_twists_drive_and_odometry_follows_through_mosquitto() {
    if mosquitto_here() {
        ros_twists_drive_and_odometry_follows(Kind::Mosquitto);
    }
}

fn ros_twists_drive_and_odometry_follows(kind: Kind) {
    let dir = scratch(&format!("ros-{kind:?}"));
    let broker = Broker::start_kind(&dir, kind);
    let p = broker.port;
    let sub = Sub::start(p, "droidctl/BB-0001/#", &[]);
    let _bridge = BridgeProc::start(
        &dir,
        &["--mqtt", &broker.url(), "--sim", "bb8", "--rate", "20"],
    );
    sub.wait(20, "droidctl/BB-0001/state", |v| v["ready"] == true);
    let cmd_vel = "droidctl/BB-0001/cmd_vel";
    let odom = "droidctl/BB-0001/odom";
    // Standing: odometry already, every field as nav_msgs/Odometry has it.
    let o = sub.wait(10, odom, |_| true);
    let schema = crate::bridge_schema::validator("ros_odometry");
    assert!(
        schema.is_valid(&o),
        "{o}: {}",
        crate::bridge_schema::errors(&schema, &o)
    );
    assert_eq!(o["header"]["frame_id"], "odom");
    assert_eq!(o["child_frame_id"], "base_link");
    let now = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64();
    let stamp = o["header"]["stamp"]["sec"].as_f64().unwrap()
        + o["header"]["stamp"]["nanosec"].as_f64().unwrap() / 1e9;
    assert!(
        (now - stamp).abs() < 30.0,
        "the stamp is the wall clock: {stamp} vs {now}"
    );
    // groove-x json:dumps: forward at 0.6 m/s, then odometry says it rolls forward.
    stream(p, cmd_vel, json_twist(0.6, 0.0).as_bytes(), 1500);
    let o = sub.wait(5, odom, |v| lin(v) > 0.2);
    assert!(schema.is_valid(&o), "{o}");
    // groove-x's default, MessagePack: turning left (counter-clockwise, angular.z > 0).
    stream(
        p,
        cmd_vel,
        &droidctl::bridge::msgpack::twist_bytes(0.3, 1.5),
        1500,
    );
    let o = sub.wait(5, odom, |v| ang(v) > 0.3);
    let q = &o["pose"]["pose"]["orientation"];
    let norm: f64 = ["x", "y", "z", "w"]
        .iter()
        .map(|k| q[k].as_f64().unwrap().powi(2))
        .sum();
    assert!((norm - 1.0).abs() < 1e-3, "a unit quaternion: {q}");
    // rosbridge's publish: turning right.
    let rb = json!({"op":"publish","topic":"/cmd_vel",
        "msg":{"linear":{"x":0.3,"y":0.0,"z":0.0},"angular":{"x":0.0,"y":0.0,"z":-1.5}}});
    stream(p, cmd_vel, rb.to_string().as_bytes(), 1500);
    sub.wait(5, odom, |v| ang(v) < -0.3);
    // Silence: the command timeout stops it, said on the reply topic.
    let s = sub.wait(5, "droidctl/BB-0001/reply", |v| v["type"] == "stopped");
    assert_eq!(s["reason"], "timeout");
    // What no ground droid can do, and what is not a Twist: errors on the reply topic.
    assert!(publish(p, cmd_vel, r#"{"linear":{"x":0.1,"z":1.0}}"#, &[]));
    let e = sub.wait(5, "droidctl/BB-0001/reply", |v| v["type"] == "error");
    assert_eq!(e["code"], "bad_field", "{e}");
    assert!(mosquitto::publish_bytes(
        p,
        cmd_vel,
        &[0x82, 0xa6, b'l'],
        false,
        &[]
    ));
    let e = sub.wait(5, "droidctl/BB-0001/reply", |v| v["type"] == "error");
    assert_eq!(e["code"], "bad_json", "{e}");
    assert!(e["error"].as_str().unwrap().contains("MessagePack"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
