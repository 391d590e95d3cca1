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
use triwild::{Error, ErrorKind, Length, Mesher, Params, Stage};

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
enum Command {
    /// Preprocess the features only: write the primary / secondary FeatureSet as JSON.
    Features(FeaturesArgs),
}

#[derive(Args, Debug, Clone)]
struct FeaturesArgs {
    /// Input SVG file.
    input: PathBuf,
    /// Output JSON file [default: the input's path with extension .features.json].
    #[arg(short, long, value_name = "OUT.json")]
    output: Option<PathBuf>,
    /// Also write an SVG picture: primary red, secondary green, points black, input grey.
    #[arg(long, value_name = "OUT.svg")]
    preview: Option<PathBuf>,
    /// Print counts and the preprocessing time as one JSON object on stdout.
    #[arg(long)]
    stats: bool,
    #[command(flatten)]
    params: ParamArgs,
}

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
    /// TriWild's exact BSP mesher (features, exact BSP, rounding). The optimizer
    /// does not exist yet, so this writes the raw BSP mesh, as with `--stop-after bsp`.
    Bsp,
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum StageArg {
    /// The exact BSP mesh, rounded to f64, feature edges as physical curves (needs --mesher bsp).
    Bsp,
}

/// Meshing parameters (DESIGN "Coordinates and parameters").
#[derive(Args, Debug, Clone)]
struct ParamArgs {
    /// Linear mesher.
    #[arg(long, value_enum, default_value = "cdt")]
    mesher: MesherArg,
    /// Stop after this stage and write its mesh.
    #[arg(long, value_enum, value_name = "STAGE")]
    stop_after: Option<StageArg>,
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
            .with_stop_after(self.stop_after.map(|s| match s {
                StageArg::Bsp => Stage::Bsp,
            }))
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
        .with_preview(args.preview.clone());
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

/// `triwild features`: load, preprocess, write the JSON (and preview).
fn features_one(args: &FeaturesArgs, quiet: bool) -> ExitCode {
    use triwild::features::{self, FeatureSet};
    let input = &args.input;
    let params = args.params.to_params();
    let fail = |path: &Path, err: Error| {
        eprintln!("error: {}: {err}", path.display());
        exit_code(err.kind())
    };
    if let Err(e) = params.validate() {
        return fail(input, e);
    }
    let drawing = match triwild::svg::load_file(input) {
        Ok(d) => d,
        Err(e) => return fail(input, e),
    };
    if !quiet {
        for w in &drawing.warnings {
            eprintln!("warning: {}: {w}", input.display());
        }
    }
    let fs = FeatureSet::build(&drawing, &params.resolve(drawing.diagonal()));
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| input.with_extension("features.json"));
    let json = features::to_json(&fs).to_string();
    if let Err(e) = std::fs::write(&output, json) {
        return fail(&output, Error::Write(e));
    }
    if let Some(p) = &args.preview {
        if let Err(e) = std::fs::write(p, features::to_svg(&fs, &drawing)) {
            return fail(p, Error::Write(e));
        }
    }
    if args.stats {
        let stats =
            serde_json::json!({"input": input, "counts": fs.counts, "timing_ms": fs.timing});
        println!("{stats}");
    }
    ExitCode::SUCCESS
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(&cli.log);
    match &cli.command {
        None => mesh_one(&cli.mesh, cli.log.quiet),
        Some(Command::Features(args)) => features_one(args, cli.log.quiet),
    }
}
