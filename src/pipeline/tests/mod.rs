//! White-box tests of the whole pipeline: they build realistic meshes from the front
//! stages (load, features, BSP, optimization) and inspect the intermediate meshes and
//! feature sets that the public API does not show. They live here, at the top of the
//! module graph, so no lower module imports anything above it.
//!
//! Every mesh they write goes under `target/test-out/<test>/`, which CI validates with
//! `shared/bench/mshcheck.py --strict`, and through the independent reader and checker
//! of `tests/support` (shared with the integration tests, sharing nothing with the code
//! it checks).

#[path = "../../../tests/support/mod.rs"]
#[allow(
    unreachable_pub,
    reason = "the support module is written for the integration tests, where pub(crate) is the crate"
)]
mod support;

mod bsp_pipeline;
mod conics;
mod curved_ops;
mod curving;
mod features_devset;
mod optimize_pipeline;

use super::stages::{self, Front, Linear, Log, StageOptions};
use crate::budget::Deadline;
use crate::features::FeatureSet;
use crate::mesh::TriMesh;
use crate::ops::Context;
use crate::optimize::OptimizeStats;
use crate::{Drawing, Params, Result};

/// The exact BSP mesh of a drawing's features as the pipeline makes it
/// ([`stages::front`], then [`stages::bsp_stage`], default regions, no time
/// limit): the rounded [`TriMesh`], the feature set its tags index, and the
/// operations' [`Context`]. Vertices the BSP could not round stay rational.
///
/// # Errors
/// Invalid parameters, or as the stages.
fn bsp_mesh(drawing: &Drawing, params: &Params) -> Result<(TriMesh, FeatureSet, Context)> {
    let (linear, features, _) = linear_mesh(drawing, params, false)?;
    Ok((linear.mesh, features, linear.ctx))
}

/// [`bsp_mesh`] followed by the optimizer ([`stages::optimize_stage`]), with
/// what it did. The mesh may still hold rational vertices or off-curve primary
/// vertices when the stats say so (the pipeline refuses to write the former
/// and warns about the latter).
///
/// # Errors
/// As [`bsp_mesh`].
fn optimized_mesh(
    drawing: &Drawing,
    params: &Params,
) -> Result<(TriMesh, FeatureSet, Context, OptimizeStats)> {
    let (linear, features, stats) = linear_mesh(drawing, params, true)?;
    let stats = stats.expect("internal: optimized");
    Ok((linear.mesh, features, linear.ctx, stats))
}

/// The front, the BSP stage and (if `optimize`) the optimizer, on `drawing`.
fn linear_mesh(
    drawing: &Drawing,
    params: &Params,
    optimize: bool,
) -> Result<(Linear, FeatureSet, Option<OptimizeStats>)> {
    params.validate()?;
    let (field, features) = stages::front(drawing, params, Deadline::NONE)?;
    let opts = StageOptions::default_regions(params, drawing, Deadline::NONE);
    let front = Front {
        drawing,
        field: &field,
        features,
    };
    let mut log = Log::default();
    let (mut linear, _) = stages::bsp_stage(&front, &opts, &mut log)?;
    let stats = if optimize {
        Some(stages::optimize_stage(&front, &mut linear, &opts, &mut log)?.0)
    } else {
        None
    };
    Ok((linear, front.features, stats))
}

/// The optimizer's options for `drawing` under `params`, as the pipeline
/// builds them ([`StageOptions::optimize`]), with no time limit.
fn optimize_options(drawing: &Drawing, params: &Params) -> crate::optimize::OptimizeOptions {
    StageOptions::default_regions(params, drawing, Deadline::NONE).optimize()
}

/// An unforced element below the Jacobian ratio floor is reported in a
/// warning (how many, the worst and where); none below it, no warning.
#[test]
fn low_ratio_warning_names_the_count_and_the_worst() {
    use crate::quality::{Unforced, WorstElement};
    let worst = WorstElement {
        element: 7,
        x: 1.5,
        y: -2.0,
        min_angle_deg: 30.0,
        jacobian_ratio: 0.05,
    };
    let mut u = Unforced {
        min_angle_deg: 30.0,
        min_jacobian_ratio: 0.05,
        below_alpha: 0,
        below_ratio_floor: 2,
        forced_corners: 0,
        forced_by_angle: 0,
        corners: 30,
        forced_elements: 0,
        worst: Some(worst),
        worst_ratio: Some(worst),
    };
    let w = super::warnings::low_ratio_warning(&u).expect("a warning");
    assert!(w.starts_with("2 unforced element(s)"), "{w}");
    assert!(
        w.contains("0.050") && w.contains("(1.500000, -2.000000)"),
        "{w}"
    );
    u.below_ratio_floor = 0;
    assert_eq!(super::warnings::low_ratio_warning(&u), None);
}
