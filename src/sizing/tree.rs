//! The size field's background: a grid of square cells, each refined as a
//! quadtree where the size is small, with one value per cell corner and
//! bilinear interpolation inside a leaf. Evaluation is a grid lookup and a
//! descent of a few levels (none in open areas).
//!
//! Building it (see [`Tree::build`]):
//! 1. **Refine** level by level: a cell splits while its side exceeds a fraction of
//!    the size asked for in it: by the point fields (sampled at its corners and
//!    centre, all points of a level in one batch) and by the *sources*, points
//!    `p` with a size `h` that grows at a slope `s` away from them (outlines of
//!    thin strokes, `--size-near` outlines, region and box boundaries, the
//!    feature size). Near a source the fraction is small, so the value at the
//!    source is resolved; farther away cells may be as large as the size.
//! 2. **Value** every corner: the point fields there, and the cone
//!    `h + s·|x − p|` of each source, spread over the corners from the leaf that
//!    holds the source outwards, nearest first, with the exact Euclidean
//!    distance to the source (a vector distance transform), each cone at its
//!    own slope. The point fields spread the same way at the grading's slope, so
//!    the result grows by at most the grading per element everywhere but next
//!    to thin strokes, whose cones are steeper.

use kurbo::{Point, Rect};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Sizes at a batch of points (`∞` where none is set), or why not.
pub(crate) type PointField<'a, E> = dyn FnMut(&[Point]) -> Result<Vec<f64>, E> + 'a;

/// A point or straight piece whose size bounds the field around it:
/// `h + slope·dist(x, [a, b])`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Source {
    /// One end.
    pub a: Point,
    /// The other end (`a` for a point).
    pub b: Point,
    /// The size on it.
    pub h: f64,
    /// How fast the bound grows with the distance: the grading's slope, or
    /// less (`--size-near` over its distance), or more for a thin stroke (the
    /// drawing's own need, see `sources::STROKE_SLOPE`).
    pub slope: f64,
}

impl Source {
    /// A point source.
    pub(crate) fn point(p: Point, h: f64, slope: f64) -> Source {
        Source {
            a: p,
            b: p,
            h,
            slope,
        }
    }

    /// The distance from `p` to the piece.
    pub(crate) fn distance(&self, p: Point) -> f64 {
        let ab = self.b - self.a;
        let len2 = ab.hypot2();
        let t = if len2 > 0.0 {
            ((p - self.a).dot(ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        p.distance(self.a + t * ab)
    }

    /// The bound at `p`.
    pub(crate) fn at(&self, p: Point) -> f64 {
        self.h + self.slope * self.distance(p)
    }

    /// The smallest distance from the piece to the square at `at` of side `side`.
    fn box_distance(&self, at: Point, side: f64) -> f64 {
        let bx = Rect::new(at.x, at.y, at.x + side, at.y + side);
        if bx.contains(self.a) || bx.contains(self.b) {
            return 0.0;
        }
        let corners = [
            Point::new(bx.x0, bx.y0),
            Point::new(bx.x1, bx.y0),
            Point::new(bx.x1, bx.y1),
            Point::new(bx.x0, bx.y1),
        ];
        // crossing a side: distance 0
        for k in 0..4 {
            if segments_cross(self.a, self.b, corners[k], corners[(k + 1) % 4]) {
                return 0.0;
            }
        }
        let to_box = |p: Point| {
            let dx = (bx.x0 - p.x).max(p.x - bx.x1).max(0.0);
            let dy = (bx.y0 - p.y).max(p.y - bx.y1).max(0.0);
            dx.hypot(dy)
        };
        corners
            .iter()
            .map(|&c| self.distance(c))
            .fold(to_box(self.a).min(to_box(self.b)), f64::min)
    }

    fn bbox(&self) -> Rect {
        Rect::from_points(self.a, self.b)
    }

    /// A cheap lower bound of [`Self::box_distance`]: the distance between the
    /// piece's bounding box and the square.
    fn box_distance_bound(&self, at: Point, side: f64) -> f64 {
        let bb = self.bbox();
        let dx = (at.x - bb.x1).max(bb.x0 - (at.x + side)).max(0.0);
        let dy = (at.y - bb.y1).max(bb.y0 - (at.y + side)).max(0.0);
        dx.hypot(dy)
    }

    /// Whether the source matters to a square at `at` of side `side` in a field
    /// below `hi`: it asks for a split (a side above [`FINE`] of its size
    /// there), or lies within a side of it (a leaf keeps it).
    fn matters(&self, at: Point, side: f64, lo: f64, hi: f64) -> bool {
        let far = |dist: f64| {
            let want = self.h + self.slope * dist;
            dist > side && !(want < hi && side > FINE * want.max(lo))
        };
        if far(self.box_distance_bound(at, side)) {
            return false;
        }
        !far(self.box_distance(at, side))
    }
}

/// Whether segments pq and rs cross or touch (floating point; a near miss only
/// makes a box look farther than it is by at most the miss).
fn segments_cross(p: Point, q: Point, r: Point, s: Point) -> bool {
    let d = |a: Point, b: Point, c: Point| (b - a).cross(c - a);
    let (d1, d2) = (d(r, s, p), d(r, s, q));
    let (d3, d4) = (d(p, q, r), d(p, q, s));
    (d1 * d2 <= 0.0) && (d3 * d4 <= 0.0) && !(d1 == 0.0 && d2 == 0.0 && d3 == 0.0 && d4 == 0.0)
}

/// A cell side is at most this fraction of the size asked for in the cell.
/// Near a source the leaf also keeps the source itself (see [`Tree::at`]), so
/// the value there is exact; elsewhere the bilinear interpolation of a cone
/// errs by a few per cent at this resolution.
const FINE: f64 = 1.0;
/// Boxes (or spread steps) between two checks of the deadline inside a
/// level: a level of a fine field over many sources takes seconds.
const CHECK_EVERY: usize = 1024;
/// Deepest refinement below a grid cell.
const MAX_DEPTH: u32 = 24;
/// The grid has at most this many cells.
const MAX_CELLS: f64 = 65_536.0;
/// What a box of the tree takes while it is built and spread, bytes: its
/// node, its corners in the lattice and the point-field map, their
/// neighbour lists and the spreading's state (measured: about 615 bytes per
/// leaf at 0.3 to 1.2 million leaves).
pub(crate) const BYTES_PER_CELL: u64 = 640;

#[derive(Clone, Copy, Debug)]
struct Node {
    /// Index of the first of four children (0: a leaf; the roots are never children).
    child: u32,
    /// Corner ids: (x0, y0), (x1, y0), (x0, y1), (x1, y1).
    corners: [u32; 4],
    /// A leaf's own sources: `local[start..start + len]` (those within a side of it).
    local: (u32, u32),
    /// A leaf's groups of its own sources: `groups[start..start + len]`
    /// (none when it has fewer than [`GROUPED_FROM`]).
    groups: (u32, u32),
    /// A leaf's corner values (copied from the corners once they are known).
    values: [f64; 4],
}

impl Node {
    /// A box not split (yet), with its corners' ids.
    fn unsplit(corners: [u32; 4]) -> Node {
        Node {
            child: 0,
            corners,
            local: (0, 0),
            groups: (0, 0),
            values: [0.0; 4],
        }
    }
}

/// The quadtree background (see the module doc).
#[derive(Clone, Debug)]
pub(crate) struct Tree {
    origin: Point,
    cell: f64,
    nx: usize,
    ny: usize,
    nodes: Vec<Node>,
    /// `nodes[i].child` alone: the descent reads only this (compact, so it
    /// stays in cache).
    child: Vec<u32>,
    values: Vec<f64>,
    /// The leaves' own sources (see [`Node::local`]).
    local: Vec<Source>,
    /// The groups of the leaves' own sources (see [`Node::groups`]).
    groups: Vec<Group>,
    lo: f64,
    hi: f64,
    /// Whether refinement stopped at the leaf budget (see [`Tree::build`]).
    capped: bool,
}

/// Consecutive sources of a leaf's own (along a curve, mostly: the sources
/// come in the features' order) with a lower bound of what any of them asks
/// for at a point: their smallest size and slope, and their bounding box.
#[derive(Clone, Copy, Debug)]
struct Group {
    lo: Point,
    hi: Point,
    h: f64,
    slope: f64,
    /// The sources: `local[start..start + len]`.
    start: u32,
    len: u32,
}

impl Group {
    /// The group of `sources`, which start at `start` in the tree's list.
    fn of(sources: &[Source], start: usize) -> Group {
        let mut g = Group {
            lo: Point::new(f64::INFINITY, f64::INFINITY),
            hi: Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
            h: f64::INFINITY,
            slope: f64::INFINITY,
            start: start as u32,
            len: sources.len() as u32,
        };
        for s in sources {
            for q in [s.a, s.b] {
                g.lo = Point::new(g.lo.x.min(q.x), g.lo.y.min(q.y));
                g.hi = Point::new(g.hi.x.max(q.x), g.hi.y.max(q.y));
            }
            g.h = g.h.min(s.h);
            g.slope = g.slope.min(s.slope);
        }
        g
    }

    /// A lower bound of what its sources ask for at `p`.
    fn bound(&self, p: Point) -> f64 {
        let dx = (self.lo.x - p.x).max(p.x - self.hi.x).max(0.0);
        let dy = (self.lo.y - p.y).max(p.y - self.hi.y).max(0.0);
        self.h + self.slope * (dx * dx + dy * dy).sqrt()
    }
}

/// A leaf with at least this many sources of its own groups them
/// ([`Group`]): [`Tree::at`] then reads the groups nearest first and stops at
/// the first that cannot ask for less than what it has. Near a curve drawn
/// with many short segments a leaf holds a hundred.
const GROUPED_FROM: usize = 24;
/// Sources per group: at least this many, more where a leaf would have more
/// than [`MAX_GROUPS`] groups.
const GROUP_SIZE: usize = 8;
/// A leaf has at most this many groups (their bounds are sorted on the stack).
const MAX_GROUPS: usize = 32;
/// A group is passed over only when its bound exceeds the size found by this
/// relative margin: far more than the rounding of the distances, so a source
/// passed over could not have asked for less, and the value is the one every
/// source read would give.
const GROUP_MARGIN: f64 = 1e-9;

/// A box being refined: its node, its lower-left corner, its side and the
/// sources that may still split it.
struct Pending {
    node: u32,
    at: Point,
    side: f64,
    depth: u32,
    sources: Vec<u32>,
}

/// What a box of a level keeps ([`Tree::build`]): a leaf its own sources, a
/// box that splits the sources that still matter to each quadrant.
enum Kept {
    Leaf(Vec<Source>),
    Children([Vec<u32>; 4]),
}

/// The lower-left corners of the four quadrants of the square at `at` of
/// side `2·half`, in the children's order.
fn quadrants(at: Point, half: f64) -> [Point; 4] {
    [(0.0, 0.0), (half, 0.0), (0.0, half), (half, half)]
        .map(|(dx, dy)| Point::new(at.x + dx, at.y + dy))
}

/// The lattice of corner positions: integer coordinates in units of the
/// finest side.
struct Lattice {
    origin: Point,
    unit: f64,
    ids: FxHashMap<(i64, i64), u32>,
    points: Vec<Point>,
}

impl Lattice {
    fn id(&mut self, p: Point) -> u32 {
        let key = (
            ((p.x - self.origin.x) / self.unit).round() as i64,
            ((p.y - self.origin.y) / self.unit).round() as i64,
        );
        let next = self.points.len() as u32;
        *self.ids.entry(key).or_insert_with(|| {
            self.points.push(p);
            next
        })
    }
}

/// The size a source asks for in a box (infinite where it is `hi` or more:
/// then it asks for no split).
fn asked(s: &Source, at: Point, side: f64, hi: f64) -> f64 {
    let want = s.h + s.slope * s.box_distance(at, side);
    if want < hi { want } else { f64::INFINITY }
}

/// The state of [`Tree::spread`]: values, labels and the queue, nearest first.
struct Spread<'a> {
    points: &'a [Point],
    value: Vec<f64>,
    label: Vec<Option<Source>>,
    heap: BinaryHeap<Reverse<(u64, u32)>>,
}

impl Spread<'_> {
    /// Offer corner `i` the cone of `s`; it takes it when that is smaller.
    fn offer(&mut self, i: usize, s: Source) {
        let v = s.at(self.points[i]);
        if v < self.value[i] {
            self.value[i] = v;
            self.label[i] = Some(s);
            self.heap.push(Reverse((v.to_bits(), i as u32)));
        }
    }
}

impl Tree {
    /// A field over `bounds` that is `hi` everywhere, clamped to `[lo, hi]`.
    pub(crate) fn uniform(bounds: Rect, hi: f64) -> Tree {
        Tree {
            origin: Point::new(bounds.x0, bounds.y0),
            cell: bounds.width().max(bounds.height()).max(f64::MIN_POSITIVE),
            nx: 1,
            ny: 1,
            nodes: vec![Node {
                child: 0,
                corners: [0, 1, 2, 3],
                local: (0, 0),
                groups: (0, 0),
                values: [hi; 4],
            }],
            child: vec![0],
            values: vec![hi; 4],
            local: Vec::new(),
            groups: Vec::new(),
            lo: hi,
            hi,
            capped: false,
        }
    }

    /// Build the field over `bounds` (see the module doc): sizes within
    /// `[lo, hi]`, growing by at most `slope` per unit length (the grading less
    /// one), bounded by `sources` and by `point_field` (sizes at a batch of
    /// points, `∞` where it sets none; an error stops the build).
    ///
    /// Refinement goes level by level and stops before a level that would
    /// take the tree past `max_leaves` leaves: the field is then resolved
    /// only to the last level that fits ([`Tree::capped`]). `keep_going` is
    /// asked before each level with the bytes that level may add (the
    /// memory budget's check before a large allocation).
    ///
    /// # Errors
    /// What `point_field` or `keep_going` returns.
    #[expect(
        clippy::too_many_arguments,
        reason = "the field's range and grading, its two inputs and its two budgets, passed \
                  straight through by the one caller"
    )]
    pub(crate) fn build<E>(
        bounds: Rect,
        lo: f64,
        hi: f64,
        slope: f64,
        sources: &[Source],
        point_field: &mut PointField<'_, E>,
        max_leaves: usize,
        keep_going: &dyn Fn(u64) -> Result<(), E>,
    ) -> Result<Tree, E> {
        let (w, h) = (bounds.width().max(lo), bounds.height().max(lo));
        let mut cell = hi.max(lo);
        while (w / cell).ceil() * (h / cell).ceil() > MAX_CELLS {
            cell *= 2.0;
        }
        let nx = ((w / cell).ceil() as usize).max(1);
        let ny = ((h / cell).ceil() as usize).max(1);
        let origin = Point::new(bounds.x0, bounds.y0);
        let mut lattice = Lattice {
            origin,
            unit: cell / f64::from(1u32 << MAX_DEPTH),
            ids: FxHashMap::default(),
            points: Vec::new(),
        };
        let mut nodes = Vec::with_capacity(nx * ny);
        let corner_points = |at: Point, side: f64| {
            [
                at,
                Point::new(at.x + side, at.y),
                Point::new(at.x, at.y + side),
                Point::new(at.x + side, at.y + side),
            ]
        };
        for j in 0..ny {
            for i in 0..nx {
                let at = Point::new(origin.x + i as f64 * cell, origin.y + j as f64 * cell);
                nodes.push(Node::unsplit(
                    corner_points(at, cell).map(|p| lattice.id(p)),
                ));
            }
        }
        // Sources by grid cell: those whose cone may ask for a cell smaller
        // than the grid's.
        let mut by_root: Vec<Vec<u32>> = vec![Vec::new(); nx * ny];
        for (k, s) in sources.iter().enumerate() {
            // how far it may still ask for a size below hi, or lies within a
            // cell's side (its own leaf keeps it)
            let reach = if s.slope > 0.0 {
                ((hi - s.h) / s.slope).max(0.0).max(cell)
            } else {
                f64::INFINITY
            };
            let bb = s.bbox();
            let range = |c0: f64, c1: f64, o: f64, n: usize| {
                let lo_i = ((c0 - reach - o) / cell).floor().max(0.0);
                let hi_i = ((c1 + reach - o) / cell).floor().min(n as f64 - 1.0);
                (lo_i as usize, hi_i.max(lo_i) as usize)
            };
            let (i0, i1) = range(bb.x0, bb.x1, origin.x, nx);
            let (j0, j1) = range(bb.y0, bb.y1, origin.y, ny);
            for j in j0..=j1.min(ny - 1) {
                for i in i0..=i1.min(nx - 1) {
                    by_root[j * nx + i].push(k as u32);
                }
            }
        }
        let mut level: Vec<Pending> = by_root
            .into_iter()
            .enumerate()
            .map(|(r, sources)| Pending {
                node: r as u32,
                at: Point::new(
                    origin.x + (r % nx) as f64 * cell,
                    origin.y + (r / nx) as f64 * cell,
                ),
                side: cell,
                depth: 0,
                sources,
            })
            .collect();
        // Point-field values by corner id (centres too, under ids of their own).
        let mut pointwise: FxHashMap<u32, f64> = FxHashMap::default();
        let mut local: Vec<Source> = Vec::new();
        let mut leaves = 0usize;
        let mut capped = false;
        while !level.is_empty() {
            keep_going(0)?;
            // The point field at every corner and centre of this level not yet known.
            let mut ask: Vec<(u32, Point)> = Vec::new();
            let mut centres: Vec<u32> = Vec::with_capacity(level.len());
            for b in &level {
                let centre = Point::new(b.at.x + 0.5 * b.side, b.at.y + 0.5 * b.side);
                let ids = nodes[b.node as usize].corners;
                let pts = corner_points(b.at, b.side);
                for (id, p) in ids.into_iter().zip(pts) {
                    ask.push((id, p));
                }
                let centre_id = lattice.id(centre);
                centres.push(centre_id);
                ask.push((centre_id, centre));
            }
            ask.sort_unstable_by_key(|a| a.0);
            ask.dedup_by_key(|a| a.0);
            ask.retain(|a| !pointwise.contains_key(&a.0));
            if !ask.is_empty() {
                let pts: Vec<Point> = ask.iter().map(|a| a.1).collect();
                let vals = point_field(&pts)?;
                for (a, v) in ask.iter().zip(vals) {
                    pointwise.insert(a.0, v);
                }
            }
            // Which boxes of the level split, then whether the level fits; then
            // each leaf's own sources and each split box's children's. Both in
            // parallel, a block of boxes between two checks of the deadline;
            // the nodes and the lattice grow in the level's order after, so the
            // tree is the same on any number of threads.
            let mut splits: Vec<bool> = Vec::with_capacity(level.len());
            for (block, ids) in level.chunks(CHECK_EVERY).zip(centres.chunks(CHECK_EVERY)) {
                keep_going(0)?;
                let nodes = &nodes;
                let pointwise = &pointwise;
                splits.par_extend(block.par_iter().zip(ids).map(|(b, &centre_id)| {
                    let field = nodes[b.node as usize]
                        .corners
                        .iter()
                        .chain([&centre_id])
                        .map(|id| pointwise[id])
                        .fold(f64::INFINITY, f64::min);
                    let mut split = field < hi && b.side > FINE * field.max(lo);
                    for &k in &b.sources {
                        if split {
                            break;
                        }
                        let s = &sources[k as usize];
                        let bound = s.h + s.slope * s.box_distance_bound(b.at, b.side);
                        if bound >= hi || b.side <= FINE * bound.max(lo) {
                            continue;
                        }
                        let want = asked(s, b.at, b.side, hi);
                        split = b.side > FINE * want.max(lo);
                    }
                    split && b.depth < MAX_DEPTH && 0.5 * b.side >= FINE * lo
                }));
            }
            let n_split = splits.iter().filter(|&&x| x).count();
            if n_split > 0 {
                if leaves + level.len() + 3 * n_split > max_leaves {
                    capped = true;
                    splits.fill(false);
                } else {
                    keep_going(4 * n_split as u64 * BYTES_PER_CELL)?;
                }
            }
            let mut next = Vec::with_capacity(4 * n_split);
            for (block, block_splits) in level.chunks(CHECK_EVERY).zip(splits.chunks(CHECK_EVERY)) {
                keep_going(0)?;
                let kept: Vec<Kept> = block
                    .par_iter()
                    .zip(block_splits)
                    .map(|(b, &split)| {
                        if !split {
                            // a leaf: it keeps the sources within its side
                            return Kept::Leaf(
                                b.sources
                                    .iter()
                                    .map(|&k| sources[k as usize])
                                    .filter(|s| s.box_distance(b.at, b.side) <= b.side)
                                    .collect(),
                            );
                        }
                        let half = 0.5 * b.side;
                        Kept::Children(quadrants(b.at, half).map(|at| {
                            b.sources
                                .iter()
                                .copied()
                                .filter(|&k| sources[k as usize].matters(at, half, lo, hi))
                                .collect()
                        }))
                    })
                    .collect();
                for (b, kept) in block.iter().zip(kept) {
                    match kept {
                        Kept::Leaf(own) => {
                            leaves += 1;
                            let start = local.len() as u32;
                            local.extend(own);
                            nodes[b.node as usize].local = (start, local.len() as u32 - start);
                        }
                        Kept::Children(children) => {
                            let half = 0.5 * b.side;
                            let first = nodes.len() as u32;
                            nodes[b.node as usize].child = first;
                            for (q, (at, kept)) in
                                quadrants(b.at, half).into_iter().zip(children).enumerate()
                            {
                                nodes.push(Node::unsplit(
                                    corner_points(at, half).map(|p| lattice.id(p)),
                                ));
                                next.push(Pending {
                                    node: first + q as u32,
                                    at,
                                    side: half,
                                    depth: b.depth + 1,
                                    sources: kept,
                                });
                            }
                        }
                    }
                }
            }
            level = next;
        }
        let n = lattice.points.len();
        // Corners created as the centre of a leaf that never split have a
        // point-field value but no edges; they are values like any other.
        let mut tree = Tree {
            origin,
            cell,
            nx,
            ny,
            child: nodes.iter().map(|n| n.child).collect(),
            nodes,
            values: vec![hi; n],
            local,
            groups: Vec::new(),
            lo,
            hi,
            capped,
        };
        tree.spread(&lattice.points, &pointwise, slope, keep_going)?;
        Ok(tree)
    }

    /// Step 2 of the module doc: every corner's value from the point fields and
    /// the sources' cones, spread nearest first.
    fn spread<E>(
        &mut self,
        points: &[Point],
        pointwise: &FxHashMap<u32, f64>,
        slope: f64,
        keep_going: &dyn Fn(u64) -> Result<(), E>,
    ) -> Result<(), E> {
        let n = points.len();
        // Neighbours along the leaves' sides and diagonals.
        let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
        for node in &self.nodes {
            if node.child != 0 {
                continue;
            }
            let [a, b, c, d] = node.corners;
            for (u, v) in [(a, b), (a, c), (b, d), (c, d), (a, d), (b, c)] {
                adj[u as usize].push(v);
                adj[v as usize].push(u);
            }
        }
        for list in &mut adj {
            list.sort_unstable();
            list.dedup();
        }
        // The label of a corner: the origin, size and slope of the cone that
        // gives its value.
        let mut sp = Spread {
            points,
            value: vec![self.hi; n],
            label: vec![None; n],
            heap: BinaryHeap::new(),
        };
        let mut ids: Vec<(u32, f64)> = pointwise.iter().map(|(&k, &v)| (k, v)).collect();
        ids.sort_unstable_by_key(|e| e.0);
        for (id, v) in ids {
            if v.is_finite() && (id as usize) < n {
                let s = Source::point(points[id as usize], v.max(self.lo), slope);
                sp.offer(id as usize, s);
            }
        }
        // Every leaf offers its corners its own sources (a source is in the
        // lists of the leaves within a side of it).
        for node in &self.nodes {
            let (start, len) = node.local;
            for s in &self.local[start as usize..(start + len) as usize] {
                let s = Source {
                    h: s.h.max(self.lo),
                    ..*s
                };
                for c in node.corners {
                    sp.offer(c as usize, s);
                }
            }
        }
        let mut popped = 0usize;
        while let Some(Reverse((bits, i))) = sp.heap.pop() {
            popped += 1;
            if popped % CHECK_EVERY == 0 {
                keep_going(0)?;
            }
            let i = i as usize;
            if bits != sp.value[i].to_bits() {
                continue; // beaten since it was queued
            }
            let Some(s) = sp.label[i] else { continue };
            for &w in &adj[i] {
                sp.offer(w as usize, s);
            }
        }
        let value = sp.value;
        // A leaf keeps only the sources that ask for less than its corners
        // somewhere in it (elsewhere the bilinear interpolation is as small).
        let mut kept: Vec<Source> = Vec::with_capacity(self.local.len());
        for node in &mut self.nodes {
            let (start, len) = node.local;
            let top = node
                .corners
                .iter()
                .map(|&c| value[c as usize])
                .fold(0.0, f64::max);
            let new_start = kept.len() as u32;
            for s in &self.local[start as usize..(start + len) as usize] {
                let side =
                    points[node.corners[0] as usize].distance(points[node.corners[1] as usize]);
                let at = points[node.corners[0] as usize];
                if s.h + s.slope * s.box_distance(at, side) < top {
                    kept.push(*s);
                }
            }
            node.local = (new_start, kept.len() as u32 - new_start);
        }
        self.local = kept;
        let mut groups = Vec::new();
        for node in &mut self.nodes {
            let (start, len) = (node.local.0 as usize, node.local.1 as usize);
            if len < GROUPED_FROM {
                continue;
            }
            let size = GROUP_SIZE.max(len.div_ceil(MAX_GROUPS));
            let first = groups.len() as u32;
            for (i, chunk) in self.local[start..start + len].chunks(size).enumerate() {
                groups.push(Group::of(chunk, start + i * size));
            }
            node.groups = (first, groups.len() as u32 - first);
        }
        self.groups = groups;
        for node in &mut self.nodes {
            node.values = node
                .corners
                .map(|c| value[c as usize].clamp(self.lo, self.hi));
        }
        self.values = value
            .into_iter()
            .map(|v| v.clamp(self.lo, self.hi))
            .collect();
        Ok(())
    }

    /// The leaf holding `p` (clamped into the grid), and `p`'s coordinates in
    /// it, each in `[0, 1]`.
    fn locate(&self, p: Point) -> (usize, f64, f64) {
        let fx = ((p.x - self.origin.x) / self.cell).clamp(0.0, self.nx as f64);
        let fy = ((p.y - self.origin.y) / self.cell).clamp(0.0, self.ny as f64);
        let i = (fx.floor() as usize).min(self.nx - 1);
        let j = (fy.floor() as usize).min(self.ny - 1);
        let (mut u, mut v) = (
            (fx - i as f64).clamp(0.0, 1.0),
            (fy - j as f64).clamp(0.0, 1.0),
        );
        let mut node = j * self.nx + i;
        loop {
            let child = self.child[node] as usize;
            if child == 0 {
                return (node, u, v);
            }
            let (right, up) = (u >= 0.5, v >= 0.5);
            u = if right { 2.0 * u - 1.0 } else { 2.0 * u };
            v = if up { 2.0 * v - 1.0 } else { 2.0 * v };
            node = child + usize::from(right) + 2 * usize::from(up);
        }
    }

    /// The size at `p` (outside the grid: at the nearest point of it): the
    /// bilinear interpolation of the leaf's corners, or the leaf's own sources
    /// where they ask for less.
    pub(crate) fn at(&self, p: Point) -> f64 {
        let (leaf, u, v) = self.locate(p);
        let node = &self.nodes[leaf];
        let [a, b, c, d] = node.values;
        let mut h = (a * (1.0 - u) + b * u) * (1.0 - v) + (c * (1.0 - u) + d * u) * v;
        let read = |h: f64, sources: &[Source]| {
            sources
                .iter()
                .fold(h, |h, s| if s.h < h { h.min(s.at(p)) } else { h })
        };
        let (start, len) = node.local;
        let (first, n) = node.groups;
        if n == 0 {
            h = read(h, &self.local[start as usize..(start + len) as usize]);
        } else {
            // the nearest group first, then the others whose bound is below
            // what is found (a group above it cannot lower it)
            let groups = &self.groups[first as usize..(first + n) as usize];
            let bounds: smallvec::SmallVec<[f64; MAX_GROUPS]> =
                groups.iter().map(|g| g.bound(p)).collect();
            let nearest = (0..bounds.len())
                .min_by(|&a, &b| bounds[a].total_cmp(&bounds[b]))
                .unwrap_or(0);
            let of = |g: &Group| &self.local[g.start as usize..(g.start + g.len) as usize];
            h = read(h, of(&groups[nearest]));
            for (i, (g, &bound)) in groups.iter().zip(&bounds).enumerate() {
                if i != nearest && bound < h * (1.0 + GROUP_MARGIN) {
                    h = read(h, of(g));
                }
            }
        }
        h.clamp(self.lo, self.hi)
    }

    /// Whether refinement stopped at the leaf budget: the field is coarser
    /// than asked where it is finest.
    pub(crate) fn capped(&self) -> bool {
        self.capped
    }

    /// Every leaf: its centre, its side and its smallest corner value.
    pub(crate) fn leaf_boxes(&self) -> Vec<(Point, f64, f64)> {
        let mut out = Vec::new();
        let mut stack: Vec<(usize, Point, f64)> = Vec::new();
        for j in 0..self.ny {
            for i in 0..self.nx {
                let at = Point::new(
                    self.origin.x + i as f64 * self.cell,
                    self.origin.y + j as f64 * self.cell,
                );
                stack.push((j * self.nx + i, at, self.cell));
            }
        }
        while let Some((node, at, side)) = stack.pop() {
            let child = self.child[node] as usize;
            if child == 0 {
                let h = self.nodes[node]
                    .values
                    .into_iter()
                    .fold(f64::INFINITY, f64::min);
                out.push((Point::new(at.x + side / 2.0, at.y + side / 2.0), side, h));
                continue;
            }
            let half = side / 2.0;
            for (q, off) in quadrants(at, half).into_iter().enumerate() {
                stack.push((child + q, off, half));
            }
        }
        out
    }

    /// Number of leaves (for the report).
    pub(crate) fn leaves(&self) -> usize {
        self.nodes.iter().filter(|n| n.child == 0).count()
    }

    /// The smallest corner value.
    pub(crate) fn min_value(&self) -> f64 {
        self.values.iter().copied().fold(self.hi, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn no_points(p: &[Point]) -> Result<Vec<f64>, ()> {
        Ok(vec![f64::INFINITY; p.len()])
    }

    /// The field of `src` alone over `bounds`, within [0.01, 5], graded 1.5.
    fn from_sources(bounds: Rect, src: &[Source]) -> Tree {
        let no_budget = |_: u64| Ok(());
        Tree::build(
            bounds,
            0.01,
            5.0,
            0.5,
            src,
            &mut no_points,
            usize::MAX,
            &no_budget,
        )
        .unwrap()
    }

    #[test]
    fn a_source_is_resolved_and_its_cone_graded() {
        let bounds = Rect::new(0.0, 0.0, 100.0, 100.0);
        let src = [Source::point(Point::new(31.3, 47.9), 0.5, 0.5)];
        let t = from_sources(bounds, &src);
        let at_source = t.at(src[0].a);
        assert_eq!(at_source, 0.5, "exact at the source");
        for d in [1.0, 2.0, 4.0, 8.0] {
            let p = Point::new(31.3 + d, 47.9);
            let want = (0.5 + 0.5 * d).min(5.0);
            assert!(
                (t.at(p) - want).abs() < 0.1 * want,
                "at distance {d}: {} vs {want}",
                t.at(p)
            );
        }
        assert_eq!(t.at(Point::new(90.0, 90.0)), 5.0);
    }

    /// The levels' split decisions and kept sources are made in parallel:
    /// the tree is the same on one thread and on two (its nodes, corners,
    /// values and leaves' own sources), over many sources of either kind.
    #[test]
    fn the_tree_is_the_same_on_one_and_two_threads() {
        let bounds = Rect::new(0.0, 0.0, 100.0, 60.0);
        let src: Vec<Source> = (0..400)
            .map(|i| {
                let t = f64::from(i) * 0.37;
                let a = Point::new(50.0 + 40.0 * t.cos(), 30.0 + 25.0 * (1.3 * t).sin());
                if i % 3 == 0 {
                    Source::point(a, 0.05 + 0.01 * f64::from(i % 7), 0.5)
                } else {
                    let b = Point::new(a.x + 0.8 * t.sin(), a.y + 0.6);
                    Source {
                        a,
                        b,
                        h: 0.1 + 0.02 * f64::from(i % 5),
                        slope: 1.5,
                    }
                }
            })
            .collect();
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool")
                .install(|| from_sources(bounds, &src))
        };
        let (one, two) = (on(1), on(2));
        assert!(one.leaves() > 1000, "{} leaves", one.leaves());
        assert_eq!(one.leaves(), two.leaves());
        assert_eq!(one.child, two.child);
        assert_eq!(one.values, two.values);
        assert_eq!(one.local, two.local);
        let nodes = |t: &Tree| -> Vec<([u32; 4], (u32, u32))> {
            t.nodes.iter().map(|n| (n.corners, n.local)).collect()
        };
        assert_eq!(nodes(&one), nodes(&two));
    }

    /// The leaves ([`Tree::leaf_boxes`]) tile the grid: as many as the tree
    /// counts, their areas summing to the grid's, each centre in the leaf
    /// that `locate` finds for it, with that leaf's smallest corner value.
    /// A leaf near a curve drawn with many short segments groups its
    /// sources; the lookup, which reads only the groups that may ask for
    /// less, gives exactly the minimum over all its sources.
    #[test]
    fn grouped_sources_give_the_value_of_every_source() {
        let bounds = Rect::new(0.0, 0.0, 10.0, 10.0);
        // a circle of 600 segments, sizes varying along it, and a second,
        // concentric one close by
        let ring = |r: f64, n: usize, h0: f64| {
            (0..n).map(move |i| {
                let at = |k: usize| {
                    let t = std::f64::consts::TAU * k as f64 / n as f64;
                    Point::new(5.0 + r * t.cos(), 5.0 + r * t.sin())
                };
                let h = h0 * (1.0 + 0.5 * (i as f64 * 0.05).sin());
                Source {
                    a: at(i),
                    b: at(i + 1),
                    h,
                    slope: 0.5 + 0.1 * (i % 3) as f64,
                }
            })
        };
        let src: Vec<Source> = ring(3.0, 600, 0.3).chain(ring(3.2, 300, 0.2)).collect();
        let t = from_sources(bounds, &src);
        let grouped = t.nodes.iter().filter(|n| n.groups.1 > 0).count();
        assert!(grouped > 0, "no leaf has groups");
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut read_grouped = 0;
        for _ in 0..20_000 {
            // (near the circles, where the leaves group their sources)
            let (r, angle) = (2.6 + next(), std::f64::consts::TAU * next());
            let p = Point::new(5.0 + r * angle.cos(), 5.0 + r * angle.sin());
            let (leaf, u, v) = t.locate(p);
            let node = &t.nodes[leaf];
            let [a, b, c, d] = node.values;
            let mut want = (a * (1.0 - u) + b * u) * (1.0 - v) + (c * (1.0 - u) + d * u) * v;
            let (start, len) = node.local;
            for s in &t.local[start as usize..(start + len) as usize] {
                want = want.min(s.at(p));
            }
            assert_eq!(t.at(p), want.clamp(t.lo, t.hi), "at {p:?}");
            read_grouped += usize::from(node.groups.1 > 0);
        }
        assert!(
            read_grouped > 1000,
            "{read_grouped} lookups in grouped leaves"
        );
    }

    #[test]
    fn the_leaf_boxes_tile_the_grid() {
        let bounds = Rect::new(0.0, 0.0, 100.0, 60.0);
        let src = [Source::point(Point::new(31.3, 47.9), 0.5, 0.5)];
        let t = from_sources(bounds, &src);
        let leaves = t.leaf_boxes();
        assert_eq!(leaves.len(), t.leaves());
        let area: f64 = leaves.iter().map(|&(_, side, _)| side * side).sum();
        let grid = (t.nx * t.ny) as f64 * t.cell * t.cell;
        assert!((area - grid).abs() < 1e-9 * grid, "{area} vs {grid}");
        for &(p, side, h) in &leaves {
            let (leaf, u, v) = t.locate(p);
            assert!(
                (u - 0.5).abs() < 1e-9 && (v - 0.5).abs() < 1e-9,
                "{p:?} {side}"
            );
            let min = t.nodes[leaf]
                .values
                .into_iter()
                .fold(f64::INFINITY, f64::min);
            assert_eq!(h, min);
        }
        assert!(
            leaves.iter().any(|&(_, _, h)| h < 1.0),
            "refined near the source"
        );
    }

    #[test]
    fn a_steeper_source_keeps_its_own_slope() {
        // A thin stroke's cone grows at slope 1 under a grading of 1.5 (slope
        // 0.5): the spread must not flatten it to the grading's slope.
        let bounds = Rect::new(0.0, 0.0, 100.0, 100.0);
        let src = [Source::point(Point::new(50.0, 50.0), 0.2, 1.0)];
        let t = from_sources(bounds, &src);
        for d in [1.0, 2.0, 3.0] {
            let got = t.at(Point::new(50.0 + d, 50.0));
            let want = 0.2 + d;
            assert!((got - want).abs() < 0.1 * want, "at {d}: {got} vs {want}");
        }
        assert_eq!(t.at(Point::new(50.0, 60.0)), 5.0, "l beyond 4.8");
    }

    #[test]
    fn a_point_field_is_graded_and_clamped() {
        let bounds = Rect::new(0.0, 0.0, 10.0, 10.0);
        // 0.05 left of x = 5, 2 right of it: the grading spreads the small
        // size to the right at slope 0.5.
        let mut step = |p: &[Point]| -> Result<Vec<f64>, ()> {
            Ok(p.iter()
                .map(|q| if q.x < 5.0 { 0.05 } else { 2.0 })
                .collect())
        };
        let t = Tree::build(bounds, 0.1, 1.0, 0.5, &[], &mut step, usize::MAX, &|_| {
            Ok(())
        })
        .unwrap();
        assert!(
            (t.at(Point::new(2.0, 5.0)) - 0.1).abs() < 1e-12,
            "clamped to lo"
        );
        let right = t.at(Point::new(6.0, 5.0));
        assert!(right > 0.4 && right < 0.75, "graded: {right}");
        assert!(
            (t.at(Point::new(9.9, 5.0)) - 1.0).abs() < 1e-12,
            "clamped to hi"
        );
    }

    /// A field finer than the leaf budget stops refining at the last level
    /// that fits, the same everywhere (a uniform field gives a uniform
    /// tree), and says so; the memory check sees each level's bytes before
    /// they are allocated, and its refusal stops the build.
    #[test]
    fn the_leaf_budget_bounds_a_field_too_fine_for_it() {
        let bounds = Rect::new(0.0, 0.0, 10.0, 10.0);
        let mut fine = |p: &[Point]| -> Result<Vec<f64>, ()> { Ok(vec![0.001; p.len()]) };
        let free = Tree::build(bounds, 0.04, 1.0, 0.5, &[], &mut fine, usize::MAX, &|_| {
            Ok(())
        })
        .unwrap();
        assert!(!free.capped());
        // 10^2 roots of side 1 split while half a side is at least lo = 0.04:
        // down to side 1/16, 4^4 leaves each
        assert_eq!(free.leaves(), 100 << 8);
        for budget in [100, 399, 400, 2_000, 100 << 8] {
            let t =
                Tree::build(bounds, 0.04, 1.0, 0.5, &[], &mut fine, budget, &|_| Ok(())).unwrap();
            assert!(t.leaves() <= budget.max(100), "{budget}: {}", t.leaves());
            assert_eq!(t.capped(), budget < 100 << 8, "{budget}");
            // the whole level or none: a power of four of the roots
            assert!(t.leaves() / 100 == 1 << (2 * (t.leaves() / 100).trailing_zeros() / 2));
            let v = t.at(Point::new(3.3, 7.1));
            assert!(
                (v - 0.04).abs() < 1e-12,
                "the value is still the field's: {v}"
            );
        }
        let asked = std::cell::RefCell::new(Vec::new());
        let r = Tree::build(
            bounds,
            0.04,
            1.0,
            0.5,
            &[],
            &mut fine,
            usize::MAX,
            &|bytes| {
                asked.borrow_mut().push(bytes);
                if bytes > 1 << 20 { Err(()) } else { Ok(()) }
            },
        );
        assert!(r.is_err(), "refused before the level past 1 MB");
        let asked = asked.into_inner();
        let last = *asked.last().unwrap();
        assert!(
            last > 1 << 20 && last <= (100 << 8) * BYTES_PER_CELL,
            "{asked:?}"
        );
    }

    #[test]
    fn an_error_of_the_point_field_stops_the_build() {
        let bounds = Rect::new(0.0, 0.0, 1.0, 1.0);
        let mut fail = |_: &[Point]| -> Result<Vec<f64>, &'static str> { Err("no") };
        let r = Tree::build(bounds, 0.01, 0.1, 0.5, &[], &mut fail, usize::MAX, &|_| {
            Ok(())
        });
        assert_eq!(r.err(), Some("no"));
    }
}
