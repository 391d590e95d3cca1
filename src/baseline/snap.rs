//! Iterated snap rounding of the baseline's planar input, before spade sees it.
//!
//! Owns: moving every flattened point to a grid of pitch δ (a power of two, about
//! 1e-9 of the drawing's diagonal, so exact in f64 after the power-of-two scaling),
//! then splitting pieces until no two pieces cross or overlap and no vertex lies
//! within [`HOT_RADIUS`] grid units of a piece's interior.
//!
//! Guarantees (on return): every point is on the δ-grid and points are distinct;
//! pieces have distinct end points, each undirected piece is listed once per owning
//! shape; no two pieces cross properly or overlap, and no point is within
//! `HOT_RADIUS · δ` of the interior of a piece it is not an end of (all decided
//! exactly in integer grid coordinates). So spade can insert every piece with its
//! non-splitting constraint API and creates no vertex of its own there, which is
//! what made the near-duplicate vertices and slivers (docs/design.md "Data flow",
//! `baseline`; thesis ch. 4 uses exact rationals instead). Pieces still offending
//! after [`MAX_ROUNDS`] rounds are dropped and counted.

use super::input::{Piece, PlanarInput};
use crate::svg::ShapeId;
use kurbo::Point;
use std::collections::{HashMap, HashSet};

/// Rounds of crossing splits and hot-vertex splits before giving up.
const MAX_ROUNDS: usize = 8;

/// A point closer than this (grid units) to a piece's interior splits the piece.
const HOT_RADIUS: i64 = 2;

/// A grid point, in units of δ.
type Ip = (i64, i64);

/// The snapped input.
#[derive(Clone, Debug)]
pub(super) struct Snapped {
    /// Points and pieces, in the same scaled coordinates as the input.
    pub(super) planar: PlanarInput,
    /// Rounds used.
    pub(super) rounds: usize,
    /// Pieces split at crossings or near vertices (summed over rounds).
    pub(super) splits: usize,
    /// Pieces dropped because they still offended after the last round.
    pub(super) dropped: usize,
}

/// Finest grid: scaled coordinates are below 2 in magnitude, so grid coordinates
/// stay below 2^61 and every orientation below 2^125 fits an `i128`.
const MIN_PITCH_EXP: i32 = -60;

/// δ: the power of two nearest below `rel · d` (scaled units), within
/// `[2^MIN_PITCH_EXP, 1]`.
pub(super) fn grid_pitch(d: f64, rel: f64) -> f64 {
    let target = rel * d;
    let e = if target.is_finite() && target > 0.0 {
        target.log2().floor()
    } else {
        f64::from(MIN_PITCH_EXP)
    };
    2f64.powi((e as i32).clamp(MIN_PITCH_EXP, 0))
}

/// Twice the signed area of the grid triangle `a b c`, exact in `i128`: its
/// sign is the orientation (snapped points are integers, so no filter is
/// needed) and its magnitude gives distances and crossing parameters.
fn area2(a: Ip, b: Ip, c: Ip) -> i128 {
    let (abx, aby) = (i128::from(b.0 - a.0), i128::from(b.1 - a.1));
    let (acx, acy) = (i128::from(c.0 - a.0), i128::from(c.1 - a.1));
    abx * acy - aby * acx
}

/// A geometric piece and the shapes that own it.
#[derive(Clone, Debug)]
struct Seg {
    a: u32,
    b: u32,
    shapes: Vec<ShapeId>,
}

struct State {
    pts: Vec<Ip>,
    index: HashMap<Ip, u32>,
    segs: Vec<Seg>,
}

impl State {
    fn vertex(&mut self, p: Ip) -> u32 {
        // Grid coordinates above 2^53 are those an f64 holds (so the output points,
        // `p · δ` in f64, are distinct exactly when the keys are).
        let p = ((p.0 as f64) as i64, (p.1 as f64) as i64);
        if let Some(&i) = self.index.get(&p) {
            return i;
        }
        let i = u32::try_from(self.pts.len()).expect("internal: more than 2^32 points");
        self.pts.push(p);
        self.index.insert(p, i);
        i
    }

    /// Merge identical pieces (either direction), keeping every owner once.
    fn dedup(&mut self) {
        let mut at: HashMap<(u32, u32), usize> = HashMap::new();
        let mut out: Vec<Seg> = Vec::with_capacity(self.segs.len());
        for s in self.segs.drain(..) {
            if s.a == s.b {
                continue;
            }
            let key = (s.a.min(s.b), s.a.max(s.b));
            match at.get(&key) {
                Some(&k) => {
                    for sh in s.shapes {
                        if !out[k].shapes.contains(&sh) {
                            out[k].shapes.push(sh);
                        }
                    }
                }
                None => {
                    at.insert(key, out.len());
                    out.push(s);
                }
            }
        }
        self.segs = out;
    }

    /// A uniform grid over the pieces: cell size and, per cell, the pieces passing
    /// within `HOT_RADIUS` (plus a margin) of it.
    fn grid(&self) -> (i64, HashMap<Ip, Vec<u32>>) {
        let total: f64 = self
            .segs
            .iter()
            .map(|s| {
                let (a, b) = (self.pts[s.a as usize], self.pts[s.b as usize]);
                ((b.0 - a.0) as f64).hypot((b.1 - a.1) as f64)
            })
            .sum();
        let n = self.segs.len().max(1) as f64;
        let cell = ((total / n).max(8.0 * HOT_RADIUS as f64)).min(1e15) as i64;
        let margin = (HOT_RADIUS + 2) as f64;
        let mut map: HashMap<Ip, Vec<u32>> = HashMap::new();
        for (i, s) in self.segs.iter().enumerate() {
            let (a, b) = (self.pts[s.a as usize], self.pts[s.b as usize]);
            let (ax, ay, bx, by) = (a.0 as f64, a.1 as f64, b.0 as f64, b.1 as f64);
            let cy0 = (ay.min(by) - margin).div_euclid(cell as f64) as i64;
            let cy1 = (ay.max(by) + margin).div_euclid(cell as f64) as i64;
            for cy in cy0..=cy1 {
                // The x-range of the piece within this row band (grown by the margin).
                let lo = (cy * cell) as f64 - margin;
                let hi = ((cy + 1) * cell) as f64 + margin;
                let (x0, x1) = if (by - ay).abs() < 1.0 {
                    (ax.min(bx), ax.max(bx))
                } else {
                    let xat = |y: f64| ax + (bx - ax) * ((y - ay) / (by - ay)).clamp(0.0, 1.0);
                    let (p, q) = (xat(lo), xat(hi));
                    (p.min(q), p.max(q))
                };
                let cx0 = (x0 - margin).div_euclid(cell as f64) as i64;
                let cx1 = (x1 + margin).div_euclid(cell as f64) as i64;
                for cx in cx0..=cx1 {
                    map.entry((cx, cy)).or_default().push(i as u32);
                }
            }
        }
        (cell, map)
    }

    /// One round: find crossings and hot vertices; returns the split points per piece.
    fn find_splits(&mut self) -> Vec<Vec<u32>> {
        let (cell, map) = self.grid();
        let mut splits: Vec<Vec<u32>> = vec![Vec::new(); self.segs.len()];
        // (a) proper crossings, split at the snapped crossing point.
        let mut tested: HashSet<(u32, u32)> = HashSet::new();
        let mut crossings: Vec<(u32, u32, Ip)> = Vec::new();
        for list in map.values() {
            for (k, &i) in list.iter().enumerate() {
                for &j in &list[k + 1..] {
                    if !tested.insert((i.min(j), i.max(j))) {
                        continue;
                    }
                    if let Some(x) = self.crossing(i, j) {
                        crossings.push((i, j, x));
                    }
                }
            }
        }
        // The grid is a HashMap, so the crossings arrive in a random order; sort them
        // so new vertices are numbered the same on every run (same input, same mesh).
        crossings.sort_unstable();
        for (i, j, x) in crossings {
            let v = self.vertex(x);
            splits[i as usize].push(v);
            splits[j as usize].push(v);
        }
        // (b) every vertex near the interior of a piece splits it.
        let r2 = i128::from(HOT_RADIUS * HOT_RADIUS);
        for (v, &p) in self.pts.iter().enumerate() {
            let v = v as u32;
            let key = (p.0.div_euclid(cell), p.1.div_euclid(cell));
            let Some(list) = map.get(&key) else { continue };
            for &i in list {
                let s = &self.segs[i as usize];
                if s.a == v || s.b == v {
                    continue;
                }
                let (a, b) = (self.pts[s.a as usize], self.pts[s.b as usize]);
                let (dx, dy) = (i128::from(b.0 - a.0), i128::from(b.1 - a.1));
                let t = i128::from(p.0 - a.0) * dx + i128::from(p.1 - a.1) * dy;
                let l2 = dx * dx + dy * dy;
                if t <= 0 || t >= l2 {
                    continue;
                }
                let c = area2(a, b, p);
                // c² ≤ r² · l2, without overflow: c and l2 are below 2^106.
                let near = if c.unsigned_abs() > (1u128 << 63) {
                    false
                } else {
                    c * c <= r2.saturating_mul(l2)
                };
                if near {
                    splits[i as usize].push(v);
                }
            }
        }
        splits
    }

    /// The snapped point where pieces `i` and `j` cross properly, if they do.
    fn crossing(&self, i: u32, j: u32) -> Option<Ip> {
        let (s, t) = (&self.segs[i as usize], &self.segs[j as usize]);
        if s.a == t.a || s.a == t.b || s.b == t.a || s.b == t.b {
            return None;
        }
        let [a, b, c, d] = [s.a, s.b, t.a, t.b].map(|k| self.pts[k as usize]);
        let (o1, o2) = (area2(a, b, c), area2(a, b, d));
        let (o3, o4) = (area2(c, d, a), area2(c, d, b));
        if !(o1.signum() * o2.signum() < 0 && o3.signum() * o4.signum() < 0) {
            return None;
        }
        // The parameter along a–b is o3 / (o3 - o4), in (0, 1); rounding errors of
        // a grid unit or so are harmless (hot vertices catch what they leave).
        let u = o3 as f64 / (o3 as f64 - o4 as f64);
        let x = a.0 as f64 + (b.0 - a.0) as f64 * u;
        let y = a.1 as f64 + (b.1 - a.1) as f64 * u;
        Some((x.round() as i64, y.round() as i64))
    }

    /// Replace every piece by its chain through its split points.
    fn apply(&mut self, splits: Vec<Vec<u32>>) -> usize {
        let mut n = 0;
        let old = std::mem::take(&mut self.segs);
        for (s, mut sp) in old.into_iter().zip(splits) {
            sp.retain(|&v| v != s.a && v != s.b);
            if sp.is_empty() {
                self.segs.push(s);
                continue;
            }
            n += 1;
            let (a, b) = (self.pts[s.a as usize], self.pts[s.b as usize]);
            let (dx, dy) = (i128::from(b.0 - a.0), i128::from(b.1 - a.1));
            let param = |v: u32| {
                let p = self.pts[v as usize];
                i128::from(p.0 - a.0) * dx + i128::from(p.1 - a.1) * dy
            };
            sp.sort_by_key(|&v| (param(v), v));
            sp.dedup();
            let mut prev = s.a;
            for v in sp.into_iter().chain([s.b]) {
                if v != prev {
                    self.segs.push(Seg {
                        a: prev,
                        b: v,
                        shapes: s.shapes.clone(),
                    });
                }
                prev = v;
            }
        }
        self.dedup();
        n
    }
}

/// Snap `planar` (scaled coordinates) to the grid of pitch `delta` and split its
/// pieces until they are pairwise non-crossing and clear of foreign vertices.
pub(super) fn snap(planar: &PlanarInput, delta: f64) -> Snapped {
    let mut st = State {
        pts: Vec::with_capacity(planar.points.len()),
        index: HashMap::new(),
        segs: Vec::with_capacity(planar.pieces.len()),
    };
    let to_grid = |p: Point| ((p.x / delta).round() as i64, (p.y / delta).round() as i64);
    let map: Vec<u32> = planar
        .points
        .iter()
        .map(|&p| st.vertex(to_grid(p)))
        .collect();
    let mut dropped_zero = 0;
    for p in &planar.pieces {
        let (a, b) = (map[p.a as usize], map[p.b as usize]);
        if a == b {
            dropped_zero += 1;
            continue;
        }
        st.segs.push(Seg {
            a,
            b,
            shapes: vec![p.shape],
        });
    }
    st.dedup();
    let mut rounds = 0;
    let mut splits = 0;
    let mut clean = false;
    while rounds < MAX_ROUNDS {
        rounds += 1;
        let sp = st.find_splits();
        let n = st.apply(sp);
        splits += n;
        if n == 0 {
            clean = true;
            break;
        }
    }
    let mut dropped = 0;
    if !clean {
        // Drop the pieces that still offend (and forget the crossing points found).
        let n_pts = st.pts.len();
        let sp = st.find_splits();
        for p in st.pts.drain(n_pts..) {
            st.index.remove(&p);
        }
        let before = st.segs.len();
        let old = std::mem::take(&mut st.segs);
        st.segs = old
            .into_iter()
            .zip(sp)
            .filter(|(s, v)| v.iter().all(|&v| v == s.a || v == s.b))
            .map(|(s, _)| s)
            .collect();
        dropped = before - st.segs.len();
        tracing::warn!(
            dropped,
            "baseline: snap rounding did not settle; dropping the offending pieces"
        );
    }
    let points = st
        .pts
        .iter()
        .map(|&(x, y)| Point::new(x as f64 * delta, y as f64 * delta))
        .collect();
    let pieces = st
        .segs
        .iter()
        .flat_map(|s| {
            s.shapes.iter().map(|&shape| Piece {
                a: s.a,
                b: s.b,
                shape,
            })
        })
        .collect();
    Snapped {
        planar: PlanarInput {
            points,
            pieces,
            merged: planar.merged + planar.points.len() - map.iter().collect::<HashSet<_>>().len(),
            dropped_pieces: planar.dropped_pieces + dropped_zero,
        },
        rounds,
        splits,
        dropped,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Planar input from points and (a, b, shape) pieces.
    fn planar(points: &[(f64, f64)], pieces: &[(u32, u32, u32)]) -> PlanarInput {
        PlanarInput {
            points: points.iter().map(|&(x, y)| Point::new(x, y)).collect(),
            pieces: pieces
                .iter()
                .map(|&(a, b, s)| Piece {
                    a,
                    b,
                    shape: ShapeId::from_index(s as usize),
                })
                .collect(),
            merged: 0,
            dropped_pieces: 0,
        }
    }

    /// Check every guarantee of [`snap`] by brute force, in f64 geometry.
    fn assert_snapped(s: &Snapped, delta: f64) {
        let p = &s.planar.points;
        for q in p {
            assert_eq!((q.x / delta).fract(), 0.0, "{q:?} off the grid");
            assert_eq!((q.y / delta).fract(), 0.0, "{q:?} off the grid");
        }
        let distinct: HashSet<(u64, u64)> =
            p.iter().map(|q| (q.x.to_bits(), q.y.to_bits())).collect();
        assert_eq!(distinct.len(), p.len(), "duplicate points");
        let mut keys = HashSet::new();
        for piece in &s.planar.pieces {
            assert_ne!(piece.a, piece.b);
            assert!(keys.insert((piece.a.min(piece.b), piece.a.max(piece.b), piece.shape)));
        }
        let geo: Vec<(u32, u32)> = s
            .planar
            .pieces
            .iter()
            .map(|x| (x.a, x.b))
            .collect::<HashSet<_>>()
            .into_iter()
            .collect();
        for &(a, b) in &geo {
            let seg = kurbo::Line::new(p[a as usize], p[b as usize]);
            // No point near the interior.
            for (v, &q) in p.iter().enumerate() {
                if v as u32 == a || v as u32 == b {
                    continue;
                }
                let d = seg.p1 - seg.p0;
                let t = (q - seg.p0).dot(d) / d.hypot2();
                if t > 0.0 && t < 1.0 {
                    let dist = (q - seg.p0).cross(d).abs() / d.hypot();
                    assert!(
                        dist > 1.5 * delta,
                        "point {q:?} is {dist} from piece {seg:?}"
                    );
                }
            }
            // No proper crossing with another piece.
            for &(c, e) in &geo {
                if [a, b].contains(&c) || [a, b].contains(&e) {
                    continue;
                }
                let o = |u: Point, v: Point, w: Point| (v - u).cross(w - u);
                let (pc, pe) = (p[c as usize], p[e as usize]);
                let crosses = o(seg.p0, seg.p1, pc) * o(seg.p0, seg.p1, pe) < 0.0
                    && o(pc, pe, seg.p0) * o(pc, pe, seg.p1) < 0.0;
                assert!(!crosses, "{seg:?} crosses {pc:?}–{pe:?}");
            }
        }
    }

    #[test]
    fn crossing_t_junction_overlap_and_near_vertex() {
        let delta = 2f64.powi(-30);
        let cases = [
            // Two crossing segments.
            planar(
                &[(0.0, 0.0), (1.0, 0.7), (0.0, 0.7), (1.0, 0.0)],
                &[(0, 1, 0), (2, 3, 1)],
            ),
            // T-junction off by 1e-13.
            planar(
                &[(0.0, 0.0), (1.0, 0.0), (0.5, 1e-13), (0.5, 1.0)],
                &[(0, 1, 0), (2, 3, 1)],
            ),
            // Near-parallel overlap at angle 1e-14.
            planar(
                &[(0.0, 0.0), (1.0, 0.0), (0.1, 0.0), (0.9, 0.8e-14)],
                &[(0, 1, 0), (2, 3, 1)],
            ),
            // A lone vertex 1e-13 from a segment.
            planar(&[(0.0, 0.0), (1.0, 1.0), (0.3, 0.3 + 1e-13)], &[(0, 1, 0)]),
        ];
        let expect_pieces = [4, 3, 3, 2];
        for (c, n) in cases.iter().zip(expect_pieces) {
            let s = snap(c, delta);
            assert_snapped(&s, delta);
            assert_eq!(s.dropped, 0);
            let geo: HashSet<(u32, u32)> = s
                .planar
                .pieces
                .iter()
                .map(|x| (x.a.min(x.b), x.a.max(x.b)))
                .collect();
            assert_eq!(geo.len(), n, "{:?}", s.planar);
        }
        // The overlap keeps both owners on the shared middle piece.
        let s = snap(&cases[2], delta);
        assert_eq!(s.planar.pieces.len(), 4, "{:?}", s.planar.pieces);
    }

    #[test]
    fn grid_pitch_is_a_clamped_power_of_two() {
        assert_eq!(grid_pitch(1.0, 1e-9), 2f64.powi(-30));
        assert_eq!(grid_pitch(0.0, 1e-9), 2f64.powi(MIN_PITCH_EXP));
        assert_eq!(grid_pitch(1e300, 1.0), 1.0);
    }

    /// Near-degenerate soups: points on a coarse lattice nudged by 1e-13.. 1e-15.
    fn soup() -> impl Strategy<Value = PlanarInput> {
        let coord = prop_oneof![
            3 => (0..5i32, -2..=2i32).prop_map(|(i, e)| f64::from(i) / 4.0 + f64::from(e) * 1e-13),
            1 => 0.0..1.0f64,
        ];
        let pts = prop::collection::vec((coord.clone(), coord), 2..30);
        (
            pts,
            prop::collection::vec((0..30u32, 0..30u32, 0..3u32), 1..40),
        )
            .prop_map(|(pts, pieces)| {
                let n = pts.len() as u32;
                let pieces: Vec<_> = pieces
                    .into_iter()
                    .map(|(a, b, s)| (a % n, b % n, s))
                    .filter(|(a, b, _)| a != b)
                    .collect();
                planar(&pts, &pieces)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 200,
            failure_persistence: None,
            rng_algorithm: proptest::test_runner::RngAlgorithm::ChaCha,
            ..ProptestConfig::default()
        })]

        #[test]
        fn snapping_meets_its_guarantees(p in soup()) {
            let delta = 2f64.powi(-30);
            let s = snap(&p, delta);
            if s.dropped == 0 {
                assert_snapped(&s, delta);
            }
        }
    }
}
