//! The curved mode of the invariants (thesis §4.4.2 "Curved Optimization";
//! docs/design.md "Curved elements"): once the linear mesh is curved, the local
//! operations keep every element they touch a valid curved element instead of
//! keeping each primary edge's turn below α.
//!
//! A triangle's shape is read off the mesh: an edge is curved when it carries a
//! primary tag whose section lies on a curved (cubic or conic) parent (edges on
//! straight parents stay straight); the curved edge takes its exact curve piece
//! (`element::triangle::piece_inner`: its inner nodes are points of the parent
//! at equal steps of its natural parameter, `Parent::along`; a conic's are
//! exact and equally spaced in its angle). A triangle passes when it has at
//! most one curved edge and its element is certified
//! ([`crate::element::jacobian::certify_element`]).

use super::super::{Context, CurvedRule, Reject};
use crate::element::triangle as element;
use crate::mesh::{EdgeKey, FaceId, FeatureOn, TriMesh, VertexId};
use kurbo::{Point, Vec2};

/// The primary tag of an edge: section and the parameters at `lo`, `hi`.
pub(crate) fn primary(mesh: &TriMesh, key: EdgeKey) -> Option<(u32, [f64; 2])> {
    mesh.edge_tags(key.lo, key.hi)
        .iter()
        .find_map(|t| match *t {
            FeatureOn::Primary { section, t } => Some((section, t)),
            FeatureOn::Secondary { .. } => None,
        })
}

/// Whether the section lies on a curved (cubic or conic, not a straight) parent.
pub(crate) fn on_curved(ctx: &Context, section: u32) -> bool {
    ctx.section(section).is_some_and(|s| !s.parent.is_line())
}

/// The primary tag of an edge (section and the parameters at `key.lo`,
/// `key.hi`), as the mesh has it ([`primary`]) or as a change would leave it
/// (the verdicts decided ahead).
pub(crate) type PrimaryOf<'a> = &'a dyn Fn(EdgeKey) -> Option<(u32, [f64; 2])>;

/// The tag of a primary edge on a curved parent: the edges that are curved.
pub(crate) fn curved_tag(mesh: &TriMesh, ctx: &Context, key: EdgeKey) -> Option<(u32, [f64; 2])> {
    curved_tag_by(ctx, &|k| primary(mesh, k), key)
}

/// [`curved_tag`] with the primary tags given by `primary_of`.
fn curved_tag_by(
    ctx: &Context,
    primary_of: PrimaryOf<'_>,
    key: EdgeKey,
) -> Option<(u32, [f64; 2])> {
    primary_of(key).filter(|&(section, _)| on_curved(ctx, section))
}

/// The exact inner nodes (from `key.lo` to `key.hi`) of a curved edge, or
/// `None` when the edge is not curved.
pub(crate) fn exact_inner(
    mesh: &TriMesh,
    ctx: &Context,
    order: crate::element::Order,
    key: EdgeKey,
) -> Option<Vec<Point>> {
    exact_inner_by(mesh, ctx, &|k| primary(mesh, k), order, key)
}

/// [`exact_inner`] with the primary tags given by `primary_of`.
fn exact_inner_by(
    mesh: &TriMesh,
    ctx: &Context,
    primary_of: PrimaryOf<'_>,
    order: crate::element::Order,
    key: EdgeKey,
) -> Option<Vec<Point>> {
    let (section, t) = curved_tag_by(ctx, primary_of, key)?;
    let parent = ctx.section(section)?.parent;
    Some(element::piece_inner(
        |s| parent.along(t, s),
        [0.0, 1.0],
        mesh.position(key.lo),
        mesh.position(key.hi),
        order,
    ))
}

/// The Lagrange nodes of the triangle `tri` with its exact curved edge, or
/// `None` when it has more than one curved edge (the tests' view; the
/// invariants go through [`energy_within_by`]).
#[cfg(test)]
pub(crate) fn exact_nodes(
    mesh: &TriMesh,
    ctx: &Context,
    order: crate::element::Order,
    tri: [VertexId; 3],
) -> Option<Vec<Point>> {
    exact_nodes_by(mesh, ctx, &|k| primary(mesh, k), order, tri)
}

/// The Lagrange nodes of `tri` as `exact_nodes` (test-only) gives them, with
/// the primary tags given by `primary_of`.
fn exact_nodes_by(
    mesh: &TriMesh,
    ctx: &Context,
    primary_of: PrimaryOf<'_>,
    order: crate::element::Order,
    tri: [VertexId; 3],
) -> Option<Vec<Point>> {
    let mut curved: Option<(usize, Vec<Point>)> = None;
    for (e, [i, j]) in element::EDGES.into_iter().enumerate() {
        let key = EdgeKey::new(tri[i], tri[j]);
        if let Some(mut inner) = exact_inner_by(mesh, ctx, primary_of, order, key) {
            if curved.is_some() {
                return None;
            }
            if key.lo != tri[i] {
                inner.reverse();
            }
            curved = Some((e, inner));
        }
    }
    let mut inner: [Option<&[Point]>; 3] = [None; 3];
    if let Some((e, pts)) = &curved {
        inner[*e] = Some(pts);
    }
    Some(element::nodes(
        order,
        tri.map(|v| mesh.position(v)),
        inner,
        Vec2::ZERO,
    ))
}

/// The curved energy of the triangle `tri`, or `None` when it is not a valid
/// curved element (more than one curved edge, or not certified).
///
/// A straight triangle takes a shortcut: its `det J` is the constant twice its
/// area and its curved energy is the linear AMIPS, so it is judged from its
/// corners when its area is clearly (twice) above the certification's zero
/// tolerance; the full certification at the rule's order decides otherwise.
pub(crate) fn energy(
    mesh: &TriMesh,
    ctx: &Context,
    rule: &CurvedRule,
    tri: [VertexId; 3],
) -> Option<f64> {
    energy_within(mesh, ctx, rule, tri, f64::INFINITY).ok()
}

/// [`energy`], but energy first: a curved element whose sampled energy exceeds
/// `bound` is refused ([`Reject::Energy`]) before it is certified, since either
/// it is valid and its energy (at least the sampled one) exceeds `bound`, or it
/// is not valid; an element that is not valid is [`Reject::Jacobian`].
fn energy_within(
    mesh: &TriMesh,
    ctx: &Context,
    rule: &CurvedRule,
    tri: [VertexId; 3],
    bound: f64,
) -> Result<f64, Reject> {
    energy_within_by(mesh, ctx, &|k| primary(mesh, k), rule, tri, bound)
}

/// [`energy_within`] with the primary tags given by `primary_of`.
fn energy_within_by(
    mesh: &TriMesh,
    ctx: &Context,
    primary_of: PrimaryOf<'_>,
    rule: &CurvedRule,
    tri: [VertexId; 3],
    bound: f64,
) -> Result<f64, Reject> {
    let straight = element::EDGES
        .iter()
        .all(|&[i, j]| curved_tag_by(ctx, primary_of, EdgeKey::new(tri[i], tri[j])).is_none());
    if straight {
        let [a, b, c] = tri.map(|v| mesh.position(v));
        let det = (b - a).cross(c - a);
        let zero = crate::element::jacobian::zero_abs(&[a, b, c], rule.certify.zero_rel);
        if det > 2.0 * zero {
            let e = crate::element::energy::amips(a, b, c);
            return if e > bound {
                Err(Reject::Energy)
            } else {
                Ok(e)
            };
        }
    }
    let nodes = exact_nodes_by(mesh, ctx, primary_of, rule.order, tri).ok_or(Reject::Jacobian)?;
    let e = element::amips(rule.order, &nodes);
    if e == f64::INFINITY {
        // `det J ≤ 0` at a sample point: not valid.
        return Err(Reject::Jacobian);
    }
    if e > bound {
        return Err(Reject::Energy);
    }
    if element::is_certified(rule.order, &nodes, &rule.certify) {
        Ok(e)
    } else {
        Err(Reject::Jacobian)
    }
}

/// [`holds_within`] for the triangles `tris` of a change decided ahead, with
/// the primary tags the change would leave (`primary_of`), on the positions
/// the mesh has now.
pub(crate) fn holds_within_after(
    mesh: &TriMesh,
    ctx: &Context,
    rule: &CurvedRule,
    tris: &[[VertexId; 3]],
    bound: f64,
    primary_of: PrimaryOf<'_>,
) -> Result<f64, Reject> {
    tris.iter().try_fold(0.0f64, |m, &t| {
        energy_within_by(mesh, ctx, primary_of, rule, t, bound).map(|e| m.max(e))
    })
}

/// The largest curved energy of `faces`, or `None` when one of them is not a
/// valid curved element.
pub(crate) fn holds(
    mesh: &TriMesh,
    ctx: &Context,
    rule: &CurvedRule,
    faces: &[FaceId],
) -> Option<f64> {
    holds_within(mesh, ctx, rule, faces, f64::INFINITY).ok()
}

/// [`holds`] under the energy rule with the faces' old largest energy
/// `bound`: [`Reject::Jacobian`] when a face is not a valid curved element,
/// [`Reject::Energy`] when one's energy exceeds `bound` (judged from the
/// sampled energy before certifying, which saves most certifications: most
/// refused curved operations fail the energy rule).
pub(crate) fn holds_within(
    mesh: &TriMesh,
    ctx: &Context,
    rule: &CurvedRule,
    faces: &[FaceId],
    bound: f64,
) -> Result<f64, Reject> {
    faces.iter().try_fold(0.0f64, |m, &f| {
        energy_within(mesh, ctx, rule, mesh.face(f), bound).map(|e| m.max(e))
    })
}
