//! The size field as the stages read it.

use super::*;
use crate::features::FeatureSet;
use crate::params::{Length, Params};

/// The size field of `drawing` with the default parameters and no regions.
fn default_field(drawing: &Drawing, r: &Resolved) -> SizeField {
    field_of(drawing, r, &Params::DEFAULT.size)
}

/// The size field of `drawing` with the sizes `spec` and no regions.
fn field_of(drawing: &Drawing, r: &Resolved, spec: &SizeSpec) -> SizeField {
    let names = vec![None; drawing.shapes.len()];
    SizeField::build(&FieldInput {
        drawing,
        resolved: r,
        spec,
        region_names: &names,
        bounds: Rect::new(-200.0, -200.0, 200.0, 200.0),
        deadline: Deadline::NONE,
        max_vertices: Params::DEFAULT.max_vertices as usize,
    })
    .expect("the field builds")
}

/// A thin stroke's size goes to its own outline only: the edge of
/// another shape running 0.75 from the stroke is resampled at the size it had
/// without the stroke (`l`), not at the field there (the stroke's size grown
/// by 0.75), while the stroke's own outline is cut at its own size. The
/// optimizer still reads the whole field.
#[test]
fn a_stroke_sizes_its_own_outline_not_the_curves_along_it() {
    let svg = br##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
        <rect x="10" y="40" width="80" height="20" fill="#58a"/>
        <path d="M 10 39.1 H 90" stroke="#000" stroke-width="0.3" fill="none"/></svg>"##;
    let drawing = crate::svg::load_bytes(svg, &crate::svg::LoadOptions::DEFAULT).expect("loads");
    let r = Params::DEFAULT.resolve(drawing.diagonal());
    let field = default_field(&drawing, &r);
    assert_eq!(field.report().fields, ["strokes"]);
    let stroke = ShapeId::from_index(
        drawing
            .shapes
            .iter()
            .position(|s| s.paint.stroke_width.is_some_and(|w| (w - 0.3).abs() < 1e-6))
            .expect("the stroke is meshed as an area"),
    );
    let rect = ShapeId::from_index(
        drawing
            .shapes
            .iter()
            .position(|s| s.filled && s.paint.stroke_width.is_none())
            .expect("the rect"),
    );
    let width = drawing.shapes[stroke.index()].paint.stroke_width;
    let h_stroke = sources::STROKE_SIZE_PER_WIDTH * width.expect("a stroke");
    assert!(
        h_stroke + 0.75 < 0.75 * r.l,
        "the test needs the stroke's size well below l"
    );

    let fs = FeatureSet::build_sized(
        &drawing,
        &r,
        &Deadline::NONE,
        &|p, s, cut| field.for_curve(p, s.shape, cut),
        usize::MAX,
    );
    // Every section, primary or secondary, as (shape, chord).
    let mut chords: Vec<(ShapeId, Point, Point)> = fs
        .primary
        .iter()
        .map(|s| (s.source.shape, s.ctrl.p0, s.ctrl.p3))
        .collect();
    for q in &fs.secondary {
        for w in q.points.windows(2) {
            chords.push((q.source.shape, w[0], w[1]));
        }
    }
    let of = |shape: ShapeId| chords.iter().filter(move |c| c.0 == shape);
    // The stroke's own outline: cut at its size.
    assert!(of(stroke).count() as f64 >= 2.0 * 80.0 / h_stroke);
    for &(_, a, b) in of(stroke) {
        assert!(a.distance(b) <= h_stroke * (1.0 + 1e-9), "{a:?} {b:?}");
        assert_eq!(
            field.for_curve(a.midpoint(b), stroke, CutFor::Any),
            h_stroke
        );
    }
    // The rect's edge along the stroke (its chords 0.75 to 1.25 from the
    // stroke's outline): cut at l, far above the field there.
    let stroke_y: f64 = of(stroke).map(|c| c.1.y).sum::<f64>() / of(stroke).count() as f64;
    let along: Vec<_> = of(rect)
        .filter(|c| c.1.y == c.2.y && (c.1.y - stroke_y).abs() < 2.0)
        .collect();
    assert_eq!(along.len(), (80.0 / r.l).ceil() as usize, "{along:?}");
    for &&(_, a, b) in &along {
        let mid = a.midpoint(b);
        assert_eq!(field.for_curve(mid, rect, CutFor::Any), r.l);
        assert!(
            field.at(mid) < 0.75 * a.distance(b),
            "the field there is the stroke's: {} vs {}",
            field.at(mid),
            a.distance(b)
        );
    }
}

/// Without a thin stroke the features read the field itself.
#[test]
fn without_strokes_the_curves_read_the_field() {
    let svg = br##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
        <rect x="10" y="40" width="80" height="20" fill="#58a"/>
        <path d="M 10 38.5 H 90" stroke="#000" stroke-width="0.01" fill="none"/></svg>"##;
    let drawing = crate::svg::load_bytes(svg, &crate::svg::LoadOptions::DEFAULT).expect("loads");
    let r = Params::DEFAULT.resolve(drawing.diagonal());
    let field = default_field(&drawing, &r);
    assert!(field.is_uniform());
    assert!(matches!(field.curves, CurveField::Full));
    for s in 0..drawing.shapes.len() {
        assert_eq!(
            field.for_curve(Point::new(50.0, 40.0), ShapeId::from_index(s), CutFor::Any),
            r.l
        );
    }
}

/// With the user's sizes beside a thin stroke, the other curves read the
/// user's field (built without the stroke) and the stroke's outline the
/// smaller of that and its own size.
#[test]
fn beside_a_stroke_the_curves_read_the_users_field() {
    let svg = br##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
        <rect x="10" y="40" width="80" height="20" fill="#58a"/>
        <path d="M 10 38.5 H 90" stroke="#000" stroke-width="0.25" fill="none"/></svg>"##;
    let drawing = crate::svg::load_bytes(svg, &crate::svg::LoadOptions::DEFAULT).expect("loads");
    let r = Params::DEFAULT.resolve(drawing.diagonal());
    // A box of size 3 over everything, a box of size 1.5 far from the stroke.
    let spec = SizeSpec::default()
        .with_box([-150.0, -150.0, 150.0, 150.0], Length::Abs(3.0))
        .with_box([140.0, 140.0, 150.0, 150.0], Length::Abs(1.5));
    let field = field_of(&drawing, &r, &spec);
    assert!(matches!(field.curves, CurveField::WithoutStrokes(_)));
    let stroke = drawing
        .shapes
        .iter()
        .position(|s| s.paint.stroke_width.is_some())
        .expect("the stroke");
    let rect = drawing
        .shapes
        .iter()
        .position(|s| s.filled)
        .expect("the rect");
    for sh in &drawing.shapes {
        for sp in &sh.subpaths {
            let p = sp.start;
            let (at, other) = (
                field.at(p),
                field.for_curve(p, ShapeId::from_index(rect), CutFor::Any),
            );
            assert!(
                at <= 3.0 && (other - 3.0).abs() < 1e-9,
                "{p:?}: {at} {other}"
            );
            assert_eq!(
                field.for_curve(p, ShapeId::from_index(stroke), CutFor::Any),
                sources::STROKE_SIZE_PER_WIDTH * 0.25
            );
        }
    }
    assert!(
        field.for_curve(
            Point::new(145.0, 145.0),
            ShapeId::from_index(rect),
            CutFor::Any
        ) <= 1.5 + 1e-9
    );
}

/// A thin stroke drawn on another shape's edge, narrower than 2 mu: its
/// outline is within mu of that edge, so it is secondary, and its runs are cut
/// again at the size without the stroke (the optimizer refines them as the
/// field asks).
#[test]
fn a_stroke_that_is_not_kept_apart_is_cut_at_the_size_without_it() {
    let svg = br##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">
        <rect x="10" y="40" width="80" height="20" fill="#58a"/>
        <path d="M 10 40 H 90" stroke="#000" stroke-width="0.1" fill="none"/></svg>"##;
    let drawing = crate::svg::load_bytes(svg, &crate::svg::LoadOptions::DEFAULT).expect("loads");
    let r = Params::DEFAULT.resolve(drawing.diagonal());
    assert!(
        0.1 >= r.mu && 0.05 < r.mu,
        "the test needs mu <= w < 2 mu: {}",
        r.mu
    );
    let field = default_field(&drawing, &r);
    assert_eq!(field.report().fields, ["strokes"]);
    let stroke = ShapeId::from_index(
        drawing
            .shapes
            .iter()
            .position(|s| s.paint.stroke_width.is_some())
            .expect("the stroke is meshed as an area"),
    );
    let fs = FeatureSet::build_sized(
        &drawing,
        &r,
        &Deadline::NONE,
        &|p, s, cut| field.for_curve(p, s.shape, cut),
        usize::MAX,
    );
    assert!(fs.primary.iter().all(|s| s.source.shape != stroke));
    let longest = fs
        .secondary
        .iter()
        .filter(|q| q.source.shape == stroke)
        .flat_map(|q| q.points.windows(2).map(|w| w[0].distance(w[1])))
        .fold(0.0, f64::max);
    assert!(longest > 0.5 * r.l, "{longest} vs l = {}", r.l);
    // Cut for any section, the stroke's own size.
    let on = drawing.shapes[stroke.index()].subpaths[0].start;
    let width = drawing.shapes[stroke.index()].paint.stroke_width;
    assert_eq!(
        Some(field.for_curve(on, stroke, CutFor::Any)),
        width.map(|w| sources::STROKE_SIZE_PER_WIDTH * w)
    );
    assert_eq!(field.for_curve(on, stroke, CutFor::Secondary), r.l);
}

/// The BSP's seeds from the field ([`SizeField::seed_points`]): where a
/// formula asks for sizes from 0.5 (x = -200) up to `l` (15.1), every seed lies
/// at a leaf centre where the field is below half of `l`, inside the box by
/// half its size, at least half its size from every feature segment and
/// point; the default field (thin strokes only), a uniform field and a
/// budget smaller than the seeds give none.
#[test]
fn seeds_follow_the_field_where_it_is_fine_and_keep_off_the_features() {
    let svg = br##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="-200 -200 400 400">
        <rect x="-150" y="-20" width="300" height="40" fill="#58a"/></svg>"##;
    let drawing = crate::svg::load_bytes(svg, &crate::svg::LoadOptions::DEFAULT).expect("loads");
    let r = Params::DEFAULT.resolve(drawing.diagonal());
    let spec = SizeSpec::DEFAULT.with_expr("0.5 + 0.1*(x + 200)");
    let field = field_of(&drawing, &r, &spec);
    let bounds = Rect::new(-200.0, -200.0, 200.0, 200.0);
    let segments = [
        kurbo::Line::new((-150.0, -20.0), (150.0, -20.0)),
        kurbo::Line::new((-150.0, 20.0), (150.0, 20.0)),
        kurbo::Line::new((-150.0, -20.0), (-150.0, 20.0)),
    ];
    let points = [Point::new(-180.0, 100.0)];
    let seeds = field.seed_points(bounds, &segments, &points, 1_000_000);
    let half_l = seeds::SEED_BELOW * r.l;
    assert!(seeds.len() > 100, "{} seeds", seeds.len());
    for &p in &seeds {
        let h = field.at(p);
        // (the leaf's smallest corner is below half of l; its centre may be a
        // little above, by the grading across half a leaf)
        assert!(h < 1.5 * half_l, "{p:?}: h {h} vs l {}", r.l);
        let m = 0.25 * h;
        assert!(
            p.x - bounds.x0 > m
                && bounds.x1 - p.x > m
                && p.y - bounds.y0 > m
                && bounds.y1 - p.y > m,
            "{p:?} near the box"
        );
        for s in &segments {
            let d = crate::mesh::point_segment_distance(p, *s);
            assert!(d > 0.25 * h, "{p:?} at {d} from {s:?}, h {h}");
        }
        assert!(p.distance(points[0]) > 0.25 * h, "{p:?} at the point");
    }
    // Where the field is above half of l (x > -129), no seed (but for a
    // leaf straddling that line).
    assert!((r.l - 15.13).abs() < 0.01, "l = {}", r.l);
    assert!(seeds.iter().all(|p| p.x < -120.0), "a seed where h > l/2");
    // Deterministic.
    assert_eq!(
        seeds,
        field.seed_points(bounds, &segments, &points, 1_000_000)
    );
    // Past half the budget: none.
    assert!(
        field
            .seed_points(bounds, &segments, &points, seeds.len())
            .is_empty()
    );
    // The default field (no size asked) and a uniform one: none.
    let default = default_field(&drawing, &r);
    assert!(
        default
            .seed_points(bounds, &segments, &points, 1_000_000)
            .is_empty()
    );
    let uniform = field_of(&drawing, &r, &SizeSpec::DEFAULT.with_expr("1000"));
    assert!(uniform.is_uniform());
    assert!(
        uniform
            .seed_points(bounds, &segments, &points, 1_000_000)
            .is_empty()
    );
}
