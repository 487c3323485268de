//! `droidctl examples [NAME]`: the built-in missions and Sphero Edu programs
//! ([`crate::examples`]), listed with the models each is for, or one printed whole so that
//! `droidctl examples square.js > square.js` starts a user off from any directory.

use super::CliError;
use crate::examples::{self, EXAMPLES, Example};
use clap::Args;
use clap::builder::{PossibleValue, TypedValueParser};
use std::ffi::OsStr;
use std::io::Write;

#[derive(Debug, Clone, Args)]
pub struct ExamplesArgs {
    /// The example to print (`tour.txt`, `square.js`; the name without its extension will do
    /// when only one example has it). Without it, every example is listed.
    #[arg(value_name = "NAME", value_parser = ExampleNames)]
    pub name: Option<String>,
}

/// The value parser of NAME: it offers every example's file name to the shell completions and
/// the man page, and takes any text, which [`examples::find`] then reads (so a short or
/// ambiguous name gets its own message, not clap's list).
#[derive(Debug, Clone, Copy)]
struct ExampleNames;

impl TypedValueParser for ExampleNames {
    type Value = String;

    fn parse_ref(
        &self,
        _cmd: &clap::Command,
        _arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<String, clap::Error> {
        Ok(value.to_string_lossy().into_owned())
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(
            EXAMPLES
                .iter()
                .map(|e| PossibleValue::new(e.name).help(e.summary())),
        ))
    }
}

/// Run `droidctl examples [NAME]`.
pub fn run(args: ExamplesArgs, out: &mut dyn Write) -> Result<i32, CliError> {
    let text = match args.name {
        Some(name) => examples::find(&name)
            .map_err(|e| CliError::usage(e.to_string()))?
            .text
            .to_string(),
        None => listing(),
    };
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(CliError::output)?;
    Ok(0)
}

/// The list: each kind under its heading, a line per example (name, models, what it does),
/// and how to use one. Fits 80 columns.
pub fn listing() -> String {
    let mut s = String::new();
    for (kind, how) in [
        (examples::Kind::Mission, "Missions: `droidctl run NAME.txt`"),
        (
            examples::Kind::Program,
            "Sphero Edu programs: `droidctl run NAME.js`",
        ),
    ] {
        s.push_str(how);
        s.push('\n');
        for e in EXAMPLES.iter().filter(|e| e.kind == kind) {
            s.push_str(&line(e));
        }
        s.push('\n');
    }
    s.push_str(
        "Print one: `droidctl examples NAME`; save it: `droidctl examples NAME > NAME`;\n\
         run it on the simulator: `droidctl run NAME --sim MODEL`.\n",
    );
    s
}

fn line(e: &Example) -> String {
    // A built-in example's header is checked by a test; should one be wrong, the list says so
    // rather than failing.
    let models = e
        .fits()
        .map(|f| f.describe())
        .unwrap_or_else(|err| format!("? ({err})"));
    // Wide enough for "bolt, boltplus, rvr" (issue 41 added BOLT+ to BOLT's examples).
    let head = format!("  {:<12} {:<19} ", e.name, models);
    let indent = head.chars().count();
    let mut s = head;
    let mut col = indent;
    for word in e.summary().split_whitespace() {
        let len = word.chars().count();
        if col > indent && col + 1 + len > 80 {
            s.push('\n');
            s.push_str(&" ".repeat(indent));
            col = indent;
        } else if col > indent {
            s.push(' ');
            col += 1;
        }
        s.push_str(word);
        col += len;
    }
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_list_names_every_example_with_its_models_within_80_columns() {
        let text = listing();
        for e in EXAMPLES {
            let row = text
                .lines()
                .find(|l| l.trim_start().starts_with(e.name))
                .unwrap_or_else(|| panic!("{} not listed:\n{text}", e.name));
            let first_word = e.summary().split_whitespace().next().unwrap_or("");
            assert!(row.contains(first_word), "{row}");
        }
        assert!(text.contains("  tour.txt     all "), "{text}");
        assert!(text.contains("  matrix.js    bolt, boltplus "), "{text}");
        assert!(text.contains("  patrol.txt   r2d2 + bb8 "), "{text}");
        for l in text.lines() {
            assert!(
                l.chars().count() <= 80,
                "{} columns: {l}",
                l.chars().count()
            );
        }
    }

    #[test]
    fn a_name_prints_the_example_and_a_wrong_one_is_bad_input() {
        let mut out = Vec::new();
        let args = ExamplesArgs {
            name: Some("tour".into()),
        };
        assert_eq!(run(args, &mut out).ok(), Some(0));
        assert_eq!(out, examples::find("tour.txt").unwrap().text.as_bytes());
        let err = run(
            ExamplesArgs {
                name: Some("square".into()),
            },
            &mut Vec::new(),
        )
        .unwrap_err();
        assert_eq!(err.status, 2);
        assert!(
            err.message.contains("square.txt or square.js"),
            "{}",
            err.message
        );
    }
}
