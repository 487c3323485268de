//! `droidctl sim --serial rvr [--trace [--json]]`: the simulated RVR on a new
//! pseudo-terminal ([`crate::sim::serial`]). Prints the terminal's path on stdout and nothing
//! else there; status lines (and with `--trace` one line per packet, as `sim --bluez`
//! prints them) on stderr. Ctrl-C, SIGTERM and SIGHUP stop it; the pseudo-terminal goes with
//! it, which its clients see as the serial link lost.

use super::CliError;
use crate::model::Model;

/// Which models have a serial port to simulate: RVR's UART is the one droidctl knows of.
fn serial_model(id: &str) -> Result<Model, CliError> {
    match Model::from_id(id) {
        Some(m) if m == Model::ON_SERIAL => Ok(m),
        Some(m) => Err(CliError::usage(format!(
            "--serial: {} has no serial port (RVR's UART is the one there is); give `rvr`",
            m.display_name()
        ))),
        None => Err(CliError::usage(
            Model::parse_id(id).err().unwrap_or_default(),
        )),
    }
}

#[cfg(not(unix))]
pub fn run(
    model: &str,
    _link: Option<&std::path::Path>,
    _trace: bool,
    _json: bool,
) -> Result<i32, CliError> {
    serial_model(model)?;
    Err(CliError::failure(
        "`droidctl sim --serial` needs Linux or macOS (it serves on a pseudo-terminal); use \
         `--sim rvr` to drive a simulated RVR here",
    ))
}

/// `--link PATH`: a symbolic link to the pseudo-terminal while the simulator runs. The
/// kernel hands a closed pseudo-terminal's number to the next one opened, so a client
/// reconnecting to `/dev/pts/N` after the simulator stopped could reach another program's
/// terminal; the link goes with the simulator, and reconnecting finds no port.
#[cfg(unix)]
struct Symlink(std::path::PathBuf);

#[cfg(unix)]
impl Symlink {
    fn make(target: &std::path::Path, at: &std::path::Path) -> Result<Symlink, CliError> {
        std::os::unix::fs::symlink(target, at).map_err(|e| {
            CliError::failure(format!(
                "--link: cannot make {} (an existing file there is kept): {e}",
                at.display()
            ))
        })?;
        Ok(Symlink(at.to_path_buf()))
    }
}

#[cfg(unix)]
impl Drop for Symlink {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

#[cfg(unix)]
pub fn run(
    model: &str,
    link: Option<&std::path::Path>,
    trace: bool,
    json: bool,
) -> Result<i32, CliError> {
    use crate::sim::serial::{SerialReport, serve};
    use std::io::Write;
    let model = serial_model(model)?;
    let say = |line: &str| {
        let _ = writeln!(std::io::stderr(), "droidctl sim: {line}");
    };
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| CliError::failure(format!("cannot start the runtime: {e}")))?;
    rt.block_on(async move {
        let (pty, _peer, path) = crate::link::serial::tty::open_pty()
            .map_err(|e| CliError::failure(format!("cannot create a pseudo-terminal: {e}")))?;
        let _link = link.map(|at| Symlink::make(&path, at)).transpose()?;
        if let Some(at) = link {
            say(&format!("{} links to {}", at.display(), path.display()));
        }
        let device = model
            .name_prefix()
            .map_or_else(|| model.display_name().to_string(), |p| format!("{p}SIM"));
        say(&format!(
            "{} ({}) on {}, 115200 baud; Ctrl-C stops (the path is on stdout)",
            device,
            model.display_name(),
            path.display()
        ));
        super::sim::print_for_scripts(&path.display().to_string(), "the terminal's path")?;
        let report = |r: SerialReport| match r {
            SerialReport::Status(line) => say(&line),
            SerialReport::Trace { t_ms, record } => {
                let line = if json {
                    record.json_line(t_ms, &device)
                } else {
                    format!(
                        "{:>8} ms {} {:<3} {}",
                        t_ms,
                        device,
                        record.dir.name(),
                        record.text
                    )
                };
                let _ = writeln!(std::io::stderr(), "{line}");
            }
        };
        tokio::select! {
            sig = super::signals::terminated() => {
                say(&format!("{sig}: stopped"));
                Ok(0)
            }
            why = serve(pty, model, trace, report) => Err(CliError::failure(why)),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_rvr_has_a_serial_port() {
        assert_eq!(serial_model("rvr").ok(), Some(Model::Rvr));
        assert_eq!(serial_model("r2d2").err().map(|e| e.status), Some(2));
        assert_eq!(serial_model("tardis").err().map(|e| e.status), Some(2));
    }
}
