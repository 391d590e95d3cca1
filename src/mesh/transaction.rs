//! A journal of changes to a [`TriMesh`] that rolls them back unless committed.
//!
//! Every mutation made through a [`Transaction`] first records the old value of
//! each slot it touches (vertex, face, edge tag) and each free-list push or pop;
//! dropping the guard without [`Transaction::commit`] restores them, so the mesh
//! compares equal (`PartialEq`) to what it was. STYLE "Local operations and
//! invariants", step 2 and 4. Reads go through `Deref<Target = TriMesh>`.
//! The mesh's own mutators are crate-private: outside the crate a mesh
//! changes only through a transaction.

use super::ids::{FaceId, VertexId};
use super::storage::{EdgeKey, FaceData, FeatureOn, TagList, TriMesh, VertexData, VertexTag};
use crate::exact::PointQ;
use kurbo::Point;

#[derive(Clone, Copy, Debug)]
enum FreeOp {
    PushV,
    PopV(VertexId),
    PushF,
    PopF(FaceId),
}

/// The journal's buffers, kept between transactions (one spare set per thread)
/// so that the millions of operations an optimization tries do not allocate
/// them afresh each time.
#[derive(Debug, Default)]
struct Journal {
    old_vertices: Vec<(VertexId, Option<VertexData>)>,
    old_faces: Vec<(FaceId, Option<FaceData>)>,
    old_tags: Vec<(EdgeKey, Option<TagList>)>,
    free_log: Vec<FreeOp>,
    /// Scratch of [`Transaction::replace_faces`]: the faces outside the region
    /// by their shared edge, and the new faces' unmatched edges.
    outside: Vec<(EdgeKey, FaceId)>,
    inner: Vec<(EdgeKey, FaceId, usize)>,
    /// This transaction's number (never 0), and by slot index the number of the
    /// last transaction that journaled the face / vertex: a slot is journaled
    /// once per transaction without searching the journal.
    generation: u32,
    face_mark: Vec<u32>,
    vertex_mark: Vec<u32>,
}

/// Mark slot `i` as journaled in `generation`; whether it was not yet.
fn mark(marks: &mut Vec<u32>, i: usize, generation: u32) -> bool {
    if i >= marks.len() {
        marks.resize(i + 1, 0);
    }
    let fresh = marks[i] != generation;
    marks[i] = generation;
    fresh
}

thread_local! {
    static SPARE: std::cell::Cell<Option<Journal>> = const { std::cell::Cell::new(None) };
}

/// A guard over a mesh: changes made through it are undone on drop unless
/// [`Transaction::commit`] is called.
#[derive(Debug)]
pub(crate) struct Transaction<'a> {
    mesh: &'a mut TriMesh,
    j: Journal,
    vertex_len: usize,
    face_len: usize,
    live: (usize, usize),
    committed: bool,
    /// Whether changes are journaled (see [`Transaction::decided_if`]).
    journaled: bool,
}

impl std::ops::Deref for Transaction<'_> {
    type Target = TriMesh;
    fn deref(&self) -> &TriMesh {
        self.mesh
    }
}

impl<'a> Transaction<'a> {
    /// Open a transaction on `mesh`.
    pub(crate) fn new(mesh: &'a mut TriMesh) -> Self {
        let (vertex_len, face_len) = (mesh.vertices.len(), mesh.faces.len());
        let live = (mesh.live_vertices, mesh.live_faces);
        let mut j = SPARE.with(std::cell::Cell::take).unwrap_or_default();
        j.generation = j.generation.wrapping_add(1);
        if j.generation == 0 {
            // Wrapped: forget every mark (0 is never a live generation).
            j.face_mark.fill(0);
            j.vertex_mark.fill(0);
            j.generation = 1;
        }
        Transaction {
            mesh,
            j,
            vertex_len,
            face_len,
            live,
            committed: false,
            journaled: true,
        }
    }

    /// Open a transaction, for a change already decided when `decided`:
    /// the plan's verdict checked its invariants on the mesh as it is, so the
    /// change is committed, never rolled back, and keeps no journal (no copy
    /// of the old faces, vertices and tags it changes). Debug builds check
    /// the invariants again, which reads the mesh and needs no journal either.
    /// Dropping a decided transaction without [`Transaction::commit`] is a
    /// bug: the mesh keeps whatever the change did so far. `decided` false:
    /// [`Transaction::new`].
    pub(crate) fn decided_if(mesh: &'a mut TriMesh, decided: bool) -> Self {
        let mut tx = Transaction::new(mesh);
        tx.journaled = !decided;
        tx
    }

    /// Keep the changes.
    pub(crate) fn commit(mut self) {
        self.committed = true;
    }

    fn touch_v(&mut self, v: VertexId) {
        if self.journaled && mark(&mut self.j.vertex_mark, v.index(), self.j.generation) {
            let old = self.mesh.vertices.get(v.index()).cloned().flatten();
            self.j.old_vertices.push((v, old));
        }
    }

    fn touch_f(&mut self, f: FaceId) {
        if self.journaled && mark(&mut self.j.face_mark, f.index(), self.j.generation) {
            let old = self.mesh.faces.get(f.index()).cloned().flatten();
            self.j.old_faces.push((f, old));
        }
    }

    fn log(&mut self, op: FreeOp) {
        if self.journaled {
            self.j.free_log.push(op);
        }
    }

    fn touch_tag(&mut self, key: EdgeKey) {
        if self.journaled && !self.j.old_tags.iter().any(|(k, _)| *k == key) {
            let old = self.mesh.edge_tags.get(&key).cloned();
            self.j.old_tags.push((key, old));
        }
    }

    fn before_vertex_insert(&mut self) {
        if let Some(&v) = self.mesh.free_vertices.last() {
            self.log(FreeOp::PopV(v));
            self.touch_v(v);
        } else {
            self.touch_v(VertexId::from_index(self.mesh.vertices.len()));
        }
    }

    /// Add a vertex at an `f64` position, journaled.
    pub(crate) fn add_vertex(&mut self, pos: Point, tag: VertexTag) -> VertexId {
        self.before_vertex_insert();
        self.mesh.add_vertex(pos, tag)
    }

    /// Add a vertex at an exact position (kept rational unless it is an
    /// `f64` point), journaled.
    pub(crate) fn add_vertex_q(&mut self, p: PointQ, tag: VertexTag) -> VertexId {
        self.before_vertex_insert();
        self.mesh.add_vertex_q(p, tag)
    }

    /// Remove a vertex (its slot goes to the free list; faces using it must
    /// be removed first), journaled.
    pub(crate) fn remove_vertex(&mut self, v: VertexId) {
        if self.mesh.is_vertex_alive(v) {
            self.touch_v(v);
            self.log(FreeOp::PushV);
            self.mesh.remove_vertex(v);
        }
    }

    /// Move a vertex to an `f64` position (dropping its rational one), journaled.
    pub(crate) fn set_position(&mut self, v: VertexId, pos: Point) {
        self.touch_v(v);
        self.mesh.set_position(v, pos);
    }

    /// Add a face (vertices counter-clockwise), with no adjacency yet, journaled.
    pub(crate) fn add_face(&mut self, v: [VertexId; 3]) -> FaceId {
        if let Some(&f) = self.mesh.free_faces.last() {
            self.log(FreeOp::PopF(f));
            self.touch_f(f);
        } else {
            self.touch_f(FaceId::from_index(self.mesh.faces.len()));
        }
        for x in v {
            self.touch_v(x);
        }
        self.mesh.add_face(v)
    }

    /// Remove a face (its neighbours forget it, its vertices point to another
    /// live incident face when one is adjacent), journaled.
    pub(crate) fn remove_face(&mut self, f: FaceId) {
        if !self.mesh.is_face_alive(f) {
            return;
        }
        self.touch_f(f);
        for g in self.mesh.neighbours(f).into_iter().flatten() {
            self.touch_f(g);
        }
        for x in self.mesh.face(f) {
            self.touch_v(x);
        }
        self.log(FreeOp::PushF);
        self.mesh.remove_face(f);
    }

    /// Set the face across edge `i` of `f` (one side only), journaled.
    pub(crate) fn set_neighbour(&mut self, f: FaceId, i: usize, g: Option<FaceId>) {
        self.touch_f(f);
        self.mesh.set_neighbour(f, i, g);
    }

    /// Record that the edge `a b` lies on a feature (no duplicate entries; a
    /// primary's `t` is given at `a`, then `b`), journaled.
    pub(crate) fn add_edge_tag(&mut self, a: VertexId, b: VertexId, tag: FeatureOn) {
        self.touch_tag(EdgeKey::new(a, b));
        // (the ends' counts of tagged edges change with the tags)
        self.touch_v(a);
        self.touch_v(b);
        self.mesh.add_edge_tag(a, b, tag);
    }

    /// Remove and return every tag of the edge `a b`, journaled.
    pub(crate) fn take_edge_tags(&mut self, a: VertexId, b: VertexId) -> TagList {
        self.touch_tag(EdgeKey::new(a, b));
        self.touch_v(a);
        self.touch_v(b);
        self.mesh.take_edge_tags(a, b)
    }

    /// Replace the faces `old` (live, forming a region) by faces with the
    /// vertices `new` (counter-clockwise), linking the new faces to each other
    /// and to the faces that were across the region's outer edges. Returns the
    /// new face ids, in the order of `new`. Purely topological.
    pub(crate) fn replace_faces(&mut self, old: &[FaceId], new: &[[VertexId; 3]]) -> Vec<FaceId> {
        // The faces outside the region, by the edge they share with it.
        // Regions are a few faces: linear scans beat hashing here.
        let mut outside = std::mem::take(&mut self.j.outside);
        outside.clear();
        for &f in old {
            for (i, g) in self.mesh.neighbours(f).into_iter().enumerate() {
                if let Some(g) = g.filter(|g| !old.contains(g)) {
                    let (a, b) = self.mesh.edge(f, i);
                    outside.push((EdgeKey::new(a, b), g));
                }
            }
        }
        for &f in old {
            self.remove_face(f);
        }
        let ids: Vec<FaceId> = new.iter().map(|&v| self.add_face(v)).collect();
        let mut inner = std::mem::take(&mut self.j.inner);
        inner.clear();
        for &f in &ids {
            for i in 0..3 {
                let (a, b) = self.mesh.edge(f, i);
                let key = EdgeKey::new(a, b);
                if let Some(pos) = inner.iter().position(|(k, _, _)| *k == key) {
                    let (_, g, j) = inner.swap_remove(pos);
                    self.set_neighbour(f, i, Some(g));
                    self.set_neighbour(g, j, Some(f));
                } else if let Some(&(_, g)) = outside.iter().find(|(k, _)| *k == key) {
                    if let Some(j) = self.mesh.edge_index(g, a, b) {
                        self.set_neighbour(f, i, Some(g));
                        self.set_neighbour(g, j, Some(f));
                    }
                } else {
                    inner.push((key, f, i));
                }
            }
        }
        self.j.outside = outside;
        self.j.inner = inner;
        ids
    }

    fn rollback(&mut self) {
        let m = &mut *self.mesh;
        for op in self.j.free_log.drain(..).rev() {
            match op {
                FreeOp::PushV => {
                    m.free_vertices.pop();
                }
                FreeOp::PopV(v) => m.free_vertices.push(v),
                FreeOp::PushF => {
                    m.free_faces.pop();
                }
                FreeOp::PopF(f) => m.free_faces.push(f),
            }
        }
        m.vertices.truncate(self.vertex_len);
        m.faces.truncate(self.face_len);
        for (v, old) in self.j.old_vertices.drain(..) {
            if let Some(slot) = m.vertices.get_mut(v.index()) {
                *slot = old;
            }
        }
        for (f, old) in self.j.old_faces.drain(..) {
            if let Some(slot) = m.faces.get_mut(f.index()) {
                *slot = old;
            }
        }
        for (key, old) in self.j.old_tags.drain(..) {
            match old {
                Some(list) => {
                    m.edge_tags.insert(key, list);
                }
                None => {
                    m.edge_tags.remove(&key);
                }
            }
        }
        (m.live_vertices, m.live_faces) = self.live;
    }
}

impl Drop for Transaction<'_> {
    fn drop(&mut self) {
        debug_assert!(
            self.committed || self.journaled || std::thread::panicking(),
            "a decided transaction was dropped without a commit"
        );
        if !self.committed && self.journaled {
            self.rollback();
        }
        let mut spare = std::mem::take(&mut self.j);
        spare.old_vertices.clear();
        spare.old_faces.clear();
        spare.old_tags.clear();
        spare.free_log.clear();
        SPARE.with(|s| s.set(Some(spare)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square cut along its diagonal `a c`, which carries a
    /// secondary tag.
    fn split_square() -> (TriMesh, [VertexId; 4], [FaceId; 2]) {
        let (mut m, [a, b, c, d]) = super::super::check::tests::square();
        let f = m.add_face([a, b, c]);
        let g = m.add_face([a, c, d]);
        m.link_all();
        m.add_edge_tag(a, c, FeatureOn::Secondary { polyline: 3 });
        (m, [a, b, c, d], [f, g])
    }

    #[test]
    fn dropped_transaction_restores_the_mesh() {
        let (mut m, [a, b, c, d], [f, g]) = split_square();
        let t = VertexTag::default();
        let before = m.clone();
        {
            let mut tx = Transaction::new(&mut m);
            let e = tx.add_vertex(Point::new(0.5, 0.5), t);
            tx.take_edge_tags(a, c);
            tx.add_edge_tag(a, e, FeatureOn::Secondary { polyline: 3 });
            let new = tx.replace_faces(&[f, g], &[[a, b, e], [b, c, e], [c, d, e], [d, a, e]]);
            assert_eq!(new.len(), 4);
            assert!(tx.check().is_empty(), "{:?}", tx.check());
            tx.set_position(e, Point::new(0.4, 0.5));
        }
        assert_eq!(m, before);
        {
            let mut tx = Transaction::new(&mut m);
            tx.take_edge_tags(a, c);
            tx.replace_faces(&[f, g], &[[a, b, d], [b, c, d]]);
            tx.commit();
        }
        assert_ne!(m, before);
        assert!(m.check().is_empty(), "{:?}", m.check());
    }

    #[test]
    fn a_decided_transaction_makes_the_same_mesh_without_a_journal() {
        let (m, [a, b, c, d], [f, g]) = split_square();
        let t = VertexTag::default();
        let change = |tx: &mut Transaction<'_>| {
            let e = tx.add_vertex(Point::new(0.5, 0.5), t);
            tx.take_edge_tags(a, c);
            tx.add_edge_tag(a, e, FeatureOn::Secondary { polyline: 3 });
            tx.replace_faces(&[f, g], &[[a, b, e], [b, c, e], [c, d, e], [d, a, e]]);
            tx.set_position(e, Point::new(0.4, 0.5));
        };
        let (mut journaled, mut decided) = (m.clone(), m.clone());
        {
            let mut tx = Transaction::decided_if(&mut journaled, false);
            change(&mut tx);
            tx.commit();
        }
        {
            let mut tx = Transaction::decided_if(&mut decided, true);
            change(&mut tx);
            assert!(
                tx.j.old_faces.is_empty()
                    && tx.j.old_vertices.is_empty()
                    && tx.j.old_tags.is_empty()
                    && tx.j.free_log.is_empty()
            );
            tx.commit();
        }
        assert_eq!(journaled, decided);
        assert_ne!(journaled, m);
    }
}
