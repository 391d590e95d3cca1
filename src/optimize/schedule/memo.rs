//! The schedule's memos: the operation clock, the stamps it gives the
//! vertices whose faces an operation changed, and what the passes remember
//! under those stamps (refused collapses and moves, the collapses the role
//! rules refused, the last swap scan). A memo stands while the stamps of the
//! vertices it read have not passed the clock it was made at; the outcome
//! depends on nothing else.

use crate::mesh::{EdgeKey, TriMesh, VertexId};
use crate::ops::{Outcome, Reject};
use rustc_hash::{FxHashMap, FxHashSet};

use super::slot;

/// The operation clock, the vertices' stamps and the memos of refusals.
pub(super) struct Memos {
    /// Operation clock: advanced by every applied operation.
    clock: u64,
    /// By vertex slot: the clock when a face around the vertex last changed.
    stamp: Vec<u64>,
    /// By vertex slot: the clock when the faces around the vertex last changed
    /// (split, collapse, swap; not a move).
    topo_stamp: Vec<u64>,
    /// Collapses refused, with the clock then and whether the length rule
    /// refused some direction: retried only once a face around either end has
    /// changed (the outcome depends on nothing else), or, for a length
    /// refusal, once the sizing field changed.
    failed_collapse: FxHashMap<EdgeKey, FailedCollapse>,
    /// Smoothing refused, by vertex slot, with the clock then (`u64::MAX`:
    /// none).
    failed_smooth: Vec<u64>,
    /// Collapses of `.1` into `.0` refused by the role rules alone (a
    /// [`CollapsePlan::new`](crate::ops::CollapsePlan::new) refusal that says so), with the clock then and
    /// the reason: they stay refused until the faces around `.1` change.
    role_refused: FxHashMap<(VertexId, VertexId), (u64, Reject)>,
    /// The clock when the last swap pass scanned the edges, and the edges it
    /// found a gain on: an edge whose ends' faces have not changed since
    /// (so neither has its quad) and that had no gain then has none now.
    swap_scan: Option<(u64, FxHashSet<EdgeKey>)>,
}

/// A refused collapse in [`Memos::failed_collapse`].
#[derive(Clone, Copy)]
struct FailedCollapse {
    /// The operation clock when it was refused.
    at: u64,
    /// Whether the length rule ([`lengths_kept`](super::sizing::lengths_kept),
    /// which reads the targets) refused a direction.
    by_length: bool,
    /// The lowest energy floor ([`Context::energy_floor`](crate::ops::Context::energy_floor))
    /// under which the energy rule refused a direction with the floor
    /// applied (`+∞`: none did). The refusal stands under that floor or a
    /// lower one; every other refusal but the length rule's reads only
    /// positions, tags and faces, whatever the phase.
    floor: f64,
}

impl FailedCollapse {
    /// Whether the refusal stands in a phase whose rules are those of the
    /// last one but for the sizes, the stretch and the energy floor, now
    /// `floor`.
    fn stands_under(&self, floor: f64) -> bool {
        !self.by_length && floor <= self.floor
    }
}

impl Memos {
    /// The clock at 1, nothing stamped or remembered.
    pub(super) fn new() -> Self {
        Memos {
            clock: 1,
            stamp: Vec::new(),
            topo_stamp: Vec::new(),
            failed_collapse: FxHashMap::default(),
            failed_smooth: Vec::new(),
            role_refused: FxHashMap::default(),
            swap_scan: None,
        }
    }

    /// The operation clock.
    pub(super) fn clock(&self) -> u64 {
        self.clock
    }

    /// Record an operation's `outcome` on `mesh`: when applied, every vertex
    /// of the faces it created (or moved) gets the new clock, and with
    /// `topology` (a split, collapse or swap, not a move) the new clock as its
    /// topology stamp too.
    pub(super) fn touch(&mut self, mesh: &TriMesh, outcome: &Outcome, topology: bool) {
        let Outcome::Applied(ch) = outcome else {
            return;
        };
        self.clock += 1;
        for &f in &ch.created {
            if !mesh.is_face_alive(f) {
                continue;
            }
            for v in mesh.face(f) {
                *slot(&mut self.stamp, v, 0) = self.clock;
                if topology {
                    *slot(&mut self.topo_stamp, v, 0) = self.clock;
                }
            }
        }
    }

    pub(super) fn topo_stamp_of(&self, v: VertexId) -> u64 {
        self.topo_stamp.get(v.index()).copied().unwrap_or(0)
    }

    pub(super) fn stamp_of(&self, v: VertexId) -> u64 {
        self.stamp.get(v.index()).copied().unwrap_or(0)
    }

    /// Whether a plan made ahead at clock `at`, which read the vertices
    /// `read` (and their rings), still stands: none of them changed since.
    pub(super) fn fresh(&self, at: u64, read: &[VertexId]) -> bool {
        read.iter().all(|&x| self.stamp_of(x) <= at)
    }

    /// The clock of the remembered refusal of the collapse of `k`, if any.
    pub(super) fn collapse_refused_at(&self, k: EdgeKey) -> Option<u64> {
        self.failed_collapse.get(&k).map(|f| f.at)
    }

    /// Whether a remembered refusal of the collapse of `k` stands: no face
    /// around either end changed since.
    pub(super) fn collapse_refused(&self, k: EdgeKey) -> bool {
        matches!(self.failed_collapse.get(&k), Some(&FailedCollapse { at, .. })
            if self.stamp_of(k.lo) <= at && self.stamp_of(k.hi) <= at)
    }

    /// Remember that the collapse of `k` was refused now, by the length rule
    /// in some direction or not, and by the energy rule under `floor`
    /// ([`FailedCollapse::floor`]).
    pub(super) fn refuse_collapse(&mut self, k: EdgeKey, by_length: bool, floor: f64) {
        let at = self.clock;
        self.failed_collapse.insert(
            k,
            FailedCollapse {
                at,
                by_length,
                floor,
            },
        );
    }

    /// Forget the collapses the length rule refused (the sizes changed);
    /// every other refusal depends on the faces around the edge alone.
    pub(super) fn forget_length_refusals(&mut self) {
        self.failed_collapse.retain(|_, f| !f.by_length);
    }

    /// Keep the refused collapses that stand under the energy floor `floor`
    /// after a change of phase ([`FailedCollapse::stands_under`]), forget the
    /// rest.
    pub(super) fn keep_refusals_standing_under(&mut self, floor: f64) {
        self.failed_collapse.retain(|_, f| f.stands_under(floor));
    }

    /// Tests: the refused collapses remembered, with the clock of each.
    #[cfg(test)]
    pub(super) fn collapse_refusals(&self) -> Vec<(EdgeKey, u64)> {
        self.failed_collapse
            .iter()
            .map(|(&k, f)| (k, f.at))
            .collect()
    }

    /// The reason the role rules refused the collapse of `v` into `u`, while
    /// the faces around `v` are unchanged since.
    pub(super) fn role_refusal(&self, u: VertexId, v: VertexId) -> Option<Reject> {
        match self.role_refused.get(&(u, v)) {
            Some(&(at, reason)) if self.topo_stamp_of(v) <= at => Some(reason),
            _ => None,
        }
    }

    /// Remember that the role rules refused the collapse of `v` into `u` now,
    /// for `reason`.
    pub(super) fn refuse_role(&mut self, u: VertexId, v: VertexId, reason: Reject) {
        self.role_refused.insert((u, v), (self.clock, reason));
    }

    /// Whether the smoothing of `v` was refused and `v` is unchanged since.
    pub(super) fn smooth_refused(&self, v: VertexId) -> bool {
        matches!(self.failed_smooth.get(v.index()), Some(&at)
            if at != u64::MAX && self.stamp_of(v) <= at)
    }

    /// Record the smoothing of `v`: applied (nothing to remember) or refused
    /// now.
    pub(super) fn smoothed(&mut self, v: VertexId, applied: bool) {
        let at = if applied { u64::MAX } else { self.clock };
        *slot(&mut self.failed_smooth, v, u64::MAX) = at;
    }

    /// Forget the refused moves (the rules of the moves change).
    pub(super) fn forget_smooth_refusals(&mut self) {
        self.failed_smooth.clear();
    }

    /// The last swap scan, taken out (the pass scans again and puts its own).
    pub(super) fn take_swap_scan(&mut self) -> Option<(u64, FxHashSet<EdgeKey>)> {
        self.swap_scan.take()
    }

    /// Remember the swap scan made at clock `at`, with the edges it found.
    pub(super) fn set_swap_scan(&mut self, at: u64, found: FxHashSet<EdgeKey>) {
        self.swap_scan = Some((at, found));
    }

    /// Tests: the last swap scan.
    #[cfg(test)]
    pub(super) fn swap_scan(&self) -> Option<&(u64, FxHashSet<EdgeKey>)> {
        self.swap_scan.as_ref()
    }

    /// Forget the last swap scan: it saw only the edges of its pass's scope,
    /// so it does not hold for another scope.
    pub(super) fn forget_swap_scan(&mut self) {
        self.swap_scan = None;
    }

    /// Forget every memo of refused operations and the swap scan, after the
    /// mesh was restored to an earlier state (they describe the abandoned
    /// one): the clock moves on and every stamp is set to it.
    pub(super) fn forget(&mut self) {
        self.clock += 1;
        self.failed_collapse.clear();
        self.failed_smooth.clear();
        self.role_refused.clear();
        self.swap_scan = None;
        let clock = self.clock;
        for s in self.stamp.iter_mut().chain(self.topo_stamp.iter_mut()) {
            *s = clock;
        }
    }
}
