//! The command table both Sphero catalogues (API v2's and v1's) are built on: named commands
//! with their device and command ids and payload schemas, found by id or by name, with "did
//! you mean" suggestions for a mistyped name.
//!
//! Each catalogue declares its rows with its own macro (the typed constructors come from the
//! same rows); the lookup machinery lives here once, so the two families cannot drift apart in
//! how a name is derived, found or suggested.

use super::error::{EncodeError, UnknownCommand};
use super::schema::Schema;
use std::collections::HashMap;

/// One command of a catalogue.
#[derive(Debug)]
pub struct CommandDef {
    /// kebab-case name, e.g. `drive-with-heading`.
    pub name: String,
    /// The name as the spec writes it, e.g. "Drive With Heading".
    pub spec_name: &'static str,
    pub did: u8,
    pub cid: u8,
    pub params: Schema,
    pub response: Schema,
}

impl CommandDef {
    /// Encode parameters given as (option name, text) pairs, in any order. A parameter left
    /// out takes its default; one without a default is required. Unknown options are errors.
    pub fn encode_params(&self, given: &[(String, String)]) -> Result<Vec<u8>, EncodeError> {
        super::schema::encode_params(&self.name, self.params, given)
    }
}

/// A row as a catalogue macro writes it: the constructor's snake_case name gives the
/// command's kebab-case name.
pub struct RawCommand {
    pub did: u8,
    pub cid: u8,
    pub fn_name: &'static str,
    pub spec_name: &'static str,
    pub params: Schema,
    pub response: Schema,
}

/// A catalogue's commands, indexed by id and by name.
pub struct CommandTable {
    commands: Vec<CommandDef>,
    by_id: HashMap<(u8, u8), usize>,
    by_name: HashMap<String, usize>,
}

impl CommandTable {
    pub fn new(raw: &[RawCommand]) -> CommandTable {
        let commands: Vec<CommandDef> = raw
            .iter()
            .map(|r| CommandDef {
                name: r.fn_name.replace('_', "-"),
                spec_name: r.spec_name,
                did: r.did,
                cid: r.cid,
                params: r.params,
                response: r.response,
            })
            .collect();
        let by_id = commands
            .iter()
            .enumerate()
            .map(|(i, c)| ((c.did, c.cid), i))
            .collect();
        let by_name = commands
            .iter()
            .enumerate()
            .map(|(i, c)| (c.name.clone(), i))
            .collect();
        CommandTable {
            commands,
            by_id,
            by_name,
        }
    }

    /// A table of several parts' rows, in order (a catalogue split by device).
    pub fn from_parts(parts: &[&[RawCommand]]) -> CommandTable {
        let mut table = CommandTable::new(&[]);
        for raw in parts {
            let more = CommandTable::new(raw);
            for c in more.commands {
                let i = table.commands.len();
                table.by_id.insert((c.did, c.cid), i);
                table.by_name.insert(c.name.clone(), i);
                table.commands.push(c);
            }
        }
        table
    }

    /// Every command, in table order.
    pub fn commands(&self) -> &[CommandDef] {
        &self.commands
    }

    /// The command with this DID/CID.
    pub fn lookup(&self, did: u8, cid: u8) -> Option<&CommandDef> {
        self.by_id.get(&(did, cid)).map(|&i| &self.commands[i])
    }

    /// The command with this kebab-case name.
    pub fn by_name(&self, name: &str) -> Option<&CommandDef> {
        self.by_name.get(name).map(|&i| &self.commands[i])
    }

    /// Command names closest to `name`, for "did you mean" hints: the most words of `name`
    /// in common first, shorter names before longer ones, three at most.
    pub fn suggestions(&self, name: &str) -> Vec<&str> {
        let words: Vec<&str> = name.split('-').filter(|w| w.len() > 2).collect();
        let mut scored: Vec<(usize, &str)> = self
            .commands
            .iter()
            .map(|c| {
                let score = words.iter().filter(|w| c.name.contains(*w)).count();
                (score, c.name.as_str())
            })
            .filter(|(s, _)| *s > 0)
            .collect();
        scored.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.len().cmp(&b.1.len())));
        scored.into_iter().take(3).map(|(_, n)| n).collect()
    }
}

/// "unknown command X; did you mean …?" from a catalogue's suggestions; `list` is what
/// follows `droidctl packet list` to see that catalogue (` --protocol v1`).
pub fn unknown_command(name: &str, suggestions: Vec<&str>, list: &'static str) -> UnknownCommand {
    UnknownCommand {
        name: name.to_string(),
        suggestions: suggestions.into_iter().map(str::to_string).collect(),
        list,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::schema::FieldDef;

    static RAW: &[RawCommand] = &[
        RawCommand {
            did: 1,
            cid: 2,
            fn_name: "drive_with_heading",
            spec_name: "Drive With Heading",
            params: &[FieldDef::of::<u8>("speed")],
            response: &[],
        },
        RawCommand {
            did: 1,
            cid: 3,
            fn_name: "drive_raw",
            spec_name: "Drive Raw",
            params: &[],
            response: &[],
        },
    ];

    #[test]
    fn found_by_id_and_name() {
        let t = CommandTable::new(RAW);
        assert_eq!(t.commands().len(), 2);
        assert_eq!(
            t.lookup(1, 2).map(|c| c.name.as_str()),
            Some("drive-with-heading")
        );
        assert_eq!(t.by_name("drive-raw").map(|c| (c.did, c.cid)), Some((1, 3)));
        assert!(t.lookup(9, 9).is_none() && t.by_name("fly").is_none());
        assert_eq!(
            t.by_name("drive-with-heading")
                .unwrap()
                .encode_params(&[("speed".to_string(), "7".to_string())]),
            Ok(vec![7])
        );
    }

    #[test]
    fn suggestions_rank_by_shared_words() {
        let t = CommandTable::new(RAW);
        assert_eq!(
            t.suggestions("drive-heading"),
            ["drive-with-heading", "drive-raw"]
        );
        assert!(t.suggestions("fly").is_empty());
    }
}
