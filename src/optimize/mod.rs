//! Mesh optimization: the AMIPS energy the local operations minimise (and,
//! next, the schedule of split / collapse / swap / smooth passes).
//!
//! Owns [`energy`]: the 2D conformal AMIPS of a triangle with analytic
//! derivatives in one free vertex and along a feature curve. Thesis §2.3.2,
//! §4.4.1, §4.4.3; DESIGN "Data flow" (optimize).

pub mod energy;
pub mod schedule;

pub use schedule::{OptimizeOptions, OptimizeStats, optimize};

#[cfg(test)]
mod tests;
