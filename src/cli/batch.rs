//! `triwild batch`: mesh a collection, each file in a child process of this
//! binary, with a progress display on stderr and the summary on stdout; or
//! merge the reports of shards (`--merge-reports`).
//!
//! The library plans and runs the batch and hands over each finished file's
//! row; everything shown to the user is here.

use super::args::{FormatArgs, ParamArgs};
use crate::cli::console::{errln, outln};
use crate::exit_code;
use clap::{ArgMatches, Args};
use std::ffi::OsString;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;
use triwild::batch::{self, BatchOptions, MemoryGuard, Row, Shard};
use triwild::{Error, ErrorKind};

const BATCH_HELP: &str = "\
Each file runs in a child process of this binary (the single-file command with
the same flags plus --stats), so its mesh has the same bytes; a panic, crash,
timeout or memory overrun becomes that file's report row and the batch goes on.
Meshes mirror the input tree: DIR/a/b.svg -> OUTDIR/a/b.msh. Each finished file
appends one JSON line to OUTDIR/report.jsonl (OUTDIR/report.shard-K-of-N.jsonl
with --shard): file, status, cause, message, wall time, peak memory, output,
and the child's --stats object (times per stage, counts, quality).

--max-memory (MiB, or a size like 8G), when given, is each child's budget of
estimated memory and also its limit: the child runs under `prlimit --as=BYTES`
(util-linux) when prlimit is on the PATH (a limit on address space, enforced by
the kernel); otherwise the batch samples the child's resident memory in /proc
every 50 ms and kills it past the limit.

Merging shards: triwild batch --merge-reports A.jsonl B.jsonl ... -o OUT.jsonl

The report page: OUTDIR/report.html (--no-html to skip), one offline file with
the headline, plots, a gallery of every mesh (each child also writes its preview,
OUTDIR/a/b.preview.svg), the slowest and worst files and every failure. Build
it again from a report (merged shard reports too): triwild report REPORT.jsonl
-o report.html

Exit codes:
  0  every file meshed
  1  some file failed (see the report)
  2  usage error (bad flag, missing input, no .svg file found)
  4  I/O error (cannot write OUTDIR or the report)
  130, 143  interrupted by SIGINT / SIGTERM: running children are stopped,
     their files get an `interrupted` row; a child whose batch dies (even by
     SIGKILL) removes its temporary output and exits";

/// The text after `triwild batch --help`'s options.
#[cfg(not(feature = "test-hooks"))]
fn after_help() -> &'static str {
    BATCH_HELP
}

/// The text after `triwild batch --help`'s options, and the test hooks.
#[cfg(feature = "test-hooks")]
fn after_help() -> String {
    format!("{BATCH_HELP}\n\n{}", super::hooks::HELP)
}

/// `triwild batch` arguments.
#[derive(Args, Debug, Clone)]
#[command(after_help = after_help())]
pub(crate) struct BatchArgs {
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
    #[arg(long, default_value_t = BatchOptions::DEFAULT_TIMEOUT.as_secs_f64(), value_name = "SECONDS", value_parser = parse_timeout)]
    timeout: f64,
    /// Skip the files whose report row is ok and whose mesh exists; run the rest.
    #[arg(long)]
    resume: bool,
    /// Mesh only shard K of N of the sorted file list (files i with i mod N = K-1).
    #[arg(long, value_name = "K/N")]
    shard: Option<Shard>,
    /// Merge the reports given as inputs into the file given by -o (one row per
    /// file, sorted) and print their summary.
    #[arg(long, conflicts_with_all = ["resume", "shard", "jobs"])]
    merge_reports: bool,
    /// Do not write the report page (OUTDIR/report.html, or
    /// report.shard-K-of-N.html for a shard) nor the mesh previews it shows.
    #[arg(long)]
    no_html: bool,
    /// Fill the previews' triangles by how their size matches the size field
    /// (edge / h, as `triwild IN.svg --preview OUT.svg --preview-size`).
    #[arg(long, conflicts_with = "no_html")]
    preview_size: bool,
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
    // The batch runs its children side by side: one thread each, unless told.
    if matches.value_source("threads") != Some(clap::parser::ValueSource::CommandLine) {
        out.push(OsString::from("--threads=1"));
    }
    out
}

/// Each child's memory limit, bytes: `--max-memory` when given on the command
/// line (its default is only the children's estimate budget), else none.
fn memory_limit(args: &BatchArgs, matches: &ArgMatches) -> Option<u64> {
    (matches.value_source("max_memory") == Some(clap::parser::ValueSource::CommandLine))
        .then(|| args.params.max_memory_bytes())
}

/// `--merge-reports`: join the reports, print their summary; exit 0 when no
/// file failed, else 1.
fn merge(args: &BatchArgs) -> ExitCode {
    let inputs: Vec<&Path> = args.inputs.iter().map(PathBuf::as_path).collect();
    match batch::merge_reports(&inputs, &args.output) {
        Ok(m) => {
            for d in &m.duplicates {
                errln!("warning: {d}: in more than one report; kept the last");
            }
            for l in &m.bad_lines {
                errln!("warning: {l}: not a report row; skipped");
            }
            let summary = batch::Summary::of(&m.rows);
            outln!("{summary}");
            outln!("report: {}", args.output.display());
            ExitCode::from(if summary.failed_total() == 0 { 0 } else { 1 })
        }
        Err(e) => {
            errln!("error: {e}");
            exit_code(e.kind())
        }
    }
}

/// Run the batch (or merge reports), show progress, print the summary; exit
/// 0 when every file meshed, 1 when some failed, 2 usage, 4 I/O.
///
/// The children run `child` (a program and its leading arguments) when given,
/// else this executable.
pub(crate) fn run(
    args: &BatchArgs,
    matches: &ArgMatches,
    quiet: bool,
    child: Option<&[OsString]>,
) -> ExitCode {
    if args.merge_reports {
        return merge(args);
    }
    let (exe, mut leading) = match child {
        Some([program, leading @ ..]) => (program.into(), leading.to_vec()),
        _ => match std::env::current_exe() {
            Ok(e) => (e, Vec::new()),
            Err(e) => {
                errln!("error: cannot find the triwild executable: {e}");
                return ExitCode::from(4);
            }
        },
    };
    let flags = child_args(matches);
    let recorded = flags
        .iter()
        .map(|f| f.to_string_lossy().into_owned())
        .collect();
    leading.extend(flags);
    let mut opts = BatchOptions::new(exe, args.output.clone())
        .with_child_args(leading)
        .with_flags(recorded)
        .with_previews(!args.no_html)
        .with_preview_size(args.preview_size)
        .with_timeout(Duration::from_secs_f64(args.timeout))
        .with_memory(MemoryGuard::detect(memory_limit(args, matches)))
        .with_resume(args.resume)
        .with_shard(args.shard);
    if let Some(j) = args.jobs {
        opts = opts.with_jobs(j as usize);
    }
    let plan = match batch::plan(&args.inputs, &opts) {
        Ok(p) => p,
        Err(e) => {
            errln!("error: {e}");
            return ExitCode::from(match e.kind() {
                ErrorKind::Io if matches!(e, Error::Write(_)) => 4,
                _ => 2,
            });
        }
    };
    for w in &plan.warnings {
        errln!("warning: {w}");
    }
    if !quiet {
        let shard = opts.shard.map_or(String::new(), |s| {
            format!(" (shard {s} of {} found)", plan.found)
        });
        errln!(
            "{} files{shard}: {} to mesh, {} done before; {} at once; report {}",
            plan.total(),
            plan.todo.len(),
            plan.done.len(),
            opts.jobs.min(plan.todo.len().max(1)),
            plan.report.display()
        );
    }
    let mut progress = Progress::new(plan.todo.len(), quiet);
    let ran = batch::run(&plan, &opts, &mut |row: &Row| progress.row(row));
    progress.finish();
    match ran {
        Ok(ran) => {
            let summary = ran.summary();
            outln!("{summary}");
            outln!("report: {}", plan.report.display());
            if !args.no_html {
                let page = opts.page_path();
                let popts = batch::PageOptions::new(opts.out_dir.clone());
                match batch::write_page(&ran.rows, &popts, &page) {
                    Ok(s) => outln!("{}", super::report::page_line(&page, &s)),
                    Err(e) => {
                        errln!("error: report page: {e}");
                        return ExitCode::from(4);
                    }
                }
            }
            if let Some(sig) = batch::interrupted() {
                errln!(
                    "interrupted by signal {sig}: the files being meshed have an `interrupted` row; --resume runs the rest"
                );
                return ExitCode::from(u8::try_from(128 + sig).unwrap_or(130));
            }
            ExitCode::from(if summary.failed_total() == 0 { 0 } else { 1 })
        }
        Err(e) => {
            errln!("error: {e}");
            exit_code(e.kind())
        }
    }
}

/// What the user sees while a batch runs, on stderr: a progress bar with the
/// failures printed above it on a terminal, else one line per file; nothing
/// when quiet.
struct Progress {
    bar: Option<indicatif::ProgressBar>,
    quiet: bool,
    total: usize,
    done: usize,
    ok: usize,
    failed: usize,
}

impl Progress {
    fn new(total: usize, quiet: bool) -> Self {
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
        Progress {
            bar,
            quiet,
            total,
            done: 0,
            ok: 0,
            failed: 0,
        }
    }

    /// One file is done.
    fn row(&mut self, row: &Row) {
        self.done += 1;
        let line = match row.status {
            batch::Status::Ok => {
                self.ok += 1;
                let tris = row
                    .triangles()
                    .map_or(String::new(), |t| format!(", {t} triangles"));
                format!("ok      {} ({:.2} s{tris})", row.file, row.wall)
            }
            batch::Status::Failed => {
                self.failed += 1;
                let cause = row.cause.map_or("?", batch::Cause::name);
                let msg = row.message.as_deref().unwrap_or("");
                format!("FAILED  {} [{cause}] {msg}", row.file)
            }
        };
        match &self.bar {
            Some(pb) => {
                if row.status == batch::Status::Failed {
                    pb.println(&line);
                }
                pb.set_message(format!("ok {} failed {}", self.ok, self.failed));
                pb.inc(1);
            }
            None if !self.quiet => errln!("[{}/{}] {line}", self.done, self.total),
            None => {}
        }
    }

    /// The batch is over: clear the bar.
    fn finish(&self) {
        if let Some(pb) = &self.bar {
            pb.finish_and_clear();
        }
    }
}
