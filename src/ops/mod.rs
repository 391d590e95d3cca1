//! Local mesh operations under TriWild's invariants: edge split, edge
//! collapse, edge swap, vertex smoothing, vertex rounding and vertex
//! projection onto a primary curve.
//!
//! Each operation has the four steps of STYLE "Local operations and
//! invariants": a plan that reads `&TriMesh` only and runs the topological and
//! feature checks (link condition, §4.4.1 feature rules); a tentative change
//! through a [`Transaction`](crate::mesh::Transaction); the invariants of [`invariants`] run on the new
//! faces only; then commit, or drop the transaction, which rolls the mesh
//! back bit for bit. Every `try_*` returns an [`Outcome`]; a rejection is a
//! value naming the refusing rule, never an error.
//!
//! Feature rules (§4.4.1): box corners, feature points and section endpoints
//! never move, nor do vertices where primary features meet, end or branch
//! (where only secondary features end, meet or cross, a vertex may collapse
//! into a neighbour within ε, under the envelope test); a vertex
//! on a primary section moves only along its curve, its parameter tracked in
//! the edge tags; a split primary edge gets its vertex at the curve's
//! parameter midpoint unless that inverts a triangle, else at the edge's
//! midpoint (to be projected later); collapses keep the surviving vertex in
//! place and slide a primary vertex only along its own curve; feature edges
//! are never swapped. Mesh boundary vertices stay put; a boundary vertex may be
//! collapsed along the boundary only where the boundary is exactly straight.
//! With [`Context::fixed_boundary`] (a periodic cell, whose side vertices are
//! also tagged as box corners) no boundary edge is split either.
//!
//! Guarantees: an applied operation leaves `TriMesh::check` clean and every
//! invariant true on the faces it created (given they held before); a
//! rejected one leaves the mesh equal (`PartialEq`) to before.
//! docs/design.md "Invariants" 1-5; thesis §2.3.2, §2.3.4, §4.4.1.

pub(crate) mod invariants;

mod collapse;
mod project;
mod round;
mod smooth;
mod split;
mod swap;

#[cfg(test)]
pub(crate) mod tests;

pub(crate) use collapse::{
    CollapsePlan, refusal as collapse_refusal, try_collapse, try_collapse_planned,
};
pub(crate) use project::try_project;
pub(crate) use round::try_round;
pub(crate) use smooth::{Objective, SmoothPlan, try_smooth, try_smooth_planned};
pub(crate) use split::{SplitPlan, try_split, try_split_bounded, try_split_planned};
#[cfg(test)]
pub(crate) use swap::try_reroute;
pub(crate) use swap::{ReroutePlan, SwapPlan, try_reroute_planned, try_swap, try_swap_planned};

use crate::features::{FeatureSet, Parent, PrimaryChains};
use crate::mesh::{EdgeKey, FaceId, FeatureOn, TriMesh, VertexId};
use invariants::Envelope;

/// Why an operation was refused: the rule or invariant that refused it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub(crate) enum Reject {
    /// The element is dead, or the two vertices are not an edge.
    NotAnEdge,
    /// The vertex may not move (feature endpoint, box corner, feature junction, boundary).
    FixedVertex,
    /// A feature rule of §4.4.1 (swap of a feature edge, a primary vertex leaving its curve).
    FeatureRule,
    /// The mesh boundary would change shape.
    Boundary,
    /// The link condition (collapse) or an existing edge (swap) forbids the change.
    Topology,
    /// Nothing to do (a vertex already `f64`, no better position found).
    NoChange,
    /// Invariant 1: a triangle would be inverted or degenerate.
    Inversion,
    /// Invariant 4/5: a primary vertex would leave (or move away from) its curve.
    OnCurve,
    /// Invariant 3: a primary edge's curve piece would turn α or more.
    Curvature,
    /// Invariant 2: a secondary edge would leave the ε-envelope.
    Envelope,
    /// The energy rule: the worst triangle would get worse.
    Energy,
    /// Curved mode: a curved element would not be certified valid, or a
    /// triangle would get more than one curved edge.
    Jacobian,
    /// The schedule's length rule: a collapse would make an edge longer than the
    /// split threshold (4/3 of its target), so the split pass would undo it (decided
    /// by the schedule before the operation is planned); or a smoothing would make an
    /// edge longer than [`Context::max_new_edge`] (a swap too, but the schedule
    /// skips those).
    EdgeLength,
}

impl Reject {
    /// How many reasons there are.
    pub(crate) const COUNT: usize = 13;

    /// Every reason, in declaration order (`ALL[r as usize] == r`).
    pub(crate) const ALL: [Reject; Reject::COUNT] = [
        Reject::NotAnEdge,
        Reject::FixedVertex,
        Reject::FeatureRule,
        Reject::Boundary,
        Reject::Topology,
        Reject::NoChange,
        Reject::Inversion,
        Reject::OnCurve,
        Reject::Curvature,
        Reject::Envelope,
        Reject::Energy,
        Reject::Jacobian,
        Reject::EdgeLength,
    ];

    /// A short lower-case name (for statistics).
    pub(crate) fn name(self) -> &'static str {
        match self {
            Reject::NotAnEdge => "not_an_edge",
            Reject::FixedVertex => "fixed_vertex",
            Reject::FeatureRule => "feature_rule",
            Reject::Boundary => "boundary",
            Reject::Topology => "topology",
            Reject::NoChange => "no_change",
            Reject::Inversion => "inversion",
            Reject::OnCurve => "on_curve",
            Reject::Curvature => "curvature",
            Reject::Envelope => "envelope",
            Reject::Energy => "energy",
            Reject::Jacobian => "jacobian",
            Reject::EdgeLength => "edge_length",
        }
    }
}

// A reason declared after `EdgeLength` must grow `Reject::COUNT` and `ALL`.
const _: () = assert!(Reject::EdgeLength as usize + 1 == Reject::COUNT);

/// What an applied operation changed.
#[derive(Clone, Debug, PartialEq, Default)]
pub(crate) struct LocalChange {
    /// Faces the operation created (ids may reuse removed ones). For
    /// smoothing and rounding: the faces around the moved vertex.
    pub created: Vec<FaceId>,
    /// A vertex the operation added (split).
    pub new_vertex: Option<VertexId>,
    /// A vertex the operation removed (collapse).
    pub removed_vertex: Option<VertexId>,
    /// A vertex the operation moved (smoothing, rounding).
    pub moved_vertex: Option<VertexId>,
}

/// The result of a `try_*` operation.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Outcome {
    /// The operation was applied and committed.
    Applied(LocalChange),
    /// The operation was refused; the mesh is unchanged.
    Rejected(Reject),
}

impl Outcome {
    /// Whether the operation was applied.
    pub(crate) fn is_applied(&self) -> bool {
        matches!(self, Outcome::Applied(_))
    }
}

/// Which energy condition (beyond validity) an operation must meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum EnergyRule {
    /// Any valid change is accepted (the tests' random operations).
    #[cfg(test)]
    Ignore,
    /// The largest AMIPS energy of the new triangles is no larger than that of
    /// the triangles they replace (collapse, swap, smoothing; never split).
    /// In curved mode ([`Context::curved`]) the energies are the curved ones.
    NoWorseMax,
}

/// The curved mode of the invariants (thesis §4.4.2 "Curved Optimization"):
/// every triangle has at most one curved edge (a primary edge on a cubic
/// parent), takes the exact curve piece there and must be certified valid;
/// energies are the curved AMIPS of the elements
/// ([`crate::element::triangle::amips`]; an uncertified element counts `+∞`);
/// and a primary edge's piece need only turn less than [`CurvedRule::alpha`]
/// instead of [`Context::alpha`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CurvedRule {
    /// Element order (quadratic or cubic).
    pub order: crate::element::Order,
    /// How elements are certified.
    pub certify: crate::element::CertifyOptions,
    /// Bound on the turn of a primary edge's curve piece, radians (strict).
    pub alpha: f64,
    /// The corner rule's floor: an operation may not make the largest straight
    /// (corner) AMIPS energy of the faces it creates larger than both that of
    /// the faces it replaces and this. The curved energy alone lets a collapse
    /// trade a badly curved element for a straight sliver (on some dev drawings
    /// it takes the worst angle from the linear mesh's 8.2° to 0.92° to bring
    /// the curved maximum from 540 to 94; with the rule the angle stays 8.0°
    /// and the curved maximum ends at 222). By induction the curved stage never makes
    /// the mesh's worst corner energy exceed max(its value before, the floor).
    /// [`CurvedRule::new`]: the linear stop energy.
    pub corner_floor: f64,
}

impl CurvedRule {
    /// The rule for `order` with validity-only certification and a turn
    /// bound of 90° (Theorem 4.4 needs less than π; 90° keeps a margin).
    pub(crate) fn new(order: crate::element::Order) -> CurvedRule {
        CurvedRule {
            order,
            certify: crate::element::CertifyOptions::VALIDITY,
            alpha: std::f64::consts::FRAC_PI_2,
            corner_floor: crate::params::defaults::STOP_ENERGY,
        }
    }
}

/// The curve a primary section's edges lie on: `parent` on `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CurveSection {
    /// The parametric curve.
    pub parent: Parent,
    /// The parameter interval of the section on `parent`.
    pub t: [f64; 2],
    /// The input feature it came from (`None` where no drawing is behind it).
    pub source: Option<crate::svg::FeatureSource>,
    /// The other shapes whose outlines run along it, if any (an index into
    /// [`FeatureSet::sharers`]).
    pub shared: Option<u32>,
}

/// Everything the operations need besides the mesh: the curves that primary
/// tags index (`FeatureOn::Primary::section`), the secondary envelope
/// (`FeatureOn::Secondary::polyline` indexes its polylines) and tolerances.
#[derive(Clone, Debug)]
pub(crate) struct Context {
    /// Curves of the primary sections, indexed by the tags' `section`.
    pub sections: Vec<CurveSection>,
    /// The ε-envelope of the input secondary polylines.
    pub envelope: Envelope,
    /// Bound on the turn of a primary edge's curve piece, radians (α).
    pub alpha: f64,
    /// Distance (user units) within which a primary vertex counts as on its curve.
    pub on_curve_abs: f64,
    /// The energy condition for collapse, swap and smoothing.
    pub energy: EnergyRule,
    /// Under [`EnergyRule::NoWorseMax`], the collapse of a vertex without
    /// features may make new faces up to this energy even where the faces they
    /// replace were better (0: the plain rule). The final coarsening sets it to
    /// min(stop energy, the mesh's worst energy), so coarsening never makes the
    /// mesh's worst triangle worse.
    pub energy_floor: f64,
    /// Smoothing (here) and the schedule's swaps may not make an edge longer than
    /// this (user units) unless it was longer before ([`Reject::EdgeLength`]); `+∞`:
    /// no bound. The schedule's final phases set it to 2 l, so the sizes the final
    /// coarsening leaves hold.
    pub max_new_edge: f64,
    /// The curved mode of the invariants (`None`: the linear stage).
    pub curved: Option<CurvedRule>,
    /// The mesh boundary is fixed: no edge on it is split (a periodic cell's
    /// sides keep the vertices the BSP gave them, partners of the opposite
    /// side's; the vertices themselves are tagged fixed).
    pub fixed_boundary: bool,
}

impl Context {
    /// The context for a mesh whose primary tags index the chains of
    /// `features` ([`FeatureSet::primary_chains`]), with the parameter of the
    /// chain's parent curve, and whose secondary tags index
    /// `features.secondary`: a vertex inside a chain slides along the whole
    /// chain. `eps_abs` is the envelope ε, `sample_abs` the envelope sampling
    /// spacing (thesis: ε), both user units.
    pub(crate) fn from_chains(
        features: &FeatureSet,
        chains: &PrimaryChains,
        eps_abs: f64,
        sample_abs: f64,
    ) -> Context {
        let sections = chains
            .chains
            .iter()
            .map(|c| CurveSection {
                parent: c.parent,
                t: c.t,
                source: Some(c.source),
                shared: c.shared,
            })
            .collect();
        let polylines: Vec<Vec<kurbo::Point>> = features
            .secondary
            .iter()
            .map(|p| p.points.clone())
            .collect();
        Context {
            sections,
            envelope: Envelope::new(&polylines, eps_abs, sample_abs),
            alpha: features.params.alpha,
            fixed_boundary: false,
            on_curve_abs: 1e-9 * features.params.d,
            energy: EnergyRule::NoWorseMax,
            energy_floor: 0.0,
            max_new_edge: f64::INFINITY,
            curved: None,
        }
    }

    /// The curve of a section tag, if the index is known.
    pub(crate) fn section(&self, section: u32) -> Option<&CurveSection> {
        self.sections.get(section as usize)
    }

    /// The bound on the turn of a primary edge's curve piece, radians: the
    /// curved rule's when in curved mode, else α.
    pub(crate) fn turn_bound(&self) -> f64 {
        self.curved.map_or(self.alpha, |r| r.alpha)
    }

    /// This context in curved mode with `rule`.
    pub(crate) fn with_curved(&self, rule: CurvedRule) -> Context {
        Context {
            curved: Some(rule),
            ..self.clone()
        }
    }
}

/// The parameter of a primary tag at vertex `v` of the edge `key`.
pub(crate) fn t_at(key: EdgeKey, t: [f64; 2], v: VertexId) -> f64 {
    if key.lo == v { t[0] } else { t[1] }
}

/// What a vertex may do, from its tag and its incident feature edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Role {
    /// Never moves and is never removed.
    Fixed,
    /// On the mesh boundary (no feature): stays put; may collapse along a straight boundary.
    Boundary,
    /// No feature: moves freely.
    Free,
    /// Inside a secondary chain (exactly two secondary edges, no primary).
    Secondary,
    /// On secondary features only, but where they end, meet or cross (not two
    /// secondary edges): never smoothed; collapsible into a neighbour within
    /// ε, where the envelope test decides (TetWild's rule for surface vertices).
    SecondaryJunction,
    /// Inside a primary section: slides along it between its two neighbours.
    Primary {
        section: u32,
        t: f64,
        /// The two neighbours along the section with their parameters.
        along: [(VertexId, f64); 2],
    },
}

/// Whether `v`'s tag alone makes it [`Role::Fixed`] (a box corner, a feature
/// point, a section's end): [`role`] without the ring.
pub(crate) fn fixed_by_tag(mesh: &TriMesh, v: VertexId) -> bool {
    let tag = mesh.vertex_tag(v);
    tag.box_corner || tag.feature_point || tag.section_endpoint
}

/// What `v` may do, from its tag and the feature edges of its ring `ring`.
pub(crate) fn role(mesh: &TriMesh, v: VertexId, ring: &crate::mesh::VertexRing) -> Role {
    if fixed_by_tag(mesh, v) {
        return Role::Fixed;
    }
    if !mesh.may_have_tagged_edges(v) {
        // no feature at v: no tag to look up
        return if ring.boundary {
            Role::Boundary
        } else {
            Role::Free
        };
    }
    // The first two primary tags (a third makes the vertex fixed anyway).
    let mut primary = [(v, 0u32, 0.0f64, 0.0f64); 2];
    let mut n_primary = 0usize;
    let mut secondary = 0;
    for &w in &ring.neighbours {
        let key = EdgeKey::new(v, w);
        let tags = mesh.edge_tags(v, w);
        if tags
            .iter()
            .any(|t| matches!(t, FeatureOn::Secondary { .. }))
        {
            secondary += 1;
        }
        for t in tags {
            if let FeatureOn::Primary { section, t } = *t {
                if let Some(slot) = primary.get_mut(n_primary) {
                    *slot = (w, section, t_at(key, t, v), t_at(key, t, w));
                }
                n_primary += 1;
            }
        }
    }
    let featured = secondary > 0 || n_primary > 0;
    if ring.boundary {
        return if featured {
            Role::Fixed
        } else {
            Role::Boundary
        };
    }
    match (n_primary, secondary) {
        (0, 0) => Role::Free,
        (0, 2) => Role::Secondary,
        (0, _) => Role::SecondaryJunction,
        (2, 0) if primary[0].1 == primary[1].1 && primary[0].2 == primary[1].2 => Role::Primary {
            section: primary[0].1,
            t: primary[0].2,
            along: [(primary[0].0, primary[0].3), (primary[1].0, primary[1].3)],
        },
        _ => Role::Fixed,
    }
}

/// The largest AMIPS energy of the faces (f64 positions; curved energies in
/// curved mode).
pub(crate) fn max_energy(mesh: &TriMesh, ctx: &Context, faces: &[FaceId]) -> f64 {
    max_energy_of(mesh, ctx, faces.iter().map(|&f| mesh.face(f)))
}

/// The largest AMIPS energy of triangles given by their vertices (f64
/// positions). In curved mode, the curved energy with the edge tags the mesh
/// has now (an edge that does not exist yet is straight).
pub(crate) fn max_energy_of(
    mesh: &TriMesh,
    ctx: &Context,
    tris: impl IntoIterator<Item = [VertexId; 3]>,
) -> f64 {
    match ctx.curved {
        None => max_corner_energy_of(mesh, tris),
        Some(rule) => tris
            .into_iter()
            .map(|t| invariants::curved::energy(mesh, ctx, &rule, t).unwrap_or(f64::INFINITY))
            .fold(0.0, f64::max),
    }
}

/// In curved mode, the largest straight (corner) AMIPS energy of the faces, for
/// the corner rule ([`CurvedRule::corner_floor`]); `None` in linear mode, where
/// the energy rule compares these energies already.
pub(crate) fn corner_energy(mesh: &TriMesh, ctx: &Context, faces: &[FaceId]) -> Option<f64> {
    ctx.curved
        .map(|_| max_corner_energy(mesh, faces.iter().copied()))
}

/// The largest straight (corner) AMIPS energy of the faces, whatever the mode.
pub(crate) fn max_corner_energy(mesh: &TriMesh, faces: impl IntoIterator<Item = FaceId>) -> f64 {
    max_corner_energy_of(mesh, faces.into_iter().map(|f| mesh.face(f)))
}

/// [`max_corner_energy`] of triangles given by their vertices (a change's
/// new faces, before it is made).
pub(crate) fn max_corner_energy_of(
    mesh: &TriMesh,
    tris: impl IntoIterator<Item = [VertexId; 3]>,
) -> f64 {
    tris.into_iter()
        .map(|t| {
            let [a, b, c] = t.map(|x| mesh.position(x));
            crate::element::energy::amips(a, b, c)
        })
        .fold(0.0, f64::max)
}

/// Off-curve distance a primary vertex may have after an operation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CurveBudget {
    pub(crate) vertex: VertexId,
    pub(crate) max_off: f64,
}

/// Whether one of `faces` has an edge on a curved primary section (a cubic or
/// conic, not a straight one): a move that ignores the curves' bulge (the
/// equalisation's relaxation toward the neighbours' mean) leaves such a ring
/// alone.
pub(crate) fn faces_a_curve(mesh: &TriMesh, ctx: &Context, faces: &[FaceId]) -> bool {
    faces.iter().any(|&f| {
        let [a, b, c] = mesh.face(f);
        [(a, b), (b, c), (c, a)].into_iter().any(|(x, y)| {
            mesh.edge_tags(x, y).iter().any(|t| match t {
                FeatureOn::Primary { section, .. } => ctx
                    .section(*section)
                    .is_none_or(|s| !matches!(s.parent, crate::features::Parent::Line(_))),
                FeatureOn::Secondary { .. } => false,
            })
        })
    })
}
