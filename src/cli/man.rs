//! `droidctl man [SUBCOMMAND…] [--dir DIR]`: the manual pages, droidctl(1) and one per
//! subcommand (droidctl-drive(1), droidctl-packet-decode(1) …, the names droidctl(1) refers
//! to), generated from the one CLI definition ([`super::Cli`]). droidctl(1) adds what the app
//! and the configuration define: KEYS (the key table the app's help shows, [`key_sections`]),
//! CONFIGURATION (the shipped defaults the user's file is merged over), FILES, ENVIRONMENT
//! and EXIT STATUS ([`super::EXIT_STATUSES`]); every page ends with EXIT STATUS and SEE ALSO.

use super::{Cli, CliError};
use crate::app::state::HelpSection;
use clap::{Args, CommandFactory};
use std::io::Write;
use std::path::PathBuf;

#[derive(Debug, Clone, Args)]
pub struct ManArgs {
    /// The subcommand whose page to print (`droidctl man packet decode` prints
    /// droidctl-packet-decode(1)); none: droidctl(1).
    #[arg(value_name = "SUBCOMMAND")]
    pub subcommand: Vec<String>,
    /// Write every page (droidctl.1 and droidctl-*.1) into DIR instead, e.g.
    /// ~/.local/share/man/man1 (created if missing).
    #[arg(long, value_name = "DIR", conflicts_with = "subcommand")]
    pub dir: Option<PathBuf>,
    /// With --dir: replace pages that exist (without it an existing page is kept and nothing
    /// is written).
    #[arg(long, requires = "dir")]
    pub force: bool,
}

/// The keys the man page lists: the app's help as it shows with the default bindings (driving,
/// the packet log, the scope, the palettes, prompts, help, the gamepad), then replay's own
/// keys. The one place that knows where the app keeps that table.
pub fn key_sections() -> Vec<HelpSection> {
    let config = crate::config::Config::defaults();
    let mut sections = crate::app::help::live(&config);
    sections.extend(
        crate::app::help::replay(&config.keymap)
            .into_iter()
            .filter(|s| s.title == "Replay"),
    );
    sections
}

/// The documentation chapters, for SEE ALSO: `cargo install` installs no README.
const DOCS: &str = "docs/README.md in droidctl's source: the manual, a chapter per topic \
                    (the app and its keys, fleets, monitoring, captures, Bluetooth, the \
                    simulators, remote droids, the bridge, configuration, missions)";

/// Text for roff: backslashes doubled, a line starting with `.` or `'` kept as text.
fn esc(text: &str) -> String {
    text.lines()
        .map(|l| {
            let l = l.replace('\\', "\\e");
            if l.starts_with('.') || l.starts_with('\'') {
                format!("\\&{l}")
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// A `.TP` item: `term` in bold, then `body`.
fn item(out: &mut String, term: &str, body: &str) {
    out.push_str(&format!(".TP\n\\fB{}\\fR\n{}\n", esc(term), esc(body)));
}

/// `~` for the home directory in a path shown.
fn shown(p: &std::path::Path) -> String {
    let text = p.display().to_string();
    match directories::BaseDirs::new().map(|b| b.home_dir().display().to_string()) {
        Some(home) if !home.is_empty() && text.starts_with(&home) => {
            format!("~{}", &text[home.len()..])
        }
        _ => text,
    }
}

fn keys_section() -> String {
    let mut s = String::from(
        ".SH KEYS\nThe defaults; each is configurable (see CONFIGURATION), and \\fB?\\fR in the app \
         shows them as configured. A key acts in the place on top only.\n",
    );
    for section in key_sections() {
        s.push_str(&format!(".SS {}\n", esc(&section.title)));
        for line in &section.lines {
            item(&mut s, &line.keys, &line.action);
        }
    }
    s
}

fn configuration_section() -> String {
    let mut s = String::from(
        ".SH CONFIGURATION\nA TOML file (see FILES), merged over the defaults below: it needs only \
         the keys it changes. \\fBdroidctl config init\\fR writes these defaults, with their \
         comments; \\fBdroidctl config check\\fR reports an invalid file with its line and key, \
         and the app refuses to start with one.\n.PP\n.nf\n",
    );
    s.push_str(&esc(crate::config::DEFAULT_TOML));
    s.push_str("\n.fi\n");
    s
}

fn files_section() -> String {
    let mut s = String::from(".SH FILES\n");
    item(
        &mut s,
        &shown(&crate::config::default_config_path()),
        "The configuration file (on this system; droidctl config path prints the one in use). \
         DROIDCTL_CONFIG names another.",
    );
    item(
        &mut s,
        &shown(&crate::logging::default_log_path()),
        "The log (on this system), rotated past 10 MiB; never written to the terminal the app \
         owns. DROIDCTL_LOG_FILE names another.",
    );
    s
}

fn environment_section() -> String {
    let mut s = String::from(".SH ENVIRONMENT\n");
    for (name, what) in [
        (
            "DROIDCTL_CONFIG",
            "The configuration file to read instead of the default; it must exist (/dev/null \
             for the defaults).",
        ),
        (
            "DROIDCTL_LOG_FILE",
            "The log file to write instead of the default.",
        ),
        (
            "DROIDCTL_LOG",
            "The log filter (default info; debug for more).",
        ),
        (
            "DROIDCTL_MQTT_PASSWORD",
            "The MQTT password of droidctl bridge, when --password-file does not give it.",
        ),
        (
            "DBUS_SYSTEM_BUS_ADDRESS",
            "The D-Bus bus where BlueZ is found (Linux): the line droidctl sim --bluez prints \
             points droidctl at its simulated droids.",
        ),
    ] {
        item(&mut s, name, what);
    }
    s
}

fn exit_status_section() -> String {
    let mut s = String::from(".SH EXIT STATUS\n");
    for (status, what) in super::EXIT_STATUSES {
        item(&mut s, &status.to_string(), what);
    }
    s
}

fn see_also_section(pages: &[String], this: &str) -> String {
    let others: Vec<String> = pages
        .iter()
        .filter(|p| p.as_str() != this)
        .map(|p| format!("\\fB{p}\\fR(1)"))
        .collect();
    format!(".SH SEE ALSO\n{}\n.PP\n{}\n", others.join(", "), esc(DOCS))
}

/// Every page: its name (`droidctl`, `droidctl-packet-decode`) and its subcommand path.
fn commands() -> Vec<(String, clap::Command)> {
    fn walk(cmd: &clap::Command, out: &mut Vec<(String, clap::Command)>) {
        let name = cmd.get_display_name().unwrap_or(cmd.get_name()).to_string();
        out.push((name, cmd.clone()));
        for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
            walk(sub, out);
        }
    }
    let mut cmd = Cli::command().disable_help_subcommand(true);
    cmd.build();
    let mut out = Vec::new();
    walk(&cmd, &mut out);
    out
}

/// Every page, rendered: (`droidctl-drive`, roff).
pub fn pages() -> Vec<(String, Vec<u8>)> {
    let all = commands();
    let names: Vec<String> = all.iter().map(|(n, _)| n.clone()).collect();
    all.into_iter()
        .map(|(name, cmd)| {
            let main = name == "droidctl";
            let man = clap_mangen::Man::new(cmd.clone())
                .source(format!("droidctl {}", env!("CARGO_PKG_VERSION")));
            let mut page = Vec::new();
            // The sections clap_mangen makes from the definition, then ours.
            man.render_title(&mut page)
                .and_then(|()| man.render_name_section(&mut page))
                .and_then(|()| man.render_synopsis_section(&mut page))
                .and_then(|()| man.render_description_section(&mut page))
                .and_then(|()| {
                    if cmd.get_arguments().any(|a| !a.is_hide_set()) {
                        man.render_options_section(&mut page)
                    } else {
                        Ok(())
                    }
                })
                .and_then(|()| {
                    if cmd.has_subcommands() {
                        man.render_subcommands_section(&mut page)
                    } else {
                        Ok(())
                    }
                })
                .and_then(|()| {
                    if cmd.get_after_help().is_some() || cmd.get_after_long_help().is_some() {
                        man.render_extra_section(&mut page)
                    } else {
                        Ok(())
                    }
                })
                .expect("rendering into memory cannot fail");
            let mut ours = String::new();
            if main {
                ours.push_str(&keys_section());
                ours.push_str(&configuration_section());
                ours.push_str(&files_section());
                ours.push_str(&environment_section());
            }
            if name == "droidctl-run" {
                ours.push_str(&missions_section());
            }
            ours.push_str(&exit_status_section());
            ours.push_str(&see_also_section(&names, &name));
            page.extend_from_slice(ours.as_bytes());
            (name, page)
        })
        .collect()
}

fn missions_section() -> String {
    format!(
        ".SH MISSION SCRIPTS\nOne command per line; blank lines and # comments are ignored. \
         The commands: {}. With several droids, @NAME before a line addresses one droid and \
         together {{ … }} runs its lines on every droid at once. The whole script is checked \
         before anything is sent. docs/missions.md describes every line.\n",
        crate::script::COMMANDS.join(", ")
    )
}

/// The page of `path` (none: droidctl(1)).
pub fn page(path: &[String]) -> Result<Vec<u8>, CliError> {
    let name = std::iter::once("droidctl")
        .chain(path.iter().map(String::as_str))
        .collect::<Vec<_>>()
        .join("-");
    let all = pages();
    let names: Vec<&str> = all.iter().map(|(n, _)| n.as_str()).collect();
    let list = names
        .iter()
        .filter_map(|n| n.strip_prefix("droidctl-"))
        .map(|n| n.replace('-', " "))
        .collect::<Vec<_>>()
        .join(", ");
    all.iter()
        .find(|(n, _)| *n == name)
        .map(|(_, p)| p.clone())
        .ok_or_else(|| {
            CliError::usage(format!(
                "no page for `{}`: use one of {list}",
                path.join(" ")
            ))
        })
}

/// Whether the file at `path` is droidctl's own page `name` (its title line within the first
/// lines, as [`pages`] writes it, naming droidctl as its source), from whichever version.
fn ours(path: &std::path::Path, name: &str) -> bool {
    use std::io::Read;
    // Only a regular file is read (opening a FIFO would wait for a writer).
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return false;
    }
    let Ok(f) = std::fs::File::open(path) else {
        return false;
    };
    let mut head = Vec::new();
    if f.take(512).read_to_end(&mut head).is_err() {
        return false;
    }
    let title = format!(".TH {name} 1 ");
    String::from_utf8_lossy(&head)
        .lines()
        .take(4)
        .any(|l| l.starts_with(&title) && l.contains("\"droidctl "))
}

/// Run `droidctl man`.
pub fn run(args: ManArgs, out: &mut dyn Write) -> Result<i32, CliError> {
    let Some(dir) = args.dir else {
        out.write_all(&page(&args.subcommand)?)
            .and_then(|()| out.flush())
            .map_err(CliError::output)?;
        return Ok(0);
    };
    std::fs::create_dir_all(&dir)
        .map_err(|e| CliError::failure(format!("cannot create {}: {e}", dir.display())))?;
    let pages = pages();
    // All refused before any is written. A page droidctl wrote itself (of any version) is
    // replaced without --force: `man --dir` after an upgrade brings the pages up to date.
    for (name, _) in &pages {
        let path = dir.join(format!("{name}.1"));
        crate::output::check(&path, args.force || ours(&path, name)).map_err(CliError::usage)?;
    }
    for (name, page) in &pages {
        let path = dir.join(format!("{name}.1"));
        crate::output::create(&path, args.force || ours(&path, name))
            .and_then(|mut f| f.write_all(page).map_err(|e| e.to_string()))
            .map_err(|e| CliError::failure(format!("cannot write {}: {e}", path.display())))?;
    }
    let _ = writeln!(
        std::io::stderr(),
        "droidctl: wrote {} pages into {}",
        pages.len(),
        dir.display()
    );
    Ok(0)
}
