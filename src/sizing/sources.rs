//! The sources of the size field: points on outlines with the size they ask
//! for there, growing away from them (see `tree`): thin strokes, the
//! outlines of `--size` regions, `--size-near` outlines, box edges, and the
//! automatic local feature size.

use super::FieldInput;
use super::tree::Source;
use crate::svg::{Drawing, FeatureGeom, Segment, Shape, ShapeId, Subpath};
use crate::{Error, Result};
use kurbo::{ParamCurve, ParamCurveCurvature, ParamCurveDeriv, Point, Rect, Vec2};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

/// The name of the region no filled shape covers.
pub(super) const BACKGROUND: &str = "background";

/// Edge length per stroke width on the outline of a stroke meshed as an area:
/// the sides of a strip of width w carry vertices about 4.8–8 w apart (the
/// optimizer's [4/5, 4/3] band), so one layer of staggered triangles fills
/// the strip with angles of about atan(2w / 6w) = 18° (10–14° where the
/// staggering breaks, at joins and ends), where the global size would make
/// needles. Smaller values cost triangles and time, larger ones the minimum
/// angle (measurements in `docs/tuning.md`).
pub(crate) const STROKE_SIZE_PER_WIDTH: f64 = 6.0;

/// The slope at which a thin stroke's size grows away from its outline, at
/// least (the grading's own when that is steeper): a factor 2 per element, the
/// wildmeshing-toolkit's ratio. The stroke's size is the drawing's need, not
/// the user's: graded gently it would refine a band of many elements around
/// every stroke (measurements in `docs/tuning.md`).
pub(crate) const STROKE_SLOPE: f64 = 1.0;

/// At most this many sample points of the feature size on one segment, and
/// pieces of one flattened segment.
const MAX_PIECES: f64 = 4096.0;
/// Outlines are flattened to within this fraction of the size they carry.
const FLATTEN_TOL: f64 = 1e-2;

/// The automatic feature size asks for this many elements across a narrow gap
/// or a thin part: the size is the gap's width divided by it.
const ELEMENTS_ACROSS: f64 = 1.0;

/// A point of another branch counts for the feature size only when it lies
/// across the curve: the direction to it makes at most this cosine with the
/// curve's tangent (60° or more from it). Two curves meeting at a junction at an
/// angle of 30° or more are then not a narrow gap near the junction; a sharper
/// wedge is, and the size shrinks into it.
const ACROSS_COS: f64 = 0.5;

/// A point on a drawing's curve, with what the feature size needs.
#[derive(Clone, Copy, Debug)]
struct Sample {
    p: Point,
    /// Unit tangent (zero where the curve has none).
    tangent: Vec2,
    /// Curvature (1 / radius), 0 on straight pieces.
    curvature: f64,
    /// (shape, subpath) of the curve.
    branch: (ShapeId, u32),
    /// Arc length from the subpath's start.
    arc: f64,
    /// The subpath's length when it is closed (arc distances wrap), else ∞.
    period: f64,
}

/// The subpaths flattened to straight pieces within `tol` of the curves.
fn outline_pieces(subpaths: &[Subpath], tol: f64, out: &mut Vec<(Point, Point)>) {
    for sp in subpaths {
        let closing = sp.implicit_closing_segment().map(Segment::Line);
        for seg in sp.segments.iter().copied().chain(closing) {
            let n = match seg {
                Segment::Line(_) => 1.0,
                _ => {
                    // chord error of n pieces ≈ κ (L / n)² / 8
                    let kappa = (0..=8)
                        .map(|i| curvature(&seg, f64::from(i) / 8.0))
                        .fold(0.0, f64::max);
                    polygon_length(&seg) * (kappa / (8.0 * tol)).sqrt()
                }
            };
            let n = n.ceil().clamp(1.0, MAX_PIECES) as usize;
            let mut prev = eval(&seg, 0.0);
            for i in 1..=n {
                let p = eval(&seg, i as f64 / n as f64);
                out.push((prev, p));
                prev = p;
            }
        }
        if sp.segments.is_empty() {
            out.push((sp.start, sp.start));
        }
    }
}

fn curvature(seg: &Segment, t: f64) -> f64 {
    match seg {
        Segment::Line(_) => 0.0,
        Segment::Cubic(c) => c.curvature(t).abs(),
        Segment::Conic(c) => c.curvature(t).abs(),
    }
}

fn polygon_length(seg: &Segment) -> f64 {
    let pts = seg.control_points();
    pts.windows(2).map(|w| w[0].distance(w[1])).sum()
}

fn eval(seg: &Segment, t: f64) -> Point {
    match seg {
        Segment::Line(l) => l.eval(t),
        Segment::Cubic(c) => c.eval(t),
        Segment::Conic(c) => c.eval(t),
    }
}

/// Sources of size `h` growing at `slope` along the outlines of `shapes`.
fn along(drawing: &Drawing, shapes: &[ShapeId], h: f64, slope: f64, out: &mut Vec<Source>) {
    let mut pieces = Vec::new();
    for s in shapes {
        outline_pieces(
            &drawing.shapes[s.index()].subpaths,
            FLATTEN_TOL * h,
            &mut pieces,
        );
    }
    out.extend(pieces.into_iter().map(|(a, b)| Source { a, b, h, slope }));
}

/// Thin strokes meshed as areas: [`STROKE_SIZE_PER_WIDTH`] times the width on
/// the stroke's outline, graded at `slope` or [`STROKE_SLOPE`], the steeper. A stroke narrower than `mu` gets
/// none: its two outlines are not kept apart (they are closer than the feature
/// envelope), so no element ever fits its width.
pub(super) fn strokes(drawing: &Drawing, mu: f64, slope: f64) -> Vec<Source> {
    let mut out = Vec::new();
    for (i, s) in drawing.shapes.iter().enumerate() {
        if let Some(h) = stroke_size(s, mu) {
            along(
                drawing,
                &[ShapeId::from_index(i)],
                h,
                slope.max(STROKE_SLOPE),
                &mut out,
            );
        }
    }
    out
}

/// The size a thin stroke meshed as an area asks for on its own outline
/// ([`STROKE_SIZE_PER_WIDTH`] times its width; see [`strokes`]), `None` for
/// any other shape, for a stroke narrower than `mu`, and for a stroke that
/// joins its fill's region (its inner outline bounds nothing: no band to fit).
pub(super) fn stroke_size(shape: &Shape, mu: f64) -> Option<f64> {
    if shape.paint.joins_fill {
        return None;
    }
    let w = shape.paint.stroke_width.filter(|&w| w >= mu)?;
    Some(STROKE_SIZE_PER_WIDTH * w)
}

/// The shapes whose region is `name` (none for [`BACKGROUND`]).
///
/// # Errors
/// [`Error::InvalidParams`] when no region has that name, listing those that exist.
pub(super) fn shapes_named(input: &FieldInput<'_>, name: &str, flag: &str) -> Result<Vec<ShapeId>> {
    if name == BACKGROUND {
        return Ok(Vec::new());
    }
    let found: Vec<ShapeId> = input
        .region_names
        .iter()
        .enumerate()
        .filter(|(_, n)| n.as_deref() == Some(name))
        .map(|(i, _)| ShapeId::from_index(i))
        .collect();
    if found.is_empty() {
        let mut names: Vec<&str> = input
            .region_names
            .iter()
            .flatten()
            .map(String::as_str)
            .collect();
        names.sort_unstable();
        names.dedup();
        const SHOWN: usize = 30;
        let more = if names.len() > SHOWN { ", ..." } else { "" };
        names.truncate(SHOWN);
        names.push(BACKGROUND);
        return Err(Error::InvalidParams(format!(
            "{flag} {name}: no region of that name; the regions are: {}{more}",
            names.join(", ")
        )));
    }
    Ok(found)
}

/// Every filled shape (the outline of the background).
fn filled(drawing: &Drawing) -> Vec<ShapeId> {
    (0..drawing.shapes.len())
        .filter(|&i| drawing.shapes[i].filled)
        .map(ShapeId::from_index)
        .collect()
}

/// The user's outline fields: region outlines (`--size`), `--size-near`, box edges.
///
/// # Errors
/// As [`shapes_named`].
pub(super) fn user(
    input: &FieldInput<'_>,
    slope: f64,
    applied: &mut Vec<String>,
) -> Result<Vec<Source>> {
    let (d, l) = (input.resolved.d, input.resolved.l);
    let mut out = Vec::new();
    for r in &input.spec.regions {
        let size = r.size.resolve(d);
        let mut shapes = shapes_named(input, &r.name, "--size")?;
        if r.name == BACKGROUND {
            shapes = filled(input.drawing);
        }
        along(input.drawing, &shapes, size, slope, &mut out);
    }
    for n in &input.spec.near {
        let size = n.size.resolve(d);
        let mut shapes = shapes_named(input, &n.name, "--size-near")?;
        if n.name == BACKGROUND {
            shapes = filled(input.drawing);
        }
        let s = match n.distance {
            Some(dist) => ((l - size) / dist.resolve(d)).max(0.0).min(slope),
            None => slope,
        };
        along(input.drawing, &shapes, size, s, &mut out);
    }
    if !input.spec.near.is_empty() {
        applied.push("size-near".into());
    }
    for b in &input.spec.boxes {
        let [x0, y0, x1, y1] = b.corners;
        let r = Rect::new(x0, y0, x1, y1).abs();
        let size = b.size.resolve(d);
        let corners = [
            Point::new(r.x0, r.y0),
            Point::new(r.x1, r.y0),
            Point::new(r.x1, r.y1),
            Point::new(r.x0, r.y1),
        ];
        for k in 0..4 {
            let (a, b) = (corners[k], corners[(k + 1) % 4]);
            out.push(Source {
                a,
                b,
                h: size,
                slope,
            });
        }
    }
    Ok(out)
}

/// Samples of every feature of the drawing: at most `step` apart, and at most
/// `turn` radians of turning apart on curves.
fn feature_samples(drawing: &Drawing, step: f64, turn: f64) -> Vec<Sample> {
    // Arc length per (shape, subpath), accumulated in feature order.
    let mut arc: FxHashMap<(ShapeId, u32), f64> = FxHashMap::default();
    let mut out = Vec::new();
    for f in &drawing.features {
        let branch = (f.source.shape, f.source.subpath);
        let seg = match f.geom {
            FeatureGeom::Point(_) => continue,
            FeatureGeom::Line(l) => Segment::Line(l),
            FeatureGeom::Cubic(c) => Segment::Cubic(c),
            FeatureGeom::Conic(c) => Segment::Conic(c),
        };
        let deriv = |t: f64| -> Vec2 {
            match seg {
                Segment::Line(l) => l.p1 - l.p0,
                Segment::Cubic(c) => c.deriv().eval(t).to_vec2(),
                Segment::Conic(c) => c.deriv(t),
            }
        };
        // turning, from 16 tangents
        let mut turning = 0.0;
        let mut last = deriv(0.0);
        for i in 1..=16 {
            let d = deriv(f64::from(i) / 16.0);
            if last.hypot2() > 0.0 && d.hypot2() > 0.0 {
                turning += last.cross(d).atan2(last.dot(d)).abs();
            }
            if d.hypot2() > 0.0 {
                last = d;
            }
        }
        let len = polygon_length(&seg);
        let n = ((len / step).ceil() + (turning / turn).ceil()).clamp(1.0, 4096.0) as usize;
        let start = *arc.get(&branch).unwrap_or(&0.0);
        let mut prev = eval(&seg, 0.0);
        let mut s = start;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let p = eval(&seg, t);
            s += p.distance(prev);
            prev = p;
            let d = deriv(t);
            let tangent = if d.hypot2() > 0.0 {
                d.normalize()
            } else {
                Vec2::ZERO
            };
            out.push(Sample {
                p,
                tangent,
                curvature: curvature(&seg, t),
                branch,
                arc: s,
                period: f64::INFINITY,
            });
        }
        arc.insert(branch, s);
    }
    // Closed subpaths: arc distances wrap around.
    for smp in &mut out {
        let (shape, sub) = smp.branch;
        if let Some(sp) = drawing
            .shapes
            .get(shape.index())
            .and_then(|s| s.subpaths.get(sub as usize))
            && (sp.closed || sp.segments.last().is_some_and(|l| l.end() == sp.start))
        {
            smp.period = arc.get(&smp.branch).copied().unwrap_or(f64::INFINITY);
        }
    }
    out
}

/// The automatic local feature size: on every curve, the size its curvature
/// allows a primary edge (α times the radius: the turning bound of invariant 3)
/// and the width of the narrow gap or thin part it bounds (the distance to the
/// nearest point of another branch of the curve network across from it, beyond
/// the envelope ε: curves closer than that are one feature), divided by
/// [`ELEMENTS_ACROSS`].
pub(super) fn feature_size(input: &FieldInput<'_>, slope: f64) -> Vec<Source> {
    let r = input.resolved;
    let l = r.l;
    let samples = feature_samples(input.drawing, 0.25 * l, 0.5 * r.alpha);
    if samples.is_empty() {
        return Vec::new();
    }
    // Bucket grid of cell l/2 over the samples.
    let cell = 0.5 * l;
    let key = |p: Point| ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
    let mut grid: FxHashMap<(i64, i64), Vec<u32>> = FxHashMap::default();
    for (i, s) in samples.iter().enumerate() {
        grid.entry(key(s.p)).or_default().push(i as u32);
    }
    let eps = r.eps;
    let sizes: Vec<Option<f64>> = samples
        .par_iter()
        .map(|a| {
            let mut h = l;
            if a.curvature > 0.0 {
                h = h.min(r.alpha / a.curvature);
            }
            let (ci, cj) = key(a.p);
            for dj in -2..=2 {
                for di in -2..=2 {
                    let Some(list) = grid.get(&(ci + di, cj + dj)) else {
                        continue;
                    };
                    for &k in list {
                        let b = &samples[k as usize];
                        let v = b.p - a.p;
                        let dist = v.hypot();
                        if dist <= eps || dist / ELEMENTS_ACROSS >= h {
                            continue;
                        }
                        if a.tangent.dot(v).abs() > ACROSS_COS * dist {
                            continue;
                        }
                        if a.branch == b.branch {
                            let mut sep = (a.arc - b.arc).abs();
                            if a.period.is_finite() {
                                sep = sep.min(a.period - sep);
                            }
                            if sep <= 2.0 * dist {
                                continue;
                            }
                        }
                        h = h.min(dist / ELEMENTS_ACROSS);
                    }
                }
            }
            (h < l).then_some(h)
        })
        .collect();
    // Keep the sources no kept one already dominates (smallest first).
    let mut order: Vec<usize> = (0..samples.len()).filter(|&i| sizes[i].is_some()).collect();
    order.sort_by(|&a, &b| {
        sizes[a]
            .unwrap_or(l)
            .total_cmp(&sizes[b].unwrap_or(l))
            .then(a.cmp(&b))
    });
    let mut kept: FxHashMap<(i64, i64), Vec<Source>> = FxHashMap::default();
    let mut out = Vec::new();
    for i in order {
        let h = sizes[i].unwrap_or(l).max(r.l_min);
        let p = samples[i].p;
        let kf = ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
        let dominated = (-1..=1).any(|dj| {
            (-1..=1).any(|di| {
                kept.get(&(kf.0 + di, kf.1 + dj))
                    .is_some_and(|v| v.iter().any(|q| q.at(p) <= h))
            })
        });
        if dominated {
            continue;
        }
        let s = Source::point(p, h, slope);
        kept.entry(kf).or_default().push(s);
        out.push(s);
    }
    out
}
