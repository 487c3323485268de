//! `droidctl plot` (issue 22 point 6): a picture of a run. The path on the floor seen from
//! above, collisions marked, the start and the end; below it the chosen channels against
//! time, one strip each, with titles, axes and units. Drawn with plotters into a PNG (text
//! from a built-in bitmap font, [`pixel`]) or an SVG (text left to the viewer's fonts).
//!
//! The samples come from a `run --json` output or from a capture folded as replay folds it
//! ([`read`]), streamed and reduced as they come ([`track`], [`decimate`]): memory does not
//! grow with the input. A fleet's droids are drawn each in its own colour, named in the
//! legend; only as many channel strips as stay legible at the size asked are drawn
//! ([`strips_that_fit`]).

pub mod decimate;
pub mod pixel;
pub mod read;
pub mod track;

use crate::mission::Sample;
use crate::telemetry::history::Channel;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;

/// The path's colour (tests look for it).
pub const PATH: RGBColor = RGBColor(20, 90, 200);
/// Collision marks.
pub const COLLISION: RGBColor = RGBColor(220, 30, 30);
const START: RGBColor = RGBColor(30, 160, 60);
pub const CHANNEL_COLOURS: [RGBColor; 6] = [
    RGBColor(200, 100, 0),
    RGBColor(120, 40, 160),
    RGBColor(0, 140, 140),
    RGBColor(160, 120, 0),
    RGBColor(90, 90, 90),
    RGBColor(200, 0, 120),
];

/// Each droid's colour in a fleet's plot (the path, its channels), in order.
pub const DROID_COLOURS: [RGBColor; 10] = [
    RGBColor(20, 90, 200),
    RGBColor(220, 120, 0),
    RGBColor(0, 150, 70),
    RGBColor(150, 40, 170),
    RGBColor(0, 160, 180),
    RGBColor(140, 90, 40),
    RGBColor(230, 60, 150),
    RGBColor(100, 100, 100),
    RGBColor(120, 160, 0),
    RGBColor(60, 60, 160),
];

/// A channel strip needs this many pixels to stay legible (title, values, axis labels).
pub const MIN_STRIP_PX: u32 = 100;

/// How many channel strips stay legible in a picture `height` pixels high: the floor keeps
/// at least 40 % of the height, each strip at least [`MIN_STRIP_PX`], and the last strip its
/// time axis.
pub fn strips_that_fit(height: u32) -> usize {
    (height * 60 / 100).saturating_sub(40) as usize / MIN_STRIP_PX as usize
}

/// What a plot shows.
#[derive(Debug, Clone)]
pub struct Run {
    pub title: String,
    pub tracks: track::Tracks,
    pub channels: Vec<Channel>,
}

impl Run {
    /// A run of one droid from its samples (the channels: `channels`, or the defaults).
    pub fn of_samples(title: &str, samples: &[Sample], channels: &[Channel]) -> Run {
        let mut tracks = track::Tracks::new(channels);
        for s in samples {
            // One droid: never more than one track.
            let _ = tracks.push(None, s);
        }
        let channels = tracks.channels();
        Run {
            title: title.to_string(),
            tracks,
            channels,
        }
    }
}

/// Where the floor plot landed: its pixel rect and the ranges its axes span, so a caller (a
/// test) can say where a position must be drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct FloorFrame {
    pub pixels_x: Range<i32>,
    pub pixels_y: Range<i32>,
    pub x_cm: Range<f64>,
    pub y_cm: Range<f64>,
}

impl FloorFrame {
    /// The pixel of the floor position (x, y) cm (y grows up, pixels grow down).
    pub fn pixel(&self, x: f64, y: f64) -> (i32, i32) {
        let fx = (x - self.x_cm.start) / (self.x_cm.end - self.x_cm.start);
        let fy = (y - self.y_cm.start) / (self.y_cm.end - self.y_cm.start);
        let px = self.pixels_x.start as f64 + fx * (self.pixels_x.end - self.pixels_x.start) as f64;
        let py = self.pixels_y.end as f64 - fy * (self.pixels_y.end - self.pixels_y.start) as f64;
        (px.round() as i32, py.round() as i32)
    }
}

/// A channel's value in a sample.
pub fn value(c: Channel, s: &Sample) -> Option<f32> {
    match c {
        Channel::Pitch => s.pitch_deg,
        Channel::Roll => s.roll_deg,
        Channel::Yaw => s.yaw_deg,
        Channel::AccelX => s.accel_g.map(|a| a[0]),
        Channel::AccelY => s.accel_g.map(|a| a[1]),
        Channel::AccelZ => s.accel_g.map(|a| a[2]),
        Channel::GyroX => s.gyro_deg_s.map(|g| g[0]),
        Channel::GyroY => s.gyro_deg_s.map(|g| g[1]),
        Channel::GyroZ => s.gyro_deg_s.map(|g| g[2]),
        Channel::VelocityX => s.velocity_cm_s.map(|v| v[0]),
        Channel::VelocityY => s.velocity_cm_s.map(|v| v[1]),
        Channel::Speed => s.speed,
        Channel::Battery => s.battery_v,
        Channel::MotorLeft => s.motor_left_rad_s,
        Channel::MotorRight => s.motor_right_rad_s,
        Channel::Poti => s.poti.map(f32::from),
    }
    .filter(|v| v.is_finite())
}

/// A range around `lo..hi` with a margin, never empty.
fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let pad = ((hi - lo) * 0.08).max(5.0);
    (lo - pad, hi + pad)
}

type DrawResult<T> = Result<T, String>;

fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("{e:?}")
}

/// Draw `run` on `root`; returns where the floor went.
pub fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    run: &Run,
) -> DrawResult<FloorFrame> {
    root.fill(&WHITE).map_err(err)?;
    let (w, h) = root.dim_in_pixel();
    let strips = run.channels.len() as u32;
    let floor_h = if run.channels.is_empty() {
        h
    } else {
        h.saturating_sub((strips * 160 + 40).min(h * 60 / 100))
    };
    let (floor_area, rest) = root.split_vertically(floor_h);
    let droids = &run.tracks.droids;
    let fleet = run.tracks.is_fleet();
    let colour = |i: usize| {
        if fleet {
            DROID_COLOURS[i % DROID_COLOURS.len()]
        } else {
            PATH
        }
    };
    let span = |d: usize| {
        droids
            .iter()
            .filter_map(|t| t.path.range(d))
            .fold(None, |a: Option<(f64, f64)>, (lo, hi)| {
                let (lo, hi) = (lo as f64, hi as f64);
                Some(a.map_or((lo, hi), |(l, h)| (l.min(lo), h.max(hi))))
            })
            .unwrap_or((-50.0, 50.0))
    };
    let (mut x0, mut x1) = padded(span(0).0, span(0).1);
    let (mut y0, mut y1) = padded(span(1).0, span(1).1);
    // The same cm per pixel on both axes: widen the narrower span to the area's shape.
    let (label_x, label_y, margin, caption) = (45, 70, 15, 30);
    // A band at the top is kept free of data for the legend.
    let legend = 70.0;
    let pw = (w as i32 - label_y - 2 * margin).max(10) as f64;
    let ph = ((floor_h as i32 - label_x - caption - 2 * margin) as f64 - legend).max(10.0);
    let (sx, sy) = ((x1 - x0) / pw, (y1 - y0) / ph);
    if sx > sy {
        let extra = (sx * ph - (y1 - y0)) / 2.0;
        (y0, y1) = (y0 - extra, y1 + extra);
    } else {
        let extra = (sy * pw - (x1 - x0)) / 2.0;
        (x0, x1) = (x0 - extra, x1 + extra);
    }
    y1 += legend * (y1 - y0) / ph;
    let mut chart = ChartBuilder::on(&floor_area)
        .caption(
            format!("{}: path from above", run.title),
            ("sans-serif", 20).into_font(),
        )
        .margin(margin)
        .x_label_area_size(label_x)
        .y_label_area_size(label_y)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("x (cm)")
        .y_desc("y (cm)")
        .label_style(("sans-serif", 12))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    for (i, t) in droids.iter().enumerate() {
        let c = colour(i);
        let pts: Vec<(f64, f64)> = t
            .path
            .points()
            .iter()
            .map(|p| (p.v[0] as f64, p.v[1] as f64))
            .collect();
        let label = match (&t.name, fleet) {
            (Some(n), true) => n.clone(),
            _ => "path".to_string(),
        };
        chart
            .draw_series(LineSeries::new(pts, c.stroke_width(3)))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], c.stroke_width(3)));
    }
    let starts: Vec<(f64, f64)> = droids
        .iter()
        .filter_map(|t| t.path.ends())
        .map(|(p, _)| (p.v[0] as f64, p.v[1] as f64))
        .collect();
    if !starts.is_empty() {
        chart
            .draw_series(starts.iter().map(|p| Circle::new(*p, 6, START.filled())))
            .map_err(err)?
            .label("start")
            .legend(|(x, y)| Circle::new((x + 8, y), 5, START.filled()));
    }
    let hit_count: u64 = droids.iter().map(|t| t.hit_count).sum();
    if hit_count > 0 {
        chart
            .draw_series(
                droids
                    .iter()
                    .flat_map(|t| t.hits.iter())
                    .map(|p| Cross::new(*p, 8, COLLISION.stroke_width(3))),
            )
            .map_err(err)?
            .label(format!("collision ({hit_count})"))
            .legend(|(x, y)| Cross::new((x + 8, y), 5, COLLISION.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font(("sans-serif", 12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    let (pixels_x, pixels_y) = chart.plotting_area().get_pixel_range();
    let frame = FloorFrame {
        pixels_x,
        pixels_y,
        x_cm: x0..x1,
        y_cm: y0..y1,
    };

    // The channels, one strip each, sharing the time axis.
    let t_end = droids
        .iter()
        .map(|t| t.t_end_ms as f64 / 1000.0)
        .fold(0.0f64, f64::max)
        .max(0.1);
    let areas = rest.split_evenly((run.channels.len().max(1), 1));
    for (i, (c, area)) in run.channels.iter().zip(areas.iter()).enumerate() {
        let (lo, hi) = droids
            .iter()
            .filter_map(|t| t.channel(*c).and_then(|d| d.range(0)))
            .fold(None, |a: Option<(f64, f64)>, (lo, hi)| {
                let (lo, hi) = (lo as f64, hi as f64);
                Some(a.map_or((lo, hi), |(l, h)| (l.min(lo), h.max(hi))))
            })
            .unwrap_or(c.range());
        let pad = ((hi - lo) * 0.1).max(if hi == lo { 1.0 } else { 0.0 });
        let last = i + 1 == run.channels.len();
        let mut chart = ChartBuilder::on(area)
            .caption(c.label(), ("sans-serif", 14).into_font())
            .margin(10)
            .x_label_area_size(if last { 40 } else { 20 })
            .y_label_area_size(label_y)
            .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))
            .map_err(err)?;
        let mut mesh = chart.configure_mesh();
        mesh.y_desc(c.unit())
            .y_labels(4)
            .label_style(("sans-serif", 12))
            .light_line_style(RGBColor(235, 235, 235));
        if last {
            mesh.x_desc("time (s)");
        }
        mesh.draw().map_err(err)?;
        // An angle that wraps (yaw at ±180°) is cut where it wraps, not joined by a
        // vertical stroke across the strip.
        let (clo, chi) = c.range();
        let wrap = (chi - clo >= 360.0).then_some((chi - clo) as f32);
        for (k, t) in droids.iter().enumerate() {
            let Some(d) = t.channel(*c) else {
                continue;
            };
            let stroke = if fleet {
                colour(k)
            } else {
                CHANNEL_COLOURS[i % CHANNEL_COLOURS.len()]
            };
            for run in decimate::runs(&d.points(), wrap) {
                chart
                    .draw_series(LineSeries::new(run, stroke.stroke_width(2)))
                    .map_err(err)?;
            }
        }
    }
    root.present().map_err(err)?;
    Ok(frame)
}

/// Render `run` as a PNG of `size` into `out`.
pub fn png(run: &Run, size: (u32, u32), out: impl std::io::Write) -> DrawResult<FloorFrame> {
    let mut buf = vec![0u8; size.0 as usize * size.1 as usize * 3];
    let frame = {
        let root = pixel::Canvas::new(&mut buf, size).into_drawing_area();
        draw(&root, run)?
    };
    pixel::encode_png(&buf, size, out)?;
    Ok(frame)
}

/// Render `run` as SVG text of `size`.
pub fn svg(run: &Run, size: (u32, u32)) -> DrawResult<String> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw(&root, run)?;
    }
    Ok(text)
}
