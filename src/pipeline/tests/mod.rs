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
    let w = super::low_ratio_warning(&u).expect("a warning");
    assert!(w.starts_with("2 unforced element(s)"), "{w}");
    assert!(
        w.contains("0.050") && w.contains("(1.500000, -2.000000)"),
        "{w}"
    );
    u.below_ratio_floor = 0;
    assert_eq!(super::low_ratio_warning(&u), None);
}
