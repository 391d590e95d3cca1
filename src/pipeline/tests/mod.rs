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
