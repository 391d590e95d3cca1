//! The drawing as a pattern's tile: every feature cut where it crosses the
//! lines of the period lattice and each piece translated into the cell; each
//! shape becomes the union of its translated copies that reach the cell, so
//! the paint test of a point in the cell is the pattern's.
//!
//! A crossing point of a lattice line is computed once (one parameter, one
//! point) and written into both pieces it joins: on the cell's sides the two
//! pieces' ends are partners, the same coordinate along the side bit for bit.

use super::Cell;
use crate::svg::drawing::{Conic, Drawing, Feature, FeatureGeom, FeatureSource, Subpath};
use kurbo::{CubicBez, Line, ParamCurve, Point, Rect, Vec2};

/// Parameters within this of a piece's ends are its ends.
const T_EPS: f64 = 1e-12;
/// Bisection steps for a crossing (the parameter to f64 resolution).
const BISECT_STEPS: u32 = 80;

/// One axis of the cell: its range and whether it repeats.
#[derive(Clone, Copy)]
struct AxisCell {
    lo: f64,
    hi: f64,
    periodic: bool,
}

impl AxisCell {
    fn period(self) -> f64 {
        self.hi - self.lo
    }
    /// The lattice cell of coordinate `v` (0: the cell). A non-periodic axis
    /// has three: below (-1), the cell (0), above (1).
    fn index(self, v: f64) -> i64 {
        if self.periodic {
            #[allow(
                clippy::cast_possible_truncation,
                reason = "coordinates are at most 1e15 and the cell is not degenerate"
            )]
            let k = ((v - self.lo) / self.period()).floor() as i64;
            k
        } else if v < self.lo {
            -1
        } else if v > self.hi {
            1
        } else {
            0
        }
    }
    /// The lattice line between cells `k - 1` and `k`.
    fn line(self, k: i64) -> f64 {
        if self.periodic {
            self.lo + k as f64 * self.period()
        } else if k <= 0 {
            self.lo
        } else {
            self.hi
        }
    }
    /// The translation taking lattice cell `k` to the cell.
    fn shift(self, k: i64) -> f64 {
        if self.periodic {
            -(k as f64) * self.period()
        } else {
            0.0
        }
    }
}

/// A feature's curve, for cutting.
#[derive(Clone, Copy)]
enum Curve {
    Line(Line),
    Cubic(CubicBez),
    Conic(Conic),
}

impl Curve {
    fn eval(&self, t: f64) -> Point {
        match self {
            Curve::Line(l) => l.eval(t),
            Curve::Cubic(c) => c.eval(t),
            Curve::Conic(c) => c.eval(t),
        }
    }
    fn deriv(&self, t: f64) -> Vec2 {
        match self {
            Curve::Line(l) => l.p1 - l.p0,
            Curve::Cubic(c) => kurbo::ParamCurveDeriv::deriv(c).eval(t).to_vec2(),
            Curve::Conic(c) => c.deriv(t),
        }
    }
    /// Parameters in (0, 1) where coordinate `axis` (0: x, 1: y) is extremal,
    /// so that it is monotone between them.
    fn extrema(&self, axis: usize) -> Vec<f64> {
        let c = |p: Point| if axis == 0 { p.x } else { p.y };
        match self {
            Curve::Line(_) => Vec::new(),
            Curve::Cubic(q) => {
                // x'(t)/3 = a (1-t)^2 + 2 b (1-t) t + c t^2
                let (a, b, cc) = (c(q.p1) - c(q.p0), c(q.p2) - c(q.p1), c(q.p3) - c(q.p2));
                let (c2, c1, c0) = (a - 2.0 * b + cc, 2.0 * (b - a), a);
                kurbo::common::solve_quadratic(c0, c1, c2)
                    .into_iter()
                    .filter(|t| *t > 0.0 && *t < 1.0)
                    .collect()
            }
            Curve::Conic(_) => {
                // a conic piece of at most 90° has at most one extremum per
                // axis: bracket the derivative's sign changes and bisect
                const N: usize = 32;
                let d = |t: f64| {
                    let v = self.deriv(t);
                    if axis == 0 { v.x } else { v.y }
                };
                let mut out = Vec::new();
                for i in 0..N {
                    let (mut a, mut b) = (i as f64 / N as f64, (i + 1) as f64 / N as f64);
                    let (da, db) = (d(a), d(b));
                    if da == 0.0 || da.signum() == db.signum() || db == 0.0 {
                        continue;
                    }
                    for _ in 0..BISECT_STEPS {
                        let m = 0.5 * (a + b);
                        if d(m).signum() == da.signum() {
                            a = m;
                        } else {
                            b = m;
                        }
                    }
                    out.push(0.5 * (a + b));
                }
                out
            }
        }
    }
    /// The piece on `[t0, t1]` translated by `shift`, its ends replaced by `ends`.
    fn piece(&self, t0: f64, t1: f64, shift: Vec2, ends: [Point; 2]) -> FeatureGeom {
        let a = kurbo::Affine::translate(shift);
        match self {
            Curve::Line(_) => FeatureGeom::Line(Line::new(ends[0], ends[1])),
            Curve::Cubic(c) => {
                let mut s = a * c.subsegment(t0..t1);
                s.p0 = ends[0];
                s.p3 = ends[1];
                FeatureGeom::Cubic(s)
            }
            Curve::Conic(c) => {
                let mut s = c.subsegment(t0, t1).transform(a);
                s.p0 = ends[0];
                s.p2 = ends[1];
                FeatureGeom::Conic(s)
            }
        }
    }
    fn control_points(&self) -> Vec<Point> {
        match self {
            Curve::Line(l) => vec![l.p0, l.p1],
            Curve::Cubic(c) => vec![c.p0, c.p1, c.p2, c.p3],
            Curve::Conic(c) => c.control_points().to_vec(),
        }
    }
}

/// Where a feature crosses a lattice line: its parameter, the point, and the
/// line (axis, lattice index of the cell above it).
#[derive(Clone, Copy)]
struct Crossing {
    t: f64,
    p: Point,
    axis: usize,
    line: i64,
}

/// The tiling of a drawing into `cell`.
pub(super) struct Tiler {
    axes: [AxisCell; 2],
    /// Snap distance onto the cell's sides (user units): a feature end this
    /// close to a side is on it, a piece that lies this close along a side is
    /// the side (the drawing meant its edge to be the cell's: left apart, the
    /// two would make a sliver of that width along the fixed side).
    snap: f64,
}

impl Tiler {
    pub(super) fn new(cell: &Cell, snap: f64) -> Tiler {
        let r = cell.rect;
        Tiler {
            axes: [
                AxisCell {
                    lo: r.x0,
                    hi: r.x1,
                    periodic: cell.x,
                },
                AxisCell {
                    lo: r.y0,
                    hi: r.y1,
                    periodic: cell.y,
                },
            ],
            snap,
        }
    }

    fn coord(p: Point, axis: usize) -> f64 {
        if axis == 0 { p.x } else { p.y }
    }

    /// The crossings of `curve` with the lattice lines, by parameter. Where
    /// the curve turns back within the snap distance of a line (touching
    /// it, or crossing it twice that close), it touches the line once at its
    /// extremum instead.
    fn crossings(&self, curve: &Curve) -> Vec<Crossing> {
        let mut ts = vec![0.0, 1.0];
        let mut touches: Vec<Crossing> = Vec::new();
        for axis in 0..2 {
            let ax = self.axes[axis];
            for te in curve.extrema(axis) {
                ts.push(te);
                let p = curve.eval(te);
                let v = Self::coord(p, axis);
                let k = if ax.periodic {
                    #[allow(
                        clippy::cast_possible_truncation,
                        reason = "coordinates are at most 1e15 and the cell is not degenerate"
                    )]
                    let k = ((v - ax.lo) / ax.period()).round() as i64;
                    k
                } else if (v - ax.lo).abs() < (v - ax.hi).abs() {
                    0
                } else {
                    1
                };
                let line = ax.line(k);
                if (v - line).abs() <= self.snap && te > T_EPS && te < 1.0 - T_EPS {
                    let mut q = p;
                    if axis == 0 {
                        q.x = line;
                    } else {
                        q.y = line;
                    }
                    touches.push(Crossing {
                        t: te,
                        p: q,
                        axis,
                        line: k,
                    });
                }
            }
        }
        ts.sort_by(f64::total_cmp);
        ts.dedup();
        let mut out = Vec::new();
        for w in ts.windows(2) {
            let (ta, tb) = (w[0], w[1]);
            let (pa, pb) = (curve.eval(ta), curve.eval(tb));
            for (axis, ax) in self.axes.iter().enumerate() {
                let (va, vb) = (Self::coord(pa, axis), Self::coord(pb, axis));
                let (ka, kb) = (ax.index(va), ax.index(vb));
                let (lo, hi) = (ka.min(kb), ka.max(kb));
                // the lines between the two cells: k in (lo, hi]
                for k in (lo + 1)..=hi {
                    // a touch at an end of this monotone interval stands for it
                    if touches
                        .iter()
                        .any(|c| c.axis == axis && c.line == k && (c.t == ta || c.t == tb))
                    {
                        continue;
                    }
                    let value = ax.line(k);
                    let f = |t: f64| Self::coord(curve.eval(t), axis) - value;
                    let (mut a, mut b) = (ta, tb);
                    let fa = f(a);
                    if f(b) == 0.0 {
                        // ends on the line: no crossing inside this interval
                        continue;
                    }
                    for _ in 0..BISECT_STEPS {
                        let m = 0.5 * (a + b);
                        if m <= a || m >= b {
                            break;
                        }
                        if (f(m) < 0.0) == (fa < 0.0) {
                            a = m;
                        } else {
                            b = m;
                        }
                    }
                    let t = 0.5 * (a + b);
                    if t > T_EPS && t < 1.0 - T_EPS {
                        let mut p = curve.eval(t);
                        if axis == 0 {
                            p.x = value;
                        } else {
                            p.y = value;
                        }
                        out.push(Crossing {
                            t,
                            p,
                            axis,
                            line: k,
                        });
                    }
                }
            }
        }
        out.extend(touches);
        out.sort_by(|a, b| a.t.total_cmp(&b.t));
        out
    }

    /// The end of a piece in lattice cell `cells` at a crossing (snapped onto
    /// the side it crosses) or at a feature's own end (snapped onto a side
    /// within the snap distance).
    fn end_point(&self, crossing: Option<&Crossing>, p: Point, cells: [i64; 2]) -> Point {
        let mut q = Point::new(
            p.x + self.axes[0].shift(cells[0]),
            p.y + self.axes[1].shift(cells[1]),
        );
        if let Some(c) = crossing {
            // the side the crossing lies on, seen from this piece's cell
            let ax = self.axes[c.axis];
            let side = if c.line == cells[c.axis] {
                ax.lo
            } else {
                ax.hi
            };
            if c.axis == 0 {
                q.x = side;
            } else {
                q.y = side;
            }
        }
        for (axis, ax) in self.axes.iter().enumerate() {
            let v = if axis == 0 { &mut q.x } else { &mut q.y };
            for side in [ax.lo, ax.hi] {
                if (*v - side).abs() <= self.snap {
                    *v = side;
                }
            }
        }
        q
    }

    /// The pieces of one feature in the cell, each with the lattice cell it
    /// came from.
    fn pieces(&self, geom: &FeatureGeom) -> Vec<(FeatureGeom, [i64; 2])> {
        let curve = match *geom {
            FeatureGeom::Point(p) => {
                let cells = [self.axes[0].index(p.x), self.axes[1].index(p.y)];
                if self.outside(cells) {
                    return Vec::new();
                }
                let q = self.end_point(None, p, cells);
                return vec![(FeatureGeom::Point(q), cells)];
            }
            FeatureGeom::Line(l) => Curve::Line(l),
            FeatureGeom::Cubic(c) => Curve::Cubic(c),
            FeatureGeom::Conic(c) => Curve::Conic(c),
        };
        let crossings = self.crossings(&curve);
        let mut out = Vec::new();
        let n = crossings.len();
        for i in 0..=n {
            let start = i.checked_sub(1).map(|j| &crossings[j]);
            let end = crossings.get(i);
            let t0 = start.map_or(0.0, |c| c.t);
            let t1 = end.map_or(1.0, |c| c.t);
            if t1 <= t0 {
                continue;
            }
            let mid = curve.eval(0.5 * (t0 + t1));
            let cells = [self.axes[0].index(mid.x), self.axes[1].index(mid.y)];
            if self.outside(cells) {
                continue;
            }
            let p0 = start.map_or_else(|| curve.eval(0.0), |c| c.p);
            let p1 = end.map_or_else(|| curve.eval(1.0), |c| c.p);
            let ends = [
                self.end_point(start, p0, cells),
                self.end_point(end, p1, cells),
            ];
            let shift = Vec2::new(self.axes[0].shift(cells[0]), self.axes[1].shift(cells[1]));
            let g = curve.piece(t0, t1, shift, ends);
            if self.on_side(&g) {
                continue;
            }
            out.push((g, cells));
        }
        out
    }

    /// Whether a lattice cell is outside the pattern (off a non-periodic axis).
    fn outside(&self, cells: [i64; 2]) -> bool {
        (0..2).any(|a| !self.axes[a].periodic && cells[a] != 0)
    }

    /// Whether a piece lies along a side of the cell (the side is the mesh's
    /// boundary already).
    fn on_side(&self, g: &FeatureGeom) -> bool {
        let points = match *g {
            FeatureGeom::Point(_) => return false,
            FeatureGeom::Line(l) => Curve::Line(l).control_points(),
            FeatureGeom::Cubic(c) => Curve::Cubic(c).control_points(),
            FeatureGeom::Conic(c) => Curve::Conic(c).control_points(),
        };
        (0..2).any(|axis| {
            let ax = self.axes[axis];
            [ax.lo, ax.hi].iter().any(|&s| {
                points
                    .iter()
                    .all(|&p| (Self::coord(p, axis) - s).abs() <= self.snap)
            })
        })
    }

    /// The lattice translations (in cells) that bring some of `bbox` into the cell.
    fn copies(&self, bbox: Rect) -> Vec<[i64; 2]> {
        let range = |axis: usize, lo: f64, hi: f64| {
            let ax = self.axes[axis];
            if !ax.periodic {
                return 0..=0;
            }
            // translations by -k periods with [lo, hi] - k P meeting [ax.lo, ax.hi]
            ax.index(lo).min(0)..=ax.index(hi).max(0)
        };
        let mut out = Vec::new();
        for i in range(0, bbox.x0, bbox.x1) {
            for j in range(1, bbox.y0, bbox.y1) {
                let shifted = Rect::new(
                    bbox.x0 + self.axes[0].shift(i),
                    bbox.y0 + self.axes[1].shift(j),
                    bbox.x1 + self.axes[0].shift(i),
                    bbox.y1 + self.axes[1].shift(j),
                );
                let c = Rect::new(
                    self.axes[0].lo,
                    self.axes[1].lo,
                    self.axes[0].hi,
                    self.axes[1].hi,
                );
                if shifted.x1 >= c.x0
                    && shifted.x0 <= c.x1
                    && shifted.y1 >= c.y0
                    && shifted.y0 <= c.y1
                {
                    out.push([i, j]);
                }
            }
        }
        out
    }

    /// The tile of `drawing`: see the module doc.
    pub(super) fn tile(&self, drawing: &Drawing, cell: Rect) -> Drawing {
        let mut shapes = drawing.shapes.clone();
        let mut copies_of: Vec<Vec<[i64; 2]>> = Vec::with_capacity(shapes.len());
        let mut bbox = cell;
        let mut clipped_copies = 0usize;
        for shape in &mut shapes {
            let mut sb: Option<Rect> = None;
            for sp in &shape.subpaths {
                for p in std::iter::once(sp.start)
                    .chain(sp.segments.iter().flat_map(|s| s.control_points()))
                {
                    sb = Some(sb.map_or(Rect::from_points(p, p), |b| b.union_pt(p)));
                }
            }
            let copies = sb.map_or_else(Vec::new, |b| self.copies(b));
            if copies.len() > 1 && !shape.paint.clips.is_empty() {
                clipped_copies += 1;
            }
            let mut subpaths: Vec<Subpath> = Vec::new();
            for &[i, j] in &copies {
                let a = kurbo::Affine::translate((self.axes[0].shift(i), self.axes[1].shift(j)));
                for sp in &shape.subpaths {
                    let moved = Subpath {
                        segments: sp.segments.iter().map(|s| s.transform(a)).collect(),
                        start: a * sp.start,
                        closed: sp.closed,
                    };
                    for p in std::iter::once(moved.start)
                        .chain(moved.segments.iter().flat_map(|s| s.control_points()))
                    {
                        bbox = bbox.union_pt(p);
                    }
                    subpaths.push(moved);
                }
            }
            shape.subpaths = subpaths;
            copies_of.push(copies);
        }
        let mut features: Vec<Feature> = Vec::new();
        for f in &drawing.features {
            let s = f.source.shape.index();
            let n_sub = drawing.shapes.get(s).map_or(1, |sh| sh.subpaths.len()) as u32;
            for (geom, [m, n]) in self.pieces(&f.geom) {
                // the piece from lattice cell (m, n) lies on the copy shifted from there
                let copy = copies_of
                    .get(s)
                    .and_then(|c| c.iter().position(|&k| k == [m, n]));
                let subpath = match copy {
                    Some(c) => (c as u32)
                        .saturating_mul(n_sub)
                        .saturating_add(f.source.subpath),
                    None => f.source.subpath,
                };
                features.push(Feature {
                    geom,
                    source: FeatureSource {
                        subpath,
                        ..f.source
                    },
                });
            }
        }
        let mut warnings = drawing.warnings.clone();
        if clipped_copies > 0 {
            warnings.push(format!(
                "--periodic: {clipped_copies} shape(s) painted through a clip path or mask \
                 re-enter the cell; their clips are not translated with them"
            ));
        }
        Drawing {
            shapes,
            features,
            bbox,
            warnings,
            precision: drawing.precision,
            paint: drawing.paint,
            view_box: drawing.view_box,
            cell: Some(cell),
        }
    }
}
