//! Shared by the integration tests (`mod support;` in each test file): an
//! independent gmsh reader (`reader`), an independent mesh checker (`check`), and
//! where tests write their meshes (`target/test-out/<test>/`, which CI validates
//! with `shared/bench/mshcheck.py --strict`).
#![allow(
    dead_code,
    unused_imports,
    reason = "each test binary uses a different part of the support module"
)]

pub(crate) mod check;
pub(crate) mod devset;
pub(crate) mod fem;
pub(crate) mod reader;

pub(crate) use check::{DefectKind, Report, check, check_msh};
pub(crate) use reader::{Msh, read_msh};

use std::path::PathBuf;

/// A fresh directory `target/test-out/<test>/` for a test's output files:
/// emptied by the first call for `test` in this process only. Tests run in
/// parallel, and several share a directory (`exact`): emptying it on every
/// call removed the files, and the directory, of a test writing beside
/// (a write failed with "No such file or directory" in CI).
pub(crate) fn out_dir(test: &str) -> PathBuf {
    static EMPTIED: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    // CARGO_TARGET_TMPDIR is <target>/tmp; test output goes next to it. Cargo sets it
    // for integration tests only; the library's own tests (which include this module
    // from src/pipeline/tests) use the default target directory.
    let tmp = option_env!("CARGO_TARGET_TMPDIR").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/tmp"),
        PathBuf::from,
    );
    let dir = tmp
        .parent()
        .map(|t| t.join("test-out"))
        .unwrap_or_else(|| tmp.join("test-out"))
        .join(test);
    // Held while emptying and creating, so no test sees the directory gone.
    let mut emptied = EMPTIED
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if !emptied.iter().any(|t| t == test) {
        let _ = std::fs::remove_dir_all(&dir);
        emptied.push(test.to_owned());
    }
    std::fs::create_dir_all(&dir).expect("create test output directory");
    dir
}
