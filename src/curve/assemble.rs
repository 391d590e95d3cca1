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
use std::collections::HashMap;

/// Accuracy of the distance statistics ([`edge_distance`]) relative to `d`.
/// Introduced in ac447f1.
const DISTANCE_ACCURACY_REL: f64 = 1e-12;

/// Number the nodes (the vertices as every mesh delivered from a `TriMesh`
/// numbers them, [`VertexNumbers`]; then edge and centre nodes) and write the
/// elements and the feature lines ([`feature_lines`]).
pub(super) fn assemble(
    mesh: &TriMesh,
    order: Order,
    shape: &Bend,
    feature: impl Fn(&FeatureOn) -> (ShapeId, LineKind),
) -> CurvedMesh {
    let (numbers, mut nodes) = VertexNumbers::of(mesh);
    let next =
        |nodes: &Vec<Point>| u32::try_from(nodes.len()).expect("internal: node count fits u32");
    let inner_count = order as usize - 1;
    // Inner node indices of each edge, from lo to hi.
    let mut edge_nodes: HashMap<EdgeKey, Vec<u32>> = HashMap::new();
    let mut edge_inner = |nodes: &mut Vec<Point>, key: EdgeKey| -> Vec<u32> {
        edge_nodes
            .entry(key)
            .or_insert_with(|| {
                let pts = shape.edges.get(&key).cloned().unwrap_or_else(|| {
                    straight_inner(mesh.position(key.lo), mesh.position(key.hi), order)
                });
                pts.into_iter()
                    .map(|p| {
                        let i = next(nodes);
                        nodes.push(p);
                        i
                    })
                    .collect()
            })
            .clone()
    };
    let mut faces: Vec<FaceId> = mesh.faces().collect();
    faces.sort_unstable();
    let mut triangles = Vec::with_capacity(faces.len() * order.triangle_nodes());
    for &f in &faces {
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
                triangles.extend(ids.into_iter().rev());
            }
        }
        if order == Order::Cubic {
            let el = shape.element(mesh, order, f);
            triangles.push(next(&nodes));
            nodes.push(el[9]);
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
    let mut pts = Vec::with_capacity(n);
    for (i, t) in curved.triangles.chunks_exact(n).enumerate() {
        pts.clear();
        pts.extend(t.iter().map(|&k| curved.nodes[k as usize]));
        let cert = jacobian::certify_element(order, &pts, &opts.certify)
            .expect("internal: element has its order's node count");
        if !cert.is_certified() {
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
    }
    // Curved elements: those with a curved edge on a cubic feature.
    let mut curved_faces: Vec<FaceId> = Vec::new();
    let mut on_edge = Vec::new();
    let mut dist_sum = 0.0;
    let mut dist_count = 0usize;
    let mut dist_max = 0.0f64;
    let mut corner_max = 0.0f64;
    let mut keys: Vec<EdgeKey> = mesh.tagged_edges().map(|(k, _)| k).collect();
    keys.sort_unstable();
    for key in keys {
        let Some((section, t)) = primary(mesh, key) else {
            continue;
        };
        let Some(sec) = ctx.section(section) else {
            continue;
        };
        let (a, b) = (mesh.position(key.lo), mesh.position(key.hi));
        let inner = shape
            .edges
            .get(&key)
            .cloned()
            .unwrap_or_else(|| straight_inner(a, b, order));
        let off = (a - sec.parent.eval(t[0]))
            .hypot()
            .max((b - sec.parent.eval(t[1])).hypot());
        corner_max = corner_max.max(off);
        let acc = DISTANCE_ACCURACY_REL * opts.d;
        let dist = edge_distance(a, b, &inner, |p| sec.parent.distance(p, t, acc));
        dist_max = dist_max.max(dist);
        dist_sum += dist;
        dist_count += 1;
        if on_curved(ctx, section) && shape.edges.contains_key(&key) && order != Order::Linear {
            mesh.faces_on_edge(key.lo, key.hi, &mut on_edge);
            curved_faces.extend(&on_edge);
        }
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
    for f in curved_faces {
        if let Some(c) = shape.certificate(mesh, order, f, &CertifyOptions::DEFAULT) {
            stats.min_jacobian_ratio = stats.min_jacobian_ratio.min(c.ratio());
        }
    }
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
