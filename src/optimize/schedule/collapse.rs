//! The collapse pass: rounds of shortest-first collapses of the edges below
//! their target, refusals remembered until the neighbourhood changes, the
//! collapses planned ahead in parallel.

use super::queue::{PlanAhead, Popped, ShortestFirst, sort_unstable};
use super::scope::Scope;
use super::sizing::lengths_kept;
use super::{
    COLLAPSE_BUDGET_EXTRA, COLLAPSE_BUDGET_PER_EDGE, COLLAPSE_ROUNDS, PLAN_AHEAD, STAGE_MIN,
    STAGE_PAR_MIN, Schedule,
};
use crate::mesh::{EdgeKey, TriMesh, VertexId};
use crate::ops::{CollapsePlan, Outcome, Reject, collapse_refusal, try_collapse_planned};
use rayon::prelude::*;

/// One direction of a collapse planned ([`Schedule::plan_collapse`]).
enum CollapseDirection {
    /// Its refusal by the role rules is remembered, and v's faces are
    /// unchanged since ([`Memos::role_refusal`](super::Memos::role_refusal)): the same refusal,
    /// without planning it again.
    Remembered(Reject),
    /// The length rule refused it.
    Length,
    /// [`CollapsePlan::new`] on v's ring, with [`CollapsePlan::verdict`]
    /// (boxed: plans are moved through the window and the round).
    Plan(Box<PlannedCollapse>),
    /// The plan or its verdict refused it (as `try_collapse_planned` would,
    /// with whether by the role rules, and whether the energy floor applied:
    /// [`CollapsePlan::new_noting_floor`]).
    Refused(Reject, bool, bool),
    /// Not planned: the first direction's collapse was decided, and a
    /// decided collapse is applied (it commits without a check that could
    /// refuse it), so the round never reads the second.
    Unneeded,
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
/// [`Memos::collapse_refused`](super::Memos::collapse_refused)).
struct CollapseAhead {
    at: u64,
    /// `None`: the round skips the edge (an end is dead, its length changed
    /// or is long enough, or its refusal is remembered).
    directions: Option<[CollapseDirection; 2]>,
}

impl<D: Sync> Schedule<'_, D> {
    /// Collapse the edges of `scope` shorter than `factor` times their mean
    /// target, shortest first.
    pub(super) fn collapse_pass(&mut self, scope: &Scope, factor: f64) -> u64 {
        // Refused collapses are retried (in a new round) once a collapse has
        // changed their neighbourhood, as long as rounds make progress.
        let mut total = 0;
        let mut since = None;
        for _ in 0..COLLAPSE_ROUNDS {
            let start = self.memos.clock();
            let n = self.collapse_round(scope, factor, since);
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
    /// (its memo still holds, and a collapse pass changes no length or
    /// target), so the round skips the scan of the whole mesh.
    fn collapse_round(&mut self, scope: &Scope, factor: f64, since: Option<u64>) -> u64 {
        // Shortest first, by the bits of the (non-negative) length, which
        // order like the lengths: the short edges sorted once, and a min-heap
        // for the edges queued again during the round, popped together in
        // one order.
        let mut queue = ShortestFirst::default();
        let edges: Vec<EdgeKey> = match since {
            None => scope.edges(self.mesh),
            Some(at) => {
                // The edges at the vertices stamped since `at`, found in
                // parallel and sorted (the queue's order does not depend on
                // how they were found).
                let mesh: &TriMesh = self.mesh;
                let touched: Vec<VertexId> = mesh
                    .vertices()
                    .filter(|&v| self.memos.stamp_of(v) > at)
                    .collect();
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
                (len < factor * self.targets.edge_target(self.mesh, k) && scope.touches(k.lo, k.hi))
                    .then_some((len.to_bits(), k))
            })
            .collect();
        queue.sort();
        self.queued(queue.sorted.len());
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
                    ahead.window(|| batch.par_iter().map(plan).collect())
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
            if budget == 0 || self.out_of_time_at(budget) {
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
                        self.tally.staged += usize::from(plan.is_some());
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
                    |s: &Self| matches!(s.memos.collapse_refused_at(k), Some(at) if at >= a.at);
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
            // The lowest energy floor under which a direction was refused by
            // the energy rule with the floor applied (a free vertex).
            let mut floor = f64::INFINITY;
            let ends = [(k.lo, k.hi), (k.hi, k.lo)];
            for ((u, v), direction) in ends.into_iter().zip(directions) {
                let (out, by_role, floored) = match direction {
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
                        let (out, by_role) =
                            try_collapse_planned(self.mesh, self.ctx, plan, verdict);
                        // (a refusal here, past the verdict, counts as floored)
                        (out, by_role, true)
                    }
                    CollapseDirection::Refused(r, by_role, floored) => {
                        tried = true;
                        (Outcome::Rejected(r), by_role, floored)
                    }
                    CollapseDirection::Unneeded => {
                        // (the first direction's decided collapse was applied
                        // and ended the loop; were it not, the edge is left
                        // as refused, never a panic)
                        debug_assert!(false, "the collapse decided first was not applied");
                        continue;
                    }
                };
                if matches!(out, Outcome::Rejected(Reject::Energy)) && floored {
                    floor = floor.min(self.ctx.energy_floor);
                }
                self.memos.touch(self.mesh, &out, true);
                if let Outcome::Rejected(reason) = out
                    && by_role
                {
                    self.memos.refuse_role(u, v, reason);
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
                self.memos.refuse_collapse(k, by_length, floor);
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
                    if len < factor * self.targets.edge_target(self.mesh, e) {
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
            at: self.memos.clock(),
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
        if !self.collapse_due(bits, k, factor) {
            return None;
        }
        Some(self.plan_both(k))
    }

    /// Tests: whether planning `k` now, its memo aside, refuses both
    /// directions (`None`: the round would not try it: an end is dead or the
    /// edge is not short).
    #[cfg(test)]
    pub(super) fn refused_on_replanning(&self, k: EdgeKey, factor: f64) -> Option<bool> {
        let alive = self.mesh.is_vertex_alive(k.lo) && self.mesh.is_vertex_alive(k.hi);
        if !alive
            || self.mesh.distance(k.lo, k.hi) >= factor * self.targets.edge_target(self.mesh, k)
        {
            return None;
        }
        Some(
            self.plan_both(k)
                .iter()
                .all(|d| !matches!(d, CollapseDirection::Plan(_))),
        )
    }

    /// [`Self::plan_directions`] of an edge the round tries.
    fn plan_both(&self, k: EdgeKey) -> [CollapseDirection; 2] {
        let mesh: &TriMesh = self.mesh;
        // The rings of both ends, each read once: `v`'s for its own
        // direction, `u`'s for the link condition (the ring of `v` in the
        // other direction).
        let mut rings: [Option<crate::mesh::ScratchRing>; 2] = [None, None];
        let mut direction = |u: VertexId, v: VertexId| {
            if let Some(reason) = self.memos.role_refusal(u, v) {
                return CollapseDirection::Remembered(reason);
            }
            // (what the plan's role rule says of a vertex fixed by its tag,
            // without reading its ring)
            if crate::ops::fixed_by_tag(mesh, v) {
                return CollapseDirection::Refused(Reject::FixedVertex, true, false);
            }
            let [ring_lo, ring_hi] = &mut rings;
            let (slot_v, slot_u) = if v == k.hi {
                (ring_hi, ring_lo)
            } else {
                (ring_lo, ring_hi)
            };
            let ring_v: &crate::mesh::VertexRing =
                slot_v.get_or_insert_with(|| crate::mesh::ScratchRing::of(mesh, v));
            // The length rule: against a uniform field it reads no field and
            // is asked first; else inside the plan, after the role and energy
            // rules, which refuse most collapses for less than its lookups.
            // (The same collapses are refused either way; only the reason
            // recorded differs.)
            let kept = |ring: &crate::mesh::VertexRing| {
                lengths_kept(mesh, &self.targets, self.stretch, u, ring)
            };
            let lookups = !self.targets.is_uniform();
            if !lookups && !kept(ring_v) {
                return CollapseDirection::Length;
            }
            let (plan, floored) = CollapsePlan::new_noting_floor(
                mesh,
                self.ctx,
                u,
                v,
                Some(ring_v),
                Some(slot_u),
                lookups.then_some(&kept as &dyn Fn(&crate::mesh::VertexRing) -> bool),
            );
            if let Err((Reject::EdgeLength, _)) = plan {
                return CollapseDirection::Length;
            }
            let verdict = plan.as_ref().ok().and_then(|p| p.verdict(mesh, self.ctx));
            // A refused plan is dropped here, in parallel, not on the
            // pipeline's thread (most plans are refused).
            match collapse_refusal(&plan, verdict) {
                Some((r, by_role)) => CollapseDirection::Refused(r, by_role, floored),
                None => CollapseDirection::Plan(Box::new((plan, verdict))),
            }
        };
        let first = direction(k.lo, k.hi);
        // (planning both directions of every edge would waste up to a fifth
        // of the plans: most collapses go the first way)
        if let CollapseDirection::Plan(planned) = &first
            && matches!(planned.1, Some(Ok(())))
        {
            return [first, CollapseDirection::Unneeded];
        }
        let second = direction(k.hi, k.lo);
        [first, second]
    }

    /// Whether the collapse round tries `k` (popped with `bits`) now: both
    /// ends alive, the length as queued and still short, no refusal of it
    /// remembered.
    fn collapse_due(&self, bits: u64, k: EdgeKey, factor: f64) -> bool {
        if !(self.mesh.is_vertex_alive(k.lo) && self.mesh.is_vertex_alive(k.hi)) {
            return false;
        }
        let len = self.mesh.distance(k.lo, k.hi);
        if len.to_bits() != bits || len >= factor * self.targets.edge_target(self.mesh, k) {
            return false;
        }

        !self.memos.collapse_refused(k)
    }
}
