//! Outlines that two shapes share are one exact feature.
//!
//! Three rectangles with edges in common (a and b side by side, c drawn over the
//! lower part of a): the coincident and collinear-overlapping edges become one
//! primary feature each, so every region's area is the document's to rounding
//! at every order and size, the nodes of the shared edges lie on the document's
//! lines, and each shared edge is one line listed by both shapes' physical
//! curves. The meshes go to `target/test-out/shared/` (CI's mshcheck validates
//! them).

mod support;

use triwild::{FemMesh, Length, Meshed, MshOptions, Order, Params, RegionOptions};

const RECTS: &str = r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
<rect id="a" x="6" y="37" width="40" height="60" fill="#ff0000"/>
<rect id="b" x="46" y="37" width="40" height="60" fill="#00ff00"/>
<rect id="c" x="6" y="71" width="40" height="26" fill="#0000ff"/>
</svg>"##;

fn mesh(name: &str, svg: &str, order: Order, l: f64) -> (Meshed, f64) {
    let drawing = triwild::load_bytes(svg.as_bytes(), &triwild::LoadOptions::DEFAULT)
        .expect("the drawing loads");
    let params = Params::DEFAULT.with_l(Length::Rel(l)).with_order(order);
    let meshed = triwild::mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT)
        .expect("the drawing meshes");
    let path = support::out_dir("shared").join(format!("{name}_l{l}_o{}.msh", order as u8));
    triwild::write_msh(&meshed.mesh, &path, MshOptions::DEFAULT).expect("write the mesh");
    (meshed, drawing.diagonal())
}

/// The line elements (by their two end nodes, sorted) of the physical curve `curve`.
fn lines_of(mesh: &FemMesh, curve: &str) -> Vec<[u32; 2]> {
    let group = mesh
        .curves
        .iter()
        .position(|c| c == curve)
        .unwrap_or_else(|| panic!("no physical curve {curve}: {:?}", mesh.curves));
    let mut out: Vec<[u32; 2]> = (0..mesh.line_count())
        .filter(|&i| mesh.line_group[i] as usize == group)
        .map(|i| {
            let l = mesh.line(i);
            [l[0].min(l[1]), l[0].max(l[1])]
        })
        .collect();
    out.sort_unstable();
    out
}

#[test]
fn shared_rectangle_edges_are_exact_at_every_order_and_size() {
    for l in [0.1, 0.05, 0.025] {
        for order in [Order::Linear, Order::Quadratic, Order::Cubic] {
            let (m, d) = mesh("rects", RECTS, order, l);
            let f = m
                .report
                .features
                .expect("the TriWild mesher reports its features");
            assert_eq!(f.secondary_segments, 0, "l {l}: {f:?}");
            assert!(
                f.coincident_merged >= 5 && f.coincident_splits >= 3,
                "{f:?}"
            );
            for (name, want) in [
                ("a", 40.0 * 60.0 - 40.0 * 26.0),
                ("b", 2400.0),
                ("c", 1040.0),
            ] {
                let got = m
                    .report
                    .regions
                    .surfaces
                    .iter()
                    .find(|s| s.name == name)
                    .unwrap_or_else(|| panic!("no region {name}"))
                    .area;
                assert!(
                    ((got - want) / want).abs() < 1e-12,
                    "l {l} order {order:?}: region {name} has area {got}, not {want}"
                );
            }
            // Every node of every line element of the shapes' curves lies on one
            // of the document's lines (x = 6, 46, 86 or y = 37, 71, 97).
            let on = |v: f64, at: &[f64]| at.iter().any(|&a| (v - a).abs() <= 1e-12 * d);
            let shapes: Vec<usize> = ["a", "b", "c"]
                .iter()
                .map(|c| m.mesh.curves.iter().position(|x| x == c).expect("curve"))
                .collect();
            for i in 0..m.mesh.line_count() {
                if !shapes.contains(&(m.mesh.line_group[i] as usize)) {
                    continue;
                }
                for &v in m.mesh.line(i) {
                    let p = m.mesh.nodes[v as usize];
                    // output coordinates flip y: the document's y is -p.y
                    assert!(
                        on(p.x, &[6.0, 46.0, 86.0]) || on(-p.y, &[37.0, 71.0, 97.0]),
                        "l {l} order {order:?}: line node {p:?} off the document's lines"
                    );
                }
            }
            // The edge x = 46 is one line per element, on both a's and b's curves.
            let (a, b) = (lines_of(&m.mesh, "a"), lines_of(&m.mesh, "b"));
            let both = a.iter().filter(|e| b.binary_search(e).is_ok()).count();
            assert!(both >= 2, "l {l}: {both} lines on both a and b");
        }
    }
}

#[test]
fn a_collinear_overlap_inside_one_path_is_one_feature() {
    // One path that runs along its own edge (x = 10) twice, the second time in
    // part: the overlap is one feature, so nothing is secondary.
    let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 40 40">
<path id="p" fill="#808080" d="M10 5 L30 5 L30 35 L10 35 Z M10 12 L2 12 L2 25 L10 25 Z"/>
</svg>"##;
    let (m, _) = mesh("overlap", svg, Order::Linear, 0.05);
    let f = m
        .report
        .features
        .expect("the TriWild mesher reports its features");
    assert_eq!(f.secondary_segments, 0, "{f:?}");
    assert_eq!(f.coincident_merged, 1, "{f:?}");
    let area: f64 = m
        .report
        .regions
        .surfaces
        .iter()
        .filter(|s| s.name == "p")
        .map(|s| s.area)
        .sum();
    assert!(
        (area - (20.0 * 30.0 + 8.0 * 13.0)).abs() < 1e-9,
        "area {area}"
    );
}
