//! Edge collapse: the vertex `v` of the edge `u v` is removed and its
//! triangles are re-attached to `u`, which does not move.
//!
//! Feature rules (§4.4.1 "Feature Handling" 2): `v` may not be a fixed vertex
//! (feature endpoint, box corner, junction); a primary `v` slides along its own
//! curve only, so `u v` must be an edge of `v`'s section, and the merged edge
//! gets `u`'s parameter; the features on `v`'s other edges move to `u` and are
//! then checked (envelope, curvature). A boundary `v` collapses only along a
//! boundary edge where the boundary is exactly straight. The link condition
//! keeps the mesh a manifold.
//!
//! In curved mode a feature that moves from `v w` to `u w` also reshapes the
//! face on the other side of `u w` (outside `v`'s star): that face is checked,
//! and weighed by the energy rule, with the created ones.

use super::invariants::{self, Check};
use super::{
    Context, CurvedRule, EnergyRule, LocalChange, Outcome, Reject, Role, corner_energy, max_energy,
    max_energy_of, role, t_at,
};
use crate::exact::Orientation;
use crate::mesh::{
    EdgeKey, FaceId, FeatureOn, ScratchRing, Transaction, TriMesh, VertexId, VertexRing,
};

/// Everything a collapse of `v` into `u` needs, gathered from `&TriMesh`.
#[derive(Clone, Debug)]
pub(crate) struct CollapsePlan {
    u: VertexId,
    v: VertexId,
    /// Faces around `v` (all removed).
    star: Vec<FaceId>,
    /// The new faces: those of `star` without `u`, `v` replaced by `u`.
    new: Vec<[VertexId; 3]>,
    /// Tags to add on `(u, w)` for each former edge `(v, w)`.
    retag: Vec<(VertexId, VertexId, FeatureOn)>,
    /// Vertices `w` whose edge `(v, w)` has tags to drop.
    drop_tags: Vec<VertexId>,
    /// Curved mode: faces outside the star whose edge `u w` gets a primary tag.
    reshaped: Vec<FaceId>,
    old_max_energy: f64,
    old_corner_energy: Option<f64>,
}

/// The refusal of collapsing `v` into `u` that depends on the vertex tags and
/// the feature tags of v's edges alone (never on a position): `v` fixed, or
/// on a primary section that the edge `u v` does not follow. Nothing but an
/// operation that changes the faces around `v` can lift it.
fn role_refusal(mesh: &TriMesh, u: VertexId, v: VertexId, role_v: Role) -> Option<Reject> {
    match role_v {
        Role::Fixed => Some(Reject::FixedVertex),
        Role::Primary { section, .. } => {
            let on_section = mesh
                .edge_tags(u, v)
                .iter()
                .any(|t| matches!(*t, FeatureOn::Primary { section: s, .. } if s == section));
            (!on_section).then_some(Reject::FeatureRule)
        }
        _ => None,
    }
}

impl CollapsePlan {
    /// Plan the collapse of `v` into `u`.
    ///
    /// # Errors
    /// The rule that forbids it: [`Reject::NotAnEdge`], [`Reject::FixedVertex`],
    /// [`Reject::Boundary`], [`Reject::FeatureRule`], [`Reject::Topology`],
    /// [`Reject::Energy`] (linear mode), with whether the role rules alone
    /// refused it.
    /// `ctx.envelope.eps()` bounds how far a secondary junction may move.
    pub(crate) fn new(
        mesh: &TriMesh,
        ctx: &Context,
        u: VertexId,
        v: VertexId,
        ring_v: Option<&VertexRing>,
    ) -> Result<Self, (Reject, bool)> {
        Self::new_noting_floor(mesh, ctx, u, v, ring_v, None, None).0
    }

    /// [`Self::new`], and whether the context's energy floor applied to its
    /// energy rule (`v` has no feature: [`Role::Free`]); `false` when the
    /// plan stopped before the rule. An energy refusal without the floor
    /// (here or in [`Self::verdict`]) depends on positions alone: it stands
    /// under any floor, where one with the floor stands under a lower floor
    /// only. `ring_u`: a slot for `u`'s ring, filled when the plan reads
    /// it (unless the caller had filled it). `lengths`: the caller's length
    /// rule on v's ring, asked after the role rules and the linear energy
    /// rule (which refuse most collapses, and cost less than the size
    /// field's lookups a length rule makes) and before the rest; its
    /// refusal is [`Reject::EdgeLength`].
    pub(crate) fn new_noting_floor(
        mesh: &TriMesh,
        ctx: &Context,
        u: VertexId,
        v: VertexId,
        ring_v: Option<&VertexRing>,
        ring_u: Option<&mut Option<ScratchRing>>,
        lengths: Option<&dyn Fn(&VertexRing) -> bool>,
    ) -> (Result<Self, (Reject, bool)>, bool) {
        let mut floored = false;
        let plan = Self::plan(mesh, ctx, u, v, (ring_v, ring_u), lengths, &mut floored);
        (plan, floored)
    }

    /// [`Self::new_noting_floor`], the floor's use into `floored`.
    fn plan(
        mesh: &TriMesh,
        ctx: &Context,
        u: VertexId,
        v: VertexId,
        (ring_v, ring_u): (Option<&VertexRing>, Option<&mut Option<ScratchRing>>),
        lengths: Option<&dyn Fn(&VertexRing) -> bool>,
        floored: &mut bool,
    ) -> Result<Self, (Reject, bool)> {
        let eps = ctx.envelope.eps();
        if u == v || !mesh.is_vertex_alive(u) || !mesh.is_vertex_alive(v) {
            return Err((Reject::NotAnEdge, false));
        }
        let scratch;
        let rv: &VertexRing = match ring_v {
            Some(r) => {
                debug_assert!(r.vertex == v, "the ring given is v's");
                r
            }
            None => {
                scratch = crate::mesh::ScratchRing::of(mesh, v);
                &scratch
            }
        };
        if !rv.neighbours.contains(&u) {
            return Err((Reject::NotAnEdge, false));
        }
        // The role rules first: they need v's ring only, and they refuse most of
        // the collapses the schedule tries.
        let role_v = role(mesh, v, rv);
        if let Some(r) = role_refusal(mesh, u, v, role_v) {
            return Err((r, true));
        }
        // A vertex without features may go where its faces get as bad as the
        // context's floor; near features the plain rule keeps their
        // neighbourhood (and the secondary geometry) as it is.
        *floored = role_v == Role::Free;
        let floor = if *floored { ctx.energy_floor } else { 0.0 };
        // Linear mode: the energy rule needs v's ring and positions only (u
        // does not move), so it refuses here, before u's ring, the link
        // condition and the tags, what it would refuse anyway: most refused
        // collapses stop here. An infinite energy (inverted or degenerate in
        // f64) is left to the exact inversion test. Curved energies depend on
        // the moved tags (and reshape faces outside the star): left to the
        // invariants.
        let linear_max = if ctx.curved.is_none() {
            let old = max_energy(mesh, ctx, &rv.faces).max(floor);
            if ctx.energy == EnergyRule::NoWorseMax {
                let new_max = max_energy_of(
                    mesh,
                    ctx,
                    rv.faces
                        .iter()
                        .map(|&f| mesh.face(f))
                        .filter(|t| !t.contains(&u))
                        .map(|t| t.map(|x| if x == v { u } else { x })),
                );
                if new_max.is_finite() && new_max > old {
                    return Err((Reject::Energy, false));
                }
            }
            Some(old)
        } else {
            None
        };
        if lengths.is_some_and(|kept| !kept(rv)) {
            return Err((Reject::EdgeLength, false));
        }
        let mut own = None;
        let ru: &VertexRing = ring_u
            .unwrap_or(&mut own)
            .get_or_insert_with(|| ScratchRing::of(mesh, u));
        debug_assert!(ru.vertex == u, "the ring given is u's");
        // The faces on the edge, from v's ring (as `faces_on_edge` finds them).
        let edge_faces: Vec<FaceId> = rv
            .faces
            .iter()
            .copied()
            .filter(|&f| mesh.face(f).contains(&u))
            .collect();
        let opposite: Vec<VertexId> = edge_faces
            .iter()
            .map(|&f| mesh.opposite(f, u, v).expect("internal: third vertex"))
            .collect();
        let boundary_edge = edge_faces.len() == 1;
        match role_v {
            // A fixed vertex, and a primary one off the edge's section, were
            // refused above (`role_refusal`); free and secondary vertices go.
            Role::Fixed | Role::Primary { .. } | Role::Free | Role::Secondary => {}
            Role::Boundary => {
                if !boundary_edge {
                    return Err((Reject::Boundary, false));
                }
                // v's other boundary neighbour must be on the line u v.
                let others: Vec<VertexId> = rv
                    .neighbours
                    .iter()
                    .copied()
                    .filter(|&w| w != u && mesh.is_boundary_edge(rv, w))
                    .collect();
                let [w] = others[..] else {
                    return Err((Reject::Boundary, false));
                };
                if mesh.orientation_of(u, v, w) != Orientation::Collinear {
                    return Err((Reject::Boundary, false));
                }
            }
            Role::SecondaryJunction => {
                // The features' ends and crossings move by at most ε, so the
                // input stays within ε of the mesh there too.
                if mesh.distance(u, v) > eps {
                    return Err((Reject::FeatureRule, false));
                }
            }
        }
        // Link condition: the common neighbours are exactly the opposite vertices,
        // and two boundary vertices are joined only by a boundary edge.
        let common = rv
            .neighbours
            .iter()
            .filter(|w| ru.neighbours.contains(w))
            .count();
        if common != opposite.len() || opposite.iter().any(|w| !ru.neighbours.contains(w)) {
            return Err((Reject::Topology, false));
        }
        if rv.boundary && ru.boundary && !boundary_edge {
            return Err((Reject::Topology, false));
        }
        let new: Vec<[VertexId; 3]> = rv
            .faces
            .iter()
            .filter(|f| !edge_faces.contains(f))
            .map(|&f| mesh.face(f).map(|x| if x == v { u } else { x }))
            .collect();
        if new.is_empty() {
            return Err((Reject::Topology, false));
        }
        // Features on v's edges move to u.
        let key_uv = EdgeKey::new(u, v);
        let t_u_on = |section: u32| {
            mesh.edge_tags(u, v).iter().find_map(|t| match *t {
                FeatureOn::Primary { section: s, t } if s == section => Some(t_at(key_uv, t, u)),
                _ => None,
            })
        };
        let mut retag = Vec::new();
        let mut drop_tags = vec![u];
        for &w in &rv.neighbours {
            if w == u || mesh.edge_tags(v, w).is_empty() {
                continue;
            }
            drop_tags.push(w);
            let key = EdgeKey::new(v, w);
            for tag in mesh.edge_tags(v, w) {
                match *tag {
                    FeatureOn::Primary { section, t } => {
                        let Some(tu) = t_u_on(section) else {
                            return Err((Reject::FeatureRule, false));
                        };
                        retag.push((
                            u,
                            w,
                            FeatureOn::Primary {
                                section,
                                t: [tu, t_at(key, t, w)],
                            },
                        ));
                    }
                    sec @ FeatureOn::Secondary { .. } => retag.push((u, w, sec)),
                }
            }
        }
        let mut reshaped = Vec::new();
        if ctx.curved.is_some() {
            let mut on_edge = Vec::new();
            for &(a, w, tag) in &retag {
                if !matches!(tag, FeatureOn::Primary { .. }) {
                    continue;
                }
                mesh.faces_on_edge(a, w, &mut on_edge);
                for &f in &on_edge {
                    if !rv.faces.contains(&f) && !reshaped.contains(&f) {
                        reshaped.push(f);
                    }
                }
            }
        }
        let (old_max_energy, old_corner_energy) = match linear_max {
            Some(old) => (old, None),
            None => {
                let old: Vec<FaceId> = rv.faces.iter().chain(&reshaped).copied().collect();
                (
                    max_energy(mesh, ctx, &old).max(floor),
                    corner_energy(mesh, ctx, &old),
                )
            }
        };
        Ok(CollapsePlan {
            u,
            v,
            old_max_energy,
            old_corner_energy,
            reshaped,
            star: rv.faces.clone(),
            new,
            retag,
            drop_tags,
        })
    }
}

impl CollapsePlan {
    /// What [`apply`] would decide on this plan, decided on the mesh as it is,
    /// without the tentative change: the exact orientation of the new faces,
    /// then the curvature and the envelope of the feature edges at `u` with
    /// the tags they would have, then the energy rule, in the order of
    /// [`invariants::validate`] (so the same refusal); in curved mode
    /// [`Self::curved_verdict`]. The schedule decides these ahead, in
    /// parallel, with the plan.
    pub(crate) fn verdict(&self, mesh: &TriMesh, ctx: &Context) -> Option<Result<(), Reject>> {
        let u = self.u;
        let ccw = self
            .new
            .iter()
            .all(|t| mesh.orientation_of(t[0], t[1], t[2]) == Orientation::CounterClockwise);
        if !ccw {
            return Some(Err(Reject::Inversion));
        }
        if let Some(rule) = ctx.curved {
            return Some(self.curved_verdict(mesh, ctx, &rule));
        }
        // The edges at u of the new faces, with the tags they would have: the
        // ones they have, then those moved from v's edges.
        let edges = invariants::tags_after(mesh, &self.new, |a, b| a == u || b == u, &self.retag);
        if let Err(r) = invariants::feature_edges_hold(ctx, &edges, |x| mesh.position(x)) {
            return Some(Err(r));
        }
        if ctx.energy == EnergyRule::NoWorseMax
            && max_energy_of(mesh, ctx, self.new.iter().copied()) > self.old_max_energy
        {
            return Some(Err(Reject::Energy));
        }
        Some(Ok(()))
    }

    /// [`Self::verdict`] in curved mode, once the new faces are known to be
    /// counter-clockwise (the reshaped ones keep their corners): the rules of
    /// [`invariants::validate`] after the inversion, in its order, on the new
    /// and the reshaped faces with the tags they would have: the turn of the
    /// primary pieces at `u`, the curved elements (energy first), the corner
    /// rule, the envelope.
    fn curved_verdict(
        &self,
        mesh: &TriMesh,
        ctx: &Context,
        rule: &CurvedRule,
    ) -> Result<(), Reject> {
        let u = self.u;
        let faces: Vec<[VertexId; 3]> = self
            .new
            .iter()
            .copied()
            .chain(self.reshaped.iter().map(|&f| mesh.face(f)))
            .collect();
        let edges = invariants::tags_after(mesh, &faces, |a, b| a == u || b == u, &self.retag);
        invariants::curvature_holds(ctx, &edges)?;
        // An edge at u takes the tags it would have; every other edge of the
        // faces keeps its own.
        let primary_of = |k: EdgeKey| match edges.iter().find(|(e, _)| *e == k) {
            Some((_, tags)) => tags.iter().find_map(|t| match *t {
                FeatureOn::Primary { section, t } => Some((section, t)),
                FeatureOn::Secondary { .. } => None,
            }),
            None if k.lo == u || k.hi == u => None,
            None => invariants::curved::primary(mesh, k),
        };
        // Without the energy rule only validity counts (an infinite bound
        // refuses nothing by energy).
        let bound = if ctx.energy == EnergyRule::NoWorseMax {
            self.old_max_energy
        } else {
            f64::INFINITY
        };
        invariants::curved::holds_within_after(mesh, ctx, rule, &faces, bound, &primary_of)?;
        if let (EnergyRule::NoWorseMax, Some(old)) = (ctx.energy, self.old_corner_energy) {
            let corner = super::max_corner_energy_of(mesh, faces.iter().copied());
            if corner > old.max(rule.corner_floor) {
                return Err(Reject::Energy);
            }
        }
        invariants::envelope_holds(ctx, &edges, |x| mesh.position(x))
    }
}

/// Collapse `v` into `u` (see the module doc).
pub(crate) fn try_collapse(mesh: &mut TriMesh, ctx: &Context, u: VertexId, v: VertexId) -> Outcome {
    try_collapse_noting_role(mesh, ctx, u, v, None).0
}

/// [`try_collapse`] (with `v`'s ring when the caller has it: [`TriMesh::vertex_ring`]
/// of the mesh as it is), and whether the refusal (if any) came from the role rules
/// alone (`role_refusal`: they depend on the tags around `v`, never on a
/// position): the caller may remember it until the faces around `v` change.
pub(crate) fn try_collapse_noting_role(
    mesh: &mut TriMesh,
    ctx: &Context,
    u: VertexId,
    v: VertexId,
    ring_v: Option<&VertexRing>,
) -> (Outcome, bool) {
    let plan = match CollapsePlan::new(mesh, ctx, u, v, ring_v) {
        Ok(p) => p,
        Err((r, by_role)) => return (Outcome::Rejected(r), by_role),
    };
    (apply(mesh, ctx, plan), false)
}

/// The rest of [`try_collapse_noting_role`] once its plan is made: `planned` is
/// [`CollapsePlan::new`] of the mesh as it is now (the schedule plans ahead,
/// in parallel, and hands the plan over while the faces around both ends are
/// unchanged), so the outcome is the one `try_collapse_noting_role` gives.
///
/// With `verdict` ([`CollapsePlan::verdict`] of the mesh as it is), the
/// collapse is refused or committed as it says, without checking the
/// invariants again.
pub(crate) fn try_collapse_planned(
    mesh: &mut TriMesh,
    ctx: &Context,
    planned: Result<CollapsePlan, (Reject, bool)>,
    verdict: Option<Result<(), Reject>>,
) -> (Outcome, bool) {
    if let Some((r, by_role)) = refusal(&planned, verdict) {
        return (Outcome::Rejected(r), by_role);
    }
    match (planned, verdict) {
        (Ok(plan), Some(Ok(()))) => (apply_decided(mesh, ctx, plan, true), false),
        (Ok(plan), _) => (apply(mesh, ctx, plan), false),
        (Err(_), _) => unreachable!("a failed plan is a refusal"),
    }
}

/// The refusal [`try_collapse_planned`] returns for a plan and its verdict
/// without touching the mesh (with whether the role rules refused), if it
/// refuses: the schedule keeps only this of a plan refused ahead, and drops
/// the plan where it was made.
pub(crate) fn refusal(
    planned: &Result<CollapsePlan, (Reject, bool)>,
    verdict: Option<Result<(), Reject>>,
) -> Option<(Reject, bool)> {
    match (planned, verdict) {
        (Err((r, by_role)), _) => Some((*r, *by_role)),
        (Ok(_), Some(Err(r))) => Some((r, false)),
        (Ok(_), _) => None,
    }
}

/// The tentative change of `plan`, its invariants, then commit or roll back.
fn apply(mesh: &mut TriMesh, ctx: &Context, plan: CollapsePlan) -> Outcome {
    apply_decided(mesh, ctx, plan, false)
}

/// [`apply`]; with `decided` (the invariants hold by [`CollapsePlan::verdict`])
/// the change is committed without checking them again (debug builds do).
fn apply_decided(mesh: &mut TriMesh, ctx: &Context, plan: CollapsePlan, decided: bool) -> Outcome {
    let mut tx = Transaction::decided_if(mesh, decided);
    for &w in &plan.drop_tags {
        tx.take_edge_tags(plan.v, w);
    }
    let created = tx.replace_faces(&plan.star, &plan.new);
    tx.remove_vertex(plan.v);
    for &(a, b, tag) in &plan.retag {
        tx.add_edge_tag(a, b, tag);
    }
    // The new faces and the reshaped ones (gathered only to be checked).
    let validate = |tx: &Transaction<'_>| {
        let faces: Vec<FaceId> = created.iter().chain(&plan.reshaped).copied().collect();
        let check = Check {
            faces: &faces,
            changed: &[plan.u],
            budgets: &[],
            old_max_energy: Some(plan.old_max_energy),
            old_corner_energy: plan.old_corner_energy,
        };
        invariants::validate(tx, ctx, &check)
    };
    if decided {
        debug_assert!(
            validate(&tx).is_ok(),
            "a collapse decided ahead fails the invariants"
        );
    } else if let Err(r) = validate(&tx) {
        return Outcome::Rejected(r);
    }
    tx.commit();
    Outcome::Applied(LocalChange {
        created,
        removed_vertex: Some(plan.v),
        ..LocalChange::default()
    })
}
