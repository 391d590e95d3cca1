//! The orientation predicate, filtered then exact.

use super::rational::{Interval, PointQ};
use kurbo::Point;
use rug::{Integer, Rational};
use std::cmp::Ordering;

/// The orientation of an ordered triple of points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Orientation {
    /// Counter-clockwise: `c` is strictly left of the directed line `a → b` (positive area).
    CounterClockwise,
    /// Clockwise: `c` is strictly right of `a → b` (negative area).
    Clockwise,
    /// The three points are collinear (zero area; includes coincident points).
    Collinear,
}

impl Orientation {
    fn from_ordering(o: Ordering) -> Self {
        match o {
            Ordering::Greater => Orientation::CounterClockwise,
            Ordering::Less => Orientation::Clockwise,
            Ordering::Equal => Orientation::Collinear,
        }
    }

    /// The orientation of the triple with two points swapped.
    pub fn reversed(self) -> Self {
        match self {
            Orientation::CounterClockwise => Orientation::Clockwise,
            Orientation::Clockwise => Orientation::CounterClockwise,
            Orientation::Collinear => Orientation::Collinear,
        }
    }

    /// `+1`, `-1` or `0`: the sign of twice the signed area.
    pub fn sign(self) -> i32 {
        match self {
            Orientation::CounterClockwise => 1,
            Orientation::Clockwise => -1,
            Orientation::Collinear => 0,
        }
    }
}

/// Shewchuk's predicate in the `robust` crate is exact while no intermediate
/// overflows or underflows: spade uses exponents in [-142, 201]; we stay in it.
fn in_shewchuk_range(v: f64) -> bool {
    const MIN: f64 = 1.793_662_034_335_766e-43; // 2^-142
    const MAX: f64 = 3.213_876_088_517_980_6e60; // 2^201
    v == 0.0 || (v.abs() >= MIN && v.abs() <= MAX)
}

/// Exact orientation of three `f64` points.
///
/// Points must be finite. Within the exponent range 2^-142..2^201 this is
/// Shewchuk's adaptive predicate; outside it, exact rationals.
pub fn orient2d(a: Point, b: Point, c: Point) -> Orientation {
    let all_in = [a.x, a.y, b.x, b.y, c.x, c.y]
        .iter()
        .all(|&v| in_shewchuk_range(v));
    if all_in {
        let d = robust::orient2d(
            robust::Coord { x: a.x, y: a.y },
            robust::Coord { x: b.x, y: b.y },
            robust::Coord { x: c.x, y: c.y },
        );
        Orientation::from_ordering(d.partial_cmp(&0.0).unwrap_or(Ordering::Equal))
    } else {
        orient2d_q_exact(
            &PointQ::from_point(a),
            &PointQ::from_point(b),
            &PointQ::from_point(c),
        )
    }
}

/// The interval filter alone: `Some(orientation)` when outward-rounded
/// interval arithmetic over enclosures of the coordinates decides the sign,
/// `None` when only exact arithmetic can.
pub fn orient2d_q_filter(a: &PointQ, b: &PointQ, c: &PointQ) -> Option<Orientation> {
    orient2d_enclosures([a.ix, a.iy], [b.ix, b.iy], [c.ix, c.iy])
}

/// The interval filter on enclosures of the three points' coordinates.
fn orient2d_enclosures(
    [ax, ay]: [Interval; 2],
    [bx, by]: [Interval; 2],
    [cx, cy]: [Interval; 2],
) -> Option<Orientation> {
    let det = bx.sub(ax).mul(cy.sub(ay)).sub(by.sub(ay).mul(cx.sub(ax)));
    det.strict_sign().map(Orientation::from_ordering)
}

/// The orientation computed in rationals, without any filter.
///
/// In integers, with every fraction left unreduced: with `p - q` written
/// `num(p, q) / (p.den · q.den)`, the determinant
/// `(b.x - a.x)(c.y - a.y) - (b.y - a.y)(c.x - a.x)` times the positive
/// `a.x.den · a.y.den · b.x.den · b.y.den · c.x.den · c.y.den` is `l - r`
/// with `l = num(b.x, a.x) · num(c.y, a.y) · b.y.den · c.x.den` and
/// `r = num(b.y, a.y) · num(c.x, a.x) · b.x.den · c.y.den`.
/// Rational arithmetic would reduce every intermediate by a gcd, most of the
/// predicate's time where it is called most: the BSP's tagging tests every
/// vertex exactly on its segment, where the filter cannot decide.
pub fn orient2d_q_exact(a: &PointQ, b: &PointQ, c: &PointQ) -> Orientation {
    // num(p, q) = p.num · q.den - q.num · p.den
    fn num(p: &Rational, q: &Rational) -> Integer {
        Integer::from(p.numer() * q.denom()) - Integer::from(q.numer() * p.denom())
    }
    let l = num(&b.x, &a.x) * num(&c.y, &a.y) * Integer::from(b.y.denom() * c.x.denom());
    let r = num(&b.y, &a.y) * num(&c.x, &a.x) * Integer::from(b.x.denom() * c.y.denom());
    Orientation::from_ordering(l.cmp(&r))
}

/// Exact orientation of three rational points: `f64` points go to
/// [`orient2d`], others through the interval filter, then rationals.
pub fn orient2d_q(a: &PointQ, b: &PointQ, c: &PointQ) -> Orientation {
    if let (Some(pa), Some(pb), Some(pc)) = (a.as_f64(), b.as_f64(), c.as_f64()) {
        return orient2d(pa, pb, pc);
    }
    orient2d_q_filter(a, b, c).unwrap_or_else(|| orient2d_q_exact(a, b, c))
}

/// A point given to [`orient2d_mixed`]: an `f64` point, or a rational one.
#[derive(Clone, Copy, Debug)]
pub(crate) enum PointRef<'a> {
    F64(Point),
    Q(&'a PointQ),
}

impl<'a> PointRef<'a> {
    /// The point as a rational (made for an `f64` point).
    fn to_q(self) -> std::borrow::Cow<'a, PointQ> {
        match self {
            PointRef::F64(p) => std::borrow::Cow::Owned(PointQ::from_point(p)),
            PointRef::Q(q) => std::borrow::Cow::Borrowed(q),
        }
    }

    /// Enclosures of the coordinates.
    fn enclosure(self) -> [Interval; 2] {
        match self {
            PointRef::F64(p) => [Interval::point(p.x), Interval::point(p.y)],
            PointRef::Q(q) => [q.ix, q.iy],
        }
    }
}

/// Exact orientation of three points, each an `f64` point or a rational one,
/// as [`orient2d_q`] decides it, without making rationals of the `f64`
/// points unless the interval filter cannot decide (the BSP's rounding asks
/// it millions of times with an `f64` candidate beside rational neighbours).
pub(crate) fn orient2d_mixed(a: PointRef<'_>, b: PointRef<'_>, c: PointRef<'_>) -> Orientation {
    if let (PointRef::F64(pa), PointRef::F64(pb), PointRef::F64(pc)) = (a, b, c) {
        return orient2d(pa, pb, pc);
    }
    orient2d_enclosures(a.enclosure(), b.enclosure(), c.enclosure()).unwrap_or_else(|| {
        let (qa, qb, qc) = (a.to_q(), b.to_q(), c.to_q());
        orient2d_q_exact(&qa, &qb, &qc)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn p(x: f64, y: f64) -> Point {
        Point::new(x, y)
    }
    fn q(x: f64, y: f64) -> PointQ {
        PointQ::from_point(p(x, y))
    }
    /// Plain rational evaluation, independent of the kernel's code path.
    fn reference(a: &PointQ, b: &PointQ, c: &PointQ) -> i32 {
        let det = (b.x.clone() - &a.x) * (c.y.clone() - &a.y)
            - (b.y.clone() - &a.y) * (c.x.clone() - &a.x);
        det.cmp0() as i32
    }

    #[test]
    fn basic_orientations() {
        let (a, b) = (p(0.0, 0.0), p(1.0, 0.0));
        assert_eq!(orient2d(a, b, p(0.0, 1.0)), Orientation::CounterClockwise);
        assert_eq!(orient2d(a, b, p(0.0, -1.0)), Orientation::Clockwise);
        assert_eq!(orient2d(a, b, p(7.0, 0.0)), Orientation::Collinear);
        assert_eq!(orient2d(a, a, a), Orientation::Collinear);
    }

    #[test]
    fn nearly_collinear_f64() {
        // Points on y = x perturbed by one ulp: the naive float determinant lies.
        let a = p(0.5, 0.5);
        let b = p(12.0, 12.0);
        let mut x = 0.5;
        for _ in 0..256 {
            x = super::super::rational::next_up(x);
            for c in [p(x, 0.5), p(0.5, x), p(x, x), p(24.0, x + 23.5)] {
                let want = reference(&q(a.x, a.y), &q(b.x, b.y), &q(c.x, c.y));
                assert_eq!(orient2d(a, b, c).sign(), want, "{c:?}");
            }
        }
    }

    #[test]
    fn rational_collinear_and_nearly() {
        // Rational points on the line y = x/3 and one-ulp-sized perturbations.
        let o = q(0.0, 0.0);
        let t = q(3.0, 1.0);
        let third = o.lerp_ratio(&t, 1.0, 3.0);
        let fifth = o.lerp_ratio(&t, 2.0, 7.0);
        assert_eq!(orient2d_q(&o, &third, &fifth), Orientation::Collinear);
        assert_eq!(orient2d_q_filter(&o, &third, &fifth), None);
        let up = q(1.0, 1.0 / 3.0); // 1/3 rounded: off the line by < 1 ulp
        let want = reference(&o, &t, &up);
        assert_ne!(want, 0);
        assert_eq!(orient2d_q(&o, &third, &up).sign(), want);
        assert_eq!(orient2d_q(&fifth, &third, &up).sign(), want);
        assert_eq!(orient2d_q(&third, &fifth, &up).sign(), -want);
    }

    #[test]
    fn out_of_shewchuk_range_is_exact() {
        let a = p(1e-300, 1e-300);
        let b = p(3e-300, 3e-300);
        let c = p(2e-300, 2e-300);
        assert_eq!(
            orient2d(a, b, c).sign(),
            reference(&q(a.x, a.y), &q(b.x, b.y), &q(c.x, c.y))
        );
        let c2 = p(2e-300, super::super::rational::next_up(2e-300));
        assert_eq!(orient2d(a, b, c2), Orientation::CounterClockwise);
        let big = p(1e250, -1e250);
        let c3 = p(-1e250, 1e250 * (1.0 + f64::EPSILON));
        assert_eq!(
            orient2d(a, big, c3).sign(),
            reference(&q(a.x, a.y), &q(big.x, big.y), &q(c3.x, c3.y))
        );
    }

    /// Exhaustive: every triple from a small grid of awkward values, f64 and rational.
    #[test]
    fn exhaustive_small_grid() {
        let vals = [0.0, 1.0, -1.0, 0.1, 0.3, 1e-9, 1e9, 1.0 + f64::EPSILON];
        let pts: Vec<PointQ> = vals
            .iter()
            .flat_map(|&x| vals.iter().map(move |&y| q(x, y)))
            .collect();
        // Add rational points: midpoints and thirds of a few pairs.
        let mut all = pts.clone();
        for w in pts.windows(7).step_by(5) {
            all.push(w[0].lerp_ratio(&w[6], 1.0, 3.0));
        }
        let n = all.len();
        let mut checked = 0;
        for i in (0..n).step_by(3) {
            for j in (0..n).step_by(2) {
                for k in 0..n {
                    let (a, b, c) = (&all[i], &all[j], &all[k]);
                    let want = reference(a, b, c);
                    assert_eq!(orient2d_q(a, b, c).sign(), want);
                    if let Some(o) = orient2d_q_filter(a, b, c) {
                        assert_eq!(o.sign(), want);
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked > 10_000);
    }

    /// Near-degenerate generator: points on a line plus tiny perturbations, or rational points on it.
    fn near_line() -> impl Strategy<Value = (PointQ, PointQ, PointQ)> {
        (
            -1e3..1e3f64,
            -1e3..1e3f64,
            -1e3..1e3f64,
            -1e3..1e3f64,
            -4i32..4,
            0u8..3,
            1u32..50,
            1u32..50,
        )
            .prop_map(|(ax, ay, bx, by, ulps, kind, n, d)| {
                let a = q(ax, ay);
                let b = q(bx, by);
                let c = a.lerp_ratio(&b, f64::from(n), f64::from(d));
                let c = match kind {
                    0 => c,
                    1 => {
                        let (cp, _) = c.to_f64();
                        let mut y = cp.y;
                        for _ in 0..ulps.unsigned_abs() {
                            y = if ulps > 0 {
                                super::super::rational::next_up(y)
                            } else {
                                super::super::rational::next_down(y)
                            };
                        }
                        q(cp.x, y)
                    }
                    _ => PointQ::barycentre(&[a.clone(), b.clone(), c]).expect("non-empty"),
                };
                (a, b, c)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn filter_agrees_with_exact((a, b, c) in near_line()) {
            let exact = orient2d_q_exact(&a, &b, &c);
            prop_assert_eq!(exact.sign(), reference(&a, &b, &c));
            if let Some(f) = orient2d_q_filter(&a, &b, &c) {
                prop_assert_eq!(f, exact);
            }
            prop_assert_eq!(orient2d_q(&a, &b, &c), exact);
        }

        /// Each point given as `f64` where it is one, else as a rational:
        /// the same orientation as the rational predicate.
        #[test]
        fn mixed_agrees_with_exact((a, b, c) in near_line(), which in 0u8..8) {
            let exact = orient2d_q_exact(&a, &b, &c);
            fn r(q: &PointQ, as_f64: bool) -> PointRef<'_> {
                match q.as_f64() {
                    Some(p) if as_f64 => PointRef::F64(p),
                    _ => PointRef::Q(q),
                }
            }
            let (ra, rb, rc) = (r(&a, which & 1 != 0), r(&b, which & 2 != 0), r(&c, which & 4 != 0));
            prop_assert_eq!(orient2d_mixed(ra, rb, rc), exact);
            prop_assert_eq!(orient2d_mixed(rb, ra, rc), exact.reversed());
        }

        /// Three rational points with unrelated denominators, all on one line
        /// (the points at ratios n/d of the way between two `f64` points) or
        /// one of them moved off it by a rational amount: the unreduced
        /// integer determinant decides as the reduced rational one does.
        #[test]
        fn exact_agrees_with_reference_on_rational_triples(
            (ax, ay, bx, by) in (-1e3..1e3f64, -1e3..1e3f64, -1e3..1e3f64, -1e3..1e3f64),
            ratios in prop::array::uniform3((-60i32..60, 1u32..60)),
            off in (0u8..3, -3i32..4, 1u32..97),
        ) {
            let (p0, p1) = (q(ax, ay), q(bx, by));
            let mut pts: Vec<PointQ> = ratios
                .iter()
                .map(|&(n, d)| p0.lerp_ratio(&p1, f64::from(n), f64::from(d)))
                .collect();
            let (which, num, den) = off;
            if num != 0 {
                let delta = Rational::from((num, den)) / Rational::from(1u32 << 20);
                let i = usize::from(which);
                let y = Rational::from(&pts[i].y + &delta);
                pts[i] = PointQ::from_rationals(pts[i].x.clone(), y);
            }
            let (a, b, c) = (&pts[0], &pts[1], &pts[2]);
            prop_assert_eq!(orient2d_q_exact(a, b, c).sign(), reference(a, b, c));
            prop_assert_eq!(orient2d_q_exact(b, a, c).sign(), -reference(a, b, c));
        }

        #[test]
        fn swap_flips_cyclic_keeps((a, b, c) in near_line()) {
            let o = orient2d_q(&a, &b, &c);
            prop_assert_eq!(orient2d_q(&b, &a, &c), o.reversed());
            prop_assert_eq!(orient2d_q(&a, &c, &b), o.reversed());
            prop_assert_eq!(orient2d_q(&b, &c, &a), o);
            prop_assert_eq!(orient2d_q(&c, &a, &b), o);
        }

        #[test]
        fn f64_predicate_matches_rational(ax in -1e9..1e9f64, ay in -1e9..1e9f64, bx in -1e-9..1e-9f64, by in -1e-9..1e-9f64, cx in -1.0..1.0f64, cy in -1.0..1.0f64) {
            let (a, b, c) = (p(ax, ay), p(bx, by), p(cx, cy));
            let want = reference(&q(ax, ay), &q(bx, by), &q(cx, cy));
            prop_assert_eq!(orient2d(a, b, c).sign(), want);
            prop_assert_eq!(orient2d(c, b, a).sign(), -want);
        }
    }
}

/// Whether `c` lies within `tol` of the line through `a` and `b` (`a ≠ b`),
/// decided exactly: `orient(a, b, c)² ≤ tol² · |b − a|²` in rationals (the
/// orientation determinant is twice the triangle's area, `|b − a|` times the
/// distance). `tol` must be finite and non-negative.
pub(crate) fn near_line(a: Point, b: Point, c: Point, tol: f64) -> bool {
    let q = |v: f64| Rational::from_f64(v).expect("internal: coordinates are finite");
    let (ax, ay, bx, by, cx, cy) = (q(a.x), q(a.y), q(b.x), q(b.y), q(c.x), q(c.y));
    let (ux, uy) = (Rational::from(&bx - &ax), Rational::from(&by - &ay));
    let (vx, vy) = (Rational::from(&cx - &ax), Rational::from(&cy - &ay));
    let det = Rational::from(&ux * &vy) - Rational::from(&uy * &vx);
    let len2 = Rational::from(&ux * &ux) + Rational::from(&uy * &uy);
    let t = q(tol);
    let lhs = Rational::from(&det * &det);
    let rhs = Rational::from(&t * &t) * len2;
    lhs <= rhs
}

/// Whether `|a − b| ≤ tol`, decided exactly. `tol` must be finite and
/// non-negative.
pub(crate) fn within(a: Point, b: Point, tol: f64) -> bool {
    if a == b {
        return true;
    }
    let q = |v: f64| Rational::from_f64(v).expect("internal: coordinates are finite");
    let dx = q(a.x) - q(b.x);
    let dy = q(a.y) - q(b.y);
    let t = q(tol);
    Rational::from(&dx * &dx) + Rational::from(&dy * &dy) <= Rational::from(&t * &t)
}

#[cfg(test)]
mod near_tests {
    use super::*;

    #[test]
    fn near_line_decides_at_the_tolerance_exactly() {
        let (a, b) = (Point::new(0.0, 0.0), Point::new(4.0, 0.0));
        assert!(near_line(a, b, Point::new(2.0, 0.5), 0.5));
        assert!(!near_line(a, b, Point::new(2.0, 0.5f64.next_up()), 0.5));
        // beyond the segment's ends still measures to the infinite line
        assert!(near_line(a, b, Point::new(-7.0, -0.25), 0.5));
        // a slanted line: (1, 1) direction, point at distance sqrt(2)/2 exactly
        let (c, d) = (Point::new(0.0, 0.0), Point::new(3.0, 3.0));
        assert!(near_line(
            c,
            d,
            Point::new(1.0, 0.0),
            0.5f64.sqrt().next_up()
        ));
        assert!(!near_line(
            c,
            d,
            Point::new(1.0, 0.0),
            0.5f64.sqrt().next_down()
        ));
    }

    #[test]
    fn within_is_the_euclidean_distance_exactly() {
        let (a, b) = (Point::new(1.0, 1.0), Point::new(4.0, 5.0));
        assert!(within(a, b, 5.0));
        assert!(!within(a, b, 5.0f64.next_down()));
        assert!(within(a, a, 0.0));
    }
}
