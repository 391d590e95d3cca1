//! μ-separation and secondary simplification (thesis §4.3.1 Definition 4.1, §4.4 "Primary
//! and secondary feature tagging", "Secondary feature simplification").
//!
//! The test runs on each section's control polygon, whose convex hull contains both the
//! curve piece and its chord, so it is conservative for the curve and for the linear mesh:
//! an eligible section stays primary only if
//! - the hull of every section it shares no end point with, and every isolated point, is at
//!   least μ away from its hull (this catches crossings, near-parallel curves, close end
//!   points and tangencies, also between parts of the same curve);
//! - for every section it shares an end point `q` with (a corner, or a crossing where both
//!   curves were split), the two chords meet at `q` at an angle θ of at least 4α (so the
//!   two curve pieces, each within 2α of its chord, cannot cross), they do not share both
//!   end points, and the part of either chord farther than 1.01·μ / sin θ from `q` stays μ
//!   away from the other chord (nearer to `q` than μ / sin θ two straight branches at angle
//!   θ are closer than μ whatever they do: that stretch is the corner itself).
//!
//! Offending sections are demoted to secondary (conservatively: both of a pair). Candidate
//! pairs come from a uniform grid over the hulls' boxes.
//!
//! The simplification then moves secondary polyline vertices closer than μ to their
//! barycentre (greedy clusters around a seed; vertices that are end points of primary
//! sections stay put), and re-checks the primary sections against the moved segments,
//! demoting any that a moved segment came too close to.

use super::grid::Grid;
use super::resample::polygon_length;
use super::{FeaturePoint, SecondaryPolyline, Section};
use crate::budget::Deadline;
use crate::mesh::{angle_between, point_segment_distance, segment_distance};
use crate::svg::{Drawing, ShapeKind};
use kurbo::{CubicBez, Line, Point, Rect};
use rustc_hash::FxHashSet;
use std::collections::HashSet;

/// Chord parts within this factor of μ of a shared end point are exempt (see module doc).
const CORNER_RADIUS: f64 = 1.01;

fn key(p: Point) -> (u64, u64) {
    (p.x.to_bits(), p.y.to_bits())
}

fn ctrl_points(c: &CubicBez) -> [Point; 4] {
    [c.p0, c.p1, c.p2, c.p3]
}

fn ctrl_box(c: &CubicBez) -> Rect {
    let ps = ctrl_points(c);
    ps[1..]
        .iter()
        .fold(Rect::from_points(ps[0], ps[0]), |r, p| r.union_pt(*p))
}

/// Whether `p` is in the triangle `a b c` (a control-hull proximity test of the
/// μ-separation, like [`segment_distance`] a measurement with float products: a
/// wrong answer within rounding of the hull's boundary changes nothing the separation
/// guarantees, and the exact predicate made this hot loop several times slower).
fn in_triangle(p: Point, a: Point, b: Point, c: Point) -> bool {
    let side = |p: Point, q: Point, r: Point| (q - p).cross(r - p);
    let area = side(a, b, c);
    if area == 0.0 {
        return false;
    }
    let s = area.signum();
    s * side(a, b, p) >= 0.0 && s * side(b, c, p) >= 0.0 && s * side(c, a, p) >= 0.0
}

fn in_hull(p: Point, q: &[Point; 4]) -> bool {
    in_triangle(p, q[0], q[1], q[2])
        || in_triangle(p, q[0], q[1], q[3])
        || in_triangle(p, q[0], q[2], q[3])
        || in_triangle(p, q[1], q[2], q[3])
}

const PAIRS: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

/// Distance between the convex hulls of two control polygons (0 if they overlap).
pub(super) fn hull_distance(a: &[Point; 4], b: &[Point; 4]) -> f64 {
    if a.iter().any(|p| in_hull(*p, b)) || b.iter().any(|p| in_hull(*p, a)) {
        return 0.0;
    }
    let mut d = f64::INFINITY;
    for (i, j) in PAIRS {
        for (k, l) in PAIRS {
            d = d.min(segment_distance(
                Line::new(a[i], a[j]),
                Line::new(b[k], b[l]),
            ));
        }
    }
    d
}

/// Distance from a point to the convex hull of a control polygon.
fn point_hull_distance(p: Point, b: &[Point; 4]) -> f64 {
    if in_hull(p, b) {
        return 0.0;
    }
    PAIRS
        .iter()
        .map(|&(k, l)| point_segment_distance(p, Line::new(b[k], b[l])))
        .fold(f64::INFINITY, f64::min)
}

/// The end point two control polygons share (bit for bit), if any.
fn shared_end(a: &CubicBez, b: &CubicBez) -> Option<Point> {
    [a.p0, a.p3].into_iter().find(|p| *p == b.p0 || *p == b.p3)
}

/// The chord of `c` oriented from its end `q`.
fn chord_from(c: &CubicBez, q: Point) -> Line {
    if c.p0 == q {
        Line::new(c.p0, c.p3)
    } else {
        Line::new(c.p3, c.p0)
    }
}

/// The part of `l` (which starts at the shared point) farther than `r` from its start.
fn trimmed(l: Line, r: f64) -> Option<Line> {
    let len = l.length();
    (len > r).then(|| Line::new(l.p0.lerp(l.p1, r / len), l.p1))
}

/// Whether two sections that may share an end point violate μ-separation (see the
/// module doc). `alpha` is the turning bound in radians.
pub(super) fn violates(a: &CubicBez, b: &CubicBez, mu: f64, alpha: f64) -> bool {
    let Some(q) = shared_end(a, b) else {
        // Boxes farther apart than μ: hulls are too.
        let (ra, rb) = (ctrl_box(a), ctrl_box(b));
        let gap_x = (rb.x0 - ra.x1).max(ra.x0 - rb.x1);
        let gap_y = (rb.y0 - ra.y1).max(ra.y0 - rb.y1);
        if gap_x >= mu || gap_y >= mu {
            return false;
        }
        return hull_distance(&ctrl_points(a), &ctrl_points(b)) < mu;
    };
    let (ca, cb) = (chord_from(a, q), chord_from(b, q));
    if ca.p1 == cb.p1 {
        return true;
    }
    let (u, v) = (ca.p1 - q, cb.p1 - q);
    let angle = angle_between(u, v);
    if angle < 4.0 * alpha {
        return true;
    }
    // Near q the two chords are closer than μ for a length μ / sin(angle) (at
    // most μ / sin(4α)): that part belongs to the corner.
    let r = CORNER_RADIUS * mu / angle.sin().max((4.0 * alpha).min(1.0).sin());
    trimmed(ca, r).is_some_and(|t| segment_distance(t, cb) < mu)
        || trimmed(cb, r).is_some_and(|t| segment_distance(t, ca) < mu)
}

fn grid_for(boxes: impl Iterator<Item = Rect> + Clone, n: usize, mu: f64) -> Grid {
    let mut bounds: Option<Rect> = None;
    let mut extent = 0.0;
    for r in boxes.clone() {
        bounds = Some(bounds.map_or(r, |b| b.union(r)));
        extent += r.width().max(r.height());
    }
    let bounds = bounds.unwrap_or(Rect::ZERO).inflate(mu, mu);
    let cell = (extent / n.max(1) as f64).max(mu);
    let mut g = Grid::new(bounds, cell, n);
    for (i, r) in boxes.enumerate() {
        g.insert(u32::try_from(i).expect("internal: item count fits u32"), r);
    }
    g
}

/// Merge isolated points closer than `mu` to their barycentre (greedy clusters).
pub(super) fn merge_points(points: Vec<FeaturePoint>, mu: f64) -> Vec<FeaturePoint> {
    let pos: Vec<Point> = points.iter().map(|p| p.pos).collect();
    let moved = cluster(&pos, &vec![false; pos.len()], mu);
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for (p, m) in points.iter().zip(moved.positions) {
        if seen.insert(key(m)) {
            out.push(FeaturePoint {
                pos: m,
                source: p.source,
            });
        }
    }
    out
}

/// Decide, for every section, whether it is primary: eligible, and no other
/// section or feature point violates its μ-separation. Stops early once
/// `deadline` has passed (the answer is then incomplete: the caller checks the
/// deadline and discards it).
///
/// A section's answer reads the other sections' geometry only (never their
/// answers), so runs of sections are decided in parallel, each run with its
/// own hint.
pub(super) fn separate(
    sections: &[Section],
    points: &[FeaturePoint],
    mu: f64,
    alpha: f64,
    deadline: &Deadline,
) -> Vec<bool> {
    use rayon::prelude::*;
    let n = sections.len();
    let boxes = sections
        .iter()
        .map(|s| ctrl_box(&s.ctrl))
        .chain(points.iter().map(|p| Rect::from_points(p.pos, p.pos)));
    let grid = grid_for(boxes, n + points.len(), mu);
    let mut primary: Vec<bool> = sections.iter().map(|s| s.eligible).collect();
    primary
        .par_chunks_mut(SEPARATE_RUN)
        .enumerate()
        .for_each(|(run, flags)| {
            separate_run(
                sections,
                points,
                &grid,
                (mu, alpha),
                run * SEPARATE_RUN,
                flags,
                deadline,
            );
        });
    primary
}

/// Sections decided in one run of [`separate`] (a run shares a hint).
const SEPARATE_RUN: usize = 256;

/// [`separate`] for the sections `from..from + primary.len()`, whose flags
/// (eligibility on entry) are `primary`.
fn separate_run(
    sections: &[Section],
    points: &[FeaturePoint],
    grid: &Grid,
    (mu, alpha): (f64, f64),
    from: usize,
    primary: &mut [bool],
    deadline: &Deadline,
) {
    let n = sections.len();
    // The section that made the previous one fail: its successor along its curve
    // (or itself) usually makes this one fail too, next to a parallel curve. Tried
    // first, it spares the grid search; any violating section is one the search
    // would report, so the answer is the same.
    let mut hint: Option<usize> = None;
    for (k, flag) in primary.iter_mut().enumerate() {
        let i = from + k;
        let s = &sections[i];
        if !s.eligible {
            continue;
        }
        if i % 64 == 0 && deadline.expired() {
            break;
        }
        let hinted = hint.is_some_and(|h| {
            [h + 1, h]
                .into_iter()
                .any(|j| j != i && j < n && violates(&s.ctrl, &sections[j].ctrl, mu, alpha))
        });
        if hinted {
            *flag = false;
            hint = hint.map(|h| h + 1);
            continue;
        }
        let hull = ctrl_points(&s.ctrl);
        // Boxes farther than μ apart cannot violate: the grid reports only boxes
        // that overlap this one grown by μ (and a hair, for the rounding of the
        // growth), and the first violation ends the search.
        let reach = mu * (1.0 + 1e-9);
        let mut culprit = None;
        let bad = grid.any(ctrl_box(&s.ctrl).inflate(reach, reach), |j| {
            let j = j as usize;
            let bad = if j == i {
                false
            } else if j < n {
                violates(&s.ctrl, &sections[j].ctrl, mu, alpha)
            } else {
                point_hull_distance(points[j - n].pos, &hull) < mu
            };
            if bad && j < n {
                culprit = Some(j);
            }
            bad
        });
        hint = culprit;
        if bad {
            *flag = false;
        }
    }
}

/// A periodic cell's sides are no features, but the mesh's boundary: a primary
/// section within `mu` of one would keep its exact curve beside a fixed side
/// vertex, and the cusp of background between them makes slivers whatever the
/// side's sampling. Demote every primary section whose control polygon comes
/// within `mu` of a side of `cell`, unless it ends on that side and leaves it
/// at an angle θ of at least 4α (a crossing), its controls farther than
/// 1.01·μ / sin θ from the end (the corner itself) staying `mu` away; as the
/// μ-separation treats a section beside a drawn rectangle. Returns how many.
pub(super) fn demote_near_sides(
    sections: &[Section],
    primary: &mut [bool],
    cell: Rect,
    mu: f64,
    alpha: f64,
) -> usize {
    let mut demoted = 0;
    for (s, flag) in sections.iter().zip(primary.iter_mut()) {
        if !*flag {
            continue;
        }
        let q = ctrl_points(&s.ctrl);
        // each side: (coordinate across, axis: 0 for x = const, 1 for y = const)
        let near = [(cell.x0, 0), (cell.x1, 0), (cell.y0, 1), (cell.y1, 1)]
            .into_iter()
            .any(|(side, axis)| {
                let across = |p: Point| if axis == 0 { p.x } else { p.y };
                let gap = |p: Point| (across(p) - side).abs();
                if q.iter().all(|p| gap(*p) >= mu) {
                    return false;
                }
                // an end on the side: the chord's angle with it decides
                let end = [q[0], q[3]].into_iter().find(|p| across(*p) == side);
                let Some(e) = end else { return true };
                let other = if e == q[0] { q[3] } else { q[0] };
                let chord = other - e;
                let len = chord.hypot();
                if len == 0.0 {
                    return true;
                }
                let sin = gap(other) / len;
                if sin < (4.0 * alpha).min(std::f64::consts::FRAC_PI_2).sin() {
                    return true;
                }
                let corner = CORNER_RADIUS * mu / sin;
                q.iter().any(|p| (*p - e).hypot() > corner && gap(*p) < mu)
            });
        if near {
            *flag = false;
            demoted += 1;
        }
    }
    demoted
}

/// Demote every primary section whose control polygon is shorter than `mu` and that
/// shares no end point with another primary section; returns how many.
pub(super) fn demote_short_isolated(sections: &[Section], primary: &mut [bool], mu: f64) -> usize {
    let mut ends: std::collections::HashMap<(u64, u64), usize> = std::collections::HashMap::new();
    for (s, _) in sections.iter().zip(primary.iter()).filter(|(_, p)| **p) {
        *ends.entry(key(s.ctrl.p0)).or_default() += 1;
        *ends.entry(key(s.ctrl.p3)).or_default() += 1;
    }
    let mut demoted = 0;
    for (s, p) in sections.iter().zip(primary.iter_mut()) {
        let lone = |q: Point| ends.get(&key(q)).copied().unwrap_or(0) <= 1;
        if *p && polygon_length(&s.ctrl) < mu && lone(s.ctrl.p0) && lone(s.ctrl.p3) {
            *p = false;
            demoted += 1;
        }
    }
    demoted
}

/// Result of greedy clustering.
struct Clusters {
    positions: Vec<Point>,
    moved: usize,
}

/// Greedy clusters of the non-`fixed` positions closer than `mu` to a seed; each cluster
/// moves to its barycentre. Equal positions always end in the same cluster.
fn cluster(pos: &[Point], fixed: &[bool], mu: f64) -> Clusters {
    let grid = grid_for(pos.iter().map(|p| Rect::from_points(*p, *p)), pos.len(), mu);
    let mut done = fixed.to_vec();
    let mut positions = pos.to_vec();
    let mut moved = 0;
    for i in 0..pos.len() {
        if done[i] {
            continue;
        }
        // (a hair beyond μ for the rounding of the box's growth)
        let reach = mu * (1.0 + 1e-9);
        let members: Vec<usize> = grid
            .query(Rect::from_points(pos[i], pos[i]).inflate(reach, reach))
            .into_iter()
            .map(|j| j as usize)
            .filter(|&j| !done[j] && pos[j].distance(pos[i]) < mu)
            .collect();
        let sum = members
            .iter()
            .fold(kurbo::Vec2::ZERO, |a, &j| a + pos[j].to_vec2());
        let c = (sum / members.len() as f64).to_point();
        let all_same = members.iter().all(|&j| pos[j] == pos[i]);
        for &j in &members {
            done[j] = true;
            if !all_same {
                positions[j] = c;
                moved += 1;
            }
        }
    }
    Clusters { positions, moved }
}

/// What the simplification produced.
pub(super) struct Simplified {
    pub(super) polylines: Vec<SecondaryPolyline>,
    pub(super) collapsed: usize,
    pub(super) demoted: usize,
    /// Secondary segments the merge dropped with their runs ([`super::merge`]).
    pub(super) merged: usize,
}

/// Build the secondary polylines (runs of consecutive secondary sections of one input
/// feature), collapse close vertices, re-check primary sections against the
/// segments when some moved (else against those of the sections `recut` after the
/// separation test, [`super::resample::recut_secondary`]), demoting offenders in
/// `primary`, and turn polylines that collapsed to one point into isolated points.
pub(super) fn simplify(
    sections: &[Section],
    primary: &mut [bool],
    drawing: &Drawing,
    points: &mut Vec<FeaturePoint>,
    (mu, alpha): (f64, f64),
    recut: &[bool],
    deadline: &Deadline,
) -> Simplified {
    // Runs of secondary sections.
    // A run's feature and sharers, and its points.
    type Run = ((u32, Option<u32>), Vec<Point>);
    let mut runs: Vec<Run> = Vec::new();
    // By segment of the runs, in order: whether its section was cut again.
    let mut seg_recut: Vec<bool> = Vec::new();
    let mut prev: Option<usize> = None;
    for (i, s) in sections.iter().enumerate() {
        if primary[i] {
            prev = None;
            continue;
        }
        let continues = prev.is_some_and(|p| {
            sections[p].feature == s.feature
                && sections[p].shared == s.shared
                && sections[p].ctrl.p3 == s.ctrl.p0
        });
        match runs.last_mut() {
            Some((_, pts)) if continues => pts.push(s.ctrl.p3),
            _ => runs.push(((s.feature, s.shared), vec![s.ctrl.p0, s.ctrl.p3])),
        }
        seg_recut.push(recut.get(i).copied().unwrap_or(false));
        prev = Some(i);
    }
    // Open runs within μ of other runs that stay go (before the collapse, which
    // would weld the lines of a hatch into one another).
    let run_points: Vec<Vec<Point>> = runs.iter().map(|(_, pts)| pts.clone()).collect();
    let others = sections
        .iter()
        .zip(primary.iter())
        .filter(|(_, p)| **p)
        .flat_map(|(s, _)| [s.ctrl.p0, s.ctrl.p3])
        .chain(points.iter().map(|p| p.pos));
    // A run separates no colours when its shape paints no area (a stroke's centre
    // line, an unfilled element) and no other outline runs along it.
    let colourless: Vec<bool> = runs
        .iter()
        .map(|((feature, shared), _)| {
            let shape = drawing.features[*feature as usize].source.shape.index();
            // (a drawing without shapes, as the tests build: coloured)
            drawing.shapes.get(shape).is_some_and(|shape| {
                shared.is_none() && !shape.filled && shape.paint.kind == ShapeKind::Element
            })
        })
        .collect();
    let merge = super::merge::merge_close(&run_points, &colourless, others, mu, deadline);
    if merge.dropped > 0 {
        // Split the runs where segments went, and their recut flags with them.
        let mut flags = seg_recut.into_iter();
        seg_recut = Vec::new();
        let mut kept_runs = Vec::with_capacity(runs.len());
        for ((id, pts), keep) in runs.into_iter().zip(&merge.keep) {
            let mut part: Vec<Point> = Vec::new();
            for (k, &stays) in keep.iter().enumerate() {
                let flag = flags.next().unwrap_or(false);
                if stays {
                    if part.is_empty() {
                        part.push(pts[k]);
                    }
                    part.push(pts[k + 1]);
                    seg_recut.push(flag);
                } else if !part.is_empty() {
                    kept_runs.push((id, std::mem::take(&mut part)));
                }
            }
            if !part.is_empty() {
                kept_runs.push((id, part));
            }
        }
        runs = kept_runs;
    }
    // Collapse free vertices.
    let fixed_keys: FxHashSet<(u64, u64)> = sections
        .iter()
        .zip(primary.iter())
        .filter(|(_, p)| **p)
        .flat_map(|(s, _)| [key(s.ctrl.p0), key(s.ctrl.p3)])
        .collect();
    let flat: Vec<Point> = runs
        .iter()
        .flat_map(|(_, pts)| pts.iter().copied())
        .collect();
    let fixed: Vec<bool> = flat.iter().map(|p| fixed_keys.contains(&key(*p))).collect();
    let clusters = cluster(&flat, &fixed, mu);
    let mut k = 0;
    for (_, pts) in &mut runs {
        for p in pts.iter_mut() {
            *p = clusters.positions[k];
            k += 1;
        }
    }
    // Re-check primary sections against the (possibly moved) secondary segments,
    // or, when none moved, against those cut again after the separation test.
    let mut segs: Vec<Line> = runs
        .iter()
        .flat_map(|(_, pts)| pts.windows(2).map(|w| Line::new(w[0], w[1])))
        .collect();
    if clusters.moved == 0 {
        let mut flags = seg_recut.iter();
        segs.retain(|_| flags.next().copied().unwrap_or(false));
    }
    let mut demoted = 0;
    if !segs.is_empty() {
        let boxes = segs.iter().map(|l| Rect::from_points(l.p0, l.p1));
        let grid = grid_for(boxes, segs.len(), mu);
        // Each primary section's test on its own, in parallel; the demotions
        // then in order.
        let reach = mu * (1.0 + 1e-9);
        let bad: Vec<bool> = {
            use rayon::prelude::*;
            sections
                .par_iter()
                .zip(primary.par_iter())
                .with_min_len(SEPARATE_RUN)
                .map(|(s, &p)| {
                    p && grid.any(ctrl_box(&s.ctrl).inflate(reach, reach), |j| {
                        let l = segs[j as usize];
                        let c = CubicBez::new(
                            l.p0,
                            l.p0.lerp(l.p1, 1.0 / 3.0),
                            l.p0.lerp(l.p1, 2.0 / 3.0),
                            l.p1,
                        );
                        violates(&s.ctrl, &c, mu, alpha)
                    })
                })
                .collect()
        };
        for (i, s) in sections.iter().enumerate() {
            if bad[i] {
                primary[i] = false;
                demoted += 1;
                runs.push(((s.feature, s.shared), vec![s.ctrl.p0, s.ctrl.p3]));
            }
        }
    }
    // Output: drop repeated vertices; single points become isolated points.
    let mut polylines = Vec::new();
    // The points so far, by value (+0.0 makes −0.0 and 0.0, equal points, one key).
    let point_key = |p: Point| key(Point::new(p.x + 0.0, p.y + 0.0));
    let mut known: FxHashSet<(u64, u64)> = points.iter().map(|p| point_key(p.pos)).collect();
    for ((feature, shared), mut pts) in runs {
        pts.dedup();
        let source = drawing.features[feature as usize].source;
        if pts.len() < 2 {
            if known.insert(point_key(pts[0])) {
                points.push(FeaturePoint {
                    pos: pts[0],
                    source,
                });
            }
        } else {
            polylines.push(SecondaryPolyline {
                points: pts,
                source,
                shared,
            });
        }
    }
    Simplified {
        polylines,
        collapsed: clusters.moved,
        demoted,
        merged: merge.dropped,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(a: (f64, f64), b: (f64, f64)) -> CubicBez {
        let (a, b) = (Point::from(a), Point::from(b));
        CubicBez::new(a, a.lerp(b, 1.0 / 3.0), a.lerp(b, 2.0 / 3.0), b)
    }

    #[test]
    fn only_short_primary_sections_without_primary_neighbours_are_demoted() {
        let section = |a: (f64, f64), b: (f64, f64)| {
            let (pa, pb) = (Point::from(a), Point::from(b));
            Section {
                feature: 0,
                shared: None,
                parent: super::super::Parent::Line(Line::new(pa, pb)),
                t0: 0.0,
                t1: 1.0,
                ctrl: seg(a, b),
                eligible: true,
            }
        };
        let sections = [
            // Short and alone between two secondary sections: demoted.
            section((0.0, 0.0), (5.0, 0.0)),
            section((5.0, 0.0), (5.05, 0.0)),
            section((5.05, 0.0), (9.0, 0.0)),
            // Short but continued by a primary section: kept.
            section((0.0, 2.0), (0.05, 2.0)),
            section((0.05, 2.0), (4.0, 2.0)),
            // Alone but not short: kept.
            section((0.0, 4.0), (0.5, 4.0)),
        ];
        let mut primary = [false, true, false, true, true, true];
        let n = demote_short_isolated(&sections, &mut primary, 0.1);
        assert_eq!(n, 1);
        assert_eq!(primary, [false, false, false, true, true, true]);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 24, failure_persistence: None, ..proptest::prelude::ProptestConfig::default()
        })]
        /// Runs decided in parallel, each with its own hint, give every
        /// section the answer of the definition: eligible, and no other
        /// section violating its separation. Random walks (consecutive
        /// sections share ends, so hints are taken and dropped) over more
        /// sections than a run holds.
        #[test]
        fn separating_in_parallel_runs_matches_the_definition(
            steps in proptest::collection::vec((-1.0..1.0f64, -1.0..1.0f64, proptest::bool::weighted(0.9), 0u8..20), 300..900),
        ) {
            let mut at = Point::ZERO;
            let sections: Vec<Section> = steps
                .iter()
                .map(|&(dx, dy, eligible, jump)| {
                    let from = if jump == 0 { Point::new(dx * 7.0, dy * 7.0) } else { at };
                    at = from + kurbo::Vec2::new(dx, dy);
                    Section {
                        feature: 0,
                        shared: None,
                        parent: super::super::Parent::Line(Line::new(from, at)),
                        t0: 0.0,
                        t1: 1.0,
                        ctrl: seg((from.x, from.y), (at.x, at.y)),
                        eligible,
                    }
                })
                .collect();
            let (mu, alpha) = (0.05, 10f64.to_radians());
            let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("pool");
            let got = pool.install(|| separate(&sections, &[], mu, alpha, &Deadline::after(None)));
            let want: Vec<bool> = (0..sections.len())
                .map(|i| {
                    sections[i].eligible
                        && !(0..sections.len())
                            .any(|j| j != i && violates(&sections[i].ctrl, &sections[j].ctrl, mu, alpha))
                })
                .collect();
            proptest::prop_assert_eq!(&got, &want);
            // Both answers occur.
            proptest::prop_assert!(want.iter().any(|&p| p) && want.iter().any(|&p| !p));
        }
    }

    #[test]
    fn hull_distance_of_parallel_segments() {
        let a = ctrl_points(&seg((0.0, 0.0), (10.0, 0.0)));
        let b = ctrl_points(&seg((2.0, 0.5), (8.0, 0.5)));
        assert!((hull_distance(&a, &b) - 0.5).abs() < 1e-12);
        let c = ctrl_points(&seg((5.0, -1.0), (5.0, 1.0)));
        assert_eq!(hull_distance(&a, &c), 0.0);
    }

    #[test]
    fn corners_right_angle_passes_sharp_fails_fold_fails() {
        let alpha = 10f64.to_radians();
        let a = seg((0.0, 0.0), (1.0, 0.0));
        assert!(!violates(&a, &seg((0.0, 0.0), (0.0, 1.0)), 0.01, alpha));
        assert!(!violates(&a, &seg((1.0, 0.0), (2.0, 0.0)), 0.01, alpha));
        // 30° corner: points of a beyond 1.01μ are within μ of b.
        let b = seg(
            (0.0, 0.0),
            (30f64.to_radians().cos(), 30f64.to_radians().sin()),
        );
        assert!(violates(&a, &b, 0.01, alpha));
        // Folding back on itself.
        assert!(violates(&a, &seg((0.0, 0.0), (0.5, 0.0)), 0.01, alpha));
        // Same chord twice.
        assert!(violates(&a, &seg((1.0, 0.0), (0.0, 0.0)), 0.01, alpha));
    }
}
