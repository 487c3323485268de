//! `droidctl plot` (issue 22 point 6): a picture of a run. The path on the floor seen from
//! above, collisions marked, the start and the end; below it the chosen channels against
//! time, one strip each, with titles, axes and units. Drawn with plotters into a PNG (text
//! from a built-in bitmap font, [`pixel`]) or an SVG (text left to the viewer's fonts).
//!
//! The samples come from a `run --json` output or from a capture folded as replay folds it
//! ([`crate::capture::replay::samples`]).

pub mod pixel;

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
const CHANNEL_COLOURS: [RGBColor; 6] = [
    RGBColor(200, 100, 0),
    RGBColor(120, 40, 160),
    RGBColor(0, 140, 140),
    RGBColor(160, 120, 0),
    RGBColor(90, 90, 90),
    RGBColor(200, 0, 120),
];

/// What a plot shows.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    pub title: String,
    pub samples: Vec<Sample>,
    pub channels: Vec<Channel>,
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

/// Points on the floor, cm.
type Points = Vec<(f64, f64)>;

/// The floor positions, and where collisions happened (the position of the sample whose
/// count went up).
fn path(samples: &[Sample]) -> (Points, Points) {
    let mut pts = Vec::new();
    let mut hits = Vec::new();
    let mut count = samples.first().map_or(0, |s| s.collisions);
    for s in samples {
        if let (Some(x), Some(y)) = (s.x_cm, s.y_cm)
            && x.is_finite()
            && y.is_finite()
        {
            pts.push((x as f64, y as f64));
            if s.collisions > count {
                hits.push((x as f64, y as f64));
            }
        }
        count = count.max(s.collisions);
    }
    (pts, hits)
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
    let strips = run.channels.len().max(1) as u32;
    let floor_h = if run.channels.is_empty() {
        h
    } else {
        (h * 55 / 100).max(h.saturating_sub(strips * 160))
    };
    let (floor_area, rest) = root.split_vertically(floor_h);
    let (pts, hits) = path(&run.samples);
    let (x0, x1) = pts
        .iter()
        .fold(None, |a: Option<(f64, f64)>, p| {
            Some(a.map_or((p.0, p.0), |(l, h)| (l.min(p.0), h.max(p.0))))
        })
        .unwrap_or((-50.0, 50.0));
    let (y0, y1) = pts
        .iter()
        .fold(None, |a: Option<(f64, f64)>, p| {
            Some(a.map_or((p.1, p.1), |(l, h)| (l.min(p.1), h.max(p.1))))
        })
        .unwrap_or((-50.0, 50.0));
    let (mut x0, mut x1) = padded(x0, x1);
    let (mut y0, mut y1) = padded(y0, y1);
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
    chart
        .draw_series(LineSeries::new(pts.iter().copied(), PATH.stroke_width(3)))
        .map_err(err)?
        .label("path")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], PATH.stroke_width(3)));
    if let Some(p) = pts.first() {
        chart
            .draw_series([Circle::new(*p, 6, START.filled())])
            .map_err(err)?
            .label("start")
            .legend(|(x, y)| Circle::new((x + 8, y), 5, START.filled()));
    }
    if !hits.is_empty() {
        chart
            .draw_series(
                hits.iter()
                    .map(|p| Cross::new(*p, 8, COLLISION.stroke_width(3))),
            )
            .map_err(err)?
            .label(format!("collision ({})", hits.len()))
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
    let t_end = run
        .samples
        .iter()
        .map(|s| s.t_ms as f64 / 1000.0)
        .fold(0.0f64, f64::max)
        .max(0.1);
    let areas = rest.split_evenly((run.channels.len(), 1));
    for (i, (c, area)) in run.channels.iter().zip(areas.iter()).enumerate() {
        let series: Vec<(f64, f64)> = run
            .samples
            .iter()
            .filter_map(|s| value(*c, s).map(|v| (s.t_ms as f64 / 1000.0, v as f64)))
            .collect();
        let (lo, hi) = series
            .iter()
            .fold(None, |a: Option<(f64, f64)>, p| {
                Some(a.map_or((p.1, p.1), |(l, h)| (l.min(p.1), h.max(p.1))))
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
        let colour = CHANNEL_COLOURS[i % CHANNEL_COLOURS.len()];
        chart
            .draw_series(LineSeries::new(series, colour.stroke_width(2)))
            .map_err(err)?;
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

/// The channels a plot shows when none are asked for: the wheels on Robi 42, else speed
/// and yaw.
pub fn default_channels(samples: &[Sample]) -> Vec<Channel> {
    if samples.iter().any(|s| s.motor_left_rad_s.is_some()) {
        vec![Channel::MotorLeft, Channel::MotorRight]
    } else {
        vec![Channel::Speed, Channel::Yaw]
    }
}
