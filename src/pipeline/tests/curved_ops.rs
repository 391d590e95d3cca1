//! Tests that need the whole front of the pipeline (load, features, BSP,
//! optimization) to build realistic meshes for lower-level code: the local
//! operations in curved mode. They live here, at the top of the module graph,
//! so `ops` itself imports nothing above it.

use crate::element::Order;
use crate::mesh::{FaceId, FeatureOn, TriMesh, VertexId};
use crate::ops::invariants::{self, curvature};
use crate::ops::tests::Rng;
use crate::ops::{
    Context, CurvedRule, EnergyRule, Outcome, Reject, try_collapse, try_smooth, try_swap,
};
use std::collections::HashMap;

/// The optimized linear mesh of a small drawing with curves (a disk, and a
/// rounded shape of cubics and lines), with its context in curved mode.
fn curved_mode_mesh(drawing: &crate::Drawing, order: Order) -> (TriMesh, Context) {
    let params = crate::Params::DEFAULT.with_l(crate::Length::Rel(0.15));
    let (mut mesh, _, mut ctx) = super::bsp_mesh(drawing, &params).expect("bsp");
    crate::optimize::optimize(
        &mut mesh,
        &mut ctx,
        &super::optimize_options(drawing, &params),
    );
    (mesh, ctx.with_curved(CurvedRule::new(order)))
}

/// Faces that are not certified curved elements (checked with the default,
/// tighter certification, independent of the rule's options).
fn uncertified_faces(mesh: &TriMesh, ctx: &Context, order: Order) -> Vec<[VertexId; 3]> {
    let mut bad: Vec<[VertexId; 3]> = mesh
        .faces()
        .map(|f| mesh.face(f))
        .filter(|&t| {
            !invariants::curved::exact_nodes(mesh, ctx, order, t).is_some_and(|n| {
                crate::element::jacobian::certify_element(
                    order,
                    &n,
                    &crate::element::CertifyOptions::DEFAULT,
                )
                .is_some_and(|c| c.is_certified())
            })
        })
        .collect();
    bad.sort_unstable();
    bad
}

#[test]
fn random_ops_in_curved_mode_keep_every_element_certified() {
    run_curved_ops(&[]);
}

/// The same runs on an exact disk of four conics (a hand-built drawing).
#[test]
fn random_ops_in_curved_mode_on_exact_conics_keep_every_element_certified() {
    let drawing = super::conics::drawing_of(vec![crate::svg::Shape {
        svg_id: Some("disk".into()),
        element_index: 0,
        paint_order: 0,
        filled: true,
        stroked: false,
        fill_rule: crate::svg::FillRule::NonZero,
        fill_colour: None,
        paint: Default::default(),
        subpaths: vec![super::conics::disk_subpath()],
    }]);
    run_curved_ops(&[
        (drawing.clone(), Order::Cubic, EnergyRule::NoWorseMax),
        (drawing.clone(), Order::Cubic, EnergyRule::Ignore),
        (drawing, Order::Quadratic, EnergyRule::Ignore),
    ]);
}

/// The SVG cases of [`run_curved_ops`]: a disk and a rounded shape of cubics
/// and lines, cubic under either energy rule, and the shape quadratic.
fn svg_cases() -> [(crate::Drawing, Order, EnergyRule); 5] {
    let disk = br#"<svg xmlns="http://www.w3.org/2000/svg" width="100" height="100">
        <circle cx="50" cy="50" r="40" fill="black"/></svg>"#;
    let blob = br#"<svg xmlns="http://www.w3.org/2000/svg" width="120" height="80">
        <path d="M 10 70 L 10 30 C 10 0 60 0 60 30 C 60 50 110 20 110 70 Z" fill="red"/>
        <path d="M 30 60 L 90 60" stroke="black" fill="none"/></svg>"#;
    let load = |svg: &[u8]| {
        crate::svg::load_bytes(svg, &crate::svg::LoadOptions::DEFAULT).expect("drawing loads")
    };
    [
        (load(&disk[..]), Order::Cubic, EnergyRule::NoWorseMax),
        (load(&disk[..]), Order::Cubic, EnergyRule::Ignore),
        (load(&blob[..]), Order::Cubic, EnergyRule::NoWorseMax),
        (load(&blob[..]), Order::Cubic, EnergyRule::Ignore),
        (load(&blob[..]), Order::Quadratic, EnergyRule::Ignore),
    ]
}

/// Random collapses, swaps and smoothings in curved mode on the drawings of
/// `cases` (the SVG cases below when empty), each checked.
fn run_curved_ops(cases: &[(crate::Drawing, Order, EnergyRule)]) {
    let mut applied = [0usize; 4];
    let mut rejected: HashMap<Reject, usize> = HashMap::new();
    let svg_cases = svg_cases();
    let cases = if cases.is_empty() {
        &svg_cases[..]
    } else {
        cases
    };
    for (seed, (drawing, order, energy)) in cases.iter().enumerate() {
        let (order, energy) = (*order, *energy);
        let (mesh, ctx) = curved_mode_mesh(drawing, order);
        let (mut mesh, ctx) = (mesh, Context { energy, ..ctx });
        let start = uncertified_faces(&mesh, &ctx, order);
        let mut rng = Rng(seed as u64 ^ 0x5eed);
        for step in 0..300 {
            let faces: Vec<FaceId> = mesh.faces().collect();
            let f = faces[rng.below(faces.len())];
            let v = mesh.face(f);
            let i = rng.below(3);
            let (a, b) = (v[i], v[(i + 1) % 3]);
            let kind = rng.below(4);
            let before = mesh.clone();
            let out = match kind {
                0 | 1 => try_collapse(&mut mesh, &ctx, a, b),
                2 => try_swap(&mut mesh, &ctx, a, b),
                _ => try_smooth(&mut mesh, &ctx, a),
            };
            let what = format!("seed {seed} step {step} op {kind} on {a:?} {b:?}: {out:?}");
            match out {
                Outcome::Rejected(r) => {
                    assert!(mesh == before, "{what}: rejected but changed");
                    *rejected.entry(r).or_default() += 1;
                }
                Outcome::Applied(_) => {
                    applied[kind] += 1;
                    // The corner rule: the worst corner energy never exceeds
                    // the larger of its value before and the floor.
                    if energy == EnergyRule::NoWorseMax {
                        let floor = ctx.curved.expect("curved mode").corner_floor;
                        let old = crate::ops::max_corner_energy(&before, before.faces());
                        let new = crate::ops::max_corner_energy(&mesh, mesh.faces());
                        assert!(
                            new <= old.max(floor),
                            "{what}: corner energy {old} -> {new}"
                        );
                    }
                    assert!(mesh.check().is_empty(), "{what}: {:?}", mesh.check());
                    // No face became uncertified (those uncertified at the start
                    // may only disappear).
                    let bad = uncertified_faces(&mesh, &ctx, order);
                    assert!(
                        bad.iter().all(|t| start.contains(t)),
                        "{what}: {bad:?} (start {start:?})"
                    );
                    for (key, tags) in mesh.tagged_edges() {
                        for t in tags {
                            if let FeatureOn::Primary { section, t } = *t {
                                assert!(curvature::holds(&ctx, section, t), "{what}: {key:?}");
                            }
                        }
                    }
                }
            }
        }
    }
    // Collapses, swaps and smoothing did happen, and the curved rule refused some.
    assert!(applied.iter().all(|&n| n > 5), "{applied:?} {rejected:?}");
    assert!(rejected.contains_key(&Reject::Jacobian), "{rejected:?}");
}
