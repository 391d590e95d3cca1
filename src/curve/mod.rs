//! The curving stage: the optimized linear mesh turned into certified curved
//! Lagrange elements (thesis §4.4.2-4.4.3, docs/design.md "Curved elements"). The
//! geometry of one element (nodes, Bézier nets, Jacobian certification, energies)
//! is in [`crate::element`]; this module drives it over a mesh.
//!
//! - [`certify`]: a whole mesh's validity, Jacobian ratio and exact area (what
//!   `triwild check` prints);
//! - [`optimize`]: the curved mesh optimization (collapse, swap, smoothing under
//!   the invariants in curved mode), a step of the curving stage;
//! - [`build`]: the curving stage, a linear `TriMesh` with primary feature edges
//!   turned into a [`CurvedMesh`] whose every element is certified: its options,
//!   statistics and driver [`curve_mesh`], over the stage's phases:
//!   - `repair`: rounding, splitting triangles with several curved edges, and
//!     the repair of uncertified elements on the linear mesh;
//!   - `shape`: the curved shape over the linear mesh (inner nodes of bent
//!     edges, moved centres), exact from the curve pieces;
//!   - `fit`: the constrained fit of edges whose exact piece is not certified;
//!   - `assemble`: nodes numbered, elements and feature lines written, the
//!     final certification and the distance statistics.
//!
//! Guarantee to the later stages: [`build::curve_mesh`] emits only elements that
//! [`crate::element::jacobian::certify`] proves valid (`det J > 0` everywhere).

mod assemble;
pub(crate) mod build;
pub(crate) mod certify;
mod fit;
pub(crate) mod optimize;
mod repair;
mod shape;

pub(crate) use build::{CurveOptions, CurveStats, CurvedMesh, curve_mesh};
