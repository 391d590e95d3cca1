//! The source document behind usvg's tree: which element each usvg path came
//! from, and the f64 transform from that element's coordinates to the root's
//! user units, read from the document's own text.
//!
//! usvg keeps element ids on paths and on the groups of `<g>` and `<use>`, but
//! nothing else that ties a path to its element. So before usvg parses, every
//! shape element and every `<use>` without an `id` gets a private one
//! ([`with_private_ids`]); [`Source`] maps ids back to elements and hides the
//! private ones from everything a user sees. usvg drops all ids inside a
//! `<use>` instance (it would duplicate them), so the paths of an instance are
//! matched in document order against the instance's expansion
//! ([`Source::expand_uses`]); every match is validated against usvg's own
//! geometry by the caller, which makes a wrong match harmless.
//!
//! Transforms follow SVG: each element's `transform` (and `transform-origin`),
//! `<use>` `x`/`y` and `transform`, nested `<svg>` positions and `viewBox`
//! mappings, the `viewBox` of a `<symbol>` sized by its `<use>`. Lengths in
//! absolute units (px, in, cm, mm, pt, pc) convert exactly; anything that needs
//! context (%, em, ex), CSS-set transforms and a `transform` on the root `<svg>`
//! are [`Unsupported`]: the caller keeps usvg's single-precision geometry.

use kurbo::Affine;
use std::cell::Cell;
use std::collections::{HashMap, HashSet};
use std::str::FromStr;
use usvg::roxmltree::{Document, Node};

/// Why a path keeps usvg's single-precision geometry (a short, fixed phrase:
/// warnings count paths per reason).
pub(super) type Unsupported = &'static str;

/// The SVG namespace.
const SVG_NS: &str = "http://www.w3.org/2000/svg";

/// Elements usvg turns into one path each.
pub(super) const SHAPES: &[&str] = &[
    "path", "rect", "circle", "ellipse", "line", "polyline", "polygon",
];

/// Containers whose content is never rendered in place (only through a
/// reference: `<use>`, paint servers, clip paths, markers, ...).
const NOT_RENDERED: &[&str] = &[
    "defs",
    "clipPath",
    "mask",
    "pattern",
    "marker",
    "symbol",
    "text",
    "style",
    "title",
    "desc",
    "metadata",
    "linearGradient",
    "radialGradient",
    "filter",
    "image",
    "foreignObject",
];

/// At most this many shape instances are expanded from `<use>` elements per
/// document (beyond it, instance paths keep usvg's geometry).
const MAX_EXPANDED: usize = 200_000;

/// At most this many `<use>` levels are followed.
const MAX_USE_DEPTH: usize = 64;

/// The smallest scale factor usvg keeps: an element whose own `transform`,
/// rounded to f32, maps a unit vector to a length at most this (f32's epsilon)
/// is not rendered by usvg, with its content.
const USVG_MIN_SCALE: f32 = f32::EPSILON;

/// Whether usvg drops an element for its `transform` (`value` parsed as usvg
/// parses it, rounded to f32, a row scale factor at most [`USVG_MIN_SCALE`]),
/// although the transform is invertible in f64 and the element is drawn.
fn tiny_for_usvg(value: &str) -> bool {
    let Ok(t) = svgtypes::Transform::from_str(value) else {
        return false;
    };
    let f64_invertible = [t.a, t.b, t.c, t.d, t.e, t.f].iter().all(|v| v.is_finite())
        && (t.a * t.d - t.b * t.c).abs() >= f64::MIN_POSITIVE;
    #[allow(
        clippy::cast_possible_truncation,
        reason = "usvg's own rounding of the transform to f32"
    )]
    let [a, b, c, d] = [t.a, t.b, t.c, t.d].map(|v| v as f32);
    let (x_scale, y_scale) = ((a * a + c * c).sqrt(), (b * b + d * d).sqrt());
    f64_invertible && (x_scale <= USVG_MIN_SCALE || y_scale <= USVG_MIN_SCALE)
}

/// The document's text as usvg is given it, and the prefix of the private
/// names in it (chosen so that no id of the document starts with it).
///
/// - Every shape element and `<use>` without an `id` gets a private one.
/// - A `<g>` or shape element drawn in place (not inside `<defs>`, a clip path,
///   a mask, a marker, a pattern, a symbol or text, nor within an element a
///   `<use>` refers to; when it is a shape, without a clip path, mask or
///   markers of its own) whose `transform` has a scale factor below f32's precision,
///   which usvg would drop with all its content, has that attribute renamed to
///   `{prefix}transform` (and gets a private id if it has none): usvg then
///   draws the content in the element's own coordinates, well conditioned,
///   and [`Source`] reads the true transform in f64 from the renamed
///   attribute. `outline.rs` composes the same transform onto usvg's geometry
///   below the element ([`Source::usvg_omits`]), so its single-precision
///   geometry (clips, strokes, glyphs, the check of the f64 reconstruction)
///   is in the true coordinates too.
///
/// `None` when nothing needs a change, or when a style sheet selects on `[id…]`
/// (the ids could change its matches); no transform is renamed when a style
/// sheet selects on `[transform…]` or sets transforms.
pub(super) fn with_private_ids(text: &str, doc: &Document<'_>) -> Option<(String, String)> {
    let ids: Vec<&str> = doc
        .descendants()
        .filter_map(|n| n.attribute("id"))
        .collect();
    let style_sheet = |needle: &dyn Fn(&str) -> bool| {
        doc.descendants()
            .filter(|n| n.tag_name().name() == "style")
            .any(|n| n.text().is_some_and(needle))
    };
    if style_sheet(&|t| t.contains("[id")) {
        return None;
    }
    let may_rename = !style_sheet(&|t| t.contains("[transform") || declares_transform(t));
    let prefix = (0u32..).map(|k| format!("triwild{k}-")).find(|p| {
        !ids.iter().any(|id| id.starts_with(p.as_str()))
            && !doc
                .descendants()
                .any(|n| n.attributes().any(|a| a.name().starts_with(p.as_str())))
    })?;
    let referenced = if may_rename {
        use_targets(doc)
    } else {
        HashSet::new()
    };
    let body_start = doc.root_element().range().start;
    let bytes = text.as_bytes();
    // (position, replaced length, new text)
    let mut edits: Vec<(usize, usize, String)> = Vec::new();
    let mut seen = HashSet::new();
    let mut private = 0usize;
    for node in doc.descendants().filter(Node::is_element) {
        let name = node.tag_name();
        if !matches!(name.namespace(), None | Some(SVG_NS))
            || node.ancestors().any(|a| a.tag_name().name() == "text")
        {
            continue;
        }
        let shape = SHAPES.contains(&name.name());
        // the cheap test first: the rest reads ancestors and every id
        let rename = may_rename
            && (shape || name.name() == "g")
            && node
                .attributes()
                .find(|a| a.name() == "transform" && a.namespace().is_none())
                .is_some_and(|a| tiny_for_usvg(a.value()))
            && drawn_in_place(node, &referenced)
            && !(shape && ["clip-path", "mask"].iter().any(|p| has_property(node, p)))
            && !(shape
                && node.ancestors().any(|a| {
                    ["marker", "marker-start", "marker-mid", "marker-end"]
                        .iter()
                        .any(|p| has_property(a, p))
                }))
            && !node.attribute("style").is_some_and(declares_transform)
            && node
                .attribute("id")
                .is_none_or(|id| ids.iter().filter(|i| **i == id).count() == 1);
        let wants_id = (shape || name.name() == "use" || rename) && node.attribute("id").is_none();
        if !wants_id && !rename {
            continue;
        }
        // The start tag in the text: `<` then the (possibly prefixed) name. An
        // element from an entity expansion may point elsewhere: skipped.
        let start = node.range().start;
        if start < body_start || bytes.get(start) != Some(&b'<') {
            continue;
        }
        let name_len = bytes[start + 1..]
            .iter()
            .position(|b| b.is_ascii_whitespace() || *b == b'/' || *b == b'>')
            .unwrap_or(bytes.len() - start - 1);
        let end = start + 1 + name_len;
        let qname = &text[start + 1..end];
        let local = qname.rsplit(':').next().unwrap_or(qname);
        if local != name.name() || !seen.insert(end) {
            continue;
        }
        if rename {
            let attr = node
                .attributes()
                .find(|a| a.name() == "transform" && a.namespace().is_none())
                .expect("internal: the transform attribute exists");
            let at = attr.range_qname();
            if text.get(at.clone()) != Some("transform") {
                continue;
            }
            edits.push((at.start, at.len(), format!("{prefix}transform")));
        }
        if wants_id {
            edits.push((end, 0, format!(" id=\"{prefix}{private}\"")));
            private += 1;
        }
    }
    if edits.is_empty() {
        return None;
    }
    edits.sort_unstable_by_key(|e| e.0);
    let mut out = String::with_capacity(text.len() + edits.len() * (prefix.len() + 12));
    let mut last = 0;
    for (at, len, new) in edits {
        out.push_str(&text[last..at]);
        out.push_str(&new);
        last = at + len;
    }
    out.push_str(&text[last..]);
    Some((out, prefix))
}

/// The elements some `<use>` refers to (by `href` or `xlink:href`).
fn use_targets<'a, 'input>(doc: &'a Document<'input>) -> HashSet<Node<'a, 'input>> {
    let by_id: HashMap<&str, Node<'a, 'input>> = doc
        .descendants()
        .filter_map(|n| Some((n.attribute("id")?, n)))
        .rev()
        .collect();
    doc.descendants()
        .filter(|n| n.tag_name().name() == "use")
        .flat_map(|u| u.attributes().filter(|a| a.name() == "href"))
        .filter_map(|a| svgtypes::IRI::from_str(a.value()).ok())
        .filter_map(|iri| by_id.get(iri.0).copied())
        .collect()
}

/// Whether `node` is drawn in its place only: no ancestor (or itself) is a
/// container whose content is drawn by reference, or the target of a `<use>`.
fn drawn_in_place(node: Node<'_, '_>, referenced: &HashSet<Node<'_, '_>>) -> bool {
    node.ancestors().filter(Node::is_element).all(|a| {
        !referenced.contains(&a)
            && (a == node || !NOT_RENDERED.contains(&a.tag_name().name()))
            && !matches!(a.tag_name().name(), "symbol" | "switch")
    })
}

/// The value `node` itself gives `property`: the last declaration in its
/// `style`, else its attribute.
fn property_value<'a>(node: Node<'a, '_>, property: &str) -> Option<&'a str> {
    let in_style = node.attribute("style").and_then(|style| {
        style.split(';').rev().find_map(|d| {
            let (k, v) = d.split_once(':')?;
            (k.trim() == property).then(|| v.trim())
        })
    });
    in_style.or_else(|| node.attribute(property).map(str::trim))
}

/// Whether `node` sets `property` (as an attribute or in its `style`).
fn has_property(node: Node<'_, '_>, property: &str) -> bool {
    node.has_attribute(property)
        || node.attribute("style").is_some_and(|s| {
            s.split(';')
                .any(|d| d.split_once(':').is_some_and(|(k, _)| k.trim() == property))
        })
}

/// A shape element as one instance: the element and the `<use>` elements it is
/// instantiated through, outermost first (empty when it is drawn in place).
#[derive(Clone, Debug)]
pub(super) struct Candidate<'a, 'input> {
    /// The shape element.
    pub(super) node: Node<'a, 'input>,
    /// The `<use>` chain, outermost first.
    pub(super) uses: Vec<Node<'a, 'input>>,
}

/// The source document, its ids and its transforms.
pub(super) struct Source<'a, 'input> {
    doc: &'a Document<'input>,
    /// The prefix of private ids, if any were added.
    private_prefix: Option<String>,
    /// Every id → its elements, in document order (duplicates kept; a reference
    /// resolves to the first, as in usvg).
    by_id: HashMap<&'a str, Vec<Node<'a, 'input>>>,
    /// A style sheet declares `transform` (CSS transforms are presentation
    /// properties that usvg applies): transforms are then not read at all.
    css_transform: bool,
    /// A style sheet mentions `marker` (it may set marker properties this
    /// reader does not resolve).
    css_marker: bool,
    /// Shape instances expanded so far (bounded by [`MAX_EXPANDED`]).
    expanded: Cell<usize>,
}

impl<'a, 'input> Source<'a, 'input> {
    /// The model of `doc`, whose private ids (if any) start with `private_prefix`.
    pub(super) fn new(doc: &'a Document<'input>, private_prefix: Option<String>) -> Self {
        let mut by_id: HashMap<&'a str, Vec<Node<'a, 'input>>> = HashMap::new();
        let mut css_transform = false;
        let mut css_marker = false;
        for node in doc.descendants().filter(Node::is_element) {
            if let Some(id) = node.attribute("id") {
                by_id.entry(id).or_default().push(node);
            }
            if node.tag_name().name() == "style" {
                css_transform |= node.text().is_some_and(declares_transform);
                css_marker |= node.text().is_some_and(|t| t.contains("marker"));
            }
        }
        Self {
            doc,
            private_prefix,
            by_id,
            css_transform,
            css_marker,
            expanded: Cell::new(0),
        }
    }

    /// Whether `id` is one of ours.
    pub(super) fn is_private(&self, id: &str) -> bool {
        self.private_prefix
            .as_deref()
            .is_some_and(|p| id.starts_with(p))
    }

    /// `id` as a user may see it: `None` for an empty or private id.
    pub(super) fn public<'s>(&self, id: &'s str) -> Option<&'s str> {
        (!id.is_empty() && !self.is_private(id)).then_some(id)
    }

    /// The shape elements with this id, in document order (several if the
    /// document repeats an id).
    pub(super) fn shapes_with_id(&self, id: &str) -> Vec<Node<'a, 'input>> {
        self.elements_with_id(id, |n| SHAPES.contains(&n))
    }

    /// The `<use>` elements with this id.
    pub(super) fn uses_with_id(&self, id: &str) -> Vec<Node<'a, 'input>> {
        self.elements_with_id(id, |n| n == "use")
    }

    fn elements_with_id(&self, id: &str, tag: impl Fn(&str) -> bool) -> Vec<Node<'a, 'input>> {
        if id.is_empty() {
            return Vec::new();
        }
        self.by_id.get(id).map_or_else(Vec::new, |nodes| {
            nodes
                .iter()
                .copied()
                .filter(|n| is_svg(*n) && tag(n.tag_name().name()))
                .collect()
        })
    }

    /// Whether a style sheet mentions `marker` (it may set marker properties).
    #[cfg(test)]
    pub(super) fn style_sheet_mentions_markers(&self) -> bool {
        self.css_marker
    }

    /// Whether usvg may draw markers on `element`: its `marker-start`,
    /// `marker-mid` or `marker-end` (set on it or inherited; as an attribute, in
    /// its `style`, or through the `marker` shorthand there) names a `<marker>`
    /// of the document, as usvg resolves them; also `true` when a style sheet
    /// mentions markers (this reader does not apply style sheets), and never
    /// inside a `<clipPath>` (usvg draws no markers there). `marker: none`
    /// names none.
    pub(super) fn may_have_markers(&self, element: Node<'a, 'input>) -> bool {
        if element
            .ancestors()
            .any(|a| a.tag_name().name() == "clipPath")
        {
            return false;
        }
        if self.css_marker {
            return true;
        }
        ["marker-start", "marker-mid", "marker-end"]
            .iter()
            .any(|property| {
                let value = element
                    .ancestors()
                    .filter(Node::is_element)
                    .find_map(|n| marker_property(n, property));
                value.is_some_and(|v| {
                    // `none` or anything but a link names no marker
                    svgtypes::FuncIRI::from_str(v).is_ok_and(|link| {
                        self.by_id
                            .get(link.0)
                            .and_then(|nodes| nodes.first())
                            .is_some_and(|n| is_svg(*n) && n.tag_name().name() == "marker")
                    })
                })
            })
    }

    /// The element a `<use>` refers to, as usvg resolves it (unprefixed `href`
    /// first, then `xlink:href`; the first element with that id).
    fn target(&self, use_node: Node<'a, 'input>) -> Option<Node<'a, 'input>> {
        const XLINK_NS: &str = "http://www.w3.org/1999/xlink";
        let link = use_node
            .attributes()
            .find(|a| a.name() == "href" && a.namespace().is_none())
            .or_else(|| {
                use_node
                    .attributes()
                    .find(|a| a.name() == "href" && a.namespace() == Some(XLINK_NS))
            })?;
        let id = svgtypes::IRI::from_str(link.value()).ok()?.0;
        self.by_id
            .get(id)
            .and_then(|nodes| nodes.first().copied())
            .filter(|n| is_svg(*n))
    }

    /// Every shape instance drawn by these `<use>` elements, in document (paint)
    /// order, nested `<use>` elements expanded.
    pub(super) fn expand_uses(&self, uses: &[Node<'a, 'input>]) -> Vec<Candidate<'a, 'input>> {
        let mut out = Vec::new();
        for &u in uses {
            self.expand(u, &mut Vec::new(), &mut out);
        }
        out
    }

    fn expand(
        &self,
        use_node: Node<'a, 'input>,
        chain: &mut Vec<Node<'a, 'input>>,
        out: &mut Vec<Candidate<'a, 'input>>,
    ) {
        let Some(target) = self.target(use_node) else {
            return;
        };
        // usvg skips self references and references to an ancestor
        if chain.len() >= MAX_USE_DEPTH
            || chain.contains(&use_node)
            || use_node.ancestors().any(|a| a == target)
        {
            return;
        }
        chain.push(use_node);
        let mut stack = vec![target];
        while let Some(e) = stack.pop() {
            if self.expanded.get() >= MAX_EXPANDED {
                break;
            }
            if !e.is_element() || !is_svg(e) {
                continue;
            }
            let name = e.tag_name().name();
            if SHAPES.contains(&name) {
                self.expanded.set(self.expanded.get() + 1);
                out.push(Candidate {
                    node: e,
                    uses: chain.clone(),
                });
            } else if name == "use" {
                self.expand(e, chain, out);
            } else if e == target || !NOT_RENDERED.contains(&name) {
                stack.extend(e.children().rev());
            }
        }
        chain.pop();
    }

    /// The transform from `c.node`'s coordinates to the user units of the root
    /// `<svg>` (its own `viewBox` mapping not included), as the steps that make it,
    /// innermost first (the element's own transform, then its ancestors').
    ///
    /// # Errors
    /// The reason when the chain needs context this reader does not have, or when
    /// the candidate is not where usvg's tree says it is.
    pub(super) fn transform_steps(
        &self,
        c: &Candidate<'a, 'input>,
    ) -> Result<Vec<Affine>, Unsupported> {
        let mut steps = Vec::new();
        let mut current = c.node;
        for &u in c.uses.iter().rev() {
            let target = self.target(u).ok_or("a <use> without target")?;
            self.ascend(current, Some((target, u)), &mut steps)?;
            let x = length(u, "x", 0.0)?;
            let y = length(u, "y", 0.0)?;
            steps.push(self.own_transform(u)? * Affine::translate((x, y)));
            // its ancestors next (or the use itself, when an outer use refers to it)
            current = u;
        }
        self.ascend(current, None, &mut steps)?;
        Ok(steps)
    }

    /// The transforms of `from` and its ancestors, up to and including the target
    /// of `via` (a `(target, use)` pair), or up to the root `<svg>` (excluded),
    /// appended to `steps`. `from` may be a `<use>` whose own transform is applied
    /// already.
    fn ascend(
        &self,
        from: Node<'a, 'input>,
        via: Option<(Node<'a, 'input>, Node<'a, 'input>)>,
        steps: &mut Vec<Affine>,
    ) -> Result<(), Unsupported> {
        let unexpected = "an element where usvg's tree does not expect it";
        let mut node = Some(from);
        while let Some(e) = node {
            if !e.is_element() {
                break;
            }
            let is_target = via.is_some_and(|(t, _)| t == e);
            let use_node = via.filter(|_| is_target).map(|(_, u)| u);
            let name = e.tag_name().name();
            if e.parent_element().is_none() {
                return match (via, name) {
                    (None, "svg") => Ok(()),
                    (None, _) => Err("not inside the root <svg>"),
                    (Some(_), _) => Err("a <use> target outside its expected place"),
                };
            }
            let step = match name {
                "svg" => Some(self.nested_svg(e, use_node)?),
                "symbol" if is_target => Some(self.symbol(e, use_node)?),
                "g" | "a" | "switch" => Some(self.own_transform(e)?),
                n if SHAPES.contains(&n) && e == from => Some(self.own_transform(e)?),
                "use" if e == from => None,
                _ => return Err(unexpected),
            };
            steps.extend(step);
            if is_target {
                return Ok(());
            }
            node = e.parent_element();
        }
        Err(unexpected)
    }

    /// The text of an element's `transform`: the attribute usvg was kept from
    /// (see [`with_private_ids`]) if there is one, else `transform`.
    fn transform_attribute(&self, e: Node<'a, 'input>) -> Option<&'a str> {
        self.private_prefix
            .as_deref()
            .and_then(|p| {
                e.attributes().find(|a| {
                    a.namespace().is_none() && a.name().strip_prefix(p) == Some("transform")
                })
            })
            .map_or_else(|| e.attribute("transform"), |a| Some(a.value()))
    }

    /// The transform usvg did not apply to the `<g>` or shape element with
    /// this id (its own, about its `transform-origin`; see
    /// [`with_private_ids`]); `None` for every other element.
    pub(super) fn usvg_omits(&self, id: &str) -> Option<Affine> {
        let prefix = self.private_prefix.as_deref()?;
        let e = self
            .elements_with_id(id, |n| n == "g" || SHAPES.contains(&n))
            .into_iter()
            .next()?;
        e.attributes()
            .any(|a| a.namespace().is_none() && a.name().strip_prefix(prefix) == Some("transform"))
            .then(|| self.own_transform(e).ok())
            .flatten()
    }

    /// The transform on `element`'s chain (its own and its ancestors') that
    /// stretches most unevenly, as written and where (`skewX(89.9) on <g
    /// id='s'>`; a private id is not shown), when its largest stretch is more
    /// than [`ShapePaint::UNEVEN`](super::drawing::ShapePaint::UNEVEN) times its
    /// smallest.
    pub(super) fn most_uneven(&self, element: Node<'a, 'input>) -> Option<String> {
        let mut best: Option<(f64, Node<'a, 'input>, &str)> = None;
        for e in element.ancestors().filter(Node::is_element) {
            let Some(text) = self.transform_attribute(e) else {
                continue;
            };
            let Ok(t) = svgtypes::Transform::from_str(text) else {
                continue;
            };
            // singular values: s1·s2 = |det|, s1² + s2² = the squares' sum
            let det = (t.a * t.d - t.b * t.c).abs();
            let sum = t.a * t.a + t.b * t.b + t.c * t.c + t.d * t.d;
            let root = (sum * sum - 4.0 * det * det).max(0.0).sqrt();
            let (s1, s2) = (
                (0.5 * (sum + root)).sqrt(),
                det / (0.5 * (sum + root)).sqrt(),
            );
            let ratio = if s2 > 0.0 { s1 / s2 } else { f64::INFINITY };
            if ratio.is_finite()
                && ratio > super::drawing::ShapePaint::UNEVEN
                && best.is_none_or(|b| ratio > b.0)
            {
                best = Some((ratio, e, text));
            }
        }
        best.map(|(_, e, text)| {
            let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
            let mut shown: String = text.chars().take(40).collect();
            if text.chars().count() > 40 {
                shown.push('…');
            }
            let tag = e.tag_name().name();
            match e.attribute("id").and_then(|id| self.public(id)) {
                Some(id) => format!("{shown} on <{tag} id='{id}'>"),
                None => format!("{shown} on <{tag}>"),
            }
        })
    }

    /// The elements drawn in place that usvg drops for a transform with a
    /// scale factor below f32's precision and that [`with_private_ids`] did
    /// not hand over (a `<use>`, `<text>`, nested `<svg>`, a shape with a
    /// clip path, mask or markers, ...), as one warning; `None` for none.
    pub(super) fn dropped_for_tiny_transforms(&self) -> Option<String> {
        const NAMED: usize = 5;
        let empty = HashSet::new();
        let names: Vec<String> = self
            .doc
            .descendants()
            .filter(|n| {
                is_svg(*n)
                    && n.parent_element().is_some()
                    && n.attribute("transform").is_some_and(tiny_for_usvg)
                    && drawn_in_place(*n, &empty)
            })
            .map(|n| {
                let tag = n.tag_name().name();
                match n.attribute("id").and_then(|id| self.public(id)) {
                    Some(id) => format!("<{tag} id='{id}'>"),
                    None => format!("<{tag}>"),
                }
            })
            .collect();
        let more = if names.len() > NAMED { ", ..." } else { "" };
        (!names.is_empty()).then(|| {
            format!(
                "{} element(s) not drawn: a transform with a scale factor below {:.1e} (the SVG \
                 parser's single precision) drops the element with its content, and triwild \
                 carries such a transform itself only on a <g> or on a shape without clip \
                 path, mask or markers (wrap the element in a <g> with that transform): {}{more}",
                names.len(),
                f64::from(USVG_MIN_SCALE),
                names[..names.len().min(NAMED)].join(", ")
            )
        })
    }

    /// Why a drawing usvg found nothing in may be empty: when every shape
    /// element drawn in place lies under a `clip-path` or `mask` (its own or
    /// an ancestor's), the references, as one sentence; `None` otherwise.
    pub(super) fn all_under_references(&self) -> Option<String> {
        let empty = HashSet::new();
        let mut refs: Vec<String> = Vec::new();
        let mut shapes = 0usize;
        for node in self.doc.descendants().filter(|n| is_svg(*n)) {
            if !SHAPES.contains(&node.tag_name().name()) || !drawn_in_place(node, &empty) {
                continue;
            }
            shapes += 1;
            let mut found = false;
            for a in node.ancestors().filter(Node::is_element) {
                for (property, what) in [("clip-path", "clip path"), ("mask", "mask")] {
                    let Some(value) = property_value(a, property) else {
                        continue;
                    };
                    let Ok(link) = svgtypes::FuncIRI::from_str(value) else {
                        continue;
                    };
                    found = true;
                    let named = format!("{what} '{}'", link.0);
                    if !refs.contains(&named) {
                        refs.push(named);
                    }
                }
            }
            if !found {
                return None;
            }
        }
        (shapes > 0).then(|| {
            format!(
                "all {shapes} shape element(s) lie under {}, which leaves nothing painted \
                 (an empty or invalid clip path or mask hides what it applies to)",
                refs.join(", ")
            )
        })
    }

    /// An element's own `transform` (about its `transform-origin`).
    fn own_transform(&self, e: Node<'a, 'input>) -> Result<Affine, Unsupported> {
        if self.css_transform || e.attribute("style").is_some_and(declares_transform) {
            return Err("a transform set by CSS");
        }
        // usvg ignores a transform it cannot parse (an invalid one hides the element)
        let t = self
            .transform_attribute(e)
            .and_then(|s| svgtypes::Transform::from_str(s).ok())
            .map_or(Affine::IDENTITY, |t| {
                Affine::new([t.a, t.b, t.c, t.d, t.e, t.f])
            });
        match e.attribute("transform-origin") {
            None => Ok(t),
            Some(s) => {
                let origin =
                    svgtypes::TransformOrigin::from_str(s).map_err(|_| "a bad transform-origin")?;
                let dx = absolute(origin.x_offset)?;
                let dy = absolute(origin.y_offset)?;
                Ok(Affine::translate((dx, dy)) * t * Affine::translate((-dx, -dy)))
            }
        }
    }

    /// A nested `<svg>`: its transform, position and `viewBox` mapping (its size
    /// replaced by a referencing `<use>`'s width and height when given).
    fn nested_svg(
        &self,
        e: Node<'a, 'input>,
        use_node: Option<Node<'a, 'input>>,
    ) -> Result<Affine, Unsupported> {
        let x = length(e, "x", 0.0)?;
        let y = length(e, "y", 0.0)?;
        let mut m = self.own_transform(e)? * Affine::translate((x, y));
        if let Some(vb) = view_box(e) {
            let size = |attr: &str| {
                use_node
                    .filter(|u| u.has_attribute(attr))
                    .map_or_else(|| sized(e, attr), |u| sized(u, attr))
            };
            let (w, h) = (size("width")?, size("height")?);
            if let Some(vb_map) = view_box_mapping(vb, aspect(e), w, h) {
                m *= vb_map;
            }
        }
        Ok(m)
    }

    /// A `<symbol>` drawn by `use_node`: its `viewBox` mapped to the use's size
    /// (usvg ignores a symbol's own `transform`).
    fn symbol(
        &self,
        e: Node<'a, 'input>,
        use_node: Option<Node<'a, 'input>>,
    ) -> Result<Affine, Unsupported> {
        let Some(vb) = view_box(e) else {
            return Ok(Affine::IDENTITY);
        };
        let u = use_node.ok_or("a <symbol> outside a <use>")?;
        let (w, h) = (sized(u, "width")?, sized(u, "height")?);
        Ok(view_box_mapping(vb, aspect(e), w, h).unwrap_or(Affine::IDENTITY))
    }

    /// The root `viewBox` → viewport (CSS px) mapping, as usvg sizes the root.
    ///
    /// # Errors
    /// A `transform` on the root (usvg applies it about the viewport's centre), or a
    /// size that needs context.
    pub(super) fn root_px_mapping(&self) -> Result<Affine, Unsupported> {
        let root = self.doc.root_element();
        if self.root_transform() {
            return Err("a transform on the root <svg>");
        }
        let Some(vb) = view_box(root) else {
            return Ok(Affine::IDENTITY);
        };
        let side = |attr: &str, full: f64| -> Result<(f64, bool), Unsupported> {
            match root
                .attribute(attr)
                .and_then(|s| svgtypes::Length::from_str(s).ok())
            {
                None => Ok((full, false)),
                Some(l) if l.unit == svgtypes::LengthUnit::Percent => {
                    Ok((full * (l.number / 100.0), true))
                }
                Some(l) => Ok((absolute(l)?, true)),
            }
        };
        let (mut w, w_given) = side("width", vb.w)?;
        let (mut h, h_given) = side("height", vb.h)?;
        match (w_given, h_given) {
            (true, false) => h = vb.h * w / vb.w,
            (false, true) => w = vb.w * h / vb.h,
            _ => {}
        }
        view_box_mapping(vb, aspect(root), w, h).ok_or("a root size that is not positive")
    }

    /// Whether the root `<svg>` has a transform (its own, or one CSS may set).
    pub(super) fn root_transform(&self) -> bool {
        let root = self.doc.root_element();
        self.css_transform
            || root.has_attribute("transform")
            || root.attribute("style").is_some_and(declares_transform)
    }
}

/// The value `n` itself gives marker property `property` (`marker-start`,
/// `marker-mid` or `marker-end`), as usvg reads it: the last declaration in its
/// `style` (the `marker` shorthand sets all three), else its attribute;
/// `None` when `n` leaves it to inheritance (unset or `inherit`).
fn marker_property<'a>(n: Node<'a, '_>, property: &str) -> Option<&'a str> {
    let in_style = n.attribute("style").and_then(|style| {
        style.split(';').rev().find_map(|decl| {
            let (k, v) = decl.split_once(':')?;
            let k = k.trim();
            (k == property || k == "marker").then(|| v.trim().trim_end_matches("!important").trim())
        })
    });
    in_style
        .or_else(|| n.attribute(property).map(str::trim))
        .filter(|v| *v != "inherit")
}

/// Whether CSS text (a `style` attribute or a style sheet) declares `transform`
/// or `transform-origin` (conservative: a match inside a comment counts).
fn declares_transform(css: &str) -> bool {
    css.split([';', '{', '}']).any(|declaration| {
        declaration.split_once(':').is_some_and(|(name, _)| {
            let name = name.trim();
            name.eq_ignore_ascii_case("transform") || name.eq_ignore_ascii_case("transform-origin")
        })
    })
}

/// Whether `n` is an element in the SVG namespace (or in none).
fn is_svg(n: Node<'_, '_>) -> bool {
    n.is_element() && matches!(n.tag_name().namespace(), None | Some(SVG_NS))
}

/// A valid `viewBox` (positive, finite size).
fn view_box(e: Node<'_, '_>) -> Option<svgtypes::ViewBox> {
    let vb = svgtypes::ViewBox::from_str(e.attribute("viewBox")?).ok()?;
    (vb.w > 0.0 && vb.h > 0.0 && [vb.x, vb.y, vb.w, vb.h].iter().all(|v| v.is_finite()))
        .then_some(vb)
}

/// `preserveAspectRatio` (default `xMidYMid meet`).
fn aspect(e: Node<'_, '_>) -> svgtypes::AspectRatio {
    e.attribute("preserveAspectRatio")
        .and_then(|s| svgtypes::AspectRatio::from_str(s).ok())
        .unwrap_or_default()
}

/// A `width`/`height` that a viewBox mapping needs: given in absolute units
/// (the default, 100% of the parent viewport, needs context).
fn sized(e: Node<'_, '_>, attr: &str) -> Result<f64, Unsupported> {
    match e
        .attribute(attr)
        .and_then(|s| svgtypes::Length::from_str(s).ok())
    {
        Some(l) => absolute(l),
        None => Err("a viewport sized by percentage"),
    }
}

/// The `viewBox` → viewport mapping of SVG (usvg's `ViewBox::to_transform`, in
/// f64); `None` for a viewport without area.
pub(super) fn view_box_mapping(
    vb: svgtypes::ViewBox,
    aspect: svgtypes::AspectRatio,
    width: f64,
    height: f64,
) -> Option<Affine> {
    if !(width > 0.0 && height > 0.0 && width.is_finite() && height.is_finite()) {
        return None;
    }
    let (sx, sy, tx, ty) = super::viewport::fit([vb.x, vb.y, vb.w, vb.h], aspect, width, height);
    Some(Affine::new([sx, 0.0, 0.0, sy, tx, ty]))
}

/// A length attribute in user units: `default` when absent or not a length
/// (as usvg does).
///
/// # Errors
/// A length in %, em or ex (context needed).
pub(super) fn length(e: Node<'_, '_>, attr: &str, default: f64) -> Result<f64, Unsupported> {
    match e
        .attribute(attr)
        .and_then(|s| svgtypes::Length::from_str(s).ok())
    {
        None => Ok(default),
        Some(l) => absolute(l),
    }
}

/// A length with an absolute unit, in user units (CSS px, 96 per inch),
/// with as few roundings as the unit allows.
///
/// # Errors
/// A length in %, em or ex (context needed).
pub(super) fn absolute(l: svgtypes::Length) -> Result<f64, Unsupported> {
    use svgtypes::LengthUnit as U;
    let n = l.number;
    match l.unit {
        U::None | U::Px => Ok(n),
        U::In => Ok(n * 96.0),
        // 96 / 2.54 = 4800 / 127, 96 / 25.4 = 480 / 127
        U::Cm => Ok(n * 4800.0 / 127.0),
        U::Mm => Ok(n * 480.0 / 127.0),
        U::Pt => Ok(n * 4.0 / 3.0),
        U::Pc => Ok(n * 16.0),
        U::Percent | U::Em | U::Ex => Err("a length in %, em or ex"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(text: &str) -> Document<'_> {
        Document::parse(text).expect("test XML parses")
    }

    #[test]
    fn private_ids_go_on_anonymous_shapes_and_uses_only() {
        let text = r##"<svg xmlns="http://www.w3.org/2000/svg"><g><rect width="1" height="1"/><svg:path xmlns:svg="http://www.w3.org/2000/svg" d="M0 0L1 1"/></g><circle id="c" r="1"/><use href="#c"/><text><tspan>hi</tspan></text></svg>"##;
        let (marked, prefix) = with_private_ids(text, &doc(text)).expect("ids added");
        assert_eq!(prefix, "triwild0-");
        let d = doc(&marked);
        let ids: Vec<(&str, Option<&str>)> = d
            .descendants()
            .filter(Node::is_element)
            .map(|n| (n.tag_name().name(), n.attribute("id")))
            .collect();
        assert_eq!(
            ids,
            [
                ("svg", None),
                ("g", None),
                ("rect", Some("triwild0-0")),
                ("path", Some("triwild0-1")),
                ("circle", Some("c")),
                ("use", Some("triwild0-2")),
                ("text", None),
                ("tspan", None),
            ]
        );
        let source = Source::new(&d, Some(prefix));
        assert_eq!(source.public("triwild0-1"), None);
        assert_eq!(source.public("c"), Some("c"));
        assert_eq!(source.public(""), None);
    }

    #[test]
    fn the_prefix_avoids_the_documents_ids() {
        let text =
            r#"<svg xmlns="http://www.w3.org/2000/svg"><rect id="triwild0-7"/><rect/></svg>"#;
        let (marked, prefix) = with_private_ids(text, &doc(text)).expect("ids added");
        assert_eq!(prefix, "triwild1-");
        assert!(marked.contains(r#"<rect id="triwild1-0"/>"#), "{marked}");
        // a style sheet selecting on ids: no private ids
        let text = r#"<svg xmlns="http://www.w3.org/2000/svg"><style>[id] { fill: red }</style><rect/></svg>"#;
        assert!(with_private_ids(text, &doc(text)).is_none());
    }

    #[test]
    fn transforms_usvg_drops_are_those_below_f32_precision_that_f64_inverts() {
        assert!(tiny_for_usvg("scale(1e-7)"));
        assert!(tiny_for_usvg("scale(1e-7 1)"));
        assert!(tiny_for_usvg("matrix(0 1e-7 1e-7 0 0 0)"));
        assert!(tiny_for_usvg("translate(5 5) scale(1e-9)"));
        assert!(!tiny_for_usvg("scale(3e-7)"));
        assert!(!tiny_for_usvg("skewX(89.9)"));
        // singular in f64 too: not drawn by SVG's rules, nothing to carry
        assert!(!tiny_for_usvg("scale(0)"));
        assert!(!tiny_for_usvg("matrix(1 1 1 1 0 0)"));
        assert!(!tiny_for_usvg("not a transform"));
    }

    #[test]
    fn a_tiny_transform_is_renamed_on_groups_and_plain_shapes_drawn_in_place() {
        let text = r##"<svg xmlns="http://www.w3.org/2000/svg"><g transform="scale(1e-8)"><rect width="1" height="1"/></g><circle id="c" r="1" transform="scale(1e-8)"/><circle id="m" r="1" transform="scale(1e-8)" clip-path="url(#k)"/><use id="u" href="#d" transform="scale(1e-8)"/><defs><g id="d" transform="scale(1e-8)"><rect width="1" height="1"/></g></defs><g transform="scale(2)"/></svg>"##;
        let (marked, prefix) = with_private_ids(text, &doc(text)).expect("changes made");
        assert_eq!(prefix, "triwild0-");
        let d = doc(&marked);
        let renamed: Vec<(&str, Option<&str>)> = d
            .descendants()
            .filter(|n| n.has_attribute("triwild0-transform"))
            .map(|n| (n.tag_name().name(), n.attribute("id")))
            .collect();
        // the group (which gets an id) and the plain circle; not the clipped
        // circle, the <use>, nor the group drawn only through it
        assert_eq!(renamed, [("g", Some("triwild0-0")), ("circle", Some("c"))]);
        let source = Source::new(&d, Some(prefix));
        assert_eq!(
            source.usvg_omits("c"),
            Some(Affine::scale(1e-8)),
            "the true transform, read from the renamed attribute"
        );
        assert_eq!(source.usvg_omits("m"), None);
        assert_eq!(source.usvg_omits("d"), None);
        let dropped = source.dropped_for_tiny_transforms().expect("a warning");
        assert!(
            dropped.starts_with("2 element(s) not drawn")
                && dropped.ends_with("<circle id='m'>, <use id='u'>"),
            "{dropped}"
        );
    }

    #[test]
    fn css_transforms_are_recognised() {
        assert!(declares_transform("fill:red; transform: rotate(3)"));
        assert!(declares_transform("rect { Transform-Origin : 1px 2px }"));
        assert!(!declares_transform("text-transform:none;fill:red"));
        assert!(!declares_transform("fill:url(#transform)"));
    }

    #[test]
    fn lengths_in_absolute_units_convert_exactly() {
        let l = |s: &str| absolute(svgtypes::Length::from_str(s).expect("a length"));
        assert_eq!(l("2.54cm"), Ok(96.0));
        assert_eq!(l("25.4mm"), Ok(96.0));
        assert_eq!(l("1in"), Ok(96.0));
        assert_eq!(l("72pt"), Ok(96.0));
        assert_eq!(l("6pc"), Ok(96.0));
        assert_eq!(l("0.1"), Ok(0.1));
        assert_eq!(l("0.1px"), Ok(0.1));
        assert!(l("10%").is_err() && l("2em").is_err() && l("1ex").is_err());
    }
}
