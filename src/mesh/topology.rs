//! Navigation and adjacency: pure topology, never reads a coordinate.

use super::ids::{FaceId, VertexId};
use super::storage::{EdgeKey, TriMesh};

impl TriMesh {
    /// The directed edge `i` of `f`: from `v[i+1]` to `v[i+2]` (opposite `v[i]`).
    pub(crate) fn edge(&self, f: FaceId, i: usize) -> (VertexId, VertexId) {
        let v = self.face(f);
        (v[(i + 1) % 3], v[(i + 2) % 3])
    }

    /// The local index (0..3) of vertex `v` in face `f`.
    pub(crate) fn local_index(&self, f: FaceId, v: VertexId) -> Option<usize> {
        self.face(f).iter().position(|&x| x == v)
    }

    /// The index of the edge of `f` joining `a` and `b` (either direction).
    pub(crate) fn edge_index(&self, f: FaceId, a: VertexId, b: VertexId) -> Option<usize> {
        (0..3).find(|&i| {
            let (p, q) = self.edge(f, i);
            (p == a && q == b) || (p == b && q == a)
        })
    }

    /// Make `f` and `g` neighbours across their shared edge (both sides).
    /// Returns `false`, changing nothing, if they share no edge.
    pub(crate) fn link(&mut self, f: FaceId, g: FaceId) -> bool {
        for i in 0..3 {
            let (a, b) = self.edge(f, i);
            if let Some(j) = self.edge_index(g, a, b) {
                self.set_neighbour(f, i, Some(g));
                self.set_neighbour(g, j, Some(f));
                return true;
            }
        }
        false
    }

    /// Recompute the adjacency of every live face from scratch. An edge used
    /// by more than two faces (non-manifold) links none of them; `check`
    /// reports it.
    pub(crate) fn link_all(&mut self) {
        use rayon::prelude::*;
        // Every side of every face by its undirected edge, sorted (in
        // parallel): the sides of one edge are then next to each other.
        let mut sides: Vec<((VertexId, VertexId), FaceId, u8)> = self
            .faces
            .par_iter_mut()
            .enumerate()
            .filter_map(|(k, d)| d.as_mut().map(|d| (FaceId::from_index(k), d)))
            .flat_map_iter(|(f, d)| {
                d.adj = [None; 3];
                let v = d.v;
                (0..3u8).map(move |i| {
                    let (a, b) = (v[(i as usize + 1) % 3], v[(i as usize + 2) % 3]);
                    (if a < b { (a, b) } else { (b, a) }, f, i)
                })
            })
            .collect();
        sides.par_sort_unstable_by_key(|&(key, _, _)| key);
        for run in sides.chunk_by(|x, y| x.0 == y.0) {
            if let [(_, f, i), (_, g, j)] = *run {
                self.set_neighbour(f, i as usize, Some(g));
                self.set_neighbour(g, j as usize, Some(f));
            }
        }
    }

    /// The live faces around `v`, found by walking adjacency from
    /// [`TriMesh::vertex_face`] in both directions (a bounded walk): first
    /// counter-clockwise from it, then, if the fan is open, clockwise.
    pub(crate) fn incident_faces(&self, v: VertexId) -> Vec<FaceId> {
        let mut out = Vec::new();
        self.incident_faces_into(v, &mut out);
        out
    }

    /// [`TriMesh::incident_faces`] into `out` (cleared first), so a loop can
    /// reuse one buffer.
    pub(crate) fn incident_faces_into(&self, v: VertexId, out: &mut Vec<FaceId>) {
        out.clear();
        let Some(start) = self.vertex_face(v) else {
            return;
        };
        // The walk reads the face slots directly: it is the hottest loop of the
        // optimizer (one call per ring, a few faces each).
        let slot = |f: FaceId| self.faces.get(f.index()).and_then(Option::as_ref);
        let at = |d: &super::storage::FaceData| d.v.iter().position(|&x| x == v);
        let Some(start_data) = slot(start) else {
            return;
        };
        let Some(start_i) = at(start_data) else {
            return;
        };
        let budget = self.face_capacity() + 1;
        out.push(start);
        // Counter-clockwise: cross the edge v → next, i.e. the edge opposite
        // prev; a dead face (or one without v) ends the walk like a border.
        let (mut data, mut i) = (start_data, start_i);
        let mut closed = false;
        for _ in 0..budget {
            let Some(g) = data.adj[(i + 2) % 3] else {
                break;
            };
            if g == start {
                closed = true;
                break;
            }
            let Some((gd, j)) = slot(g).and_then(|gd| Some((gd, at(gd)?))) else {
                break;
            };
            out.push(g);
            (data, i) = (gd, j);
        }
        if !closed {
            let (mut data, mut i) = (start_data, start_i);
            for _ in 0..budget {
                let Some(g) = data.adj[(i + 1) % 3] else {
                    break;
                };
                if g == start || out.contains(&g) {
                    break;
                }
                let Some((gd, j)) = slot(g).and_then(|gd| Some((gd, at(gd)?))) else {
                    break;
                };
                out.push(g);
                (data, i) = (gd, j);
            }
        }
    }

    /// The live faces on the edge `a b`, into `out` (cleared first), in the
    /// order [`TriMesh::incident_faces`] meets them around `a`: none when `a b`
    /// is not an edge, one on the boundary, two inside (more only where
    /// adjacency is broken).
    pub(crate) fn faces_on_edge(&self, a: VertexId, b: VertexId, out: &mut Vec<FaceId>) {
        self.incident_faces_into(a, out);
        out.retain(|&f| self.face(f).contains(&b));
    }

    /// Whether some live face has the edge `a b` (found around `a`).
    pub(crate) fn has_edge(&self, a: VertexId, b: VertexId) -> bool {
        self.incident_faces(a)
            .iter()
            .any(|&f| self.face(f).contains(&b))
    }

    /// The vertex of `f` that is neither `a` nor `b` (the first one, if `f`
    /// does not hold both).
    pub(crate) fn opposite(&self, f: FaceId, a: VertexId, b: VertexId) -> Option<VertexId> {
        self.face(f).into_iter().find(|&x| x != a && x != b)
    }

    /// The quadrilateral of the two faces `[f, g]` on the edge `a b`, with the
    /// edge as `f` holds it counter-clockwise; `None` when `f` does not hold the
    /// edge or a face has no third vertex.
    pub(crate) fn quad(&self, [f, g]: [FaceId; 2], a: VertexId, b: VertexId) -> Option<EdgeQuad> {
        let i = self.edge_index(f, a, b)?;
        let v = self.face(f);
        let (a, b, c) = (v[(i + 1) % 3], v[(i + 2) % 3], v[i]);
        let d = self.opposite(g, a, b)?;
        Some(EdgeQuad {
            faces: [f, g],
            a,
            b,
            c,
            d,
        })
    }

    /// The quadrilateral around the interior edge `a b` ([`TriMesh::quad`] of
    /// [`TriMesh::faces_on_edge`], `buf` its scratch); `None` unless the edge
    /// has exactly two faces.
    pub(crate) fn edge_quad(
        &self,
        a: VertexId,
        b: VertexId,
        buf: &mut Vec<FaceId>,
    ) -> Option<EdgeQuad> {
        self.faces_on_edge(a, b, buf);
        let [f, g] = buf[..] else { return None };
        self.quad([f, g], a, b)
    }

    /// Every edge of the live faces once, face by face in id order, each edge
    /// at the first face that has it (boundary edges at their one face).
    pub(crate) fn edges(&self) -> impl Iterator<Item = EdgeKey> + '_ {
        self.faces()
            .flat_map(move |f| first_face_edges(f, self.face(f), self.neighbours(f)))
    }

    /// [`TriMesh::edges`] collected, in the same order; in parallel when the
    /// pool has more than one thread (rayon's collect keeps the order).
    pub(crate) fn edge_list(&self) -> Vec<EdgeKey> {
        use rayon::prelude::*;
        if rayon::current_num_threads() == 1 {
            return self.edges().collect();
        }
        self.faces
            .par_iter()
            .enumerate()
            .with_min_len(4096)
            .filter_map(|(k, d)| d.as_ref().map(|d| (FaceId::from_index(k), d.v, d.adj)))
            .flat_map_iter(|(f, v, adj)| first_face_edges(f, v, adj))
            .collect()
    }

    /// The one-ring of `v`: its faces, its distinct neighbours and whether it
    /// is on the boundary.
    pub(crate) fn vertex_ring(&self, v: VertexId) -> VertexRing {
        let mut ring = VertexRing {
            vertex: v,
            faces: Vec::new(),
            neighbours: Vec::new(),
            boundary: false,
        };
        self.vertex_ring_into(v, &mut ring);
        ring
    }

    /// [`TriMesh::vertex_ring`] into `ring` (its buffers reused).
    pub(crate) fn vertex_ring_into(&self, v: VertexId, ring: &mut VertexRing) {
        self.incident_faces_into(v, &mut ring.faces);
        ring.vertex = v;
        ring.neighbours.clear();
        ring.boundary = false;
        // Each neighbour once, in the order the faces first give it: a scan
        // of the few found so far, or a set on a huge ring (a fan of
        // thousands of faces at a fixed vertex made the scan quadratic).
        if ring.faces.len() > LARGE_RING {
            let mut seen = rustc_hash::FxHashSet::default();
            self.ring_neighbours(v, ring, |_, w| seen.insert(w));
        } else {
            self.ring_neighbours(v, ring, |found, w| !found.contains(&w));
        }
    }

    /// The rest of [`Self::vertex_ring_into`]: the neighbours, those that
    /// `new` (given the ones found so far) says are new, and whether the ring
    /// is open.
    fn ring_neighbours(
        &self,
        v: VertexId,
        ring: &mut VertexRing,
        mut new: impl FnMut(&[VertexId], VertexId) -> bool,
    ) {
        for &f in &ring.faces {
            let d = self.fdata(f);
            let (face, adj) = (d.v, d.adj);
            let i = face
                .iter()
                .position(|&x| x == v)
                .expect("internal: incident face has v");
            for k in [1, 2] {
                let w = face[(i + k) % 3];
                if new(&ring.neighbours, w) {
                    ring.neighbours.push(w);
                }
            }
            // The two edges of f at v are opposite v[i+1] and v[i+2].
            if adj[(i + 1) % 3].is_none() || adj[(i + 2) % 3].is_none() {
                ring.boundary = true;
            }
        }
    }

    /// Whether the edge from the ring's vertex to `w` is a boundary edge: one
    /// face of the ring has it, with no face across.
    pub(crate) fn is_boundary_edge(&self, ring: &VertexRing, w: VertexId) -> bool {
        let mut with = ring.faces.iter().filter(|&&f| self.face(f).contains(&w));
        match (with.next(), with.next()) {
            (Some(&f), None) => {
                let i = self
                    .edge_index(f, ring.vertex, w)
                    .expect("internal: edge of f");
                self.neighbours(f)[i].is_none()
            }
            _ => false,
        }
    }
}

/// Faces around a vertex beyond which [`TriMesh::vertex_ring_into`] keeps its
/// neighbours in a set rather than scanning them.
const LARGE_RING: usize = 32;

/// The two triangles on an interior edge and the quadrilateral they form:
/// `f = (a, b, c)` and `g = (b, a, d)`, both counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct EdgeQuad {
    /// `[f, g]`: `f` holds the edge as `a → b`, `g` as `b → a`.
    pub faces: [FaceId; 2],
    /// The edge's first vertex, as `f` holds it.
    pub a: VertexId,
    /// The edge's second vertex, as `f` holds it.
    pub b: VertexId,
    /// The vertex of `f` opposite the edge.
    pub c: VertexId,
    /// The vertex of `g` opposite the edge.
    pub d: VertexId,
}

/// The one-ring of a vertex ([`TriMesh::vertex_ring`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct VertexRing {
    /// The vertex.
    pub vertex: VertexId,
    /// Its live faces, in [`TriMesh::incident_faces`] order.
    pub faces: Vec<FaceId>,
    /// Its distinct neighbour vertices, in the order the faces meet them.
    pub neighbours: Vec<VertexId>,
    /// Whether the vertex is on the mesh boundary (an edge at it has one face).
    pub boundary: bool,
}

impl VertexRing {
    /// A ring of nothing: a buffer for [`TriMesh::vertex_ring_into`].
    pub(crate) fn empty() -> Self {
        VertexRing {
            vertex: VertexId::from_index(0),
            faces: Vec::new(),
            neighbours: Vec::new(),
            boundary: false,
        }
    }
}

thread_local! {
    /// Spare ring buffers for [`ScratchRing`].
    static SPARE_RINGS: std::cell::RefCell<Vec<VertexRing>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The edges of face `f` (vertices `v`, neighbours `adj`) that no face of a
/// smaller id shares: [`TriMesh::edges`] lists each edge at its first face.
fn first_face_edges(
    f: FaceId,
    v: [VertexId; 3],
    adj: [Option<FaceId>; 3],
) -> impl Iterator<Item = EdgeKey> {
    (0..3)
        .filter(move |&i| adj[i].is_none_or(|g| g > f))
        .map(move |i| EdgeKey::new(v[(i + 1) % 3], v[(i + 2) % 3]))
}

/// A vertex ring in a reused buffer (one of a per-thread stack of spares,
/// given back on drop): for the hot paths that need a ring only for a while.
#[derive(Debug)]
pub(crate) struct ScratchRing(VertexRing);

impl ScratchRing {
    /// The ring of `v` ([`TriMesh::vertex_ring`]).
    pub(crate) fn of(mesh: &TriMesh, v: VertexId) -> Self {
        let mut ring = SPARE_RINGS
            .with_borrow_mut(Vec::pop)
            .unwrap_or_else(VertexRing::empty);
        mesh.vertex_ring_into(v, &mut ring);
        ScratchRing(ring)
    }
}

impl std::ops::Deref for ScratchRing {
    type Target = VertexRing;
    fn deref(&self) -> &VertexRing {
        &self.0
    }
}

impl Drop for ScratchRing {
    fn drop(&mut self) {
        let ring = std::mem::replace(&mut self.0, VertexRing::empty());
        SPARE_RINGS.with_borrow_mut(|s| s.push(ring));
    }
}

#[cfg(test)]
mod tests {
    use crate::mesh::{EdgeKey, TriMesh, VertexTag};
    use kurbo::Point;

    #[test]
    fn fan_navigation() {
        // A hexagon fan around a centre vertex, plus one open fan.
        let mut m = TriMesh::new();
        let c = m.add_vertex(Point::ORIGIN, VertexTag::default());
        let ring: Vec<_> = (0..6)
            .map(|k| {
                let a = f64::from(k) * std::f64::consts::PI / 3.0;
                m.add_vertex(Point::new(a.cos(), a.sin()), VertexTag::default())
            })
            .collect();
        let faces: Vec<_> = (0..6)
            .map(|k| m.add_face([c, ring[k], ring[(k + 1) % 6]]))
            .collect();
        m.link_all();
        let mut around = m.incident_faces(c);
        around.sort();
        assert_eq!(around, faces);
        assert_eq!(m.incident_faces(ring[0]).len(), 2);
        m.remove_face(faces[2]);
        let around = m.incident_faces(c);
        assert_eq!(around.len(), 5);
        assert!(m.check().is_empty(), "{:?}", m.check());
        assert_eq!(m.edge_index(faces[0], ring[1], c), Some(1));
    }

    #[test]
    fn edge_queries_on_a_square() {
        // a b c d counter-clockwise, split by the diagonal a c.
        let mut m = TriMesh::new();
        let t = VertexTag::default();
        let [a, b, c, d] = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .map(|(x, y)| m.add_vertex(Point::new(x, y), t));
        let f = m.add_face([a, b, c]);
        let g = m.add_face([a, c, d]);
        m.link_all();
        let mut buf = vec![f; 7];
        m.faces_on_edge(c, a, &mut buf);
        assert_eq!(buf.len(), 2);
        m.faces_on_edge(a, b, &mut buf);
        assert_eq!(buf, [f]);
        m.faces_on_edge(b, d, &mut buf);
        assert!(buf.is_empty());
        assert!(m.has_edge(a, c) && !m.has_edge(b, d));
        assert_eq!(m.opposite(f, a, c), Some(b));
        let q = m.edge_quad(c, a, &mut buf).expect("interior edge");
        assert_eq!(q.faces, [g, f]);
        assert_eq!((q.a, q.b, q.c, q.d), (a, c, d, b));
        assert_eq!(m.edge_quad(a, b, &mut buf), None);
        let mut edges: Vec<EdgeKey> = m.edges().collect();
        edges.sort();
        let mut want = [(a, b), (b, c), (c, d), (d, a), (a, c)].map(|(x, y)| EdgeKey::new(x, y));
        want.sort();
        assert_eq!(edges, want);
        let r = m.vertex_ring(a);
        assert_eq!(r.faces.len(), 2);
        assert_eq!(r.neighbours.len(), 3);
        assert!(r.boundary);
        assert!(m.is_boundary_edge(&r, b) && m.is_boundary_edge(&r, d));
        assert!(!m.is_boundary_edge(&r, c));
    }
}
