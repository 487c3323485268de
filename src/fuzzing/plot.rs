//! `plot`'s readers (issue 27 point 6): any bytes read as `plot FILE` reads them — a run's
//! JSON lines, a droidctl capture of one droid or of several — give tracks or one error,
//! never a panic, in bounded memory: at most [`MAX_DROIDS`] droids, each path and channel
//! reduced to a bounded number of points. Whatever was read draws (a small SVG), with no
//! more channel strips than fit.
//!
//! Input layout: the first byte picks the reader (0: by the file's first bytes, 1: JSON,
//! 2: one droid's capture, 3: several droids'), its high nibble the channels asked for (0:
//! the defaults; else that many, from the byte after); the rest is the file.

use super::{Bytes, Target};
use crate::plot::decimate::MAX_BUCKETS;
use crate::plot::read::{self, Kind, Options, ReadError};
use crate::plot::track::{MAX_DROIDS, Tracks};
use crate::telemetry::history::Channel;
use std::io::Cursor;
use std::time::Duration;

pub const TARGET: Target = Target {
    name: "plot",
    run: run_input,
    dictionary: &[
        b"{\"t_ms\":0,\"x_cm\":1.5,\"y_cm\":-2,\"speed\":3,\"heading\":90,\"head_deg\":null,\"stance\":\"tripod\",\"battery_v\":4.1,\"collisions\":0}\n",
        b"{\"droid\":\"D2-0001\",",
        b"{\"droid\":\"BB-0002\",",
        b"\"done\":true}\n",
        b"\"yaw_deg\":179.5,",
        b"\"yaw_deg\":-179.5,",
        b"\"collisions\":4294967295",
        b"\"t_ms\":18446744073709551615,",
        b"\"motor_left_rad_s\":1e38,",
        b"droidctl-capture 1\n# model: r2d2\n",
        b"droidctl-capture 2\n# droid-1: r2d2 v2 D2-0001\n# droid-2: bb8 v1 BB-0002\n",
        b"@1 ",
        b"@2 ",
        b"0.000 connect\n",
        b" in notify 8d0a130d00d5d8\n",
        b" mark mission-start\n",
        b" end\n",
    ],
};

pub fn run_input(data: &[u8]) {
    let mut b = Bytes::new(data);
    let head = b.u8();
    let n = (head >> 4) as usize;
    let channels: Vec<Channel> = b
        .take(n)
        .iter()
        .map(|i| Channel::ALL[*i as usize % Channel::ALL.len()])
        .fold(Vec::new(), |mut v, c| {
            if !v.contains(&c) {
                v.push(c);
            }
            v
        });
    let file = b.rest();
    let mut tracks = Tracks::new(&channels);
    let opts = Options {
        interval: Duration::from_millis(250),
        model: None,
    };
    let mut open = || Ok(Cursor::new(file));
    let kind = match head & 0x0F {
        1 => Some(Kind::Json),
        2 => Some(Kind::Capture),
        3 => Some(Kind::Fleet),
        _ => read::kind(file),
    };
    let r = match kind {
        Some(Kind::Json) => read::json(Cursor::new(file), "the input", &mut tracks),
        Some(Kind::Capture) => read::capture(&mut open, "the input", opts, &mut tracks),
        Some(Kind::Fleet) => read::fleet(&mut open, "the input", opts, &mut tracks),
        Some(Kind::Btsnoop) | None => return,
    };
    if let Err(ReadError::Bad(m) | ReadError::Io(m)) = &r {
        assert!(!m.is_empty());
    }
    assert!(tracks.droids.len() <= MAX_DROIDS);
    for t in &tracks.droids {
        assert!(t.path.points().len() <= 6 * MAX_BUCKETS);
        assert!(t.hits.len() <= crate::plot::track::MAX_HITS);
        for (_, d) in &t.channels {
            assert!(d.points().len() <= 6 * MAX_BUCKETS);
        }
    }
    if r.is_err() || tracks.samples() == 0 {
        return;
    }
    let mut shown = tracks.channels();
    shown.truncate(crate::plot::strips_that_fit(360));
    let run = crate::plot::Run {
        title: "fuzz".into(),
        tracks,
        channels: shown,
    };
    if let Err(e) = crate::plot::svg(&run, (320, 360)) {
        panic!("a plot of what was read does not draw: {e}");
    }
}
