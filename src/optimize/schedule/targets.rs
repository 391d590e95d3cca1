//! The schedule's targets: each vertex's target edge length and the size
//! field at it (its base), which vertices the optimizer refined below the
//! field, and the target of an edge or of a collapse's new edge.
//! `sizing.rs` refines and relaxes the targets.

use super::{FIELD_LINEAR, slot};
use crate::mesh::{EdgeKey, TriMesh, VertexId};
use crate::sizing::SizeField;
use rayon::prelude::*;

/// The target edge length of every vertex, against the size field.
///
/// Without a field (`None`) the field is `l` everywhere; `l` is also the value
/// of a vertex slot with no entry yet. A snapshot is a clone (the field is
/// borrowed).
#[derive(Clone)]
pub(super) struct Targets<'a> {
    /// The size field (`crate::sizing`): what every edge is measured
    /// against (`None`: `l` everywhere).
    field: Option<&'a SizeField>,
    /// The largest size, and the target of a slot with no entry.
    l: f64,
    /// Target edge length by vertex slot.
    target: Vec<f64>,
    /// The size field at the vertex by vertex slot (the largest target: the
    /// optimizer's refinement relaxes and the coarsening resets to it).
    base: Vec<f64>,
    /// By vertex slot: whether the optimizer refined the vertex's target below
    /// the field (around a triangle it could not improve at the field's size).
    refined: Vec<bool>,
}

/// The size field at every vertex slot (`l` at free slots, and everywhere
/// for a uniform field or none).
fn bases(mesh: &TriMesh, field: Option<&SizeField>, l: f64) -> Vec<f64> {
    let mut out = vec![l; mesh.vertex_capacity()];
    let Some(field) = field.filter(|f| !f.is_uniform()) else {
        return out;
    };
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

impl<'a> Targets<'a> {
    /// Every target at the field (`None`: at `l`), nothing refined.
    pub(super) fn new(mesh: &TriMesh, field: Option<&'a SizeField>, l: f64) -> Self {
        let base = bases(mesh, field, l);
        Targets {
            field,
            l,
            target: base.clone(),
            base,
            refined: Vec::new(),
        }
    }

    /// The largest size `l`.
    pub(super) fn l(&self) -> f64 {
        self.l
    }

    /// Whether the field is `l` everywhere (or there is none).
    pub(super) fn is_uniform(&self) -> bool {
        self.field.is_none_or(SizeField::is_uniform)
    }

    /// Whether the user asked for sizes ([`SizeField::is_asked`]).
    pub(super) fn is_asked(&self) -> bool {
        self.field.is_some_and(SizeField::is_asked)
    }

    /// The size field at `p` (`l` where it is uniform).
    pub(super) fn field_at(&self, p: kurbo::Point) -> f64 {
        match self.field {
            Some(field) if !field.is_uniform() => field.at(p),
            _ => self.l,
        }
    }

    pub(super) fn target_of(&self, v: VertexId) -> f64 {
        self.target.get(v.index()).copied().unwrap_or(self.l)
    }

    pub(super) fn base_of(&self, v: VertexId) -> f64 {
        self.base.get(v.index()).copied().unwrap_or(self.l)
    }

    pub(super) fn set_target(&mut self, v: VertexId, t: f64) {
        *slot(&mut self.target, v, self.l) = t;
    }

    pub(super) fn set_base(&mut self, v: VertexId, t: f64) {
        *slot(&mut self.base, v, self.l) = t;
    }

    pub(super) fn is_refined(&self, v: VertexId) -> bool {
        self.refined.get(v.index()).copied().unwrap_or(false)
    }

    pub(super) fn set_refined(&mut self, v: VertexId, refined: bool) {
        *slot(&mut self.refined, v, false) = refined;
    }

    /// The size field at every vertex of `mesh` again (smoothing and
    /// projection move vertices); targets keep their ratio to it.
    pub(super) fn refresh(&mut self, mesh: &TriMesh) {
        if self.is_uniform() {
            return;
        }
        let fresh = bases(mesh, self.field, self.l);
        for v in mesh.vertices() {
            let i = v.index();
            let old = self.base.get(i).copied().unwrap_or(self.l);
            let ratio = self.target.get(i).map_or(1.0, |t| t / old);
            *slot(&mut self.target, v, self.l) = fresh[i] * ratio;
        }
        self.base = fresh;
    }

    /// The target length of edge `k` of `mesh`: the size field at its
    /// midpoint, times its ends' mean refinement (their targets over the field
    /// at them). Where the field at the two ends differs by less than
    /// [`FIELD_LINEAR`], the midpoint's value is their mean (the field is
    /// linear along such an edge to well within the split and collapse bounds,
    /// and no lookup is needed); for a uniform field, the ends' mean target.
    pub(super) fn edge_target(&self, mesh: &TriMesh, k: EdgeKey) -> f64 {
        self.pair_target(mesh, k.lo, k.hi)
    }

    /// [`Self::edge_target`] of the segment from `u` to `w`, an edge or not
    /// (a collapse's new edges are judged as the split pass will judge them).
    pub(super) fn pair_target(&self, mesh: &TriMesh, u: VertexId, w: VertexId) -> f64 {
        let (tu, tw) = (self.target_of(u), self.target_of(w));
        let field = match self.field {
            Some(field) if !field.is_uniform() => field,
            _ => return 0.5 * (tu + tw),
        };
        let (bu, bw) = (self.base_of(u), self.base_of(w));
        let ratio = 0.5 * (tu / bu + tw / bw);
        let h = if bu.max(bw) <= FIELD_LINEAR * bu.min(bw) {
            0.5 * (bu + bw)
        } else {
            let (a, b) = (mesh.position(u), mesh.position(w));
            field.at_mid(a, b)
        };
        h * ratio
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimize::schedule::driver::mesh_bounds;
    use crate::optimize::schedule::test_meshes;

    /// Without a field the targets are those of a uniform field at `l`
    /// (what the curved stage without a field measures against): every
    /// lookup agrees, before and after a vertex is refined.
    #[test]
    fn no_field_is_a_uniform_field_at_l() {
        let l = 0.1;
        for (mesh, _) in test_meshes(2, 2) {
            let field = SizeField::uniform(l, mesh_bounds(&mesh));
            let mut with = Targets::new(&mesh, Some(&field), l);
            let mut without = Targets::new(&mesh, None, l);
            assert!(with.is_uniform() && without.is_uniform());
            assert_eq!(with.is_asked(), without.is_asked());
            let v = mesh.vertices().next().expect("a vertex");
            for t in [&mut with, &mut without] {
                t.set_target(v, 0.5 * l);
                t.refresh(&mesh);
            }
            for k in mesh.edges() {
                let (a, b) = (with.edge_target(&mesh, k), without.edge_target(&mesh, k));
                assert_eq!(a.to_bits(), b.to_bits(), "{k:?}");
            }
            for u in mesh.vertices() {
                assert_eq!(with.target_of(u), without.target_of(u));
                assert_eq!(with.base_of(u), without.base_of(u));
                let p = mesh.position(u);
                assert_eq!(with.field_at(p), without.field_at(p));
            }
        }
    }
}
