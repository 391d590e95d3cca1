//! Typed `u32` handles for vertices and faces.

/// A vertex of a [`TriMesh`](super::TriMesh). `Debug` prints `v12`.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct VertexId(pub u32);

/// A triangle of a [`TriMesh`](super::TriMesh). `Debug` prints `f3`.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct FaceId(pub u32);

impl VertexId {
    pub(super) fn idx(self) -> usize {
        self.0 as usize
    }
}

impl FaceId {
    pub(super) fn idx(self) -> usize {
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
    fn short_debug() {
        assert_eq!(format!("{:?}", VertexId(12)), "v12");
        assert_eq!(format!("{:?}", FaceId(3)), "f3");
    }
}
