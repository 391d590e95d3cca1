//! One Lagrange triangle of the curved mesh: its nodes from its corners and
//! the curve pieces of its edges, its certification, and its curved AMIPS
//! energy (thesis §4.4.2 "Splitting and Curving", "Curved Optimization",
//! §4.4.3 "Curved AMIPS"; docs/design.md "Curved elements").
//!
//! The same functions serve the curving stage (`build`) and the curved-mode
//! invariant of the local operations (`ops::invariants::curved`), so an
//! element is shaped and judged the same way everywhere.
//!
//! Nodes: an edge on a curve piece `[t0, t1]` of a cubic parent takes the curve
//! at the parameter thirds (cubic elements: the piece exactly) or at the
//! parameter midpoint (quadratic); when a corner is off its curve, the piece is
//! moved by the linear blend of the two corner offsets so the edge still ends
//! at its corners. Other edges are straight; the cubic centre node is
//! [`lagrange::cubic_centre`] of the other nine (exact for quadratic maps) plus an
//! optional offset (the fit's).
//!
//! Energy ([`amips`]): the conformal AMIPS `tr(JᵀJ) / (2 det J)` of the map
//! from the equilateral reference triangle, in the normalisation of
//! [`crate::element::energy::amips`] (1 for an equilateral straight triangle,
//! equal to it for any straight element), taken as the maximum over the 15
//! points of the degree-4 barycentric lattice of the reference triangle
//! (corners, edge quarter points, three interior points): `det J` is a
//! degree-4 polynomial, and the lattice is where its Bernstein coefficients
//! sit. `+∞` where `det J ≤ 0` at a sample.

use super::Order;
use super::bernstein::lattice;
use super::jacobian::{self, CertifyOptions};
use super::lagrange;
use kurbo::{Point, Vec2};

/// The gmsh edges of a triangle as corner pairs (0→1, 1→2, 2→0).
pub(crate) const EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];

/// Fractions of an edge where its inner nodes sit.
pub(crate) fn fractions(order: Order) -> &'static [f64] {
    match order {
        Order::Linear => &[],
        Order::Quadratic => &[0.5],
        Order::Cubic => &[1.0 / 3.0, 2.0 / 3.0],
    }
}

/// Straight inner nodes of the edge from `a` to `b`.
pub(crate) fn straight_inner(a: Point, b: Point, order: Order) -> Vec<Point> {
    fractions(order).iter().map(|&s| a.lerp(b, s)).collect()
}

/// The inner nodes (from `a` to `b`) of the edge whose corners `a`, `b` stand
/// for the curve `eval` (a parametrised curve, e.g. a feature's parent piece) at
/// `t[0]`, `t[1]`: the piece at the node fractions, moved by the blend of the
/// corner offsets (zero when the corners are on the curve).
pub(crate) fn piece_inner(
    eval: impl Fn(f64) -> Point,
    t: [f64; 2],
    a: Point,
    b: Point,
    order: Order,
) -> Vec<Point> {
    let (da, db) = (a - eval(t[0]), b - eval(t[1]));
    fractions(order)
        .iter()
        .map(|&s| eval(t[0] + s * (t[1] - t[0])) + (1.0 - s) * da + s * db)
        .collect()
}

/// The Lagrange nodes (gmsh order) of the triangle with `corners`, where
/// `inner[e]` gives the inner nodes of edge `e` (in the edge's direction,
/// `EDGES[e][0]` to `EDGES[e][1]`; `None` = straight) and `centre` offsets the
/// cubic centre node from [`lagrange::cubic_centre`] of the other nine.
pub(crate) fn nodes(
    order: Order,
    corners: [Point; 3],
    inner: [Option<&[Point]>; 3],
    centre: Vec2,
) -> Vec<Point> {
    let mut n = corners.to_vec();
    if order == Order::Linear {
        return n;
    }
    for (e, [i, j]) in EDGES.into_iter().enumerate() {
        match inner[e] {
            Some(pts) => n.extend_from_slice(pts),
            None => n.extend(straight_inner(corners[i], corners[j], order)),
        }
    }
    if order == Order::Cubic {
        n.push(lagrange::cubic_centre(&n) + centre);
    }
    n
}

/// The certificate of an element (`None` if `nodes` is not `order`'s count).
pub(crate) fn certificate(
    order: Order,
    nodes: &[Point],
    opts: &CertifyOptions,
) -> Option<jacobian::Certificate> {
    jacobian::certify_element(order, nodes, opts)
}

/// Whether the element is certified valid.
pub(crate) fn is_certified(order: Order, nodes: &[Point], opts: &CertifyOptions) -> bool {
    certificate(order, nodes, opts).is_some_and(|c| c.is_certified())
}

/// `1 / √3`.
const INV_SQRT3: f64 = 0.577_350_269_189_625_8;

/// AMIPS of the map whose derivatives along the reference axes `(1,0)` and
/// `(0,1)` (reference triangle `(0,0), (1,0), (0,1)`) are `dxi`, `deta`, with
/// the map composed from the equilateral reference triangle: 1 for an
/// equilateral image, `+∞` when `det ≤ 0`.
fn amips_of_jacobian(dxi: Vec2, deta: Vec2) -> f64 {
    // Equilateral (0,0), (1,0), (1/2, √3/2) onto the right reference triangle:
    // columns (1, 0) and (-1/√3, 2/√3).
    let u = dxi;
    let v = (2.0 * deta - dxi) * INV_SQRT3;
    let det = u.cross(v);
    if det <= 0.0 || !det.is_finite() {
        return f64::INFINITY;
    }
    (u.hypot2() + v.hypot2()) / (2.0 * det)
}

/// The curved AMIPS energy of a Lagrange element (see the module doc): the
/// maximum over the degree-4 lattice. `+∞` when `det J ≤ 0` at a sample or
/// `nodes` is not `order`'s node count.
pub fn amips(order: Order, nodes: &[Point]) -> f64 {
    if order == Order::Linear {
        let Ok(c) = <[Point; 3]>::try_from(nodes) else {
            return f64::INFINITY;
        };
        return amips_of_jacobian(c[1] - c[0], c[2] - c[0]);
    }
    let Some((net, _)) = lagrange::relative_bezier_array(order, nodes) else {
        return f64::INFINITY;
    };
    amips_of_net(order as usize, &net)
}

/// Sample points of [`amips`]: the degree-4 lattice.
const SAMPLES: usize = super::bernstein::len(4);

/// The Bernstein basis of degree `m` (1 or 2; lattice order, padded to 6) at
/// the samples: `BASIS[m - 1][s][i]`.
static BASIS: std::sync::LazyLock<[[[f64; 6]; SAMPLES]; 2]> = std::sync::LazyLock::new(|| {
    const FACT: [f64; 3] = [1.0, 1.0, 2.0];
    let mut t = [[[0.0; 6]; SAMPLES]; 2];
    for (m, table) in [1usize, 2].into_iter().zip(&mut t) {
        for (row, b) in table.iter_mut().zip(lattice(4)) {
            let l = b.map(|x| x as f64 / 4.0);
            for (v, a) in row.iter_mut().zip(lattice(m)) {
                let coeff = FACT[m] / (FACT[a[0]] * FACT[a[1]] * FACT[a[2]]);
                *v = coeff
                    * l[0].powi(a[0] as i32)
                    * l[1].powi(a[1] as i32)
                    * l[2].powi(a[2] as i32);
            }
        }
    }
    t
});

/// [`amips`] of the Bézier triangle `net` of degree `n` (2 or 3; lattice
/// order, relative to its first node): the derivative nets along the two
/// reference axes (degree `n − 1`) evaluated at the samples from [`BASIS`].
fn amips_of_net(n: usize, net: &[Point]) -> f64 {
    let idx = super::bernstein::index;
    let m = n - 1;
    let mut da = [Vec2::ZERO; 6];
    let mut dc = [Vec2::ZERO; 6];
    for (i, b) in lattice(m).enumerate() {
        let (j, k) = (b[1], b[2]);
        let base = net[idx(n, j, k)];
        da[i] = n as f64 * (net[idx(n, j + 1, k)] - base);
        dc[i] = n as f64 * (net[idx(n, j, k + 1)] - base);
    }
    let count = super::bernstein::len(m);
    let mut worst: f64 = 0.0;
    for row in &BASIS[m - 1] {
        let (mut a, mut c) = (Vec2::ZERO, Vec2::ZERO);
        for i in 0..count {
            a += row[i] * da[i];
            c += row[i] * dc[i];
        }
        worst = worst.max(amips_of_jacobian(a, c));
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::energy;
    use kurbo::{CubicBez, ParamCurve};

    fn tri() -> [Point; 3] {
        [
            Point::new(0.3, -0.2),
            Point::new(2.1, 0.4),
            Point::new(0.7, 1.9),
        ]
    }

    #[test]
    fn straight_element_energy_is_linear_amips() {
        let [a, b, c] = tri();
        let want = energy::amips(a, b, c);
        for order in [Order::Linear, Order::Quadratic, Order::Cubic] {
            let n = nodes(order, [a, b, c], [None; 3], Vec2::ZERO);
            let got = amips(order, &n);
            assert!(
                (got - want).abs() <= 1e-12 * want,
                "{order:?}: {got} vs {want}"
            );
        }
        let h = 3f64.sqrt() / 2.0;
        let eq = [
            Point::new(5.0, 5.0),
            Point::new(6.0, 5.0),
            Point::new(5.5, 5.0 + h),
        ];
        let n = nodes(Order::Cubic, eq, [None; 3], Vec2::ZERO);
        assert!((amips(Order::Cubic, &n) - 1.0).abs() < 1e-12);
        // Clockwise: infinite.
        let n = nodes(Order::Cubic, [a, c, b], [None; 3], Vec2::ZERO);
        assert_eq!(amips(Order::Cubic, &n), f64::INFINITY);
        assert_eq!(amips(Order::Cubic, &n[..9]), f64::INFINITY);
    }

    #[test]
    fn bending_raises_the_energy_and_inverting_makes_it_infinite() {
        let (a, b) = (Point::new(0.0, 0.0), Point::new(1.0, 0.0));
        let h = 3f64.sqrt() / 2.0;
        let c = Point::new(0.5, h);
        let straight = amips(
            Order::Cubic,
            &nodes(Order::Cubic, [a, b, c], [None; 3], Vec2::ZERO),
        );
        let mut last = straight;
        for bulge in [0.1, 0.3, 0.6] {
            let curve = CubicBez::new(a, Point::new(0.3, -bulge), Point::new(0.7, -bulge), b);
            let inner = piece_inner(|t| curve.eval(t), [0.0, 1.0], a, b, Order::Cubic);
            let n = nodes(
                Order::Cubic,
                [a, b, c],
                [Some(&inner), None, None],
                Vec2::ZERO,
            );
            let e = amips(Order::Cubic, &n);
            assert!(e > last, "{bulge}: {e} vs {last}");
            assert!(is_certified(Order::Cubic, &n, &CertifyOptions::DEFAULT));
            last = e;
        }
        // A bulge through the opposite corner inverts the element.
        let curve = CubicBez::new(a, Point::new(0.3, 1.5), Point::new(0.7, 1.5), b);
        let inner = piece_inner(|t| curve.eval(t), [0.0, 1.0], a, b, Order::Cubic);
        let n = nodes(
            Order::Cubic,
            [a, b, c],
            [Some(&inner), None, None],
            Vec2::ZERO,
        );
        assert_eq!(amips(Order::Cubic, &n), f64::INFINITY);
        assert!(!is_certified(Order::Cubic, &n, &CertifyOptions::DEFAULT));
    }

    #[test]
    fn piece_inner_follows_offset_corners() {
        let curve = CubicBez::new((0.0, 0.0), (1.0, 1.0), (2.0, 1.0), (3.0, 0.0));
        let p = |t| curve.eval(t);
        let (a, b) = (p(0.2), p(0.8));
        let on = piece_inner(p, [0.2, 0.8], a, b, Order::Cubic);
        assert!((on[0] - p(0.4)).hypot() < 1e-15);
        let shift = Vec2::new(0.0, 0.3);
        let off = piece_inner(p, [0.2, 0.8], a + shift, b + shift, Order::Cubic);
        assert!((off[1] - (p(0.6) + shift)).hypot() < 1e-15);
        assert_eq!(piece_inner(p, [0.2, 0.8], a, b, Order::Quadratic).len(), 1);
    }

    #[test]
    fn nodes_agree_with_lagrange_and_offset_the_quadratic_exact_centre() {
        // The same curved element through `nodes` (any edge, either direction) and
        // through `lagrange::cubic_nodes`; the offset moves the centre from that base.
        let curve = CubicBez::new((0.0, 0.0), (0.4, -0.5), (1.4, -0.3), (2.0, 0.3));
        let (t0, t1) = (0.1, 0.8);
        let p = |t| curve.eval(t);
        let apex = Point::new(0.9, 1.3);
        for edge in 0..3 {
            let [i, j] = EDGES[edge];
            let mut corners = [apex; 3];
            corners[i] = p(t0);
            corners[j] = p(t1);
            let inner = piece_inner(p, [t0, t1], corners[i], corners[j], Order::Cubic);
            let mut pieces: [Option<&[Point]>; 3] = [None; 3];
            pieces[edge] = Some(&inner);
            let e = lagrange::CurvedEdge {
                edge,
                curve,
                t0,
                t1,
            };
            let want = lagrange::cubic_nodes(corners, Some(&e));
            let got = nodes(Order::Cubic, corners, pieces, Vec2::ZERO);
            for (k, (g, w)) in got.iter().zip(&want).enumerate() {
                assert!((*g - *w).hypot() < 1e-14, "edge {edge} node {k}");
            }
            let off = Vec2::new(0.01, -0.02);
            let moved = nodes(Order::Cubic, corners, pieces, off);
            assert!((moved[9] - (want[9] + off)).hypot() < 1e-14);
            assert_eq!(moved[..9], got[..9]);
            // quadratic: the edge node is the piece's parameter midpoint exactly
            let inner2 = piece_inner(p, [t0, t1], corners[i], corners[j], Order::Quadratic);
            assert!((inner2[0] - p(0.5 * (t0 + t1))).hypot() < 1e-15);
        }
    }
}
