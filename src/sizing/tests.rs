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
/// formula asks for sizes from 0.5 (x = -200) up to `l` (15.1), every seed
/// lies inside the box and at least h/2 (h the field at the seed) from every
/// feature segment and point, no two seeds are closer than 3/5 of the smaller
/// of their sizes (a leaf's lattice level is within 3^(±1/4) of its smallest
/// size, and the field grows by the grading across the leaf; h/2 from a
/// point on the box's sides, as from a feature),
/// and there are about as many as a mesh of the field has vertices (the
/// integral of 1/(√3/2·h²), less the bands kept free along the features); deterministic;
/// none past the vertex budget. With the open space left out (a drawing
/// whose features hold more vertices than [`seeds::SEED_OPEN_FROM`] asks)
/// there are none where the field is above [`seeds::SEED_BELOW`]·l.
#[test]
fn seeds_follow_the_field_and_keep_off_the_features() {
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
    let seeds = field.seed_points(bounds, &segments, &points, 1_000_000, true);
    assert!(seeds.len() > 1000, "{} seeds", seeds.len());
    for &p in &seeds {
        let h = field.at(p);
        assert!(
            (bounds.x0..=bounds.x1).contains(&p.x) && (bounds.y0..=bounds.y1).contains(&p.y),
            "{p:?} outside the box"
        );
        for s in &segments {
            let d = crate::mesh::point_segment_distance(p, *s);
            assert!(d >= 0.5 * h, "{p:?} at {d} from {s:?}, h {h}");
        }
        assert!(p.distance(points[0]) >= 0.5 * h, "{p:?} at the point");
    }
    // No two seeds closer than 3/5 of the smaller size (a grid of cells of
    // the largest size, each seed against its own and the next cells).
    let cell = r.l;
    let key = |p: Point| ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
    let mut grid: std::collections::HashMap<(i64, i64), Vec<Point>> = Default::default();
    for &p in &seeds {
        grid.entry(key(p)).or_default().push(p);
    }
    for &p in &seeds {
        let (i, j) = key(p);
        for q in (i - 1..=i + 1)
            .flat_map(|a| (j - 1..=j + 1).map(move |b| (a, b)))
            .filter_map(|k| grid.get(&k))
            .flatten()
        {
            if *q != p {
                let h = field.at(p).min(field.at(*q));
                // (a point on the box's sides is to the lattice as a
                // feature's vertex: at least h/2 away)
                let on_side = |p: &Point| {
                    p.x == bounds.x0 || p.x == bounds.x1 || p.y == bounds.y0 || p.y == bounds.y1
                };
                let least = if on_side(&p) || on_side(q) { 0.5 } else { 0.6 };
                assert!(p.distance(*q) >= least * h, "{p:?} and {q:?}: h {h}");
            }
        }
    }
    // About as many as a mesh of the field has vertices, by the integral over
    // a fine grid (the bands kept free along the features hold a few).
    let n = 400;
    let step = bounds.width() / f64::from(n);
    let mut vertices = 0.0;
    for i in 0..n {
        for j in 0..n {
            let p = Point::new(
                bounds.x0 + (f64::from(i) + 0.5) * step,
                bounds.y0 + (f64::from(j) + 0.5) * step,
            );
            vertices += step * step / (0.866 * field.at(p).powi(2));
        }
    }
    let ratio = seeds.len() as f64 / vertices;
    assert!(
        (0.7..=1.3).contains(&ratio),
        "{} seeds for {vertices:.0} vertices",
        seeds.len()
    );
    // Deterministic.
    assert_eq!(
        seeds,
        field.seed_points(bounds, &segments, &points, 1_000_000, true)
    );
    // Past the budget's share: none.
    assert!(
        field
            .seed_points(bounds, &segments, &points, seeds.len(), true)
            .is_empty()
    );
    // Below half of l only: none where the field is above it (x > -129),
    // but for a leaf straddling that line.
    assert_eq!(seeds::SEED_BELOW, 0.5);
    assert!((r.l - 15.13).abs() < 0.01, "l = {}", r.l);
    let fine = field.seeds(Some(false), bounds, &segments, &points, 1_000_000, true);
    assert!(!fine.is_empty() && fine.len() < seeds.len());
    assert!(fine.iter().all(|p| p.x < -120.0), "a seed where h > l/2");
}

/// A uniform field's seeds are one equilateral lattice of spacing `l`: every
/// seed's nearest neighbour is `l` away, and the box's sides carry points
/// `l` apart on them; as many as a mesh of edges `l` has vertices. With
/// features of more than a quarter of that many vertices
/// ([`seeds::SEED_OPEN_FROM`]), none.
#[test]
fn a_uniform_fields_seeds_are_an_equilateral_lattice() {
    let bounds = Rect::new(-3.0, -2.0, 17.0, 10.0);
    let l = 0.5;
    let field = SizeField::uniform(l, bounds);
    let seeds = field.seed_points(bounds, &[], &[], 1_000_000, true);
    let inside: Vec<Point> = seeds
        .iter()
        .copied()
        .filter(|p| p.x > bounds.x0 && p.x < bounds.x1 && p.y > bounds.y0 && p.y < bounds.y1)
        .collect();
    let on_sides = seeds.len() - inside.len();
    // 2·(40 + 24) side pieces of 0.5: 128 less the 4 corners.
    assert_eq!(on_sides, 124);
    for &p in &inside {
        let nearest = seeds
            .iter()
            .filter(|&&q| q != p)
            .map(|q| p.distance(*q))
            .fold(f64::INFINITY, f64::min);
        let to_side = (p.x - bounds.x0)
            .min(bounds.x1 - p.x)
            .min(p.y - bounds.y0)
            .min(bounds.y1 - p.y);
        if to_side > 1.5 * l {
            assert!((nearest - l).abs() < 1e-9 * l, "{p:?}: nearest {nearest}");
        }
    }
    let vertices = bounds.area() / (0.866 * l * l);
    let ratio = seeds.len() as f64 / vertices;
    assert!(
        (0.9..=1.1).contains(&ratio),
        "{} seeds for {vertices:.0}",
        seeds.len()
    );
    // Feature points on a grid of 0.7 (some 490 of them, above a quarter
    // of the seeds).
    let points: Vec<Point> = (0..28)
        .flat_map(|i| {
            (0..17).map(move |j| Point::new(-2.5 + 0.7 * f64::from(i), -1.5 + 0.7 * f64::from(j)))
        })
        .collect();
    assert!(4.0 * points.len() as f64 > vertices);
    assert!(
        field
            .seed_points(bounds, &[], &points, 1_000_000, true)
            .is_empty()
    );
}
