//! The 2D conformal AMIPS energy of a triangle, with the analytic gradient and
//! Hessian in one free vertex, and its restriction to a feature curve.
//!
//! With `J` the affine map from the equilateral reference triangle onto the
//! triangle, `E = tr(JᵀJ) / (2 det J)`; in closed form
//! `E = (|e0|² + |e1|² + |e2|²) / (4√3 A)` with `e_i` the edges and `A` the signed
//! area. It is 1 exactly for an equilateral triangle (its minimum), invariant
//! under similarity, and `+∞` for degenerate or clockwise triangles.
//! For one free vertex `p` the numerator is a convex quadratic and `A` is affine
//! in `p`, so `E(p)` is convex where `A > 0`: Newton's method on a sum over a
//! one-ring is well behaved.
//!
//! Thesis §2.3.2 ("Quality Measure"), §4.4.3 ("Curved AMIPS": the univariate
//! energy `E(c(t))` and its derivatives by the chain rule). The same value is
//! reported by `quality`.

use kurbo::{CubicBez, ParamCurve, ParamCurveDeriv, Point, Vec2};
use nalgebra::{Matrix2, Vector2};

/// `1 / (4√3)`.
const K: f64 = 0.144_337_567_297_406_43;

/// The AMIPS energy of the triangle `(a, b, c)` (counter-clockwise): 1 for an
/// equilateral triangle, `+∞` when degenerate or clockwise.
pub fn amips(a: Point, b: Point, c: Point) -> f64 {
    let (u, v) = (b - a, c - a);
    let area2 = u.cross(v);
    if area2 <= 0.0 || !area2.is_finite() {
        return f64::INFINITY;
    }
    let s = u.hypot2() + v.hypot2() + (c - b).hypot2();
    2.0 * K * s / area2
}

/// Energy, gradient and Hessian of a triangle in its free vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Amips2 {
    /// The energy.
    pub value: f64,
    /// Gradient with respect to the free vertex.
    pub grad: Vector2<f64>,
    /// Hessian with respect to the free vertex (symmetric positive semi-definite).
    pub hess: Matrix2<f64>,
}

impl std::ops::Add for Amips2 {
    type Output = Amips2;
    /// The sum of two (for a one-ring).
    fn add(self, o: Amips2) -> Amips2 {
        Amips2 {
            value: self.value + o.value,
            grad: self.grad + o.grad,
            hess: self.hess + o.hess,
        }
    }
}

impl Amips2 {
    /// Zero energy, gradient and Hessian.
    pub const ZERO: Amips2 = Amips2 {
        value: 0.0,
        grad: Vector2::new(0.0, 0.0),
        hess: Matrix2::new(0.0, 0.0, 0.0, 0.0),
    };

    /// `(E / scale)^power` with its derivatives (chain rule). Summed over a
    /// one-ring with a large power, it is a smooth stand-in for the ring's
    /// largest energy (min-max smoothing); `scale` (positive, e.g. the ring's
    /// current maximum) keeps the powers in range.
    pub fn powered(self, power: i32, scale: f64) -> Amips2 {
        let p = f64::from(power);
        let r = self.value / scale;
        let d1 = p * r.powi(power - 1) / scale;
        let d2 = p * (p - 1.0) * r.powi(power - 2) / (scale * scale);
        Amips2 {
            value: r.powi(power),
            grad: self.grad * d1,
            hess: self.hess * d1 + self.grad * self.grad.transpose() * d2,
        }
    }
}

/// AMIPS of the triangle `(p, b, c)` (counter-clockwise) with its derivatives
/// in the free vertex `p`; `None` when the triangle is degenerate or clockwise.
pub fn amips_free(p: Point, b: Point, c: Point) -> Option<Amips2> {
    // Work relative to b for accuracy.
    let (q, cc) = (p - b, c - b);
    // 2A = (b - p) × (c - p) = (-q) × (cc - q) = cc × q ... written out:
    let area2 = (-q).cross(cc - q);
    if area2 <= 0.0 || !area2.is_finite() {
        return None;
    }
    let a = 0.5 * area2;
    // ∇A = ½ perp(c - b), perp(v) = (-v.y, v.x).
    let ga = Vector2::new(-0.5 * cc.y, 0.5 * cc.x);
    let s = q.hypot2() + (q - cc).hypot2() + cc.hypot2();
    let gs = Vector2::new(2.0 * (2.0 * q.x - cc.x), 2.0 * (2.0 * q.y - cc.y));
    let value = K * s / a;
    let grad = (gs / a - ga * (s / (a * a))) * K;
    let hess = (Matrix2::identity() * (4.0 / a)
        - (gs * ga.transpose() + ga * gs.transpose()) / (a * a)
        + ga * ga.transpose() * (2.0 * s / (a * a * a)))
        * K;
    Some(Amips2 { value, grad, hess })
}

/// Energy and its first two derivatives along a curve parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Amips1 {
    /// The energy.
    pub value: f64,
    /// dE/dt.
    pub d1: f64,
    /// d²E/dt².
    pub d2: f64,
}

/// A curve a vertex may slide along: position, first and second derivative
/// at a parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveJet {
    /// `c(t)`.
    pub pos: Point,
    /// `c'(t)`.
    pub d1: Vec2,
    /// `c''(t)`.
    pub d2: Vec2,
}

impl CurveJet {
    /// The jet of a cubic Bézier at `t`.
    pub fn cubic(c: &CubicBez, t: f64) -> CurveJet {
        let d = c.deriv();
        let dd = d.deriv();
        CurveJet {
            pos: c.eval(t),
            d1: d.eval(t).to_vec2(),
            d2: dd.eval(t).to_vec2(),
        }
    }
}

/// The univariate energy `E(c(t))` of a one-ring by the chain rule (§4.4.3):
/// `E' = ∇E·c'`, `E'' = c'ᵀ H c' + ∇E·c''`. `e` is the one-ring's energy at
/// `c(t)` (from [`amips_free`], summed).
pub fn along_curve(e: &Amips2, jet: &CurveJet) -> Amips1 {
    let d1 = Vector2::new(jet.d1.x, jet.d1.y);
    let d2 = Vector2::new(jet.d2.x, jet.d2.y);
    Amips1 {
        value: e.value,
        d1: e.grad.dot(&d1),
        d2: d1.dot(&(e.hess * d1)) + e.grad.dot(&d2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eq_tri() -> [Point; 3] {
        [
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(0.5, 3f64.sqrt() / 2.0),
        ]
    }

    #[test]
    fn equilateral_is_one_and_a_minimum() {
        let [a, b, c] = eq_tri();
        assert!((amips(a, b, c) - 1.0).abs() < 1e-14);
        let e = amips_free(a, b, c).expect("ccw");
        assert!((e.value - 1.0).abs() < 1e-14);
        assert!(e.grad.norm() < 1e-12, "{:?}", e.grad);
        let eig = e.hess.symmetric_eigen().eigenvalues;
        assert!(eig.iter().all(|&l| l > 0.0), "{eig:?}");
        for k in 0..32 {
            let ang = f64::from(k) * 0.2;
            let p = a + Vec2::new(ang.cos(), ang.sin()) * 1e-3;
            assert!(amips(p, b, c) > 1.0);
        }
        assert_eq!(amips(a, c, b), f64::INFINITY);
        assert_eq!(amips(a, b, Point::new(2.0, 0.0)), f64::INFINITY);
    }

    #[test]
    fn invariant_under_similarity() {
        let t = [
            Point::new(0.3, -0.2),
            Point::new(2.0, 0.1),
            Point::new(0.9, 0.7),
        ];
        let e0 = amips(t[0], t[1], t[2]);
        for (s, rot, dx) in [(3.5, 0.7, 10.0), (1e-3, -2.0, -4.0), (1e4, 3.0, 1e3)] {
            let (cs, sn) = (f64::cos(rot), f64::sin(rot));
            let m = |p: Point| {
                Point::new(
                    s * (cs * p.x - sn * p.y) + dx,
                    s * (sn * p.x + cs * p.y) - dx,
                )
            };
            let e = amips(m(t[0]), m(t[1]), m(t[2]));
            assert!((e - e0).abs() < 1e-10 * e0, "{e} vs {e0}");
            // Cyclic order does not matter either.
            assert!((amips(t[1], t[2], t[0]) - e0).abs() < 1e-12 * e0);
        }
    }

    #[test]
    fn powered_derivatives_agree_with_finite_differences() {
        let (b, c) = (Point::new(1.0, 0.1), Point::new(0.3, 0.9));
        let p = Point::new(0.2, 0.15);
        let f = |q: Point| amips_free(q, b, c).expect("valid").powered(6, 2.0);
        let e = f(p);
        let h = 1e-6;
        for (k, d) in [Vec2::new(h, 0.0), Vec2::new(0.0, h)]
            .into_iter()
            .enumerate()
        {
            let (fp, fm) = (f(p + d), f(p - d));
            let g = (fp.value - fm.value) / (2.0 * h);
            assert!(
                (g - e.grad[k]).abs() <= 1e-5 * (1.0 + g.abs()),
                "{g} vs {}",
                e.grad[k]
            );
            let hk = (fp.grad - fm.grad) / (2.0 * h);
            for j in 0..2 {
                assert!((hk[j] - e.hess[(j, k)]).abs() <= 1e-4 * (1.0 + hk[j].abs()));
            }
        }
        // Power 1 with scale 1 is the energy itself.
        assert_eq!(
            amips_free(p, b, c).expect("valid").powered(1, 1.0).value,
            amips_free(p, b, c).expect("valid").value
        );
    }

    #[test]
    fn finite_differences_agree() {
        let (b, c) = (Point::new(1.0, 0.2), Point::new(-0.3, 1.1));
        for p in [
            Point::new(0.1, -0.4),
            Point::new(-1.0, -2.0),
            Point::new(0.6, 0.0),
        ] {
            let e = amips_free(p, b, c).expect("ccw");
            let h = 1e-6;
            for (i, d) in [Vec2::new(h, 0.0), Vec2::new(0.0, h)]
                .into_iter()
                .enumerate()
            {
                let ep = amips_free(p + d, b, c).expect("ccw");
                let em = amips_free(p - d, b, c).expect("ccw");
                let g = (ep.value - em.value) / (2.0 * h);
                assert!(
                    (g - e.grad[i]).abs() < 1e-6 * (1.0 + g.abs()),
                    "{g} {:?}",
                    e.grad
                );
                let hcol = (ep.grad - em.grad) / (2.0 * h);
                for j in 0..2 {
                    let want = hcol[j];
                    assert!(
                        (want - e.hess[(j, i)]).abs() < 1e-5 * (1.0 + want.abs()),
                        "{want} {:?}",
                        e.hess
                    );
                }
            }
            assert!((amips(p, b, c) - e.value).abs() < 1e-12 * e.value);
        }
    }

    #[test]
    fn curve_chain_rule_agrees_with_finite_differences() {
        let curve = CubicBez::new((-1.0, -1.0), (-0.2, -0.5), (0.4, -0.8), (1.2, -0.9));
        let ring = [
            (Point::new(1.5, 1.0), Point::new(0.0, 1.5)),
            (Point::new(0.0, 1.5), Point::new(-1.5, 0.8)),
        ];
        let energy = |t: f64| {
            let jet = CurveJet::cubic(&curve, t);
            let e = ring
                .iter()
                .map(|&(b, c)| amips_free(jet.pos, b, c).expect("ccw"))
                .fold(Amips2::ZERO, |a, b| a + b);
            along_curve(&e, &jet)
        };
        for t in [0.2, 0.5, 0.7] {
            let e = energy(t);
            let h = 1e-5;
            let (ep, em) = (energy(t + h), energy(t - h));
            let d1 = (ep.value - em.value) / (2.0 * h);
            let d2 = (ep.d1 - em.d1) / (2.0 * h);
            assert!((d1 - e.d1).abs() < 1e-6 * (1.0 + d1.abs()), "{d1} {}", e.d1);
            assert!((d2 - e.d2).abs() < 1e-5 * (1.0 + d2.abs()), "{d2} {}", e.d2);
        }
    }
}
