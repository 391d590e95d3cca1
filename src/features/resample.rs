//! Curve resampling into discrete curve sections (thesis §4.4 "Curve resampling",
//! §4.3.1 "Bounded curvature", Theorem 4.4).
//!
//! A piece (constant-sign curvature, turn below 180°) is halved in parameter until every
//! section is *eligible* for primary: its control polygon is no longer than l (so its arc
//! is not either), its inner control points are within μ of the chord (so the curve is,
//! being in their convex hull), the angle between its end tangents is below α (its turn,
//! given the previous splits), and its curvature, sampled, is at most 2/l_m. For a conic
//! the control polygon is its hull ([`Parent::restrict`]: same ends and end tangents, the
//! conic inside), so the same bounds hold, and the curvature is the conic's own. A section
//! that breaks the curvature or turn condition when it is already no longer than μ (the
//! part around a cusp or a curvature spike) is kept as a *non-eligible* section: it will be
//! secondary. A section shorter than l_m (an inflection or crossing cut next to a curve's
//! end: the snap stage merged every end closer than that) is not eligible either: as a
//! primary section its two fixed end points would force a sliver of that size into the
//! mesh. A depth and count budget bounds the work on any input.

use super::split::{end_tangent, start_tangent};
use super::{CutFor, Parent, Section};
use crate::mesh::{angle_between, point_segment_distance};
use crate::params::Resolved;
use kurbo::{CubicBez, Line, ParamCurveCurvature};

/// Maximum halving depth of one piece.
const MAX_DEPTH: u32 = 48;
/// Maximum sections cut from one piece or line.
const MAX_SECTIONS: usize = 1 << 16;
/// Curvature samples per section (plus both ends).
const CURVATURE_SAMPLES: usize = 8;

/// One discrete curve section of a parent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Piece {
    pub(super) t0: f64,
    pub(super) t1: f64,
    /// `parent` restricted to `[t0, t1]`.
    pub(super) ctrl: CubicBez,
    /// Satisfies every per-section condition of a primary section.
    pub(super) eligible: bool,
}

/// Length of the control polygon (an upper bound of the arc length).
pub(super) fn polygon_length(c: &CubicBez) -> f64 {
    c.p0.distance(c.p1) + c.p1.distance(c.p2) + c.p2.distance(c.p3)
}

/// Upper bound of the distance from the curve to its chord.
fn chord_deviation(c: &CubicBez) -> f64 {
    let chord = Line::new(c.p0, c.p3);
    point_segment_distance(c.p1, chord).max(point_segment_distance(c.p2, chord))
}

/// Angle (radians, in [0, π]) between the end tangents.
fn end_tangent_angle(c: &CubicBez) -> f64 {
    let (u, v) = (start_tangent(c), end_tangent(c));
    if u.hypot2() == 0.0 || v.hypot2() == 0.0 {
        return std::f64::consts::PI;
    }
    angle_between(u, v)
}

/// Whether the curvature of `parent` on `[t0, t1]`, sampled, stays within `kappa_max` (a
/// non-finite value, at a zero-derivative point, does not). A cubic's section is sampled
/// on its own control polygon (the same curve), a conic's on the conic itself (its hull
/// cubic has another curvature).
fn curvature_bounded(parent: &Parent, t0: f64, t1: f64, ctrl: &CubicBez, kappa_max: f64) -> bool {
    (0..=CURVATURE_SAMPLES).all(|i| {
        let s = i as f64 / CURVATURE_SAMPLES as f64;
        let k = match parent {
            Parent::Conic(c) => c.curvature(t0 + s * (t1 - t0)),
            Parent::Cubic(_) | Parent::Line(_) => ctrl.curvature(s),
        };
        k.is_finite() && k.abs() <= kappa_max
    })
}

/// The smallest size of the field `size` at the ends and the middle of a
/// section (at most `r.l`).
fn size_along(ctrl: &CubicBez, r: &Resolved, size: &dyn Fn(kurbo::Point) -> f64) -> f64 {
    let mid = kurbo::ParamCurve::eval(ctrl, 0.5);
    r.l.min(size(ctrl.p0)).min(size(mid)).min(size(ctrl.p3))
}

/// Samples of the size along a line per size: the cuts follow a field that
/// changes by the grading from one element to the next to within a few
/// percent of its own integral.
const LINE_SAMPLES_PER_SIZE: f64 = 4.0;

/// The parameters that cut the line `l` on `[t0, t1]` into pieces that follow
/// the size field `size` (at most `l_max`), `t0` and `t1` included: as many
/// pieces as the integral of 1/h along the line rounded up, each spanning an
/// equal share of that integral, so a piece's length is the size at it where
/// the field varies (a graded field near a corner: the pieces shrink toward
/// it, instead of all taking the smallest size), and equal pieces where the
/// field is the same at every sample.
fn line_cuts(
    l: &Line,
    t0: f64,
    t1: f64,
    l_max: f64,
    size: &dyn Fn(kurbo::Point) -> f64,
) -> Vec<f64> {
    let len = l.length() * (t1 - t0);
    let at = |s: f64| {
        let f = if len > 0.0 {
            (s / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let t = t0 + (t1 - t0) * f;
        l_max.min(size(kurbo::ParamCurve::eval(l, t)))
    };
    // (arc length, size) samples, a fraction of the local size apart, and the
    // running integral of 1/h by the trapezoid rule.
    let mut samples = vec![(0.0, at(0.0))];
    let mut integral = vec![0.0];
    let (mut lo, mut hi) = (samples[0].1, samples[0].1);
    let mut s = 0.0;
    let max_samples = (LINE_SAMPLES_PER_SIZE as usize + 1) * MAX_SECTIONS;
    while s < len && samples.len() < max_samples {
        let h = samples.last().expect("internal: a first sample").1;
        let next = if samples.len() + 1 == max_samples {
            len
        } else {
            (s + h / LINE_SAMPLES_PER_SIZE).min(len)
        };
        if next <= s {
            break;
        }
        let hn = at(next);
        let acc = integral.last().expect("internal: a first integral")
            + 0.5 * (next - s) * (1.0 / h + 1.0 / hn);
        samples.push((next, hn));
        integral.push(acc);
        lo = lo.min(hn);
        hi = hi.max(hn);
        s = next;
    }
    let total = *integral.last().expect("internal: a first integral");
    let even = lo == hi || len == 0.0;
    let n = if even { len / lo } else { total }
        .ceil()
        .clamp(1.0, MAX_SECTIONS as f64) as usize;
    let mut ts = Vec::with_capacity(n + 1);
    ts.push(t0);
    let mut k = 1;
    for i in 1..n {
        let t = if even {
            t0 + (t1 - t0) * i as f64 / n as f64
        } else {
            let want = total * i as f64 / n as f64;
            while k + 1 < integral.len() && integral[k] < want {
                k += 1;
            }
            let (a, b) = (integral[k - 1], integral[k]);
            let f = if b > a {
                ((want - a) / (b - a)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let s = samples[k - 1].0 + f * (samples[k].0 - samples[k - 1].0);
            t0 + (t1 - t0) * (s / len)
        };
        if t > *ts.last().expect("internal: t0") && t < t1 {
            ts.push(t);
        }
    }
    ts.push(t1);
    ts
}

/// Cut `parent` on `[t0, t1]` into sections no longer than the size field
/// `size` along them (at most l). For a line: equal pieces.
pub(super) fn resample(
    parent: &Parent,
    t0: f64,
    t1: f64,
    r: &Resolved,
    size: &dyn Fn(kurbo::Point) -> f64,
) -> Vec<Piece> {
    let mut out = Vec::new();
    match parent {
        Parent::Line(l) => {
            let len = l.length() * (t1 - t0);
            let ts = line_cuts(l, t0, t1, r.l, size);
            for w in ts.windows(2) {
                out.push(Piece {
                    t0: w[0],
                    t1: w[1],
                    ctrl: parent.restrict(w[0], w[1]),
                    eligible: len >= r.l_min,
                });
            }
        }
        Parent::Cubic(_) | Parent::Conic(_) => {
            let mut stack = vec![(t0, t1, 0u32)];
            // Depth-first, left half first, so sections come out in parameter order.
            while let Some((a, b, depth)) = stack.pop() {
                let ctrl = parent.restrict(a, b);
                let len = polygon_length(&ctrl);
                let shape_ok = len <= size_along(&ctrl, r, size) && chord_deviation(&ctrl) <= r.mu;
                let turn_ok = end_tangent_angle(&ctrl) < r.alpha;
                let curvature_ok = curvature_bounded(parent, a, b, &ctrl, 2.0 / r.l_min);
                let m = 0.5 * (a + b);
                let can_split =
                    depth < MAX_DEPTH && out.len() + stack.len() < MAX_SECTIONS && m > a && m < b;
                // Too curved and already short: secondary. A turn of α or more with bounded
                // curvature always goes away by halving (turn ≤ length · 2/l_m).
                let long_enough = len >= r.l_min;
                let eligible = shape_ok && turn_ok && curvature_ok && long_enough;
                let done = eligible
                    || !long_enough
                    || (shape_ok && !curvature_ok && len <= r.mu)
                    || !can_split;
                if done {
                    out.push(Piece {
                        t0: a,
                        t1: b,
                        ctrl,
                        eligible,
                    });
                } else {
                    stack.push((m, b, depth + 1));
                    stack.push((a, m, depth + 1));
                }
            }
        }
    }
    out
}

/// Primary sections longer than the size asked along them (`size(section,
/// p)`) cut again at that size, each piece primary: the μ-separation judged
/// the sections at a size of at least [`super::SEPARATION_SIZE_PER_MU`] μ, and
/// a piece of a section lies in its control hull (a straight piece on its
/// segment), so what kept the section apart from every other keeps its pieces
/// apart; its pieces are neighbours along one curve, which separation never
/// compares. The section's end points stay bit for bit (crossing points).
/// When the pieces would take the primary sections past `max_primary`, no
/// section is cut (`unrefined` counts those that were to be).
pub(super) fn refine_primary(
    sections: Vec<Section>,
    primary: Vec<bool>,
    recut: Vec<bool>,
    r: &Resolved,
    size: &dyn Fn(&Section, kurbo::Point) -> f64,
    max_primary: usize,
) -> Refined {
    // (a hair over the size is rounding: n equal pieces of a line n·h long)
    let longer = |s: &Section| {
        polygon_length(&s.ctrl) > (1.0 + 1e-9) * size_along(&s.ctrl, r, &|p| size(s, p))
    };
    let unchanged = |sections: Vec<Section>, primary, recut, unrefined| {
        let judged = (0..sections.len() as u32).collect();
        Refined {
            sections,
            primary,
            recut,
            judged,
            added: 0,
            unrefined,
        }
    };
    let cut: Vec<bool> = sections
        .iter()
        .zip(&primary)
        .map(|(s, &p)| p && longer(s))
        .collect();
    let to_cut = cut.iter().filter(|&&c| c).count();
    if to_cut == 0 {
        return unchanged(sections, primary, recut, 0);
    }
    let mut out = Vec::with_capacity(sections.len());
    let mut out_primary = Vec::with_capacity(sections.len());
    let mut out_recut = Vec::with_capacity(sections.len());
    let mut judged = Vec::with_capacity(sections.len());
    let mut added = 0;
    let n_primary = primary.iter().filter(|&&p| p).count();
    let original = sections.clone();
    for (i, s) in sections.into_iter().enumerate() {
        let was_recut = recut.get(i).copied().unwrap_or(false);
        let id = u32::try_from(i).expect("internal: section count fits u32");
        if !cut[i] {
            out.push(s);
            out_primary.push(primary[i]);
            out_recut.push(was_recut);
            judged.push(id);
            continue;
        }
        let pieces = resample(&s.parent, s.t0, s.t1, r, &|p| size(&s, p));
        let n = pieces.len();
        added += n - 1;
        if n_primary + added > max_primary {
            return unchanged(original, primary, recut, to_cut);
        }
        // (a primary section's pieces stay eligible whatever their length)
        out.extend(as_sections(pieces, &s, s.ctrl.p3).map(|p| Section {
            eligible: true,
            ..p
        }));
        out_primary.extend(std::iter::repeat_n(true, n));
        out_recut.extend(std::iter::repeat_n(was_recut, n));
        judged.extend(std::iter::repeat_n(id, n));
    }
    Refined {
        sections: out,
        primary: out_primary,
        recut: out_recut,
        judged,
        added,
        unrefined: 0,
    }
}

/// `pieces` of `from`'s parent as sections of `from`'s feature, the first
/// starting at `from`'s start and the last ending at `end` bit for bit (the
/// pieces' own ends are the parent evaluated there; a run's ends may be
/// crossing points).
fn as_sections(
    pieces: Vec<Piece>,
    from: &Section,
    end: kurbo::Point,
) -> impl Iterator<Item = Section> {
    let n = pieces.len();
    let start = from.ctrl.p0;
    let from = *from;
    pieces.into_iter().enumerate().map(move |(k, p)| {
        let mut ctrl = p.ctrl;
        if k == 0 {
            ctrl.p0 = start;
        }
        if k + 1 == n {
            ctrl.p3 = end;
        }
        Section {
            t0: p.t0,
            t1: p.t1,
            ctrl,
            eligible: p.eligible,
            ..from
        }
    })
}

/// What [`refine_primary`] returns.
pub(super) struct Refined {
    /// The sections, in order.
    pub(super) sections: Vec<Section>,
    /// Whether each is primary.
    pub(super) primary: Vec<bool>,
    /// Whether each was cut again as a secondary run (`recut`, by section).
    pub(super) recut: Vec<bool>,
    /// By section: the section the μ-separation judged that it was cut from
    /// (its index then; the pieces of one judged section share it).
    pub(super) judged: Vec<u32>,
    /// Pieces added.
    pub(super) added: usize,
    /// Sections that were to be cut but stayed whole: their pieces would have
    /// passed `max_primary` primary sections.
    pub(super) unrefined: usize,
}

/// Runs of consecutive secondary sections (one feature, one parent, one window
/// between crossings: `window_start` by section) cut finer than a secondary
/// section needs (`size(section, p, CutFor::Secondary)` above
/// `size(section, p, CutFor::Any)` at some section's midpoint), cut again at
/// their secondary size; each run keeps its end points. Returns the sections,
/// whether each is primary, and whether each was cut again.
pub(super) fn recut_secondary(
    sections: Vec<Section>,
    primary: Vec<bool>,
    window_start: &[bool],
    r: &Resolved,
    size: &dyn Fn(&Section, kurbo::Point, CutFor) -> f64,
) -> (Vec<Section>, Vec<bool>, Vec<bool>) {
    let finer = |s: &Section| {
        let m = s.ctrl.p0.midpoint(s.ctrl.p3);
        size(s, m, CutFor::Secondary) > size(s, m, CutFor::Any)
    };
    if !sections.iter().zip(&primary).any(|(s, p)| !p && finer(s)) {
        return (sections, primary, Vec::new());
    }
    let mut out = Vec::with_capacity(sections.len());
    let mut out_primary = Vec::with_capacity(sections.len());
    let mut recut = Vec::with_capacity(sections.len());
    let mut i = 0;
    while i < sections.len() {
        let first = sections[i];
        if primary[i] {
            out.push(first);
            out_primary.push(true);
            recut.push(false);
            i += 1;
            continue;
        }
        let mut j = i + 1;
        while j < sections.len()
            && !primary[j]
            && !window_start[j]
            && sections[j].feature == first.feature
            && sections[j].parent == first.parent
            && sections[j].t0 == sections[j - 1].t1
            && sections[j].ctrl.p0 == sections[j - 1].ctrl.p3
        {
            j += 1;
        }
        if j - i >= 2 && sections[i..j].iter().any(finer) {
            let last = sections[j - 1];
            let pieces = resample(&first.parent, first.t0, last.t1, r, &|p| {
                size(&first, p, CutFor::Secondary)
            });
            if pieces.len() < j - i {
                let n = pieces.len();
                out.extend(as_sections(pieces, &first, last.ctrl.p3));
                out_primary.extend(std::iter::repeat_n(false, n));
                recut.extend(std::iter::repeat_n(true, n));
                i = j;
                continue;
            }
        }
        out.extend_from_slice(&sections[i..j]);
        out_primary.extend(std::iter::repeat_n(false, j - i));
        recut.extend(std::iter::repeat_n(false, j - i));
        i = j;
    }
    (out, out_primary, recut)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    #[test]
    fn quarter_circle_is_cut_in_sixteen_equal_parameter_steps() {
        // Unit circle: d = 2√2 with four quarters, l = d/20 ≈ 0.1414, arc π/2 ≈ 1.571:
        // halving needs 2⁴ = 16 pieces (0.098 each; 8 would be 0.196 > l).
        let r = Params::DEFAULT.resolve(2.0 * 2f64.sqrt());
        let k = 0.552_284_749_8;
        let c = CubicBez::new((1.0, 0.0), (1.0, k), (k, 1.0), (0.0, 1.0));
        let ps = resample(&Parent::Cubic(c), 0.0, 1.0, &r, &|_| r.l);
        assert_eq!(ps.len(), 16);
        for (i, p) in ps.iter().enumerate() {
            assert_eq!(p.t0, i as f64 / 16.0);
            assert!(p.eligible);
        }
    }

    #[test]
    fn line_pieces_are_no_longer_than_l_and_share_end_points() {
        let r = Params::DEFAULT.resolve(20.0);
        let l = Line::new((0.0, 0.0), (10.0, 0.0));
        let ps = resample(&Parent::Line(l), 0.0, 1.0, &r, &|_| r.l);
        assert_eq!(ps.len(), 10);
        assert_eq!(ps[0].ctrl.p0, l.p0);
        assert_eq!(ps[9].ctrl.p3, l.p1);
        for w in ps.windows(2) {
            assert_eq!(w[0].ctrl.p3, w[1].ctrl.p0);
        }
    }

    #[test]
    fn windows_shorter_than_l_min_are_one_non_eligible_section() {
        // An inflection or crossing cut 1e-7·d from a curve's end leaves a window far
        // below l_m: it must not become a primary section (two fixed ends 1e-7·d apart).
        let d = 2.0 * 2f64.sqrt();
        let r = Params::DEFAULT.resolve(d);
        let k = 0.552_284_749_8;
        let c = CubicBez::new((1.0, 0.0), (1.0, k), (k, 1.0), (0.0, 1.0));
        let ps = resample(&Parent::Cubic(c), 0.0, 1e-7, &r, &|_| r.l);
        assert_eq!(ps.len(), 1);
        assert!(!ps[0].eligible);
        let l = Line::new((0.0, 0.0), (1.0, 0.0));
        let ps = resample(&Parent::Line(l), 1.0 - 1e-7, 1.0, &r, &|_| r.l);
        assert_eq!(ps.len(), 1);
        assert!(!ps[0].eligible);
        // Just above l_m both stay eligible.
        let t = 2.0 * r.l_min;
        assert!(resample(&Parent::Line(l), 0.0, t, &r, &|_| r.l)[0].eligible);
        assert!(
            resample(&Parent::Cubic(c), 0.0, t, &r, &|_| r.l)
                .iter()
                .all(|p| p.eligible)
        );
    }

    #[test]
    fn exact_quarter_circle_is_cut_like_its_cubic_and_keeps_its_curvature() {
        // The same halving as the cubic quarter (16 sections at the default l), and
        // every section's ends on the circle, its hull around the arc.
        let r = Params::DEFAULT.resolve(2.0 * 2f64.sqrt());
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let c = crate::svg::drawing::Conic::new((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), w);
        let ps = resample(&Parent::Conic(c), 0.0, 1.0, &r, &|_| r.l);
        assert_eq!(ps.len(), 16);
        assert_eq!(ps[0].ctrl.p0, c.p0);
        assert_eq!(ps[15].ctrl.p3, c.p2);
        for (i, p) in ps.iter().enumerate() {
            assert!(p.eligible, "{p:?}");
            assert_eq!(p.ctrl.p0, c.eval(p.t0));
            assert!((p.ctrl.p0.to_vec2().hypot() - 1.0).abs() < 1e-15);
            if i > 0 {
                assert_eq!(p.t0, ps[i - 1].t1);
            }
        }
        // Curvature 1 everywhere on the conic; its hull cubic (an elevated quadratic)
        // goes from 0.5 at the ends to √2 in the middle: the conic's own is used.
        let hull = Parent::Conic(c).restrict(0.0, 1.0);
        assert!(curvature_bounded(
            &Parent::Conic(c),
            0.0,
            1.0,
            &hull,
            1.0 + 1e-9
        ));
        assert!(!curvature_bounded(
            &Parent::Conic(c),
            0.0,
            1.0,
            &hull,
            1.0 - 1e-9
        ));
        assert!(!curvature_bounded(
            &Parent::Cubic(hull),
            0.0,
            1.0,
            &hull,
            1.0 + 1e-9
        ));
    }
}
