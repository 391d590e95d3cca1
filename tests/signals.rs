//! Signals: SIGINT / SIGTERM at any moment leave no temporary
//! output and exit 130 / 143; a batch child whose batch is killed (even with
//! SIGKILL) stops without writing; an interrupted batch reports the files it
//! was meshing. The test hooks (`test-hooks` feature) hold the process at a
//! chosen moment: meshing (`TRIWILD_TEST_SLEEP_ON`) or with the temporary
//! output complete but not yet renamed (`TRIWILD_TEST_SLOW_WRITE_ON`).
#![cfg(unix)]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const SQUARE: &[u8] = br#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><rect x="1" y="1" width="8" height="8"/></svg>"#;

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("signals")
        .join(name);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_triwild"))
}

fn send(pid: u32, signal: &str) {
    let ok = Command::new("kill")
        .args([format!("-{signal}"), pid.to_string()])
        .status()
        .expect("run kill")
        .success();
    assert!(ok, "kill -{signal} {pid}");
}

/// Every file name below `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in fs::read_dir(&d).expect("read dir").flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p.clone());
            }
            out.push(
                p.strip_prefix(dir)
                    .expect("below")
                    .to_string_lossy()
                    .into_owned(),
            );
        }
    }
    out.sort();
    out
}

/// Poll `cond` for up to `secs` seconds.
fn wait_for(secs: u64, mut cond: impl FnMut() -> bool) -> bool {
    let t = Instant::now();
    while t.elapsed() < Duration::from_secs(secs) {
        if cond() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

fn wait_exit(child: &mut Child, secs: u64) -> std::process::ExitStatus {
    let mut status = None;
    let ended = wait_for(secs, || {
        status = child.try_wait().expect("try_wait");
        status.is_some()
    });
    if !ended {
        let _ = child.kill();
        panic!("the process did not end within {secs} s");
    }
    status.expect("ended")
}

/// The single-file command, signalled at several moments.
#[test]
fn a_signal_leaves_no_temporary_file() {
    enum Moment {
        Start,
        Meshing,
        Writing,
    }
    for (k, (moment, signal, code)) in [
        (Moment::Start, "INT", 130),
        (Moment::Meshing, "INT", 130),
        (Moment::Meshing, "TERM", 143),
        (Moment::Writing, "INT", 130),
        (Moment::Writing, "TERM", 143),
    ]
    .into_iter()
    .enumerate()
    {
        let dir = scratch(&format!("single-{k}"));
        let input = dir.join("in.svg");
        fs::write(&input, SQUARE).expect("input");
        let mut cmd = bin();
        cmd.arg(&input)
            .arg("-o")
            .arg(dir.join("out.msh"))
            .args(["-l", "0.2", "--order", "1"])
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        match moment {
            Moment::Start => {}
            Moment::Meshing => {
                cmd.env("TRIWILD_TEST_SLEEP_ON", "in.svg");
            }
            Moment::Writing => {
                cmd.env("TRIWILD_TEST_SLOW_WRITE_ON", "out.msh");
            }
        }
        let mut child = cmd.spawn().expect("run triwild");
        match moment {
            // the handler may not be installed yet: then the default action
            // kills the process, which has created nothing either
            Moment::Start => std::thread::sleep(Duration::from_millis(30)),
            Moment::Meshing => std::thread::sleep(Duration::from_millis(500)),
            Moment::Writing => assert!(
                wait_for(60, || names(&dir).iter().any(|n| n.contains(".tmp"))),
                "case {k}: the temporary output never appeared"
            ),
        }
        send(child.id(), signal);
        let status = wait_exit(&mut child, 30);
        if matches!(moment, Moment::Start) && status.success() {
            // finished before the signal: the mesh is complete
            let mesh = fs::read_to_string(dir.join("out.msh")).expect("the mesh");
            assert!(
                mesh.ends_with("$EndElements\n"),
                "case {k}: incomplete mesh"
            );
            assert_eq!(names(&dir), ["in.svg", "out.msh"], "case {k}");
            continue;
        }
        if !matches!(moment, Moment::Start) {
            assert_eq!(status.code(), Some(code), "case {k}: {status:?}");
        }
        assert_eq!(names(&dir), ["in.svg"], "case {k}: nothing but the input");
    }
}

/// Processes whose parent is `pid` (Linux `/proc`), not yet reaped zombies excluded.
fn children_of(pid: u32) -> Vec<u32> {
    let mut out = Vec::new();
    for e in fs::read_dir("/proc").expect("/proc").flatten() {
        let Ok(p) = e.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        if let Some((state, ppid)) = stat(p) {
            if ppid == pid && state != 'Z' {
                out.push(p);
            }
        }
    }
    out
}

/// State and parent of process `pid`.
fn stat(pid: u32) -> Option<(char, u32)> {
    let s = fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let mut f = rest.split_whitespace();
    let state = f.next()?.chars().next()?;
    let ppid = f.next()?.parse().ok()?;
    Some((state, ppid))
}

fn alive(pid: u32) -> bool {
    stat(pid).is_some_and(|(state, _)| state != 'Z')
}

/// A batch of two files that sleep while meshing, started and waited for
/// until both children run.
fn sleeping_batch(name: &str) -> (PathBuf, PathBuf, Child, Vec<u32>) {
    let dir = scratch(name);
    let input = dir.join("in");
    let out = dir.join("out");
    fs::create_dir_all(&input).expect("input dir");
    for f in ["sleep-a.svg", "sleep-b.svg"] {
        fs::write(input.join(f), SQUARE).expect("input");
    }
    let child = bin()
        .args(["batch", "-q"])
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["-j", "2", "-l", "0.2", "--order", "1"])
        .env("TRIWILD_TEST_SLEEP_ON", "sleep-")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("run the batch");
    let mut kids = Vec::new();
    assert!(
        wait_for(60, || {
            kids = children_of(child.id());
            kids.len() == 2
        }),
        "two children should start"
    );
    (input, out, child, kids)
}

/// `kill -9` of the batch: its children notice (their pipe from the batch
/// closes), remove their temporary output and exit; no mesh appears.
#[test]
fn children_die_with_a_killed_batch() {
    let (_input, out, mut batch, kids) = sleeping_batch("kill9");
    send(batch.id(), "KILL");
    let _ = batch.wait();
    assert!(
        wait_for(20, || kids.iter().all(|&k| !alive(k))),
        "orphaned children still run: {kids:?}"
    );
    let meshes: Vec<String> = names(&out)
        .into_iter()
        .filter(|n| n.contains(".msh"))
        .collect();
    assert!(meshes.is_empty(), "{meshes:?}");
}

/// SIGTERM to the batch (twice): children are stopped, both files get an
/// `interrupted` row, the batch exits 143.
#[test]
fn an_interrupted_batch_reports_the_files_in_flight() {
    let (_input, out, mut batch, kids) = sleeping_batch("sigterm");
    // twice at once, as `timeout` sends it (to the process and its group)
    send(batch.id(), "TERM");
    send(batch.id(), "TERM");
    let status = wait_exit(&mut batch, 30);
    assert_eq!(status.code(), Some(143), "{status:?}");
    assert!(kids.iter().all(|&k| !alive(k)), "children left: {kids:?}");
    let report = fs::read_to_string(out.join("report.jsonl")).expect("report");
    let rows: Vec<serde_json::Value> = report
        .lines()
        .map(|l| serde_json::from_str(l).expect("a report row"))
        .collect();
    assert_eq!(rows.len(), 2, "{report}");
    // the page of the interrupted batch shows both files with their cause
    let page = fs::read_to_string(out.join("report.html")).expect("report page");
    assert!(
        page.contains("id=\"n-cause-interrupted\">2<"),
        "the page counts two interrupted files"
    );
    for r in &rows {
        assert_eq!(r["cause"], "interrupted", "{r}");
        assert!(
            r["message"].as_str().is_some_and(|m| m.contains("SIGTERM")),
            "{r}"
        );
    }
    let meshes: Vec<String> = names(&out)
        .into_iter()
        .filter(|n| n.contains(".msh"))
        .collect();
    assert!(meshes.is_empty(), "{meshes:?}");
}
