//! The feature density budget: a drawing whose outlines lie many deep within the
//! feature envelope μ is refused before the features stage, at once, with one line.
//!
//! The depth is the outlines' total length times μ over the area of their box grown
//! by μ: how many outline pieces an average μ-wide window of the drawing holds. A
//! drawing of curves no closer than μ has a depth of a few at most (a single line
//! 0.5; a hatch of lines μ apart 1). At a depth of hundreds (a stroked zigzag of
//! 100 000 segments 0.001 apart in a 100 × 2 box, μ = 0.1: its stroke outline's
//! pieces overlap about 230 deep) every piece is within μ of hundreds of others:
//! none can be a primary feature, the crossings and the trimming of the overlaps
//! grow with the depth times the pieces, and the mesh could show none of the detail
//! (it lies far inside the envelope). Such an input is not a drawing worth meshing
//! as it stands: the user simplifies it (draws the area it covers).
//!
//! The crossing depth is the same budget for outlines that cross rather than
//! lie side by side: how many crossings an average μ-long stretch of outline
//! holds (twice the crossings, times μ, over the outlines' length). Every
//! crossing is a vertex of the exact arrangement the BSP computes, and past one
//! crossing every μ/2 the sections between them are far shorter than the
//! envelope: all secondary, moved within ε, the arrangement's millions of
//! exact vertices collapsed again by the optimizer. It is judged on what is
//! painted: the segments the features stage gives the BSP, after the outlines
//! that bound nothing were trimmed (a stroke's outline under an opaque shape
//! painted above it among them, `features::trim`) and the secondary ones
//! merged and simplified, with each place where the trimming cut an outline at
//! a covering shape's counted as a crossing (a kept outline ends on another
//! there: a vertex all the same). 2 000 random opaque strokes of width 1 in a
//! 100 × 100 square cross more than twice per μ with every outline kept, what
//! is left of them 0.4 times: meshed. 5 000 random stroked lines in a square, narrower
//! than μ (2.8 million crossings, 3.1 per μ), would take past ten minutes and
//! 2.5 GB: refused (`docs/tuning.md`). The crossings are counted on the
//! segments in a grid, each where it lies, and the count stops at eight times
//! the budget. A refusal names the μ (`--mu-abs`) at which the same outlines
//! pass: the depth is proportional to μ, taken from the segments or from the
//! outlines as drawn (what the features stage keeps at a smaller μ, where it
//! merges less), whichever is the denser; a mesh of every crossing then
//! follows, slowly.

use crate::error::{Error, Result};
use crate::svg::{Drawing, FeatureGeom};
use kurbo::Point;

/// Most outline depth within μ (see the module doc) a drawing may have: the
/// fuzz corpus's stroked soups, dashes and cross-hatches pass, dense
/// hatches are refused (`docs/tuning.md`).
pub(super) const MAX_DEPTH: f64 = 32.0;

/// Most crossings per μ of outline (see the module doc): one every μ/2.
pub(super) const MAX_CROSSING_DEPTH: f64 = 2.0;

/// The depth of `drawing`'s outlines within `mu` (see the module doc).
pub(super) fn depth(drawing: &Drawing, mu: f64) -> f64 {
    let length: f64 = chords(drawing).iter().map(|c| c[0].distance(c[1])).sum();
    let b = drawing.bbox;
    let area = (b.width() + 2.0 * mu) * (b.height() + 2.0 * mu);
    if length > 0.0 && area > 0.0 {
        length * mu / area
    } else {
        0.0
    }
}

/// The chords of `drawing`'s outlines as drawn: each line, and each curve's
/// control polygon.
pub(super) fn chords(drawing: &Drawing) -> Vec<[Point; 2]> {
    let mut out = Vec::new();
    let mut polygon = |ps: &[Point]| out.extend(ps.windows(2).map(|w| [w[0], w[1]]));
    for f in &drawing.features {
        match f.geom {
            FeatureGeom::Point(_) => {}
            FeatureGeom::Line(l) => polygon(&[l.p0, l.p1]),
            FeatureGeom::Cubic(c) => polygon(&[c.p0, c.p1, c.p2, c.p3]),
            FeatureGeom::Conic(c) => polygon(&[c.p0, c.p1, c.p2]),
        }
    }
    out
}

/// The distinct chords among `chords` (an outline drawn twice, a `<line>`'s
/// fill outline under its stroke's centre line, counts once; finite, of
/// non-zero length), and their total length.
fn distinct(chords: impl Iterator<Item = [Point; 2]>) -> (Vec<[Point; 2]>, f64) {
    let key = |p: Point| ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits());
    let finite = |p: Point| p.x.is_finite() && p.y.is_finite();
    let mut out: Vec<[Point; 2]> = chords
        .filter(|&[a, b]| finite(a) && finite(b) && a != b)
        .map(|[a, b]| if key(a) <= key(b) { [a, b] } else { [b, a] })
        .collect();
    out.sort_unstable_by_key(|c| (key(c[0]), key(c[1])));
    out.dedup_by_key(|c| (key(c[0]), key(c[1])));
    let length = out.iter().map(|c| c[0].distance(c[1])).sum();
    (out, length)
}

/// Whether chords `a` and `b` cross properly (each has the other's ends
/// strictly on either side), and where.
fn cross(a: [Point; 2], b: [Point; 2]) -> Option<Point> {
    let side = |p: Point, q: Point, r: Point| (q - p).cross(r - p);
    let (d1, d2) = (side(a[0], a[1], b[0]), side(a[0], a[1], b[1]));
    let (d3, d4) = (side(b[0], b[1], a[0]), side(b[0], b[1], a[1]));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        let t = d3 / (d3 - d4);
        Some(a[0].lerp(a[1], t))
    } else {
        None
    }
}

/// How many times `chords` cross one another, counted up to `cap` (the count
/// stops there). A grid of about one chord per cell; each chord is walked in
/// steps of a cell and listed in the cells its steps' boxes meet; two chords
/// listed in one cell are tried there, and their crossing counts in the cell
/// that holds it.
fn crossings(chords: &[[Point; 2]], cap: u64) -> u64 {
    let Some(first) = chords.first() else {
        return 0;
    };
    let bbox = chords
        .iter()
        .fold(kurbo::Rect::from_points(first[0], first[1]), |r, c| {
            r.union_pt(c[0]).union_pt(c[1])
        });
    let (w, h) = (bbox.width(), bbox.height());
    let side = w.max(h);
    if side <= 0.0 || !side.is_finite() {
        return 0;
    }
    let cell = (w * h / chords.len() as f64).sqrt().max(side / 2048.0);
    let pad = 1e-9 * side;
    let cols = ((w / cell).floor() as u64 + 1).min(4096);
    let rows = ((h / cell).floor() as u64 + 1).min(4096);
    let at = |p: Point| -> (u64, u64) {
        let cx = (((p.x - bbox.x0) / cell).floor().max(0.0) as u64).min(cols - 1);
        let cy = (((p.y - bbox.y0) / cell).floor().max(0.0) as u64).min(rows - 1);
        (cx, cy)
    };
    // (cell, chord), each pair once.
    let mut entries: Vec<(u64, u32)> = Vec::new();
    let mut own: Vec<u64> = Vec::new();
    for (k, c) in chords.iter().enumerate() {
        let Ok(k) = u32::try_from(k) else {
            break;
        };
        let steps = (c[0].distance(c[1]) / cell).ceil().max(1.0) as usize;
        own.clear();
        for i in 0..steps {
            let p = c[0].lerp(c[1], i as f64 / steps as f64);
            let q = c[0].lerp(c[1], (i + 1) as f64 / steps as f64);
            // Grown by a hair: a crossing computed within rounding of a cell's
            // edge finds both chords listed in its cell.
            let (lo, hi) = (
                Point::new(p.x.min(q.x) - pad, p.y.min(q.y) - pad),
                Point::new(p.x.max(q.x) + pad, p.y.max(q.y) + pad),
            );
            let ((x0, y0), (x1, y1)) = (at(lo), at(hi));
            for x in x0..=x1 {
                for y in y0..=y1 {
                    own.push(y * cols + x);
                }
            }
        }
        own.sort_unstable();
        own.dedup();
        entries.extend(own.iter().map(|&g| (g, k)));
    }
    entries.sort_unstable();
    let mut count = 0;
    for group in entries.chunk_by(|a, b| a.0 == b.0) {
        let g = group[0].0;
        for (i, &(_, a)) in group.iter().enumerate() {
            for &(_, b) in &group[i + 1..] {
                let Some(x) = cross(chords[a as usize], chords[b as usize]) else {
                    continue;
                };
                let (cx, cy) = at(x);
                if cy * cols + cx == g {
                    count += 1;
                    if count >= cap {
                        return count;
                    }
                }
            }
        }
    }
    count
}

/// The crossings are counted up to this many times [`MAX_CROSSING_DEPTH`]:
/// far enough past the budget to say how much smaller μ would pass it.
const COUNTED_DEPTH: f64 = 8.0 * MAX_CROSSING_DEPTH;

/// The crossing depth of `segments` at `mu` (see the module doc), with
/// `junctions` more vertices where an outline ends on another, counted up to
/// [`COUNTED_DEPTH`].
pub(super) fn crossing_depth(
    segments: impl Iterator<Item = [Point; 2]>,
    junctions: usize,
    mu: f64,
) -> f64 {
    let (chords, length) = distinct(segments);
    if !(length > 0.0 && mu > 0.0) {
        return 0.0;
    }
    let cap = (COUNTED_DEPTH * length / (2.0 * mu))
        .ceil()
        .min(u64::MAX as f64) as u64
        + 1;
    let junctions = junctions as u64;
    let count = if junctions >= cap {
        cap
    } else {
        crossings(&chords, cap - junctions) + junctions
    };
    2.0 * count as f64 * mu / length
}

/// `Err` with one line saying why when the segments the BSP is given (the
/// features stage's output: what it trimmed, merged and simplified no longer
/// counts) cross, or meet at `junctions` where a trimmed outline ends on
/// another, more than [`MAX_CROSSING_DEPTH`] times per `mu` of their length.
/// The line names a feature envelope (`--mu-abs`) at which the same
/// outlines pass: below the one at which these segments, or the outlines
/// as `drawn` (their chords, asked for only then), would meet the budget.
///
/// # Errors
/// [`Error::TooLarge`] for such segments.
pub(super) fn check_crossings(
    segments: impl Iterator<Item = [Point; 2]>,
    junctions: usize,
    mu: f64,
    drawn: impl FnOnce() -> Vec<[Point; 2]>,
) -> Result<()> {
    let depth = crossing_depth(segments, junctions, mu);
    tracing::debug!(depth, "crossing density");
    if depth > MAX_CROSSING_DEPTH {
        // The depth per μ of these segments and of the outlines as drawn
        // (what the features stage keeps of them at a smaller μ, where it
        // merges and simplifies less), the larger; a margin besides.
        let per_mu = (depth / mu).max(crossing_depth(drawn().into_iter(), junctions, mu) / mu);
        let smaller = SUGGESTED_MARGIN * MAX_CROSSING_DEPTH / per_mu;
        let (at_least, or_below) = if depth >= COUNTED_DEPTH {
            ("at least ", " or below")
        } else {
            ("", "")
        };
        return Err(Error::TooLarge(format!(
            "the outlines cross one another {at_least}{depth:.1} times per feature envelope \
             μ = {mu:.3e} of their length (at most {MAX_CROSSING_DEPTH:.0}): detail far finer \
             than μ that no mesh can show, and an exact arrangement of as many crossings; \
             simplify the drawing, or mesh every crossing with --mu-abs {smaller:.3e}{or_below} \
             (slow)"
        )));
    }
    Ok(())
}

/// The μ a refusal names is this fraction of the μ that would just meet the
/// budget.
const SUGGESTED_MARGIN: f64 = 0.8;

/// `Err` with one line saying why when `drawing`'s outlines lie deeper than
/// [`MAX_DEPTH`] within `mu`.
///
/// # Errors
/// [`Error::TooLarge`] for such a drawing.
pub(super) fn check(drawing: &Drawing, mu: f64) -> Result<()> {
    let depth = depth(drawing, mu);
    tracing::debug!(depth, "feature density");
    if depth > MAX_DEPTH {
        return Err(Error::TooLarge(format!(
            "the outlines lie {depth:.0} deep within the feature envelope μ = {mu:.3e} \
             (at most {MAX_DEPTH:.0}): detail far finer than μ that no mesh can show, \
             and crossings that grow with the depth; simplify the drawing (draw the \
             area it covers) or make μ smaller (--mu)"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    /// `n` horizontal lines of length 1, `gap` apart (filled rectangles' outlines
    /// would count twice: thin filled rectangles of height `gap / 4`).
    fn hatch(n: usize, gap: f64) -> Drawing {
        let mut svg = String::from(r#"<svg xmlns="http://www.w3.org/2000/svg">"#);
        for i in 0..n {
            let y = i as f64 * gap;
            svg.push_str(&format!(
                r##"<rect x="0" y="{y}" width="1" height="{}" fill="#000"/>"##,
                gap / 4.0
            ));
        }
        svg.push_str("</svg>");
        crate::svg::load_bytes(svg.as_bytes(), &crate::svg::LoadOptions::DEFAULT)
            .expect("a drawing")
    }

    fn mu(d: &Drawing) -> f64 {
        Params::default().resolve(d.diagonal()).mu
    }

    #[test]
    fn depth_is_the_envelope_over_the_spacing() {
        // One rectangle of 1 × 0.25: about half its outline's length times μ over its box.
        let one = hatch(1, 1.0);
        let m = mu(&one);
        let expect = 2.5 * m / ((1.0 + 2.0 * m) * (0.25 + 2.0 * m));
        assert!((depth(&one, m) - expect).abs() < 1e-9, "{}", depth(&one, m));
        assert!(check(&one, m).is_ok());
        // Rectangles (two long sides each) μ/4 apart: about 6 deep; μ/40 apart: about 50.
        for (gap_in_mu, lo, hi) in [(0.25, 4.0, 9.0), (0.025, 40.0, 90.0)] {
            let probe = hatch(2, 1.0);
            let gap = gap_in_mu * mu(&probe);
            let d = hatch(400, gap);
            let m = mu(&d);
            let depth = depth(&d, m);
            assert!(depth > lo && depth < hi, "{gap_in_mu}: {depth}");
            assert_eq!(check(&d, m).is_ok(), depth <= MAX_DEPTH);
        }
    }

    /// Crossings counted by brute force over all pairs of distinct chords.
    fn brute(chords: &[[Point; 2]]) -> u64 {
        let mut n = 0;
        for (i, &a) in chords.iter().enumerate() {
            for &b in &chords[i + 1..] {
                n += u64::from(cross(a, b).is_some());
            }
        }
        n
    }

    proptest::proptest! {
        /// On small integer grids (collinear, duplicated, touching and
        /// crossing-at-a-cell-edge chords galore) and on random soups, the
        /// grid counts each crossing once: as many as the pairs that cross.
        #[test]
        fn the_grid_counts_every_crossing_once(
            ends in proptest::collection::vec((0i32..12, 0i32..12, 0i32..12, 0i32..12), 1..80),
            scale in proptest::prop_oneof![proptest::strategy::Just(1.0), 1e-7f64..1e7],
        ) {
            let raw = ends.iter().map(|&(a, b, c, d)| {
                let p = |x: i32, y: i32| Point::new(f64::from(x) * scale, f64::from(y) * scale);
                [p(a, b), p(c, d)]
            });
            let (chords, _) = distinct(raw);
            proptest::prop_assert_eq!(crossings(&chords, u64::MAX), brute(&chords));
            let cap = brute(&chords) / 2;
            if cap > 0 {
                proptest::prop_assert_eq!(crossings(&chords, cap), cap);
            }
        }

        #[test]
        fn random_soups_count_like_brute_force(
            ends in proptest::collection::vec((0.0f64..100.0, 0.0f64..100.0, 0.0f64..100.0, 0.0f64..100.0), 1..150),
        ) {
            let (chords, _) = distinct(ends.iter().map(|&(a, b, c, d)| [Point::new(a, b), Point::new(c, d)]));
            proptest::prop_assert_eq!(crossings(&chords, u64::MAX), brute(&chords));
        }
    }

    /// A grid of n horizontal and n vertical lines `gap` apart crosses n² times
    /// over 2n lines: a depth of μ / gap. Past one crossing every μ/2 the BSP
    /// is not asked; a line drawn twice counts once.
    #[test]
    fn crossing_depth_is_the_envelope_over_the_spacing() {
        let mu = 0.01;
        let lines = |n: usize, gap: f64| -> Vec<[Point; 2]> {
            let len = n as f64 * gap;
            let mut v = Vec::new();
            for i in 0..n {
                let t = (i as f64 + 0.5) * gap;
                v.push([Point::new(0.0, t), Point::new(len, t)]);
                v.push([Point::new(t, 0.0), Point::new(t, len)]);
                v.push([Point::new(t, len), Point::new(t, 0.0)]);
            }
            v
        };
        for (gap_in_mu, refused) in [(1.0, false), (0.6, false), (0.4, true), (0.1, true)] {
            let v = lines(200, gap_in_mu * mu);
            let depth = crossing_depth(v.iter().copied(), 0, mu);
            if refused {
                assert!(depth > MAX_CROSSING_DEPTH, "{gap_in_mu}: {depth}");
            } else {
                assert!(
                    (depth - 1.0 / gap_in_mu).abs() < 1e-9,
                    "{gap_in_mu}: {depth}"
                );
            }
            assert_eq!(
                check_crossings(v.into_iter(), 0, mu, Vec::new).is_err(),
                refused
            );
        }
        assert_eq!(crossing_depth(std::iter::empty(), 0, mu), 0.0);
    }
}
