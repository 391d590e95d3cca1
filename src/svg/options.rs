//! [`LoadOptions`]: how [`super::load_file`] and [`super::load_bytes`] read a document.

use super::PaintOptions;
use crate::budget::Limits;
use crate::units::Units;

/// How an SVG document is read into a [`super::Drawing`]: the units and scale
/// of its coordinates, how SVG's paint model is read, and the input budgets.
///
/// [`LoadOptions::DEFAULT`] reads the numbers written in the document (the
/// user units of its root `viewBox`, scale 1), paints as
/// [`PaintOptions::DEFAULT`] says, with no budget. [`LoadOptions::from_params`]
/// reads a document as the mesher's parameters say (their units, scale,
/// budgets, and strokes narrower than their `l_min` or `mu` kept as lines):
/// what `run_file`, `triwild features` and the Python package load.
///
/// ```
/// use triwild::{LoadOptions, PaintOptions, StrokeMode, Units, load_bytes};
/// let doc = br#"<svg xmlns="http://www.w3.org/2000/svg" width="210mm" height="297mm"
///     viewBox="0 0 210 297"><rect x="10" y="20" width="100" height="50"/></svg>"#;
/// let mm = load_bytes(doc, &LoadOptions::DEFAULT)?;
/// assert_eq!(mm.bbox.width(), 100.0);
/// let px = load_bytes(doc, &LoadOptions::DEFAULT.with_units(Units::Px))?;
/// assert!((px.bbox.width() - 100.0 * 96.0 / 25.4).abs() < 1e-4);
/// let lines = LoadOptions::DEFAULT.with_paint(PaintOptions::DEFAULT.with_strokes(StrokeMode::Line));
/// assert_eq!(load_bytes(doc, &lines)?.shapes.len(), 1);
/// # Ok::<(), triwild::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct LoadOptions {
    /// The units of the output coordinates. Default [`Units::User`], the
    /// numbers written in the document.
    pub units: Units,
    /// A factor on every coordinate, after `units`; finite and positive.
    /// Default 1.
    pub scale: f64,
    /// How SVG's paint model is read (strokes, opacity thresholds, hairline
    /// width). Default [`PaintOptions::DEFAULT`]. Options made by
    /// [`LoadOptions::from_params`] replace its hairline width and μ with the
    /// parameters' `l_min` and `mu` when the document is read.
    pub paint: PaintOptions,
    /// Input budgets (segments, shapes, memory estimate). Default none.
    pub(crate) limits: Limits,
    /// The parameters' hairline width and μ, which replace `paint`'s own.
    pub(crate) hairlines: Option<HairlineRule>,
}

/// The hairline width and feature envelope μ a stroke must reach to become
/// an area, each with whether it is a fraction of the drawing's diagonal:
/// the parameters' `l_min` and `mu`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct HairlineRule {
    /// Strokes narrower stay centre lines.
    pub(crate) min_stroke_width: (f64, bool),
    /// Strokes narrower stay centre lines (their outlines would be closer than μ).
    pub(crate) mu: (f64, bool),
}

impl LoadOptions {
    /// User units, scale 1, [`PaintOptions::DEFAULT`], no budget.
    pub const DEFAULT: LoadOptions = LoadOptions {
        units: Units::User,
        scale: 1.0,
        paint: PaintOptions::DEFAULT,
        limits: Limits::NONE,
        hairlines: None,
    };

    /// Set the units of the output coordinates.
    pub const fn with_units(mut self, units: Units) -> Self {
        self.units = units;
        self
    }

    /// Set the factor on every coordinate.
    pub const fn with_scale(mut self, scale: f64) -> Self {
        self.scale = scale;
        self
    }

    /// Set how the paint model is read. Options made by
    /// [`LoadOptions::from_params`] keep the parameters' hairline width and μ.
    pub const fn with_paint(mut self, paint: PaintOptions) -> Self {
        self.paint = paint;
        self
    }

    /// The paint model as the loader reads it: `paint` with the parameters'
    /// hairline width and μ, if any.
    pub(crate) fn effective_paint(&self) -> PaintOptions {
        match self.hairlines {
            Some(h) => self
                .paint
                .with_mu(h.mu.0, h.mu.1)
                .with_min_stroke_width(h.min_stroke_width.0, h.min_stroke_width.1),
            None => self.paint,
        }
    }
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions::DEFAULT
    }
}
