//! Typed `u32` handles for vertices and faces.

/// A vertex of a [`TriMesh`](super::TriMesh). `Debug` prints `v12`.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct VertexId(u32);

/// A triangle of a [`TriMesh`](super::TriMesh). `Debug` prints `f3`.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct FaceId(u32);

fn to_u32(i: usize) -> u32 {
    u32::try_from(i).expect("internal: more than u32::MAX mesh elements")
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
        self.0 as usize
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
        self.0 as usize
    }
}

impl std::fmt::Debug for VertexId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "v{}", self.0)
    }
}

impl std::fmt::Debug for FaceId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "f{}", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_debug_and_index() {
        assert_eq!(format!("{:?}", VertexId(12)), "v12");
        assert_eq!(format!("{:?}", FaceId(3)), "f3");
        assert_eq!(VertexId::from_index(7).index(), 7);
        assert_eq!(FaceId::from_index(0), FaceId(0));
    }
}
