//! `triwild report REPORT.jsonl... -o report.html`: the batch's report page
//! built again from reports (a batch's, or the shards' of a cluster run, which
//! are joined one row per file as `batch --merge-reports` joins them).

use crate::cli::console::{errln, outln};
use crate::exit_code;
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use triwild::batch::{self, PageOptions, PageStats};

/// `triwild report` arguments.
#[derive(Args, Debug, Clone)]
pub(crate) struct ReportArgs {
    /// Batch reports (report.jsonl, report.shard-K-of-N.jsonl, or a merged
    /// report); several are joined, one row per file, later ones winning.
    #[arg(required = true, value_name = "REPORT.jsonl")]
    reports: Vec<PathBuf>,
    /// The page to write.
    #[arg(short, long, value_name = "report.html")]
    output: PathBuf,
    /// The batch's output directory, where the meshes and their previews are
    /// [default: the first report's folder].
    #[arg(long, value_name = "OUTDIR")]
    meshes: Option<PathBuf>,
}

/// The line the batch and `triwild report` print about the page.
pub(crate) fn page_line(page: &Path, s: &PageStats) -> String {
    let missing = if s.missing_previews > 0 {
        format!(
            "; {} meshed file(s) without a preview (run with the page on to get them)",
            s.missing_previews
        )
    } else {
        String::new()
    };
    format!(
        "page: {} ({} files, {} thumbnails, {:.1} MB, {:.2} s){missing}",
        page.display(),
        s.files,
        s.thumbnails,
        s.bytes as f64 / 1e6,
        s.seconds
    )
}

/// Read the reports, write the page; exit 0 (a report without rows gives a
/// page that says so), 2 for a missing or unreadable report, 4 if the page
/// cannot be written.
pub(crate) fn run(args: &ReportArgs, quiet: bool) -> ExitCode {
    let mut rows = Vec::new();
    for r in &args.reports {
        if !r.is_file() {
            errln!("error: {}: no such report", r.display());
            return ExitCode::from(2);
        }
        match batch::read_report(r) {
            Ok(rep) => {
                if !quiet {
                    for l in &rep.bad_lines {
                        errln!("warning: {}:{l}: not a report row; skipped", r.display());
                    }
                }
                rows.extend(rep.rows);
            }
            Err(e) => {
                errln!("error: {e}");
                return ExitCode::from(2);
            }
        }
    }
    let out_dir = args.meshes.clone().unwrap_or_else(|| {
        args.reports[0]
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
    });
    let rows = batch::last_per_file(rows);
    match batch::write_page(&rows, &PageOptions::new(out_dir), &args.output) {
        Ok(s) => {
            outln!("{}", page_line(&args.output, &s));
            ExitCode::SUCCESS
        }
        Err(e) => {
            errln!("error: {e}");
            exit_code(e.kind())
        }
    }
}
