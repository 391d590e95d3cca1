//! Endpoint snapping: the first sanitation of the input curves (thesis §4.3.1, "the
//! algorithm starts by sanitizing the input curves").
//!
//! Clip art is full of curve ends that are meant to meet but miss each other by a hair
//! (coordinates rounded to three decimals, closing segments a thousandth of a unit long).
//! Kept as they are, two such ends are two fixed feature vertices `1e-7·d` apart, and the
//! triangles between them can only be slivers whatever the optimization does. No mesh whose
//! edges are at least `l_m` long can tell such points apart anyway (the bounded-curvature
//! argument of §4.3 with the same `l_m`), so ends closer than `l_m` become one point here:
//!
//! - endpoints (and isolated points) are clustered greedily in input order: a point joins
//!   the nearest existing cluster centre within `tol`, or starts a new cluster at itself, so
//!   no point moves by more than `tol` and points that were bit-identical stay so;
//! - each curve end moves to its centre; a cubic's adjacent control point moves with it
//!   (the end tangent is kept), so no point of the curve moves by more than `tol`;
//! - a conic whose end moved stays an exact conic: it is mapped by the affine map that takes
//!   its ends to their centres and moves its control point by the mean of the two end
//!   moves (an affine image of a conic is the conic with the same weight and mapped
//!   controls). A point of the curve is a combination of the controls with positive
//!   weights summing to 1, so it moves by a convex combination of the three moves: at most
//!   `tol`. A circle may become a slightly different ellipse, and the end tangents turn
//!   slightly; a conic whose ends did not move is untouched, bit for bit;
//! - a curve that is left with both ends on one centre and every control point within `tol`
//!   of it is dropped (its neighbours' ends now meet at that centre), or becomes an isolated
//!   point if nothing else ends there.
//!
//! Guarantees: every output coordinate is within `tol` of the input one it comes from;
//! ends that were equal stay equal; the output order follows the input order.

use crate::svg::{Feature, FeatureGeom};
use kurbo::{Point, Vec2};
use rustc_hash::FxHashMap;

/// What snapping did.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Snapped {
    /// The snapped features (tiny ones dropped), each with its index in the input.
    pub(super) features: Vec<(u32, Feature)>,
    /// Ends (and points) that moved.
    pub(super) moved: usize,
    /// Curves dropped or turned into a point because they collapsed.
    pub(super) collapsed: usize,
}

/// Greedy clustering of points on a grid of cell `tol`.
struct Clusters {
    tol: f64,
    centres: Vec<Point>,
    /// How many curve ends (or points) use each centre.
    uses: Vec<usize>,
    grid: FxHashMap<(i64, i64), Vec<usize>>,
}

impl Clusters {
    fn cell(&self, p: Point) -> (i64, i64) {
        // Coordinates are bounded (Drawing::MAX_COORD), `tol` is positive: the casts saturate at worst.
        (
            (p.x / self.tol).floor() as i64,
            (p.y / self.tol).floor() as i64,
        )
    }

    /// The centre `p` snaps to (a new one at `p` if none is within `tol`).
    fn snap(&mut self, p: Point) -> usize {
        let (cx, cy) = self.cell(p);
        let mut best: Option<(f64, usize)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(ids) = self.grid.get(&(cx + dx, cy + dy)) {
                    for &i in ids {
                        let dist = self.centres[i].distance(p);
                        if dist <= self.tol && best.is_none_or(|(b, j)| (dist, i) < (b, j)) {
                            best = Some((dist, i));
                        }
                    }
                }
            }
        }
        let id = match best {
            Some((_, i)) => i,
            None => {
                let i = self.centres.len();
                self.centres.push(p);
                self.uses.push(0);
                self.grid.entry((cx, cy)).or_default().push(i);
                i
            }
        };
        self.uses[id] += 1;
        id
    }
}

/// Snap the ends of `features` that are closer than `tol` (user units; nothing happens
/// when `tol` is not positive).
pub(super) fn snap(features: &[Feature], tol: f64) -> Snapped {
    if !(tol > 0.0 && tol.is_finite()) {
        return Snapped {
            features: numbered(features.iter().copied()),
            ..Snapped::default()
        };
    }
    let mut clusters = Clusters {
        tol,
        centres: Vec::new(),
        uses: Vec::new(),
        grid: FxHashMap::default(),
    };
    // Ends as centre ids, in input order.
    let ends: Vec<[usize; 2]> = features
        .iter()
        .map(|f| match f.geom {
            FeatureGeom::Point(p) => {
                let i = clusters.snap(p);
                [i, i]
            }
            FeatureGeom::Line(l) => [clusters.snap(l.p0), clusters.snap(l.p1)],
            FeatureGeom::Cubic(c) => [clusters.snap(c.p0), clusters.snap(c.p3)],
            FeatureGeom::Conic(c) => [clusters.snap(c.p0), clusters.snap(c.p2)],
        })
        .collect();
    let mut out = Snapped::default();
    let mut moved = |from: Point, to: Point| {
        if from != to {
            out.moved += 1;
        }
        to - from
    };
    let mut snapped: Vec<(Feature, bool)> = Vec::with_capacity(features.len());
    for (f, &[a, b]) in features.iter().zip(&ends) {
        let (ca, cb) = (clusters.centres[a], clusters.centres[b]);
        let (geom, tiny) = match f.geom {
            FeatureGeom::Point(p) => {
                moved(p, ca);
                (FeatureGeom::Point(ca), false)
            }
            FeatureGeom::Line(mut l) => {
                moved(l.p0, ca);
                moved(l.p1, cb);
                l.p0 = ca;
                l.p1 = cb;
                (FeatureGeom::Line(l), a == b)
            }
            FeatureGeom::Cubic(mut c) => {
                let d0: Vec2 = moved(c.p0, ca);
                let d3: Vec2 = moved(c.p3, cb);
                c.p0 = ca;
                c.p1 += d0;
                c.p2 += d3;
                c.p3 = cb;
                let tiny = a == b && [c.p1, c.p2].iter().all(|p| p.distance(ca) <= tol);
                (FeatureGeom::Cubic(c), tiny)
            }
            FeatureGeom::Conic(mut c) => {
                let d0: Vec2 = moved(c.p0, ca);
                let d2: Vec2 = moved(c.p2, cb);
                c.p0 = ca;
                c.p1 += (d0 + d2) * 0.5;
                c.p2 = cb;
                let tiny = a == b && c.p1.distance(ca) <= tol;
                (FeatureGeom::Conic(c), tiny)
            }
        };
        snapped.push((
            Feature {
                geom,
                source: f.source,
            },
            tiny,
        ));
    }
    for (i, ((mut f, tiny), &[a, _])) in snapped.into_iter().zip(&ends).enumerate() {
        let i = u32::try_from(i).expect("internal: more than 2^32 features");
        if tiny {
            out.collapsed += 1;
            // Both ends count as uses of the centre: another feature ends there too iff
            // more than two uses remain.
            if clusters.uses[a] > 2 {
                clusters.uses[a] -= 2;
                continue;
            }
            f.geom = FeatureGeom::Point(clusters.centres[a]);
        }
        out.features.push((i, f));
    }
    out
}

fn numbered(features: impl Iterator<Item = Feature>) -> Vec<(u32, Feature)> {
    features
        .enumerate()
        .map(|(i, f)| {
            (
                u32::try_from(i).expect("internal: more than 2^32 features"),
                f,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::svg::FeatureSource;
    use kurbo::{CubicBez, Line};
    use proptest::prelude::*;

    fn feat(geom: FeatureGeom) -> Feature {
        Feature {
            geom,
            source: FeatureSource {
                shape: crate::svg::ShapeId::from_index(0),
                subpath: 0,
                segment: 0,
            },
        }
    }

    fn ends(f: &Feature) -> Vec<Point> {
        match f.geom {
            FeatureGeom::Point(p) => vec![p],
            FeatureGeom::Line(l) => vec![l.p0, l.p1],
            FeatureGeom::Cubic(c) => vec![c.p0, c.p3],
            FeatureGeom::Conic(c) => vec![c.p0, c.p2],
        }
    }

    #[test]
    fn near_ends_meet_and_a_tiny_closing_segment_goes() {
        let tol = 1e-3;
        let a = CubicBez::new((0.0, 0.0), (1.0, 1.0), (2.0, 1.0), (3.0, 0.0));
        // A closing segment 1e-4 long, then a cubic starting at its far end.
        let gap = Line::new((3.0, 0.0), (3.0001, 0.0));
        let b = CubicBez::new((3.0001, 0.0), (4.0, -1.0), (5.0, -1.0), (6.0, 0.0));
        let s = snap(
            &[
                feat(FeatureGeom::Cubic(a)),
                feat(FeatureGeom::Line(gap)),
                feat(FeatureGeom::Cubic(b)),
            ],
            tol,
        );
        assert_eq!(s.features.len(), 2, "{s:?}");
        assert_eq!(s.collapsed, 1);
        let (FeatureGeom::Cubic(a2), FeatureGeom::Cubic(b2)) =
            (s.features[0].1.geom, s.features[1].1.geom)
        else {
            panic!("two cubics expected: {s:?}");
        };
        assert_eq!(a2, a, "the first curve keeps its ends");
        assert_eq!(b2.p0, a.p3, "the second starts where the first ends");
        assert_eq!(b2.p1 - b2.p0, b.p1 - b.p0, "its end tangent is kept");
        assert_eq!(b2.p3, b.p3);
    }

    #[test]
    fn a_lone_tiny_curve_becomes_a_point_and_far_ends_stay() {
        let tol = 1e-3;
        let tiny = Line::new((5.0, 5.0), (5.0002, 5.0));
        let far = Line::new((0.0, 0.0), (0.0, 2e-3));
        let s = snap(
            &[feat(FeatureGeom::Line(tiny)), feat(FeatureGeom::Line(far))],
            tol,
        );
        assert_eq!(s.features.len(), 2);
        assert!(matches!(s.features[0].1.geom, FeatureGeom::Point(_)));
        assert_eq!(s.features[1].1.geom, FeatureGeom::Line(far));
        assert_eq!(s.features[1].0, 1);
        assert_eq!(s.moved, 1);
    }

    #[test]
    fn nothing_moves_without_tolerance() {
        let l = Line::new((0.0, 0.0), (1e-9, 0.0));
        let s = snap(&[feat(FeatureGeom::Line(l))], 0.0);
        assert_eq!(s.features, vec![(0, feat(FeatureGeom::Line(l)))]);
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]
        /// Every end moves by at most `tol`, equal ends stay equal, and no two distinct
        /// ends of the output are closer than `tol` unless they come from distinct centres
        /// chosen by input order (the greedy rule), which is checked as: every output end
        /// is a centre, and centres are pairwise more than `tol` apart.
        #[test]
        fn ends_move_at_most_tol_and_centres_are_separated(
            pts in prop::collection::vec((0i32..40, 0i32..40), 2..30),
            tol_milli in 1u32..30,
        ) {
            let tol = f64::from(tol_milli) * 1e-3;
            let p = |(x, y): (i32, i32)| Point::new(f64::from(x) * 7e-3, f64::from(y) * 7e-3);
            let feats: Vec<Feature> = pts
                .windows(2)
                .map(|w| feat(FeatureGeom::Line(Line::new(p(w[0]), p(w[1])))))
                .collect();
            let s = snap(&feats, tol);
            let mut out_ends: Vec<Point> = Vec::new();
            for (_, f) in &s.features {
                out_ends.extend(ends(f));
            }
            let in_ends: Vec<Point> = feats.iter().flat_map(ends).collect();
            for q in &out_ends {
                prop_assert!(in_ends.iter().any(|e| e.distance(*q) <= tol));
            }
            let mut centres: Vec<Point> = out_ends.clone();
            centres.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
            centres.dedup();
            for i in 0..centres.len() {
                for j in i + 1..centres.len() {
                    prop_assert!(centres[i].distance(centres[j]) > tol);
                }
            }
        }
    }

    #[test]
    fn a_conic_with_a_moved_end_stays_a_conic_and_moves_at_most_tol() {
        let tol = 1e-3;
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let q = crate::svg::drawing::Conic::new((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), w);
        // A line ending 4e-4 beside the conic's start: the conic's start moves there.
        let l = Line::new((2.0, 0.0), (1.0004, 0.0003));
        let s = snap(
            &[feat(FeatureGeom::Line(l)), feat(FeatureGeom::Conic(q))],
            tol,
        );
        let FeatureGeom::Conic(c) = s.features[1].1.geom else {
            panic!("a conic expected: {s:?}");
        };
        assert_eq!(c.p0, l.p1);
        assert_eq!(c.p2, q.p2);
        assert_eq!(c.w, q.w);
        assert!(((c.p1 - q.p1) - (l.p1 - q.p0) * 0.5).hypot() < 1e-15);
        for k in 0..=64 {
            let t = f64::from(k) / 64.0;
            assert!(c.eval(t).distance(q.eval(t)) <= tol);
        }
        // Nothing moved: bit for bit.
        let s = snap(&[feat(FeatureGeom::Conic(q))], tol);
        assert_eq!(s.features[0].1.geom, FeatureGeom::Conic(q));
    }
}
