//! Exact conics through the whole pipeline: a hand-built
//! [`Drawing`] holding a unit disk (four quarter-circle conics, w = √2/2) and a
//! rotated ellipse (four conic pieces from [`Conic::ellipse_arc`]) is meshed by
//! [`crate::mesh_drawing`] at orders 1, 2 and 3 and several `-l`. Every
//! node of every feature line (corners and high-order edge nodes) lies on the
//! true circle or ellipse to 1e-12·r, the order-3 disk has area π to 1e-10
//! (relative) at a fine `-l`, and every mesh is written under
//! `target/test-out/conics*/` (CI validates it with `mshcheck.py`) and checked by
//! the library's certificate and by the independent checker of `tests/support`.
//!
//! `cargo test --lib pipeline::tests::conics -- --nocapture` prints the errors.
#![allow(clippy::print_stdout, reason = "the test reports its measurements")]

use super::support::{check_msh, out_dir};
use crate::element::Order;
use crate::output::{self, MshOptions};
use crate::regions::{self, RegionOptions};
use crate::svg::drawing::Conic;
use crate::svg::{Feature, FeatureGeom, FeatureSource, FillRule, Segment, Shape, ShapeId};
use crate::{Drawing, FemMesh, Length, Params, certify_fem};
use kurbo::{Affine, Point, Rect, Vec2};
use std::f64::consts::{FRAC_1_SQRT_2, PI};

/// The disk's centre (radius 1).
const DISK: Point = Point::new(1.0, 1.0);
/// The ellipse's centre, radii and rotation.
const ELLIPSE: (Point, Vec2, f64) = (Point::new(4.5, 1.0), Vec2::new(1.5, 0.75), 0.3);

/// The unit disk centred at [`DISK`]: four quarter circles, anticlockwise.
pub(super) fn disk_subpath() -> crate::svg::Subpath {
    let (x, y) = (DISK.x, DISK.y);
    let p = |a: f64, b: f64| Point::new(x + a, y + b);
    let w = FRAC_1_SQRT_2;
    let segments = vec![
        Conic::new(p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0), w),
        Conic::new(p(0.0, 1.0), p(-1.0, 1.0), p(-1.0, 0.0), w),
        Conic::new(p(-1.0, 0.0), p(-1.0, -1.0), p(0.0, -1.0), w),
        Conic::new(p(0.0, -1.0), p(1.0, -1.0), p(1.0, 0.0), w),
    ];
    crate::svg::Subpath {
        segments: segments.into_iter().map(Segment::Conic).collect(),
        start: p(1.0, 0.0),
        closed: true,
    }
}

/// The rotated ellipse: four pieces of kurbo's arc parametrisation, closed bit for bit.
fn ellipse_subpath() -> crate::svg::Subpath {
    let (center, radii, rot) = ELLIPSE;
    let arc = kurbo::Arc {
        center,
        radii,
        start_angle: 0.2,
        sweep_angle: 2.0 * PI,
        x_rotation: rot,
    };
    let mut pieces = Conic::ellipse_arc(&arc, None, None);
    let start = pieces[0].p0;
    if let Some(last) = pieces.last_mut() {
        last.p2 = start;
    }
    crate::svg::Subpath {
        segments: pieces.into_iter().map(Segment::Conic).collect(),
        start,
        closed: true,
    }
}

fn shape(name: &str, index: u32, subpath: crate::svg::Subpath) -> Shape {
    Shape {
        svg_id: Some(name.to_owned()),
        element_index: index,
        paint_order: index,
        filled: true,
        stroked: false,
        fill_rule: FillRule::NonZero,
        fill_colour: Some([0, 0, 0]),
        paint: Default::default(),
        subpaths: vec![subpath],
    }
}

/// A drawing of `shapes` with the feature soup and bbox the loader would give it.
pub(super) fn drawing_of(shapes: Vec<Shape>) -> Drawing {
    let mut features = Vec::new();
    let mut bbox: Option<Rect> = None;
    for (si, s) in shapes.iter().enumerate() {
        for (pi, sp) in s.subpaths.iter().enumerate() {
            for (k, seg) in sp.segments.iter().enumerate() {
                let geom = match *seg {
                    Segment::Line(l) => FeatureGeom::Line(l),
                    Segment::Cubic(c) => FeatureGeom::Cubic(c),
                    Segment::Conic(c) => FeatureGeom::Conic(c),
                };
                for p in seg.control_points() {
                    bbox = Some(bbox.map_or(Rect::from_points(p, p), |b| b.union_pt(p)));
                }
                features.push(Feature {
                    geom,
                    source: FeatureSource {
                        shape: ShapeId::from_index(si),
                        subpath: u32::try_from(pi).expect("few subpaths"),
                        segment: u32::try_from(k).expect("few segments"),
                    },
                });
            }
        }
    }
    Drawing {
        shapes,
        features,
        bbox: bbox.expect("a drawing with features"),
        warnings: Vec::new(),
        precision: Default::default(),
        paint: Default::default(),
        view_box: None,
        cell: None,
    }
}

/// The disk and the ellipse.
fn disk_and_ellipse() -> Drawing {
    drawing_of(vec![
        shape("disk", 0, disk_subpath()),
        shape("ellipse", 1, ellipse_subpath()),
    ])
}

/// The distance (bounded above: along the ray from the centre) of `p` from the ellipse.
fn ellipse_distance(p: Point) -> f64 {
    let (center, radii, rot) = ELLIPSE;
    let q = Affine::rotate(-rot) * (p - center).to_point();
    let rho = (q.x / radii.x).hypot(q.y / radii.y);
    (rho - 1.0).abs() * q.to_vec2().hypot() / rho
}

/// Largest distance of the feature lines' nodes from their true curves, per curve name.
fn boundary_errors(mesh: &FemMesh) -> (f64, f64, usize) {
    let (mut disk, mut ellipse, mut nodes) = (0.0f64, 0.0f64, 0usize);
    for i in 0..mesh.line_count() {
        let name = &mesh.curves[mesh.line_group[i] as usize];
        if name == "boundary" {
            // the meshed domain's outer boundary (the padded box), not a drawn curve
            continue;
        }
        for &n in mesh.line(i) {
            let p = mesh.nodes[n as usize];
            nodes += 1;
            if name.starts_with("disk") {
                disk = disk.max(((p - DISK).hypot() - 1.0).abs());
            } else if name.starts_with("ellipse") {
                ellipse = ellipse.max(ellipse_distance(p));
            } else {
                panic!("an unexpected feature line {name}");
            }
        }
    }
    (disk, ellipse, nodes)
}

/// The area of surface `name` (0 without such a surface).
fn area_of(mesh: &FemMesh, name: &str) -> f64 {
    regions::stats_of(mesh)
        .iter()
        .find(|s| s.name == name)
        .map_or(0.0, |s| s.area)
}

/// Mesh, write, certify (library and independent checker); the boundary errors
/// and the two areas.
fn mesh_and_check(
    drawing: &Drawing,
    params: &Params,
    dir: &std::path::Path,
    name: &str,
) -> (f64, f64, f64, f64) {
    let meshed = crate::mesh_drawing(drawing, params, &RegionOptions::DEFAULT).expect("meshing");
    let mesh = &meshed.mesh;
    let c = certify_fem(mesh, &crate::CertifyOptions::DEFAULT);
    assert!(c.is_valid(), "{name}: {c:?}");
    let path = dir.join(format!("{name}.msh"));
    output::write_msh(mesh, &path, MshOptions::DEFAULT).expect("write");
    let r = check_msh(&path);
    assert!(r.defects.is_empty(), "{name}: {:?}", r.defects);
    let (disk, ellipse, nodes) = boundary_errors(mesh);
    assert!(nodes > 0, "{name}: no feature line");
    let (a_disk, a_ellipse) = (area_of(mesh, "disk"), area_of(mesh, "ellipse"));
    let (ea, eb) = (ELLIPSE.1.x, ELLIPSE.1.y);
    let (rel_disk, rel_ellipse) = (
        (a_disk - PI) / PI,
        (a_ellipse - PI * ea * eb) / (PI * ea * eb),
    );
    println!(
        "{name}: {} triangles, {nodes} line nodes, radial error disk {disk:.3e} ellipse \
         {ellipse:.3e}, area error disk {rel_disk:.3e} ellipse {rel_ellipse:.3e}; curve {:?}",
        mesh.triangle_count(),
        meshed.report.curve.as_ref().map(|s| (
            s.curved_triangles,
            s.fitted_triangles,
            s.straight_triangles,
            s.max_curve_distance_rel
        )),
    );
    (disk, ellipse, rel_disk, rel_ellipse)
}

#[test]
fn disk_and_ellipse_nodes_lie_on_the_true_conics_at_every_order() {
    let drawing = disk_and_ellipse();
    let dir = out_dir("conics");
    for (order, tag) in [
        (Order::Linear, "p1"),
        (Order::Quadratic, "p2"),
        (Order::Cubic, "p3"),
    ] {
        let mut areas = Vec::new();
        for l in [0.2, 0.1, 0.05] {
            let params = Params::DEFAULT.with_order(order).with_l(Length::Rel(l));
            let name = format!("disk-ellipse-{tag}-l{l}");
            let (disk, ellipse, rel_disk, rel_ellipse) =
                mesh_and_check(&drawing, &params, &dir, &name);
            assert!(disk <= 1e-12, "{name}: a disk node {disk} off the circle");
            assert!(
                ellipse <= 1e-12 * ELLIPSE.1.x,
                "{name}: an ellipse node {ellipse} off the ellipse"
            );
            areas.push((rel_disk.abs(), rel_ellipse.abs()));
        }
        // Curved elements on the exact conics: at order 2 the area error falls as l
        // does (with the cubic approximation it stayed at 2.8e-4 whatever l); at order
        // 3 every curved edge on a conic carries the conic's own area (the inner nodes'
        // angles are area-matched, `Parent::along`), so the areas are exact to rounding
        // at every l.
        if order == Order::Quadratic {
            assert!(
                areas.windows(2).all(|w| w[1].0 < w[0].0),
                "{tag}: disk area errors {areas:?}"
            );
        }
        if order == Order::Cubic {
            assert!(
                areas
                    .iter()
                    .all(|&(a, b)| a.abs() < 1e-13 && b.abs() < 1e-13),
                "{tag}: area errors {areas:?}"
            );
        }
    }
}

#[test]
fn order_3_disk_area_is_pi_at_a_fine_l() {
    let drawing = drawing_of(vec![shape("disk", 0, disk_subpath())]);
    let params = Params::DEFAULT
        .with_order(Order::Cubic)
        .with_l(Length::Abs(0.02));
    let (disk, _, rel, _) =
        mesh_and_check(&drawing, &params, &out_dir("conics-fine"), "disk-p3-fine");
    assert!(disk <= 1e-12, "a node {disk} off the circle");
    assert!(rel.abs() <= 1e-10, "area error {rel:e} (relative)");
}

/// Conics the loader never makes (weights not in (0, 1], tiny or huge, collinear or
/// coincident controls) mesh without a panic: a valid mesh or an error.
#[test]
fn odd_conics_never_panic() {
    let odd = [
        (
            Point::new(0.0, 0.0),
            Point::new(1.0, 1.0),
            Point::new(2.0, 0.0),
        ),
        (
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(2.0, 0.0),
        ),
        (
            Point::new(0.0, 0.0),
            Point::new(3.0, 0.0),
            Point::new(2.0, 0.0),
        ),
        (
            Point::new(0.0, 0.0),
            Point::new(0.0, 0.0),
            Point::new(2.0, 0.0),
        ),
    ];
    for (k, &(a, b, c)) in odd.iter().enumerate() {
        for w in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e300, 1e-300, 5.0, 1.0] {
            let closing = kurbo::Line::new(c, Point::new(1.0, -1.0));
            let back = kurbo::Line::new(Point::new(1.0, -1.0), a);
            let sp = crate::svg::Subpath {
                segments: vec![
                    Segment::Conic(Conic::new(a, b, c, w)),
                    Segment::Line(closing),
                    Segment::Line(back),
                ],
                start: a,
                closed: true,
            };
            let drawing = drawing_of(vec![shape("odd", 0, sp)]);
            for order in [Order::Linear, Order::Cubic] {
                let params = Params::DEFAULT.with_order(order);
                if let Ok(m) = crate::mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT) {
                    let c = certify_fem(&m.mesh, &crate::CertifyOptions::DEFAULT);
                    assert!(c.is_valid(), "case {k} w {w}: {c:?}");
                }
            }
        }
    }
}
