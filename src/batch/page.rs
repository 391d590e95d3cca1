//! The report page (`OUTDIR/report.html`): a collection at a glance, built
//! from the report's rows alone (and the previews beside the meshes), so
//! `triwild report` makes the same page again from a report, merged shard
//! reports included.
//!
//! What it holds: a headline (files, ok, failed by cause with the stage each
//! stopped in, time, triangles, the build and the flags), plots (see
//! [`super::plots`]), a gallery of every file (a thumbnail of its mesh with
//! name, time, triangles and worst angle; sortable, filterable by status and
//! folder), the slowest and worst files, every failure with its error, and a
//! section per file (the preview and the input drawing, linked, loaded when the
//! section is opened; its `--stats` figures, warnings and the command that
//! reproduces it).
//!
//! Guarantees: one self-contained file (inline CSS, script, plots and PNG
//! thumbnails; no network, no font, no external script), that renders for any
//! rows (none, one, all failed); every text from a report is HTML-escaped and
//! every link percent-encoded; the same rows and files give the same bytes.
//! The gallery cards carry each file's figures exactly (`data-wall` and the
//! others, Rust's shortest round-trip form), so a test can read them back.

use super::plots::{self, Axis};
use super::report::{Cause, Row, Status, last_per_file};
use super::summary::Percentiles;
use super::thumbnail;
use crate::{Error, Result};
use base64::Engine as _;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};
use std::time::Instant;

/// What the page is made from, besides the rows.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct PageOptions {
    /// The batch's output directory: the rows' meshes and previews are
    /// relative to it.
    pub out_dir: PathBuf,
    /// The longer side of a gallery thumbnail, pixels.
    pub thumb_px: u32,
    /// Rows in each "slowest" and "worst" table.
    pub top: usize,
}

impl PageOptions {
    /// Defaults: thumbnails of [`thumbnail::THUMB_PX`], tables of 25.
    pub fn new(out_dir: PathBuf) -> Self {
        PageOptions {
            out_dir,
            thumb_px: thumbnail::THUMB_PX,
            top: 25,
        }
    }
}

/// What [`write_page`] made.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PageStats {
    /// Files on the page.
    pub files: usize,
    /// Thumbnails drawn.
    pub thumbnails: usize,
    /// Meshed files whose preview was missing or unreadable (no thumbnail).
    pub missing_previews: usize,
    /// The page's size, bytes.
    pub bytes: u64,
    /// Time to build and write it, seconds.
    pub seconds: f64,
}

/// The preview a batch child writes beside its mesh: `x/y.msh` → `x/y.preview.svg`.
pub fn preview_path(mesh: &Path) -> PathBuf {
    mesh.with_extension("preview.svg")
}

/// Build the page of `rows` (one per file; later rows of a file win) and
/// write it at `html` (atomically).
///
/// # Errors
/// [`Error::Write`] if `html` cannot be written.
pub fn write_page(rows: &[Row], opts: &PageOptions, html: &Path) -> Result<PageStats> {
    let t0 = Instant::now();
    let dir = html
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let (text, mut stats) = render_page(rows, opts, dir);
    crate::output::write_file(html, text.as_bytes()).map_err(|e| match e {
        Error::Write(io) => Error::Write(std::io::Error::new(
            io.kind(),
            format!("{}: {io}", html.display()),
        )),
        other => other,
    })?;
    stats.bytes = text.len() as u64;
    stats.seconds = t0.elapsed().as_secs_f64();
    Ok(stats)
}

/// The page's HTML for `rows`, its links relative to `html_dir` (where the
/// page will be).
pub fn render_page(rows: &[Row], opts: &PageOptions, html_dir: &Path) -> (String, PageStats) {
    let rows = last_per_file(rows.iter().cloned());
    let entries: Vec<Entry> = rows
        .par_iter()
        .enumerate()
        .map(|(i, r)| Entry::of(i, r, opts, html_dir))
        .collect();
    let stats = PageStats {
        files: entries.len(),
        thumbnails: entries.iter().filter(|e| e.thumb.is_some()).count(),
        missing_previews: entries
            .iter()
            .filter(|e| e.row.status == Status::Ok && e.thumb.is_none())
            .count(),
        bytes: 0,
        seconds: 0.0,
    };
    let mut h = String::with_capacity(4096 + entries.len() * 8192);
    head(&mut h, &entries);
    headline(&mut h, &entries);
    plots_section(&mut h, &entries);
    gallery(&mut h, &entries);
    tables(&mut h, &entries, opts.top);
    file_sections(&mut h, &entries, opts);
    h.push_str("<script>");
    h.push_str(SCRIPT);
    h.push_str("</script>\n</body>\n</html>\n");
    (h, stats)
}

/// One file as the page shows it.
struct Entry<'a> {
    id: usize,
    row: &'a Row,
    folder: String,
    /// `ok`, or the cause's name.
    status: &'static str,
    triangles: Option<u64>,
    angle: Option<f64>,
    jacobian: Option<f64>,
    /// Peak memory, MiB.
    memory: Option<f64>,
    /// Input segments (lines, cubics and conics).
    segments: Option<f64>,
    stage: Option<String>,
    /// Base64 PNG.
    thumb: Option<String>,
    preview_link: Option<String>,
    input_link: String,
    mesh: PathBuf,
}

impl<'a> Entry<'a> {
    fn of(id: usize, row: &'a Row, opts: &PageOptions, html_dir: &Path) -> Self {
        let mesh =
            opts.out_dir.join(row.output.clone().unwrap_or_else(
                || match row.file.rsplit_once('.') {
                    Some((stem, _)) => format!("{stem}.msh"),
                    None => format!("{}.msh", row.file),
                },
            ));
        let preview = (row.status == Status::Ok).then(|| preview_path(&mesh));
        let thumb = preview
            .as_deref()
            .and_then(|p| thumbnail::render_png(p, opts.thumb_px))
            .map(|png| base64::engine::general_purpose::STANDARD.encode(png));
        let segments = ["lines", "cubics", "conics"]
            .iter()
            .map(|k| row.stat(&format!("/input/{k}")))
            .try_fold(0.0, |acc, v| v.map(|v| acc + v));
        Entry {
            id,
            row,
            folder: row
                .file
                .rsplit_once('/')
                .map_or(".".to_string(), |(d, _)| d.to_string()),
            status: match row.status {
                Status::Ok => "ok",
                Status::Failed => row.cause.unwrap_or(Cause::Internal).name(),
            },
            triangles: row.triangles(),
            angle: row.stat("/quality/min_angle_deg"),
            jacobian: row.stat("/quality/min_jacobian_ratio"),
            memory: row
                .peak_rss
                .map(|b| b as f64 / (1u64 << 20) as f64)
                .or_else(|| row.stat("/peak_memory_mb")),
            segments,
            stage: stage_of(row),
            thumb,
            preview_link: preview.map(|p| rel_link(html_dir, &p)),
            input_link: rel_link(html_dir, Path::new(&row.input)),
            mesh,
        }
    }
}

/// The stage a failed file stopped in, as far as its row tells: the stage an
/// error names (`in stage bsp`, `reached in curve`), `load` for bad input,
/// the source folder of a panic; `None` when it was stopped from outside
/// (timeout, memory, interrupted) or nothing says.
pub fn stage_of(row: &Row) -> Option<String> {
    if row.status == Status::Ok {
        return None;
    }
    let msg = row.message.as_deref().unwrap_or("");
    const STAGES: [&str; 6] = [
        "features", "bsp", "optimize", "curve", "baseline", "regions",
    ];
    for marker in ["in stage ", "reached in "] {
        if let Some(i) = msg.find(marker) {
            let rest = &msg[i + marker.len()..];
            if let Some(s) = STAGES.iter().find(|s| rest.starts_with(**s)) {
                return Some((*s).to_string());
            }
        }
    }
    match row.cause {
        Some(Cause::BadInput) => Some("load".into()),
        Some(Cause::Io) if msg.contains("cannot write") => Some("write".into()),
        Some(Cause::Io) => Some("load".into()),
        Some(Cause::Panic) => {
            let at = msg.find("panicked at src/")?;
            let module = msg[at + "panicked at src/".len()..]
                .split(['/', '.', ':'])
                .next()?;
            Some(
                match module {
                    "svg" => "load",
                    "ops" | "optimize" => "optimize",
                    "curve" | "element" => "curve",
                    "output" | "fem" => "write",
                    "features" | "bsp" | "baseline" | "regions" => module,
                    _ => return None,
                }
                .to_string(),
            )
        }
        _ => None,
    }
}

/// `s` escaped for HTML text and attribute values.
pub(crate) fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// A path as a relative URL: every byte but unreserved ones and `/`
/// percent-encoded.
fn url(path: &str) -> String {
    let mut o = String::with_capacity(path.len());
    for b in path.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            o.push(b as char);
        } else {
            let _ = write!(o, "%{b:02X}");
        }
    }
    o
}

/// `p` made absolute (against the working directory) with `.` and `..` removed.
fn normal(p: &Path) -> Option<Vec<String>> {
    let abs = std::path::absolute(p).ok()?;
    let mut parts: Vec<String> = Vec::new();
    for c in abs.components() {
        match c {
            Component::Normal(s) => parts.push(s.to_string_lossy().into_owned()),
            Component::ParentDir => {
                parts.pop();
            }
            Component::Prefix(p) => parts.push(p.as_os_str().to_string_lossy().into_owned()),
            Component::RootDir | Component::CurDir => {}
        }
    }
    Some(parts)
}

/// `p` as an absolute path without `.` and `..` (as given when that fails):
/// the same text however the output directory was spelled.
fn absolute(p: &Path) -> String {
    match normal(p) {
        Some(parts) if cfg!(unix) => format!("/{}", parts.join("/")),
        _ => p.to_string_lossy().into_owned(),
    }
}

/// The URL of `target` relative to the folder `from` (both taken against the
/// working directory).
fn rel_link(from: &Path, target: &Path) -> String {
    let (Some(a), Some(b)) = (normal(from), normal(target)) else {
        return url(&target.to_string_lossy());
    };
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut parts: Vec<&str> = vec![".."; a.len() - common];
    parts.extend(b[common..].iter().map(String::as_str));
    url(&parts.join("/"))
}

/// A shell word: quoted when it holds anything but safe characters.
fn shell_word(s: &str) -> String {
    if !s.is_empty()
        && s.bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"-_./=:,+@%".contains(&b))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// Seconds, shown.
fn secs(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0} s")
    } else if v >= 1.0 {
        format!("{v:.2} s")
    } else {
        format!("{v:.3} s")
    }
}

fn opt(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map_or_else(|| "—".to_string(), f)
}

fn deg(v: f64) -> String {
    format!("{v:.2}°")
}

fn ratio(v: f64) -> String {
    format!("{v:.4}")
}

fn mib(v: f64) -> String {
    format!("{v:.0} MiB")
}

/// An exact data attribute (empty when absent).
fn data(v: Option<f64>) -> String {
    v.map_or_else(String::new, |v| format!("{v}"))
}

fn head(h: &mut String, entries: &[Entry<'_>]) {
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <meta name=\"generator\" content=\"triwild {}\">\n\
         <title>triwild batch: {} files</title>\n<style>{STYLE}</style>\n</head>\n<body>",
        env!("CARGO_PKG_VERSION"),
        entries.len()
    );
}

fn headline(h: &mut String, entries: &[Entry<'_>]) {
    let ok = entries
        .iter()
        .filter(|e| e.row.status == Status::Ok)
        .count();
    let failed = entries.len() - ok;
    let wall = Percentiles::of(entries.iter().map(|e| e.row.wall).collect());
    let tris: u64 = entries.iter().filter_map(|e| e.triangles).sum();
    let tri_p = Percentiles::of(
        entries
            .iter()
            .filter_map(|e| e.triangles.map(|t| t as f64))
            .collect(),
    );
    let worst = |f: fn(&Entry<'_>) -> Option<f64>| {
        entries
            .iter()
            .filter_map(|e| f(e).filter(|v| v.is_finite()).map(|v| (v, e)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    };
    h.push_str("<header><h1>triwild batch</h1><nav><a href=\"#plots\">plots</a> <a href=\"#gallery\">gallery</a> <a href=\"#tables\">tables</a> <a href=\"#failures\">failures</a></nav></header>\n<section id=\"headline\" class=\"cards\">\n");
    let _ = write!(
        h,
        "<div class=\"card-n\"><span class=\"big\" id=\"n-files\">{}</span>files</div>\
         <div class=\"card-n ok\"><span class=\"big\" id=\"n-ok\">{ok}</span>ok{}</div>\
         <div class=\"card-n bad\"><span class=\"big\" id=\"n-failed\">{failed}</span>failed</div>",
        entries.len(),
        if entries.is_empty() {
            String::new()
        } else {
            format!(" ({:.1} %)", 100.0 * ok as f64 / entries.len() as f64)
        }
    );
    match wall {
        Some(p) => {
            let _ = write!(
                h,
                "<div class=\"card-n\"><span class=\"big\" id=\"n-time\" data-v=\"{}\">{}</span>time, summed over files<br>median {} · p90 {} · max {}</div>",
                p.sum,
                secs(p.sum),
                secs(p.p50),
                secs(p.p90),
                secs(p.max)
            );
        }
        None => h.push_str("<div class=\"card-n\"><span class=\"big\">—</span>time</div>"),
    }
    let _ = write!(
        h,
        "<div class=\"card-n\"><span class=\"big\" id=\"n-triangles\" data-v=\"{tris}\">{tris}</span>triangles{}</div>",
        tri_p.map_or(String::new(), |p| format!(
            "<br>median {:.0} · max {:.0}",
            p.p50, p.max
        ))
    );
    if let Some((v, e)) = worst(|e| e.angle) {
        let _ = write!(
            h,
            "<div class=\"card-n\"><span class=\"big\" id=\"n-worst-angle\" data-v=\"{v}\">{}</span>worst min angle<br><a href=\"#f-{}\">{}</a></div>",
            deg(v),
            e.id,
            esc(&e.row.file)
        );
    }
    if let Some((v, e)) = worst(|e| e.jacobian) {
        let _ = write!(
            h,
            "<div class=\"card-n\"><span class=\"big\" id=\"n-worst-jacobian\" data-v=\"{v}\">{}</span>worst min Jacobian ratio<br><a href=\"#f-{}\">{}</a></div>",
            ratio(v),
            e.id,
            esc(&e.row.file)
        );
    }
    h.push_str("</section>\n");

    // failures by cause, with the stages they stopped in
    let mut by_cause: BTreeMap<Cause, (usize, BTreeMap<String, usize>)> = BTreeMap::new();
    for e in entries.iter().filter(|e| e.row.status == Status::Failed) {
        let slot = by_cause
            .entry(e.row.cause.unwrap_or(Cause::Internal))
            .or_default();
        slot.0 += 1;
        *slot
            .1
            .entry(e.stage.clone().unwrap_or_else(|| "unknown".into()))
            .or_default() += 1;
    }
    h.push_str("<section id=\"causes\"><h2>Failures by cause</h2>");
    if by_cause.is_empty() {
        h.push_str("<p id=\"no-failures\">No file failed.</p>");
    } else {
        h.push_str("<table class=\"t\"><thead><tr><th>cause</th><th>files</th><th>stage stopped in</th></tr></thead><tbody>");
        for c in Cause::ALL {
            if let Some((n, stages)) = by_cause.get(&c) {
                let st: Vec<String> = stages
                    .iter()
                    .map(|(s, k)| format!("{} × {k}", esc(s)))
                    .collect();
                let _ = write!(
                    h,
                    "<tr><td>{}<br><small>{}</small></td><td class=\"num\" id=\"n-cause-{}\">{n}</td><td>{}</td></tr>",
                    c.name(),
                    cause_text(c),
                    c.name(),
                    st.join(", ")
                );
            }
        }
        h.push_str("</tbody></table>");
    }
    h.push_str("</section>\n");

    // build and options
    let mut builds: BTreeMap<String, usize> = BTreeMap::new();
    let mut flags: BTreeMap<String, usize> = BTreeMap::new();
    let mut meshers: BTreeMap<String, usize> = BTreeMap::new();
    for e in entries {
        *builds
            .entry(e.row.build.clone().unwrap_or_else(|| "not recorded".into()))
            .or_default() += 1;
        let f: Vec<String> = e.row.flags.iter().map(|a| shell_word(a)).collect();
        *flags
            .entry(if e.row.flags.is_empty() {
                "(none recorded)".into()
            } else {
                f.join(" ")
            })
            .or_default() += 1;
        if let Some(m) = e
            .row
            .stats
            .as_ref()
            .and_then(|s| s.get("mesher"))
            .and_then(|m| m.as_str())
        {
            *meshers.entry(m.to_string()).or_default() += 1;
        }
    }
    let list = |m: &BTreeMap<String, usize>| -> String {
        m.iter()
            .map(|(k, n)| format!("<code>{}</code> ({n} files)", esc(k)))
            .collect::<Vec<_>>()
            .join("<br>")
    };
    let _ = writeln!(
        h,
        "<section id=\"run\"><h2>Build and options</h2><table class=\"kv\">\
         <tr><th>build</th><td>{}</td></tr><tr><th>flags</th><td>{}</td></tr>\
         <tr><th>mesher</th><td>{}</td></tr><tr><th>page</th><td>made by triwild {} from {} report rows</td></tr></table></section>",
        list(&builds),
        list(&flags),
        if meshers.is_empty() {
            "—".into()
        } else {
            list(&meshers)
        },
        env!("CARGO_PKG_VERSION"),
        entries.len()
    );
}

/// What a cause means, in a few words.
fn cause_text(c: Cause) -> &'static str {
    match c {
        Cause::BadInput => "bad input",
        Cause::Meshing => "meshing failed (or --time-limit)",
        Cause::Io => "reading or writing failed",
        Cause::Panic => "a panic: a triwild bug",
        Cause::Crash => "crashed (signal or unknown exit)",
        Cause::Timeout => "time limit (--timeout)",
        Cause::Memory => "memory limit (--max-memory)",
        Cause::Internal => "the batch could not run it",
        Cause::Interrupted => "interrupted (SIGINT / SIGTERM)",
    }
}

fn plots_section(h: &mut String, entries: &[Entry<'_>]) {
    let ok: Vec<&Entry<'_>> = entries
        .iter()
        .filter(|e| e.row.status == Status::Ok)
        .collect();
    let col =
        |f: fn(&Entry<'_>) -> Option<f64>| -> Vec<f64> { ok.iter().filter_map(|e| f(e)).collect() };
    let times: Vec<f64> = entries.iter().map(|e| e.row.wall).collect();
    let size_time: Vec<(f64, f64)> = ok
        .iter()
        .filter_map(|e| Some((e.segments?, e.row.wall)))
        .collect();
    let size_tris: Vec<(f64, f64)> = ok
        .iter()
        .filter_map(|e| Some((e.segments?, e.triangles? as f64)))
        .collect();
    let fit = plots::fit(&size_time);
    h.push_str("<section id=\"plots\"><h2>Plots</h2><div class=\"plots\">\n");
    let figs = [
        plots::histogram("Time per file (all files)", "seconds", &times, Axis::Log),
        plots::histogram(
            "Triangles per mesh",
            "triangles",
            &col(|e| e.triangles.map(|t| t as f64)),
            Axis::Log,
        ),
        plots::histogram(
            "Minimum angle per mesh",
            "degrees",
            &col(|e| e.angle),
            Axis::Fixed(0.0, 60.0),
        ),
        plots::histogram(
            "Minimum Jacobian ratio per mesh",
            "min det J / max det J",
            &col(|e| e.jacobian),
            Axis::Fixed(0.0, 1.0),
        ),
        plots::histogram(
            "Peak memory per file",
            "MiB",
            &entries.iter().filter_map(|e| e.memory).collect::<Vec<_>>(),
            Axis::Log,
        ),
        plots::scatter(
            "Time against input size",
            "input segments",
            "seconds",
            &size_time,
            true,
        ),
        plots::scatter(
            "Triangles against input size",
            "input segments",
            "triangles",
            &size_tris,
            false,
        ),
    ];
    for f in figs {
        let _ = writeln!(h, "<figure class=\"plot\">{f}</figure>");
    }
    h.push_str("</div>");
    let _ = write!(
        h,
        "<p id=\"fit\">Time against input size (meshed files, segments = lines + cubics + conics): {}</p>",
        fit.map_or_else(
            || "too few sizes to fit an exponent.".to_string(),
            |f| format!(
                "time ∝ segments<sup><span id=\"n-exponent\" data-v=\"{}\">{:.2}</span></sup> (least squares on log-log).",
                f.k, f.k
            )
        )
    );
    let buckets = plots::buckets(&size_time);
    if !buckets.is_empty() {
        h.push_str("<table class=\"t small\"><thead><tr><th>segments</th><th>files</th><th>median time</th><th>p95 time</th></tr></thead><tbody>");
        for b in &buckets {
            let _ = write!(
                h,
                "<tr><td>{:.0} – {:.0}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td></tr>",
                b.from,
                2.0 * b.from - 1.0,
                b.count,
                secs(b.median),
                secs(b.p95)
            );
        }
        h.push_str("</tbody></table>");
    }
    h.push_str("</section>\n");
}

fn gallery(h: &mut String, entries: &[Entry<'_>]) {
    let mut folders: BTreeMap<&str, usize> = BTreeMap::new();
    let mut statuses: BTreeMap<&str, usize> = BTreeMap::new();
    for e in entries {
        *folders.entry(e.folder.as_str()).or_default() += 1;
        *statuses.entry(e.status).or_default() += 1;
    }
    h.push_str("<section id=\"gallery\"><h2>Gallery</h2><div class=\"controls\">\
        <label>sort <select id=\"sort\"><option value=\"file\">name</option><option value=\"wall\">time</option>\
        <option value=\"tris\">triangles</option><option value=\"angle\">worst angle</option>\
        <option value=\"jac\">min Jacobian ratio</option><option value=\"mem\">peak memory</option></select></label>\
        <select id=\"dir\"><option value=\"asc\">ascending</option><option value=\"desc\">descending</option></select>\
        <label>status <select id=\"status\"><option value=\"\">all</option>");
    for (s, n) in &statuses {
        let _ = write!(h, "<option value=\"{s}\">{s} ({n})</option>");
    }
    h.push_str(
        "</select></label><label>folder <select id=\"folder\"><option value=\"\">all</option>",
    );
    for (f, n) in &folders {
        let _ = write!(h, "<option value=\"{0}\">{0} ({n})</option>", esc(f));
    }
    h.push_str("</select></label><label>name <input id=\"q\" type=\"search\" placeholder=\"filter\"></label> <span id=\"shown\"></span></div>\n<div id=\"grid\">\n");
    for e in entries {
        let _ = write!(
            h,
            "<a class=\"card {}\" href=\"#f-{}\" data-file=\"{}\" data-folder=\"{}\" data-status=\"{}\" data-wall=\"{}\" data-tris=\"{}\" data-angle=\"{}\" data-jac=\"{}\" data-mem=\"{}\">",
            if e.row.status == Status::Ok {
                "ok"
            } else {
                "failed"
            },
            e.id,
            esc(&e.row.file),
            esc(&e.folder),
            e.status,
            e.row.wall,
            e.triangles.map_or_else(String::new, |t| t.to_string()),
            data(e.angle),
            data(e.jacobian),
            data(e.memory),
        );
        match &e.thumb {
            Some(b64) => {
                let _ = write!(
                    h,
                    "<img class=\"thumb\" alt=\"\" src=\"data:image/png;base64,{b64}\">"
                );
            }
            None if e.row.status == Status::Ok => {
                h.push_str("<span class=\"thumb none\">no preview</span>");
            }
            None => {
                let _ = write!(h, "<span class=\"thumb none\">{}</span>", e.status);
            }
        }
        let meta = match e.row.status {
            Status::Ok => format!(
                "{} · {} ▲ · {}",
                secs(e.row.wall),
                e.triangles.map_or("—".into(), |t| t.to_string()),
                opt(e.angle, deg)
            ),
            Status::Failed => format!(
                "{} · {}{}",
                secs(e.row.wall),
                e.status,
                e.stage
                    .as_deref()
                    .map_or(String::new(), |s| format!(" in {s}"))
            ),
        };
        let _ = writeln!(
            h,
            "<span class=\"name\" title=\"{}\">{}</span><span class=\"meta\">{}</span></a>",
            esc(&e.row.file),
            esc(e
                .row
                .file
                .rsplit_once('/')
                .map_or(e.row.file.as_str(), |(_, n)| n)),
            esc(&meta)
        );
    }
    h.push_str("</div></section>\n");
}

fn table_rows<'e>(
    h: &mut String,
    id: &str,
    title: &str,
    rows: &[&'e Entry<'e>],
    empty: &str,
    failures: bool,
) {
    let _ = write!(h, "<div class=\"tbl\" id=\"{id}\"><h3>{}</h3>", esc(title));
    if rows.is_empty() {
        let _ = write!(h, "<p>{}</p></div>", esc(empty));
        return;
    }
    h.push_str("<table class=\"t\"><thead><tr><th>#</th><th>file</th>");
    if failures {
        h.push_str("<th>cause</th><th>stage</th><th>time</th><th>error</th>");
    } else {
        h.push_str("<th>status</th><th>time</th><th>triangles</th><th>min angle</th><th>min Jacobian ratio</th><th>peak memory</th>");
    }
    h.push_str("</tr></thead><tbody>");
    for (i, e) in rows.iter().enumerate() {
        let _ = write!(
            h,
            "<tr><td class=\"num\">{}</td><td><a href=\"#f-{}\">{}</a></td>",
            i + 1,
            e.id,
            esc(&e.row.file)
        );
        if failures {
            let _ = write!(
                h,
                "<td>{}</td><td>{}</td><td class=\"num\">{}</td><td class=\"msg\">{}</td></tr>",
                e.status,
                esc(e.stage.as_deref().unwrap_or("unknown")),
                secs(e.row.wall),
                esc(e.row.message.as_deref().unwrap_or(""))
            );
        } else {
            let _ = write!(
                h,
                "<td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td></tr>",
                e.status,
                secs(e.row.wall),
                e.triangles.map_or("—".into(), |t| t.to_string()),
                opt(e.angle, deg),
                opt(e.jacobian, ratio),
                opt(e.memory, mib)
            );
        }
    }
    h.push_str("</tbody></table></div>");
}

fn tables(h: &mut String, entries: &[Entry<'_>], top: usize) {
    let worst_by = |f: fn(&Entry<'_>) -> Option<f64>| {
        let mut v: Vec<&Entry<'_>> = entries
            .iter()
            .filter(|e| f(e).is_some_and(f64::is_finite))
            .collect();
        v.sort_by(|a, b| {
            f(a).unwrap_or(0.0)
                .total_cmp(&f(b).unwrap_or(0.0))
                .then(a.id.cmp(&b.id))
        });
        v.truncate(top);
        v
    };
    let mut slow: Vec<&Entry<'_>> = entries.iter().collect();
    slow.sort_by(|a, b| b.row.wall.total_cmp(&a.row.wall).then(a.id.cmp(&b.id)));
    slow.truncate(top);
    h.push_str("<section id=\"tables\"><h2>Slowest and worst</h2>");
    table_rows(
        h,
        "slowest",
        &format!("The {top} slowest files"),
        &slow,
        "No file.",
        false,
    );
    table_rows(
        h,
        "worst-angle",
        &format!("The {top} worst meshes by minimum angle"),
        &worst_by(|e| e.angle),
        "No mesh.",
        false,
    );
    table_rows(
        h,
        "worst-jacobian",
        &format!("The {top} worst meshes by minimum Jacobian ratio"),
        &worst_by(|e| e.jacobian),
        "No mesh.",
        false,
    );
    let area: Vec<&Entry<'_>> = entries
        .iter()
        .filter(|e| {
            e.row
                .stats
                .as_ref()
                .and_then(|s| s.get("warnings"))
                .and_then(|w| w.as_array())
                .is_some_and(|a| {
                    a.iter()
                        .filter_map(|w| w.as_str())
                        .any(|w| w.contains(crate::regions::AREA_WARNING))
                })
        })
        .collect();
    table_rows(
        h,
        "area-check",
        &format!(
            "{} files whose regions {} (the warning in each file's section)",
            area.len(),
            crate::regions::AREA_WARNING
        ),
        &area,
        "Every region has its drawn area.",
        false,
    );
    h.push_str("</section>\n<section id=\"failures\"><h2>Failures</h2>");
    let failed: Vec<&Entry<'_>> = entries
        .iter()
        .filter(|e| e.row.status == Status::Failed)
        .collect();
    table_rows(
        h,
        "failure-list",
        &format!("All {} failed files", failed.len()),
        &failed,
        "No file failed.",
        true,
    );
    h.push_str("</section>\n");
}

/// The `--stats` object as `path = value` lines (arrays and long values
/// shortened), warnings left out (they are listed on their own).
fn flatten(prefix: &str, v: &serde_json::Value, out: &mut Vec<(String, String)>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                if prefix.is_empty() && k == "warnings" {
                    continue;
                }
                let p = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&p, x, out);
            }
        }
        serde_json::Value::Number(n) => {
            let s = match n.as_f64() {
                Some(f) if n.is_f64() => {
                    let t = format!("{f:.6}");
                    let t = t.trim_end_matches('0').trim_end_matches('.');
                    if t.is_empty() || t == "-" {
                        "0".into()
                    } else {
                        t.to_string()
                    }
                }
                _ => n.to_string(),
            };
            out.push((prefix.to_string(), s));
        }
        other => {
            let mut s = match other {
                serde_json::Value::String(s) => s.clone(),
                _ => other.to_string(),
            };
            if s.len() > 300 {
                let mut cut = 300;
                while !s.is_char_boundary(cut) {
                    cut -= 1;
                }
                s.truncate(cut);
                s.push('…');
            }
            out.push((prefix.to_string(), s));
        }
    }
}

fn file_sections(h: &mut String, entries: &[Entry<'_>], opts: &PageOptions) {
    h.push_str("<div id=\"files\">\n");
    for e in entries {
        let r = e.row;
        let _ = write!(
            h,
            "<section class=\"file\" id=\"f-{}\"><div class=\"sheet\"><a class=\"close\" href=\"#gallery\">× close</a>\
             <h2>{}</h2><p class=\"st {}\">{}",
            e.id,
            esc(&r.file),
            if r.status == Status::Ok {
                "ok"
            } else {
                "failed"
            },
            e.status
        );
        if r.status == Status::Failed {
            let _ = write!(
                h,
                " — stage {}: {}",
                esc(e.stage.as_deref().unwrap_or("unknown")),
                esc(r.message.as_deref().unwrap_or(""))
            );
        }
        let _ = write!(
            h,
            " · {} · {} triangles · min angle {} · min Jacobian ratio {} · peak memory {}</p><div class=\"pics\">",
            secs(r.wall),
            e.triangles.map_or("—".into(), |t| t.to_string()),
            opt(e.angle, deg),
            opt(e.jacobian, ratio),
            opt(e.memory, mib)
        );
        match &e.preview_link {
            Some(link) => {
                let _ = write!(
                    h,
                    "<figure><img data-src=\"{link}\" alt=\"preview not found: {0}\"><figcaption>mesh preview (<a href=\"{link}\">{0}</a>)</figcaption></figure>",
                    esc(&link_text(link))
                );
            }
            None => h.push_str("<figure><div class=\"thumb none big\">no mesh</div><figcaption>mesh preview</figcaption></figure>"),
        }
        let _ = write!(
            h,
            "<figure><img data-src=\"{0}\" alt=\"input not found: {1}\"><figcaption>input drawing (<a href=\"{0}\">{1}</a>)</figcaption></figure></div>",
            e.input_link,
            esc(&r.input)
        );
        let warnings: Vec<&str> = r
            .stats
            .as_ref()
            .and_then(|s| s.get("warnings"))
            .and_then(|w| w.as_array())
            .map(|a| a.iter().filter_map(|w| w.as_str()).collect())
            .unwrap_or_default();
        if !warnings.is_empty() {
            h.push_str("<h3>Warnings</h3><ul class=\"warn\">");
            for w in warnings {
                let _ = write!(h, "<li>{}</li>", esc(w));
            }
            h.push_str("</ul>");
        }
        let mut cmd = vec!["triwild".to_string()];
        cmd.extend(r.flags.iter().map(|f| shell_word(f)));
        cmd.push("-o".into());
        cmd.push(shell_word(&absolute(&e.mesh)));
        cmd.push("--stats".into());
        cmd.push("--".into());
        cmd.push(shell_word(&r.input));
        let _ = write!(
            h,
            "<h3>Reproduce</h3><pre class=\"cmd\">{}</pre>",
            esc(&cmd.join(" "))
        );
        if let Some(stats) = &r.stats {
            time_tables(h, stats);
            let mut kv = Vec::new();
            flatten("", stats, &mut kv);
            // the phases have their table above
            kv.retain(|(k, _)| !k.starts_with("optimize.phases"));
            // one line per top-level group: `curve  k v · k v · ...`
            let mut groups: Vec<(String, Vec<String>)> = Vec::new();
            for (k, v) in kv {
                let (g, rest) = k.split_once('.').unwrap_or((k.as_str(), ""));
                let item = if rest.is_empty() {
                    esc(&v)
                } else {
                    format!("{} <b>{}</b>", esc(rest), esc(&v))
                };
                match groups.last_mut() {
                    Some((last, items)) if last == g => items.push(item),
                    _ => groups.push((g.to_string(), vec![item])),
                }
            }
            h.push_str("<h3>--stats figures</h3><table class=\"kv stats\">");
            for (g, items) in groups {
                let _ = write!(
                    h,
                    "<tr><th>{}</th><td>{}</td></tr>",
                    esc(&g),
                    items.join(" · ")
                );
            }
            h.push_str("</table>");
        }
        let _ = writeln!(
            h,
            "<p class=\"small\">exit code {} · signal {} · mesh {}</p></div></section>",
            r.exit_code.map_or("—".into(), |c| c.to_string()),
            r.signal.map_or("—".into(), |s| s.to_string()),
            esc(&r
                .output
                .as_deref()
                .map_or_else(|| "none".to_string(), |o| absolute(&opts.out_dir.join(o))))
        );
    }
    h.push_str("</div>\n");
}

/// A file's "Where the time went": its stages' seconds (`times`), then the
/// optimizer's phases (`optimize.phases`: seconds, queues, items queued,
/// operations applied and refused, triangles after), when the stats have them.
fn time_tables(h: &mut String, stats: &serde_json::Value) {
    let num = |v: &serde_json::Value, k: &str| v.get(k).and_then(|x| x.as_f64());
    let stages: Vec<(&String, f64)> = stats
        .get("times")
        .and_then(|t| t.as_object())
        .map(|t| {
            t.iter()
                .filter(|(k, _)| k.as_str() != "total")
                .filter_map(|(k, v)| Some((k, v.as_f64()?)))
                .collect()
        })
        .unwrap_or_default();
    let phases: &[serde_json::Value] = stats
        .pointer("/optimize/phases")
        .and_then(|p| p.as_array())
        .map_or(&[], |a| a.as_slice());
    if stages.is_empty() && phases.is_empty() {
        return;
    }
    h.push_str("<h3>Where the time went</h3>");
    if !stages.is_empty() {
        let total: f64 = stages.iter().map(|s| s.1).sum::<f64>().max(1e-12);
        h.push_str("<table class=\"t time\"><thead><tr><th>stage</th><th>seconds</th><th>share</th></tr></thead><tbody>");
        let mut sorted = stages;
        sorted.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(b.0)));
        for (k, s) in sorted {
            let _ = write!(
                h,
                "<tr><td>{}</td><td>{s:.3}</td><td>{:.0} %</td></tr>",
                esc(k),
                100.0 * s / total
            );
        }
        h.push_str("</tbody></table>");
    }
    if !phases.is_empty() {
        h.push_str("<table class=\"t phases\"><thead><tr><th>optimizer phase</th><th>seconds</th><th>queues</th><th>queued</th><th>largest queue</th><th>applied</th><th>refused</th><th>triangles after</th></tr></thead><tbody>");
        for p in phases {
            let cell = |k: &str| num(p, k).map_or("—".into(), |v| format!("{v:.0}"));
            let _ = write!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                esc(p.get("phase").and_then(|x| x.as_str()).unwrap_or("?")),
                num(p, "seconds").map_or("—".into(), |v| format!("{v:.3}")),
                cell("queues"),
                cell("queued"),
                cell("largest_queue"),
                cell("applied"),
                cell("refused"),
                cell("triangles")
            );
        }
        h.push_str("</tbody></table>");
    }
}

/// A link shown as text: its percent-encoding undone where it is ASCII.
fn link_text(link: &str) -> String {
    let b = link.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Ok(v) = u8::from_str_radix(&link[i + 1..i + 3], 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

const STYLE: &str = r#"
body{font:14px/1.4 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0;color:#222;background:#f4f5f7}
header{background:#1f2d3d;color:#fff;padding:10px 20px;display:flex;align-items:baseline;gap:24px}
header h1{margin:0;font-size:20px}header a{color:#cde}
section{padding:8px 20px}h2{margin:14px 0 8px;font-size:18px}h3{font-size:15px;margin:12px 0 6px}
.cards{display:flex;flex-wrap:wrap;gap:10px}
.card-n{background:#fff;border-radius:6px;padding:8px 14px;min-width:120px;box-shadow:0 1px 2px #0002}
.card-n .big{display:block;font-size:24px;font-weight:600}.card-n.ok .big{color:#1a7f37}.card-n.bad .big{color:#b42318}
table.t{border-collapse:collapse;background:#fff;font-size:13px}
table.t th,table.t td{border-bottom:1px solid #e3e5e8;padding:3px 8px;text-align:left;vertical-align:top}
td.num{text-align:right;font-variant-numeric:tabular-nums}td.msg{max-width:640px;word-break:break-word}
table.kv th{text-align:left;padding-right:12px;font-weight:500;color:#555}table.kv td{word-break:break-all}
.plots{display:flex;flex-wrap:wrap;gap:10px}.plot{margin:0;background:#fff;box-shadow:0 1px 2px #0002}
.noplot{width:440px;height:120px;display:flex;flex-direction:column;align-items:center;justify-content:center;background:#fff;color:#777}
.controls{display:flex;flex-wrap:wrap;gap:12px;align-items:center;margin-bottom:8px}
#grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(150px,1fr));gap:8px}
a.card{display:flex;flex-direction:column;align-items:center;background:#fff;border-radius:6px;padding:6px;text-decoration:none;color:#222;box-shadow:0 1px 2px #0002;min-width:0}
a.card:hover{outline:2px solid #3168b5}a.card.failed{background:#fdecea}a.card[hidden]{display:none}
.thumb{width:128px;height:128px;object-fit:contain}.thumb.none{display:flex;align-items:center;justify-content:center;color:#b42318;font-weight:600;background:#fff5f4}
.thumb.big{width:320px;height:200px}
.name{font-size:12px;max-width:100%;overflow:hidden;text-overflow:ellipsis;white-space:nowrap}.meta{font-size:11px;color:#555}
.tbl{display:inline-block;vertical-align:top;margin:0 16px 12px 0}
.file{display:none}.file:target{display:block;position:fixed;inset:0;background:#0008;overflow:auto;z-index:10;padding:20px}
.sheet{background:#fff;border-radius:8px;padding:12px 20px;max-width:1200px;margin:0 auto}
.close{float:right}.pics{display:flex;flex-wrap:wrap;gap:16px}.pics figure{margin:0}
.pics img{width:min(540px,44vw);max-height:640px;object-fit:contain;border:1px solid #ddd;background:#fff}
pre.cmd{background:#f0f2f4;padding:8px;white-space:pre-wrap;word-break:break-all}
.st.ok{color:#1a7f37}.st.failed{color:#b42318}.small{font-size:12px;color:#666}ul.warn li{color:#8a5a00}
"#;

const SCRIPT: &str = r#"
(function(){
  var grid=document.getElementById('grid');
  var cards=Array.prototype.slice.call(grid.children);
  var sortSel=document.getElementById('sort'),dirSel=document.getElementById('dir'),
      stSel=document.getElementById('status'),foSel=document.getElementById('folder'),
      q=document.getElementById('q'),shown=document.getElementById('shown');
  function num(c,k){var v=c.getAttribute('data-'+k);return v===null||v===''?NaN:parseFloat(v);}
  function byName(a,b){var x=a.getAttribute('data-file'),y=b.getAttribute('data-file');return x<y?-1:x>y?1:0;}
  function apply(){
    var k=sortSel.value,d=dirSel.value==='desc'?-1:1;
    var sorted=cards.slice().sort(function(a,b){
      if(k==='file'){return d*byName(a,b);}
      var x=num(a,k),y=num(b,k);
      if(isNaN(x)&&isNaN(y)){return byName(a,b);}
      if(isNaN(x)){return 1;} if(isNaN(y)){return -1;}
      return d*(x-y)||byName(a,b);
    });
    var s=stSel.value,f=foSel.value,t=q.value.toLowerCase(),n=0;
    sorted.forEach(function(c){
      var ok=(s===''||c.getAttribute('data-status')===s)&&(f===''||c.getAttribute('data-folder')===f)
        &&(t===''||c.getAttribute('data-file').toLowerCase().indexOf(t)>=0);
      c.hidden=!ok; if(ok){n++;} grid.appendChild(c);
    });
    shown.textContent=n+' of '+cards.length+' shown';
  }
  [sortSel,dirSel,stSel,foSel].forEach(function(e){e.addEventListener('change',apply);});
  q.addEventListener('input',apply);
  function open(){
    var id=decodeURIComponent(location.hash.slice(1)),s=id&&document.getElementById(id);
    if(s&&s.classList.contains('file')){
      s.querySelectorAll('img[data-src]').forEach(function(i){i.src=i.getAttribute('data-src');i.removeAttribute('data-src');});
    }
  }
  window.addEventListener('hashchange',open);
  open(); apply();
})();
"#;

#[cfg(test)]
mod tests {
    use super::*;

    fn row(file: &str, cause: Option<Cause>, message: &str) -> Row {
        Row {
            file: file.into(),
            input: format!("in/{file}"),
            status: if cause.is_some() {
                Status::Failed
            } else {
                Status::Ok
            },
            cause,
            message: cause.map(|_| message.to_string()),
            exit_code: None,
            signal: None,
            output: cause.is_none().then(|| file.replace(".svg", ".msh")),
            wall: 0.25,
            peak_rss: Some(50 << 20),
            stats: cause.is_none().then(|| {
                serde_json::json!({"input": {"lines": 10, "cubics": 4, "conics": 0},
                    "output": {"triangles": 120}, "mesher": "tri-wild",
                    "quality": {"min_angle_deg": 21.5, "min_jacobian_ratio": 0.75},
                    "warnings": ["a <warning> & more"]})
            }),
            flags: vec!["-l".into(), "0.05".into()],
            build: Some("triwild test".into()),
        }
    }

    #[test]
    fn stages_from_messages() {
        let s = |cause, msg| stage_of(&row("a.svg", Some(cause), msg));
        assert_eq!(
            s(
                Cause::Meshing,
                "error: a.svg: meshing failed in stage bsp: x"
            )
            .as_deref(),
            Some("bsp")
        );
        assert_eq!(
            s(
                Cause::Meshing,
                "error: a.svg: time limit of 1 s reached in regions"
            )
            .as_deref(),
            Some("regions")
        );
        assert_eq!(
            s(Cause::BadInput, "error: a.svg: empty file").as_deref(),
            Some("load")
        );
        assert_eq!(
            s(
                Cause::Panic,
                "thread 'main' panicked at src/ops/split.rs:3:5: boom"
            )
            .as_deref(),
            Some("optimize")
        );
        assert_eq!(
            s(Cause::Timeout, "killed after the time limit").as_deref(),
            None
        );
        assert_eq!(stage_of(&row("a.svg", None, "")), None);
    }

    #[test]
    fn escaping_and_links() {
        assert_eq!(
            esc(r#"<a href="x">'&'</a>"#),
            "&lt;a href=&quot;x&quot;&gt;&#39;&amp;&#39;&lt;/a&gt;"
        );
        assert_eq!(url("a b/#c%?.svg"), "a%20b/%23c%25%3F.svg");
        assert_eq!(link_text("a%20b/%23c.svg"), "a b/#c.svg");
        assert_eq!(
            rel_link(Path::new("/x/out"), Path::new("/x/in/a b.svg")),
            "../in/a%20b.svg"
        );
        assert_eq!(
            rel_link(Path::new("/x/out"), Path::new("/x/out/./a/../b.svg")),
            "b.svg"
        );
        #[cfg(unix)]
        assert_eq!(absolute(Path::new("/a/./b/../c.msh")), "/a/c.msh");
        assert_eq!(shell_word("a b'c"), r"'a b'\''c'");
        assert_eq!(shell_word("--edge-length=0.1"), "--edge-length=0.1");
    }

    #[test]
    fn pages_for_weird_names_empty_and_all_failed() {
        let dir = tempfile::tempdir().expect("tempdir");
        let opts = PageOptions::new(dir.path().to_path_buf());
        let weird = row("<b>&\"x'</b>.svg", None, "");
        let (page, stats) = render_page(&[weird], &opts, dir.path());
        assert!(!page.contains("<b>&"), "unescaped name");
        assert!(page.contains("&lt;b&gt;&amp;&quot;x&#39;&lt;/b&gt;.svg"));
        assert!(page.contains("a &lt;warning&gt; &amp; more"));
        assert_eq!(
            (stats.files, stats.thumbnails, stats.missing_previews),
            (1, 0, 1)
        );
        let (page, stats) = render_page(&[], &opts, dir.path());
        assert_eq!(stats.files, 0);
        assert!(page.contains("id=\"n-files\">0<") && page.contains("no data"));
        let failed = [
            row(
                "a.svg",
                Some(Cause::Timeout),
                "killed after the time limit of 3 s",
            ),
            row(
                "b.svg",
                Some(Cause::Interrupted),
                "interrupted by SIGINT (2) while meshing",
            ),
            row("c.svg", Some(Cause::BadInput), "error: c.svg: empty file"),
        ];
        let (page, _) = render_page(&failed, &opts, dir.path());
        for c in ["timeout", "interrupted", "bad-input"] {
            assert!(page.contains(&format!("id=\"n-cause-{c}\">1<")), "{c}");
        }
        assert!(page.contains("id=\"n-ok\">0<"));
        let (again, _) = render_page(&failed, &opts, dir.path());
        assert_eq!(page, again, "reproducible");
    }

    #[test]
    fn the_files_whose_areas_differ_are_listed() {
        let dir = tempfile::tempdir().expect("tempdir");
        let opts = PageOptions::new(dir.path().to_path_buf());
        let mut warned = row("warned.svg", None, "");
        if let Some(w) = warned.stats.as_mut().and_then(|s| s.get_mut("warnings")) {
            *w = serde_json::json!([format!(
                "1 region(s) {} by more than --area-tolerance 1e-6",
                crate::regions::AREA_WARNING
            )]);
        }
        let (page, _) = render_page(&[row("quiet.svg", None, ""), warned], &opts, dir.path());
        let table = page
            .split("id=\"area-check\"")
            .nth(1)
            .and_then(|t| t.split("</div>").next())
            .expect("the area table");
        assert!(table.contains("1 files whose regions"), "{table}");
        assert!(
            table.contains("warned.svg") && !table.contains("quiet.svg"),
            "{table}"
        );
        let (page, _) = render_page(&[row("quiet.svg", None, "")], &opts, dir.path());
        assert!(page.contains("Every region has its drawn area."));
    }

    #[test]
    fn a_file_says_where_its_time_went() {
        let dir = tempfile::tempdir().expect("tempdir");
        let opts = PageOptions::new(dir.path().to_path_buf());
        let mut timed = row("timed.svg", None, "");
        if let Some(serde_json::Value::Object(m)) = timed.stats.as_mut() {
            m.insert(
                "times".into(),
                serde_json::json!({"bsp": 0.25, "optimize": 0.75, "total": 1.0}),
            );
            m.insert(
                "optimize".into(),
                serde_json::json!({"passes": 3, "phases": [
                    {"phase": "main", "seconds": 0.5, "queues": 12, "queued": 4000,
                     "largest_queue": 900, "applied": 37, "refused": 1200, "triangles": 640},
                    {"phase": "repair", "seconds": 0.125, "queues": 2, "queued": 80,
                     "largest_queue": 50, "applied": 5, "refused": 9, "triangles": 650}]}),
            );
        }
        let (page, _) = render_page(&[timed], &opts, dir.path());
        let section = page
            .split("Where the time went")
            .nth(1)
            .and_then(|t| t.split("<h3>").next())
            .expect("the time tables");
        // stages by time, with their shares of the stages' sum
        let optimize = section.find("<td>optimize</td><td>0.750</td><td>75 %</td>");
        let bsp = section.find("<td>bsp</td><td>0.250</td><td>25 %</td>");
        assert!(
            matches!((optimize, bsp), (Some(o), Some(b)) if o < b),
            "{section}"
        );
        assert!(!section.contains("<td>total</td>"), "{section}");
        assert!(section.contains(
            "<td>main</td><td>0.500</td><td>12</td><td>4000</td><td>900</td><td>37</td><td>1200</td><td>640</td>"
        ), "{section}");
        assert!(
            section.contains("<td>repair</td><td>0.125</td>"),
            "{section}"
        );
        // the phases are not repeated among the flat figures
        assert!(!page.contains("phases.0"), "phases flattened too");
        // a row without timings has no such section
        let (page, _) = render_page(&[row("plain.svg", None, "")], &opts, dir.path());
        assert!(!page.contains("Where the time went"));
    }
}
