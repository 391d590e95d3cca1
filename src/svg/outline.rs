//! usvg tree → [`Shape`]s: one shape per usvg path (text glyphs included), in
//! output coordinates (y flipped), quadratics elevated to cubics, zero-length
//! segments dropped.
//!
//! Each path's geometry is re-derived in f64 from its source element
//! (`reconstruct.rs`); when that is not possible, or disagrees with usvg, the
//! path keeps usvg's f32 data with its absolute transform and the output
//! [`Frame`] applied in f64 (text glyphs and markers always do).

use super::conic::Conic;
use super::drawing::{FillRule, Segment, Shape, Subpath};
use super::load::{Parsed, XmlFacts};
use super::reconstruct::{self, MARKER, OutputMap, Precision};
use super::source::{Candidate, Source, Unsupported};
use super::viewport::Frame;
use crate::{Error, Result};
use kurbo::{Affine, CubicBez, Line, Point};
use std::collections::HashSet;
use usvg::tiny_skia_path::PathSegment;

/// How many candidates of a `<use>` instance a path is tried against, from the
/// instance's cursor on (usvg skips invisible elements; ids do not survive into
/// instances, so their paths are matched in order).
const INSTANCE_WINDOW: usize = 64;

/// Shapes in paint order plus warnings about what was skipped.
#[derive(Debug, Default)]
pub(super) struct Outlines {
    /// One shape per usvg path, in paint (document) order.
    pub(super) shapes: Vec<Shape>,
    /// Skipped text, ignored images and filters, paths kept in single precision.
    pub(super) warnings: Vec<String>,
    /// How the paths came out.
    pub(super) precision: Precision,
}

/// Where a usvg node sits: in the document, in a `<use>` instance (index into the
/// walk's instances), or in a text element's glyph outlines.
#[derive(Clone, Copy, Debug)]
enum Scope {
    Document,
    Instance(usize),
    Text,
}

/// The shape instances a `<use>` draws, and how far its paths have matched them.
struct Instance<'a, 'input> {
    candidates: Vec<Candidate<'a, 'input>>,
    cursor: usize,
}

/// A pending step of the tree walk.
enum Step<'a> {
    /// Visit a node; the string is the id inherited from a named `<use>` or `<text>` ancestor.
    Visit(&'a usvg::Node, Option<&'a str>, Scope),
    /// All glyph paths of the text node whose walk began at shape count `.1` are done.
    TextDone(&'a usvg::Text, usize),
}

/// Walk the render tree (clip paths, masks and pattern contents are not geometry).
///
/// # Errors
/// [`Error::BadCoordinate`] when a coordinate is not finite or exceeds
/// [`super::Drawing::MAX_COORD`] after transforms.
pub(super) fn collect(parsed: &Parsed<'_, '_>, frame: &Frame, map: OutputMap) -> Result<Outlines> {
    let (tree, facts, source) = (&parsed.tree, &parsed.facts, &parsed.source);
    let mut out = Outlines::default();
    let mut images = 0usize;
    let mut filters = 0usize;
    let mut texts_with_outline: Vec<&str> = Vec::new();
    let mut instances: Vec<Instance<'_, '_>> = Vec::new();
    let mut stack: Vec<Step<'_>> = Vec::new();
    if !tree.root().filters().is_empty() {
        filters += 1;
    }
    for node in tree.root().children().iter().rev() {
        stack.push(Step::Visit(node, None, Scope::Document));
    }
    while let Some(step) = stack.pop() {
        match step {
            Step::Visit(usvg::Node::Group(g), inherited, scope) => {
                if !g.filters().is_empty() {
                    filters += 1;
                }
                let inherited = if facts.use_ids.contains(g.id()) {
                    source.public(g.id()).or(inherited)
                } else {
                    inherited
                };
                let mut scope = scope;
                if matches!(scope, Scope::Document) {
                    let uses = source.uses_with_id(g.id());
                    if !uses.is_empty() {
                        scope = Scope::Instance(instances.len());
                        instances.push(Instance {
                            candidates: source.expand_uses(&uses),
                            cursor: 0,
                        });
                    }
                }
                for child in g.children().iter().rev() {
                    stack.push(Step::Visit(child, inherited, scope));
                }
            }
            Step::Visit(usvg::Node::Path(p), inherited, scope) => {
                let id = source.public(p.id()).or(inherited);
                let mut shape = convert_path(p, out.shapes.len(), id, frame)?;
                match exact_subpaths(p, scope, source, &mut instances, map, &shape.subpaths) {
                    Ok(subpaths) => {
                        shape.subpaths = subpaths;
                        check_coordinates(&shape)?;
                        out.precision.exact += 1;
                    }
                    Err(None) => out.precision.glyphs += 1,
                    Err(Some(reason)) => *out.precision.fallback.entry(reason).or_default() += 1,
                }
                out.shapes.push(shape);
            }
            Step::Visit(usvg::Node::Text(t), inherited, _) => {
                let id = source.public(t.id()).or(inherited);
                stack.push(Step::TextDone(t, out.shapes.len()));
                let flat = t.flattened();
                if !flat.filters().is_empty() {
                    filters += 1;
                }
                for child in flat.children().iter().rev() {
                    stack.push(Step::Visit(child, id, Scope::Text));
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
            Step::Visit(usvg::Node::Image(_), _, _) => images += 1,
        }
    }
    warn_missing_texts(facts, &texts_with_outline, &mut out.warnings);
    // usvg keeps an image node only for data it could decode (never, here)
    let images = images.max(facts.images);
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
    out.warnings.extend(out.precision.warning());
    Ok(out)
}

/// The f64 subpaths of usvg path `p` from its source element, or why not
/// (`None` for a text glyph outline, single precision by design).
fn exact_subpaths<'a, 'input>(
    p: &usvg::Path,
    scope: Scope,
    source: &Source<'a, 'input>,
    instances: &mut [Instance<'a, 'input>],
    map: OutputMap,
    reference: &[Subpath],
) -> std::result::Result<Vec<Subpath>, Option<Unsupported>> {
    let attempt = |c: &Candidate<'a, 'input>| reconstruct::reconstruct(source, c, map, reference);
    let first_ok = |candidates: &mut dyn Iterator<Item = (usize, Candidate<'a, 'input>)>| {
        let mut first_err = None;
        for (k, c) in candidates {
            match attempt(&c) {
                Ok(sp) => return Ok((k, sp)),
                Err(e) => {
                    first_err.get_or_insert(e);
                }
            }
        }
        Err(first_err)
    };
    match scope {
        Scope::Text => Err(None),
        // an id (the document's or a private one) names the element
        _ if !p.id().is_empty() => {
            let nodes = source.shapes_with_id(p.id());
            let mut candidates = nodes.into_iter().map(|node| Candidate {
                node,
                uses: Vec::new(),
            });
            first_ok(&mut candidates.by_ref().enumerate())
                .map(|(_, sp)| sp)
                .map_err(|e| Some(e.unwrap_or("no source element with the path's id")))
        }
        Scope::Instance(i) => {
            let inst = &mut instances[i];
            let end = (inst.cursor + INSTANCE_WINDOW).min(inst.candidates.len());
            let mut candidates = (inst.cursor..end).map(|k| (k, inst.candidates[k].clone()));
            match first_ok(&mut candidates) {
                Ok((k, sp)) => {
                    inst.cursor = k + 1;
                    Ok(sp)
                }
                Err(e) => Err(Some(
                    e.unwrap_or("a <use> instance path without a source element"),
                )),
            }
        }
        Scope::Document => Err(Some(MARKER)),
    }
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

/// A path command (in an element's own coordinates or in output coordinates).
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
    /// An exact conic piece from the current point (its `p0`) to its `p2`.
    Conic(Conic),
    /// Close the subpath.
    Close,
}

impl Verb {
    /// The command's points.
    pub(super) fn points(&self) -> Vec<Point> {
        match *self {
            Verb::Move(p) | Verb::Line(p) => vec![p],
            Verb::Quad(a, b) => vec![a, b],
            Verb::Cubic(a, b, c) => vec![a, b, c],
            Verb::Conic(c) => c.control_points().to_vec(),
            Verb::Close => Vec::new(),
        }
    }

    /// The command under an affine map (exact for conics: weights are kept).
    pub(super) fn transform(&self, m: Affine) -> Verb {
        match *self {
            Verb::Move(p) => Verb::Move(m * p),
            Verb::Line(p) => Verb::Line(m * p),
            Verb::Quad(a, b) => Verb::Quad(m * a, m * b),
            Verb::Cubic(a, b, c) => Verb::Cubic(m * a, m * b, m * c),
            Verb::Conic(c) => Verb::Conic(c.transform(m)),
            Verb::Close => Verb::Close,
        }
    }
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
            // a conic starts at the current point by construction (its `p0` is
            // the end of the previous command, bit for bit)
            Verb::Conic(c) => (c.p1 != pen || c.p2 != pen)
                .then(|| Segment::Conic(Conic::new(pen, c.p1, c.p2, c.w))),
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
                short_number(p.x),
                short_number(-p.y)
            )));
        }
    }
    Ok(())
}

/// A number as a message shows it: plain when moderate, else in scientific
/// notation (never 300 digits).
fn short_number(x: f64) -> String {
    if x == 0.0 || (1e-6..1e15).contains(&x.abs()) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// How an error message names a shape.
pub(super) fn describe(shape: &Shape) -> String {
    match &shape.svg_id {
        Some(id) => format!("element '{id}' (shape #{})", shape.element_index),
        None => format!("shape #{} (document order)", shape.element_index),
    }
}
