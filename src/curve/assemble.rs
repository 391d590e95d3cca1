//! The curved mesh as delivered: nodes numbered (the vertices, then edge and
//! centre nodes), elements and feature lines written in gmsh order, every
//! element certified once more and the distances to the curves measured for
//! [`CurveStats`]; and the [`FemMesh`] of a [`CurvedMesh`].

use super::build::{CurveOptions, CurveStats, CurvedMesh};
use super::fit::edge_distance;
use super::shape::{Bend, face_edges};
use crate::element::Order;
use crate::element::jacobian::{self, CertifyOptions};
use crate::element::triangle::{EDGES, straight_inner};
use crate::fem::{FemMesh, LineKind, VertexNumbers, feature_lines};
use crate::mesh::{EdgeKey, FaceId, FeatureOn, TriMesh};
use crate::ops::Context;
use crate::ops::invariants::curved::{on_curved, primary};
use crate::stage::Stage;
use crate::svg::ShapeId;
use crate::{Error, Result};
use kurbo::Point;
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// Accuracy of the distance statistics ([`edge_distance`]) relative to `d`.
const DISTANCE_ACCURACY_REL: f64 = 1e-14;

/// Number the nodes (the vertices as every mesh delivered from a `TriMesh`
/// numbers them, [`VertexNumbers`]; then edge and centre nodes) and write the
/// elements and the feature lines ([`feature_lines`]).
pub(super) fn assemble<I: IntoIterator<Item = (ShapeId, LineKind)>>(
    mesh: &TriMesh,
    order: Order,
    shape: &Bend,
    feature: impl Fn(&FeatureOn) -> I,
) -> CurvedMesh {
    let (numbers, mut nodes) = VertexNumbers::of(mesh);
    let next =
        |nodes: &Vec<Point>| u32::try_from(nodes.len()).expect("internal: node count fits u32");
    let inner_count = order as usize - 1;
    // The index of each edge's first inner node (its inner nodes are numbered
    // together, from lo to hi).
    let mut edge_nodes: FxHashMap<EdgeKey, u32> = FxHashMap::default();
    let mut edge_inner = |nodes: &mut Vec<Point>, key: EdgeKey| -> std::ops::Range<u32> {
        let first = *edge_nodes.entry(key).or_insert_with(|| {
            let first = next(nodes);
            match shape.edges.get(&key) {
                Some(pts) => nodes.extend_from_slice(pts),
                None => nodes.extend(straight_inner(
                    mesh.position(key.lo),
                    mesh.position(key.hi),
                    order,
                )),
            }
            debug_assert_eq!(next(nodes) - first, inner_count as u32);
            first
        });
        first..first + inner_count as u32
    };
    let mut faces: Vec<FaceId> = mesh.faces().collect();
    faces.sort_unstable();
    // The cubic centre nodes, in parallel (each reads its face's element).
    let centres: Vec<Point> = if order == Order::Cubic {
        faces
            .par_iter()
            .map(|&f| shape.element(mesh, order, f)[9])
            .collect()
    } else {
        Vec::new()
    };
    let mut triangles = Vec::with_capacity(faces.len() * order.triangle_nodes());
    for (n, &f) in faces.iter().enumerate() {
        let v = mesh.face(f);
        triangles.extend(v.map(|x| numbers.get(x)));
        if inner_count == 0 {
            continue;
        }
        for [i, j] in EDGES {
            let key = EdgeKey::new(v[i], v[j]);
            let ids = edge_inner(&mut nodes, key);
            if key.lo == v[i] {
                triangles.extend(ids);
            } else {
                triangles.extend(ids.rev());
            }
        }
        if let Some(&centre) = centres.get(n) {
            triangles.push(next(&nodes));
            nodes.push(centre);
        }
    }
    let mut lines = Vec::new();
    let mut line_feature: Vec<(ShapeId, LineKind)> = Vec::new();
    for (key, fk) in feature_lines(mesh, feature) {
        line_feature.push(fk);
        lines.push(numbers.get(key.lo));
        lines.push(numbers.get(key.hi));
        if inner_count > 0 {
            lines.extend(edge_inner(&mut nodes, key));
        }
    }
    CurvedMesh {
        order: Some(order),
        nodes,
        triangles,
        lines,
        line_feature,
    }
}

/// Certify every element of the output, count curved ones and measure distances.
pub(super) fn finish_stats(
    mesh: &TriMesh,
    ctx: &Context,
    opts: &CurveOptions,
    shape: &Bend,
    curved: &CurvedMesh,
    stats: &mut CurveStats,
) -> Result<()> {
    let order = curved.order();
    let n = order.triangle_nodes();
    // Every element certified, in parallel; the first that fails (in element
    // order) is the error.
    let failed = curved
        .triangles
        .par_chunks_exact(n)
        .enumerate()
        .map(|(i, t)| {
            let pts: Vec<Point> = t.iter().map(|&k| curved.nodes[k as usize]).collect();
            let cert = jacobian::certify_element(order, &pts, &opts.certify)
                .expect("internal: element has its order's node count");
            (i, cert)
        })
        .find_first(|(_, cert)| !cert.is_certified());
    if let Some((i, cert)) = failed {
        let mut faces: Vec<FaceId> = mesh.faces().collect();
        faces.sort_unstable();
        let f = faces[i];
        let bent = face_edges(mesh, f)
            .iter()
            .filter(|k| shape.edges.contains_key(k))
            .count();
        return Err(Error::meshing(
            Stage::Curve,
            format!(
                "element {i} ({f:?}, {bent} curved edges, centre moved: {}) is not \
                 certified valid ({:?}): a straight sliver of the linear mesh that no \
                 local operation could remove",
                shape.centre.contains_key(&f),
                cert.validity
            ),
        ));
    }
    // Curved elements: those with a curved edge on a cubic feature. The
    // distances of the primary edges are measured in parallel and summed in
    // edge order.
    let mut keys: Vec<EdgeKey> = mesh.tagged_edges().map(|(k, _)| k).collect();
    keys.sort_unstable();
    let acc = DISTANCE_ACCURACY_REL * opts.d;
    let measured: Vec<(f64, f64, Vec<FaceId>)> = keys
        .par_iter()
        .filter_map(|&key| {
            let (section, t) = primary(mesh, key)?;
            let sec = ctx.section(section)?;
            let (a, b) = (mesh.position(key.lo), mesh.position(key.hi));
            let inner = shape
                .edges
                .get(&key)
                .cloned()
                .unwrap_or_else(|| straight_inner(a, b, order));
            let off = (a - sec.parent.eval(t[0]))
                .hypot()
                .max((b - sec.parent.eval(t[1])).hypot());
            let dist = edge_distance(a, b, &inner, |p| sec.parent.distance(p, t, acc));
            let mut on_edge = Vec::new();
            if on_curved(ctx, section) && shape.edges.contains_key(&key) && order != Order::Linear {
                mesh.faces_on_edge(key.lo, key.hi, &mut on_edge);
            }
            Some((off, dist, on_edge))
        })
        .collect();
    let mut curved_faces: Vec<FaceId> = Vec::new();
    let mut dist_sum = 0.0;
    let mut dist_count = 0usize;
    let mut dist_max = 0.0f64;
    let mut corner_max = 0.0f64;
    for (off, dist, on_edge) in measured {
        corner_max = corner_max.max(off);
        dist_max = dist_max.max(dist);
        dist_sum += dist;
        dist_count += 1;
        curved_faces.extend(on_edge);
    }
    curved_faces.sort_unstable();
    curved_faces.dedup();
    stats.curved_triangles = curved_faces.len();
    let d = if opts.d > 0.0 { opts.d } else { 1.0 };
    stats.max_curve_distance_rel = dist_max / d;
    stats.max_corner_offset_rel = corner_max / d;
    stats.mean_curve_distance_rel = if dist_count > 0 {
        dist_sum / dist_count as f64 / d
    } else {
        0.0
    };
    let min_ratio = curved_faces
        .par_iter()
        .filter_map(|&f| shape.certificate(mesh, order, f, &CertifyOptions::DEFAULT))
        .map(|c| c.ratio())
        .reduce(|| f64::INFINITY, f64::min);
    stats.min_jacobian_ratio = stats.min_jacobian_ratio.min(min_ratio);
    Ok(())
}

impl FemMesh {
    /// The FemMesh of a curved mesh (any order), with one physical surface
    /// `surface` and one physical curve per shape that has feature lines (named
    /// with `shape_name`), as [`FemMesh::from_linear`] does.
    /// (It lives here, with the curved mesh, so `fem` need not know the curving stage.)
    pub fn from_curved(
        mesh: &CurvedMesh,
        surface: &str,
        shape_name: impl Fn(crate::svg::ShapeId) -> String,
    ) -> FemMesh {
        FemMesh::assemble(
            mesh.order(),
            mesh.nodes.clone(),
            mesh.triangles.clone(),
            mesh.lines.clone(),
            mesh.line_feature.iter().copied(),
            surface,
            shape_name,
        )
    }
}
