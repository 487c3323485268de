//! A ROS `cmd_vel` payload as a ROS-to-MQTT bridge sends it (issue 40 point 7): any bytes,
//! read as MessagePack or JSON by [`crate::bridge::ros::cmd_vel`]. Whatever the input:
//! nothing panics; MessagePack that decodes is JSON that re-encodes and decodes to the same
//! value (finite numbers, string keys), nested at most [`msgpack::MAX_DEPTH`]; a payload
//! taken is a twist within the schema's ranges (or another command, parsed as on `cmd`),
//! and a payload refused is one error with a code and a message.
//!
//! Input layout: the payload, as delivered.

use super::Target;
use crate::bridge::msgpack;
use crate::bridge::ros;
use crate::bridge::schema::Cmd;

pub const TARGET: Target = Target {
    name: "ros",
    run: run_input,
    dictionary: &[
        b"\x82\xa6linear\x83\xa1x\xcb",
        b"\xa7angular\x83\xa1x\xcb\x00\x00\x00\x00\x00\x00\x00\x00",
        b"\xa1z\xcb\x3f\xe0\x00\x00\x00\x00\x00\x00",
        b"{\"linear\":{\"x\":0.3},\"angular\":{\"z\":-0.5}}",
        b"{\"op\":\"publish\",\"topic\":\"/cmd_vel\",\"msg\":",
        b"\xde\xff\xff",
        b"\xdd\xff\xff\xff\xff",
        b"\xca\x7f\xc0\x00\x00",
    ],
};

fn depth(v: &serde_json::Value) -> usize {
    match v {
        serde_json::Value::Array(a) => 1 + a.iter().map(depth).max().unwrap_or(0),
        serde_json::Value::Object(o) => 1 + o.values().map(depth).max().unwrap_or(0),
        _ => 0,
    }
}

pub fn run_input(data: &[u8]) {
    if let Ok(v) = msgpack::decode(data) {
        assert!(depth(&v) <= msgpack::MAX_DEPTH, "nested past the bound");
        let text = v.to_string();
        let back: serde_json::Value = serde_json::from_str(&text).expect("JSON it wrote");
        assert_eq!(
            back, v,
            "MessagePack decoded to JSON that reads back the same"
        );
    }
    match ros::cmd_vel(data) {
        Ok(r) => {
            if let Cmd::Twist { linear, angular } = r.cmd {
                assert!(linear.is_finite() && linear.abs() <= 5.0, "linear {linear}");
                assert!(
                    angular.is_finite() && angular.abs() <= 20.0,
                    "angular {angular}"
                );
            }
        }
        Err(e) => assert!(!e.message.is_empty(), "an error says why"),
    }
}
