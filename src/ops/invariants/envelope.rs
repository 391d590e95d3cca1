//! Invariant 2: every secondary edge stays within ε of the input secondary
//! polyline it is tagged with (DESIGN "Invariants" 2; thesis §2.3.4
//! "Envelope Test", in 1D).
//!
//! The test is conservative: an edge is accepted only when a chain of points
//! along it, each provably within ε of the polyline, covers it. From a point at
//! distance `d ≤ ε` the next `ε − d` of the edge are within ε too (distance is
//! 1-Lipschitz), so the march steps by `ε − d`; a point farther than
//! `ε − spacing/2` rejects the edge. With a fixed spacing `s` this is the
//! thesis's sampling with `ε̂ = ε − s/2`; adaptive steps only accept more edges
//! that are provably inside. Distances are found through a uniform grid of the
//! input segments, never a linear scan.

use crate::mesh::point_segment_distance;
use kurbo::{Line, Point, Rect};
use std::collections::{HashMap, HashSet};

/// The ε-envelope of a set of polylines (by index), with its search grid.
#[derive(Clone, Debug)]
pub(crate) struct Envelope {
    eps: f64,
    spacing: f64,
    cell: f64,
    segments: Vec<(Line, u32)>,
    /// The segments of each polyline by the cells they pass: (cell x, cell y,
    /// polyline) → segment indices, in order (a query reads only its own
    /// polyline's segments, however many others pass the same cells).
    grid: HashMap<(i64, i64, u32), Vec<u32>>,
    /// Each polyline's segments: a range of `segments` (they are added polyline
    /// by polyline).
    ranges: Vec<std::ops::Range<u32>>,
}

/// A polyline with at most this many segments is searched whole, without the
/// grid (most polylines are the sections of one input curve).
const SCAN_WHOLE: u32 = 8;

impl Envelope {
    /// The envelope of `polylines` (polyline `i` is the tags' `polyline: i`)
    /// with radius `eps_abs` and sampling spacing `sample_abs` (clamped to
    /// `(0, 2 eps_abs)`), both in user units.
    pub(crate) fn new(polylines: &[Vec<Point>], eps_abs: f64, sample_abs: f64) -> Envelope {
        let mut segments = Vec::new();
        // A polyline that runs over one segment again (a dense zigzag after the
        // secondary simplification: back and forth between two clusters) has it
        // once here: the distance to a set of segments does not change, and the
        // grid's cells stay as full as the drawing is dense, not as its input.
        let mut seen: HashSet<(u32, [u64; 4])> = HashSet::new();
        let bits =
            |a: Point, b: Point| [a.x.to_bits(), a.y.to_bits(), b.x.to_bits(), b.y.to_bits()];
        for (i, pl) in polylines.iter().enumerate() {
            let id = u32::try_from(i).expect("internal: polyline count fits u32");
            for w in pl.windows(2) {
                if seen.insert((id, bits(w[0], w[1]))) && !seen.contains(&(id, bits(w[1], w[0]))) {
                    segments.push((Line::new(w[0], w[1]), id));
                }
            }
        }
        Envelope::from_segments(segments, eps_abs, sample_abs)
    }

    /// The same input polylines with another radius and sampling spacing (the
    /// envelope stages of thesis §2.3.4: denser sampling, then a larger ε).
    pub(crate) fn restaged(&self, eps_abs: f64, sample_abs: f64) -> Envelope {
        Envelope::from_segments(self.segments.clone(), eps_abs, sample_abs)
    }

    /// The sampling spacing (user units).
    pub(crate) fn spacing(&self) -> f64 {
        self.spacing
    }

    fn from_segments(segments: Vec<(Line, u32)>, eps_abs: f64, sample_abs: f64) -> Envelope {
        let eps = if eps_abs.is_finite() && eps_abs > 0.0 {
            eps_abs
        } else {
            0.0
        };
        let spacing = if sample_abs.is_finite() && sample_abs > 0.0 {
            sample_abs.min(1.5 * eps)
        } else {
            eps
        };
        let mut bounds: Option<Rect> = None;
        for (l, _) in &segments {
            let r = Rect::from_points(l.p0, l.p1);
            bounds = Some(bounds.map_or(r, |b| b.union(r)));
        }
        let b = bounds.unwrap_or(Rect::ZERO);
        let n = segments.len().max(1) as f64;
        let diag = b.width().hypot(b.height());
        let mut cell = (4.0 * eps).max(diag / (2.0 * n.sqrt()));
        if !(cell.is_finite() && cell > 0.0) {
            cell = 1.0;
        }
        let mut ranges: Vec<std::ops::Range<u32>> = Vec::new();
        for (k, &(_, polyline)) in segments.iter().enumerate() {
            let k = u32::try_from(k).expect("internal: segment count fits u32");
            let polyline = polyline as usize;
            if ranges.len() <= polyline {
                ranges.resize(polyline + 1, k..k);
            }
            debug_assert!(ranges[polyline].end == k, "internal: segments by polyline");
            ranges[polyline].end = k + 1;
        }
        let mut env = Envelope {
            eps,
            spacing,
            cell,
            segments,
            grid: HashMap::new(),
            ranges,
        };
        for k in 0..env.segments.len() {
            let (l, _) = env.segments[k];
            let steps = ((l.p0.distance(l.p1) / (0.5 * cell)).ceil() as usize).clamp(1, 1 << 20);
            let mut cells: Vec<(i64, i64)> = Vec::new();
            for s in 0..steps {
                let (a, b) = (
                    l.p0.lerp(l.p1, s as f64 / steps as f64),
                    l.p0.lerp(l.p1, (s + 1) as f64 / steps as f64),
                );
                let (x0, y0) = env.key(Point::new(a.x.min(b.x), a.y.min(b.y)));
                let (x1, y1) = env.key(Point::new(a.x.max(b.x), a.y.max(b.y)));
                for x in x0..=x1 {
                    for y in y0..=y1 {
                        cells.push((x, y));
                    }
                }
            }
            cells.sort_unstable();
            cells.dedup();
            let id = u32::try_from(k).expect("internal: segment count fits u32");
            let polyline = env.segments[k].1;
            for (x, y) in cells {
                env.grid.entry((x, y, polyline)).or_default().push(id);
            }
        }
        env
    }

    /// The envelope radius ε (user units).
    pub(crate) fn eps(&self) -> f64 {
        self.eps
    }

    fn key(&self, p: Point) -> (i64, i64) {
        // Saturating float-to-int casts keep far points in the outermost cells.
        (
            (p.x / self.cell).floor() as i64,
            (p.y / self.cell).floor() as i64,
        )
    }

    /// The distance from `p` to polyline `polyline` when it is at most `ε`,
    /// else `None`.
    pub(crate) fn distance_within(&self, p: Point, polyline: u32) -> Option<f64> {
        let (x0, y0) = self.key(Point::new(p.x - self.eps, p.y - self.eps));
        let (x1, y1) = self.key(Point::new(p.x + self.eps, p.y + self.eps));
        let mut best: Option<f64> = None;
        // Every segment within ε of `p` is in a cell this box meets, so the grid
        // and a scan of the whole polyline find the same nearest distance.
        let range = self.ranges.get(polyline as usize).cloned().unwrap_or(0..0);
        if range.len() <= SCAN_WHOLE as usize {
            for (l, _) in &self.segments[range.start as usize..range.end as usize] {
                let d = point_segment_distance(p, *l);
                if d <= self.eps && best.is_none_or(|b| d < b) {
                    best = Some(d);
                }
            }
            return best;
        }
        for x in x0..=x1.min(x0.saturating_add(4)) {
            for y in y0..=y1.min(y0.saturating_add(4)) {
                let bucket = self.grid.get(&(x, y, polyline));
                for &k in bucket.map_or(&[][..], Vec::as_slice) {
                    let d = point_segment_distance(p, self.segments[k as usize].0);
                    if d <= self.eps && best.is_none_or(|b| d < b) {
                        best = Some(d);
                    }
                }
            }
        }
        best
    }

    /// The input segments of polyline `polyline` within `r ≤ ε` of `p`, each
    /// once, into `out` (cleared first): what the polyline looks like at `p`
    /// (the forced-corner classification reads the drawing's directions there).
    pub(crate) fn segments_near(&self, p: Point, polyline: u32, r: f64, out: &mut Vec<Line>) {
        out.clear();
        let r = r.min(self.eps);
        let range = self.ranges.get(polyline as usize).cloned().unwrap_or(0..0);
        let mut push = |k: u32| {
            let l = self.segments[k as usize].0;
            if point_segment_distance(p, l) <= r && !out.contains(&l) {
                out.push(l);
            }
        };
        if range.len() <= SCAN_WHOLE as usize {
            range.for_each(&mut push);
            return;
        }
        let (x0, y0) = self.key(Point::new(p.x - r, p.y - r));
        let (x1, y1) = self.key(Point::new(p.x + r, p.y + r));
        for x in x0..=x1.min(x0.saturating_add(4)) {
            for y in y0..=y1.min(y0.saturating_add(4)) {
                if let Some(bucket) = self.grid.get(&(x, y, polyline)) {
                    bucket.iter().copied().for_each(&mut push);
                }
            }
        }
    }

    /// Whether the segment `a b` lies within ε of polyline `polyline`,
    /// decided conservatively (see the module doc). Rejects when unsure.
    pub(crate) fn contains_segment(&self, a: Point, b: Point, polyline: u32) -> bool {
        let len = a.distance(b);
        let margin = 0.5 * self.spacing;
        if !(len.is_finite() && margin > 0.0) {
            return false;
        }
        // At most 2·len/spacing + 2 queries: each accepted point is ≥ margin from the next.
        let mut s = 0.0;
        loop {
            let p = if len > 0.0 {
                a.lerp(b, (s / len).min(1.0))
            } else {
                a
            };
            match self.distance_within(p, polyline) {
                Some(d) if d <= self.eps - margin => {
                    if s >= len {
                        return true;
                    }
                    // Shrink the step a little for the rounding of lerp and distances.
                    s = (s + (self.eps - d) * (1.0 - 1e-9)).min(len);
                    if s + 1e-12 * len >= len && s < len {
                        s = len;
                    }
                }
                _ => return false,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inside_outside_and_other_polyline() {
        let pls = vec![
            vec![
                Point::new(0.0, 0.0),
                Point::new(10.0, 0.0),
                Point::new(10.0, 10.0),
            ],
            vec![Point::new(0.0, 5.0), Point::new(5.0, 5.0)],
        ];
        let env = Envelope::new(&pls, 0.1, 0.1);
        assert!(env.contains_segment(Point::new(0.0, 0.05), Point::new(10.0, -0.04), 0));
        assert!(env.contains_segment(Point::new(10.0, 1.0), Point::new(10.02, 3.0), 0));
        // Cuts the corner by more than ε.
        assert!(!env.contains_segment(Point::new(9.0, 0.0), Point::new(10.0, 1.0), 0));
        assert!(!env.contains_segment(Point::new(0.0, 0.2), Point::new(10.0, 0.0), 0));
        // Near polyline 0 but tagged 1.
        assert!(!env.contains_segment(Point::new(0.0, 0.0), Point::new(1.0, 0.0), 1));
        assert!(env.contains_segment(Point::new(1.0, 5.0), Point::new(4.0, 5.0), 1));
        // Conservative: a point near ε from the input is refused.
        assert!(!env.contains_segment(Point::new(2.0, 0.099), Point::new(2.0, 0.099), 0));
        assert!(env.contains_segment(Point::new(2.0, 0.04), Point::new(2.0, 0.04), 0));
    }

    #[test]
    fn accepted_segments_are_within_eps_densely() {
        let pl = vec![
            (0..40)
                .map(|i| {
                    let t = f64::from(i) * 0.1;
                    Point::new(t, (3.0 * t).sin())
                })
                .collect::<Vec<_>>(),
        ];
        let env = Envelope::new(&pl, 0.05, 0.05);
        let mut accepted = 0;
        for k in 0..400 {
            let t = f64::from(k) * 0.0097;
            let a = Point::new(t, (3.0 * t).sin() + 0.03 * (f64::from(k) * 1.7).sin());
            let t2 = t + 0.05 + 0.3 * (f64::from(k) * 0.37).cos().abs();
            let b = Point::new(t2, (3.0 * t2).sin() - 0.02);
            if env.contains_segment(a, b, 0) {
                accepted += 1;
                for j in 0..=200 {
                    let p = a.lerp(b, f64::from(j) / 200.0);
                    let d = pl[0]
                        .windows(2)
                        .map(|w| point_segment_distance(p, Line::new(w[0], w[1])))
                        .fold(f64::INFINITY, f64::min);
                    assert!(d <= 0.05 * (1.0 + 1e-9), "{d} at {p:?} on {a:?} {b:?}");
                }
            }
        }
        assert!(accepted > 20, "{accepted}");
    }

    /// The nearest distance within ε to polyline `k`, by brute force.
    fn brute(pls: &[Vec<Point>], k: usize, p: Point, eps: f64) -> Option<f64> {
        pls[k]
            .windows(2)
            .map(|w| point_segment_distance(p, Line::new(w[0], w[1])))
            .filter(|&d| d <= eps)
            .fold(None, |b: Option<f64>, d| Some(b.map_or(d, |b| b.min(d))))
    }

    #[test]
    fn short_and_long_polylines_find_the_nearest_distance() {
        // A long wavy polyline (searched through the grid), a short one (scanned
        // whole), and a zigzag running back and forth over the same segments
        // (kept once).
        let long: Vec<Point> = (0..200)
            .map(|i| {
                let t = f64::from(i) * 0.05;
                Point::new(t, (2.0 * t).sin())
            })
            .collect();
        let short = vec![
            Point::new(0.0, 0.5),
            Point::new(3.0, 0.6),
            Point::new(6.0, 0.4),
        ];
        let zigzag: Vec<Point> = (0..100)
            .map(|i| Point::new(f64::from(i % 2) * 2.0, 1.0 + f64::from(i % 4 / 2) * 0.5))
            .collect();
        let pls = vec![long, short, zigzag];
        let eps = 0.2;
        let env = Envelope::new(&pls, eps, eps);
        assert!(
            env.segments.len() < 199 + 2 + 99,
            "repeated segments are kept once"
        );
        let mut x: u64 = 3;
        let mut r = || {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..3000 {
            let p = Point::new(11.0 * r() - 0.5, 3.0 * r() - 1.5);
            for k in 0..3 {
                let got = env.distance_within(p, k as u32);
                let want = brute(&pls, k, p, eps);
                assert_eq!(got.is_some(), want.is_some(), "{p:?} polyline {k}");
                if let (Some(g), Some(w)) = (got, want) {
                    assert!((g - w).abs() <= 1e-12, "{p:?} polyline {k}: {g} vs {w}");
                }
            }
        }
    }
}
