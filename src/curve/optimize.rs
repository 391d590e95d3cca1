//! Curved mesh optimization (thesis §4.4.2 "Curved Mesh Optimization"): the
//! collapse, swap and smoothing of the linear stage, run again once the mesh
//! is to be curved, with the invariants in curved mode
//! ([`crate::ops::CurvedRule`]).
//!
//! The linear stage keeps each primary edge's curve piece turning less than
//! α = 10° (invariant 3), which forces many short edges along curves. Here that
//! bound is relaxed (to the curved rule's, 90° by default); instead every
//! element an operation touches is re-curved with its exact pieces and must be
//! certified, and the energy rule compares curved AMIPS energies (an
//! uncertified element counts `+∞`, so an operation that certifies it is an
//! improvement). No split is made.
//!
//! Schedule: one preliminary pass, then at most `max_passes` passes, each
//! 1. collapse edges shorter than 4/5 `l`, shortest first (edges made short are
//!    queued again; refused ones are retried once a face around them changed),
//!    never creating an edge longer than 4/3 `l`;
//! 2. swap interior non-feature edges where that strictly lowers the larger
//!    curved energy of their two triangles, longest first;
//! 3. smooth every movable vertex (`ops::try_smooth`; primary vertices slide
//!    along their curve) in a fixed pseudo-random order.
//!
//! It stops before a pass when the largest curved energy (of the certified
//! triangles not locked by three feature edges) is below the stop energy, and
//! after a pass that lowered the largest energy by less than 1e-2 and the mean
//! by less than 1e-3. Every loop has a budget.
//!
//! Guarantee: every operation goes through `crate::ops`, so each face it
//! created is a certified curved element with at most one curved edge, and no
//! certified face became uncertified.

use crate::fem::Order;
use crate::mesh::{EdgeKey, TriMesh, VertexId};
use crate::ops::invariants::curved;
use crate::ops::{self, Context, Outcome, Reject, try_collapse, try_smooth, try_swap};
use crate::optimize::schedule::{OpTally, Shuffle, edges, length, locked, swap_gain};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

/// Collapse edges shorter than this fraction of `l`.
const COLLAPSE_BELOW: f64 = 4.0 / 5.0;
/// A collapse may not create an edge longer than this multiple of `l`.
const MAX_STRETCH: f64 = 4.0 / 3.0;
/// Rounds of one collapse pass (refused collapses retried after changes).
const COLLAPSE_ROUNDS: usize = 4;

/// Parameters of the curved optimization, in user units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvedOptimizeOptions {
    /// Target edge length `l`.
    pub l: f64,
    /// Curved AMIPS energy (1 for equilateral) below which the mesh is good enough.
    pub stop_energy: f64,
    /// Passes after the preliminary one; 0 skips the stage.
    pub max_passes: u32,
}

/// What the curved optimization did (part of [`super::CurveStats`]).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CurvedOptimizeStats {
    /// Passes run, the preliminary one included (0: the stage was skipped).
    pub passes: u32,
    /// Edge collapses.
    pub collapse: OpTally,
    /// Edge swaps.
    pub swap: OpTally,
    /// Vertex smoothing.
    pub smooth: OpTally,
    /// Largest curved AMIPS of the certified triangles before the stage.
    pub max_amips_before: f64,
    /// Largest curved AMIPS of the certified triangles after the stage.
    pub max_amips_after: f64,
    /// Triangles before the stage.
    pub triangles_before: usize,
    /// Triangles after the stage.
    pub triangles_after: usize,
    /// Triangles that were not certified curved elements before the stage
    /// (left to the fit).
    pub uncertified_before: usize,
    /// Same, after the stage.
    pub uncertified_after: usize,
}

/// Curved energies of a mesh, for the stop rules.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Measure {
    /// Largest energy of the certified triangles not locked.
    max: f64,
    /// Largest energy of all certified triangles.
    max_all: f64,
    /// Mean energy of the certified triangles.
    mean: f64,
    /// Triangles that are not certified curved elements.
    uncertified: usize,
}

fn measure(mesh: &TriMesh, ctx: &Context, rule: &ops::CurvedRule) -> Measure {
    let mut m = Measure {
        max: 0.0,
        max_all: 0.0,
        mean: 0.0,
        uncertified: 0,
    };
    let (mut sum, mut n) = (0.0, 0usize);
    for f in mesh.faces() {
        let v = mesh.face(f);
        match curved::energy(mesh, ctx, rule, v).filter(|e| e.is_finite()) {
            None => m.uncertified += 1,
            Some(e) => {
                sum += e;
                n += 1;
                m.max_all = m.max_all.max(e);
                if !locked(mesh, v) {
                    m.max = m.max.max(e);
                }
            }
        }
    }
    if n > 0 {
        m.mean = sum / n as f64;
    }
    m
}

/// The schedule's state: the retry stamps and the tallies.
struct Schedule<'a> {
    mesh: &'a mut TriMesh,
    ctx: &'a Context,
    opts: CurvedOptimizeOptions,
    stats: CurvedOptimizeStats,
    rng: Shuffle,
    /// Operation clock: advanced by every applied operation.
    clock: u64,
    /// By vertex slot: the clock when a face around the vertex last changed.
    stamp: Vec<u64>,
    /// Refused collapses with the clock then.
    failed_collapse: HashMap<EdgeKey, u64>,
    /// Refused smoothing by vertex slot, with the clock then (`u64::MAX`: none).
    failed_smooth: Vec<u64>,
}

impl Schedule<'_> {
    fn touch(&mut self, outcome: &Outcome) {
        let Outcome::Applied(ch) = outcome else {
            return;
        };
        self.clock += 1;
        for &f in &ch.created {
            if !self.mesh.is_face_alive(f) {
                continue;
            }
            for v in self.mesh.face(f) {
                let i = v.0 as usize;
                if i >= self.stamp.len() {
                    self.stamp.resize(i + 1, 0);
                }
                self.stamp[i] = self.clock;
            }
        }
    }

    fn stamp_of(&self, v: VertexId) -> u64 {
        self.stamp.get(v.0 as usize).copied().unwrap_or(0)
    }

    fn is_short(&self, k: EdgeKey) -> bool {
        length(self.mesh, k) < COLLAPSE_BELOW * self.opts.l
    }

    /// Whether collapsing `v` into `u` creates no edge longer than 4/3 `l`.
    fn keeps_lengths(&self, u: VertexId, v: VertexId) -> bool {
        let pu = self.mesh.position(u);
        ops::ring(self.mesh, v)
            .neighbours
            .into_iter()
            .filter(|&w| w != u)
            .all(|w| pu.distance(self.mesh.position(w)) <= MAX_STRETCH * self.opts.l)
    }

    fn collapse_pass(&mut self) -> u64 {
        let mut total = 0;
        for _ in 0..COLLAPSE_ROUNDS {
            let n = self.collapse_round();
            total += n;
            if n == 0 {
                break;
            }
        }
        total
    }

    /// Every short edge once, shortest first.
    fn collapse_round(&mut self) -> u64 {
        let mut heap: BinaryHeap<Reverse<(u64, EdgeKey)>> = BinaryHeap::new();
        for k in edges(self.mesh) {
            if self.is_short(k) {
                heap.push(Reverse((length(self.mesh, k).to_bits(), k)));
            }
        }
        let mut budget = 4 * heap.len() + 16;
        let mut applied = 0;
        while let Some(Reverse((bits, k))) = heap.pop() {
            if budget == 0 {
                break;
            }
            budget -= 1;
            if !(self.mesh.is_vertex_alive(k.lo) && self.mesh.is_vertex_alive(k.hi)) {
                continue;
            }
            if length(self.mesh, k).to_bits() != bits || !self.is_short(k) {
                continue;
            }
            if let Some(&at) = self.failed_collapse.get(&k) {
                if self.stamp_of(k.lo) <= at && self.stamp_of(k.hi) <= at {
                    continue;
                }
            }
            let mut done = false;
            let mut tried = false;
            for (u, v) in [(k.lo, k.hi), (k.hi, k.lo)] {
                if !self.keeps_lengths(u, v) {
                    continue;
                }
                tried = true;
                let out = try_collapse(self.mesh, self.ctx, u, v);
                self.touch(&out);
                if self.stats.collapse.record(&out) {
                    done = true;
                    break;
                }
            }
            if !tried {
                *self
                    .stats
                    .collapse
                    .rejected
                    .entry("edge_length")
                    .or_default() += 1;
            }
            if !done {
                self.failed_collapse.insert(k, self.clock);
                continue;
            }
            applied += 1;
            let u = if self.mesh.is_vertex_alive(k.lo) {
                k.lo
            } else {
                k.hi
            };
            for w in ops::ring(self.mesh, u).neighbours {
                let e = EdgeKey::new(u, w);
                if self.is_short(e) {
                    heap.push(Reverse((length(self.mesh, e).to_bits(), e)));
                }
            }
        }
        applied
    }

    fn swap_pass(&mut self) -> u64 {
        let mut cands: Vec<(f64, EdgeKey)> = edges(self.mesh)
            .into_iter()
            .filter(|k| self.mesh.edge_tags(k.lo, k.hi).is_empty())
            .filter(|&k| swap_gain(self.mesh, self.ctx, k).is_some())
            .map(|k| (length(self.mesh, k), k))
            .collect();
        cands.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let mut applied = 0;
        for (_, k) in cands {
            if swap_gain(self.mesh, self.ctx, k).is_none() {
                continue;
            }
            let out = try_swap(self.mesh, self.ctx, k.lo, k.hi);
            self.touch(&out);
            if self.stats.swap.record(&out) {
                applied += 1;
            }
        }
        applied
    }

    fn smooth_pass(&mut self) -> u64 {
        let mut verts: Vec<VertexId> = self.mesh.vertices().collect();
        self.rng.shuffle(&mut verts);
        let mut applied = 0;
        for v in verts {
            let i = v.0 as usize;
            if i >= self.failed_smooth.len() {
                self.failed_smooth.resize(i + 1, u64::MAX);
            }
            let at = self.failed_smooth[i];
            if at != u64::MAX && self.stamp_of(v) <= at {
                continue;
            }
            let out = try_smooth(self.mesh, self.ctx, v);
            self.touch(&out);
            self.failed_smooth[i] = if out.is_applied() {
                u64::MAX
            } else {
                self.clock
            };
            if out != Outcome::Rejected(Reject::FixedVertex) && self.stats.smooth.record(&out) {
                applied += 1;
            }
        }
        applied
    }

    fn pass(&mut self) {
        let collapses = self.collapse_pass();
        let swaps = self.swap_pass();
        let smooths = self.smooth_pass();
        self.stats.passes += 1;
        tracing::debug!(
            pass = self.stats.passes,
            collapses,
            swaps,
            smooths,
            faces = self.mesh.num_faces(),
            "curved optimization pass"
        );
    }
}

/// Optimize `mesh` in curved mode (see the module doc). `ctx` must be in curved
/// mode (`ctx.curved` set); without it, or with `max_passes == 0` or a linear
/// order, nothing is done.
pub fn optimize_curved(
    mesh: &mut TriMesh,
    ctx: &Context,
    opts: &CurvedOptimizeOptions,
) -> CurvedOptimizeStats {
    let Some(rule) = ctx.curved else {
        return CurvedOptimizeStats::default();
    };
    if opts.max_passes == 0
        || rule.order == Order::Linear
        || opts.l.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return CurvedOptimizeStats::default();
    }
    let _span = tracing::info_span!("curved optimization").entered();
    let start = measure(mesh, ctx, &rule);
    let mut s = Schedule {
        stats: CurvedOptimizeStats {
            max_amips_before: start.max_all,
            triangles_before: mesh.num_faces(),
            uncertified_before: start.uncertified,
            ..CurvedOptimizeStats::default()
        },
        mesh,
        ctx,
        opts: *opts,
        rng: Shuffle(0x0063_7572_7665_6421),
        clock: 1,
        stamp: Vec::new(),
        failed_collapse: HashMap::new(),
        failed_smooth: Vec::new(),
    };
    s.pass();
    let mut last = measure(s.mesh, ctx, &rule);
    for _ in 0..opts.max_passes {
        if last.max < opts.stop_energy {
            break;
        }
        s.pass();
        let now = measure(s.mesh, ctx, &rule);
        let stalled = last.max - now.max < 1e-2 && last.mean - now.mean < 1e-3;
        last = now;
        if stalled {
            break;
        }
    }
    s.stats.max_amips_after = last.max_all;
    s.stats.uncertified_after = last.uncertified;
    s.stats.triangles_after = s.mesh.num_faces();
    s.stats
}
