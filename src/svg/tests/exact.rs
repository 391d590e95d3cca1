//! f64 geometry from the document's text at the loader: exact conics, exact transforms, agreement with usvg, fallbacks.

use super::*;
use crate::svg::drawing::Conic;
use crate::svg::reconstruct::MARKER;
use kurbo::{Affine, Vec2};
use std::f64::consts::{FRAC_1_SQRT_2, PI};

/// Load `body` in a 100×100 document (user units), with the precision report.
fn load_p(body: &str) -> (Drawing, Precision) {
    load_outlines(svg(body).as_bytes(), Units::User, 1.0).expect("test SVG loads")
}

/// Load and require every path to come out in f64.
fn load_exact(doc: &str) -> Drawing {
    let (d, p) = load_outlines(doc.as_bytes(), Units::User, 1.0).expect("test SVG loads");
    assert_eq!(p.fallbacks(), 0, "{p:?} {:?}", d.warnings);
    assert_eq!(p.exact, painted(&d), "{p:?}");
    d
}

/// The shapes that are not clip outlines (a nested `<svg>` or `<symbol>` clips
/// its content to its viewport: its outline comes after the painted shapes).
fn painted(d: &Drawing) -> usize {
    d.shapes
        .iter()
        .filter(|s| s.paint.kind != crate::svg::drawing::ShapeKind::ClipOutline)
        .count()
}

fn all_conics(d: &Drawing) -> Vec<Conic> {
    d.shapes
        .iter()
        .flat_map(|s| &s.subpaths)
        .flat_map(|s| &s.segments)
        .filter_map(|s| match s {
            Segment::Conic(c) => Some(*c),
            _ => None,
        })
        .collect()
}

/// The largest deviation of `conics` (sampled) from the ellipse with centre `c`,
/// radii `r` and x-axis rotation `phi` (radians), in output coordinates (y up),
/// as |implicit equation| (a relative radial error).
fn ellipse_error(conics: &[Conic], c: Point, r: Vec2, phi: f64) -> f64 {
    let to_unit = Affine::scale_non_uniform(1.0 / r.x, 1.0 / r.y) * Affine::rotate(-phi);
    let mut worst = 0.0_f64;
    for k in conics {
        // translate first (exact for these inputs), then evaluate: the error measured
        // is the curve's, not the evaluation's rounding at a large offset
        let local = k.transform(Affine::translate(-c.to_vec2()));
        for i in 0..=64 {
            let q = to_unit * local.eval(f64::from(i) / 64.0);
            worst = worst.max((q.to_vec2().hypot() - 1.0).abs());
        }
    }
    worst
}

#[test]
fn a_unit_circle_far_from_the_origin_is_exact() {
    let doc = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 2000002 2000002"><circle cx="1000000" cy="1000000" r="1"/></svg>"#;
    let d = load_exact(doc);
    let k = all_conics(&d);
    assert_eq!(k.len(), 4);
    // the document's numbers, exactly: (1e6 + 1, -1e6) first, then (1e6, -1e6 - 1)
    // (SVG's y-down (cx, cy + r), flipped)
    let (c, r) = (1e6, 1.0);
    assert_eq!(k[0].p0, Point::new(c + r, -c));
    assert_eq!(k[0].p1, Point::new(c + r, -c - r));
    assert_eq!(k[0].p2, Point::new(c, -c - r));
    assert!(k.iter().all(|q| q.w == FRAC_1_SQRT_2));
    for q in &k {
        for i in 0..=64 {
            let p = q.eval(f64::from(i) / 64.0);
            let radial = ((p - Point::new(c, -c)).hypot() - r).abs();
            assert!(radial <= 1e-15 * c, "radial error {radial:e} at {p:?}");
        }
    }
    let err = ellipse_error(&k, Point::new(c, -c), Vec2::new(r, r), 0.0);
    assert!(err < 1e-15, "{err:e}");
}

/// The radial error of the loaded circle's points at (1e6, 1e6): usvg's f32
/// cubics (its absolute transform applied in f64) against the loader's conics.
#[test]
#[allow(clippy::print_stderr, reason = "the measurement is the test's report")]
fn circle_at_a_million_radial_error_before_and_after() {
    let doc = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 2000002 2000002"><circle cx="1000000" cy="1000000" r="1"/></svg>"#;
    let centre = Point::new(1e6, 1e6);
    let tree = usvg::Tree::from_str(doc, &usvg::Options::default()).expect("usvg parses");
    let mut before = 0.0_f64;
    let mut nodes: Vec<&usvg::Node> = tree.root().children().iter().collect();
    while let Some(node) = nodes.pop() {
        match node {
            usvg::Node::Group(g) => nodes.extend(g.children()),
            usvg::Node::Path(p) => {
                let t = p.abs_transform();
                let m = Affine::new([t.sx, t.ky, t.kx, t.sy, t.tx, t.ty].map(f64::from));
                let pt =
                    |q: usvg::tiny_skia_path::Point| m * Point::new(f64::from(q.x), f64::from(q.y));
                let mut pen = Point::ORIGIN;
                for seg in p.data().segments() {
                    use usvg::tiny_skia_path::PathSegment as S;
                    match seg {
                        S::MoveTo(q) | S::LineTo(q) => pen = pt(q),
                        S::CubicTo(a, b, q) => {
                            let c = kurbo::CubicBez::new(pen, pt(a), pt(b), pt(q));
                            for i in 0..=64 {
                                let r = (c.eval(f64::from(i) / 64.0) - centre).hypot();
                                before = before.max((r - 1.0).abs());
                            }
                            pen = c.p3;
                        }
                        _ => {}
                    }
                }
            }
            _ => {}
        }
    }
    let d = load_exact(doc);
    let k = all_conics(&d);
    let after = ellipse_error(&k, Point::new(1e6, -1e6), Vec2::new(1.0, 1.0), 0.0);
    eprintln!("unit circle at (1e6, 1e6): max radial error before {before:e}, after {after:e}");
    assert!(before > 1e-4, "{before:e}");
    assert!(after < 1e-15, "{after:e}");
}

#[test]
fn ellipses_and_rounded_rects_are_exact_conics() {
    let d = load_exact(&svg(r#"<ellipse cx="30.1" cy="40.7" rx="20.3" ry="7.9"/>
           <rect x="10.5" y="20.25" width="50" height="30" rx="5.5" ry="4.1"/>"#));
    let ellipse = all_conics(&Drawing {
        shapes: vec![d.shapes[0].clone()],
        ..d.clone()
    });
    assert_eq!(ellipse.len(), 4);
    let err = ellipse_error(&ellipse, Point::new(30.1, -40.7), Vec2::new(20.3, 7.9), 0.0);
    assert!(err < 4e-15, "ellipse {err:e}");
    // SVG's start and direction: (cx + rx, cy), then (cx, cy + ry) (y flipped)
    assert_eq!(ellipse[0].p0, Point::new(30.1 + 20.3, -40.7));
    assert_eq!(ellipse[0].p2, Point::new(30.1, -(40.7 + 7.9)));
    // the rect: 4 lines, 4 quarter ellipses of radii (5.5, 4.1) about the corners' centres
    let sub = &d.shapes[1].subpaths[0];
    assert_eq!(count(sub), (4, 4));
    let (x0, y0, x1, y1) = (10.5, 20.25, 60.5, 50.25);
    let centres = [
        (x1 - 5.5, y0 + 4.1),
        (x1 - 5.5, y1 - 4.1),
        (x0 + 5.5, y1 - 4.1),
        (x0 + 5.5, y0 + 4.1),
    ];
    let corners: Vec<Conic> = sub
        .segments
        .iter()
        .filter_map(|s| match s {
            Segment::Conic(c) => Some(*c),
            _ => None,
        })
        .collect();
    for (k, (cx, cy)) in corners.iter().zip(centres) {
        let err = ellipse_error(&[*k], Point::new(cx, -cy), Vec2::new(5.5, 4.1), 0.0);
        assert!(err < 1e-14, "corner {err:e}");
    }
    // starts at (x + rx, y), as usvg does
    assert_eq!(sub.start, Point::new(x0 + 5.5, -y0));
}

#[test]
fn rect_radii_follow_svg_rules() {
    // only rx: ry = rx; rx beyond half the width: clamped; negative: ignored (auto)
    let d = load_exact(&svg(r#"<rect width="10" height="40" rx="3"/>
           <rect width="10" height="40" rx="30" ry="2"/>
           <rect width="10" height="40" rx="-3" ry="2"/>
           <rect width="10" height="40" rx="0" ry="2"/>
           <rect width="10" height="40" rx="2" ry="0"/>"#));
    let radii = |i: usize| {
        let k = all_conics(&Drawing {
            shapes: vec![d.shapes[i].clone()],
            ..d.clone()
        });
        k.first()
            .map(|c| ((c.p1.x - c.p0.x).abs(), (c.p2.y - c.p1.y).abs()))
    };
    assert_eq!(radii(0), Some((3.0, 3.0)));
    assert_eq!(radii(1), Some((5.0, 2.0)));
    assert_eq!(radii(2), Some((2.0, 2.0)));
    // a zero radius: a plain rectangle (4 lines)
    assert_eq!(radii(3), None);
    assert_eq!(count(&d.shapes[3].subpaths[0]), (4, 0));
    assert_eq!(radii(4), None);
}

/// A point of the ellipse (centre `c`, radii `r`, rotation `phi`) at parameter
/// `theta`, in SVG coordinates.
fn on_ellipse(c: Point, r: Vec2, phi: f64, theta: f64) -> Point {
    c + (Affine::rotate(phi) * Point::new(r.x * theta.cos(), r.y * theta.sin())).to_vec2()
}

#[test]
fn arcs_keep_flags_rotation_and_their_ellipse() {
    let c = Point::new(40.0, 30.0);
    let r = Vec2::new(25.0, 10.0);
    let phi_deg: f64 = 30.0;
    let phi = phi_deg.to_radians();
    let (a, b) = (on_ellipse(c, r, phi, 0.3), on_ellipse(c, r, phi, 2.0));
    for (large, sweep) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
        let body = format!(
            r#"<path d="M {:?} {:?} A {} {} {phi_deg} {large} {sweep} {:?} {:?}" fill="none" stroke="black"/>"#,
            a.x, a.y, r.x, r.y, b.x, b.y
        );
        let d = load_exact(&svg(&body));
        let k = all_conics(&d);
        // the centre: c for the short positive arc and the long negative one, its
        // mirror image through the chord's midpoint for the other two. Going from a
        // to b the short way (1.7 rad) about c is SVG's positive direction (y down);
        // y is flipped on output, where a positive SVG sweep is negative.
        let centre = if large != sweep {
            c
        } else {
            (a.to_vec2() + b.to_vec2() - c.to_vec2()).to_point()
        };
        let o = Point::new(centre.x, -centre.y);
        let span: f64 = k
            .iter()
            .flat_map(|q| {
                (0..16).map(move |i| (q.eval(f64::from(i) / 16.0), q.eval(f64::from(i + 1) / 16.0)))
            })
            .map(|(p, q)| {
                let (u, v) = (p - o, q - o);
                u.cross(v).atan2(u.dot(v))
            })
            .sum();
        let (expect_large, expect_svg_positive) = (large == 1, sweep == 1);
        assert_eq!(span.abs() > PI, expect_large, "{body}: span {span}");
        assert_eq!(span < 0.0, expect_svg_positive, "{body}: span {span}");
        let err = ellipse_error(&k, o, r, -phi);
        assert!(err < 1e-14, "{body}: {err:e}");
        // ends exactly the document's
        assert_eq!(k[0].p0, Point::new(a.x, -a.y));
        assert_eq!(k.last().map(|q| q.p2), Some(Point::new(b.x, -b.y)));
        assert!(k.len() <= 4);
    }
}

#[test]
fn arc_radii_too_small_scale_up_and_zero_radii_are_lines() {
    // radius 1 cannot reach from (0, 50) to (10, 50): scaled to 5, a half circle
    let d = load_exact(&svg(
        r#"<path d="M 0 50 A 1 1 0 0 1 10 50" fill="none" stroke="black"/>
           <path d="M 0 50 A 0 3 0 0 1 10 50" fill="none" stroke="black"/>
           <path d="M 0 0 a 1e-7 1e-7 0 0 0 2e-7 0" fill="none" stroke="black"/>"#,
    ));
    let half = all_conics(&Drawing {
        shapes: vec![d.shapes[0].clone()],
        ..d.clone()
    });
    assert_eq!(half.len(), 2);
    let err = ellipse_error(&half, Point::new(5.0, -50.0), Vec2::new(5.0, 5.0), 0.0);
    assert!(err < 4e-15, "{err:e}");
    assert_eq!(count(&d.shapes[1].subpaths[0]), (1, 0));
    // a radius below kurbo's 1e-5 threshold is still an arc, not a line
    let tiny = all_conics(&Drawing {
        shapes: vec![d.shapes[2].clone()],
        ..d.clone()
    });
    assert_eq!(tiny.len(), 2);
    let err = ellipse_error(&tiny, Point::new(1e-7, 0.0), Vec2::new(1e-7, 1e-7), 0.0);
    assert!(err < 4e-15, "{err:e}");
}

#[test]
fn degenerate_arcs_never_panic() {
    // (a chord of 1e-200 under radius 1 trips a debug assertion in usvg's own
    // arc conversion, before ours runs: `arc_pieces` is tested on it directly)
    for d in [
        "M 0 0 A 1e-300 1e-300 0 1 1 1e-300 0",
        "M 0 0 A 3e38 3e38 0 1 1 1 0",
        "M 0 0 A 1 1 0 0 1 0 0 L 5 5",
    ] {
        let (drawing, p) = load_outlines(
            svg(&format!(
                r#"<path d="{d}" stroke="black"/><rect width="1" height="1"/>"#
            ))
            .as_bytes(),
            Units::User,
            1.0,
        )
        .expect("loads");
        assert_sane(&drawing, d);
        assert_eq!(p.exact + p.fallbacks(), drawing.shapes.len(), "{d}: {p:?}");
    }
}

#[test]
fn transforms_apply_exactly_in_f64() {
    let d = load_exact(&svg(
        r#"<g transform="translate(0.1)"><rect x="1" y="0.2" width="2" height="3"/></g>"#,
    ));
    // usvg's f32 gives 1.1f32 = 1.100000023841858
    assert_eq!(d.bbox.x0, 1.0 + 0.1);
    assert_eq!(d.bbox.y1, -0.2);
    assert_eq!(d.bbox.x1, 3.0 + 0.1);
}

#[test]
fn use_nested_svg_symbol_and_chains_agree_with_usvg_and_are_exact() {
    let doc = r##"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="200" height="200" viewBox="0 0 100 100">
        <defs>
          <g id="g"><rect x="0.1" width="1" height="1"/><circle cx="0.3" cy="0.3" r="0.25"/></g>
          <symbol id="s" viewBox="0 0 10 10"><rect width="10" height="10" rx="1"/></symbol>
        </defs>
        <g transform="translate(10 20) scale(0.5)">
          <use id="u1" xlink:href="#g" x="4" y="8"/>
          <use xlink:href="#u1" transform="translate(0.1 0.2)"/>
          <use href="#s" x="40" y="40" width="20" height="40"/>
          <svg x="60" y="60" width="40" height="20" viewBox="0 0 4 4" preserveAspectRatio="xMinYMin meet">
            <rect width="4" height="4"/>
          </svg>
        </g>
        <use href="#g" transform="rotate(30) skewX(10)"/>
      </svg>"##;
    let d = load_exact(doc);
    assert_eq!(painted(&d), 8);
    let bb = |i: usize| bbox_of(&d.shapes[i]);
    // g through u1: translate(10 20) scale(0.5) translate(4 8): x = 10 + (0.1 + 4) / 2
    assert_eq!(bb(0).x0, 10.0 + (0.1 + 4.0) * 0.5);
    // u1 again through the second use: + translate(0.1 0.2) (scaled by 0.5)
    // (composed in another order here: equal up to rounding)
    assert!((bb(2).x0 - (10.0 + (0.1 + (0.1 + 4.0)) * 0.5)).abs() < 1e-14);
    // the symbol: viewBox 10×10 into 20×40 (meet: factor 2, centred vertically)
    let sym = bb(4);
    assert_eq!((sym.width(), sym.height()), (10.0, 10.0));
    assert_eq!(sym.x0, 10.0 + 40.0 * 0.5);
    assert_eq!(sym.y1, -(20.0 + (40.0 + 10.0) * 0.5));
    // the nested svg: 4×4 into 40×20 at the top left: factor 5
    let nested = bb(5);
    assert_eq!((nested.width(), nested.height()), (10.0, 10.0));
    assert_eq!((nested.x0, nested.y1), (10.0 + 30.0, -(20.0 + 30.0)));
    // the names: u1 names its anonymous shapes, private ids never show
    assert_eq!(d.shapes[0].svg_id.as_deref(), Some("u1"));
    assert_eq!(d.shapes[4].svg_id, None);
    assert!(d.shapes[4].name().starts_with("shape-"));
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
}

#[test]
fn duplicated_ids_are_told_apart_by_their_geometry() {
    let (d, p) = load_p(
        r#"<rect id="a" x="1" width="1" height="1"/><rect id="a" x="5" width="2" height="1"/>"#,
    );
    assert_eq!(p.exact, 2, "{p:?}");
    assert_eq!(bbox_of(&d.shapes[1]).x0, 5.0);
    assert_eq!(d.shapes[1].svg_id.as_deref(), Some("a"));
}

#[test]
fn unsupported_cases_fall_back_once_with_a_warning() {
    let (d, p) = load_p(
        r#"<rect x="10%" width="5" height="5"/><rect x="1em" width="5" height="5"/>
           <rect style="transform: translate(3)" width="5" height="5"/>"#,
    );
    assert_eq!(p.exact, 0);
    assert_eq!(p.fallbacks(), 3, "{p:?}");
    assert_eq!(d.warnings.len(), 1, "{:?}", d.warnings);
    assert!(d.warnings[0].contains("3 of 3 path(s)"), "{:?}", d.warnings);
    // usvg's geometry is kept: 10% of 100 is 10
    assert!((bbox_of(&d.shapes[0]).x0 - 10.0).abs() < 1e-5);
    // the CSS transform shifts the shape
    assert!((bbox_of(&d.shapes[2]).x0 - 3.0).abs() < 1e-5);
}

#[test]
fn markers_and_glyphs_keep_single_precision_silently() {
    let (d, p) = load_p(
        r##"<defs><marker id="m" markerWidth="4" markerHeight="4"><circle cx="2" cy="2" r="2"/></marker></defs>
            <path d="M 10 10 L 50 50" stroke="black" marker-end="url(#m)"/>"##,
    );
    assert_eq!(p.exact, 1, "{p:?}");
    assert_eq!(p.fallback.get(MARKER), Some(&1), "{p:?}");
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
}

#[test]
fn px_units_map_the_root_viewbox_in_f64() {
    let doc = r#"<svg xmlns="http://www.w3.org/2000/svg" width="210mm" height="297mm"
        viewBox="0 0 210 297"><rect x="10" y="20" width="100" height="50"/></svg>"#;
    let (d, p) = load_outlines(doc.as_bytes(), Units::Px, 1.0).expect("loads");
    assert_eq!(p.exact, 1);
    let px_per_mm = 96.0 / 25.4;
    let w = d.bbox.width();
    assert!((w / (100.0 * px_per_mm) - 1.0).abs() < 1e-14, "{w}");
    let (d, _) = load_outlines(doc.as_bytes(), Units::User, 1.0).expect("loads");
    assert_eq!(d.bbox, kurbo::Rect::new(10.0, -70.0, 110.0, -20.0));
}

mod property {
    use super::*;
    use proptest::prelude::*;

    fn config() -> ProptestConfig {
        ProptestConfig {
            cases: 96,
            failure_persistence: None,
            rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
            ..ProptestConfig::default()
        }
    }

    /// A number as a document writes it: a few decimals, sometimes an integer or 0.
    fn num() -> impl Strategy<Value = String> {
        prop_oneof![
            (-600i32..600).prop_map(|v| format!("{}", f64::from(v) / 10.0)),
            (-80i32..80).prop_map(|v| format!("{v}")),
            Just("0".to_owned()),
        ]
    }

    fn radius() -> impl Strategy<Value = String> {
        prop_oneof![
            (0i32..400).prop_map(|v| format!("{}", f64::from(v) / 10.0)),
            Just("0".to_owned()),
        ]
    }

    /// One path command (relative or absolute) with its arguments.
    fn command() -> impl Strategy<Value = String> {
        let pt = || (num(), num()).prop_map(|(x, y)| format!("{x} {y}"));
        let cmd = |c: &'static str| prop_oneof![Just(c.to_owned()), Just(c.to_lowercase())];
        prop_oneof![
            (cmd("M"), pt()).prop_map(|(c, p)| format!("{c} {p}")),
            (cmd("L"), pt()).prop_map(|(c, p)| format!("{c} {p}")),
            (cmd("H"), num()).prop_map(|(c, p)| format!("{c} {p}")),
            (cmd("V"), num()).prop_map(|(c, p)| format!("{c} {p}")),
            (cmd("C"), pt(), pt(), pt()).prop_map(|(c, a, b, p)| format!("{c} {a} {b} {p}")),
            (cmd("S"), pt(), pt()).prop_map(|(c, a, p)| format!("{c} {a} {p}")),
            (cmd("Q"), pt(), pt()).prop_map(|(c, a, p)| format!("{c} {a} {p}")),
            (cmd("T"), pt()).prop_map(|(c, p)| format!("{c} {p}")),
            (
                cmd("A"),
                radius(),
                radius(),
                -360i32..360,
                any::<bool>(),
                any::<bool>(),
                pt()
            )
                .prop_map(|(c, rx, ry, rot, l, s, p)| {
                    format!("{c} {rx} {ry} {rot} {} {} {p}", u8::from(l), u8::from(s))
                }),
            Just("Z".to_owned()),
        ]
    }

    /// A non-degenerate transform.
    fn transform() -> impl Strategy<Value = String> {
        let factor = prop_oneof![
            (1i32..40).prop_map(|v| f64::from(v) / 10.0),
            (1i32..40).prop_map(|v| -f64::from(v) / 10.0)
        ];
        prop_oneof![
            (num(), num()).prop_map(|(x, y)| format!("translate({x} {y})")),
            (factor.clone(), factor).prop_map(|(x, y)| format!("scale({x} {y})")),
            (-360i32..360, num(), num()).prop_map(|(a, x, y)| format!("rotate({a} {x} {y})")),
            (-60i32..60).prop_map(|a| format!("skewX({a})")),
            (-60i32..60).prop_map(|a| format!("skewY({a})")),
        ]
    }

    /// A basic shape with random (sometimes zero, negative or clamped) sizes and radii.
    fn basic_shape() -> impl Strategy<Value = String> {
        prop_oneof![
            (
                num(),
                num(),
                radius(),
                radius(),
                proptest::option::of(radius()),
                proptest::option::of(num())
            )
                .prop_map(|(x, y, w, h, rx, ry)| {
                    let rx = rx.map_or(String::new(), |v| format!(r#" rx="{v}""#));
                    let ry = ry.map_or(String::new(), |v| format!(r#" ry="{v}""#));
                    format!(r#"<rect x="{x}" y="{y}" width="{w}" height="{h}"{rx}{ry}/>"#)
                }),
            (num(), num(), radius())
                .prop_map(|(x, y, r)| format!(r#"<circle cx="{x}" cy="{y}" r="{r}"/>"#)),
            (num(), num(), radius(), radius()).prop_map(|(x, y, rx, ry)| format!(
                r#"<ellipse cx="{x}" cy="{y}" rx="{rx}" ry="{ry}"/>"#
            )),
            (num(), num(), num(), num()).prop_map(|(a, b, c, d)| format!(
                r#"<line x1="{a}" y1="{b}" x2="{c}" y2="{d}" stroke="black"/>"#
            )),
            proptest::collection::vec((num(), num()), 1..6).prop_map(|pts| {
                let pts: Vec<String> = pts.iter().map(|(x, y)| format!("{x},{y}")).collect();
                format!(r#"<polygon points="{}"/>"#, pts.join(" "))
            }),
        ]
    }

    proptest! {
        #![proptest_config(config())]

        /// Random basic shapes under random transforms: reconstructed, never a fallback.
        #[test]
        fn random_basic_shapes_are_reconstructed(
            shapes in proptest::collection::vec(basic_shape(), 1..5),
            outer in proptest::collection::vec(transform(), 0..3),
        ) {
            let body = format!(r#"<g transform="{}">{}</g>"#, outer.join(" "), shapes.join(""));
            match load_outlines(svg(&body).as_bytes(), Units::User, 1.0) {
                Ok((drawing, p)) => {
                    prop_assert_eq!(p.fallbacks(), 0, "{} {:?} {:?}", body, p, drawing.warnings);
                    prop_assert_eq!(p.exact, drawing.shapes.len());
                }
                Err(e) => prop_assert!(matches!(e, Error::NoGeometry(_)), "{}: {}", body, e),
            }
        }

        /// Random paths under random transform chains (groups, a `<use>` with x/y,
        /// a nested `<svg>`): the f64 reconstruction agrees with usvg (the loader
        /// validates it) and no path falls back.
        #[test]
        fn random_paths_and_transforms_are_reconstructed(
            start in (num(), num()),
            commands in proptest::collection::vec(command(), 1..12),
            outer in proptest::collection::vec(transform(), 0..3),
            inner in transform(),
            via_use in any::<bool>(),
            use_at in (num(), num()),
            in_svg in any::<bool>(),
        ) {
            let d = format!("M {} {} {}", start.0, start.1, commands.join(" "));
            let path = format!(r#"<path id="p" d="{d}" fill="none" stroke="black" transform="{inner}"/>"#);
            let shape = if via_use {
                format!(r##"<defs>{path}</defs><use href="#p" x="{}" y="{}"/>"##, use_at.0, use_at.1)
            } else {
                path
            };
            let shape = if in_svg {
                format!(r#"<svg x="3" y="-2" width="50" height="70" viewBox="-10 -10 100 100" preserveAspectRatio="xMaxYMid slice">{shape}</svg>"#)
            } else {
                shape
            };
            let body = format!(r#"<g transform="{}">{shape}</g>"#, outer.join(" "));
            let doc = format!(r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">{body}</svg>"#);
            match load_outlines(doc.as_bytes(), Units::User, 1.0) {
                Ok((drawing, p)) => {
                    prop_assert_eq!(p.fallbacks(), 0, "{} {:?} {:?}", doc, p, drawing.warnings);
                    prop_assert_eq!(p.exact, drawing.shapes.len());
                }
                // a path that is only a move, or collapses to nothing: no geometry
                Err(e) => prop_assert!(matches!(e, Error::NoGeometry(_)), "{}: {}", doc, e),
            }
        }
    }
}
