//! The swap pass: swaps (reroutes on secondary feature edges) that lower the
//! larger energy of their two triangles, longest first, with the memo of the
//! last scan; and the gain of a swap.

use super::queue::PlanAhead;
use super::scope::Scope;
use super::{SWAP_MIN_GAIN, Schedule};
use crate::mesh::{EdgeKey, EdgeQuad, FeatureOn, TriMesh, VertexId};
use crate::ops;
use crate::ops::{Context, Reject, ReroutePlan, SwapPlan, try_reroute_planned, try_swap_planned};
use rayon::prelude::*;
use rustc_hash::FxHashSet;

/// Edges of the swap scan between two readings of the deadline (small
/// enough that the blocks still share out well between threads).
const SCAN_BLOCK: usize = 512;

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

impl<D: Sync> Schedule<'_, D> {
    /// Swap the edges of `scope` where that lowers the larger energy of their
    /// two triangles; on secondary feature edges, the same change is a
    /// reroute (`ops::swap`).
    pub(super) fn swap_pass(&mut self, scope: &Scope) -> u64 {
        let scanned_at = self.memos.clock();
        let last = self.memos.take_swap_scan();
        let cands = self.swap_candidates(scope, last.as_ref());
        if self.out_of_time_in_loop() {
            // (the scan may have skipped blocks: the run ends here)
            return 0;
        }
        self.memos
            .set_swap_scan(scanned_at, cands.iter().map(|&(_, k)| k).collect());
        self.queued(cands.len());
        let mut applied = 0;
        // As in the collapse round: with more than one thread the next
        // `PLAN_AHEAD` swaps are planned (and their invariants decided) at
        // once in parallel; a plan is used only while the four vertices of
        // its quad are unchanged since.
        let mut ahead = PlanAhead::new();
        for (n, &(_, k)) in cands.iter().enumerate() {
            if self.out_of_time_at(n) {
                break;
            }
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
                    let changed = self.memos.stamp_of(k.lo) > scanned_at
                        || self.memos.stamp_of(k.hi) > scanned_at;
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
            self.memos.touch(self.mesh, &out, true);
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
        let at = self.memos.clock();
        let changed =
            self.memos.stamp_of(k.lo) > scanned_at || self.memos.stamp_of(k.hi) > scanned_at;
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

    /// The swap pass's candidates in `scope`, longest first: the edges off
    /// primary features where a swap lowers the larger energy of their two
    /// triangles.
    /// With `last` (the clock of the previous scan and the edges it found),
    /// an edge whose ends' faces have not changed since and that was not
    /// found then is not evaluated again: its quad is the same (a change of
    /// either face, or a move of any of its four vertices, stamps both ends),
    /// and so is the answer.
    fn swap_candidates(
        &self,
        scope: &Scope,
        last: Option<&(u64, FxHashSet<EdgeKey>)>,
    ) -> Vec<(f64, EdgeKey)> {
        let edges: Vec<EdgeKey> = scope.edges(self.mesh);
        let deadline = &self.limits.deadline;
        let keep = |&k: &EdgeKey| {
            if !scope.touches(k.lo, k.hi) {
                return false;
            }
            if let Some((at, found)) = last
                && self.memos.stamp_of(k.lo) <= *at
                && self.memos.stamp_of(k.hi) <= *at
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
        };
        // In blocks, each asking the deadline first (a scan of a large mesh
        // takes a good part of a second); past it the rest are skipped and
        // the pass stops before it applies anything.
        let mut cands: Vec<(f64, EdgeKey)> = edges
            .par_chunks(SCAN_BLOCK)
            .flat_map_iter(|block| {
                let skip = deadline.expired_in_loop();
                block
                    .iter()
                    .filter(move |k| !skip && keep(k))
                    .map(|&k| (self.mesh.distance(k.lo, k.hi), k))
            })
            .collect();
        // (The edges are distinct: an unstable sort gives the one order.)
        super::queue::sort_unstable_by(&mut cands, |a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        cands
    }
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

#[cfg(test)]
mod swap_memo_tests {
    use super::*;
    use crate::optimize::schedule::driver::mesh_bounds;
    use crate::optimize::schedule::{test_meshes, test_options};
    use crate::sizing::SizeField;

    /// Between the passes of a schedule, the swap pass's memo (edges not
    /// evaluated again) yields exactly the candidates of a full evaluation.
    #[test]
    fn the_swap_memo_finds_what_a_full_scan_finds() {
        let (mut checked, mut skipped) = (0, 0);
        for (i, (mut mesh, mut ctx)) in test_meshes(3, 2).enumerate() {
            let opts = test_options();
            let field = SizeField::uniform(opts.limits.l, mesh_bounds(&mesh));
            let mut s = Schedule::new(&mut mesh, &mut ctx, &opts, 7, &field);
            let whole = &mut Scope::Whole;
            for pass in 0..8 {
                s.split_pass(whole);
                s.collapse_pass(whole, 0.8);
                // A full scan, then the memo's, against the state the last
                // swap pass left (none before the first).
                let full = s.swap_candidates(whole, None);
                let memo = s.swap_candidates(whole, s.memos.swap_scan());
                assert_eq!(full, memo, "mesh {i}, pass {pass}");
                checked += full.len();
                if let Some((at, found)) = s.memos.swap_scan() {
                    skipped += s
                        .mesh
                        .edges()
                        .filter(|k| {
                            s.memos.stamp_of(k.lo) <= *at
                                && s.memos.stamp_of(k.hi) <= *at
                                && !found.contains(k)
                        })
                        .count();
                }
                s.swap_pass(whole);
                s.smooth_pass(whole);
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
