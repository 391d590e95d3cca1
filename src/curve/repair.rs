//! Repairs on the linear mesh before it is curved (thesis §4.4.2 "Splitting
//! and Curving"): rational vertices rounded, triangles with more than one
//! curved edge split until each has at most one, and elements the exact shape
//! does not certify repaired by the local operations (a straight sliver
//! swapped, smoothed or collapsed away; a curved element's opposite vertex
//! smoothed, then its curved edge split).

use super::build::{CurveOptions, CurveStats};
use super::shape::{Bend, exact_shape, exact_shape_around, face_edges, uncertified};
use crate::Result;
use crate::element::Order;
use crate::element::jacobian::CertifyOptions;
use crate::mesh::{EdgeKey, FaceId, TriMesh, VertexId};
use crate::ops::invariants::curved::curved_tag;
use crate::ops::{self, Context, Outcome};

/// Passes of [`split_multi_primary`]: each pass halves the offending
/// configurations, so a few suffice. Empirical (`docs/tuning.md`).
const MULTI_PRIMARY_PASSES: usize = 16;
/// A curved edge is split for repair only if it is at least this multiple of
/// [`CurveOptions::l_min_abs`] long (its halves stay about `l_min` or longer).
const SPLIT_MIN_MULTIPLE: f64 = 2.0;

/// Round every rational vertex (the output has `f64` vertices only).
pub(super) fn round_all(mesh: &mut TriMesh, ctx: &Context) -> Result<()> {
    let rational: Vec<VertexId> = mesh.vertices().filter(|&v| mesh.is_rational(v)).collect();
    for v in rational {
        ops::try_round(mesh, ctx, v);
    }
    crate::fem::require_f64(mesh, crate::Stage::Curve)
}

/// Split triangles with two or three curved edges until each has at most one
/// (or the budget runs out). Returns the number of splits.
pub(super) fn split_multi_primary(mesh: &mut TriMesh, ctx: &Context, budget: &mut usize) -> usize {
    let mut done = 0;
    for _ in 0..MULTI_PRIMARY_PASSES {
        let bad: Vec<FaceId> = mesh
            .faces()
            .filter(|&f| curved_edges(mesh, ctx, f).len() > 1)
            .collect();
        if bad.is_empty() || *budget == 0 {
            break;
        }
        let mut progress = false;
        for f in bad {
            if *budget == 0 {
                break;
            }
            if !mesh.is_face_alive(f) || curved_edges(mesh, ctx, f).len() < 2 {
                continue;
            }
            let edges = face_edges(mesh, f);
            let len = |k: &EdgeKey| (mesh.position(k.hi) - mesh.position(k.lo)).hypot();
            // Prefer the non-primary edge (it separates the primary ones), then the longest.
            let mut order: Vec<EdgeKey> = edges.to_vec();
            order.sort_by(|a, b| {
                let (pa, pb) = (
                    curved_tag(mesh, ctx, *a).is_some(),
                    curved_tag(mesh, ctx, *b).is_some(),
                );
                pa.cmp(&pb).then(len(b).total_cmp(&len(a)))
            });
            for k in order {
                if ops::try_split(mesh, ctx, k.lo, k.hi).is_applied() {
                    *budget -= 1;
                    done += 1;
                    progress = true;
                    break;
                }
            }
        }
        if !progress {
            break;
        }
    }
    done
}

/// The curved edges (primary, on a cubic) of face `f`.
pub(super) fn curved_edges(mesh: &TriMesh, ctx: &Context, f: FaceId) -> Vec<EdgeKey> {
    face_edges(mesh, f)
        .into_iter()
        .filter(|k| curved_tag(mesh, ctx, *k).is_some())
        .collect()
}

/// Straight faces that are not certified at `order`: slivers whose exact
/// orientation is positive but whose `det J` is within the zero tolerance.
pub(super) fn uncertified_straight(
    mesh: &TriMesh,
    shape: &Bend,
    order: Order,
    opts: &CertifyOptions,
) -> Vec<FaceId> {
    mesh.faces()
        .filter(|&f| {
            face_edges(mesh, f)
                .iter()
                .all(|k| !shape.edges.contains_key(k))
                && !shape.certified(mesh, order, f, opts)
        })
        .collect()
}

/// Try to remove a sliver: swap its longest edge, smooth its vertices, collapse
/// its shortest edge (the local operations keep the linear invariants).
pub(super) fn repair_sliver(mesh: &mut TriMesh, ctx: &Context, f: FaceId) -> bool {
    let mut edges = face_edges(mesh, f);
    let len = |k: &EdgeKey| (mesh.position(k.hi) - mesh.position(k.lo)).hypot();
    edges.sort_by(|a, b| len(b).total_cmp(&len(a)));
    for k in &edges {
        if ops::try_swap(mesh, ctx, k.lo, k.hi).is_applied() {
            return true;
        }
    }
    for v in mesh.face(f) {
        if ops::try_smooth(mesh, ctx, v).is_applied() {
            return true;
        }
    }
    let k = edges[2];
    ops::try_collapse(mesh, ctx, k.lo, k.hi).is_applied()
        || ops::try_collapse(mesh, ctx, k.hi, k.lo).is_applied()
}

/// Repair on the linear mesh: smooth the vertex opposite a failing curved edge,
/// and if that does not certify the element, split the curved edge.
pub(super) fn repair(
    mesh: &mut TriMesh,
    ctx: &Context,
    opts: &CurveOptions,
    stats: &mut CurveStats,
    budget: &mut usize,
) {
    let order = opts.order;
    for _ in 0..opts.repair_rounds {
        let shape = exact_shape(mesh, ctx, order);
        let bad = uncertified(mesh, &shape, order, &opts.certify);
        let slivers = uncertified_straight(mesh, &shape, order, &opts.certify);
        tracing::debug!(
            bad = bad.len(),
            slivers = slivers.len(),
            "curving repair round"
        );
        if bad.is_empty() && slivers.is_empty() {
            return;
        }
        let mut progress = false;
        for f in slivers {
            if mesh.is_face_alive(f) && repair_sliver(mesh, ctx, f) {
                stats.sliver_repairs += 1;
                progress = true;
            }
        }
        for f in bad {
            if !mesh.is_face_alive(f) {
                continue;
            }
            let curved = curved_edges(mesh, ctx, f);
            let Some(&key) = curved.first() else {
                continue;
            };
            let opposite: Vec<VertexId> = mesh
                .face(f)
                .into_iter()
                .filter(|&v| v != key.lo && v != key.hi)
                .collect();
            let mut fixed = false;
            for v in opposite {
                if ops::try_smooth(mesh, ctx, v).is_applied() {
                    stats.smooths_repair += 1;
                    progress = true;
                    let shape = exact_shape_around(mesh, ctx, order, v);
                    fixed = mesh
                        .incident_faces(v)
                        .into_iter()
                        .all(|g| shape.certified(mesh, order, g, &opts.certify));
                }
            }
            if fixed || *budget == 0 || !mesh.is_face_alive(f) {
                continue;
            }
            let len = (mesh.position(key.hi) - mesh.position(key.lo)).hypot();
            if len < SPLIT_MIN_MULTIPLE * opts.l_min_abs || curved_tag(mesh, ctx, key).is_none() {
                continue;
            }
            // The split must not trade an uncertified element for slivers (a
            // vertex almost on the curve's chord line makes the halves needles):
            // its triangles stay within the curved stop energy, or within the
            // worst of the faces it replaces when that is already worse.
            let mut on_edge = Vec::new();
            mesh.faces_on_edge(key.lo, key.hi, &mut on_edge);
            let bound = ops::max_energy(mesh, ctx, &on_edge).max(opts.params.stop_energy_curved);
            if let Outcome::Applied(_) =
                ops::try_split_bounded(mesh, ctx, key.lo, key.hi, Some(bound))
            {
                *budget -= 1;
                stats.splits_repair += 1;
                progress = true;
            }
        }
        stats.splits_multi_primary += split_multi_primary(mesh, ctx, budget);
        if !progress {
            return;
        }
    }
}
