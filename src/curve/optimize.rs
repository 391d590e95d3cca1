//! Curved mesh optimization (thesis §4.4.2 "Curved Mesh Optimization"): the
//! collapse, swap and smoothing of the linear stage, run again once the mesh
//! is to be curved, with the invariants in curved mode
//! ([`crate::ops::CurvedRule`]).
//!
//! The linear stage keeps each primary edge's curve piece turning less than
//! α = 10° (invariant 3), which forces many short edges along curves. Here that
//! bound is relaxed (to the curved rule's, 90° by default); instead every
//! element an operation touches is re-curved with its exact pieces and must be
//! certified, and the energy rule compares curved AMIPS energies (an
//! uncertified element counts `+∞`, so an operation that certifies it is an
//! improvement), and the corner rule keeps the straight (corner) energies:
//! no operation makes one larger than both the worst of the faces it replaces
//! and the linear stop energy ([`crate::ops::CurvedRule::corner_floor`]), so a
//! badly curved element is never traded for a straight sliver. No split is
//! made.
//!
//! Schedule: one preliminary pass, then at most `max_passes` passes, each
//! 1. collapse edges shorter than 4/5 `l`, shortest first (edges made short are
//!    queued again; refused ones are retried once a face around them changed),
//!    never creating an edge longer than 4/3 `l`;
//! 2. swap interior non-feature edges where that strictly lowers the larger
//!    curved energy of their two triangles, longest first;
//! 3. smooth every movable vertex (`ops::try_smooth`; primary vertices slide
//!    along their curve) in a fixed pseudo-random order.
//!
//! It stops before a pass when the largest curved energy (of the certified
//! triangles not locked by three feature edges) is below the stop energy, and
//! after a pass that lowered the largest energy by less than 1e-2 and the mean
//! by less than 1e-3. Every loop has a budget.
//!
//! Guarantee: every operation goes through `crate::ops`, so each face it
//! created is a certified curved element with at most one curved edge, and no
//! certified face became uncertified.

use crate::budget::Deadline;
use crate::element::Order;
use crate::mesh::TriMesh;
use crate::ops::invariants::curved;
use crate::ops::{self, Context};
use crate::optimize::schedule::{CurvedPasses, EnergyMeasure, OpTally, PassLimits, measure_energy};
use crate::params::OptimizerParams;
use crate::sizing::SizeField;

/// Collapse edges shorter than this fraction of `l` (the shared schedule's
/// collapses never create an edge longer than 4/3 `l`): thesis §2.3.2,
/// "collapse an edge if its length is smaller than 4ℓ/5".
const COLLAPSE_BELOW: f64 = 4.0 / 5.0;
/// The stage stops after a pass that lowered the largest curved energy by less
/// than this (and the mean by less than [`STALL_MEAN`]). Empirical
/// (`docs/tuning.md`).
const STALL_MAX: f64 = 1e-2;
/// See [`STALL_MAX`].
const STALL_MEAN: f64 = 1e-3;
/// Seed of the curved stage's smoothing order: "curve!" in ASCII.
const SEED: u64 = 0x0063_7572_7665_6421;

/// Parameters of the curved optimization, in user units.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CurvedOptimizeOptions<'a> {
    /// Target edge length `l`.
    pub l: f64,
    /// The size field (`None`: `l` everywhere).
    pub field: Option<&'a SizeField>,
    /// Curved AMIPS energy (1 for equilateral) below which the mesh is good enough.
    pub stop_energy: f64,
    /// Passes after the preliminary one; 0 skips the stage.
    pub max_passes: u32,
    /// The run's wall-clock limit: no pass starts after it.
    pub deadline: Deadline,
    /// The user's optimizer parameters, carried whole (the schedule's passes
    /// read their knobs here).
    pub params: OptimizerParams,
}

/// What the curved optimization did (part of [`super::CurveStats`]).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CurvedOptimizeStats {
    /// Passes run, the preliminary one included (0: the stage was skipped).
    pub passes: u32,
    /// Edge collapses.
    pub collapse: OpTally,
    /// Edge swaps.
    pub swap: OpTally,
    /// Secondary feature edges rerouted through the apex of their sliver.
    pub reroute: OpTally,
    /// Vertex smoothing.
    pub smooth: OpTally,
    /// Largest curved AMIPS of the certified triangles before the stage.
    pub max_amips_before: f64,
    /// Largest curved AMIPS of the certified triangles after the stage.
    pub max_amips_after: f64,
    /// Largest straight (corner) AMIPS of the triangles before the stage (the
    /// corner rule keeps the value after below the larger of this and the
    /// linear stop energy).
    pub max_corner_amips_before: f64,
    /// Same, after the stage.
    pub max_corner_amips_after: f64,
    /// Triangles before the stage.
    pub triangles_before: usize,
    /// Triangles after the stage.
    pub triangles_after: usize,
    /// Triangles that were not certified curved elements before the stage
    /// (left to the fit).
    pub uncertified_before: usize,
    /// Same, after the stage.
    pub uncertified_after: usize,
}

/// Curved energies of a mesh, for the stop rules: triangles that are not
/// certified curved elements are `unmeasured`.
fn measure(mesh: &TriMesh, ctx: &Context, rule: &ops::CurvedRule) -> EnergyMeasure {
    measure_energy(mesh, |v| {
        curved::energy(mesh, ctx, rule, v).filter(|e| e.is_finite())
    })
}

/// Optimize `mesh` in curved mode (see the module doc). `ctx` must be in curved
/// mode (`ctx.curved` set); without it, or with `max_passes == 0` or a linear
/// order, nothing is done.
pub(crate) fn optimize_curved(
    mesh: &mut TriMesh,
    ctx: &Context,
    opts: &CurvedOptimizeOptions,
) -> CurvedOptimizeStats {
    let Some(rule) = ctx.curved else {
        return CurvedOptimizeStats::default();
    };
    if opts.max_passes == 0
        || rule.order == Order::Linear
        || opts.l.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return CurvedOptimizeStats::default();
    }
    let _span = tracing::info_span!("curved optimization").entered();
    let start = measure(mesh, ctx, &rule);
    let mut stats = CurvedOptimizeStats {
        max_amips_before: start.max_all,
        max_corner_amips_before: ops::max_corner_energy(mesh, mesh.faces()),
        triangles_before: mesh.num_faces(),
        uncertified_before: start.unmeasured,
        ..CurvedOptimizeStats::default()
    };
    // The linear schedule's collapse, swap and smoothing passes, with every
    // target at the size field (its refinement and stop rules are not used
    // here), under the bounds of its main passes, not the linear stage's last
    // ones.
    let limits = PassLimits {
        l: opts.l,
        deadline: opts.deadline,
        params: opts.params,
    };
    let mut sched_ctx = ctx.clone();
    let mut s = CurvedPasses::new(mesh, &mut sched_ctx, limits, opts.field, SEED);
    let mut pass = |s: &mut CurvedPasses<'_>| {
        let (collapses, swaps, smooths) = s.pass(COLLAPSE_BELOW);
        stats.passes += 1;
        tracing::debug!(
            pass = stats.passes,
            collapses,
            swaps,
            smooths,
            faces = s.mesh().num_faces(),
            "curved optimization pass"
        );
    };
    pass(&mut s);
    let mut last = measure(s.mesh(), ctx, &rule);
    for _ in 0..opts.max_passes {
        if last.max < opts.stop_energy || opts.deadline.expired() {
            break;
        }
        pass(&mut s);
        let now = measure(s.mesh(), ctx, &rule);
        let stalled = last.max - now.max < STALL_MAX && last.mean - now.mean < STALL_MEAN;
        last = now;
        if stalled {
            break;
        }
    }
    let tallies = s.stats();
    stats.collapse = tallies.collapse.clone();
    stats.swap = tallies.swap.clone();
    stats.reroute = tallies.reroute.clone();
    stats.smooth = tallies.smooth.clone();
    stats.max_amips_after = last.max_all;
    stats.uncertified_after = last.unmeasured;
    stats.triangles_after = s.mesh().num_faces();
    stats.max_corner_amips_after = ops::max_corner_energy(s.mesh(), s.mesh().faces());
    stats
}
