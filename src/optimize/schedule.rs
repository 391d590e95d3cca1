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

use crate::budget::Deadline;
use crate::element::energy::amips;
use crate::mesh::{EdgeKey, EdgeQuad, FeatureOn, TriMesh, VertexId, VertexRing, min_angle_deg};
use crate::ops::{
    self, CollapsePlan, Context, Objective, Outcome, Reject, ReroutePlan, SmoothPlan, SplitPlan,
    SwapPlan, collapse_refusal, invariants::on_curve, try_collapse_planned, try_project,
    try_reroute_planned, try_round, try_smooth_planned, try_split, try_split_planned,
    try_swap_planned,
};
use crate::sizing::SizeField;
use rayon::prelude::*;
use rustc_hash::FxHashSet;
use std::collections::{BTreeMap, BinaryHeap, VecDeque};

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
/// 1 measured better on the dev set (8f4bc8a: min-angle ratio 0.94 -> 1.02).
const COLLAPSE_FACTOR: f64 = 1.0;
/// Edges shorter than this multiple of `l` are collapsed by the final
/// coarsening: every edge (the energy rule and [`COARSEN_STRETCH`] decide).
/// Introduced in 8f4bc8a ("final coarsening over every edge").
const COARSEN_FACTOR: f64 = f64::INFINITY;
/// The final coarsening may create edges up to this multiple of `l` (no split
/// pass follows it to undo them). Introduced in 8f4bc8a ("new edges up to 2l").
const COARSEN_STRETCH: f64 = 2.0;
/// The final coarsening may always make triangles up to this energy (1 for
/// equilateral), even in a mesh whose worst triangle is better (the stop energy
/// still caps it). With the mesh's own worst energy as the only bound, a mesh
/// of near-equilateral triangles coarsened by 21 % at one `l` and by 58 % at
/// half of it (worst 1.38 vs 1.78): a `<circle>` gave 223, 1415 and 3107
/// triangles at `-l 0.05, 0.025, 0.0125`; with 2, 219, 788 and 3125 (issue 14).
/// Our value: 1.5 left the jump, 2 and 2.5 measured alike on the disk.
const COARSEN_ENERGY: f64 = 2.0;
/// At most this many min-max polishing passes (min-max smoothing and swaps).
/// Empirical, introduced in 8f4bc8a.
const MINMAX_PASSES: usize = 10;
/// The min-max polish stops once a pass lowers the largest energy by less
/// than this fraction of it. Empirical, introduced in 8f4bc8a.
const MINMAX_MIN_GAIN: f64 = 1e-3;
/// At most this many polishing passes (swaps and smoothing) end the schedule.
/// Empirical, introduced in 8ea5c2c.
const POLISH_PASSES: usize = 6;
/// The polish stops once a pass lowers the mean energy by less than this
/// fraction of it. Empirical, introduced in 8ea5c2c.
const POLISH_MIN_GAIN: f64 = 1e-4;
/// The sizing field is refined after a pass that lowered the largest energy by
/// less than this (and the mean by less than [`SIZING_STALL_MEAN`]). The
/// TriWild reference (`optimization.cpp`, `refine`) uses 5e-1 with its energy
/// (2 for an equilateral triangle); halved for ours (1 for equilateral), as
/// [`crate::Params::stop_energy`] halves the thesis's 10. Introduced in 020a590.
const SIZING_STALL_MAX: f64 = 0.25;
/// See [`SIZING_STALL_MAX`]: the reference's 5e-2 for the mean energy, halved.
const SIZING_STALL_MEAN: f64 = 0.025;
/// Once the sizing field has hit its floor, this many passes in a row without
/// gain stop the schedule (TriWild reference, `optimization.cpp`, `refine`:
/// `it > 10` and the last 10 passes). Introduced in 020a590.
const STALL_PASSES: usize = 10;
/// A pass "without gain" lowers neither the largest nor the mean energy by
/// more than this (the TriWild reference's 1e-4). Introduced in 020a590.
const STALL_TOLERANCE: f64 = 1e-4;
/// The quality goal also needs every edge shorter than this multiple of `l`
/// (smoothing may stretch a few edges past [`SPLIT_ABOVE`]). Introduced in
/// 3ff3cbe.
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
/// neighbourhood changed). Empirical, introduced in 3ff3cbe.
const COLLAPSE_ROUNDS: usize = 4;
/// Pops of one collapse round: this many per queued edge, plus
/// [`COLLAPSE_BUDGET_EXTRA`] (edges made short are queued again). Empirical,
/// introduced in 020a590.
const COLLAPSE_BUDGET_PER_EDGE: usize = 4;
/// See [`COLLAPSE_BUDGET_PER_EDGE`].
const COLLAPSE_BUDGET_EXTRA: usize = 16;
/// A swap must lower the larger energy of its two triangles by more than this
/// fraction, so equal configurations never flip back and forth. Empirical,
/// introduced in 020a590.
const SWAP_MIN_GAIN: f64 = 1e-9;
/// With more than one worker thread, the collapse and smoothing passes plan
/// this many upcoming operations at a time in parallel (see
/// [`Schedule::collapse_round`]); the plans are then applied one by one in the
/// sequential order, so the mesh is the same for any number of threads.
const PLAN_AHEAD: usize = 256;
/// The step of [`ShortestFirst`]'s summary of its sorted edges: a block of
/// sixteen 16-byte entries is four cache lines.
const SUMMARY_STEP: usize = 16;

/// The fewest edges queued again worth staging to plan in parallel: two (a
/// lone edge is planned when popped). Staging from 16 left 9 % of organ's
/// pops planned one by one on the pipeline's thread; from 2, the three
/// slowest drawings' two-thread times fell 2-5 % (session 15).
const STAGE_MIN: usize = 2;
/// A staged batch smaller than this is planned on the pipeline's thread, at
/// once: handing out a few plans costs about what making them does (organ
/// stages some 29 thousand batches of two to four edges, emoji_u1f98e 4
/// thousand, besides 14 and 9 thousand single edges).
const STAGE_PAR_MIN: usize = 8;
/// The envelope stages for vertices left rational (after §2.3.4's, which
/// sample denser and then widen ε): ε multiplied by each of these in turn,
/// with [`ENVELOPE_SPACING`] of the sampling spacing. Our values, introduced
/// in 020a590.
const ENVELOPE_EPS: [f64; 3] = [1.0, 1.5, 2.0];
/// See [`ENVELOPE_EPS`]: the sampling spacing of every stage, as a fraction
/// of the original one.
const ENVELOPE_SPACING: f64 = 0.5;
/// Smoothing and rounding rounds in one envelope stage. Empirical, introduced
/// in 020a590.
const ENVELOPE_ROUNDS: usize = 3;
/// Seed of the linear schedule's smoothing order: "triwild" in ASCII.
/// Introduced in 3ff3cbe.
const SEED: u64 = 0x0074_7269_7769_6c64;

/// Parameters of the schedule, in user units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct OptimizeOptions {
    /// Target edge length `l`: the sizing field's upper bound.
    pub l: f64,
    /// Lower bound of the sizing field (the thesis uses ε).
    pub l_floor: f64,
    /// AMIPS energy (1 for equilateral) below which a mesh is good enough.
    pub stop_energy: f64,
    /// Minimum angle, degrees, above which a mesh is good enough.
    pub alpha_deg: f64,
    /// Maximum number of passes.
    pub max_passes: u32,
    /// No split once the mesh has this many vertices.
    pub max_vertices: usize,
    /// The run's wall-clock limit: past it the schedule stops at the next
    /// pass ([`StopReason::TimeLimit`]).
    pub deadline: Deadline,
}

/// How often an operation was applied and why it was refused.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct OpTally {
    /// Applied operations.
    pub applied: u64,
    /// Refusals, by the rule or invariant that refused ([`Reject`] as
    /// index: the count is on every operation's path, a name lookup is not);
    /// serialized as a map from [`Reject::name`] to the count, the rules that
    /// refused nothing left out.
    #[serde(serialize_with = "rejected_by_name")]
    rejected: [u64; Reject::COUNT],
}

fn rejected_by_name<S: serde::Serializer>(
    rejected: &[u64; Reject::COUNT],
    s: S,
) -> Result<S::Ok, S::Error> {
    let named: BTreeMap<&str, u64> = Reject::ALL
        .iter()
        .filter(|&&r| rejected[r as usize] > 0)
        .map(|&r| (r.name(), rejected[r as usize]))
        .collect();
    serde::Serialize::serialize(&named, s)
}

impl OptimizeOptions {
    /// Set [`OptimizeOptions::deadline`].
    pub(crate) fn with_deadline(mut self, deadline: Deadline) -> Self {
        self.deadline = deadline;
        self
    }
}

impl OpTally {
    /// Count `outcome`; returns whether it was applied.
    pub(crate) fn record(&mut self, outcome: &Outcome) -> bool {
        match outcome {
            Outcome::Applied(_) => {
                self.applied += 1;
                true
            }
            Outcome::Rejected(r) => {
                self.rejected[*r as usize] += 1;
                false
            }
        }
    }
}

/// Why the schedule stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The quality goal was met (angle above α or energy below the stop energy).
    Quality,
    /// A pass changed nothing measurable.
    Stalled,
    /// The pass limit was reached.
    PassLimit,
    /// The run's wall-clock limit (`--time-limit`) passed: the pipeline
    /// reports an error and writes nothing.
    TimeLimit,
}

/// What the schedule did.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct OptimizeStats {
    /// Passes run.
    pub passes: u32,
    /// Why it stopped.
    pub stop: StopReason,
    /// Edge splits.
    pub split: OpTally,
    /// Edge collapses.
    pub collapse: OpTally,
    /// Edge swaps.
    pub swap: OpTally,
    /// Secondary feature edges rerouted through the apex of their sliver.
    pub reroute: OpTally,
    /// Vertex smoothing.
    pub smooth: OpTally,
    /// Rounding of rational vertices to `f64`.
    pub round: OpTally,
    /// Moves of off-curve primary vertices toward their curve.
    pub project: OpTally,
    /// Primary vertices that were off their curve at the start (or after a
    /// fallback split) and ended on it.
    pub projected_vertices: usize,
    /// Primary vertices still off their curve at the end.
    pub off_curve_left: usize,
    /// Vertices still rational at the end (the mesh is unusable if not 0).
    pub rational_left: usize,
    /// Envelope stages run for leftover rational vertices (0 when none were needed).
    pub envelope_stages: u32,
    /// Smallest angle at the end, degrees.
    pub min_angle_deg: f64,
    /// Largest AMIPS energy at the end.
    pub max_amips: f64,
}

/// Quality of a mesh for the stop rules.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Measure {
    /// Smallest angle (degrees) of the triangles that are not locked.
    min_angle: f64,
    /// Largest energy of the triangles that are not locked.
    max_energy: f64,
    /// Mean energy of all triangles.
    mean_energy: f64,
    /// Smallest angle and largest energy of all triangles.
    all: (f64, f64),
    /// The longest edge.
    longest: f64,
}

/// Whether the triangle `v` has three feature edges (see [`measure`]).
pub(crate) fn locked(mesh: &TriMesh, v: [VertexId; 3]) -> bool {
    (0..3).all(|i| !mesh.edge_tags(v[i], v[(i + 1) % 3]).is_empty())
}

/// The energies of a mesh's triangles, for the stop rules of both stages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct EnergyMeasure {
    /// Largest energy of the measured triangles that are not locked.
    pub(crate) max: f64,
    /// Largest energy of all measured triangles.
    pub(crate) max_all: f64,
    /// Mean energy of the measured triangles (0 when none is).
    pub(crate) mean: f64,
    /// Triangles without an energy.
    pub(crate) unmeasured: usize,
}

/// Measure the energies of `mesh`'s triangles: `energy(v)` gives the energy
/// of the triangle `v`, or `None` to leave it out (counted in `unmeasured`).
/// A triangle whose three edges are feature edges is locked ([`locked`]): its
/// shape is the input's (no swap, split or collapse can change it), so it is
/// left out of `max`, though not out of `max_all`. The energies are computed
/// in parallel and summed in face order (the same sum for any number of
/// threads).
pub(crate) fn measure_energy(
    mesh: &TriMesh,
    energy: impl Fn([VertexId; 3]) -> Option<f64> + Sync,
) -> EnergyMeasure {
    let faces: Vec<_> = mesh.faces().collect();
    let values: Vec<(bool, Option<f64>)> = faces
        .par_iter()
        .map(|&f| {
            let v = mesh.face(f);
            (locked(mesh, v), energy(v))
        })
        .collect();
    fold_energies(&values)
}

/// [`measure_energy`]'s tally of `(locked, energy)` by face, in face order.
fn fold_energies(values: &[(bool, Option<f64>)]) -> EnergyMeasure {
    let mut m = EnergyMeasure {
        max: 0.0,
        max_all: 0.0,
        mean: 0.0,
        unmeasured: 0,
    };
    let (mut sum, mut n) = (0.0, 0usize);
    for &(locked, e) in values {
        match e {
            None => m.unmeasured += 1,
            Some(e) => {
                sum += e;
                n += 1;
                m.max_all = m.max_all.max(e);
                if !locked {
                    m.max = m.max.max(e);
                }
            }
        }
    }
    if n > 0 {
        m.mean = sum / n as f64;
    }
    m
}

/// Measure `mesh`: the AMIPS energies ([`measure_energy`]), angles and edge
/// lengths. Locked triangles are left out of `min_angle` and `max_energy`.
fn measure(mesh: &TriMesh) -> Measure {
    if mesh.num_faces() == 0 {
        return Measure {
            min_angle: 0.0,
            max_energy: 0.0,
            mean_energy: 0.0,
            all: (0.0, 0.0),
            longest: 0.0,
        };
    }
    // Per face, in parallel: (locked, energy), min angle, longest edge; then
    // folded in face order.
    let faces: Vec<_> = mesh.faces().collect();
    let per_face: Vec<((bool, Option<f64>), f64, f64)> = faces
        .par_iter()
        .map(|&f| {
            let v = mesh.face(f);
            let [a, b, c] = v.map(|x| mesh.position(x));
            let longest = a.distance(b).max(b.distance(c)).max(c.distance(a));
            (
                (locked(mesh, v), Some(amips(a, b, c))),
                min_angle_deg([a, b, c]),
                longest,
            )
        })
        .collect();
    let (mut min_angle, mut min_angle_all, mut longest) = (180.0f64, 180.0f64, 0.0f64);
    for &((locked, _), angle, long) in &per_face {
        min_angle_all = min_angle_all.min(angle);
        longest = longest.max(long);
        if !locked {
            min_angle = min_angle.min(angle);
        }
    }
    let values: Vec<(bool, Option<f64>)> = per_face.iter().map(|p| p.0).collect();
    let e = fold_energies(&values);
    Measure {
        min_angle,
        max_energy: e.max,
        mean_energy: e.mean,
        all: (min_angle_all, e.max_all),
        longest,
    }
}

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
    /// [`CollapsePlan::new`] refusal that says so), with the clock then and
    /// the reason: they stay refused until the faces around `.1` change.
    role_refused: rustc_hash::FxHashMap<(VertexId, VertexId), (u64, Reject)>,
    /// Longest edge a collapse may create, relative to its mean target.
    max_stretch: f64,
    /// The clock when the last swap pass scanned the edges, and the edges it
    /// found a gain on: an edge whose ends' faces have not changed since
    /// (so neither has its quad) and that had no gain then has none now.
    swap_scan: Option<(u64, FxHashSet<EdgeKey>)>,
    /// Tests: the plans made ahead that were used, and those found stale.
    #[cfg(test)]
    ahead_tally: (usize, usize),
    /// Tests: the plans of edges queued again and staged that were popped.
    #[cfg(test)]
    staged_tally: usize,
}

/// A refused collapse in [`Schedule::failed_collapse`].
#[derive(Clone, Copy)]
struct FailedCollapse {
    /// The operation clock when it was refused.
    at: u64,
    /// Whether the length rule (`keeps_lengths`, which reads the sizing
    /// field) refused a direction.
    by_length: bool,
}

/// The collapse round's queue: edges by the bits of their length (which order
/// like the lengths), then by key. The edges short at the start of the round
/// are sorted once (cheaper than a heap of all of them); the edges queued
/// again after a collapse go to a heap; with more than one thread, the
/// smallest of those are taken from the heap a batch at a time
/// ([`ShortestFirst::stage`]) to be planned together, each batch kept in order
/// with its plans. `pop` takes the smallest of the three heads, so the order
/// is that of one heap holding them all.
struct ShortestFirst<P = ()> {
    sorted: Vec<(u64, EdgeKey)>,
    next: usize,
    /// Every [`SUMMARY_STEP`]-th entry of `sorted` (from its first), made by
    /// [`Self::sort`]: [`Self::is_ahead`] searches this first (a sixteenth of
    /// `sorted`, it stays in cache), then one block of `sorted`.
    summary: Vec<(u64, EdgeKey)>,
    again: BinaryHeap<std::cmp::Reverse<(u64, EdgeKey)>>,
    /// Edges taken from `again` in order, each with its plan made ahead.
    staged: VecDeque<(u64, EdgeKey, Option<P>)>,
}

impl<P> Default for ShortestFirst<P> {
    fn default() -> Self {
        ShortestFirst {
            sorted: Vec::new(),
            next: 0,
            summary: Vec::new(),
            again: BinaryHeap::new(),
            staged: VecDeque::new(),
        }
    }
}

/// Sort `v`, in parallel when the pool has more than one thread (a
/// parallel sort on one thread only costs more).
fn sort_unstable<T: Ord + Send>(v: &mut [T]) {
    if rayon::current_num_threads() > 1 {
        v.par_sort_unstable();
    } else {
        v.sort_unstable();
    }
}

/// Where [`ShortestFirst::pop_indexed`] took an edge from.
enum Popped<P> {
    /// `sorted`, at this index.
    Sorted(usize),
    /// `staged`, with its plan.
    Staged(Option<P>),
    /// `again`: not planned.
    Again,
}

impl<P> ShortestFirst<P> {
    fn sort(&mut self) {
        sort_unstable(&mut self.sorted);
        self.next = 0;
        self.summary.clear();
        self.summary
            .extend(self.sorted.iter().step_by(SUMMARY_STEP).copied());
    }

    /// Whether `key` is in `sorted[next..]`. A binary search of all of
    /// `sorted` (over a megabyte on organ) missed the cache at most of its
    /// steps, on the pipeline's thread, for every edge queued again: 3-4 % of
    /// that thread's time on renault. Below the head nothing is ahead (most
    /// of the edges queued again that are not duplicates); otherwise the
    /// summary's search finds the block of `sorted` that holds `key`'s place.
    fn is_ahead(&self, key: (u64, EdgeKey)) -> bool {
        match self.sorted.get(self.next) {
            Some(&head) if head <= key => {}
            _ => return false,
        }
        // summary[j - 1] = sorted[(j - 1) · step] < key <= sorted[j · step]
        // (where those exist): key's place in `sorted` is in between.
        let j = self.summary.partition_point(|s| *s < key);
        let lo = if j == 0 {
            0
        } else {
            (j - 1) * SUMMARY_STEP + 1
        };
        let hi = (j * SUMMARY_STEP).min(self.sorted.len());
        let at = lo + self.sorted[lo..hi].partition_point(|s| *s < key);
        at >= self.next && self.sorted.get(at) == Some(&key)
    }

    /// Which head is the smallest: 0 `sorted`, 1 `staged`, 2 `again` (on a tie
    /// the first; equal heads are the same edge). On every pop: compared by
    /// hand, not through a `min_by_key` over three options.
    fn smallest(&self) -> Option<usize> {
        let heads = [
            self.sorted.get(self.next).copied(),
            self.staged.front().map(|&(b, k, _)| (b, k)),
            self.again.peek().map(|r| r.0),
        ];
        let mut which = None;
        let mut best = None;
        for (i, head) in heads.into_iter().enumerate() {
            if let Some(h) = head
                && best.is_none_or(|b| h < b)
            {
                (which, best) = (Some(i), Some(h));
            }
        }
        which
    }

    /// Whether the next edge comes from `again`: the moment to
    /// [`Self::stage`] a batch (before what is staged already: a collapse
    /// queues the short edges at its vertex, shorter than the staged ones
    /// more often than not; waiting until the staged batch ran out left
    /// organ's and the emoji's edges queued again planned one by one, 260-300
    /// thousand of them, on the pipeline's thread).
    fn next_is_unstaged(&self) -> bool {
        self.smallest() == Some(2)
    }

    /// Take the `n` smallest edges of `again` (fewer if it holds fewer, and
    /// only those before the first staged edge), in order, for the caller to
    /// plan and [`Self::push_staged`].
    fn stage(&mut self, n: usize) -> Vec<(u64, EdgeKey)> {
        let bound = self.staged.front().map(|&(b, k, _)| (b, k));
        let mut batch = Vec::new();
        while batch.len() < n
            && let Some(r) = self.again.peek()
            && bound.is_none_or(|b| r.0 < b)
        {
            batch.push(r.0);
            self.again.pop();
        }
        batch
    }

    /// Queue `key` again, unless it is still ahead in `sorted`: that copy
    /// comes first (on a tie `sorted` wins) and the copy queued again would
    /// come right after it, with nothing changed in between, only to be
    /// skipped. Half the edges queued again after a collapse are such
    /// duplicates (organ 62 %, the emoji 45 %): the round's positions do
    /// not change, so an edge of u's ring kept its length and its key.
    fn push_again(&mut self, key: (u64, EdgeKey)) {
        if !self.is_ahead(key) {
            self.again.push(std::cmp::Reverse(key));
        }
    }

    /// Put staged edges (the output of [`Self::stage`], in its order) with
    /// their plans before those staged already.
    fn push_staged(&mut self, batch: impl IntoIterator<Item = (u64, EdgeKey, Option<P>)>) {
        let batch: Vec<_> = batch.into_iter().collect();
        for item in batch.into_iter().rev() {
            self.staged.push_front(item);
        }
    }

    /// The next edge, with where it came from.
    fn pop_indexed(&mut self) -> Option<(u64, EdgeKey, Popped<P>)> {
        match self.smallest()? {
            0 => {
                self.next += 1;
                let (b, k) = self.sorted[self.next - 1];
                Some((b, k, Popped::Sorted(self.next - 1)))
            }
            1 => self
                .staged
                .pop_front()
                .map(|(b, k, plan)| (b, k, Popped::Staged(plan))),
            _ => self.again.pop().map(|r| (r.0.0, r.0.1, Popped::Again)),
        }
    }
}

/// Plans made ahead, in parallel, for the next [`PLAN_AHEAD`] items of a
/// pass's queue (see [`Schedule::collapse_round`]); none with one thread.
struct PlanAhead<T> {
    parallel: bool,
    /// The queue index of `plans[0]`.
    from: usize,
    plans: Vec<Option<T>>,
}

impl<T: Send> PlanAhead<T> {
    fn new() -> Self {
        PlanAhead {
            parallel: rayon::current_num_threads() > 1,
            from: 0,
            plans: Vec::new(),
        }
    }

    /// The plan of `items[n]`, planning `items[n..n + PLAN_AHEAD]` at once
    /// first when `n` is past the window planned; `None` with one thread
    /// (and where `plan` made none).
    fn take<I: Sync>(
        &mut self,
        n: usize,
        items: &[I],
        plan: impl Fn(&I) -> Option<T> + Sync + Send,
    ) -> Option<T> {
        if !self.parallel {
            return None;
        }
        if n >= self.from + self.plans.len() {
            let end = (n + PLAN_AHEAD).min(items.len());
            // Into the same buffer: organ plans some twelve thousand windows.
            self.plans.clear();
            self.plans.par_extend(items[n..end].par_iter().map(plan));
            self.from = n;
        }
        self.plans.get_mut(n - self.from).and_then(Option::take)
    }
}

/// One direction of a collapse planned ([`Schedule::plan_collapse`]).
enum CollapseDirection {
    /// Its refusal by the role rules is remembered, and v's faces are
    /// unchanged since ([`Schedule::role_refused`]): the same refusal,
    /// without planning it again.
    Remembered(Reject),
    /// The length rule refused it.
    Length,
    /// [`CollapsePlan::new`] on v's ring, with [`CollapsePlan::verdict`]
    /// (boxed: plans are moved through the window and the round).
    Plan(Box<PlannedCollapse>),
    /// The plan or its verdict refused it (as `try_collapse_planned` would,
    /// with whether by the role rules).
    Refused(Reject, bool),
}

/// [`CollapseDirection::Plan`]'s plan and verdict.
type PlannedCollapse = (
    Result<CollapsePlan, (Reject, bool)>,
    Option<Result<(), Reject>>,
);

/// A collapse of an edge planned ahead at clock `at`, both directions in the
/// collapse round's order: it stands while neither end's stamp has passed
/// `at` (no face around either end changed, no neighbour of either moved; the
/// plans read nothing else that a pass changes, the reasoning of
/// [`Schedule::failed_collapse`]).
struct CollapseAhead {
    at: u64,
    /// `None`: the round skips the edge (an end is dead, its length changed
    /// or is long enough, or its refusal is remembered).
    directions: Option<[CollapseDirection; 2]>,
}

/// A smoothing planned ahead at clock `at`: it stands while the vertex's stamp
/// has not passed `at`.
struct SmoothAhead {
    at: u64,
    plan: Result<SmoothPlan, Reject>,
    /// [`SmoothPlan::verdict`].
    verdict: Option<Result<(), Reject>>,
}

/// What the swap pass does with an edge, by its tags: swap an untagged edge,
/// reroute a secondary one, leave a primary one.
enum SwapKind {
    Swap,
    Reroute,
    Neither,
}

fn swap_kind(mesh: &TriMesh, k: EdgeKey) -> SwapKind {
    let tags = mesh.edge_tags(k.lo, k.hi);
    if tags.is_empty() {
        SwapKind::Swap
    } else if tags
        .iter()
        .all(|t| matches!(t, FeatureOn::Secondary { .. }))
    {
        SwapKind::Reroute
    } else {
        SwapKind::Neither
    }
}

/// A swap pass candidate planned ahead at clock `at` ([`Schedule::plan_swap`]):
/// it stands while no vertex of `quad` has a stamp past `at`.
struct SwapAhead {
    at: u64,
    quad: [VertexId; 4],
    what: SwapWhat,
}

enum SwapWhat {
    /// The pass skips it (no gain left, or a primary edge).
    Skip,
    /// A swap, with [`SwapPlan::verdict`].
    Swap(SwapPlan, Option<Result<(), Reject>>),
    /// A reroute, with [`ReroutePlan::verdict`].
    Reroute(ReroutePlan, Option<Result<(), Reject>>),
}

/// Whether collapsing `v` into `u` makes no edge longer than `max_stretch`
/// times its target (`target(u, w)`: what the split pass would compare it
/// with), `ring_v` being v's ring. Else the split pass would cut such an
/// edge again (4/3 of its target): the two passes would undo each other
/// forever. Where the user's size field asks for less than `l` (`strict`),
/// no collapse stretches an edge past the split bound; at `l`, and without a
/// field of the user's, the coarsening may (see [`COARSEN_STRETCH`]).
fn lengths_kept(
    mesh: &TriMesh,
    target: impl Fn(VertexId, VertexId) -> f64,
    l: f64,
    max_stretch: f64,
    strict: bool,
    u: VertexId,
    ring_v: &VertexRing,
) -> bool {
    let pu = mesh.position(u);
    ring_v.neighbours.iter().all(|&w| {
        if w == u {
            return true;
        }
        let t = target(u, w);
        let stretch = if strict && t < l * REFINED_BELOW {
            max_stretch.min(SPLIT_ABOVE)
        } else {
            max_stretch
        };
        pu.distance(mesh.position(w)) <= stretch * t
    })
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
        Schedule {
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
                min_angle_deg: 0.0,
                max_amips: 0.0,
            },
            rng: Shuffle(seed),
            clock: 1,
            stamp: Vec::new(),
            failed_collapse: rustc_hash::FxHashMap::default(),
            failed_smooth: Vec::new(),
            topo_stamp: Vec::new(),
            role_refused: rustc_hash::FxHashMap::default(),
            max_stretch: SPLIT_ABOVE,
            swap_scan: None,
            #[cfg(test)]
            ahead_tally: (0, 0),
            #[cfg(test)]
            staged_tally: 0,
        }
    }

    /// The mesh being improved.
    pub(crate) fn mesh(&self) -> &TriMesh {
        self.mesh
    }

    /// The tallies so far.
    pub(crate) fn stats(&self) -> &OptimizeStats {
        &self.stats
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

    fn target_of(&self, v: VertexId) -> f64 {
        self.target.get(v.index()).copied().unwrap_or(self.opts.l)
    }

    fn base_of(&self, v: VertexId) -> f64 {
        self.base.get(v.index()).copied().unwrap_or(self.opts.l)
    }

    fn set_base(&mut self, v: VertexId, t: f64) {
        *slot(&mut self.base, v, self.opts.l) = t;
    }

    fn is_refined(&self, v: VertexId) -> bool {
        self.refined.get(v.index()).copied().unwrap_or(false)
    }

    /// The size field at every vertex again (smoothing and projection move
    /// vertices); targets keep their ratio to it.
    fn refresh_bases(&mut self) {
        if self.field.is_uniform() {
            return;
        }
        let fresh = bases(self.mesh, self.field, self.opts.l);
        for v in self.mesh.vertices() {
            let i = v.index();
            let old = self.base.get(i).copied().unwrap_or(self.opts.l);
            let ratio = self.target.get(i).map_or(1.0, |t| t / old);
            *slot(&mut self.target, v, self.opts.l) = fresh[i] * ratio;
        }
        self.base = fresh;
    }

    /// Whether some edge is longer than the split bound of the field (only
    /// looked at when the field is not uniform: the BSP mesh knows nothing of it).
    fn sizes_pending(&self) -> bool {
        !self.field.is_uniform()
            && self
                .mesh
                .edge_list()
                .into_par_iter()
                .any(|k| self.mesh.distance(k.lo, k.hi) > SPLIT_ABOVE * self.edge_target(k))
    }

    /// The longest edge over its target (the stop rule's stretch).
    fn longest_stretch(&self) -> f64 {
        self.mesh
            .edge_list()
            .into_par_iter()
            .map(|k| self.mesh.distance(k.lo, k.hi) / self.edge_target(k))
            .reduce(|| 0.0, f64::max)
    }

    /// The target length of edge `k`: the size field at its midpoint, times
    /// its ends' mean refinement (their targets over the field at them). Where
    /// the field at the two ends differs by less than [`FIELD_LINEAR`], the
    /// midpoint's value is their mean (the field is linear along such an edge
    /// to well within the split and collapse bounds, and no lookup is needed);
    /// for a uniform field, the ends' mean target.
    fn edge_target(&self, k: EdgeKey) -> f64 {
        self.pair_target(k.lo, k.hi)
    }

    /// [`Self::edge_target`] of the segment from `u` to `w`, an edge or not
    /// (a collapse's new edges are judged as the split pass will judge them).
    fn pair_target(&self, u: VertexId, w: VertexId) -> f64 {
        let (tu, tw) = (self.target_of(u), self.target_of(w));
        if self.field.is_uniform() {
            return 0.5 * (tu + tw);
        }
        let (bu, bw) = (self.base_of(u), self.base_of(w));
        let ratio = 0.5 * (tu / bu + tw / bw);
        let h = if bu.max(bw) <= FIELD_LINEAR * bu.min(bw) {
            0.5 * (bu + bw)
        } else {
            let (a, b) = (self.mesh.position(u), self.mesh.position(w));
            self.field.at_mid(a, b)
        };
        h * ratio
    }

    fn set_target(&mut self, v: VertexId, t: f64) {
        *slot(&mut self.target, v, self.opts.l) = t;
    }

    /// Split every edge longer than 4/3 of its mean target once, longest first.
    /// Returns the number of candidates and of splits applied.
    fn split_pass(&mut self) -> (usize, u64) {
        let edges: Vec<EdgeKey> = self.mesh.edge_list();
        let mut cands: Vec<(f64, EdgeKey, f64)> = edges
            .into_par_iter()
            .filter_map(|k| {
                let (len, t) = (self.mesh.distance(k.lo, k.hi), self.edge_target(k));
                (len > SPLIT_ABOVE * t).then_some((len, k, t))
            })
            .collect();
        cands.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let n = cands.len();
        let mut applied = 0;
        // As in the collapse round: with more than one thread the next
        // `PLAN_AHEAD` splits are planned at once in parallel (the plan reads
        // the faces and tags of the edge), and a plan is used only while
        // neither end has changed since.
        let mut ahead = PlanAhead::new();
        for (i, &(_, k, t)) in cands.iter().enumerate() {
            if self.mesh.num_vertices() >= self.opts.max_vertices {
                break;
            }
            let this = &*self;
            let planned = ahead
                .take(i, &cands, |&(_, e, _)| {
                    Some((this.clock, SplitPlan::new(this.mesh, this.ctx, e.lo, e.hi)))
                })
                .filter(|(at, _)| self.fresh(*at, &[k.lo, k.hi]));
            let out = match planned {
                Some((_, plan)) => try_split_planned(self.mesh, self.ctx, plan),
                None => try_split(self.mesh, self.ctx, k.lo, k.hi),
            };
            self.touch(&out, true);
            if let Outcome::Applied(ch) = &out {
                if let Some(m) = ch.new_vertex {
                    if self.field.is_uniform() {
                        self.set_target(m, t);
                    } else {
                        // the field at the new vertex, refined as its edge's ends were
                        let ratio = |s: &Self, v: VertexId| s.target_of(v) / s.base_of(v);
                        let r = 0.5 * (ratio(self, k.lo) + ratio(self, k.hi));
                        let h = self.field.at(self.mesh.position(m));
                        self.set_base(m, h);
                        self.set_target(m, h * r);
                    }
                    let refined = self.is_refined(k.lo) || self.is_refined(k.hi);
                    *slot(&mut self.refined, m, false) = refined;
                }
                applied += 1;
            }
            self.stats.split.record(&out);
        }
        (n, applied)
    }

    /// Refine the sizing field where the worst triangles are, relax it
    /// elsewhere. A triangle is bad when its energy exceeds
    /// `max(worst / 100, 0.9 · stop energy)` (only the worst ones drive
    /// refinement); each vertex of a bad triangle gets its target halved, and
    /// vertices within `1.8 l` of one (scaled like the target) are refined less
    /// the farther they are, so the sizing field grades smoothly. Every other
    /// target grows by 1.5. Targets stay in `[l_floor, l]`. Returns whether some
    /// target hit the floor.
    fn update_sizing(&mut self, worst: f64) -> bool {
        // Collapses refused by the length rule under the old sizes may pass
        // under the new ones; every other refusal depends on the faces around
        // the edge alone.
        self.failed_collapse.retain(|_, f| !f.by_length);
        let threshold =
            (worst / SIZING_WORST_DIVISOR).max(SIZING_STOP_FRACTION * self.opts.stop_energy);
        let faces: Vec<_> = self.mesh.faces().collect();
        let mesh: &TriMesh = self.mesh;
        let mut seeds: Vec<VertexId> = faces
            .into_par_iter()
            .filter_map(|f| {
                let v = mesh.face(f);
                let [a, b, c] = v.map(|x| mesh.position(x));
                (amips(a, b, c) > threshold && !locked(mesh, v)).then_some(v)
            })
            .flatten_iter()
            .collect();
        seeds.sort_unstable();
        seeds.dedup();
        let cap = self.mesh.vertex_capacity();
        let mut mult = vec![SIZING_RELAX; cap];
        // Breadth-first from the bad vertices; `near[v]` = (seed, distance).
        let mut seen = vec![false; cap];
        let mut queue = std::collections::VecDeque::new();
        for &v in &seeds {
            mult[v.index()] = SIZING_REFINE;
            seen[v.index()] = true;
            queue.push_back((v, v));
        }
        while let Some((v, seed)) = queue.pop_front() {
            let radius = SIZING_RADIUS * self.target_of(seed);
            let ps = self.mesh.position(seed);
            for &w in &crate::mesh::ScratchRing::of(self.mesh, v).neighbours {
                let i = w.index();
                if seen[i] {
                    continue;
                }
                seen[i] = true;
                let dist = self.mesh.position(w).distance(ps);
                if dist < radius {
                    let m = SIZING_REFINE + (1.0 - SIZING_REFINE) * dist / radius;
                    mult[i] = mult[i].min(m);
                    queue.push_back((w, seed));
                }
            }
        }
        let mut hit_floor = false;
        let verts: Vec<VertexId> = self.mesh.vertices().collect();
        for v in verts {
            let t = self.target_of(v) * mult[v.index()];
            if t < self.opts.l_floor {
                hit_floor = true;
            }
            let top = self.base_of(v);
            let t = t.clamp(self.opts.l_floor.min(top), top);
            if t < top * REFINED_BELOW {
                *slot(&mut self.refined, v, false) = true;
            }
            self.set_target(v, t);
        }
        hit_floor
    }

    /// Collapse edges shorter than `factor` times their mean target, shortest first.
    pub(crate) fn collapse_pass(&mut self, factor: f64) -> u64 {
        // Refused collapses are retried (in a new round) once a collapse has
        // changed their neighbourhood, as long as rounds make progress.
        let mut total = 0;
        let mut since = None;
        for _ in 0..COLLAPSE_ROUNDS {
            let start = self.clock;
            let n = self.collapse_round(factor, since);
            total += n;
            if n == 0 {
                break;
            }
            since = Some(start);
        }
        total
    }

    /// One round of [`Self::collapse_pass`]: every short edge once, shortest
    /// first. With `since`, only the edges at a vertex whose faces changed
    /// after that clock: a refused collapse elsewhere would be refused again
    /// (its memo in `failed_collapse` still holds, and a collapse pass changes
    /// no length or target), so the round skips the scan of the whole mesh.
    fn collapse_round(&mut self, factor: f64, since: Option<u64>) -> u64 {
        // Shortest first, by the bits of the (non-negative) length, which
        // order like the lengths: the short edges sorted once, and a min-heap
        // for the edges queued again during the round, popped together in
        // one order.
        let mut queue = ShortestFirst::default();
        let edges: Vec<EdgeKey> = match since {
            None => self.mesh.edge_list(),
            Some(at) => {
                // The edges at the vertices stamped since `at`, found in
                // parallel and sorted (the queue's order does not depend on
                // how they were found).
                let mesh: &TriMesh = self.mesh;
                let touched: Vec<VertexId> =
                    mesh.vertices().filter(|&v| self.stamp_of(v) > at).collect();
                let mut edges: Vec<EdgeKey> = touched
                    .into_par_iter()
                    .fold(Vec::new, |mut edges, v| {
                        let ring = crate::mesh::ScratchRing::of(mesh, v);
                        edges.extend(ring.neighbours.iter().map(|&w| EdgeKey::new(v, w)));
                        edges
                    })
                    .reduce(Vec::new, |mut a, mut b| {
                        a.append(&mut b);
                        a
                    });
                sort_unstable(&mut edges);
                edges.dedup();
                edges
            }
        };
        queue.sorted = edges
            .into_par_iter()
            .filter_map(|k| {
                let len = self.mesh.distance(k.lo, k.hi);
                (len < factor * self.edge_target(k)).then_some((len.to_bits(), k))
            })
            .collect();
        queue.sort();
        let mut budget = COLLAPSE_BUDGET_PER_EDGE * queue.sorted.len() + COLLAPSE_BUDGET_EXTRA;
        let mut applied = 0;
        // With more than one thread, the next `PLAN_AHEAD` edges of the sorted
        // queue are planned at once in parallel; a plan is used below only
        // while neither end has changed since, so the round does exactly what
        // it does planning each collapse when it gets to it.
        // The edges queued again are planned ahead too, a batch of the
        // smallest at a time (`ShortestFirst::stage`), under the same rule.
        let mut ahead = PlanAhead::new();
        loop {
            if ahead.parallel && queue.again.len() >= STAGE_MIN && queue.next_is_unstaged() {
                let batch = queue.stage(PLAN_AHEAD);
                let this = &*self;
                let plan = |&(b, e): &(u64, EdgeKey)| this.plan_collapse(b, e, factor);
                let plans: Vec<CollapseAhead> = if batch.len() >= STAGE_PAR_MIN {
                    batch.par_iter().map(plan).collect()
                } else {
                    batch.iter().map(plan).collect()
                };
                queue.push_staged(
                    batch
                        .into_iter()
                        .zip(plans)
                        .map(|((b, e), plan)| (b, e, Some(plan))),
                );
            }
            let Some((bits, k, popped)) = queue.pop_indexed() else {
                break;
            };
            if budget == 0 {
                break;
            }
            budget -= 1;
            let this = &*self;
            let from_sorted = matches!(popped, Popped::Sorted(_));
            let planned = match popped {
                Popped::Sorted(i) => ahead.take(i, &queue.sorted, |&(b, e)| {
                    Some(this.plan_collapse(b, e, factor))
                }),
                Popped::Staged(plan) => {
                    #[cfg(test)]
                    {
                        self.staged_tally += usize::from(plan.is_some());
                    }
                    plan
                }
                Popped::Again => None,
            }
            .filter(|a: &CollapseAhead| {
                // (An edge queued twice may have been refused since its plan;
                // a plan that skips the edge needs no look: with both ends
                // unchanged since, such a refusal makes the round skip it too.
                // Nor does an edge popped from `sorted`: `push_again` queued
                // no copy of it while it was ahead there, so this is its
                // first pop since its plan. A hash lookup per pop saved.)
                let refused_since =
                    |s: &Self| matches!(s.failed_collapse.get(&k), Some(f) if f.at >= a.at);
                debug_assert!(
                    !(from_sorted && a.directions.is_some() && refused_since(self)),
                    "an edge popped from `sorted` refused since its plan"
                );
                self.fresh(a.at, &[k.lo, k.hi])
                    && (a.directions.is_none() || from_sorted || !refused_since(self))
            });
            // A plan that stands already made the round's checks; without
            // one, the edge is planned now, by the same function (the checks,
            // then the plan and its verdict: a refusal only reads the mesh,
            // and a decided collapse commits without a journal). Both
            // directions are planned on the mesh as it is: the first changes
            // nothing unless it is applied, and then the second is not tried.
            let planned = planned.unwrap_or_else(|| self.plan_collapse(bits, k, factor));
            let Some(directions) = planned.directions else {
                continue;
            };
            let mut applied_now = false;
            let mut tried = false;
            let mut by_length = false;
            let ends = [(k.lo, k.hi), (k.hi, k.lo)];
            for ((u, v), direction) in ends.into_iter().zip(directions) {
                let (out, by_role) = match direction {
                    CollapseDirection::Remembered(reason) => {
                        tried = true;
                        self.stats.collapse.record(&Outcome::Rejected(reason));
                        continue;
                    }
                    CollapseDirection::Length => {
                        by_length = true;
                        continue;
                    }
                    CollapseDirection::Plan(planned) => {
                        tried = true;
                        let (plan, verdict) = *planned;
                        try_collapse_planned(self.mesh, self.ctx, plan, verdict)
                    }
                    CollapseDirection::Refused(r, by_role) => {
                        tried = true;
                        (Outcome::Rejected(r), by_role)
                    }
                };
                self.touch(&out, true);
                if let Outcome::Rejected(reason) = out
                    && by_role
                {
                    self.role_refused.insert((u, v), (self.clock, reason));
                }
                if self.stats.collapse.record(&out) {
                    applied_now = true;
                    break;
                }
            }
            if !tried {
                self.stats
                    .collapse
                    .record(&Outcome::Rejected(Reject::EdgeLength));
            }
            if !applied_now {
                let at = self.clock;
                self.failed_collapse
                    .insert(k, FailedCollapse { at, by_length });
            }
            if applied_now {
                applied += 1;
                let u = if self.mesh.is_vertex_alive(k.lo) {
                    k.lo
                } else {
                    k.hi
                };
                let ring = crate::mesh::ScratchRing::of(self.mesh, u);
                for &w in &ring.neighbours {
                    let e = EdgeKey::new(u, w);
                    let len = self.mesh.distance(e.lo, e.hi);
                    if len < factor * self.edge_target(e) {
                        queue.push_again((len.to_bits(), e));
                    }
                }
            }
        }
        applied
    }

    /// Plan the collapse of `k` (popped with `bits`) on the mesh as it is,
    /// ahead or when popped without a plan that stands: what the collapse
    /// round would do with it now, short of applying it.
    fn plan_collapse(&self, bits: u64, k: EdgeKey, factor: f64) -> CollapseAhead {
        CollapseAhead {
            at: self.clock,
            directions: self.plan_directions(bits, k, factor),
        }
    }

    /// [`Self::plan_collapse`]'s two directions, or `None` where the round
    /// skips the edge.
    fn plan_directions(
        &self,
        bits: u64,
        k: EdgeKey,
        factor: f64,
    ) -> Option<[CollapseDirection; 2]> {
        let mesh: &TriMesh = self.mesh;
        if !self.collapse_due(bits, k, factor) {
            return None;
        }
        let direction = |u: VertexId, v: VertexId| {
            if let Some(&(at, reason)) = self.role_refused.get(&(u, v))
                && self.topo_stamp_of(v) <= at
            {
                return CollapseDirection::Remembered(reason);
            }
            let ring_v = crate::mesh::ScratchRing::of(mesh, v);
            if !lengths_kept(
                mesh,
                |a, b| self.pair_target(a, b),
                self.opts.l,
                self.max_stretch,
                self.field.is_asked(),
                u,
                &ring_v,
            ) {
                return CollapseDirection::Length;
            }
            let plan = CollapsePlan::new(mesh, self.ctx, u, v, Some(&ring_v));
            let verdict = plan.as_ref().ok().and_then(|p| p.verdict(mesh, self.ctx));
            // A refused plan is dropped here, in parallel, not on the
            // pipeline's thread (most plans are refused).
            match collapse_refusal(&plan, verdict) {
                Some((r, by_role)) => CollapseDirection::Refused(r, by_role),
                None => CollapseDirection::Plan(Box::new((plan, verdict))),
            }
        };
        Some([direction(k.lo, k.hi), direction(k.hi, k.lo)])
    }

    /// Whether the collapse round tries `k` (popped with `bits`) now: both
    /// ends alive, the length as queued and still short, no refusal of it
    /// remembered.
    fn collapse_due(&self, bits: u64, k: EdgeKey, factor: f64) -> bool {
        if !(self.mesh.is_vertex_alive(k.lo) && self.mesh.is_vertex_alive(k.hi)) {
            return false;
        }
        let len = self.mesh.distance(k.lo, k.hi);
        if len.to_bits() != bits || len >= factor * self.edge_target(k) {
            return false;
        }
        !matches!(self.failed_collapse.get(&k), Some(&FailedCollapse { at, .. })
            if self.stamp_of(k.lo) <= at && self.stamp_of(k.hi) <= at)
    }

    /// Swap edges where that lowers the larger energy of their two triangles;
    /// on secondary feature edges, the same change is a reroute (`ops::swap`).
    pub(crate) fn swap_pass(&mut self) -> u64 {
        let scanned_at = self.clock;
        let last = self.swap_scan.take();
        let cands = self.swap_candidates(last.as_ref());
        self.swap_scan = Some((scanned_at, cands.iter().map(|&(_, k)| k).collect()));
        let mut applied = 0;
        // As in the collapse round: with more than one thread the next
        // `PLAN_AHEAD` swaps are planned (and their invariants decided) at
        // once in parallel; a plan is used only while the four vertices of
        // its quad are unchanged since.
        let mut ahead = PlanAhead::new();
        for (n, &(_, k)) in cands.iter().enumerate() {
            let this = &*self;
            let planned = ahead
                .take(n, &cands, |&(_, e)| this.plan_swap(e, scanned_at))
                .filter(|a: &SwapAhead| self.fresh(a.at, &a.quad));
            let (out, tally) = match planned.map(|a| a.what) {
                Some(SwapWhat::Skip) => continue,
                Some(SwapWhat::Swap(plan, verdict)) => (
                    try_swap_planned(self.mesh, self.ctx, Ok(plan), verdict),
                    &mut self.stats.swap,
                ),
                Some(SwapWhat::Reroute(plan, verdict)) => (
                    try_reroute_planned(self.mesh, self.ctx, Ok(plan), verdict),
                    &mut self.stats.reroute,
                ),
                None => {
                    // Earlier swaps may have changed the quad (else it still
                    // has the gain the scan found: a change of either face, or
                    // a move of any of its four vertices, stamps both ends).
                    let changed =
                        self.stamp_of(k.lo) > scanned_at || self.stamp_of(k.hi) > scanned_at;
                    if changed && swap_gain(self.mesh, self.ctx, k).is_none() {
                        continue;
                    }
                    // Planned now, with its verdict, as ahead.
                    let (mesh, ctx): (&TriMesh, &Context) = (self.mesh, self.ctx);
                    match swap_kind(mesh, k) {
                        SwapKind::Swap => {
                            let plan = SwapPlan::new(mesh, ctx, k.lo, k.hi);
                            let verdict =
                                plan.as_ref().ok().and_then(|p| p.verdict(mesh, ctx, &[]));
                            (
                                try_swap_planned(self.mesh, self.ctx, plan, verdict),
                                &mut self.stats.swap,
                            )
                        }
                        SwapKind::Reroute => {
                            let plan = ReroutePlan::new(mesh, ctx, k.lo, k.hi);
                            let verdict = plan.as_ref().ok().and_then(|p| p.verdict(mesh, ctx));
                            (
                                try_reroute_planned(self.mesh, self.ctx, plan, verdict),
                                &mut self.stats.reroute,
                            )
                        }
                        SwapKind::Neither => continue,
                    }
                }
            };
            let counted = tally.record(&out);
            self.touch(&out, true);
            if counted {
                applied += 1;
            }
        }
        applied
    }

    /// Plan the swap (or reroute) of the candidate `k` ahead, on the mesh as
    /// it is: what the swap pass would do with it now, short of applying it.
    /// `None` where that is left to the pass (the plan refused it: cheap).
    fn plan_swap(&self, k: EdgeKey, scanned_at: u64) -> Option<SwapAhead> {
        let (mesh, ctx): (&TriMesh, &Context) = (self.mesh, self.ctx);
        let at = self.clock;
        let changed = self.stamp_of(k.lo) > scanned_at || self.stamp_of(k.hi) > scanned_at;
        if changed && swap_gain(mesh, ctx, k).is_none() {
            // The gain depends on the quad alone: both ends are stamped when
            // it changes.
            return Some(SwapAhead {
                at,
                quad: [k.lo, k.hi, k.lo, k.hi],
                what: SwapWhat::Skip,
            });
        }
        let quad = |[c, d]: [VertexId; 2]| [k.lo, k.hi, c, d];
        match swap_kind(mesh, k) {
            SwapKind::Neither => Some(SwapAhead {
                at,
                quad: [k.lo, k.hi, k.lo, k.hi],
                what: SwapWhat::Skip,
            }),
            SwapKind::Swap => {
                let plan = SwapPlan::new(mesh, ctx, k.lo, k.hi).ok()?;
                let verdict = plan.verdict(mesh, ctx, &[]);
                Some(SwapAhead {
                    at,
                    quad: quad(plan.diagonal()),
                    what: SwapWhat::Swap(plan, verdict),
                })
            }
            SwapKind::Reroute => {
                let plan = ReroutePlan::new(mesh, ctx, k.lo, k.hi).ok()?;
                let verdict = plan.verdict(mesh, ctx);
                Some(SwapAhead {
                    at,
                    quad: quad(plan.swap().diagonal()),
                    what: SwapWhat::Reroute(plan, verdict),
                })
            }
        }
    }

    /// The swap pass's candidates, longest first: the edges off primary
    /// features where a swap lowers the larger energy of their two triangles.
    /// With `last` (the clock of the previous scan and the edges it found),
    /// an edge whose ends' faces have not changed since and that was not
    /// found then is not evaluated again: its quad is the same (a change of
    /// either face, or a move of any of its four vertices, stamps both ends),
    /// and so is the answer.
    fn swap_candidates(&self, last: Option<&(u64, FxHashSet<EdgeKey>)>) -> Vec<(f64, EdgeKey)> {
        let edges: Vec<EdgeKey> = self.mesh.edge_list();
        let mut cands: Vec<(f64, EdgeKey)> = edges
            .into_par_iter()
            .filter(|&k| {
                if let Some((at, found)) = last
                    && self.stamp_of(k.lo) <= *at
                    && self.stamp_of(k.hi) <= *at
                    && !found.contains(&k)
                {
                    return false;
                }
                let primary = self
                    .mesh
                    .edge_tags(k.lo, k.hi)
                    .iter()
                    .any(|t| matches!(t, FeatureOn::Primary { .. }));
                !primary && swap_gain(self.mesh, self.ctx, k).is_some()
            })
            .map(|k| (self.mesh.distance(k.lo, k.hi), k))
            .collect();
        cands.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        cands
    }

    /// Smooth every vertex that may move, in a fixed pseudo-random order.
    pub(crate) fn smooth_pass(&mut self) -> u64 {
        self.smooth_pass_with(Objective::Sum)
    }

    /// [`Self::smooth_pass`] minimising `objective`.
    fn smooth_pass_with(&mut self, objective: Objective) -> u64 {
        let mut verts: Vec<VertexId> = self.mesh.vertices().collect();
        self.rng.shuffle(&mut verts);
        let mut applied = 0;
        // As in the collapse round: with more than one thread the next
        // `PLAN_AHEAD` moves are planned at once in parallel, and a plan is
        // used only while its vertex is unchanged since.
        let mut ahead = PlanAhead::new();
        for (n, &v) in verts.iter().enumerate() {
            let i = v.index();
            if i >= self.failed_smooth.len() {
                self.failed_smooth.resize(i + 1, u64::MAX);
            }
            let at = self.failed_smooth[i];
            if at != u64::MAX && self.stamp_of(v) <= at {
                continue;
            }
            let this = &*self;
            let planned = ahead
                .take(n, &verts, |&w| this.plan_smooth(w, objective))
                .filter(|a: &SmoothAhead| self.fresh(a.at, &[v]));
            let out = match planned {
                Some(a) => try_smooth_planned(self.mesh, self.ctx, a.plan, a.verdict),
                // Planned now, by the same function, with its verdict.
                None => match self.plan_smooth(v, objective) {
                    Some(a) => try_smooth_planned(self.mesh, self.ctx, a.plan, a.verdict),
                    None => continue,
                },
            };
            self.touch(&out, false);
            self.failed_smooth[i] = if out.is_applied() {
                u64::MAX
            } else {
                self.clock
            };
            match out {
                // Fixed vertices are the common case: not worth a tally.
                Outcome::Rejected(Reject::FixedVertex) => {}
                _ => {
                    if self.stats.smooth.record(&out) {
                        applied += 1;
                    }
                }
            }
        }
        applied
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

    /// Plan the smoothing of `v` ahead, on the mesh as it is: `None` where the
    /// pass would skip it (its refusal is remembered).
    fn plan_smooth(&self, v: VertexId, objective: Objective) -> Option<SmoothAhead> {
        if let Some(&at) = self.failed_smooth.get(v.index())
            && at != u64::MAX
            && self.stamp_of(v) <= at
        {
            return None;
        }
        let plan = SmoothPlan::with_objective(self.mesh, self.ctx, v, objective);
        let verdict = plan
            .as_ref()
            .ok()
            .and_then(|p| p.verdict(self.mesh, self.ctx));
        // A refused move keeps its reason only (`try_smooth_planned` refuses
        // a failed plan as it refuses a refused verdict); the plan is
        // dropped here, in parallel.
        let (plan, verdict) = match verdict {
            Some(Err(r)) => (Err(r), None),
            _ => (plan, verdict),
        };
        Some(SmoothAhead {
            at: self.clock,
            plan,
            verdict,
        })
    }

    /// Round every rational vertex that can be; returns how many stay rational.
    fn round_all(&mut self) -> usize {
        let rational: Vec<VertexId> = self
            .mesh
            .vertices()
            .filter(|&v| self.mesh.is_rational(v))
            .collect();
        let mut left = 0;
        for v in rational {
            let out = try_round(self.mesh, self.ctx, v);
            self.touch(&out, false);
            if !self.stats.round.record(&out) {
                left += 1;
            }
        }
        left
    }

    /// Move off-curve primary vertices toward their curve; returns how many stay off.
    fn project_all(&mut self, ever_off: &mut Vec<VertexId>) -> usize {
        let off = off_curve_vertices(self.mesh, self.ctx);
        let mut left = 0;
        for v in off {
            if !ever_off.contains(&v) {
                ever_off.push(v);
            }
            let out = try_project(self.mesh, self.ctx, v);
            self.touch(&out, false);
            self.stats.project.record(&out);
            if on_curve::off_curve(self.mesh, self.ctx, v).unwrap_or(0.0) > self.ctx.on_curve_abs {
                left += 1;
            }
        }
        left
    }
}

/// Primary vertices farther than `ctx.on_curve_abs` from their curve point.
pub(crate) fn off_curve_vertices(mesh: &TriMesh, ctx: &Context) -> Vec<VertexId> {
    let mut primary: Vec<VertexId> = mesh
        .tagged_edges()
        .filter(|(_, tags)| tags.iter().any(|t| matches!(t, FeatureOn::Primary { .. })))
        .flat_map(|(k, _)| [k.lo, k.hi])
        .collect();
    primary.sort_unstable();
    primary.dedup();
    primary
        .into_par_iter()
        .filter(|&v| on_curve::off_curve(mesh, ctx, v).unwrap_or(0.0) > ctx.on_curve_abs)
        .collect()
}

thread_local! {
    /// The face buffer of [`swap_gain`]'s quad lookups.
    static QUAD_BUF: std::cell::RefCell<Vec<crate::mesh::FaceId>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// The energy gain of swapping `k` (old max minus new max) when positive
/// (curved energies in curved mode).
fn swap_gain(mesh: &TriMesh, ctx: &Context, k: EdgeKey) -> Option<f64> {
    let EdgeQuad {
        faces: [f, g],
        a,
        b,
        c,
        d,
    } = QUAD_BUF.with_borrow_mut(|buf| mesh.edge_quad(k.lo, k.hi, buf))?;
    // No edge longer than the context's bound (unless the old one was).
    let new_len = mesh.distance(c, d);
    if new_len > ctx.max_new_edge && new_len > mesh.distance(a, b) {
        return None;
    }
    let old = ops::max_energy_of(mesh, ctx, [mesh.face(f), mesh.face(g)]);
    let new = ops::max_energy_of(mesh, ctx, [[a, d, c], [d, b, c]]);
    // A clear improvement only, so equal configurations never flip back and forth.
    (new.is_finite() && new < old * (1.0 - SWAP_MIN_GAIN)).then_some(old - new)
}

/// Improve `mesh` in place (see the module doc) with the size `opts.l`
/// everywhere. `ctx.envelope` may be restaged (denser sampling, larger ε) when
/// rational vertices are left.
#[cfg(test)]
pub(crate) fn optimize(
    mesh: &mut TriMesh,
    ctx: &mut Context,
    opts: &OptimizeOptions,
) -> OptimizeStats {
    let field = SizeField::uniform(opts.l, mesh_bounds(mesh));
    optimize_with_field(mesh, ctx, opts, &field).0
}

/// The bounding box of a mesh's vertices.
#[cfg(test)]
fn mesh_bounds(mesh: &TriMesh) -> kurbo::Rect {
    mesh.vertices()
        .map(|v| mesh.position(v))
        .fold(None, |r: Option<kurbo::Rect>, p| {
            Some(r.map_or(kurbo::Rect::from_points(p, p), |r| r.union_pt(p)))
        })
        .unwrap_or_default()
}

/// The optimization (the module doc) against the size field `field`: every
/// target starts at the field (`opts.l` is its largest value); split passes
/// resolve it before the main passes where it asks for sizes below the BSP
/// mesh's edges. Returns the statistics and the positions of the vertices the
/// optimizer refined below the field (the size report leaves their edges out).
pub(crate) fn optimize_with_field(
    mesh: &mut TriMesh,
    ctx: &mut Context,
    opts: &OptimizeOptions,
    field: &SizeField,
) -> (OptimizeStats, Vec<kurbo::Point>) {
    let mut ever_off = Vec::new();
    let mut s = Schedule::new(mesh, ctx, opts, SEED, field);
    let rational = s.improve(&mut ever_off);
    if s.stats().stop == StopReason::TimeLimit {
        return (s.stats().clone(), Vec::new());
    }
    // From here on no operation stretches an edge past 2 l: the coarsening's
    // collapses by their length rule, smoothing and swaps by the context's bound.
    s.ctx.max_new_edge = STOP_STRETCH * opts.l;
    s.coarsen();
    s.polish();
    // The min-max polish lifts the worst triangles: quality first.
    s.ctx.max_new_edge = f64::INFINITY;
    s.minmax_polish();
    let rational = s.envelope_stages(rational);
    let refined: Vec<kurbo::Point> = s
        .mesh
        .vertices()
        .filter(|&v| s.is_refined(v))
        .map(|v| s.mesh.position(v))
        .collect();
    (s.finish(rational, &mut ever_off), refined)
}

/// The size field at every vertex slot (`l` at free slots).
fn bases(mesh: &TriMesh, field: &SizeField, l: f64) -> Vec<f64> {
    let mut out = vec![l; mesh.vertex_capacity()];
    if field.is_uniform() {
        return out;
    }
    let verts: Vec<VertexId> = mesh.vertices().collect();
    let vals: Vec<f64> = verts
        .par_iter()
        .map(|&v| field.at(mesh.position(v)))
        .collect();
    for (v, h) in verts.into_iter().zip(vals) {
        out[v.index()] = h;
    }
    out
}

/// Whether the quality goal is met: every vertex in `f64` and on its curve, no
/// edge longer than `2 l`, and the minimum angle above α or the maximum energy
/// below the stop energy (over the triangles not locked).
fn quality_reached(
    m: &Measure,
    opts: &OptimizeOptions,
    rational: usize,
    off: usize,
    stretch: impl FnOnce() -> f64,
) -> bool {
    let good = m.min_angle > opts.alpha_deg || m.max_energy < opts.stop_energy;
    good && rational == 0 && off == 0 && m.longest <= STOP_STRETCH * opts.l && {
        stretch() <= STOP_STRETCH
    }
}

/// Whether a pass from `last` to `now` paid off too little at the current
/// sizes (then the sizing field is refined).
fn paid_off_little(last: &Measure, now: &Measure) -> bool {
    last.max_energy - now.max_energy < SIZING_STALL_MAX
        && last.mean_energy - now.mean_energy < SIZING_STALL_MEAN
}

/// Whether the last ten passes of `history` (maximum and mean energy after
/// each pass) improved neither.
fn stalled(history: &[(f64, f64)]) -> bool {
    let n = history.len();
    n > STALL_PASSES
        && (n - STALL_PASSES..n).all(|i| {
            history[i].0 - history[i - 1].0 >= -STALL_TOLERANCE
                && history[i].1 - history[i - 1].1 >= -STALL_TOLERANCE
        })
}

impl Schedule<'_> {
    /// Whether the deadline has passed (then the stop reason says so).
    fn out_of_time(&mut self) -> bool {
        let expired = self.opts.deadline.expired();
        if expired {
            self.stats.stop = StopReason::TimeLimit;
        }
        expired
    }

    /// The main passes (split, collapse, swap, smooth, round, project), the
    /// sizing field refined when they stop paying off, until a stop rule holds
    /// or the pass limit. Returns how many vertices stay rational.
    fn improve(&mut self, ever_off: &mut Vec<VertexId>) -> usize {
        let opts = self.opts;
        let mut rational = self.round_all();
        let mut off = self.project_all(ever_off);
        let mut last = measure(self.mesh);
        let mut just_updated = false;
        let mut hit_floor = false;
        let mut history: Vec<(f64, f64)> = Vec::new();
        // Splits applied by the last pass: once none is, the stretch against
        // the field is as good as the splits can make it (the rest are refused).
        let mut last_splits = u64::MAX;
        // Where the field asks for sizes well below the BSP mesh's edges (thin
        // strokes, the user's fields), split down to them first: the main
        // passes then work at those sizes.
        for _ in 0..FIELD_SPLIT_PASSES {
            if !self.sizes_pending() || self.out_of_time() {
                break;
            }
            self.split_pass();
        }
        for pass in 0..opts.max_passes {
            if opts.deadline.expired() {
                self.stats.stop = StopReason::TimeLimit;
                break;
            }
            let uniform = self.field.is_uniform();
            if quality_reached(&last, &opts, rational, off, || {
                if uniform || last_splits == 0 {
                    0.0
                } else {
                    self.longest_stretch()
                }
            }) {
                self.stats.stop = StopReason::Quality;
                break;
            }
            self.stats.passes = pass + 1;
            self.refresh_bases();
            // The deadline is also checked between the sub-passes: one pass of
            // a large mesh can take seconds, more on a loaded machine.
            let (long, splits) = self.split_pass();
            last_splits = splits;
            if self.out_of_time() {
                break;
            }
            let collapses = self.collapse_pass(COLLAPSE_FACTOR);
            if self.out_of_time() {
                break;
            }
            let swaps = self.swap_pass();
            if self.out_of_time() {
                break;
            }
            let smooths = self.smooth_pass();
            rational = self.round_all();
            off = self.project_all(ever_off);
            let now = measure(self.mesh);
            tracing::debug!(
                pass,
                long,
                splits,
                collapses,
                swaps,
                smooths,
                rational,
                off,
                min_angle = now.min_angle,
                max_energy = now.max_energy,
                mean_energy = now.mean_energy,
                faces = self.mesh.num_faces(),
                "optimization pass"
            );
            // Refine the sizing field only when the operations stop paying off
            // at the current sizes (then give them a pass to use the new sizes).
            if !just_updated && paid_off_little(&last, &now) {
                hit_floor |= self.update_sizing(now.max_energy);
                just_updated = true;
            } else {
                just_updated = false;
            }
            last = now;
            history.push((now.max_energy, now.mean_energy));
            // Once the sizes are at their floor, ten passes without any gain end it.
            if hit_floor && rational == 0 && off == 0 && stalled(&history) {
                self.stats.stop = StopReason::Stalled;
                break;
            }
        }
        rational
    }

    /// Coarsen where the sizing field was refined for nothing: targets back to
    /// `l`, one collapse pass of every edge whose collapse makes no edge longer
    /// than [`COARSEN_STRETCH`] `l` (collapses never make the local worst
    /// triangle worse).
    fn coarsen(&mut self) {
        self.refresh_bases();
        let all: Vec<VertexId> = self.mesh.vertices().collect();
        for v in all {
            let b = self.base_of(v);
            self.set_target(v, b);
        }
        self.failed_collapse.clear();
        self.max_stretch = COARSEN_STRETCH;
        // Coarsening may make a ring worse, up to the stop energy (the quality
        // asked for) but never worse than the mesh's worst triangle (outside the
        // locked ones) or COARSEN_ENERGY, whichever is larger: the quality the goal
        // measured holds, and how far a good mesh coarsens depends on l, not on
        // how good its worst triangle happened to be.
        self.ctx.energy_floor = measure(self.mesh)
            .max_energy
            .max(COARSEN_ENERGY)
            .min(self.opts.stop_energy);
        self.collapse_pass(COARSEN_FACTOR);
        self.ctx.energy_floor = 0.0;
    }

    /// Polish: swaps and smoothing only (no change of size), each never making
    /// a local worst triangle worse, while they still improve the mean energy.
    fn polish(&mut self) {
        let mut before = measure(self.mesh);
        for _ in 0..POLISH_PASSES {
            let changed = self.swap_pass() + self.smooth_pass();
            let now = measure(self.mesh);
            let gain = before.mean_energy - now.mean_energy;
            before = now;
            if changed == 0 || gain < POLISH_MIN_GAIN * now.mean_energy {
                break;
            }
        }
    }

    /// Min-max polish: smoothing that lowers each ring's largest energy (and
    /// swaps), while the worst triangle still improves.
    fn minmax_polish(&mut self) {
        self.failed_smooth.clear();
        let mut worst = measure(self.mesh).max_energy;
        for _ in 0..MINMAX_PASSES {
            let changed = self.smooth_pass_with(Objective::MinMax) + self.swap_pass();
            let now = measure(self.mesh).max_energy;
            let gain = worst - now;
            worst = now;
            if changed == 0 || gain < MINMAX_MIN_GAIN * now {
                break;
            }
        }
    }

    /// Envelope stages (§2.3.4) while `rational` vertices are left: each gives
    /// them more room (denser sampling, then a larger ε) and smooths and
    /// rounds again. Returns how many stay rational.
    fn envelope_stages(&mut self, mut rational: usize) -> usize {
        let base = self.ctx.envelope.eps();
        let spacing = self.ctx.envelope.spacing();
        for scale in ENVELOPE_EPS {
            let (eps, sp) = (scale * base, ENVELOPE_SPACING * spacing);
            if rational == 0 {
                break;
            }
            self.stats.envelope_stages += 1;
            self.ctx.envelope = self.ctx.envelope.restaged(eps, sp);
            for _ in 0..ENVELOPE_ROUNDS {
                self.smooth_pass();
                rational = self.round_all();
                if rational == 0 {
                    break;
                }
            }
        }
        rational
    }

    /// The last projection of off-curve primary vertices, and the final
    /// statistics (`rational` vertices left; `ever_off`: the primary vertices
    /// that were ever off their curve).
    fn finish(mut self, rational: usize, ever_off: &mut Vec<VertexId>) -> OptimizeStats {
        let off = self.project_all(ever_off);
        let (min_angle, max_e) = measure(self.mesh).all;
        self.stats.rational_left = rational;
        self.stats.off_curve_left = off;
        if off > 0 {
            for v in off_curve_vertices(self.mesh, self.ctx) {
                tracing::debug!(
                    vertex = ?self.mesh.position(v),
                    off = ?on_curve::off_curve(self.mesh, self.ctx, v),
                    tag = ?self.mesh.vertex_tag(v),
                    "primary vertex left off its curve"
                );
            }
        }
        self.stats.projected_vertices = ever_off
            .iter()
            .filter(|&&v| {
                self.mesh.is_vertex_alive(v)
                    && on_curve::off_curve(self.mesh, self.ctx, v).unwrap_or(0.0)
                        <= self.ctx.on_curve_abs
            })
            .count();
        self.stats.min_angle_deg = min_angle;
        self.stats.max_amips = max_e;
        self.stats
    }
}

#[cfg(test)]
mod queue_tests {
    use super::*;
    use proptest::prelude::*;

    fn key(a: usize, b: usize) -> EdgeKey {
        EdgeKey::new(VertexId::from_index(a), VertexId::from_index(b + 100))
    }

    proptest! {
        /// The collapse round's queue pops what one min-heap holding all its
        /// parts would, pushes during the pops included (duplicates too), and
        /// batches staged from the heap at any step.
        #[test]
        fn the_queue_pops_like_one_heap(
            start in prop::collection::vec((0u64..20, 0usize..5, 0usize..5), 0..40),
            pushes in prop::collection::vec((0usize..60, 0u64..20, 0usize..5, 0usize..5), 0..30),
            stages in prop::collection::vec((0usize..60, 1usize..6), 0..10),
        ) {
            let mut q = ShortestFirst::<u64>::default();
            let mut heap = BinaryHeap::new();
            for &(bits, a, b) in &start {
                q.sorted.push((bits, key(a, b)));
                heap.push(std::cmp::Reverse((bits, key(a, b))));
            }
            q.sort();
            let mut step = 0;
            loop {
                for &(at, bits, a, b) in &pushes {
                    if at == step {
                        q.again.push(std::cmp::Reverse((bits, key(a, b))));
                        heap.push(std::cmp::Reverse((bits, key(a, b))));
                    }
                }
                for &(at, n) in &stages {
                    if at == step && q.next_is_unstaged() {
                        // The plan of a staged edge is its bits: it must come
                        // back with its own edge.
                        let batch = q.stage(n);
                        q.push_staged(batch.into_iter().map(|(b, k)| (b, k, Some(b))));
                    }
                }
                let popped = q.pop_indexed();
                if let Some((b, _, Popped::Staged(plan))) = &popped {
                    prop_assert_eq!(*plan, Some(*b));
                }
                let (x, y) = (popped.map(|(b, k, _)| (b, k)), heap.pop().map(|r| r.0));
                prop_assert_eq!(x, y);
                if x.is_none() && step > 60 {
                    break;
                }
                step += 1;
            }
        }

        /// Queued with `push_again`, an edge still ahead in `sorted` is not
        /// queued at all; anything else is, as in one heap: the queue pops
        /// what one min-heap would with that rule applied to each push (its
        /// own record of the sorted edges not yet popped), batches staged at
        /// any step included.
        #[test]
        fn pushing_again_skips_the_edges_still_ahead_in_sorted(
            start in prop::collection::vec((0u64..20, 0usize..5, 0usize..5), 0..40),
            pushes in prop::collection::vec((0usize..60, 0u64..20, 0usize..5, 0usize..5), 0..30),
            stages in prop::collection::vec((0usize..60, 1usize..6), 0..10),
        ) {
            // The round's sorted edges are distinct.
            let start: std::collections::BTreeSet<(u64, EdgeKey)> =
                start.iter().map(|&(bits, a, b)| (bits, key(a, b))).collect();
            let mut q = ShortestFirst::<u64>::default();
            let mut heap = BinaryHeap::new();
            let mut ahead = start.clone();
            for &k in &start {
                q.sorted.push(k);
                heap.push(std::cmp::Reverse((k, true)));
            }
            q.sort();
            for step in 0..200 {
                for &(at, bits, a, b) in &pushes {
                    if at == step {
                        let k = (bits, key(a, b));
                        q.push_again(k);
                        if !ahead.contains(&k) {
                            heap.push(std::cmp::Reverse((k, false)));
                        }
                    }
                }
                for &(at, n) in &stages {
                    if at == step && q.next_is_unstaged() {
                        let batch = q.stage(n);
                        q.push_staged(batch.into_iter().map(|(b, k)| (b, k, Some(b))));
                    }
                }
                let x = q.pop_indexed().map(|(b, k, _)| (b, k));
                let y = heap.pop().map(|r| {
                    if r.0.1 {
                        ahead.remove(&r.0.0);
                    }
                    r.0.0
                });
                prop_assert_eq!(x, y);
            }
        }
    }

    proptest! {
        /// `is_ahead` (the summary, then a block) answers what a search of
        /// `sorted[next..]` does, on lists of many blocks, with runs of
        /// equal bits, for keys in the list, between its entries and beyond
        /// both ends, at any `next`.
        #[test]
        fn is_ahead_finds_what_a_search_of_the_rest_finds(
            start in prop::collection::btree_set((0u64..400, 0usize..8, 0usize..8), 0..700),
            next_at in 0.0f64..1.0,
            probes in prop::collection::vec((0u64..420, 0usize..8, 0usize..8), 1..60),
            from_list in prop::collection::vec(any::<prop::sample::Index>(), 0..60),
        ) {
            let mut q = ShortestFirst::<u64> {
                sorted: start.iter().map(|&(bits, a, b)| (bits, key(a, b))).collect(),
                ..ShortestFirst::default()
            };
            q.sort();
            let n = q.sorted.len();
            q.next = ((n as f64) * next_at) as usize;
            let mut keys: Vec<(u64, EdgeKey)> =
                probes.iter().map(|&(bits, a, b)| (bits, key(a, b))).collect();
            if n > 0 {
                keys.extend(from_list.iter().map(|i| q.sorted[i.index(n)]));
            }
            for k in keys {
                prop_assert_eq!(
                    q.is_ahead(k),
                    q.sorted[q.next..].binary_search(&k).is_ok(),
                    "{:?} with next {} of {}", k, q.next, n
                );
            }
        }
    }

    /// The rule of `push_again` itself: an edge still ahead in `sorted` is
    /// not queued; one popped already is, and so is one never sorted.
    #[test]
    fn an_edge_still_ahead_is_not_queued_again() {
        let mut q = ShortestFirst::<u64> {
            sorted: vec![(1, key(0, 0)), (2, key(1, 1))],
            ..ShortestFirst::default()
        };
        q.sort();
        q.push_again((2, key(1, 1)));
        assert!(q.again.is_empty());
        assert_eq!(
            q.pop_indexed().map(|(b, k, _)| (b, k)),
            Some((1, key(0, 0)))
        );
        q.push_again((1, key(0, 0)));
        q.push_again((2, key(0, 0)));
        assert_eq!(q.again.len(), 2);
    }
}

#[cfg(test)]
mod tally_tests {
    use super::*;

    #[test]
    fn a_tally_serializes_its_refusals_by_name() {
        let mut t = OpTally::default();
        assert_eq!(
            serde_json::to_string(&t).unwrap(),
            r#"{"applied":0,"rejected":{}}"#
        );
        for r in [Reject::Energy, Reject::EdgeLength, Reject::Energy] {
            assert!(!t.record(&Outcome::Rejected(r)));
        }
        assert!(t.record(&Outcome::Applied(crate::ops::LocalChange::default())));
        // By name, as a map sorted by name would be: the names the stats
        // printed before the counts were an array.
        assert_eq!(
            serde_json::to_string(&t).unwrap(),
            r#"{"applied":1,"rejected":{"edge_length":1,"energy":2}}"#
        );
    }
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
    }
}

#[cfg(test)]
mod swap_memo_tests {
    use super::*;
    use crate::ops::EnergyRule;
    use crate::ops::tests::{bsp_mesh, delaunay_mesh};

    /// Between the passes of a schedule, the swap pass's memo (edges not
    /// evaluated again) yields exactly the candidates of a full evaluation.
    #[test]
    fn the_swap_memo_finds_what_a_full_scan_finds() {
        let meshes = (0..3)
            .map(|seed| bsp_mesh(seed, EnergyRule::NoWorseMax))
            .chain((0..2).map(|seed| delaunay_mesh(seed, EnergyRule::NoWorseMax)));
        let (mut checked, mut skipped) = (0, 0);
        for (i, (mut mesh, mut ctx)) in meshes.enumerate() {
            let opts = test_options();
            let field = SizeField::uniform(opts.l, mesh_bounds(&mesh));
            let mut s = Schedule::new(&mut mesh, &mut ctx, &opts, 7, &field);
            for pass in 0..8 {
                s.split_pass();
                s.collapse_pass(0.8);
                // A full scan, then the memo's, against the state the last
                // swap pass left (none before the first).
                let full = s.swap_candidates(None);
                let memo = s.swap_candidates(s.swap_scan.as_ref());
                assert_eq!(full, memo, "mesh {i}, pass {pass}");
                checked += full.len();
                if let Some((at, found)) = &s.swap_scan {
                    skipped += s
                        .mesh
                        .edges()
                        .filter(|k| {
                            s.stamp_of(k.lo) <= *at && s.stamp_of(k.hi) <= *at && !found.contains(k)
                        })
                        .count();
                }
                s.swap_pass();
                s.smooth_pass();
            }
        }
        // The check saw candidates and skipped edges (it would pass vacuously
        // on none).
        assert!(
            checked > 50 && skipped > 50,
            "{checked} candidates, {skipped} skipped"
        );
    }
}

#[cfg(test)]
mod plan_ahead_tests {
    use super::*;
    use crate::ops::EnergyRule;
    use crate::ops::tests::{bsp_mesh, delaunay_mesh};

    /// The passes with their plans made ahead on two threads do exactly what
    /// they do on one (same mesh, same tallies), and the plans were used and
    /// some found stale (else the check would be vacuous).
    #[test]
    fn planning_ahead_on_two_threads_changes_nothing() {
        let meshes: Vec<_> = (0..3)
            .map(|seed| bsp_mesh(seed, EnergyRule::NoWorseMax))
            .chain((0..2).map(|seed| delaunay_mesh(seed, EnergyRule::NoWorseMax)))
            .collect();
        let opts = test_options();
        let run = |threads: usize, mesh: &TriMesh, ctx: &Context| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            pool.install(|| {
                let (mut mesh, mut ctx) = (mesh.clone(), ctx.clone());
                let field = SizeField::uniform(opts.l, mesh_bounds(&mesh));
                let mut s = Schedule::new(&mut mesh, &mut ctx, &opts, 7, &field);
                for pass in 0..6 {
                    s.split_pass();
                    s.collapse_pass(if pass < 3 { 0.8 } else { COARSEN_FACTOR });
                    s.swap_pass();
                    s.smooth_pass();
                    s.smooth_pass_with(Objective::MinMax);
                    let worst = measure(s.mesh).max_energy;
                    s.update_sizing(worst);
                }
                let (stats, tally) = (s.stats().clone(), (s.ahead_tally, s.staged_tally));
                (mesh, stats, tally)
            })
        };
        let (mut used, mut stale, mut staged) = (0, 0, 0);
        for (i, (mesh, ctx)) in meshes.iter().enumerate() {
            let (one, stats_one, tally_one) = run(1, mesh, ctx);
            let (two, stats_two, tally_two) = run(2, mesh, ctx);
            assert!(one == two, "mesh {i}: two threads made another mesh");
            assert_eq!(stats_one, stats_two, "mesh {i}");
            assert_eq!(
                tally_one,
                ((0, 0), 0),
                "mesh {i}: one thread plans nothing ahead"
            );
            used += tally_two.0.0;
            stale += tally_two.0.1;
            staged += tally_two.1;
        }
        assert!(
            used > 1000 && stale > 10 && staged > 100,
            "{used} plans used, {stale} stale, {staged} staged"
        );
    }
}
