//! Typed `u32` handles for vertices and faces.
//!
//! Each stores its slot index plus one, non-zero, so that an `Option` of an
//! id takes four bytes: a face's three neighbours, `[Option<FaceId>; 3]`, take
//! 12 bytes instead of 24, and a face slot 24 instead of 36 (the walks around
//! a vertex, the optimizer's hottest loop, read a face slot per step).

use std::num::NonZeroU32;

/// A vertex of a [`TriMesh`](super::TriMesh). `Debug` prints `v12`.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct VertexId(NonZeroU32);

/// A triangle of a [`TriMesh`](super::TriMesh). `Debug` prints `f3`.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct FaceId(NonZeroU32);

/// Slot `i` as stored: `i + 1`.
fn to_u32(i: usize) -> NonZeroU32 {
    u32::try_from(i)
        .ok()
        .and_then(|i| i.checked_add(1))
        .and_then(NonZeroU32::new)
        .expect("internal: more than u32::MAX - 1 mesh elements")
}

impl VertexId {
    /// The id of vertex slot `i`.
    ///
    /// # Panics
    /// If `i` does not fit in a `u32`.
    pub(crate) fn from_index(i: usize) -> Self {
        VertexId(to_u32(i))
    }

    /// The slot index, for dense side tables (below
    /// [`TriMesh::vertex_capacity`](super::TriMesh::vertex_capacity)).
    pub(crate) fn index(self) -> usize {
        (self.0.get() - 1) as usize
    }
}

impl FaceId {
    /// The id of face slot `i`.
    ///
    /// # Panics
    /// If `i` does not fit in a `u32`.
    pub(crate) fn from_index(i: usize) -> Self {
        FaceId(to_u32(i))
    }

    /// The slot index, for dense side tables (below
    /// [`TriMesh::face_capacity`](super::TriMesh::face_capacity)).
    pub(crate) fn index(self) -> usize {
        (self.0.get() - 1) as usize
    }
}

impl std::fmt::Debug for VertexId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "v{}", self.index())
    }
}

impl std::fmt::Debug for FaceId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "f{}", self.index())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_debug_and_index() {
        assert_eq!(format!("{:?}", VertexId::from_index(12)), "v12");
        assert_eq!(format!("{:?}", FaceId::from_index(3)), "f3");
        assert_eq!(VertexId::from_index(7).index(), 7);
        assert_eq!(FaceId::from_index(0).index(), 0);
        assert!(VertexId::from_index(2) < VertexId::from_index(3));
        assert_eq!(std::mem::size_of::<Option<FaceId>>(), 4);
        // a face slot: three vertices and three neighbours, the `None` of a
        // dead slot in a vertex id's niche
        assert_eq!(
            std::mem::size_of::<Option<super::super::storage::FaceData>>(),
            24
        );
    }
}
