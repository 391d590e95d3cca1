//! The size field h(x): the one answer to "how long should an edge be here".
//!
//! Built once per run, before the BSP, from the drawing and the parameters,
//! never from the mesh being optimized: the global edge length `l` (the largest
//! size), the user's fields ([`crate::SizeSpec`]: per region, near outlines,
//! boxes, a formula, a background mesh, a function), the sizes the drawing
//! itself asks for (thin strokes meshed as areas: `STROKE_SIZE_PER_WIDTH` times their width on their
//! outlines, growing by a factor 2 per element; the automatic local feature size: narrow gaps, thin parts and
//! tight curves), combined by minimum, clamped to `[l_min, l]` and graded so
//! that h grows by at most the grading `G` from one element to the next (a
//! slope of `G − 1` per unit length). Every stage reads it: the optimizer
//! (split above 4/3·h, collapse below h, judged at the edge's midpoint), the
//! curved stage and the CDT baseline. The features' resampling reads it per
//! curve ([`SizeField::for_curve`]): a thin stroke's size applies to that
//! stroke's own outline only, and only where it is primary, so the other
//! curves that run along or across a stroke (the outline of the shape it
//! strokes, its neighbours) keep the size they had without it and the
//! optimizer refines around them only as much as the field asks.
//!
//! Thesis §2.3.2 and §4.4.1 drive the optimizer with a sizing field refined
//! around bad elements; that refinement stays the optimizer's (below h, counted
//! apart in the report), this field is what it starts from and returns to.

mod fields;
mod report;
mod seeds;
mod sources;
pub(crate) mod tree;

pub(crate) use report::edge_match;
pub use report::{EdgeMatch, HISTOGRAM_BOUNDS, SizingReport};

use crate::Result;
use crate::budget::Deadline;
use crate::features::CutFor;
use crate::params::{Resolved, SizeSpec};
use crate::svg::{Drawing, ShapeId};
use kurbo::{Point, Rect};
use tree::Tree;

/// The size field of one run (see the module doc).
#[derive(Clone, Debug)]
pub(crate) struct SizeField {
    tree: Tree,
    /// `Some(l)` when the field is `l` everywhere (evaluation is then free).
    uniform: Option<f64>,
    l: f64,
    /// What the features' resampling reads besides a thin stroke's own size.
    curves: CurveField,
    /// Per shape: the size a thin stroke asks for on its own outline, within
    /// `[l_min, l]` (`None`: no thin stroke; empty when the drawing has none).
    stroke_sizes: Vec<Option<f64>>,
    report: SizingReport,
}

/// The field the features' resampling reads (see [`SizeField::for_curve`]).
#[derive(Clone, Debug)]
enum CurveField {
    /// The field itself: no thin stroke adds to it.
    Full,
    /// `l`: the thin strokes' sizes were the only ones.
    Uniform,
    /// The field built from every source but the thin strokes.
    WithoutStrokes(Tree),
}

/// What the field is built from beside the parameters: the drawing, the name
/// of each shape's region as the .msh will write it (`None`: the shape is no
/// region), and the box the mesh covers.
pub(crate) struct FieldInput<'a> {
    pub drawing: &'a Drawing,
    pub resolved: &'a Resolved,
    pub spec: &'a SizeSpec,
    pub region_names: &'a [Option<String>],
    pub bounds: Rect,
    pub deadline: Deadline,
    /// The mesh's vertex budget (`--max-vertices`): a field finer than a mesh
    /// of this many vertices could follow is resolved only to
    /// [`LEAVES_PER_VERTEX`] leaves per vertex of it.
    pub max_vertices: usize,
}

/// Leaves of the field's quadtree per vertex of the budget: a field that
/// asks for a mesh of the whole budget has about 1.6 leaves per vertex (a
/// leaf's side is between h/2 and h), so a budget of two leaves resolves every
/// field that a mesh within the vertex budget can follow.
pub(crate) const LEAVES_PER_VERTEX: usize = 2;

impl SizeField {
    /// `l` everywhere.
    pub(crate) fn uniform(l: f64, bounds: Rect) -> SizeField {
        SizeField {
            tree: Tree::uniform(bounds, l),
            uniform: Some(l),
            l,
            curves: CurveField::Full,
            stroke_sizes: Vec::new(),
            report: SizingReport::uniform(l),
        }
    }

    /// Build the field (see the module doc).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParams`] for a field that names no region, a formula that
    /// does not parse or gives a non-finite value, a background mesh that cannot
    /// be read or does not cover the drawing, a function that fails or gives a
    /// non-finite value (each naming the point); [`crate::Error::TimeLimit`] past the deadline.
    pub(crate) fn build(input: &FieldInput<'_>) -> Result<SizeField> {
        let r = input.resolved;
        let l = r.l;
        let l_min = r.l_min.min(l);
        let slope = input.spec.grading - 1.0;
        let mut points = fields::PointFields::new(input)?;
        let mut sources = sources::strokes(input.drawing, r.mu, slope);
        let n_strokes = sources.len();
        let mut applied: Vec<String> = Vec::new();
        if n_strokes > 0 {
            applied.push("strokes".into());
        }
        let user = sources::user(input, slope, &mut applied)?;
        let mut asked_min = user.iter().map(|s| s.h).fold(l, f64::min);
        sources.extend(user);
        if input.spec.feature_size {
            let lfs = sources::feature_size(input, slope);
            if !lfs.is_empty() {
                applied.push("feature-size".into());
            }
            sources.extend(lfs);
        }
        applied.extend(points.names());
        let n_sources = sources.len();
        if applied.is_empty() || slope.is_nan() {
            let mut f = SizeField::uniform(l, input.bounds);
            f.report.grading = input.spec.grading;
            return Ok(f);
        }
        let deadline = input.deadline;
        let keep_going = |bytes: u64| {
            crate::error::check_deadline(&deadline, crate::Stage::Sizing)?;
            if bytes >= crate::budget::LARGE_BYTES {
                deadline
                    .check_room(bytes)
                    .map_err(|o| crate::Error::overrun(o, crate::Stage::Sizing))?;
            }
            Ok(())
        };
        let max_leaves = input.max_vertices.saturating_mul(LEAVES_PER_VERTEX);
        let mut build = |sources: &[tree::Source]| {
            Tree::build(
                input.bounds,
                l_min,
                l,
                slope,
                sources,
                &mut |pts: &[Point]| {
                    let v = points.eval(pts)?;
                    asked_min = v.iter().copied().fold(asked_min, f64::min);
                    Ok(v)
                },
                max_leaves,
                &keep_going,
            )
        };
        let tree = build(&sources)?;
        let min_size = tree.min_value();
        let (curves, stroke_sizes) = if n_strokes == 0 || min_size >= l {
            (CurveField::Full, Vec::new())
        } else {
            let curves = if applied.len() == 1 {
                CurveField::Uniform
            } else {
                CurveField::WithoutStrokes(build(&sources[n_strokes..])?)
            };
            let sizes = input
                .drawing
                .shapes
                .iter()
                .map(|s| sources::stroke_size(s, r.mu).map(|h| h.clamp(l_min, l)))
                .collect();
            (curves, sizes)
        };
        let report = SizingReport {
            fields: applied,
            grading: input.spec.grading,
            l,
            l_min,
            min_size,
            asked_min,
            sources: n_sources,
            leaves: tree.leaves(),
            capped: tree.capped(),
            edges: None,
        };
        Ok(SizeField {
            uniform: (min_size >= l).then_some(l),
            tree,
            l,
            curves,
            stroke_sizes,
            report,
        })
    }

    /// The size at `p`, within `[l_min, l]`.
    pub(crate) fn at(&self, p: Point) -> f64 {
        match self.uniform {
            Some(l) => l,
            None => self.tree.at(p),
        }
    }

    /// The size the features stage cuts a curve of `shape` to at `p` (see
    /// the module doc): the field without the thin strokes' sizes, and on a
    /// thin stroke's own outline, for any section ([`CutFor::Any`]: it may
    /// become primary), at most the stroke's size (what the field is there).
    /// A run of the stroke's sections found secondary ([`CutFor::Secondary`])
    /// is cut at the size without it: the optimizer refines it as the field
    /// asks, and cut finer it only made the BSP and the optimizer slower (the
    /// stroked house clipart home4: 17 230 secondary segments instead of
    /// 5 454, 14 % more triangles, the same smallest angle). The field itself
    /// ([`SizeField::at`]) where the drawing has no thin stroke.
    pub(crate) fn for_curve(&self, p: Point, shape: ShapeId, cut: CutFor) -> f64 {
        let h = match &self.curves {
            CurveField::Full => return self.at(p),
            CurveField::Uniform => self.l,
            CurveField::WithoutStrokes(tree) => tree.at(p),
        };
        if cut == CutFor::Secondary {
            return h;
        }
        match self.stroke_sizes.get(shape.index()) {
            Some(&Some(stroke)) => h.min(stroke),
            _ => h,
        }
    }

    /// The size at the midpoint of `a` and `b`.
    pub(crate) fn at_mid(&self, a: Point, b: Point) -> f64 {
        match self.uniform {
            Some(l) => l,
            None => self.tree.at(a.midpoint(b)),
        }
    }

    /// Whether the user asked for sizes (a field of [`SizeSpec`] or the
    /// automatic feature size): then no collapse stretches an edge past the
    /// split bound where the field is below `l`. Without (the drawing's own
    /// thin strokes only), the final coarsening stretches edges as it did
    /// before the size field, and the default meshes keep their size.
    pub(crate) fn is_asked(&self) -> bool {
        self.report.fields.iter().any(|f| f != "strokes")
    }

    /// Whether the field is `l` everywhere.
    pub(crate) fn is_uniform(&self) -> bool {
        self.uniform.is_some()
    }

    /// The largest size, `l`.
    pub(crate) fn l(&self) -> f64 {
        self.l
    }

    /// What the field was built from (the edge match is filled in later).
    pub(crate) fn report(&self) -> &SizingReport {
        &self.report
    }
}

#[cfg(test)]
mod tests;
