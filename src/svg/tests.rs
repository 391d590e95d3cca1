//! Unit tests of the SVG loader, through its own API (`load_bytes`, `load_file`).

use super::*;
use crate::ErrorKind;
use crate::budget::Limits;
use crate::units::Units;
use kurbo::{ParamCurve, Point};

/// Wrap `body` in an `<svg>` root with a 100×100 user space (no viewBox scaling).
fn svg(body: &str) -> String {
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="100" height="100">{body}</svg>"#
    )
}

/// Load with strokes as centre lines (the outlines as written: most tests here
/// are about geometry; the paint model has its own tests below).
fn load(body: &str) -> Drawing {
    load_bytes(svg(body).as_bytes(), &OUTLINES).expect("test SVG loads")
}

/// User units, scale 1, every outline as written ([`PaintOptions::OUTLINES`]).
const OUTLINES: LoadOptions = LoadOptions::DEFAULT.with_paint(PaintOptions::OUTLINES);

/// Load `data` in `units` at `scale`, every outline as written, with the
/// precision report.
fn load_outlines(data: &[u8], units: Units, scale: f64) -> Result<(Drawing, Precision)> {
    load_with_precision(data, &OUTLINES.with_units(units).with_scale(scale))
}

fn load_err(doc: &str) -> Error {
    load_bytes(doc.as_bytes(), &LoadOptions::DEFAULT).expect_err("test SVG must be rejected")
}

fn count(sub: &Subpath) -> (usize, usize) {
    let lines = sub
        .segments
        .iter()
        .filter(|s| matches!(s, Segment::Line(_)))
        .count();
    (lines, sub.segments.len() - lines)
}

fn conics(sub: &Subpath) -> usize {
    sub.segments
        .iter()
        .filter(|s| matches!(s, Segment::Conic(_)))
        .count()
}

fn close(a: Point, b: Point) -> bool {
    (a - b).hypot() < 1e-9
}

#[test]
fn rounded_rect_is_four_conics_and_four_lines() {
    let d = load(r#"<rect x="10" y="10" width="50" height="30" rx="5" ry="4"/>"#);
    assert_eq!(d.shapes.len(), 1);
    let subs = &d.shapes[0].subpaths;
    assert_eq!(subs.len(), 1);
    assert!(subs[0].closed);
    assert_eq!(count(&subs[0]), (4, 4));
    assert_eq!(conics(&subs[0]), 4);
    assert_eq!(d.features.len(), 8);
    assert!(close(d.bbox.origin(), Point::new(10.0, -40.0)));
    assert!((d.bbox.width() - 50.0).abs() < 1e-9 && (d.bbox.height() - 30.0).abs() < 1e-9);
}

#[test]
fn circle_is_four_conics() {
    let d = load(r#"<circle cx="50" cy="50" r="20"/>"#);
    let sub = &d.shapes[0].subpaths[0];
    assert!(sub.closed);
    assert_eq!(count(sub), (0, 4));
    assert_eq!(conics(sub), 4);
    for seg in &sub.segments {
        let Segment::Conic(c) = seg else {
            panic!("{seg:?}")
        };
        for t in [0.0, 0.25, 0.5, 0.75, 1.0] {
            let r = (c.eval(t) - Point::new(50.0, -50.0)).hypot();
            assert!((r - 20.0).abs() < 1e-13, "radius {r}");
        }
    }
}

#[test]
fn ellipse_line_polyline_polygon() {
    let d = load(
        r#"<ellipse cx="50" cy="50" rx="20" ry="10"/>
           <line x1="0" y1="0" x2="10" y2="10" stroke="black"/>
           <polyline points="0,0 10,0 10,10" fill="none" stroke="black"/>
           <polygon points="0,0 10,0 10,10"/>"#,
    );
    assert_eq!(d.shapes.len(), 4);
    assert_eq!(count(&d.shapes[0].subpaths[0]), (0, 4));
    assert_eq!(conics(&d.shapes[0].subpaths[0]), 4);
    assert_eq!(count(&d.shapes[1].subpaths[0]), (1, 0));
    assert_eq!(count(&d.shapes[2].subpaths[0]), (2, 0));
    assert!(!d.shapes[2].subpaths[0].closed);
    assert_eq!(count(&d.shapes[3].subpaths[0]), (3, 0));
    assert!(d.shapes[3].subpaths[0].closed);
    let idx: Vec<u32> = d.shapes.iter().map(|s| s.element_index).collect();
    assert_eq!(idx, [0, 1, 2, 3]);
}

#[test]
fn y_is_flipped() {
    let d = load(r#"<path d="M 1 2 L 10 20" stroke="black"/>"#);
    let FeatureGeom::Line(l) = d.features[0].geom else {
        panic!("expected a line, got {:?}", d.features[0].geom)
    };
    assert_eq!(
        (l.p0, l.p1),
        (Point::new(1.0, -2.0), Point::new(10.0, -20.0))
    );
}

#[test]
fn transforms_are_applied() {
    let d = load(
        r#"<g transform="translate(10,20) scale(2)">
             <rect x="1" y="1" width="1" height="1" transform="rotate(90 1 1)"/>
           </g>"#,
    );
    // rect (1..2, 1..2) rotated 90° about (1,1) -> (0..1, 1..2); then scale 2, translate.
    assert!(
        close(d.bbox.origin(), Point::new(10.0, -24.0)),
        "{:?}",
        d.bbox
    );
    assert!(close(
        Point::new(d.bbox.x1, d.bbox.y1),
        Point::new(12.0, -22.0)
    ));
}

#[test]
fn nested_svg_and_use_are_positioned() {
    let d = load(
        r##"<svg x="10" y="10" width="20" height="20" viewBox="0 0 10 10">
              <rect width="10" height="10"/>
            </svg>
            <defs><rect id="r" width="5" height="5"/></defs>
            <use id="u" xlink:href="#r" x="50" y="60"/>"##,
    );
    // the two rects, then the nested viewport's clip outline (feature geometry)
    assert_eq!(d.shapes.len(), 3);
    assert!(!d.shapes[2].filled && d.shapes[0].paint.clips.len() == 1);
    let b0 = bbox_of(&d.shapes[0]);
    assert!(close(b0.origin(), Point::new(10.0, -30.0)), "{b0:?}");
    assert!(
        close(Point::new(b0.x1, b0.y1), Point::new(30.0, -10.0)),
        "{b0:?}"
    );
    let b1 = bbox_of(&d.shapes[1]);
    assert!(close(b1.origin(), Point::new(50.0, -65.0)), "{b1:?}");
    assert!(d.shapes[1].svg_id.is_some());
}

#[test]
fn use_id_names_anonymous_children() {
    let d = load(
        r##"<defs><g id="g"><rect width="5" height="5"/></g></defs>
            <use id="u" xlink:href="#g"/>"##,
    );
    assert_eq!(d.shapes[0].svg_id.as_deref(), Some("u"));
    assert_eq!(d.shapes[0].name(), "u");
}

fn bbox_of(shape: &Shape) -> kurbo::Rect {
    let mut pts = shape
        .subpaths
        .iter()
        .flat_map(|s| s.segments.iter().flat_map(Segment::control_points));
    let first = pts.next().expect("shape has points");
    pts.fold(kurbo::Rect::from_points(first, first), |r, p| r.union_pt(p))
}

#[test]
fn css_styles_apply() {
    let d = load(
        r##"<style>.a { fill: #00ff00; fill-rule: evenodd } #b { fill: none; stroke: red }</style>
           <rect class="a" width="5" height="5"/>
           <rect id="b" width="5" height="5"/>"##,
    );
    assert_eq!(d.shapes[0].fill_colour, Some([0, 255, 0]));
    assert_eq!(d.shapes[0].fill_rule, FillRule::EvenOdd);
    assert!(!d.shapes[1].filled && d.shapes[1].stroked);
}

#[test]
fn quadratic_is_elevated_exactly() {
    let d = load(r#"<path d="M 0 0 Q 30 60 60 0 T 120 0" fill="none" stroke="black"/>"#);
    let sub = &d.shapes[0].subpaths[0];
    assert_eq!(count(sub), (0, 2));
    let Segment::Cubic(c) = sub.segments[0] else {
        panic!("expected a cubic")
    };
    let q = kurbo::QuadBez::new((0.0, 0.0), (30.0, -60.0), (60.0, 0.0));
    for i in 0..=16 {
        let t = f64::from(i) / 16.0;
        assert!((c.eval(t) - q.eval(t)).hypot() < 1e-12);
    }
    assert_eq!(c.p1, Point::new(20.0, -40.0));
}

#[test]
fn fill_rule_colour_and_id() {
    let d = load(
        r##"<path id="star" fill="#102030" fill-rule="evenodd" d="M 0 0 L 10 0 L 5 10 Z"/>
           <path d="M 0 0 L 10 0 L 5 10 Z" fill="url(#nope)" stroke="blue"/>
           <path d="M 0 0 L 10 0 L 5 10 Z" fill="none"/>"##,
    );
    let s = &d.shapes[0];
    assert_eq!(s.svg_id.as_deref(), Some("star"));
    assert_eq!((s.filled, s.stroked), (true, false));
    assert_eq!(s.fill_rule, FillRule::EvenOdd);
    assert_eq!(s.fill_colour, Some([0x10, 0x20, 0x30]));
    assert_eq!(d.shapes[1].fill_rule, FillRule::NonZero);
    assert_eq!(d.shapes[1].name(), "shape-1");
    // Neither fill nor stroke: the renderer paints nothing, so nothing is loaded.
    assert_eq!(d.shapes.len(), 2);
    assert_eq!(
        d.paint.dropped_invisible, 0,
        "no paint at all is not a dropped paint"
    );
    // the stroke of shape 1 as the area it paints (the default)
    let d = load_bytes(
        svg(r##"<path d="M 0 0 L 10 0 L 5 10 Z" fill="url(#nope)" stroke="blue"/>"##).as_bytes(),
        &LoadOptions::DEFAULT,
    )
    .expect("loads");
    assert_eq!(d.shapes[0].name(), "shape-0-stroke");
}

#[test]
fn filled_open_subpath_gets_implicit_close() {
    let d = load(
        r#"<path d="M 0 0 L 10 0 L 10 10" fill="red"/>
           <path d="M 0 0 L 10 0 L 10 10" fill="none" stroke="red"/>
           <path d="M 0 0 L 10 0 L 10 10 L 0 0" fill="red"/>"#,
    );
    let implicit: Vec<&Feature> = d
        .features
        .iter()
        .filter(|f| f.source.segment == FeatureSource::IMPLICIT_CLOSE)
        .collect();
    assert_eq!(implicit.len(), 1);
    assert_eq!(implicit[0].source.shape, ShapeId::from_index(0));
    assert_eq!(
        implicit[0].geom,
        FeatureGeom::Line(kurbo::Line::new((10.0, -10.0), (0.0, 0.0)))
    );
    assert_eq!(d.features.len(), 3 + 2 + 3);
}

#[test]
fn zero_length_subpaths_are_points() {
    let d = load(
        r#"<path d="M 5 5 L 5 5" stroke="black" stroke-linecap="round"/>
           <path d="M 0 0 L 10 0 L 10 0 L 20 0" fill="none" stroke="black"/>"#,
    );
    let s0 = &d.shapes[0];
    assert!(s0.subpaths[0].segments.is_empty());
    assert_eq!(
        d.features[0].geom,
        FeatureGeom::Point(Point::new(5.0, -5.0))
    );
    // The zero-length middle segment is dropped.
    assert_eq!(count(&d.shapes[1].subpaths[0]), (2, 0));
    assert_eq!(d.features.len(), 3);
    // A single point is a valid drawing.
    let p = load(r#"<path d="M 5 5 L 5 5" stroke="black"/>"#);
    assert_eq!(p.features.len(), 1);
    assert_eq!(p.diagonal(), 1.0);
}

#[test]
fn trailing_moveto_is_a_point() {
    let d = load(r#"<path d="M 0 0 L 10 0 M 20 20" stroke="black"/>"#);
    let geoms: Vec<FeatureGeom> = d.features.iter().map(|f| f.geom).collect();
    assert!(
        geoms.contains(&FeatureGeom::Point(Point::new(20.0, -20.0))),
        "{geoms:?}"
    );
}

#[test]
fn text_without_outline_warns() {
    let d = load(
        r#"<rect width="5" height="5"/>
           <text id="t0" x="10" y="10" font-size="0">Hello</text>"#,
    );
    assert_eq!(d.shapes.len(), 1);
    assert!(
        d.warnings.iter().any(|w| w.contains("'t0'")),
        "{:?}",
        d.warnings
    );
}

#[test]
fn text_becomes_outlines_when_a_font_exists() {
    let d = load_bytes(
        svg(r#"<text id="hello" x="10" y="50" font-size="20" font-family="sans-serif">Hi</text>"#)
            .as_bytes(),
        &LoadOptions::DEFAULT,
    );
    if super::load::font_database().is_empty() {
        // No font on this machine: the text is skipped with a warning.
        assert!(matches!(d, Err(Error::NoGeometry(_))));
    } else {
        let d = d.expect("text drawing loads");
        assert!(!d.shapes.is_empty());
        assert!(
            d.shapes
                .iter()
                .all(|s| s.svg_id.as_deref() == Some("hello"))
        );
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
    }
}

/// Text whose family is missing falls back, for the characters its
/// font lacks, to a face of the requested weight and style (usvg's default
/// fallback took the first face with the character: Arabic in regular text came
/// out DejaVu Sans Bold). Here the requested family is missing, the default
/// serif face has no Arabic, and the fallback must draw what DejaVu Sans in
/// the same weight and style draws. Skipped without DejaVu Sans.
#[test]
fn the_fallback_font_keeps_the_weight_and_style() {
    let db = super::load::font_database();
    let has = |family: &str| {
        db.faces()
            .any(|f| f.families.iter().any(|(name, _)| name == family))
    };
    if !has("DejaVu Sans") || !has("DejaVu Serif") {
        return;
    }
    let outline = |family: &str, style: &str| {
        let text = format!(
            r#"<text x="10" y="50" font-size="20" font-family="{family}" {style}>&#x645;&#x631;&#x62D;&#x628;&#x627;</text>"#
        );
        let d = load_bytes(svg(&text).as_bytes(), &LoadOptions::DEFAULT)
            .expect("the text has outlines");
        let points: Vec<Point> = d
            .shapes
            .iter()
            .flat_map(|s| &s.subpaths)
            .flat_map(|sp| {
                std::iter::once(sp.start)
                    .chain(sp.segments.iter().flat_map(Segment::control_points))
            })
            .collect();
        assert!(!points.is_empty(), "{family} {style}: no outline");
        points
    };
    for style in [
        r#"font-weight="normal""#,
        r#"font-weight="bold""#,
        r#"font-style="italic""#,
        r#"font-weight="bold" font-style="italic""#,
    ] {
        assert_eq!(
            outline("NoSuchFamily, serif", style),
            outline("DejaVu Sans", style),
            "{style}"
        );
    }
    // and the weights differ, so the comparison can fail
    assert_ne!(
        outline("DejaVu Sans", r#"font-weight="normal""#),
        outline("DejaVu Sans", r#"font-weight="bold""#)
    );
}

#[test]
fn images_are_ignored_with_a_warning() {
    let d = load(
        r#"<image width="10" height="10" xlink:href="data:image/png;base64,iVBORw0KGgo="/>
           <image width="10" height="10" xlink:href="/etc/passwd"/>
           <rect width="5" height="5"/>"#,
    );
    assert_eq!(d.shapes.len(), 1);
}

#[test]
fn clip_paths_and_masks_limit_the_shape_and_their_outlines_are_features() {
    let d = load(
        r##"<clipPath id="c"><circle cx="5" cy="5" r="5"/></clipPath>
            <mask id="m"><rect width="100" height="100" fill="white"/></mask>
            <rect width="10" height="10" clip-path="url(#c)" mask="url(#m)"/>"##,
    );
    assert_eq!(count(&d.shapes[0].subpaths[0]), (4, 0));
    assert_eq!(d.shapes[0].paint.clips.len(), 2);
    assert_eq!((d.paint.clipped_shapes, d.paint.masked_shapes), (1, 1));
    // the clip's circle, the mask's content and its rectangle: outlines only
    let outlines: Vec<String> = d.shapes[1..].iter().map(Shape::name).collect();
    assert!(
        d.shapes[1..]
            .iter()
            .all(|s| !s.filled && s.paint.kind == drawing::ShapeKind::ClipOutline)
    );
    assert_eq!(outlines, ["clip-c", "mask-m", "mask-m"]);
}

/// A rectangle with `marker="none"` beside a group keeps the group's path (usvg's
/// group must not be taken for the rectangle's markers).
#[test]
fn marker_none_beside_a_group_keeps_both_shapes() {
    let doc = r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100"><rect fill="#85d8f6" marker="none" width="40" height="60" x="6" y="37"/><g><path fill="#9fc510" d="M6 71h40v26H6z"/></g></svg>"##;
    let d = load_bytes(doc.as_bytes(), &LoadOptions::DEFAULT).expect("loads");
    let colours: Vec<_> = d.shapes.iter().map(|s| s.fill_colour).collect();
    assert_eq!(
        colours,
        [Some([0x85, 0xd8, 0xf6]), Some([0x9f, 0xc5, 0x10])],
        "{:?}",
        d.shapes
    );
}

/// Every arrangement of a basic shape whose marker properties say `none` (as
/// attributes or in its style) before or after a transformed, clipped or
/// masked path or group: every shape is kept. With a marker that resolves,
/// the basic shape's markers are still not drawn (SVG draws none on it) and
/// the neighbour is still kept.
#[test]
fn basic_shapes_with_marker_properties_never_hide_a_neighbour() {
    let defs = r##"<defs><clipPath id="c"><rect width="100" height="100"/></clipPath>
        <mask id="m"><rect width="100" height="100" fill="white"/></mask>
        <marker id="dot" markerWidth="4" markerHeight="4" markerUnits="userSpaceOnUse">
          <circle cx="2" cy="2" r="2" fill="#f00"/></marker></defs>"##;
    let basics = [
        r##"<rect id="b" x="6" y="37" width="40" height="30" fill="#00f" MARK/>"##,
        r##"<circle id="b" cx="26" cy="50" r="10" fill="#00f" MARK/>"##,
        r##"<ellipse id="b" cx="26" cy="50" rx="10" ry="5" fill="#00f" MARK/>"##,
    ];
    let none_marks = [
        r#"marker="none""#,
        r#"marker-start="none""#,
        r#"marker-end="none" marker-mid="none""#,
        r#"style="marker:none""#,
        r##"style="fill:#00f;marker-start:none;stroke:none""##,
    ];
    let neighbours = [
        r##"<path id="n" transform="translate(1 2)" d="M6 71h40v26H6z" fill="#0f0"/>"##,
        r##"<path id="n" clip-path="url(#c)" d="M6 71h40v26H6z" fill="#0f0"/>"##,
        r##"<path id="n" mask="url(#m)" d="M6 71h40v26H6z" fill="#0f0"/>"##,
        r##"<g id="g"><path id="n" d="M6 71h40v26H6z" fill="#0f0"/></g>"##,
        r##"<g><path id="n" d="M6 71h40v26H6z" fill="#0f0"/></g>"##,
        r##"<g transform="scale(1.01)"><path id="n" d="M6 71h40v26H6z" fill="#0f0"/></g>"##,
        r##"<g clip-path="url(#c)"><path id="n" d="M6 71h40v26H6z" fill="#0f0"/></g>"##,
        r##"<g mask="url(#m)"><path id="n" d="M6 71h40v26H6z" fill="#0f0"/></g>"##,
        r##"<g><g transform="rotate(1)"><path id="n" d="M6 71h40v26H6z" fill="#0f0"/></g></g>"##,
    ];
    let ids = |body: &str| {
        let d = load(&format!("{defs}{body}"));
        let mut ids: Vec<String> = d
            .shapes
            .iter()
            .filter(|s| s.filled)
            .map(Shape::name)
            .collect();
        ids.sort();
        ids
    };
    let mut cases = 0;
    for basic in basics {
        for mark in none_marks.iter().chain([&r#"marker-start="url(#dot)""#]) {
            let basic = basic.replace("MARK", mark);
            for neighbour in neighbours {
                for body in [format!("{basic}{neighbour}"), format!("{neighbour}{basic}")] {
                    assert_eq!(ids(&body), ["b", "n"], "{body}");
                    cases += 1;
                }
            }
        }
    }
    assert_eq!(cases, 3 * 6 * 9 * 2);
    // a path's markers are drawn: the marker group is not mistaken for a neighbour's
    let body = r##"<path id="p" d="M 10 10 L 50 50" fill="none" stroke="#000" marker-end="url(#dot)"/>
        <rect id="b" x="60" y="60" width="10" height="10" marker="none"/>"##;
    let d = load(&format!("{defs}{body}"));
    assert_eq!(d.shapes.iter().filter(|s| s.filled).count(), 2, "{body}");
}

#[test]
fn invisible_elements_stay_dropped() {
    let err = load_err(&svg(r#"<rect width="5" height="5" display="none"/>"#));
    assert!(matches!(err, Error::NoGeometry(_)), "{err}");
}

// ---- bad input ----

#[test]
fn missing_file_is_a_read_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let err =
        load_file(&dir.path().join("nope.svg"), &LoadOptions::DEFAULT).expect_err("missing file");
    assert!(matches!(err, Error::Read(_)));
    // A path that names no file is a bad argument (exit 2), not a failing disk.
    assert_eq!(err.kind(), ErrorKind::BadInput);
    assert!(err.to_string().contains("No such file"), "{err}");
}

#[test]
fn directory_is_rejected() {
    let dir = tempfile::tempdir().expect("tempdir");
    assert!(matches!(
        load_file(dir.path(), &LoadOptions::DEFAULT),
        Err(Error::IsDirectory)
    ));
}

#[test]
fn empty_file_is_rejected() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("empty.svg");
    std::fs::write(&path, b"").expect("write");
    assert!(matches!(
        load_file(&path, &LoadOptions::DEFAULT),
        Err(Error::EmptyFile)
    ));
    assert!(matches!(
        load_bytes(b" \n\t ", &LoadOptions::DEFAULT),
        Err(Error::EmptyFile)
    ));
}

#[test]
fn a_file_loads() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("ok.svg");
    std::fs::write(&path, svg(r#"<rect width="5" height="5"/>"#)).expect("write");
    assert_eq!(
        load_file(&path, &LoadOptions::DEFAULT)
            .expect("loads")
            .features
            .len(),
        4
    );
}

fn not_svg(doc: &[u8]) -> String {
    match load_bytes(doc, &LoadOptions::DEFAULT) {
        Err(Error::NotSvg(cause)) => cause,
        other => panic!("expected NotSvg, got {other:?}"),
    }
}

#[test]
fn non_svg_inputs_are_not_svg() {
    assert!(not_svg(b"hello world").contains("XML"));
    assert!(
        not_svg(b"<svg xmlns='http://www.w3.org/2000/svg'><rect></svg>").contains("broken XML")
    );
    let html = b"<!DOCTYPE html>\n<html><head><meta charset='utf-8'></head><body>x</body></html>";
    assert!(not_svg(html).contains("HTML"));
    let xhtml = b"<html xmlns='http://www.w3.org/1999/xhtml'><body/></html>";
    assert!(not_svg(xhtml).contains("<html>"));
    assert!(not_svg(b"<?xml version='1.0'?><foo/>").contains("<foo>"));
    let zero = b"<svg xmlns='http://www.w3.org/2000/svg' width='0' height='10'><rect width='5' height='5'/></svg>";
    assert!(not_svg(zero).contains("invalid size"));
    let png = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x01";
    assert!(not_svg(png).contains("PNG"));
    assert!(not_svg(&[0x1f, 0x8b, 8, 0, 0, 0]).contains("gzip"));
    assert!(not_svg(&[0x3c, 0xff, 0xfe, 0x00]).contains("UTF-8"));
    for e in [
        load_bytes(b"hello", &LoadOptions::DEFAULT),
        load_bytes(png, &LoadOptions::DEFAULT),
    ] {
        assert_eq!(e.expect_err("bad").kind(), ErrorKind::BadInput);
    }
}

#[test]
fn utf16_with_bom_is_decoded() {
    let text = svg(r#"<rect width="5" height="5"/>"#);
    let mut bytes = vec![0xff, 0xfe];
    bytes.extend(text.encode_utf16().flat_map(u16::to_le_bytes));
    assert_eq!(
        load_bytes(&bytes, &LoadOptions::DEFAULT)
            .expect("utf-16 loads")
            .features
            .len(),
        4
    );
    let bom8 = format!("\u{feff}{text}");
    assert_eq!(
        load_bytes(bom8.as_bytes(), &LoadOptions::DEFAULT)
            .expect("bom loads")
            .features
            .len(),
        4
    );
}

#[test]
fn empty_svg_has_no_geometry() {
    assert!(matches!(load_err(&svg("")), Error::NoGeometry(_)));
    assert!(matches!(
        load_err(&svg(r#"<path d=""/>"#)),
        Error::NoGeometry(_)
    ));
}

#[test]
fn huge_coordinates_are_bad() {
    let err = load_err(&svg(
        r#"<path id="far" d="M 0 0 L 1e20 0" stroke="black"/>"#,
    ));
    let Error::BadCoordinate(msg) = &err else {
        panic!("expected BadCoordinate, got {err:?}")
    };
    assert!(msg.contains("'far'"), "{msg}");
    let err = load_err(&svg(
        r#"<g transform="scale(1e20)"><rect width="1e10" height="1"/></g>"#,
    ));
    assert!(matches!(err, Error::BadCoordinate(_)), "{err:?}");
}

#[test]
fn nan_and_overflow_never_give_garbage() {
    let cases = [
        r#"<path d="M 0 0 L NaN 0 L 5 5" stroke="black"/>"#,
        r#"<path d="M 0 0 L 1e400 0 L 5 5" stroke="black"/>"#,
        r#"<path d="M 0 0 L 1e39 0 L 5 5" stroke="black"/>"#,
        r#"<path d="M 0 0 L inf 0" stroke="black"/>"#,
        r#"<rect width="1e39" height="5"/>"#,
        r#"<rect width="NaN" height="5"/>"#,
        r#"<circle r="1e400"/>"#,
        r#"<rect width="5" height="5" transform="scale(1e400)"/>"#,
        r#"<rect width="5" height="5" transform="scale(1e39)"/>"#,
        r#"<rect width="5" height="5" transform="translate(NaN)"/>"#,
        r#"<rect width="1e38" height="1e38" transform="scale(1e38)"/>"#,
        r#"<polygon points="0 0 1e39 0 0 1e39"/>"#,
    ];
    for case in cases {
        match load_bytes(svg(case).as_bytes(), &LoadOptions::DEFAULT) {
            Ok(d) => {
                for f in &d.features {
                    let pts: Vec<Point> = match f.geom {
                        FeatureGeom::Point(p) => vec![p],
                        FeatureGeom::Line(l) => vec![l.p0, l.p1],
                        FeatureGeom::Cubic(c) => vec![c.p0, c.p1, c.p2, c.p3],
                        FeatureGeom::Conic(c) => c.control_points().to_vec(),
                    };
                    for p in pts {
                        assert!(
                            p.is_finite() && p.x.abs() <= 1e15 && p.y.abs() <= 1e15,
                            "{case}"
                        );
                    }
                }
            }
            Err(Error::BadCoordinate(_) | Error::NoGeometry(_)) => {}
            Err(e) => panic!("{case}: unexpected {e:?}"),
        }
    }
}

#[test]
fn numbers_beyond_f32_are_bad_not_silently_dropped() {
    // usvg would drop these elements (f32 overflow) and mesh the rest.
    for (case, attr) in [
        (r#"<path id="a" d="M 0 0 L 1e39 0 L 5 5"/>"#, "'d'"),
        (r#"<rect id="a" width="1e400" height="5"/>"#, "'width'"),
        (
            r#"<g id="a" transform="translate(0 -4e38)"><rect width="5" height="5"/></g>"#,
            "'transform'",
        ),
    ] {
        let body = format!(r#"<rect width="5" height="5"/>{case}"#);
        let err = load_err(&svg(&body));
        let Error::BadCoordinate(msg) = &err else {
            panic!("{case}: expected BadCoordinate, got {err:?}")
        };
        assert!(msg.contains("id='a'") && msg.contains(attr), "{msg}");
    }
    // Large but representable numbers and foreign attributes are fine (up to
    // `Drawing::MIN_RELATIVE_EXTENT`: at 1e10 a 5-unit drawing is refused).
    load(r#"<rect width="5" height="5" x="1e6" y="-3e5" data-x="1e999"/>"#);
    let far = load_err(&svg(r#"<rect width="5" height="5" x="1e10" y="-3e9"/>"#));
    assert!(matches!(far, Error::BadCoordinate(_)), "{far:?}");
}

#[test]
fn tiny_extent_far_from_origin_is_bad() {
    let err = load_err(&svg(
        r#"<path d="M 1e14 0 L 1e14 0.00001" stroke="black"/>"#,
    ));
    assert!(
        matches!(err, Error::BadCoordinate(ref m) if m.contains("too small")),
        "{err:?}"
    );
    // The same extent near the origin is fine.
    load(r#"<path d="M 1 0 L 1 0.00001" stroke="black"/>"#);
}

#[test]
fn entity_bomb_is_rejected_quickly() {
    let mut doc = String::from(
        "<?xml version=\"1.0\"?>\n<!DOCTYPE svg [\n<!ENTITY a \"<rect width='1' height='1'/>\">\n",
    );
    let mut prev = "a".to_owned();
    for i in 0..12 {
        let name = format!("e{i}");
        doc.push_str(&format!(
            "<!ENTITY {name} \"{}\">\n",
            format!("&{prev};").repeat(10)
        ));
        prev = name;
    }
    doc.push_str(&format!(
        "]>\n<svg xmlns='http://www.w3.org/2000/svg'>&{prev};</svg>"
    ));
    let t = std::time::Instant::now();
    let err = load_err(&doc);
    assert!(matches!(err, Error::NotSvg(_)), "{err:?}");
    assert!(t.elapsed().as_secs_f64() < 5.0);
}

#[test]
fn use_bomb_is_rejected_quickly() {
    // Each level uses the previous one twice: 2^40 rectangles if expanded.
    let mut body = String::from(r#"<defs><rect id="l0" width="1" height="1"/>"#);
    for i in 1..=40 {
        body.push_str(&format!(
            r##"<g id="l{i}"><use xlink:href="#l{p}"/><use xlink:href="#l{p}" x="1"/></g>"##,
            p = i - 1
        ));
    }
    body.push_str(r##"</defs><use xlink:href="#l40"/>"##);
    let t = std::time::Instant::now();
    let err = load_err(&svg(&body));
    assert!(
        matches!(err, Error::NotSvg(ref m) if m.contains("limit")),
        "{err:?}"
    );
    assert!(t.elapsed().as_secs_f64() < 20.0, "{:?}", t.elapsed());
}

#[test]
fn deep_nesting_does_not_overflow_the_stack() {
    for depth in [1000, 5000] {
        let body = format!(
            "{}<rect width='1' height='1'/>{}",
            "<g>".repeat(depth),
            "</g>".repeat(depth)
        );
        match load_bytes(svg(&body).as_bytes(), &LoadOptions::DEFAULT) {
            Ok(d) => assert_eq!(d.shapes.len(), 1),
            Err(e) => assert!(matches!(e, Error::NotSvg(_)), "{e:?}"),
        }
    }
}

#[test]
fn recursive_use_is_skipped() {
    let d = load(
        r##"<g id="g1"><rect width="1" height="1"/><use xlink:href="#g1"/></g>
            <use id="self" xlink:href="#self"/>"##,
    );
    assert_eq!(d.shapes.len(), 1);
}

// ---- corpus and fuzzing ----

/// Every coordinate of a loaded drawing is finite and in range, and the bbox holds them.
fn assert_sane(d: &Drawing, what: &str) {
    assert!(!d.features.is_empty(), "{what}: no features");
    let bbox = d.bbox.inflate(1e-9 * d.diagonal(), 1e-9 * d.diagonal());
    for f in &d.features {
        let pts: Vec<Point> = match f.geom {
            FeatureGeom::Point(p) => vec![p],
            FeatureGeom::Line(l) => vec![l.p0, l.p1],
            FeatureGeom::Cubic(c) => vec![c.p0, c.p1, c.p2, c.p3],
            FeatureGeom::Conic(c) => c.control_points().to_vec(),
        };
        for p in pts {
            assert!(
                p.is_finite() && p.x.abs() <= Drawing::MAX_COORD && p.y.abs() <= Drawing::MAX_COORD,
                "{what}: bad point {p:?}"
            );
            assert!(bbox.contains(p), "{what}: {p:?} outside bbox {:?}", d.bbox);
        }
    }
}

/// Load every file of the dev corpus: no panic, Ok with sane geometry or a bad-input error.
/// About 1.5 s (test profile); skipped where the corpus is absent. Summary with
/// `cargo test --lib svg::tests::dev_corpus -- --nocapture`.
#[test]
#[allow(
    clippy::print_stderr,
    reason = "the corpus summary is the test's report"
)]
fn dev_corpus() {
    let root = std::path::Path::new("/work/shared/data/svg-dev");
    if !root.is_dir() {
        eprintln!("dev corpus not found at {}: skipped", root.display());
        return;
    }
    let mut files = Vec::new();
    let mut dirs = vec![root.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).expect("corpus directory readable") {
            let path = entry.expect("dir entry").path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "svg") {
                files.push(path);
            }
        }
    }
    files.sort();
    assert!(files.len() >= 300, "corpus has {} files", files.len());
    let mut counts: std::collections::BTreeMap<String, usize> = Default::default();
    let start = std::time::Instant::now();
    let mut slowest = (0.0, String::new());
    let mut precision = Precision::default();
    let mut files_by_reason: std::collections::BTreeMap<&str, usize> = Default::default();
    for path in &files {
        let name = path
            .strip_prefix(root)
            .unwrap_or(path)
            .display()
            .to_string();
        let t = std::time::Instant::now();
        let result = std::fs::read(path)
            .map_err(Error::Read)
            .and_then(|data| load_outlines(&data, Units::User, 1.0));
        let secs = t.elapsed().as_secs_f64();
        if secs > slowest.0 {
            slowest = (secs, name.clone());
        }
        let key = match &result {
            Ok((d, p)) => {
                assert_sane(d, &name);
                eprintln!(
                    "ok   {name}: {} shapes, {} features, bbox {:?}, warnings {:?}",
                    d.shapes.len(),
                    d.features.len(),
                    d.bbox,
                    d.warnings
                );
                precision.exact += p.exact;
                precision.glyphs += p.glyphs;
                for (reason, n) in &p.fallback {
                    *precision.fallback.entry(reason).or_default() += n;
                    *files_by_reason.entry(reason).or_default() += 1;
                }
                "ok".to_owned()
            }
            Err(e) => {
                assert_eq!(e.kind(), ErrorKind::BadInput, "{name}: {e}");
                eprintln!("FAIL {name}: {e}");
                format!("{e:?}").split('(').next().unwrap_or("?").to_owned()
            }
        };
        *counts.entry(key).or_default() += 1;
    }
    eprintln!(
        "dev corpus: {} files in {:.2} s (slowest {:.3} s: {}); {counts:?}",
        files.len(),
        start.elapsed().as_secs_f64(),
        slowest.0,
        slowest.1
    );
    eprintln!(
        "dev corpus paths: {} f64, {} glyph outlines, {} kept usvg's f32: {:?} (files per reason: {files_by_reason:?})",
        precision.exact,
        precision.glyphs,
        precision.fallbacks(),
        precision.fallback
    );
}

/// The dev corpus's SVG files, sorted; empty where the corpus is absent.
fn dev_corpus_files() -> Vec<std::path::PathBuf> {
    let root = std::path::Path::new("/work/shared/data/svg-dev");
    let mut files = Vec::new();
    if !root.is_dir() {
        return files;
    }
    let mut dirs = vec![root.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).expect("corpus directory readable") {
            let path = entry.expect("dir entry").path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "svg") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The loader audit of one parsed document: usvg's render tree walked on its
/// own (every group, every text's glyphs; clip, mask and pattern contents are
/// not painted in place), each path's fill and stroke checked against what
/// the loader did with it. Returns the defects: a painted fill or stroke that
/// is neither a shape nor counted under a named reason in the paint counts
/// (`--stats`), a skipped marker group that holds an element of the document
/// or sits beside no basic shape asking for markers, and counts that do not
/// add up.
fn audit(parsed: &load::Parsed<'_, '_>, out: &outline::Outlines) -> Vec<String> {
    use outline::Fate;
    use std::collections::{HashMap, HashSet};
    let ledger: HashMap<usize, [Fate; 2]> = out.ledger.iter().copied().collect();
    let skipped: HashSet<usize> = out.skipped_markers.iter().copied().collect();
    let source = &parsed.source;
    let mut problems = Vec::new();
    let mut marker_items = 0usize;
    let mut painted = [0usize; 2];
    let mut by_fate: HashMap<(usize, Fate), usize> = HashMap::new();
    fn items(node: &usvg::Node, named: &mut Vec<String>) -> usize {
        match node {
            usvg::Node::Group(g) => g.children().iter().map(|c| items(c, named)).sum(),
            usvg::Node::Path(p) => {
                if !p.id().is_empty() {
                    named.push(p.id().to_owned());
                }
                usize::from(p.fill().is_some()) + usize::from(p.stroke().is_some())
            }
            usvg::Node::Text(t) => t
                .flattened()
                .children()
                .iter()
                .map(|c| items(c, named))
                .sum(),
            usvg::Node::Image(_) => 0,
        }
    }
    // a neighbour that asks for markers, judged on the document's text alone:
    // a rect, circle or ellipse whose own text links a marker property, or a
    // style sheet that mentions markers
    let style_sheet_markers = source.style_sheet_mentions_markers();
    let asks_for_markers = |siblings: &[usvg::Node], j: usize| {
        let Some(usvg::Node::Path(p)) = siblings.get(j) else {
            return false;
        };
        source.shapes_with_id(p.id()).first().is_some_and(|n| {
            let links = n.ancestors().filter(|a| a.is_element()).any(|a| {
                a.attributes().any(|at| {
                    (at.name().starts_with("marker") && at.value().contains("url("))
                        || (at.name() == "style"
                            && at.value().split(';').any(|d| {
                                d.split_once(':').is_some_and(|(k, v)| {
                                    k.trim().starts_with("marker") && v.contains("url(")
                                })
                            }))
                })
            });
            matches!(n.tag_name().name(), "rect" | "circle" | "ellipse")
                && (links || style_sheet_markers)
        })
    };
    let mut stack: Vec<&usvg::Group> = vec![parsed.tree.root()];
    while let Some(g) = stack.pop() {
        let children = g.children();
        for (k, node) in children.iter().enumerate() {
            if skipped.contains(&std::ptr::from_ref(node).addr()) {
                let mut named = Vec::new();
                marker_items += items(node, &mut named);
                if !named.is_empty() {
                    problems.push(format!(
                        "a group skipped as markers holds document element(s) {named:?}"
                    ));
                }
                if !((k > 0 && asks_for_markers(children, k - 1))
                    || asks_for_markers(children, k + 1))
                {
                    problems.push(
                        "a group skipped as markers is beside no basic shape asking for markers"
                            .to_owned(),
                    );
                }
                continue;
            }
            match node {
                usvg::Node::Group(inner) => stack.push(inner),
                usvg::Node::Text(t) => stack.push(t.flattened()),
                usvg::Node::Image(_) => {}
                usvg::Node::Path(p) => {
                    let present = [p.fill().is_some(), p.stroke().is_some()];
                    let name = source.public(p.id()).unwrap_or("(anonymous)");
                    let Some(fates) = ledger.get(&std::ptr::from_ref::<usvg::Path>(p).addr())
                    else {
                        if present.iter().any(|&b| b) {
                            problems.push(format!(
                                "path {name}: painted, neither a shape nor counted under a reason"
                            ));
                        }
                        continue;
                    };
                    for (i, what) in ["fill", "stroke"].into_iter().enumerate() {
                        if present[i] != (fates[i] != Fate::None) {
                            problems.push(format!(
                                "path {name}: its {what} is {:?} but present = {}",
                                fates[i], present[i]
                            ));
                        }
                        if fates[i] == Fate::Painted {
                            painted[i] += 1;
                        }
                        *by_fate.entry((i, fates[i])).or_default() += 1;
                    }
                }
            }
        }
    }
    let n = |i: usize, f: Fate| by_fate.get(&(i, f)).copied().unwrap_or(0);
    let c = &out.paint;
    let mut expect = |what: &str, counted: usize, audited: usize| {
        if counted != audited {
            problems.push(format!(
                "{what}: --stats says {counted}, the audit finds {audited}"
            ));
        }
    };
    expect("markers_not_drawn", c.markers_not_drawn, marker_items);
    expect(
        "dropped_invisible",
        c.dropped_invisible,
        n(0, Fate::Invisible) + n(1, Fate::Invisible),
    );
    expect(
        "dropped_decoration",
        c.dropped_decoration,
        n(0, Fate::Decoration) + n(1, Fate::Decoration),
    );
    expect(
        "strokes_ignored",
        c.strokes_ignored,
        n(1, Fate::Ignored) + n(1, Fate::Invisible),
    );
    expect(
        "painted strokes as areas or lines",
        c.strokes_as_areas + c.strokes_as_lines,
        painted[1],
    );
    let filled = out.shapes.iter().filter(|s| s.filled).count();
    expect(
        "filled shapes (fills and stroke areas)",
        filled,
        painted[0] + c.strokes_as_areas,
    );
    problems
}

/// The loader audit over the dev corpus: every fill and stroke
/// usvg paints in every drawing is a shape or counted under a named reason
/// (see [`audit`]). Fails on any that is neither, naming the file and the
/// path. About 3 s in the test profile; skipped where the corpus is absent.
#[test]
#[allow(
    clippy::print_stderr,
    reason = "the audit's summary is the test's report"
)]
fn loader_audit_dev_corpus() {
    let files = dev_corpus_files();
    if files.is_empty() {
        eprintln!("dev corpus not found: skipped");
        return;
    }
    let start = std::time::Instant::now();
    let (mut audited, mut rejected, mut markers) = (0usize, 0usize, 0usize);
    let mut failures = Vec::new();
    for path in &files {
        let data = std::fs::read(path).expect("corpus file readable");
        let result = load::parse(&data, &Limits::NONE, |parsed| {
            let frame = viewport::Frame::new(
                Units::User,
                1.0,
                parsed.facts.root_view_box,
                parsed.tree.size(),
            )?;
            let map = reconstruct::OutputMap::new(&parsed.source, Units::User, 1.0);
            let out = outline::collect(parsed, &frame, map, &PaintOptions::DEFAULT)?;
            Ok((audit(parsed, &out), out.paint.markers_not_drawn))
        });
        match result {
            Ok((problems, m)) => {
                audited += 1;
                markers += m;
                failures.extend(
                    problems
                        .into_iter()
                        .map(|p| format!("{}: {p}", path.display())),
                );
            }
            Err(e) => {
                assert_eq!(e.kind(), ErrorKind::BadInput, "{}: {e}", path.display());
                rejected += 1;
            }
        }
    }
    eprintln!(
        "loader audit: {audited} drawings audited, {rejected} rejected as bad input, \
         {markers} marker paint items on basic shapes not drawn, {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(audited >= 280, "only {audited} drawings audited");
}

mod fuzz {
    use super::*;
    use proptest::prelude::*;

    const SEED_SVG: &str = r##"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" viewBox="0 0 100 100"><defs><path id="p" d="M 10 10 Q 20 40 30 10 T 50 10 A 5 5 0 0 1 60 20"/></defs><g transform="rotate(30 50 50) scale(1.5)"><rect x="5" y="5" width="40" height="20" rx="4"/><circle cx="50" cy="50" r="10" fill="none" stroke="red"/><use xlink:href="#p" x="3"/><polygon points="1,2 30,40 50,2" fill-rule="evenodd"/><svg x="60" y="60" width="20" height="20" viewBox="0 0 10 10"><ellipse cx="5" cy="5" rx="5" ry="2"/></svg></g><text x="5" y="90" font-size="8">Hi</text></svg>"##;

    fn config() -> ProptestConfig {
        ProptestConfig {
            cases: 128,
            failure_persistence: None,
            rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
            ..ProptestConfig::default()
        }
    }

    fn check(data: &[u8]) {
        match load_bytes(data, &LoadOptions::DEFAULT) {
            Ok(d) => assert_sane(&d, "fuzz input"),
            Err(e) => assert_eq!(e.kind(), ErrorKind::BadInput, "{e}"),
        }
    }

    #[test]
    fn seed_document_loads() {
        let d = load_bytes(SEED_SVG.as_bytes(), &LoadOptions::DEFAULT).expect("seed loads");
        assert!(d.shapes.len() >= 5);
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn random_bytes_never_panic(data in proptest::collection::vec(any::<u8>(), 0..256)) {
            check(&data);
        }

        #[test]
        fn mutated_svg_never_panics(
            edits in proptest::collection::vec((0..SEED_SVG.len(), 0u8..4, any::<u8>()), 1..8)
        ) {
            let mut data = SEED_SVG.as_bytes().to_vec();
            for (pos, op, byte) in edits {
                let pos = pos.min(data.len());
                match op {
                    0 => data.insert(pos, byte),
                    1 if pos < data.len() => { data.remove(pos); }
                    2 if pos < data.len() => data[pos] = byte,
                    // Splice in a digit run: huge, tiny or malformed numbers.
                    _ => data.splice(pos..pos, b"9e3".iter().copied().cycle().take(1 + usize::from(byte % 12))).for_each(drop),
                }
            }
            check(&data);
        }
    }
}

/// A root `<svg>` with `attrs`, holding `body`.
fn doc(attrs: &str, body: &str) -> String {
    format!(r#"<svg xmlns="http://www.w3.org/2000/svg" {attrs}>{body}</svg>"#)
}

fn load_in(doc: &str, units: Units, scale: f64) -> Drawing {
    load_bytes(
        doc.as_bytes(),
        &LoadOptions::DEFAULT.with_units(units).with_scale(scale),
    )
    .expect("test SVG loads")
}

/// The bbox as (x0, y0, x1, y1), output coordinates (y up).
fn corners(d: &Drawing) -> [f64; 4] {
    [d.bbox.x0, d.bbox.y0, d.bbox.x1, d.bbox.y1]
}

#[test]
fn root_viewbox_gives_user_units_by_default_and_px_on_request() {
    let doc = doc(
        r#"width="200" height="200" viewBox="0 0 100 100""#,
        r#"<rect width="10" height="10"/>"#,
    );
    // the document's numbers, exactly (y flipped)
    assert_eq!(
        corners(&load_bytes(doc.as_bytes(), &LoadOptions::DEFAULT).unwrap()),
        [0.0, -10.0, 10.0, 0.0]
    );
    assert_eq!(
        corners(&load_in(&doc, Units::User, 1.0)),
        [0.0, -10.0, 10.0, 0.0]
    );
    // the root viewport's px: the viewBox is shown twice as large
    assert_eq!(
        corners(&load_in(&doc, Units::Px, 1.0)),
        [0.0, -20.0, 20.0, 0.0]
    );
}

#[test]
fn a_drawing_in_millimetres_keeps_its_numbers() {
    let doc = doc(
        r#"width="210mm" height="297mm" viewBox="0 0 210 297""#,
        r#"<rect x="10" y="20" width="100" height="50"/><circle cx="105" cy="148.5" r="30"/>"#,
    );
    let mm = load_in(&doc, Units::User, 1.0);
    assert_eq!(
        bbox_of(&mm.shapes[0]),
        kurbo::Rect::new(10.0, -70.0, 110.0, -20.0)
    );
    let c = bbox_of(&mm.shapes[1]);
    assert!(close(c.center(), Point::new(105.0, -148.5)) && (c.width() - 60.0).abs() < 1e-5);
    // px: 96 px per inch, 25.4 mm per inch (usvg maps in f32)
    let px = load_in(&doc, Units::Px, 1.0);
    let px_per_mm = 96.0 / 25.4;
    let r = bbox_of(&px.shapes[0]);
    assert!((r.width() / 100.0 / px_per_mm - 1.0).abs() < 1e-6, "{r:?}");
    assert!((r.x0 / 10.0 / px_per_mm - 1.0).abs() < 1e-6, "{r:?}");
}

#[test]
fn viewbox_origin_and_aspect_are_undone() {
    let body = r#"<rect x="-40" y="30" width="60" height="100"/>"#;
    // the viewBox's numbers, whatever its origin, aspect and alignment
    for aspect in [
        "none",
        "xMidYMid meet",
        "xMinYMax slice",
        "xMaxYMin",
        "xMidYMid slice",
    ] {
        let doc = doc(
            &format!(
                r#"width="300" height="100" viewBox="-50 20 100 200" preserveAspectRatio="{aspect}""#
            ),
            body,
        );
        let d = load_in(&doc, Units::User, 1.0);
        assert_eq!(corners(&d), [-40.0, -130.0, 20.0, -30.0], "{aspect}");
    }
    // `none` stretches x by 3 and y by 1/2
    let stretched = doc(
        r#"width="300" height="100" viewBox="-50 20 100 200" preserveAspectRatio="none""#,
        body,
    );
    assert_eq!(
        corners(&load_in(&stretched, Units::Px, 1.0)),
        [30.0, -55.0, 210.0, -5.0]
    );
    // the default xMidYMid meet: factor 1/2, the 50 px wide box centred in 300 px
    let meet = doc(r#"width="300" height="100" viewBox="-50 20 100 200""#, body);
    assert_eq!(
        corners(&load_in(&meet, Units::Px, 1.0)),
        [130.0, -55.0, 160.0, -5.0]
    );
}

#[test]
fn without_a_viewbox_user_units_are_px() {
    for attrs in [
        r#"width="100mm" height="50mm""#,
        r#"width="300" height="100""#,
        "",
    ] {
        let doc = doc(attrs, r#"<rect x="5" y="5" width="10" height="20"/>"#);
        let user = load_in(&doc, Units::User, 1.0);
        assert_eq!(user, load_in(&doc, Units::Px, 1.0), "{attrs}");
        assert_eq!(corners(&user), [5.0, -25.0, 15.0, -5.0], "{attrs}");
    }
}

#[test]
fn viewbox_without_size_only_loses_its_translation() {
    let doc = doc(
        r#"viewBox="100 200 50 50""#,
        r#"<rect x="110" y="210" width="10" height="10"/>"#,
    );
    assert_eq!(
        corners(&load_in(&doc, Units::User, 1.0)),
        [110.0, -220.0, 120.0, -210.0]
    );
    assert_eq!(
        corners(&load_in(&doc, Units::Px, 1.0)),
        [10.0, -20.0, 20.0, -10.0]
    );
}

#[test]
fn nested_svg_use_and_root_transform_keep_their_own_transforms() {
    let doc = doc(
        r##"xmlns:xlink="http://www.w3.org/1999/xlink" width="200" height="200" viewBox="0 0 100 100""##,
        r##"<svg x="10" y="10" width="20" height="20" viewBox="0 0 10 10"><rect width="10" height="10"/></svg>
            <defs><rect id="r" width="5" height="5"/></defs>
            <use xlink:href="#r" x="50" y="60" transform="scale(0.5)"/>"##,
    );
    let d = load_in(&doc, Units::User, 1.0);
    assert_eq!(
        bbox_of(&d.shapes[0]),
        kurbo::Rect::new(10.0, -30.0, 30.0, -10.0)
    );
    assert_eq!(
        bbox_of(&d.shapes[1]),
        kurbo::Rect::new(25.0, -32.5, 27.5, -30.0)
    );
    let px = load_in(&doc, Units::Px, 1.0);
    assert_eq!(
        bbox_of(&px.shapes[0]),
        kurbo::Rect::new(20.0, -60.0, 60.0, -20.0)
    );
    // a transform on the root <svg> acts on the viewport (SVG 2): 10 px are 5 user units
    let moved = doc.replacen(
        "width=\"200\"",
        "transform=\"translate(10 0)\" width=\"200\"",
        1,
    );
    let d = load_in(&moved, Units::User, 1.0);
    assert_eq!(
        bbox_of(&d.shapes[0]),
        kurbo::Rect::new(15.0, -30.0, 35.0, -10.0)
    );
}

#[test]
fn scale_multiplies_every_coordinate() {
    let doc = doc(
        r#"width="210mm" height="297mm" viewBox="0 0 210 297""#,
        r#"<path d="M 10 20 C 30 0 60 90 110 20 Z"/>"#,
    );
    let one = load_in(&doc, Units::User, 1.0);
    let two = load_in(&doc, Units::User, 2.0);
    assert_eq!(corners(&two), corners(&one).map(|v| 2.0 * v));
    for (a, b) in one.features.iter().zip(&two.features) {
        match (a.geom, b.geom) {
            (FeatureGeom::Cubic(a), FeatureGeom::Cubic(b)) => {
                assert_eq!(b.p1, Point::new(2.0 * a.p1.x, 2.0 * a.p1.y));
            }
            (FeatureGeom::Line(a), FeatureGeom::Line(b)) => {
                assert_eq!(b.p0, Point::new(2.0 * a.p0.x, 2.0 * a.p0.y));
            }
            other => panic!("{other:?}"),
        }
    }
    let px = load_in(&doc, Units::Px, 0.5);
    assert!((px.bbox.width() * 2.0 * 25.4 / 96.0 - one.bbox.width()).abs() < 1e-4);
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = load_bytes(doc.as_bytes(), &LoadOptions::DEFAULT.with_scale(bad)).unwrap_err();
        assert!(matches!(e, Error::InvalidParams(_)), "{bad}: {e}");
    }
}

#[test]
fn coordinates_are_checked_after_units_and_scale() {
    // 1e12 user units fit, 1e4 times that does not
    let doc = doc(
        r#"width="1" height="1" viewBox="0 0 1e12 1e12""#,
        r#"<rect width="1e12" height="1e12"/>"#,
    );
    load_in(&doc, Units::User, 1.0);
    let e = load_bytes(doc.as_bytes(), &LoadOptions::DEFAULT.with_scale(1e4)).unwrap_err();
    assert!(matches!(e, Error::BadCoordinate(_)), "{e}");
    // a viewport mapping that underflows f32 cannot be undone: a clear error in
    // user units, and in px too
    let tiny = doc.replace(r#"viewBox="0 0 1e12 1e12""#, r#"viewBox="0 0 3e38 3e38""#);
    let tiny = tiny.replace(
        r#"width="1e12" height="1e12""#,
        r#"width="1e38" height="1e38""#,
    );
    let tiny = tiny.replace(r#"width="1" height="1""#, r#"width="1e-9" height="1e-9""#);
    let e = load_bytes(tiny.as_bytes(), &LoadOptions::DEFAULT).unwrap_err();
    assert!(e.to_string().contains("root viewBox"), "{e}");
    assert!(matches!(e, Error::BadCoordinate(_)), "{e}");
    // in px the drawing collapses to a point
    let px = load_in(&tiny, Units::Px, 1.0);
    assert_eq!(px.bbox.area(), 0.0);
}

mod duplicates;
mod exact;

#[test]
fn messages_say_why_there_is_nothing_to_mesh() {
    // a root <svg> in another namespace is named as such (not "<svg>, not <svg>")
    let e =
        load_err(r#"<svg xmlns="http://example.com/not-svg"><rect width="1" height="1"/></svg>"#);
    let msg = e.to_string();
    assert!(
        msg.contains("namespace 'http://example.com/not-svg'") && msg.contains(SVG_NS_FOR_TESTS),
        "{msg}"
    );
    // a drawing that holds only a raster image says so
    let e = load_err(
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><image width="10" height="10" href="data:image/png;base64,iVBORw0KGgo="/></svg>"#,
    );
    assert!(matches!(e, Error::NoGeometry(_)), "{e}");
    assert!(e.to_string().contains("image"), "{e}");
    // nothing at all: the plain message
    let e = load_err(r#"<svg xmlns="http://www.w3.org/2000/svg"/>"#);
    assert_eq!(
        e.to_string(),
        "no geometry: the drawing has no paths, shapes or points to mesh"
    );
}

const SVG_NS_FOR_TESTS: &str = "http://www.w3.org/2000/svg";
