//! The curving stage: a linear [`TriMesh`] whose primary feature edges carry
//! their curve pieces becomes a [`CurvedMesh`] of quadratic or cubic Lagrange
//! triangles, every one certified valid (thesis §4.4.2 "Splitting and Curving",
//! "Curved Optimization"; docs/design.md "Curved elements").
//!
//! Steps of [`curve_mesh`] (each in its own module):
//! 1. vertices still rational are rounded (an error if one cannot be; `repair`);
//! 2. every triangle with more than one curved edge (a primary edge on a cubic;
//!    primary edges on straight parents stay straight) is split (`ops::try_split`:
//!    an edge that is not curved if it has one, else its longest curved edge) until
//!    each has at most one (`repair`);
//! 3. each primary edge takes its curve piece: the cubic nodes at the parameter
//!    thirds (order 3, which reproduces the piece exactly) or the parameter
//!    midpoint (order 2); at equal arc length instead where the cubic's
//!    parametric speed is uneven, which would bunch the nodes and drop the
//!    element's Jacobian ratio (`features::Parent::along`). When a corner is
//!    off its curve (a vertex the BSP left on
//!    a chord) the piece is moved by the linear blend of the two corner offsets,
//!    so the element still passes through its corners (`shape`);
//! 4. repair of elements that are not certified, on the linear mesh: a straight
//!    sliver (exactly positive, but `det J` within the zero tolerance) is swapped,
//!    smoothed or collapsed away; for a curved element, smooth the
//!    vertex opposite the curved edge, then split the curved edge at its
//!    parameter midpoint (within [`CurveOptions::max_splits`], never below
//!    [`CurveOptions::l_min_abs`], and only when no new triangle's energy exceeds
//!    [`OptimizerParams::stop_energy_curved`] or the worst of the faces it replaces: a
//!    vertex almost on the curve's chord line would make the halves needles,
//!    and such an element is better fitted in step 6), re-curving and
//!    re-certifying what changed (`repair`);
//! 5. curved optimization ([`super::optimize`]): collapse, swap and smoothing
//!    with the invariants in curved mode (a primary edge's piece may turn up to
//!    [`CurveOptions::curved_alpha`], every touched element certified with its
//!    exact piece, curved energies), skipped when [`OptimizerParams::max_passes_curved`]
//!    is 0; the exact shape is then taken again on the optimized mesh;
//! 6. the elements still not certified get a constrained fit of their free
//!    nodes (the curved edge's inner nodes, shared by both triangles on that
//!    edge, and the two centres): the largest certified blend toward the
//!    straight edge, then a pattern search minimising the nodes' distance to
//!    the curve under certified positivity of both triangles; if no curved
//!    position is certified, the edge stays straight (both neighbours straight
//!    there; `fit`);
//! 7. the nodes are numbered and the elements and feature lines written; every
//!    element is certified once more and the distances to the curves measured
//!    (`assemble`).
//!
//! Guarantees: every element of the returned mesh is certified
//! ([`crate::element::jacobian::certify_element`] says `Certified`; the last
//! step re-checks all of them and returns [`crate::Error::Meshing`] otherwise).
//! Nodes on an edge are shared by both triangles on it and by the edge's line
//! element.

use super::assemble::{assemble, finish_stats};
use super::fit::fit_all;
use super::optimize::{CurvedOptimizeOptions, CurvedOptimizeStats, optimize_curved};
use super::repair::{repair, round_all, split_multi_primary};
use super::shape::{Bend, exact_shape};
use crate::Result;
use crate::budget::Deadline;
use crate::element::Order;
use crate::element::jacobian::CertifyOptions;
use crate::fem::LineKind;
use crate::mesh::{FeatureOn, TriMesh};
use crate::ops::{Context, CurvedRule};
use crate::params::OptimizerParams;
use crate::svg::ShapeId;
use kurbo::Point;

/// How the curving stage works.
#[derive(Clone, Copy, Debug)]
#[non_exhaustive]
pub(crate) struct CurveOptions<'a> {
    /// Element order of the output (1: straight, 2: quadratic, 3: cubic).
    pub order: Order,
    /// The input's bounding-box diagonal `d` (user units): distances in
    /// [`CurveStats`] are relative to it.
    pub d: f64,
    /// Curved edges shorter than this (user units) are not split for repair.
    pub l_min_abs: f64,
    /// Most splits (multi-primary triangles and repair together).
    pub max_splits: usize,
    /// Rounds of the repair on the linear mesh (smooth, then split).
    pub repair_rounds: usize,
    /// Pattern-search iterations of one fit.
    pub fit_iterations: usize,
    /// Smallest certified Jacobian ratio (`lower / upper` of the certificate) a
    /// fitted element may have: the fit stops short of near-degenerate elements.
    pub fit_min_ratio: f64,
    /// How elements are certified while curving.
    pub certify: CertifyOptions,
    /// Target edge length `l` of the curved optimization (user units).
    pub l_abs: f64,
    /// The user's optimizer parameters, carried whole from
    /// [`crate::Params::optimizer`]: the curved optimization stops below
    /// `stop_energy_curved` or after `max_passes_curved` passes past its
    /// preliminary one (0 skips it), and its passes read their knobs here.
    pub params: OptimizerParams,
    /// The curved optimization's corner rule ([`CurvedRule::corner_floor`]): no
    /// operation makes a straight (corner) AMIPS energy larger than this and the
    /// worst of the faces it replaces. Default: the linear stop energy.
    pub corner_floor: f64,
    /// Bound on the turn of a primary edge's curve piece in the curved
    /// optimization, radians (strict; less than π).
    pub curved_alpha: f64,
    /// The run's wall-clock limit: the curved optimization starts no pass
    /// after it (default none).
    pub deadline: Deadline,
    /// The size field the curved optimization measures edges against
    /// (default: `l_abs` everywhere).
    pub size: Option<&'a crate::sizing::SizeField>,
}

/// Default [`CurveOptions::max_splits`]: a budget that only a runaway repair
/// reaches. Empirical (`docs/tuning.md`).
const DEFAULT_MAX_SPLITS: usize = 10_000;
/// Default [`CurveOptions::repair_rounds`]. Empirical (`docs/tuning.md`).
const DEFAULT_REPAIR_ROUNDS: usize = 8;
/// Default [`CurveOptions::fit_iterations`]. Empirical (`docs/tuning.md`).
const DEFAULT_FIT_ITERATIONS: usize = 80;
/// Default [`CurveOptions::fit_min_ratio`]: the fit keeps a certified Jacobian
/// ratio of at least 1 % rather than creep to a degenerate element.
/// Empirical (`docs/tuning.md`).
const DEFAULT_FIT_MIN_RATIO: f64 = 0.01;

impl<'a> CurveOptions<'a> {
    /// `d` as given; `l_min`, `l`, the curved stop energy and pass limit from
    /// [`crate::Params::DEFAULT`] (`1e-4 · d`, `0.05 · d`, 10, 10); 10 000
    /// splits, 8 repair rounds, 80 fit iterations, fitted ratio ≥ 0.01; the
    /// certification and turn bound of [`CurvedRule::new`] (validity only, 90°).
    pub(crate) fn new(order: Order, d: f64) -> Self {
        let defaults = crate::Params::DEFAULT;
        let rule = CurvedRule::new(order);
        CurveOptions {
            order,
            d,
            l_min_abs: defaults.l_min.resolve(d),
            max_splits: DEFAULT_MAX_SPLITS,
            repair_rounds: DEFAULT_REPAIR_ROUNDS,
            fit_iterations: DEFAULT_FIT_ITERATIONS,
            fit_min_ratio: DEFAULT_FIT_MIN_RATIO,
            certify: rule.certify,
            l_abs: defaults.l.resolve(d),
            params: defaults.optimizer,
            corner_floor: rule.corner_floor,
            curved_alpha: rule.alpha,
            deadline: Deadline::NONE,
            size: None,
        }
    }
    /// Set the wall-clock limit.
    pub(crate) fn with_deadline(mut self, deadline: Deadline) -> Self {
        self.deadline = deadline;
        self
    }
    /// Set the minimal edge length below which curved edges are not split.
    pub(crate) fn with_l_min_abs(mut self, l: f64) -> Self {
        self.l_min_abs = l;
        self
    }
    /// Set the size field of the curved optimization (its largest size is `l`).
    pub(crate) fn with_size(mut self, field: &'a crate::sizing::SizeField) -> Self {
        self.l_abs = field.l();
        self.size = Some(field);
        self
    }
    /// Set the target edge length `l` (user units) of the curved optimization.
    #[cfg(test)]
    pub(crate) fn with_l_abs(mut self, l: f64) -> Self {
        self.l_abs = l;
        self
    }
    /// Set the corner rule's floor (normally the linear stage's stop energy).
    pub(crate) fn with_corner_floor(mut self, energy: f64) -> Self {
        self.corner_floor = energy;
        self
    }
    /// Set the optimizer parameters (the curved stop rule among them).
    pub(crate) fn with_optimizer(mut self, params: OptimizerParams) -> Self {
        self.params = params;
        self
    }
}

/// What the curving stage did (part of `--stats`).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CurveStats {
    /// Element order.
    pub order: u8,
    /// Triangles with an edge on a curved (cubic) feature that is curved in the output.
    pub curved_triangles: usize,
    /// Of those, triangles whose curved edge or centre was fitted (not the exact piece).
    pub fitted_triangles: usize,
    /// Triangles left straight on a curved feature for lack of a valid fit.
    pub straight_triangles: usize,
    /// Splits of triangles with more than one primary edge.
    pub splits_multi_primary: usize,
    /// Splits of curved edges to repair elements.
    pub splits_repair: usize,
    /// Smoothings applied to repair elements.
    pub smooths_repair: usize,
    /// Local operations applied to straight slivers that could not be certified.
    pub sliver_repairs: usize,
    /// Largest sampled distance of a primary edge from its curve piece, relative to `d`.
    pub max_curve_distance_rel: f64,
    /// Mean over primary edges of their largest sampled distance, relative to `d`.
    pub mean_curve_distance_rel: f64,
    /// Largest distance of a primary edge's corner from its curve point `c(t)`,
    /// relative to `d`: vertices the linear mesh left off their curve (the curved
    /// edge follows the curve up to this offset).
    pub max_corner_offset_rel: f64,
    /// Smallest certified Jacobian ratio (lower bound of `min det J / max det J`) of
    /// the curved elements (1 when none is curved).
    pub min_jacobian_ratio: f64,
    /// What the curved optimization did.
    pub optimization: CurvedOptimizeStats,
}

/// A mesh of Lagrange triangles of one order, with its feature lines (gmsh node order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CurvedMesh {
    /// Element order.
    pub order: Option<Order>,
    /// All nodes: vertices first (live vertices in id order), then edge and centre nodes.
    pub nodes: Vec<Point>,
    /// Flat connectivity, `order.triangle_nodes()` per triangle (gmsh types 2 / 9 / 21).
    pub triangles: Vec<u32>,
    /// Flat connectivity of the feature lines, `order.line_nodes()` per line
    /// (ends, then inner nodes along the line; gmsh types 1 / 8 / 26).
    pub lines: Vec<u32>,
    /// The shape and kind of each line.
    pub line_feature: Vec<(ShapeId, LineKind)>,
}

impl CurvedMesh {
    /// The element order (linear when unset).
    pub fn order(&self) -> Order {
        self.order.unwrap_or(Order::Linear)
    }
}

/// Curve every primary edge of `mesh` (see the module doc), splitting and
/// repairing on `mesh` first. `feature` names the shape and kind of each tag (as
/// for [`crate::fem::LinearMesh::from_trimesh`]).
///
/// # Errors
/// [`crate::Error::Meshing`] (stage `curve`) if a vertex stays rational, or an
/// element cannot be certified even straight: a sliver of the linear mesh,
/// exactly positive but with `det J` within the zero tolerance, that no local
/// operation could remove (e.g. between two features 1e-16 apart).
pub(crate) fn curve_mesh<I: IntoIterator<Item = (ShapeId, LineKind)>>(
    mesh: &mut TriMesh,
    ctx: &Context,
    opts: &CurveOptions,
    feature: impl Fn(&FeatureOn) -> I,
) -> Result<(CurvedMesh, CurveStats)> {
    let _span = tracing::info_span!("curve", order = opts.order as u8).entered();
    round_all(mesh, ctx)?;
    let order = opts.order;
    let mut stats = CurveStats {
        order: order as u8,
        min_jacobian_ratio: 1.0,
        ..CurveStats::default()
    };
    let mut shape = Bend::default();
    if order != Order::Linear {
        let mut budget = opts.max_splits;
        stats.splits_multi_primary += split_multi_primary(mesh, ctx, &mut budget);
        repair(mesh, ctx, opts, &mut stats, &mut budget);
        if opts.params.max_passes_curved > 0 {
            stats.optimization = curved_optimization(mesh, ctx, opts);
        }
        shape = exact_shape(mesh, ctx, order);
        fit_all(mesh, opts, &mut shape, &mut stats);
    }
    let curved = assemble(mesh, order, &shape, feature);
    finish_stats(mesh, ctx, opts, &shape, &curved, &mut stats)?;
    tracing::debug!(?stats, "curving done");
    Ok((curved, stats))
}

/// Step 5: the curved mesh optimization with `opts`' turn bound, certification
/// and stop rules.
fn curved_optimization(
    mesh: &mut TriMesh,
    ctx: &Context,
    opts: &CurveOptions,
) -> CurvedOptimizeStats {
    let rule = CurvedRule {
        order: opts.order,
        certify: opts.certify,
        alpha: opts.curved_alpha,
        corner_floor: opts.corner_floor,
    };
    let curved_opts = CurvedOptimizeOptions {
        l: opts.l_abs,
        field: opts.size,
        stop_energy: opts.params.stop_energy_curved,
        max_passes: opts.params.max_passes_curved,
        deadline: opts.deadline,
        params: opts.params,
    };
    optimize_curved(mesh, &ctx.with_curved(rule), &curved_opts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::repair::curved_edges;
    use crate::element::jacobian;
    use crate::features::Parent;
    use crate::mesh::VertexTag;
    use crate::ops::invariants::Envelope;
    use crate::ops::{CurveSection, EnergyRule};
    use kurbo::CubicBez;

    const FIXED: VertexTag = VertexTag {
        box_corner: true,
        feature_point: false,
        segment_endpoint: false,
        section_endpoint: false,
    };

    fn context(curves: &[CubicBez]) -> Context {
        Context {
            sections: curves
                .iter()
                .map(|&c| CurveSection {
                    parent: Parent::Cubic(c),
                    t: [0.0, 1.0],
                    source: None,
                    shared: None,
                })
                .collect(),
            envelope: Envelope::new(&[], 1e-3, 1e-3),
            alpha: std::f64::consts::PI,
            on_curve_abs: 1e-12,
            energy: EnergyRule::NoWorseMax,
            energy_floor: 0.0,
            max_new_edge: f64::INFINITY,
            curved: None,
            fixed_boundary: false,
        }
    }

    fn feature(_: &FeatureOn) -> [(ShapeId, LineKind); 1] {
        [(ShapeId::from_index(0), LineKind::Primary)]
    }

    /// Two triangles on the primary edge (0,0)–(1,0) (the cubic `c`), apex at
    /// `(0.5, apex)` above and `(0.5, -1)` below; all vertices fixed.
    fn diamond(c: CubicBez, apex: f64) -> (TriMesh, Context) {
        let mut m = TriMesh::new();
        let a = m.add_vertex(Point::new(0.0, 0.0), FIXED);
        let b = m.add_vertex(Point::new(1.0, 0.0), FIXED);
        let top = m.add_vertex(Point::new(0.5, apex), FIXED);
        let bottom = m.add_vertex(Point::new(0.5, -1.0), FIXED);
        m.add_face([a, b, top]);
        m.add_face([b, a, bottom]);
        m.link_all();
        m.add_edge_tag(
            a,
            b,
            FeatureOn::Primary {
                section: 0,
                t: [0.0, 1.0],
            },
        );
        (m, context(&[c]))
    }

    fn all_certified(cm: &CurvedMesh) -> bool {
        let order = cm.order();
        cm.triangles.chunks_exact(order.triangle_nodes()).all(|t| {
            let pts: Vec<Point> = t.iter().map(|&i| cm.nodes[i as usize]).collect();
            jacobian::certify_element(order, &pts, &CertifyOptions::DEFAULT)
                .is_some_and(|c| c.is_certified())
        })
    }

    #[test]
    fn gentle_curve_is_exact_and_shared() {
        let c = CubicBez::new((0.0, 0.0), (0.3, 0.1), (0.7, 0.1), (1.0, 0.0));
        let (mut m, ctx) = diamond(c, 0.6);
        let opts = CurveOptions::new(Order::Cubic, 2.0);
        let (cm, stats) = curve_mesh(&mut m, &ctx, &opts, feature).expect("curving");
        assert_eq!(stats.curved_triangles, 2, "{stats:?}");
        assert_eq!(stats.fitted_triangles + stats.straight_triangles, 0);
        assert!(stats.max_curve_distance_rel < 1e-15, "{stats:?}");
        assert!(all_certified(&cm));
        // 4 vertices + 5 edges × 2 + 2 centres; the line shares the edge's nodes
        assert_eq!(cm.nodes.len(), 4 + 10 + 2);
        assert_eq!(cm.lines.len(), 4);
        let t0 = &cm.triangles[..10];
        let t1 = &cm.triangles[10..20];
        let line = &cm.lines;
        for n in &line[2..] {
            assert!(t0.contains(n) && t1.contains(n));
        }
        // the line runs from its first end through 1/3 and 2/3 (gmsh type 26)
        let p = |i: usize| cm.nodes[line[i] as usize];
        let s = if p(0).x < p(1).x {
            1.0 / 3.0
        } else {
            2.0 / 3.0
        };
        assert!((p(2) - kurbo::ParamCurve::eval(&c, s)).hypot() < 1e-15);
        // order 2: the midpoint
        let (mut m, ctx) = diamond(c, 0.6);
        let (cm, _) = curve_mesh(
            &mut m,
            &ctx,
            &CurveOptions::new(Order::Quadratic, 2.0),
            feature,
        )
        .expect("curving");
        assert_eq!(cm.lines.len(), 3);
        assert!((cm.nodes[cm.lines[2] as usize] - Point::new(0.5, 0.075)).hypot() < 1e-15);
        assert!(all_certified(&cm));
    }

    #[test]
    fn uneven_cubic_speed_keeps_the_jacobian_ratio() {
        // A nearly straight edge on a cubic whose first control point sits next to
        // its start: at the parameter thirds the edge's nodes bunch toward that end
        // and the element is certified, but with a ratio far below 0.1;
        // at equal arc length it is nearly straight.
        let c = CubicBez::new((0.0, 0.0), (0.002, 0.0002), (0.41, 0.03), (1.0, 0.0));
        let corners = [
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(0.5, 0.6),
        ];
        for order in [Order::Cubic, Order::Quadratic] {
            let thirds = crate::element::triangle::piece_inner(
                |s| kurbo::ParamCurve::eval(&c, s),
                [0.0, 1.0],
                corners[0],
                corners[1],
                order,
            );
            let nodes = crate::element::triangle::nodes(
                order,
                corners,
                [Some(&thirds), None, None],
                kurbo::Vec2::ZERO,
            );
            let at_thirds = jacobian::certify_element(order, &nodes, &CertifyOptions::DEFAULT)
                .expect("certificate");
            assert!(at_thirds.ratio() < 0.1, "{order:?} {at_thirds:?}");
            let (mut m, ctx) = diamond(c, 0.6);
            let opts = CurveOptions::new(order, 2.0);
            let (cm, stats) = curve_mesh(&mut m, &ctx, &opts, feature).expect("curving");
            assert!(all_certified(&cm));
            assert_eq!(stats.curved_triangles, 2, "{stats:?}");
            assert!(stats.min_jacobian_ratio > 0.5, "{order:?} {stats:?}");
            // still on the curve
            assert!(stats.max_curve_distance_rel < 1e-3, "{order:?} {stats:?}");
        }
    }

    #[test]
    fn bulge_past_the_apex_is_fitted_not_dropped() {
        // The arc rises to 0.45, above the fixed apex at 0.3: the exact element is
        // inverted, no split may help (edge below l_min), so the nodes are fitted.
        let c = CubicBez::new((0.0, 0.0), (0.3, 0.6), (0.7, 0.6), (1.0, 0.0));
        let (mut m, ctx) = diamond(c, 0.3);
        for order in [Order::Cubic, Order::Quadratic] {
            let opts = CurveOptions::new(order, 1.0).with_l_min_abs(10.0);
            let (cm, stats) = curve_mesh(&mut m.clone(), &ctx, &opts, feature).expect("curving");
            assert!(all_certified(&cm), "{order:?}");
            assert_eq!(stats.fitted_triangles, 2, "{order:?} {stats:?}");
            assert_eq!(stats.straight_triangles, 0, "{order:?} {stats:?}");
            assert_eq!(stats.curved_triangles, 2);
            // closer than the chord (0.45 away), still not the curve; the corner
            // angles bound the edge's end slopes, so it cannot rise much above 0.15
            assert!(
                stats.max_curve_distance_rel > 0.25 && stats.max_curve_distance_rel < 0.4,
                "{order:?} {stats:?}"
            );
            assert!(stats.min_jacobian_ratio >= opts.fit_min_ratio, "{stats:?}");
        }
        // With splits allowed, the repair splits first; the result is still certified.
        let opts = CurveOptions::new(Order::Cubic, 1.0).with_l_min_abs(1e-3);
        let (cm, stats) = curve_mesh(&mut m, &ctx, &opts, feature).expect("curving");
        assert!(all_certified(&cm));
        assert!(stats.splits_repair > 0, "{stats:?}");
    }

    #[test]
    fn two_curved_edges_are_separated() {
        let mut m = TriMesh::new();
        let a = m.add_vertex(Point::new(0.0, 0.0), FIXED);
        let b = m.add_vertex(Point::new(1.0, 0.0), FIXED);
        let c = m.add_vertex(Point::new(0.5, 1.0), FIXED);
        m.add_face([a, b, c]);
        m.link_all();
        let ab = CubicBez::new((0.0, 0.0), (0.3, -0.1), (0.7, -0.1), (1.0, 0.0));
        let bc = CubicBez::new((1.0, 0.0), (0.9, 0.4), (0.8, 0.7), (0.5, 1.0));
        let ctx = context(&[ab, bc]);
        m.add_edge_tag(
            a,
            b,
            FeatureOn::Primary {
                section: 0,
                t: [0.0, 1.0],
            },
        );
        m.add_edge_tag(
            b,
            c,
            FeatureOn::Primary {
                section: 1,
                t: [0.0, 1.0],
            },
        );
        let opts = CurveOptions::new(Order::Cubic, 1.5);
        let (cm, stats) = curve_mesh(&mut m, &ctx, &opts, feature).expect("curving");
        assert_eq!(stats.splits_multi_primary, 1, "{stats:?}");
        assert_eq!(m.num_faces(), 2);
        for f in m.faces() {
            assert_eq!(curved_edges(&m, &ctx, f).len(), 1);
        }
        assert!(all_certified(&cm));
        assert_eq!(stats.curved_triangles, 2);
        assert!(stats.max_curve_distance_rel < 1e-15);
    }
}
