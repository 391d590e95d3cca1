//! Invariant 1: no triangle is inverted or degenerate (docs/design.md "Invariants" 1).
//!
//! Decided exactly by `TriMesh::orientation`: the float filter of
//! `exact::orient2d` for `f64` vertices, rationals where a vertex is rational.

use crate::exact::Orientation;
use crate::mesh::{FaceId, TriMesh};

/// Whether every face is exactly counter-clockwise.
pub(crate) fn holds(mesh: &TriMesh, faces: &[FaceId]) -> bool {
    faces
        .iter()
        .all(|&f| mesh.orientation(f) == Orientation::CounterClockwise)
}
