//! SVG preview of a [`FemMesh`]: what a user opens to eyeball a result.
//!
//! Triangles are thin grey outlines, feature lines are coloured by kind (primary
//! red, secondary green, constraint blue). Curved elements are drawn exactly: a
//! quadratic or cubic Lagrange edge is converted to the Bézier curve it is.
//! y is flipped back (SVG y = −y), so the preview looks like the input drawing.
//!
//! Triangles are filled either with their region's colour or, with a size
//! field (`--preview-size`), by how their size matches it: the mean of the
//! three corner-to-corner edge lengths over h at the corners' centroid, on a
//! diverging scale (blue below 4/5, neutral within [4/5, 4/3], the band the
//! optimizer aims for, red above 4/3), with a legend to the right.
//!
//! [`PreviewMarks`] adds the element-quality marks of `--preview`:
//! an orange dot in each forced corner (a little inside the triangle, so the
//! two corners of a wedge's vertex are told apart) and a blue ring around the
//! worst unforced element.

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

/// The classes of edge / h: `(lower bound, fill, label as SVG text)`, smallest first. The
/// neutral class is the optimizer's band [4/5, 4/3]; each step away from it is
/// a factor 1.5 (colours: ColorBrewer's 7-class RdBu, blue for small).
const SIZE_CLASSES: [(f64, &str, &str); 7] = [
    (0.0, "#2166ac", "&lt; 0.36"),
    (0.8 / 2.25, "#67a9cf", "0.36 \u{2013} 0.53"),
    (0.8 / 1.5, "#d1e5f0", "0.53 \u{2013} 0.8"),
    (0.8, "#f7f7f7", "0.8 \u{2013} 1.33"),
    (4.0 / 3.0, "#fddbc7", "1.33 \u{2013} 2"),
    (2.0, "#ef8a62", "2 \u{2013} 3"),
    (3.0, "#b2182b", "\u{2265} 3"),
];
/// The legend's width and row height, in pixels.
const LEGEND_WIDTH_PX: f64 = 190.0;
const LEGEND_ROW_PX: f64 = 22.0;

/// Radius of a forced corner's dot and the ring's smallest radius, as
/// fractions of the bounding-box diagonal.
const MARK_DOT_REL: f64 = 2.5e-3;
const MARK_RING_REL: f64 = 1.5e-2;

/// Marks drawn over the mesh: forced corners and the worst unforced element.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct PreviewMarks {
    /// Forced corners as (triangle, corner 0..3).
    pub forced: Vec<(usize, usize)>,
    /// The worst unforced triangle.
    pub worst: Option<usize>,
}

/// The class of `ratio` (edge / h) in [`SIZE_CLASSES`].
fn size_class(ratio: f64) -> usize {
    SIZE_CLASSES[1..]
        .iter()
        .take_while(|c| ratio >= c.0)
        .count()
}

/// A triangle's mean corner-to-corner edge length over `h` at its corners'
/// centroid.
fn size_ratio(tri: &[u32], node: &impl Fn(u32) -> Point, h: &dyn Fn(Point) -> f64) -> f64 {
    let [a, b, c] = [tri[0], tri[1], tri[2]].map(node);
    let mean = (a.distance(b) + b.distance(c) + c.distance(a)) / 3.0;
    let centroid = Point::new((a.x + b.x + c.x) / 3.0, (a.y + b.y + c.y) / 3.0);
    mean / h(centroid)
}

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

/// The longest path data one `<path>` element carries: longer data is split
/// at subpath starts into several elements, since SVG readers bound an
/// attribute's length (libxml2, under librsvg, refuses one of 10 MB).
const PATH_DATA_MAX: usize = 1 << 19;

/// `d` cut at subpath starts (`M`) into pieces of at most [`PATH_DATA_MAX`]
/// bytes (a single subpath longer than that stays whole), trimmed.
fn path_chunks(d: &str) -> Vec<&str> {
    let d = d.trim_end();
    let mut out = Vec::new();
    let mut start = 0;
    while d.len() - start > PATH_DATA_MAX {
        let window = &d[start..start + PATH_DATA_MAX];
        let cut = window
            .rfind('M')
            .filter(|&i| i > 0)
            .map(|i| start + i)
            .or_else(|| {
                d[start + PATH_DATA_MAX..]
                    .find('M')
                    .map(|i| start + PATH_DATA_MAX + i)
            });
        let Some(cut) = cut else { break };
        out.push(d[start..cut].trim_end());
        start = cut;
    }
    if start < d.len() {
        out.push(&d[start..]);
    }
    out
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

/// Write the preview: triangles filled with their surface's colour
/// (`colours[s]`), or by edge / h when `size` gives h. The mesh must have
/// passed `msh::validate`.
pub(crate) fn write_svg<W: Write>(
    w: &mut W,
    mesh: &FemMesh,
    colours: &[Option<String>],
    size: Option<&dyn Fn(Point) -> f64>,
    marks: &PreviewMarks,
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
    let (mesh_w, mesh_h) = (hi.x - lo.x + 2.0 * margin, hi.y - lo.y + 2.0 * margin);
    let scale = PIXELS / mesh_w.max(mesh_h);
    // the legend sits to the right of the mesh, as tall as it needs
    let (vw, vh) = match size {
        Some(_) => (
            mesh_w + LEGEND_WIDTH_PX / scale,
            mesh_h.max((SIZE_CLASSES.len() + 3) as f64 * LEGEND_ROW_PX / scale),
        ),
        None => (mesh_w, mesh_h),
    };

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

    // Fills: by edge / h with a size field, else by region colour; one path
    // per colour (curved edges as the curves they are).
    let mut counts = [0usize; SIZE_CLASSES.len()];
    let fills: Vec<(&str, Vec<usize>)> = match size {
        Some(h) => {
            let mut by_class = vec![Vec::new(); SIZE_CLASSES.len()];
            for t in 0..mesh.triangle_count() {
                let class = size_class(size_ratio(mesh.triangle(t), &node, h));
                by_class[class].push(t);
                counts[class] += 1;
            }
            SIZE_CLASSES.iter().map(|c| c.1).zip(by_class).collect()
        }
        None => colours
            .iter()
            .enumerate()
            .filter_map(|(g, colour)| {
                let colour = colour.as_deref().filter(|c| is_css_hex(c))?;
                let members = (0..mesh.triangle_count())
                    .filter(|&t| mesh.triangle_group[t] as usize == g)
                    .collect();
                Some((colour, members))
            })
            .collect(),
    };
    for (colour, members) in fills {
        let mut fill = PathData { d: String::new() };
        for t in members {
            triangle_outline(order, mesh.triangle(t), &node, &mut fill);
        }
        for d in path_chunks(&fill.d) {
            writeln!(w, "<path fill=\"{colour}\" stroke=\"none\" d=\"{d}\"/>")?;
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
    write_marks(w, mesh, marks, diag)?;
    if size.is_some() {
        write_legend(w, (vx + mesh_w, vy), 1.0 / scale, &counts)?;
    }
    w.write_all(b"</svg>\n")
}

/// The forced corners' dots and the worst unforced element's ring (y flipped
/// like everything else).
fn write_marks<W: Write>(
    w: &mut W,
    mesh: &FemMesh,
    marks: &PreviewMarks,
    diag: f64,
) -> io::Result<()> {
    let dot = MARK_DOT_REL * diag;
    let mut d = String::new();
    for &(t, k) in &marks.forced {
        if t >= mesh.triangle_count() || k > 2 {
            continue;
        }
        let c = mesh.corners(t);
        let centroid = Point::new(
            (c[0].x + c[1].x + c[2].x) / 3.0,
            (c[0].y + c[1].y + c[2].y) / 3.0,
        );
        // A little into the triangle from the corner, never past its centroid.
        let v = c[k];
        let towards = centroid - v;
        let step = towards.hypot().min(2.0 * dot);
        let p = if towards.hypot() > 0.0 {
            v + towards * (step / towards.hypot())
        } else {
            v
        };
        d.push_str(&format!(
            "M{:?} {:?}m{:?} 0a{dot:?} {dot:?} 0 1 0 {:?} 0a{dot:?} {dot:?} 0 1 0 {:?} 0",
            p.x,
            -p.y,
            -dot,
            2.0 * dot,
            -2.0 * dot
        ));
    }
    for d in path_chunks(&d) {
        writeln!(
            w,
            "<path fill=\"#ff7f0e\" fill-opacity=\"0.8\" stroke=\"none\" d=\"{d}\"/>"
        )?;
    }
    if let Some(t) = marks.worst.filter(|&t| t < mesh.triangle_count()) {
        let c = mesh.corners(t);
        let centroid = Point::new(
            (c[0].x + c[1].x + c[2].x) / 3.0,
            (c[0].y + c[1].y + c[2].y) / 3.0,
        );
        let r = c
            .iter()
            .map(|p| p.distance(centroid))
            .fold(MARK_RING_REL * diag, f64::max)
            * 1.2;
        writeln!(
            w,
            "<circle cx=\"{:?}\" cy=\"{:?}\" r=\"{r:?}\" fill=\"none\" stroke=\"#1f3fff\" \
             stroke-width=\"{:?}\"><title>worst unforced element</title></circle>",
            centroid.x,
            -centroid.y,
            FEATURE_STROKE_REL * diag
        )?;
    }
    Ok(())
}

/// The legend of the size shading at `at` (its top left corner, SVG
/// coordinates), `px` user units a pixel: a title, then a swatch, the class's
/// range of edge / h and its number of triangles per class.
fn write_legend<W: Write>(
    w: &mut W,
    at: (f64, f64),
    px: f64,
    counts: &[usize; SIZE_CLASSES.len()],
) -> io::Result<()> {
    let (x, y) = (at.0 + 10.0 * px, at.1 + 10.0 * px);
    let row = LEGEND_ROW_PX * px;
    writeln!(
        w,
        "<g id=\"size-legend\" font-family=\"sans-serif\" font-size=\"{:?}\" fill=\"#202020\">",
        13.0 * px
    )?;
    writeln!(
        w,
        "<text x=\"{x:?}\" y=\"{:?}\" font-weight=\"bold\">edge / h</text>",
        y + 0.7 * row
    )?;
    for (k, ((_, colour, label), n)) in SIZE_CLASSES.iter().zip(counts).enumerate() {
        let top = y + (k + 1) as f64 * row;
        writeln!(
            w,
            "<rect x=\"{x:?}\" y=\"{top:?}\" width=\"{:?}\" height=\"{:?}\" fill=\"{colour}\" \
             stroke=\"#808080\" stroke-width=\"{:?}\"/>",
            16.0 * px,
            16.0 * px,
            px
        )?;
        writeln!(
            w,
            "<text x=\"{:?}\" y=\"{:?}\">{label}</text><text x=\"{:?}\" y=\"{:?}\" \
             text-anchor=\"end\">{n}</text>",
            x + 24.0 * px,
            top + 13.0 * px,
            x + 170.0 * px,
            top + 13.0 * px
        )?;
    }
    writeln!(
        w,
        "<text x=\"{x:?}\" y=\"{:?}\" font-size=\"{:?}\">mean edge / h at the centroid</text>",
        y + (SIZE_CLASSES.len() + 1) as f64 * row + 12.0 * px,
        11.0 * px
    )?;
    writeln!(w, "</g>")
}

/// A closed path around a triangle (its curved edges as the curves they are).
fn triangle_outline(
    order: crate::element::Order,
    tri: &[u32],
    node: &impl Fn(u32) -> Point,
    fill: &mut PathData,
) {
    fill.d.push('M');
    fill.pt(node(tri[0]));
    for k in 0..3 {
        inner_nodes(order, k, tri, node, fill);
        fill.pt(node(tri[(k + 1) % 3]));
    }
    fill.d.push('Z');
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
    for d in path_chunks(d) {
        writeln!(
            w,
            "<path fill=\"none\" stroke=\"{colour}\" stroke-width=\"{width:?}\" \
             stroke-linecap=\"round\" stroke-linejoin=\"round\" d=\"{d}\"/>"
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_path_data_is_cut_at_subpath_starts_into_bounded_pieces() {
        let one = "M1.0 2.0 L3.0 4.0 L5.0 6.0 Z ";
        let d = one.repeat(3 * PATH_DATA_MAX / one.len());
        let pieces = path_chunks(&d);
        assert!(pieces.len() >= 3, "{}", pieces.len());
        for p in &pieces {
            assert!(p.len() <= PATH_DATA_MAX && p.starts_with('M') && !p.ends_with(' '));
        }
        assert_eq!(pieces.join(" "), d.trim_end());
        assert_eq!(path_chunks(""), Vec::<&str>::new());
        assert_eq!(path_chunks("M0 0 L1 1 "), vec!["M0 0 L1 1"]);
    }

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
            periodic: None,
        };
        let mut buf = Vec::new();
        write_svg(&mut buf, &mesh, &[], None, &PreviewMarks::default()).expect("write");
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
        write_svg(
            &mut buf,
            &mesh,
            &[Some("#ff000080".into())],
            None,
            &PreviewMarks::default(),
        )
        .expect("write");
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
        write_svg(
            &mut buf,
            &mesh,
            &[Some("red\" onload=\"x".into())],
            None,
            &PreviewMarks::default(),
        )
        .expect("write");
        assert!(!String::from_utf8(buf).expect("utf8").contains("onload"));
    }

    #[test]
    fn size_classes_are_split_at_four_fifths_and_four_thirds() {
        let neutral = size_class(1.0);
        assert_eq!(SIZE_CLASSES[neutral].1, "#f7f7f7");
        assert_eq!(size_class(0.8), neutral);
        assert_eq!(size_class(4.0 / 3.0 - 1e-12), neutral);
        assert!(size_class(0.8 - 1e-12) < neutral);
        assert!(size_class(4.0 / 3.0) > neutral);
        assert_eq!(size_class(0.0), 0);
        assert_eq!(size_class(100.0), SIZE_CLASSES.len() - 1);
        for k in 1..SIZE_CLASSES.len() {
            assert!(SIZE_CLASSES[k - 1].0 < SIZE_CLASSES[k].0);
        }
    }

    #[test]
    fn size_shading_fills_by_edge_over_h_with_a_legend() {
        // two right triangles of legs 1: mean edge (2 + √2) / 3 ≈ 1.14
        let mesh = FemMesh {
            order: Some(crate::element::Order::Linear),
            nodes: vec![
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(0.0, 1.0),
                Point::new(1.0, 1.0),
            ],
            triangles: vec![0, 1, 2, 1, 3, 2],
            triangle_group: vec![0, 0],
            surfaces: vec!["s".into()],
            lines: vec![],
            line_group: vec![],
            line_kind: vec![],
            curves: vec![],
            periodic: None,
        };
        // h = 1 on the left half, 0.25 on the right: one neutral, one red triangle
        let h = |p: Point| if p.x < 0.5 { 1.0 } else { 0.25 };
        let mut buf = Vec::new();
        write_svg(
            &mut buf,
            &mesh,
            &[Some("#ff0000".into())],
            Some(&h),
            &PreviewMarks::default(),
        )
        .expect("write");
        let s = String::from_utf8(buf).expect("utf8");
        assert!(
            s.contains("id=\"size-legend\"") && s.contains("edge / h"),
            "{s}"
        );
        usvg::Tree::from_str(&s, &usvg::Options::default()).expect("valid SVG");
        // the size shading replaces the region colours
        assert!(!s.contains("#ff0000"), "{s}");
        let filled = |colour: &str| {
            s.lines()
                .filter(|l| l.starts_with("<path") && l.contains(&format!("fill=\"{colour}\"")))
                .map(|l| l.matches('Z').count())
                .sum::<usize>()
        };
        assert_eq!(filled("#f7f7f7"), 1, "{s}");
        assert_eq!(filled("#b2182b"), 1, "{s}"); // 1.14 / 0.25 ≈ 4.6
        // the legend counts them
        assert!(s.contains(">1</text>"), "{s}");
    }
}
