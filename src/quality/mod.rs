//! Mesh quality metrics: angles, AMIPS energy, areas.

use crate::FemMesh;

/// Quality summary of a mesh (corner triangles).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Quality {
    /// Smallest corner angle, degrees.
    pub min_angle_deg: f64,
    /// Largest corner angle, degrees.
    pub max_angle_deg: f64,
    /// Largest 2D AMIPS energy (1 for equilateral).
    pub max_amips: f64,
    /// Mean 2D AMIPS energy.
    pub mean_amips: f64,
    /// Total area of the triangles (straight-sided).
    pub area: f64,
}

impl Quality {
    /// Measure the straight triangles spanned by the corners of `mesh`'s elements.
    pub fn of(mesh: &FemMesh) -> Quality {
        let _ = mesh;
        unimplemented!("quality")
    }
}
