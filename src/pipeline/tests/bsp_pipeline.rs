//! TriWild's linear path end to end (`--mesher bsp --stop-after bsp`): features → exact BSP
//! → rounded linear mesh → .msh. Every drawing of `data/svg` and `tests/fixtures/bsp` is
//! meshed through the library API, written under `target/test-out/bsp/` (CI runs gmsh's
//! `mshcheck --strict` on them), read back with the independent reader of `tests/support`
//! and checked: valid (counter-clockwise, conforming, manifold), covering the padded box,
//! and every primary chord and secondary segment of the FeatureSet present as a chain of
//! feature line elements whose vertices lie within 1e-9·d of it, in a physical curve named
//! after the segment's source shape (`<name>-curve` when a surface has that name).
//!
//! The dev-set run is ignored (slow, needs the corpus):
//! `cargo test --release --lib pipeline::tests::bsp_pipeline -- --ignored --nocapture`.
#![allow(clippy::print_stdout, reason = "the dev-set run reports per file")]

use super::support::devset::{devset_files, svg_files};

use super::support::{Msh, check, out_dir, read_msh};
use crate::features::FeaturePiece;
use crate::pipeline::{self, Report, RunOptions};
use crate::{Drawing, Mesher, Params, Stage};
use kurbo::{Line, Point};
use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::time::Instant;

fn bsp_params() -> Params {
    Params::DEFAULT
        .with_mesher(Mesher::TriWild)
        .with_stop_after(Some(Stage::Bsp))
}

/// Node tag by exact position.
fn key(p: [f64; 2]) -> (u64, u64) {
    ((p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits())
}

/// What the conformance check found wrong, in words (empty: all good).
fn conformance_defects(drawing: &Drawing, params: &Params, m: &Msh) -> Vec<String> {
    let d = drawing.diagonal();
    let (_, fs) = super::stages::front(drawing, params, crate::budget::Deadline::NONE)
        .expect("the size field builds");
    let tol = 1e-9 * d;
    let pos: HashMap<u64, [f64; 2]> = m.nodes.iter().map(|&(t, x)| (t, [x[0], x[1]])).collect();
    let by_pos: HashMap<(u64, u64), u64> = m
        .nodes
        .iter()
        .map(|&(t, x)| (key([x[0], x[1]]), t))
        .collect();
    // Feature line elements: undirected edge -> names of its physical curves.
    let mut line_names: HashMap<(u64, u64), HashSet<&str>> = HashMap::new();
    let mut adj: HashMap<u64, Vec<u64>> = HashMap::new();
    for e in m.of_type(1) {
        let (a, b) = (e.nodes[0], e.nodes[1]);
        let names = line_names.entry((a.min(b), a.max(b))).or_default();
        for p in &e.physical {
            if let Some(n) = m.physical_names.get(&(1, *p)) {
                names.insert(n.as_str());
            }
        }
        adj.entry(a).or_default().push(b);
        adj.entry(b).or_default().push(a);
    }
    let mut defects = Vec::new();
    for (line, tag) in fs.conforming_input().segments {
        let source = match tag {
            FeaturePiece::Primary(id) => fs.primary[id.index()].source,
            FeaturePiece::Secondary { polyline, .. } => fs.secondary[polyline.index()].source,
        };
        let mut name = drawing.shapes[source.shape.index()].name();
        // Names are unique in a file: a curve named like a surface is written `<name>-curve`.
        if m.physical_names
            .iter()
            .any(|((dim, _), n)| *dim == 2 && *n == name)
        {
            name.push_str("-curve");
        }
        if let Err(e) = find_chain(line, &name, tol, &pos, &by_pos, &adj, &line_names) {
            // A secondary feature is kept within its ε-envelope, not exactly: the
            // clean-up of degenerate rounded triangles may move its vertices
            // so its ends need only a node of its curve within ε.
            let within_envelope = matches!(tag, FeaturePiece::Secondary { .. })
                && [line.p0, line.p1].iter().all(|p| {
                    line_names.iter().any(|(&(a, b), names)| {
                        names.contains(name.as_str())
                            && [a, b].iter().any(|t| {
                                Point::new(pos[t][0], pos[t][1]).distance(*p) <= fs.params.eps
                            })
                    })
                });
            if !within_envelope {
                defects.push(format!("{tag:?} {line:?} of {name}: {e}"));
            }
        }
    }
    defects
}

/// Search a chain of feature lines (in the curve `name`) from `line.p0` to `line.p1` whose
/// vertices are within `tol` of the segment and advance strictly along it.
fn find_chain(
    line: Line,
    name: &str,
    tol: f64,
    pos: &HashMap<u64, [f64; 2]>,
    by_pos: &HashMap<(u64, u64), u64>,
    adj: &HashMap<u64, Vec<u64>>,
    line_names: &HashMap<(u64, u64), HashSet<&str>>,
) -> Result<(), String> {
    let (a, b) = (line.p0, line.p1);
    let (Some(&ta), Some(&tb)) = (by_pos.get(&key([a.x, a.y])), by_pos.get(&key([b.x, b.y])))
    else {
        return Err("an endpoint is not a node".into());
    };
    if ta == tb {
        return Ok(());
    }
    let dir = b - a;
    let len2 = dir.hypot2();
    let along = |t: u64| {
        let p = pos[&t];
        let v = Point::new(p[0], p[1]) - a;
        (v.dot(dir) / len2, v.cross(dir).abs() / len2.sqrt())
    };
    let mut stack = vec![ta];
    let mut seen = HashSet::from([ta]);
    while let Some(u) = stack.pop() {
        if u == tb {
            return Ok(());
        }
        let (su, _) = along(u);
        for &w in adj.get(&u).map(Vec::as_slice).unwrap_or(&[]) {
            let (sw, dist) = along(w);
            let named = line_names[&(u.min(w), u.max(w))].contains(name);
            if named && dist <= tol && sw > su && seen.insert(w) {
                stack.push(w);
            }
        }
    }
    Err("no chain of feature lines along it".into())
}

/// One meshed and checked file.
struct Outcome {
    report: Report,
    seconds: f64,
    /// Defects of the written file and of its conformance, in words.
    defects: Vec<String>,
}

/// Mesh `svg` to `out` with the BSP path, read it back and check it.
fn mesh_and_check(svg: &Path, out: &Path) -> Result<Outcome, String> {
    let params = bsp_params();
    let drawing = crate::svg::load_file(svg, &crate::svg::LoadOptions::DEFAULT)
        .map_err(|e| format!("load: {e}"))?;
    let t = Instant::now();
    let report = pipeline::run_file(svg, out, &RunOptions::new(params.clone()))
        .map_err(|e| format!("mesh: {e}"))?;
    let seconds = t.elapsed().as_secs_f64();
    let m = read_msh(out).map_err(|e| format!("read back: {e}"))?;
    let r = check(&m);
    let mut defects: Vec<String> = r
        .defects
        .iter()
        .map(|d| format!("{:?}: {}", d.kind, d.detail))
        .collect();
    // The triangles tile the padded box.
    let pad = params.padding.resolve(drawing.diagonal());
    let b = drawing.bbox.inflate(pad, pad);
    if (r.area - b.area()).abs() > 1e-9 * b.area() {
        defects.push(format!("area {} is not the box's {}", r.area, b.area()));
    }
    let bsp = report.bsp.as_ref().ok_or("no bsp stats")?;
    if bsp.rational_vertices != 0 || r.nodes != bsp.vertices || r.triangles != bsp.triangles {
        defects.push(format!(
            "counts disagree: file {} nodes {} triangles, stats {bsp:?}",
            r.nodes, r.triangles
        ));
    }
    defects.extend(conformance_defects(&drawing, &params, &m));
    Ok(Outcome {
        report,
        seconds,
        defects,
    })
}

#[test]
fn sample_drawings_and_fixtures_mesh_valid_and_conforming() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    svg_files(&root.join("data/svg"), &mut files);
    let samples = files.len();
    svg_files(&root.join("tests/fixtures/bsp"), &mut files);
    assert!(samples >= 5 && files.len() >= samples + 4, "{files:?}");
    let dir = out_dir("bsp");
    for f in &files {
        let stem = f.file_stem().expect("a file name").to_string_lossy();
        let out = dir.join(format!("{stem}.msh"));
        let o = mesh_and_check(f, &out).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert!(
            o.defects.is_empty(),
            "{}: {} defects, first: {:#?}",
            f.display(),
            o.defects.len(),
            &o.defects[..o.defects.len().min(5)]
        );
        let bsp = o.report.bsp.as_ref().expect("bsp stats");
        assert!(bsp.tagged_edges > 0 && o.report.output.feature_edges > 0);
        assert!(o.report.times.contains_key("features") && o.report.times.contains_key("bsp"));
    }
}

#[test]
fn crossing_fixtures_exercise_crossing_splits_and_rational_vertices() {
    // Transversal crossings are split by the feature stage (both curves end at the
    // crossing point); what stays (beyond the 32 a piece is split at, shallow
    // crossings of secondary features) is refused as a constraint of the seed
    // and makes the BSP cut, and rational vertices appear, which rounding must
    // all remove.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/bsp");
    let dir = out_dir("bsp-crossings");
    let (mut cuts, mut rational) = (0, 0);
    for name in [
        "crossing-lines",
        "overlapping-circles",
        "t-junction",
        "near-parallel",
        "crossing-many",
    ] {
        let f = root.join(format!("{name}.svg"));
        let o = mesh_and_check(&f, &dir.join(format!("{name}.msh")))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let bsp = o.report.bsp.expect("bsp stats");
        assert_eq!(bsp.rational_vertices, 0, "{name}");
        cuts += bsp.cut_triangles;
        rational += bsp.rational_before_rounding;
        let features = o.report.features.expect("feature counts");
        if name == "crossing-lines" || name == "overlapping-circles" {
            assert!(features.crossing_splits >= 6, "{name}: {features:?}");
        }
    }
    assert!(cuts > 0 && rational > 0, "{cuts} cuts, {rational} rational");
}

#[test]
fn stop_after_bsp_needs_the_triwild_mesher() {
    let err = Params::DEFAULT
        .with_mesher(Mesher::Cdt)
        .with_stop_after(Some(Stage::Bsp))
        .validate()
        .expect_err("cdt cannot stop after bsp");
    assert_eq!(err.kind(), crate::ErrorKind::BadInput);
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

#[test]
#[ignore = "slow corpus run over ../shared/data/svg-dev (or TRIWILD_DEVSET)"]
fn devset_meshes_valid_and_conforming() {
    let Some((dir, files)) = devset_files() else {
        return;
    };
    let out = out_dir("bsp-devset");
    let (mut ok, mut unloadable, mut failed) = (0usize, 0usize, Vec::new());
    let (mut rational_before, mut rational_after, mut collapsed) = (0usize, 0usize, 0usize);
    let mut times = Vec::new();
    // seconds: load + features + bsp + write; bsp_s: the BSP stage alone.
    println!(
        "file\tseconds\tbsp_s\tvertices\ttriangles\trational_before\tcollapsed\trational_left\tvalid"
    );
    for (i, f) in files.iter().enumerate() {
        let name = f.strip_prefix(&dir).unwrap_or(f).display().to_string();
        if crate::svg::load_file(f, &crate::svg::LoadOptions::DEFAULT).is_err() {
            unloadable += 1;
            continue;
        }
        let msh = out.join(format!("{i:03}.msh"));
        let result = std::panic::catch_unwind(|| mesh_and_check(f, &msh));
        match result {
            Ok(Ok(o)) => {
                let b = o.report.bsp.as_ref().expect("bsp stats");
                let valid = o.defects.is_empty();
                println!(
                    "{name}\t{:.3}\t{:.3}\t{}\t{}\t{}\t{}\t{}\t{valid}",
                    o.seconds,
                    b.seconds,
                    b.vertices,
                    b.triangles,
                    b.rational_before_rounding,
                    b.collapsed_vertices,
                    b.rational_vertices
                );
                times.push(o.seconds);
                rational_before += b.rational_before_rounding;
                rational_after += b.rational_vertices;
                collapsed += b.collapsed_vertices;
                if valid {
                    ok += 1;
                } else {
                    println!("  {} defects, first: {}", o.defects.len(), o.defects[0]);
                    failed.push(name);
                }
            }
            Ok(Err(e)) => {
                println!("{name}\tFAILED: {e}");
                failed.push(name);
            }
            Err(_) => {
                println!("{name}\tPANICKED");
                failed.push(name);
            }
        }
    }
    let max = times.iter().copied().fold(0.0, f64::max);
    println!(
        "{} files: {ok} ok, {} failed, {unloadable} not loadable; time per file median {:.3} s, \
         max {max:.3} s; rational vertices before rounding {rational_before}, collapsed {collapsed}, left {rational_after}",
        files.len(),
        failed.len(),
        median(&mut times)
    );
    assert!(failed.is_empty(), "failed: {failed:?}");
}

/// What gmsh and `mshcheck --strict` reject in a straight mesh: triangles with
/// `|2·area| ≤ 1e-12·h²` (h² the squared extents of their bounding box) and
/// nodes within 1e-12 of the mesh's diagonal of each other.
fn rejected_by_gmsh(nodes: &[Point], triangles: &[[Point; 3]]) -> (usize, usize) {
    let degenerate = triangles
        .iter()
        .filter(|[a, b, c]| {
            let (xs, ys) = ([a.x, b.x, c.x], [a.y, b.y, c.y]);
            let ext = |v: [f64; 3]| {
                v.iter().copied().fold(f64::MIN, f64::max)
                    - v.iter().copied().fold(f64::MAX, f64::min)
            };
            (*b - *a).cross(*c - *a).abs() <= 1e-12 * (ext(xs).powi(2) + ext(ys).powi(2))
        })
        .count();
    let bbox = nodes
        .iter()
        .fold(kurbo::Rect::from_points(nodes[0], nodes[0]), |r, p| {
            r.union_pt(*p)
        });
    let q = 1e-12 * bbox.width().hypot(bbox.height());
    let cells: HashSet<(i64, i64)> = nodes
        .iter()
        .map(|p| ((p.x / q).round() as i64, (p.y / q).round() as i64))
        .collect();
    (degenerate, nodes.len() - cells.len())
}

/// Rounded to f64, the exact BSP mesh of this drawing has degenerate
/// triangles and coinciding vertices; the delivered `--stop-after bsp` mesh
/// has neither (they are collapsed, swapped or smoothed away). The drawing is
/// resvg's `M L M Z` path: a thick stroke over its own zero-area fill.
#[test]
fn rounding_degenerate_triangles_are_removed_from_the_bsp_output() {
    let f =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/bsp/rounding-degenerate.svg");
    let svg = std::fs::read(&f).expect("fixture");
    let drawing = crate::load_bytes(&svg, &crate::LoadOptions::DEFAULT).expect("load");
    let (raw, _, _) = super::bsp_mesh(&drawing, &bsp_params()).expect("bsp");
    let nodes: Vec<Point> = raw.vertices().map(|v| raw.position(v)).collect();
    let tris: Vec<[Point; 3]> = raw
        .faces()
        .map(|t| raw.face(t).map(|v| raw.position(v)))
        .collect();
    let (degenerate, duplicate) = rejected_by_gmsh(&nodes, &tris);
    assert!(
        degenerate + duplicate > 0,
        "the fixture no longer exercises the fix"
    );
    let params = bsp_params();
    let opts = crate::LoadOptions::from_params(&params).expect("valid parameters");
    let drawing = crate::load_bytes(&svg, &opts).expect("load");
    let meshed = pipeline::mesh_drawing(&drawing, &params, &crate::RegionOptions::DEFAULT)
        .expect("the bsp mesh");
    let m = &meshed.mesh;
    let tris: Vec<[Point; 3]> = (0..m.triangle_count()).map(|i| m.corners(i)).collect();
    assert_eq!(rejected_by_gmsh(&m.nodes, &tris), (0, 0));
}
