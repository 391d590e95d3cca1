//! Vertex projection (thesis §4.4.1 "Vertex Projection", docs/design.md "Invariants" 5):
//! a primary vertex that the BSP (or a fallback split) left near but off its
//! curve moves toward its curve point `c(t)`, as far as the other invariants
//! allow: all the way if possible, else the largest of a few fractions of the
//! way. It never moves away from the curve, and its parameter `t` stays the
//! one its edges carry, so a later projection or smoothing finishes the job
//! once the mesh around it has moved.

use super::invariants::{self, Check, on_curve};
use super::{Context, CurveBudget, LocalChange, Outcome, Reject, Role, role};
use crate::mesh::{Transaction, TriMesh, VertexId};

/// Fractions of the way to the curve point tried, in order.
const FRACTIONS: [f64; 5] = [1.0, 0.5, 0.25, 0.125, 0.0625];

/// Move the off-curve primary vertex `v` toward its curve point `c(t)`.
///
/// Rejected with [`Reject::NoChange`] for a vertex already on its curve (within
/// `ctx.on_curve_abs`), [`Reject::FixedVertex`] for one that may not move, and
/// with the last refusing invariant when no fraction of the move is allowed.
/// The energy rule does not apply: the move restores an invariant.
pub(crate) fn try_project(mesh: &mut TriMesh, ctx: &Context, v: VertexId) -> Outcome {
    if !mesh.is_vertex_alive(v) {
        return Outcome::Rejected(Reject::NotAnEdge);
    }
    let r = mesh.vertex_ring(v);
    let (section, t) = match role(mesh, v, &r) {
        Role::Primary { section, t, .. } => (section, t),
        Role::Fixed | Role::Boundary => return Outcome::Rejected(Reject::FixedVertex),
        Role::Free | Role::Secondary | Role::SecondaryJunction => {
            return Outcome::Rejected(Reject::NoChange);
        }
    };
    let Some(s) = ctx.section(section) else {
        return Outcome::Rejected(Reject::FeatureRule);
    };
    let off = on_curve::off_curve(mesh, ctx, v).unwrap_or(0.0);
    if off <= ctx.on_curve_abs || !off.is_finite() {
        return Outcome::Rejected(Reject::NoChange);
    }
    let target = s.parent.eval(t);
    let from = mesh.position(v);
    let mut last = Reject::NoChange;
    for s in FRACTIONS {
        let p = if s == 1.0 {
            target
        } else {
            from.lerp(target, s)
        };
        if p == from {
            break;
        }
        let mut tx = Transaction::new(mesh);
        tx.set_position(v, p);
        // Strictly closer than before (or on the curve).
        let budgets = [CurveBudget {
            vertex: v,
            max_off: if s == 1.0 { 0.0 } else { off * (1.0 - 0.5 * s) },
        }];
        let check = Check {
            faces: &r.faces,
            changed: &[v],
            budgets: &budgets,
            old_max_energy: None,
            old_corner_energy: None,
        };
        match invariants::validate(&tx, ctx, &check) {
            Ok(()) => {
                tx.commit();
                return Outcome::Applied(LocalChange {
                    created: r.faces,
                    moved_vertex: Some(v),
                    ..LocalChange::default()
                });
            }
            Err(e) => last = e,
        }
    }
    Outcome::Rejected(last)
}
