//! Removal of degenerate curves and detection of straight ones (thesis §4.4, first two
//! paragraphs).
//!
//! A curve whose control points all lie within ε_m of their mean becomes a point (the
//! mean). A cubic whose control points lie within ε_m (sum of distances) of their
//! least-squares line becomes the segment(s) it traces: one segment from `p0` to `p3`, or
//! several collinear ones if the curve reverses along the line. A conic is judged the same
//! way on its three control points (a rational quadratic of positive weight lies in their
//! triangle). A conic whose weight is not positive and finite is no bounded arc from `p0`
//! to `p2` (the loader never makes one): it is taken as its chord, the limit `w → 0`.

use crate::svg::FeatureGeom;
use crate::svg::drawing::Conic;
use kurbo::{CubicBez, Line, ParamCurve, Point, Vec2};

/// What an input feature is, geometrically.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Class {
    /// An isolated point (input point or degenerate curve).
    Point(Point),
    /// Straight: consecutive segments, each starting where the previous ends.
    Lines(Vec<Line>),
    /// A genuinely curved cubic.
    Curve(CubicBez),
    /// A genuinely curved conic (positive, finite weight).
    Conic(Conic),
}

fn mean(ps: &[Point]) -> Point {
    let s = ps.iter().fold(Vec2::ZERO, |a, p| a + p.to_vec2());
    (s / ps.len() as f64).to_point()
}

/// Classify one input feature with numerical tolerance `eps_m` (user units).
pub(super) fn classify(geom: &FeatureGeom, eps_m: f64) -> Class {
    match *geom {
        FeatureGeom::Point(p) => Class::Point(p),
        FeatureGeom::Line(l) => {
            let m = l.p0.midpoint(l.p1);
            if m.distance(l.p0) <= eps_m && m.distance(l.p1) <= eps_m {
                Class::Point(m)
            } else {
                Class::Lines(vec![l])
            }
        }
        FeatureGeom::Cubic(c) => classify_cubic(&c, eps_m),
        FeatureGeom::Conic(c) if c.w > 0.0 && c.w.is_finite() => classify_conic(&c, eps_m),
        FeatureGeom::Conic(c) => classify(&FeatureGeom::Line(Line::new(c.p0, c.p2)), eps_m),
    }
}

/// The mean of the control points, if they all lie within `eps_m` of it (a degenerate
/// curve), else the unit direction of their least-squares line and the sum of their
/// distances to it.
enum Fit {
    Degenerate(Point),
    Line { mean: Point, dir: Vec2, off: f64 },
}

fn fit_line(ps: &[Point], eps_m: f64) -> Fit {
    let m = mean(ps);
    if ps.iter().all(|p| p.distance(m) <= eps_m) {
        return Fit::Degenerate(m);
    }
    // Least-squares line through the mean: the principal axis of the control points.
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in ps {
        let v = *p - m;
        sxx += v.x * v.x;
        sxy += v.x * v.y;
        syy += v.y * v.y;
    }
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let dir = Vec2::new(theta.cos(), theta.sin());
    let off: f64 = ps.iter().map(|p| dir.cross(*p - m).abs()).sum();
    Fit::Line { mean: m, dir, off }
}

fn classify_conic(c: &Conic, eps_m: f64) -> Class {
    let ps = c.control_points();
    let (m, dir) = match fit_line(&ps, eps_m) {
        Fit::Degenerate(m) => return Class::Point(m),
        Fit::Line { off, .. } if off > eps_m => return Class::Conic(*c),
        Fit::Line { mean, dir, .. } => (mean, dir),
    };
    // Straight: the projection on the line has derivative ∝ the quadratic with Bernstein
    // coefficients w(a1 − a0), (a2 − a0)/2, w(a2 − a1) (C′ = 2Q/D², Q(t) = w(1−t)²(p1 − p0)
    // + t(1−t)(p2 − p0) + wt²(p2 − p1)).
    let [a0, a1, a2] = ps.map(|p| dir.dot(p - ps[0]));
    let (b0, b1, b2) = (c.w * (a1 - a0), 0.5 * (a2 - a0), c.w * (a2 - a1));
    let turns = kurbo::common::solve_quadratic(b0, 2.0 * (b1 - b0), b0 - 2.0 * b1 + b2);
    straight(c.p0, c.p2, m, turns.into_iter(), |t| c.eval(t), eps_m)
}

fn classify_cubic(c: &CubicBez, eps_m: f64) -> Class {
    let ps = [c.p0, c.p1, c.p2, c.p3];
    let (m, dir) = match fit_line(&ps, eps_m) {
        Fit::Degenerate(m) => return Class::Point(m),
        Fit::Line { off, .. } if off > eps_m => return Class::Curve(*c),
        Fit::Line { mean, dir, .. } => (mean, dir),
    };
    // Straight: split where the projection on the line reverses (roots of its derivative).
    let a = dir.dot(c.p1 - c.p0);
    let b = dir.dot(c.p2 - c.p1);
    let e = dir.dot(c.p3 - c.p2);
    // d/dt of the projection ∝ (1-t)² a + 2t(1-t) b + t² e = a + 2t(b-a) + t²(a-2b+e).
    let turns = kurbo::common::solve_quadratic(a, 2.0 * (b - a), a - 2.0 * b + e);
    straight(c.p0, c.p3, m, turns.into_iter(), |t| c.eval(t), eps_m)
}

/// The segments a straight curve from `start` to `end` traces: cut at its turning points
/// (the parameters `turns`, those in (0, 1) count), dropping cuts within `eps_m` of a
/// neighbour; a point (`mean`) if nothing is left.
fn straight(
    start: Point,
    end: Point,
    mean: Point,
    turns: impl Iterator<Item = f64>,
    eval: impl Fn(f64) -> Point,
    eps_m: f64,
) -> Class {
    let mut ts: Vec<f64> = turns.filter(|t| *t > 0.0 && *t < 1.0).collect();
    ts.sort_by(f64::total_cmp);
    let mut pts = vec![start];
    for t in ts {
        let p = eval(t);
        let last = *pts.last().expect("internal: pts starts non-empty");
        if p.distance(last) > eps_m && p.distance(end) > eps_m {
            pts.push(p);
        }
    }
    let last = *pts.last().expect("internal: pts starts non-empty");
    if last.distance(end) > eps_m || pts.len() == 1 {
        pts.push(end);
    } else {
        // Snap the last kept point onto the exact end point.
        *pts.last_mut().expect("internal: pts non-empty") = end;
    }
    if pts.len() < 2 || pts[0] == pts[pts.len() - 1] && pts.len() == 2 {
        return Class::Point(mean);
    }
    Class::Lines(pts.windows(2).map(|w| Line::new(w[0], w[1])).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degenerate_cubic_is_its_mean() {
        let c = CubicBez::new((1.0, 1.0), (1.0 + 1e-9, 1.0), (1.0, 1.0 - 1e-9), (1.0, 1.0));
        match classify(&FeatureGeom::Cubic(c), 1e-8) {
            Class::Point(p) => assert!(p.distance(Point::new(1.0, 1.0)) < 1e-9),
            other => panic!("expected a point, got {other:?}"),
        }
    }

    #[test]
    fn straight_cubic_is_a_segment_and_curved_one_is_not() {
        let c = CubicBez::new((0.0, 0.0), (1.0, 1.0), (2.0, 2.0), (3.0, 3.0 + 1e-12));
        assert_eq!(
            classify(&FeatureGeom::Cubic(c), 1e-8),
            Class::Lines(vec![Line::new(c.p0, c.p3)])
        );
        let bent = CubicBez::new((0.0, 0.0), (1.0, 1e-3), (2.0, 0.0), (3.0, 0.0));
        assert_eq!(
            classify(&FeatureGeom::Cubic(bent), 1e-8),
            Class::Curve(bent)
        );
    }

    #[test]
    fn straight_cubic_that_folds_back_becomes_collinear_segments() {
        // Goes right past x = 3, comes back to 2.
        let c = CubicBez::new((0.0, 0.0), (4.0, 0.0), (4.0, 0.0), (2.0, 0.0));
        let Class::Lines(ls) = classify(&FeatureGeom::Cubic(c), 1e-8) else {
            panic!("expected lines");
        };
        assert_eq!(ls.len(), 2);
        assert_eq!(ls[0].p0, c.p0);
        assert_eq!(ls[1].p1, c.p3);
        assert_eq!(ls[0].p1, ls[1].p0);
        assert!(ls[0].p1.x > 2.9, "turning point {:?}", ls[0].p1);
    }

    #[test]
    fn short_line_is_a_point() {
        let l = Line::new((5.0, 5.0), (5.0, 5.0 + 1e-9));
        assert!(matches!(
            classify(&FeatureGeom::Line(l), 1e-8),
            Class::Point(_)
        ));
    }

    #[test]
    fn conics_are_points_lines_or_curves() {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let quarter = Conic::new((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), w);
        assert_eq!(
            classify(&FeatureGeom::Conic(quarter), 1e-8),
            Class::Conic(quarter)
        );
        let tiny = Conic::new((1.0, 1.0), (1.0 + 1e-9, 1.0), (1.0, 1.0 + 1e-9), w);
        assert!(matches!(
            classify(&FeatureGeom::Conic(tiny), 1e-8),
            Class::Point(_)
        ));
        // Collinear controls, the middle one between the ends: one segment.
        let flat = Conic::new((0.0, 0.0), (1.0, 1e-12), (3.0, 0.0), 0.5);
        assert_eq!(
            classify(&FeatureGeom::Conic(flat), 1e-8),
            Class::Lines(vec![Line::new(flat.p0, flat.p2)])
        );
        // The middle one beyond the end: the curve goes past x = 2 and comes back.
        let folded = Conic::new((0.0, 0.0), (4.0, 0.0), (2.0, 0.0), 0.9);
        let Class::Lines(ls) = classify(&FeatureGeom::Conic(folded), 1e-8) else {
            panic!("expected lines");
        };
        assert_eq!(ls.len(), 2);
        assert_eq!((ls[0].p0, ls[1].p1), (folded.p0, folded.p2));
        let far = (0..=1000)
            .map(|k| folded.eval(f64::from(k) / 1000.0).x)
            .fold(0.0, f64::max);
        assert!((ls[0].p1.x - far).abs() < 1e-6, "{:?} vs {far}", ls[0].p1);
        // Weights that make no bounded arc: the chord.
        for w in [0.0, -0.5, f64::NAN, f64::INFINITY] {
            let c = Conic::new((0.0, 0.0), (1.0, 1.0), (2.0, 0.0), w);
            assert_eq!(
                classify(&FeatureGeom::Conic(c), 1e-8),
                Class::Lines(vec![Line::new(c.p0, c.p2)])
            );
        }
    }
}
