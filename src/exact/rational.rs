//! Rational points with cached `f64` enclosures.

use kurbo::Point;
use rug::{Integer, Rational};
use std::cmp::Ordering;
use std::hash::{Hash, Hasher};

/// The next `f64` toward +∞ (`f64::next_up`, spelled out for the crate's MSRV).
pub(super) fn next_up(x: f64) -> f64 {
    if x.is_nan() || x == f64::INFINITY {
        return x;
    }
    if x == 0.0 {
        return f64::from_bits(1);
    }
    let bits = x.to_bits();
    if x > 0.0 {
        f64::from_bits(bits + 1)
    } else {
        f64::from_bits(bits - 1)
    }
}

/// The next `f64` toward −∞.
pub(super) fn next_down(x: f64) -> f64 {
    -next_up(-x)
}

/// A closed interval `[lo, hi]` of reals, bounds in `f64`, rounded outward.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Interval {
    pub(super) lo: f64,
    pub(super) hi: f64,
}

impl Interval {
    pub(super) fn point(x: f64) -> Self {
        Interval { lo: x, hi: x }
    }

    /// An enclosure of `a - b`.
    pub(super) fn sub(self, b: Interval) -> Interval {
        Interval {
            lo: next_down(self.lo - b.hi),
            hi: next_up(self.hi - b.lo),
        }
    }

    /// An enclosure of `a * b`.
    pub(super) fn mul(self, b: Interval) -> Interval {
        let p = [
            self.lo * b.lo,
            self.lo * b.hi,
            self.hi * b.lo,
            self.hi * b.hi,
        ];
        let mut lo = p[0];
        let mut hi = p[0];
        for &q in &p[1..] {
            // NaN (0 * inf) propagates through `min`/`max` poorly: poison explicitly.
            if q.is_nan() {
                return Interval {
                    lo: f64::NAN,
                    hi: f64::NAN,
                };
            }
            lo = lo.min(q);
            hi = hi.max(q);
        }
        Interval {
            lo: next_down(lo),
            hi: next_up(hi),
        }
    }

    /// The sign of every value in the interval, if they all share it strictly.
    pub(super) fn strict_sign(self) -> Option<Ordering> {
        if !(self.lo.is_finite() && self.hi.is_finite()) {
            None
        } else if self.lo > 0.0 {
            Some(Ordering::Greater)
        } else if self.hi < 0.0 {
            Some(Ordering::Less)
        } else {
            None
        }
    }
}

/// An enclosure of a rational. `Rational::to_f64` truncates toward zero, so
/// the true value is within one ulp of it.
fn enclose(r: &Rational) -> Interval {
    let t = r.to_f64();
    if !t.is_finite() {
        return Interval {
            lo: f64::NEG_INFINITY,
            hi: f64::INFINITY,
        };
    }
    if *r == t {
        Interval::point(t)
    } else {
        Interval {
            lo: next_down(t),
            hi: next_up(t),
        }
    }
}

/// The `f64` nearest to `r` (ties to the one with the even mantissa is not
/// guaranteed; ties go toward zero), and whether it equals `r` exactly.
///
/// `r` lies between its truncation `t` and the next float away from zero,
/// and rounds away exactly when it lies beyond their midpoint, a dyadic
/// `S · 2^(e - 1)`: one comparison of integers, `num · 2^(1 - e)` against
/// `S · den` (shifting whichever side needs it). (Subtracting both
/// neighbours as rationals would reduce each difference by a gcd, a few per
/// cent of a large run's time when the BSP rounds its exact crossings.)
fn nearest_f64(r: &Rational) -> (f64, bool) {
    let t = r.to_f64();
    if *r == t {
        return (t, true);
    }
    let away = if r.is_negative() {
        next_down(t)
    } else {
        next_up(t)
    };
    if !away.is_finite() {
        return (t, false);
    }
    let ((mt, et), (ma, ea)) = (dyadic(t), dyadic(away));
    // t may be zero (mt = 0); neighbours otherwise differ in exponent by at most one.
    let e = if mt == 0 { ea } else { et.min(ea) };
    let shifted = |m: i64, at: i32| Integer::from(m) << u32::try_from(at - e).unwrap_or(0);
    let sum = shifted(mt, et) + shifted(ma, ea);
    // r against (t + away) / 2 = sum · 2^(e - 1), times den > 0.
    let (num, den) = (r.numer(), r.denom());
    let order = if e >= 1 {
        num.cmp(&((sum * den) << u32::try_from(e - 1).unwrap_or(0)))
    } else {
        Integer::from(num << u32::try_from(1 - e).unwrap_or(0)).cmp(&(sum * den))
    };
    let beyond = if r.is_negative() {
        order == Ordering::Less
    } else {
        order == Ordering::Greater
    };
    if beyond { (away, false) } else { (t, false) }
}

/// A finite `f64` as `m · 2^e` (`m` 0 for zero).
pub(super) fn dyadic(v: f64) -> (i64, i32) {
    debug_assert!(v.is_finite(), "internal: finite value");
    if v == 0.0 {
        return (0, 0);
    }
    let bits = v.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32;
    let fraction = (bits & ((1 << 52) - 1)) as i64;
    let (m, e) = if exponent == 0 {
        (fraction, -1074)
    } else {
        (fraction | (1 << 52), exponent - 1075)
    };
    (if bits >> 63 == 1 { -m } else { m }, e)
}

/// A point with exact rational coordinates.
///
/// Equality and hashing compare the exact values (rationals are kept in
/// canonical form, so equal points hash alike however they were computed).
#[derive(Clone)]
pub struct PointQ {
    pub(super) x: Rational,
    pub(super) y: Rational,
    /// Enclosures of `x` and `y`, for the float filters.
    pub(super) ix: Interval,
    pub(super) iy: Interval,
}

impl PointQ {
    pub(super) fn from_rationals(x: Rational, y: Rational) -> Self {
        let ix = enclose(&x);
        let iy = enclose(&y);
        PointQ { x, y, ix, iy }
    }

    /// The exact rational value of an `f64` point.
    ///
    /// # Panics
    /// If a coordinate is NaN or infinite (finite input is checked once at the
    /// input boundary).
    pub fn from_point(p: Point) -> Self {
        let x = Rational::from_f64(p.x).expect("internal: finite x coordinate");
        let y = Rational::from_f64(p.y).expect("internal: finite y coordinate");
        PointQ {
            x,
            y,
            ix: Interval::point(p.x),
            iy: Interval::point(p.y),
        }
    }

    /// The nearest `f64` point (coordinate-wise nearest) and whether it is
    /// exactly this point.
    pub fn to_f64(&self) -> (Point, bool) {
        // A point enclosure is the exact value (`+ 0.0`: zero has no sign).
        if let Some(p) = self.as_f64() {
            return (Point::new(p.x + 0.0, p.y + 0.0), true);
        }
        let (x, ex) = nearest_f64(&self.x);
        let (y, ey) = nearest_f64(&self.y);
        (Point::new(x, y), ex && ey)
    }

    /// Whether both coordinates are exactly representable as `f64`.
    pub fn is_f64(&self) -> bool {
        self.ix.lo == self.ix.hi && self.iy.lo == self.iy.hi
    }

    /// Whether each coordinate (x, then y) is exactly representable as `f64`.
    pub fn coords_are_f64(&self) -> [bool; 2] {
        [self.ix.lo == self.ix.hi, self.iy.lo == self.iy.hi]
    }

    /// The exact `f64` value of this point, if it has one.
    pub fn as_f64(&self) -> Option<Point> {
        self.is_f64().then(|| Point::new(self.ix.lo, self.iy.lo))
    }

    /// The average of `points` (for a convex polygon: a point of its
    /// interior whenever the polygon has positive area). `None` when empty.
    pub fn barycentre<'a>(points: impl IntoIterator<Item = &'a PointQ>) -> Option<PointQ> {
        let mut sx = Rational::new();
        let mut sy = Rational::new();
        let mut count: u64 = 0;
        for p in points {
            sx += &p.x;
            sy += &p.y;
            count += 1;
        }
        if count == 0 {
            return None;
        }
        let n = Rational::from(count);
        sx /= &n;
        sy /= &n;
        Some(PointQ::from_rationals(sx, sy))
    }

    /// The point `self + t (other - self)` for the rational `t = num / den`
    /// given as two `f64` (exact).
    ///
    /// # Panics
    /// If `den` is zero or either argument is not finite.
    pub fn lerp_ratio(&self, other: &PointQ, num: f64, den: f64) -> PointQ {
        let n = Rational::from_f64(num).expect("internal: finite numerator");
        let d = Rational::from_f64(den).expect("internal: finite denominator");
        assert!(d != 0, "internal: lerp_ratio with zero denominator");
        let t = n / d;
        let x = Rational::from(&other.x - &self.x) * &t + &self.x;
        let y = Rational::from(&other.y - &self.y) * &t + &self.y;
        PointQ::from_rationals(x, y)
    }

    /// Compare the projections of `self` and `other` on the direction `(dx, dy)`
    /// exactly (used to sort points along a line).
    pub fn cmp_along(&self, other: &PointQ, dx: f64, dy: f64) -> Ordering {
        let dx = Rational::from_f64(dx).expect("internal: finite direction");
        let dy = Rational::from_f64(dy).expect("internal: finite direction");
        let a = Rational::from(&self.x * &dx) + Rational::from(&self.y * &dy);
        let b = Rational::from(&other.x * &dx) + Rational::from(&other.y * &dy);
        a.cmp(&b)
    }

    /// Compare the projections of `self` and `other` on the exact direction
    /// `to - from` (orders points of the line through `from` and `to`).
    pub fn cmp_along_q(&self, other: &PointQ, from: &PointQ, to: &PointQ) -> Ordering {
        let dx = Rational::from(&to.x - &from.x);
        let dy = Rational::from(&to.y - &from.y);
        let a = Rational::from(&self.x * &dx) + Rational::from(&self.y * &dy);
        let b = dx * &other.x + dy * &other.y;
        a.cmp(&b)
    }
}

impl PartialEq for PointQ {
    fn eq(&self, other: &Self) -> bool {
        self.x == other.x && self.y == other.y
    }
}

impl Eq for PointQ {}

impl Hash for PointQ {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.x.hash(state);
        self.y.hash(state);
    }
}

impl std::fmt::Debug for PointQ {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (p, exact) = self.to_f64();
        let mark = if exact { "" } else { "~" };
        write!(f, "{mark}({:?}, {:?})", p.x, p.y)
    }
}

impl From<Point> for PointQ {
    fn from(p: Point) -> Self {
        PointQ::from_point(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// An `f64` point rounds to itself without a rational division, and a
    /// negative zero to the zero a rational has (no sign), as the division
    /// would give it.
    #[test]
    fn an_f64_point_rounds_to_itself_with_unsigned_zero() {
        let (p, exact) = PointQ::from_point(Point::new(-0.0, 0.1)).to_f64();
        assert!(exact && p == Point::new(0.0, 0.1));
        assert!(p.x.is_sign_positive());
        let sum = PointQ::from_point(Point::new(0.1, 0.0)).lerp_ratio(
            &PointQ::from_point(Point::new(0.1, 0.0)),
            1.0,
            2.0,
        );
        assert_eq!(sum.to_f64(), (Point::new(0.1, 0.0), true));
    }

    #[test]
    fn roundtrip_f64_is_exact() {
        let p = Point::new(0.1, -3.5e-300);
        let q = PointQ::from_point(p);
        assert!(q.is_f64());
        assert_eq!(q.to_f64(), (p, true));
        assert_eq!(q.as_f64(), Some(p));
    }

    #[test]
    fn third_rounds_to_nearest_and_is_inexact() {
        let a = PointQ::from_point(Point::new(0.0, 0.0));
        let b = PointQ::from_point(Point::new(1.0, -1.0));
        let c = PointQ::from_point(Point::new(0.0, 1.0));
        let m = PointQ::barycentre(&[a, b, c]).expect("non-empty");
        let (p, exact) = m.to_f64();
        assert!(!exact);
        assert!(!m.is_f64());
        assert_eq!(p, Point::new(1.0 / 3.0, 0.0));
        assert!(m.ix.lo < 1.0 / 3.0 + 1e-15 && m.ix.hi > 1.0 / 3.0 - 1e-15);
        assert_eq!(m.iy, Interval::point(0.0));
    }

    #[test]
    fn nearest_of_negative_values() {
        let r = Rational::from((-2, 3));
        let (x, exact) = nearest_f64(&r);
        assert!(!exact);
        assert_eq!(x, -2.0 / 3.0);
        let r = Rational::from((7, 3));
        assert_eq!(nearest_f64(&r).0, 7.0 / 3.0);
    }

    #[test]
    fn equality_is_canonical() {
        let a = PointQ::from_point(Point::new(0.0, 0.0));
        let b = PointQ::from_point(Point::new(2.0, 2.0));
        let m1 = a.lerp_ratio(&b, 1.0, 2.0);
        let m2 = PointQ::barycentre(&[a.clone(), b.clone()]).expect("non-empty");
        assert_eq!(m1, m2);
        assert_eq!(m1, PointQ::from_point(Point::new(1.0, 1.0)));
        assert!(m1.is_f64());
    }

    #[test]
    fn next_up_down() {
        assert_eq!(next_up(1.0), 1.0 + f64::EPSILON);
        assert!(next_down(1.0) < 1.0);
        assert!(next_up(-0.0) > 0.0);
        assert!(next_down(0.0) < 0.0);
        assert_eq!(next_up(f64::MAX), f64::INFINITY);
    }

    /// [`nearest_f64`] as it was: by the two differences, as rationals (the
    /// reference of its property test). The `f64` nearest to `r` (ties to the one with the even mantissa is not
    /// guaranteed; ties go toward zero), and whether it equals `r` exactly.
    fn nearest_f64_by_differences(r: &Rational) -> (f64, bool) {
        let t = r.to_f64();
        if *r == t {
            return (t, true);
        }
        // The truncation `t` and the next float away from zero bracket `r`.
        let away = if r.is_negative() {
            next_down(t)
        } else {
            next_up(t)
        };
        if !away.is_finite() {
            return (t, false);
        }
        let tq = Rational::from_f64(t).expect("internal: finite truncation");
        let aq = Rational::from_f64(away).expect("internal: finite neighbour");
        let dt = Rational::from(r - &tq).abs();
        let da = Rational::from(r - &aq).abs();
        if da < dt { (away, false) } else { (t, false) }
    }

    /// Rationals of every kind: small fractions, values just off a float
    /// (either side, by far less than an ulp), exact midpoints of two
    /// neighbouring floats (ties, which go toward zero), subnormals and
    /// values past the largest float.
    fn rational() -> impl Strategy<Value = Rational> {
        let off_float =
            (-1e3f64..1e3, -300i32..300, any::<bool>(), 1u32..200).prop_map(|(m, e, up, k)| {
                let f = m * 2f64.powi(e);
                let mut r = Rational::from_f64(f).expect("finite");
                let mut ulp =
                    Rational::from_f64(f64::EPSILON * f.abs().max(1e-300)).expect("finite");
                ulp >>= k;
                if up {
                    r += ulp
                } else {
                    r -= ulp
                }
                r
            });
        let midpoint = (-1e3f64..1e3, -1070i32..1000).prop_map(|(m, e)| {
            let f = m * 2f64.powi(e.min(1000) - 40);
            let g = if f > 0.0 { next_up(f) } else { next_down(f) };
            let mut r =
                Rational::from_f64(f).expect("finite") + Rational::from_f64(g).expect("finite");
            r >>= 1u32;
            r
        });
        prop_oneof![
            (-1000i64..1000, 1i64..1000).prop_map(|(n, d)| Rational::from((n, d))),
            off_float,
            midpoint,
            (any::<i64>(), 1u64..u64::MAX, -1100i32..1100).prop_map(|(n, d, e)| {
                let mut r = Rational::from((n, d));
                r <<= e;
                r
            }),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 4096, failure_persistence: None, ..ProptestConfig::default() })]

        /// The midpoint comparison rounds as the two differences did.
        #[test]
        fn nearest_by_the_midpoint_is_nearest_by_differences(r in rational()) {
            prop_assert_eq!(nearest_f64(&r), nearest_f64_by_differences(&r), "{}", r);
        }
    }
}
