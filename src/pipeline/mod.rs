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

use crate::Result;
use crate::bsp::BspStats;
use crate::budget::Deadline;
use crate::curve::CurveStats;
use crate::features::{FeatureCounts, FeatureSet};
use crate::fem::FemMesh;
use crate::optimize::OptimizeStats;
use crate::output::{self, MeshFormat, MshOptions, PreviewOptions};
use crate::params::{Mesher, Params, Resolved, Stage};
use crate::periodic::PeriodicReport;
use crate::quality::Quality;
use crate::regions::{RegionOptions, RegionReport};
use crate::sizing::{SizeField, SizingReport};
use crate::svg::{self, Drawing, FeatureGeom, LoadOptions, PaintOptions};
#[cfg(doc)]
use crate::{Error, curve::CurvedMesh, fem::LinearMesh};
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
        let tile = stages::periodic_tile(drawing, params)?.map(|(_, t)| t);
        let drawing = tile.as_ref().unwrap_or(drawing);
        with_threads(params.threads, || {
            let (_, set) = stages::front(drawing, params, Deadline::NONE)?;
            Ok(FeatureAnalysis { set, tile: None })
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
        stages::mesh_stages(drawing, params, regions, deadline).map(|(m, _, _)| m)
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

/// The size field of `drawing` as the pipeline builds it with the default
/// region names ([`stages::sizing_stage`]).
///
/// # Errors
/// As [`SizeField::build`].
pub(crate) fn default_field(
    drawing: &Drawing,
    params: &Params,
    deadline: Deadline,
) -> Result<SizeField> {
    let opts = stages::StageOptions::default_regions(params, drawing, deadline);
    stages::sizing_stage(drawing, &opts, &mut stages::Log::default())
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
            stages::mesh_stages(&drawing, params, &opts.regions, deadline)?;
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
mod stages;
#[cfg(test)]
mod tests;
mod warnings;
