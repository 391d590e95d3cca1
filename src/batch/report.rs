//! The batch report: one JSON line per file (`report.jsonl`), appended and
//! flushed as each file finishes, so a killed batch loses no finished row.
//!
//! Guarantees: every line [`ReportWriter`] writes is one complete [`Row`];
//! [`read_report`] skips a torn last line (a batch killed mid-write) instead
//! of failing; [`merge_reports`] keeps one row per file, sorted by key.

use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Write};
use std::path::Path;

/// Whether a file was meshed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// The mesh was written.
    Ok,
    /// No mesh; see the row's [`Cause`].
    Failed,
}

/// Why a file failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Cause {
    /// The input is unusable: empty, not SVG, no geometry (exit code 2).
    BadInput,
    /// Meshing failed (exit code 3).
    Meshing,
    /// Reading the input or writing the mesh failed (exit code 4).
    Io,
    /// The child panicked (exit code 101): a bug in triwild.
    Panic,
    /// The child died of a signal or an unexpected exit code: a bug in
    /// triwild, or the system's OOM killer.
    Crash,
    /// The child ran past `--timeout` and was killed.
    Timeout,
    /// The child ran out of its `--max-memory`.
    Memory,
    /// The batch could not run the child or read its statistics.
    Internal,
    /// The batch was interrupted (SIGINT / SIGTERM) while the file was being
    /// meshed: the child was stopped, nothing written.
    Interrupted,
}

impl Cause {
    /// Every cause, in display order.
    pub const ALL: [Cause; 9] = [
        Cause::BadInput,
        Cause::Meshing,
        Cause::Io,
        Cause::Panic,
        Cause::Crash,
        Cause::Timeout,
        Cause::Memory,
        Cause::Internal,
        Cause::Interrupted,
    ];

    /// The cause's name in reports (`bad-input`, `timeout`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Cause::BadInput => "bad-input",
            Cause::Meshing => "meshing",
            Cause::Io => "io",
            Cause::Panic => "panic",
            Cause::Crash => "crash",
            Cause::Timeout => "timeout",
            Cause::Memory => "memory",
            Cause::Internal => "internal",
            Cause::Interrupted => "interrupted",
        }
    }
}

/// One file's line in the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The file's key: its path relative to the input root (see
    /// [`super::SourceFile::key`]).
    pub file: String,
    /// The path the batch read.
    pub input: String,
    /// Ok or failed.
    pub status: Status,
    /// Why it failed (`None` when ok).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cause: Option<Cause>,
    /// The child's error message (or panic message, or what killed it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub message: Option<String>,
    /// The child's exit code, if it exited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exit_code: Option<i32>,
    /// The signal that ended the child, if one did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal: Option<i32>,
    /// The mesh, relative to the output directory (`None` unless ok).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output: Option<String>,
    /// Wall time of the child process, seconds.
    pub wall: f64,
    /// Peak resident memory of the child (sampled `VmHWM`), bytes, where
    /// the system tells.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_rss: Option<u64>,
    /// The child's `--stats` object (input counts, resolved parameters,
    /// times per stage, output counts, quality, warnings) when ok.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stats: Option<serde_json::Value>,
    /// The single-file command's flags the batch gave this file's child
    /// (`-l 0.02`, ...; the batch adds `--threads=1` unless told): with the
    /// input and output, the command that reproduces the run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub flags: Vec<String>,
    /// The triwild that ran the batch (`triwild 0.1.0 (release)`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub build: Option<String>,
}

/// This library's build, as report rows record it: `triwild VERSION (release)`
/// or `(debug)`.
pub fn build_name() -> String {
    format!(
        "triwild {} ({})",
        env!("CARGO_PKG_VERSION"),
        if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        }
    )
}

impl Row {
    /// A float at `pointer` (RFC 6901, like `/quality/min_angle_deg`) in the stats.
    pub fn stat(&self, pointer: &str) -> Option<f64> {
        self.stats.as_ref()?.pointer(pointer)?.as_f64()
    }

    /// Triangles of the written mesh.
    pub fn triangles(&self) -> Option<u64> {
        self.stats.as_ref()?.pointer("/output/triangles")?.as_u64()
    }

    /// This row without what changes from run to run of the same input
    /// (wall time, memory, stage times): rows of two runs of one file compare
    /// equal after this.
    pub fn without_measurements(&self) -> Row {
        let mut r = self.clone();
        r.wall = 0.0;
        r.peak_rss = None;
        if let Some(serde_json::Value::Object(m)) = &mut r.stats {
            m.remove("times");
            m.remove("t_core");
            m.remove("peak_memory_mb");
        }
        if let Some(stats) = &mut r.stats {
            strip_seconds(stats);
        }
        r
    }
}

/// Remove every `seconds` / `*_seconds` field (stage timings) at any depth.
fn strip_seconds(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|k, _| !(k == "seconds" || k.ends_with("_seconds")));
            m.values_mut().for_each(strip_seconds);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip_seconds),
        _ => {}
    }
}

/// Appends rows to a report file, one flushed line each.
#[derive(Debug)]
pub struct ReportWriter {
    file: File,
}

impl ReportWriter {
    /// Open `path` for appending (created if missing); `truncate` starts it empty.
    ///
    /// # Errors
    /// [`Error::Write`].
    pub fn open(path: &Path, truncate: bool) -> Result<Self> {
        let mut o = OpenOptions::new();
        if truncate {
            o.write(true).create(true).truncate(true);
        } else {
            o.append(true).create(true);
        }
        let file = o.open(path).map_err(|e| annotate_write(path, e))?;
        Ok(ReportWriter { file })
    }

    /// Append one row as one line (a single `write` call) and flush it.
    ///
    /// # Errors
    /// [`Error::Write`].
    pub fn append(&mut self, row: &Row) -> Result<()> {
        let mut line = serde_json::to_string(row).expect("internal: a report row serializes");
        line.push('\n');
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(Error::Write)
    }
}

fn annotate_write(path: &Path, e: std::io::Error) -> Error {
    Error::Write(std::io::Error::new(
        e.kind(),
        format!("{}: {e}", path.display()),
    ))
}

/// The rows of a report, with the lines that were not rows.
#[derive(Clone, Debug, Default)]
pub struct ReadReport {
    /// The rows, in file order.
    pub rows: Vec<Row>,
    /// Lines that did not parse (1-based line numbers): a batch killed while
    /// writing leaves at most one, at the end.
    pub bad_lines: Vec<usize>,
}

/// Read a report; a missing file reads as empty.
///
/// # Errors
/// [`Error::Read`] if the file exists but cannot be read.
pub fn read_report(path: &Path) -> Result<ReadReport> {
    let file = match File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(ReadReport::default()),
        Err(e) => {
            return Err(Error::Read(std::io::Error::new(
                e.kind(),
                format!("{}: {e}", path.display()),
            )));
        }
    };
    let mut out = ReadReport::default();
    for (i, line) in BufReader::new(file).split(b'\n').enumerate() {
        let line = line.map_err(Error::Read)?;
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        match serde_json::from_slice::<Row>(&line) {
            Ok(row) => out.rows.push(row),
            Err(_) => out.bad_lines.push(i + 1),
        }
    }
    Ok(out)
}

/// The last row of each file, sorted by key. Later rows win: a file rerun by
/// `--resume`, or present in two merged reports, keeps its newest row.
pub fn last_per_file(rows: impl IntoIterator<Item = Row>) -> Vec<Row> {
    let mut by_key: BTreeMap<String, Row> = BTreeMap::new();
    for r in rows {
        by_key.insert(r.file.clone(), r);
    }
    by_key.into_values().collect()
}

/// Write `rows` as a complete report at `path`, atomically (temporary file
/// and rename).
///
/// # Errors
/// [`Error::Write`].
pub fn write_report(path: &Path, rows: &[Row]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(|e| annotate_write(path, e))?;
    for r in rows {
        let line = serde_json::to_string(r).expect("internal: a report row serializes");
        writeln!(tmp, "{line}").map_err(|e| annotate_write(path, e))?;
    }
    tmp.as_file()
        .sync_all()
        .map_err(|e| annotate_write(path, e))?;
    tmp.persist(path)
        .map_err(|e| annotate_write(path, e.error))?;
    Ok(())
}

/// What [`merge_reports`] did.
#[derive(Clone, Debug, Default)]
pub struct Merged {
    /// The merged rows, one per file, sorted by key.
    pub rows: Vec<Row>,
    /// Files that had rows in more than one input (the last input's row is kept).
    pub duplicates: Vec<String>,
    /// Unparsable lines, as `path:line`.
    pub bad_lines: Vec<String>,
}

/// Join reports (the shards of one collection) into one row per file,
/// sorted by key, and write them to `out`.
///
/// # Errors
/// [`Error::Read`] for an unreadable input, [`Error::Write`] for `out`.
pub fn merge_reports(inputs: &[&Path], out: &Path) -> Result<Merged> {
    let mut merged = Merged::default();
    let mut by_key: BTreeMap<String, (usize, Row)> = BTreeMap::new();
    for (k, path) in inputs.iter().enumerate() {
        if !path.is_file() {
            return Err(Error::Read(std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("{}: no such report", path.display()),
            )));
        }
        let rep = read_report(path)?;
        merged.bad_lines.extend(
            rep.bad_lines
                .iter()
                .map(|l| format!("{}:{l}", path.display())),
        );
        for row in last_per_file(rep.rows) {
            if let Some((prev, _)) = by_key.get(&row.file) {
                if *prev != k {
                    merged.duplicates.push(row.file.clone());
                }
            }
            by_key.insert(row.file.clone(), (k, row));
        }
    }
    merged.rows = by_key.into_values().map(|(_, r)| r).collect();
    write_report(out, &merged.rows)?;
    Ok(merged)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(file: &str, status: Status) -> Row {
        Row {
            file: file.into(),
            input: format!("in/{file}"),
            status,
            cause: (status == Status::Failed).then_some(Cause::Timeout),
            message: None,
            exit_code: None,
            signal: None,
            output: (status == Status::Ok).then(|| file.replace(".svg", ".msh")),
            wall: 0.5,
            peak_rss: Some(1 << 20),
            stats: Some(serde_json::json!({"times": {"load": 0.1}, "t_core": 0.2,
                "output": {"triangles": 12}, "quality": {"min_angle_deg": 21.5}})),
            flags: vec!["-l".into(), "0.1".into()],
            build: Some(build_name()),
        }
    }

    #[test]
    fn roundtrip_and_torn_line() {
        let dir = tempfile::tempdir().expect("tempdir");
        let p = dir.path().join("report.jsonl");
        let mut w = ReportWriter::open(&p, true).expect("open");
        w.append(&row("a.svg", Status::Ok)).expect("append");
        w.append(&row("b.svg", Status::Failed)).expect("append");
        drop(w);
        // A batch killed mid-write leaves a torn line.
        let mut f = OpenOptions::new().append(true).open(&p).expect("open");
        f.write_all(br#"{"file":"c.svg","inp"#).expect("write");
        let r = read_report(&p).expect("read");
        assert_eq!(
            r.rows,
            vec![row("a.svg", Status::Ok), row("b.svg", Status::Failed)]
        );
        assert_eq!(r.bad_lines, vec![3]);
        assert_eq!(r.rows[0].triangles(), Some(12));
        assert_eq!(r.rows[0].stat("/quality/min_angle_deg"), Some(21.5));
        assert!(
            read_report(&dir.path().join("none.jsonl"))
                .expect("read")
                .rows
                .is_empty()
        );
    }

    #[test]
    fn serialized_names() {
        let line = serde_json::to_string(&row("b.svg", Status::Failed)).expect("json");
        assert!(
            line.contains(r#""status":"failed","cause":"timeout""#),
            "{line}"
        );
        for c in Cause::ALL {
            let s = serde_json::to_string(&c).expect("json");
            assert_eq!(s, format!("\"{}\"", c.name()));
        }
    }

    #[test]
    fn merge_keeps_one_row_per_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let (a, b, out) = (
            dir.path().join("a.jsonl"),
            dir.path().join("b.jsonl"),
            dir.path().join("out.jsonl"),
        );
        write_report(
            &a,
            &[row("z.svg", Status::Ok), row("x.svg", Status::Failed)],
        )
        .expect("w");
        write_report(&b, &[row("y.svg", Status::Ok), row("x.svg", Status::Ok)]).expect("w");
        let m = merge_reports(&[&a, &b], &out).expect("merge");
        let keys: Vec<_> = m.rows.iter().map(|r| r.file.as_str()).collect();
        assert_eq!(keys, ["x.svg", "y.svg", "z.svg"]);
        assert_eq!(m.rows[0].status, Status::Ok);
        assert_eq!(m.duplicates, ["x.svg"]);
        assert_eq!(read_report(&out).expect("read").rows, m.rows);
        assert!(merge_reports(&[&dir.path().join("missing.jsonl")], &out).is_err());
    }

    #[test]
    fn measurements_removed() {
        let mut r2 = row("a.svg", Status::Ok);
        r2.wall = 9.0;
        r2.peak_rss = None;
        if let Some(serde_json::Value::Object(m)) = &mut r2.stats {
            m.insert("times".into(), serde_json::json!({"load": 7.0}));
        }
        let r1 = row("a.svg", Status::Ok);
        assert_ne!(r1, r2);
        assert_eq!(r1.without_measurements(), r2.without_measurements());
    }
}
