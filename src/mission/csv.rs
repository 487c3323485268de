//! Telemetry out as files (issue 22 point 4): samples as CSV, one row per sample, with
//! columns named with their units, so a spreadsheet or pandas reads it without a script, and
//! as JSON lines (what `run --json` prints). `run`, `replay` and the app write them.
//!
//! Every file has every column; a value the droid did not report is an empty cell. Times
//! are seconds from the start (`t_s`, millisecond resolution).

use super::Sample;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

type Cell = fn(&Sample) -> String;

fn f(v: Option<f32>, prec: usize) -> String {
    v.filter(|v| v.is_finite())
        .map(|v| format!("{v:.prec$}"))
        .unwrap_or_default()
}

fn i<T: ToString>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

/// The columns, in order: name (with its unit) and how a sample fills it.
pub const COLUMNS: &[(&str, Cell)] = &[
    ("t_s", |s| format!("{:.3}", s.t_ms as f64 / 1000.0)),
    ("x_cm", |s| f(s.x_cm, 2)),
    ("y_cm", |s| f(s.y_cm, 2)),
    ("speed_cm_s", |s| f(s.speed, 2)),
    ("heading_deg", |s| i(s.heading)),
    ("head_deg", |s| f(s.head_deg, 1)),
    ("stance", |s| s.stance.clone().unwrap_or_default()),
    ("stance_to", |s| s.stance_to.clone().unwrap_or_default()),
    ("battery_v", |s| f(s.battery_v, 2)),
    ("collisions", |s| s.collisions.to_string()),
    ("pitch_deg", |s| f(s.pitch_deg, 2)),
    ("roll_deg", |s| f(s.roll_deg, 2)),
    ("yaw_deg", |s| f(s.yaw_deg, 2)),
    ("accel_x_g", |s| f(s.accel_g.map(|a| a[0]), 4)),
    ("accel_y_g", |s| f(s.accel_g.map(|a| a[1]), 4)),
    ("accel_z_g", |s| f(s.accel_g.map(|a| a[2]), 4)),
    ("gyro_x_deg_s", |s| f(s.gyro_deg_s.map(|g| g[0]), 2)),
    ("gyro_y_deg_s", |s| f(s.gyro_deg_s.map(|g| g[1]), 2)),
    ("gyro_z_deg_s", |s| f(s.gyro_deg_s.map(|g| g[2]), 2)),
    ("velocity_x_cm_s", |s| f(s.velocity_cm_s.map(|v| v[0]), 2)),
    ("velocity_y_cm_s", |s| f(s.velocity_cm_s.map(|v| v[1]), 2)),
    ("motor_left_rad_s", |s| f(s.motor_left_rad_s, 3)),
    ("motor_right_rad_s", |s| f(s.motor_right_rad_s, 3)),
    ("poti", |s| i(s.poti)),
    ("frames", |s| i(s.frames)),
    ("lost_frames", |s| i(s.lost_frames)),
];

/// The header line (no newline).
pub fn header() -> String {
    COLUMNS
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(",")
}

/// One sample as a CSV line (no newline). Only the stance columns are text, and they never
/// hold a comma or a quote; a name is quoted anyway should that change (empty: no value).
pub fn row(s: &Sample) -> String {
    COLUMNS
        .iter()
        .map(|(name, cell)| {
            let v = cell(s);
            if name.starts_with("stance") && !v.is_empty() {
                quoted(v)
            } else {
                v
            }
        })
        .collect::<Vec<_>>()
        .join(",")
}

/// Where samples go: a CSV file, a JSON-lines file, either or both.
pub struct SampleFiles {
    csv: Option<BufWriter<File>>,
    jsonl: Option<BufWriter<File>>,
}

/// A sample naming its droid first (a fleet's JSON lines).
#[derive(serde::Serialize)]
struct Tagged<'a> {
    droid: &'a str,
    #[serde(flatten)]
    sample: &'a Sample,
}

/// A CSV cell as written: quoted when it holds a comma, a quote or a line end.
fn quoted(v: String) -> String {
    if v.contains([',', '"', '\n']) {
        format!("\"{}\"", v.replace('"', "\"\""))
    } else {
        v
    }
}

impl SampleFiles {
    /// Create the files now (so a refusal comes before anything connects); the CSV gets its
    /// header at once. An existing file is kept unless `force` ([`crate::output`]'s rule).
    pub fn create(
        csv: Option<&Path>,
        jsonl: Option<&Path>,
        force: bool,
    ) -> Result<SampleFiles, String> {
        SampleFiles::create_with(csv, jsonl, false, force)
    }

    /// [`SampleFiles::create`] for a fleet: the CSV's first column is `droid`, each JSON line's
    /// first field `droid` ([`SampleFiles::write_for`]).
    pub fn create_for_fleet(
        csv: Option<&Path>,
        jsonl: Option<&Path>,
        force: bool,
    ) -> Result<SampleFiles, String> {
        SampleFiles::create_with(csv, jsonl, true, force)
    }

    fn create_with(
        csv: Option<&Path>,
        jsonl: Option<&Path>,
        fleet: bool,
        force: bool,
    ) -> Result<SampleFiles, String> {
        // Both refused before either is created.
        for p in csv.iter().chain(jsonl.iter()) {
            crate::output::check(p, force)?;
        }
        let open = |p: &Path| crate::output::create(p, force).map(BufWriter::new);
        let mut csv = csv.map(open).transpose()?;
        if let Some(w) = &mut csv {
            let droid = if fleet { "droid," } else { "" };
            writeln!(w, "{droid}{}", header()).map_err(|e| e.to_string())?;
        }
        Ok(SampleFiles {
            csv,
            jsonl: jsonl.map(open).transpose()?,
        })
    }

    pub fn is_empty(&self) -> bool {
        self.csv.is_none() && self.jsonl.is_none()
    }

    pub fn write(&mut self, s: &Sample) -> std::io::Result<()> {
        if let Some(w) = &mut self.csv {
            writeln!(w, "{}", row(s))?;
        }
        if let Some(w) = &mut self.jsonl {
            serde_json::to_writer(&mut *w, s).map_err(std::io::Error::from)?;
            writeln!(w)?;
        }
        Ok(())
    }

    /// A fleet's sample of `droid`.
    pub fn write_for(&mut self, droid: &str, s: &Sample) -> std::io::Result<()> {
        if let Some(w) = &mut self.csv {
            writeln!(w, "{},{}", quoted(droid.to_string()), row(s))?;
        }
        if let Some(w) = &mut self.jsonl {
            let t = Tagged { droid, sample: s };
            serde_json::to_writer(&mut *w, &t).map_err(std::io::Error::from)?;
            writeln!(w)?;
        }
        Ok(())
    }

    pub fn flush(&mut self) -> std::io::Result<()> {
        if let Some(w) = &mut self.csv {
            w.flush()?;
        }
        if let Some(w) = &mut self.jsonl {
            w.flush()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_per_sample_under_named_columns() {
        let s = Sample {
            t_ms: 1250,
            x_cm: Some(10.0),
            y_cm: None,
            speed: Some(3.5),
            heading: Some(90),
            head_deg: None,
            stance: Some("tripod".into()),
            stance_to: None,
            battery_v: Some(3.9),
            collisions: 2,
            motor_left_rad_s: None,
            motor_right_rad_s: None,
            frames: None,
            lost_frames: None,
            pitch_deg: Some(-1.5),
            roll_deg: None,
            yaw_deg: Some(90.0),
            accel_g: Some([0.0, 0.5, 1.0]),
            gyro_deg_s: None,
            velocity_cm_s: None,
            poti: None,
        };
        let h = header();
        let r = row(&s);
        assert_eq!(h.split(',').count(), r.split(',').count());
        let cell = |name: &str| {
            let i = h.split(',').position(|c| c == name).unwrap();
            r.split(',').nth(i).unwrap().to_string()
        };
        assert_eq!(cell("t_s"), "1.250");
        assert_eq!(cell("x_cm"), "10.00");
        assert_eq!(cell("y_cm"), "");
        assert_eq!(cell("accel_y_g"), "0.5000");
        assert_eq!(cell("stance"), "tripod");
        assert_eq!(cell("stance_to"), "");
        assert!(h.starts_with("t_s,x_cm,y_cm,speed_cm_s,heading_deg"));
    }
}
