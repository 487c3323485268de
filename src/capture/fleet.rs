//! A capture of several droids in one file, each droid's traffic kept apart.
//!
//! It is the droidctl capture format with a droid on every line: the magic line says version
//! 2 (an older droidctl refuses it with its version rather than misreading it), the header
//! lists the droids, and each event line starts with `@K` (K from 1, in the header's order)
//! followed by the version-1 event line of that droid:
//!
//! ```text
//! droidctl-capture 2
//! # droidctl: 0.1.0
//! # started: 2025-06-01T10:00:00.123Z
//! # droids: 2
//! # droid-1: r2d2 v2 D2-0001
//! # droid-2: bb8 v1 BB-0002
//! @1 0.000 connect
//! @2 0.004 connect
//! @1 0.120 out api 8d0a130d00d5d8
//! …
//! ```
//!
//! Reading splits it into one [`Capture`] per droid, each read by the version-1 reader, so
//! everything that replays or decodes one droid's capture does so for each droid of a fleet.

use super::{Capture, Header, MAGIC};
use crate::model::Model;
use std::fmt::Write;

/// The format version of a capture of several droids.
pub const FLEET_VERSION: u32 = 2;

/// Most droids a capture may list (a bound on what a file can make us allocate).
pub const MAX_DROIDS: usize = 64;

/// The header of a capture of several droids.
pub fn header_text(droids: &[Header]) -> String {
    let mut s = format!("{MAGIC} {FLEET_VERSION}\n");
    let first = droids.first();
    if let Some(v) = first.and_then(|h| h.droidctl.as_deref()) {
        let _ = writeln!(s, "# droidctl: {v}");
    }
    if let Some(v) = first.and_then(|h| h.started.as_deref()) {
        let _ = writeln!(s, "# started: {v}");
    }
    let _ = writeln!(s, "# droids: {}", droids.len());
    for (i, h) in droids.iter().enumerate() {
        let model = h.model.map(Model::id).unwrap_or("-");
        let family = h
            .family
            .map(|p| crate::family::for_protocol(p).name())
            .unwrap_or("-");
        let name = h.droid.as_deref().unwrap_or("-").replace(['\n', '\r'], " ");
        let _ = writeln!(s, "# droid-{}: {model} {family} {name}", i + 1);
    }
    s
}

/// Whether `bytes` start like a capture of several droids.
pub fn sniff(bytes: &[u8]) -> bool {
    let head = format!("{MAGIC} {FLEET_VERSION}");
    bytes.starts_with(head.as_bytes())
        && matches!(bytes.get(head.len()), None | Some(b'\n' | b'\r' | b' '))
}

/// Split a capture of several droids into one capture per droid (in the header's order).
/// Bad lines are warnings of the droid they name (or of every droid), as for one droid.
pub fn split(text: &str) -> Result<Vec<Capture>, String> {
    let mut lines = text.split_inclusive('\n');
    let first = lines.next().unwrap_or("");
    if !sniff(first.as_bytes()) {
        return Err(format!(
            "line 1: not a capture of several droids (it does not start with \"{MAGIC} {FLEET_VERSION}\")"
        ));
    }
    let mut common = String::new();
    let mut droids: Vec<String> = Vec::new();
    let mut texts: Vec<String> = Vec::new();
    let mut warnings: Vec<String> = Vec::new();
    for (i, line) in lines.enumerate() {
        let n = i + 2;
        if let Some(c) = line.strip_prefix('#') {
            let Some((k, v)) = c.split_once(':') else {
                continue;
            };
            let (k, v) = (k.trim(), v.trim());
            match k {
                "droidctl" | "started" => {
                    let _ = writeln!(common, "# {k}: {v}");
                }
                _ => {
                    if let Some(idx) = k.strip_prefix("droid-") {
                        let idx: usize = idx
                            .parse()
                            .map_err(|_| format!("line {n}: {k:?} is not droid-N"))?;
                        if idx != droids.len() + 1 || idx > MAX_DROIDS {
                            return Err(format!(
                                "line {n}: droid-{idx} out of order (expected droid-{}, at most {MAX_DROIDS})",
                                droids.len() + 1
                            ));
                        }
                        droids.push(droid_header(v));
                    }
                }
            }
            continue;
        }
        if droids.is_empty() {
            return Err(format!("line {n}: an event before the droids are listed"));
        }
        if texts.is_empty() {
            texts = droids
                .iter()
                .map(|h| format!("{MAGIC} {}\n{common}{h}", super::VERSION))
                .collect();
        }
        if line.trim().is_empty() {
            continue;
        }
        match line.strip_prefix('@').and_then(|r| r.split_once(' ')) {
            Some((k, rest)) => match k.parse::<usize>() {
                Ok(k) if (1..=texts.len()).contains(&k) => texts[k - 1].push_str(rest),
                _ => warnings.push(format!("line {n}: no droid {k:?} in this capture")),
            },
            // A line about no droid in particular (none is written now): every droid's.
            None => texts.iter_mut().for_each(|t| t.push_str(line)),
        }
    }
    if droids.is_empty() {
        return Err("the capture lists no droids (no `# droid-1:` line)".into());
    }
    if texts.is_empty() {
        texts = droids
            .iter()
            .map(|h| format!("{MAGIC} {}\n{common}{h}", super::VERSION))
            .collect();
    }
    let mut out = Vec::with_capacity(texts.len());
    for t in texts {
        let mut c = Capture::from_text(&t)?;
        c.warnings.extend(warnings.iter().cloned());
        out.push(c);
    }
    Ok(out)
}

/// `MODEL FAMILY NAME` as header lines of one droid's capture.
fn droid_header(v: &str) -> String {
    let mut words = v.splitn(3, ' ');
    let model = words.next().unwrap_or("-");
    let family = words.next().unwrap_or("-");
    let name = words.next().unwrap_or("").trim();
    let mut s = String::new();
    if model != "-" {
        let _ = writeln!(s, "# model: {model}");
    }
    if family != "-" {
        let _ = writeln!(s, "# family: {family}");
    }
    if !name.is_empty() && name != "-" {
        let _ = writeln!(s, "# droid: {name}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::capture::{Event, Timed, event_line};
    use std::time::Duration;

    fn header(model: Model, name: &str) -> Header {
        Header {
            droidctl: Some("0.1.0".into()),
            model: Some(model),
            family: Some(model.protocol()),
            droid: Some(name.into()),
            started: Some("2025-06-01T10:00:00.123Z".into()),
        }
    }

    #[test]
    fn droids_are_kept_apart_and_read_back_as_one_capture_each() {
        let mut text = header_text(&[
            header(Model::R2D2, "D2-0001"),
            header(Model::BB8, "BB-0002"),
        ]);
        let ev = |ms: u64, e: Event| {
            event_line(&Timed {
                at: Duration::from_millis(ms),
                event: e,
            })
        };
        text += &format!("@1 {}", ev(0, Event::Connect));
        text += &format!("@2 {}", ev(4, Event::Connect));
        text += &format!("@2 {}", ev(5, Event::In(vec![0xff, 0xff, 0, 1, 1, 0xfd])));
        text += &format!("@1 {}", ev(9, Event::Close));
        text += &format!("@3 {}", ev(10, Event::Close));
        text += "@1 not a time\n";
        assert!(sniff(text.as_bytes()));
        let split = split(&text).unwrap();
        assert_eq!(split.len(), 2);
        assert_eq!(split[0].header.model, Some(Model::R2D2));
        assert_eq!(split[0].header.droid.as_deref(), Some("D2-0001"));
        assert_eq!(split[0].events.len(), 2);
        assert_eq!(split[1].header.model, Some(Model::BB8));
        assert_eq!(split[1].events.len(), 2);
        assert_eq!(
            split[1].events[1].event,
            Event::In(vec![0xff, 0xff, 0, 1, 1, 0xfd])
        );
        assert!(
            split[0]
                .warnings
                .iter()
                .any(|w| w.contains("no droid \"3\""))
        );
        assert!(split[0].warnings.iter().any(|w| w.contains("not a time")));
        // One droid's reader refuses the fleet's version with what to do.
        let e = Capture::from_text(&text).unwrap_err();
        assert!(e.contains("several droids"), "{e}");
    }

    #[test]
    fn malformed_headers_are_errors() {
        assert!(split("droidctl-capture 1\n").is_err());
        assert!(split("droidctl-capture 2\n@1 0.000 connect\n").is_err());
        assert!(split("droidctl-capture 2\n# droid-2: r2d2 v2 X\n").is_err());
        assert!(split("droidctl-capture 2\n# droids: 0\n").is_err());
        assert!(!sniff(b"droidctl-capture 20\n"));
    }
}
