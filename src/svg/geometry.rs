//! One source element's outline in f64, in the element's own coordinates,
//! read from the document's text: path data (`svgtypes`' f64 parser, arcs kept
//! as arcs), `<rect>` (rounded corners by SVG's `rx`/`ry` rules), `<circle>`,
//! `<ellipse>`, `<line>`, `<polyline>`, `<polygon>`.
//!
//! Arcs, circles, ellipses and rounded corners become exact [`Conic`] pieces
//! (at most 90° each). Everything else follows usvg 0.49's reading of the same
//! element, so that the result can be checked against usvg's f32 path: the same
//! subpaths with the same start points and directions (a circle starts at
//! `(cx + r, cy)` and goes through `(cx, cy + r)`, SVG's y-down order), a path's
//! data read up to its first error, consecutive moves merged, `Z` not repeated.

use super::conic::Conic;
use super::outline::Verb;
use super::source::{Unsupported, absolute, length};
use kurbo::{Point, SvgArc, Vec2};
use std::f64::consts::FRAC_1_SQRT_2;
use std::str::FromStr;
use usvg::roxmltree::Node;

/// kurbo (hence usvg) draws an arc whose radius is at most this (in the
/// element's units) as a straight line.
const KURBO_STRAIGHT: f64 = 1e-5;

/// A shape element's outline in its own coordinates.
#[derive(Debug)]
pub(super) struct Outline {
    /// The path commands.
    pub(super) verbs: Vec<Verb>,
    /// Whether it has an arc so small that usvg draws it as a line (radius at
    /// most 1e-5): its bounding box may then differ from usvg's by the arc.
    pub(super) tiny_arcs: bool,
}

/// The outline of a shape element as path commands in its own coordinates.
///
/// # Errors
/// An element this reader does not draw the way usvg does (lengths that need
/// context, a shape usvg would not render).
pub(super) fn outline(e: Node<'_, '_>) -> Result<Outline, Unsupported> {
    let mut out = Commands::default();
    match e.tag_name().name() {
        "path" => path_data(e.attribute("d").unwrap_or(""), &mut out),
        "rect" => rect(e, &mut out)?,
        "circle" => {
            let r = length(e, "r", 0.0)?;
            ellipse(length(e, "cx", 0.0)?, length(e, "cy", 0.0)?, r, r, &mut out)?;
        }
        "ellipse" => {
            let (rx, ry) = radii(e)?;
            ellipse(
                length(e, "cx", 0.0)?,
                length(e, "cy", 0.0)?,
                rx,
                ry,
                &mut out,
            )?;
        }
        "line" => {
            out.push(Verb::Move(point(e, "x1", "y1")?));
            out.push(Verb::Line(point(e, "x2", "y2")?));
        }
        "polyline" => polyline(e, &mut out)?,
        "polygon" => {
            polyline(e, &mut out)?;
            out.push(Verb::Close);
        }
        _ => return Err("not a shape element"),
    }
    let tiny_arcs = out.0.iter().any(|v| match v {
        Verb::Conic(c) => {
            let (a, b) = (c.p1 - c.p0, c.p2 - c.p1);
            a.hypot().min(b.hypot()) <= 2.0 * KURBO_STRAIGHT
        }
        _ => false,
    });
    Ok(Outline {
        verbs: out.0,
        tiny_arcs,
    })
}

/// Path commands, with tiny-skia's normalisation (usvg builds its paths with it):
/// a move right after a move replaces it, a close right after a close is dropped.
#[derive(Default)]
struct Commands(Vec<Verb>);

impl Commands {
    fn push(&mut self, v: Verb) {
        match (self.0.last_mut(), v) {
            (Some(last @ Verb::Move(_)), Verb::Move(_)) => *last = v,
            (Some(Verb::Close), Verb::Close) | (None, Verb::Close) => {}
            _ => self.0.push(v),
        }
    }
}

/// `(x, y)` from two length attributes (default 0).
fn point(e: Node<'_, '_>, x: &str, y: &str) -> Result<Point, Unsupported> {
    Ok(Point::new(length(e, x, 0.0)?, length(e, y, 0.0)?))
}

/// Path data, absolute, up to the first error (as usvg reads it).
fn path_data(d: &str, out: &mut Commands) {
    use svgtypes::PathSegment as S;
    let mut pen = Point::ORIGIN;
    let mut start = Point::ORIGIN;
    // the second control point of a preceding C/S, the control point of a preceding Q/T
    let mut cubic_ctrl: Option<Point> = None;
    let mut quad_ctrl: Option<Point> = None;
    let mut closed = false;
    for seg in svgtypes::PathParser::from(d) {
        let Ok(seg) = seg else { break };
        let rel = |abs: bool, x: f64, y: f64| {
            if abs {
                Point::new(x, y)
            } else {
                Point::new(pen.x + x, pen.y + y)
            }
        };
        // after Z, a drawing command starts a new subpath where the last one began
        if closed && !matches!(seg, S::MoveTo { .. } | S::ClosePath { .. }) {
            out.push(Verb::Move(start));
        }
        closed = false;
        let (mut next_cubic, mut next_quad) = (None, None);
        match seg {
            S::MoveTo { abs, x, y } => {
                pen = rel(abs, x, y);
                start = pen;
                out.push(Verb::Move(pen));
            }
            S::LineTo { abs, x, y } => {
                pen = rel(abs, x, y);
                out.push(Verb::Line(pen));
            }
            S::HorizontalLineTo { abs, x } => {
                pen = Point::new(if abs { x } else { pen.x + x }, pen.y);
                out.push(Verb::Line(pen));
            }
            S::VerticalLineTo { abs, y } => {
                pen = Point::new(pen.x, if abs { y } else { pen.y + y });
                out.push(Verb::Line(pen));
            }
            S::CurveTo {
                abs,
                x1,
                y1,
                x2,
                y2,
                x,
                y,
            } => {
                let (c1, c2, p) = (rel(abs, x1, y1), rel(abs, x2, y2), rel(abs, x, y));
                out.push(Verb::Cubic(c1, c2, p));
                (pen, next_cubic) = (p, Some(c2));
            }
            S::SmoothCurveTo { abs, x2, y2, x, y } => {
                let c1 = cubic_ctrl.map_or(pen, |c| reflect(c, pen));
                let (c2, p) = (rel(abs, x2, y2), rel(abs, x, y));
                out.push(Verb::Cubic(c1, c2, p));
                (pen, next_cubic) = (p, Some(c2));
            }
            S::Quadratic { abs, x1, y1, x, y } => {
                let (c, p) = (rel(abs, x1, y1), rel(abs, x, y));
                out.push(Verb::Quad(c, p));
                (pen, next_quad) = (p, Some(c));
            }
            S::SmoothQuadratic { abs, x, y } => {
                let c = quad_ctrl.map_or(pen, |c| reflect(c, pen));
                let p = rel(abs, x, y);
                out.push(Verb::Quad(c, p));
                (pen, next_quad) = (p, Some(c));
            }
            S::EllipticalArc {
                abs,
                rx,
                ry,
                x_axis_rotation,
                large_arc,
                sweep,
                x,
                y,
            } => {
                let to = rel(abs, x, y);
                let arc = SvgArc {
                    from: pen,
                    to,
                    radii: Vec2::new(rx, ry),
                    x_rotation: x_axis_rotation.to_radians(),
                    large_arc,
                    sweep,
                };
                for v in arc_pieces(&arc) {
                    out.push(v);
                }
                pen = to;
            }
            S::ClosePath { .. } => {
                out.push(Verb::Close);
                pen = start;
                closed = true;
            }
        }
        (cubic_ctrl, quad_ctrl) = (next_cubic, next_quad);
    }
}

/// `c` reflected about `p` (svgtypes' arithmetic: `2·p − c`).
fn reflect(c: Point, p: Point) -> Point {
    Point::new(p.x * 2.0 - c.x, p.y * 2.0 - c.y)
}

/// An SVG arc as exact conic pieces: nothing when its ends coincide, a line when
/// a radius is zero, radii too small to reach the end scaled up (SVG's rules).
pub(super) fn arc_pieces(arc: &SvgArc) -> Vec<Verb> {
    if arc.from == arc.to {
        return Vec::new();
    }
    if arc.radii.x == 0.0 || arc.radii.y == 0.0 || !arc.radii.is_finite() {
        return vec![Verb::Line(arc.to)];
    }
    // kurbo takes radii below 1e-5 for zero: work on the arc scaled by a power of
    // two (exact) about its start, so that its size is about 1.
    let size = arc.radii.x.abs().max(arc.radii.y.abs());
    let k = (-size.log2().floor()).clamp(-1000.0, 1000.0);
    let s = 2f64.powf(k);
    let local = SvgArc {
        from: Point::ORIGIN,
        to: ((arc.to - arc.from) * s).to_point(),
        radii: arc.radii * s,
        ..*arc
    };
    // a chord so short against the radii that its squares underflow: kurbo's
    // centre construction divides by them (0/0); the arc is a point-sized sliver
    // or a full ellipse through one point, neither of which SVG authors mean
    if local.to.to_vec2().hypot() < 1e-120 {
        return vec![Verb::Line(arc.to)];
    }
    let Some(mut centred) = kurbo::Arc::from_svg_arc(&local) else {
        return vec![Verb::Line(arc.to)];
    };
    centred.center = arc.from + centred.center.to_vec2() / s;
    centred.radii /= s;
    if !(centred.center.is_finite() && centred.radii.is_finite()) {
        return vec![Verb::Line(arc.to)];
    }
    Conic::ellipse_arc(&centred, Some(arc.from), Some(arc.to))
        .into_iter()
        .map(Verb::Conic)
        .collect()
}

/// `rx`/`ry` of a `<rect>` or `<ellipse>` (usvg's reading of SVG: a negative or
/// unreadable one is absent, an absent one copies the other, both absent is 0).
fn radii(e: Node<'_, '_>) -> Result<(f64, f64), Unsupported> {
    let get = |attr: &str| {
        e.attribute(attr)
            .and_then(|s| svgtypes::Length::from_str(s).ok())
            .filter(|l| !l.number.is_sign_negative())
    };
    Ok(match (get("rx"), get("ry")) {
        (None, None) => (0.0, 0.0),
        (Some(rx), None) => (absolute(rx)?, absolute(rx)?),
        (None, Some(ry)) => (absolute(ry)?, absolute(ry)?),
        (Some(rx), Some(ry)) => (absolute(rx)?, absolute(ry)?),
    })
}

/// A positive, finite length (what usvg renders).
fn valid(v: f64) -> bool {
    v > 0.0 && v.is_finite()
}

/// A `<rect>`: corners rounded by `rx`/`ry` clamped to half the sides; without
/// rounding when `rx` is zero (usvg's rule; with `ry` zero the corners are lines).
fn rect(e: Node<'_, '_>, out: &mut Commands) -> Result<(), Unsupported> {
    let (w, h) = (length(e, "width", 0.0)?, length(e, "height", 0.0)?);
    if !(valid(w) && valid(h)) {
        return Err("a <rect> without area");
    }
    let (x, y) = (length(e, "x", 0.0)?, length(e, "y", 0.0)?);
    let (rx, ry) = radii(e)?;
    let (rx, ry) = (rx.min(w / 2.0), ry.min(h / 2.0));
    let (x1, y1) = (x + w, y + h);
    if rx == 0.0 {
        out.push(Verb::Move(Point::new(x, y)));
        out.push(Verb::Line(Point::new(x1, y)));
        out.push(Verb::Line(Point::new(x1, y1)));
        out.push(Verb::Line(Point::new(x, y1)));
        out.push(Verb::Close);
        return Ok(());
    }
    let start = Point::new(x + rx, y);
    out.push(Verb::Move(start));
    let mut corner = |from: Point, ctrl: Point, to: Point| {
        out.push(Verb::Line(from));
        if ry == 0.0 {
            out.push(Verb::Line(to));
        } else {
            out.push(Verb::Conic(Conic::new(from, ctrl, to, FRAC_1_SQRT_2)));
        }
    };
    corner(
        Point::new(x1 - rx, y),
        Point::new(x1, y),
        Point::new(x1, y + ry),
    );
    corner(
        Point::new(x1, y1 - ry),
        Point::new(x1, y1),
        Point::new(x1 - rx, y1),
    );
    corner(
        Point::new(x + rx, y1),
        Point::new(x, y1),
        Point::new(x, y1 - ry),
    );
    corner(Point::new(x, y + ry), Point::new(x, y), start);
    out.push(Verb::Close);
    Ok(())
}

/// A full ellipse as four quarter conics, starting at `(cx + rx, cy)` towards
/// `(cx, cy + ry)` (SVG's order, y down), every control point exact.
fn ellipse(cx: f64, cy: f64, rx: f64, ry: f64, out: &mut Commands) -> Result<(), Unsupported> {
    if !(valid(rx) && valid(ry)) {
        return Err("an ellipse without area");
    }
    let (x0, x1, y0, y1) = (cx - rx, cx + rx, cy - ry, cy + ry);
    let quarters = [
        ((x1, cy), (x1, y1), (cx, y1)),
        ((cx, y1), (x0, y1), (x0, cy)),
        ((x0, cy), (x0, y0), (cx, y0)),
        ((cx, y0), (x1, y0), (x1, cy)),
    ];
    out.push(Verb::Move(Point::new(x1, cy)));
    for (a, c, b) in quarters {
        out.push(Verb::Conic(Conic::new(a, c, b, FRAC_1_SQRT_2)));
    }
    out.push(Verb::Close);
    Ok(())
}

/// `points` as a move and lines (usvg renders at least two points).
fn polyline(e: Node<'_, '_>, out: &mut Commands) -> Result<(), Unsupported> {
    let text = e.attribute("points").ok_or("no points")?;
    let mut n = 0;
    for (x, y) in svgtypes::PointsParser::from(text) {
        let p = Point::new(x, y);
        out.push(if n == 0 { Verb::Move(p) } else { Verb::Line(p) });
        n += 1;
    }
    if n < 2 {
        return Err("fewer than two points");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc(to: (f64, f64), r: f64, large: bool) -> SvgArc {
        SvgArc {
            from: Point::ORIGIN,
            to: to.into(),
            radii: Vec2::new(r, r),
            x_rotation: 0.0,
            large_arc: large,
            sweep: true,
        }
    }

    #[test]
    fn degenerate_arcs_are_lines_or_nothing() {
        assert!(arc_pieces(&arc((0.0, 0.0), 1.0, false)).is_empty());
        for a in [
            arc((1e-200, 0.0), 1.0, false),
            arc((1e-200, 0.0), 1.0, true),
            arc((1.0, 0.0), 0.0, true),
            arc((1.0, 0.0), f64::INFINITY, true),
        ] {
            assert!(
                matches!(arc_pieces(&a)[..], [Verb::Line(p)] if p == a.to),
                "{a:?}"
            );
        }
        // a tiny radius (below kurbo's 1e-5) is still an arc: a half circle
        let half = arc_pieces(&arc((2e-9, 0.0), 1e-9, false));
        assert_eq!(half.len(), 2);
        let Verb::Conic(c) = half[0] else {
            panic!("{half:?}")
        };
        assert!(((c.eval(1.0) - Point::new(1e-9, 0.0)).hypot() - 1e-9).abs() < 1e-24);
    }
}
