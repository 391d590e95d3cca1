//! The CDT baseline mesher (spade): the speed floor and comparison point of DESIGN
//! "Data flow" (`baseline`).
//!
//! Owns: flattening the feature soup to polylines within the feature envelope μ,
//! merging points closer than ε_m, and a constrained Delaunay triangulation of the
//! padded box whose constraints are those polylines (crossings split), refined by
//! spade to a minimum angle ([`Params::cdt_min_angle_deg`]) and the target edge
//! length l within the vertex budget [`Params::max_vertices`].
//!
//! Guarantees to the next stage (a [`LinearMesh`]):
//! - the triangles tile the padded box exactly (their areas sum to its area);
//! - every triangle is strictly counter-clockwise, decided with the exact
//!   predicate `robust::orient2d` on the returned f64 vertices; otherwise the
//!   result is an [`crate::Error::Meshing`], never a bad mesh;
//! - every input point and polyline vertex is a mesh vertex (up to the ε_m merge),
//!   and every constraint piece is a chain of mesh edges, listed in
//!   [`LinearMesh::edges`] once per shape with [`LineKind::Constraint`];
//! - termination: spade's refinement stops at the vertex budget; when it does,
//!   the mesh is valid, only coarser than asked (logged at info).
//!
//! Spade validates coordinates (`spade::validate_coordinate`: finite, magnitude in
//! `[2^-142, 2^201]` or zero). The input is scaled by a power of two, which is exact
//! both ways and keeps every orientation, so the padded box's largest coordinate
//! is in `[1/2, 2)`; smaller magnitudes than 2^-142 are flushed to zero.

mod input;

use crate::fem::{FeatureEdge, LineKind};
use crate::svg::ShapeId;
use crate::{Drawing, Error, LinearMesh, Params, Result};
use input::{FlattenParams, PlanarInput, Pow2Scale};
use kurbo::Point;
use spade::handles::FixedVertexHandle;
use spade::{AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation};
use std::collections::HashSet;

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// Area of the equilateral triangle of side `l`.
fn equilateral_area(l: f64) -> f64 {
    3f64.sqrt() / 4.0 * l * l
}

/// Mesh a drawing with the CDT baseline.
///
/// # Errors
/// [`crate::Error::Meshing`] (stage `baseline`) if spade rejects the input or the
/// result is not a valid counter-clockwise triangulation; neither happens for a
/// drawing that keeps the loader's guarantees.
pub fn triangulate(drawing: &Drawing, params: &Params) -> Result<LinearMesh> {
    let r = params.resolve(drawing.diagonal());
    let bx = input::padded_box(drawing, r.padding);
    let magnitude = [bx.x0, bx.y0, bx.x1, bx.y1]
        .into_iter()
        .fold(0.0f64, |m, c| m.max(c.abs()));
    if !(magnitude.is_finite() && magnitude > 0.0) {
        return Err(Error::meshing(
            "baseline",
            format!("the padded box {bx:?} is not finite"),
        ));
    }
    let scale = Pow2Scale::normalizing(magnitude);
    let planar = PlanarInput::new(
        drawing,
        FlattenParams {
            scale,
            accuracy: r.mu,
            merge_distance: r.eps_m,
        },
    );
    tracing::debug!(
        points = planar.points.len(),
        pieces = planar.pieces.len(),
        merged_points = planar.merged,
        dropped_pieces = planar.dropped_pieces,
        scale_exp = scale.k,
        "baseline: flattened input"
    );

    // Box corners first (indices 0..4), then the input points.
    let corners = [
        Point::new(bx.x0, bx.y0),
        Point::new(bx.x1, bx.y0),
        Point::new(bx.x1, bx.y1),
        Point::new(bx.x0, bx.y1),
    ];
    let n_corners = corners.len() as u32;
    let mut vertices: Vec<Point2<f64>> = Vec::with_capacity(planar.points.len() + 4);
    for p in corners.iter().map(|&c| scale.point(c)).chain(planar.points.iter().copied()) {
        debug_assert!(
            spade::validate_coordinate(p.x).is_ok() && spade::validate_coordinate(p.y).is_ok(),
            "internal: coordinate {p:?} out of spade's range"
        );
        vertices.push(Point2::new(p.x, p.y));
    }
    let n_input = vertices.len();
    let mut cdt = Cdt::bulk_load_cdt(vertices, Vec::new())
        .map_err(|e| Error::meshing("baseline", format!("spade rejected a point: {e}")))?;
    if cdt.num_vertices() != n_input {
        return Err(Error::meshing(
            "baseline",
            format!(
                "spade merged input points ({} of {n_input} kept)",
                cdt.num_vertices()
            ),
        ));
    }

    // Constraints: each undirected piece once, crossings split.
    let handle = |i: u32| FixedVertexHandle::from_index((i + n_corners) as usize);
    let mut constrained: HashSet<(u32, u32)> = HashSet::new();
    for p in &planar.pieces {
        if constrained.insert((p.a.min(p.b), p.a.max(p.b))) {
            cdt.add_constraint_and_split(handle(p.a), handle(p.b), |q| q);
        }
    }
    let n_constrained = cdt.num_vertices();
    tracing::debug!(
        constraints = constrained.len(),
        crossing_vertices = n_constrained - n_input,
        constraint_edges = cdt.num_constraints(),
        "baseline: constrained triangulation"
    );

    // Refinement to the minimum angle and the target edge length, within the budget.
    let s = |l: f64| scale.length(l);
    let budget = (params.max_vertices as usize).saturating_sub(cdt.num_vertices());
    let refinement = RefinementParameters::<f64>::new()
        .with_angle_limit(AngleLimit::from_deg(params.cdt_min_angle_deg))
        .with_max_allowed_area(equilateral_area(s(r.l)))
        .with_min_required_area(equilateral_area(s(r.l_min)))
        .with_max_additional_vertices(budget);
    let result = cdt.refine(refinement);
    if !result.refinement_complete {
        tracing::info!(
            max_vertices = params.max_vertices,
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

    let mesh = extract(&cdt, scale, &planar, n_corners)?;
    tracing::debug!(
        vertices = mesh.vertices.len(),
        triangles = mesh.triangles.len(),
        feature_edges = mesh.edges.len(),
        "baseline: done"
    );
    Ok(mesh)
}

/// Turn the refined triangulation back into user units and check it.
fn extract(cdt: &Cdt, scale: Pow2Scale, planar: &PlanarInput, n_corners: u32) -> Result<LinearMesh> {
    let index = |i: usize| u32::try_from(i).map_err(|_| Error::meshing("baseline", "more than 2^32 vertices"));
    let vertices: Vec<Point> = cdt
        .vertices()
        .map(|v| scale.unpoint(Point::new(v.position().x, v.position().y)))
        .collect();
    let mut triangles = Vec::with_capacity(cdt.num_inner_faces());
    for f in cdt.inner_faces() {
        let [a, b, c] = f.vertices().map(|v| v.fix().index());
        let t = [index(a)?, index(b)?, index(c)?];
        let o = orient([vertices[a], vertices[b], vertices[c]]);
        if !(o > 0.0) {
            return Err(Error::meshing(
                "baseline",
                format!(
                    "triangle {:?} at {:?} is {} after scaling back to user units",
                    t,
                    [vertices[a], vertices[b], vertices[c]],
                    if o == 0.0 { "degenerate" } else { "clockwise" }
                ),
            ));
        }
        triangles.push(t);
    }
    let edges = attribute_edges(cdt, planar, n_corners)?;
    Ok(LinearMesh {
        vertices,
        triangles,
        edges,
    })
}

/// The exact orientation of a triangle: positive when counter-clockwise.
fn orient(p: [Point; 3]) -> f64 {
    let c = |p: Point| robust::Coord { x: p.x, y: p.y };
    robust::orient2d(c(p[0]), c(p[1]), c(p[2]))
}

/// The feature edges: for every input piece, the chain of constraint edges spade
/// made of it (split at crossings and by refinement), once per (edge, shape).
fn attribute_edges(cdt: &Cdt, planar: &PlanarInput, n_corners: u32) -> Result<Vec<FeatureEdge>> {
    let mut seen: HashSet<(u32, u32, ShapeId)> = HashSet::new();
    let mut edges = Vec::new();
    let mut chain = Vec::new();
    for p in &planar.pieces {
        chain.clear();
        walk_constraint_chain(cdt, p.a + n_corners, p.b + n_corners, &mut chain).ok_or_else(|| {
            Error::meshing(
                "baseline",
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
    Ok(edges)
}

/// Walk the constraint edges from vertex `from` to vertex `to`, which were joined by
/// one constraint before splitting; push the vertices passed (both ends included)
/// to `chain`. `None` if no chain is found.
///
/// Every vertex spade put on that constraint lies on the segment up to rounding, so
/// at each vertex the next one is the constraint neighbour that moves toward `to`
/// (projection on `to - from` increases) with the smallest deviation angle from
/// the segment's direction. Projections strictly increase, so the walk never
/// cycles; it is also bounded by the vertex count.
fn walk_constraint_chain(cdt: &Cdt, from: u32, to: u32, chain: &mut Vec<u32>) -> Option<()> {
    let pos = |i: u32| {
        let p = cdt.vertex(FixedVertexHandle::from_index(i as usize)).position();
        kurbo::Vec2::new(p.x, p.y)
    };
    let (p0, p1) = (pos(from), pos(to));
    let dir = p1 - p0;
    chain.push(from);
    let mut w = from;
    for _ in 0..cdt.num_vertices() {
        if w == to {
            return Some(());
        }
        let pw = pos(w);
        let mut best: Option<(f64, u32)> = None;
        for e in cdt.vertex(FixedVertexHandle::from_index(w as usize)).out_edges() {
            if !e.is_constraint_edge() {
                continue;
            }
            let x = u32::try_from(e.to().fix().index()).ok()?;
            if x == to {
                best = Some((-1.0, x));
                break;
            }
            let step = pos(x) - pw;
            let along = step.dot(dir);
            if !(along > 0.0) {
                continue;
            }
            // |sin| of the angle between the step and the segment.
            let deviation = step.cross(dir).abs() / (step.hypot() * dir.hypot());
            if best.is_none_or(|(b, _)| deviation < b) {
                best = Some((deviation, x));
            }
        }
        let (_, next) = best?;
        chain.push(next);
        w = next;
    }
    (w == to).then_some(())
}

#[cfg(test)]
mod tests;
