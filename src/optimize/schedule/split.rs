//! The split pass: every edge longer than 4/3 of its target once, longest
//! first; the new vertex gets the field at it, refined as its edge's ends were.

use super::queue::PlanAhead;
use super::scope::Scope;
use super::{LinearOptions, SPLIT_ABOVE, Schedule};
use crate::mesh::{EdgeKey, VertexId};
use crate::ops::{Outcome, SplitPlan, try_split, try_split_bounded, try_split_planned};
use rayon::prelude::*;

impl Schedule<'_, LinearOptions> {
    /// Split every edge of `scope` longer than 4/3 of its mean target once,
    /// longest first; the new vertices join the scope. Returns the number of
    /// candidates and of splits applied.
    pub(super) fn split_pass(&mut self, scope: &mut Scope) -> (usize, u64) {
        if !scope.bounded_splits() {
            // the budget's mark says whether the last sizing pass was cut
            // short (a pass cut early whose mesh then lost vertices to
            // collapses does the rest later)
            self.stats.vertex_budget_reached = false;
        }
        let edges: Vec<EdgeKey> = scope.edges(self.mesh);
        let scope_now: &Scope = scope;
        let mut cands: Vec<(f64, EdgeKey, f64)> = edges
            .into_par_iter()
            .filter_map(|k| {
                let len = self.mesh.distance(k.lo, k.hi);
                let t = self.targets.edge_target(self.mesh, k);
                (len > SPLIT_ABOVE * t && scope_now.touches(k.lo, k.hi)).then_some((len, k, t))
            })
            .collect();
        cands.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let n = cands.len();
        self.queued(n);
        let mut applied = 0;
        // As in the collapse round: with more than one thread the next
        // `PLAN_AHEAD` splits are planned at once in parallel (the plan reads
        // the faces and tags of the edge), and a plan is used only while
        // neither end has changed since.
        let mut ahead = PlanAhead::new();
        for (i, &(_, k, t)) in cands.iter().enumerate() {
            if self.out_of_time_at(i) {
                break;
            }
            if self.mesh.num_vertices() >= self.driver.max_vertices {
                self.stats.vertex_budget_reached = true;
                break;
            }
            let this = &*self;
            let planned = ahead
                .take(i, &cands, |&(_, e, _)| {
                    Some((
                        this.memos.clock(),
                        SplitPlan::new(this.mesh, this.ctx, e.lo, e.hi),
                    ))
                })
                .filter(|(at, _)| self.fresh(*at, &[k.lo, k.hi]));
            let out = if scope.bounded_splits() {
                // the worst-element phase: no split makes its edge's faces worse
                // than they were or than a corner of α allows
                let bound = self.split_bound(k.lo, k.hi);
                try_split_bounded(self.mesh, self.ctx, k.lo, k.hi, Some(bound))
            } else {
                match planned {
                    Some((_, plan)) => try_split_planned(self.mesh, self.ctx, plan),
                    None => try_split(self.mesh, self.ctx, k.lo, k.hi),
                }
            };
            self.memos.touch(self.mesh, &out, true);
            if let Outcome::Applied(ch) = &out {
                if let Some(m) = ch.new_vertex {
                    let targets = &mut self.targets;
                    if targets.is_uniform() {
                        targets.set_target(m, t);
                    } else {
                        // the field at the new vertex, refined as its edge's ends were
                        let ratio = |v: VertexId| targets.target_of(v) / targets.base_of(v);
                        let r = 0.5 * (ratio(k.lo) + ratio(k.hi));
                        let h = targets.field_at(self.mesh.position(m));
                        targets.set_base(m, h);
                        targets.set_target(m, h * r);
                    }
                    let refined = targets.is_refined(k.lo) || targets.is_refined(k.hi);
                    targets.set_refined(m, refined);
                    scope.insert(m);
                }
                applied += 1;
            }
            self.stats.split.record(&out);
        }
        (n, applied)
    }
}
