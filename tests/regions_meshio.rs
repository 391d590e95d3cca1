//! Regions on real drawings: on a CI sample (the bundled
//! `data/svg` drawings plus a few small dev-set files) and, ignored, on the whole
//! dev set (`../shared/data/svg-dev` or `TRIWILD_DEVSET`):
//! - every region area of the report sums to the area of the meshed box (1e-9
//!   relative), each region's area and triangle count match the mesh itself, and
//!   every element is in a physical group;
//! - the CI sample is written as MSH 4.1 and 2.2 (ASCII, and one binary of each)
//!   under `target/test-out/regions_meshio/`, each file with a JSON sidecar
//!   `<file>.json` naming the physical groups it must hold (name, dim, tag,
//!   element count). `.ci/meshio_check.py` reads every sidecar's mesh with meshio
//!   and checks the cell tags against it (run from `.ci/run`).
//!
//! Whole dev set: `cargo test --release --test regions_meshio -- --ignored --nocapture`.
#![allow(
    clippy::print_stdout,
    reason = "the corpus runs report their numbers with --nocapture"
)]

use kurbo::{Point, Rect};
use std::path::{Path, PathBuf};
use std::time::Instant;
use triwild::Params;
use triwild::{FemMesh, LineKind};
use triwild::{Meshed, RegionOptions, mesh_drawing};
use triwild::{MshOptions, MshVersion};

mod support;

use support::devset::{devset_dir, svg_files};

/// The bundled drawings of `data/svg`, in sorted order.
fn bundled() -> Vec<PathBuf> {
    let mut files = Vec::new();
    svg_files(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg"),
        &mut files,
    );
    files
}

/// CI's dev-set sample: five files under 20 KB spread evenly over the sorted dev
/// set (so several collections), or nothing when the dev set is absent.
fn devset_sample() -> Vec<PathBuf> {
    let mut files = Vec::new();
    svg_files(&devset_dir(), &mut files);
    files.retain(|f| std::fs::metadata(f).is_ok_and(|m| m.len() < 20_000));
    let step = (files.len() / 5).max(1);
    files.into_iter().step_by(step).take(5).collect()
}

/// The axis-aligned box of the mesh's nodes.
fn node_box(mesh: &FemMesh) -> Rect {
    mesh.nodes.iter().fold(
        Rect::new(
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ),
        |r, p| Rect::new(r.x0.min(p.x), r.y0.min(p.y), r.x1.max(p.x), r.y1.max(p.y)),
    )
}

/// The exact area of a Lagrange triangle of any order (gmsh node order), by
/// Green's theorem on its three polynomial edges: `½ ∮ x dy − y dx`, with a
/// Gauss rule exact for the degree (at most 5) of the integrand.
fn element_area(nodes: &[Point]) -> f64 {
    // The nodes of each edge from its first corner to its second, evenly spaced.
    let edges: Vec<Vec<Point>> = match nodes.len() {
        3 => vec![
            vec![nodes[0], nodes[1]],
            vec![nodes[1], nodes[2]],
            vec![nodes[2], nodes[0]],
        ],
        6 => vec![
            vec![nodes[0], nodes[3], nodes[1]],
            vec![nodes[1], nodes[4], nodes[2]],
            vec![nodes[2], nodes[5], nodes[0]],
        ],
        10 => vec![
            vec![nodes[0], nodes[3], nodes[4], nodes[1]],
            vec![nodes[1], nodes[5], nodes[6], nodes[2]],
            vec![nodes[2], nodes[7], nodes[8], nodes[0]],
        ],
        n => panic!("{n} nodes per triangle"),
    };
    // 4-point Gauss-Legendre on [0, 1]: exact to degree 7.
    let g = [
        (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
        (0.330_009_478_207_571_9, 0.326_072_577_431_273_07),
        (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
        (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
    ];
    let mut area = 0.0;
    for e in &edges {
        let k = e.len() - 1;
        // Lagrange basis on the nodes s_i = i / k and its derivative.
        let basis = |s: f64| -> (Vec<f64>, Vec<f64>) {
            let xs: Vec<f64> = (0..=k).map(|i| i as f64 / k as f64).collect();
            let mut l = vec![0.0; k + 1];
            let mut dl = vec![0.0; k + 1];
            for i in 0..=k {
                let mut v = 1.0;
                for j in (0..=k).filter(|&j| j != i) {
                    v *= (s - xs[j]) / (xs[i] - xs[j]);
                }
                l[i] = v;
                let mut dv = 0.0;
                for m in (0..=k).filter(|&m| m != i) {
                    let mut t = 1.0 / (xs[i] - xs[m]);
                    for j in (0..=k).filter(|&j| j != i && j != m) {
                        t *= (s - xs[j]) / (xs[i] - xs[j]);
                    }
                    dv += t;
                }
                dl[i] = dv;
            }
            (l, dl)
        };
        for (s, w) in g {
            let (l, dl) = basis(s);
            let (mut x, mut y, mut dx, mut dy) = (0.0, 0.0, 0.0, 0.0);
            for i in 0..=k {
                x += l[i] * e[i].x;
                y += l[i] * e[i].y;
                dx += dl[i] * e[i].x;
                dy += dl[i] * e[i].y;
            }
            area += 0.5 * w * (x * dy - y * dx);
        }
    }
    area
}

/// Every defect of the region sums and physical groups of `m` (empty: all good).
/// The box is the nodes' bounding box, which must contain the drawing.
fn region_defects(m: &Meshed, drawing_box: Rect) -> Vec<String> {
    let mesh = &m.mesh;
    let stats = &m.report.regions.surfaces;
    let mut defects = Vec::new();
    // Every element is in a physical group, and every group has elements.
    if mesh.triangle_group.len() != mesh.triangle_count() {
        defects.push(format!(
            "{} triangle groups for {} triangles",
            mesh.triangle_group.len(),
            mesh.triangle_count()
        ));
        return defects;
    }
    if mesh.line_group.len() != mesh.line_count() {
        defects.push(format!(
            "{} line groups for {} lines",
            mesh.line_group.len(),
            mesh.line_count()
        ));
        return defects;
    }
    let mut tris = vec![0usize; mesh.surfaces.len()];
    let mut areas = vec![0.0f64; mesh.surfaces.len()];
    for (i, &g) in mesh.triangle_group.iter().enumerate() {
        match tris.get_mut(g as usize) {
            Some(n) => {
                *n += 1;
                let nodes: Vec<Point> = mesh
                    .triangle(i)
                    .iter()
                    .map(|&n| mesh.nodes[n as usize])
                    .collect();
                areas[g as usize] += element_area(&nodes);
            }
            None => defects.push(format!("triangle {i} in surface {g} of {}", tris.len())),
        }
    }
    let mut lines = vec![0usize; mesh.curves.len()];
    for (i, &g) in mesh.line_group.iter().enumerate() {
        match lines.get_mut(g as usize) {
            Some(n) => *n += 1,
            None => defects.push(format!("line {i} in curve {g} of {}", lines.len())),
        }
    }
    for (name, n) in mesh.surfaces.iter().zip(&tris) {
        if *n == 0 {
            defects.push(format!("surface {name} has no triangle"));
        }
    }
    for (name, n) in mesh.curves.iter().zip(&lines) {
        if *n == 0 {
            defects.push(format!("curve {name} has no line"));
        }
    }
    // The report's stats are the mesh's surfaces, counts and (straight) areas.
    let stat_names: Vec<&String> = stats.iter().map(|s| &s.name).collect();
    let surface_names: Vec<&String> = mesh.surfaces.iter().collect();
    if stat_names != surface_names {
        defects.push(format!(
            "stats {stat_names:?} vs surfaces {surface_names:?}"
        ));
    }
    let total_area: f64 = areas.iter().sum();
    for (s, (n, a)) in stats.iter().zip(tris.iter().zip(&areas)) {
        if s.triangles != *n {
            defects.push(format!(
                "{}: {} triangles in stats, {n} in mesh",
                s.name, s.triangles
            ));
        }
        if (s.area - a).abs() > 1e-9 * total_area.abs().max(f64::MIN_POSITIVE) {
            defects.push(format!("{}: area {} in stats, {a} in mesh", s.name, s.area));
        }
    }
    // The regions tile the box: their areas add up to its area.
    let bx = node_box(mesh);
    if !(bx.contains(drawing_box.origin()) && bx.x1 >= drawing_box.x1 && bx.y1 >= drawing_box.y1) {
        defects.push(format!(
            "mesh box {bx:?} does not cover the drawing {drawing_box:?}"
        ));
    }
    let sum: f64 = stats.iter().map(|s| s.area).sum();
    let box_area = bx.area();
    // Written so that a NaN sum is a defect.
    let within = (sum - box_area).abs() <= 1e-9 * box_area;
    if !within {
        defects.push(format!(
            "region areas sum to {sum}, box area {box_area} (rel {:.2e})",
            (sum - box_area).abs() / box_area
        ));
    }
    defects
}

/// The physical groups `mesh` must show once written: surfaces (dim 2) then
/// curves (dim 1), tag = index + 1, with their element counts, named as the
/// writer documents (`src/output/msh.rs`): names are unique in a file; the
/// domain's boundary (the curve of `LineKind::Boundary` lines) is named first,
/// then surfaces, then the other curves; a name already taken gets `-surface`
/// / `-curve`, then `-…-N` (N = 2, 3, …). The sample's names are short and
/// plain, so no cleaning applies.
fn expected_groups(mesh: &FemMesh) -> serde_json::Value {
    let mut taken = std::collections::HashSet::new();
    let boundary: Vec<bool> = (0..mesh.curves.len())
        .map(|g| {
            (0..mesh.line_count()).any(|i| {
                mesh.line_group[i] as usize == g && mesh.line_kind[i] == LineKind::Boundary
            })
        })
        .collect();
    let mut all = Vec::new();
    for (dim, names, members, kind) in [
        (2, &mesh.surfaces, &mesh.triangle_group, "-surface"),
        (1, &mesh.curves, &mesh.line_group, "-curve"),
    ] {
        for (i, name) in names.iter().enumerate() {
            assert!(
                name.len() < 100 && !name.contains('"') && !name.contains(char::is_control),
                "sample names are plain: {name:?}"
            );
            let first = dim == 1 && boundary[i];
            all.push((first, dim, i, name, members, kind));
        }
    }
    // Naming order: the boundary, then the rest as listed (stable sort).
    let mut naming: Vec<usize> = (0..all.len()).collect();
    naming.sort_by_key(|&k| !all[k].0);
    let mut written_names = vec![String::new(); all.len()];
    for k in naming {
        let (_, _, _, name, _, kind) = all[k];
        let mut written = name.clone();
        if taken.contains(&written) {
            written = format!("{name}{kind}");
        }
        let mut n = 2;
        while taken.contains(&written) {
            written = format!("{name}{kind}-{n}");
            n += 1;
        }
        taken.insert(written.clone());
        written_names[k] = written;
    }
    let groups: Vec<serde_json::Value> = all
        .iter()
        .zip(written_names)
        .map(|(&(_, dim, i, name, members, _), written)| {
            let count = members.iter().filter(|&&g| g as usize == i).count();
            serde_json::json!({
                "name": written, "mesh_name": name, "dim": dim, "tag": i + 1, "elements": count,
            })
        })
        .collect();
    serde_json::Value::Array(groups)
}

/// The number of distinct edges among `mesh`'s line elements (MSH 4.1 writes
/// one element per edge, listed by every physical curve on it).
fn distinct_lines(mesh: &FemMesh) -> usize {
    let nodes = mesh.order().line_nodes();
    mesh.lines
        .chunks(nodes)
        .map(|l| (l[0].min(l[1]), l[0].max(l[1])))
        .collect::<std::collections::HashSet<_>>()
        .len()
}

/// Write `mesh` as `<stem>-<version>.msh` (ASCII, plus binary when asked) in
/// `dir`, each with its sidecar `<file>.json`. Returns the files written.
fn write_with_sidecars(mesh: &FemMesh, dir: &Path, stem: &str, binary: bool) -> Vec<PathBuf> {
    let groups = expected_groups(mesh);
    let mut written = Vec::new();
    for (version, tag) in [(MshVersion::V41, "v41"), (MshVersion::V22, "v22")] {
        for bin in [false, true] {
            if bin && !binary {
                continue;
            }
            let name = format!("{stem}-{tag}{}.msh", if bin { "-bin" } else { "" });
            let path = dir.join(&name);
            let opts = MshOptions {
                version,
                binary: bin,
            };
            triwild::write_msh(mesh, &path, opts).expect("msh written");
            let sidecar = serde_json::json!({
                "msh": name,
                "version": tag,
                "binary": bin,
                "nodes": mesh.nodes.len(),
                "triangles": mesh.triangle_count(),
                "lines": mesh.line_count(),
                // 4.1 writes an edge on several physical curves once
                "distinct_lines": distinct_lines(mesh),
                "groups": groups,
            });
            let text = serde_json::to_string_pretty(&sidecar).expect("json");
            std::fs::write(dir.join(format!("{name}.json")), text).expect("sidecar written");
            written.push(path);
        }
    }
    written
}

/// A file name safe stem for `f` (its path below the dev set or `data/svg`).
fn stem_of(f: &Path) -> String {
    let rel = f
        .strip_prefix(devset_dir())
        .or_else(|_| f.strip_prefix(Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg")))
        .unwrap_or(f);
    rel.with_extension("")
        .to_string_lossy()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// What a corpus run found.
#[derive(Default)]
struct Tally {
    checked: usize,
    unloadable: Vec<String>,
    failed_meshing: Vec<String>,
    defective: Vec<String>,
    worst_rel: f64,
}

/// Mesh each file with the defaults and check its regions; when `out` is given,
/// write it there with sidecars (the first file also in binary).
fn run(files: &[PathBuf], out: Option<&Path>) -> Tally {
    let mut t = Tally::default();
    let start = Instant::now();
    for f in files {
        let name = f.display().to_string();
        let Ok(drawing) = triwild::load_file(f, &triwild::LoadOptions::DEFAULT) else {
            t.unloadable.push(name);
            continue;
        };
        let t0 = Instant::now();
        let m = match mesh_drawing(&drawing, &Params::DEFAULT, &RegionOptions::DEFAULT) {
            Ok(m) => m,
            Err(e) => {
                println!("{name}: meshing failed: {e}");
                t.failed_meshing.push(name);
                continue;
            }
        };
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        t.checked += 1;
        let bx = node_box(&m.mesh);
        let sum: f64 = m.report.regions.surfaces.iter().map(|s| s.area).sum();
        let rel = (sum - bx.area()).abs() / bx.area();
        t.worst_rel = t.worst_rel.max(rel);
        let defects = region_defects(&m, drawing.bbox);
        println!(
            "{name}\t{} triangles\t{} surfaces\t{} curves\tsum rel err {rel:.2e}\t{ms:.0} ms",
            m.mesh.triangle_count(),
            m.mesh.surfaces.len(),
            m.mesh.curves.len()
        );
        if !defects.is_empty() {
            println!("  {} defects, first: {}", defects.len(), defects[0]);
            t.defective.push(name);
            continue;
        }
        if let Some(dir) = out {
            write_with_sidecars(&m.mesh, dir, &stem_of(f), t.checked == 1);
        }
    }
    println!(
        "{} files: {} checked, {} not loadable, {} failed meshing, {} with region defects; \
         worst |sum - box| / box = {:.2e}; {:.1} s",
        files.len(),
        t.checked,
        t.unloadable.len(),
        t.failed_meshing.len(),
        t.defective.len(),
        t.worst_rel,
        start.elapsed().as_secs_f64()
    );
    t
}

/// CI: the bundled drawings and a few dev files mesh, tile the box with their
/// regions, tag every element, and are written (4.1, 2.2, ASCII and binary) with
/// sidecars for `.ci/meshio_check.py`.
#[test]
fn ci_sample_regions_sum_to_the_box_and_are_written_for_meshio() {
    let dir = support::out_dir("regions_meshio");
    let bundled = bundled();
    assert_eq!(bundled.len(), 5, "data/svg holds the five bundled drawings");
    let sample = devset_sample();
    if sample.is_empty() {
        println!(
            "no dev set at {}: bundled drawings only",
            devset_dir().display()
        );
    }
    let files: Vec<PathBuf> = bundled.into_iter().chain(sample).collect();
    let t = run(&files, Some(&dir));
    assert!(
        t.defective.is_empty(),
        "region defects in {:?}",
        t.defective
    );
    assert!(
        t.failed_meshing.is_empty() && t.unloadable.is_empty(),
        "the CI sample must mesh: {:?} {:?}",
        t.failed_meshing,
        t.unloadable
    );
    let sidecars = std::fs::read_dir(&dir)
        .expect("out dir")
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "json"))
        })
        .count();
    assert_eq!(
        sidecars,
        2 * files.len() + 2,
        "one sidecar per written mesh"
    );
}

/// The whole dev set: every file that meshes has regions summing to the box
/// and every element in a physical group. Meshing failures are counted and
/// listed (they belong to the meshers), region defects fail the test.
#[test]
#[ignore = "slow corpus run; needs ../shared/data/svg-dev"]
fn devset_regions_sum_to_the_box() {
    let dir = devset_dir();
    let mut files = Vec::new();
    svg_files(&dir, &mut files);
    assert!(!files.is_empty(), "no .svg under {}", dir.display());
    let t = run(&files, None);
    println!("not loadable: {:?}", t.unloadable);
    println!("failed meshing: {:?}", t.failed_meshing);
    assert!(t.checked > 0, "nothing meshed");
    assert!(
        t.defective.is_empty(),
        "region defects in {:?}",
        t.defective
    );
}
