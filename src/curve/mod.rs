//! Curved elements: Lagrange nodes and certified Jacobians (thesis §4.4.2-4.4.3,
//! DESIGN "Curved elements").
//!
//! Owns the geometry of high-order triangles:
//! - [`lagrange`]: the quadratic (gmsh type 9) and cubic (type 21) Lagrange nodes of a
//!   triangle with at most one curved edge, and the exact conversions between Lagrange
//!   nodes and Bézier control nets;
//! - [`bernstein`]: scalar polynomials on a triangle in Bernstein form (bounds,
//!   evaluation, exact subdivision);
//! - [`jacobian`]: the Bernstein coefficients of `det J` computed from the map's
//!   derivatives, and their certification by subdivision;
//! - [`certify`]: a whole mesh's validity, Jacobian ratio and exact area (what
//!   `triwild check` prints);
//! - [`element`]: one Lagrange triangle's nodes from its edges' curve pieces, its
//!   certification and its curved AMIPS energy (shared by `build` and the curved
//!   mode of the operations' invariants);
//! - [`optimize`]: the curved mesh optimization (collapse, swap, smoothing under
//!   the invariants in curved mode), a step of the curving stage;
//! - [`build`]: the curving stage, a linear `TriMesh` with primary feature edges
//!   turned into a [`CurvedMesh`] whose every element is certified.
//!
//! Guarantee to the later stages: an element is valid only if [`jacobian::certify`]
//! says [`jacobian::Validity::Certified`], which proves `det J > 0` on the whole
//! element. [`build::curve_mesh`] emits only such elements.

pub mod bernstein;
pub mod build;
pub mod certify;
pub mod element;
pub mod jacobian;
pub mod lagrange;
pub mod optimize;

pub use build::{CurveOptions, CurveStats, CurvedMesh, curve_mesh};
pub use certify::{FileCheck, MeshCheck, certify_fem, certify_mesh, check_msh};
pub use jacobian::{Certificate, CertifyOptions, Validity};
pub use lagrange::CurvedEdge;
pub use optimize::{CurvedOptimizeOptions, CurvedOptimizeStats, optimize_curved};
