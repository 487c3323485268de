//! The recent past of every plotted channel (issue 22 point 1): one row per sample the droid
//! streamed (a sensor notification, a Robi frame), holding every channel's value at that
//! moment, for the scope and the sample rate measured. Bounded by time (the scope's longest
//! window, two minutes) and by count (two minutes at 100 samples a second): memory stays
//! flat (about 1 MiB at the bound) however long the session.

use super::Telemetry;
use std::collections::VecDeque;
use std::time::Duration;

/// The longest span kept: the scope's widest window.
pub const SPAN: Duration = Duration::from_secs(120);
/// At most this many rows (two minutes at 100 samples a second).
pub const MAX_ROWS: usize = 12_000;
/// The measured rate counts the samples of this last stretch.
pub const RATE_WINDOW: Duration = Duration::from_secs(2);

macro_rules! channels {
    ($( $v:ident $name:literal $unit:literal ($lo:literal, $hi:literal) $robi:expr; )*) => {
        /// A plotted quantity.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Channel { $( $v, )* }

        impl Channel {
            pub const ALL: &'static [Channel] = &[ $( Channel::$v, )* ];

            /// The name in legends, CSV columns and `plot --channels`.
            pub fn name(self) -> &'static str {
                match self { $( Channel::$v => $name, )* }
            }

            pub fn unit(self) -> &'static str {
                match self { $( Channel::$v => $unit, )* }
            }

            /// The fixed axis range (the sensor's span), when not autoscaled.
            pub fn range(self) -> (f64, f64) {
                match self { $( Channel::$v => ($lo as f64, $hi as f64), )* }
            }

            /// Only Robi 42 reports it (`true`), or only Sphero droids (`false`); battery
            /// and speed are everybody's.
            fn robi(self) -> Option<bool> {
                match self { $( Channel::$v => $robi, )* }
            }
        }
    };
}

channels! {
    Pitch "pitch" "deg" (-180, 180) Some(false);
    Roll "roll" "deg" (-180, 180) Some(false);
    Yaw "yaw" "deg" (-180, 180) None;
    AccelX "accel_x" "g" (-2, 2) Some(false);
    AccelY "accel_y" "g" (-2, 2) Some(false);
    AccelZ "accel_z" "g" (-2, 2) Some(false);
    GyroX "gyro_x" "deg/s" (-500, 500) Some(false);
    GyroY "gyro_y" "deg/s" (-500, 500) Some(false);
    GyroZ "gyro_z" "deg/s" (-500, 500) Some(false);
    VelocityX "velocity_x" "cm/s" (-200, 200) None;
    VelocityY "velocity_y" "cm/s" (-200, 200) None;
    Speed "speed" "cm/s" (0, 200) None;
    Battery "battery" "V" (3, 4.3) Some(false);
    MotorLeft "motor_left" "rad/s" (0, 60) Some(true);
    MotorRight "motor_right" "rad/s" (0, 60) Some(true);
    Poti "poti" "" (0, 255) Some(true);
}

/// How many channels there are.
pub const CHANNELS: usize = Channel::ALL.len();

impl Channel {
    /// The channel named `name` (`speed`, `gyro_z`).
    pub fn parse(name: &str) -> Option<Channel> {
        let n = name.trim().to_ascii_lowercase();
        Channel::ALL.iter().copied().find(|c| c.name() == n)
    }

    /// Whether a droid that reports Robi frames (`robi`) or Sphero sensors has it.
    pub fn reported_by(self, robi: bool) -> bool {
        self.robi().is_none_or(|r| r == robi)
    }

    /// `speed (cm/s)`.
    pub fn label(self) -> String {
        match self.unit() {
            "" => self.name().to_string(),
            u => format!("{} ({u})", self.name()),
        }
    }

    /// Its value in `t` now.
    pub fn value(self, t: &Telemetry) -> Option<f32> {
        let robi = t.robi.as_ref();
        let motors = robi.and_then(|r| r.motors);
        match self {
            Channel::Pitch => t.pitch,
            Channel::Roll => t.roll,
            Channel::Yaw => t.yaw,
            Channel::AccelX => t.accel.map(|a| a[0]),
            Channel::AccelY => t.accel.map(|a| a[1]),
            Channel::AccelZ => t.accel.map(|a| a[2]),
            Channel::GyroX => t.gyro.map(|g| g[0]),
            Channel::GyroY => t.gyro.map(|g| g[1]),
            Channel::GyroZ => t.gyro.map(|g| g[2]),
            Channel::VelocityX => t.velocity_cm_s.map(|v| v[0]),
            Channel::VelocityY => t.velocity_cm_s.map(|v| v[1]),
            Channel::Speed => t.speed_cm_s(),
            Channel::Battery => t.battery_v,
            Channel::MotorLeft => motors.map(|m| m.left_rad_s),
            Channel::MotorRight => motors.map(|m| m.right_rad_s),
            Channel::Poti => robi.and_then(|r| r.poti).map(f32::from),
        }
    }
}

/// One sample: when, and every channel's value then (NaN where there is none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    pub at: Duration,
    pub values: [f32; CHANNELS],
}

impl Row {
    pub fn get(&self, c: Channel) -> Option<f32> {
        let v = self.values[c as usize];
        (!v.is_nan()).then_some(v)
    }
}

/// The recent samples, oldest first.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct History {
    rows: VecDeque<Row>,
}

impl History {
    /// Record `t` as it is after a sample at `at`. A time before the last row (a new
    /// connection's clock, a replay played again) starts the history afresh.
    pub fn record(&mut self, at: Duration, t: &Telemetry) {
        if self.rows.back().is_some_and(|r| r.at > at) {
            self.rows.clear();
        }
        let mut values = [f32::NAN; CHANNELS];
        for (i, c) in Channel::ALL.iter().enumerate() {
            values[i] = c.value(t).filter(|v| v.is_finite()).unwrap_or(f32::NAN);
        }
        while self.rows.len() >= MAX_ROWS
            || self
                .rows
                .front()
                .is_some_and(|r| at.saturating_sub(r.at) > SPAN)
        {
            self.rows.pop_front();
        }
        self.rows.push_back(Row { at, values });
    }

    /// More of the last sample arrived (another of RVR's tokens in the same period): the last
    /// row takes every channel as it is now; no new row, so the measured rate counts samples,
    /// not packets.
    pub fn complete_last(&mut self, t: &Telemetry) {
        if let Some(last) = self.rows.back_mut() {
            for (i, c) in Channel::ALL.iter().enumerate() {
                last.values[i] = c.value(t).filter(|v| v.is_finite()).unwrap_or(f32::NAN);
            }
        }
    }

    pub fn len(&self) -> usize {
        self.rows.len()
    }

    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    pub fn last(&self) -> Option<&Row> {
        self.rows.back()
    }

    /// The rows from `from` to `to` (inclusive), oldest first.
    pub fn between(&self, from: Duration, to: Duration) -> impl Iterator<Item = &Row> {
        let start = self.rows.partition_point(|r| r.at < from);
        self.rows.range(start..).take_while(move |r| r.at <= to)
    }

    /// Samples per second over the [`RATE_WINDOW`] before `now`; `None` without two samples
    /// in it.
    pub fn measured_rate(&self, now: Duration) -> Option<f32> {
        let from = now.saturating_sub(RATE_WINDOW);
        let mut it = self.between(from, now);
        let first = it.next()?.at;
        let (n, last) = it.fold((1usize, first), |(n, _), r| (n + 1, r.at));
        let span = last.saturating_sub(first).as_secs_f32();
        (n >= 2 && span > 0.0).then(|| (n - 1) as f32 / span)
    }

    /// `c` from `from` to `to` reduced to at most `buckets` columns: each column's lowest
    /// and highest value (so a spike narrower than a column still shows), as (seconds
    /// relative to `to`, value) points in time order. Cheap at any rate: a screen column
    /// costs two points.
    pub fn series(
        &self,
        c: Channel,
        from: Duration,
        to: Duration,
        buckets: usize,
    ) -> Vec<(f64, f64)> {
        self.series_of(&[c], from, to, buckets)
            .pop()
            .unwrap_or_default()
    }

    /// [`History::series`] for several channels in one pass over the rows.
    pub fn series_of(
        &self,
        channels: &[Channel],
        from: Duration,
        to: Duration,
        buckets: usize,
    ) -> Vec<Vec<(f64, f64)>> {
        // The column being filled per channel: its index, lowest and highest (time, value).
        type Column = (usize, (f64, f32), (f64, f32));
        let buckets = buckets.max(1);
        let span = to.saturating_sub(from).as_nanos().max(1);
        let end = to.as_secs_f64();
        let mut out: Vec<Vec<(f64, f64)>> = channels
            .iter()
            .map(|_| Vec::with_capacity(buckets * 2))
            .collect();
        let mut cur: Vec<Option<Column>> = vec![None; channels.len()];
        let flush = |out: &mut Vec<(f64, f64)>, lo: (f64, f32), hi: (f64, f32)| {
            let (a, b) = if lo.0 <= hi.0 { (lo, hi) } else { (hi, lo) };
            out.push((a.0, a.1 as f64));
            if a != b {
                out.push((b.0, b.1 as f64));
            }
        };
        for r in self.between(from, to) {
            let col = ((r.at - from).as_nanos() * buckets as u128 / span) as usize;
            let col = col.min(buckets - 1);
            let t = r.at.as_secs_f64() - end;
            for (i, c) in channels.iter().enumerate() {
                let Some(v) = r.get(*c) else { continue };
                match &mut cur[i] {
                    Some((k, lo, hi)) if *k == col => {
                        if v < lo.1 {
                            *lo = (t, v);
                        }
                        if v > hi.1 {
                            *hi = (t, v);
                        }
                    }
                    slot => {
                        if let Some((_, lo, hi)) = slot.take() {
                            flush(&mut out[i], lo, hi);
                        }
                        *slot = Some((col, (t, v), (t, v)));
                    }
                }
            }
        }
        for (i, c) in cur.into_iter().enumerate() {
            if let Some((_, lo, hi)) = c {
                flush(&mut out[i], lo, hi);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t_with(speed: f32) -> Telemetry {
        Telemetry {
            velocity_cm_s: Some([0.0, speed]),
            pitch: Some(speed / 10.0),
            ..Telemetry::default()
        }
    }

    #[test]
    fn bounded_by_time_and_count() {
        let mut h = History::default();
        for i in 0..20_000u64 {
            h.record(Duration::from_millis(i * 5), &t_with(i as f32));
        }
        assert_eq!(h.len(), MAX_ROWS, "100 s at 200/s: the count bounds it");
        let mut h = History::default();
        for i in 0..3_000u64 {
            h.record(Duration::from_millis(i * 100), &t_with(1.0));
        }
        let first = h.between(Duration::ZERO, Duration::MAX).next().unwrap().at;
        assert_eq!(
            first,
            Duration::from_millis(179_900),
            "300 s at 10/s: 120 s kept"
        );
        // A clock going back starts afresh.
        h.record(Duration::from_secs(1), &t_with(1.0));
        assert_eq!(h.len(), 1);
    }

    #[test]
    fn measured_rate_and_decimated_series() {
        let mut h = History::default();
        for i in 0..=500u64 {
            h.record(Duration::from_millis(i * 20), &t_with((i % 50) as f32));
        }
        let now = Duration::from_secs(10);
        assert!((h.measured_rate(now).unwrap() - 50.0).abs() < 0.5);
        // 10 s at 50/s into 20 columns: 2 points each, min and max of the column kept.
        let s = h.series(Channel::Speed, Duration::ZERO, now, 20);
        assert!(s.len() <= 40, "{}", s.len());
        assert!(s.iter().any(|p| p.1 == 49.0) && s.iter().any(|p| p.1 == 0.0));
        assert!(s.windows(2).all(|w| w[0].0 <= w[1].0), "in time order");
        assert!(s.iter().all(|p| (-10.0..=0.0).contains(&p.0)));
        // Channels a droid does not report have no points.
        assert!(
            h.series(Channel::MotorLeft, Duration::ZERO, now, 20)
                .is_empty()
        );
        assert!(Channel::MotorLeft.reported_by(true) && !Channel::MotorLeft.reported_by(false));
        assert_eq!(Channel::parse("Gyro_Z"), Some(Channel::GyroZ));
        assert_eq!(Channel::Speed.label(), "speed (cm/s)");
    }
}
