//! `f64` measurements: distances and angles of points, lengths of mesh edges.
//! The geometry `topology.rs` must not do, shared by every stage that measures
//! with the same arithmetic (so their numbers agree bit for bit).

use super::ids::VertexId;
use super::storage::TriMesh;
use kurbo::{Line, Point, Vec2};

impl TriMesh {
    /// The distance between the `f64` positions of `a` and `b` (an edge's length).
    pub(crate) fn distance(&self, a: VertexId, b: VertexId) -> f64 {
        self.position(a).distance(self.position(b))
    }
}

/// Whether the triangle `[a, b, c]` is thin to rounding: `|2·area| ≤ rel · h²`,
/// h² the sum of its bounding box's squared extents (scale-free: `mshcheck`'s
/// degeneracy test has this form). A triangle with a NaN coordinate is thin.
pub(crate) fn is_sliver([a, b, c]: [Point; 3], rel: f64) -> bool {
    let twice_area = (b - a).cross(c - a);
    let ext = |v: [f64; 3]| {
        v.iter().fold(f64::MIN, |m, x| m.max(*x)) - v.iter().fold(f64::MAX, |m, x| m.min(*x))
    };
    let h2 = ext([a.x, b.x, c.x]).powi(2) + ext([a.y, b.y, c.y]).powi(2);
    twice_area.abs().partial_cmp(&(rel * h2)) != Some(std::cmp::Ordering::Greater)
}

/// The distance from `p` to the segment `l` (to `l.p0` when `l` has zero length).
pub(crate) fn point_segment_distance(p: Point, l: Line) -> f64 {
    let d = l.p1 - l.p0;
    let len2 = d.hypot2();
    if len2 == 0.0 {
        return p.distance(l.p0);
    }
    let s = ((p - l.p0).dot(d) / len2).clamp(0.0, 1.0);
    p.distance(l.p0 + d * s)
}

/// The unsigned angle between the vectors `u` and `v`, radians in `[0, π]`;
/// 0 when either is zero.
pub(crate) fn angle_between(u: Vec2, v: Vec2) -> f64 {
    u.cross(v).abs().atan2(u.dot(v))
}

/// The unsigned angle at `at` between the directions to `prev` and `next`,
/// radians in `[0, π]`; 0 when an adjacent edge has zero length.
pub(crate) fn corner_angle(prev: Point, at: Point, next: Point) -> f64 {
    angle_between(prev - at, next - at)
}

/// The corner angles of the triangle `[a, b, c]`, radians, at `a`, `b`, `c`.
pub(crate) fn corner_angles([a, b, c]: [Point; 3]) -> [f64; 3] {
    [
        corner_angle(c, a, b),
        corner_angle(a, b, c),
        corner_angle(b, c, a),
    ]
}

/// The smallest corner angle of the triangle `[a, b, c]`, degrees: the one
/// facing the shortest edge, computed as [`corner_angles`] computes that
/// corner (one `atan2` instead of three: the optimizer measures every face
/// after every pass).
pub(crate) fn min_angle_deg([a, b, c]: [Point; 3]) -> f64 {
    let (ab, bc, ca) = ((b - a).hypot2(), (c - b).hypot2(), (a - c).hypot2());
    if ab <= bc && ab <= ca {
        corner_angle(b, c, a)
    } else if bc <= ca {
        corner_angle(c, a, b)
    } else {
        corner_angle(a, b, c)
    }
    .to_degrees()
}

/// Distance between two segments (0 if they cross or touch).
///
/// A measurement, not a decision: the crossing test only short-cuts to 0, and where
/// float rounding could get it wrong the segments nearly cross, so the endpoint
/// distances below are within rounding of 0 too. Plain products keep this hot loop
/// of the μ-separation cheap (the exact predicate doubled the stage's time).
pub(crate) fn segment_distance(a: Line, b: Line) -> f64 {
    let side = |p: Point, q: Point, r: Point| (q - p).cross(r - p);
    let (d1, d2) = (side(a.p0, a.p1, b.p0), side(a.p0, a.p1, b.p1));
    let (d3, d4) = (side(b.p0, b.p1, a.p0), side(b.p0, b.p1, a.p1));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return 0.0;
    }
    point_segment_distance(a.p0, b)
        .min(point_segment_distance(a.p1, b))
        .min(point_segment_distance(b.p0, a))
        .min(point_segment_distance(b.p1, a))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slivers_are_scale_free_and_nan_is_thin() {
        let p = |x: f64, y: f64| Point::new(x, y);
        for s in [1e-9, 1.0, 1e9] {
            assert!(!is_sliver([p(0.0, 0.0), p(s, 0.0), p(0.0, s)], 1e-10));
            assert!(is_sliver(
                [p(0.0, 0.0), p(s, 0.0), p(2.0 * s, 1e-12 * s)],
                1e-10
            ));
        }
        assert!(is_sliver(
            [p(0.0, 0.0), p(1.0, 0.0), p(f64::NAN, 1.0)],
            1e-10
        ));
    }

    #[test]
    fn distances_and_angles() {
        let l = Line::new(Point::new(0.0, 0.0), Point::new(2.0, 0.0));
        assert_eq!(point_segment_distance(Point::new(1.0, 3.0), l), 3.0);
        assert_eq!(point_segment_distance(Point::new(5.0, 4.0), l), 5.0);
        let dot = Line::new(Point::new(1.0, 1.0), Point::new(1.0, 1.0));
        assert_eq!(point_segment_distance(Point::new(4.0, 5.0), dot), 5.0);
        let right = [Point::ZERO, Point::new(1.0, 0.0), Point::new(0.0, 1.0)];
        assert!((min_angle_deg(right) - 45.0).abs() < 1e-12);
        // The corner facing the shortest edge is the smallest of the three,
        // on random, thin and degenerate triangles.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for i in 0..10_000 {
            let a = Point::new(next(), next());
            let b = Point::new(next(), next());
            let c = match i % 4 {
                0 => Point::new(next(), next()),
                1 => a.lerp(b, next()) + Vec2::new(1e-9 * next(), 1e-9 * next()),
                2 => a.lerp(b, 0.5 * next() + 0.5),
                _ => a,
            };
            let [x, y, z] = corner_angles([a, b, c]);
            let all = x.min(y).min(z).to_degrees();
            let got = min_angle_deg([a, b, c]);
            assert!(
                (got - all).abs() <= 1e-9 * all.max(1.0),
                "{a:?} {b:?} {c:?}: {got} {all}"
            );
        }
        assert!((corner_angles(right)[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert_eq!(
            corner_angle(Point::ZERO, Point::ZERO, Point::new(1.0, 0.0)),
            0.0
        );
    }
}
