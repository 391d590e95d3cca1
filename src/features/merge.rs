//! Secondary merge: an open run of secondary sections that lies within μ
//! of secondary segments of *other* runs already kept is dropped before the linear
//! mesher sees it; the kept segments stand for it. It runs inside the secondary
//! simplification (`separation::simplify`), before the collapse of close vertices,
//! which would otherwise weld the lines of a hatch into one another at shared
//! vertices.
//!
//! Secondary features are approximated within the envelope anyway (docs/design.md
//! "Invariants" 2), and two of them closer than μ are exactly what the features stage does not keep
//! apart: a stroke narrower than μ is already meshed as its centre line, and the
//! simplification already collapses vertices closer than μ. Without this step every
//! line of a hatch or a stroked soup reaches the BSP, which must cut the mesh along all
//! of them, and the optimizer then works on slivers whose size the hatch's spacing
//! sets, not the size field (1 000 parallel strokes at a third of μ apart gave 593 k
//! BSP triangles and 80 s). After the merge the kept lines are about μ apart.
//!
//! **Which segments.** A run that separates no colours (the centre line of a stroke,
//! a shape drawn without fill, shared with no other outline) loses each segment that
//! kept runs cover: the faces on its two sides take one label, the same, whatever
//! else it touches, so a gap in it merges faces of one label. Any other run goes
//! whole or not at all, and only when it is open. A run that touches nothing else
//! (every vertex its own) may be covered by any kept runs: an open line whose ends
//! touch nothing bounds no face. A run that shares vertices with other features (a
//! primary section's end, an isolated point, another run's vertex) goes only when one
//! kept run has every one of those vertices, bit for bit, and covers it alone: what
//! met the dropped run still meets that one, and the faces on either side of the
//! dropped run were the thin one between the two lines and its neighbour. A closed
//! outline stays whatever is near it, as does a run whose shared vertices no single
//! kept run passes through: dropping part of a region's boundary would let the
//! regions stage's faces (which take one label each) run into one another through
//! the gap (dropping any covered segment loses 37-92 % of the picture on some dev
//! drawings).
//!
//! **The cover test** is conservative, like the envelope test
//! (`ops::invariants::envelope`): a segment is covered only when a chain of points
//! along it, each within μ of a kept segment, covers it (distance to a set is
//! 1-Lipschitz, so from a point at distance `d` the next `μ − d` of the segment are
//! within μ too); a point farther than `(1 − 1/16)·μ` fails it. A quick accept comes
//! first: when one kept segment is within μ of both ends, the whole segment is (the
//! distance to a segment is convex along a segment).
//!
//! **Order**: the longest polylines first (ties by index), so a long line survives and
//! the short ones near it go; a polyline is never compared with itself. Dropping only
//! removes geometry: the guarantees of the μ-separation to the primary sections hold.

use super::grid::Grid;
use crate::budget::Deadline;
use crate::mesh::point_segment_distance;
use kurbo::{Line, Point, Rect};
use rustc_hash::FxHashMap;
use smallvec::SmallVec;

/// A sample farther than this fraction of μ from every kept segment keeps its
/// segment (so every step of the march is at least `(1 − REJECT)·μ`).
const REJECT: f64 = 15.0 / 16.0;

/// What the merge decided.
pub(super) struct Merged {
    /// Whether each segment of each polyline stays.
    pub(super) keep: Vec<Vec<bool>>,
    /// Secondary segments dropped.
    pub(super) dropped: usize,
}

/// The kept segments, searchable: a grid over pieces of each segment no longer than
/// a cell (so a long diagonal segment fills a line of cells, not its whole box).
struct Kept {
    grid: Grid,
    /// Each piece's segment, by piece id.
    piece_of: Vec<u32>,
    /// The kept segments with their polyline.
    segments: Vec<(Line, u32)>,
    /// The kept polylines through each vertex, bit for bit (a shared vertex must be
    /// one of theirs: a point the float distance puts on a kept segment may be off it
    /// exactly, and the exact BSP would leave a gap there).
    /// (Two inline: most vertices are on one polyline, or where two meet.)
    at: FxHashMap<(u64, u64), SmallVec<[u32; 2]>>,
}

/// A point's key, bit for bit (+0.0 makes −0.0 and 0.0, equal points, one key).
fn key(p: Point) -> (u64, u64) {
    ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits())
}

impl Kept {
    fn insert(&mut self, seg: Line, polyline: u32) {
        let id = u32::try_from(self.segments.len()).expect("internal: segment count fits u32");
        self.segments.push((seg, polyline));
        for q in [seg.p0, seg.p1] {
            let at = self.at.entry(key(q)).or_default();
            if at.last() != Some(&polyline) {
                at.push(polyline);
            }
        }
        let cell = self.grid.cell();
        let pieces = (seg.length() / cell).ceil().clamp(1.0, 1e6) as usize;
        for k in 0..pieces {
            let a = seg.p0.lerp(seg.p1, k as f64 / pieces as f64);
            let b = seg.p0.lerp(seg.p1, (k + 1) as f64 / pieces as f64);
            let piece = u32::try_from(self.piece_of.len()).expect("internal: piece count fits u32");
            self.piece_of.push(id);
            self.grid.insert(piece, Rect::from_points(a, b));
        }
    }

    /// The kept segment of a polyline `by` accepts nearest to `p` within `r`, with
    /// its distance.
    fn nearest(&self, p: Point, r: f64, by: By) -> Option<(f64, u32)> {
        let mut best: Option<(f64, u32)> = None;
        self.grid
            .any(Rect::from_points(p, p).inflate(r, r), |piece| {
                let s = self.piece_of[piece as usize];
                let (line, polyline) = self.segments[s as usize];
                if by.accepts(polyline) {
                    let d = point_segment_distance(p, line);
                    if d <= r && best.is_none_or(|(b, _)| d < b) {
                        best = Some((d, s));
                    }
                }
                false
            });
        best
    }

    /// Whether every point of `seg` is within `r` of kept segments of the
    /// polylines `by` accepts (conservative: see the module doc).
    fn covers(&self, seg: Line, r: f64, by: By) -> bool {
        let reject = REJECT * r;
        let Some((d0, first)) = self.nearest(seg.p0, r, by) else {
            return false;
        };
        if d0 > reject {
            return false;
        }
        if point_segment_distance(seg.p1, self.segments[first as usize].0) <= r {
            return true;
        }
        let len = seg.length();
        let mut s = (r - d0).min(len);
        loop {
            let p = seg.p0.lerp(seg.p1, s / len);
            match self.nearest(p, r, by) {
                Some((d, _)) if d <= reject => {
                    if s >= len {
                        return true;
                    }
                    s = (s + (r - d)).min(len);
                }
                _ => return false,
            }
        }
    }
}

/// Which kept polylines may cover a segment.
#[derive(Clone, Copy)]
enum By {
    /// Any but this one (its own).
    AnyBut(u32),
    /// Only this one.
    Only(u32),
}

impl By {
    fn accepts(self, polyline: u32) -> bool {
        match self {
            By::AnyBut(own) => polyline != own,
            By::Only(one) => polyline == one,
        }
    }
}

/// Drop the open secondary polylines lying within `mu` of kept secondary segments of
/// other polylines (see the module doc). `others` are the vertices of the other
/// features (primary section ends, isolated points): a coloured polyline whose
/// vertices another feature or polyline shares goes only when one kept polyline has
/// every such vertex. `keep` holds a flag per segment. Stops merging (keeping the rest as it is) once `deadline` has
/// passed.
pub(super) fn merge_close(
    polylines: &[Vec<Point>],
    colourless: &[bool],
    others: impl Iterator<Item = Point>,
    mu: f64,
    deadline: &Deadline,
) -> Merged {
    let segments: usize = polylines.iter().map(|p| p.len() - 1).sum();
    if polylines.len() < 2 || !(mu.is_finite() && mu > 0.0) {
        return Merged {
            keep: polylines.iter().map(|p| vec![true; p.len() - 1]).collect(),
            dropped: 0,
        };
    }
    // How many features use each vertex (a closed polyline's first and last point once).
    let mut uses: FxHashMap<(u64, u64), u32> = FxHashMap::default();
    for p in polylines {
        let closed = p.first() == p.last();
        let n = p.len() - usize::from(closed);
        for &q in &p[..n] {
            *uses.entry(key(q)).or_default() += 1;
        }
    }
    for q in others {
        *uses.entry(key(q)).or_default() += 1;
    }
    let bounds = polylines
        .iter()
        .flat_map(|p| p.iter())
        .fold(None::<Rect>, |b, &q| {
            let r = Rect::from_points(q, q);
            Some(b.map_or(r, |b| b.union(r)))
        })
        .expect("polylines have points")
        .inflate(mu, mu);
    let mut kept = Kept {
        grid: Grid::new(bounds, mu, segments.max(1024)),
        piece_of: Vec::new(),
        segments: Vec::new(),
        at: FxHashMap::default(),
    };
    let length = |p: &Vec<Point>| -> f64 { p.windows(2).map(|w| w[0].distance(w[1])).sum() };
    let mut order: Vec<(f64, usize)> = polylines
        .iter()
        .enumerate()
        .map(|(i, p)| (length(p), i))
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut keep: Vec<Vec<bool>> = polylines.iter().map(|p| vec![true; p.len() - 1]).collect();
    let mut dropped = 0;
    for &(_, i) in &order {
        let p = &polylines[i];
        let own = u32::try_from(i).expect("internal: polyline count fits u32");
        let open = p.first() != p.last();
        let covered_by = |by: By| {
            p.windows(2)
                .all(|w| kept.covers(Line::new(w[0], w[1]), mu, by))
        };
        if colourless.get(i).copied().unwrap_or(false) {
            // Separates no colours: segment by segment, any kept lines may stand
            // for it.
            for (k, w) in p.windows(2).enumerate() {
                let seg = Line::new(w[0], w[1]);
                if !deadline.expired() && kept.covers(seg, mu, By::AnyBut(own)) {
                    keep[i][k] = false;
                    dropped += 1;
                } else {
                    kept.insert(seg, own);
                }
            }
            continue;
        }
        let shared: Vec<(u64, u64)> = p
            .iter()
            .map(|&q| key(q))
            .filter(|k| uses.get(k).copied().unwrap_or(0) > 1)
            .collect();
        let goes = open
            && !deadline.expired()
            && match shared.split_first() {
                // Touches nothing: any kept lines may stand for it.
                None => covered_by(By::AnyBut(own)),
                // One kept polyline must pass through every shared vertex and
                // cover it alone (so what met it there still meets that one).
                Some((first, rest)) => kept.at.get(first).is_some_and(|cands| {
                    cands.iter().any(|&a| {
                        rest.iter()
                            .all(|k| kept.at.get(k).is_some_and(|c| c.contains(&a)))
                            && covered_by(By::Only(a))
                    })
                }),
            };
        if goes {
            keep[i].iter_mut().for_each(|k| *k = false);
            dropped += p.len() - 1;
        } else {
            for w in p.windows(2) {
                kept.insert(Line::new(w[0], w[1]), own);
            }
        }
    }
    Merged { keep, dropped }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::SecondaryPolyline;
    use crate::svg::{FeatureSource, ShapeId};

    fn pl(points: &[(f64, f64)]) -> SecondaryPolyline {
        SecondaryPolyline {
            points: points.iter().map(|&(x, y)| Point::new(x, y)).collect(),
            source: FeatureSource {
                shape: ShapeId::from_index(0),
                subpath: 0,
                segment: 0,
            },
            shared: None,
        }
    }

    /// What stays of `pls`, and the segments dropped.
    struct Out {
        polylines: Vec<SecondaryPolyline>,
        dropped: usize,
    }

    fn merge_with(pls: Vec<SecondaryPolyline>, others: &[Point], mu: f64) -> Out {
        let points: Vec<Vec<Point>> = pls.iter().map(|p| p.points.clone()).collect();
        let coloured = vec![false; points.len()];
        let m = merge_close(
            &points,
            &coloured,
            others.iter().copied(),
            mu,
            &Deadline::NONE,
        );
        // (the coloured runs of these tests go whole or not at all)
        Out {
            polylines: pls
                .into_iter()
                .zip(m.keep)
                .filter_map(|(p, k)| k.iter().all(|&k| k).then_some(p))
                .collect(),
            dropped: m.dropped,
        }
    }

    fn merge(pls: Vec<SecondaryPolyline>, mu: f64) -> Out {
        merge_with(pls, &[], mu)
    }

    /// The distance from `p` to the polylines' segments.
    fn dist(p: Point, pls: &[SecondaryPolyline]) -> f64 {
        pls.iter()
            .flat_map(|q| q.points.windows(2).map(|w| Line::new(w[0], w[1])))
            .map(|l| point_segment_distance(p, l))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn a_hatch_closer_than_mu_keeps_lines_about_mu_apart() {
        // 100 lines 0.1 apart, μ = 1: about every tenth stays.
        let pls: Vec<_> = (0..100)
            .map(|k| pl(&[(0.0, k as f64 * 0.1), (50.0, k as f64 * 0.1)]))
            .collect();
        let m = merge(pls.clone(), 1.0);
        assert!(
            m.polylines.len() >= 9 && m.polylines.len() <= 12,
            "{}",
            m.polylines.len()
        );
        assert_eq!(m.dropped, 100 - m.polylines.len());
        // Every input point is within μ of what is kept.
        for p in &pls {
            for k in 0..=50 {
                let q = p.points[0].lerp(p.points[1], k as f64 / 50.0);
                assert!(dist(q, &m.polylines) <= 1.0, "{q:?}");
            }
        }
    }

    #[test]
    fn lines_farther_than_mu_all_stay() {
        let pls: Vec<_> = (0..20)
            .map(|k| pl(&[(0.0, k as f64 * 1.5), (50.0, k as f64 * 1.5 + 0.2)]))
            .collect();
        let m = merge(pls.clone(), 1.0);
        assert_eq!(m.dropped, 0);
        assert_eq!(m.polylines, pls);
    }

    #[test]
    fn a_polyline_never_merges_with_itself() {
        // A zigzag whose teeth are far closer than μ, and a hairpin.
        let zig: Vec<(f64, f64)> = (0..40)
            .map(|k| (k as f64 * 0.01, if k % 2 == 0 { 0.0 } else { 10.0 }))
            .collect();
        let hairpin = [(0.0, 20.0), (30.0, 20.0), (30.0, 20.1), (0.0, 20.1)];
        let pls = vec![pl(&zig), pl(&hairpin)];
        let m = merge(pls.clone(), 1.0);
        assert_eq!(m.dropped, 0);
        assert_eq!(m.polylines, pls);
    }

    #[test]
    fn a_line_near_a_kept_one_for_a_stretch_only_stays_whole() {
        let long = pl(&[(0.0, 0.0), (100.0, 0.0)]);
        let near = pl(&[
            (0.0, 0.3),
            (40.0, 0.3),
            (50.0, 10.0),
            (60.0, 0.3),
            (80.0, 0.3),
        ]);
        let m = merge(vec![long.clone(), near.clone()], 1.0);
        assert_eq!(m.dropped, 0);
        assert_eq!(m.polylines, vec![long, near]);
    }

    #[test]
    fn closed_outlines_stay() {
        let outer = pl(&[
            (0.0, 0.0),
            (50.0, 0.0),
            (50.0, 50.0),
            (0.0, 50.0),
            (0.0, 0.0),
        ]);
        let inner = pl(&[
            (0.2, 0.2),
            (49.8, 0.2),
            (49.8, 49.8),
            (0.2, 49.8),
            (0.2, 0.2),
        ]);
        let m = merge(vec![outer.clone(), inner.clone()], 1.0);
        assert_eq!(m.dropped, 0);
        assert_eq!(m.polylines, vec![outer, inner]);
    }

    #[test]
    fn a_shared_vertex_off_the_kept_lines_keeps_its_polyline() {
        // `b` runs 0.3 from `a` and ends where `c` starts: dropping it would cut `c`
        // off. `d` runs 0.3 from `a` too but ends on `a`'s own end point: it goes.
        let a = pl(&[(0.0, 0.0), (100.0, 0.0)]);
        let b = pl(&[(10.0, 0.3), (90.0, 0.3)]);
        let c = pl(&[(90.0, 0.3), (90.0, 40.0)]);
        let d = pl(&[(20.0, -0.3), (100.0, 0.0)]);
        let m = merge(vec![a.clone(), b.clone(), c.clone(), d], 1.0);
        assert_eq!(m.dropped, 1);
        assert_eq!(m.polylines, vec![a, b, c]);
        // With a primary section's end at b's free end, b stays too.
        let m = merge_with(
            vec![
                pl(&[(0.0, 0.0), (100.0, 0.0)]),
                pl(&[(10.0, 0.3), (80.0, 0.3)]),
            ],
            &[Point::new(10.0, 0.3)],
            1.0,
        );
        assert_eq!(m.dropped, 0);
    }

    #[test]
    fn a_line_that_separates_no_colours_goes_whatever_it_touches() {
        // `b` ends on `c`'s start, off `a`; closed `e` lies along `a` too. Coloured
        // (a fill's outline), both stay; colourless (centre lines), both go.
        let a = pl(&[(0.0, 0.0), (100.0, 0.0)]);
        let b = pl(&[(10.0, 0.3), (90.0, 0.3)]);
        let c = pl(&[(90.0, 0.3), (90.0, 40.0)]);
        let e = pl(&[(20.0, -0.2), (60.0, -0.2), (60.0, -0.4), (20.0, -0.2)]);
        let points: Vec<Vec<Point>> = [&a, &b, &c, &e].iter().map(|p| p.points.clone()).collect();
        let run = |colourless: [bool; 4]| {
            merge_close(
                &points,
                &colourless,
                std::iter::empty(),
                1.0,
                &Deadline::NONE,
            )
        };
        let m = run([false; 4]);
        assert!(m.keep.iter().flatten().all(|&k| k));
        let m = run([false, true, false, true]);
        assert_eq!(
            m.keep,
            vec![vec![true], vec![false], vec![true], vec![false; 3]]
        );
        assert_eq!(m.dropped, 4);
        // Colourless, a line along `a` for a stretch loses that stretch only.
        let f = pl(&[
            (0.0, 0.5),
            (40.0, 0.5),
            (50.0, 10.0),
            (60.0, 0.5),
            (80.0, 0.5),
        ]);
        let points = vec![a.points.clone(), f.points.clone()];
        let m = merge_close(
            &points,
            &[false, true],
            std::iter::empty(),
            1.0,
            &Deadline::NONE,
        );
        assert_eq!(m.keep[1], vec![false, true, true, false]);
    }

    #[test]
    fn a_segment_covered_by_two_kept_segments_together_goes() {
        // Kept: two segments meeting at (50, 0) at a slight bend; the other line runs
        // 0.5 above both: no single one covers it, the march does.
        let kept = pl(&[(0.0, 0.0), (50.0, 0.0), (100.0, 0.4)]);
        let other = pl(&[(5.0, 0.5), (95.0, 0.8)]);
        let m = merge(vec![kept.clone(), other], 1.0);
        assert_eq!(m.dropped, 1);
        assert_eq!(m.polylines, vec![kept]);
    }

    #[test]
    fn a_crossing_line_stays() {
        let a = pl(&[(0.0, 0.0), (100.0, 0.0)]);
        let b = pl(&[(50.0, -30.0), (50.0, 30.0)]);
        let m = merge(vec![a.clone(), b.clone()], 1.0);
        assert_eq!(m.dropped, 0);
        assert_eq!(m.polylines, vec![a, b]);
    }
}
