//! `droidctl config path|init|check`.

use super::CliError;
use crate::config::{Config, DEFAULT_TOML, config_path};
use clap::Subcommand;

#[derive(Debug, Subcommand)]
pub enum ConfigCmd {
    /// Print where the config file is read from.
    Path,
    /// Write the default config file (with comments) there.
    Init {
        /// Overwrite an existing file.
        #[arg(long)]
        force: bool,
    },
    /// Check the config file and report the first problem.
    Check,
}

pub fn run(cmd: ConfigCmd) -> Result<i32, CliError> {
    let path = config_path();
    match cmd {
        ConfigCmd::Path => {
            println!("{}", path.display());
            Ok(0)
        }
        ConfigCmd::Init { force } => {
            // Whatever is there (a dangling link too) is kept unless --force.
            if std::fs::symlink_metadata(&path).is_ok() && !force {
                return Err(CliError::failure(format!(
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
            println!("wrote {}", path.display());
            Ok(0)
        }
        ConfigCmd::Check => {
            Config::load(&path).map_err(|e| CliError::usage(e.to_string()))?;
            println!("{}: ok", path.display());
            Ok(0)
        }
    }
}
