//! An SVG picture of a [`FeatureSet`] over its input: input outlines light grey, primary
//! sections red, secondary polylines green, isolated points black. Conics (input pieces and
//! sections of them) are drawn as fine polylines of points on the exact conic (SVG has no
//! rational Bézier, and a section's `ctrl` is only a hull of it).

use super::{FeatureSet, Parent};
use crate::svg::{Drawing, FeatureGeom};
use kurbo::Point;
use std::fmt::Write;

/// SVG coordinates of an output point (y flipped back).
fn p(q: Point) -> String {
    format!("{} {}", q.x, -q.y)
}

/// Chords per conic piece (a quarter circle drawn with 32 chords is within 4e-4·r).
const CONIC_CHORDS: u32 = 32;

/// Append the polyline of `parent` on `t` (the exact points at `CONIC_CHORDS + 1` parameters).
fn flattened(out: &mut String, parent: &Parent, t: [f64; 2]) {
    let _ = write!(out, "M{}", p(parent.eval(t[0])));
    for k in 1..=CONIC_CHORDS {
        let s = f64::from(k) / f64::from(CONIC_CHORDS);
        let tk = if k == CONIC_CHORDS {
            t[1]
        } else {
            t[0] + s * (t[1] - t[0])
        };
        let _ = write!(out, "L{}", p(parent.eval(tk)));
    }
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
            FeatureGeom::Conic(k) if k.w > 0.0 && k.w.is_finite() => {
                flattened(&mut input, &Parent::Conic(k), [0.0, 1.0]);
            }
            // No bounded arc: the features stage takes it as its chord.
            FeatureGeom::Conic(k) => {
                let _ = write!(input, "M{}L{}", p(k.p0), p(k.p2));
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
        if let Parent::Conic(_) = sct.parent {
            flattened(&mut pri, &sct.parent, sct.t);
        } else {
            let c = sct.ctrl;
            let _ = write!(pri, "M{}C{} {} {}", p(c.p0), p(c.p1), p(c.p2), p(c.p3));
        }
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
