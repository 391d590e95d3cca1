//! Tests of classification and region selection on hand-built meshes.
//! (End-to-end tests on CDT meshes are in `tests/regions.rs`.)

use super::*;
use crate::budget::Deadline;
use crate::element::Order;
use crate::fem::LineKind;
use crate::regions::select::RegionMode;
use crate::svg::{Feature, FeatureGeom, FeatureSource, FillRule, Segment, Shape, ShapeId, Subpath};
use kurbo::{Line, Point, Rect};

pub(crate) fn shape(
    id: Option<&str>,
    index: u32,
    rule: FillRule,
    colour: [u8; 3],
    subpaths: Vec<Subpath>,
) -> Shape {
    Shape {
        svg_id: id.map(str::to_owned),
        element_index: index,
        paint_order: index,
        filled: true,
        stroked: false,
        fill_rule: rule,
        fill_colour: Some(colour),
        paint: Default::default(),
        subpaths,
    }
}

pub(crate) fn polygon(points: &[(f64, f64)]) -> Subpath {
    let p: Vec<Point> = points.iter().map(|&(x, y)| Point::new(x, y)).collect();
    let mut segments: Vec<Segment> = p
        .windows(2)
        .map(|w| Segment::Line(Line::new(w[0], w[1])))
        .collect();
    segments.push(Segment::Line(Line::new(p[p.len() - 1], p[0])));
    Subpath {
        segments,
        start: p[0],
        closed: true,
    }
}

/// A drawing of `shapes` with its feature soup and bbox derived as the loader does.
pub(crate) fn drawing(shapes: Vec<Shape>) -> Drawing {
    let mut features = Vec::new();
    for (si, s) in shapes.iter().enumerate() {
        for (pi, sp) in s.subpaths.iter().enumerate() {
            let src = |segment| FeatureSource {
                shape: ShapeId::from_index(si),
                subpath: pi as u32,
                segment,
            };
            for (k, seg) in sp.segments.iter().enumerate() {
                let geom = match *seg {
                    Segment::Line(l) => FeatureGeom::Line(l),
                    Segment::Cubic(c) => FeatureGeom::Cubic(c),
                    Segment::Conic(c) => FeatureGeom::Conic(c),
                };
                features.push(Feature {
                    geom,
                    source: src(k as u32),
                });
            }
            if s.filled {
                if let Some(l) = sp.implicit_closing_segment() {
                    features.push(Feature {
                        geom: FeatureGeom::Line(l),
                        source: src(FeatureSource::IMPLICIT_CLOSE),
                    });
                }
            }
        }
    }
    let mut bbox: Option<Rect> = None;
    for s in &shapes {
        for sp in &s.subpaths {
            for seg in &sp.segments {
                for p in seg.control_points() {
                    bbox = Some(bbox.map_or(Rect::from_points(p, p), |b| b.union_pt(p)));
                }
            }
        }
    }
    Drawing {
        shapes,
        features,
        bbox: bbox.expect("test drawing has geometry"),
        warnings: vec![],
        precision: Default::default(),
        paint: Default::default(),
        view_box: None,
        cell: None,
    }
}

/// A structured grid mesh of [0, n]² (unit cells, two CCW triangles each), with
/// line elements on the given closed unit-grid polygons (group per polygon).
fn grid(n: u32, outlines: &[(&str, &[(u32, u32)])]) -> FemMesh {
    let id = |i: u32, j: u32| j * (n + 1) + i;
    let mut m = FemMesh {
        order: Some(Order::Linear),
        surfaces: vec!["domain".into()],
        ..FemMesh::default()
    };
    for j in 0..=n {
        for i in 0..=n {
            m.nodes.push(Point::new(i as f64, j as f64));
        }
    }
    for j in 0..n {
        for i in 0..n {
            m.triangles
                .extend([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            m.triangles
                .extend([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            m.triangle_group.extend([0, 0]);
        }
    }
    for (g, (name, poly)) in outlines.iter().enumerate() {
        m.curves.push((*name).to_owned());
        for k in 0..poly.len() {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            // Unit steps along the (axis-aligned) side a→b.
            let (dx, dy) = (
                (b.0 as i64 - a.0 as i64).signum(),
                (b.1 as i64 - a.1 as i64).signum(),
            );
            let steps = a.0.abs_diff(b.0).max(a.1.abs_diff(b.1)) as i64;
            for s in 0..steps {
                let at = |s: i64| ((a.0 as i64 + s * dx) as u32, (a.1 as i64 + s * dy) as u32);
                let (p, q) = (at(s), at(s + 1));
                m.lines.extend([id(p.0, p.1), id(q.0, q.1)]);
                m.line_group.push(g as u32);
                m.line_kind.push(LineKind::Constraint);
            }
        }
    }
    m
}

/// [`tag`] with the tolerances these tests use (ε_m 1e-9, l_min 1e-5) and no
/// time limit.
fn tag_no_limit(
    d: &Drawing,
    mesh: &FemMesh,
    opts: &RegionOptions,
) -> Result<(FemMesh, RegionReport, Vec<ShapeId>)> {
    tag(d, mesh, opts, 1e-9, 1e-5, None, Deadline::NONE)
}

fn stat<'a>(stats: &'a [RegionStat], name: &str) -> &'a RegionStat {
    stats
        .iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no region {name} in {stats:?}"))
}

fn check_mesh(m: &FemMesh) {
    let nn = m.nodes.len() as u32;
    assert!(m.triangles.iter().chain(&m.lines).all(|&v| v < nn));
    let mut used = vec![false; m.nodes.len()];
    for &v in m.triangles.iter().chain(&m.lines) {
        used[v as usize] = true;
    }
    assert!(used.iter().all(|&u| u), "unused node");
    assert_eq!(m.triangle_group.len(), m.triangle_count());
    assert!(
        m.triangle_group
            .iter()
            .all(|&g| (g as usize) < m.surfaces.len())
    );
    assert_eq!(m.line_group.len(), m.line_count());
    assert_eq!(m.line_kind.len(), m.line_count());
    assert!(m.line_group.iter().all(|&g| (g as usize) < m.curves.len()));
    for g in 0..m.surfaces.len() as u32 {
        assert!(
            m.triangle_group.contains(&g),
            "empty surface {}",
            m.surfaces[g as usize]
        );
    }
    for g in 0..m.curves.len() as u32 {
        assert!(
            m.line_group.contains(&g),
            "empty curve {}",
            m.curves[g as usize]
        );
    }
}

/// Two overlapping squares: `a` = [1,5]×[1,5] under `b` = [3,7]×[3,7], box [0,8]².
fn two_squares() -> (Drawing, FemMesh) {
    let a = shape(
        Some("a"),
        0,
        FillRule::NonZero,
        [255, 0, 0],
        vec![polygon(&[(1.0, 1.0), (5.0, 1.0), (5.0, 5.0), (1.0, 5.0)])],
    );
    let b = shape(
        Some("b"),
        1,
        FillRule::NonZero,
        [0, 0, 255],
        vec![polygon(&[(3.0, 3.0), (7.0, 3.0), (7.0, 7.0), (3.0, 7.0)])],
    );
    let mesh = grid(
        8,
        &[
            ("a", &[(1, 1), (5, 1), (5, 5), (1, 5)]),
            ("b", &[(3, 3), (7, 3), (7, 7), (3, 7)]),
        ],
    );
    (drawing(vec![a, b]), mesh)
}

#[test]
fn topmost_shape_wins_and_areas_add_up() {
    let (d, mesh) = two_squares();
    for vote in [false, true] {
        let asg = classify(
            &d,
            &mesh,
            &ClassifyOptions::new(1e-9).with_vote_per_face(vote),
        );
        assert_eq!(asg.near_boundary, 0);
        assert_eq!(asg.relabelled, 0);
        let (out, stats) = apply(&d, &mesh, &asg, &RegionOptions::DEFAULT, None).unwrap();
        check_mesh(&out);
        assert_eq!(out.surfaces, ["background", "a", "b"]);
        assert_eq!(stat(&stats, "a").area, 12.0);
        assert_eq!(stat(&stats, "b").area, 16.0);
        assert_eq!(stat(&stats, "background").area, 64.0 - 28.0);
        assert_eq!(stat(&stats, "b").triangles, 32);
        assert_eq!(out.nodes.len(), mesh.nodes.len());
        assert_eq!(out.lines, mesh.lines);
    }
}

#[test]
fn paint_order_not_document_order_decides() {
    let (mut d, mesh) = two_squares();
    d.shapes[0].paint_order = 5;
    let asg = classify(&d, &mesh, &ClassifyOptions::new(1e-9));
    let (_, stats) = apply(&d, &mesh, &asg, &RegionOptions::DEFAULT, None).unwrap();
    assert_eq!(stat(&stats, "a").area, 16.0);
    assert_eq!(stat(&stats, "b").area, 12.0);
}

/// A fill at opacity 0.999 is alpha 255 as a byte: it names the
/// same region as the opaque fill (`fill-#5d432e`), not a second one
/// (`fill-#5d432eff`); an opacity that rounds below 255 keeps its alpha.
#[test]
fn an_opacity_that_rounds_to_opaque_names_the_opaque_region() {
    let (mut d, mesh) = two_squares();
    d.shapes[0].fill_colour = Some([0x5d, 0x43, 0x2e]);
    d.shapes[1].fill_colour = Some([0x5d, 0x43, 0x2e]);
    d.shapes[1].paint.alpha = 0.999;
    let asg = classify(&d, &mesh, &ClassifyOptions::new(1e-9));
    let opts = RegionOptions::DEFAULT.with_mode(RegionMode::Colour);
    let (out, stats) = apply(&d, &mesh, &asg, &opts, None).unwrap();
    assert_eq!(out.surfaces, ["background", "fill-#5d432e"]);
    assert_eq!(stat(&stats, "fill-#5d432e").area, 28.0);
    assert_eq!(
        stat(&stats, "fill-#5d432e").colour.as_deref(),
        Some("#5d432e")
    );
    for (alpha, name) in [
        (0.997, "fill-#5d432efe"),
        (0.5, "fill-#5d432e80"),
        (0.0, "fill-#5d432e00"),
    ] {
        d.shapes[1].paint.alpha = alpha;
        let (out, _) = apply(&d, &mesh, &asg, &opts, None).unwrap();
        assert_eq!(
            out.surfaces,
            ["background", "fill-#5d432e", name],
            "alpha {alpha}"
        );
    }
}

#[test]
fn colour_mode_merges_equal_fills_and_none_mode_is_one_domain() {
    let (mut d, mesh) = two_squares();
    let asg = classify(&d, &mesh, &ClassifyOptions::new(1e-9));
    let opts = RegionOptions::DEFAULT.with_mode(RegionMode::Colour);
    let (_, stats) = apply(&d, &mesh, &asg, &opts, None).unwrap();
    assert_eq!(stat(&stats, "fill-#ff0000").area, 12.0);
    assert_eq!(stat(&stats, "fill-#0000ff").area, 16.0);
    d.shapes[1].fill_colour = Some([255, 0, 0]);
    let (out, stats) = apply(&d, &mesh, &asg, &opts, None).unwrap();
    assert_eq!(out.surfaces, ["background", "fill-#ff0000"]);
    assert_eq!(stat(&stats, "fill-#ff0000").area, 28.0);

    // Past the run's time limit the stage stops with a time-limit error
    // naming it (a drawing whose winding queries are slow must not run 11 s here
    // under a 10 s limit and still write its mesh).
    let passed = Deadline::after(Some(0.0));
    match tag(&d, &mesh, &RegionOptions::DEFAULT, 1e-9, 1e-5, None, passed) {
        Err(crate::Error::TimeLimit { stage, .. }) => assert_eq!(stage, crate::Stage::Regions),
        other => panic!("expected a time-limit error, got {:?}", other.map(|r| r.1)),
    }

    let none = RegionOptions::DEFAULT.with_mode(RegionMode::None);
    let (out, report, _) = tag_no_limit(&d, &mesh, &none).unwrap();
    assert_eq!(out.surfaces, ["domain"]);
    assert_eq!(report.surfaces[0].area, 64.0);
    let (out, report, _) = tag_no_limit(&d, &mesh, &none.with_cut_outside(true)).unwrap();
    assert_eq!(out.surfaces, ["domain"]);
    assert_eq!(report.surfaces[0].area, 28.0);
}

#[test]
fn cut_outside_drops_background_nodes_and_keeps_boundary_lines() {
    let (d, mesh) = two_squares();
    let opts = RegionOptions::DEFAULT.with_cut_outside(true);
    let (out, report, _) = tag_no_limit(&d, &mesh, &opts).unwrap();
    check_mesh(&out);
    assert_eq!(out.surfaces, ["a", "b"]);
    let area: f64 = report.surfaces.iter().map(|s| s.area).sum();
    assert_eq!(area, 28.0);
    // Nodes of the two squares' union: 5×5 + 5×5 − 3×3.
    assert_eq!(out.nodes.len(), 41);
    // Every boundary line of both squares borders a kept triangle.
    assert_eq!(feature_lines(&out), mesh.line_count());
    assert_eq!(out.curves, ["a", "b", "boundary"]);
    // The union's outline: 16 + 16 − 2 × 4 unit edges, counter-clockwise.
    assert_eq!(boundary_enclosed(&out), (24, 28.0));
}

/// Number of lines that are not on the domain's boundary.
fn feature_lines(m: &FemMesh) -> usize {
    m.line_kind
        .iter()
        .filter(|&&k| k != LineKind::Boundary)
        .count()
}

/// The number of lines of the physical curve `boundary` and the area they
/// enclose (positive: the domain is on their left), after checking that no
/// two of them start or end at the same node.
fn boundary_enclosed(m: &FemMesh) -> (usize, f64) {
    let g = m
        .curves
        .iter()
        .position(|c| c == crate::fem::BOUNDARY)
        .expect("a boundary curve") as u32;
    let (mut starts, mut ends) = (
        std::collections::HashSet::new(),
        std::collections::HashSet::new(),
    );
    let mut n = 0;
    let mut area = 0.0;
    for i in (0..m.line_count()).filter(|&i| m.line_group[i] == g) {
        assert_eq!(m.line_kind[i], LineKind::Boundary);
        let l = m.line(i);
        assert!(starts.insert(l[0]) && ends.insert(l[1]), "line {i}: {l:?}");
        let (a, b) = (m.nodes[l[0] as usize], m.nodes[l[1] as usize]);
        area += 0.5 * a.to_vec2().cross(b.to_vec2());
        n += 1;
    }
    (n, area)
}

#[test]
fn keep_and_hole_select_regions() {
    let (d, mesh) = two_squares();
    let (out, report, _) = tag_no_limit(
        &d,
        &mesh,
        &RegionOptions::DEFAULT.with_keep(vec!["a".into()]),
    )
    .unwrap();
    check_mesh(&out);
    assert_eq!(out.surfaces, ["a"]);
    assert_eq!(report.surfaces[0].area, 12.0);
    // Region a is the L-shape [1,5]² \ [3,5]²: a's outline without its 4 lines
    // inside b (12), and b's outline along the L's inner corner (2 + 2).
    assert_eq!(feature_lines(&out), 16);
    assert_eq!(out.curves, ["a", "b", "boundary"]);
    // Its boundary is the L's outline (16 unit edges), counter-clockwise.
    assert_eq!(boundary_enclosed(&out), (16, 12.0));
    // Removing b by a point inside it, and the background by a point in the padding.
    let holes = vec![Point::new(6.5, 6.5), Point::new(0.5, 7.5)];
    let (out, report, _) =
        tag_no_limit(&d, &mesh, &RegionOptions::DEFAULT.with_holes(holes)).unwrap();
    assert_eq!(out.surfaces, ["a"]);
    assert_eq!(report.surfaces[0].area, 12.0);
    assert_eq!(boundary_enclosed(&out), (16, 12.0));
    // Errors a user can act on.
    let bad = tag_no_limit(
        &d,
        &mesh,
        &RegionOptions::DEFAULT.with_keep(vec!["c".into()]),
    )
    .unwrap_err();
    assert!(bad.to_string().contains("background, a, b"), "{bad}");
    let outside = RegionOptions::DEFAULT.with_holes(vec![Point::new(9.0, 1.0)]);
    assert!(tag_no_limit(&d, &mesh, &outside).is_err());
    let all = RegionOptions::DEFAULT
        .with_cut_outside(true)
        .with_keep(vec!["background".into()]);
    assert!(tag_no_limit(&d, &mesh, &all).is_err());
}

#[test]
fn evenodd_and_nonzero_differ_in_the_overlap() {
    // Two nested squares, same orientation, in one shape: nonzero fills the
    // inner one (winding 2), evenodd leaves it empty.
    let sub = vec![
        polygon(&[(1.0, 1.0), (7.0, 1.0), (7.0, 7.0), (1.0, 7.0)]),
        polygon(&[(3.0, 3.0), (5.0, 3.0), (5.0, 5.0), (3.0, 5.0)]),
    ];
    let mesh = grid(
        8,
        &[
            ("s", &[(1, 1), (7, 1), (7, 7), (1, 7)]),
            ("s", &[(3, 3), (5, 3), (5, 5), (3, 5)]),
        ],
    );
    for (rule, area) in [(FillRule::NonZero, 36.0), (FillRule::EvenOdd, 32.0)] {
        let d = drawing(vec![shape(Some("s"), 0, rule, [0; 3], sub.clone())]);
        let (_, report, _) = tag_no_limit(&d, &mesh, &RegionOptions::DEFAULT).unwrap();
        assert_eq!(stat(&report.surfaces, "s").area, area, "{rule:?}");
        assert_eq!(stat(&report.surfaces, "background").area, 64.0 - area);
    }
}

#[test]
fn a_face_is_labelled_by_its_majority() {
    // The shape is the square [1,5]² but the mesh's feature lines run along
    // [1,5]×[1,4] (as if a flattening were off by one row): the row y ∈ [4,5] is
    // in the background's face; per-face voting gives it to the background and
    // reports it as relabelled.
    let (d, _) = two_squares();
    let d = drawing(vec![d.shapes[0].clone()]);
    let mesh = grid(8, &[("a", &[(1, 1), (5, 1), (5, 4), (1, 4)])]);
    let asg = classify(&d, &mesh, &ClassifyOptions::new(1e-9));
    assert_eq!(asg.relabelled, 8);
    assert_eq!(asg.relabelled_area, 4.0);
    let (_, stats) = apply(&d, &mesh, &asg, &RegionOptions::DEFAULT, None).unwrap();
    assert_eq!(stat(&stats, "a").area, 12.0);
    let own = classify(
        &d,
        &mesh,
        &ClassifyOptions::new(1e-9).with_vote_per_face(false),
    );
    let (_, stats) = apply(&d, &mesh, &own, &RegionOptions::DEFAULT, None).unwrap();
    assert_eq!(stat(&stats, "a").area, 16.0);
}

#[test]
fn a_shape_named_background_does_not_merge_with_it() {
    let (mut d, mesh) = two_squares();
    d.shapes[1].svg_id = Some("background".into());
    let (out, _, _) = tag_no_limit(&d, &mesh, &RegionOptions::DEFAULT).unwrap();
    assert_eq!(out.surfaces, ["background", "a", "shape-1"]);
}

#[test]
fn the_rim_of_a_hole_runs_clockwise() {
    // An outer square [1,7]² around an inner one [3,5]², cut outside and with
    // the inner one dropped: the boundary is the outer outline (24 unit edges,
    // counter-clockwise) and the hole's rim (8, clockwise).
    let outer = shape(
        Some("outer"),
        0,
        FillRule::NonZero,
        [255, 0, 0],
        vec![polygon(&[(1.0, 1.0), (7.0, 1.0), (7.0, 7.0), (1.0, 7.0)])],
    );
    let inner = shape(
        Some("inner"),
        1,
        FillRule::NonZero,
        [0, 0, 255],
        vec![polygon(&[(3.0, 3.0), (5.0, 3.0), (5.0, 5.0), (3.0, 5.0)])],
    );
    let mesh = grid(
        8,
        &[
            ("outer", &[(1, 1), (7, 1), (7, 7), (1, 7)]),
            ("inner", &[(3, 3), (5, 3), (5, 5), (3, 5)]),
        ],
    );
    let d = drawing(vec![outer, inner]);
    let opts = RegionOptions::DEFAULT
        .with_cut_outside(true)
        .with_holes(vec![Point::new(4.2, 4.5)]);
    let (out, _, _) = tag_no_limit(&d, &mesh, &opts).unwrap();
    assert_eq!(out.surfaces, ["outer"]);
    assert_eq!(boundary_enclosed(&out), (32, 36.0 - 4.0));
}

/// Lines `(a, b)` of `m` in group `g`, as node pairs.
fn lines_of(m: &FemMesh, g: u32) -> Vec<(u32, u32)> {
    (0..m.line_count())
        .filter(|&i| m.line_group[i] == g)
        .map(|i| (m.line(i)[0], m.line(i)[1]))
        .collect()
}

#[test]
fn feature_lines_run_one_way() {
    // A closed square written clockwise, and an open polyline from right to
    // left; their lines are written in scrambled directions.
    let square = shape(
        Some("sq"),
        0,
        FillRule::NonZero,
        [255, 0, 0],
        vec![polygon(&[(1.0, 1.0), (1.0, 5.0), (5.0, 5.0), (5.0, 1.0)])],
    );
    let stroke_path = Subpath {
        segments: vec![
            Segment::Line(Line::new(Point::new(7.0, 6.0), Point::new(4.0, 6.0))),
            Segment::Line(Line::new(Point::new(4.0, 6.0), Point::new(2.0, 6.0))),
        ],
        start: Point::new(7.0, 6.0),
        closed: false,
    };
    let mut stroke = shape(
        Some("st"),
        1,
        FillRule::NonZero,
        [0, 0, 0],
        vec![stroke_path],
    );
    stroke.filled = false;
    let d = drawing(vec![square, stroke]);
    let mut mesh = grid(
        8,
        &[
            ("sq", &[(1, 1), (5, 1), (5, 5), (1, 5)]),
            ("st", &[(2, 6), (7, 6)]),
        ],
    );
    // `grid` closes every outline: drop the stroke's way back.
    let keep: Vec<usize> = (0..mesh.line_count())
        .filter(|&i| mesh.line_group[i] == 0 || mesh.line(i)[0] < mesh.line(i)[1])
        .collect();
    let (lines, group) = (mesh.lines.clone(), mesh.line_group.clone());
    mesh.lines = keep
        .iter()
        .flat_map(|&i| lines[2 * i..2 * i + 2].to_vec())
        .collect();
    mesh.line_group = keep.iter().map(|&i| group[i]).collect();
    mesh.line_kind = vec![LineKind::Constraint; keep.len()];
    for i in (0..mesh.line_count()).step_by(3) {
        mesh.reverse_line(i);
    }
    let shapes: Vec<ShapeId> = mesh
        .line_group
        .iter()
        .map(|&g| ShapeId::from_index(g as usize))
        .collect();
    orient_lines(&d, &mut mesh, &shapes, &Deadline::NONE);
    for g in [0, 1] {
        let lines = lines_of(&mesh, g);
        let starts: std::collections::HashSet<u32> = lines.iter().map(|l| l.0).collect();
        let ends: std::collections::HashSet<u32> = lines.iter().map(|l| l.1).collect();
        assert_eq!(
            (starts.len(), ends.len()),
            (lines.len(), lines.len()),
            "{g}"
        );
    }
    // The square runs counter-clockwise whatever its source's direction.
    let area: f64 = lines_of(&mesh, 0)
        .iter()
        .map(|&(a, b)| {
            0.5 * mesh.nodes[a as usize]
                .to_vec2()
                .cross(mesh.nodes[b as usize].to_vec2())
        })
        .sum();
    assert_eq!(area, 16.0);
    // The stroke runs as drawn: from x = 7 to x = 2.
    for (a, b) in lines_of(&mesh, 1) {
        assert!(mesh.nodes[a as usize].x > mesh.nodes[b as usize].x);
    }
}
