//! Regions: what the drawing fills becomes tagged FEM domains (docs/design.md "regions").
//!
//! Owns the decision of which filled SVG shape each triangle belongs to, the
//! physical surfaces made from it, and the dropping of regions (`--cut-outside`,
//! `--keep`, `--hole`). Works on a [`FemMesh`] of any order, so it serves every
//! mesher (cdt, linear, curved).
//!
//! # What a region is
//! - Inside / outside per shape comes from the shape's own fill rule (nonzero,
//!   evenodd) and winding numbers evaluated on the input curves ([`crate::svg::winding`]);
//!   an open subpath is closed by a straight segment, as SVG fills it (the loader
//!   adds that segment as a feature, so region boundaries conform to the mesh).
//! - A triangle belongs to the topmost filled shape (paint order) covering it,
//!   else to the background: what you see is what is meshed.
//!
//! # Guarantees
//! - Every triangle and every line element of the result is in a physical group;
//!   empty groups are removed; nodes no element uses are removed and the
//!   numbering stays contiguous, in the old order.
//! - Every edge of the kept domain's boundary (the padded box, the outline left
//!   by `--cut-outside`, the rims of dropped regions) is a line element of the
//!   physical curve [`crate::fem::BOUNDARY`], with the domain on its left
//!   (`orient`); feature lines run one way per chain ([`orient_lines`]).
//! - Each face of the mesh (triangles connected across edges that are not line
//!   elements) gets one label, so a region boundary is always a chain of line
//!   elements.
//!
//! # The region of a flattened triangle
//! A linear mesh (the CDT baseline) conforms to the *flattened* features: each
//! curve is replaced by a polyline within μ of it. A triangle in the thin sliver
//! between a curve and its polyline may then have its centroid on the other side
//! of the true curve than its face. We define the region of a triangle as the
//! region of its face, and the region of a face as the label that covers the
//! largest part of its area when each triangle is classified against the true
//! curves at a point well inside it. Away from the curves (farther than μ) the
//! two sides agree, so a face that is not itself a μ-thin sliver is labelled
//! as the true drawing labels it, and region boundaries are exactly the
//! mesh's feature edges. The area of a region then differs from the exact
//! area by at most the area between the curves and their flattening:
//! |Δ area| ≤ μ · (length of the region's curved boundary) (for chords of a
//! smooth arc the sliver is about ⅔·μ per unit length). Triangles whose own
//! sample disagrees with their face are counted in [`RegionReport`]
//! (`relabelled`, `relabelled_area`): a large relabelled area points at a
//! missing feature edge. A shape the picture shows (wider than half the
//! hairline width l_min beside its outline, or thinner than that there and
//! topmost inside its own outline, or under a triangle's own sample) that ends
//! with no triangle at all has lost its region, typically a stroke or sliver
//! narrower than the feature envelope μ, or a shape a transform thinned out,
//! whose outlines the mesh does not keep apart: counted (`lost_shapes`) and
//! named in a `--stats` warning, never dropped silently. The curved mesher makes the boundaries exact; then
//! the same rule gives exact areas.

mod classify;
mod drawn;
mod element;
mod orient;
pub(crate) mod select;

pub(crate) use classify::{ClassifyOptions, classify};
pub(crate) use drawn::DrawnAreas;
pub(crate) use orient::orient_lines;
pub(crate) use select::{
    DOMAIN, RegionOptions, RegionStat, apply, colour_name, secondary_lengths, stats_of,
};

use crate::Result;
use crate::fem::FemMesh;
use crate::svg::Drawing;
use kurbo::Rect;

/// The words every area-check warning carries (the batch page finds the
/// files that warn by them).
pub(crate) const AREA_WARNING: &str = "differ from the drawing";

/// What the area check needs beyond the drawing: the meshed box (the
/// background's extent) and the drawing's diagonal d.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct AreaCheck {
    /// The box the mesh covers.
    pub bounds: Rect,
    /// The drawing's diagonal.
    pub d: f64,
}

/// What the region stage did, for `--stats`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RegionReport {
    /// Each physical surface of the output: name, triangle count, area.
    pub surfaces: Vec<RegionStat>,
    /// Triangles whose sample points were all within ε_m of an outline.
    pub near_boundary: usize,
    /// Triangles relabelled to their face's majority (see the module docs).
    pub relabelled: usize,
    /// Their total area.
    pub relabelled_area: f64,
    /// Painted shapes whose region the mesh lost: the picture shows them (a
    /// triangle's own sample, or a probe beside their outline) but they own no
    /// triangle once each face took its majority label (their outlines are
    /// closer than the mesh resolves; `--stats` warns with their names).
    pub lost_shapes: usize,
    /// A bound on what the drawn areas ([`RegionStat::drawn_area`]) may be
    /// off by: the outline pieces whose sides could not be sampled (shorter
    /// than rounding resolves, or between outlines closer than 1e-10·d).
    pub drawn_unsure: f64,
    /// Surfaces of at most [`SmallRegions::MAX_TRIANGLES`] triangles, which a
    /// solver meets as a material of a handful of elements.
    pub small: SmallRegions,
}

/// The physical surfaces of a few triangles at most: how many, and
/// the smallest ones by area.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SmallRegions {
    /// Surfaces with at most [`SmallRegions::MAX_TRIANGLES`] triangles.
    pub count: usize,
    /// The smallest of them by area (at most [`SmallRegions::LISTED`]),
    /// smallest first: name, triangles, area.
    pub smallest: Vec<SmallRegion>,
}

/// One small surface.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SmallRegion {
    /// Surface name.
    pub name: String,
    /// Number of triangles.
    pub triangles: usize,
    /// Area.
    pub area: f64,
}

impl SmallRegions {
    /// A surface of at most this many triangles is small.
    pub const MAX_TRIANGLES: usize = 4;
    /// How many of the smallest are named.
    pub const LISTED: usize = 5;

    /// The small surfaces among `surfaces` (a surface with no triangle is not
    /// in the mesh and is not counted).
    pub(crate) fn of(surfaces: &[RegionStat]) -> SmallRegions {
        let mut small: Vec<&RegionStat> = surfaces
            .iter()
            .filter(|s| s.triangles > 0 && s.triangles <= Self::MAX_TRIANGLES)
            .collect();
        small.sort_by(|a, b| {
            a.area
                .abs()
                .total_cmp(&b.area.abs())
                .then(a.name.cmp(&b.name))
        });
        SmallRegions {
            count: small.len(),
            smallest: small
                .iter()
                .take(Self::LISTED)
                .map(|s| SmallRegion {
                    name: s.name.clone(),
                    triangles: s.triangles,
                    area: s.area,
                })
                .collect(),
        }
    }
}

/// Classify `mesh` by the fills of `drawing` and make the surfaces `opts` asks
/// for. `eps_abs` is the tolerance of [`ClassifyOptions::eps_abs`] (the pipeline
/// passes ε_m), `l_min` the hairline width (half of it is the probe step of
/// [`ClassifyOptions::probe_step`]). With [`select::RegionMode::None`] and
/// nothing to drop, no classification is done: every triangle goes to one
/// surface `domain`.
/// Either way the kept domain's boundary is added as the physical curve
/// [`crate::fem::BOUNDARY`] (the module's guarantees). Also returns the shapes
/// whose region was lost ([`RegionReport::lost_shapes`]). With `area`, each
/// surface's [`RegionStat::drawn_area`] is computed from the drawing
/// ([`drawn`]) and set beside its area on the mesh.
///
/// # Errors
/// As [`apply`]: a `--keep` name that matches no region, a `--hole` outside the
/// mesh, or nothing left; [`crate::Error::TimeLimit`] once `deadline` has passed
/// (checked while the triangles are classified).
pub(crate) fn tag(
    drawing: &Drawing,
    mesh: &FemMesh,
    opts: &RegionOptions,
    eps_abs: f64,
    l_min: f64,
    area: Option<AreaCheck>,
    deadline: crate::budget::Deadline,
) -> Result<(FemMesh, RegionReport, Vec<crate::svg::ShapeId>)> {
    if !opts.needs_classification() {
        let mut out = mesh.clone();
        out.surfaces = vec![DOMAIN.to_owned()];
        out.triangle_group = vec![0; mesh.triangle_count()];
        orient::add_boundary(&mut out);
        let mut surfaces = stats_of(&out);
        if let Some(check) = area {
            // one domain: the whole box
            for s in &mut surfaces {
                s.set_drawn(check.bounds.area());
            }
        }
        let report = RegionReport {
            surfaces,
            ..RegionReport::default()
        };
        return Ok((out, report, Vec::new()));
    }
    let classify_opts = ClassifyOptions::new(eps_abs)
        .with_probe_step(0.5 * l_min)
        .with_deadline(deadline);
    let asg = classify(drawing, mesh, &classify_opts);
    crate::error::check_deadline(&deadline, crate::stage::Stage::Regions)?;
    let drawn = match area {
        Some(check) => {
            let painting = crate::svg::winding::Painting::new(drawing);
            let drawn = drawn::drawn_areas(drawing, &painting, check.bounds, check.d, &deadline);
            crate::error::check_deadline(&deadline, crate::stage::Stage::Regions)?;
            drawn
        }
        None => None,
    };
    let (mut out, surfaces) = apply(drawing, mesh, &asg, opts, drawn.as_ref())?;
    orient::add_boundary(&mut out);
    Ok((
        out,
        RegionReport {
            surfaces,
            near_boundary: asg.near_boundary,
            relabelled: asg.relabelled,
            relabelled_area: asg.relabelled_area,
            lost_shapes: asg.lost.len(),
            drawn_unsure: drawn.as_ref().map_or(0.0, |d| d.unsure),
            small: SmallRegions::default(),
        },
        asg.lost,
    ))
}

#[cfg(test)]
mod tests;
