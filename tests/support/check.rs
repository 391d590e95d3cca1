//! An independent mesh checker for the tests (shares no code with `src/curve` or
//! `src/output`).
//!
//! Checks: exact counter-clockwise orientation (robust's `orient2d`), conforming
//! and manifold edges (high-order edge nodes included), no duplicate nodes, every
//! element in a named physical group, feature lines on triangle edges, and for
//! quadratic and cubic triangles a positive-Jacobian certificate: the Jacobian
//! determinant is a polynomial of degree 2(p−1); its Bernstein coefficients are
//! computed from the element's Bézier control net, and where some coefficient is
//! not positive the reference triangle is subdivided (blossoming) a few levels.
//! The total area integrates that determinant exactly.

use super::reader::{Element, Msh, read_msh, type_info};
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// How many times a reference triangle may be split in four before an element
/// whose Jacobian is not certified counts as uncertain.
pub(crate) const MAX_DEPTH: u32 = 6;

/// The kinds of defect the checker reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum DefectKind {
    /// The file could not be read.
    Unreadable,
    /// Clockwise corners.
    Clockwise,
    /// Collinear corners.
    Degenerate,
    /// Jacobian determinant ≤ 0 somewhere (proven by a sample).
    Inverted,
    /// Positivity of the Jacobian not certified at `MAX_DEPTH`.
    Uncertain,
    /// An interior edge whose two sides disagree (orientation or edge nodes).
    NonConforming,
    /// An edge shared by more than two triangles.
    NonManifold,
    /// Two used nodes at the same position.
    DuplicateNode,
    /// An element without a physical group, or a group without a name.
    NoPhysicalGroup,
    /// A line element that is not an edge of a triangle.
    LineOffMesh,
    /// Unknown or mixed element types, references to missing nodes.
    Structure,
}

/// One defect.
#[derive(Clone, Debug)]
pub(crate) struct Defect {
    /// What is wrong.
    pub(crate) kind: DefectKind,
    /// Which element / node, in words.
    pub(crate) detail: String,
}

/// What `check_msh` found.
#[derive(Clone, Debug, Default)]
pub(crate) struct Report {
    /// Number of nodes in the file.
    pub(crate) nodes: usize,
    /// Number of triangles (any order).
    pub(crate) triangles: usize,
    /// Number of line elements.
    pub(crate) lines: usize,
    /// Element order of the triangles (0 when there are none).
    pub(crate) order: usize,
    /// Sum of the triangles' signed areas (exact integral of det J).
    pub(crate) area: f64,
    /// Edges with one triangle.
    pub(crate) boundary_edges: usize,
    /// Triangles whose Jacobian needed subdivision to be certified.
    pub(crate) subdivided: usize,
    /// Every defect found.
    pub(crate) defects: Vec<Defect>,
}

impl Report {
    /// No defects.
    pub(crate) fn is_valid(&self) -> bool {
        self.defects.is_empty()
    }
    /// Some defect of `kind`.
    pub(crate) fn has(&self, kind: DefectKind) -> bool {
        self.defects.iter().any(|d| d.kind == kind)
    }
    /// Panic with the list of defects unless valid.
    pub(crate) fn assert_valid(&self, what: &str) {
        assert!(
            self.is_valid(),
            "{what}: {} defects, first: {:#?}",
            self.defects.len(),
            &self.defects[..self.defects.len().min(10)]
        );
    }
    fn defect(&mut self, kind: DefectKind, detail: String) {
        // Keep reports small on badly broken files.
        if self.defects.len() < 1000 {
            self.defects.push(Defect { kind, detail });
        }
    }
}

/// Read and check the .msh file at `path`.
pub(crate) fn check_msh(path: &Path) -> Report {
    match read_msh(path) {
        Ok(m) => check(&m),
        Err(e) => Report {
            defects: vec![Defect {
                kind: DefectKind::Unreadable,
                detail: e,
            }],
            ..Report::default()
        },
    }
}

type P = [f64; 2];

/// Check a parsed file.
pub(crate) fn check(m: &Msh) -> Report {
    let mut r = Report {
        nodes: m.nodes.len(),
        ..Report::default()
    };
    let index = m.node_index();
    if index.len() != m.nodes.len() {
        r.defect(DefectKind::Structure, "repeated node tag".into());
    }
    let pos = |t: u64| index.get(&t).map(|&i| [m.nodes[i].1[0], m.nodes[i].1[1]]);

    let mut tri_types = HashSet::new();
    let mut tris: Vec<&Element> = Vec::new();
    let mut lines: Vec<&Element> = Vec::new();
    for e in &m.elements {
        let Some((_, dim)) = type_info(e.etype) else {
            r.defect(
                DefectKind::Structure,
                format!("element {} of unknown type {}", e.tag, e.etype),
            );
            continue;
        };
        if e.nodes.iter().any(|&t| !index.contains_key(&t)) {
            r.defect(
                DefectKind::Structure,
                format!("element {} uses a missing node", e.tag),
            );
            continue;
        }
        match dim {
            2 => {
                tri_types.insert(e.etype);
                tris.push(e);
            }
            1 => lines.push(e),
            _ => {}
        }
        if dim >= 1 {
            match e.physical.first() {
                None => r.defect(
                    DefectKind::NoPhysicalGroup,
                    format!("element {} has no physical group", e.tag),
                ),
                Some(&p) if !m.physical_names.contains_key(&(dim, p)) => r.defect(
                    DefectKind::NoPhysicalGroup,
                    format!(
                        "physical group ({dim}, {p}) of element {} has no name",
                        e.tag
                    ),
                ),
                Some(_) => {}
            }
        }
    }
    r.triangles = tris.len();
    r.lines = lines.len();
    if tri_types.len() > 1 {
        r.defect(
            DefectKind::Structure,
            format!("mixed triangle types {tri_types:?}"),
        );
    }

    // Orientation, Jacobian and area.
    for e in &tris {
        let order = match e.etype {
            2 => 1,
            9 => 2,
            _ => 3,
        };
        r.order = r.order.max(order);
        let x: Vec<P> = e
            .nodes
            .iter()
            .map(|&t| pos(t).expect("checked above"))
            .collect();
        let o = robust::orient2d(
            robust::Coord {
                x: x[0][0],
                y: x[0][1],
            },
            robust::Coord {
                x: x[1][0],
                y: x[1][1],
            },
            robust::Coord {
                x: x[2][0],
                y: x[2][1],
            },
        );
        if o < 0.0 {
            r.defect(DefectKind::Clockwise, format!("triangle {}", e.tag));
        } else if o == 0.0 {
            r.defect(DefectKind::Degenerate, format!("triangle {}", e.tag));
        }
        let det = jacobian_bernstein(order, &x);
        let n = 2 * (order - 1);
        r.area += det.iter().sum::<f64>() / ((n + 1) * (n + 2)) as f64;
        if order > 1 && o > 0.0 {
            match certify(&det, n) {
                Certificate::Positive { depth } => r.subdivided += usize::from(depth > 0),
                Certificate::Inverted => {
                    r.defect(DefectKind::Inverted, format!("triangle {}", e.tag));
                }
                Certificate::Uncertain => {
                    r.defect(DefectKind::Uncertain, format!("triangle {}", e.tag));
                }
            }
        }
    }

    // Edges: key (min corner, max corner) -> sides (from, to, inner nodes from `from`).
    let mut edges: HashMap<(u64, u64), Vec<Side>> = HashMap::new();
    for e in &tris {
        let inner = edge_inner(e.etype);
        for (k, local) in inner.iter().enumerate() {
            let (a, b) = (e.nodes[k], e.nodes[(k + 1) % 3]);
            let nodes: Vec<u64> = local.iter().map(|&j| e.nodes[j]).collect();
            edges
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push((a, b, nodes));
        }
    }
    let mut keys: Vec<_> = edges.keys().copied().collect();
    keys.sort_unstable();
    for key in keys {
        let sides = &edges[&key];
        match sides.len() {
            1 => r.boundary_edges += 1,
            2 => {
                let ((a0, b0, n0), (a1, b1, n1)) = (&sides[0], &sides[1]);
                let mut rev = n1.clone();
                rev.reverse();
                if !(a0 == b1 && b0 == a1 && *n0 == rev) {
                    r.defect(DefectKind::NonConforming, format!("edge {key:?}"));
                }
            }
            _ => r.defect(DefectKind::NonManifold, format!("edge {key:?}")),
        }
    }

    // Lines lie on triangle edges, with the same edge nodes.
    for l in &lines {
        let (a, b) = (l.nodes[0], l.nodes[1]);
        let mut inner: Vec<u64> = l.nodes[2..].to_vec();
        let ok = edges.get(&(a.min(b), a.max(b))).is_some_and(|sides| {
            sides.iter().any(|(sa, _, n)| {
                if *sa != a {
                    inner.reverse();
                    let same = *n == inner;
                    inner.reverse();
                    same
                } else {
                    *n == inner
                }
            })
        });
        if !ok {
            r.defect(DefectKind::LineOffMesh, format!("line {}", l.tag));
        }
    }

    // Duplicate nodes among the used ones (exact position equality).
    let used: HashSet<u64> = tris
        .iter()
        .chain(&lines)
        .flat_map(|e| e.nodes.iter().copied())
        .collect();
    let mut at: HashMap<(u64, u64), u64> = HashMap::new();
    let mut used: Vec<u64> = used.into_iter().collect();
    used.sort_unstable();
    for t in used {
        let p = pos(t).expect("checked above");
        // +0.0 and -0.0 are the same position.
        let key = ((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits());
        if let Some(o) = at.insert(key, t) {
            r.defect(
                DefectKind::DuplicateNode,
                format!("nodes {o} and {t} at {p:?}"),
            );
        }
    }
    r
}

/// One side of an edge: (from, to, inner nodes in order from `from`).
type Side = (u64, u64, Vec<u64>);

/// Local indices of the inner nodes of triangle edges 0→1, 1→2, 2→0 (gmsh order).
fn edge_inner(etype: i32) -> [&'static [usize]; 3] {
    match etype {
        9 => [&[3], &[4], &[5]],
        21 => [&[3, 4], &[5, 6], &[7, 8]],
        _ => [&[], &[], &[]],
    }
}

/// Multi-indices (a0, a1, a2) with sum `k`, in a fixed order; `flat` gives positions.
fn multi_indices(k: usize) -> Vec<[usize; 3]> {
    let mut v = Vec::new();
    for a2 in 0..=k {
        for a1 in 0..=k - a2 {
            v.push([k - a1 - a2, a1, a2]);
        }
    }
    v
}

fn flat(k: usize, a: [usize; 3]) -> usize {
    let (a1, a2) = (a[1], a[2]);
    a2 * (k + 1) - a2 * a2.saturating_sub(1) / 2 + a1
}

fn factorial(n: usize) -> f64 {
    (1..=n).map(|i| i as f64).product()
}

fn multinomial(a: [usize; 3]) -> f64 {
    factorial(a[0] + a[1] + a[2]) / (factorial(a[0]) * factorial(a[1]) * factorial(a[2]))
}

fn lin(terms: &[(f64, P)]) -> P {
    let mut s = [0.0, 0.0];
    for &(c, p) in terms {
        s[0] += c * p[0];
        s[1] += c * p[1];
    }
    s
}

/// Bézier control net (indexed by `flat(p, ·)`) of a Lagrange triangle with gmsh nodes `x`,
/// translated so corner 0 is the origin.
fn control_net(p: usize, x: &[P]) -> Vec<P> {
    let o = x[0];
    let x: Vec<P> = x.iter().map(|q| [q[0] - o[0], q[1] - o[1]]).collect();
    let mut net = vec![[0.0; 2]; multi_indices(p).len()];
    let mut set = |a: [usize; 3], v: P| net[flat(p, a)] = v;
    let corner = |i: usize| {
        let mut a = [0; 3];
        a[i] = p;
        a
    };
    for (i, &xi) in x.iter().take(3).enumerate() {
        set(corner(i), xi);
    }
    match p {
        1 => {}
        2 => {
            for (k, (i, j)) in [(0, 1), (1, 2), (2, 0)].into_iter().enumerate() {
                let mut a = [0; 3];
                a[i] = 1;
                a[j] = 1;
                set(a, lin(&[(2.0, x[3 + k]), (-0.5, x[i]), (-0.5, x[j])]));
            }
        }
        _ => {
            let mut edge_sum = [0.0, 0.0];
            for (k, (i, j)) in [(0, 1), (1, 2), (2, 0)].into_iter().enumerate() {
                let (n1, n2) = (x[3 + 2 * k], x[4 + 2 * k]);
                // Interpolation at t = 1/3, 2/3 solved for the two inner controls.
                let c1 = lin(&[(-5.0 / 6.0, x[i]), (3.0, n1), (-1.5, n2), (1.0 / 3.0, x[j])]);
                let c2 = lin(&[(1.0 / 3.0, x[i]), (-1.5, n1), (3.0, n2), (-5.0 / 6.0, x[j])]);
                let mut a = [0; 3];
                a[i] = 2;
                a[j] = 1;
                set(a, c1);
                let mut a = [0; 3];
                a[i] = 1;
                a[j] = 2;
                set(a, c2);
                edge_sum = lin(&[(1.0, edge_sum), (1.0, c1), (1.0, c2)]);
            }
            // Centre: x(1/3,1/3,1/3) = (Σ corners + 3 Σ edge controls + 6 c111) / 27.
            let corners = lin(&[(1.0, x[0]), (1.0, x[1]), (1.0, x[2])]);
            set(
                [1, 1, 1],
                lin(&[(27.0 / 6.0, x[9]), (-1.0 / 6.0, corners), (-0.5, edge_sum)]),
            );
        }
    }
    net
}

/// Bernstein coefficients (degree 2(p−1), indexed by `flat`) of det J over the
/// reference triangle (ξ = λ1, η = λ2).
fn jacobian_bernstein(p: usize, x: &[P]) -> Vec<f64> {
    let net = control_net(p, x);
    let m = p - 1;
    let n = 2 * m;
    let lower = multi_indices(m);
    // ∂x/∂ξ and ∂x/∂η as degree-m Bézier nets (without the factor p).
    let du: Vec<P> = lower
        .iter()
        .map(|&b| {
            let (mut b1, mut b0) = (b, b);
            b1[1] += 1;
            b0[0] += 1;
            lin(&[(1.0, net[flat(p, b1)]), (-1.0, net[flat(p, b0)])])
        })
        .collect();
    let dv: Vec<P> = lower
        .iter()
        .map(|&b| {
            let (mut b2, mut b0) = (b, b);
            b2[2] += 1;
            b0[0] += 1;
            lin(&[(1.0, net[flat(p, b2)]), (-1.0, net[flat(p, b0)])])
        })
        .collect();
    let mut det = vec![0.0; multi_indices(n).len()];
    let pp = (p * p) as f64;
    for (ia, &a) in lower.iter().enumerate() {
        for (ib, &b) in lower.iter().enumerate() {
            let c = [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
            let w = multinomial(a) * multinomial(b) / multinomial(c);
            let cross = du[ia][0] * dv[ib][1] - du[ia][1] * dv[ib][0];
            det[flat(n, c)] += pp * w * cross;
        }
    }
    det
}

/// The blossom of a degree-`n` Bernstein polynomial at barycentric points `args`.
fn blossom(coef: &[f64], n: usize, args: &[[f64; 3]]) -> f64 {
    let mut c = coef.to_vec();
    for (s, u) in args.iter().enumerate() {
        let k = n - s - 1;
        let mut next = vec![0.0; multi_indices(k).len()];
        for a in multi_indices(k) {
            let up = |i: usize| {
                let mut b = a;
                b[i] += 1;
                c[flat(k + 1, b)]
            };
            next[flat(k, a)] = u[0] * up(0) + u[1] * up(1) + u[2] * up(2);
        }
        c = next;
    }
    c[0]
}

/// Bernstein coefficients of the same polynomial on the sub-triangle `q`.
fn restrict(coef: &[f64], n: usize, q: &[[f64; 3]; 3]) -> Vec<f64> {
    let mut out = vec![0.0; coef.len()];
    for a in multi_indices(n) {
        let args: Vec<[f64; 3]> = (0..3)
            .flat_map(|i| std::iter::repeat_n(q[i], a[i]))
            .collect();
        out[flat(n, a)] = blossom(coef, n, &args);
    }
    out
}

enum Certificate {
    Positive { depth: u32 },
    Inverted,
    Uncertain,
}

/// Certify det J > 0 on the reference triangle.
fn certify(coef: &[f64], n: usize) -> Certificate {
    let scale = coef.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    let corners = |c: &[f64]| {
        [
            c[flat(n, [n, 0, 0])],
            c[flat(n, [0, n, 0])],
            c[flat(n, [0, 0, n])],
        ]
    };
    let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut work = vec![(id, coef.to_vec())];
    let mut max_depth = 0;
    for depth in 0..=MAX_DEPTH {
        let mut next = Vec::new();
        for (tri, c) in work {
            // Corner coefficients are values of det J: a non-positive one proves inversion.
            if corners(&c).iter().any(|&v| v <= 0.0) {
                return Certificate::Inverted;
            }
            if c.iter().all(|&v| v > 1e-14 * scale) {
                continue;
            }
            max_depth = depth + 1;
            let mid = |i: usize, j: usize| {
                let (a, b): ([f64; 3], [f64; 3]) = (tri[i], tri[j]);
                [
                    (a[0] + b[0]) / 2.0,
                    (a[1] + b[1]) / 2.0,
                    (a[2] + b[2]) / 2.0,
                ]
            };
            let (m01, m12, m20) = (mid(0, 1), mid(1, 2), mid(2, 0));
            for sub in [
                [tri[0], m01, m20],
                [m01, tri[1], m12],
                [m20, m12, tri[2]],
                [m12, m20, m01],
            ] {
                next.push((sub, restrict(coef, n, &sub)));
            }
        }
        if next.is_empty() {
            return Certificate::Positive { depth: max_depth };
        }
        if depth == MAX_DEPTH {
            return Certificate::Uncertain;
        }
        work = next;
    }
    Certificate::Uncertain
}

#[cfg(test)]
mod tests {
    use super::*;

    /// gmsh nodes of the straight order-`p` triangle with corners `c`.
    fn straight(p: usize, c: [P; 3]) -> Vec<P> {
        let at = |i: usize, j: usize, t: f64| lin(&[(1.0 - t, c[i]), (t, c[j])]);
        let mut x = c.to_vec();
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            x.extend((1..p).map(|s| at(i, j, s as f64 / p as f64)));
        }
        if p == 3 {
            x.push(lin(&[
                (1.0 / 3.0, c[0]),
                (1.0 / 3.0, c[1]),
                (1.0 / 3.0, c[2]),
            ]));
        }
        x
    }

    #[test]
    fn straight_elements_have_constant_jacobian() {
        let c = [[0.5, -1.0], [3.0, 0.25], [-0.75, 2.0]];
        let twice_area =
            (c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[1][1] - c[0][1]) * (c[2][0] - c[0][0]);
        for p in 1..=3 {
            let det = jacobian_bernstein(p, &straight(p, c));
            assert_eq!(det.len(), multi_indices(2 * (p - 1)).len());
            for d in det {
                assert!((d - twice_area).abs() < 1e-12 * twice_area, "p={p}: {d}");
            }
        }
    }

    #[test]
    fn flat_enumerates_in_order() {
        for k in 0..5 {
            for (i, a) in multi_indices(k).into_iter().enumerate() {
                assert_eq!(flat(k, a), i);
            }
        }
    }
}
