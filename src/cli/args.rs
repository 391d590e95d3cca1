//! The argument groups several commands share, and their conversion to the
//! library's options: meshing parameters ([`Params`]), the .msh format
//! ([`MshOptions`]) and regions ([`RegionOptions`]).
//!
//! Every default shown by `--help` is the library's own: [`defaults`],
//! [`MshOptions::DEFAULT`] and [`RegionOptions::DEFAULT`].

use clap::{Args, ValueEnum};
use triwild::Order;
use triwild::defaults;
use triwild::{Length, Mesher, OptimizerParams, Params, SizeSpec, Stage, Units};
use triwild::{MshOptions, MshVersion};
use triwild::{PaintOptions, StrokeMode};
use triwild::{RegionMode, RegionOptions};

/// What becomes a physical surface, and what is dropped.
#[derive(Args, Debug, Clone)]
pub(crate) struct RegionArgs {
    /// Physical surfaces: one per filled shape (SVG id, else shape-N), one per fill
    /// colour (fill-#rrggbb), or a single `domain`; plus `background`.
    #[arg(long, value_enum, default_value_t = RegionOptions::DEFAULT.mode.into())]
    regions: RegionsArg,
    /// Drop the background (what no filled shape covers).
    #[arg(long)]
    cut_outside: bool,
    /// Keep only the named regions.
    #[arg(long, value_delimiter = ',', value_name = "NAME,...")]
    keep: Vec<String>,
    /// Remove the region containing the point X,Y (output coordinates: --units
    /// times --scale, y pointing up, i.e. y = -y_svg). Repeatable.
    #[arg(long, value_name = "X,Y", value_parser = parse_point, allow_hyphen_values = true)]
    hole: Vec<(f64, f64)>,
    /// Strokes: the area they paint (a region `<name>-stroke`; strokes narrower
    /// than --l-min stay lines), their centre lines (features, no region), or nothing.
    #[arg(long, value_enum, default_value_t = StrokesArg::Area)]
    strokes: StrokesArg,
    /// Paint whose effective opacity (group opacities x fill or stroke opacity x a
    /// gradient's mean stop opacity) is below this is decoration: no region.
    #[arg(long, value_name = "ALPHA", default_value_t = PaintOptions::DEFAULT.min_opacity,
          value_parser = parse_opacity)]
    min_opacity: f32,
    /// Keep the outlines of decoration (paint below --min-opacity) as features.
    #[arg(long)]
    keep_decoration: bool,
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum StrokesArg {
    /// The area the stroke paints.
    Area,
    /// The centre line.
    Line,
    /// Nothing.
    Ignore,
}

fn parse_opacity(s: &str) -> Result<f32, String> {
    s.trim()
        .parse::<f32>()
        .ok()
        .filter(|v| (0.0..=1.0).contains(v))
        .ok_or_else(|| format!("not an opacity in [0, 1]: `{s}`"))
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum RegionsArg {
    /// One surface per filled shape.
    Shape,
    /// One surface per fill colour.
    Colour,
    /// One surface `domain`.
    None,
}

impl From<RegionsArg> for RegionMode {
    fn from(arg: RegionsArg) -> Self {
        match arg {
            RegionsArg::Shape => RegionMode::Shape,
            RegionsArg::Colour => RegionMode::Colour,
            RegionsArg::None => RegionMode::None,
        }
    }
}

impl From<RegionMode> for RegionsArg {
    fn from(mode: RegionMode) -> Self {
        match mode {
            RegionMode::Shape => RegionsArg::Shape,
            RegionMode::Colour => RegionsArg::Colour,
            RegionMode::None => RegionsArg::None,
        }
    }
}

fn parse_point(s: &str) -> Result<(f64, f64), String> {
    let (x, y) = s.split_once(',').ok_or("expected X,Y")?;
    let num = |v: &str| {
        v.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("not a finite number: `{v}`"))
    };
    Ok((num(x)?, num(y)?))
}

impl RegionArgs {
    /// How these flags ask the paint model to be read.
    pub(crate) fn paint_options(&self) -> PaintOptions {
        PaintOptions::DEFAULT
            .with_strokes(match self.strokes {
                StrokesArg::Area => StrokeMode::Area,
                StrokesArg::Line => StrokeMode::Line,
                StrokesArg::Ignore => StrokeMode::Ignore,
            })
            .with_min_opacity(self.min_opacity)
            .with_keep_decoration(self.keep_decoration)
    }

    /// The region options these flags ask for.
    pub(crate) fn to_options(&self) -> RegionOptions {
        RegionOptions::DEFAULT
            .with_mode(self.regions.into())
            .with_cut_outside(self.cut_outside)
            .with_keep(self.keep.clone())
            .with_holes(
                self.hole
                    .iter()
                    .map(|&(x, y)| kurbo::Point::new(x, y))
                    .collect(),
            )
    }
}

/// The output format of a mesh.
#[derive(Args, Debug, Clone)]
pub(crate) struct FormatArgs {
    /// gmsh file format version.
    #[arg(long, value_enum, default_value_t = MshOptions::DEFAULT.version.into())]
    msh_version: MshVersionArg,
    /// Write binary .msh instead of ASCII.
    #[arg(long)]
    binary: bool,
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum MshVersionArg {
    #[value(name = "4.1")]
    V41,
    #[value(name = "2.2")]
    V22,
}

impl From<MshVersion> for MshVersionArg {
    fn from(version: MshVersion) -> Self {
        match version {
            MshVersion::V41 => MshVersionArg::V41,
            MshVersion::V22 => MshVersionArg::V22,
        }
    }
}

impl FormatArgs {
    /// The .msh options these flags ask for.
    pub(crate) fn to_options(&self) -> MshOptions {
        MshOptions {
            version: match self.msh_version {
                MshVersionArg::V41 => MshVersion::V41,
                MshVersionArg::V22 => MshVersion::V22,
            },
            binary: self.binary,
        }
    }
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum MesherArg {
    /// spade constrained Delaunay triangulation with refinement (linear baseline).
    Cdt,
    /// TriWild: feature analysis, exact BSP mesh, AMIPS optimization under the
    /// feature invariants (and curving).
    #[value(name = "triwild", alias = "bsp")]
    TriWild,
}

impl From<Mesher> for MesherArg {
    fn from(mesher: Mesher) -> Self {
        match mesher {
            Mesher::Cdt => MesherArg::Cdt,
            Mesher::TriWild => MesherArg::TriWild,
        }
    }
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum UnitsArg {
    /// The user units of the root viewBox: the numbers written in the document
    /// (px when there is no viewBox).
    User,
    /// CSS px of the root viewport (96 per inch, after the viewBox -> width/height
    /// mapping), as browsers size the drawing.
    Px,
}

impl From<Units> for UnitsArg {
    fn from(units: Units) -> Self {
        match units {
            Units::User => UnitsArg::User,
            Units::Px => UnitsArg::Px,
        }
    }
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum StageArg {
    /// The exact BSP mesh, rounded to f64, feature edges as physical curves.
    Bsp,
    /// The optimized linear mesh (same as --linear).
    Optimize,
}

/// Meshing parameters (docs/design.md "Coordinates and parameters").
#[derive(Args, Debug, Clone)]
pub(crate) struct ParamArgs {
    /// Units of the output coordinates and of every -abs length: the drawing's
    /// own numbers (the root viewBox's user units; y flipped, origin kept), or
    /// CSS px.
    #[arg(long, value_enum, default_value_t = defaults::UNITS.into())]
    units: UnitsArg,
    /// Multiply every output coordinate by S (e.g. 0.001: a drawing in mm, a mesh
    /// in m); -abs lengths are in the scaled units.
    #[arg(long, default_value_t = defaults::SCALE, value_name = "S")]
    scale: f64,
    /// Mesher.
    #[arg(long, value_enum, default_value_t = defaults::MESHER.into())]
    mesher: MesherArg,
    /// Stop after this stage and write its mesh (needs --mesher triwild).
    #[arg(long, value_enum, value_name = "STAGE")]
    stop_after: Option<StageArg>,
    /// Element order: 3 = cubic triangles (gmsh type 21) whose edges are the
    /// drawing's Béziers, 2 = quadratic (type 9), 1 = straight.
    #[arg(long, default_value_t = defaults::ORDER as u8, value_parser = clap::value_parser!(u8).range(1..=3))]
    order: u8,
    /// Write the optimized linear mesh (straight triangles, feature edges as
    /// physical curves), without curving: --stop-after optimize.
    #[arg(long, conflicts_with = "stop_after")]
    linear: bool,
    /// Target edge length l, relative to d.
    #[arg(short = 'l', long, default_value_t = defaults::EDGE_LENGTH_REL, value_name = "REL")]
    edge_length: f64,
    /// Target edge length l in output units (overrides --edge-length).
    #[arg(long, value_name = "UNITS")]
    edge_length_abs: Option<f64>,
    /// Minimal edge length l_m, relative to d; in output units when
    /// --edge-length-abs is given (the form of the edge length, as the size
    /// fields take it) [default: 1e-4, relative to d].
    #[arg(long, value_name = "REL")]
    min_edge_length: Option<f64>,
    /// Minimal edge length l_m in output units.
    #[arg(long, value_name = "UNITS")]
    min_edge_length_abs: Option<f64>,
    /// Feature envelope μ, relative to d.
    #[arg(long, default_value_t = defaults::MU_REL, value_name = "REL")]
    mu: f64,
    /// Feature envelope μ in output units.
    #[arg(long, value_name = "UNITS")]
    mu_abs: Option<f64>,
    /// Envelope ε of secondary features, relative to d.
    #[arg(short = 'e', long, default_value_t = defaults::EPS_REL, value_name = "REL")]
    eps: f64,
    /// Envelope ε in output units.
    #[arg(long, value_name = "UNITS")]
    eps_abs: Option<f64>,
    /// Numerical tolerance ε_m, relative to d.
    #[arg(long, default_value_t = defaults::EPS_M_REL, value_name = "REL")]
    eps_m: f64,
    /// Numerical tolerance ε_m in output units.
    #[arg(long, value_name = "UNITS")]
    eps_m_abs: Option<f64>,
    /// Padding of the meshed box around the drawing, relative to d.
    #[arg(long, default_value_t = defaults::PADDING_REL, value_name = "REL")]
    padding: f64,
    /// Padding in output units.
    #[arg(long, value_name = "UNITS")]
    padding_abs: Option<f64>,
    /// Minimal angle α (degrees) for optimization and curve sections.
    #[arg(long, default_value_t = defaults::ALPHA_DEG, value_name = "DEG")]
    alpha: f64,
    /// AMIPS energy (1 = equilateral) at which linear optimization stops; 5 is the
    /// thesis's 10 in its normalization (2 = equilateral).
    #[arg(long, default_value_t = defaults::STOP_ENERGY)]
    stop_energy: f64,
    /// Maximum linear optimization passes.
    #[arg(long, default_value_t = defaults::MAX_PASSES)]
    max_passes: u32,
    /// AMIPS energy (1 = equilateral) at which curved optimization stops (the thesis's 20).
    #[arg(long, default_value_t = defaults::STOP_ENERGY_CURVED)]
    stop_energy_curved: f64,
    /// Maximum curved optimization passes.
    #[arg(long, default_value_t = defaults::MAX_PASSES_CURVED)]
    max_passes_curved: u32,
    /// Minimum angle (degrees) the CDT baseline refines to.
    #[arg(long, default_value_t = defaults::CDT_MIN_ANGLE_DEG, value_name = "DEG")]
    cdt_min_angle: f64,
    /// Vertex budget of the mesh: the optimizer's splits (and the CDT
    /// baseline's refinement) stop there, and the size field is resolved only
    /// as finely as such a mesh can follow; a mesh the budget kept coarser than
    /// the size asked comes with a warning.
    #[arg(long, default_value_t = defaults::MAX_VERTICES)]
    max_vertices: u32,
    /// The area check: a region whose area on the cubic mesh differs from its
    /// area in the drawing by more than this fraction (or 1e-9·d², if larger)
    /// is named in a warning.
    #[arg(long, default_value_t = defaults::AREA_TOLERANCE, value_name = "REL")]
    area_tolerance: f64,
    /// Validate the mesh after every stage (slow; for debugging).
    #[arg(long)]
    paranoid: bool,
    /// Most input segments (`<use>` copies and XML entities expanded); more
    /// fails at once with exit 2.
    #[arg(long, default_value_t = defaults::MAX_SEGMENTS, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    max_segments: u64,
    /// Most drawable elements (paths and basic shapes, `<use>` copies included).
    #[arg(long, default_value_t = defaults::MAX_SHAPES, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    max_shapes: u64,
    /// Most memory, MiB (or a size like 4G): the run's estimate from the
    /// input's counts is checked before meshing (exit 2), and the process's
    /// resident memory while it meshes (exit 3, nothing written). `triwild
    /// batch` also limits each child's memory to it when given.
    #[arg(long, default_value_t = defaults::MAX_MEMORY_MB, value_name = "MB", value_parser = parse_mb)]
    max_memory: u64,
    /// Stop with exit 3 after this many seconds of wall-clock time (checked
    /// between and inside the stages; nothing is written); `none` for no limit.
    #[arg(long, value_name = "SECONDS", default_value_t = DEFAULT_TIME_LIMIT, value_parser = parse_seconds)]
    time_limit: f64,
    /// Worker threads of the stages that run in parallel (0: one per core); the
    /// output is the same for every count. `triwild batch` gives each child 1
    /// unless this is given.
    #[arg(long, default_value_t = defaults::THREADS, value_name = "N")]
    threads: usize,
    /// Mesh size inside a region: h ≤ L there (repeatable). NAME is a region as
    /// the .msh names it (a shape's id, shape-N, fill-#rrggbb with --regions
    /// colour, background); L is relative to d, or in output units when the
    /// edge length is given with --edge-length-abs (as are all the size fields'
    /// lengths).
    #[arg(long = "size", value_name = "NAME=L", value_parser = parse_named_size)]
    size: Vec<(String, f64)>,
    /// Mesh size near a region's outline: h = L on it, growing linearly to the
    /// ambient size over DIST (gmsh's Distance + Threshold), or at the grading
    /// without DIST (repeatable).
    #[arg(long, value_name = "NAME=L[:DIST]", value_parser = parse_near_size)]
    size_near: Vec<(String, f64, Option<f64>)>,
    /// Mesh size in a box of output coordinates: h ≤ L there (repeatable).
    #[arg(long, value_name = "X0,Y0,X1,Y1=L", value_parser = parse_box_size, allow_hyphen_values = true)]
    size_box: Vec<([f64; 4], f64)>,
    /// Mesh size as a formula in x and y (output coordinates), in output units,
    /// e.g. '0.5 + 0.05*x' (+ - * / ^, sin, cos, exp, ln, sqrt, abs, ...).
    #[arg(long, value_name = "EXPR", allow_hyphen_values = true)]
    size_expr: Option<String>,
    /// Mesh size from a background mesh: a gmsh triangle mesh with one
    /// $NodeData value per node (a view, as gmsh writes it), in output units,
    /// interpolated linearly; it must cover the drawing.
    #[arg(long, value_name = "FILE.msh")]
    size_from: Option<std::path::PathBuf>,
    /// The automatic local feature size: narrow gaps, thin parts and tight
    /// curves get elements that fit them.
    #[arg(long, value_enum, default_value_t = if defaults::FEATURE_SIZE { OnOff::On } else { OnOff::Off })]
    feature_size: OnOff,
    /// Grading: the mesh size grows by at most this factor from one element
    /// to the next (at least 1).
    #[arg(long, default_value_t = defaults::GRADING, value_name = "G")]
    grading: f64,
    /// A periodic cell: the drawing is a pattern's tile, what lies outside the
    /// cell re-enters from the opposite side, the mesh covers the cell exactly
    /// and opposite sides match node for node (gmsh `$Periodic`; physical
    /// curves left, right, bottom, top). The cell is the root viewBox or --cell.
    #[arg(long, value_enum, num_args = 0..=1, default_missing_value = "xy", value_name = "AXES")]
    periodic: Option<PeriodicArg>,
    /// The periodic cell in output coordinates (y up), instead of the root viewBox.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_cell,
          allow_hyphen_values = true, requires = "periodic")]
    cell: Option<[f64; 4]>,
}

/// The repeating directions of `--periodic`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PeriodicArg {
    /// Left and right sides match.
    X,
    /// Bottom and top sides match.
    Y,
    /// Both.
    Xy,
}

fn parse_cell(s: &str) -> Result<[f64; 4], String> {
    let bad = || format!("expected X0,Y0,X1,Y1 (four numbers), got `{s}`");
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    let [x0, y0, x1, y1] = v[..] else {
        return Err(bad());
    };
    Ok([x0, y0, x1, y1])
}

/// A switch.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum OnOff {
    /// On.
    On,
    /// Off.
    Off,
}

/// `NAME=L`.
fn parse_named_size(s: &str) -> Result<(String, f64), String> {
    let (name, l) = s
        .rsplit_once('=')
        .ok_or_else(|| format!("expected NAME=L, got `{s}`"))?;
    if name.is_empty() {
        return Err(format!("expected NAME=L, got `{s}` (no name)"));
    }
    let l: f64 = l
        .trim()
        .parse()
        .map_err(|_| format!("expected NAME=L with a number L, got `{s}`"))?;
    Ok((name.to_owned(), l))
}

/// `NAME=L[:DIST]`.
fn parse_near_size(s: &str) -> Result<(String, f64, Option<f64>), String> {
    let (name, rest) = s
        .rsplit_once('=')
        .ok_or_else(|| format!("expected NAME=L[:DIST], got `{s}`"))?;
    if name.is_empty() {
        return Err(format!("expected NAME=L[:DIST], got `{s}` (no name)"));
    }
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .map_err(|_| format!("expected NAME=L[:DIST] with numbers, got `{s}`"))
    };
    match rest.split_once(':') {
        Some((l, dist)) => Ok((name.to_owned(), num(l)?, Some(num(dist)?))),
        None => Ok((name.to_owned(), num(rest)?, None)),
    }
}

/// `X0,Y0,X1,Y1=L`.
fn parse_box_size(s: &str) -> Result<([f64; 4], f64), String> {
    let bad = || format!("expected X0,Y0,X1,Y1=L, got `{s}`");
    let (corners, l) = s.rsplit_once('=').ok_or_else(bad)?;
    let v: Vec<f64> = corners
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    let [x0, y0, x1, y1] = v[..] else {
        return Err(bad());
    };
    Ok(([x0, y0, x1, y1], l.trim().parse().map_err(|_| bad())?))
}

/// `--time-limit`'s default from [`defaults::TIME_LIMIT`]; infinite for none.
const DEFAULT_TIME_LIMIT: f64 = match defaults::TIME_LIMIT {
    Some(t) => t,
    None => f64::INFINITY,
};

/// A memory size in MiB: a bare number is MiB, a number with a suffix (`4G`,
/// `512M`, `100K`) is converted (rounded up to whole MiB).
pub(crate) fn parse_mb(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let mb = if let Ok(v) = t.parse::<u64>() {
        v
    } else {
        triwild::batch::parse_size(t)?.div_ceil(1 << 20)
    };
    if mb == 0 {
        return Err(format!("expected at least 1 MiB, got `{s}`"));
    }
    Ok(mb)
}

/// A positive, finite number of seconds, or `none` (infinite).
fn parse_seconds(s: &str) -> Result<f64, String> {
    if s.trim().eq_ignore_ascii_case("none") {
        return Ok(f64::INFINITY);
    }
    match s.trim().parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 => Ok(t),
        _ => Err(format!(
            "expected a positive number of seconds or `none`, got `{s}`"
        )),
    }
}

fn len(rel: f64, abs: Option<f64>) -> Length {
    abs.map_or(Length::Rel(rel), Length::Abs)
}

impl ParamArgs {
    /// The meshing parameters these flags ask for (not validated).
    pub(crate) fn to_params(&self) -> Params {
        Params::DEFAULT
            .with_units(match self.units {
                UnitsArg::User => Units::User,
                UnitsArg::Px => Units::Px,
            })
            .with_scale(self.scale)
            .with_mesher(match self.mesher {
                MesherArg::Cdt => Mesher::Cdt,
                MesherArg::TriWild => Mesher::TriWild,
            })
            .with_stop_after(match (self.stop_after, self.linear) {
                (Some(StageArg::Bsp), _) => Some(Stage::Bsp),
                (Some(StageArg::Optimize), _) | (None, true) => Some(Stage::Optimize),
                (None, false) => None,
            })
            .with_order(match self.order {
                1 => Order::Linear,
                2 => Order::Quadratic,
                _ => Order::Cubic,
            })
            .with_l(len(self.edge_length, self.edge_length_abs))
            .with_l_min(match (self.min_edge_length_abs, self.min_edge_length) {
                (Some(abs), _) => Length::Abs(abs),
                (None, Some(v)) if self.edge_length_abs.is_some() => Length::Abs(v),
                (None, v) => Length::Rel(v.unwrap_or(defaults::MIN_EDGE_LENGTH_REL)),
            })
            .with_mu(len(self.mu, self.mu_abs))
            .with_eps(len(self.eps, self.eps_abs))
            .with_eps_m(len(self.eps_m, self.eps_m_abs))
            .with_padding(len(self.padding, self.padding_abs))
            .with_alpha_deg(self.alpha)
            .with_optimizer(self.optimizer())
            .with_cdt_min_angle_deg(self.cdt_min_angle)
            .with_max_vertices(self.max_vertices)
            .with_area_tolerance(self.area_tolerance)
            .with_paranoid(self.paranoid)
            .with_limits(self.max_segments, self.max_shapes, self.max_memory)
            .with_time_limit(self.time_limit.is_finite().then_some(self.time_limit))
            .with_threads(self.threads)
            .with_size(self.size_spec())
            .with_periodic(self.periodic.map(|axes| {
                let p = triwild::Periodic::new(match axes {
                    PeriodicArg::X => triwild::PeriodicAxes::X,
                    PeriodicArg::Y => triwild::PeriodicAxes::Y,
                    PeriodicArg::Xy => triwild::PeriodicAxes::Xy,
                });
                match self.cell {
                    Some(c) => p.with_cell(c),
                    None => p,
                }
            }))
    }

    /// The size fields these flags ask for: their lengths take the edge
    /// length's form (relative to d, or absolute with --edge-length-abs).
    /// The optimizer's stop rules and knobs (`Params::optimizer`): a knob's
    /// flag above and its line here are all the command line adds.
    fn optimizer(&self) -> OptimizerParams {
        let mut o = OptimizerParams::DEFAULT;
        o.stop_energy = self.stop_energy;
        o.stop_energy_curved = self.stop_energy_curved;
        o.max_passes = self.max_passes;
        o.max_passes_curved = self.max_passes_curved;
        o
    }

    fn size_spec(&self) -> SizeSpec {
        let form = |v: f64| {
            if self.edge_length_abs.is_some() {
                Length::Abs(v)
            } else {
                Length::Rel(v)
            }
        };
        let mut spec = SizeSpec::DEFAULT
            .with_feature_size(self.feature_size == OnOff::On)
            .with_grading(self.grading);
        for (name, l) in &self.size {
            spec = spec.with_region(name.clone(), form(*l));
        }
        for (name, l, dist) in &self.size_near {
            spec = spec.with_near(name.clone(), form(*l), dist.map(form));
        }
        for (corners, l) in &self.size_box {
            spec = spec.with_box(*corners, form(*l));
        }
        if let Some(e) = &self.size_expr {
            spec = spec.with_expr(e.clone());
        }
        if let Some(p) = &self.size_from {
            spec = spec.with_background(p.clone());
        }
        spec
    }

    /// `--max-memory` in bytes.
    pub(crate) fn max_memory_bytes(&self) -> u64 {
        self.max_memory.saturating_mul(1 << 20)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Flags {
        #[command(flatten)]
        params: ParamArgs,
    }

    fn l_min(args: &[&str]) -> Length {
        Flags::try_parse_from(std::iter::once("triwild").chain(args.iter().copied()))
            .expect("the flags parse")
            .params
            .to_params()
            .l_min
    }

    /// `--min-edge-length` takes the edge length's form: relative to d, or
    /// in output units with `--edge-length-abs`; `-abs` wins; the default
    /// stays relative.
    #[test]
    fn the_minimal_edge_length_follows_the_edge_lengths_form() {
        let default = Length::Rel(defaults::MIN_EDGE_LENGTH_REL);
        assert_eq!(l_min(&[]), default);
        assert_eq!(l_min(&["--edge-length-abs", "5"]), default);
        assert_eq!(l_min(&["--min-edge-length", "0.01"]), Length::Rel(0.01));
        assert_eq!(
            l_min(&["--edge-length-abs", "5", "--min-edge-length", "0.01"]),
            Length::Abs(0.01)
        );
        assert_eq!(
            l_min(&["--min-edge-length", "0.5", "--min-edge-length-abs", "2"]),
            Length::Abs(2.0)
        );
    }
}
