//! The loader's product: shapes and their feature soup, in f64 output coordinates.

pub use super::conic::Conic;
use kurbo::{CubicBez, Line, Point, Rect};

/// Index of a [`Shape`] in [`Drawing::shapes`]. `Debug` prints `s3`.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
pub struct ShapeId(u32);

impl ShapeId {
    /// The id of shape `i`.
    ///
    /// # Panics
    /// If `i` does not fit in a `u32`.
    pub(crate) fn from_index(i: usize) -> Self {
        ShapeId(u32::try_from(i).expect("internal: shape count fits u32"))
    }

    /// The index into [`Drawing::shapes`].
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl std::fmt::Debug for ShapeId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "s{}", self.0)
    }
}

/// SVG fill rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum FillRule {
    /// `nonzero` (the SVG default).
    NonZero,
    /// `evenodd`.
    EvenOdd,
}

/// One drawable SVG element after usvg's normalisation.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Shape {
    /// The SVG `id` attribute, if the element (or its nearest named ancestor `<use>`,
    /// or for glyph outlines its `<text>` element) had one.
    pub svg_id: Option<String>,
    /// Index of the element in document order among drawable elements (0-based).
    pub element_index: u32,
    /// Paint order: later shapes are painted on top of earlier ones.
    pub paint_order: u32,
    /// Whether the shape has a fill (any paint: colour, gradient or pattern).
    pub filled: bool,
    /// Whether the shape has a stroke.
    pub stroked: bool,
    /// The fill rule (meaningful when `filled`).
    pub fill_rule: FillRule,
    /// The fill colour as RGB, when the fill is a plain colour.
    pub fill_colour: Option<[u8; 3]>,
    /// The outline: one entry per subpath, in output coordinates.
    pub subpaths: Vec<Subpath>,
    /// What the shape paints (its fill or a stroke's area), how opaquely, and
    /// the clip paths and masks that limit it.
    pub paint: ShapePaint,
}

/// What a [`Shape`] stands for in the picture.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShapeKind {
    /// The element's own outline (its fill when `filled`, else its centre lines).
    #[default]
    Element,
    /// The area a stroke paints (kurbo's stroke expansion, nonzero fill); named
    /// `<name>-stroke`.
    Stroke,
    /// The outline of a clip path or mask: feature geometry only, never a region.
    ClipOutline,
}

/// The paint of a [`Shape`] beyond its outline.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ShapePaint {
    /// Fill, stroke area, or clip outline.
    pub kind: ShapeKind,
    /// Effective opacity of the paint: the group opacities along the chain times
    /// the fill (or stroke) opacity times, for a gradient, its stops' mean opacity.
    pub alpha: f32,
    /// The gradient or pattern id of a paint server fill, if any.
    pub server: Option<String>,
    /// The average colour of a gradient fill's opaque stops (for previews).
    pub average_colour: Option<[u8; 3]>,
    /// The shape or one of its groups has a filter (its outline is meshed as is).
    pub filtered: bool,
    /// For a [`ShapeKind::Stroke`], the stroke's width in output units (the
    /// optimizer sizes the mesh of a thin stroke by it).
    pub stroke_width: Option<f64>,
    /// For a [`ShapeKind::Stroke`], whether its paint equals its element's fill
    /// (one opaque colour, or the same paint server, both opaque, painted
    /// through the same clips): the stroke's area joins the fill's region (the
    /// fill's name, [`Shape::name`]), and the outlines between the two (the
    /// fill's outline under the stroke, the stroke's inner outline) bound
    /// nothing, so no band is meshed.
    pub joins_fill: bool,
    /// Clip regions the shape is painted through (all of them at once).
    #[serde(skip)]
    pub clips: Vec<std::sync::Arc<Clip>>,
    /// For a [`ShapeKind::ClipOutline`], the clip it outlines (the features
    /// stage keeps its pieces only where they bound what that clip lets paint).
    #[serde(skip)]
    pub outlined_clip: Option<std::sync::Arc<Clip>>,
    /// The transform on the element's chain that stretches its outline most
    /// unevenly, as the document writes it and where (`skewX(89.9) on <g
    /// id='s'>`), when it stretches one direction more than
    /// [`ShapePaint::UNEVEN`] times the other (a shape it thins out beyond what
    /// the mesh resolves is named with it).
    #[serde(skip)]
    pub stretched_by: Option<String>,
}

impl ShapePaint {
    /// The ratio of a transform's largest to smallest stretch from which
    /// [`ShapePaint::stretched_by`] names it.
    pub const UNEVEN: f64 = 100.0;
}

impl Default for ShapePaint {
    fn default() -> Self {
        ShapePaint {
            kind: ShapeKind::Element,
            alpha: 1.0,
            server: None,
            average_colour: None,
            filtered: false,
            stroke_width: None,
            joins_fill: false,
            clips: Vec::new(),
            outlined_clip: None,
            stretched_by: None,
        }
    }
}

/// A clip region: the union of its parts, intersected with every clip in `within`
/// (a `clip-path` on the `<clipPath>` itself). A mask is approximated by the clip
/// of its content that is not fully transparent (its shapes' fills, each
/// intersected with the mask's rectangle).
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// How the clip's outline is named as feature geometry (`clip-<id>`, `mask-<id>`).
    pub name: String,
    /// Whether this is a mask approximated as a clip.
    pub mask: bool,
    /// The outlines whose union is the clip.
    pub parts: Vec<ClipPart>,
    /// Clips the whole clip is itself clipped by.
    pub within: Vec<std::sync::Arc<Clip>>,
}

/// One outline of a [`Clip`], with its own rule (`clip-rule`, or `fill-rule` for a mask).
#[derive(Clone, Debug, PartialEq)]
pub struct ClipPart {
    /// The rule deciding inside.
    pub rule: FillRule,
    /// The outline, in output coordinates.
    pub subpaths: Vec<Subpath>,
    /// Clips on this part alone (a `clip-path` on a child of the `<clipPath>`).
    pub clips: Vec<std::sync::Arc<Clip>>,
}

/// `c` and every clip inside it, once each.
pub(crate) fn collect_clips(c: &std::sync::Arc<Clip>, all: &mut Vec<std::sync::Arc<Clip>>) {
    if all.iter().any(|e| std::sync::Arc::ptr_eq(e, c)) {
        return;
    }
    all.push(c.clone());
    for inner in c
        .within
        .iter()
        .chain(c.parts.iter().flat_map(|p| p.clips.iter()))
    {
        collect_clips(inner, all);
    }
}

impl Shape {
    /// The shape's mean width: twice its area over its perimeter (the width of
    /// a long thin strip), from its outline sampled 16 times per segment; 0
    /// for an outline without area.
    pub(crate) fn mean_width(&self) -> f64 {
        const SAMPLES: usize = 16;
        let (mut area, mut length) = (0.0, 0.0);
        for sp in &self.subpaths {
            let mut points = vec![sp.start];
            for seg in &sp.segments {
                for k in 1..=SAMPLES {
                    let t = k as f64 / SAMPLES as f64;
                    points.push(match seg {
                        Segment::Line(l) => kurbo::ParamCurve::eval(l, t),
                        Segment::Cubic(c) => kurbo::ParamCurve::eval(c, t),
                        Segment::Conic(c) => c.eval(t),
                    });
                }
            }
            points.push(sp.start);
            for w in points.windows(2) {
                area += w[0].x * w[1].y - w[1].x * w[0].y;
                length += w[0].distance(w[1]);
            }
        }
        if length > 0.0 {
            area.abs() / length
        } else {
            0.0
        }
    }

    /// The name used for physical groups: the SVG id, else `shape-N` (N = element
    /// index); a stroke's area adds `-stroke` unless it joins its fill's region
    /// ([`ShapePaint::joins_fill`]).
    pub fn name(&self) -> String {
        let base = match &self.svg_id {
            Some(id) if !id.is_empty() => id.clone(),
            _ => format!("shape-{}", self.element_index),
        };
        match self.paint.kind {
            ShapeKind::Stroke if !self.paint.joins_fill => format!("{base}-stroke"),
            _ => base,
        }
    }
}

/// One piece of a subpath: a straight segment, a cubic Bézier (quadratics are
/// elevated) or an exact conic piece (arcs, circles, ellipses, rounded corners).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment {
    /// A straight segment.
    Line(Line),
    /// A cubic Bézier curve.
    Cubic(CubicBez),
    /// A piece of an ellipse, as a rational quadratic Bézier (at most 90°).
    Conic(Conic),
}

impl Segment {
    /// Start point.
    pub fn start(&self) -> Point {
        match self {
            Segment::Line(l) => l.p0,
            Segment::Cubic(c) => c.p0,
            Segment::Conic(c) => c.p0,
        }
    }
    /// End point.
    pub fn end(&self) -> Point {
        match self {
            Segment::Line(l) => l.p1,
            Segment::Cubic(c) => c.p3,
            Segment::Conic(c) => c.p2,
        }
    }
    /// The control points (2 for a line, 4 for a cubic, 3 for a conic).
    pub fn control_points(&self) -> Vec<Point> {
        match self {
            Segment::Line(l) => vec![l.p0, l.p1],
            Segment::Cubic(c) => vec![c.p0, c.p1, c.p2, c.p3],
            Segment::Conic(c) => c.control_points().to_vec(),
        }
    }
    /// The image under an affine map (exact for every kind: a conic keeps its weight).
    pub fn transform(&self, a: kurbo::Affine) -> Segment {
        match self {
            Segment::Line(l) => Segment::Line(Line::new(a * l.p0, a * l.p1)),
            Segment::Cubic(c) => Segment::Cubic(a * *c),
            Segment::Conic(c) => Segment::Conic(c.transform(a)),
        }
    }
    /// The same curve run the other way.
    pub fn reverse(&self) -> Segment {
        match self {
            Segment::Line(l) => Segment::Line(Line::new(l.p1, l.p0)),
            Segment::Cubic(c) => Segment::Cubic(CubicBez::new(c.p3, c.p2, c.p1, c.p0)),
            Segment::Conic(c) => Segment::Conic(c.reverse()),
        }
    }
    /// The segment as a cubic (a line becomes a cubic with controls at 1/3 and 2/3;
    /// a conic is approximated, see [`Conic::approx_cubic`]).
    pub fn to_cubic(&self) -> CubicBez {
        match self {
            Segment::Line(l) => CubicBez::new(
                l.p0,
                l.p0.lerp(l.p1, 1.0 / 3.0),
                l.p0.lerp(l.p1, 2.0 / 3.0),
                l.p1,
            ),
            Segment::Cubic(c) => *c,
            Segment::Conic(c) => c.approx_cubic(),
        }
    }
}

/// A subpath: a chain of segments, each starting where the previous ends.
#[derive(Clone, Debug, PartialEq)]
pub struct Subpath {
    /// The segments, in order. Empty for an isolated point (a lone `M`, or a
    /// zero-length subpath), which is then given by `start`.
    pub segments: Vec<Segment>,
    /// The first point.
    pub start: Point,
    /// Whether the subpath was closed with `Z` (the closing segment, if not of
    /// zero length, is included in `segments`).
    pub closed: bool,
}

impl Subpath {
    /// The straight segment SVG adds when filling an open subpath (end → start),
    /// if the subpath is open and its ends differ.
    pub fn implicit_closing_segment(&self) -> Option<Line> {
        let end = self.segments.last()?.end();
        (!self.closed && end != self.start).then(|| Line::new(end, self.start))
    }
}

impl serde::Serialize for Subpath {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut st = s.serialize_struct("Subpath", 2)?;
        st.serialize_field("segments", &self.segments.len())?;
        st.serialize_field("closed", &self.closed)?;
        st.end()
    }
}

/// The geometry of one input feature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FeatureGeom {
    /// An isolated point.
    Point(Point),
    /// A straight segment.
    Line(Line),
    /// A cubic Bézier.
    Cubic(CubicBez),
    /// An exact conic piece (a piece of an ellipse, at most 90°).
    Conic(Conic),
}

/// Where a feature came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct FeatureSource {
    /// The shape.
    pub shape: ShapeId,
    /// Subpath index within the shape.
    pub subpath: u32,
    /// Segment index within the subpath (`u32::MAX` for the implicit closing segment).
    pub segment: u32,
}

impl FeatureSource {
    /// Segment index used for the implicit closing segment of a filled open subpath.
    pub const IMPLICIT_CLOSE: u32 = u32::MAX;
}

/// One input feature: a point, segment, cubic or conic, tagged with its source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Feature {
    /// The geometry, in output coordinates.
    pub geom: FeatureGeom,
    /// Its source.
    pub source: FeatureSource,
}

/// How many of a drawing's paths were read in f64 from the document's text, and
/// how many kept usvg's single precision (text glyph outlines and markers by
/// design; unsupported cases with a warning). Zero for a drawing built in code.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct PathPrecision {
    /// Paths whose every coordinate comes from the document's numbers in f64.
    pub f64_paths: usize,
    /// Paths in usvg's single precision.
    pub single_precision_paths: usize,
}

/// A loaded drawing: the shapes and the feature soup that the meshers consume,
/// in output coordinates (the units and scale it was loaded with: by default
/// the user units of the root `viewBox`, the document's own numbers).
///
/// Guarantees (what later stages may assume): every coordinate is finite and
/// its magnitude is at most [`Drawing::MAX_COORD`]; y is flipped (y = −y_svg);
/// there is at least one feature; `bbox` contains every feature's control points.
#[derive(Clone, Debug, PartialEq)]
pub struct Drawing {
    /// Drawable shapes in document (paint) order.
    pub shapes: Vec<Shape>,
    /// The feature soup: every segment of every subpath, plus isolated points, plus
    /// the implicit closing segment of each open subpath of a filled shape.
    pub features: Vec<Feature>,
    /// Bounding box of all control points.
    pub bbox: Rect,
    /// Warnings for the user (skipped text, ignored images, ...).
    pub warnings: Vec<String>,
    /// How the paths' geometry was read: in f64 from the document's text, or in
    /// usvg's single precision (text glyphs, markers, unsupported cases).
    pub precision: PathPrecision,
    /// What the paint model did: strokes meshed as areas, clipped shapes, shapes
    /// dropped as invisible or decoration.
    pub paint: PaintCounts,
    /// The root `viewBox` in output coordinates (y up), when the document has a
    /// valid one (`--periodic`'s cell by default); `None` for a drawing built in code.
    pub view_box: Option<Rect>,
    /// When the drawing is a periodic cell's tile (every feature translated by
    /// the periods into the cell, each shape the union of its translated
    /// copies): the cell, which is then its extent.
    pub cell: Option<Rect>,
}

/// What the loader did with SVG's paint model (`--stats`: no region is lost or
/// gained silently).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct PaintCounts {
    /// Strokes meshed as the area they paint.
    pub strokes_as_areas: usize,
    /// Strokes kept as centre lines (`--strokes line`, or hairlines thinner than
    /// l_min or than the feature envelope μ).
    pub strokes_as_lines: usize,
    /// Of the strokes kept as lines, those at least l_min wide but narrower than
    /// μ: their two outlines would be closer than the feature envelope, which
    /// does not keep them apart (a band of secondary features, its area off by
    /// up to ε times its length), so the stroke is its centre line instead.
    pub strokes_below_mu: usize,
    /// Of the strokes meshed as areas, those whose paint equals their element's
    /// fill ([`ShapePaint::joins_fill`]): one region with the fill, no band.
    pub strokes_joined: usize,
    /// Of the strokes meshed as areas, dashed ones whose every gap is
    /// shorter than μ: stroked whole (the dashes on either side of a gap
    /// would lie closer than the feature envelope, which does not keep them
    /// apart, and a dashed spiral of 80 000 such dashes would take minutes).
    pub dashes_closed: usize,
    /// Of the strokes meshed as areas, the closed subpaths whose outlines are
    /// the exact offsets (concentric conics, parallel lines); the others are
    /// kurbo's stroke expansion to a tolerance far below μ.
    pub exact_stroke_subpaths: usize,
    /// Strokes left out (`--strokes ignore`, or invisible).
    pub strokes_ignored: usize,
    /// Shapes (fills and stroke areas) painted through a clip path or mask.
    pub clipped_shapes: usize,
    /// Of those, shapes clipped by a mask (approximated as a clip).
    pub masked_shapes: usize,
    /// Fills and strokes not painted at all (hidden, zero opacity along the group
    /// chain, zero fill or stroke opacity, no paint).
    pub dropped_invisible: usize,
    /// Fills and strokes whose effective opacity is below `--min-opacity`.
    pub dropped_decoration: usize,
    /// Shapes under a filter (meshed by their outline).
    pub filtered_shapes: usize,
    /// Shapes dropped because a copy of them (the same outline to 1e-10·d, the
    /// same role: fill rule, kind, clips) is painted on top and covers them.
    pub duplicates_merged: usize,
    /// Fills and strokes of the markers usvg would draw on a `<rect>`,
    /// `<circle>` or `<ellipse>` (SVG 1.1 draws markers on paths, lines,
    /// polylines and polygons only): not loaded.
    pub markers_not_drawn: usize,
}

impl Drawing {
    /// The fill whose region the stroke area `stroke` joins
    /// ([`ShapePaint::joins_fill`]): its element's fill, next to it in paint
    /// order. `None` for any other shape, or when that fill is not there (a
    /// copy painted on top replaced it).
    pub fn joined_fill(&self, stroke: ShapeId) -> Option<ShapeId> {
        let s = self.shapes.get(stroke.index())?;
        if s.paint.kind != ShapeKind::Stroke || !s.paint.joins_fill {
            return None;
        }
        let i = stroke.index();
        [i.checked_sub(1), i.checked_add(1)]
            .into_iter()
            .flatten()
            .find(|&j| {
                self.shapes.get(j).is_some_and(|f| {
                    f.paint.kind == ShapeKind::Element
                        && f.filled
                        && f.element_index == s.element_index
                        && f.svg_id == s.svg_id
                })
            })
            .map(ShapeId::from_index)
    }

    /// Largest accepted coordinate magnitude (output units, after `--units` and
    /// `--scale`). Far beyond any drawing,
    /// and small enough that squares and products stay finite in f64.
    pub const MAX_COORD: f64 = 1e15;
    /// Smallest accepted bounding-box diagonal (output units) of a drawing that
    /// is not a single point: products of coordinates (areas, orientations in
    /// f64) must not underflow.
    pub const MIN_DIAGONAL: f64 = 1e-100;
    /// Smallest accepted ratio of the bounding-box diagonal to the largest
    /// coordinate magnitude: f64 then resolves the drawing to about 2e-10 of its
    /// size (l_min is 1e-4 of it by default, and the nodes of one edge, computed
    /// by any client, agree far below 1e-8 of it). Below it the drawing is
    /// refused: translate it closer to the origin.
    pub const MIN_RELATIVE_EXTENT: f64 = 1e-6;

    /// The diagonal `d` of the drawing's extent (the unit of relative
    /// parameters): the tight bounding box of its curves ([`Self::extent`]), so
    /// that `d` does not depend on how a curve is parametrised or rotated; for a
    /// drawing that is a single point, 1.0, or [`Self::MIN_RELATIVE_EXTENT`]
    /// times the point's largest coordinate magnitude when that is larger (so
    /// the mesh around a far point is resolved in f64 as any drawing's is).
    pub fn diagonal(&self) -> f64 {
        let e = self.extent();
        let d = e.width().hypot(e.height());
        if d > 0.0 {
            d
        } else {
            let magnitude = [self.bbox.x0, self.bbox.y0]
                .into_iter()
                .fold(0.0_f64, |m, c| m.max(c.abs()));
            (Self::MIN_RELATIVE_EXTENT * magnitude).max(1.0)
        }
    }

    /// The tight bounding box of the drawing's curves (cubics and conics at
    /// their extrema, not their control points); inside [`Self::bbox`].
    pub fn extent(&self) -> Rect {
        if let Some(cell) = self.cell {
            return cell;
        }
        let mut out: Option<Rect> = None;
        for f in &self.features {
            let r = match f.geom {
                FeatureGeom::Point(p) => Rect::from_points(p, p),
                FeatureGeom::Line(l) => Rect::from_points(l.p0, l.p1),
                FeatureGeom::Cubic(c) => kurbo::ParamCurveExtrema::bounding_box(&c),
                FeatureGeom::Conic(c) => super::reconstruct::conic_bbox(&c),
            };
            out = Some(out.map_or(r, |o| o.union(r)));
        }
        out.unwrap_or(self.bbox)
    }
}
