//! Bad input gets one clear line, its exit code, and no output file.
//!
//! Table-driven over every case of the foundation issue: each row runs the real
//! binary and checks stderr (`error: <file>: <cause>`), the exit code, and that no
//! output appeared (and that an existing output file was left untouched).

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_triwild"))
}

/// A fresh scratch directory under target/test-tmp for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cli-errors")
        .join(name);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

const PNG_MAGIC: &[u8] =
    b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x00\x01\x00\x00\x00\x01\x08\x06\x00\x00\x00";

struct Case {
    name: &'static str,
    /// Input file content; `None` for "does not exist", `Some(None)` for a directory.
    input: Input,
    /// Output path relative to the scratch dir.
    output: &'static str,
    code: i32,
    /// A word the cause must contain (case-insensitive).
    cause: &'static str,
    /// Which file the message must name.
    names_output: bool,
}

enum Input {
    Missing,
    Directory,
    Bytes(&'static [u8]),
}

const SQUARE: &[u8] = br#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><rect x="1" y="1" width="8" height="8"/></svg>"#;

fn cases() -> Vec<Case> {
    use Input::*;
    vec![
        Case { name: "missing", input: Missing, output: "out.msh", code: 2, cause: "no such file", names_output: false },
        Case { name: "directory", input: Directory, output: "out.msh", code: 2, cause: "directory", names_output: false },
        Case { name: "empty", input: Bytes(b""), output: "out.msh", code: 2, cause: "empty", names_output: false },
        Case { name: "not-xml", input: Bytes(b"hello, this is plain text\n"), output: "out.msh", code: 2, cause: "svg", names_output: false },
        Case { name: "broken-xml", input: Bytes(b"<svg xmlns=\"http://www.w3.org/2000/svg\"><path d=\"M0 0 L1 1\"</svg>"), output: "out.msh", code: 2, cause: "svg", names_output: false },
        Case { name: "html", input: Bytes(b"<!DOCTYPE html><html><head><title>x</title></head><body><p>hi</p></body></html>"), output: "out.msh", code: 2, cause: "svg", names_output: false },
        Case { name: "png", input: Bytes(PNG_MAGIC), output: "out.msh", code: 2, cause: "svg", names_output: false },
        Case { name: "no-geometry", input: Bytes(br#"<svg xmlns="http://www.w3.org/2000/svg" width="10" height="10"><title>nothing</title></svg>"#), output: "out.msh", code: 2, cause: "geometry", names_output: false },
        Case { name: "nan", input: Bytes(br#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><path d="M 0 0 L NaN 5 L 5 5 Z"/></svg>"#), output: "out.msh", code: 2, cause: "non-finite", names_output: false },
        Case { name: "infinity", input: Bytes(br#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><polygon points="0,0 Infinity,5 5,5"/></svg>"#), output: "out.msh", code: 2, cause: "non-finite", names_output: false },
        Case { name: "huge", input: Bytes(br#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><path d="M 0 0 L 1e300 5 L 5 5 Z"/></svg>"#), output: "out.msh", code: 2, cause: "coordinate", names_output: false },
        Case { name: "infinite-transform", input: Bytes(br#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><path transform="scale(1e200)" d="M 0 0 L 1e200 5 L 5 5 Z"/></svg>"#), output: "out.msh", code: 2, cause: "", names_output: false },
        Case { name: "missing-out-dir", input: Bytes(SQUARE), output: "no/such/dir/out.msh", code: 4, cause: "", names_output: true },
        Case { name: "out-under-file", input: Bytes(SQUARE), output: "a-file/out.msh", code: 4, cause: "", names_output: true },
        Case { name: "out-is-dir", input: Bytes(SQUARE), output: "a-dir", code: 4, cause: "directory", names_output: true },
    ]
}

#[test]
fn bad_input_gets_one_line_an_exit_code_and_no_output() {
    for case in cases() {
        let dir = scratch(case.name);
        fs::write(dir.join("a-file"), b"not a directory").unwrap();
        fs::create_dir_all(dir.join("a-dir")).unwrap();
        let input = dir.join("in.svg");
        match case.input {
            Input::Missing => {}
            Input::Directory => fs::create_dir_all(&input).unwrap(),
            Input::Bytes(b) => fs::write(&input, b).unwrap(),
        }
        let output = dir.join(case.output);
        let before: Vec<_> = list(&dir);
        let out = bin().arg(&input).arg("-o").arg(&output).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(
            out.status.code(),
            Some(case.code),
            "{}: exit code; stderr: {stderr}",
            case.name
        );
        assert_eq!(
            lines.len(),
            1,
            "{}: exactly one line on stderr, got: {stderr}",
            case.name
        );
        let named = if case.names_output { &output } else { &input };
        let prefix = format!("error: {}: ", named.display());
        assert!(
            lines[0].starts_with(&prefix),
            "{}: `{}` should start with `{prefix}`",
            case.name,
            lines[0]
        );
        assert!(
            lines[0].to_lowercase().contains(case.cause),
            "{}: `{}` should mention `{}`",
            case.name,
            lines[0],
            case.cause
        );
        assert_eq!(list(&dir), before, "{}: no file may be created", case.name);
        assert!(out.stdout.is_empty(), "{}: nothing on stdout", case.name);
    }
}

#[test]
fn an_existing_output_is_left_untouched_on_failure() {
    let dir = scratch("untouched");
    let input = dir.join("in.svg");
    fs::write(&input, b"<svg xmlns=\"http://www.w3.org/2000/svg\"></svg>").unwrap();
    let output = dir.join("out.msh");
    fs::write(&output, b"precious").unwrap();
    let out = bin().arg(&input).arg("-o").arg(&output).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(fs::read(&output).unwrap(), b"precious");
    assert_eq!(list(&dir).len(), 2, "no temporary file left behind");
}

#[test]
fn an_unwritable_preview_is_named_and_nothing_is_written() {
    let dir = scratch("preview");
    let input = dir.join("in.svg");
    fs::write(&input, SQUARE).unwrap();
    let output = dir.join("out.msh");
    let preview = dir.join("missing/preview.svg");
    let out = bin()
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .arg("--preview")
        .arg(&preview)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(4));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.starts_with(&format!("error: {}: ", preview.display())),
        "{stderr}"
    );
    assert!(
        !output.exists(),
        "no mesh written when the preview cannot be"
    );
}

#[test]
fn usage_errors_exit_2() {
    let out = bin().output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = bin()
        .args(["x.svg", "--edge-length", "-1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = bin().args(["x.svg", "--no-such-flag"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn help_documents_exit_codes_and_defaults() {
    let out = bin().arg("--help").output().unwrap();
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "Exit codes",
        "[default: 0.05]",
        "[default: 4.1]",
        "--stats",
        "--preview",
    ] {
        assert!(help.contains(needle), "--help should mention {needle}");
    }
}

/// Every path below `dir`, sorted, relative to it.
fn list(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p.clone());
            }
            out.push(p.strip_prefix(dir).unwrap().to_path_buf());
        }
    }
    out.sort();
    out
}

/// A reader that closes the pipe early (`triwild … | head -c 1`) is no panic:
/// the process stops quietly with 141 (what a shell reports for `cat`), and
/// the files it wrote are complete.
#[test]
fn a_closed_stdout_is_no_panic() {
    use std::io::Read;
    use std::process::Stdio;
    let dir = scratch("closed-stdout");
    let out = dir.join("ello.msh");
    let mut child = bin()
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg/ello.svg"))
        .arg("-o")
        .arg(&out)
        .args(["--stats", "-l", "0.2", "--order", "1"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run triwild");
    // close our end before anything is printed
    drop(child.stdout.take());
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut stderr)
        .expect("read stderr");
    let status = child.wait().expect("wait");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(status.code(), Some(141), "{stderr}");
    let mesh = fs::read_to_string(&out).expect("the mesh was written");
    assert!(mesh.ends_with("$EndElements\n"), "an incomplete mesh");
}

/// An input with `n` references to an entity of 25 000 segments (path data
/// multiplied by XML entities, never expanded by triwild's checks).
fn entity_path(n: usize) -> Vec<u8> {
    let seg = "l1 1 l-1 -1 ".repeat(50);
    format!(
        "<?xml version=\"1.0\"?>\n<!DOCTYPE svg [\n<!ENTITY a \"{seg}\">\n<!ENTITY b \"{}\">\n]>\n\
         <svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 100 100\">\
         <path d=\"M10 10 {}\" fill=\"none\" stroke=\"black\"/></svg>\n",
        "&a;".repeat(250),
        "&b;".repeat(n)
    )
    .into_bytes()
}

/// Resource budgets: too large an input, or too long a run, is one
/// line naming the flag to raise, exit 2 (or 3 for the time limit), no output.
#[test]
fn budgets_fail_with_one_line_naming_the_flag() {
    let two = br#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><rect x="1" y="1" width="3" height="3"/><rect x="5" y="5" width="3" height="3"/></svg>"#;
    let mut uses = String::from(
        r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><defs><path id="p" d="M1 1 L2 1 L2 2 Z"/></defs>"##,
    );
    uses.push_str(&r##"<use href="#p"/>"##.repeat(1000));
    uses.push_str("</svg>");
    /// name, input, flags, exit code, what the line says
    type BudgetCase = (
        &'static str,
        Vec<u8>,
        &'static [&'static str],
        i32,
        &'static str,
    );
    let cases: Vec<BudgetCase> = vec![
        (
            "segments",
            SQUARE.to_vec(),
            &["--max-segments", "3"],
            2,
            "too large: 8 segments (limit 3), raise with --max-segments",
        ),
        (
            "shapes",
            two.to_vec(),
            &["--max-shapes", "1"],
            2,
            "too large: 2 shapes (limit 1), raise with --max-shapes",
        ),
        (
            "memory",
            SQUARE.to_vec(),
            &["--max-memory", "1"],
            2,
            "raise with --max-memory",
        ),
        (
            "use-copies",
            uses.into_bytes(),
            &["--max-segments", "2000"],
            2,
            "too large: 3000 segments (limit 2000)",
        ),
        // 10 million segments (120 MB of expanded text, within the entity
        // allowance): counted on the XML tree, before usvg builds its own
        (
            "entity-10m",
            entity_path(400),
            &[],
            2,
            "too large: 10000001 segments (limit 1000000)",
        ),
        // just over the segment budget
        (
            "entity-1m",
            entity_path(41),
            &[],
            2,
            "too large: 1025001 segments (limit 1000000)",
        ),
        (
            "time-limit",
            SQUARE.to_vec(),
            &["--time-limit", "1e-9"],
            3,
            "time limit of 0.000000001 s reached in features",
        ),
        (
            "scale-overflow",
            SQUARE.to_vec(),
            &["--scale", "1e300"],
            2,
            "coordinates too large after --scale 1e300",
        ),
        (
            "scale-underflow",
            SQUARE.to_vec(),
            &["--scale", "1e-300"],
            2,
            "coordinates too small after --scale 1e-300",
        ),
        // 25 million segments: refused on the raw text, before the XML parser
        // expands the entities
        (
            "entity-25m-text",
            entity_path(1000),
            &[],
            2,
            "xml entities expand the document by",
        ),
    ];
    for (name, input_bytes, args, code, cause) in cases {
        let dir = scratch(&format!("budget-{name}"));
        let input = dir.join("in.svg");
        fs::write(&input, &input_bytes).unwrap();
        let output = dir.join("out.msh");
        let out = bin()
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .args(args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(out.status.code(), Some(code), "{name}: {stderr}");
        assert_eq!(lines.len(), 1, "{name}: one line, got {stderr}");
        let prefix = format!("error: {}: ", input.display());
        assert!(lines[0].starts_with(&prefix), "{name}: {}", lines[0]);
        assert!(
            lines[0].to_lowercase().contains(&cause.to_lowercase()),
            "{name}: `{}` should contain `{cause}`",
            lines[0]
        );
        assert_eq!(
            list(&dir),
            vec![PathBuf::from("in.svg")],
            "{name}: no output"
        );
    }
}

/// A drawing with nothing left to mesh says why, on its one line: here every
/// shape lies under a clip path with no area, and the parser skipped the
/// clip's rectangle.
#[test]
fn no_geometry_says_why_on_one_line() {
    let input =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/kept/empty-clip-hides-all.svg");
    let dir = scratch("no-geometry-why");
    let out = bin()
        .arg(&input)
        .arg("-o")
        .arg(dir.join("out.msh"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    for part in [
        "empty-clip-hides-all.svg: no geometry",
        "all 2 shape element(s) lie under clip path 'cp'",
        "the SVG parser ignored what it could not read",
    ] {
        assert!(stderr.contains(part), "{part:?} not in {stderr}");
    }
    assert!(!dir.join("out.msh").exists());
}
