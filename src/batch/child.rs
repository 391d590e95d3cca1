//! Running one file in a child process and turning whatever happens to it
//! into a [`Row`].
//!
//! Guarantees: [`run_child`] always returns a row and never blocks past the
//! time limit (plus one poll interval and the kill); the child's pipes are
//! drained by threads, so a chatty child cannot deadlock the batch; a failed
//! file leaves no mesh (nor temporary mesh) behind.

use super::report::{Cause, Row, Status};
use std::ffi::OsString;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicI32, Ordering};
use std::time::{Duration, Instant};

/// The signal that interrupted the batch (0: none), set by [`interrupt`].
static INTERRUPTED: AtomicI32 = AtomicI32::new(0);

/// Interrupt the running batch (the binary calls this from its SIGINT /
/// SIGTERM handler): running children are stopped and their files get an
/// `interrupted` row, no new file starts, and [`super::run`] returns.
pub fn interrupt(signal: i32) {
    INTERRUPTED.store(signal.max(1), Ordering::SeqCst);
}

/// The signal [`interrupt`] was called with, if any.
pub fn interrupted() -> Option<i32> {
    match INTERRUPTED.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// The environment variable that tells a child its standard input is a pipe
/// from the batch: when it reads end-of-file there, the batch is gone (even
/// killed with SIGKILL) and the child removes its temporary files and exits.
pub const PARENT_PIPE_ENV: &str = "TRIWILD_BATCH_PARENT_PIPE";

/// How a child's memory is limited.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MemoryGuard {
    /// No limit.
    None,
    /// The child runs under `prlimit --as=BYTES` (util-linux): its address
    /// space is capped by the kernel, so an allocation past it fails at once.
    Prlimit {
        /// The `prlimit` executable.
        prlimit: PathBuf,
        /// The address-space limit, bytes.
        bytes: u64,
    },
    /// The batch samples the child's resident memory (`/proc/PID/status`)
    /// while it runs and kills it past the limit: catches slow growth, may
    /// miss a spike between two samples.
    Poll {
        /// The resident-memory limit, bytes.
        bytes: u64,
    },
}

impl MemoryGuard {
    /// The best guard for a limit of `bytes` on this system: `prlimit` if it is
    /// on the `PATH`, else polling.
    pub fn detect(bytes: Option<u64>) -> Self {
        let Some(bytes) = bytes else {
            return MemoryGuard::None;
        };
        match find_in_path("prlimit") {
            Some(prlimit) => MemoryGuard::Prlimit { prlimit, bytes },
            None => MemoryGuard::Poll { bytes },
        }
    }

    /// The limit in bytes, if any.
    pub fn bytes(&self) -> Option<u64> {
        match *self {
            MemoryGuard::None => None,
            MemoryGuard::Prlimit { bytes, .. } | MemoryGuard::Poll { bytes } => Some(bytes),
        }
    }
}

fn find_in_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

/// Parse a memory size: bytes, or a number with a suffix `K`, `M`, `G`, `T`
/// (powers of 1024; an optional trailing `B` or `iB` is accepted).
///
/// # Errors
/// A message when `s` is not such a size.
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix("ib"))
        .or_else(|| t.strip_suffix(['B', 'b']))
        .unwrap_or(t);
    let (num, mult) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 1u64 << 10),
        Some('M') => (&t[..t.len() - 1], 1 << 20),
        Some('G') => (&t[..t.len() - 1], 1 << 30),
        Some('T') => (&t[..t.len() - 1], 1 << 40),
        _ => (t, 1),
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("expected a size like 8G, 512M or 1000000, got `{s}`"))?;
    if !(v.is_finite() && v > 0.0 && v * (mult as f64) < 1.8e19) {
        return Err(format!("size out of range: `{s}`"));
    }
    Ok((v * mult as f64) as u64)
}

/// One child run: the command and its limits.
#[derive(Clone, Debug)]
pub struct ChildSpec<'a> {
    /// The triwild executable.
    pub exe: &'a Path,
    /// Parameters and format flags passed to every child.
    pub args: &'a [OsString],
    /// Wall-time limit.
    pub timeout: Duration,
    /// Memory limit.
    pub memory: &'a MemoryGuard,
    /// Also write the mesh's SVG preview beside it
    /// ([`super::page::preview_path`]: `x/y.msh` → `x/y.preview.svg`), for
    /// the report page.
    pub preview: bool,
    /// The preview shades triangles by edge length over the size field.
    pub preview_size: bool,
}

/// The longest message kept from a child's stderr.
const MESSAGE_MAX: usize = 600;
/// The most bytes kept from each of a child's pipes (the end is kept).
const PIPE_MAX: usize = 1 << 20;

/// Read a pipe to its end on a thread, keeping the last `PIPE_MAX` bytes.
fn drain(mut pipe: impl Read + Send + 'static) -> std::thread::JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let mut kept = Vec::new();
        let mut buf = [0u8; 8192];
        loop {
            match pipe.read(&mut buf) {
                Ok(0) | Err(_) => break,
                Ok(n) => {
                    kept.extend_from_slice(&buf[..n]);
                    if kept.len() > 2 * PIPE_MAX {
                        kept.drain(..kept.len() - PIPE_MAX);
                    }
                }
            }
        }
        kept
    })
}

/// Resident memory of process `pid` from `/proc`: (current, peak), bytes.
fn rss(pid: u32) -> Option<(u64, u64)> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let field = |name: &str| -> Option<u64> {
        let line = status.lines().find(|l| l.starts_with(name))?;
        let kb: u64 = line[name.len()..]
            .trim()
            .trim_end_matches("kB")
            .trim()
            .parse()
            .ok()?;
        Some(kb * 1024)
    };
    let cur = field("VmRSS:")?;
    Some((cur, field("VmHWM:").unwrap_or(cur)))
}

/// Why the batch killed a child.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Killed {
    Timeout,
    Memory,
    Interrupted(i32),
}

/// Remove `output` and the temporary files the writer may have left next to
/// it (`.NAME.tmp*`, and `NAME.tmp*`), after a failure.
fn remove_output(output: &Path) {
    let _ = std::fs::remove_file(output);
    let (Some(dir), Some(name)) = (output.parent(), output.file_name()) else {
        return;
    };
    // The writer's temporary files are hidden: `.NAME.tmpXXXXXX`.
    let prefix = format!("{}.tmp", name.to_string_lossy());
    let hidden = format!(".{prefix}");
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let n = e.file_name().to_string_lossy().into_owned();
            if n.starts_with(&prefix) || n.starts_with(&hidden) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

/// `thread 'main' (1234) panicked at ...` without the `(1234)`, which
/// changes from run to run (reports of two runs should compare equal).
fn without_thread_id(line: &str) -> String {
    if let Some(open) = line.find("' (") {
        let rest = &line[open + 3..];
        if let Some(close) = rest.find(") panicked") {
            if rest[..close].bytes().all(|b| b.is_ascii_digit()) {
                return format!("{}'{}", &line[..open], &rest[close + 1..]);
            }
        }
    }
    line.to_string()
}

/// The message to report from a child's stderr: the panic message, else the
/// last `error:` line, else the last line.
fn message_of(stderr: &str) -> Option<String> {
    let lines: Vec<&str> = stderr
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    let pick = if let Some(i) = lines.iter().rposition(|l| l.contains("panicked at")) {
        let head = without_thread_id(lines[i]);
        match lines.get(i + 1) {
            Some(next) if !next.starts_with("note:") => format!("{head} {next}"),
            _ => head,
        }
    } else if let Some(l) = lines.iter().rev().find(|l| l.starts_with("error:")) {
        (*l).to_string()
    } else {
        (*lines.last()?).to_string()
    };
    let mut m = pick;
    if m.len() > MESSAGE_MAX {
        let mut cut = MESSAGE_MAX;
        while !m.is_char_boundary(cut) {
            cut -= 1;
        }
        m.truncate(cut);
        m.push('…');
    }
    Some(m)
}

#[cfg(unix)]
fn signal_of(status: ExitStatus) -> Option<i32> {
    use std::os::unix::process::ExitStatusExt;
    status.signal()
}

#[cfg(not(unix))]
fn signal_of(_status: ExitStatus) -> Option<i32> {
    None
}

fn signal_name(sig: i32) -> &'static str {
    match sig {
        4 => "SIGILL",
        6 => "SIGABRT",
        7 => "SIGBUS",
        8 => "SIGFPE",
        2 => "SIGINT",
        9 => "SIGKILL",
        11 => "SIGSEGV",
        15 => "SIGTERM",
        _ => "signal",
    }
}

/// Whether stderr says an allocation failed.
fn out_of_memory(stderr: &str) -> bool {
    stderr.contains("memory allocation of")
        || stderr.contains("out of memory")
        || stderr.contains("Cannot allocate memory")
}

/// Mesh `input` into `output` in a child process and report what happened.
/// The row's `file` is `key`, its `output` is `output_rel`.
pub fn run_child(
    spec: &ChildSpec<'_>,
    key: &str,
    input: &Path,
    output: &Path,
    output_rel: &str,
) -> Row {
    let mut row = Row {
        file: key.to_string(),
        input: input.to_string_lossy().into_owned(),
        status: Status::Failed,
        cause: None,
        message: None,
        exit_code: None,
        signal: None,
        output: None,
        wall: 0.0,
        peak_rss: None,
        stats: None,
        flags: Vec::new(),
        build: None,
    };
    let preview = spec.preview.then(|| super::page::preview_path(output));
    let fail = |mut row: Row, cause: Cause, message: String| {
        remove_output(output);
        if let Some(p) = &preview {
            remove_output(p);
        }
        row.cause = Some(cause);
        row.message = Some(message);
        row
    };
    if let Some(dir) = output.parent() {
        if let Err(e) = std::fs::create_dir_all(dir) {
            return fail(
                row,
                Cause::Io,
                format!("cannot create {}: {e}", dir.display()),
            );
        }
    }
    let mut cmd = match spec.memory {
        MemoryGuard::Prlimit { prlimit, bytes } => {
            let mut c = Command::new(prlimit);
            c.arg(format!("--as={bytes}")).arg("--").arg(spec.exe);
            // glibc reserves 64-128 MiB of address space for each thread's
            // malloc arena: under an address-space cap the child's few
            // threads (mesher, rayon worker, parent watcher) would spend the
            // cap on reservations and fail a small allocation. One arena
            // keeps the cap for what the child really allocates.
            c.env("MALLOC_ARENA_MAX", "1");
            c
        }
        _ => Command::new(spec.exe),
    };
    cmd.args(spec.args).arg("-o").arg(output);
    if let Some(p) = &preview {
        cmd.arg("--preview").arg(p);
        if spec.preview_size {
            cmd.arg("--preview-size");
        }
    }
    cmd.arg("--stats")
        .arg("--")
        .arg(input)
        // The batch keeps only the panic message; symbolizing a backtrace
        // costs seconds and memory, and under a memory limit it may not finish.
        .env("RUST_BACKTRACE", "0")
        .env(PARENT_PIPE_ENV, "1")
        // The child watches this pipe: it closes when the batch dies, however.
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let t0 = Instant::now();
    let mut child = match cmd.spawn() {
        Ok(c) => c,
        Err(e) => return fail(row, Cause::Internal, format!("cannot start the child: {e}")),
    };
    // Held until the child has been waited for: dropping it tells the child
    // its batch is gone.
    let parent_pipe = child.stdin.take();
    let out = child.stdout.take().map(drain);
    let err = child.stderr.take().map(drain);
    let pid = child.id();
    let poll_limit = match spec.memory {
        MemoryGuard::Poll { bytes } => Some(*bytes),
        _ => None,
    };
    let mut killed = None;
    let mut nap = Duration::from_millis(1);
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break Ok(status),
            Ok(None) => {}
            Err(e) => {
                let _ = child.kill();
                let _ = child.wait();
                break Err(e);
            }
        }
        if let Some((cur, peak)) = rss(pid) {
            row.peak_rss = Some(row.peak_rss.unwrap_or(0).max(peak));
            if poll_limit.is_some_and(|limit| cur > limit) {
                killed = Some(Killed::Memory);
            }
        }
        if t0.elapsed() > spec.timeout {
            killed = Some(Killed::Timeout);
        }
        if let Some(sig) = interrupted() {
            killed = Some(Killed::Interrupted(sig));
        }
        if killed.is_some() {
            let _ = child.kill();
            break child.wait();
        }
        std::thread::sleep(nap);
        nap = (nap * 2).min(Duration::from_millis(50));
    };
    row.wall = t0.elapsed().as_secs_f64();
    drop(parent_pipe);
    let join = |h: Option<std::thread::JoinHandle<Vec<u8>>>| {
        h.and_then(|h| h.join().ok())
            .map(|b| String::from_utf8_lossy(&b).into_owned())
            .unwrap_or_default()
    };
    let (stdout, stderr) = (join(out), join(err));
    let status = match status {
        Ok(s) => s,
        Err(e) => {
            return fail(
                row,
                Cause::Internal,
                format!("cannot wait for the child: {e}"),
            );
        }
    };
    row.exit_code = status.code();
    row.signal = signal_of(status);
    let message = message_of(&stderr);
    // A child that a terminal's Ctrl-C reached before the batch stopped it.
    if killed.is_none() && status.code() != Some(0) {
        if let Some(sig) = interrupted() {
            killed = Some(Killed::Interrupted(sig));
        }
    }
    match killed {
        Some(Killed::Timeout) => {
            let m = format!(
                "killed after the time limit of {:.0} s",
                spec.timeout.as_secs_f64()
            );
            return fail(row, Cause::Timeout, m);
        }
        Some(Killed::Interrupted(sig)) => {
            let m = format!("interrupted by {} ({sig}) while meshing", signal_name(sig));
            return fail(row, Cause::Interrupted, m);
        }
        Some(Killed::Memory) => {
            let limit = poll_limit.unwrap_or(0);
            let m = format!(
                "killed past the memory limit of {} MiB (resident)",
                limit >> 20
            );
            return fail(row, Cause::Memory, m);
        }
        None => {}
    }
    let mem_limit = spec.memory.bytes().is_some();
    let unknown = || "no message".to_string();
    match (status.code(), row.signal) {
        (Some(0), _) => {
            let stats = stdout
                .lines()
                .rev()
                .find_map(|l| serde_json::from_str::<serde_json::Value>(l.trim()).ok())
                .filter(serde_json::Value::is_object);
            match stats {
                Some(s) if output.is_file() => {
                    row.status = Status::Ok;
                    row.output = Some(output_rel.to_string());
                    row.stats = Some(s);
                    row
                }
                Some(_) => fail(row, Cause::Internal, "exited 0 but wrote no mesh".into()),
                None => fail(
                    row,
                    Cause::Internal,
                    "exited 0 without a --stats line".into(),
                ),
            }
        }
        (Some(code), _) if mem_limit && out_of_memory(&stderr) => {
            let m = message.unwrap_or_else(|| format!("exit code {code}"));
            fail(row, Cause::Memory, m)
        }
        (Some(2), _) => fail(row, Cause::BadInput, message.unwrap_or_else(unknown)),
        (Some(3), _) => fail(row, Cause::Meshing, message.unwrap_or_else(unknown)),
        (Some(4), _) => fail(row, Cause::Io, message.unwrap_or_else(unknown)),
        (Some(101), _) => fail(row, Cause::Panic, message.unwrap_or_else(unknown)),
        (Some(code), _) => {
            let m = format!("exit code {code}: {}", message.unwrap_or_else(unknown));
            fail(row, Cause::Crash, m)
        }
        (None, Some(sig)) if mem_limit && out_of_memory(&stderr) => {
            let m = format!(
                "{} ({}): {}",
                signal_name(sig),
                sig,
                message.unwrap_or_else(unknown)
            );
            fail(row, Cause::Memory, m)
        }
        (None, sig) => {
            let sig = sig.unwrap_or(0);
            let hint = if sig == 9 {
                " (by the system's OOM killer?)"
            } else {
                ""
            };
            let m = format!("killed by {} ({sig}){hint}", signal_name(sig));
            let m = match message {
                Some(msg) => format!("{m}: {msg}"),
                None => m,
            };
            fail(row, Cause::Crash, m)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes() {
        assert_eq!(parse_size("8G"), Ok(8 << 30));
        assert_eq!(parse_size("512m"), Ok(512 << 20));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("100"), Ok(100));
        assert_eq!(parse_size("2kB"), Ok(2048));
        assert!(parse_size("").is_err());
        assert!(parse_size("-1G").is_err());
        assert!(parse_size("lots").is_err());
        assert!(parse_size("1e30").is_err());
    }

    #[test]
    fn messages() {
        let panic =
            "thread 'main' panicked at src/main.rs:3:5:\nboom\nnote: run with `RUST_BACKTRACE=1`\n";
        assert_eq!(
            message_of(panic).as_deref(),
            Some("thread 'main' panicked at src/main.rs:3:5: boom")
        );
        let panic = "thread 'main' (4242) panicked at src/main.rs:3:5:\nboom\n";
        assert_eq!(
            message_of(panic).as_deref(),
            Some("thread 'main' panicked at src/main.rs:3:5: boom")
        );
        let err = "warning: x.svg: odd\nerror: x.svg: empty file\n";
        assert_eq!(message_of(err).as_deref(), Some("error: x.svg: empty file"));
        assert_eq!(message_of("\n  \n"), None);
        let long = "é".repeat(1000);
        assert!(message_of(&long).expect("message").len() <= MESSAGE_MAX + 3);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn own_rss() {
        let (cur, peak) = rss(std::process::id()).expect("own /proc status");
        assert!(cur > 0 && peak >= cur);
    }

    #[test]
    fn cleanup_removes_temporaries() {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("a.msh");
        for name in ["a.msh", "a.msh.tmp123", ".a.msh.tmpAbC123", "b.msh"] {
            std::fs::write(dir.path().join(name), "x").expect("write");
        }
        remove_output(&out);
        let mut left: Vec<_> = std::fs::read_dir(dir.path())
            .expect("read_dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["b.msh"]);
    }

    /// A child that is not triwild at all: `false` exits 1, `sh -c 'kill -9 $$'`
    /// dies of a signal, `sleep` outlives its time limit.
    #[cfg(unix)]
    #[test]
    fn exits_signals_timeouts() {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("x.msh");
        let none = MemoryGuard::None;
        let run = |exe: &str, args: &[&str], secs: f64| {
            let args: Vec<OsString> = args.iter().map(OsString::from).collect();
            let spec = ChildSpec {
                exe: Path::new(exe),
                args: &args,
                timeout: Duration::from_secs_f64(secs),
                memory: &none,
                preview: false,
                preview_size: false,
            };
            run_child(&spec, "x.svg", Path::new("x.svg"), &out, "x.msh")
        };
        // `sh -c SCRIPT -o OUT --stats -- x.svg`: the script sees `-o` as $0.
        let r = run("/bin/sh", &["-c", "exit 3"], 10.0);
        assert_eq!((r.cause, r.exit_code), (Some(Cause::Meshing), Some(3)));
        let r = run(
            "/bin/sh",
            &["-c", "echo 'error: broken' >&2; exit 101"],
            10.0,
        );
        assert_eq!(r.cause, Some(Cause::Panic));
        assert_eq!(r.message.as_deref(), Some("error: broken"));
        let r = run("/bin/sh", &["-c", "kill -9 $$"], 10.0);
        assert_eq!((r.cause, r.signal), (Some(Cause::Crash), Some(9)));
        let t = Instant::now();
        let r = run("/bin/sh", &["-c", "exec sleep 30"], 0.3);
        assert_eq!(r.cause, Some(Cause::Timeout));
        assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
        // Exit 0 without statistics is not a success.
        std::fs::write(&out, "stale").expect("write");
        let r = run("/bin/sh", &["-c", "exit 0"], 10.0);
        assert_eq!((r.status, r.cause), (Status::Failed, Some(Cause::Internal)));
        assert!(!out.exists(), "a failed file leaves no mesh");
        let r = run(
            "/bin/sh",
            &[
                "-c",
                "echo x > \"$1\"; echo '{\"output\":{\"triangles\":3}}'",
            ],
            10.0,
        );
        assert_eq!(r.status, Status::Ok, "{r:?}");
        assert_eq!(r.triangles(), Some(3));
        let r = run("/nonexistent/triwild", &[], 10.0);
        assert_eq!(r.cause, Some(Cause::Internal));
    }
}
