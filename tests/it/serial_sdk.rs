//! Judged by the field: Sphero's own RVR SDK for Python (`sphero-sdk` 0.3.4 on PyPI,
//! `SpheroRvrAsync` with `SerialAsyncDal` over pyserial — what a Raspberry Pi on RVR's UART
//! runs) drives `droidctl sim --serial rvr` on its pseudo-terminal: wake, drive with a
//! heading, raw motors, LEDs, the battery, sensor streaming, infrared and colour detection
//! (tests/sphero_sdk_rvr.py). Every packet the SDK sends must be a command droidctl names, and
//! every one that asks for an answer must get a successful one.
//!
//! The SDK needs no Raspberry Pi library, so nothing is stood in for. It is installed by
//! `.ci/run` into `target/sphero-sdk-venv` and found through
//! `DROIDCTL_TEST_SPHERO_SDK_PYTHON`; without it the test says it is skipped.

#![cfg(unix)]

use crate::common::serial_sim::SerialSim;
use serde_json::Value;
use std::collections::BTreeSet;
use std::process::Command;

/// The Python with `sphero_sdk` importable, or why there is none.
fn sdk_python() -> Result<String, String> {
    crate::common::python::Library::SpheroSdk.python("sphero_sdk, serial, serial_asyncio")
}

fn script() -> String {
    format!("{}/tests/sphero_sdk_rvr.py", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn spheros_rvr_sdk_drives_the_simulated_rvr_on_its_serial_port() {
    let py = match sdk_python() {
        Ok(py) => py,
        Err(why) => {
            println!("SKIPPED spheros_rvr_sdk_drives_the_simulated_rvr_on_its_serial_port: {why}");
            return;
        }
    };
    let mut sim = SerialSim::start();
    let out = Command::new(&py)
        .arg(script())
        .arg(&sim.path)
        .output()
        .expect("run the SDK");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    let steps: Vec<Value> = stdout
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect();
    assert!(
        out.status.success(),
        "the SDK's run failed:\n{stdout}\n{stderr}\nsimulator:\n{}",
        sim.stderr()
    );
    let done: BTreeSet<&str> = steps
        .iter()
        .filter(|s| s["ok"] == true)
        .filter_map(|s| s["step"].as_str())
        .collect();
    for step in [
        "echo",
        "wake",
        "version nordic",
        "version st",
        "battery percentage",
        "battery volts",
        "drive with heading",
        "raw motors",
        "stop",
        "streamed imu",
        "streamed locator",
        "streamed ambient light",
        "set all leds",
        "bot to bot infrared readings",
        "enable color detection",
        "rgbc sensor values",
        "ambient light",
        "color notifications",
    ] {
        assert!(done.contains(step), "{step} did not succeed:\n{stdout}");
    }
    assert_eq!(sim.interrupt(), Some(0), "{}", sim.stderr());

    // Every packet the SDK sent: a command droidctl names, whole, and answered when it asked.
    let packets = sim.packets();
    let ins: Vec<&Value> = packets
        .iter()
        .filter(|(d, _)| d == "in")
        .map(|(_, p)| p)
        .collect();
    let outs: Vec<&Value> = packets
        .iter()
        .filter(|(d, _)| d == "out")
        .map(|(_, p)| p)
        .collect();
    assert!(ins.len() > 30, "{} packets in", ins.len());
    let mut names = BTreeSet::new();
    for p in &ins {
        assert_eq!(p["kind"], "command", "{p}");
        assert_eq!(p["checksum_ok"], true, "{p}");
        assert!(p["problem"].is_null(), "{p}");
        let name = p["command"]
            .as_str()
            .unwrap_or_else(|| panic!("an unnamed command: {p}"));
        names.insert(name.to_string());
        // On the UART the SDK addresses RVR's processors as 0x01 and 0x02, with no source.
        assert!(matches!(p["tid"].as_u64(), Some(1 | 2)), "{p}");
        assert!(p["sid"].is_null(), "{p}");
        let asks = p["flag_names"]
            .as_array()
            .is_some_and(|f| f.iter().any(|n| n == "requests_response"));
        if asks {
            let answer = outs.iter().find(|r| {
                r["kind"] == "response"
                    && r["did"] == p["did"]
                    && r["cid"] == p["cid"]
                    && r["seq"] == p["seq"]
            });
            let answer = answer.unwrap_or_else(|| panic!("unanswered: {p}"));
            assert!(answer["err"].is_null() || answer["err"] == 0, "{answer}");
            // The answer comes from the processor asked.
            assert_eq!(answer["sid"], p["tid"], "{answer}");
        }
    }
    for name in [
        "wake",
        "drive-with-heading",
        "set-raw-motors",
        "reset-yaw",
        "set-all-leds-with-32-bit-mask",
        "get-battery-percentage",
        "get-battery-voltage-in-volts",
        "configure-streaming-service",
        "start-streaming-service",
        "clear-streaming-service",
        "start-robot-to-robot-ir-broadcasting",
        "start-robot-to-robot-ir-following",
        "enable-robot-ir-message-notify",
        "send-infrared-message",
        "enable-color-detection",
        "enable-color-detection-notify",
        "get-rgbc-sensor-values",
        "get-ambient-light-sensor-value",
    ] {
        assert!(names.contains(name), "the SDK sent no {name}: {names:?}");
    }
    // And what it waited for came: streaming data from both processors, colour detections.
    let notified: BTreeSet<(String, u64)> = outs
        .iter()
        .filter(|p| p["kind"] == "notification")
        .filter_map(|p| Some((p["command"].as_str()?.to_string(), p["sid"].as_u64()?)))
        .collect();
    for want in [
        ("streaming-service-data".to_string(), 1),
        ("streaming-service-data".to_string(), 2),
        ("color-detection".to_string(), 1),
    ] {
        assert!(notified.contains(&want), "{want:?} not in {notified:?}");
    }
}
