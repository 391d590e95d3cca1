//! Winding numbers of points with respect to a filled shape's outline, evaluated
//! on the input curves themselves (never on a flattening).
//!
//! The outline of a shape is the union of its subpaths, each closed as SVG fills
//! it: a straight segment joins the end of an open subpath back to its start
//! (the same segment the loader adds as a feature, `FeatureSource::IMPLICIT_CLOSE`).
//!
//! # Method
//! Ray casting towards +x with the half-open rule (an upward piece counts when
//! `y0 ∈ [y_start, y_end)`, a downward one when `y0 ∈ [y_end, y_start)`), so a ray
//! through a vertex or along a horizontal piece is counted once, exactly.
//! - A straight piece decides its crossing with the exact `orient2d` predicate.
//! - A cubic is replaced by its chord whenever the point lies outside the
//!   bounding box of its control points (inflated by a margin): the curve and
//!   its chord then bound a closed loop inside a convex set that excludes the
//!   point, so both contribute the same to the winding number. Otherwise the
//!   cubic is split in two (de Casteljau at t = ½, the shared midpoint computed
//!   once so the chain stays closed) and each half is treated the same way.
//! - A conic piece (positive weight) lies in its control triangle: it is treated
//!   as a cubic is, with the triangle's bounding box, and halved by
//!   [`Conic::subsegment`] at t = ½ (both halves take their shared point from
//!   the same evaluation). A conic whose weight is not positive and finite is
//!   no bounded arc (the loader never makes one): it counts as its chord, as the
//!   features stage takes it.
//!
//! The result is exact whenever the point is clear of the outline; a point that
//! lies on a straight piece, or within about `eps_abs` of a curve (where
//! subdivision stops), is reported as [`Winding::Near`] with a best-effort
//! number, and the caller picks another point.

mod cells;

use super::drawing::Conic;
use super::{Clip, Drawing, FillRule, Segment, Shape, ShapeId, Subpath};
use crate::exact::{Orientation, orient2d};
use kurbo::{CubicBez, Point, Rect};

/// Subdivision depth at which a cubic piece is given up on (2⁻⁶⁰ of the curve).
const MAX_DEPTH: u32 = 60;
/// Total number of pieces examined per cubic or conic before giving up (keeps
/// pathological, self-overlapping curves bounded).
const MAX_PIECES: u32 = 4096;
/// Outlines of at least this many pieces answer queries from a grid of cells
/// ([`cells`]) rather than from their horizontal bands alone.
const CELLS_MIN_PIECES: usize = 1024;

/// The winding number of a point, and whether it is certain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Winding {
    /// The point is clear of the outline (at least `eps_abs / 4` from every
    /// curve, and on no straight piece): the number is exact.
    Clear(i32),
    /// The point lies on a straight piece or within about `2·eps_abs` of a
    /// curve: the number is a best guess.
    Near(i32),
}

impl Winding {
    /// The winding number (exact for [`Winding::Clear`]).
    pub(crate) fn number(self) -> i32 {
        match self {
            Winding::Clear(w) | Winding::Near(w) => w,
        }
    }
    /// Whether the number is certain.
    pub(crate) fn is_clear(self) -> bool {
        matches!(self, Winding::Clear(_))
    }
    /// Whether a winding number means "inside" under `rule`.
    pub(crate) fn inside(self, rule: FillRule) -> bool {
        let w = self.number();
        match rule {
            FillRule::NonZero => w != 0,
            FillRule::EvenOdd => w % 2 != 0,
        }
    }
}

/// One piece of a closed outline.
#[derive(Clone, Copy, Debug)]
enum Piece {
    Line(Point, Point),
    Cubic(CubicBez),
    /// A conic of positive, finite weight.
    Conic(Conic),
}

impl Piece {
    fn bbox(&self) -> Rect {
        match *self {
            Piece::Line(a, b) => Rect::from_points(a, b),
            Piece::Cubic(c) => control_bbox(&c),
            Piece::Conic(c) => conic_bbox(&c),
        }
    }
}

fn control_bbox(c: &CubicBez) -> Rect {
    Rect::from_points(c.p0, c.p1).union_pt(c.p2).union_pt(c.p3)
}

fn conic_bbox(c: &Conic) -> Rect {
    Rect::from_points(c.p0, c.p1).union_pt(c.p2)
}

/// A shape's closed outline, prepared for many winding queries: its pieces
/// bucketed into horizontal bands, so a query only looks at the pieces whose
/// vertical extent holds the query point; a large outline also answers from a
/// grid of cells with known winding numbers ([`cells`], built at the first query),
/// so a query looks only at the pieces near it.
#[derive(Clone, Debug)]
pub(crate) struct Outline {
    pieces: Vec<Piece>,
    bbox: Option<Rect>,
    band_y0: f64,
    band_h: f64,
    bands: Vec<Vec<u32>>,
    cells: std::sync::OnceLock<Option<cells::Cells>>,
}

impl Outline {
    /// The outline of `subpaths`, each closed by a straight segment if open.
    /// Consecutive segments that do not meet exactly are joined by a straight
    /// segment (the loader never produces such gaps; this keeps the chain closed).
    pub(crate) fn new(subpaths: &[Subpath]) -> Outline {
        let mut pieces = Vec::new();
        for sp in subpaths {
            if sp.segments.is_empty() {
                continue;
            }
            let mut cursor = sp.start;
            for seg in &sp.segments {
                if seg.start() != cursor {
                    pieces.push(Piece::Line(cursor, seg.start()));
                }
                pieces.push(match *seg {
                    Segment::Line(l) => Piece::Line(l.p0, l.p1),
                    Segment::Cubic(c) => Piece::Cubic(c),
                    Segment::Conic(c) if c.w > 0.0 && c.w.is_finite() => Piece::Conic(c),
                    Segment::Conic(c) => Piece::Line(c.p0, c.p2),
                });
                cursor = seg.end();
            }
            if cursor != sp.start {
                pieces.push(Piece::Line(cursor, sp.start));
            }
        }
        let bbox = pieces.iter().map(Piece::bbox).reduce(|a, b| a.union(b));
        let mut outline = Outline {
            pieces,
            bbox,
            band_y0: 0.0,
            band_h: 1.0,
            bands: Vec::new(),
            cells: std::sync::OnceLock::new(),
        };
        outline.build_bands();
        outline
    }

    /// The outline of a shape's subpaths.
    pub(crate) fn of_shape(shape: &Shape) -> Outline {
        Outline::new(&shape.subpaths)
    }

    /// Bounding box of the control points, `None` for an empty outline.
    pub(crate) fn bbox(&self) -> Option<Rect> {
        self.bbox
    }

    fn build_bands(&mut self) {
        let Some(bb) = self.bbox else { return };
        let n = self.pieces.len();
        let ranges: Vec<(f64, f64)> = self
            .pieces
            .iter()
            .map(|p| {
                let b = p.bbox();
                (b.y0, b.y1)
            })
            .collect();
        // Fewer bands while long pieces would make the index much larger than the outline.
        let mut k = n.clamp(1, 1024);
        loop {
            let h = bb.height() / k as f64;
            if h.is_nan() || h <= 0.0 || h.is_infinite() {
                k = 1;
            }
            let h = if k == 1 { f64::INFINITY } else { h };
            let band = |y: f64| -> usize {
                if k == 1 {
                    0
                } else {
                    (((y - bb.y0) / h).floor().max(0.0) as usize).min(k - 1)
                }
            };
            let total: usize = ranges.iter().map(|&(a, b)| band(b) - band(a) + 1).sum();
            if k > 1 && total > 16 * n + 1024 {
                k /= 2;
                continue;
            }
            let mut bands = vec![Vec::new(); k];
            for (i, &(a, b)) in ranges.iter().enumerate() {
                for list in &mut bands[band(a)..=band(b)] {
                    list.push(i as u32);
                }
            }
            self.band_y0 = bb.y0;
            self.band_h = h;
            self.bands = bands;
            return;
        }
    }

    fn band_of(&self, y: f64) -> Option<&[u32]> {
        let k = self.bands.len();
        if k == 0 {
            return None;
        }
        let i = if k == 1 {
            0
        } else {
            (((y - self.band_y0) / self.band_h).floor().max(0.0) as usize).min(k - 1)
        };
        Some(&self.bands[i])
    }

    /// Where the segment `a b` meets the outline, as fractions along it
    /// (`None`, with nothing added, when more than `max_pieces` pieces share
    /// its vertical extent): `cuts` gets each point where it crosses or
    /// touches a straight piece (decided exactly, placed in f64), `unsure` each
    /// range where it runs along a straight piece or through a curved piece's
    /// control box (where it may meet the curve). Between consecutive cuts and
    /// off every unsure range the segment meets no piece, so the winding number
    /// is the same all along it.
    pub(crate) fn meet_segment(
        &self,
        (a, b): (Point, Point),
        max_pieces: usize,
        cuts: &mut Vec<f64>,
        unsure: &mut Vec<[f64; 2]>,
    ) -> Option<()> {
        let Some(bb) = self.bbox else {
            return Some(());
        };
        let sb = Rect::from_points(a, b);
        if sb.x1 < bb.x0 || sb.x0 > bb.x1 || sb.y1 < bb.y0 || sb.y0 > bb.y1 {
            return Some(());
        }
        // The bands the segment's vertical extent meets (a piece listed in
        // several is examined in each: the answers repeat, harmlessly).
        let k = self.bands.len();
        let band = |y: f64| -> usize {
            if k <= 1 {
                0
            } else {
                (((y - self.band_y0) / self.band_h).floor().max(0.0) as usize).min(k - 1)
            }
        };
        if k == 0 {
            return Some(());
        }
        let bands = &self.bands[band(sb.y0)..=band(sb.y1)];
        if bands.iter().map(Vec::len).sum::<usize>() > max_pieces {
            return None;
        }
        let d = b - a;
        let len2 = d.hypot2();
        if !(len2 > 0.0 && len2.is_finite()) {
            return None;
        }
        // The fraction range of the segment inside box `r` (Liang-Barsky).
        let clip = |r: Rect| -> Option<[f64; 2]> {
            let (mut lo, mut hi) = (0.0f64, 1.0f64);
            for (p, q) in [
                (-d.x, a.x - r.x0),
                (d.x, r.x1 - a.x),
                (-d.y, a.y - r.y0),
                (d.y, r.y1 - a.y),
            ] {
                if p == 0.0 {
                    if q < 0.0 {
                        return None;
                    }
                } else {
                    let t = q / p;
                    if p < 0.0 {
                        lo = lo.max(t);
                    } else {
                        hi = hi.min(t);
                    }
                }
            }
            (lo <= hi).then_some([lo, hi])
        };
        let along = |p: Point| ((p - a).dot(d) / len2).clamp(0.0, 1.0);
        for &i in bands.iter().flatten() {
            let piece = self.pieces[i as usize];
            let pb = piece.bbox();
            if pb.x1 < sb.x0 || pb.x0 > sb.x1 || pb.y1 < sb.y0 || pb.y0 > sb.y1 {
                continue;
            }
            let (c, e) = match piece {
                Piece::Line(c, e) => (c, e),
                Piece::Cubic(_) | Piece::Conic(_) => {
                    unsure.extend(clip(pb));
                    continue;
                }
            };
            let side = |p: Point, q: Point, r: Point| match orient2d(p, q, r) {
                Orientation::CounterClockwise => 1i8,
                Orientation::Clockwise => -1,
                Orientation::Collinear => 0,
            };
            let (o1, o2) = (side(a, b, c), side(a, b, e));
            if o1 * o2 > 0 {
                continue;
            }
            let (o3, o4) = (side(c, e, a), side(c, e, b));
            if o3 * o4 > 0 {
                continue;
            }
            if o1 == 0 && o2 == 0 {
                // Along the segment: the range it shares.
                let (u, v) = (along(c), along(e));
                unsure.push([u.min(v), u.max(v)]);
                continue;
            }
            let f = e - c;
            let den = d.cross(f);
            let u = if den == 0.0 {
                along(if o1 == 0 { c } else { e })
            } else {
                ((c - a).cross(f) / den).clamp(0.0, 1.0)
            };
            cuts.push(u);
        }
        Some(())
    }

    /// The winding number of `p` around the outline. `eps_abs` (user units, > 0)
    /// is the distance to a curve below which the answer is only a best guess.
    ///
    /// A large outline builds its grid of cells for the `eps_abs` of its first query
    /// and answers from it the queries with no larger `eps_abs` whose cell can tell;
    /// the answer is always the one the full ray cast gives.
    pub(crate) fn winding(&self, p: Point, eps_abs: f64) -> Winding {
        if self.pieces.len() >= CELLS_MIN_PIECES
            && self.is_near_box(p, eps_abs * 0.25)
            && let Some(cells) = self
                .cells
                .get_or_init(|| cells::Cells::build(self, eps_abs))
            && let Some(w) = cells.winding(self, p, eps_abs)
        {
            return w;
        }
        self.winding_banded(p, eps_abs)
    }

    /// Whether `p` is within `margin` of the outline's box.
    fn is_near_box(&self, p: Point, margin: f64) -> bool {
        self.bbox.is_some_and(|bb| {
            p.x >= bb.x0 - margin
                && p.x <= bb.x1 + margin
                && p.y >= bb.y0 - margin
                && p.y <= bb.y1 + margin
        })
    }

    /// [`Outline::winding`] by the full ray cast (the pieces of `p`'s band).
    fn winding_banded(&self, p: Point, eps_abs: f64) -> Winding {
        let margin = eps_abs * 0.25;
        let Some(bb) = self.bbox else {
            return Winding::Clear(0);
        };
        if p.x < bb.x0 - margin
            || p.x > bb.x1 + margin
            || p.y < bb.y0 - margin
            || p.y > bb.y1 + margin
        {
            return Winding::Clear(0);
        }
        let mut acc = Acc::default();
        // A piece whose vertical extent misses p.y (by more than the margin) adds
        // nothing: its chord misses the ray and p is outside its box.
        for &i in self.band_of(p.y).unwrap_or(&[]) {
            match self.pieces[i as usize] {
                Piece::Line(a, b) => acc.line(a, b, p),
                Piece::Cubic(c) => acc.curve(c, p, eps_abs, margin),
                Piece::Conic(c) => acc.curve(c, p, eps_abs, margin),
            }
        }
        if acc.near {
            Winding::Near(acc.w)
        } else {
            Winding::Clear(acc.w)
        }
    }
}

/// The winding number of `p` around `subpaths` (each closed as SVG fills it).
/// Builds an [`Outline`] each call; prepare one for repeated queries.
#[cfg(test)]
pub(crate) fn winding(subpaths: &[Subpath], p: Point, eps_abs: f64) -> Winding {
    Outline::new(subpaths).winding(p, eps_abs)
}

/// A clip region ready for point queries (see [`Clip`]).
pub(crate) struct ClipTest {
    parts: Vec<(FillRule, Outline, Vec<ClipTest>)>,
    within: Vec<ClipTest>,
}

impl ClipTest {
    pub(crate) fn new(clip: &Clip) -> ClipTest {
        ClipTest {
            parts: clip
                .parts
                .iter()
                .map(|p| {
                    (
                        p.rule,
                        Outline::new(&p.subpaths),
                        p.clips.iter().map(|c| ClipTest::new(c)).collect(),
                    )
                })
                .collect(),
            within: clip.within.iter().map(|c| ClipTest::new(c)).collect(),
        }
    }

    /// Whether `p` is inside the clip, and whether that answer is certain
    /// (`p` clear of every outline that decided it).
    pub(crate) fn contains(&self, p: Point, eps_abs: f64) -> (bool, bool) {
        let (inside, mut clear) = all_contain(&self.within, p, eps_abs);
        if !inside {
            return (false, clear);
        }
        for (rule, outline, clips) in &self.parts {
            let w = outline.winding(p, eps_abs);
            clear &= w.is_clear();
            if w.inside(*rule) {
                let (inner, inner_clear) = all_contain(clips, p, eps_abs);
                clear &= inner_clear;
                if inner {
                    return (true, clear);
                }
            }
        }
        (false, clear)
    }
}

/// Whether `p` is inside every clip of `clips`, and whether that is certain.
pub(crate) fn all_contain(clips: &[ClipTest], p: Point, eps_abs: f64) -> (bool, bool) {
    let mut clear = true;
    for c in clips {
        let (inside, c_clear) = c.contains(p, eps_abs);
        clear &= c_clear;
        if !inside {
            return (false, clear);
        }
    }
    (true, clear)
}

/// What one filled shape paints, ready for point queries: inside its outline
/// under its fill rule and inside every clip it is painted through.
pub(crate) struct PaintTest {
    rule: FillRule,
    outline: Outline,
    clips: Vec<ClipTest>,
}

impl PaintTest {
    /// The test of `shape`'s fill (its clips included).
    pub(crate) fn new(shape: &Shape) -> PaintTest {
        PaintTest {
            rule: shape.fill_rule,
            outline: Outline::of_shape(shape),
            clips: shape.paint.clips.iter().map(|c| ClipTest::new(c)).collect(),
        }
    }

    /// Bounding box of the outline, `None` for an empty outline.
    pub(crate) fn bbox(&self) -> Option<Rect> {
        self.outline.bbox()
    }

    /// The shape's outline (its clips aside).
    pub(crate) fn outline(&self) -> &Outline {
        &self.outline
    }

    /// Whether the shape paints `p`, and whether that answer is certain (`p`
    /// clear of every outline that decided it).
    pub(crate) fn paints(&self, p: Point, eps_abs: f64) -> (bool, bool) {
        let w = self.outline.winding(p, eps_abs);
        if !w.inside(self.rule) {
            return (false, w.is_clear());
        }
        let (inside, clip_clear) = all_contain(&self.clips, p, eps_abs);
        (inside, w.is_clear() && clip_clear)
    }
}

/// The filled shapes of a drawing, topmost first, ready for point queries:
/// which shape paints a point (what `regions` labels a triangle with, and where
/// `sizing` applies a per-region size).
pub(crate) struct Painting {
    /// Each filled shape's test and the bounding box of its outline, with the
    /// shape whose region it paints (itself, or for a stroke that joins its
    /// fill, [`Drawing::joined_fill`], that fill).
    layers: Vec<(ShapeId, ShapeId, PaintTest, Rect)>,
    /// The layers by the cells of a grid their boxes meet, for drawings of
    /// many shapes (a query reads the layers near it, not all of them).
    index: Option<LayerGrid>,
    /// Each shape's layer.
    layer_of: std::collections::HashMap<ShapeId, usize>,
}

/// Fewer layers than this are scanned whole by [`Painting::owner_at`].
const SCAN_LAYERS: usize = 64;

/// A uniform grid over the layers' boxes: each cell lists, in layer order,
/// the layers whose box meets it.
struct LayerGrid {
    origin: Point,
    cell: f64,
    cols: usize,
    rows: usize,
    /// Cell `(x, y)`'s layers: `ids[starts[y * cols + x]..starts[y * cols + x + 1]]`.
    starts: Vec<u32>,
    ids: Vec<u32>,
}

impl LayerGrid {
    /// The grid of `boxes` (about one cell per box over their union), `None`
    /// when they would fill it with far more entries than boxes.
    fn new(boxes: &[Rect]) -> Option<LayerGrid> {
        let all = boxes.iter().copied().reduce(|a, b| a.union(b))?;
        let n = boxes.len();
        let side = (n as f64).sqrt().ceil().max(1.0);
        let cell = (all.width().max(all.height()) / side).max(f64::MIN_POSITIVE);
        if !(cell.is_finite() && cell > 0.0) {
            return None;
        }
        let cols = ((all.width() / cell).floor() as usize + 1).min(1 << 12);
        let rows = ((all.height() / cell).floor() as usize + 1).min(1 << 12);
        let origin = Point::new(all.x0, all.y0);
        let mut g = LayerGrid {
            origin,
            cell,
            cols,
            rows,
            starts: Vec::new(),
            ids: Vec::new(),
        };
        // Entries in all: a drawing of many large layers (each over most of
        // the grid) gets no index; its queries scan the layers.
        let entries: usize = boxes
            .iter()
            .map(|b| {
                let (x0, y0, x1, y1) = g.span(*b);
                (x1 - x0 + 1) * (y1 - y0 + 1)
            })
            .sum();
        if entries > 32 * n + (1 << 20) {
            return None;
        }
        // Two sweeps: count, then fill (layer order within each cell).
        let mut counts = vec![0u32; cols * rows + 1];
        for b in boxes {
            let (x0, y0, x1, y1) = g.span(*b);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    counts[y * cols + x] += 1;
                }
            }
        }
        let mut starts = Vec::with_capacity(counts.len());
        let mut total = 0u32;
        for c in &counts {
            starts.push(total);
            total = total.checked_add(*c)?;
        }
        let mut fill = starts.clone();
        let mut ids = vec![0u32; total as usize];
        for (k, b) in boxes.iter().enumerate() {
            let (x0, y0, x1, y1) = g.span(*b);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let slot = &mut fill[y * cols + x];
                    ids[*slot as usize] = k as u32;
                    *slot += 1;
                }
            }
        }
        g.starts = starts;
        g.ids = ids;
        Some(g)
    }

    /// The column or row of coordinate `v` from `origin` (clamped to the grid).
    fn index(&self, v: f64, o: f64, len: usize) -> usize {
        let i = ((v - o) / self.cell).floor();
        if i.is_nan() || i < 0.0 {
            0
        } else {
            (i as usize).min(len - 1)
        }
    }

    /// The cells `b` meets: columns `x0..=x1`, rows `y0..=y1`.
    fn span(&self, b: Rect) -> (usize, usize, usize, usize) {
        (
            self.index(b.x0, self.origin.x, self.cols),
            self.index(b.y0, self.origin.y, self.rows),
            self.index(b.x1, self.origin.x, self.cols),
            self.index(b.y1, self.origin.y, self.rows),
        )
    }

    /// The layers whose box may come within `r` of `p`, in layer order, into
    /// `out` (a box that meets none of the cells near `p` cannot); `false` when
    /// `p ± r` spans too many cells to be worth it (then scan all layers).
    fn near(&self, p: Point, r: f64, out: &mut Vec<u32>) -> bool {
        out.clear();
        let b = Rect::new(p.x - r, p.y - r, p.x + r, p.y + r);
        if !(b.x0.is_finite() && b.y0.is_finite() && b.x1.is_finite() && b.y1.is_finite()) {
            return false;
        }
        let (x0, y0, x1, y1) = self.span(b);
        if (x1 - x0 + 1) * (y1 - y0 + 1) > 4 {
            return false;
        }
        for y in y0..=y1 {
            for x in x0..=x1 {
                let c = y * self.cols + x;
                out.extend_from_slice(
                    &self.ids[self.starts[c] as usize..self.starts[c + 1] as usize],
                );
            }
        }
        if (x1, y1) != (x0, y0) {
            out.sort_unstable();
            out.dedup();
        }
        true
    }
}

/// Whether `shape`'s fill covers no area: every subpath lies on one line,
/// control points included (a curve stays in their convex hull), so its
/// winding number is zero everywhere off that line. A `<line>` element, filled
/// black by default, is one; it paints nothing a renderer shows, and as a
/// layer it would be tested at every query point its box holds (a drawing of
/// 2 000 random `<line>`s would spend seconds in the regions stage for a mesh
/// that is all background).
pub(crate) fn paints_nothing(shape: &Shape) -> bool {
    shape.subpaths.iter().all(|sp| {
        let mut points = std::iter::once(sp.start).chain(sp.segments.iter().flat_map(|seg| {
            let (pts, n): ([Point; 4], usize) = match seg {
                Segment::Line(l) => ([l.p0, l.p1, l.p1, l.p1], 2),
                Segment::Cubic(c) => ([c.p0, c.p1, c.p2, c.p3], 4),
                Segment::Conic(c) => ([c.p0, c.p1, c.p2, c.p2], 3),
            };
            pts.into_iter().take(n)
        }));
        let Some(a) = points.next() else {
            return true;
        };
        let mut b = None;
        points.all(|p| match b {
            _ if p == a => true,
            None => {
                b = Some(p);
                true
            }
            Some(b) => orient2d(a, b, p) == Orientation::Collinear,
        })
    })
}

impl Painting {
    /// The filled shapes of `drawing` whose fill covers some area
    /// ([`paints_nothing`]); topmost first, equal paint orders falling back
    /// to document order.
    pub(crate) fn new(drawing: &Drawing) -> Painting {
        let mut layers: Vec<(u32, ShapeId, PaintTest, Rect)> = drawing
            .shapes
            .iter()
            .enumerate()
            .filter(|(_, s)| s.filled && !paints_nothing(s))
            .filter_map(|(i, s)| {
                let t = PaintTest::new(s);
                let bb = t.bbox()?;
                Some((s.paint_order, ShapeId::from_index(i), t, bb))
            })
            .collect();
        layers.sort_by_key(|l| std::cmp::Reverse((l.0, l.1)));
        let layers: Vec<_> = layers
            .into_iter()
            .map(|(_, id, t, bb)| (drawing.joined_fill(id).unwrap_or(id), id, t, bb))
            .collect();
        let index = (layers.len() > SCAN_LAYERS)
            .then(|| LayerGrid::new(&layers.iter().map(|l| l.3).collect::<Vec<_>>()))
            .flatten();
        let layer_of = layers.iter().enumerate().map(|(k, l)| (l.1, k)).collect();
        Painting {
            layers,
            index,
            layer_of,
        }
    }

    /// The shapes that own a region, topmost first (a stroke that joins its
    /// fill is not one: its area is the fill's region).
    pub(crate) fn shapes(&self) -> impl Iterator<Item = ShapeId> + '_ {
        self.layers.iter().filter(|l| l.0 == l.1).map(|l| l.0)
    }

    /// Whether shape `id`'s own fill paints `p` (see [`PaintTest::paints`]);
    /// `false` for a shape that is not a layer.
    pub(crate) fn shape_paints(&self, id: ShapeId, p: Point, eps_abs: f64) -> bool {
        self.layer_of
            .get(&id)
            .is_some_and(|&k| self.layers[k].2.paints(p, eps_abs).0)
    }

    /// The topmost region covering `p` (a shape, or the fill a stroke joins),
    /// and whether that answer is certain: it is
    /// unless `p` is within `eps_abs` of the outline of a shape at or above the
    /// answer. A shape whose outline's box, grown by `eps_abs`, misses `p` is
    /// skipped: it neither paints `p` nor passes near it.
    pub(crate) fn owner_at(&self, p: Point, eps_abs: f64) -> (Option<ShapeId>, bool) {
        if let Some(g) = &self.index {
            let mut near = Vec::new();
            if g.near(p, eps_abs, &mut near) {
                return self.owner_among(
                    near.iter().map(|&k| &self.layers[k as usize]),
                    p,
                    eps_abs,
                );
            }
        }
        self.owner_among(self.layers.iter(), p, eps_abs)
    }

    /// [`Painting::owner_at`] over `layers` (topmost first): all of them, or
    /// those the grid finds near `p` (every layer whose grown box holds `p`
    /// is among them).
    fn owner_among<'a>(
        &'a self,
        layers: impl Iterator<Item = &'a (ShapeId, ShapeId, PaintTest, Rect)>,
        p: Point,
        eps_abs: f64,
    ) -> (Option<ShapeId>, bool) {
        let mut clear = true;
        for (id, _, test, bb) in layers {
            let near_box = p.x >= bb.x0 - eps_abs
                && p.x <= bb.x1 + eps_abs
                && p.y >= bb.y0 - eps_abs
                && p.y <= bb.y1 + eps_abs;
            if !near_box {
                continue;
            }
            let (inside, layer_clear) = test.paints(p, eps_abs);
            clear &= layer_clear;
            if inside {
                return (Some(*id), clear);
            }
        }
        (None, clear)
    }
}

#[derive(Default)]
struct Acc {
    w: i32,
    near: bool,
}

impl Acc {
    /// Exact crossing of the +x ray from `p` with the segment a→b (half-open rule).
    fn line(&mut self, a: Point, b: Point, p: Point) {
        if p == a || p == b {
            self.near = true;
            return;
        }
        if a.y <= p.y && p.y < b.y {
            match orient2d(a, b, p) {
                Orientation::CounterClockwise => self.w += 1,
                Orientation::Collinear => self.near = true,
                Orientation::Clockwise => {}
            }
        } else if b.y <= p.y && p.y < a.y {
            match orient2d(a, b, p) {
                Orientation::Clockwise => self.w -= 1,
                Orientation::Collinear => self.near = true,
                Orientation::CounterClockwise => {}
            }
        } else if a.y == p.y && b.y == p.y && (a.x.min(b.x) <= p.x && p.x <= a.x.max(b.x)) {
            self.near = true;
        }
    }

    /// Crossings of the +x ray from `p` with a cubic or a conic, by subdivision
    /// until each piece's control box excludes `p` (then the chord stands for the piece).
    fn curve<C: Halving>(&mut self, c: C, p: Point, eps_abs: f64, margin: f64) {
        let mut stack = vec![(c, 0u32)];
        let mut budget = MAX_PIECES;
        while let Some((c, depth)) = stack.pop() {
            let b = c.control_box();
            let (a, z) = c.ends();
            let outside = p.x < b.x0 - margin
                || p.x > b.x1 + margin
                || p.y < b.y0 - margin
                || p.y > b.y1 + margin;
            if outside {
                if p.y >= b.y0 && p.y <= b.y1 {
                    self.line(a, z, p);
                }
                continue;
            }
            let small = b.width().max(b.height()) <= eps_abs;
            if small || depth >= MAX_DEPTH || budget < 2 {
                // p is within about eps_abs of the curve: best effort with the chord.
                self.line(a, z, p);
                self.near = true;
                continue;
            }
            budget -= 2;
            let (l, r) = c.halves();
            stack.push((r, depth + 1));
            stack.push((l, depth + 1));
        }
    }
}

/// A curve piece that lies in the box of its control points and can be halved.
trait Halving: Sized {
    /// The bounding box of the controls (it contains the curve).
    fn control_box(&self) -> Rect;
    /// Start and end point.
    fn ends(&self) -> (Point, Point);
    /// The two halves; their joint is shared bit for bit.
    fn halves(&self) -> (Self, Self);
}

impl Halving for CubicBez {
    fn control_box(&self) -> Rect {
        control_bbox(self)
    }
    fn ends(&self) -> (Point, Point) {
        (self.p0, self.p3)
    }
    fn halves(&self) -> (Self, Self) {
        split_half(self)
    }
}

/// For a conic of positive weight (the curve lies in its control triangle).
impl Halving for Conic {
    fn control_box(&self) -> Rect {
        conic_bbox(self)
    }
    fn ends(&self) -> (Point, Point) {
        (self.p0, self.p2)
    }
    fn halves(&self) -> (Self, Self) {
        // Both take the midpoint from `eval(0.5)`, bit for bit the same.
        (self.subsegment(0.0, 0.5), self.subsegment(0.5, 1.0))
    }
}

/// de Casteljau split at t = ½; the midpoint is shared bit for bit.
fn split_half(c: &CubicBez) -> (CubicBez, CubicBez) {
    let m = |a: Point, b: Point| Point::new(0.5 * (a.x + b.x), 0.5 * (a.y + b.y));
    let p01 = m(c.p0, c.p1);
    let p12 = m(c.p1, c.p2);
    let p23 = m(c.p2, c.p3);
    let p012 = m(p01, p12);
    let p123 = m(p12, p23);
    let mid = m(p012, p123);
    (
        CubicBez::new(c.p0, p01, p012, mid),
        CubicBez::new(mid, p123, p23, c.p3),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use kurbo::{Line, ParamCurve, Vec2};
    use proptest::prelude::*;
    use std::f64::consts::PI;

    fn open(points: &[Point]) -> Subpath {
        Subpath {
            segments: points
                .windows(2)
                .map(|w| Segment::Line(Line::new(w[0], w[1])))
                .collect(),
            start: points[0],
            closed: false,
        }
    }

    fn closed(points: &[Point]) -> Subpath {
        let mut pts = points.to_vec();
        pts.push(points[0]);
        Subpath {
            closed: true,
            ..open(&pts)
        }
    }

    /// A segment through a square is cut where it enters and leaves it; one
    /// along a side is unsure there; one through a curve's control box is
    /// unsure across the box; one clear of the outline meets nothing.
    #[test]
    fn a_segment_meets_the_outline_where_it_crosses_or_may_touch_it() {
        let square = Outline::new(&[closed(&[
            Point::new(0.0, 0.0),
            Point::new(4.0, 0.0),
            Point::new(4.0, 4.0),
            Point::new(0.0, 4.0),
        ])]);
        let meet = |outline: &Outline, a: (f64, f64), b: (f64, f64)| {
            let (mut cuts, mut unsure) = (Vec::new(), Vec::new());
            outline
                .meet_segment((a.into(), b.into()), 64, &mut cuts, &mut unsure)
                .expect("few pieces");
            cuts.sort_by(f64::total_cmp);
            (cuts, unsure)
        };
        let (cuts, unsure) = meet(&square, (-2.0, 2.0), (6.0, 2.0));
        assert_eq!(cuts, [0.25, 0.75]);
        assert!(unsure.is_empty());
        let (_, unsure) = meet(&square, (-4.0, 0.0), (8.0, 0.0));
        assert!(
            unsure
                .iter()
                .any(|r| (r[0] - 1.0 / 3.0).abs() < 1e-12 && (r[1] - 2.0 / 3.0).abs() < 1e-12),
            "{unsure:?}"
        );
        assert_eq!(meet(&square, (1.0, 1.0), (3.0, 3.0)), (vec![], vec![]));
        let round = Outline::new(&[circle(Point::new(0.0, 0.0), 1.0)]);
        let (cuts, unsure) = meet(&round, (-2.0, 0.5), (2.0, 0.5));
        assert!(cuts.is_empty() && !unsure.is_empty());
        assert!(
            square
                .meet_segment(
                    (Point::new(-1.0, 2.0), Point::new(5.0, 2.0)),
                    1,
                    &mut Vec::new(),
                    &mut Vec::new()
                )
                .is_none()
        );
    }

    /// A circle as 4 cubics (the standard k = 0.5523 construction), counter-clockwise.
    pub(crate) fn circle(c: Point, r: f64) -> Subpath {
        let k = 4.0 / 3.0 * (2f64.sqrt() - 1.0) * r;
        let p = |x: f64, y: f64| Point::new(c.x + x, c.y + y);
        let segs = vec![
            CubicBez::new(p(r, 0.0), p(r, k), p(k, r), p(0.0, r)),
            CubicBez::new(p(0.0, r), p(-k, r), p(-r, k), p(-r, 0.0)),
            CubicBez::new(p(-r, 0.0), p(-r, -k), p(-k, -r), p(0.0, -r)),
            CubicBez::new(p(0.0, -r), p(k, -r), p(r, -k), p(r, 0.0)),
        ];
        Subpath {
            segments: segs.into_iter().map(Segment::Cubic).collect(),
            start: p(r, 0.0),
            closed: true,
        }
    }

    /// The exact circle: four quarter conics, counter-clockwise.
    pub(crate) fn conic_circle(c: Point, r: f64) -> Subpath {
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let p = |x: f64, y: f64| Point::new(c.x + x * r, c.y + y * r);
        let segs = vec![
            Conic::new(p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0), w),
            Conic::new(p(0.0, 1.0), p(-1.0, 1.0), p(-1.0, 0.0), w),
            Conic::new(p(-1.0, 0.0), p(-1.0, -1.0), p(0.0, -1.0), w),
            Conic::new(p(0.0, -1.0), p(1.0, -1.0), p(1.0, 0.0), w),
        ];
        Subpath {
            segments: segs.into_iter().map(Segment::Conic).collect(),
            start: p(1.0, 0.0),
            closed: true,
        }
    }

    /// A five-pointed star {5/2} (self-intersecting pentagram).
    pub(crate) fn star(c: Point, r: f64) -> Subpath {
        let pts: Vec<Point> = (0..5)
            .map(|i| {
                let a = PI / 2.0 + i as f64 * 4.0 * PI / 5.0;
                Point::new(c.x + r * a.cos(), c.y + r * a.sin())
            })
            .collect();
        closed(&pts)
    }

    const EPS: f64 = 1e-9;

    #[test]
    fn circle_inside_outside_and_near() {
        let s = [circle(Point::ZERO, 1.0)];
        assert_eq!(winding(&s, Point::ZERO, EPS), Winding::Clear(1));
        assert_eq!(winding(&s, Point::new(0.7, 0.7), EPS), Winding::Clear(1));
        assert_eq!(winding(&s, Point::new(0.72, 0.72), EPS), Winding::Clear(0));
        assert_eq!(winding(&s, Point::new(2.0, 0.0), EPS), Winding::Clear(0));
        // On the ray through the joints (y = 0) and through a cubic's extremum (y = 1 - 1e-12).
        assert_eq!(winding(&s, Point::new(-0.5, 0.0), EPS), Winding::Clear(1));
        assert_eq!(
            winding(&s, Point::new(0.0, 1.0 - 1e-6), EPS),
            Winding::Clear(1)
        );
        assert_eq!(
            winding(&s, Point::new(0.0, 1.0 + 1e-6), EPS),
            Winding::Clear(0)
        );
        assert_eq!(winding(&s, Point::new(-3.0, 1.0), EPS), Winding::Clear(0));
        // Exactly on a joint, and closer than eps to the curve.
        assert!(!winding(&s, Point::new(1.0, 0.0), EPS).is_clear());
        assert!(!winding(&s, Point::new(0.0, 1.0 - 1e-11), EPS).is_clear());
        // The Bézier circle bulges slightly beyond the unit circle between its
        // joints and midpoints (radius 1.000 27 near t = 0.2); just inside and
        // just outside the curve along that ray (the curve is star-shaped).
        let q = circle(Point::ZERO, 1.0).segments[0]
            .to_cubic()
            .eval(0.2)
            .to_vec2();
        assert!(q.length() > 1.0002, "{}", q.length());
        let dir = q.normalize();
        assert_eq!(
            winding(&s, (dir * (q.length() - 1e-7)).to_point(), EPS),
            Winding::Clear(1)
        );
        assert_eq!(
            winding(&s, (dir * (q.length() + 1e-7)).to_point(), EPS),
            Winding::Clear(0)
        );
    }

    #[test]
    fn exact_circle_of_conics_is_the_true_circle() {
        let c = Point::new(3.0, -2.0);
        let s = [conic_circle(c, 2.0)];
        // Where the cubic circle bulges out (radius 1.000 27 at its t = 0.2), the
        // exact circle does not: in and out 1e-7 around radius 2, at many angles
        // (including the joints and the rays through them).
        for k in 0..360 {
            let a = f64::from(k) * PI / 180.0;
            let u = Vec2::from_angle(a);
            assert_eq!(
                winding(&s, c + u * (2.0 - 1e-7), EPS),
                Winding::Clear(1),
                "{k}°"
            );
            assert_eq!(
                winding(&s, c + u * (2.0 + 1e-7), EPS),
                Winding::Clear(0),
                "{k}°"
            );
        }
        assert_eq!(winding(&s, c, EPS), Winding::Clear(1));
        // On the circle (a joint, and a point between): not certain.
        assert!(!winding(&s, Point::new(5.0, -2.0), EPS).is_clear());
        let on = s[0].segments[1].to_cubic().p0; // the joint at the top
        assert!(!winding(&s, on, EPS).is_clear());
        let Segment::Conic(q) = s[0].segments[2] else {
            panic!("a conic")
        };
        assert!(!winding(&s, q.eval(0.3), EPS).is_clear());
        // A conic of non-positive weight counts as its chord.
        let mut bad = conic_circle(c, 2.0);
        if let Segment::Conic(q) = &mut bad.segments[0] {
            q.w = -1.0;
        }
        let bad = [bad];
        assert_eq!(
            winding(&bad, c + Vec2::new(1.2, 1.2), EPS),
            Winding::Clear(0)
        );
        assert_eq!(
            winding(&bad, c + Vec2::new(0.9, 0.9), EPS),
            Winding::Clear(1)
        );
    }

    #[test]
    fn clockwise_circle_winds_negatively() {
        let mut c = circle(Point::ZERO, 1.0);
        c.segments.reverse();
        for s in &mut c.segments {
            let k = s.to_cubic();
            *s = Segment::Cubic(CubicBez::new(k.p3, k.p2, k.p1, k.p0));
        }
        let w = winding(&[c], Point::new(0.1, 0.2), EPS);
        assert_eq!(w, Winding::Clear(-1));
        assert!(w.inside(FillRule::NonZero) && w.inside(FillRule::EvenOdd));
    }

    #[test]
    fn star_centre_winds_twice_points_once() {
        let s = [star(Point::ZERO, 1.0)];
        let centre = winding(&s, Point::new(0.01, 0.02), EPS);
        assert_eq!(centre.number().abs(), 2);
        assert!(centre.inside(FillRule::NonZero));
        assert!(!centre.inside(FillRule::EvenOdd));
        let tip = winding(&s, Point::new(0.0, 0.9), EPS);
        assert_eq!(tip.number().abs(), 1);
        assert!(tip.inside(FillRule::EvenOdd));
        assert_eq!(winding(&s, Point::new(0.0, -0.9), EPS), Winding::Clear(0));
    }

    #[test]
    fn open_subpath_is_closed_by_a_straight_segment() {
        // A square with its left side missing: SVG fill closes it.
        let sq = [open(&[
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(1.0, 1.0),
            Point::new(0.0, 1.0),
        ])];
        assert_eq!(winding(&sq, Point::new(0.5, 0.5), EPS).number().abs(), 1);
        assert_eq!(winding(&sq, Point::new(0.05, 0.95), EPS).number().abs(), 1);
        assert_eq!(winding(&sq, Point::new(-0.05, 0.5), EPS), Winding::Clear(0));
        // On the implicit closing segment itself.
        assert!(!winding(&sq, Point::new(0.0, 0.5), EPS).is_clear());
        // A circle with a small gap (the last cubic ends short of the start).
        let mut c = circle(Point::ZERO, 1.0);
        c.closed = false;
        if let Some(Segment::Cubic(k)) = c.segments.last_mut() {
            k.p3 = Point::new(1.0, -0.01);
        }
        let c = [c];
        assert_eq!(winding(&c, Point::ZERO, EPS), Winding::Clear(1));
        assert_eq!(
            winding(&c, Point::new(0.999, -0.005), EPS),
            Winding::Clear(1)
        );
        assert_eq!(
            winding(&c, Point::new(1.001, -0.005), EPS),
            Winding::Clear(0)
        );
    }

    #[test]
    fn rays_through_vertices_and_horizontal_edges_count_once() {
        // A polygon with a horizontal edge and vertices at the query's height.
        let poly = [closed(&[
            Point::new(0.0, 0.0),
            Point::new(4.0, 0.0),
            Point::new(4.0, 2.0),
            Point::new(3.0, 1.0),
            Point::new(2.0, 1.0),
            Point::new(1.0, 2.0),
            Point::new(0.0, 1.0),
        ])];
        assert_eq!(winding(&poly, Point::new(0.5, 1.0), EPS), Winding::Clear(1));
        assert_eq!(
            winding(&poly, Point::new(-1.0, 1.0), EPS),
            Winding::Clear(0)
        );
        assert_eq!(winding(&poly, Point::new(2.5, 1.5), EPS), Winding::Clear(0));
        assert_eq!(winding(&poly, Point::new(3.5, 2.0), EPS), Winding::Clear(0));
        assert_eq!(
            winding(&poly, Point::new(-1.0, 2.0), EPS),
            Winding::Clear(0)
        );
        assert!(!winding(&poly, Point::new(2.5, 1.0), EPS).is_clear());
    }

    /// Shapes whose fill covers no area are no layers: a `<line>` (filled
    /// black by default), a collinear polyline, a flat cubic and a flat
    /// two-part path; a shape with one point off the line is one. A point
    /// on the lines belongs to the rectangle under them, with certainty.
    #[test]
    fn shapes_that_paint_nothing_are_no_layers() {
        let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
            <rect x="10" y="10" width="80" height="80" fill="#123456"/>
            <line x1="0" y1="0" x2="100" y2="100" stroke="#000" stroke-width="0.001"/>
            <polyline points="0,50 20,50 60,50 40,50" stroke="#000" stroke-width="0.001"/>
            <path d="M0 30 C 30 30 10 30 100 30 M 50 0 L 50 100" stroke="#000" stroke-width="0.001"/>
            <polyline points="0,70 20,70 60,70 40,70.001" fill="#ff0000"/>
        </svg>"##;
        let drawing = crate::svg::load_bytes(svg.as_bytes(), &crate::svg::LoadOptions::DEFAULT)
            .expect("a drawing");
        assert!(drawing.shapes.iter().all(|s| s.filled));
        let flags: Vec<bool> = drawing.shapes.iter().map(paints_nothing).collect();
        assert_eq!(flags, [false, true, true, true, false]);
        let painting = Painting::new(&drawing);
        assert_eq!(painting.layers.len(), 2);
        // (y points up in the drawing: y = -y_svg)
        for p in [
            Point::new(50.0, -50.0),
            Point::new(30.0, -30.0),
            Point::new(50.0, -20.0),
        ] {
            assert_eq!(
                painting.owner_at(p, 1e-6),
                (Some(ShapeId::from_index(0)), true),
                "{p:?}"
            );
        }
    }

    #[test]
    fn degenerate_outlines_wind_zero() {
        assert_eq!(winding(&[], Point::ZERO, EPS), Winding::Clear(0));
        let dot = Subpath {
            segments: vec![],
            start: Point::ZERO,
            closed: false,
        };
        assert_eq!(
            winding(&[dot], Point::new(1.0, 0.0), EPS),
            Winding::Clear(0)
        );
        let pt = Point::new(1.0, 1.0);
        let zero = Subpath {
            segments: vec![Segment::Cubic(CubicBez::new(pt, pt, pt, pt))],
            start: pt,
            closed: true,
        };
        assert_eq!(
            winding(std::slice::from_ref(&zero), Point::ZERO, EPS),
            Winding::Clear(0)
        );
        assert!(!winding(&[zero], pt, EPS).is_clear());
    }

    #[test]
    fn cubic_loop_self_intersection() {
        // A cubic whose control polygon makes it loop: winding differs inside the loop.
        let c = CubicBez::new((0.0, 0.0), (3.0, 3.0), (-1.0, 3.0), (2.0, 0.0));
        let sp = Subpath {
            segments: vec![Segment::Cubic(c)],
            start: c.p0,
            closed: false,
        };
        // Compare with a fine polygon of the same curve, far from the curve.
        let mut pts: Vec<Point> = (0..=20_000).map(|i| c.eval(i as f64 / 20_000.0)).collect();
        pts.pop();
        let poly = Outline::new(&[open(&pts)]);
        let curve = Outline::new(&[sp]);
        let mut checked = 0;
        for i in 0..40 {
            for j in 0..40 {
                let p = Point::new(-0.5 + i as f64 * 0.07, -0.3 + j as f64 * 0.07);
                let (a, b) = (curve.winding(p, 1e-3), poly.winding(p, 1e-3));
                if a.is_clear() {
                    assert_eq!(a.number(), b.number(), "at {p:?}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000);
    }

    /// Reference: the winding number of a polygon by summing signed angles,
    /// rounded (only used on points well away from the edges).
    fn angle_winding(pts: &[Point], p: Point) -> i32 {
        let mut total = 0.0;
        for i in 0..pts.len() {
            let a = pts[i] - p;
            let b = pts[(i + 1) % pts.len()] - p;
            total += a.cross(b).atan2(a.dot(b));
        }
        (total / (2.0 * PI)).round() as i32
    }

    fn seg_dist(p: Point, a: Point, b: Point) -> f64 {
        use kurbo::ParamCurveNearest;
        Line::new(a, b).nearest(p, 0.0).distance_sq.sqrt()
    }

    /// Exactly on the closed segment a–b.
    fn on_segment(p: Point, a: Point, b: Point) -> bool {
        orient2d(a, b, p) == Orientation::Collinear
            && a.x.min(b.x) <= p.x
            && p.x <= a.x.max(b.x)
            && a.y.min(b.y) <= p.y
            && p.y <= a.y.max(b.y)
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 256,
            failure_persistence: None,
            rng_seed: proptest::test_runner::RngSeed::Fixed(7),
            ..ProptestConfig::default()
        })]

        /// On straight inputs, the winding number equals the polygon's exact
        /// winding number (angle sum, or orientation tests where the angle sum is
        /// not reliable), including integer grid points on vertices and edges.
        #[test]
        fn matches_polygon_winding(
            verts in proptest::collection::vec((-8i32..8, -8i32..8), 3..12),
            queries in proptest::collection::vec((-18i32..18, -18i32..18), 20),
            scale_exp in -30i32..30,
        ) {
            let s = 2f64.powi(scale_exp);
            let pts: Vec<Point> = verts.iter().map(|&(x, y)| Point::new(x as f64 * s, y as f64 * s)).collect();
            let outline = Outline::new(&[open(&pts)]);
            for &(qx, qy) in &queries {
                // Half-integer grid: often on rays through vertices and horizontal edges.
                let p = Point::new(qx as f64 * 0.5 * s, qy as f64 * 0.5 * s);
                let w = outline.winding(p, 1e-9 * s);
                let on_edge = (0..pts.len()).any(|i| on_segment(p, pts[i], pts[(i + 1) % pts.len()]));
                prop_assert_eq!(w.is_clear(), !on_edge, "p {:?}", p);
                if !on_edge {
                    prop_assert_eq!(w.number(), angle_winding(&pts, p), "p {:?}", p);
                }
            }
        }

        /// With more layers than are scanned whole, the grid's owner of a point
        /// is the whole scan's (same shape, same certainty), on and off the
        /// outlines, with layers of every size (a background over all of them).
        #[test]
        fn indexed_owner_matches_the_scan(
            rects in proptest::collection::vec((0i32..200, 0i32..200, 1i32..6, 1i32..6), 65..160),
            grid_queries in proptest::collection::vec((-4i32..420, -4i32..420), 40),
            queries in proptest::collection::vec((-5.0f64..210.0, -5.0f64..210.0), 200),
            eps_exp in -8i32..4,
        ) {
            let mut svg = String::from(r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 210 210">"#);
            svg.push_str(r##"<rect x="-1" y="-1" width="212" height="212" fill="#123456"/>"##);
            for (k, &(x, y, w, h)) in rects.iter().enumerate() {
                svg.push_str(&format!(
                    r##"<rect x="{x}" y="{y}" width="{w}" height="{h}" fill="#{:06x}"/>"##,
                    (k * 7919) % 0xffffff
                ));
            }
            svg.push_str("</svg>");
            let drawing = crate::svg::load_bytes(svg.as_bytes(), &crate::svg::LoadOptions::DEFAULT).expect("a drawing");
            let painting = Painting::new(&drawing);
            prop_assert!(painting.index.is_some());
            let eps = 2f64.powi(eps_exp);
            // Half-integer grid points (on outlines, corners and between
            // them), and points anywhere (near outlines in other cells).
            let points = grid_queries
                .iter()
                .map(|&(qx, qy)| Point::new(f64::from(qx) * 0.5, f64::from(qy) * 0.5))
                .chain(queries.iter().map(|&(x, y)| Point::new(x, y)));
            for p in points {
                let scan = painting.owner_among(painting.layers.iter(), p, eps);
                prop_assert_eq!(painting.owner_at(p, eps), scan, "p {:?}", p);
                // Every layer whose box grown by eps holds p is near p.
                let mut near = Vec::new();
                if painting.index.as_ref().is_some_and(|g| g.near(p, eps, &mut near)) {
                    for (k, l) in painting.layers.iter().enumerate() {
                        let b = l.3.inflate(eps, eps);
                        if b.contains(p) {
                            prop_assert!(near.contains(&(k as u32)), "layer {} at {:?}", k, p);
                        }
                    }
                }
            }
        }

        /// The same polygon given with its straight edges as (degree-elevated)
        /// cubics gives the same winding numbers away from the edges.
        #[test]
        fn cubic_lines_match_lines(
            verts in proptest::collection::vec((-1000.0f64..1000.0, -1000.0f64..1000.0), 3..10),
            queries in proptest::collection::vec((-1100.0f64..1100.0, -1100.0f64..1100.0), 20),
        ) {
            let mut pts: Vec<Point> = verts.iter().map(|&(x, y)| Point::new(x, y)).collect();
            pts.push(pts[0]);
            let lines = open(&pts);
            let cubics = Subpath {
                segments: lines.segments.iter().map(|s| Segment::Cubic(s.to_cubic())).collect(),
                ..lines.clone()
            };
            let (a, b) = (Outline::new(&[lines]), Outline::new(&[cubics]));
            for &(x, y) in &queries {
                let p = Point::new(x, y);
                let wb = b.winding(p, 1e-6);
                if wb.is_clear() {
                    prop_assert_eq!(a.winding(p, 1e-6), wb);
                }
                let d = (0..pts.len() - 1).map(|i| seg_dist(p, pts[i], pts[i + 1])).fold(f64::INFINITY, f64::min);
                if d > 1e-5 {
                    prop_assert!(wb.is_clear());
                }
            }
        }
    }
}
