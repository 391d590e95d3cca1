//! The baseline's planar input: the feature soup flattened to polylines, scaled by a
//! power of two into the range spade accepts, with near-duplicate points merged.

use crate::svg::drawing::Conic;
use crate::svg::{Drawing, FeatureGeom, ShapeId};
use kurbo::{CubicBez, PathEl, Point, Rect};

/// Most segments one cubic is flattened into. Bounds the work of a cubic whose
/// tolerance is tiny compared with its size (an absolute `--mu` on a huge drawing).
const MAX_PIECES_PER_CUBIC: f64 = 4096.0;

/// Scaling by an exact power of two: `scaled = user · 2^k`.
///
/// Multiplying by a power of two is exact unless the result over- or underflows, so
/// it maps points to points without changing any orientation, and back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Pow2Scale {
    /// The exponent `k`.
    pub(super) k: i32,
}

impl Pow2Scale {
    /// The scale that brings `max_abs` (> 0, finite) into `[1/2, 2)`.
    pub(super) fn normalizing(max_abs: f64) -> Pow2Scale {
        debug_assert!(
            max_abs > 0.0 && max_abs.is_finite(),
            "internal: bad magnitude {max_abs}"
        );
        // log2 may be off by one ulp at exact powers of two: the range is [1/2, 2), not [1/2, 1).
        let e = max_abs.log2().floor();
        let k = if e.is_finite() { -(e as i32) - 1 } else { 0 };
        Pow2Scale { k }
    }

    /// `x · 2^k`.
    pub(super) fn apply(self, x: f64) -> f64 {
        ldexp(x, self.k)
    }

    /// `x · 2^-k`.
    pub(super) fn invert(self, x: f64) -> f64 {
        ldexp(x, -self.k)
    }

    /// Scale a point.
    pub(super) fn point(self, p: Point) -> Point {
        Point::new(self.apply(p.x), self.apply(p.y))
    }

    /// Unscale a point.
    pub(super) fn unpoint(self, p: Point) -> Point {
        Point::new(self.invert(p.x), self.invert(p.y))
    }

    /// Scale a length.
    pub(super) fn length(self, l: f64) -> f64 {
        self.apply(l)
    }
}

/// `x · 2^k`, exact whenever the result is a normal number (steps of at most 2^±1000,
/// so no step overflows on its own).
fn ldexp(mut x: f64, mut k: i32) -> f64 {
    while k > 1000 {
        x *= 2f64.powi(1000);
        k -= 1000;
    }
    while k < -1000 {
        x *= 2f64.powi(-1000);
        k += 1000;
    }
    x * 2f64.powi(k)
}

/// A straight piece of a flattened feature between two merged points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Piece {
    /// Index of the start point in [`PlanarInput::points`].
    pub(super) a: u32,
    /// Index of the end point.
    pub(super) b: u32,
    /// The shape of the feature it comes from.
    pub(super) shape: ShapeId,
}

/// Flattened, scaled, merged input.
#[derive(Clone, Debug)]
pub(super) struct PlanarInput {
    /// Distinct points, in scaled coordinates, first-seen order; no two are within
    /// the merge distance (greedy merge: a point joins the nearest kept point within
    /// the merge distance, else it is kept).
    pub(super) points: Vec<Point>,
    /// Pieces of non-zero length, each `(a, b, shape)` at most once (either direction).
    pub(super) pieces: Vec<Piece>,
    /// Input points that were merged into an earlier one.
    pub(super) merged: usize,
    /// Pieces dropped because their ends merged.
    pub(super) dropped_pieces: usize,
}

/// Everything flattening needs to know.
#[derive(Clone, Copy, Debug)]
pub(super) struct FlattenParams {
    /// The power-of-two scale into spade's range.
    pub(super) scale: Pow2Scale,
    /// Flattening accuracy, user units (the feature envelope μ).
    pub(super) accuracy: f64,
    /// Points closer than this (user units) are merged (ε_m).
    pub(super) merge_distance: f64,
}

impl PlanarInput {
    /// Flatten every feature of `drawing`.
    pub(super) fn new(drawing: &Drawing, fp: FlattenParams) -> PlanarInput {
        let s = fp.scale;
        let accuracy = s.length(fp.accuracy).max(f64::MIN_POSITIVE);
        let mut merger = Merger::new(s.length(fp.merge_distance));
        let mut pieces = Vec::new();
        let mut seen = std::collections::HashSet::new();
        let mut dropped_pieces = 0;
        let mut polyline: Vec<Point> = Vec::new();
        for f in &drawing.features {
            polyline.clear();
            match f.geom {
                FeatureGeom::Point(p) => polyline.push(s.point(p)),
                FeatureGeom::Line(l) => polyline.extend([s.point(l.p0), s.point(l.p1)]),
                FeatureGeom::Cubic(c) => {
                    let c =
                        CubicBez::new(s.point(c.p0), s.point(c.p1), s.point(c.p2), s.point(c.p3));
                    flatten_cubic(c, accuracy, &mut polyline);
                }
                FeatureGeom::Conic(k) => {
                    let c = Conic::new(s.point(k.p0), s.point(k.p1), s.point(k.p2), k.w);
                    flatten_conic(c, accuracy, &mut polyline);
                }
            }
            let mut prev: Option<u32> = None;
            for &p in &polyline {
                let v = merger.insert(spade_safe(p));
                if let Some(u) = prev {
                    if u == v {
                        dropped_pieces += 1;
                        continue;
                    }
                    let key = (u.min(v), u.max(v), f.source.shape);
                    if seen.insert(key) {
                        pieces.push(Piece {
                            a: u,
                            b: v,
                            shape: f.source.shape,
                        });
                    }
                }
                prev = Some(v);
            }
        }
        PlanarInput {
            merged: merger.merged,
            points: merger.points,
            pieces,
            dropped_pieces,
        }
    }
}

/// Flush coordinates too small for spade (below [`spade::MIN_ALLOWED_VALUE`], 2^-142)
/// to zero. In scaled coordinates (magnitudes below 2) this moves a point by less
/// than 2^-142, far below any tolerance.
fn spade_safe(p: Point) -> Point {
    let q = spade::mitigate_underflow(spade::Point2::new(p.x, p.y));
    Point::new(q.x, q.y)
}

/// Append the flattened polyline of `c` (both ends included) to `out`.
fn flatten_cubic(c: CubicBez, accuracy: f64, out: &mut Vec<Point>) {
    // Uniform subdivision into n pieces deviates at most max|B''| / (8 n²) from the
    // curve, and max|B''| ≤ 6 max(|p0 - 2p1 + p2|, |p1 - 2p2 + p3|); kurbo's adaptive
    // flattening needs fewer pieces than that. Coarsen the accuracy so that bound
    // stays below MAX_PIECES_PER_CUBIC.
    let second = (c.p0.to_vec2() - 2.0 * c.p1.to_vec2() + c.p2.to_vec2())
        .hypot()
        .max((c.p1.to_vec2() - 2.0 * c.p2.to_vec2() + c.p3.to_vec2()).hypot());
    let floor = 6.0 * second / (8.0 * MAX_PIECES_PER_CUBIC * MAX_PIECES_PER_CUBIC);
    let accuracy = accuracy.max(floor);
    out.push(c.p0);
    kurbo::flatten(
        [PathEl::MoveTo(c.p0), PathEl::CurveTo(c.p1, c.p2, c.p3)],
        accuracy,
        |el| {
            if let PathEl::LineTo(p) = el {
                // Points of a cubic lie in the hull of its control points; anything else
                // (a non-finite value) would be a flattening defect: skip it.
                if p.is_finite() {
                    out.push(p);
                }
            }
        },
    );
    // kurbo ends on p3 exactly; make sure of it.
    if out.last() != Some(&c.p3) {
        out.push(c.p3);
    }
}

/// Append the flattened polyline of the conic `c` (both ends included) to `out`: every
/// point of the curve within `accuracy` of the polyline, in at most
/// `MAX_PIECES_PER_CUBIC` pieces (the accuracy is coarsened beyond that).
///
/// A point of the conic is the combination of `p0`, `p1`, `p2` with positive weights
/// summing to 1 whose `p1` weight `2t(1−t)w / ((1−t)² + 2t(1−t)w + t²)` peaks at
/// `w / (1 + w)` (t = ½); the distance to the chord's segment being convex, the curve
/// is within `w / (1 + w) · dist(p1, chord)` of its chord. Pieces are halved
/// (standard-form [`Conic::subsegment`]) until that bound is within `accuracy`. A conic
/// whose weight is not positive and finite is no bounded arc: its chord.
fn flatten_conic(c: Conic, accuracy: f64, out: &mut Vec<Point>) {
    out.push(c.p0);
    if c.w > 0.0 && c.w.is_finite() {
        // Depth-first, first half first: the pieces come out in order.
        let max_depth = MAX_PIECES_PER_CUBIC.log2() as u32;
        let mut stack = vec![(c, 0u32)];
        while let Some((k, depth)) = stack.pop() {
            let chord = kurbo::Line::new(k.p0, k.p2);
            let bound = k.w / (1.0 + k.w) * crate::mesh::point_segment_distance(k.p1, chord);
            // A non-finite bound (overflow) is a flattening defect: take the chord.
            if bound <= accuracy || !bound.is_finite() || depth >= max_depth {
                if k.p2.is_finite() {
                    out.push(k.p2);
                }
            } else {
                stack.push((k.subsegment(0.5, 1.0), depth + 1));
                stack.push((k.subsegment(0.0, 0.5), depth + 1));
            }
        }
    }
    if out.last() != Some(&c.p2) {
        out.push(c.p2);
    }
}

/// Greedy point merging on a uniform grid.
struct Merger {
    tol: f64,
    cell: f64,
    grid: std::collections::HashMap<(i64, i64), Vec<u32>>,
    points: Vec<Point>,
    merged: usize,
}

impl Merger {
    fn new(tol: f64) -> Merger {
        // Scaled coordinates are below 2 in magnitude: 2^-50 keeps cell indices small.
        let tol = tol.max(0.0);
        Merger {
            tol,
            cell: tol.max(2f64.powi(-50)),
            grid: std::collections::HashMap::new(),
            points: Vec::new(),
            merged: 0,
        }
    }

    fn key(&self, p: Point) -> (i64, i64) {
        (
            (p.x / self.cell).floor() as i64,
            (p.y / self.cell).floor() as i64,
        )
    }

    /// The index of `p`: an earlier point within the merge distance, else a new one.
    fn insert(&mut self, p: Point) -> u32 {
        let (kx, ky) = self.key(p);
        let tol2 = self.tol * self.tol;
        let mut best: Option<(f64, u32)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                let Some(cands) = self
                    .grid
                    .get(&(kx.saturating_add(dx), ky.saturating_add(dy)))
                else {
                    continue;
                };
                for &i in cands {
                    let d2 = (self.points[i as usize] - p).hypot2();
                    if d2 <= tol2 && best.is_none_or(|(bd, bi)| (d2, i) < (bd, bi)) {
                        best = Some((d2, i));
                    }
                }
            }
        }
        if let Some((_, i)) = best {
            if self.points[i as usize] != p {
                self.merged += 1;
            }
            return i;
        }
        let i = u32::try_from(self.points.len()).expect("internal: more than 2^32 points");
        self.points.push(p);
        self.grid.entry((kx, ky)).or_default().push(i);
        i
    }
}

/// The box the baseline meshes: the drawing's bounding box (grown to hold every
/// feature's control points, whatever the drawing claims) padded by `padding`, and
/// always strictly larger than the bounding box.
pub(super) fn padded_box(drawing: &Drawing, padding: f64) -> Rect {
    let mut bbox = drawing.bbox;
    for f in &drawing.features {
        let conic;
        let pts: &[Point] = match &f.geom {
            FeatureGeom::Point(p) => std::slice::from_ref(p),
            FeatureGeom::Line(l) => &[l.p0, l.p1],
            FeatureGeom::Cubic(c) => &[c.p0, c.p1, c.p2, c.p3],
            FeatureGeom::Conic(c) => {
                conic = c.control_points();
                &conic
            }
        };
        for &p in pts {
            bbox = bbox.union_pt(p);
        }
    }
    let magnitude = [bbox.x0, bbox.y0, bbox.x1, bbox.y1]
        .into_iter()
        .fold(0.0f64, |m, c| m.max(c.abs()));
    // An absolute padding far below the coordinates' resolution would vanish in the
    // sums below; keep a few ulps of room so the box stays strictly larger.
    let pad = padding.max(magnitude * 1e-12).max(f64::MIN_POSITIVE);
    Rect::new(bbox.x0 - pad, bbox.y0 - pad, bbox.x1 + pad, bbox.y1 + pad)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pow2_scale_is_exact_and_normalizing() {
        for m in [1e-300, 1e-9, 0.3, 1.0, 2.0, 1e9, 1e15, 5e-324] {
            let s = Pow2Scale::normalizing(m);
            let scaled = s.apply(m);
            assert!((0.5..2.0).contains(&scaled), "{m} -> {scaled}");
            assert_eq!(s.invert(scaled), m);
        }
    }

    #[test]
    fn merger_merges_within_tolerance_only() {
        let mut m = Merger::new(1e-3);
        assert_eq!(m.insert(Point::new(0.0, 0.0)), 0);
        assert_eq!(m.insert(Point::new(0.0005, 0.0)), 0);
        assert_eq!(m.insert(Point::new(0.002, 0.0)), 1);
        assert_eq!(m.insert(Point::new(0.0, 0.0)), 0);
        assert_eq!(m.merged, 1);
    }

    #[test]
    fn flattening_stays_within_accuracy_and_keeps_ends() {
        let c = CubicBez::new((0.0, 0.0), (0.0, 0.5), (0.5, 1.0), (1.0, 1.0));
        let mut out = Vec::new();
        flatten_cubic(c, 1e-3, &mut out);
        assert_eq!(out[0], c.p0);
        assert_eq!(*out.last().unwrap(), c.p3);
        assert!(out.len() > 3 && out.len() < 100, "{}", out.len());
        // A tiny accuracy on a big cubic is capped.
        let mut out = Vec::new();
        flatten_cubic(c, 1e-30, &mut out);
        assert!(
            out.len() <= MAX_PIECES_PER_CUBIC as usize + 2,
            "{}",
            out.len()
        );
        // A degenerate cubic flattens to its end points.
        let mut out = Vec::new();
        flatten_cubic(
            CubicBez::new((1.0, 1.0), (1.0, 1.0), (1.0, 1.0), (1.0, 1.0)),
            1e-3,
            &mut out,
        );
        assert!(out.iter().all(|&p| p == Point::new(1.0, 1.0)));
    }

    #[test]
    fn conic_flattening_stays_within_accuracy_and_keeps_ends() {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let c = Conic::new((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), w);
        for acc in [1e-2, 1e-4, 1e-6] {
            let mut out = Vec::new();
            flatten_conic(c, acc, &mut out);
            assert_eq!(out[0], c.p0);
            assert_eq!(*out.last().unwrap(), c.p2);
            // Vertices on the circle, chords within acc of it (sagitta of each chord).
            for w in out.windows(2) {
                assert!((w[0].to_vec2().hypot() - 1.0).abs() < 1e-15);
                let half = 0.5 * w[0].distance(w[1]);
                let sagitta = 1.0 - (1.0 - half * half).sqrt();
                assert!(sagitta <= acc, "{sagitta} > {acc}");
            }
            // Not wastefully fine: within a factor 4 of the uniform chord count.
            let uniform = (std::f64::consts::FRAC_PI_2 / (8.0 * acc).sqrt()).ceil();
            assert!(
                (out.len() - 1) as f64 <= 4.0 * uniform,
                "{} pieces",
                out.len()
            );
        }
        // A tiny accuracy is capped; a bad weight gives the chord.
        let mut out = Vec::new();
        flatten_conic(c, 1e-30, &mut out);
        assert!(
            out.len() <= MAX_PIECES_PER_CUBIC as usize + 1,
            "{}",
            out.len()
        );
        let mut out = Vec::new();
        flatten_conic(Conic::new(c.p0, c.p1, c.p2, -1.0), 1e-3, &mut out);
        assert_eq!(out, vec![c.p0, c.p2]);
    }
}
