//! The `[bridge]` table (issue 20): what `droidctl bridge` uses unless its options say
//! otherwise. Checked when the file loads.

use serde::Deserialize;

/// `[bridge]` as written.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bridge {
    /// A droid driven over the bridge stops when no drive or twist came for this long
    /// (ROS drivers' `cmd_vel_timeout`), 100..=10000 ms.
    pub command_timeout_ms: u64,
    /// Telemetry samples per second per droid, 1..=100.
    pub telemetry_hz: u16,
    /// Seconds between battery readings, 1..=3600.
    pub battery_poll_s: u64,
    /// MQTT: the QoS of commands, telemetry and replies (0, 1 or 2; the retained state is
    /// always sent at least once).
    pub qos: u8,
    /// MQTT: the first level of every topic (`droidctl/D2-0001/cmd`).
    pub topic_prefix: String,
    /// MQTT: seconds between keep-alive pings when nothing else is sent, 1..=3600 (the
    /// broker sends the last will after 1.5 times this without a word).
    pub keepalive_s: u64,
}

/// Range checks: (section, key, message).
pub fn validate(b: &Bridge) -> Result<(), (String, String, String)> {
    let bad = |k: &str, m: String| Err(("bridge".to_string(), k.to_string(), m));
    if !(100..=10_000).contains(&b.command_timeout_ms) {
        return bad(
            "command_timeout_ms",
            format!("{} is out of range 100..=10000", b.command_timeout_ms),
        );
    }
    if !(1..=100).contains(&b.telemetry_hz) {
        return bad(
            "telemetry_hz",
            format!("{} is out of range 1..=100", b.telemetry_hz),
        );
    }
    if !(1..=3600).contains(&b.battery_poll_s) {
        return bad(
            "battery_poll_s",
            format!("{} is out of range 1..=3600", b.battery_poll_s),
        );
    }
    if b.qos > 2 {
        return bad("qos", format!("{} is not a QoS: 0, 1 or 2", b.qos));
    }
    if let Err(m) = check_prefix(&b.topic_prefix) {
        return bad("topic_prefix", m);
    }
    if !(1..=3600).contains(&b.keepalive_s) {
        return bad(
            "keepalive_s",
            format!("{} is out of range 1..=3600", b.keepalive_s),
        );
    }
    Ok(())
}

/// A topic prefix: one or more levels, no wildcards, no empty level, not a broker's own
/// (`$SYS`: a `$` topic is reserved for the broker and never matches the bridge's
/// subscriptions as clients publish them: the bridge would never get a command).
pub fn check_prefix(p: &str) -> Result<(), String> {
    if p.starts_with('$') {
        return Err(format!(
            "{p:?} is not a topic prefix: topics starting with $ are the broker's own (like \
             $SYS); use a name like `droidctl` or `school/room1`"
        ));
    }
    if p.is_empty()
        || p.len() > 128
        || p.contains(['+', '#', '\0'])
        || p.split('/').any(str::is_empty)
    {
        return Err(format!(
            "{p:?} is not a topic prefix: one or more levels like `droidctl` or `school/room1`, \
             without + or # or empty levels"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::config::Config;

    #[test]
    fn defaults_and_range_checks() {
        let c = Config::defaults();
        assert_eq!(c.bridge.command_timeout_ms, 600);
        assert_eq!(c.bridge.telemetry_hz, 10);
        assert_eq!(c.bridge.topic_prefix, "droidctl");
        for (text, key) in [
            (
                "[bridge]\ncommand_timeout_ms = 50\n",
                "bridge.command_timeout_ms",
            ),
            ("[bridge]\ntelemetry_hz = 0\n", "bridge.telemetry_hz"),
            ("[bridge]\nqos = 3\n", "bridge.qos"),
            ("[bridge]\ntopic_prefix = \"a/#\"\n", "bridge.topic_prefix"),
            ("[bridge]\ntopic_prefix = \"a//b\"\n", "bridge.topic_prefix"),
            ("[bridge]\ntopic_prefix = \"$SYS\"\n", "bridge.topic_prefix"),
            (
                "[bridge]\ntopic_prefix = \"$share/x\"\n",
                "bridge.topic_prefix",
            ),
            ("[bridge]\nkeepalive_s = 0\n", "bridge.keepalive_s"),
        ] {
            let e = Config::parse_merged(None, text).unwrap_err();
            assert_eq!(e.key.as_deref(), Some(key), "{text}: {e}");
            assert_eq!(e.line, Some(2), "{text}: {e}");
        }
        let c =
            Config::parse_merged(None, "[bridge]\ncommand_timeout_ms = 1500\nqos = 1\n").unwrap();
        assert_eq!(c.bridge.command_timeout_ms, 1500);
        assert_eq!(c.bridge.qos, 1);
        assert_eq!(c.bridge.telemetry_hz, 10);
    }
}
