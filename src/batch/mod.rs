//! Batch meshing of whole collections (`triwild batch`): discovery, one
//! isolated child process per file, a report row per file, resume, shards
//! and the closing summary. docs/design.md "Outputs a user can check" (batch report);
//! STYLE "Errors and logging" (one bad SVG never stops a batch).
//!
//! Each file is meshed by a child process of the triwild binary itself
//! running the single-file command (`triwild ARGS -o OUT.msh --stats -- IN.svg`),
//! so a batch writes the same bytes as the single-file command, and a panic,
//! a crash, a time-out or running out of memory ends only that child: it
//! becomes the file's [`Row`] and the batch goes on.
//!
//! Guarantees:
//! - every file of the plan gets exactly one row in the report, appended and
//!   flushed as soon as the file is done (a killed batch keeps every finished
//!   row; [`read_report`] skips the torn line a kill may leave);
//! - output paths mirror the input tree: `DIR/a/b.svg` → `OUTDIR/a/b.msh`;
//!   a failed file leaves no mesh;
//! - `--shard K/N` is a deterministic slice of the sorted file list, and
//!   shards `1/N … N/N` cover every file exactly once;
//! - `--resume` reruns exactly the files without an ok row whose mesh exists.
//!
//! The library does not print; the binary shows progress from the rows it
//! is handed and prints the [`Summary`].

mod child;
mod discover;
mod page;
mod plots;
mod report;
mod summary;
mod thumbnail;

pub use child::{
    ChildSpec, MemoryGuard, PARENT_PIPE_ENV, interrupt, interrupted, parse_size, run_child,
};
pub use discover::{Discovery, Shard, SourceFile, discover};
pub use page::{PageOptions, PageStats, preview_path, render_page, stage_of, write_page};
pub use report::{
    Cause, Merged, ReadReport, ReportWriter, Row, Status, build_name, last_per_file, merge_reports,
    read_report, write_report,
};
pub use summary::{Extreme, Percentiles, Summary};
pub use thumbnail::{THUMB_PX, render_png as render_thumbnail};

use crate::{Error, Result};
use std::collections::HashSet;
use std::ffi::OsString;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// How to run a batch.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct BatchOptions {
    /// The triwild executable the children run (the CLI passes its own,
    /// `std::env::current_exe()`).
    pub exe: PathBuf,
    /// The single-file command's parameter and format flags, passed to every child.
    pub child_args: Vec<OsString>,
    /// Where meshes and the report go.
    pub out_dir: PathBuf,
    /// Children run at once. Default: the available parallelism.
    pub jobs: usize,
    /// Wall-time limit per file. Default 600 s.
    pub timeout: Duration,
    /// Memory limit per file. Default none.
    pub memory: MemoryGuard,
    /// Keep the ok rows of an existing report whose meshes exist; run the rest.
    pub resume: bool,
    /// Run only this slice of the sorted file list.
    pub shard: Option<Shard>,
    /// The flags recorded in each row (the single-file command's flags in
    /// `child_args`, without a launcher's leading arguments).
    pub flags: Vec<String>,
    /// Have each child write its mesh's SVG preview beside the mesh
    /// ([`preview_path`]), for the report page. Default on.
    pub previews: bool,
    /// Fill the previews' triangles by how their size matches the size field
    /// (the single-file command's `--preview-size`). Default off.
    pub preview_size: bool,
}

impl BatchOptions {
    /// The default time limit per file.
    pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(600);

    /// Defaults: no extra child flags, all cores, 600 s, no memory limit,
    /// no resume, no shard.
    pub fn new(exe: PathBuf, out_dir: PathBuf) -> Self {
        BatchOptions {
            exe,
            child_args: Vec::new(),
            out_dir,
            jobs: std::thread::available_parallelism().map_or(1, usize::from),
            timeout: Self::DEFAULT_TIMEOUT,
            memory: MemoryGuard::None,
            resume: false,
            shard: None,
            flags: Vec::new(),
            previews: true,
            preview_size: false,
        }
    }
    /// Set the flags passed to every child.
    pub fn with_child_args(mut self, args: Vec<OsString>) -> Self {
        self.child_args = args;
        self
    }
    /// Set the number of children at once (at least 1).
    pub fn with_jobs(mut self, jobs: usize) -> Self {
        self.jobs = jobs.max(1);
        self
    }
    /// Set the time limit per file.
    pub fn with_timeout(mut self, timeout: Duration) -> Self {
        self.timeout = timeout;
        self
    }
    /// Set the memory guard.
    pub fn with_memory(mut self, memory: MemoryGuard) -> Self {
        self.memory = memory;
        self
    }
    /// Resume from the existing report.
    pub fn with_resume(mut self, resume: bool) -> Self {
        self.resume = resume;
        self
    }
    /// Run one shard.
    pub fn with_shard(mut self, shard: Option<Shard>) -> Self {
        self.shard = shard;
        self
    }
    /// Set the flags recorded in each row.
    pub fn with_flags(mut self, flags: Vec<String>) -> Self {
        self.flags = flags;
        self
    }
    /// Write (or not) a preview beside each mesh.
    pub fn with_previews(mut self, previews: bool) -> Self {
        self.previews = previews;
        self
    }
    /// Shade the previews by edge length over the size field (or not).
    pub fn with_preview_size(mut self, on: bool) -> Self {
        self.preview_size = on;
        self
    }

    /// The report page's path: the report's with extension `.html`
    /// (`OUTDIR/report.html`, `OUTDIR/report.shard-K-of-N.html`).
    pub fn page_path(&self) -> PathBuf {
        self.report_path().with_extension("html")
    }

    /// The report's path: `OUTDIR/report.jsonl`, or
    /// `OUTDIR/report.shard-K-of-N.jsonl` for a shard (so the shards of a
    /// job array can share one output directory).
    pub fn report_path(&self) -> PathBuf {
        let name = match self.shard {
            None => "report.jsonl".to_string(),
            Some(s) => format!("report.shard-{}-of-{}.jsonl", s.k, s.n),
        };
        self.out_dir.join(name)
    }
}

/// What a batch will do.
#[derive(Clone, Debug)]
pub struct Plan {
    /// Files to mesh, sorted by key.
    pub todo: Vec<SourceFile>,
    /// Rows kept from the existing report (`--resume`), sorted by key.
    pub done: Vec<Row>,
    /// Files found before sharding.
    pub found: usize,
    /// The report path.
    pub report: PathBuf,
    /// Problems stepped over (unreadable directories, torn report lines).
    pub warnings: Vec<String>,
}

impl Plan {
    /// Files in this batch (or shard), done or not.
    pub fn total(&self) -> usize {
        self.todo.len() + self.done.len()
    }
}

/// Find the files under `inputs`, take the shard, and (with `resume`) read
/// the report to skip the files already done. Reads only; writes nothing.
///
/// # Errors
/// [`Error::Read`] for a missing input or an unreadable report;
/// [`Error::InvalidParams`] when no SVG file is found or two files would
/// write the same mesh.
pub fn plan(inputs: &[PathBuf], opts: &BatchOptions) -> Result<Plan> {
    let found = discover(inputs)?;
    if found.files.is_empty() {
        let list: Vec<String> = inputs.iter().map(|p| p.display().to_string()).collect();
        return Err(Error::InvalidParams(format!(
            "no .svg file found in {}",
            list.join(", ")
        )));
    }
    let files = match opts.shard {
        Some(s) => s.select(&found.files),
        None => found.files.clone(),
    };
    let mut plan = Plan {
        todo: Vec::new(),
        done: Vec::new(),
        found: found.files.len(),
        report: opts.report_path(),
        warnings: found.warnings,
    };
    if !opts.resume {
        plan.todo = files;
        return Ok(plan);
    }
    let old = read_report(&plan.report)?;
    if !old.bad_lines.is_empty() {
        plan.warnings.push(format!(
            "{}: skipped {} unreadable line(s) (a killed batch leaves one); their files run again",
            plan.report.display(),
            old.bad_lines.len()
        ));
    }
    let keys: HashSet<&str> = files.iter().map(|f| f.key.as_str()).collect();
    plan.done = last_per_file(old.rows)
        .into_iter()
        .filter(|r| {
            keys.contains(r.file.as_str())
                && r.status == Status::Ok
                && r.output
                    .as_ref()
                    .is_some_and(|o| opts.out_dir.join(o).is_file())
        })
        .collect();
    let done: HashSet<&str> = plan.done.iter().map(|r| r.file.as_str()).collect();
    plan.todo = files
        .iter()
        .filter(|f| !done.contains(f.key.as_str()))
        .cloned()
        .collect();
    Ok(plan)
}

/// What a batch did.
#[derive(Clone, Debug)]
pub struct BatchRun {
    /// One row per file of the plan (kept and new), sorted by key; after an
    /// [`interrupt`], the files not started have none.
    pub rows: Vec<Row>,
    /// Wall-clock time of the run, seconds.
    pub wall: f64,
}

impl BatchRun {
    /// The summary of the rows, with the run's wall time.
    pub fn summary(&self) -> Summary {
        Summary::of(&self.rows).with_batch_wall(self.wall)
    }
}

/// Run `plan`: mesh its files in `opts.jobs` children at once, append each
/// row to the report as it comes, and hand it to `on_row` (on the calling
/// thread, in completion order).
///
/// Without `resume` the report starts empty; with it, the report is first
/// rewritten (atomically) to hold exactly the kept rows.
///
/// # Errors
/// [`Error::Write`] if the output directory or the report cannot be
/// written; the batch stops starting new files then. A file's failure is
/// never an error: it is its row.
pub fn run(plan: &Plan, opts: &BatchOptions, on_row: &mut dyn FnMut(&Row)) -> Result<BatchRun> {
    let t0 = Instant::now();
    std::fs::create_dir_all(&opts.out_dir).map_err(|e| {
        Error::Write(std::io::Error::new(
            e.kind(),
            format!("{}: {e}", opts.out_dir.display()),
        ))
    })?;
    if opts.resume {
        write_report(&plan.report, &plan.done)?;
    }
    let mut writer = ReportWriter::open(&plan.report, !opts.resume)?;
    let spec = ChildSpec {
        exe: &opts.exe,
        args: &opts.child_args,
        timeout: opts.timeout,
        memory: &opts.memory,
        preview: opts.previews,
        preview_size: opts.preview_size,
    };
    let build = build_name();
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let mut rows = plan.done.clone();
    let mut failure = None;
    std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel::<Row>();
        for _ in 0..opts.jobs.clamp(1, plan.todo.len().max(1)) {
            let tx = tx.clone();
            let (spec, next, stop, build) = (&spec, &next, &stop, &build);
            s.spawn(move || {
                while !stop.load(Ordering::Relaxed) && interrupted().is_none() {
                    let Some(f) = plan.todo.get(next.fetch_add(1, Ordering::Relaxed)) else {
                        break;
                    };
                    let _span = tracing::info_span!("file", key = %f.key).entered();
                    let rel = f.output_rel();
                    let out = opts.out_dir.join(&rel);
                    let mut row = run_child(spec, &f.key, &f.path, &out, &rel);
                    row.flags.clone_from(&opts.flags);
                    row.build = Some(build.clone());
                    if tx.send(row).is_err() {
                        break;
                    }
                }
            });
        }
        drop(tx);
        for row in rx {
            if failure.is_none() {
                if let Err(e) = writer.append(&row) {
                    stop.store(true, Ordering::Relaxed);
                    failure = Some(e);
                }
            }
            on_row(&row);
            rows.push(row);
        }
    });
    if let Some(e) = failure {
        return Err(e);
    }
    rows.sort_by(|a, b| a.file.cmp(&b.file));
    Ok(BatchRun {
        rows,
        wall: t0.elapsed().as_secs_f64(),
    })
}
