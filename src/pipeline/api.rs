//! The library's entry points on a drawing: [`LoadOptions::from_params`],
//! which loads a document as the mesher's parameters say, and
//! [`mesh_drawing`], which meshes a loaded drawing. [`super::run_file`] is
//! the file-to-file run of the command line.

use super::{Meshed, mesh_within};
use crate::Result;
use crate::params::{Length, Params};
use crate::regions::RegionOptions;
use crate::svg::{Drawing, HairlineRule, LoadOptions, PaintOptions};

impl LoadOptions {
    /// Load options as `params` say: their units and scale, their input
    /// budgets ([`Params::max_segments`], [`Params::max_shapes`],
    /// [`Params::max_memory_mb`]), [`PaintOptions::DEFAULT`], and strokes
    /// narrower than `params.l_min` (hairlines) or than `params.mu` (outlines
    /// the features stage would not keep apart) kept as lines, whatever paint
    /// model [`LoadOptions::with_paint`] sets afterwards: what
    /// [`crate::run_file`], `triwild features` and the Python package load.
    ///
    /// ```
    /// use triwild::{Length, LoadOptions, Params, RegionOptions, load_bytes, mesh_drawing};
    /// let params = Params::DEFAULT.with_l(Length::Rel(0.2));
    /// let svg = br#"<svg xmlns="http://www.w3.org/2000/svg"><rect width="4" height="2"/></svg>"#;
    /// let drawing = load_bytes(svg, &LoadOptions::from_params(&params)?)?;
    /// let meshed = mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT)?;
    /// assert!(meshed.report.output.triangles > 0);
    /// # Ok::<(), triwild::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`crate::Error::InvalidParams`] for parameters that
    /// [`Params::validate`] rejects.
    pub fn from_params(params: &Params) -> Result<LoadOptions> {
        params.validate()?;
        let length = |l: Length| match l {
            Length::Rel(r) => (r, true),
            Length::Abs(a) => (a, false),
        };
        Ok(LoadOptions {
            units: params.units,
            scale: params.scale,
            paint: PaintOptions::DEFAULT,
            limits: params.limits(),
            hairlines: Some(HairlineRule {
                min_stroke_width: length(params.l_min),
                mu: length(params.mu),
            }),
        })
    }
}

/// Mesh a loaded drawing and tag (or drop) its regions as `regions` says
/// ([`RegionOptions::DEFAULT`]: one physical surface per filled shape, plus
/// `background`). The drawing is in the units it was loaded in:
/// `params.units` and `params.scale` only say so in the report (load it with
/// [`LoadOptions::from_params`] for the parameters' units and scale).
///
/// ```
/// use triwild::{Length, LoadOptions, Params, RegionMode, RegionOptions, load_bytes, mesh_drawing};
/// let svg = br#"<svg xmlns="http://www.w3.org/2000/svg">
///     <rect x="0" y="0" width="10" height="10" fill="grey"/>
///     <circle id="hole" cx="5" cy="5" r="2" fill="white"/></svg>"#;
/// let params = Params::DEFAULT.with_l(Length::Rel(0.1));
/// let drawing = load_bytes(svg, &LoadOptions::from_params(&params)?)?;
/// let by_shape = mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT)?;
/// assert!(by_shape.mesh.surfaces.iter().any(|s| s == "hole"));
/// let by_colour = RegionOptions::DEFAULT.with_mode(RegionMode::Colour);
/// let by_colour = mesh_drawing(&drawing, &params, &by_colour)?;
/// assert!(by_colour.mesh.surfaces.iter().any(|s| s == "fill-#ffffff"));
/// # Ok::<(), triwild::Error>(())
/// ```
///
/// # Errors
/// Invalid parameters, a failed meshing stage, or region options that select
/// nothing or name regions that do not exist.
pub fn mesh_drawing(drawing: &Drawing, params: &Params, regions: &RegionOptions) -> Result<Meshed> {
    params.validate()?;
    mesh_within(drawing, params, regions, params.deadline())
}
