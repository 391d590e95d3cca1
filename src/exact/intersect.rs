//! Exact intersections of lines and segments.

use super::predicates::{Orientation, orient2d_q};
use super::rational::{PointQ, dyadic};
use kurbo::Point;
use rug::{Integer, Rational};

/// How two closed segments meet.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum SegmentIntersection {
    /// They have no common point.
    Disjoint,
    /// They cross at one point interior to both.
    Crossing(PointQ),
    /// They share exactly one point, an endpoint of at least one of them
    /// (also a degenerate, point-like segment lying on the other).
    Touching(PointQ),
    /// They are collinear and share a piece of positive length, given by its
    /// two ends ordered along the first segment.
    Overlap(PointQ, PointQ),
}

/// The intersection point of the line through `a`, `b` and the line through
/// `c`, `d`; `None` when they are parallel, identical or undefined.
pub(crate) fn line_intersection(a: &PointQ, b: &PointQ, c: &PointQ, d: &PointQ) -> Option<PointQ> {
    let bax = Rational::from(&b.x - &a.x);
    let bay = Rational::from(&b.y - &a.y);
    let dcx = Rational::from(&d.x - &c.x);
    let dcy = Rational::from(&d.y - &c.y);
    let denom = Rational::from(&bax * &dcy) - Rational::from(&bay * &dcx);
    if denom == 0 {
        return None;
    }
    let cax = Rational::from(&c.x - &a.x);
    let cay = Rational::from(&c.y - &a.y);
    let num = cax * &dcy - cay * &dcx;
    let t = num / denom;
    let x = bax * &t + &a.x;
    let y = bay * &t + &a.y;
    Some(PointQ::from_rationals(x, y))
}

/// [`line_intersection`] of the lines through `f64` points, by integer
/// arithmetic: every coordinate is an integer times a power of two, so after
/// scaling all eight by the smallest such power the formula needs integer
/// products and one exact division per coordinate. The rational version
/// reduces every one of its dozen intermediate results by a gcd; the BSP
/// cuts with lines through input points only (hundreds of thousands of
/// crossings on a large input). The same point (rationals are kept reduced).
pub(crate) fn line_intersection_f64(a: Point, b: Point, c: Point, d: Point) -> Option<PointQ> {
    let (parts, scale) = scaled_parts([a.x, a.y, b.x, b.y, c.x, c.y, d.x, d.y]);
    if let Some(words) = in_words(&parts, scale) {
        return line_intersection_words(words, scale);
    }
    let [ax, ay, bx, by, cx, cy, dx, dy] =
        parts.map(|(m, e)| Integer::from(m) << u32::try_from(e - scale).unwrap_or(0));
    let (bax, bay) = (Integer::from(&bx - &ax), Integer::from(&by - &ay));
    let (dcx, dcy) = (dx - &cx, dy - &cy);
    let denom = Integer::from(&bax * &dcy) - Integer::from(&bay * &dcx);
    if denom == 0 {
        return None;
    }
    let num = (cx - &ax) * &dcy - (cy - &ay) * &dcx;
    // a + (b - a) · num / denom, scaled back.
    let coordinate = |a: Integer, ba: Integer| {
        let mut r = Rational::from((a * &denom + ba * &num, denom.clone()));
        r <<= scale;
        r
    };
    Some(PointQ::from_rationals(
        coordinate(ax, bax),
        coordinate(ay, bay),
    ))
}

/// The mantissas and exponents of eight coordinates ([`dyadic`]), and the
/// smallest exponent of a non-zero one (0 if all are zero): the scale of
/// [`line_intersection_f64`]'s integers.
fn scaled_parts(c: [f64; 8]) -> ([(i64, i32); 8], i32) {
    let parts = c.map(dyadic);
    let scale = parts
        .iter()
        .filter(|&&(m, _)| m != 0)
        .map(|&(_, e)| e)
        .min()
        .unwrap_or(0);
    (parts, scale)
}

/// The eight scaled integers of [`line_intersection_f64`] as `i64`, when each
/// is below 2^62 in magnitude (the points of a drawing lie within a few
/// binades of each other: 53-bit mantissas, shifts of a few bits); `None`
/// when one is not.
fn in_words(parts: &[(i64, i32); 8], scale: i32) -> Option<[i64; 8]> {
    let mut words = [0i64; 8];
    for (w, &(m, e)) in words.iter_mut().zip(parts) {
        if m == 0 {
            continue;
        }
        let shift = u32::try_from(e - scale).ok()?;
        let bits = 64 - m.unsigned_abs().leading_zeros();
        if bits + shift > 62 {
            return None;
        }
        *w = m << shift;
    }
    Some(words)
}

/// [`line_intersection_f64`] with its integers in machine words
/// ([`in_words`]): differences below 2^63, the two determinants below 2^127
/// in `i128`; only the coordinates' numerators (190 bits) and the
/// denominator are GMP integers. The general version's dozen GMP
/// temporaries, each an allocation, are most of its time, and the BSP may
/// compute hundreds of thousands of crossings. The same point.
fn line_intersection_words(words: [i64; 8], scale: i32) -> Option<PointQ> {
    let [ax, ay, bx, by, cx, cy, dx, dy] = words;
    // |a|, |b| < 2^62: no difference overflows.
    let (bax, bay, dcx, dcy, cax, cay) = (bx - ax, by - ay, dx - cx, dy - cy, cx - ax, cy - ay);
    let wide = |p: i64, q: i64| i128::from(p) * i128::from(q);
    // Products below 2^126 each: no difference of two overflows.
    let denom = wide(bax, dcy) - wide(bay, dcx);
    if denom == 0 {
        return None;
    }
    let num = wide(cax, dcy) - wide(cay, dcx);
    let (denom, num) = (Integer::from(denom), Integer::from(num));
    // a + (b - a) · num / denom, scaled back.
    let coordinate = |a: i64, ba: i64, den: Integer| {
        let mut n = Integer::from(&denom * a);
        n += Integer::from(&num * ba);
        let mut r = Rational::from((n, den));
        r <<= scale;
        r
    };
    let x = coordinate(ax, bax, denom.clone());
    let y = coordinate(ay, bay, denom.clone());
    Some(PointQ::from_rationals(x, y))
}

/// `p · (b - a)`, exactly: a monotone parameter along the direction `a → b`.
fn along(p: &PointQ, a: &PointQ, b: &PointQ) -> Rational {
    let dx = Rational::from(&b.x - &a.x);
    let dy = Rational::from(&b.y - &a.y);
    dx * &p.x + dy * &p.y
}

/// Whether `p` lies on the closed segment `a b` (which may be a point).
fn on_segment(p: &PointQ, a: &PointQ, b: &PointQ) -> bool {
    if a == b {
        return p == a;
    }
    if orient2d_q(a, b, p) != Orientation::Collinear {
        return false;
    }
    let (ka, kb, kp) = (along(a, a, b), along(b, a, b), along(p, a, b));
    ka <= kp && kp <= kb
}

/// How the closed segments `a b` and `c d` meet, exactly.
pub(crate) fn segment_intersection(
    a: &PointQ,
    b: &PointQ,
    c: &PointQ,
    d: &PointQ,
) -> SegmentIntersection {
    if a == b || c == d {
        let (p, (s, t)) = if a == b { (a, (c, d)) } else { (c, (a, b)) };
        return if on_segment(p, s, t) {
            SegmentIntersection::Touching(p.clone())
        } else {
            SegmentIntersection::Disjoint
        };
    }
    let o1 = orient2d_q(a, b, c);
    let o2 = orient2d_q(a, b, d);
    if o1 == Orientation::Collinear && o2 == Orientation::Collinear {
        // Collinear: intersect the parameter ranges along a → b.
        let (ka, kb) = (along(a, a, b), along(b, a, b));
        let (kc, kd) = (along(c, a, b), along(d, a, b));
        let (lo_cd, hi_cd) = if kc <= kd {
            ((kc, c), (kd, d))
        } else {
            ((kd, d), (kc, c))
        };
        let (lo, lo_p) = if lo_cd.0 > ka {
            (lo_cd.0, lo_cd.1)
        } else {
            (ka, a)
        };
        let (hi, hi_p) = if hi_cd.0 < kb {
            (hi_cd.0, hi_cd.1)
        } else {
            (kb, b)
        };
        return match lo.cmp(&hi) {
            std::cmp::Ordering::Less => SegmentIntersection::Overlap(lo_p.clone(), hi_p.clone()),
            std::cmp::Ordering::Equal => SegmentIntersection::Touching(lo_p.clone()),
            std::cmp::Ordering::Greater => SegmentIntersection::Disjoint,
        };
    }
    if o1 == o2 {
        return SegmentIntersection::Disjoint;
    }
    let o3 = orient2d_q(c, d, a);
    let o4 = orient2d_q(c, d, b);
    if o3 == o4 {
        // Both non-collinear (else the four points would be collinear).
        return SegmentIntersection::Disjoint;
    }
    for (o, p) in [(o1, c), (o2, d), (o3, a), (o4, b)] {
        if o == Orientation::Collinear {
            return SegmentIntersection::Touching(p.clone());
        }
    }
    let x = line_intersection(a, b, c, d).expect("internal: crossing segments are not parallel");
    SegmentIntersection::Crossing(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn q(x: f64, y: f64) -> PointQ {
        PointQ::from_point(Point::new(x, y))
    }
    use SegmentIntersection as SI;

    #[test]
    fn proper_crossing() {
        let r = segment_intersection(&q(0.0, 0.0), &q(3.0, 3.0), &q(0.0, 1.0), &q(1.0, 0.0));
        assert_eq!(r, SI::Crossing(q(0.5, 0.5)));
        // An exact non-f64 crossing: x = 1/3.
        let r = segment_intersection(&q(0.0, 0.0), &q(1.0, 0.0), &q(0.0, -1.0), &q(1.0, 2.0));
        let SI::Crossing(x) = r else { panic!("{r:?}") };
        assert!(!x.is_f64());
        assert_eq!(x, q(0.0, 0.0).lerp_ratio(&q(1.0, 0.0), 1.0, 3.0));
    }

    #[test]
    fn touching_cases() {
        // T-junction.
        let r = segment_intersection(&q(0.0, 0.0), &q(2.0, 0.0), &q(1.0, 0.0), &q(1.0, 5.0));
        assert_eq!(r, SI::Touching(q(1.0, 0.0)));
        // Shared endpoint.
        let r = segment_intersection(&q(0.0, 0.0), &q(2.0, 0.0), &q(2.0, 0.0), &q(3.0, 5.0));
        assert_eq!(r, SI::Touching(q(2.0, 0.0)));
        // Collinear, end to end.
        let r = segment_intersection(&q(0.0, 0.0), &q(2.0, 0.0), &q(2.0, 0.0), &q(3.0, 0.0));
        assert_eq!(r, SI::Touching(q(2.0, 0.0)));
        // Degenerate segment on the other.
        let r = segment_intersection(&q(1.0, 0.0), &q(1.0, 0.0), &q(0.0, 0.0), &q(2.0, 0.0));
        assert_eq!(r, SI::Touching(q(1.0, 0.0)));
        let r = segment_intersection(&q(1.0, 1.0), &q(1.0, 1.0), &q(0.0, 0.0), &q(2.0, 0.0));
        assert_eq!(r, SI::Disjoint);
    }

    #[test]
    fn overlap_and_disjoint() {
        let r = segment_intersection(&q(0.0, 0.0), &q(4.0, 4.0), &q(5.0, 5.0), &q(1.0, 1.0));
        assert_eq!(r, SI::Overlap(q(1.0, 1.0), q(4.0, 4.0)));
        let r = segment_intersection(&q(4.0, 4.0), &q(0.0, 0.0), &q(1.0, 1.0), &q(2.0, 2.0));
        assert_eq!(r, SI::Overlap(q(2.0, 2.0), q(1.0, 1.0)));
        let r = segment_intersection(&q(0.0, 0.0), &q(1.0, 1.0), &q(2.0, 2.0), &q(3.0, 3.0));
        assert_eq!(r, SI::Disjoint);
        // Parallel, not collinear.
        let r = segment_intersection(
            &q(0.0, 0.0),
            &q(1.0, 1.0),
            &q(0.0, 1e-300),
            &q(1.0, 1.0 + f64::EPSILON),
        );
        assert_eq!(r, SI::Disjoint);
        // Nearly parallel, crossing far from the origin of either segment.
        let r = segment_intersection(
            &q(0.0, 0.0),
            &q(1.0, 1.0),
            &q(0.0, 1e-17),
            &q(1.0, 1.0 - 1e-16),
        );
        assert!(matches!(r, SI::Crossing(_)), "{r:?}");
    }

    fn pt() -> impl Strategy<Value = PointQ> {
        // Small integer grid: lots of collinear / touching / overlapping cases.
        (-3i32..4, -3i32..4).prop_map(|(x, y)| q(f64::from(x), f64::from(y)))
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 1024, failure_persistence: None, ..ProptestConfig::default() })]

        /// Every reported point lies on both segments; the answer is symmetric.
        #[test]
        fn intersection_is_consistent(a in pt(), b in pt(), c in pt(), d in pt()) {
            let r = segment_intersection(&a, &b, &c, &d);
            let s = segment_intersection(&c, &d, &a, &b);
            match (&r, &s) {
                (SI::Disjoint, SI::Disjoint) => {
                    // Sampled check: no lattice point of 1/4 step on both.
                    for i in 0..=8 {
                        let x = a.lerp_ratio(&b, f64::from(i), 8.0);
                        prop_assert!(!(on_segment(&x, &a, &b) && on_segment(&x, &c, &d)));
                    }
                }
                (SI::Crossing(x), SI::Crossing(y)) | (SI::Touching(x), SI::Touching(y)) => {
                    prop_assert_eq!(x, y);
                    prop_assert!(on_segment(x, &a, &b) && on_segment(x, &c, &d));
                }
                (SI::Overlap(x0, x1), SI::Overlap(y0, y1)) => {
                    prop_assert!(x0 != x1);
                    prop_assert!((x0 == y0 && x1 == y1) || (x0 == y1 && x1 == y0));
                    for x in [x0, x1] {
                        prop_assert!(on_segment(x, &a, &b) && on_segment(x, &c, &d));
                    }
                }
                _ => prop_assert!(false, "asymmetric: {:?} vs {:?}", r, s),
            }
        }
    }

    /// Coordinates of every kind: small integers (parallel, collinear and
    /// coincident lines), fractions, and far apart magnitudes down to
    /// subnormals, either sign.
    fn coordinate() -> impl Strategy<Value = f64> {
        prop_oneof![
            (-3i32..4).prop_map(f64::from),
            -1e3f64..1e3,
            (-1e3f64..1e3, -320i32..300).prop_map(|(m, e)| m * 2f64.powi(e)),
            Just(5e-324),
            Just(-2.5e-308),
            Just(1.7e308),
        ]
    }

    #[test]
    fn dyadic_parts() {
        for v in [1.0, -1.0, 0.75, 3.0e-5, -1e300, 5e-324, 2.2e-308, f64::MAX] {
            let (m, e) = dyadic(v);
            let mut back = Rational::from(m);
            back <<= e;
            assert_eq!(back, Rational::from_f64(v).unwrap(), "{v}");
        }
        assert_eq!(dyadic(0.0).0, 0);
        assert_eq!(dyadic(-0.0).0, 0);
    }

    /// The points `(c[0], c[1])` .. `(c[6], c[7])` and the crossing of the
    /// line through the first two with the line through the last two, by the
    /// rational version.
    fn four_points_and_crossing(c: [f64; 8]) -> ([Point; 4], Option<PointQ>) {
        let pts: [Point; 4] = std::array::from_fn(|i| Point::new(c[2 * i], c[2 * i + 1]));
        let [a, b, p, r] = pts.map(PointQ::from_point);
        (pts, line_intersection(&a, &b, &p, &r))
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2048, failure_persistence: None, ..ProptestConfig::default() })]

        /// The integer version finds the rational version's point, or its
        /// `None`, on lines of every kind.
        #[test]
        fn integer_line_intersection_is_the_rational_one(
            c in proptest::array::uniform8(coordinate())
        ) {
            let ([a, b, p, r], exact) = four_points_and_crossing(c);
            prop_assert_eq!(line_intersection_f64(a, b, p, r), exact);
        }

        /// Points within a few binades of each other, with full mantissas
        /// and zeros: the machine-word version runs ([`in_words`]) up to
        /// its 62-bit bound and finds the rational version's point.
        #[test]
        fn word_line_intersection_is_the_rational_one(
            m in proptest::array::uniform8(prop_oneof![
                Just(0i64),
                (-3i64..4),
                -(1i64 << 53) + 1..(1i64 << 53),
            ]),
            e in proptest::array::uniform8(-62i32..-51),
        ) {
            let c: [f64; 8] = std::array::from_fn(|i| m[i] as f64 * 2f64.powi(e[i]));
            let (parts, scale) = scaled_parts(c);
            let ([a, b, p, r], exact) = four_points_and_crossing(c);
            // Spreads up to nine bits on 53-bit mantissas fit, wider may not.
            let words = in_words(&parts, scale);
            let too_wide = parts.iter().any(|&(m, e)| {
                m != 0 && (64 - m.unsigned_abs().leading_zeros()) + (e - scale).unsigned_abs() > 62
            });
            prop_assert_eq!(words.is_none(), too_wide);
            if let Some(w) = words {
                prop_assert_eq!(line_intersection_words(w, scale), exact.clone());
            }
            prop_assert_eq!(line_intersection_f64(a, b, p, r), exact);
        }
    }

    /// The words' bound: a spread that would pass 2^62 takes the general way.
    #[test]
    fn words_hold_up_to_62_bits() {
        let full = (1i64 << 53) - 1;
        let mut parts = [(full, 0); 8];
        parts[3] = (full, 9);
        assert!(in_words(&parts, 0).is_some());
        parts[3] = (full, 10);
        assert!(in_words(&parts, 0).is_none());
        parts[3] = (-1, 61);
        assert!(in_words(&parts, 0).is_some());
        parts[3] = (-1, 62);
        assert!(in_words(&parts, 0).is_none());
        // Extreme words: the determinants' bounds hold.
        let big = (1i64 << 62) - 1;
        let w = [big, -big, -big, big, -big, -big, big, big];
        let q = |x: i64, y: i64| PointQ::from_rationals(Rational::from(x), Rational::from(y));
        let exact = line_intersection(
            &q(w[0], w[1]),
            &q(w[2], w[3]),
            &q(w[4], w[5]),
            &q(w[6], w[7]),
        );
        assert_eq!(line_intersection_words(w, 0), exact);
    }
}
