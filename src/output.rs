//! The one overwrite rule for the files droidctl writes when asked (`--record`, `--csv`,
//! `--jsonl`, `plot -o`): a file that exists is kept, and the command refuses before it
//! starts, unless `--force` says to replace it. Devices and pipes (`/dev/null`, `/dev/full`,
//! `/dev/stdout`, a FIFO) are written as they are, as a shell's `noclobber` does.

use std::fs::{File, OpenOptions};
use std::path::Path;

/// What an existing regular file gets without `force`.
pub fn exists_message(path: &Path) -> String {
    format!(
        "{} exists: droidctl does not overwrite it (--force replaces it)",
        path.display()
    )
}

/// Refuse `path` now when it is a regular file that exists and `force` is not given (for
/// outputs created only once the work is done, such as pictures).
pub fn check(path: &Path, force: bool) -> Result<(), String> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() && !force => Err(exists_message(path)),
        _ => Ok(()),
    }
}

/// Open `path` for writing under the rule: a new file is created; an existing regular file
/// is refused unless `force` (then truncated); anything else (a device, a pipe) is opened
/// for writing as it is.
pub fn create(path: &Path, force: bool) -> Result<File, String> {
    let cannot = |e: std::io::Error| format!("cannot create {}: {e}", path.display());
    match OpenOptions::new().write(true).create_new(true).open(path) {
        Ok(f) => Ok(f),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            let regular = std::fs::metadata(path).map_err(cannot)?.is_file();
            match (regular, force) {
                (true, false) => Err(exists_message(path)),
                (true, true) => OpenOptions::new()
                    .write(true)
                    .truncate(true)
                    .open(path)
                    .map_err(cannot),
                (false, _) => OpenOptions::new().write(true).open(path).map_err(cannot),
            }
        }
        Err(e) => Err(cannot(e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn an_existing_file_is_kept_unless_forced_and_a_device_is_written() {
        let dir = std::env::temp_dir().join(format!("droidctl-output-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("out.csv");
        create(&p, false).unwrap().write_all(b"first").unwrap();
        let e = create(&p, false).unwrap_err();
        assert!(e.contains("exists") && e.contains("--force"), "{e}");
        assert_eq!(check(&p, false).unwrap_err(), e);
        assert_eq!(std::fs::read(&p).unwrap(), b"first", "kept");
        check(&p, true).unwrap();
        create(&p, true).unwrap().write_all(b"2").unwrap();
        assert_eq!(
            std::fs::read(&p).unwrap(),
            b"2",
            "replaced, not appended to"
        );
        if cfg!(unix) {
            check(Path::new("/dev/null"), false).unwrap();
            create(Path::new("/dev/null"), false).unwrap();
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
