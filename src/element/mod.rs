//! Leaf geometry of triangle elements: what one element is, independent of any
//! mesh (thesis §2.3.2, §4.4.2-4.4.3; docs/design.md "Curved elements").
//!
//! Nothing here knows a mesh, a feature or a stage; everything above (the local
//! operations and their invariants, the optimization schedule, the curving stage,
//! the writers and readers) shapes and judges elements through this module, so an
//! element is the same everywhere.
//!
//! - [`order`]: the element [`Order`] (1, 2, 3) and its gmsh type numbers;
//! - [`lagrange`]: the quadratic (gmsh type 9) and cubic (type 21) Lagrange nodes of a
//!   triangle with at most one curved edge, and the exact conversions between Lagrange
//!   nodes and Bézier control nets;
//! - [`bernstein`]: scalar polynomials on a triangle in Bernstein form (bounds,
//!   evaluation, exact subdivision);
//! - [`jacobian`]: the Bernstein coefficients of `det J` computed from the map's
//!   derivatives, and their certification by subdivision;
//! - [`energy`]: the conformal AMIPS energy of a straight triangle with analytic
//!   derivatives in one free vertex and along a curve;
//! - [`triangle`]: one Lagrange triangle's nodes from its corners and its edges'
//!   curve pieces, its certification and its curved AMIPS energy.
//!
//! Guarantee: an element is valid only if [`jacobian::certify`] says
//! [`jacobian::Validity::Certified`], which proves `det J > 0` on the whole element.
//! Imports: nothing of the crate (kurbo and nalgebra only).

pub mod bernstein;
pub mod energy;
pub mod jacobian;
pub mod lagrange;
pub mod order;
pub mod triangle;

pub use jacobian::{Certificate, CertifyOptions, Validity};
pub use lagrange::CurvedEdge;
pub use order::Order;
