//! Free vertices for the BSP at the size field's density, so that the
//! optimizer starts from a mesh near its final one instead of making it by
//! splits (gmsh and Triangle likewise start their refinement from a
//! background-driven point set, not from the boundary alone).
//!
//! The BSP triangulates the features' vertices only. Without seeds, open
//! space is a fan of long triangles between the outlines' vertices and the
//! box's corners, and the optimizer makes every interior vertex by a checked
//! split, one at a time: the L-shaped domain of `benches/gmsh_lshape.py` at
//! 20 000 triangles goes from a BSP of 436 vertices through 50 911 splits and
//! 33 774 collapses. Where a field asks for small elements away from any
//! vertex (a band along an outline, a box, a formula) the fans are slivers
//! reaching across the drawing, which the split passes cut again and again
//! before the collapses remove the excess.
//!
//! The seeds are the points of a triangular lattice whose spacing follows
//! the field: each leaf of the field's quadtree takes the lattice level
//! nearest its size h (the smaller of its corners' values and its centre's).
//! The levels are nested: the lattice of level k+1 is that of level k turned
//! by 30° and shrunk by √3 (the "√3 subdivision" of a triangular lattice), so
//! it holds every point of level k, and two seeds are never closer than the
//! finer spacing of their two leaves; where the field is uniform the seeds
//! are one equilateral lattice of spacing l. A level's spacing is within
//! [3^(-1/4), 3^(1/4)] ≈ [0.76, 1.32] of h, inside the optimizer's split
//! bound 4/3·h. The box's sides get points at the field's size along them
//! (but for a periodic cell, whose sides the cell's own points set): without
//! them a side is one edge whose triangle reaches to the nearest seed.
//!
//! A seed closer than h/2 to a feature segment, a feature point or the box is
//! left out: the BSP would cut a sliver between them, and the features'
//! vertices already set the size there. Leaves below [`SEED_BELOW`]·l are
//! seeded where the user asked for sizes; every leaf, open space included,
//! where the leaves at or above it would hold [`SEED_OPEN_FROM`] seeds per
//! feature vertex: on drawings whose features make most of the mesh, seeding
//! open space cost triangles and saved no time, and the default field's fine
//! parts (thin strokes) are left to the split passes as they were
//! (docs/tuning.md, "The BSP's free vertices"). A field the vertex
//! budget cannot follow (capped, or more seeds than [`SEED_SHARE`] of the
//! budget with the features' vertices) gets none: the optimizer's split
//! passes alone refine toward it, and stop at the budget.

use super::SizeField;
use crate::features::grid::Grid;
use kurbo::{Line, Point, Rect};

/// Leaves whose size is below this fraction of `l` always get seeds: there
/// the BSP's fans between the features' vertices are slivers the split passes
/// cut again and again.
pub(crate) const SEED_BELOW: f64 = 0.5;

/// The other leaves (open space, where the field is near `l`) get seeds when
/// they hold at least this many per feature vertex: the mesh is then mostly
/// interior vertices the optimizer would make one split at a time. Below it,
/// seeding them cost triangles and saved no time (measured in docs/tuning.md,
/// "The BSP's free vertices").
pub(crate) const SEED_OPEN_FROM: f64 = 4.0;

/// The share of the vertex budget the seeds and the features' vertices may
/// take together: the rest is the optimizer's room to split.
const SEED_SHARE: f64 = 0.75;

/// The area per vertex of a mesh of equilateral triangles of side 1 (each
/// vertex has six triangles of area √3/4, each shared by three vertices).
const VERTEX_AREA: f64 = 0.866_025_403_784_438_6;

/// The deepest lattice level (a spacing of l/3^16, some 4·10⁻⁸ l: below any
/// `l_min` the parameters allow).
const MAX_LEVEL: u32 = 32;

/// The nested triangular lattices: level k is `origin + l·τ^k·(a + b·ω)` for
/// integers a, b, with ω = e^{iπ/3} and τ = e^{iπ/6}/√3. Since
/// 1/τ = 2 − ω is an Eisenstein integer, a point of level k has the integer
/// coordinates `(2 − ω)^(K−k)·(a + b·ω)` at any deeper level K: every seed
/// is evaluated at the deepest level used, so points that two levels share
/// come out bit for bit the same.
struct Lattices {
    origin: Point,
    l: f64,
    /// The deepest level used, K.
    deepest: u32,
    /// `l·τ^K` as (re, im).
    unit: (f64, f64),
}

impl Lattices {
    fn new(origin: Point, l: f64, deepest: u32) -> Lattices {
        Lattices {
            origin,
            l,
            deepest,
            unit: Self::scale(l, deepest),
        }
    }

    /// `l·τ^k` as (re, im).
    fn scale(l: f64, k: u32) -> (f64, f64) {
        let angle = f64::from(k) * std::f64::consts::FRAC_PI_6;
        let r = l * 3f64.powf(-0.5 * f64::from(k));
        (r * angle.cos(), r * angle.sin())
    }

    /// The spacing of level `k`.
    fn spacing(l: f64, k: u32) -> f64 {
        l * 3f64.powf(-0.5 * f64::from(k))
    }

    /// The level whose spacing is nearest `h` on a log scale (at most
    /// [`MAX_LEVEL`]; level 0 for `h ≥ l`).
    fn level(l: f64, h: f64) -> u32 {
        if h >= l {
            return 0;
        }
        // spacing_k = l·3^(-k/2): k = 2·log3(l/h), rounded.
        let k = (2.0 * (l / h).ln() / 3f64.ln()).round();
        (k.max(0.0) as u32).min(MAX_LEVEL)
    }

    /// The point of level `k` with coordinates (a, b).
    fn point(&self, k: u32, (mut a, mut b): (i64, i64)) -> Point {
        for _ in k..self.deepest {
            // (a + bω)(2 − ω) = (2a + b) + (b − a)ω, as ω² = ω − 1.
            (a, b) = (2 * a + b, b - a);
        }
        let (x, y) = (
            a as f64 + 0.5 * b as f64,
            0.866_025_403_784_438_6 * b as f64,
        );
        let (ur, ui) = self.unit;
        Point::new(
            self.origin.x + ur * x - ui * y,
            self.origin.y + ui * x + ur * y,
        )
    }

    /// Every point of level `k` in the half-open box `[x0, x1) × [y0, y1)`.
    fn in_box(&self, k: u32, b: Rect, out: &mut impl FnMut(Point)) {
        // Coordinates of the box's corners at level k (the lattice's own
        // f64 map, only to bound the integer ranges; one more on each side).
        let (ur, ui) = Self::scale(self.l, k);
        let n2 = ur * ur + ui * ui;
        let coords = |p: Point| {
            let (dx, dy) = (p.x - self.origin.x, p.y - self.origin.y);
            // w = (p − origin) / (l·τ^k), then a + b/2 = Re w, b·√3/2 = Im w.
            let (wr, wi) = ((dx * ur + dy * ui) / n2, (dy * ur - dx * ui) / n2);
            let bb = wi / 0.866_025_403_784_438_6;
            (wr - 0.5 * bb, bb)
        };
        let corners = [
            coords(Point::new(b.x0, b.y0)),
            coords(Point::new(b.x1, b.y0)),
            coords(Point::new(b.x0, b.y1)),
            coords(Point::new(b.x1, b.y1)),
        ];
        let lo_a = corners.iter().map(|c| c.0).fold(f64::INFINITY, f64::min);
        let hi_a = corners
            .iter()
            .map(|c| c.0)
            .fold(f64::NEG_INFINITY, f64::max);
        let lo_b = corners.iter().map(|c| c.1).fold(f64::INFINITY, f64::min);
        let hi_b = corners
            .iter()
            .map(|c| c.1)
            .fold(f64::NEG_INFINITY, f64::max);
        for bi in (lo_b.floor() as i64 - 1)..=(hi_b.ceil() as i64 + 1) {
            for ai in (lo_a.floor() as i64 - 1)..=(hi_a.ceil() as i64 + 1) {
                let p = self.point(k, (ai, bi));
                if p.x >= b.x0 && p.x < b.x1 && p.y >= b.y0 && p.y < b.y1 {
                    out(p);
                }
            }
        }
    }
}

/// Samples of the size along a box side per size (as the features' lines).
const SIDE_SAMPLES_PER_SIZE: f64 = 4.0;

impl SizeField {
    /// Points strictly inside the side from `a` to `b` (one coordinate held
    /// exactly, so they lie on the side) at the field's size along it, where
    /// it is below `limit`: as many pieces as the integral of 1/h along the
    /// side rounded, each an equal share of it.
    fn side_points(&self, a: Point, b: Point, limit: f64) -> Vec<Point> {
        let len = a.distance(b);
        let at = |s: f64| a.lerp(b, (s / len).clamp(0.0, 1.0));
        let mut samples = vec![(0.0, 0.0)];
        let mut s = 0.0;
        while s < len {
            let h = self.at(at(s));
            let next = (s + h / SIDE_SAMPLES_PER_SIZE).min(len);
            let hn = self.at(at(next));
            let acc =
                samples.last().map_or(0.0, |&(_, i)| i) + 0.5 * (next - s) * (1.0 / h + 1.0 / hn);
            samples.push((next, acc));
            s = next;
        }
        let total = samples.last().map_or(0.0, |&(_, i)| i);
        let n = total.round().max(1.0) as usize;
        let mut out = Vec::with_capacity(n);
        let mut k = 1;
        for i in 1..n {
            let want = total * i as f64 / n as f64;
            while k + 1 < samples.len() && samples[k].1 < want {
                k += 1;
            }
            let ((s0, i0), (s1, i1)) = (samples[k - 1], samples[k]);
            let f = if i1 > i0 {
                (want - i0) / (i1 - i0)
            } else {
                0.0
            };
            let mut p = at(s0 + f * (s1 - s0));
            // exactly on the side
            if a.x == b.x {
                p.x = a.x;
            } else {
                p.y = a.y;
            }
            if self.at(p) < limit {
                out.push(p);
            }
        }
        out
    }

    /// The seeds (see the module doc) inside `bounds`, away from `segments`
    /// and `points`, with points on the box's sides when `sides`: in the
    /// leaves below [`SEED_BELOW`]·l when the user asked for sizes
    /// ([`SizeField::is_asked`]), in every leaf when the leaves at or above it
    /// would hold at least [`SEED_OPEN_FROM`] seeds per feature vertex; none
    /// for a field capped by the vertex budget and none past
    /// [`SEED_SHARE`] of the budget `max_vertices`. In the quadtree's order
    /// (deterministic).
    pub(crate) fn seed_points(
        &self,
        bounds: Rect,
        segments: &[Line],
        points: &[Point],
        max_vertices: usize,
        sides: bool,
    ) -> Vec<Point> {
        self.seeds(None, bounds, segments, points, max_vertices, sides)
    }

    /// [`SizeField::seed_points`] with the open space seeded or not as
    /// `open` says (`None`: as [`SEED_OPEN_FROM`] decides).
    pub(super) fn seeds(
        &self,
        open: Option<bool>,
        bounds: Rect,
        segments: &[Line],
        points: &[Point],
        max_vertices: usize,
        sides: bool,
    ) -> Vec<Point> {
        if self.report.capped || !(bounds.width() > 0.0 && bounds.height() > 0.0) {
            return Vec::new();
        }
        let l = self.l;
        let fine = SEED_BELOW * l;
        // Each leaf clipped to the box, with its size and lattice level.
        let mut leaves: Vec<(Rect, f64, u32)> = self
            .tree
            .leaf_boxes()
            .into_iter()
            .filter_map(|(c, side, h)| {
                let h = h.min(self.at(c));
                let r = 0.5 * side;
                let cell = Rect::new(c.x - r, c.y - r, c.x + r, c.y + r).intersect(bounds);
                (cell.width() > 0.0 && cell.height() > 0.0)
                    .then(|| (cell, h, Lattices::level(l, h)))
            })
            .collect();
        // How many seeds each leaf holds, before any point is made.
        let expected = |&(cell, _, k): &(Rect, f64, u32)| {
            cell.area() / (VERTEX_AREA * Lattices::spacing(l, k).powi(2))
        };
        let features = segments.len() + points.len();
        let open = open.unwrap_or_else(|| {
            let in_open: f64 = leaves.iter().filter(|c| c.1 >= fine).map(expected).sum();
            in_open >= SEED_OPEN_FROM * features as f64
        });
        if !open && !self.is_asked() {
            return Vec::new();
        }
        let limit = if open { f64::INFINITY } else { fine };
        leaves.retain(|c| c.1 < limit);
        let room = (SEED_SHARE * max_vertices as f64 - (2 * features) as f64).max(0.0);
        if leaves.is_empty() || leaves.iter().map(expected).sum::<f64>() > room {
            return Vec::new();
        }
        let deepest = leaves.iter().map(|&(_, _, k)| k).max().unwrap_or(0);
        let lattices = Lattices::new(Point::new(bounds.x0, bounds.y0), l, deepest);
        // The features in a grid of cells of about the largest seeded size
        // (each segment by its box; points after the segments' ids).
        let largest = leaves.iter().map(|&(_, h, _)| h).fold(0.0, f64::max);
        let mut near = Grid::new(bounds, largest, segments.len() + points.len());
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
        let mut seeds = Vec::new();
        // (a point on a boundary two leaves' boxes both hold, by rounding)
        let mut seen = rustc_hash::FxHashSet::default();
        for (cell, _, k) in leaves {
            lattices.in_box(k, cell, &mut |p: Point| {
                let r = 0.5 * self.at(p);
                if p.x - r > bounds.x0
                    && p.x + r < bounds.x1
                    && p.y - r > bounds.y0
                    && p.y + r < bounds.y1
                    && !within(p, r)
                    && seen.insert((p.x.to_bits(), p.y.to_bits()))
                {
                    seeds.push(p);
                }
            });
        }
        if sides {
            for (a, b) in [
                (
                    Point::new(bounds.x0, bounds.y0),
                    Point::new(bounds.x1, bounds.y0),
                ),
                (
                    Point::new(bounds.x1, bounds.y0),
                    Point::new(bounds.x1, bounds.y1),
                ),
                (
                    Point::new(bounds.x1, bounds.y1),
                    Point::new(bounds.x0, bounds.y1),
                ),
                (
                    Point::new(bounds.x0, bounds.y1),
                    Point::new(bounds.x0, bounds.y0),
                ),
            ] {
                for p in self.side_points(a, b, limit) {
                    if !within(p, 0.5 * self.at(p)) {
                        seeds.push(p);
                    }
                }
            }
        }
        if seeds.len() as f64 > room {
            return Vec::new();
        }
        seeds
    }
}
