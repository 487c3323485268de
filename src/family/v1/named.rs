//! `packet encode --protocol v1` and `packet list --protocol v1`: v1 commands built from
//! catalogue names and parameters, and the catalogue listed.

use crate::family::error::NamedError;
use crate::family::named::{byte_opt, catalogue_names, data_opt, keep, params_text};
use crate::protocol::table::unknown_command;
use crate::protocol::v1::{CommandPacket, Packet, catalog};
use std::io::Write;

/// The names [`encode`] takes: the catalogue's, and `raw`.
pub fn names() -> Vec<(String, &'static str)> {
    catalogue_names(catalog::commands())
}

/// Build the wire bytes of a v1 command: a catalogue name with its parameters, or `raw`.
/// Header options: `--seq N` (0..=255), `--no-response` (clears SOP2's answer bit),
/// `--no-reset-timeout` (clears its reset-timeout bit).
pub fn encode(name: &str, given: Vec<(String, String)>) -> Result<Vec<u8>, NamedError> {
    let is_raw = name == "raw";
    let (mut seq, mut answer, mut reset_timeout) = (0, true, true);
    let mut params = Vec::new();
    let (mut did, mut cid, mut data) = (None, None, Vec::new());
    for (k, v) in given {
        match k.as_str() {
            "seq" => seq = byte_opt(&k, &v, 255)?,
            "no-response" => answer = false,
            "no-reset-timeout" => reset_timeout = false,
            "tid" | "sid" => {
                return Err(NamedError::NoIdsInV1(k));
            }
            "did" if is_raw => did = Some(byte_opt(&k, &v, 255)?),
            "cid" if is_raw => cid = Some(byte_opt(&k, &v, 255)?),
            "data" if is_raw => data = data_opt(&v)?,
            _ => params.push((k, v)),
        }
    }
    let (did, cid, data) = if is_raw {
        if let Some((k, _)) = params.first() {
            return Err(NamedError::RawParameter(k.clone()));
        }
        let did = did.ok_or(NamedError::RawNeeds("did"))?;
        let cid = cid.ok_or(NamedError::RawNeeds("cid"))?;
        (did, cid, data)
    } else {
        let def = catalog::by_name(name)
            .ok_or_else(|| unknown_command(name, catalog::suggestions(name), " --protocol v1"))?;
        let data = def.encode_params(&params)?;
        (def.did, def.cid, data)
    };
    let packet = CommandPacket::new(did, cid, seq, data).with_options(answer, reset_timeout);
    Packet::Command(packet)
        .encode()
        .map_err(|e| NamedError::V1Frame(e.to_string()))
}

/// `packet list --protocol v1`: commands with their parameters, async messages with their
/// fields.
pub fn list(filter: Option<&str>, out: &mut dyn Write) -> std::io::Result<usize> {
    let keep = |n: &str| keep(filter, n);
    let mut l = crate::family::listing::Listing::new(out);
    l.heading("Commands (DID/CID  name  parameters):");
    for c in catalog::commands().iter().filter(|c| keep(&c.name)) {
        let line = format!(
            "  {:02X}/{:02X}  {:<30} {}",
            c.did,
            c.cid,
            c.name,
            params_text(c.params)
        );
        l.entry(line.trim_end())?;
    }
    l.heading("Async messages (ID  name  fields):");
    for a in catalog::async_messages().iter().filter(|a| keep(a.name)) {
        let fields: Vec<_> = a.fields.iter().map(|f| f.name).collect();
        let line = format!(
            "  {:02X}     {:<30} {}",
            a.id_code,
            a.name,
            fields.join(" ")
        );
        l.entry(line.trim_end())?;
    }
    Ok(l.entries())
}
