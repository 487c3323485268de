//! What `packet encode` and `packet list` share across families: packets built from a name
//! and `--key value` parameters, and catalogues listed with their parameters. Each family's
//! own rules (headers, `raw`, test input) live in its `named.rs`.

use crate::family::error::NamedError;
use crate::protocol::error::ParamError;
use crate::protocol::schema::FieldDef;
use crate::protocol::wire::parse_uint;

/// A number in `0..=max` for option `--key` (decimal or `0x` hex).
pub fn uint_opt(key: &str, v: &str, max: u64) -> Result<u64, NamedError> {
    parse_uint(v, max).map_err(|error| NamedError::Option {
        key: key.to_string(),
        error,
    })
}

/// A byte in `0..=max` for option `--key`.
pub fn byte_opt(key: &str, v: &str, max: u64) -> Result<u8, NamedError> {
    uint_opt(key, v, max.min(255)).map(|n| n as u8)
}

/// Hex data of `--data`.
pub fn data_opt(v: &str) -> Result<Vec<u8>, NamedError> {
    crate::hex::parse(v).map_err(|e| NamedError::Option {
        key: "data".to_string(),
        error: ParamError::Hex(e),
    })
}

/// A command's parameters as `--name <description> ...`, for `packet list`.
pub fn params_text(params: &[FieldDef]) -> String {
    params
        .iter()
        .map(|p| format!("--{} <{}>", p.option(), p.description))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Whether `name` passes `packet list`'s filter.
pub fn keep(filter: Option<&str>, name: &str) -> bool {
    filter.is_none_or(|f| name.contains(f))
}

/// A catalogue's command names with their names in the spec, and `raw` (any DID/CID): what
/// `packet encode NAME` takes in the v1 and v2 families.
pub fn catalogue_names(
    commands: &'static [crate::protocol::table::CommandDef],
) -> Vec<(String, &'static str)> {
    commands
        .iter()
        .map(|c| (c.name.clone(), c.spec_name))
        .chain([(
            "raw".to_string(),
            "any DID and CID: --did N --cid N --data HEX",
        )])
        .collect()
}
