//! Exact conic pieces: rational quadratic Béziers in standard form.
//!
//! SVG's elliptical arcs, `<circle>`, `<ellipse>` and the corners of a rounded
//! `<rect>` are pieces of ellipses. A cubic Bézier only approximates them (the
//! usual 4-piece circle is off by 2.7e-4·r), which caps the accuracy a curved
//! finite-element mesh can reach. A rational quadratic Bézier represents an
//! ellipse arc exactly:
//!
//! ```text
//!        (1−t)² p0 + 2t(1−t) w p1 + t² p2
//! C(t) = ─────────────────────────────────,   t ∈ [0, 1]
//!          (1−t)² + 2t(1−t) w + t²
//! ```
//!
//! with end weights 1 (the standard form) and middle weight `w`. For an arc of
//! sweep 2h ≤ 90° on an ellipse, `w = cos h` and `p1` is where the end tangents
//! meet. Pieces are kept to at most 90° of the ellipse's parameter, so
//! `0 < w < 1`: the curve is an ellipse arc, lies inside its control triangle,
//! and also inside the control polygon of the cubic that elevates the
//! polynomial quadratic with the same controls ([`Conic::hull_cubic`]).

use kurbo::{Affine, CubicBez, Nearest, Point, Vec2};
use std::f64::consts::FRAC_PI_2;

/// A rational quadratic Bézier in standard form (end weights 1, middle weight `w > 0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conic {
    /// Start point.
    pub p0: Point,
    /// Control point (where the end tangents meet).
    pub p1: Point,
    /// End point.
    pub p2: Point,
    /// Weight of the control point; `cos(half sweep)` for an ellipse arc.
    pub w: f64,
}

impl Conic {
    /// A conic from its controls and middle weight.
    pub fn new(p0: impl Into<Point>, p1: impl Into<Point>, p2: impl Into<Point>, w: f64) -> Self {
        Self {
            p0: p0.into(),
            p1: p1.into(),
            p2: p2.into(),
            w,
        }
    }

    /// The homogeneous control points `(x·ω, y·ω, ω)`.
    fn homogeneous(&self) -> [[f64; 3]; 3] {
        [
            [self.p0.x, self.p0.y, 1.0],
            [self.w * self.p1.x, self.w * self.p1.y, self.w],
            [self.p2.x, self.p2.y, 1.0],
        ]
    }

    /// Numerator and denominator at `t` and their first and second derivatives.
    fn parts(&self, t: f64) -> [[f64; 3]; 3] {
        let h = self.homogeneous();
        let s = 1.0 - t;
        let (b0, b1, b2) = (s * s, 2.0 * s * t, t * t);
        let (d0, d1, d2) = (-2.0 * s, 2.0 - 4.0 * t, 2.0 * t);
        let mut out = [[0.0; 3]; 3];
        for k in 0..3 {
            out[0][k] = b0 * h[0][k] + b1 * h[1][k] + b2 * h[2][k];
            out[1][k] = d0 * h[0][k] + d1 * h[1][k] + d2 * h[2][k];
            out[2][k] = 2.0 * h[0][k] - 4.0 * h[1][k] + 2.0 * h[2][k];
        }
        out
    }

    /// The point at parameter `t`; exactly `p0` at 0 and `p2` at 1.
    pub fn eval(&self, t: f64) -> Point {
        if t == 0.0 {
            return self.p0;
        }
        if t == 1.0 {
            return self.p2;
        }
        let [n, _, _] = self.parts(t);
        Point::new(n[0] / n[2], n[1] / n[2])
    }

    /// First and second derivatives with respect to `t`.
    pub fn derivs(&self, t: f64) -> (Vec2, Vec2) {
        let [n, dn, ddn] = self.parts(t);
        let d = n[2];
        let c = Vec2::new(n[0] / d, n[1] / d);
        let dc = (Vec2::new(dn[0], dn[1]) - c * dn[2]) / d;
        let ddc = (Vec2::new(ddn[0], ddn[1]) - dc * (2.0 * dn[2]) - c * ddn[2]) / d;
        (dc, ddc)
    }

    /// The derivative `C′(t)`.
    pub fn deriv(&self, t: f64) -> Vec2 {
        self.derivs(t).0
    }

    /// Signed curvature at `t` (positive when turning anticlockwise); 0 where `C′` vanishes.
    pub fn curvature(&self, t: f64) -> f64 {
        let (d1, d2) = self.derivs(t);
        let n = d1.hypot();
        if n == 0.0 {
            0.0
        } else {
            d1.cross(d2) / (n * n * n)
        }
    }

    /// The piece on `[t0, t1]`, reparametrised to `[0, 1]` in standard form. Its end
    /// points are exactly `self.eval(t0)` and `self.eval(t1)`. The map from the new
    /// parameter to the old one is not linear (a Möbius map), so parameters of the
    /// piece are not parameters of `self`.
    pub fn subsegment(&self, t0: f64, t1: f64) -> Self {
        let h = self.homogeneous();
        // blossom of the homogeneous quadratic at (a, b)
        let blossom = |a: f64, b: f64| {
            let (c0, c1, c2) = ((1.0 - a) * (1.0 - b), (1.0 - a) * b + a * (1.0 - b), a * b);
            let mut q = [0.0; 3];
            for (k, qk) in q.iter_mut().enumerate() {
                *qk = c0 * h[0][k] + c1 * h[1][k] + c2 * h[2][k];
            }
            q
        };
        let (q0, q1, q2) = (blossom(t0, t0), blossom(t0, t1), blossom(t1, t1));
        let w = q1[2] / (q0[2] * q2[2]).sqrt();
        Self {
            p0: self.eval(t0),
            p1: Point::new(q1[0] / q1[2], q1[1] / q1[2]),
            p2: self.eval(t1),
            w,
        }
    }

    /// The same curve traversed backwards.
    pub fn reverse(&self) -> Self {
        Self::new(self.p2, self.p1, self.p0, self.w)
    }

    /// The image under an affine map (exact: affine maps keep the weights).
    pub fn transform(&self, a: Affine) -> Self {
        Self::new(a * self.p0, a * self.p1, a * self.p2, self.w)
    }

    /// The control points.
    pub fn control_points(&self) -> [Point; 3] {
        [self.p0, self.p1, self.p2]
    }

    /// A cubic whose control polygon contains the conic (for hulls, chord distances
    /// and turn bounds): the degree elevation of the polynomial quadratic with the same
    /// controls. Same end points and end tangents as the conic. For `w ≤ 1` the conic
    /// lies between its chord and that quadratic, hence inside this control polygon.
    pub fn hull_cubic(&self) -> CubicBez {
        CubicBez::new(
            self.p0,
            self.p0.lerp(self.p1, 2.0 / 3.0),
            self.p2.lerp(self.p1, 2.0 / 3.0),
            self.p2,
        )
    }

    /// The signed area between the curve and the origin, `½∫(x dy − y dx)`, exactly
    /// (kurbo's `ParamCurveArea` convention, so closed outlines sum to their area,
    /// positive anticlockwise). Requires `0 < w ≤ 1` (an ellipse arc or a parabola).
    pub fn signed_area(&self) -> f64 {
        let chord = 0.5 * self.p0.to_vec2().cross(self.p2.to_vec2());
        let triangle = 0.5 * (self.p1 - self.p0).cross(self.p2 - self.p0);
        chord + triangle * segment_ratio(self.w)
    }

    /// The usual cubic approximation of the conic (exact ends and end tangents;
    /// for a quarter circle the familiar 0.5523 handles, radial error 2.7e-4·r).
    /// Not the curve: only for consumers that cannot take a conic.
    pub fn approx_cubic(&self) -> CubicBez {
        let k = 4.0 * self.w / (3.0 * (1.0 + self.w));
        CubicBez::new(
            self.p0,
            self.p0.lerp(self.p1, k),
            self.p2.lerp(self.p1, k),
            self.p2,
        )
    }

    /// The point of the curve nearest to `p`: its parameter and squared distance
    /// (kurbo's [`kurbo::ParamCurveNearest`] contract; requires `w > 0`).
    ///
    /// `|C(t) − p|²` is stationary where `(C(t) − p)·C′(t) = 0`, and with
    /// `C − p = A/D`, `C′ = 2Q/D²` (`A`, `Q` quadratic) that is the quartic
    /// `A(t)·Q(t) = 0`: its roots in `[0, 1]`, the ends, and a few samples (a
    /// safety net for a root the solver misses) are the candidates; the best is
    /// polished by Newton steps on the quartic until a step moves the point by
    /// less than `accuracy`.
    pub fn nearest(&self, p: Point, accuracy: f64) -> Nearest {
        let w = self.w;
        // Power-basis coefficients of a quadratic given by Bernstein coefficients.
        let power = |b0: Vec2, b1: Vec2, b2: Vec2| [b0, (b1 - b0) * 2.0, b0 - b1 * 2.0 + b2];
        let a = power(self.p0 - p, (self.p1 - p) * w, self.p2 - p);
        let (u, v) = (self.p1 - self.p0, self.p2 - self.p1);
        let q = power(u * w, (u + v) * 0.5, v * w);
        let mut g = [0.0; 5];
        for (i, ai) in a.iter().enumerate() {
            for (j, qj) in q.iter().enumerate() {
                g[i + j] += ai.dot(*qj);
            }
        }
        let dist2 = |t: f64| (self.eval(t) - p).hypot2();
        let mut best = Nearest {
            distance_sq: dist2(0.0),
            t: 0.0,
        };
        let consider = |t: f64, best: &mut Nearest| {
            if (0.0..=1.0).contains(&t) {
                let d = dist2(t);
                if d < best.distance_sq {
                    *best = Nearest { distance_sq: d, t };
                }
            }
        };
        consider(1.0, &mut best);
        for t in kurbo::common::solve_quartic(g[0], g[1], g[2], g[3], g[4]) {
            consider(t, &mut best);
        }
        for k in 1..NEAREST_SAMPLES {
            consider(f64::from(k) / f64::from(NEAREST_SAMPLES), &mut best);
        }
        // Newton on the quartic from the best candidate, keeping improvements only.
        let mut t = best.t;
        for _ in 0..NEAREST_NEWTON {
            let (mut val, mut der) = (0.0, 0.0);
            for k in (0..5).rev() {
                der = der * t + val;
                val = val * t + g[k];
            }
            if der == 0.0 || !der.is_finite() {
                break;
            }
            let next = (t - val / der).clamp(0.0, 1.0);
            if !next.is_finite() {
                break;
            }
            let moved = (self.eval(next) - self.eval(t)).hypot();
            t = next;
            consider(t, &mut best);
            if moved.partial_cmp(&accuracy) != Some(std::cmp::Ordering::Greater) {
                break;
            }
        }
        best
    }

    /// Pieces of an ellipse arc, each at most 90° of the ellipse's parameter.
    ///
    /// `arc` is kurbo's centre parametrisation (from [`kurbo::Arc::from_svg_arc`], for
    /// example). The first piece starts exactly at `from` and the last ends exactly at
    /// `to` when given (the SVG end points, so that consecutive segments share their
    /// points bit for bit); interior joints lie on the ellipse.
    pub fn ellipse_arc(arc: &kurbo::Arc, from: Option<Point>, to: Option<Point>) -> Vec<Self> {
        let sweep = arc.sweep_angle;
        if !sweep.is_finite() || sweep == 0.0 {
            return Vec::new();
        }
        let n = ((sweep.abs() / FRAC_PI_2) - 1e-9).ceil().max(1.0);
        // at most 4 pieces per turn; a sweep above 2π (not produced by SVG arcs) is clamped
        let n = n.min(4.0 * 64.0) as usize;
        let step = sweep / n as f64;
        let rot = Affine::rotate(arc.x_rotation);
        let at = |theta: f64, scale: f64| {
            let (s, c) = theta.sin_cos();
            arc.center
                + (rot * Point::new(arc.radii.x * c * scale, arc.radii.y * s * scale)).to_vec2()
        };
        let half = step / 2.0;
        let w = half.cos();
        let angle = |i: usize| {
            if i == n {
                arc.start_angle + sweep
            } else {
                arc.start_angle + step * i as f64
            }
        };
        // the joints, computed once so that consecutive pieces share them bit for bit
        let mut joints: Vec<Point> = (0..=n).map(|i| at(angle(i), 1.0)).collect();
        if let Some(p) = from {
            joints[0] = p;
        }
        if let Some(p) = to {
            joints[n] = p;
        }
        (0..n)
            .map(|i| Self::new(joints[i], at(angle(i) + half, 1.0 / w), joints[i + 1], w))
            .collect()
    }
}

/// Samples of [`Conic::nearest`]'s safety net (plus both ends).
const NEAREST_SAMPLES: u32 = 8;
/// Newton steps of [`Conic::nearest`]'s polish.
const NEAREST_NEWTON: usize = 8;

/// The area between an ellipse arc of weight `w` and its chord, as a fraction of its
/// control triangle's area: `(h − sin h cos h) cos h / sin³ h` with `w = cos h` (an
/// affine map keeps the ratio, so the unit circle decides it); 2/3 for a parabola.
fn segment_ratio(w: f64) -> f64 {
    let w = w.clamp(0.0, 1.0);
    let h = w.acos();
    if h == 0.0 {
        return 2.0 / 3.0;
    }
    if h < 1e-2 {
        // h − sin h cos h = h − sin(2h)/2, by its series (the difference cancels)
        let h2 = h * h;
        let num = h * h2 * (2.0 / 3.0 - h2 * (2.0 / 15.0 - h2 * (4.0 / 315.0)));
        let s = h.sin();
        return num * w / (s * s * s);
    }
    let s = h.sin();
    (h - s * w) * w / (s * s * s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_1_SQRT_2, PI};

    fn quarter() -> Conic {
        Conic::new((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), FRAC_1_SQRT_2)
    }

    #[test]
    fn quarter_circle_is_exact() {
        let c = quarter();
        for i in 0..=64 {
            let t = f64::from(i) / 64.0;
            let p = c.eval(t);
            assert!((p.to_vec2().hypot() - 1.0).abs() < 4e-16, "t={t}");
            assert!((c.curvature(t) - 1.0).abs() < 1e-13);
            // tangent perpendicular to the radius
            assert!(c.deriv(t).dot(p.to_vec2()).abs() < 1e-14);
        }
    }

    #[test]
    fn subsegments_stay_on_the_circle_and_join() {
        let c = quarter();
        let (a, b) = (c.subsegment(0.0, 0.3), c.subsegment(0.3, 1.0));
        assert_eq!(a.p2, b.p0);
        assert_eq!(a.p0, c.p0);
        assert_eq!(b.p2, c.p2);
        for s in [a, b, c.subsegment(0.25, 0.75)] {
            assert!(s.w > 0.0 && s.w < 1.0);
            for i in 0..=16 {
                let p = s.eval(f64::from(i) / 16.0);
                assert!((p.to_vec2().hypot() - 1.0).abs() < 1e-15);
            }
        }
        // a subsegment of sweep 2h has weight cos h
        let s = c.subsegment(0.0, 0.5); // the half-way point of a symmetric quarter is 45°
        assert!((s.w - (PI / 8.0).cos()).abs() < 1e-15);
    }

    #[test]
    fn ellipse_arcs_hit_their_ends_and_stay_inside_the_hull_cubic() {
        let arc = kurbo::Arc {
            center: Point::new(3.0, -1.0),
            radii: Vec2::new(2.0, 0.5),
            start_angle: 0.3,
            sweep_angle: -4.0,
            x_rotation: 0.7,
        };
        let pieces = Conic::ellipse_arc(&arc, None, None);
        assert_eq!(pieces.len(), 3);
        let on_ellipse = |p: Point| {
            let q = Affine::rotate(-0.7) * (p - arc.center).to_point();
            (q.x / 2.0).powi(2) + (q.y / 0.5).powi(2)
        };
        for w in pieces.windows(2) {
            assert_eq!(w[0].p2, w[1].p0);
        }
        for c in &pieces {
            let hull = c.hull_cubic();
            for i in 0..=32 {
                let p = c.eval(f64::from(i) / 32.0);
                assert!((on_ellipse(p) - 1.0).abs() < 1e-14);
                // inside the convex quadrilateral: same side of every edge
                let q = [hull.p0, hull.p1, hull.p2, hull.p3];
                let sides: Vec<f64> = (0..4)
                    .map(|k| (q[(k + 1) % 4] - q[k]).cross(p - q[k]))
                    .collect();
                let s = if c.w > 0.0 && sides.iter().any(|&x| x > 1e-12) {
                    1.0
                } else {
                    -1.0
                };
                assert!(sides.iter().all(|&x| x * s >= -1e-12), "{sides:?}");
            }
        }
        let end = arc.center
            + (Affine::rotate(0.7) * Point::new(2.0 * (-3.7f64).cos(), 0.5 * (-3.7f64).sin()))
                .to_vec2();
        assert!((pieces[2].p2 - end).hypot() < 1e-15);
    }

    #[test]
    fn areas_are_exact() {
        // the unit disk from four quarters, anywhere, either way round
        let q = quarter();
        let offset = Affine::translate((3.5, -2.25));
        let quarters: Vec<Conic> = (0..4)
            .map(|k| q.transform(offset * Affine::rotate(f64::from(k) * FRAC_PI_2)))
            .collect();
        let a: f64 = quarters.iter().map(Conic::signed_area).sum();
        assert!((a - PI).abs() < 1e-14, "{a}");
        let b: f64 = quarters.iter().map(|c| c.reverse().signed_area()).sum();
        assert!((b + PI).abs() < 1e-14, "{b}");
        // small arcs (the series branch) and their complement add up
        let arc = kurbo::Arc {
            center: Point::ORIGIN,
            radii: Vec2::new(1.0, 1.0),
            start_angle: 0.0,
            sweep_angle: 2.0 * PI,
            x_rotation: 0.0,
        };
        let mut pieces = Conic::ellipse_arc(&arc, None, None);
        let first = pieces[0];
        pieces[0] = first.subsegment(0.0, 1e-3);
        pieces.push(first.subsegment(1e-3, 1.0));
        let a: f64 = pieces.iter().map(Conic::signed_area).sum();
        assert!((a - PI).abs() < 1e-14, "{a}");
        assert!((segment_ratio(1.0) - 2.0 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn affine_images_stay_exact() {
        let a = Affine::new([2.0, 0.5, -1.0, 3.0, 10.0, -4.0]);
        let c = quarter().transform(a);
        let inv = a.inverse();
        for i in 0..=16 {
            let p = inv * c.eval(f64::from(i) / 16.0);
            assert!((p.to_vec2().hypot() - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn nearest_points_match_dense_sampling() {
        let a = Affine::new([2.0, 0.5, -1.0, 3.0, 10.0, -4.0]);
        let curves = [
            quarter(),
            quarter().transform(a),
            quarter().subsegment(0.1, 0.35),
            Conic::new((0.0, 0.0), (5.0, 0.01), (10.0, 0.0), 0.3),
            Conic::new((0.0, 0.0), (1.0, 4.0), (2.0, 0.0), 2.5),
        ];
        for c in curves {
            let [p0, p1, p2] = c.control_points();
            for (i, p) in [
                p0,
                p1,
                p2,
                p0.midpoint(p2),
                p1 + (p1 - p0),
                Point::new(0.3, 0.7),
            ]
            .into_iter()
            .enumerate()
            {
                let n = c.nearest(p, 1e-13);
                let brute = (0..=20_000)
                    .map(|k| (c.eval(f64::from(k) / 20_000.0) - p).hypot2())
                    .fold(f64::INFINITY, f64::min);
                assert!((0.0..=1.0).contains(&n.t));
                assert!((n.distance_sq - (c.eval(n.t) - p).hypot2()).abs() <= 1e-12);
                assert!(
                    n.distance_sq <= brute * (1.0 + 1e-9) + 1e-24,
                    "{c:?} point {i}: {} > {brute}",
                    n.distance_sq
                );
            }
        }
        // On the curve: distance 0 at the right parameter.
        let c = quarter();
        let n = c.nearest(c.eval(0.37), 1e-15);
        assert!(n.distance_sq < 1e-28 && (n.t - 0.37).abs() < 1e-9, "{n:?}");
    }
}
