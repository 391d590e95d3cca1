//! The `triwild` command line: argument parsing, logging and printing only.
#![allow(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "the binary talks to the user"
)]

use clap::{ArgMatches, Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use std::ffi::OsString;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;
use triwild::batch::{self, BatchOptions, MemoryGuard, Shard};
use triwild::output::{MshOptions, MshVersion};
use triwild::pipeline::{self, RunOptions};
use triwild::regions::{RegionMode, RegionOptions};
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
#[allow(
    clippy::large_enum_variant,
    reason = "parsed once per run; boxing would only add noise"
)]
enum Command {
    /// Preprocess the features only: write the primary / secondary FeatureSet as JSON.
    Features(FeaturesArgs),
    /// Mesh every SVG file under directories, each in its own child process.
    Batch(BatchArgs),
    /// Check a gmsh mesh (2.2 / 4.1, ASCII / binary, triangles of order 1-3): certify
    /// every triangle's Jacobian, report invalid elements, the minimum Jacobian ratio
    /// and the area. Exit 0 valid, 1 invalid, 2 unreadable.
    Check(CheckArgs),
}

#[derive(Args, Debug, Clone)]
struct CheckArgs {
    /// Mesh file (.msh).
    input: PathBuf,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    json: bool,
}

const BATCH_HELP: &str = "\
Each file runs in a child process of this binary (the single-file command with
the same flags plus --stats), so its mesh has the same bytes; a panic, crash,
timeout or memory overrun becomes that file's report row and the batch goes on.
Meshes mirror the input tree: DIR/a/b.svg -> OUTDIR/a/b.msh. Each finished file
appends one JSON line to OUTDIR/report.jsonl (OUTDIR/report.shard-K-of-N.jsonl
with --shard): file, status, cause, message, wall time, peak memory, output,
and the child's --stats object (times per stage, counts, quality).

--max-memory runs each child under `prlimit --as=BYTES` (util-linux) when
prlimit is on the PATH (a limit on address space, enforced by the kernel);
otherwise the batch samples the child's resident memory in /proc every 50 ms
and kills it past the limit.

Merging shards: triwild batch --merge-reports A.jsonl B.jsonl ... -o OUT.jsonl

Exit codes:
  0  every file meshed
  1  some file failed (see the report)
  2  usage error (bad flag, missing input, no .svg file found)
  4  I/O error (cannot write OUTDIR or the report)

Test-only hooks (environment variables read by the single-file command; never
set them in production): TRIWILD_TEST_PANIC_ON=S panics, TRIWILD_TEST_SLEEP_ON=S
sleeps for an hour, TRIWILD_TEST_ALLOC_ON=S allocates until killed (up to
16 GiB), each when the input path contains S.";

/// `triwild batch`: mesh a collection.
#[derive(Args, Debug, Clone)]
#[command(after_help = BATCH_HELP)]
struct BatchArgs {
    /// Directories (searched recursively for .svg files) and files to mesh;
    /// with --merge-reports, the reports to merge.
    #[arg(required = true, value_name = "DIR|FILE")]
    inputs: Vec<PathBuf>,
    /// Output directory; with --merge-reports, the merged report file.
    #[arg(short, long, value_name = "OUTDIR")]
    output: PathBuf,
    /// Files meshed at once [default: the number of cores].
    #[arg(short, long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    jobs: Option<u32>,
    /// Time limit per file, seconds.
    #[arg(long, default_value_t = 600.0, value_name = "SECONDS", value_parser = parse_timeout)]
    timeout: f64,
    /// Memory limit per file, like 8G or 512M [default: none].
    #[arg(long, value_name = "SIZE", value_parser = batch::parse_size)]
    max_memory: Option<u64>,
    /// Skip the files whose report row is ok and whose mesh exists; run the rest.
    #[arg(long)]
    resume: bool,
    /// Mesh only shard K of N of the sorted file list (files i with i mod N = K-1).
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Merge the reports given as inputs into the file given by -o (one row per
    /// file, sorted) and print their summary.
    #[arg(long, conflicts_with_all = ["resume", "shard", "jobs", "max_memory"])]
    merge_reports: bool,
    #[command(flatten)]
    format: FormatArgs,
    #[command(flatten)]
    params: ParamArgs,
}

fn parse_timeout(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(t) if t > 0.0 && Duration::try_from_secs_f64(t).is_ok() => Ok(t),
        _ => Err(format!("expected a positive number of seconds, got `{s}`")),
    }
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
    /// TriWild: feature analysis, exact BSP mesh, AMIPS optimization under the
    /// feature invariants (and curving).
    #[value(name = "triwild", alias = "bsp")]
    TriWild,
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum StageArg {
    /// The exact BSP mesh, rounded to f64, feature edges as physical curves.
    Bsp,
    /// The optimized linear mesh (same as --linear).
    Optimize,
}

/// Meshing parameters (DESIGN "Coordinates and parameters").
#[derive(Args, Debug, Clone)]
struct ParamArgs {
    /// Mesher.
    #[arg(long, value_enum, default_value = "triwild")]
    mesher: MesherArg,
    /// Stop after this stage and write its mesh (needs --mesher triwild).
    #[arg(long, value_enum, value_name = "STAGE")]
    stop_after: Option<StageArg>,
    /// Element order: 3 = cubic triangles (gmsh type 21) whose edges are the
    /// drawing's Béziers, 2 = quadratic (type 9), 1 = straight.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(1..=3))]
    order: u8,
    /// Write the optimized linear mesh (straight triangles, feature edges as
    /// physical curves), without curving: --stop-after optimize.
    #[arg(long, conflicts_with = "stop_after")]
    linear: bool,
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
    /// AMIPS energy (1 = equilateral) at which linear optimization stops; 5 is the
    /// thesis's 10 in its normalization (2 = equilateral).
    #[arg(long, default_value_t = 5.0)]
    stop_energy: f64,
    /// Maximum linear optimization passes.
    #[arg(long, default_value_t = 80)]
    max_passes: u32,
    /// AMIPS energy (1 = equilateral) at which curved optimization stops (the thesis's 20).
    #[arg(long, default_value_t = 10.0)]
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
                MesherArg::TriWild => Mesher::TriWild,
            })
            .with_stop_after(match (self.stop_after, self.linear) {
                (Some(StageArg::Bsp), _) => Some(Stage::Bsp),
                (Some(StageArg::Optimize), _) | (None, true) => Some(Stage::Optimize),
                (None, false) => None,
            })
            .with_order(match self.order {
                1 => triwild::fem::Order::Linear,
                2 => triwild::fem::Order::Quadratic,
                _ => triwild::fem::Order::Cubic,
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

/// Test-only hooks, so the batch tests can make a child misbehave: each
/// variable holds a substring of the input path that triggers it.
fn test_hooks(input: &Path) {
    let name = input.to_string_lossy();
    let hit = |var: &str| {
        std::env::var(var)
            .ok()
            .is_some_and(|s| !s.is_empty() && name.contains(&s))
    };
    if hit("TRIWILD_TEST_PANIC_ON") {
        panic!("test hook TRIWILD_TEST_PANIC_ON matched {name}");
    }
    if hit("TRIWILD_TEST_SLEEP_ON") {
        std::thread::sleep(Duration::from_secs(3600));
    }
    if hit("TRIWILD_TEST_ALLOC_ON") {
        let mut hog: Vec<Vec<u8>> = Vec::new();
        for _ in 0..1024 {
            hog.push(vec![1u8; 16 << 20]);
            std::thread::sleep(Duration::from_millis(10));
        }
        std::thread::sleep(Duration::from_secs(3600));
        drop(hog);
    }
}

fn mesh_one(args: &MeshArgs, quiet: bool) -> ExitCode {
    let Some(input) = &args.input else {
        eprintln!("error: no input file given (try `triwild --help`)");
        return ExitCode::from(2);
    };
    test_hooks(input);
    let output = args.output.clone().unwrap_or_else(|| default_output(input));
    let opts = RunOptions::new(args.params.to_params())
        .with_msh(args.format.to_options())
        .with_preview(args.preview.clone())
        .with_regions(args.regions.to_options());
    // The library's write errors do not say which file; an unwritable preview
    // is reported here, naming the preview, before anything is meshed.
    if let Some(preview) = &args.preview {
        if let Err(err) = triwild::output::check_writable(preview) {
            eprintln!("error: {}: {err}", preview.display());
            return exit_code(err.kind());
        }
    }
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
    if let Err(e) = triwild::output::write_file(&output, json.as_bytes()) {
        return fail(&output, e);
    }
    if let Some(p) = &args.preview {
        if let Err(e) = triwild::output::write_file(p, features::to_svg(&fs, &drawing).as_bytes()) {
            return fail(p, e);
        }
    }
    if args.stats {
        let stats =
            serde_json::json!({"input": input, "counts": fs.counts, "timing_ms": fs.timing});
        println!("{stats}");
    }
    ExitCode::SUCCESS
}

/// `triwild check`: read a mesh, certify it, print a summary or JSON; exit 0/1/2.
fn check_one(args: &CheckArgs) -> ExitCode {
    let input = &args.input;
    let mesh = match triwild::input::read_msh_file(input) {
        Ok(m) => m,
        Err(e) => {
            if args.json {
                let v = serde_json::json!({"file": input, "readable": false, "valid": false, "error": e.to_string()});
                println!("{v}");
            }
            eprintln!("error: {}: {e}", input.display());
            return ExitCode::from(2);
        }
    };
    let opts = triwild::curve::CertifyOptions::DEFAULT;
    let r = triwild::curve::check_msh(&mesh, &opts);
    if args.json {
        let mut v = serde_json::to_value(&r).unwrap_or_default();
        if let Some(o) = v.as_object_mut() {
            o.insert("file".into(), serde_json::json!(input));
            o.insert("readable".into(), true.into());
            o.insert("invalid".into(), r.mesh.invalid().into());
        }
        println!("{v}");
    } else {
        let m = &r.mesh;
        let orders: Vec<String> = m
            .by_order
            .iter()
            .zip(1..)
            .filter(|(n, _)| **n > 0)
            .map(|(n, o)| format!("{n} of order {o}"))
            .collect();
        println!(
            "{}: {}",
            input.display(),
            if r.valid {
                "valid".to_owned()
            } else {
                format!("INVALID ({})", r.reasons.join(", "))
            }
        );
        println!(
            "  triangles: {} ({}), {} curved, {} invalid",
            m.triangles,
            orders.join(", "),
            m.curved,
            m.invalid()
        );
        if let Some(w) = m.worst_element {
            println!(
                "  min Jacobian ratio: {:.6} (triangle {w})",
                m.min_detj_ratio
            );
        }
        println!("  area: {}", m.total_area);
    }
    ExitCode::from(if r.valid { 0 } else { 1 })
}

/// The flags of `matches` that belong to the single-file command's
/// parameters and format, as given on the command line: what every batch
/// child gets. Generic over the flags, so a new parameter is passed on too.
fn child_args(matches: &ArgMatches) -> Vec<OsString> {
    let mut cmd = clap::Command::new("child");
    cmd = ParamArgs::augment_args(cmd);
    cmd = FormatArgs::augment_args(cmd);
    let mut out = Vec::new();
    for arg in cmd.get_arguments() {
        let id = arg.get_id().as_str();
        if matches.value_source(id) != Some(clap::parser::ValueSource::CommandLine) {
            continue;
        }
        let long = arg
            .get_long()
            .expect("internal: parameter flags have long names");
        if arg.get_action().takes_values() {
            for v in matches.get_raw(id).into_iter().flatten() {
                let mut flag = OsString::from(format!("--{long}="));
                flag.push(v);
                out.push(flag);
            }
        } else {
            out.push(OsString::from(format!("--{long}")));
        }
    }
    out
}

fn batch_merge(args: &BatchArgs) -> ExitCode {
    let inputs: Vec<&Path> = args.inputs.iter().map(PathBuf::as_path).collect();
    match batch::merge_reports(&inputs, &args.output) {
        Ok(m) => {
            for d in &m.duplicates {
                eprintln!("warning: {d}: in more than one report; kept the last");
            }
            for l in &m.bad_lines {
                eprintln!("warning: {l}: not a report row; skipped");
            }
            let summary = batch::Summary::of(&m.rows);
            println!("{summary}");
            println!("report: {}", args.output.display());
            ExitCode::from(if summary.failed_total() == 0 { 0 } else { 1 })
        }
        Err(e) => {
            eprintln!("error: {e}");
            exit_code(e.kind())
        }
    }
}

fn run_batch(args: &BatchArgs, matches: &ArgMatches, quiet: bool) -> ExitCode {
    if args.merge_reports {
        return batch_merge(args);
    }
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: cannot find the triwild executable: {e}");
            return ExitCode::from(4);
        }
    };
    let mut opts = BatchOptions::new(exe, args.output.clone())
        .with_child_args(child_args(matches))
        .with_timeout(Duration::from_secs_f64(args.timeout))
        .with_memory(MemoryGuard::detect(args.max_memory))
        .with_resume(args.resume)
        .with_shard(args.shard);
    if let Some(j) = args.jobs {
        opts = opts.with_jobs(j as usize);
    }
    let plan = match batch::plan(&args.inputs, &opts) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(match e.kind() {
                ErrorKind::Io if matches!(e, Error::Write(_)) => 4,
                _ => 2,
            });
        }
    };
    for w in &plan.warnings {
        eprintln!("warning: {w}");
    }
    if !quiet {
        let shard = opts.shard.map_or(String::new(), |s| {
            format!(" (shard {s} of {} found)", plan.found)
        });
        eprintln!(
            "{} files{shard}: {} to mesh, {} done before; {} at once; report {}",
            plan.total(),
            plan.todo.len(),
            plan.done.len(),
            opts.jobs.min(plan.todo.len().max(1)),
            plan.report.display()
        );
    }
    let total = plan.todo.len();
    let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
        let pb = indicatif::ProgressBar::new(total as u64);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} [{wide_bar}] {pos}/{len} {msg} {per_sec} ETA {eta}",
            )
            .expect("internal: valid progress template")
            .progress_chars("=> "),
        );
        pb
    });
    let (mut ok, mut failed, mut done) = (0usize, 0usize, 0usize);
    let mut on_row = |row: &batch::Row| {
        done += 1;
        let line = match row.status {
            batch::Status::Ok => {
                ok += 1;
                let tris = row
                    .triangles()
                    .map_or(String::new(), |t| format!(", {t} triangles"));
                format!("ok      {} ({:.2} s{tris})", row.file, row.wall)
            }
            batch::Status::Failed => {
                failed += 1;
                let cause = row.cause.map_or("?", batch::Cause::name);
                let msg = row.message.as_deref().unwrap_or("");
                format!("FAILED  {} [{cause}] {msg}", row.file)
            }
        };
        match &bar {
            Some(pb) => {
                if row.status == batch::Status::Failed {
                    pb.println(&line);
                }
                pb.set_message(format!("ok {ok} failed {failed}"));
                pb.inc(1);
            }
            None if !quiet => eprintln!("[{done}/{total}] {line}"),
            None => {}
        }
    };
    let outcome = batch::run(&plan, &opts, &mut on_row);
    if let Some(pb) = &bar {
        pb.finish_and_clear();
    }
    match outcome {
        Ok(outcome) => {
            let summary = outcome.summary();
            println!("{summary}");
            println!("report: {}", plan.report.display());
            ExitCode::from(if summary.failed_total() == 0 { 0 } else { 1 })
        }
        Err(e) => {
            eprintln!("error: {e}");
            exit_code(e.kind())
        }
    }
}

/// Keep the default panic message, except for panics raised inside spade: the
/// baseline mesher catches those (a known spade limitation when splitting
/// crossing constraints) and recovers, so they are not the user's business.
fn install_panic_hook() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let in_spade = info
            .location()
            .is_some_and(|l| l.file().replace('\\', "/").contains("/spade-"));
        if !in_spade {
            default(info);
        }
    }));
}

fn main() -> ExitCode {
    install_panic_hook();
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    init_logging(&cli.log);
    match &cli.command {
        None => mesh_one(&cli.mesh, cli.log.quiet),
        Some(Command::Features(args)) => features_one(args, cli.log.quiet),
        Some(Command::Check(args)) => check_one(args),
        Some(Command::Batch(args)) => {
            let sub = matches
                .subcommand_matches("batch")
                .expect("internal: the batch subcommand matched");
            run_batch(args, sub, cli.log.quiet)
        }
    }
}
