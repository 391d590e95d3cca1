//! The global edge length `-l`: refining `-l` refines the mesh steadily, also on coarse
//! settings. (The graded size field, `--size*`, is `tests/size_field.rs`.)
//!
//! A `<circle>` and a disk drawn as 64 arcs are meshed (background cut away) at several
//! `-l`; at every step the element count must strictly grow, by a factor between 2 and 6
//! per halving once `l` is below the size the boundary itself imposes, and the mean
//! boundary and element edge lengths must follow `l` within a factor. The disk is drawn
//! twice: as 64 cubic arcs (`C`; their joints must stay mesh vertices: two different
//! cubics are not one exact curve) and as 64 SVG arcs (`A`, which the loader keeps as
//! exact conic pieces), whose joints are not corners: the features stage joins them
//! into four exact quarters, so the coarse meshes are not pinned to a 64-gon. Every mesh is written under `target/test-out/edge_length/` and
//! checked by the independent checker. `cargo test --test edge_length -- --nocapture`
//! prints the table.
#![allow(
    clippy::print_stdout,
    reason = "the size table is the test's report (shown with --nocapture)"
)]

mod support;

use std::f64::consts::PI;
use triwild::{
    Drawing, FeatureGeom, FemMesh, Length, MshOptions, Order, Params, RegionMode, RegionOptions,
};

const CIRCLE: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 2 2"><circle cx="1" cy="1" r="1" fill="black"/></svg>"#;

/// Arcs in the disk drawn as a path.
const ARCS: usize = 64;

/// The end point of the `k`-th of [`ARCS`] arcs of the unit disk about (1, 1).
fn joint(k: usize) -> (f64, f64) {
    let a = 2.0 * PI * k as f64 / ARCS as f64;
    if k % ARCS == 0 {
        (2.0, 1.0)
    } else {
        (1.0 + a.cos(), 1.0 + a.sin())
    }
}

/// The unit disk about (1, 1) drawn as a path of [`ARCS`] SVG arcs.
fn arcs_svg() -> String {
    let mut d = String::from("M 2 1");
    for k in 1..=ARCS {
        let (x, y) = joint(k);
        d += &format!(" A 1 1 0 0 1 {x:.17} {y:.17}");
    }
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 2 2"><path fill="black" d="{d} Z"/></svg>"#
    )
}

/// The same disk drawn as [`ARCS`] cubic Béziers (the usual arc approximation).
fn cubics_svg() -> String {
    let k = 4.0 / 3.0 * (PI / (2.0 * ARCS as f64)).tan();
    let mut d = String::from("M 2 1");
    for i in 0..ARCS {
        let ((x0, y0), (x1, y1)) = (joint(i), joint(i + 1));
        // tangents: perpendicular to the radius, in the direction of travel
        let (c1x, c1y) = (x0 - k * (y0 - 1.0), y0 + k * (x0 - 1.0));
        let (c2x, c2y) = (x1 + k * (y1 - 1.0), y1 - k * (x1 - 1.0));
        d += &format!(" C {c1x:.17} {c1y:.17} {c2x:.17} {c2y:.17} {x1:.17} {y1:.17}");
    }
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 2 2"><path fill="black" d="{d} Z"/></svg>"#
    )
}

/// What one mesh measures.
#[derive(Clone, Copy, Debug)]
struct Row {
    level: f64,
    l: f64,
    triangles: usize,
    boundary: usize,
    mean_boundary: f64,
    mean_edge: f64,
}

/// Mesh `drawing` at `level` (relative `-l`) and `order`, the background cut away;
/// write it, check it, measure it.
fn mesh(name: &str, drawing: &Drawing, level: f64, order: Order) -> Row {
    let params = Params::DEFAULT.with_l(Length::Rel(level)).with_order(order);
    let regions = RegionOptions::DEFAULT
        .with_mode(RegionMode::Shape)
        .with_cut_outside(true);
    let meshed = triwild::mesh_drawing(drawing, &params, &regions).expect("the disk meshes");
    let m: FemMesh = meshed.mesh;
    let path = out_dir().join(format!("{name}_o{}_l{level}.msh", order as u8));
    triwild::write_msh(&m, &path, MshOptions::DEFAULT).expect("write the mesh");
    support::check_msh(&path).assert_valid(&format!("{name} at -l {level}"));
    let chord = |a: u32, b: u32| m.nodes[a as usize].distance(m.nodes[b as usize]);
    // the drawn outline's lines (with --cut-outside the physical curve `boundary`
    // repeats the same edges)
    let boundary: Vec<f64> = (0..m.line_count())
        .filter(|&i| m.curves[m.line_group[i] as usize] != "boundary")
        .map(|i| chord(m.line(i)[0], m.line(i)[1]))
        .collect();
    let mut edges: Vec<(u32, u32)> = (0..m.triangle_count())
        .flat_map(|i| {
            let t = m.triangle(i);
            [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
        })
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    Row {
        level,
        l: level * drawing.diagonal(),
        triangles: m.triangle_count(),
        boundary: boundary.len(),
        mean_boundary: mean(&boundary),
        mean_edge: mean(&edges.iter().map(|&(a, b)| chord(a, b)).collect::<Vec<_>>()),
    }
}

fn out_dir() -> std::path::PathBuf {
    support::out_dir("edge_length")
}

/// Below this `-l` (relative) a level is "fine": `l` is below the boundary edges that
/// the curves themselves impose (at order 1 the turn bound α cuts a unit circle into
/// about 55 edges of 0.11, 0.04·d; the 64 pinned joints of the cubic disk are 0.1 apart).
const FINE: f64 = 0.05;

/// Mesh at every level and check that the size follows `l`.
fn assert_follows(name: &str, drawing: &Drawing, levels: &[f64], order: Order) -> Vec<Row> {
    let rows: Vec<Row> = levels
        .iter()
        .map(|&level| mesh(name, drawing, level, order))
        .collect();
    println!("{name}, order {}", order as u8);
    println!(
        "  {:>7} {:>7} {:>6} {:>5} {:>9} {:>9}",
        "-l", "l", "tris", "bnd", "mean bnd", "mean edge"
    );
    for r in &rows {
        println!(
            "  {:>7} {:>7.4} {:>6} {:>5} {:>9.4} {:>9.4}",
            r.level, r.l, r.triangles, r.boundary, r.mean_boundary, r.mean_edge
        );
    }
    for w in rows.windows(2) {
        let (a, b) = (w[0], w[1]);
        assert!(
            b.triangles > a.triangles,
            "{name}: {} triangles at -l {} after {} at -l {}",
            b.triangles,
            b.level,
            a.triangles,
            a.level
        );
        let factor = b.triangles as f64 / a.triangles as f64;
        let halvings = (a.level / b.level).log2();
        if a.level <= FINE {
            let per_halving = factor.powf(1.0 / halvings);
            assert!(
                (2.0..=6.0).contains(&per_halving),
                "{name}: -l {} -> {}: ×{per_halving:.2} per halving",
                a.level,
                b.level
            );
        }
    }
    for r in &rows {
        let (bnd, edge) = (r.mean_boundary / r.l, r.mean_edge / r.l);
        // Coarse levels: the curves' own joints or turn bound may keep boundary edges
        // shorter than l.
        let lo = if r.level <= FINE { 0.5 } else { 0.25 };
        assert!(
            (lo..=2.0).contains(&bnd),
            "{name}: mean boundary edge {:.4} at l = {:.4}",
            r.mean_boundary,
            r.l
        );
        if r.level <= FINE {
            assert!(
                (0.5..=2.0).contains(&edge),
                "{name}: mean edge {:.4} at l = {:.4}",
                r.mean_edge,
                r.l
            );
        }
    }
    rows
}

#[test]
fn circle_refines_steadily_with_l() {
    let drawing = triwild::load_bytes(CIRCLE.as_bytes(), &triwild::LoadOptions::DEFAULT)
        .expect("the circle loads");
    assert_follows("circle", &drawing, &[0.2, 0.1, 0.05, 0.025], Order::Cubic);
    assert_follows("circle", &drawing, &[0.1, 0.05, 0.025], Order::Linear);
}

#[test]
fn disk_of_64_cubic_arcs_refines_steadily_with_l() {
    // 64 cubics: every joint a mesh vertex (64 boundary edges at least).
    let drawing = triwild::load_bytes(cubics_svg().as_bytes(), &triwild::LoadOptions::DEFAULT)
        .expect("the disk loads");
    assert!(
        drawing
            .features
            .iter()
            .all(|f| matches!(f.geom, FeatureGeom::Cubic(_)))
    );
    let rows = assert_follows("disk64", &drawing, &[0.1, 0.05, 0.025], Order::Cubic);
    assert!(rows.iter().all(|r| r.boundary >= ARCS));
}

#[test]
fn disk_of_64_exact_arcs_is_not_pinned_to_a_64_gon() {
    // 64 SVG arcs: 64 exact conic pieces, joined where they continue one circle.
    let drawing = triwild::load_bytes(arcs_svg().as_bytes(), &triwild::LoadOptions::DEFAULT)
        .expect("the disk loads");
    let conics = drawing
        .features
        .iter()
        .filter(|f| matches!(f.geom, FeatureGeom::Conic(_)))
        .count();
    assert_eq!(conics, ARCS);
    let rows = assert_follows(
        "disk64-conic",
        &drawing,
        &[0.2, 0.1, 0.05, 0.025],
        Order::Cubic,
    );
    // The joints are gone: the coarse meshes have far fewer boundary edges than arcs.
    assert!(
        rows[0].boundary < ARCS / 2 && rows[1].boundary < ARCS,
        "{rows:?}"
    );
}

/// Open space is seeded at the field's density (`sizing::seeds`): the
/// L-shaped domain, [0,2]² less [1,2]², at l = 0.0186 (some 20 000
/// triangles in the L, 35 000 in the padded box) starts from a BSP mesh with
/// about as many vertices as the final mesh, and the optimizer splits and
/// collapses few edges (without the seeds: 436 BSP vertices, 50 911 splits
/// and 33 774 collapses). The mesh is valid and its edges match l.
#[test]
fn an_l_shape_at_small_l_starts_near_its_final_mesh() {
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="-0.5 -2.5 3 3"><path d="M0,0 H2 V-1 H1 V-2 H0 Z" fill="black"/></svg>"#;
    let drawing =
        triwild::load_bytes(svg.as_bytes(), &triwild::LoadOptions::DEFAULT).expect("the L loads");
    let params = Params::DEFAULT
        .with_l(Length::Abs(0.0186))
        .with_order(Order::Linear);
    let meshed =
        triwild::mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT).expect("the L meshes");
    let path = out_dir().join("l_shape_uniform.msh");
    triwild::write_msh(&meshed.mesh, &path, MshOptions::DEFAULT).expect("write the mesh");
    support::check_msh(&path).assert_valid("the L at l = 0.0186");
    let bsp = meshed.report.bsp.as_ref().expect("bsp stats");
    let opt = meshed.report.optimize.as_ref().expect("optimize stats");
    let nodes = meshed.mesh.nodes.len();
    println!(
        "L at l = 0.0186: {} BSP vertices ({} seeds), {nodes} nodes, {} triangles, {} splits, {} collapses",
        bsp.vertices,
        bsp.field_seeds,
        meshed.mesh.triangle_count(),
        opt.split.applied,
        opt.collapse.applied
    );
    let ratio = bsp.vertices as f64 / nodes as f64;
    assert!(
        (0.9..=1.1).contains(&ratio),
        "{} BSP vertices for {nodes} nodes",
        bsp.vertices
    );
    assert!(
        (opt.split.applied + opt.collapse.applied) as usize <= nodes / 20,
        "{} splits and {} collapses for {nodes} nodes",
        opt.split.applied,
        opt.collapse.applied
    );
    let e = meshed.report.sizing.as_ref().and_then(|s| s.edges.as_ref());
    let e = e.expect("an edge match");
    assert!(e.matched >= 0.95, "{e:?}");
}
