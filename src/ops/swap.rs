//! Edge swap: the diagonal `a b` of the quadrilateral of its two triangles is
//! replaced by the other diagonal `c d`. Never on a feature edge (§4.4.1
//! "Feature Handling" 3) nor on the mesh boundary.

use super::invariants::{self, Check};
use super::{Context, LocalChange, Outcome, Reject, max_energy};
use crate::mesh::{FaceId, Transaction, TriMesh, VertexId};

/// Everything a swap needs, gathered from `&TriMesh`.
#[derive(Clone, Debug)]
pub struct SwapPlan {
    faces: [FaceId; 2],
    new: [[VertexId; 3]; 2],
    c: VertexId,
    d: VertexId,
    old_max_energy: f64,
}

impl SwapPlan {
    /// Plan the swap of the edge `a b`.
    ///
    /// # Errors
    /// [`Reject::NotAnEdge`], [`Reject::Boundary`], [`Reject::FeatureRule`] (a
    /// tagged edge), [`Reject::Topology`] (`c d` is already an edge).
    pub fn new(mesh: &TriMesh, ctx: &Context, a: VertexId, b: VertexId) -> Result<Self, Reject> {
        if a == b || !mesh.is_vertex_alive(a) || !mesh.is_vertex_alive(b) {
            return Err(Reject::NotAnEdge);
        }
        let faces: Vec<FaceId> = mesh
            .incident_faces(a)
            .into_iter()
            .filter(|&f| mesh.face(f).contains(&b))
            .collect();
        let [f, g] = match faces[..] {
            [] => return Err(Reject::NotAnEdge),
            [_] => return Err(Reject::Boundary),
            [f, g] => [f, g],
            _ => return Err(Reject::Topology),
        };
        if !mesh.edge_tags(a, b).is_empty() {
            return Err(Reject::FeatureRule);
        }
        // Orient so that f = (a, b, c) counter-clockwise, g = (b, a, d).
        let (a, b) = {
            let i = mesh.edge_index(f, a, b).expect("internal: edge of f");
            let v = mesh.face(f);
            (v[(i + 1) % 3], v[(i + 2) % 3])
        };
        let third = |h: FaceId| {
            *mesh
                .face(h)
                .iter()
                .find(|&&x| x != a && x != b)
                .expect("internal: third vertex")
        };
        let (c, d) = (third(f), third(g));
        if c == d
            || mesh
                .incident_faces(c)
                .iter()
                .any(|&h| mesh.face(h).contains(&d))
        {
            return Err(Reject::Topology);
        }
        Ok(SwapPlan {
            faces: [f, g],
            new: [[a, d, c], [d, b, c]],
            c,
            d,
            old_max_energy: max_energy(mesh, ctx, &[f, g]),
        })
    }
}

/// Swap the edge `a b` (see the module doc).
pub fn try_swap(mesh: &mut TriMesh, ctx: &Context, a: VertexId, b: VertexId) -> Outcome {
    let plan = match SwapPlan::new(mesh, ctx, a, b) {
        Ok(p) => p,
        Err(r) => return Outcome::Rejected(r),
    };
    let mut tx = Transaction::new(mesh);
    let created = tx.replace_faces(&plan.faces, &plan.new);
    let check = Check {
        faces: &created,
        changed: &[plan.c, plan.d],
        budgets: &[],
        old_max_energy: Some(plan.old_max_energy),
    };
    if let Err(r) = invariants::validate(&tx, ctx, &check) {
        return Outcome::Rejected(r);
    }
    tx.commit();
    Outcome::Applied(LocalChange {
        created,
        ..LocalChange::default()
    })
}
