//! Bytes → usvg tree: decoding, XML sanity checks, the usvg call and its limits,
//! and error messages a user can act on.
//!
//! Safety limits come from roxmltree and usvg themselves (verified by tests):
//! entity expansion stops at depth 10 / 255 references per entity ("billion
//! laughs"), `<use>` self-references are skipped, and the expanded element tree
//! is capped at 1,000,000 elements and 1024 levels of nesting. usvg recurses
//! along the element nesting, so the parse runs on its own thread with a large
//! stack; a panic inside usvg becomes a [`Error::NotSvg`] instead of unwinding
//! into the caller.

use super::budget;
use super::source::{self, Source};
use super::viewport::RootViewBox;
use crate::budget::Limits;
use crate::{Error, Result};
use std::collections::HashSet;
use std::sync::{Arc, OnceLock};
use usvg::{fontdb, roxmltree};

/// The SVG namespace.
const SVG_NS: &str = "http://www.w3.org/2000/svg";

/// Stack size of the parsing thread (usvg recurses once per nesting level, up to 1024).
const PARSE_STACK_BYTES: usize = 256 << 20;

/// What the XML pre-pass learned that the usvg tree does not keep.
#[derive(Debug, Default)]
pub(super) struct XmlFacts {
    /// Ids of `<use>` elements (their usvg group carries the id to anonymous children).
    pub(super) use_ids: HashSet<String>,
    /// Text elements that should render: (index among all `<text>` elements, id, text snippet).
    pub(super) texts: Vec<TextElement>,
    /// The root element's `viewBox` and `preserveAspectRatio` (the root viewport
    /// mapping that usvg folds into every absolute transform).
    pub(super) root_view_box: Option<RootViewBox>,
    /// `<image>` elements outside `<defs>` and the like (usvg drops an image whose
    /// data it does not decode, and triwild never decodes images).
    pub(super) images: usize,
}

/// A `<text>` element outside `<defs>`, clip paths, masks and the like.
#[derive(Debug)]
pub(super) struct TextElement {
    /// Index among all `<text>` elements, in document order.
    pub(super) index: usize,
    /// The `id` attribute, if any.
    pub(super) id: Option<String>,
    /// The first characters of its content.
    pub(super) snippet: String,
}

impl TextElement {
    /// How a warning names this element.
    pub(super) fn label(&self) -> String {
        match &self.id {
            Some(id) => format!("text element '{id}'"),
            None => format!("text element #{} (\"{}\")", self.index, self.snippet),
        }
    }
}

/// Everything the loader learned from one document: usvg's tree, the facts of
/// the XML pre-pass, and the source document itself (with private ids, see
/// [`Source`]).
pub(super) struct Parsed<'a, 'input> {
    /// usvg's render tree.
    pub(super) tree: usvg::Tree,
    /// What the XML pre-pass learned.
    pub(super) facts: XmlFacts,
    /// The source document, for the f64 geometry.
    pub(super) source: Source<'a, 'input>,
}

/// Parse `data` and run `work` on the result, on a thread with a large stack.
///
/// The usvg tree borrows nothing, but the source document borrows its text, so
/// the work that needs both runs inside this call.
pub(super) fn parse<R, F>(data: &[u8], limits: &Limits, work: F) -> Result<R>
where
    R: Send,
    F: FnOnce(&Parsed<'_, '_>) -> Result<R> + Send,
{
    let text = decode(data)?;
    let fontdb = font_database();
    let limits = *limits;
    let job = move || parse_text(&text, &limits, fontdb, work);
    std::thread::scope(|scope| {
        let spawned = std::thread::Builder::new()
            .name("triwild-svg-parse".into())
            .stack_size(PARSE_STACK_BYTES)
            .spawn_scoped(scope, job);
        match spawned {
            Ok(handle) => handle.join().unwrap_or_else(|_| {
                Err(Error::NotSvg(
                    "the SVG loader crashed on this input (usvg or triwild: a bug)".into(),
                ))
            }),
            // No thread available: not worth a second attempt on a small stack.
            Err(e) => Err(Error::NotSvg(format!(
                "cannot start the SVG parsing thread: {e}"
            ))),
        }
    })
}

/// Bytes → text, recognising common non-SVG inputs on the way.
fn decode(data: &[u8]) -> Result<String> {
    if data.iter().all(u8::is_ascii_whitespace) {
        return Err(Error::EmptyFile);
    }
    if let Some(what) = binary_format(data) {
        return Err(Error::NotSvg(what));
    }
    if let Some(units) = utf16_units(data) {
        return String::from_utf16(&units)
            .map_err(|_| Error::NotSvg("broken UTF-16 text (invalid surrogate pairs)".into()));
    }
    let text = std::str::from_utf8(data).map_err(|e| {
        Error::NotSvg(format!(
            "not UTF-8 text (invalid byte at offset {}); binary data or a legacy encoding",
            e.valid_up_to()
        ))
    })?;
    Ok(text.strip_prefix('\u{feff}').unwrap_or(text).to_owned())
}

/// A readable name for well-known binary formats, by their magic bytes.
fn binary_format(data: &[u8]) -> Option<String> {
    const MAGIC: &[(&[u8], &str)] = &[
        (
            &[0x1f, 0x8b],
            "gzip-compressed data (an .svgz file?); compressed SVG is not supported, decompress it first (gunzip)",
        ),
        (b"\x89PNG\r\n\x1a\n", "a PNG image, not an SVG document"),
        (&[0xff, 0xd8, 0xff], "a JPEG image, not an SVG document"),
        (b"GIF8", "a GIF image, not an SVG document"),
        (b"%PDF", "a PDF document, not an SVG document"),
        (b"PK\x03\x04", "a ZIP archive, not an SVG document"),
    ];
    MAGIC
        .iter()
        .find(|(magic, _)| data.starts_with(magic))
        .map(|(_, what)| (*what).to_owned())
        .or_else(|| {
            (data.len() >= 12 && &data[..4] == b"RIFF" && &data[8..12] == b"WEBP")
                .then(|| "a WebP image, not an SVG document".to_owned())
        })
}

/// UTF-16 code units if `data` starts with a UTF-16 byte-order mark.
fn utf16_units(data: &[u8]) -> Option<Vec<u16>> {
    let (body, little) = match data {
        [0xff, 0xfe, rest @ ..] => (rest, true),
        [0xfe, 0xff, rest @ ..] => (rest, false),
        _ => return None,
    };
    Some(
        body.chunks(2)
            .map(|c| {
                let pair = [c[0], c.get(1).copied().unwrap_or(0)];
                if little {
                    u16::from_le_bytes(pair)
                } else {
                    u16::from_be_bytes(pair)
                }
            })
            .collect(),
    )
}

/// Text → XML document → checks → private ids → usvg tree → `work`.
fn parse_text<R>(
    text: &str,
    limits: &Limits,
    fontdb: Arc<fontdb::Database>,
    work: impl FnOnce(&Parsed<'_, '_>) -> Result<R>,
) -> Result<R> {
    // Budgets first: entity expansion before the XML parser expands, segments
    // and elements before usvg builds its tree.
    budget::check_text(text, limits)?;
    let doc = parse_xml(text).map_err(|e| Error::NotSvg(xml_error_message(text, &e)))?;
    let root = doc.root_element();
    let name = root.tag_name();
    if !name.name().eq_ignore_ascii_case("svg") || !matches!(name.namespace(), None | Some(SVG_NS))
    {
        if let (true, Some(ns)) = (name.name().eq_ignore_ascii_case("svg"), name.namespace()) {
            return Err(Error::NotSvg(format!(
                "the root element <{}> is in the namespace '{ns}', not SVG's ({SVG_NS})",
                name.name()
            )));
        }
        let hint = if name.name().eq_ignore_ascii_case("html") {
            " (an HTML page?)"
        } else {
            ""
        };
        return Err(Error::NotSvg(format!(
            "the root element is <{}>, not <svg>{hint}",
            name.name()
        )));
    }
    budget::check_counts(budget::count(&doc), text.len() as u64, limits)?;
    check_numbers(&doc)?;
    // The same document with a private id on every anonymous shape and <use>;
    // should it not parse (it always should), the original is used and the
    // anonymous paths keep usvg's geometry.
    if let Some((marked, prefix)) = source::with_private_ids(text, &doc) {
        if let Ok(marked_doc) = parse_xml(&marked) {
            return convert(&marked_doc, Some(prefix), fontdb, work);
        }
    }
    convert(&doc, None, fontdb, work)
}

/// The XML parse, with DTDs allowed (usvg's own settings).
fn parse_xml(text: &str) -> std::result::Result<roxmltree::Document<'_>, roxmltree::Error> {
    let xml_opt = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    roxmltree::Document::parse_with_options(text, xml_opt)
}

/// A checked XML document → usvg tree → `work`.
fn convert<R>(
    doc: &roxmltree::Document<'_>,
    private_prefix: Option<String>,
    fontdb: Arc<fontdb::Database>,
    work: impl FnOnce(&Parsed<'_, '_>) -> Result<R>,
) -> Result<R> {
    let facts = xml_facts(doc);
    let opt = usvg::Options {
        fontdb,
        font_resolver: usvg::FontResolver {
            select_font: usvg::FontResolver::default_font_selector(),
            select_fallback: Box::new(fallback_face),
        },
        image_href_resolver: usvg::ImageHrefResolver {
            // Images are not geometry: never decode or read them.
            resolve_data: Box::new(|_, _, _| None),
            resolve_string: Box::new(|_, _| None),
        },
        ..usvg::Options::default()
    };
    let tree =
        usvg::Tree::from_xmltree(doc, &opt).map_err(|e| Error::NotSvg(usvg_error_message(&e)))?;
    work(&Parsed {
        tree,
        facts,
        source: Source::new(doc, private_prefix),
    })
}

/// usvg's error, made readable.
fn usvg_error_message(e: &usvg::Error) -> String {
    match e {
        usvg::Error::ParsingFailed(roxmltree::Error::NodesLimitReached) => {
            "too many elements or too deep nesting after expanding <use> references \
             (usvg's safety limits: 1,000,000 elements, 1024 levels)"
                .into()
        }
        usvg::Error::ParsingFailed(roxmltree::Error::NoRootNode) => {
            "the document has no <svg> root element".into()
        }
        usvg::Error::ParsingFailed(e) => format!("broken XML: {e}"),
        usvg::Error::ElementsLimitReached => {
            "more than 1,000,000 elements (usvg's safety limit)".into()
        }
        usvg::Error::InvalidSize => {
            "the <svg> element has an invalid size (zero or negative width/height, or a bad viewBox)"
                .into()
        }
        usvg::Error::NotAnUtf8Str => "not UTF-8 text".into(),
        usvg::Error::SvgzFeatureNotEnabled | usvg::Error::MalformedGZip => {
            "gzip-compressed data (an .svgz file?); compressed SVG is not supported".into()
        }
    }
}

/// roxmltree's error, with a hint when the input looks like HTML.
fn xml_error_message(text: &str, e: &roxmltree::Error) -> String {
    let head: String = text
        .trim_start()
        .chars()
        .take(64)
        .collect::<String>()
        .to_ascii_lowercase();
    if head.starts_with("<!doctype html") || head.starts_with("<html") {
        return format!("an HTML page, not an SVG document (XML error: {e})");
    }
    match e {
        roxmltree::Error::NoRootNode => "no XML element: not an XML document".into(),
        roxmltree::Error::EntityReferenceLoop(pos) => {
            format!("XML entity expansion too deep or too large at {pos} (entity bomb?)")
        }
        roxmltree::Error::NodesLimitReached => "too many XML nodes".into(),
        _ => format!("broken XML: {e}"),
    }
}

/// Reject numbers in geometry attributes that usvg would silently turn into a
/// dropped element: beyond the f32 range, or overflowing f64 (`1e400`).
///
/// usvg keeps geometry in f32; an element with such a number vanishes without a
/// trace, which would mesh a drawing with a piece missing. Conservative: it
/// also rejects such a number in an element that is never rendered.
fn check_numbers(doc: &roxmltree::Document<'_>) -> Result<()> {
    const GEOMETRY: &[&str] = &[
        "d",
        "points",
        "x",
        "y",
        "width",
        "height",
        "rx",
        "ry",
        "cx",
        "cy",
        "r",
        "x1",
        "y1",
        "x2",
        "y2",
        "transform",
        "viewBox",
    ];
    let limit = f64::from(f32::MAX);
    for node in doc.descendants().filter(roxmltree::Node::is_element) {
        if !matches!(node.tag_name().namespace(), None | Some(SVG_NS)) {
            continue;
        }
        for attr in node.attributes() {
            if attr.namespace().is_some() || !GEOMETRY.contains(&attr.name()) {
                continue;
            }
            let element = || match node.attribute("id") {
                Some(id) => format!("<{} id='{id}'>", node.tag_name().name()),
                None => format!("<{}>", node.tag_name().name()),
            };
            // `NaN`, `inf` and `Infinity` are not SVG numbers; usvg would stop the path
            // there and mesh what came before. No path command or transform name
            // contains these letter sequences, so their presence is always an error.
            let lower = attr.value().to_ascii_lowercase();
            if lower.contains("nan") || lower.contains("inf") {
                return Err(Error::BadCoordinate(format!(
                    "{}: attribute '{}' holds a non-finite number (NaN or infinity)",
                    element(),
                    attr.name()
                )));
            }
            if let Some(bad) = numbers(attr.value()).find(|(_, v)| v.is_nan() || v.abs() > limit) {
                let element = element();
                let shown: String = bad.0.chars().take(32).collect();
                return Err(Error::BadCoordinate(format!(
                    "{element}: the number {shown} in attribute '{}' is out of range \
                     (magnitude above {limit:e})",
                    attr.name()
                )));
            }
        }
    }
    Ok(())
}

/// The decimal numbers in an attribute value (signs ignored), with their text.
fn numbers(s: &str) -> impl Iterator<Item = (&str, f64)> {
    let b = s.as_bytes();
    let digits = |mut i: usize| {
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut i = 0;
    std::iter::from_fn(move || {
        while i < b.len() {
            let starts = b[i].is_ascii_digit()
                || (b[i] == b'.' && b.get(i + 1).is_some_and(u8::is_ascii_digit));
            if !starts {
                i += 1;
                continue;
            }
            let start = i;
            i = digits(i);
            if b.get(i) == Some(&b'.') {
                i = digits(i + 1);
            }
            if matches!(b.get(i), Some(b'e' | b'E')) {
                let mut j = i + 1;
                if matches!(b.get(j), Some(b'+' | b'-')) {
                    j += 1;
                }
                if b.get(j).is_some_and(u8::is_ascii_digit) {
                    i = digits(j);
                }
            }
            let text = &s[start..i];
            return Some((text, text.parse::<f64>().unwrap_or(f64::INFINITY)));
        }
        None
    })
}

/// What the usvg tree forgets: which groups are `<use>` elements, which text
/// elements exist, and the root viewBox.
fn xml_facts(doc: &roxmltree::Document<'_>) -> XmlFacts {
    const NOT_RENDERED: &[&str] = &[
        "defs", "clipPath", "mask", "pattern", "marker", "symbol", "title", "desc", "metadata",
    ];
    let mut facts = XmlFacts {
        root_view_box: RootViewBox::of(doc.root_element()),
        ..XmlFacts::default()
    };
    let mut text_index = 0;
    for node in doc.descendants().filter(roxmltree::Node::is_element) {
        let name = node.tag_name().name();
        if name == "use" {
            if let Some(id) = node.attribute("id") {
                facts.use_ids.insert(id.to_owned());
            }
        } else if name == "image" {
            let hidden = node
                .ancestors()
                .filter(roxmltree::Node::is_element)
                .any(|a| NOT_RENDERED.contains(&a.tag_name().name()));
            if !hidden {
                facts.images += 1;
            }
        } else if name == "text" {
            let index = text_index;
            text_index += 1;
            let hidden = node
                .ancestors()
                .filter(roxmltree::Node::is_element)
                .any(|a| {
                    NOT_RENDERED.contains(&a.tag_name().name())
                        || a.attribute("display") == Some("none")
                });
            let content: String = node
                .descendants()
                .filter_map(|n| n.text())
                .collect::<String>();
            let content = content.split_whitespace().collect::<Vec<_>>().join(" ");
            if hidden || content.is_empty() {
                continue;
            }
            let mut snippet: String = content.chars().take(20).collect();
            if content.chars().count() > 20 {
                snippet.push('…');
            }
            facts.texts.push(TextElement {
                index,
                id: node.attribute("id").map(str::to_owned),
                snippet,
            });
        }
    }
    facts
}

/// The face that draws `c` where the faces in `used` cannot (`used[0]` is the
/// face the text asked for): of the faces that have `c`, the closest to
/// `used[0]` in style (the same, else italic for oblique or the reverse, else
/// any), then weight, then stretch, then a face of the default sans-serif
/// family ([`font_database`] sets it); remaining ties go to the database's order.
///
/// usvg's default fallback takes the first face with the character unless it
/// differs in style *and* weight *and* stretch, so regular text could come out
/// in a bold face (Arabic in DejaVu Sans Bold).
fn fallback_face(
    c: char,
    used: &[fontdb::ID],
    db: &mut Arc<fontdb::Database>,
) -> Option<fontdb::ID> {
    let base = db.face(*used.first()?)?;
    let (style, weight, stretch) = (base.style, base.weight.0, base.stretch.to_number());
    let slanted = |s: fontdb::Style| s != fontdb::Style::Normal;
    let sans = db.family_name(&fontdb::Family::SansSerif).to_owned();
    let mut candidates: Vec<(u8, u16, u16, bool, usize, fontdb::ID)> = db
        .faces()
        .enumerate()
        .filter(|(_, f)| !used.contains(&f.id))
        .map(|(k, f)| {
            let style_distance = if f.style == style {
                0
            } else if slanted(f.style) == slanted(style) {
                1
            } else {
                2
            };
            (
                style_distance,
                f.weight.0.abs_diff(weight),
                f.stretch.to_number().abs_diff(stretch),
                !f.families.iter().any(|(name, _)| *name == sans),
                k,
                f.id,
            )
        })
        .collect();
    candidates.sort_unstable_by_key(|&(s, w, t, other, k, _)| (s, w, t, other, k));
    candidates
        .into_iter()
        .map(|c| c.5)
        .find(|&id| has_char(db, id, c))
}

/// Whether face `id` of `db` maps `c` to a glyph (as usvg's own check).
fn has_char(db: &fontdb::Database, id: fontdb::ID, c: char) -> bool {
    db.with_face_data(id, |data, index| {
        skrifa::FontRef::from_index(data, index)
            .ok()
            .and_then(|font| skrifa::MetadataProvider::charmap(&font).map(c))
            .is_some()
    })
    .unwrap_or(false)
}

/// The system fonts, loaded once per process.
///
/// Generic families (serif, sans-serif, ...) are pointed at fonts that exist
/// here, so that text with an unknown `font-family` still gets outlines.
pub(super) fn font_database() -> Arc<fontdb::Database> {
    static DB: OnceLock<Arc<fontdb::Database>> = OnceLock::new();
    DB.get_or_init(|| {
        let mut db = fontdb::Database::new();
        db.load_system_fonts();
        let families: Vec<String> = db
            .faces()
            .filter_map(|f| f.families.first().map(|(name, _)| name.clone()))
            .collect();
        let pick = |preferred: &[&str]| {
            preferred
                .iter()
                .find(|p| families.iter().any(|f| f == *p))
                .map(|p| (*p).to_owned())
                .or_else(|| families.first().cloned())
        };
        if let Some(f) = pick(&[
            "DejaVu Serif",
            "Liberation Serif",
            "Noto Serif",
            "FreeSerif",
        ]) {
            db.set_serif_family(f);
        }
        if let Some(f) = pick(&["DejaVu Sans", "Liberation Sans", "Noto Sans", "FreeSans"]) {
            db.set_sans_serif_family(f.clone());
            db.set_cursive_family(f.clone());
            db.set_fantasy_family(f);
        }
        if let Some(f) = pick(&["DejaVu Sans Mono", "Liberation Mono", "Noto Sans Mono"]) {
            db.set_monospace_family(f);
        }
        Arc::new(db)
    })
    .clone()
}
