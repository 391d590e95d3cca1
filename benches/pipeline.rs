//! Meshing three drawings of the dev set (small, medium, large) from a loaded
//! `Drawing` (no file I/O): the exact BSP mesh (`--stop-after bsp`), the optimized
//! linear mesh (`--linear`), the default curved mesh, and the CDT baseline.
//! Skips drawings that are absent (the dev set lives in ../shared/data/svg-dev,
//! beside the repository). The large drawing takes tens of seconds per run with
//! the optimizer: `cargo bench --bench pipeline -- small` for a quick look.
#![allow(missing_docs, reason = "criterion macros generate undocumented items")]
#![allow(clippy::print_stdout, reason = "the bench reports per-stage times")]

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;
use triwild::Stage;
use triwild::{Mesher, Params};

const DRAWINGS: [(&str, &str); 3] = [
    ("small", "gilbarbara-logos/ello.svg"),
    ("medium", "gilbarbara-logos/argo.svg"),
    ("large", "noto-emoji/emoji_u1f98e.svg"),
];

fn bench(c: &mut Criterion) {
    let dev = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/svg-dev");
    let mut group = c.benchmark_group("pipeline");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    for (size, file) in DRAWINGS {
        let Ok(drawing) = triwild::load_file(&dev.join(file), &triwild::LoadOptions::DEFAULT)
        else {
            println!("{file}: not available, skipped");
            continue;
        };
        let bsp = Params::DEFAULT
            .with_mesher(Mesher::TriWild)
            .with_stop_after(Some(Stage::Bsp));
        let linear = Params::DEFAULT.with_stop_after(Some(Stage::Optimize));
        let curved = Params::DEFAULT;
        let cdt = Params::DEFAULT.with_mesher(Mesher::Cdt);
        for (name, params) in [
            ("bsp", &bsp),
            ("linear", &linear),
            ("curved", &curved),
            ("cdt", &cdt),
        ] {
            let once = triwild::mesh_drawing(&drawing, params, &triwild::RegionOptions::DEFAULT)
                .expect("meshes");
            println!(
                "{size} {file} {name}: {} triangles, stage seconds {:?}",
                once.report.output.triangles, once.report.times
            );
            group.bench_function(format!("{name}/{size}"), |b| {
                b.iter(|| {
                    triwild::mesh_drawing(
                        black_box(&drawing),
                        params,
                        &triwild::RegionOptions::DEFAULT,
                    )
                    .expect("meshes")
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
