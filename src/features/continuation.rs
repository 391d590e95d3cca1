//! Exact continuations: consecutive pieces of one subpath that are pieces of one curve
//! become one input curve before anything else looks at them.
//!
//! A drawing often cuts one curve into many pieces: a disk drawn as 64 arcs, a circle's
//! four quarters, a straight side with redundant points on it. Every piece is a parent
//! curve of its own to the later stages, so every joint is a chain end: a fixed mesh
//! vertex (§4.4.1), and the mesh can never be coarser than the joints. A joint between
//! two pieces of *one* curve is not a feature of the drawing, only of how it was written;
//! joining the pieces lets the mesh place its vertices as the target length asks.
//!
//! Two pieces join only when the joined curve *is* both pieces, so every later guarantee
//! (edges interpolate the exact input curves; an order-3 edge on a cubic is that cubic's
//! piece; the Jacobian certificate) is unchanged:
//!
//! - two segments whose three points are collinear (exact orientation test) and that run
//!   the same way join into one segment;
//! - two conic pieces (ellipse arcs in standard form) that lie on one ellipse and turn the
//!   same way join into one piece of at most 90° (the loader's convention for a piece),
//!   checked by sampling both within `tol` of the joined conic;
//! - cubics never join: two cubic pieces are one curve only if they are pieces of one
//!   polynomial, which rounding in the document breaks (and an edge spanning the joint
//!   of two different cubics would only approximate them at order 3).
//!
//! A joint joins only where nothing else ends: no other curve end or point within `l_m`
//! (snapping would otherwise move a neighbour's end onto what is now the inside of a
//! curve, and the separation test would demote both).

use crate::exact::predicates::{Orientation, orient2d};
use crate::svg::drawing::Conic;
use crate::svg::{Feature, FeatureGeom};
use kurbo::{Line, Point};
use rustc_hash::FxHashMap;

/// Samples per conic piece when checking that it lies on the joined conic.
const SAMPLES: usize = 8;
/// The joined conic's weight is at least cos 45°: a piece of at most 90° of its
/// ellipse, as the loader cuts them (minus rounding).
const MIN_WEIGHT: f64 = std::f64::consts::FRAC_1_SQRT_2 - 1e-12;
/// Tangents at a joint must agree to within this sine before the samples are checked
/// (a cheap filter: pieces of one ellipse agree to rounding).
const G1_SIN: f64 = 1e-6;

/// The joined features.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Joined {
    /// The features, each with the index (in the input) of its first piece; the input
    /// order is kept.
    pub(super) features: Vec<(u32, Feature)>,
    /// Joints removed.
    pub(super) joints: usize,
}

/// Join exact continuations in `features` (see the module doc): `tol` is the distance
/// (user units) within which conic samples must lie on the joined conic, `l_min` the
/// radius around a joint that must hold no other curve end or point.
pub(super) fn join(features: &[Feature], tol: f64, l_min: f64) -> Joined {
    let ends = EndGrid::new(features, l_min);
    let mut out: Vec<(u32, Feature)> = Vec::with_capacity(features.len());
    let mut joints = 0;
    for (i, f) in features.iter().enumerate() {
        let i = u32::try_from(i).expect("internal: feature count fits u32");
        if let Some((_, last)) = out.last_mut() {
            let same_subpath =
                last.source.shape == f.source.shape && last.source.subpath == f.source.subpath;
            if same_subpath {
                if let Some(geom) = join_pair(&last.geom, &f.geom, tol, &ends) {
                    last.geom = geom;
                    joints += 1;
                    continue;
                }
            }
        }
        out.push((i, *f));
    }
    Joined {
        features: out,
        joints,
    }
}

/// The one curve that `a` followed by `b` is, if they join.
fn join_pair(a: &FeatureGeom, b: &FeatureGeom, tol: f64, ends: &EndGrid) -> Option<FeatureGeom> {
    match (a, b) {
        (FeatureGeom::Line(a), FeatureGeom::Line(b))
            if a.p1 == b.p0 && ends.lone_joint(a.p1) && continues_straight(a, b) =>
        {
            Some(FeatureGeom::Line(Line::new(a.p0, b.p1)))
        }
        (FeatureGeom::Conic(a), FeatureGeom::Conic(b)) if a.p2 == b.p0 && ends.lone_joint(a.p2) => {
            join_conics(a, b, tol).map(FeatureGeom::Conic)
        }
        _ => None,
    }
}

/// Whether `b` continues `a` straight on: the three points exactly collinear, both
/// segments non-degenerate and running the same way.
fn continues_straight(a: &Line, b: &Line) -> bool {
    let (u, v) = (a.p1 - a.p0, b.p1 - b.p0);
    u.hypot2() > 0.0
        && v.hypot2() > 0.0
        && u.dot(v) > 0.0
        && orient2d(a.p0, a.p1, b.p1) == Orientation::Collinear
}

/// The conic that is `a` followed by `b`, when both are pieces of one ellipse turning
/// the same way and together span at most 90° of it.
pub(super) fn join_conics(a: &Conic, b: &Conic, tol: f64) -> Option<Conic> {
    let proper = |c: &Conic| c.w > 0.0 && c.w < 1.0;
    if !(proper(a) && proper(b)) {
        return None;
    }
    // Same turning direction.
    let turn = |c: &Conic| (c.p1 - c.p0).cross(c.p2 - c.p1);
    let same_turn = turn(a) * turn(b);
    if same_turn.is_nan() || same_turn <= 0.0 {
        return None;
    }
    // G1 at the joint (a filter; the samples decide).
    let (ta, tb) = (a.p2 - a.p1, b.p1 - b.p0);
    let (na, nb) = (ta.hypot(), tb.hypot());
    if !(na > 0.0 && nb > 0.0) || ta.dot(tb) <= 0.0 || ta.cross(tb).abs() > G1_SIN * na * nb {
        return None;
    }
    // Half sweeps add: w = cos(h_a + h_b), with w = cos h for each piece (an affine
    // image of a circle keeps the weights).
    let sin = |w: f64| (1.0 - w * w).max(0.0).sqrt();
    let w = a.w * b.w - sin(a.w) * sin(b.w);
    if !(MIN_WEIGHT..1.0).contains(&w) {
        return None;
    }
    // The control point: where the end tangents meet.
    let (d0, d1) = (a.p1 - a.p0, b.p2 - b.p1);
    let den = d0.cross(d1);
    if den == 0.0 || !den.is_finite() {
        return None;
    }
    let s = (b.p2 - a.p0).cross(d1) / den;
    if !(s > 0.0 && s.is_finite()) {
        return None;
    }
    let joined = Conic::new(a.p0, a.p0 + d0 * s, b.p2, w);
    let on = |c: &Conic| {
        (0..=SAMPLES).all(|k| distance_bound(&joined, c.eval(k as f64 / SAMPLES as f64)) <= tol)
    };
    (on(a) && on(b)).then_some(joined)
}

/// An upper bound of the distance from `q` to the conic `c` (standard form, `0 < w < 1`):
/// the distance to the conic's point on the line through `c.p1` and `q` (its barycentric
/// coordinates λ₀ : λ₂ = (1−t)² : t²); infinite when `q` is outside the wedge at `p1`.
fn distance_bound(c: &Conic, q: Point) -> f64 {
    let area = (c.p1 - c.p0).cross(c.p2 - c.p0);
    if area == 0.0 || !area.is_finite() {
        return f64::INFINITY;
    }
    let l0 = (c.p1 - q).cross(c.p2 - q) / area;
    let l2 = (c.p1 - c.p0).cross(q - c.p0) / area;
    if !(l0 >= 0.0 && l2 >= 0.0) || l0 + l2 == 0.0 {
        return f64::INFINITY;
    }
    let t = if l0 == 0.0 {
        1.0
    } else {
        let r = (l2 / l0).sqrt();
        r / (1.0 + r)
    };
    c.eval(t).distance(q)
}

/// Every curve end and isolated point on a grid of cell `l_min`, to tell whether a
/// joint is touched by anything but its two pieces.
struct EndGrid {
    cell: f64,
    grid: FxHashMap<(i64, i64), Vec<Point>>,
}

impl EndGrid {
    fn new(features: &[Feature], l_min: f64) -> EndGrid {
        let mut g = EndGrid {
            cell: l_min,
            grid: FxHashMap::default(),
        };
        for f in features {
            let ends: &[Point] = &match f.geom {
                FeatureGeom::Point(p) => [p, p],
                FeatureGeom::Line(l) => [l.p0, l.p1],
                FeatureGeom::Cubic(c) => [c.p0, c.p3],
                FeatureGeom::Conic(c) => [c.p0, c.p2],
            };
            let n = if matches!(f.geom, FeatureGeom::Point(_)) {
                1
            } else {
                2
            };
            for &p in &ends[..n] {
                let key = g.key(p);
                g.grid.entry(key).or_default().push(p);
            }
        }
        g
    }

    fn key(&self, p: Point) -> (i64, i64) {
        // Coordinates are bounded (Drawing::MAX_COORD) and `cell` positive: the casts
        // saturate at worst.
        (
            (p.x / self.cell).floor() as i64,
            (p.y / self.cell).floor() as i64,
        )
    }

    /// Whether exactly two ends (the joint's own two pieces) lie within `l_min` of `p`.
    fn lone_joint(&self, p: Point) -> bool {
        if self.cell.is_nan() || self.cell <= 0.0 {
            return false;
        }
        let (cx, cy) = self.key(p);
        let mut near = 0;
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(ps) = self.grid.get(&(cx + dx, cy + dy)) {
                    near += ps.iter().filter(|q| q.distance(p) <= self.cell).count();
                }
            }
        }
        near == 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::svg::{FeatureSource, ShapeId};
    use kurbo::{Arc, Vec2};
    use std::f64::consts::PI;

    fn feature(geom: FeatureGeom, subpath: u32, segment: u32) -> Feature {
        Feature {
            geom,
            source: FeatureSource {
                shape: ShapeId::from_index(0),
                subpath,
                segment,
            },
        }
    }

    /// A unit circle about `c` as `n` arcs (each cut by the loader's rule), joints shared
    /// bit for bit, closed exactly.
    fn arcs(c: Point, n: usize) -> Vec<Feature> {
        let at = |k: usize| {
            if k == n {
                c + Vec2::new(1.0, 0.0)
            } else {
                c + Vec2::from_angle(2.0 * PI * k as f64 / n as f64)
            }
        };
        let mut out = Vec::new();
        for k in 0..n {
            let arc = Arc::new(
                c,
                Vec2::new(1.0, 1.0),
                2.0 * PI * k as f64 / n as f64,
                2.0 * PI / n as f64,
                0.0,
            );
            for piece in Conic::ellipse_arc(&arc, Some(at(k)), Some(at(k + 1))) {
                out.push(feature(FeatureGeom::Conic(piece), 0, k as u32));
            }
        }
        out
    }

    #[test]
    fn sixty_four_arcs_of_a_circle_join_into_four_exact_quarters() {
        let c = Point::new(1.0, 1.0);
        let j = join(&arcs(c, 64), 1e-11, 1e-4);
        assert_eq!(j.features.len(), 4, "{:?}", j.features);
        assert_eq!(j.joints, 60);
        for (k, (first, f)) in j.features.iter().enumerate() {
            assert_eq!(*first as usize, 16 * k);
            let FeatureGeom::Conic(q) = f.geom else {
                panic!("not a conic: {f:?}");
            };
            assert!(
                (q.w - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12,
                "{q:?}"
            );
            for i in 0..=32 {
                let r = q.eval(f64::from(i) / 32.0).distance(c);
                assert!((r - 1.0).abs() < 1e-14, "radius {r}");
            }
        }
        // The joined curves still close up bit for bit.
        for w in 0..4 {
            let (FeatureGeom::Conic(a), FeatureGeom::Conic(b)) =
                (j.features[w].1.geom, j.features[(w + 1) % 4].1.geom)
            else {
                unreachable!()
            };
            assert_eq!(a.p2, b.p0);
        }
    }

    #[test]
    fn quarters_of_a_circle_stay_quarters_and_other_subpaths_never_join() {
        let c = Point::new(0.0, 0.0);
        // Four quarters: a half circle is not one conic piece (w = 0).
        assert_eq!(join(&arcs(c, 4), 1e-11, 1e-4).features.len(), 4);
        // Two subpaths: the arcs join within each, never across.
        let mut fs = arcs(c, 8);
        for f in &mut fs[4..] {
            f.source.subpath = 1;
        }
        let j = join(&fs, 1e-11, 1e-4);
        assert_eq!(j.features.len(), 4);
        assert!(
            j.features
                .iter()
                .take(2)
                .all(|(_, f)| f.source.subpath == 0)
        );
    }

    #[test]
    fn arcs_of_different_circles_and_opposite_turns_do_not_join() {
        let c = Point::new(0.0, 0.0);
        let fs = arcs(c, 16);
        let (FeatureGeom::Conic(a), FeatureGeom::Conic(b)) = (fs[0].geom, fs[1].geom) else {
            unreachable!()
        };
        assert!(join_conics(&a, &b, 1e-11).is_some());
        // The same joint, the second arc on a circle of radius 1.001 tangent there.
        let k = a.p2.to_vec2();
        let scale = |p: Point| (p.to_vec2() * 1.001 - k * 0.001).to_point();
        let b2 = Conic::new(b.p0, scale(b.p1), scale(b.p2), b.w);
        assert_eq!(b2.p0, a.p2);
        assert!(join_conics(&a, &b2, 1e-11).is_none());
        // An S: the second arc turns the other way.
        let mirror = |p: Point| (k * 2.0 - p.to_vec2()).to_point();
        let s = Conic::new(a.p2, mirror(a.p1), mirror(a.p0), a.w);
        assert!(join_conics(&a, &s, 1e-11).is_none());
    }

    #[test]
    fn collinear_segments_join_unless_something_else_ends_at_the_joint() {
        let l = |a: (f64, f64), b: (f64, f64)| FeatureGeom::Line(Line::new(a, b));
        let fs = vec![
            feature(l((0.0, 0.0), (1.0, 0.0)), 0, 0),
            feature(l((1.0, 0.0), (3.0, 0.0)), 0, 1),
            feature(l((3.0, 0.0), (3.0, 1.0)), 0, 2),
            feature(l((3.0, 1.0), (2.0, 1.0)), 0, 3),
            feature(l((2.0, 1.0), (0.0, 1.0)), 0, 4),
        ];
        let j = join(&fs, 1e-11, 1e-4);
        let geoms: Vec<FeatureGeom> = j.features.iter().map(|(_, f)| f.geom).collect();
        assert_eq!(
            geoms,
            vec![
                l((0.0, 0.0), (3.0, 0.0)),
                l((3.0, 0.0), (3.0, 1.0)),
                l((3.0, 1.0), (0.0, 1.0))
            ]
        );
        assert_eq!(j.joints, 2);
        // A point (or another curve's end) at a joint keeps that joint.
        let mut with_point = fs.clone();
        with_point.push(feature(FeatureGeom::Point(Point::new(1.0, 0.0)), 1, 0));
        let j = join(&with_point, 1e-11, 1e-4);
        assert_eq!(j.features.len(), 5);
        assert_eq!(j.features[0].1.geom, l((0.0, 0.0), (1.0, 0.0)));
        // Folding back is not a continuation; nor is a kink of one ulp.
        let back = vec![
            feature(l((0.0, 0.0), (2.0, 0.0)), 0, 0),
            feature(l((2.0, 0.0), (1.0, 0.0)), 0, 1),
        ];
        assert_eq!(join(&back, 1e-11, 1e-4).features.len(), 2);
        let kink = vec![
            feature(l((0.0, 0.0), (1.0, 0.0)), 0, 0),
            feature(l((1.0, 0.0), (2.0, f64::EPSILON)), 0, 1),
        ];
        assert_eq!(join(&kink, 1e-11, 1e-4).features.len(), 2);
    }
}
