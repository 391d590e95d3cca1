//! The area each region has in the drawing, computed from the input curves and
//! the paint model alone (never from a mesh): what [`super::RegionStat::drawn_area`]
//! holds and the area check compares the mesh with.
//!
//! # Method
//! Every point of the plane has one owner: the topmost shape painting it, or
//! none ([`Painting::owner_at`]: fill rules, clips, strokes as areas). The owner
//! can change only across an outline: a shape's subpaths (closed as SVG fills
//! them) or the outline of one of its clips. So
//! 1. the outlines are gathered, each curve once (a curve drawn twice, in either
//!    direction, as where two shapes share an edge or a clip repeats a shape,
//!    bounds once), and cut where `x` or `y` turns, so each piece is monotone and
//!    lies in the box of its end points;
//! 2. each piece is cut where another piece crosses or touches it: collinear
//!    segments at each other's end points (their common parts then coincide
//!    exactly and count once), other pairs by subdividing both until their
//!    pieces are flat to [`FLAT_REL`]·d, the crossing then placed on each curve
//!    by bisection along its chord;
//! 3. between two cuts the owner on either side is constant: it is sampled once,
//!    a short step either side of the middle of the piece (a step certified
//!    clear of every outline by [`Painting::owner_at`], halved until it is);
//! 4. by Green's theorem the area of the set a shape owns is the sum of
//!    `½∫(x dy − y dx)` over the pieces with that shape on their left, less the
//!    same over those with it on their right. A line and a conic piece give
//!    that integral in closed form, a cubic too (kurbo's `signed_area`), so the
//!    areas are exact up to rounding and to where the crossings are placed
//!    (within [`FLAT_REL`]·d along each curve).
//!
//! The coordinates are taken relative to the middle of the drawing's box, so a
//! drawing far from the origin loses no digits to cancellation.
//!
//! # What is not exact
//! Two different curves that overlap along a stretch (a cubic drawn again as
//! two halves, say) would count that stretch twice: a pair of curves that
//! stays within [`FLAT_REL`]·d of each other over more than [`MAX_LEAVES`]
//! flat pieces is counted in [`DrawnAreas::overlaps`], and the areas are then
//! not trusted. A piece whose sides no certified step can sample (shorter than
//! rounding) adds its `|∫|` to [`DrawnAreas::unsure`], a bound on the error.

use crate::budget::Deadline;
use crate::svg::drawing::{Clip, Conic, collect_clips};
use crate::svg::winding::Painting;
use crate::svg::{Drawing, Segment, ShapeId, Subpath};
use kurbo::{CubicBez, ParamCurve, ParamCurveArea, ParamCurveDeriv, Point, Rect, Vec2};
use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};
use std::sync::Arc;

/// Flatness (relative to d) at which two subdivided pieces are taken as their
/// chords to find where they cross: the crossing is then within this distance
/// of the true one along each curve, an area error of about `FLAT_REL·d²` per
/// crossing, far below the check's floor of 1e-9·d².
const FLAT_REL: f64 = 1e-12;
/// Distance (relative to d) within which two pieces are taken to run
/// together: each is cut where the other ends, and where they run together
/// their terms share one count. The area between two curves this close, at
/// most `TOGETHER_REL·d` times their length, goes to either side.
const TOGETHER_REL: f64 = 2e-12;
/// The side step (relative to d) at which the owner beside a piece is sampled,
/// before it is shortened to a fraction of a short piece or to a quarter of
/// the distance to the nearest other outline (never below 2·[`TOGETHER_REL`]·d).
const STEP_REL: f64 = 1e-9;
/// Flat piece pairs within [`FLAT_REL`]·d of each other above which two curves
/// are taken to overlap along a stretch rather than to cross or touch.
const MAX_LEAVES: usize = 4096;
/// Subdivision depth at which a pair is given up on (2⁻⁶⁰ of a piece).
const MAX_DEPTH: u32 = 60;
/// Subdivision steps over all pairs, per piece, past which the drawn areas
/// are not computed (outlines so dense and so close that finding where they
/// cross would cost more than meshing them): the check then reports none
/// rather than slow the run.
const STEPS_PER_PIECE: usize = 400;

/// The areas the drawing's owners have, before any mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct DrawnAreas {
    /// For each shape (by index) the area of the set it owns; shapes that own
    /// nothing (strokes joined to their fill, hidden or empty shapes) have 0.
    pub by_shape: Vec<f64>,
    /// The area no shape paints inside `bounds`.
    pub background: f64,
    /// Pairs of different curves found to overlap along a stretch: the areas
    /// of the owners on either side are then not exact.
    pub overlaps: usize,
    /// Σ `|½∫(x dy − y dx)|` over the pieces whose sides could not be sampled:
    /// a bound on what they could change in any area.
    pub unsure: f64,
}

/// One outline curve.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Curve {
    Line(Point, Point),
    Cubic(CubicBez),
    /// Positive, finite weight.
    Conic(Conic),
}

impl Curve {
    fn eval(&self, t: f64) -> Point {
        match *self {
            Curve::Line(_, b) if t == 1.0 => b,
            Curve::Line(a, b) => a.lerp(b, t),
            Curve::Cubic(c) if t == 0.0 => c.p0,
            Curve::Cubic(c) if t == 1.0 => c.p3,
            Curve::Cubic(c) => c.eval(t),
            Curve::Conic(c) => c.eval(t),
        }
    }

    fn deriv(&self, t: f64) -> Vec2 {
        match *self {
            Curve::Line(a, b) => b - a,
            Curve::Cubic(c) => c.deriv().eval(t).to_vec2(),
            Curve::Conic(c) => c.deriv(t),
        }
    }

    /// The control points of the piece on `[t0, t1]` (the piece lies in their
    /// convex hull) and how many there are.
    fn controls(&self, t0: f64, t1: f64) -> ([Point; 4], usize) {
        match *self {
            Curve::Line(..) => ([self.eval(t0), self.eval(t1), Point::ZERO, Point::ZERO], 2),
            Curve::Cubic(c) => {
                let s = c.subsegment(t0..t1);
                ([s.p0, s.p1, s.p2, s.p3], 4)
            }
            Curve::Conic(c) => {
                let s = c.subsegment(t0, t1);
                ([s.p0, s.p1, s.p2, Point::ZERO], 3)
            }
        }
    }

    /// `½∫(x dy − y dx)` over the piece on `[t0, t1]`, with `origin` as the origin.
    fn area_term(&self, t0: f64, t1: f64, origin: Vec2) -> f64 {
        match *self {
            Curve::Line(..) => {
                let (a, b) = (self.eval(t0) - origin, self.eval(t1) - origin);
                0.5 * a.to_vec2().cross(b.to_vec2())
            }
            Curve::Cubic(c) => {
                let s = c.subsegment(t0..t1);
                CubicBez::new(s.p0 - origin, s.p1 - origin, s.p2 - origin, s.p3 - origin)
                    .signed_area()
            }
            Curve::Conic(c) => {
                let s = c.subsegment(t0, t1);
                let s = Conic::new(s.p0 - origin, s.p1 - origin, s.p2 - origin, s.w);
                if s.w <= 1.0 {
                    s.signed_area()
                } else {
                    gauss_area(&s)
                }
            }
        }
    }

    /// The distance from `p` to the piece on `t` (to within `accuracy`).
    fn distance(&self, t: [f64; 2], p: Point, accuracy: f64) -> f64 {
        use kurbo::ParamCurveNearest;
        match *self {
            Curve::Line(..) => {
                let (a, b) = (self.eval(t[0]), self.eval(t[1]));
                let (_, _, dist) = closest_on_segments(a, b, p, p);
                dist
            }
            Curve::Cubic(c) => c
                .subsegment(t[0]..t[1])
                .nearest(p, accuracy)
                .distance_sq
                .sqrt(),
            Curve::Conic(c) => c
                .subsegment(t[0], t[1])
                .nearest(p, accuracy)
                .distance_sq
                .sqrt(),
        }
    }

    /// The same curve, oriented so that it starts at the lexicographically
    /// smaller end, and its key (the bits of its controls and weight).
    fn canonical(self) -> (Curve, Vec<u64>) {
        let less = |a: Point, b: Point| (a.x, a.y) < (b.x, b.y);
        let c = match self {
            Curve::Line(a, b) if less(b, a) => Curve::Line(b, a),
            Curve::Cubic(c) if less(c.p3, c.p0) => {
                Curve::Cubic(CubicBez::new(c.p3, c.p2, c.p1, c.p0))
            }
            Curve::Conic(c) if less(c.p2, c.p0) => Curve::Conic(c.reverse()),
            other => other,
        };
        let pts: Vec<f64> = match c {
            Curve::Line(a, b) => vec![0.0, a.x, a.y, b.x, b.y],
            Curve::Cubic(q) => vec![
                1.0, q.p0.x, q.p0.y, q.p1.x, q.p1.y, q.p2.x, q.p2.y, q.p3.x, q.p3.y,
            ],
            Curve::Conic(q) => vec![2.0, q.p0.x, q.p0.y, q.p1.x, q.p1.y, q.p2.x, q.p2.y, q.w],
        };
        // +0.0 and -0.0 are one coordinate
        (c, pts.into_iter().map(|v| (v + 0.0).to_bits()).collect())
    }

    /// Parameters in (0, 1) where `x` or `y` is stationary.
    fn turns(&self) -> Vec<f64> {
        let mut ts = Vec::new();
        match *self {
            Curve::Line(..) => {}
            Curve::Cubic(c) => {
                for k in 0..2 {
                    let v = |p: Point| if k == 0 { p.x } else { p.y };
                    // derivative's Bernstein coefficients (quadratic), in power form
                    let (d0, d1, d2) = (v(c.p1) - v(c.p0), v(c.p2) - v(c.p1), v(c.p3) - v(c.p2));
                    ts.extend(kurbo::common::solve_quadratic(
                        d0,
                        2.0 * (d1 - d0),
                        d0 - 2.0 * d1 + d2,
                    ));
                }
            }
            Curve::Conic(c) => {
                // x = X/W with X, W quadratic: x' ∝ (a1 b0 − a0 b1) + 2 (a2 b0 − a0 b2) t + (a2 b1 − a1 b2) t²
                let power = |c0: f64, c1: f64, c2: f64| [c0, 2.0 * (c1 - c0), c0 - 2.0 * c1 + c2];
                let b = power(1.0, c.w, 1.0);
                for k in 0..2 {
                    let v = |p: Point| if k == 0 { p.x } else { p.y };
                    let a = power(v(c.p0), c.w * v(c.p1), v(c.p2));
                    ts.extend(kurbo::common::solve_quadratic(
                        a[1] * b[0] - a[0] * b[1],
                        2.0 * (a[2] * b[0] - a[0] * b[2]),
                        a[2] * b[1] - a[1] * b[2],
                    ));
                }
            }
        }
        ts.retain(|t| *t > 0.0 && *t < 1.0);
        ts.sort_by(f64::total_cmp);
        ts.dedup();
        ts
    }
}

/// `½∫(x dy − y dx)` over a conic of any positive weight, by Gauss–Legendre
/// quadrature on its halves' halves (for the rare weight above 1, a hyperbolic
/// arc, which the closed form does not cover).
fn gauss_area(c: &Conic) -> f64 {
    const X: [f64; 5] = [
        0.0,
        0.538_469_310_105_683_1,
        -0.538_469_310_105_683_1,
        0.906_179_845_938_664,
        -0.906_179_845_938_664,
    ];
    const W: [f64; 5] = [
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_5,
        0.478_628_670_499_366_5,
        0.236_926_885_056_189_1,
        0.236_926_885_056_189_1,
    ];
    let n = 16;
    let mut sum = 0.0;
    for k in 0..n {
        let (a, b) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
        for (x, w) in X.iter().zip(W) {
            let t = 0.5 * (a + b) + 0.5 * (b - a) * x;
            let p = c.eval(t).to_vec2();
            let d = c.deriv(t);
            sum += w * 0.5 * (b - a) * 0.5 * p.cross(d);
        }
    }
    sum
}

/// The owners left and right of a piece and how many pieces run there
/// together (see [`sides`]).
type Sides = (Option<ShapeId>, Option<ShapeId>, usize);

/// A monotone piece of a curve: parameters `t` of `curve`.
#[derive(Clone, Copy, Debug)]
struct Piece {
    curve: u32,
    t: [f64; 2],
    bbox: Rect,
}

/// Compute the drawn areas of `drawing`'s owners inside `bounds` (the meshed
/// box), `d` its diagonal. `None` once `deadline` has passed.
pub(crate) fn drawn_areas(
    drawing: &Drawing,
    painting: &Painting,
    bounds: Rect,
    d: f64,
    deadline: &Deadline,
) -> Option<DrawnAreas> {
    let curves = outline_curves(drawing);
    let pieces = monotone_pieces(&curves);
    let tol = FLAT_REL * d;
    let grid = BoxGrid::new(
        pieces
            .iter()
            .map(|p| p.bbox.inflate(TOGETHER_REL * d, TOGETHER_REL * d))
            .collect(),
    );
    let together = TOGETHER_REL * d;
    let (cuts, overlaps) = crossings(&curves, &pieces, &grid, tol, together, deadline)?;
    let near = Near {
        curves: &curves,
        pieces: &pieces,
        grid: &grid,
        tol,
        together,
    };
    let origin = bounds.center().to_vec2();
    let step = STEP_REL * d;
    // Each piece's windows between cuts, with their area terms.
    let windows: Vec<Window> = pieces
        .iter()
        .zip(&cuts)
        .enumerate()
        .flat_map(|(k, (piece, cut))| {
            let mut ts = Vec::with_capacity(cut.len() + 2);
            ts.push(piece.t[0]);
            ts.extend(
                cut.iter()
                    .copied()
                    .filter(|t| *t > piece.t[0] && *t < piece.t[1]),
            );
            ts.push(piece.t[1]);
            ts.sort_by(f64::total_cmp);
            ts.dedup();
            let windows: Vec<Window> = ts
                .windows(2)
                .map(|w| Window {
                    piece: k,
                    t: [w[0], w[1]],
                })
                .collect();
            windows
        })
        .collect();
    let terms: Vec<f64> = windows
        .par_iter()
        .map(|w| curves[pieces[w.piece].curve as usize].area_term(w.t[0], w.t[1], origin))
        .collect();
    // The owners either side, sampled once per chain of windows joined end to
    // end where nothing else comes near (see [`chains`]).
    let chains = chains(&near, &windows);
    let sampled: Vec<Vec<(usize, Option<Sides>)>> = chains
        .par_iter()
        .enumerate()
        .map(|(c, chain)| {
            if c % 64 == 0 && deadline.expired() {
                return Vec::new();
            }
            // the longest window first: it allows the longest step
            let mut order: Vec<usize> = (0..chain.len()).collect();
            let chord = |i: usize| {
                let w = &windows[chain[i].0];
                let curve = &curves[pieces[w.piece].curve as usize];
                (curve.eval(w.t[1]) - curve.eval(w.t[0])).hypot()
            };
            order.sort_by(|a, b| chord(*b).total_cmp(&chord(*a)));
            let found = order.iter().find_map(|&i| {
                let w = &windows[chain[i].0];
                sides(&near, w.piece, w.t[0], w.t[1], painting, step)
                    .map(|s| if chain[i].1 { (s.1, s.0, s.2) } else { s })
            });
            chain
                .iter()
                .map(|&(w, flipped)| {
                    let s = found.map(|s| if flipped { (s.1, s.0, s.2) } else { s });
                    (w, s)
                })
                .collect()
        })
        .collect();
    if deadline.expired() {
        return None;
    }
    let mut window_sides: Vec<Option<Sides>> = vec![None; windows.len()];
    for (w, s) in sampled.into_iter().flatten() {
        window_sides[w] = s;
    }
    let terms = terms.into_iter().zip(window_sides);
    let mut by_shape = vec![Sum::default(); drawing.shapes.len()];
    let mut background = Sum::default();
    let mut unsure = 0.0;
    for (term, sides) in terms {
        match sides {
            Some((left, right, together)) if left != right => {
                let mut add = |owner: Option<ShapeId>, v: f64| match owner {
                    Some(s) => by_shape[s.index()].add(v),
                    None => background.add(v),
                };
                let term = term / together as f64;
                add(left, term);
                add(right, -term);
            }
            Some(_) => {}
            None => unsure += term.abs(),
        }
    }
    Some(DrawnAreas {
        by_shape: by_shape.iter().map(Sum::value).collect(),
        background: bounds.area() + background.value(),
        overlaps,
        unsure,
    })
}

/// A stretch of a piece between two cuts: parameters `t` of the piece's curve.
#[derive(Clone, Copy, Debug)]
struct Window {
    piece: usize,
    t: [f64; 2],
}

/// The windows in chains: each chain is a list of windows (and whether each
/// runs against the chain's direction) joined end to end at points where
/// exactly two window ends meet, bit for bit, no other piece comes within
/// twice the run-together distance, and neither window runs together with the
/// other's piece at its middle (as where a subpath goes out and back along
/// itself). Along such a chain no outline is crossed or touched (the windows
/// end at every crossing and touch, and where pieces stop running together),
/// and no window shares its stretch with another, so the owner either side is
/// one: it is sampled once per chain.
fn chains(near: &Near<'_>, windows: &[Window]) -> Vec<Vec<(usize, bool)>> {
    /// A window and whether this is its end (or its start).
    type End = (usize, bool);
    let key = |p: Point| (p.x.to_bits(), p.y.to_bits());
    // (window, at its end) for every window end that is an end of its piece
    let mut ends: FxHashMap<(u64, u64), Vec<End>> = FxHashMap::default();
    for (i, w) in windows.iter().enumerate() {
        let piece = &near.pieces[w.piece];
        let curve = &near.curves[piece.curve as usize];
        if w.t[0] == piece.t[0] {
            ends.entry(key(curve.eval(w.t[0])))
                .or_default()
                .push((i, false));
        }
        if w.t[1] == piece.t[1] {
            ends.entry(key(curve.eval(w.t[1])))
                .or_default()
                .push((i, true));
        }
    }
    // union-find with the parity of each window's direction to its root's
    let mut parent: Vec<usize> = (0..windows.len()).collect();
    let mut flip = vec![false; windows.len()];
    fn find(parent: &mut [usize], flip: &mut [bool], i: usize) -> (usize, bool) {
        let mut path = Vec::new();
        let mut r = i;
        while parent[r] != r {
            path.push(r);
            r = parent[r];
        }
        // compress: each node on the path points at the root with its parity
        let mut acc = false;
        for &n in path.iter().rev() {
            acc ^= flip[n];
            flip[n] = acc;
            parent[n] = r;
        }
        (r, if i == r { false } else { flip[i] })
    }
    let joints: Vec<((u64, u64), [End; 2])> = ends
        .into_iter()
        .filter_map(|(k, v)| match v[..] {
            [a, b] if a.0 != b.0 => Some((k, [a, b])),
            _ => None,
        })
        .collect();
    let clean: Vec<bool> = joints
        .par_iter()
        .map(|(k, [a, b])| {
            let p = Point::new(f64::from_bits(k.0), f64::from_bits(k.1));
            let (wa, wb) = (&windows[a.0], &windows[b.0]);
            let r = 2.0 * near.together;
            // the two must not run together (a spike drawn out and back):
            // there the sides are sampled as one stretch, window by window
            let apart = |w: &Window, other: &Window| {
                let curve = &near.curves[near.pieces[w.piece].curve as usize];
                let m = curve.eval(0.5 * (w.t[0] + w.t[1]));
                let o = &near.pieces[other.piece];
                near.curves[o.curve as usize].distance(o.t, m, near.tol) > r
            };
            near.clear_of(p, [wa.piece, wb.piece], r) && apart(wa, wb) && apart(wb, wa)
        })
        .collect();
    for ((_, [a, b]), clean) in joints.iter().zip(clean) {
        if !clean {
            continue;
        }
        let (ra, fa) = find(&mut parent, &mut flip, a.0);
        let (rb, fb) = find(&mut parent, &mut flip, b.0);
        if ra == rb {
            continue;
        }
        // an end meeting a start keeps the direction; two ends or two starts flip it
        let opposed = a.1 == b.1;
        parent[rb] = ra;
        flip[rb] = fa ^ fb ^ opposed;
    }
    let mut index: FxHashMap<usize, usize> = FxHashMap::default();
    let mut out: Vec<Vec<(usize, bool)>> = Vec::new();
    for i in 0..windows.len() {
        let (r, f) = find(&mut parent, &mut flip, i);
        let c = *index.entry(r).or_insert_with(|| {
            out.push(Vec::new());
            out.len() - 1
        });
        out[c].push((i, f));
    }
    out
}

/// Neumaier's compensated sum.
#[derive(Clone, Copy, Debug, Default)]
struct Sum {
    s: f64,
    c: f64,
}

impl Sum {
    fn add(&mut self, v: f64) {
        let t = self.s + v;
        if self.s.abs() >= v.abs() {
            self.c += (self.s - t) + v;
        } else {
            self.c += (v - t) + self.s;
        }
        self.s = t;
    }
    fn value(&self) -> f64 {
        self.s + self.c
    }
}

/// The pieces, for the distance from a point to the nearest other piece.
struct Near<'a> {
    curves: &'a [Curve],
    pieces: &'a [Piece],
    grid: &'a BoxGrid,
    tol: f64,
    together: f64,
}

impl Near<'_> {
    /// Whether no piece but the two `skip` comes within `r` of `p`.
    fn clear_of(&self, p: Point, skip: [usize; 2], r: f64) -> bool {
        let probe = Rect::new(p.x - r, p.y - r, p.x + r, p.y + r);
        let (x0, y0, x1, y1) = self.grid.range(&probe);
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &j in &self.grid.cells[y * self.grid.cols + x] {
                    let j = j as usize;
                    if skip.contains(&j) || !self.grid.boxes[j].inflate(r, r).contains(p) {
                        continue;
                    }
                    let piece = &self.pieces[j];
                    if self.curves[piece.curve as usize].distance(piece.t, p, self.tol) <= r {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// Around `p`: how many pieces other than `own` pass within `tau` of it
    /// (coincident with `own` there), the distance to the nearest of the
    /// others, or `r` if none is nearer, and to the nearest coincident one.
    fn around(&self, p: Point, own: usize, r: f64, tau: f64) -> (usize, f64, f64) {
        let mut best = r;
        let mut coincident = 0;
        let mut gap = f64::INFINITY;
        let probe = Rect::new(p.x - r, p.y - r, p.x + r, p.y + r);
        let (x0, y0, x1, y1) = self.grid.range(&probe);
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &j in &self.grid.cells[y * self.grid.cols + x] {
                    let j = j as usize;
                    if j == own || !self.grid.boxes[j].inflate(r, r).contains(p) {
                        continue;
                    }
                    // each piece once: in the first cell of the probe it meets
                    let (bx, by, _, _) = self.grid.range(&self.grid.boxes[j].intersect(probe));
                    if (bx, by) != (x, y) {
                        continue;
                    }
                    let piece = &self.pieces[j];
                    let dist = self.curves[piece.curve as usize].distance(piece.t, p, self.tol);
                    // a curve does not run together with itself: its other
                    // pieces only meet this one at an end
                    if dist <= tau && piece.curve != self.pieces[own].curve {
                        coincident += 1;
                        gap = gap.min(dist);
                    } else {
                        best = best.min(dist);
                    }
                }
            }
        }
        (coincident, best, gap)
    }
}

/// The owners left and right of piece `k` of `near` on `[t0, t1]`, sampled a
/// step either side of its middle, and how many pieces run there together
/// (itself and those within 2·tol of its middle: one stretch drawn by
/// several nearly equal curves, whose terms then share one count). The step
/// is shorter than the distance to any other piece, so it crosses no outline
/// but those running together; `None` when no step is certain.
fn sides(
    near: &Near<'_>,
    k: usize,
    t0: f64,
    t1: f64,
    painting: &Painting,
    step: f64,
) -> Option<Sides> {
    let curve = &near.curves[near.pieces[k].curve as usize];
    let (a, b) = (curve.eval(t0), curve.eval(t1));
    let chord = (b - a).hypot();
    if chord == 0.0 {
        // no length, no area
        return Some((None, None, 1));
    }
    let tm = 0.5 * (t0 + t1);
    let m = curve.eval(tm);
    let mut tangent = curve.deriv(tm);
    if tangent.hypot() <= 0.0 || tangent.hypot().is_nan() {
        tangent = b - a;
    }
    let normal = Vec2::new(-tangent.y, tangent.x) / tangent.hypot();
    let mut h = step.min(0.125 * chord);
    let tau = near.together;
    let (together, clear, gap) = near.around(m, k, 2.0 * h, tau);
    if clear < 2.0 * h {
        h = 0.25 * clear;
    }
    // The samples must differ from the middle in floating point.
    let resolution = 1e-14 * (m.x.abs() + m.y.abs() + tau / TOGETHER_REL);
    let sample = |mut h: f64, floor: f64, count: usize| {
        for _ in 0..8 {
            if h <= floor || h.is_nan() {
                break;
            }
            let (left, left_clear) = painting.owner_at(m + normal * h, 0.25 * h);
            let (right, right_clear) = painting.owner_at(m - normal * h, 0.25 * h);
            if left_clear && right_clear {
                return Some((left, right, count));
            }
            h *= 0.125;
        }
        None
    };
    // Pieces running together but apart in floating point (two curves that
    // meet at a tangent, or part after a hairpin) are sampled between them,
    // each on its own: the stretches two such pieces share as one are not
    // quite the same where they part, and counting them once would leave
    // the difference to no owner.
    if together > 0
        && let Some(s) = sample(h.min(0.25 * gap), resolution, 1)
    {
        return Some(s);
    }
    // Otherwise the samples clear what runs together with the piece.
    let floor = if together > 0 { 2.0 * tau } else { resolution };
    sample(h, floor, together + 1)
}

/// Every outline that can separate two owners: the subpaths of the filled
/// shapes (closed as SVG fills them) and of their clips, each curve once.
fn outline_curves(drawing: &Drawing) -> Vec<Curve> {
    let mut seen: FxHashSet<Vec<u64>> = FxHashSet::default();
    let mut curves = Vec::new();
    let mut push = |c: Curve| {
        let degenerate = match c {
            Curve::Line(a, b) => a == b,
            Curve::Cubic(q) => q.p0 == q.p1 && q.p1 == q.p2 && q.p2 == q.p3,
            Curve::Conic(q) => q.p0 == q.p1 && q.p1 == q.p2,
        };
        if degenerate {
            return;
        }
        let (c, key) = c.canonical();
        if seen.insert(key) {
            curves.push(c);
        }
    };
    let add_subpaths = |subpaths: &[Subpath], push: &mut dyn FnMut(Curve)| {
        for sp in subpaths {
            let Some(last) = sp.segments.last() else {
                continue;
            };
            let mut cursor = sp.start;
            for seg in &sp.segments {
                if seg.start() != cursor {
                    push(Curve::Line(cursor, seg.start()));
                }
                push(match *seg {
                    Segment::Line(l) => Curve::Line(l.p0, l.p1),
                    Segment::Cubic(c) => Curve::Cubic(c),
                    Segment::Conic(c) if c.w > 0.0 && c.w.is_finite() => Curve::Conic(c),
                    Segment::Conic(c) => Curve::Line(c.p0, c.p2),
                });
                cursor = seg.end();
            }
            if last.end() != sp.start {
                push(Curve::Line(last.end(), sp.start));
            }
        }
    };
    let mut clips: Vec<Arc<Clip>> = Vec::new();
    for s in drawing.shapes.iter().filter(|s| s.filled) {
        add_subpaths(&s.subpaths, &mut push);
        for c in &s.paint.clips {
            collect_clips(c, &mut clips);
        }
    }
    for c in &clips {
        for part in &c.parts {
            add_subpaths(&part.subpaths, &mut push);
        }
    }
    merge_collinear(curves)
}

/// The curves with every set of collinear, overlapping segments replaced by
/// the pieces of their union between consecutive end points, each once (so a
/// stretch two shapes share counts once, whatever their end points).
fn merge_collinear(curves: Vec<Curve>) -> Vec<Curve> {
    use crate::exact::{Orientation, orient2d};
    let lines: Vec<usize> = (0..curves.len())
        .filter(|&i| matches!(curves[i], Curve::Line(..)))
        .collect();
    let ends = |i: usize| match curves[i] {
        Curve::Line(a, b) => (a, b),
        _ => unreachable!("internal: lines only"),
    };
    let grid = BoxGrid::new(
        lines
            .iter()
            .map(|&i| {
                let (a, b) = ends(i);
                Rect::from_points(a, b)
            })
            .collect(),
    );
    // Union-find over the lines: collinear with a common stretch.
    let mut parent: Vec<usize> = (0..lines.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut near = Vec::new();
    let mut any = false;
    for i in 0..lines.len() {
        grid.candidates(i, &mut near);
        let (a0, a1) = ends(lines[i]);
        for &j in &near {
            let (b0, b1) = ends(lines[j as usize]);
            if orient2d(a0, a1, b0) != Orientation::Collinear
                || orient2d(a0, a1, b1) != Orientation::Collinear
            {
                continue;
            }
            let d = a1 - a0;
            let (u0, u1) = ((b0 - a0).dot(d), (b1 - a0).dot(d));
            if u0.max(u1) <= 0.0 || u0.min(u1) >= d.hypot2() {
                continue; // one point in common at most
            }
            let (ri, rj) = (root(&mut parent, i), root(&mut parent, j as usize));
            if ri != rj {
                parent[ri] = rj;
                any = true;
            }
        }
    }
    if !any {
        return curves;
    }
    let mut groups: rustc_hash::FxHashMap<usize, Vec<usize>> = Default::default();
    for (i, &line) in lines.iter().enumerate() {
        let r = root(&mut parent, i);
        groups.entry(r).or_default().push(line);
    }
    let mut merged = vec![false; curves.len()];
    for g in groups.values().filter(|g| g.len() > 1) {
        for &i in g {
            merged[i] = true;
        }
    }
    let mut out: Vec<Curve> = curves
        .iter()
        .zip(&merged)
        .filter(|(_, m)| !**m)
        .map(|(c, _)| *c)
        .collect();
    let mut group_list: Vec<Vec<usize>> = groups.into_values().filter(|g| g.len() > 1).collect();
    group_list.sort();
    for group in group_list {
        let (o, e) = ends(group[0]);
        let dir = e - o;
        let at = |p: Point| (p - o).dot(dir);
        let mut points: Vec<Point> = group
            .iter()
            .flat_map(|&i| {
                let (a, b) = ends(i);
                [a, b]
            })
            .collect();
        points.sort_by(|p, q| {
            at(*p)
                .total_cmp(&at(*q))
                .then(p.x.total_cmp(&q.x))
                .then(p.y.total_cmp(&q.y))
        });
        points.dedup();
        let spans: Vec<(f64, f64)> = group
            .iter()
            .map(|&i| {
                let (a, b) = ends(i);
                (at(a).min(at(b)), at(a).max(at(b)))
            })
            .collect();
        for w in points.windows(2) {
            let mid = 0.5 * (at(w[0]) + at(w[1]));
            if spans.iter().any(|&(u0, u1)| u0 <= mid && mid <= u1) {
                out.push(Curve::Line(w[0], w[1]));
            }
        }
    }
    out
}

/// The curves cut where `x` or `y` turns.
fn monotone_pieces(curves: &[Curve]) -> Vec<Piece> {
    let mut pieces = Vec::new();
    for (i, c) in curves.iter().enumerate() {
        let mut ts = vec![0.0];
        ts.extend(c.turns());
        ts.push(1.0);
        for w in ts.windows(2) {
            let (a, b) = (c.eval(w[0]), c.eval(w[1]));
            pieces.push(Piece {
                curve: i as u32,
                t: [w[0], w[1]],
                // monotone: the end points' box holds the piece
                bbox: Rect::from_points(a, b),
            });
        }
    }
    pieces
}

/// For each piece, the parameters where another piece crosses or touches it,
/// and how many pairs overlap along a stretch. `None` once `deadline` passed.
fn crossings(
    curves: &[Curve],
    pieces: &[Piece],
    grid: &BoxGrid,
    tol: f64,
    together: f64,
    deadline: &Deadline,
) -> Option<(Vec<Vec<f64>>, usize)> {
    // Per piece i: the cuts it finds on itself and on later pieces j > i.
    let budget = STEPS_PER_PIECE * pieces.len() + 100_000;
    let spent = std::sync::atomic::AtomicUsize::new(0);
    // per piece: its cuts (piece, parameter), overlaps, steps, pairs
    type Found = (Vec<(u32, f64)>, usize, usize, usize);
    let found: Vec<Found> = (0..pieces.len())
        .into_par_iter()
        .map(|i| {
            if (i % 64 == 0 && deadline.expired())
                || spent.load(std::sync::atomic::Ordering::Relaxed) > budget
            {
                return (Vec::new(), 0, 0, 0);
            }
            let mut out = Vec::new();
            let mut overlaps = 0;
            let mut steps = 0;
            let mut near = Vec::new();
            grid.candidates(i, &mut near);
            for &j in &near {
                let (a, b) = (&pieces[i], &pieces[j as usize]);
                let (ca, cb) = (&curves[a.curve as usize], &curves[b.curve as usize]);
                let pair = cut_pair(ca, a.t, cb, b.t, tol, together, budget);
                overlaps += usize::from(pair.overlap);
                steps += pair.steps;
                out.extend(pair.on_a.into_iter().map(|t| (i as u32, t)));
                out.extend(pair.on_b.into_iter().map(|t| (j, t)));
            }
            let pairs = near.len();
            spent.fetch_add(steps, std::sync::atomic::Ordering::Relaxed);
            (out, overlaps, steps, pairs)
        })
        .collect();
    if deadline.expired() {
        return None;
    }
    if spent.load(std::sync::atomic::Ordering::Relaxed) > budget {
        tracing::debug!(
            pieces = pieces.len(),
            budget,
            "drawn areas: not computed, over budget"
        );
        return None;
    }
    let mut cuts = vec![Vec::new(); pieces.len()];
    let mut overlaps = 0;
    let (steps, pairs): (usize, usize) = found.iter().fold((0, 0), |a, f| (a.0 + f.2, a.1 + f.3));
    tracing::debug!(
        pieces = pieces.len(),
        pairs,
        steps,
        "drawn areas: crossings"
    );
    for (list, o, _, _) in found {
        overlaps += o;
        for (k, t) in list {
            cuts[k as usize].push(t);
        }
    }
    Some((cuts, overlaps))
}

/// What [`cut_pair`] found.
#[derive(Default)]
struct PairCuts {
    on_a: Vec<f64>,
    on_b: Vec<f64>,
    overlap: bool,
    steps: usize,
}

/// Where two monotone pieces cross or come within `together` of each other
/// (subdivided until flat to `tol`).
/// Past `max_steps` subdivisions the pair counts as overlapping.
fn cut_pair(
    a: &Curve,
    ta: [f64; 2],
    b: &Curve,
    tb: [f64; 2],
    tol: f64,
    together: f64,
    max_steps: usize,
) -> PairCuts {
    let mut out = PairCuts::default();
    let mut stack = vec![(ta, tb, 0u32)];
    let mut leaves = 0;
    while let Some((sa, sb, depth)) = stack.pop() {
        out.steps += 1;
        if out.steps > max_steps {
            out.overlap = true;
            return out;
        }
        let (pa, na) = a.controls(sa[0], sa[1]);
        let (pb, nb) = b.controls(sb[0], sb[1]);
        let ba = hull_box(&pa[..na]).inflate(together, together);
        let bb = hull_box(&pb[..nb]).inflate(together, together);
        if !ba.overlaps(bb)
            || fat_line_apart(&pa[..na], &pb[..nb], together)
            || fat_line_apart(&pb[..nb], &pa[..na], together)
        {
            continue;
        }
        let (p0, p1, q0, q1) = (pa[0], pa[na - 1], pb[0], pb[nb - 1]);
        // Pieces that meet at an end point (consecutive segments, shapes
        // sharing a vertex) and leave it in directions apart meet only there.
        let shared = [p0, p1].into_iter().find(|e| *e == q0 || *e == q1);
        if shared.is_some_and(|e| cones_apart(e, &pa[..na], &pb[..nb])) {
            continue;
        }
        if flatness(&pa[..na]) <= together
            && flatness(&pb[..nb]) <= together
            && run_together(p0, p1, q0, q1, 2.0 * together)
        {
            // Flat and side by side over their common stretch: each is cut
            // where the other ends, and the stretch counts once.
            leaves += 1;
            if leaves > MAX_LEAVES {
                out.overlap = true;
                return out;
            }
            for e in [q0, q1] {
                if let Some(t) = inside_param(a, sa, e, p0, p1) {
                    out.on_a.push(t);
                }
            }
            for e in [p0, p1] {
                if let Some(t) = inside_param(b, sb, e, q0, q1) {
                    out.on_b.push(t);
                }
            }
            continue;
        }
        let fa = flatness(&pa[..na]) <= tol;
        let fb = flatness(&pb[..nb]) <= tol;
        if (fa && fb) || depth >= MAX_DEPTH {
            let (u, v, dist) = closest_on_segments(p0, p1, q0, q1);
            if dist <= together {
                leaves += 1;
                if leaves > MAX_LEAVES {
                    out.overlap = true;
                    return out;
                }
                let x = p0.lerp(p1, u).midpoint(q0.lerp(q1, v));
                out.on_a.push(param_at(a, sa, x));
                out.on_b.push(param_at(b, sb, x));
            }
            continue;
        }
        // Halve the piece with the larger box (a flat one is not halved).
        let halve_a = !fa && (fb || ba.width() + ba.height() >= bb.width() + bb.height());
        if halve_a {
            let m = 0.5 * (sa[0] + sa[1]);
            stack.push(([sa[0], m], sb, depth + 1));
            stack.push(([m, sa[1]], sb, depth + 1));
        } else {
            let m = 0.5 * (sb[0] + sb[1]);
            stack.push((sa, [sb[0], m], depth + 1));
            stack.push((sa, [m, sb[1]], depth + 1));
        }
    }
    out
}

/// Whether the control points `b` lie all on one side of the band that
/// holds `a` about its chord, by more than `margin`: then the pieces (each in
/// the hull of its controls) do not meet (the fat line test of Bézier
/// clipping).
fn fat_line_apart(a: &[Point], b: &[Point], margin: f64) -> bool {
    let (a0, a1) = (a[0], a[a.len() - 1]);
    let d = a1 - a0;
    let len = d.hypot();
    if len <= 0.0 || len.is_nan() {
        return false;
    }
    let n = Vec2::new(-d.y, d.x) / len;
    let side = |p: &Point| n.dot(*p - a0);
    let (alo, ahi) = a
        .iter()
        .map(side)
        .fold((0.0f64, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (blo, bhi) = b
        .iter()
        .map(side)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    blo > ahi + margin || bhi < alo - margin
}

/// Whether the cones from `apex` spanned by the control points `a` and `b`
/// (each set's convex hull with `apex` lies in its cone) meet only at `apex`:
/// their angular intervals, each narrower than a half turn, are apart.
fn cones_apart(apex: Point, a: &[Point], b: &[Point]) -> bool {
    use std::f64::consts::{PI, TAU};
    // The angular interval of the directions from `apex`, about their mean.
    let interval = |pts: &[Point]| -> Option<(f64, f64, Vec2)> {
        let dirs: Vec<Vec2> = pts
            .iter()
            .map(|q| *q - apex)
            .filter(|v| v.hypot2() > 0.0)
            .map(|v| v / v.hypot())
            .collect();
        let mean = dirs.iter().fold(Vec2::ZERO, |s, v| s + *v);
        if dirs.is_empty() || mean.hypot2() <= 0.0 {
            return None;
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in &dirs {
            let ang = mean.cross(*v).atan2(mean.dot(*v));
            lo = lo.min(ang);
            hi = hi.max(ang);
        }
        (hi - lo < PI).then_some((lo, hi, mean))
    };
    let (Some((alo, ahi, am)), Some((blo, bhi, bm))) = (interval(a), interval(b)) else {
        return false;
    };
    let shift = am.cross(bm).atan2(am.dot(bm));
    let margin = 1e-9;
    (-1..=1).all(|k| {
        let (lo, hi) = (shift + blo + k as f64 * TAU, shift + bhi + k as f64 * TAU);
        lo > ahi + margin || hi < alo - margin
    })
}

/// Whether chords `p0 p1` and `q0 q1` run side by side within `dist`: at
/// least two of the four end points project into the other chord, and all
/// that do lie within `dist` of it (then, both being straight, so does all
/// of their common stretch).
fn run_together(p0: Point, p1: Point, q0: Point, q1: Point, dist: f64) -> bool {
    let mut inside = 0;
    for (e, c0, c1) in [(q0, p0, p1), (q1, p0, p1), (p0, q0, q1), (p1, q0, q1)] {
        let d = c1 - c0;
        let len2 = d.hypot2();
        if len2 <= 0.0 || len2.is_nan() {
            continue;
        }
        let w = (e - c0).dot(d) / len2;
        if (0.0..=1.0).contains(&w) {
            if (e - c0.lerp(c1, w)).hypot() > dist {
                return false;
            }
            inside += 1;
        }
    }
    inside >= 2
}

/// The parameter on `curve`'s flat piece `s` (chord `c0 c1`) where point
/// `e` projects, if strictly inside the chord.
fn inside_param(curve: &Curve, s: [f64; 2], e: Point, c0: Point, c1: Point) -> Option<f64> {
    let d = c1 - c0;
    let w = (e - c0).dot(d) / d.hypot2();
    (w > 0.0 && w < 1.0).then(|| param_at(curve, s, e))
}

fn hull_box(p: &[Point]) -> Rect {
    p[1..]
        .iter()
        .fold(Rect::from_points(p[0], p[0]), |r, q| r.union_pt(*q))
}

/// The largest distance of a control point from the chord (from the end
/// point where the chord has no length).
fn flatness(p: &[Point]) -> f64 {
    let (a, b) = (p[0], p[p.len() - 1]);
    let d = b - a;
    let len = d.hypot();
    p[1..p.len() - 1]
        .iter()
        .map(|q| {
            if len > 0.0 {
                (d.cross(*q - a) / len).abs()
            } else {
                (*q - a).hypot()
            }
        })
        .fold(0.0, f64::max)
}

/// The parameter in `s` of the point of `curve`'s (flat, monotone) piece on
/// `s` that projects onto the chord where `x` does: bisection along the chord.
fn param_at(curve: &Curve, s: [f64; 2], x: Point) -> f64 {
    let (a, b) = (curve.eval(s[0]), curve.eval(s[1]));
    let d = b - a;
    if d.hypot2() <= 0.0 || d.hypot2().is_nan() {
        return 0.5 * (s[0] + s[1]);
    }
    let target = (x - a).dot(d);
    let (mut lo, mut hi) = (s[0], s[1]);
    for _ in 0..64 {
        let m = 0.5 * (lo + hi);
        if m <= lo || m >= hi {
            break;
        }
        if (curve.eval(m) - a).dot(d) < target {
            lo = m;
        } else {
            hi = m;
        }
    }
    0.5 * (lo + hi)
}

/// The closest points of segments `p0 p1` and `q0 q1`: their parameters and distance.
fn closest_on_segments(p0: Point, p1: Point, q0: Point, q1: Point) -> (f64, f64, f64) {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.hypot2(), d2.hypot2(), d2.dot(r));
    let (mut s, mut t);
    if a <= 0.0 && e <= 0.0 {
        return (0.0, 0.0, r.hypot());
    }
    if a <= 0.0 {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(r);
        if e <= 0.0 {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            s = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
        }
    }
    let dist = ((p0 + d1 * s) - (q0 + d2 * t)).hypot();
    (s, t, dist)
}

/// A uniform grid of boxes: which boxes may meet box `i`.
struct BoxGrid {
    boxes: Vec<Rect>,
    origin: Point,
    cell: f64,
    cols: usize,
    rows: usize,
    cells: Vec<Vec<u32>>,
    /// The mean length of a cell's list (rounded up).
    per_cell: usize,
}

impl BoxGrid {
    fn new(boxes: Vec<Rect>) -> BoxGrid {
        let all = boxes
            .iter()
            .copied()
            .reduce(|a, b| a.union(b))
            .unwrap_or(Rect::ZERO);
        let n = boxes.len().max(1);
        let side = ((n as f64).sqrt().ceil()).clamp(1.0, 1024.0);
        let cell = (all.width().max(all.height()) / side).max(f64::MIN_POSITIVE);
        let cols = ((all.width() / cell).floor() as usize + 1).min(1024);
        let rows = ((all.height() / cell).floor() as usize + 1).min(1024);
        let mut g = BoxGrid {
            boxes,
            origin: Point::new(all.x0, all.y0),
            cell,
            cols,
            rows,
            cells: vec![Vec::new(); cols * rows],
            per_cell: 1,
        };
        for (i, b) in g.boxes.iter().enumerate() {
            let (x0, y0, x1, y1) = g.range(b);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    g.cells[y * cols + x].push(i as u32);
                }
            }
        }
        let entries: usize = g.cells.iter().map(Vec::len).sum();
        g.per_cell = entries.div_ceil(g.cells.len().max(1)).max(1);
        g
    }

    fn range(&self, b: &Rect) -> (usize, usize, usize, usize) {
        let ix = |v: f64, n: usize| (((v / self.cell).floor().max(0.0)) as usize).min(n - 1);
        (
            ix(b.x0 - self.origin.x, self.cols),
            ix(b.y0 - self.origin.y, self.rows),
            ix(b.x1 - self.origin.x, self.cols),
            ix(b.y1 - self.origin.y, self.rows),
        )
    }

    /// The boxes `j > i` that meet box `i`, each once. A box over more cells
    /// than there are boxes after it (a long diagonal segment's, among many
    /// others: its cells list most boxes many times over) is compared with
    /// those boxes directly instead, in order.
    fn candidates(&self, i: usize, out: &mut Vec<u32>) {
        out.clear();
        let b = self.boxes[i];
        let (x0, y0, x1, y1) = self.range(&b);
        let cells = (x1 - x0 + 1) * (y1 - y0 + 1);
        if cells.saturating_mul(self.per_cell) > self.boxes.len() - i {
            out.extend(
                (i + 1..self.boxes.len())
                    .filter(|&j| b.overlaps(self.boxes[j]))
                    .map(|j| j as u32),
            );
            return;
        }
        for y in y0..=y1 {
            for x in x0..=x1 {
                for &j in &self.cells[y * self.cols + x] {
                    if (j as usize) <= i {
                        continue;
                    }
                    let c = self.boxes[j as usize];
                    if !b.overlaps(c) {
                        continue;
                    }
                    // Reported in the cell of the common box's lower corner only.
                    let corner = Rect::new(b.x0.max(c.x0), b.y0.max(c.y0), 0.0, 0.0);
                    let (cx, cy, _, _) =
                        self.range(&Rect::new(corner.x0, corner.y0, corner.x0, corner.y0));
                    if cx == x && cy == y {
                        out.push(j);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn areas(svg: &str) -> (Drawing, DrawnAreas) {
        let drawing = crate::svg::load_bytes(svg.as_bytes(), &crate::svg::LoadOptions::DEFAULT)
            .expect("load");
        let painting = Painting::new(&drawing);
        let bounds = drawing.bbox.inflate(1.0, 1.0);
        let d = drawing.diagonal();
        let drawn = drawn_areas(&drawing, &painting, bounds, d, &Deadline::NONE).expect("drawn");
        (drawing, drawn)
    }

    fn of(drawing: &Drawing, drawn: &DrawnAreas, name: &str) -> f64 {
        let i = drawing
            .shapes
            .iter()
            .position(|s| s.name() == name)
            .unwrap_or_else(|| panic!("no shape {name}"));
        drawn.by_shape[i]
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * b.abs().max(1.0)
    }

    /// Each owner's area estimated on an `n × n` grid of cell centres over
    /// `bounds` by [`Painting::owner_at`] alone (by shape, then the background).
    fn grid_estimate(drawing: &Drawing, bounds: Rect, n: usize) -> Vec<f64> {
        let painting = Painting::new(drawing);
        let cell = Vec2::new(bounds.width() / n as f64, bounds.height() / n as f64);
        let mut total = vec![0usize; drawing.shapes.len() + 1];
        for j in 0..n {
            for i in 0..n {
                let p = Point::new(
                    bounds.x0 + (i as f64 + 0.5) * cell.x,
                    bounds.y0 + (j as f64 + 0.5) * cell.y,
                );
                match painting.owner_at(p, 1e-9).0 {
                    Some(s) => total[s.index()] += 1,
                    None => total[drawing.shapes.len()] += 1,
                }
            }
        }
        total.iter().map(|&k| k as f64 * cell.x * cell.y).collect()
    }

    #[test]
    fn the_topmost_shape_owns_what_it_covers() {
        let (dr, a) = areas(
            r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
            <rect id="plate" x="0" y="0" width="100" height="60" fill="grey"/>
            <rect id="bar" x="20" y="40" width="30" height="50" fill="red"/>
            <circle id="disk" cx="70" cy="30" r="20" fill="blue"/></svg>"#,
        );
        assert!(close(of(&dr, &a, "bar"), 1500.0, 1e-12), "{a:?}");
        assert!(close(of(&dr, &a, "disk"), PI * 400.0, 1e-12), "{a:?}");
        assert!(
            close(of(&dr, &a, "plate"), 6000.0 - 600.0 - PI * 400.0, 1e-12),
            "{a:?}"
        );
        // the box is the drawing's box grown by 1
        let painted = 6000.0 + 900.0;
        assert!(close(a.background, 102.0 * 92.0 - painted, 1e-12), "{a:?}");
        assert_eq!(a.overlaps, 0);
        assert!(a.unsure < 1e-9, "{a:?}");
    }

    #[test]
    fn a_shared_edge_with_other_end_points_counts_once() {
        // bottom's top edge (0..100) is drawn again in two pieces by the two
        // shapes above it, with end points of their own
        let (dr, a) = areas(
            r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
            <path id="bottom" d="M0 50H100V100H0Z" fill="grey"/>
            <path id="left" d="M0 0H40V50H0Z" fill="red"/>
            <path id="right" d="M100 50H40V20H100Z" fill="blue"/></svg>"#,
        );
        assert!(close(of(&dr, &a, "bottom"), 5000.0, 1e-12), "{a:?}");
        assert!(close(of(&dr, &a, "left"), 2000.0, 1e-12), "{a:?}");
        assert!(close(of(&dr, &a, "right"), 1800.0, 1e-12), "{a:?}");
    }

    #[test]
    fn a_hairpin_is_exact() {
        // A cubic runs out to a tip and a line comes straight back along its
        // end tangent: near the tip the two run within the run-together
        // distance, farther back they part (from a path of the gilbarbara logos,
        // CC0).
        let hairpin = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="60 38 14 12">
            <rect x="60" y="38" width="14" height="12" fill="grey"/>
            <path d="M66.0464995,42.8595956 C66.0454235,42.8617477 66.0432714,42.8638998
              69.3790251,45.7326481 L66.0432714,42.8638998 C64.4980466,44.705693
              64.7167493,47.4466741 66.5344772,49.0201375 L72 49 L72 40 Z" fill="red"/></svg>"#;
        let (dr, a) = areas(hairpin);
        // the path's own area, by Green's theorem on a polygon of 200 000
        // points per cubic (it does not cross itself)
        assert!(
            close(of(&dr, &a, "shape-1"), 49.022363134974, 1e-9),
            "{a:?}"
        );
        // the whole path the hairpin is cut from: there two pieces running
        // together near the tip were counted as one stretch over lengths that
        // differ (off by 6e-5); they are sampled between them instead
        let (dr, a) = areas(&format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 120 110">
            <rect width="120" height="110" fill="grey"/>
            <path fill="red" d="{}"/></svg>"#,
            "M72.6975621,48.6239933 L72.7319956,48.5852555 C72.7750376,48.5389854
              72.8546653,48.4539775 72.9698026,48.3377641 C73.2022293,48.1053374 73.5756185,47.748089
              74.085666,47.3176691 C75.5041689,46.1302307 77.0545426,45.1098869 78.706223,44.276753
              C82.742485,42.2344108 88.752222,40.56761 96.6342853,42.3850578 C99.0025141,42.9312064
              101.365084,41.4541186 101.911232,39.0858897 C102.457381,36.7176609 100.980293,34.3550912
              98.6120644,33.8089425 C88.4089622,31.4566981 80.2966243,33.6077212 74.7312958,36.4258951
              C72.471515,37.5661779 70.3509304,38.9635323 68.4116565,40.5902071 C67.8295728,41.0791275
              67.2691337,41.5932523 66.7319431,42.1311101 C66.5233374,42.3405802 66.3199028,42.5551373
              66.121823,42.7745877 L66.0744768,42.8283902 L66.05726,42.8477591 L66.0497277,42.8563675
              L66.0464995,42.8595956 C66.0454235,42.8617477 66.0432714,42.8638998
              69.3790251,45.7326481 L66.0432714,42.8638998 C64.4980466,44.705693 64.7167493,47.4466741
              66.5344772,49.0201375 C68.3522051,50.5936008 71.0962349,50.417223 72.6975621,48.6239933
              L72.6975621,48.6239933 Z"
        ));
        assert!(
            close(of(&dr, &a, "shape-1"), 329.80883675769, 1e-9),
            "{a:?}"
        );
    }

    #[test]
    fn evenodd_holes_and_nearly_equal_edges() {
        // the hole's edges lie 1e-13 from the frame's inner edges: one stretch
        let (dr, a) = areas(
            r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
            <path id="frame" fill-rule="evenodd" d="M0 0H100V100H0Z M20 20H80V80H20Z" fill="grey"/>
            <path id="inlay" d="M20.0000000000001 20H80V79.9999999999999H20.0000000000001Z" fill="red"/></svg>"#,
        );
        assert!(close(of(&dr, &a, "frame"), 10000.0 - 3600.0, 1e-9), "{a:?}");
        assert!(close(of(&dr, &a, "inlay"), 3600.0, 1e-9), "{a:?}");
    }

    #[test]
    fn a_circle_over_its_cubic_approximation() {
        // the cubics run within 0.02 of the circle, touching it at their ends
        // and crossing it twice in each quarter
        let (dr, a) = areas(
            r#"<svg viewBox="0 0 200 200" xmlns="http://www.w3.org/2000/svg">
            <path id="p" fill="red" d="M180 100C180 55.82 144.18 20 100 20 55.82 20 20 55.82 20 100 20 144.18 55.82 180 100 180 144.18 180 180 144.18 180 100Z"/>
            <circle id="c" cx="100" cy="100" r="80" fill="green"/></svg>"#,
        );
        // Where the cubics touch the circle (at their ends) the two run within
        // 2e-12·d of each other for a stretch, whose terms are shared between
        // them by the count at each piece's middle: the circle's area is off
        // by a part of that stretch's sliver.
        assert!(close(of(&dr, &a, "c"), PI * 6400.0, 2e-6), "{a:?}");
        let p = of(&dr, &a, "p");
        // the slivers where the cubics pass outside the circle
        assert!(p > 1.0 && p < 10.0, "{a:?}");
    }

    #[test]
    fn clips_and_strokes_against_a_grid() {
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
            <clipPath id="cp"><circle cx="50" cy="50" r="35"/></clipPath>
            <rect id="under" x="5" y="5" width="90" height="90" fill="grey"/>
            <path id="blob" clip-path="url(#cp)" fill="red" d="M10 30C40 -10 90 20 80 60S20 110 10 30Z"/>
            <path id="ring" d="M50 20C70 20 80 40 70 60" fill="none" stroke="blue" stroke-width="6"/></svg>"#;
        let (dr, a) = areas(svg);
        let bounds = dr.bbox.inflate(1.0, 1.0);
        // (an odd count, so no cell centre falls on the rectangle's edges)
        let est = grid_estimate(&dr, bounds, 397);
        // A grid counts each cell on a boundary whole or not at all: its error
        // is at most half a cell's width along every outline (under 700 units
        // of them here).
        let slack = 350.0 * bounds.width().max(bounds.height()) / 397.0;
        for (i, s) in dr.shapes.iter().enumerate() {
            assert!(
                (a.by_shape[i] - est[i]).abs() <= slack,
                "{} drawn {} grid {}",
                s.name(),
                a.by_shape[i],
                est[i]
            );
        }
        assert!((a.background - est[dr.shapes.len()]).abs() <= slack);
        // The union of the paint is the rectangle under the rest, exactly.
        let painted: f64 = a.by_shape.iter().sum();
        assert!(close(painted, 8100.0, 1e-12), "{a:?}");
        assert_eq!(a.overlaps, 0);
    }
}
