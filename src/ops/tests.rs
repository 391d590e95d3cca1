//! Property tests of the local operations: random sequences of operations on
//! random meshes (a constrained Delaunay mesh with a curved primary chain and
//! a secondary polyline; BSP meshes of random segment soups) keep `check()`
//! clean and every invariant true, and a rejected operation leaves the mesh
//! equal to before. Fixed seeds.

use super::invariants::{curvature, on_curve};
use super::*;
use crate::bsp::{self, BspInput, BspOptions, BspSegment, SegmentTag};
use crate::mesh::VertexTag;
use kurbo::{CubicBez, Line, Point, Rect};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
use std::collections::HashMap;

/// A small deterministic generator (splitmix64).
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

fn curve() -> CubicBez {
    CubicBez::new((0.1, 0.3), (0.35, 0.36), (0.65, 0.36), (0.9, 0.3))
}

/// A CDT of the unit box with a curved primary chain (two sections of one
/// cubic, split at t = 0.5), a secondary polyline and random points.
pub(crate) fn delaunay_mesh(seed: u64, energy: EnergyRule) -> (TriMesh, Context) {
    delaunay_mesh_on(seed, energy, Parent::Cubic(curve()))
}

/// An exact conic arc over the same span as [`curve`] (a piece of an ellipse).
fn conic_curve() -> crate::svg::drawing::Conic {
    crate::svg::drawing::Conic::new((0.1, 0.3), (0.5, 0.42), (0.9, 0.3), 0.8)
}

/// [`delaunay_mesh`] with the primary chain on `parent`.
fn delaunay_mesh_on(seed: u64, energy: EnergyRule, parent: Parent) -> (TriMesh, Context) {
    let mut rng = Rng(seed);
    let sections = vec![
        CurveSection {
            parent,
            t: [0.0, 0.5],
            source: None,
            shared: None,
        },
        CurveSection {
            parent,
            t: [0.5, 1.0],
            source: None,
            shared: None,
        },
    ];
    let polyline: Vec<Point> = [(0.1, 0.7), (0.3, 0.75), (0.5, 0.65), (0.7, 0.8), (0.9, 0.7)]
        .map(Point::from)
        .to_vec();
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    let mut tags: Vec<VertexTag> = Vec::new();
    let mut ins =
        |cdt: &mut ConstrainedDelaunayTriangulation<Point2<f64>>, p: Point, tag: VertexTag| {
            let h = cdt.insert(Point2::new(p.x, p.y)).expect("finite point");
            if h.index() >= tags.len() {
                tags.resize(h.index() + 1, VertexTag::default());
            }
            tags[h.index()] = tags[h.index()].union(tag);
            h
        };
    let corner = VertexTag {
        box_corner: true,
        ..VertexTag::default()
    };
    for p in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        ins(&mut cdt, p.into(), corner);
    }
    let n_curve = 8;
    let mut chain = Vec::new();
    for i in 0..=n_curve {
        let t = f64::from(i) / f64::from(n_curve);
        let tag = VertexTag {
            section_endpoint: i == 0 || i == n_curve || 2 * i == n_curve,
            ..VertexTag::default()
        };
        chain.push((ins(&mut cdt, parent.eval(t), tag), t));
    }
    let mut sec = Vec::new();
    for (k, w) in polyline.windows(2).enumerate() {
        let parts = 1 + rng.below(3);
        for j in 0..parts {
            let tag = VertexTag {
                segment_endpoint: j == 0,
                ..VertexTag::default()
            };
            sec.push(ins(&mut cdt, w[0].lerp(w[1], j as f64 / parts as f64), tag));
        }
        if k == polyline.len() - 2 {
            let tag = VertexTag {
                segment_endpoint: true,
                ..VertexTag::default()
            };
            sec.push(ins(&mut cdt, w[1], tag));
        }
    }
    for _ in 0..(20 + rng.below(40)) {
        let p = Point::new(0.02 + 0.96 * rng.unit(), 0.02 + 0.96 * rng.unit());
        let near_curve = (0..=64).any(|i| p.distance(parent.eval(f64::from(i) / 64.0)) < 0.03);
        let near_sec = polyline
            .windows(2)
            .any(|w| (0..=32).any(|i| p.distance(w[0].lerp(w[1], f64::from(i) / 32.0)) < 0.03));
        if !near_curve && !near_sec {
            ins(&mut cdt, p, VertexTag::default());
        }
    }
    for w in chain.windows(2) {
        cdt.add_constraint(w[0].0, w[1].0);
    }
    for w in sec.windows(2) {
        cdt.add_constraint(w[0], w[1]);
    }
    let (mut mesh, ids) = crate::mesh::trimesh_of_cdt(&cdt, &tags);
    for w in chain.windows(2) {
        let ((a, ta), (b, tb)) = (w[0], w[1]);
        let section = u32::from(ta >= 0.5);
        mesh.add_edge_tag(
            ids[a.index()],
            ids[b.index()],
            FeatureOn::Primary {
                section,
                t: [ta, tb],
            },
        );
    }
    for w in sec.windows(2) {
        mesh.add_edge_tag(
            ids[w[0].index()],
            ids[w[1].index()],
            FeatureOn::Secondary { polyline: 0 },
        );
    }
    let ctx = Context {
        sections,
        envelope: Envelope::new(&[polyline], 0.02, 0.02),
        alpha: 15f64.to_radians(),
        on_curve_abs: 1e-12,
        energy,
        energy_floor: 0.0,
        max_new_edge: f64::INFINITY,
        curved: None,
        fixed_boundary: false,
    };
    (mesh, ctx)
}

/// The BSP mesh of a random segment soup: odd segments primary (straight
/// sections), even ones secondary (one polyline each).
pub(crate) fn bsp_mesh(seed: u64, energy: EnergyRule) -> (TriMesh, Context) {
    let mut rng = Rng(seed);
    let mut input = BspInput::default();
    let mut sections = Vec::new();
    let mut polylines = Vec::new();
    for i in 0..(3 + rng.below(6)) {
        let mut pt = || {
            // Some points on a coarse grid, for collinear and touching segments.
            if rng.below(3) == 0 {
                Point::new(rng.below(5) as f64 / 4.0, rng.below(5) as f64 / 4.0)
            } else {
                Point::new(rng.unit(), rng.unit())
            }
        };
        let (a, b) = (pt(), pt());
        if a == b {
            continue;
        }
        let tag = if i % 2 == 1 {
            sections.push(CurveSection {
                parent: Parent::Line(Line::new(a, b)),
                t: [0.0, 1.0],
                source: None,
                shared: None,
            });
            input.section_endpoints.extend([a, b]);
            SegmentTag::Primary {
                section: (sections.len() - 1) as u32,
                t: [0.0, 1.0],
            }
        } else {
            polylines.push(vec![a, b]);
            SegmentTag::Secondary {
                polyline: (polylines.len() - 1) as u32,
            }
        };
        input.segments.push(BspSegment { a, b, tag });
    }
    let bbox = Rect::new(-0.25, -0.25, 1.25, 1.25);
    let (mesh, _) = bsp::build(&input, bbox, &BspOptions::DEFAULT).expect("bsp of a small soup");
    let ctx = Context {
        sections,
        envelope: Envelope::new(&polylines, 0.01, 0.01),
        alpha: 10f64.to_radians(),
        on_curve_abs: 1e-12,
        energy,
        energy_floor: 0.0,
        max_new_edge: f64::INFINITY,
        curved: None,
        fixed_boundary: false,
    };
    (mesh, ctx)
}

/// Every invariant on the whole mesh; `off` tracks each primary vertex's
/// distance to its curve, which may never grow past the tolerance.
pub(crate) fn assert_invariants(
    mesh: &TriMesh,
    ctx: &Context,
    off: &mut HashMap<VertexId, f64>,
    what: &str,
) {
    let defects = mesh.check();
    assert!(defects.is_empty(), "{what}: {defects:?}");
    for (key, tags) in mesh.tagged_edges() {
        for t in tags {
            match *t {
                FeatureOn::Primary { section, t } => {
                    assert!(
                        curvature::holds(ctx, section, t),
                        "{what}: curvature {key:?}"
                    )
                }
                FeatureOn::Secondary { polyline } => assert!(
                    ctx.envelope.contains_segment(
                        mesh.position(key.lo),
                        mesh.position(key.hi),
                        polyline
                    ),
                    "{what}: envelope {key:?}"
                ),
            }
        }
    }
    for v in mesh.vertices() {
        if let Some(d) = on_curve::off_curve(mesh, ctx, v) {
            assert!(d.is_finite(), "{what}: inconsistent t at {v:?}");
            let before = off.get(&v).copied().unwrap_or(f64::INFINITY);
            assert!(
                d <= before.max(ctx.on_curve_abs),
                "{what}: {v:?} moved away from its curve: {d} > {before}"
            );
            off.insert(v, d);
        }
    }
}

#[derive(Default, Debug)]
struct Tally {
    applied: [usize; 7],
    rejected: HashMap<Reject, usize>,
}

fn run_ops(mut mesh: TriMesh, ctx: &Context, seed: u64, n_ops: usize) -> Tally {
    let mut rng = Rng(seed ^ 0xABCD);
    let mut off = HashMap::new();
    let mut tally = Tally::default();
    assert_invariants(&mesh, ctx, &mut off, "initial");
    for step in 0..n_ops {
        let faces: Vec<FaceId> = mesh.faces().collect();
        let f = faces[rng.below(faces.len())];
        let v = mesh.face(f);
        let i = rng.below(3);
        let (a, b) = (v[i], v[(i + 1) % 3]);
        let kind = rng.below(7);
        let before = mesh.clone();
        let out = match kind {
            0 if mesh.num_vertices() < 600 => try_split(&mut mesh, ctx, a, b),
            0 | 1 => try_collapse(&mut mesh, ctx, a, b),
            2 => try_swap(&mut mesh, ctx, a, b),
            3 => try_smooth(&mut mesh, ctx, a),
            4 => try_round(&mut mesh, ctx, a),
            5 => try_project(&mut mesh, ctx, a),
            _ => try_reroute(&mut mesh, ctx, a, b),
        };
        let what = format!("seed {seed} step {step} op {kind} on {a:?} {b:?}: {out:?}");
        match out {
            Outcome::Rejected(r) => {
                assert!(mesh == before, "{what}: rejected but changed");
                *tally.rejected.entry(r).or_default() += 1;
            }
            Outcome::Applied(change) => {
                if let Some(m) = change.new_vertex {
                    off.remove(&m);
                }
                if let Some(m) = change.removed_vertex {
                    off.remove(&m);
                }
                assert_invariants(&mesh, ctx, &mut off, &what);
                tally.applied[kind] += 1;
            }
        }
    }
    tally
}

#[test]
fn random_ops_on_delaunay_meshes_keep_every_invariant() {
    let mut total = Tally::default();
    for seed in 0..6 {
        let rule = if seed % 2 == 0 {
            EnergyRule::Ignore
        } else {
            EnergyRule::NoWorseMax
        };
        let (mesh, ctx) = delaunay_mesh(seed, rule);
        let t = run_ops(mesh, &ctx, seed, 400);
        for k in 0..7 {
            total.applied[k] += t.applied[k];
        }
        for (r, n) in t.rejected {
            *total.rejected.entry(r).or_default() += n;
        }
    }
    // Every operation kind got applied, and the feature rules did refuse some.
    assert!(total.applied[..4].iter().all(|&n| n > 10), "{total:?}");
    assert!(
        total.rejected.contains_key(&Reject::FixedVertex),
        "{total:?}"
    );
    assert!(total.rejected.contains_key(&Reject::Inversion), "{total:?}");
}

#[test]
fn random_ops_on_a_conic_chain_keep_every_invariant() {
    // The same runs on an exact conic parent: its vertices stay on the conic (split at
    // the parameter midpoint, smoothing along its jet), its pieces' turns are measured
    // on their hulls.
    let mut total = Tally::default();
    for seed in 0..4 {
        let rule = if seed % 2 == 0 {
            EnergyRule::Ignore
        } else {
            EnergyRule::NoWorseMax
        };
        let (mesh, ctx) = delaunay_mesh_on(seed, rule, Parent::Conic(conic_curve()));
        let t = run_ops(mesh, &ctx, seed, 400);
        for k in 0..7 {
            total.applied[k] += t.applied[k];
        }
    }
    assert!(total.applied[..4].iter().all(|&n| n > 5), "{total:?}");
}

#[test]
fn smoothing_and_splitting_keep_vertices_on_a_conic() {
    let (mut mesh, ctx) = delaunay_mesh_on(1, EnergyRule::Ignore, Parent::Conic(conic_curve()));
    let (key, _, t) = primary_edges(&mesh)[0];
    let Outcome::Applied(change) = try_split(&mut mesh, &ctx, key.lo, key.hi) else {
        panic!("the split of a primary edge applies")
    };
    let m = change.new_vertex.expect("split adds a vertex");
    let c = conic_curve();
    assert_eq!(mesh.position(m), c.eval(0.5 * (t[0] + t[1])));
    assert_eq!(on_curve::off_curve(&mesh, &ctx, m), Some(0.0));
    let (mut mesh, ctx) = delaunay_mesh_on(3, EnergyRule::Ignore, Parent::Conic(conic_curve()));
    let mut moved = 0;
    let verts: Vec<VertexId> = mesh.vertices().collect();
    for v in verts {
        let Role::Primary { .. } = role(&mesh, v, &mesh.vertex_ring(v)) else {
            continue;
        };
        if let Outcome::Applied(_) = try_smooth(&mut mesh, &ctx, v) {
            let Role::Primary { t: t2, .. } = role(&mesh, v, &mesh.vertex_ring(v)) else {
                panic!("still primary")
            };
            assert_eq!(mesh.position(v), c.eval(t2));
            moved += 1;
        }
    }
    assert!(moved > 0);
    assert!(mesh.check().is_empty());
}

#[test]
fn random_ops_on_bsp_meshes_keep_every_invariant() {
    let mut applied_round = 0;
    let mut applied = 0;
    for seed in 0..8 {
        let rule = if seed % 2 == 0 {
            EnergyRule::NoWorseMax
        } else {
            EnergyRule::Ignore
        };
        let (mesh, ctx) = bsp_mesh(seed, rule);
        let t = run_ops(mesh, &ctx, seed, 300);
        applied_round += t.applied[4];
        applied += t.applied.iter().sum::<usize>();
    }
    assert!(applied > 300, "{applied}");
    let _ = applied_round;
}

fn primary_edges(mesh: &TriMesh) -> Vec<(EdgeKey, u32, [f64; 2])> {
    let mut out: Vec<_> = mesh
        .tagged_edges()
        .flat_map(|(k, tags)| {
            tags.iter().filter_map(move |t| match *t {
                FeatureOn::Primary { section, t } => Some((k, section, t)),
                FeatureOn::Secondary { .. } => None,
            })
        })
        .collect();
    out.sort_by_key(|e| e.0);
    out
}

#[test]
fn split_of_a_primary_edge_puts_its_vertex_at_the_curve_midpoint() {
    let (mut mesh, ctx) = delaunay_mesh(1, EnergyRule::Ignore);
    let (key, section, t) = primary_edges(&mesh)[0];
    let out = try_split(&mut mesh, &ctx, key.lo, key.hi);
    let Outcome::Applied(change) = out else {
        panic!("{out:?}")
    };
    let m = change.new_vertex.expect("split adds a vertex");
    let tm = 0.5 * (t[0] + t[1]);
    assert_eq!(
        mesh.position(m),
        ctx.sections[section as usize].parent.eval(tm)
    );
    assert_eq!(
        mesh.edge_tags(key.lo, m),
        &[FeatureOn::Primary {
            section,
            t: [t[0], tm]
        }]
    );
    assert!(mesh.edge_tags(key.lo, key.hi).is_empty());
    assert_eq!(on_curve::off_curve(&mesh, &ctx, m), Some(0.0));
}

#[test]
fn feature_edges_are_never_swapped_and_endpoints_never_collapse() {
    let (mut mesh, ctx) = delaunay_mesh(2, EnergyRule::Ignore);
    let before = mesh.clone();
    for (key, _, _) in primary_edges(&mesh) {
        assert_eq!(
            try_swap(&mut mesh, &ctx, key.lo, key.hi),
            Outcome::Rejected(Reject::FeatureRule)
        );
        for (u, v) in [(key.lo, key.hi), (key.hi, key.lo)] {
            if mesh.vertex_tag(v).section_endpoint {
                assert_eq!(
                    try_collapse(&mut mesh, &ctx, u, v),
                    Outcome::Rejected(Reject::FixedVertex)
                );
            }
        }
    }
    assert_eq!(mesh, before);
    // A primary vertex may not leave its curve through an off-curve edge.
    let v = mesh
        .vertices()
        .find(|&v| matches!(role(&mesh, v, &mesh.vertex_ring(v)), Role::Primary { .. }))
        .expect("an interior curve vertex");
    let r = mesh.vertex_ring(v);
    let off_edge = r
        .neighbours
        .iter()
        .copied()
        .find(|&w| mesh.edge_tags(v, w).is_empty())
        .expect("an untagged edge");
    assert_eq!(
        try_collapse(&mut mesh, &ctx, off_edge, v),
        Outcome::Rejected(Reject::FeatureRule)
    );
    assert_eq!(mesh, before);
}

#[test]
fn smoothing_moves_a_primary_vertex_along_its_curve() {
    let (mut mesh, ctx) = delaunay_mesh(3, EnergyRule::Ignore);
    let mut moved = 0;
    let verts: Vec<VertexId> = mesh.vertices().collect();
    for v in verts {
        let Role::Primary { section, t, .. } = role(&mesh, v, &mesh.vertex_ring(v)) else {
            continue;
        };
        if let Outcome::Applied(_) = try_smooth(&mut mesh, &ctx, v) {
            let Role::Primary { t: t2, .. } = role(&mesh, v, &mesh.vertex_ring(v)) else {
                panic!("still primary")
            };
            assert_ne!(t, t2);
            assert_eq!(
                mesh.position(v),
                ctx.sections[section as usize].parent.eval(t2)
            );
            moved += 1;
        }
    }
    assert!(moved > 0);
    assert!(mesh.check().is_empty());
}

#[test]
fn smoothing_improves_a_bad_free_vertex() {
    let (mut mesh, ctx) = delaunay_mesh(4, EnergyRule::NoWorseMax);
    let v = mesh
        .vertices()
        .find(|&v| role(&mesh, v, &mesh.vertex_ring(v)) == Role::Free)
        .expect("a free vertex");
    let faces = mesh.vertex_ring(v).faces;
    let e0 = max_energy(&mesh, &ctx, &faces);
    let mut applied = 0;
    for _ in 0..3 {
        applied += usize::from(try_smooth(&mut mesh, &ctx, v).is_applied());
    }
    assert!(max_energy(&mesh, &ctx, &faces) <= e0);
    assert!(applied >= 1 || e0 < 1.5, "{e0}");
}

#[test]
fn relaxation_moves_a_free_vertex_to_its_neighbours_mean_within_the_floor() {
    for seed in 0..6 {
        let (mut mesh, mut ctx) = delaunay_mesh(seed, EnergyRule::NoWorseMax);
        let verts: Vec<VertexId> = mesh.vertices().collect();
        let mut moved = 0;
        for v in verts {
            let ring = mesh.vertex_ring(v);
            let free = role(&mesh, v, &ring) == Role::Free;
            let mean = ring
                .neighbours
                .iter()
                .map(|&w| mesh.position(w).to_vec2())
                .fold(kurbo::Vec2::ZERO, |a, b| a + b)
                / ring.neighbours.len() as f64;
            // Without a floor, the ring's worst energy may not grow; with
            // one, up to it.
            for floor in [0.0, 3.0] {
                ctx.energy_floor = floor;
                let e0 = max_energy(&mesh, &ctx, &ring.faces);
                let out = super::smooth::try_smooth_with(&mut mesh, &ctx, v, Objective::Relax);
                if !free {
                    assert!(
                        matches!(out, Outcome::Rejected(Reject::FixedVertex)),
                        "seed {seed}"
                    );
                    continue;
                }
                if out.is_applied() {
                    moved += 1;
                    assert!(mesh.position(v).distance(mean.to_point()) < 1e-12);
                    assert!(max_energy(&mesh, &ctx, &ring.faces) <= e0.max(floor) + 1e-12);
                    break;
                }
            }
        }
        ctx.energy_floor = 0.0;
        assert!(moved > 0, "seed {seed}: no free vertex relaxed");
        assert_invariants(&mesh, &ctx, &mut HashMap::new(), "relaxation");
    }
}

/// Three secondary features, `a b` and `a k b` with `k` at height `h` above
/// `a b`: the BSP mesh holds the sliver `(a, b, k)`, whose three edges are
/// features.
fn sliver_of_three_features(h: f64) -> (TriMesh, Context, [VertexId; 3]) {
    let (pa, pb, pk) = (
        Point::new(0.1, 0.5),
        Point::new(0.9, 0.5),
        Point::new(0.45, 0.5 + h),
    );
    let mut mesh = TriMesh::new();
    let corner = VertexTag {
        box_corner: true,
        ..VertexTag::default()
    };
    let end = VertexTag {
        segment_endpoint: true,
        ..VertexTag::default()
    };
    let [p0, p1, p2, p3] = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
        .map(|(x, y)| mesh.add_vertex(Point::new(x, y), corner));
    let [a, b, k] = [pa, pb, pk].map(|p| mesh.add_vertex(p, end));
    for f in [
        [a, b, k],
        [p0, p1, b],
        [p0, b, a],
        [p0, a, p3],
        [a, k, p3],
        [k, p2, p3],
        [k, b, p2],
        [b, p1, p2],
    ] {
        mesh.add_face(f);
    }
    mesh.link_all();
    // a, b and k are where features meet (each also ends a feature to a box
    // corner), as in the drawings where this sliver shows up.
    let edges = [(a, b), (a, k), (k, b), (a, p0), (b, p1), (k, p2)];
    for (i, (u, v)) in edges.into_iter().enumerate() {
        mesh.add_edge_tag(u, v, FeatureOn::Secondary { polyline: i as u32 });
    }
    assert!(mesh.check().is_empty(), "{:?}", mesh.check());
    let polylines = edges.map(|(u, v)| vec![mesh.position(u), mesh.position(v)]);
    (mesh, straight_context(&polylines), [a, b, k])
}

/// A context without primary sections: these secondary polylines in an
/// envelope of 0.01, α = 10°, the no-worse-max energy rule, linear mode.
fn straight_context(polylines: &[Vec<Point>]) -> Context {
    Context {
        sections: Vec::new(),
        envelope: Envelope::new(polylines, 0.01, 0.01),
        alpha: 10f64.to_radians(),
        on_curve_abs: 1e-12,
        energy: EnergyRule::NoWorseMax,
        energy_floor: 0.0,
        max_new_edge: f64::INFINITY,
        curved: None,
        fixed_boundary: false,
    }
}

#[test]
fn reroute_removes_a_sliver_between_nearly_coincident_secondary_features() {
    let (mut mesh, ctx, [a, b, k]) = sliver_of_three_features(1e-4);
    // None of the plain operations can: the edges are features, the vertices
    // ends of features farther apart than ε.
    let before = mesh.clone();
    assert_eq!(
        try_swap(&mut mesh, &ctx, a, b),
        Outcome::Rejected(Reject::FeatureRule)
    );
    for (u, v) in [(a, k), (k, a), (b, k), (k, b), (a, b), (b, a)] {
        assert!(!try_collapse(&mut mesh, &ctx, u, v).is_applied());
    }
    assert!(mesh == before);
    let out = try_reroute(&mut mesh, &ctx, a, b);
    assert!(out.is_applied(), "{out:?}");
    assert!(mesh.check().is_empty(), "{:?}", mesh.check());
    assert!(mesh.edge_tags(a, b).is_empty());
    let mut off = HashMap::new();
    assert_invariants(&mesh, &ctx, &mut off, "after reroute");
    let sec = |p: u32| FeatureOn::Secondary { polyline: p };
    assert_eq!(mesh.edge_tags(a, k), &[sec(1), sec(0)]);
    assert_eq!(mesh.edge_tags(k, b), &[sec(2), sec(0)]);
    // No face holds all of a, b and k any more.
    assert!(mesh.faces().all(|f| {
        let v = mesh.face(f);
        !(v.contains(&a) && v.contains(&b) && v.contains(&k))
    }));
}

#[test]
fn reroute_refuses_an_apex_beyond_eps_and_unfeatured_edges() {
    let (mut mesh, ctx, [a, b, k]) = sliver_of_three_features(0.05);
    let before = mesh.clone();
    assert_eq!(
        try_reroute(&mut mesh, &ctx, a, b),
        Outcome::Rejected(Reject::FeatureRule)
    );
    // An interior edge without features: a p3 (a's edges in turn: b, k, p3, p0).
    let p3 = mesh
        .vertices()
        .find(|&v| mesh.position(v) == Point::new(0.0, 1.0))
        .expect("corner");
    assert!(mesh.edge_tags(a, p3).is_empty());
    assert_eq!(
        try_reroute(&mut mesh, &ctx, a, p3),
        Outcome::Rejected(Reject::FeatureRule)
    );
    assert!(mesh == before);
    let _ = k;
}

#[test]
fn rational_vertices_of_a_bsp_mesh_round_or_stay_valid() {
    let (mut mesh, ctx) = bsp_mesh(11, EnergyRule::Ignore);
    let mesh_r = {
        let mut input = BspInput::default();
        input.segments.push(BspSegment {
            a: Point::new(0.1, 0.1),
            b: Point::new(0.9, 0.7),
            tag: SegmentTag::Secondary { polyline: 0 },
        });
        input.segments.push(BspSegment {
            a: Point::new(0.1, 0.8),
            b: Point::new(0.8, 0.05),
            tag: SegmentTag::Secondary { polyline: 1 },
        });
        let opts = BspOptions::DEFAULT.with_round(false);
        bsp::build(&input, Rect::new(0.0, 0.0, 1.0, 1.0), &opts)
            .expect("bsp")
            .0
    };
    let ctx_r = Context {
        envelope: Envelope::new(
            &[
                vec![Point::new(0.1, 0.1), Point::new(0.9, 0.7)],
                vec![Point::new(0.1, 0.8), Point::new(0.8, 0.05)],
            ],
            0.01,
            0.01,
        ),
        ..ctx.clone()
    };
    let mut mesh_r = mesh_r;
    let rational: Vec<VertexId> = mesh_r
        .vertices()
        .filter(|&v| mesh_r.is_rational(v))
        .collect();
    assert!(!rational.is_empty());
    for v in rational {
        let out = try_round(&mut mesh_r, &ctx_r, v);
        assert!(out.is_applied(), "{out:?}");
        assert!(!mesh_r.is_rational(v));
    }
    assert!(mesh_r.check().is_empty());
    let v = mesh.vertices().next().expect("a vertex");
    if !mesh.is_rational(v) {
        assert_eq!(
            try_round(&mut mesh, &ctx, v),
            Outcome::Rejected(Reject::NoChange)
        );
    }
}

#[test]
fn smoothing_snaps_a_chord_vertex_onto_its_curve_and_never_away() {
    let (mut mesh, ctx) = delaunay_mesh(5, EnergyRule::Ignore);
    let v = mesh
        .vertices()
        .find(|&v| matches!(role(&mesh, v, &mesh.vertex_ring(v)), Role::Primary { .. }))
        .expect("an interior curve vertex");
    let Role::Primary { along, .. } = role(&mesh, v, &mesh.vertex_ring(v)) else {
        unreachable!()
    };
    // Put v on the chord of its neighbours, as the BSP leaves such vertices.
    let chord = mesh
        .position(along[0].0)
        .midpoint(mesh.position(along[1].0));
    let p = mesh.position(v).lerp(chord, 0.5);
    mesh.set_position(v, p);
    assert!(mesh.check().is_empty());
    let off0 = on_curve::off_curve(&mesh, &ctx, v).expect("primary");
    assert!(off0 > 1e-4, "{off0}");
    let out = try_smooth(&mut mesh, &ctx, v);
    assert!(out.is_applied(), "{out:?}");
    assert!(on_curve::off_curve(&mesh, &ctx, v).expect("primary") <= ctx.on_curve_abs);
}

#[test]
fn curvature_refuses_pieces_that_turn_too_much_or_leave_the_section() {
    let (_, mut ctx) = delaunay_mesh(0, EnergyRule::Ignore);
    assert!(curvature::holds(&ctx, 0, [0.1, 0.4]));
    assert!(curvature::holds(&ctx, 1, [1.0, 0.5]));
    assert!(!curvature::holds(&ctx, 0, [0.2, 0.7]), "leaves section 0");
    assert!(!curvature::holds(&ctx, 7, [0.1, 0.2]), "unknown section");
    assert!(!curvature::holds(&ctx, 0, [0.3, 0.3]), "empty piece");
    ctx.sections[0].t = [0.0, 1.0];
    // The whole cubic turns about 27°, more than α = 15°.
    assert!(!curvature::holds(&ctx, 0, [0.0, 1.0]));
    assert!(curvature::holds(&ctx, 0, [0.0, 0.5]));
}

#[test]
fn curvature_sums_the_turn_of_a_piece_across_an_inflection() {
    // A symmetric S (inflection at 1/2): its end tangents are parallel, but each
    // half bends by about 10°. A chain may run across the inflection, so an
    // edge's piece can: it turns about 20°, more than α = 15°, not 0.
    let (_, mut ctx) = delaunay_mesh(0, EnergyRule::Ignore);
    let s = CubicBez::new((0.0, 0.0), (1.0, 0.12), (2.0, -0.12), (3.0, 0.0));
    ctx.sections[0].parent = Parent::Cubic(s);
    ctx.sections[0].t = [0.0, 1.0];
    assert_eq!(curvature::turn(&s), 0.0);
    assert!(!curvature::holds(&ctx, 0, [0.0, 1.0]));
    assert!(!curvature::holds(&ctx, 0, [0.98, 0.02]));
    assert!(curvature::holds(&ctx, 0, [0.0, 0.5]));
    assert!(curvature::holds(&ctx, 0, [0.4, 0.6]));
    // Across a cusp the tangent turns back: refused however short the piece.
    let cusp = CubicBez::new((0.0, 0.0), (2.0, 1.0), (0.0, 1.0), (2.0, 0.0));
    ctx.sections[0].parent = Parent::Cubic(cusp);
    assert!(!curvature::holds(&ctx, 0, [0.49, 0.51]));
}

#[test]
fn projection_moves_a_chord_vertex_onto_its_curve_or_closer() {
    for seed in 0..6 {
        let (mut mesh, ctx) = delaunay_mesh(seed, EnergyRule::NoWorseMax);
        let Some(v) = mesh
            .vertices()
            .find(|&v| matches!(role(&mesh, v, &mesh.vertex_ring(v)), Role::Primary { .. }))
        else {
            continue;
        };
        let Role::Primary { along, .. } = role(&mesh, v, &mesh.vertex_ring(v)) else {
            unreachable!()
        };
        let chord = mesh
            .position(along[0].0)
            .midpoint(mesh.position(along[1].0));
        mesh.set_position(v, mesh.position(v).lerp(chord, 0.9));
        if !mesh.check().is_empty() {
            continue;
        }
        let off0 = on_curve::off_curve(&mesh, &ctx, v).expect("primary");
        let before = mesh.clone();
        match try_project(&mut mesh, &ctx, v) {
            Outcome::Applied(_) => {
                let off1 = on_curve::off_curve(&mesh, &ctx, v).expect("primary");
                assert!(off1 < off0, "seed {seed}: {off1} >= {off0}");
                assert!(mesh.check().is_empty());
                // Again until on the curve or stuck: never farther.
                for _ in 0..8 {
                    if !try_project(&mut mesh, &ctx, v).is_applied() {
                        break;
                    }
                }
                let off2 = on_curve::off_curve(&mesh, &ctx, v).expect("primary");
                assert!(off2 <= off1);
            }
            Outcome::Rejected(r) => {
                assert!(mesh == before, "seed {seed}: {r:?} changed the mesh");
                assert_ne!(r, Reject::NoChange, "seed {seed}: {off0} off is a change");
            }
        }
        // A vertex on its curve is left alone.
        let on = mesh.vertices().find(|&w| {
            w != v
                && matches!(role(&mesh, w, &mesh.vertex_ring(w)), Role::Primary { .. })
                && on_curve::off_curve(&mesh, &ctx, w).is_some_and(|d| d <= ctx.on_curve_abs)
        });
        if let Some(w) = on {
            assert_eq!(
                try_project(&mut mesh, &ctx, w),
                Outcome::Rejected(Reject::NoChange)
            );
        }
    }
}

#[test]
fn boundary_vertices_slide_along_the_box_side_and_stay_on_it() {
    let mut moved = 0;
    for seed in 0..4 {
        let (mut mesh, ctx) = delaunay_mesh(seed, EnergyRule::NoWorseMax);
        // Put vertices on the box sides: split every boundary edge, twice.
        for _ in 0..2 {
            let sides: Vec<(VertexId, VertexId)> = mesh
                .faces()
                .flat_map(|f| {
                    let v = mesh.face(f);
                    let adj = mesh.neighbours(f);
                    (0..3)
                        .filter(move |&i| adj[i].is_none())
                        .map(move |i| (v[(i + 1) % 3], v[(i + 2) % 3]))
                })
                .collect();
            for (a, b) in sides {
                try_split(&mut mesh, &ctx, a, b);
            }
        }
        let boundary: Vec<VertexId> = mesh
            .vertices()
            .filter(|&v| role(&mesh, v, &mesh.vertex_ring(v)) == Role::Boundary)
            .collect();
        for v in boundary {
            let p = mesh.position(v);
            let before = mesh.clone();
            match try_smooth(&mut mesh, &ctx, v) {
                Outcome::Applied(_) => {
                    let q = mesh.position(v);
                    // Still exactly on the same side of the unit box.
                    assert!(
                        (q.x == p.x && (p.x == 0.0 || p.x == 1.0))
                            || (q.y == p.y && (p.y == 0.0 || p.y == 1.0)),
                        "seed {seed}: {p:?} -> {q:?}"
                    );
                    assert!((0.0..=1.0).contains(&q.x) && (0.0..=1.0).contains(&q.y));
                    assert!(mesh.check().is_empty());
                    moved += 1;
                }
                Outcome::Rejected(_) => assert!(mesh == before),
            }
        }
    }
    assert!(moved > 0, "no boundary vertex ever slid");
}

#[test]
fn curved_mode_relaxes_the_turn_bound_only() {
    let (_, ctx) = delaunay_mesh(1, EnergyRule::NoWorseMax);
    // A quarter turn.
    let ctx = Context {
        sections: vec![CurveSection {
            parent: Parent::Cubic(CubicBez::new(
                Point::new(0.0, 0.0),
                Point::new(0.5, 0.0),
                Point::new(1.0, 0.5),
                Point::new(1.0, 1.0),
            )),
            t: [0.0, 1.0],
            source: None,
            shared: None,
        }],
        ..ctx
    };
    assert!(ctx.curved.is_none());
    assert_eq!(ctx.turn_bound(), ctx.alpha);
    let curved = ctx.with_curved(CurvedRule::new(crate::element::Order::Cubic));
    assert_eq!(curved.turn_bound(), std::f64::consts::FRAC_PI_2);
    // A piece turning 40° fails α = 15° and passes in curved mode; the whole
    // quarter turn (90°, not less) fails both.
    assert!(!curvature::holds(&ctx, 0, [0.0, 0.5]));
    assert!(curvature::holds(&curved, 0, [0.0, 0.5]));
    assert!(!curvature::holds(&curved, 0, [0.0, 1.0]));
}

/// A bounded split (the curving stage's repair split) refuses to leave a
/// triangle worse than its bound, leaving the mesh as it was; unbounded, the
/// same split is applied. `k` lies almost on the line through `a b`, so the
/// half `m b k` is a needle worse than the triangle `a b k` it comes from.
#[test]
fn a_bounded_split_refuses_to_make_a_needle() {
    let mut mesh = TriMesh::new();
    let [a, b, k, c] = [(0.0, 0.0), (1.0, 0.0), (3.0, 0.1), (0.5, -1.0)]
        .map(|(x, y)| mesh.add_vertex(Point::new(x, y), VertexTag::default()));
    let upper = mesh.add_face([a, b, k]);
    let lower = mesh.add_face([b, a, c]);
    mesh.link_all();
    assert!(mesh.check().is_empty(), "{:?}", mesh.check());
    let ctx = straight_context(&[]);
    let before = mesh.clone();
    let old = max_energy(&mesh, &ctx, &[upper, lower]);
    assert_eq!(
        try_split_bounded(&mut mesh, &ctx, a, b, Some(old)),
        Outcome::Rejected(Reject::Energy)
    );
    assert!(mesh == before, "a refused split changed the mesh");
    let Outcome::Applied(change) = try_split_bounded(&mut mesh, &ctx, a, b, Some(4.0 * old)) else {
        panic!("a split within four times the old energy is refused");
    };
    assert!(max_energy(&mesh, &ctx, &change.created) > old);
    assert!(max_energy(&mesh, &ctx, &change.created) <= 4.0 * old);
    assert!(mesh.check().is_empty(), "{:?}", mesh.check());
}

/// The verdicts decided on the mesh as it is (`CollapsePlan::verdict`,
/// `SmoothPlan::verdict`, `SwapPlan::verdict`, `ReroutePlan::verdict`, which the
/// schedule computes ahead in parallel) are the outcomes of the tentative
/// change and its invariants: the same refusal, or applied. Random plans on
/// random meshes, the meshes moving on between them; the last three meshes
/// are in curved mode (cubic), where only the collapse is decided ahead.
#[test]
fn verdicts_decided_ahead_match_the_tentative_changes() {
    let cubic = CurvedRule::new(crate::element::Order::Cubic);
    let mut meshes: Vec<(TriMesh, Context)> = (0..3)
        .map(|seed| delaunay_mesh(seed, EnergyRule::NoWorseMax))
        .chain((0..10).map(|seed| bsp_mesh(seed, EnergyRule::NoWorseMax)))
        .chain((0..3).map(|seed| {
            let (mesh, ctx) = delaunay_mesh(seed + 10, EnergyRule::NoWorseMax);
            (mesh, ctx.with_curved(cubic))
        }))
        .collect();
    // (decided, of which refused) by operation, linear mode.
    let mut seen = [(0usize, 0usize); 4];
    // Curved collapses decided ahead: applied, and refused by reason.
    let mut curved_applied = 0usize;
    let mut curved_refused: HashMap<Reject, usize> = HashMap::new();
    for (i, (mesh, ctx)) in meshes.iter_mut().enumerate() {
        let mut rng = Rng(100 + i as u64);
        for step in 0..1500 {
            let verts: Vec<VertexId> = mesh.vertices().collect();
            let v = verts[rng.below(verts.len())];
            let ring = mesh.vertex_ring(v);
            let Some(&u) = ring.neighbours.get(rng.below(ring.neighbours.len().max(1))) else {
                continue;
            };
            // Curved mode: some collapses run along a feature edge (v's tags
            // move to u).
            let (u, v) = match mesh.edges().find(|k| {
                ctx.curved.is_some()
                    && step % 8 == 0
                    && !mesh.edge_tags(k.lo, k.hi).is_empty()
                    && rng.below(8) == 0
            }) {
                Some(k) if rng.below(2) == 0 => (k.lo, k.hi),
                Some(k) => (k.hi, k.lo),
                None => (u, v),
            };
            let what = format!("mesh {i} step {step}");
            // The tentative path on `mesh`; the decided one (the plan and its
            // verdict handed over) on a copy: the same outcome, the same mesh.
            let mut decided = mesh.clone();
            let (verdict, outcome, by_verdict, op) = match step % 4 {
                0 => {
                    let Ok(plan) = CollapsePlan::new(mesh, ctx, u, v, None) else {
                        continue;
                    };
                    let verdict = plan.verdict(mesh, ctx);
                    let d = try_collapse_planned(&mut decided, ctx, Ok(plan), verdict).0;
                    (verdict, try_collapse(mesh, ctx, u, v), d, 0)
                }
                1 => {
                    let Ok(plan) = SmoothPlan::with_objective(mesh, ctx, v, Objective::Sum) else {
                        continue;
                    };
                    let verdict = plan.verdict(mesh, ctx);
                    let d = try_smooth_planned(&mut decided, ctx, Ok(plan), verdict);
                    (verdict, try_smooth(mesh, ctx, v), d, 1)
                }
                2 => {
                    let Ok(plan) = SwapPlan::new(mesh, ctx, u, v) else {
                        continue;
                    };
                    let verdict = plan.verdict(mesh, ctx, &[]);
                    let d = try_swap_planned(&mut decided, ctx, Ok(plan), verdict);
                    (verdict, try_swap(mesh, ctx, u, v), d, 2)
                }
                _ => {
                    let Ok(plan) = ReroutePlan::new(mesh, ctx, u, v) else {
                        continue;
                    };
                    let verdict = plan.verdict(mesh, ctx);
                    let d = try_reroute_planned(&mut decided, ctx, Ok(plan), verdict);
                    (verdict, try_reroute(mesh, ctx, u, v), d, 3)
                }
            };
            assert!(
                *mesh == decided,
                "{what}, op {op}: the decided path made another mesh"
            );
            assert_eq!(outcome, by_verdict, "{what}, op {op}");
            let Some(verdict) = verdict else {
                assert!(
                    op > 0 || ctx.curved.is_none(),
                    "{what}: a collapse undecided"
                );
                continue;
            };
            match (&verdict, &outcome) {
                (Ok(()), Outcome::Applied(_)) => {}
                (Err(r), Outcome::Rejected(s)) if r == s => {}
                _ => panic!("{what}, op {op}: verdict {verdict:?}, outcome {outcome:?}"),
            }
            if ctx.curved.is_some() {
                match verdict {
                    Ok(()) => curved_applied += 1,
                    Err(r) => *curved_refused.entry(r).or_default() += 1,
                }
                continue;
            }
            seen[op].0 += 1;
            seen[op].1 += usize::from(verdict.is_err());
        }
    }
    // Curved collapses were decided both ways, and refused by the curved
    // elements' rules too, not only by the inversion test.
    assert!(
        curved_applied >= 5,
        "{curved_applied} applied, {curved_refused:?}"
    );
    let by_elements = [Reject::Energy, Reject::Jacobian]
        .iter()
        .map(|r| curved_refused.get(r).copied().unwrap_or(0))
        .sum::<usize>();
    assert!(by_elements >= 5, "{curved_refused:?}");
    // Every kind was decided ahead, both ways (else the check is vacuous);
    // reroutes are rare on these meshes.
    for (op, &(decided, refused)) in seen.iter().enumerate() {
        assert!(decided >= 5, "op {op}: {decided} decided ({seen:?})");
        if op < 3 {
            assert!(refused >= 1 && refused < decided, "op {op}: {seen:?}");
        }
    }
}

#[test]
fn every_reason_is_listed_once_at_its_own_index() {
    let mut names = std::collections::BTreeSet::new();
    for (i, r) in Reject::ALL.iter().enumerate() {
        assert_eq!(*r as usize, i, "{r:?}");
        assert!(names.insert(r.name()), "{r:?}: name used twice");
    }
    assert_eq!(names.len(), Reject::COUNT);
}
