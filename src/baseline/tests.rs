//! Tests of the CDT baseline through [`triangulate`], with the size field the
//! pipeline would build ([`baseline`]).

use super::*;
use crate::FemMesh;
use crate::quality::Quality;
use crate::svg::{Feature, FeatureGeom, FeatureSource, FillRule, Shape};
use kurbo::{CubicBez, Line, Rect};
use proptest::prelude::*;
use std::collections::{HashMap, HashSet};

fn shape(i: u32) -> Shape {
    Shape {
        svg_id: None,
        element_index: i,
        paint_order: i,
        filled: true,
        stroked: false,
        fill_rule: FillRule::NonZero,
        fill_colour: None,
        paint: Default::default(),
        subpaths: Vec::new(),
    }
}

/// A drawing of `features`, each tagged with its shape index.
fn drawing(features: &[(u32, FeatureGeom)]) -> Drawing {
    let n_shapes = features.iter().map(|f| f.0 + 1).max().unwrap_or(0);
    let mut bbox: Option<Rect> = None;
    let mut add = |p: Point| bbox = Some(bbox.map_or(Rect::from_points(p, p), |b| b.union_pt(p)));
    for (_, g) in features {
        match *g {
            FeatureGeom::Point(p) => add(p),
            FeatureGeom::Line(l) => [l.p0, l.p1].into_iter().for_each(&mut add),
            FeatureGeom::Cubic(c) => [c.p0, c.p1, c.p2, c.p3].into_iter().for_each(&mut add),
            FeatureGeom::Conic(c) => c.control_points().into_iter().for_each(&mut add),
        }
    }
    Drawing {
        shapes: (0..n_shapes).map(shape).collect(),
        features: features
            .iter()
            .enumerate()
            .map(|(i, &(s, geom))| Feature {
                geom,
                source: FeatureSource {
                    shape: ShapeId::from_index(s as usize),
                    subpath: 0,
                    segment: i as u32,
                },
            })
            .collect(),
        bbox: bbox.unwrap_or_default(),
        warnings: Vec::new(),
        precision: Default::default(),
        paint: Default::default(),
        view_box: None,
        cell: None,
    }
}

/// The size field of `d` and `params` as the pipeline builds it (each filled
/// shape a region named as `--regions shape` names it; no time limit).
fn field(d: &Drawing, params: &Params) -> SizeField {
    let r = params.resolve(d.diagonal());
    let names: Vec<Option<String>> = d
        .shapes
        .iter()
        .map(|s| s.filled.then(|| s.name()))
        .collect();
    SizeField::build(&crate::sizing::FieldInput {
        drawing: d,
        resolved: &r,
        spec: &params.size,
        region_names: &names,
        bounds: input::padded_box(d, r.padding),
        deadline: crate::budget::Deadline::NONE,
        max_vertices: params.max_vertices as usize,
    })
    .expect("the tests' size fields build")
}

/// [`triangulate`] with the size field of `params`.
fn baseline(d: &Drawing, params: &Params) -> Result<LinearMesh> {
    triangulate(d, params, &field(d, params))
}

fn line(a: (f64, f64), b: (f64, f64)) -> FeatureGeom {
    FeatureGeom::Line(Line::new(a, b))
}

/// The unit square as four segments of shape 0.
fn square(scale: f64) -> Vec<(u32, FeatureGeom)> {
    let c = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(x, y)| (x * scale, y * scale));
    (0..4).map(|i| (0, line(c[i], c[(i + 1) % 4]))).collect()
}

/// Every check the baseline promises; returns the mesh's quality.
fn check(d: &Drawing, params: &Params, mesh: &LinearMesh) -> Quality {
    let n = mesh.vertices.len() as u32;
    assert!(mesh.vertices.iter().all(|p| p.is_finite()));
    // Strictly CCW (exactly), indices in range.
    for t in &mesh.triangles {
        assert!(t.iter().all(|&i| i < n), "{t:?}");
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        assert_eq!(
            orient2d(a, b, c),
            Orientation::CounterClockwise,
            "not CCW: {:?}",
            [a, b, c]
        );
    }
    // Every edge has at most two triangles, one on each side.
    let mut directed: HashSet<(u32, u32)> = HashSet::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            assert!(
                directed.insert((t[k], t[(k + 1) % 3])),
                "edge used twice in one direction"
            );
        }
    }
    // The triangles tile the padded box.
    let r = params.resolve(d.diagonal());
    let bx = input::padded_box(d, r.padding);
    let area: f64 = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            0.5 * (b - a).cross(c - a)
        })
        .sum();
    // Up to rounding: spade places refinement vertices on the box's sides by
    // interpolation, which can round them an ulp inside (far from the origin an ulp
    // of the coordinates is not small against the box).
    let magnitude = [bx.x0, bx.y0, bx.x1, bx.y1]
        .into_iter()
        .fold(0.0f64, |m, c| m.max(c.abs()));
    let ulp = magnitude * f64::EPSILON;
    assert!(
        (area - bx.area()).abs() <= 1e-9 * bx.area() + 4.0 * ulp * (bx.width() + bx.height()),
        "area {area} vs box {}",
        bx.area()
    );
    // Feature edges are mesh edges.
    for e in &mesh.edges {
        assert_eq!(e.kind, LineKind::Constraint);
        assert!(
            directed.contains(&(e.v[0], e.v[1])) || directed.contains(&(e.v[1], e.v[0])),
            "feature edge {e:?} is not a mesh edge"
        );
    }
    // Input points and segment ends are mesh vertices (up to the ε_m merge).
    let tol = r.eps_m * (1.0 + 1e-9);
    let near_vertex = |p: Point| mesh.vertices.iter().any(|&v| (v - p).hypot() <= tol);
    for f in &d.features {
        let ends = match f.geom {
            FeatureGeom::Point(p) => vec![p],
            FeatureGeom::Line(l) => vec![l.p0, l.p1],
            FeatureGeom::Cubic(c) => vec![c.p0, c.p3],
            FeatureGeom::Conic(c) => vec![c.p0, c.p2],
        };
        for p in ends {
            assert!(near_vertex(p), "input point {p:?} is not a mesh vertex");
        }
    }
    // The acceptance checker's criteria hold.
    assert_eq!(checker_defects(mesh), (0, 0), "gmsh-side validity");
    let fem = FemMesh::from_linear(mesh, "domain", |s| format!("{s:?}"));
    Quality::of(&fem)
}

/// The acceptance checker's (mshcheck.py --strict) criteria, written independently of
/// [`gmsh_defects`]: (used nodes sharing a cell of the 1e-12·diag grid, triangles with
/// |det J| ≤ 1e-12·h², h² = x-range² + y-range² of the corners).
fn checker_defects(mesh: &LinearMesh) -> (usize, usize) {
    let mut used: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    used.sort_unstable();
    used.dedup();
    let xy: Vec<Point> = used.iter().map(|&i| mesh.vertices[i as usize]).collect();
    let (mut lo, mut hi) = (
        Point::new(f64::MAX, f64::MAX),
        Point::new(f64::MIN, f64::MIN),
    );
    for p in &xy {
        lo = Point::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    let diag = (hi - lo).hypot();
    let g = 1e-12 * diag + 1e-300;
    let mut q: Vec<(f64, f64)> = xy
        .iter()
        .map(|p| ((p.x / g).round(), (p.y / g).round()))
        .collect();
    q.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let before = q.len();
    q.dedup();
    let dup = before - q.len();
    let degenerate = mesh
        .triangles
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
            let xs = [a.x, b.x, c.x];
            let ys = [a.y, b.y, c.y];
            let ptp = |v: [f64; 3]| {
                v.iter().copied().fold(f64::MIN, f64::max)
                    - v.iter().copied().fold(f64::MAX, f64::min)
            };
            det.abs() <= 1e-12 * (ptp(xs).powi(2) + ptp(ys).powi(2))
        })
        .count();
    (dup, degenerate)
}

/// Total length of the feature edges of `shape`.
fn feature_length(mesh: &LinearMesh, shape: u32) -> f64 {
    mesh.edges
        .iter()
        .filter(|e| e.shape == ShapeId::from_index(shape as usize))
        .map(|e| (mesh.vertices[e.v[0] as usize] - mesh.vertices[e.v[1] as usize]).hypot())
        .sum()
}

#[test]
fn unit_square_meets_the_angle_and_conforms() {
    let d = drawing(&square(1.0));
    let mesh = baseline(&d, &Params::DEFAULT).unwrap();
    let q = check(&d, &Params::DEFAULT, &mesh);
    assert!(q.min_angle_deg >= 25.0, "{q:?}");
    // The four sides are covered exactly by feature edges.
    assert!(
        (feature_length(&mesh, 0) - 4.0).abs() < 1e-12,
        "{}",
        feature_length(&mesh, 0)
    );
    // The target length l = d/20 bounds the triangles' size (area cap).
    let l = Params::DEFAULT.resolve(d.diagonal()).l;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        assert!(0.5 * (b - a).cross(c - a) <= equilateral_area(l) * (1.0 + 1e-9));
    }
    assert!(mesh.triangles.len() > 500, "{}", mesh.triangles.len());
}

#[test]
fn crossing_lines_are_split_at_the_crossing() {
    let d = drawing(&[
        (0, line((0.0, 0.0), (1.0, 1.0))),
        (1, line((0.0, 1.0), (1.0, 0.0))),
    ]);
    let mesh = baseline(&d, &Params::DEFAULT).unwrap();
    let q = check(&d, &Params::DEFAULT, &mesh);
    assert!(q.min_angle_deg >= 25.0, "{q:?}");
    let centre = Point::new(0.5, 0.5);
    let at_centre: Vec<u32> = (0..mesh.vertices.len() as u32)
        .filter(|&i| (mesh.vertices[i as usize] - centre).hypot() < 1e-12)
        .collect();
    assert_eq!(at_centre.len(), 1);
    for s in [0, 1] {
        assert!((feature_length(&mesh, s) - 2f64.sqrt()).abs() < 1e-9);
        // Each diagonal passes through the crossing vertex.
        assert!(
            mesh.edges
                .iter()
                .any(|e| e.shape == ShapeId::from_index(s as usize) && e.v.contains(&at_centre[0]))
        );
    }
}

#[test]
fn an_edge_shared_by_two_shapes_is_listed_for_each() {
    let mut f = square(1.0);
    f.push((1, line((1.0, 1.0), (1.0, 0.0)))); // shape 1 repeats the right side, reversed
    let d = drawing(&f);
    let mesh = baseline(&d, &Params::DEFAULT).unwrap();
    check(&d, &Params::DEFAULT, &mesh);
    assert!((feature_length(&mesh, 0) - 4.0).abs() < 1e-12);
    assert!((feature_length(&mesh, 1) - 1.0).abs() < 1e-12);
    let mut per_edge: HashMap<(u32, u32), usize> = HashMap::new();
    for e in &mesh.edges {
        *per_edge
            .entry((e.v[0].min(e.v[1]), e.v[0].max(e.v[1])))
            .or_default() += 1;
    }
    assert!(per_edge.values().all(|&k| k <= 2));
    assert_eq!(
        per_edge.values().filter(|&&k| k == 2).count(),
        mesh.edges
            .iter()
            .filter(|e| e.shape == ShapeId::from_index(1))
            .count()
    );
}

#[test]
fn a_single_point_gets_a_box() {
    let d = drawing(&[(0, FeatureGeom::Point(Point::new(3.0, -2.0)))]);
    let mesh = baseline(&d, &Params::DEFAULT).unwrap();
    let q = check(&d, &Params::DEFAULT, &mesh);
    assert!(mesh.edges.is_empty());
    assert!(q.min_angle_deg >= 25.0, "{q:?}");
}

/// A circle of radius `r` at the origin as kurbo's cubics (shape 0).
fn circle(r: f64) -> Vec<(u32, FeatureGeom)> {
    use kurbo::{PathEl, Shape as _};
    let mut out = Vec::new();
    let mut last = Point::ZERO;
    for el in kurbo::Circle::new(Point::ZERO, r).path_elements(1e-9 * r) {
        match el {
            PathEl::MoveTo(p) => last = p,
            PathEl::CurveTo(a, b, c) => {
                out.push((0, FeatureGeom::Cubic(CubicBez::new(last, a, b, c))));
                last = c;
            }
            _ => {}
        }
    }
    out
}

#[test]
fn a_circle_of_cubics_is_flattened_within_mu() {
    let d = drawing(&circle(1.0));
    let params = Params::DEFAULT;
    let mesh = baseline(&d, &params).unwrap();
    let quality = check(&d, &params, &mesh);
    assert!(quality.min_angle_deg >= 25.0, "{quality:?}");
    let mu = params.resolve(d.diagonal()).mu;
    // Every feature vertex is on the circle (up to kurbo's 1e-9 approximation), and
    // the polygon is within μ of it.
    for e in &mesh.edges {
        for &v in &e.v {
            let r = mesh.vertices[v as usize].to_vec2().hypot();
            assert!((r - 1.0).abs() <= 1e-8, "{r}");
        }
        let mid = mesh.vertices[e.v[0] as usize].midpoint(mesh.vertices[e.v[1] as usize]);
        assert!(1.0 - mid.to_vec2().hypot() <= mu, "{mid:?}");
    }
    assert!((feature_length(&mesh, 0) - 2.0 * std::f64::consts::PI).abs() < 1e-2);
}

#[test]
fn tiny_and_huge_coordinates() {
    for scale in [1e-9, 1e9] {
        // A square far from the origin and crossing lines, at that scale.
        let mut f = square(scale);
        f.push((1, line((0.0, 0.0), (scale, scale))));
        f.push((1, line((0.0, scale), (scale, 0.0))));
        f.push((2, FeatureGeom::Point(Point::new(0.3 * scale, 0.6 * scale))));
        let d = drawing(&f);
        let mesh = baseline(&d, &Params::DEFAULT).unwrap();
        let q = check(&d, &Params::DEFAULT, &mesh);
        assert!(q.min_angle_deg >= 20.0, "{scale}: {q:?}");
        // Snap rounding moves points by up to δ ≤ 1e-9 d.
        assert!((feature_length(&mesh, 0) - 4.0 * scale).abs() < 1e-8 * scale);
        // Offset by 1000 sizes: far from the origin.
        let off = 1000.0 * scale;
        let f: Vec<_> = square(scale)
            .into_iter()
            .map(|(s, g)| match g {
                FeatureGeom::Line(l) => (
                    s,
                    FeatureGeom::Line(Line::new(
                        l.p0 + kurbo::Vec2::new(off, off),
                        l.p1 + kurbo::Vec2::new(off, off),
                    )),
                ),
                g => (s, g),
            })
            .collect();
        let d = drawing(&f);
        let mesh = baseline(&d, &Params::DEFAULT).unwrap();
        check(&d, &Params::DEFAULT, &mesh);
    }
}

#[test]
fn the_vertex_budget_stops_refinement_with_a_valid_mesh() {
    let d = drawing(&circle(1.0));
    let params = Params::DEFAULT.with_max_vertices(200);
    let mesh = baseline(&d, &params).unwrap();
    check(&d, &params, &mesh);
    assert!(mesh.vertices.len() <= 200, "{}", mesh.vertices.len());
}

/// Coordinates that often coincide (a 7×7 lattice: duplicates, shared ends,
/// collinear overlaps), sometimes not.
fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![3 => (0..7i32).prop_map(|i| f64::from(i) / 6.0), 1 => 0.0..1.0f64]
}

fn point() -> impl Strategy<Value = Point> {
    (coordinate(), coordinate()).prop_map(|(x, y)| Point::new(x, y))
}

fn feature() -> impl Strategy<Value = (u32, FeatureGeom)> {
    let geom = prop_oneof![
        4 => (point(), point()).prop_map(|(a, b)| FeatureGeom::Line(Line::new(a, b))),
        2 => (point(), point(), point(), point()).prop_map(|(a, b, c, d)| FeatureGeom::Cubic(CubicBez::new(a, b, c, d))),
        1 => point().prop_map(FeatureGeom::Point),
    ];
    (0..3u32, geom)
}

/// A soup at scale 10^e, offset by `off` sizes.
fn soup() -> impl Strategy<Value = Vec<(u32, FeatureGeom)>> {
    (
        prop::collection::vec(feature(), 1..24),
        -9..=9i32,
        prop_oneof![Just(0.0), Just(-0.5), Just(3.0)],
    )
        .prop_map(|(features, e, off)| {
            let s = 10f64.powi(e);
            let map = |p: Point| Point::new((p.x + off) * s, (p.y + off) * s);
            features
                .into_iter()
                .map(|(shape, g)| {
                    let g = match g {
                        FeatureGeom::Point(p) => FeatureGeom::Point(map(p)),
                        FeatureGeom::Line(l) => FeatureGeom::Line(Line::new(map(l.p0), map(l.p1))),
                        FeatureGeom::Cubic(c) => FeatureGeom::Cubic(CubicBez::new(
                            map(c.p0),
                            map(c.p1),
                            map(c.p2),
                            map(c.p3),
                        )),
                        FeatureGeom::Conic(c) => FeatureGeom::Conic(
                            crate::svg::drawing::Conic::new(map(c.p0), map(c.p1), map(c.p2), c.w),
                        ),
                    };
                    (shape, g)
                })
                .collect()
        })
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 200,
        failure_persistence: None,
        rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
        ..ProptestConfig::default()
    })]

    /// Random segment and cubic soups never panic and always give a valid CCW
    /// tiling of the padded box that contains every segment's ends.
    #[test]
    fn soups_always_mesh(features in soup()) {
        let d = drawing(&features);
        // A smaller budget keeps the test fast; refinement must stop cleanly at it.
        let params = Params::DEFAULT.with_max_vertices(5_000);
        let mesh = baseline(&d, &params).unwrap();
        check(&d, &params, &mesh);
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 48,
        failure_persistence: None,
        rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
        ..ProptestConfig::default()
    })]

    /// The same soups with a size field ten times finer than l over a quarter
    /// of the drawing: the size rounds keep every promise too.
    #[test]
    fn soups_mesh_to_a_size_field(features in soup()) {
        let d = drawing(&features);
        let b = d.bbox;
        let corners = [b.x0, b.y0, b.x0 + 0.5 * b.width(), b.y0 + 0.5 * b.height()];
        let spec = crate::SizeSpec::DEFAULT.with_box(corners, crate::Length::Rel(0.005));
        let params = Params::DEFAULT.with_max_vertices(5_000).with_size(spec);
        let mesh = baseline(&d, &params).unwrap();
        check(&d, &params, &mesh);
    }
}

/// Numbers for the report: `cargo test --release --lib baseline::tests::report -- --ignored --nocapture`.
#[test]
#[ignore = "measurement, run by hand in release"]
#[allow(clippy::print_stderr, reason = "a measurement printed for a human")]
fn report_default_parameters() {
    let cases: Vec<(&str, Vec<(u32, FeatureGeom)>)> = vec![
        ("unit square", square(1.0)),
        ("circle (4 cubics)", circle(1.0)),
        (
            "crossing lines",
            vec![
                (0, line((0.0, 0.0), (1.0, 1.0))),
                (1, line((0.0, 1.0), (1.0, 0.0))),
            ],
        ),
    ];
    for (name, f) in cases {
        let d = drawing(&f);
        let t = std::time::Instant::now();
        let mesh = baseline(&d, &Params::DEFAULT).unwrap();
        let dt = t.elapsed().as_secs_f64();
        let q = check(&d, &Params::DEFAULT, &mesh);
        eprintln!(
            "{name}: {} vertices, {} triangles, {} feature edges, min angle {:.2}°, max angle {:.2}°, max AMIPS {:.3}, mean AMIPS {:.3}, {:.4}s",
            mesh.vertices.len(),
            mesh.triangles.len(),
            mesh.edges.len(),
            q.min_angle_deg,
            q.max_angle_deg,
            q.max_amips,
            q.mean_amips,
            dt
        );
    }
    // 10k random short segments in the unit square (deterministic LCG).
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let f: Vec<(u32, FeatureGeom)> = (0..10_000)
        .map(|_| {
            let a = Point::new(rnd(), rnd());
            let b = a + kurbo::Vec2::new(rnd() - 0.5, rnd() - 0.5) * 0.04;
            (0, FeatureGeom::Line(Line::new(a, b)))
        })
        .collect();
    let d = drawing(&f);
    let t = std::time::Instant::now();
    let mesh = baseline(&d, &Params::DEFAULT).unwrap();
    let dt = t.elapsed().as_secs_f64();
    let q = check(&d, &Params::DEFAULT, &mesh);
    eprintln!(
        "10k segments (length ≤ 0.028, unit square): {} vertices, {} triangles, {} feature edges, min angle {:.2}°, {:.3}s",
        mesh.vertices.len(),
        mesh.triangles.len(),
        mesh.edges.len(),
        q.min_angle_deg,
        dt
    );
}

/// Found by `soups_always_mesh`: spade's `add_constraint_and_split` asserts on this
/// input (`!previous_region.is_empty() || from == final_vertex`); the baseline falls
/// back to meshing without the crossing pieces and still returns a valid mesh.
#[test]
fn regression_spade_split_assertion() {
    let t = 10_000.0 / 3.0;
    let f = [
        (
            0,
            FeatureGeom::Cubic(CubicBez::new(
                (-t, 0.0),
                (-t, 0.0),
                (-5000.0, 1666.6666666666663),
                (0.0, -3333.3333333333335),
            )),
        ),
        (
            0,
            line((-4240.002742118334, -3333.3333333333335), (5000.0, -5000.0)),
        ),
        (
            0,
            line((-5000.0, 1666.6666666666663), (1666.6666666666663, -5000.0)),
        ),
    ];
    let d = drawing(&f);
    let params = Params::DEFAULT.with_max_vertices(5_000);
    let mesh = baseline(&d, &params).unwrap();
    check(&d, &params, &mesh);
}

/// Found by `soups_always_mesh`: a cubic whose control points are on a vertical
/// line flattens to points a rounding error off it, interleaving with a segment on
/// that line; the constraint chains must still be found.
#[test]
fn regression_near_collinear_overlap() {
    let x = -0.33333333333333337;
    let f = [
        (
            0,
            line((-0.5, -0.5), (-0.22207300655589118, -0.16666666666666669)),
        ),
        (0, line((x, -0.12941845925859025), (x, -0.5))),
        (
            0,
            FeatureGeom::Cubic(CubicBez::new(
                (x, -0.3678078538943085),
                (x, -0.5),
                (x, x),
                (x, 0.0),
            )),
        ),
        (
            0,
            line((-0.16666666666666669, -0.5), (-0.5, -0.16666666666666669)),
        ),
        (0, line((-0.5, -0.5), (-0.5, -0.5))),
    ];
    let d = drawing(&f);
    let params = Params::DEFAULT.with_max_vertices(5_000);
    let mesh = baseline(&d, &params).unwrap();
    check(&d, &params, &mesh);
}

/// Snap rounding cases that made spade create near-duplicate vertices and slivers:
/// each meshes, passes [`check`] (including the checker's criteria) and keeps the
/// features' lengths per shape.
#[test]
fn snap_rounding_cases_pass_the_checker() {
    type Case = (&'static str, Vec<(u32, FeatureGeom)>, [f64; 2]);
    let cases: Vec<Case> = vec![
        (
            "two crossing segments",
            vec![
                (0, line((0.0, 0.0), (1.0, 0.7))),
                (1, line((0.0, 0.7), (1.0, 0.0))),
            ],
            [1.0f64.hypot(0.7), 1.0f64.hypot(0.7)],
        ),
        (
            "T-junction off by 1e-13",
            vec![
                (0, line((0.0, 0.0), (1.0, 0.0))),
                (1, line((0.5, 1e-13), (0.5, 1.0))),
            ],
            [1.0, 1.0 - 1e-13],
        ),
        (
            "near-parallel overlap at angle 1e-14",
            vec![
                (0, line((0.0, 0.0), (1.0, 0.0))),
                (1, line((0.1, 0.0), (0.9, 0.8e-14))),
            ],
            [1.0, 0.8],
        ),
        (
            "a vertex 1e-13 from a segment",
            vec![
                (0, line((0.0, 0.0), (1.0, 1.0))),
                (1, FeatureGeom::Point(Point::new(0.3, 0.3 + 1e-13))),
                (1, line((0.0, 1.0), (0.0, 0.0))),
            ],
            [2f64.sqrt(), 1.0],
        ),
        (
            "collinear partial overlap of two shapes",
            vec![
                (0, line((0.0, 0.0), (1.0, 0.0))),
                (1, line((1.5, 0.0), (0.5, 0.0))),
            ],
            [1.0, 1.0],
        ),
    ];
    for (name, f, lengths) in cases {
        let d = drawing(&f);
        let mesh = baseline(&d, &Params::DEFAULT).unwrap_or_else(|e| panic!("{name}: {e}"));
        check(&d, &Params::DEFAULT, &mesh);
        for (s, &len) in lengths.iter().enumerate() {
            let got = feature_length(&mesh, s as u32);
            assert!(
                (got - len).abs() < 1e-8,
                "{name}: shape {s}: {got} vs {len}"
            );
        }
    }
}

/// Many nearly coincident, nearly parallel segments (the pattern of the failing
/// real drawings): valid for the checker.
#[test]
fn a_fan_of_nearly_coincident_segments_passes_the_checker() {
    let mut f = Vec::new();
    for i in 0..40 {
        let e = f64::from(i) * 1e-13;
        f.push((i % 3, line((0.0, e), (1.0, 0.5 - e))));
        f.push((i % 3, line((e, 0.5), (1.0 - e, 0.0))));
        f.push((i % 3, line((0.2 + e, 0.0), (0.8, 0.3 + e * 3.0))));
    }
    let d = drawing(&f);
    let params = Params::DEFAULT.with_max_vertices(20_000);
    let mesh = baseline(&d, &params).unwrap();
    check(&d, &params, &mesh);
}

/// Every edge of `mesh`'s triangles once, as its length over the size field at
/// its midpoint.
fn size_ratios(mesh: &LinearMesh, field: &SizeField) -> Vec<(Point, f64)> {
    let mut edges: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges
        .into_iter()
        .map(|(a, b)| {
            let (a, b) = (mesh.vertices[a as usize], mesh.vertices[b as usize]);
            let mid = a.midpoint(b);
            (mid, a.distance(b) / field.at(mid))
        })
        .collect()
}

#[test]
fn a_size_box_refines_inside_it_and_no_edge_passes_the_split_bound() {
    let d = drawing(&square(1.0));
    // h = d/200 on the left half of the square, l = d/20 elsewhere (graded).
    let spec = crate::SizeSpec::DEFAULT.with_box([0.0, 0.0, 0.5, 1.0], crate::Length::Rel(0.005));
    let params = Params::DEFAULT.with_size(spec);
    let f = field(&d, &params);
    assert!(!f.is_uniform());
    let plain = baseline(&d, &Params::DEFAULT).unwrap();
    let mesh = baseline(&d, &params).unwrap();
    let q = check(&d, &params, &mesh);
    assert!(q.min_angle_deg >= 25.0, "{q:?}");
    // The four sides are still covered exactly by feature edges.
    assert!((feature_length(&mesh, 0) - 4.0).abs() < 1e-12);
    let ratios = size_ratios(&mesh, &f);
    let worst = ratios.iter().map(|r| r.1).fold(0.0, f64::max);
    assert!(worst <= 4.0 / 3.0 + 1e-9, "an edge of {worst} h");
    // Finer in the box: the ideal count there is its area over that of an
    // equilateral triangle of side h.
    let h = 0.005 * d.diagonal();
    let in_box = |m: &LinearMesh| {
        m.triangles
            .iter()
            .filter(|t| {
                let c = t.map(|i| m.vertices[i as usize]);
                (c[0].x + c[1].x + c[2].x) / 3.0 < 0.45
            })
            .count() as f64
    };
    let ideal = 0.45 / equilateral_area(h);
    let (before, after) = (in_box(&plain), in_box(&mesh));
    assert!(after > 10.0 * before, "{before} -> {after}");
    assert!(
        (0.7 * ideal..=2.5 * ideal).contains(&after),
        "{after} vs {ideal}"
    );
    let matched = ratios
        .iter()
        .filter(|r| (0.8..=4.0 / 3.0).contains(&r.1))
        .count();
    assert!(
        matched as f64 >= 0.5 * ratios.len() as f64,
        "{matched} of {}",
        ratios.len()
    );
}

#[test]
fn a_graded_formula_grades_the_mesh() {
    let d = drawing(&square(1.0));
    // h from d/100 at x = 0 to d/25 at x = 1.
    let dd = d.diagonal();
    let expr = format!("{} * (1 + 3 * x)", dd / 100.0);
    let params = Params::DEFAULT.with_size(crate::SizeSpec::DEFAULT.with_expr(expr));
    let f = field(&d, &params);
    let mesh = baseline(&d, &params).unwrap();
    check(&d, &params, &mesh);
    let ratios = size_ratios(&mesh, &f);
    let worst = ratios.iter().map(|r| r.1).fold(0.0, f64::max);
    assert!(worst <= 4.0 / 3.0 + 1e-9, "an edge of {worst} h");
    // Mean edge length in the left and right tenths: about 4 times apart.
    let mean_len = |x0: f64, x1: f64| {
        let sel: Vec<f64> = ratios
            .iter()
            .filter(|(m, _)| (x0..x1).contains(&m.x))
            .map(|(m, r)| r * f.at(*m))
            .collect();
        sel.iter().sum::<f64>() / sel.len() as f64
    };
    let (left, right) = (mean_len(0.0, 0.1), mean_len(0.9, 1.0));
    assert!((2.5..6.0).contains(&(right / left)), "{left} .. {right}");
}

#[test]
fn outlines_are_split_to_the_size_field() {
    // A line of length 1 with h = 0.01 at its start, growing to 0.1 at its end:
    // spade splits it (as a constraint, knowing its pieces), the size rounds make
    // it split every piece longer than 4/3 h, so the pieces grow with h.
    let d = drawing(&[(0, line((0.0, 0.0), (1.0, 0.0)))]);
    let expr = "0.01 + 0.09 * x";
    let params = Params::DEFAULT
        .with_l(crate::Length::Abs(0.1))
        .with_size(crate::SizeSpec::DEFAULT.with_expr(expr));
    let f = field(&d, &params);
    let mesh = baseline(&d, &params).unwrap();
    check(&d, &params, &mesh);
    let mut pieces: Vec<(f64, f64)> = mesh
        .edges
        .iter()
        .map(|e| {
            let (a, b) = (
                mesh.vertices[e.v[0] as usize],
                mesh.vertices[e.v[1] as usize],
            );
            (a.x.min(b.x), a.distance(b))
        })
        .collect();
    pieces.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = pieces.iter().map(|p| p.1).sum();
    assert!((total - 1.0).abs() < 1e-12, "{total}");
    for &(x, len) in &pieces {
        let h = f.at(Point::new(x + 0.5 * len, 0.0));
        assert!(len <= 4.0 / 3.0 * h, "a piece of {len} at {x}, h {h}");
    }
    // ∫_0^1 dx / (0.01 + 0.09 x) = ln(10) / 0.09 ≈ 25.6 pieces of h; no piece
    // longer than 4/3 h takes at least 20.
    let n = pieces.len();
    assert!((20..=60).contains(&n), "{n} pieces");
    let mean = |p: &[(f64, f64)]| p.iter().map(|q| q.1).sum::<f64>() / p.len() as f64;
    assert!(
        mean(&pieces[n - 5..]) > 4.0 * mean(&pieces[..5]),
        "{pieces:?}"
    );
}
