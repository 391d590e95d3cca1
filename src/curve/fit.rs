//! The constrained fit of a curved edge that its exact curve piece cannot
//! take (thesis §4.4.2 "Termination Criteria and Least Squares Fitting": the
//! nodes that best approximate the curve under a positive Jacobian), and the
//! distance of a Lagrange edge from its curve piece.

use super::build::{CurveOptions, CurveStats};
use super::shape::{Bend, face_edges, uncertified};
use crate::element::Order;
use crate::element::triangle::straight_inner;
use crate::mesh::{EdgeKey, FaceId, TriMesh};
use kurbo::{Point, Vec2};

/// Bisection steps of the largest certified blend toward the curve (the
/// blend then within 2^-30 of the largest).
const BLEND_BISECTIONS: usize = 30;
/// The pattern search's first step is at least this fraction of the edge
/// length `h`. Empirical (`docs/tuning.md`).
const FIT_FIRST_STEP_REL: f64 = 1e-3;
/// The pattern search stops once the nodes are within this fraction of `h`
/// of the curve (in the root of the summed squares).
const FIT_CONVERGED_REL: f64 = 1e-12;
/// A pattern-search node moves toward the curve by the step, or by its
/// distance to the curve when smaller, but by at least this fraction of the
/// step.
const FIT_MIN_MOVE: f64 = 0.5;
/// The pattern search's step shrinks by this factor after a round without
/// improvement.
const FIT_STEP_SHRINK: f64 = 0.5;
/// ... and stops below this fraction of `h`.
const FIT_LAST_STEP_REL: f64 = 1e-9;
/// A fit must bring the nodes closer to the curve than the straight edge by
/// more than this fraction (of the squared distance), else the edge stays
/// straight.
const FIT_MIN_GAIN: f64 = 1e-12;
/// Samples of a Lagrange edge in [`edge_distance`].
const SAMPLES: usize = 16;

/// How a failing curved edge ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Fit {
    /// Curved, with fitted nodes.
    Fitted,
    /// Straight: no certified curved position found.
    Straight,
}

/// Fit every curved edge of an uncertified face; straighten what cannot be fitted.
pub(super) fn fit_all(
    mesh: &TriMesh,
    opts: &CurveOptions,
    shape: &mut Bend,
    stats: &mut CurveStats,
) {
    let order = opts.order;
    let bad = uncertified(mesh, shape, order, &opts.certify);
    let mut fitted: Vec<FaceId> = Vec::new();
    let mut straight: Vec<FaceId> = Vec::new();
    let mut faces = Vec::new();
    for f in bad {
        if shape.certified(mesh, order, f, &opts.certify) {
            continue; // fixed by the fit of a neighbouring edge
        }
        for key in face_edges(mesh, f) {
            let Some(target) = shape.edges.get(&key).cloned() else {
                continue;
            };
            mesh.faces_on_edge(key.lo, key.hi, &mut faces);
            let out = fit_edge(mesh, opts, shape, key, &faces, &target);
            match out {
                Fit::Fitted => fitted.extend(&faces),
                Fit::Straight => straight.extend(&faces),
            }
        }
        if !shape.certified(mesh, order, f, &opts.certify) {
            // Last resort for a face whose edges failed together: all straight.
            for key in face_edges(mesh, f) {
                if shape.edges.remove(&key).is_some() {
                    mesh.faces_on_edge(key.lo, key.hi, &mut faces);
                    for &g in &faces {
                        shape.centre.remove(&g);
                        straight.push(g);
                    }
                }
            }
            shape.centre.remove(&f);
        }
    }
    fitted.sort_unstable();
    fitted.dedup();
    straight.sort_unstable();
    straight.dedup();
    fitted.retain(|f| straight.binary_search(f).is_err());
    stats.fitted_triangles = fitted.len();
    stats.straight_triangles = straight.len();
}

/// Constrained fit of the inner nodes of the curved edge `key` (shared by
/// `faces`) and of those faces' centres: minimise the distance of the inner
/// nodes to `target` subject to both faces being certified.
pub(super) fn fit_edge(
    mesh: &TriMesh,
    opts: &CurveOptions,
    shape: &mut Bend,
    key: EdgeKey,
    faces: &[FaceId],
    target: &[Point],
) -> Fit {
    let order = opts.order;
    let (a, b) = (mesh.position(key.lo), mesh.position(key.hi));
    let straight = straight_inner(a, b, order);
    let h = (b - a).hypot();
    let feasible = |shape: &Bend| -> Option<f64> {
        let mut margin = f64::INFINITY;
        for &f in faces {
            let c = shape.certificate(mesh, order, f, &opts.certify)?;
            if !c.is_certified() || c.ratio() < opts.fit_min_ratio {
                return None;
            }
            margin = margin.min(c.ratio());
        }
        Some(margin)
    };
    let dist2 =
        |q: &[Point]| -> f64 { q.iter().zip(target).map(|(p, t)| (*p - *t).hypot2()).sum() };
    let blend = |s: f64| -> Vec<Point> {
        straight
            .iter()
            .zip(target)
            .map(|(p, t)| p.lerp(*t, s))
            .collect()
    };
    for &f in faces {
        shape.centre.remove(&f);
    }
    // The largest certified blend toward the curve (0 = straight).
    shape.edges.insert(key, straight.clone());
    if feasible(shape).is_none() {
        shape.edges.remove(&key);
        return Fit::Straight;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..BLEND_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        shape.edges.insert(key, blend(mid));
        if feasible(shape).is_some() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let mut q = blend(lo);
    shape.edges.insert(key, q.clone());
    let mut margin = feasible(shape).expect("internal: the blend search keeps a certified state");
    let mut best = dist2(&q);
    // Pattern search: edge nodes toward the curve, centres toward more margin.
    let mut step = q
        .iter()
        .zip(target)
        .map(|(p, t)| (*p - *t).hypot())
        .fold(0.0, f64::max)
        .max(FIT_FIRST_STEP_REL * h);
    let dirs = [
        Vec2::new(1.0, 0.0),
        Vec2::new(-1.0, 0.0),
        Vec2::new(0.0, 1.0),
        Vec2::new(0.0, -1.0),
    ];
    for _ in 0..opts.fit_iterations {
        if best <= (FIT_CONVERGED_REL * h).powi(2) {
            break;
        }
        let mut improved = false;
        for i in 0..q.len() {
            let toward = target[i] - q[i];
            let mut cand_dirs = dirs.to_vec();
            if toward.hypot() > 0.0 {
                let u = toward.normalize();
                cand_dirs.insert(0, u);
                cand_dirs.push(Vec2::new(-u.y, u.x));
                cand_dirs.push(Vec2::new(u.y, -u.x));
            }
            for d in cand_dirs {
                let mut cand = q.clone();
                cand[i] += d * step.min(toward.hypot().max(step * FIT_MIN_MOVE));
                let dd = dist2(&cand);
                if dd >= best {
                    continue;
                }
                shape.edges.insert(key, cand.clone());
                if let Some(m) = feasible(shape) {
                    q = cand;
                    best = dd;
                    margin = m;
                    improved = true;
                    break;
                }
                shape.edges.insert(key, q.clone());
            }
        }
        if order == Order::Cubic {
            for &f in faces {
                for d in dirs {
                    let old = shape.centre.get(&f).copied();
                    let off = old.unwrap_or(Vec2::ZERO) + d * step;
                    shape.centre.insert(f, off);
                    match feasible(shape) {
                        Some(m) if m > margin => {
                            margin = m;
                            improved = true;
                        }
                        _ => match old {
                            Some(o) => {
                                shape.centre.insert(f, o);
                            }
                            None => {
                                shape.centre.remove(&f);
                            }
                        },
                    }
                }
            }
        }
        if !improved {
            step *= FIT_STEP_SHRINK;
            if step < FIT_LAST_STEP_REL * h {
                break;
            }
        }
    }
    shape.edges.insert(key, q.clone());
    if dist2(&q) >= dist2(&straight) * (1.0 - FIT_MIN_GAIN) {
        // Nothing better than straight: the plain straight edge.
        shape.edges.remove(&key);
        for &f in faces {
            shape.centre.remove(&f);
        }
        return Fit::Straight;
    }
    Fit::Fitted
}

/// Largest distance, over samples of the Lagrange edge `a, inner.., b`, from the
/// curve piece, given as the distance to it (`Parent::distance`: a cubic's or a
/// conic's nearest point, to the caller's accuracy).
pub(super) fn edge_distance(
    a: Point,
    b: Point,
    inner: &[Point],
    distance: impl Fn(Point) -> f64,
) -> f64 {
    (0..=SAMPLES)
        .map(|i| distance(lagrange_edge(a, b, inner, i as f64 / SAMPLES as f64)))
        .fold(0.0, f64::max)
}

/// The point at `s ∈ [0, 1]` of the Lagrange curve through `a`, `inner` (equally
/// spaced in the parameter) and `b`.
pub(super) fn lagrange_edge(a: Point, b: Point, inner: &[Point], s: f64) -> Point {
    let mut pts = Vec::with_capacity(inner.len() + 2);
    pts.push(a);
    pts.extend_from_slice(inner);
    pts.push(b);
    let n = pts.len() - 1;
    let nodes: Vec<f64> = (0..=n).map(|i| i as f64 / n as f64).collect();
    let mut out = Vec2::ZERO;
    for (i, p) in pts.iter().enumerate() {
        let mut w = 1.0;
        for (j, &sj) in nodes.iter().enumerate() {
            if j != i {
                w *= (s - sj) / (nodes[i] - sj);
            }
        }
        out += w * p.to_vec2();
    }
    out.to_point()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lagrange_edge_interpolates() {
        let (a, b) = (Point::new(0.0, 0.0), Point::new(3.0, 0.0));
        let inner = [Point::new(1.0, 1.0), Point::new(2.0, 1.0)];
        assert!((lagrange_edge(a, b, &inner, 1.0 / 3.0) - inner[0]).hypot() < 1e-15);
        assert!((lagrange_edge(a, b, &inner, 1.0) - b).hypot() < 1e-15);
        assert!((lagrange_edge(a, b, &[], 0.5) - Point::new(1.5, 0.0)).hypot() < 1e-15);
    }
}
