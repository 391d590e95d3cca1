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

use crate::error::{Error, Result};
use crate::svg::{Drawing, FeatureGeom};
use kurbo::Point;

/// Most outline depth within μ (see the module doc) a drawing may have. Of the
/// fuzz findings of issue 41, the stroked soups, dashes and cross-hatches lie at 1
/// to 29; refused: hatches of 25 000 and 20 000 lines 0.04 and 0.02 apart (μ ≈ 1.1)
/// at 37 and 53, and the stroked 100k zigzag.
pub(super) const MAX_DEPTH: f64 = 32.0;

/// The depth of `drawing`'s outlines within `mu` (see the module doc).
pub(super) fn depth(drawing: &Drawing, mu: f64) -> f64 {
    let polygon = |ps: &[Point]| -> f64 { ps.windows(2).map(|w| w[0].distance(w[1])).sum() };
    let length: f64 = drawing
        .features
        .iter()
        .map(|f| match f.geom {
            FeatureGeom::Point(_) => 0.0,
            FeatureGeom::Line(l) => l.p0.distance(l.p1),
            FeatureGeom::Cubic(c) => polygon(&[c.p0, c.p1, c.p2, c.p3]),
            FeatureGeom::Conic(c) => polygon(&[c.p0, c.p1, c.p2]),
        })
        .sum();
    let b = drawing.bbox;
    let area = (b.width() + 2.0 * mu) * (b.height() + 2.0 * mu);
    if length > 0.0 && area > 0.0 {
        length * mu / area
    } else {
        0.0
    }
}

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
        crate::svg::load_bytes(svg.as_bytes()).expect("a drawing")
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
}
