//! SVG preview of a [`FemMesh`]: what a user opens to eyeball a result.
//!
//! Triangles are thin grey outlines, feature lines are coloured by kind (primary
//! red, secondary green, constraint blue). Curved elements are drawn exactly: a
//! quadratic or cubic Lagrange edge is converted to the Bézier curve it is.
//! y is flipped back (SVG y = −y), so the preview looks like the input drawing.

use crate::FemMesh;
use crate::element::lagrange;
use crate::fem::LineKind;
use kurbo::Point;
use std::collections::HashSet;
use std::io::{self, Write};

/// Stroke width of triangle edges, as a fraction of the bounding-box diagonal.
const MESH_STROKE_REL: f64 = 6e-4;
/// Stroke width of feature lines, as a fraction of the bounding-box diagonal.
const FEATURE_STROKE_REL: f64 = 2e-3;
/// Margin around the mesh, as a fraction of the bounding-box diagonal.
const MARGIN_REL: f64 = 0.02;
/// Size in pixels of the longer side of the picture.
const PIXELS: f64 = 1000.0;

/// An edge of an element as the curve it is: end points and Bézier controls.
enum Curve {
    Line(Point, Point),
    Quad(Point, Point, Point),
    Cubic(Point, Point, Point, Point),
}

/// The Bézier form of a Lagrange edge: `ends` and `inner` nodes (evenly spaced in t).
fn edge_curve(a: Point, b: Point, inner: &[Point]) -> Curve {
    match *inner {
        [m] => Curve::Quad(a, lagrange::quadratic_edge_control(a, m, b), b),
        [p1, p2] => {
            let [c1, c2] = lagrange::cubic_edge_controls(a, p1, p2, b);
            Curve::Cubic(a, c1, c2, b)
        }
        _ => Curve::Line(a, b),
    }
}

/// Appends SVG path commands, flipping y.
struct PathData {
    d: String,
}

impl PathData {
    fn pt(&mut self, p: Point) {
        use std::fmt::Write as _;
        let _ = write!(self.d, "{:?} {:?} ", p.x, -p.y);
    }
    fn push(&mut self, c: &Curve) {
        match *c {
            Curve::Line(a, b) => {
                self.d.push('M');
                self.pt(a);
                self.d.push('L');
                self.pt(b);
            }
            Curve::Quad(a, c, b) => {
                self.d.push('M');
                self.pt(a);
                self.d.push('Q');
                self.pt(c);
                self.pt(b);
            }
            Curve::Cubic(a, c1, c2, b) => {
                self.d.push('M');
                self.pt(a);
                self.d.push('C');
                self.pt(c1);
                self.pt(c2);
                self.pt(b);
            }
        }
    }
}

/// Write the preview. The mesh must have passed `msh::validate`.
pub(crate) fn write_svg<W: Write>(
    w: &mut W,
    mesh: &FemMesh,
    colours: &[Option<String>],
) -> io::Result<()> {
    let order = mesh.order();
    let node = |i: u32| mesh.nodes[i as usize];

    // Bounding box of the nodes (a unit box for an empty mesh).
    let (mut lo, mut hi) = (Point::new(f64::INFINITY, f64::INFINITY), Point::ORIGIN);
    hi.x = f64::NEG_INFINITY;
    hi.y = f64::NEG_INFINITY;
    for p in &mesh.nodes {
        lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    if lo.x > hi.x {
        lo = Point::ORIGIN;
        hi = Point::new(1.0, 1.0);
    }
    let mut diag = (hi - lo).hypot();
    if !(diag > 0.0 && diag.is_finite()) {
        diag = 1.0;
    }
    let margin = MARGIN_REL * diag;
    let (vx, vy) = (lo.x - margin, -hi.y - margin);
    let (vw, vh) = (hi.x - lo.x + 2.0 * margin, hi.y - lo.y + 2.0 * margin);
    let scale = PIXELS / vw.max(vh);

    writeln!(
        w,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"{vx:?} {vy:?} {vw:?} {vh:?}\" \
         width=\"{:.0}\" height=\"{:.0}\">",
        (vw * scale).max(1.0),
        (vh * scale).max(1.0)
    )?;
    writeln!(
        w,
        "<rect x=\"{vx:?}\" y=\"{vy:?}\" width=\"{vw:?}\" height=\"{vh:?}\" fill=\"white\"/>"
    )?;

    // Region colours: each triangle filled, one path per surface (its curved
    // edges as the curves they are).
    for (g, colour) in colours.iter().enumerate() {
        let Some(colour) = colour.as_deref().filter(|c| is_css_hex(c)) else {
            continue;
        };
        let mut d = String::new();
        for t in (0..mesh.triangle_count()).filter(|&t| mesh.triangle_group[t] as usize == g) {
            let tri = mesh.triangle(t);
            let mut fill = PathData { d: String::new() };
            fill.d.push('M');
            fill.pt(node(tri[0]));
            for k in 0..3 {
                inner_nodes(order, k, tri, &node, &mut fill);
                fill.pt(node(tri[(k + 1) % 3]));
            }
            fill.d.push('Z');
            d.push_str(&fill.d);
        }
        if !d.is_empty() {
            writeln!(
                w,
                "<path fill=\"{colour}\" stroke=\"none\" d=\"{}\"/>",
                d.trim_end()
            )?;
        }
    }

    // Triangle edges, each once.
    let mut seen: HashSet<(u32, u32)> = HashSet::with_capacity(mesh.triangle_count() * 2);
    let mut path = PathData { d: String::new() };
    let mut inner = Vec::with_capacity(2);
    for t in 0..mesh.triangle_count() {
        let tri = mesh.triangle(t);
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if !seen.insert((a.min(b), a.max(b))) {
                continue;
            }
            inner.clear();
            inner.extend(
                crate::fem::triangle_edge_inner(order, k)
                    .iter()
                    .map(|&j| node(tri[j])),
            );
            path.push(&edge_curve(node(a), node(b), &inner));
        }
        if path.d.len() > 1 << 16 {
            write_path(w, &path.d, "#808080", MESH_STROKE_REL * diag)?;
            path.d.clear();
        }
    }
    write_path(w, &path.d, "#808080", MESH_STROKE_REL * diag)?;

    // Feature lines by kind.
    for (kind, colour) in [
        (LineKind::Secondary, "#2ca02c"),
        (LineKind::Constraint, "#1f77b4"),
        (LineKind::Boundary, "#000000"),
        (LineKind::Primary, "#d62728"),
    ] {
        let mut path = PathData { d: String::new() };
        for l in 0..mesh.line_count() {
            // Lines without a kind (a short `line_kind`) are drawn as constraints.
            let k = mesh
                .line_kind
                .get(l)
                .copied()
                .unwrap_or(LineKind::Constraint);
            if k != kind {
                continue;
            }
            let line = mesh.line(l);
            inner.clear();
            inner.extend(line[2..].iter().map(|&j| node(j)));
            path.push(&edge_curve(node(line[0]), node(line[1]), &inner));
            if path.d.len() > 1 << 16 {
                write_path(w, &path.d, colour, FEATURE_STROKE_REL * diag)?;
                path.d.clear();
            }
        }
        write_path(w, &path.d, colour, FEATURE_STROKE_REL * diag)?;
    }
    w.write_all(b"</svg>\n")
}

/// Whether `c` is `#` and 6 or 8 hex digits (nothing else reaches the SVG).
fn is_css_hex(c: &str) -> bool {
    c.strip_prefix('#')
        .is_some_and(|h| matches!(h.len(), 6 | 8) && h.bytes().all(|b| b.is_ascii_hexdigit()))
}

/// The path command from a triangle's corner `k` to corner `k + 1` (the end
/// point written by the caller): `L`, or `Q` / `C` with the edge's controls.
fn inner_nodes(
    order: crate::element::Order,
    k: usize,
    tri: &[u32],
    node: &impl Fn(u32) -> Point,
    fill: &mut PathData,
) {
    let (a, b) = (node(tri[k]), node(tri[(k + 1) % 3]));
    let inner: Vec<Point> = crate::fem::triangle_edge_inner(order, k)
        .iter()
        .map(|&j| node(tri[j]))
        .collect();
    match edge_curve(a, b, &inner) {
        Curve::Line(..) => fill.d.push('L'),
        Curve::Quad(_, c, _) => {
            fill.d.push('Q');
            fill.pt(c);
        }
        Curve::Cubic(_, c1, c2, _) => {
            fill.d.push('C');
            fill.pt(c1);
            fill.pt(c2);
        }
    }
}

fn write_path<W: Write>(w: &mut W, d: &str, colour: &str, width: f64) -> io::Result<()> {
    if d.is_empty() {
        return Ok(());
    }
    writeln!(
        w,
        "<path fill=\"none\" stroke=\"{colour}\" stroke-width=\"{width:?}\" \
         stroke-linecap=\"round\" stroke-linejoin=\"round\" d=\"{}\"/>",
        d.trim_end()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval_cubic(p: [Point; 4], t: f64) -> Point {
        let s = 1.0 - t;
        let c = [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t];
        Point::new(
            (0..4).map(|i| c[i] * p[i].x).sum(),
            (0..4).map(|i| c[i] * p[i].y).sum(),
        )
    }

    #[test]
    fn cubic_edge_passes_through_lagrange_nodes() {
        let a = Point::new(0.0, 0.0);
        let b = Point::new(3.0, 0.0);
        let p1 = Point::new(1.0, 0.7);
        let p2 = Point::new(2.1, -0.4);
        let Curve::Cubic(a0, c1, c2, b0) = edge_curve(a, b, &[p1, p2]) else {
            panic!("expected a cubic");
        };
        let q1 = eval_cubic([a0, c1, c2, b0], 1.0 / 3.0);
        let q2 = eval_cubic([a0, c1, c2, b0], 2.0 / 3.0);
        assert!((q1 - p1).hypot() < 1e-12, "{q1:?}");
        assert!((q2 - p2).hypot() < 1e-12, "{q2:?}");
    }

    #[test]
    fn quadratic_edge_passes_through_midpoint() {
        let (a, b, m) = (
            Point::new(0.0, 0.0),
            Point::new(2.0, 0.0),
            Point::new(1.0, 1.0),
        );
        let Curve::Quad(_, c, _) = edge_curve(a, b, &[m]) else {
            panic!("expected a quadratic");
        };
        // B(1/2) = (a + 2c + b) / 4
        let mid = Point::new((a.x + 2.0 * c.x + b.x) / 4.0, (a.y + 2.0 * c.y + b.y) / 4.0);
        assert!((mid - m).hypot() < 1e-15);
    }

    #[test]
    fn preview_flips_y_and_colours_kinds() {
        let mesh = FemMesh {
            order: Some(crate::element::Order::Linear),
            nodes: vec![
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(0.0, 2.0),
            ],
            triangles: vec![0, 1, 2],
            triangle_group: vec![0],
            surfaces: vec!["s".into()],
            lines: vec![0, 1, 1, 2],
            line_group: vec![0, 0],
            line_kind: vec![LineKind::Primary, LineKind::Secondary],
            curves: vec!["c".into()],
        };
        let mut buf = Vec::new();
        write_svg(&mut buf, &mesh, &[]).expect("write");
        let s = String::from_utf8(buf).expect("utf8");
        assert!(s.contains("#d62728") && s.contains("#2ca02c") && !s.contains("#1f77b4"));
        assert!(s.contains("0.0 -2.0"), "{s}");
        assert!(s.contains("fill=\"white\""));
        // Three triangle edges, each drawn once.
        let grey = s
            .lines()
            .find(|l| l.contains("#808080"))
            .expect("mesh path");
        assert_eq!(grey.matches('M').count(), 3);
        // with colours: the surface's triangles filled, one closed outline each;
        // anything but a hex colour never reaches the SVG
        let mut buf = Vec::new();
        write_svg(&mut buf, &mesh, &[Some("#ff000080".into())]).expect("write");
        let s = String::from_utf8(buf).expect("utf8");
        let fill = s
            .lines()
            .find(|l| l.contains("fill=\"#ff000080\""))
            .expect("region path");
        assert_eq!(
            (fill.matches('M').count(), fill.matches('Z').count()),
            (1, 1)
        );
        let mut buf = Vec::new();
        write_svg(&mut buf, &mesh, &[Some("red\" onload=\"x".into())]).expect("write");
        assert!(!String::from_utf8(buf).expect("utf8").contains("onload"));
    }
}
