//! Free vertices for the BSP where the size field asks for a finer mesh than
//! the features' own vertices give (gmsh and Triangle start their refinement
//! from a background-driven point set, not from the boundary alone).
//!
//! The BSP triangulates the features' vertices only. Where a field asks for
//! small elements away from any vertex (a band along an outline, a box, a
//! formula), that triangulation is a fan of slivers reaching across the
//! drawing, and the optimizer's field split passes cut the fans' long edges
//! again and again before its collapses remove the excess: ello with
//! `--size-near shape-0=0.002` (h = d/180 on its outline) grew to some
//! 400 000 faces before its first pass brought it back to 70 000, 3.2 s of
//! optimization for a mesh of 17 000 triangles. Seeding vertices at the
//! centres of the quadtree's leaves where the field is below [`SEED_BELOW`]·l,
//! as many as a mesh of the field's size has there, gives the BSP a point set
//! already graded like the field, so the passes start from well-shaped
//! triangles.
//!
//! A seed closer than h/2 to a feature segment, a feature point or the box is
//! left out: the BSP would cut a sliver between them, and the features'
//! vertices already set the size there. A field the vertex budget cannot
//! follow (capped, or more seeds than half the budget) gets none: the
//! optimizer's split passes stop at the budget as before.

use super::SizeField;
use kurbo::{Line, Point, Rect};
use rustc_hash::FxHashMap;

/// Leaves whose smallest corner value is below this fraction of `l` get a
/// seed. Where the field is near `l` the features' vertices and the usual
/// split passes make the mesh as before.
pub(crate) const SEED_BELOW: f64 = 0.5;

/// The most steps [`Near`] samples the segments at (the cells grow past
/// half of `l` for longer segments; a larger cell only holds more of them).
const MAX_SAMPLES: f64 = 1e7;

/// The area per vertex of a mesh of equilateral triangles of side 1 (each
/// vertex has six triangles of area √3/4, each shared by three vertices).
const VERTEX_AREA: f64 = 0.866_025_403_784_438_6;

impl SizeField {
    /// The seeds (see the module doc) inside `bounds`, away from `segments`
    /// and `points`; none unless the user asked for sizes
    /// ([`SizeField::is_asked`]) and the field is below `l` somewhere, so the
    /// default meshes are unchanged, and none past the vertex budget
    /// `max_vertices`. In the quadtree's order (deterministic).
    pub(crate) fn seed_points(
        &self,
        bounds: Rect,
        segments: &[Line],
        points: &[Point],
        max_vertices: usize,
    ) -> Vec<Point> {
        if !self.is_asked() || self.is_uniform() || self.report.capped {
            return Vec::new();
        }
        let below = SEED_BELOW * self.l;
        let leaves: Vec<(Point, f64, f64)> = self
            .tree
            .leaf_boxes()
            .into_iter()
            .filter(|&(_, _, h)| h < below)
            .collect();
        if leaves.is_empty() {
            return Vec::new();
        }
        if leaves.len() > max_vertices {
            return Vec::new();
        }
        // Cells of half of l at least (a seed keeps r ≤ l/4 clear), larger
        // where the segments are so long in all that sampling them at a
        // quarter cell would take more than `MAX_SAMPLES` steps.
        let length: f64 = segments.iter().map(|s| s.length()).sum();
        let cell = below.max(4.0 * length / MAX_SAMPLES);
        let near = Near::new(cell, segments, points);
        // A mesh of edges h has a vertex per √3/2·h² of area; a leaf's side is
        // between h/2 and h, so one seed per leaf would be up to 3.5 times too
        // many. Each leaf adds its area in vertices and a seed is placed where
        // the running sum passes a whole number, in the quadtree's order (a
        // Z-order, so the sum runs over neighbouring leaves).
        let mut mass = 0.5;
        let mut seeds = Vec::new();
        for (p, side, h) in leaves {
            let r = 0.5 * h;
            if !(p.x - r > bounds.x0
                && p.x + r < bounds.x1
                && p.y - r > bounds.y0
                && p.y + r < bounds.y1)
                || near.within(p, r, segments, points)
            {
                continue;
            }
            mass += side * side / (VERTEX_AREA * h * h);
            if mass >= 1.0 {
                mass -= mass.floor();
                seeds.push(p);
            }
        }
        if seeds.len() > max_vertices / 2 {
            return Vec::new();
        }
        seeds
    }
}

/// A uniform hash grid of the features' segments and points, for "is any
/// within r of p" with r at most half a cell.
struct Near {
    cell: f64,
    /// Per cell: indices into the segments, then (offset by their count) the points.
    cells: FxHashMap<(i64, i64), Vec<u32>>,
    n_segments: usize,
}

impl Near {
    fn new(cell: f64, segments: &[Line], points: &[Point]) -> Near {
        let mut near = Near {
            cell,
            cells: FxHashMap::default(),
            n_segments: segments.len(),
        };
        for (i, s) in segments.iter().enumerate() {
            // Samples at most a quarter cell apart along the segment: every
            // point of it is within a quarter cell of one, so a segment
            // within r ≤ cell/2 of p has a sample in p's cell or a neighbour.
            let steps = (s.length() / (0.25 * cell)).ceil() as usize;
            let mut last = None;
            for k in 0..=steps {
                let t = if steps == 0 {
                    0.0
                } else {
                    k as f64 / steps as f64
                };
                let key = near.key(s.p0.lerp(s.p1, t));
                if last != Some(key) {
                    let list = near.cells.entry(key).or_default();
                    if list.last() != Some(&(i as u32)) {
                        list.push(i as u32);
                    }
                    last = Some(key);
                }
            }
        }
        for (i, &p) in points.iter().enumerate() {
            let key = near.key(p);
            near.cells
                .entry(key)
                .or_default()
                .push((segments.len() + i) as u32);
        }
        near
    }

    fn key(&self, p: Point) -> (i64, i64) {
        (
            (p.x / self.cell).floor() as i64,
            (p.y / self.cell).floor() as i64,
        )
    }

    /// Whether a segment or point lies within `r` (at most half a cell) of `p`.
    fn within(&self, p: Point, r: f64, segments: &[Line], points: &[Point]) -> bool {
        let (x, y) = self.key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                let Some(list) = self.cells.get(&(x + dx, y + dy)) else {
                    continue;
                };
                for &i in list {
                    let i = i as usize;
                    let d = if i < self.n_segments {
                        crate::mesh::point_segment_distance(p, segments[i])
                    } else {
                        points[i - self.n_segments].distance(p)
                    };
                    if d < r {
                        return true;
                    }
                }
            }
        }
        false
    }
}
