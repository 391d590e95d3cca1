//! The pipeline: load → mesh (and curve) → regions → output, with per-stage
//! timings gathered into a [`Report`].
//!
//! Meshers ([`Params::mesher`]): the CDT baseline (`baseline`), or TriWild:
//! features → exact BSP (`bsp`) → AMIPS optimization (`optimize`) → curving
//! (`curve`); a vertex that stays rational is an error, never written (docs/design.md
//! "Exactness"). `--stop-after bsp` delivers the BSP mesh, `--linear` the
//! optimized one, each as a [`LinearMesh`] (`linear`); the curved mesh is
//! delivered as a [`CurvedMesh`]. Both become a [`FemMesh`] whose vertices are
//! numbered and feature lines written the same way
//! ([`crate::fem::VertexNumbers`], [`crate::fem::feature_lines`]).

use crate::bsp::{self, BspInput, BspOptions, BspSegment, BspStats};
use crate::budget::Deadline;
use crate::curve::{CurveOptions, CurveStats, CurvedMesh, curve_mesh};
use crate::error::check_deadline;
use crate::features::{self, FeatureCounts, FeatureSet, PrimaryChains};
use crate::fem::{FemMesh, LineKind, LinearMesh};
use crate::mesh::{FeatureOn, TriMesh};
use crate::ops::Context;
use crate::optimize::forced::ForcedCorners;
use crate::optimize::{OptimizeOptions, OptimizeStats};
use crate::output::{self, MeshFormat, MshOptions, PreviewOptions};
use crate::params::{Mesher, Params, Resolved, Stage};
use crate::periodic::{Cell, PeriodicReport};
use crate::quality::Quality;
use crate::regions::select::RegionMode;
use crate::regions::{RegionOptions, RegionReport};
use crate::sizing::{FieldInput, SizeField, SizingReport};
use crate::svg::{self, Drawing, FeatureGeom, LoadOptions, PaintOptions};
use crate::{Error, Result};
use kurbo::Rect;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

mod api;
pub use api::mesh_drawing;

/// Options of one run beyond the meshing parameters.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct RunOptions {
    /// Meshing parameters.
    pub params: Params,
    /// The .msh format (when `format` is [`MeshFormat::Msh`]).
    pub msh: MshOptions,
    /// The mesh file's format. Default [`MeshFormat::Msh`].
    pub format: MeshFormat,
    /// Where to write an SVG preview, if anywhere.
    pub preview: Option<PathBuf>,
    /// Fill the preview's triangles by edge / h (their mean edge length over
    /// the size field at their centroid) instead of by region colour
    /// (`--preview-size`). Default `false`.
    pub preview_size: bool,
    /// Physical surfaces and dropped regions (default: one surface per filled shape).
    pub regions: RegionOptions,
    /// How SVG's paint model is read (strokes, opacity); its hairline width is
    /// always the parameters' l_min.
    pub paint: PaintOptions,
}

impl RunOptions {
    /// Default output options with `params`.
    pub fn new(params: Params) -> Self {
        RunOptions {
            params,
            msh: MshOptions::DEFAULT,
            format: MeshFormat::Msh,
            preview: None,
            preview_size: false,
            regions: RegionOptions::DEFAULT,
            paint: PaintOptions::DEFAULT,
        }
    }
    /// Set how the paint model is read (strokes, opacity thresholds).
    pub fn with_paint(mut self, paint: PaintOptions) -> Self {
        self.paint = paint;
        self
    }
    /// Set the output format.
    pub fn with_msh(mut self, msh: MshOptions) -> Self {
        self.msh = msh;
        self
    }
    /// Set the mesh file's format (.msh or .vtu).
    pub fn with_format(mut self, format: MeshFormat) -> Self {
        self.format = format;
        self
    }
    /// Write a preview to `path`.
    pub fn with_preview(mut self, path: Option<PathBuf>) -> Self {
        self.preview = path;
        self
    }
    /// Shade the preview by edge / h (see [`RunOptions::preview_size`]).
    pub fn with_preview_size(mut self, on: bool) -> Self {
        self.preview_size = on;
        self
    }
    /// Set the region options.
    pub fn with_regions(mut self, regions: RegionOptions) -> Self {
        self.regions = regions;
        self
    }
}

/// Counts of the loaded input.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct InputCounts {
    /// Drawable shapes.
    pub shapes: usize,
    /// Paths read in f64 from the document's text.
    pub f64_paths: usize,
    /// Paths in usvg's single precision (text glyphs, markers, unsupported cases).
    pub single_precision_paths: usize,
    /// Features of every kind.
    pub features: usize,
    /// Isolated points.
    pub points: usize,
    /// Straight segments.
    pub lines: usize,
    /// Cubic Béziers.
    pub cubics: usize,
    /// Conic pieces (arcs, circles, ellipses, rounded corners).
    pub conics: usize,
    /// Bounding-box diagonal d.
    pub d: f64,
    /// What the paint model did: strokes meshed as areas or lines, clipped
    /// shapes, shapes dropped as invisible or decoration.
    pub paint: crate::svg::drawing::PaintCounts,
}

impl InputCounts {
    /// Count the features of `drawing`.
    pub fn of(drawing: &Drawing) -> Self {
        let mut c = InputCounts {
            f64_paths: drawing.precision.f64_paths,
            single_precision_paths: drawing.precision.single_precision_paths,
            shapes: drawing.shapes.len(),
            features: drawing.features.len(),
            d: drawing.diagonal(),
            paint: drawing.paint,
            ..Default::default()
        };
        for f in &drawing.features {
            match f.geom {
                FeatureGeom::Point(_) => c.points += 1,
                FeatureGeom::Line(_) => c.lines += 1,
                FeatureGeom::Cubic(_) => c.cubics += 1,
                FeatureGeom::Conic(_) => c.conics += 1,
            }
        }
        c
    }
}

/// Counts of the written mesh.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct OutputCounts {
    /// Nodes (corners and high-order nodes).
    pub nodes: usize,
    /// Triangles.
    pub triangles: usize,
    /// Line elements on features.
    pub feature_edges: usize,
    /// Element order.
    pub order: u8,
    /// Physical surfaces.
    pub surfaces: usize,
    /// Physical curves.
    pub curves: usize,
}

impl OutputCounts {
    /// Count `mesh`.
    pub fn of(mesh: &FemMesh) -> Self {
        OutputCounts {
            nodes: mesh.nodes.len(),
            triangles: mesh.triangle_count(),
            feature_edges: mesh.line_count(),
            order: mesh.order() as u8,
            surfaces: mesh.surfaces.len(),
            curves: mesh.curves.len(),
        }
    }
}

/// What one run did: the `--stats` JSON object and one batch report row.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Report {
    /// Input counts.
    pub input: InputCounts,
    /// The parameters in absolute units.
    pub params: Resolved,
    /// The mesher used.
    pub mesher: Mesher,
    /// Seconds per stage.
    pub times: BTreeMap<&'static str, f64>,
    /// Meshing time alone (everything but reading and writing), seconds.
    pub t_core: f64,
    /// Output counts.
    pub output: OutputCounts,
    /// Quality of the output.
    pub quality: Quality,
    /// Physical surfaces (triangles and area of each) and classification counts.
    pub regions: RegionReport,
    /// Feature preprocessing counts (TriWild mesher only).
    pub features: Option<FeatureCounts>,
    /// Counts and timings of the BSP stage (TriWild mesher only); its
    /// `rational_before_rounding` and `rational_vertices` say how many vertices
    /// were still rational before and after rounding.
    pub bsp: Option<BspStats>,
    /// The stage the run stopped after, if it stopped early.
    pub stopped_after: Option<Stage>,
    /// What the optimizer did (`--mesher triwild` unless stopped after `bsp`).
    pub optimize: Option<OptimizeStats>,
    /// What curving did (`--mesher triwild` without `--linear` / `--stop-after`);
    /// its `min_jacobian_ratio` is that of the mesh as written (after regions
    /// dropped any elements), equal to `quality.min_jacobian_ratio`.
    pub curve: Option<CurveStats>,
    /// The size field: the fields applied, the grading, and how well the
    /// mesh's edges match it (either mesher; always present since the CDT
    /// baseline reads the field too).
    pub sizing: Option<SizingReport>,
    /// Warnings about the input.
    pub warnings: Vec<String>,
    /// The periodic match (`--periodic`): node pairs, unpaired nodes, the
    /// largest mismatch as written; `None` for a mesh that is not periodic.
    pub periodic: Option<PeriodicReport>,
    /// The process's peak resident memory in MiB when the report was made
    /// (`run_file`: after the mesh was written), `None` where the system does
    /// not report it (`VmHWM` of `/proc/self/status`).
    pub peak_memory_mb: Option<f64>,
}

/// Stage timer.
#[derive(Default)]
struct Times(BTreeMap<&'static str, f64>);

impl Times {
    fn time<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let _span = tracing::info_span!("stage", stage).entered();
        let t = Instant::now();
        let out = f();
        *self.0.entry(stage).or_default() += t.elapsed().as_secs_f64();
        out
    }
}

/// The product of meshing a drawing, before it is written.
#[derive(Clone, Debug)]
pub struct Meshed {
    /// The mesh.
    pub mesh: FemMesh,
    /// Report (output counts and quality filled in).
    pub report: Report,
}

/// The feature analysis of a drawing (what `triwild features` writes): the
/// primary and secondary features of thesis §4.3.1 and §4.4, before any meshing.
#[derive(Clone, Debug)]
pub struct FeatureAnalysis {
    set: FeatureSet,
    /// The periodic tile analysed instead of the drawing (`params.periodic`).
    tile: Option<Drawing>,
}

impl FeatureAnalysis {
    /// Analyse `drawing` with `params`' lengths, the features resampled against
    /// the size field the mesh would use (regions named as by default), on
    /// `params.threads` workers as the mesher would.
    ///
    /// # Errors
    /// [`crate::ErrorKind::BadInput`] for a size field naming no region, a
    /// formula that does not parse, a background mesh that cannot be read.
    pub fn new(drawing: &Drawing, params: &Params) -> Result<FeatureAnalysis> {
        let tile = periodic_tile(drawing, params)?.map(|(_, t)| t);
        let drawing = tile.as_ref().unwrap_or(drawing);
        with_threads(params.threads, || {
            let resolved = params.resolve(drawing.diagonal());
            density::check(drawing, resolved.mu)?;
            let field = default_field(drawing, params, Deadline::NONE)?;
            Ok(FeatureAnalysis {
                set: FeatureSet::build_sized(
                    drawing,
                    &resolved,
                    &Deadline::NONE,
                    &|p, source, cut| field.for_curve(p, source.shape, cut),
                    section_budget(params),
                ),
                tile: None,
            })
        })
        .map(|a| FeatureAnalysis { tile, ..a })
    }

    /// The feature set as JSON (docs/features-json.md describes the format).
    pub fn json(&self) -> serde_json::Value {
        crate::features::to_json(&self.set)
    }

    /// An SVG picture of the features over `drawing` (the drawing analysed;
    /// with `--periodic`, its tile in the cell).
    pub fn svg(&self, drawing: &Drawing) -> String {
        crate::features::to_svg(&self.set, self.tile.as_ref().unwrap_or(drawing))
    }

    /// The counts of the analysis (input curves, primary sections, secondary
    /// polylines, ...), as in `--stats`.
    pub fn counts(&self) -> serde_json::Value {
        serde_json::to_value(self.set.counts).expect("internal: counts serialize")
    }

    /// Milliseconds per step of the analysis.
    pub fn timing(&self) -> serde_json::Value {
        serde_json::to_value(self.set.timing).expect("internal: timings serialize")
    }
}

/// [`mesh_drawing`] with the run's deadline, checked between stages and
/// in the BSP's, the optimizer's and the curved optimization's loops.
fn mesh_within(
    drawing: &Drawing,
    params: &Params,
    regions: &RegionOptions,
    deadline: Deadline,
) -> Result<Meshed> {
    let meshed = with_threads(params.threads, || {
        mesh_stages(drawing, params, regions, deadline).map(|(m, _, _)| m)
    });
    deadline.finish();
    meshed
}

/// Run `f` on a pool of `threads` workers (0: rayon's global pool, one per
/// core). A pool that cannot be made runs `f` on the global pool: the result
/// is the same either way.
fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    if threads == 0 {
        return f();
    }
    match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
        Ok(pool) => pool.install(f),
        Err(e) => {
            tracing::warn!("cannot start {threads} worker threads ({e}); using the global pool");
            f()
        }
    }
}

/// The stages of [`mesh_within`], on the current thread pool; with the size
/// field they met (the CDT baseline's: `l` everywhere) and each delivered
/// triangle's mask of forced corners (empty for the CDT baseline; see
/// [`crate::optimize::forced`]).
fn mesh_stages(
    drawing: &Drawing,
    params: &Params,
    regions: &RegionOptions,
    deadline: Deadline,
) -> Result<(Meshed, SizeField, Vec<u8>)> {
    let mut times = Times::default();
    if params.periodic.is_some() && regions.cut_outside {
        return Err(Error::InvalidParams(
            "--cut-outside has no meaning with --periodic: the mesh covers the cell".into(),
        ));
    }
    let periodic = match params.periodic {
        Some(_) => times.time("periodic", || periodic_tile(drawing, params))?,
        None => None,
    };
    let (cell, tiled) = match periodic {
        Some((c, t)) => (Some(c), Some(t)),
        None => (None, None),
    };
    let drawing = tiled.as_ref().unwrap_or(drawing);
    let resolved = params.resolve(drawing.diagonal());
    let mut features = None;
    let mut bsp = None;
    let mut optimize = None;
    let mut warnings = drawing.warnings.clone();
    let mut curve = None;
    let mut forced: Option<ForcedCorners> = None;
    let mut refined: Vec<kurbo::Point> = Vec::new();
    // One size field for either mesher, built before any meshing.
    let names = region_names(drawing, regions);
    let field = times.time("sizing", || {
        SizeField::build(&FieldInput {
            drawing,
            resolved: &resolved,
            spec: &params.size,
            region_names: &names,
            bounds: padded_box(drawing, resolved.padding),
            deadline,
            max_vertices: params.max_vertices as usize,
        })
    })?;
    if let Some(w) = size_clamp_warning(field.report()) {
        warnings.push(w);
    }
    let delivered = match params.mesher {
        Mesher::Cdt => {
            check_deadline(&deadline, Stage::Baseline)?;
            let linear = times.time("baseline", || {
                crate::baseline::triangulate(drawing, params, &field)
            })?;
            check_deadline(&deadline, Stage::Baseline)?;
            Delivered::Linear(linear)
        }
        Mesher::TriWild => {
            let field = &field;
            let mut classify = |mesh: &TriMesh, ctx: &Context, times: &mut Times| {
                forced = Some(times.time("forced", || {
                    ForcedCorners::classify(mesh, ctx, resolved.alpha)
                }));
            };
            check_deadline(&deadline, Stage::Features)?;
            density::check(drawing, resolved.mu)?;
            let fs = times.time("features", || {
                FeatureSet::build_sized(
                    drawing,
                    &resolved,
                    &deadline,
                    &|p, source, cut| field.for_curve(p, source.shape, cut),
                    section_budget(params),
                )
            });
            check_deadline(&deadline, Stage::Features)?;
            features = Some(fs.counts);
            if fs.counts.near_cell_sides > 0 {
                warnings.push(format!(
                    "--periodic: {} outline piece(s) within mu = {:.3e} of the cell's sides \
                     (a shape touching or grazing a side) meshed within eps = {:.3e}, not \
                     exact, so the elements between them and the side keep their shape; \
                     --mu-abs {:.3e} keeps more of them exact",
                    fs.counts.near_cell_sides,
                    resolved.mu,
                    resolved.eps,
                    0.25 * resolved.mu,
                ));
            }
            let chains = fs.primary_chains();
            let (mut mesh, stats) = bsp_trimesh(
                drawing, &fs, &chains, params, &resolved, deadline, &mut times, field,
            )?;
            bsp = Some(stats);
            let mut ctx = Context::from_chains(&fs, &chains, resolved.eps, resolved.eps);
            ctx.fixed_boundary = cell.is_some();
            if params.stop_after == Some(Stage::Bsp) {
                // Exact, but rounded to f64 a few triangles may be degenerate.
                times.time("snap", || {
                    snap::snap_degenerate(&mut mesh, &ctx, resolved.d)
                })?;
                if let Some(s) = &mut bsp {
                    // the counts of the mesh delivered
                    s.vertices = mesh.num_vertices();
                    s.triangles = mesh.num_faces();
                }
                classify(&mesh, &ctx, &mut times);
                Delivered::Linear(to_linear(&mesh, &fs, &ctx, Stage::Bsp, &mut times)?)
            } else {
                let opts = optimize_options(params, &resolved).with_deadline(deadline);
                let (stats, below) = times.time("optimize", || {
                    crate::optimize::optimize_with_field(&mut mesh, &mut ctx, &opts, field)
                });
                refined = below;
                check_deadline(&deadline, Stage::Optimize)?;
                if params.paranoid {
                    check_trimesh(&mesh, Stage::Optimize)?;
                }
                if stats.off_curve_left > 0 {
                    warnings.push(format!(
                        "{} primary vertices could not be moved onto their curves",
                        stats.off_curve_left
                    ));
                }
                if stats.vertex_budget_reached
                    || field.report().capped
                    || features.is_some_and(|c| c.unrefined_over_budget > 0)
                {
                    warnings.push(vertex_budget_warning(params.max_vertices));
                }
                if stats.bad_corners_left > 0 {
                    warnings.push(bad_corners_warning(
                        stats.bad_corners_left,
                        resolved.alpha,
                        stats.stop,
                    ));
                }
                optimize = Some(stats);
                if params.stop_after == Some(Stage::Optimize) {
                    classify(&mesh, &ctx, &mut times);
                    Delivered::Linear(to_linear(&mesh, &fs, &ctx, Stage::Optimize, &mut times)?)
                } else {
                    let (cm, cs) = times.time("curve", || {
                        let opts = CurveOptions::new(params.order, resolved.d)
                            .with_l_min_abs(resolved.l_min)
                            .with_size(field)
                            .with_stop_curved(params.stop_energy_curved, params.max_passes_curved)
                            .with_corner_floor(corner_floor(params, &resolved))
                            .with_deadline(deadline);
                        curve_mesh(&mut mesh, &ctx, &opts, |t| feature_of(&fs, &ctx, t))
                    })?;
                    check_deadline(&deadline, Stage::Curve)?;
                    classify(&mesh, &ctx, &mut times);
                    curve = Some(cs);
                    Delivered::Curved(cm)
                }
            }
        }
    };
    let name = |s: crate::svg::ShapeId| drawing.shapes[s.index()].name();
    let (mut mesh, line_shape): (FemMesh, Vec<crate::svg::ShapeId>) = match &delivered {
        Delivered::Linear(linear) => (
            FemMesh::from_linear(linear, "domain", name),
            linear.edges.iter().map(|e| e.shape).collect(),
        ),
        Delivered::Curved(cm) => (
            FemMesh::from_curved(cm, "domain", name),
            cm.line_feature.iter().map(|f| f.0).collect(),
        ),
    };
    let (mesh, region_report, lost) = times.time("regions", || {
        crate::regions::orient_lines(drawing, &mut mesh, &line_shape, &deadline);
        crate::regions::tag(
            drawing,
            &mesh,
            regions,
            resolved.eps_m,
            resolved.l_min,
            // (a periodic tile's shapes are their whole translated copies:
            // the drawn areas would count what lies outside the cell)
            drawing.cell.is_none().then(|| crate::regions::AreaCheck {
                bounds: padded_box(drawing, resolved.padding),
                d: resolved.d,
            }),
            deadline,
        )
    })?;
    let mut mesh = mesh;
    let periodic_report = cell.map(|c| times.time("periodic", || c.finish(&mut mesh)));
    if let Some(r) = &periodic_report {
        if r.unpaired > 0 || r.max_mismatch > 0.0 {
            warnings.push(format!(
                "--periodic: {} side node(s) without a partner, largest mismatch {:e}",
                r.unpaired, r.max_mismatch
            ));
        }
    }
    if !lost.is_empty() {
        warnings.push(lost_regions_warning(
            drawing,
            &lost,
            resolved.mu,
            resolved.l_min,
            resolved.eps_m,
        ));
    }
    // The area check warns on cubic meshes: there a mesh that keeps the
    // outlines has the drawn areas to rounding (chords at lower orders and
    // the baseline's flattened curves change areas by design).
    if matches!(delivered, Delivered::Curved(_)) && params.order == crate::element::Order::Cubic {
        if let Some(w) = area_warning(&region_report, &mesh, params, &resolved) {
            warnings.push(w);
        }
    }
    // The quality of the elements as written (what `triwild check` reads back):
    // the curving stage's own ratio also saw the elements regions dropped.
    let mask = forced.map(|f| f.mask(&mesh)).unwrap_or_default();
    let quality = times.time("quality", || match params.mesher {
        Mesher::TriWild => Quality::of_classified(&mesh, &mask, params.alpha_deg),
        Mesher::Cdt => Quality::of(&mesh),
    });
    if let Some(warning) = quality.unforced.as_ref().and_then(low_ratio_warning) {
        warnings.push(warning);
    }
    let mut region_report = region_report;
    region_report.small = crate::regions::SmallRegions::of(&region_report.surfaces);
    let mut sizing = field.report().clone();
    sizing.edges = Some(times.time("sizing", || mesh_edge_match(&mesh, &field, &refined)));
    let sizing = Some(sizing);
    if let Some(c) = &mut curve {
        c.min_jacobian_ratio = quality.min_jacobian_ratio;
    }
    let t_core = times.0.values().sum();
    let report = Report {
        input: InputCounts::of(drawing),
        params: resolved,
        mesher: params.mesher,
        times: times.0,
        t_core,
        output: OutputCounts::of(&mesh),
        quality,
        regions: region_report,
        features,
        bsp,
        stopped_after: params.stop_after,
        optimize,
        curve,
        sizing,
        warnings,
        periodic: periodic_report,
        peak_memory_mb: crate::budget::peak_memory_mb(),
    };
    Ok((Meshed { mesh, report }, field, mask))
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

/// The warning for shapes whose regions the mesh lost (see
/// [`crate::regions::RegionReport::lost_shapes`]), naming the first few. When
/// every one is thinner (its mean width, [`crate::svg::Shape::mean_width`])
/// than the feature envelope μ or the minimal edge length l_min, it says so,
/// names the transform that thinned them if one did, and gives the values of
/// `--mu-abs` and `--min-edge-length-abs` that keep them: a quarter of the
/// narrowest mean width, rounded down to one digit, for each of the two that
/// is larger; or, when that is below the numerical tolerance ε_m, that no
/// flag keeps them.
fn lost_regions_warning(
    drawing: &Drawing,
    lost: &[crate::svg::ShapeId],
    mu: f64,
    l_min: f64,
    eps_m: f64,
) -> String {
    const NAMED: usize = 5;
    let shapes: Vec<&crate::svg::Shape> = lost.iter().map(|s| &drawing.shapes[s.index()]).collect();
    let names: Vec<String> = shapes.iter().take(NAMED).map(|s| s.name()).collect();
    let more = if lost.len() > NAMED { ", ..." } else { "" };
    let widths: Vec<f64> = shapes.iter().map(|s| s.mean_width()).collect();
    let narrowest = widths.iter().copied().fold(f64::INFINITY, f64::min);
    let widest = widths.iter().copied().fold(0.0, f64::max);
    if narrowest > 0.0 && widest < mu.max(l_min) {
        let under = shapes
            .iter()
            .find_map(|s| s.paint.stretched_by.as_deref())
            .map_or_else(String::new, |t| format!(" under {t}"));
        let value = narrowest / 4.0;
        let shown = crate::svg::one_digit_below(value);
        let mut limits = Vec::new();
        let mut flags = Vec::new();
        for (limit, name, flag) in [
            (mu, "the feature envelope mu", "--mu-abs"),
            (
                l_min,
                "the minimal edge length l_min",
                "--min-edge-length-abs",
            ),
        ] {
            if widest < limit {
                limits.push(format!("{name} = {limit:.3e}"));
            }
            if value < limit {
                flags.push(format!("{flag} {shown}"));
            }
        }
        let remedy = if value < eps_m {
            format!(
                "thinner than the numerical tolerance eps_m = {eps_m:.3e} as well: no flag \
                 keeps them beside the rest of the drawing"
            )
        } else {
            format!("they are kept with {}", flags.join(" "))
        };
        return format!(
            "{} painted shape(s){under} thinner than {} (mean width {narrowest:.2e} and up) \
             have no region in the mesh: their outlines are not kept apart ({remedy}): \
             {}{more}",
            lost.len(),
            limits.join(" and "),
            names.join(", ")
        );
    }
    format!(
        "{} painted shape(s) show in the picture but have no region in the mesh: their \
         outlines did not become mesh edges (outlines closer together than the feature \
         envelope mu = {mu:.3e} are not kept apart; a smaller --mu keeps more): {}{more}",
        lost.len(),
        names.join(", ")
    )
}

/// One warning naming the regions whose area on the mesh differs from their
/// drawn area by more than the tolerance, with the cause the mesh shows and
/// the flag that keeps them.
fn area_warning(
    report: &crate::regions::RegionReport,
    mesh: &FemMesh,
    params: &Params,
    resolved: &Resolved,
) -> Option<String> {
    const NAMED: usize = 3;
    let floor = 1e-9 * resolved.d * resolved.d;
    let secondary = crate::regions::secondary_lengths(mesh);
    let mut off: Vec<(f64, &crate::regions::RegionStat, f64)> = report
        .surfaces
        .iter()
        .zip(&secondary)
        .filter_map(|(s, &sec)| {
            let (drawn, err) = (s.drawn_area?, s.area_error?);
            let allowed = (params.area_tolerance * drawn.abs()).max(floor) + report.drawn_unsure;
            (err.abs() > allowed).then_some((err.abs() / allowed, s, sec))
        })
        .collect();
    if off.is_empty() {
        return None;
    }
    off.sort_by(|a, b| b.0.total_cmp(&a.0));
    let named: Vec<String> = off
        .iter()
        .take(NAMED)
        .map(|(_, s, _)| {
            let drawn = s.drawn_area.unwrap_or(0.0);
            let rel = if drawn != 0.0 {
                format!(" ({:+.2} %)", 100.0 * (s.area - drawn) / drawn.abs())
            } else {
                String::new()
            };
            format!(
                "{} {:.6e} on the mesh against {:.6e} drawn{rel}",
                s.name, s.area, drawn
            )
        })
        .collect();
    let more = if off.len() > NAMED { ", ..." } else { "" };
    let with_secondary = off.iter().filter(|o| o.2 > 0.0).count();
    let cause = if with_secondary > 0 {
        format!(
            "{with_secondary} of them border outlines meshed within eps = {:.3e} (outlines \
             closer than mu = {:.3e} to another are secondary features); --mu-abs {:.3e} \
             keeps more outlines exact",
            resolved.eps,
            resolved.mu,
            resolved.mu / 4.0
        )
    } else {
        "their outlines are exact on the mesh: a region's triangles were given to a \
         neighbour (see regions.lost_shapes and relabelled)"
            .to_owned()
    };
    Some(format!(
        "{} region(s) {} by more than --area-tolerance {:e} (or 1e-9*d^2): {}{more}; {cause}",
        off.len(),
        crate::regions::AREA_WARNING,
        params.area_tolerance,
        named.join(", ")
    ))
}

/// The periodic cell of `params` and the drawing's tile in it (`None`
/// without `--periodic`); a feature within l_min of a side is on it (l_min
/// relative to the cell's diagonal, the tile's d).
fn periodic_tile(drawing: &Drawing, params: &Params) -> Result<Option<(Cell, Drawing)>> {
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

/// The BSP input of a feature set: every conforming segment with its tag,
/// isolated points and section endpoints.
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

/// The exact BSP mesh of a drawing's features (TriWild §4.3-4.4 up to the
/// conforming mesh, before optimization): the rounded [`TriMesh`], the feature
/// set its tags index, and the operations' [`Context`] (curves of the primary
/// sections, ε-envelope of the secondary polylines). Vertices the BSP could
/// not round stay rational (the optimizer rounds them later).
///
/// # Errors
/// [`Error::Meshing`] if the BSP fails, or (with `params.paranoid`) if its mesh
/// has a defect.
#[cfg(test)]
pub(crate) fn bsp_stage(
    drawing: &Drawing,
    params: &Params,
) -> Result<(TriMesh, FeatureSet, Context)> {
    params.validate()?;
    let resolved = params.resolve(drawing.diagonal());
    let mut times = Times::default();
    let field = test_field(drawing, params)?;
    let fs = sized_features(drawing, params)?;
    let chains = fs.primary_chains();
    let (mesh, _) = bsp_trimesh(
        drawing,
        &fs,
        &chains,
        params,
        &resolved,
        Deadline::NONE,
        &mut times,
        &field,
    )?;
    let ctx = Context::from_chains(&fs, &chains, resolved.eps, resolved.eps);
    Ok((mesh, fs, ctx))
}

/// The size field of `drawing` as the pipeline builds it with the default
/// region names (what `triwild features` and the tests' stage functions use).
///
/// # Errors
/// As [`SizeField::build`].
pub(crate) fn default_field(
    drawing: &Drawing,
    params: &Params,
    deadline: Deadline,
) -> Result<SizeField> {
    let resolved = params.resolve(drawing.diagonal());
    SizeField::build(&FieldInput {
        drawing,
        resolved: &resolved,
        spec: &params.size,
        region_names: &region_names(drawing, &RegionOptions::DEFAULT),
        bounds: padded_box(drawing, resolved.padding),
        deadline,
        max_vertices: params.max_vertices as usize,
    })
}

/// [`default_field`] with no time limit, for the stage functions of the tests.
///
/// # Errors
/// As [`SizeField::build`].
#[cfg(test)]
fn test_field(drawing: &Drawing, params: &Params) -> Result<SizeField> {
    default_field(drawing, params, Deadline::NONE)
}

/// The features of `drawing` as the pipeline builds them: resampled against
/// the size field of `params` (default region names).
///
/// # Errors
/// As [`SizeField::build`].
#[cfg(test)]
pub(crate) fn sized_features(drawing: &Drawing, params: &Params) -> Result<FeatureSet> {
    let resolved = params.resolve(drawing.diagonal());
    let field = test_field(drawing, params)?;
    Ok(FeatureSet::build_sized(
        drawing,
        &resolved,
        &Deadline::NONE,
        &|p, source, cut| field.for_curve(p, source.shape, cut),
        section_budget(params),
    ))
}

/// The optimized linear mesh of a drawing (TriWild §4.4.1): [`bsp_stage`]
/// followed by the optimizer, with what it did. The mesh may still hold
/// rational vertices or off-curve primary vertices when the stats say so
/// (the pipeline refuses to write the former and warns about the latter).
///
/// # Errors
/// As [`bsp_stage`].
#[cfg(test)]
pub(crate) fn optimize_stage(
    drawing: &Drawing,
    params: &Params,
) -> Result<(TriMesh, FeatureSet, Context, OptimizeStats)> {
    let (mut mesh, fs, mut ctx) = bsp_stage(drawing, params)?;
    let resolved = params.resolve(drawing.diagonal());
    let field = test_field(drawing, params)?;
    let (stats, _) = crate::optimize::optimize_with_field(
        &mut mesh,
        &mut ctx,
        &optimize_options(params, &resolved),
        &field,
    );
    Ok((mesh, fs, ctx, stats))
}

/// The BSP stage's mesh: the conforming segments and points of `fs` (with
/// free seed vertices where `field` asks for a finer mesh than the features
/// give) triangulated exactly in the drawing's padded box ([`bsp::build`]);
/// refused first when the segments cross too densely ([`density`]).
#[expect(
    clippy::too_many_arguments,
    reason = "the BSP stage's inputs (the features, their chains, the field) and the run's \
              parameters, budgets and timer, passed straight through by its two callers"
)]
fn bsp_trimesh(
    drawing: &Drawing,
    fs: &FeatureSet,
    chains: &PrimaryChains,
    params: &Params,
    resolved: &Resolved,
    deadline: Deadline,
    times: &mut Times,
    field: &SizeField,
) -> Result<(TriMesh, BspStats)> {
    let mut input = bsp_input(fs, chains);
    density::check_crossings(input.segments.iter().map(|s| [s.a, s.b]), resolved.mu)?;
    let bbox = padded_box(drawing, resolved.padding);
    let cell = Cell::of_tile(drawing, params);
    if let Some(cell) = &cell {
        // the cell's sides: every feature end on a side, its partner, the gaps
        // resampled once for both partner sides
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
        let sides = cell.side_points(&ends, &chords, field, resolved.l_min);
        input.points.extend(sides);
    }
    let opts = BspOptions::DEFAULT.with_deadline(deadline);
    let (mesh, stats) = times.time("bsp", || {
        // Free vertices where the size field asks for a finer mesh than the
        // features give (`sizing::seeds`; none at the default settings).
        let lines: Vec<kurbo::Line> = input
            .segments
            .iter()
            .map(|s| kurbo::Line::new(s.a, s.b))
            .collect();
        input.steiner =
            field.seed_points(bbox, &lines, &input.points, params.max_vertices as usize);
        bsp::build(&input, bbox, &opts)
    })?;
    let mut mesh = mesh;
    if cell.is_some() {
        Cell::fix_sides(&mut mesh);
    }
    check_deadline(&deadline, Stage::Bsp)?;
    if params.paranoid {
        times.time("check", || check_trimesh(&mesh, Stage::Bsp))?;
    }
    Ok((mesh, stats))
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

/// The curved stage's corner rule ([`crate::ops::CurvedRule::corner_floor`]):
/// the linear stop energy, or the energy below which no corner is under α
/// if that is lower, so the curved passes never make a straight corner below
/// α where the linear stage left none (the stop energy alone admits triangles
/// with corners near 7°, below the default α of 10°).
fn corner_floor(params: &Params, resolved: &Resolved) -> f64 {
    params
        .stop_energy
        .min(crate::optimize::needle_energy(resolved.alpha))
}

/// The optimizer's options from the parameters (thesis §2.3.2: target `l`,
/// sizing floor ε).
pub(crate) fn optimize_options(params: &Params, resolved: &Resolved) -> OptimizeOptions {
    OptimizeOptions {
        l: resolved.l,
        l_floor: resolved.eps.min(resolved.l),
        stop_energy: params.stop_energy,
        alpha_deg: params.alpha_deg,
        max_passes: params.max_passes,
        max_vertices: params.max_vertices as usize,
        deadline: Deadline::NONE,
    }
}

/// The delivered linear form of a mesh whose tags index `fs`.
fn to_linear(
    mesh: &TriMesh,
    fs: &FeatureSet,
    ctx: &Context,
    stage: Stage,
    times: &mut Times,
) -> Result<LinearMesh> {
    times.time("linear", || {
        LinearMesh::from_trimesh(mesh, stage, |t| feature_of(fs, ctx, t))
    })
}

/// The source shapes and kind of the feature a tag stands for (primary tags
/// index `ctx.sections`, secondary ones `fs.secondary`): its own source's
/// shape, then the shapes whose outlines coincide with it (`fs.sharers`).
pub(crate) fn feature_of<'a>(
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

/// What the mesher hands to the FEM conversion.
enum Delivered {
    Linear(LinearMesh),
    Curved(CurvedMesh),
}

/// Load `input`, mesh it, write `output` (and the preview, if asked for).
///
/// Checks that the output can be created before meshing, so a bad output path
/// fails fast; nothing is written unless meshing succeeded.
///
/// # Errors
/// Any [`Error`]; [`Error::Write`] is about `output` (or the preview), everything
/// else about `input`.
pub fn run_file(input: &Path, output: &Path, opts: &RunOptions) -> Result<Report> {
    let t0 = Instant::now();
    opts.params.validate()?;
    output::check_writable(output)?;
    if let Some(p) = &opts.preview {
        output::check_writable(p)?;
    }
    let deadline = opts.params.deadline();
    let t = Instant::now();
    let params = &opts.params;
    let drawing = svg::load_file(
        input,
        &LoadOptions::from_params(params)?.with_paint(opts.paint),
    )?;
    let t_load = t.elapsed().as_secs_f64();
    // Meshing and writing on one pool: the writer formats in parallel too,
    // on no more threads than the mesher was given.
    let written = with_threads(params.threads, || -> Result<(Report, f64)> {
        let (Meshed { mesh, report }, field, mask) =
            mesh_stages(&drawing, params, &opts.regions, deadline)?;
        let t = Instant::now();
        match opts.format {
            MeshFormat::Msh => output::write_msh(&mesh, output, opts.msh)?,
            MeshFormat::Vtu => output::write_vtu(&mesh, output)?,
        }
        if let Some(p) = opts.preview.as_ref().filter(|_| opts.preview_size) {
            output::write_preview(
                &mesh,
                p,
                &PreviewOptions::DEFAULT.with_size_field(&|x| field.at(x)),
            )?;
        } else if let Some(p) = &opts.preview {
            let colours: Vec<Option<String>> = report
                .regions
                .surfaces
                .iter()
                .map(|s| s.colour.clone())
                .collect();
            let marks = output::PreviewMarks {
                forced: (0..mask.len())
                    .flat_map(|t| (0..3).map(move |k| (t, k)))
                    .filter(|&(t, k)| mask[t] & (0b1001 << k) != 0)
                    .collect(),
                worst: report
                    .quality
                    .unforced
                    .and_then(|u| u.worst)
                    .map(|w| w.element),
            };
            output::write_preview(
                &mesh,
                p,
                &PreviewOptions::DEFAULT
                    .with_colours(&colours)
                    .with_marks(&marks),
            )?;
        }
        Ok((report, t.elapsed().as_secs_f64()))
    });
    deadline.finish();
    let (mut report, t_output) = written?;
    report.times.insert("load", t_load);
    report.times.insert("output", t_output);
    report.times.insert("total", t0.elapsed().as_secs_f64());
    report.peak_memory_mb = crate::budget::peak_memory_mb();
    Ok(report)
}

mod density;
mod snap;
#[cfg(test)]
mod tests;

/// The warning for unforced elements whose certified Jacobian ratio is below
/// [`crate::quality::RATIO_FLOOR`], `None` when there is none: how
/// many, the worst and where. The curving stage repairs only elements that it
/// cannot certify, then fits those it still cannot (to a ratio of at least
/// 0.01), so such an element is a fitted one or a valid one bent too far for
/// its size.
fn low_ratio_warning(u: &crate::quality::Unforced) -> Option<String> {
    let w = u.worst_ratio.filter(|_| u.below_ratio_floor > 0)?;
    Some(format!(
        "{} unforced element(s) with a certified Jacobian ratio below {} left by the curving \
         stage (its repair splits only elements it cannot certify); the worst, {:.3}, at \
         ({:.6}, {:.6}); --stats quality.unforced.worst_ratio",
        u.below_ratio_floor,
        crate::quality::RATIO_FLOOR,
        w.jacobian_ratio,
        w.x,
        w.y
    ))
}

/// The most primary sections the features stage cuts to a size below the
/// separation's: half the vertex budget, so the outlines leave room for the
/// mesh inside them.
fn section_budget(params: &Params) -> usize {
    params.max_vertices as usize / 2
}

/// The warning for size fields that ask below the minimal edge length l_min:
/// the field is clamped there, and the flag that follows them.
fn size_clamp_warning(report: &crate::sizing::SizingReport) -> Option<String> {
    (report.asked_min < report.l_min).then(|| {
        format!(
            "the size fields ask for sizes below the minimal edge length l_min = {:.3e} \
             (down to {:.3e} where the field was sampled): sizes are clamped to l_min; \
             --min-edge-length-abs {:.3e} or smaller follows them",
            report.l_min, report.asked_min, report.asked_min
        )
    })
}

/// The warning for a mesh that the vertex budget kept coarser than the size
/// field asks (the optimizer's splits stopped at it, or the field itself was
/// resolved only as far as it allows).
fn vertex_budget_warning(max_vertices: u32) -> String {
    format!(
        "the vertex budget of {max_vertices} (--max-vertices) stopped refinement: the mesh is \
         coarser than the size asked (-l, --size*); --stats sizing.edges says by how much; \
         raise --max-vertices or ask for larger sizes"
    )
}

/// The warning for corners below α that the worst-element phase left where
/// the drawing leaves room: how many, and why it stopped.
fn bad_corners_warning(
    n: usize,
    alpha: f64,
    stop: crate::optimize::schedule::StopReason,
) -> String {
    let why = if stop == crate::optimize::schedule::StopReason::TimeLimit {
        "the time limit"
    } else {
        "its rounds ran out"
    };
    format!(
        "{n} corner(s) below alpha = {:.1} degrees left where the features leave room \
         (the worst-element phase stopped: {why}); --stats quality.unforced gives the worst",
        alpha.to_degrees()
    )
}
