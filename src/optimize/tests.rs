//! Tests of the schedule: whole optimizations of random meshes (a constrained
//! Delaunay mesh with a curved primary chain and a secondary polyline; BSP
//! meshes of random segment soups) keep every invariant, end with every vertex
//! in `f64` and on its curve, improve the worst triangle, and are
//! deterministic. Fixed seeds.

use super::schedule::{OptimizeOptions, StopReason, optimize};
use crate::element::energy::amips;
use crate::mesh::TriMesh;
use crate::ops::tests::{assert_invariants, bsp_mesh, delaunay_mesh};
use crate::ops::{Context, EnergyRule};
use std::collections::HashMap;

fn max_energy(mesh: &TriMesh) -> f64 {
    mesh.faces()
        .map(|f| {
            let [a, b, c] = mesh.face(f).map(|v| mesh.position(v));
            amips(a, b, c)
        })
        .fold(0.0, f64::max)
}

fn options(l: f64) -> OptimizeOptions {
    OptimizeOptions {
        l,
        l_floor: 0.01,
        stop_energy: 5.0,
        alpha_deg: 10.0,
        max_passes: 40,
        max_vertices: 20_000,
        deadline: crate::budget::Deadline::NONE,
    }
}

fn run(mut mesh: TriMesh, mut ctx: Context, l: f64, what: &str) -> (TriMesh, f64, f64) {
    let before = max_energy(&mesh);
    let mut off = HashMap::new();
    assert_invariants(&mesh, &ctx, &mut off, what);
    let stats = optimize(&mut mesh, &mut ctx, &options(l));
    // Distances to the curve may only have shrunk, and all are now within tolerance.
    assert_invariants(&mesh, &ctx, &mut off, what);
    assert_eq!(stats.rational_left, 0, "{what}: {stats:?}");
    assert!(mesh.vertices().all(|v| !mesh.is_rational(v)), "{what}");
    assert_eq!(stats.off_curve_left, 0, "{what}: {stats:?}");
    for v in mesh.vertices() {
        if let Some(d) = crate::ops::invariants::on_curve::off_curve(&mesh, &ctx, v) {
            assert!(d <= ctx.on_curve_abs, "{what}: {v:?} is {d} off its curve");
        }
    }
    let after = max_energy(&mesh);
    assert_eq!(after, stats.max_amips, "{what}");
    assert!(stats.passes >= 1 && stats.passes <= 40, "{what}: {stats:?}");
    (mesh, before, after)
}

#[test]
fn optimizing_delaunay_meshes_keeps_invariants_and_meets_the_goal() {
    for seed in 0..4 {
        let (mesh, ctx) = delaunay_mesh(seed, EnergyRule::NoWorseMax);
        let what = format!("delaunay seed {seed}");
        let (out, before, after) = run(mesh, ctx, 0.1, &what);
        assert!(after <= before.max(5.0), "{what}: {before} -> {after}");
        assert!(out.num_faces() > 0);
    }
}

#[test]
fn optimizing_bsp_meshes_turns_slivers_into_good_triangles() {
    let mut improved = 0;
    for seed in 0..8 {
        let (mesh, ctx) = bsp_mesh(seed, EnergyRule::NoWorseMax);
        let what = format!("bsp seed {seed}");
        let (_, before, after) = run(mesh, ctx, 0.1, &what);
        assert!(after.is_finite(), "{what}");
        if after < before {
            improved += 1;
        }
    }
    // BSP meshes start with slivers; the optimizer must fix most of them (some
    // soups have input angles that bound the quality from above).
    assert!(improved >= 6, "{improved} of 8 improved");
}

#[test]
fn the_goal_stops_the_passes_early_and_the_result_is_deterministic() {
    let (mesh, ctx) = delaunay_mesh(1, EnergyRule::NoWorseMax);
    let (mut a, mut b) = (mesh.clone(), mesh);
    let (mut ca, mut cb) = (ctx.clone(), ctx);
    let sa = optimize(&mut a, &mut ca, &options(0.1));
    let sb = optimize(&mut b, &mut cb, &options(0.1));
    assert!(a == b, "two runs differ");
    assert_eq!(sa, sb);
    assert_ne!(sa.stop, StopReason::PassLimit, "{sa:?}");
    assert!(sa.min_angle_deg > 10.0 || sa.max_amips < 5.0, "{sa:?}");
    assert!(sa.split.applied > 0 && sa.smooth.applied > 0, "{sa:?}");
}

#[test]
fn the_sizing_field_bounds_edge_lengths_by_l() {
    let (mut mesh, mut ctx) = delaunay_mesh(2, EnergyRule::NoWorseMax);
    let l = 0.08;
    let stats = optimize(&mut mesh, &mut ctx, &options(l));
    let longest = mesh
        .faces()
        .flat_map(|f| {
            let [a, b, c] = mesh.face(f).map(|v| mesh.position(v));
            [a.distance(b), b.distance(c), c.distance(a)]
        })
        .fold(0.0, f64::max);
    // Split above 4/3 l each pass until settled: nothing is much longer than l.
    // The final coarsening makes edges up to 2 l and the polish after it keeps
    // them so, but the min-max polish, which lifts the worst triangles, may
    // stretch a few a little (2.03 l here; on a circle at -l 0.0125, 2.39 l
    // before the bound existed).
    assert!(
        longest <= 2.25 * l,
        "longest {longest} with l = {l}: {stats:?}"
    );
}
