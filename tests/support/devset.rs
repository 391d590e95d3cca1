//! Where the dev corpus is and which SVG files it holds, for the corpus tests.

use std::path::{Path, PathBuf};

/// The dev set: `TRIWILD_DEVSET`, else `shared/data/svg-dev` beside the repository
/// (looked up from each ancestor, so a git worktree that sits deeper finds it too).
pub(crate) fn devset_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("TRIWILD_DEVSET") {
        return d.into();
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    root.ancestors()
        .skip(1)
        .map(|a| a.join("shared/data/svg-dev"))
        .find(|d| d.is_dir())
        .unwrap_or_else(|| root.join("../shared/data/svg-dev"))
}

/// Every `.svg` file below `dir`, recursively, in sorted order, appended to `out`.
pub(crate) fn svg_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            svg_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "svg") {
            out.push(p);
        }
    }
}

/// The dev set's directory and its `.svg` files; `None` (said on stdout) when it holds
/// none, so a corpus test that needs it can skip.
#[allow(clippy::print_stdout, reason = "a skipped corpus test says why")]
pub(crate) fn devset_files() -> Option<(PathBuf, Vec<PathBuf>)> {
    let dir = devset_dir();
    let mut files = Vec::new();
    svg_files(&dir, &mut files);
    if files.is_empty() {
        println!("no .svg under {}: skipped", dir.display());
        return None;
    }
    Some((dir, files))
}
