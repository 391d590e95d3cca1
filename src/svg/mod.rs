//! SVG input: usvg tree → [`Drawing`] (docs/design.md "svg"; thesis §4.3.1 input).
//!
//! Owns everything between the bytes of an SVG file and the f64 geometry the
//! meshers consume. Normalises once at the input boundary:
//!
//! - every drawable element (paths, basic shapes, `<use>`, nested `<svg>`, CSS
//!   styling, text when a font is found) becomes one [`Shape`] per usvg path, made
//!   of straight segments, cubic Béziers (quadratics are elevated exactly) and
//!   exact conic pieces ([`drawing::Conic`]: arcs, `<circle>`, `<ellipse>`,
//!   rounded `<rect>` corners, at most 90° each), after all transforms, y flipped
//!   (y = −y_svg);
//! - geometry is f64 from the document's text: usvg supplies structure, styles,
//!   `<use>`, CSS, visibility and text, and each of its paths is matched to its
//!   source element (`source.rs`: private ids on anonymous shapes and `<use>`
//!   elements, never shown to a user) and re-read in f64 (`geometry.rs`: path
//!   data with `svgtypes`, arcs kept as arcs, basic shapes by SVG's rules), its
//!   transform chain composed in f64 (`transform`s, `<use>` x/y, nested `<svg>` and
//!   `<symbol>` viewBox mappings; lengths in absolute units converted exactly).
//!   usvg drops an element whose own transform has a scale factor below f32's
//!   epsilon (1.2e-7), content and all, although f64 carries it: on a `<g>` or
//!   a plain shape drawn in place, the attribute is renamed in the text usvg
//!   reads (`source.rs`), so usvg lays the content out, well conditioned, in
//!   the element's own coordinates, and the true transform is composed in f64,
//!   both in the reconstruction and onto usvg's own geometry below the element
//!   (`viewport::Frame::with_omitted`). The trade-off: usvg never sees the
//!   true transform, so what only usvg's geometry gives (markers, clip paths
//!   and masks, glyphs, a path whose reconstruction fails) is right only where
//!   that composition is exact; hence not on a `<use>`, `<text>`, nested
//!   `<svg>`, an element drawn through a `<use>`, or a shape with its own clip
//!   path, mask or markers: those are still dropped, and named in a warning.
//!   Each reconstruction is checked against usvg's own f32 path (`reconstruct.rs`);
//!   where it disagrees or needs context this reader lacks (lengths in %, em or
//!   ex, CSS transforms, a transform on the root `<svg>`), the path keeps usvg's
//!   f32 data with its absolute transform applied in f64, and one warning in
//!   [`Drawing::warnings`] counts such paths by reason. Text glyph outlines and
//!   marker contents come from fonts and usvg: they are always single precision
//!   (their arcs are cubics), without a warning;
//! - coordinates are in [`Units`](crate::Units): by default the user units of the root
//!   `viewBox`, the numbers written in the document (an Inkscape drawing in mm
//!   comes out in mm): the root `viewBox` → `width`/`height` mapping is not
//!   applied (on the f32 fallback, where usvg folds it into every absolute
//!   transform, `viewport.rs` undoes it once, in f64; a `transform` on the root
//!   `<svg>` stays, expressed in user units). [`Units::Px`](crate::Units::Px) gives the root
//!   viewport's CSS px (96 per inch), as usvg and the reference's nanosvg give
//!   them, the root mapping computed in f64. Without a root `viewBox` both are
//!   the same. A `scale` then multiplies every coordinate;
//! - zero-length segments are dropped; a subpath with no segment left is an
//!   isolated point (a path that is only `M x y` is dropped by usvg, as by
//!   browsers and nanosvg; a trailing `M` after drawing commands is kept);
//! - a number in a geometry attribute beyond the f32 range (which usvg would
//!   silently drop with its element) is a [`Error::BadCoordinate`];
//! - [`Drawing::features`] lists every segment, every isolated point and the
//!   implicit closing segment of each open subpath of a filled shape;
//! - what you see is what you mesh (`paint.rs`, [`PaintOptions`]): what the
//!   renderer does not paint is not loaded (hidden, `display: none`, zero
//!   opacity along the group chain, zero fill or stroke opacity, markers on
//!   `<rect>`, `<circle>`, `<ellipse>`: usvg's group of them is recognised by
//!   what it holds and by the element's marker properties resolving to a
//!   `<marker>`, never by position alone); paint whose effective opacity is
//!   below `min_opacity` is decoration (no shape; its outline only on request);
//!   a stroke becomes the area it paints (kurbo's stroke expansion of the f64
//!   path in the path's user space: width, joins, caps, miter limit, dashes),
//!   a shape of its own after (or, `paint-order: stroke`, before) its fill,
//!   unless thinner than the hairline width; a shape under clip paths and
//!   masks carries them ([`Clip`]: the clip's own rule, nested clips,
//!   `clipPathUnits`; a mask approximated by the fills of its content that are
//!   not fully transparent, within its rectangle, in usvg's single precision),
//!   and each clip's outline is feature geometry ([`drawing::ShapeKind::ClipOutline`]);
//!   [`Drawing::paint`] counts all of it;
//! - images and filters are not geometry (they leave a warning, as does text
//!   that yields no outline; a filtered shape keeps its outline and is counted).
//!
//! Guarantees to the next stage (see [`Drawing`]): at least one feature, every
//! coordinate finite with magnitude at most [`Drawing::MAX_COORD`], and a bbox
//! whose diagonal is not negligible (< 1e-6) relative to its distance from the
//! origin unless the drawing is a single point.

mod budget;
mod conic;
pub(crate) mod drawing;
mod duplicates;
mod geometry;
mod load;
mod options;
mod outline;
mod paint;
mod reconstruct;
mod soup;
mod source;
mod viewport;
pub(crate) mod winding;

pub(crate) use drawing::{
    Clip, Drawing, Feature, FeatureGeom, FeatureSource, FillRule, Segment, Shape, ShapeId,
    ShapeKind, Subpath,
};
pub(crate) use options::HairlineRule;
pub use options::LoadOptions;
pub use paint::{PaintOptions, StrokeMode};

pub(crate) use outline::one_digit_below;
pub(crate) use reconstruct::Precision;

use crate::{Error, Result};
use std::path::Path;

/// Load and normalise an SVG file as `opts` says (units, scale, paint
/// model, budgets).
///
/// # Errors
/// [`Error::Read`] if the file cannot be read (the message names the cause),
/// [`Error::IsDirectory`] for a directory, otherwise as [`load_bytes`].
pub fn load_file(path: &Path, opts: &LoadOptions) -> Result<Drawing> {
    let data = read_input(path)?;
    load_bytes(&data, opts)
}

/// The bytes of the input file at `path`.
///
/// # Errors
/// [`Error::Read`], [`Error::IsDirectory`], [`Error::EmptyFile`].
fn read_input(path: &Path) -> Result<Vec<u8>> {
    let meta = std::fs::metadata(path).map_err(Error::Read)?;
    if meta.is_dir() {
        return Err(Error::IsDirectory);
    }
    let data = std::fs::read(path).map_err(Error::Read)?;
    if data.is_empty() {
        return Err(Error::EmptyFile);
    }
    Ok(data)
}

/// Load and normalise an SVG document from its bytes (UTF-8, or UTF-16 with a
/// BOM) as `opts` says: its coordinates in [`LoadOptions::units`] multiplied
/// by [`LoadOptions::scale`], SVG's paint model read as
/// [`LoadOptions::paint`] says (what the renderer does not paint is not
/// loaded: hidden, `display: none`, zero opacity along the group chain, zero
/// fill or stroke opacity; paint below [`PaintOptions::min_opacity`] is
/// decoration, no region; strokes become the areas they paint, see
/// [`StrokeMode`]; shapes under a clip path or mask carry it, see
/// [`Shape::paint`], and the clip's outline is feature geometry), within the
/// input budgets of options made by [`LoadOptions::from_params`].
///
/// ```
/// use triwild::{ErrorKind, LoadOptions, load_bytes};
/// let d = load_bytes(br#"<svg xmlns="http://www.w3.org/2000/svg">
///     <rect x="0" y="0" width="4" height="2"/></svg>"#, &LoadOptions::DEFAULT)?;
/// assert_eq!(d.shapes.len(), 1);
/// assert_eq!(d.diagonal(), 20f64.sqrt());
/// // Not a drawing: one clear error, never a panic.
/// let e = load_bytes(b"<html><body>hello</body></html>", &LoadOptions::DEFAULT).unwrap_err();
/// assert_eq!(e.kind(), ErrorKind::BadInput);
/// # Ok::<(), triwild::Error>(())
/// ```
///
/// Units and scale:
///
/// ```
/// use triwild::{LoadOptions, Units, load_bytes};
/// // an A4 page drawn in millimetres (Inkscape's default)
/// let doc = br#"<svg xmlns="http://www.w3.org/2000/svg" width="210mm" height="297mm"
///     viewBox="0 0 210 297"><rect x="10" y="20" width="100" height="50"/></svg>"#;
/// let mm = load_bytes(doc, &LoadOptions::DEFAULT)?;
/// assert_eq!((mm.bbox.x0, mm.bbox.y1), (10.0, -20.0)); // the document's numbers, y up
/// assert_eq!(mm.bbox.width(), 100.0);
/// let px = load_bytes(doc, &LoadOptions::DEFAULT.with_units(Units::Px))?; // CSS px: 96 per inch
/// assert!((px.bbox.width() - 100.0 * 96.0 / 25.4).abs() < 1e-4);
/// let metres = load_bytes(doc, &LoadOptions::DEFAULT.with_scale(1e-3))?;
/// assert!((metres.bbox.width() - 0.1).abs() < 1e-15);
/// # Ok::<(), triwild::Error>(())
/// ```
///
/// The paint model:
///
/// ```
/// use triwild::{LoadOptions, PaintOptions, StrokeMode, load_bytes};
/// let doc = br##"<svg xmlns="http://www.w3.org/2000/svg">
///     <rect x="0" y="0" width="10" height="10" fill="none" stroke="#000" stroke-width="2"/>
///     <rect x="20" y="0" width="10" height="10" fill="#f00" visibility="hidden"/></svg>"##;
/// let area = load_bytes(doc, &LoadOptions::DEFAULT)?;
/// assert_eq!(area.shapes.len(), 1);
/// assert_eq!(area.shapes[0].name(), "shape-0-stroke");
/// assert_eq!(area.paint.strokes_as_areas, 1);
/// assert_eq!(area.paint.dropped_invisible, 1);
/// let line = PaintOptions::DEFAULT.with_strokes(StrokeMode::Line);
/// let line = load_bytes(doc, &LoadOptions::DEFAULT.with_paint(line))?;
/// assert!(!line.shapes[0].filled); // the centre line: a feature, no region
/// # Ok::<(), triwild::Error>(())
/// ```
///
/// # Errors
/// - [`Error::InvalidParams`]: the scale is not finite and positive;
/// - [`Error::EmptyFile`]: no bytes, or only whitespace;
/// - [`Error::NotSvg`]: binary data (PNG, gzip/.svgz, ...), broken XML, an HTML
///   page, a root element other than `<svg>`, or input beyond usvg's safety
///   limits (entity bombs, more than 1,000,000 elements after `<use>` expansion);
/// - [`Error::NoGeometry`]: nothing drawable;
/// - [`Error::BadCoordinate`]: a coordinate that is not finite or exceeds
///   [`Drawing::MAX_COORD`] after transforms (the units and the scale
///   included), a drawing too small for its distance from the origin, or (in
///   user units) a root `viewBox` whose mapping to the viewport cannot be undone;
/// - [`Error::TooLarge`]: past an input budget.
pub fn load_bytes(data: &[u8], opts: &LoadOptions) -> Result<Drawing> {
    load_with_precision(data, opts).map(|(drawing, _)| drawing)
}

/// A coordinate error that `--scale` caused says so.
fn blame_scale(e: Error, scale: f64) -> Error {
    match e {
        Error::BadCoordinate(m) if scale > 1.0 => Error::BadCoordinate(format!(
            "coordinates too large after --scale {scale:e}: {m}"
        )),
        e => e,
    }
}

/// [`load_bytes`], and how the paths came out (f64 from the document's text,
/// or usvg's single precision and why): XML entity expansion is checked
/// against the budgets on the raw text, segments, elements and the memory
/// estimate on the XML tree before usvg builds its tree, and again on the
/// drawing.
///
/// # Errors
/// As [`load_bytes`].
pub(crate) fn load_with_precision(data: &[u8], opts: &LoadOptions) -> Result<(Drawing, Precision)> {
    let (units, scale, limits) = (opts.units, opts.scale, &opts.limits);
    let paint = &opts.effective_paint();
    // checked before parsing, so a bad scale is reported whatever the input
    viewport::check_scale(scale)?;
    let (outlines, view_box) = load::parse(data, limits, |parsed| {
        let frame =
            viewport::Frame::new(units, scale, parsed.facts.root_view_box, parsed.tree.size())?;
        let view_box = parsed
            .facts
            .root_view_box
            .map(|vb| vb.output_rect(units, scale, parsed.tree.size()));
        let map = reconstruct::OutputMap::new(&parsed.source, units, scale);
        outline::collect(parsed, &frame, map, paint).map(|o| (o, view_box))
    })
    .map_err(|e| blame_scale(e, scale))?;
    let tol = duplicates::DUPLICATE_TOL_REL * soup::diagonal(&outlines.shapes);
    let (shapes, merged) = duplicates::merge(outlines.shapes, tol);
    let mut drawing = soup::assemble(shapes, outlines.warnings)?;
    drawing.paint = outlines.paint;
    drawing.paint.duplicates_merged = merged;
    drawing.view_box = view_box;
    // A stroke whose fill a copy on top replaced is its own region again.
    for i in 0..drawing.shapes.len() {
        let id = ShapeId::from_index(i);
        if drawing.shapes[i].paint.joins_fill && drawing.joined_fill(id).is_none() {
            drawing.shapes[i].paint.joins_fill = false;
            drawing.paint.strokes_joined -= 1;
        }
    }
    let d = drawing.diagonal();
    if d < Drawing::MIN_DIAGONAL {
        let cause = format!(
            "the drawing's bounding-box diagonal is {d:e}, below {:e}",
            Drawing::MIN_DIAGONAL
        );
        return Err(Error::BadCoordinate(if scale < 1.0 {
            format!("coordinates too small after --scale {scale:e}: {cause}")
        } else {
            format!("coordinates too small: {cause}")
        }));
    }
    let counts = budget::Counts {
        segments: drawing
            .features
            .iter()
            .filter(|f| !matches!(f.geom, FeatureGeom::Point(_)))
            .count() as u64,
        shapes: drawing.shapes.len() as u64,
    };
    budget::check_counts(counts, data.len() as u64, limits)?;
    drawing.precision = drawing::PathPrecision {
        f64_paths: outlines.precision.exact,
        single_precision_paths: outlines.precision.glyphs + outlines.precision.fallbacks(),
    };
    tracing::debug!(
        shapes = drawing.shapes.len(),
        features = drawing.features.len(),
        warnings = drawing.warnings.len(),
        exact_paths = outlines.precision.exact,
        single_precision_paths = outlines.precision.fallbacks(),
        glyph_paths = outlines.precision.glyphs,
        "svg loaded"
    );
    Ok((drawing, outlines.precision))
}

#[cfg(test)]
mod tests;
