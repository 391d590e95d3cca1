//! The last resort of rounding: collapsing a vertex that no `f64` point near it
//! can hold into a neighbouring `f64` vertex.
//!
//! A rational vertex can be unroundable for good: e.g. three distinct points
//! of one segment within a single ulp of each other, two of them already
//! `f64`, leave no `f64` point for the third. Only removing it helps. The
//! collapse `v → u` is done only when it keeps everything the BSP promises:
//! `v` is a Steiner vertex (no vertex tag) inside the box; it lies on no
//! feature, or on exactly one chain `w – v – u` (its only two tagged edges
//! carry the same features), which becomes the edge `w – u`; the link
//! condition holds (no fold-over of the topology); and every triangle that
//! moves to `u` stays exactly counter-clockwise. Thesis §2.3.2 (edge
//! collapse), docs/design.md "Exactness".

use crate::exact::Orientation;
use crate::mesh::{FaceId, FeatureOn, TriMesh, VertexId};
use std::collections::HashSet;

/// The ring of neighbours of `v` (from its incident faces), and whether the
/// fan around `v` is closed (an interior vertex).
fn ring(mesh: &TriMesh, v: VertexId, star: &[FaceId]) -> (HashSet<VertexId>, bool) {
    let mut n = HashSet::new();
    let mut closed = true;
    for &f in star {
        let i = mesh
            .local_index(f, v)
            .expect("internal: star face contains its vertex");
        let vs = mesh.face(f);
        n.insert(vs[(i + 1) % 3]);
        n.insert(vs[(i + 2) % 3]);
        let adj = mesh.neighbours(f);
        // The two edges incident to v are opposite the other two corners.
        if adj[(i + 1) % 3].is_none() || adj[(i + 2) % 3].is_none() {
            closed = false;
        }
    }
    (n, closed)
}

/// What identifies a feature on an edge regardless of parameters.
fn feature_id(t: &FeatureOn) -> (bool, u32) {
    match *t {
        FeatureOn::Primary { section, .. } => (true, section),
        FeatureOn::Secondary { polyline } => (false, polyline),
    }
}

/// The parameter a primary tag of edge `a b` gives at vertex `x` (one of `a`, `b`).
fn t_at(t: [f64; 2], a: VertexId, b: VertexId, x: VertexId) -> f64 {
    if x == a.min(b) { t[0] } else { t[1] }
}

/// Try to collapse the rational vertex `v` into some `f64` neighbour; returns
/// whether it was collapsed (the mesh is unchanged otherwise).
pub(super) fn try_collapse(mesh: &mut TriMesh, v: VertexId) -> bool {
    if mesh.vertex_tag(v).any() {
        return false;
    }
    let star = mesh.incident_faces(v);
    let (nv, closed) = ring(mesh, v, &star);
    if !closed || star.len() < 3 {
        return false;
    }
    let tagged: Vec<VertexId> = nv
        .iter()
        .copied()
        .filter(|&w| !mesh.edge_tags(v, w).is_empty())
        .collect();
    let mut targets: Vec<VertexId> = match tagged[..] {
        [] => nv.iter().copied().collect(),
        [a, b] => {
            let ids = |w: VertexId| {
                let mut s: Vec<(bool, u32)> = mesh.edge_tags(v, w).iter().map(feature_id).collect();
                s.sort_unstable();
                s
            };
            if ids(a) != ids(b) {
                return false;
            }
            vec![a, b]
        }
        _ => return false,
    };
    targets.retain(|&u| !mesh.is_rational(u));
    let pv = mesh.position(v);
    targets.sort_by(|&a, &b| {
        let (da, db) = (
            (mesh.position(a) - pv).hypot2(),
            (mesh.position(b) - pv).hypot2(),
        );
        da.total_cmp(&db).then(a.cmp(&b))
    });
    targets
        .into_iter()
        .any(|u| collapse_into(mesh, v, u, &star, &nv, &tagged))
}

/// Collapse `v` into its neighbour `u` if the link condition holds and every
/// moved triangle stays counter-clockwise.
fn collapse_into(
    mesh: &mut TriMesh,
    v: VertexId,
    u: VertexId,
    star: &[FaceId],
    nv: &HashSet<VertexId>,
    tagged: &[VertexId],
) -> bool {
    // Faces on the edge u v are removed; the others move to u.
    let (gone, moved): (Vec<FaceId>, Vec<FaceId>) = star
        .iter()
        .partition(|&&f| mesh.local_index(f, u).is_some());
    if gone.len() != 2 {
        return false;
    }
    // Link condition: u and v share exactly the two apexes of the removed faces.
    let apexes: HashSet<VertexId> = gone
        .iter()
        .flat_map(|&f| mesh.face(f))
        .filter(|&x| x != u && x != v)
        .collect();
    let nu: HashSet<VertexId> = mesh
        .incident_faces(u)
        .into_iter()
        .flat_map(|f| mesh.face(f))
        .filter(|&x| x != u)
        .collect();
    let common: HashSet<VertexId> = nv.intersection(&nu).copied().collect();
    if common != apexes || apexes.len() != 2 {
        return false;
    }
    let new_faces: Vec<[VertexId; 3]> = moved
        .iter()
        .map(|&f| mesh.face(f).map(|x| if x == v { u } else { x }))
        .collect();
    if !new_faces
        .iter()
        .all(|&[a, b, c]| mesh.orientation_of(a, b, c) == Orientation::CounterClockwise)
    {
        return false;
    }
    // Tags: the chain w – v – u becomes w – u.
    let mut new_tags: Vec<(VertexId, VertexId, FeatureOn)> = Vec::new();
    if let Some(&w) = tagged.iter().find(|&&w| w != u) {
        let on_u = mesh.take_edge_tags(v, u);
        let on_w = mesh.take_edge_tags(v, w);
        for tw in &on_w {
            let tag = match *tw {
                FeatureOn::Primary { section, t } => {
                    let tu = on_u
                        .iter()
                        .find_map(|x| match *x {
                            FeatureOn::Primary { section: s, t: tt } if s == section => {
                                Some(t_at(tt, v, u, u))
                            }
                            _ => None,
                        })
                        .expect("internal: both chain edges carry the same features");
                    FeatureOn::Primary {
                        section,
                        t: [t_at(t, v, w, w), tu],
                    }
                }
                other => other,
            };
            new_tags.push((w, u, tag));
        }
    }
    // Faces around the star, outside it, whose adjacency must be rebuilt.
    let star_set: HashSet<FaceId> = star.iter().copied().collect();
    let outer: Vec<FaceId> = star
        .iter()
        .flat_map(|&f| mesh.neighbours(f))
        .flatten()
        .filter(|g| !star_set.contains(g))
        .collect();
    for &f in star {
        mesh.remove_face(f);
    }
    mesh.remove_vertex(v);
    let added: Vec<FaceId> = new_faces.into_iter().map(|f| mesh.add_face(f)).collect();
    for (i, &f) in added.iter().enumerate() {
        for &g in added[i + 1..].iter().chain(&outer) {
            mesh.link(f, g);
        }
    }
    for (a, b, tag) in new_tags {
        mesh.add_edge_tag(a, b, tag);
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::PointQ;
    use crate::mesh::VertexTag;
    use kurbo::Point;

    /// A rational vertex a third of the way between two `f64` vertices one ulp
    /// apart, on a feature chain: no `f64` point can hold it.
    fn one_ulp_gap() -> (TriMesh, [VertexId; 5]) {
        let eps = f64::EPSILON;
        let mut m = TriMesh::new();
        let t = VertexTag::default();
        let u = m.add_vertex(Point::new(0.0, 1.0), t);
        let w = m.add_vertex(Point::new(0.0, 1.0 + eps), t);
        let l = m.add_vertex(Point::new(-1.0, 1.0), t);
        let r = m.add_vertex(Point::new(1.0, 1.0 + eps), t);
        let v = m.add_vertex_q(
            PointQ::from_point(Point::new(0.0, 1.0)).lerp_ratio(
                &PointQ::from_point(Point::new(0.0, 1.0 + eps)),
                1.0,
                3.0,
            ),
            t,
        );
        for f in [[u, r, v], [v, r, w], [w, l, v], [v, l, u]] {
            m.add_face(f);
        }
        m.link_all();
        for (a, b, ta, tb) in [(u, v, 0.0, 0.25), (v, w, 0.25, 1.0)] {
            m.add_edge_tag(a, b, FeatureOn::Secondary { polyline: 7 });
            m.add_edge_tag(
                a,
                b,
                FeatureOn::Primary {
                    section: 3,
                    t: [ta, tb],
                },
            );
        }
        (m, [u, v, w, l, r])
    }

    #[test]
    fn unroundable_vertex_on_a_chain_collapses_keeping_the_chain() {
        let (mut m, [u, v, w, l, r]) = one_ulp_gap();
        assert!(m.check().is_empty(), "{:?}", m.check());
        super::super::fan::round_vertices(&mut m, 4, &crate::budget::Deadline::NONE)
            .expect("no deadline");
        assert!(m.is_rational(v), "no f64 point fits between u and w");
        assert!(try_collapse(&mut m, v));
        assert!(!m.is_vertex_alive(v));
        assert!(m.check().is_empty(), "{:?}", m.check());
        assert_eq!(m.num_faces(), 2);
        let mut tags = m.edge_tags(u, w).to_vec();
        tags.sort_by_key(feature_id);
        let (lo_t, hi_t) = if u < w { (0.0, 1.0) } else { (1.0, 0.0) };
        assert_eq!(
            tags,
            vec![
                FeatureOn::Secondary { polyline: 7 },
                FeatureOn::Primary {
                    section: 3,
                    t: [lo_t, hi_t]
                },
            ]
        );
        assert_eq!(m.tagged_edges().count(), 1);
        assert_eq!(m.incident_faces(l).len(), 1);
        assert_eq!(m.incident_faces(r).len(), 1);
    }

    #[test]
    fn collapse_is_refused_at_a_crossing_and_for_tagged_vertices() {
        let (mut m, [_, v, _, l, r]) = one_ulp_gap();
        // A second feature through v: four tagged edges.
        m.add_edge_tag(l, v, FeatureOn::Secondary { polyline: 9 });
        m.add_edge_tag(v, r, FeatureOn::Secondary { polyline: 9 });
        assert!(!try_collapse(&mut m, v));
        assert!(m.is_vertex_alive(v));
        let (mut m, [_, v, ..]) = one_ulp_gap();
        m.set_vertex_tag(
            v,
            VertexTag {
                feature_point: true,
                ..VertexTag::default()
            },
        );
        assert!(!try_collapse(&mut m, v));
        assert_eq!(m.num_faces(), 4);
    }
}
