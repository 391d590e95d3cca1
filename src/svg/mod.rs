//! SVG input: usvg tree → [`Drawing`] (DESIGN `svg`).
//!
//! Normalises once at the input boundary: every drawable element becomes cubic
//! Béziers, straight segments and isolated points in user units after all
//! transforms, converted to f64 and y-flipped. Coordinates are validated here.

mod drawing;

pub use drawing::{
    Drawing, Feature, FeatureGeom, FeatureSource, FillRule, Segment, Shape, ShapeId, Subpath,
};

use crate::Result;
use std::path::Path;

/// Load and normalise an SVG file.
///
/// # Errors
/// [`crate::Error`] of kind bad input or I/O; see [`load_bytes`].
pub fn load_file(path: &Path) -> Result<Drawing> {
    let _ = path;
    unimplemented!("svg loader")
}

/// Load and normalise an SVG document from its bytes.
///
/// # Errors
/// `EmptyFile`, `NotSvg`, `NoGeometry`, `BadCoordinate`.
pub fn load_bytes(data: &[u8]) -> Result<Drawing> {
    let _ = data;
    unimplemented!("svg loader")
}
