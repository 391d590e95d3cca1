//! The gmsh model a solver gets, read back with the repository's own
//! reader (`triwild::read_msh_file`). On a square (`id=box`) holding a
//! `<circle id=inclusion>` crossed by an open stroked curve, with and without
//! `--cut-outside`, and on a `<circle>` at `-l 0.2 --cut-outside`, written by
//! the binary as MSH 4.1 (ASCII and binary) and 2.2 (ASCII and binary):
//! - every surface entity has nodes classified on it and bounding curves that
//!   exist, every curve's bounding points exist, every node of a line element
//!   lies on a point or a curve (4.1);
//! - a physical curve `boundary` exists and its line elements run
//!   counter-clockwise around the domain (the area they enclose is the area
//!   of the corner triangles);
//! - within each piece of a physical curve (its lines on one entity) no two
//!   line elements start (or end) at the same node; in 4.1 no two line
//!   elements join the same two nodes (an edge on several physical curves is
//!   one element in one entity that each of them lists);
//! - `--stats`' minimum Jacobian ratio (`quality` and `curve`) equals `triwild
//!   check --json`'s `min_detj_ratio` to 1e-6, its area and the regions' areas
//!   add up to `total_area` to 1e-9.
//!
//! The meshes stay under `target/test-out/gmsh_model/`: `.ci/run` opens them
//! with gmsh's API (`.ci/gmsh_model_check.py`) and `shared/bench/mshcheck.py`.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::process::Command;
use triwild::{MshMesh, read_msh_file};

const EXE: &str = env!("CARGO_BIN_EXE_triwild");

/// The output directory, emptied.
fn out_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-out/gmsh_model");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create test output dir");
    dir
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// Run the binary; its stdout as JSON.
fn run_json(args: &[&str]) -> serde_json::Value {
    let out = Command::new(EXE).args(args).output().expect("run triwild");
    assert!(
        out.status.success(),
        "triwild {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object on stdout")
}

fn num(v: &serde_json::Value, path: &[&str]) -> f64 {
    let mut v = v;
    for k in path {
        v = &v[k];
    }
    v.as_f64()
        .unwrap_or_else(|| panic!("{path:?} is not a number: {v}"))
}

/// Every line element of the file, once per physical curve it is on:
/// (physical tag, entity, nodes). In 4.1 an element's physical curves are its
/// entity's (an edge on several curves is one element); in 2.2, each element's.
fn lines(m: &MshMesh) -> Vec<(i32, Option<i32>, &[u32])> {
    let physicals = |b: &triwild::LineBlock| -> Vec<i32> {
        let of_entity = b.entity.and_then(|e| {
            m.entities
                .iter()
                .find(|c| c.dim == 1 && c.tag == e)
                .map(|c| c.physicals.clone())
        });
        of_entity.unwrap_or_else(|| vec![b.physical.unwrap_or(0)])
    };
    m.line_blocks
        .iter()
        .flat_map(|b| {
            let p = physicals(b);
            b.lines()
                .flat_map(move |l| p.clone().into_iter().map(move |g| (g, b.entity, l)))
        })
        .collect()
}

/// Check the model in `m` (see the file's docs); `what` names the case.
fn check_model(m: &MshMesh, what: &str) {
    let names: HashMap<(i32, i32), &str> = m
        .physical_names
        .iter()
        .map(|(d, t, n)| ((*d, *t), n.as_str()))
        .collect();
    let lines = lines(m);
    assert!(!lines.is_empty(), "{what}: no line elements");

    // Within each piece of a physical curve (its lines on one entity), no two
    // lines start or end at one node.
    let mut starts: HashSet<(i32, Option<i32>, u32)> = HashSet::new();
    let mut ends: HashSet<(i32, Option<i32>, u32)> = HashSet::new();
    for &(g, e, l) in &lines {
        assert!(
            starts.insert((g, e, l[0])) && ends.insert((g, e, l[1])),
            "{what}: physical curve {:?} has two lines starting or ending at node {}",
            names.get(&(1, g)),
            if starts.contains(&(g, e, l[0])) {
                l[0]
            } else {
                l[1]
            }
        );
    }

    // The boundary runs counter-clockwise around the domain.
    let boundary = names
        .iter()
        .find(|(k, n)| k.0 == 1 && **n == "boundary")
        .map(|(k, _)| k.1)
        .unwrap_or_else(|| panic!("{what}: no physical curve `boundary`: {names:?}"));
    let p = |i: u32| m.nodes[i as usize];
    let enclosed: f64 = lines
        .iter()
        .filter(|l| l.0 == boundary)
        .map(|l| 0.5 * p(l.2[0]).to_vec2().cross(p(l.2[1]).to_vec2()))
        .sum();
    let corners: f64 = m
        .triangles()
        .map(|(_, t)| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])))
        .sum();
    assert!(
        corners > 0.0 && (enclosed - corners).abs() <= 1e-9 * corners,
        "{what}: the boundary encloses {enclosed}, the domain's corner triangles {corners}"
    );

    if m.format.version != "4.1" {
        assert!(m.entities.is_empty(), "{what}: 2.2 has no $Entities");
        return;
    }
    // No two line elements join the same two nodes: an edge on
    // several physical curves is one element in one entity they all list.
    let mut edges = HashSet::new();
    for b in &m.line_blocks {
        for l in b.lines() {
            assert!(
                edges.insert((l[0].min(l[1]), l[0].max(l[1]))),
                "{what}: two line elements join nodes {} and {}",
                l[0],
                l[1]
            );
        }
    }
    let entity = |dim: i32, tag: i32| m.entities.iter().find(|e| e.dim == dim && e.tag == tag);
    let surfaces: Vec<_> = m.entities.iter().filter(|e| e.dim == 2).collect();
    assert!(!surfaces.is_empty(), "{what}: no surface entity");
    for s in &surfaces {
        assert!(
            m.node_entities.contains(&(2, s.tag)),
            "{what}: surface {} has no node",
            s.tag
        );
        assert!(
            !s.bounding.is_empty(),
            "{what}: surface {} has no bounding curve",
            s.tag
        );
        for b in &s.bounding {
            assert!(
                entity(1, b.abs()).is_some(),
                "{what}: surface {} bounded by missing curve {b}",
                s.tag
            );
        }
        assert_eq!(s.physicals.len(), 1, "{what}: surface {}", s.tag);
    }
    for c in m.entities.iter().filter(|e| e.dim == 1) {
        assert!(
            !c.bounding.is_empty(),
            "{what}: curve {} has no point",
            c.tag
        );
        for b in &c.bounding {
            assert!(
                entity(0, b.abs()).is_some(),
                "{what}: curve {} bounded by missing point {b}",
                c.tag
            );
        }
    }
    // Each line's entity is a curve of its physical group; its nodes lie on a
    // point or a curve, never inside a surface.
    for &(g, e, l) in &lines {
        let e = e.expect("4.1 lines have an entity");
        let c = entity(1, e).unwrap_or_else(|| panic!("{what}: line on missing curve {e}"));
        assert!(c.physicals.contains(&g), "{what}: curve {e}");
        for &v in l {
            assert!(
                m.node_entities[v as usize].0 <= 1,
                "{what}: node {v} of a line is on {:?}",
                m.node_entities[v as usize]
            );
        }
    }
    // Point nodes end lines.
    let line_ends: HashSet<u32> = lines.iter().flat_map(|l| [l.2[0], l.2[1]]).collect();
    for (v, &(d, _)) in m.node_entities.iter().enumerate() {
        if d == 0 {
            assert!(
                line_ends.contains(&(v as u32)),
                "{what}: point node {v} ends no line"
            );
        }
    }
}

#[test]
fn the_model_a_solver_gets() {
    let dir = out_dir();
    let cases: [(&str, &str, &[&str]); 3] = [
        ("box", "model-box.svg", &[]),
        ("box-cut", "model-box.svg", &["--cut-outside"]),
        (
            "circle-cut",
            "model-circle.svg",
            &["-l", "0.2", "--cut-outside"],
        ),
    ];
    let formats: [(&str, &[&str]); 4] = [
        ("v41", &[]),
        ("v41-bin", &["--binary"]),
        ("v22", &["--msh-version", "2.2"]),
        ("v22-bin", &["--msh-version", "2.2", "--binary"]),
    ];
    for (stem, svg, flags) in cases {
        let input = fixture(svg);
        for (fmt, fmt_flags) in formats {
            let what = format!("{stem}-{fmt}");
            let out = dir.join(format!("{what}.msh"));
            let mut args = vec![input.to_str().expect("utf-8 path"), "-o"];
            args.push(out.to_str().expect("utf-8 path"));
            args.push("--stats");
            args.extend(flags);
            args.extend(fmt_flags);
            let stats = run_json(&args);
            let check = run_json(&["check", "--json", out.to_str().expect("utf-8 path")]);
            assert_eq!(check["valid"], true, "{what}: {check}");

            let ratio = num(&check, &["min_detj_ratio"]);
            let area = num(&check, &["total_area"]);
            assert!(
                (num(&stats, &["quality", "min_jacobian_ratio"]) - ratio).abs() <= 1e-6,
                "{what}"
            );
            assert!(
                (num(&stats, &["curve", "min_jacobian_ratio"]) - ratio).abs() <= 1e-6,
                "{what}"
            );
            assert!(
                (num(&stats, &["quality", "area"]) - area).abs() <= 1e-9,
                "{what}"
            );
            let regions: f64 = stats["regions"]["surfaces"]
                .as_array()
                .expect("surfaces")
                .iter()
                .map(|s| s["area"].as_f64().expect("area"))
                .sum();
            assert!(
                (regions - area).abs() <= 1e-9,
                "{what}: regions {regions}, check {area}"
            );

            let m = read_msh_file(&out).expect("read back");
            check_model(&m, &what);
        }
    }
}
