//! The schedule's sizing: the refinement of the targets ([`Targets`]) around
//! the worst triangles and their relaxation elsewhere, the edges' stretch
//! against their targets (the stop rule's, and whether the field is resolved
//! yet), and the collapses' length rule ([`lengths_kept`]).

use super::stats::locked;
use super::targets::Targets;
use super::{
    LinearOptions, REFINED_BELOW, SIZING_RADIUS, SIZING_REFINE, SIZING_RELAX, SIZING_STOP_FRACTION,
    SIZING_WORST_DIVISOR, SPLIT_ABOVE, Schedule, Stretch,
};
use crate::element::energy::amips;
use crate::mesh::{TriMesh, VertexId, VertexRing};
use rayon::prelude::*;

/// Whether collapsing `v` into `u` makes no edge longer than `stretch` times
/// its target (`targets.pair_target(u, w)`: what the split pass would compare
/// it with; `stretch.open` where the target is `l`, `stretch.below`
/// elsewhere), `ring_v` being v's ring. In the main passes both are the split
/// bound: else the split pass would cut such an edge again and the two passes
/// would undo each other forever.
pub(super) fn lengths_kept(
    mesh: &TriMesh,
    targets: &Targets,
    stretch: Stretch,
    u: VertexId,
    ring_v: &VertexRing,
) -> bool {
    let pu = mesh.position(u);
    let l = targets.l();
    ring_v.neighbours.iter().all(|&w| {
        if w == u {
            return true;
        }
        let t = targets.pair_target(mesh, u, w);
        let s = if t >= l * REFINED_BELOW {
            stretch.open
        } else {
            stretch.below
        };
        pu.distance(mesh.position(w)) <= s * t
    })
}

impl Schedule<'_, LinearOptions> {
    /// Whether some edge is longer than the split bound of the field (only
    /// looked at when the field is not uniform: the BSP mesh knows nothing of it).
    pub(super) fn sizes_pending(&self) -> bool {
        let (mesh, targets): (&TriMesh, &Targets) = (self.mesh, &self.targets);
        !targets.is_uniform()
            && mesh
                .edge_list()
                .into_par_iter()
                .any(|k| mesh.distance(k.lo, k.hi) > SPLIT_ABOVE * targets.edge_target(mesh, k))
    }

    /// The longest edge over its target (the stop rule's stretch).
    pub(super) fn longest_stretch(&self) -> f64 {
        let (mesh, targets): (&TriMesh, &Targets) = (self.mesh, &self.targets);
        mesh.edge_list()
            .into_par_iter()
            .map(|k| mesh.distance(k.lo, k.hi) / targets.edge_target(mesh, k))
            .reduce(|| 0.0, f64::max)
    }

    /// Refine the sizing field where the worst triangles are, relax it
    /// elsewhere. A triangle is bad when its energy exceeds
    /// `max(worst / 100, 0.9 · stop energy)` (only the worst ones drive
    /// refinement); each vertex of a bad triangle gets its target halved, and
    /// vertices within `1.8 l` of one (scaled like the target) are refined less
    /// the farther they are, so the sizing field grades smoothly. Every other
    /// target grows by 1.5. Targets stay in `[l_floor, l]`. Returns whether some
    /// target hit the floor.
    pub(super) fn update_sizing(&mut self, worst: f64) -> bool {
        // Collapses refused by the length rule under the old sizes may pass
        // under the new ones; every other refusal depends on the faces around
        // the edge alone.
        self.memos.forget_length_refusals();
        let threshold =
            (worst / SIZING_WORST_DIVISOR).max(SIZING_STOP_FRACTION * self.driver.stop_energy);
        let faces: Vec<_> = self.mesh.faces().collect();
        let mesh: &TriMesh = self.mesh;
        let mut seeds: Vec<VertexId> = faces
            .into_par_iter()
            .filter_map(|f| {
                let v = mesh.face(f);
                let [a, b, c] = v.map(|x| mesh.position(x));
                (amips(a, b, c) > threshold && !locked(mesh, v)).then_some(v)
            })
            .flatten_iter()
            .collect();
        seeds.sort_unstable();
        seeds.dedup();
        let (mult, _) = self.refine_multipliers(&seeds, SIZING_RELAX);
        let mut hit_floor = false;
        let verts: Vec<VertexId> = self.mesh.vertices().collect();
        let l_floor = self.driver.l_floor;
        for v in verts {
            let t = self.targets.target_of(v) * mult[v.index()];
            if t < l_floor {
                hit_floor = true;
            }
            let top = self.targets.base_of(v);
            let t = t.clamp(l_floor.min(top), top);
            if t < top * REFINED_BELOW {
                self.targets.set_refined(v, true);
            }
            self.targets.set_target(v, t);
        }
        hit_floor
    }

    /// The target multipliers around `seeds`, found breadth-first:
    /// [`SIZING_REFINE`] at a seed, growing linearly to 1 at [`SIZING_RADIUS`]
    /// times the seed's target, and `rest` at every vertex out of reach of
    /// all seeds. Also the vertices within reach, the seeds first.
    pub(super) fn refine_multipliers(
        &self,
        seeds: &[VertexId],
        rest: f64,
    ) -> (Vec<f64>, Vec<VertexId>) {
        let cap = self.mesh.vertex_capacity();
        let mut mult = vec![rest; cap];
        let mut seen = vec![false; cap];
        let mut queue = std::collections::VecDeque::new();
        for &v in seeds {
            mult[v.index()] = SIZING_REFINE;
            seen[v.index()] = true;
            queue.push_back((v, v));
        }
        let mut reached: Vec<VertexId> = seeds.to_vec();
        while let Some((v, seed)) = queue.pop_front() {
            let radius = SIZING_RADIUS * self.targets.target_of(seed);
            let ps = self.mesh.position(seed);
            for &w in &crate::mesh::ScratchRing::of(self.mesh, v).neighbours {
                let i = w.index();
                if seen[i] {
                    continue;
                }
                seen[i] = true;
                let dist = self.mesh.position(w).distance(ps);
                if dist < radius {
                    let m = SIZING_REFINE + (1.0 - SIZING_REFINE) * dist / radius;
                    mult[i] = mult[i].min(m);
                    queue.push_back((w, seed));
                    reached.push(w);
                }
            }
        }
        (mult, reached)
    }
}
