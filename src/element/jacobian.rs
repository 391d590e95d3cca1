//! Certified bounds of the Jacobian determinant of Lagrange triangles (thesis
//! §4.4.2 "validity", docs/design.md "Curved elements").
//!
//! For an order-`p` triangle the map `x(ξ, η)` is a degree-`p` Bézier triangle; its
//! partial derivatives are degree-`p − 1` Bézier triangles whose control points are
//! `p` times differences of neighbouring control points, and `det J = ∂ξx × ∂ηx` is
//! a polynomial of degree `2(p − 1)`: 15 Bernstein coefficients for a cubic, 6 for a
//! quadratic, one constant for a linear triangle. We compute them directly with
//! the Bernstein product rule
//! `(Σ a_α B^m_α)(Σ c_β B^m_β) = Σ_γ (Σ_{α+β=γ} C(m,α) C(m,β) / C(2m,γ) a_α c_β) B^{2m}_γ`,
//! never by sampling. `det J` is measured against the reference triangle
//! `(0,0), (1,0), (0,1)` (so a straight triangle has `det J = 2 · area`).
//!
//! [`certify`] guarantees: `Certified` only if every Bernstein coefficient on every
//! final piece of a midpoint subdivision (de Casteljau, exact up to rounding) exceeds
//! the zero tolerance, so `det J` is positive on the whole element; `Inverted` /
//! `Degenerate` only with a sampled value of `det J` below `−zero` / within `±zero`,
//! a proof; `Uncertain` when the depth or piece budget ran out first. Only
//! `Certified` elements are valid. The bounds `lower ≤ min det J` and
//! `upper ≥ max det J` are tightened (subdivision continues) until they are within
//! `rtol · max` of sampled extremes, so `lower / upper`, the Jacobian ratio, is a
//! certified lower bound of `min det J / max det J`, tight to about `rtol`.

use super::bernstein::{self, BernsteinTri, index, lattice, len};
use super::lagrange;
use crate::element::Order;
use kurbo::{Point, Vec2};

/// The determinant of a straight triangle (constant; `2 ·` its signed area).
pub fn det_linear(corners: &[Point; 3]) -> BernsteinTri {
    BernsteinTri::new(&[(corners[1] - corners[0]).cross(corners[2] - corners[0])])
}

/// The degree-2 Bernstein form of `det J` of a quadratic Lagrange triangle (gmsh type 9 order).
pub fn det_quadratic(nodes: &[Point; 6]) -> BernsteinTri {
    let o = nodes[0].to_vec2();
    let net = lagrange::quadratic_to_bezier(&nodes.map(|p| p - o));
    det_of_net(&net.map(|p| p.to_vec2()), 2)
}

/// The degree-4 Bernstein form of `det J` of a cubic Lagrange triangle (gmsh type 21 order).
pub fn det_cubic(nodes: &[Point; 10]) -> BernsteinTri {
    let o = nodes[0].to_vec2();
    // Translating to node 0 avoids cancellation far from the origin.
    let net = lagrange::cubic_to_bezier(&nodes.map(|p| p - o));
    det_of_net(&net.map(|p| p.to_vec2()), 3)
}

/// `det J` of a triangle of the given order from its Lagrange nodes in gmsh order;
/// `None` if `nodes` does not hold exactly that order's node count.
pub fn det_lagrange(order: Order, nodes: &[Point]) -> Option<BernsteinTri> {
    Some(match order {
        Order::Linear => det_linear(nodes.try_into().ok()?),
        Order::Quadratic => det_quadratic(nodes.try_into().ok()?),
        Order::Cubic => det_cubic(nodes.try_into().ok()?),
    })
}

/// `det J` of a degree-`n` (2 or 3) Bézier triangle, control net in lattice order.
fn det_of_net(net: &[Vec2], n: usize) -> BernsteinTri {
    let m = n - 1;
    let mut dxi = [Vec2::ZERO; len(2)];
    let mut deta = [Vec2::ZERO; len(2)];
    for (i, b) in lattice(m).enumerate() {
        let (j, k) = (b[1], b[2]);
        let base = net[index(n, j, k)];
        dxi[i] = n as f64 * (net[index(n, j + 1, k)] - base);
        deta[i] = n as f64 * (net[index(n, j, k + 1)] - base);
    }
    let mut d = [0.0; len(bernstein::MAX_DEGREE)];
    let table: &[(u8, u8, u8, f64)] = if m == 2 { &PRODUCT_2 } else { &PRODUCT_1 };
    for &(g, ia, ib, w) in table {
        d[g as usize] += w * dxi[ia as usize].cross(deta[ib as usize]);
    }
    BernsteinTri::new(&d[..len(2 * m)])
}

/// The Bernstein product rule for two degree-`m` polynomials as a table of
/// (index of γ in degree 2m, index of α, index of β, C(m,α) C(m,β) / C(2m,γ)).
const fn product_table<const N: usize>(m: usize) -> [(u8, u8, u8, f64); N] {
    const FACT: [f64; 5] = [1.0, 1.0, 2.0, 6.0, 24.0];
    let mut out = [(0u8, 0u8, 0u8, 0.0f64); N];
    let mut i = 0;
    // enumerate α, β in lattice order (k outer, j inner)
    let mut ka = 0;
    while ka <= m {
        let mut ja = 0;
        while ja <= m - ka {
            let a = [m - ja - ka, ja, ka];
            let mut kb = 0;
            while kb <= m {
                let mut jb = 0;
                while jb <= m - kb {
                    let b = [m - jb - kb, jb, kb];
                    let g = [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
                    let ca = FACT[m] / (FACT[a[0]] * FACT[a[1]] * FACT[a[2]]);
                    let cb = FACT[m] / (FACT[b[0]] * FACT[b[1]] * FACT[b[2]]);
                    let cg = FACT[2 * m] / (FACT[g[0]] * FACT[g[1]] * FACT[g[2]]);
                    out[i] = (
                        index(2 * m, g[1], g[2]) as u8,
                        index(m, ja, ka) as u8,
                        index(m, jb, kb) as u8,
                        ca * cb / cg,
                    );
                    i += 1;
                    jb += 1;
                }
                kb += 1;
            }
            ja += 1;
        }
        ka += 1;
    }
    out
}

/// Product table for two linear factors (quadratic elements).
const PRODUCT_1: [(u8, u8, u8, f64); 9] = product_table::<9>(1);
/// Product table for two quadratic factors (cubic elements).
const PRODUCT_2: [(u8, u8, u8, f64); 36] = product_table::<36>(2);

/// The exact signed area of the element whose `det J` is `det` (∫ det J over the
/// reference triangle of area 1/2).
pub fn area(det: &BernsteinTri) -> f64 {
    0.5 * det.mean()
}

/// How hard [`certify`] works.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CertifyOptions {
    /// Deepest midpoint subdivision (each level splits a piece in 4). Default 8.
    pub max_depth: u32,
    /// Subdivide until the bounds are within `rtol · max det J` of sampled extremes;
    /// `f64::INFINITY` decides validity only (cheapest). Default 1e-3.
    pub rtol: f64,
    /// Values of `det J` within `zero_rel · h²` of 0 count as zero, `h` the diagonal of
    /// the nodes' bounding box (scale-free, like mshcheck). Default 1e-12.
    pub zero_rel: f64,
    /// Most pieces examined per element before giving up. Default 20 000.
    pub max_pieces: usize,
}

impl CertifyOptions {
    /// Depth 8, rtol 1e-3, zero_rel 1e-12, 20 000 pieces (the settings of mshcheck).
    pub const DEFAULT: CertifyOptions = CertifyOptions {
        max_depth: 8,
        rtol: 1e-3,
        zero_rel: 1e-12,
        max_pieces: 20_000,
    };
    /// Validity only: no tightening of the ratio.
    pub const VALIDITY: CertifyOptions = CertifyOptions {
        rtol: f64::INFINITY,
        ..CertifyOptions::DEFAULT
    };
}

impl Default for CertifyOptions {
    fn default() -> Self {
        CertifyOptions::DEFAULT
    }
}

/// The verdict on an element.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Validity {
    /// `det J > 0` everywhere, proved by positive Bernstein coefficients.
    Certified,
    /// `det J < 0` somewhere (a sampled value proves it).
    Inverted,
    /// `det J` is zero (within tolerance) somewhere, and nowhere proved negative.
    Degenerate,
    /// No proof either way within the subdivision budget: not valid.
    Uncertain,
}

/// What [`certify`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Certificate {
    /// The verdict.
    pub validity: Validity,
    /// Certified lower bound of `det J` (the smallest final coefficient).
    pub lower: f64,
    /// Certified upper bound of `det J` (the largest final coefficient).
    pub upper: f64,
    /// Smallest sampled value of `det J`.
    pub sampled_min: f64,
    /// Largest sampled value of `det J`.
    pub sampled_max: f64,
    /// Number of pieces examined (1 when the first coefficients decide).
    pub pieces: usize,
}

impl Certificate {
    /// `lower / upper`: a certified lower bound of `min det J / max det J` (1 for a
    /// straight triangle, ≤ 0 for an invalid element; −1 when `det J` is nowhere
    /// positive, 0 when it is zero everywhere). Always finite.
    pub fn ratio(&self) -> f64 {
        if self.upper > 0.0 {
            self.lower / self.upper
        } else if self.lower < 0.0 {
            -1.0
        } else {
            0.0
        }
    }

    /// Whether the element is certified valid.
    pub fn is_certified(&self) -> bool {
        self.validity == Validity::Certified
    }
}

/// The absolute zero tolerance of [`CertifyOptions::zero_rel`] for these nodes.
pub fn zero_abs(nodes: &[Point], zero_rel: f64) -> f64 {
    let (mut lo, mut hi) = (
        Vec2::new(f64::INFINITY, f64::INFINITY),
        Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for p in nodes {
        lo = Vec2::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Vec2::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    if nodes.is_empty() {
        return 0.0;
    }
    zero_rel * (hi - lo).hypot2()
}

/// Certify the Lagrange triangle `nodes` (gmsh order) of the given order.
/// `None` if `nodes` does not hold that order's node count.
///
/// A cubic triangle whose edge 0→1 bulges along a Bézier arc is valid; pulled
/// through the opposite corner, the same edge folds the element:
///
/// ```
/// use kurbo::{CubicBez, Point};
/// use triwild::element::jacobian::{Validity, certify_element};
/// use triwild::element::lagrange::cubic_nodes;
/// use triwild::element::{CertifyOptions, CurvedEdge, Order};
///
/// let corners = [Point::new(0.0, 0.0), Point::new(1.0, 0.0), Point::new(0.5, 1.0)];
/// let bulge = |h: f64| CurvedEdge {
///     edge: 0,
///     curve: CubicBez::new((0.0, 0.0), (0.3, h), (0.7, h), (1.0, 0.0)),
///     t0: 0.0,
///     t1: 1.0,
/// };
/// let opts = CertifyOptions::DEFAULT;
/// let good = cubic_nodes(corners, Some(&bulge(-0.2)));
/// assert!(certify_element(Order::Cubic, &good, &opts).unwrap().is_certified());
/// let folded = cubic_nodes(corners, Some(&bulge(2.0)));
/// let cert = certify_element(Order::Cubic, &folded, &opts).unwrap();
/// assert_ne!(cert.validity, Validity::Certified);
/// ```
pub fn certify_element(
    order: Order,
    nodes: &[Point],
    opts: &CertifyOptions,
) -> Option<Certificate> {
    let det = det_lagrange(order, nodes)?;
    Some(certify(&det, zero_abs(nodes, opts.zero_rel), opts))
}

/// Certify `det > zero` on the whole triangle (see the module doc for the guarantees).
pub fn certify(det: &BernsteinTri, zero: f64, opts: &CertifyOptions) -> Certificate {
    const UNIT: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    if opts.rtol == f64::INFINITY && det.min_coeff() > zero {
        // Fast path of the validity-only check: the first coefficients decide.
        let v = det.corner_values();
        return Certificate {
            validity: Validity::Certified,
            lower: det.min_coeff(),
            upper: det.max_coeff(),
            sampled_min: v[0].min(v[1]).min(v[2]),
            sampled_max: v[0].max(v[1]).max(v[2]),
            pieces: 1,
        };
    }
    let mut smin = f64::INFINITY;
    let mut smax = f64::NEG_INFINITY;
    let mut lower = f64::INFINITY;
    let mut upper = f64::NEG_INFINITY;
    let mut pieces = 0usize;
    let mut level: Vec<(BernsteinTri, [[f64; 3]; 3])> = vec![(*det, UNIT)];
    let mut depth = 0u32;
    let mut unresolved = false;
    while !level.is_empty() {
        pieces += level.len();
        // Samples: the corner values (exact coefficients), the edge midpoints and
        // the centroid.
        const SAMPLES: [[f64; 3]; 4] = [
            [0.5, 0.5, 0.0],
            [0.0, 0.5, 0.5],
            [0.5, 0.0, 0.5],
            [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
        ];
        for (p, _) in &level {
            for v in p
                .corner_values()
                .into_iter()
                .chain(SAMPLES.map(|l| p.eval(l)))
            {
                smin = smin.min(v);
                smax = smax.max(v);
            }
        }
        if smin <= zero {
            // Proved invalid: the bounds are those of the current pieces.
            for (p, _) in &level {
                lower = lower.min(p.min_coeff());
                upper = upper.max(p.max_coeff());
            }
            let validity = if smin < -zero {
                Validity::Inverted
            } else {
                Validity::Degenerate
            };
            return Certificate {
                validity,
                lower: lower.min(smin),
                upper: upper.max(smax),
                sampled_min: smin,
                sampled_max: smax,
                pieces,
            };
        }
        let tol = opts.rtol * smax.abs();
        let last = depth >= opts.max_depth || pieces + 4 * level.len() > opts.max_pieces;
        let mut next = Vec::new();
        for (p, corners) in &level {
            let (cmin, cmax) = (p.min_coeff(), p.max_coeff());
            let need = cmin <= zero || cmin < smin - tol || cmax > smax + tol;
            if need && !last {
                next.extend(p.split4(*corners));
            } else {
                if cmin <= zero {
                    unresolved = true;
                }
                lower = lower.min(cmin);
                upper = upper.max(cmax);
            }
        }
        level = next;
        depth += 1;
    }
    Certificate {
        validity: if unresolved {
            Validity::Uncertain
        } else {
            Validity::Certified
        },
        lower,
        upper,
        sampled_min: smin,
        sampled_max: smax,
        pieces,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::bernstein::multinomial;
    use crate::element::lagrange::{CUBIC_REF, CurvedEdge, cubic_nodes, quadratic_nodes};
    use kurbo::CubicBez;
    use nalgebra::{DMatrix, DVector};
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngAlgorithm, RngSeed};

    /// Partial derivatives of the thesis's ten cubic basis functions (§4.4.3),
    /// differentiated by hand: an evaluation of det J independent of Bézier forms.
    fn grad_basis(x: f64, y: f64) -> [[f64; 2]; 10] {
        let s = x + y;
        [
            // ℓ0 = -1/2 (3s-1)(s-1)(3s-2): d/ds = -1/2 (27 s² - 36 s + 11)
            [-0.5 * (27.0 * s * s - 36.0 * s + 11.0); 2],
            [0.5 * (27.0 * x * x - 18.0 * x + 2.0), 0.0],
            [0.0, 0.5 * (27.0 * y * y - 18.0 * y + 2.0)],
            // ℓ3 = 9/2 x (s-1)(3s-2)
            [
                4.5 * ((s - 1.0) * (3.0 * s - 2.0) + x * (6.0 * s - 5.0)),
                4.5 * x * (6.0 * s - 5.0),
            ],
            // ℓ4 = -9/2 (3x³ + 3x²y - 4x² - xy + x)
            [
                -4.5 * (9.0 * x * x + 6.0 * x * y - 8.0 * x - y + 1.0),
                -4.5 * (3.0 * x * x - x),
            ],
            // ℓ5 = 9/2 (3x²y - xy)
            [4.5 * (6.0 * x * y - y), 4.5 * (3.0 * x * x - x)],
            // ℓ6 = 9/2 (3xy² - xy)
            [4.5 * (3.0 * y * y - y), 4.5 * (6.0 * x * y - x)],
            // ℓ7 = -9/2 (3xy² - xy + 3y³ - 4y² + y)
            [
                -4.5 * (3.0 * y * y - y),
                -4.5 * (6.0 * x * y - x + 9.0 * y * y - 8.0 * y + 1.0),
            ],
            // ℓ8 = 9/2 y (s-1)(3s-2)
            [
                4.5 * y * (6.0 * s - 5.0),
                4.5 * ((s - 1.0) * (3.0 * s - 2.0) + y * (6.0 * s - 5.0)),
            ],
            // ℓ9 = -27 (x²y + xy² - xy)
            [
                -27.0 * (2.0 * x * y + y * y - y),
                -27.0 * (x * x + 2.0 * x * y - x),
            ],
        ]
    }

    fn det_direct(nodes: &[Point; 10], x: f64, y: f64) -> f64 {
        let g = grad_basis(x, y);
        let mut j = [[0.0; 2]; 2];
        for (p, gi) in nodes.iter().zip(g) {
            j[0][0] += p.x * gi[0];
            j[0][1] += p.x * gi[1];
            j[1][0] += p.y * gi[0];
            j[1][1] += p.y * gi[1];
        }
        j[0][0] * j[1][1] - j[0][1] * j[1][0]
    }

    /// A triangle with one edge on a cubic arc: the typical curved element.
    fn curved_element(bulge: f64) -> [Point; 10] {
        let c = CubicBez::new((0.0, 0.0), (0.3, -bulge), (0.7, -bulge), (1.0, 0.0));
        let e = CurvedEdge {
            edge: 0,
            curve: c,
            t0: 0.0,
            t1: 1.0,
        };
        cubic_nodes(
            [
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(0.4, 0.9),
            ],
            Some(&e),
        )
    }

    #[test]
    fn gradients_match_finite_differences() {
        let n = curved_element(0.3);
        let (x, y, h) = (0.21, 0.33, 1e-6);
        let f = |x, y| lagrange::eval_cubic_lagrange(&n, x, y);
        let jx = (f(x + h, y) - f(x - h, y)) / (2.0 * h);
        let jy = (f(x, y + h) - f(x, y - h)) / (2.0 * h);
        assert!((jx.cross(jy) - det_direct(&n, x, y)).abs() < 1e-6);
    }

    #[test]
    fn straight_elements_have_constant_det() {
        let c = [
            Point::new(1.0, 1.0),
            Point::new(3.0, 1.5),
            Point::new(1.5, 4.0),
        ];
        let want = (c[1] - c[0]).cross(c[2] - c[0]);
        for det in [
            det_linear(&c),
            det_quadratic(&quadratic_nodes(c, None)),
            det_cubic(&cubic_nodes(c, None)),
        ] {
            for &v in det.coeffs() {
                assert!((v - want).abs() < 1e-12 * want, "{v} vs {want}");
            }
            assert!((area(&det) - want / 2.0).abs() < 1e-12);
        }
        let cert = certify(
            &det_cubic(&cubic_nodes(c, None)),
            0.0,
            &CertifyOptions::DEFAULT,
        );
        assert!(cert.is_certified());
        assert!((cert.ratio() - 1.0).abs() < 1e-12);
        assert_eq!(cert.pieces, 1);
    }

    /// det J's Bernstein coefficients from sampling at the 15 lattice points and
    /// solving the Bernstein collocation system (nalgebra).
    fn sampled_coefficients(nodes: &[Point; 10]) -> Vec<f64> {
        let pts: Vec<[usize; 3]> = lattice(4).collect();
        let mut m = DMatrix::<f64>::zeros(15, 15);
        let mut v = DVector::<f64>::zeros(15);
        for (r, a) in pts.iter().enumerate() {
            let l = [a[0] as f64 / 4.0, a[1] as f64 / 4.0, a[2] as f64 / 4.0];
            v[r] = det_direct(nodes, l[1], l[2]);
            for (c, b) in pts.iter().enumerate() {
                m[(r, c)] = multinomial(*b)
                    * l[0].powi(b[0] as i32)
                    * l[1].powi(b[1] as i32)
                    * l[2].powi(b[2] as i32);
            }
        }
        m.lu()
            .solve(&v)
            .expect("Bernstein collocation matrix is invertible")
            .iter()
            .copied()
            .collect()
    }

    #[test]
    fn coefficients_agree_with_sampling() {
        for bulge in [0.0, 0.2, 0.6, 1.5] {
            let n = curved_element(bulge);
            let det = det_cubic(&n);
            let s = sampled_coefficients(&n);
            for (a, b) in det.coeffs().iter().zip(&s) {
                assert!((a - b).abs() < 1e-9, "bulge {bulge}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn typical_curved_element_is_certified() {
        let n = curved_element(0.2);
        let c = certify_element(Order::Cubic, &n, &CertifyOptions::DEFAULT).expect("10 nodes");
        assert!(c.is_certified(), "{c:?}");
        assert!(c.ratio() > 0.3 && c.ratio() < 1.0, "{c:?}");
        assert!(c.lower <= c.sampled_min && c.upper >= c.sampled_max);
    }

    #[test]
    fn edge_node_across_opposite_side_is_inverted() {
        let mut n = cubic_nodes(
            [
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(0.0, 1.0),
            ],
            None,
        );
        // push the first node of edge 0→1 far across the opposite corner
        n[3] = Point::new(0.3, 1.8);
        let c = certify_element(Order::Cubic, &n, &CertifyOptions::DEFAULT).expect("10 nodes");
        assert_eq!(c.validity, Validity::Inverted, "{c:?}");
        assert!(c.sampled_min < 0.0 && c.ratio() < 0.0);
    }

    #[test]
    fn near_invalid_needs_subdivision() {
        // an edge bulging into the element, centre node displaced (to the mean of the
        // other nine, the thesis's rule): a negative coefficient, det J still positive
        let curved_element = |bulge| {
            let mut n = curved_element(bulge);
            n[9] = (n[..9]
                .iter()
                .fold(kurbo::Vec2::ZERO, |s, p| s + p.to_vec2())
                / 9.0)
                .to_point();
            n
        };
        let n = curved_element(-0.3);
        let det = det_cubic(&n);
        assert!(det.min_coeff() < 0.0);
        assert!(dense_min(&n, 60) > 0.0);
        let c = certify(&det, 0.0, &CertifyOptions::VALIDITY);
        assert!(c.is_certified() && c.pieces > 1, "{c:?}");
        // tightening refines the ratio bound upwards but never above the truth
        let t = certify(&det, 0.0, &CertifyOptions::DEFAULT);
        assert!(t.ratio() >= c.ratio() && t.lower <= dense_min(&n, 60));
        // bulging further inverts it
        let n = curved_element(-0.5);
        assert!(dense_min(&n, 60) < 0.0);
        let c = certify(&det_cubic(&n), 0.0, &CertifyOptions::DEFAULT);
        assert_eq!(c.validity, Validity::Inverted);
        // with no subdivision allowed, the negative coefficient is not a proof either way
        let n = curved_element(-0.3);
        let c = certify(
            &det_cubic(&n),
            0.0,
            &CertifyOptions {
                max_depth: 0,
                ..CertifyOptions::VALIDITY
            },
        );
        assert_eq!(c.validity, Validity::Uncertain);
    }

    fn dense_min(n: &[Point; 10], k: usize) -> f64 {
        let mut m = f64::INFINITY;
        for i in 0..=k {
            for j in 0..=k - i {
                m = m.min(det_direct(n, i as f64 / k as f64, j as f64 / k as f64));
            }
        }
        m
    }

    #[test]
    fn quadratic_det_matches_cubic_of_same_map() {
        // a quadratic edge is also a cubic one: elevate by sampling the quadratic map
        let e = CurvedEdge {
            edge: 1,
            curve: CubicBez::new((1.0, 0.0), (1.3, 0.3), (1.2, 0.7), (0.0, 1.0)),
            t0: 0.0,
            t1: 1.0,
        };
        let c = [
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(0.0, 1.0),
        ];
        let q = quadratic_nodes(c, Some(&e));
        let qnet = lagrange::quadratic_to_bezier(&q);
        let cub: [Point; 10] = std::array::from_fn(|i| {
            lagrange::eval_net(&qnet, 2, {
                let r = CUBIC_REF[i];
                [1.0 - r[0] - r[1], r[0], r[1]]
            })
        });
        let (dq, dc) = (det_quadratic(&q), det_cubic(&cub));
        for l in [[0.2, 0.3, 0.5], [0.7, 0.1, 0.2], [0.0, 0.5, 0.5]] {
            assert!((dq.eval(l) - dc.eval(l)).abs() < 1e-10);
        }
        assert!((area(&dq) - area(&dc)).abs() < 1e-12);
    }

    fn config() -> Config {
        Config {
            cases: 256,
            failure_persistence: None,
            rng_algorithm: RngAlgorithm::ChaCha,
            rng_seed: RngSeed::Fixed(0x5eed_c0de),
            ..Config::default()
        }
    }

    proptest! {
        #![proptest_config(config())]

        /// Random perturbations of a curved element, including near-degenerate
        /// ones: certified implies positive on a dense sample; a sampled negative
        /// value is never certified; coefficients match sampling.
        #[test]
        fn certified_implies_positive(
            d in proptest::collection::vec(-0.45f64..0.45, 20),
            bulge in -0.8f64..0.8,
            scale in prop_oneof![Just(1.0), Just(1e-6), Just(1e6)],
        ) {
            let mut n = curved_element(bulge);
            for (i, p) in n.iter_mut().enumerate().skip(3) {
                *p += Vec2::new(d[2 * i], d[2 * i + 1]) * 0.5;
            }
            let n = n.map(|p| (p.to_vec2() * scale + Vec2::new(100.0, -50.0) * scale).to_point());
            let det = det_cubic(&n);
            let s = sampled_coefficients(&n);
            let mag = det.coeffs().iter().fold(0.0f64, |m, c| m.max(c.abs()));
            for (a, b) in det.coeffs().iter().zip(&s) {
                prop_assert!((a - b).abs() <= 1e-7 * mag.max(1e-300));
            }
            let c = certify(&det, zero_abs(&n, 1e-12), &CertifyOptions::DEFAULT);
            let m = dense_min(&n, 40);
            if c.is_certified() {
                prop_assert!(m > 0.0, "certified but min {m}");
                prop_assert!(c.lower <= m * (1.0 + 1e-9));
            }
            if m < -1e-9 * mag {
                prop_assert!(!c.is_certified());
            }
            if c.validity == Validity::Inverted {
                prop_assert!(c.sampled_min < 0.0);
            }
        }

        /// Known inverted elements: a cubic triangle with one edge node pushed
        /// across the opposite corner (a negative det J at a dense sample proves
        /// it inverted) is never certified, and is reported inverted.
        #[test]
        fn known_inverted_is_never_certified(
            c in proptest::collection::vec(-0.3f64..0.3, 4),
            node in 3usize..9,
            push in 0.5f64..3.0,
            scale in prop_oneof![Just(1.0), Just(1e-6), Just(1e6)],
        ) {
            let corners = [
                Point::new(0.0, 0.0),
                Point::new(1.0 + c[0], c[1]),
                Point::new(c[2], 1.0 + c[3]),
            ];
            let mut n = cubic_nodes(corners, None);
            // node 3 + 2e, 4 + 2e lies on edge e; the opposite corner is (e + 2) % 3
            let opposite = corners[((node - 3) / 2 + 2) % 3];
            n[node] = opposite + (opposite - n[node]) * push;
            let n = n.map(|p| (p.to_vec2() * scale).to_point());
            let m = dense_min(&n, 40);
            prop_assume!(m < 0.0);
            let c = certify(&det_cubic(&n), zero_abs(&n, 1e-12), &CertifyOptions::DEFAULT);
            prop_assert!(!c.is_certified(), "{c:?}");
            prop_assert_eq!(c.validity, Validity::Inverted);
        }
    }
}
