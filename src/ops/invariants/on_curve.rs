//! Invariants 4 and 5: a vertex on a primary section lies on its curve at its
//! tracked parameter, and one the BSP left off the curve never moves away
//! from it (docs/design.md "Invariants" 4, 5; thesis §4.4.1 "Vertex Projection").
//!
//! A vertex's parameter is read from the primary tags of its edges; all tags
//! of one section must agree on it.

use super::super::{Context, CurveBudget, t_at};
use crate::mesh::{EdgeKey, FeatureOn, TriMesh, VertexId};

/// The distance from a primary vertex to its curve points `c(t)` (the largest
/// over the sections and parameters its edges give it; a curve that passes
/// through the vertex twice gives two), or `None` for a vertex on no primary
/// edge. `Some(∞)` when an edge names an unknown section.
pub(crate) fn off_curve(mesh: &TriMesh, ctx: &Context, v: VertexId) -> Option<f64> {
    let mut seen: Vec<(u32, f64)> = Vec::new();
    let ring = crate::mesh::ScratchRing::of(mesh, v);
    for &w in &ring.neighbours {
        let key = EdgeKey::new(v, w);
        for tag in mesh.edge_tags(v, w) {
            if let FeatureOn::Primary { section, t } = *tag {
                let tv = t_at(key, t, v);
                // A curve through the vertex twice (a self-crossing split
                // there) carries two parameters: both must map to it.
                if !seen.contains(&(section, tv)) {
                    seen.push((section, tv));
                }
            }
        }
    }
    if seen.is_empty() {
        return None;
    }
    let p = mesh.position(v);
    let mut worst: f64 = 0.0;
    for (section, t) in seen {
        let Some(s) = ctx.section(section) else {
            return Some(f64::INFINITY);
        };
        worst = worst.max(p.distance(s.parent.eval(t)));
    }
    Some(worst)
}

/// Whether each budgeted vertex is within its allowed distance of its curve
/// (or within `ctx.on_curve_abs`, always allowed).
pub(crate) fn holds(mesh: &TriMesh, ctx: &Context, budgets: &[CurveBudget]) -> bool {
    budgets
        .iter()
        .all(|b| match off_curve(mesh, ctx, b.vertex) {
            None => true,
            Some(d) => d <= ctx.on_curve_abs.max(b.max_off),
        })
}

/// The budget of a vertex about to move: its current distance (never farther).
pub(crate) fn budget_now(mesh: &TriMesh, ctx: &Context, v: VertexId) -> Option<CurveBudget> {
    off_curve(mesh, ctx, v).map(|d| CurveBudget {
        vertex: v,
        max_off: d,
    })
}
