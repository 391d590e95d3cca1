//! Shapes → the feature soup ([`Drawing::features`]), its bounding box, and the
//! whole-drawing checks (not empty, extent representable in f64).

use super::drawing::{
    Drawing, Feature, FeatureGeom, FeatureSource, PaintCounts, PathPrecision, Segment, Shape,
    ShapeId,
};
use crate::{Error, Result};
use kurbo::Rect;

/// Smallest accepted ratio of the bbox diagonal to the largest coordinate
/// magnitude: below it, f64 cannot resolve the drawing's details.
const MIN_RELATIVE_EXTENT: f64 = Drawing::MIN_RELATIVE_EXTENT;

/// Assemble a [`Drawing`] from shapes: features, bbox and the whole-drawing checks.
///
/// # Errors
/// [`Error::NoGeometry`] without any feature, [`Error::BadCoordinate`] when the
/// drawing is too small for its distance from the origin.
pub(super) fn assemble(shapes: Vec<Shape>, warnings: Vec<String>) -> Result<Drawing> {
    let features = features(&shapes);
    let Some(first) = features.first() else {
        // say what was there instead (the loader's warnings: images, text
        // without a usable font, ...)
        let why = if warnings.is_empty() {
            String::new()
        } else {
            format!(" ({})", warnings.join("; "))
        };
        return Err(Error::NoGeometry(why));
    };
    let start = match first.geom {
        FeatureGeom::Point(p) => p,
        FeatureGeom::Line(l) => l.p0,
        FeatureGeom::Cubic(c) => c.p0,
        FeatureGeom::Conic(c) => c.p0,
    };
    let mut bbox = Rect::from_points(start, start);
    for f in &features {
        for p in control_points(&f.geom) {
            bbox = bbox.union_pt(p);
        }
    }
    let diagonal = bbox.width().hypot(bbox.height());
    let magnitude = [bbox.x0, bbox.x1, bbox.y0, bbox.y1]
        .into_iter()
        .fold(0.0_f64, |m, c| m.max(c.abs()));
    if diagonal > 0.0 && diagonal < MIN_RELATIVE_EXTENT * magnitude {
        return Err(Error::BadCoordinate(format!(
            "the drawing is too small for its position to be meshed in double precision: \
             its extent {diagonal:e} is below {MIN_RELATIVE_EXTENT:e} times its distance \
             {magnitude:e} from the origin; translate it closer to the origin"
        )));
    }
    Ok(Drawing {
        shapes,
        features,
        bbox,
        warnings,
        precision: PathPrecision::default(),
        paint: PaintCounts::default(),
        view_box: None,
        cell: None,
    })
}

/// The diagonal of the bounding box of every control point of `shapes` (the
/// drawing's `d` before assembly; 0 without any point).
pub(super) fn diagonal(shapes: &[Shape]) -> f64 {
    let mut bbox: Option<Rect> = None;
    for sub in shapes.iter().flat_map(|s| &s.subpaths) {
        let points =
            std::iter::once(sub.start).chain(sub.segments.iter().flat_map(Segment::control_points));
        for p in points {
            bbox = Some(bbox.map_or(Rect::from_points(p, p), |b| b.union_pt(p)));
        }
    }
    bbox.map_or(0.0, |b| b.width().hypot(b.height()))
}

/// Control points of a feature.
fn control_points(g: &FeatureGeom) -> impl Iterator<Item = kurbo::Point> {
    let (pts, n) = match *g {
        FeatureGeom::Point(p) => ([p; 4], 1),
        FeatureGeom::Line(l) => ([l.p0, l.p1, l.p1, l.p1], 2),
        FeatureGeom::Cubic(c) => ([c.p0, c.p1, c.p2, c.p3], 4),
        FeatureGeom::Conic(c) => ([c.p0, c.p1, c.p2, c.p2], 3),
    };
    pts.into_iter().take(n)
}

/// The feature soup: every segment, a point per segment-less subpath, and the
/// implicit closing segment of each open subpath of a filled shape.
pub(super) fn features(shapes: &[Shape]) -> Vec<Feature> {
    let mut out = Vec::new();
    for (si, shape) in shapes.iter().enumerate() {
        let shape_id = ShapeId::from_index(si);
        for (pi, sub) in shape.subpaths.iter().enumerate() {
            let source = |segment: u32| FeatureSource {
                shape: shape_id,
                subpath: u32::try_from(pi).unwrap_or(u32::MAX),
                segment,
            };
            if sub.segments.is_empty() {
                out.push(Feature {
                    geom: FeatureGeom::Point(sub.start),
                    source: source(0),
                });
                continue;
            }
            for (k, seg) in sub.segments.iter().enumerate() {
                let geom = match *seg {
                    Segment::Line(l) => FeatureGeom::Line(l),
                    Segment::Cubic(c) => FeatureGeom::Cubic(c),
                    Segment::Conic(c) => FeatureGeom::Conic(c),
                };
                out.push(Feature {
                    geom,
                    source: source(u32::try_from(k).unwrap_or(u32::MAX - 1)),
                });
            }
            if shape.filled {
                if let Some(line) = sub.implicit_closing_segment() {
                    out.push(Feature {
                        geom: FeatureGeom::Line(line),
                        source: source(FeatureSource::IMPLICIT_CLOSE),
                    });
                }
            }
        }
    }
    out
}
