//! `droidctl plot FILE`: a capture or a `run --json` output as a PNG or SVG picture of the
//! run (the path from above with collisions, the chosen channels against time).

use super::CliError;
use crate::telemetry::history::Channel;
use clap::Args;
use std::io::Write as _;
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
    /// Replace the pictures when they exist (without it an existing file is kept and nothing
    /// is drawn).
    #[arg(long)]
    pub force: bool,
    /// Channels plotted against time, comma separated (e.g. `speed,yaw,gyro_z`; see docs/monitoring.md
    /// for the names). Default: speed and yaw, Robi's wheels on Robi 42.
    #[arg(long, value_delimiter = ',', value_name = "NAMES",
          add = clap_complete::ArgValueCandidates::new(super::complete::channels))]
    pub channels: Vec<String>,
    /// Image size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1200x900", value_name = "WxH")]
    pub size: String,
    /// For a capture: the sample interval in milliseconds.
    #[arg(long, default_value_t = 100, value_name = "MS", value_parser = clap::value_parser!(u64).range(1..=60_000))]
    pub interval: u64,
    /// For a capture that does not name its droid: the model.
    #[arg(long, value_name = "MODEL", value_parser = super::models::ModelNames::one())]
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

/// The input's samples, streamed into tracks gathering `channels` (none: the defaults).
pub fn tracks(
    args: &PlotArgs,
    channels: &[Channel],
) -> Result<crate::plot::track::Tracks, CliError> {
    use crate::plot::read::{self, Kind, ReadError};
    use std::io::{BufRead, BufReader};
    let file = &args.file;
    let name = file.display().to_string();
    let open = || std::fs::File::open(file).map(|f| BufReader::with_capacity(64 * 1024, f));
    let mut head = open().map_err(|e| CliError::usage(format!("cannot read {name}: {e}")))?;
    let first = head
        .fill_buf()
        .map_err(|e| CliError::failure(format!("cannot read {name}: {e}")))?
        .to_vec();
    let mut tracks = crate::plot::track::Tracks::new(channels);
    let whole = std::fs::metadata(file).is_ok_and(|m| m.len() <= first.len() as u64);
    if whole && first.iter().all(u8::is_ascii_whitespace) {
        // Empty: nothing to plot (said below, status 2 as for any input without samples).
        return Ok(tracks);
    }
    let model = match &args.model {
        Some(m) => Some(crate::model::Model::parse_id(m).map_err(CliError::usage)?),
        None => None,
    };
    let opts = read::Options {
        interval: std::time::Duration::from_millis(args.interval),
        model,
    };
    let mut reopen = open;
    let r = match read::kind(&first) {
        Some(Kind::Json) => read::json(head, &name, &mut tracks),
        Some(Kind::Capture) => read::capture(&mut reopen, &name, opts, &mut tracks),
        Some(Kind::Fleet) => read::fleet(&mut reopen, &name, opts, &mut tracks),
        Some(Kind::Btsnoop) => {
            // A phone's log is sorted by time as a whole: loaded, then sampled.
            let replay = super::replay::ReplayArgs {
                file: file.clone(),
                json: false,
                csv: None,
                force: false,
                interval: args.interval,
                model: args.model.clone(),
                handle: Vec::new(),
            };
            let (capture, model) = super::replay::load(&replay)?;
            let mut failed = None;
            crate::capture::replay::samples(
                &capture,
                model,
                opts.interval,
                &mut |s| {
                    if let Err(e) = tracks.push(None, s) {
                        failed = Some(e);
                    }
                    Ok(())
                },
                &mut |_, _| {},
            )
            .map_err(CliError::output)?;
            failed.map_or(Ok(()), |e| Err(ReadError::Bad(e)))
        }
        None => Err(ReadError::Bad(format!(
            "{name} is neither a run's JSON output nor a capture: {}",
            crate::plot::read::READS
        ))),
    };
    match r {
        Ok(()) => Ok(tracks),
        Err(ReadError::Bad(m)) => Err(CliError::usage(m)),
        Err(ReadError::Io(m)) => Err(CliError::failure(m)),
    }
}

/// The channels asked for: known names, each once, no more than stay legible at `height`.
fn channels(args: &PlotArgs, height: u32) -> Result<Vec<Channel>, CliError> {
    let mut out: Vec<Channel> = Vec::new();
    for n in args
        .channels
        .iter()
        .map(|n| n.trim())
        .filter(|n| !n.is_empty())
    {
        let c = Channel::parse(n).ok_or_else(|| {
            let all: Vec<&str> = Channel::ALL.iter().map(|c| c.name()).collect();
            CliError::usage(format!("unknown channel {n:?}: use {}", all.join(", ")))
        })?;
        if !out.contains(&c) {
            out.push(c);
        }
    }
    let fit = crate::plot::strips_that_fit(height);
    if out.len() > fit {
        return Err(CliError::usage(format!(
            "--channels: {} channels asked for; {fit} fit legibly in a picture {height} pixels \
             high (each strip needs {} pixels): ask for fewer, or a taller --size",
            out.len(),
            crate::plot::MIN_STRIP_PX
        )));
    }
    Ok(out)
}

/// Whether `a` and `b` are the same file (both exist and are one).
fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

pub fn run(args: PlotArgs) -> Result<i32, CliError> {
    let size = parse_size(&args.size)?;
    let channels = channels(&args, size.1)?;
    // `plot X.png`: the default output is never the input itself.
    let outs = if args.out.is_empty() {
        let png = args.file.with_extension("png");
        if same_file(&png, &args.file) {
            let stem = args
                .file
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            vec![args.file.with_file_name(format!("{stem}.plot.png"))]
        } else {
            vec![png]
        }
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
        if same_file(o, &args.file) {
            return Err(CliError::usage(format!(
                "{}: that is the input; the picture would overwrite it (choose another -o)",
                o.display()
            )));
        }
        crate::output::check(o, args.force).map_err(CliError::usage)?;
    }
    let tracks = tracks(&args, &channels)?;
    if tracks.samples() == 0 {
        return Err(CliError::usage(format!(
            "{}: no telemetry samples to plot",
            args.file.display()
        )));
    }
    let mut channels = tracks.channels();
    // The defaults, at a size too small for all of them: as many as fit.
    channels.truncate(crate::plot::strips_that_fit(size.1));
    let run = crate::plot::Run {
        title: args
            .file
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        tracks,
        channels,
    };
    for o in &outs {
        let svg = o.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg"));
        let written = if svg {
            crate::plot::svg(&run, size).and_then(|t| {
                crate::output::create(o, args.force)
                    .and_then(|mut f| f.write_all(t.as_bytes()).map_err(|e| e.to_string()))
            })
        } else {
            crate::output::create(o, args.force).and_then(|f| {
                let mut w = std::io::BufWriter::new(f);
                crate::plot::png(&run, size, &mut w)?;
                w.flush().map_err(|e| e.to_string())
            })
        };
        written.map_err(|e| CliError::failure(format!("cannot write {}: {e}", o.display())))?;
        let _ = writeln!(std::io::stderr(), "droidctl: wrote {}", o.display());
    }
    Ok(0)
}
