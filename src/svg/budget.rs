//! The input budgets (`--max-segments`, `--max-shapes`, `--max-memory`),
//! checked before the large allocations: XML entity expansion on the raw text
//! (before roxmltree expands it), then segments and drawable elements on the
//! XML tree with `<use>` copies counted (before usvg builds its tree), then
//! the same counts on the loaded drawing (text glyphs included).

use crate::budget::Limits;
use crate::{Error, Result};
use std::collections::HashMap;
use usvg::roxmltree;

/// Bytes of expanded entity text allowed per segment of `--max-segments`:
/// path data needs a few bytes per segment, so this is generous.
const ENTITY_BYTES_PER_SEGMENT: u64 = 64;

/// Containers whose content is drawn only through `<use>` (or not at all).
const NOT_DRAWN: &[&str] = &[
    "defs", "symbol", "clipPath", "mask", "pattern", "marker", "title", "desc", "metadata",
];

/// Nesting of `<use>` references followed before giving up (usvg's own limit
/// on the expanded tree is far below what deeper chains could multiply to).
const MAX_USE_DEPTH: u32 = 32;

fn too_large(what: &str, n: u64, limit: u64, flag: &str) -> Error {
    Error::TooLarge(format!("{n} {what} (limit {limit}), raise with --{flag}"))
}

/// The internal entities declared in the document type of `text`, with their
/// replacement text.
fn entities(text: &str) -> Vec<(&str, &str)> {
    let mut out = Vec::new();
    let Some(start) = text.find("<!DOCTYPE") else {
        return out;
    };
    let mut rest = &text[start..];
    while let Some(i) = rest.find("<!ENTITY") {
        rest = rest[i + "<!ENTITY".len()..].trim_start();
        if rest.starts_with('%') {
            continue; // a parameter entity: not expanded in the document
        }
        let name_end = rest.find(|c: char| c.is_whitespace()).unwrap_or(rest.len());
        let name = &rest[..name_end];
        let after = rest[name_end..].trim_start();
        let Some(quote) = after.chars().next().filter(|c| *c == '"' || *c == '\'') else {
            continue; // an external entity (SYSTEM / PUBLIC): never loaded
        };
        let Some(end) = after[1..].find(quote) else {
            break;
        };
        out.push((name, &after[1..=end]));
        rest = &after[end + 1..];
    }
    out
}

/// How often each entity of `names` is referenced in `s`.
fn references(s: &str, names: &HashMap<&str, usize>) -> Vec<(usize, u64)> {
    let mut counts: HashMap<usize, u64> = HashMap::new();
    let mut rest = s;
    while let Some(i) = rest.find('&') {
        rest = &rest[i + 1..];
        if let Some(end) = rest.find(';') {
            if let Some(&k) = names.get(&rest[..end]) {
                *counts.entry(k).or_default() += 1;
            }
        }
    }
    counts.into_iter().collect()
}

/// How many bytes XML entity expansion adds to `text` (saturating).
pub(super) fn entity_growth(text: &str) -> u64 {
    let decls = entities(text);
    if decls.is_empty() {
        return 0;
    }
    let names: HashMap<&str, usize> = decls
        .iter()
        .enumerate()
        .map(|(i, (n, _))| (*n, i))
        .collect();
    let refs: Vec<Vec<(usize, u64)>> = decls.iter().map(|(_, v)| references(v, &names)).collect();
    // Expanded length of each entity, innermost first; a reference loop
    // counts as empty (roxmltree rejects it anyway).
    let mut len: Vec<Option<u64>> = vec![None; decls.len()];
    fn expanded(
        k: usize,
        decls: &[(&str, &str)],
        refs: &[Vec<(usize, u64)>],
        len: &mut Vec<Option<u64>>,
        depth: u32,
    ) -> u64 {
        if let Some(n) = len[k] {
            return n;
        }
        if depth > 16 {
            return 0;
        }
        // in progress: a reference back to it (a loop) counts as empty
        len[k] = Some(0);
        let mut n = decls[k].1.len() as u64;
        for &(r, count) in &refs[k] {
            let inner = expanded(r, decls, refs, len, depth + 1);
            let reference = decls[r].0.len() as u64 + 2;
            n = n.saturating_add(count.saturating_mul(inner.saturating_sub(reference)));
        }
        len[k] = Some(n);
        n
    }
    let body = text.rfind("]>").map_or(text, |i| &text[i..]);
    let mut growth = 0u64;
    for (k, count) in references(body, &names) {
        let inner = expanded(k, &decls, &refs, &mut len, 0);
        let reference = decls[k].0.len() as u64 + 2;
        growth = growth.saturating_add(count.saturating_mul(inner.saturating_sub(reference)));
    }
    growth
}

/// Check the raw text against the budgets before the XML parser expands its
/// entities.
///
/// # Errors
/// [`Error::TooLarge`] when entity expansion would add more text than the
/// segment budget can use, or the estimated memory is over budget.
pub(super) fn check_text(text: &str, limits: &Limits) -> Result<()> {
    let growth = entity_growth(text);
    let allowed = limits.max_segments.saturating_mul(ENTITY_BYTES_PER_SEGMENT);
    if growth > allowed {
        return Err(Error::TooLarge(format!(
            "XML entities expand the document by {} MB of text (limit {} MB: {ENTITY_BYTES_PER_SEGMENT} bytes \
             per segment of --max-segments {}), raise with --max-segments",
            growth >> 20,
            allowed >> 20,
            limits.max_segments
        )));
    }
    let text_bytes = (text.len() as u64).saturating_add(growth);
    let mb = Limits::estimate_mb(text_bytes, 0, 0);
    if mb > limits.max_memory_mb {
        return Err(too_large(
            "MiB of memory estimated for the document's text",
            mb,
            limits.max_memory_mb,
            "max-memory",
        ));
    }
    Ok(())
}

/// Segments and drawable elements of a document, `<use>` copies included.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Counts {
    /// Path segments (polygon points, shape sides).
    pub(super) segments: u64,
    /// Paths and basic shapes.
    pub(super) shapes: u64,
}

impl Counts {
    fn add(self, other: Counts, times: u64) -> Counts {
        Counts {
            segments: self
                .segments
                .saturating_add(other.segments.saturating_mul(times)),
            shapes: self
                .shapes
                .saturating_add(other.shapes.saturating_mul(times)),
        }
    }
}

/// Segments of path data: one per drawing command (implicit repeats included).
fn path_segments(d: &str) -> u64 {
    svgtypes::PathParser::from(d)
        .take_while(Result::is_ok)
        .filter(|s| {
            !matches!(
                s,
                Ok(svgtypes::PathSegment::MoveTo { .. } | svgtypes::PathSegment::ClosePath { .. })
            )
        })
        .count() as u64
        + 1
}

/// Numbers in a `points` attribute, halved: the points of a polyline.
fn point_count(points: &str) -> u64 {
    let numbers = points
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .count() as u64;
    numbers / 2 + 1
}

/// An element's own counts (not its children's).
fn own(node: roxmltree::Node<'_, '_>) -> Counts {
    let segments = match node.tag_name().name() {
        "path" => path_segments(node.attribute("d").unwrap_or("")),
        "polygon" | "polyline" => point_count(node.attribute("points").unwrap_or("")),
        "rect" => 8,
        "circle" | "ellipse" => 4,
        "line" => 1,
        _ => return Counts::default(),
    };
    Counts {
        segments,
        shapes: 1,
    }
}

/// The counts of a whole document, `<use>` references followed.
pub(super) fn count(doc: &roxmltree::Document<'_>) -> Counts {
    let ids: HashMap<&str, roxmltree::Node<'_, '_>> = doc
        .descendants()
        .filter_map(|n| n.attribute("id").map(|id| (id, n)))
        .collect();
    let mut memo: HashMap<(roxmltree::NodeId, bool), Counts> = HashMap::new();
    subtree(doc.root_element(), false, &ids, &mut memo, 0)
}

fn subtree<'a, 'i>(
    node: roxmltree::Node<'a, 'i>,
    via_use: bool,
    ids: &HashMap<&str, roxmltree::Node<'a, 'i>>,
    memo: &mut HashMap<(roxmltree::NodeId, bool), Counts>,
    depth: u32,
) -> Counts {
    if !via_use && NOT_DRAWN.contains(&node.tag_name().name()) {
        return Counts::default();
    }
    if let Some(&c) = memo.get(&(node.id(), via_use)) {
        return c;
    }
    if depth > MAX_USE_DEPTH {
        return Counts::default();
    }
    let mut c = own(node);
    if node.tag_name().name() == "use" {
        let href = node
            .attributes()
            .find(|a| a.name() == "href")
            .map(|a| a.value());
        if let Some(target) = href
            .and_then(|h| h.strip_prefix('#'))
            .and_then(|id| ids.get(id))
        {
            // A reference to itself or an ancestor is a loop usvg skips.
            if !node.ancestors().any(|a| a == *target) {
                c = c.add(subtree(*target, true, ids, memo, depth + 1), 1);
            }
        }
    }
    for child in node.children().filter(roxmltree::Node::is_element) {
        c = c.add(subtree(child, false, ids, memo, depth + 1), 1);
    }
    memo.insert((node.id(), via_use), c);
    c
}

/// Check counts (of the XML tree, or of the loaded drawing) against the budgets.
///
/// # Errors
/// [`Error::TooLarge`] naming the first budget exceeded and its flag.
pub(super) fn check_counts(c: Counts, text_bytes: u64, limits: &Limits) -> Result<()> {
    if c.segments > limits.max_segments {
        return Err(too_large(
            "segments",
            c.segments,
            limits.max_segments,
            "max-segments",
        ));
    }
    if c.shapes > limits.max_shapes {
        return Err(too_large(
            "shapes",
            c.shapes,
            limits.max_shapes,
            "max-shapes",
        ));
    }
    let mb = Limits::estimate_mb(text_bytes, c.segments, c.shapes);
    if mb > limits.max_memory_mb {
        return Err(too_large(
            "MiB of memory estimated",
            mb,
            limits.max_memory_mb,
            "max-memory",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc_counts(text: &str) -> Counts {
        let opt = roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        };
        count(&roxmltree::Document::parse_with_options(text, opt).expect("xml"))
    }

    #[test]
    fn counts_follow_use_and_skip_defs() {
        let c = doc_counts(
            r##"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink">
            <defs><path id="p" d="M0 0 L1 0 L1 1 Z"/></defs>
            <use xlink:href="#p"/><use href="#p"/><use href="#g"/>
            <g id="g"><rect width="1" height="1"/><polygon points="0,0 1,0 1,1"/></g>
            <use href="#u"/><use id="u" href="#u"/></svg>"##,
        );
        // path: 2 line segments + the closing one counted as 1 extra (3), twice;
        // the group (rect 8 + polygon 4) twice
        assert_eq!(
            c,
            Counts {
                segments: 2 * 3 + 2 * 12,
                shapes: 2 + 4
            }
        );
    }

    #[test]
    fn entity_growth_is_computed_without_expanding() {
        let seg = "l1 1 ".repeat(100);
        let text = format!(
            "<?xml version=\"1.0\"?><!DOCTYPE svg [<!ENTITY a \"{seg}\"><!ENTITY b \"{}\">]>\
             <svg><path d=\"M0 0 {}\"/></svg>",
            "&a;".repeat(250),
            "&b;".repeat(400)
        );
        let growth = entity_growth(&text);
        // b: its own 750 bytes ("&a;" 250 times) and 250 expansions of a;
        // each of the 400 references to b adds b's length less its own 3
        let expected = 400 * (750 + 250 * (seg.len() as u64 - 3) - 3);
        assert_eq!(growth, expected);
        let limits = Limits {
            max_segments: 100_000,
            max_shapes: 10,
            max_memory_mb: 1 << 20,
        };
        // 50 MB of path data, more than 64 bytes for each of 100 000 segments
        let e = check_text(&text, &limits).expect_err("over the entity allowance");
        assert!(e.to_string().contains("raise with --max-segments"), "{e}");
        assert_eq!(entity_growth("<svg/>"), 0);
        // a loop is not followed forever
        assert!(entity_growth("<!DOCTYPE s [<!ENTITY a \"&a;&a;\">]><s>&a;</s>") < 100);
    }

    #[test]
    fn budget_messages_name_the_flag() {
        let limits = Limits {
            max_segments: 10,
            max_shapes: 2,
            max_memory_mb: 100,
        };
        let msg = |c, t| check_counts(c, t, &limits).expect_err("over").to_string();
        assert_eq!(
            msg(
                Counts {
                    segments: 11,
                    shapes: 1
                },
                0
            ),
            "too large: 11 segments (limit 10), raise with --max-segments"
        );
        assert_eq!(
            msg(
                Counts {
                    segments: 1,
                    shapes: 3
                },
                0
            ),
            "too large: 3 shapes (limit 2), raise with --max-shapes"
        );
        assert!(
            msg(
                Counts {
                    segments: 1,
                    shapes: 1
                },
                1 << 30
            )
            .contains("--max-memory")
        );
        check_counts(
            Counts {
                segments: 10,
                shapes: 2,
            },
            0,
            &limits,
        )
        .expect("at the limit");
    }
}
