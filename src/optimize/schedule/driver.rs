//! The linear schedule's driver: its options, the entry points
//! ([`optimize_with_field`], and `optimize` for the tests), the main passes
//! with their stop rules, then the coarsening, the polish, the min-max polish,
//! the worst-element phase (`repair.rs`), the envelope stages and the final
//! statistics; and the deadline checks every pass makes.

use super::scope::Scope;
use super::smooth::off_curve_vertices;
use super::stats::{Measure, OptimizeStats, StopReason, measure};
use super::{
    COARSEN_ENERGY, COARSEN_FACTOR, COARSEN_STRETCH, COLLAPSE_FACTOR, ENVELOPE_EPS,
    ENVELOPE_ROUNDS, ENVELOPE_SPACING, EQUALIZE_COLLAPSE, EQUALIZE_ROUNDS, EQUALIZE_STRETCH,
    FIELD_SPLIT_PASSES, MAIN_BOUNDS, MINMAX_MIN_GAIN, MINMAX_PASSES, OPEN_STRETCH, POLISH_MIN_GAIN,
    POLISH_PASSES, PassLimits, Phase, SEED, SIZING_STALL_MAX, SIZING_STALL_MEAN, SPLIT_ABOVE,
    STALL_PASSES, STALL_TOLERANCE, STOP_STRETCH, Schedule, Stretch, UNDONE_PASSES,
};
use crate::mesh::{TriMesh, VertexId};
use crate::ops::invariants::on_curve;
use crate::ops::{Context, Objective};
use crate::sizing::SizeField;
use rustc_hash::FxHashSet;

/// Parameters of the linear schedule, in user units: what every pass reads,
/// and what only its driver reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct OptimizeOptions {
    /// `l`, the deadline and the optimizer's parameters.
    pub limits: PassLimits,
    /// The sizing floor, the stop rules and the vertex budget.
    pub linear: LinearOptions,
}

/// What only the linear schedule reads (its driver, the split pass, the
/// refinement of the targets and the worst-element phase), in user units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LinearOptions {
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
}

/// Improve `mesh` in place (see the module doc) with the size `opts.limits.l`
/// everywhere. `ctx.envelope` may be restaged (denser sampling, larger ε) when
/// rational vertices are left.
#[cfg(test)]
pub(crate) fn optimize(
    mesh: &mut TriMesh,
    ctx: &mut Context,
    opts: &OptimizeOptions,
) -> OptimizeStats {
    let field = SizeField::uniform(opts.limits.l, mesh_bounds(mesh));
    optimize_with_field(mesh, ctx, opts, &field).0
}

/// The bounding box of a mesh's vertices.
#[cfg(test)]
pub(super) fn mesh_bounds(mesh: &TriMesh) -> kurbo::Rect {
    mesh.vertices()
        .map(|v| mesh.position(v))
        .fold(None, |r: Option<kurbo::Rect>, p| {
            Some(r.map_or(kurbo::Rect::from_points(p, p), |r| r.union_pt(p)))
        })
        .unwrap_or_default()
}

/// The optimization (the module doc) against the size field `field`: every
/// target starts at the field (`opts.limits.l` is its largest value); split passes
/// resolve it before the main passes where it asks for sizes below the BSP
/// mesh's edges. Returns the statistics and the positions of the vertices the
/// optimizer refined below the field (the size report leaves their edges out).
pub(crate) fn optimize_with_field(
    mesh: &mut TriMesh,
    ctx: &mut Context,
    opts: &OptimizeOptions,
    field: &SizeField,
) -> (OptimizeStats, Vec<kurbo::Point>) {
    let mut ever_off = FxHashSet::default();
    let mut s = Schedule::new(mesh, ctx, opts, SEED, field);
    let rational = s.improve(&mut ever_off);
    // Past the deadline the run ends with the time limit's error, so the
    // phases left are not run (each is a pass or more over the whole mesh).
    let stopped =
        |s: &Schedule<LinearOptions>| (s.timed_out()).then(|| (s.stats().clone(), Vec::new()));
    if let Some(out) = stopped(&s) {
        return out;
    }
    let phases: [(fn(&mut _), &str, &str); 4] = [
        (Schedule::coarsen, "coarsen", "coarsening done"),
        (Schedule::equalize, "equalize", "equalizing done"),
        (Schedule::polish, "polish", "polish done"),
        (Schedule::minmax_polish, "min_max", "min-max polish done"),
    ];
    for (phase, name, done) in phases {
        s.begin_phase(name);
        phase(&mut s);
        tracing::debug!(collapses_refused = s.stats.collapse.refused(), "{done}");
        if let Some(out) = stopped(&s) {
            return out;
        }
    }
    s.enter(Phase::Main);
    s.begin_phase("repair");
    s.stats.bad_corners_left = s.repair_angles();
    if let Some(out) = stopped(&s) {
        return out;
    }
    // the splits of the worst-element phase may leave rational vertices
    s.begin_phase("envelope");
    let rational = if rational > 0 || s.mesh.vertices().any(|v| s.mesh.is_rational(v)) {
        s.round_all()
    } else {
        0
    };
    let rational = s.envelope_stages(rational);
    if let Some(out) = stopped(&s) {
        return out;
    }
    let refined: Vec<kurbo::Point> = s
        .mesh
        .vertices()
        .filter(|&v| s.targets.is_refined(v))
        .map(|v| s.mesh.position(v))
        .collect();
    (s.finish(rational, &mut ever_off), refined)
}

/// Whether the quality goal is met: every vertex in `f64` and on its curve, no
/// edge longer than `2 l`, and the minimum angle above α or the maximum energy
/// below the stop energy (over the triangles not locked).
fn quality_reached(
    m: &Measure,
    l: f64,
    linear: &LinearOptions,
    rational: usize,
    off: usize,
    stretch: impl FnOnce() -> f64,
) -> bool {
    let good = m.min_angle > linear.alpha_deg || m.max_energy < linear.stop_energy;
    good && rational == 0 && off == 0 && m.longest <= STOP_STRETCH * l && {
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

/// Items of a pass between two checks of the deadline inside it.
pub(super) const DEADLINE_EVERY: usize = 64;

impl<D> Schedule<'_, D> {
    /// Inside a pass's loop, at its `n`-th item: whether the time limit has
    /// passed (or a memory overrun is latched; the memory itself is read
    /// between the passes), asked every [`DEADLINE_EVERY`] items (one item on a vertex of a
    /// huge ring can take milliseconds, a pass many seconds). A pass cut
    /// short here ends the run with the time limit's error, so no mesh that
    /// is written depends on where it stopped.
    pub(super) fn out_of_time_at(&mut self, n: usize) -> bool {
        n % DEADLINE_EVERY == DEADLINE_EVERY - 1 && self.out_of_time_in_loop()
    }

    /// [`Self::out_of_time_at`] now, whatever the item: the time and a
    /// latched overrun only (then the stop reason says so).
    pub(super) fn out_of_time_in_loop(&mut self) -> bool {
        if !self.limits.deadline.expired_in_loop() {
            return false;
        }
        self.stats.stop = StopReason::TimeLimit;
        true
    }

    /// Whether a check has found the deadline passed (the stop reason says
    /// so): the run then ends with the time limit's error.
    pub(super) fn timed_out(&self) -> bool {
        self.stats.stop == StopReason::TimeLimit
    }

    /// Whether the deadline has passed (then the stop reason says so).
    pub(super) fn out_of_time(&mut self) -> bool {
        let expired = self.limits.deadline.expired();
        if expired {
            self.stats.stop = StopReason::TimeLimit;
        }
        expired
    }
}

impl Schedule<'_, LinearOptions> {
    /// The main passes (split, collapse, swap, smooth, round, project), the
    /// sizing field refined when they stop paying off, until a stop rule holds
    /// or the pass limit. Returns how many vertices stay rational.
    fn improve(&mut self, ever_off: &mut FxHashSet<VertexId>) -> usize {
        let (limits, linear) = (self.limits, self.driver);
        self.begin_phase("start");
        let mut rational = self.round_all();
        let mut off = self.project_all(ever_off);
        let mut last = measure(self.mesh);
        let mut just_updated = false;
        let mut hit_floor = false;
        let mut history: Vec<(f64, f64)> = Vec::new();
        // Splits applied by the last pass: once none is, the stretch against
        // the field is as good as the splits can make it (the rest are refused).
        let mut last_splits = u64::MAX;
        // Passes in a row whose splits the collapses undid: as many of each,
        // and the mesh's size and worst energy as after the pass before. The
        // remaining long edges are then ones the collapses will not keep
        // split (on a flag of Aquitaine, 9 splits and 9 collapses in each of
        // 60 passes, to the pass limit).
        let mut undone = 0usize;
        let mut last_faces = usize::MAX;
        // Where the field asks for sizes well below the BSP mesh's edges (thin
        // strokes, the user's fields), split down to them first: the main
        // passes then work at those sizes.
        for _ in 0..FIELD_SPLIT_PASSES {
            if !self.sizes_pending() || self.out_of_time() {
                break;
            }
            self.split_pass(&mut Scope::Whole);
        }
        self.begin_phase("main");
        for pass in 0..linear.max_passes {
            if limits.deadline.expired() {
                self.stats.stop = StopReason::TimeLimit;
                break;
            }
            let uniform = self.targets.is_uniform();
            if quality_reached(&last, limits.l, &linear, rational, off, || {
                if uniform || last_splits == 0 || undone >= UNDONE_PASSES {
                    0.0
                } else {
                    self.longest_stretch()
                }
            }) {
                self.stats.stop = StopReason::Quality;
                break;
            }
            self.stats.passes = pass + 1;
            self.targets.refresh(self.mesh);
            // The deadline is also checked between the sub-passes: one pass of
            // a large mesh can take seconds, more on a loaded machine.
            let (long, splits) = self.split_pass(&mut Scope::Whole);
            last_splits = splits;
            let splits_of_pass = splits;
            if self.out_of_time() {
                break;
            }
            let collapses = self.collapse_pass(&Scope::Whole, COLLAPSE_FACTOR);
            if self.out_of_time() {
                break;
            }
            let swaps = self.swap_pass(&Scope::Whole);
            if self.out_of_time() {
                break;
            }
            let smooths = self.smooth_pass(&Scope::Whole);
            rational = self.round_all();
            off = self.project_all(ever_off);
            let now = measure(self.mesh);
            let faces = self.mesh.num_faces();
            let same = faces == last_faces && now.max_energy == last.max_energy;
            undone = if splits_of_pass > 0 && splits_of_pass == collapses && same {
                undone + 1
            } else {
                0
            };
            last_faces = faces;
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
                collapses_refused = self.stats.collapse.refused(),
                smooths_refused = self.stats.smooth.refused(),
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
    /// the field, one collapse pass of every edge whose collapse makes no edge
    /// longer than [`OPEN_STRETCH`] times its target where the field is at `l`,
    /// and [`COARSEN_STRETCH`] below it (the split bound there too when the
    /// user asked for sizes). Collapses never make the local worst triangle
    /// worse than the floor below.
    fn coarsen(&mut self) {
        self.targets.refresh(self.mesh);
        let all: Vec<VertexId> = self.mesh.vertices().collect();
        for v in all {
            let b = self.targets.base_of(v);
            self.targets.set_target(v, b);
        }
        self.enter(Phase::Coarsen);
        self.keep_standing_refusals(COARSEN_FACTOR);
        self.collapse_pass(&Scope::Whole, COARSEN_FACTOR);
    }

    /// Equalise edge lengths against the field (isotropic remeshing's
    /// rounds): free vertices relaxed to their neighbours' mean, edges below
    /// [`EQUALIZE_COLLAPSE`] of their target collapsed where no edge gets past
    /// [`EQUALIZE_STRETCH`] of its own (the split bound near the user's size
    /// sources), swaps; rings may get as bad as the coarsening allows.
    fn equalize(&mut self) {
        self.enter(Phase::Equalize);
        // Refusals under the earlier phases' rules are forgotten once; within
        // the rounds a refusal stands until its vertices move or their faces
        // change (the memos' stamps).
        self.memos.forget_smooth_refusals();
        self.keep_standing_refusals(EQUALIZE_COLLAPSE);
        for _ in 0..EQUALIZE_ROUNDS {
            if self.out_of_time() {
                break;
            }
            let relaxed = self.smooth_pass_with(&Scope::Whole, Objective::Relax);
            let collapsed = self.collapse_pass(&Scope::Whole, EQUALIZE_COLLAPSE);
            let swaps = self.swap_pass(&Scope::Whole);
            tracing::debug!(
                relaxed,
                collapsed,
                swaps,
                collapses_refused = self.stats.collapse.refused(),
                "equalize round"
            );
            if relaxed + collapsed == 0 {
                break;
            }
        }
        self.memos.forget_smooth_refusals();
    }

    /// Forget the refused collapses that the phase just entered (its
    /// collapses shorter than `factor` times the target) may allow: its
    /// sizes, stretch or energy floor differ. Keep the rest
    /// ([`Memos::keep_refusals_standing_under`](super::Memos::keep_refusals_standing_under)):
    /// re-planning them would refuse them again (the tests re-plan every one
    /// kept and check).
    pub(super) fn keep_standing_refusals(&mut self, factor: f64) {
        let floor = self.ctx.energy_floor;
        self.memos.keep_refusals_standing_under(floor);
        #[cfg(test)]
        {
            let kept = self.memos.collapse_refusals();
            for (k, at) in kept {
                let unchanged = self.mesh.is_vertex_alive(k.lo)
                    && self.mesh.is_vertex_alive(k.hi)
                    && self.memos.stamp_of(k.lo) <= at
                    && self.memos.stamp_of(k.hi) <= at;
                if !unchanged {
                    continue;
                }
                if let Some(refused) = self.refused_on_replanning(k, factor) {
                    assert!(
                        refused,
                        "a refusal kept across phases is not refused: {k:?}"
                    );
                    self.tally.standing_checked += 1;
                }
            }
        }
        let _ = factor;
    }

    /// Enter `phase`: its energy floor, its longest new edge and its
    /// collapses' stretch (see [`Phase`]).
    pub(super) fn enter(&mut self, phase: Phase) {
        // The floor of the phases that coarsen: a ring may get as bad as the
        // stop energy (the quality asked for) but never worse than the mesh's
        // worst triangle (outside the locked ones) or COARSEN_ENERGY,
        // whichever is larger: the quality the goal measured holds, and how
        // far a good mesh coarsens depends on l, not on how good its worst
        // triangle happened to be.
        let coarsen_floor = || {
            measure(self.mesh)
                .max_energy
                .max(COARSEN_ENERGY)
                .min(self.driver.stop_energy)
        };
        // Near size sources the user asked for, collapses keep the split
        // bound in every phase; near the drawing's own (thin strokes) the
        // coarsening stretches as it did before the size field.
        let asked = self.targets.is_asked();
        let below = |s: f64| if asked { SPLIT_ABOVE } else { s };
        // After the main passes no operation stretches an edge past 2 l (the
        // collapses by their length rule, smoothing and swaps by the
        // context's bound), except the min-max polish: quality first.
        let (floor, max_new_edge, stretch) = match phase {
            Phase::Main => MAIN_BOUNDS,
            Phase::Coarsen => (
                coarsen_floor(),
                STOP_STRETCH * self.limits.l,
                Stretch {
                    open: OPEN_STRETCH,
                    below: below(COARSEN_STRETCH),
                },
            ),
            Phase::Equalize => (
                coarsen_floor(),
                STOP_STRETCH * self.limits.l,
                Stretch {
                    open: EQUALIZE_STRETCH,
                    below: below(EQUALIZE_STRETCH),
                },
            ),
            Phase::Polish => (
                0.0,
                STOP_STRETCH * self.limits.l,
                Stretch::uniform(SPLIT_ABOVE),
            ),
            Phase::MinMax => (0.0, f64::INFINITY, Stretch::uniform(SPLIT_ABOVE)),
        };
        self.bound((floor, max_new_edge, stretch));
    }

    /// Polish: swaps and smoothing only (no change of size), each never making
    /// a local worst triangle worse, while they still improve the mean energy.
    fn polish(&mut self) {
        self.enter(Phase::Polish);
        let mut before = measure(self.mesh);
        for _ in 0..POLISH_PASSES {
            let changed = self.swap_pass(&Scope::Whole) + self.smooth_pass(&Scope::Whole);
            if self.timed_out() {
                return;
            }
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
        self.enter(Phase::MinMax);
        self.memos.forget_smooth_refusals();
        let mut worst = measure(self.mesh).max_energy;
        for _ in 0..MINMAX_PASSES {
            let changed = self.smooth_pass_with(&Scope::Whole, Objective::MinMax)
                + self.swap_pass(&Scope::Whole);
            if self.timed_out() {
                return;
            }
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
                self.smooth_pass(&Scope::Whole);
                rational = self.round_all();
                if rational == 0 || self.timed_out() {
                    return rational;
                }
            }
        }
        rational
    }

    /// The last projection of off-curve primary vertices, and the final
    /// statistics (`rational` vertices left; `ever_off`: the primary vertices
    /// that were ever off their curve).
    fn finish(mut self, rational: usize, ever_off: &mut FxHashSet<VertexId>) -> OptimizeStats {
        let off = self.project_all(ever_off);
        self.end_phase();
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
mod standing_tests {
    use super::*;
    use crate::optimize::schedule::{test_meshes, test_options};

    /// The collapses refused in the main passes and kept across the
    /// coarsening's and the equalisation's change of rules are refused again
    /// when planned under the new rules (`keep_standing_refusals` plans each
    /// again in tests and asserts it); and there were such refusals to check.
    #[test]
    fn refusals_kept_across_phases_are_refused_when_planned_again() {
        let mut checked = 0;
        for (mut mesh, mut ctx) in test_meshes(10, 5) {
            let opts = test_options();
            let field = SizeField::uniform(opts.limits.l, mesh_bounds(&mesh));
            let mut s = Schedule::new(&mut mesh, &mut ctx, &opts, SEED, &field);
            s.improve(&mut FxHashSet::default());
            s.coarsen();
            s.equalize();
            checked += s.tally.standing_checked;
        }
        // (most refusals of these small meshes are the length rule's or at
        // free vertices: 30 stand)
        assert!(checked > 10, "{checked} kept refusals planned again");
    }

    /// The phases' records account for the whole run: every phase once, in
    /// the order it ran; their operations add up to the tallies; each ends
    /// with the triangles the next starts from, the last with the mesh's.
    #[test]
    fn the_phases_account_for_every_operation_in_order() {
        let mut seen_main_work = false;
        for (mut mesh, mut ctx) in test_meshes(2, 1) {
            let opts = test_options();
            let field = SizeField::uniform(opts.limits.l, mesh_bounds(&mesh));
            let stats = optimize_with_field(&mut mesh, &mut ctx, &opts, &field).0;
            let names: Vec<&str> = stats.phases.iter().map(|p| p.phase).collect();
            assert_eq!(
                names,
                [
                    "start", "main", "coarsen", "equalize", "polish", "min_max", "repair",
                    "envelope"
                ]
            );
            let tallies = [
                &stats.split,
                &stats.collapse,
                &stats.swap,
                &stats.reroute,
                &stats.smooth,
                &stats.round,
                &stats.project,
            ];
            let applied: u64 = tallies.iter().map(|t| t.applied).sum();
            let refused: u64 = tallies.iter().map(|t| t.refused()).sum();
            assert_eq!(stats.phases.iter().map(|p| p.applied).sum::<u64>(), applied);
            assert_eq!(stats.phases.iter().map(|p| p.refused).sum::<u64>(), refused);
            for p in &stats.phases {
                assert!(p.seconds >= 0.0 && p.largest_queue <= p.queued, "{p:?}");
                assert!(p.queues > 0 || p.queued == 0, "{p:?}");
            }
            assert_eq!(stats.phases.last().unwrap().triangles, mesh.num_faces());
            let main = &stats.phases[1];
            seen_main_work |= main.queues > 0 && main.applied > 0;
        }
        assert!(
            seen_main_work,
            "the main passes did nothing on any test mesh"
        );
    }

    /// Past the deadline every pass stops and says so: the swap pass after
    /// its scan with nothing applied, the others and the rounding within
    /// their first [`DEADLINE_EVERY`] items; the phases after the main passes
    /// are not entered (a whole optimization stops before its first pass).
    #[test]
    fn passes_past_the_deadline_stop_and_say_so() {
        let mut swapped_without = 0;
        for (mut mesh, mut ctx) in test_meshes(4, 2) {
            // what a swap pass does with time to spare
            {
                let (mut mesh, mut ctx) = (mesh.clone(), ctx.clone());
                let opts = test_options();
                let field = SizeField::uniform(opts.limits.l, mesh_bounds(&mesh));
                let mut s = Schedule::new(&mut mesh, &mut ctx, &opts, SEED, &field);
                swapped_without += s.swap_pass(&Scope::Whole);
            }
            let mut opts = test_options();
            opts.limits.deadline = crate::budget::Deadline::after(Some(0.0));
            let field = SizeField::uniform(opts.limits.l, mesh_bounds(&mesh));
            let (mut fresh, mut fresh_ctx) = (mesh.clone(), ctx.clone());
            {
                let mut s = Schedule::new(&mut mesh, &mut ctx, &opts, SEED, &field);
                assert_eq!(s.swap_pass(&Scope::Whole), 0);
                assert!(s.timed_out());
                let limit = (DEADLINE_EVERY - 1) as u64;
                for pass in 0..3 {
                    s.stats.stop = StopReason::PassLimit;
                    let applied = match pass {
                        0 => s.split_pass(&mut Scope::Whole).1,
                        1 => s.collapse_pass(&Scope::Whole, COLLAPSE_FACTOR),
                        _ => s.smooth_pass(&Scope::Whole),
                    };
                    assert!(s.timed_out() || applied < limit, "pass {pass}");
                    assert!(applied <= limit, "pass {pass}: {applied} applied");
                }
            }
            // (the passes above may have changed the mesh: a fresh copy)
            let stats = optimize_with_field(&mut fresh, &mut fresh_ctx, &opts, &field).0;
            assert_eq!(stats.stop, StopReason::TimeLimit);
            assert_eq!(stats.passes, 0);
            assert_eq!(stats.collapse.applied + stats.smooth.applied, 0);
        }
        assert!(swapped_without > 0, "the meshes had swaps to do");
    }
}
