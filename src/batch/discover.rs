//! Finding the SVG files of a batch and slicing them into shards.
//!
//! Guarantees: the file list is sorted by its key (the path relative to the
//! root it was found under, `/`-separated), has no duplicate keys, and the
//! shard `K/N` of it is the same on every machine that sees the same tree.

use crate::{Error, Result};
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// One SVG file of a batch.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SourceFile {
    /// The file's key: its path relative to the root it was found under, with
    /// `/` separators (a file given directly is keyed by its file name). Output
    /// paths mirror it and reports are keyed by it.
    pub key: String,
    /// The path to read.
    pub path: PathBuf,
}

impl SourceFile {
    /// The output path of this file, relative to the output directory: the key
    /// with extension `.msh`.
    pub fn output_rel(&self) -> String {
        match self.key.rsplit_once('.') {
            Some((stem, ext)) if !stem.is_empty() && !ext.contains('/') => format!("{stem}.msh"),
            _ => format!("{}.msh", self.key),
        }
    }
}

/// What discovery found: the sorted files and the problems it stepped over.
#[derive(Clone, Debug, Default)]
pub struct Discovery {
    /// The files, sorted by key.
    pub files: Vec<SourceFile>,
    /// Directories that could not be read (the batch goes on without them).
    pub warnings: Vec<String>,
}

/// Whether `path` names an SVG file by its extension (`.svg`, any case).
fn is_svg(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
}

fn key_of(rel: &Path) -> String {
    rel.components()
        .map(|c| c.as_os_str().to_string_lossy())
        .collect::<Vec<_>>()
        .join("/")
}

/// Walk `dir` recursively, depth-first; symbolic links to directories are not
/// followed (no cycles), symbolic links to files are.
fn walk(root: &Path, dir: &Path, out: &mut Discovery) {
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) => {
            out.warnings
                .push(format!("{}: cannot read directory: {e}", dir.display()));
            return;
        }
    };
    for entry in entries {
        let entry = match entry {
            Ok(e) => e,
            Err(e) => {
                out.warnings
                    .push(format!("{}: cannot read directory: {e}", dir.display()));
                continue;
            }
        };
        let path = entry.path();
        let Ok(ty) = entry.file_type() else { continue };
        if ty.is_dir() {
            walk(root, &path, out);
        } else if is_svg(&path) && (ty.is_file() || path.is_file()) {
            let rel = path.strip_prefix(root).unwrap_or(&path);
            out.files.push(SourceFile {
                key: key_of(rel),
                path,
            });
        }
    }
}

/// Find the SVG files under `inputs` (directories, searched recursively, or
/// files, taken as they are whatever their extension), sorted by key.
///
/// # Errors
/// [`Error::Read`] if an input does not exist; [`Error::InvalidParams`] if two
/// files have the same key (they would write the same output).
pub fn discover(inputs: &[PathBuf]) -> Result<Discovery> {
    let mut out = Discovery::default();
    for input in inputs {
        let meta = std::fs::metadata(input).map_err(|e| {
            Error::Read(std::io::Error::new(
                e.kind(),
                format!("{}: {e}", input.display()),
            ))
        })?;
        if meta.is_dir() {
            walk(input, input, &mut out);
        } else {
            let name = input
                .file_name()
                .map_or_else(|| key_of(input), |n| n.to_string_lossy().into_owned());
            out.files.push(SourceFile {
                key: name,
                path: input.clone(),
            });
        }
    }
    out.files
        .sort_by(|a, b| a.key.cmp(&b.key).then(a.path.cmp(&b.path)));
    out.files.dedup_by(|a, b| a.path == b.path);
    if let Some(w) = out.files.windows(2).find(|w| w[0].key == w[1].key) {
        return Err(Error::InvalidParams(format!(
            "{} and {} both map to the output {}; mesh them in separate batches",
            w[0].path.display(),
            w[1].path.display(),
            w[0].output_rel()
        )));
    }
    Ok(out)
}

/// A slice `K/N` (1 ≤ K ≤ N) of a sorted file list: the files whose index `i`
/// (from 0) has `i mod N = K − 1`. Round-robin, so each shard gets a similar
/// mix of the tree's folders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, from 1.
    pub k: usize,
    /// How many shards.
    pub n: usize,
}

impl Shard {
    /// The files of `files` in this shard, in order.
    pub fn select<T: Clone>(self, files: &[T]) -> Vec<T> {
        files
            .iter()
            .enumerate()
            .filter(|(i, _)| i % self.n == self.k - 1)
            .map(|(_, f)| f.clone())
            .collect()
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

impl FromStr for Shard {
    type Err = String;
    /// Parse `K/N`.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let bad = || format!("expected K/N with 1 <= K <= N (like 2/8), got `{s}`");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let k: usize = k.trim().parse().map_err(|_| bad())?;
        let n: usize = n.trim().parse().map_err(|_| bad())?;
        if k == 0 || n == 0 || k > n {
            return Err(bad());
        }
        Ok(Shard { k, n })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_parse() {
        assert_eq!("2/3".parse::<Shard>(), Ok(Shard { k: 2, n: 3 }));
        assert!("0/3".parse::<Shard>().is_err());
        assert!("4/3".parse::<Shard>().is_err());
        assert!("3".parse::<Shard>().is_err());
        assert!("a/b".parse::<Shard>().is_err());
    }

    #[test]
    fn shards_partition() {
        let files: Vec<usize> = (0..10).collect();
        let mut all: Vec<usize> = (1..=3)
            .flat_map(|k| Shard { k, n: 3 }.select(&files))
            .collect();
        assert_eq!(Shard { k: 1, n: 3 }.select(&files), vec![0, 3, 6, 9]);
        all.sort_unstable();
        assert_eq!(all, files);
        assert_eq!(Shard { k: 5, n: 12 }.select(&files), vec![4]);
        assert!(Shard { k: 12, n: 12 }.select(&files).is_empty());
    }

    #[test]
    fn output_names() {
        let f = |key: &str| SourceFile {
            key: key.into(),
            path: key.into(),
        };
        assert_eq!(f("a/b.svg").output_rel(), "a/b.msh");
        assert_eq!(f("a.b/c").output_rel(), "a.b/c.msh");
        assert_eq!(f("x.SVG").output_rel(), "x.msh");
    }

    #[test]
    fn discover_tree() {
        let dir = tempfile::tempdir().expect("tempdir");
        let root = dir.path();
        std::fs::create_dir_all(root.join("b/c")).expect("mkdir");
        for p in ["z.svg", "b/c/y.SVG", "b/a.svg", "b/notes.txt"] {
            std::fs::write(root.join(p), "<svg/>").expect("write");
        }
        let d = discover(&[root.to_path_buf()]).expect("discover");
        let keys: Vec<_> = d.files.iter().map(|f| f.key.as_str()).collect();
        assert_eq!(keys, ["b/a.svg", "b/c/y.SVG", "z.svg"]);
        assert!(d.warnings.is_empty());
        // The same tree given twice: the same paths are merged.
        let d2 = discover(&[root.to_path_buf(), root.join("z.svg")]).expect("discover");
        assert_eq!(d2.files, d.files);
        // Two different files with the same key would write the same output.
        let d3 = discover(&[root.join("b/c/y.SVG"), root.join("b/c")]).expect("discover");
        assert_eq!(d3.files.len(), 1);
        std::fs::write(root.join("b/z.svg"), "<svg/>").expect("write");
        let d3 = discover(&[root.join("z.svg"), root.join("b")]);
        assert!(matches!(d3, Err(Error::InvalidParams(_))), "{d3:?}");
        assert!(discover(&[root.join("missing")]).is_err());
    }
}
