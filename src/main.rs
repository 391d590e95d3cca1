//! The `triwild` command line: argument parsing, logging and printing only.
//!
//! This file holds the top level (the clap command, logging, the panic hook,
//! dispatch and exit codes); each command lives in its module under `cli/`.
#![allow(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "the binary talks to the user"
)]

mod cli {
    //! The commands of the binary, one module each, and the argument groups
    //! they share.
    pub(crate) mod args;
    pub(crate) mod batch;
    pub(crate) mod check;
    pub(crate) mod console;
    pub(crate) mod features;
    #[cfg(feature = "test-hooks")]
    pub(crate) mod hooks;
    pub(crate) mod mesh;
}

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use cli::batch::BatchArgs;
use cli::check::CheckArgs;
use cli::features::FeaturesArgs;
use cli::mesh::MeshArgs;
use std::process::ExitCode;
use triwild::ErrorKind;

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
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .without_time()
        .with_target(false)
        .init();
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

/// SIGINT and SIGTERM: remove the temporary output files and exit 128 + the
/// signal (130, 143); in `triwild batch`, stop the children, write their rows
/// as interrupted and let the batch finish (a second signal exits at once).
fn install_signal_handlers(batch: bool) {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    std::thread::spawn(move || {
        let mut first: Option<std::time::Instant> = None;
        for sig in signals.forever() {
            if batch {
                // The same signal often comes twice at once (to the process
                // and to its group, as `timeout` and a terminal send it):
                // only a repeat after a grace period ends the batch at once.
                match first {
                    None => {
                        first = Some(std::time::Instant::now());
                        triwild::batch::interrupt(sig);
                        continue;
                    }
                    Some(t) if t.elapsed() < SIGNAL_GRACE => continue,
                    Some(_) => {}
                }
            }
            triwild::remove_temporaries();
            std::process::exit(128 + sig);
        }
    });
}

/// A `triwild batch` child: its standard input is a pipe from the batch, which
/// closes when the batch ends in any way (SIGKILL included). At end-of-file the
/// child removes its temporary output and exits, so no orphan writes a mesh
/// that no report row describes.
fn watch_parent_pipe() {
    if std::env::var_os(triwild::batch::PARENT_PIPE_ENV).is_none() {
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
            triwild::remove_temporaries();
            std::process::exit(EXIT_ORPHAN);
        });
    drop(watcher);
}

/// A second SIGINT / SIGTERM this long after the first ends a batch at once.
const SIGNAL_GRACE: std::time::Duration = std::time::Duration::from_secs(2);

/// Exit code of a batch child whose batch is gone (128 + SIGHUP, as a shell
/// reports a process that lost its terminal).
const EXIT_ORPHAN: i32 = 129;

fn main() -> ExitCode {
    install_panic_hook();
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    init_logging(&cli.log);
    install_signal_handlers(matches!(cli.command, Some(Command::Batch(_))));
    watch_parent_pipe();
    let quiet = cli.log.quiet;
    match &cli.command {
        None => cli::mesh::run(&cli.mesh, quiet),
        Some(Command::Features(args)) => cli::features::run(args, quiet),
        Some(Command::Check(args)) => cli::check::run(args),
        Some(Command::Batch(args)) => {
            let sub = matches
                .subcommand_matches("batch")
                .expect("internal: the batch subcommand matched");
            cli::batch::run(args, sub, quiet)
        }
    }
}
