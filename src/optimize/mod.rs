//! Mesh optimization: the schedule of split / collapse / swap / smooth passes
//! that drives the local operations (`ops`) over the whole mesh, with the sizing
//! field and the stop rules. The energy it minimises is
//! [`crate::element::energy`]. The curved mesh optimization (`curve::optimize`,
//! a layer up) runs the same collapse, swap and smoothing passes through
//! their own entry (`schedule::CurvedPasses`). Its tuning constants, with their provenance, head
//! `schedule/mod.rs`. Thesis §2.3.2, §4.4.1; docs/design.md "Data flow" (optimize).

pub(crate) mod forced;
pub(crate) mod schedule;

#[cfg(test)]
pub(crate) use schedule::optimize;
pub(crate) use schedule::{
    LinearOptions, OptimizeOptions, OptimizeStats, PassLimits, needle_energy, optimize_with_field,
};

#[cfg(test)]
mod tests;
