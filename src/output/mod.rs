//! Output: gmsh .msh writers (4.1 and 2.2, ASCII and binary) and the SVG preview.
//!
//! Every file is written to a temporary file in the target directory and renamed,
//! so no partial file ever appears.

use crate::{FemMesh, Result};
use std::path::Path;

/// gmsh file format version.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum MshVersion {
    /// MSH 4.1 (default).
    V41,
    /// MSH 2.2 (legacy readers).
    V22,
}

/// How to write a .msh file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MshOptions {
    /// Format version.
    pub version: MshVersion,
    /// Binary instead of ASCII.
    pub binary: bool,
}

impl MshOptions {
    /// MSH 4.1 ASCII.
    pub const DEFAULT: MshOptions = MshOptions {
        version: MshVersion::V41,
        binary: false,
    };
}

impl Default for MshOptions {
    fn default() -> Self {
        MshOptions::DEFAULT
    }
}

/// Write `mesh` as a gmsh file at `path` (atomically).
///
/// # Errors
/// [`crate::Error::Write`].
pub fn write_msh(mesh: &FemMesh, path: &Path, opts: MshOptions) -> Result<()> {
    let _ = (mesh, path, opts);
    unimplemented!("msh writer")
}

/// Write an SVG preview of `mesh` at `path` (atomically).
///
/// # Errors
/// [`crate::Error::Write`].
pub fn write_preview(mesh: &FemMesh, path: &Path) -> Result<()> {
    let _ = (mesh, path);
    unimplemented!("preview")
}

/// Check that a file can be created at `path` (its directory exists and is
/// writable, and `path` is not a directory), without leaving anything behind.
///
/// # Errors
/// [`crate::Error::Write`].
pub fn check_writable(path: &Path) -> Result<()> {
    let _ = path;
    unimplemented!("check_writable")
}
