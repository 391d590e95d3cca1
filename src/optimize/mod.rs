//! Mesh optimization: the schedule of split / collapse / swap / smooth passes
//! that drives the local operations (`ops`) over the whole mesh, with the sizing
//! field and the stop rules. The energy it minimises is
//! [`crate::element::energy`]. Thesis §2.3.2, §4.4.1; DESIGN "Data flow" (optimize).

pub mod schedule;

pub use schedule::{OptimizeOptions, OptimizeStats, optimize};

#[cfg(test)]
mod tests;
