//! Feature preprocessing: the loader's feature soup → [`FeatureSet`] (docs/design.md "features",
//! thesis §4.3.1 "Input preprocessing" and §4.4 "Feature processing for curved meshing").
//!
//! Conic pieces (arcs, circles, ellipses, rounded corners) stay exact: a section of a conic
//! keeps its [`Parent::Conic`] and its parameter interval, and its `ctrl` is a control hull
//! of the piece (same ends and end tangents), which every hull-based test below uses as it
//! uses a cubic's own control polygon.
//!
//! This module owns the classification of every input curve into *primary* discrete curve
//! sections (kept exactly, to be curved later) and *secondary* polylines (approximated
//! within ε), plus isolated points. The stages, in order:
//!
//! 0. `continuation`: consecutive pieces of one subpath that are pieces of one curve
//!    (collinear segments, arcs of one ellipse up to 90°) join into one curve, so their
//!    joints are no fixed vertices; then `snap`: curve ends (and points)
//!    closer than l_m meet at one point; curves that collapse with it go (the drawing
//!    moves by at most l_m).
//! 1. `classify`: degenerate curves (control points within ε_m of their mean) become
//!    points, straight curves (control points within ε_m of their least-squares line) become
//!    segments.
//! 2. `split`: cubics are split at inflections (det(c′, c″) = 0, eq. 4.1) and at
//!    zero-derivative points (cusps), then recursively where the tangent bisects the total
//!    turn, until every piece has constant-sign curvature and turns less than 180°. A conic
//!    piece (an ellipse arc of at most 90° of its parameter, or any rational quadratic of
//!    positive weight) has neither inflection nor cusp and turns less than 180°: it is only
//!    split where the turn limit of this stage requires it.
//!    Then `coincide`: outlines that coincide (equal curves, collinear segments
//!    overlapping, within ε_m, decided exactly) become one feature whose shapes
//!    share it (`FeatureSet::sharers`), so a shared boundary stays exact instead
//!    of two copies closer than μ demoting each other; then `crossings`.
//! 3. `resample`: pieces are halved until each is shorter than the size asked along it (at
//!    least [`SEPARATION_SIZE_PER_MU`] μ here), within μ of its chord and turns less than α
//!    (Theorem 4.4); a straight piece is cut where the integral of 1/h along it reaches whole
//!    numbers; parts with curvature above 2/l_m, and windows shorter than l_m (a cut next to
//!    a curve's end), are not eligible.
//! 4. `separation`: μ-separation (Definition 4.1), decided conservatively on the sections'
//!    control hulls with a uniform grid; a primary section shorter than μ that shares no end
//!    point with another primary section is demoted too (its fixed ends, within μ of the
//!    secondary features around it, would only force slivers); runs of secondary
//!    sections cut finer than a secondary section needs (the size field gives a thin
//!    stroke's size to its own outline only where that outline may be primary) are cut
//!    again at their secondary size; primary sections longer than the size asked (below
//!    the test's floor of [`SEPARATION_SIZE_PER_MU`] μ) are cut to it, every piece primary;
//!    then the secondary simplification (endpoints closer than μ collapse to their
//!    barycentre).
//! 5. `merge`: an open secondary polyline within μ of kept secondary segments of other
//!    polylines goes (the longest polylines stay first), so the lines of a hatch or a
//!    stroked soup closer than μ reach the linear mesher about μ apart.
//!
//! Guarantees to the next stage (checked by the property tests with an independent checker):
//! every primary section has constant-sign curvature, turns less than α, is no longer than
//! l and not shorter than l_m (control polygon), lies within μ of its chord; the sections as the
//! μ-separation judged them (each primary section, or the pieces cut from one of them to a
//! size below [`SEPARATION_SIZE_PER_MU`] μ, [`PrimarySection::judged`]) are at least μ away
//! from every section, secondary segment and point they do not share an endpoint with; no
//! primary chord crosses any other chord or secondary segment. Sections that share an endpoint share it bit for bit.
//! [`FeatureSet::conforming_input`] lists what the linear mesher must conform to.

mod build;
mod chains;
mod classify;
mod coincide;
mod continuation;
mod crossings;
pub(crate) mod grid;
mod json;
mod merge;
mod preview;
mod resample;
mod separation;
mod snap;
mod split;
mod trim;

pub(crate) use chains::PrimaryChains;
pub(crate) use json::to_json;
pub(crate) use preview::to_svg;

use crate::budget::Deadline;
use crate::params::Resolved;
use crate::svg::drawing::Conic;
use crate::svg::{Drawing, FeatureGeom, FeatureSource};
use kurbo::{CubicBez, Line, ParamCurve, ParamCurveDeriv, ParamCurveNearest, Point, Vec2};
use std::time::Instant;

/// Tolerance (relative to d) within which two conic pieces must lie on the one conic
/// that joins them (`continuation`): far below the 1e-9·d to which nodes must lie on the
/// drawing's curves, far above the rounding of the pieces' own evaluation.
const JOIN_TOL_REL: f64 = 1e-11;
/// The smallest size, in units of μ, that the sections are cut to for the
/// μ-separation test. Sections shorter than μ along one curve would be within
/// μ of their next-but-one and fail it against their own neighbours; at this
/// size and above a section's next-but-one along a curve that turns less than
/// α per section is more than μ away. Where a smaller size is asked, primary
/// sections are cut to it after the test (their pieces lie in their hulls, so
/// they keep the separation the test found).
pub(crate) const SEPARATION_SIZE_PER_MU: f64 = 4.0;
/// The trimming and resampling take the pieces in parallel, at least this
/// many to a task.
const RESAMPLE_CHUNK: usize = 16;
/// ... and at most this many at once.
const RESAMPLE_BLOCK: usize = 4096;

/// One piece trimmed and resampled ([`FeatureSet::build_sized`], step 3): its
/// sections, each with whether it starts a window (a crossing or a trimmed
/// piece before it), how many of its windows were trimmed, and how many cuts
/// where a shape painted above starts or stops covering it were added.
type Resampled = (Vec<(Section, bool)>, usize, usize);

/// What a section's size is asked for (see [`FeatureSet::build_sized`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CutFor {
    /// Any section, before μ-separation decides which are primary.
    Any,
    /// A run of secondary sections, after it: never smaller than for `Any`.
    Secondary,
}

/// Index of a primary section in [`FeatureSet::primary`]. `Debug` prints `p3`.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct SectionId(u32);

impl SectionId {
    /// The id of primary section `i`.
    ///
    /// # Panics
    /// If `i` does not fit in a `u32`.
    pub(crate) fn from_index(i: usize) -> Self {
        SectionId(u32::try_from(i).expect("internal: section count fits u32"))
    }

    /// The index into [`FeatureSet::primary`].
    pub(crate) fn index(self) -> usize {
        self.0 as usize
    }
}

impl std::fmt::Debug for SectionId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "p{}", self.index())
    }
}

/// Index of a secondary polyline in [`FeatureSet::secondary`]. `Debug` prints `q3`.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct PolylineId(u32);

impl PolylineId {
    /// The id of secondary polyline `i`.
    ///
    /// # Panics
    /// If `i` does not fit in a `u32`.
    pub(crate) fn from_index(i: usize) -> Self {
        PolylineId(u32::try_from(i).expect("internal: polyline count fits u32"))
    }

    /// The index into [`FeatureSet::secondary`].
    pub(crate) fn index(self) -> usize {
        self.0 as usize
    }

    /// The index as the `u32` a mesh edge's tag stores.
    pub(crate) fn raw(self) -> u32 {
        self.0
    }
}

impl std::fmt::Debug for PolylineId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "q{}", self.index())
    }
}

/// An isolated feature point: an input point, a degenerate curve, or a secondary polyline
/// that collapsed to a single point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FeaturePoint {
    /// Position (output coordinates).
    pub pos: Point,
    /// The input feature it came from.
    pub source: FeatureSource,
}

/// The input curve a section was cut from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Parent {
    /// An input cubic Bézier (parameter t of the cubic).
    Cubic(CubicBez),
    /// A straight segment: an input line, or a straight input cubic or conic replaced by the
    /// segment (or one of the collinear segments, if it folds back) it traces (parameter t
    /// of the segment, 0 at `p0`).
    Line(Line),
    /// An input conic piece, kept exact (parameter t of the rational quadratic; its weight
    /// is positive and finite: [`classify`] takes any other conic as its chord).
    Conic(Conic),
}

impl Parent {
    /// The point at parameter `t`; exactly the end points at `t = 0` and `t = 1`.
    pub(crate) fn eval(&self, t: f64) -> Point {
        match self {
            Parent::Cubic(c) if t == 0.0 => c.p0,
            Parent::Cubic(c) if t == 1.0 => c.p3,
            Parent::Cubic(c) => c.eval(t),
            Parent::Line(l) if t == 0.0 => l.p0,
            Parent::Line(l) if t == 1.0 => l.p1,
            Parent::Line(l) => l.p0.lerp(l.p1, t),
            Parent::Conic(c) => c.eval(t),
        }
    }

    /// The point at fraction `s ∈ [0, 1]` of the piece on `[t[0], t[1]]` (either order), in
    /// the curve's natural parametrization: where a curved edge's inner nodes go.
    /// Exactly `self.eval(t[0])` at `s = 0` and `self.eval(t[1])` at `s = 1`.
    ///
    /// A line: its own parameter, `t[0] + s (t[1] − t[0])`. A cubic: its own parameter
    /// too (the cubic Lagrange edge through the nodes at the parameter thirds is the piece
    /// itself), unless the piece's parametric speed is uneven (below
    /// [`CUBIC_EVEN_SPEED`] of its largest somewhere, as next to a control point that
    /// (nearly) coincides with its end point): then at fraction `s` of its arc length (see
    /// [`cubic_along`]). A conic: its angle.
    /// The piece's standard form (weight `w = cos h`) is an affine image of a circle arc
    /// from −h to h, traced at angle φ where `tan(φ/2) = (2σ − 1) tan(h/2)` (σ its own
    /// parameter): `s` maps to φ = h (A u + (1 − A) u³) with u = 2s − 1, so the nodes of a
    /// circle's edge are spaced nearly equally along it, an ellipse's in its eccentric
    /// angle. Interpolating there is 1.6–3× closer to the curve than at equal conic
    /// parameters (the rational parametrization's speed varies by 17% over a quarter
    /// circle). The mid node of a quadratic edge (u = 0) is the arc's midpoint; `A`
    /// (within 1% of 1, see [`area_matching_coefficient`]) puts the two inner nodes of a
    /// cubic edge (u = ∓1/3) where the cubic through the four nodes encloses exactly the
    /// conic's own area with the chord: every curved cubic edge on a conic then carries
    /// its exact area, and a cubic mesh of a disk has the disk's area to rounding.
    pub(crate) fn along(&self, t: [f64; 2], s: f64) -> Point {
        if s == 0.0 {
            return self.eval(t[0]);
        }
        if s == 1.0 {
            return self.eval(t[1]);
        }
        match self {
            Parent::Cubic(c) => self.eval(cubic_along(c, t, s)),
            Parent::Line(_) => self.eval(t[0] + s * (t[1] - t[0])),
            Parent::Conic(c) => {
                let piece = c.subsegment(t[0], t[1]);
                let h = piece.w.clamp(-1.0, 1.0).acos();
                let sigma = if h > CONIC_ANGLE_MIN {
                    let u = 2.0 * s - 1.0;
                    let a = area_matching_coefficient(h);
                    let phi = h * (a * u + (1.0 - a) * u * u * u);
                    0.5 * (1.0 + (0.5 * phi).tan() / (0.5 * h).tan())
                } else {
                    s
                };
                piece.eval(sigma)
            }
        }
    }

    /// The derivative `c′(t)`.
    pub(crate) fn deriv(&self, t: f64) -> Vec2 {
        match self {
            Parent::Cubic(c) => c.deriv().eval(t).to_vec2(),
            Parent::Line(l) => l.p1 - l.p0,
            Parent::Conic(c) => c.deriv(t),
        }
    }

    /// A control polygon of the restriction to `[t0, t1]`, whose convex hull contains
    /// that piece of the curve, with end points exactly `self.eval(t0)` and
    /// `self.eval(t1)` and the piece's end tangents (so its end-tangent angle is the
    /// piece's turn, its length bounds the arc length, and its inner points bound the
    /// distance to the chord).
    ///
    /// - Cubic: the restriction itself (de Casteljau), so it also evaluates the curve.
    /// - Line: collinear controls at 1/3 and 2/3.
    /// - Conic: only a hull, not the curve: [`Conic::hull_cubic`] of the standard-form
    ///   piece `subsegment(t0, t1)` (whose parameter is not the parent's), or its control
    ///   triangle (`p0, p1, p1, p2`) for a weight above 1, where the hull cubic would not
    ///   contain the curve.
    pub(crate) fn restrict(&self, t0: f64, t1: f64) -> CubicBez {
        let (a, b) = (self.eval(t0), self.eval(t1));
        match self {
            Parent::Cubic(c) => {
                let s = c.subsegment(t0..t1);
                CubicBez::new(a, s.p1, s.p2, b)
            }
            Parent::Line(_) => CubicBez::new(a, a.lerp(b, 1.0 / 3.0), a.lerp(b, 2.0 / 3.0), b),
            Parent::Conic(c) => {
                let s = c.subsegment(t0, t1);
                if s.w <= 1.0 {
                    let h = s.hull_cubic();
                    CubicBez::new(a, h.p1, h.p2, b)
                } else {
                    CubicBez::new(a, s.p1, s.p1, b)
                }
            }
        }
    }

    /// The distance from `p` to the curve's piece on `[t0, t1]`, found to `accuracy`
    /// (user units; kurbo's nearest-point search, or [`Conic::nearest`] on the
    /// standard-form piece).
    pub(crate) fn distance(&self, p: Point, t: [f64; 2], accuracy: f64) -> f64 {
        let accuracy = accuracy.max(MIN_NEAREST_ACCURACY);
        match self {
            Parent::Cubic(_) | Parent::Line(_) => self
                .restrict(t[0], t[1])
                .nearest(p, accuracy)
                .distance_sq
                .sqrt(),
            Parent::Conic(c) => c
                .subsegment(t[0], t[1])
                .nearest(p, accuracy)
                .distance_sq
                .sqrt(),
        }
    }

    /// Where the curvature of the piece on `[t0, t1]` (either order) changes sign: the
    /// parent cubic's inflections strictly inside, in increasing order (none for a line
    /// or a conic); `None` when a zero-derivative point (a cusp, where the tangent turns
    /// back) lies strictly inside. A section has neither (the feature stage splits
    /// there), but a chain of sections, along which the optimizer slides and collapses
    /// vertices, may have both.
    pub(crate) fn inflections_within(&self, t0: f64, t1: f64) -> Option<Vec<f64>> {
        let Parent::Cubic(c) = self else {
            return Some(Vec::new());
        };
        let (lo, hi) = (t0.min(t1), t0.max(t1));
        let inside = |t: f64| t > lo && t < hi;
        if split::cusps(c).into_iter().any(inside) {
            return None;
        }
        let mut ts: Vec<f64> = c.inflections().into_iter().filter(|&t| inside(t)).collect();
        ts.sort_by(f64::total_cmp);
        Some(ts)
    }

    /// Whether this is a straight segment.
    pub(crate) fn is_line(&self) -> bool {
        matches!(self, Parent::Line(_))
    }
}

/// A cubic piece whose parametric speed `|c′(t)|`, sampled at five equal steps of its
/// parameter, falls below this fraction of its largest sample has its edge nodes at equal
/// steps of arc length ([`Parent::along`]). At equal parameter steps the edge's speed,
/// and with it the element's `det J` along that edge, varies as the cubic's: a near
/// straight edge whose nodes bunch toward one end (tangential fractions 0.12 and 0.46
/// instead of 1/3 and 2/3) gave cubic elements of certified Jacobian ratio 0.006 on
/// straight-looking triangles. Below one half, the arc-length nodes give the edge a
/// nearly even speed; above it, the parameter thirds keep the piece exact. One half keeps
/// most order-3 edges exact and the certified ratios above 0.25 on the dev sample
/// (measurements in `docs/tuning.md`).
pub(crate) const CUBIC_EVEN_SPEED: f64 = 0.5;

/// The parameter of the node at fraction `s` of the cubic `c`'s piece on `[t[0], t[1]]`
/// ([`Parent::along`]): `t[0] + s (t[1] − t[0])` when the piece's parametric speed is
/// even (within [`CUBIC_EVEN_SPEED`]), else the parameter at fraction `s` of the piece's
/// arc length (kurbo's arc length inverse on the restriction, to 1e-9 of its control
/// polygon's length; symmetric in the direction of `t`, so both triangles on an edge and
/// either direction give the same nodes up to that accuracy).
fn cubic_along(c: &CubicBez, t: [f64; 2], s: f64) -> f64 {
    let at = |s: f64| t[0] + s * (t[1] - t[0]);
    let d = c.deriv();
    let speeds = [0.0, 0.25, 0.5, 0.75, 1.0].map(|s| d.eval(at(s)).to_vec2().hypot());
    let hi = speeds.iter().copied().fold(0.0, f64::max);
    let lo = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    if hi == 0.0 || lo >= CUBIC_EVEN_SPEED * hi {
        return at(s);
    }
    let piece = c.subsegment(t[0]..t[1]);
    let polygon = (piece.p1 - piece.p0).hypot()
        + (piece.p2 - piece.p1).hypot()
        + (piece.p3 - piece.p2).hypot();
    let accuracy = 1e-9 * polygon;
    let length = kurbo::ParamCurveArclen::arclen(&piece, accuracy);
    at(kurbo::ParamCurveArclen::inv_arclen(
        &piece,
        s * length,
        accuracy,
    ))
}

/// Below this half-angle (radians) a conic piece is traced at its own parameter by
/// [`Parent::along`] (the angle map tends to the identity; a weight of 1 or more has no
/// angle).
const CONIC_ANGLE_MIN: f64 = 1e-6;

/// The coefficient `A` of [`Parent::along`]'s angle map for a conic piece of half-angle
/// `h` (in its circle frame): the inner nodes of a cubic edge at angles ±β with
/// `β = h (8A + 1)/27` (u = ±1/3), where the cubic Lagrange curve through the circle's
/// points at −h, −β, β, h encloses with its chord the circular segment's area
/// `h − sin h cos h`. An affine map keeps area ratios, so the same angles serve every
/// ellipse. `A = 1` (equal angles) leaves a relative area error of about 0.075 h²
/// per edge; the matched β is `(h/3)(1 − 0.037 h² + …)`.
///
/// Solved by secant steps from the series start, to the rounding of the area
/// difference; below h = 1e-2 the series alone is exact to rounding (its next term is
/// below 1e-9 relative). Falls back to 1 if the iteration leaves its bracket.
pub(crate) fn area_matching_coefficient(h: f64) -> f64 {
    /// The series start's h² coefficient of 1 − 3β/h (fitted; the secant polishes it).
    const C2: f64 = 0.037_04;
    let from_beta = |beta: f64| ((27.0 * beta / h - 1.0) / 8.0).clamp(0.5, 1.5);
    let series = (h / 3.0) * (1.0 - C2 * h * h);
    if !(h > 0.0 && h <= std::f64::consts::FRAC_PI_2) {
        return 1.0;
    }
    if h < 1e-2 {
        return from_beta(series);
    }
    // the area between the cubic through the circle's points at −h, −β, β, h and its
    // chord, minus the segment's area (coordinates relative to the chord's midpoint)
    let (sh, ch) = h.sin_cos();
    let segment = h - sh * ch;
    let excess = |beta: f64| {
        let (sb, cb) = beta.sin_cos();
        let (a, p, q, b) = (
            Point::new(0.0, -sh),
            Point::new(cb - ch, -sb),
            Point::new(cb - ch, sb),
            Point::new(0.0, sh),
        );
        let [c1, c2] = crate::element::lagrange::cubic_edge_controls(a, p, q, b);
        let cubic = CubicBez::new(a, c1, c2, b);
        // the curve's area plus the chord's back (which is 0: the chord passes the origin)
        kurbo::ParamCurveArea::signed_area(&cubic) - segment
    };
    let (mut b0, mut b1) = (h / 3.0, series);
    let (mut f0, mut f1) = (excess(b0), excess(b1));
    for _ in 0..8 {
        if f1 == f0 || f1 == 0.0 {
            break;
        }
        let b2 = b1 - f1 * (b1 - b0) / (f1 - f0);
        if !(b2 > h / 6.0 && b2 < h / 2.0) {
            return 1.0;
        }
        (b0, f0) = (b1, f1);
        b1 = b2;
        f1 = excess(b1);
        if (b1 - b0).abs() <= 1e-15 * h {
            break;
        }
    }
    from_beta(b1)
}

/// Smallest accuracy passed to a nearest-point search (an accuracy of 0 would never
/// end kurbo's).
const MIN_NEAREST_ACCURACY: f64 = 1e-300;

/// A primary discrete curve section: a piece of one input curve that the mesh represents
/// by a single (later curved) edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PrimarySection {
    /// The curve it was cut from.
    pub parent: Parent,
    /// The input feature it came from.
    pub source: FeatureSource,
    /// The other shapes whose outlines run along it, if any (an index into
    /// [`FeatureSet::sharers`]).
    pub shared: Option<u32>,
    /// Parameter interval `[t0, t1]` on `parent`, `t0 < t1`.
    pub t: [f64; 2],
    /// Control polygon of the section itself: `parent` restricted to `t`
    /// ([`Parent::restrict`]: the piece itself for a cubic, a control hull of it for a
    /// conic). Collinear for a straight section. `ctrl.p0`/`ctrl.p3` are the chord the
    /// linear mesher conforms to.
    pub ctrl: CubicBez,
    /// The primary section that continues this one at `ctrl.p0`: the neighbour along the same
    /// subpath if it is primary, else the only other primary section ending there, else none.
    pub prev: Option<SectionId>,
    /// Same as `prev`, at `ctrl.p3`.
    pub next: Option<SectionId>,
    /// The section the μ-separation judged that this one was cut from: the
    /// consecutive pieces cut from one judged section share it (no other
    /// section does), and together they are that section.
    pub judged: u32,
}

impl PrimarySection {
    /// The chord: the straight edge the linear mesher conforms to.
    pub(crate) fn chord(&self) -> Line {
        Line::new(self.ctrl.p0, self.ctrl.p3)
    }
}

/// A secondary feature: a polyline within μ of (a run of consecutive secondary sections of)
/// one input curve, after the secondary simplification.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SecondaryPolyline {
    /// The vertices, at least two, consecutive ones distinct.
    pub points: Vec<Point>,
    /// The input feature it came from.
    pub source: FeatureSource,
    /// The other shapes whose outlines run along it, if any (an index into
    /// [`FeatureSet::sharers`]).
    pub shared: Option<u32>,
}

/// The piece of a feature that a segment of [`ConformingInput`] stands for:
/// a primary section's chord or one segment of a secondary polyline (the
/// pipeline makes the BSP's segment tag, copied onto mesh edges, from it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum FeaturePiece {
    /// The chord of a primary section.
    Primary(SectionId),
    /// Segment `index` (from `points[index]` to `points[index + 1]`) of a secondary polyline.
    Secondary {
        /// The polyline.
        polyline: PolylineId,
        /// The segment within it.
        index: u32,
    },
}

/// Everything the linear (BSP) mesher must conform to.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ConformingInput {
    /// Straight segments with what they represent; primary chords first.
    pub segments: Vec<(Line, FeaturePiece)>,
    /// Isolated points.
    pub points: Vec<Point>,
}

/// Counts of what preprocessing found and produced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct FeatureCounts {
    /// Input point features.
    pub input_points: usize,
    /// Input straight segments.
    pub input_lines: usize,
    /// Input cubics.
    pub input_cubics: usize,
    /// Input conic pieces (arcs, circles, ellipses, rounded corners).
    pub input_conics: usize,
    /// Joints removed between consecutive pieces of one curve (collinear segments, arcs
    /// of one ellipse), which become one input curve (step 0).
    pub joined_pieces: usize,
    /// Curve ends (and points) moved onto another end closer than l_m (step 0).
    pub snapped_ends: usize,
    /// Curves shorter than l_m that collapsed onto their snapped ends (step 0).
    pub snap_collapsed: usize,
    /// Curves (lines, cubics or conics) that degenerated to a point.
    pub degenerate: usize,
    /// Cubics and conics found straight and replaced by segments.
    pub straight: usize,
    /// Splits at inflections and zero-derivative points.
    pub inflection_splits: usize,
    /// Splits that halve a total curvature of 180° or more.
    pub curvature_splits: usize,
    /// Straight pieces split where another straight piece overlaps them
    /// (`coincide`).
    pub coincident_splits: usize,
    /// Pieces that coincided with an earlier one and went: their shapes share
    /// its feature (`coincide`).
    pub coincident_merged: usize,
    /// Transversal crossings of two curves where both were split (so the
    /// sections around a crossing share its point).
    pub crossing_splits: usize,
    /// Pieces of stroke areas, clipped fills, clip outlines and clipped centre
    /// lines dropped because they bound nothing painted (see `trim`).
    pub trimmed_pieces: usize,
    /// Where a stroke's outline was cut because an opaque shape painted above
    /// it starts or stops covering it (see `trim`): each a vertex where the
    /// kept outline ends on the covering shape's.
    pub cover_cuts: usize,
    /// Discrete curve sections after resampling.
    pub sections: usize,
    /// Sections not eligible because of curvature above 2/l_m (or a refinement budget).
    pub high_curvature: usize,
    /// Eligible sections demoted by the μ-separation test.
    pub not_separated: usize,
    /// Pieces added by cutting primary sections to a size asked below the
    /// separation's ([`SEPARATION_SIZE_PER_MU`] μ).
    pub refined_sections: usize,
    /// Primary sections left at the separation's size because cutting them
    /// to the size asked would pass the section budget (half the vertex
    /// budget, `--max-vertices`).
    pub unrefined_over_budget: usize,
    /// Primary sections shorter than μ sharing no end point with another primary
    /// section, demoted (a lone sliver-maker between secondary features).
    pub short_isolated: usize,
    /// Primary sections within μ of a periodic cell's side, demoted (they do
    /// not cross it at an angle of at least 4α).
    pub near_cell_sides: usize,
    /// Primary sections demoted after the secondary simplification moved a neighbour.
    pub demoted_after_simplify: usize,
    /// Secondary vertices moved by the simplification.
    pub collapsed_vertices: usize,
    /// Secondary segments dropped with their open polylines, which lie within μ
    /// of secondary segments of other polylines that stay (step 5, `merge`).
    pub merged_segments: usize,
    /// Primary sections.
    pub primary: usize,
    /// Secondary polylines.
    pub secondary_polylines: usize,
    /// Segments of all secondary polylines.
    pub secondary_segments: usize,
    /// Isolated points in the output.
    pub points: usize,
}

/// Wall time of each preprocessing stage, in milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub(crate) struct FeatureTiming {
    /// Degenerate / straight classification.
    pub classify_ms: f64,
    /// Inflection and total-curvature splits.
    pub split_ms: f64,
    /// Resampling into discrete curve sections.
    pub resample_ms: f64,
    /// μ-separation.
    pub separation_ms: f64,
    /// Secondary simplification and assembly of the output.
    pub simplify_ms: f64,
    /// Everything.
    pub total_ms: f64,
}

/// The preprocessed features: what the meshers consume (docs/design.md "features").
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FeatureSet {
    /// The absolute parameters it was built with.
    pub params: Resolved,
    /// Isolated points.
    pub points: Vec<FeaturePoint>,
    /// Primary sections, in input order (and along each input curve).
    pub primary: Vec<PrimarySection>,
    /// Secondary polylines.
    pub secondary: Vec<SecondaryPolyline>,
    /// Lists of shapes whose outlines run along a feature besides its own
    /// source's (`coincide`: copies merged into it), indexed by the
    /// features' `shared`; ascending, each once.
    pub sharers: Vec<Vec<crate::svg::ShapeId>>,
    /// Counts.
    pub counts: FeatureCounts,
    /// Per-stage timing.
    pub timing: FeatureTiming,
}

/// A discrete curve section before classification (shared by the stages).
#[derive(Clone, Copy, Debug)]
struct Section {
    /// Index into `Drawing::features`.
    feature: u32,
    /// Other shapes whose outlines run along it (index into
    /// [`FeatureSet::sharers`]; `coincide`).
    shared: Option<u32>,
    parent: Parent,
    t0: f64,
    t1: f64,
    ctrl: CubicBez,
    /// Satisfies the per-section primary conditions (curvature, turn, length, chord).
    eligible: bool,
}

fn ms(since: Instant) -> f64 {
    since.elapsed().as_secs_f64() * 1e3
}

impl FeatureSet {
    /// Preprocess the features of `drawing` with the absolute parameters `params`
    /// (`Params::resolve(drawing.diagonal())`) and the uniform size `l` (the
    /// tests' shorthand: the pipeline resamples against its size field, see
    /// [`FeatureSet::build_sized`]).
    ///
    /// Never fails and always terminates: every refinement loop has a budget; what exceeds
    /// it is made secondary.
    #[cfg(test)]
    pub(crate) fn build(drawing: &Drawing, params: &Resolved) -> FeatureSet {
        Self::build_within(drawing, params, &Deadline::NONE)
    }

    /// What a build stopped by its deadline returns: no sections, the counts and
    /// timings so far (the caller sees the deadline passed and discards it).
    fn incomplete(
        params: &Resolved,
        points: Vec<FeaturePoint>,
        counts: FeatureCounts,
        timing: FeatureTiming,
    ) -> FeatureSet {
        FeatureSet {
            params: *params,
            points,
            primary: Vec::new(),
            secondary: Vec::new(),
            sharers: Vec::new(),
            counts,
            timing,
        }
    }

    /// [`FeatureSet::build`] that gives up once `deadline` has passed: the
    /// set is then incomplete (the caller checks the deadline and discards it).
    #[cfg(test)]
    pub(crate) fn build_within(
        drawing: &Drawing,
        params: &Resolved,
        deadline: &Deadline,
    ) -> FeatureSet {
        Self::build_sized(drawing, params, deadline, &|_, _, _| params.l, usize::MAX)
    }

    /// Preprocess the features of `drawing` against the size field `size`
    /// (output units, at most `params.l`), giving up once `deadline` has passed
    /// (the set is then incomplete: the caller checks the deadline and discards
    /// it). Never fails and always terminates: every refinement loop has a
    /// budget; what exceeds it is made secondary. Curves are resampled into sections no longer than
    /// the size along them: `size(p, source, CutFor::Any)` is the size at `p` for a section of the
    /// input feature `source`; after μ-separation, runs of secondary sections are cut again
    /// where `size(p, source, CutFor::Secondary)` is larger (the pipeline gives a thin
    /// stroke's size to the stroke's own outline only, and only where it is primary:
    /// `SizeField::for_curve`).
    ///
    /// Primary sections are cut below the separation's size
    /// ([`SEPARATION_SIZE_PER_MU`] μ) only while the primary sections stay
    /// within `max_sections` (the pipeline gives half the vertex budget): past
    /// it they keep the separation's size, [`FeatureCounts::unrefined_over_budget`]
    /// counts them, and the optimizer refines toward the field as far as its
    /// budget goes.
    pub(crate) fn build_sized(
        drawing: &Drawing,
        params: &Resolved,
        deadline: &Deadline,
        size: &(dyn Fn(kurbo::Point, FeatureSource, CutFor) -> f64 + Sync),
        max_sections: usize,
    ) -> FeatureSet {
        let _span = tracing::debug_span!("features").entered();
        let start = Instant::now();
        let mut b = build::Build::new(drawing, params, deadline);
        let classified = b.classify();
        let Some(split) = b.split(classified) else {
            return b.incomplete();
        };
        let Some(resampled) = b.resample(&split, size) else {
            return b.incomplete();
        };
        let Some(separated) = b.separate(resampled, size, max_sections) else {
            return b.incomplete();
        };
        b.assemble(separated, split.sharers, start)
    }

    /// Every straight segment the linear mesher must conform to (primary chords, then the
    /// segments of secondary polylines) with what it represents, and every isolated point.
    pub(crate) fn conforming_input(&self) -> ConformingInput {
        let mut segments = Vec::with_capacity(self.primary.len() + self.counts.secondary_segments);
        for (i, s) in self.primary.iter().enumerate() {
            segments.push((s.chord(), FeaturePiece::Primary(SectionId::from_index(i))));
        }
        for (i, p) in self.secondary.iter().enumerate() {
            let polyline = PolylineId::from_index(i);
            for (k, w) in p.points.windows(2).enumerate() {
                let index = u32::try_from(k).expect("internal: polyline length fits u32");
                segments.push((
                    Line::new(w[0], w[1]),
                    FeaturePiece::Secondary { polyline, index },
                ));
            }
        }
        ConformingInput {
            segments,
            points: self.points.iter().map(|p| p.pos).collect(),
        }
    }
}

/// Build the primary sections with their adjacency.
fn assemble_primary(
    sections: &[Section],
    primary: &[bool],
    judged: &[u32],
    drawing: &Drawing,
) -> Vec<PrimarySection> {
    use std::collections::HashMap;
    let mut out = Vec::new();
    for (i, s) in sections.iter().enumerate() {
        if primary[i] {
            out.push(PrimarySection {
                judged: judged[i],
                parent: s.parent,
                source: drawing.features[s.feature as usize].source,
                shared: s.shared,
                t: [s.t0, s.t1],
                ctrl: s.ctrl,
                prev: None,
                next: None,
            });
        }
    }
    // Endpoint → primary sections incident there.
    let key = |p: Point| (p.x.to_bits(), p.y.to_bits());
    let mut at: HashMap<(u64, u64), Vec<u32>> = HashMap::new();
    for (i, s) in out.iter().enumerate() {
        let i = u32::try_from(i).expect("internal: section count fits u32");
        at.entry(key(s.ctrl.p0)).or_default().push(i);
        if s.ctrl.p3 != s.ctrl.p0 {
            at.entry(key(s.ctrl.p3)).or_default().push(i);
        }
    }
    let pick = |i: usize, p: Point, out: &[PrimarySection]| -> Option<SectionId> {
        let others: Vec<u32> = at[&key(p)]
            .iter()
            .copied()
            .filter(|&j| j as usize != i)
            .collect();
        let me = out[i].source;
        let same_subpath = others.iter().copied().find(|&j| {
            let o = out[j as usize].source;
            o.shape == me.shape && o.subpath == me.subpath
        });
        same_subpath
            .or_else(|| (others.len() == 1).then(|| others[0]))
            .map(|j| SectionId::from_index(j as usize))
    };
    for i in 0..out.len() {
        let prev = pick(i, out[i].ctrl.p0, &out);
        let next = pick(i, out[i].ctrl.p3, &out);
        out[i].prev = prev;
        out[i].next = next;
    }
    out
}

#[cfg(test)]
pub(crate) mod tests;
