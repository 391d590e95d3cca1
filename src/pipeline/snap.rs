//! `--stop-after bsp`: the BSP mesh is exact, but rounded to f64 some of its
//! vertices sit within rounding distance of each other or of an opposite
//! edge, and gmsh (and `mshcheck --strict`) reject those triangles as
//! degenerate and those nodes as duplicates. Before the mesh is delivered,
//! such triangles are removed by the operations the optimizer uses (each
//! checked by the same invariants: no inversion, features kept within their
//! envelope): collapse of the shortest edge, else a swap of the longest, else
//! smoothing a corner; vertices the BSP left rational are rounded, smoothed
//! or collapsed the same way (or rounded after splitting their edges). What cannot be removed is refused with one line
//! naming it.

use crate::error::Error;
use crate::mesh::{FaceId, TriMesh, VertexId, is_sliver};
use crate::ops::{Context, try_collapse, try_round, try_smooth, try_split, try_swap};
use crate::params::Stage;
use kurbo::Point;

/// A triangle is degenerate when `|2·area| ≤ DEGENERATE_REL · h²` (h² the sum
/// of its bounding box's squared extents): 100 times `mshcheck`'s scale-free
/// tolerance, so what passes here passes there.
const DEGENERATE_REL: f64 = 1e-10;
/// Two vertices closer than this times `d` are duplicates (`mshcheck` rounds
/// nodes to 1e-12 of the padded box's diagonal, which is larger than `d`).
const DUPLICATE_REL: f64 = 1e-10;
/// Rounds of removal (each removes every degenerate triangle it can).
const ROUNDS: usize = 8;

/// A coordinate in a message: plain when moderate, else scientific.
fn num(x: f64) -> String {
    if x == 0.0 || (1e-6..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

fn degenerate(p: [Point; 3], d: f64) -> bool {
    let (a, b, c) = (p[0], p[1], p[2]);
    let short = [(a, b), (b, c), (c, a)]
        .iter()
        .any(|(p, q)| (*p - *q).hypot() <= DUPLICATE_REL * d);
    is_sliver(p, DEGENERATE_REL) || short
}

fn bad_faces(mesh: &TriMesh, d: f64) -> Vec<FaceId> {
    mesh.faces()
        .filter(|&f| degenerate(mesh.face(f).map(|v| mesh.position(v)), d))
        .collect()
}

/// One attempt to remove the degenerate face `f`: collapse along its edges,
/// shortest first (either way), then swap its edges, longest first, then
/// smooth its corners.
fn remove(mesh: &mut TriMesh, ctx: &Context, f: FaceId) -> bool {
    let v = mesh.face(f);
    let mut edges: Vec<(VertexId, VertexId)> = vec![(v[0], v[1]), (v[1], v[2]), (v[2], v[0])];
    let len = |m: &TriMesh, (a, b): (VertexId, VertexId)| (m.position(a) - m.position(b)).hypot();
    edges.sort_by(|x, y| len(mesh, *x).total_cmp(&len(mesh, *y)));
    for &(a, b) in &edges {
        if try_collapse(mesh, ctx, a, b).is_applied() || try_collapse(mesh, ctx, b, a).is_applied()
        {
            return true;
        }
    }
    if edges
        .iter()
        .rev()
        .any(|&(a, b)| try_swap(mesh, ctx, a, b).is_applied())
    {
        return true;
    }
    // Smoothing a corner (on its feature, within its envelope) may lift it.
    v.iter().any(|&u| try_smooth(mesh, ctx, u).is_applied())
}

/// Remove the triangles of `mesh` that are degenerate in f64, and refuse
/// (naming the first) when some remain or two vertices coincide: the
/// rational vertices rounded or collapsed ([`round_rational`]), the
/// degenerate faces removed ([`remove_degenerate`]), then what is left
/// refused ([`refuse_degenerate`]). Returns how many vertices and faces were
/// removed.
///
/// # Errors
/// [`Error::Meshing`] in [`Stage::Bsp`] naming what could not be removed.
pub(super) fn snap_degenerate(mesh: &mut TriMesh, ctx: &Context, d: f64) -> crate::Result<usize> {
    let removed = round_rational(mesh, ctx) + remove_degenerate(mesh, ctx, d);
    refuse_degenerate(mesh, d)?;
    Ok(removed)
}

/// Round the vertices the BSP's own rounding left rational: the optimizer's
/// rounding (which may move them a few ulps), else a collapse into a
/// neighbour, else a smaller star (its edges split) rounded again. Returns
/// how many were collapsed.
fn round_rational(mesh: &mut TriMesh, ctx: &Context) -> usize {
    let mut removed = 0;
    let rational: Vec<VertexId> = mesh.vertices().filter(|&v| mesh.is_rational(v)).collect();
    for v in rational {
        if !mesh.is_vertex_alive(v)
            || try_round(mesh, ctx, v).is_applied()
            || try_smooth(mesh, ctx, v).is_applied()
        {
            continue;
        }
        let mut around: Vec<VertexId> = mesh
            .faces()
            .map(|f| mesh.face(f))
            .filter(|t| t.contains(&v))
            .flatten()
            .filter(|&u| u != v)
            .collect();
        around.sort_unstable();
        around.dedup();
        let p = mesh.position(v);
        around.sort_by(|a, b| {
            (mesh.position(*a) - p)
                .hypot()
                .total_cmp(&(mesh.position(*b) - p).hypot())
        });
        if around
            .iter()
            .any(|&u| try_collapse(mesh, ctx, u, v).is_applied())
        {
            removed += 1;
            continue;
        }
        // A smaller star may hold it: split its edges, then round again.
        for &u in &around {
            if !mesh.is_rational(v) {
                break;
            }
            if try_split(mesh, ctx, v, u).is_applied() {
                let _ =
                    try_round(mesh, ctx, v).is_applied() || try_smooth(mesh, ctx, v).is_applied();
            }
        }
    }
    removed
}

/// Remove the faces degenerate in f64, in up to [`ROUNDS`] sweeps while one
/// makes progress. Returns how many were removed.
fn remove_degenerate(mesh: &mut TriMesh, ctx: &Context, d: f64) -> usize {
    let mut removed = 0;
    for _ in 0..ROUNDS {
        let bad = bad_faces(mesh, d);
        if bad.is_empty() {
            break;
        }
        let mut progress = false;
        for f in bad {
            if mesh.is_face_alive(f)
                && degenerate(mesh.face(f).map(|v| mesh.position(v)), d)
                && remove(mesh, ctx, f)
            {
                removed += 1;
                progress = true;
            }
        }
        if !progress {
            break;
        }
    }
    removed
}

/// Refuse a mesh with a degenerate face left, or two vertices that coincide
/// within [`DUPLICATE_REL`] d.
///
/// # Errors
/// [`Error::Meshing`] in [`Stage::Bsp`] naming the first.
fn refuse_degenerate(mesh: &TriMesh, d: f64) -> crate::Result<()> {
    let bad = bad_faces(mesh, d);
    if let Some(&f) = bad.first() {
        let p = mesh.face(f).map(|v| mesh.position(v));
        return Err(Error::meshing(
            Stage::Bsp,
            format!(
                "{} triangle(s) degenerate after rounding the exact BSP mesh to f64, first with corners \
                 ({}, {}), ({}, {}), ({}, {}); the optimized mesh (--linear) has none",
                bad.len(),
                num(p[0].x),
                num(p[0].y),
                num(p[1].x),
                num(p[1].y),
                num(p[2].x),
                num(p[2].y)
            ),
        ));
    }
    // Coinciding vertices that share no triangle (the faces above catch those
    // that do).
    let mut pos: Vec<(Point, VertexId)> = mesh.vertices().map(|v| (mesh.position(v), v)).collect();
    pos.sort_by(|a, b| a.0.x.total_cmp(&b.0.x));
    let tol = DUPLICATE_REL * d;
    for (i, &(p, _)) in pos.iter().enumerate() {
        for &(q, _) in pos[i + 1..].iter().take_while(|(q, _)| q.x - p.x <= tol) {
            if (q - p).hypot() <= tol {
                return Err(Error::meshing(
                    Stage::Bsp,
                    format!(
                        "two vertices of the BSP mesh coincide after rounding to f64 at ({}, {}); \
                         the optimized mesh (--linear) has none",
                        num(p.x),
                        num(p.y)
                    ),
                ));
            }
        }
    }
    Ok(())
}
