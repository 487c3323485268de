//! ROS over MQTT (issue 40 point 7): what the ROS-to-MQTT bridges people use send and take,
//! on two topics of each droid beside its droidctl ones.
//!
//! - `PREFIX/DROID/cmd_vel`, in: a `geometry_msgs/Twist` as those bridges publish it, no
//!   `v` or `cmd` around it: groove-x `mqtt_bridge`'s MessagePack (its default serializer,
//!   `msgpack.dumps` of the message's fields: [`super::msgpack`]) or JSON (`json:dumps`:
//!   `{"linear":{"x":…,"y":…,"z":…},"angular":{…}}`), and rosbridge's
//!   `{"op":"publish","topic":…,"msg":{Twist}}`. It becomes the bridge's `twist` command,
//!   with its checks (only `linear.x` and `angular.z` move a droid on the ground; anything
//!   else not 0 is a `bad_field` error) and its command timeout (600 ms: a ROS node
//!   publishes `cmd_vel` at 10 Hz or more). A full droidctl command (`v`, `cmd`) is taken
//!   too, as on `cmd`.
//! - `PREFIX/DROID/odom`, out: each telemetry sample with a position and a yaw as a
//!   `nav_msgs/Odometry` in JSON ([`Odometry`]): REP-103 axes and units, REP-105 frames
//!   (`header.frame_id` `odom`, `child_frame_id` `base_link`), the stamp the sample's time in
//!   epoch seconds and nanoseconds (ROS 2's `builtin_interfaces/Time` field names).
//!
//! Sans-IO: payloads in, [`super::schema::Request`] or JSON text out; the wall clock is
//! given.

use super::schema::{self, BadCommand, ErrorCode, MAX_COMMAND_BYTES, Out, Request};
use serde::Serialize;
use serde_json::{Map, Value, json};
use std::time::{Duration, SystemTime};

/// The topic leaf a Twist is taken on.
pub const CMD_VEL: &str = "cmd_vel";
/// The topic leaf odometry goes out on.
pub const ODOM: &str = "odom";
/// REP-105's frames: the fixed odometry frame and the droid's own.
pub const ODOM_FRAME: &str = "odom";
pub const BASE_FRAME: &str = "base_link";

fn refused(code: ErrorCode, message: impl Into<String>) -> Box<BadCommand> {
    Box::new(BadCommand {
        id: None,
        droid: None,
        cmd: Some("twist".into()),
        code,
        message: message.into(),
    })
}

/// One `cmd_vel` payload as the bridge's command: a bare Twist (MessagePack or JSON), a
/// rosbridge `publish` of one, or a droidctl command.
pub fn cmd_vel(payload: &[u8]) -> Result<Request, Box<BadCommand>> {
    if payload.len() > MAX_COMMAND_BYTES {
        return Err(refused(
            ErrorCode::BadJson,
            format!(
                "a cmd_vel payload of {} bytes: at most {MAX_COMMAND_BYTES}",
                payload.len()
            ),
        ));
    }
    let value = if super::msgpack::looks_like_map(payload) {
        super::msgpack::decode(payload).map_err(|e| {
            refused(
                ErrorCode::BadJson,
                format!("{e}: cmd_vel takes a geometry_msgs/Twist as MessagePack or JSON"),
            )
        })?
    } else {
        let text = payload.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(payload);
        serde_json::from_slice(text).map_err(|e| {
            refused(
                ErrorCode::BadJson,
                format!(
                    "not JSON ({e}) nor MessagePack: cmd_vel takes a geometry_msgs/Twist, \
                     e.g. {{\"linear\":{{\"x\":0.3}},\"angular\":{{\"z\":0.5}}}}"
                ),
            )
        })?
    };
    let Value::Object(obj) = value else {
        return Err(refused(
            ErrorCode::BadJson,
            "a Twist is an object: {\"linear\":{\"x\":…},\"angular\":{\"z\":…}}",
        ));
    };
    // A droidctl command: as on `cmd`.
    if obj.contains_key("cmd") || obj.contains_key("v") {
        return schema::parse(Value::Object(obj).to_string().as_bytes());
    }
    let twist = match obj.get("op") {
        None => obj,
        // rosbridge v2: {"op":"publish","topic":"/cmd_vel","msg":{…}} (the topic is
        // not checked: this MQTT topic says which droid).
        Some(Value::String(op)) if op == "publish" => match obj.get("msg") {
            Some(Value::Object(m)) => m.clone(),
            _ => {
                return Err(refused(
                    ErrorCode::BadField,
                    "a rosbridge publish without a \"msg\" object: \
                     {\"op\":\"publish\",\"topic\":\"/cmd_vel\",\"msg\":{\"linear\":…,\"angular\":…}}",
                ));
            }
        },
        Some(op) => {
            return Err(refused(
                ErrorCode::BadField,
                format!("rosbridge op {op} is not taken on cmd_vel: only \"publish\""),
            ));
        }
    };
    twist_command(&twist)
}

/// A Twist's fields as the bridge's `twist` command (missing vectors and components are 0).
fn twist_command(t: &Map<String, Value>) -> Result<Request, Box<BadCommand>> {
    if let Some(k) = t
        .keys()
        .find(|k| !matches!(k.as_str(), "linear" | "angular"))
    {
        return Err(refused(
            ErrorCode::BadField,
            format!("a geometry_msgs/Twist has no `{k}` (it has linear and angular, each x, y, z)"),
        ));
    }
    let part = |k: &str| t.get(k).cloned().unwrap_or_else(|| json!({}));
    let cmd = json!({"v": 1, "cmd": "twist", "linear": part("linear"), "angular": part("angular")});
    schema::parse(cmd.to_string().as_bytes())
}

/// `builtin_interfaces/Time`: seconds and nanoseconds since the epoch.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stamp {
    pub sec: u64,
    pub nanosec: u32,
}

impl Stamp {
    pub fn of(t: SystemTime) -> Stamp {
        let d = t.duration_since(SystemTime::UNIX_EPOCH).unwrap_or_default();
        Stamp {
            sec: d.as_secs(),
            nanosec: d.subsec_nanos(),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Header {
    pub stamp: Stamp,
    pub frame_id: &'static str,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pose {
    pub position: Vector3,
    pub orientation: Quaternion,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoseWithCovariance {
    pub pose: Pose,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Twist {
    pub linear: Vector3,
    pub angular: Vector3,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TwistWithCovariance {
    pub twist: Twist,
}

/// `nav_msgs/Odometry` as rosbridge's JSON conversion reads it: field for field, the
/// covariances left out (unknown; a conversion leaves them zero).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Odometry {
    pub header: Header,
    pub child_frame_id: &'static str,
    pub pose: PoseWithCovariance,
    pub twist: TwistWithCovariance,
}

/// One droid's odometry, from its telemetry samples: the yaw rate is the change of yaw
/// between two samples (the droids stream no yaw rate in the `odom` frame's sense).
#[derive(Debug, Clone)]
pub struct OdomTrack {
    /// The wall clock when the bridge's `t_ms` was 0.
    epoch: SystemTime,
    last: Option<(u64, f32)>,
}

impl OdomTrack {
    /// `epoch`: the wall clock at the bridge's `t_ms` 0.
    pub fn new(epoch: SystemTime) -> OdomTrack {
        OdomTrack { epoch, last: None }
    }

    /// The odometry of a telemetry object; `None` for anything else, and for a sample
    /// without a position or a yaw (an orientation made up would mislead a ROS node).
    pub fn odometry(&mut self, o: &Out) -> Option<Odometry> {
        let Out::Telemetry {
            sample,
            odom: Some(odom),
            ..
        } = o
        else {
            return None;
        };
        let yaw = odom.yaw_rad?;
        let yaw_rate = match self.last {
            Some((t0, y0)) if sample.t_ms > t0 => {
                let d = wrap(yaw - y0);
                f64::from(d) / ((sample.t_ms - t0) as f64 / 1000.0)
            }
            _ => 0.0,
        };
        self.last = Some((sample.t_ms, yaw));
        // Forward speed: the velocity along the heading where the droid streams one (it
        // is signed: a droid backing up goes negative), else its measured speed.
        let heading = sample
            .yaw_deg
            .or_else(|| sample.heading.map(f32::from))
            .unwrap_or(0.0)
            .to_radians();
        let forward_cm_s = match (sample.velocity_cm_s, sample.speed) {
            (Some([vx, vy]), _) => vx * heading.sin() + vy * heading.cos(),
            (None, Some(s)) => s,
            (None, None) => 0.0,
        };
        let half = f64::from(yaw) / 2.0;
        Some(Odometry {
            header: Header {
                stamp: Stamp::of(self.epoch + Duration::from_millis(sample.t_ms)),
                frame_id: ODOM_FRAME,
            },
            child_frame_id: BASE_FRAME,
            pose: PoseWithCovariance {
                pose: Pose {
                    position: Vector3 {
                        x: f64::from(odom.x_m),
                        y: f64::from(odom.y_m),
                        z: 0.0,
                    },
                    orientation: Quaternion {
                        x: 0.0,
                        y: 0.0,
                        z: half.sin(),
                        w: half.cos(),
                    },
                },
            },
            twist: TwistWithCovariance {
                twist: Twist {
                    linear: Vector3 {
                        x: f64::from(forward_cm_s) / 100.0,
                        y: 0.0,
                        z: 0.0,
                    },
                    angular: Vector3 {
                        x: 0.0,
                        y: 0.0,
                        z: yaw_rate,
                    },
                },
            },
        })
    }
}

/// An angle wrapped to −π..=π.
fn wrap(a: f32) -> f32 {
    let w = a.rem_euclid(std::f32::consts::TAU);
    if w > std::f32::consts::PI {
        w - std::f32::consts::TAU
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::schema::Cmd;

    fn twist_of(r: Result<Request, Box<BadCommand>>) -> (f32, f32) {
        match r.map(|r| r.cmd) {
            Ok(Cmd::Twist { linear, angular }) => (linear, angular),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_bare_twist_in_json_msgpack_and_rosbridge() {
        let json = br#"{"linear":{"x":0.3,"y":0.0,"z":0.0},"angular":{"x":0.0,"y":0.0,"z":-0.5}}"#;
        assert_eq!(twist_of(cmd_vel(json)), (0.3, -0.5));
        let mp = crate::bridge::msgpack::twist_bytes(0.25, 1.0);
        assert_eq!(twist_of(cmd_vel(&mp)), (0.25, 1.0));
        let rb = br#"{"op":"publish","topic":"/cmd_vel","msg":{"linear":{"x":-0.2},"angular":{"z":0.1}}}"#;
        assert_eq!(twist_of(cmd_vel(rb)), (-0.2, 0.1));
        // Missing parts are 0; a droidctl command is taken as on `cmd`.
        assert_eq!(twist_of(cmd_vel(br#"{"angular":{"z":1}}"#)), (0.0, 1.0));
        let full = cmd_vel(br#"{"v":1,"cmd":"stop","id":3}"#).unwrap();
        assert_eq!(full.cmd, Cmd::Stop);
    }

    #[test]
    fn what_a_ground_droid_cannot_do_and_what_is_no_twist_are_errors() {
        let e = cmd_vel(br#"{"linear":{"x":0.1,"z":0.5},"angular":{}}"#).unwrap_err();
        assert_eq!(e.code, ErrorCode::BadField);
        assert!(e.message.contains("linear.z"), "{}", e.message);
        let e = cmd_vel(br#"{"linear":{},"angular":{},"extra":1}"#).unwrap_err();
        assert!(e.message.contains("`extra`"), "{}", e.message);
        let e = cmd_vel(br#"{"op":"subscribe","topic":"/x"}"#).unwrap_err();
        assert_eq!(e.code, ErrorCode::BadField);
        let e = cmd_vel(b"linear: {x: 0.3}").unwrap_err();
        assert_eq!(e.code, ErrorCode::BadJson);
        let e = cmd_vel(&[0x82, 0xa6]).unwrap_err();
        assert_eq!(e.code, ErrorCode::BadJson);
        assert!(e.message.contains("MessagePack"), "{}", e.message);
        let e = cmd_vel(&vec![b' '; MAX_COMMAND_BYTES + 1]).unwrap_err();
        assert_eq!(e.code, ErrorCode::BadJson);
    }

    fn sample(t_ms: u64, x_cm: f32, y_cm: f32, yaw_deg: f32) -> Out {
        let s = serde_json::from_value(json!({"t_ms": t_ms, "x_cm": x_cm, "y_cm": y_cm,
            "speed": 50.0, "yaw_deg": yaw_deg, "collisions": 0}))
        .unwrap();
        crate::bridge::feeds::telemetry_out("BB-0001", s, None)
    }

    #[test]
    fn odometry_in_rep_103_axes_with_a_stamp_and_a_yaw_rate() {
        let epoch = SystemTime::UNIX_EPOCH + Duration::from_secs(1_700_000_000);
        let mut t = OdomTrack::new(epoch);
        // 1 m ahead (droidctl's +y), facing 90° clockwise (toward droidctl's +x: right).
        let o = t.odometry(&sample(1500, 0.0, 100.0, 0.0)).unwrap();
        assert_eq!(o.header.frame_id, "odom");
        assert_eq!(o.child_frame_id, "base_link");
        assert_eq!(
            o.header.stamp,
            Stamp {
                sec: 1_700_000_001,
                nanosec: 500_000_000
            }
        );
        assert!((o.pose.pose.position.x - 1.0).abs() < 1e-6);
        assert_eq!(o.pose.pose.orientation.w, 1.0);
        assert_eq!(o.twist.twist.angular.z, 0.0);
        assert!((o.twist.twist.linear.x - 0.5).abs() < 1e-6);
        // 0.5 s later, turned 90° clockwise: yaw −π/2 (REP-103: counter-clockwise is +),
        // at −π rad/s; 20 cm to the right is y −0.2.
        let o = t.odometry(&sample(2000, 20.0, 100.0, 90.0)).unwrap();
        assert!((o.pose.pose.position.y + 0.2).abs() < 1e-6);
        let q = o.pose.pose.orientation;
        assert!(
            (q.z + (std::f64::consts::FRAC_PI_4).sin()).abs() < 1e-6,
            "{q:?}"
        );
        assert!(
            (q.w - (std::f64::consts::FRAC_PI_4).cos()).abs() < 1e-6,
            "{q:?}"
        );
        let rate = o.twist.twist.angular.z;
        assert!((rate + std::f64::consts::PI).abs() < 1e-3, "{rate}");
        // Across ±π the rate is the short way round.
        let mut t = OdomTrack::new(epoch);
        t.odometry(&sample(0, 0.0, 0.0, 179.0));
        let o = t.odometry(&sample(100, 0.0, 0.0, -179.0 + 360.0)).unwrap();
        assert!(
            o.twist.twist.angular.z.abs() < 0.5,
            "{}",
            o.twist.twist.angular.z
        );
        // No yaw, no odometry; not telemetry, none.
        let s =
            serde_json::from_value(json!({"t_ms": 0, "x_cm": 1.0, "y_cm": 1.0, "collisions": 0}))
                .unwrap();
        assert!(
            t.odometry(&crate::bridge::feeds::telemetry_out("B", s, None))
                .is_none()
        );
        assert!(t.odometry(&crate::bridge::feeds::offline("B")).is_none());
    }
}
