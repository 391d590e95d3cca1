//! Lagrange nodes of quadratic and cubic triangles, in gmsh's order, and their
//! exact conversion to and from Bézier control nets (thesis §4.4.2 "Splitting and
//! Curving", §4.4.3 "Cubic Lagrange Bases"; docs/design.md "Curved elements").
//!
//! Node order (reference triangle `(0,0), (1,0), (0,1)`, coordinates `ξ, η`):
//! - cubic, gmsh type 21: corners 0, 1, 2; nodes 3, 4 at 1/3, 2/3 of edge 0→1;
//!   5, 6 on edge 1→2; 7, 8 on edge 2→0; node 9 at the centre `(1/3, 1/3)`;
//! - quadratic, gmsh type 9: corners 0, 1, 2; midpoints of edges 0→1, 1→2, 2→0.
//!
//! A curved edge stands for a piece `[t0, t1]` of a cubic Bézier `c` (`t0` at the
//! edge's first corner). Cubic elements take `c` at the parameter thirds of the
//! piece, so the element's edge *is* the piece exactly (a cubic reparametrised
//! linearly is still a cubic, and four samples determine it). Quadratic elements
//! take `c` at the parameter midpoint: the edge is the quadratic interpolating the
//! piece at `t0`, `(t0 + t1)/2`, `t1`, an approximation whose error is the caller's
//! to judge. Straight edges take their linear points.
//!
//! The cubic centre node is [`cubic_centre`]: `Σ(edge nodes)/4 − Σ(corners)/6`. It is
//! exact for quadratic maps (when the other nine nodes sample a quadratic map, it is
//! that map's value at the centroid), so the interior of a cubic element with a curved
//! edge is `O(h³)` from the smooth map the edge comes from. The thesis's mean of the
//! nine reproduces only affine maps: its centre is `O(h²)` off, which capped P3 finite
//! elements on our meshes at the H1 rate 2 (`tests/fem_convergence.rs` measures the rates).
//!
//! The control net of a degree-`n` triangle lists the control points in the
//! lattice order of `curve::bernstein` (`(n − j − k, j, k)` ↔ weights of corners
//! 0, 1, 2). The conversions are the exact inverse linear maps (closed forms with
//! rational constants, not a fitted solve); they round-trip to rounding error.

use kurbo::{CubicBez, ParamCurve, Point};

/// A curved edge of a triangle: which edge, and the curve piece it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvedEdge {
    /// The edge: 0 is corner 0→1, 1 is 1→2, 2 is 2→0.
    pub edge: usize,
    /// The whole feature curve.
    pub curve: CubicBez,
    /// Parameter of the edge's first corner (`c(t0)` is that corner).
    pub t0: f64,
    /// Parameter of the edge's second corner; may be smaller than `t0`.
    pub t1: f64,
}

impl CurvedEdge {
    /// The curve at fraction `s` of the piece (`s = 0` at the first corner).
    pub fn at(&self, s: f64) -> Point {
        self.curve.eval(self.t0 + s * (self.t1 - self.t0))
    }
}

/// Corner pairs of the edges 0→1, 1→2, 2→0.
const EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];

/// The ten cubic nodes (gmsh type 21) of the triangle `corners` (counter-clockwise),
/// with at most one curved edge.
///
/// The corners are used as given: the caller keeps them on the curve (docs/design.md
/// "Invariants" 4), so `curved.at(0)` and `curved.at(1)` should equal the edge's corners.
/// An out-of-range `curved.edge` is treated as no curved edge.
pub fn cubic_nodes(corners: [Point; 3], curved: Option<&CurvedEdge>) -> [Point; 10] {
    let mut n = [Point::ZERO; 10];
    n[..3].copy_from_slice(&corners);
    for (e, [a, b]) in EDGES.into_iter().enumerate() {
        let (p, q) = match curved {
            Some(c) if c.edge == e => (c.at(1.0 / 3.0), c.at(2.0 / 3.0)),
            _ => (
                corners[a].lerp(corners[b], 1.0 / 3.0),
                corners[a].lerp(corners[b], 2.0 / 3.0),
            ),
        };
        n[3 + 2 * e] = p;
        n[4 + 2 * e] = q;
    }
    n[9] = cubic_centre(&n[..9]);
    n
}

/// The cubic centre node (gmsh node 9, reference point `(1/3, 1/3)`) from the other
/// nine nodes `n` (gmsh order: corners 0–2, edge nodes 3–8):
/// `Σ(edge nodes)/4 − Σ(corners)/6`.
///
/// The rule is exact for quadratic maps: if the nine nodes are any quadratic map
/// `x(ξ, η)` sampled at the cubic Lagrange points, the result is `x(1/3, 1/3)`.
/// Proof: both sides are linear in `x`, so checking the six monomials suffices;
/// for `1`: `6/4 − 3/6 = 1`; for `ξ` (corners sum 1, edge nodes sum 2):
/// `2/4 − 1/6 = 1/3`; for `ξ²` (corners 1, edge nodes `10/9`): `10/36 − 1/6 = 1/9`;
/// for `ξη` (corners 0, edge nodes `4/9`): `1/9`; `η`, `η²` by symmetry. The
/// coefficients sum to 1, so the rule is evaluated relative to corner 0 (no
/// cancellation far from the origin). Straight elements get their centroid.
///
/// # Panics
/// If `n` has fewer than nine points.
pub fn cubic_centre(n: &[Point]) -> Point {
    let o = n[0].to_vec2();
    let corners = (n[1] - n[0]) + (n[2] - n[0]);
    let edges = n[3..9]
        .iter()
        .fold(kurbo::Vec2::ZERO, |s, p| s + (p.to_vec2() - o));
    (o + edges / 4.0 - corners / 6.0).to_point()
}

/// The six quadratic nodes (gmsh type 9) of the triangle `corners`, with at most
/// one curved edge, which takes the curve at the piece's parameter midpoint.
pub fn quadratic_nodes(corners: [Point; 3], curved: Option<&CurvedEdge>) -> [Point; 6] {
    let mut n = [Point::ZERO; 6];
    n[..3].copy_from_slice(&corners);
    for (e, [a, b]) in EDGES.into_iter().enumerate() {
        n[3 + e] = match curved {
            Some(c) if c.edge == e => c.at(0.5),
            _ => corners[a].midpoint(corners[b]),
        };
    }
    n
}

/// Reference coordinates `(ξ, η)` of the cubic nodes, in gmsh order.
pub const CUBIC_REF: [[f64; 2]; 10] = [
    [0.0, 0.0],
    [1.0, 0.0],
    [0.0, 1.0],
    [1.0 / 3.0, 0.0],
    [2.0 / 3.0, 0.0],
    [2.0 / 3.0, 1.0 / 3.0],
    [1.0 / 3.0, 2.0 / 3.0],
    [0.0, 2.0 / 3.0],
    [0.0, 1.0 / 3.0],
    [1.0 / 3.0, 1.0 / 3.0],
];

/// Reference coordinates `(ξ, η)` of the quadratic nodes, in gmsh order.
pub const QUADRATIC_REF: [[f64; 2]; 6] = [
    [0.0, 0.0],
    [1.0, 0.0],
    [0.0, 1.0],
    [0.5, 0.0],
    [0.5, 0.5],
    [0.0, 0.5],
];

/// For each cubic lattice index (see `curve::bernstein`), the gmsh node at that
/// lattice point.
pub const CUBIC_NODE_OF_LATTICE: [usize; 10] = [0, 3, 4, 1, 8, 9, 5, 7, 6, 2];

/// For each quadratic lattice index, the gmsh node at that lattice point.
pub const QUADRATIC_NODE_OF_LATTICE: [usize; 6] = [0, 3, 1, 5, 4, 2];

/// Lattice index of the control point next to corner `a` on the edge a→b (cubic).
fn cubic_edge_lattice(a: usize, b: usize) -> usize {
    // weights: 2 on a, 1 on b
    let mut w = [0usize; 3];
    w[a] = 2;
    w[b] = 1;
    super::bernstein::index(3, w[1], w[2])
}

/// The inner Bézier control points of the cubic Lagrange edge through `a`
/// (t = 0), `p` (t = 1/3), `q` (t = 2/3) and `b` (t = 1): the inverse of
/// p = (8A + 12P + 6Q + B)/27, q = (A + 6P + 12Q + 8B)/27.
pub fn cubic_edge_controls(a: Point, p: Point, q: Point, b: Point) -> [Point; 2] {
    // per coordinate, divided (kurbo's `Vec2 / f64` multiplies by the reciprocal)
    let near_a = |a: f64, p: f64, q: f64, b: f64| (-5.0 * a + 18.0 * p - 9.0 * q + 2.0 * b) / 6.0;
    let near_b = |a: f64, p: f64, q: f64, b: f64| (2.0 * a - 9.0 * p + 18.0 * q - 5.0 * b) / 6.0;
    [
        Point::new(near_a(a.x, p.x, q.x, b.x), near_a(a.y, p.y, q.y, b.y)),
        Point::new(near_b(a.x, p.x, q.x, b.x), near_b(a.y, p.y, q.y, b.y)),
    ]
}

/// The Bézier control point of the quadratic Lagrange edge through `a` (t = 0),
/// `m` (t = 1/2) and `b` (t = 1): `2m − (a + b)/2`.
pub fn quadratic_edge_control(a: Point, m: Point, b: Point) -> Point {
    Point::new(2.0 * m.x - 0.5 * (a.x + b.x), 2.0 * m.y - 0.5 * (a.y + b.y))
}

/// The cubic Bézier control net (lattice order) of the cubic Lagrange triangle `nodes`.
pub fn cubic_to_bezier(nodes: &[Point; 10]) -> [Point; 10] {
    let v = |i: usize| nodes[i].to_vec2();
    let mut b = [kurbo::Vec2::ZERO; 10];
    // corners
    b[super::bernstein::index(3, 0, 0)] = v(0);
    b[super::bernstein::index(3, 3, 0)] = v(1);
    b[super::bernstein::index(3, 0, 3)] = v(2);
    let mut edge_sum = kurbo::Vec2::ZERO;
    for (e, [a, c]) in EDGES.into_iter().enumerate() {
        // Lagrange values p at 1/3 (near a), q at 2/3; as `cubic_edge_controls`,
        // in the Vec2 arithmetic the certification has always used.
        let (pa, pc) = (v(a), v(c));
        let (p, q) = (v(3 + 2 * e), v(4 + 2 * e));
        let near_a = (-5.0 * pa + 18.0 * p - 9.0 * q + 2.0 * pc) / 6.0;
        let near_c = (2.0 * pa - 9.0 * p + 18.0 * q - 5.0 * pc) / 6.0;
        b[cubic_edge_lattice(a, c)] = near_a;
        b[cubic_edge_lattice(c, a)] = near_c;
        edge_sum += near_a + near_c;
    }
    // centre value = (Σ corners + 3 Σ edge controls + 6 b111) / 27
    let corners = v(0) + v(1) + v(2);
    b[super::bernstein::index(3, 1, 1)] = (27.0 * v(9) - corners - 3.0 * edge_sum) / 6.0;
    b.map(|p| p.to_point())
}

/// The cubic Lagrange nodes (gmsh order) of the cubic Bézier triangle `net`.
pub fn bezier_to_cubic(net: &[Point; 10]) -> [Point; 10] {
    let mut n = [Point::ZERO; 10];
    for (li, a) in super::bernstein::lattice(3).enumerate() {
        let l = [a[0] as f64 / 3.0, a[1] as f64 / 3.0, a[2] as f64 / 3.0];
        n[CUBIC_NODE_OF_LATTICE[li]] = eval_net(net, 3, l);
    }
    n
}

/// The Bézier control net (lattice order) of a quadratic or cubic Lagrange triangle
/// (`nodes` in gmsh order), translated so that node 0 is the origin (no cancellation far
/// from it). `None` for the linear order or a wrong node count.
pub fn relative_bezier_net(
    order: crate::element::Order,
    nodes: &[Point],
) -> Option<Vec<kurbo::Vec2>> {
    let (net, len) = relative_bezier_array(order, nodes)?;
    Some(net[..len].iter().map(|p| p.to_vec2()).collect())
}

/// [`relative_bezier_net`] without allocating: the net in the first `len`
/// entries (6 quadratic, 10 cubic) of a fixed array.
pub(crate) fn relative_bezier_array(
    order: crate::element::Order,
    nodes: &[Point],
) -> Option<([Point; 10], usize)> {
    use crate::element::Order;
    let o = nodes.first()?.to_vec2();
    let mut net = [Point::ZERO; 10];
    let len = match order {
        Order::Linear => return None,
        Order::Quadratic => {
            let q = quadratic_to_bezier(&<[Point; 6]>::try_from(nodes).ok()?.map(|p| p - o));
            net[..6].copy_from_slice(&q);
            6
        }
        Order::Cubic => {
            net = cubic_to_bezier(&<[Point; 10]>::try_from(nodes).ok()?.map(|p| p - o));
            10
        }
    };
    Some((net, len))
}

/// The quadratic Bézier control net (lattice order) of the quadratic Lagrange triangle `nodes`.
pub fn quadratic_to_bezier(nodes: &[Point; 6]) -> [Point; 6] {
    let v = |i: usize| nodes[i].to_vec2();
    let mut b = [Point::ZERO; 6];
    b[super::bernstein::index(2, 0, 0)] = nodes[0];
    b[super::bernstein::index(2, 2, 0)] = nodes[1];
    b[super::bernstein::index(2, 0, 2)] = nodes[2];
    for (e, [a, c]) in EDGES.into_iter().enumerate() {
        // midpoint m = (A + 2P + C)/4
        let mut w = [0usize; 3];
        w[a] = 1;
        w[c] = 1;
        let p = 2.0 * v(3 + e) - 0.5 * (v(a) + v(c));
        b[super::bernstein::index(2, w[1], w[2])] = p.to_point();
    }
    b
}

/// The quadratic Lagrange nodes (gmsh order) of the quadratic Bézier triangle `net`.
pub fn bezier_to_quadratic(net: &[Point; 6]) -> [Point; 6] {
    let mut n = [Point::ZERO; 6];
    for (li, a) in super::bernstein::lattice(2).enumerate() {
        let l = [a[0] as f64 / 2.0, a[1] as f64 / 2.0, a[2] as f64 / 2.0];
        n[QUADRATIC_NODE_OF_LATTICE[li]] = eval_net(net, 2, l);
    }
    n
}

/// Point of a degree-`n` Bézier triangle (control net in lattice order) at
/// barycentric coordinates `l`.
pub fn eval_net(net: &[Point], n: usize, l: [f64; 3]) -> Point {
    let x: Vec<f64> = net.iter().map(|p| p.x).collect();
    let y: Vec<f64> = net.iter().map(|p| p.y).collect();
    let bx = super::bernstein::BernsteinTri::new(&x);
    let by = super::bernstein::BernsteinTri::new(&y);
    debug_assert_eq!(bx.degree(), n, "net size matches degree");
    Point::new(bx.eval(l), by.eval(l))
}

/// The map of a cubic Lagrange triangle at reference point `(ξ, η)`, evaluated
/// directly with the ten Lagrange basis functions of thesis §4.4.3 (independent
/// of the Bézier form; used by tests and checks).
pub fn eval_cubic_lagrange(nodes: &[Point; 10], xi: f64, eta: f64) -> Point {
    let (x, y) = (xi, eta);
    let l = [
        -0.5 * (3.0 * y - 1.0 + 3.0 * x) * (y - 1.0 + x) * (3.0 * y - 2.0 + 3.0 * x),
        0.5 * x * (9.0 * x * x - 9.0 * x + 2.0),
        0.5 * y * (9.0 * y * y - 9.0 * y + 2.0),
        4.5 * x * (x + y - 1.0) * (3.0 * x + 3.0 * y - 2.0),
        -4.5 * x * (3.0 * x * x + 3.0 * x * y - 4.0 * x - y + 1.0),
        4.5 * x * y * (3.0 * x - 1.0),
        4.5 * x * y * (3.0 * y - 1.0),
        -4.5 * y * (3.0 * x * y - x + 3.0 * y * y - 4.0 * y + 1.0),
        4.5 * y * (x + y - 1.0) * (3.0 * x + 3.0 * y - 2.0),
        -27.0 * x * y * (x + y - 1.0),
    ];
    let (mut px, mut py) = (0.0, 0.0);
    for (p, w) in nodes.iter().zip(l) {
        px += w * p.x;
        py += w * p.y;
    }
    Point::new(px, py)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngAlgorithm, RngSeed};

    fn tri() -> [Point; 3] {
        [
            Point::new(0.0, 0.0),
            Point::new(2.0, 0.2),
            Point::new(0.5, 1.7),
        ]
    }

    fn arc_edge() -> CurvedEdge {
        // a bulging cubic from corner 0 to corner 1, piece [0.2, 0.7] of a longer curve
        let c = CubicBez::new((-0.5, -0.3), (0.5, -0.8), (1.8, -0.6), (2.6, 0.6));
        let (t0, t1) = (0.2, 0.7);
        CurvedEdge {
            edge: 0,
            curve: c,
            t0,
            t1,
        }
    }

    fn close(a: Point, b: Point, tol: f64) -> bool {
        (a - b).hypot() <= tol
    }

    #[test]
    fn basis_is_interpolating_and_matches_ref_nodes() {
        // each basis function is 1 at its node and 0 at the others
        for i in 0..10 {
            let mut nodes = [Point::ZERO; 10];
            nodes[i] = Point::new(1.0, 0.0);
            for (j, r) in CUBIC_REF.iter().enumerate() {
                let v = eval_cubic_lagrange(&nodes, r[0], r[1]).x;
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-12, "l{i} at node {j}: {v}");
            }
        }
    }

    #[test]
    fn lattice_maps_agree_with_reference_nodes() {
        for (li, a) in super::super::bernstein::lattice(3).enumerate() {
            let r = CUBIC_REF[CUBIC_NODE_OF_LATTICE[li]];
            assert!((r[0] - a[1] as f64 / 3.0).abs() < 1e-15);
            assert!((r[1] - a[2] as f64 / 3.0).abs() < 1e-15);
        }
        for (li, a) in super::super::bernstein::lattice(2).enumerate() {
            let r = QUADRATIC_REF[QUADRATIC_NODE_OF_LATTICE[li]];
            assert!((r[0] - a[1] as f64 / 2.0).abs() < 1e-15);
            assert!((r[1] - a[2] as f64 / 2.0).abs() < 1e-15);
        }
    }

    #[test]
    fn straight_cubic_nodes_are_linear() {
        let c = tri();
        let n = cubic_nodes(c, None);
        for (i, r) in CUBIC_REF.iter().enumerate() {
            let want = c[0] + r[0] * (c[1] - c[0]) + r[1] * (c[2] - c[0]);
            assert!(close(n[i], want, 1e-12), "node {i}");
        }
        let q = quadratic_nodes(c, None);
        for (i, r) in QUADRATIC_REF.iter().enumerate() {
            let want = c[0] + r[0] * (c[1] - c[0]) + r[1] * (c[2] - c[0]);
            assert!(close(q[i], want, 1e-12), "node {i}");
        }
    }

    #[test]
    fn curved_cubic_edge_reproduces_the_piece_exactly() {
        let e = arc_edge();
        let c = [e.at(0.0), e.at(1.0), Point::new(0.8, 1.5)];
        let n = cubic_nodes(c, Some(&e));
        // the element's edge 0→1 is (ξ = s, η = 0); it must be the curve at t0 + s (t1 − t0)
        for i in 0..=20 {
            let s = i as f64 / 20.0;
            let p = eval_cubic_lagrange(&n, s, 0.0);
            assert!(close(p, e.at(s), 1e-12), "s {s}: {p:?} vs {:?}", e.at(s));
        }
        // centre: Σ(edge nodes)/4 − Σ(corners)/6
        let sum =
            |r: std::ops::Range<usize>| n[r].iter().fold(kurbo::Vec2::ZERO, |s, p| s + p.to_vec2());
        let m = sum(3..9) / 4.0 - sum(0..3) / 6.0;
        assert!(close(n[9], m.to_point(), 1e-14));
    }

    #[test]
    fn reversed_and_other_edges() {
        let mut e = arc_edge();
        // the same piece on edge 1→2 walked backwards
        std::mem::swap(&mut e.t0, &mut e.t1);
        e.edge = 1;
        let c = [Point::new(0.8, 1.5), e.at(0.0), e.at(1.0)];
        let n = cubic_nodes(c, Some(&e));
        assert!(close(n[5], e.at(1.0 / 3.0), 1e-15));
        assert!(close(n[6], e.at(2.0 / 3.0), 1e-15));
        // edge 1→2 is (1 − s, s)
        for i in 0..=10 {
            let s = i as f64 / 10.0;
            assert!(close(eval_cubic_lagrange(&n, 1.0 - s, s), e.at(s), 1e-12));
        }
        let q = quadratic_nodes(c, Some(&e));
        assert!(close(q[4], e.at(0.5), 1e-15));
    }

    #[test]
    fn conversions_round_trip() {
        let e = arc_edge();
        let c = [e.at(0.0), e.at(1.0), Point::new(0.8, 1.5)];
        let mut n = cubic_nodes(c, Some(&e));
        n[9] += kurbo::Vec2::new(0.05, -0.02); // a general centre
        let net = cubic_to_bezier(&n);
        let back = bezier_to_cubic(&net);
        for i in 0..10 {
            assert!(close(n[i], back[i], 1e-12), "node {i}");
        }
        // the net evaluates to the Lagrange map everywhere
        for (xi, eta) in [(0.1, 0.2), (0.5, 0.25), (0.3, 0.6)] {
            let l = [1.0 - xi - eta, xi, eta];
            assert!(close(
                eval_net(&net, 3, l),
                eval_cubic_lagrange(&n, xi, eta),
                1e-12
            ));
        }
        // the curved edge's control points are the piece's own control points
        let piece = e.curve.subsegment(e.t0..e.t1);
        let b = |j, k| net[super::super::bernstein::index(3, j, k)];
        assert!(close(b(1, 0), piece.p1, 1e-12));
        assert!(close(b(2, 0), piece.p2, 1e-12));

        let q = quadratic_nodes(c, Some(&e));
        let qnet = quadratic_to_bezier(&q);
        let qback = bezier_to_quadratic(&qnet);
        for i in 0..6 {
            assert!(close(q[i], qback[i], 1e-12), "node {i}");
        }
    }

    /// A quadratic map `x(ξ, η) = a + b ξ + c η + d ξ² + e ξη + f η²` (coefficients as
    /// points).
    fn quadratic_map(k: &[Point; 6], xi: f64, eta: f64) -> Point {
        let m = [1.0, xi, eta, xi * xi, xi * eta, eta * eta];
        let v = k
            .iter()
            .zip(m)
            .fold(kurbo::Vec2::ZERO, |s, (p, w)| s + w * p.to_vec2());
        v.to_point()
    }

    /// The thesis's rule, the mean of the nine other nodes (kept to show the difference).
    fn mean_of_nine(n: &[Point; 10]) -> Point {
        (n[..9]
            .iter()
            .fold(kurbo::Vec2::ZERO, |s, p| s + p.to_vec2())
            / 9.0)
            .to_point()
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

        /// For any quadratic map sampled at the nine boundary nodes, the centre rule
        /// returns the map at the centroid, and the cubic element is that map everywhere.
        #[test]
        fn centre_rule_reproduces_quadratic_maps(
            k in prop::array::uniform6(
                (-100.0f64..100.0, -100.0f64..100.0).prop_map(|(x, y)| Point::new(x, y))),
            shift in (-1e4f64..1e4, -1e4f64..1e4),
        ) {
            let mut k = k;
            k[0] += kurbo::Vec2::new(shift.0, shift.1);
            let mut n = CUBIC_REF.map(|r| quadratic_map(&k, r[0], r[1]));
            let want = n[9];
            n[9] = Point::ZERO;
            let got = cubic_centre(&n[..9]);
            let scale = k.iter().map(|p| p.to_vec2().hypot()).sum::<f64>();
            prop_assert!((got - want).hypot() <= 1e-14 * scale, "{:?} vs {:?}", got, want);
            n[9] = got;
            for (xi, eta) in [(0.1, 0.2), (0.5, 0.25), (0.3, 0.6), (0.05, 0.9)] {
                let p = eval_cubic_lagrange(&n, xi, eta);
                let q = quadratic_map(&k, xi, eta);
                prop_assert!((p - q).hypot() <= 1e-13 * scale);
            }
        }
    }

    #[test]
    fn parabola_edge_element_is_its_quadratic_map() {
        // The edge 0→1 on the parabola y = x² (a degree-elevated quadratic, so an exact
        // cubic piece), edges 1→2 and 2→0 straight: the element is the quadratic
        // element on the same six points, and the centre is that map's centroid.
        for h in [0.4, 0.1, 0.01] {
            let q0 = Point::new(-h, h * h);
            let q2 = Point::new(h, h * h);
            let q1 = Point::new(0.0, -h * h); // control point: the parabola's tangents meet here
            let curve = CubicBez::new(q0, q0.lerp(q1, 2.0 / 3.0), q2.lerp(q1, 2.0 / 3.0), q2);
            let e = CurvedEdge {
                edge: 0,
                curve,
                t0: 0.0,
                t1: 1.0,
            };
            let corners = [q0, q2, Point::new(0.2 * h, 1.5 * h)];
            let n = cubic_nodes(corners, Some(&e));
            let quad = quadratic_nodes(corners, Some(&e));
            let centroid = bezier_to_quadratic_value(&quad, [1.0 / 3.0; 3]);
            assert!(close(n[9], centroid, 1e-15), "h {h}");
            // the old mean is off by a multiple of the sagitta h²
            assert!(
                (mean_of_nine(&n) - centroid).hypot() > 0.05 * h * h,
                "h {h}"
            );
        }
    }

    /// The quadratic Lagrange element `nodes` at barycentric coordinates `l`.
    fn bezier_to_quadratic_value(nodes: &[Point; 6], l: [f64; 3]) -> Point {
        eval_net(&quadratic_to_bezier(nodes), 2, l)
    }

    /// Third derivatives of the cubic map `n` (along ξξξ, ξξη, ξηη, ηηη): the third
    /// differences of its Bézier net (times 6); the largest length.
    fn third_derivative(n: &[Point; 10]) -> f64 {
        let net = cubic_to_bezier(n);
        let idx = super::super::bernstein::index;
        let b = |j, k| net[idx(3, j, k)].to_vec2();
        let d3 = [
            b(3, 0) - 3.0 * b(2, 0) + 3.0 * b(1, 0) - b(0, 0),
            b(2, 1) - 2.0 * b(1, 1) + b(0, 1) - (b(2, 0) - 2.0 * b(1, 0) + b(0, 0)),
            b(1, 2) - 2.0 * b(1, 1) + b(1, 0) - (b(0, 2) - 2.0 * b(0, 1) + b(0, 0)),
            b(0, 3) - 3.0 * b(0, 2) + 3.0 * b(0, 1) - b(0, 0),
        ];
        6.0 * d3.iter().map(|v| v.hypot()).fold(0.0, f64::max)
    }

    /// The image of the small triangle of size `h` near `(0.3, 0.2)` under the smooth
    /// map `F(u, v) = exp(u + iv)` (curvature O(1) everywhere, all three edges curved):
    /// the distance of the centre node from `F` at the centroid, by the new rule and by
    /// the mean of nine.
    fn smooth_map_centre_errors(h: f64) -> (f64, f64) {
        let f = |u: f64, v: f64| Point::new(u.exp() * v.cos(), u.exp() * v.sin());
        let (u0, v0) = (0.3, 0.2);
        // a reference triangle scaled by h and sheared, in (u, v)
        let map = |xi: f64, eta: f64| f(u0 + h * (xi + 0.3 * eta), v0 + h * (0.2 * xi + eta));
        let mut n = CUBIC_REF.map(|r| map(r[0], r[1]));
        let want = n[9];
        n[9] = cubic_centre(&n[..9]);
        ((n[9] - want).hypot(), (mean_of_nine(&n) - want).hypot())
    }

    #[test]
    fn centre_is_third_order_on_a_smooth_map() {
        let (new_a, old_a) = smooth_map_centre_errors(0.1);
        let (new_b, old_b) = smooth_map_centre_errors(0.05);
        // halving the size divides an O(h³) error by 8, an O(h²) one by 4
        let (r_new, r_old) = (new_a / new_b, old_a / old_b);
        assert!(r_new > 7.0, "new rule ratio {r_new} ({new_a:e}, {new_b:e})");
        assert!(
            r_old < 4.5,
            "mean-of-nine ratio {r_old} ({old_a:e}, {old_b:e})"
        );
        assert!(new_b < 0.25 * old_b, "{new_b:e} vs {old_b:e}");
    }

    /// The cubic element with its edge 0→1 on an arc of the unit circle of angle
    /// `theta` (a cubic Bézier arc, radial error ~ 1e-6 θ⁶) and its third corner inside
    /// at distance ~ θ: the distance of its centre node from the centroid of the
    /// quadratic element on the same arc (a map with the right derivative scaling), and
    /// the largest third derivative of the cubic map with the new centre and with the
    /// mean of nine.
    fn arc_element(theta: f64) -> (f64, f64, f64) {
        let k = 4.0 / 3.0 * (theta / 4.0).tan();
        let (s, c) = theta.sin_cos();
        let curve = CubicBez::new((1.0, 0.0), (1.0, k), (c + k * s, s - k * c), (c, s));
        let e = CurvedEdge {
            edge: 0,
            curve,
            t0: 0.0,
            t1: 1.0,
        };
        let r = 1.0 - 0.9 * theta;
        let apex = Point::new(r * (theta / 2.0).cos(), r * (theta / 2.0).sin());
        let corners = [curve.p0, curve.p3, apex];
        let mut n = cubic_nodes(corners, Some(&e));
        let quad = quadratic_nodes(corners, Some(&e));
        let centroid = bezier_to_quadratic_value(&quad, [1.0 / 3.0; 3]);
        let dist = (n[9] - centroid).hypot();
        let d3_new = third_derivative(&n);
        n[9] = mean_of_nine(&n);
        (dist, d3_new, third_derivative(&n))
    }

    #[test]
    fn arc_element_is_third_order() {
        let (dist_a, new_a, old_a) = arc_element(0.2);
        let (dist_b, new_b, old_b) = arc_element(0.1);
        // With one cubic edge (others straight) the rule puts the centre exactly at the
        // quadratic element's centroid: for an edge deviation d(s) = s(1−s)(α + βs),
        // (d(1/3) + d(2/3))/4 = (2α + β)/18 = (4/9) d(1/2).
        assert!(dist_a < 1e-15 && dist_b < 1e-15, "{dist_a:e} {dist_b:e}");
        // The element map's third derivatives (which P3 error estimates need to be
        // O(h³)) scale as θ³ with the new centre, as θ² with the mean of nine.
        let (r_new, r_old) = (new_a / new_b, old_a / old_b);
        assert!(r_new > 7.0, "new rule ratio {r_new} ({new_a:e}, {new_b:e})");
        assert!(
            r_old < 4.5,
            "mean-of-nine ratio {r_old} ({old_a:e}, {old_b:e})"
        );
        assert!(new_b < 0.1 * old_b, "{new_b:e} vs {old_b:e}");
    }
}
