//! Which filled shape each triangle belongs to: the topmost one (in paint order)
//! whose fill covers it, or none (background).

use super::element::{element_area, element_point};
use crate::fem::FemMesh;
use crate::svg::winding::Painting;
use crate::svg::{Drawing, Segment, ShapeId};
use kurbo::Point;
use rayon::prelude::*;
use std::collections::{HashMap, HashSet};

/// Options of [`classify`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub(crate) struct ClassifyOptions {
    /// Distance to an input curve (user units) below which a sample point's
    /// winding number is not trusted and another interior point is tried. The
    /// pipeline uses the numerical tolerance ε_m (default 1e-8·d).
    pub eps_abs: f64,
    /// Give every triangle of a face (a set of triangles connected across
    /// non-feature edges) the face's area-majority label. Default true; see the
    /// module documentation for why.
    pub vote_per_face: bool,
    /// How far beside an outline a shape must show to count as shown when its
    /// region is missing (see [`lost_shapes`]; user units). The pipeline uses
    /// half the hairline width l_min: a stroke narrower than l_min stays a line,
    /// and a sliver that thin (a shape peeking out from under a near-copy of
    /// itself) is no region anybody sees. A shape that is itself thinner than
    /// this beside its outline (a shape a transform thinned out) counts as
    /// shown where it is topmost at a finer probe inside it (`shows_thin`).
    pub probe_step: f64,
    /// The run's time limit: once it has passed, the triangles left are not
    /// classified (the caller checks it and stops the run).
    pub deadline: crate::budget::Deadline,
}

impl ClassifyOptions {
    /// Options with tolerance `eps_abs` (user units), per-face voting and a
    /// probe step of `1000 eps_abs`.
    pub(crate) fn new(eps_abs: f64) -> Self {
        ClassifyOptions {
            eps_abs,
            vote_per_face: true,
            probe_step: PROBE_STEP * eps_abs,
            deadline: crate::budget::Deadline::NONE,
        }
    }
    /// Set the time limit (see [`ClassifyOptions::deadline`]).
    pub(crate) fn with_deadline(mut self, deadline: crate::budget::Deadline) -> Self {
        self.deadline = deadline;
        self
    }
    /// Set the probe step (user units; see [`ClassifyOptions::probe_step`]).
    pub(crate) fn with_probe_step(mut self, step: f64) -> Self {
        self.probe_step = step;
        self
    }
    /// Turn per-face voting on or off.
    #[cfg(test)]
    pub(crate) fn with_vote_per_face(mut self, vote: bool) -> Self {
        self.vote_per_face = vote;
        self
    }
}

/// The classification of a mesh's triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct RegionAssignment {
    /// For each triangle, the topmost filled shape covering it; `None` is the background.
    pub owner: Vec<Option<ShapeId>>,
    /// Triangles none of whose sample points was clear of the outlines (their
    /// own label is a best guess; with per-face voting their face decides).
    pub near_boundary: usize,
    /// Triangles whose own sample disagreed with their face's majority and took
    /// the face's label (the sliver between a flattened curve and the true one).
    pub relabelled: usize,
    /// Total area of the relabelled triangles.
    pub relabelled_area: f64,
    /// Filled shapes the picture shows (see [`lost_shapes`]) that own no
    /// triangle: their outlines did not become mesh edges (closer than the mesh
    /// resolves), so what they paint went to a neighbour's region. In shape
    /// order.
    pub lost: Vec<ShapeId>,
}

/// Interior points tried in turn (barycentric), the centroid first.
const SAMPLES: [[f64; 3]; 7] = [
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
    [0.5, 0.25, 0.25],
    [0.25, 0.5, 0.25],
    [0.25, 0.25, 0.5],
    [0.2, 0.4, 0.4],
    [0.4, 0.2, 0.4],
    [0.4, 0.4, 0.2],
];

/// Classify every triangle of `mesh` by the fills of `drawing`.
///
/// Each triangle is sampled at a point well inside it (its centroid, or for a
/// curved element the image of the reference centroid, node 9 of a cubic
/// triangle); when that point is within `eps_abs` of an outline, other interior
/// points are tried. Winding numbers are evaluated on the input curves
/// ([`crate::svg::winding`]). With [`ClassifyOptions::vote_per_face`], each face of
/// the mesh (triangles connected across edges that are not line elements) then
/// takes the label that covers most of its area.
pub(crate) fn classify(
    drawing: &Drawing,
    mesh: &FemMesh,
    opts: &ClassifyOptions,
) -> RegionAssignment {
    let painting = Painting::new(drawing);
    let order = mesh.order();
    let n = mesh.triangle_count();
    let eps = opts.eps_abs;
    let samples: Vec<(Option<ShapeId>, bool, f64)> = (0..n)
        .into_par_iter()
        .map(|t| {
            // Past the time limit the rest is not classified (the caller stops).
            if opts.deadline.expired() {
                return (None, false, 0.0);
            }
            let nodes: Vec<Point> = mesh
                .triangle(t)
                .iter()
                .map(|&v| mesh.nodes[v as usize])
                .collect();
            let area = element_area(order, &nodes).abs();
            let mut first = None;
            for l in SAMPLES {
                let (owner, clear) = painting.owner_at(element_point(order, &nodes, l), eps);
                if clear {
                    return (owner, true, area);
                }
                first.get_or_insert(owner);
            }
            (first.flatten(), false, area)
        })
        .collect();
    let near_boundary = samples.iter().filter(|s| !s.1).count();
    let mut out = RegionAssignment {
        owner: samples.iter().map(|s| s.0).collect(),
        near_boundary,
        relabelled: 0,
        relabelled_area: 0.0,
        lost: Vec::new(),
    };
    if opts.vote_per_face && n > 0 {
        let face = faces(mesh);
        // Per face: total weight of each label; uncertain samples count for little.
        let mut votes: HashMap<u32, Vec<(Option<ShapeId>, f64)>> = HashMap::new();
        for (t, &(owner, clear, area)) in samples.iter().enumerate() {
            let w = if clear { area } else { area * 1e-6 } + f64::MIN_POSITIVE;
            let v = votes.entry(face[t]).or_default();
            match v.iter_mut().find(|e| e.0 == owner) {
                Some(e) => e.1 += w,
                None => v.push((owner, w)),
            }
        }
        let winner: HashMap<u32, Option<ShapeId>> = votes
            .into_iter()
            .map(|(f, v)| {
                let best = v
                    .iter()
                    .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
                    .expect("internal: a face has at least one triangle");
                (f, best.0)
            })
            .collect();
        for t in 0..n {
            let w = winner[&face[t]];
            if out.owner[t] != w {
                out.owner[t] = w;
                out.relabelled += 1;
                out.relabelled_area += samples[t].2;
            }
        }
    }
    let sampled: HashSet<ShapeId> = samples.iter().filter(|s| s.1).filter_map(|s| s.0).collect();
    out.lost = lost_shapes(drawing, &painting, &out.owner, &sampled, opts);
    tracing::debug!(
        triangles = n,
        near_boundary = out.near_boundary,
        relabelled = out.relabelled,
        "regions classified"
    );
    out
}

/// Probe points per shape (on as many of its segments, spread over them).
const PROBES: usize = 8;
/// The default probe step, in units of `eps_abs`.
const PROBE_STEP: f64 = 1e3;
/// Finer probes beside a thin shape's outline: the probe step divided by
/// 10, 100, ... this many times (while the offset still moves the point).
const THIN_LEVELS: i32 = 12;

/// The filled shapes that own no triangle in `owner` although the picture
/// shows them: a triangle's own clear sample was theirs (`sampled`, before the
/// faces voted), or at a probe point [`ClassifyOptions::probe_step`] to either
/// side of the middle of one of their segments the topmost shape painting it
/// (clear of every outline) is the shape itself, or the shape is thin there
/// ([`shows_thin`]). A shape hidden under others everywhere is not lost, nor a
/// sliver of a wide shape peeking out by less than the probe step from under
/// another; one visible only where neither a sample nor a probe falls goes
/// unnoticed (a probe per segment, on at most [`PROBES`] segments; an open
/// subpath's closing segment is not probed).
fn lost_shapes(
    drawing: &Drawing,
    painting: &Painting,
    owner: &[Option<ShapeId>],
    sampled: &HashSet<ShapeId>,
    opts: &ClassifyOptions,
) -> Vec<ShapeId> {
    let kept: HashSet<ShapeId> = owner.iter().flatten().copied().collect();
    let (step, eps_abs) = (opts.probe_step, opts.eps_abs);
    let candidates: Vec<ShapeId> = painting.shapes().filter(|id| !kept.contains(id)).collect();
    let mut lost: Vec<ShapeId> = candidates
        .into_par_iter()
        .filter(|&id| {
            if sampled.contains(&id) {
                return true;
            }
            if opts.deadline.expired() {
                return false;
            }
            let segments: Vec<&Segment> = drawing.shapes[id.index()]
                .subpaths
                .iter()
                .flat_map(|sp| sp.segments.iter())
                .collect();
            let n = segments.len();
            (0..n.min(PROBES)).any(|k| {
                let Some((p, normal)) = middle_and_normal(segments[k * n / n.min(PROBES)]) else {
                    return false;
                };
                [normal, -normal].into_iter().any(|side| {
                    let (top, clear) = painting.owner_at(p + side * step, eps_abs);
                    (clear && top == Some(id)) || shows_thin(painting, id, p, side, step, eps_abs)
                })
            })
        })
        .collect();
    lost.sort_unstable();
    lost
}

/// Whether shape `id` is thinner than `step` beside outline point `p` on
/// `side` (it does not paint the probe point `step` away) and shows there: at
/// the first of the finer probes (`step` / 10, / 100, ... down to where the
/// offset no longer moves the point) that it paints, it is the topmost shape
/// (clear of the outlines when the probe is more than `eps_abs` away; closer,
/// as the winding numbers at a tenth of the offset say).
fn shows_thin(
    painting: &Painting,
    id: ShapeId,
    p: Point,
    side: kurbo::Vec2,
    step: f64,
    eps_abs: f64,
) -> bool {
    if painting.shape_paints(id, p + side * step, eps_abs) {
        return false;
    }
    for k in 1..=THIN_LEVELS {
        let offset = step * 10f64.powi(-k);
        let q = p + side * offset;
        if q == p {
            return false;
        }
        let below = offset <= eps_abs;
        let tolerance = if below { 0.1 * offset } else { eps_abs };
        if painting.shape_paints(id, q, tolerance) {
            let (top, clear) = painting.owner_at(q, tolerance);
            return top == Some(id) && (clear || below);
        }
    }
    false
}

/// The middle of a segment and its unit normal there, `None` where the
/// tangent vanishes.
fn middle_and_normal(seg: &Segment) -> Option<(Point, kurbo::Vec2)> {
    use kurbo::{ParamCurve, ParamCurveDeriv};
    let (p, d) = match seg {
        Segment::Line(l) => (l.eval(0.5), l.p1 - l.p0),
        Segment::Cubic(c) => (c.eval(0.5), c.deriv().eval(0.5).to_vec2()),
        Segment::Conic(c) => (c.eval(0.5), c.deriv(0.5)),
    };
    let len = d.hypot();
    (len > 0.0 && len.is_finite()).then(|| (p, kurbo::Vec2::new(-d.y, d.x) / len))
}

/// Edge key: the two corner indices, sorted.
pub(crate) fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// The face of each triangle: union-find over edges shared by two triangles
/// that are not line elements (features separate faces).
fn faces(mesh: &FemMesh) -> Vec<u32> {
    let n = mesh.triangle_count();
    let features: std::collections::HashSet<(u32, u32)> = (0..mesh.line_count())
        .map(|i| edge_key(mesh.line(i)[0], mesh.line(i)[1]))
        .collect();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            let p = parent[parent[x as usize] as usize];
            parent[x as usize] = p;
            x = p;
        }
        x
    }
    let mut first: HashMap<(u32, u32), u32> = HashMap::with_capacity(3 * n);
    for t in 0..n {
        let c = mesh.triangle(t);
        for e in 0..3 {
            let k = edge_key(c[e], c[(e + 1) % 3]);
            if features.contains(&k) {
                continue;
            }
            match first.get(&k) {
                Some(&u) => {
                    let (a, b) = (find(&mut parent, u), find(&mut parent, t as u32));
                    if a != b {
                        parent[a.max(b) as usize] = a.min(b);
                    }
                }
                None => {
                    first.insert(k, t as u32);
                }
            }
        }
    }
    (0..n as u32).map(|t| find(&mut parent, t)).collect()
}
