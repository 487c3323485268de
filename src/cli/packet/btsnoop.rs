//! `droidctl packet decode --btsnoop FILE`: the droid's traffic in an HCI snoop log, decoded
//! as droidctl's own session would log it: time, direction, the packet explained by its
//! family (masks learnt from the log's own streaming commands, v1 answers read with their
//! requests). Read in blocks: a log of any size goes through in bounded memory.

use super::{CliError, DecodeArgs, io_err};
use crate::app::packet_log::LogLine;
use crate::capture::btsnoop::{Item, Reader};
use crate::capture::hci::{self, Decoder};
use crate::capture::mirror::{Mirror, Output};
use crate::capture::{Event, Timed};
use crate::model::Protocol;
use crate::protocol::value::{FieldsJson, HexJson};
use crate::session::{Direction, LinkState, LogEntry, LogItem};
use serde::Serialize;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::time::Duration;

/// A packet of the log as `--btsnoop --json` prints it: the catalogue entry under `command`
/// as in every JSON output (null when the catalogue does not know it), the log's label beside
/// it.
#[derive(Serialize)]
struct PacketLine<'a> {
    /// In a log of several droids, which one (its address, or `connection N`).
    #[serde(skip_serializing_if = "Option::is_none")]
    droid: Option<&'a str>,
    t_s: f64,
    dir: &'static str,
    kind: &'static str,
    command: Option<&'a str>,
    label: &'a str,
    did: Option<u8>,
    seq: Option<u8>,
    error: Option<String>,
    fields: Option<FieldsJson<'a>>,
    problem: Option<&'a str>,
    wire: HexJson<'a>,
}

/// A decode error of the log as `--btsnoop --json` prints it.
#[derive(Serialize)]
struct ErrorLine<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    droid: Option<&'a str>,
    t_s: f64,
    dir: &'static str,
    error: &'static str,
    offset: u64,
    detail: &'a str,
}

struct Printer<'a> {
    out: &'a mut dyn Write,
    json: bool,
    summary_only: bool,
    decode_errors: BTreeMap<&'static str, u64>,
    packets: (u64, u64),
    /// The droid the lines are about, once the log has shown more than one.
    droid: Option<String>,
}

fn secs(at: Duration) -> String {
    format!("{:.6}", at.as_secs_f64())
}

impl Printer<'_> {
    fn note(&mut self, at: Duration, what: &str) -> std::io::Result<()> {
        if self.summary_only {
            return Ok(());
        }
        if self.json {
            writeln!(
                self.out,
                "{}",
                json!({"t_s": at.as_secs_f64(), "note": what})
            )
        } else {
            writeln!(self.out, "{:>12} -- {what}", secs(at))
        }
    }

    fn entry(&mut self, e: &LogEntry) -> std::io::Result<()> {
        match &e.item {
            LogItem::DecodeError(de) => {
                *self.decode_errors.entry(de.kind.name()).or_default() += 1;
            }
            LogItem::Packet { .. } if e.dir == Direction::Out => self.packets.0 += 1,
            LogItem::Packet { .. } => self.packets.1 += 1,
        }
        if self.summary_only {
            return Ok(());
        }
        let dir = match e.dir {
            Direction::Out => "out",
            Direction::In => "in",
        };
        if self.json {
            let t_s = e.at.as_secs_f64();
            match &e.item {
                LogItem::Packet { packet, explained } => {
                    let wire = packet.encode();
                    let fields = explained.fields.as_deref().map(FieldsJson);
                    let line = PacketLine {
                        droid: self.droid.as_deref(),
                        t_s,
                        dir,
                        kind: explained.kind.name(),
                        command: explained.known.then_some(explained.label.as_str()),
                        label: &explained.label,
                        did: explained.did,
                        seq: explained.seq,
                        error: explained.error.map(|x| x.name()),
                        fields,
                        problem: explained.problem.as_deref(),
                        wire: HexJson(&wire),
                    };
                    serde_json::to_writer(&mut *self.out, &line).map_err(std::io::Error::from)?;
                }
                LogItem::DecodeError(de) => {
                    let line = ErrorLine {
                        droid: self.droid.as_deref(),
                        t_s,
                        dir,
                        error: de.kind.name(),
                        offset: de.offset,
                        detail: &de.detail,
                    };
                    serde_json::to_writer(&mut *self.out, &line).map_err(std::io::Error::from)?;
                }
            }
            return writeln!(self.out);
        }
        let l = LogLine::from_entry(e);
        let seq = l.seq.map(|s| format!(" seq {s}")).unwrap_or_default();
        let err = l
            .err
            .map(|x| format!(" ERROR {}", x.name()))
            .unwrap_or_default();
        let fields = if l.decoded.is_empty() {
            String::new()
        } else {
            format!("  {}", l.decoded)
        };
        let hex = if l.hex.is_empty() {
            String::new()
        } else {
            format!("  [{}]", l.hex)
        };
        let droid = self
            .droid
            .as_deref()
            .map(|d| format!("{d} "))
            .unwrap_or_default();
        writeln!(
            self.out,
            "{:>12} {droid}{} {}{seq}{err}{fields}{hex}",
            secs(e.at),
            e.dir.arrow(),
            l.name
        )
    }

    fn outputs(&mut self, at: Duration, outs: &[Output]) -> std::io::Result<()> {
        for o in outs {
            match o {
                Output::Log(e) => self.entry(e)?,
                Output::Link(LinkState::Connected) => self.note(at, "connected")?,
                Output::Link(LinkState::Reconnecting { reason, .. }) => {
                    self.note(at, &format!("link lost: {reason}"))?
                }
                Output::Link(LinkState::Closed { .. }) => self.note(at, "closed")?,
                Output::Mark(m) => self.note(at, m)?,
                Output::BadNotification { name, reason } => {
                    self.note(at, &format!("malformed {name}: {reason}"))?
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// The family to decode with, once known.
enum State {
    /// Events held until the family is known (a connect, notes).
    Waiting(Vec<Timed>),
    Decoding(Box<Mirror>),
}

pub(super) fn decode(
    path: &str,
    args: DecodeArgs,
    handles: &[u16],
    json: bool,
    summary_only: bool,
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    for (flag, given) in [
        ("--from", args.from.is_some()),
        ("--sensor-mask", args.sensor_mask.is_some()),
        ("--ext-mask", args.ext_mask.is_some()),
        ("--mask2", args.mask2.is_some()),
        ("--frames", args.frames.is_some()),
        ("--request", args.request.is_some()),
    ] {
        if given {
            return Err(CliError::usage(format!(
                "{flag} does not apply to --btsnoop: a log says who sent what, and its own commands set the masks and name the requests"
            )));
        }
    }
    let forced = args
        .protocol
        .as_deref()
        .map(super::family_named)
        .transpose()?
        .map(|f| f.protocol());
    let mut input: Box<dyn Read> = if path == "-" {
        Box::new(std::io::stdin().lock())
    } else {
        Box::new(
            std::fs::File::open(path)
                .map_err(|e| CliError::usage(format!("cannot read {path}: {e}")))?,
        )
    };
    decode_reader(&mut input, path, forced, handles, json, summary_only, out)
}

/// Decode the log `input` holds (`path` names it in messages), the family `forced` or found
/// in the log: every packet printed (unless `summary_only`), then the summary. A damaged or
/// unreadable log, or one without droid traffic, ends with an error after the summary of
/// what was read.
pub fn decode_reader(
    input: &mut dyn Read,
    path: &str,
    forced: Option<Protocol>,
    handles: &[u16],
    json: bool,
    summary_only: bool,
    out: &mut dyn Write,
) -> Result<i32, CliError> {
    let mut printer = Printer {
        out,
        json,
        summary_only,
        decode_errors: BTreeMap::new(),
        packets: (0, 0),
        droid: None,
    };
    let mut reader = Reader::new();
    let mut decoder: Option<Decoder> = None;
    // Each droid's own mirror: two droids' bytes never meet in one decoder.
    let mut droids = Droids::default();
    let mut events = Vec::new();
    let mut outs = Vec::new();
    let mut block = vec![0u8; 64 * 1024];
    let mut damage = None;
    let mut read_error = None;
    'read: loop {
        let n = match input.read(&mut block) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => {
                read_error = Some(format!(
                    "cannot read {path} at offset {}: {e}",
                    reader.offset()
                ));
                break;
            }
        };
        reader.feed(&block[..n]);
        while let Some(item) = reader.next_item() {
            match item {
                Ok(Item::Header(h)) => decoder = Some(Decoder::new(h.datalink, handles)),
                Ok(Item::Record(r)) => {
                    let Some(d) = decoder.as_mut() else { continue };
                    d.record_tagged(&r, &mut events);
                    for (conn, t) in events.drain(..) {
                        let family = forced.or(d.family()).or_else(|| t.event.family());
                        let state = droids.of(d, conn, t.at, &mut printer).map_err(io_err)?;
                        step(state, t, family, &mut outs, &mut printer).map_err(io_err)?;
                    }
                }
                Err(e) => {
                    damage = Some(e);
                    break 'read;
                }
            }
        }
    }
    if damage.is_none() && read_error.is_none() {
        damage = reader.finish();
    }
    let Some(decoder) = decoder else {
        let why = damage
            .map(|e| e.to_string())
            .or(read_error)
            .unwrap_or_else(|| "the file is empty".into());
        return Err(CliError::failure(format!("{path}: {why}")));
    };
    // Summary.
    let decoding = droids.list.iter().find_map(|(_, s)| match s {
        State::Decoding(m) => Some(m),
        State::Waiting(_) => None,
    });
    let found = decoding.is_some();
    let family = decoding.map_or("none", |m| crate::family::for_model(m.model()).name());
    let droid_count = droids.list.len();
    let st = &decoder.stats;
    let damage_text = damage.as_ref().map(|e| e.to_string());
    if printer.json {
        let errors: serde_json::Map<String, Value> = printer
            .decode_errors
            .iter()
            .map(|(k, v)| (k.to_string(), json!(v)))
            .collect();
        let v = json!({"summary": {
            "datalink": reader.header().map(|h| h.datalink.code()),
            "records": st.records,
            "att_pdus": st.att_pdus,
            "droid_values": st.droid_values,
            "family": family,
            "droids": droid_count,
            "packets_out": printer.packets.0,
            "packets_in": printer.packets.1,
            "decode_errors": errors,
            "malformed_hci": st.malformed,
            "damage": damage_text,
        }});
        writeln!(printer.out, "{v}").map_err(io_err)?;
    } else {
        let errors: Vec<String> = printer
            .decode_errors
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect();
        writeln!(
            printer.out,
            "summary: {} records, {} ATT PDUs, {} droid values ({family}): {} packets out, {} in, {}{}",
            st.records,
            st.att_pdus,
            st.droid_values,
            printer.packets.0,
            printer.packets.1,
            if errors.is_empty() {
                "no decode errors".to_string()
            } else {
                format!("decode errors: {}", errors.join(", "))
            },
            if st.malformed > 0 {
                format!("; {} malformed HCI packets skipped", st.malformed)
            } else {
                String::new()
            }
        )
        .map_err(io_err)?;
        for w in &decoder.warnings {
            writeln!(printer.out, "warning: {w}").map_err(io_err)?;
        }
    }
    if let Some(e) = damage {
        return Err(CliError::failure(format!(
            "{path} is damaged: {e} (the {} record(s) before it were decoded)",
            reader.records()
        )));
    }
    if let Some(e) = read_error {
        return Err(CliError::failure(e));
    }
    if !found {
        return Err(CliError::failure(format!(
            "{path}: {}",
            hci::no_traffic_hint(&decoder.stats)
        )));
    }
    Ok(0)
}

/// The droids of the log, each with its own mirror: by peer address when the log has its
/// connection, else by connection. Bounded like the decoder's connections.
#[derive(Default)]
struct Droids {
    list: Vec<(String, State)>,
    index: std::collections::HashMap<String, usize>,
}

impl Droids {
    /// The state of the droid on connection `conn`; when a second droid appears, the lines
    /// from then on name their droid.
    fn of(
        &mut self,
        d: &Decoder,
        conn: usize,
        at: Duration,
        printer: &mut Printer,
    ) -> std::io::Result<&mut State> {
        let key = match d.peer(conn) {
            Some(a) => crate::hex::spaced(&a).replace(' ', ":"),
            None => format!("connection {conn}"),
        };
        let i = match self.index.get(&key) {
            Some(i) => *i,
            None if self.list.len() < Decoder::MAX_CONNECTIONS => {
                self.list.push((key.clone(), State::Waiting(Vec::new())));
                self.index.insert(key.clone(), self.list.len() - 1);
                if self.list.len() == 2 {
                    printer.droid = None;
                    printer.note(
                        at,
                        &format!("a second droid ({key}): each line names its droid from here on"),
                    )?;
                }
                self.list.len() - 1
            }
            // Past the bound: the last droid's mirror takes the rest.
            None => self.list.len() - 1,
        };
        if self.list.len() > 1 {
            printer.droid = Some(self.list[i].0.clone());
        }
        Ok(&mut self.list[i].1)
    }
}

/// One event through the mirror (made when the family is known).
fn step(
    state: &mut State,
    t: Timed,
    family: Option<Protocol>,
    outs: &mut Vec<Output>,
    printer: &mut Printer,
) -> std::io::Result<()> {
    if let State::Waiting(held) = state {
        let Some(f) = family.filter(|_| matches!(t.event, Event::Out(..) | Event::In(_))) else {
            // Keep a few events (a connect, the setup notes) for when it is known.
            if held.len() < 64 {
                held.push(t);
            }
            return Ok(());
        };
        let held = std::mem::take(held);
        let model = crate::family::for_protocol(f).representative();
        *state = State::Decoding(Box::new(Mirror::new(model)));
        for h in held {
            step(state, h, family, outs, printer)?;
        }
    }
    let State::Decoding(m) = state else {
        return Ok(());
    };
    outs.clear();
    m.event(&t, outs);
    printer.outputs(t.at, outs)
}
