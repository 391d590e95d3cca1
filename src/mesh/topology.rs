//! Navigation and adjacency: pure topology, never reads a coordinate.

use super::ids::{FaceId, VertexId};
use super::storage::TriMesh;
use std::collections::HashMap;

impl TriMesh {
    /// The directed edge `i` of `f`: from `v[i+1]` to `v[i+2]` (opposite `v[i]`).
    pub fn edge(&self, f: FaceId, i: usize) -> (VertexId, VertexId) {
        let v = self.face(f);
        (v[(i + 1) % 3], v[(i + 2) % 3])
    }

    /// The local index (0..3) of vertex `v` in face `f`.
    pub fn local_index(&self, f: FaceId, v: VertexId) -> Option<usize> {
        self.face(f).iter().position(|&x| x == v)
    }

    /// The index of the edge of `f` joining `a` and `b` (either direction).
    pub fn edge_index(&self, f: FaceId, a: VertexId, b: VertexId) -> Option<usize> {
        (0..3).find(|&i| {
            let (p, q) = self.edge(f, i);
            (p == a && q == b) || (p == b && q == a)
        })
    }

    /// Make `f` and `g` neighbours across their shared edge (both sides).
    /// Returns `false`, changing nothing, if they share no edge.
    pub fn link(&mut self, f: FaceId, g: FaceId) -> bool {
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
    pub fn link_all(&mut self) {
        let mut by_edge: HashMap<(VertexId, VertexId), Vec<(FaceId, usize)>> = HashMap::new();
        let faces: Vec<FaceId> = self.faces().collect();
        for &f in &faces {
            for i in 0..3 {
                let (a, b) = self.edge(f, i);
                let key = if a < b { (a, b) } else { (b, a) };
                by_edge.entry(key).or_default().push((f, i));
                self.set_neighbour(f, i, None);
            }
        }
        for sides in by_edge.values() {
            if let [(f, i), (g, j)] = sides[..] {
                self.set_neighbour(f, i, Some(g));
                self.set_neighbour(g, j, Some(f));
            }
        }
    }

    /// The live faces around `v`, found by walking adjacency from
    /// [`TriMesh::vertex_face`] in both directions (a bounded walk).
    pub fn incident_faces(&self, v: VertexId) -> Vec<FaceId> {
        let Some(start) = self.vertex_face(v) else {
            return Vec::new();
        };
        if !self.is_face_alive(start) || self.local_index(start, v).is_none() {
            return Vec::new();
        }
        let budget = self.face_capacity() + 1;
        let mut out = vec![start];
        // Counter-clockwise: cross the edge v → next, i.e. the edge opposite prev.
        let step = |f: FaceId, forward: bool| -> Option<FaceId> {
            let i = self.local_index(f, v)?;
            let e = if forward { (i + 2) % 3 } else { (i + 1) % 3 };
            self.neighbours(f)[e].filter(|&g| self.is_face_alive(g))
        };
        let mut f = start;
        let mut closed = false;
        for _ in 0..budget {
            match step(f, true) {
                Some(g) if g == start => {
                    closed = true;
                    break;
                }
                Some(g) => {
                    out.push(g);
                    f = g;
                }
                None => break,
            }
        }
        if !closed {
            let mut f = start;
            for _ in 0..budget {
                match step(f, false) {
                    Some(g) if g != start && !out.contains(&g) => {
                        out.push(g);
                        f = g;
                    }
                    _ => break,
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use crate::mesh::{TriMesh, VertexTag};
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
}
