//! End-to-end tests of the regions stage on CDT meshes: SVG text → load →
//! CDT baseline → regions, checked against areas computed from the loaded
//! curves themselves.

use kurbo::{BezPath, ParamCurveArea, Point};
use triwild::FemMesh;
use triwild::{Drawing, Segment};
use triwild::{Meshed, mesh_drawing};
use triwild::{MshOptions, MshVersion, Params};
use triwild::{RegionMode, RegionOptions, RegionStat};

mod support;

use std::path::PathBuf;
use std::sync::OnceLock;

fn mesh(svg: &str, opts: &RegionOptions) -> (Drawing, Meshed) {
    let drawing = triwild::load_bytes(svg.as_bytes(), &triwild::LoadOptions::DEFAULT)
        .expect("test SVG loads");
    let meshed = mesh_drawing(&drawing, &Params::DEFAULT, opts).expect("meshing succeeds");
    (drawing, meshed)
}

fn area_of(stats: &[RegionStat], name: &str) -> f64 {
    stats
        .iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no region {name} in {stats:?}"))
        .area
}

/// The area of the padded box the mesh covers.
fn box_area(d: &Drawing) -> f64 {
    let p = Params::DEFAULT.resolve(d.diagonal()).padding;
    (d.bbox.width() + 2.0 * p) * (d.bbox.height() + 2.0 * p)
}

/// Exact area enclosed by a shape's (closed) outline, from its curves (Green).
fn curve_area(d: &Drawing, shape: usize) -> f64 {
    let mut a = 0.0;
    for sp in &d.shapes[shape].subpaths {
        for s in &sp.segments {
            a += match s {
                Segment::Line(l) => l.signed_area(),
                Segment::Cubic(c) => c.signed_area(),
                Segment::Conic(c) => c.signed_area(),
            };
        }
        if let Some(l) = sp.implicit_closing_segment() {
            a += l.signed_area();
        }
    }
    a.abs()
}

fn curve_length(d: &Drawing, shape: usize) -> f64 {
    use kurbo::ParamCurveArclen;
    d.shapes[shape]
        .subpaths
        .iter()
        .flat_map(|sp| &sp.segments)
        .map(|s| s.to_cubic().arclen(1e-9))
        .sum()
}

/// A fine counter-clockwise polygon of a convex shape's outline (flattened to 1e-6).
fn fine_polygon(d: &Drawing, shape: usize) -> Vec<Point> {
    let mut path = BezPath::new();
    for sp in &d.shapes[shape].subpaths {
        path.move_to(sp.start);
        for s in &sp.segments {
            match s {
                Segment::Line(l) => path.line_to(l.p1),
                Segment::Cubic(c) => path.curve_to(c.p1, c.p2, c.p3),
                Segment::Conic(c) => {
                    for i in 1..=1024 {
                        path.line_to(c.eval(f64::from(i) / 1024.0));
                    }
                }
            }
        }
        path.close_path();
    }
    let mut pts = Vec::new();
    kurbo::flatten(path.iter(), 1e-6, |el| match el {
        kurbo::PathEl::MoveTo(p) | kurbo::PathEl::LineTo(p) => pts.push(p),
        _ => {}
    });
    pts.dedup();
    if pts.first() == pts.last() {
        pts.pop();
    }
    if polygon_area(&pts) < 0.0 {
        pts.reverse();
    }
    pts
}

fn polygon_area(p: &[Point]) -> f64 {
    (0..p.len())
        .map(|i| p[i].to_vec2().cross(p[(i + 1) % p.len()].to_vec2()))
        .sum::<f64>()
        / 2.0
}

/// Sutherland–Hodgman: `subject` clipped by the convex CCW polygon `clip`.
fn clip(subject: &[Point], clip: &[Point]) -> Vec<Point> {
    let mut out = subject.to_vec();
    for i in 0..clip.len() {
        let (a, b) = (clip[i], clip[(i + 1) % clip.len()]);
        let side = |p: Point| (b - a).cross(p - a);
        let input = std::mem::take(&mut out);
        for j in 0..input.len() {
            let (p, q) = (input[j], input[(j + 1) % input.len()]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                out.push(p.lerp(q, sp / (sp - sq)));
            }
        }
    }
    out
}

/// Write `mesh` (4.1 and 2.2) under `target/test-out/regions/`, keeping each
/// file only if the independent reader and checker find it valid and every
/// surface of the mesh appears as a named physical group of dimension 2.
fn write_if_valid(mesh: &FemMesh, name: &str) {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    let dir = DIR.get_or_init(|| support::out_dir("regions"));
    for (version, tag) in [(MshVersion::V41, "v41"), (MshVersion::V22, "v22")] {
        let opts = MshOptions {
            version,
            binary: false,
        };
        let tmp = dir.join(format!("{name}-{tag}.msh.tmp"));
        triwild::write_msh(mesh, &tmp, opts).expect("msh written");
        let report = support::check_msh(&tmp);
        let msh = support::read_msh(&tmp).expect("msh readable");
        let named: Vec<&String> = msh
            .physical_names
            .iter()
            .filter(|((dim, _), _)| *dim == 2)
            .map(|(_, n)| n)
            .collect();
        let ok = report.is_valid() && mesh.surfaces.iter().all(|s| named.contains(&s));
        if !ok {
            let _ = std::fs::remove_file(&tmp);
        }
        report.assert_valid(name);
        assert!(
            ok,
            "{name}: surfaces {:?} vs physical names {named:?}",
            mesh.surfaces
        );
        std::fs::rename(&tmp, dir.join(format!("{name}-{tag}.msh"))).expect("rename");
    }
}

fn check_groups(mesh: &FemMesh) {
    assert_eq!(mesh.triangle_group.len(), mesh.triangle_count());
    assert!(
        mesh.triangle_group
            .iter()
            .all(|&g| (g as usize) < mesh.surfaces.len())
    );
    assert_eq!(mesh.line_group.len(), mesh.line_count());
    assert!(
        mesh.line_group
            .iter()
            .all(|&g| (g as usize) < mesh.curves.len())
    );
    let mut used = vec![false; mesh.nodes.len()];
    for &v in mesh.triangles.iter().chain(&mesh.lines) {
        used[v as usize] = true;
    }
    assert!(used.iter().all(|&u| u), "every node is used");
}

const CIRCLES: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 140 100">
  <title>two overlapping filled circles, a under b</title>
  <circle id="a" cx="50" cy="50" r="30" fill="red"/>
  <circle id="b" cx="85" cy="50" r="30" fill="blue"/>
</svg>"#;

#[test]
#[allow(
    clippy::print_stderr,
    reason = "the measured errors are worth seeing with --nocapture"
)]
fn overlapping_circles_give_background_a_b_with_exact_areas() {
    let (d, m) = mesh(CIRCLES, &RegionOptions::DEFAULT);
    let stats = &m.report.regions.surfaces;
    assert_eq!(m.mesh.surfaces, ["background", "a", "b"]);
    check_groups(&m.mesh);
    let mu = m.report.params.mu;
    let (pa, pb) = (fine_polygon(&d, 0), fine_polygon(&d, 1));
    let overlap = polygon_area(&clip(&pa, &pb));
    let exact_b = curve_area(&d, 1);
    let exact_a = curve_area(&d, 0) - overlap;
    assert!((polygon_area(&pb) - exact_b).abs() < 1e-6 * exact_b);
    // Flattening within μ moves each boundary by at most μ: |Δ area| ≤ μ · boundary length.
    let (la, lb) = (curve_length(&d, 0), curve_length(&d, 1));
    let (ga, gb) = (area_of(stats, "a"), area_of(stats, "b"));
    // The default output is cubic: the circles (split where they cross) are
    // primary curves, reproduced exactly, so the areas are exact to 1e-6.
    assert_eq!(m.report.output.order, 3);
    assert!(
        (gb - exact_b).abs() <= 1e-6 * exact_b,
        "b: {gb} vs {exact_b}"
    );
    assert!(
        (ga - exact_a).abs() <= 1e-6 * exact_a,
        "a: {ga} vs {exact_a}"
    );
    // Within the linear bound too (μ times the boundary length), trivially.
    assert!((ga - exact_a).abs() <= mu * (la + lb) && (gb - exact_b).abs() <= mu * lb);
    let total: f64 = stats.iter().map(|s| s.area).sum();
    let box_a = box_area(&d);
    assert!((total - box_a).abs() <= 1e-9 * box_a, "{total} vs {box_a}");
    eprintln!(
        "circles: |Δa|/a = {:.2e}, |Δb|/b = {:.2e}, bound μL/area = {:.2e}, relabelled {} ({:.2e} area)",
        (ga - exact_a).abs() / exact_a,
        (gb - exact_b).abs() / exact_b,
        mu * lb / exact_b,
        m.report.regions.relabelled,
        m.report.regions.relabelled_area
    );
    write_if_valid(&m.mesh, "circles");

    // Cut outside: the background disappears, a and b keep their areas.
    let (_, cut) = mesh(CIRCLES, &RegionOptions::DEFAULT.with_cut_outside(true));
    assert_eq!(cut.mesh.surfaces, ["a", "b"]);
    check_groups(&cut.mesh);
    assert_eq!(area_of(&cut.report.regions.surfaces, "a"), ga);
    assert!(cut.mesh.nodes.len() < m.mesh.nodes.len());
    write_if_valid(&cut.mesh, "circles-cut");
    // A hole at b's centre (output coordinates: y = -y_svg) removes b.
    let hole = RegionOptions::DEFAULT.with_holes(vec![Point::new(100.0, -50.0)]);
    let (_, holed) = mesh(CIRCLES, &hole);
    assert_eq!(holed.mesh.surfaces, ["background", "a"]);
    // Colour mode names by fill.
    let (_, col) = mesh(
        CIRCLES,
        &RegionOptions::DEFAULT.with_mode(RegionMode::Colour),
    );
    assert_eq!(
        col.mesh.surfaces,
        ["background", "fill-#ff0000", "fill-#0000ff"]
    );
}

/// A pentagram {5/2} of circumradius R around (50, 50).
fn star_svg(rule: &str) -> String {
    let pts: Vec<String> = (0..5)
        .map(|i| {
            let t = -std::f64::consts::FRAC_PI_2 + i as f64 * 4.0 * std::f64::consts::PI / 5.0;
            format!("{},{}", 50.0 + 40.0 * t.cos(), 50.0 + 40.0 * t.sin())
        })
        .collect();
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
  <title>a pentagram with fill-rule {rule}</title>
  <polygon id="star" points="{}" fill="black" fill-rule="{rule}"/>
</svg>"#,
        pts.join(" ")
    )
}

#[test]
fn evenodd_and_nonzero_stars_have_their_areas() {
    use std::f64::consts::PI;
    let r = 40.0;
    let inner = r * (2.0 * PI / 5.0).cos() / (PI / 5.0).cos();
    let star = 5.0 * r * inner * (PI / 5.0).sin();
    let pentagon = 2.5 * inner * inner * (2.0 * PI / 5.0).sin();
    for (rule, exact) in [("nonzero", star), ("evenodd", star - pentagon)] {
        let (d, m) = mesh(&star_svg(rule), &RegionOptions::DEFAULT);
        let got = area_of(&m.report.regions.surfaces, "star");
        // The input points are exact (f64 from the document's text), but the
        // star's edges cross and come within μ of each other near the crossings,
        // where they are secondary features, kept only inside the ε-envelope
        // (docs/design.md "Invariants" 2): the meshed area is close, not exact (the
        // envelope allows ~1e-3 here: ε = 2e-3·d along the secondary stretches
        // near the ten crossings). Measured: 1.9e-5 relative (nonzero) with the
        // f64 loader and a plain Delaunay seed; 1.5e-4 with the constrained
        // seed (the optimizer's path differs, not the precision).
        assert!(
            (got - exact).abs() < 3e-4 * exact,
            "{rule}: {got} vs {exact}"
        );
        let total: f64 = m.report.regions.surfaces.iter().map(|s| s.area).sum();
        assert!((total - box_area(&d)).abs() <= 1e-9 * box_area(&d));
        check_groups(&m.mesh);
        write_if_valid(&m.mesh, &format!("star-{rule}"));
    }
}

const GAP: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
  <title>a filled square outline with a small gap (no Z): SVG closes it</title>
  <path id="gap" d="M 10 10 L 90 10 L 90 90 L 10 90 L 10 10.5" fill="green"/>
</svg>"#;

#[test]
fn a_shape_with_a_small_gap_is_still_filled() {
    let (d, m) = mesh(GAP, &RegionOptions::DEFAULT.with_cut_outside(true));
    assert_eq!(m.mesh.surfaces, ["gap"]);
    let got = area_of(&m.report.regions.surfaces, "gap");
    assert!((got - 6400.0).abs() < 1e-9 * 6400.0, "{got}");
    assert!(d.shapes[0].subpaths[0].implicit_closing_segment().is_some());
    check_groups(&m.mesh);
    write_if_valid(&m.mesh, "gap");
}
