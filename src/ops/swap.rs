//! Edge swap: the diagonal `a b` of the quadrilateral of its two triangles is
//! replaced by the other diagonal `c d`. Never on a feature edge (§4.4.1
//! "Feature Handling" 3) nor on the mesh boundary.
//!
//! Reroute: the same change of triangles on a *secondary* feature edge `a b`
//! whose opposite vertex `k` (`c` or `d`, the nearer) lies within ε of it. The
//! feature then runs `a → k → b`: it is the split of `a b` at the foot of `k`
//! followed by the collapse of that new vertex into `k`, in one step. It is
//! what removes a sliver between two nearly coincident secondary features
//! (three feature edges, none of which may be swapped and whose vertices are
//! more than ε apart). `a`, `b` and `k` stay where they are; the envelope test
//! decides on `a k` and `k b` as for any operation.

use super::invariants::{self, Check};
use super::{Context, LocalChange, Outcome, Reject, corner_energy, max_energy};
use crate::mesh::{
    EdgeQuad, FaceId, FeatureOn, Transaction, TriMesh, VertexId, point_segment_distance,
};
use kurbo::Line;

/// Everything a swap needs, gathered from `&TriMesh`.
#[derive(Clone, Debug)]
pub(crate) struct SwapPlan {
    faces: [FaceId; 2],
    new: [[VertexId; 3]; 2],
    c: VertexId,
    d: VertexId,
    old_max_energy: f64,
    old_corner_energy: Option<f64>,
}

impl SwapPlan {
    /// Plan the swap of the edge `a b`.
    ///
    /// # Errors
    /// [`Reject::NotAnEdge`], [`Reject::Boundary`], [`Reject::FeatureRule`] (a
    /// tagged edge), [`Reject::Topology`] (`c d` is already an edge).
    pub(crate) fn new(
        mesh: &TriMesh,
        ctx: &Context,
        a: VertexId,
        b: VertexId,
    ) -> Result<Self, Reject> {
        let q = quad(mesh, a, b)?;
        if !mesh.edge_tags(a, b).is_empty() {
            return Err(Reject::FeatureRule);
        }
        other_diagonal_free(mesh, &q)?;
        let EdgeQuad {
            faces: [f, g],
            a,
            b,
            c,
            d,
        } = q;
        Ok(SwapPlan {
            faces: [f, g],
            new: [[a, d, c], [d, b, c]],
            c,
            d,
            old_max_energy: max_energy(mesh, ctx, &[f, g]),
            old_corner_energy: corner_energy(mesh, ctx, &[f, g]),
        })
    }
}

/// The quadrilateral around the interior edge `a b`, or why there is none:
/// [`Reject::NotAnEdge`], [`Reject::Boundary`], [`Reject::Topology`] (more
/// than two faces).
fn quad(mesh: &TriMesh, a: VertexId, b: VertexId) -> Result<EdgeQuad, Reject> {
    if a == b || !mesh.is_vertex_alive(a) || !mesh.is_vertex_alive(b) {
        return Err(Reject::NotAnEdge);
    }
    let mut faces = Vec::new();
    mesh.faces_on_edge(a, b, &mut faces);
    let q = match faces[..] {
        [] => return Err(Reject::NotAnEdge),
        [_] => return Err(Reject::Boundary),
        [f, g] => mesh.quad([f, g], a, b).expect("internal: edge of f"),
        _ => return Err(Reject::Topology),
    };
    Ok(q)
}

/// [`Reject::Topology`] when the other diagonal `c d` of `q` is already an edge.
fn other_diagonal_free(mesh: &TriMesh, q: &EdgeQuad) -> Result<(), Reject> {
    if q.c == q.d || mesh.has_edge(q.c, q.d) {
        return Err(Reject::Topology);
    }
    Ok(())
}

/// Swap the edge `a b` (see the module doc).
pub(crate) fn try_swap(mesh: &mut TriMesh, ctx: &Context, a: VertexId, b: VertexId) -> Outcome {
    try_swap_planned(mesh, ctx, SwapPlan::new(mesh, ctx, a, b), None)
}

/// The rest of [`try_swap`] once its plan is made on the mesh as it is now;
/// with `verdict` ([`SwapPlan::verdict`]), the swap is refused or committed
/// as it says, without checking the invariants again.
pub(crate) fn try_swap_planned(
    mesh: &mut TriMesh,
    ctx: &Context,
    planned: Result<SwapPlan, Reject>,
    verdict: Option<Result<(), Reject>>,
) -> Outcome {
    let plan = match planned {
        Ok(p) => p,
        Err(r) => return Outcome::Rejected(r),
    };
    if let Some(Err(r)) = verdict {
        return Outcome::Rejected(r);
    }
    let mut tx = Transaction::decided_if(mesh, verdict.is_some());
    let created = tx.replace_faces(&plan.faces, &plan.new);
    validate_and_commit(tx, ctx, &plan, created, verdict.is_some())
}

impl SwapPlan {
    /// The two vertices of the new diagonal.
    pub(crate) fn diagonal(&self) -> [VertexId; 2] {
        [self.c, self.d]
    }

    /// What the swap's invariants would decide, on the mesh as it is, without
    /// the tentative change, in linear mode (`None` in curved mode), with the
    /// tags `moved` added to the new faces' edges (a reroute's): the exact
    /// orientation of the new faces, the curvature and the envelope of their
    /// feature edges, the energy rule, in the order of
    /// [`invariants::validate`]. The schedule decides these ahead, in
    /// parallel.
    pub(crate) fn verdict(
        &self,
        mesh: &TriMesh,
        ctx: &Context,
        moved: &[(VertexId, VertexId, FeatureOn)],
    ) -> Option<Result<(), Reject>> {
        if ctx.curved.is_some() {
            return None;
        }
        let ccw = self.new.iter().all(|t| {
            mesh.orientation_of(t[0], t[1], t[2]) == crate::exact::Orientation::CounterClockwise
        });
        if !ccw {
            return Some(Err(Reject::Inversion));
        }
        // Every edge of the new faces has c or d as an end.
        let edges = invariants::tags_after(mesh, &self.new, |_, _| true, moved);
        if let Err(r) = invariants::feature_edges_hold(ctx, &edges, |x| mesh.position(x)) {
            return Some(Err(r));
        }
        if ctx.energy == super::EnergyRule::NoWorseMax
            && super::max_energy_of(mesh, ctx, self.new) > self.old_max_energy
        {
            return Some(Err(Reject::Energy));
        }
        Some(Ok(()))
    }
}

/// The invariants on the faces a swap (or reroute) created in `tx`, then commit,
/// or roll back by dropping `tx`.
fn validate_and_commit(
    tx: Transaction<'_>,
    ctx: &Context,
    plan: &SwapPlan,
    created: Vec<FaceId>,
    decided: bool,
) -> Outcome {
    let check = Check {
        faces: &created,
        changed: &[plan.c, plan.d],
        budgets: &[],
        old_max_energy: Some(plan.old_max_energy),
        old_corner_energy: plan.old_corner_energy,
    };
    if decided {
        debug_assert!(
            invariants::validate(&tx, ctx, &check).is_ok(),
            "a swap decided ahead fails the invariants"
        );
    } else if let Err(r) = invariants::validate(&tx, ctx, &check) {
        return Outcome::Rejected(r);
    }
    tx.commit();
    Outcome::Applied(LocalChange {
        created,
        ..LocalChange::default()
    })
}

/// Everything a reroute needs, gathered from `&TriMesh`.
#[derive(Clone, Debug)]
pub(crate) struct ReroutePlan {
    swap: SwapPlan,
    a: VertexId,
    b: VertexId,
    /// The vertex the feature is rerouted through (`c` or `d`).
    k: VertexId,
    tags: Vec<FeatureOn>,
}

impl ReroutePlan {
    /// Plan the reroute of the secondary edge `a b` (see the module doc).
    ///
    /// # Errors
    /// [`Reject::NotAnEdge`], [`Reject::Boundary`], [`Reject::FeatureRule`] (not
    /// a secondary edge, a primary tag on it, or neither opposite vertex within
    /// ε of it), [`Reject::Topology`] (`c d` is already an edge).
    pub(crate) fn new(
        mesh: &TriMesh,
        ctx: &Context,
        a: VertexId,
        b: VertexId,
    ) -> Result<Self, Reject> {
        let q = quad(mesh, a, b)?;
        let tags = mesh.edge_tags(a, b);
        if tags.is_empty()
            || tags
                .iter()
                .any(|t| !matches!(t, FeatureOn::Secondary { .. }))
        {
            return Err(Reject::FeatureRule);
        }
        let tags = tags.to_vec();
        other_diagonal_free(mesh, &q)?;
        let EdgeQuad {
            faces: [f, g],
            a,
            b,
            c,
            d,
        } = q;
        let ab = Line::new(mesh.position(a), mesh.position(b));
        let (hc, hd) = (
            point_segment_distance(mesh.position(c), ab),
            point_segment_distance(mesh.position(d), ab),
        );
        let (k, h) = if hc <= hd { (c, hc) } else { (d, hd) };
        if h.is_nan() || h > ctx.envelope.eps() {
            return Err(Reject::FeatureRule);
        }
        Ok(ReroutePlan {
            swap: SwapPlan {
                faces: [f, g],
                new: [[a, d, c], [d, b, c]],
                c,
                d,
                old_max_energy: max_energy(mesh, ctx, &[f, g]),
                old_corner_energy: corner_energy(mesh, ctx, &[f, g]),
            },
            a,
            b,
            k,
            tags,
        })
    }
}

/// Reroute the secondary edge `a b` through the nearer opposite vertex (see the
/// module doc), as a tentative change checked by the invariants. The schedule
/// decides reroutes by [`ReroutePlan::verdict`] instead; the tests compare the
/// two.
#[cfg(test)]
pub(crate) fn try_reroute(mesh: &mut TriMesh, ctx: &Context, a: VertexId, b: VertexId) -> Outcome {
    try_reroute_planned(mesh, ctx, ReroutePlan::new(mesh, ctx, a, b), None)
}

impl ReroutePlan {
    /// The swap under the reroute.
    pub(crate) fn swap(&self) -> &SwapPlan {
        &self.swap
    }

    /// [`SwapPlan::verdict`] with the tags that move to `a k` and `k b`.
    pub(crate) fn verdict(&self, mesh: &TriMesh, ctx: &Context) -> Option<Result<(), Reject>> {
        let moved: Vec<(VertexId, VertexId, FeatureOn)> = self
            .tags
            .iter()
            .flat_map(|&tag| [(self.a, self.k, tag), (self.k, self.b, tag)])
            .collect();
        self.swap.verdict(mesh, ctx, &moved)
    }
}

/// The rest of `try_reroute` once its plan is made on the mesh as it is
/// now; with `verdict` ([`ReroutePlan::verdict`]), the reroute is refused or
/// committed as it says, without checking the invariants again.
pub(crate) fn try_reroute_planned(
    mesh: &mut TriMesh,
    ctx: &Context,
    planned: Result<ReroutePlan, Reject>,
    verdict: Option<Result<(), Reject>>,
) -> Outcome {
    let plan = match planned {
        Ok(p) => p,
        Err(r) => return Outcome::Rejected(r),
    };
    if let Some(Err(r)) = verdict {
        return Outcome::Rejected(r);
    }
    let mut tx = Transaction::decided_if(mesh, verdict.is_some());
    let created = tx.replace_faces(&plan.swap.faces, &plan.swap.new);
    tx.take_edge_tags(plan.a, plan.b);
    for &tag in &plan.tags {
        for (x, y) in [(plan.a, plan.k), (plan.k, plan.b)] {
            if !tx.edge_tags(x, y).contains(&tag) {
                tx.add_edge_tag(x, y, tag);
            }
        }
    }
    validate_and_commit(tx, ctx, &plan.swap, created, verdict.is_some())
}
