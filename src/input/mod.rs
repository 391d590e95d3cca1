//! Reading meshes back: the gmsh MSH reader behind `triwild check` (docs/design.md
//! "Outputs a user can check").
//!
//! Owns parsing of files this library did not necessarily write. Guarantees: any
//! byte string gives a [`MshMesh`] or an [`crate::Error::BadMesh`], never a panic;
//! node indices in the result are in range; coordinates are finite. This reader
//! is the library's own; the integration tests keep an independent one in
//! `tests/support`.

pub(crate) mod msh;

pub(crate) use msh::{MshFormat, MshMesh};
