//! The curving stage: a linear [`TriMesh`] whose primary feature edges carry
//! their curve pieces becomes a [`CurvedMesh`] of quadratic or cubic Lagrange
//! triangles, every one certified valid (thesis §4.4.2 "Splitting and Curving",
//! "Curved Optimization"; DESIGN "Curved elements").
//!
//! Steps of [`curve_mesh`]:
//! 1. vertices still rational are rounded (an error if one cannot be);
//! 2. every triangle with more than one curved edge (a primary edge on a cubic;
//!    primary edges on straight parents stay straight) is split (`ops::try_split`:
//!    an edge that is not curved if it has one, else its longest curved edge) until
//!    each has at most one;
//! 3. each primary edge takes its curve piece: the cubic nodes at the parameter
//!    thirds (order 3, which reproduces the piece exactly) or the parameter
//!    midpoint (order 2). When a corner is off its curve (a vertex the BSP left on
//!    a chord) the piece is moved by the linear blend of the two corner offsets,
//!    so the element still passes through its corners;
//! 4. repair of elements that are not certified, on the linear mesh: a straight
//!    sliver (exactly positive, but `det J` within the zero tolerance) is swapped,
//!    smoothed or collapsed away; for a curved element, smooth the
//!    vertex opposite the curved edge, then split the curved edge at its
//!    parameter midpoint (within [`CurveOptions::max_splits`] and never below
//!    [`CurveOptions::l_min_abs`]), re-curving and re-certifying what changed;
//! 5. curved optimization ([`super::optimize`]): collapse, swap and smoothing
//!    with the invariants in curved mode (a primary edge's piece may turn up to
//!    [`CurveOptions::curved_alpha`], every touched element certified with its
//!    exact piece, curved energies), skipped when [`CurveOptions::max_passes`]
//!    is 0; the exact shape is then taken again on the optimized mesh;
//! 6. the elements still not certified get a constrained fit of their free
//!    nodes (the curved edge's inner nodes, shared by both triangles on that
//!    edge, and the two centres): the largest certified blend toward the
//!    straight edge, then a pattern search minimising the nodes' distance to
//!    the curve under certified positivity of both triangles; if no curved
//!    position is certified, the edge stays straight (both neighbours straight
//!    there).
//!
//! Guarantees: every element of the returned mesh is certified
//! ([`jacobian::certify_element`] says `Certified`; the last step re-checks all of
//! them and returns [`Error::Meshing`] otherwise). Nodes on an edge are shared by
//! both triangles on it and by the edge's line element.

use super::optimize::{CurvedOptimizeOptions, CurvedOptimizeStats, optimize_curved};
use crate::element::Order;
use crate::element::jacobian::{self, CertifyOptions};
use crate::element::triangle::{self as element, EDGES, straight_inner};
use crate::fem::{FemMesh, LineKind};
use crate::mesh::{EdgeKey, FaceId, FeatureOn, TriMesh, VertexId};
use crate::ops::invariants::curved::{self, curved_tag, on_cubic, primary};
use crate::ops::{self, Context, CurvedRule, Outcome};
use crate::svg::ShapeId;
use crate::{Error, Result};
use kurbo::{ParamCurveNearest, Point, Vec2};
use std::collections::HashMap;

/// How the curving stage works.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct CurveOptions {
    /// Element order of the output (1: straight, 2: quadratic, 3: cubic).
    pub order: Order,
    /// The input's bounding-box diagonal `d` (user units): distances in
    /// [`CurveStats`] are relative to it.
    pub d: f64,
    /// Curved edges shorter than this (user units) are not split for repair.
    pub l_min_abs: f64,
    /// Most splits (multi-primary triangles and repair together).
    pub max_splits: usize,
    /// Rounds of the repair on the linear mesh (smooth, then split).
    pub repair_rounds: usize,
    /// Pattern-search iterations of one fit.
    pub fit_iterations: usize,
    /// Smallest certified Jacobian ratio (`lower / upper` of the certificate) a
    /// fitted element may have: the fit stops short of near-degenerate elements.
    pub fit_min_ratio: f64,
    /// How elements are certified while curving.
    pub certify: CertifyOptions,
    /// Target edge length `l` of the curved optimization (user units).
    pub l_abs: f64,
    /// Curved AMIPS energy below which the curved optimization stops.
    pub stop_energy: f64,
    /// Passes of the curved optimization after its preliminary one; 0 skips it.
    pub max_passes: u32,
    /// Bound on the turn of a primary edge's curve piece in the curved
    /// optimization, radians (strict; less than π).
    pub curved_alpha: f64,
}

impl CurveOptions {
    /// `d` as given, `l_min = 1e-4 · d`, 10 000 splits, 8 repair rounds, 80 fit
    /// iterations, fitted ratio ≥ 0.01, validity-only certification; curved
    /// optimization with `l = d / 20`, stop energy 10, 10 passes, turn bound 90°.
    pub fn new(order: Order, d: f64) -> Self {
        CurveOptions {
            order,
            d,
            l_min_abs: 1e-4 * d,
            max_splits: 10_000,
            repair_rounds: 8,
            fit_iterations: 80,
            fit_min_ratio: 0.01,
            certify: CertifyOptions::VALIDITY,
            l_abs: d / 20.0,
            stop_energy: 10.0,
            max_passes: 10,
            curved_alpha: std::f64::consts::FRAC_PI_2,
        }
    }
    /// Set the minimal edge length below which curved edges are not split.
    pub fn with_l_min_abs(mut self, l: f64) -> Self {
        self.l_min_abs = l;
        self
    }
    /// Set the split budget.
    pub fn with_max_splits(mut self, n: usize) -> Self {
        self.max_splits = n;
        self
    }
    /// Set the number of repair rounds.
    pub fn with_repair_rounds(mut self, n: usize) -> Self {
        self.repair_rounds = n;
        self
    }
    /// Set the target edge length `l` (user units) of the curved optimization.
    pub fn with_l_abs(mut self, l: f64) -> Self {
        self.l_abs = l;
        self
    }
    /// Set the curved optimization's stop energy and pass limit (0 skips it).
    pub fn with_stop_curved(mut self, energy: f64, max_passes: u32) -> Self {
        self.stop_energy = energy;
        self.max_passes = max_passes;
        self
    }
}

/// What the curving stage did (part of `--stats`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CurveStats {
    /// Element order.
    pub order: u8,
    /// Triangles with an edge on a curved (cubic) feature that is curved in the output.
    pub curved_triangles: usize,
    /// Of those, triangles whose curved edge or centre was fitted (not the exact piece).
    pub fitted_triangles: usize,
    /// Triangles left straight on a curved feature for lack of a valid fit.
    pub straight_triangles: usize,
    /// Splits of triangles with more than one primary edge.
    pub splits_multi_primary: usize,
    /// Splits of curved edges to repair elements.
    pub splits_repair: usize,
    /// Smoothings applied to repair elements.
    pub smooths_repair: usize,
    /// Local operations applied to straight slivers that could not be certified.
    pub sliver_repairs: usize,
    /// Largest sampled distance of a primary edge from its curve piece, relative to `d`.
    pub max_curve_distance_rel: f64,
    /// Mean over primary edges of their largest sampled distance, relative to `d`.
    pub mean_curve_distance_rel: f64,
    /// Largest distance of a primary edge's corner from its curve point `c(t)`,
    /// relative to `d`: vertices the linear mesh left off their curve (the curved
    /// edge follows the curve up to this offset).
    pub max_corner_offset_rel: f64,
    /// Smallest certified Jacobian ratio (lower bound of `min det J / max det J`) of
    /// the curved elements (1 when none is curved).
    pub min_jacobian_ratio: f64,
    /// What the curved optimization did.
    pub optimization: CurvedOptimizeStats,
}

/// A mesh of Lagrange triangles of one order, with its feature lines (gmsh node order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CurvedMesh {
    /// Element order.
    pub order: Option<Order>,
    /// All nodes: vertices first (live vertices in id order), then edge and centre nodes.
    pub nodes: Vec<Point>,
    /// Flat connectivity, `order.triangle_nodes()` per triangle (gmsh types 2 / 9 / 21).
    pub triangles: Vec<u32>,
    /// Flat connectivity of the feature lines, `order.line_nodes()` per line
    /// (ends, then inner nodes along the line; gmsh types 1 / 8 / 26).
    pub lines: Vec<u32>,
    /// The shape and kind of each line.
    pub line_feature: Vec<(ShapeId, LineKind)>,
}

impl CurvedMesh {
    /// The element order (linear when unset).
    pub fn order(&self) -> Order {
        self.order.unwrap_or(Order::Linear)
    }
}

/// The curved inner nodes (from `lo` to `hi`) of a primary edge on a cubic, or
/// `None` if the edge is not such an edge (straight parents stay straight).
fn curved_inner(mesh: &TriMesh, ctx: &Context, order: Order, key: EdgeKey) -> Option<Vec<Point>> {
    curved::exact_inner(mesh, ctx, order, key)
}

/// Inner nodes and centre offsets that differ from the straight defaults.
#[derive(Clone, Debug, Default)]
struct Bend {
    /// Inner nodes of curved edges, from `lo` to `hi`.
    edges: HashMap<EdgeKey, Vec<Point>>,
    /// Offset of a cubic centre node from the mean of the other nine.
    centre: HashMap<FaceId, Vec2>,
}

impl Bend {
    /// The Lagrange nodes (gmsh order) of face `f`.
    fn element(&self, mesh: &TriMesh, order: Order, f: FaceId) -> Vec<Point> {
        let v = mesh.face(f);
        let mut reversed: [Option<Vec<Point>>; 3] = [None, None, None];
        let mut inner: [Option<&[Point]>; 3] = [None; 3];
        for (e, [i, j]) in EDGES.into_iter().enumerate() {
            let key = EdgeKey::new(v[i], v[j]);
            if let Some(pts) = self.edges.get(&key) {
                if key.lo == v[i] {
                    inner[e] = Some(pts);
                } else {
                    reversed[e] = Some(pts.iter().rev().copied().collect());
                }
            }
        }
        for (e, r) in reversed.iter().enumerate() {
            if let Some(r) = r {
                inner[e] = Some(r);
            }
        }
        let centre = self.centre.get(&f).copied().unwrap_or(Vec2::ZERO);
        element::nodes(order, v.map(|x| mesh.position(x)), inner, centre)
    }

    /// Whether face `f` is certified with these nodes.
    fn certified(&self, mesh: &TriMesh, order: Order, f: FaceId, opts: &CertifyOptions) -> bool {
        self.certificate(mesh, order, f, opts)
            .is_some_and(|c| c.is_certified())
    }

    fn certificate(
        &self,
        mesh: &TriMesh,
        order: Order,
        f: FaceId,
        opts: &CertifyOptions,
    ) -> Option<jacobian::Certificate> {
        element::certificate(order, &self.element(mesh, order, f), opts)
    }
}

/// The edges of face `f` as keys, in gmsh order.
fn face_edges(mesh: &TriMesh, f: FaceId) -> [EdgeKey; 3] {
    let v = mesh.face(f);
    EDGES.map(|[i, j]| EdgeKey::new(v[i], v[j]))
}

/// Curve every primary edge of `mesh` (see the module doc), splitting and
/// repairing on `mesh` first. `feature` names the shape and kind of each tag (as
/// for [`crate::fem::LinearMesh::from_trimesh`]).
///
/// # Errors
/// [`Error::Meshing`] (stage `curve`) if a vertex stays rational, or an element
/// cannot be certified even straight: a sliver of the linear mesh, exactly
/// positive but with `det J` within the zero tolerance, that no local operation
/// could remove (e.g. between two features 1e-16 apart).
pub fn curve_mesh(
    mesh: &mut TriMesh,
    ctx: &Context,
    opts: &CurveOptions,
    feature: impl Fn(&FeatureOn) -> (ShapeId, LineKind),
) -> Result<(CurvedMesh, CurveStats)> {
    let _span = tracing::info_span!("curve", order = opts.order as u8).entered();
    round_all(mesh, ctx)?;
    let order = opts.order;
    let mut stats = CurveStats {
        order: order as u8,
        min_jacobian_ratio: 1.0,
        ..CurveStats::default()
    };
    let mut shape = Bend::default();
    if order != Order::Linear {
        let mut budget = opts.max_splits;
        stats.splits_multi_primary += split_multi_primary(mesh, ctx, &mut budget);
        repair(mesh, ctx, opts, &mut stats, &mut budget);
        if opts.max_passes > 0 {
            let rule = CurvedRule {
                order,
                certify: opts.certify,
                alpha: opts.curved_alpha,
            };
            let curved_opts = CurvedOptimizeOptions {
                l: opts.l_abs,
                stop_energy: opts.stop_energy,
                max_passes: opts.max_passes,
            };
            stats.optimization = optimize_curved(mesh, &ctx.with_curved(rule), &curved_opts);
        }
        shape = exact_shape(mesh, ctx, order);
        fit_all(mesh, opts, &mut shape, &mut stats);
    }
    let curved = assemble(mesh, order, &shape, feature);
    finish_stats(mesh, ctx, opts, &shape, &curved, &mut stats)?;
    tracing::debug!(?stats, "curving done");
    Ok((curved, stats))
}

/// Round every rational vertex (the output has `f64` vertices only).
fn round_all(mesh: &mut TriMesh, ctx: &Context) -> Result<()> {
    let rational: Vec<VertexId> = mesh.vertices().filter(|&v| mesh.is_rational(v)).collect();
    for v in rational {
        ops::try_round(mesh, ctx, v);
    }
    let left = mesh.vertices().filter(|&v| mesh.is_rational(v)).count();
    if left > 0 {
        return Err(Error::meshing(
            "curve",
            format!("{left} vertices could not be rounded to f64 without inverting a triangle"),
        ));
    }
    Ok(())
}

/// Split triangles with two or three curved edges until each has at most one
/// (or the budget runs out). Returns the number of splits.
fn split_multi_primary(mesh: &mut TriMesh, ctx: &Context, budget: &mut usize) -> usize {
    let mut done = 0;
    // Each pass halves the offending configurations; a few passes suffice.
    for _ in 0..16 {
        let bad: Vec<FaceId> = mesh
            .faces()
            .filter(|&f| curved_edges(mesh, ctx, f).len() > 1)
            .collect();
        if bad.is_empty() || *budget == 0 {
            break;
        }
        let mut progress = false;
        for f in bad {
            if *budget == 0 {
                break;
            }
            if !mesh.is_face_alive(f) || curved_edges(mesh, ctx, f).len() < 2 {
                continue;
            }
            let edges = face_edges(mesh, f);
            let len = |k: &EdgeKey| (mesh.position(k.hi) - mesh.position(k.lo)).hypot();
            // Prefer the non-primary edge (it separates the primary ones), then the longest.
            let mut order: Vec<EdgeKey> = edges.to_vec();
            order.sort_by(|a, b| {
                let (pa, pb) = (
                    curved_tag(mesh, ctx, *a).is_some(),
                    curved_tag(mesh, ctx, *b).is_some(),
                );
                pa.cmp(&pb).then(len(b).total_cmp(&len(a)))
            });
            for k in order {
                if ops::try_split(mesh, ctx, k.lo, k.hi).is_applied() {
                    *budget -= 1;
                    done += 1;
                    progress = true;
                    break;
                }
            }
        }
        if !progress {
            break;
        }
    }
    done
}

/// The curved edges (primary, on a cubic) of face `f`.
fn curved_edges(mesh: &TriMesh, ctx: &Context, f: FaceId) -> Vec<EdgeKey> {
    face_edges(mesh, f)
        .into_iter()
        .filter(|k| curved_tag(mesh, ctx, *k).is_some())
        .collect()
}

/// The exact curved shape: every primary edge takes its curve piece.
fn exact_shape(mesh: &TriMesh, ctx: &Context, order: Order) -> Bend {
    let mut shape = Bend::default();
    let keys: Vec<EdgeKey> = mesh.tagged_edges().map(|(k, _)| k).collect();
    for key in keys {
        if let Some(inner) = curved_inner(mesh, ctx, order, key) {
            shape.edges.insert(key, inner);
        }
    }
    shape
}

/// Faces with a curved edge that are not certified.
fn uncertified(mesh: &TriMesh, shape: &Bend, order: Order, opts: &CertifyOptions) -> Vec<FaceId> {
    let mut bad: Vec<FaceId> = Vec::new();
    let mut on_edge = Vec::new();
    for key in shape.edges.keys() {
        mesh.faces_on_edge(key.lo, key.hi, &mut on_edge);
        for &f in &on_edge {
            if !bad.contains(&f) && !shape.certified(mesh, order, f, opts) {
                bad.push(f);
            }
        }
    }
    bad.sort_unstable();
    bad
}

/// Straight faces that are not certified at `order`: slivers whose exact
/// orientation is positive but whose `det J` is within the zero tolerance.
fn uncertified_straight(
    mesh: &TriMesh,
    shape: &Bend,
    order: Order,
    opts: &CertifyOptions,
) -> Vec<FaceId> {
    mesh.faces()
        .filter(|&f| {
            face_edges(mesh, f)
                .iter()
                .all(|k| !shape.edges.contains_key(k))
                && !shape.certified(mesh, order, f, opts)
        })
        .collect()
}

/// Try to remove a sliver: swap its longest edge, smooth its vertices, collapse
/// its shortest edge (the local operations keep the linear invariants).
fn repair_sliver(mesh: &mut TriMesh, ctx: &Context, f: FaceId) -> bool {
    let mut edges = face_edges(mesh, f);
    let len = |k: &EdgeKey| (mesh.position(k.hi) - mesh.position(k.lo)).hypot();
    edges.sort_by(|a, b| len(b).total_cmp(&len(a)));
    for k in &edges {
        if ops::try_swap(mesh, ctx, k.lo, k.hi).is_applied() {
            return true;
        }
    }
    for v in mesh.face(f) {
        if ops::try_smooth(mesh, ctx, v).is_applied() {
            return true;
        }
    }
    let k = edges[2];
    ops::try_collapse(mesh, ctx, k.lo, k.hi).is_applied()
        || ops::try_collapse(mesh, ctx, k.hi, k.lo).is_applied()
}

/// Repair on the linear mesh: smooth the vertex opposite a failing curved edge,
/// and if that does not certify the element, split the curved edge.
fn repair(
    mesh: &mut TriMesh,
    ctx: &Context,
    opts: &CurveOptions,
    stats: &mut CurveStats,
    budget: &mut usize,
) {
    let order = opts.order;
    for _ in 0..opts.repair_rounds {
        let shape = exact_shape(mesh, ctx, order);
        let bad = uncertified(mesh, &shape, order, &opts.certify);
        let slivers = uncertified_straight(mesh, &shape, order, &opts.certify);
        tracing::debug!(
            bad = bad.len(),
            slivers = slivers.len(),
            "curving repair round"
        );
        if bad.is_empty() && slivers.is_empty() {
            return;
        }
        let mut progress = false;
        for f in slivers {
            if mesh.is_face_alive(f) && repair_sliver(mesh, ctx, f) {
                stats.sliver_repairs += 1;
                progress = true;
            }
        }
        for f in bad {
            if !mesh.is_face_alive(f) {
                continue;
            }
            let curved = curved_edges(mesh, ctx, f);
            let Some(&key) = curved.first() else {
                continue;
            };
            let opposite: Vec<VertexId> = mesh
                .face(f)
                .into_iter()
                .filter(|&v| v != key.lo && v != key.hi)
                .collect();
            let mut fixed = false;
            for v in opposite {
                if ops::try_smooth(mesh, ctx, v).is_applied() {
                    stats.smooths_repair += 1;
                    progress = true;
                    let shape = exact_shape_around(mesh, ctx, order, v);
                    fixed = mesh
                        .incident_faces(v)
                        .into_iter()
                        .all(|g| shape.certified(mesh, order, g, &opts.certify));
                }
            }
            if fixed || *budget == 0 || !mesh.is_face_alive(f) {
                continue;
            }
            let len = (mesh.position(key.hi) - mesh.position(key.lo)).hypot();
            if len < 2.0 * opts.l_min_abs || curved_tag(mesh, ctx, key).is_none() {
                continue;
            }
            if let Outcome::Applied(_) = ops::try_split(mesh, ctx, key.lo, key.hi) {
                *budget -= 1;
                stats.splits_repair += 1;
                progress = true;
            }
        }
        stats.splits_multi_primary += split_multi_primary(mesh, ctx, budget);
        if !progress {
            return;
        }
    }
}

/// The exact shape of the primary edges of the faces around `v`.
fn exact_shape_around(mesh: &TriMesh, ctx: &Context, order: Order, v: VertexId) -> Bend {
    let mut shape = Bend::default();
    for f in mesh.incident_faces(v) {
        for key in face_edges(mesh, f) {
            if let Some(inner) = curved_inner(mesh, ctx, order, key) {
                shape.edges.insert(key, inner);
            }
        }
    }
    shape
}

/// How a failing curved edge ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Fit {
    /// Curved, with fitted nodes.
    Fitted,
    /// Straight: no certified curved position found.
    Straight,
}

/// Fit every curved edge of an uncertified face; straighten what cannot be fitted.
fn fit_all(mesh: &TriMesh, opts: &CurveOptions, shape: &mut Bend, stats: &mut CurveStats) {
    let order = opts.order;
    let bad = uncertified(mesh, shape, order, &opts.certify);
    let mut fitted: Vec<FaceId> = Vec::new();
    let mut straight: Vec<FaceId> = Vec::new();
    let mut faces = Vec::new();
    for f in bad {
        if shape.certified(mesh, order, f, &opts.certify) {
            continue; // fixed by the fit of a neighbouring edge
        }
        for key in face_edges(mesh, f) {
            let Some(target) = shape.edges.get(&key).cloned() else {
                continue;
            };
            mesh.faces_on_edge(key.lo, key.hi, &mut faces);
            let out = fit_edge(mesh, opts, shape, key, &faces, &target);
            match out {
                Fit::Fitted => fitted.extend(&faces),
                Fit::Straight => straight.extend(&faces),
            }
        }
        if !shape.certified(mesh, order, f, &opts.certify) {
            // Last resort for a face whose edges failed together: all straight.
            for key in face_edges(mesh, f) {
                if shape.edges.remove(&key).is_some() {
                    mesh.faces_on_edge(key.lo, key.hi, &mut faces);
                    for &g in &faces {
                        shape.centre.remove(&g);
                        straight.push(g);
                    }
                }
            }
            shape.centre.remove(&f);
        }
    }
    fitted.sort_unstable();
    fitted.dedup();
    straight.sort_unstable();
    straight.dedup();
    fitted.retain(|f| straight.binary_search(f).is_err());
    stats.fitted_triangles = fitted.len();
    stats.straight_triangles = straight.len();
}

/// Constrained fit of the inner nodes of the curved edge `key` (shared by
/// `faces`) and of those faces' centres: minimise the distance of the inner
/// nodes to `target` subject to both faces being certified.
fn fit_edge(
    mesh: &TriMesh,
    opts: &CurveOptions,
    shape: &mut Bend,
    key: EdgeKey,
    faces: &[FaceId],
    target: &[Point],
) -> Fit {
    let order = opts.order;
    let (a, b) = (mesh.position(key.lo), mesh.position(key.hi));
    let straight = straight_inner(a, b, order);
    let h = (b - a).hypot();
    let feasible = |shape: &Bend| -> Option<f64> {
        let mut margin = f64::INFINITY;
        for &f in faces {
            let c = shape.certificate(mesh, order, f, &opts.certify)?;
            if !c.is_certified() || c.ratio() < opts.fit_min_ratio {
                return None;
            }
            margin = margin.min(c.ratio());
        }
        Some(margin)
    };
    let dist2 =
        |q: &[Point]| -> f64 { q.iter().zip(target).map(|(p, t)| (*p - *t).hypot2()).sum() };
    let blend = |s: f64| -> Vec<Point> {
        straight
            .iter()
            .zip(target)
            .map(|(p, t)| p.lerp(*t, s))
            .collect()
    };
    for &f in faces {
        shape.centre.remove(&f);
    }
    // The largest certified blend toward the curve (0 = straight).
    shape.edges.insert(key, straight.clone());
    if feasible(shape).is_none() {
        shape.edges.remove(&key);
        return Fit::Straight;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        shape.edges.insert(key, blend(mid));
        if feasible(shape).is_some() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut q = blend(lo);
    shape.edges.insert(key, q.clone());
    let mut margin = feasible(shape).expect("internal: the blend search keeps a certified state");
    let mut best = dist2(&q);
    // Pattern search: edge nodes toward the curve, centres toward more margin.
    let mut step = q
        .iter()
        .zip(target)
        .map(|(p, t)| (*p - *t).hypot())
        .fold(0.0, f64::max)
        .max(1e-3 * h);
    let dirs = [
        Vec2::new(1.0, 0.0),
        Vec2::new(-1.0, 0.0),
        Vec2::new(0.0, 1.0),
        Vec2::new(0.0, -1.0),
    ];
    for _ in 0..opts.fit_iterations {
        if best <= (1e-12 * h).powi(2) {
            break;
        }
        let mut improved = false;
        for i in 0..q.len() {
            let toward = target[i] - q[i];
            let mut cand_dirs = dirs.to_vec();
            if toward.hypot() > 0.0 {
                let u = toward.normalize();
                cand_dirs.insert(0, u);
                cand_dirs.push(Vec2::new(-u.y, u.x));
                cand_dirs.push(Vec2::new(u.y, -u.x));
            }
            for d in cand_dirs {
                let mut cand = q.clone();
                cand[i] += d * step.min(toward.hypot().max(step * 0.5));
                let dd = dist2(&cand);
                if dd >= best {
                    continue;
                }
                shape.edges.insert(key, cand.clone());
                if let Some(m) = feasible(shape) {
                    q = cand;
                    best = dd;
                    margin = m;
                    improved = true;
                    break;
                }
                shape.edges.insert(key, q.clone());
            }
        }
        if order == Order::Cubic {
            for &f in faces {
                for d in dirs {
                    let old = shape.centre.get(&f).copied();
                    let off = old.unwrap_or(Vec2::ZERO) + d * step;
                    shape.centre.insert(f, off);
                    match feasible(shape) {
                        Some(m) if m > margin => {
                            margin = m;
                            improved = true;
                        }
                        _ => match old {
                            Some(o) => {
                                shape.centre.insert(f, o);
                            }
                            None => {
                                shape.centre.remove(&f);
                            }
                        },
                    }
                }
            }
        }
        if !improved {
            step *= 0.5;
            if step < 1e-9 * h {
                break;
            }
        }
    }
    shape.edges.insert(key, q.clone());
    if dist2(&q) >= dist2(&straight) * (1.0 - 1e-12) {
        // Nothing better than straight: the plain straight edge.
        shape.edges.remove(&key);
        for &f in faces {
            shape.centre.remove(&f);
        }
        return Fit::Straight;
    }
    Fit::Fitted
}

/// Number the nodes and write the elements and feature lines.
fn assemble(
    mesh: &TriMesh,
    order: Order,
    shape: &Bend,
    feature: impl Fn(&FeatureOn) -> (ShapeId, LineKind),
) -> CurvedMesh {
    let mut index = vec![u32::MAX; mesh.vertex_capacity()];
    let mut nodes: Vec<Point> = Vec::with_capacity(mesh.num_vertices());
    let next =
        |nodes: &Vec<Point>| u32::try_from(nodes.len()).expect("internal: node count fits u32");
    for v in mesh.vertices() {
        index[v.index()] = next(&nodes);
        nodes.push(mesh.position(v));
    }
    let inner_count = order as usize - 1;
    // Inner node indices of each edge, from lo to hi.
    let mut edge_nodes: HashMap<EdgeKey, Vec<u32>> = HashMap::new();
    let mut edge_inner = |nodes: &mut Vec<Point>, key: EdgeKey| -> Vec<u32> {
        edge_nodes
            .entry(key)
            .or_insert_with(|| {
                let pts = shape.edges.get(&key).cloned().unwrap_or_else(|| {
                    straight_inner(mesh.position(key.lo), mesh.position(key.hi), order)
                });
                pts.into_iter()
                    .map(|p| {
                        let i = next(nodes);
                        nodes.push(p);
                        i
                    })
                    .collect()
            })
            .clone()
    };
    let mut faces: Vec<FaceId> = mesh.faces().collect();
    faces.sort_unstable();
    let mut triangles = Vec::with_capacity(faces.len() * order.triangle_nodes());
    for &f in &faces {
        let v = mesh.face(f);
        triangles.extend(v.map(|x| index[x.index()]));
        if inner_count == 0 {
            continue;
        }
        for [i, j] in EDGES {
            let key = EdgeKey::new(v[i], v[j]);
            let ids = edge_inner(&mut nodes, key);
            if key.lo == v[i] {
                triangles.extend(ids);
            } else {
                triangles.extend(ids.into_iter().rev());
            }
        }
        if order == Order::Cubic {
            let el = shape.element(mesh, order, f);
            triangles.push(next(&nodes));
            nodes.push(el[9]);
        }
    }
    let mut tagged: Vec<(EdgeKey, Vec<FeatureOn>)> =
        mesh.tagged_edges().map(|(k, t)| (k, t.to_vec())).collect();
    tagged.sort_unstable_by_key(|(k, _)| *k);
    let mut lines = Vec::new();
    let mut line_feature: Vec<(ShapeId, LineKind)> = Vec::new();
    for (key, tags) in tagged {
        let first = line_feature.len();
        for t in &tags {
            let fk = feature(t);
            if line_feature[first..].contains(&fk) {
                continue;
            }
            line_feature.push(fk);
            lines.push(index[key.lo.index()]);
            lines.push(index[key.hi.index()]);
            if inner_count > 0 {
                lines.extend(edge_inner(&mut nodes, key));
            }
        }
    }
    CurvedMesh {
        order: Some(order),
        nodes,
        triangles,
        lines,
        line_feature,
    }
}

/// Certify every element of the output, count curved ones and measure distances.
fn finish_stats(
    mesh: &TriMesh,
    ctx: &Context,
    opts: &CurveOptions,
    shape: &Bend,
    curved: &CurvedMesh,
    stats: &mut CurveStats,
) -> Result<()> {
    let order = curved.order();
    let n = order.triangle_nodes();
    let mut pts = Vec::with_capacity(n);
    for (i, t) in curved.triangles.chunks_exact(n).enumerate() {
        pts.clear();
        pts.extend(t.iter().map(|&k| curved.nodes[k as usize]));
        let cert = jacobian::certify_element(order, &pts, &opts.certify)
            .expect("internal: element has its order's node count");
        if !cert.is_certified() {
            let mut faces: Vec<FaceId> = mesh.faces().collect();
            faces.sort_unstable();
            let f = faces[i];
            let bent = face_edges(mesh, f)
                .iter()
                .filter(|k| shape.edges.contains_key(k))
                .count();
            return Err(Error::meshing(
                "curve",
                format!(
                    "element {i} ({f:?}, {bent} curved edges, centre moved: {}) is not \
                     certified valid ({:?}): a straight sliver of the linear mesh that no \
                     local operation could remove",
                    shape.centre.contains_key(&f),
                    cert.validity
                ),
            ));
        }
    }
    // Curved elements: those with a curved edge on a cubic feature.
    let mut curved_faces: Vec<FaceId> = Vec::new();
    let mut on_edge = Vec::new();
    let mut dist_sum = 0.0;
    let mut dist_count = 0usize;
    let mut dist_max = 0.0f64;
    let mut corner_max = 0.0f64;
    let mut keys: Vec<EdgeKey> = mesh.tagged_edges().map(|(k, _)| k).collect();
    keys.sort_unstable();
    for key in keys {
        let Some((section, t)) = primary(mesh, key) else {
            continue;
        };
        let Some(sec) = ctx.section(section) else {
            continue;
        };
        let (a, b) = (mesh.position(key.lo), mesh.position(key.hi));
        let inner = shape
            .edges
            .get(&key)
            .cloned()
            .unwrap_or_else(|| straight_inner(a, b, order));
        let off = (a - sec.parent.eval(t[0]))
            .hypot()
            .max((b - sec.parent.eval(t[1])).hypot());
        corner_max = corner_max.max(off);
        let piece = sec.parent.restrict(t[0], t[1]);
        let dist = edge_distance(a, b, &inner, &piece, 1e-12 * opts.d);
        dist_max = dist_max.max(dist);
        dist_sum += dist;
        dist_count += 1;
        if on_cubic(ctx, section) && shape.edges.contains_key(&key) && order != Order::Linear {
            mesh.faces_on_edge(key.lo, key.hi, &mut on_edge);
            curved_faces.extend(&on_edge);
        }
    }
    curved_faces.sort_unstable();
    curved_faces.dedup();
    stats.curved_triangles = curved_faces.len();
    let d = if opts.d > 0.0 { opts.d } else { 1.0 };
    stats.max_curve_distance_rel = dist_max / d;
    stats.max_corner_offset_rel = corner_max / d;
    stats.mean_curve_distance_rel = if dist_count > 0 {
        dist_sum / dist_count as f64 / d
    } else {
        0.0
    };
    for f in curved_faces {
        if let Some(c) = shape.certificate(mesh, order, f, &CertifyOptions::DEFAULT) {
            stats.min_jacobian_ratio = stats.min_jacobian_ratio.min(c.ratio());
        }
    }
    Ok(())
}

/// Largest distance, over samples of the Lagrange edge `a, inner.., b`, from the
/// curve piece.
fn edge_distance(a: Point, b: Point, inner: &[Point], piece: &kurbo::CubicBez, acc: f64) -> f64 {
    const SAMPLES: usize = 16;
    let mut worst = 0.0f64;
    for i in 0..=SAMPLES {
        let s = i as f64 / SAMPLES as f64;
        let p = lagrange_edge(a, b, inner, s);
        let near = piece.nearest(p, acc.max(1e-300));
        worst = worst.max(near.distance_sq.sqrt());
    }
    worst
}

/// The point at `s ∈ [0, 1]` of the Lagrange curve through `a`, `inner` (equally
/// spaced in the parameter) and `b`.
fn lagrange_edge(a: Point, b: Point, inner: &[Point], s: f64) -> Point {
    let mut pts = Vec::with_capacity(inner.len() + 2);
    pts.push(a);
    pts.extend_from_slice(inner);
    pts.push(b);
    let n = pts.len() - 1;
    let nodes: Vec<f64> = (0..=n).map(|i| i as f64 / n as f64).collect();
    let mut out = Vec2::ZERO;
    for (i, p) in pts.iter().enumerate() {
        let mut w = 1.0;
        for (j, &sj) in nodes.iter().enumerate() {
            if j != i {
                w *= (s - sj) / (nodes[i] - sj);
            }
        }
        out += w * p.to_vec2();
    }
    out.to_point()
}

impl FemMesh {
    /// The FemMesh of a curved mesh (any order), with one physical surface
    /// `surface` and one physical curve per shape that has feature lines (named
    /// with `shape_name`), as [`FemMesh::from_linear`] does.
    /// (It lives here, with the curved mesh, so `fem` need not know the curving stage.)
    pub fn from_curved(
        mesh: &CurvedMesh,
        surface: &str,
        shape_name: impl Fn(crate::svg::ShapeId) -> String,
    ) -> FemMesh {
        FemMesh::assemble(
            mesh.order(),
            mesh.nodes.clone(),
            mesh.triangles.clone(),
            mesh.lines.clone(),
            mesh.line_feature.iter().copied(),
            surface,
            shape_name,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::Parent;
    use crate::mesh::VertexTag;
    use crate::ops::invariants::Envelope;
    use crate::ops::{CurveSection, EnergyRule};
    use kurbo::CubicBez;

    const FIXED: VertexTag = VertexTag {
        box_corner: true,
        feature_point: false,
        segment_endpoint: false,
        section_endpoint: false,
    };

    fn context(curves: &[CubicBez]) -> Context {
        Context {
            sections: curves
                .iter()
                .map(|&c| CurveSection {
                    parent: Parent::Cubic(c),
                    t: [0.0, 1.0],
                    source: None,
                })
                .collect(),
            envelope: Envelope::new(&[], 1e-3, 1e-3),
            alpha: std::f64::consts::PI,
            on_curve_abs: 1e-12,
            energy: EnergyRule::NoWorseMax,
            energy_floor: 0.0,
            curved: None,
        }
    }

    fn feature(_: &FeatureOn) -> (ShapeId, LineKind) {
        (ShapeId(0), LineKind::Primary)
    }

    /// Two triangles on the primary edge (0,0)–(1,0) (the cubic `c`), apex at
    /// `(0.5, apex)` above and `(0.5, -1)` below; all vertices fixed.
    fn diamond(c: CubicBez, apex: f64) -> (TriMesh, Context) {
        let mut m = TriMesh::new();
        let a = m.add_vertex(Point::new(0.0, 0.0), FIXED);
        let b = m.add_vertex(Point::new(1.0, 0.0), FIXED);
        let top = m.add_vertex(Point::new(0.5, apex), FIXED);
        let bottom = m.add_vertex(Point::new(0.5, -1.0), FIXED);
        m.add_face([a, b, top]);
        m.add_face([b, a, bottom]);
        m.link_all();
        m.add_edge_tag(
            a,
            b,
            FeatureOn::Primary {
                section: 0,
                t: [0.0, 1.0],
            },
        );
        (m, context(&[c]))
    }

    fn all_certified(cm: &CurvedMesh) -> bool {
        let order = cm.order();
        cm.triangles.chunks_exact(order.triangle_nodes()).all(|t| {
            let pts: Vec<Point> = t.iter().map(|&i| cm.nodes[i as usize]).collect();
            jacobian::certify_element(order, &pts, &CertifyOptions::DEFAULT)
                .is_some_and(|c| c.is_certified())
        })
    }

    #[test]
    fn gentle_curve_is_exact_and_shared() {
        let c = CubicBez::new((0.0, 0.0), (0.3, 0.1), (0.7, 0.1), (1.0, 0.0));
        let (mut m, ctx) = diamond(c, 0.6);
        let opts = CurveOptions::new(Order::Cubic, 2.0);
        let (cm, stats) = curve_mesh(&mut m, &ctx, &opts, feature).expect("curving");
        assert_eq!(stats.curved_triangles, 2, "{stats:?}");
        assert_eq!(stats.fitted_triangles + stats.straight_triangles, 0);
        assert!(stats.max_curve_distance_rel < 1e-15, "{stats:?}");
        assert!(all_certified(&cm));
        // 4 vertices + 5 edges × 2 + 2 centres; the line shares the edge's nodes
        assert_eq!(cm.nodes.len(), 4 + 10 + 2);
        assert_eq!(cm.lines.len(), 4);
        let t0 = &cm.triangles[..10];
        let t1 = &cm.triangles[10..20];
        let line = &cm.lines;
        for n in &line[2..] {
            assert!(t0.contains(n) && t1.contains(n));
        }
        // the line runs from its first end through 1/3 and 2/3 (gmsh type 26)
        let p = |i: usize| cm.nodes[line[i] as usize];
        let s = if p(0).x < p(1).x {
            1.0 / 3.0
        } else {
            2.0 / 3.0
        };
        assert!((p(2) - kurbo::ParamCurve::eval(&c, s)).hypot() < 1e-15);
        // order 2: the midpoint
        let (mut m, ctx) = diamond(c, 0.6);
        let (cm, _) = curve_mesh(
            &mut m,
            &ctx,
            &CurveOptions::new(Order::Quadratic, 2.0),
            feature,
        )
        .expect("curving");
        assert_eq!(cm.lines.len(), 3);
        assert!((cm.nodes[cm.lines[2] as usize] - Point::new(0.5, 0.075)).hypot() < 1e-15);
        assert!(all_certified(&cm));
    }

    #[test]
    fn bulge_past_the_apex_is_fitted_not_dropped() {
        // The arc rises to 0.45, above the fixed apex at 0.3: the exact element is
        // inverted, no split may help (edge below l_min), so the nodes are fitted.
        let c = CubicBez::new((0.0, 0.0), (0.3, 0.6), (0.7, 0.6), (1.0, 0.0));
        let (mut m, ctx) = diamond(c, 0.3);
        for order in [Order::Cubic, Order::Quadratic] {
            let opts = CurveOptions::new(order, 1.0).with_l_min_abs(10.0);
            let (cm, stats) = curve_mesh(&mut m.clone(), &ctx, &opts, feature).expect("curving");
            assert!(all_certified(&cm), "{order:?}");
            assert_eq!(stats.fitted_triangles, 2, "{order:?} {stats:?}");
            assert_eq!(stats.straight_triangles, 0, "{order:?} {stats:?}");
            assert_eq!(stats.curved_triangles, 2);
            // closer than the chord (0.45 away), still not the curve; the corner
            // angles bound the edge's end slopes, so it cannot rise much above 0.15
            assert!(
                stats.max_curve_distance_rel > 0.25 && stats.max_curve_distance_rel < 0.4,
                "{order:?} {stats:?}"
            );
            assert!(stats.min_jacobian_ratio >= opts.fit_min_ratio, "{stats:?}");
        }
        // With splits allowed, the repair splits first; the result is still certified.
        let opts = CurveOptions::new(Order::Cubic, 1.0).with_l_min_abs(1e-3);
        let (cm, stats) = curve_mesh(&mut m, &ctx, &opts, feature).expect("curving");
        assert!(all_certified(&cm));
        assert!(stats.splits_repair > 0, "{stats:?}");
    }

    #[test]
    fn two_curved_edges_are_separated() {
        let mut m = TriMesh::new();
        let a = m.add_vertex(Point::new(0.0, 0.0), FIXED);
        let b = m.add_vertex(Point::new(1.0, 0.0), FIXED);
        let c = m.add_vertex(Point::new(0.5, 1.0), FIXED);
        m.add_face([a, b, c]);
        m.link_all();
        let ab = CubicBez::new((0.0, 0.0), (0.3, -0.1), (0.7, -0.1), (1.0, 0.0));
        let bc = CubicBez::new((1.0, 0.0), (0.9, 0.4), (0.8, 0.7), (0.5, 1.0));
        let ctx = context(&[ab, bc]);
        m.add_edge_tag(
            a,
            b,
            FeatureOn::Primary {
                section: 0,
                t: [0.0, 1.0],
            },
        );
        m.add_edge_tag(
            b,
            c,
            FeatureOn::Primary {
                section: 1,
                t: [0.0, 1.0],
            },
        );
        let opts = CurveOptions::new(Order::Cubic, 1.5);
        let (cm, stats) = curve_mesh(&mut m, &ctx, &opts, feature).expect("curving");
        assert_eq!(stats.splits_multi_primary, 1, "{stats:?}");
        assert_eq!(m.num_faces(), 2);
        for f in m.faces() {
            assert_eq!(curved_edges(&m, &ctx, f).len(), 1);
        }
        assert!(all_certified(&cm));
        assert_eq!(stats.curved_triangles, 2);
        assert!(stats.max_curve_distance_rel < 1e-15);
    }

    #[test]
    fn lagrange_edge_interpolates() {
        let (a, b) = (Point::new(0.0, 0.0), Point::new(3.0, 0.0));
        let inner = [Point::new(1.0, 1.0), Point::new(2.0, 1.0)];
        assert!((lagrange_edge(a, b, &inner, 1.0 / 3.0) - inner[0]).hypot() < 1e-15);
        assert!((lagrange_edge(a, b, &inner, 1.0) - b).hypot() < 1e-15);
        assert!((lagrange_edge(a, b, &[], 0.5) - Point::new(1.5, 0.0)).hypot() < 1e-15);
    }
}
