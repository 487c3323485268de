//! What a droid's MQTT connection does with what the broker delivers on its command topics
//! (no connection in it: the fuzz target drives it). Split from [`super::mqtt`] as its own
//! job.

use super::Bridge;
use super::schema::{ErrorCode, Out};
use super::topics::topic;
use std::sync::Arc;

/// What a droid's connection does with what the broker delivers: commands on the droid's
/// `cmd` topic go to the bridge; a retained one does not (said once per connection to the
/// broker: a reply said on a connection that then dropped may never have left); anything
/// else is ignored.
pub struct Inbox {
    bridge: Arc<Bridge>,
    i: usize,
    cmd: String,
    cmd_vel: String,
    retained: u64,
    /// A retained command was said on this connection.
    said: bool,
}

impl Inbox {
    /// Droid `i`'s inbox, its commands on `PREFIX/TOPIC/cmd`.
    pub fn new(bridge: Arc<Bridge>, i: usize, prefix: &str) -> Inbox {
        let t = bridge.topic(i).unwrap_or("droid").to_string();
        Inbox {
            cmd: topic(prefix, &t, "cmd"),
            cmd_vel: topic(prefix, &t, super::ros::CMD_VEL),
            bridge,
            i,
            retained: 0,
            said: false,
        }
    }

    /// A new connection to the broker: the next retained command is said again.
    pub fn connected(&mut self) {
        self.said = false;
    }

    /// The topic it takes commands on.
    pub fn cmd_topic(&self) -> &str {
        &self.cmd
    }

    /// The topic it takes ROS Twists on.
    pub fn cmd_vel_topic(&self) -> &str {
        &self.cmd_vel
    }

    /// Retained commands ignored so far.
    pub fn retained(&self) -> u64 {
        self.retained
    }

    /// One publish delivered by the broker; the first retained command ignored is said on
    /// the droid's `reply` topic and in the log, and returned for the terminal.
    pub fn publish(&mut self, topic: &str, retain: bool, payload: &[u8]) -> Option<String> {
        if topic != self.cmd && topic != self.cmd_vel {
            return None;
        }
        if retain {
            // A retained command is one the broker kept for whoever subscribes: it would
            // run at every (re)connect with nobody there (issue 26 point 5).
            self.retained += 1;
            if !self.said {
                self.said = true;
                let name = self.bridge.fleet().member(self.i).map(|m| m.name.clone());
                let error = format!(
                    "a retained message on {topic} was ignored: commands are taken only from a \
                     client that is there (publish without -r); clear it with \
                     `mosquitto_pub -r -n -t {topic}`"
                );
                tracing::warn!(topic, "bridge: a retained command ignored");
                let said = format!("droidctl: {error}");
                self.bridge.emit(
                    Some(self.i),
                    Out::Error {
                        id: None,
                        droid: name,
                        cmd: None,
                        code: ErrorCode::Retained,
                        robot: None,
                        capability: None,
                        error,
                    },
                );
                return Some(said);
            }
            tracing::debug!(topic, "bridge: a retained command ignored");
            return None;
        }
        if topic == self.cmd_vel {
            self.bridge
                .handle_parsed(super::ros::cmd_vel(payload), Some(self.i));
        } else {
            self.bridge.handle(payload, Some(self.i));
        }
        None
    }
}
