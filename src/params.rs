//! Meshing parameters (docs/design.md "Coordinates and parameters").
//!
//! Every length is given either relative to `d`, the diagonal of the input's
//! bounding box, or in absolute output units ([`Params::units`] times
//! [`Params::scale`]); [`Params::resolve`] turns them into absolute [`Resolved`]
//! values once `d` is known.

use crate::budget::{Deadline, Limits};
use crate::element::Order;
pub(crate) use crate::stage::Stage;
pub(crate) use crate::units::Units;
use crate::{Error, Result};

/// The default value of every parameter, named once: [`Params::DEFAULT`] and
/// the command line's `[default: …]` are both built from these constants.
///
/// Lengths are relative to `d`, the diagonal of the drawing's bounding box.
/// "The thesis" is the TriWild chapter of the WildMeshing thesis (§4.4 lists
/// μ, ε, ε_m, α, l and l_m "in our experiments"; §4.4.1 and §4.4.2 give the
/// stop rules); the values that are ours say so.
///
/// The command line's other defaults live with the options they fill:
/// `RegionOptions::DEFAULT` (`--regions shape`), `MshOptions::DEFAULT`
/// (`--msh-version 4.1`, ASCII) and `batch::BatchOptions::DEFAULT_TIMEOUT`
/// (`batch --timeout 600`), in the modules above this one.
pub mod defaults {
    use super::{Mesher, Order, Units};

    /// Feature envelope μ = 1e-3·d: the distance that separates primary
    /// features (thesis §4.4).
    pub const MU_REL: f64 = 1e-3;
    /// Envelope ε of secondary features = 2e-3·d, i.e. 2μ (thesis §4.4).
    pub const EPS_REL: f64 = 2e-3;
    /// Numerical tolerance ε_m = 1e-8·d for degenerate and straight curves
    /// (the thesis's 1e-8, §4.4, taken relative to d like every other length).
    pub const EPS_M_REL: f64 = 1e-8;
    /// Target edge length l = d/20 (thesis §4.4, as in TetWild).
    pub const EDGE_LENGTH_REL: f64 = 0.05;
    /// Minimal edge length l_m = 1e-4·d; curvature above 2/l_m is not primary
    /// (thesis §4.3.1, §4.4).
    pub const MIN_EDGE_LENGTH_REL: f64 = 1e-4;
    /// Padding of the meshed box around the drawing = 0.05·d (the reference
    /// implementation's).
    pub const PADDING_REL: f64 = 0.05;
    /// Area tolerance 1e-6 (relative to the region's drawn area, with
    /// 1e-9·d² the floor): a region of the cubic mesh whose area differs from
    /// its drawn area by more is named in a warning. The drawn area is exact
    /// to rounding and a cubic mesh that keeps the outlines has the drawn
    /// area to rounding (about 1e-13 relative), so this flags what the mesh
    /// changed: outlines meshed within ε, lost slivers, moved corners.
    pub const AREA_TOLERANCE: f64 = 1e-6;
    /// Minimal angle α = 10° the optimizer aims for, also the turning bound of
    /// a primary section (thesis §4.4, Theorem 4.4).
    pub const ALPHA_DEG: f64 = 10.0;
    /// AMIPS energy at which linear optimization stops = 5: the thesis's 10
    /// (§4.4.1, TetWild's default) in our normalisation, where an equilateral
    /// triangle has energy 1 (the thesis's `tr(JᵀJ)/det J` gives it 2).
    pub const STOP_ENERGY: f64 = 5.0;
    /// Maximum linear optimization passes = 80 (thesis §4.4.1).
    pub const MAX_PASSES: u32 = 80;
    /// AMIPS energy at which curved optimization stops = 10: the thesis's 20
    /// (§4.4.2) in our normalisation (1 = equilateral).
    pub const STOP_ENERGY_CURVED: f64 = 10.0;
    /// Maximum curved optimization passes = 10 (thesis §4.4.2).
    pub const MAX_PASSES_CURVED: u32 = 10;
    /// Minimum angle 25° the CDT baseline refines to (ours: the baseline is
    /// not in the thesis; refinement may not terminate above 34°).
    pub const CDT_MIN_ANGLE_DEG: f64 = 25.0;
    /// Vertex budget 200 000 of the CDT baseline's refinement, so that it
    /// always terminates (ours).
    pub const MAX_VERTICES: u32 = 200_000;
    /// The mesher: TriWild (features, exact BSP, optimization, curving).
    pub const MESHER: Mesher = Mesher::TriWild;
    /// Element order: cubic, whose edges reproduce the drawing's Béziers
    /// exactly (the thesis's cubic Lagrange map, §4.4.2).
    pub const ORDER: Order = Order::Cubic;
    /// Output units: the user units of the root `viewBox`, the numbers written
    /// in the document (ours: a FEM model is in the drawing's units).
    pub const UNITS: Units = Units::User;
    /// Output scale: 1, the coordinates as [`UNITS`] gives them.
    pub const SCALE: f64 = 1.0;
    /// Most input segments, 1 000 000 (ours: about 60 times the dev set's
    /// largest drawing, 16 896; `<use>` copies and XML entities counted
    /// expanded): `--max-segments`.
    pub const MAX_SEGMENTS: u64 = 1_000_000;
    /// Most drawable elements, 200 000 (ours: about 230 times the dev set's
    /// largest, 878): `--max-shapes`.
    pub const MAX_SHAPES: u64 = 200_000;
    /// Most estimated memory, MiB: 8 GiB (ours; the estimate is 64 MiB, plus
    /// 4 KiB per segment and 4 bytes per byte of text, about twice what was
    /// measured): `--max-memory`.
    pub const MAX_MEMORY_MB: u64 = 8 << 10;
    /// Wall-clock limit of one run: ten minutes, as `triwild batch`'s
    /// `--timeout` (ours: the dev set's slowest drawing takes under two minutes,
    /// the slowest held-out one 95 s; a run that would take hours stops
    /// cleanly instead, exit 3): `--time-limit`.
    pub const TIME_LIMIT: Option<f64> = Some(600.0);
    /// Worker threads of the stages that run in parallel: 0, one per core
    /// (ours; `triwild batch` gives each child 1): `--threads`.
    pub const THREADS: usize = 0;
    /// Grading of the size field: from one element to the next the size grows
    /// by at most this factor (ours: 1.5, the growth rate 0.5 per unit length
    /// that thin strokes' sizes used before the size field; gmsh's
    /// `Mesh.SmoothRatio` default is 1.8): `--grading`.
    pub const GRADING: f64 = 1.5;
    /// The automatic local-feature-size field (`--feature-size on|off`): off
    /// by default (ours: on, with the grading 1.5, it gave 2.5 times the
    /// triangles on a 12-drawing sample of the dev set; see the README's "Mesh size").
    pub const FEATURE_SIZE: bool = false;
}

mod size_spec;
pub use size_spec::{
    BackgroundMesh, BoxSize, NearSize, RegionSize, SizeFn, SizeFnSignature, SizeSpec,
};

/// A length, relative to the bounding-box diagonal `d` or absolute.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Length {
    /// A fraction of `d`.
    Rel(f64),
    /// Output units: after all SVG transforms, in [`Params::units`] times
    /// [`Params::scale`].
    Abs(f64),
}

impl Length {
    /// The absolute value for a drawing of diagonal `d`.
    pub fn resolve(self, d: f64) -> f64 {
        match self {
            Length::Rel(r) => r * d,
            Length::Abs(a) => a,
        }
    }

    /// The number as given (relative or absolute).
    pub(crate) fn value(self) -> f64 {
        match self {
            Length::Rel(v) | Length::Abs(v) => v,
        }
    }
}

/// Which mesher builds the linear mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mesher {
    /// spade's constrained Delaunay triangulation with refinement: the baseline.
    Cdt,
    /// TriWild: features, the exact BSP mesh, then mesh optimization (and curving).
    #[serde(rename = "triwild")]
    TriWild,
}

/// All meshing parameters. Start from [`Params::DEFAULT`] and use the `with_*` builders.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct Params {
    /// Feature envelope μ: distance that separates primary features (§4.3.1).
    /// Default [`defaults::MU_REL`]·d. Larger: fewer primary features, coarser meshes.
    pub mu: Length,
    /// Envelope ε for secondary features (§4.4.1). Default [`defaults::EPS_REL`]·d (2μ).
    pub eps: Length,
    /// Numerical tolerance ε_m for degenerate and straight curves (§4.4).
    /// Default [`defaults::EPS_M_REL`]·d.
    pub eps_m: Length,
    /// Target edge length l. Default [`defaults::EDGE_LENGTH_REL`]·d.
    pub l: Length,
    /// Minimal edge length l_m; curvature above 2/l_m is not primary (§4.3.1).
    /// Default [`defaults::MIN_EDGE_LENGTH_REL`]·d.
    pub l_min: Length,
    /// Padding of the meshed box around the input. Default [`defaults::PADDING_REL`]·d.
    pub padding: Length,
    /// Minimal angle α in degrees the optimizer aims for; also the turning bound of
    /// a primary section (Theorem 4.4). Default [`defaults::ALPHA_DEG`].
    pub alpha_deg: f64,
    /// The mesh optimizer's stop rules and knobs, which the linear and the
    /// curved optimization carry whole. Default [`OptimizerParams::DEFAULT`].
    /// Serialized flat, beside the other fields.
    #[serde(flatten)]
    pub optimizer: OptimizerParams,
    /// Minimum angle (degrees) the CDT baseline refines to. Default
    /// [`defaults::CDT_MIN_ANGLE_DEG`].
    pub cdt_min_angle_deg: f64,
    /// Vertex budget of the mesh: the optimizer's splits and the CDT
    /// baseline's refinement stop there (so both always terminate), and the
    /// size field's background is resolved only as finely as a mesh of this
    /// many vertices can follow. Default [`defaults::MAX_VERTICES`].
    pub max_vertices: u32,
    /// The mesher. Default [`defaults::MESHER`].
    pub mesher: Mesher,
    /// Stop after this stage and deliver its mesh. Default `None` (run every
    /// stage that exists). [`Stage::Bsp`] needs [`Mesher::TriWild`].
    pub stop_after: Option<Stage>,
    /// Run the full mesh validator after every stage (slow). Default false.
    pub paranoid: bool,
    /// Order of the output elements of the TriWild mesher: cubic (gmsh type
    /// 21, the curves exactly), quadratic (type 9) or linear (straight).
    /// Default [`defaults::ORDER`]. Serialized as its number (3, 2 or 1).
    #[serde(serialize_with = "serialize_order")]
    pub order: Order,
    /// Units of the output coordinates (and of every absolute length): the
    /// user units of the root `viewBox` or CSS px. Default [`defaults::UNITS`].
    /// Applied when an SVG is loaded with `LoadOptions::from_params` (`run_file`):
    /// an already loaded `Drawing` is in the units it was loaded in.
    pub units: Units,
    /// Multiplies every output coordinate (e.g. 0.001 for a drawing in mm and a
    /// mesh in m); absolute lengths are in the scaled units. Default
    /// [`defaults::SCALE`]. Applied when an SVG is loaded, like [`Params::units`].
    pub scale: f64,
    /// Most input segments (`<use>` copies and XML entities expanded); more is
    /// an [`Error::TooLarge`] before usvg builds its tree. Default
    /// [`defaults::MAX_SEGMENTS`].
    pub max_segments: u64,
    /// Most drawable elements (paths and basic shapes, `<use>` copies
    /// included). Default [`defaults::MAX_SHAPES`].
    pub max_shapes: u64,
    /// Most memory, MiB: the run's estimate from the input's counts is checked
    /// against it before usvg builds its tree, and the process's resident
    /// memory in the pipeline's loops and before the large allocations (past
    /// it the run stops with [`Error::MemoryLimit`] and writes nothing).
    /// Default [`defaults::MAX_MEMORY_MB`].
    pub max_memory_mb: u64,
    /// Wall-clock limit, seconds, checked cooperatively in the pipeline's
    /// loops: past it the run stops with [`Error::TimeLimit`] and writes
    /// nothing. Default [`defaults::TIME_LIMIT`] (none).
    pub time_limit: Option<f64>,
    /// Worker threads of the stages that run in parallel (region
    /// classification); 0: one per core. The output is the same for every
    /// count. Default [`defaults::THREADS`].
    pub threads: usize,
    /// The size field's inputs beside [`Params::l`]: per-region sizes, sizes
    /// near outlines, boxes, a formula, a background mesh, a function, the
    /// automatic feature size and the grading. Default [`SizeSpec::DEFAULT`].
    pub size: SizeSpec,
    /// The area check's tolerance: a region whose area on the cubic mesh
    /// differs from its area in the drawing by more than this fraction (or
    /// 1e-9·d², if larger) is named in a warning. Default
    /// [`defaults::AREA_TOLERANCE`].
    pub area_tolerance: f64,
    /// A periodic cell: the drawing is the tile of a pattern, meshed on the
    /// cell with matching opposite sides and gmsh's `$Periodic` section.
    /// Default `None` (the padded box of the drawing).
    pub periodic: Option<Periodic>,
}

/// The mesh optimizer's stop rules and knobs: what the linear optimization
/// (`optimize::schedule`) and the curved one (`curve::optimize`) read from the
/// parameters. Both stages carry this value whole, so a knob added here (its
/// field, its default, its check in [`OptimizerParams::validate`]) reaches
/// every pass with no other hop (the optimizer's passes read it as
/// `self.limits.params`, the curving stage's as `opts.params`; docs/design.md
/// "Coordinates and parameters").
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct OptimizerParams {
    /// AMIPS energy (1 for equilateral) at which linear optimization stops.
    /// Default [`defaults::STOP_ENERGY`] (the thesis's 10 in its normalization).
    pub stop_energy: f64,
    /// AMIPS energy (1 for equilateral) at which curved optimization stops.
    /// Default [`defaults::STOP_ENERGY_CURVED`] (the thesis's 20).
    pub stop_energy_curved: f64,
    /// Maximum linear optimization passes. Default [`defaults::MAX_PASSES`].
    pub max_passes: u32,
    /// Maximum curved optimization passes. Default [`defaults::MAX_PASSES_CURVED`].
    pub max_passes_curved: u32,
}

impl OptimizerParams {
    /// The defaults of [`defaults`].
    pub const DEFAULT: OptimizerParams = OptimizerParams {
        stop_energy: defaults::STOP_ENERGY,
        stop_energy_curved: defaults::STOP_ENERGY_CURVED,
        max_passes: defaults::MAX_PASSES,
        max_passes_curved: defaults::MAX_PASSES_CURVED,
    };

    /// Check the values; the error names the command-line flag.
    pub fn validate(&self) -> Result<()> {
        for (name, e) in [
            ("stop-energy", self.stop_energy),
            ("stop-energy-curved", self.stop_energy_curved),
        ] {
            if !(e.is_finite() && e >= 1.0) {
                return Err(Error::InvalidParams(format!(
                    "--{name} must be at least 1 (the AMIPS energy of an equilateral triangle), got {e}"
                )));
            }
        }
        Ok(())
    }
}

/// Which directions of a [`Periodic`] cell repeat.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PeriodicAxes {
    /// Left and right sides match (period along x).
    X,
    /// Bottom and top sides match (period along y).
    Y,
    /// Both.
    Xy,
}

impl PeriodicAxes {
    /// Whether the period runs along x.
    pub fn x(self) -> bool {
        matches!(self, PeriodicAxes::X | PeriodicAxes::Xy)
    }
    /// Whether the period runs along y.
    pub fn y(self) -> bool {
        matches!(self, PeriodicAxes::Y | PeriodicAxes::Xy)
    }
}

/// A periodic cell (`--periodic`, `--cell`): the mesh covers the cell exactly,
/// the drawing translated by the periods and clipped to the cell is meshed
/// (what lies outside re-enters from the opposite side), and every node on a
/// periodic side has a partner on the opposite side at the same position after
/// the translation.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Periodic {
    /// The repeating directions.
    pub axes: PeriodicAxes,
    /// The cell `[x0, y0, x1, y1]` in output coordinates (y up); `None`: the
    /// root `viewBox` (an error for a drawing without one).
    pub cell: Option<[f64; 4]>,
}

impl Periodic {
    /// A cell repeating along `axes`, the root `viewBox` by default.
    pub const fn new(axes: PeriodicAxes) -> Periodic {
        Periodic { axes, cell: None }
    }
    /// The cell `[x0, y0, x1, y1]` in output coordinates.
    pub const fn with_cell(mut self, cell: [f64; 4]) -> Periodic {
        self.cell = Some(cell);
        self
    }
}

impl Params {
    /// The defaults of [`defaults`] (docs/design.md "Coordinates and parameters").
    ///
    /// ```
    /// use triwild::{Length, Order, Params, defaults};
    /// let p = Params::DEFAULT
    ///     .with_l(Length::Abs(2.5)) // element size in user units
    ///     .with_order(Order::Quadratic);
    /// assert!(p.validate().is_ok());
    /// assert_eq!(Params::DEFAULT.l, Length::Rel(defaults::EDGE_LENGTH_REL));
    /// // lengths relative to the drawing's diagonal d become absolute once d is known
    /// assert_eq!(p.resolve(100.0).l, 2.5);
    /// assert!(Params::DEFAULT.with_l(Length::Rel(-1.0)).validate().is_err());
    /// ```
    pub const DEFAULT: Params = Params {
        mu: Length::Rel(defaults::MU_REL),
        eps: Length::Rel(defaults::EPS_REL),
        eps_m: Length::Rel(defaults::EPS_M_REL),
        l: Length::Rel(defaults::EDGE_LENGTH_REL),
        l_min: Length::Rel(defaults::MIN_EDGE_LENGTH_REL),
        padding: Length::Rel(defaults::PADDING_REL),
        alpha_deg: defaults::ALPHA_DEG,
        optimizer: OptimizerParams::DEFAULT,
        cdt_min_angle_deg: defaults::CDT_MIN_ANGLE_DEG,
        max_vertices: defaults::MAX_VERTICES,
        mesher: defaults::MESHER,
        stop_after: None,
        paranoid: false,
        order: defaults::ORDER,
        units: defaults::UNITS,
        scale: defaults::SCALE,
        max_segments: defaults::MAX_SEGMENTS,
        max_shapes: defaults::MAX_SHAPES,
        max_memory_mb: defaults::MAX_MEMORY_MB,
        time_limit: defaults::TIME_LIMIT,
        threads: defaults::THREADS,
        size: SizeSpec::DEFAULT,
        area_tolerance: defaults::AREA_TOLERANCE,
        periodic: None,
    };

    /// Set the feature envelope μ.
    pub fn with_mu(mut self, mu: Length) -> Self {
        self.mu = mu;
        self
    }
    /// Set the envelope ε.
    pub fn with_eps(mut self, eps: Length) -> Self {
        self.eps = eps;
        self
    }
    /// Set the numerical tolerance ε_m.
    pub fn with_eps_m(mut self, eps_m: Length) -> Self {
        self.eps_m = eps_m;
        self
    }
    /// Set the target edge length l.
    pub fn with_l(mut self, l: Length) -> Self {
        self.l = l;
        self
    }
    /// Set the minimal edge length l_m.
    pub fn with_l_min(mut self, l_min: Length) -> Self {
        self.l_min = l_min;
        self
    }
    /// Set the box padding.
    pub fn with_padding(mut self, padding: Length) -> Self {
        self.padding = padding;
        self
    }
    /// Set α in degrees.
    pub fn with_alpha_deg(mut self, alpha_deg: f64) -> Self {
        self.alpha_deg = alpha_deg;
        self
    }
    /// Set the CDT baseline's minimum angle.
    pub fn with_cdt_min_angle_deg(mut self, deg: f64) -> Self {
        self.cdt_min_angle_deg = deg;
        self
    }
    /// Set the CDT baseline's vertex budget.
    pub fn with_max_vertices(mut self, n: u32) -> Self {
        self.max_vertices = n;
        self
    }
    /// Set the area check's tolerance (see [`Params::area_tolerance`]).
    pub fn with_area_tolerance(mut self, tolerance: f64) -> Self {
        self.area_tolerance = tolerance;
        self
    }
    /// Set the element order of the TriWild mesher.
    pub fn with_order(mut self, order: Order) -> Self {
        self.order = order;
        self
    }

    /// Set the units of the output coordinates.
    pub fn with_units(mut self, units: Units) -> Self {
        self.units = units;
        self
    }
    /// Set the factor applied to every output coordinate.
    pub fn with_scale(mut self, scale: f64) -> Self {
        self.scale = scale;
        self
    }

    /// Choose the mesher.
    pub fn with_mesher(mut self, mesher: Mesher) -> Self {
        self.mesher = mesher;
        self
    }
    /// Set the optimization stop rules.
    pub fn with_stop(mut self, energy: f64, max_passes: u32) -> Self {
        self.optimizer.stop_energy = energy;
        self.optimizer.max_passes = max_passes;
        self
    }
    /// Set the curved optimization stop rules.
    pub fn with_stop_curved(mut self, energy: f64, max_passes: u32) -> Self {
        self.optimizer.stop_energy_curved = energy;
        self.optimizer.max_passes_curved = max_passes;
        self
    }
    /// Set the optimizer's stop rules and knobs at once.
    pub fn with_optimizer(mut self, optimizer: OptimizerParams) -> Self {
        self.optimizer = optimizer;
        self
    }
    /// Stop after `stage` (or run every stage, with `None`).
    pub fn with_stop_after(mut self, stage: Option<Stage>) -> Self {
        self.stop_after = stage;
        self
    }
    /// Set the input budgets: segments, drawable elements, estimated memory (MiB).
    pub fn with_limits(mut self, max_segments: u64, max_shapes: u64, max_memory_mb: u64) -> Self {
        self.max_segments = max_segments;
        self.max_shapes = max_shapes;
        self.max_memory_mb = max_memory_mb;
        self
    }
    /// Set the wall-clock limit, seconds (`None`: no limit).
    pub fn with_time_limit(mut self, seconds: Option<f64>) -> Self {
        self.time_limit = seconds;
        self
    }

    /// Set the size field's inputs (see [`SizeSpec`]).
    pub fn with_size(mut self, size: SizeSpec) -> Self {
        self.size = size;
        self
    }

    /// Set the worker threads (0: one per core).
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = threads;
        self
    }

    /// The input budgets the loader checks.
    pub(crate) fn limits(&self) -> Limits {
        Limits {
            max_segments: self.max_segments,
            max_shapes: self.max_shapes,
            max_memory_mb: self.max_memory_mb,
        }
    }

    /// The deadline of a run starting now.
    pub(crate) fn deadline(&self) -> Deadline {
        Deadline::after(self.time_limit).with_memory_mb(self.max_memory_mb)
    }

    /// Mesh a periodic cell (see [`Periodic`]).
    pub fn with_periodic(mut self, periodic: Option<Periodic>) -> Self {
        self.periodic = periodic;
        self
    }

    /// Turn the paranoid validator on or off.
    pub fn with_paranoid(mut self, paranoid: bool) -> Self {
        self.paranoid = paranoid;
        self
    }

    /// Check every parameter's range.
    ///
    /// # Errors
    /// [`Error::InvalidParams`] naming the first bad parameter.
    pub fn validate(&self) -> Result<()> {
        let lengths = [
            ("mu", self.mu),
            ("eps", self.eps),
            ("eps-m", self.eps_m),
            ("edge-length", self.l),
            ("min-edge-length", self.l_min),
            ("padding", self.padding),
        ];
        for (name, len) in lengths {
            let v = len.value();
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidParams(format!(
                    "--{name} must be a positive finite number, got {v}"
                )));
            }
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(Error::InvalidParams(format!(
                "--scale must be a positive finite number, got {}",
                self.scale
            )));
        }
        if !(self.alpha_deg > 0.0 && self.alpha_deg < 60.0) {
            return Err(Error::InvalidParams(format!(
                "--alpha must be in (0, 60) degrees, got {}",
                self.alpha_deg
            )));
        }
        if !(self.cdt_min_angle_deg >= 0.0 && self.cdt_min_angle_deg <= 34.0) {
            return Err(Error::InvalidParams(format!(
                "--cdt-min-angle must be in [0, 34] degrees (refinement may not terminate above), got {}",
                self.cdt_min_angle_deg
            )));
        }
        if !(self.area_tolerance.is_finite() && self.area_tolerance > 0.0) {
            return Err(Error::InvalidParams(format!(
                "--area-tolerance must be a positive finite number, got {}",
                self.area_tolerance
            )));
        }
        if self.max_vertices < 16 {
            return Err(Error::InvalidParams(format!(
                "--max-vertices must be at least 16, got {}",
                self.max_vertices
            )));
        }
        self.optimizer.validate()?;
        for (name, v) in [
            ("max-segments", self.max_segments),
            ("max-shapes", self.max_shapes),
            ("max-memory", self.max_memory_mb),
        ] {
            if v == 0 {
                return Err(Error::InvalidParams(format!(
                    "--{name} must be at least 1, got 0"
                )));
            }
        }
        if let Some(t) = self.time_limit {
            if !(t.is_finite() && t > 0.0) {
                return Err(Error::InvalidParams(format!(
                    "--time-limit must be a positive finite number of seconds, got {t}"
                )));
            }
        }
        if let Some(stage) = self.stop_after {
            if !stage.can_stop_after() {
                return Err(Error::InvalidParams(format!(
                    "meshing cannot stop after stage {stage}: only bsp and optimize deliver a mesh"
                )));
            }
        }
        self.size.validate()?;
        if let Some(p) = self.periodic {
            if self.mesher != Mesher::TriWild {
                return Err(Error::InvalidParams(
                    "--periodic needs --mesher triwild (the cdt baseline meshes a padded box)"
                        .into(),
                ));
            }
            if let Some([x0, y0, x1, y1]) = p.cell {
                let finite = [x0, y0, x1, y1].iter().all(|v| v.is_finite());
                if !(finite && x1 > x0 && y1 > y0) {
                    return Err(Error::InvalidParams(format!(
                        "--cell {x0},{y0},{x1},{y1}: a cell needs X0 < X1 and Y0 < Y1, all finite"
                    )));
                }
            }
        }
        if self.stop_after.is_some() && self.mesher != Mesher::TriWild {
            return Err(Error::InvalidParams(
                "--stop-after and --linear need --mesher triwild".into(),
            ));
        }
        Ok(())
    }

    /// Absolute values for a drawing whose bounding-box diagonal is `d`.
    pub fn resolve(&self, d: f64) -> Resolved {
        Resolved {
            d,
            mu: self.mu.resolve(d),
            eps: self.eps.resolve(d),
            eps_m: self.eps_m.resolve(d),
            l: self.l.resolve(d),
            l_min: self.l_min.resolve(d),
            padding: self.padding.resolve(d),
            alpha: self.alpha_deg.to_radians(),
            units: self.units,
            scale: self.scale,
        }
    }
}

/// [`Params::order`] as its number (1, 2 or 3) rather than the variant's name.
fn serialize_order<S: serde::Serializer>(
    order: &Order,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_u8(*order as u8)
}

impl Default for Params {
    fn default() -> Self {
        Params::DEFAULT
    }
}

/// Absolute parameter values for one drawing (output units, radians), and the
/// output units themselves.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Resolved {
    /// Diagonal of the input's bounding box.
    pub d: f64,
    /// Feature envelope μ.
    pub mu: f64,
    /// Secondary envelope ε.
    pub eps: f64,
    /// Numerical tolerance ε_m.
    pub eps_m: f64,
    /// Target edge length l.
    pub l: f64,
    /// Minimal edge length l_m.
    pub l_min: f64,
    /// Box padding.
    pub padding: f64,
    /// α in radians.
    pub alpha: f64,
    /// The units of the output coordinates ([`Params::units`]).
    pub units: Units,
    /// The factor applied to the output coordinates ([`Params::scale`]).
    pub scale: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_resolve_relative_to_d() {
        Params::DEFAULT.validate().unwrap();
        let r = Params::DEFAULT.resolve(200.0);
        assert_eq!(r.l, 10.0);
        assert_eq!(r.mu, 0.2);
        assert_eq!(r.eps, 0.4);
    }

    #[test]
    fn units_and_scale_serialize_by_name_and_value() {
        let p = Params::DEFAULT.with_units(Units::Px).with_scale(2.5);
        let json = serde_json::to_value(&p).unwrap();
        assert_eq!(
            (json["units"].clone(), json["scale"].clone()),
            ("px".into(), 2.5.into())
        );
        // the optimizer's parameters serialize flat, beside the others
        assert_eq!(json["stop_energy"], defaults::STOP_ENERGY);
        assert_eq!(json["max_passes_curved"], defaults::MAX_PASSES_CURVED);
        assert!(json.get("optimizer").is_none());
        let r = serde_json::to_value(Params::DEFAULT.resolve(1.0)).unwrap();
        assert_eq!(
            (r["units"].clone(), r["scale"].clone()),
            ("user".into(), 1.0.into())
        );
    }

    #[test]
    fn order_serializes_as_its_number() {
        let json = |p: Params| serde_json::to_value(p).unwrap()["order"].clone();
        assert_eq!(json(Params::DEFAULT), 3);
        assert_eq!(json(Params::DEFAULT.with_order(Order::Quadratic)), 2);
        assert_eq!(json(Params::DEFAULT.with_order(Order::Linear)), 1);
    }

    #[test]
    fn bad_values_are_rejected() {
        assert!(
            Params::DEFAULT
                .with_mu(Length::Rel(0.0))
                .validate()
                .is_err()
        );
        assert!(
            Params::DEFAULT
                .with_l(Length::Abs(f64::NAN))
                .validate()
                .is_err()
        );
        assert!(
            Params::DEFAULT
                .with_cdt_min_angle_deg(40.0)
                .validate()
                .is_err()
        );
        assert!(Params::DEFAULT.with_alpha_deg(-1.0).validate().is_err());
        for scale in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Params::DEFAULT.with_scale(scale).validate().is_err());
        }
        Params::DEFAULT
            .with_units(Units::Px)
            .with_scale(1e-3)
            .validate()
            .unwrap();
        assert!(
            Params::DEFAULT
                .with_mesher(Mesher::Cdt)
                .with_stop_after(Some(Stage::Bsp))
                .validate()
                .is_err()
        );
        Params::DEFAULT
            .with_mesher(Mesher::TriWild)
            .with_stop_after(Some(Stage::Bsp))
            .validate()
            .unwrap();
    }
}
