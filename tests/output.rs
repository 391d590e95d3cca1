//! The gmsh writers and the preview, checked through the public API with the
//! independent reader and checker of `tests/support`.

mod support;

use kurbo::Point;
use std::collections::HashMap;
use std::path::Path;
use support::{DefectKind, Msh, check_msh, out_dir, read_msh};
use triwild::LineKind;
use triwild::Order;
use triwild::{Error, FemMesh};
use triwild::{MshOptions, MshVersion};

const FORMATS: [(MshVersion, bool, &str); 4] = [
    (MshVersion::V41, false, "v41-ascii"),
    (MshVersion::V41, true, "v41-binary"),
    (MshVersion::V22, false, "v22-ascii"),
    (MshVersion::V22, true, "v22-binary"),
];

/// A 2×2-cell grid on [0, 2/3]² (coordinates with no short decimal form), split
/// in 8 triangles: surfaces "left" and "right" (and an unused one), curves
/// "bottom" and "middle" (and an unused one).
fn linear_square() -> FemMesh {
    let h = 1.0 / 3.0;
    let mut nodes = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            nodes.push(Point::new(0.1 + i as f64 * h, -7.0 + j as f64 * h));
        }
    }
    let v = |i: u32, j: u32| j * 3 + i;
    let mut triangles = Vec::new();
    let mut triangle_group = Vec::new();
    for j in 0..2 {
        for i in 0..2 {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            triangles.extend_from_slice(&[a, b, c, a, c, d]);
            triangle_group.extend_from_slice(&[i * 2, i * 2]);
        }
    }
    FemMesh {
        order: Some(Order::Linear),
        nodes,
        triangles,
        triangle_group,
        surfaces: vec!["left".into(), "unused surface".into(), "right".into()],
        lines: vec![
            v(0, 0),
            v(1, 0),
            v(1, 0),
            v(2, 0),
            v(1, 0),
            v(1, 1),
            v(1, 1),
            v(1, 2),
        ],
        line_group: vec![0, 0, 2, 2],
        line_kind: vec![
            LineKind::Primary,
            LineKind::Primary,
            LineKind::Secondary,
            LineKind::Constraint,
        ],
        curves: vec!["bottom".into(), "unused curve".into(), "middle".into()],
        periodic: None,
    }
}

/// The map that bends the unit square's bottom edge down: exactly cubic, so a
/// cubic mesh of it is exact; its image has area 1 + 4·0.1/6.
fn bend(p: Point) -> Point {
    Point::new(p.x, p.y - 0.4 * p.x * (1.0 - p.x) * (1.0 - p.y))
}

const BENT_AREA: f64 = 1.0 + 0.4 / 6.0;

/// Lift a straight mesh to order `order` with Lagrange nodes placed by `map`,
/// sharing edge nodes between neighbours (gmsh node order, see `triwild::fem`).
fn lift(
    order: Order,
    corners: &[Point],
    tris: &[[u32; 3]],
    map: impl Fn(Point) -> Point,
) -> (Vec<Point>, Vec<u32>) {
    let p = order as u32;
    let mut nodes: Vec<Point> = corners.iter().map(|&c| map(c)).collect();
    let mut edge_nodes: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    let mut out = Vec::new();
    for t in tris {
        out.extend_from_slice(t);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let ids = if let Some(ids) = edge_nodes.get(&(b, a)) {
                ids.iter().rev().copied().collect()
            } else {
                let (pa, pb) = (corners[a as usize], corners[b as usize]);
                let ids: Vec<u32> = (1..p)
                    .map(|s| {
                        nodes.push(map(pa.lerp(pb, f64::from(s) / f64::from(p))));
                        nodes.len() as u32 - 1
                    })
                    .collect();
                edge_nodes.insert((a, b), ids.clone());
                ids
            };
            out.extend(ids);
        }
        if order == Order::Cubic {
            let c = corners;
            let centre = Point::new(
                (c[t[0] as usize].x + c[t[1] as usize].x + c[t[2] as usize].x) / 3.0,
                (c[t[0] as usize].y + c[t[1] as usize].y + c[t[2] as usize].y) / 3.0,
            );
            nodes.push(map(centre));
            out.push(nodes.len() as u32 - 1);
        }
    }
    (nodes, out)
}

/// The unit square in two triangles, bottom edge bent by [`bend`], at `order`;
/// feature lines on the bottom (primary, curved) and right (secondary) edges.
fn bent_square(order: Order) -> FemMesh {
    let corners = [
        Point::new(0.0, 0.0),
        Point::new(1.0, 0.0),
        Point::new(1.0, 1.0),
        Point::new(0.0, 1.0),
    ];
    let (nodes, triangles) = lift(order, &corners, &[[0, 1, 2], [0, 2, 3]], bend);
    // Lines: ends, then the inner nodes of triangle 0's edges 0→1 and 1→2.
    let e = order as usize - 1;
    let inner = |k: usize| &triangles[3 + k * e..3 + (k + 1) * e];
    let mut lines = vec![0, 1];
    lines.extend_from_slice(inner(0));
    lines.extend_from_slice(&[1, 2]);
    lines.extend_from_slice(inner(1));
    FemMesh {
        order: Some(order),
        nodes,
        triangles,
        triangle_group: vec![0, 0],
        surfaces: vec!["shape \"one\"".into()],
        lines,
        line_group: vec![0, 1],
        line_kind: vec![LineKind::Primary, LineKind::Secondary],
        curves: vec!["bottom".into(), "right".into()],
        periodic: None,
    }
}

fn triangle_type(order: Order) -> i32 {
    [2, 9, 21][order as usize - 1]
}

fn line_type(order: Order) -> i32 {
    [1, 8, 26][order as usize - 1]
}

/// (type, 1-based node tags, group name) of every element, sorted.
fn expected_elements(mesh: &FemMesh) -> Vec<(i32, Vec<u64>, String)> {
    let tags = |s: &[u32]| s.iter().map(|&i| u64::from(i) + 1).collect::<Vec<_>>();
    let mut v: Vec<_> = (0..mesh.triangle_count())
        .map(|t| {
            let name = mesh.surfaces[mesh.triangle_group[t] as usize].replace('"', "'");
            (triangle_type(mesh.order()), tags(mesh.triangle(t)), name)
        })
        .chain((0..mesh.line_count()).map(|l| {
            let name = mesh.curves[mesh.line_group[l] as usize].clone();
            (line_type(mesh.order()), tags(mesh.line(l)), name)
        }))
        .collect();
    v.sort();
    v
}

fn read_elements(msh: &Msh) -> Vec<(i32, Vec<u64>, String)> {
    let mut v: Vec<_> = msh
        .elements
        .iter()
        .map(|e| {
            let dim = if matches!(e.etype, 1 | 8 | 26) { 1 } else { 2 };
            assert_eq!(e.physical.len(), 1, "element {} physical tags", e.tag);
            let name = msh.physical_names[&(dim, e.physical[0])].clone();
            (e.etype, e.nodes.clone(), name)
        })
        .collect();
    v.sort();
    v
}

fn opts(version: MshVersion, binary: bool) -> MshOptions {
    MshOptions { version, binary }
}

/// Write `mesh` in all four formats, read each back and check it.
fn roundtrip(test: &str, mesh: &FemMesh, area: f64) {
    let dir = out_dir(test);
    for (version, binary, tag) in FORMATS {
        let path = dir.join(format!("{test}-{tag}.msh"));
        triwild::write_msh(mesh, &path, opts(version, binary)).expect("write");
        let msh = read_msh(&path).unwrap_or_else(|e| panic!("{tag}: unreadable: {e}"));
        assert_eq!(msh.binary, binary, "{tag}");
        assert_eq!(
            msh.version,
            if version == MshVersion::V41 {
                "4.1"
            } else {
                "2.2"
            }
        );
        // Nodes: tags 1..=N, coordinates bit-exact (ASCII uses shortest round-trip
        // decimals); 4.1 lists them by the entity they lie on, so in tag order here.
        assert_eq!(msh.nodes.len(), mesh.nodes.len(), "{tag}");
        let mut nodes = msh.nodes.clone();
        nodes.sort_by_key(|n| n.0);
        for (i, (t, xyz)) in nodes.iter().enumerate() {
            assert_eq!(*t, i as u64 + 1, "{tag}");
            let p = mesh.nodes[i];
            assert_eq!(
                (xyz[0].to_bits(), xyz[1].to_bits(), xyz[2]),
                (p.x.to_bits(), p.y.to_bits(), 0.0),
                "{tag}: node {t}"
            );
        }
        // Element tags 1..=M, same connectivity and groups.
        let mut etags: Vec<u64> = msh.elements.iter().map(|e| e.tag).collect();
        etags.sort_unstable();
        assert_eq!(etags, (1..=msh.elements.len() as u64).collect::<Vec<_>>());
        assert_eq!(read_elements(&msh), expected_elements(mesh), "{tag}");
        // Only used groups are written.
        let mut names: Vec<&str> = msh.physical_names.values().map(String::as_str).collect();
        names.sort_unstable();
        assert!(
            !names.iter().any(|n| n.contains("unused")),
            "{tag}: {names:?}"
        );
        let report = check_msh(&path);
        report.assert_valid(tag);
        assert_eq!(report.order, mesh.order() as usize);
        assert_eq!(report.triangles, mesh.triangle_count());
        assert_eq!(report.lines, mesh.line_count());
        assert!(
            (report.area - area).abs() <= 1e-13 * area,
            "{tag}: area {} vs {area}",
            report.area
        );
    }
}

#[test]
fn linear_square_roundtrips_in_every_format() {
    let mesh = linear_square();
    let side = 2.0 * (1.0 / 3.0);
    roundtrip("output-linear", &mesh, side * side);
}

#[test]
fn quadratic_mesh_roundtrips_in_every_format() {
    let mesh = bent_square(Order::Quadratic);
    roundtrip("output-quadratic", &mesh, BENT_AREA);
}

#[test]
fn cubic_mesh_roundtrips_in_every_format() {
    let mesh = bent_square(Order::Cubic);
    roundtrip("output-cubic", &mesh, BENT_AREA);
}

/// A scratch directory for files the CI validator must not see (they are invalid on purpose).
fn scratch(test: &str) -> std::path::PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(test);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

#[test]
fn checker_rejects_a_clockwise_triangle() {
    let mut mesh = linear_square();
    mesh.triangles.swap(1, 2); // first triangle now clockwise
    let dir = scratch("checker-clockwise");
    for (version, binary, tag) in FORMATS {
        let path = dir.join(format!("{tag}.msh"));
        triwild::write_msh(&mesh, &path, opts(version, binary)).expect("write");
        let report = check_msh(&path);
        assert!(report.has(DefectKind::Clockwise), "{tag}: {report:#?}");
        assert!(report.has(DefectKind::NonConforming), "{tag}: {report:#?}");
    }
}

#[test]
fn checker_rejects_an_inverted_cubic_with_ccw_corners() {
    let mut mesh = bent_square(Order::Cubic);
    // Pull triangle 0's node at 1/3 of edge 0→1 across the element.
    let n = mesh.triangles[3] as usize;
    mesh.nodes[n] = Point::new(0.33, 0.9);
    let dir = scratch("checker-inverted");
    let path = dir.join("inverted.msh");
    triwild::write_msh(&mesh, &path, MshOptions::DEFAULT).expect("write");
    let report = check_msh(&path);
    assert!(report.has(DefectKind::Inverted), "{report:#?}");
    assert!(!report.has(DefectKind::Clockwise));
}

#[test]
fn checker_certifies_a_curved_element_that_needs_subdivision() {
    // det J = 1 − 3.2·x(1−x) ≥ 0.2, but its Bernstein coefficients at
    // (1,1,0) and (0,1,1) are 1 − 1.6 < 0: only subdivision certifies it.
    let corners = [
        Point::new(0.0, 0.0),
        Point::new(1.0, 0.0),
        Point::new(0.0, 1.0),
    ];
    let map = |p: Point| Point::new(p.x, p.y * (1.0 - 3.2 * p.x * (1.0 - p.x)));
    let (nodes, triangles) = lift(Order::Cubic, &corners, &[[0, 1, 2]], map);
    let mesh = FemMesh {
        order: Some(Order::Cubic),
        nodes,
        triangles,
        triangle_group: vec![0],
        surfaces: vec!["s".into()],
        ..FemMesh::default()
    };
    let path = out_dir("output-subdivided").join("subdivided.msh");
    triwild::write_msh(&mesh, &path, MshOptions::DEFAULT).expect("write");
    let report = check_msh(&path);
    report.assert_valid("strongly curved");
    assert_eq!(report.subdivided, 1, "{report:#?}");
}

#[test]
fn checker_rejects_elements_without_a_physical_group() {
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n\
                $EndNodes\n$Elements\n1\n1 2 2 0 1 1 2 3\n$EndElements\n";
    let path = scratch("checker-nogroup").join("nogroup.msh");
    std::fs::write(&path, text).expect("write");
    let report = check_msh(&path);
    assert!(report.has(DefectKind::NoPhysicalGroup), "{report:#?}");
    assert_eq!(report.defects.len(), 1, "{report:#?}");
}

#[test]
fn writing_into_a_missing_directory_fails_and_creates_nothing() {
    let dir = scratch("atomic-missing");
    let target = dir.join("missing/sub/out.msh");
    let err = triwild::write_msh(&linear_square(), &target, MshOptions::DEFAULT)
        .expect_err("missing directory");
    assert!(matches!(err, Error::Write(_)), "{err:?}");
    assert!(err.to_string().contains("does not exist"), "{err}");
    assert!(!dir.join("missing").exists());
    let err = triwild::check_writable(&target).expect_err("missing directory");
    assert!(matches!(err, Error::Write(_)), "{err:?}");
    assert_eq!(std::fs::read_dir(&dir).expect("list").count(), 0);
}

#[test]
fn failed_writes_leave_an_existing_file_untouched() {
    let dir = scratch("atomic-untouched");
    let target = dir.join("out.msh");
    std::fs::write(&target, b"previous result").expect("seed");
    let mut bad = linear_square();
    let last = bad.nodes.len() - 1;
    bad.nodes[last].y = f64::NAN;
    for (version, binary, tag) in FORMATS {
        let err = triwild::write_msh(&bad, &target, opts(version, binary)).expect_err(tag);
        assert!(matches!(err, Error::Write(_)), "{err:?}");
        assert_eq!(std::fs::read(&target).expect("read"), b"previous result");
    }
    let err = triwild::write_preview(&bad, &target, &triwild::PreviewOptions::DEFAULT)
        .expect_err("preview");
    assert!(matches!(err, Error::Write(_)), "{err:?}");
    // A directory in the way: the rename fails, the temporary file is removed.
    let blocked = dir.join("blocked.msh");
    std::fs::create_dir(&blocked).expect("mkdir");
    let err = triwild::write_msh(&linear_square(), &blocked, MshOptions::DEFAULT)
        .expect_err("a directory");
    assert!(matches!(err, Error::Write(_)), "{err:?}");
    let mut left: Vec<String> = std::fs::read_dir(&dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["blocked.msh", "out.msh"]);
    assert_eq!(std::fs::read(&target).expect("read"), b"previous result");
}

#[test]
fn preview_draws_curved_edges_and_feature_kinds() {
    let dir = out_dir("output-preview");
    let mesh = bent_square(Order::Cubic);
    let path = dir.join("cubic.svg");
    triwild::write_preview(&mesh, &path, &triwild::PreviewOptions::DEFAULT).expect("preview");
    let svg = std::fs::read_to_string(&path).expect("read");
    assert!(svg.starts_with("<svg"));
    assert!(svg.trim_end().ends_with("</svg>"));
    // 5 distinct triangle edges, each a cubic; the primary bottom edge in red.
    let grey = svg.lines().find(|l| l.contains("#808080")).expect("mesh");
    assert_eq!(grey.matches('C').count(), 5, "{grey}");
    assert!(svg.contains("#d62728") && svg.contains("#2ca02c"));
    triwild::write_preview(
        &linear_square(),
        &dir.join("linear.svg"),
        &triwild::PreviewOptions::DEFAULT,
    )
    .expect("preview");
    triwild::write_preview(
        &bent_square(Order::Quadratic),
        &dir.join("quadratic.svg"),
        &triwild::PreviewOptions::DEFAULT,
    )
    .expect("preview");
}

#[test]
fn reader_and_checker_accept_files_written_by_gmsh() {
    // Cubic meshes of the ellipse x² + (y/0.6)² ≤ 1 written by gmsh 4.15 itself
    // (physical surface 7 "disk", physical curve 3 "rim"), in all four formats.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let mut first: Option<Msh> = None;
    for (_, _, tag) in FORMATS {
        let path = dir.join(format!("gmsh-disk-p3-{tag}.msh"));
        let msh = read_msh(&path).unwrap_or_else(|e| panic!("{tag}: {e}"));
        assert_eq!(msh.physical_names[&(2, 7)], "disk");
        assert_eq!(msh.physical_names[&(1, 3)], "rim");
        assert_eq!(msh.of_type(21).count(), 90, "{tag}");
        assert!(msh.of_type(21).all(|e| e.physical == [7]), "{tag}");
        assert!(msh.of_type(26).all(|e| e.physical == [3]), "{tag}");
        let report = check_msh(&path);
        report.assert_valid(tag);
        let ellipse = std::f64::consts::PI * 0.6;
        assert!(
            (report.area - ellipse).abs() < 1e-3 * ellipse,
            "{tag}: {}",
            report.area
        );
        if let Some(f) = &first {
            // Same mesh in every format (gmsh's ASCII keeps 16 digits).
            assert_eq!(f.nodes.len(), msh.nodes.len());
            for ((t0, p0), (t1, p1)) in f.nodes.iter().zip(&msh.nodes) {
                assert_eq!(t0, t1);
                for k in 0..3 {
                    assert!(
                        (p0[k] - p1[k]).abs() <= 1e-15 * (1.0 + p0[k].abs()),
                        "{tag}"
                    );
                }
            }
            let conn = |m: &Msh| {
                let mut v: Vec<_> = m.of_type(21).map(|e| e.nodes.clone()).collect();
                v.sort();
                v
            };
            assert_eq!(conn(f), conn(&msh), "{tag}");
        } else {
            first = Some(msh);
        }
    }
}

/// A structured grid of `2·k²` triangles lifted to `order`.
fn grid(k: u32, order: Order) -> FemMesh {
    let mut corners = Vec::new();
    for j in 0..=k {
        for i in 0..=k {
            corners.push(Point::new(f64::from(i) / 7.0, f64::from(j) / 7.0));
        }
    }
    let v = |i: u32, j: u32| j * (k + 1) + i;
    let mut tris = Vec::new();
    for j in 0..k {
        for i in 0..k {
            tris.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            tris.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    let (nodes, triangles) = lift(order, &corners, &tris, |p| p);
    FemMesh {
        order: Some(order),
        nodes,
        triangle_group: vec![0; tris.len()],
        triangles,
        surfaces: vec!["grid".into()],
        ..FemMesh::default()
    }
}

#[test]
#[ignore = "timing run: cargo test --release --test output -- --ignored --nocapture"]
fn write_a_million_triangles() {
    let dir = scratch("output-million");
    for order in [Order::Linear, Order::Cubic] {
        let mesh = grid(708, order);
        assert!(mesh.triangle_count() > 1_000_000);
        for (version, binary, tag) in FORMATS {
            let path = dir.join(format!("{tag}.msh"));
            let t = std::time::Instant::now();
            triwild::write_msh(&mesh, &path, opts(version, binary)).expect("write");
            let secs = t.elapsed().as_secs_f64();
            let bytes = std::fs::metadata(&path).expect("meta").len();
            #[allow(clippy::print_stderr, reason = "a timing report is this test's output")]
            {
                eprintln!("{order:?} {tag}: {secs:.2} s, {} MB", bytes >> 20);
            }
            let msh = read_msh(&path).expect("read");
            assert_eq!(msh.elements.len(), mesh.triangle_count());
        }
    }
}
