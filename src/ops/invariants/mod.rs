//! The invariants every local operation keeps (docs/design.md "Invariants" 1-5), each
//! run on the faces an operation created and the edges at the vertices it
//! changed, cheapest first.
//!
//! - [`inversion`]: invariant 1, exact orientation (rationals where a vertex is rational).
//! - [`on_curve`]: invariants 4 and 5, primary vertices on (or moving toward) their curve.
//! - [`curvature`]: invariant 3, a primary edge's curve piece turns less than α.
//! - [`envelope`]: invariant 2, secondary edges inside the ε-envelope (sampled, conservative).
//! - [`curved`]: in curved mode only, every face has at most one curved edge and
//!   is a certified curved element; the energy rule then compares curved energies.

pub(crate) mod curvature;
pub(crate) mod curved;
pub(crate) mod envelope;
pub(crate) mod inversion;
pub(crate) mod on_curve;

pub(crate) use envelope::Envelope;

use super::{Context, CurveBudget, EnergyRule, Reject, max_energy};
use crate::mesh::{EdgeKey, FaceId, FeatureOn, TriMesh, VertexId};

/// What one operation asks the invariants to check.
#[derive(Clone, Debug, Default)]
pub(crate) struct Check<'a> {
    /// The faces the operation created (or whose vertices moved).
    pub(crate) faces: &'a [FaceId],
    /// Vertices added, moved or re-connected: their edges are checked.
    pub(crate) changed: &'a [VertexId],
    /// Allowed off-curve distance of primary vertices that moved or were added.
    pub(crate) budgets: &'a [CurveBudget],
    /// Largest energy of the faces replaced, when the energy rule applies
    /// (curved energies in curved mode, `+∞` for an uncertified element).
    pub(crate) old_max_energy: Option<f64>,
    /// In curved mode, the largest straight (corner) energy of the faces
    /// replaced, for the corner rule ([`super::CurvedRule::corner_floor`]).
    pub(crate) old_corner_energy: Option<f64>,
}

/// The edges of the faces `new` that `keep` selects, each with the tags it
/// would have once `added` are given to it as [`TriMesh::add_edge_tag`] gives
/// them (ordered as the key, no duplicate), in face order, the untagged left
/// out: what [`feature_edges_hold`] checks for a change decided ahead.
pub(crate) fn tags_after(
    mesh: &TriMesh,
    new: &[[VertexId; 3]],
    keep: impl Fn(VertexId, VertexId) -> bool,
    added: &[(VertexId, VertexId, FeatureOn)],
) -> Vec<(EdgeKey, Vec<FeatureOn>)> {
    let mut edges: Vec<(EdgeKey, Vec<FeatureOn>)> = Vec::new();
    for t in new {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let key = EdgeKey::new(a, b);
            if !keep(a, b) || edges.iter().any(|(k, _)| *k == key) {
                continue;
            }
            let mut tags = mesh.edge_tags(a, b).to_vec();
            for &(x, y, tag) in added {
                let tag = tag.keyed(x, y);
                if EdgeKey::new(x, y) == key && !tags.contains(&tag) {
                    tags.push(tag);
                }
            }
            if !tags.is_empty() {
                edges.push((key, tags));
            }
        }
    }
    edges
}

/// The feature rules of [`validate`] on edges given with the tags they
/// would have after a change, in its order: the turn of every primary piece
/// ([`Reject::Curvature`]), then every secondary edge, its ends at `at`, in
/// the envelope ([`Reject::Envelope`]). The verdicts the schedule decides
/// ahead, without the tentative change, use it (curved mode checks the
/// curved elements between the two: [`curvature_holds`], then
/// [`envelope_holds`]).
pub(crate) fn feature_edges_hold(
    ctx: &Context,
    edges: &[(EdgeKey, Vec<FeatureOn>)],
    at: impl Fn(VertexId) -> kurbo::Point,
) -> Result<(), Reject> {
    curvature_holds(ctx, edges)?;
    envelope_holds(ctx, edges, at)
}

/// The first half of [`feature_edges_hold`]: the turn of every primary piece.
pub(crate) fn curvature_holds(
    ctx: &Context,
    edges: &[(EdgeKey, Vec<FeatureOn>)],
) -> Result<(), Reject> {
    let bent = edges.iter().flat_map(|(_, tags)| tags).any(|tag| {
        matches!(*tag, FeatureOn::Primary { section, t } if !curvature::holds(ctx, section, t))
    });
    if bent { Err(Reject::Curvature) } else { Ok(()) }
}

/// The second half of [`feature_edges_hold`]: every secondary edge, its ends
/// at `at`, in the envelope.
pub(crate) fn envelope_holds(
    ctx: &Context,
    edges: &[(EdgeKey, Vec<FeatureOn>)],
    at: impl Fn(VertexId) -> kurbo::Point,
) -> Result<(), Reject> {
    for (key, tags) in edges {
        let (a, b) = (at(key.lo), at(key.hi));
        for tag in tags {
            if let FeatureOn::Secondary { polyline } = *tag
                && !ctx.envelope.contains_segment(a, b, polyline)
            {
                return Err(Reject::Envelope);
            }
        }
    }
    Ok(())
}

/// Run every invariant; the first that fails names the rejection.
pub(crate) fn validate(mesh: &TriMesh, ctx: &Context, check: &Check<'_>) -> Result<(), Reject> {
    if !inversion::holds(mesh, check.faces) {
        return Err(Reject::Inversion);
    }
    if !on_curve::holds(mesh, ctx, check.budgets) {
        return Err(Reject::OnCurve);
    }
    let mut edges: Vec<(EdgeKey, &[FeatureOn])> = Vec::new();
    for &f in check.faces {
        let v = mesh.face(f);
        for i in 0..3 {
            let (a, b) = (v[i], v[(i + 1) % 3]);
            if !(check.changed.contains(&a) || check.changed.contains(&b)) {
                continue;
            }
            let key = EdgeKey::new(a, b);
            let tags = mesh.edge_tags(a, b);
            if !tags.is_empty() && !edges.iter().any(|(k, _)| *k == key) {
                edges.push((key, tags));
            }
        }
    }
    for (_, tags) in &edges {
        for t in *tags {
            if let FeatureOn::Primary { section, t } = *t {
                if !curvature::holds(ctx, section, t) {
                    return Err(Reject::Curvature);
                }
            }
        }
    }
    // Curved mode: the elements first (cheaper than the envelope sampling).
    let old_max = check.old_max_energy;
    let new_max = match (&ctx.curved, ctx.energy, old_max) {
        (None, ..) => None,
        // Energy first: most refused curved operations fail the energy rule,
        // which the sampled energy decides before the certification.
        (Some(rule), EnergyRule::NoWorseMax, Some(old)) => {
            Some(curved::holds_within(mesh, ctx, rule, check.faces, old)?)
        }
        (Some(rule), ..) => {
            Some(curved::holds(mesh, ctx, rule, check.faces).ok_or(Reject::Jacobian)?)
        }
    };
    if let (EnergyRule::NoWorseMax, Some(rule), Some(old)) =
        (ctx.energy, &ctx.curved, check.old_corner_energy)
    {
        if super::corner_energy(mesh, ctx, check.faces)
            .is_some_and(|new| new > old.max(rule.corner_floor))
        {
            return Err(Reject::Energy);
        }
    }
    for (key, tags) in &edges {
        let (a, b) = (mesh.position(key.lo), mesh.position(key.hi));
        for t in *tags {
            if let FeatureOn::Secondary { polyline } = *t {
                if !ctx.envelope.contains_segment(a, b, polyline) {
                    return Err(Reject::Envelope);
                }
            }
        }
    }
    if let (EnergyRule::NoWorseMax, Some(old), None) = (ctx.energy, old_max, new_max) {
        if max_energy(mesh, ctx, check.faces) > old {
            return Err(Reject::Energy);
        }
    }
    Ok(())
}
