//! Thin strokes exact and cheap: a stroke's outlines
//! are its exact offsets where they can be (circles, arcs and lines joined
//! smoothly), curved at order 3; a stroke of its fill's paint joins the fill's
//! region, a stroke of another colour stays its own. Meshes go to
//! `target/test-out/strokes/` (CI checks them with mshcheck).

mod support;

use std::f64::consts::PI;
use std::sync::OnceLock;
use triwild::{
    Drawing, FemMesh, LoadOptions, MshOptions, MshVersion, Order, Params, RegionMode,
    RegionOptions, load_bytes, mesh_drawing,
};

const R: f64 = 30.0;
const CENTRE: (f64, f64) = (50.0, -50.0);

fn circle(stroke: &str, width: f64, extra: &str) -> String {
    format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100"><title>a stroked circle</title><circle id="disk" cx="50" cy="50" r="{R}" fill="#88ccff" stroke="{stroke}" stroke-width="{width}" {extra}/></svg>"##
    )
}

fn load(svg: &str) -> Drawing {
    load_bytes(svg.as_bytes(), &LoadOptions::DEFAULT).expect("test SVG loads")
}

fn mesh(d: &Drawing, order: Order, mode: RegionMode, name: &str) -> triwild::Meshed {
    let params = Params::DEFAULT.with_order(order);
    let opts = RegionOptions::DEFAULT.with_mode(mode);
    let meshed = mesh_drawing(d, &params, &opts).expect("meshing succeeds");
    write_checked(&meshed.mesh, name);
    meshed
}

/// Write `mesh` under `target/test-out/strokes/` and check it with the
/// independent reader and checker.
fn write_checked(mesh: &FemMesh, name: &str) {
    static DIR: OnceLock<std::path::PathBuf> = OnceLock::new();
    let dir = DIR.get_or_init(|| support::out_dir("strokes"));
    let path = dir.join(format!("{name}.msh"));
    let opts = MshOptions {
        version: MshVersion::V41,
        binary: false,
    };
    triwild::write_msh(mesh, &path, opts).expect("msh written");
    support::check_msh(&path).assert_valid(name);
}

fn area(m: &triwild::Meshed, name: &str) -> f64 {
    let s = &m.report.regions.surfaces;
    s.iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no region {name} in {s:?}"))
        .area
}

fn names(m: &triwild::Meshed) -> Vec<&str> {
    let s = &m.report.regions.surfaces;
    s.iter()
        .map(|s| s.name.as_str())
        .filter(|&n| n != "background")
        .collect()
}

fn assert_rel(got: f64, want: f64, rel: f64, what: &str) {
    assert!(
        (got - want).abs() <= rel * want.abs(),
        "{what}: {got} != {want} (relative {:e}, tolerance {rel:e})",
        (got - want) / want
    );
}

/// Cubic triangles with an edge on the circle of radius `r` about the centre:
/// both corners and both edge nodes on it (to 1e-9·r), so the edge is the arc,
/// not its chord (a chord's inner nodes lie inside by its sagitta).
fn curved_edges_on(mesh: &FemMesh, r: f64) -> usize {
    let on = |k: u32| {
        let p = mesh.nodes[k as usize];
        ((p.x - CENTRE.0).hypot(p.y - CENTRE.1) - r).abs() <= 1e-9 * r
    };
    // gmsh's 10-node triangle: corners 0 1 2, edge nodes (3 4) (5 6) (7 8)
    const EDGES: [[usize; 4]; 3] = [[0, 1, 3, 4], [1, 2, 5, 6], [2, 0, 7, 8]];
    (0..mesh.triangle_count())
        .filter(|&t| {
            let n = mesh.triangle(t);
            EDGES.iter().any(|e| e.iter().all(|&i| on(n[i])))
        })
        .count()
}

#[test]
fn a_stroked_ring_and_its_fill_are_exact_with_curved_outlines() {
    for width in [0.3, 1.0, 4.0] {
        let d = load(&circle("#000000", width, ""));
        assert_eq!(d.paint.strokes_as_areas, 1);
        assert_eq!(d.paint.exact_stroke_subpaths, 1, "width {width}");
        let m = mesh(
            &d,
            Order::Cubic,
            RegionMode::Shape,
            &format!("ring-{width}"),
        );
        assert_eq!(names(&m), ["disk", "disk-stroke"]);
        let (inner, outer) = (R - 0.5 * width, R + 0.5 * width);
        assert_rel(area(&m, "disk"), PI * inner * inner, 1e-6, "fill");
        let ring = PI * (outer * outer - inner * inner);
        assert_rel(area(&m, "disk-stroke"), ring, 1e-6, "ring");
        for r in [inner, outer] {
            let n = curved_edges_on(&m.mesh, r);
            assert!(n >= 8, "width {width}: {n} curved edges on radius {r}");
        }
    }
}

#[test]
fn a_stroke_of_the_fill_colour_joins_its_region_and_costs_less() {
    let same = load(&circle("#88ccff", 1.0, ""));
    assert_eq!(same.paint.strokes_joined, 1);
    let joined = mesh(&same, Order::Cubic, RegionMode::Shape, "same-colour");
    assert_eq!(names(&joined), ["disk"]);
    // the fill and the ring are one disk of the stroke's outer radius
    assert_rel(area(&joined, "disk"), PI * 30.5 * 30.5, 1e-9, "joined disk");
    // the fill's outline and the stroke's inner outline bound nothing
    assert!(curved_edges_on(&joined.mesh, 30.5) >= 8);
    assert_eq!(curved_edges_on(&joined.mesh, 29.5), 0);
    assert_eq!(curved_edges_on(&joined.mesh, 30.0), 0);
    let by_colour = mesh(
        &same,
        Order::Cubic,
        RegionMode::Colour,
        "same-colour-by-colour",
    );
    assert_eq!(names(&by_colour), ["fill-#88ccff"]);

    let other = load(&circle("#000000", 1.0, ""));
    assert_eq!(other.paint.strokes_joined, 0);
    let banded = mesh(&other, Order::Cubic, RegionMode::Shape, "other-colour");
    assert_eq!(names(&banded), ["disk", "disk-stroke"]);
    let (a, b) = (joined.mesh.triangle_count(), banded.mesh.triangle_count());
    assert!(a < b, "joined {a} triangles, banded {b}");
}

#[test]
fn a_translucent_stroke_of_the_fill_colour_stays_its_own_region() {
    // where a translucent stroke overlaps its fill the colour differs
    let d = load(&circle("#88ccff", 1.0, r#"stroke-opacity="0.6""#));
    assert_eq!(d.paint.strokes_joined, 0);
    let m = mesh(&d, Order::Linear, RegionMode::Shape, "translucent");
    assert_eq!(names(&m), ["disk", "disk-stroke"]);
}

#[test]
fn a_stroke_narrower_than_mu_is_its_centre_line() {
    // μ = 1e-3·d, d ≈ 85: a stroke of width 0.05 is wider than l_min, narrower than μ
    let d = load(&circle("#000000", 0.05, ""));
    assert_eq!(d.paint.strokes_as_areas, 0);
    assert_eq!(d.paint.strokes_below_mu, 1);
    let m = mesh(&d, Order::Cubic, RegionMode::Shape, "below-mu");
    assert_eq!(names(&m), ["disk"]);
    assert_rel(area(&m, "disk"), PI * R * R, 1e-9, "fill");
}

#[test]
fn a_dash_pattern_with_gaps_below_mu_is_stroked_whole() {
    // μ = 1e-3·d, d ≈ 85: gaps of 0.05 would leave the dashes closer than μ
    // (a spiral of 80 000 such dashes took minutes); gaps of 3 do not
    let d = load(&circle("#000000", 4.0, r#"stroke-dasharray="0.02 0.05""#));
    assert_eq!(d.paint.dashes_closed, 1);
    assert!(
        d.warnings.iter().any(|w| w.contains("stroked whole")),
        "{:?}",
        d.warnings
    );
    let m = mesh(&d, Order::Cubic, RegionMode::Shape, "dashes-closed");
    assert_eq!(names(&m), ["disk", "disk-stroke"]);
    // the whole ring, offset exactly
    assert_rel(
        area(&m, "disk-stroke"),
        PI * ((R + 2.0).powi(2) - (R - 2.0).powi(2)),
        1e-9,
        "ring",
    );
    // an odd pattern repeats, each entry a gap in turn: 0.02 on, 3 off, ...
    let odd = load(&circle("#000000", 4.0, r#"stroke-dasharray="0.02 0.05 3""#));
    assert_eq!(odd.paint.dashes_closed, 0);
    let apart = load(&circle("#000000", 4.0, r#"stroke-dasharray="6 3""#));
    assert_eq!(apart.paint.dashes_closed, 0);
    let m = mesh(&apart, Order::Linear, RegionMode::Shape, "dashes-apart");
    let ring = PI * ((R + 2.0).powi(2) - (R - 2.0).powi(2));
    let dashed = area(&m, "disk-stroke");
    assert!(
        dashed < 0.8 * ring && dashed > 0.5 * ring,
        "{dashed} of {ring}"
    );
}

#[test]
fn a_rounded_rectangle_stroke_is_offset_exactly() {
    // lines and quarter circles joined smoothly: parallel lines, concentric arcs
    let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100"><title>a stroked rounded rectangle</title><rect id="rr" x="20" y="30" width="60" height="40" rx="10" fill="#ffcc00" stroke="#000000" stroke-width="2"/></svg>"##;
    let d = load(svg);
    assert_eq!(d.paint.exact_stroke_subpaths, 1);
    let m = mesh(&d, Order::Cubic, RegionMode::Shape, "rounded-rect");
    let rounded = |w: f64, h: f64, r: f64| w * h - (4.0 - PI) * r * r;
    let inner = rounded(58.0, 38.0, 9.0);
    assert_rel(area(&m, "rr"), inner, 1e-9, "fill");
    let ring = rounded(62.0, 42.0, 11.0) - inner;
    assert_rel(area(&m, "rr-stroke"), ring, 1e-9, "ring");
}
