//! What the schedule counts and measures: the tally of each operation
//! ([`OpTally`]), the statistics ([`OptimizeStats`], [`StopReason`]), and the
//! quality measures of the stop rules ([`Measure`], and [`measure_energy`],
//! which the curved stage shares).

use crate::element::energy::amips;
use crate::mesh::{TriMesh, VertexId, min_angle_deg};
use crate::ops::{Outcome, Reject};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// How often an operation was applied and why it was refused.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct OpTally {
    /// Applied operations.
    pub applied: u64,
    /// Refusals, by the rule or invariant that refused ([`Reject`] as
    /// index: the count is on every operation's path, a name lookup is not);
    /// serialized as a map from [`Reject::name`] to the count, the rules that
    /// refused nothing left out.
    #[serde(serialize_with = "rejected_by_name")]
    rejected: [u64; Reject::COUNT],
}

fn rejected_by_name<S: serde::Serializer>(
    rejected: &[u64; Reject::COUNT],
    s: S,
) -> Result<S::Ok, S::Error> {
    let named: BTreeMap<&str, u64> = Reject::ALL
        .iter()
        .filter(|&&r| rejected[r as usize] > 0)
        .map(|&r| (r.name(), rejected[r as usize]))
        .collect();
    serde::Serialize::serialize(&named, s)
}

impl OpTally {
    /// All refusals (the running totals of the debug log).
    pub(crate) fn refused(&self) -> u64 {
        self.rejected.iter().sum()
    }

    /// Count `outcome`; returns whether it was applied.
    pub(crate) fn record(&mut self, outcome: &Outcome) -> bool {
        match outcome {
            Outcome::Applied(_) => {
                self.applied += 1;
                true
            }
            Outcome::Rejected(r) => {
                self.rejected[*r as usize] += 1;
                false
            }
        }
    }
}

/// Why the schedule stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The quality goal was met (angle above α or energy below the stop energy).
    Quality,
    /// A pass changed nothing measurable.
    Stalled,
    /// The pass limit was reached.
    PassLimit,
    /// The run's wall-clock limit (`--time-limit`) passed: the pipeline
    /// reports an error and writes nothing.
    TimeLimit,
}

/// What the schedule did.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct OptimizeStats {
    /// Passes run.
    pub passes: u32,
    /// Why it stopped.
    pub stop: StopReason,
    /// Edge splits.
    pub split: OpTally,
    /// Edge collapses.
    pub collapse: OpTally,
    /// Edge swaps.
    pub swap: OpTally,
    /// Secondary feature edges rerouted through the apex of their sliver.
    pub reroute: OpTally,
    /// Vertex smoothing.
    pub smooth: OpTally,
    /// Rounding of rational vertices to `f64`.
    pub round: OpTally,
    /// Moves of off-curve primary vertices toward their curve.
    pub project: OpTally,
    /// Primary vertices that were off their curve at the start (or after a
    /// fallback split) and ended on it.
    pub projected_vertices: usize,
    /// Primary vertices still off their curve at the end.
    pub off_curve_left: usize,
    /// Vertices still rational at the end (the mesh is unusable if not 0).
    pub rational_left: usize,
    /// Envelope stages run for leftover rational vertices (0 when none were needed).
    pub envelope_stages: u32,
    /// Triangles left with a corner below α that the mesh's feature edges
    /// leave room for (the worst-element phase's goal: 0).
    pub bad_corners_left: usize,
    /// Whether the last split pass of the main passes (or a split pass of
    /// the worst-element phase) left splits undone because the mesh had
    /// reached the vertex budget (`--max-vertices`): the mesh is then coarser
    /// than the size field asks somewhere.
    pub vertex_budget_reached: bool,
    /// Smallest angle at the end, degrees.
    pub min_angle_deg: f64,
    /// Largest AMIPS energy at the end.
    pub max_amips: f64,
    /// Where the time went: the phases in the order they ran.
    pub phases: Vec<PhaseStats>,
}

impl OptimizeStats {
    /// Nothing done yet, stopped by the pass limit unless something else
    /// stops the schedule.
    pub(super) fn start() -> OptimizeStats {
        OptimizeStats {
            passes: 0,
            stop: StopReason::PassLimit,
            split: OpTally::default(),
            collapse: OpTally::default(),
            swap: OpTally::default(),
            reroute: OpTally::default(),
            smooth: OpTally::default(),
            round: OpTally::default(),
            project: OpTally::default(),
            projected_vertices: 0,
            off_curve_left: 0,
            rational_left: 0,
            envelope_stages: 0,
            bad_corners_left: 0,
            vertex_budget_reached: false,
            min_angle_deg: 0.0,
            max_amips: 0.0,
            phases: Vec::new(),
        }
    }

    /// These statistics with the phases' seconds at 0: what two runs of one
    /// input have in common.
    #[cfg(test)]
    pub(crate) fn without_times(mut self) -> OptimizeStats {
        for p in &mut self.phases {
            p.seconds = 0.0;
        }
        self
    }

    /// Operations applied and refused so far, every kind together.
    fn totals(&self) -> (u64, u64) {
        let tallies = [
            &self.split,
            &self.collapse,
            &self.swap,
            &self.reroute,
            &self.smooth,
            &self.round,
            &self.project,
        ];
        tallies
            .iter()
            .fold((0, 0), |(a, r), t| (a + t.applied, r + t.refused()))
    }
}

/// Tests: what the schedule's machinery did, beside the statistics.
#[cfg(test)]
#[derive(Default)]
pub(super) struct TestTally {
    /// The plans made ahead that were used, and those found stale.
    pub(super) ahead: (usize, usize),
    /// The plans of edges queued again and staged that were popped.
    pub(super) staged: usize,
    /// The refusals kept across a phase change that were planned again and
    /// found refused (`Schedule::keep_standing_refusals`).
    pub(super) standing_checked: usize,
}

/// What one phase of the schedule did (`--stats` `optimize.phases[*]`): its
/// time, the queues its passes worked through, and the operations they
/// applied and refused. A pass queues the items it looks at (the edges to
/// split, collapse or swap, the vertices to smooth, round or project), so
/// `queued` against `applied` says how much of a phase's work changed the
/// mesh.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PhaseStats {
    /// The phase: `start` (the first rounding and projection of the BSP
    /// mesh's vertices, and the split passes toward the size field before
    /// the main passes), `main`, `coarsen`, `equalize`, `polish`,
    /// `min_max`, `repair` (the worst-element phase) or `envelope` (the last
    /// rounding and the envelope stages).
    pub phase: &'static str,
    /// Wall time, seconds.
    pub seconds: f64,
    /// Queues its passes worked through (one per pass of one operation kind,
    /// or per collapse round).
    pub queues: u64,
    /// Items in those queues, all together.
    pub queued: u64,
    /// Items in the largest of them.
    pub largest_queue: u64,
    /// Operations applied (every kind).
    pub applied: u64,
    /// Operations planned and refused (every kind); a queued item whose
    /// refusal is remembered and still stands is skipped, neither applied
    /// nor refused.
    pub refused: u64,
    /// Triangles at its end.
    pub triangles: usize,
}

/// The phase being timed: its record so far, its start, and the totals of
/// [`OptimizeStats`] then.
#[derive(Debug)]
pub(super) struct OpenPhase {
    record: PhaseStats,
    start: std::time::Instant,
    totals: (u64, u64),
}

impl OpenPhase {
    /// Start timing `phase` with `stats` as they are.
    pub(super) fn start(phase: &'static str, stats: &OptimizeStats) -> OpenPhase {
        OpenPhase {
            record: PhaseStats {
                phase,
                seconds: 0.0,
                queues: 0,
                queued: 0,
                largest_queue: 0,
                applied: 0,
                refused: 0,
                triangles: 0,
            },
            start: std::time::Instant::now(),
            totals: stats.totals(),
        }
    }

    /// Count a pass's queue of `n` items.
    pub(super) fn queue(&mut self, n: usize) {
        let r = &mut self.record;
        r.queues += 1;
        r.queued += n as u64;
        r.largest_queue = r.largest_queue.max(n as u64);
    }

    /// The phase's record, ended with `stats` and `triangles` as they are now.
    pub(super) fn end(self, stats: &OptimizeStats, triangles: usize) -> PhaseStats {
        let (applied, refused) = stats.totals();
        PhaseStats {
            seconds: self.start.elapsed().as_secs_f64(),
            applied: applied - self.totals.0,
            refused: refused - self.totals.1,
            triangles,
            ..self.record
        }
    }
}

/// Quality of a mesh for the stop rules.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Measure {
    /// Smallest angle (degrees) of the triangles that are not locked.
    pub(super) min_angle: f64,
    /// Largest energy of the triangles that are not locked.
    pub(super) max_energy: f64,
    /// Mean energy of all triangles.
    pub(super) mean_energy: f64,
    /// Smallest angle and largest energy of all triangles.
    pub(super) all: (f64, f64),
    /// The longest edge.
    pub(super) longest: f64,
}

/// Whether the triangle `v` has three feature edges (see [`measure`]).
pub(crate) fn locked(mesh: &TriMesh, v: [VertexId; 3]) -> bool {
    (0..3).all(|i| !mesh.edge_tags(v[i], v[(i + 1) % 3]).is_empty())
}

/// The energies of a mesh's triangles, for the stop rules of both stages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct EnergyMeasure {
    /// Largest energy of the measured triangles that are not locked.
    pub(crate) max: f64,
    /// Largest energy of all measured triangles.
    pub(crate) max_all: f64,
    /// Mean energy of the measured triangles (0 when none is).
    pub(crate) mean: f64,
    /// Triangles without an energy.
    pub(crate) unmeasured: usize,
}

/// Measure the energies of `mesh`'s triangles: `energy(v)` gives the energy
/// of the triangle `v`, or `None` to leave it out (counted in `unmeasured`).
/// A triangle whose three edges are feature edges is locked ([`locked`]): its
/// shape is the input's (no swap, split or collapse can change it), so it is
/// left out of `max`, though not out of `max_all`. The energies are computed
/// in parallel and summed in face order (the same sum for any number of
/// threads).
pub(crate) fn measure_energy(
    mesh: &TriMesh,
    energy: impl Fn([VertexId; 3]) -> Option<f64> + Sync,
) -> EnergyMeasure {
    let faces: Vec<_> = mesh.faces().collect();
    let values: Vec<Option<f64>> = faces.par_iter().map(|&f| energy(mesh.face(f))).collect();
    fold_energies(&values, |i| locked(mesh, mesh.face(faces[i])))
}

/// [`measure_energy`]'s tally of the energies by face, in face order, with
/// `locked(i)` whether the `i`-th face is locked. A face is asked only when
/// its energy would raise the largest energy of the faces not locked so far:
/// no other face can change it, and most faces are not asked (their three
/// edges' tag lookups would be most of the measure on a large drawing).
fn fold_energies(values: &[Option<f64>], locked: impl Fn(usize) -> bool) -> EnergyMeasure {
    let mut m = EnergyMeasure {
        max: 0.0,
        max_all: 0.0,
        mean: 0.0,
        unmeasured: 0,
    };
    let (mut sum, mut n) = (0.0, 0usize);
    for (i, &e) in values.iter().enumerate() {
        match e {
            None => m.unmeasured += 1,
            Some(e) => {
                sum += e;
                n += 1;
                m.max_all = m.max_all.max(e);
                if e > m.max && !locked(i) {
                    m.max = e;
                }
            }
        }
    }
    if n > 0 {
        m.mean = sum / n as f64;
    }
    m
}

/// Measure `mesh`: the AMIPS energies ([`measure_energy`]), angles and edge
/// lengths. Locked triangles are left out of `min_angle` and `max_energy`.
pub(super) fn measure(mesh: &TriMesh) -> Measure {
    if mesh.num_faces() == 0 {
        return Measure {
            min_angle: 0.0,
            max_energy: 0.0,
            mean_energy: 0.0,
            all: (0.0, 0.0),
            longest: 0.0,
        };
    }
    // Per face, in parallel: energy, min angle, longest edge; then folded in
    // face order, asking whether a face is locked only where its angle or
    // energy would change the unlocked minimum or maximum so far.
    let faces: Vec<_> = mesh.faces().collect();
    let per_face: Vec<(Option<f64>, f64, f64)> = faces
        .par_iter()
        .map(|&f| {
            let [a, b, c] = mesh.face(f).map(|x| mesh.position(x));
            let longest = a.distance(b).max(b.distance(c)).max(c.distance(a));
            (Some(amips(a, b, c)), min_angle_deg([a, b, c]), longest)
        })
        .collect();
    let is_locked = |i: usize| locked(mesh, mesh.face(faces[i]));
    let (mut min_angle, mut min_angle_all, mut longest) = (180.0f64, 180.0f64, 0.0f64);
    for (i, &(_, angle, long)) in per_face.iter().enumerate() {
        min_angle_all = min_angle_all.min(angle);
        longest = longest.max(long);
        if angle < min_angle && !is_locked(i) {
            min_angle = angle;
        }
    }
    let values: Vec<Option<f64>> = per_face.iter().map(|p| p.0).collect();
    let e = fold_energies(&values, is_locked);
    Measure {
        min_angle,
        max_energy: e.max,
        mean_energy: e.mean,
        all: (min_angle_all, e.max_all),
        longest,
    }
}

#[cfg(test)]
mod tally_tests {
    use super::*;

    #[test]
    fn a_tally_serializes_its_refusals_by_name() {
        let mut t = OpTally::default();
        assert_eq!(
            serde_json::to_string(&t).unwrap(),
            r#"{"applied":0,"rejected":{}}"#
        );
        for r in [Reject::Energy, Reject::EdgeLength, Reject::Energy] {
            assert!(!t.record(&Outcome::Rejected(r)));
        }
        assert!(t.record(&Outcome::Applied(crate::ops::LocalChange::default())));
        // By name, as a map sorted by name would be: the names the stats
        // printed before the counts were an array.
        assert_eq!(
            serde_json::to_string(&t).unwrap(),
            r#"{"applied":1,"rejected":{"edge_length":1,"energy":2}}"#
        );
    }
}
