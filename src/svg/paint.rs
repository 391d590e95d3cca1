//! SVG's paint model beyond flat fills: what is painted at all (visibility,
//! opacity), strokes as the areas they cover (exact offsets where the path is
//! a smooth closed chain of lines and circular arcs, else kurbo's stroke
//! expansion far below μ), and paint servers (gradients) summarised by their
//! mean opacity and colour.

use super::conic::Conic;
use super::drawing::{Segment, Subpath};
use super::outline::{Verb, subpaths};
use kurbo::{Affine, BezPath, ParamCurve, PathEl, Point, Vec2};

/// What becomes of strokes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StrokeMode {
    /// A stroke is the area it paints: a shape of its own (`<name>-stroke`),
    /// right after (or, with `paint-order: stroke`, before) its fill. Strokes
    /// thinner than [`PaintOptions::min_stroke_width`] or [`PaintOptions::mu`]
    /// stay centre lines; a stroke of its fill's opaque paint joins the fill's
    /// region ([`crate::ShapePaint::joins_fill`]).
    Area,
    /// A stroke is its centre line: feature geometry, no region.
    Line,
    /// Strokes are left out (a stroke-only path gives nothing).
    Ignore,
}

/// How the loader reads SVG's paint model (`--strokes`, `--min-opacity`,
/// `--keep-decoration`, and the hairline width from `--l-min`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct PaintOptions {
    /// What strokes become. Default [`StrokeMode::Area`].
    pub strokes: StrokeMode,
    /// A fill or stroke whose effective opacity (group opacities × paint opacity
    /// × a gradient's mean stop opacity) is below this is decoration: no region.
    /// Default 0.5.
    pub min_opacity: f32,
    /// Keep the outline of decoration as feature geometry (never a region).
    /// Default false.
    pub keep_decoration: bool,
    /// Strokes narrower than this (output units, after transforms) stay centre
    /// lines; relative to the drawing's diagonal when `min_stroke_relative`.
    pub min_stroke_width: f64,
    /// Whether `min_stroke_width` is a fraction of the diagonal of the drawing's
    /// outlines (strokes not counted) rather than an absolute width.
    pub min_stroke_relative: bool,
    /// The feature envelope μ (output units, or a fraction of the diagonal when
    /// `mu_relative`): a stroke narrower stays its centre line, since its two
    /// outlines would be closer than μ and the features stage would not keep
    /// them apart (counted in [`crate::PaintCounts::strokes_below_mu`]).
    /// Default 1e-3 of the diagonal (the default μ).
    pub mu: f64,
    /// Whether `mu` is a fraction of the diagonal.
    pub mu_relative: bool,
    /// How far a stroke's outlines may lie from the exact offset curves, as a
    /// fraction of the diagonal (and never more than 1/200 of the width).
    /// Default 1e-6, a thousandth of the default μ (circles, arcs and lines
    /// joined smoothly are offset exactly whatever it is). On 20 stroked dev
    /// drawings 1e-7 cost 2 % more triangles than kurbo's old 1/200 of the
    /// width, 1e-6 none (0.7 % fewer), 1e-5 2 % fewer.
    pub stroke_accuracy: f64,
}

impl PaintOptions {
    /// Strokes as areas, min opacity 0.5, decoration dropped, hairlines below
    /// 1e-4 of the diagonal (the default l_min).
    pub const DEFAULT: PaintOptions = PaintOptions {
        strokes: StrokeMode::Area,
        min_opacity: 0.5,
        keep_decoration: false,
        min_stroke_width: 1e-4,
        min_stroke_relative: true,
        mu: 1e-3,
        mu_relative: true,
        stroke_accuracy: 1e-6,
    };
    /// Every outline as written: strokes as centre lines, no decoration (only
    /// what is not painted at all is left out); the loader's geometry tests.
    #[cfg(test)]
    pub(crate) const OUTLINES: PaintOptions = PaintOptions {
        strokes: StrokeMode::Line,
        min_opacity: 0.0,
        keep_decoration: true,
        min_stroke_width: 1e-4,
        min_stroke_relative: true,
        mu: 1e-3,
        mu_relative: true,
        stroke_accuracy: 1e-6,
    };
    /// Set what strokes become.
    pub fn with_strokes(mut self, strokes: StrokeMode) -> Self {
        self.strokes = strokes;
        self
    }
    /// Set the opacity below which paint is decoration.
    pub fn with_min_opacity(mut self, min_opacity: f32) -> Self {
        self.min_opacity = min_opacity;
        self
    }
    /// Keep (or drop) the outlines of decoration.
    pub fn with_keep_decoration(mut self, keep: bool) -> Self {
        self.keep_decoration = keep;
        self
    }
    /// Set the hairline width: strokes narrower stay lines (`relative`: a
    /// fraction of the drawing's diagonal).
    pub fn with_min_stroke_width(mut self, width: f64, relative: bool) -> Self {
        self.min_stroke_width = width;
        self.min_stroke_relative = relative;
        self
    }
    /// Set the feature envelope μ: strokes narrower stay lines (`relative`: a
    /// fraction of the drawing's diagonal).
    pub fn with_mu(mut self, mu: f64, relative: bool) -> Self {
        self.mu = mu;
        self.mu_relative = relative;
        self
    }
    /// Set how far a stroke's outlines may lie from the exact offsets (a
    /// fraction of the diagonal).
    pub fn with_stroke_accuracy(mut self, accuracy: f64) -> Self {
        self.stroke_accuracy = accuracy;
        self
    }
}

impl Default for PaintOptions {
    fn default() -> Self {
        PaintOptions::DEFAULT
    }
}

/// A paint's own opacity factor: 1 for a colour or pattern, the mean opacity of
/// a gradient's stops over its offsets (piecewise linear between stops,
/// constant beyond the ends).
pub(super) fn server_alpha(paint: &usvg::Paint) -> f32 {
    match stops(paint) {
        Some(stops) => mean_over_offsets(stops, |s| s.opacity().get()),
        None => 1.0,
    }
}

/// The id of a paint server, `None` for a plain colour.
pub(super) fn server_id(paint: &usvg::Paint) -> Option<String> {
    match paint {
        usvg::Paint::Color(_) => None,
        usvg::Paint::LinearGradient(g) => Some(g.id().to_owned()),
        usvg::Paint::RadialGradient(g) => Some(g.id().to_owned()),
        usvg::Paint::Pattern(p) => Some(p.id().to_owned()),
    }
    .filter(|s| !s.is_empty())
}

/// The average colour of a gradient, its stops weighted by opacity over their
/// offsets (`None` for a colour or pattern, or a gradient with no opaque stop).
pub(super) fn average_colour(paint: &usvg::Paint) -> Option<[u8; 3]> {
    let stops = stops(paint)?;
    let weight = mean_over_offsets(stops, |s| s.opacity().get());
    if weight <= 0.0 {
        return None;
    }
    let channel = |c: fn(&usvg::Stop) -> u8| {
        let m = mean_over_offsets(stops, |s| s.opacity().get() * f32::from(c(s)));
        (m / weight).round().clamp(0.0, 255.0) as u8
    };
    Some([
        channel(|s| s.color().red),
        channel(|s| s.color().green),
        channel(|s| s.color().blue),
    ])
}

fn stops(paint: &usvg::Paint) -> Option<&[usvg::Stop]> {
    match paint {
        usvg::Paint::LinearGradient(g) => Some(g.stops()),
        usvg::Paint::RadialGradient(g) => Some(g.stops()),
        _ => None,
    }
    .filter(|s| !s.is_empty())
}

/// The mean of `f` over offsets 0..1, linear between stops, constant outside.
fn mean_over_offsets(stops: &[usvg::Stop], f: impl Fn(&usvg::Stop) -> f32) -> f32 {
    let first = &stops[0];
    let last = &stops[stops.len() - 1];
    let mut total = first.offset().get() * f(first) + (1.0 - last.offset().get()) * f(last);
    for w in stops.windows(2) {
        let dx = w[1].offset().get() - w[0].offset().get();
        total += dx * 0.5 * (f(&w[0]) + f(&w[1]));
    }
    total
}

/// The area a stroke paints: its outline subpaths (to fill by the nonzero
/// rule), and how many of the stroked subpaths got exact offsets.
pub(super) struct StrokeArea {
    /// The area's outline, in output coordinates.
    pub(super) subpaths: Vec<Subpath>,
    /// Closed subpaths of the centre line offset exactly ([`exact_offsets`]).
    pub(super) exact: usize,
    /// The stroke was dashed, but every gap of its pattern is narrower than
    /// μ: it was stroked whole ([`dash_gaps_below`]).
    pub(super) dashes_closed: bool,
}

/// Whether every gap of a dash pattern (user units) is shorter than `mu`
/// (output units) under a map that stretches lengths by at most `stretch`:
/// the two dashes on either side of any gap would lie closer than the feature
/// envelope, which does not keep them apart (a hatch of secondary sections
/// every gap wide, the dashes' ends moved within ε of each other), so the
/// pattern is detail below the envelope and the stroke is meshed whole. An
/// odd-length pattern repeats, each entry a gap in turn (SVG 2, §13.5.6).
pub(super) fn dash_gaps_below(dashes: &[f64], stretch: f64, mu: f64) -> bool {
    if dashes.is_empty() {
        return false;
    }
    // Even: the odd entries are the gaps; odd: every entry is one in turn.
    let step = if dashes.len() % 2 == 0 { 2 } else { 1 };
    dashes
        .iter()
        .skip(step - 1)
        .step_by(step)
        .all(|&g| g * stretch < mu)
}

/// The area `stroke` paints along `outline` (output coordinates), as subpaths to
/// fill by the nonzero rule; `to_output` maps the path's user space (where the
/// stroke's width, dashes and joins are defined) to output coordinates.
/// `accuracy` (output units) bounds the distance of the outlines from the
/// exact offset curves: a closed subpath of lines and circular arcs that turns
/// smoothly everywhere gets its exact offsets (parallel lines, concentric
/// conics: [`exact_offsets`]); any other goes through kurbo's stroke expansion
/// at that tolerance (at most 1/200 of the width), its conic pieces first
/// turned into cubics within a quarter of it.
/// `None` if the map is singular or the stroke paints nothing.
///
/// A dashed stroke whose every gap is shorter than `mu` (output units) is
/// stroked whole ([`dash_gaps_below`]).
pub(super) fn stroke_area(
    outline: &[Subpath],
    stroke: &usvg::Stroke,
    to_output: Affine,
    accuracy: f64,
    mu: f64,
) -> Option<StrokeArea> {
    let det = to_output.determinant();
    if !(det.abs() > 0.0 && det.is_finite()) {
        return None;
    }
    let to_user = to_output.inverse();
    let width = f64::from(stroke.width().get());
    // the largest stretch of the map: user-space lengths grow at most by it
    let [a, b, c, d, _, _] = to_output.as_coeffs();
    let (sq, prod) = (a * a + b * b + c * c + d * d, (a * d - b * c).abs());
    let stretch = (0.5 * (sq + (sq * sq - 4.0 * prod * prod).max(0.0).sqrt())).sqrt();
    let tolerance = (width * 5e-3).min(accuracy / stretch);
    let pattern: Option<Vec<f64>> = stroke
        .dasharray()
        .map(|d| d.iter().map(|&v| f64::from(v)).collect());
    let dashes_closed = pattern
        .as_deref()
        .is_some_and(|d| dash_gaps_below(d, stretch, mu));
    let pattern = pattern.filter(|_| !dashes_closed);
    let dashed = pattern.is_some();
    let mut out_verbs: Vec<Verb> = Vec::new();
    let mut exact = 0;
    let mut path = BezPath::new();
    for sp in outline {
        let user = Subpath {
            segments: sp.segments.iter().map(|s| s.transform(to_user)).collect(),
            start: to_user * sp.start,
            closed: sp.closed,
        };
        if !dashed {
            if let Some(verbs) = exact_offsets(&user, 0.5 * width) {
                out_verbs.extend(verbs);
                exact += 1;
                continue;
            }
        }
        path.move_to(user.start);
        if user.segments.is_empty() {
            // a lone point: a zero-length subpath (caps may paint it)
            path.line_to(user.start);
        }
        for seg in &user.segments {
            match *seg {
                Segment::Line(l) => path.line_to(l.p1),
                Segment::Cubic(c) => path.curve_to(c.p1, c.p2, c.p3),
                Segment::Conic(c) => {
                    for k in conic_cubics(c, 0.25 * tolerance) {
                        path.curve_to(k.p1, k.p2, k.p3);
                    }
                }
            }
        }
        if user.closed {
            path.close_path();
        }
    }
    let join = match stroke.linejoin() {
        usvg::LineJoin::Miter | usvg::LineJoin::MiterClip => kurbo::Join::Miter,
        usvg::LineJoin::Round => kurbo::Join::Round,
        usvg::LineJoin::Bevel => kurbo::Join::Bevel,
    };
    let cap = match stroke.linecap() {
        usvg::LineCap::Butt => kurbo::Cap::Butt,
        usvg::LineCap::Round => kurbo::Cap::Round,
        usvg::LineCap::Square => kurbo::Cap::Square,
    };
    let mut style = kurbo::Stroke::new(width)
        .with_join(join)
        .with_miter_limit(f64::from(stroke.miterlimit().get()))
        .with_caps(cap);
    if let Some(dashes) = pattern {
        style = style.with_dashes(f64::from(stroke.dashoffset()), dashes);
    }
    if !path.elements().is_empty() {
        let area = kurbo::stroke(path, &style, &kurbo::StrokeOpts::default(), tolerance);
        out_verbs.extend(area.elements().iter().map(|el| match *el {
            PathEl::MoveTo(p) => Verb::Move(p),
            PathEl::LineTo(p) => Verb::Line(p),
            PathEl::QuadTo(a, b) => Verb::Quad(a, b),
            PathEl::CurveTo(a, b, c) => Verb::Cubic(a, b, c),
            PathEl::ClosePath => Verb::Close,
        }));
    }
    let out: Vec<Subpath> = subpaths(out_verbs.iter().map(|v| v.transform(to_output)))
        .into_iter()
        .filter(|s| !s.segments.is_empty())
        .collect();
    (!out.is_empty()).then_some(StrokeArea {
        subpaths: out,
        exact,
        dashes_closed,
    })
}

/// Cubics within `tolerance` of the conic `c` (its usual cubic approximation
/// on pieces halved until the sampled distance to the conic is below it).
fn conic_cubics(c: Conic, tolerance: f64) -> Vec<kurbo::CubicBez> {
    let mut out = Vec::new();
    let mut todo = vec![(c, 0u32)];
    while let Some((piece, depth)) = todo.pop() {
        let k = piece.approx_cubic();
        let off = [0.2, 0.4, 0.6, 0.8]
            .iter()
            .map(|&t| {
                piece
                    .nearest(k.eval(t), 1e-3 * tolerance)
                    .distance_sq
                    .sqrt()
            })
            .fold(0.0, f64::max);
        if off <= tolerance || depth >= 8 {
            out.push(k);
        } else {
            // depth first, the second half below the first: output in order
            todo.push((piece.subsegment(0.5, 1.0), depth + 1));
            todo.push((piece.subsegment(0.0, 0.5), depth + 1));
        }
    }
    out
}

/// The centre and radius of a conic piece that is a circular arc (to 1e-9
/// relative), with the sign of its turn (+1 left, −1 right); `None` otherwise.
fn circular(c: &Conic) -> Option<(Point, f64, f64)> {
    let (u, v) = (c.p1 - c.p0, c.p2 - c.p1);
    let (lu, lv) = (u.hypot(), v.hypot());
    if !(lu > 0.0 && lv > 0.0) || (lu - lv).abs() > 1e-9 * lu.max(lv) {
        return None;
    }
    if !(c.w > 0.0 && c.w < 1.0) {
        return None;
    }
    // the turn 2h between the end tangents: cos 2h = 2w² − 1
    let cos_turn = u.dot(v) / (lu * lv);
    if (cos_turn - (2.0 * c.w * c.w - 1.0)).abs() > 1e-9 {
        return None;
    }
    let side = u.cross(v).signum();
    let tan_h = (1.0 - c.w * c.w).sqrt() / c.w;
    let r = lu / tan_h;
    let normal = Vec2::new(-u.y, u.x) / lu;
    let centre = c.p0 + normal * (side * r);
    // the end must be on the same circle
    let on_circle = ((c.p2 - centre).hypot() - r).abs() <= 1e-9 * r;
    (on_circle && r.is_finite() && side != 0.0).then_some((centre, r, side))
}

/// The exact outline of a stroke of half width `half` along the closed
/// subpath `sp` (user space) when every piece is a line or a circular arc and
/// the subpath turns smoothly at every joint (the end tangent of each piece
/// is the start tangent of the next, to 1e-9): the offsets by `half` to
/// either side, each piece a parallel line or a concentric arc (a homothety of
/// its conic about the centre, the weight kept), the right one as it runs and
/// the left one reversed, so the band between them has winding ±1 and the
/// inside 0 (nonzero rule). Joins and caps paint nothing beyond these at a
/// smooth joint of a closed path. `None` (kurbo then strokes it) for an open
/// or dashed path, a corner, a cubic or elliptic piece, or an arc whose
/// inner offset would vanish (radius ≤ `half`).
fn exact_offsets(sp: &Subpath, half: f64) -> Option<Vec<Verb>> {
    if !sp.closed || sp.segments.is_empty() || half.is_nan() || half <= 0.0 {
        return None;
    }
    let n = sp.segments.len();
    let tangent = |seg: &Segment, end: bool| -> Option<Vec2> {
        let t = match *seg {
            Segment::Line(l) => l.p1 - l.p0,
            Segment::Conic(c) if end => c.p2 - c.p1,
            Segment::Conic(c) => c.p1 - c.p0,
            Segment::Cubic(_) => return None,
        };
        let len = t.hypot();
        (len > 0.0).then(|| t / len)
    };
    for i in 0..n {
        let (a, b) = (&sp.segments[i], &sp.segments[(i + 1) % n]);
        if a.end() != b.start() && (a.end() - b.start()).hypot() > 1e-12 * half {
            return None;
        }
        let (ta, tb) = (tangent(a, true)?, tangent(b, false)?);
        if ta.cross(tb).abs() > 1e-9 || ta.dot(tb) <= 0.0 {
            return None;
        }
    }
    // each piece offset by `sign * half` along its left normal
    let offset = |sign: f64| -> Option<Vec<Segment>> {
        let mut pieces = Vec::with_capacity(n);
        for seg in &sp.segments {
            pieces.push(match *seg {
                Segment::Line(l) => {
                    let t = (l.p1 - l.p0) / (l.p1 - l.p0).hypot();
                    let m = Vec2::new(-t.y, t.x) * (sign * half);
                    Segment::Line(kurbo::Line::new(l.p0 + m, l.p1 + m))
                }
                Segment::Conic(c) => {
                    let (centre, r, side) = circular(&c)?;
                    // to the left of a left turn is towards the centre
                    let radius = r - sign * side * half;
                    if radius <= 1e-6 * r {
                        return None;
                    }
                    let k = radius / r;
                    let h = |p: Point| centre + (p - centre) * k;
                    Segment::Conic(Conic::new(h(c.p0), h(c.p1), h(c.p2), c.w))
                }
                Segment::Cubic(_) => return None,
            });
        }
        Some(pieces)
    };
    let right = offset(-1.0)?;
    let left: Vec<Segment> = offset(1.0)?.iter().rev().map(Segment::reverse).collect();
    let mut verbs = Vec::with_capacity(2 * n + 4);
    for ring in [right, left] {
        let start = ring[0].start();
        verbs.push(Verb::Move(start));
        let last = ring.len() - 1;
        for (i, seg) in ring.iter().enumerate() {
            // the joints agree to rounding; the last piece ends where it began
            let end = if i == last { start } else { seg.end() };
            verbs.push(match *seg {
                Segment::Line(_) => Verb::Line(end),
                Segment::Conic(c) => Verb::Conic(Conic::new(c.p0, c.p1, end, c.w)),
                Segment::Cubic(_) => unreachable!("internal: no cubic is offset exactly"),
            });
        }
        verbs.push(Verb::Close);
    }
    Some(verbs)
}

#[cfg(test)]
mod tests {
    use super::dash_gaps_below;

    #[test]
    fn dash_gaps_are_the_odd_entries_or_all_of_an_odd_pattern() {
        // gaps 0.05 and 0.08 below μ = 0.1; the dashes' own length does not count
        assert!(dash_gaps_below(&[5.0, 0.05, 7.0, 0.08], 1.0, 0.1));
        assert!(!dash_gaps_below(&[5.0, 0.05, 7.0, 0.2], 1.0, 0.1));
        // an odd pattern repeats: 0.05 on, 3 off, 0.02 on, 0.05 off, 3 on, ...
        assert!(!dash_gaps_below(&[0.05, 3.0, 0.02], 1.0, 0.1));
        assert!(dash_gaps_below(&[0.05, 0.02, 0.01], 1.0, 0.1));
        // lengths are in user units: a map that doubles them doubles the gaps
        assert!(!dash_gaps_below(&[1.0, 0.06], 2.0, 0.1));
        assert!(!dash_gaps_below(&[], 1.0, 0.1));
    }
}
