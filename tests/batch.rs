//! `triwild batch` end to end: isolation of bad files (panic, timeout,
//! memory, broken input), resume after a kill, shards and merged reports.
//!
//! Meshes are written under `target/test-out/batch/` (CI checks every .msh
//! there with gmsh; failed files leave none).
//!
//! The tests that make a child panic, hang or hog memory need the binary's
//! test hooks: they run with `cargo test --features test-hooks` (the
//! project's test command) and are left out without it.

#[cfg(feature = "test-hooks")]
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use triwild::batch::{self, Row};
#[cfg(feature = "test-hooks")]
use triwild::batch::{Cause, Status};

const EXE: &str = env!("CARGO_BIN_EXE_triwild");

const SQUARE: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
  <title>a filled square</title>
  <rect x="10" y="10" width="80" height="80" fill="black"/>
</svg>"#;
const CIRCLE: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
  <title>a circle</title>
  <circle cx="50" cy="50" r="40" fill="red"/>
</svg>"#;
const STAR: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 200 200">
  <title>an even-odd star in a frame</title>
  <path d="M 100 20 l 50 160 l -130 -100 l 160 0 l -130 100 z" fill="green" fill-rule="evenodd"/>
  <rect x="1" y="1" width="198" height="198" fill="none" stroke="black"/>
</svg>"#;
const TWO_BOXES: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 50">
  <title>two touching boxes</title>
  <rect x="0" y="0" width="50" height="50" fill="blue"/>
  <rect x="50" y="10" width="40" height="30" fill="none" stroke="black"/>
</svg>"#;

/// A fresh directory under `target/test-out/batch/`.
fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("target/test-out/batch")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create test output dir");
    dir
}

fn write(root: &Path, rel: &str, content: &[u8]) {
    let p = root.join(rel);
    std::fs::create_dir_all(p.parent().expect("parent")).expect("mkdir");
    std::fs::write(p, content).expect("write fixture");
}

/// A nested tree of good drawings.
fn good_tree(root: &Path) -> Vec<&'static str> {
    let files = [
        ("a/square.svg", SQUARE),
        ("a/b/circle.svg", CIRCLE),
        ("c/star.svg", STAR),
        ("top.svg", TWO_BOXES),
        ("a/b/deeper/square2.svg", SQUARE),
    ];
    for (rel, svg) in files {
        write(root, rel, svg.as_bytes());
    }
    let mut keys: Vec<_> = files.iter().map(|f| f.0).collect();
    keys.sort_unstable();
    keys
}

fn triwild(args: &[&dyn AsRef<std::ffi::OsStr>], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(EXE);
    for a in args {
        cmd.arg(a);
    }
    for var in [
        "TRIWILD_TEST_PANIC_ON",
        "TRIWILD_TEST_SLEEP_ON",
        "TRIWILD_TEST_ALLOC_ON",
    ] {
        cmd.env_remove(var);
    }
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run triwild")
}

fn text(o: &Output) -> String {
    format!(
        "status {:?}\n--- stdout\n{}\n--- stderr\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn rows(report: &Path) -> Vec<Row> {
    let r = batch::read_report(report).expect("read report");
    assert!(
        r.bad_lines.is_empty(),
        "{report:?}: bad lines {:?}",
        r.bad_lines
    );
    r.rows
}

#[cfg(feature = "test-hooks")]
fn by_file(rows: &[Row], file: &str) -> Row {
    rows.iter()
        .find(|r| r.file == file)
        .unwrap_or_else(|| panic!("no row for {file} in {rows:#?}"))
        .clone()
}

fn normalized(mut rows: Vec<Row>) -> Vec<Row> {
    rows.sort_by(|a, b| a.file.cmp(&b.file));
    rows.iter().map(Row::without_measurements).collect()
}

#[cfg(feature = "test-hooks")]
fn assert_ok(row: &Row, out: &Path) {
    assert_eq!(row.status, Status::Ok, "{row:#?}");
    let mesh = out.join(row.output.as_ref().expect("ok row has an output"));
    assert!(mesh.is_file(), "{mesh:?} missing");
    assert!(row.triangles().is_some_and(|t| t > 0), "{row:#?}");
}

#[cfg(feature = "test-hooks")]
#[test]
fn failures_are_rows_and_the_rest_succeeds() {
    let base = out_dir("isolation");
    let (input, out) = (base.join("in"), base.join("out"));
    let good = good_tree(&input);
    write(&input, "broken/empty.svg", b"");
    write(
        &input,
        "broken/not-svg.svg",
        b"\x00\x01 this is not XML \xff",
    );
    write(
        &input,
        "broken/no-geometry.svg",
        br#"<svg xmlns="http://www.w3.org/2000/svg"/>"#,
    );
    write(&input, "hooks/panic-me.svg", SQUARE.as_bytes());
    write(&input, "hooks/sleep-me.svg", SQUARE.as_bytes());
    write(&input, "hooks/hog-me.svg", SQUARE.as_bytes());
    write(&input, "README.txt", b"not an svg: never read");
    // A stale mesh of a file that now fails must not survive the batch.
    write(&out, "hooks/panic-me.msh", b"stale");

    let o = triwild(
        &[
            &"batch",
            &input,
            &"-o",
            &out,
            &"-j",
            &"2",
            &"--timeout",
            &"3",
            &"--max-memory",
            &"400M",
            &"-l",
            &"0.2",
        ],
        &[
            ("TRIWILD_TEST_PANIC_ON", "panic-me"),
            ("TRIWILD_TEST_SLEEP_ON", "sleep-me"),
            ("TRIWILD_TEST_ALLOC_ON", "hog-me"),
        ],
    );
    assert_eq!(o.status.code(), Some(1), "some files fail: {}", text(&o));
    let rows = rows(&out.join("report.jsonl"));
    assert_eq!(rows.len(), good.len() + 6, "{rows:#?}");
    let files: BTreeSet<_> = rows.iter().map(|r| r.file.as_str()).collect();
    assert_eq!(files.len(), rows.len(), "one row per file");

    for f in &good {
        assert_ok(&by_file(&rows, f), &out);
    }
    let cause = |f: &str| {
        let r = by_file(&rows, f);
        assert_eq!(r.status, Status::Failed, "{r:#?}");
        assert!(r.output.is_none() && r.message.is_some(), "{r:#?}");
        assert!(
            !out.join(f).with_extension("msh").exists(),
            "{f}: a failed file leaves no mesh"
        );
        r.cause.expect("failed row has a cause")
    };
    assert_eq!(cause("broken/empty.svg"), Cause::BadInput);
    assert_eq!(cause("broken/not-svg.svg"), Cause::BadInput);
    assert_eq!(cause("broken/no-geometry.svg"), Cause::BadInput);
    assert_eq!(cause("hooks/panic-me.svg"), Cause::Panic);
    assert_eq!(cause("hooks/sleep-me.svg"), Cause::Timeout);
    assert_eq!(cause("hooks/hog-me.svg"), Cause::Memory);
    assert!(
        by_file(&rows, "hooks/panic-me.svg")
            .message
            .is_some_and(|m| m.contains("TRIWILD_TEST_PANIC_ON"))
    );
    let slept = by_file(&rows, "hooks/sleep-me.svg").wall;
    assert!(
        (3.0..20.0).contains(&slept),
        "killed soon after 3 s, took {slept}"
    );

    // The summary counts every cause.
    let stdout = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<String> = stdout
        .lines()
        .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect();
    for needle in [
        "files 11",
        "ok 5",
        "failed 6",
        "bad-input 3",
        "panic 1",
        "timeout 1",
        "memory 1",
    ] {
        assert!(
            lines.iter().any(|l| l == needle),
            "summary lacks `{needle}`:\n{stdout}"
        );
    }

    // The report page lists every failure with its cause.
    let page = std::fs::read_to_string(out.join("report.html")).expect("report page");
    for (f, c) in [
        ("broken/empty.svg", "bad-input"),
        ("hooks/panic-me.svg", "panic"),
        ("hooks/sleep-me.svg", "timeout"),
        ("hooks/hog-me.svg", "memory"),
    ] {
        assert!(
            page.contains(&format!(">{f}</a></td><td>{c}</td>")),
            "{f} [{c}] not in the page's failures"
        );
    }

    // The same bytes as the single-file command with the same parameters;
    // and the parameters reached the child.
    let single = base.join("single.msh");
    let s = triwild(
        &[&input.join("c/star.svg"), &"-o", &single, &"-l", &"0.2"],
        &[],
    );
    assert!(s.status.success(), "{}", text(&s));
    let a = std::fs::read(&single).expect("single mesh");
    let b = std::fs::read(out.join("c/star.msh")).expect("batch mesh");
    assert!(a == b, "batch and single-file meshes differ");
    std::fs::remove_file(&single).expect("rm");
    let star = by_file(&rows, "c/star.svg");
    let (l, d) = (star.stat("/params/l"), star.stat("/params/d"));
    assert!(
        matches!((l, d), (Some(l), Some(d)) if (l - 0.2 * d).abs() < 1e-9 * d),
        "-l 0.2 not passed on: {l:?} {d:?}"
    );
}

#[cfg(feature = "test-hooks")]
#[test]
fn resume_meshes_only_the_rest() {
    let base = out_dir("resume");
    let (input, full, out) = (base.join("in"), base.join("full"), base.join("out"));
    let good = good_tree(&input);
    let o = triwild(&[&"batch", &input, &"-o", &full, &"-j", &"2"], &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let reference = rows(&full.join("report.jsonl"));
    assert_eq!(reference.len(), good.len());

    // A batch killed midway: two files done (rows and meshes), one failed
    // row, one mesh without its row, and a torn last line.
    let (done, failed, orphan) = (&good[..2], good[2], good[3]);
    let mut partial = String::new();
    for f in done {
        let r = by_file(&reference, f);
        let rel = r.output.clone().expect("output");
        std::fs::create_dir_all(out.join(&rel).parent().expect("parent")).expect("mkdir");
        std::fs::copy(full.join(&rel), out.join(&rel)).expect("copy mesh");
        partial += &serde_json::to_string(&r).expect("json");
        partial.push('\n');
    }
    let mut bad = by_file(&reference, failed);
    bad.status = Status::Failed;
    bad.cause = Some(Cause::Timeout);
    bad.output = None;
    partial += &serde_json::to_string(&bad).expect("json");
    partial.push('\n');
    let orphan_rel = by_file(&reference, orphan).output.expect("output");
    write(&out, &orphan_rel, b"partial mesh of a killed run");
    partial += r#"{"file":"top.svg","inp"#;
    write(&out, "report.jsonl", partial.as_bytes());

    // The files already done would panic if they were meshed again.
    let hook = common_hook(done);
    let o = triwild(
        &[&"batch", &input, &"-o", &out, &"-j", &"2", &"--resume"],
        &[("TRIWILD_TEST_PANIC_ON", hook.as_str())],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let stderr = String::from_utf8_lossy(&o.stderr);
    let expect = format!("{} to mesh, {} done before", good.len() - 2, 2);
    assert!(stderr.contains(&expect), "{stderr}");
    let after = rows(&out.join("report.jsonl"));
    assert_eq!(after.len(), good.len(), "one row per file: {after:#?}");
    for f in done {
        assert_eq!(by_file(&after, f), by_file(&reference, f), "{f} was rerun");
    }
    for r in &after {
        assert_ok(r, &out);
    }
    assert_eq!(normalized(after), normalized(reference));
    let orphan_mesh = std::fs::read(out.join(&orphan_rel)).expect("mesh");
    assert_eq!(
        orphan_mesh,
        std::fs::read(full.join(&orphan_rel)).expect("mesh")
    );
}

/// A substring of the input paths of `files` and of no other good file:
/// their common directory prefix (the first two good files share `a/`).
#[cfg(feature = "test-hooks")]
fn common_hook(files: &[&str]) -> String {
    let first = files[0];
    let mut prefix = first.to_string();
    for f in files {
        while !f.starts_with(&prefix) {
            prefix.pop();
        }
    }
    assert!(prefix.ends_with('/'), "{files:?} share no folder");
    format!("/{prefix}")
}

#[test]
fn shards_cover_every_file_once_and_merge_to_the_whole() {
    let base = out_dir("shards");
    let (input, whole, shared) = (base.join("in"), base.join("whole"), base.join("sharded"));
    let good = good_tree(&input);
    write(&input, "z/empty.svg", b"");
    let o = triwild(&[&"batch", &input, &"-o", &whole, &"-j", &"2"], &[]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let reference = rows(&whole.join("report.jsonl"));
    assert_eq!(reference.len(), good.len() + 1);

    let mut seen = Vec::new();
    let mut reports = Vec::new();
    for k in 1..=3 {
        let shard = format!("{k}/3");
        let o = triwild(
            &[
                &"batch", &input, &"-o", &shared, &"--shard", &shard, &"-j", &"1",
            ],
            &[],
        );
        assert!(matches!(o.status.code(), Some(0 | 1)), "{}", text(&o));
        let report = shared.join(format!("report.shard-{k}-of-3.jsonl"));
        let rows = rows(&report);
        assert!(!rows.is_empty(), "shard {shard} is empty");
        seen.extend(rows.iter().map(|r| r.file.clone()));
        reports.push(report);
    }
    seen.sort();
    let mut all: Vec<_> = reference.iter().map(|r| r.file.clone()).collect();
    all.sort();
    assert_eq!(seen, all, "the shards cover every file exactly once");

    let merged = base.join("merged.jsonl");
    let o = triwild(
        &[
            &"batch",
            &"--merge-reports",
            &reports[0],
            &reports[1],
            &reports[2],
            &"-o",
            &merged,
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "one file failed: {}", text(&o));
    let merged_rows = rows(&merged);
    let keys: Vec<_> = merged_rows.iter().map(|r| r.file.clone()).collect();
    assert_eq!(keys, all, "merged rows are sorted by file");
    assert_eq!(normalized(merged_rows), normalized(reference));
}

#[test]
fn usage_errors_exit_2() {
    let base = out_dir("usage");
    let cases: [&[&dyn AsRef<std::ffi::OsStr>]; 4] = [
        &[&"batch", &base.join("missing"), &"-o", &base],
        &[&"batch", &base, &"-o", &base.join("o")],
        &[&"batch", &base, &"-o", &base, &"--shard", &"4/3"],
        &[&"batch", &base, &"-o", &base, &"--max-memory", &"lots"],
    ];
    for args in cases {
        let o = triwild(args, &[]);
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    }
}

/// The polling memory guard (used when `prlimit` is missing) kills a child
/// that grows past the limit.
#[cfg(all(target_os = "linux", feature = "test-hooks"))]
#[test]
fn polling_memory_guard_kills() {
    let base = out_dir("memory-poll");
    write(&base, "hog-me.svg", SQUARE.as_bytes());
    let guard = batch::MemoryGuard::Poll { bytes: 200 << 20 };
    // `env VAR=VALUE triwild ...` sets the test hook for this child only.
    let args = ["TRIWILD_TEST_ALLOC_ON=hog-me".into(), EXE.into()];
    let spec = batch::ChildSpec {
        exe: Path::new("/usr/bin/env"),
        args: &args,
        timeout: std::time::Duration::from_secs(60),
        memory: &guard,
        preview: false,
        preview_size: false,
    };
    let row = batch::run_child(
        &spec,
        "hog-me.svg",
        &base.join("hog-me.svg"),
        &base.join("hog-me.msh"),
        "hog-me.msh",
    );
    assert_eq!(row.cause, Some(Cause::Memory), "{row:#?}");
    assert!(row.peak_rss.is_some_and(|p| p > 200 << 20), "{row:#?}");
}

/// Without the `test-hooks` feature the binary has no hooks: the variables
/// change nothing, and `batch --help` does not mention them.
#[cfg(not(feature = "test-hooks"))]
#[test]
fn hooks_are_not_built_in() {
    let base = out_dir("no-hooks");
    write(&base, "panic-me.svg", SQUARE.as_bytes());
    let o = triwild(
        &[
            &base.join("panic-me.svg"),
            &"-o",
            &base.join("panic-me.msh"),
        ],
        &[("TRIWILD_TEST_PANIC_ON", "panic-me")],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let o = triwild(&[&"batch", &"--help"], &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(!String::from_utf8_lossy(&o.stdout).contains("TRIWILD_TEST"));
}

#[test]
fn batch_previews_can_shade_triangles_by_size() {
    let base = out_dir("preview_size");
    let (input, out) = (base.join("in"), base.join("out"));
    write(&input, "square.svg", SQUARE.as_bytes());
    let o = triwild(
        &[
            &"batch",
            &input,
            &"-o",
            &out,
            &"-j",
            &"1",
            &"--preview-size",
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let svg = std::fs::read_to_string(out.join("square.preview.svg")).expect("the preview");
    assert!(svg.contains("id=\"size-legend\""), "no size legend");
    // Without the page there are no previews to shade: a usage error.
    let o = triwild(
        &[
            &"batch",
            &input,
            &"-o",
            &base.join("x"),
            &"--no-html",
            &"--preview-size",
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
}
