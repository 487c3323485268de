//! `packet encode` and `packet list` for Sphero API v2: packets built from catalogue names
//! and parameters, and the catalogue listed.

use crate::family::error::NamedError;
use crate::family::named::{byte_opt, catalogue_names, data_opt, keep, params_text};
use crate::model::Model;
use crate::protocol::table::unknown_command;
use crate::protocol::v2::catalog::targets::{self, Home};
use crate::protocol::v2::{Flags, Packet, catalog};
use std::io::Write;

/// Header options of `packet encode`.
#[derive(Debug, Default)]
struct Header {
    seq: u8,
    tid: Option<u8>,
    sid: Option<u8>,
    no_response: bool,
}

/// The names [`encode`] takes: the catalogue's, and `raw`.
pub fn names() -> Vec<(String, &'static str)> {
    catalogue_names(catalog::commands())
}

/// Build the wire bytes for `packet encode NAME --key value ...` (v2): a catalogue name with
/// its parameters, or `raw`; header options `--seq N`, `--tid N`, `--sid N`, `--no-response`.
pub fn encode(name: &str, given: Vec<(String, String)>) -> Result<Vec<u8>, NamedError> {
    let mut header = Header::default();
    let mut params = Vec::new();
    let mut raw = (None, None, Vec::new());
    for (k, v) in given {
        match k.as_str() {
            // 0xFF marks notifications: never a request's SEQ.
            "seq" => header.seq = byte_opt(&k, &v, 254)?,
            "tid" => header.tid = Some(byte_opt(&k, &v, 255)?),
            "sid" => header.sid = Some(byte_opt(&k, &v, 255)?),
            "no-response" => header.no_response = true,
            "did" if name == "raw" => raw.0 = Some(byte_opt(&k, &v, 255)?),
            "cid" if name == "raw" => raw.1 = Some(byte_opt(&k, &v, 255)?),
            "data" if name == "raw" => raw.2 = data_opt(&v)?,
            "no-reset-timeout" => {
                return Err(NamedError::NoResetTimeoutInV2);
            }
            _ => params.push((k, v)),
        }
    }
    let (did, cid, data) = if name == "raw" {
        if let Some((k, _)) = params.first() {
            return Err(NamedError::RawParameter(k.clone()));
        }
        let did = raw.0.ok_or(NamedError::RawNeeds("did"))?;
        let cid = raw.1.ok_or(NamedError::RawNeeds("cid"))?;
        (did, cid, raw.2)
    } else {
        let def = catalog::by_name(name)
            .ok_or_else(|| unknown_command(name, catalog::suggestions(name), ""))?;
        let data = def.encode_params(&params)?;
        check_led_values(def.name.as_str(), &data)?;
        (def.did, def.cid, data)
    };
    let mut p = Packet::command(did, cid, header.seq, data);
    if header.no_response {
        p.flags.remove(Flags::REQUESTS_RESPONSE);
    }
    p.tid = header.tid;
    p.sid = header.sid;
    Ok(p.normalized().encode())
}

/// The LED mask commands carry one value per set mask bit; catch a mismatch before the droid
/// answers bad_data_length.
fn check_led_values(name: &str, data: &[u8]) -> Result<(), NamedError> {
    let width = match name {
        "set-all-leds-with-8-bit-mask" => 1,
        "set-all-leds-with-16-bit-mask" => 2,
        "set-all-leds-with-32-bit-mask" => 4,
        _ => return Ok(()),
    };
    let Some(mask_bytes) = data.get(..width) else {
        return Ok(());
    };
    let mask = mask_bytes.iter().fold(0u32, |a, &b| (a << 8) | b as u32);
    let values = data.len() - width;
    if values != mask.count_ones() as usize {
        return Err(NamedError::LedValues {
            mask,
            width,
            bits: mask.count_ones(),
            values,
        });
    }
    Ok(())
}

/// `packet list` for v2: commands with their parameters, notifications with their fields.
/// A model id as the filter (`bolt`) lists that model's commands, with the processor each
/// is addressed to on robots with two.
pub fn list(filter: Option<&str>, out: &mut dyn Write) -> std::io::Result<usize> {
    let mut l = crate::family::listing::Listing::new(out);
    let model = filter
        .and_then(Model::from_id)
        .filter(|m| m.protocol() == crate::model::Protocol::SpheroV2);
    let keep = |n: &str, did: u8, cid: u8| match model {
        Some(m) => super::robots::model_has(m, did, cid),
        None => keep(filter, n),
    };
    l.heading("Commands (DID/CID  name  parameters):");
    for c in catalog::commands()
        .iter()
        .filter(|c| keep(&c.name, c.did, c.cid))
    {
        let to = match model.map(|m| targets::home(m, c.did, c.cid)) {
            Some(Home::On(p)) => format!("  [{}]", p.name()),
            Some(Home::Both) => "  [either]".to_string(),
            _ => String::new(),
        };
        l.entry(format_args!(
            "  {:02X}/{:02X}  {:<44} {}{to}",
            c.did,
            c.cid,
            c.name,
            params_text(c.params)
        ))?;
    }
    l.heading("Notifications (DID/CID  name  fields):");
    for n in catalog::notifications()
        .iter()
        .filter(|n| keep(&n.name, n.device.id(), n.cid))
    {
        let fields: Vec<_> = n.fields.iter().map(|f| f.name).collect();
        l.entry(format_args!(
            "  {:02X}/{:02X}  {:<44} {}",
            n.device.id(),
            n.cid,
            n.name,
            fields.join(" ")
        ))?;
    }
    Ok(l.entries())
}
