//! Certification of a whole mesh: every triangle's Jacobian bound, the Jacobian
//! ratio, the exact area (docs/design.md "Outputs a user can check"; what `triwild check`
//! reports).
//!
//! Orientation: the mesh's orientation is the majority sign of its corner
//! triangles (counter-clockwise wins ties), and each element's `det J` is
//! certified positive *in that orientation*; a mesh mixing both orientations is
//! invalid. This is the convention of `shared/bench/mshcheck.py`, whose numbers
//! (`min_detj_ratio`, `total_area`, invalid counts) this summary reproduces with
//! its own code.

use crate::element::Order;
use crate::element::jacobian::{self, CertifyOptions, Validity};
use kurbo::Point;

/// The certification summary of a mesh.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MeshCheck {
    /// Number of triangles examined.
    pub triangles: usize,
    /// Triangles of order 1, 2 and 3.
    pub by_order: [usize; 3],
    /// Triangles whose high-order nodes are off their straight positions
    /// (by more than 1e-9 of the mesh diagonal).
    pub curved: usize,
    /// Triangles whose Jacobian is certified positive.
    pub certified: usize,
    /// Triangles proved inverted.
    pub inverted: usize,
    /// Triangles proved degenerate (zero Jacobian somewhere).
    pub degenerate: usize,
    /// Triangles neither certified nor proved invalid within the budget.
    pub uncertain: usize,
    /// Triangles that reference a node that does not exist.
    pub malformed: usize,
    /// `"ccw"`, `"cw"`, `"mixed"` or `"none"` (no triangles).
    pub orientation: &'static str,
    /// Smallest certified lower bound of `min det J / max det J` over the
    /// elements (1 for straight triangles; ≤ 0 if any is invalid).
    pub min_detj_ratio: f64,
    /// Index of the element with the smallest ratio.
    pub worst_element: Option<usize>,
    /// Smallest certified lower bound of `det J` (reference triangle of area 1/2).
    pub min_detj_lower: f64,
    /// Largest sampled `det J`.
    pub max_detj: f64,
    /// Total area, the exact integral of `det J` (in the mesh's orientation).
    pub total_area: f64,
}

impl MeshCheck {
    /// Number of triangles that are not certified valid.
    pub fn invalid(&self) -> usize {
        self.triangles - self.certified
    }

    /// Whether the mesh is valid: at least one triangle, all certified, one orientation.
    pub fn is_valid(&self) -> bool {
        self.triangles > 0 && self.invalid() == 0 && self.orientation != "mixed"
    }
}

/// Certify every triangle. `triangles` yields each element's order and node
/// indices into `nodes` (gmsh order); an element with the wrong node count or an
/// index out of range counts as malformed (and invalid).
pub fn certify_mesh<'a>(
    nodes: &[Point],
    triangles: impl Iterator<Item = (Order, &'a [u32])> + Clone,
    opts: &CertifyOptions,
) -> MeshCheck {
    let _span = tracing::debug_span!("certify_mesh").entered();
    let gather = |order: Order, idx: &[u32]| -> Option<Vec<Point>> {
        if idx.len() != order.triangle_nodes() {
            return None;
        }
        idx.iter()
            .map(|&i| nodes.get(i as usize).copied())
            .collect()
    };
    // Pass 1: orientation by the corner triangles.
    let (mut ccw, mut cw) = (0usize, 0usize);
    for (order, idx) in triangles.clone() {
        if let Some(p) = gather(order, idx) {
            let a = (p[1] - p[0]).cross(p[2] - p[0]);
            if a > 0.0 {
                ccw += 1;
            } else if a < 0.0 {
                cw += 1;
            }
        }
    }
    let sign = if cw > ccw { -1.0 } else { 1.0 };
    let diag = {
        let (mut lo, mut hi) = (
            Point::new(f64::INFINITY, f64::INFINITY),
            Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for p in nodes {
            lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        if nodes.is_empty() {
            0.0
        } else {
            (hi - lo).hypot()
        }
    };
    let mut r = MeshCheck {
        triangles: 0,
        by_order: [0; 3],
        curved: 0,
        certified: 0,
        inverted: 0,
        degenerate: 0,
        uncertain: 0,
        malformed: 0,
        orientation: "none",
        min_detj_ratio: f64::INFINITY,
        worst_element: None,
        min_detj_lower: f64::INFINITY,
        max_detj: f64::NEG_INFINITY,
        total_area: 0.0,
    };
    for (i, (order, idx)) in triangles.enumerate() {
        r.triangles += 1;
        r.by_order[order as usize - 1] += 1;
        let Some(p) = gather(order, idx) else {
            r.malformed += 1;
            r.min_detj_ratio = f64::NEG_INFINITY;
            r.worst_element.get_or_insert(i);
            continue;
        };
        if is_curved(order, &p, 1e-9 * diag) {
            r.curved += 1;
        }
        let det = jacobian::det_lagrange(order, &p)
            .expect("internal: node count checked by gather")
            .scaled(sign);
        r.total_area += jacobian::area(&det);
        let cert = jacobian::certify(&det, jacobian::zero_abs(&p, opts.zero_rel), opts);
        match cert.validity {
            Validity::Certified => r.certified += 1,
            Validity::Inverted => r.inverted += 1,
            Validity::Degenerate => r.degenerate += 1,
            Validity::Uncertain => r.uncertain += 1,
        }
        let ratio = cert.ratio();
        if ratio < r.min_detj_ratio || r.worst_element.is_none() {
            r.min_detj_ratio = ratio;
            r.worst_element = Some(i);
        }
        r.min_detj_lower = r.min_detj_lower.min(cert.lower);
        r.max_detj = r.max_detj.max(cert.sampled_max);
    }
    r.orientation = match (ccw, cw) {
        (0, 0) => "none",
        (_, 0) => "ccw",
        (0, _) => "cw",
        _ => "mixed",
    };
    if r.triangles == 0 {
        r.min_detj_ratio = 0.0;
        r.min_detj_lower = 0.0;
        r.max_detj = 0.0;
    }
    r
}

/// Whether the high-order nodes are off the straight positions by more than `tol`.
fn is_curved(order: Order, p: &[Point], tol: f64) -> bool {
    let refs: &[[f64; 2]] = match order {
        Order::Linear => return false,
        Order::Quadratic => &crate::element::lagrange::QUADRATIC_REF,
        Order::Cubic => &crate::element::lagrange::CUBIC_REF,
    };
    refs.iter().zip(p).skip(3).any(|(r, q)| {
        let s = p[0] + r[0] * (p[1] - p[0]) + r[1] * (p[2] - p[0]);
        (s - *q).hypot() > tol
    })
}

/// Certify every triangle of a [`crate::FemMesh`] (what `triwild check` reports).
///
/// ```
/// use triwild::{CertifyOptions, Length, LoadOptions, Params, RegionOptions};
/// use triwild::{certify_fem, load_bytes, mesh_drawing};
/// let svg = br#"<svg xmlns="http://www.w3.org/2000/svg" width="10" height="10">
///     <circle cx="5" cy="5" r="4"/></svg>"#;
/// let params = Params::DEFAULT.with_l(Length::Rel(0.2));
/// let drawing = load_bytes(svg, &LoadOptions::from_params(&params)?)?;
/// let meshed = mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT)?;
/// let check = certify_fem(&meshed.mesh, &CertifyOptions::DEFAULT);
/// assert!(check.is_valid());
/// assert_eq!(check.certified, check.triangles);
/// assert!(check.curved > 0);
/// # Ok::<(), triwild::Error>(())
/// ```
pub fn certify_fem(mesh: &crate::FemMesh, opts: &CertifyOptions) -> MeshCheck {
    let order = mesh.order();
    certify_mesh(
        &mesh.nodes,
        mesh.triangles
            .chunks_exact(order.triangle_nodes())
            .map(move |t| (order, t)),
        opts,
    )
}

/// The check of a mesh file: format, element counts, and the certification.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FileCheck {
    /// Format line of the file.
    pub format: crate::input::MshFormat,
    /// Number of nodes.
    pub nodes: usize,
    /// Number of line elements.
    pub lines: usize,
    /// 2D elements that are not triangles of order 1-3 (they make the mesh invalid).
    pub unsupported_2d: usize,
    /// Largest |z| of a node (the check is planar and ignores z).
    pub max_abs_z: f64,
    /// The certification of the triangles.
    #[serde(flatten)]
    pub mesh: MeshCheck,
    /// Valid: triangles exist, all certified, one orientation, no unsupported elements.
    pub valid: bool,
    /// Why not valid (empty when valid).
    pub reasons: Vec<String>,
}

/// Certify a mesh read by [`crate::read_msh`].
pub fn check_msh(m: &crate::input::MshMesh, opts: &CertifyOptions) -> FileCheck {
    let mesh = certify_mesh(&m.nodes, m.triangles(), opts);
    let mut reasons = Vec::new();
    if mesh.triangles == 0 {
        reasons.push("no triangles".to_owned());
    }
    if mesh.orientation == "mixed" {
        reasons.push("mixed orientation".to_owned());
    }
    for (n, what) in [
        (mesh.inverted, "inverted"),
        (mesh.degenerate, "degenerate"),
        (mesh.uncertain, "uncertain"),
        (mesh.malformed, "malformed"),
        (m.unsupported_2d, "unsupported 2D"),
    ] {
        if n > 0 {
            reasons.push(format!("{n} {what} elements"));
        }
    }
    FileCheck {
        format: m.format.clone(),
        nodes: m.nodes.len(),
        lines: m.lines,
        unsupported_2d: m.unsupported_2d,
        max_abs_z: m.max_abs_z,
        valid: reasons.is_empty(),
        reasons,
        mesh,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::lagrange::{CurvedEdge, cubic_nodes};
    use kurbo::CubicBez;

    fn square_nodes() -> Vec<Point> {
        vec![
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(1.0, 1.0),
            Point::new(0.0, 1.0),
        ]
    }

    #[test]
    fn linear_square() {
        let nodes = square_nodes();
        let tris: Vec<u32> = vec![0, 1, 2, 0, 2, 3];
        let r = certify_mesh(
            &nodes,
            tris.chunks(3).map(|t| (Order::Linear, t)),
            &CertifyOptions::DEFAULT,
        );
        assert!(r.is_valid(), "{r:?}");
        assert_eq!((r.triangles, r.certified, r.curved), (2, 2, 0));
        assert!((r.total_area - 1.0).abs() < 1e-15);
        assert!((r.min_detj_ratio - 1.0).abs() < 1e-15);
        assert_eq!(r.orientation, "ccw");
        // both clockwise: still valid, area positive
        let cw: Vec<u32> = vec![0, 2, 1, 0, 3, 2];
        let r = certify_mesh(
            &nodes,
            cw.chunks(3).map(|t| (Order::Linear, t)),
            &CertifyOptions::DEFAULT,
        );
        assert!(r.is_valid() && r.orientation == "cw" && (r.total_area - 1.0).abs() < 1e-15);
        // mixed: invalid
        let mixed: Vec<u32> = vec![0, 1, 2, 0, 3, 2];
        let r = certify_mesh(
            &nodes,
            mixed.chunks(3).map(|t| (Order::Linear, t)),
            &CertifyOptions::DEFAULT,
        );
        assert!(!r.is_valid() && r.inverted == 1 && r.orientation == "mixed");
        // out-of-range index
        let bad: Vec<u32> = vec![0, 1, 9];
        let r = certify_mesh(
            &nodes,
            bad.chunks(3).map(|t| (Order::Linear, t)),
            &CertifyOptions::DEFAULT,
        );
        assert_eq!((r.malformed, r.invalid()), (1, 1));
        // empty
        let r = certify_mesh(&nodes, std::iter::empty(), &CertifyOptions::DEFAULT);
        assert!(!r.is_valid() && r.triangles == 0);
    }

    #[test]
    fn curved_area_is_exact() {
        // Triangle (0,0),(1,0),(0,1) whose edge 0→1 bulges down along a cubic: the
        // area is the triangle's plus the area between the chord and the cubic.
        let c = CubicBez::new((0.0, 0.0), (0.3, -0.3), (0.7, -0.3), (1.0, 0.0));
        let e = CurvedEdge {
            edge: 0,
            curve: c,
            t0: 0.0,
            t1: 1.0,
        };
        let n = cubic_nodes(
            [
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(0.0, 1.0),
            ],
            Some(&e),
        );
        let idx: Vec<u32> = (0..10).collect();
        let r = certify_mesh(
            &n,
            std::iter::once((Order::Cubic, &idx[..])),
            &CertifyOptions::DEFAULT,
        );
        // area under a cubic Bézier with y0 = y3 = 0: -(3/20)(... ) via Green: 3/10 · 0.3 · ... computed by kurbo
        let seg_area = kurbo::ParamCurveArea::signed_area(&c).abs(); // closed by the chord (y = 0)
        assert!(
            (r.total_area - (0.5 + seg_area)).abs() < 1e-14,
            "{} vs {}",
            r.total_area,
            0.5 + seg_area
        );
        assert_eq!((r.curved, r.certified), (1, 1));
        assert!(r.min_detj_ratio > 0.0 && r.min_detj_ratio < 1.0);
    }

    #[test]
    fn mixed_orders_in_one_file() {
        // a straight triangle (type 2) and a straight-noded cubic one (type 21)
        // sharing the edge 1-2 of the unit square, plus a quadrangle
        let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n\
            $Nodes\n1 11 1 11\n2 1 0 11\n1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n11\n\
            0 0 0\n1 0 0\n0 1 0\n1 1 0\n\
            1 0.3333333333333333 0\n1 0.6666666666666666 0\n0.6666666666666667 1 0\n\
            0.33333333333333337 1 0\n0.6666666666666666 0.6666666666666666 0\n\
            0.3333333333333333 0.6666666666666667 0\n0.6666666666666667 0.3333333333333333 0\n\
            $EndNodes\n$Elements\n3 3 1 3\n\
            2 1 2 1\n1 1 2 3\n\
            2 1 21 1\n2 2 4 3 5 6 7 8 10 11 9\n\
            2 1 3 1\n3 1 2 4 3\n$EndElements\n";
        let m = crate::read_msh(text.as_bytes()).expect("read");
        assert_eq!(m.triangle_blocks.len(), 2);
        let r = check_msh(&m, &CertifyOptions::DEFAULT);
        assert_eq!(r.mesh.by_order, [1, 0, 1]);
        assert_eq!(r.mesh.certified, 2);
        assert!(
            (r.mesh.total_area - 1.0).abs() < 1e-14,
            "{}",
            r.mesh.total_area
        );
        // the quadrangle is not supported: the file is not valid
        assert_eq!(r.unsupported_2d, 1);
        assert!(!r.valid && r.reasons.iter().any(|s| s.contains("unsupported")));
    }
}
