//! The full validator: reports every defect, never stops at the first.

use super::ids::{FaceId, VertexId};
use super::storage::{EdgeKey, FeatureOn, TriMesh};
use crate::exact::{Orientation, SegmentIntersection, segment_intersection};
use std::collections::HashMap;

/// One thing wrong with a [`TriMesh`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub(crate) enum Defect {
    /// A face uses a dead or unknown vertex.
    DeadVertex(FaceId, VertexId),
    /// A face repeats a vertex.
    RepeatedVertex(FaceId),
    /// A face is not exactly counter-clockwise (inverted or degenerate).
    NotCounterClockwise(FaceId, Orientation),
    /// `adj[i]` of the face names a dead face.
    DeadNeighbour(FaceId, usize),
    /// `adj[i]` of the face names a face that does not share edge `i`, or does
    /// not name it back.
    AsymmetricAdjacency(FaceId, usize),
    /// More than two faces share an edge, or two share it in the same direction.
    NonManifoldEdge(EdgeKey),
    /// Two faces share an edge but are not linked as neighbours.
    UnlinkedEdge(EdgeKey),
    /// A vertex lies inside a boundary edge: the mesh is not conforming.
    TJunction(EdgeKey, VertexId),
    /// A live vertex no live face uses.
    IsolatedVertex(VertexId),
    /// The vertex's incident-face pointer is missing, dead, or wrong.
    BadVertexFace(VertexId),
    /// A rational position that is in fact an `f64` point (should have been dropped).
    NeedlessRational(VertexId),
    /// An edge tag on a pair of vertices that is not a mesh edge.
    DanglingEdgeTag(EdgeKey),
    /// An edge tag with an empty list or a non-finite primary parameter.
    BadEdgeTag(EdgeKey),
    /// The vertex's count of tagged edges is not the number of its edges
    /// with tags.
    BadTagCount(VertexId),
}

impl TriMesh {
    /// Every defect of the mesh (empty when valid). Orientation is decided
    /// exactly; conformity is checked on boundary edges (exact point-on-edge
    /// tests against the vertices whose `x` lies in the edge's range).
    pub(crate) fn check(&self) -> Vec<Defect> {
        let mut out = Vec::new();
        let mut used = vec![false; self.vertex_capacity()];
        let mut edges: HashMap<EdgeKey, Vec<(FaceId, VertexId)>> = HashMap::new();
        for f in self.faces() {
            let v = self.face(f);
            let mut ok = true;
            for &x in &v {
                if self.is_vertex_alive(x) {
                    used[x.index()] = true;
                } else {
                    out.push(Defect::DeadVertex(f, x));
                    ok = false;
                }
            }
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
                out.push(Defect::RepeatedVertex(f));
                ok = false;
            }
            if ok {
                let o = self.orientation(f);
                if o != Orientation::CounterClockwise {
                    out.push(Defect::NotCounterClockwise(f, o));
                }
            }
            for i in 0..3 {
                let (a, b) = self.edge(f, i);
                edges.entry(EdgeKey::new(a, b)).or_default().push((f, a));
                match self.neighbours(f)[i] {
                    None => {}
                    Some(g) if !self.is_face_alive(g) => out.push(Defect::DeadNeighbour(f, i)),
                    Some(g) => {
                        let back = self
                            .edge_index(g, a, b)
                            .map(|j| self.neighbours(g)[j] == Some(f));
                        if back != Some(true) || g == f {
                            out.push(Defect::AsymmetricAdjacency(f, i));
                        }
                    }
                }
            }
        }
        let mut boundary = Vec::new();
        for (key, sides) in &edges {
            match sides[..] {
                [(f, _)] => {
                    let i = self
                        .edge_index(f, key.lo, key.hi)
                        .expect("internal: edge of f");
                    if self.neighbours(f)[i].is_none() {
                        boundary.push(*key);
                    }
                }
                [(f, a), (g, b)] if a != b => {
                    let i = self
                        .edge_index(f, key.lo, key.hi)
                        .expect("internal: edge of f");
                    if self.neighbours(f)[i] != Some(g) {
                        out.push(Defect::UnlinkedEdge(*key));
                    }
                }
                _ => out.push(Defect::NonManifoldEdge(*key)),
            }
        }
        for v in self.vertices() {
            if !used[v.index()] {
                out.push(Defect::IsolatedVertex(v));
            } else {
                let ok = self
                    .vertex_face(v)
                    .is_some_and(|f| self.is_face_alive(f) && self.local_index(f, v).is_some());
                if !ok {
                    out.push(Defect::BadVertexFace(v));
                }
            }
            if self.exact(v).is_some_and(|p| p.is_f64()) {
                out.push(Defect::NeedlessRational(v));
            }
        }
        let mut tagged = vec![0u32; self.vertex_capacity()];
        for (key, _) in self.tagged_edges() {
            for x in [key.lo, key.hi] {
                if let Some(n) = tagged.get_mut(x.index()) {
                    *n += 1;
                }
            }
        }
        for v in self.vertices() {
            if self.tagged_count(v) != tagged[v.index()] {
                out.push(Defect::BadTagCount(v));
            }
        }
        for (key, tags) in self.tagged_edges() {
            if !edges.contains_key(&key) {
                out.push(Defect::DanglingEdgeTag(key));
            }
            let bad_t = tags.iter().any(|t| {
                matches!(t, FeatureOn::Primary { t, .. } if !(t[0].is_finite() && t[1].is_finite()))
            });
            if tags.is_empty() || bad_t {
                out.push(Defect::BadEdgeTag(key));
            }
        }
        self.check_t_junctions(&boundary, &used, &mut out);
        out
    }

    fn check_t_junctions(&self, boundary: &[EdgeKey], used: &[bool], out: &mut Vec<Defect>) {
        // Vertices sorted by their f64 x (within one ulp of the exact x).
        let mut by_x: Vec<(f64, VertexId)> = self
            .vertices()
            .filter(|v| used[v.index()])
            .map(|v| (self.position(v).x, v))
            .collect();
        by_x.sort_by(|a, b| a.0.total_cmp(&b.0));
        let widen = |x: f64, up: bool| {
            let step = x.abs() * (4.0 * f64::EPSILON) + f64::MIN_POSITIVE;
            if up { x + step } else { x - step }
        };
        for key in boundary {
            if !(self.is_vertex_alive(key.lo) && self.is_vertex_alive(key.hi)) {
                continue;
            }
            let (pa, pb) = (self.position(key.lo), self.position(key.hi));
            let lo = widen(pa.x.min(pb.x), false);
            let hi = widen(pa.x.max(pb.x), true);
            let start = by_x.partition_point(|e| e.0 < lo);
            let (qa, qb) = (self.point_q(key.lo), self.point_q(key.hi));
            let (ymin, ymax) = (widen(pa.y.min(pb.y), false), widen(pa.y.max(pb.y), true));
            for &(x, v) in &by_x[start..] {
                if x > hi {
                    break;
                }
                let y = self.position(v).y;
                if v == key.lo || v == key.hi || y < ymin || y > ymax {
                    continue;
                }
                let p = self.point_q(v);
                if let SegmentIntersection::Touching(_) = segment_intersection(&qa, &qb, &p, &p) {
                    out.push(Defect::TJunction(*key, v));
                }
            }
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::mesh::VertexTag;
    use kurbo::Point;

    /// The unit square's four corners, counter-clockwise from the origin, no faces.
    pub(in crate::mesh) fn square() -> (TriMesh, [VertexId; 4]) {
        let mut m = TriMesh::new();
        let t = VertexTag::default();
        let a = m.add_vertex(Point::new(0.0, 0.0), t);
        let b = m.add_vertex(Point::new(1.0, 0.0), t);
        let c = m.add_vertex(Point::new(1.0, 1.0), t);
        let d = m.add_vertex(Point::new(0.0, 1.0), t);
        (m, [a, b, c, d])
    }

    #[test]
    fn clean_square() {
        let (mut m, [a, b, c, d]) = square();
        m.add_face([a, b, c]);
        m.add_face([a, c, d]);
        m.link_all();
        m.add_edge_tag(a, c, FeatureOn::Secondary { polyline: 0 });
        assert_eq!(m.check(), vec![]);
    }

    #[test]
    fn reports_every_defect() {
        let (mut m, [a, b, c, d]) = square();
        let t = VertexTag::default();
        let mid = m.add_vertex(Point::new(0.5, 0.5), t);
        let lonely = m.add_vertex(Point::new(9.0, 9.0), t);
        let f0 = m.add_face([a, b, c]);
        // T-junction: mid lies on the diagonal a-c, used by the two upper faces only.
        m.add_face([a, mid, d]);
        m.add_face([mid, c, d]);
        let inv = m.add_face([a, d, b]); // clockwise
        m.add_face([c, d, mid]); // a duplicate of (mid, c, d): non-manifold edges
        m.link_all();
        m.set_neighbour(f0, 0, Some(inv)); // asymmetric: inv does not share edge 0 of f0
        m.add_edge_tag(b, d, FeatureOn::Secondary { polyline: 1 });
        m.add_edge_tag(
            a,
            b,
            FeatureOn::Primary {
                section: 0,
                t: [0.0, f64::NAN],
            },
        );
        let defects = m.check();
        let has = |d: &Defect| defects.contains(d);
        assert!(
            has(&Defect::NotCounterClockwise(inv, Orientation::Clockwise)),
            "{defects:?}"
        );
        assert!(has(&Defect::AsymmetricAdjacency(f0, 0)), "{defects:?}");
        assert!(
            has(&Defect::TJunction(EdgeKey::new(a, c), mid)),
            "{defects:?}"
        );
        assert!(has(&Defect::IsolatedVertex(lonely)), "{defects:?}");
        assert!(has(&Defect::BadEdgeTag(EdgeKey::new(a, b))), "{defects:?}");
        assert!(
            !has(&Defect::DanglingEdgeTag(EdgeKey::new(b, d))),
            "b-d is an edge of inv"
        );
        assert!(
            defects
                .iter()
                .any(|d| matches!(d, Defect::NonManifoldEdge(_))),
            "{defects:?}"
        );
    }
}
