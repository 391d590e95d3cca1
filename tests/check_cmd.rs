//! `triwild check`: valid and invalid meshes of order 1, 2 and 3, written with
//! `triwild::write_msh` from hand-made `FemMesh` values, checked for exit
//! codes and numbers (invalid count, Jacobian ratio, exact area). Valid meshes go
//! to `target/test-out/check_cmd/` (CI validates them with mshcheck); invalid ones
//! to a scratch directory.

mod support;

use kurbo::{CubicBez, ParamCurveArea, Point};
use std::path::{Path, PathBuf};
use std::process::Command;
use triwild::FemMesh;
use triwild::LineKind;
use triwild::Order;
use triwild::{MshOptions, MshVersion, write_msh};

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("check-cmd")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// Run `triwild check --json` and return (exit code, parsed JSON).
fn check(path: &Path) -> (i32, serde_json::Value) {
    let out = Command::new(env!("CARGO_BIN_EXE_triwild"))
        .args(["check", "--json"])
        .arg(path)
        .output()
        .expect("run triwild");
    let v = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out.stdout)));
    (out.status.code().expect("exit code"), v)
}

fn mesh(order: Order, nodes: Vec<Point>, triangles: Vec<u32>, lines: Vec<u32>) -> FemMesh {
    let nt = triangles.len() / order.triangle_nodes();
    let nl = lines.len() / order.line_nodes();
    FemMesh {
        order: Some(order),
        nodes,
        triangles,
        triangle_group: vec![0; nt],
        surfaces: vec!["inside".into()],
        lines,
        line_group: vec![0; nl],
        line_kind: vec![LineKind::Primary; nl],
        curves: vec!["rim".into()],
        periodic: None,
    }
}

fn square() -> FemMesh {
    let nodes = vec![
        Point::new(0.0, 0.0),
        Point::new(1.0, 0.0),
        Point::new(1.0, 1.0),
        Point::new(0.0, 1.0),
    ];
    mesh(Order::Linear, nodes, vec![0, 1, 2, 0, 2, 3], vec![0, 1])
}

/// Triangle (0,0), (1,0), (0,1) whose edge 1→2 bulges out to the quadratic through
/// the mid node (0.6, 0.6): area 1/2 + 2/3 · area(A, P, B) with control P = (0.7, 0.7).
fn quadratic() -> (FemMesh, f64) {
    let nodes = vec![
        Point::new(0.0, 0.0),
        Point::new(1.0, 0.0),
        Point::new(0.0, 1.0),
        Point::new(0.5, 0.0),
        Point::new(0.6, 0.6),
        Point::new(0.0, 0.5),
    ];
    (
        mesh(Order::Quadratic, nodes, (0..6).collect(), vec![1, 2, 4]),
        0.5 + 2.0 / 3.0 * 0.2,
    )
}

/// A quarter disk: triangle (0,0), (1,0), (0,1) with edge 1→2 the usual cubic arc;
/// its area is the Green's-theorem area of that cubic (the straight sides pass
/// through the origin and add nothing).
fn cubic() -> (FemMesh, f64) {
    let k = 0.551_915_024_494;
    let arc = CubicBez::new((1.0, 0.0), (1.0, k), (k, 1.0), (0.0, 1.0));
    let e = triwild::element::CurvedEdge {
        edge: 1,
        curve: arc,
        t0: 0.0,
        t1: 1.0,
    };
    let n = triwild::element::lagrange::cubic_nodes(
        [
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(0.0, 1.0),
        ],
        Some(&e),
    );
    let m = mesh(
        Order::Cubic,
        n.to_vec(),
        (0..10).collect(),
        vec![1, 2, 5, 6],
    );
    (m, arc.signed_area())
}

fn num(v: &serde_json::Value, k: &str) -> f64 {
    v[k].as_f64()
        .unwrap_or_else(|| panic!("{k} missing in {v}"))
}

#[test]
fn valid_meshes_of_every_order_and_format() {
    let out = support::out_dir("check_cmd");
    let (q, q_area) = quadratic();
    let (c, c_area) = cubic();
    let cases = [
        ("square", square(), 1.0, true),
        ("quadratic", q, q_area, false),
        ("cubic", c, c_area, false),
    ];
    for (name, m, area, straight) in cases {
        for (version, v) in [(MshVersion::V41, "41"), (MshVersion::V22, "22")] {
            for binary in [false, true] {
                let p = out.join(format!(
                    "{name}-v{v}-{}.msh",
                    if binary { "bin" } else { "ascii" }
                ));
                write_msh(&m, &p, MshOptions { version, binary }).expect("write");
                let (code, j) = check(&p);
                assert_eq!(code, 0, "{name}: {j}");
                assert_eq!(j["valid"], true);
                assert_eq!(j["invalid"], 0);
                assert_eq!(j["triangles"].as_u64(), Some(m.triangle_count() as u64));
                let a = num(&j, "total_area");
                assert!(
                    (a - area).abs() < 1e-13 * area,
                    "{name}: area {a} vs {area}"
                );
                let r = num(&j, "min_detj_ratio");
                if straight {
                    assert!((r - 1.0).abs() < 1e-12);
                } else {
                    assert!(r > 0.1 && r < 1.0, "{name}: ratio {r}");
                    assert_eq!(j["curved"], 1);
                }
            }
        }
    }
    // the quarter disk's ratio is tight: min/max of det J sampled densely
    let (c, _) = cubic();
    let n: [Point; 10] = c.nodes.clone().try_into().expect("10 nodes");
    let det = triwild::element::jacobian::det_cubic(&n);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..=50 {
        for k in 0..=50 - i {
            let v = det.eval([
                1.0 - (i + k) as f64 / 50.0,
                i as f64 / 50.0,
                k as f64 / 50.0,
            ]);
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let (_, j) = check(&out.join("cubic-v41-ascii.msh"));
    let r = num(&j, "min_detj_ratio");
    assert!(
        r <= lo / hi + 1e-12 && r > lo / hi - 2e-3,
        "{r} vs {}",
        lo / hi
    );
}

#[test]
fn invalid_meshes_exit_1() {
    let dir = scratch("invalid");
    // order 1: one of two triangles clockwise (mixed orientation)
    let mut m1 = square();
    m1.triangles = vec![0, 1, 2, 0, 3, 2];
    // order 2: the mid node of edge 1→2 pushed across corner 0
    let (mut m2, _) = quadratic();
    m2.nodes[4] = Point::new(-0.4, -0.4);
    // order 3: the first node of edge 0→1 pushed across the opposite side
    let (mut m3, _) = cubic();
    m3.nodes[3] = Point::new(0.3, 1.8);
    // order 3, degenerate: all nodes on one line
    let mut m4 = m3.clone();
    for p in &mut m4.nodes {
        p.y = 0.0;
    }
    for (name, m, inverted) in [
        ("mixed", m1, 1),
        ("p2", m2, 1),
        ("p3", m3, 1),
        ("flat", m4, 0),
    ] {
        let p = dir.join(format!("{name}.msh"));
        write_msh(&m, &p, MshOptions::DEFAULT).expect("write");
        let (code, j) = check(&p);
        assert_eq!(code, 1, "{name}: {j}");
        assert_eq!(j["valid"], false);
        assert_eq!(j["invalid"], 1, "{name}: {j}");
        assert_eq!(j["inverted"], inverted, "{name}: {j}");
        assert!(num(&j, "min_detj_ratio") <= 0.0, "{name}: {j}");
    }
    // no triangles at all
    let p = dir.join("empty.msh");
    write_msh(&FemMesh::default(), &p, MshOptions::DEFAULT).expect("write");
    assert_eq!(check(&p).0, 1);
}

#[test]
fn unreadable_exit_2() {
    let dir = scratch("unreadable");
    let cases: [(&str, &[u8]); 3] = [
        ("garbage.msh", b"not a mesh at all"),
        ("svg.msh", b"<svg xmlns='http://www.w3.org/2000/svg'/>"),
        (
            "truncated.msh",
            b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n",
        ),
    ];
    for (name, bytes) in cases {
        let p = dir.join(name);
        std::fs::write(&p, bytes).expect("write");
        let (code, j) = check(&p);
        assert_eq!(code, 2, "{name}");
        assert_eq!(j["readable"], false);
    }
    let (code, _) = check(&dir.join("missing.msh"));
    assert_eq!(code, 2);
    // the human summary
    let out = Command::new(env!("CARGO_BIN_EXE_triwild"))
        .arg("check")
        .arg(dir.join("garbage.msh"))
        .output()
        .expect("run");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a readable gmsh mesh"));
}

/// gmsh's own P3 meshes of an elliptic disk (axes 1, 0.6), in all four formats: the numbers
/// mshcheck (gmsh's reader, numpy Bernstein check) reports for them.
#[test]
fn gmsh_fixtures_agree_with_mshcheck() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    for f in [
        "gmsh-disk-p3-v22-ascii.msh",
        "gmsh-disk-p3-v22-binary.msh",
        "gmsh-disk-p3-v41-ascii.msh",
        "gmsh-disk-p3-v41-binary.msh",
    ] {
        let (code, j) = check(&dir.join(f));
        assert_eq!(code, 0, "{f}: {j}");
        assert_eq!(
            (j["triangles"].as_u64(), j["curved"].as_u64()),
            (Some(90), Some(22)),
            "{f}"
        );
        // mshcheck: min_detj_ratio 0.8026052627769277, total_area 1.884963907679325
        assert!(
            (num(&j, "min_detj_ratio") - 0.802_605_262_776_927_7).abs() < 1e-9,
            "{f}: {j}"
        );
        assert!(
            (num(&j, "total_area") - 1.884_963_907_679_325).abs() < 1e-12,
            "{f}: {j}"
        );
    }
}
