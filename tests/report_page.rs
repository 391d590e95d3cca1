//! The batch's report page (`OUTDIR/report.html`, `triwild report`): the
//! numbers on the page are those of report.jsonl, every file has one gallery
//! card, a page built again from merged shard reports is the batch's page,
//! failures of every kind appear with their cause, and pages for one file
//! and for a batch where everything failed render.
//!
//! The page is read as text here (its gallery cards carry each file's figures
//! in `data-*` attributes, exactly); `.ci/report_page_check.py` opens it in a
//! headless Chromium.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use triwild::batch::{self, Cause, Row, Status};

const EXE: &str = env!("CARGO_BIN_EXE_triwild");

const SQUARE: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
  <title>a filled square</title>
  <rect x="10" y="10" width="80" height="80" fill="black"/>
</svg>"#;
const CIRCLE: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
  <title>a circle</title>
  <circle cx="50" cy="50" r="40" fill="red"/>
</svg>"#;
const TWO: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 50">
  <title>two boxes</title>
  <rect x="0" y="0" width="50" height="50" fill="blue"/>
  <rect x="50" y="10" width="40" height="30" fill="orange"/>
</svg>"#;

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("target/test-out/report_page")
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
    assert!(r.bad_lines.is_empty(), "{report:?}: {:?}", r.bad_lines);
    r.rows
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&#39;", "'")
        .replace("&amp;", "&")
}

/// The attributes of every gallery card (`<a class="card ...">`), in page order.
fn cards(page: &str) -> Vec<BTreeMap<String, String>> {
    let mut out = Vec::new();
    for chunk in page.split("<a class=\"card ").skip(1) {
        let tag = &chunk[..chunk.find('>').expect("card tag ends")];
        let mut attrs = BTreeMap::new();
        let mut rest = tag;
        while let Some(eq) = rest.find("=\"") {
            let name = rest[..eq].rsplit(' ').next().expect("name").to_string();
            let after = &rest[eq + 2..];
            let end = after.find('"').expect("closing quote");
            attrs.insert(name, unescape(&after[..end]));
            rest = &after[end + 1..];
        }
        out.push(attrs);
    }
    out
}

/// The text of the element with `id="ID"` (up to the next `<`).
fn by_id(page: &str, id: &str) -> Option<String> {
    let start = page.find(&format!("id=\"{id}\""))?;
    let from = start + page[start..].find('>')? + 1;
    let end = from + page[from..].find('<')?;
    Some(unescape(&page[from..end]))
}

/// The `data-v` value of the element with `id="ID"`.
fn data_v(page: &str, id: &str) -> Option<f64> {
    let needle = format!("id=\"{id}\" data-v=\"");
    let from = page.find(&needle)? + needle.len();
    let end = from + page[from..].find('"')?;
    page[from..end].parse().ok()
}

fn opt_eq(attr: Option<&String>, value: Option<f64>, what: &str, file: &str) {
    let got = attr
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>().expect("a number"));
    assert_eq!(got, value, "{file}: {what}");
}

/// Every number the page shows per file and in the headline equals the report's.
fn assert_page_matches(page: &str, rows: &[Row]) {
    let cards = cards(page);
    let files: Vec<&str> = cards.iter().map(|c| c["data-file"].as_str()).collect();
    let unique: BTreeSet<&str> = files.iter().copied().collect();
    assert_eq!(unique.len(), files.len(), "each file once in the gallery");
    let expected: BTreeSet<&str> = rows.iter().map(|r| r.file.as_str()).collect();
    assert_eq!(
        unique, expected,
        "the gallery shows exactly the report's files"
    );
    for r in rows {
        let c = cards
            .iter()
            .find(|c| c["data-file"] == r.file)
            .expect("card");
        let status = match r.status {
            Status::Ok => "ok",
            Status::Failed => r.cause.expect("cause").name(),
        };
        assert_eq!(c["data-status"], status, "{}", r.file);
        assert_eq!(
            c["data-wall"].parse::<f64>().ok(),
            Some(r.wall),
            "{}",
            r.file
        );
        opt_eq(
            c.get("data-tris"),
            r.triangles().map(|t| t as f64),
            "triangles",
            &r.file,
        );
        opt_eq(
            c.get("data-angle"),
            r.stat("/quality/min_angle_deg"),
            "min angle",
            &r.file,
        );
        opt_eq(
            c.get("data-jac"),
            r.stat("/quality/min_jacobian_ratio"),
            "Jacobian",
            &r.file,
        );
        opt_eq(
            c.get("data-mem"),
            r.peak_rss
                .map(|b| b as f64 / f64::from(1u32 << 20))
                .or_else(|| r.stat("/peak_memory_mb")),
            "memory",
            &r.file,
        );
    }
    let ok = rows.iter().filter(|r| r.status == Status::Ok).count();
    let count = |id: &str| by_id(page, id).and_then(|t| t.parse::<usize>().ok());
    assert_eq!(count("n-files"), Some(rows.len()));
    assert_eq!(count("n-ok"), Some(ok));
    assert_eq!(count("n-failed"), Some(rows.len() - ok));
    for c in Cause::ALL {
        let n = rows.iter().filter(|r| r.cause == Some(c)).count();
        let shown = count(&format!("n-cause-{}", c.name()));
        assert_eq!(shown, (n > 0).then_some(n), "cause {}", c.name());
    }
    let tris: u64 = rows.iter().filter_map(Row::triangles).sum();
    assert_eq!(data_v(page, "n-triangles"), Some(tris as f64));
    if !rows.is_empty() {
        let wall: f64 = rows.iter().map(|r| r.wall).sum();
        let shown = data_v(page, "n-time").expect("total time");
        assert!(
            (shown - wall).abs() <= 1e-9 * wall.max(1.0),
            "{shown} vs {wall}"
        );
    }
    let worst = rows
        .iter()
        .filter_map(|r| r.stat("/quality/min_angle_deg"))
        .min_by(f64::total_cmp);
    assert_eq!(data_v(page, "n-worst-angle"), worst);
    // every failure is listed with its cause and its error
    let failures = &page[page.find("id=\"failures\"").expect("failures section")..];
    for r in rows.iter().filter(|r| r.status == Status::Failed) {
        let name = format!(
            ">{}</a></td><td>{}</td>",
            esc(&r.file),
            r.cause.expect("cause").name()
        );
        assert!(
            failures.contains(&name),
            "{} not in the failures table",
            r.file
        );
        if let Some(m) = &r.message {
            assert!(failures.contains(&esc(m)), "{}: message missing", r.file);
        }
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{p:?}: {e}"))
}

/// A batch over a few bundled drawings, a fixture, a file with an awkward
/// name and a broken file.
#[test]
fn page_numbers_equal_the_report() {
    let base = out_dir("numbers");
    let (input, out) = (base.join("in"), base.join("out"));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for f in ["star-evenodd.svg", "ello.svg"] {
        let svg = std::fs::read(root.join("data/svg").join(f)).expect("bundled drawing");
        write(&input, &format!("data/{f}"), &svg);
    }
    let fixture = std::fs::read(root.join("tests/fixtures/model-circle.svg")).expect("fixture");
    write(&input, "fixtures/model-circle.svg", &fixture);
    write(&input, "odd/we<i>rd & 'name' #1.svg", TWO.as_bytes());
    write(&input, "odd/empty.svg", b"");
    let o = triwild(&[&"batch", &input, &"-o", &out, &"-j", &"2"], &[]);
    assert_eq!(o.status.code(), Some(1), "some files fail: {}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("page: "), "{stdout}");
    let report = rows(&out.join("report.jsonl"));
    let page = read(&out.join("report.html"));
    assert_page_matches(&page, &report);
    for r in &report {
        assert!(
            r.flags.iter().any(|f| f == "--threads=1"),
            "{}: flags recorded",
            r.file
        );
        if r.status == Status::Ok {
            let preview = batch::preview_path(&out.join(r.output.as_ref().expect("output")));
            assert!(preview.is_file(), "{preview:?}");
        }
    }
    let ok = report.iter().filter(|r| r.status == Status::Ok).count();
    assert!(ok >= 4, "{report:#?}");
    assert_eq!(
        page.matches("<img class=\"thumb\" alt=\"\" src=\"data:image/png;base64,")
            .count(),
        ok,
        "a thumbnail for every mesh"
    );
    assert!(page.contains("we&lt;i&gt;rd &amp; &#39;name&#39; #1.svg"));
    assert!(!page.contains("we<i>rd"), "a name is never raw HTML");
    // the link to the awkward input is percent-encoded
    assert!(page.contains("../in/odd/we%3Ci%3Erd%20%26%20%27name%27%20%231.svg"));

    // `triwild report` on the batch's report makes the same page.
    let again = out.join("again.html");
    let o = triwild(&[&"report", &out.join("report.jsonl"), &"-o", &again], &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(
        read(&again) == page,
        "triwild report differs from the batch's page"
    );
}

/// `triwild report` on merged shard reports gives the page of the unsharded
/// batch: byte for byte for the same rows; for a real sharded run (other
/// times) the same files, statuses and figures.
#[test]
fn merged_shards_give_the_batch_page() {
    let base = out_dir("shards");
    let (input, whole, sharded) = (base.join("in"), base.join("whole"), base.join("sharded"));
    write(&input, "a/square.svg", SQUARE.as_bytes());
    write(&input, "a/circle.svg", CIRCLE.as_bytes());
    write(&input, "b/two.svg", TWO.as_bytes());
    write(&input, "b/empty.svg", b"");
    let o = triwild(&[&"batch", &input, &"-o", &whole, &"-j", &"2"], &[]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let reference = rows(&whole.join("report.jsonl"));
    let page = read(&whole.join("report.html"));
    assert_page_matches(&page, &reference);

    // The same rows, split into shard reports the way --shard splits files
    // and merged: the very same page.
    let mut shards = Vec::new();
    for k in 0..2 {
        let part: Vec<Row> = reference
            .iter()
            .enumerate()
            .filter(|(i, _)| i % 2 == k)
            .map(|(_, r)| r.clone())
            .collect();
        let p = whole.join(format!("report.shard-{}-of-2.jsonl", k + 1));
        batch::write_report(&p, &part).expect("write shard report");
        shards.push(p);
    }
    let merged = whole.join("merged.jsonl");
    let o = triwild(
        &[
            &"batch",
            &"--merge-reports",
            &shards[1],
            &shards[0],
            &"-o",
            &merged,
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let rebuilt = whole.join("rebuilt.html");
    let o = triwild(&[&"report", &merged, &"-o", &rebuilt], &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(
        read(&rebuilt) == page,
        "merged-report page differs from the batch page"
    );
    // the shard reports themselves, given together
    let o = triwild(&[&"report", &shards[0], &shards[1], &"-o", &rebuilt], &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(
        read(&rebuilt) == page,
        "shard reports' page differs from the batch page"
    );

    // A real sharded run into one directory, merged, then its page.
    let mut reports = Vec::new();
    for k in 1..=2 {
        let shard = format!("{k}/2");
        let o = triwild(
            &[
                &"batch", &input, &"-o", &sharded, &"--shard", &shard, &"-j", &"1",
            ],
            &[],
        );
        assert!(matches!(o.status.code(), Some(0 | 1)), "{}", text(&o));
        assert!(
            sharded
                .join(format!("report.shard-{k}-of-2.html"))
                .is_file()
        );
        reports.push(sharded.join(format!("report.shard-{k}-of-2.jsonl")));
    }
    let merged = sharded.join("report.jsonl");
    let o = triwild(
        &[
            &"batch",
            &"--merge-reports",
            &reports[0],
            &reports[1],
            &"-o",
            &merged,
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let html = sharded.join("report.html");
    let o = triwild(&[&"report", &merged, &"-o", &html], &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let shard_page = read(&html);
    let merged_rows = rows(&merged);
    assert_page_matches(&shard_page, &merged_rows);
    let figures = |p: &str| -> Vec<(String, String, String, String)> {
        cards(p)
            .into_iter()
            .map(|c| {
                (
                    c["data-file"].clone(),
                    c["data-status"].clone(),
                    c["data-tris"].clone(),
                    c["data-angle"].clone(),
                )
            })
            .collect()
    };
    assert_eq!(figures(&shard_page), figures(&page));
    let thumbs = |p: &str| p.matches("src=\"data:image/png;base64,").count();
    assert_eq!(thumbs(&shard_page), thumbs(&page));
    assert_eq!(thumbs(&page), 3);
}

/// A failed, a timed-out and an interrupted file each appear with their
/// cause (rows as a batch writes them, built into a page by `triwild report`).
#[test]
fn every_failure_appears_with_its_reason() {
    let base = out_dir("failures");
    let row = |file: &str, cause: Cause, message: &str, code: Option<i32>| Row {
        file: file.into(),
        input: format!("in/{file}"),
        status: Status::Failed,
        cause: Some(cause),
        message: Some(message.into()),
        exit_code: code,
        signal: None,
        output: None,
        wall: 1.5,
        peak_rss: Some(30 << 20),
        stats: None,
        flags: vec!["--threads=1".into()],
        build: Some(batch::build_name()),
    };
    let rows = vec![
        row(
            "m/bsp-fails.svg",
            Cause::Meshing,
            "error: in/m/bsp-fails.svg: meshing failed in stage bsp: no valid cut",
            Some(3),
        ),
        row(
            "m/slow.svg",
            Cause::Timeout,
            "killed after the time limit of 600 s",
            None,
        ),
        row(
            "m/stopped.svg",
            Cause::Interrupted,
            "interrupted by SIGINT (2) while meshing",
            None,
        ),
    ];
    let report = base.join("report.jsonl");
    batch::write_report(&report, &rows).expect("write report");
    let html = base.join("report.html");
    let o = triwild(&[&"report", &report, &"-o", &html], &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let page = read(&html);
    assert_page_matches(&page, &rows);
    let failures = &page[page.find("id=\"failures\"").expect("failures")..];
    assert!(
        failures.contains("<td>meshing</td><td>bsp</td>"),
        "stage of the meshing failure"
    );
    assert!(failures.contains("<td>timeout</td><td>unknown</td>"));
    assert!(failures.contains("<td>interrupted</td><td>unknown</td>"));
    assert!(page.contains("bsp × 1"), "the cause table names the stage");
    assert!(page.contains("id=\"n-ok\">0<"));
}

/// Pages of a batch of one file and of a batch where every file failed.
#[test]
fn one_file_and_all_failed_render() {
    let base = out_dir("small");
    write(&base, "one/square.svg", SQUARE.as_bytes());
    let o = triwild(
        &[
            &"batch",
            &base.join("one/square.svg"),
            &"-o",
            &base.join("one-out"),
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    let page = read(&base.join("one-out/report.html"));
    assert_page_matches(&page, &rows(&base.join("one-out/report.jsonl")));
    assert!(page.contains("No file failed."));
    assert!(page.contains("</html>"));

    write(&base, "bad/empty.svg", b"");
    write(&base, "bad/not-svg.svg", b"\x00\x01 not XML");
    let o = triwild(
        &[&"batch", &base.join("bad"), &"-o", &base.join("bad-out")],
        &[],
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let page = read(&base.join("bad-out/report.html"));
    assert_page_matches(&page, &rows(&base.join("bad-out/report.jsonl")));
    assert!(page.contains("no data (no file meshed)"));
    assert!(page.contains("</html>"));

    // --no-html: neither the page nor the previews
    let o = triwild(
        &[
            &"batch",
            &base.join("one"),
            &"-o",
            &base.join("no-html"),
            &"--no-html",
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(base.join("no-html/square.msh").is_file());
    assert!(!base.join("no-html/report.html").exists());
    assert!(!base.join("no-html/square.preview.svg").exists());
    // an empty report still gives a page
    std::fs::write(base.join("empty.jsonl"), "").expect("write");
    let o = triwild(
        &[
            &"report",
            &base.join("empty.jsonl"),
            &"-o",
            &base.join("empty.html"),
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(read(&base.join("empty.html")).contains("id=\"n-files\">0<"));
    let o = triwild(
        &[
            &"report",
            &base.join("missing.jsonl"),
            &"-o",
            &base.join("x.html"),
        ],
        &[],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
}
