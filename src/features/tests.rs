//! Analytic cases and the property test of the FeatureSet invariants, checked by an
//! independent checker ([`check`]: its own Bézier evaluation and distances, dense sampling).

use super::*;
use crate::params::{Length, Params};
use crate::svg::drawing::Conic;
use crate::svg::{Feature, ShapeId};
use kurbo::{Rect, Vec2};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;
use std::f64::consts::{FRAC_PI_2, PI};

#[path = "../../tests/support/features_check.rs"]
pub(crate) mod features_check;
use features_check::{bez, bez_d, bez_dd, check};

// ---------- drawings built in code ----------

fn drawing(geoms: Vec<FeatureGeom>) -> Drawing {
    let mut bbox: Option<Rect> = None;
    let mut features = Vec::new();
    for (k, g) in geoms.into_iter().enumerate() {
        let ps: Vec<Point> = match g {
            FeatureGeom::Point(p) => vec![p],
            FeatureGeom::Line(l) => vec![l.p0, l.p1],
            FeatureGeom::Cubic(c) => vec![c.p0, c.p1, c.p2, c.p3],
            FeatureGeom::Conic(c) => c.control_points().to_vec(),
        };
        for p in ps {
            bbox = Some(bbox.map_or(Rect::from_points(p, p), |b| b.union_pt(p)));
        }
        let source = FeatureSource {
            shape: ShapeId::from_index(0),
            subpath: 0,
            segment: k as u32,
        };
        features.push(Feature { geom: g, source });
    }
    Drawing {
        shapes: Vec::new(),
        features,
        bbox: bbox.expect("test drawing has a feature"),
        warnings: Vec::new(),
        precision: Default::default(),
        paint: Default::default(),
        view_box: None,
        cell: None,
    }
}

fn build(geoms: Vec<FeatureGeom>, params: Params) -> (FeatureSet, Drawing) {
    let d = drawing(geoms);
    let fs = FeatureSet::build(&d, &params.resolve(d.diagonal()));
    let defects = check(&fs);
    assert!(defects.is_empty(), "invariants broken: {defects:#?}");
    (fs, d)
}

const K: f64 = 0.552_284_749_830_793_4; // 4/3·(√2 − 1): the usual quarter-circle cubic

/// A circle as four cubics, starting at angle `phase`.
fn circle(c: Point, r: f64, phase: f64) -> Vec<FeatureGeom> {
    let q = std::f64::consts::FRAC_PI_2;
    let u: Vec<Vec2> = (0..4)
        .map(|k| Vec2::from_angle(phase + k as f64 * q))
        .collect();
    let perp = |u: Vec2| Vec2::new(-u.y, u.x);
    (0..4)
        .map(|k| {
            let (u0, u1) = (u[k], u[(k + 1) % 4]);
            // End points computed once, so consecutive cubics share them bit for bit.
            FeatureGeom::Cubic(CubicBez::new(
                c + u0 * r,
                c + (u0 + perp(u0) * K) * r,
                c + (u1 - perp(u1) * K) * r,
                c + u1 * r,
            ))
        })
        .collect()
}

fn line(a: (f64, f64), b: (f64, f64)) -> FeatureGeom {
    FeatureGeom::Line(Line::new(a, b))
}

fn cubic(p: [(f64, f64); 4]) -> FeatureGeom {
    FeatureGeom::Cubic(CubicBez::new(p[0], p[1], p[2], p[3]))
}

fn secondary_points(fs: &FeatureSet) -> Vec<Point> {
    fs.secondary
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .collect()
}

// ---------- analytic cases ----------

#[test]
fn circle_splits_land_at_sixteenths_and_all_is_primary() {
    // d = 2√2, l = d/20: each quarter (arc π/2) halves to 16 sections of ≈ 0.098 < l
    // (8 would be 0.196 > l); turn 5.6° < α; no inflection, turn 90° < 180°: no split.
    let (fs, _) = build(circle(Point::ZERO, 1.0, 0.0), Params::DEFAULT);
    assert_eq!(fs.primary.len(), 64);
    assert!(fs.secondary.is_empty() && fs.points.is_empty());
    assert_eq!(fs.counts.inflection_splits + fs.counts.curvature_splits, 0);
    for (i, s) in fs.primary.iter().enumerate() {
        assert_eq!(s.t, [(i % 16) as f64 / 16.0, (i % 16 + 1) as f64 / 16.0]);
        assert_eq!(s.source.segment, (i / 16) as u32);
        let n = fs.primary.len();
        assert_eq!(
            s.next,
            Some(SectionId::from_index((i + 1) % n)),
            "next of {i}"
        );
        assert_eq!(
            s.prev,
            Some(SectionId::from_index((i + n - 1) % n)),
            "prev of {i}"
        );
    }
    let ci = fs.conforming_input();
    assert_eq!(ci.segments.len(), 64);
    assert!(ci.points.is_empty());
}

#[test]
fn s_curve_is_cut_at_its_inflection() {
    for (c, t_infl) in [
        ([(0.0, 0.0), (1.0, 1.0), (2.0, -1.0), (3.0, 0.0)], 0.5),
        ([(0.0, 0.0), (1.0, 1.0), (2.0, -2.0), (3.0, 0.0)], 4.0 / 9.0),
    ] {
        let (fs, _) = build(vec![cubic(c)], Params::DEFAULT);
        assert_eq!(fs.counts.inflection_splits, 1);
        assert!(fs.secondary.is_empty());
        let cut = fs
            .primary
            .iter()
            .position(|s| (s.t[0] - t_infl).abs() < 1e-12);
        let cut = cut.expect("a section starts at the inflection");
        assert_eq!(fs.primary[cut - 1].t[1], fs.primary[cut].t[0]);
        // Curvature signs differ on the two sides.
        let sign = |s: &PrimarySection| {
            let c = [s.ctrl.p0, s.ctrl.p1, s.ctrl.p2, s.ctrl.p3];
            bez_d(&c, 0.5).cross(bez_dd(&c, 0.5)).signum()
        };
        assert_eq!(sign(&fs.primary[cut - 1]), -sign(&fs.primary[cut]));
    }
}

#[test]
fn loop_cubic_is_split_at_its_self_crossing() {
    let c = [(0.0, 0.0), (3.0, 2.0), (-1.0, 2.0), (2.0, 0.0)];
    let (fs, _) = build(vec![cubic(c)], Params::DEFAULT);
    assert!(fs.counts.curvature_splits >= 1, "{:?}", fs.counts);
    // The self-crossing is where x(t) = x(s), y(t) = y(s) for t ≠ s: by symmetry of this
    // curve about x = 1 it lies on x = 1; find it by bisection on t < 1/2.
    let cc = [c[0].into(), c[1].into(), c[2].into(), c[3].into()];
    let (mut lo, mut hi) = (0.0, 0.5);
    for _ in 0..60 {
        let m = 0.5 * (lo + hi);
        if bez(&cc, m).x < 1.0 { lo = m } else { hi = m }
    }
    let x = bez(&cc, lo);
    // The two pieces through it (from either side of the curvature split) cross at a
    // wide angle: both are split there, four sections share that point, all primary.
    assert_eq!(fs.counts.crossing_splits, 1, "{:?}", fs.counts);
    assert!(fs.secondary.is_empty(), "{:?}", fs.counts);
    let ends: Vec<Point> = fs
        .primary
        .iter()
        .flat_map(|s| [s.ctrl.p0, s.ctrl.p3])
        .filter(|p| p.distance(x) <= 1e-9)
        .collect();
    assert_eq!(ends.len(), 4, "{ends:?}");
    assert!(ends.iter().all(|p| *p == ends[0]));
}

#[test]
fn cusp_cubic_is_cut_at_the_cusp_and_secondary_around_it() {
    let (fs, _) = build(
        vec![cubic([(0.0, 0.0), (2.0, 2.0), (0.0, 2.0), (2.0, 0.0)])],
        Params::DEFAULT,
    );
    assert!(fs.counts.inflection_splits >= 1);
    let cusp = Point::new(1.0, 1.5);
    assert!(
        secondary_points(&fs)
            .iter()
            .any(|p| p.distance(cusp) <= fs.params.mu)
    );
    for s in &fs.primary {
        assert!(!(s.t[0] < 0.5 && s.t[1] > 0.5));
        assert!(
            s.ctrl.p0.distance(cusp) >= fs.params.mu && s.ctrl.p3.distance(cusp) >= fs.params.mu
        );
    }
    assert!(fs.primary.iter().any(|s| s.t[0] == 0.0) && fs.primary.iter().any(|s| s.t[1] == 1.0));
}

#[test]
fn degenerate_cubic_becomes_a_point() {
    let (fs, _) = build(
        vec![
            cubic([
                (1.0, 1.0),
                (1.0, 1.0 + 1e-12),
                (1.0 + 1e-12, 1.0),
                (1.0, 1.0),
            ]),
            line((0.0, 0.0), (5.0, 0.0)),
        ],
        Params::DEFAULT,
    );
    // Shorter than l_m: the snapping step already makes it a point.
    assert_eq!(fs.counts.degenerate + fs.counts.snap_collapsed, 1);
    assert_eq!(fs.points.len(), 1);
    assert!(fs.points[0].pos.distance(Point::new(1.0, 1.0)) < 1e-11);
    assert_eq!(fs.points[0].source.segment, 0);
}

#[test]
fn straight_cubic_becomes_a_segment() {
    let (fs, _) = build(
        vec![cubic([(0.0, 0.0), (1.0, 2.0), (2.0, 4.0), (3.0, 6.0)])],
        Params::DEFAULT,
    );
    assert_eq!(fs.counts.straight, 1);
    assert_eq!(fs.primary.len(), 20);
    for s in &fs.primary {
        assert_eq!(s.parent, Parent::Line(Line::new((0.0, 0.0), (3.0, 6.0))));
        let c = s.ctrl;
        assert!((c.p1 - c.p0).cross(c.p3 - c.p0).abs() < 1e-12);
        assert!((c.p2 - c.p0).cross(c.p3 - c.p0).abs() < 1e-12);
    }
}

fn abs_params(mu: f64, l: f64) -> Params {
    Params::DEFAULT
        .with_mu(Length::Abs(mu))
        .with_l(Length::Abs(l))
}

#[test]
fn parallel_lines_closer_than_mu_are_secondary_farther_primary() {
    let lines = |h| vec![line((0.0, 0.0), (10.0, 0.0)), line((0.0, h), (10.0, h))];
    let (near, _) = build(lines(0.05), abs_params(0.1, 1.0));
    assert!(near.primary.is_empty());
    // Both secondary, and the merge keeps one of the two (they are closer than μ).
    assert_eq!(near.counts.merged_segments, 10);
    assert_eq!(near.counts.secondary_segments, 10);
    assert_eq!(near.secondary.len(), 1);
    let (far, _) = build(lines(0.2), abs_params(0.1, 1.0));
    assert_eq!(far.primary.len(), 20);
    assert!(far.secondary.is_empty());
}

#[test]
fn crossing_lines_are_split_at_the_crossing_and_stay_primary() {
    // Line 1 is cut at its crossing (0.5, 0) and at integer x; line 2 at the crossing,
    // which is also where its integer-y cuts fall. All sections stay primary, and the
    // four around the crossing share its point exactly.
    let (fs, _) = build(
        vec![line((-5.0, 0.0), (5.0, 0.0)), line((0.5, -5.0), (0.5, 5.0))],
        abs_params(0.1, 1.0),
    );
    assert_eq!(fs.counts.crossing_splits, 1);
    assert!(fs.secondary.is_empty(), "{:?}", fs.counts);
    assert_eq!(fs.primary.len(), 21);
    let x = Point::new(0.5, 0.0);
    let ends = fs
        .primary
        .iter()
        .flat_map(|s| [s.ctrl.p0, s.ctrl.p3])
        .filter(|p| *p == x)
        .count();
    assert_eq!(ends, 4);
    // A shallow crossing (below 4α) is not split: it stays secondary near the crossing.
    let (shallow, _) = build(
        vec![
            line((-5.0, 0.0), (5.0, 0.0)),
            line((-5.0, -0.5), (5.0, 0.5)),
        ],
        abs_params(0.1, 1.0),
    );
    assert_eq!(shallow.counts.crossing_splits, 0);
    assert!(!shallow.secondary.is_empty());
}

#[test]
fn touching_circles_are_secondary_only_near_the_contact() {
    let mut g = circle(Point::new(-1.0, 0.0), 1.0, 0.3);
    g.extend(circle(Point::new(1.0, 0.0), 1.0, 0.7));
    let (fs, _) = build(g, Params::DEFAULT);
    assert!(!fs.secondary.is_empty());
    // The gap between the circles at height y is about y², below μ for |y| < √μ ≈ 0.067.
    for p in secondary_points(&fs) {
        assert!(
            p.to_vec2().hypot() < 0.5,
            "secondary point {p:?} far from the contact"
        );
    }
    assert!(fs.primary.len() >= 100, "{}", fs.primary.len());
}

#[test]
fn isolated_point_demotes_the_section_it_sits_next_to() {
    let (fs, _) = build(
        vec![
            line((0.0, 0.0), (10.0, 0.0)),
            FeatureGeom::Point(Point::new(5.5, 0.05)),
        ],
        abs_params(0.1, 1.0),
    );
    assert_eq!(fs.primary.len(), 9);
    assert_eq!(fs.points.len(), 1);
}

#[test]
fn json_has_the_documented_fields() {
    let (fs, _) = build(
        vec![
            line((0.0, 0.0), (10.0, 0.0)),
            line((0.0, 0.05), (3.0, 0.05)),
        ],
        abs_params(0.1, 1.0),
    );
    let v = to_json(&fs);
    for k in [
        "d",
        "params",
        "counts",
        "timing_ms",
        "points",
        "point_sources",
        "primary",
        "secondary",
    ] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    assert_eq!(v["params"]["mu"], 0.1);
    assert_eq!(v["primary"][0]["ctrl"].as_array().map(Vec::len), Some(4));
    assert_eq!(
        v["primary"].as_array().map(Vec::len),
        Some(fs.primary.len())
    );
    assert!(
        v["secondary"][0]["points"]
            .as_array()
            .is_some_and(|a| a.len() >= 2)
    );
}

#[test]
fn checker_reports_tampered_sets() {
    let (fs, _) = build(
        vec![line((0.0, 0.0), (10.0, 0.0)), line((0.0, 0.5), (10.0, 0.5))],
        abs_params(0.1, 1.0),
    );
    let mut t = fs.clone();
    t.params.l = 0.5;
    assert!(check(&t).iter().any(|d| d.contains("length")));
    let mut t = fs.clone();
    t.params.mu = 0.6;
    assert!(check(&t).iter().any(|d| d.contains("< μ")));
    let mut t = fs.clone();
    t.primary[3].ctrl.p1.y += 0.01;
    assert!(check(&t).iter().any(|d| d.contains("restricted")));
    let (circ, _) = build(circle(Point::ZERO, 1.0, 0.0), Params::DEFAULT);
    let mut t = circ.clone();
    t.params.alpha = 1f64.to_radians();
    assert!(check(&t).iter().any(|d| d.contains("turns")));
    let mut t = circ;
    t.params.mu = 1e-4;
    assert!(check(&t).iter().any(|d| d.contains("chord")));
}

/// Whether `p` is within `tol` of the convex hull of `q` (inside one of the four
/// triangles of its points, sides allowed `tol` of slack).
fn inside_hull(p: Point, q: &[Point; 4], tol: f64) -> bool {
    [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]
        .iter()
        .any(|&(i, j, k)| {
            let (a, b, c) = (q[i], q[j], q[k]);
            let area = (b - a).cross(c - a);
            if area == 0.0 {
                return false;
            }
            let side = |u: Point, v: Point| {
                area.signum() * (v - u).cross(p - u) / u.distance(v).max(1e-300)
            };
            side(a, b) >= -tol && side(b, c) >= -tol && side(c, a) >= -tol
        })
}

#[test]
fn conic_sections_cut_a_circle_like_its_cubics_and_place_nodes_at_area_matched_angles() {
    // The exact circle: the same 64 sections as the cubic one, ends on the circle.
    let w = std::f64::consts::FRAC_1_SQRT_2;
    let q = Conic::new((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), w);
    let quarters: Vec<FeatureGeom> = (0..4)
        .map(|k| FeatureGeom::Conic(q.transform(kurbo::Affine::rotate(f64::from(k) * FRAC_PI_2))))
        .collect();
    let mut quarters = quarters;
    // Close the circle bit for bit (the rotations round the joints differently).
    for k in 0..4 {
        let next = match quarters[(k + 1) % 4] {
            FeatureGeom::Conic(c) => c.p0,
            _ => unreachable!("conics"),
        };
        if let FeatureGeom::Conic(c) = &mut quarters[k] {
            c.p2 = next;
        }
    }
    let (fs, _) = build(quarters, Params::DEFAULT);
    assert_eq!(fs.primary.len(), 64, "{:?}", fs.counts);
    assert_eq!(fs.counts.input_conics, 4);
    assert_eq!(fs.counts.curvature_splits + fs.counts.inflection_splits, 0);
    for s in &fs.primary {
        assert!(matches!(s.parent, Parent::Conic(_)));
        assert!((s.ctrl.p0.to_vec2().hypot() - 1.0).abs() < 1e-15);
        // `along`: exact ends, the mid point at the mid angle, the cubic's inner points
        // at the area-matched angles (the cubic through the four points encloses the
        // arc's own segment area), either direction.
        for t in [s.t, [s.t[1], s.t[0]]] {
            let (a, b) = (s.parent.along(t, 0.0), s.parent.along(t, 1.0));
            assert_eq!((a, b), (s.parent.eval(t[0]), s.parent.eval(t[1])));
            let angle = |p: Point| p.to_vec2().atan2();
            let step = (angle(b) - angle(a) + PI).rem_euclid(2.0 * PI) - PI;
            let inner = (8.0 * super::area_matching_coefficient(step.abs() / 2.0) + 1.0) / 27.0;
            let mut nodes = vec![a];
            for (frac, want) in [
                (1.0 / 3.0, 0.5 * (1.0 - inner)),
                (0.5, 0.5),
                (2.0 / 3.0, 0.5 * (1.0 + inner)),
            ] {
                let p = s.parent.along(t, frac);
                assert!((p.to_vec2().hypot() - 1.0).abs() < 1e-15);
                let got = (angle(p) - angle(a) + PI).rem_euclid(2.0 * PI) - PI;
                assert!((got - step * want).abs() < 1e-13, "{got} vs {step}·{want}");
                if frac != 0.5 {
                    nodes.push(p);
                }
            }
            nodes.push(b);
            let [c1, c2] = crate::element::lagrange::cubic_edge_controls(
                nodes[0], nodes[1], nodes[2], nodes[3],
            );
            let cubic = kurbo::CubicBez::new(nodes[0], c1, c2, nodes[3]);
            let enclosed = kurbo::ParamCurveArea::signed_area(&cubic)
                + kurbo::ParamCurveArea::signed_area(&kurbo::Line::new(b, a));
            let h = step.abs() / 2.0;
            let segment = (h - h.sin() * h.cos()) * step.signum();
            assert!(
                (enclosed - segment).abs() <= 1e-9 * segment.abs(),
                "{enclosed} vs {segment}"
            );
        }
    }
    // A tampered hull is reported.
    let mut t = fs.clone();
    t.primary[5].ctrl.p1 = t.primary[5].ctrl.p0.lerp(t.primary[5].ctrl.p3, 0.4);
    t.primary[5].ctrl.p2 = t.primary[5].ctrl.p0.lerp(t.primary[5].ctrl.p3, 0.6);
    assert!(
        check(&t).iter().any(|d| d.contains("hull")),
        "{:?}",
        check(&t)
    );
}

// ---------- property test ----------

fn coord() -> impl Strategy<Value = f64> {
    // Half the time on a coarse grid, so coincident and collinear controls are common.
    prop_oneof![(0i32..=8).prop_map(|v| v as f64 * 1.25), 0.0..10.0f64]
}

fn point() -> impl Strategy<Value = Point> {
    (coord(), coord()).prop_map(|(x, y)| Point::new(x, y))
}

fn geom() -> impl Strategy<Value = FeatureGeom> {
    prop_oneof![
        6 => (point(), point(), point(), point()).prop_map(|(a, b, c, d)| FeatureGeom::Cubic(CubicBez::new(a, b, c, d))),
        // A cusp-prone or end-degenerate cubic: repeated control points.
        2 => (point(), point(), point()).prop_map(|(a, b, c)| FeatureGeom::Cubic(CubicBez::new(a, a, b, c))),
        1 => (point(), point(), point()).prop_map(|(a, b, c)| FeatureGeom::Cubic(CubicBez::new(a, c, b, a))),
        2 => (point(), point()).prop_map(|(a, b)| FeatureGeom::Line(Line::new(a, b))),
        1 => point().prop_map(FeatureGeom::Point),
        // Conics of any positive weight, on the same coarse grid (collinear, coincident).
        3 => (point(), point(), point(), weight()).prop_map(|(a, b, c, w)| FeatureGeom::Conic(Conic::new(a, b, c, w))),
    ]
}

fn weight() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(std::f64::consts::FRAC_1_SQRT_2),
        Just(1.0),
        1e-3..1.0f64,
        1.0..4.0f64,
    ]
}

/// An affine image of a circle arc (any start, any sweep up to a full turn, any
/// non-degenerate linear part, any offset), as the loader's conic pieces.
fn affine_arc() -> impl Strategy<Value = Vec<Conic>> {
    (
        -PI..PI,
        prop_oneof![1e-3..2.0 * PI, Just(2.0 * PI), Just(FRAC_PI_2)],
        (0.2..5.0f64, 0.2..5.0f64, -2.0..2.0f64, -PI..PI),
        (-50.0..50.0f64, -50.0..50.0f64),
    )
        .prop_map(|(start, sweep, (rx, ry, skew, rot), (x, y))| {
            let arc = kurbo::Arc {
                center: Point::ZERO,
                radii: Vec2::new(1.0, 1.0),
                start_angle: start,
                sweep_angle: sweep,
                x_rotation: 0.0,
            };
            let a = kurbo::Affine::translate((x, y))
                * kurbo::Affine::rotate(rot)
                * kurbo::Affine::skew(skew, 0.0)
                * kurbo::Affine::scale_non_uniform(rx, ry);
            Conic::ellipse_arc(&arc, None, None)
                .into_iter()
                .map(|c| c.transform(a))
                .collect()
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]

    /// Affine images of circle arcs through the features stage: the independent checker
    /// holds (hull containment of every conic section included), every section's hull
    /// contains its piece of the conic (dense samples), its ends are the conic's points at
    /// its parameters, and consecutive sections (and pieces) share their ends bit for bit.
    #[test]
    fn affine_circle_arcs_keep_exact_hulls_and_shared_ends(pieces in affine_arc()) {
        let d = drawing(pieces.iter().map(|c| FeatureGeom::Conic(*c)).collect());
        let fs = FeatureSet::build(&d, &Params::DEFAULT.resolve(d.diagonal()));
        let defects = check(&fs);
        prop_assert!(defects.is_empty(), "{:#?}", defects);
        prop_assert_eq!(fs.counts.input_conics, pieces.len());
        prop_assert!(!fs.primary.is_empty());
        for (i, s) in fs.primary.iter().enumerate() {
            let Parent::Conic(c) = s.parent else {
                return Err(TestCaseError::fail(format!("p{i}: not a conic parent")));
            };
            prop_assert_eq!(s.ctrl.p0, c.eval(s.t[0]));
            prop_assert_eq!(s.ctrl.p3, c.eval(s.t[1]));
            let hull = [s.ctrl.p0, s.ctrl.p1, s.ctrl.p2, s.ctrl.p3];
            let size = s.ctrl.p0.distance(s.ctrl.p3) + 1e-300;
            for k in 0..=32 {
                let p = c.eval(s.t[0] + (s.t[1] - s.t[0]) * f64::from(k) / 32.0);
                prop_assert!(inside_hull(p, &hull, 1e-12 * size), "p{}: {:?} outside {:?}", i, p, hull);
            }
            if let Some(n) = s.next {
                let n = &fs.primary[n.index()];
                prop_assert_eq!(s.ctrl.p3, n.ctrl.p0);
            }
        }
        // Sections of one conic come in parameter order; where they meet, bit for bit.
        for w in fs.primary.windows(2) {
            if w[0].parent == w[1].parent {
                prop_assert!(w[0].t[1] <= w[1].t[0]);
                if w[0].t[1] == w[1].t[0] {
                    prop_assert_eq!(w[0].ctrl.p3, w[1].ctrl.p0);
                }
            }
        }
    }

    #[test]
    fn random_soups_keep_every_invariant(geoms in prop::collection::vec(geom(), 1..6)) {
        let d = drawing(geoms);
        let fs = FeatureSet::build(&d, &Params::DEFAULT.resolve(d.diagonal()));
        let defects = check(&fs);
        prop_assert!(defects.is_empty(), "{:#?}", defects);
    }
}

#[test]
fn area_matching_angles_stay_near_equal_spacing_and_join_the_series() {
    use super::area_matching_coefficient as a;
    for h in [1e-6, 1e-3, 1e-2, 0.1, 0.3, 0.5, std::f64::consts::FRAC_PI_4] {
        let c = a(h);
        assert!((c - 1.0).abs() < 0.03 && c <= 1.0, "h = {h}: A = {c}");
    }
    // the series branch and the solved branch agree where they meet
    assert!((a(0.01 - 1e-12) - a(0.01)).abs() < 1e-9);
    // out of range: equal angles
    assert_eq!(a(f64::NAN), 1.0);
    assert_eq!(a(-1.0), 1.0);
    assert_eq!(a(2.0), 1.0);
}

/// `along` on a cubic: at the parameter thirds where its speed is even (the cubic edge
/// is then the piece itself); at equal arc length where it is not (a control point next
/// to its end point), either direction, on the curve and exact at the ends.
#[test]
fn cubic_nodes_at_parameter_thirds_or_equal_arc_length() {
    use kurbo::ParamCurveArclen;
    let even = Parent::Cubic(CubicBez::new(
        (0.0, 0.0),
        (1.0, 0.3),
        (2.0, 0.3),
        (3.0, 0.0),
    ));
    for s in [1.0 / 3.0, 0.5, 2.0 / 3.0] {
        assert_eq!(even.along([0.2, 0.9], s), even.eval(0.2 + s * 0.7));
    }
    let c = CubicBez::new((0.0, 0.0), (0.01, 0.001), (0.5, 0.03), (1.0, 0.0));
    let uneven = Parent::Cubic(c);
    for t in [[0.0, 0.8], [0.8, 0.0]] {
        assert_eq!(uneven.along(t, 0.0), uneven.eval(t[0]));
        assert_eq!(uneven.along(t, 1.0), uneven.eval(t[1]));
        let piece = c.subsegment(t[0]..t[1]);
        let length = piece.arclen(1e-12);
        for s in [1.0 / 3.0, 0.5, 2.0 / 3.0] {
            let p = uneven.along(t, s);
            // on the curve: at the parameter of the arc length fraction
            let u = piece.inv_arclen(s * length, 1e-12);
            assert!((p - piece.eval(u)).hypot() < 1e-8, "{t:?} {s}");
            let mirrored = uneven.along([t[1], t[0]], 1.0 - s);
            assert!((p - mirrored).hypot() < 1e-8, "{t:?} {s}");
            // at the parameter fraction the node would sit far from that fraction of
            // its arc length (0.14 at 1/3 from the slow end, 0.50 from the fast one)
            let at_parameter = piece.subsegment(0.0..s).arclen(1e-12) / length;
            assert!((at_parameter - s).abs() > 0.15, "{at_parameter} at {s}");
        }
    }
}
