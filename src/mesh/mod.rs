//! The hybrid triangle mesh shared by the BSP mesher and the optimizer.
//!
//! It owns [`TriMesh`]: vertices with an `f64` position plus an exact
//! rational one while the vertex is not roundable (thesis §2.3.4 "Hybrid
//! Kernel"), triangles with per-edge adjacency, tags on edges (which input
//! feature segments an edge lies on) and on vertices (feature points, section
//! endpoints, box corners), and free lists so the local operations of the
//! optimizer can delete and reuse slots.
//!
//! Guarantees: [`TriMesh::check`] reports every defect of a mesh (inverted or
//! degenerate triangles decided exactly, asymmetric adjacency, non-manifold
//! edges, T-junctions, dangling tags). Topology navigation (`topology.rs`)
//! never reads a coordinate; `geometry.rs` holds the `f64` measurements
//! (distances, corner angles) the stages share. [`Transaction`] journals changes and rolls them
//! back on drop, for the optimizer's local operations. docs/design.md "Invariants" 1 and "Exactness".

mod check;
mod geometry;
mod ids;
mod storage;
mod topology;
mod transaction;

pub(crate) use geometry::{
    angle_between, corner_angles, is_sliver, min_angle_deg, point_segment_distance,
    segment_distance,
};
pub(crate) use ids::{FaceId, VertexId};
pub(crate) use storage::{EdgeKey, FeatureOn, TriMesh, VertexTag};
pub(crate) use topology::{EdgeQuad, ScratchRing, VertexRing};
pub(crate) use transaction::Transaction;

/// A test mesh from a spade constrained triangulation: its vertices (tagged by
/// `tags`, indexed like spade's vertices) and inner faces, linked. Returns the
/// mesh and the mesh's vertex for each of spade's.
#[cfg(test)]
pub(crate) fn trimesh_of_cdt(
    cdt: &spade::ConstrainedDelaunayTriangulation<spade::Point2<f64>>,
    tags: &[VertexTag],
) -> (TriMesh, Vec<VertexId>) {
    use spade::Triangulation;
    let mut mesh = TriMesh::new();
    let ids: Vec<VertexId> = cdt
        .vertices()
        .map(|v| {
            let p = v.position();
            mesh.add_vertex(kurbo::Point::new(p.x, p.y), tags[v.fix().index()])
        })
        .collect();
    for f in cdt.inner_faces() {
        mesh.add_face(f.vertices().map(|v| ids[v.fix().index()]));
    }
    mesh.link_all();
    (mesh, ids)
}
