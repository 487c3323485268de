//! Series reduced as they come, in memory independent of their length (issue 27 point 6: a
//! plot of 10 M samples took 3.5 GB, while a picture shows a few thousand points).
//!
//! Points fall into time buckets; when there are more than [`MAX_BUCKETS`] the buckets
//! double in width and pairs merge. Each bucket keeps its first and last point and its
//! extremes (on each axis of a path), so the shape, the spikes and the ends survive; a
//! series of any length becomes at most about 6 × [`MAX_BUCKETS`] points.

use std::collections::BTreeMap;

/// Most buckets a series keeps (a picture is at most 8000 pixels wide; its plot area far
/// less: two points of detail per column at 1200 pixels).
pub const MAX_BUCKETS: usize = 1024;

/// A point: time (ms) and up to two values (a channel's value; a path's x and y).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    pub t_ms: u64,
    pub v: [f32; 2],
}

/// What a bucket keeps: first, last, and the smallest and largest of each value.
#[derive(Debug, Clone, Copy)]
struct Bucket {
    first: Point,
    last: Point,
    min: [Point; 2],
    max: [Point; 2],
}

impl Bucket {
    fn of(p: Point) -> Bucket {
        Bucket {
            first: p,
            last: p,
            min: [p; 2],
            max: [p; 2],
        }
    }

    fn add(&mut self, p: Point) {
        if p.t_ms < self.first.t_ms {
            self.first = p;
        }
        if p.t_ms >= self.last.t_ms {
            self.last = p;
        }
        for d in 0..2 {
            if p.v[d] < self.min[d].v[d] {
                self.min[d] = p;
            }
            if p.v[d] > self.max[d].v[d] {
                self.max[d] = p;
            }
        }
    }

    fn merge(&mut self, o: &Bucket) {
        for p in [o.first, o.last, o.min[0], o.min[1], o.max[0], o.max[1]] {
            self.add(p);
        }
    }
}

/// A series (or a path) reduced as it comes.
#[derive(Debug, Clone)]
pub struct Decimated {
    /// Bucket width in ms.
    width: u64,
    buckets: BTreeMap<u64, Bucket>,
    count: u64,
}

impl Default for Decimated {
    fn default() -> Self {
        Decimated {
            width: 1,
            buckets: BTreeMap::new(),
            count: 0,
        }
    }
}

impl Decimated {
    /// Add a point (times may come in any order).
    pub fn push(&mut self, t_ms: u64, v: [f32; 2]) {
        if !v.iter().all(|x| x.is_finite()) {
            return;
        }
        self.count += 1;
        let p = Point { t_ms, v };
        self.buckets
            .entry(t_ms / self.width)
            .and_modify(|b| b.add(p))
            .or_insert_with(|| Bucket::of(p));
        while self.buckets.len() > MAX_BUCKETS {
            self.width = self.width.saturating_mul(2);
            let old = std::mem::take(&mut self.buckets);
            for (k, b) in old {
                self.buckets
                    .entry(k / 2)
                    .and_modify(|m| m.merge(&b))
                    .or_insert(b);
            }
        }
    }

    /// Points pushed in all.
    pub fn count(&self) -> u64 {
        self.count
    }

    pub fn is_empty(&self) -> bool {
        self.buckets.is_empty()
    }

    /// The points kept, in time order.
    pub fn points(&self) -> Vec<Point> {
        let mut out: Vec<Point> = Vec::with_capacity(self.buckets.len() * 3);
        for b in self.buckets.values() {
            let mut pts = [b.first, b.min[0], b.max[0], b.min[1], b.max[1], b.last];
            pts.sort_by_key(|p| p.t_ms);
            for p in pts {
                if out.last() != Some(&p) {
                    out.push(p);
                }
            }
        }
        out
    }

    /// The smallest and largest of value `d`.
    pub fn range(&self, d: usize) -> Option<(f32, f32)> {
        self.buckets.values().fold(None, |a, b| {
            let (lo, hi) = (b.min[d].v[d], b.max[d].v[d]);
            Some(a.map_or((lo, hi), |(l, h): (f32, f32)| (l.min(lo), h.max(hi))))
        })
    }

    /// The first and last points.
    pub fn ends(&self) -> Option<(Point, Point)> {
        Some((
            self.buckets.values().next()?.first,
            self.buckets.values().next_back()?.last,
        ))
    }
}

/// Cut a channel's points into the runs a line may join: an angle that wraps (yaw at ±180°)
/// jumps by more than half its range from one point to the next, which is no vertical
/// stroke across the strip but the end of one run and the start of the next.
pub fn runs(points: &[Point], wrap: Option<f32>) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut prev: Option<f32> = None;
    for p in points {
        let v = p.v[0];
        let jump = match (prev, wrap) {
            (Some(a), Some(span)) => (v - a).abs() > span / 2.0,
            _ => prev.is_none(),
        };
        if jump || out.is_empty() {
            out.push(Vec::new());
        }
        if let Some(run) = out.last_mut() {
            run.push((p.t_ms as f64 / 1000.0, v as f64));
        }
        prev = Some(v);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_length_becomes_a_bounded_number_of_points_keeping_the_extremes() {
        let mut d = Decimated::default();
        for i in 0..1_000_000u64 {
            let spike = if i == 654_321 { 1000.0 } else { 0.0 };
            d.push(i * 10, [(i % 100) as f32 + spike, -(i as f32)]);
        }
        assert_eq!(d.count(), 1_000_000);
        let pts = d.points();
        assert!(pts.len() <= 6 * MAX_BUCKETS, "{}", pts.len());
        assert_eq!(d.range(0), Some((0.0, 1021.0)), "the spike survives");
        assert_eq!(d.range(1), Some((-999_999.0, 0.0)));
        let (first, last) = d.ends().unwrap();
        assert_eq!((first.t_ms, last.t_ms), (0, 9_999_990));
        assert!(pts.windows(2).all(|w| w[0].t_ms <= w[1].t_ms));
    }

    #[test]
    fn a_wrapping_angle_is_cut_where_it_wraps() {
        let p = |t, v| Point {
            t_ms: t,
            v: [v, 0.0],
        };
        let pts = [p(0, 170.0), p(100, 179.0), p(200, -179.0), p(300, -170.0)];
        let r = runs(&pts, Some(360.0));
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].len(), 2);
        assert_eq!(runs(&pts, None).len(), 1);
    }
}
