//! The shape a curved mesh takes over its linear [`TriMesh`]: the inner
//! Lagrange nodes of the edges that bend and the moved cubic centres
//! ([`Bend`]; every other node sits at its straight default), the exact shape
//! in which every primary edge on a cubic takes its curve piece, and the faces
//! a shape leaves uncertified (thesis §4.4.2 "Splitting and Curving").

use crate::element::Order;
use crate::element::jacobian::{self, CertifyOptions};
use crate::element::triangle::{self as element, EDGES};
use crate::mesh::{EdgeKey, FaceId, TriMesh, VertexId};
use crate::ops::Context;
use crate::ops::invariants::curved;
use kurbo::{Point, Vec2};
use std::collections::HashMap;

/// The curved inner nodes (from `lo` to `hi`) of a primary edge on a cubic, or
/// `None` if the edge is not such an edge (straight parents stay straight).
pub(super) fn curved_inner(
    mesh: &TriMesh,
    ctx: &Context,
    order: Order,
    key: EdgeKey,
) -> Option<Vec<Point>> {
    curved::exact_inner(mesh, ctx, order, key)
}

/// Inner nodes and centre offsets that differ from the straight defaults.
#[derive(Clone, Debug, Default)]
pub(super) struct Bend {
    /// Inner nodes of curved edges, from `lo` to `hi`.
    pub(super) edges: HashMap<EdgeKey, Vec<Point>>,
    /// Offset of a cubic centre node from its quadratic-exact base (`lagrange::cubic_centre`).
    pub(super) centre: HashMap<FaceId, Vec2>,
}

impl Bend {
    /// The Lagrange nodes (gmsh order) of face `f`.
    pub(super) fn element(&self, mesh: &TriMesh, order: Order, f: FaceId) -> Vec<Point> {
        let v = mesh.face(f);
        let mut reversed: [Option<Vec<Point>>; 3] = [None, None, None];
        let mut inner: [Option<&[Point]>; 3] = [None; 3];
        for (e, [i, j]) in EDGES.into_iter().enumerate() {
            let key = EdgeKey::new(v[i], v[j]);
            if let Some(pts) = self.edges.get(&key) {
                if key.lo == v[i] {
                    inner[e] = Some(pts);
                } else {
                    reversed[e] = Some(pts.iter().rev().copied().collect());
                }
            }
        }
        for (e, r) in reversed.iter().enumerate() {
            if let Some(r) = r {
                inner[e] = Some(r);
            }
        }
        let centre = self.centre.get(&f).copied().unwrap_or(Vec2::ZERO);
        element::nodes(order, v.map(|x| mesh.position(x)), inner, centre)
    }

    /// Whether face `f` is certified with these nodes.
    pub(super) fn certified(
        &self,
        mesh: &TriMesh,
        order: Order,
        f: FaceId,
        opts: &CertifyOptions,
    ) -> bool {
        self.certificate(mesh, order, f, opts)
            .is_some_and(|c| c.is_certified())
    }

    pub(super) fn certificate(
        &self,
        mesh: &TriMesh,
        order: Order,
        f: FaceId,
        opts: &CertifyOptions,
    ) -> Option<jacobian::Certificate> {
        element::certificate(order, &self.element(mesh, order, f), opts)
    }
}

/// The edges of face `f` as keys, in gmsh order.
pub(super) fn face_edges(mesh: &TriMesh, f: FaceId) -> [EdgeKey; 3] {
    let v = mesh.face(f);
    EDGES.map(|[i, j]| EdgeKey::new(v[i], v[j]))
}

/// The exact curved shape: every primary edge takes its curve piece.
pub(super) fn exact_shape(mesh: &TriMesh, ctx: &Context, order: Order) -> Bend {
    let mut shape = Bend::default();
    let keys: Vec<EdgeKey> = mesh.tagged_edges().map(|(k, _)| k).collect();
    for key in keys {
        if let Some(inner) = curved_inner(mesh, ctx, order, key) {
            shape.edges.insert(key, inner);
        }
    }
    shape
}

/// Faces with a curved edge that are not certified.
pub(super) fn uncertified(
    mesh: &TriMesh,
    shape: &Bend,
    order: Order,
    opts: &CertifyOptions,
) -> Vec<FaceId> {
    let mut faces: Vec<FaceId> = Vec::new();
    let mut on_edge = Vec::new();
    for key in shape.edges.keys() {
        mesh.faces_on_edge(key.lo, key.hi, &mut on_edge);
        faces.extend_from_slice(&on_edge);
    }
    faces.sort_unstable();
    faces.dedup();
    faces.retain(|&f| !shape.certified(mesh, order, f, opts));
    faces
}

/// The exact shape of the primary edges of the faces around `v`.
pub(super) fn exact_shape_around(mesh: &TriMesh, ctx: &Context, order: Order, v: VertexId) -> Bend {
    let mut shape = Bend::default();
    for f in mesh.incident_faces(v) {
        for key in face_edges(mesh, f) {
            if let Some(inner) = curved_inner(mesh, ctx, order, key) {
                shape.edges.insert(key, inner);
            }
        }
    }
    shape
}
