//! Coincident outlines: curves that two shapes (or two parts of one
//! shape) draw on top of each other become one feature.
//!
//! Clip art and FEM drawings are full of shared boundaries: touching fills, a
//! shape drawn over another, flags, maps, material interfaces. Kept as two
//! features, two copies of one curve are closer than μ to each other, so the
//! μ-separation test demotes both to secondary polylines that move within ε:
//! the regions on the two sides meet somewhere near the document's curve, not
//! on it, and the domain changes with `l`. Merged into one feature, the curve
//! is kept exact like any primary feature.
//!
//! Runs after the splits (step 2) and before the crossings, on the curve pieces:
//!
//! 1. **Collinear overlaps.** A straight piece is split at every end point of
//!    another straight piece that lies inside it, within `tol` of it, when that
//!    other piece lies along it (both its ends within `tol` of the first
//!    piece's line). Two collinear pieces that overlap then share the overlap's
//!    end points bit for bit (the split points are the other pieces' own end
//!    points), and their pieces over the overlap are equal. A split moves the
//!    piece by at most `tol` (the split point's distance to its line).
//! 2. **Equal pieces.** Pieces with the same end points (either way round)
//!    whose control points agree within `tol` (a conic's weight within
//!    [`WEIGHT_TOL`]) are one piece: the first in input order stays, the
//!    others go, and the shapes of the copies that went are listed as the
//!    piece's *sharers* (the trimming keeps a piece that any copy's shape
//!    keeps; the mesh writes its edges on every sharer's physical curve).
//!
//! Every tolerance test is exact ([`crate::exact::near_line`],
//! [`crate::exact::within`]); float arithmetic only picks the candidates
//! (a grid over the straight pieces' end points, queried along each piece in
//! boxes about one cell long, so a hatch's long lines meet only their
//! neighbours' ends) and orders the split points along a piece.
//!
//! Pieces that coincide only in part and are not straight (a circle drawn as
//! four arcs beside one drawn as two) are left alone: they stay two features,
//! and the separation test demotes them where they lie within μ.

use super::Parent;
use super::grid::Grid;
use crate::budget::Deadline;
use crate::exact::{near_line, within};
use crate::svg::{Feature, ShapeId};
use kurbo::{Line, Point, Rect};
use rayon::prelude::*;
use std::collections::HashMap;

/// The conic weight's tolerance (absolute; weights are cosines, at most 1 for
/// ellipse arcs), as for duplicate shapes.
const WEIGHT_TOL: f64 = 1e-12;

/// A curve piece as the features stage carries it: the index of its input
/// feature, its parent curve and its parameter intervals.
pub(super) type Piece = (u32, Parent, Vec<[f64; 2]>);

/// What merging did.
#[derive(Debug, Default)]
pub(super) struct Merged {
    /// The pieces, straight ones split at the collinear overlaps, equal ones
    /// once (in input order).
    pub(super) pieces: Vec<Piece>,
    /// By piece: its curve as drawn, where snapping moved it.
    pub(super) as_drawn: Vec<Option<Parent>>,
    /// By piece: its sharers (index into `sharers`), if copies of it went.
    pub(super) shared: Vec<Option<u32>>,
    /// Lists of sharers: the shapes of the copies that went (other than the
    /// kept piece's own shape), ascending, each once.
    pub(super) sharers: Vec<Vec<ShapeId>>,
    /// Splits of straight pieces at collinear overlaps.
    pub(super) splits: usize,
    /// Pieces that went as copies of another.
    pub(super) merged: usize,
}

/// Merge the coincident pieces of `pieces` (see the module doc). `as_drawn`
/// is by piece; `features` are the drawing's (for the pieces' shapes); `tol` is
/// the coincidence tolerance (ε_m) and `min_len` the shortest piece a split may
/// leave (l_m: snapping already joined end points closer than that).
///
/// Gives up once `deadline` has passed, returning the pieces as they are then
/// (the caller checks the deadline and discards them): a thousand collinear
/// copies of a line, each shifted along it, split one another into a million
/// pieces, tens of seconds of work.
pub(super) fn merge(
    pieces: Vec<Piece>,
    as_drawn: Vec<Option<Parent>>,
    features: &[Feature],
    tol: f64,
    min_len: f64,
    deadline: &Deadline,
) -> Merged {
    let (pieces, as_drawn, splits) = split_overlaps(pieces, as_drawn, tol, min_len, deadline);
    if deadline.expired() {
        return Merged {
            shared: vec![None; pieces.len()],
            pieces,
            as_drawn,
            splits,
            ..Merged::default()
        };
    }
    let n = pieces.len();
    // Candidates by their unordered end points.
    let key = |p: Point| (p.x + 0.0).to_bits() ^ (p.y + 0.0).to_bits().rotate_left(17);
    let ends_key = |p: &Parent| {
        let (a, b) = (p.eval(0.0), p.eval(1.0));
        let (ka, kb) = (key(a), key(b));
        (ka.min(kb), ka.max(kb))
    };
    let mut by_ends: HashMap<(u64, u64), Vec<usize>> = HashMap::new();
    let mut copy_of: Vec<Option<usize>> = vec![None; n];
    for (k, (_, parent, _)) in pieces.iter().enumerate() {
        if k % CHECK_EVERY == 0 && deadline.expired() {
            break;
        }
        let bucket = by_ends.entry(ends_key(parent)).or_default();
        if let Some(&first) = bucket
            .iter()
            .find(|&&j| same_curve(&pieces[j].1, parent, tol))
        {
            copy_of[k] = Some(first);
        } else {
            bucket.push(k);
        }
    }
    let shape_of = |k: usize| features[pieces[k].0 as usize].source.shape;
    let mut sharer_sets: Vec<Vec<ShapeId>> = vec![Vec::new(); n];
    let mut merged = 0;
    for (k, copy) in copy_of.iter().enumerate() {
        if let Some(first) = *copy {
            merged += 1;
            let s = shape_of(k);
            if s != shape_of(first) && !sharer_sets[first].contains(&s) {
                sharer_sets[first].push(s);
            }
        }
    }
    let mut out = Merged {
        splits,
        merged,
        ..Merged::default()
    };
    for (k, ((piece, drawn), mut sharers)) in pieces
        .into_iter()
        .zip(as_drawn)
        .zip(sharer_sets)
        .enumerate()
    {
        if copy_of[k].is_some() {
            continue;
        }
        out.pieces.push(piece);
        out.as_drawn.push(drawn);
        out.shared.push(if sharers.is_empty() {
            None
        } else {
            sharers.sort_unstable();
            out.sharers.push(sharers);
            Some(u32::try_from(out.sharers.len() - 1).expect("internal: sharer count fits u32"))
        });
    }
    out
}

/// Whether two pieces with the same end points are one curve: same kind, control
/// points within `tol` in the same or the reverse order (exactly decided).
fn same_curve(a: &Parent, b: &Parent, tol: f64) -> bool {
    let all_within = |p: &[Point], q: &[Point]| p.iter().zip(q).all(|(x, y)| within(*x, *y, tol));
    let both_ways = |p: [Point; 4], q: [Point; 4]| {
        all_within(&p, &q) || all_within(&p, &[q[3], q[2], q[1], q[0]])
    };
    match (a, b) {
        (Parent::Line(p), Parent::Line(q)) => {
            both_ways([p.p0, p.p0, p.p1, p.p1], [q.p0, q.p0, q.p1, q.p1])
        }
        (Parent::Cubic(p), Parent::Cubic(q)) => {
            both_ways([p.p0, p.p1, p.p2, p.p3], [q.p0, q.p1, q.p2, q.p3])
        }
        (Parent::Conic(p), Parent::Conic(q)) => {
            (p.w - q.w).abs() <= WEIGHT_TOL
                && both_ways([p.p0, p.p1, p.p1, p.p2], [q.p0, q.p1, q.p1, q.p2])
        }
        _ => false,
    }
}

/// Pieces between two looks at the deadline in the merging loop.
const CHECK_EVERY: usize = 4096;

/// Step 1 of the module doc: straight pieces split at the end points of the
/// straight pieces that lie along them. Returns the pieces, their drawn curves
/// and the number of splits.
fn split_overlaps(
    pieces: Vec<Piece>,
    as_drawn: Vec<Option<Parent>>,
    tol: f64,
    min_len: f64,
    deadline: &Deadline,
) -> (Vec<Piece>, Vec<Option<Parent>>, usize) {
    // The straight pieces (a line's one interval is [0, 1]).
    let lines: Vec<(usize, Line)> = pieces
        .iter()
        .enumerate()
        .filter_map(|(k, (_, p, iv))| match p {
            Parent::Line(l) if iv.len() == 1 && l.p0 != l.p1 => Some((k, *l)),
            _ => None,
        })
        .collect();
    if lines.len() < 2 {
        return (pieces, as_drawn, 0);
    }
    let ends: Vec<Point> = lines.iter().flat_map(|(_, l)| [l.p0, l.p1]).collect();
    let bounds = ends
        .iter()
        .fold(Rect::from_points(ends[0], ends[0]), |r, p| r.union_pt(*p));
    let cell = (bounds.area() / lines.len() as f64)
        .sqrt()
        .max(bounds.width().max(bounds.height()) / (4.0 * lines.len() as f64));
    let mut grid = Grid::new(bounds, cell, ends.len());
    for (id, p) in ends.iter().enumerate() {
        grid.insert(
            u32::try_from(id).expect("internal: end count fits u32"),
            Rect::from_points(*p, *p),
        );
    }
    let step = grid.cell();
    // By straight piece: its split points, with their parameter along it
    // (each piece's from the grid alone, so in parallel, in any order).
    let cuts_of = |li: usize, l: &Line| -> Vec<(f64, Point)> {
        let mut cuts = Vec::new();
        if deadline.expired_in_loop() {
            return cuts;
        }
        let (p, q) = (l.p0, l.p1);
        let dir = q - p;
        let len2 = dir.hypot2();
        let len = len2.sqrt();
        let runs = ((len / step).ceil() as usize).clamp(1, 1 << 20);
        let pad = 2.0 * tol;
        for r in 0..runs {
            let (a, b) = (
                p.lerp(q, r as f64 / runs as f64),
                p.lerp(q, (r + 1) as f64 / runs as f64),
            );
            grid.any(Rect::from_points(a, b).inflate(pad, pad), |id| {
                let (lj, end) = (id as usize / 2, id as usize % 2);
                if lj == li {
                    return false;
                }
                let other = lines[lj].1;
                let (x, y) = if end == 0 {
                    (other.p0, other.p1)
                } else {
                    (other.p1, other.p0)
                };
                if x == p || x == q {
                    return false;
                }
                let t = (x - p).dot(dir) / len2;
                // strictly inside, and not within l_m of an end
                if !(t * len > min_len && (1.0 - t) * len > min_len) {
                    return false;
                }
                // a float filter, then the exact tests
                let off = (x - p).cross(dir).abs() / len;
                if off > 4.0 * tol + 1e-12 * len {
                    return false;
                }
                if near_line(p, q, x, tol) && near_line(p, q, y, tol) {
                    cuts.push((t, x));
                }
                false
            });
        }
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        cuts.dedup_by(|a, b| a.1 == b.1);
        cuts
    };
    let mut cuts: Vec<Vec<(f64, Point)>> = Vec::with_capacity(lines.len());
    for (block, from) in lines.chunks(CHECK_EVERY).zip((0..).step_by(CHECK_EVERY)) {
        if deadline.expired() {
            return (pieces, as_drawn, 0);
        }
        cuts.par_extend(
            block
                .par_iter()
                .enumerate()
                .map(|(i, (_, l))| cuts_of(from + i, l)),
        );
    }
    if deadline.expired() {
        return (pieces, as_drawn, 0);
    }
    let total: usize = cuts.iter().map(Vec::len).sum();
    if total == 0 {
        return (pieces, as_drawn, 0);
    }
    let mut cut_of: Vec<Option<usize>> = vec![None; pieces.len()];
    for (li, (k, _)) in lines.iter().enumerate() {
        if !cuts[li].is_empty() {
            cut_of[*k] = Some(li);
        }
    }
    let mut out = Vec::with_capacity(pieces.len() + total);
    let mut out_drawn = Vec::with_capacity(pieces.len() + total);
    for (k, (piece, drawn)) in pieces.into_iter().zip(as_drawn).enumerate() {
        let Some(li) = cut_of[k] else {
            out.push(piece);
            out_drawn.push(drawn);
            continue;
        };
        let l = lines[li].1;
        let mut at: Vec<(f64, Point)> = vec![(0.0, l.p0)];
        at.extend(cuts[li].iter().copied());
        at.push((1.0, l.p1));
        for w in at.windows(2) {
            out.push((
                piece.0,
                Parent::Line(Line::new(w[0].1, w[1].1)),
                vec![[0.0, 1.0]],
            ));
            out_drawn.push(match drawn {
                Some(Parent::Line(d)) => Some(Parent::Line(Line::new(
                    Parent::Line(d).eval(w[0].0),
                    Parent::Line(d).eval(w[1].0),
                ))),
                _ => None,
            });
        }
    }
    (out, out_drawn, total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::svg::{FeatureGeom, FeatureSource};

    fn feature(shape: usize) -> Feature {
        Feature {
            geom: FeatureGeom::Point(Point::ZERO),
            source: FeatureSource {
                shape: ShapeId::from_index(shape),
                subpath: 0,
                segment: 0,
            },
        }
    }

    fn line(f: u32, a: (f64, f64), b: (f64, f64)) -> Piece {
        (f, Parent::Line(Line::new(a, b)), vec![[0.0, 1.0]])
    }

    /// [`merge`] with no drawn curves and no deadline.
    fn merged(pieces: Vec<Piece>, features: &[Feature], tol: f64, min_len: f64) -> Merged {
        let n = pieces.len();
        merge(
            pieces,
            vec![None; n],
            features,
            tol,
            min_len,
            &Deadline::NONE,
        )
    }

    fn ends(m: &Merged) -> Vec<((f64, f64), (f64, f64))> {
        m.pieces
            .iter()
            .map(|(_, p, _)| {
                let (a, b) = (p.eval(0.0), p.eval(1.0));
                ((a.x, a.y), (b.x, b.y))
            })
            .collect()
    }

    /// Past the deadline nothing is split or merged (the pieces come back as
    /// they were, one `shared` entry each); the same pieces split and merge
    /// within it.
    #[test]
    fn a_passed_deadline_stops_the_splitting() {
        let shifted = |k: u32| {
            line(
                k,
                (0.01 * f64::from(k), 0.0),
                (10.0 + 0.01 * f64::from(k), 0.0),
            )
        };
        let pieces: Vec<Piece> = (0..50u32).map(shifted).collect();
        let features: Vec<Feature> = (0..50).map(feature).collect();
        let passed = Deadline::after(Some(0.0));
        let m = merge(
            pieces.clone(),
            vec![None; 50],
            &features,
            1e-9,
            1e-6,
            &passed,
        );
        assert_eq!(
            (m.splits, m.merged, m.pieces.len(), m.shared.len()),
            (0, 0, 50, 50)
        );
        let m = merged(pieces, &features, 1e-9, 1e-6);
        assert!(
            m.splits > 50 * 40 && m.merged > 50 * 40,
            "{} {}",
            m.splits,
            m.merged
        );
    }

    #[test]
    fn overlapping_collinear_segments_share_their_overlap_once() {
        // a: 0..10, b: 4..14 on y = 0; c crosses elsewhere.
        let pieces = vec![
            line(0, (0.0, 0.0), (10.0, 0.0)),
            line(1, (4.0, 0.0), (14.0, 0.0)),
            line(2, (5.0, -3.0), (5.0, 3.0)),
        ];
        let features = [feature(0), feature(1), feature(2)];
        let m = merged(pieces, &features, 1e-9, 1e-6);
        assert_eq!(m.splits, 2);
        assert_eq!(m.merged, 1);
        assert_eq!(
            ends(&m),
            [
                ((0.0, 0.0), (4.0, 0.0)),
                ((4.0, 0.0), (10.0, 0.0)),
                ((10.0, 0.0), (14.0, 0.0)),
                ((5.0, -3.0), (5.0, 3.0)),
            ]
        );
        // the overlap is a's piece, shared with b's shape
        assert_eq!(m.shared, [None, Some(0), None, None]);
        assert_eq!(m.sharers, [vec![ShapeId::from_index(1)]]);
    }

    #[test]
    fn reversed_copies_merge_and_near_parallel_ones_do_not() {
        let tol = 1e-6;
        let pieces = vec![
            line(0, (0.0, 0.0), (10.0, 0.0)),
            line(1, (10.0, 0.0), (0.0, 0.0)),
            // a parallel segment 2·tol away: not one curve, not split
            line(2, (2.0, 2.0 * tol), (8.0, 2.0 * tol)),
            // a segment ending on a's inside at a right angle: no split
            line(3, (5.0, 0.0), (5.0, 4.0)),
        ];
        let features = [feature(0), feature(1), feature(2), feature(3)];
        let m = merged(pieces, &features, tol, 1e-3);
        assert_eq!((m.splits, m.merged), (0, 1));
        assert_eq!(m.pieces.len(), 3);
        assert_eq!(m.shared[0], Some(0));
    }

    #[test]
    fn equal_cubics_and_conics_merge_either_way_round() {
        use crate::svg::drawing::Conic;
        let c = kurbo::CubicBez::new((0.0, 0.0), (1.0, 2.0), (3.0, 2.0), (4.0, 0.0));
        let r = kurbo::CubicBez::new(c.p3, c.p2, c.p1, c.p0);
        let k = Conic {
            p0: Point::new(0.0, 0.0),
            p1: Point::new(0.0, 5.0),
            p2: Point::new(5.0, 5.0),
            w: std::f64::consts::FRAC_1_SQRT_2,
        };
        let kr = Conic {
            p0: k.p2,
            p1: k.p1,
            p2: k.p0,
            w: k.w,
        };
        let bent = Conic { w: 0.5, ..k };
        let pieces = vec![
            (0, Parent::Cubic(c), vec![[0.0, 1.0]]),
            (1, Parent::Cubic(r), vec![[0.0, 1.0]]),
            (2, Parent::Conic(k), vec![[0.0, 1.0]]),
            (3, Parent::Conic(kr), vec![[0.0, 1.0]]),
            (4, Parent::Conic(bent), vec![[0.0, 1.0]]),
        ];
        let features: Vec<Feature> = (0..5).map(feature).collect();
        let m = merged(pieces, &features, 1e-9, 1e-6);
        assert_eq!(m.merged, 2);
        assert_eq!(m.shared, [Some(0), Some(1), None]);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig {
            cases: 64, failure_persistence: None, ..proptest::prelude::ProptestConfig::default()
        })]
        /// The straight pieces' split points are found in parallel: one
        /// thread and two split the same pieces at the same points.
        #[test]
        fn overlaps_split_the_same_on_one_and_two_threads(
            segs in proptest::collection::vec((0u32..40, 1u32..12, 0u32..3), 2..60),
        ) {
            let dir = kurbo::Vec2::new(3.0, 1.0);
            let at = |s: u32, row: u32| Point::new(0.0, 7.0 * f64::from(row)) + dir * f64::from(s);
            let pieces: Vec<Piece> = segs
                .iter()
                .enumerate()
                .map(|(f, &(s, len, row))| {
                    (f as u32, Parent::Line(Line::new(at(s, row), at(s + len, row))), vec![[0.0, 1.0]])
                })
                .collect();
            let features: Vec<Feature> = (0..segs.len()).map(feature).collect();
            let on = |threads: usize| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("a pool")
                    .install(|| {
                        let m = merged(pieces.clone(), &features, 1e-9, 1e-6);
                        (ends(&m), m.splits, m.merged)
                    })
            };
            proptest::prop_assert_eq!(on(1), on(2));
        }

        /// Random collinear segments on one slanted line (end points on a grid
        /// of the line's parameter, so some coincide): after merging, no two
        /// pieces overlap, and every point of the union is on exactly one piece.
        #[test]
        fn collinear_segments_become_a_partition_of_their_union(
            segs in proptest::collection::vec((0u32..20, 1u32..8), 2..12),
        ) {
            let dir = kurbo::Vec2::new(3.0, 1.0);
            let at = |s: u32| Point::ORIGIN + dir * f64::from(s);
            let pieces: Vec<Piece> = segs
                .iter()
                .enumerate()
                .map(|(f, &(s, len))| {
                    (f as u32, Parent::Line(Line::new(at(s), at(s + len))), vec![[0.0, 1.0]])
                })
                .collect();
            let features: Vec<Feature> = (0..segs.len()).map(feature).collect();
            let m = merged(pieces, &features, 1e-9, 1e-6);
            // each unit step covered by some input segment is covered exactly once
            for u in 0..27u32 {
                let mid = Point::ORIGIN + dir * (f64::from(u) + 0.5);
                let want = segs.iter().any(|&(s, len)| s <= u && u < s + len);
                let got = m
                    .pieces
                    .iter()
                    .filter(|(_, p, _)| {
                        let Parent::Line(l) = p else { return false };
                        let (lo, hi) = (l.p0.x.min(l.p1.x), l.p0.x.max(l.p1.x));
                        lo < mid.x && mid.x < hi
                    })
                    .count();
                proptest::prop_assert_eq!(got, usize::from(want), "step {}", u);
            }
        }
    }
}
