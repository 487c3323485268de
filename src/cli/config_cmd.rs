//! `droidctl config path|show|init|check`.

use super::CliError;
use crate::config::{Config, DEFAULT_TOML, config_path};
use clap::Subcommand;
use std::io::Write;
use std::path::Path;

#[derive(Debug, Subcommand)]
pub enum ConfigCmd {
    /// Print where the config file is read from.
    Path,
    /// Print the configuration in effect, each value with where it came from (default,
    /// file), then what the app remembers per model (it wins over both).
    Show,
    /// Write the default config file (with comments) there.
    Init {
        /// Overwrite an existing file.
        #[arg(long)]
        force: bool,
    },
    /// Check the config file and report the first problem.
    Check,
}

pub fn run(cmd: ConfigCmd, out: &mut dyn Write) -> Result<i32, CliError> {
    let path = config_path();
    // Every line through `say`: a closed reader is status 0, a full disk status 1 (never a
    // panic, as `println!` gives).
    let mut say = |line: String| writeln!(out, "{line}").and_then(|()| out.flush());
    match cmd {
        ConfigCmd::Path => {
            say(path.display().to_string()).map_err(CliError::output)?;
            Ok(0)
        }
        ConfigCmd::Init { force } => {
            // Whatever is there (a dangling link too) is kept unless --force: bad input
            // (status 2), as for every file droidctl would otherwise replace.
            if std::fs::symlink_metadata(&path).is_ok() && !force {
                return Err(CliError::usage(format!(
                    "{} already exists; use --force to overwrite it",
                    path.display()
                )));
            }
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).map_err(|e| {
                    CliError::failure(format!("cannot create {}: {e}", dir.display()))
                })?;
            }
            // Written anew in its place: a FIFO there does not hang `init`, and a link is
            // replaced rather than written through.
            crate::own_file::write_atomic(&path, DEFAULT_TOML.as_bytes())
                .map_err(|e| CliError::failure(format!("cannot write {}: {e}", path.display())))?;
            say(format!("wrote {}", path.display())).map_err(CliError::output)?;
            Ok(0)
        }
        ConfigCmd::Check => {
            Config::load(&path).map_err(|e| CliError::usage(e.to_string()))?;
            let line = if path.exists() {
                format!("{}: ok", path.display())
            } else {
                format!(
                    "{}: no file; the defaults are in use (`droidctl config init` writes them \
                     there to edit)",
                    path.display()
                )
            };
            say(line).map_err(CliError::output)?;
            Ok(0)
        }
        ConfigCmd::Show => {
            show(&path, crate::app::remember::default_dir().as_deref(), out)?;
            out.flush().map_err(CliError::output)?;
            Ok(0)
        }
    }
}

/// Where a value in effect came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Source {
    Default,
    File,
}

impl Source {
    fn word(self) -> &'static str {
        match self {
            Source::Default => "default",
            Source::File => "file",
        }
    }
}

/// Print the configuration in effect from `path` (checked first, so a bad file is the same
/// error `config check` gives), then the settings remembered per model in `state`.
fn show(path: &Path, state: Option<&Path>, out: &mut dyn Write) -> Result<(), CliError> {
    Config::load(path).map_err(|e| CliError::usage(e.to_string()))?;
    let user: toml::Table = match crate::text_file::read(path, crate::text_file::MAX_CONFIG_BYTES) {
        // Already parsed by `load` above; an error here cannot happen but is not a panic.
        Ok(text) => toml::from_str(&text).map_err(|e| CliError::usage(e.to_string()))?,
        Err(_) => toml::Table::new(),
    };
    let defaults: toml::Table = toml::from_str(DEFAULT_TOML)
        .map_err(|e| CliError::failure(format!("shipped defaults: {e}")))?;
    let w = |out: &mut dyn Write, s: String| writeln!(out, "{s}").map_err(CliError::output);
    w(
        out,
        format!(
            "# the configuration in effect: {} ({})",
            path.display(),
            if path.exists() {
                "read"
            } else {
                "no file: defaults"
            }
        ),
    )?;
    for line in lines(&defaults, &user) {
        w(out, line)?;
    }
    let Some(state) = state else {
        return Ok(());
    };
    for model in crate::model::Model::ALL {
        if !crate::app::remember::path(state, model).exists() {
            continue;
        }
        let (r, warning) = crate::app::remember::Remembered::load(state, model);
        w(out, String::new())?;
        w(
            out,
            format!(
                "# remembered for {} ({}): the app uses these over the values above; R in the \
                 app forgets them",
                model.display_name(),
                crate::app::remember::path(state, model).display()
            ),
        )?;
        w(out, format!("[remembered.{}]", model.id()))?;
        if let Some(warning) = warning {
            w(out, format!("# {warning}"))?;
        }
        let table = toml::Table::try_from(&r).unwrap_or_default();
        for (k, v) in table {
            w(out, format!("{k} = {v}  # remembered"))?;
        }
    }
    Ok(())
}

/// The merged configuration as TOML lines, each leaf value followed by its source. Sections
/// come in the defaults' order, keys a file adds after them.
fn lines(defaults: &toml::Table, user: &toml::Table) -> Vec<String> {
    let mut out = Vec::new();
    let mut top = Vec::new();
    let mut sections = Vec::new();
    let names = defaults
        .keys()
        .chain(user.keys().filter(|k| !defaults.contains_key(*k)));
    for name in names {
        let d = defaults.get(name);
        let u = user.get(name);
        match (d, u) {
            (Some(toml::Value::Table(_)), _) | (None, Some(toml::Value::Table(_))) => {
                sections.push(name.clone())
            }
            _ => {
                let (v, s) = pick(d, u);
                if let Some(v) = v {
                    top.push(format!("{name} = {v}  # {}", s.word()));
                }
            }
        }
    }
    out.extend(top);
    let empty = toml::Table::new();
    for name in sections {
        let d = defaults.get(name.as_str()).and_then(toml::Value::as_table);
        let u = user.get(name.as_str()).and_then(toml::Value::as_table);
        out.push(String::new());
        out.push(format!("[{name}]"));
        let d = d.unwrap_or(&empty);
        let u = u.unwrap_or(&empty);
        // Key bindings replace per action (as the loader merges them): a file's action
        // stands whole.
        for key in d.keys().chain(u.keys().filter(|k| !d.contains_key(*k))) {
            let (v, s) = pick(d.get(key), u.get(key));
            if let Some(v) = v {
                out.push(format!("{} = {v}  # {}", toml_key(key), s.word()));
            }
        }
    }
    out
}

/// The value in effect of one key and where it came from.
fn pick<'a>(d: Option<&'a toml::Value>, u: Option<&'a toml::Value>) -> (Option<String>, Source) {
    match u {
        Some(v) => (Some(inline(v)), Source::File),
        None => (d.map(inline), Source::Default),
    }
}

/// A value on one line (an inline table for a nested one).
fn inline(v: &toml::Value) -> String {
    match v {
        toml::Value::Table(t) => {
            let parts: Vec<String> = t
                .iter()
                .map(|(k, v)| format!("{} = {}", toml_key(k), inline(v)))
                .collect();
            format!("{{ {} }}", parts.join(", "))
        }
        other => other.to_string(),
    }
}

/// A key as TOML writes it: bare when it may be, quoted otherwise.
fn toml_key(k: &str) -> String {
    if !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        k.to_string()
    } else {
        toml::Value::String(k.to_string()).to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shown(user: &str) -> Vec<String> {
        let d: toml::Table = toml::from_str(DEFAULT_TOML).unwrap();
        let u: toml::Table = toml::from_str(user).unwrap();
        lines(&d, &u)
    }

    #[test]
    fn a_value_from_the_file_says_file_and_the_rest_say_default() {
        let l = shown("[control]\ncruise_speed = 60\n");
        assert!(l.iter().any(|l| l == "cruise_speed = 60  # file"), "{l:#?}");
        assert!(
            l.iter()
                .any(|l| l.starts_with("speed_step = ") && l.ends_with("# default")),
            "{l:#?}"
        );
        assert!(l.iter().any(|l| l == "[control]"));
    }

    #[test]
    fn what_is_shown_parses_back_to_the_configuration_in_effect() {
        let user = "[control]\ncruise_speed = 60\n";
        let text = shown(user).join("\n");
        let back = Config::parse_merged(None, &text).unwrap();
        let direct = Config::parse_merged(None, user).unwrap();
        assert_eq!(back, direct);
    }
}
