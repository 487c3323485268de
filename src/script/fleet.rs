//! Missions for several droids: the same lines as for one, addressed and grouped.
//!
//! ```text
//! @R2 drive 100 90 for 2s     # one droid: the mission waits for it, then goes on
//! stance tripod               # no address: every droid, at once; waits for all
//! together {                  # every droid's lines in the block run at once, each droid's
//!   @R2 drive 80 0 for 3s     #   in order; the block ends when all droids are done
//!   @BB8 drive 80 180 for 1s
//!   @BB8 wait 1s
//!   sound 3                   #   (an unaddressed line in a block: every droid)
//! }
//! ```
//!
//! A name is any part of a droid's name or its model (`@r2d2`, `@BB-8`, `@0001`), resolved
//! against the fleet before anything is sent. Blocks do not nest. A script without `@` or
//! blocks is an ordinary one-droid mission (run on every droid of a fleet at once).

use super::{ScriptError, Step, parse_line};

/// A line, for one droid (`Some(name)` as written after `@`) or for every droid.
#[derive(Debug, Clone, PartialEq)]
pub struct Addressed {
    pub droid: Option<String>,
    pub step: Step,
}

/// One item of a fleet mission, run one after the other.
#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    Line(Addressed),
    /// `together { … }`: the line the block opened on, and its lines.
    Together {
        line: usize,
        lines: Vec<Addressed>,
    },
}

impl Item {
    /// Every line of the item.
    pub fn lines(&self) -> Vec<&Addressed> {
        match self {
            Item::Line(a) => vec![a],
            Item::Together { lines, .. } => lines.iter().collect(),
        }
    }
}

/// Whether `items` say anything a one-droid mission cannot (an address or a block).
pub fn is_fleet(items: &[Item]) -> bool {
    items.iter().any(|i| match i {
        Item::Line(a) => a.droid.is_some(),
        Item::Together { .. } => true,
    })
}

/// The steps of a script without addresses or blocks, for a one-droid mission.
pub fn plain_steps(items: &[Item]) -> Vec<Step> {
    items
        .iter()
        .flat_map(Item::lines)
        .map(|a| a.step.clone())
        .collect()
}

/// Parse a fleet script; every malformed line is reported.
pub fn parse_fleet(text: &str) -> Result<Vec<Item>, Vec<ScriptError>> {
    let mut items = Vec::new();
    let mut errors = Vec::new();
    // The open block: its line and lines so far.
    let mut block: Option<(usize, Vec<Addressed>)> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let err = |message: String| ScriptError { line, message };
        let words: Vec<&str> = content.split_whitespace().collect();
        if words[0].eq_ignore_ascii_case("together") {
            if words.len() != 2 || words[1] != "{" {
                errors.push(err("expected `together {`".into()));
            } else if block.is_some() {
                errors.push(err(
                    "`together` blocks do not nest: close the first with `}`".into(),
                ));
            } else {
                block = Some((line, Vec::new()));
            }
            continue;
        }
        if content == "}" {
            match block.take() {
                Some((at, lines)) => items.push(Item::Together { line: at, lines }),
                None => errors.push(err("`}` without a `together {`".into())),
            }
            continue;
        }
        let (droid, rest) = match content.strip_prefix('@') {
            Some(r) => {
                let mut parts = r.splitn(2, char::is_whitespace);
                let name = parts.next().unwrap_or("");
                let rest = parts.next().unwrap_or("").trim();
                if name.is_empty() || rest.is_empty() {
                    errors.push(err(
                        "expected `@NAME LINE`, e.g. `@R2 drive 100 90 for 2s`".into()
                    ));
                    continue;
                }
                (Some(name.to_string()), rest)
            }
            None => (None, content),
        };
        match parse_line(rest) {
            Ok(action) => {
                let a = Addressed {
                    droid,
                    step: Step {
                        line,
                        text: content.to_string(),
                        action,
                    },
                };
                match &mut block {
                    Some((_, lines)) => lines.push(a),
                    None => items.push(Item::Line(a)),
                }
            }
            Err(message) => errors.push(err(message)),
        }
    }
    if let Some((at, _)) = block {
        errors.push(ScriptError {
            line: at,
            message: "this `together {` is never closed with `}`".into(),
        });
    }
    if errors.is_empty() {
        Ok(items)
    } else {
        Err(errors)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::script::Action;

    #[test]
    fn addresses_blocks_and_plain_lines() {
        let items = parse_fleet(
            "@R2 drive 100 90 for 2s\nstance tripod\ntogether {\n  @BB8 wait 1s # c\n  sound 3\n}\n",
        )
        .unwrap();
        assert_eq!(items.len(), 3);
        let Item::Line(a) = &items[0] else { panic!() };
        assert_eq!(a.droid.as_deref(), Some("R2"));
        assert!(matches!(a.step.action, Action::Drive { speed: 100, .. }));
        assert_eq!(a.step.line, 1);
        let Item::Line(b) = &items[1] else { panic!() };
        assert_eq!(b.droid, None);
        let Item::Together { line, lines } = &items[2] else {
            panic!()
        };
        assert_eq!((*line, lines.len()), (3, 2));
        assert_eq!(lines[0].droid.as_deref(), Some("BB8"));
        assert_eq!(lines[1].droid, None);
        assert!(is_fleet(&items));
        // A one-droid script is one.
        let plain = parse_fleet("drive 50 0 for 1s\nstop\n").unwrap();
        assert!(!is_fleet(&plain));
        assert_eq!(
            plain_steps(&plain),
            crate::script::parse("drive 50 0 for 1s\nstop\n").unwrap()
        );
    }

    #[test]
    fn malformed_structure_is_reported_by_line() {
        let e =
            parse_fleet("together {\ntogether {\n}\n}\n@ drive 1 1\n@R2\n@R2 fly\n").unwrap_err();
        let lines: Vec<usize> = e.iter().map(|e| e.line).collect();
        assert_eq!(lines, vec![2, 4, 5, 6, 7], "{e:?}");
        let e = parse_fleet("together {\n@R2 stop\n").unwrap_err();
        assert_eq!(e[0].line, 1);
        assert!(e[0].message.contains("never closed"));
        assert!(parse_fleet("together now\n").is_err());
    }
}
