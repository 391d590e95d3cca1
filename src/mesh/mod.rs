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
//! back on drop, for the optimizer's local operations. DESIGN "Invariants" 1 and "Exactness".

mod check;
mod geometry;
mod ids;
mod storage;
mod topology;
mod transaction;

pub(crate) use geometry::{
    angle_between, corner_angles, min_angle_deg, point_segment_distance, segment_distance,
};
pub(crate) use ids::{FaceId, VertexId};
pub(crate) use storage::{EdgeKey, FeatureOn, TriMesh, VertexTag};
pub(crate) use topology::{EdgeQuad, ScratchRing, VertexRing};
pub(crate) use transaction::Transaction;
