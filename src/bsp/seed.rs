//! The seed: every input vertex and the box corners, triangulated by spade
//! (Delaunay), with the segments that cross many of its edges as constraints
//! (constrained Delaunay).
//!
//! A segment that is a chain of seed edges meets no seed triangle's interior,
//! so the cut has nothing to do for it. With a plain Delaunay seed every long
//! segment of a hatch crossed a row of thin triangles and the supporting line
//! cut each of them into cells the optimizer then had to collapse; those
//! segments are constraints now, unless spade refuses them (they cross a
//! constraint already in: crossings the feature stage left to the exact
//! kernel), and then the exact BSP cuts them (on 1 000 parallel strokes the
//! constraints take the cells from 99 365 to 20 847, the end mesh from 86 k to
//! 27 k triangles and 24.2 s to 4.5 s).
//! A panic inside spade falls back to the plain Delaunay triangulation, which
//! the cut makes conform all the same.

use super::BspInput;
use crate::mesh::{VertexTag, is_sliver};
use crate::{Error, Result};
use kurbo::{Point, Rect};
use spade::{
    ConstrainedDelaunayTriangulation, DelaunayTriangulation, Intersection,
    LineIntersectionIterator, Point2, Triangulation,
};
use std::collections::HashMap;

/// The seed triangulation, in the caller's (unscaled) coordinates.
pub(super) struct Seed {
    /// Distinct points with their tags.
    pub(super) points: Vec<(Point, VertexTag)>,
    /// Counter-clockwise triangles, as indices into `points`.
    pub(super) triangles: Vec<[u32; 3]>,
    /// The coordinates were multiplied by 2^scale_exp for spade.
    pub(super) scale_exp: i32,
    /// Distinct segments offered to spade as constraint edges (those that
    /// cross more than [`CONSTRAIN_FROM`] edges of the plain triangulation).
    pub(super) constraints: usize,
    /// Of those, the ones refused because they cross a constraint already in
    /// (all of them when the constrained triangulation fell back).
    pub(super) refused: usize,
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
    for &p in &input.steiner {
        add(p, VertexTag::default())?;
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
    let to_index = |p: Point2<f64>| -> u32 {
        *back
            .get(&key(Point::new(p.x, p.y)))
            .expect("internal: spade vertex is an input point")
    };
    // Each segment once, as a pair of seed indices (zero-length ones add nothing).
    let at = |p: Point| index[&key(Point::new(p.x + 0.0, p.y + 0.0))];
    let mut edges: Vec<[usize; 2]> = input
        .segments
        .iter()
        .map(|s| (at(s.a), at(s.b)))
        .filter(|(a, b)| a != b)
        .map(|(a, b)| [a.min(b), a.max(b)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let tri: DelaunayTriangulation<Point2<f64>> = Triangulation::bulk_load(spade_points.clone())
        .map_err(|e| Error::BadCoordinate(format!("bsp: Delaunay rejected a coordinate: {e:?}")))?;
    let mut handle = vec![None; points.len()];
    for v in tri.vertices() {
        handle[to_index(v.position()) as usize] = Some(v.fix());
    }
    // The segments that cross many of the plain triangulation's edges.
    let long: Vec<[usize; 2]> = edges
        .into_iter()
        .filter(|&[a, b]| {
            let (Some(a), Some(b)) = (handle[a], handle[b]) else {
                return false;
            };
            LineIntersectionIterator::new_from_handles(&tri, a, b)
                .filter(|x| matches!(x, Intersection::EdgeIntersection(_)))
                .take(CONSTRAIN_FROM + 1)
                .count()
                > CONSTRAIN_FROM
        })
        .collect();
    let constraints = long.len();
    let plain = |tri: DelaunayTriangulation<Point2<f64>>| -> Vec<[u32; 3]> {
        tri.inner_faces()
            .map(|f| f.vertices().map(|v| to_index(v.position())))
            .collect()
    };
    let (triangles, refused) = if long.is_empty() {
        (plain(tri), 0)
    } else {
        match constrained(&spade_points, &long, &to_index) {
            Some(built) => built,
            None => {
                tracing::debug!("bsp: the constrained seed failed; plain Delaunay instead");
                (plain(tri), constraints)
            }
        }
    };
    Ok(Seed {
        points,
        triangles,
        scale_exp: k,
        constraints,
        refused,
    })
}

/// A seed triangle this thin (`|2·area| ≤ THIN_REL · h²`, h² the sum of its
/// box's squared extents) is one rounding cannot be trusted with: the
/// snapping of `--stop-after bsp` refuses it (pipeline/snap.rs, the same
/// tolerance), and the plain Delaunay seed never makes it. The constrained
/// one does when an input vertex lies within rounding of a constraint's
/// line: such constraints are refused (and cut instead).
const THIN_REL: f64 = 1e-10;

/// A segment that crosses more edges than this of the plain Delaunay
/// triangulation is offered as a constraint; the exact BSP cuts the others.
/// Constraining every segment makes the meshes of ordinary drawings no
/// smaller but their worst angles worse: a constraint edge leaves the
/// optimizer a long feature edge to split where the cut left vertices to move.
/// A hatch's lines cross hundreds of edges, ordinary outlines few (the
/// measurements in `docs/tuning.md`).
const CONSTRAIN_FROM: usize = 32;

/// Rebuilds after refusing the constraints of thin triangles, at most.
const THIN_REBUILDS: usize = 3;

fn thin(p: [Point2<f64>; 3]) -> bool {
    is_sliver(p.map(|q| Point::new(q.x, q.y)), THIN_REL)
}

/// The constrained Delaunay triangulation of `points` with `edges` (pairs of
/// indices, distinct, sorted) as constraints where spade can put them: its
/// triangles and the number of constraints refused (crossing one already in,
/// or making a thin triangle). `None` when spade panics or errs, or thin
/// triangles remain after [`THIN_REBUILDS`].
fn constrained(
    points: &[Point2<f64>],
    edges: &[[usize; 2]],
    to_index: &dyn Fn(Point2<f64>) -> u32,
) -> Option<(Vec<[u32; 3]>, usize)> {
    let mut refused_thin: Vec<[usize; 2]> = Vec::new();
    for _ in 0..=THIN_REBUILDS {
        let offered: Vec<[usize; 2]> = edges
            .iter()
            .filter(|e| refused_thin.binary_search(e).is_err())
            .copied()
            .collect();
        let mut crossing = 0usize;
        // spade's bulk loader reports crossing constraints rather than
        // panicking on them; a panic inside it on some degenerate input must
        // still not take the run down (unwind safe: only the triangulation
        // under construction is lost).
        let built = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(
                points.to_vec(),
                offered,
                |_| crossing += 1,
            )
        }));
        let cdt = match built {
            Ok(Ok(cdt)) => cdt,
            Ok(Err(_)) | Err(_) => return None,
        };
        let mut more: Vec<[usize; 2]> = Vec::new();
        for f in cdt.inner_faces() {
            if !thin(f.vertices().map(|v| v.position())) {
                continue;
            }
            for e in f.adjacent_edges() {
                if e.is_constraint_edge() {
                    let [a, b] = e.vertices().map(|v| to_index(v.position()) as usize);
                    more.push([a.min(b), a.max(b)]);
                }
            }
        }
        if more.is_empty() {
            let triangles = cdt
                .inner_faces()
                .map(|f| f.vertices().map(|v| to_index(v.position())))
                .collect();
            return Some((triangles, crossing + refused_thin.len()));
        }
        // A constraint split at a vertex on it is not one of `edges`: only the
        // plain seed is left then.
        if more.iter().any(|e| edges.binary_search(e).is_err()) {
            return None;
        }
        refused_thin.extend(more);
        refused_thin.sort_unstable();
        refused_thin.dedup();
    }
    None
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
