//! A uniform grid over a large outline's pieces, with the exact winding number of one
//! anchor point per cell, so that a query looks only at the pieces of its own cell.
//!
//! # Method
//! The winding number of `p` equals that of the cell's anchor `a` plus the signed
//! crossings of the outline with an L-shaped path from `p` to `a` inside the cell:
//! horizontally from `p` to `c = (a.x, p.y)`, then vertically from `c` to `a`. Each leg
//! is counted as the difference of two half-open ray casts (the [`Acc`] of the module
//! above): `+x` rays from `p` and from `c`, and `+y` rays from `c` and from `a` (cast as
//! `+x` rays in the frame turned by −90°, `(x, y) ↦ (y, −x)`, exact in floating point).
//! A piece that does not meet a leg adds the same to both of its rays, so only the pieces
//! registered in the cell are looked at. Every piece is registered in each cell it
//! might meet, grown by the query margin (a curve by its control box; a segment row by
//! row of cells): a point in a cell is then clear of every piece not registered there,
//! and such a piece's chord and curve add the same to both rays.
//!
//! Each leg's difference is exact when its two ray origins are clear (no ray origin on a
//! straight piece nor within the margin of a curve: see [`Winding::Clear`]), because a
//! clear point's ray count is its true winding number. When one is not, the index gives
//! no answer and the caller casts the full ray, so every answer is the one the full ray
//! cast gives ([`Winding::Near`] answers always come from it).
//!
//! The anchors are chained the same way: along each row from the cell before, the first
//! cell of a row from the first cell of the row below (the L-path then stays in the two
//! cells), a cell whose chain fails from the full ray cast. Building costs a few passes
//! over the registrations, and a query a few passes over its cell's pieces: linear in
//! the outline for a grid whose cells each hold few pieces, where the full ray cast
//! looks at every piece in a horizontal band (all of them, for a dense zigzag of tall
//! pieces or a diagonal hatch).

#[cfg(test)]
use super::CELLS_MIN_PIECES;
use super::{Acc, Outline, Piece, Winding};
use kurbo::{CubicBez, Point, Rect};

/// Registrations allowed per piece (plus a constant) before the cells are made larger.
const MAX_REGISTRATIONS_PER_PIECE: usize = 48;
/// Registrations allowed in any case.
const MIN_REGISTRATIONS: usize = 1 << 16;
/// Cells per piece at most (the grid never has more cells than this times the pieces).
const MAX_CELLS_PER_PIECE: f64 = 4.0;
/// Anchor candidates in a cell, as fractions of its width and height, tried in order.
const ANCHORS: [(f64, f64); 5] = [
    (0.5, 0.5),
    (0.371, 0.613),
    (0.613, 0.371),
    (0.229, 0.287),
    (0.787, 0.713),
];

/// The grid, its registrations and anchors (see the module doc).
#[derive(Clone, Debug)]
pub(super) struct Cells {
    /// The margin the pieces were registered with (queries with a larger one are not
    /// answered).
    margin: f64,
    x0: f64,
    y0: f64,
    /// Cell side.
    s: f64,
    nx: usize,
    ny: usize,
    /// Cell `k`'s pieces are `items[start[k]..start[k + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
    /// By cell: a clear point and its winding number, if one was found.
    anchors: Vec<Option<(Point, i32)>>,
}

/// `q` in the frame turned by −90°, where a `+y` ray is a `+x` ray.
fn turn(q: Point) -> Point {
    Point::new(q.y, -q.x)
}

impl Piece {
    fn turned(&self) -> Piece {
        match *self {
            Piece::Line(a, b) => Piece::Line(turn(a), turn(b)),
            Piece::Cubic(c) => Piece::Cubic(CubicBez::new(
                turn(c.p0),
                turn(c.p1),
                turn(c.p2),
                turn(c.p3),
            )),
            Piece::Conic(mut c) => {
                c.p0 = turn(c.p0);
                c.p1 = turn(c.p1);
                c.p2 = turn(c.p2);
                Piece::Conic(c)
            }
        }
    }
}

/// Ray counts from `p` over `pieces`: towards `+x`, or towards `+y` when `up`.
fn count(outline: &Outline, pieces: &[u32], p: Point, up: bool, eps_abs: f64) -> Acc {
    let margin = eps_abs * 0.25;
    let mut acc = Acc::default();
    let p = if up { turn(p) } else { p };
    for &i in pieces {
        let piece = outline.pieces[i as usize];
        let piece = if up { piece.turned() } else { piece };
        match piece {
            Piece::Line(a, b) => acc.line(a, b, p),
            Piece::Cubic(c) => acc.curve(c, p, eps_abs, margin),
            Piece::Conic(c) => acc.curve(c, p, eps_abs, margin),
        }
    }
    acc
}

/// The winding number of `to` from that of `from` (`w_from`), over the L-path
/// `to → (from.x, to.y) → from`, which must lie in the cells whose pieces are `pieces`
/// (each once); `None` if a ray origin is not clear.
fn transfer(
    outline: &Outline,
    pieces: &[u32],
    from: Point,
    w_from: i32,
    to: Point,
    eps_abs: f64,
) -> Option<i32> {
    let c = Point::new(from.x, to.y);
    let h_to = count(outline, pieces, to, false, eps_abs);
    if h_to.near {
        return None;
    }
    let h_c = count(outline, pieces, c, false, eps_abs);
    let v_c = count(outline, pieces, c, true, eps_abs);
    let v_from = count(outline, pieces, from, true, eps_abs);
    if h_c.near || v_c.near || v_from.near {
        return None;
    }
    Some(w_from + (h_to.w - h_c.w) + (v_c.w - v_from.w))
}

impl Cells {
    /// The index of `outline` for queries with `eps_abs` up to the given one; `None`
    /// for an empty or degenerate outline.
    pub(super) fn build(outline: &Outline, eps_abs: f64) -> Option<Cells> {
        let bb = outline.bbox?;
        let n = outline.pieces.len();
        let margin = eps_abs * 0.25;
        if n == 0 || margin.is_nan() || margin < 0.0 || !margin.is_finite() {
            return None;
        }
        let size = bb.width().max(bb.height());
        let grow = 2.0 * margin + 1e-9 * size;
        let bb = bb.inflate(grow, grow);
        let (w, h) = (bb.width(), bb.height());
        if !(w > 0.0 && h > 0.0 && w.is_finite() && h.is_finite()) {
            return None;
        }
        let mut s = (w * h / n as f64).sqrt();
        let max_cells = MAX_CELLS_PER_PIECE * n as f64 + 64.0;
        // Not more cells than allowed along either side or in all.
        s = s.max(w / 65536.0).max(h / 65536.0);
        while (w / s).ceil() * (h / s).ceil() > max_cells {
            s *= 1.25;
        }
        let boxes: Vec<Rect> = outline.pieces.iter().map(Piece::bbox).collect();
        let budget = MAX_REGISTRATIONS_PER_PIECE * n + MIN_REGISTRATIONS;
        loop {
            let estimate: f64 = outline
                .pieces
                .iter()
                .zip(&boxes)
                .map(|(p, b)| match p {
                    Piece::Line(..) => (b.width() + b.height()) / s + 3.0,
                    _ => (b.width() / s + 2.0) * (b.height() / s + 2.0),
                })
                .sum();
            if estimate <= budget as f64 {
                break;
            }
            s *= 1.25;
        }
        let nx = ((w / s).ceil() as usize).max(1);
        let ny = ((h / s).ceil() as usize).max(1);
        let mut cells = Cells {
            margin,
            x0: bb.x0,
            y0: bb.y0,
            s,
            nx,
            ny,
            start: Vec::new(),
            items: Vec::new(),
            anchors: Vec::new(),
        };
        // Count, then fill (compressed rows).
        let mut counts = vec![0u32; nx * ny + 1];
        for (piece, b) in outline.pieces.iter().zip(&boxes) {
            cells.register(piece, b, &mut |k| counts[k] += 1);
        }
        let mut start = Vec::with_capacity(nx * ny + 1);
        let mut total = 0u32;
        for c in &counts[..nx * ny] {
            start.push(total);
            total = total
                .checked_add(*c)
                .expect("internal: registrations fit u32");
        }
        start.push(total);
        let mut items = vec![0u32; total as usize];
        let mut fill = start.clone();
        for (i, (piece, b)) in outline.pieces.iter().zip(&boxes).enumerate() {
            cells.register(piece, b, &mut |k| {
                items[fill[k] as usize] = i as u32;
                fill[k] += 1;
            });
        }
        cells.start = start;
        cells.items = items;
        cells.anchors = cells.anchor_all(outline, eps_abs);
        Some(cells)
    }

    fn col(&self, x: f64) -> usize {
        (((x - self.x0) / self.s).floor().max(0.0) as usize).min(self.nx - 1)
    }

    fn row(&self, y: f64) -> usize {
        (((y - self.y0) / self.s).floor().max(0.0) as usize).min(self.ny - 1)
    }

    fn pieces(&self, k: usize) -> &[u32] {
        &self.items[self.start[k] as usize..self.start[k + 1] as usize]
    }

    /// Calls `f` with every cell `piece` (whose box is `b`) might come within the
    /// margin of (and a little more, for the rounding of cell coordinates).
    fn register(&self, piece: &Piece, b: &Rect, f: &mut impl FnMut(usize)) {
        let r = self.margin + 1e-7 * self.s + 1e-12 * (b.x1.abs().max(b.x0.abs()));
        let ry = self.margin + 1e-7 * self.s + 1e-12 * (b.y1.abs().max(b.y0.abs()));
        let (j0, j1) = (self.row(b.y0 - ry), self.row(b.y1 + ry));
        match *piece {
            Piece::Line(a, z) if a.y != z.y => {
                let (lo, hi) = if a.y < z.y { (a, z) } else { (z, a) };
                let slope = (hi.x - lo.x) / (hi.y - lo.y);
                let slack = 1e-9 * ((hi.x - lo.x).abs() + self.s);
                for j in j0..=j1 {
                    let ya = (self.y0 + j as f64 * self.s - ry).max(lo.y);
                    let yb = (self.y0 + (j + 1) as f64 * self.s + ry).min(hi.y);
                    let (xa, xb) = if ya > yb {
                        // The row misses the segment's span but for the margin: its nearer end.
                        let e = if ya > hi.y { hi.x } else { lo.x };
                        (e, e)
                    } else {
                        let xa = lo.x + (ya - lo.y) * slope;
                        let xb = lo.x + (yb - lo.y) * slope;
                        (xa.min(xb), xa.max(xb))
                    };
                    let xa = xa.max(b.x0) - r - slack;
                    let xb = xb.min(b.x1) + r + slack;
                    for i in self.col(xa)..=self.col(xb) {
                        f(j * self.nx + i);
                    }
                }
            }
            _ => {
                let (i0, i1) = (self.col(b.x0 - r), self.col(b.x1 + r));
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        f(j * self.nx + i);
                    }
                }
            }
        }
    }

    /// A candidate anchor of cell `(i, j)`.
    fn candidate(&self, i: usize, j: usize, c: (f64, f64)) -> Point {
        Point::new(
            self.x0 + (i as f64 + c.0) * self.s,
            self.y0 + (j as f64 + c.1) * self.s,
        )
    }

    /// Every cell's anchor, chained along rows (see the module doc).
    fn anchor_all(&self, outline: &Outline, eps_abs: f64) -> Vec<Option<(Point, i32)>> {
        let mut anchors: Vec<Option<(Point, i32)>> = vec![None; self.nx * self.ny];
        let mut union: Vec<u32> = Vec::new();
        for j in 0..self.ny {
            for i in 0..self.nx {
                let k = j * self.nx + i;
                let pred = if i > 0 {
                    Some(k - 1)
                } else if j > 0 {
                    Some(k - self.nx)
                } else {
                    None
                };
                let pred = pred.and_then(|q| anchors[q].map(|a| (q, a)));
                if let Some((q, _)) = pred {
                    union.clear();
                    union.extend_from_slice(self.pieces(q));
                    union.extend_from_slice(self.pieces(k));
                    union.sort_unstable();
                    union.dedup();
                }
                for c in ANCHORS {
                    let a = self.candidate(i, j, c);
                    let w = match pred {
                        Some((_, (from, w_from))) => {
                            transfer(outline, &union, from, w_from, a, eps_abs)
                        }
                        None => match outline.winding_banded(a, eps_abs) {
                            Winding::Clear(w) => Some(w),
                            Winding::Near(_) => None,
                        },
                    };
                    // The anchor must also be clear for the queries' vertical rays.
                    if let Some(w) = w
                        && !count(outline, self.pieces(k), a, true, eps_abs).near
                    {
                        anchors[k] = Some((a, w));
                        break;
                    }
                }
                if anchors[k].is_none() && pred.is_some() {
                    // The chain failed here: start it again from the full ray cast.
                    for c in ANCHORS {
                        let a = self.candidate(i, j, c);
                        if let Winding::Clear(w) = outline.winding_banded(a, eps_abs)
                            && !count(outline, self.pieces(k), a, true, eps_abs).near
                        {
                            anchors[k] = Some((a, w));
                            break;
                        }
                    }
                }
            }
        }
        anchors
    }

    /// The winding number of `p` (within the outline's box grown by the margin), if its
    /// cell can tell it: `None` when `eps_abs` is larger than the index was built for,
    /// the cell has no anchor, or a ray origin on the way is not clear.
    pub(super) fn winding(&self, outline: &Outline, p: Point, eps_abs: f64) -> Option<Winding> {
        if eps_abs * 0.25 > self.margin {
            return None;
        }
        let k = self.row(p.y) * self.nx + self.col(p.x);
        let (a, w_a) = self.anchors[k]?;
        transfer(outline, self.pieces(k), a, w_a, p, eps_abs).map(Winding::Clear)
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{circle, conic_circle};
    use super::*;
    use crate::svg::{Segment, Subpath};
    use kurbo::Line;
    use proptest::prelude::*;

    fn polygon(points: &[Point]) -> Subpath {
        let mut pts = points.to_vec();
        pts.push(points[0]);
        Subpath {
            segments: pts
                .windows(2)
                .map(|w| Segment::Line(Line::new(w[0], w[1])))
                .collect(),
            start: points[0],
            closed: true,
        }
    }

    /// Every answer of the cells is clear and the full ray cast's; returns how many
    /// of `queries` the cells answered, and how many lie near the outline's box.
    fn agree(outline: &Outline, queries: &[Point], eps: f64) -> (usize, usize) {
        let cells = Cells::build(outline, eps).expect("an index");
        let (mut answered, mut asked) = (0, 0);
        for &p in queries {
            if !outline.is_near_box(p, eps * 0.25) {
                continue;
            }
            asked += 1;
            if let Some(w) = cells.winding(outline, p, eps) {
                assert_eq!(w, outline.winding_banded(p, eps), "at {p:?}");
                answered += 1;
            }
        }
        (answered, asked)
    }

    /// The stroke outline of a dense zigzag (the case this index is for): tall thin
    /// pieces side by side, every horizontal band holding all of them.
    #[test]
    fn dense_zigzag_matches_the_full_ray_cast() {
        let n = 600;
        let left: Vec<Point> = (0..n)
            .map(|i| Point::new(i as f64 * 0.01, if i % 2 == 0 { 0.0 } else { 1.0 }))
            .collect();
        let mut pts = left.clone();
        pts.extend(left.iter().rev().map(|p| Point::new(p.x + 0.3, p.y + 0.1)));
        let outline = Outline::new(&[polygon(&pts)]);
        let queries: Vec<Point> = (0..2000)
            .map(|k| {
                let k = k as f64;
                Point::new(
                    (k * 0.618_034).fract() * 4.4 - 0.1,
                    (k * 0.414_214).fract() * 1.4 - 0.2,
                )
            })
            .collect();
        let (answered, asked) = agree(&outline, &queries, 1e-9);
        assert!(asked > 1000 && answered == asked, "{answered} of {asked}");
        // Through the entry point (which builds the cells itself at the first query).
        assert!(outline.pieces.len() >= CELLS_MIN_PIECES);
        for &p in &queries {
            assert_eq!(outline.winding(p, 1e-9), outline.winding_banded(p, 1e-9));
        }
        assert!(outline.cells.get().is_some_and(Option::is_some));
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 128,
            failure_persistence: None,
            rng_seed: proptest::test_runner::RngSeed::Fixed(11),
            ..ProptestConfig::default()
        })]

        /// Integer polygons (queries on their vertices, edges and the rays through
        /// them): the cells answer exactly as the full ray cast, and most of the time.
        #[test]
        fn polygons_match_the_full_ray_cast(
            verts in proptest::collection::vec((-12i32..12, -12i32..12), 3..60),
            queries in proptest::collection::vec((-26i32..26, -26i32..26), 60),
            scale_exp in -20i32..20,
        ) {
            let s = 2f64.powi(scale_exp);
            let pts: Vec<Point> = verts.iter().map(|&(x, y)| Point::new(x as f64 * s, y as f64 * s)).collect();
            let outline = Outline::new(&[polygon(&pts)]);
            let qs: Vec<Point> = queries.iter().map(|&(x, y)| Point::new(x as f64 * 0.5 * s, y as f64 * 0.5 * s)).collect();
            agree(&outline, &qs, 1e-9 * s);
        }

        /// Curved outlines (cubic and conic circles, overlapping) with a coarse
        /// tolerance: answers agree (near points, and clear ones whose path to the
        /// anchor passes near a curve, are left to the full ray cast).
        #[test]
        fn curves_match_the_full_ray_cast(
            discs in proptest::collection::vec((-10.0f64..10.0, -10.0f64..10.0, 0.1f64..5.0, any::<bool>()), 1..12),
            queries in proptest::collection::vec((-16.0f64..16.0, -16.0f64..16.0), 80),
            eps in prop_oneof![Just(1e-9), Just(1e-3), Just(0.2)],
        ) {
            let subpaths: Vec<Subpath> = discs.iter().map(|&(x, y, r, exact)| {
                if exact { conic_circle(Point::new(x, y), r) } else { circle(Point::new(x, y), r) }
            }).collect();
            let outline = Outline::new(&subpaths);
            let qs: Vec<Point> = queries.iter().map(|&(x, y)| Point::new(x, y)).collect();
            agree(&outline, &qs, eps);
        }
    }
}
