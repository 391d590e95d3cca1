//! Inflection and total-curvature splits (thesis §4.4 "Inflection point split" and "Total
//! curvature split").
//!
//! A cubic is cut at the roots in (0, 1) of det(c′, c″) (equation 4.1) and at its
//! zero-derivative points (cusps), so every piece has constant-sign curvature. A piece
//! that turns 180° or more is then cut, recursively, where its tangent is the bisector of
//! the turn (the mean of the end tangents, negated when the turn exceeds 180°), until every
//! piece turns less than 180°: after this, the turn of a piece is the angle between its end
//! tangents.
//!
//! A conic of positive weight turns by less than 180° with constant-sign curvature (its
//! derivative is a positive combination of `p1 − p0` and `p2 − p1`), so only the turn
//! split applies, and its turn over any interval is the angle between the end tangents.

use crate::mesh::angle_between;
use crate::svg::drawing::Conic;
use kurbo::common::solve_quadratic;
use kurbo::{CubicBez, ParamCurve, ParamCurveDeriv, Vec2};
use std::f64::consts::PI;

/// Parameters closer than this are one split.
const T_MERGE: f64 = 1e-9;
/// Recursion budget of the total-curvature split (each level halves the turn).
const MAX_TURN_DEPTH: u32 = 8;
/// A piece turning at least this much is split (a margin below 180°).
const MAX_TURN: f64 = 0.9 * PI;
/// Samples of the tangent used to measure a piece's total turn.
const TURN_SAMPLES: usize = 32;

/// The pieces of one cubic.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Splits {
    /// Consecutive parameter intervals covering [0, 1].
    pub(super) intervals: Vec<[f64; 2]>,
    /// Cuts at inflections and zero-derivative points.
    pub(super) inflection_splits: usize,
    /// Cuts halving a large turn.
    pub(super) curvature_splits: usize,
}

/// The derivative c′(t)/3 = (1-t)² a + 2t(1-t) b + t² c as `(a, b, c)`.
fn hodograph(c: &CubicBez) -> (Vec2, Vec2, Vec2) {
    (c.p1 - c.p0, c.p2 - c.p1, c.p3 - c.p2)
}

/// Parameters in (0, 1) where det(c′, c″) = 0 or c′ = 0.
pub(super) fn inflections_and_cusps(c: &CubicBez) -> Vec<f64> {
    let mut ts: Vec<f64> = c.inflections().into_iter().collect();
    ts.extend(cusps(c));
    ts.retain(|t| *t > T_MERGE && *t < 1.0 - T_MERGE);
    ts.sort_by(f64::total_cmp);
    ts.dedup_by(|x, y| (*x - *y).abs() < T_MERGE);
    ts
}

/// Zero-derivative points in (0, 1): common roots of both components of c′ (to
/// 1e-9 of the hodograph's size).
pub(super) fn cusps(c: &CubicBez) -> Vec<f64> {
    let mut ts = Vec::new();
    let (a, b, e) = hodograph(c);
    let scale = a.hypot() + b.hypot() + e.hypot();
    for (a, b, e) in [(a.x, b.x, e.x), (a.y, b.y, e.y)] {
        for t in solve_quadratic(a, 2.0 * (b - a), a - 2.0 * b + e) {
            if t > 0.0 && t < 1.0 && c.deriv().eval(t).to_vec2().hypot() <= 1e-9 * scale {
                ts.push(t);
            }
        }
    }
    ts
}

/// The tangent direction at the start of a control polygon: the first control vector that
/// is not negligible (so it is defined at zero-derivative end points too).
pub(super) fn start_tangent(c: &CubicBez) -> Vec2 {
    let scale = (c.p1 - c.p0).hypot() + (c.p2 - c.p1).hypot() + (c.p3 - c.p2).hypot();
    let tiny = 1e-12 * scale;
    for v in [c.p1 - c.p0, c.p2 - c.p0, c.p3 - c.p0] {
        if v.hypot() > tiny {
            return v;
        }
    }
    Vec2::ZERO
}

/// The tangent direction at the end of a control polygon.
pub(super) fn end_tangent(c: &CubicBez) -> Vec2 {
    -start_tangent(&CubicBez::new(c.p3, c.p2, c.p1, c.p0))
}

/// Total turn (radians, ≥ 0) of `c` on `[t0, t1]`, assuming constant-sign curvature there,
/// and the sign of that curvature (+1 counter-clockwise, −1 clockwise, 0 straight).
fn total_turn(c: &CubicBez, t0: f64, t1: f64) -> (f64, f64) {
    let piece = c.subsegment(t0..t1);
    let d = piece.deriv();
    let dd = d.deriv();
    let mut dirs = Vec::with_capacity(TURN_SAMPLES + 1);
    dirs.push(start_tangent(&piece));
    for i in 1..TURN_SAMPLES {
        let v = d.eval(i as f64 / TURN_SAMPLES as f64).to_vec2();
        if v.hypot2() > 0.0 {
            dirs.push(v);
        }
    }
    dirs.push(end_tangent(&piece));
    let mid = 0.5;
    let mut sign = d.eval(mid).to_vec2().cross(dd.eval(mid).to_vec2()).signum();
    let cross_sum: f64 = dirs.windows(2).map(|w| w[0].cross(w[1])).sum();
    if d.eval(mid).to_vec2().cross(dd.eval(mid).to_vec2()) == 0.0 {
        sign = if cross_sum == 0.0 {
            0.0
        } else {
            cross_sum.signum()
        };
    }
    if sign == 0.0 {
        return (0.0, 0.0);
    }
    let mut turn = 0.0;
    for w in dirs.windows(2) {
        let (u, v) = (w[0], w[1]);
        if u.hypot2() == 0.0 || v.hypot2() == 0.0 {
            continue;
        }
        let mut a = (sign * u.cross(v)).atan2(u.dot(v));
        if a < -1e-6 {
            a += 2.0 * PI;
        } else if a < 0.0 {
            a = 0.0;
        }
        turn += a;
    }
    (turn, sign)
}

/// The parameter in (t0, t1) where the tangent bisects the turn of the piece.
fn bisecting_parameter(c: &CubicBez, t0: f64, t1: f64, turn: f64, sign: f64) -> f64 {
    let piece = c.subsegment(t0..t1);
    let d0 = start_tangent(&piece);
    let fallback = 0.5 * (t0 + t1);
    if d0.hypot2() == 0.0 {
        return fallback;
    }
    // Rotate the start tangent by half the turn: the mean of the end tangents when the turn
    // is below 180°, minus that mean above.
    let half = 0.5 * sign * turn;
    let u = d0.normalize();
    let m = Vec2::new(
        u.x * half.cos() - u.y * half.sin(),
        u.x * half.sin() + u.y * half.cos(),
    );
    let (a, b, e) = hodograph(&piece);
    let (ca, cb, ce) = (m.cross(a), m.cross(b), m.cross(e));
    let mut best: Option<f64> = None;
    for s in solve_quadratic(ca, 2.0 * (cb - ca), ca - 2.0 * cb + ce) {
        if s > 1e-6 && s < 1.0 - 1e-6 && piece.deriv().eval(s).to_vec2().dot(m) > 0.0 {
            // Prefer the root closest to the middle (there is one in exact arithmetic).
            if best.is_none_or(|b| (s - 0.5).abs() < (b - 0.5).abs()) {
                best = Some(s);
            }
        }
    }
    best.map_or(fallback, |s| t0 + s * (t1 - t0))
}

fn split_turn(c: &CubicBez, t0: f64, t1: f64, depth: u32, out: &mut Vec<[f64; 2]>, n: &mut usize) {
    let (turn, sign) = total_turn(c, t0, t1);
    if turn >= MAX_TURN && depth < MAX_TURN_DEPTH && t1 - t0 > 4.0 * T_MERGE {
        let tm = bisecting_parameter(c, t0, t1, turn, sign);
        if tm > t0 + T_MERGE && tm < t1 - T_MERGE {
            *n += 1;
            split_turn(c, t0, tm, depth + 1, out, n);
            split_turn(c, tm, t1, depth + 1, out, n);
            return;
        }
    }
    out.push([t0, t1]);
}

/// Split a (non-degenerate, non-straight) cubic into constant-sign-curvature pieces that
/// each turn less than 180°.
pub(super) fn split(c: &CubicBez) -> Splits {
    let cuts = inflections_and_cusps(c);
    let inflection_splits = cuts.len();
    let mut bounds = vec![0.0];
    bounds.extend(cuts);
    bounds.push(1.0);
    let mut intervals = Vec::new();
    let mut curvature_splits = 0;
    for w in bounds.windows(2) {
        split_turn(c, w[0], w[1], 0, &mut intervals, &mut curvature_splits);
    }
    Splits {
        intervals,
        inflection_splits,
        curvature_splits,
    }
}

/// A positive multiple of the conic's derivative at `t`: `Q(t)` of `C′ = 2Q/D²`, with
/// Bernstein coefficients `w(p1 − p0)`, `(p2 − p0)/2`, `w(p2 − p1)`.
fn conic_tangent_coefficients(c: &Conic) -> [Vec2; 3] {
    let (u, v) = (c.p1 - c.p0, c.p2 - c.p1);
    [u * c.w, (u + v) * 0.5, v * c.w]
}

fn conic_tangent(q: &[Vec2; 3], t: f64) -> Vec2 {
    let s = 1.0 - t;
    q[0] * (s * s) + q[1] * (2.0 * s * t) + q[2] * (t * t)
}

/// The parameter in `(t0, t1)` where the conic's tangent bisects its turn there, if found.
fn conic_bisecting_parameter(q: &[Vec2; 3], t0: f64, t1: f64) -> Option<f64> {
    let (d0, d1) = (conic_tangent(q, t0), conic_tangent(q, t1));
    if d0.hypot2() == 0.0 || d1.hypot2() == 0.0 {
        return None;
    }
    // The turn is below 180°: the bisector is the sum of the unit end tangents.
    let m = d0.normalize() + d1.normalize();
    let (a, b, e) = (m.cross(q[0]), m.cross(q[1]), m.cross(q[2]));
    solve_quadratic(a, 2.0 * (b - a), a - 2.0 * b + e)
        .into_iter()
        .filter(|&t| t > t0 && t < t1 && conic_tangent(q, t).dot(m) > 0.0)
        .min_by(|x, y| {
            (x - 0.5 * (t0 + t1))
                .abs()
                .total_cmp(&(y - 0.5 * (t0 + t1)).abs())
        })
}

fn split_conic_turn(
    q: &[Vec2; 3],
    t0: f64,
    t1: f64,
    depth: u32,
    out: &mut Vec<[f64; 2]>,
    n: &mut usize,
) {
    let (d0, d1) = (conic_tangent(q, t0), conic_tangent(q, t1));
    let turn = if d0.hypot2() == 0.0 || d1.hypot2() == 0.0 {
        PI
    } else {
        angle_between(d0, d1)
    };
    if turn >= MAX_TURN && depth < MAX_TURN_DEPTH && t1 - t0 > 4.0 * T_MERGE {
        if let Some(tm) = conic_bisecting_parameter(q, t0, t1) {
            if tm > t0 + T_MERGE && tm < t1 - T_MERGE {
                *n += 1;
                split_conic_turn(q, t0, tm, depth + 1, out, n);
                split_conic_turn(q, tm, t1, depth + 1, out, n);
                return;
            }
        }
    }
    out.push([t0, t1]);
}

/// Split a (non-degenerate, non-straight, positive-weight) conic into pieces that each
/// turn less than [`MAX_TURN`]: at most one cut, where the tangent bisects the turn, for
/// the rare piece of a very eccentric ellipse that turns more (a circle's ≤ 90° pieces
/// are never cut).
pub(super) fn split_conic(c: &Conic) -> Splits {
    let q = conic_tangent_coefficients(c);
    let mut intervals = Vec::new();
    let mut curvature_splits = 0;
    split_conic_turn(&q, 0.0, 1.0, 0, &mut intervals, &mut curvature_splits);
    Splits {
        intervals,
        inflection_splits: 0,
        curvature_splits,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symmetric_s_curve_inflects_at_one_half() {
        let c = CubicBez::new((0.0, 0.0), (1.0, 1.0), (2.0, -1.0), (3.0, 0.0));
        let ts = inflections_and_cusps(&c);
        assert_eq!(ts.len(), 1);
        assert!((ts[0] - 0.5).abs() < 1e-12, "{ts:?}");
    }

    #[test]
    fn asymmetric_s_curve_inflects_at_the_analytic_root() {
        // x(t) = 3t and y(t) = 3t(1-t)² - 6t²(1-t) = 3t - 12t² + 9t³, so
        // det(c′, c″) = 3·y″(t) = 3(-24 + 54t) vanishes at t = 4/9.
        let c = CubicBez::new((0.0, 0.0), (1.0, 1.0), (2.0, -2.0), (3.0, 0.0));
        let ts = inflections_and_cusps(&c);
        assert_eq!(ts.len(), 1);
        assert!((ts[0] - 4.0 / 9.0).abs() < 1e-12, "{ts:?}");
        // y(t) = 3t - 3t² - 2t³ for controls (0,0) (1,1) (2,1) (3,-2): y″ = -6 - 12t < 0 on
        // (0, 1), no inflection.
        let c = CubicBez::new((0.0, 0.0), (1.0, 1.0), (2.0, 1.0), (3.0, -2.0));
        assert!(inflections_and_cusps(&c).is_empty());
    }

    #[test]
    fn cusp_is_a_split_point() {
        let c = CubicBez::new((0.0, 0.0), (2.0, 2.0), (0.0, 2.0), (2.0, 0.0));
        let ts = inflections_and_cusps(&c);
        assert!(ts.iter().any(|t| (t - 0.5).abs() < 1e-9), "{ts:?}");
    }

    #[test]
    fn symmetric_loop_is_halved_at_one_half() {
        // A teardrop loop, symmetric about x = 0, turning well over 180°.
        let c = CubicBez::new((0.0, 0.0), (3.0, 3.0), (-3.0, 3.0), (0.0, 0.0));
        let (turn, _) = total_turn(&c, 0.0, 1.0);
        assert!(turn > PI, "turn {turn}");
        let s = split(&c);
        assert!(
            s.intervals.iter().any(|iv| (iv[1] - 0.5).abs() < 1e-9),
            "{s:?}"
        );
        for iv in &s.intervals {
            assert!(total_turn(&c, iv[0], iv[1]).0 < PI);
        }
    }

    #[test]
    fn quarter_circle_is_not_split() {
        let k = 0.552_284_749_8;
        let c = CubicBez::new((1.0, 0.0), (1.0, k), (k, 1.0), (0.0, 1.0));
        let s = split(&c);
        assert_eq!(s.intervals, vec![[0.0, 1.0]]);
        let (turn, sign) = total_turn(&c, 0.0, 1.0);
        assert!(
            (turn - PI / 2.0).abs() < 1e-9 && sign > 0.0,
            "{turn} {sign}"
        );
    }

    #[test]
    fn conics_split_only_where_they_turn_too_much() {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let quarter = Conic::new((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), w);
        assert_eq!(split_conic(&quarter).intervals, vec![[0.0, 1.0]]);
        // An affine image of a quarter circle turning 170°: one cut, where the tangent
        // bisects the turn.
        let a = kurbo::Affine::skew(80f64.to_radians().tan(), 0.0);
        let c = quarter.transform(a);
        let turn = angle_between(c.p1 - c.p0, c.p2 - c.p1);
        assert!(turn > MAX_TURN, "{}", turn.to_degrees());
        let s = split_conic(&c);
        assert_eq!(s.intervals.len(), 2, "{s:?}");
        assert_eq!(s.curvature_splits, 1);
        let tm = s.intervals[0][1];
        assert_eq!(s.intervals[1][0], tm);
        let (t0, tm_d, t1) = (c.deriv(0.0), c.deriv(tm), c.deriv(1.0));
        let (first, second) = (angle_between(t0, tm_d), angle_between(tm_d, t1));
        assert!((first - second).abs() < 1e-9, "{first} {second}");
        assert!((first + second - turn).abs() < 1e-9);
    }
}
