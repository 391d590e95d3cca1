//! Forced corners: where the drawing itself leaves no room for a good angle.
//! Decided from the input features (the primary curves and the
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
//!
//! A feature that merely passes close to a vertex forces no corner. Such a
//! vertex `p` at a distance δ from a feature `L` forces small *elements*
//! there (some triangle under `p` has a height ≤ δ), but not small angles:
//! the mesh may put vertices on `L` on either side of `p`'s foot, about δ
//! apart, and every triangle there can be well shaped. The optimizer's size
//! floor does not stop it: splits follow the size field, but the BSP's cuts,
//! smoothing along a curve and the ends of sections make shorter edges wherever
//! the features need them. (A rule marking the corners under `p` forced when
//! δ < tan(α)·h_min/2, for the size floor h_min, would be wrong: on a whisker
//! ending 0.01 from a square's edge in a 100-unit drawing, with `--mu 1e-5` so
//! that both stay primary, the mesh puts two vertices 0.08 apart under it and
//! the corners such a rule calls forced are 13.6° and 14.6°.)
//!
//! An element is forced when one of its corners is. The mesh is read to
//! locate things (which sector a corner lies in, which input segment a mesh
//! edge follows) and for its secondary edges' lengths (the envelope's slack);
//! the decision compares input angles with α, never a triangle's angle.

use crate::fem::FemMesh;
use crate::mesh::{EdgeKey, FeatureOn, TriMesh, VertexId, segment_distance};
use crate::ops::{Context, t_at};
use crate::quality::FORCED_BY_ANGLE as BY_ANGLE;
use kurbo::{Line, Point, Vec2};
use rustc_hash::FxHashMap;
use std::f64::consts::{PI, TAU};

/// The forced corners of a [`TriMesh`], keyed by their positions (so they are
/// found again in the delivered [`FemMesh`], whatever its numbering and
/// whatever triangles regions dropped).
#[derive(Clone, Debug, Default)]
pub(crate) struct ForcedCorners {
    /// Corner `(v, next, prev)` positions (counter-clockwise) -> reason bits
    /// (`BY_ANGLE`).
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
impl ForcedCorners {
    /// Classify every corner of `mesh`, whose tags index `ctx`'s sections and
    /// envelope polylines. `alpha` in radians.
    pub(crate) fn classify(mesh: &TriMesh, ctx: &Context, alpha: f64) -> ForcedCorners {
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
            let Some(sectors) = Sectors::at(mesh, ctx, v, edges, alpha, &mut near) else {
                continue;
            };
            let pv = mesh.position(v);
            mesh.incident_faces_into(v, &mut faces);
            for &f in &faces {
                let t = mesh.face(f);
                let Some(k) = t.iter().position(|&x| x == v) else {
                    continue;
                };
                let (pn, pp) = (mesh.position(t[(k + 1) % 3]), mesh.position(t[(k + 2) % 3]));
                if sectors.holds_forced(pv, pn, pp) {
                    *out.corners.entry(corner_key(pv, pn, pp)).or_default() |= BY_ANGLE;
                }
            }
        }
        out
    }

    /// The forced corners of `fem`'s triangles: per triangle, `BY_ANGLE << k`
    /// for its corner `k`. Triangles not found (not from
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
                    }
                }
                m
            })
            .collect()
    }
}

/// The sectors of a vertex between its feature edges, with the wedge rule (a)
/// decided for each.
struct Sectors {
    /// The feature edges' chord angles, sorted; sector `i` runs
    /// counter-clockwise from chord `i` to chord `i + 1`.
    chords: Vec<f64>,
    /// By sector: whether it is a forced wedge.
    forced: Vec<bool>,
}

impl Sectors {
    /// The sectors at `v`, whose feature edges are `edges` (neighbour, its
    /// first tag); `None` when fewer than two or none is forced.
    fn at(
        mesh: &TriMesh,
        ctx: &Context,
        v: VertexId,
        edges: &[(VertexId, FeatureOn)],
        alpha: f64,
        near: &mut Vec<Line>,
    ) -> Option<Sectors> {
        if edges.len() < 2 {
            return None;
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
                let input = input_direction(mesh, ctx, v, w, &tag, near);
                let slack = match tag {
                    FeatureOn::Primary { .. } => 0.0,
                    FeatureOn::Secondary { .. } => (2.0 * eps / chord.hypot()).min(1.0).asin(),
                };
                (chord.atan2(), input.map(Vec2::atan2), near.clone(), slack)
            })
            .collect();
        dirs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let n = dirs.len();
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
        forced.contains(&true).then(|| Sectors {
            chords: dirs.iter().map(|d| d.0).collect(),
            forced,
        })
    }

    /// Whether the corner at `pv` from `pn` counter-clockwise to `pp` lies in a
    /// forced sector (by its bisector).
    fn holds_forced(&self, pv: Point, pn: Point, pp: Point) -> bool {
        let n = self.chords.len();
        let (a0, a1) = ((pn - pv).atan2(), (pp - pv).atan2());
        let mid = a0 + 0.5 * ccw(a0, a1);
        let sector = (0..n).find(|&i| {
            let (c0, c1) = (self.chords[i], self.chords[(i + 1) % n]);
            ccw(c0, mid) < ccw(c0, c1) || n == 1
        });
        sector.is_some_and(|i| self.forced[i])
    }
}

/// Whether the corner of `mesh` at `v` from `next` counter-clockwise to `prev`
/// is forced by rule (a) (see the module doc): what
/// [`ForcedCorners::classify`] decides for it, for one corner of the mesh as it
/// is (the optimizer's worst-element phase asks while it changes the mesh).
pub(crate) fn corner_forced(
    mesh: &TriMesh,
    ctx: &Context,
    v: VertexId,
    next: VertexId,
    prev: VertexId,
    alpha: f64,
) -> bool {
    let ring = crate::mesh::ScratchRing::of(mesh, v);
    let edges: Vec<(VertexId, FeatureOn)> = ring
        .neighbours
        .iter()
        .filter_map(|&w| mesh.edge_tags(v, w).first().map(|&t| (w, t)))
        .collect();
    let mut near = Vec::new();
    Sectors::at(mesh, ctx, v, &edges, alpha, &mut near)
        .is_some_and(|s| s.holds_forced(mesh.position(v), mesh.position(next), mesh.position(prev)))
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
