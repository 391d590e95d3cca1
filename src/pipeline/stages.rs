//! The stages of one run, each one call (docs/design.md "Data flow"): the
//! periodic tile, the size field, then the CDT baseline or TriWild's
//! features → BSP → optimization → curving, then regions, the periodic match,
//! quality and the report.
//!
//! Every stage takes its input and the run's [`StageOptions`], built once from
//! the parameters, and returns its output and its statistics; the [`Log`]
//! gathers the seconds per stage and the warnings in the order the stages
//! push them. `--stop-after` is one early return per stage
//! ([`triwild_stages`]). The front (size field, then features) is
//! [`sizing_stage`] and [`features_stage`], which [`mesh_stages`] and
//! [`front`] (the tests, `triwild features`) share.

use super::density;
use super::snap;
use super::warnings;
use super::{InputCounts, Meshed, OutputCounts, Report};
use crate::bsp::{self, BspInput, BspOptions, BspSegment, BspStats};
use crate::budget::Deadline;
use crate::curve::{CurveOptions, CurveStats, CurvedMesh, curve_mesh};
use crate::error::check_deadline;
use crate::features::{self, FeatureCounts, FeatureSet, PrimaryChains};
use crate::fem::{FemMesh, LineKind, LinearMesh};
use crate::mesh::{FeatureOn, TriMesh};
use crate::ops::Context;
use crate::optimize::forced::ForcedCorners;
use crate::optimize::{LinearOptions, OptimizeOptions, OptimizeStats, PassLimits};
use crate::params::{Mesher, Params, Resolved, Stage};
use crate::periodic::{Cell, PeriodicReport};
use crate::quality::Quality;
use crate::regions::select::RegionMode;
use crate::regions::{RegionOptions, RegionReport};
use crate::sizing::{FieldInput, SizeField, SizingReport};
use crate::svg::{Drawing, ShapeId};
use crate::{Error, Result};
use kurbo::Rect;
use std::collections::BTreeMap;
use std::time::Instant;

/// What every stage reads of the run, built once from the parameters: the
/// parameters, the region options, their lengths resolved against the
/// drawing meshed (a periodic tile's d is its cell's), and the run's deadline.
/// Each stage's own options come from here ([`StageOptions::optimize`],
/// [`StageOptions::curve`], ...), so a new knob is a field of [`Params`] and
/// one line in the stage's options.
pub(super) struct StageOptions<'a> {
    /// The run's parameters.
    pub(super) params: &'a Params,
    /// How regions are named, grouped and dropped.
    pub(super) regions: &'a RegionOptions,
    /// `params` in absolute units for the drawing meshed.
    pub(super) resolved: Resolved,
    /// The run's wall-clock limit, checked between stages and in their loops.
    pub(super) deadline: Deadline,
}

impl<'a> StageOptions<'a> {
    /// The options of a run meshing `drawing` (the periodic tile, if any).
    pub(super) fn new(
        params: &'a Params,
        regions: &'a RegionOptions,
        drawing: &Drawing,
        deadline: Deadline,
    ) -> Self {
        StageOptions {
            params,
            regions,
            resolved: params.resolve(drawing.diagonal()),
            deadline,
        }
    }

    /// The options of a run with the default regions (one surface per filled
    /// shape), as `triwild features` and the tests build them.
    pub(super) fn default_regions(
        params: &'a Params,
        drawing: &Drawing,
        deadline: Deadline,
    ) -> Self {
        static DEFAULT_REGIONS: RegionOptions = RegionOptions::DEFAULT;
        StageOptions::new(params, &DEFAULT_REGIONS, drawing, deadline)
    }

    /// The most primary sections the features stage cuts to a size below the
    /// separation's: half the vertex budget, so the outlines leave room for the
    /// mesh inside them.
    fn section_budget(&self) -> usize {
        self.params.max_vertices as usize / 2
    }

    /// The BSP's options: its defaults, with the run's deadline.
    fn bsp(&self) -> BspOptions {
        BspOptions::DEFAULT.with_deadline(self.deadline)
    }

    /// The optimizer's options (thesis §2.3.2: target `l`, sizing floor ε).
    pub(super) fn optimize(&self) -> OptimizeOptions {
        let (params, resolved) = (self.params, &self.resolved);
        OptimizeOptions {
            limits: PassLimits {
                l: resolved.l,
                deadline: self.deadline,
                params: params.optimizer,
            },
            linear: LinearOptions {
                l_floor: resolved.eps.min(resolved.l),
                stop_energy: params.optimizer.stop_energy,
                alpha_deg: params.alpha_deg,
                max_passes: params.optimizer.max_passes,
                max_vertices: params.max_vertices as usize,
            },
        }
    }

    /// The curving stage's options against the size field `field` (its
    /// largest size is `l`).
    fn curve<'f>(&self, field: &'f SizeField) -> CurveOptions<'f> {
        let (params, resolved) = (self.params, &self.resolved);
        CurveOptions::new(params.order, resolved.d)
            .with_l_min_abs(resolved.l_min)
            .with_size(field)
            .with_optimizer(params.optimizer)
            .with_corner_floor(self.corner_floor())
            .with_deadline(self.deadline)
    }

    /// The curved stage's corner rule ([`crate::ops::CurvedRule::corner_floor`]):
    /// the linear stop energy, or the energy below which no corner is under α
    /// if that is lower, so the curved passes never make a straight corner below
    /// α where the linear stage left none (the stop energy alone admits triangles
    /// with corners near 7°, below the default α of 10°).
    fn corner_floor(&self) -> f64 {
        self.params
            .optimizer
            .stop_energy
            .min(crate::optimize::needle_energy(self.resolved.alpha))
    }
}

/// What the stages record beside their outputs: seconds per stage, and the
/// warnings in the order they were pushed (the drawing's first).
#[derive(Default)]
pub(super) struct Log {
    /// Seconds per stage.
    pub(super) times: Times,
    /// Warnings for the report.
    pub(super) warnings: Vec<String>,
}

/// The front of TriWild's pipeline: the drawing meshed, its size field, and
/// its features resampled against the field.
pub(super) struct Front<'a> {
    /// The drawing meshed (a periodic tile, or the drawing itself).
    pub(super) drawing: &'a Drawing,
    /// The size field every stage meets.
    pub(super) field: &'a SizeField,
    /// The features ([`features_stage`]).
    pub(super) features: FeatureSet,
}

/// TriWild's mesh between its linear stages: the triangulation and the
/// operations' context (curves of the primary sections, ε-envelope of the
/// secondary polylines).
pub(super) struct Linear {
    /// The mesh; after the BSP, vertices it could not round stay rational
    /// (the optimizer rounds them).
    pub(super) mesh: TriMesh,
    /// The context the mesh's feature tags index.
    pub(super) ctx: Context,
}

/// What each TriWild stage did (all `None` for the CDT baseline).
#[derive(Default)]
struct StageStats {
    features: Option<FeatureCounts>,
    bsp: Option<BspStats>,
    optimize: Option<OptimizeStats>,
    curve: Option<CurveStats>,
}

/// What the mesher hands to the FEM conversion.
enum Delivered {
    Linear(LinearMesh),
    Curved(CurvedMesh),
}

/// The meshers' product: the delivered mesh, its triangles' forced corners
/// (TriWild's), the positions of the vertices the optimizer refined below
/// the field, and what each stage did.
struct Meshing {
    delivered: Delivered,
    forced: Option<ForcedCorners>,
    refined: Vec<kurbo::Point>,
    stats: StageStats,
}

/// The regions stage's product: the FEM mesh tagged with its physical groups,
/// the report, and the shapes whose regions the mesh lost.
struct Regions {
    mesh: FemMesh,
    report: RegionReport,
    lost: Vec<ShapeId>,
}

/// The stages of [`super::mesh_within`], on the current thread pool; with the
/// size field they met (the CDT baseline's: `l` everywhere) and each delivered
/// triangle's mask of forced corners (empty for the CDT baseline; see
/// [`crate::optimize::forced`]).
pub(super) fn mesh_stages(
    drawing: &Drawing,
    params: &Params,
    regions: &RegionOptions,
    deadline: Deadline,
) -> Result<(Meshed, SizeField, Vec<u8>)> {
    let mut log = Log::default();
    let (cell, tile) = periodic_stage(drawing, params, regions, &mut log)?.unzip();
    let drawing = tile.as_ref().unwrap_or(drawing);
    let opts = StageOptions::new(params, regions, drawing, deadline);
    log.warnings = drawing.warnings.clone();
    let field = sizing_stage(drawing, &opts, &mut log)?;
    let meshing = match params.mesher {
        Mesher::Cdt => baseline_stage(drawing, &field, &opts, &mut log)?,
        Mesher::TriWild => triwild_stages(drawing, &field, &opts, &mut log)?,
    };
    let mut out = regions_stage(drawing, &meshing.delivered, &opts, &mut log)?;
    let periodic = cell.map(|c| cell_stage(c, &mut out.mesh, &mut log));
    let curved = matches!(meshing.delivered, Delivered::Curved(_));
    log.warnings
        .extend(region_warnings(drawing, &out, curved, &opts));
    let (quality, mask) = quality_stage(&out.mesh, meshing.forced.as_ref(), &opts, &mut log);
    out.report.small = crate::regions::SmallRegions::of(&out.report.surfaces);
    let sizing = sizing_report(&out.mesh, &field, &meshing.refined, &mut log);
    let mut stats = meshing.stats;
    if let Some(c) = &mut stats.curve {
        c.min_jacobian_ratio = quality.min_jacobian_ratio;
    }
    let t_core = log.times.0.values().sum();
    let report = Report {
        input: InputCounts::of(drawing),
        params: opts.resolved,
        mesher: params.mesher,
        times: log.times.0,
        t_core,
        output: OutputCounts::of(&out.mesh),
        quality,
        regions: out.report,
        features: stats.features,
        bsp: stats.bsp,
        stopped_after: params.stop_after,
        optimize: stats.optimize,
        curve: stats.curve,
        sizing: Some(sizing),
        warnings: log.warnings,
        periodic,
        peak_memory_mb: crate::budget::peak_memory_mb(),
    };
    let mesh = out.mesh;
    Ok((Meshed { mesh, report }, field, mask))
}

/// TriWild (`--mesher triwild`): features → BSP → optimization → curving,
/// each `--stop-after` one early return with the linear mesh of its stage.
fn triwild_stages(
    drawing: &Drawing,
    field: &SizeField,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<Meshing> {
    let features = features_stage(drawing, field, opts, log)?;
    let front = Front {
        drawing,
        field,
        features,
    };
    let mut stats = StageStats {
        features: Some(front.features.counts),
        ..StageStats::default()
    };
    let stop_after = opts.params.stop_after;
    let (mut linear, bsp) = bsp_stage(&front, opts, log)?;
    if stop_after == Some(Stage::Bsp) {
        stats.bsp = Some(snap_stage(&mut linear, bsp, opts, log)?);
        let (delivered, forced) = deliver_linear(&front, &linear, opts, log)?;
        return Ok(Meshing::triwild(delivered, forced, Vec::new(), stats));
    }
    stats.bsp = Some(bsp);
    let (optimize, refined) = optimize_stage(&front, &mut linear, opts, log)?;
    stats.optimize = Some(optimize);
    if stop_after == Some(Stage::Optimize) {
        let (delivered, forced) = deliver_linear(&front, &linear, opts, log)?;
        return Ok(Meshing::triwild(delivered, forced, refined, stats));
    }
    let (delivered, forced, curve) = curve_stage(&front, linear, opts, log)?;
    stats.curve = Some(curve);
    Ok(Meshing::triwild(delivered, forced, refined, stats))
}

impl Meshing {
    /// TriWild's product.
    fn triwild(
        delivered: Delivered,
        forced: ForcedCorners,
        refined: Vec<kurbo::Point>,
        stats: StageStats,
    ) -> Meshing {
        Meshing {
            delivered,
            forced: Some(forced),
            refined,
            stats,
        }
    }
}

/// `--periodic`: the cell and the drawing's tile in it (`None` without it),
/// refused with `--cut-outside` (the mesh covers the cell).
fn periodic_stage(
    drawing: &Drawing,
    params: &Params,
    regions: &RegionOptions,
    log: &mut Log,
) -> Result<Option<(Cell, Drawing)>> {
    if params.periodic.is_some() && regions.cut_outside {
        return Err(Error::InvalidParams(
            "--cut-outside has no meaning with --periodic: the mesh covers the cell".into(),
        ));
    }
    match params.periodic {
        Some(_) => log
            .times
            .time("periodic", || periodic_tile(drawing, params)),
        None => Ok(None),
    }
}

/// The size field of `drawing` (for either mesher, built before any
/// meshing), its regions named as `opts.regions` groups them; warns when
/// it asks below l_min.
///
/// # Errors
/// As [`SizeField::build`].
pub(super) fn sizing_stage(
    drawing: &Drawing,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<SizeField> {
    let names = region_names(drawing, opts.regions);
    let field = log.times.time("sizing", || {
        SizeField::build(&FieldInput {
            drawing,
            resolved: &opts.resolved,
            spec: &opts.params.size,
            region_names: &names,
            bounds: padded_box(drawing, opts.resolved.padding),
            deadline: opts.deadline,
            max_vertices: opts.params.max_vertices as usize,
        })
    })?;
    log.warnings
        .extend(warnings::size_clamp_warning(field.report()));
    Ok(field)
}

/// The features of `drawing` (thesis §4.3.1, §4.4) resampled against
/// `field` ([`SizeField::for_curve`]), refused first when the drawing's
/// curves cross too densely ([`density`]).
///
/// # Errors
/// [`Error::Meshing`] for a drawing too dense or past the deadline.
pub(super) fn features_stage(
    drawing: &Drawing,
    field: &SizeField,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<FeatureSet> {
    let resolved = &opts.resolved;
    check_deadline(&opts.deadline, Stage::Features)?;
    density::check(drawing, resolved.mu)?;
    let fs = log.times.time("features", || {
        FeatureSet::build_sized(
            drawing,
            resolved,
            &opts.deadline,
            &|p, source, cut| field.for_curve(p, source.shape, cut),
            opts.section_budget(),
        )
    });
    check_deadline(&opts.deadline, Stage::Features)?;
    log.warnings
        .extend(warnings::near_cell_sides_warning(&fs.counts, resolved));
    Ok(fs)
}

/// The size field and the features of `drawing` with the default region
/// names, as [`mesh_stages`] builds them: what `triwild features` analyses and
/// what the tests' meshes start from.
///
/// # Errors
/// As [`sizing_stage`] and [`features_stage`].
pub(super) fn front(
    drawing: &Drawing,
    params: &Params,
    deadline: Deadline,
) -> Result<(SizeField, FeatureSet)> {
    let opts = StageOptions::default_regions(params, drawing, deadline);
    let mut log = Log::default();
    let field = sizing_stage(drawing, &opts, &mut log)?;
    let features = features_stage(drawing, &field, &opts, &mut log)?;
    Ok((field, features))
}

/// The CDT baseline (`--mesher cdt`): the drawing's outlines triangulated
/// and refined to the field.
fn baseline_stage(
    drawing: &Drawing,
    field: &SizeField,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<Meshing> {
    check_deadline(&opts.deadline, Stage::Baseline)?;
    let linear = log.times.time("baseline", || {
        crate::baseline::triangulate(drawing, opts.params, field)
    })?;
    check_deadline(&opts.deadline, Stage::Baseline)?;
    Ok(Meshing {
        delivered: Delivered::Linear(linear),
        forced: None,
        refined: Vec::new(),
        stats: StageStats::default(),
    })
}

/// The exact BSP mesh of the front's features (TriWild §4.3-4.4 up to the
/// conforming mesh): the conforming segments and points (with the periodic
/// cell's side points, and free seed vertices at the field's density
/// where the optimizer would otherwise make them by splits) triangulated exactly in the drawing's
/// padded box ([`bsp::build`]); refused first when the segments cross too
/// densely ([`density`]). Vertices it could not round stay rational.
///
/// # Errors
/// [`Error::Meshing`] if the BSP fails or (with `params.paranoid`) its mesh
/// has a defect.
pub(super) fn bsp_stage(
    front: &Front,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<(Linear, BspStats)> {
    let (drawing, field, resolved) = (front.drawing, front.field, &opts.resolved);
    let chains = front.features.primary_chains();
    let mut input = bsp_input(&front.features, &chains);
    density::check_crossings(
        input.segments.iter().map(|s| [s.a, s.b]),
        front.features.counts.cover_cuts,
        resolved.mu,
        || density::chords(drawing),
    )?;
    let bbox = padded_box(drawing, resolved.padding);
    let cell = Cell::of_tile(drawing, opts.params);
    if let Some(cell) = &cell {
        let sides = cell_side_points(cell, &input, field, resolved.l_min);
        input.points.extend(sides);
    }
    let bsp_opts = opts.bsp();
    let (mut mesh, stats) = log.times.time("bsp", || {
        // Free vertices at the size field's density (`sizing::seeds`): where
        // an asked field is finer than l/2, and everywhere, the box's sides
        // too, where open space outnumbers the features' vertices.
        let lines: Vec<kurbo::Line> = input
            .segments
            .iter()
            .map(|s| kurbo::Line::new(s.a, s.b))
            .collect();
        let max_vertices = opts.params.max_vertices as usize;
        input.steiner =
            field.seed_points(bbox, &lines, &input.points, max_vertices, cell.is_none());
        bsp::build(&input, bbox, &bsp_opts)
    })?;
    if cell.is_some() {
        Cell::fix_sides(&mut mesh);
    }
    check_deadline(&opts.deadline, Stage::Bsp)?;
    if opts.params.paranoid {
        log.times
            .time("check", || check_trimesh(&mesh, Stage::Bsp))?;
    }
    let mut ctx = Context::from_chains(&front.features, &chains, resolved.eps, resolved.eps);
    ctx.fixed_boundary = cell.is_some();
    Ok((Linear { mesh, ctx }, stats))
}

/// The periodic cell's side points for the BSP: every feature end on a side,
/// its partner, the gaps resampled once for both partner sides.
fn cell_side_points(
    cell: &Cell,
    input: &BspInput,
    field: &SizeField,
    l_min: f64,
) -> Vec<kurbo::Point> {
    let ends: Vec<kurbo::Point> = input
        .segments
        .iter()
        .flat_map(|s| [s.a, s.b])
        .chain(input.points.iter().copied())
        .chain(input.section_endpoints.iter().copied())
        .collect();
    let chords: Vec<kurbo::Line> = input
        .segments
        .iter()
        .map(|s| kurbo::Line::new(s.a, s.b))
        .collect();
    cell.side_points(&ends, &chords, field, l_min)
}

/// `--stop-after bsp`: the BSP mesh is exact, but rounded to f64 a few
/// triangles may be degenerate; they are snapped away. Returns `stats` with
/// the counts of the mesh delivered.
///
/// # Errors
/// As [`snap::snap_degenerate`].
fn snap_stage(
    linear: &mut Linear,
    stats: BspStats,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<BspStats> {
    log.times.time("snap", || {
        snap::snap_degenerate(&mut linear.mesh, &linear.ctx, opts.resolved.d)
    })?;
    Ok(BspStats {
        vertices: linear.mesh.num_vertices(),
        triangles: linear.mesh.num_faces(),
        ..stats
    })
}

/// The AMIPS optimization (TriWild §4.4.1) of the BSP mesh against the
/// front's field, with its statistics and the positions of the vertices it
/// refined below the field; warns about primary vertices left off their
/// curves, the vertex budget, and corners left below α.
///
/// # Errors
/// [`Error::Meshing`] past the deadline or (with `params.paranoid`) for a
/// mesh defect.
pub(super) fn optimize_stage(
    front: &Front,
    linear: &mut Linear,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<(OptimizeStats, Vec<kurbo::Point>)> {
    let optimize_opts = opts.optimize();
    let (stats, refined) = log.times.time("optimize", || {
        crate::optimize::optimize_with_field(
            &mut linear.mesh,
            &mut linear.ctx,
            &optimize_opts,
            front.field,
        )
    });
    check_deadline(&opts.deadline, Stage::Optimize)?;
    if opts.params.paranoid {
        check_trimesh(&linear.mesh, Stage::Optimize)?;
    }
    log.warnings
        .extend(warnings::optimize_warnings(&stats, front, opts));
    Ok((stats, refined))
}

/// Curving (TriWild §4.4.2): the optimized mesh's elements made curved of
/// `params.order`, with each triangle's forced corners and what it did.
///
/// # Errors
/// As [`curve_mesh`], and [`Error::Meshing`] past the deadline.
fn curve_stage(
    front: &Front,
    mut linear: Linear,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<(Delivered, ForcedCorners, CurveStats)> {
    let curve_opts = opts.curve(front.field);
    let (curved, stats) = log.times.time("curve", || {
        curve_mesh(&mut linear.mesh, &linear.ctx, &curve_opts, |t| {
            feature_of(&front.features, &linear.ctx, t)
        })
    })?;
    check_deadline(&opts.deadline, Stage::Curve)?;
    let forced = classify(&linear, opts, log);
    Ok((Delivered::Curved(curved), forced, stats))
}

/// The linear mesh delivered by `--stop-after` (its stage), with each
/// triangle's forced corners.
///
/// # Errors
/// As [`LinearMesh::from_trimesh`].
fn deliver_linear(
    front: &Front,
    linear: &Linear,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<(Delivered, ForcedCorners)> {
    let forced = classify(linear, opts, log);
    let stage = opts
        .params
        .stop_after
        .expect("internal: a linear TriWild mesh is delivered only by --stop-after");
    let (mesh, ctx, fs) = (&linear.mesh, &linear.ctx, &front.features);
    let delivered = log.times.time("linear", || {
        LinearMesh::from_trimesh(mesh, stage, |t| feature_of(fs, ctx, t))
    })?;
    Ok((Delivered::Linear(delivered), forced))
}

/// The corners of the mesh's triangles that its features force below α
/// ([`crate::optimize::forced`]).
fn classify(linear: &Linear, opts: &StageOptions, log: &mut Log) -> ForcedCorners {
    log.times.time("forced", || {
        ForcedCorners::classify(&linear.mesh, &linear.ctx, opts.resolved.alpha)
    })
}

/// The FEM mesh of the delivered mesh, its feature lines oriented and its
/// triangles tagged with (or dropped by) their regions.
///
/// # Errors
/// As [`crate::regions::tag`].
fn regions_stage(
    drawing: &Drawing,
    delivered: &Delivered,
    opts: &StageOptions,
    log: &mut Log,
) -> Result<Regions> {
    let name = |s: ShapeId| drawing.shapes[s.index()].name();
    let (mut mesh, line_shape): (FemMesh, Vec<ShapeId>) = match delivered {
        Delivered::Linear(linear) => (
            FemMesh::from_linear(linear, "domain", name),
            linear.edges.iter().map(|e| e.shape).collect(),
        ),
        Delivered::Curved(cm) => (
            FemMesh::from_curved(cm, "domain", name),
            cm.line_feature.iter().map(|f| f.0).collect(),
        ),
    };
    let resolved = &opts.resolved;
    let (mesh, report, lost) = log.times.time("regions", || {
        crate::regions::orient_lines(drawing, &mut mesh, &line_shape, &opts.deadline);
        crate::regions::tag(
            drawing,
            &mesh,
            opts.regions,
            resolved.eps_m,
            resolved.l_min,
            // (a periodic tile's shapes are their whole translated copies:
            // the drawn areas would count what lies outside the cell)
            drawing.cell.is_none().then(|| crate::regions::AreaCheck {
                bounds: padded_box(drawing, resolved.padding),
                d: resolved.d,
            }),
            opts.deadline,
        )
    })?;
    Ok(Regions { mesh, report, lost })
}

/// `--periodic`: the side nodes of `mesh` paired with their partners; warns
/// about unpaired nodes and mismatches.
fn cell_stage(cell: Cell, mesh: &mut FemMesh, log: &mut Log) -> PeriodicReport {
    let report = log.times.time("periodic", || cell.finish(mesh));
    log.warnings.extend(warnings::periodic_warning(&report));
    report
}

/// The warnings about the regions: shapes the mesh lost, then (on cubic
/// curved meshes) areas off the drawn ones.
fn region_warnings(
    drawing: &Drawing,
    regions: &Regions,
    curved: bool,
    opts: &StageOptions,
) -> Vec<String> {
    let (params, resolved) = (opts.params, &opts.resolved);
    let mut out = Vec::new();
    if !regions.lost.is_empty() {
        out.push(warnings::lost_regions_warning(
            drawing,
            &regions.lost,
            resolved,
        ));
    }
    // The area check warns on cubic meshes: there a mesh that keeps the
    // outlines has the drawn areas to rounding (chords at lower orders and
    // the baseline's flattened curves change areas by design).
    if curved && params.order == crate::element::Order::Cubic {
        out.extend(warnings::area_warning(
            &regions.report,
            &regions.mesh,
            params,
            resolved,
        ));
    }
    out
}

/// The quality of the elements as written (what `triwild check` reads back:
/// the curving stage's own ratio also saw the elements regions dropped), with
/// each triangle's mask of forced corners; warns about low Jacobian ratios.
fn quality_stage(
    mesh: &FemMesh,
    forced: Option<&ForcedCorners>,
    opts: &StageOptions,
    log: &mut Log,
) -> (Quality, Vec<u8>) {
    let mask = forced.map(|f| f.mask(mesh)).unwrap_or_default();
    let quality = log.times.time("quality", || match opts.params.mesher {
        Mesher::TriWild => Quality::of_classified(mesh, &mask, opts.params.alpha_deg),
        Mesher::Cdt => Quality::of(mesh),
    });
    log.warnings.extend(
        quality
            .unforced
            .as_ref()
            .and_then(warnings::low_ratio_warning),
    );
    (quality, mask)
}

/// The size field's report, with how well the mesh's edges match it.
fn sizing_report(
    mesh: &FemMesh,
    field: &SizeField,
    refined: &[kurbo::Point],
    log: &mut Log,
) -> SizingReport {
    let mut sizing = field.report().clone();
    sizing.edges = Some(
        log.times
            .time("sizing", || mesh_edge_match(mesh, field, refined)),
    );
    sizing
}

/// The name of each shape's region as the .msh will write it under `regions`'
/// grouping (`None`: the shape paints no region), for the size fields that
/// name regions.
fn region_names(drawing: &Drawing, regions: &RegionOptions) -> Vec<Option<String>> {
    drawing
        .shapes
        .iter()
        .map(|s| {
            s.filled.then(|| match regions.mode {
                RegionMode::Shape => s.name(),
                RegionMode::Colour => crate::regions::colour_name(s),
                RegionMode::None => crate::regions::DOMAIN.to_owned(),
            })
        })
        .collect()
}

/// How well the delivered mesh's edges (between its triangles' corners) match
/// `field`, leaving out the edges at vertices the optimizer refined below it.
fn mesh_edge_match(
    mesh: &FemMesh,
    field: &SizeField,
    refined: &[kurbo::Point],
) -> crate::sizing::EdgeMatch {
    use rayon::prelude::*;
    let key = |p: kurbo::Point| (p.x.to_bits(), p.y.to_bits());
    let refined: rustc_hash::FxHashSet<(u64, u64)> = refined.iter().map(|&p| key(p)).collect();
    // The triangles' edges, gathered and sorted in parallel, each once.
    let mut edges: Vec<(u32, u32)> = (0..mesh.triangle_count())
        .into_par_iter()
        .flat_map_iter(|t| {
            let c = mesh.triangle(t);
            [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])]
                .into_iter()
                .map(|(a, b)| (a.min(b), a.max(b)))
        })
        .collect();
    edges.par_sort_unstable();
    edges.dedup();
    let ends: Vec<(kurbo::Point, kurbo::Point)> = edges
        .par_iter()
        .map(|&(a, b)| (mesh.nodes[a as usize], mesh.nodes[b as usize]))
        .collect();
    crate::sizing::edge_match(field, &ends, |a, b| {
        refined.contains(&key(a)) || refined.contains(&key(b))
    })
}

/// The periodic cell of `params` and the drawing's tile in it (`None`
/// without `--periodic`); a feature within l_min of a side is on it (l_min
/// relative to the cell's diagonal, the tile's d).
pub(super) fn periodic_tile(drawing: &Drawing, params: &Params) -> Result<Option<(Cell, Drawing)>> {
    let Some(p) = &params.periodic else {
        return Ok(None);
    };
    let cell = Cell::of(drawing, p)?;
    let snap = params
        .l_min
        .resolve(cell.rect.width().hypot(cell.rect.height()));
    Ok(Some((cell, cell.tile(drawing, snap)?)))
}

/// The box the TriWild meshers cover: a periodic tile's cell exactly, else
/// the drawing's bounding box padded by `padding` (at least a few ulps of the
/// coordinates, so it stays strictly larger).
fn padded_box(drawing: &Drawing, padding: f64) -> Rect {
    if let Some(cell) = drawing.cell {
        return cell;
    }
    let b = drawing.bbox;
    let magnitude = [b.x0, b.y0, b.x1, b.y1]
        .into_iter()
        .fold(0.0f64, |m, c| m.max(c.abs()));
    let pad = padding.max(magnitude * 1e-12).max(f64::MIN_POSITIVE);
    Rect::new(b.x0 - pad, b.y0 - pad, b.x1 + pad, b.y1 + pad)
}

/// The BSP's input: primary chords tagged with their chain and the parameter
/// interval of their section, secondary segments, isolated points; only chain
/// ends are fixed section endpoints.
fn bsp_input(fs: &FeatureSet, chains: &PrimaryChains) -> BspInput {
    let ci = fs.conforming_input();
    let segments = ci
        .segments
        .iter()
        .map(|(line, tag)| BspSegment {
            a: line.p0,
            b: line.p1,
            tag: match *tag {
                features::FeaturePiece::Primary(id) => bsp::SegmentTag::Primary {
                    section: chains.chain_of[id.index()],
                    t: fs.primary[id.index()].t,
                },
                features::FeaturePiece::Secondary { polyline, .. } => bsp::SegmentTag::Secondary {
                    polyline: polyline.raw(),
                },
            },
        })
        .collect();
    let section_endpoints = chains.chains.iter().flat_map(|c| c.ends).collect();
    BspInput {
        points: ci.points,
        section_endpoints,
        segments,
        steiner: Vec::new(),
    }
}

/// `--paranoid`: the full validator on a stage's mesh.
fn check_trimesh(mesh: &TriMesh, stage: Stage) -> Result<()> {
    let defects = mesh.check();
    match defects.first() {
        Some(d) => Err(Error::meshing(
            stage,
            format!("internal: {} mesh defects, first: {d:?}", defects.len()),
        )),
        None => Ok(()),
    }
}

/// The source shapes and kind of the feature a tag stands for (primary tags
/// index `ctx.sections`, secondary ones `fs.secondary`): its own source's
/// shape, then the shapes whose outlines coincide with it (`fs.sharers`).
pub(super) fn feature_of<'a>(
    fs: &'a FeatureSet,
    ctx: &Context,
    tag: &FeatureOn,
) -> impl Iterator<Item = (crate::svg::ShapeId, LineKind)> + use<'a> {
    let (shape, kind, shared) = match *tag {
        FeatureOn::Primary { section, .. } => {
            let s = &ctx.sections[section as usize];
            let source = s
                .source
                .expect("internal: the pipeline's sections name their source");
            (source.shape, LineKind::Primary, s.shared)
        }
        FeatureOn::Secondary { polyline } => {
            let p = &fs.secondary[polyline as usize];
            (p.source.shape, LineKind::Secondary, p.shared)
        }
    };
    let others = shared.map_or(&[][..], |g| fs.sharers[g as usize].as_slice());
    std::iter::once((shape, kind)).chain(others.iter().map(move |&s| (s, kind)))
}

/// Seconds per stage, each stage in a tracing span.
#[derive(Default)]
pub(super) struct Times(pub(super) BTreeMap<&'static str, f64>);

impl Times {
    fn time<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let _span = tracing::info_span!("stage", stage).entered();
        let t = Instant::now();
        let out = f();
        *self.0.entry(stage).or_default() += t.elapsed().as_secs_f64();
        out
    }
}
