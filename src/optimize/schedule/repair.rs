//! The worst-element phase: after the polish, the corners below α
//! that the drawing does not force are repaired locally, the way
//! TetWild and TriWild reach their energies when the passes stall: the targets
//! around each bad triangle are halved (graded as in `update_sizing`), and the
//! split, collapse, swap and min-max smoothing passes run on that patch only,
//! round after round while bad corners are left.
//!
//! A corner is **bad** when it is below α and not forced: the rule of the
//! quality report ([`crate::optimize::forced`]), decided from the input
//! features, never from the mesh's angles. A corner between two feature edges
//! is bad too when the features meet at an input angle the envelope lets the
//! mesh open (two secondary polylines at a tip, each edge free to turn by
//! `asin(2ε / |e|)`): the patch's smoothing moves their vertices within ε.
//! Deciding forced corners from the mesh's feature edges instead would excuse
//! most corners below α, since the worst corner usually lies between two
//! feature edges.
//!
//! The patch's operations are the main passes' own (every invariant checked,
//! collapses, swaps and moves never raise the local largest energy); only
//! their candidates are limited to the patch (the passes' [`Scope`]), so the
//! rest of the mesh keeps the sizes the coarsening left. Splits ignore the
//! energy rule, so a round is checked as a whole: one that leaves the worst
//! bad corner worse is rolled back (mesh and targets restored, the memos of
//! refusals forgotten) and run again with splits bounded by
//! [`needle_energy`].
//!
//! Each round first splits the faces with two curved primary edges, the split
//! the curved stage makes (at most one curved edge per element) without
//! smoothing: made here, the round repairs the corners it leaves.
//!
//! Why the main passes leave corners below α: the quality goal is met once the
//! largest energy is below the stop energy (5), and a needle of 7.5° has
//! energy 4.4; the sizing field is refined only around triangles above 0.9
//! times the stop energy; most such corners are at a vertex on one feature
//! facing short edges of another
//! (a fan from a vertex to a curve sampled within α, a strip between two close
//! features) that only new vertices between the features resolve.

use super::scope::{Patch, Scope};
use super::targets::Targets;
use super::{LinearOptions, REFINED_BELOW, Schedule};
use crate::mesh::{EdgeKey, FaceId, TriMesh, VertexId, corner_angles};
use crate::ops::{Context, Objective};
use crate::optimize::forced::corner_forced;
use rayon::prelude::*;

/// At most this many repair rounds (each halves the targets around the bad
/// triangles once more).
const REPAIR_ROUNDS: usize = 10;
/// Around bad corners the targets may go this many times below the sizing
/// floor (ε): at the floor the collapses undid the splits that open a corner
/// at a kink of a feature (the chord's midpoint, closer than ε to the kink).
const REPAIR_FLOOR_DIVISOR: f64 = 16.0;
/// Min-max smoothing passes per repair round.
const REPAIR_SMOOTHS: usize = 3;
/// The smallest AMIPS energy of a triangle with a corner of `alpha` (radians,
/// below 60°): the isosceles needle with that apex. A triangle of lower energy
/// has every corner above `alpha`.
pub(crate) fn needle_energy(alpha: f64) -> f64 {
    let apex = kurbo::Point::new(0.0, 0.0);
    let b = kurbo::Point::new(1.0, 0.0);
    let c = kurbo::Point::new(alpha.cos(), alpha.sin());
    crate::element::energy::amips(apex, b, c)
}

/// What a worst-element round restores when it is rolled back.
struct RepairSnapshot<'a> {
    mesh: TriMesh,
    targets: Targets<'a>,
}

/// The faces with a bad corner (see the module doc), `alpha` in radians,
/// each with its smallest bad corner.
pub(super) fn bad_faces(mesh: &TriMesh, ctx: &Context, alpha: f64) -> Vec<(FaceId, f64)> {
    let faces: Vec<FaceId> = mesh.faces().collect();
    faces
        .into_par_iter()
        .filter_map(|f| {
            let v = mesh.face(f);
            let angles = corner_angles(v.map(|x| mesh.position(x)));
            let worst = (0..3)
                .filter(|&k| {
                    angles[k] < alpha
                        && !corner_forced(mesh, ctx, v[k], v[(k + 1) % 3], v[(k + 2) % 3], alpha)
                })
                .map(|k| angles[k])
                .fold(f64::INFINITY, f64::min);
            worst.is_finite().then_some((f, worst))
        })
        .collect()
}

/// The smallest bad corner of `bad` ([`bad_faces`]; `+∞` for none).
fn worst_corner(bad: &[(FaceId, f64)]) -> f64 {
    bad.iter().map(|b| b.1).fold(f64::INFINITY, f64::min)
}

impl Schedule<'_, LinearOptions> {
    /// The worst-element phase (see the module doc). Returns the bad faces
    /// left.
    ///
    /// A round's splits ignore the energy rule (a fan of needles from a vertex
    /// is undone by splitting all its spokes, then collapsing between the new
    /// vertices, and the single splits on the way are worse than the fan); a
    /// round that leaves the worst bad corner worse than before is rolled back
    /// as a whole and run again with splits that may not make their faces
    /// worse than before or than a corner of α allows.
    pub(super) fn repair_angles(&mut self) -> usize {
        let alpha = self.driver.alpha_deg.to_radians();
        let mut bad = Vec::new();
        self.memos.forget_smooth_refusals();
        for round in 0..REPAIR_ROUNDS {
            // faces with two curved edges first: the round smooths what their
            // splits leave
            if round == 0 || !bad.is_empty() {
                self.split_multi_curved();
                bad = bad_faces(self.mesh, self.ctx, alpha);
            }
            if bad.is_empty() || self.out_of_time() {
                break;
            }
            let worst = worst_corner(&bad);
            let snap = RepairSnapshot {
                mesh: self.mesh.clone(),
                targets: self.targets.clone(),
            };
            self.repair_round(round, &bad, false);
            if self.timed_out() {
                return bad.len();
            }
            let now = bad_faces(self.mesh, self.ctx, alpha);
            if worst_corner(&now) < worst {
                tracing::debug!(round, "worst-element round rolled back");
                *self.mesh = snap.mesh;
                self.targets = snap.targets;
                self.memos.forget();
                self.repair_round(round, &bad, true);
                bad = bad_faces(self.mesh, self.ctx, alpha);
            } else {
                bad = now;
            }
        }
        if self.timed_out() {
            return bad.len();
        }
        // The rounds' collapses and swaps may have made faces with two curved
        // edges again: split them, and smooth around the new vertices only
        // (no change of topology after that).
        let new = self.split_multi_curved();
        if !new.is_empty() {
            let mut patch = Patch::default();
            for &m in &new {
                if !self.mesh.is_vertex_alive(m) {
                    continue;
                }
                patch.insert(m);
                for &w in &crate::mesh::ScratchRing::of(self.mesh, m).neighbours {
                    patch.insert(w);
                }
            }
            let scope = Scope::Patch {
                patch,
                bounded_splits: false,
            };
            self.memos.forget_smooth_refusals();
            for _ in 0..REPAIR_SMOOTHS {
                self.smooth_pass_with(&scope, Objective::MinMax);
            }
            bad = bad_faces(self.mesh, self.ctx, alpha);
        }
        bad.len()
    }

    /// Split the faces with two or more curved primary edges (on a curved
    /// parent) as the curved stage would (thesis §4.4.2: at most one curved
    /// edge per element), through an edge that is not curved, the longest
    /// first: done here, the new vertex is smoothed with the rest of the
    /// patch instead of being left where the split put it. Returns the new
    /// vertices.
    fn split_multi_curved(&mut self) -> Vec<VertexId> {
        let mesh: &TriMesh = self.mesh;
        let ctx: &crate::ops::Context = self.ctx;
        let curved =
            |k: EdgeKey| crate::ops::invariants::curved::curved_tag(mesh, ctx, k).is_some();
        let faces: Vec<FaceId> = mesh.faces().collect();
        let multi: Vec<FaceId> = faces
            .into_par_iter()
            .filter(|&f| {
                let v = mesh.face(f);
                (0..3)
                    .filter(|&i| curved(EdgeKey::new(v[i], v[(i + 1) % 3])))
                    .count()
                    > 1
            })
            .collect();
        let mut new = Vec::new();
        for f in multi {
            if !self.mesh.is_face_alive(f) {
                continue;
            }
            let v = self.mesh.face(f);
            let mut edges: Vec<(f64, EdgeKey)> = (0..3)
                .map(|i| EdgeKey::new(v[i], v[(i + 1) % 3]))
                .filter(|&k| {
                    crate::ops::invariants::curved::curved_tag(self.mesh, self.ctx, k).is_none()
                })
                .map(|k| (self.mesh.distance(k.lo, k.hi), k))
                .collect();
            if edges.len() != 1 {
                continue;
            }
            edges.sort_by(|a, b| b.0.total_cmp(&a.0));
            let k = edges[0].1;
            let out = crate::ops::try_split(self.mesh, self.ctx, k.lo, k.hi);
            self.memos.touch(self.mesh, &out, true);
            if let crate::ops::Outcome::Applied(ch) = &out
                && let Some(m) = ch.new_vertex
            {
                let targets = &mut self.targets;
                let t = 0.5 * (targets.target_of(k.lo) + targets.target_of(k.hi));
                let h = targets.field_at(self.mesh.position(m));
                targets.set_base(m, h);
                targets.set_target(m, t.min(h));
                new.push(m);
            }
            self.stats.split.record(&out);
        }
        new
    }

    /// One round of [`Self::repair_angles`] around the faces `bad`, with
    /// `bounded` splits or not.
    fn repair_round(&mut self, round: usize, bad: &[(FaceId, f64)], bounded: bool) {
        let patch = self.refine_around(bad);
        let mut scope = Scope::Patch {
            patch,
            bounded_splits: bounded,
        };
        // The swap scan's memo holds for the scope it scanned: the patch's
        // passes scan afresh, and so does the next pass over the whole mesh.
        self.memos.forget_swap_scan();
        let (_, splits) = self.split_pass(&mut scope);
        let collapses = self.collapse_pass(&scope, super::COLLAPSE_FACTOR);
        let mut swaps = self.swap_pass(&scope);
        let mut smooths = 0;
        for _ in 0..REPAIR_SMOOTHS {
            smooths += self.smooth_pass_with(&scope, Objective::MinMax);
            swaps += self.swap_pass(&scope);
        }
        self.memos.forget_swap_scan();
        tracing::debug!(
            round,
            bounded,
            bad = bad.len(),
            splits,
            collapses,
            swaps,
            smooths,
            faces = self.mesh.num_faces(),
            collapses_refused = self.stats.collapse.refused(),
            smooths_refused = self.stats.smooth.refused(),
            "worst-element round"
        );
    }

    /// The largest energy a split of `a`–`b` may make in the worst-element
    /// phase: the largest of the edge's faces now, or [`needle_energy`] of α
    /// (below which no corner is under α), whichever is larger.
    pub(super) fn split_bound(&self, a: VertexId, b: VertexId) -> f64 {
        let mut faces = Vec::new();
        self.mesh.faces_on_edge(a, b, &mut faces);
        let old = crate::ops::max_energy(self.mesh, self.ctx, &faces);
        old.max(needle_energy(self.driver.alpha_deg.to_radians()))
    }

    /// Halve the targets at the vertices of `bad` (those within
    /// [`SIZING_RADIUS`](super::SIZING_RADIUS) of their target less the farther they are, as
    /// `update_sizing` grades them). Returns the patch: those vertices and
    /// their neighbours.
    fn refine_around(&mut self, bad: &[(FaceId, f64)]) -> Patch {
        self.memos.forget_length_refusals();
        let mut seeds: Vec<VertexId> = bad.iter().flat_map(|&(f, _)| self.mesh.face(f)).collect();
        seeds.sort_unstable();
        seeds.dedup();
        let (mult, touched) = self.refine_multipliers(&seeds, 1.0);
        let mut patch = Patch::default();
        for &v in &touched {
            let top = self.targets.base_of(v);
            let floor = self.driver.l_floor / REPAIR_FLOOR_DIVISOR;
            let t = (self.targets.target_of(v) * mult[v.index()]).clamp(floor.min(top), top);
            if t < top * REFINED_BELOW {
                self.targets.set_refined(v, true);
            }
            self.targets.set_target(v, t);
            patch.insert(v);
            for &w in &crate::mesh::ScratchRing::of(self.mesh, v).neighbours {
                patch.insert(w);
            }
        }
        patch
    }
}
