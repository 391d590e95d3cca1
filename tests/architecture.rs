//! The module graph is layered: every `crate::` path in a module of `src/` names a
//! module of a strictly lower layer. The layers are read from the `layers` block of
//! ARCHITECTURE.md, so the document and this test cannot drift apart.
//!
//! Paths are found as text (`crate::x`, `crate::{x, y::z}`, and the crate-root
//! re-exports of `src/lib.rs` such as `crate::Params`), in code and in doc links
//! alike: a doc link upward is a dependency upward too.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Layer index of each top-level module, from ARCHITECTURE.md's `layers` block:
/// one line per layer, lowest first, `N  module module ...`.
fn layers() -> BTreeMap<String, usize> {
    let doc = std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let block = doc
        .split("```layers\n")
        .nth(1)
        .and_then(|rest| rest.split("```").next())
        .expect("ARCHITECTURE.md has a ```layers block");
    let mut map = BTreeMap::new();
    for (i, line) in block.lines().filter(|l| !l.trim().is_empty()).enumerate() {
        let mut words = line.split_whitespace();
        let n: usize = words
            .next()
            .and_then(|w| w.parse().ok())
            .expect("each layer line starts with its number");
        assert_eq!(n, i, "layers are numbered 0, 1, 2, ... in order: {line}");
        for m in words {
            assert!(
                map.insert(m.to_owned(), n).is_none(),
                "{m} is in two layers"
            );
        }
    }
    map
}

/// The top-level modules declared in src/lib.rs, and the module each crate-root
/// re-export (`pub use module::{A, B}`) comes from.
fn lib_modules() -> (BTreeSet<String>, BTreeMap<String, String>) {
    let lib = std::fs::read_to_string(root().join("src/lib.rs")).expect("src/lib.rs");
    let mut modules = BTreeSet::new();
    let mut aliases = BTreeMap::new();
    for line in lib.lines().map(str::trim) {
        let decl = line.strip_prefix("pub ").unwrap_or(line);
        // `mod x;` declares a module of src/; an inline `mod x { .. }` (the hidden
        // bench re-exports) holds no code of its own
        if let Some(m) = decl.strip_prefix("mod ").and_then(|m| m.strip_suffix(';')) {
            modules.insert(m.trim().to_owned());
        }
    }
    // `pub use module::{...};`, on one line or several
    for (i, _) in lib.match_indices("pub use ") {
        let rest = &lib[i + "pub use ".len()..];
        let u = rest.split(';').next().unwrap_or("");
        let (module, names) = u.split_once("::").expect("pub use module::...");
        let names = names.trim().trim_start_matches('{').trim_end_matches('}');
        for name in names.split(',') {
            let name = name.split("::").last().unwrap_or(name);
            let name = name.split(" as ").last().unwrap_or(name).trim();
            if !name.is_empty() {
                aliases.insert(name.to_owned(), module.trim().to_owned());
            }
        }
    }
    (modules, aliases)
}

/// The first path segments after each `crate::` in `text`, looking into brace
/// groups (`crate::{a, b::{c}}` gives `a`, `b`).
fn crate_paths(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    for (i, _) in text.match_indices("crate::") {
        // `triwild::crate::` does not occur; skip identifiers that merely end in `crate`
        let before = text[..i].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let rest = &text[i + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 0usize;
            let mut start = true;
            for (j, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => start = true,
                    c if c.is_whitespace() => {}
                    _ if start && depth == 0 => {
                        out.push(ident(&group[j..]));
                        start = false;
                    }
                    _ => {}
                }
            }
        } else {
            out.push(ident(rest));
        }
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src") {
        let p = entry.expect("entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// Every import edge between top-level modules: (from, to) -> the files.
fn edges(aliases: &BTreeMap<String, String>) -> BTreeMap<(String, String), BTreeSet<String>> {
    let src = root().join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut edges: BTreeMap<(String, String), BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(&src).expect("under src");
        let first = rel.components().next().expect("a component");
        let top = first.as_os_str().to_string_lossy();
        let top = top.trim_end_matches(".rs").to_owned();
        // the crate root and the binary (main.rs and its cli modules) sit above every layer
        if matches!(top.as_str(), "lib" | "main" | "cli") {
            continue;
        }
        let text = std::fs::read_to_string(&f).expect("read");
        for name in crate_paths(&text) {
            let to = aliases.get(&name).cloned().unwrap_or(name);
            if to != top {
                edges
                    .entry((top.clone(), to))
                    .or_default()
                    .insert(rel.display().to_string());
            }
        }
    }
    edges
}

#[test]
fn every_import_points_to_a_lower_layer() {
    let layer = layers();
    let (modules, aliases) = lib_modules();
    let listed: BTreeSet<String> = layer.keys().cloned().collect();
    assert_eq!(
        modules, listed,
        "the modules of src/lib.rs and the layers of ARCHITECTURE.md differ"
    );
    let mut upward = Vec::new();
    for ((from, to), files) in edges(&aliases) {
        let Some(&lt) = layer.get(&to) else {
            // `crate::` followed by something that is not a module of ours
            // (a macro path, a keyword): not an edge
            assert!(
                !modules.contains(&to),
                "{to} is a module but not in a layer"
            );
            continue;
        };
        let lf = layer[&from];
        if lt >= lf {
            upward.push(format!(
                "{from} (layer {lf}) -> {to} (layer {lt}) in {files:?}"
            ));
        }
    }
    assert!(
        upward.is_empty(),
        "imports that do not point to a lower layer:\n{}",
        upward.join("\n")
    );
}

#[test]
fn the_path_scanner_sees_groups_and_re_exports() {
    let text =
        "use crate::{a::{B, c}, d};\nlet x = crate::e::f(); // [`crate::Params`]\nmycrate::g";
    assert_eq!(crate_paths(text), ["a", "d", "e", "Params"]);
    let (_, aliases) = lib_modules();
    assert_eq!(aliases.get("Params").map(String::as_str), Some("params"));
}
