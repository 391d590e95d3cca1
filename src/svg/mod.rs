//! SVG input: usvg tree → [`Drawing`] (DESIGN "Data flow", `svg`; thesis §4.3.1 input).
//!
//! Owns everything between the bytes of an SVG file and the f64 geometry the
//! meshers consume. Normalises once at the input boundary:
//!
//! - every drawable element (paths, basic shapes, `<use>`, nested `<svg>`, CSS
//!   styling, text when a font is found) becomes one [`Shape`] per usvg path, made
//!   of straight segments and cubic Béziers (quadratics are elevated exactly,
//!   arcs arrive from usvg as cubics), in user units after all transforms
//!   (each path's absolute transform applied in f64 to usvg's f32 data), y flipped;
//!   the root `viewBox` → `width`/`height` mapping is one of those transforms, so
//!   coordinates are in the root viewport's units (px at 96 dpi), as usvg and the
//!   reference's nanosvg give them;
//! - zero-length segments are dropped; a subpath with no segment left is an
//!   isolated point (a path that is only `M x y` is dropped by usvg, as by
//!   browsers and nanosvg; a trailing `M` after drawing commands is kept);
//! - a number in a geometry attribute beyond the f32 range (which usvg would
//!   silently drop with its element) is a [`Error::BadCoordinate`];
//! - [`Drawing::features`] lists every segment, every isolated point and the
//!   implicit closing segment of each open subpath of a filled shape;
//! - clip paths, masks, images and filters are not geometry (images and filters
//!   leave a warning, as does text that yields no outline).
//!
//! Guarantees to the next stage (see [`Drawing`]): at least one feature, every
//! coordinate finite with magnitude at most [`Drawing::MAX_COORD`], and a bbox
//! whose diagonal is not negligible (< 1e-12) relative to its distance from the
//! origin unless the drawing is a single point.

pub(crate) mod drawing;
mod load;
mod outline;
mod soup;

pub(crate) use drawing::{
    Drawing, Feature, FeatureGeom, FeatureSource, FillRule, Segment, Shape, ShapeId, Subpath,
};

use crate::{Error, Result};
use std::path::Path;

/// Load and normalise an SVG file.
///
/// # Errors
/// [`Error::Read`] if the file cannot be read (the message names the cause),
/// [`Error::IsDirectory`] for a directory, otherwise as [`load_bytes`].
pub fn load_file(path: &Path) -> Result<Drawing> {
    let meta = std::fs::metadata(path).map_err(Error::Read)?;
    if meta.is_dir() {
        return Err(Error::IsDirectory);
    }
    let data = std::fs::read(path).map_err(Error::Read)?;
    if data.is_empty() {
        return Err(Error::EmptyFile);
    }
    load_bytes(&data)
}

/// Load and normalise an SVG document from its bytes (UTF-8, or UTF-16 with a BOM).
///
/// ```
/// use triwild::{ErrorKind, load_bytes};
/// let d = load_bytes(br#"<svg xmlns="http://www.w3.org/2000/svg">
///     <rect x="0" y="0" width="4" height="2"/></svg>"#)?;
/// assert_eq!(d.shapes.len(), 1);
/// assert_eq!(d.diagonal(), 20f64.sqrt());
/// // Not a drawing: one clear error, never a panic.
/// let e = load_bytes(b"<html><body>hello</body></html>").unwrap_err();
/// assert_eq!(e.kind(), ErrorKind::BadInput);
/// # Ok::<(), triwild::Error>(())
/// ```
///
/// # Errors
/// - [`Error::EmptyFile`]: no bytes, or only whitespace;
/// - [`Error::NotSvg`]: binary data (PNG, gzip/.svgz, ...), broken XML, an HTML
///   page, a root element other than `<svg>`, or input beyond usvg's safety
///   limits (entity bombs, more than 1,000,000 elements after `<use>` expansion);
/// - [`Error::NoGeometry`]: nothing drawable;
/// - [`Error::BadCoordinate`]: a coordinate that is not finite or exceeds
///   [`Drawing::MAX_COORD`] after transforms, or a drawing too small for its
///   distance from the origin.
pub fn load_bytes(data: &[u8]) -> Result<Drawing> {
    let (tree, facts) = load::parse(data)?;
    let outlines = outline::collect(&tree, &facts)?;
    let drawing = soup::assemble(outlines.shapes, outlines.warnings)?;
    tracing::debug!(
        shapes = drawing.shapes.len(),
        features = drawing.features.len(),
        warnings = drawing.warnings.len(),
        "svg loaded"
    );
    Ok(drawing)
}

#[cfg(test)]
mod tests;
