//! Trimming derived outlines to where they bound what is painted.
//!
//! The loader's paint model adds outlines that are not all boundary of the
//! picture: a stroke's painted area is kurbo's stroke outline filled by the
//! nonzero rule, and its inner joins (and a dashed or self-overlapping path's
//! overlaps) loop back inside the area; a clipped fill's outline runs on
//! outside its clip; a clip's outline runs on outside what it clips. Kept whole,
//! those pieces are features the mesh must conform to: needles where an inner
//! join loop nearly touches the outline, triangles spent on geometry nobody
//! sees.
//!
//! After the crossing splits every piece of such an outline lies, between two
//! consecutive crossings, either on the boundary of what its shape paints or
//! not (the paint test changes only across the outlines that define it, and
//! those cross the piece only at its split points). A piece is judged at three
//! inner points: at each, the shape's paint test (fill rule and clips, the
//! regions stage's own test, [`PaintTest`]) is evaluated a small step to
//! either side. The piece is dropped only when every test is certain and no
//! side differs: anything uncertain keeps it, so trimming can cost at most an
//! unneeded feature, never a region boundary.
//!
//! The tests are built on the outlines as drawn, so a piece is judged on its
//! curve as drawn. Snapping (step 0) moves a curve whose end it joins to a
//! neighbour's by up to l_m, ten times the side step: judged where it moved to,
//! a piece of an outline can have both sides off the drawn outline, on one
//! side of it, and be dropped as bounding nothing (a stroke's bend whose join
//! pieces were shorter than l_m lost its outer offset that way, and the strip
//! its boundary). A piece of a moved curve is therefore also judged on the
//! curve before snapping, at the same parameters, and dropped only when both
//! judgements find it bounds nothing. (The drawn curve alone would not do: its
//! crossings lie where they were before snapping, so near a window's end its
//! samples may belong to the neighbouring piece.)
//!
//! What is judged:
//! - a stroke area ([`ShapeKind::Stroke`]) and a clipped fill: by its own test;
//! - a stroke that joins its element's fill ([`crate::svg::drawing::ShapePaint::joins_fill`])
//!   and that fill: by the union of their tests (one region): the fill's
//!   outline under the stroke and the stroke's inner outline bound nothing;
//! - a clip or mask outline ([`ShapeKind::ClipOutline`]): by the tests of the
//!   filled shapes painted through that clip (kept where any of them changes);
//! - a clipped centre line (an unfilled element): kept where it lies inside its
//!   clips;
//! - an unclipped fill under its own element's opaque stroke (painted right
//!   over it, another region): dropped where the stroke paints both of its
//!   sides. The fill's outline runs in the middle of the stroke, half its width
//!   from both of the stroke's outlines: kept, it would make a stroke only
//!   twice μ wide fail the μ-separation, whatever else the drawing holds.
//!
//! A stroke area's straight outline is also dropped where a shape painted
//! above it covers it: a filled, fully opaque, unclipped shape later in the
//! paint order (its region then owns both sides, whatever the region mode).
//! Such a cover need not cross the outline where the crossing search split it
//! (it splits a piece at most `MAX_PER_PIECE` times), so the covered stretches
//! are found on their own ([`Trimmer::covered`]): the outline is cut where it
//! meets each covering shape's outline (straight pieces decided exactly,
//! curved ones kept clear of by their control boxes) and a stretch between two
//! cuts is covered when the shape certainly paints its middle. A stroke soup
//! many strokes deep (random lines, a fan of lines through one point) keeps
//! only the outlines the picture shows, and with them the crossings the BSP
//! meets (`pipeline::density` counts what is left, and each cut here as a
//! vertex where a kept outline ends on another).
//!
//! Other unclipped fills and centre lines are never trimmed: every input curve
//! of the drawing stays a feature, as in TriWild.

use super::Parent;
use super::grid::Grid;
use crate::svg::drawing::{ShapeKind, collect_clips};
use crate::svg::winding::{ClipTest, PaintTest, all_contain, paints_nothing};
use crate::svg::{Clip, Drawing, ShapeId};
use kurbo::{Point, Rect, Vec2};
use std::sync::Arc;

/// Fractions of a piece where it is judged.
const SAMPLES: [f64; 3] = [0.5, 0.25, 0.75];
/// The side step, as a fraction of the drawing's diagonal d (at most; a tenth
/// of the narrowest stroke meshed as an area, l_min = 1e-4·d).
const STEP_REL: f64 = 1e-5;
/// The side step as a fraction of the piece's chord (at most).
const STEP_CHORD: f64 = 1e-3;

/// How one shape's pieces are judged.
enum Judge {
    /// Never trimmed.
    Keep,
    /// Kept where the test differs across the piece.
    Boundary(Vec<u32>),
    /// Kept where the union of the tests differs across the piece (a stroke
    /// and the fill it joins).
    Union(Vec<u32>),
    /// Kept where the piece lies inside these clips (a clipped centre line).
    Inside(Vec<ClipTest>),
    /// Kept unless this test (an opaque stroke painted over the piece's fill)
    /// certainly paints both sides of it: a fill's outline under its own
    /// stroke bounds nothing the picture shows, and kept it lies half the
    /// stroke's width from both of the stroke's outlines.
    Covered(u32),
}

/// The trimming tests of a drawing's shapes.
pub(super) struct Trimmer {
    judges: Vec<Judge>,
    tests: Vec<PaintTest>,
    eps_abs: f64,
    step: f64,
    covers: Covers,
}

/// A covering shape's outline is examined against a straight piece only
/// when at most this many of its pieces share the piece's vertical extent
/// (else the piece is not judged against it: a crossed hatch drawn as two
/// paths of 10 000 lines would pair every line with every other).
const COVER_MAX_PIECES: usize = 256;

/// Most boxes a piece's run has for the search of its covers (a longer
/// piece's boxes are longer than a cell).
const COVER_MAX_STEPS: f64 = 4096.0;

/// The opaque shapes that may cover a stroke's outline (see the module doc):
/// filled, fully opaque, not clipped, painting some area; each with its place
/// in the paint order (paint order, then shape index: larger is on top) and
/// its test, found through a grid of their boxes.
struct Covers {
    /// By shape index: its place in the paint order, and whether its
    /// straight pieces are judged against the covers (a stroke's area).
    order: Vec<(u64, bool)>,
    /// The covering shapes: place in the paint order, test.
    layers: Vec<(u64, PaintTest)>,
    grid: Option<Grid>,
}

impl Covers {
    fn new(drawing: &Drawing) -> Covers {
        let order: Vec<(u64, bool)> = drawing
            .shapes
            .iter()
            .enumerate()
            .map(|(i, s)| {
                (
                    (u64::from(s.paint_order) << 32) | i as u64,
                    s.paint.kind == ShapeKind::Stroke,
                )
            })
            .collect();
        let mut layers: Vec<(u64, PaintTest)> = Vec::new();
        let mut boxes: Vec<Rect> = Vec::new();
        if order.iter().any(|o| o.1) {
            for (i, s) in drawing.shapes.iter().enumerate() {
                if !s.filled
                    || s.paint.kind == ShapeKind::ClipOutline
                    || s.paint.alpha < 1.0
                    || !s.paint.clips.is_empty()
                    || paints_nothing(s)
                {
                    continue;
                }
                let test = PaintTest::new(s);
                let Some(bb) = test.bbox() else { continue };
                if !bb.area().is_finite() {
                    continue;
                }
                layers.push((order[i].0, test));
                boxes.push(bb);
            }
        }
        let grid = boxes.iter().copied().reduce(|a, b| a.union(b)).map(|all| {
            let side = all.width().max(all.height()) / (boxes.len() as f64).sqrt().max(1.0);
            let mut g = Grid::new(all, side, boxes.len());
            for (k, b) in boxes.iter().enumerate() {
                g.insert(
                    u32::try_from(k).expect("internal: shape count fits u32"),
                    *b,
                );
            }
            g
        });
        Covers {
            order,
            layers,
            grid,
        }
    }
}

impl Trimmer {
    /// The tests for `drawing`; `None` when no shape can be trimmed (no stroke
    /// area, no clip: the common case costs nothing).
    pub(super) fn new(drawing: &Drawing, d: f64, eps_abs: f64) -> Option<Trimmer> {
        let trimmable = drawing
            .shapes
            .iter()
            .any(|s| s.paint.kind != ShapeKind::Element || !s.paint.clips.is_empty());
        if !trimmable {
            return None;
        }
        let mut tests: Vec<PaintTest> = Vec::new();
        let mut own: Vec<Option<u32>> = vec![None; drawing.shapes.len()];
        // Each joined stroke and the fill it joins: (fill, stroke).
        let joined: Vec<(usize, usize)> = (0..drawing.shapes.len())
            .filter_map(|i| {
                let stroke = ShapeId::from_index(i);
                drawing.joined_fill(stroke).map(|f| (f.index(), i))
            })
            .collect();
        // The filled shapes painted through each clip (by pointer), for clip outlines.
        let mut through: Vec<(*const Clip, Vec<u32>)> = Vec::new();
        for (i, s) in drawing.shapes.iter().enumerate() {
            if !s.filled {
                continue;
            }
            let needs_own = s.paint.kind == ShapeKind::Stroke
                || !s.paint.clips.is_empty()
                || joined.iter().any(|&(f, _)| f == i);
            if !needs_own {
                continue;
            }
            let test = PaintTest::new(s);
            if test.bbox().is_none() {
                continue;
            }
            let k = u32::try_from(tests.len()).expect("internal: shape count fits u32");
            tests.push(test);
            own[i] = Some(k);
            let mut clips = Vec::new();
            for c in &s.paint.clips {
                collect_clips(c, &mut clips);
            }
            for c in clips {
                let ptr = Arc::as_ptr(&c);
                match through.iter_mut().find(|e| e.0 == ptr) {
                    Some(e) => e.1.push(k),
                    None => through.push((ptr, vec![k])),
                }
            }
        }
        let union_of = |i: usize| {
            let &(f, st) = joined.iter().find(|&&(f, st)| f == i || st == i)?;
            Some(vec![own[f]?, own[st]?])
        };
        // The opaque stroke of a fill's own element painted right over it.
        let stroke_over = |i: usize| {
            let f = &drawing.shapes[i];
            let st = drawing.shapes.get(i + 1)?;
            let over = f.paint.kind == ShapeKind::Element
                && f.filled
                && f.paint.clips.is_empty()
                && st.paint.kind == ShapeKind::Stroke
                && !st.paint.joins_fill
                && st.paint.alpha >= 1.0
                && st.element_index == f.element_index
                && st.svg_id == f.svg_id;
            if over { own[i + 1] } else { None }
        };
        let judges = drawing
            .shapes
            .iter()
            .zip(&own)
            .enumerate()
            .map(|(i, (s, own))| match (s.paint.kind, own) {
                (_, Some(_)) if union_of(i).is_some() => {
                    Judge::Union(union_of(i).expect("internal: checked"))
                }
                (_, None) if stroke_over(i).is_some() => {
                    Judge::Covered(stroke_over(i).expect("internal: checked"))
                }
                (ShapeKind::ClipOutline, _) => {
                    let shapes = s
                        .paint
                        .outlined_clip
                        .as_ref()
                        .and_then(|c| through.iter().find(|e| e.0 == Arc::as_ptr(c)))
                        .map(|e| e.1.clone());
                    // A clip outline whose clip paints nothing here bounds nothing
                    // (an empty list drops it); one with no known clip is kept.
                    match shapes {
                        Some(list) => Judge::Boundary(list),
                        None if s.paint.outlined_clip.is_some() => Judge::Boundary(Vec::new()),
                        None => Judge::Keep,
                    }
                }
                (_, Some(k)) => Judge::Boundary(vec![*k]),
                (_, None) if !s.filled && !s.paint.clips.is_empty() => {
                    Judge::Inside(s.paint.clips.iter().map(|c| ClipTest::new(c)).collect())
                }
                _ => Judge::Keep,
            })
            .collect();
        Some(Trimmer {
            judges,
            tests,
            eps_abs,
            step: STEP_REL * d,
            covers: Covers::new(drawing),
        })
    }

    /// Whether the straight pieces of `shape` are judged against the shapes
    /// painted above it ([`Trimmer::covered`]): a stroke's area.
    pub(super) fn judges_cover(&self, shape: ShapeId) -> bool {
        self.covers.grid.is_some() && self.covers.order.get(shape.index()).is_some_and(|o| o.1)
    }

    /// The parts of the straight piece `a b` of `shape`'s outline that an
    /// opaque shape painted above `shape` covers, as sorted, disjoint ranges
    /// of fractions along it: where one such shape certainly paints the
    /// piece and its outline does not meet it (so it paints both sides).
    pub(super) fn covered(&self, shape: ShapeId, a: Point, b: Point) -> Vec<[f64; 2]> {
        let covers = &self.covers;
        let (Some(grid), Some(&(below, _))) = (&covers.grid, covers.order.get(shape.index()))
        else {
            return Vec::new();
        };
        let len = a.distance(b);
        if !(len > 0.0 && len.is_finite()) {
            return Vec::new();
        }
        // Ranges shorter than this (a few times the paint test's own
        // tolerance) are not judged.
        let shortest = 8.0 * self.eps_abs / len;
        // The shapes above whose boxes meet the piece: those met by its run
        // of boxes about a grid cell long each (a long diagonal piece's own
        // box would meet most of the grid).
        let steps = (len / grid.cell()).ceil().clamp(1.0, COVER_MAX_STEPS);
        let mut near: Vec<u32> = Vec::new();
        for i in 0..steps as usize {
            let u0 = a.lerp(b, i as f64 / steps);
            let u1 = a.lerp(b, (i + 1) as f64 / steps);
            grid.any_of(
                Rect::from_points(u0, u1),
                |k| covers.layers[k as usize].0 > below,
                |k| {
                    near.push(k);
                    false
                },
            );
        }
        near.sort_unstable();
        near.dedup();
        let mut found: Vec<[f64; 2]> = Vec::new();
        let (mut cuts, mut unsure) = (Vec::new(), Vec::new());
        for k in near {
            let test = &covers.layers[k as usize].1;
            cuts.clear();
            unsure.clear();
            if test
                .outline()
                .meet_segment((a, b), COVER_MAX_PIECES, &mut cuts, &mut unsure)
                .is_none()
            {
                continue;
            }
            cuts.push(0.0);
            cuts.push(1.0);
            cuts.sort_by(f64::total_cmp);
            for w in cuts.windows(2) {
                let (u0, u1) = (w[0], w[1]);
                if u1 - u0 <= shortest || unsure.iter().any(|r| r[0] <= u1 && r[1] >= u0) {
                    continue;
                }
                let (inside, clear) = test.paints(a.lerp(b, 0.5 * (u0 + u1)), self.eps_abs);
                if inside && clear {
                    found.push([u0, u1]);
                }
            }
        }
        found.sort_by(|x, y| x[0].total_cmp(&y[0]));
        let mut merged: Vec<[f64; 2]> = Vec::with_capacity(found.len());
        for r in found {
            match merged.last_mut() {
                Some(last) if r[0] <= last[1] => last[1] = last[1].max(r[1]),
                _ => merged.push(r),
            }
        }
        merged
    }

    /// Whether pieces of `shape` may be trimmed.
    pub(super) fn trims(&self, shape: ShapeId) -> bool {
        !matches!(self.judges.get(shape.index()), None | Some(Judge::Keep))
    }

    /// Whether the piece `[t0, t1]` of `parent` (a feature of shape `shape`)
    /// is to be kept. `drawn` is the parent as drawn when snapping moved it
    /// (see the module doc): the piece is then dropped only when it bounds
    /// nothing judged on either curve.
    pub(super) fn keeps(
        &self,
        shape: ShapeId,
        parent: &Parent,
        drawn: Option<&Parent>,
        t0: f64,
        t1: f64,
    ) -> bool {
        let Some(judge) = self.judges.get(shape.index()) else {
            return true;
        };
        let chord = (parent.eval(t1) - parent.eval(t0)).hypot();
        let step = self.step.min(STEP_CHORD * chord);
        // Too short to step off clear of its own ends: keep.
        if step.is_nan() || step <= 8.0 * self.eps_abs {
            return true;
        }
        self.bounds(judge, parent, t0, t1, step)
            || drawn.is_some_and(|d| self.bounds(judge, d, t0, t1, step))
    }

    /// Whether `judge` finds the piece `[t0, t1]` of `curve` bounding what is
    /// painted (or is unsure), stepping `step` to either side.
    fn bounds(&self, judge: &Judge, curve: &Parent, t0: f64, t1: f64, step: f64) -> bool {
        match judge {
            Judge::Keep => true,
            Judge::Inside(clips) => SAMPLES.iter().any(|&f| {
                let p = curve.eval(t0 + f * (t1 - t0));
                let (inside, clear) = all_contain(clips, p, self.eps_abs);
                inside || !clear
            }),
            Judge::Boundary(list) => SAMPLES.iter().any(|&f| {
                let t = t0 + f * (t1 - t0);
                let Some(n) = normal(curve, t) else {
                    return true;
                };
                let p = curve.eval(t);
                let (a, b) = (p + n * step, p - n * step);
                list.iter().any(|&k| {
                    let test = &self.tests[k as usize];
                    let grown = test.bbox().map(|b| b.inflate(2.0 * step, 2.0 * step));
                    if grown.is_none_or(|g| !g.contains(a) && !g.contains(b)) {
                        return false;
                    }
                    let (ia, ca) = test.paints(a, self.eps_abs);
                    let (ib, cb) = test.paints(b, self.eps_abs);
                    !(ca && cb) || ia != ib
                })
            }),
            Judge::Covered(k) => SAMPLES.iter().any(|&f| {
                let t = t0 + f * (t1 - t0);
                let Some(n) = normal(curve, t) else {
                    return true;
                };
                let p = curve.eval(t);
                let test = &self.tests[*k as usize];
                let covers = |q| test.paints(q, self.eps_abs) == (true, true);
                !(covers(p + n * step) && covers(p - n * step))
            }),
            Judge::Union(list) => SAMPLES.iter().any(|&f| {
                let t = t0 + f * (t1 - t0);
                let Some(n) = normal(curve, t) else {
                    return true;
                };
                let p = curve.eval(t);
                // certainly painted by one of them, certainly by none, or unsure
                let side = |q| {
                    let mut all_clear = true;
                    for &k in list {
                        let (inside, clear) = self.tests[k as usize].paints(q, self.eps_abs);
                        if inside && clear {
                            return Some(true);
                        }
                        all_clear &= clear;
                    }
                    all_clear.then_some(false)
                };
                match (side(p + n * step), side(p - n * step)) {
                    (Some(a), Some(b)) => a != b,
                    _ => true,
                }
            }),
        }
    }
}

/// The unit normal of `parent` at `t`, `None` where its tangent vanishes.
fn normal(parent: &Parent, t: f64) -> Option<Vec2> {
    let d = parent.deriv(t);
    let len = d.hypot();
    (len > 0.0 && len.is_finite()).then(|| Vec2::new(-d.y, d.x) / len)
}
