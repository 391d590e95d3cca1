//! Whole shapes painted again on top of themselves (a path duplicated
//! thousands of times): the lower copies are merged into the topmost one.
//!
//! A shape is a *duplicate* of a shape painted above it when both have the same
//! structure (subpaths, their closing, the kinds of their segments) and every
//! control point (and conic weight) of one is within `tol` of the other's in
//! each coordinate, and when the upper copy stands for the same thing in the
//! picture: the same kind (fill, stroke area, clip outline), both filled or
//! neither, the same fill rule, the same clips (and the rest of the paint but
//! what only colours the region: opacity, paint server). The upper copy then
//! covers the lower one exactly (to `tol`): wherever the lower copy paints, the
//! upper paints on top of it (and of anything painted in between), so no point
//! of the picture changes owner; and its outline is the lower's, so the feature
//! soup loses only coincident curves. The topmost copy keeps its own paint (colour,
//! id, opacity) and place in the paint order.
//!
//! Linear in the input: shapes are bucketed by a hash of their structure and
//! their centroid quantized to cells of `2·tol`, and each shape is compared in
//! full only with the kept shapes in the 3×3 cells around its own, at most
//! [`MAX_CANDIDATES`] of them.

use super::drawing::{Segment, Shape, ShapePaint};
use kurbo::Point;
use std::collections::HashMap;
use std::hash::{DefaultHasher, Hash, Hasher};

/// Tolerance, relative to the drawing's bounding-box diagonal, within which two
/// copies' control points must agree: far below the 1e-9·d to which output nodes
/// lie on the drawing's curves.
pub(super) const DUPLICATE_TOL_REL: f64 = 1e-10;

/// At most this many kept shapes are compared in full with each shape (many
/// different shapes with one structure and one centroid, such as segments
/// crossing at their midpoints, then stay apart: merging is only ever an
/// optimisation).
const MAX_CANDIDATES: usize = 64;

/// The conic weight's tolerance (absolute; weights are cosines, at most 1 for
/// ellipse arcs).
const WEIGHT_TOL: f64 = 1e-12;

/// A shape's geometry as compared here: its structure's hash and its points.
struct Signature {
    structure: u64,
    points: Vec<Point>,
    weights: Vec<f64>,
}

fn signature(s: &Shape) -> Signature {
    let mut h = DefaultHasher::new();
    let mut points = Vec::new();
    let mut weights = Vec::new();
    s.subpaths.len().hash(&mut h);
    for sub in &s.subpaths {
        (sub.closed, sub.segments.len()).hash(&mut h);
        points.push(sub.start);
        for seg in &sub.segments {
            match seg {
                Segment::Line(l) => {
                    0u8.hash(&mut h);
                    points.extend([l.p0, l.p1]);
                }
                Segment::Cubic(c) => {
                    1u8.hash(&mut h);
                    points.extend([c.p0, c.p1, c.p2, c.p3]);
                }
                Segment::Conic(c) => {
                    2u8.hash(&mut h);
                    points.extend([c.p0, c.p1, c.p2]);
                    weights.push(c.w);
                }
            }
        }
    }
    Signature {
        structure: h.finish(),
        points,
        weights,
    }
}

/// Whether `upper`, painted above `lower`, stands for the same thing in the
/// picture (see the module doc); the geometry is compared apart. Every part of
/// the paint counts but what only colours the region the topmost copy owns
/// (opacity, paint server, average colour) and the filter flag.
fn same_role(upper: &Shape, lower: &Shape) -> bool {
    let same_clips = upper.paint.clips.len() == lower.paint.clips.len()
        && upper
            .paint
            .clips
            .iter()
            .zip(&lower.paint.clips)
            .all(|(a, b)| std::sync::Arc::ptr_eq(a, b) || a == b);
    if !(same_clips
        && upper.filled == lower.filled
        && (!upper.filled || upper.fill_rule == lower.fill_rule))
    {
        return false;
    }
    let mut paint: ShapePaint = upper.paint.clone();
    paint.alpha = lower.paint.alpha;
    paint.server.clone_from(&lower.paint.server);
    paint.average_colour = lower.paint.average_colour;
    paint.filtered = lower.paint.filtered;
    paint.clips.clone_from(&lower.paint.clips);
    paint == lower.paint
}

/// Whether two signatures agree to `tol` (per coordinate).
fn same_geometry(a: &Signature, b: &Signature, tol: f64) -> bool {
    a.structure == b.structure
        && a.points.len() == b.points.len()
        && a.weights.len() == b.weights.len()
        && a.points
            .iter()
            .zip(&b.points)
            .all(|(p, q)| (p.x - q.x).abs() <= tol && (p.y - q.y).abs() <= tol)
        && a.weights
            .iter()
            .zip(&b.weights)
            .all(|(v, w)| (v - w).abs() <= WEIGHT_TOL)
}

/// Drop every shape that a shape painted above it duplicates (see the module
/// doc), to `tol` (user units, per coordinate). Returns the kept shapes, in their
/// order, and how many were dropped.
pub(super) fn merge(shapes: Vec<Shape>, tol: f64) -> (Vec<Shape>, usize) {
    if shapes.len() < 2 {
        return (shapes, 0);
    }
    let tol = if tol.is_finite() && tol > 0.0 {
        tol
    } else {
        0.0
    };
    let cell = if tol > 0.0 { 2.0 * tol } else { 1.0 };
    let sigs: Vec<Signature> = shapes.iter().map(signature).collect();
    let key = |s: &Signature| -> (i64, i64) {
        let n = s.points.len().max(1) as f64;
        let (sx, sy) = s
            .points
            .iter()
            .fold((0.0, 0.0), |(x, y), p| (x + p.x, y + p.y));
        // Saturating casts: far centroids share the outermost cells.
        (
            (sx / n / cell).floor() as i64,
            (sy / n / cell).floor() as i64,
        )
    };
    // Topmost first: the paint order, ties broken by document order.
    let mut order: Vec<usize> = (0..shapes.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse((shapes[i].paint_order, i)));
    let mut kept_cells: HashMap<(u64, i64, i64), Vec<usize>> = HashMap::new();
    let mut keep = vec![true; shapes.len()];
    let mut dropped = 0;
    for i in order {
        let (kx, ky) = key(&sigs[i]);
        let structure = sigs[i].structure;
        let mut compared = 0;
        let mut duplicate = false;
        'probe: for dx in -1..=1 {
            for dy in -1..=1 {
                let cell_key = (structure, kx.saturating_add(dx), ky.saturating_add(dy));
                for &j in kept_cells.get(&cell_key).map_or(&[][..], Vec::as_slice) {
                    if compared >= MAX_CANDIDATES {
                        break 'probe;
                    }
                    compared += 1;
                    if same_role(&shapes[j], &shapes[i]) && same_geometry(&sigs[j], &sigs[i], tol) {
                        duplicate = true;
                        break 'probe;
                    }
                }
            }
        }
        if duplicate {
            keep[i] = false;
            dropped += 1;
        } else {
            kept_cells.entry((structure, kx, ky)).or_default().push(i);
        }
    }
    if dropped == 0 {
        return (shapes, 0);
    }
    let kept = shapes
        .into_iter()
        .zip(keep)
        .filter_map(|(s, k)| k.then_some(s))
        .collect();
    (kept, dropped)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::svg::drawing::{FillRule, Subpath};
    use kurbo::CubicBez;
    use proptest::prelude::*;

    fn shape(index: u32, points: [Point; 4], colour: [u8; 3]) -> Shape {
        let c = CubicBez::new(points[0], points[1], points[2], points[3]);
        Shape {
            svg_id: None,
            element_index: index,
            paint_order: index,
            filled: true,
            stroked: false,
            fill_rule: FillRule::NonZero,
            fill_colour: Some(colour),
            subpaths: vec![Subpath {
                segments: vec![
                    Segment::Cubic(c),
                    Segment::Line(kurbo::Line::new(c.p3, c.p0)),
                ],
                start: c.p0,
                closed: true,
            }],
            paint: ShapePaint::default(),
        }
    }

    const BLOB: [Point; 4] = [
        Point::new(0.0, 0.0),
        Point::new(10.0, 30.0),
        Point::new(40.0, 30.0),
        Point::new(50.0, 0.0),
    ];

    #[test]
    fn the_topmost_copy_stays_with_its_own_paint() {
        let shapes = vec![
            shape(0, BLOB, [255, 0, 0]),
            shape(1, BLOB, [0, 255, 0]),
            shape(2, BLOB, [0, 0, 255]),
        ];
        let (kept, dropped) = merge(shapes, 1e-8);
        assert_eq!(dropped, 2);
        assert_eq!(kept.len(), 1);
        assert_eq!(kept[0].element_index, 2);
        assert_eq!(kept[0].fill_colour, Some([0, 0, 255]));
    }

    #[test]
    fn the_paint_order_not_the_document_order_decides_the_top() {
        let mut shapes = vec![shape(0, BLOB, [255, 0, 0]), shape(1, BLOB, [0, 255, 0])];
        shapes[0].paint_order = 5;
        let (kept, dropped) = merge(shapes, 1e-8);
        assert_eq!((kept.len(), dropped), (1, 1));
        assert_eq!(kept[0].element_index, 0);
    }

    #[test]
    fn copies_in_another_role_stay() {
        let mut rule = shape(1, BLOB, [0; 3]);
        rule.fill_rule = FillRule::EvenOdd;
        let mut unfilled = shape(2, BLOB, [0; 3]);
        unfilled.filled = false;
        let mut stroke = shape(3, BLOB, [0; 3]);
        stroke.paint.kind = crate::svg::drawing::ShapeKind::Stroke;
        let shapes = vec![shape(0, BLOB, [0; 3]), rule, unfilled, stroke];
        let (kept, dropped) = merge(shapes, 1e-8);
        assert_eq!((kept.len(), dropped), (4, 0));
    }

    #[test]
    fn another_structure_stays() {
        let mut open = shape(1, BLOB, [0; 3]);
        open.subpaths[0].closed = false;
        let mut line = shape(2, BLOB, [0; 3]);
        line.subpaths[0].segments[0] = Segment::Line(kurbo::Line::new(BLOB[0], BLOB[3]));
        let shapes = vec![shape(0, BLOB, [0; 3]), open, line];
        assert_eq!(merge(shapes, 1e-8).1, 0);
    }

    fn config() -> ProptestConfig {
        ProptestConfig {
            cases: 256,
            failure_persistence: None,
            rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
            ..ProptestConfig::default()
        }
    }

    proptest! {
        #![proptest_config(config())]

        /// A copy moved by at most `tol` in every coordinate is merged, wherever
        /// the quantization cells fall; one control point moved by more than
        /// `tol` in one coordinate keeps it.
        #[test]
        fn near_copies_merge_within_tol_and_not_beyond(
            coords in proptest::array::uniform8(-1e3..1e3f64),
            shifts in proptest::array::uniform8(-1.0..=1.0f64),
            tol_exp in -9i32..-3,
            far in 0usize..8,
            beyond in 1.01..100.0f64,
        ) {
            let tol = 10f64.powi(tol_exp);
            let pts = |c: [f64; 8]| [
                Point::new(c[0], c[1]),
                Point::new(c[2], c[3]),
                Point::new(c[4], c[5]),
                Point::new(c[6], c[7]),
            ];
            let base = shape(0, pts(coords), [0; 3]);
            // Within: every coordinate moved by at most tol (the sum's rounding
            // is far below tol at these magnitudes, but stay a hair inside).
            let mut near = coords;
            for (c, s) in near.iter_mut().zip(shifts) {
                *c += 0.999 * tol * s;
            }
            let (kept, dropped) = merge(vec![base.clone(), shape(1, pts(near), [9; 3])], tol);
            prop_assert_eq!(dropped, 1);
            prop_assert_eq!(kept[0].element_index, 1);
            // Beyond: one coordinate moved by more than tol.
            let mut off = coords;
            off[far] += beyond * tol;
            let (kept, dropped) = merge(vec![base, shape(1, pts(off), [9; 3])], tol);
            prop_assert_eq!(dropped, 0);
            prop_assert_eq!(kept.len(), 2);
        }
    }
}
