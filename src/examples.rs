//! The examples built into the binary: missions and Sphero Edu programs that `droidctl
//! examples` lists and prints, so the README's tour works from any directory after `cargo
//! install`, not only inside the checkout.
//!
//! Each example's own text says what it is and which models it is for: its first comment line
//! is its summary, and a comment line `Models: …` names the models (`all`, `all but robi`,
//! `r2d2, r2q5` for any one of them, `r2d2 + bb8` for a fleet that runs them together). The
//! header is the one place that says it; a test runs every example on every model it names and
//! checks it fails on the others.

use crate::model::Model;

/// What kind of file an example is: it decides how `droidctl run` reads it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A mission script (`.txt`): one line per step, see docs/missions.md.
    Mission,
    /// A Sphero Edu JavaScript program (`.js`), see docs/edu-programs.md.
    Program,
}

impl Kind {
    pub fn label(self) -> &'static str {
        match self {
            Kind::Mission => "mission",
            Kind::Program => "Sphero Edu program",
        }
    }
}

/// One built-in example: its file name and text.
#[derive(Debug, Clone, Copy)]
pub struct Example {
    pub name: &'static str,
    pub kind: Kind,
    pub text: &'static str,
}

/// Which droids an example runs on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fits {
    /// Any one of these models (`all` is every model).
    Each(Vec<Model>),
    /// These droids at once, as a fleet (`--sim r2d2,bb8`).
    Together(Vec<Model>),
}

/// Every built-in example, in the order `droidctl examples` lists them: the first drive first.
pub const EXAMPLES: &[Example] = &[
    Example {
        name: "tour.txt",
        kind: Kind::Mission,
        text: include_str!("../assets/missions/tour.txt"),
    },
    Example {
        name: "square.txt",
        kind: Kind::Mission,
        text: include_str!("../assets/missions/square.txt"),
    },
    Example {
        name: "patrol.txt",
        kind: Kind::Mission,
        text: include_str!("../examples/patrol.txt"),
    },
    Example {
        name: "square.js",
        kind: Kind::Program,
        text: include_str!("../examples/edu/square.js"),
    },
    Example {
        name: "pong.js",
        kind: Kind::Program,
        text: include_str!("../examples/edu/pong.js"),
    },
    Example {
        name: "matrix.js",
        kind: Kind::Program,
        text: include_str!("../examples/edu/matrix.js"),
    },
    Example {
        name: "infrared.js",
        kind: Kind::Program,
        text: include_str!("../examples/edu/infrared.js"),
    },
    Example {
        name: "beacon.js",
        kind: Kind::Program,
        text: include_str!("../examples/edu/beacon.js"),
    },
    Example {
        name: "follow.js",
        kind: Kind::Program,
        text: include_str!("../examples/edu/follow.js"),
    },
];

/// Why a name does not pick one example.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LookupError {
    #[error(
        "no example is called {name:?}: `droidctl examples` lists them ({})",
        names()
    )]
    Unknown { name: String },
    #[error("{name:?} could be {}: give the whole name", .matches.join(" or "))]
    Ambiguous {
        name: String,
        matches: Vec<&'static str>,
    },
}

/// Every example's name, for messages.
fn names() -> String {
    EXAMPLES
        .iter()
        .map(|e| e.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The example a name picks: its whole file name (any case), or the name without its
/// extension when only one example has it (`tour`, but not `square`, which is both a mission
/// and a program).
pub fn find(name: &str) -> Result<&'static Example, LookupError> {
    let wanted = name.trim().to_ascii_lowercase();
    if let Some(e) = EXAMPLES.iter().find(|e| e.name == wanted) {
        return Ok(e);
    }
    let stem = |e: &Example| e.name.rsplit_once('.').map_or(e.name, |(s, _)| s);
    let matches: Vec<&'static Example> = EXAMPLES.iter().filter(|e| stem(e) == wanted).collect();
    match matches.as_slice() {
        [one] => Ok(one),
        [] => Err(LookupError::Unknown {
            name: name.to_string(),
        }),
        many => Err(LookupError::Ambiguous {
            name: name.to_string(),
            matches: many.iter().map(|e| e.name).collect(),
        }),
    }
}

/// A comment line's text without its marker (`#` for missions, `//` for programs).
fn comments(text: &str) -> impl Iterator<Item = &str> {
    text.lines().map_while(|l| {
        let l = l.trim();
        l.strip_prefix("//")
            .or_else(|| l.strip_prefix('#'))
            .map(str::trim)
    })
}

impl Example {
    /// The first line of the example's header comment: what it does.
    pub fn summary(&self) -> &'static str {
        comments(self.text).next().unwrap_or("")
    }

    /// The text after `Models:` in the header, as written.
    pub fn models_line(&self) -> Option<&'static str> {
        comments(self.text).find_map(|l| l.strip_prefix("Models:").map(str::trim))
    }

    /// The models the header names. Only built-in texts are read here, and a test reads every
    /// one, so an error is a mistake in an example, never the user's.
    pub fn fits(&self) -> Result<Fits, String> {
        let line = self
            .models_line()
            .ok_or_else(|| format!("{}: no `Models:` line in its header", self.name))?;
        // A note in parentheses after the list is for people.
        let list = line.split('(').next().unwrap_or("").trim();
        if list == "all" {
            return Ok(Fits::Each(Model::ALL.to_vec()));
        }
        if let Some(but) = list.strip_prefix("all but ") {
            let out = parse_list(but, ',')?;
            return Ok(Fits::Each(
                Model::ALL
                    .into_iter()
                    .filter(|m| !out.contains(m))
                    .collect(),
            ));
        }
        if list.contains('+') {
            return Ok(Fits::Together(parse_list(list, '+')?));
        }
        Ok(Fits::Each(parse_list(list, ',')?))
    }
}

fn parse_list(list: &str, sep: char) -> Result<Vec<Model>, String> {
    list.split(sep)
        .map(|id| Model::from_id(id).ok_or_else(|| format!("unknown model {:?}", id.trim())))
        .collect()
}

impl Fits {
    /// How `droidctl examples` shows it: `all`, `all but robi`, `bolt`, `r2d2 + bb8`.
    pub fn describe(&self) -> String {
        match self {
            Fits::Together(ms) => ms.iter().map(|m| m.id()).collect::<Vec<_>>().join(" + "),
            Fits::Each(ms) if ms.len() == Model::ALL.len() => "all".to_string(),
            Fits::Each(ms) if ms.len() * 2 > Model::ALL.len() => {
                let out: Vec<&str> = Model::ALL
                    .into_iter()
                    .filter(|m| !ms.contains(m))
                    .map(Model::id)
                    .collect();
                format!("all but {}", out.join(", "))
            }
            Fits::Each(ms) => ms.iter().map(|m| m.id()).collect::<Vec<_>>().join(", "),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_example_says_what_it_is_and_which_models_it_is_for() {
        for e in EXAMPLES {
            assert!(!e.summary().is_empty(), "{}: no summary", e.name);
            let fits = e.fits().unwrap_or_else(|err| panic!("{err}"));
            match &fits {
                Fits::Each(ms) | Fits::Together(ms) => assert!(!ms.is_empty(), "{}", e.name),
            }
            let ext = if e.kind == Kind::Mission {
                ".txt"
            } else {
                ".js"
            };
            assert!(e.name.ends_with(ext), "{}", e.name);
        }
    }

    #[test]
    fn one_mission_runs_on_every_model() {
        let all = EXAMPLES
            .iter()
            .filter(|e| e.kind == Kind::Mission)
            .find(|e| e.fits() == Ok(Fits::Each(Model::ALL.to_vec())));
        assert_eq!(all.map(|e| e.name), Some("tour.txt"));
    }

    #[test]
    fn names_pick_one_example() {
        assert_eq!(find("tour").map(|e| e.name), Ok("tour.txt"));
        assert_eq!(find("Square.JS").map(|e| e.name), Ok("square.js"));
        assert_eq!(
            find("square").map(|e| e.name),
            Err(LookupError::Ambiguous {
                name: "square".into(),
                matches: vec!["square.txt", "square.js"],
            })
        );
        let unknown = find("c3po.txt").unwrap_err().to_string();
        assert!(unknown.contains("tour.txt, square.txt"), "{unknown}");
    }

    #[test]
    fn fits_read_and_describe_each_form() {
        let ex = |text: &'static str| Example {
            name: "x.txt",
            kind: Kind::Mission,
            text,
        };
        let fits = |t| ex(t).fits();
        assert_eq!(
            fits("# a\n# Models: all (notes)\n").map(|f| f.describe()),
            Ok("all".into())
        );
        assert_eq!(
            fits("# a\n# Models: all but robi\n").map(|f| f.describe()),
            Ok("all but robi".into())
        );
        assert_eq!(
            fits("# a\n# Models: r2d2 + bb8\n"),
            Ok(Fits::Together(vec![Model::R2D2, Model::BB8]))
        );
        assert_eq!(
            fits("# a\n# Models: R2-D2, r2q5\n").map(|f| f.describe()),
            Ok("r2d2, r2q5".into())
        );
        assert!(fits("# a\n# Models: c3po\n").is_err());
        assert!(
            fits("# a\ndrive 1 2\n# Models: all\n").is_err(),
            "only the header counts"
        );
    }
}
