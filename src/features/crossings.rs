//! Transversal crossings of curve pieces (thesis §4.3.1: curves are split where
//! they intersect, so a crossing is a shared end point of the sections around it,
//! not a place where two sections come closer than μ).
//!
//! Two pieces that cross at an angle of at least 4α, away (farther than μ) from
//! their ends, are both split at the crossing, and the sections that end there
//! all get the same end point (the mean of the two curves' points, which agree
//! to rounding), so the μ-separation test sees a shared corner and keeps them
//! primary when they are otherwise separated. Shallower crossings, tangencies
//! and overlaps are left alone: the separation test demotes them where they lie within μ.
//!
//! Candidates come from a grid over the pieces' boxes: a curve's control box,
//! a straight piece's run of boxes about one grid cell long each (the
//! boxes of long parallel lines of a hatch all overlap one another, their runs
//! of small boxes only their neighbours'), so the pairs tried grow with the
//! pairs that come near each other, not with all pairs. Two straight pieces
//! whose directions differ by less than the smallest crossing angle any pair
//! is split at are never tried (their crossing would be refused): a hatch's
//! parallel lines are not paired at all. Each candidate pair
//! is flattened into a few chords (a straight piece is its one chord), chord
//! crossings seed a Newton solve of `c1(s) = c2(t)`, and only converged
//! solutions inside both pieces count. Budgets bound the work per piece and in
//! total.

use super::Parent;
use super::grid::Grid;
use crate::budget::Deadline;
use crate::params::Resolved;
use kurbo::{Point, Rect, Vec2};
use rayon::prelude::*;
use std::collections::HashMap;

/// Chords per piece for the search.
const CHORDS: usize = 16;
/// At most this many crossings split one piece.
const MAX_PER_PIECE: usize = 32;
/// Pieces searched together (in parallel) before their crossings are
/// filtered: the block starts at the smallest and doubles while the blocks
/// find few crossings.
const BLOCK_MIN: usize = 64;
const BLOCK_MAX: usize = 1 << 16;
/// Crossings a block's list is kept near (64 bytes each).
const BLOCK_FOUND: usize = 1 << 18;
/// Newton iterations per seed.
const NEWTON: usize = 30;
/// Smallest crossing angle (degrees) split between two trimmable pieces.
const TRIM_MIN_DEG: f64 = 1.0;
/// Between two trimmable pieces, the distance (fraction of μ) from the ends and
/// between crossings below which a crossing is not split.
const TRIM_NEAR: f64 = 0.01;

/// A curve piece: its parent and parameter interval.
#[derive(Clone, Copy, Debug)]
pub(super) struct Piece {
    pub(super) parent: Parent,
    pub(super) t: [f64; 2],
}

/// Where the pieces are split, and the shared points there.
#[derive(Clone, Debug, Default)]
pub(super) struct Crossings {
    /// For each piece, the sorted interior parameters to split at.
    pub(super) splits: Vec<Vec<f64>>,
    /// The point every section ending at `(piece, t)` gets.
    pub(super) points: HashMap<(usize, u64), Point>,
    /// Crossings found.
    pub(super) count: usize,
}

fn deriv(p: &Parent, t: f64) -> Vec2 {
    p.deriv(t)
}

/// The bounding box of the piece's control hull (it contains the piece).
fn control_box(p: &Parent, t: [f64; 2]) -> Rect {
    match p {
        Parent::Cubic(_) | Parent::Conic(_) => {
            let c = p.restrict(t[0], t[1]);
            Rect::from_points(c.p0, c.p3).union_pt(c.p1).union_pt(c.p2)
        }
        Parent::Line(_) => Rect::from_points(p.eval(t[0]), p.eval(t[1])),
    }
}

/// The boxes that cover `p` for the candidate search: a straight piece's run
/// of boxes at most `step` long each (grown by `pad`), a curve's control box.
fn cover_boxes(p: &Piece, step: f64, pad: f64, out: &mut Vec<Rect>) {
    match p.parent {
        Parent::Line(_) => {
            let (a, b) = (p.parent.eval(p.t[0]), p.parent.eval(p.t[1]));
            let len = a.distance(b);
            // At most MAX_RUN boxes: a piece longer than that many cells is
            // covered by longer boxes (the search stays correct, only coarser).
            let k = if step > 0.0 && len.is_finite() {
                ((len / step).ceil() as usize).clamp(1, MAX_RUN)
            } else {
                1
            };
            for i in 0..k {
                let u0 = a.lerp(b, i as f64 / k as f64);
                let u1 = if i + 1 == k {
                    b
                } else {
                    a.lerp(b, (i + 1) as f64 / k as f64)
                };
                out.push(Rect::from_points(u0, u1).inflate(pad, pad));
            }
        }
        Parent::Cubic(_) | Parent::Conic(_) => {
            out.push(control_box(&p.parent, p.t).inflate(pad, pad));
        }
    }
}

/// Most boxes in a straight piece's run (see [`cover_boxes`]).
const MAX_RUN: usize = 4096;
/// Most direction classes of straight pieces (see [`direction_classes`]);
/// with more (a tiny α) every piece is tried against every other.
const MAX_CLASSES: usize = 4096;
/// A direction class of at least this many pieces (and 1/32 of them) gets a
/// grid of its own (see [`find`]).
const BIG_CLASS: usize = 64;

/// The direction class of each piece and the number of straight classes
/// (curves and degenerate lines get that number, a class of their own).
/// Straight pieces are binned by direction modulo π in bins a little
/// narrower than half of `min_angle` (radians): two straight pieces in the
/// same or in neighbouring bins (circularly) meet at less than `min_angle`,
/// so a crossing of theirs would be refused by its angle.
fn direction_classes(pieces: &[Piece], min_angle: f64) -> (Vec<u32>, u32) {
    let width = 0.5 * min_angle * (1.0 - 1e-6);
    let bins = (std::f64::consts::PI / width).ceil();
    if !(bins.is_finite() && bins >= 3.0 && bins <= MAX_CLASSES as f64) {
        // Too fine to bin (or nothing to skip): one class, every pair tried.
        return (vec![0; pieces.len()], 0);
    }
    let bins = bins as u32;
    let class = pieces
        .iter()
        .map(|p| match p.parent {
            Parent::Line(_) => {
                let v = p.parent.eval(p.t[1]) - p.parent.eval(p.t[0]);
                if v.hypot2() > 0.0 && v.is_finite() {
                    let a = v.y.atan2(v.x).rem_euclid(std::f64::consts::PI);
                    ((a / width) as u32).min(bins - 1)
                } else {
                    bins
                }
            }
            Parent::Cubic(_) | Parent::Conic(_) => bins,
        })
        .collect();
    (class, bins)
}

/// Whether pieces of classes `a` and `b` (of [`direction_classes`], `bins`
/// straight ones) may cross at an angle that counts.
fn may_cross(a: u32, b: u32, bins: u32) -> bool {
    if a >= bins || b >= bins {
        return true;
    }
    let d = a.abs_diff(b);
    d.min(bins - d) > 1
}

/// The crossing parameters of segments `a b` and `c d` (as fractions), if they
/// cross properly.
fn chord_cross(a: Point, b: Point, c: Point, d: Point) -> Option<(f64, f64)> {
    let r = b - a;
    let s = d - c;
    let den = r.cross(s);
    if den == 0.0 || !den.is_finite() {
        return None;
    }
    let u = (c - a).cross(s) / den;
    let v = (c - a).cross(r) / den;
    ((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)).then_some((u, v))
}

/// Solve `p(s) = q(t)` by Newton from `(s, t)`, staying inside the intervals.
/// Iterates to rounding level and accepts a gap of at most `tol`.
fn newton(p: &Piece, q: &Piece, mut s: f64, mut t: f64, tol: f64) -> Option<(f64, f64)> {
    for _ in 0..NEWTON {
        let f = p.parent.eval(s) - q.parent.eval(t);
        if f.hypot() <= 1e-6 * tol {
            return Some((s, t));
        }
        let (ds, dt) = (deriv(&p.parent, s), -deriv(&q.parent, t));
        let det = ds.cross(dt);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        // [ds dt] [Δs Δt]ᵀ = -f
        let step_s = -(f.cross(dt)) / det;
        let step_t = -(ds.cross(f)) / det;
        s = (s + step_s).clamp(p.t[0], p.t[1]);
        t = (t + step_t).clamp(q.t[0], q.t[1]);
    }
    let f = p.parent.eval(s) - q.parent.eval(t);
    (f.hypot() <= tol).then_some((s, t))
}

/// Find the transversal crossings of `pieces` (see the module doc).
///
/// Two pieces that are both `trimmable` (outlines the features stage keeps only
/// where they bound what is painted, see `trim`) are split at any crossing
/// steeper than [`TRIM_MIN_DEG`] and farther than [`TRIM_NEAR`]·μ from their
/// ends: a stroke's inner join overshoots its neighbour at the corner's own
/// angle, and the overshoot is dropped only if it is a piece of its own.
///
/// Stops early, with the crossings found so far, once `deadline` has passed
/// (the caller discards the result then).
pub(super) fn find(
    pieces: &[Piece],
    trimmable: &[bool],
    params: &Resolved,
    deadline: &Deadline,
) -> Crossings {
    let n = pieces.len();
    let mut out = Crossings {
        splits: vec![Vec::new(); n],
        ..Crossings::default()
    };
    if n < 2 {
        return out;
    }
    let boxes: Vec<Rect> = pieces.iter().map(|p| control_box(&p.parent, p.t)).collect();
    let bounds = boxes.iter().skip(1).fold(boxes[0], |r, b| r.union(*b));
    // Each piece is covered by boxes about a cell of a grid with a few cells
    // per piece long (never shorter than μ); the grid over those boxes has
    // cells of that size.
    let step = Grid::new(bounds, params.mu, n).cell();
    // Touching counts: a crossing at a box's edge is in both boxes grown by a
    // hair.
    let pad = 1e-9 * params.d;
    let mut cover: Vec<Rect> = Vec::new();
    // The boxes of piece i: cover[first[i]..first[i + 1]].
    let mut first: Vec<usize> = Vec::with_capacity(n + 1);
    for p in pieces {
        first.push(cover.len());
        cover_boxes(p, step, pad, &mut cover);
    }
    first.push(cover.len());
    let Ok(boxes_u32) = u32::try_from(cover.len()) else {
        // Past 4 billion boxes no grid is built: nothing is split (the
        // memory budget stops such a run long before).
        return out;
    };
    // The piece of each box.
    let owner: Vec<u32> = (0..n)
        .flat_map(|i| std::iter::repeat_n(i as u32, first[i + 1] - first[i]))
        .collect();
    // The smallest angle any pair is split at: below it, no pair counts.
    let min_angle = (4.0 * params.alpha)
        .min(TRIM_MIN_DEG.to_radians())
        .min(std::f64::consts::FRAC_PI_2);
    let (class, bins) = direction_classes(pieces, min_angle);
    // A direction class of many pieces (a hatch's) has a grid of its own,
    // which the pieces that may cross it search and the others skip; the
    // rest share one grid, filtered by class item by item.
    let mut members = vec![0usize; bins as usize + 1];
    for &c in &class {
        members[c as usize] += 1;
    }
    let big = |c: u32| c < bins && members[c as usize] >= BIG_CLASS.max(n / 32);
    let big_classes: Vec<u32> = (0..bins).filter(|&c| big(c)).collect();
    let area = bounds.inflate(pad, pad);
    let mut shared = Grid::new(area, step, boxes_u32 as usize);
    let mut own: Vec<Grid> = big_classes
        .iter()
        .map(|&c| Grid::new(area, step, members[c as usize]))
        .collect();
    for (k, b) in cover.iter().enumerate() {
        let c = class[owner[k] as usize];
        match big_classes.binary_search(&c) {
            Ok(g) => own[g].insert(k as u32, *b),
            Err(_) => shared.insert(k as u32, *b),
        }
    }
    // The two curves' points must agree far below the on-curve tolerance
    // (1e-9·d): the shared point is their mean.
    let tol = (1e-10 * params.d).max(f64::MIN_POSITIVE);
    let min_sin = (4.0 * params.alpha).min(std::f64::consts::FRAC_PI_2).sin();
    let trim_sin = TRIM_MIN_DEG.to_radians().sin();
    let is_trimmable = |k: usize| trimmable.get(k).copied().unwrap_or(false);
    // Each piece's chords, once (a straight piece is its own chord).
    let chords: Vec<Vec<(Point, f64)>> = pieces
        .par_iter()
        .map(|p| {
            let m = match p.parent {
                Parent::Line(_) => 1,
                Parent::Cubic(_) | Parent::Conic(_) => CHORDS,
            };
            (0..=m)
                .map(|k| {
                    let t = p.t[0] + (p.t[1] - p.t[0]) * k as f64 / m as f64;
                    (p.parent.eval(t), t)
                })
                .collect()
        })
        .collect();
    // (piece, s, piece, t, point, nearness bound, split the first, the second)
    type Found = (usize, f64, usize, f64, Point, f64, bool, bool);
    // The crossings of piece i with the pieces after it that it overlaps and
    // that are not `full` yet.
    let crossings_of = |i: usize, full: &[bool], found: &mut Vec<Found>| {
        // The pieces after i with a box overlapping one of i's, in order.
        let mut near: Vec<u32> = Vec::new();
        let keep = |k: u32| {
            let j = owner[k as usize] as usize;
            j > i && !full[j] && may_cross(class[i], class[j], bins)
        };
        let grids = std::iter::once(&shared).chain(
            big_classes
                .iter()
                .zip(&own)
                .filter(|&(&c, _)| may_cross(class[i], c, bins))
                .map(|(_, g)| g),
        );
        for grid in grids {
            for b in &cover[first[i]..first[i + 1]] {
                grid.any_of(*b, keep, |k| {
                    near.push(owner[k as usize]);
                    false
                });
            }
        }
        near.sort_unstable();
        near.dedup();
        if near.is_empty() {
            return;
        }
        let ci = &chords[i];
        for j in near {
            let j = j as usize;
            let cj = &chords[j];
            let (near_ends, pair_sin) = if is_trimmable(i) && is_trimmable(j) {
                (TRIM_NEAR * params.mu, trim_sin)
            } else {
                (params.mu, min_sin)
            };
            // This pair's crossings so far: found[pair..].
            let pair = found.len();
            for a in ci.windows(2) {
                for b in cj.windows(2) {
                    let Some((u, v)) = chord_cross(a[0].0, a[1].0, b[0].0, b[1].0) else {
                        continue;
                    };
                    let s0 = a[0].1 + u * (a[1].1 - a[0].1);
                    let t0 = b[0].1 + v * (b[1].1 - b[0].1);
                    let Some((s, t)) = newton(&pieces[i], &pieces[j], s0, t0, tol) else {
                        continue;
                    };
                    let (p, q) = (&pieces[i], &pieces[j]);
                    let mut x = p.parent.eval(s).midpoint(q.parent.eval(t));
                    // Away from every end of both pieces (no tiny sections); between
                    // trimmable pieces, one ending on the other splits the other
                    // there (at the end point itself).
                    let p_ends = [p.parent.eval(p.t[0]), p.parent.eval(p.t[1])];
                    let q_ends = [q.parent.eval(q.t[0]), q.parent.eval(q.t[1])];
                    let near = |ends: &[Point; 2]| {
                        ends.iter().find(|e| e.distance(x) <= near_ends).copied()
                    };
                    // An end on the other curve (within the crossing tolerance).
                    let on = |e: Option<Point>| e.filter(|e| e.distance(x) <= tol);
                    let (p_end, q_end) = (near(&p_ends), near(&q_ends));
                    let t_junction = near_ends < params.mu;
                    let (split_p, split_q) = match (p_end, q_end) {
                        (None, None) => (true, true),
                        (Some(_), None) if t_junction && on(p_end).is_some() => {
                            x = p_end.expect("checked");
                            (false, true)
                        }
                        (None, Some(_)) if t_junction && on(q_end).is_some() => {
                            x = q_end.expect("checked");
                            (true, false)
                        }
                        _ => continue,
                    };
                    // Transversal: at least 4α between the tangents.
                    let (dp, dq) = (deriv(&p.parent, s), deriv(&q.parent, t));
                    let sin = dp.cross(dq).abs() / (dp.hypot() * dq.hypot());
                    if sin.is_nan() || sin < pair_sin {
                        continue;
                    }
                    // The same crossing from another chord pair.
                    if found[pair..].iter().any(|f| f.4.distance(x) <= near_ends) {
                        continue;
                    }
                    found.push((i, s, j, t, x, near_ends, split_p, split_q));
                }
            }
        }
    };
    // A block of pieces at a time: per piece i of the block, in parallel, its
    // crossings with the pieces after it; then in piece order, as one pass
    // over i would find them, the filter below. A piece with
    // [`MAX_PER_PIECE`] splits is full, the filter drops every crossing of a
    // full piece, and a full piece stays full: so the search skips the pieces
    // full when its block starts, which changes no split, only the work and
    // the memory (a 20 000-line cross-hatch finds some 19 million crossings
    // to keep 160 000). Past the deadline the
    // pieces left find nothing.
    let mut kept: Vec<Found> = Vec::new();
    // The points kept on each piece.
    let mut on_piece: Vec<Vec<Point>> = vec![Vec::new(); n];
    let mut full = vec![false; n];
    let mut start = 0;
    let mut block = BLOCK_MIN;
    while start < n && !deadline.expired() {
        let end = (start + block).min(n);
        let by_piece: Vec<Vec<Found>> = (start..end)
            .into_par_iter()
            .map(|i| {
                let mut found: Vec<Found> = Vec::new();
                if !full[i] && !deadline.expired() {
                    crossings_of(i, &full, &mut found);
                }
                found
            })
            .collect();
        // The block's list in one buffer, reserved within the memory budget
        // (past it the run stops at the next check instead of growing a list
        // the system may refuse).
        let total: usize = by_piece.iter().map(Vec::len).sum();
        let mut found: Vec<Found> = Vec::new();
        if crate::budget::reserve(&mut found, total, deadline).is_err() {
            return out;
        }
        found.extend(by_piece.into_iter().flatten());
        // Crossings within μ of each other on one piece would make tiny
        // sections: keep the first of such a cluster (by order found) and drop
        // its partners.
        for f in found {
            let clash = [f.0, f.2]
                .iter()
                .any(|&k| on_piece[k].iter().any(|x| x.distance(f.4) <= f.5));
            if clash || full[f.0] || full[f.2] {
                continue;
            }
            if f.6 {
                out.splits[f.0].push(f.1);
                on_piece[f.0].push(f.4);
            }
            if f.7 {
                out.splits[f.2].push(f.3);
                on_piece[f.2].push(f.4);
            }
            for k in [f.0, f.2] {
                full[k] = out.splits[k].len() >= MAX_PER_PIECE;
            }
            kept.push(f);
        }
        // Blocks that find few crossings grow, blocks that find many shrink:
        // a block's list stays near BLOCK_FOUND entries.
        block = if total > BLOCK_FOUND {
            (block / 2).max(BLOCK_MIN)
        } else if total < BLOCK_FOUND / 4 {
            (block * 2).min(BLOCK_MAX)
        } else {
            block
        };
        start = end;
    }
    for &(i, s, j, t, x, _, split_i, split_j) in &kept {
        if split_i {
            out.points.insert((i, s.to_bits()), x);
        }
        if split_j {
            out.points.insert((j, t.to_bits()), x);
        }
    }
    out.count = kept.len();
    for s in &mut out.splits {
        s.sort_by(f64::total_cmp);
        s.dedup();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;
    use kurbo::Line;

    fn line(a: (f64, f64), b: (f64, f64)) -> Piece {
        Piece {
            parent: Parent::Line(Line::new(a, b)),
            t: [0.0, 1.0],
        }
    }

    /// A hatch of parallel lines crossed by short transversals (fewer
    /// crossings each than [`MAX_PER_PIECE`]): every hatch-transversal
    /// crossing is found (the count a pair-by-pair check gives), and the
    /// parallel lines are split only there.
    #[test]
    fn hatch_crossings_are_the_transversal_ones() {
        let mut pieces: Vec<Piece> = (0..200)
            .map(|k| {
                let x = k as f64 * 0.5;
                line((x - 50.0, 0.0), (x + 50.0, 100.0))
            })
            .collect();
        for k in 0..6 {
            let (x, y) = (k as f64 * 12.0, 10.0 + k as f64 * 14.0);
            pieces.push(line((x, y), (x + 10.0, y + 0.5)));
        }
        let params = Params::DEFAULT.resolve(Point::new(160.0, 100.0).to_vec2().hypot());
        let found = find(&pieces, &[], &params, &Deadline::NONE);
        // Each transversal crosses the hatch lines whose span reaches it,
        // away from their ends.
        let transversals = 200..pieces.len();
        let brute = pieces[transversals.clone()]
            .iter()
            .map(|t| {
                let (a, b) = (t.parent.eval(0.0), t.parent.eval(1.0));
                pieces[..200]
                    .iter()
                    .filter(|h| {
                        let (c, d) = (h.parent.eval(0.0), h.parent.eval(1.0));
                        chord_cross(a, b, c, d).is_some_and(|(u, v)| {
                            let x = a.lerp(b, u);
                            let far = |e: Point| e.distance(x) > params.mu;
                            (far(a) && far(b) && far(c) && far(d)) && (0.0..=1.0).contains(&v)
                        })
                    })
                    .count()
            })
            .sum::<usize>();
        assert!(brute > 60, "{brute}");
        assert_eq!(found.count, brute);
        let hatch_splits: usize = found.splits[..200].iter().map(Vec::len).sum();
        let transversal_splits: usize = found.splits[transversals].iter().map(Vec::len).sum();
        assert_eq!((hatch_splits, transversal_splits), (brute, brute));
    }

    /// A cross-hatch whose lines each cross far more lines than
    /// [`MAX_PER_PIECE`], over several blocks: the search keeps exactly the
    /// crossings that a pass over all pairs in order keeps (the first ones,
    /// until a piece is full), though it skips the pieces full at a block's
    /// start.
    #[test]
    fn full_pieces_are_skipped_without_changing_the_splits() {
        let a = (0..150).map(|k| {
            let x = k as f64;
            line((x - 50.0, 0.0), (x + 50.0, 100.0))
        });
        let b = (0..150).map(|k| {
            let x = k as f64;
            line((x + 50.0, 0.0), (x - 50.0, 100.0))
        });
        let pieces: Vec<Piece> = a.chain(b).collect();
        assert!(pieces.len() > 2 * BLOCK_MIN);
        let params = Params::DEFAULT.resolve(Point::new(250.0, 100.0).to_vec2().hypot());
        let found = find(&pieces, &[], &params, &Deadline::NONE);
        // Pair by pair, in order, with the filter's rules.
        let mut splits: Vec<Vec<Point>> = vec![Vec::new(); pieces.len()];
        let mut count = 0;
        let mut candidates = 0;
        for i in 0..pieces.len() {
            for j in i + 1..pieces.len() {
                let ends = |k: usize| (pieces[k].parent.eval(0.0), pieces[k].parent.eval(1.0));
                let ((p, q), (r, t)) = (ends(i), ends(j));
                let Some((u, _)) = chord_cross(p, q, r, t) else {
                    continue;
                };
                let x = p.lerp(q, u);
                if [p, q, r, t].iter().any(|e| e.distance(x) <= params.mu) {
                    continue;
                }
                candidates += 1;
                let clash = [i, j]
                    .iter()
                    .any(|&k| splits[k].iter().any(|y| y.distance(x) <= params.mu));
                if clash || splits[i].len() >= MAX_PER_PIECE || splits[j].len() >= MAX_PER_PIECE {
                    continue;
                }
                splits[i].push(x);
                splits[j].push(x);
                count += 1;
            }
        }
        assert!(candidates > 3 * count, "{candidates} {count}");
        assert_eq!(found.count, count);
        for (k, want) in splits.iter().enumerate() {
            assert_eq!(found.splits[k].len(), want.len(), "piece {k}");
            for (s, x) in found.splits[k].iter().zip({
                let mut w: Vec<f64> = want
                    .iter()
                    .map(|x| (x.y - pieces[k].parent.eval(0.0).y) / 100.0)
                    .collect();
                w.sort_by(f64::total_cmp);
                w
            }) {
                assert!((s - x).abs() < 1e-9, "piece {k}: {s} against {x}");
            }
        }
    }

    #[test]
    fn direction_classes_pair_only_steep_meetings() {
        let min_angle = 1f64.to_radians();
        let pieces = [
            line((0.0, 0.0), (1.0, 0.0)),
            line((0.0, 1.0), (1.0, 1.0 + 0.3f64.to_radians().tan())),
            line((0.0, 0.0), (1.0, 2f64.to_radians().tan())),
            line((0.0, 0.0), (-1.0, -0.001)),
            line((0.0, 0.0), (0.0, 0.0)),
        ];
        let (class, bins) = direction_classes(&pieces, min_angle);
        assert!(bins >= 360);
        // 0.3°: never paired; 2°: paired; opposite direction, 0.06°: never;
        // a degenerate line: always.
        assert!(!may_cross(class[0], class[1], bins));
        assert!(may_cross(class[0], class[2], bins));
        assert!(!may_cross(class[0], class[3], bins));
        assert_eq!(class[4], bins);
        assert!(may_cross(class[0], class[4], bins));
        // A too fine binning: one class, every pair tried.
        let (class, bins) = direction_classes(&pieces, 1e-9);
        assert_eq!(bins, 0);
        assert!(class.iter().all(|&c| may_cross(c, class[0], bins)));
    }
}
