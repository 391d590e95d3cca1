//! The exact kernel: orient2d on f64 points, the interval filter on rational
//! points (hit rate printed once), and the exact rational fallback.
#![allow(missing_docs, reason = "criterion macros generate undocumented items")]
#![allow(clippy::print_stdout, reason = "the bench reports the filter hit rate")]

use criterion::{Criterion, criterion_group, criterion_main};
use kurbo::Point;
use std::hint::black_box;
use triwild::__bench::{PointQ, orient2d, orient2d_q, orient2d_q_exact, orient2d_q_filter};

/// xorshift64*: deterministic, dependency-free.
struct Rng(u64);
impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn point(&mut self) -> Point {
        Point::new(self.next_f64() * 100.0, self.next_f64() * 100.0)
    }
}

/// Rational triples like the BSP makes: crossing points of f64 lines, tested
/// against f64 lines; `degenerate` puts the third point on the line.
fn rational_triples(n: usize, degenerate: bool) -> Vec<(PointQ, PointQ, PointQ)> {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    (0..n)
        .map(|_| {
            let a = PointQ::from_point(rng.point());
            let b = PointQ::from_point(rng.point());
            let c = if degenerate {
                a.lerp_ratio(&b, 1.0 + (rng.next_f64() * 5.0).floor(), 7.0)
            } else {
                let x = PointQ::from_point(rng.point());
                x.lerp_ratio(&PointQ::from_point(rng.point()), 1.0, 3.0)
            };
            (a, b, c)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut rng = Rng(42);
    let f64_triples: Vec<(Point, Point, Point)> = (0..1000)
        .map(|_| (rng.point(), rng.point(), rng.point()))
        .collect();
    let general = rational_triples(1000, false);
    let degenerate = rational_triples(1000, true);
    let hits = |t: &[(PointQ, PointQ, PointQ)]| {
        t.iter()
            .filter(|(a, b, c)| orient2d_q_filter(a, b, c).is_some())
            .count() as f64
            / t.len() as f64
    };
    println!(
        "filter hit rate: general rational triples {:.1}%, collinear rational triples {:.1}%",
        100.0 * hits(&general),
        100.0 * hits(&degenerate)
    );
    c.bench_function("orient2d f64 (robust) x1000", |bch| {
        bch.iter(|| {
            for &(a, b, p) in &f64_triples {
                black_box(orient2d(a, b, p));
            }
        })
    });
    c.bench_function("orient2d_q filtered, general x1000", |bch| {
        bch.iter(|| {
            for (a, b, p) in &general {
                black_box(orient2d_q(a, b, p));
            }
        })
    });
    c.bench_function("orient2d_q exact only, general x1000", |bch| {
        bch.iter(|| {
            for (a, b, p) in &general {
                black_box(orient2d_q_exact(a, b, p));
            }
        })
    });
    c.bench_function("orient2d_q filtered, collinear x1000", |bch| {
        bch.iter(|| {
            for (a, b, p) in &degenerate {
                black_box(orient2d_q(a, b, p));
            }
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
