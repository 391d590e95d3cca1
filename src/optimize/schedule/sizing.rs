//! The schedule's sizing: each vertex's target against the size field (the
//! bases, refined around the worst triangles and relaxed elsewhere), the
//! target of an edge or of a collapse's new edge, and the collapses' length
//! rule ([`lengths_kept`]).

use super::stats::locked;
use super::{
    FIELD_LINEAR, REFINED_BELOW, SIZING_RADIUS, SIZING_REFINE, SIZING_RELAX, SIZING_STOP_FRACTION,
    SIZING_WORST_DIVISOR, SPLIT_ABOVE, Schedule, Stretch, slot,
};
use crate::element::energy::amips;
use crate::mesh::{EdgeKey, TriMesh, VertexId, VertexRing};
use crate::sizing::SizeField;
use rayon::prelude::*;

/// Whether collapsing `v` into `u` makes no edge longer than `stretch` times
/// its target (`target(u, w)`: what the split pass would compare it with;
/// `stretch.open` where the target is `l`, `stretch.below` elsewhere), `ring_v`
/// being v's ring. In the main passes both are the split bound: else the
/// split pass would cut such an edge again and the two passes would undo each
/// other forever.
pub(super) fn lengths_kept(
    mesh: &TriMesh,
    target: impl Fn(VertexId, VertexId) -> f64,
    l: f64,
    stretch: Stretch,
    u: VertexId,
    ring_v: &VertexRing,
) -> bool {
    let pu = mesh.position(u);
    ring_v.neighbours.iter().all(|&w| {
        if w == u {
            return true;
        }
        let t = target(u, w);
        let s = if t >= l * REFINED_BELOW {
            stretch.open
        } else {
            stretch.below
        };
        pu.distance(mesh.position(w)) <= s * t
    })
}

/// The size field at every vertex slot (`l` at free slots).
pub(super) fn bases(mesh: &TriMesh, field: &SizeField, l: f64) -> Vec<f64> {
    let mut out = vec![l; mesh.vertex_capacity()];
    if field.is_uniform() {
        return out;
    }
    let verts: Vec<VertexId> = mesh.vertices().collect();
    let vals: Vec<f64> = verts
        .par_iter()
        .map(|&v| field.at(mesh.position(v)))
        .collect();
    for (v, h) in verts.into_iter().zip(vals) {
        out[v.index()] = h;
    }
    out
}

impl Schedule<'_> {
    pub(super) fn target_of(&self, v: VertexId) -> f64 {
        self.target.get(v.index()).copied().unwrap_or(self.opts.l)
    }

    pub(super) fn base_of(&self, v: VertexId) -> f64 {
        self.base.get(v.index()).copied().unwrap_or(self.opts.l)
    }

    pub(super) fn set_base(&mut self, v: VertexId, t: f64) {
        *slot(&mut self.base, v, self.opts.l) = t;
    }

    pub(super) fn is_refined(&self, v: VertexId) -> bool {
        self.refined.get(v.index()).copied().unwrap_or(false)
    }

    /// The size field at every vertex again (smoothing and projection move
    /// vertices); targets keep their ratio to it.
    pub(super) fn refresh_bases(&mut self) {
        if self.field.is_uniform() {
            return;
        }
        let fresh = bases(self.mesh, self.field, self.opts.l);
        for v in self.mesh.vertices() {
            let i = v.index();
            let old = self.base.get(i).copied().unwrap_or(self.opts.l);
            let ratio = self.target.get(i).map_or(1.0, |t| t / old);
            *slot(&mut self.target, v, self.opts.l) = fresh[i] * ratio;
        }
        self.base = fresh;
    }

    /// Whether some edge is longer than the split bound of the field (only
    /// looked at when the field is not uniform: the BSP mesh knows nothing of it).
    pub(super) fn sizes_pending(&self) -> bool {
        !self.field.is_uniform()
            && self
                .mesh
                .edge_list()
                .into_par_iter()
                .any(|k| self.mesh.distance(k.lo, k.hi) > SPLIT_ABOVE * self.edge_target(k))
    }

    /// The longest edge over its target (the stop rule's stretch).
    pub(super) fn longest_stretch(&self) -> f64 {
        self.mesh
            .edge_list()
            .into_par_iter()
            .map(|k| self.mesh.distance(k.lo, k.hi) / self.edge_target(k))
            .reduce(|| 0.0, f64::max)
    }

    /// The target length of edge `k`: the size field at its midpoint, times
    /// its ends' mean refinement (their targets over the field at them). Where
    /// the field at the two ends differs by less than [`FIELD_LINEAR`], the
    /// midpoint's value is their mean (the field is linear along such an edge
    /// to well within the split and collapse bounds, and no lookup is needed);
    /// for a uniform field, the ends' mean target.
    pub(super) fn edge_target(&self, k: EdgeKey) -> f64 {
        self.pair_target(k.lo, k.hi)
    }

    /// [`Self::edge_target`] of the segment from `u` to `w`, an edge or not
    /// (a collapse's new edges are judged as the split pass will judge them).
    pub(super) fn pair_target(&self, u: VertexId, w: VertexId) -> f64 {
        let (tu, tw) = (self.target_of(u), self.target_of(w));
        if self.field.is_uniform() {
            return 0.5 * (tu + tw);
        }
        let (bu, bw) = (self.base_of(u), self.base_of(w));
        let ratio = 0.5 * (tu / bu + tw / bw);
        let h = if bu.max(bw) <= FIELD_LINEAR * bu.min(bw) {
            0.5 * (bu + bw)
        } else {
            let (a, b) = (self.mesh.position(u), self.mesh.position(w));
            self.field.at_mid(a, b)
        };
        h * ratio
    }

    pub(super) fn set_target(&mut self, v: VertexId, t: f64) {
        *slot(&mut self.target, v, self.opts.l) = t;
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
        self.failed_collapse.retain(|_, f| !f.by_length);
        let threshold =
            (worst / SIZING_WORST_DIVISOR).max(SIZING_STOP_FRACTION * self.opts.stop_energy);
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
        for v in verts {
            let t = self.target_of(v) * mult[v.index()];
            if t < self.opts.l_floor {
                hit_floor = true;
            }
            let top = self.base_of(v);
            let t = t.clamp(self.opts.l_floor.min(top), top);
            if t < top * REFINED_BELOW {
                *slot(&mut self.refined, v, false) = true;
            }
            self.set_target(v, t);
        }
        hit_floor
    }
}

impl Schedule<'_> {
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
            let radius = SIZING_RADIUS * self.target_of(seed);
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
