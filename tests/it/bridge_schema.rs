//! The bridge's JSON Schema (`assets/bridge.schema.json`) and the bridge agree, both ways
//! (issue 20 point 1): every command the schema accepts the bridge parses and every one it
//! refuses the bridge refuses; every object the bridge sends on simulated droids (hello,
//! telemetry, collision, battery, link, stopped, reply, error, the MQTT last will) is valid
//! against the schema. Validated with the `jsonschema` crate (draft 2020-12).

use droidctl::bridge::schema::{self, Out};
use droidctl::bridge::{Bridge, Settings, stdio};
use droidctl::model::Model;
use serde_json::{Value, json};
use std::time::Duration;
use tokio::io::{AsyncBufReadExt, AsyncWriteExt};
use tokio::time::{Instant, sleep};

fn schema_doc() -> Value {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/bridge.schema.json");
    serde_json::from_str(&std::fs::read_to_string(path).expect("the schema file")).expect("JSON")
}

/// A validator for one of the schema's definitions (`command`, `out`).
pub(crate) fn validator(def: &str) -> jsonschema::Validator {
    let mut doc = schema_doc();
    let root = doc.as_object_mut().unwrap();
    root.remove("anyOf");
    root.insert("$ref".into(), json!(format!("#/$defs/{def}")));
    jsonschema::draft202012::new(&doc).expect("a valid JSON Schema")
}

pub(crate) fn errors(v: &jsonschema::Validator, x: &Value) -> String {
    v.iter_errors(x)
        .map(|e| format!("{} at {}", e, e.instance_path()))
        .collect::<Vec<_>>()
        .join("; ")
}

#[test]
fn the_schema_is_valid_and_takes_the_readme_examples() {
    let commands = validator("command");
    for c in [
        json!({"v":1,"cmd":"drive","speed":100,"heading":90}),
        json!({"v":1,"cmd":"twist","linear":0.3,"angular":0.5}),
        // ROS's geometry_msgs/Twist (issue 31 point 5).
        json!({"v":1,"cmd":"twist","linear":{"x":0.3,"y":0,"z":0},"angular":{"x":0,"y":0.0,"z":-0.5}}),
        json!({"v":1,"cmd":"twist","linear":{"x":0.3},"angular":0.5}),
        json!({"v":1,"cmd":"stop"}),
        json!({"v":1,"cmd":"estop"}),
        json!({"v":1,"cmd":"hold","droid":"D2-0001","id":"h"}),
        json!({"v":1,"cmd":"release"}),
        json!({"v":1,"cmd":"head","angle":-45.5,"droid":"D2-0001"}),
        json!({"v":1,"cmd":"stance","stance":"bipod","id":"s1"}),
        json!({"v":1,"cmd":"lights","group":"front","rgb":[255,0,0],"id":7}),
        json!({"v":1,"cmd":"lights","group":"logic","brightness":200}),
        json!({"v":1,"cmd":"animation","animation":3}),
        json!({"v":1,"cmd":"sound","sound":12}),
        // The catalogue's names, as Home Assistant's selects send them (issue 40 point 5).
        json!({"v":1,"cmd":"animation","animation":"Frustrated"}),
        json!({"v":1,"cmd":"sound","sound":"r2 burnout"}),
        // The cruise speed, and a drive at it (Home Assistant's Speed and Heading numbers).
        json!({"v":1,"cmd":"cruise","speed":120,"id":"c"}),
        json!({"v":1,"cmd":"drive","heading":90}),
        json!({"v":1,"cmd":"matrix","op":"text","text":"HELLO","rgb":[0,255,0]}),
        json!({"v":1,"cmd":"matrix","op":"char","char":"A"}),
        json!({"v":1,"cmd":"matrix","op":"fill","rgb":[0,0,255]}),
        json!({"v":1,"cmd":"matrix","op":"pixel","x":7,"y":0}),
        json!({"v":1,"cmd":"matrix","op":"clear"}),
        json!({"v":1,"cmd":"matrix","op":"rotate","degrees":90}),
        json!({"v":1,"cmd":"stream","rate_hz":20,"sensors":["attitude","gyro"]}),
        json!({"v":1,"cmd":"stream","rate_hz":0}),
        // Python's json writes floats: an integral one is an integer to both.
        json!({"v":1,"cmd":"drive","speed":100.0,"heading":90}),
    ] {
        assert!(commands.is_valid(&c), "{c}: {}", errors(&commands, &c));
        let parsed = schema::parse(c.to_string().as_bytes());
        assert!(parsed.is_ok(), "{c}: {parsed:?}");
    }
}

#[test]
fn what_the_schema_refuses_the_bridge_refuses() {
    let commands = validator("command");
    for c in [
        json!({"cmd":"stop"}),
        json!({"v":2,"cmd":"stop"}),
        json!({"v":1}),
        json!({"v":1,"cmd":"fly"}),
        json!({"v":1,"cmd":"drive","speed":256,"heading":0}),
        json!({"v":1,"cmd":"drive","speed":-1,"heading":0}),
        json!({"v":1,"cmd":"drive","speed":1.5,"heading":0}),
        json!({"v":1,"cmd":"drive","speed":10,"heading":360}),
        json!({"v":1,"cmd":"drive","speed":10}),
        json!({"v":1,"cmd":"drive","speed":10,"heading":0,"sped":1}),
        json!({"v":1,"cmd":"drive","speed":"10","heading":0}),
        json!({"v":1,"cmd":"twist","linear":6,"angular":0}),
        json!({"v":1,"cmd":"twist","linear":0.1}),
        json!({"v":1,"cmd":"twist","linear":{"x":0.1,"y":0.2},"angular":0}),
        json!({"v":1,"cmd":"twist","linear":{"x":0,"z":1},"angular":0}),
        json!({"v":1,"cmd":"twist","linear":0,"angular":{"x":0.1,"z":0}}),
        json!({"v":1,"cmd":"twist","linear":{"x":6},"angular":0}),
        json!({"v":1,"cmd":"twist","linear":{"x":"1"},"angular":0}),
        json!({"v":1,"cmd":"twist","linear":{"w":1},"angular":0}),
        json!({"v":1,"cmd":"stop","speed":0}),
        json!({"v":1,"cmd":"hold","speed":0}),
        json!({"v":1,"cmd":"release","held":false}),
        json!({"v":1,"cmd":"stop","droid":""}),
        json!({"v":1,"cmd":"stop","id":[1]}),
        json!({"v":1,"cmd":"stop","id":1.5}),
        json!({"v":1,"cmd":"head","angle":-170}),
        json!({"v":1,"cmd":"stance","stance":"sit"}),
        json!({"v":1,"cmd":"lights","group":"front"}),
        json!({"v":1,"cmd":"lights","group":"front","rgb":[1,2,3],"brightness":4}),
        json!({"v":1,"cmd":"lights","group":"top","brightness":4}),
        json!({"v":1,"cmd":"lights","group":"front","rgb":[1,2]}),
        json!({"v":1,"cmd":"lights","group":"front","rgb":[1,2,256]}),
        json!({"v":1,"cmd":"animation","animation":65536}),
        json!({"v":1,"cmd":"animation","animation":""}),
        json!({"v":1,"cmd":"sound","sound":null}),
        json!({"v":1,"cmd":"cruise","speed":256}),
        json!({"v":1,"cmd":"cruise"}),
        json!({"v":1,"cmd":"cruise","speed":10,"heading":0}),
        json!({"v":1,"cmd":"matrix","op":"text","text":""}),
        json!({"v":1,"cmd":"matrix","op":"text","text":"abcdefghijklmnopqrstuvwxyz"}),
        json!({"v":1,"cmd":"matrix","op":"text","text":"é"}),
        json!({"v":1,"cmd":"matrix","op":"char","char":"AB"}),
        json!({"v":1,"cmd":"matrix","op":"char","char":" "}),
        json!({"v":1,"cmd":"matrix","op":"fill"}),
        json!({"v":1,"cmd":"matrix","op":"pixel","x":8,"y":0}),
        json!({"v":1,"cmd":"matrix","op":"clear","rgb":[1,1,1]}),
        json!({"v":1,"cmd":"matrix","op":"rotate","degrees":45}),
        json!({"v":1,"cmd":"matrix","op":"spin"}),
        json!({"v":1,"cmd":"stream","rate_hz":101}),
        json!({"v":1,"cmd":"stream","rate_hz":10,"sensors":["sonar"]}),
        json!({"v":1,"cmd":"stream","rate_hz":10,"sensors":"gyro"}),
        json!([1, 2]),
        json!("drive"),
    ] {
        assert!(!commands.is_valid(&c), "the schema takes {c}");
        let parsed = schema::parse(c.to_string().as_bytes());
        assert!(parsed.is_err(), "the bridge takes {c}: {parsed:?}");
        let e = parsed.unwrap_err();
        // The error object made of it is valid too.
        let out = validator("out");
        let o: Value = serde_json::from_str(&Out::error(*e).to_json()).unwrap();
        assert!(out.is_valid(&o), "{o}: {}", errors(&out, &o));
    }
}

/// Every line a bridge on simulated droids writes, over stdio under paused time: a
/// session that drives into a wall, asks for lights and what a robot lacks, sends bad lines,
/// lets the command timeout stop one droid, and ends its input.
async fn a_session() -> Vec<Value> {
    let models = [Model::R2D2, Model::BB8, Model::Robi42, Model::Bolt];
    let config = droidctl::config::Config::defaults();
    let found = droidctl::cli::fleet::simulated(&models);
    let specs = found
        .into_iter()
        .map(|f| {
            let s = droidctl::cli::fleet::session_config(f.model, &config, true);
            f.into_spec(s)
        })
        .collect();
    let fleet = droidctl::fleet::Fleet::start(specs);
    let setups = models
        .iter()
        .map(|m| droidctl::family::setup::from_config(*m, &config).0)
        .collect();
    let settings = Settings {
        battery_poll: Duration::from_secs(2),
        ..Settings::default()
    };
    let (bridge, rx) = Bridge::start(fleet, setups, settings);
    let (client, server) = tokio::io::duplex(1 << 20);
    let (server_in, server_out) = tokio::io::split(server);
    let task = tokio::spawn(stdio::run(
        bridge,
        rx,
        tokio::io::BufReader::new(server_in),
        server_out,
        std::future::pending(),
    ));
    let (client_in, mut client_out) = tokio::io::split(client);
    let reader = tokio::spawn(async move {
        let mut lines = Vec::new();
        let mut r = tokio::io::BufReader::new(client_in);
        let mut l = String::new();
        while r.read_line(&mut l).await.unwrap_or(0) > 0 {
            lines.push(std::mem::take(&mut l));
        }
        lines
    });
    let mut send = async |line: &str| {
        client_out.write_all(line.as_bytes()).await.unwrap();
        client_out.write_all(b"\n").await.unwrap();
    };
    sleep(Duration::from_secs(1)).await;
    send(r#"{"v":1,"cmd":"lights","droid":"D2-0001","group":"front","rgb":[0,0,255],"id":"l1"}"#)
        .await;
    send(r#"{"v":1,"cmd":"stream","droid":"D2-0001","rate_hz":50,"id":2}"#).await;
    send(r#"{"v":1,"cmd":"head","droid":"BB-0002","angle":10,"id":3}"#).await;
    send(r#"{"v":1,"cmd":"drive","droid":"nobody","speed":1,"heading":0}"#).await;
    send("{\"v\":1,").await;
    // BB-8 rolls into the wall, R2 turns and stops by the timeout.
    let end = Instant::now() + Duration::from_secs(6);
    while Instant::now() < end {
        send(r#"{"v":1,"cmd":"drive","droid":"BB-0002","speed":255,"heading":0}"#).await;
        sleep(Duration::from_millis(200)).await;
    }
    // A latched stop: the next drive is refused (code held) until released.
    send(r#"{"v":1,"cmd":"hold","droid":"BB-0002","id":"h1"}"#).await;
    send(r#"{"v":1,"cmd":"drive","droid":"BB-0002","speed":255,"heading":0,"id":"h2"}"#).await;
    send(r#"{"v":1,"cmd":"release","droid":"BB-0002","id":"h3"}"#).await;
    // A cruise speed, and what R2 played by its catalogue name (issue 40 point 5).
    send(r#"{"v":1,"cmd":"cruise","droid":"BB-0002","speed":60,"id":"c1"}"#).await;
    send(r#"{"v":1,"cmd":"drive","droid":"BB-0002","heading":180,"id":"c2"}"#).await;
    send(r#"{"v":1,"cmd":"animation","droid":"D2-0001","animation":"frustrated","id":"a1"}"#).await;
    sleep(Duration::from_secs(1)).await;
    send(r#"{"v":1,"cmd":"twist","droid":"D2-0001","linear":0.2,"angular":0.3}"#).await;
    sleep(Duration::from_secs(1)).await;
    send(r#"{"v":1,"cmd":"drive","droid":"robi","speed":40,"heading":0}"#).await;
    // The end of input (a half's drop is not: the duplex ends when both halves go).
    client_out.shutdown().await.unwrap();
    let end = task.await.unwrap();
    assert_eq!(end, stdio::End::InputClosed);
    reader
        .await
        .unwrap()
        .iter()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}")))
        .collect()
}

#[tokio::test(start_paused = true)]
async fn everything_the_bridge_sends_is_valid_against_the_schema() {
    let out = validator("out");
    let lines = a_session().await;
    let mut seen = std::collections::BTreeSet::new();
    for v in &lines {
        assert!(out.is_valid(v), "{v}: {}", errors(&out, v));
        seen.insert(v["type"].as_str().unwrap().to_string());
    }
    for t in [
        "hello",
        "info",
        "telemetry",
        "collision",
        "battery",
        "link",
        "hold",
        "cruise",
        "played",
        "stopped",
        "reply",
        "error",
    ] {
        assert!(
            seen.contains(t),
            "no {t} object in {} lines: {seen:?}",
            lines.len()
        );
    }
    assert_eq!(lines[0]["type"], "hello");
    let held = lines
        .iter()
        .find(|v| v["id"] == "h2")
        .expect("the held drive's answer");
    assert_eq!(
        (&held["type"], &held["code"]),
        (&json!("error"), &json!("held"))
    );
    let holds: Vec<&Value> = lines.iter().filter(|v| v["type"] == "hold").collect();
    assert_eq!(holds.len(), 2, "held, then released: {holds:?}");
    assert_eq!(
        (&holds[0]["held"], &holds[1]["held"]),
        (&json!(true), &json!(false))
    );
    let cruise: Vec<&Value> = lines.iter().filter(|v| v["type"] == "cruise").collect();
    assert_eq!(cruise.len(), 1, "{cruise:?}");
    assert_eq!(
        (&cruise[0]["droid"], &cruise[0]["speed"]),
        (&json!("BB-0002"), &json!(60))
    );
    let played = lines
        .iter()
        .find(|v| v["type"] == "played")
        .expect("R2's animation said played");
    assert_eq!(
        (&played["what"], &played["id"], &played["name"]),
        (&json!("animation"), &json!(10), &json!("Frustrated"))
    );
    // Readiness and odometry (issue 31 points 3 and 5).
    assert!(
        lines
            .iter()
            .any(|v| v["type"] == "link" && v["ready"] == true)
    );
    assert!(lines.iter().any(|v| v["odom"]["x_m"].is_number()));
    // The capped streaming rate is said in the reply.
    let r2 = lines
        .iter()
        .find(|v| v["type"] == "reply" && v["id"] == 2)
        .expect("the stream reply");
    assert!(
        r2["note"].as_str().is_some_and(|n| n.contains("capped")),
        "{r2}"
    );
    // Robi's samples carry its wheels; the others' do not.
    assert!(
        lines
            .iter()
            .any(|v| v["droid"] == "Robi 42" && v["motor_left_rad_s"].is_number())
    );
    // The will is valid too, and the objects of issue 26 (a retained command refused, a
    // drive let go when the link dropped).
    use droidctl::bridge::schema::{ErrorCode, Out};
    for o in [
        droidctl::bridge::feeds::offline("D2-0001"),
        Out::Error {
            id: None,
            droid: Some("BB-0001".into()),
            cmd: None,
            code: ErrorCode::Retained,
            robot: None,
            capability: None,
            error: "a retained message".into(),
        },
        Out::Stopped {
            droid: "D2-0001".into(),
            reason: "link_lost",
            message: "the link went down".into(),
        },
    ] {
        let v: Value = serde_json::from_str(&o.to_json()).unwrap();
        assert!(out.is_valid(&v), "{v}: {}", errors(&out, &v));
    }
    // Each kind of stop happened.
    for reason in ["timeout", "input_closed"] {
        assert!(
            lines
                .iter()
                .any(|v| v["type"] == "stopped" && v["reason"] == reason),
            "no stop for {reason}"
        );
    }
}

/// What only MQTT carries (the retained collision count, a bridge's availability) and Home
/// Assistant's JSON light (its command and the state the bridge retains) agree with the
/// schema (issue 40).
#[test]
fn mqtt_only_objects_and_the_home_assistant_light_are_valid() {
    use droidctl::bridge::{ha_light::Light, kept::Kept, presence};
    let out = validator("out");
    let k = Kept::new(1);
    let mut objects: Vec<String> = vec![
        presence::state_json("pi-lab-1", true),
        presence::state_json("pi-lab-1", false),
    ];
    objects.extend(
        k.at_connect(0, "D2-0001", false)
            .into_iter()
            .map(|(_, p)| p),
    );
    for o in &objects {
        let v: Value = serde_json::from_str(o).unwrap();
        assert!(out.is_valid(&v), "{v}: {}", errors(&out, &v));
    }
    let (cmd, state) = (
        validator("homeassistant_light_command"),
        validator("homeassistant_light_state"),
    );
    let mut l = Light::default();
    for c in [
        json!({"state":"ON"}),
        json!({"state":"ON","brightness":77}),
        json!({"state":"ON","color":{"r":10,"g":20,"b":30}}),
        json!({"state":"OFF"}),
    ] {
        assert!(cmd.is_valid(&c), "{c}: {}", errors(&cmd, &c));
        l = l.apply(c.to_string().as_bytes()).unwrap();
        let s: Value = serde_json::from_str(&l.state()).unwrap();
        assert!(state.is_valid(&s), "{s}: {}", errors(&state, &s));
    }
    for c in [
        json!({"brightness":3}),
        json!({"state":"ON","brightness":256}),
    ] {
        assert!(!cmd.is_valid(&c), "the schema takes {c}");
        assert!(
            l.apply(c.to_string().as_bytes()).is_err(),
            "the bridge takes {c}"
        );
    }
}

/// Issue 40 point 7: the ROS shapes on `cmd_vel` (`ros_twist`) and `odom`
/// (`ros_odometry`): what the schema takes the bridge takes, and the bridge's odometry is
/// valid against it.
#[test]
fn the_ros_shapes_agree_with_the_schema() {
    use droidctl::bridge::ros;
    let twists = validator("ros_twist");
    for t in [
        json!({"linear":{"x":0.3,"y":0.0,"z":0.0},"angular":{"x":0.0,"y":0.0,"z":-0.5}}),
        json!({"angular":{"z":1}}),
        json!({}),
        json!({"op":"publish","topic":"/cmd_vel","msg":{"linear":{"x":0.2},"angular":{"z":0.1}}}),
    ] {
        assert!(twists.is_valid(&t), "{t}: {}", errors(&twists, &t));
        let parsed = ros::cmd_vel(t.to_string().as_bytes());
        assert!(parsed.is_ok(), "{t}: {parsed:?}");
    }
    for t in [
        json!({"linear":{"x":0.3},"angular":{"z":0.5},"extra":1}),
        json!({"linear":{"w":0.3}}),
        json!({"op":"publish","topic":"/cmd_vel"}),
        json!({"op":"subscribe","msg":{}}),
    ] {
        assert!(!twists.is_valid(&t), "the schema takes {t}");
        assert!(
            ros::cmd_vel(t.to_string().as_bytes()).is_err(),
            "the bridge takes {t}"
        );
    }
    let odometry = validator("ros_odometry");
    let mut track = ros::OdomTrack::new(std::time::SystemTime::now());
    for (t_ms, yaw) in [(0u64, 10.0f32), (100, 30.0), (200, 350.0)] {
        let sample: droidctl::mission::Sample = serde_json::from_value(json!({"t_ms": t_ms,
            "x_cm": 12.0, "y_cm": -3.0, "speed": 20.0, "yaw_deg": yaw, "collisions": 0,
            "velocity_cm_s": [3.0, -20.0]}))
        .unwrap();
        let o = droidctl::bridge::feeds::telemetry_out("BB-0001", sample, None);
        let od = serde_json::to_value(track.odometry(&o).expect("odometry")).unwrap();
        assert!(odometry.is_valid(&od), "{od}: {}", errors(&odometry, &od));
    }
}
