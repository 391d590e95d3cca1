//! usvg tree → [`Shape`]s: one shape per usvg path (text glyphs included), its
//! absolute transform and the output [`Frame`] applied in f64, y flipped,
//! quadratics elevated to cubics, zero-length segments dropped.

use super::drawing::{FillRule, Segment, Shape, Subpath};
use super::load::XmlFacts;
use super::viewport::Frame;
use crate::{Error, Result};
use kurbo::{CubicBez, Line, Point};
use std::collections::HashSet;
use usvg::tiny_skia_path::PathSegment;

/// Shapes in paint order plus warnings about what was skipped.
#[derive(Debug, Default)]
pub(super) struct Outlines {
    /// One shape per usvg path, in paint (document) order.
    pub(super) shapes: Vec<Shape>,
    /// Skipped text, ignored images and filters.
    pub(super) warnings: Vec<String>,
}

/// A pending step of the tree walk.
enum Step<'a> {
    /// Visit a node; the string is the id inherited from a named `<use>` or `<text>` ancestor.
    Visit(&'a usvg::Node, Option<&'a str>),
    /// All glyph paths of the text node whose walk began at shape count `.1` are done.
    TextDone(&'a usvg::Text, usize),
}

/// Walk the render tree (clip paths, masks and pattern contents are not geometry).
///
/// # Errors
/// [`Error::BadCoordinate`] when a coordinate is not finite or exceeds
/// [`super::Drawing::MAX_COORD`] after transforms.
pub(super) fn collect(tree: &usvg::Tree, facts: &XmlFacts, frame: &Frame) -> Result<Outlines> {
    let mut out = Outlines::default();
    let mut images = 0usize;
    let mut filters = 0usize;
    let mut texts_with_outline: Vec<&str> = Vec::new();
    let mut stack: Vec<Step<'_>> = Vec::new();
    if !tree.root().filters().is_empty() {
        filters += 1;
    }
    for node in tree.root().children().iter().rev() {
        stack.push(Step::Visit(node, None));
    }
    while let Some(step) = stack.pop() {
        match step {
            Step::Visit(usvg::Node::Group(g), inherited) => {
                if !g.filters().is_empty() {
                    filters += 1;
                }
                let inherited = if facts.use_ids.contains(g.id()) {
                    Some(g.id())
                } else {
                    inherited
                };
                for child in g.children().iter().rev() {
                    stack.push(Step::Visit(child, inherited));
                }
            }
            Step::Visit(usvg::Node::Path(p), inherited) => {
                let id = non_empty(p.id()).or(inherited);
                out.shapes
                    .push(convert_path(p, out.shapes.len(), id, frame)?);
            }
            Step::Visit(usvg::Node::Text(t), inherited) => {
                let id = non_empty(t.id()).or(inherited);
                stack.push(Step::TextDone(t, out.shapes.len()));
                let flat = t.flattened();
                if !flat.filters().is_empty() {
                    filters += 1;
                }
                for child in flat.children().iter().rev() {
                    stack.push(Step::Visit(child, id));
                }
            }
            Step::TextDone(t, first_shape) => {
                if out.shapes.len() > first_shape {
                    texts_with_outline.push(t.id());
                } else {
                    let name = non_empty(t.id()).map_or_else(
                        || "a text element".to_owned(),
                        |id| format!("text element '{id}'"),
                    );
                    out.warnings.push(format!(
                        "{name} produced no outline (no usable glyphs); skipped"
                    ));
                }
            }
            Step::Visit(usvg::Node::Image(_), _) => images += 1,
        }
    }
    warn_missing_texts(facts, &texts_with_outline, &mut out.warnings);
    if images > 0 {
        out.warnings.push(format!(
            "{images} image element(s) ignored: raster images are not geometry"
        ));
    }
    if filters > 0 {
        out.warnings.push(format!(
            "filter effects ignored on {filters} element(s): only outlines are meshed"
        ));
    }
    Ok(out)
}

/// Warn about `<text>` elements that usvg dropped (no usable font, typically).
///
/// usvg silently drops a text element it cannot lay out. Text elements are
/// matched by id; anonymous ones by count, in document order (a `<use>` of a
/// text element, or CSS `display: none`, can make this imprecise).
fn warn_missing_texts(facts: &XmlFacts, rendered: &[&str], warnings: &mut Vec<String>) {
    let rendered_ids: HashSet<&str> = rendered.iter().copied().filter(|s| !s.is_empty()).collect();
    let mut anonymous_rendered = rendered.iter().filter(|s| s.is_empty()).count();
    for text in &facts.texts {
        let ok = match &text.id {
            Some(id) => rendered_ids.contains(id.as_str()),
            None if anonymous_rendered > 0 => {
                anonymous_rendered -= 1;
                true
            }
            None => false,
        };
        if !ok {
            warnings.push(format!(
                "{} produced no outline (no usable font, or not rendered); skipped",
                text.label()
            ));
        }
    }
}

/// `Some(s)` unless `s` is empty.
fn non_empty(s: &str) -> Option<&str> {
    (!s.is_empty()).then_some(s)
}

/// One usvg path → one [`Shape`], in output coordinates.
fn convert_path(path: &usvg::Path, index: usize, id: Option<&str>, frame: &Frame) -> Result<Shape> {
    let element_index = u32::try_from(index).unwrap_or(u32::MAX);
    let [sx, ky, kx, sy, tx, ty] = frame.map(path.abs_transform());
    let map = |p: usvg::tiny_skia_path::Point| {
        let (x, y) = (f64::from(p.x), f64::from(p.y));
        Point::new(sx * x + kx * y + tx, -(ky * x + sy * y + ty))
    };
    let subpaths = subpaths(path.data().segments().map(|seg| match seg {
        PathSegment::MoveTo(p) => Verb::Move(map(p)),
        PathSegment::LineTo(p) => Verb::Line(map(p)),
        PathSegment::QuadTo(p1, p2) => Verb::Quad(map(p1), map(p2)),
        PathSegment::CubicTo(p1, p2, p3) => Verb::Cubic(map(p1), map(p2), map(p3)),
        PathSegment::Close => Verb::Close,
    }));
    let shape = Shape {
        svg_id: id.map(str::to_owned),
        element_index,
        paint_order: element_index,
        filled: path.fill().is_some(),
        stroked: path.stroke().is_some(),
        fill_rule: match path.fill().map(usvg::Fill::rule) {
            Some(usvg::FillRule::EvenOdd) => FillRule::EvenOdd,
            _ => FillRule::NonZero,
        },
        fill_colour: path.fill().and_then(|f| match f.paint() {
            usvg::Paint::Color(c) => Some([c.red, c.green, c.blue]),
            _ => None,
        }),
        subpaths,
    };
    check_coordinates(&shape)?;
    Ok(shape)
}

/// A path command in output coordinates.
#[derive(Clone, Copy, Debug)]
pub(super) enum Verb {
    /// Start a subpath.
    Move(Point),
    /// Straight segment to the point.
    Line(Point),
    /// Quadratic Bézier (control, end).
    Quad(Point, Point),
    /// Cubic Bézier (control, control, end).
    Cubic(Point, Point, Point),
    /// Close the subpath.
    Close,
}

/// Build subpaths from path commands: quadratics elevated, zero-length segments dropped.
pub(super) fn subpaths(verbs: impl IntoIterator<Item = Verb>) -> Vec<Subpath> {
    let mut done = Vec::new();
    let mut current: Option<Subpath> = None;
    // Where a drawing command without a preceding move starts (SVG: after `Z`,
    // the current point is the start of the closed subpath).
    let mut pen = Point::ORIGIN;
    for verb in verbs {
        let seg = match verb {
            Verb::Move(p) => {
                done.extend(current.take());
                current = Some(Subpath {
                    segments: Vec::new(),
                    start: p,
                    closed: false,
                });
                pen = p;
                continue;
            }
            Verb::Close => {
                if let Some(mut sub) = current.take() {
                    if pen != sub.start {
                        sub.segments.push(Segment::Line(Line::new(pen, sub.start)));
                    }
                    sub.closed = true;
                    pen = sub.start;
                    done.push(sub);
                }
                continue;
            }
            Verb::Line(p) => (p != pen).then(|| Segment::Line(Line::new(pen, p))),
            Verb::Quad(q1, p) => (q1 != pen || p != pen).then(|| {
                Segment::Cubic(CubicBez::new(
                    pen,
                    pen + (q1 - pen) * (2.0 / 3.0),
                    p + (q1 - p) * (2.0 / 3.0),
                    p,
                ))
            }),
            Verb::Cubic(c1, c2, p) => (c1 != pen || c2 != pen || p != pen)
                .then(|| Segment::Cubic(CubicBez::new(pen, c1, c2, p))),
        };
        let sub = current.get_or_insert_with(|| Subpath {
            segments: Vec::new(),
            start: pen,
            closed: false,
        });
        if let Some(seg) = seg {
            pen = seg.end();
            sub.segments.push(seg);
        }
    }
    done.extend(current);
    done
}

/// Every coordinate finite and within [`super::Drawing::MAX_COORD`].
fn check_coordinates(shape: &Shape) -> Result<()> {
    let limit = super::Drawing::MAX_COORD;
    let points = shape.subpaths.iter().flat_map(|s| {
        std::iter::once(s.start).chain(s.segments.iter().flat_map(Segment::control_points))
    });
    for p in points {
        if !(p.x.abs() <= limit && p.y.abs() <= limit) {
            let what = if p.is_finite() {
                format!("exceeds the limit ±{limit:e}")
            } else {
                "is not finite".to_owned()
            };
            return Err(Error::BadCoordinate(format!(
                "{} has the point ({}, {}) after transforms, which {what}",
                describe(shape),
                p.x,
                -p.y
            )));
        }
    }
    Ok(())
}

/// How an error message names a shape.
pub(super) fn describe(shape: &Shape) -> String {
    match &shape.svg_id {
        Some(id) => format!("element '{id}' (shape #{})", shape.element_index),
        None => format!("shape #{} (document order)", shape.element_index),
    }
}
