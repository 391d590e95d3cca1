//! The VTK XML writer (`write_vtu`), read back with a parser of its own: counts,
//! cell types and offsets, the tags of every cell against the mesh, the
//! physical names against the .msh file's, and the area of the Lagrange
//! triangles, integrated from the file's points alone, against the run's
//! exact `quality.area`.

mod support;

use std::collections::BTreeMap;
use triwild::{Length, MshOptions, Order, Params, RegionMode, RegionOptions};

/// The `DataArray`s of a .vtu file by name, as numbers.
fn arrays(text: &str) -> BTreeMap<String, Vec<f64>> {
    let mut out = BTreeMap::new();
    let mut rest = text;
    while let Some(start) = rest.find("<DataArray ") {
        let tag_end = start + rest[start..].find('>').expect("a closed tag");
        let tag = &rest[start..tag_end];
        let name = tag
            .split("Name=\"")
            .nth(1)
            .and_then(|s| s.split('"').next())
            .expect("every array is named")
            .to_owned();
        let end = tag_end + rest[tag_end..].find("</DataArray>").expect("closed");
        let values = rest[tag_end + 1..end]
            .split_whitespace()
            .map(|v| v.parse::<f64>().expect("a number"))
            .collect();
        assert!(out.insert(name, values).is_none(), "one array per name");
        rest = &rest[end..];
    }
    out
}

/// The Lagrange basis on `n` equispaced points of [0, 1] in gmsh's line order
/// (ends, then inner points), and its derivative, at `t`.
fn line_basis(n: usize, t: f64) -> (Vec<f64>, Vec<f64>) {
    let nodes: Vec<f64> = match n {
        2 => vec![0.0, 1.0],
        3 => vec![0.0, 1.0, 0.5],
        _ => vec![0.0, 1.0, 1.0 / 3.0, 2.0 / 3.0],
    };
    let factor = |i: usize, j: usize| (t - nodes[j]) / (nodes[i] - nodes[j]);
    let value = (0..n)
        .map(|i| (0..n).filter(|&j| j != i).map(|j| factor(i, j)).product())
        .collect();
    let slope = (0..n)
        .map(|i| {
            (0..n)
                .filter(|&m| m != i)
                .map(|m| {
                    let rest: f64 = (0..n)
                        .filter(|&j| j != i && j != m)
                        .map(|j| factor(i, j))
                        .product();
                    rest / (nodes[i] - nodes[m])
                })
                .sum()
        })
        .collect();
    (value, slope)
}

/// The area of a Lagrange triangle of VTK's point order: ½∮(x dy − y dx) over
/// its three edges, each a polynomial of degree k (corners `i`, `i + 1`, then
/// its inner points), with 4-point Gauss–Legendre (exact for degree 7).
fn lagrange_area(pts: &[[f64; 2]]) -> f64 {
    let k = match pts.len() {
        3 => 1,
        6 => 2,
        10 => 3,
        n => panic!("{n} points"),
    };
    let gauss = [
        (0.069_431_844_202_973_71, 0.173_927_422_568_726_9),
        (0.330_009_478_207_571_9, 0.326_072_577_431_273_1),
        (0.669_990_521_792_428_1, 0.326_072_577_431_273_1),
        (0.930_568_155_797_026_3, 0.173_927_422_568_726_9),
    ];
    let mut area = 0.0;
    for e in 0..3 {
        let mut edge = vec![pts[e], pts[(e + 1) % 3]];
        edge.extend((0..k - 1).map(|i| pts[3 + e * (k - 1) + i]));
        for &(t, w) in &gauss {
            let (b, db) = line_basis(edge.len(), t);
            let dot =
                |c: &[f64], k: usize| -> f64 { c.iter().zip(&edge).map(|(c, p)| c * p[k]).sum() };
            let (x, y, dx, dy) = (dot(&b, 0), dot(&b, 1), dot(&db, 0), dot(&db, 1));
            area += 0.5 * w * (x * dy - y * dx);
        }
    }
    area
}

fn disk() -> triwild::Drawing {
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 4 2">
        <rect id="plate" width="4" height="2" fill="grey"/>
        <circle id="disk" cx="1" cy="1" r="0.6" fill="red"/>
        <path id="crack" d="M 2.4 0.5 C 3 0.5 3 1.5 3.6 1.5" stroke="black" fill="none"/></svg>"#;
    triwild::load_bytes(svg.as_bytes(), &triwild::LoadOptions::DEFAULT).expect("the drawing loads")
}

#[test]
fn a_vtu_holds_the_mesh_as_lagrange_cells_with_its_tags_and_area() {
    let dir = support::out_dir("vtu");
    for (order, cut) in [
        (Order::Linear, false),
        (Order::Quadratic, true),
        (Order::Cubic, false),
        (Order::Cubic, true),
    ] {
        let params = Params::DEFAULT.with_l(Length::Rel(0.08)).with_order(order);
        let regions = RegionOptions::DEFAULT
            .with_mode(RegionMode::Shape)
            .with_cut_outside(cut);
        let meshed = triwild::mesh_drawing(&disk(), &params, &regions).expect("it meshes");
        let mesh = &meshed.mesh;
        let path = dir.join(format!("disk_o{}_cut{cut}.vtu", order as u8));
        triwild::write_vtu(mesh, &path).expect("the vtu is written");
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\""));
        let a = arrays(&text);
        let (nt, nl) = (mesh.triangle_count(), mesh.line_count());
        let (tn, ln) = (order.triangle_nodes(), order.line_nodes());
        assert!(text.contains(&format!(
            "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
            mesh.nodes.len(),
            nt + nl
        )));
        let points = &a["Points"];
        assert_eq!(points.len(), 3 * mesh.nodes.len());
        for (p, q) in points.chunks(3).zip(&mesh.nodes) {
            assert_eq!(
                [p[0], p[1], p[2]],
                [q.x, q.y, 0.0],
                "points to the last bit"
            );
        }
        let types = &a["types"];
        assert_eq!(types.len(), nt + nl);
        assert!(types[..nt].iter().all(|&t| t == 69.0));
        assert!(types[nt..].iter().all(|&t| t == 68.0));
        let offsets = &a["offsets"];
        let conn = &a["connectivity"];
        assert_eq!(offsets[nt - 1] as usize, nt * tn);
        assert_eq!(*offsets.last().unwrap() as usize, nt * tn + nl * ln);
        assert_eq!(conn.len(), nt * tn + nl * ln);
        // triangles by region, lines by curve, each in the mesh's order
        let by_group = |groups: &[u32]| {
            let mut order: Vec<usize> = (0..groups.len()).collect();
            order.sort_by_key(|&i| groups[i]);
            order
        };
        let region = &a["region"];
        let curve = &a["curve"];
        for (j, t) in by_group(&mesh.triangle_group).into_iter().enumerate() {
            assert_eq!(region[j] as u32, mesh.triangle_group[t] + 1);
            assert_eq!(curve[j], 0.0);
            let nodes: Vec<u32> = conn[j * tn..(j + 1) * tn]
                .iter()
                .map(|&n| n as u32)
                .collect();
            assert_eq!(nodes, mesh.triangle(t));
        }
        for (j, l) in by_group(&mesh.line_group).into_iter().enumerate() {
            assert_eq!(region[nt + j], 0.0);
            assert_eq!(curve[nt + j] as u32, mesh.line_group[l] + 1);
            let at = nt * tn + j * ln;
            let nodes: Vec<u32> = conn[at..at + ln].iter().map(|&n| n as u32).collect();
            assert_eq!(nodes, mesh.line(l));
        }
        // the .msh file's triangles in the same order (cell j is element j + 1),
        // and its physical names, each with [tag, dim]
        let mut msh = Vec::new();
        triwild::write_msh_to(mesh, &mut msh, MshOptions::DEFAULT).unwrap();
        let back = triwild::read_msh(&msh).unwrap();
        let file_triangles: Vec<f64> = back
            .triangle_blocks
            .iter()
            .flat_map(|b| b.nodes.iter().map(|&n| f64::from(n)))
            .collect();
        assert_eq!(file_triangles, conn[..nt * tn]);
        assert!(!back.physical_names.is_empty());
        for (dim, tag, name) in &back.physical_names {
            assert_eq!(
                a.get(name.as_str()),
                Some(&vec![f64::from(*tag), f64::from(*dim)]),
                "{name}"
            );
        }
        assert_eq!(
            a.len(),
            back.physical_names.len() + 6,
            "the groups, the points, 3 cell arrays, 2 tag arrays"
        );
        // the Lagrange triangles' area, from the file alone
        let area: f64 = (0..nt)
            .map(|t| {
                let pts: Vec<[f64; 2]> = conn[t * tn..(t + 1) * tn]
                    .iter()
                    .map(|&n| [points[3 * n as usize], points[3 * n as usize + 1]])
                    .collect();
                let a = lagrange_area(&pts);
                assert!(a > 0.0, "counter-clockwise");
                a
            })
            .sum();
        let exact = meshed.report.quality.area;
        assert!(
            (area - exact).abs() <= 1e-9 * exact,
            "order {order:?} cut {cut}: {area} vs {exact}"
        );
    }
}
