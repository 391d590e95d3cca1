//! Vertex rounding: a rational vertex moves to its nearest `f64` point when no
//! invariant breaks (thesis §2.3.4 "Hybrid Kernel"; docs/design.md "Exactness").

use super::invariants::{self, Check, on_curve};
use super::{Context, LocalChange, Outcome, Reject};
use crate::mesh::{Transaction, TriMesh, VertexId};

/// Round the rational vertex `v` to `f64`. [`Reject::NoChange`] when it
/// already is `f64`.
pub(crate) fn try_round(mesh: &mut TriMesh, ctx: &Context, v: VertexId) -> Outcome {
    if !mesh.is_vertex_alive(v) {
        return Outcome::Rejected(Reject::NotAnEdge);
    }
    if !mesh.is_rational(v) {
        return Outcome::Rejected(Reject::NoChange);
    }
    let faces = mesh.vertex_ring(v).faces;
    let budget: Vec<_> = on_curve::budget_now(mesh, ctx, v).into_iter().collect();
    let mut tx = Transaction::new(mesh);
    let p = tx.position(v);
    tx.set_position(v, p);
    let check = Check {
        faces: &faces,
        changed: &[v],
        budgets: &budget,
        old_max_energy: None,
        old_corner_energy: None,
    };
    if let Err(r) = invariants::validate(&tx, ctx, &check) {
        return Outcome::Rejected(r);
    }
    tx.commit();
    Outcome::Applied(LocalChange {
        created: faces,
        moved_vertex: Some(v),
        ..LocalChange::default()
    })
}
