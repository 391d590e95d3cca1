//! The size field: building it and looking it up, on the plate
//! fixture with a `--size-near` field (graded cones from an outline) and on a
//! bundled drawing whose thin stroke is a field of its own. `Tree::at` is what
//! the optimizer's edge targets call for every edge of a non-uniform field.
#![allow(missing_docs, reason = "criterion macros generate undocumented items")]

use criterion::{Criterion, criterion_group, criterion_main};
use kurbo::Point;
use std::hint::black_box;
use triwild::__bench::SizeFieldProbe;
use triwild::{Length, Params, SizeSpec};

/// `n` points spread over `[0, w] × [-h, 0]` by a fixed low-discrepancy walk.
fn points(n: usize, w: f64, h: f64) -> Vec<Point> {
    let (a, b) = (0.754_877_666_246_692_8, 0.569_840_290_998_053_3);
    (0..n)
        .map(|i| {
            let i = i as f64;
            Point::new((i * a).fract() * w, -(i * b).fract() * h)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let plate = triwild::load_bytes(
        include_bytes!("../tests/fixtures/plate.svg"),
        &triwild::LoadOptions::DEFAULT,
    )
    .expect("plate");
    let near = Params::DEFAULT
        .with_l(Length::Abs(5.0))
        .with_size(SizeSpec::DEFAULT.with_near("steel", Length::Abs(0.5), Some(Length::Abs(10.0))));
    let star = triwild::load_file(
        std::path::Path::new("data/svg/star-evenodd.svg"),
        &triwild::LoadOptions::DEFAULT,
    )
    .expect("star");
    let plain = Params::DEFAULT;
    c.bench_function("size field build (plate, --size-near steel=0.5:10)", |b| {
        b.iter(|| SizeFieldProbe::build(black_box(&plate), &near).expect("field"))
    });
    c.bench_function("size field build (star-evenodd, stroke)", |b| {
        b.iter(|| SizeFieldProbe::build(black_box(&star), &plain).expect("field"))
    });
    let cases = [
        (
            "plate near",
            SizeFieldProbe::build(&plate, &near).expect("field"),
            points(10_000, 100.0, 100.0),
        ),
        (
            "star stroke",
            SizeFieldProbe::build(&star, &plain).expect("field"),
            {
                let bb = star.extent();
                points(10_000, bb.width(), bb.height())
                    .into_iter()
                    .map(|p| Point::new(bb.x0 + p.x, bb.y1 + p.y))
                    .collect()
            },
        ),
    ];
    for (name, field, pts) in &cases {
        c.bench_function(&format!("size field at x10000 ({name})"), |b| {
            b.iter(|| pts.iter().map(|&p| field.at(black_box(p))).sum::<f64>())
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
