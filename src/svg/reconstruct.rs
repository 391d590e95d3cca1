//! A usvg path's geometry re-derived in f64 from its source element, checked
//! against usvg's own single-precision result, and the tally of how each path
//! came out ([`Precision`]).
//!
//! A reconstruction is accepted only if it agrees with usvg's path: the same
//! number of subpaths, each one closed alike and starting and ending within an
//! f32 tolerance (relative to the magnitudes involved), and bounding boxes that
//! agree within that tolerance (plus usvg's own arc approximation error where
//! the path has conics). Anything else keeps usvg's geometry.

use super::conic::Conic;
use super::drawing::{Segment, Subpath};
use super::geometry;
use super::outline::{Verb, subpaths};
use super::source::{Candidate, Source, Unsupported};
use crate::units::Units;
use kurbo::{Affine, ParamCurveExtrema, Point, Rect};
use std::collections::BTreeMap;

/// Relative tolerance of the agreement with usvg's f32 geometry (f32's epsilon
/// is 1.2e-7; usvg composes transforms and maps the root viewBox in f32).
const F32_REL: f64 = 1e-6;

/// usvg approximates arcs by cubics (kurbo, at least 4 per turn: radial error
/// up to 2.7e-4 of the radius); bounding boxes of paths with conics may differ
/// by that much, relative to the path's size.
const ARC_REL: f64 = 1e-3;

/// How a drawing's paths came out.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Precision {
    /// Paths re-derived in f64 from the document's text.
    pub(crate) exact: usize,
    /// Text glyph outlines (from fonts through usvg: single precision by design).
    pub(crate) glyphs: usize,
    /// Paths that kept usvg's f32 geometry, by reason.
    pub(crate) fallback: BTreeMap<&'static str, usize>,
}

/// The reason given for marker content and paint-order copies of a path (usvg
/// strips their ids): single precision, documented, no warning.
pub(super) const MARKER: Unsupported = "a marker (or a paint-order copy of a path with markers)";

/// The reason given when a reconstruction disagrees with usvg.
pub(super) const MISMATCH: Unsupported = "the f64 reconstruction disagreed with usvg's geometry";

impl Precision {
    /// Paths that kept usvg's geometry.
    pub(crate) fn fallbacks(&self) -> usize {
        self.fallback.values().sum()
    }

    /// One warning for the paths that kept usvg's geometry (markers aside), if any.
    pub(super) fn warning(&self) -> Option<String> {
        let reasons: Vec<String> = self
            .fallback
            .iter()
            .filter(|(r, _)| **r != MARKER)
            .map(|(r, n)| format!("{r} ({n})"))
            .collect();
        let n: usize = self
            .fallback
            .iter()
            .filter(|(r, _)| **r != MARKER)
            .map(|(_, n)| n)
            .sum();
        (n > 0).then(|| {
            format!(
                "{n} of {} path(s) keep usvg's single-precision geometry (arcs as cubics): {}",
                self.exact + self.fallbacks(),
                reasons.join(", ")
            )
        })
    }
}

/// From the root `<svg>`'s user units to output coordinates (units, scale, y flip).
#[derive(Clone, Copy, Debug)]
pub(super) struct OutputMap(Result<Affine, Unsupported>);

impl OutputMap {
    /// The map for `units` and `scale` (already validated).
    pub(super) fn new(source: &Source<'_, '_>, units: Units, scale: f64) -> Self {
        let root = match units {
            Units::User if source.root_transform() => Err("a transform on the root <svg>"),
            Units::User => Ok(Affine::IDENTITY),
            Units::Px => source.root_px_mapping(),
        };
        Self(root.map(|r| Affine::FLIP_Y * Affine::scale(scale) * r))
    }
}

/// The f64 subpaths of `candidate`, in output coordinates, if they agree with
/// `reference` (usvg's geometry of the same path, in output coordinates).
///
/// # Errors
/// Why not: a case this reader does not support, or [`MISMATCH`].
pub(super) fn reconstruct(
    source: &Source<'_, '_>,
    candidate: &Candidate<'_, '_>,
    map: OutputMap,
    reference: &[Subpath],
) -> Result<Vec<Subpath>, Unsupported> {
    let mut steps = source.transform_steps(candidate)?;
    steps.push(map.0?);
    let m = steps.iter().rev().fold(Affine::IDENTITY, |m, s| m * *s);
    let outline = geometry::outline(candidate.node)?;
    let local = &outline.verbs;
    let local_size = local
        .iter()
        .flat_map(Verb::points)
        .fold(0.0_f64, |a, p| a.max(p.x.abs()).max(p.y.abs()));
    let mine = subpaths(local.iter().map(|v| v.transform(m)));
    // usvg rounds coordinates and composes transforms in f32: its errors scale with
    // the magnitudes in every intermediate frame (large translations that cancel
    // included), bounded here in output units
    let (mut outer_norm, mut magnitude) = (1.0_f64, 0.0_f64);
    for s in steps.iter().rev() {
        let [a, b, c, d, e, f] = s.as_coeffs();
        magnitude += outer_norm * e.abs().max(f.abs());
        outer_norm *= (a.abs() + c.abs()).max(b.abs() + d.abs());
    }
    let magnitude = (magnitude + outer_norm * local_size)
        .max(max_abs(reference))
        .max(max_abs(&mine));
    let tol = F32_REL * magnitude;
    if agrees(&mine, reference, tol, outline.tiny_arcs) {
        Ok(mine)
    } else {
        Err(MISMATCH)
    }
}

/// The largest coordinate magnitude of the subpaths' bounding box.
fn max_abs(subpaths: &[Subpath]) -> f64 {
    bbox(subpaths).map_or(0.0, |r| {
        [r.x0, r.y0, r.x1, r.y1]
            .into_iter()
            .fold(0.0, |m, v| m.max(v.abs()))
    })
}

/// Same subpaths, closed alike, ends within `tol`, bounding boxes within `tol`
/// (plus the arc approximation allowance when `mine` has conics; not compared
/// when usvg drew tiny arcs as lines).
fn agrees(mine: &[Subpath], reference: &[Subpath], tol: f64, tiny_arcs: bool) -> bool {
    let near = |p: Point, q: Point| (p.x - q.x).abs() <= tol && (p.y - q.y).abs() <= tol;
    let end = |s: &Subpath| s.segments.last().map_or(s.start, Segment::end);
    let same_subpaths = mine.len() == reference.len()
        && mine
            .iter()
            .zip(reference)
            .all(|(m, r)| m.closed == r.closed && near(m.start, r.start) && near(end(m), end(r)));
    if !same_subpaths {
        return false;
    }
    if tiny_arcs {
        return true;
    }
    let (Some(a), Some(b)) = (bbox(mine), bbox(reference)) else {
        return mine.is_empty() && reference.is_empty();
    };
    let has_conic = mine
        .iter()
        .any(|s| s.segments.iter().any(|g| matches!(g, Segment::Conic(_))));
    let slack = tol
        + if has_conic {
            ARC_REL * a.width().hypot(a.height())
        } else {
            0.0
        };
    (a.x0 - b.x0).abs() <= slack
        && (a.y0 - b.y0).abs() <= slack
        && (a.x1 - b.x1).abs() <= slack
        && (a.y1 - b.y1).abs() <= slack
}

/// The tight bounding box of the subpaths (`None` without any).
pub(super) fn bbox(subpaths: &[Subpath]) -> Option<Rect> {
    let mut out: Option<Rect> = None;
    let mut add = |r: Rect| out = Some(out.map_or(r, |o| o.union(r)));
    for s in subpaths {
        add(Rect::from_points(s.start, s.start));
        for seg in &s.segments {
            add(match seg {
                Segment::Line(l) => Rect::from_points(l.p0, l.p1),
                Segment::Cubic(c) => c.bounding_box(),
                Segment::Conic(c) => conic_bbox(c),
            });
        }
    }
    out
}

/// The tight bounding box of a conic piece: its ends and the interior extrema of
/// each coordinate, where the derivative's numerator
/// `w(p1 − p0)(1 − t)² + (p2 − p0)t(1 − t) + w(p2 − p1)t²` vanishes.
pub(super) fn conic_bbox(c: &Conic) -> Rect {
    let mut r = Rect::from_points(c.p0, c.p2);
    for axis in [0, 1] {
        let v = |p: Point| if axis == 0 { p.x } else { p.y };
        let (x0, x1, x2) = (v(c.p0), v(c.p1), v(c.p2));
        let (c0, c1, c2) = (c.w * (x1 - x0), x2 - x0, c.w * (x2 - x1));
        // c0 (1 − t)² + c1 t (1 − t) + c2 t² in powers of t
        for t in kurbo::common::solve_quadratic(c0, c1 - 2.0 * c0, c0 - c1 + c2) {
            if t > 0.0 && t < 1.0 {
                r = r.union_pt(c.eval(t));
            }
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_1_SQRT_2;

    #[test]
    fn conic_bounding_boxes_are_tight() {
        // a quarter of the unit circle rotated by 45°: its apex is an extremum
        let q = Conic::new((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), FRAC_1_SQRT_2)
            .transform(Affine::rotate(std::f64::consts::FRAC_PI_4));
        let r = conic_bbox(&q);
        let samples = (0..=10_000).map(|i| q.eval(f64::from(i) / 10_000.0));
        let mut s = Rect::from_points(q.p0, q.p0);
        for p in samples {
            s = s.union_pt(p);
            assert!(r.inflate(1e-12, 1e-12).contains(p), "{p:?} outside {r:?}");
        }
        assert!((r.y1 - 1.0).abs() < 1e-12, "{r:?}");
        for (a, b) in [(r.x0, s.x0), (r.y0, s.y0), (r.x1, s.x1), (r.y1, s.y1)] {
            assert!((a - b).abs() < 1e-7, "{r:?} vs sampled {s:?}");
        }
    }
}
