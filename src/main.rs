//! The `triwild` command line: argument parsing, logging and printing only.
#![allow(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "the binary talks to the user"
)]

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use triwild::output::{MshOptions, MshVersion};
use triwild::pipeline::{self, RunOptions};
use triwild::regions::{RegionMode, RegionOptions};
use triwild::{Error, ErrorKind, Length, Mesher, Params};

const EXIT_HELP: &str = "\
Exit codes:
  0  success
  2  bad input or usage (missing, unreadable-as-SVG or empty drawing, bad flag)
  3  meshing failed
  4  I/O error (reading the input or writing an output)";

/// Robust curved triangle meshing of SVG drawings (TriWild, in Rust).
///
/// Lengths are relative to d, the diagonal of the drawing's bounding box, unless
/// given with the matching `-abs` flag in user units.
#[derive(Parser, Debug)]
#[command(version, about, long_about = None, after_help = EXIT_HELP, args_conflicts_with_subcommands = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    mesh: MeshArgs,
    #[command(flatten)]
    log: LogArgs,
}

#[derive(Subcommand, Debug)]
enum Command {}

#[derive(Args, Debug, Clone)]
struct LogArgs {
    /// Print only errors.
    #[arg(short, long, global = true)]
    quiet: bool,
    /// More log output (-v info, -vv debug, -vvv trace), on stderr.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
}

#[derive(Args, Debug, Clone)]
struct MeshArgs {
    /// Input SVG file.
    input: Option<PathBuf>,
    /// Output .msh file [default: the input's path with extension .msh].
    #[arg(short, long, value_name = "OUT.msh")]
    output: Option<PathBuf>,
    /// Also write an SVG drawing of the mesh.
    #[arg(long, value_name = "OUT.svg")]
    preview: Option<PathBuf>,
    /// Print one JSON object of statistics on stdout.
    #[arg(long)]
    stats: bool,
    #[command(flatten)]
    format: FormatArgs,
    #[command(flatten)]
    params: ParamArgs,
    #[command(flatten)]
    regions: RegionArgs,
}

/// What becomes a physical surface, and what is dropped.
#[derive(Args, Debug, Clone)]
struct RegionArgs {
    /// Physical surfaces: one per filled shape (SVG id, else shape-N), one per fill
    /// colour (fill-#rrggbb), or a single `domain`; plus `background`.
    #[arg(long, value_enum, default_value = "shape")]
    regions: RegionsArg,
    /// Drop the background (what no filled shape covers).
    #[arg(long)]
    cut_outside: bool,
    /// Keep only the named regions.
    #[arg(long, value_delimiter = ',', value_name = "NAME,...")]
    keep: Vec<String>,
    /// Remove the region containing the point X,Y (output coordinates: SVG user
    /// units after transforms, y pointing up, i.e. y = -y_svg). Repeatable.
    #[arg(long, value_name = "X,Y", value_parser = parse_point, allow_hyphen_values = true)]
    hole: Vec<(f64, f64)>,
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
    fn to_options(&self) -> RegionOptions {
        RegionOptions::DEFAULT
            .with_mode(match self.regions {
                RegionsArg::Shape => RegionMode::Shape,
                RegionsArg::Colour => RegionMode::Colour,
                RegionsArg::None => RegionMode::None,
            })
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

#[derive(Args, Debug, Clone)]
struct FormatArgs {
    /// gmsh file format version.
    #[arg(long, value_enum, default_value = "4.1")]
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

#[derive(ValueEnum, Debug, Clone, Copy)]
enum MesherArg {
    /// spade constrained Delaunay triangulation with refinement (linear baseline).
    Cdt,
    /// TriWild's exact BSP mesher.
    Bsp,
}

/// Meshing parameters (DESIGN "Coordinates and parameters").
#[derive(Args, Debug, Clone)]
struct ParamArgs {
    /// Linear mesher.
    #[arg(long, value_enum, default_value = "cdt")]
    mesher: MesherArg,
    /// Target edge length l, relative to d.
    #[arg(short = 'l', long, default_value_t = 0.05, value_name = "REL")]
    edge_length: f64,
    /// Target edge length l in user units (overrides --edge-length).
    #[arg(long, value_name = "UNITS")]
    edge_length_abs: Option<f64>,
    /// Minimal edge length l_m, relative to d.
    #[arg(long, default_value_t = 1e-4, value_name = "REL")]
    min_edge_length: f64,
    /// Minimal edge length l_m in user units.
    #[arg(long, value_name = "UNITS")]
    min_edge_length_abs: Option<f64>,
    /// Feature envelope μ, relative to d.
    #[arg(long, default_value_t = 1e-3, value_name = "REL")]
    mu: f64,
    /// Feature envelope μ in user units.
    #[arg(long, value_name = "UNITS")]
    mu_abs: Option<f64>,
    /// Envelope ε of secondary features, relative to d.
    #[arg(short = 'e', long, default_value_t = 2e-3, value_name = "REL")]
    eps: f64,
    /// Envelope ε in user units.
    #[arg(long, value_name = "UNITS")]
    eps_abs: Option<f64>,
    /// Numerical tolerance ε_m, relative to d.
    #[arg(long, default_value_t = 1e-8, value_name = "REL")]
    eps_m: f64,
    /// Numerical tolerance ε_m in user units.
    #[arg(long, value_name = "UNITS")]
    eps_m_abs: Option<f64>,
    /// Padding of the meshed box around the drawing, relative to d.
    #[arg(long, default_value_t = 0.05, value_name = "REL")]
    padding: f64,
    /// Padding in user units.
    #[arg(long, value_name = "UNITS")]
    padding_abs: Option<f64>,
    /// Minimal angle α (degrees) for optimization and curve sections.
    #[arg(long, default_value_t = 10.0, value_name = "DEG")]
    alpha: f64,
    /// AMIPS energy at which linear optimization stops.
    #[arg(long, default_value_t = 10.0)]
    stop_energy: f64,
    /// Maximum linear optimization passes.
    #[arg(long, default_value_t = 80)]
    max_passes: u32,
    /// AMIPS energy at which curved optimization stops.
    #[arg(long, default_value_t = 20.0)]
    stop_energy_curved: f64,
    /// Maximum curved optimization passes.
    #[arg(long, default_value_t = 10)]
    max_passes_curved: u32,
    /// Minimum angle (degrees) the CDT baseline refines to.
    #[arg(long, default_value_t = 25.0, value_name = "DEG")]
    cdt_min_angle: f64,
    /// Vertex budget of the CDT baseline's refinement.
    #[arg(long, default_value_t = 200_000)]
    max_vertices: u32,
    /// Validate the mesh after every stage (slow; for debugging).
    #[arg(long)]
    paranoid: bool,
}

fn len(rel: f64, abs: Option<f64>) -> Length {
    abs.map_or(Length::Rel(rel), Length::Abs)
}

impl ParamArgs {
    fn to_params(&self) -> Params {
        Params::DEFAULT
            .with_mesher(match self.mesher {
                MesherArg::Cdt => Mesher::Cdt,
                MesherArg::Bsp => Mesher::Bsp,
            })
            .with_l(len(self.edge_length, self.edge_length_abs))
            .with_l_min(len(self.min_edge_length, self.min_edge_length_abs))
            .with_mu(len(self.mu, self.mu_abs))
            .with_eps(len(self.eps, self.eps_abs))
            .with_eps_m(len(self.eps_m, self.eps_m_abs))
            .with_padding(len(self.padding, self.padding_abs))
            .with_alpha_deg(self.alpha)
            .with_stop(self.stop_energy, self.max_passes)
            .with_stop_curved(self.stop_energy_curved, self.max_passes_curved)
            .with_cdt_min_angle_deg(self.cdt_min_angle)
            .with_max_vertices(self.max_vertices)
            .with_paranoid(self.paranoid)
    }
}

impl FormatArgs {
    fn to_options(&self) -> MshOptions {
        MshOptions {
            version: match self.msh_version {
                MshVersionArg::V41 => MshVersion::V41,
                MshVersionArg::V22 => MshVersion::V22,
            },
            binary: self.binary,
        }
    }
}

fn exit_code(kind: ErrorKind) -> ExitCode {
    ExitCode::from(match kind {
        ErrorKind::BadInput => 2,
        ErrorKind::Meshing => 3,
        ErrorKind::Io => 4,
    })
}

fn init_logging(log: &LogArgs) {
    let level = if log.quiet {
        "error"
    } else {
        match log.verbose {
            0 => "warn",
            1 => "info",
            2 => "debug",
            _ => "trace",
        }
    };
    let filter = tracing_subscriber::EnvFilter::try_from_env("TRIWILD_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .without_time()
        .with_target(false)
        .init();
}

/// The default output path: the input with extension `.msh`.
fn default_output(input: &Path) -> PathBuf {
    input.with_extension("msh")
}

fn mesh_one(args: &MeshArgs, quiet: bool) -> ExitCode {
    let Some(input) = &args.input else {
        eprintln!("error: no input file given (try `triwild --help`)");
        return ExitCode::from(2);
    };
    let output = args.output.clone().unwrap_or_else(|| default_output(input));
    let opts = RunOptions::new(args.params.to_params())
        .with_msh(args.format.to_options())
        .with_preview(args.preview.clone())
        .with_regions(args.regions.to_options());
    match pipeline::run_file(input, &output, &opts) {
        Ok(report) => {
            if !quiet {
                for w in &report.warnings {
                    eprintln!("warning: {}: {w}", input.display());
                }
            }
            if args.stats {
                match serde_json::to_string(&report) {
                    Ok(s) => println!("{s}"),
                    Err(e) => {
                        eprintln!("error: {}: cannot format statistics: {e}", input.display());
                        return ExitCode::from(4);
                    }
                }
            }
            ExitCode::SUCCESS
        }
        Err(err) => {
            let file = match &err {
                Error::Write(_) => &output,
                _ => input,
            };
            eprintln!("error: {}: {err}", file.display());
            exit_code(err.kind())
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(&cli.log);
    match &cli.command {
        None => mesh_one(&cli.mesh, cli.log.quiet),
        Some(c) => match *c {},
    }
}
