//! Feature preprocessing on every file of the dev set (`../shared/data/svg-dev`, or
//! `TRIWILD_DEVSET`): each loadable drawing's FeatureSet must keep every invariant, checked
//! by the independent checker in `tests/support/features_check.rs`. Prints counts and time
//! per file. Ignored (slow, needs the corpus): `cargo test --release --lib pipeline::tests::features_devset
//! -- --ignored --nocapture`.
#![allow(clippy::print_stdout, reason = "the dev-set run reports its counts")]

use crate::Params;
use crate::features::FeatureSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::support::devset::{devset_dir, devset_files, svg_files};
use crate::features::tests::features_check;

/// CI's sample: every 15th file of the dev set under 40 KB (about 15 drawings from
/// every collection), so the invariants are checked on real drawings in every run.
#[test]
fn devset_sample_feature_sets_keep_every_invariant() {
    let Some((dir, files)) = devset_files() else {
        return;
    };
    let sample: Vec<PathBuf> = files
        .iter()
        .step_by(15)
        .filter(|f| std::fs::metadata(f).is_ok_and(|m| m.len() < 40_000))
        .cloned()
        .collect();
    assert!(sample.len() >= 8, "sample of {} files", sample.len());
    check_files(&dir, &sample);
}

#[test]
#[ignore = "slow corpus run; needs the svg loader and ../shared/data/svg-dev"]
fn devset_feature_sets_keep_every_invariant() {
    let dir = devset_dir();
    let mut files = Vec::new();
    svg_files(&dir, &mut files);
    assert!(!files.is_empty(), "no .svg under {}", dir.display());
    check_files(&dir, &files);
}

fn check_files(dir: &Path, files: &[PathBuf]) {
    let (mut ok, mut unloadable, mut failures) = (0, 0, Vec::new());
    let (mut primary, mut secondary, mut points) = (0, 0, 0);
    let start = Instant::now();
    println!("file\tsections\tprimary\tsecondary_segments\tpoints\tms");
    for f in files {
        let Ok(drawing) = crate::svg::load_file(f, &crate::svg::LoadOptions::DEFAULT) else {
            unloadable += 1;
            continue;
        };
        let t = Instant::now();
        let fs = FeatureSet::build(&drawing, &Params::DEFAULT.resolve(drawing.diagonal()));
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let name = f.strip_prefix(dir).unwrap_or(f).display().to_string();
        let c = fs.counts;
        println!(
            "{name}\t{}\t{}\t{}\t{}\t{ms:.1}",
            c.sections, c.primary, c.secondary_segments, c.points
        );
        let defects = features_check::check(&fs);
        if !defects.is_empty() {
            println!("  {} defects, first: {}", defects.len(), defects[0]);
            failures.push(name);
        }
        ok += 1;
        primary += c.primary;
        secondary += c.secondary_segments;
        points += c.points;
    }
    println!(
        "{} files: {ok} preprocessed, {unloadable} not loadable; {primary} primary sections, \
         {secondary} secondary segments, {points} points; {:.1} s",
        files.len(),
        start.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "invariants broken in {failures:?}");
}
