//! The optimized linear mesh, checked independently of the
//! optimizer's own bookkeeping:
//! - the mesh is valid (`TriMesh::check`), every vertex is an `f64` point;
//! - every vertex of a primary feature edge lies within 1e-9·d of its section's
//!   curve, measured as the distance to the curve piece (dense sampling refined
//!   by golden-section search on the parameter), not through the parameter the
//!   optimizer tracks;
//! - every secondary feature edge lies within ε of its input polyline, sampled
//!   every ε/8 along the edge against every segment of the polyline;
//! - the written .msh (`--linear`) is read back and valid, for gmsh's strict
//!   check in CI.
//!
//! The CI sample is the bundled drawings plus a few small dev files; the whole
//! dev set is an ignored run:
//! `cargo test --release --lib pipeline::tests::optimize_pipeline -- --ignored --nocapture`.
#![allow(clippy::print_stdout, reason = "the dev-set run reports per file")]

use super::support::devset::{devset_dir, devset_files, svg_files};
use super::support::{check_msh, out_dir};
use crate::features::Parent;
use crate::mesh::FeatureOn;
use crate::pipeline::{self, RunOptions};
use crate::{Params, Stage};
use kurbo::{Line, ParamCurveNearest, Point};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The distance from `p` to the piece `[t0, t1]` of `parent`.
fn distance_to_piece(parent: &Parent, t: [f64; 2], p: Point) -> f64 {
    let (lo, hi) = (t[0].min(t[1]), t[0].max(t[1]));
    if let Parent::Line(l) = parent {
        let a = parent.eval(lo);
        let b = parent.eval(hi);
        let _ = l;
        return Line::new(a, b).nearest(p, 1e-12).distance_sq.sqrt();
    }
    const N: usize = 64;
    let at = |s: f64| parent.eval(s).distance(p);
    let mut best = (lo, at(lo));
    for i in 1..=N {
        let s = lo + (hi - lo) * i as f64 / N as f64;
        let d = at(s);
        if d < best.1 {
            best = (s, d);
        }
    }
    // Golden-section search around the best sample.
    let h = (hi - lo) / N as f64;
    let (mut a, mut b) = ((best.0 - h).max(lo), (best.0 + h).min(hi));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..80 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if at(c) < at(d) {
            b = d;
        } else {
            a = c;
        }
    }
    best.1.min(at(0.5 * (a + b)))
}

fn distance_to_polyline(points: &[Point], p: Point) -> f64 {
    points
        .windows(2)
        .map(|w| Line::new(w[0], w[1]).nearest(p, 1e-12).distance_sq.sqrt())
        .fold(f64::INFINITY, f64::min)
        .min(points.first().map_or(f64::INFINITY, |q| q.distance(p)))
}

/// What one file measured.
#[derive(Debug, Default)]
struct Summary {
    triangles: usize,
    /// Largest primary-vertex distance to its curve, relative to d.
    primary_rel: f64,
    /// Largest secondary-edge distance to its polyline, relative to ε.
    secondary_rel: f64,
    seconds: f64,
}

/// Optimize `svg` and check it; the defects in words.
fn optimize_and_check(svg: &Path) -> Result<Summary, Vec<String>> {
    let drawing = crate::svg::load_file(svg, &crate::svg::LoadOptions::DEFAULT)
        .map_err(|e| vec![format!("load: {e}")])?;
    let d = drawing.diagonal();
    let params = Params::DEFAULT;
    let t = Instant::now();
    let (mesh, fs, ctx, stats) =
        super::optimized_mesh(&drawing, &params).map_err(|e| vec![format!("mesh: {e}")])?;
    let seconds = t.elapsed().as_secs_f64();
    let eps = params.resolve(d).eps;
    let mut defects: Vec<String> = mesh
        .check()
        .iter()
        .take(3)
        .map(|x| format!("{x:?}"))
        .collect();
    let rational = mesh.vertices().filter(|&v| mesh.is_rational(v)).count();
    if rational > 0 || stats.rational_left > 0 {
        defects.push(format!("{rational} rational vertices"));
    }
    let mut s = Summary {
        triangles: mesh.num_faces(),
        seconds,
        ..Summary::default()
    };
    for (k, tags) in mesh.tagged_edges() {
        let (a, b) = (mesh.position(k.lo), mesh.position(k.hi));
        for tag in tags {
            match *tag {
                FeatureOn::Primary { section, .. } => {
                    let sec = &ctx.sections[section as usize];
                    for p in [a, b] {
                        let dist = distance_to_piece(&sec.parent, sec.t, p);
                        s.primary_rel = s.primary_rel.max(dist / d);
                        if dist > 1e-9 * d {
                            defects.push(format!("primary vertex {p:?} is {dist:e} off its curve"));
                        }
                    }
                }
                FeatureOn::Secondary { polyline } => {
                    let pl = &fs.secondary[polyline as usize].points;
                    let n = ((a.distance(b) / (eps / 8.0)).ceil() as usize).clamp(1, 100_000);
                    for i in 0..=n {
                        let p = a.lerp(b, i as f64 / n as f64);
                        let dist = distance_to_polyline(pl, p);
                        s.secondary_rel = s.secondary_rel.max(dist / eps);
                        if dist > eps * (1.0 + 1e-9) {
                            defects.push(format!(
                                "secondary edge {a:?}-{b:?} is {dist:e} > ε = {eps:e} from its polyline"
                            ));
                            break;
                        }
                    }
                }
            }
        }
    }
    if defects.is_empty() {
        Ok(s)
    } else {
        defects.truncate(5);
        Err(defects)
    }
}

fn ci_sample() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    svg_files(&root.join("data/svg"), &mut files);
    let mut dev = Vec::new();
    svg_files(&devset_dir(), &mut dev);
    // A few small dev files spread over the collections (sorted, so fixed).
    let small: Vec<PathBuf> = dev
        .into_iter()
        .filter(|p| std::fs::metadata(p).is_ok_and(|m| m.len() < 6_000))
        .collect();
    let step = (small.len() / 6).max(1);
    files.extend(small.into_iter().step_by(step).take(6));
    files
}

#[test]
fn optimized_meshes_keep_primary_vertices_on_curves_and_secondary_edges_in_the_envelope() {
    let files = ci_sample();
    assert!(files.len() >= 5, "{files:?}");
    let dir = out_dir("optimize");
    for f in &files {
        let s = optimize_and_check(f).unwrap_or_else(|e| panic!("{}: {e:#?}", f.display()));
        assert!(s.triangles > 0);
        // The written --linear mesh, for the independent reader here and gmsh in CI.
        let stem = f.file_stem().expect("a file name").to_string_lossy();
        let out = dir.join(format!("{stem}.msh"));
        let params = Params::DEFAULT.with_stop_after(Some(Stage::Optimize));
        let report = pipeline::run_file(f, &out, &RunOptions::new(params))
            .unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let o = report.optimize.expect("optimizer stats");
        assert_eq!(o.rational_left, 0);
        assert_eq!(o.off_curve_left, 0, "{}", f.display());
        check_msh(&out).assert_valid(&stem);
    }
}

#[test]
#[ignore = "slow corpus run over ../shared/data/svg-dev (or TRIWILD_DEVSET)"]
fn devset_optimized_meshes_meet_the_invariants() {
    let Some((_, files)) = devset_files() else {
        return;
    };
    let (mut ok, mut bad_input, mut failed) = (0, 0, Vec::new());
    let (mut worst_p, mut worst_s, mut total) = (0f64, 0f64, 0f64);
    for f in &files {
        if crate::svg::load_file(f, &crate::svg::LoadOptions::DEFAULT).is_err() {
            bad_input += 1;
            continue;
        }
        match optimize_and_check(f) {
            Ok(s) => {
                ok += 1;
                worst_p = worst_p.max(s.primary_rel);
                worst_s = worst_s.max(s.secondary_rel);
                total += s.seconds;
                println!(
                    "ok {:>8} tris {:>7.3}s {}",
                    s.triangles,
                    s.seconds,
                    f.display()
                );
            }
            Err(e) => {
                println!("FAIL {}: {e:?}", f.display());
                failed.push(f.clone());
            }
        }
    }
    println!(
        "{ok} ok, {bad_input} bad input, {} failed; worst primary distance {worst_p:e}·d, \
         worst secondary distance {worst_s:.3}·ε; {total:.1}s optimizing",
        failed.len()
    );
    assert!(failed.is_empty(), "{failed:#?}");
}
