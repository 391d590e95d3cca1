//! The mesh improvement schedule (thesis §2.3.2 "Mesh Improvement", §4.4.1):
//! passes of edge splitting, collapsing, swapping and vertex smoothing over the
//! whole mesh, with a target edge length per vertex, until the mesh is good
//! enough or the pass limit is reached.
//!
//! One pass:
//! 1. split every edge longer than 4/3 of its endpoints' mean target length,
//!    longest first (the new vertex gets that mean);
//! 2. collapse edges shorter than their mean target, shortest first
//!    (edges made short by a collapse are queued again; refused ones are
//!    retried once their neighbourhood changed), never creating an edge longer
//!    than 4/3 of its target (else splits and collapses would undo each other);
//! 3. swap interior non-feature edges where the swap lowers the larger energy of
//!    the two triangles, longest first;
//! 4. smooth every movable vertex (Newton on the one-ring AMIPS; along its curve
//!    for a primary vertex), in a fixed pseudo-random order;
//! 5. round the vertices still rational and project off-curve primary vertices
//!    toward their curve (invariant 5).
//!
//! When a pass stops paying off (the maximum energy fell by less than 0.25 and
//! the mean by less than 0.025), the sizing field is refined around the worst
//! triangles and relaxed (×1.5, up to `l`) elsewhere (see `update_sizing`).
//! After the last pass the targets go back to `l` and one more collapse pass
//! over every edge coarsens what was refined for nothing (new edges up to
//! `2 l`, triangles up to the mesh's worst energy or 2, whichever is larger,
//! capped by the stop energy); swaps and smoothing polish it, then min-max
//! smoothing (each ring's largest energy, through a high power of the energies)
//! and swaps lift the worst triangles while that still pays. From the
//! coarsening on, smoothing and swaps stretch no edge past `2 l`.
//!
//! Last, the worst-element phase (`repair.rs`) repairs the corners
//! below α that the feature edges leave room for: targets halved around them,
//! the passes run on that patch only, round after round (a round that makes
//! the worst such corner worse is rolled back and run with energy-bounded
//! splits); the statistics count the triangles left with one.
//!
//! Every operation goes through `crate::ops`, so every invariant holds after
//! each one and refused operations leave the mesh as it was. Collapse, swap and
//! smoothing never raise the local maximum energy; splits may.
//!
//! Stop rules: the mesh has every vertex in `f64` and on its curve, no edge
//! longer than `2 l` (smoothing may stretch a few edges past the split bound
//! of 4/3 of the target), and the minimum angle exceeds α or the maximum energy
//! is below the stop energy, both over the triangles not locked by three
//! feature edges (the input's own shapes); or, once the sizing field has hit
//! its floor, ten passes in a row improved neither the maximum nor the mean
//! energy; or the pass limit. Vertices still rational at the end go through the envelope
//! stages of §2.3.4 (denser sampling, then a larger ε, each followed by more
//! rounding and smoothing); a vertex left rational after them makes the mesh
//! unusable, which the caller reports as an error.
//!
//! The schedule's files, by phase: `driver.rs` (the linear entry points, the
//! phases, the stop rules), `curved.rs` (the curved stage's entry:
//! [`CurvedPasses`]), one file per pass (`split.rs`, `collapse.rs`,
//! `swap.rs`, `smooth.rs` with rounding and projection), `repair.rs` (the
//! worst-element phase), `sizing.rs` (the refinement of the targets, the
//! collapses' length rule), `queue.rs` (the edge queue, the plans made ahead).
//! The state has one owner per kind: `targets.rs` ([`Targets`]: each vertex's
//! target and the size field at it), `memo.rs` ([`Memos`]: the operation
//! clock, the stamps and the memos of refused operations), `scope.rs`
//! ([`Scope`](scope::Scope): what a pass works on, the whole mesh or the worst-element
//! phase's patch, passed to each pass) and `stats.rs` (tallies, statistics,
//! measures). This file holds the tuning constants and [`Schedule`], which
//! owns the mesh, its context, the limits and one value of each.

mod collapse;
mod curved;
mod driver;
mod memo;
mod queue;
mod repair;
mod scope;
mod sizing;
mod smooth;
mod split;
mod stats;
mod swap;
mod targets;

pub(crate) use curved::CurvedPasses;
#[cfg(test)]
pub(crate) use driver::optimize;
pub(crate) use driver::{LinearOptions, OptimizeOptions, optimize_with_field};
pub(crate) use repair::needle_energy;
pub(crate) use stats::{EnergyMeasure, OpTally, OptimizeStats, StopReason, measure_energy};

use crate::budget::Deadline;
use crate::mesh::{TriMesh, VertexId};
use crate::ops::Context;
use crate::params::OptimizerParams;
use crate::sizing::SizeField;
use memo::Memos;
use targets::Targets;

/// Edges longer than this multiple of their mean target are split, and a
/// collapse may not create an edge longer than this multiple (else splits and
/// collapses would undo each other). Thesis §2.3.2: "larger than 4/3 [Botsch
/// and Kobbelt 2004; Dunyach et al. 2013] times the average of the target edge
/// lengths".
const SPLIT_ABOVE: f64 = 4.0 / 3.0;

/// At most this many split passes resolve the size field before the main
/// passes where it asks for sizes well below the BSP mesh's edges (each halves
/// the longest edges: 2^12 covers any size above the sizing floor).
const FIELD_SPLIT_PASSES: usize = 12;
/// Edges shorter than this fraction of their target are collapsed in a pass
/// (the collapse may not make an edge longer than [`SPLIT_ABOVE`] of its
/// target, so splits never undo it). The thesis (§2.3.2) collapses below 4/5;
/// 1 measured better on the dev set; see `docs/tuning.md`.
const COLLAPSE_FACTOR: f64 = 1.0;
/// Edges shorter than this multiple of `l` are collapsed by the final
/// coarsening: every edge (the energy rule and [`COARSEN_STRETCH`] decide).
const COARSEN_FACTOR: f64 = f64::INFINITY;
/// The final coarsening may create edges up to this multiple of `l` (no split
/// pass follows it to undo them).
const COARSEN_STRETCH: f64 = 2.0;
/// Where the field is at `l` (open space, away from every size source) the
/// final coarsening keeps new edges within the split bound: `l` then means the
/// edge length there. It costs few triangles: most are near features, where
/// the field is below `l` and the coarsening still stretches edges to
/// [`COARSEN_STRETCH`]. Measurements in `docs/tuning.md`.
const OPEN_STRETCH: f64 = SPLIT_ABOVE;
/// Rounds of the equalisation (relaxation, collapse below
/// [`EQUALIZE_COLLAPSE`], swaps) after the coarsening; it stops earlier once a
/// round moves and collapses nothing.
const EQUALIZE_ROUNDS: usize = 6;
/// The equalisation collapses edges shorter than this fraction of their
/// target: isotropic remeshing's 4/5 (thesis §2.3.2 too).
const EQUALIZE_COLLAPSE: f64 = 0.8;
/// The equalisation's collapses may create edges up to this multiple of their
/// target; the relaxation that follows shortens them again. With the split
/// bound 4/3 instead, a half-edge collapse in a mesh of edges near 1 is
/// refused (its new edges reach 1 + 0.8). Measurements in `docs/tuning.md`.
const EQUALIZE_STRETCH: f64 = 1.5;
/// The final coarsening may always make triangles up to this energy (1 for
/// equilateral), even in a mesh whose worst triangle is better (the stop energy
/// still caps it). With the mesh's own worst energy as the only bound, a mesh
/// of near-equilateral triangles coarsens far more at one `l` than at half of
/// it, so the triangle count jumps with `l`. Measurements in `docs/tuning.md`.
const COARSEN_ENERGY: f64 = 2.0;
/// After this many passes in a row whose splits the collapses undid (see
/// `driver`), the stop rule no longer asks for the stretch against the field.
const UNDONE_PASSES: usize = 3;
/// At most this many min-max polishing passes (min-max smoothing and swaps).
/// Empirical (`docs/tuning.md`).
const MINMAX_PASSES: usize = 10;
/// The min-max polish stops once a pass lowers the largest energy by less
/// than this fraction of it. Empirical (`docs/tuning.md`).
const MINMAX_MIN_GAIN: f64 = 1e-3;
/// At most this many polishing passes (swaps and smoothing) end the schedule.
/// Empirical (`docs/tuning.md`).
const POLISH_PASSES: usize = 6;
/// The polish stops once a pass lowers the mean energy by less than this
/// fraction of it. Empirical (`docs/tuning.md`).
const POLISH_MIN_GAIN: f64 = 1e-4;
/// The sizing field is refined after a pass that lowered the largest energy by
/// less than this (and the mean by less than [`SIZING_STALL_MEAN`]). The
/// TriWild reference (`optimization.cpp`, `refine`) uses 5e-1 with its energy
/// (2 for an equilateral triangle); halved for ours (1 for equilateral), as
/// [`crate::OptimizerParams::stop_energy`] halves the thesis's 10.
const SIZING_STALL_MAX: f64 = 0.25;
/// See [`SIZING_STALL_MAX`]: the reference's 5e-2 for the mean energy, halved.
const SIZING_STALL_MEAN: f64 = 0.025;
/// Once the sizing field has hit its floor, this many passes in a row without
/// gain stop the schedule (TriWild reference, `optimization.cpp`, `refine`:
/// `it > 10` and the last 10 passes).
const STALL_PASSES: usize = 10;
/// A pass "without gain" lowers neither the largest nor the mean energy by
/// more than this (the TriWild reference's 1e-4).
const STALL_TOLERANCE: f64 = 1e-4;
/// The quality goal also needs every edge shorter than this multiple of `l`
/// (smoothing may stretch a few edges past [`SPLIT_ABOVE`]).
const STOP_STRETCH: f64 = 2.0;
/// A triangle refines the sizing field when its energy exceeds the largest
/// energy divided by this (and [`SIZING_STOP_FRACTION`] of the stop energy).
/// TriWild reference (`update_scaling_field`: `max_energy / 100`).
const SIZING_WORST_DIVISOR: f64 = 100.0;
/// See [`SIZING_WORST_DIVISOR`]: the reference's `stop_energy * 0.9`.
const SIZING_STOP_FRACTION: f64 = 0.9;
/// Along an edge whose ends' field values differ by less than this factor the
/// field at the midpoint is taken as their mean (see `Targets::edge_target`).
const FIELD_LINEAR: f64 = 1.1;
/// A vertex whose target falls below this fraction of the field counts as
/// refined by the optimizer (the size report leaves its edges out).
const REFINED_BELOW: f64 = 0.999;
/// A target near a bad triangle is multiplied by this (thesis §2.3.2: "divided
/// by 2"; the reference's `refine_scale = 0.5`).
const SIZING_REFINE: f64 = 0.5;
/// Every other target is multiplied by this (thesis §2.3.2: "multiplied by
/// 1.5"; the TriWild reference uses 1.1 when it preserves features).
const SIZING_RELAX: f64 = 1.5;
/// Targets within this multiple of a bad vertex's target are refined too,
/// graded by distance (TriWild reference: `radius0 = ideal_edge_length * 1.8`,
/// "increasing the radius would increase the #v in output"; ours scales with
/// the bad vertex's target).
const SIZING_RADIUS: f64 = 1.8;
/// Rounds of a collapse pass (refused collapses retried once their
/// neighbourhood changed). Empirical (`docs/tuning.md`).
const COLLAPSE_ROUNDS: usize = 4;
/// Pops of one collapse round: this many per queued edge, plus
/// [`COLLAPSE_BUDGET_EXTRA`] (edges made short are queued again). Empirical
/// (`docs/tuning.md`).
const COLLAPSE_BUDGET_PER_EDGE: usize = 4;
/// See [`COLLAPSE_BUDGET_PER_EDGE`].
const COLLAPSE_BUDGET_EXTRA: usize = 16;
/// A swap must lower the larger energy of its two triangles by more than this
/// fraction, so equal configurations never flip back and forth. Empirical
/// (`docs/tuning.md`).
const SWAP_MIN_GAIN: f64 = 1e-9;
/// With more than one worker thread, the collapse and smoothing passes plan
/// this many upcoming operations at a time in parallel (see
/// [`Schedule::collapse_round`]); the plans are then applied one by one in the
/// sequential order, so the mesh is the same for any number of threads.
const PLAN_AHEAD: usize = 256;
/// The step of [`ShortestFirst`](queue::ShortestFirst)'s summary of its sorted edges: a block of
/// sixteen 16-byte entries is four cache lines.
const SUMMARY_STEP: usize = 16;
/// The top summary of the collapse round's sorted edges holds at most this
/// many (16 KiB: it stays in the first-level cache).
const SUMMARY_TOP: usize = 1024;

/// The fewest edges queued again worth staging to plan in parallel: two (a
/// lone edge is planned when popped); staging from larger batches left more
/// pops planned one by one on the pipeline's thread. Measurements in
/// `docs/tuning.md`.
const STAGE_MIN: usize = 2;
/// A staged batch smaller than this is planned on the pipeline's thread, at
/// once: handing out a few plans costs about what making them does (see
/// `docs/tuning.md`).
const STAGE_PAR_MIN: usize = 8;
/// The envelope stages for vertices left rational (after §2.3.4's, which
/// sample denser and then widen ε): ε multiplied by each of these in turn,
/// with [`ENVELOPE_SPACING`] of the sampling spacing. Our values, empirical
/// (`docs/tuning.md`).
const ENVELOPE_EPS: [f64; 3] = [1.0, 1.5, 2.0];
/// See [`ENVELOPE_EPS`]: the sampling spacing of every stage, as a fraction
/// of the original one.
const ENVELOPE_SPACING: f64 = 0.5;
/// Smoothing and rounding rounds in one envelope stage. Empirical
/// (`docs/tuning.md`).
const ENVELOPE_ROUNDS: usize = 3;
/// Seed of the linear schedule's smoothing order: "triwild" in ASCII.
const SEED: u64 = 0x0074_7269_7769_6c64;

/// A deterministic permutation generator (SplitMix64).
struct Shuffle(u64);

impl Shuffle {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Shuffle `v` in place.
    fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            let j = (self.next() % (i as u64 + 1)) as usize;
            v.swap(i, j);
        }
    }
}

/// What every pass reads, in the linear schedule and the curved stage alike,
/// in user units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PassLimits {
    /// Target edge length `l`: the sizing field's upper bound, and every
    /// target without a field.
    pub l: f64,
    /// The run's wall-clock limit: past it a pass stops and the schedule
    /// says so ([`StopReason::TimeLimit`]).
    pub deadline: Deadline,
    /// The user's optimizer parameters, carried whole from
    /// [`crate::Params::optimizer`]: a pass reads a knob as
    /// `self.limits.params.<knob>`.
    pub params: OptimizerParams,
}

/// The optimizer's state: the mesh and its context, the limits, the targets
/// ([`Targets`]), the memos of the passes ([`Memos`]) and the statistics.
/// What a pass works on is its argument ([`Scope`](scope::Scope)).
///
/// `D` is what only the driver reads: [`LinearOptions`] for the linear
/// schedule ([`Schedule::new`]); `()` for the curved stage, which runs the
/// collapse, swap and smoothing passes alone ([`CurvedPasses`]).
pub(crate) struct Schedule<'a, D> {
    mesh: &'a mut TriMesh,
    ctx: &'a mut Context,
    /// What every pass reads.
    limits: PassLimits,
    /// What only the driver reads (see above).
    driver: D,
    /// The smoothing order's generator.
    rng: Shuffle,
    targets: Targets<'a>,
    memos: Memos,
    /// Longest edge a collapse may create, relative to its target: the
    /// phase's ([`Schedule::enter`]).
    stretch: Stretch,
    stats: OptimizeStats,
    /// The phase being timed (`None`: none is, as in the curved stage).
    phase: Option<stats::OpenPhase>,
    /// Tests: what the plans made ahead and the refusals kept did.
    #[cfg(test)]
    tally: stats::TestTally,
}

/// The bounds of the main passes (and of the curved stage's): no energy
/// floor ([`Context::energy_floor`]), no bound on a new edge
/// ([`Context::max_new_edge`]), collapses within the split bound.
const MAIN_BOUNDS: (f64, f64, Stretch) = (0.0, f64::INFINITY, Stretch::uniform(SPLIT_ABOVE));

/// The entry of `v` in a per-vertex-slot array, grown with `fill` as needed.
fn slot<T: Copy>(values: &mut Vec<T>, v: VertexId, fill: T) -> &mut T {
    let i = v.index();
    if i >= values.len() {
        values.resize(i + 1, fill);
    }
    &mut values[i]
}

impl<'a> Schedule<'a, LinearOptions> {
    /// The linear schedule over `mesh` with every target at the size field
    /// `field`, the bounds of [`Phase::Main`], and the smoothing order drawn
    /// from `seed`.
    pub(crate) fn new(
        mesh: &'a mut TriMesh,
        ctx: &'a mut Context,
        opts: &OptimizeOptions,
        seed: u64,
        field: &'a SizeField,
    ) -> Self {
        Schedule::with_driver(mesh, ctx, opts.limits, opts.linear, seed, Some(field))
    }
}

impl<'a, D> Schedule<'a, D> {
    /// A schedule over `mesh` with every target at `field` (`None`:
    /// `limits.l` everywhere), the bounds of the main passes
    /// ([`MAIN_BOUNDS`]), and the smoothing order drawn from `seed`.
    fn with_driver(
        mesh: &'a mut TriMesh,
        ctx: &'a mut Context,
        limits: PassLimits,
        driver: D,
        seed: u64,
        field: Option<&'a SizeField>,
    ) -> Self {
        let targets = Targets::new(mesh, field, limits.l);
        let mut s = Schedule {
            mesh,
            ctx,
            limits,
            driver,
            rng: Shuffle(seed),
            targets,
            memos: Memos::new(),
            stretch: MAIN_BOUNDS.2,
            stats: OptimizeStats::start(),
            phase: None,
            #[cfg(test)]
            tally: stats::TestTally::default(),
        };
        s.bound(MAIN_BOUNDS);
        s
    }

    /// The mesh being improved.
    pub(super) fn mesh(&self) -> &TriMesh {
        self.mesh
    }

    /// The tallies so far.
    pub(super) fn stats(&self) -> &OptimizeStats {
        &self.stats
    }

    /// Bound what the operations may do: the energy a free vertex's ring may
    /// reach, the longest edge a swap or a move may create, and the
    /// collapses' stretch (what the phases differ by: [`Phase`]).
    fn bound(&mut self, (energy_floor, max_new_edge, stretch): (f64, f64, Stretch)) {
        self.ctx.energy_floor = energy_floor;
        self.ctx.max_new_edge = max_new_edge;
        self.stretch = stretch;
    }

    /// End the phase being timed (if any) and start timing `phase`
    /// ([`stats::PhaseStats`]).
    pub(super) fn begin_phase(&mut self, phase: &'static str) {
        self.end_phase();
        self.phase = Some(stats::OpenPhase::start(phase, &self.stats));
    }

    /// End the phase being timed, if any: its record joins the statistics.
    pub(super) fn end_phase(&mut self) {
        if let Some(open) = self.phase.take() {
            let record = open.end(&self.stats, self.mesh.num_faces());
            self.stats.phases.push(record);
        }
    }

    /// Count a pass's queue of `n` items in the phase being timed.
    pub(super) fn queued(&mut self, n: usize) {
        if let Some(open) = &mut self.phase {
            open.queue(n);
        }
    }

    /// [`Memos::fresh`]: whether a plan made ahead at clock `at`, which read
    /// the vertices `read` (and their rings), still stands (the tests count
    /// the answers).
    fn fresh(&mut self, at: u64, read: &[VertexId]) -> bool {
        let fresh = self.memos.fresh(at, read);
        #[cfg(test)]
        if fresh {
            self.tally.ahead.0 += 1;
        } else {
            self.tally.ahead.1 += 1;
        }
        fresh
    }
}

/// The meshes of the schedule's whole-pass tests: `bsp` BSP meshes of random
/// segments, then `delaunay` Delaunay meshes with a primary curve (seeds from
/// 0), under the plain energy rule.
#[cfg(test)]
fn test_meshes(bsp: u64, delaunay: u64) -> impl Iterator<Item = (TriMesh, crate::ops::Context)> {
    use crate::ops::EnergyRule;
    use crate::ops::tests::{bsp_mesh, delaunay_mesh};
    (0..bsp)
        .map(|seed| bsp_mesh(seed, EnergyRule::NoWorseMax))
        .chain((0..delaunay).map(|seed| delaunay_mesh(seed, EnergyRule::NoWorseMax)))
}

/// The options of the schedule's whole-pass tests: `l` 0.1 on the unit box.
#[cfg(test)]
pub(super) fn test_options() -> OptimizeOptions {
    OptimizeOptions {
        limits: PassLimits {
            l: 0.1,
            deadline: Deadline::NONE,
            params: OptimizerParams::DEFAULT,
        },
        linear: LinearOptions {
            l_floor: 0.01,
            stop_energy: 5.0,
            alpha_deg: 10.0,
            max_passes: 40,
            max_vertices: 20_000,
        },
    }
}

/// How far a collapse may stretch the edges it creates, as a multiple of
/// their target: where the field is at `l`, and where it is below (near a
/// size source).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Stretch {
    /// Where the field is at `l`.
    pub open: f64,
    /// Where the field is below `l`.
    pub below: f64,
}

impl Stretch {
    /// The same bound everywhere.
    pub(super) const fn uniform(s: f64) -> Stretch {
        Stretch { open: s, below: s }
    }
}

/// The phases of the linear schedule, each with its own bounds on what the
/// operations may do: the energy a free vertex's ring may reach
/// ([`Context::energy_floor`]), the longest edge a swap or a move may create
/// ([`Context::max_new_edge`]), and the collapses' [`Stretch`].
/// [`Schedule::enter`] sets all three, so no phase inherits another's. The
/// curved stage's passes keep the bounds of the main passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Phase {
    /// The main passes (and the split passes before them): every operation
    /// keeps the worst energy of its ring, collapses keep the split bound.
    Main,
    /// The final coarsening (see `driver`).
    Coarsen,
    /// The equalisation of edge lengths after it.
    Equalize,
    /// The polish (swaps and smoothing) at the delivered sizes.
    Polish,
    /// The min-max polish: quality first, no length bound.
    MinMax,
}
