//! usvg tree → [`Shape`]s: one shape per usvg path (text glyphs included), in
//! output coordinates (y flipped), quadratics elevated to cubics, zero-length
//! segments dropped.
//!
//! Each path's geometry is re-derived in f64 from its source element
//! (`reconstruct.rs`); when that is not possible, or disagrees with usvg, the
//! path keeps usvg's f32 data with its absolute transform and the output
//! [`Frame`] applied in f64 (text glyphs and markers always do).

use super::conic::Conic;
use super::drawing::{
    Clip, ClipPart, FillRule, PaintCounts, Segment, Shape, ShapeKind, ShapePaint, Subpath,
};
use super::load::{Parsed, XmlFacts};
use super::paint::{self, PaintOptions, StrokeMode};
use super::reconstruct::{self, MARKER, OutputMap, Precision};
use super::source::{Candidate, Source, Unsupported};
use super::viewport::Frame;
use crate::{Error, Result};
use kurbo::{Affine, CubicBez, Line, Point};
use std::collections::HashSet;
use std::rc::Rc;
use std::sync::Arc;
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
    /// What the paint model did.
    pub(super) paint: PaintCounts,
    /// The loader audit's ledger (tests only): what became of each usvg path
    /// the walk visited, by the path's address in the tree.
    #[cfg(test)]
    pub(super) ledger: Vec<(usize, [Fate; 2])>,
    /// The loader audit's ledger (tests only): the groups skipped as markers
    /// on a basic shape, by address.
    #[cfg(test)]
    pub(super) skipped_markers: Vec<usize>,
}

/// What became of a path's fill or stroke.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Fate {
    /// No such paint.
    None,
    /// Not painted at all ([`PaintCounts::dropped_invisible`]).
    Invisible,
    /// Below `--min-opacity` ([`PaintCounts::dropped_decoration`]).
    Decoration,
    /// A stroke left out (`--strokes ignore`, [`PaintCounts::strokes_ignored`]).
    Ignored,
    /// Painted: a shape (a fill, a stroke's area, or a stroke's centre line).
    Painted,
}

/// What the groups above a node do to its paint.
#[derive(Clone, Debug)]
struct Ctx {
    /// Product of the group opacities.
    opacity: f32,
    /// Clip paths and masks along the chain (all apply).
    clips: Vec<Arc<Clip>>,
    /// A group on the chain has a filter.
    filtered: bool,
    /// usvg's coordinates to output coordinates (with the transforms usvg
    /// was kept from on the chain, [`Source::usvg_omits`]).
    frame: Frame,
}

impl Ctx {
    fn root(frame: Frame) -> Ctx {
        Ctx {
            opacity: 1.0,
            clips: Vec::new(),
            filtered: false,
            frame,
        }
    }
}

/// One painted element before strokes are resolved (the hairline width and
/// the outlines' accuracy need the drawing's size).
enum Item {
    /// A shape as it is.
    Shape(Shape),
    /// A stroke to expand into its area, and what replaces it if it is too
    /// thin: its centre lines (`None` when the element's fill already carries them).
    Stroke(Box<PendingStroke>),
    /// A fill or stroke below `--min-opacity`: how the warning names it, its
    /// effective opacity, and its outline when decoration is kept.
    Decoration(String, f32, Option<Shape>),
}

/// A stroke whose area is computed once the drawing's size is known.
struct PendingStroke {
    /// The area's shape, its subpaths still the centre line (output coordinates).
    area: Shape,
    /// The stroke's style (width, joins, caps, dashes in user space).
    stroke: usvg::Stroke,
    /// The path's user space to output coordinates.
    to_output: Affine,
    /// The centre lines that replace a stroke too thin to mesh as an area.
    centre: Option<Shape>,
    /// The width in output units.
    width: f64,
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
    Visit(&'a usvg::Node, Option<&'a str>, Scope, Rc<Ctx>),
    /// All glyph paths of the text node whose walk began at shape count `.1` are done.
    TextDone(&'a usvg::Text, usize),
}

/// Walk the render tree (clip paths and masks limit the shapes they apply to;
/// pattern contents are not geometry).
///
/// # Errors
/// [`Error::BadCoordinate`] when a coordinate is not finite or exceeds
/// [`super::Drawing::MAX_COORD`] after transforms.
pub(super) fn collect(
    parsed: &Parsed<'_, '_>,
    frame: &Frame,
    map: OutputMap,
    opts: &PaintOptions,
) -> Result<Outlines> {
    let (tree, facts, source) = (&parsed.tree, &parsed.facts, &parsed.source);
    let mut out = Outlines::default();
    let mut items: Vec<Item> = Vec::new();
    let mut paths = 0usize;
    let mut images = 0usize;
    let mut filters = 0usize;
    let mut texts_with_outline: Vec<&str> = Vec::new();
    let mut instances: Vec<Instance<'_, '_>> = Vec::new();
    let mut stack: Vec<Step<'_>> = Vec::new();
    let mut root = Ctx::root(*frame);
    if !tree.root().filters().is_empty() {
        filters += 1;
        root.filtered = true;
    }
    let root = Rc::new(root);
    let children = tree.root().children();
    for (k, node) in children.iter().enumerate().rev() {
        if is_basic_shape_markers(children, k, source) {
            skip_markers(node, &mut out);
        } else {
            stack.push(Step::Visit(node, None, Scope::Document, root.clone()));
        }
    }
    while let Some(step) = stack.pop() {
        match step {
            Step::Visit(usvg::Node::Group(g), inherited, scope, ctx) => {
                if !g.filters().is_empty() {
                    filters += 1;
                }
                let ctx = match source
                    .usvg_omits(g.id())
                    .and_then(|t| ctx.frame.with_omitted(g.abs_transform(), t))
                {
                    Some(frame) => Rc::new(Ctx {
                        frame,
                        ..(*ctx).clone()
                    }),
                    None => ctx,
                };
                let ctx = group_ctx(g, &ctx)?;
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
                let children = g.children();
                for (k, child) in children.iter().enumerate().rev() {
                    if is_basic_shape_markers(children, k, source) {
                        skip_markers(child, &mut out);
                    } else {
                        stack.push(Step::Visit(child, inherited, scope, ctx.clone()));
                    }
                }
            }
            Step::Visit(usvg::Node::Path(p), inherited, scope, ctx) => {
                let id = source.public(p.id()).or(inherited);
                let frame = source
                    .usvg_omits(p.id())
                    .and_then(|t| ctx.frame.with_omitted(p.abs_transform(), t))
                    .unwrap_or(ctx.frame);
                let mut shape = convert_path(p, paths, id, &frame)?;
                paths += 1;
                match exact_subpaths(p, scope, source, &mut instances, map, &shape.subpaths) {
                    Ok(subpaths) => {
                        shape.subpaths = subpaths;
                        check_coordinates(&shape)?;
                        out.precision.exact += 1;
                    }
                    Err(None) => out.precision.glyphs += 1,
                    Err(Some(reason)) => *out.precision.fallback.entry(reason).or_default() += 1,
                }
                if !p.id().is_empty() {
                    shape.paint.stretched_by = source
                        .shapes_with_id(p.id())
                        .first()
                        .and_then(|&node| source.most_uneven(node));
                }
                let servers = [
                    document_server(p, source, "fill"),
                    document_server(p, source, "stroke"),
                ];
                let fates = paint_items(
                    p,
                    shape,
                    &ctx,
                    &frame,
                    opts,
                    &servers,
                    &mut items,
                    &mut out.paint,
                )?;
                #[cfg(test)]
                out.ledger
                    .push((std::ptr::from_ref::<usvg::Path>(p).addr(), fates));
                #[cfg(not(test))]
                let _ = fates;
            }
            Step::Visit(usvg::Node::Text(t), inherited, _, ctx) => {
                let id = source.public(t.id()).or(inherited);
                stack.push(Step::TextDone(t, paths));
                let flat = t.flattened();
                if !flat.filters().is_empty() {
                    filters += 1;
                }
                let ctx = group_ctx(flat, &ctx)?;
                for child in flat.children().iter().rev() {
                    stack.push(Step::Visit(child, id, Scope::Text, ctx.clone()));
                }
            }
            Step::TextDone(t, first_path) => {
                if paths > first_path {
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
            Step::Visit(usvg::Node::Image(_), _, _, _) => images += 1,
        }
    }
    out.shapes = resolve_items(items, opts, &mut out.paint, &mut out.warnings)?;
    out.warnings.extend(source.dropped_for_tiny_transforms());
    if paths == 0 {
        out.warnings.extend(source.all_under_references());
    }
    add_clip_outlines(&mut out.shapes, paths);
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
            "filter effects ignored on {filters} element(s): only outlines are meshed \
             ({} shape(s) under a filter)",
            out.paint.filtered_shapes
        ));
    }
    if out.paint.masked_shapes > 0 {
        out.warnings.push(format!(
            "{} shape(s) under a mask: the mask is approximated as a clip by its \
             content's fills (where it is not fully transparent)",
            out.paint.masked_shapes
        ));
    }
    out.warnings.extend(out.precision.warning());
    Ok(out)
}

/// The id of the paint server `url(#id)` that the source element of `p` (or the
/// nearest ancestor that sets it) names for `property` (`fill` or `stroke`), as
/// written in the document: usvg renames a bounding-box gradient used twice.
fn document_server(p: &usvg::Path, source: &Source<'_, '_>, property: &str) -> Option<String> {
    if p.id().is_empty() {
        return None;
    }
    let node = *source.shapes_with_id(p.id()).first()?;
    for n in node.ancestors().filter(usvg::roxmltree::Node::is_element) {
        let in_style = n.attribute("style").and_then(|style| {
            style.split(';').find_map(|decl| {
                let (k, v) = decl.split_once(':')?;
                (k.trim() == property).then(|| v.trim())
            })
        });
        if let Some(value) = in_style.or_else(|| n.attribute(property)) {
            let id = value
                .strip_prefix("url(")?
                .trim_start_matches(['\'', '"', '#']);
            let end = id.find([')', '\'', '"'])?;
            return Some(id[..end].to_owned()).filter(|s| !s.is_empty());
        }
    }
    None
}

/// Skip `node`, usvg's markers on a basic shape: its fills and strokes are
/// counted in [`PaintCounts::markers_not_drawn`].
fn skip_markers(node: &usvg::Node, out: &mut Outlines) {
    fn count(node: &usvg::Node) -> usize {
        match node {
            usvg::Node::Group(g) => g.children().iter().map(count).sum(),
            usvg::Node::Path(p) => {
                usize::from(p.fill().is_some()) + usize::from(p.stroke().is_some())
            }
            usvg::Node::Text(t) => t.flattened().children().iter().map(count).sum(),
            usvg::Node::Image(_) => 0,
        }
    }
    out.paint.markers_not_drawn += count(node);
    #[cfg(test)]
    out.skipped_markers.push(std::ptr::from_ref(node).addr());
}

/// Whether `siblings[k]` is the group of markers usvg draws on a `<rect>`,
/// `<circle>` or `<ellipse>` (SVG draws markers on path, line, polyline and
/// polygon only).
///
/// usvg puts that group right before or after the element's path, and makes it
/// only when a marker property resolves. So the group is recognised by what it
/// holds and by what its neighbour asks for, never by a neighbour's style
/// merely mentioning markers (`marker: none` included): it has the form of a
/// marker group ([`holds_marker_instances`]), and a neighbouring path is such
/// an element whose `marker-start`, `marker-mid` or `marker-end` names a
/// `<marker>` ([`Source::may_have_markers`]).
fn is_basic_shape_markers(siblings: &[usvg::Node], k: usize, source: &Source<'_, '_>) -> bool {
    let usvg::Node::Group(g) = &siblings[k] else {
        return false;
    };
    let basic_with_markers = |j: usize| {
        let Some(usvg::Node::Path(p)) = siblings.get(j) else {
            return false;
        };
        !p.id().is_empty()
            && source.shapes_with_id(p.id()).first().is_some_and(|n| {
                matches!(n.tag_name().name(), "rect" | "circle" | "ellipse")
                    && source.may_have_markers(*n)
            })
    };
    // the neighbour first: rare to pass, and cheaper than the group's content
    ((k > 0 && basic_with_markers(k - 1)) || basic_with_markers(k + 1)) && holds_marker_instances(g)
}

/// Whether `g` has the form of usvg's marker group: no id, transform, clip,
/// mask, filter, opacity or blending of its own; every child an anonymous group
/// (one per marker instance: a marker's position, scale and `overflow` clip);
/// no path below it with an id (usvg gives marker content none, while every
/// shape of the document has one, its own or a private one: a group usvg makes
/// for a transformed, clipped or masked element holds that element's path).
fn holds_marker_instances(g: &usvg::Group) -> bool {
    fn no_named_path(g: &usvg::Group) -> bool {
        g.children().iter().all(|c| match c {
            usvg::Node::Group(inner) => no_named_path(inner),
            usvg::Node::Path(p) => p.id().is_empty(),
            usvg::Node::Image(i) => i.id().is_empty(),
            usvg::Node::Text(t) => t.id().is_empty(),
        })
    }
    g.id().is_empty()
        && g.transform().is_identity()
        && g.clip_path().is_none()
        && g.mask().is_none()
        && g.filters().is_empty()
        && g.opacity().get() >= 1.0
        && g.blend_mode() == usvg::BlendMode::Normal
        && !g.isolate()
        && g.children().iter().all(|c| match c {
            usvg::Node::Group(inner) => inner.id().is_empty(),
            _ => false,
        })
        && no_named_path(g)
}

/// The context of a group's children: its opacity, clip path, mask and filters added.
fn group_ctx(g: &usvg::Group, parent: &Rc<Ctx>) -> Result<Rc<Ctx>> {
    let frame = &parent.frame;
    let plain = g.opacity().get() >= 1.0
        && g.clip_path().is_none()
        && g.mask().is_none()
        && g.filters().is_empty();
    if plain {
        return Ok(parent.clone());
    }
    let mut ctx = (**parent).clone();
    ctx.opacity *= g.opacity().get();
    ctx.filtered |= !g.filters().is_empty();
    if let Some(cp) = g.clip_path() {
        ctx.clips
            .push(Arc::new(clip_of(cp, g.abs_transform(), frame)?));
    }
    if let Some(m) = g.mask() {
        ctx.clips
            .push(Arc::new(mask_of(m, g.abs_transform(), frame)?));
    }
    Ok(Rc::new(ctx))
}

/// A `<clipPath>` in output coordinates; `base` maps the clipped element's user space.
fn clip_of(cp: &usvg::ClipPath, base: usvg::Transform, frame: &Frame) -> Result<Clip> {
    let space = base.pre_concat(cp.transform());
    let mut parts = Vec::new();
    clip_parts(cp.root(), space, &[], frame, &mut parts, &mut |p| {
        p.fill().map(|f| f.rule())
    })?;
    let within = match cp.clip_path() {
        Some(inner) => vec![Arc::new(clip_of(inner, base, frame)?)],
        None => Vec::new(),
    };
    Ok(Clip {
        name: format!("clip-{}", cp.id()),
        mask: false,
        parts,
        within,
    })
}

/// A `<mask>` approximated as a clip: the fills of its content that are not
/// fully transparent (black is transparent in a luminance mask), within the
/// mask's rectangle.
fn mask_of(m: &usvg::Mask, base: usvg::Transform, frame: &Frame) -> Result<Clip> {
    let luminance = m.kind() == usvg::MaskType::Luminance;
    let mut parts = Vec::new();
    clip_parts(m.root(), base, &[], frame, &mut parts, &mut |p| {
        let f = p.fill()?;
        let alpha = f.opacity().get() * paint::server_alpha(f.paint());
        let dark = match f.paint() {
            usvg::Paint::Color(c) => luminance && c.red == 0 && c.green == 0 && c.blue == 0,
            _ => false,
        };
        (p.is_visible() && alpha > 0.0 && !dark).then(|| f.rule())
    })?;
    let r = m.rect();
    let rect = usvg::tiny_skia_path::PathBuilder::from_rect(r.to_rect());
    let mut within = vec![Arc::new(Clip {
        name: format!("mask-{}", m.id()),
        mask: true,
        parts: vec![ClipPart {
            rule: FillRule::NonZero,
            subpaths: outline_of(&rect, base, frame),
            clips: Vec::new(),
        }],
        within: Vec::new(),
    })];
    if let Some(inner) = m.mask() {
        within.push(Arc::new(mask_of(inner, base, frame)?));
    }
    Ok(Clip {
        name: format!("mask-{}", m.id()),
        mask: true,
        parts,
        within,
    })
}

/// The paths under `g` (a clip path's or mask's content) as clip parts; `rule`
/// says whether a path counts and by which rule.
fn clip_parts(
    g: &usvg::Group,
    space: usvg::Transform,
    clips: &[Arc<Clip>],
    frame: &Frame,
    out: &mut Vec<ClipPart>,
    rule: &mut dyn FnMut(&usvg::Path) -> Option<usvg::FillRule>,
) -> Result<()> {
    for node in g.children() {
        match node {
            usvg::Node::Group(c) => {
                let mut inner = clips.to_vec();
                if let Some(cp) = c.clip_path() {
                    inner.push(Arc::new(clip_of(
                        cp,
                        space.pre_concat(c.abs_transform()),
                        frame,
                    )?));
                }
                clip_parts(c, space, &inner, frame, out, rule)?;
            }
            usvg::Node::Path(p) => {
                if let Some(r) = rule(p) {
                    out.push(ClipPart {
                        rule: match r {
                            usvg::FillRule::EvenOdd => FillRule::EvenOdd,
                            usvg::FillRule::NonZero => FillRule::NonZero,
                        },
                        subpaths: outline_of(p.data(), space.pre_concat(p.abs_transform()), frame),
                        clips: clips.to_vec(),
                    });
                }
            }
            usvg::Node::Text(t) => clip_parts(t.flattened(), space, clips, frame, out, rule)?,
            usvg::Node::Image(_) => {}
        }
    }
    Ok(())
}

/// What one usvg path paints: its fill and stroke as items in paint order,
/// unless invisible (hidden, zero opacity) or decoration (below `--min-opacity`);
/// what became of the fill and of the stroke.
#[allow(
    clippy::too_many_arguments,
    reason = "one path's paint: the path, its shape, context, frame, options, servers and outputs"
)]
fn paint_items(
    p: &usvg::Path,
    shape: Shape,
    ctx: &Ctx,
    frame: &Frame,
    opts: &PaintOptions,
    servers: &[Option<String>; 2],
    items: &mut Vec<Item>,
    counts: &mut PaintCounts,
) -> Result<[Fate; 2]> {
    let visible = p.is_visible();
    let fate = |alpha: f32| {
        if !visible || alpha <= 0.0 {
            Fate::Invisible
        } else if alpha < opts.min_opacity {
            Fate::Decoration
        } else {
            Fate::Painted
        }
    };
    let fill_alpha = p
        .fill()
        .map(|f| ctx.opacity * f.opacity().get() * paint::server_alpha(f.paint()));
    let stroke_alpha = p
        .stroke()
        .map(|s| ctx.opacity * s.opacity().get() * paint::server_alpha(s.paint()));
    let fill_fate = fill_alpha.map_or(Fate::None, fate);
    let stroke_fate = stroke_alpha.map_or(Fate::None, fate);
    let base_paint = ShapePaint {
        filtered: ctx.filtered,
        clips: ctx.clips.clone(),
        stretched_by: shape.paint.stretched_by.clone(),
        ..ShapePaint::default()
    };
    let centre = |shape: &Shape| Shape {
        filled: false,
        paint: base_paint.clone(),
        ..shape.clone()
    };
    let count_painted = |counts: &mut PaintCounts| {
        if !ctx.clips.is_empty() {
            counts.clipped_shapes += 1;
            if ctx.clips.iter().any(|c| c.mask) {
                counts.masked_shapes += 1;
            }
        }
        if ctx.filtered {
            counts.filtered_shapes += 1;
        }
    };

    let mut fill_item = None;
    match fill_fate {
        Fate::None | Fate::Ignored => {}
        Fate::Invisible => counts.dropped_invisible += 1,
        Fate::Decoration => {
            counts.dropped_decoration += 1;
            fill_item = Some(Item::Decoration(
                shape.name(),
                fill_alpha.unwrap_or(0.0),
                opts.keep_decoration.then(|| centre(&shape)),
            ));
        }
        Fate::Painted => {
            count_painted(counts);
            let f = p.fill().expect("internal: a painted fill exists");
            fill_item = Some(Item::Shape(Shape {
                filled: true,
                paint: ShapePaint {
                    alpha: fill_alpha.unwrap_or(1.0),
                    server: servers[0].clone().or_else(|| paint::server_id(f.paint())),
                    average_colour: paint::average_colour(f.paint()),
                    ..base_paint.clone()
                },
                ..shape.clone()
            }));
        }
    }
    let fill_is_region = fill_fate == Fate::Painted;
    let stroke_result = match (stroke_fate, opts.strokes) {
        (Fate::None, _) => Fate::None,
        (_, StrokeMode::Ignore) => Fate::Ignored,
        (f, _) => f,
    };
    let mut stroke_item = None;
    match (stroke_fate, opts.strokes) {
        (Fate::None | Fate::Ignored, _) => {}
        (_, StrokeMode::Ignore) => counts.strokes_ignored += 1,
        (Fate::Invisible, _) => {
            counts.strokes_ignored += 1;
            counts.dropped_invisible += 1;
        }
        (Fate::Decoration, _) => {
            counts.dropped_decoration += 1;
            let outline_kept = matches!(fill_item, Some(Item::Decoration(_, _, Some(_))));
            stroke_item = Some(Item::Decoration(
                format!("{}-stroke", shape.name()),
                stroke_alpha.unwrap_or(0.0),
                (opts.keep_decoration && !outline_kept && !fill_is_region).then(|| centre(&shape)),
            ));
        }
        (Fate::Painted, StrokeMode::Line) => {
            counts.strokes_as_lines += 1;
            if !fill_is_region {
                stroke_item = Some(Item::Shape(centre(&shape)));
            }
        }
        (Fate::Painted, StrokeMode::Area) => {
            let s = p.stroke().expect("internal: a painted stroke exists");
            let [sx, ky, kx, sy, tx, ty] = frame.map(p.abs_transform());
            let to_output = Affine::new([sx, -ky, kx, -sy, tx, -ty]);
            let width = f64::from(s.width().get()) * to_output.determinant().abs().sqrt();
            let centre_shape = (!fill_is_region).then(|| centre(&shape));
            let colour = match s.paint() {
                usvg::Paint::Color(c) => Some([c.red, c.green, c.blue]),
                _ => None,
            };
            let server = servers[1].clone().or_else(|| paint::server_id(s.paint()));
            let alpha = stroke_alpha.unwrap_or(1.0);
            // the fill's own paint, opaque on both: the stroke changes nothing
            // where it overlaps the fill, and beyond it paints what the fill does
            let joins_fill = match (&fill_item, p.fill()) {
                (Some(Item::Shape(fill)), Some(f)) if fill_is_region => {
                    let same = match (f.paint(), s.paint()) {
                        (usvg::Paint::Color(a), usvg::Paint::Color(b)) => a == b,
                        _ => fill.paint.server.is_some() && fill.paint.server == server,
                    };
                    same && opaque(fill.paint.alpha) && opaque(alpha)
                }
                _ => false,
            };
            let area = Shape {
                filled: true,
                stroked: false,
                fill_rule: FillRule::NonZero,
                fill_colour: colour,
                paint: ShapePaint {
                    kind: ShapeKind::Stroke,
                    stroke_width: Some(width),
                    alpha,
                    server,
                    average_colour: paint::average_colour(s.paint()),
                    joins_fill,
                    ..base_paint.clone()
                },
                ..shape.clone()
            };
            stroke_item = Some(Item::Stroke(Box::new(PendingStroke {
                area,
                stroke: s.clone(),
                to_output,
                centre: centre_shape,
                width,
            })));
        }
    }
    let stroke_first = p.paint_order() == usvg::PaintOrder::StrokeAndFill;
    let (first, second) = if stroke_first {
        (stroke_item, fill_item)
    } else {
        (fill_item, stroke_item)
    };
    items.extend(first);
    items.extend(second);
    Ok([fill_fate, stroke_result])
}

/// Whether an effective opacity is opaque as a region name writes it (alpha
/// rounds to 255, as `fill-#rrggbb`).
fn opaque(alpha: f32) -> bool {
    alpha.clamp(0.0, 1.0) * 255.0 >= 254.5
}

/// Items → shapes in paint order: a stroke narrower than the hairline width
/// (see [`PaintOptions::min_stroke_width`]) or than the feature envelope
/// ([`PaintOptions::mu`]) becomes its centre lines; a wider one its area, to
/// [`PaintOptions::stroke_accuracy`].
///
/// Strokes kept as lines for being narrower than μ are named in a warning.
///
/// # Errors
/// [`Error::BadCoordinate`] when a stroke's area reaches beyond
/// [`super::Drawing::MAX_COORD`].
fn resolve_items(
    items: Vec<Item>,
    opts: &PaintOptions,
    counts: &mut PaintCounts,
    warnings: &mut Vec<String>,
) -> Result<Vec<Shape>> {
    let mut bbox: Option<kurbo::Rect> = None;
    let mut add = |s: &Shape| {
        for sp in &s.subpaths {
            let pts = std::iter::once(sp.start)
                .chain(sp.segments.iter().flat_map(Segment::control_points));
            for p in pts {
                bbox = Some(bbox.map_or(kurbo::Rect::from_points(p, p), |b| b.union_pt(p)));
            }
        }
    };
    for item in &items {
        match item {
            Item::Shape(s) | Item::Decoration(_, _, Some(s)) => add(s),
            Item::Stroke(p) => add(&p.area),
            Item::Decoration(_, _, None) => {}
        }
    }
    let d = bbox.map_or(0.0, |b| b.width().hypot(b.height()));
    let absolute = |value: f64, relative: bool| if relative { value * d } else { value };
    let hairline = absolute(opts.min_stroke_width, opts.min_stroke_relative);
    let mu = absolute(opts.mu, opts.mu_relative);
    let accuracy = opts.stroke_accuracy * d;
    let mut shapes = Vec::with_capacity(items.len());
    let mut below_mu: Vec<String> = Vec::new();
    let mut narrowest = f64::INFINITY;
    let mut closed: Vec<String> = Vec::new();
    let mut decoration: Vec<(String, f32)> = Vec::new();
    for item in items {
        let shape = match item {
            Item::Shape(s) => Some(s),
            Item::Decoration(name, alpha, outline) => {
                decoration.push((name, alpha));
                outline
            }
            Item::Stroke(p) => {
                let PendingStroke {
                    mut area,
                    stroke,
                    to_output,
                    centre,
                    width,
                } = *p;
                let expanded = (width >= hairline && width >= mu)
                    .then(|| paint::stroke_area(&area.subpaths, &stroke, to_output, accuracy, mu))
                    .flatten();
                match expanded {
                    Some(expanded) => {
                        counts.strokes_as_areas += 1;
                        counts.exact_stroke_subpaths += expanded.exact;
                        if expanded.dashes_closed {
                            counts.dashes_closed += 1;
                            closed.push(area.name());
                        }
                        if area.paint.joins_fill {
                            counts.strokes_joined += 1;
                        }
                        area.subpaths = expanded.subpaths;
                        check_coordinates(&area)?;
                        Some(area)
                    }
                    None => {
                        counts.strokes_as_lines += 1;
                        if width >= hairline && width < mu {
                            counts.strokes_below_mu += 1;
                            below_mu.push(area.name());
                            narrowest = narrowest.min(width);
                        }
                        centre
                    }
                }
            }
        };
        if let Some(mut s) = shape {
            s.paint_order = u32::try_from(shapes.len()).unwrap_or(u32::MAX);
            shapes.push(s);
        }
    }
    if !decoration.is_empty() {
        let lowest = decoration.iter().map(|d| d.1).fold(f32::INFINITY, f32::min);
        let highest = decoration.iter().map(|d| d.1).fold(0.0, f32::max);
        let opacity = if highest - lowest < 0.005 {
            format!("{lowest:.2}")
        } else {
            format!("{lowest:.2} to {highest:.2}")
        };
        let names: Vec<String> = decoration
            .iter()
            .map(|(name, alpha)| format!("{name} ({alpha:.2})"))
            .collect();
        let keep = if opts.keep_decoration {
            "their outlines kept"
        } else {
            "--keep-decoration keeps their outlines"
        };
        warnings.push(format!(
            "{} paint(s) (fills or strokes) below --min-opacity {} dropped as decoration, \
             with no region (effective opacity {opacity}: the groups' opacities times the \
             paint's; --min-opacity {} meshes them, {keep}): {}",
            decoration.len(),
            opts.min_opacity,
            one_digit_below(f64::from(lowest)),
            listed(&names)
        ));
    }
    if !closed.is_empty() {
        warnings.push(format!(
            "{} dashed stroke(s) stroked whole: every gap of the dash pattern is shorter than \
             the feature envelope μ = {mu:.3e}, so the dashes would not be kept apart: {}",
            closed.len(),
            listed(&closed)
        ));
    }
    if !below_mu.is_empty() {
        warnings.push(format!(
            "{} stroke(s) narrower than the feature envelope μ = {mu:.3e} kept as centre \
             lines, with no area of their own (their two outlines would be closer than μ; \
             --mu-abs {:.3e}, half the narrowest width, meshes them as areas): {}",
            below_mu.len(),
            0.5 * narrowest,
            listed(&below_mu)
        ));
    }
    Ok(shapes)
}

/// The first few of `names`, comma-separated, with ", ..." when more follow.
fn listed(names: &[String]) -> String {
    const LISTED: usize = 5;
    let more = if names.len() > LISTED { ", ..." } else { "" };
    format!("{}{more}", names[..names.len().min(LISTED)].join(", "))
}

/// The outlines of the clips that limit a region, as feature geometry (one
/// [`ShapeKind::ClipOutline`] shape per clip, after the painted shapes): the
/// pieces whose bounding box meets a clipped shape's.
fn add_clip_outlines(shapes: &mut Vec<Shape>, paths: usize) {
    let mut seen: Vec<(*const Clip, kurbo::Rect)> = Vec::new();
    fn bbox_of(subpaths: &[Subpath]) -> Option<kurbo::Rect> {
        let mut b: Option<kurbo::Rect> = None;
        for sp in subpaths {
            for p in std::iter::once(sp.start)
                .chain(sp.segments.iter().flat_map(Segment::control_points))
            {
                b = Some(b.map_or(kurbo::Rect::from_points(p, p), |r| r.union_pt(p)));
            }
        }
        b
    }
    fn visit(c: &Arc<Clip>, bb: kurbo::Rect, seen: &mut Vec<(*const Clip, kurbo::Rect)>) {
        let ptr = Arc::as_ptr(c);
        match seen.iter_mut().find(|e| e.0 == ptr) {
            Some(e) => e.1 = e.1.union(bb),
            None => seen.push((ptr, bb)),
        }
        for inner in c
            .within
            .iter()
            .chain(c.parts.iter().flat_map(|p| p.clips.iter()))
        {
            visit(inner, bb, seen);
        }
    }
    let mut all: Vec<Arc<Clip>> = Vec::new();
    for s in shapes.iter().filter(|s| s.filled) {
        let Some(bb) = bbox_of(&s.subpaths) else {
            continue;
        };
        for c in &s.paint.clips {
            visit(c, bb, &mut seen);
            super::drawing::collect_clips(c, &mut all);
        }
    }
    let mut index = paths;
    for (ptr, bb) in seen {
        let Some(clip) = all.iter().find(|c| Arc::as_ptr(c) == ptr) else {
            continue;
        };
        let subpaths: Vec<Subpath> = clip
            .parts
            .iter()
            .flat_map(|p| p.subpaths.iter())
            .filter(|sp| bbox_of(std::slice::from_ref(sp)).is_some_and(|b| b.overlaps(bb)))
            .cloned()
            .collect();
        if subpaths.is_empty() {
            continue;
        }
        shapes.push(Shape {
            svg_id: Some(clip.name.clone()),
            element_index: u32::try_from(index).unwrap_or(u32::MAX),
            paint_order: u32::try_from(shapes.len()).unwrap_or(u32::MAX),
            filled: false,
            stroked: false,
            fill_rule: FillRule::NonZero,
            fill_colour: None,
            subpaths,
            paint: ShapePaint {
                kind: ShapeKind::ClipOutline,
                outlined_clip: Some(clip.clone()),
                ..ShapePaint::default()
            },
        });
        index += 1;
    }
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
    let subpaths = outline_of(path.data(), path.abs_transform(), frame);
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
        paint: ShapePaint::default(),
    };
    check_coordinates(&shape)?;
    Ok(shape)
}

/// usvg path data under `transform` (then the output frame), in output coordinates.
fn outline_of(
    data: &usvg::tiny_skia_path::Path,
    transform: usvg::Transform,
    frame: &Frame,
) -> Vec<Subpath> {
    let [sx, ky, kx, sy, tx, ty] = frame.map(transform);
    let map = |p: usvg::tiny_skia_path::Point| {
        let (x, y) = (f64::from(p.x), f64::from(p.y));
        Point::new(sx * x + kx * y + tx, -(ky * x + sy * y + ty))
    };
    subpaths(data.segments().map(|seg| match seg {
        PathSegment::MoveTo(p) => Verb::Move(map(p)),
        PathSegment::LineTo(p) => Verb::Line(map(p)),
        PathSegment::QuadTo(p1, p2) => Verb::Quad(map(p1), map(p2)),
        PathSegment::CubicTo(p1, p2, p3) => Verb::Cubic(map(p1), map(p2), map(p3)),
        PathSegment::Close => Verb::Close,
    }))
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

/// `x` (positive, finite) rounded down to one significant digit, as a flag's
/// value is written (`0.008`, `3e-9`): a threshold at it lets `x` through.
pub(crate) fn one_digit_below(x: f64) -> String {
    let exp = x.log10().floor();
    let unit = 10f64.powf(exp);
    let digit = (x / unit).floor().clamp(1.0, 9.0);
    let v = digit * unit;
    if (1e-4..1e6).contains(&v) {
        let decimals = usize::try_from(-(exp as i64)).unwrap_or(0);
        format!("{v:.decimals$}")
    } else {
        format!("{digit}e{exp}")
    }
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
