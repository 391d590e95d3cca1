//! An independent checker of the FeatureSet invariants (docs/design.md "features"), shared by the
//! unit tests of `src/features` and `src/pipeline/tests/features_devset.rs`. It shares no code with the
//! module under test: its own Bézier evaluation, distances and dense sampling. The including
//! module provides `FeatureSet`, `Parent`, `Point`, `Vec2` and `Rect` in scope.
#![allow(dead_code, reason = "each includer uses a different part")]

use super::*;

/// The parent curve, evaluated by the checker's own formulas.
enum Curve {
    /// Bézier control points (a line as a degree-elevated cubic).
    Bezier([Point; 4]),
    /// A rational quadratic: controls and middle weight.
    Rational([Point; 3], f64),
}

fn curve_of(p: &Parent) -> Curve {
    match *p {
        Parent::Cubic(c) => Curve::Bezier([c.p0, c.p1, c.p2, c.p3]),
        Parent::Line(l) => Curve::Bezier([
            l.p0,
            l.p0.lerp(l.p1, 1.0 / 3.0),
            l.p0.lerp(l.p1, 2.0 / 3.0),
            l.p1,
        ]),
        Parent::Conic(c) => Curve::Rational([c.p0, c.p1, c.p2], c.w),
    }
}

impl Curve {
    /// Point, first and second derivative at `t`.
    fn jet(&self, t: f64) -> (Point, Vec2, Vec2) {
        match self {
            Curve::Bezier(c) => (bez(c, t), bez_d(c, t), bez_dd(c, t)),
            Curve::Rational(c, w) => {
                // x = n / d with n, d quadratic: x' = (n' − x d') / d,
                // x'' = (n'' − 2 x' d' − x d'') / d.
                let s = 1.0 - t;
                let h = [
                    (c[0].to_vec2(), 1.0),
                    (c[1].to_vec2() * *w, *w),
                    (c[2].to_vec2(), 1.0),
                ];
                let b = [s * s, 2.0 * s * t, t * t];
                let db = [-2.0 * s, 2.0 * (s - t), 2.0 * t];
                let ddb = [2.0, -4.0, 2.0];
                let mix = |k: &[f64; 3]| {
                    (0..3).fold((Vec2::ZERO, 0.0), |(v, d), i| {
                        (v + h[i].0 * k[i], d + h[i].1 * k[i])
                    })
                };
                let ((n, d), (dn, dd), (ddn, ddd)) = (mix(&b), mix(&db), mix(&ddb));
                let x = n / d;
                let dx = (dn - x * dd) / d;
                let ddx = (ddn - dx * (2.0 * dd) - x * ddd) / d;
                (x.to_point(), dx, ddx)
            }
        }
    }

    fn point(&self, t: f64) -> Point {
        self.jet(t).0
    }
}

/// Distance from `p` to the triangle `a b c` (0 inside).
fn pt_triangle(p: Point, a: Point, b: Point, c: Point) -> f64 {
    let area = cross3(a, b, c);
    let sides = [cross3(a, b, p), cross3(b, c, p), cross3(c, a, p)];
    if area != 0.0 && sides.iter().all(|x| x * area >= 0.0) {
        return 0.0;
    }
    pt_seg(p, a, b).min(pt_seg(p, b, c)).min(pt_seg(p, c, a))
}

/// Distance from `p` to the convex hull of four points (0 inside).
fn pt_hull(p: Point, q: &[Point; 4]) -> f64 {
    [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]
        .iter()
        .map(|&(i, j, k)| pt_triangle(p, q[i], q[j], q[k]))
        .fold(f64::INFINITY, f64::min)
}

pub(super) fn bez(c: &[Point; 4], t: f64) -> Point {
    let s = 1.0 - t;
    let w = [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t];
    let mut v = Vec2::ZERO;
    for (p, w) in c.iter().zip(w) {
        v += p.to_vec2() * w;
    }
    v.to_point()
}

pub(super) fn bez_d(c: &[Point; 4], t: f64) -> Vec2 {
    let s = 1.0 - t;
    ((c[1] - c[0]) * (s * s) + (c[2] - c[1]) * (2.0 * s * t) + (c[3] - c[2]) * (t * t)) * 3.0
}

pub(super) fn bez_dd(c: &[Point; 4], t: f64) -> Vec2 {
    let v = |p: Point| p.to_vec2();
    ((v(c[2]) - v(c[1]) * 2.0 + v(c[0])) * (1.0 - t) + (v(c[3]) - v(c[2]) * 2.0 + v(c[1])) * t)
        * 6.0
}

fn pt_seg(p: Point, a: Point, b: Point) -> f64 {
    let d = b - a;
    let l2 = d.hypot2();
    let s = if l2 == 0.0 {
        0.0
    } else {
        ((p - a).dot(d) / l2).clamp(0.0, 1.0)
    };
    p.distance(a + d * s)
}

fn cross3(a: Point, b: Point, c: Point) -> f64 {
    (b - a).cross(c - a)
}

fn seg_seg(a: Point, b: Point, c: Point, d: Point) -> f64 {
    let (o1, o2, o3, o4) = (
        cross3(a, b, c),
        cross3(a, b, d),
        cross3(c, d, a),
        cross3(c, d, b),
    );
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return 0.0;
    }
    pt_seg(a, c, d)
        .min(pt_seg(b, c, d))
        .min(pt_seg(c, a, b))
        .min(pt_seg(d, a, b))
}

const N: usize = 64;

/// Geometry of one item the checker compares: dense samples, its straight segment (the
/// chord or secondary segment), its end points.
struct Item {
    samples: Vec<Point>,
    a: Point,
    b: Point,
    bbox: Rect,
    primary: Option<usize>,
}

/// Every violated FeatureSet invariant, as text (empty when all hold).
pub(crate) fn check(fs: &FeatureSet) -> Vec<String> {
    let r = &fs.params;
    let mut bad = Vec::new();
    let mut items: Vec<Item> = Vec::new();
    let mut judged_seen = std::collections::HashSet::new();
    for (i, s) in fs.primary.iter().enumerate() {
        let pc = curve_of(&s.parent);
        let [t0, t1] = s.t;
        if t0.partial_cmp(&t1) != Some(std::cmp::Ordering::Less) {
            bad.push(format!("p{i}: empty interval {t0}..{t1}"));
        }
        let ts: Vec<f64> = (0..=N)
            .map(|k| t0 + (t1 - t0) * k as f64 / N as f64)
            .collect();
        let pts: Vec<Point> = ts.iter().map(|&t| pc.point(t)).collect();
        let own = [s.ctrl.p0, s.ctrl.p1, s.ctrl.p2, s.ctrl.p3];
        let scale = 1e-9 * (r.d + pts[0].to_vec2().hypot());
        match &pc {
            Curve::Bezier(_) => {
                for k in 0..=4 {
                    let u = k as f64 / 4.0;
                    let e = bez(&own, u).distance(pc.point(t0 + (t1 - t0) * u));
                    if e > scale {
                        bad.push(format!(
                            "p{i}: ctrl is not the parent restricted (off by {e})"
                        ));
                    }
                }
            }
            Curve::Rational(..) => {
                // A hull of the piece, with the piece's end points.
                let e = own[0]
                    .distance(pc.point(t0))
                    .max(own[3].distance(pc.point(t1)));
                if e > scale {
                    bad.push(format!("p{i}: ctrl ends are off the conic by {e}"));
                }
                let out = pts.iter().map(|p| pt_hull(*p, &own)).fold(0.0, f64::max);
                if out > scale {
                    bad.push(format!("p{i}: the conic leaves its ctrl hull by {out}"));
                }
            }
        }
        // Length.
        let len: f64 = pts.windows(2).map(|w| w[0].distance(w[1])).sum();
        if len > r.l * (1.0 + 1e-9) {
            bad.push(format!("p{i}: length {len} > l = {}", r.l));
        }
        // Not a sliver-maker: a primary section's control polygon is at least l_m long, so
        // its arc (turning less than α) is at least about that.
        if len < 0.5 * r.l_min {
            bad.push(format!("p{i}: length {len} < l_m / 2 = {}", 0.5 * r.l_min));
        }
        // Chord within μ, both ways.
        let (a, b) = (s.ctrl.p0, s.ctrl.p3);
        let dev = pts.iter().map(|p| pt_seg(*p, a, b)).fold(0.0, f64::max);
        let back = (0..=16)
            .map(|k| {
                let q = a.lerp(b, k as f64 / 16.0);
                pts.windows(2)
                    .map(|w| pt_seg(q, w[0], w[1]))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        if dev.max(back) > r.mu * (1.0 + 1e-9) {
            bad.push(format!(
                "p{i}: chord {} away from the curve > μ = {}",
                dev.max(back),
                r.mu
            ));
        }
        if !s.parent.is_line() {
            // Constant-sign curvature and turn < α.
            let dets: Vec<f64> = ts
                .iter()
                .map(|&t| {
                    let (_, d, dd) = pc.jet(t);
                    d.cross(dd)
                })
                .collect();
            let m = dets.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let tol = 1e-6 * m + 1e-300;
            if dets.iter().any(|v| *v > tol) && dets.iter().any(|v| *v < -tol) {
                bad.push(format!("p{i}: curvature changes sign"));
            }
            let tans: Vec<Vec2> = ts.iter().map(|&t| pc.jet(t).1).collect();
            if tans.iter().any(|v| v.hypot2() == 0.0) {
                bad.push(format!("p{i}: zero derivative"));
            }
            let turn: f64 = tans
                .windows(2)
                .map(|w| w[0].cross(w[1]).atan2(w[0].dot(w[1])).abs())
                .sum();
            if turn >= r.alpha {
                bad.push(format!("p{i}: turns {} ≥ α", turn.to_degrees()));
            }
            let kmax = ts
                .iter()
                .map(|&t| {
                    let (_, d, dd) = pc.jet(t);
                    d.cross(dd).abs() / d.hypot().powi(3)
                })
                .fold(0.0, f64::max);
            if kmax > 1.5 * 2.0 / r.l_min {
                bad.push(format!("p{i}: curvature {kmax} ≫ 2/l_m"));
            }
        }
        let bbox = pts
            .iter()
            .fold(Rect::from_points(a, a), |r, p| r.union_pt(*p));
        // The pieces cut from one judged section after the μ-separation are
        // compared as that section: consecutive, each starting where the one
        // before ends.
        let joins = i > 0 && fs.primary[i - 1].judged == s.judged;
        match items.last_mut() {
            Some(it) if joins => {
                if it.b != a {
                    bad.push(format!(
                        "p{i}: a piece of a judged section not joining the one before"
                    ));
                }
                it.samples.extend(pts);
                it.b = b;
                it.bbox = it.bbox.union(bbox);
            }
            _ => {
                if !judged_seen.insert(s.judged) {
                    bad.push(format!("p{i}: pieces of one judged section apart"));
                }
                items.push(Item {
                    samples: pts,
                    a,
                    b,
                    bbox,
                    primary: Some(i),
                });
            }
        }
    }
    for pl in &fs.secondary {
        if pl.points.len() < 2 {
            bad.push("secondary polyline with fewer than 2 points".into());
        }
        for w in pl.points.windows(2) {
            let samples = (0..=8).map(|k| w[0].lerp(w[1], k as f64 / 8.0)).collect();
            items.push(Item {
                samples,
                a: w[0],
                b: w[1],
                bbox: Rect::from_points(w[0], w[1]),
                primary: None,
            });
        }
    }
    for p in &fs.points {
        items.push(Item {
            samples: vec![p.pos],
            a: p.pos,
            b: p.pos,
            bbox: Rect::from_points(p.pos, p.pos),
            primary: None,
        });
    }
    // Pairs involving a primary section, by a sweep on x.
    let mut order: Vec<usize> = (0..items.len()).collect();
    order.sort_by(|&i, &j| items[i].bbox.x0.total_cmp(&items[j].bbox.x0));
    for (oi, &i) in order.iter().enumerate() {
        for &j in &order[oi + 1..] {
            if items[j].bbox.x0 > items[i].bbox.x1 + r.mu {
                break;
            }
            let (x, y) = (&items[i], &items[j]);
            if x.primary.is_none() && y.primary.is_none() {
                continue;
            }
            if x.bbox.y0 > y.bbox.y1 + r.mu || y.bbox.y0 > x.bbox.y1 + r.mu {
                continue;
            }
            let name = |it: &Item| {
                it.primary
                    .map_or("secondary/point".to_string(), |k| format!("p{k}"))
            };
            let shared = [x.a, x.b].iter().any(|p| *p == y.a || *p == y.b);
            if shared {
                // Adjacent: must not overlap (collinear, same direction from the shared point).
                let q = if x.a == y.a || x.a == y.b { x.a } else { x.b };
                let u = if x.a == q { x.b - q } else { x.a - q };
                let v = if y.a == q { y.b - q } else { y.a - q };
                let both = (x.a == y.a && x.b == y.b) || (x.a == y.b && x.b == y.a);
                if both || (u.cross(v).abs() <= 1e-12 * u.hypot() * v.hypot() && u.dot(v) > 0.0) {
                    bad.push(format!("{} overlaps adjacent {}", name(x), name(y)));
                }
                continue;
            }
            // Curve samples against the other's sample polyline (exact for straight items;
            // a curve's polyline is within 1e-3·μ of it here), and chord against chord.
            let to_poly = |p: Point, it: &Item| {
                if it.samples.len() == 1 {
                    p.distance(it.samples[0])
                } else {
                    it.samples
                        .windows(2)
                        .map(|w| pt_seg(p, w[0], w[1]))
                        .fold(f64::INFINITY, f64::min)
                }
            };
            let mut dmin = seg_seg(x.a, x.b, y.a, y.b);
            for p in &x.samples {
                dmin = dmin.min(to_poly(*p, y));
            }
            for p in &y.samples {
                dmin = dmin.min(to_poly(*p, x));
            }
            if dmin < r.mu * (1.0 - 1e-3) {
                bad.push(format!("{} is {dmin} < μ from {}", name(x), name(y)));
            }
        }
    }
    bad
}
