//! An SVG picture of a [`FeatureSet`] over its input: input outlines light grey, primary
//! sections red, secondary polylines green, isolated points black.

use super::FeatureSet;
use crate::svg::{Drawing, FeatureGeom};
use kurbo::Point;
use std::fmt::Write;

/// SVG coordinates of an output point (y flipped back).
fn p(q: Point) -> String {
    format!("{} {}", q.x, -q.y)
}

/// The preview document.
pub(crate) fn to_svg(fs: &FeatureSet, drawing: &Drawing) -> String {
    let b = drawing.bbox;
    let d = drawing.diagonal();
    let pad = 0.02 * d;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="{} {} {} {}" width="1000" height="{}">"#,
        b.x0 - pad,
        -b.y1 - pad,
        b.width() + 2.0 * pad,
        b.height() + 2.0 * pad,
        (1000.0 * (b.height() + 2.0 * pad) / (b.width() + 2.0 * pad))
            .clamp(10.0, 10_000.0)
            .round(),
    );
    let style = |colour: &str, width: f64| {
        format!(
            r#"fill="none" stroke="{colour}" stroke-width="{width}" vector-effect="non-scaling-stroke" stroke-linecap="round" stroke-linejoin="round""#
        )
    };
    let mut input = String::new();
    for f in &drawing.features {
        match f.geom {
            FeatureGeom::Point(_) => {}
            FeatureGeom::Line(l) => {
                let _ = write!(input, "M{}L{}", p(l.p0), p(l.p1));
            }
            FeatureGeom::Cubic(c) => {
                let _ = write!(input, "M{}C{} {} {}", p(c.p0), p(c.p1), p(c.p2), p(c.p3));
            }
            // CONIC-PLACEHOLDER: drawn as its cubic approximation
            FeatureGeom::Conic(k) => {
                let c = k.approx_cubic();
                let _ = write!(input, "M{}C{} {} {}", p(c.p0), p(c.p1), p(c.p2), p(c.p3));
            }
        }
    }
    let _ = writeln!(s, r#"<path d="{input}" {}/>"#, style("#c8c8c8", 3.0));
    let mut sec = String::new();
    for pl in &fs.secondary {
        let _ = write!(sec, "M{}", p(pl.points[0]));
        for q in &pl.points[1..] {
            let _ = write!(sec, "L{}", p(*q));
        }
    }
    let _ = writeln!(s, r#"<path d="{sec}" {}/>"#, style("#00a000", 1.5));
    let mut pri = String::new();
    for sct in &fs.primary {
        let c = sct.ctrl;
        let _ = write!(pri, "M{}C{} {} {}", p(c.p0), p(c.p1), p(c.p2), p(c.p3));
    }
    let _ = writeln!(s, r#"<path d="{pri}" {}/>"#, style("#e00000", 1.5));
    for pt in &fs.points {
        let _ = writeln!(
            s,
            r#"<circle cx="{}" cy="{}" r="{}" fill="black"/>"#,
            pt.pos.x,
            -pt.pos.y,
            d / 400.0
        );
    }
    s.push_str("</svg>\n");
    s
}
