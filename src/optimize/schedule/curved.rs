//! The curved stage's entry into the schedule ([`CurvedPasses`]): the
//! collapse, swap and smoothing passes over the whole mesh, in curved mode,
//! with the bounds of the main passes and every target at the size field.
//! Nothing of the linear driver (sizing floor, stop rules, vertex budget,
//! splits, phases) is part of it.

use super::scope::Scope;
use super::{OptimizeStats, PassLimits, Schedule};
use crate::mesh::TriMesh;
use crate::ops::Context;
use crate::sizing::SizeField;

/// The curved stage's passes (`curve::optimize`) over a mesh whose context
/// is in curved mode.
pub(crate) struct CurvedPasses<'a> {
    schedule: Schedule<'a, ()>,
}

impl<'a> CurvedPasses<'a> {
    /// The passes over `mesh` under `limits`, with every target at `field`
    /// (`None`: `limits.l` everywhere) and the smoothing order drawn from
    /// `seed`. `ctx` takes the bounds of the main passes: no energy floor, no
    /// bound on a new edge.
    pub(crate) fn new(
        mesh: &'a mut TriMesh,
        ctx: &'a mut Context,
        limits: PassLimits,
        field: Option<&'a SizeField>,
        seed: u64,
    ) -> Self {
        CurvedPasses {
            schedule: Schedule::with_driver(mesh, ctx, limits, (), seed, field),
        }
    }

    /// One pass: collapse the edges shorter than `collapse_below` times their
    /// target (shortest first), swap, smooth. Returns how many collapses,
    /// swaps (reroutes included) and moves it applied.
    pub(crate) fn pass(&mut self, collapse_below: f64) -> (u64, u64, u64) {
        let s = &mut self.schedule;
        let collapses = s.collapse_pass(&Scope::Whole, collapse_below);
        let swaps = s.swap_pass(&Scope::Whole);
        let smooths = s.smooth_pass(&Scope::Whole);
        (collapses, swaps, smooths)
    }

    /// The mesh being improved.
    pub(crate) fn mesh(&self) -> &TriMesh {
        self.schedule.mesh()
    }

    /// The statistics so far: the curved stage reads the tallies of its
    /// collapses, swaps, reroutes and moves.
    pub(crate) fn stats(&self) -> &OptimizeStats {
        self.schedule.stats()
    }
}
