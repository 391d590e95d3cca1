//! Geometry exact to the document's numbers, through the
//! public API: conics (`<circle>`, `<ellipse>`, rounded `<rect>`, arc commands) stay
//! exact curves from the text to the output, in f64, so every node of a curved
//! boundary (corners and high-order nodes) lies on the true curve to 1e-9·d (d the
//! drawing's diagonal), even far from the origin where f32 would be off by 3e-2·d.
//! The meshes are written under `target/test-out/exact/` (CI's mshcheck validates them).

mod support;

use triwild::{FemMesh, Length, MshOptions, Order, Params, RegionOptions};

/// Mesh `svg` at order `order`, write it, and return the mesh and the drawing's diagonal.
fn mesh(name: &str, svg: &str, order: Order, l: f64) -> (FemMesh, f64) {
    let drawing = triwild::load_bytes(svg.as_bytes(), &triwild::LoadOptions::DEFAULT)
        .expect("the drawing loads");
    let params = Params::DEFAULT.with_l(Length::Rel(l)).with_order(order);
    let meshed = triwild::mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT)
        .expect("the drawing meshes");
    let path = support::out_dir("exact").join(format!("{name}_o{}.msh", order as u8));
    triwild::write_msh(&meshed.mesh, &path, MshOptions::DEFAULT).expect("write the mesh");
    (meshed.mesh, drawing.diagonal())
}

/// The largest `|distance(node)|` over every node of every line element of the
/// physical curve `curve`, and how many nodes were measured.
fn worst(mesh: &FemMesh, curve: &str, distance: impl Fn(f64, f64) -> f64) -> (f64, usize) {
    let group = mesh
        .curves
        .iter()
        .position(|c| c == curve)
        .unwrap_or_else(|| panic!("no physical curve {curve}: {:?}", mesh.curves));
    let mut worst = 0f64;
    let mut n = 0;
    for i in 0..mesh.line_count() {
        if mesh.line_group[i] as usize != group {
            continue;
        }
        for &v in mesh.line(i) {
            let p = mesh.nodes[v as usize];
            worst = worst.max(distance(p.x, p.y).abs());
            n += 1;
        }
    }
    (worst, n)
}

const ORDERS: [Order; 3] = [Order::Linear, Order::Quadratic, Order::Cubic];

#[test]
fn a_unit_circle_far_from_the_origin_stays_on_its_circle() {
    // y is flipped on output: the centre (1e6, 1e6) comes out at (1e6, −1e6).
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 2000002 2000002"><circle id="disk" cx="1000000" cy="1000000" r="1" fill="black"/></svg>"#;
    for order in ORDERS {
        let (m, d) = mesh("far_circle", svg, order, 0.1);
        let (err, n) = worst(&m, "disk", |x, y| (x - 1e6).hypot(y + 1e6) - 1.0);
        assert!(n >= 8 * order.line_nodes(), "{n} boundary nodes");
        assert!(
            err <= 1e-9 * d,
            "order {order:?}: a node {err:e} off the circle (d = {d})"
        );
    }
}

#[test]
fn ellipses_rounded_rects_and_arcs_are_exact() {
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 40 20">
        <ellipse id="oval" cx="8" cy="10" rx="6" ry="3.5" fill="red"/>
        <rect id="tile" x="18" y="4" width="12" height="10" rx="3" ry="2" fill="blue"/>
        <path id="lens" d="M 32 14 A 5 5 0 0 1 38 14 A 5 5 0 0 1 32 14 Z" fill="green"/>
        </svg>"#;
    let in_ellipse = |x: f64, y: f64| ((x - 8.0) / 6.0).hypot((-y - 10.0) / 3.5) - 1.0;
    // the rounded rect: straight sides, and corners on ellipses of radii 3, 2
    let in_tile = |x: f64, y: f64| {
        let y = -y;
        if (21.0..=27.0).contains(&x) {
            (y - 4.0).abs().min((y - 14.0).abs())
        } else if (6.0..=12.0).contains(&y) {
            (x - 18.0).abs().min((x - 30.0).abs())
        } else {
            ((x - x.clamp(21.0, 27.0)) / 3.0).hypot((y - y.clamp(6.0, 12.0)) / 2.0) - 1.0
        }
    };
    // the lens: two arcs of radius 5 through (32, 14) and (38, 14), centres (35, 14 ± 4)
    let in_lens = |x: f64, y: f64| {
        let y = -y;
        let above = (x - 35.0).hypot(y - 18.0) - 5.0;
        let below = (x - 35.0).hypot(y - 10.0) - 5.0;
        above.abs().min(below.abs())
    };
    for order in ORDERS {
        let (m, d) = mesh("conics", svg, order, 0.03);
        for (name, err) in [
            ("oval", worst(&m, "oval", in_ellipse)),
            ("tile", worst(&m, "tile", in_tile)),
            ("lens", worst(&m, "lens", in_lens)),
        ] {
            let (err, n) = err;
            assert!(n > 0, "{name}: no boundary node");
            assert!(
                err <= 1e-9 * d,
                "order {order:?}, {name}: a node {err:e} off (d = {d})"
            );
        }
    }
}

#[test]
fn the_drawing_says_how_its_paths_were_read() {
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10">
        <circle cx="5" cy="5" r="4"/><path d="M 1 1 L 9 1 L 5 4 Z"/>
        <rect x="1" y="6" width="3" height="3" rx="1"/></svg>"#;
    let d = triwild::load_bytes(svg.as_bytes(), &triwild::LoadOptions::DEFAULT).expect("loads");
    assert_eq!(
        d.precision,
        triwild::PathPrecision {
            f64_paths: 3,
            single_precision_paths: 0
        }
    );
    // the same numbers in --stats
    let meshed = triwild::mesh_drawing(
        &d,
        &Params::DEFAULT.with_order(Order::Linear),
        &RegionOptions::DEFAULT,
    )
    .expect("meshes");
    let stats = serde_json::to_value(&meshed.report).expect("stats");
    assert_eq!(stats["input"]["f64_paths"], 3);
    assert_eq!(stats["input"]["single_precision_paths"], 0);
}
