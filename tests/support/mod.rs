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

/// A fresh (emptied) directory `target/test-out/<test>/` for a test's output files.
pub(crate) fn out_dir(test: &str) -> PathBuf {
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
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create test output directory");
    dir
}
