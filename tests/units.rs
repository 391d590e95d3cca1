//! Output units, through the public API: a drawing's
//! coordinates are its own numbers (the user units of the root `viewBox`) unless
//! `Units::Px` asks for CSS px, and `scale` multiplies them. Meshed areas are
//! measured on the straight triangles of the optimized linear mesh of the filled
//! shapes (`cut_outside`), which covers the shapes exactly.

use triwild::{FemMesh, LoadOptions, Params, RegionOptions, Stage, Units};

/// An A4 Inkscape page drawn in millimetres, with a 100 × 50 mm rectangle.
const A4_MM: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" width="210mm" height="297mm"
    viewBox="0 0 210 297"><rect id="plate" x="10" y="20" width="100" height="50" fill="grey"/></svg>"#;

/// CSS px per millimetre: 96 px per inch, 25.4 mm per inch.
const PX_PER_MM: f64 = 96.0 / 25.4;

fn area(mesh: &FemMesh) -> f64 {
    (0..mesh.triangle_count())
        .map(|i| {
            let [a, b, c] = mesh.corners(i);
            0.5 * (b - a).cross(c - a)
        })
        .sum()
}

fn linear(units: Units, scale: f64) -> Params {
    Params::DEFAULT
        .with_stop_after(Some(Stage::Optimize))
        .with_units(units)
        .with_scale(scale)
}

/// The meshed area of the filled shapes of `svg`, and the mesh.
fn meshed(svg: &str, params: &Params) -> (f64, FemMesh) {
    let opts = LoadOptions::DEFAULT
        .with_units(params.units)
        .with_scale(params.scale);
    let drawing = triwild::load_bytes(svg.as_bytes(), &opts).expect("test drawing loads");
    let meshed = triwild::mesh_drawing(
        &drawing,
        params,
        &RegionOptions::DEFAULT.with_cut_outside(true),
    )
    .expect("test drawing meshes");
    (area(&meshed.mesh), meshed.mesh)
}

fn assert_rel(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        ((got - want) / want).abs() <= tol,
        "{what}: area {got}, expected {want} (relative tolerance {tol:e})"
    );
}

#[test]
fn a_drawing_in_millimetres_meshes_in_millimetres() {
    let (mm, mesh) = meshed(A4_MM, &linear(Units::User, 1.0));
    // the document's numbers in f64: exact up to the area sum's rounding
    assert_rel(mm, 5000.0, 1e-12, "user units");
    // the document's numbers, y flipped: x in [10, 110], y in [-70, -20]
    for p in &mesh.nodes {
        assert!(
            (10.0..=110.0).contains(&p.x) && (-70.0..=-20.0).contains(&p.y),
            "{p:?}"
        );
    }
    // the defaults are user units
    assert_eq!(Params::DEFAULT.units, Units::User);
    assert_eq!(Params::DEFAULT.scale, 1.0);
    let (default, _) = meshed(
        A4_MM,
        &Params::DEFAULT.with_stop_after(Some(Stage::Optimize)),
    );
    assert_eq!(default, mm);
    // px: 71 424.14...; the root viewBox mapping is computed in f64 too
    let (px, _) = meshed(A4_MM, &linear(Units::Px, 1.0));
    assert_rel(px, 5000.0 * PX_PER_MM * PX_PER_MM, 1e-12, "px");
    assert!((px - 71_424.0).abs() < 1.0);
}

#[test]
fn scale_multiplies_coordinates() {
    let (one, m1) = meshed(A4_MM, &linear(Units::User, 1.0));
    let (two, m2) = meshed(A4_MM, &linear(Units::User, 2.0));
    assert_rel(two, 4.0 * one, 1e-12, "scale 2");
    // a power of two scales every number exactly: the same mesh, doubled
    assert_eq!(m1.triangles, m2.triangles);
    for (a, b) in m1.nodes.iter().zip(&m2.nodes) {
        assert_eq!((2.0 * a.x, 2.0 * a.y), (b.x, b.y));
    }
    // millimetres to metres
    let (m, _) = meshed(A4_MM, &linear(Units::User, 1e-3));
    assert_rel(m, 5000.0e-6, 1e-9, "scale 1e-3");
}

#[test]
fn viewbox_origin_and_aspect_keep_the_document_numbers() {
    let body = r#"<rect x="-40" y="30" width="60" height="100" fill="grey"/>"#;
    for aspect in ["none", "xMidYMid meet"] {
        let svg = format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="300" height="100"
                viewBox="-50 20 100 200" preserveAspectRatio="{aspect}">{body}</svg>"#
        );
        let (user, mesh) = meshed(&svg, &linear(Units::User, 1.0));
        assert_rel(user, 6000.0, 1e-9, aspect);
        for p in &mesh.nodes {
            assert!(
                (-40.0..=20.0).contains(&p.x) && (-130.0..=-30.0).contains(&p.y),
                "{p:?}"
            );
        }
        // px: none stretches by 3 × 1/2, meet scales both by 1/2
        let factor = if aspect == "none" { 1.5 } else { 0.25 };
        let (px, _) = meshed(&svg, &linear(Units::Px, 1.0));
        assert_rel(px, 6000.0 * factor, 1e-9, aspect);
    }
}

#[test]
fn without_a_viewbox_nothing_changes() {
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="50mm">
        <rect x="10" y="10" width="30" height="20" fill="grey"/></svg>"#;
    let (user, m_user) = meshed(svg, &linear(Units::User, 1.0));
    let (px, m_px) = meshed(svg, &linear(Units::Px, 1.0));
    assert_rel(user, 600.0, 1e-9, "no viewBox");
    assert_eq!(user, px);
    assert_eq!(m_user.nodes, m_px.nodes);
}

#[test]
fn load_options_from_params_load_in_the_params_units() {
    let mesh_svg = |svg: &[u8], params: &Params| {
        let drawing = triwild::load_bytes(svg, &LoadOptions::from_params(params)?)?;
        triwild::mesh_drawing(&drawing, params, &RegionOptions::DEFAULT)
    };
    let user = mesh_svg(A4_MM.as_bytes(), &linear(Units::User, 1.0)).unwrap();
    let px = mesh_svg(A4_MM.as_bytes(), &linear(Units::Px, 1.0)).unwrap();
    // the report's d is the drawing's diagonal: 100 × 50 mm
    assert_rel(user.report.params.d, 50.0 * 5f64.sqrt(), 1e-12, "d");
    assert_rel(
        px.report.params.d / user.report.params.d,
        PX_PER_MM,
        1e-6,
        "d px",
    );
    assert_eq!(user.report.params.units, Units::User);
    assert_eq!(px.report.params.units, Units::Px);
    // a bad scale is a parameter error, before anything is loaded
    let e = mesh_svg(b"not even svg", &linear(Units::User, 0.0)).unwrap_err();
    assert!(matches!(e, triwild::Error::InvalidParams(_)), "{e}");
}
