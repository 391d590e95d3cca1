//! The BSP mesher on random segment soups of 100, 1000 and 10000 segments
//! (segment length ~ 3 / sqrt(n) in the unit square, so crossings grow
//! linearly with n).
#![allow(missing_docs, reason = "criterion macros generate undocumented items")]
#![allow(clippy::print_stdout, reason = "the bench reports the mesh counts")]

use criterion::{Criterion, criterion_group, criterion_main};
use kurbo::{Point, Rect};
use std::hint::black_box;
use triwild::__bench::bsp_of_segments;

struct Rng(u64);
impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn soup(n: usize) -> Vec<(Point, Point)> {
    let mut rng = Rng(7 + n as u64);
    let len = 3.0 / (n as f64).sqrt();
    (0..n)
        .map(|_| {
            let a = Point::new(rng.next_f64(), rng.next_f64());
            let ang = rng.next_f64() * std::f64::consts::TAU;
            let b = Point::new(
                (a.x + len * ang.cos()).clamp(0.0, 1.0),
                (a.y + len * ang.sin()).clamp(0.0, 1.0),
            );
            (a, b)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let bbox = Rect::new(-0.1, -0.1, 1.1, 1.1);
    for n in [100, 1000, 10000] {
        let input = soup(n);
        let stats = bsp_of_segments(&input, bbox).expect("bsp builds");
        println!(
            "n={n}: {} seed triangles, {} cut, {} cells, {} vertices ({} rational before rounding, {} after), {} triangles, {:.3}s (seed {:.3}s, cut {:.3}s, finish {:.3}s)",
            stats.seed_triangles,
            stats.cut_triangles,
            stats.cells,
            stats.vertices,
            stats.rational_before_rounding,
            stats.rational_vertices,
            stats.triangles,
            stats.seconds,
            stats.seed_seconds,
            stats.cut_seconds,
            stats.finish_seconds,
        );
        c.bench_function(&format!("bsp soup {n}"), |bch| {
            bch.iter(|| black_box(bsp_of_segments(&input, bbox).expect("bsp builds")))
        });
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
