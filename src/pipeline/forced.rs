//! Forced corners: where the drawing itself leaves no room for a good angle
//! (issue 38). Decided from the input features (the primary curves and the
//! secondary polylines the mesh's edges are tagged with), the envelope ε and
//! the sizes, never from the mesh's own angles. docs/forced-corners.svg draws
//! both rules.
//!
//! A corner is a vertex `v` of a triangle, between its two edges at `v`. It is
//! **forced** when
//!
//! - **(a) wedge**: the corner lies in a wedge at `v` between two features that
//!   meet there at an input angle θ below α. Around `v` the feature edges split
//!   the plane into sectors; a sector's θ is the counter-clockwise angle
//!   between the two features' directions at `v` *as the drawing gives them*:
//!   a primary section's tangent `c′(t)` at `v`'s parameter, a secondary
//!   polyline's own input segment within ε of `v` (the one that runs the way
//!   the mesh edge does). The two features must meet in the input near `v`
//!   (their input pieces within ε of `v` touch or cross): two polylines that
//!   run side by side within ε form no wedge. A secondary edge may lie anywhere
//!   within ε of its polyline, so it may turn from it by up to
//!   `asin(2ε / |e|)`; the wedge is forced only if it stays below α turned
//!   that far: `θ + Σ asin(2ε / |e|) < α` over its secondary sides (primary
//!   sides are exact). Every triangle in the sector has its corner at `v`
//!   inside the wedge: all are forced. (Primary sections meeting below 4α are
//!   demoted to secondary by the μ-separation, so in practice every forced
//!   wedge has secondary sides; near a tip the envelope usually lets the
//!   optimizer open or close the wedge, and then it is not forced.)
//! - **(b) too close**: an edge `a b` of the triangle lies on a primary feature
//!   `L`, the opposite vertex `p` is held by the input (an isolated point or a
//!   section's end, which the operations never move; a vertex inside a section
//!   slides along it, one on a secondary polyline may move by ε, more than δ*
//!   ever is), `p` is not joined to `a` or `b`
//!   along `L`, and `p` is closer to `L`'s input curve under `a b` than
//!   `δ* = tan(α) · h_min / 2`, where `h_min = min(ε, l, h(p))` is the shortest
//!   edge the optimizer makes at `p` (its refinement stops at the floor
//!   `min(ε, l)`, and it never splits below the size field `h`). The mesh
//!   must hold `p` and conform to `L`, so some triangle stands on `L` under `p`
//!   with a height ≤ δ and a base ≥ h_min: one base corner is below
//!   `atan(2δ / h_min) < α`. The corners at `a` and `b` are forced (the one at
//!   `p` is obtuse).
//!
//! An element is forced when one of its corners is. The mesh is read to
//! locate things (which sector a corner lies in, which input segment a mesh
//! edge follows, a prefilter bound for (b)) and for its secondary edges'
//! lengths (the envelope's slack); the decision compares input angles with α
//! and input distances with δ*, never a triangle's angle.

use crate::fem::FemMesh;
use crate::mesh::{
    EdgeKey, FeatureOn, TriMesh, VertexId, point_segment_distance, segment_distance,
};
use crate::ops::{Context, t_at};
use crate::quality::{FORCED_BY_ANGLE as BY_ANGLE, FORCED_BY_PROXIMITY as BY_NEAR};
use kurbo::{Line, Point, Vec2};
use rustc_hash::FxHashMap;
use std::f64::consts::{PI, TAU};

/// The forced corners of a [`TriMesh`], keyed by their positions (so they are
/// found again in the delivered [`FemMesh`], whatever its numbering and
/// whatever triangles regions dropped).
#[derive(Clone, Debug, Default)]
pub(crate) struct ForcedCorners {
    /// Corner `(v, next, prev)` positions (counter-clockwise) -> reason bits
    /// (`BY_ANGLE`, `BY_NEAR`).
    corners: FxHashMap<[u64; 6], u8>,
}

fn bits(p: Point) -> [u64; 2] {
    [p.x.to_bits(), p.y.to_bits()]
}

fn corner_key(v: Point, next: Point, prev: Point) -> [u64; 6] {
    let [a, b] = bits(v);
    let [c, d] = bits(next);
    let [e, f] = bits(prev);
    [a, b, c, d, e, f]
}

/// The counter-clockwise angle from direction angle `from` to `to`, in `[0, 2π)`.
fn ccw(from: f64, to: f64) -> f64 {
    let d = (to - from).rem_euclid(TAU);
    if d >= TAU { 0.0 } else { d }
}

/// Whether two tags name the same input feature (section or polyline).
fn same_feature(a: &FeatureOn, b: &FeatureOn) -> bool {
    match (a, b) {
        (FeatureOn::Primary { section: s, .. }, FeatureOn::Primary { section: t, .. }) => s == t,
        (FeatureOn::Secondary { polyline: s }, FeatureOn::Secondary { polyline: t }) => s == t,
        _ => false,
    }
}

impl ForcedCorners {
    /// Classify every corner of `mesh`, whose tags index `ctx`'s sections and
    /// envelope polylines. `alpha` in radians; `h_min(p)` the shortest edge the
    /// sizes allow at `p` (see the module doc).
    pub(crate) fn classify(
        mesh: &TriMesh,
        ctx: &Context,
        alpha: f64,
        h_min: &dyn Fn(Point) -> f64,
    ) -> ForcedCorners {
        let mut out = ForcedCorners::default();
        // Each vertex's feature edges: (neighbour, its first tag).
        let mut star: FxHashMap<VertexId, Vec<(VertexId, FeatureOn)>> = FxHashMap::default();
        for (k, tags) in mesh.tagged_edges() {
            let Some(&tag) = tags.first() else { continue };
            star.entry(k.lo).or_default().push((k.hi, tag));
            star.entry(k.hi).or_default().push((k.lo, tag));
        }
        let mut near = Vec::new();
        // (a) wedges between features.
        let mut faces = Vec::new();
        for (&v, edges) in &star {
            if edges.len() < 2 {
                continue;
            }
            let pv = mesh.position(v);
            // (chord angle, input direction angle, the input near v, slack)
            // per feature edge, by chord angle. The slack is how far the
            // ε-envelope lets a secondary edge turn from its polyline:
            // asin(2ε / |e|) (each end may be ε off the input).
            let eps = ctx.envelope.eps();
            let mut dirs: Vec<(f64, Option<f64>, Vec<Line>, f64)> = edges
                .iter()
                .map(|&(w, tag)| {
                    let chord = mesh.position(w) - pv;
                    let input = input_direction(mesh, ctx, v, w, &tag, &mut near);
                    let slack = match tag {
                        FeatureOn::Primary { .. } => 0.0,
                        FeatureOn::Secondary { .. } => (2.0 * eps / chord.hypot()).min(1.0).asin(),
                    };
                    (chord.atan2(), input.map(Vec2::atan2), near.clone(), slack)
                })
                .collect();
            dirs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let n = dirs.len();
            // Sector i runs counter-clockwise from feature edge i to i + 1.
            let forced: Vec<bool> = (0..n)
                .map(|i| {
                    let (c0, d0, ref near0, s0) = dirs[i];
                    let (c1, d1, ref near1, s1) = dirs[(i + 1) % n];
                    let (Some(d0), Some(d1)) = (d0, d1) else {
                        return false;
                    };
                    // The two features must meet near v in the input (touch or
                    // cross): two polylines that merely run side by side within
                    // ε of v form no wedge.
                    let meet = near0.iter().any(|a| {
                        near1
                            .iter()
                            .any(|b| segment_distance(*a, *b) <= ctx.on_curve_abs)
                    });
                    if !meet {
                        return false;
                    }
                    let mesh_angle = ccw(c0, c1);
                    let mut input = ccw(d0, d1);
                    // The input directions are the chords' up to a small turn: an
                    // input angle a half turn beyond the mesh's has wrapped (the
                    // features touch or cross over at v: 0), one a half turn short
                    // of it is the outside of a wedge (not forced).
                    if input - mesh_angle > PI {
                        input = 0.0;
                    } else if mesh_angle - input > PI {
                        input = TAU;
                    }
                    input + s0 + s1 < alpha
                })
                .collect();
            if !forced.contains(&true) {
                continue;
            }
            mesh.incident_faces_into(v, &mut faces);
            for &f in &faces {
                let t = mesh.face(f);
                let Some(k) = t.iter().position(|&x| x == v) else {
                    continue;
                };
                let (pn, pp) = (mesh.position(t[(k + 1) % 3]), mesh.position(t[(k + 2) % 3]));
                let (a0, a1) = ((pn - pv).atan2(), (pp - pv).atan2());
                let mid = a0 + 0.5 * ccw(a0, a1);
                let sector = (0..n).find(|&i| {
                    let (c0, c1) = (dirs[i].0, dirs[(i + 1) % n].0);
                    ccw(c0, mid) < ccw(c0, c1) || n == 1
                });
                if sector.is_some_and(|i| forced[i]) {
                    *out.corners.entry(corner_key(pv, pn, pp)).or_default() |= BY_ANGLE;
                }
            }
        }
        // (b) a feature vertex closer to a feature edge's input than δ*.
        // p is held by the input: an isolated point or a section's end (the
        // operations never move them); a vertex inside a primary section may
        // slide along it, one on a secondary polyline move by ε.
        let pinned = |p: VertexId| {
            let tag = mesh.vertex_tag(p);
            tag.feature_point || tag.section_endpoint
        };
        let joined_along = |p: VertexId, q: VertexId, l: &FeatureOn| {
            mesh.edge_tags(p, q).iter().any(|t| same_feature(t, l))
        };
        let tan_alpha = alpha.tan();
        for f in mesh.faces() {
            let t = mesh.face(f);
            for k in 0..3 {
                let (a, b, p) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                // Only a primary L is where the input puts it; a secondary edge
                // may move by ε, more than δ* (< ε · tan α / 2) ever is.
                let Some(l) = mesh
                    .edge_tags(a, b)
                    .iter()
                    .find(|t| matches!(t, FeatureOn::Primary { .. }))
                    .copied()
                else {
                    continue;
                };
                if !pinned(p) || joined_along(p, a, &l) || joined_along(p, b, &l) {
                    continue;
                }
                let (pa, pb, pp) = (mesh.position(a), mesh.position(b), mesh.position(p));
                let limit = 0.5 * tan_alpha * h_min(pp);
                // Prefilter: the input piece bulges at most half the chord
                // from the mesh edge (its turn is below 90°).
                let slack = 0.5 * pa.distance(pb);
                if point_segment_distance(pp, Line::new(pa, pb)) > limit + slack {
                    continue;
                }
                let delta = input_distance(ctx, a, b, pp, &l);
                if delta.is_some_and(|d| d < limit) {
                    for (v, n, pr) in [(pa, pb, pp), (pb, pp, pa)] {
                        *out.corners.entry(corner_key(v, n, pr)).or_default() |= BY_NEAR;
                    }
                }
            }
        }
        out
    }

    /// The forced corners of `fem`'s triangles: per triangle, `BY_ANGLE << k`
    /// and `BY_NEAR << k` for its corner `k`. Triangles not found (not from
    /// the classified mesh) have no forced corner.
    pub(crate) fn mask(&self, fem: &FemMesh) -> Vec<u8> {
        (0..fem.triangle_count())
            .map(|i| {
                let c = fem.corners(i);
                let mut m = 0u8;
                for k in 0..3 {
                    if let Some(&r) =
                        self.corners
                            .get(&corner_key(c[k], c[(k + 1) % 3], c[(k + 2) % 3]))
                    {
                        if r & BY_ANGLE != 0 {
                            m |= BY_ANGLE << k;
                        }
                        if r & BY_NEAR != 0 {
                            m |= BY_NEAR << k;
                        }
                    }
                }
                m
            })
            .collect()
    }
}

/// The direction of the input feature `tag` at `v`, the way the mesh edge
/// `v w` follows it: a primary's tangent (oriented by the parameters), a
/// secondary polyline's input segment within ε of `v` best aligned with `w − v`.
/// `near` is left holding the input near `v`: a primary's point `v` itself (it
/// is on its curve), a secondary's segments within ε of `v`.
fn input_direction(
    mesh: &TriMesh,
    ctx: &Context,
    v: VertexId,
    w: VertexId,
    tag: &FeatureOn,
    near: &mut Vec<Line>,
) -> Option<Vec2> {
    let (pv, pw) = (mesh.position(v), mesh.position(w));
    near.clear();
    match *tag {
        FeatureOn::Primary { section, t } => {
            near.push(Line::new(pv, pv));
            let key = EdgeKey::new(v, w);
            let (tv, tw) = (t_at(key, t, v), t_at(key, t, w));
            let parent = ctx.section(section)?.parent;
            let sign = if tw >= tv { 1.0 } else { -1.0 };
            let d = parent.deriv(tv) * sign;
            if d.hypot() > 0.0 && d.hypot().is_finite() {
                return Some(d);
            }
            // A cusp: the chord to a point just along the curve.
            let q = parent.eval(tv + 1e-6 * (tw - tv));
            let c = q - parent.eval(tv);
            (c.hypot() > 0.0).then_some(c)
        }
        FeatureOn::Secondary { polyline } => {
            let eps = ctx.envelope.eps();
            ctx.envelope.segments_near(pv, polyline, eps, near);
            let chord = pw - pv;
            let mut best: Option<(f64, Vec2)> = None;
            for l in near.iter() {
                let d = l.p1 - l.p0;
                let len2 = d.hypot2();
                if len2 <= 0.0 || len2.is_nan() {
                    continue;
                }
                let u = ((pv - l.p0).dot(d) / len2).clamp(0.0, 1.0);
                // From v's foot, the segment runs forward unless v is at its
                // end, backward unless v is at its start.
                for (ok, dir) in [(u < 1.0 - 1e-6, d), (u > 1e-6, -d)] {
                    let cos = dir.dot(chord) / (dir.hypot() * chord.hypot());
                    if ok && best.is_none_or(|(c, _)| cos > c) {
                        best = Some((cos, dir));
                    }
                }
            }
            best.map(|(_, d)| d)
        }
    }
}

/// The distance from `pp` to the input piece of the primary feature `l` under
/// the mesh edge `a b`: its curve on `[t_a, t_b]` (as a fine polyline).
fn input_distance(
    ctx: &Context,
    a: VertexId,
    b: VertexId,
    pp: Point,
    l: &FeatureOn,
) -> Option<f64> {
    match *l {
        FeatureOn::Primary { section, t } => {
            let key = EdgeKey::new(a, b);
            let (ta, tb) = (t_at(key, t, a), t_at(key, t, b));
            let parent = ctx.section(section)?.parent;
            const N: usize = 32;
            let mut prev = parent.eval(ta);
            let mut best = f64::INFINITY;
            for i in 1..=N {
                let q = parent.eval(ta + (tb - ta) * i as f64 / N as f64);
                best = best.min(point_segment_distance(pp, Line::new(prev, q)));
                prev = q;
            }
            Some(best)
        }
        // Never asked: (b) reads primary features only.
        FeatureOn::Secondary { .. } => None,
    }
}
