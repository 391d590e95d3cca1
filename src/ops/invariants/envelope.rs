//! Invariant 2: every secondary edge stays within ε of the input secondary
//! polyline it is tagged with (docs/design.md "Invariants" 2; thesis §2.3.4
//! "Envelope Test", in 1D).
//!
//! The test is conservative: an edge is accepted only when a chain of points
//! along it, each provably within ε of the polyline, covers it. From a point at
//! distance `d ≤ ε` the next `ε − d` of the edge are within ε too (distance is
//! 1-Lipschitz), so the march steps by `ε − d`; a point farther than
//! `ε − spacing/2` rejects the edge. With a fixed spacing `s` this is the
//! thesis's sampling with `ε̂ = ε − s/2`; adaptive steps only accept more edges
//! that are provably inside. Distances are found through a tree of boxes over each
//! polyline's segments, never a linear scan.

use crate::mesh::point_segment_distance;
use kurbo::{Line, Point, Rect};
use rustc_hash::FxHashSet;

/// The ε-envelope of a set of polylines (by index), with its search tree.
#[derive(Clone, Debug)]
pub(crate) struct Envelope {
    eps: f64,
    spacing: f64,
    segments: Vec<(Line, u32)>,
    /// A bounding-box tree over each polyline's segments, in their order along
    /// the polyline (a polyline is spatially coherent, so consecutive segments
    /// make tight boxes): a query reads only its own polyline's boxes, however
    /// many other polylines pass the same place, and touches no hash table.
    nodes: Vec<Node>,
    /// Each polyline's root in `nodes` (`NONE` for a polyline without segments).
    roots: Vec<u32>,
}

/// A node of an [`Envelope`]'s tree: the box of segments `lo..hi`, and its
/// children `left` and `left + 1` (`NONE` for a leaf).
#[derive(Clone, Copy, Debug)]
struct Node {
    bbox: Rect,
    lo: u32,
    hi: u32,
    left: u32,
}

const NONE: u32 = u32::MAX;

/// Most segments in a leaf of the tree (scanned one by one).
const LEAF: u32 = 8;

impl Envelope {
    /// The envelope of `polylines` (polyline `i` is the tags' `polyline: i`)
    /// with radius `eps_abs` and sampling spacing `sample_abs` (clamped to
    /// `(0, 2 eps_abs)`), both in user units.
    pub(crate) fn new(polylines: &[Vec<Point>], eps_abs: f64, sample_abs: f64) -> Envelope {
        let mut segments = Vec::new();
        // A polyline that runs over one segment again (a dense zigzag after the
        // secondary simplification: back and forth between two clusters) has it
        // once here: the distance to a set of segments does not change, and the
        // tree's boxes stay as full as the drawing is dense, not as its input.
        let mut seen: FxHashSet<(u32, [u64; 4])> = FxHashSet::default();
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
        let mut roots: Vec<u32> = Vec::new();
        let mut nodes: Vec<Node> = Vec::with_capacity(segments.len() / 4 + 1);
        let mut start = 0usize;
        while start < segments.len() {
            let polyline = segments[start].1 as usize;
            let mut end = start + 1;
            while end < segments.len() && segments[end].1 as usize == polyline {
                end += 1;
            }
            if roots.len() <= polyline {
                roots.resize(polyline + 1, NONE);
            }
            debug_assert!(roots[polyline] == NONE, "internal: segments by polyline");
            let (lo, hi) = (
                u32::try_from(start).expect("internal: segment count fits u32"),
                u32::try_from(end).expect("internal: segment count fits u32"),
            );
            roots[polyline] = u32::try_from(nodes.len()).expect("internal: node count fits u32");
            nodes.push(Node {
                bbox: Rect::ZERO,
                lo,
                hi,
                left: NONE,
            });
            build(&segments, &mut nodes, roots[polyline] as usize);
            start = end;
        }
        Envelope {
            eps,
            spacing,
            segments,
            nodes,
            roots,
        }
    }

    /// The envelope radius ε (user units).
    pub(crate) fn eps(&self) -> f64 {
        self.eps
    }

    /// Calls `f` with every segment index of polyline `polyline` whose box is
    /// within `r` of `p` (with a margin far above the rounding of a distance:
    /// no segment within `r` is skipped), in the polyline's order.
    fn for_near(&self, p: Point, polyline: u32, r: f64, mut f: impl FnMut(usize)) {
        let Some(&root) = self.roots.get(polyline as usize) else {
            return;
        };
        if root == NONE {
            return;
        }
        let reach = r + 1e-9 * (r + p.x.abs().max(p.y.abs()));
        let mut stack = [0u32; 64];
        let mut top = 1;
        stack[0] = root;
        while top > 0 {
            top -= 1;
            let n = self.nodes[stack[top] as usize];
            let b = n.bbox;
            // NaN-safe: a NaN point is near nothing.
            if !(p.x >= b.x0 - reach
                && p.x <= b.x1 + reach
                && p.y >= b.y0 - reach
                && p.y <= b.y1 + reach)
            {
                continue;
            }
            if n.left == NONE {
                (n.lo..n.hi).for_each(|k| f(k as usize));
            } else {
                // The right child below the left: the left is read first.
                stack[top] = n.left + 1;
                stack[top + 1] = n.left;
                top += 2;
            }
        }
    }

    /// The distance from `p` to polyline `polyline` when it is at most `ε`,
    /// else `None`.
    pub(crate) fn distance_within(&self, p: Point, polyline: u32) -> Option<f64> {
        let mut best: Option<f64> = None;
        self.for_near(p, polyline, self.eps, |k| {
            let d = point_segment_distance(p, self.segments[k].0);
            if d <= self.eps && best.is_none_or(|b| d < b) {
                best = Some(d);
            }
        });
        best
    }

    /// The input segments of polyline `polyline` within `r ≤ ε` of `p`, each
    /// once, into `out` (cleared first), in the polyline's order: what the
    /// polyline looks like at `p` (the forced-corner classification reads the
    /// drawing's directions there).
    pub(crate) fn segments_near(&self, p: Point, polyline: u32, r: f64, out: &mut Vec<Line>) {
        out.clear();
        let r = r.min(self.eps);
        self.for_near(p, polyline, r, |k| {
            let l = self.segments[k].0;
            if point_segment_distance(p, l) <= r && !out.contains(&l) {
                out.push(l);
            }
        });
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

/// Fills node `i` (its range set): its box, and children while its range is
/// longer than a leaf. Depth ≤ 33 for 2³² segments: the query's stack of 64
/// holds it.
fn build(segments: &[(Line, u32)], nodes: &mut Vec<Node>, i: usize) {
    let Node { lo, hi, .. } = nodes[i];
    let mut b = Rect::from_points(segments[lo as usize].0.p0, segments[lo as usize].0.p1);
    for (l, _) in &segments[lo as usize + 1..hi as usize] {
        b = b.union(Rect::from_points(l.p0, l.p1));
    }
    nodes[i].bbox = b;
    if hi - lo <= LEAF {
        return;
    }
    let mid = lo + (hi - lo) / 2;
    let left = u32::try_from(nodes.len()).expect("internal: node count fits u32");
    nodes[i].left = left;
    for (lo, hi) in [(lo, mid), (mid, hi)] {
        nodes.push(Node {
            bbox: Rect::ZERO,
            lo,
            hi,
            left: NONE,
        });
    }
    build(segments, nodes, left as usize);
    build(segments, nodes, left as usize + 1);
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
        // A long wavy polyline (searched through the tree), a short one (scanned
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
