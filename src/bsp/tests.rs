//! Property and regression tests of the BSP mesher. The conformity check here
//! is independent of the mesher: it finds, in rationals, every mesh vertex on
//! each input segment, sorts them along it, and asks that each consecutive
//! pair be a mesh edge.

use super::*;
use crate::exact::{Orientation, PointQ, orient2d_q};
use crate::mesh::{EdgeKey, FaceId, FeatureOn, VertexId};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::cmp::Ordering;
use std::collections::HashSet;

fn p(x: f64, y: f64) -> Point {
    Point::new(x, y)
}

fn sc(q: Point, s: f64) -> Point {
    Point::new(q.x * s, q.y * s)
}

fn seg(a: Point, b: Point, i: u32) -> BspSegment {
    BspSegment {
        a,
        b,
        tag: if i % 2 == 0 {
            SegmentTag::Secondary { polyline: i }
        } else {
            SegmentTag::Primary {
                section: i,
                t: [0.0, 1.0],
            }
        },
    }
}

fn padded_box(input: &BspInput) -> Rect {
    let mut pts = input
        .points
        .iter()
        .copied()
        .chain(input.segments.iter().flat_map(|s| [s.a, s.b]));
    let Some(first) = pts.next() else {
        return Rect::new(0.0, 0.0, 1.0, 1.0);
    };
    let r = pts.fold(Rect::from_points(first, first), |r, q| r.union_pt(q));
    let pad = (r.width().max(r.height()) * 0.1).max(f64::MIN_POSITIVE * 1e10);
    r.inflate(pad, pad)
}

/// Every segment is exactly a chain of mesh edges, each tagged with it.
fn assert_conforming(mesh: &TriMesh, input: &BspInput) {
    let mut edges: HashSet<EdgeKey> = HashSet::new();
    for f in mesh.faces() {
        let [a, b, c] = mesh.face(f);
        edges.extend([EdgeKey::new(a, b), EdgeKey::new(b, c), EdgeKey::new(c, a)]);
    }
    let verts: Vec<(VertexId, PointQ)> = mesh.vertices().map(|v| (v, mesh.point_q(v))).collect();
    for (si, s) in input.segments.iter().enumerate() {
        let (qa, qb) = (PointQ::from_point(s.a), PointQ::from_point(s.b));
        if s.a == s.b {
            assert!(
                verts.iter().any(|(_, q)| *q == qa),
                "segment {si}: point-like segment is a vertex"
            );
            continue;
        }
        let mut on: Vec<&(VertexId, PointQ)> = verts
            .iter()
            .filter(|(_, q)| {
                orient2d_q(&qa, &qb, q) == Orientation::Collinear
                    && q.cmp_along_q(&qa, &qa, &qb) != Ordering::Less
                    && q.cmp_along_q(&qb, &qa, &qb) != Ordering::Greater
            })
            .collect();
        on.sort_by(|x, y| x.1.cmp_along_q(&y.1, &qa, &qb));
        assert!(on.len() >= 2, "segment {si}: endpoints are vertices");
        assert_eq!(on[0].1, qa);
        assert_eq!(on[on.len() - 1].1, qb);
        for w in on.windows(2) {
            let key = EdgeKey::new(w[0].0, w[1].0);
            assert!(
                edges.contains(&key),
                "segment {si} {s:?}: {key:?} is not a mesh edge"
            );
            let tags = mesh.edge_tags(w[0].0, w[1].0);
            let want = match s.tag {
                SegmentTag::Primary { section, .. } => tags
                    .iter()
                    .any(|t| matches!(t, FeatureOn::Primary { section: x, .. } if *x == section)),
                SegmentTag::Secondary { polyline } => {
                    tags.contains(&FeatureOn::Secondary { polyline })
                }
            };
            assert!(want, "segment {si}: edge {key:?} lacks its tag: {tags:?}");
        }
    }
}

/// The triangles tile the box: their (approximate) areas sum to its area.
fn assert_covers(mesh: &TriMesh, bbox: Rect) {
    let mut area = 0.0;
    for f in mesh.faces() {
        // In box-relative units, so tiny and huge scales neither under- nor overflow.
        let [a, b, c] = mesh.face(f).map(|v| {
            let q = mesh.position(v);
            Point::new(
                (q.x - bbox.x0) / bbox.width(),
                (q.y - bbox.y0) / bbox.height(),
            )
        });
        area += (b - a).cross(c - a) * 0.5;
    }
    let want = 1.0;
    assert!(
        ((area - want) / want).abs() < 1e-9,
        "area {area} vs box {want}"
    );
}

fn run(input: &BspInput, round: bool) -> (TriMesh, BspStats) {
    let bbox = padded_box(input);
    let (mesh, stats) =
        build(input, bbox, &BspOptions::DEFAULT.with_round(round)).expect("bsp builds");
    let defects = mesh.check();
    assert!(
        defects.is_empty(),
        "defects: {:?}",
        &defects[..defects.len().min(10)]
    );
    assert_covers(&mesh, bbox);
    if !round {
        assert_conforming(&mesh, input);
        assert_eq!(stats.rational_vertices, stats.rational_before_rounding);
    }
    assert!(stats.rational_vertices <= stats.rational_before_rounding);
    assert_eq!(stats.vertices, mesh.num_vertices());
    (mesh, stats)
}

fn run_both(input: &BspInput) -> BspStats {
    run(input, false);
    run(input, true).1
}

// ---- generators -------------------------------------------------------------

/// Segment soups mixing: coarse-lattice segments (collinear overlaps,
/// duplicates, T-junctions, shared endpoints), free random segments (many
/// crossings), nearly parallel pairs (one endpoint moved by one ulp), and
/// isolated points; all multiplied by `scale`.
fn soup(max_segments: usize) -> impl Strategy<Value = BspInput> {
    let lattice = (0u8..9, 0u8..9, 0u8..9, 0u8..9).prop_map(|(a, b, c, d)| {
        (
            p(f64::from(a), f64::from(b)),
            p(f64::from(c), f64::from(d)),
            0u8,
        )
    });
    let free = (0.0..8.0f64, 0.0..8.0f64, 0.0..8.0f64, 0.0..8.0f64)
        .prop_map(|(a, b, c, d)| (p(a, b), p(c, d), 0u8));
    let near_parallel = (0.5..8.0f64, 0.5..8.0f64, 0.5..8.0f64, 0.5..8.0f64, 1u8..3)
        .prop_map(|(a, b, c, d, kind)| (p(a, b), p(c, d), kind));
    let piece = prop_oneof![3 => lattice, 3 => free, 1 => near_parallel];
    (
        proptest::collection::vec(piece, 1..max_segments),
        proptest::collection::vec((0u8..9, 0u8..9), 0..4),
        prop_oneof![Just(1.0), Just(1e-9), Just(1e9), Just(3.0e-7)],
    )
        .prop_map(|(pieces, pts, scale)| {
            let mut segments = Vec::new();
            for (a, b, kind) in pieces {
                let i = u32::try_from(segments.len()).expect("small");
                segments.push(seg(sc(a, scale), sc(b, scale), i));
                // One ulp up (coordinates here are positive).
                let up = |v: f64| f64::from_bits(v.to_bits() + 1);
                let (a2, b2) = (sc(a, scale), sc(b, scale));
                match kind {
                    1 => segments.push(seg(a2, p(b2.x, up(b2.y)), i + 1)),
                    2 => segments.push(seg(p(a2.x, up(a2.y)), p(b2.x, up(b2.y)), i + 1)),
                    _ => {}
                }
            }
            let points = pts
                .into_iter()
                .map(|(x, y)| sc(p(f64::from(x) + 0.5, f64::from(y) + 0.25), scale))
                .collect();
            BspInput {
                points,
                section_endpoints: Vec::new(),
                steiner: Vec::new(),
                segments,
            }
        })
}

fn runner(cases: u32) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha))
}

#[test]
fn random_soups_are_valid_and_conforming() {
    let mut r = runner(48);
    r.run(&soup(24), |input| {
        run_both(&input);
        Ok(())
    })
    .expect("property holds");
}

#[test]
fn larger_random_soups() {
    let mut r = runner(6);
    r.run(&soup(120), |input| {
        run_both(&input);
        Ok(())
    })
    .expect("property holds");
}

// ---- named regressions ---------------------------------------------------------

#[test]
fn empty_input_is_the_box() {
    let input = BspInput::default();
    let (mesh, stats) =
        build(&input, Rect::new(0.0, 0.0, 2.0, 1.0), &BspOptions::DEFAULT).expect("ok");
    assert_eq!(stats.triangles, 2);
    assert_eq!(mesh.num_vertices(), 4);
    assert!(mesh.check().is_empty());
}

#[test]
fn crossing_pair_splits_at_exact_point() {
    let input = BspInput {
        segments: vec![
            seg(p(0.0, 0.0), p(3.0, 1.0), 0),
            seg(p(0.0, 1.0), p(1.0, -1.0), 1),
        ],
        ..BspInput::default()
    };
    let (mesh, _) = run(&input, false);
    // x = 3/7: the crossing is rational, not an f64.
    assert!(mesh.vertices().any(|v| mesh.is_rational(v)));
    run(&input, true);
}

#[test]
fn collinear_overlaps_duplicates_and_t_junctions() {
    let input = BspInput {
        segments: vec![
            seg(p(0.0, 0.0), p(4.0, 0.0), 0),
            seg(p(1.0, 0.0), p(6.0, 0.0), 1),
            seg(p(4.0, 0.0), p(0.0, 0.0), 2),
            seg(p(2.0, 0.0), p(2.0, 3.0), 3),
            seg(p(2.0, 3.0), p(2.0, 3.0), 4),
            seg(p(0.0, 0.0), p(6.0, 3.0), 5),
            seg(p(0.0, 3.0), p(6.0, 0.0), 6),
        ],
        points: vec![p(3.0, 1.5), p(5.0, 2.0)],
        ..BspInput::default()
    };
    run_both(&input);
}

#[test]
fn star_through_one_point() {
    let segments = (0..24)
        .map(|k| {
            let a = f64::from(k) * 0.27;
            seg(p(-a.cos(), -a.sin()), p(a.cos(), a.sin()), k)
        })
        .collect();
    run_both(&BspInput {
        segments,
        ..BspInput::default()
    });
}

#[test]
fn dense_grid_of_crossings() {
    let mut segments = Vec::new();
    for k in 0..15 {
        let t = f64::from(k) / 7.0;
        segments.push(seg(p(t, -0.1), p(t + 0.3, 2.1), 2 * k));
        segments.push(seg(p(-0.1, t * 0.9), p(2.1, t + 0.1), 2 * k + 1));
    }
    let stats = run_both(&BspInput {
        segments,
        ..BspInput::default()
    });
    assert!(stats.cut_triangles > 0 && stats.rational_before_rounding > 100);
}

#[test]
fn segment_on_box_boundary_and_tiny_scale() {
    let input = BspInput {
        segments: vec![
            seg(p(0.0, 0.0), p(1.0, 0.0), 0),
            seg(p(0.0, 0.0), p(1.0, 1.0), 1),
        ],
        ..BspInput::default()
    };
    let (mesh, _) = build(&input, Rect::new(0.0, 0.0, 1.0, 1.0), &BspOptions::DEFAULT).expect("ok");
    assert!(mesh.check().is_empty());
    let s = 1e-300;
    let tiny = BspInput {
        segments: vec![
            seg(p(0.0, 0.0), p(3.0 * s, s), 0),
            seg(p(0.0, s), p(s, -s), 1),
        ],
        ..BspInput::default()
    };
    let (_, stats) = run(&tiny, false);
    assert!(stats.delaunay_scale_exp > 0);
}

#[test]
fn bad_inputs_are_errors() {
    let nan = BspInput {
        points: vec![p(f64::NAN, 0.0)],
        ..BspInput::default()
    };
    let r = build(&nan, Rect::new(0.0, 0.0, 1.0, 1.0), &BspOptions::DEFAULT);
    assert!(matches!(r, Err(crate::Error::BadCoordinate(_))));
    let outside = BspInput {
        points: vec![p(2.0, 0.0)],
        ..BspInput::default()
    };
    let r = build(
        &outside,
        Rect::new(0.0, 0.0, 1.0, 1.0),
        &BspOptions::DEFAULT,
    );
    assert!(matches!(r, Err(crate::Error::BadCoordinate(_))));
    let r = build(
        &BspInput::default(),
        Rect::new(0.0, 0.0, 0.0, 1.0),
        &BspOptions::DEFAULT,
    );
    assert!(matches!(r, Err(crate::Error::InvalidParams(_))));
    let huge_range = BspInput {
        points: vec![p(1e-300, 0.0)],
        ..BspInput::default()
    };
    let r = build(
        &huge_range,
        Rect::new(0.0, 0.0, 1e300, 1.0),
        &BspOptions::DEFAULT,
    );
    assert!(matches!(r, Err(crate::Error::BadCoordinate(_))));
    let many = BspInput {
        segments: (0..10)
            .map(|k| seg(p(0.0, f64::from(k)), p(10.0, 10.0 - f64::from(k)), k))
            .collect(),
        ..BspInput::default()
    };
    let r = build(
        &many,
        Rect::new(-1.0, -1.0, 11.0, 11.0),
        &BspOptions::DEFAULT.with_max_vertices(8),
    );
    assert!(matches!(r, Err(crate::Error::Meshing { .. })));
}

/// Rounding in levels, in parallel, moves every vertex exactly where the
/// plain Gauss–Seidel order does: each vertex in index order, seeing the
/// earlier ones rounded.
#[test]
fn rounding_in_levels_matches_the_sequential_order() {
    fn sequential(mesh: &mut TriMesh, passes: u32) {
        for _ in 0..passes {
            let rational: Vec<VertexId> =
                mesh.vertices().filter(|&v| mesh.is_rational(v)).collect();
            let mut changed = false;
            for v in rational {
                let star: Vec<FaceId> = mesh
                    .faces()
                    .filter(|&f| mesh.face(f).contains(&v))
                    .collect();
                let fits = |p: Point| {
                    star.iter().all(|&f| {
                        mesh.orientation_if_moved(f, v, p) == Orientation::CounterClockwise
                    })
                };
                let p0 = mesh.position(v);
                let exact = mesh.exact(v).expect("rational").coords_are_f64();
                if let Some(to) = fan::round_candidates(p0, exact)
                    .into_iter()
                    .find(|&c| fits(c))
                {
                    mesh.set_position(v, to);
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    let mut r = runner(6);
    let levelled = std::cell::Cell::new(0);
    r.run(&soup(120), |input| {
        let (unrounded, stats) = run(&input, false);
        let mut want = unrounded.clone();
        sequential(&mut want, 2);
        let mut got = unrounded;
        pool.install(|| {
            fan::round_vertices(&mut got, 2, &crate::budget::Deadline::NONE).expect("no deadline")
        });
        prop_assert!(got == want, "levels and the sequential order differ");
        levelled.set(levelled.get() + stats.rational_before_rounding);
        Ok(())
    })
    .expect("property holds");
    // Enough rational vertices that some levels were decided in parallel.
    let levelled = levelled.get();
    assert!(levelled > 500, "only {levelled} rational vertices");
}

/// Points on both sides of the diagonal (0,0)-(4,4), close to it: the plain
/// Delaunay triangulation's edges between them cross the diagonal dozens of
/// times.
fn beside_diagonal() -> Vec<Point> {
    (1..40)
        .flat_map(|k| {
            let t = f64::from(k) * 0.1;
            [p(t, t + 0.05), p(t + 0.05, t)]
        })
        .collect()
}

#[test]
fn constrained_seed_cuts_only_what_crosses() {
    // A hatch of long parallel lines, each rising 50 spacings: with a plain
    // Delaunay seed each line crossed a row of thin triangles; as constraints
    // of the seed, none is cut.
    let segments: Vec<BspSegment> = (0..100)
        .map(|k| {
            let y = f64::from(k) * 0.05;
            seg(p(0.0, y), p(10.0, y + 2.5), k)
        })
        .collect();
    let input = BspInput {
        segments,
        ..BspInput::default()
    };
    let stats = run_both(&input);
    // (the first and last lines cross fewer than 32 edges: not offered)
    assert!(stats.seed_constraints >= 80, "{stats:?}");
    assert_eq!(stats.seed_refused, 0);
    assert!(stats.cut_triangles <= 4, "{stats:?}");
    // Two long crossing diagonals, each beside a row of points the plain
    // triangulation joins across it: both are offered, spade takes one and
    // refuses the other, which is cut, exactly.
    let mut points = beside_diagonal();
    points.extend(beside_diagonal().into_iter().map(|q| p(q.x, 4.0 - q.y)));
    points.retain(|q| (q.x - 2.0).abs() > 0.3);
    let stats = run_both(&BspInput {
        segments: vec![
            seg(p(0.0, 0.0), p(4.0, 4.0), 0),
            seg(p(0.0, 4.0), p(4.0, 0.0), 1),
        ],
        points,
        ..BspInput::default()
    });
    assert_eq!(
        (stats.seed_constraints, stats.seed_refused),
        (2, 1),
        "{stats:?}"
    );
    assert!(stats.cut_triangles > 0 && stats.rational_before_rounding > 0);
    // Short segments that cross a few Delaunay edges stay out of the seed
    // (the exact BSP cuts them): a crossing pair.
    let stats = run_both(&BspInput {
        segments: vec![
            seg(p(0.0, 0.0), p(3.0, 1.0), 0),
            seg(p(0.0, 1.0), p(1.0, -1.0), 1),
        ],
        ..BspInput::default()
    });
    assert_eq!((stats.seed_constraints, stats.seed_refused), (0, 0));
    assert!(stats.cut_triangles > 0);
}

#[test]
fn constrained_seed_makes_no_thin_triangle() {
    // A segment endpoint one ulp off the diagonal's line, between its ends:
    // with the diagonal as a constraint the seed would hold a triangle of area
    // ~1e-16; the diagonal is refused (cut instead), and no seed triangle is
    // thinner than the plain Delaunay one would be.
    let up = |v: f64| f64::from_bits(v.to_bits() + 1);
    let input = BspInput {
        segments: vec![
            seg(p(0.0, 0.0), p(4.0, 4.0), 0),
            seg(p(2.0, up(2.0)), p(1.0, 5.0), 1),
        ],
        points: beside_diagonal(),
        ..BspInput::default()
    };
    let bbox = padded_box(&input);
    let s = super::seed::seed(&input, bbox).expect("seed");
    assert!(s.constraints >= 1, "the diagonal is offered");
    assert!(s.refused >= 1, "refused {}", s.refused);
    for t in &s.triangles {
        let [a, b, c] = t.map(|i| s.points[i as usize].0);
        let twice = (b - a).cross(c - a);
        assert!(twice > 1e-6, "thin seed triangle {a:?} {b:?} {c:?}");
    }
    run_both(&input);
}

/// The tagging and the rounding check the deadline as they go (a BSP of
/// millions of crossings can spend over a minute in them after the cut's last
/// check): with a passed deadline each stops with the time-limit error of the
/// BSP stage, and without one the rounding moves every vertex it moved before.
#[test]
fn tagging_and_rounding_stop_at_a_passed_deadline() {
    // 70 lines each way, slanted: about 4 900 crossings, each a rational vertex.
    let mut segments = Vec::new();
    for k in 0..70u32 {
        let t = f64::from(k) / 7.0;
        let i = 2 * k;
        segments.push(seg(p(0.0, t + 0.1), p(10.0, t + 0.37), i));
        segments.push(seg(p(t + 0.2, 0.0), p(t + 0.53, 10.0), i + 2));
    }
    let input = BspInput {
        points: Vec::new(),
        section_endpoints: Vec::new(),
        steiner: Vec::new(),
        segments,
    };
    let (unrounded, stats) = run(&input, false);
    assert!(
        stats.rational_before_rounding > fan::CHECK_EVERY,
        "only {} rational vertices",
        stats.rational_before_rounding
    );
    let passed = crate::budget::Deadline::after(Some(0.0));
    let is_bsp_time_limit = |r: crate::Result<()>| {
        matches!(
            r,
            Err(crate::Error::TimeLimit {
                stage: crate::stage::Stage::Bsp,
                ..
            })
        )
    };
    let mut m = unrounded.clone();
    assert!(is_bsp_time_limit(fan::tag_segments(
        &mut m, &input, &passed
    )));
    let mut m = unrounded.clone();
    assert!(is_bsp_time_limit(fan::round_vertices(&mut m, 2, &passed)));
    let mut m = unrounded;
    fan::round_vertices(&mut m, 2, &crate::budget::Deadline::NONE).expect("no deadline");
    assert!(m.vertices().filter(|&v| m.is_rational(v)).count() < stats.rational_before_rounding);
}
