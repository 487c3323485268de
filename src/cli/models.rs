//! Model names on the command line (`--sim`, `--model`, `sim --bluez MODEL`, `--remembered`),
//! all read from the one table of models ([`Model::ALL`] with [`Model::id`] and
//! [`Model::display_name`]): what `--help` lists, what the man page and the shell completions
//! offer (the ids, never file names), and what an unknown name's error suggests.

use crate::model::Model;
use clap::builder::{PossibleValue, TypedValueParser};
use clap::error::{ContextKind, ContextValue, ErrorKind};
use std::ffi::OsStr;

/// The value parser of an argument naming models. The value stays the text given (the
/// subcommands read it as before); checking it here makes every typo the same usage error.
#[derive(Debug, Clone, Copy)]
pub struct ModelNames {
    /// `--sim r2d2,bb8`: a comma-separated list.
    list: bool,
    /// `run --sim SCRIPT` takes a value that is not a model as the script (`run` decides).
    lenient: bool,
}

impl ModelNames {
    /// One model per value.
    pub const fn one() -> ModelNames {
        ModelNames {
            list: false,
            lenient: false,
        }
    }

    /// `MODEL[,MODEL…]`.
    pub const fn list() -> ModelNames {
        ModelNames {
            list: true,
            lenient: false,
        }
    }

    /// `MODEL[,MODEL…]`, or something the subcommand reads otherwise (`run --sim SCRIPT`).
    pub const fn list_or_other() -> ModelNames {
        ModelNames {
            list: true,
            lenient: true,
        }
    }
}

/// The models as clap lists them: the id, with the model's name as its help.
pub fn possible_values() -> impl Iterator<Item = PossibleValue> {
    Model::ALL
        .into_iter()
        .map(|m| PossibleValue::new(m.id()).help(m.display_name()))
}

impl TypedValueParser for ModelNames {
    type Value = String;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<String, clap::Error> {
        let text = value.to_string_lossy().into_owned();
        if self.lenient {
            return Ok(text);
        }
        let names: Vec<&str> = if self.list {
            text.split(',')
                .map(str::trim)
                .filter(|n| !n.is_empty())
                .collect()
        } else {
            vec![text.trim()]
        };
        for name in names {
            if Model::from_id(name).is_none() {
                let mut err = clap::Error::new(ErrorKind::InvalidValue).with_cmd(cmd);
                if let Some(arg) = arg {
                    err.insert(
                        ContextKind::InvalidArg,
                        ContextValue::String(arg.to_string()),
                    );
                }
                err.insert(ContextKind::InvalidValue, ContextValue::String(name.into()));
                err.insert(
                    ContextKind::ValidValue,
                    ContextValue::Strings(Model::ALL.map(|m| m.id().to_string()).to_vec()),
                );
                return Err(err);
            }
        }
        Ok(text)
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(possible_values()))
    }
}
