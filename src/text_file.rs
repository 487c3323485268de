//! The one bound for the text files droidctl reads whole (mission scripts, Sphero Edu
//! programs, the configuration): read at most a limit, so a huge or endless file
//! (`/dev/zero`, a FIFO that never ends) is one clear error, never unbounded memory.

use std::io::Read;
use std::path::Path;

/// Mission scripts and Sphero Edu programs: a classroom's are a few KiB.
pub const MAX_SCRIPT_BYTES: u64 = 4 * 1024 * 1024;
/// The configuration file.
pub const MAX_CONFIG_BYTES: u64 = 1024 * 1024;

/// The text of `path`, if it holds at most `max` bytes of UTF-8. A larger file is an
/// `InvalidData` error that says the limit.
pub fn read(path: &Path, max: u64) -> std::io::Result<String> {
    read_from(std::fs::File::open(path)?, max)
}

/// [`read`] of what is already open (a file opened as [`crate::own_file`] opens it).
pub fn read_from(from: impl Read, max: u64) -> std::io::Result<String> {
    let mut text = String::new();
    from.take(max + 1).read_to_string(&mut text)?;
    if text.len() as u64 > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("larger than {} KiB", max / 1024),
        ));
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_endless_file_is_an_error_not_unbounded_memory() {
        let e = read(Path::new("/dev/zero"), 4096).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
        assert_eq!(e.to_string(), "larger than 4 KiB");
        let dir = std::env::temp_dir().join(format!("droidctl-text-file-{}", std::process::id()));
        std::fs::write(&dir, "ok\n").unwrap();
        assert_eq!(read(&dir, 3).unwrap(), "ok\n");
        assert!(read(&dir, 2).is_err());
        let _ = std::fs::remove_file(&dir);
    }
}
