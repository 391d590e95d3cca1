//! Directions of line elements: every physical curve's line
//! elements run one way, so a normal taken from an element's direction is the
//! same side of the curve all along it, and the domain's boundary is a physical
//! curve of its own.
//!
//! - Feature lines ([`orient_lines`]): the lines of one source shape are cut
//!   into chains at the nodes where the shape's own lines do not simply pass
//!   through (ends, branches); a chain that closes on itself runs
//!   counter-clockwise (positive enclosed area), an open chain runs along its
//!   source's direction: the parameter of the source feature its elements lie
//!   on grows along them (a few elements near the chain's middle vote).
//! - The boundary ([`add_boundary`]): every triangle edge that no other
//!   triangle shares becomes a line element of the physical curve
//!   [`BOUNDARY`], oriented as its (counter-clockwise) triangle lists it, so
//!   the domain is on its left: outer boundaries run counter-clockwise, the
//!   rims of holes clockwise.

use super::classify::edge_key;
use crate::fem::{BOUNDARY, FemMesh, LineKind};
use crate::svg::{Drawing, FeatureGeom, ShapeId};
use kurbo::{ParamCurveNearest, Point, Rect};
use std::collections::HashMap;

/// Accuracy of the projections onto source curves, relative to the drawing's
/// diagonal: far below any edge length, only the order of the two ends matters.
const NEAREST_ACCURACY_REL: f64 = 1e-9;

/// Orient the feature lines of `mesh` (see the module docs). `line_shape[i]`
/// is the source shape of line `i`; lines beyond it are left as they are.
/// Once `deadline` has passed the chains left keep their direction (the caller
/// stops the run with a time-limit error).
pub(crate) fn orient_lines(
    drawing: &Drawing,
    mesh: &mut FemMesh,
    line_shape: &[ShapeId],
    deadline: &crate::budget::Deadline,
) {
    let count = mesh.line_count().min(line_shape.len());
    let mut by_shape: HashMap<ShapeId, Vec<usize>> = HashMap::new();
    for (i, &s) in line_shape.iter().enumerate().take(count) {
        by_shape.entry(s).or_default().push(i);
    }
    let mut shapes: Vec<ShapeId> = by_shape.keys().copied().collect();
    shapes.sort_unstable_by_key(|s| s.index());
    // Each shape's features, in drawing order, found once (not per chain: a
    // drawing of many small shapes would scan all features per chain).
    let mut own: HashMap<ShapeId, Vec<Own>> = HashMap::new();
    for f in &drawing.features {
        if by_shape.contains_key(&f.source.shape) {
            own.entry(f.source.shape)
                .or_default()
                .push(Own::new(f.geom));
        }
    }
    let own: HashMap<ShapeId, Owned> = own
        .into_iter()
        .map(|(s, features)| (s, Owned::new(features)))
        .collect();
    // The nearest-point accuracy, from the drawing's diagonal found once (it scans
    // every feature: per chain, a drawing of many small shapes spent minutes here).
    let accuracy = NEAREST_ACCURACY_REL * drawing.diagonal();
    for s in shapes {
        let Some(own) = own.get(&s) else {
            continue;
        };
        for chain in chains(mesh, &by_shape[&s]) {
            if deadline.expired() {
                return;
            }
            orient_chain(accuracy, mesh, own, &chain);
        }
    }
}

/// A feature of a shape, with the box of its control points (its curve, and
/// the curve its projections are taken on, lie in it).
struct Own {
    geom: FeatureGeom,
    bbox: Rect,
}

impl Own {
    fn new(geom: FeatureGeom) -> Own {
        let bbox = match geom {
            FeatureGeom::Point(p) => Rect::from_points(p, p),
            FeatureGeom::Line(l) => Rect::from_points(l.p0, l.p1),
            FeatureGeom::Cubic(c) => {
                Rect::from_points(c.p0, c.p1).union(Rect::from_points(c.p2, c.p3))
            }
            FeatureGeom::Conic(c) => {
                let a = c.approx_cubic();
                Rect::from_points(a.p0, a.p1).union(Rect::from_points(a.p2, a.p3))
            }
        };
        Own { geom, bbox }
    }

    /// The squared distance from `p` to the box: a lower bound of the
    /// squared distance from `p` to any point of the curve.
    fn box_distance_sq(&self, p: Point) -> f64 {
        let b = self.bbox;
        let dx = (b.x0 - p.x).max(p.x - b.x1).max(0.0);
        let dy = (b.y0 - p.y).max(p.y - b.y1).max(0.0);
        dx * dx + dy * dy
    }
}

/// A shape's features, with a grid over them when there are many (one dashed
/// stroke is one shape of 100 000 features: each open chain scanned them all,
/// minutes on a dashed spiral).
struct Owned {
    features: Vec<Own>,
    grid: Option<NearGrid>,
}

/// Features beyond which a shape's features get a grid.
const GRID_FROM: usize = 64;
/// Cells beyond which a feature's box is not put in the cells but in the list
/// every query scans.
const LARGE_CELLS: usize = 64;
/// Cells per feature on average beyond which the grid is dropped (the
/// shape's features are scanned).
const MAX_REGISTRATIONS_PER_FEATURE: usize = 48;

impl Owned {
    fn new(features: Vec<Own>) -> Owned {
        let grid = (features.len() > GRID_FROM)
            .then(|| NearGrid::new(&features))
            .flatten();
        Owned { features, grid }
    }

    /// The first (in drawing order) of the features nearest `p` among those
    /// `t` projects on (`dist_sq` reads the squared distance off a projection).
    fn nearest<T>(
        &self,
        p: Point,
        t: impl Fn(&FeatureGeom, Point) -> Option<T>,
        dist_sq: impl Fn(&T) -> f64,
    ) -> Option<&FeatureGeom> {
        let mut best: Option<(f64, usize)> = None;
        let consider = |best: &mut Option<(f64, usize)>, i: usize| {
            let o = &self.features[i];
            // A feature whose box is farther than the nearest so far (with a
            // margin far above the rounding of a distance) can be neither
            // nearer nor as near, and is not projected on.
            if best.is_some_and(|(d, _)| o.box_distance_sq(p) * (1.0 - 1e-9) > d) {
                return;
            }
            let Some(n) = t(&o.geom, p) else {
                return;
            };
            let d = dist_sq(&n);
            // The smallest distance; of equal ones, the first in drawing order.
            if best.is_none_or(|(bd, bi)| d.total_cmp(&bd).then(i.cmp(&bi)).is_lt()) {
                *best = Some((d, i));
            }
        };
        match &self.grid {
            None => (0..self.features.len()).for_each(|i| consider(&mut best, i)),
            Some(g) => {
                for &i in &g.large {
                    consider(&mut best, i as usize);
                }
                g.rings(p, |cells, reach_sq| {
                    if best.is_some_and(|(d, _)| reach_sq * (1.0 - 1e-9) > d) {
                        return false;
                    }
                    for &i in cells {
                        consider(&mut best, i as usize);
                    }
                    true
                });
            }
        }
        best.map(|(_, i)| &self.features[i].geom)
    }
}

/// A uniform grid over a shape's features: each cell lists, in drawing order,
/// the lines that pass through it and the curves whose box meets it; curves
/// with a box over [`LARGE_CELLS`] cells are listed apart.
struct NearGrid {
    origin: Point,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
    /// Features whose box covers more than [`LARGE_CELLS`] cells.
    large: Vec<u32>,
}

impl NearGrid {
    /// `None` when the boxes' extent is degenerate or not finite (the caller
    /// scans the list).
    fn new(features: &[Own]) -> Option<NearGrid> {
        let bounds = features.iter().map(|o| o.bbox).reduce(|a, b| a.union(b))?;
        let (w, h) = (bounds.width(), bounds.height());
        if !(w.is_finite() && h.is_finite()) || w.max(h) <= 0.0 {
            return None;
        }
        // About one feature per cell, at most 1024 cells a side.
        let side = (features.len() as f64).sqrt().ceil().clamp(1.0, 1024.0);
        let cell = w.max(h) / side;
        let nx = ((w / cell).ceil() as usize).clamp(1, 1024);
        let ny = ((h / cell).ceil() as usize).clamp(1, 1024);
        let mut g = NearGrid {
            origin: bounds.origin(),
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
            large: Vec::new(),
        };
        let mut registrations = 0usize;
        for (i, o) in features.iter().enumerate() {
            let i = u32::try_from(i).ok()?;
            if let FeatureGeom::Line(l) = o.geom {
                // The cells the segment passes through (a long diagonal line's
                // box would cover a square of them).
                let cells = g.segment_cells(l.p0, l.p1);
                registrations += cells.len();
                for k in cells {
                    g.cells[k].push(i);
                }
            } else {
                let (x0, y0) = g.index(o.bbox.origin());
                let (x1, y1) = g.index(Point::new(o.bbox.x1, o.bbox.y1));
                // A curve whose box covers many cells would make every cell
                // long: such features are looked at by every query.
                if (x1 - x0 + 1) * (y1 - y0 + 1) > LARGE_CELLS {
                    g.large.push(i);
                    continue;
                }
                registrations += (x1 - x0 + 1) * (y1 - y0 + 1);
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        g.cells[y * g.nx + x].push(i);
                    }
                }
            }
            // Long features everywhere (a hatch of long lines): every cell
            // lists many, and the scan is cheaper than the rings.
            if registrations > MAX_REGISTRATIONS_PER_FEATURE * features.len() {
                return None;
            }
        }
        Some(g)
    }

    /// The cells segment `a b` meets (a few more, for rounding), each once:
    /// row by row, the columns between the segment's ends in that row.
    fn segment_cells(&self, a: Point, b: Point) -> Vec<usize> {
        let (lo, hi) = if a.y <= b.y { (a, b) } else { (b, a) };
        let slack = 1e-7 * self.cell + 1e-12 * (lo.x.abs().max(hi.x.abs()));
        let (_, j0) = self.index(lo);
        let (_, j1) = self.index(hi);
        let mut out = Vec::new();
        for j in j0..=j1 {
            // The segment's x range within row j's band (grown by the slack).
            let band0 = self.origin.y + j as f64 * self.cell - slack;
            let band1 = self.origin.y + (j + 1) as f64 * self.cell + slack;
            let (ya, yb) = (band0.max(lo.y), band1.min(hi.y));
            let at = |y: f64| {
                if hi.y == lo.y {
                    (lo.x, hi.x)
                } else {
                    let t = ((y - lo.y) / (hi.y - lo.y)).clamp(0.0, 1.0);
                    let x = lo.x + t * (hi.x - lo.x);
                    (x, x)
                }
            };
            let (xa, xa2) = at(ya);
            let (xb, xb2) = at(yb);
            let xmin = xa.min(xa2).min(xb).min(xb2).max(lo.x.min(hi.x)) - slack;
            let xmax = xa.max(xa2).max(xb).max(xb2).min(lo.x.max(hi.x)) + slack;
            let (i0, _) = self.index(Point::new(xmin, lo.y));
            let (i1, _) = self.index(Point::new(xmax, lo.y));
            out.extend((i0..=i1).map(|i| j * self.nx + i));
        }
        out
    }

    /// The cell of `p`, clamped into the grid (monotone in each coordinate).
    fn index(&self, p: Point) -> (usize, usize) {
        let f = |v: f64, o: f64, n: usize| {
            let t = ((v - o) / self.cell).floor();
            if t.is_nan() || t < 0.0 {
                0
            } else {
                (t as usize).min(n - 1)
            }
        };
        (
            f(p.x, self.origin.x, self.nx),
            f(p.y, self.origin.y, self.ny),
        )
    }

    /// Visit the cells in square rings around `p`'s (clamped) cell, nearest
    /// ring first: `visit(cells, reach_sq)`, where every feature not listed in
    /// this ring or an earlier one lies farther than `sqrt(reach_sq)` from `p`;
    /// stops when `visit` returns false or the grid is covered.
    fn rings(&self, p: Point, mut visit: impl FnMut(&[u32], f64) -> bool) {
        let (cx, cy) = self.index(p);
        // How far `p` lies outside the grid (clamped into the edge cell).
        let outside = {
            let (x1, y1) = (
                self.origin.x + self.cell * self.nx as f64,
                self.origin.y + self.cell * self.ny as f64,
            );
            let dx = (self.origin.x - p.x).max(p.x - x1).max(0.0);
            let dy = (self.origin.y - p.y).max(p.y - y1).max(0.0);
            dx.max(dy)
        };
        let last = self.nx.max(self.ny);
        for r in 0..=last {
            // Features met by no ring up to r-1 lie outside the square of
            // those rings: farther from `p` than r·cell inside the grid, and
            // than sqrt(outside² + (r·cell)²) from outside it (the grid lies
            // beyond `outside` in one direction, the square's far cells r
            // cells on in one of the two). One cell less, for the rounding
            // of the cell index.
            let inner = (r.saturating_sub(1) as f64) * self.cell;
            let reach_sq = outside * outside + inner * inner;
            let mut ring: Vec<u32> = Vec::new();
            let (x0, x1) = (cx.saturating_sub(r), (cx + r).min(self.nx - 1));
            let (y0, y1) = (cy.saturating_sub(r), (cy + r).min(self.ny - 1));
            for y in y0..=y1 {
                for x in x0..=x1 {
                    if x.abs_diff(cx) == r || y.abs_diff(cy) == r {
                        ring.extend_from_slice(&self.cells[y * self.nx + x]);
                    }
                }
            }
            ring.sort_unstable();
            ring.dedup();
            if !visit(&ring, reach_sq) {
                return;
            }
        }
    }
}

/// A chain of line elements in walking order, and whether it closes.
struct Chain {
    lines: Vec<usize>,
    closed: bool,
}

/// The chains of `lines`: maximal runs through nodes where exactly two of
/// `lines` meet, in walking order (each element's start is the previous one's
/// end once [`orient_chain`] has made them consistent).
fn chains(mesh: &FemMesh, lines: &[usize]) -> Vec<Chain> {
    let mut at: HashMap<u32, Vec<usize>> = HashMap::new();
    for &l in lines {
        let v = mesh.line(l);
        at.entry(v[0]).or_default().push(l);
        at.entry(v[1]).or_default().push(l);
    }
    let passes = |v: u32| at.get(&v).is_some_and(|ls| ls.len() == 2);
    let other_end = |l: usize, v: u32| {
        let e = mesh.line(l);
        if e[0] == v { e[1] } else { e[0] }
    };
    let mut done: std::collections::HashSet<usize> = std::collections::HashSet::new();
    let mut out = Vec::new();
    // Open chains first: start at every end that is not a pass-through node.
    let mut starts: Vec<(u32, usize)> = Vec::new();
    for &l in lines {
        let v = mesh.line(l);
        for &end in &v[..2] {
            if !passes(end) {
                starts.push((end, l));
            }
        }
    }
    let walk = |start: u32, first: usize, done: &mut std::collections::HashSet<usize>| {
        let mut chain = vec![first];
        done.insert(first);
        let mut v = other_end(first, start);
        let mut last = first;
        while passes(v) && v != start {
            let Some(&next) = at[&v].iter().find(|&&l| l != last) else {
                break;
            };
            if !done.insert(next) {
                break;
            }
            chain.push(next);
            v = other_end(next, v);
            last = next;
        }
        (chain, v == start)
    };
    for (end, l) in starts {
        if !done.contains(&l) {
            let (lines, _) = walk(end, l, &mut done);
            out.push(Chain {
                lines,
                closed: false,
            });
        }
    }
    // What is left runs through pass-through nodes only: closed loops.
    for &l in lines {
        if !done.contains(&l) {
            let start = mesh.line(l)[0];
            let (lines, closed) = walk(start, l, &mut done);
            out.push(Chain { lines, closed });
        }
    }
    out
}

/// Make the elements of `chain` run one way, in the direction the module docs
/// give.
/// `own`: the features of the chain's shape; `accuracy`: of the nearest-point
/// searches (user units).
fn orient_chain(accuracy: f64, mesh: &mut FemMesh, own: &Owned, chain: &Chain) {
    let lines = &chain.lines;
    // Consecutive: each element starts where the previous one ends.
    for k in 0..lines.len() {
        let l = lines[k];
        let forward = if k + 1 < lines.len() {
            let next = mesh.line(lines[k + 1]);
            let end = mesh.line(l)[1];
            end == next[0] || end == next[1]
        } else if k > 0 {
            let prev_end = mesh.line(lines[k - 1])[1];
            mesh.line(l)[0] == prev_end
        } else {
            true
        };
        if !forward {
            mesh.reverse_line(l);
        }
    }
    let reverse = if chain.closed {
        // Twice the signed area of the polygon of the chain's corner nodes.
        let area2: f64 = lines
            .iter()
            .map(|&l| {
                let v = mesh.line(l);
                let (a, b) = (mesh.nodes[v[0] as usize], mesh.nodes[v[1] as usize]);
                a.to_vec2().cross(b.to_vec2())
            })
            .sum();
        area2 < 0.0
    } else {
        runs_backwards(accuracy, mesh, own, lines)
    };
    if reverse {
        for &l in lines {
            mesh.reverse_line(l);
        }
    }
}

/// Elements of an open chain whose direction is looked up on the source (the
/// ones nearest its middle); the chain follows their majority.
const DIRECTION_VOTES: usize = 5;

/// Whether the element `a → b` runs along its shape's source (`own`, the
/// shape's features): on the feature of the shape nearest the element's
/// midpoint (the branch the element lies on, even next to a place where the source crosses itself), the parameter
/// of `b`'s projection exceeds `a`'s. `None` if the shape has no curve
/// feature or the projections coincide.
fn runs_along(accuracy: f64, own: &Owned, a: Point, b: Point) -> Option<bool> {
    let mid = a.midpoint(b);
    let t = |f: &FeatureGeom, p: Point| match *f {
        FeatureGeom::Point(_) => None,
        FeatureGeom::Line(l) => Some(l.nearest(p, accuracy)),
        FeatureGeom::Cubic(c) => Some(c.nearest(p, accuracy)),
        FeatureGeom::Conic(c) => Some(c.approx_cubic().nearest(p, accuracy)),
    };
    let f = own.nearest(mid, t, |n| n.distance_sq)?;
    let (ta, tb) = (t(f, a)?.t, t(f, b)?.t);
    (ta != tb).then_some(ta < tb)
}

/// Whether the consecutive open chain `lines` runs against its source's
/// direction: the majority of [`runs_along`] over the [`DIRECTION_VOTES`]
/// elements nearest the chain's middle (no verdict: as it is).
fn runs_backwards(accuracy: f64, mesh: &FemMesh, own: &Owned, lines: &[usize]) -> bool {
    let mid = lines.len() / 2;
    let mut order: Vec<usize> = (0..lines.len()).collect();
    order.sort_by_key(|&k| k.abs_diff(mid));
    let (mut along, mut against) = (0usize, 0usize);
    for k in order.into_iter().take(DIRECTION_VOTES) {
        let v = mesh.line(lines[k]);
        let (a, b) = (mesh.nodes[v[0] as usize], mesh.nodes[v[1] as usize]);
        match runs_along(accuracy, own, a, b) {
            Some(true) => along += 1,
            Some(false) => against += 1,
            None => {}
        }
    }
    against > along
}

/// Add the physical curve [`BOUNDARY`] (see the module docs): one line element
/// per triangle edge no other triangle shares, with the triangle's nodes on
/// that edge. Nothing is added to a mesh without triangles.
pub(crate) fn add_boundary(mesh: &mut FemMesh) {
    let order = mesh.order();
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for t in 0..mesh.triangle_count() {
        let c = mesh.triangle(t);
        for e in 0..3 {
            *count.entry(edge_key(c[e], c[(e + 1) % 3])).or_default() += 1;
        }
    }
    let mut lines = Vec::new();
    for t in 0..mesh.triangle_count() {
        let c = mesh.triangle(t);
        for e in 0..3 {
            let (a, b) = (c[e], c[(e + 1) % 3]);
            if count[&edge_key(a, b)] == 1 {
                lines.push(a);
                lines.push(b);
                lines.extend(
                    crate::fem::triangle_edge_inner(order, e)
                        .iter()
                        .map(|&j| c[j]),
                );
            }
        }
    }
    if lines.is_empty() {
        return;
    }
    let group = u32::try_from(mesh.curves.len()).expect("internal: curve count fits u32");
    mesh.curves.push(BOUNDARY.to_owned());
    let n = lines.len() / order.line_nodes();
    mesh.lines.extend(lines);
    mesh.line_group.extend(std::iter::repeat_n(group, n));
    mesh.line_kind
        .extend(std::iter::repeat_n(LineKind::Boundary, n));
}

#[cfg(test)]
mod tests {
    use super::*;
    use kurbo::{CubicBez, Line};
    use proptest::prelude::*;

    fn features(pieces: &[(f64, f64, f64, f64, bool)]) -> Vec<Own> {
        pieces
            .iter()
            .map(|&(x, y, dx, dy, cubic)| {
                let (a, b) = (Point::new(x, y), Point::new(x + dx, y + dy));
                Own::new(if cubic {
                    FeatureGeom::Cubic(CubicBez::new(
                        a,
                        Point::new(x + dy, y - dx),
                        Point::new(x + dx - dy, y + dy + dx),
                        b,
                    ))
                } else {
                    FeatureGeom::Line(Line::new(a, b))
                })
            })
            .collect()
    }

    fn nearest_of(own: &Owned, p: Point) -> Option<usize> {
        let t = |f: &FeatureGeom, q: Point| match *f {
            FeatureGeom::Line(l) => Some(l.nearest(q, 1e-9)),
            FeatureGeom::Cubic(c) => Some(c.nearest(q, 1e-9)),
            _ => None,
        };
        let f = own.nearest(p, t, |n| n.distance_sq)?;
        own.features.iter().position(|o| std::ptr::eq(&o.geom, f))
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]
        /// The grid finds what scanning every feature finds: the same
        /// feature (the first of equal distances), for points inside and far
        /// outside the features' extent, with duplicated features (ties).
        #[test]
        fn grid_nearest_is_the_scan_nearest(
            pieces in proptest::collection::vec(
                (
                    0.0..100.0f64,
                    0.0..100.0f64,
                    prop_oneof![6 => -8.0..8.0f64, 1 => -60.0..60.0f64],
                    prop_oneof![6 => -8.0..8.0f64, 1 => -60.0..60.0f64],
                    any::<bool>(),
                ),
                65..300,
            ),
            dup in 0usize..65,
            queries in proptest::collection::vec((-300.0..400.0f64, -300.0..400.0f64), 1..40),
        ) {
            let mut pieces = pieces;
            pieces.push(pieces[dup]);
            let gridded = Owned::new(features(&pieces));
            prop_assert!(gridded.grid.is_some());
            let scanned = Owned { features: features(&pieces), grid: None };
            for (x, y) in queries {
                let p = Point::new(x, y);
                prop_assert_eq!(nearest_of(&gridded, p), nearest_of(&scanned, p), "at {:?}", p);
            }
        }
    }
}
