//! The vertex passes: smoothing (the sum or the largest of the one-ring
//! energies) in a fixed pseudo-random order, the rounding of rational vertices
//! and the projection of off-curve primary vertices toward their curve.

use super::Schedule;
use super::queue::PlanAhead;
use super::scope::Scope;
use crate::mesh::{FeatureOn, TriMesh, VertexId};
use crate::ops::invariants::on_curve;
use crate::ops::{
    Context, Objective, Outcome, Reject, SmoothPlan, try_project, try_round, try_smooth_planned,
};
use rayon::prelude::*;
use rustc_hash::FxHashSet;

/// A smoothing planned ahead at clock `at`: it stands while the vertex's stamp
/// has not passed `at`.
struct SmoothAhead {
    at: u64,
    plan: Result<SmoothPlan, Reject>,
    /// [`SmoothPlan::verdict`].
    verdict: Option<Result<(), Reject>>,
}

impl<D: Sync> Schedule<'_, D> {
    /// Smooth every vertex of `scope` that may move, in a fixed pseudo-random
    /// order.
    pub(super) fn smooth_pass(&mut self, scope: &Scope) -> u64 {
        self.smooth_pass_with(scope, Objective::Sum)
    }

    /// [`Self::smooth_pass`] minimising `objective`.
    pub(super) fn smooth_pass_with(&mut self, scope: &Scope, objective: Objective) -> u64 {
        let mut verts: Vec<VertexId> = self
            .mesh
            .vertices()
            .filter(|&v| scope.contains(v))
            .collect();
        self.rng.shuffle(&mut verts);
        self.queued(verts.len());
        let mut applied = 0;
        // As in the collapse round: with more than one thread the next
        // `PLAN_AHEAD` moves are planned at once in parallel, and a plan is
        // used only while its vertex is unchanged since.
        let mut ahead = PlanAhead::new();
        for (n, &v) in verts.iter().enumerate() {
            if self.out_of_time_at(n) {
                break;
            }
            if self.memos.smooth_refused(v) {
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
            self.memos.touch(self.mesh, &out, false);
            self.memos.smoothed(v, out.is_applied());
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

    /// Plan the smoothing of `v` ahead, on the mesh as it is: `None` where the
    /// pass would skip it (its refusal is remembered).
    fn plan_smooth(&self, v: VertexId, objective: Objective) -> Option<SmoothAhead> {
        if self.memos.smooth_refused(v) {
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
            at: self.memos.clock(),
            plan,
            verdict,
        })
    }

    /// Round every rational vertex that can be; returns how many stay rational.
    pub(super) fn round_all(&mut self) -> usize {
        let rational: Vec<VertexId> = self
            .mesh
            .vertices()
            .filter(|&v| self.mesh.is_rational(v))
            .collect();
        let mut left = 0;
        let count = rational.len();
        self.queued(count);
        for (n, v) in rational.into_iter().enumerate() {
            if self.out_of_time_at(n) {
                return left + count - n;
            }
            let out = try_round(self.mesh, self.ctx, v);
            self.memos.touch(self.mesh, &out, false);
            if !self.stats.round.record(&out) {
                left += 1;
            }
        }
        left
    }

    /// Move off-curve primary vertices toward their curve; returns how many stay off.
    pub(super) fn project_all(&mut self, ever_off: &mut FxHashSet<VertexId>) -> usize {
        let off = off_curve_vertices(self.mesh, self.ctx);
        let mut left = 0;
        let count = off.len();
        self.queued(count);
        for (n, v) in off.into_iter().enumerate() {
            if self.out_of_time_at(n) {
                return left + count - n;
            }
            ever_off.insert(v);
            let out = try_project(self.mesh, self.ctx, v);
            self.memos.touch(self.mesh, &out, false);
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
