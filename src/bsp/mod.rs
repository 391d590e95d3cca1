//! The exact BSP mesher: a valid triangle mesh of a box that contains every
//! input segment exactly as a chain of its edges.
//!
//! It owns [`build`]: a Delaunay triangulation (spade, `f64`) of every input
//! point, segment endpoint and box corner, constrained by the segments that
//! cross many of its edges (a hatch's long lines) where they cross no other
//! (`seed.rs`); each triangle is the root of a BSP cell cut by the supporting
//! line of every input segment that still meets its interior, in rational
//! arithmetic (`cut.rs`); each convex cell is
//! triangulated by a fan from one of its corners when that gives no
//! degenerate triangle, else from its exact barycentre; then edges are tagged
//! with the segments they lie on, and vertices are rounded to `f64` wherever
//! no incident triangle would invert or degenerate, trying the nearest `f64`
//! point and then a few ulps around it (`fan.rs`); a vertex that none of
//! those can hold is collapsed into an `f64` neighbour when that keeps the
//! mesh valid and the feature chains intact (`collapse.rs`).
//!
//! Guarantees to the next stage, for any finite input inside the box: every
//! triangle is exactly counter-clockwise; the mesh is conforming (no
//! T-junctions) and covers the box; before rounding, every input segment is
//! exactly a chain of mesh edges, each tagged with the segment's
//! [`SegmentTag`]. Rounding ([`BspOptions::round`]) moves vertices by at most
//! a few ulps per coordinate (half an ulp when the nearest point fits), so a
//! rounded vertex may be off its segment by that much; a collapsed vertex
//! leaves its chain's neighbours joined by one edge, its tags merged; vertices
//! that can be neither rounded nor collapsed keep their rational position.
//!
//! Thesis §2.3.1 (BSP construction), §2.3.4 (hybrid kernel), §4.4.1 (linear
//! meshing); docs/design.md "Data flow" (bsp) and "Exactness".

mod collapse;
mod cut;
mod fan;
mod seed;

use crate::Result;
use crate::budget::Deadline;
use crate::error::check_deadline;
use crate::mesh::TriMesh;
use crate::stage::Stage;
use kurbo::{Point, Rect};
use std::time::Instant;

/// Which input feature a segment belongs to; the mesher copies it onto the
/// mesh edges along the segment and never interprets it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum SegmentTag {
    /// A piece of a primary feature section, with the section parameter at
    /// the segment's `a` and `b` ends.
    Primary {
        /// Section index (the caller's numbering).
        section: u32,
        /// Parameter at `a`, then at `b`.
        t: [f64; 2],
    },
    /// A piece of a secondary polyline.
    Secondary {
        /// Polyline index (the caller's numbering).
        polyline: u32,
    },
}

/// One input segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BspSegment {
    /// Start point.
    pub a: Point,
    /// End point.
    pub b: Point,
    /// What the segment belongs to.
    pub tag: SegmentTag,
}

/// The mesher's input: independent of the feature stage.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct BspInput {
    /// Isolated feature points (become vertices tagged `feature_point`).
    pub points: Vec<Point>,
    /// Endpoints of primary sections (become vertices tagged `section_endpoint`).
    pub section_endpoints: Vec<Point>,
    /// Feature segments (crossing, overlapping, duplicated: anything goes).
    pub segments: Vec<BspSegment>,
    /// Free vertices where the size field asks for a finer mesh than the
    /// features' vertices give (untagged: the optimizer moves and removes
    /// them like any vertex the BSP makes).
    pub steiner: Vec<Point>,
}

/// Options of [`build`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub(crate) struct BspOptions {
    /// Round rational vertices to `f64` where no incident triangle inverts
    /// (default `true`). Off, the output is exactly conforming in rationals.
    pub round: bool,
    /// Passes of the rounding sweep (default 4): rounding one vertex can make
    /// a neighbour roundable.
    pub round_passes: u32,
    /// Stop with an error when the mesh would exceed this many vertices
    /// (default 50 million): the BSP can be quadratic in the segment count.
    pub max_vertices: u32,
    /// The run's wall-clock limit, checked while cutting (default none).
    pub deadline: Deadline,
}

impl BspOptions {
    /// The defaults.
    pub(crate) const DEFAULT: BspOptions = BspOptions {
        round: true,
        round_passes: 4,
        max_vertices: 50_000_000,
        deadline: Deadline::NONE,
    };

    /// Set [`BspOptions::deadline`].
    pub(crate) fn with_deadline(mut self, deadline: Deadline) -> Self {
        self.deadline = deadline;
        self
    }

    /// Set [`BspOptions::round`].
    #[cfg(test)]
    pub(crate) fn with_round(mut self, round: bool) -> Self {
        self.round = round;
        self
    }

    /// Set [`BspOptions::max_vertices`].
    #[cfg(test)]
    pub(crate) fn with_max_vertices(mut self, n: u32) -> Self {
        self.max_vertices = n;
        self
    }
}

impl Default for BspOptions {
    fn default() -> Self {
        BspOptions::DEFAULT
    }
}

/// Counts and timings of one BSP build (§2.3.1).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct BspStats {
    /// Distinct vertices given to the Delaunay triangulation.
    pub seed_vertices: usize,
    /// Of the seed vertices, the free ones the size field asked for (where it
    /// is below half the global size, away from the features).
    pub field_seeds: usize,
    /// Triangles of the Delaunay triangulation.
    pub seed_triangles: usize,
    /// Distinct segments offered to the seed as constraint edges (those that
    /// cross more than 32 edges of the plain Delaunay triangulation).
    pub seed_constraints: usize,
    /// Of those, the ones the seed refused (they cross one already in): only
    /// these cut seed triangles.
    pub seed_refused: usize,
    /// Seed triangles crossed by at least one segment.
    pub cut_triangles: usize,
    /// Convex cells after cutting.
    pub cells: usize,
    /// Vertices added at cell barycentres.
    pub barycentre_vertices: usize,
    /// Output vertices.
    pub vertices: usize,
    /// Output triangles.
    pub triangles: usize,
    /// Edges tagged with at least one segment.
    pub tagged_edges: usize,
    /// Vertices with a non-`f64` position before rounding.
    pub rational_before_rounding: usize,
    /// Rational vertices that no nearby `f64` point could hold, collapsed
    /// into a neighbour.
    pub collapsed_vertices: usize,
    /// Vertices still rational in the output.
    pub rational_vertices: usize,
    /// Power-of-two exponent applied to coordinates for the Delaunay step.
    pub delaunay_scale_exp: i32,
    /// Seconds in the Delaunay step.
    pub seed_seconds: f64,
    /// Seconds cutting and triangulating cells.
    pub cut_seconds: f64,
    /// Seconds tagging edges and rounding.
    pub finish_seconds: f64,
    /// Of those, seconds tagging edges.
    pub tag_seconds: f64,
    /// Total seconds.
    pub seconds: f64,
}

/// Build the exact BSP mesh of `bbox` conforming to `input`.
///
/// # Errors
/// [`crate::Error::BadCoordinate`] for a non-finite coordinate, a point
/// outside `bbox`, or coordinates whose dynamic range no power-of-two scaling
/// brings into the Delaunay step's range (about 2^-142 .. 2^201 after
/// scaling); [`crate::Error::InvalidParams`] for an empty or non-finite box;
/// [`crate::Error::Meshing`] when [`BspOptions::max_vertices`] is exceeded;
/// the deadline's error when [`BspOptions::deadline`] passes (checked per
/// chunk of seed triangles cut, of segments tagged, of vertices rounded).
pub(crate) fn build(
    input: &BspInput,
    bbox: Rect,
    opts: &BspOptions,
) -> Result<(TriMesh, BspStats)> {
    let t0 = Instant::now();
    let mut stats = BspStats::default();
    let seed = seed::seed(input, bbox)?;
    stats.seed_vertices = seed.points.len();
    stats.field_seeds = input.steiner.len();
    stats.seed_triangles = seed.triangles.len();
    stats.seed_constraints = seed.constraints;
    stats.seed_refused = seed.refused;
    stats.delaunay_scale_exp = seed.scale_exp;
    let t1 = Instant::now();
    let mut mesh = cut::cut_all(input, &seed, opts, &mut stats)?;
    let t2 = Instant::now();
    if let Err(e) = tag_and_round(&mut mesh, input, opts, &mut stats) {
        crate::budget::dispose(mesh);
        return Err(e);
    }
    stats.rational_vertices = mesh.vertices().filter(|&v| mesh.is_rational(v)).count();
    stats.vertices = mesh.num_vertices();
    stats.triangles = mesh.num_faces();
    stats.tagged_edges = mesh.tagged_edges().count();
    let t3 = Instant::now();
    stats.seed_seconds = (t1 - t0).as_secs_f64();
    stats.cut_seconds = (t2 - t1).as_secs_f64();
    stats.finish_seconds = (t3 - t2).as_secs_f64();
    stats.seconds = (t3 - t0).as_secs_f64();
    tracing::debug!(?stats, "bsp done");
    Ok((mesh, stats))
}

/// Tag the segments' edges of the cut mesh, then round its rational vertices
/// (collapsing those no nearby `f64` point can hold), as [`build`] asks.
fn tag_and_round(
    mesh: &mut TriMesh,
    input: &BspInput,
    opts: &BspOptions,
    stats: &mut BspStats,
) -> Result<()> {
    let t = Instant::now();
    fan::tag_segments(mesh, input, &opts.deadline)?;
    stats.tag_seconds = t.elapsed().as_secs_f64();
    stats.rational_before_rounding = mesh.vertices().filter(|&v| mesh.is_rational(v)).count();
    if !opts.round {
        return Ok(());
    }
    fan::round_vertices(mesh, opts.round_passes, &opts.deadline)?;
    // What no f64 point can hold is collapsed into a neighbour, which may
    // free others to round; a few rounds at most.
    for _ in 0..opts.round_passes {
        let stuck: Vec<_> = mesh.vertices().filter(|&v| mesh.is_rational(v)).collect();
        let before = stats.collapsed_vertices;
        for (i, v) in stuck.into_iter().enumerate() {
            if i % fan::CHECK_EVERY == 0 {
                check_deadline(&opts.deadline, Stage::Bsp)?;
            }
            if mesh.is_vertex_alive(v) && collapse::try_collapse(mesh, v) {
                stats.collapsed_vertices += 1;
            }
        }
        if stats.collapsed_vertices == before {
            break;
        }
        fan::round_vertices(mesh, opts.round_passes, &opts.deadline)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
