//! Primary chains: runs of consecutive primary sections cut from one input
//! curve, joined end to end (thesis §4.4.1: the vertices inside a curve slide
//! along it and may be collapsed along it; only the ends of a curve, where it
//! meets other features or stops, are fixed).
//!
//! The feature stage cuts each curve into sections short and flat enough to be
//! one mesh edge each (`PrimarySection`); the optimizer works on whole chains:
//! a chain's parameter interval is the union of its sections', on the same
//! parent curve, so an edge's piece can be any sub-interval of it (the
//! curvature invariant still bounds each edge's turn).

use super::{FeatureSet, Parent};
use crate::svg::FeatureSource;
use kurbo::Point;

/// One chain: consecutive primary sections of one parent curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PrimaryChain {
    /// The curve.
    pub parent: Parent,
    /// The parameter interval on `parent` the chain covers, `t[0] < t[1]`.
    pub t: [f64; 2],
    /// The input feature it came from.
    pub source: FeatureSource,
    /// The other shapes whose outlines run along it (see
    /// [`super::PrimarySection::shared`]).
    pub shared: Option<u32>,
    /// The chain's end points (`parent` at `t[0]` and `t[1]`): the only fixed vertices.
    pub ends: [Point; 2],
}

/// The chains of a [`FeatureSet`]'s primary sections.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct PrimaryChains {
    /// For each primary section (by index), its chain.
    pub chain_of: Vec<u32>,
    /// The chains.
    pub chains: Vec<PrimaryChain>,
}

impl FeatureSet {
    /// Join the primary sections into chains: a section continues the one
    /// before it (`prev`) when both lie on the same parent curve and their
    /// parameter intervals meet.
    pub(crate) fn primary_chains(&self) -> PrimaryChains {
        let n = self.primary.len();
        let continues = |a: usize, b: usize| {
            // b follows a on the same curve.
            let (sa, sb) = (&self.primary[a], &self.primary[b]);
            sa.parent == sb.parent && sa.shared == sb.shared && sa.t[1] == sb.t[0] && a != b
        };
        let mut chain_of = vec![u32::MAX; n];
        let mut chains = Vec::new();
        for i in 0..n {
            if chain_of[i] != u32::MAX {
                continue;
            }
            // Walk back to the first section of the run (bounded: a closed run stops where it began).
            let mut start = i;
            for _ in 0..n {
                match self.primary[start].prev {
                    Some(p)
                        if continues(p.index(), start)
                            && chain_of[p.index()] == u32::MAX
                            && p.index() != i =>
                    {
                        start = p.index();
                    }
                    _ => break,
                }
            }
            let id = u32::try_from(chains.len()).expect("internal: chain count fits u32");
            let mut last = start;
            chain_of[start] = id;
            for _ in 0..n {
                match self.primary[last].next {
                    Some(q) if continues(last, q.index()) && chain_of[q.index()] == u32::MAX => {
                        last = q.index();
                        chain_of[last] = id;
                    }
                    _ => break,
                }
            }
            let (a, b) = (&self.primary[start], &self.primary[last]);
            chains.push(PrimaryChain {
                parent: a.parent,
                t: [a.t[0], b.t[1]],
                source: a.source,
                shared: a.shared,
                ends: [a.ctrl.p0, b.ctrl.p3],
            });
        }
        PrimaryChains { chain_of, chains }
    }
}
