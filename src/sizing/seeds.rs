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
//! optimizer's split passes alone refine toward it, and stop at the budget.

use super::SizeField;
use crate::features::grid::Grid;
use kurbo::{Line, Point, Rect};

/// Leaves whose smallest corner value is below this fraction of `l` get a
/// seed. Where the field is near `l` the features' vertices and the usual
/// split passes make the mesh.
pub(crate) const SEED_BELOW: f64 = 0.5;

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
        if leaves.is_empty() || leaves.len() > max_vertices {
            return Vec::new();
        }
        // The features in a grid of cells of about half of l (each segment by
        // its box; points after the segments' ids).
        let mut near = Grid::new(bounds, below, segments.len() + points.len());
        let boxes = segments
            .iter()
            .map(|s| Rect::from_points(s.p0, s.p1))
            .chain(points.iter().map(|&p| Rect::from_points(p, p)));
        for (id, b) in boxes.enumerate() {
            near.insert(id as u32, b);
        }
        let within = |p: Point, r: f64| {
            let around = Rect::new(p.x - r, p.y - r, p.x + r, p.y + r);
            near.any(around, |id| {
                let d = match segments.get(id as usize) {
                    Some(&s) => crate::mesh::point_segment_distance(p, s),
                    None => points[id as usize - segments.len()].distance(p),
                };
                d < r
            })
        };
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
                || within(p, r)
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
