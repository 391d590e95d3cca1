//! What a pass works on ([`Scope`]): the whole mesh, or, in the
//! worst-element phase (`repair.rs`), the patch around the bad triangles,
//! with whether its splits are energy-bounded. Every pass takes its scope as
//! an argument; the split pass takes it mutably, since the patch grows by the
//! vertices its splits make.

use super::slot;
use crate::mesh::{EdgeKey, TriMesh, VertexId};
use rayon::prelude::*;

/// [`Scope::edges`] walks the patch's vertices in parallel chunks of at
/// least this many.
const PATCH_CHUNK: usize = 256;

/// The worst-element phase's patch: a flag per vertex slot, and its
/// vertices listed once each (in the order they joined). The passes' edges
/// come from the list: a scan of the flags would go over every vertex slot the
/// mesh ever had (on a large drawing several times the live vertices, for a
/// patch of a few thousand).
#[derive(Default)]
pub(super) struct Patch {
    flags: Vec<bool>,
    list: Vec<VertexId>,
}

impl Patch {
    /// Whether `v` is in the patch.
    fn contains(&self, v: VertexId) -> bool {
        self.flags.get(v.index()).copied().unwrap_or(false)
    }

    /// Put `v` in the patch.
    pub(super) fn insert(&mut self, v: VertexId) {
        let flag = slot(&mut self.flags, v, false);
        if !*flag {
            *flag = true;
            self.list.push(v);
        }
    }
}

/// The vertices whose edges and moves a pass considers.
pub(super) enum Scope {
    /// Every vertex.
    Whole,
    /// The worst-element phase's patch (see `repair.rs`).
    Patch {
        patch: Patch,
        /// Whether splits may not make their faces worse than before or than
        /// a corner of α allows (`Schedule::split_bound`).
        bounded_splits: bool,
    },
}

impl Scope {
    /// Whether `v` may be touched by the passes: everywhere in the whole
    /// mesh, in a patch only its vertices.
    pub(super) fn contains(&self, v: VertexId) -> bool {
        match self {
            Scope::Whole => true,
            Scope::Patch { patch, .. } => patch.contains(v),
        }
    }

    /// Whether the edge `a`–`b` touches the scope ([`Self::contains`]).
    pub(super) fn touches(&self, a: VertexId, b: VertexId) -> bool {
        self.contains(a) || self.contains(b)
    }

    /// Whether the split pass bounds the energy of its splits.
    pub(super) fn bounded_splits(&self) -> bool {
        matches!(
            self,
            Scope::Patch {
                bounded_splits: true,
                ..
            }
        )
    }

    /// Put `v` (a vertex a split made in the scope) in it: a patch grows, the
    /// whole mesh holds it already.
    pub(super) fn insert(&mut self, v: VertexId) {
        if let Scope::Patch { patch, .. } = self {
            patch.insert(v);
        }
    }

    /// The edges of `mesh` the passes consider: every edge of the whole mesh,
    /// those at the patch's vertices (sorted) in a patch.
    pub(super) fn edges(&self, mesh: &TriMesh) -> Vec<EdgeKey> {
        let Scope::Patch { patch, .. } = self else {
            return mesh.edge_list();
        };
        // Found in parallel and sorted (the set does not depend on how it was
        // found). An edge between two patch vertices is listed from its lower
        // end only, so none is listed twice. On the ten slowest dev drawings this ran on the pipeline's
        // thread alone for 0.4 s in all at two threads.
        let mut edges: Vec<EdgeKey> = patch
            .list
            .par_iter()
            .with_min_len(PATCH_CHUNK)
            .filter(|&&v| mesh.is_vertex_alive(v))
            .fold(Vec::new, |mut edges, &v| {
                let ring = crate::mesh::ScratchRing::of(mesh, v);
                edges.extend(
                    ring.neighbours
                        .iter()
                        .filter(|&&w| w > v || !patch.contains(w))
                        .map(|&w| EdgeKey::new(v, w)),
                );
                edges
            })
            .reduce(Vec::new, |mut a, mut b| {
                a.append(&mut b);
                a
            });
        super::queue::sort_unstable(&mut edges);
        debug_assert!(
            edges.windows(2).all(|w| w[0] < w[1]),
            "an edge listed twice"
        );
        edges
    }
}
