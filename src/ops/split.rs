//! Edge split: a new vertex on the edge, each incident triangle cut in two.
//!
//! A primary edge gets its vertex at the curve's parameter midpoint when that
//! inverts nothing, else at the edge's midpoint (off the curve, to be
//! projected later; thesis §4.4.1 "Feature Handling" 1). Other edges get the
//! `f64` midpoint, or the exact rational midpoint when the `f64` one would
//! invert a triangle or leave a straight boundary: a split of a valid mesh is
//! then always possible.

use super::invariants::{self, Check};
use super::{Context, CurveBudget, LocalChange, Outcome, Reject, t_at};
use crate::exact::Orientation;
use crate::mesh::{EdgeKey, FaceId, FeatureOn, Transaction, TriMesh, VertexId, VertexTag};
use kurbo::Point;

/// Where a split may put its vertex, in order of preference.
#[derive(Clone, Debug, PartialEq)]
enum Candidate {
    /// An `f64` position, with the allowed off-curve distance if primary.
    F64(Point, f64),
    /// The exact midpoint (computed when tried: the `f64` candidates before
    /// it rarely fail, and rationals allocate), with the allowed off-curve
    /// distance.
    ExactMidpoint(f64),
}

/// Everything a split of one edge needs, gathered from `&TriMesh`.
#[derive(Clone, Debug)]
pub(crate) struct SplitPlan {
    a: VertexId,
    b: VertexId,
    /// The faces on the edge, with the local index of the vertex opposite it.
    faces: Vec<(FaceId, usize)>,
    tags: Vec<FeatureOn>,
    candidates: Vec<Candidate>,
    /// Largest energy a new triangle may have (none: splits ignore the energy rule).
    max_energy: Option<f64>,
}

impl SplitPlan {
    /// Plan the split of the edge `a b`.
    ///
    /// # Errors
    /// [`Reject::NotAnEdge`] when `a b` is not an edge of live faces.
    pub(crate) fn new(
        mesh: &TriMesh,
        ctx: &Context,
        a: VertexId,
        b: VertexId,
    ) -> Result<Self, Reject> {
        if a == b || !mesh.is_vertex_alive(a) || !mesh.is_vertex_alive(b) {
            return Err(Reject::NotAnEdge);
        }
        let mut on_edge = Vec::new();
        mesh.faces_on_edge(a, b, &mut on_edge);
        // Each face with the local index of its vertex opposite the edge.
        let faces: Vec<(FaceId, usize)> = on_edge
            .into_iter()
            .map(|f| {
                let third = mesh.opposite(f, a, b).expect("internal: third vertex");
                (
                    f,
                    mesh.local_index(f, third).expect("internal: vertex of f"),
                )
            })
            .collect();
        if faces.is_empty() {
            return Err(Reject::NotAnEdge);
        }
        let tags = mesh.edge_tags(a, b).to_vec();
        let key = EdgeKey::new(a, b);
        let (pa, pb) = (mesh.position(a), mesh.position(b));
        let mut candidates = Vec::new();
        let primary = tags.iter().find_map(|t| match *t {
            FeatureOn::Primary { section, t } => Some((section, t)),
            FeatureOn::Secondary { .. } => None,
        });
        let linear = pa.midpoint(pb);
        if let Some((section, t)) = primary {
            let tm = 0.5 * (t_at(key, t, a) + t_at(key, t, b));
            if let Some(s) = ctx.section(section) {
                candidates.push(Candidate::F64(s.parent.eval(tm), 0.0));
            }
            // Off the curve by design: any distance is allowed for the new vertex.
            candidates.push(Candidate::F64(linear, f64::INFINITY));
            candidates.push(Candidate::ExactMidpoint(f64::INFINITY));
        } else {
            let boundary = faces.len() == 1;
            if boundary && ctx.fixed_boundary {
                return Err(Reject::Boundary);
            }
            let straight = mesh.exact(a).is_none()
                && mesh.exact(b).is_none()
                && crate::exact::orient2d(pa, pb, linear) == Orientation::Collinear;
            if !boundary || straight {
                candidates.push(Candidate::F64(linear, f64::INFINITY));
            }
            if !straight {
                candidates.push(Candidate::ExactMidpoint(f64::INFINITY));
            }
        }
        Ok(SplitPlan {
            a,
            b,
            faces,
            tags,
            candidates,
            max_energy: None,
        })
    }

    /// Each candidate in turn, the first that the invariants accept applied.
    fn try_candidates(&self, mesh: &mut TriMesh, ctx: &Context) -> Outcome {
        let mut last = Reject::NoChange;
        for cand in &self.candidates {
            match self.apply(mesh, ctx, cand) {
                Outcome::Rejected(r) => last = r,
                applied => return applied,
            }
        }
        Outcome::Rejected(last)
    }

    fn apply(&self, mesh: &mut TriMesh, ctx: &Context, cand: &Candidate) -> Outcome {
        let mut tx = Transaction::new(mesh);
        let (m, max_off) = match cand {
            Candidate::F64(p, off) => (tx.add_vertex(*p, VertexTag::default()), *off),
            Candidate::ExactMidpoint(off) => {
                let q = tx.point_q(self.a).lerp_ratio(&tx.point_q(self.b), 1.0, 2.0);
                (tx.add_vertex_q(q, VertexTag::default()), *off)
            }
        };
        let mut new = Vec::new();
        let mut old = Vec::new();
        for &(f, k) in &self.faces {
            let v = tx.face(f);
            // v[k] is opposite the edge, which runs v[k+1] -> v[k+2].
            let (x, y, z) = (v[(k + 1) % 3], v[(k + 2) % 3], v[k]);
            new.push([x, m, z]);
            new.push([m, y, z]);
            old.push(f);
        }
        let created = tx.replace_faces(&old, &new);
        let key = EdgeKey::new(self.a, self.b);
        tx.take_edge_tags(self.a, self.b);
        for tag in &self.tags {
            match *tag {
                FeatureOn::Primary { section, t } => {
                    let (ta, tb) = (t_at(key, t, self.a), t_at(key, t, self.b));
                    let tm = 0.5 * (ta + tb);
                    tx.add_edge_tag(
                        self.a,
                        m,
                        FeatureOn::Primary {
                            section,
                            t: [ta, tm],
                        },
                    );
                    tx.add_edge_tag(
                        m,
                        self.b,
                        FeatureOn::Primary {
                            section,
                            t: [tm, tb],
                        },
                    );
                }
                sec @ FeatureOn::Secondary { .. } => {
                    tx.add_edge_tag(self.a, m, sec);
                    tx.add_edge_tag(m, self.b, sec);
                }
            }
        }
        let budgets = [CurveBudget { vertex: m, max_off }];
        let check = Check {
            faces: &created,
            changed: &[m],
            budgets: &budgets,
            old_max_energy: None,
            old_corner_energy: None,
        };
        if let Err(r) = invariants::validate(&tx, ctx, &check) {
            return Outcome::Rejected(r);
        }
        if let Some(bound) = self.max_energy {
            if super::max_energy(&tx, ctx, &created) > bound {
                return Outcome::Rejected(Reject::Energy);
            }
        }
        tx.commit();
        Outcome::Applied(LocalChange {
            created,
            new_vertex: Some(m),
            ..LocalChange::default()
        })
    }
}

/// Split the edge `a b` (see the module doc). Splits ignore the energy rule.
pub(crate) fn try_split(mesh: &mut TriMesh, ctx: &Context, a: VertexId, b: VertexId) -> Outcome {
    try_split_bounded(mesh, ctx, a, b, None)
}

/// [`try_split`] with its plan made already (ahead, on the mesh as it was:
/// the caller knows that no face around `a` or `b` has changed since).
pub(crate) fn try_split_planned(
    mesh: &mut TriMesh,
    ctx: &Context,
    planned: Result<SplitPlan, Reject>,
) -> Outcome {
    match planned {
        Ok(plan) => plan.try_candidates(mesh, ctx),
        Err(r) => Outcome::Rejected(r),
    }
}

/// Split the edge `a b` as [`try_split`] does, but refuse ([`Reject::Energy`])
/// when a new triangle's energy would exceed `max_energy`: a split made for
/// another reason than quality (the curving stage's repair) must not leave a
/// sliver behind.
pub(crate) fn try_split_bounded(
    mesh: &mut TriMesh,
    ctx: &Context,
    a: VertexId,
    b: VertexId,
    max_energy: Option<f64>,
) -> Outcome {
    match SplitPlan::new(mesh, ctx, a, b) {
        Ok(p) => SplitPlan { max_energy, ..p }.try_candidates(mesh, ctx),
        Err(r) => Outcome::Rejected(r),
    }
}
