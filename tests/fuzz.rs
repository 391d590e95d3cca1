//! A structure-aware fuzz harness over the loader and the whole pipeline.
//!
//! Cases are SVG documents drawn from a small grammar (proptest strategies: root
//! attributes, a tree of g/use/defs/symbol/svg/path/rect/circle/ellipse/line/
//! polyline/polygon/text with transforms, styles and fill rules, path data with
//! normal, tiny, huge and non-finite numbers), from attack generators (entity
//! bombs, `<use>` cycles and chains, deep nesting, huge paths, external
//! references, ...), from byte-level mutations of grammar documents (truncate,
//! splice, flip, duplicate a range, insert an entity declaration, invalid UTF-8),
//! and from mutations of the real drawings in `data/svg`. Every case records its
//! mutation kind; cases go round-robin over the kinds.
//!
//! Each case runs the real binary (`triwild -q -l 0.1 --order 2 IN -o OUT`, plus
//! the resource budgets when `triwild --help` lists them) under a watchdog. The
//! property: exit 0 with a mesh that `triwild check` certifies (and, when asked,
//! `shared/bench/mshcheck.py --strict --require-ccw`), or exit 2/3/4 with exactly
//! one line on stderr naming the file and no output left behind; never a panic
//! (exit 101), a signal, a hang (past the watchdog), a read of an external file (a
//! FIFO: reading it blocks, i.e. a hang) or a network connection (a local
//! listener that must see none).
//!
//! By default ~30 cases of a fixed seed plus every fixture under
//! `tests/fixtures/fuzz/` (earlier findings and notable attacks, replayed).
//! `docs/fuzz.md` has the long run: `TRIWILD_FUZZ_CASES`, `TRIWILD_FUZZ_SEED`,
//! `TRIWILD_FUZZ_JOBS`, `TRIWILD_FUZZ_MSHCHECK`, `TRIWILD_FUZZ_FAILURES`,
//! `TRIWILD_FUZZ_MAX_MEMORY`.
//!
//! With `--max-memory` a case also fails when the child's peak
//! resident memory (its `VmHWM`, polled while it runs) passes the budget by
//! more than [`MEMORY_MARGIN_MB`].
#![allow(
    clippy::print_stderr,
    reason = "the table by mutation kind and the failures are this test's report"
)]

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

const EXE: &str = env!("CARGO_BIN_EXE_triwild");

/// The binary under test: this build's, or `TRIWILD_FUZZ_BIN` (another build).
fn exe() -> PathBuf {
    std::env::var_os("TRIWILD_FUZZ_BIN").map_or_else(|| PathBuf::from(EXE), PathBuf::from)
}
/// The meshing parameters of every case: coarse and quadratic, to keep cases fast.
const PARAMS: &[&str] = &["-q", "-l", "0.1", "--order", "2"];
/// Placeholders in case bytes (and fixtures), replaced at run time: a FIFO nobody
/// writes to (opening it for reading blocks), and a URL of a listener that must
/// never be connected to.
const FIFO_MARK: &str = "@FIFO@";
/// A case that starts with this comment carries its own options, one per
/// line up to `-->`, each without its leading `--` (a comment may not hold
/// `--`): `order=3`, `cut-outside`. They replace [`PARAMS`] (but `-q`).
const ARGS_MARK: &str = "<!--triwild-args";
const URL_MARK: &str = "@URL@";
/// The default seed (CI replays the same cases); `TRIWILD_FUZZ_SEED` for fresh ones.
const DEFAULT_SEED: u64 = 0x7219_1d17;
const DEFAULT_CASES: usize = 30;
/// `--max-memory` of every case, MiB (`TRIWILD_FUZZ_MAX_MEMORY`).
const DEFAULT_MAX_MEMORY_MB: u64 = 2048;
/// How far past `--max-memory` a child's peak may go: the memory check reads
/// the process's memory every few milliseconds, and the error path allocates.
const MEMORY_MARGIN_MB: f64 = 64.0;

// ---------------------------------------------------------------------------
// Configuration
// ---------------------------------------------------------------------------

fn env_num(name: &str) -> Option<u64> {
    std::env::var(name).ok().map(|v| {
        let v = v.trim();
        v.strip_prefix("0x")
            .map_or_else(|| v.parse(), |h| u64::from_str_radix(h, 16))
            .unwrap_or_else(|_| panic!("{name}={v}: not a number"))
    })
}

/// How the binary is run: the budget flags it has (detected from `--help`, so the
/// harness works before and after the resource budgets exist) and the watchdog.
struct Runner {
    budget_args: Vec<String>,
    /// The binary has `--time-limit` and `--max-segments`: the `budget-*` fixtures
    /// (inputs that only a budget bounds) are replayed.
    has_budgets: bool,
    /// Past this a run is a hang: the time limit plus a margin, or a fixed
    /// generous limit when the binary has no `--time-limit`.
    watchdog: Duration,
    /// `--max-memory` passed to every case, MiB, when the binary has it: a
    /// case whose peak passes it by more than [`MEMORY_MARGIN_MB`] fails.
    max_memory_mb: Option<u64>,
    /// Cap on the huge-path generator's segments without `--max-segments` (a
    /// 100k-segment zigzag then takes minutes: the budget is what bounds it).
    max_path_segments: usize,
    mshcheck: Option<(PathBuf, PathBuf)>,
    fifo: PathBuf,
    url: String,
    listener: TcpListener,
    connections: AtomicUsize,
}

impl Runner {
    fn new(scratch: &Path) -> Runner {
        let help = Command::new(exe())
            .arg("--help")
            .output()
            .expect("run triwild --help");
        let help = String::from_utf8_lossy(&help.stdout).into_owned();
        let has = |flag: &str| help.contains(flag);
        let time_limit = env_num("TRIWILD_FUZZ_TIME_LIMIT").unwrap_or(10);
        let mut budget_args = Vec::new();
        if has("--time-limit") {
            budget_args.extend(["--time-limit".to_owned(), time_limit.to_string()]);
        }
        if has("--max-segments") {
            budget_args.extend(["--max-segments".to_owned(), "20000".to_owned()]);
        }
        if has("--max-shapes") {
            budget_args.extend(["--max-shapes".to_owned(), "2000".to_owned()]);
        }
        let max_memory_mb = has("--max-memory")
            .then(|| env_num("TRIWILD_FUZZ_MAX_MEMORY").unwrap_or(DEFAULT_MAX_MEMORY_MB));
        if let Some(mb) = max_memory_mb {
            budget_args.extend(["--max-memory".to_owned(), mb.to_string()]);
        }
        let watchdog = if has("--time-limit") {
            Duration::from_secs(time_limit + 10)
        } else {
            Duration::from_secs(env_num("TRIWILD_FUZZ_WATCHDOG").unwrap_or(60))
        };
        let max_path_segments = if has("--max-segments") { 100_000 } else { 500 };
        let mshcheck = std::env::var_os("TRIWILD_FUZZ_MSHCHECK").map(|script| {
            let python = std::env::var_os("TRIWILD_FUZZ_PYTHON")
                .map(PathBuf::from)
                .unwrap_or_else(|| {
                    let venv = PathBuf::from("/tmp/triwild-ci-venv/bin/python");
                    if venv.exists() {
                        venv
                    } else {
                        PathBuf::from("python3")
                    }
                });
            (python, PathBuf::from(script))
        });
        let fifo = scratch.join("external.fifo");
        let _ = fs::remove_file(&fifo);
        let made = Command::new("mkfifo").arg(&fifo).status();
        assert!(
            made.is_ok_and(|s| s.success()),
            "mkfifo {} failed: the external-reference cases need a FIFO",
            fifo.display()
        );
        let listener = TcpListener::bind("127.0.0.1:0").expect("bind a local listener");
        listener.set_nonblocking(true).unwrap();
        let url = format!("http://{}/external.svg", listener.local_addr().unwrap());
        Runner {
            budget_args,
            max_memory_mb,
            has_budgets: has("--time-limit") && has("--max-segments"),
            watchdog,
            max_path_segments,
            mshcheck,
            fifo,
            url,
            listener,
            connections: AtomicUsize::new(0),
        }
    }

    /// Placeholders → this run's FIFO and URL.
    fn substitute(&self, bytes: &[u8]) -> Vec<u8> {
        let fifo = self.fifo.to_string_lossy();
        replace_all(
            &replace_all(bytes, FIFO_MARK.as_bytes(), fifo.as_bytes()),
            URL_MARK.as_bytes(),
            self.url.as_bytes(),
        )
    }

    fn poll_connections(&self) -> usize {
        while let Ok((_stream, _)) = self.listener.accept() {
            self.connections.fetch_add(1, Ordering::SeqCst);
        }
        self.connections.load(Ordering::SeqCst)
    }

    /// Run one case in `dir` and classify it.
    fn run(&self, bytes: &[u8], dir: &Path, name: &str) -> Run {
        fs::create_dir_all(dir).unwrap();
        let input = dir.join(format!("{name}.svg"));
        let output = dir.join(format!("{name}.msh"));
        let err_path = dir.join(format!("{name}.stderr"));
        let _ = fs::remove_file(&output);
        fs::write(&input, self.substitute(bytes)).unwrap();
        let before = self.poll_connections();
        let start = Instant::now();
        let case_args = case_args(bytes);
        let params: Vec<String> = match &case_args {
            Some(args) => std::iter::once("-q".to_owned())
                .chain(args.iter().cloned())
                .collect(),
            None => PARAMS.iter().map(|&a| a.to_owned()).collect(),
        };
        let mut child = Command::new(exe())
            .args(&params)
            .args(&self.budget_args)
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(fs::File::create(&err_path).unwrap())
            .spawn()
            .expect("spawn triwild");
        let status_path = PathBuf::from(format!("/proc/{}/status", child.id()));
        let mut peak_mb = 0.0f64;
        let status = loop {
            // Before try_wait: the child's status is readable until it is reaped.
            if let Some(mb) = fs::read_to_string(&status_path)
                .ok()
                .and_then(|s| vm_hwm_mb(&s))
            {
                peak_mb = peak_mb.max(mb);
            }
            if let Some(status) = child.try_wait().unwrap() {
                break Some(status);
            }
            if start.elapsed() > self.watchdog {
                let _ = child.kill();
                let _ = child.wait();
                break None;
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        let wall = start.elapsed().as_secs_f64();
        let stderr = fs::read_to_string(&err_path).unwrap_or_default();
        let outcome = match status {
            None => Outcome::Hang,
            Some(status) => {
                let outcome = self.classify(status, &stderr, &input, &output);
                // A case's own options may be refused by the option parser,
                // which says so in its own words (a usage error, not an input's).
                let usage = case_args.is_some()
                    && status.code() == Some(2)
                    && stderr.starts_with("error: ")
                    && stderr.contains("For more information, try '--help'")
                    && !output.exists();
                if usage { Outcome::Error(2) } else { outcome }
            }
        };
        let outcome = if self.poll_connections() > before {
            Outcome::Network
        } else if self
            .max_memory_mb
            .is_some_and(|max| peak_mb > max as f64 + MEMORY_MARGIN_MB)
        {
            Outcome::OverMemory(peak_mb.round() as u64)
        } else {
            outcome
        };
        if outcome.is_pass() {
            let _ = fs::remove_file(&input);
            let _ = fs::remove_file(&err_path);
            // Meshes of passing cases stay (CI checks target/test-out with gmsh).
        }
        Run {
            outcome,
            wall,
            peak_mb,
            stderr,
        }
    }

    fn classify(
        &self,
        status: std::process::ExitStatus,
        stderr: &str,
        input: &Path,
        output: &Path,
    ) -> Outcome {
        #[cfg(unix)]
        {
            use std::os::unix::process::ExitStatusExt;
            if let Some(sig) = status.signal() {
                return Outcome::Signal(sig);
            }
        }
        match status.code() {
            Some(0) => {
                if !output.is_file() {
                    return Outcome::Invalid("exit 0 without the .msh".into());
                }
                let check = Command::new(exe())
                    .arg("check")
                    .arg(output)
                    .output()
                    .expect("run triwild check");
                if check.status.code() != Some(0) {
                    return Outcome::Invalid(format!(
                        "triwild check exit {:?}: {}",
                        check.status.code(),
                        last_line(
                            &String::from_utf8_lossy(&check.stdout),
                            &String::from_utf8_lossy(&check.stderr)
                        )
                    ));
                }
                if let Some((python, script)) = &self.mshcheck {
                    let out = Command::new(python)
                        .arg(script)
                        .args(["--strict", "--require-ccw", "--indent", "0"])
                        .arg(output)
                        .output()
                        .expect("run mshcheck.py");
                    if !out.status.success() {
                        return Outcome::Invalid(format!(
                            "mshcheck.py exit {:?}: {}",
                            out.status.code(),
                            last_line(
                                &String::from_utf8_lossy(&out.stdout),
                                &String::from_utf8_lossy(&out.stderr)
                            )
                        ));
                    }
                }
                Outcome::Ok
            }
            Some(code @ (2..=4)) => {
                let lines: Vec<&str> = stderr.lines().collect();
                let named = [input, output]
                    .iter()
                    .any(|p| stderr.contains(&*p.to_string_lossy()));
                if lines.len() != 1 || !named {
                    Outcome::BadMessage(
                        code,
                        format!("{} line(s), names the file: {named}", lines.len()),
                    )
                } else if output.exists() {
                    Outcome::BadMessage(code, "an output file was left behind".into())
                } else {
                    Outcome::Error(code)
                }
            }
            Some(101) => Outcome::Panic,
            Some(code) => Outcome::OtherExit(code),
            None => Outcome::OtherExit(-1),
        }
    }
}

/// The options a case carries ([`ARGS_MARK`]), each with its `--` back.
fn case_args(bytes: &[u8]) -> Option<Vec<String>> {
    let rest = bytes.strip_prefix(ARGS_MARK.as_bytes())?;
    let text = String::from_utf8_lossy(rest);
    let (head, _) = text.split_once("-->")?;
    Some(
        head.lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .map(|l| format!("--{l}"))
            .collect(),
    )
}

/// `VmHWM` (peak resident memory) of a `/proc/<pid>/status` text, MiB.
fn vm_hwm_mb(status: &str) -> Option<f64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line["VmHWM:".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    Some(kb / 1024.0)
}

fn last_line(stdout: &str, stderr: &str) -> String {
    let text = if stderr.trim().is_empty() {
        stdout
    } else {
        stderr
    };
    text.lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("")
        .chars()
        .take(300)
        .collect()
}

fn replace_all(hay: &[u8], needle: &[u8], with: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(hay.len());
    let mut i = 0;
    while i < hay.len() {
        if hay[i..].starts_with(needle) {
            out.extend_from_slice(with);
            i += needle.len();
        } else {
            out.push(hay[i]);
            i += 1;
        }
    }
    out
}

#[derive(Clone, Debug, PartialEq)]
enum Outcome {
    Ok,
    /// Exit 2, 3 or 4 with one line naming the file.
    Error(i32),
    Panic,
    Signal(i32),
    Hang,
    Invalid(String),
    BadMessage(i32, String),
    OtherExit(i32),
    Network,
    /// The peak resident memory (MiB) passed `--max-memory` plus the margin.
    OverMemory(u64),
}

impl Outcome {
    fn is_pass(&self) -> bool {
        matches!(self, Outcome::Ok | Outcome::Error(_))
    }
    /// The failure class a shrunk case must keep.
    fn class(&self) -> &'static str {
        match self {
            Outcome::Ok => "ok",
            Outcome::Error(_) => "error",
            Outcome::Panic => "panic",
            Outcome::Signal(_) => "signal",
            Outcome::Hang => "hang",
            Outcome::Invalid(_) => "invalid",
            Outcome::BadMessage(..) => "bad-message",
            Outcome::OtherExit(_) => "other-exit",
            Outcome::Network => "network",
            Outcome::OverMemory(_) => "over-memory",
        }
    }
}

struct Run {
    outcome: Outcome,
    wall: f64,
    /// The child's peak resident memory, MiB (as last polled).
    peak_mb: f64,
    stderr: String,
}

// ---------------------------------------------------------------------------
// The grammar
// ---------------------------------------------------------------------------

fn fmt_num(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" {
        "0".into()
    } else {
        s.into()
    }
}

/// Numbers as text that are fine.
fn normal_num() -> BoxedStrategy<String> {
    prop_oneof![
        6 => (-10.0f64..110.0).prop_map(fmt_num),
        3 => (0i32..100).prop_map(|v| v.to_string()),
        1 => (-1e-4f64..1e-4).prop_map(|v| format!("{v:e}")),
    ]
    .boxed()
}

const EXTREME_NUMS: &[&str] = &[
    "1e-300",
    "-1e-300",
    "4.9e-324",
    "1e300",
    "-1e308",
    "1.7976931348623157e308",
    "1e39",
    "3.4e38",
    "-3.5e38",
    "1e20",
    "1e-20",
    "1e9",
    "-1e9",
    "NaN",
    "nan",
    "-NaN",
    "inf",
    "-inf",
    "Infinity",
    "-Infinity",
    "1e+999",
    "-1e999",
    "0",
    "-0",
    "0.0000000001",
    "1e",
    "--1",
    ".",
    ".5.5",
    "0x10",
    "1,",
    "+-3",
    "1e-7",
    "9999999999999999999999",
    "1E5",
    "5e-324",
];

/// Numbers as text that are tiny, huge, non-finite or not numbers at all.
fn extreme_num() -> BoxedStrategy<String> {
    prop::sample::select(EXTREME_NUMS)
        .prop_map(str::to_owned)
        .boxed()
}

/// Mostly normal numbers, sometimes extreme ones (weight `extreme` out of 20).
fn num(extreme: u32) -> BoxedStrategy<String> {
    if extreme == 0 {
        return normal_num();
    }
    prop_oneof![20 - extreme => normal_num(), extreme => extreme_num()].boxed()
}

fn nums(n: BoxedStrategy<String>, count: usize) -> BoxedStrategy<Vec<String>> {
    prop::collection::vec(n, count).boxed()
}

/// Path data from the commands M/L/H/V/C/S/Q/T/A/Z, absolute and relative.
fn path_data(n: BoxedStrategy<String>, max_cmds: usize) -> BoxedStrategy<String> {
    const CMDS: &[(char, usize)] = &[
        ('M', 2),
        ('m', 2),
        ('L', 2),
        ('l', 2),
        ('H', 1),
        ('h', 1),
        ('V', 1),
        ('v', 1),
        ('C', 6),
        ('c', 6),
        ('S', 4),
        ('s', 4),
        ('Q', 4),
        ('q', 4),
        ('T', 2),
        ('t', 2),
        ('A', 7),
        ('a', 7),
        ('Z', 0),
        ('z', 0),
    ];
    let cmd = (
        prop::sample::select(CMDS),
        nums(n.clone(), 7),
        any::<(bool, bool, bool)>(),
    )
        .prop_map(|((c, arity), mut v, (large, sweep, junk_flags))| {
            if matches!(c, 'A' | 'a') && !junk_flags {
                v[3] = u8::from(large).to_string();
                v[4] = u8::from(sweep).to_string();
            }
            let mut s = c.to_string();
            s.push_str(&v[..arity].join(" "));
            s
        });
    (
        nums(n, 2),
        prop::collection::vec(cmd, 0..max_cmds),
        any::<bool>(),
    )
        .prop_map(|(start, cmds, comma)| {
            let sep = if comma { "," } else { " " };
            format!("M{}{sep}{}", start.join(sep), cmds.join(" "))
        })
        .boxed()
}

fn transform(n: BoxedStrategy<String>) -> BoxedStrategy<String> {
    prop_oneof![
        nums(n.clone(), 2).prop_map(|v| format!("translate({},{})", v[0], v[1])),
        nums(n.clone(), 2).prop_map(|v| format!("scale({} {})", v[0], v[1])),
        nums(n.clone(), 3).prop_map(|v| format!("rotate({} {} {})", v[0], v[1], v[2])),
        n.clone().prop_map(|v| format!("skewX({v})")),
        n.clone().prop_map(|v| format!("skewY({v})")),
        nums(n.clone(), 6).prop_map(|v| format!("matrix({})", v.join(" "))),
        prop::sample::select(
            &[
                "scale(0)",
                "matrix(0 0 0 0 0 0)",
                "matrix(1 2 2 4 0 0)",
                "scale(1e30)",
                "scale(1e-30)",
                "scale(1e200)",
                "scale(-1 1)",
                "skewX(90)",
                "rotate(1e300)",
                "matrix(1 0 0 1 1e308 0)",
                "translate(1e308)",
                "scale(1,0)",
                "matrix(1e-300 0 0 1e-300 0 0)",
                "scale(NaN)",
                "translate(10) scale(2) rotate(45)",
                "scale(",
                "matrix(1 0 0 1)",
            ][..]
        )
        .prop_map(str::to_owned),
    ]
    .boxed()
}

const COLOURS: &[&str] = &[
    "black",
    "red",
    "#00f",
    "#123456",
    "none",
    "currentColor",
    "url(#g0)",
    "url(#nope)",
    "rgb(1,2,3)",
    "hsl(120, 50%, 50%)",
    "transparent",
    "#zzz",
    "inherit",
    "",
];
const JUNK: &[&str] = &[
    "",
    "junk",
    "-1",
    "1e999",
    "NaN",
    "10furlong",
    "1e3mm",
    "50%",
    "2em",
    "3ex",
    "1in",
    "72pt",
    "6pc",
    "2.54cm",
    "\u{1F600}",
    "&amp;",
    "&#0;",
    "&#x110000;",
    "<",
    "'\"",
    "  12  ",
    "1 2 3 4 5",
    "calc(1px+2px)",
    "var(--x)",
    "!important",
];

/// Presentation attributes, ids, transforms, and junk.
fn attrs(n: BoxedStrategy<String>, junk: u32) -> BoxedStrategy<String> {
    let id = prop::option::weighted(0.5, 0..6usize);
    let tf = prop::option::weighted(0.25, transform(n));
    let fill = prop::option::weighted(0.5, prop::sample::select(COLOURS));
    let rule = prop::option::weighted(
        0.3,
        prop::sample::select(&["evenodd", "nonzero", "junk"][..]),
    );
    let stroke = prop::option::weighted(
        0.2,
        (prop::sample::select(COLOURS), prop::sample::select(JUNK)),
    );
    let style = prop::option::weighted(
        0.15,
        prop::sample::select(
            &[
                "display:none",
                "visibility:hidden",
                "opacity:0",
                "fill:red;fill-rule:evenodd",
                "stroke:black;stroke-width:3",
                "fill:url(#g0)",
                "clip-path:url(#c0)",
                "mask:url(#m0)",
                "fill:;;;:",
                "font-size:1e30px",
                "transform:scale(2)",
            ][..],
        ),
    );
    let junk = prop::collection::vec(
        (
            prop::sample::select(
                &[
                    "x",
                    "width",
                    "r",
                    "points",
                    "d",
                    "class",
                    "xml:space",
                    "foo",
                    "xlink:href",
                    "style",
                    "filter",
                ][..],
            ),
            prop::sample::select(JUNK),
        ),
        0..=(junk as usize),
    );
    (id, tf, fill, rule, stroke, style, junk)
        .prop_map(|(id, tf, fill, rule, stroke, style, junk)| {
            let mut s = String::new();
            if let Some(id) = id {
                let _ = write!(s, r#" id="s{id}""#);
            }
            if let Some(tf) = tf {
                let _ = write!(s, r#" transform="{tf}""#);
            }
            if let Some(fill) = fill {
                let _ = write!(s, r#" fill="{fill}""#);
            }
            if let Some(rule) = rule {
                let _ = write!(s, r#" fill-rule="{rule}""#);
            }
            if let Some((colour, width)) = stroke {
                let _ = write!(s, r#" stroke="{colour}" stroke-width="{width}""#);
            }
            if let Some(style) = style {
                let _ = write!(s, r#" style="{style}""#);
            }
            for (name, value) in junk {
                // a repeated attribute is broken XML: a fine case too, but rarely
                if !s.contains(&format!(" {name}=")) {
                    let _ = write!(s, r#" {name}="{}""#, xml_escape_attr(value));
                }
            }
            s
        })
        .boxed()
}

/// `text` without any ` NAME="..."` attribute.
fn strip_attr(text: &str, name: &str) -> String {
    let key = format!(" {name}=\"");
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(i) = rest.find(&key) {
        out.push_str(&rest[..i]);
        let after = &rest[i + key.len()..];
        rest = after.find('"').map_or("", |j| &after[j + 1..]);
    }
    out.push_str(rest);
    out
}

fn xml_escape_attr(v: &str) -> String {
    v.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('"', "&quot;")
}

/// One shape element.
fn shape(
    n: BoxedStrategy<String>,
    a: BoxedStrategy<String>,
    max_cmds: usize,
) -> BoxedStrategy<String> {
    prop_oneof![
        4 => (path_data(n.clone(), max_cmds), a.clone()).prop_map(|(d, a)| format!(r#"<path d="{d}"{a}/>"#)),
        2 => (nums(n.clone(), 5), any::<bool>(), a.clone()).prop_map(|(v, rx, a)| {
            let rx = if rx { format!(r#" rx="{}""#, v[4]) } else { String::new() };
            format!(r#"<rect x="{}" y="{}" width="{}" height="{}"{rx}{a}/>"#, v[0], v[1], v[2], v[3])
        }),
        2 => (nums(n.clone(), 3), a.clone()).prop_map(|(v, a)| format!(r#"<circle cx="{}" cy="{}" r="{}"{a}/>"#, v[0], v[1], v[2])),
        1 => (nums(n.clone(), 4), a.clone()).prop_map(|(v, a)| format!(r#"<ellipse cx="{}" cy="{}" rx="{}" ry="{}"{a}/>"#, v[0], v[1], v[2], v[3])),
        1 => (nums(n.clone(), 4), a.clone()).prop_map(|(v, a)| format!(r#"<line x1="{}" y1="{}" x2="{}" y2="{}"{a}/>"#, v[0], v[1], v[2], v[3])),
        2 => (prop::sample::select(&["polyline", "polygon"][..]), prop::collection::vec(n.clone(), 0..14), a.clone())
            .prop_map(|(tag, v, a)| format!(r#"<{tag} points="{}"{a}/>"#, v.join(" "))),
        1 => (nums(n, 3), prop::sample::select(&["A", "Hi", "\u{263A}", "", "ff", "&amp;"][..]), a)
            .prop_map(|(v, t, a)| format!(r#"<text x="{}" y="{}" font-size="{}"{a}>{t}</text>"#, v[0], v[1], v[2])),
    ]
    .boxed()
}

/// A `<use>` of one of the ids `s0`..`s5` (or of nothing).
fn use_elem(n: BoxedStrategy<String>, a: BoxedStrategy<String>) -> BoxedStrategy<String> {
    (0..7usize, any::<bool>(), nums(n, 2), a)
        .prop_map(|(k, xlink, v, a)| {
            let attr = if xlink { "xlink:href" } else { "href" };
            format!(r##"<use {attr}="#s{k}" x="{}" y="{}"{a}/>"##, v[0], v[1])
        })
        .boxed()
}

/// A tree of containers over shapes and uses.
fn tree(
    n: BoxedStrategy<String>,
    a: BoxedStrategy<String>,
    max_cmds: usize,
    depth: u32,
) -> BoxedStrategy<String> {
    let leaf = prop_oneof![
        5 => shape(n.clone(), a.clone(), max_cmds),
        1 => use_elem(n.clone(), a.clone()),
    ];
    leaf.prop_recursive(depth, 24, 4, move |inner| {
        let kids = prop::collection::vec(inner, 0..5).prop_map(|v| v.concat());
        prop_oneof![
            4 => (a.clone(), kids.clone()).prop_map(|(a, k)| format!("<g{a}>{k}</g>")),
            1 => kids.clone().prop_map(|k| format!("<defs>{k}</defs>")),
            1 => (0..6usize, nums(n.clone(), 4), kids.clone())
                .prop_map(|(id, v, k)| format!(r#"<symbol id="s{id}" viewBox="{}">{k}</symbol>"#, v.join(" "))),
            1 => (nums(n.clone(), 4), kids.clone()).prop_map(|(v, k)| {
                format!(r#"<svg x="{}" y="{}" width="{}" height="{}">{k}</svg>"#, v[0], v[1], v[2], v[3])
            }),
            1 => kids.clone().prop_map(|k| format!(r#"<clipPath id="c0">{k}</clipPath>"#)),
            1 => kids.clone().prop_map(|k| format!(r#"<mask id="m0">{k}</mask>"#)),
            1 => kids.prop_map(|k| format!("<switch><foo/>{k}</switch>")),
        ]
    })
    .boxed()
}

const CSS: &[&str] = &[
    "path { fill: red; fill-rule: evenodd }",
    "* { fill: none !important; stroke: black }",
    "#s0 { display: none } .a { fill: blue }",
    "rect:first-child { transform: scale(0) }",
    "@media screen { path { fill: green } }",
    "@import url(@URL@);",
    "@font-face { font-family: x; src: url(@FIFO@) }",
    "g > circle + rect ~ path { fill: url(#g0) }",
    "{{{{ ;;; }",
    "path { fill: red",
    "svg|path { fill: red }",
    "* { stroke-width: 1e300 }",
];

/// A whole document: root attributes (viewBox or not, sizes in odd units), an
/// optional style sheet and gradient, and a tree.
fn document(
    n: BoxedStrategy<String>,
    junk: u32,
    max_cmds: usize,
    depth: u32,
) -> BoxedStrategy<String> {
    let a = attrs(n.clone(), junk);
    // mostly a sane viewBox (a random one is mostly an invalid size)
    let sane = (0.0f64..20.0, 0.0f64..20.0, 20.0f64..200.0, 20.0f64..200.0)
        .prop_map(|(x, y, w, h)| vec![fmt_num(-x), fmt_num(-y), fmt_num(w), fmt_num(h)]);
    let viewbox = prop::option::weighted(0.85, prop_oneof![3 => sane, 1 => nums(n.clone(), 4)]);
    let size = prop::option::weighted(
        0.5,
        (
            n.clone(),
            prop::sample::select(
                &[
                    "", "px", "mm", "cm", "in", "pt", "pc", "em", "ex", "%", "furlong",
                ][..],
            ),
        ),
    );
    let par = prop::option::weighted(
        0.2,
        prop::sample::select(&["none", "xMidYMid slice", "xMinYMax meet", "junk"][..]),
    );
    let css = prop::option::weighted(0.15, prop::sample::select(CSS));
    // a few top-level trees: one <defs> at the top would hide everything
    let body = prop::collection::vec(tree(n, a, max_cmds, depth), 1..4).prop_map(|v| v.concat());
    (viewbox, size, par, css, any::<bool>(), body)
        .prop_map(|(viewbox, size, par, css, gradient, body)| {
            let mut s = String::from(
                r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink""#,
            );
            if let Some(v) = viewbox {
                let _ = write!(s, r#" viewBox="{}""#, v.join(" "));
            }
            if let Some((w, unit)) = size {
                let _ = write!(s, r#" width="{w}{unit}" height="{w}{unit}""#);
            }
            if let Some(p) = par {
                let _ = write!(s, r#" preserveAspectRatio="{p}""#);
            }
            s.push('>');
            if let Some(css) = css {
                let _ = write!(s, "<style>{css}</style>");
            }
            if gradient {
                s.push_str(r#"<linearGradient id="g0"><stop offset="0" stop-color="red"/></linearGradient>"#);
            }
            s.push_str(&body);
            s.push_str("</svg>");
            s
        })
        .boxed()
}

fn plain_doc() -> BoxedStrategy<String> {
    document(num(2), 1, 8, 3)
}

fn svg(body: &str) -> String {
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" viewBox="0 0 100 100">{body}</svg>"#
    )
}

// ---------------------------------------------------------------------------
// Attack generators
// ---------------------------------------------------------------------------

/// Degenerate geometry: zero-length segments, collinear points, coincident
/// subpaths, nearly parallel curves, at tiny and huge scales.
fn degenerate() -> BoxedStrategy<String> {
    let scale = prop::sample::select(&[1.0, 1e-9, 1e-6, 1e6, 1e12, 1e-300, 1e300][..]);
    let pt = (-50.0f64..50.0, -50.0f64..50.0);
    let shape = prop_oneof![
        // zero-length segments and repeated points
        (pt.clone(), 1..20usize).prop_map(|((x, y), k)| (
            format!("M{x} {y}") + &format!(" L{x} {y}").repeat(k) + " Z",
            "zero-length"
        )),
        // collinear points on one line
        (
            pt.clone(),
            pt.clone(),
            prop::collection::vec(-2.0f64..2.0, 2..10)
        )
            .prop_map(|((x, y), (dx, dy), ts)| {
                let mut d = format!("M{x} {y}");
                for t in ts {
                    let _ = write!(d, " L{} {}", x + t * dx, y + t * dy);
                }
                (d + " Z", "collinear")
            }),
        // the same subpath twice, and a triangle inside itself reversed
        (pt.clone(), pt.clone(), pt.clone()).prop_map(|((a, b), (c, d), (e, f))| {
            let sub = format!("M{a} {b} L{c} {d} L{e} {f} Z");
            (
                format!("{sub} {sub} M{a} {b} L{e} {f} L{c} {d} Z"),
                "coincident",
            )
        }),
        // two cubics a hair apart
        (
            pt.clone(),
            pt.clone(),
            prop::sample::select(&[1e-12, 1e-9, 1e-6, 1e-3][..])
        )
            .prop_map(|((x, y), (u, v), eps)| {
                (
                    format!(
                        "M{x} {y} C{u} {v} {v} {u} {y} {x} M{} {y} C{} {v} {v} {u} {y} {}",
                        x + eps,
                        u + eps,
                        x + eps
                    ),
                    "nearly-parallel",
                )
            }),
        // a cubic whose control points coincide with its ends, an arc of radius 0
        pt.prop_map(|(x, y)| (
            format!("M{x} {y} C{x} {y} {x} {y} {x} {y} A0 0 0 0 1 {x} {y} Q{x} {y} {x} {y} Z"),
            "degenerate-curve"
        )),
    ];
    (prop::collection::vec(shape, 1..5), scale, any::<bool>())
        .prop_map(|(shapes, scale, evenodd)| {
            let rule = if evenodd { "evenodd" } else { "nonzero" };
            let body: String = shapes
                .iter()
                .map(|(d, _)| {
                    format!(r#"<path transform="scale({scale:e})" fill-rule="{rule}" d="{d}"/>"#)
                })
                .collect();
            svg(&body)
        })
        .boxed()
}

/// Internal entities, nested (a billion laughs), recursive, or expanding to markup.
fn entity_bomb() -> BoxedStrategy<String> {
    (1..12usize, 2..12usize, 0..4u8).prop_map(|(depth, fanout, form)| {
        let mut dtd = String::new();
        match form {
            0 => dtd.push_str("<!ENTITY e0 \"<rect width='1' height='1'/>\">"),
            1 => dtd.push_str("<!ENTITY e0 \"M0 0 L1 1 L1 0 Z \">"),
            2 => dtd.push_str("<!ENTITY e0 \"lol\">"),
            _ => {
                let _ = write!(dtd, "<!ENTITY e0 \"&e{depth};\">");
            }
        }
        for i in 1..=depth {
            let _ = write!(dtd, "<!ENTITY e{i} \"{}\">", format!("&e{};", i - 1).repeat(fanout));
        }
        let body = match form {
            0 | 3 => format!("&e{depth};"),
            1 => format!(r#"<path d="&e{depth};"/>"#),
            _ => format!(r#"<text x="1" y="9">&e{depth};</text><rect width="5" height="5"/>"#),
        };
        format!(
            r#"<?xml version="1.0"?><!DOCTYPE svg [{dtd}]><svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10">{body}</svg>"#
        )
    })
    .boxed()
}

/// `<use>` cycles: a use of itself, of its ancestor, mutual, through a symbol.
fn use_cycle() -> BoxedStrategy<String> {
    prop::sample::select(&[
        r##"<use id="u" href="#u"/><rect width="9" height="9"/>"##,
        r##"<g id="g"><rect width="9" height="9"/><use href="#g" x="1"/></g>"##,
        r##"<use id="a" href="#b"/><use id="b" href="#a"/><circle r="5" cx="50" cy="50"/>"##,
        r##"<symbol id="s"><use href="#t"/></symbol><g id="t"><use href="#s"/><rect width="3" height="3"/></g>"##,
        r##"<defs><g id="p"><use xlink:href="#q"/></g><g id="q"><use xlink:href="#r"/></g><g id="r"><use xlink:href="#p"/></g></defs><use href="#p"/><rect width="9" height="9"/>"##,
        r##"<pattern id="pt"><rect fill="url(#pt)" width="1" height="1"/></pattern><rect fill="url(#pt)" width="9" height="9"/>"##,
        r##"<clipPath id="c"><rect clip-path="url(#c)" width="5" height="5"/></clipPath><rect clip-path="url(#c)" width="9" height="9"/>"##,
        r##"<g id="x"><use href="#x"/><use href="#x"/></g>"##,
    ][..])
    .prop_map(svg)
    .boxed()
}

/// Deep `<use>` chains: linear (u_k uses u_{k-1}) or doubling (two uses of the previous).
fn use_chain() -> BoxedStrategy<String> {
    (
        prop::sample::select(&[10usize, 100, 500, 1000, 3000][..]),
        1..4usize,
    )
        .prop_map(|(depth, fan)| {
            let fan = if depth > 100 { 1 } else { fan };
            let depth = if fan > 1 { depth.min(40) } else { depth };
            let mut body = String::from(r#"<defs><path id="u0" d="M0 0 L3 0 L0 3 Z"/>"#);
            for k in 1..depth {
                let _ = write!(body, r#"<g id="u{k}">"#);
                for f in 0..fan {
                    let _ = write!(body, r##"<use href="#u{}" x="{}"/>"##, k - 1, f);
                }
                body.push_str("</g>");
            }
            let _ = write!(body, r##"</defs><use href="#u{}"/>"##, depth - 1);
            svg(&body)
        })
        .boxed()
}

/// Deep group (or nested svg) nesting.
fn deep_nesting() -> BoxedStrategy<String> {
    (
        prop::sample::select(&[10usize, 100, 500, 1000, 1100, 5000, 20000][..]),
        0..3u8,
    )
        .prop_map(|(depth, form)| {
            let (open, close) = match form {
                0 => ("<g>", "</g>"),
                1 => (r#"<g transform="scale(1.01)">"#, "</g>"),
                _ => (r#"<svg viewBox="0 0 100 100">"#, "</svg>"),
            };
            svg(&(open.repeat(depth)
                + r#"<rect x="10" y="10" width="50" height="50"/>"#
                + &close.repeat(depth)))
        })
        .boxed()
}

/// The same shape many times, exactly or with tiny offsets.
fn duplicates() -> BoxedStrategy<String> {
    (
        prop::sample::select(&[2usize, 10, 100, 1000, 3000][..]),
        prop::sample::select(&[0.0, 1e-12, 1e-6, 0.01][..]),
        0..3u8,
    )
        .prop_map(|(count, eps, form)| {
            let mut body = String::new();
            for i in 0..count {
                let o = i as f64 * eps;
                let _ = match form {
                    0 => write!(
                        body,
                        r#"<rect x="{}" y="10" width="50" height="40"/>"#,
                        10.0 + o
                    ),
                    1 => write!(
                        body,
                        r#"<circle cx="{}" cy="50" r="30" fill="none" stroke="black"/>"#,
                        50.0 + o
                    ),
                    _ => write!(
                        body,
                        r#"<path d="M10 10 C 40 {} 60 90 90 10 Z"/>"#,
                        90.0 + o
                    ),
                };
            }
            svg(&body)
        })
        .boxed()
}

/// One path of many segments: random zigzag, a fine polygon circle, or cubics.
fn big_path(max: usize) -> BoxedStrategy<String> {
    let sizes: Vec<usize> = [1_000, 10_000, 100_000]
        .into_iter()
        .map(|s| s.min(max))
        .collect();
    (prop::sample::select(sizes), 0..3u8, any::<u64>())
        .prop_map(|(n, form, seed)| {
            let mut r = seed | 1;
            let mut rnd = move || {
                r ^= r << 13;
                r ^= r >> 7;
                r ^= r << 17;
                (r % 100_000) as f64 / 1000.0
            };
            let mut d = String::with_capacity(n * 16);
            d.push_str("M50 50");
            for i in 0..n {
                let _ = match form {
                    0 => write!(d, "L{:.3} {:.3}", rnd(), rnd()),
                    1 => {
                        let t = i as f64 / n as f64 * std::f64::consts::TAU;
                        write!(
                            d,
                            "L{:.5} {:.5}",
                            50.0 + 40.0 * t.cos(),
                            50.0 + 40.0 * t.sin()
                        )
                    }
                    _ => write!(
                        d,
                        "c{:.2} {:.2} {:.2} {:.2} {:.2} {:.2}",
                        rnd() / 50.0 - 1.0,
                        rnd() / 50.0,
                        rnd() / 50.0,
                        rnd() / 50.0 - 1.0,
                        0.01,
                        0.0
                    ),
                };
            }
            svg(&format!(r#"<path d="{d}Z"/>"#))
        })
        .boxed()
}

/// References outside the document: nothing may be read or fetched.
fn external_ref() -> BoxedStrategy<String> {
    let in_body = prop::sample::select(&[
        r##"<use xlink:href="@FIFO@#a"/><rect width="9" height="9"/>"##,
        r##"<use href="@URL@#a"/><rect width="9" height="9"/>"##,
        r##"<use href="file://@FIFO@#a"/><rect width="9" height="9"/>"##,
        r##"<image href="@FIFO@" width="50" height="50"/><rect width="9" height="9"/>"##,
        r##"<image xlink:href="@URL@" width="50" height="50"/><rect width="9" height="9"/>"##,
        r##"<image href="file://@FIFO@" width="10" height="10"/><circle cx="50" cy="50" r="9"/>"##,
        r##"<rect fill="url(@FIFO@#g)" width="9" height="9"/>"##,
        r##"<rect filter="url(@URL@#f)" width="9" height="9"/>"##,
        r##"<style>@import url("@URL@"); rect { fill: red }</style><rect width="9" height="9"/>"##,
        r##"<style>@import "@FIFO@";</style><rect width="9" height="9"/>"##,
        r##"<text x="1" y="9" style="font-family: url(@FIFO@)">A</text><rect width="9" height="9"/>"##,
        r##"<filter id="f"><feImage href="@FIFO@"/></filter><rect filter="url(#f)" width="9" height="9"/>"##,
        r##"<script href="@URL@"/><rect width="9" height="9"/>"##,
        r##"<foreignObject><iframe xmlns="http://www.w3.org/1999/xhtml" src="@URL@"/></foreignObject><rect width="9" height="9"/>"##,
    ][..])
    .prop_map(svg);
    let entity = prop::sample::select(&["SYSTEM \"@FIFO@\"", "SYSTEM \"file://@FIFO@\"", "SYSTEM \"@URL@\"", "PUBLIC \"-//x\" \"@URL@\""][..])
        .prop_map(|ext| {
            format!(
                r#"<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY ext {ext}>]><svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><rect width="5" height="5"/>&ext;</svg>"#
            )
        });
    let doctype = Just(
        r#"<?xml version="1.0"?><!DOCTYPE svg SYSTEM "@FIFO@"><svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><rect width="5" height="5"/></svg>"#.to_owned(),
    );
    prop_oneof![6 => in_body, 2 => entity, 1 => doctype].boxed()
}

// ---------------------------------------------------------------------------
// Byte-level mutations
// ---------------------------------------------------------------------------

fn at(len: usize, r: u64) -> usize {
    if len == 0 {
        0
    } else {
        (r % (len as u64 + 1)) as usize
    }
}

fn truncate(doc: &[u8], r: u64) -> Vec<u8> {
    doc[..at(doc.len(), r)].to_vec()
}

fn splice(a: &[u8], b: &[u8], r1: u64, r2: u64) -> Vec<u8> {
    let mut out = a[..at(a.len(), r1)].to_vec();
    out.extend_from_slice(&b[at(b.len(), r2)..]);
    out
}

fn flip(doc: &[u8], flips: &[(u64, u8)]) -> Vec<u8> {
    let mut out = doc.to_vec();
    for &(r, x) in flips {
        if !out.is_empty() {
            let i = (r % out.len() as u64) as usize;
            out[i] ^= x.max(1);
        }
    }
    out
}

fn dup_range(doc: &[u8], r1: u64, r2: u64, r3: u64, times: usize) -> Vec<u8> {
    let (i, j) = (at(doc.len(), r1), at(doc.len(), r2));
    let (i, j) = (i.min(j), i.max(j));
    let k = at(doc.len(), r3);
    let mut out = doc[..k].to_vec();
    for _ in 0..times {
        out.extend_from_slice(&doc[i..j]);
    }
    out.extend_from_slice(&doc[k..]);
    out
}

/// A DOCTYPE with one entity before the root, its reference put at a byte offset
/// (often inside an attribute value or a tag: a fine case too).
fn insert_entity(doc: &[u8], value: &str, r: u64) -> Vec<u8> {
    let Some(root) = doc.windows(4).position(|w| w == b"<svg") else {
        return doc.to_vec();
    };
    let mut out = doc[..root].to_vec();
    out.extend_from_slice(format!("<!DOCTYPE svg [<!ENTITY x \"{value}\">]>").as_bytes());
    let rest = &doc[root..];
    let k = at(rest.len(), r);
    out.extend_from_slice(&rest[..k]);
    out.extend_from_slice(b"&x;");
    out.extend_from_slice(&rest[k..]);
    out
}

const BAD_UTF8: &[&[u8]] = &[
    b"\xff",
    b"\xfe\xff",
    b"\xc3",
    b"\xc0\xaf",
    b"\xe2\x82",
    b"\xed\xa0\x80",
    b"\xf8\x88\x80\x80\x80",
    b"\x80",
    b"\0",
];

fn invalid_utf8(doc: &[u8], inserts: &[(u64, usize)], utf16: bool) -> Vec<u8> {
    let mut out = doc.to_vec();
    for &(r, k) in inserts {
        let i = at(out.len(), r);
        let bad = BAD_UTF8[k % BAD_UTF8.len()];
        out.splice(i..i, bad.iter().copied());
    }
    if utf16 {
        // a byte-order mark and an odd number of bytes after it
        let mut v = b"\xff\xfe".to_vec();
        v.extend(out.iter().flat_map(|&b| [b, 0]));
        v.push(b'<');
        return v;
    }
    out
}

const ENTITY_VALUES: &[&str] = &[
    "<rect width='5' height='5'/>",
    "M0 0 L1 1",
    "1e308",
    "&#0;",
    "<g>",
    "&amp;&lt;",
    "lol",
    "",
];

/// Mutations of the real drawings (read from `data/svg` when the strategy is built).
/// The drawings of `data/svg`, in a fixed order.
fn data_drawings() -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg");
    let mut drawings: Vec<Vec<u8>> = fs::read_dir(&dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "svg"))
                .map(|p| fs::read(p).unwrap())
                .collect()
        })
        .unwrap_or_default();
    drawings.sort();
    assert!(!drawings.is_empty(), "no drawings under {}", dir.display());
    drawings
}

fn real_drawing() -> BoxedStrategy<Vec<u8>> {
    let drawings = data_drawings();
    let pick = prop::sample::select(drawings);
    let r = any::<(u64, u64, u64)>();
    (pick, 0..7u8, r, extreme_num(), transform(num(4)))
        .prop_map(|(doc, form, (r1, r2, r3), extreme, tf)| match form {
            0 => truncate(&doc, r1),
            1 => flip(&doc, &[(r1, r2 as u8), (r3, (r1 >> 8) as u8)]),
            2 => dup_range(&doc, r1, r2, r3, 1 + (r3 % 3) as usize),
            // the k-th number replaced by an extreme one
            3 => replace_number(&doc, r1, &extreme),
            // a transform on the k-th element (where it has none)
            4 => {
                let text = String::from_utf8_lossy(&doc).into_owned();
                let tags: Vec<usize> = text
                    .match_indices("<path")
                    .chain(text.match_indices("<g"))
                    .map(|(i, _)| i)
                    .collect();
                if tags.is_empty() {
                    doc
                } else {
                    let i = tags[(r1 % tags.len() as u64) as usize];
                    let j = text[i..]
                        .find(|c: char| c.is_whitespace() || c == '>')
                        .map_or(text.len(), |j| i + j);
                    format!("{} transform=\"{tf}\"{}", &text[..j], &text[j..]).into_bytes()
                }
            }
            // the whole body in deep groups
            5 => {
                let text = String::from_utf8_lossy(&doc).into_owned();
                let depth = [10, 200, 1200][(r1 % 3) as usize];
                match (
                    text.find("<svg")
                        .and_then(|i| text[i..].find('>').map(|j| i + j + 1)),
                    text.rfind("</svg>"),
                ) {
                    (Some(open), Some(close)) if open <= close => format!(
                        "{}{}{}{}{}",
                        &text[..open],
                        "<g>".repeat(depth),
                        &text[open..close],
                        "</g>".repeat(depth),
                        &text[close..]
                    )
                    .into_bytes(),
                    _ => doc,
                }
            }
            _ => invalid_utf8(&doc, &[(r1, r2 as usize)], false),
        })
        .boxed()
}

/// Size formulas: plain, with exponents, graded, trigonometric, and some
/// that parse but give no size somewhere (zero, negative, NaN, infinite) or
/// do not parse.
const SIZE_EXPRS: &[&str] = &[
    "0.5",
    "1e-3",
    "2.5E+1",
    "0.05 + 0.01*abs(x)",
    "1 + 0*y",
    "0.1 + 0.1*sin(x)^2",
    "exp(-x*x)",
    "1e-300",
    "1e300",
    "x",
    "0",
    "-1",
    "1/0",
    "sqrt(-1)",
    "2x",
    "((1)",
    "0.2*(1.5 + cos(x/7)*sin(y/5))",
    "1e-9 + 0*x",
    "z",
];

/// Numbers for the options: ordinary ones (four times in five, so that most
/// cases mesh) ...
const OPTION_NUMS: &[&str] = &["0.5", "0.1", "0.02", "1", "3", "10", "1.5", "0.05", "2e-2"];
/// ... and tiny, huge, zero, negative and not finite ones.
const ODD_OPTION_NUMS: &[&str] = &["1e-9", "1e-300", "1e9", "1e300", "0", "-1", "NaN", "inf"];

/// One option, without its `--` (see [`ARGS_MARK`]), from a menu of every
/// kind the command line has: element order and format, units and scale,
/// regions and holes, strokes, every size field, the envelopes and the
/// optimizer's limits.
fn one_option() -> BoxedStrategy<String> {
    let n = || {
        prop_oneof![
            4 => prop::sample::select(OPTION_NUMS),
            1 => prop::sample::select(ODD_OPTION_NUMS),
        ]
    };
    let name = || {
        prop_oneof![
            4 => prop::sample::select(&["background", "shape-0"][..]),
            1 => prop::sample::select(&["shape-1", "domain", "fill-#000000", "nope"][..]),
        ]
    };
    prop_oneof![
        prop::sample::select(
            &[
                "order=1",
                "order=2",
                "order=3",
                "linear",
                "stop-after=bsp",
                "stop-after=optimize",
                "mesher=cdt",
                "msh-version=2.2",
                "binary",
                "units=px",
                "regions=colour",
                "regions=none",
                "regions=shape",
                "cut-outside",
                "strokes=line",
                "strokes=ignore",
                "strokes=area",
                "keep-decoration",
                "feature-size=on",
                "threads=2",
                "edge-length=0.1",
                "edge-length=0.2",
                "edge-length=0.05",
                "edge-length=0.03",
                "max-passes=0",
                "max-passes=1",
                "max-passes-curved=0",
                "max-vertices=16",
                "max-vertices=300",
                "stop-energy=1",
                "stop-energy=50",
                "min-opacity=0",
                "min-opacity=1",
                "alpha=1",
                "alpha=59.9"
            ][..]
        )
        .prop_map(str::to_owned),
        (
            prop::sample::select(
                &[
                    "scale",
                    "grading",
                    "mu",
                    "eps",
                    "padding",
                    "eps-m",
                    "min-edge-length",
                    "alpha",
                    "stop-energy",
                    "stop-energy-curved",
                    "edge-length",
                    "edge-length-abs",
                    "mu-abs",
                    "padding-abs",
                    "min-opacity",
                    "cdt-min-angle"
                ][..]
            ),
            n()
        )
            .prop_map(|(k, v)| format!("{k}={v}")),
        prop::sample::select(SIZE_EXPRS).prop_map(|e| format!("size-expr={e}")),
        (name(), n()).prop_map(|(r, v)| format!("size={r}={v}")),
        (name(), n(), prop::option::of(n())).prop_map(|(r, v, d)| match d {
            Some(d) => format!("size-near={r}={v}:{d}"),
            None => format!("size-near={r}={v}"),
        }),
        (prop::collection::vec(n(), 4), n())
            .prop_map(|(c, v)| format!("size-box={}={v}", c.join(","))),
        (n(), n()).prop_map(|(x, y)| format!("hole={x},{y}")),
        name().prop_map(|r| format!("keep={r}")),
    ]
    .boxed()
}

/// A drawing of `data/svg` (or a grammar document) with one to five options
/// of [`one_option`]: what the options do to a good input, and to an odd one.
fn with_options() -> BoxedStrategy<Vec<u8>> {
    let drawings = data_drawings();
    let doc = prop_oneof![
        3 => prop::sample::select(drawings),
        1 => plain_doc().prop_map(String::into_bytes),
    ];
    (doc, prop::collection::vec(one_option(), 1..6))
        .prop_map(|(doc, mut opts)| {
            // each option once (the parser refuses most twice)
            let mut seen = std::collections::HashSet::new();
            opts.retain(|o| seen.insert(o.split('=').next().unwrap_or(o).to_owned()));
            // the mark leads the case, so an XML declaration (which must come
            // first in a document) is left out
            let text = String::from_utf8_lossy(&doc);
            let body = match text.trim_start().strip_prefix("<?xml") {
                Some(rest) => rest.split_once("?>").map_or("", |(_, b)| b),
                None => &text,
            };
            format!("{ARGS_MARK}\n{}\n-->\n{body}", opts.join("\n")).into_bytes()
        })
        .boxed()
}

fn replace_number(doc: &[u8], r: u64, with: &str) -> Vec<u8> {
    let text = String::from_utf8_lossy(doc);
    let mut spans = Vec::new();
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() {
            let s = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            spans.push((s, i));
        } else {
            i += 1;
        }
    }
    if spans.is_empty() {
        return doc.to_vec();
    }
    let (s, e) = spans[(r % spans.len() as u64) as usize];
    format!("{}{with}{}", &text[..s], &text[e..]).into_bytes()
}

// ---------------------------------------------------------------------------
// The kinds
// ---------------------------------------------------------------------------

fn bytes(s: BoxedStrategy<String>) -> BoxedStrategy<Vec<u8>> {
    s.prop_map(String::into_bytes).boxed()
}

/// Every mutation kind and its strategy; cases go round-robin over these.
fn kinds(max_path_segments: usize) -> Vec<(&'static str, BoxedStrategy<Vec<u8>>)> {
    let doc = || plain_doc().prop_map(String::into_bytes);
    let r = || any::<(u64, u64, u64)>();
    vec![
        ("grammar", bytes(document(num(0), 0, 10, 4))),
        ("numbers", bytes(document(num(8), 0, 10, 2))),
        ("degenerate", bytes(degenerate())),
        (
            "transforms",
            bytes(
                document(num(0), 0, 6, 4)
                    .prop_flat_map(|d| {
                        // a transform on every container and shape (theirs removed)
                        let d = strip_attr(&d, "transform");
                        transform(num(6)).prop_map(move |tf| {
                            d.replace("<g", &format!("<g transform=\"{tf}\""))
                                .replace("<path ", &format!("<path transform=\"{tf}\" "))
                        })
                    })
                    .boxed(),
            ),
        ),
        ("junk-attrs", bytes(document(num(3), 4, 6, 3))),
        (
            "css",
            bytes(
                (
                    document(num(0), 1, 6, 3),
                    prop::collection::vec(prop::sample::select(CSS), 1..4),
                    any::<bool>(),
                )
                    .prop_map(|(d, css, class)| {
                        let d = if class {
                            d.replace("<path ", "<path class=\"a\" ")
                        } else {
                            d
                        };
                        let at = d.find('>').map_or(0, |i| i + 1);
                        format!("{}<style>{}</style>{}", &d[..at], css.concat(), &d[at..])
                    })
                    .boxed(),
            ),
        ),
        ("entity-bomb", bytes(entity_bomb())),
        ("use-cycle", bytes(use_cycle())),
        ("use-chain", bytes(use_chain())),
        ("deep-nesting", bytes(deep_nesting())),
        ("duplicates", bytes(duplicates())),
        ("big-path", bytes(big_path(max_path_segments))),
        ("external-ref", bytes(external_ref())),
        (
            "invalid-utf8",
            (
                doc(),
                prop::collection::vec((any::<u64>(), any::<usize>()), 1..4),
                prop::bool::weighted(0.2),
            )
                .prop_map(|(d, ins, utf16)| invalid_utf8(&d, &ins, utf16))
                .boxed(),
        ),
        (
            "truncate",
            (doc(), any::<u64>())
                .prop_map(|(d, r)| truncate(&d, r))
                .boxed(),
        ),
        (
            "splice",
            (doc(), doc(), r())
                .prop_map(|(a, b, (r1, r2, _))| splice(&a, &b, r1, r2))
                .boxed(),
        ),
        (
            "flip-byte",
            (
                doc(),
                prop::collection::vec((any::<u64>(), any::<u8>()), 1..8),
            )
                .prop_map(|(d, f)| flip(&d, &f))
                .boxed(),
        ),
        (
            "dup-range",
            (doc(), r(), 1..50usize)
                .prop_map(|(d, (r1, r2, r3), t)| dup_range(&d, r1, r2, r3, t))
                .boxed(),
        ),
        (
            "insert-entity",
            (doc(), prop::sample::select(ENTITY_VALUES), any::<u64>())
                .prop_map(|(d, v, r)| insert_entity(&d, v, r))
                .boxed(),
        ),
        ("real-drawing", real_drawing()),
        ("options", with_options()),
    ]
}

// ---------------------------------------------------------------------------
// The run
// ---------------------------------------------------------------------------

/// A per-case random source: the case is reproducible from (seed, index) alone.
fn case_runner(seed: u64, index: usize) -> TestRunner {
    let mut key = [0u8; 32];
    let mut x = seed ^ (index as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    for chunk in key.chunks_mut(8) {
        // splitmix64
        x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = x;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        chunk.copy_from_slice(&(z ^ (z >> 31)).to_le_bytes());
    }
    TestRunner::new_with_rng(
        Config::default(),
        TestRng::from_seed(RngAlgorithm::ChaCha, &key),
    )
}

#[derive(Default, Clone)]
struct Row {
    cases: usize,
    ok: usize,
    exit2: usize,
    exit3: usize,
    exit4: usize,
    panics: usize,
    signals: usize,
    hangs: usize,
    invalid: usize,
    other: usize,
    max_wall: f64,
    max_peak_mb: f64,
}

impl Row {
    fn add(&mut self, run: &Run) {
        self.cases += 1;
        self.max_wall = self.max_wall.max(run.wall);
        self.max_peak_mb = self.max_peak_mb.max(run.peak_mb);
        match run.outcome {
            Outcome::Ok => self.ok += 1,
            Outcome::Error(2) => self.exit2 += 1,
            Outcome::Error(3) => self.exit3 += 1,
            Outcome::Error(_) => self.exit4 += 1,
            Outcome::Panic => self.panics += 1,
            Outcome::Signal(_) => self.signals += 1,
            Outcome::Hang => self.hangs += 1,
            Outcome::Invalid(_) => self.invalid += 1,
            Outcome::BadMessage(..)
            | Outcome::OtherExit(_)
            | Outcome::Network
            | Outcome::OverMemory(_) => self.other += 1,
        }
    }
}

fn table(rows: &BTreeMap<String, Row>) -> String {
    let mut s = format!(
        "{:<14} {:>5} {:>6} {:>6} {:>6} {:>6} {:>6} {:>7} {:>5} {:>7} {:>5} {:>8} {:>8}\n",
        "kind",
        "cases",
        "exit0",
        "exit2",
        "exit3",
        "exit4",
        "panic",
        "signal",
        "hang",
        "invalid",
        "other",
        "max_s",
        "peak_mb"
    );
    let mut total = Row::default();
    for r in rows.values() {
        total.cases += r.cases;
        total.ok += r.ok;
        total.exit2 += r.exit2;
        total.exit3 += r.exit3;
        total.exit4 += r.exit4;
        total.panics += r.panics;
        total.signals += r.signals;
        total.hangs += r.hangs;
        total.invalid += r.invalid;
        total.other += r.other;
        total.max_wall = total.max_wall.max(r.max_wall);
        total.max_peak_mb = total.max_peak_mb.max(r.max_peak_mb);
    }
    for (name, r) in rows
        .iter()
        .map(|(k, r)| (k.as_str(), r))
        .chain(std::iter::once(("TOTAL", &total)))
    {
        let _ = writeln!(
            s,
            "{:<14} {:>5} {:>6} {:>6} {:>6} {:>6} {:>6} {:>7} {:>5} {:>7} {:>5} {:>8.2} {:>8.0}",
            name,
            r.cases,
            r.ok,
            r.exit2,
            r.exit3,
            r.exit4,
            r.panics,
            r.signals,
            r.hangs,
            r.invalid,
            r.other,
            r.max_wall,
            r.max_peak_mb
        );
    }
    s
}

struct Failure {
    name: String,
    outcome: Outcome,
    stderr: String,
    bytes: Vec<u8>,
}

fn failures_dir() -> PathBuf {
    std::env::var_os("TRIWILD_FUZZ_FAILURES")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-failures"))
}

/// Keep a failing case (placeholders kept, so it replays as a fixture) and what happened.
fn save_failure(runner: &Runner, f: &Failure) -> PathBuf {
    let dir = failures_dir();
    fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{}.svg", f.name));
    fs::write(&path, &f.bytes).unwrap();
    // the case's own options, quoted for a shell, or the fixed ones
    let params = case_args(&f.bytes).map_or_else(
        || PARAMS.join(" "),
        |args| {
            let quoted: Vec<String> = args.iter().map(|a| format!("'{a}'")).collect();
            format!("-q {}", quoted.join(" "))
        },
    );
    let note = format!(
        "outcome: {:?}\ncommand: triwild {params} {} IN.svg -o OUT.msh\nstderr:\n{}\n",
        f.outcome,
        runner.budget_args.join(" "),
        f.stderr
    );
    fs::write(dir.join(format!("{}.txt", f.name)), note).unwrap();
    path
}

/// Shrink a failing generated case with proptest's value tree, keeping the
/// failure class; a bounded number of runs.
fn shrink(
    runner: &Runner,
    strategy: &BoxedStrategy<Vec<u8>>,
    seed: u64,
    index: usize,
    class: &str,
    dir: &Path,
) -> Option<Vec<u8>> {
    // A hang costs the whole watchdog per run: not shrunk (the case is kept as is).
    if class == "hang" {
        return None;
    }
    let steps = env_num("TRIWILD_FUZZ_SHRINK").unwrap_or(48);
    let mut tree = strategy.new_tree(&mut case_runner(seed, index)).ok()?;
    let mut best = None;
    let mut runs = 0;
    if !tree.simplify() {
        return None;
    }
    while runs < steps {
        runs += 1;
        let candidate = tree.current();
        let run = runner.run(&candidate, dir, "shrink");
        let more = if run.outcome.class() == class {
            best = Some(candidate);
            tree.simplify()
        } else {
            tree.complicate()
        };
        if !more {
            break;
        }
    }
    best
}

fn fixtures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fuzz");
    let mut files: Vec<PathBuf> = fs::read_dir(&dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "svg"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

#[test]
fn fuzz_the_binary() {
    let seed = env_num("TRIWILD_FUZZ_SEED").unwrap_or(DEFAULT_SEED);
    let cases = env_num("TRIWILD_FUZZ_CASES").map_or(DEFAULT_CASES, |n| n as usize);
    // TRIWILD_FUZZ_FIRST=i with TRIWILD_FUZZ_CASES=i+1 reruns case i alone.
    let first = env_num("TRIWILD_FUZZ_FIRST").map_or(0, |n| n as usize);
    let jobs = env_num("TRIWILD_FUZZ_JOBS").map_or(1, |n| n.max(1) as usize);
    // One directory per run (and process), so runs can go at once.
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "../test-out/fuzz/seed-{seed:x}-{first}-{cases}-{}",
        std::process::id()
    ));
    let _ = fs::remove_dir_all(&out);
    fs::create_dir_all(&out).unwrap();
    let runner = Runner::new(&out);
    let mut kinds = kinds(runner.max_path_segments);
    // TRIWILD_FUZZ_KINDS=a,b: only those kinds (round-robin over them).
    if let Ok(only) = std::env::var("TRIWILD_FUZZ_KINDS") {
        let only: Vec<&str> = only.split(',').map(str::trim).collect();
        kinds.retain(|(k, _)| only.contains(k));
        assert!(
            !kinds.is_empty(),
            "TRIWILD_FUZZ_KINDS={only:?}: no such kind"
        );
    }
    eprintln!(
        "fuzz: seed {seed:#x}, {cases} cases over {} kinds, {jobs} job(s), budget flags [{}], watchdog {:?}{}",
        kinds.len(),
        runner.budget_args.join(" "),
        runner.watchdog,
        if runner.mshcheck.is_some() {
            ", mshcheck.py on every mesh"
        } else {
            ""
        }
    );

    let rows: Mutex<BTreeMap<String, Row>> = Mutex::new(BTreeMap::new());
    let failures: Mutex<Vec<(usize, Failure)>> = Mutex::new(Vec::new());
    let log: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let started = Instant::now();

    // The fixtures: earlier findings and notable attacks, replayed every time.
    for path in fixtures() {
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        if stem.starts_with("budget-") && !runner.has_budgets {
            eprintln!(
                "fuzz: fixture {stem} skipped: the binary has no --time-limit/--max-segments"
            );
            continue;
        }
        let bytes = fs::read(&path).unwrap();
        let name = format!("fixture-{}", path.file_stem().unwrap().to_string_lossy());
        let run = runner.run(&bytes, &out, &name);
        rows.lock()
            .unwrap()
            .entry("fixtures".into())
            .or_default()
            .add(&run);
        if !run.outcome.is_pass() {
            failures.lock().unwrap().push((
                usize::MAX,
                Failure {
                    name,
                    outcome: run.outcome,
                    stderr: run.stderr,
                    bytes,
                },
            ));
        }
    }

    // Generated here (the strategies are not Send), run by `jobs` threads.
    let generated: Vec<(&str, Vec<u8>)> = (0..cases)
        .filter(|&i| i >= first)
        .map(|i| {
            let (kind, strategy) = &kinds[i % kinds.len()];
            (
                *kind,
                strategy
                    .new_tree(&mut case_runner(seed, i))
                    .expect("generate a case")
                    .current(),
            )
        })
        .collect();
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                loop {
                    let i = first + next.fetch_add(1, Ordering::SeqCst);
                    if i >= cases {
                        break;
                    }
                    let Some((kind, bytes)) = generated.get(i - first) else {
                        break;
                    };
                    let bytes = bytes.clone();
                    let name = format!("{kind}-{seed:x}-{i}");
                    let run = runner.run(&bytes, &out, &name);
                    rows.lock()
                        .unwrap()
                        .entry((*kind).to_owned())
                        .or_default()
                        .add(&run);
                    log.lock().unwrap().push(format!(
                        "{name}\t{:?}\t{:.2}\t{}\n",
                        run.outcome,
                        run.wall,
                        run.stderr.lines().next().unwrap_or("")
                    ));
                    if !run.outcome.is_pass() {
                        eprintln!("fuzz: FAIL {name}: {:?} ({:.1} s)", run.outcome, run.wall);
                        let failure = Failure {
                            name,
                            outcome: run.outcome,
                            stderr: run.stderr,
                            bytes,
                        };
                        // kept at once: a long run killed later keeps its findings
                        save_failure(&runner, &failure);
                        failures.lock().unwrap().push((i, failure));
                    }
                    let n = done.fetch_add(1, Ordering::SeqCst) + 1;
                    if cases >= 100 && n % 50 == 0 {
                        eprintln!(
                            "fuzz: {n}/{cases} cases, {:.0} s",
                            started.elapsed().as_secs_f64()
                        );
                    }
                }
            });
        }
    });

    let rows = rows.into_inner().unwrap();
    // Every case's outcome and first stderr line, for reading the run afterwards.
    fs::write(out.join("cases.tsv"), log.into_inner().unwrap().concat()).unwrap();
    eprintln!(
        "fuzz: {} cases + fixtures in {:.1} s\n{}",
        cases,
        started.elapsed().as_secs_f64(),
        table(&rows)
    );

    let mut failures = failures.into_inner().unwrap();
    failures.sort_by_key(|(i, _)| *i);
    let mut report = String::new();
    for (i, f) in &failures {
        let saved = save_failure(&runner, f);
        let _ = writeln!(report, "{}: {:?} -> {}", f.name, f.outcome, saved.display());
        if *i != usize::MAX {
            let (kind, strategy) = &kinds[i % kinds.len()];
            if let Some(small) = shrink(&runner, strategy, seed, *i, f.outcome.class(), &out) {
                let shrunk = Failure {
                    name: format!("{}-shrunk", f.name),
                    outcome: f.outcome.clone(),
                    stderr: String::new(),
                    bytes: small,
                };
                let saved = save_failure(&runner, &shrunk);
                let _ = writeln!(
                    report,
                    "  shrunk ({kind}, {} bytes) -> {}",
                    shrunk.bytes.len(),
                    saved.display()
                );
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failing case(s) (kept for tests/fixtures/fuzz/):\n{report}",
        failures.len()
    );
}
