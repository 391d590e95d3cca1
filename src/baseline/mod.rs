//! The CDT baseline mesher (spade): flattened features, constrained Delaunay
//! triangulation of a padded box, refined to a minimum angle and the target edge
//! length within a vertex budget (DESIGN `baseline`).

use crate::{Drawing, LinearMesh, Params, Result};

/// Mesh a drawing with the CDT baseline.
///
/// # Errors
/// [`crate::Error::Meshing`] if spade fails.
pub fn triangulate(drawing: &Drawing, params: &Params) -> Result<LinearMesh> {
    let _ = (drawing, params);
    unimplemented!("baseline")
}
