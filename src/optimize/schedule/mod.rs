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
//! The schedule's files, by phase: `driver.rs` (the entry points, the phases,
//! the stop rules), one file per pass (`split.rs`, `collapse.rs`, `swap.rs`,
//! `smooth.rs` with rounding and projection), `repair.rs` (the worst-element
//! phase), `sizing.rs` (the targets against
//! the size field), `queue.rs` (the edge queue, the plans made ahead) and
//! `stats.rs` (tallies, statistics, measures). This file holds the tuning
//! constants and the optimizer's state ([`Schedule`]).

mod collapse;
mod driver;
mod queue;
mod repair;
mod sizing;
mod smooth;
mod split;
mod stats;
mod swap;

#[cfg(test)]
pub(crate) use driver::optimize;
pub(crate) use driver::{OptimizeOptions, optimize_with_field};
pub(crate) use repair::needle_energy;
pub(crate) use stats::{EnergyMeasure, OpTally, OptimizeStats, StopReason, measure_energy};

#[cfg(test)]
use crate::budget::Deadline;
use crate::mesh::{EdgeKey, TriMesh, VertexId};
use crate::ops::{Context, Outcome, Reject};
use crate::sizing::SizeField;
use rustc_hash::FxHashSet;
use sizing::bases;

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
/// field at the midpoint is taken as their mean (see `Schedule::edge_target`).
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

/// The optimizer's state: the sizing field, the retry stamps and the tallies.
/// The curved stage (the curved mesh optimization, one layer up) drives its collapse, swap and
/// smoothing passes too, with a uniform target.
pub(crate) struct Schedule<'a> {
    mesh: &'a mut TriMesh,
    ctx: &'a mut Context,
    opts: OptimizeOptions,
    /// Target edge length by vertex slot.
    target: Vec<f64>,
    /// The size field at the vertex by vertex slot (the largest target: the
    /// optimizer's refinement relaxes and the coarsening resets to it).
    base: Vec<f64>,
    /// The size field (`crate::sizing`): what every edge is measured against.
    field: &'a SizeField,
    /// By vertex slot: whether the optimizer refined the vertex's target below
    /// the field (around a triangle it could not improve at the field's size).
    refined: Vec<bool>,
    stats: OptimizeStats,
    rng: Shuffle,
    /// Operation clock: advanced by every applied operation.
    clock: u64,
    /// By vertex slot: the clock when a face around the vertex last changed.
    stamp: Vec<u64>,
    /// Collapses refused, with the clock then and whether the length rule
    /// refused some direction: retried only once a face around either end has
    /// changed (the outcome depends on nothing else), or, for a length
    /// refusal, once the sizing field changed.
    failed_collapse: rustc_hash::FxHashMap<EdgeKey, FailedCollapse>,
    /// Smoothing refused, by vertex slot, with the clock then.
    failed_smooth: Vec<u64>,
    /// By vertex slot: the clock when the faces around the vertex last changed
    /// (split, collapse, swap; not a move).
    topo_stamp: Vec<u64>,
    /// Collapses of `.1` into `.0` refused by the role rules alone (a
    /// [`CollapsePlan::new`](crate::ops::CollapsePlan::new) refusal that says so), with the clock then and
    /// the reason: they stay refused until the faces around `.1` change.
    role_refused: rustc_hash::FxHashMap<(VertexId, VertexId), (u64, Reject)>,
    /// Longest edge a collapse may create, relative to its target.
    stretch: Stretch,

    /// The clock when the last swap pass scanned the edges, and the edges it
    /// found a gain on: an edge whose ends' faces have not changed since
    /// (so neither has its quad) and that had no gain then has none now.
    swap_scan: Option<(u64, FxHashSet<EdgeKey>)>,
    /// In the worst-element phase (`repair.rs`): the vertices whose edges
    /// and moves the passes consider (`None`: every vertex).
    patch: Option<repair::Patch>,
    /// In the worst-element phase: splits may not make their faces worse
    /// than before or than a corner of α allows (`repair.rs`).
    split_bounded: bool,
    /// The phase being timed (`None`: none is, as in the curved stage).
    phase: Option<stats::OpenPhase>,
    /// Tests: the plans made ahead that were used, and those found stale.
    #[cfg(test)]
    ahead_tally: (usize, usize),
    /// Tests: the plans of edges queued again and staged that were popped.
    #[cfg(test)]
    staged_tally: usize,
    /// Tests: the refusals kept across a phase change that were planned
    /// again and found refused ([`Schedule::keep_standing_refusals`]).
    #[cfg(test)]
    standing_checked: usize,
}

/// A refused collapse in [`Schedule::failed_collapse`].
#[derive(Clone, Copy)]
struct FailedCollapse {
    /// The operation clock when it was refused.
    at: u64,
    /// Whether the length rule (`keeps_lengths`, which reads the sizing
    /// field) refused a direction.
    by_length: bool,
    /// The lowest energy floor ([`Context::energy_floor`](crate::ops::Context::energy_floor))
    /// under which the energy rule refused a direction with the floor
    /// applied (`+∞`: none did). The refusal stands under that floor or a
    /// lower one; every other refusal but the length rule's reads only
    /// positions, tags and faces, whatever the phase.
    floor: f64,
}

impl FailedCollapse {
    /// Whether the refusal stands in a phase whose rules are those of the
    /// last one but for the sizes, the stretch and the energy floor, now
    /// `floor`.
    fn stands_under(&self, floor: f64) -> bool {
        !self.by_length && floor <= self.floor
    }
}

/// The entry of `v` in a per-vertex-slot array, grown with `fill` as needed.
fn slot<T: Copy>(values: &mut Vec<T>, v: VertexId, fill: T) -> &mut T {
    let i = v.index();
    if i >= values.len() {
        values.resize(i + 1, fill);
    }
    &mut values[i]
}

impl<'a> Schedule<'a> {
    /// A schedule over `mesh` with every target at `opts.l`, collapses that
    /// make no edge longer than 4/3 of its target, and the smoothing order
    /// drawn from `seed`.
    pub(crate) fn new(
        mesh: &'a mut TriMesh,
        ctx: &'a mut Context,
        opts: &OptimizeOptions,
        seed: u64,
        field: &'a SizeField,
    ) -> Self {
        let base = bases(mesh, field, opts.l);
        let mut s = Schedule {
            target: base.clone(),
            base,
            field,
            refined: Vec::new(),
            mesh,
            ctx,
            opts: *opts,
            stats: OptimizeStats {
                passes: 0,
                stop: StopReason::PassLimit,
                split: OpTally::default(),
                collapse: OpTally::default(),
                swap: OpTally::default(),
                reroute: OpTally::default(),
                smooth: OpTally::default(),
                round: OpTally::default(),
                project: OpTally::default(),
                projected_vertices: 0,
                off_curve_left: 0,
                rational_left: 0,
                envelope_stages: 0,
                bad_corners_left: 0,
                vertex_budget_reached: false,
                min_angle_deg: 0.0,
                max_amips: 0.0,
                phases: Vec::new(),
            },
            phase: None,
            rng: Shuffle(seed),
            clock: 1,
            stamp: Vec::new(),
            failed_collapse: rustc_hash::FxHashMap::default(),
            failed_smooth: Vec::new(),
            topo_stamp: Vec::new(),
            role_refused: rustc_hash::FxHashMap::default(),
            stretch: Stretch::uniform(SPLIT_ABOVE),
            swap_scan: None,
            patch: None,
            split_bounded: false,
            #[cfg(test)]
            ahead_tally: (0, 0),
            #[cfg(test)]
            staged_tally: 0,
            #[cfg(test)]
            standing_checked: 0,
        };
        s.enter(Phase::Main);
        s
    }

    /// The mesh being improved.
    pub(crate) fn mesh(&self) -> &TriMesh {
        self.mesh
    }

    /// The tallies so far.
    pub(crate) fn stats(&self) -> &OptimizeStats {
        &self.stats
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

    /// Record an applied operation: every vertex of the faces it created (or
    /// moved) gets the new clock, and with `topology` (a split, collapse or
    /// swap, not a move) the new clock as its topology stamp too.
    fn touch(&mut self, outcome: &Outcome, topology: bool) {
        let Outcome::Applied(ch) = outcome else {
            return;
        };
        self.clock += 1;
        for &f in &ch.created {
            if !self.mesh.is_face_alive(f) {
                continue;
            }
            for v in self.mesh.face(f) {
                *slot(&mut self.stamp, v, 0) = self.clock;
                if topology {
                    *slot(&mut self.topo_stamp, v, 0) = self.clock;
                }
            }
        }
    }

    fn topo_stamp_of(&self, v: VertexId) -> u64 {
        self.topo_stamp.get(v.index()).copied().unwrap_or(0)
    }

    fn stamp_of(&self, v: VertexId) -> u64 {
        self.stamp.get(v.index()).copied().unwrap_or(0)
    }

    /// Whether a plan made ahead at clock `at`, which read the vertices
    /// `read` (and their rings), still stands: none of them changed since.
    fn fresh(&mut self, at: u64, read: &[VertexId]) -> bool {
        let fresh = read.iter().all(|&x| self.stamp_of(x) <= at);
        #[cfg(test)]
        if fresh {
            self.ahead_tally.0 += 1;
        } else {
            self.ahead_tally.1 += 1;
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
fn test_options() -> OptimizeOptions {
    OptimizeOptions {
        l: 0.1,
        l_floor: 0.01,
        stop_energy: 5.0,
        alpha_deg: 10.0,
        max_passes: 40,
        max_vertices: 20_000,
        deadline: Deadline::NONE,
        params: crate::params::OptimizerParams::DEFAULT,
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

/// The phases of a schedule, each with its own bounds on what the operations
/// may do: the energy a free vertex's ring may reach ([`Context::energy_floor`]),
/// the longest edge a swap or a move may create ([`Context::max_new_edge`]),
/// and the collapses' [`Stretch`]. [`Schedule::enter`] sets all three, so no
/// phase inherits another's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Phase {
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
    /// The curved stage's passes, in curved mode: as [`Phase::Main`].
    Curved,
}
