//! The CDT baseline mesher (spade): the speed floor and comparison point of docs/design.md
//! "Data flow" (`baseline`).
//!
//! Owns: flattening the feature soup to polylines within the feature envelope μ,
//! merging points closer than ε_m, and a constrained Delaunay triangulation of the
//! padded box whose constraints are those polylines (crossings split), refined to a
//! minimum angle ([`Params::cdt_min_angle_deg`]) and to the size field within the
//! vertex budget [`Params::max_vertices`]. Spade's refinement takes one area bound for
//! the whole mesh (that of h's largest value, l): a uniform field needs that bound
//! alone. The smaller sizes of a graded field are reached in
//! rounds ([`refine_to_size`]): every triangle with an edge longer than 4/3·h at the
//! edge's midpoint (the optimizer's split bound) gets a point, its circumcentre or one
//! that splits that edge, then spade refines to the angle again.
//!
//! Guarantees to the next stage (a [`LinearMesh`]):
//! - the triangles tile the padded box (their areas sum to its area, up to an ulp
//!   of the coordinates along the box's sides, where spade's refinement may round
//!   a vertex it puts on a side);
//! - every triangle is strictly counter-clockwise, decided with the exact
//!   predicate [`crate::exact::orient2d`] on the returned f64 vertices; otherwise the
//!   result is an [`crate::Error::Meshing`], never a bad mesh;
//! - every input point and polyline vertex is a mesh vertex (up to the ε_m merge),
//!   and every constraint piece is a chain of mesh edges, listed in
//!   [`LinearMesh::edges`] once per shape with [`LineKind::Constraint`];
//! - termination: spade's refinement and the size rounds stop at the vertex
//!   budget (and the rounds after [`MAX_SIZE_ROUNDS`]); when they do, the mesh is
//!   valid, only coarser than asked (logged at info).
//!
//! Spade validates coordinates (`spade::validate_coordinate`: finite, magnitude in
//! `[2^-142, 2^201]` or zero). The input is scaled by a power of two, which is exact
//! both ways and keeps every orientation, so the padded box's largest coordinate
//! is in `[1/2, 2)`; smaller magnitudes than 2^-142 are flushed to zero.

mod input;
mod snap;

use crate::exact::{Orientation, orient2d};
use crate::fem::{FeatureEdge, LineKind};
use crate::sizing::SizeField;
use crate::stage::Stage;
use crate::svg::ShapeId;
use crate::{Drawing, Error, LinearMesh, Params, Result};
use input::{FlattenParams, PlanarInput, Pow2Scale};
use kurbo::Point;
use spade::handles::FixedVertexHandle;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, PositionInTriangulation,
    RefinementParameters, Triangulation,
};
use std::collections::HashSet;

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;
type CdtEdgeHandle<'a> =
    spade::handles::DirectedEdgeHandle<'a, Point2<f64>, (), spade::CdtEdge<()>, ()>;

/// Area of the equilateral triangle of side `l`.
fn equilateral_area(l: f64) -> f64 {
    3f64.sqrt() / 4.0 * l * l
}

/// Mesh a drawing with the CDT baseline, to the size field `field` (the
/// pipeline's, built for this drawing and `params`).
///
/// # Errors
/// [`crate::Error::Meshing`] (stage `baseline`) if spade rejects the input or the
/// result is not a valid counter-clockwise triangulation; neither happens for a
/// drawing that keeps the loader's guarantees.
pub(crate) fn triangulate(
    drawing: &Drawing,
    params: &Params,
    field: &SizeField,
) -> Result<LinearMesh> {
    let r = params.resolve(drawing.diagonal());
    let bx = input::padded_box(drawing, r.padding);
    let magnitude = [bx.x0, bx.y0, bx.x1, bx.y1]
        .into_iter()
        .fold(0.0f64, |m, c| m.max(c.abs()));
    if !(magnitude.is_finite() && magnitude > 0.0) {
        return Err(Error::meshing(
            Stage::Baseline,
            format!("the padded box {bx:?} is not finite"),
        ));
    }
    let scale = Pow2Scale::normalizing(magnitude);
    let s = |l: f64| scale.length(l);
    // The size field in scaled units, at a scaled point; `None` where it is l
    // everywhere (spade's area bound is all it takes).
    let size = |p: Point| scale.length(field.at(scale.unpoint(p)));
    let graded = (!field.is_uniform()).then_some(&size as &dyn Fn(Point) -> f64);
    // The outlines are not cut to the field here: spade splits them, keeping
    // track of the pieces it makes of one input segment, which is what stops
    // its refinement between two segments at a small angle (cut beforehand,
    // the pieces are input segments of their own: the stroke field of
    // data/svg/folder-emoji.svg then took 29346 triangles instead of 12711).
    let flat = PlanarInput::new(
        drawing,
        FlattenParams {
            scale,
            accuracy: r.mu,
            merge_distance: r.eps_m,
        },
    );
    tracing::debug!(
        points = flat.points.len(),
        pieces = flat.pieces.len(),
        merged_points = flat.merged,
        dropped_pieces = flat.dropped_pieces,
        scale_exp = scale.k,
        "baseline: flattened input"
    );
    let mut last = (0, 0);
    // Snap to a grid of pitch δ ≈ 1e-9 d; should the result still fail the gmsh-side
    // validity criteria, retry with a coarser grid (δ · 16, three times at most).
    for attempt in 0..4 {
        let delta = snap::grid_pitch(s(r.d), SNAP_REL * 16f64.powi(attempt));
        let snapped = snap::snap(&flat, delta);
        tracing::debug!(
            delta,
            rounds = snapped.rounds,
            splits = snapped.splits,
            dropped = snapped.dropped,
            points = snapped.planar.points.len(),
            pieces = snapped.planar.pieces.len(),
            "baseline: snap rounded"
        );
        let sizing = Sizing {
            size: graded,
            l: s(field.l()),
            l_min: s(r.l_min),
            round_floor: s(SIDE_SPACING * field.report().min_size),
        };
        let mesh = mesh_planar(&snapped.planar, bx, scale, params, &sizing, s(r.eps_m))?;
        let defects = gmsh_defects(&mesh);
        if defects == (0, 0) {
            tracing::debug!(
                vertices = mesh.vertices.len(),
                triangles = mesh.triangles.len(),
                feature_edges = mesh.edges.len(),
                "baseline: done"
            );
            return Ok(mesh);
        }
        tracing::info!(
            attempt,
            duplicates = defects.0,
            degenerate = defects.1,
            "baseline: mesh fails the validity criteria; retrying with a coarser snap grid"
        );
        last = defects;
    }
    Err(Error::meshing(
        Stage::Baseline,
        format!(
            "the mesh keeps {} near-duplicate nodes and {} degenerate triangles after snap rounding",
            last.0, last.1
        ),
    ))
}

/// Snap grid pitch relative to the drawing's diagonal (first attempt).
const SNAP_REL: f64 = 1e-9;

/// Relative tolerance of the acceptance criteria (near-duplicate nodes, degenerate
/// triangles), as gmsh-side validity checks use it.
const VALIDITY_REL: f64 = 1e-12;

/// Rounds of refinement to the size field at most: each halves, about, the
/// triangles still too large for it, so this covers a field spanning 2^64.
const MAX_SIZE_ROUNDS: usize = 64;

/// A triangle is too large for the field where one of its edges is longer than
/// this times h at the edge's midpoint (the optimizer's split bound).
const SPLIT_ABOVE: f64 = 4.0 / 3.0;

/// A point inserted for the size field keeps at least this times h at the point
/// from every corner of the triangle it falls in (a fresh circumcentre of a
/// Delaunay triangle is at its circumradius, above 2/3 h, from every vertex: this
/// only keeps the points of one round apart).
const MIN_SPACING: f64 = 0.5;

/// The spacing of a point put inside a triangle to split its side that cannot
/// flip ([`SIDE_OFFSET`] of the side from its midpoint): the triangle's other
/// corner is at least a quarter of the side, a third of h, away from it when
/// it does not encroach on the side, and spade would have split the side if
/// it did.
const SIDE_SPACING: f64 = 0.25;

/// How far inside its triangle, in lengths of the side, a point that splits a
/// side that cannot flip is put from the side's midpoint: within the triangle
/// when the side's angles are above 21.8° (the refinement's minimum is 25°).
const SIDE_OFFSET: f64 = 0.2;

/// A point for the size field near a side that cannot flip (a constraint or
/// the box) is kept at least this times the side's length from it when it
/// encroaches on the side (lies in its diametral circle): spade's next
/// refinement splits that side, and the point makes no sliver with its halves.
const SIDE_CLEARANCE: f64 = 0.15;

/// The size field as the refinement reads it, in scaled units.
struct Sizing<'a> {
    /// h at a scaled point, scaled; `None` where it is `l` everywhere.
    size: Option<&'a dyn Fn(Point) -> f64>,
    /// The largest size (spade's global area bound).
    l: f64,
    /// The smallest size (below its area spade refines no further).
    l_min: f64,
    /// Below the area of this size spade's refinements after the size rounds
    /// leave triangles alone. The first refinement has brought them to the
    /// angle already where it can: around a small input angle it stops, knowing
    /// which vertices it put on which input segment; a later refinement no
    /// longer knows, and would refine there down to `l_min` (a point of the
    /// rounds never makes triangles this small).
    round_floor: f64,
}

/// Triangulate snapped input: constraints added without splitting, refinement
/// (angle and size field), extraction with the exact CCW check and feature-edge
/// recovery.
fn mesh_planar(
    planar: &PlanarInput,
    bx: kurbo::Rect,
    scale: Pow2Scale,
    params: &Params,
    sizing: &Sizing<'_>,
    merge_distance: f64,
) -> Result<LinearMesh> {
    // Box corners first (indices 0..4), then the input points.
    let corners = [
        Point::new(bx.x0, bx.y0),
        Point::new(bx.x1, bx.y0),
        Point::new(bx.x1, bx.y1),
        Point::new(bx.x0, bx.y1),
    ];
    let n_corners = corners.len() as u32;
    let mut vertices: Vec<Point2<f64>> = Vec::with_capacity(planar.points.len() + 4);
    for p in corners
        .iter()
        .map(|&c| scale.point(c))
        .chain(planar.points.iter().copied())
    {
        debug_assert!(
            spade::validate_coordinate(p.x).is_ok() && spade::validate_coordinate(p.y).is_ok(),
            "internal: coordinate {p:?} out of spade's range"
        );
        vertices.push(Point2::new(p.x, p.y));
    }
    let (min_angle, max_vertices) = (params.cdt_min_angle_deg, params.max_vertices as usize);
    // After `n` vertices, ignoring triangles below the area of `floor`.
    let refinement = |n: usize, floor: f64| {
        RefinementParameters::<f64>::new()
            .with_angle_limit(AngleLimit::from_deg(min_angle))
            .with_max_allowed_area(equilateral_area(sizing.l))
            .with_min_required_area(equilateral_area(floor))
            .with_max_additional_vertices(max_vertices.saturating_sub(n))
    };
    let first = |n: usize| refinement(n, sizing.l_min);
    let later = |n: usize| refinement(n, sizing.round_floor.max(sizing.l_min));
    // Snap rounding leaves no crossing, so constraints go in without splitting; a
    // panic inside spade is still caught rather than taking the process down
    // (unwind safe: the triangulation is dropped with the panic, and the size
    // field is only read).
    let built = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let (mut cdt, skipped) = build_cdt(&vertices, &planar.pieces, n_corners, false, &first)?;
        if let Some(size) = sizing.size {
            refine_to_size(&mut cdt, size, &later, max_vertices);
        }
        Ok::<_, Error>((cdt, skipped))
    }));
    let Ok(built) = built else {
        return Err(Error::meshing(
            Stage::Baseline,
            "spade failed (panicked) on this input",
        ));
    };
    let (cdt, skipped) = built?;
    if skipped > 0 {
        tracing::warn!(
            skipped,
            "baseline: spade could not insert some snapped pieces; they are left out"
        );
    }
    extract(&cdt, scale, planar, n_corners, merge_distance, skipped == 0)
}

/// The acceptance checker's two criteria on a linear mesh: used nodes sharing a
/// cell of the grid of pitch 1e-12 · (bounding-box diagonal of the used nodes), and
/// triangles with |2A| ≤ 1e-12 · h², h² = (x-range)² + (y-range)² of their corners.
pub(super) fn gmsh_defects(mesh: &LinearMesh) -> (usize, usize) {
    let mut used = vec![false; mesh.vertices.len()];
    for t in &mesh.triangles {
        for &i in t {
            used[i as usize] = true;
        }
    }
    let pts: Vec<Point> = mesh
        .vertices
        .iter()
        .zip(&used)
        .filter(|(_, u)| **u)
        .map(|(p, _)| *p)
        .collect();
    let Some(bb) = pts
        .iter()
        .map(|&p| kurbo::Rect::from_points(p, p))
        .reduce(|a, b| a.union(b))
    else {
        return (0, 0);
    };
    let cell = VALIDITY_REL * bb.width().hypot(bb.height()) + 1e-300;
    // Rounded in f64 like the checker (an integer cast would saturate far from the
    // origin); `+ 0.0` identifies -0 with 0.
    let key = |c: f64| ((c / cell).round() + 0.0).to_bits();
    let cells: HashSet<(u64, u64)> = pts.iter().map(|p| (key(p.x), key(p.y))).collect();
    let duplicates = pts.len() - cells.len();
    let degenerate = mesh
        .triangles
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            let det = (b - a).cross(c - a);
            let dx = a.x.max(b.x).max(c.x) - a.x.min(b.x).min(c.x);
            let dy = a.y.max(b.y).max(c.y) - a.y.min(b.y).min(c.y);
            det.abs() <= VALIDITY_REL * (dx * dx + dy * dy) || det.is_nan()
        })
        .count();
    (duplicates, degenerate)
}

/// Bulk-load `vertices`, add the pieces as constraints (split at crossings when
/// `split`, else skipping those that cross), and refine.
fn build_cdt(
    vertices: &[Point2<f64>],
    pieces: &[input::Piece],
    n_corners: u32,
    split: bool,
    refinement: &dyn Fn(usize) -> RefinementParameters<f64>,
) -> Result<(Cdt, usize)> {
    let n_input = vertices.len();
    let mut cdt = Cdt::bulk_load_cdt(vertices.to_vec(), Vec::new())
        .map_err(|e| Error::meshing(Stage::Baseline, format!("spade rejected a point: {e}")))?;
    if cdt.num_vertices() != n_input {
        return Err(Error::meshing(
            Stage::Baseline,
            format!(
                "spade merged input points ({} of {n_input} kept)",
                cdt.num_vertices()
            ),
        ));
    }
    // Constraints: each undirected piece once.
    let handle = |i: u32| FixedVertexHandle::from_index((i + n_corners) as usize);
    let mut constrained: HashSet<(u32, u32)> = HashSet::new();
    let mut skipped = 0usize;
    for p in pieces {
        if constrained.insert((p.a.min(p.b), p.a.max(p.b))) {
            if split {
                cdt.add_constraint_and_split(handle(p.a), handle(p.b), |q| q);
            } else if cdt.try_add_constraint(handle(p.a), handle(p.b)).is_empty() {
                skipped += 1;
            }
        }
    }
    let n_constrained = cdt.num_vertices();
    tracing::debug!(
        constraints = constrained.len(),
        skipped,
        crossing_vertices = n_constrained - n_input,
        constraint_edges = cdt.num_constraints(),
        "baseline: constrained triangulation"
    );
    // Refinement to the minimum angle and the target edge length, within the budget.
    let result = cdt.refine(refinement(cdt.num_vertices()));
    if !result.refinement_complete {
        tracing::info!(
            vertices = cdt.num_vertices(),
            "baseline: vertex budget reached, the mesh is coarser than asked"
        );
    }
    tracing::debug!(
        steiner_vertices = cdt.num_vertices() - n_constrained,
        vertices = cdt.num_vertices(),
        triangles = cdt.num_inner_faces(),
        "baseline: refined"
    );
    Ok((cdt, skipped))
}

/// A triangle too large for the size field: where to put a point in it.
struct Oversized {
    /// Its worst edge's length over [`SPLIT_ABOVE`]·h at the edge's midpoint (> 1).
    excess: f64,
    /// The circumcentre, then a point for the worst edge: its midpoint, or for
    /// a side that cannot flip, a point [`SIDE_OFFSET`] of its length inside
    /// the triangle from its midpoint (which makes spade's next refinement
    /// split the side exactly: a midpoint computed here need not lie on it);
    /// each with its spacing. The first that [`can_insert`] allows is inserted.
    sites: [(Point, f64); 2],
}

/// Refine `cdt` to the size field `size` (scaled units, at a scaled point) in
/// rounds: every triangle with an edge longer than [`SPLIT_ABOVE`]·h at the
/// edge's midpoint gets a point (its circumcentre, else one that splits that
/// edge: see [`Oversized::sites`]; where [`can_insert`] allows, the largest
/// excess first), then spade refines to the angle again (`refinement`). Stops when no triangle is too large or none of
/// them can take a point, at the vertex budget, or after [`MAX_SIZE_ROUNDS`].
fn refine_to_size(
    cdt: &mut Cdt,
    size: &dyn Fn(Point) -> f64,
    refinement: &dyn Fn(usize) -> RefinementParameters<f64>,
    max_vertices: usize,
) {
    let start = cdt.num_vertices();
    for round in 0..MAX_SIZE_ROUNDS {
        let mut oversized = oversized_faces(cdt, size);
        if oversized.is_empty() {
            break;
        }
        oversized.sort_by(|a, b| b.excess.total_cmp(&a.excess));
        let mut inserted = 0usize;
        for o in &oversized {
            if cdt.num_vertices() >= max_vertices {
                break;
            }
            let site = o
                .sites
                .into_iter()
                .find(|&(p, spacing)| can_insert(cdt, p, spacing * size(p)));
            if let Some((p, _)) = site {
                if cdt.insert(Point2::new(p.x, p.y)).is_ok() {
                    inserted += 1;
                }
            }
        }
        tracing::debug!(
            round,
            oversized = oversized.len(),
            inserted,
            vertices = cdt.num_vertices(),
            "baseline: size round"
        );
        if inserted == 0 {
            break;
        }
        let result = cdt.refine(refinement(cdt.num_vertices()));
        if !result.refinement_complete || cdt.num_vertices() >= max_vertices {
            tracing::info!(
                vertices = cdt.num_vertices(),
                "baseline: vertex budget reached, the mesh is coarser than the size field asks"
            );
            break;
        }
    }
    tracing::debug!(
        vertices = cdt.num_vertices() - start,
        "baseline: refined to the size field"
    );
}

/// The triangles of `cdt` with an edge longer than [`SPLIT_ABOVE`]·h at the
/// edge's midpoint.
fn oversized_faces(cdt: &Cdt, size: &dyn Fn(Point) -> f64) -> Vec<Oversized> {
    let pt = |p: Point2<f64>| Point::new(p.x, p.y);
    let mut out = Vec::new();
    for f in cdt.inner_faces() {
        let mut worst: Option<(f64, (Point, f64))> = None;
        // The face is on the left of its edges (counter-clockwise).
        for e in f.adjacent_edges() {
            let (a, b) = (pt(e.from().position()), pt(e.to().position()));
            let mid = a.midpoint(b);
            let excess = a.distance(b) / (SPLIT_ABOVE * size(mid));
            if excess > 1.0 && worst.is_none_or(|(w, _)| excess > w) {
                let site = if is_fixed(e) {
                    (mid + SIDE_OFFSET * (b - a).turn_90(), SIDE_SPACING)
                } else {
                    (mid, MIN_SPACING)
                };
                worst = Some((excess, site));
            }
        }
        if let Some((excess, site)) = worst {
            out.push(Oversized {
                excess,
                sites: [(pt(f.circumcenter()), MIN_SPACING), site],
            });
        }
    }
    out
}

/// Whether an edge cannot flip: a constraint or a side of the box.
fn is_fixed(e: CdtEdgeHandle<'_>) -> bool {
    e.is_constraint_edge() || e.as_undirected().is_part_of_convex_hull()
}

/// Whether a point for the size field may go at `p`: inside the triangulation
/// (not on a vertex), at least `spacing` from the corners of the
/// triangle or edge it falls on, and, inside a triangle, clear of each side of
/// it that cannot flip (a constraint or the box): outside its diametral circle,
/// or at least [`SIDE_CLEARANCE`] times its length from it (spade's next
/// refinement then splits the side; closer, the point would leave slivers). A
/// point exactly on such a side splits it and is allowed.
fn can_insert(cdt: &Cdt, p: Point, spacing: f64) -> bool {
    if !p.is_finite() {
        return false;
    }
    let pt = |q: Point2<f64>| Point::new(q.x, q.y);
    let far_from = |q: Point| q.distance(p) >= spacing;
    match cdt.locate(Point2::new(p.x, p.y)) {
        PositionInTriangulation::OnEdge(e) => {
            let e = cdt.directed_edge(e);
            far_from(pt(e.from().position())) && far_from(pt(e.to().position()))
        }
        PositionInTriangulation::OnFace(f) => {
            let f = cdt.face(f);
            f.vertices().iter().all(|v| far_from(pt(v.position())))
                && f.adjacent_edges().iter().all(|&e| {
                    let (a, b) = (pt(e.from().position()), pt(e.to().position()));
                    // Inside the diametral circle: the angle at p is obtuse.
                    let encroaches = (a - p).dot(b - p) <= 0.0;
                    let clear = crate::mesh::point_segment_distance(p, kurbo::Line::new(a, b))
                        >= SIDE_CLEARANCE * a.distance(b);
                    !is_fixed(e) || !encroaches || clear
                })
        }
        PositionInTriangulation::OnVertex(_)
        | PositionInTriangulation::OutsideOfConvexHull(_)
        | PositionInTriangulation::NoTriangulation => false,
    }
}

/// Turn the refined triangulation back into user units and check it.
fn extract(
    cdt: &Cdt,
    scale: Pow2Scale,
    planar: &PlanarInput,
    n_corners: u32,
    merge_distance: f64,
    strict: bool,
) -> Result<LinearMesh> {
    let index = |i: usize| {
        u32::try_from(i).map_err(|_| Error::meshing(Stage::Baseline, "more than 2^32 vertices"))
    };
    let vertices: Vec<Point> = cdt
        .vertices()
        .map(|v| scale.unpoint(Point::new(v.position().x, v.position().y)))
        .collect();
    let mut triangles = Vec::with_capacity(cdt.num_inner_faces());
    for f in cdt.inner_faces() {
        let [a, b, c] = f.vertices().map(|v| v.fix().index());
        let t = [index(a)?, index(b)?, index(c)?];
        let o = orient2d(vertices[a], vertices[b], vertices[c]);
        if o != Orientation::CounterClockwise {
            return Err(Error::meshing(
                Stage::Baseline,
                format!(
                    "triangle {:?} at {:?} is {} after scaling back to user units",
                    t,
                    [vertices[a], vertices[b], vertices[c]],
                    if o == Orientation::Collinear {
                        "degenerate"
                    } else {
                        "clockwise"
                    }
                ),
            ));
        }
        triangles.push(t);
    }
    let edges = attribute_edges(cdt, planar, n_corners, merge_distance, strict)?;
    Ok(LinearMesh {
        vertices,
        triangles,
        edges,
    })
}

/// The feature edges: for every input piece, the chain of constraint edges spade
/// made of it (split at crossings and by refinement), once per (edge, shape).
fn attribute_edges(
    cdt: &Cdt,
    planar: &PlanarInput,
    n_corners: u32,
    merge_distance: f64,
    strict: bool,
) -> Result<Vec<FeatureEdge>> {
    let corridor = merge_distance.max(1e-13);
    let mut lost = 0usize;
    let mut seen: HashSet<(u32, u32, ShapeId)> = HashSet::new();
    let mut edges = Vec::new();
    let mut chain = Vec::new();
    for p in &planar.pieces {
        chain.clear();
        // The merge distance, else a few ulps of the scaled coordinates (below 2), then
        // wider in case spade rounded a crossing far off.
        let found = [corridor, corridor * 1e4, corridor * 1e8]
            .into_iter()
            .any(|c| {
                chain.clear();
                walk_constraint_chain(cdt, p.a + n_corners, p.b + n_corners, c, &mut chain)
                    .is_some()
            });
        if !found && !strict {
            // Left out by the non-splitting fallback.
            lost += 1;
            continue;
        }
        found.then_some(()).ok_or_else(|| {
            Error::meshing(
                Stage::Baseline,
                format!(
                    "internal: lost the constraint chain of a piece of shape {:?} between {:?} and {:?}",
                    p.shape,
                    planar.points[p.a as usize],
                    planar.points[p.b as usize]
                ),
            )
        })?;
        for w in chain.windows(2) {
            let (u, v) = (w[0], w[1]);
            if seen.insert((u.min(v), u.max(v), p.shape)) {
                edges.push(FeatureEdge {
                    v: [u, v],
                    shape: p.shape,
                    kind: LineKind::Constraint,
                });
            }
        }
    }
    if lost > 0 {
        tracing::info!(
            lost,
            "baseline: input pieces not conforming (crossings spade could not split)"
        );
    }
    Ok(edges)
}

/// Find the constraint edges spade made of the constraint `from`–`to` (split at
/// crossings, by refinement, and where near-collinear features overlap): a path of
/// constraint edges from `from` to `to` whose vertices all lie within `corridor`
/// (scaled units) of the segment. Pushes its vertices (both ends included) to
/// `chain`; `None` if there is none.
///
/// Every vertex spade put on the constraint lies on the segment up to rounding, so
/// such a path exists; where near-collinear features of the input interleave
/// within the corridor any path through them is as good. Breadth-first over the
/// corridor's vertices: bounded by their number.
fn walk_constraint_chain(
    cdt: &Cdt,
    from: u32,
    to: u32,
    corridor: f64,
    chain: &mut Vec<u32>,
) -> Option<()> {
    let pos = |i: u32| {
        let p = cdt
            .vertex(FixedVertexHandle::from_index(i as usize))
            .position();
        kurbo::Point::new(p.x, p.y)
    };
    let segment = kurbo::Line::new(pos(from), pos(to));
    let in_corridor = |p: kurbo::Point| {
        use kurbo::ParamCurveNearest as _;
        segment.nearest(p, 0.0).distance_sq <= corridor * corridor
    };
    let mut parent: std::collections::HashMap<u32, u32> = std::collections::HashMap::new();
    let mut queue = std::collections::VecDeque::from([from]);
    parent.insert(from, from);
    while let Some(w) = queue.pop_front() {
        if w == to {
            let mut rev = vec![to];
            let mut x = to;
            while x != from {
                x = parent[&x];
                rev.push(x);
            }
            chain.extend(rev.into_iter().rev());
            return Some(());
        }
        for e in cdt
            .vertex(FixedVertexHandle::from_index(w as usize))
            .out_edges()
        {
            if !e.is_constraint_edge() {
                continue;
            }
            let x = u32::try_from(e.to().fix().index()).ok()?;
            if parent.contains_key(&x) || !in_corridor(pos(x)) {
                continue;
            }
            parent.insert(x, w);
            queue.push_back(x);
        }
    }
    None
}

#[cfg(test)]
mod tests;
