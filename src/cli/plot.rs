//! `droidctl plot FILE`: a capture or a `run --json` output as a PNG or SVG picture of the
//! run (the path from above with collisions, the chosen channels against time).

use super::CliError;
use crate::telemetry::history::Channel;
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Args)]
pub struct PlotArgs {
    /// A capture (`--record`, btsnoop) or the output of `run --json` / `replay --json`.
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Where to write: `.png` or `.svg` by the extension; repeat for both. Default: FILE
    /// with `.png`.
    #[arg(short, long = "out", value_name = "PATH")]
    pub out: Vec<PathBuf>,
    /// Channels plotted against time, comma separated (e.g. `speed,yaw,gyro_z`; see README
    /// for the names). Default: speed and yaw, Robi's wheels on Robi 42.
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub channels: Vec<String>,
    /// Image size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1200x900", value_name = "WxH")]
    pub size: String,
    /// For a capture: the sample interval in milliseconds.
    #[arg(long, default_value_t = 100, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..=60_000))]
    pub interval: u64,
    /// For a capture that does not name its droid: the model.
    #[arg(long, value_name = "MODEL")]
    pub model: Option<String>,
}

/// `1200x900` within 200..=8000 on each side.
fn parse_size(s: &str) -> Result<(u32, u32), CliError> {
    let bad = || CliError::usage(format!("--size {s:?}: use WIDTHxHEIGHT, each 200..=8000"));
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if !(200..=8000).contains(&w) || !(200..=8000).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

/// Samples of a `run --json` output: every object but the summary (`"done": true`).
fn json_samples(text: &str, file: &Path) -> Result<Vec<crate::mission::Sample>, CliError> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let v: serde_json::Value = serde_json::from_str(line)
            .map_err(|e| CliError::usage(format!("{}:{}: not JSON: {e}", file.display(), i + 1)))?;
        if v.get("done").is_some() {
            continue;
        }
        let s = serde_json::from_value(v).map_err(|e| {
            CliError::usage(format!(
                "{}:{}: not a telemetry sample: {e}",
                file.display(),
                i + 1
            ))
        })?;
        out.push(s);
    }
    Ok(out)
}

/// The samples in `file`, whichever kind it is.
pub fn samples(args: &PlotArgs) -> Result<Vec<crate::mission::Sample>, CliError> {
    let bytes = std::fs::read(&args.file)
        .map_err(|e| CliError::usage(format!("cannot read {}: {e}", args.file.display())))?;
    let first = bytes.iter().find(|b| !b.is_ascii_whitespace());
    if first == Some(&b'{') {
        let text = String::from_utf8_lossy(&bytes);
        return json_samples(&text, &args.file);
    }
    let replay = super::replay::ReplayArgs {
        file: args.file.clone(),
        json: false,
        csv: None,
        interval: args.interval,
        model: args.model.clone(),
        handle: Vec::new(),
    };
    let (capture, model) = super::replay::load(&replay)?;
    let mut out = Vec::new();
    crate::capture::replay::samples(
        &capture,
        model,
        std::time::Duration::from_millis(args.interval),
        &mut |s| {
            out.push(s.clone());
            Ok(())
        },
        &mut |_, _| {},
    )
    .map_err(CliError::output)?;
    Ok(out)
}

pub fn run(args: PlotArgs) -> Result<i32, CliError> {
    let size = parse_size(&args.size)?;
    let channels = args
        .channels
        .iter()
        .filter(|n| !n.trim().is_empty())
        .map(|n| {
            Channel::parse(n).ok_or_else(|| {
                let all: Vec<&str> = Channel::ALL.iter().map(|c| c.name()).collect();
                CliError::usage(format!("unknown channel {n:?}: use {}", all.join(", ")))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let outs = if args.out.is_empty() {
        vec![args.file.with_extension("png")]
    } else {
        args.out.clone()
    };
    for o in &outs {
        match o.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("png") || e.eq_ignore_ascii_case("svg") => {}
            _ => {
                return Err(CliError::usage(format!(
                    "{}: the output must end in .png or .svg",
                    o.display()
                )));
            }
        }
    }
    let samples = samples(&args)?;
    if samples.is_empty() {
        return Err(CliError::failure(format!(
            "{}: no telemetry samples to plot",
            args.file.display()
        )));
    }
    let channels = if channels.is_empty() {
        crate::plot::default_channels(&samples)
    } else {
        channels
    };
    let run = crate::plot::Run {
        title: args
            .file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        samples,
        channels,
    };
    for o in &outs {
        let svg = o.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg"));
        let written = if svg {
            crate::plot::svg(&run, size)
                .and_then(|t| std::fs::write(o, t).map_err(|e| e.to_string()))
        } else {
            std::fs::File::create(o)
                .map_err(|e| e.to_string())
                .and_then(|f| crate::plot::png(&run, size, std::io::BufWriter::new(f)).map(|_| ()))
        };
        written.map_err(|e| CliError::failure(format!("cannot write {}: {e}", o.display())))?;
        eprintln!("droidctl: wrote {}", o.display());
    }
    Ok(0)
}
