//! A session seen from outside: the chunks of a capture, both ways, decoded with the droid's
//! family as the live session decodes them. Host writes are reassembled into commands (the
//! codec is told about them, so it knows the streaming masks as live); the droid's bytes go
//! through the same [`Codec::feed`] as live; responses find their request by the family's
//! key; every packet is explained for the log. Out come the session's log entries and
//! notifications, the link state, counters, and what the app and missions read from
//! responses (battery, stance) — so replay feeds the app's own telemetry and log paths.
//!
//! Sans-IO: no clocks; times come with the events.

use super::{Event, Timed};
use crate::family::{Codec, Command, Family, Incoming, Key, Packet, Reader, Side};
use crate::gatt::Endpoint;
use crate::model::Model;
use crate::protocol::notify::Notification;
use crate::protocol::wire::{LegAction, LegState};
use crate::session::{Direction, LinkState, LogEntry, LogItem, SessionStats};
use std::collections::HashMap;
use std::time::Duration;

/// What the mirror found in one event.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    Log(LogEntry),
    Notification(Notification),
    BadNotification {
        name: &'static str,
        reason: String,
    },
    Link(LinkState),
    /// A battery voltage read back (as the app's and the mission's pollers read it).
    Battery(f32),
    /// A stance change was sent.
    StanceRequested(LegAction),
    /// The stance read back.
    StanceRead(LegState),
    /// A mark in the capture (`mission-start`).
    Mark(String),
    /// A command the host sent, as it was sent (replay shows the drive, dome and lights
    /// commanded).
    Command(Command),
}

pub struct Mirror {
    model: Model,
    family: &'static dyn Family,
    codec: Box<dyn Codec>,
    /// The host's side of the stream, reassembled into commands.
    host: Box<dyn Reader>,
    pending: HashMap<Key, Command>,
    stats: SessionStats,
    link: LinkState,
}

impl Mirror {
    pub fn new(model: Model) -> Mirror {
        let family = crate::family::for_model(model);
        Mirror {
            model,
            family,
            // The model's codec, as the session has it (an Ollie's samples turned to the
            // room's axes, `family::v1`), so a replay reads what the live run read.
            codec: family.codec_for(model),
            host: host_reader(family),
            pending: HashMap::new(),
            stats: SessionStats::default(),
            link: LinkState::Connecting,
        }
    }

    pub fn model(&self) -> Model {
        self.model
    }

    pub fn stats(&self) -> SessionStats {
        self.stats
    }

    /// Requests still waiting for their answer.
    pub fn pending(&self) -> usize {
        self.pending.len()
    }

    pub fn link(&self) -> &LinkState {
        &self.link
    }

    fn set_link(&mut self, s: LinkState, out: &mut Vec<Output>) {
        if self.link != s {
            self.link = s.clone();
            out.push(Output::Link(s));
        }
    }

    /// A fresh decoder state for a new connection (as the session makes a codec per
    /// connection).
    fn reconnected(&mut self) {
        self.codec = self.family.codec_for(self.model);
        self.host = host_reader(self.family);
        self.pending.clear();
    }

    /// Decode one event of the capture; what it produced is appended to `out`.
    pub fn event(&mut self, t: &Timed, out: &mut Vec<Output>) {
        let at = t.at;
        match &t.event {
            Event::Connect => {
                if matches!(self.link, LinkState::Reconnecting { .. }) {
                    self.stats.reconnects += 1;
                }
                self.reconnected();
                self.set_link(LinkState::Connected, out);
            }
            Event::ConnectFailed(reason) | Event::Disconnect(reason) => {
                let attempt = match &self.link {
                    LinkState::Reconnecting { attempt, .. } => attempt + 1,
                    _ => 1,
                };
                self.set_link(
                    LinkState::Reconnecting {
                        attempt,
                        reason: reason.clone(),
                    },
                    out,
                );
            }
            Event::WriteFailed(reason) => {
                tracing::debug!(%reason, "a recorded write failed");
            }
            Event::Close => self.set_link(LinkState::Closed { reason: None }, out),
            Event::End => {}
            Event::Mark(m) => out.push(Output::Mark(m.clone())),
            Event::Out(to, bytes) => self.host_bytes(at, *to, bytes, out),
            Event::In(bytes) => self.droid_bytes(at, bytes, out),
        }
    }

    fn log(&self, at: Duration, dir: Direction, item: LogItem, out: &mut Vec<Output>) {
        out.push(Output::Log(LogEntry { at, dir, item }));
    }

    fn log_packet(
        &self,
        at: Duration,
        dir: Direction,
        packet: Packet,
        request: Option<&Command>,
        out: &mut Vec<Output>,
    ) {
        let explained = self.codec.explain(&packet, request);
        self.log(at, dir, LogItem::Packet { packet, explained }, out);
    }

    /// Commands the host wrote.
    fn host_bytes(&mut self, at: Duration, to: Endpoint, bytes: &[u8], out: &mut Vec<Output>) {
        self.stats.bytes_out += bytes.len() as u64;
        let mut found: Vec<(Command, Packet, u8, bool)> = Vec::new();
        let mut errors = Vec::new();
        // Responses or notifications in the host's stream: logged as they are.
        let mut odd = Vec::new();
        let mut take = |f: &dyn crate::family::Found| {
            if let Some(e) = f.decode_error() {
                errors.push(e);
            } else if let Some(p) = f.packet() {
                match p.as_command() {
                    Some((cmd, seq, want)) => found.push((cmd, p, seq, want)),
                    None => odd.push(p),
                }
            }
            Ok(())
        };
        // Only the reader's own bookkeeping fails; there is no output to fail.
        let _ = self.host.write(to, bytes, Some(&mut take));
        for p in odd {
            self.log_packet(at, Direction::Out, p, None, out);
        }
        for e in errors {
            self.stats.errors += 1;
            self.stats.decode_errors += 1;
            self.log(at, Direction::Out, LogItem::DecodeError(e), out);
        }
        for (cmd, packet, seq, want) in found {
            // The codec learns what the command changes (streaming masks), as when it
            // encoded it live.
            let _ = self.codec.encode(&cmd, seq, want);
            self.stats.sent += 1;
            if want && self.codec.answers() {
                self.pending.insert(self.codec.key(&cmd, seq), cmd.clone());
            }
            for a in [
                LegAction::Tripod,
                LegAction::Bipod,
                LegAction::Waddle,
                LegAction::Stop,
            ] {
                if self.family.stance(a).as_ref() == Some(&cmd) {
                    out.push(Output::StanceRequested(a));
                }
            }
            out.push(Output::Command(cmd.clone()));
            self.log_packet(at, Direction::Out, packet, Some(&cmd), out);
        }
    }

    /// What the droid sent.
    fn droid_bytes(&mut self, at: Duration, bytes: &[u8], out: &mut Vec<Output>) {
        self.stats.bytes_in += bytes.len() as u64;
        let mut found = Vec::new();
        self.codec.feed(bytes, &mut found);
        for item in found {
            match item {
                Incoming::Error(e) => {
                    self.stats.decode_errors += 1;
                    self.stats.errors += 1;
                    self.log(at, Direction::In, LogItem::DecodeError(e), out);
                }
                Incoming::Response { key, error, packet } => {
                    self.stats.received += 1;
                    let Some(request) = self.pending.remove(&key) else {
                        self.stats.unmatched += 1;
                        self.log_packet(at, Direction::In, packet, None, out);
                        continue;
                    };
                    self.stats.answered += 1;
                    if error.is_some() {
                        self.stats.droid_errors += 1;
                        self.stats.errors += 1;
                    } else {
                        self.read_back(&request, &packet, out);
                    }
                    self.log_packet(at, Direction::In, packet, Some(&request), out);
                }
                Incoming::Async {
                    notifications,
                    packet,
                } => {
                    self.stats.received += 1;
                    for n in notifications {
                        match n {
                            Ok(n) => out.push(Output::Notification(n)),
                            Err(e) => {
                                self.stats.errors += 1;
                                out.push(Output::BadNotification {
                                    name: e.name,
                                    reason: e.reason,
                                });
                            }
                        }
                    }
                    self.log_packet(at, Direction::In, packet, None, out);
                }
                Incoming::Stray(packet) => {
                    self.stats.received += 1;
                    self.log_packet(at, Direction::In, packet, None, out);
                }
            }
        }
    }

    /// What the app and missions read from answers: the battery, the stance.
    fn read_back(&self, request: &Command, packet: &Packet, out: &mut Vec<Output>) {
        if self.family.battery_request_for(self.model).as_ref() == Some(request)
            && let Some(v) = self.family.battery_volts_for(self.model, packet.data())
        {
            out.push(Output::Battery(v));
        }
        if self.family.get_stance().as_ref() == Some(request)
            && let Some(s) = packet.data().first().and_then(|b| LegState::from_byte(*b))
        {
            out.push(Output::StanceRead(s));
        }
    }
}

/// A reader of what the host wrote: commands, reassembled across writes.
fn host_reader(family: &dyn Family) -> Box<dyn Reader> {
    family.side_reader(Side::Host, false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::family::{RobiControl, RobiPacket};
    use crate::protocol::v2::{self, ErrorCode, cmd};

    fn t(ms: u64, event: Event) -> Timed {
        Timed {
            at: Duration::from_millis(ms),
            event,
        }
    }

    #[test]
    fn a_v2_exchange_is_logged_and_matched_as_live() {
        let mut m = Mirror::new(Model::R2D2);
        let mut out = Vec::new();
        let req = cmd::get_battery_voltage().to_packet(7);
        let resp = v2::Packet::response_to(&req, ErrorCode::Success, vec![0x01, 0x9A]);
        let wire = req.encode();
        for e in [
            t(0, Event::Connect),
            // Cut as BLE cuts it.
            t(1, Event::Out(Endpoint::Api, wire[..3].to_vec())),
            t(1, Event::Out(Endpoint::Api, wire[3..].to_vec())),
            t(5, Event::In(resp.encode())),
        ] {
            m.event(&e, &mut out);
        }
        assert_eq!(out[0], Output::Link(LinkState::Connected));
        let logs: Vec<&LogEntry> = out
            .iter()
            .filter_map(|o| match o {
                Output::Log(l) => Some(l),
                _ => None,
            })
            .collect();
        assert_eq!(logs.len(), 2);
        assert_eq!(logs[0].dir, Direction::Out);
        assert_eq!(logs[1].at, Duration::from_millis(5));
        assert!(out.contains(&Output::Battery(4.1)), "{out:?}");
        let st = m.stats();
        assert_eq!(
            (st.sent, st.received, st.answered, st.unmatched),
            (1, 1, 1, 0)
        );
    }

    #[test]
    fn robi_writes_pair_into_one_control() {
        let mut m = Mirror::new(Model::Robi42);
        let mut out = Vec::new();
        for e in [
            t(0, Event::Connect),
            t(1, Event::Out(Endpoint::Velocity, vec![200])),
            t(2, Event::Out(Endpoint::Steering, vec![100])),
        ] {
            m.event(&e, &mut out);
        }
        assert_eq!(m.stats().sent, 1);
        let Some(Output::Log(LogEntry {
            item: LogItem::Packet { packet, .. },
            ..
        })) = out.last()
        else {
            panic!("{out:?}")
        };
        assert_eq!(
            packet,
            &Packet::Robi(RobiPacket::Control(RobiControl {
                velocity: 200,
                steering: 100
            }))
        );
    }

    #[test]
    fn disconnects_and_reconnects_show_as_live() {
        let mut m = Mirror::new(Model::R2D2);
        let mut out = Vec::new();
        for e in [
            t(0, Event::Connect),
            t(1, Event::Disconnect("gone".into())),
            t(2, Event::ConnectFailed("no".into())),
            t(3, Event::Connect),
        ] {
            m.event(&e, &mut out);
        }
        assert_eq!(
            out,
            vec![
                Output::Link(LinkState::Connected),
                Output::Link(LinkState::Reconnecting {
                    attempt: 1,
                    reason: "gone".into()
                }),
                Output::Link(LinkState::Reconnecting {
                    attempt: 2,
                    reason: "no".into()
                }),
                Output::Link(LinkState::Connected),
            ]
        );
        assert_eq!(m.stats().reconnects, 1);
    }
}
