//! SVG's paint model beyond flat fills: what is painted at all (visibility,
//! opacity), strokes as the areas they cover (kurbo's stroke expansion), and
//! paint servers (gradients) summarised by their mean opacity and colour.

use super::drawing::{Segment, Subpath};
use super::outline::{Verb, subpaths};
use kurbo::{Affine, BezPath, PathEl};

/// What becomes of strokes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StrokeMode {
    /// A stroke is the area it paints: a shape of its own (`<name>-stroke`),
    /// right after (or, with `paint-order: stroke`, before) its fill. Strokes
    /// thinner than [`PaintOptions::min_stroke_width`] stay centre lines.
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

/// The area `stroke` paints along `outline` (output coordinates), as subpaths to
/// fill by the nonzero rule; `to_output` maps the path's user space (where the
/// stroke's width, dashes and joins are defined) to output coordinates.
/// `None` if the map is singular or the stroke paints nothing.
pub(super) fn stroke_area(
    outline: &[Subpath],
    stroke: &usvg::Stroke,
    to_output: Affine,
) -> Option<Vec<Subpath>> {
    let det = to_output.determinant();
    if !(det.abs() > 0.0 && det.is_finite()) {
        return None;
    }
    let to_user = to_output.inverse();
    let mut path = BezPath::new();
    for sp in outline {
        path.move_to(to_user * sp.start);
        if sp.segments.is_empty() {
            // a lone point: a zero-length subpath (caps may paint it)
            path.line_to(to_user * sp.start);
        }
        for seg in &sp.segments {
            match *seg {
                Segment::Line(l) => path.line_to(to_user * l.p1),
                Segment::Cubic(c) => {
                    path.curve_to(to_user * c.p1, to_user * c.p2, to_user * c.p3);
                }
                Segment::Conic(c) => {
                    // two cubics per conic piece (≤ 90°): far below a pixel
                    let (a, b) = (c.subsegment(0.0, 0.5), c.subsegment(0.5, 1.0));
                    for h in [a, b] {
                        let k = h.approx_cubic();
                        path.curve_to(to_user * k.p1, to_user * k.p2, to_user * k.p3);
                    }
                }
            }
        }
        if sp.closed {
            path.close_path();
        }
    }
    let width = f64::from(stroke.width().get());
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
    if let Some(dashes) = stroke.dasharray() {
        style = style.with_dashes(
            f64::from(stroke.dashoffset()),
            dashes.iter().map(|&d| f64::from(d)),
        );
    }
    // the outline within 1/200 of the width of the exact offset curves
    let tolerance = width * 5e-3;
    let area = kurbo::stroke(path, &style, &kurbo::StrokeOpts::default(), tolerance);
    let verbs = area.elements().iter().map(|el| {
        let m = |p| to_output * p;
        match *el {
            PathEl::MoveTo(p) => Verb::Move(m(p)),
            PathEl::LineTo(p) => Verb::Line(m(p)),
            PathEl::QuadTo(a, b) => Verb::Quad(m(a), m(b)),
            PathEl::CurveTo(a, b, c) => Verb::Cubic(m(a), m(b), m(c)),
            PathEl::ClosePath => Verb::Close,
        }
    });
    let out: Vec<Subpath> = subpaths(verbs)
        .into_iter()
        .filter(|s| !s.segments.is_empty())
        .collect();
    (!out.is_empty()).then_some(out)
}
