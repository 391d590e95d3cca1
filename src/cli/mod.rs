//! The `triwild` command line: argument parsing, logging and printing only
//! (feature `cli`; not API). `src/main.rs` and the Python package's `triwild`
//! command both run [`main_with`].
//!
//! This file holds the top level (the clap command, logging, the panic hook,
//! dispatch and exit codes); each command lives in its module under `cli/`.
//! The modules name the library as `triwild::…`, as they did when they were
//! the binary's (`lib.rs` declares `extern crate self as triwild`).

pub(crate) mod args;
pub(crate) mod batch;
pub(crate) mod check;
pub(crate) mod console;
pub(crate) mod features;
#[cfg(feature = "test-hooks")]
pub(crate) mod hooks;
pub(crate) mod mesh;
pub(crate) mod parser_log;
pub(crate) mod report;

use crate::cli::batch::BatchArgs;
use crate::cli::check::CheckArgs;
use crate::cli::features::FeaturesArgs;
use crate::cli::mesh::MeshArgs;
use crate::cli::report::ReportArgs;
use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use std::ffi::OsString;
use std::process::ExitCode;
use triwild::ErrorKind;
use triwild::{PaintOptions, Params, RegionOptions};

const EXIT_HELP: &str = "\
Exit codes:
  0  success
  2  bad input or usage (missing, unreadable-as-SVG or empty drawing, bad flag),
     or an input over a budget ('too large: ...', raise with --max-segments,
     --max-shapes or --max-memory)
  3  meshing failed, or --time-limit reached (nothing is written)
  4  I/O error (reading the input or writing an output)
  130, 143  interrupted by SIGINT / SIGTERM (no temporary file is left)
  141  standard output closed early (`triwild ... --stats | head`); outputs complete";

/// Robust curved triangle meshing of SVG drawings (TriWild, in Rust).
///
/// Coordinates are the drawing's own numbers (the user units of the root viewBox,
/// y up; --units px for CSS px, --scale to convert). Lengths are relative to d, the
/// diagonal of the drawing's bounding box, unless given with the matching `-abs`
/// flag in output units.
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
    /// Build a batch's report page (report.html) again from its report: a
    /// batch's report.jsonl, a merged report, or the shards' reports of a
    /// cluster run (joined one row per file).
    Report(ReportArgs),
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

/// The exit code of an error of this kind: 2 bad input or usage, 3 meshing
/// failed, 4 I/O.
pub(crate) fn exit_code(kind: ErrorKind) -> ExitCode {
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
    use std::io::IsTerminal;
    use tracing_subscriber::layer::SubscriberExt;
    use tracing_subscriber::util::SubscriberInitExt;
    use tracing_subscriber::{Layer, filter};
    // triwild's own events on stderr (colour only on a terminal); the parser's
    // (usvg and its crates, through `log`) collected, to be folded into one
    // warning line per file (`parser_log`). `try_init`: a second run in the
    // same process (the Python package) keeps the first run's subscriber
    // instead of panicking.
    let own = tracing_subscriber::fmt::layer()
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .without_time()
        .with_target(false)
        .with_filter(filter::filter_fn(|m| !parser_log::is_foreign(m.target())))
        .with_filter(filter);
    let _ = tracing_subscriber::registry()
        .with(own)
        .with(parser_log::Collect)
        .try_init();
}

/// Keep the default panic message, except for panics raised inside spade: the
/// baseline mesher catches those (a known spade limitation when splitting
/// crossing constraints) and recovers, so they are not the user's business.
/// (The Python package installs it too, for `triwild.mesh(…, mesher="cdt")`.)
pub fn install_panic_hook() {
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

/// A `triwild batch` child: its standard input is a pipe from the batch, which
/// closes when the batch ends in any way (SIGKILL included). At end-of-file the
/// child removes its temporary output and exits, so no orphan writes a mesh
/// that no report row describes.
fn watch_parent_pipe() {
    if std::env::var_os(crate::batch::PARENT_PIPE_ENV).is_none() {
        return;
    }
    // The pipe is read through its own file descriptor, not std's buffered
    // stdin: the thread then never allocates, so it gets no malloc arena of
    // its own (64 MiB of address space, which a child under `prlimit --as`
    // cannot spare).
    let pipe = {
        use std::os::fd::AsFd;
        match std::io::stdin().as_fd().try_clone_to_owned() {
            Ok(fd) => std::fs::File::from(fd),
            Err(_) => return,
        }
    };
    let watcher = std::thread::Builder::new()
        .name("triwild-parent-pipe".into())
        .stack_size(64 << 10)
        .spawn(move || {
            let mut pipe = pipe;
            let mut sink = [0u8; 64];
            loop {
                match std::io::Read::read(&mut pipe, &mut sink) {
                    Ok(0) => break,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(_) => break,
                    Ok(_) => {}
                }
            }
            crate::remove_temporaries();
            std::process::exit(EXIT_ORPHAN);
        });
    drop(watcher);
}

/// Exit code of a batch child whose batch is gone (128 + SIGHUP, as a shell
/// reports a process that lost its terminal).
const EXIT_ORPHAN: i32 = 129;

/// Run the command line on `args` (the program name first, as
/// `std::env::args_os()` gives it) and return the process's exit code.
///
/// `child` is the program `triwild batch` runs once per file, with its
/// leading arguments (`[python, "-m", "triwild"]` from the Python package);
/// `None` runs this executable (`std::env::current_exe()`).
pub fn main_with(args: impl IntoIterator<Item = OsString>, child: Option<&[OsString]>) -> u8 {
    install_panic_hook();
    watch_parent_pipe();
    let matches = match Cli::command().try_get_matches_from(args) {
        Ok(m) => m,
        Err(e) => {
            // help and version (exit 0) on stdout, usage errors (exit 2) on stderr
            let _ = e.print();
            return u8::try_from(e.exit_code()).unwrap_or(2);
        }
    };
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return u8::try_from(e.exit_code()).unwrap_or(2);
        }
    };
    init_logging(&cli.log);
    let quiet = cli.log.quiet;
    let code = match &cli.command {
        None => mesh::run(&cli.mesh, quiet),
        Some(Command::Features(args)) => features::run(args, quiet),
        Some(Command::Check(args)) => check::run(args),
        Some(Command::Report(args)) => report::run(args, quiet),
        Some(Command::Batch(args)) => {
            let sub = matches
                .subcommand_matches("batch")
                .expect("internal: the batch subcommand matched");
            batch::run(args, sub, quiet, child)
        }
    };
    // `ExitCode` has no getter; the commands only build codes from a `u8`
    (0..=u8::MAX)
        .find(|&n| ExitCode::from(n) == code)
        .unwrap_or(1)
}

/// The single-file command's parameter, region and paint flags, parsed as the command
/// line parses them (same defaults, same checks): what the Python package's
/// `triwild.mesh(svg, **flags)` turns its keyword arguments into.
///
/// # Errors
/// The parser's message (one line, without the `error: ` prefix) for an
/// unknown flag or a bad value.
pub fn mesh_options(
    flags: impl IntoIterator<Item = OsString>,
) -> Result<(Params, RegionOptions, PaintOptions), String> {
    match MeshFlags::try_parse_from(flags) {
        Ok(f) => Ok((
            f.params.to_params(),
            f.regions.to_options(),
            f.regions.paint_options(),
        )),
        Err(e) => {
            let text = e.render().to_string();
            let line = text.lines().next().unwrap_or("bad flag");
            Err(line.strip_prefix("error: ").unwrap_or(line).to_owned())
        }
    }
}

/// The long names of the flags [`mesh_options`] takes (`edge-length`, …).
pub fn mesh_option_names() -> Vec<String> {
    MeshFlags::command()
        .get_arguments()
        .filter_map(|a| a.get_long().map(str::to_owned))
        .collect()
}

/// The parameter and region flags of the single-file command, alone.
#[derive(Parser, Debug)]
#[command(no_binary_name = true, disable_help_flag = true)]
struct MeshFlags {
    #[command(flatten)]
    params: args::ParamArgs,
    #[command(flatten)]
    regions: args::RegionArgs,
}
