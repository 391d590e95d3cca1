//! Jacobian certification of curved cubic triangles (docs/design.md "Curved elements"):
//! Bernstein coefficients alone, validity only, validity with a tight ratio, an
//! element that needs subdivision, and a whole mesh check.
#![allow(missing_docs, reason = "criterion macros generate undocumented items")]

use criterion::{Criterion, criterion_group, criterion_main};
use kurbo::{CubicBez, Point};
use std::hint::black_box;
use triwild::Order;
use triwild::element::jacobian::{certify, det_cubic, zero_abs};
use triwild::element::lagrange::{CurvedEdge, cubic_nodes};
use triwild::{CertifyOptions, certify_mesh};

/// A triangle whose edge 0→1 is a cubic arc bulging by `bulge` (negative: inwards).
fn element(bulge: f64) -> [Point; 10] {
    let c = CubicBez::new((0.0, 0.0), (0.3, -bulge), (0.7, -bulge), (1.0, 0.0));
    let e = CurvedEdge {
        edge: 0,
        curve: c,
        t0: 0.0,
        t1: 1.0,
    };
    cubic_nodes(
        [
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(0.4, 0.9),
        ],
        Some(&e),
    )
}

fn bench(c: &mut Criterion) {
    // typical: a gentle outward arc (all 15 coefficients positive at once)
    let typical = element(0.1);
    // hard: an inward arc whose coefficients go negative, certified after subdivision
    let hard = element(-0.3);
    let z = zero_abs(&typical, 1e-12);
    c.bench_function("det_cubic (15 Bernstein coefficients)", |b| {
        b.iter(|| det_cubic(black_box(&typical)))
    });
    c.bench_function("certify typical, validity only", |b| {
        b.iter(|| {
            certify(
                &det_cubic(black_box(&typical)),
                z,
                &CertifyOptions::VALIDITY,
            )
        })
    });
    c.bench_function("certify typical, ratio to rtol 1e-3", |b| {
        b.iter(|| certify(&det_cubic(black_box(&typical)), z, &CertifyOptions::DEFAULT))
    });
    c.bench_function("certify inward arc (subdivision), validity only", |b| {
        b.iter(|| certify(&det_cubic(black_box(&hard)), z, &CertifyOptions::VALIDITY))
    });
    c.bench_function("certify inward arc, ratio to rtol 1e-3", |b| {
        b.iter(|| certify(&det_cubic(black_box(&hard)), z, &CertifyOptions::DEFAULT))
    });
    // a mesh of 1000 curved elements (bulges spread over [-0.2, 0.3])
    let mut nodes = Vec::new();
    let mut tris = Vec::new();
    for i in 0..1000 {
        let e = element(-0.2 + 0.5 * (i as f64 / 999.0));
        let base = nodes.len() as u32;
        nodes.extend_from_slice(&e);
        tris.extend(base..base + 10);
    }
    c.bench_function("certify_mesh, 1000 curved cubic triangles", |b| {
        b.iter(|| {
            certify_mesh(
                black_box(&nodes),
                tris.chunks_exact(10).map(|t| (Order::Cubic, t)),
                &CertifyOptions::DEFAULT,
            )
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
