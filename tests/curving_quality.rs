//! The curving stage must not trade an element it cannot certify for needles.
//!
//! A flag of Albania (public domain, tests/fixtures/quality) has a vertex almost
//! on the chord line of a curved edge it faces; the curving repair used to split
//! that edge twice, and the halves were needles of 0.04° (AMIPS 750, fitted at
//! the 1 % Jacobian floor). The linear mesh's worst angle there is 4.9°. A repair
//! split now stays within the curved stop energy (or the worst of the faces it
//! replaces), so the element is fitted instead and the mesh keeps the linear
//! mesh's angles. The mesh is written under `target/test-out/curving_quality/`
//! and checked by the independent checker.

mod support;

use std::path::Path;
use triwild::{MshOptions, Params};

#[test]
fn curving_never_makes_needles_on_a_flag_of_albania() {
    let svg = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/quality/albania.svg");
    let drawing = triwild::load_file(&svg, &triwild::LoadOptions::DEFAULT).expect("the flag loads");
    let meshed =
        triwild::mesh_drawing(&drawing, &Params::DEFAULT, &triwild::RegionOptions::DEFAULT)
            .expect("the flag meshes");
    let path = support::out_dir("curving_quality").join("albania.msh");
    triwild::write_msh(&meshed.mesh, &path, MshOptions::DEFAULT).expect("write the mesh");
    support::check_msh(&path).assert_valid("albania");
    let q = &meshed.report.quality;
    let curve = meshed.report.curve.as_ref().expect("a curved mesh");
    // The straight mesh's worst angle is 4.90°; curving keeps the vertices.
    assert!(
        q.min_angle_deg > 4.0,
        "min angle {} ({curve:?})",
        q.min_angle_deg
    );
    assert!(q.max_amips < 10.0, "max AMIPS {}", q.max_amips);
    // The flag is still followed: no curved edge was left straight. The
    // largest distance is a fitted element's (4 here: its curved edge is
    // pulled off the curve to be certified), so it moves with the linear
    // mesh: measured 8.7e-5 (8b28e63), 1.2e-4 (the smoothing's Newton
    // decrement) and 6.2e-4 (the equalisation after the coarsening: 6 fitted
    // elements instead of 4, none on a 20-drawing dev sample), against 1.4e-3
    // for the quadratic mesh and 1.6e-3 for the straight one.
    assert_eq!(curve.straight_triangles, 0);
    assert!(
        curve.max_curve_distance_rel < 1e-3,
        "{}",
        curve.max_curve_distance_rel
    );
}

/// The curved optimization may not trade a badly curved element for a straight
/// sliver (the corner rule). On the butterflies of the dev set (GCompris, not
/// bundled: GPL), thin strokes meshed as areas run beside curves; the curved
/// collapses along them lowered the worst curved AMIPS from 540 to 94 but left
/// straight slivers of 0.92° where the linear mesh's worst angle was 8.2°. With
/// the rule the worst angle stays 8.0°. Skipped (said on stdout) without the
/// dev set.
#[test]
fn the_curved_stage_keeps_the_linear_meshs_corners_on_a_butterfly() {
    let Some((dir, _)) = support::devset::devset_files() else {
        return;
    };
    let svg = dir.join("gcompris/advanced_colors__resource__amber_butterfly.svg");
    let drawing =
        triwild::load_file(&svg, &triwild::LoadOptions::DEFAULT).expect("the butterfly loads");
    let params = Params::DEFAULT;
    let meshed = triwild::mesh_drawing(&drawing, &params, &triwild::RegionOptions::DEFAULT)
        .expect("the butterfly meshes");
    let path = support::out_dir("curving_quality_corners").join("butterfly.msh");
    triwild::write_msh(&meshed.mesh, &path, MshOptions::DEFAULT).expect("write the mesh");
    support::check_msh(&path).assert_valid("butterfly");
    let curve = meshed.report.curve.as_ref().expect("a curved mesh");
    let opt = &curve.optimization;
    assert!(
        opt.max_corner_amips_after
            <= opt
                .max_corner_amips_before
                .max(params.optimizer.stop_energy),
        "{opt:?}"
    );
    let linear = meshed.report.optimize.as_ref().expect("optimized");
    let q = &meshed.report.quality;
    assert!(
        q.min_angle_deg > 0.9 * linear.min_angle_deg.min(8.0),
        "min angle {} after curving, {} before ({opt:?})",
        q.min_angle_deg,
        linear.min_angle_deg
    );
}
