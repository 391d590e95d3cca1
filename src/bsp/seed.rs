//! The Delaunay seed: every input vertex and the box corners, triangulated by spade.

use super::BspInput;
use crate::mesh::VertexTag;
use crate::{Error, Result};
use kurbo::{Point, Rect};
use spade::{DelaunayTriangulation, Point2, Triangulation};
use std::collections::HashMap;

/// The seed triangulation, in the caller's (unscaled) coordinates.
pub(super) struct Seed {
    /// Distinct points with their tags.
    pub(super) points: Vec<(Point, VertexTag)>,
    /// Counter-clockwise triangles, as indices into `points`.
    pub(super) triangles: Vec<[u32; 3]>,
    /// The coordinates were multiplied by 2^scale_exp for spade.
    pub(super) scale_exp: i32,
}

/// `-0.0` and `0.0` are the same point.
fn key(p: Point) -> (u64, u64) {
    ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits())
}

/// spade's exponent range for exact predicates (`MIN_ALLOWED_VALUE`, `MAX_ALLOWED_VALUE`).
const MIN_EXP: i32 = -142;
const MAX_EXP: i32 = 201;

/// The power of two that brings every non-zero |coordinate| into
/// `[2^MIN_EXP, 2^(MAX_EXP-1)]`, if one does.
fn scale_exponent(points: &[(Point, VertexTag)]) -> Option<i32> {
    let mut lo = i32::MAX;
    let mut hi = i32::MIN;
    for (p, _) in points {
        for v in [p.x, p.y] {
            if v != 0.0 {
                // floor(log2 |v|), exact from the bits for normal and subnormal numbers.
                let e = exponent(v);
                lo = lo.min(e);
                hi = hi.max(e);
            }
        }
    }
    if lo == i32::MAX {
        return Some(0);
    }
    if lo >= MIN_EXP && hi < MAX_EXP - 1 {
        return Some(0);
    }
    let k = if lo < MIN_EXP {
        MIN_EXP - lo
    } else {
        (MAX_EXP - 2) - hi
    };
    (lo + k >= MIN_EXP && hi + k < MAX_EXP - 1).then_some(k)
}

fn exponent(v: f64) -> i32 {
    let bits = v.abs().to_bits();
    let biased = i32::try_from(bits >> 52).expect("internal: 11-bit exponent");
    if biased == 0 {
        // Subnormal: value = mantissa * 2^-1074.
        let m = bits & ((1 << 52) - 1);
        let lz = i32::try_from(m.leading_zeros()).expect("internal: small count");
        (63 - lz) - 1074
    } else {
        biased - 1023
    }
}

fn scaled(p: Point, k: i32) -> Point2<f64> {
    // Multiplying by a power of two in the normal range is exact; do it in
    // two steps so the factor itself never over- or underflows.
    let h1 = k / 2;
    let h2 = k - h1;
    let f1 = 2f64.powi(h1);
    let f2 = 2f64.powi(h2);
    Point2::new(p.x * f1 * f2, p.y * f1 * f2)
}

/// Validate the input and triangulate all its vertices with the box corners.
pub(super) fn seed(input: &BspInput, bbox: Rect) -> Result<Seed> {
    let finite = |p: Point| p.x.is_finite() && p.y.is_finite();
    if !(bbox.x0.is_finite() && bbox.x1.is_finite() && bbox.y0.is_finite() && bbox.y1.is_finite())
        || bbox.x0 >= bbox.x1
        || bbox.y0 >= bbox.y1
    {
        return Err(Error::InvalidParams(format!(
            "bsp: box {bbox:?} is empty or not finite"
        )));
    }
    let mut points: Vec<(Point, VertexTag)> = Vec::new();
    let mut index: HashMap<(u64, u64), usize> = HashMap::new();
    let mut add = |p: Point, tag: VertexTag| -> Result<()> {
        if !finite(p) {
            return Err(Error::BadCoordinate(format!("bsp: non-finite point {p:?}")));
        }
        if p.x < bbox.x0 || p.x > bbox.x1 || p.y < bbox.y0 || p.y > bbox.y1 {
            return Err(Error::BadCoordinate(format!(
                "bsp: point {p:?} outside the box {bbox:?}"
            )));
        }
        let p = Point::new(p.x + 0.0, p.y + 0.0);
        match index.get(&key(p)) {
            Some(&i) => points[i].1 = points[i].1.union(tag),
            None => {
                index.insert(key(p), points.len());
                points.push((p, tag));
            }
        }
        Ok(())
    };
    let corner = VertexTag {
        box_corner: true,
        ..VertexTag::default()
    };
    for p in [
        Point::new(bbox.x0, bbox.y0),
        Point::new(bbox.x1, bbox.y0),
        Point::new(bbox.x1, bbox.y1),
        Point::new(bbox.x0, bbox.y1),
    ] {
        add(p, corner)?;
    }
    let point_tag = VertexTag {
        feature_point: true,
        ..VertexTag::default()
    };
    for &p in &input.points {
        add(p, point_tag)?;
    }
    let end_tag = VertexTag {
        section_endpoint: true,
        ..VertexTag::default()
    };
    for &p in &input.section_endpoints {
        add(p, end_tag)?;
    }
    let seg_tag = VertexTag {
        segment_endpoint: true,
        ..VertexTag::default()
    };
    for s in &input.segments {
        add(s.a, seg_tag)?;
        add(s.b, seg_tag)?;
    }
    let k = scale_exponent(&points).ok_or_else(|| {
        Error::BadCoordinate(
            "bsp: coordinates span more than 2^340; no scaling fits the exact Delaunay range"
                .into(),
        )
    })?;
    let spade_points: Vec<Point2<f64>> = points.iter().map(|(p, _)| scaled(*p, k)).collect();
    let back: HashMap<(u64, u64), u32> = spade_points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let i = u32::try_from(i).expect("internal: fewer than 2^32 seed points");
            (key(Point::new(p.x, p.y)), i)
        })
        .collect();
    let tri: DelaunayTriangulation<Point2<f64>> = Triangulation::bulk_load(spade_points)
        .map_err(|e| Error::BadCoordinate(format!("bsp: Delaunay rejected a coordinate: {e:?}")))?;
    let triangles = tri
        .inner_faces()
        .map(|f| {
            f.vertices().map(|v| {
                let p = v.position();
                *back
                    .get(&key(Point::new(p.x, p.y)))
                    .expect("internal: spade vertex is an input point")
            })
        })
        .collect();
    Ok(Seed {
        points,
        triangles,
        scale_exp: k,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponents() {
        assert_eq!(exponent(1.0), 0);
        assert_eq!(exponent(3.0), 1);
        assert_eq!(exponent(0.5), -1);
        assert_eq!(exponent(f64::from_bits(1)), -1074);
        let t = VertexTag::default();
        let pts = |v: f64| vec![(Point::new(v, 0.0), t)];
        assert_eq!(scale_exponent(&pts(1e9)), Some(0));
        assert_eq!(scale_exponent(&pts(1e-300)).map(|k| k > 0), Some(true));
        assert_eq!(scale_exponent(&[(Point::new(1e-300, 1e300), t)]), None);
    }
}
