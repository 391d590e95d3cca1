//! Cutting each seed triangle by the lines of the segments that meet its interior.

use super::seed::Seed;
use super::{BspInput, BspOptions, BspSegment, BspStats, fan};
use crate::exact::{Orientation, PointQ, line_intersection_f64, orient2d, orient2d_q};
use crate::mesh::{TriMesh, VertexId};
use crate::stage::Stage;
use crate::{Error, Result};
use kurbo::{Point, Rect};
use smallvec::SmallVec;

/// A uniform grid over the box holding, per cell, the segments whose
/// bounding box meets it. Cell indices are monotone in the coordinate, so two
/// overlapping boxes always share a cell.
struct Grid {
    x0: f64,
    y0: f64,
    inv_w: f64,
    inv_h: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl Grid {
    fn new(bbox: Rect, segments: &[BspSegment]) -> Grid {
        let side = ((segments.len() as f64).sqrt().ceil() as usize).clamp(1, 1024);
        let (nx, ny) = (side, side);
        let mut g = Grid {
            x0: bbox.x0,
            y0: bbox.y0,
            inv_w: nx as f64 / (bbox.x1 - bbox.x0),
            inv_h: ny as f64 / (bbox.y1 - bbox.y0),
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        };
        if !(g.inv_w.is_finite() && g.inv_h.is_finite()) {
            // A box too thin or too large for f64 cell arithmetic: one cell.
            g.inv_w = 0.0;
            g.inv_h = 0.0;
        }
        for (i, s) in segments.iter().enumerate() {
            if s.a == s.b {
                continue;
            }
            let i = u32::try_from(i).expect("internal: fewer than 2^32 segments");
            let (cx0, cx1, cy0, cy1) = g.range(s.a, s.b, s.b);
            for cy in cy0..=cy1 {
                for cx in cx0..=cx1 {
                    g.cells[cy * g.nx + cx].push(i);
                }
            }
        }
        g
    }

    fn index(v: f64, origin: f64, inv: f64, n: usize) -> usize {
        let t = ((v - origin) * inv).floor();
        if t.is_nan() || t < 0.0 {
            0
        } else {
            (t as usize).min(n - 1)
        }
    }

    fn range(&self, a: Point, b: Point, c: Point) -> (usize, usize, usize, usize) {
        let (xmin, xmax) = (a.x.min(b.x).min(c.x), a.x.max(b.x).max(c.x));
        let (ymin, ymax) = (a.y.min(b.y).min(c.y), a.y.max(b.y).max(c.y));
        (
            Grid::index(xmin, self.x0, self.inv_w, self.nx),
            Grid::index(xmax, self.x0, self.inv_w, self.nx),
            Grid::index(ymin, self.y0, self.inv_h, self.ny),
            Grid::index(ymax, self.y0, self.inv_h, self.ny),
        )
    }
}

/// A supporting line through two `f64` points, `a` and `b`, also held exactly.
struct Line {
    a: Point,
    b: Point,
    p: PointQ,
    q: PointQ,
}

impl Line {
    fn through(a: Point, b: Point) -> Self {
        Line {
            a,
            b,
            p: PointQ::from_point(a),
            q: PointQ::from_point(b),
        }
    }
}

/// A convex cell: its vertices counter-clockwise, as indices into the seed
/// triangle's point table ([`Cutting::points`]), each with the index (into
/// the triangle's line table) of the line carrying the edge that starts there.
type Cell = Vec<(u32, usize)>;

/// The state of one seed triangle's cutting: its lines, its points (a cell
/// names its corners by index, so a corner shared by cells is one point,
/// never a copy), and, for the line cutting now, the crossing made on each
/// edge line.
struct Cutting {
    lines: Vec<Line>,
    points: Vec<PointQ>,
    /// Per line of `lines`, the point where the line cutting now crosses it
    /// (`NONE` if not yet made): one exact intersection for the two cells
    /// beside a crossed edge, and for every piece of that edge line. (Two
    /// distinct lines that cross strictly meet at one point.)
    crossing: Vec<u32>,
    /// The entries of `crossing` set for the line cutting now.
    crossed: Vec<usize>,
}

/// No crossing made yet on this edge line ([`Cutting::crossing`]).
const NONE: u32 = u32::MAX;

impl Cutting {
    fn new(lines: Vec<Line>, points: Vec<PointQ>) -> Self {
        Cutting {
            crossing: vec![NONE; lines.len()],
            lines,
            points,
            crossed: Vec::new(),
        }
    }

    /// Add the line through `a`, `b`: the next line to cut with. Returns its index.
    fn push_line(&mut self, a: Point, b: Point) -> usize {
        for e in self.crossed.drain(..) {
            self.crossing[e] = NONE;
        }
        self.lines.push(Line::through(a, b));
        self.crossing.push(NONE);
        self.lines.len() - 1
    }

    /// The point where line `lid` (the line cutting now) crosses the edge
    /// line `e`, made once.
    fn crossing_point(&mut self, e: usize, lid: usize) -> u32 {
        if self.crossing[e] != NONE {
            return self.crossing[e];
        }
        let (el, l) = (&self.lines[e], &self.lines[lid]);
        let x = line_intersection_f64(el.a, el.b, l.a, l.b)
            .expect("internal: a strictly crossed edge is not parallel to the cut");
        let i = u32::try_from(self.points.len()).expect("internal: fewer than 2^32 points");
        self.points.push(x);
        self.crossing[e] = i;
        self.crossed.push(e);
        i
    }
}

/// Whether the closed segment `a b` meets the open triangle `t` (counter-clockwise):
/// no edge line of `t` has both ends on its outer closed side, and the
/// segment's line strictly separates two vertices of `t`.
fn crosses_interior(t: [Point; 3], a: Point, b: Point) -> bool {
    for k in 0..3 {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        let out = |x: Point| orient2d(p, q, x) != Orientation::CounterClockwise;
        if out(a) && out(b) {
            return false;
        }
    }
    let o = t.map(|x| orient2d(a, b, x));
    o.contains(&Orientation::CounterClockwise) && o.contains(&Orientation::Clockwise)
}

/// Split `cell` by line `lid` of `cut`, if the line strictly separates two
/// of its vertices; the cell back unchanged otherwise. A crossing is made
/// once for the cells on both sides of its edge ([`Cutting::crossing_point`]),
/// and the halves name their corners by index: no point is copied (a copy
/// costs four GMP allocations, and computing each crossing in both cells
/// beside its edge doubles the work: on 2 000 random stroked lines, 685 000
/// exact crossings, this and the machine-word crossings of
/// `line_intersection_f64` halve the cut's time).
fn split(cell: Cell, cut: &mut Cutting, lid: usize) -> Result<(Cell, Cell), Cell> {
    let signs: SmallVec<[Orientation; 16]> = {
        let l = &cut.lines[lid];
        cell.iter()
            .map(|&(v, _)| orient2d_q(&l.p, &l.q, &cut.points[v as usize]))
            .collect()
    };
    if !(signs.contains(&Orientation::CounterClockwise) && signs.contains(&Orientation::Clockwise))
    {
        return Err(cell);
    }
    /// One side: its points with the line of the edge each starts (or lies
    /// on) in the cell, and whether each lies on the cut line.
    #[derive(Default)]
    struct Side {
        cell: Cell,
        on: SmallVec<[bool; 16]>,
    }
    impl Side {
        fn push(&mut self, v: u32, e: usize, on: bool) {
            self.cell.push((v, e));
            self.on.push(on);
        }
        /// An edge between two points on the cut line lies on it.
        fn finish(mut self, lid: usize) -> Cell {
            let m = self.cell.len();
            for k in 0..m {
                if self.on[k] && self.on[(k + 1) % m] {
                    self.cell[k].1 = lid;
                }
            }
            self.cell
        }
    }
    let n = cell.len();
    let (mut pos, mut neg) = (Side::default(), Side::default());
    for (i, &(v, e)) in cell.iter().enumerate() {
        let j = (i + 1) % n;
        match signs[i] {
            Orientation::CounterClockwise => pos.push(v, e, false),
            Orientation::Clockwise => neg.push(v, e, false),
            Orientation::Collinear => {
                pos.push(v, e, true);
                neg.push(v, e, true);
            }
        }
        let opposite = matches!(
            (signs[i], signs[j]),
            (Orientation::CounterClockwise, Orientation::Clockwise)
                | (Orientation::Clockwise, Orientation::CounterClockwise)
        );
        if opposite {
            let x = cut.crossing_point(e, lid);
            pos.push(x, e, true);
            neg.push(x, e, true);
        }
    }
    Ok((pos.finish(lid), neg.finish(lid)))
}

/// Seed triangles cut at once, in parallel, before their cells go into the
/// mesh in order (bounds the cells held at a time).
const CUT_CHUNK: usize = 1024;

/// A seed triangle after cutting: whole, or its points (each with its
/// rounding, [`fan::Corner`]) and its convex cells, each as indices into the
/// points (counter-clockwise) with the way [`fan::emit_cells`] triangulates it.
enum CutTriangle {
    Whole,
    Cells(Vec<fan::Corner>, Vec<(Vec<u32>, fan::CellFan)>),
}

/// Cut one seed triangle `tri` (corners `tp`) by the lines of the segments
/// that meet its interior, in segment order, each line once. Reads the mesh
/// nowhere, so the seed triangles are cut in parallel.
fn cut_one(input: &BspInput, grid: &Grid, tp: [Point; 3]) -> CutTriangle {
    let mut candidates: Vec<u32> = Vec::new();
    let (cx0, cx1, cy0, cy1) = grid.range(tp[0], tp[1], tp[2]);
    for cy in cy0..=cy1 {
        for cx in cx0..=cx1 {
            candidates.extend_from_slice(&grid.cells[cy * grid.nx + cx]);
        }
    }
    // Deterministic order, each segment once, duplicates of the same line cut
    // only once.
    candidates.sort_unstable();
    candidates.dedup();
    candidates.retain(|&s| {
        let seg = &input.segments[s as usize];
        crosses_interior(tp, seg.a, seg.b)
    });
    if candidates.is_empty() {
        return CutTriangle::Whole;
    }
    let mut cut = Cutting::new(
        (0..3)
            .map(|k| Line::through(tp[k], tp[(k + 1) % 3]))
            .collect(),
        tp.iter().map(|&p| PointQ::from_point(p)).collect(),
    );
    let mut cells: Vec<Cell> = vec![(0..3).map(|k| (k as u32, k)).collect()];
    let mut seen_lines: Vec<(Point, Point)> = Vec::new();
    for &s in &candidates {
        let seg = &input.segments[s as usize];
        if seen_lines.contains(&(seg.a, seg.b)) || seen_lines.contains(&(seg.b, seg.a)) {
            continue;
        }
        seen_lines.push((seg.a, seg.b));
        let lid = cut.push_line(seg.a, seg.b);
        let mut next = Vec::with_capacity(cells.len() + 4);
        for cell in cells.drain(..) {
            match split(cell, &mut cut, lid) {
                Ok((a, b)) => {
                    next.push(a);
                    next.push(b);
                }
                Err(cell) => next.push(cell),
            }
        }
        cells = next;
    }
    let points = cut.points;
    let cells = cells
        .into_iter()
        .map(|cell| {
            let ids: Vec<u32> = cell.into_iter().map(|(p, _)| p).collect();
            let corners: SmallVec<[&PointQ; 16]> =
                ids.iter().map(|&i| &points[i as usize]).collect();
            let how = fan::plan_cell(&corners);
            (ids, how)
        })
        .collect();
    CutTriangle::Cells(points.into_iter().map(fan::Corner::new).collect(), cells)
}

/// Put the cells of seed triangles `chunk` (chunk number `c`), cut into
/// `cut`, into the mesh in order.
///
/// # Errors
/// [`Error::meshing`] once the mesh has more than `opts.max_vertices`.
#[allow(
    clippy::too_many_arguments,
    reason = "the loop state of cut_all, split off to run beside the next chunk's cut"
)]
fn emit_chunk(
    mesh: &mut TriMesh,
    vmap: &mut fan::VertexMap,
    stats: &mut BspStats,
    opts: &BspOptions,
    c: usize,
    chunk: &[[u32; 3]],
    cut: Vec<CutTriangle>,
    seed_ids: &[VertexId],
) -> Result<()> {
    for (k, (tri, cut)) in chunk.iter().zip(cut).enumerate() {
        let ids = tri.map(|i| seed_ids[i as usize]);
        let (corners, cells) = match cut {
            CutTriangle::Whole => {
                mesh.add_face(ids);
                stats.cells += 1;
                continue;
            }
            CutTriangle::Cells(corners, cells) => (corners, cells),
        };
        stats.cut_triangles += 1;
        stats.cells += cells.len();
        stats.barycentre_vertices += fan::emit_cells(mesh, vmap, corners, cells);
        if mesh.num_vertices() > opts.max_vertices as usize {
            tracing::debug!(seed_triangle = c * CUT_CHUNK + k, "vertex budget exceeded");
            return Err(Error::meshing(
                Stage::Bsp,
                format!(
                    "more than {} vertices: too many feature crossings (raise max_vertices or simplify the input)",
                    opts.max_vertices
                ),
            ));
        }
    }
    Ok(())
}

/// Cut every seed triangle and triangulate every cell into `mesh`. The seed
/// triangles are cut in parallel, a chunk at a time; their cells go into the
/// mesh in seed order, so the mesh is the same for any number of threads.
pub(super) fn cut_all(
    input: &BspInput,
    seed: &Seed,
    opts: &BspOptions,
    stats: &mut BspStats,
) -> Result<TriMesh> {
    use rayon::prelude::*;
    let mut mesh = TriMesh::new();
    let mut vmap = fan::VertexMap::default();
    let seed_ids: Vec<VertexId> = seed
        .points
        .iter()
        .map(|&(p, tag)| {
            let id = mesh.add_vertex(p, tag);
            vmap.insert_f64(p, id);
            id
        })
        .collect();
    let bbox = seed.points.iter().fold(
        Rect::from_points(seed.points[0].0, seed.points[0].0),
        |r, (p, _)| r.union_pt(*p),
    );
    let grid = Grid::new(bbox, &input.segments);
    let cut_chunk = |chunk: &[[u32; 3]]| -> Vec<CutTriangle> {
        chunk
            .par_iter()
            .map(|tri| cut_one(input, &grid, tri.map(|i| seed.points[i as usize].0)))
            .collect()
    };
    // The cells of a chunk go into the mesh (in order, on this thread) while
    // the next chunk is cut: with two threads, the cutting of the next chunk
    // no longer waits for the mesh to take this one's cells.
    let chunks: Vec<&[[u32; 3]]> = seed.triangles.chunks(CUT_CHUNK).collect();
    let mut next = chunks.first().map(|chunk| cut_chunk(chunk));
    for (c, chunk) in chunks.iter().enumerate() {
        let cut = next
            .take()
            .expect("internal: each chunk is cut beside the one before it");
        let (emitted, following) = match crate::error::check_deadline(&opts.deadline, Stage::Bsp) {
            Ok(()) => rayon::join(
                || emit_chunk(&mut mesh, &mut vmap, stats, opts, c, chunk, cut, &seed_ids),
                || chunks.get(c + 1).map(|chunk| cut_chunk(chunk)),
            ),
            Err(e) => (Err(e), None),
        };
        if let Err(e) = emitted {
            // Millions of exact vertices take seconds to free: not on the
            // way to the error.
            crate::budget::dispose((mesh, vmap));
            return Err(e);
        }
        next = following;
    }
    mesh.link_all();
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point {
        Point::new(x, y)
    }

    #[test]
    fn interior_crossing_test() {
        let t = [p(0.0, 0.0), p(4.0, 0.0), p(0.0, 4.0)];
        assert!(crosses_interior(t, p(-1.0, 1.0), p(5.0, 1.0)));
        // Along an edge, through a vertex only, outside, ending at a vertex going out.
        assert!(!crosses_interior(t, p(-1.0, 0.0), p(5.0, 0.0)));
        assert!(!crosses_interior(t, p(-1.0, 5.0), p(1.0, 3.0)));
        assert!(!crosses_interior(t, p(-1.0, -1.0), p(-2.0, 3.0)));
        assert!(!crosses_interior(t, p(4.0, 0.0), p(6.0, -1.0)));
        // From a vertex into the triangle and out through the opposite edge.
        assert!(crosses_interior(t, p(0.0, 0.0), p(3.0, 3.0)));
        // Line crosses the triangle but the segment stops short.
        assert!(!crosses_interior(t, p(5.0, 1.0), p(7.0, 1.0)));
    }

    /// The square [0, 2]², as a cutting with one cell.
    fn square() -> (Cutting, Cell) {
        let corners = [p(0.0, 0.0), p(2.0, 0.0), p(2.0, 2.0), p(0.0, 2.0)];
        let cut = Cutting::new(
            (0..4)
                .map(|k| Line::through(corners[k], corners[(k + 1) % 4]))
                .collect(),
            corners.iter().map(|&c| PointQ::from_point(c)).collect(),
        );
        (cut, (0..4).map(|k| (k as u32, k)).collect())
    }

    #[test]
    fn split_square() {
        let (mut cut, cell) = square();
        // Through a corner and an edge midpoint.
        let lid = cut.push_line(p(0.0, 0.0), p(2.0, 1.0));
        let Ok((a, b)) = split(cell.clone(), &mut cut, lid) else {
            panic!("does not separate")
        };
        assert_eq!(a.len() + b.len(), 7);
        let on_cut = |c: &Cell| c.iter().filter(|(_, l)| *l == lid).count();
        assert_eq!(on_cut(&a), 1);
        assert_eq!(on_cut(&b), 1);
        // One crossing made (at (2, 1)), shared by both halves; the corner
        // on the line is in both too.
        assert_eq!(cut.points.len(), 5);
        assert_eq!(cut.points[4], PointQ::from_point(p(2.0, 1.0)));
        let shared = a
            .iter()
            .filter(|(v, _)| b.iter().any(|(w, _)| w == v))
            .count();
        assert_eq!(shared, 2);
        // A line along an edge does not split.
        let lid = cut.push_line(p(0.0, 0.0), p(5.0, 0.0));
        assert!(split(cell, &mut cut, lid).is_err());
    }

    #[test]
    fn a_crossing_is_made_once_for_the_cells_beside_its_edge() {
        // The square cut by a vertical line into two cells that share
        // the edge x = 1; a horizontal line then crosses that edge once and
        // the square's sides twice.
        let (mut cut, cell) = square();
        let v = cut.push_line(p(1.0, -1.0), p(1.0, 3.0));
        let Ok((l, r)) = split(cell, &mut cut, v) else {
            panic!("does not separate")
        };
        assert_eq!(cut.points.len(), 6);
        let h = cut.push_line(p(-1.0, 0.5), p(3.0, 0.5));
        let mut cells = Vec::new();
        for c in [l, r] {
            let Ok((a, b)) = split(c, &mut cut, h) else {
                panic!("does not separate")
            };
            cells.push(a);
            cells.push(b);
        }
        // (0, 0.5), (1, 0.5) once, (2, 0.5): three points more, not four.
        assert_eq!(cut.points.len(), 9);
        let mid = PointQ::from_point(p(1.0, 0.5));
        let at_mid: Vec<u32> = (0..9u32)
            .filter(|&i| cut.points[i as usize] == mid)
            .collect();
        assert_eq!(at_mid.len(), 1);
        let users = cells
            .iter()
            .filter(|c| c.iter().any(|&(i, _)| i == at_mid[0]))
            .count();
        assert_eq!(users, 4);
    }
}
