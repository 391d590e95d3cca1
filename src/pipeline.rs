//! The pipeline: load → mesh → (regions, curving) → output, with per-stage timings
//! gathered into a [`Report`].

use crate::fem::FemMesh;
use crate::output::{self, MshOptions};
use crate::params::{Mesher, Params, Resolved};
use crate::quality::Quality;
use crate::regions::{RegionOptions, RegionReport};
use crate::svg::{self, Drawing, FeatureGeom};
use crate::{Error, Result};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of one run beyond the meshing parameters.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct RunOptions {
    /// Meshing parameters.
    pub params: Params,
    /// Output format.
    pub msh: MshOptions,
    /// Where to write an SVG preview, if anywhere.
    pub preview: Option<PathBuf>,
    /// Physical surfaces and dropped regions (default: one surface per filled shape).
    pub regions: RegionOptions,
}

impl RunOptions {
    /// Default output options with `params`.
    pub fn new(params: Params) -> Self {
        RunOptions {
            params,
            msh: MshOptions::DEFAULT,
            preview: None,
            regions: RegionOptions::DEFAULT,
        }
    }
    /// Set the output format.
    pub fn with_msh(mut self, msh: MshOptions) -> Self {
        self.msh = msh;
        self
    }
    /// Write a preview to `path`.
    pub fn with_preview(mut self, path: Option<PathBuf>) -> Self {
        self.preview = path;
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
    /// Features of every kind.
    pub features: usize,
    /// Isolated points.
    pub points: usize,
    /// Straight segments.
    pub lines: usize,
    /// Cubic Béziers.
    pub cubics: usize,
    /// Bounding-box diagonal d.
    pub d: f64,
}

impl InputCounts {
    /// Count the features of `drawing`.
    pub fn of(drawing: &Drawing) -> Self {
        let mut c = InputCounts {
            shapes: drawing.shapes.len(),
            features: drawing.features.len(),
            d: drawing.diagonal(),
            ..Default::default()
        };
        for f in &drawing.features {
            match f.geom {
                FeatureGeom::Point(_) => c.points += 1,
                FeatureGeom::Line(_) => c.lines += 1,
                FeatureGeom::Cubic(_) => c.cubics += 1,
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
    /// Warnings about the input.
    pub warnings: Vec<String>,
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

/// Mesh an already loaded drawing, with the default regions (one surface per
/// filled shape, plus `background`).
///
/// # Errors
/// Invalid parameters or a failed meshing stage.
pub fn mesh_drawing(drawing: &Drawing, params: &Params) -> Result<Meshed> {
    mesh_drawing_with(drawing, params, &RegionOptions::DEFAULT)
}

/// Mesh an already loaded drawing and tag (or drop) its regions.
///
/// # Errors
/// Invalid parameters, a failed meshing stage, or region options that select
/// nothing or name regions that do not exist.
pub fn mesh_drawing_with(
    drawing: &Drawing,
    params: &Params,
    regions: &RegionOptions,
) -> Result<Meshed> {
    params.validate()?;
    let mut times = Times::default();
    let resolved = params.resolve(drawing.diagonal());
    let mesh = match params.mesher {
        Mesher::Cdt => {
            let linear =
                times.time("baseline", || crate::baseline::triangulate(drawing, params))?;
            FemMesh::from_linear(&linear, "domain", |s| drawing.shapes[s.0 as usize].name())
        }
        Mesher::Bsp => {
            return Err(Error::InvalidParams(
                "--mesher bsp is not available yet; use --mesher cdt".into(),
            ));
        }
    };
    let (mesh, region_report) = times.time("regions", || {
        crate::regions::tag(drawing, &mesh, regions, resolved.eps_m)
    })?;
    let quality = times.time("quality", || Quality::of(&mesh));
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
        warnings: drawing.warnings.clone(),
    };
    Ok(Meshed { mesh, report })
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
    let t = Instant::now();
    let drawing = svg::load_file(input)?;
    let t_load = t.elapsed().as_secs_f64();
    let Meshed { mesh, mut report } = mesh_drawing_with(&drawing, &opts.params, &opts.regions)?;
    let t = Instant::now();
    output::write_msh(&mesh, output, opts.msh)?;
    if let Some(p) = &opts.preview {
        output::write_preview(&mesh, p)?;
    }
    report.times.insert("load", t_load);
    report.times.insert("output", t.elapsed().as_secs_f64());
    report.times.insert("total", t0.elapsed().as_secs_f64());
    Ok(report)
}
