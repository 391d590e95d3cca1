//! Slots for vertices and faces (with tombstones and free lists), positions and tags.

use super::ids::{FaceId, VertexId};
use crate::exact::{Orientation, PointQ, PointRef, orient2d, orient2d_mixed, orient2d_q};
use kurbo::Point;
use rustc_hash::FxHashMap;
use std::borrow::Cow;

/// What a vertex stands for. All false for an ordinary (Steiner) vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) struct VertexTag {
    /// A corner of the padded box.
    pub box_corner: bool,
    /// An isolated input feature point.
    pub feature_point: bool,
    /// An endpoint of an input feature segment.
    pub segment_endpoint: bool,
    /// An endpoint of a primary feature section (never moves, docs/design.md "Invariants" 4).
    pub section_endpoint: bool,
}

impl VertexTag {
    /// The union of two tags.
    pub(crate) fn union(self, o: VertexTag) -> VertexTag {
        VertexTag {
            box_corner: self.box_corner || o.box_corner,
            feature_point: self.feature_point || o.feature_point,
            segment_endpoint: self.segment_endpoint || o.segment_endpoint,
            section_endpoint: self.section_endpoint || o.section_endpoint,
        }
    }

    /// Whether any flag is set.
    pub(crate) fn any(self) -> bool {
        self != VertexTag::default()
    }
}

/// One input feature an edge lies on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum FeatureOn {
    /// A primary section, with the section parameter at the edge's two ends,
    /// ordered as the [`EdgeKey`] (`t[0]` at the smaller vertex id).
    Primary {
        /// The section index chosen by the caller.
        section: u32,
        /// Parameter at `EdgeKey::lo`, then at `EdgeKey::hi`.
        t: [f64; 2],
    },
    /// A secondary polyline.
    Secondary {
        /// The polyline index chosen by the caller.
        polyline: u32,
    },
}

impl FeatureOn {
    /// The tag as the edge `a b` stores it when it is given with a primary's
    /// `t` at `a`, then `b` ([`TriMesh::add_edge_tag`]): ordered as the key.
    pub(crate) fn keyed(self, a: VertexId, b: VertexId) -> FeatureOn {
        match self {
            FeatureOn::Primary { section, t } if EdgeKey::new(a, b).lo != a => FeatureOn::Primary {
                section,
                t: [t[1], t[0]],
            },
            other => other,
        }
    }
}

/// The features an edge lies on, inline for one (a lookup reads no other
/// allocation; a second feature on an edge is rare).
pub(crate) type TagList = smallvec::SmallVec<[FeatureOn; 1]>;

/// An undirected edge, as its two vertices with `lo < hi`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct EdgeKey {
    /// The smaller vertex id.
    pub lo: VertexId,
    /// The larger vertex id.
    pub hi: VertexId,
}

impl EdgeKey {
    /// The key of the edge between `a` and `b` (in any order).
    pub(crate) fn new(a: VertexId, b: VertexId) -> Self {
        if a <= b {
            EdgeKey { lo: a, hi: b }
        } else {
            EdgeKey { lo: b, hi: a }
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct VertexData {
    pub(super) pos: Point,
    /// The exact position while it is not an `f64` point (boxed: rare, and
    /// large beside the rest, which every position lookup walks over).
    pub(super) exact: Option<Box<PointQ>>,
    pub(super) tag: VertexTag,
    /// Some live incident face, if any.
    pub(super) face: Option<FaceId>,
    /// How many edges at the vertex have tags (entries of
    /// [`TriMesh::edge_tags`] with the vertex as an end): at 0 a tag lookup
    /// at the vertex needs no hash lookup.
    pub(super) tagged: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct FaceData {
    /// Counter-clockwise.
    pub(super) v: [VertexId; 3],
    /// `adj[i]`: the face across edge `i`, the edge opposite `v[i]`.
    pub(super) adj: [Option<FaceId>; 3],
}

/// A triangle mesh with hybrid (f64 / rational) vertex positions.
///
/// Vertex and face slots are tombstoned when removed and reused from free
/// lists, so ids of live elements stay stable across local operations.
///
/// `PartialEq` compares every slot, free list and tag (a rolled-back
/// [`Transaction`](super::Transaction) leaves a mesh equal to before).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct TriMesh {
    pub(super) vertices: Vec<Option<VertexData>>,
    pub(super) faces: Vec<Option<FaceData>>,
    pub(super) free_vertices: Vec<VertexId>,
    pub(super) free_faces: Vec<FaceId>,
    pub(super) edge_tags: FxHashMap<EdgeKey, TagList>,
    pub(super) live_vertices: usize,
    pub(super) live_faces: usize,
}

impl TriMesh {
    /// An empty mesh.
    pub(crate) fn new() -> Self {
        TriMesh::default()
    }

    // ---- vertices ----------------------------------------------------------

    /// Add a vertex at an `f64` position.
    pub(crate) fn add_vertex(&mut self, pos: Point, tag: VertexTag) -> VertexId {
        self.insert_vertex(VertexData {
            pos,
            exact: None,
            tag,
            face: None,
            tagged: 0,
        })
    }

    /// Add a vertex at an exact position (kept rational unless it is an `f64` point).
    pub(crate) fn add_vertex_q(&mut self, p: PointQ, tag: VertexTag) -> VertexId {
        let (pos, exact) = p.to_f64();
        self.add_vertex_rounded(p, pos, exact, tag)
    }

    /// [`Self::add_vertex_q`] with `p`'s nearest `f64` point `pos` and whether
    /// that is `p` exactly, as [`PointQ::to_f64`] gives them (computed
    /// elsewhere, in parallel).
    pub(crate) fn add_vertex_rounded(
        &mut self,
        p: PointQ,
        pos: Point,
        exact: bool,
        tag: VertexTag,
    ) -> VertexId {
        debug_assert!(p.to_f64() == (pos, exact), "internal: not p's rounding");
        self.insert_vertex(VertexData {
            pos,
            exact: (!exact).then(|| Box::new(p)),
            tag,
            face: None,
            tagged: 0,
        })
    }

    fn insert_vertex(&mut self, data: VertexData) -> VertexId {
        self.live_vertices += 1;
        if let Some(v) = self.free_vertices.pop() {
            self.vertices[v.index()] = Some(data);
            v
        } else {
            self.vertices.push(Some(data));
            VertexId::from_index(self.vertices.len() - 1)
        }
    }

    pub(super) fn vdata(&self, v: VertexId) -> &VertexData {
        self.vertices
            .get(v.index())
            .and_then(Option::as_ref)
            .expect("internal: dead or unknown vertex id")
    }

    fn vdata_mut(&mut self, v: VertexId) -> &mut VertexData {
        self.vertices
            .get_mut(v.index())
            .and_then(Option::as_mut)
            .expect("internal: dead or unknown vertex id")
    }

    /// Remove a vertex (its slot goes to the free list). Faces using it must
    /// be removed first; [`TriMesh::check`] reports faces on dead vertices.
    pub(crate) fn remove_vertex(&mut self, v: VertexId) {
        if self.is_vertex_alive(v) {
            self.vertices[v.index()] = None;
            self.free_vertices.push(v);
            self.live_vertices -= 1;
        }
    }

    /// Whether `v` names a live vertex.
    pub(crate) fn is_vertex_alive(&self, v: VertexId) -> bool {
        matches!(self.vertices.get(v.index()), Some(Some(_)))
    }

    /// The live vertices.
    pub(crate) fn vertices(&self) -> impl Iterator<Item = VertexId> + '_ {
        self.vertices
            .iter()
            .enumerate()
            .filter(|(_, d)| d.is_some())
            .map(|(i, _)| VertexId::from_index(i))
    }

    /// Number of live vertices.
    pub(crate) fn num_vertices(&self) -> usize {
        self.live_vertices
    }

    /// Upper bound (exclusive) of vertex indices ever used, for dense side tables.
    pub(crate) fn vertex_capacity(&self) -> usize {
        self.vertices.len()
    }

    /// The `f64` position (the nearest `f64` point while the vertex is rational).
    ///
    /// # Panics
    /// If `v` is not a live vertex.
    pub(crate) fn position(&self, v: VertexId) -> Point {
        self.vdata(v).pos
    }

    /// The exact position, if the vertex is not an `f64` point.
    pub(crate) fn exact(&self, v: VertexId) -> Option<&PointQ> {
        self.vdata(v).exact.as_deref()
    }

    /// Whether the vertex has a rational (not yet rounded) position.
    pub(crate) fn is_rational(&self, v: VertexId) -> bool {
        self.vdata(v).exact.is_some()
    }

    /// The exact position as a rational point.
    pub(crate) fn point_q(&self, v: VertexId) -> PointQ {
        let d = self.vdata(v);
        d.exact
            .as_deref()
            .cloned()
            .unwrap_or_else(|| PointQ::from_point(d.pos))
    }

    /// The exact position, borrowed when the vertex is rational.
    pub(crate) fn point_q_ref(&self, v: VertexId) -> Cow<'_, PointQ> {
        let d = self.vdata(v);
        match &d.exact {
            Some(q) => Cow::Borrowed(q),
            None => Cow::Owned(PointQ::from_point(d.pos)),
        }
    }

    /// The exact orientation of face `f` if vertex `v` were at the `f64` point `p`.
    pub(crate) fn orientation_if_moved(&self, f: FaceId, v: VertexId, p: Point) -> Orientation {
        let at = |x: VertexId| {
            if x == v {
                return PointRef::F64(p);
            }
            let d = self.vdata(x);
            match &d.exact {
                Some(q) => PointRef::Q(q),
                None => PointRef::F64(d.pos),
            }
        };
        let [a, b, c] = self.face(f).map(at);
        orient2d_mixed(a, b, c)
    }

    /// Move a vertex to an `f64` position (drops the rational one).
    pub(crate) fn set_position(&mut self, v: VertexId, pos: Point) {
        let d = self.vdata_mut(v);
        d.pos = pos;
        d.exact = None;
    }

    /// The vertex tag.
    pub(crate) fn vertex_tag(&self, v: VertexId) -> VertexTag {
        self.vdata(v).tag
    }

    /// Replace the vertex tag (the pipeline tags a vertex when it adds it; a
    /// periodic cell's sides are fixed after the BSP, and tests set tags).
    pub(crate) fn set_vertex_tag(&mut self, v: VertexId, tag: VertexTag) {
        self.vdata_mut(v).tag = tag;
    }

    /// Some live face incident to `v`, if any.
    pub(crate) fn vertex_face(&self, v: VertexId) -> Option<FaceId> {
        self.vdata(v).face
    }

    // ---- faces -------------------------------------------------------------

    /// Add a face (vertices counter-clockwise), with no adjacency yet: call
    /// [`TriMesh::link_all`] after a bulk build, or [`TriMesh::set_neighbour`].
    pub(crate) fn add_face(&mut self, v: [VertexId; 3]) -> FaceId {
        let data = FaceData { v, adj: [None; 3] };
        self.live_faces += 1;
        let f = if let Some(f) = self.free_faces.pop() {
            self.faces[f.index()] = Some(data);
            f
        } else {
            self.faces.push(Some(data));
            FaceId::from_index(self.faces.len() - 1)
        };
        for x in v {
            self.vdata_mut(x).face = Some(f);
        }
        f
    }

    pub(super) fn fdata(&self, f: FaceId) -> &FaceData {
        self.faces
            .get(f.index())
            .and_then(Option::as_ref)
            .expect("internal: dead or unknown face id")
    }

    pub(super) fn fdata_mut(&mut self, f: FaceId) -> &mut FaceData {
        self.faces
            .get_mut(f.index())
            .and_then(Option::as_mut)
            .expect("internal: dead or unknown face id")
    }

    /// Remove a face: its neighbours forget it, its vertices point to another
    /// live incident face when one is adjacent, and the slot is freed.
    pub(crate) fn remove_face(&mut self, f: FaceId) {
        if !self.is_face_alive(f) {
            return;
        }
        let data = self.fdata(f).clone();
        for g in data.adj.into_iter().flatten() {
            if let Some(Some(gd)) = self.faces.get_mut(g.index()) {
                for a in &mut gd.adj {
                    if *a == Some(f) {
                        *a = None;
                    }
                }
            }
        }
        self.faces[f.index()] = None;
        self.free_faces.push(f);
        self.live_faces -= 1;
        for (i, &v) in data.v.iter().enumerate() {
            if self.is_vertex_alive(v) && self.vdata(v).face == Some(f) {
                // The faces across the two edges incident to v.
                let cand = [data.adj[(i + 1) % 3], data.adj[(i + 2) % 3]];
                let repl = cand.into_iter().flatten().find(|&g| self.is_face_alive(g));
                self.vdata_mut(v).face = repl;
            }
        }
    }

    /// Whether `f` names a live face.
    pub(crate) fn is_face_alive(&self, f: FaceId) -> bool {
        matches!(self.faces.get(f.index()), Some(Some(_)))
    }

    /// The live faces.
    pub(crate) fn faces(&self) -> impl Iterator<Item = FaceId> + '_ {
        self.faces
            .iter()
            .enumerate()
            .filter(|(_, d)| d.is_some())
            .map(|(i, _)| FaceId::from_index(i))
    }

    /// Number of live faces.
    pub(crate) fn num_faces(&self) -> usize {
        self.live_faces
    }

    /// Upper bound (exclusive) of face indices ever used.
    pub(crate) fn face_capacity(&self) -> usize {
        self.faces.len()
    }

    /// The three vertices of a face, counter-clockwise.
    pub(crate) fn face(&self, f: FaceId) -> [VertexId; 3] {
        self.fdata(f).v
    }

    /// The faces across the three edges (`[i]` is across the edge opposite vertex `i`).
    pub(crate) fn neighbours(&self, f: FaceId) -> [Option<FaceId>; 3] {
        self.fdata(f).adj
    }

    /// Set the face across edge `i` of `f` (one side only; see [`TriMesh::link`]).
    pub(crate) fn set_neighbour(&mut self, f: FaceId, i: usize, g: Option<FaceId>) {
        self.fdata_mut(f).adj[i] = g;
    }

    /// The exact orientation of a face (filtered; rationals only where needed).
    pub(crate) fn orientation(&self, f: FaceId) -> Orientation {
        let [a, b, c] = self.face(f);
        self.orientation_of(a, b, c)
    }

    /// The exact orientation of three vertices.
    pub(crate) fn orientation_of(&self, a: VertexId, b: VertexId, c: VertexId) -> Orientation {
        let (da, db, dc) = (self.vdata(a), self.vdata(b), self.vdata(c));
        if da.exact.is_none() && db.exact.is_none() && dc.exact.is_none() {
            orient2d(da.pos, db.pos, dc.pos)
        } else {
            orient2d_q(
                &self.point_q_ref(a),
                &self.point_q_ref(b),
                &self.point_q_ref(c),
            )
        }
    }

    // ---- edge tags ---------------------------------------------------------

    /// The features the edge `a b` lies on (empty when untagged).
    pub(crate) fn edge_tags(&self, a: VertexId, b: VertexId) -> &[FeatureOn] {
        if !(self.may_have_tagged_edges(a) && self.may_have_tagged_edges(b)) {
            return &[];
        }
        self.edge_tags
            .get(&EdgeKey::new(a, b))
            .map_or(&[][..], TagList::as_slice)
    }

    /// Whether some edge at `v` may have tags: `false` only for a live vertex
    /// none of whose edges has any.
    pub(crate) fn may_have_tagged_edges(&self, v: VertexId) -> bool {
        match self.vertices.get(v.index()) {
            Some(Some(d)) => d.tagged > 0,
            _ => true,
        }
    }

    /// Count one tagged edge more (`up`) or less at `v`, if it is live.
    fn count_tagged(&mut self, v: VertexId, up: bool) {
        if let Some(Some(d)) = self.vertices.get_mut(v.index()) {
            if up {
                d.tagged += 1;
            } else {
                d.tagged = d.tagged.saturating_sub(1);
            }
        }
    }

    /// Record that the edge `a b` lies on a feature (no duplicate entries).
    /// For a primary, `t_a` / `t_b` are the parameters at `a` / `b`.
    pub(crate) fn add_edge_tag(&mut self, a: VertexId, b: VertexId, tag: FeatureOn) {
        use std::collections::hash_map::Entry;
        let tag = tag.keyed(a, b);
        match self.edge_tags.entry(EdgeKey::new(a, b)) {
            Entry::Occupied(mut list) => {
                if !list.get().contains(&tag) {
                    list.get_mut().push(tag);
                }
            }
            Entry::Vacant(slot) => {
                slot.insert(smallvec::smallvec![tag]);
                self.count_tagged(a, true);
                self.count_tagged(b, true);
            }
        }
    }

    /// Remove and return every tag of the edge `a b`.
    pub(crate) fn take_edge_tags(&mut self, a: VertexId, b: VertexId) -> TagList {
        match self.edge_tags.remove(&EdgeKey::new(a, b)) {
            Some(list) => {
                self.count_tagged(a, false);
                self.count_tagged(b, false);
                list
            }
            None => TagList::new(),
        }
    }

    /// The number of tagged edges at `v` as stored (the check compares it
    /// with the tags).
    pub(super) fn tagged_count(&self, v: VertexId) -> u32 {
        self.vdata(v).tagged
    }

    /// Every tagged edge with its tags.
    pub(crate) fn tagged_edges(&self) -> impl Iterator<Item = (EdgeKey, &[FeatureOn])> + '_ {
        self.edge_tags.iter().map(|(k, v)| (*k, v.as_slice()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_are_reused() {
        let mut m = TriMesh::new();
        let a = m.add_vertex(Point::new(0.0, 0.0), VertexTag::default());
        let b = m.add_vertex(Point::new(1.0, 0.0), VertexTag::default());
        let c = m.add_vertex(Point::new(0.0, 1.0), VertexTag::default());
        let f = m.add_face([a, b, c]);
        assert_eq!(m.orientation(f), Orientation::CounterClockwise);
        m.remove_face(f);
        assert_eq!(m.num_faces(), 0);
        assert_eq!(m.vertex_face(a), None);
        let g = m.add_face([a, c, b]);
        assert_eq!(g, f);
        assert_eq!(m.orientation(g), Orientation::Clockwise);
        m.remove_face(g);
        m.remove_vertex(b);
        let d = m.add_vertex(Point::new(5.0, 5.0), VertexTag::default());
        assert_eq!(d, b);
        assert_eq!(m.num_vertices(), 3);
    }

    #[test]
    fn primary_tags_follow_key_order() {
        let mut m = TriMesh::new();
        let a = m.add_vertex(Point::new(0.0, 0.0), VertexTag::default());
        let b = m.add_vertex(Point::new(1.0, 0.0), VertexTag::default());
        m.add_edge_tag(
            b,
            a,
            FeatureOn::Primary {
                section: 2,
                t: [0.75, 0.25],
            },
        );
        m.add_edge_tag(
            a,
            b,
            FeatureOn::Primary {
                section: 2,
                t: [0.25, 0.75],
            },
        );
        assert_eq!(
            m.edge_tags(a, b),
            &[FeatureOn::Primary {
                section: 2,
                t: [0.25, 0.75]
            }]
        );
    }
}
