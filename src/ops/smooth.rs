//! Vertex smoothing: Newton's method on the AMIPS energy of the one-ring,
//! with a backtracking line search that keeps every triangle of the ring
//! counter-clockwise (in `f64`; the invariants then decide exactly).
//!
//! A free or secondary vertex moves in the plane; a primary vertex moves along
//! its curve between its two neighbours on the section (univariate Newton on
//! `E(c(t))`, thesis §4.4.3), which also snaps a vertex the BSP left on the
//! chord onto the curve. Fixed and boundary vertices do not move. The move is
//! kept only if it lowers the ring's energy.

use super::invariants::{self, Check, on_curve};
use super::{Context, LocalChange, Outcome, Reject, Role, corner_energy, max_energy, role};
use crate::element::energy::{Amips2, CurveJet, along_curve, amips_free};
use crate::features::Parent;
use crate::mesh::{EdgeKey, FaceId, FeatureOn, Transaction, TriMesh, VertexId};
use kurbo::{Point, Vec2};
use nalgebra::Vector2;
use std::cmp::Ordering;

/// Newton iterations per smoothing.
const NEWTON_ITERATIONS: usize = 10;
/// Halvings of the line search.
const LINE_SEARCH_STEPS: usize = 30;
/// Newton stops once the decrease its step predicts (the Newton decrement,
/// `-∇E·d`) is below this fraction of the energy: about what `f64` can still
/// resolve in a sum of a few energies, so further steps would only halve
/// their way through the line search to nothing.
const NEWTON_DECREMENT: f64 = 1e-12;

/// The planned move of one vertex.
#[derive(Clone, Debug)]
pub(crate) struct SmoothPlan {
    v: VertexId,
    faces: Vec<FaceId>,
    pos: Point,
    /// For a primary vertex: its section, its new parameter, and its two
    /// neighbours along the section (the ends of its only tagged edges,
    /// [`Role::Primary`]), whose tags get the new parameter.
    t: Option<(u32, f64, [VertexId; 2])>,
    old_max_energy: f64,
    old_corner_energy: Option<f64>,
}

/// What smoothing minimises over the one-ring.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Objective {
    /// The sum of the AMIPS energies (the schedule's smoothing).
    Sum,
    /// The sum of `(E / E_max)^8`, where `E_max` is the ring's largest energy
    /// before the move: a smooth stand-in for the largest energy (min-max
    /// smoothing, which lifts the worst angle of the ring).
    MinMax,
    /// Tangential relaxation: a free vertex moves to the mean of its
    /// neighbours (the length-equalising step of isotropic remeshing), its
    /// ring's largest energy allowed up to the context's `energy_floor`.
    Relax,
}

/// The power of [`Objective::MinMax`].
const MINMAX_POWER: i32 = 8;

fn ring_energy(
    mesh: &TriMesh,
    v: VertexId,
    faces: &[FaceId],
    p: Point,
    objective: Objective,
    scale: f64,
) -> Option<Amips2> {
    let mut sum = Amips2::ZERO;
    for &f in faces {
        let fv = mesh.face(f);
        let i = mesh.local_index(f, v).expect("internal: ring face has v");
        let (b, c) = (
            mesh.position(fv[(i + 1) % 3]),
            mesh.position(fv[(i + 2) % 3]),
        );
        let e = amips_free(p, b, c)?;
        sum = sum
            + match objective {
                Objective::Sum | Objective::Relax => e,
                Objective::MinMax => e.powered(MINMAX_POWER, scale),
            };
    }
    Some(sum)
}

fn jet(parent: &Parent, t: f64) -> CurveJet {
    match parent {
        Parent::Cubic(c) => CurveJet {
            pos: parent.eval(t),
            ..CurveJet::cubic(c, t)
        },
        Parent::Line(l) => CurveJet {
            pos: parent.eval(t),
            d1: l.p1 - l.p0,
            d2: Vec2::ZERO,
        },
        Parent::Conic(c) => {
            let (d1, d2) = c.derivs(t);
            CurveJet {
                pos: parent.eval(t),
                d1,
                d2,
            }
        }
    }
}

impl SmoothPlan {
    /// The invariants' check of the move, with the curve `budgets`.
    fn check<'a>(&'a self, budgets: &'a [super::CurveBudget]) -> Check<'a> {
        Check {
            faces: &self.faces,
            changed: std::slice::from_ref(&self.v),
            budgets,
            old_max_energy: Some(self.old_max_energy),
            old_corner_energy: self.old_corner_energy,
        }
    }

    /// What [`try_smooth_planned`] would decide on this plan (the length rule,
    /// then the invariants), decided on the mesh as it is, without the
    /// tentative move, in linear mode (`None` in curved mode): the exact
    /// orientation of the ring with the vertex moved, its distance to its
    /// curve against its budget (a primary vertex, with its new parameter),
    /// the curvature and the envelope of its feature edges with the tags they
    /// would have, then the energy rule, in the order of
    /// [`invariants::validate`]. The schedule decides these ahead, in
    /// parallel, with the plan.
    pub(crate) fn verdict(&self, mesh: &TriMesh, ctx: &Context) -> Option<Result<(), Reject>> {
        if ctx.curved.is_some() {
            return None;
        }
        let v = self.v;
        let ring = crate::mesh::ScratchRing::of(mesh, v);
        // A tag of v's edges as the move leaves it: the plan's section gets
        // the new parameter at v's end (as `try_smooth_planned` retags it).
        let moved_tag = |key: EdgeKey, tag: FeatureOn| match (tag, self.t) {
            (FeatureOn::Primary { section, t }, Some((s, tn, _))) if section == s => {
                FeatureOn::Primary {
                    section,
                    t: if key.lo == v { [tn, t[1]] } else { [t[0], tn] },
                }
            }
            (other, _) => other,
        };
        if ctx.max_new_edge < f64::INFINITY {
            let old = mesh.position(v);
            let stretches = ring.neighbours.iter().any(|&w| {
                let q = mesh.position(w);
                let len = self.pos.distance(q);
                len > ctx.max_new_edge && len > old.distance(q)
            });
            if stretches {
                return Some(Err(Reject::EdgeLength));
            }
        }
        let ccw = self.faces.iter().all(|&f| {
            mesh.orientation_if_moved(f, v, self.pos) == crate::exact::Orientation::CounterClockwise
        });
        if !ccw {
            return Some(Err(Reject::Inversion));
        }
        // The curve budget (a primary vertex only): its distance to its curve
        // after the move, against the one before (`on_curve::holds`).
        if self.t.is_some()
            && let Some(before) = on_curve::off_curve(mesh, ctx, v)
        {
            let mut after: Option<f64> = None;
            for &w in &ring.neighbours {
                let key = EdgeKey::new(v, w);
                for &tag in mesh.edge_tags(v, w) {
                    if let FeatureOn::Primary { section, t } = moved_tag(key, tag) {
                        let d = ctx.section(section).map_or(f64::INFINITY, |s| {
                            self.pos.distance(s.parent.eval(super::t_at(key, t, v)))
                        });
                        after = Some(after.unwrap_or(0.0).max(d));
                    }
                }
            }
            // Refused unless within the allowed distance (a NaN distance too).
            let allowed = ctx.on_curve_abs.max(before);
            if after.is_some_and(|d| d.partial_cmp(&allowed).is_none_or(|o| o.is_gt())) {
                return Some(Err(Reject::OnCurve));
            }
        }
        // v's feature edges with the tags the move leaves, v moved.
        let edges: Vec<(EdgeKey, Vec<FeatureOn>)> = ring
            .neighbours
            .iter()
            .map(|&w| {
                let key = EdgeKey::new(v, w);
                let tags = mesh.edge_tags(v, w).iter().map(|&t| moved_tag(key, t));
                (key, tags.collect::<Vec<_>>())
            })
            .filter(|(_, tags)| !tags.is_empty())
            .collect();
        let at = |x: VertexId| if x == v { self.pos } else { mesh.position(x) };
        if let Err(r) = invariants::feature_edges_hold(ctx, &edges, at) {
            return Some(Err(r));
        }
        if ctx.energy == super::EnergyRule::NoWorseMax {
            let new_max = self
                .faces
                .iter()
                .map(|&f| {
                    let [a, b, c] = mesh.face(f).map(at);
                    crate::element::energy::amips(a, b, c)
                })
                .fold(0.0, f64::max);
            if new_max > self.old_max_energy {
                return Some(Err(Reject::Energy));
            }
        }
        Some(Ok(()))
    }

    /// Find a better position for `v` under `objective`.
    ///
    /// # Errors
    /// [`Reject::NotAnEdge`] for a dead vertex, [`Reject::FixedVertex`] for a
    /// fixed or boundary one, [`Reject::NoChange`] when no position with a
    /// lower ring energy was found.
    pub(crate) fn with_objective(
        mesh: &TriMesh,
        ctx: &Context,
        v: VertexId,
        objective: Objective,
    ) -> Result<Self, Reject> {
        if !mesh.is_vertex_alive(v) {
            return Err(Reject::NotAnEdge);
        }
        let r = crate::mesh::ScratchRing::of(mesh, v);
        let faces = r.faces.clone();
        let scale = match objective {
            Objective::Sum | Objective::Relax => 1.0,
            Objective::MinMax => {
                // The linear energies' maximum: the objective's own scale.
                let m = faces
                    .iter()
                    .map(|&f| {
                        let [a, b, c] = mesh.face(f).map(|x| mesh.position(x));
                        crate::element::energy::amips(a, b, c)
                    })
                    .fold(0.0, f64::max);
                if !(m.is_finite() && m > 0.0) {
                    return Err(Reject::NoChange);
                }
                m
            }
        };
        let energy = |p: Point| ring_energy(mesh, v, &faces, p, objective, scale);
        let role = role(mesh, v, &r);
        if objective == Objective::Relax {
            if role != Role::Free || r.neighbours.is_empty() {
                return Err(Reject::FixedVertex);
            }
            // A vertex facing a curved section stays: the curved edge bulges
            // toward it, and the mean of its neighbours ignores that.
            let faces_a_curve = super::faces_a_curve(mesh, ctx, &r.faces);
            if faces_a_curve {
                return Err(Reject::FixedVertex);
            }
            let n = r.neighbours.len() as f64;
            let (sx, sy) = r.neighbours.iter().fold((0.0, 0.0), |(x, y), &w| {
                let q = mesh.position(w);
                (x + q.x, y + q.y)
            });
            let pos = Point::new(sx / n, sy / n);
            if pos == mesh.position(v) && !mesh.is_rational(v) {
                return Err(Reject::NoChange);
            }
            return Ok(SmoothPlan {
                v,
                old_max_energy: max_energy(mesh, ctx, &faces).max(ctx.energy_floor),
                old_corner_energy: corner_energy(mesh, ctx, &faces),
                faces,
                pos,
                t: None,
            });
        }
        let (pos, t) = match role {
            Role::Fixed | Role::SecondaryJunction => {
                return Err(Reject::FixedVertex);
            }
            Role::Boundary => (slide_on_boundary(mesh, v, &r, &energy)?, None),
            Role::Free | Role::Secondary => {
                let p0 = mesh.position(v);
                let e0 = energy(p0).ok_or(Reject::NoChange)?;
                let mut p = p0;
                let mut e = e0;
                for _ in 0..NEWTON_ITERATIONS {
                    let dir = e
                        .hess
                        .cholesky()
                        .map(|ch| ch.solve(&(-e.grad)))
                        .unwrap_or_else(|| -e.grad / e.hess.trace().max(1e-300));
                    // Converged: the step's predicted decrease is below what
                    // f64 can still see in the ring's energy (the line search
                    // would halve its way to nothing).
                    if (-e.grad.dot(&dir)).partial_cmp(&(NEWTON_DECREMENT * e.value))
                        != Some(Ordering::Greater)
                    {
                        break;
                    }
                    let Some((q, eq)) = line_search(p, dir, e.value, &energy) else {
                        break;
                    };
                    let moved = q.distance(p);
                    p = q;
                    e = eq;
                    if moved <= 1e-14 * (p.x.abs() + p.y.abs() + 1e-300) {
                        break;
                    }
                }
                if e.value.partial_cmp(&e0.value) != Some(Ordering::Less) {
                    return Err(Reject::NoChange);
                }
                (p, None)
            }
            Role::Primary { section, t, along } => {
                let s = ctx.section(section).ok_or(Reject::FeatureRule)?;
                let (lo, hi) = (along[0].1.min(along[1].1), along[0].1.max(along[1].1));
                let margin = 1e-3 * (hi - lo);
                let (lo, hi) = (lo + margin, hi - margin);
                if lo.partial_cmp(&hi) != Some(Ordering::Less) {
                    return Err(Reject::NoChange);
                }
                let e_at = |t: f64| {
                    let j = jet(&s.parent, t);
                    energy(j.pos).map(|e| along_curve(&e, &j))
                };
                let t0 = t.clamp(lo, hi);
                // Off the curve: any valid position on it is progress (projection).
                let off = on_curve::off_curve(mesh, ctx, v).unwrap_or(0.0) > ctx.on_curve_abs;
                let base = if off {
                    f64::INFINITY
                } else {
                    energy(mesh.position(v)).map_or(f64::INFINITY, |e| e.value)
                };
                let (tc, value) =
                    minimize_1d(t0, lo, hi, |t| e_at(t).map(|e| (e.value, e.d1, e.d2)))
                        .ok_or(Reject::NoChange)?;
                if value.partial_cmp(&base) != Some(Ordering::Less) {
                    return Err(Reject::NoChange);
                }
                let along = [along[0].0, along[1].0];
                (s.parent.eval(tc), Some((section, tc, along)))
            }
        };
        if pos == mesh.position(v) && !mesh.is_rational(v) {
            return Err(Reject::NoChange);
        }
        Ok(SmoothPlan {
            v,
            old_max_energy: max_energy(mesh, ctx, &faces),
            old_corner_energy: corner_energy(mesh, ctx, &faces),
            faces,
            pos,
            t,
        })
    }
}

/// A boundary vertex between two boundary neighbours on one axis-parallel line
/// (the box's sides) slides along that line, its other coordinate untouched, so
/// it stays exactly on the boundary: Newton on the ring energy restricted to the
/// line, kept strictly between the neighbours.
fn slide_on_boundary(
    mesh: &TriMesh,
    v: VertexId,
    r: &crate::mesh::VertexRing,
    energy: &impl Fn(Point) -> Option<Amips2>,
) -> Result<Point, Reject> {
    let ends: Vec<VertexId> = r
        .neighbours
        .iter()
        .copied()
        .filter(|&w| mesh.is_boundary_edge(r, w))
        .collect();
    let [a, b] = ends[..] else {
        return Err(Reject::FixedVertex);
    };
    if mesh.is_rational(v) || mesh.is_rational(a) || mesh.is_rational(b) {
        return Err(Reject::FixedVertex);
    }
    let (p, pa, pb) = (mesh.position(v), mesh.position(a), mesh.position(b));
    // Which coordinate moves: x on a horizontal side, y on a vertical one.
    let axis = if pa.y == p.y && pb.y == p.y {
        0
    } else if pa.x == p.x && pb.x == p.x {
        1
    } else {
        return Err(Reject::FixedVertex);
    };
    let coord = |q: Point| if axis == 0 { q.x } else { q.y };
    let at = |c: f64| {
        if axis == 0 {
            Point::new(c, p.y)
        } else {
            Point::new(p.x, c)
        }
    };
    let (lo, hi) = (coord(pa).min(coord(pb)), coord(pa).max(coord(pb)));
    let margin = 1e-3 * (hi - lo);
    let (lo, hi) = (lo + margin, hi - margin);
    if lo.partial_cmp(&hi) != Some(Ordering::Less) {
        return Err(Reject::NoChange);
    }
    let e0 = energy(p).ok_or(Reject::NoChange)?;
    let (c, value) = minimize_1d(coord(p).clamp(lo, hi), lo, hi, |c| {
        energy(at(c)).map(|e| (e.value, e.grad[axis], e.hess[(axis, axis)]))
    })
    .ok_or(Reject::NoChange)?;
    if value.partial_cmp(&e0.value) != Some(Ordering::Less) {
        return Err(Reject::NoChange);
    }
    Ok(at(c))
}

/// Damped Newton for a univariate energy on `[lo, hi]` from `x0`: `f` gives
/// the value and first two derivatives (or `None` where the energy is not
/// defined); a step is halved until the value decreases. Returns the last
/// iterate and its value (`x0` and its value when no step helps), or `None`
/// when `f(x0)` is not defined.
fn minimize_1d(
    x0: f64,
    lo: f64,
    hi: f64,
    f: impl Fn(f64) -> Option<(f64, f64, f64)>,
) -> Option<(f64, f64)> {
    let (mut x, mut e) = (x0, f(x0)?);
    for _ in 0..NEWTON_ITERATIONS {
        let (value, d1, d2) = e;
        let dx = if d2 > 0.0 {
            // Converged: see NEWTON_DECREMENT.
            if (d1 * d1 / d2).partial_cmp(&(NEWTON_DECREMENT * value.abs()))
                != Some(Ordering::Greater)
            {
                break;
            }
            -d1 / d2
        } else {
            -d1.signum() * 0.25 * (hi - lo)
        };
        let mut step = 1.0;
        let mut found = None;
        for _ in 0..LINE_SEARCH_STEPS {
            let xn = (x + step * dx).clamp(lo, hi);
            if let Some(en) = f(xn).filter(|en| en.0 < value) {
                found = Some((xn, en));
                break;
            }
            step *= 0.5;
        }
        let Some((xn, en)) = found else { break };
        let done = (xn - x).abs() <= 1e-14 * (hi - lo);
        x = xn;
        e = en;
        if done {
            break;
        }
    }
    Some((x, e.0))
}

fn line_search(
    p: Point,
    dir: Vector2<f64>,
    e0: f64,
    energy: &impl Fn(Point) -> Option<Amips2>,
) -> Option<(Point, Amips2)> {
    if !(dir[0].is_finite() && dir[1].is_finite()) {
        return None;
    }
    let mut step = 1.0;
    for _ in 0..LINE_SEARCH_STEPS {
        let q = p + Vec2::new(dir[0], dir[1]) * step;
        if let Some(e) = energy(q).filter(|e| e.value < e0) {
            return Some((q, e));
        }
        step *= 0.5;
    }
    None
}

/// Smooth the vertex `v` (see the module doc).
pub(crate) fn try_smooth(mesh: &mut TriMesh, ctx: &Context, v: VertexId) -> Outcome {
    try_smooth_with(mesh, ctx, v, Objective::Sum)
}

/// Smooth the vertex `v` minimising `objective` over its ring (same rules and
/// invariants as [`try_smooth`]).
pub(crate) fn try_smooth_with(
    mesh: &mut TriMesh,
    ctx: &Context,
    v: VertexId,
    objective: Objective,
) -> Outcome {
    try_smooth_planned(
        mesh,
        ctx,
        SmoothPlan::with_objective(mesh, ctx, v, objective),
        None,
    )
}

/// The rest of [`try_smooth_with`] once its plan is made: `planned` is
/// [`SmoothPlan::with_objective`] of the mesh as it is now (the schedule plans
/// ahead, in parallel, and hands the plan over while the faces around the
/// vertex and its neighbours' positions are unchanged), so the outcome is the
/// one `try_smooth_with` gives.
///
/// With `verdict` ([`SmoothPlan::verdict`] of the mesh as it is), the move is
/// refused or committed as it says, without checking the invariants again.
pub(crate) fn try_smooth_planned(
    mesh: &mut TriMesh,
    ctx: &Context,
    planned: Result<SmoothPlan, Reject>,
    verdict: Option<Result<(), Reject>>,
) -> Outcome {
    let plan = match planned {
        Ok(p) => p,
        Err(r) => return Outcome::Rejected(r),
    };
    let v = plan.v;
    if let Some(Err(r)) = verdict {
        return Outcome::Rejected(r);
    }
    let decided = verdict.is_some();
    if !decided && ctx.max_new_edge < f64::INFINITY {
        let old = mesh.position(v);
        let stretches = crate::mesh::ScratchRing::of(mesh, v)
            .neighbours
            .iter()
            .any(|&w| {
                let q = mesh.position(w);
                let len = plan.pos.distance(q);
                len > ctx.max_new_edge && len > old.distance(q)
            });
        if stretches {
            return Outcome::Rejected(Reject::EdgeLength);
        }
    }
    // Only a primary vertex (the plan gave it a parameter) is on a curve: any
    // other has no primary edge, so no budget (and nothing to walk for one).
    let budget: Vec<_> = if plan.t.is_some() && !decided {
        on_curve::budget_now(mesh, ctx, v).into_iter().collect()
    } else {
        Vec::new()
    };
    let mut tx = Transaction::decided_if(mesh, decided);
    tx.set_position(v, plan.pos);
    if let Some((section, tn, along)) = plan.t {
        // v's tagged edges are those to `along` alone: the plan read v's
        // edges, and a plan made ahead stands only while no face around v
        // changed (every change of a tag at v does that) and no neighbour
        // of v moved.
        for w in along {
            let key = EdgeKey::new(v, w);
            for tag in tx.take_edge_tags(v, w) {
                let tag = match tag {
                    FeatureOn::Primary { section: s, t } if s == section => FeatureOn::Primary {
                        section,
                        t: if key.lo == v { [tn, t[1]] } else { [t[0], tn] },
                    },
                    other => other,
                };
                tx.add_edge_tag(key.lo, key.hi, tag);
            }
        }
    }
    if decided {
        // `plan.verdict` decided the invariants (with the curve budget of the
        // mesh before the move): debug builds check them again.
        debug_assert!(
            invariants::validate(&tx, ctx, &plan.check(&[])).is_ok(),
            "a move decided ahead fails the invariants"
        );
    } else if let Err(r) = invariants::validate(&tx, ctx, &plan.check(&budget)) {
        return Outcome::Rejected(r);
    }
    tx.commit();
    Outcome::Applied(LocalChange {
        created: plan.faces,
        moved_vertex: Some(v),
        ..LocalChange::default()
    })
}
