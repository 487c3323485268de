//! Payload schemas shared by every protocol family: an ordered list of typed, named fields.
//!
//! A catalogue (v2's, v1's) stores one [`Schema`] per command parameter list, response and
//! notification. The CLI encodes from it, the packet log and `packet decode` decode with it,
//! and the simulators check lengths against it, so a field is described in exactly one place.

use super::error::{EncodeError, ParamError};
use super::value::Fields;
use super::wire::{FieldError, Reader, Size, Wire};

/// One parameter or response field.
#[derive(Clone, Copy)]
pub struct FieldDef {
    /// snake_case name; the CLI option is its kebab-case form.
    pub name: &'static str,
    pub description: &'static str,
    pub size: Size,
    /// The value used when the command line leaves this parameter out, as command-line
    /// text (`None`: the parameter is required).
    pub default: Option<&'static str>,
    pub parse_put: fn(&str, &mut Vec<u8>) -> Result<(), ParamError>,
    pub decode: fn(&mut Reader<'_>, &'static str, &mut Fields) -> Result<(), FieldError>,
}

impl std::fmt::Debug for FieldDef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.name, self.description)
    }
}

impl FieldDef {
    pub const fn of<T: Wire>(name: &'static str) -> FieldDef {
        FieldDef {
            name,
            description: T::DESCRIPTION,
            size: T::SIZE,
            default: None,
            parse_put: T::parse_put,
            decode: T::decode_into,
        }
    }

    /// The same field with a default for the command line.
    pub const fn with_default(mut self, default: &'static str) -> FieldDef {
        self.default = Some(default);
        self
    }

    /// The command-line option name (`x_threshold` → `x-threshold`).
    pub fn option(&self) -> String {
        self.name.replace('_', "-")
    }
}

/// A payload layout: an ordered list of fields.
pub type Schema = &'static [FieldDef];

/// Decode `data` by `schema`; the whole payload must be consumed.
pub fn decode_fields(schema: Schema, data: &[u8]) -> Result<Fields, FieldError> {
    let mut r = Reader::new(data);
    let mut out = Fields::with_capacity(schema.len());
    for f in schema {
        (f.decode)(&mut r, f.name, &mut out)?;
    }
    r.finish()?;
    Ok(out)
}

/// Whether a payload of `len` bytes can fit `schema` (the simulators' bad-length check).
pub fn length_ok(schema: Schema, len: usize) -> bool {
    let min = min_len(schema);
    if schema.iter().any(|f| matches!(f.size, Size::Rest { .. })) {
        len >= min
    } else {
        len == min
    }
}

/// The shortest payload a schema accepts: fixed fields plus each variable one's minimum.
pub fn min_len(schema: Schema) -> usize {
    schema
        .iter()
        .map(|f| match f.size {
            Size::Fixed(n) => n,
            Size::Rest { min } => min,
        })
        .sum()
}

/// A well-formed payload of zeros of the shortest length (zero is valid for every enum,
/// heading and dome angle in the catalogues).
pub fn minimal_payload(schema: Schema) -> Vec<u8> {
    vec![0; min_len(schema)]
}

/// Encode parameters given as (option name, text) pairs, in any order, for the command
/// `name`. A parameter left out takes its default; one without a default is required.
/// Unknown options are errors.
pub fn encode_params(
    name: &str,
    params: Schema,
    given: &[(String, String)],
) -> Result<Vec<u8>, EncodeError> {
    for (k, _) in given {
        if !params.iter().any(|p| p.option() == *k) {
            let expected: Vec<String> =
                params.iter().map(|p| format!("--{}", p.option())).collect();
            return Err(if expected.is_empty() {
                EncodeError::NoParameters {
                    command: name.to_string(),
                    given: k.clone(),
                }
            } else {
                EncodeError::UnknownParameter {
                    command: name.to_string(),
                    given: k.clone(),
                    expected: expected.join(" "),
                }
            });
        }
    }
    let mut data = Vec::new();
    for p in params {
        let opt = p.option();
        let text = given
            .iter()
            .rev()
            .find(|(k, _)| *k == opt)
            .map(|(_, v)| v.as_str())
            .or(p.default)
            .ok_or_else(|| EncodeError::Missing {
                command: name.to_string(),
                option: opt.clone(),
                description: p.description,
            })?;
        (p.parse_put)(text, &mut data).map_err(|error| EncodeError::Invalid {
            option: opt.clone(),
            error,
        })?;
    }
    Ok(data)
}
