//! Triangulating convex cells, tagging segment edges, rounding vertices.

use super::{BspInput, BspSegment, SegmentTag};
use crate::budget::Deadline;
use crate::error::check_deadline;
use crate::exact::{Orientation, PointQ, PointRef, orient2d_mixed, orient2d_q};
use crate::mesh::{FaceId, FeatureOn, TriMesh, VertexId, VertexTag};
use crate::stage::Stage;
use crate::{Error, Result};
use rayon::prelude::*;
use rustc_hash::FxHashMap as HashMap;
use std::cmp::Ordering;

/// How [`emit_cells`] triangulates a convex cell (vertices counter-clockwise,
/// possibly with collinear runs): a fan from the first corner whose fan has
/// no degenerate triangle, else a fan from the exact barycentre.
pub(super) enum CellFan {
    /// A fan from this corner.
    Corner(usize),
    /// A fan from the barycentre.
    Barycentre(PointQ),
}

/// Decide how to triangulate the convex cell `pts` ([`CellFan`]), from its
/// points alone (exact orientations), so cells are planned in parallel.
pub(super) fn plan_cell(pts: &[&PointQ]) -> CellFan {
    let n = pts.len();
    if n == 3 {
        return CellFan::Corner(0);
    }
    let fan_ok = |k: usize| {
        (1..n - 1).all(|i| {
            let (b, c) = (&pts[(k + i) % n], &pts[(k + i + 1) % n]);
            orient2d_q(pts[k], b, c) == Orientation::CounterClockwise
        })
    };
    match (0..n).find(|&k| fan_ok(k)) {
        Some(k) => CellFan::Corner(k),
        None => CellFan::Barycentre(
            PointQ::barycentre(pts.iter().copied()).expect("internal: a cell has vertices"),
        ),
    }
}

/// A cell's corner with its nearest `f64` point and whether that is the
/// corner exactly, rounded where the cell is cut (in parallel), so that
/// [`VertexMap`] looks corners up by the bits of that point.
pub(super) struct Corner {
    q: PointQ,
    pos: kurbo::Point,
    exact: bool,
}

impl Corner {
    pub(super) fn new(q: PointQ) -> Self {
        let (pos, exact) = q.to_f64();
        Corner { q, pos, exact }
    }
}

/// The BSP's vertices by exact position. A corner is looked up by the bits of
/// its nearest `f64` point, which equal points share, so hashing reads no
/// rational; the exact values are compared only to tell apart points that
/// round alike, and the rare point that rounds like another one goes to
/// `others`, by its exact value.
#[derive(Default)]
pub(super) struct VertexMap {
    by_bits: HashMap<(u64, u64), VertexId>,
    others: HashMap<PointQ, VertexId>,
}

impl VertexMap {
    /// Record the `f64` vertex `id` at `p`.
    pub(super) fn insert_f64(&mut self, p: kurbo::Point, id: VertexId) {
        self.by_bits.insert(key(p), id);
    }

    /// The vertex at `c`, added to `mesh` if there is none yet.
    fn get_or_add(&mut self, mesh: &mut TriMesh, c: Corner) -> VertexId {
        let add = |mesh: &mut TriMesh, c: Corner| {
            mesh.add_vertex_rounded(c.q, c.pos, c.exact, VertexTag::default())
        };
        match self.by_bits.entry(key(c.pos)) {
            std::collections::hash_map::Entry::Vacant(e) => *e.insert(add(mesh, c)),
            std::collections::hash_map::Entry::Occupied(e) => {
                let id = *e.get();
                // A vertex with no rational is exactly its point, which is
                // `c.pos`: the same point when `c` is exactly that.
                let same = match mesh.exact(id) {
                    Some(x) => *x == c.q,
                    None => c.exact,
                };
                if same {
                    return id;
                }
                if let Some(&id) = self.others.get(&c.q) {
                    return id;
                }
                let q = c.q.clone();
                let id = add(mesh, c);
                self.others.insert(q, id);
                id
            }
        }
    }
}

/// Triangulate the convex cells of one seed triangle into `mesh`, each as
/// its [`CellFan`] says ([`plan_cell`]): `cells` name their corners (counter-
/// clockwise) by index into `corners`, which are shared through `vmap`. Each
/// corner is looked up once, when a cell first uses it, so vertices are
/// numbered as the cells' corners come, in order. Returns the number of
/// barycentre vertices added.
pub(super) fn emit_cells(
    mesh: &mut TriMesh,
    vmap: &mut VertexMap,
    corners: Vec<Corner>,
    cells: Vec<(Vec<u32>, CellFan)>,
) -> usize {
    let mut corners: Vec<Option<Corner>> = corners.into_iter().map(Some).collect();
    let mut vertex: Vec<Option<VertexId>> = vec![None; corners.len()];
    let mut ids: Vec<VertexId> = Vec::new();
    let mut barycentres = 0;
    for (cell, how) in cells {
        ids.clear();
        for &i in &cell {
            let i = i as usize;
            let id = match vertex[i] {
                Some(id) => id,
                None => {
                    let c = corners[i]
                        .take()
                        .expect("internal: a corner is looked up once");
                    let id = vmap.get_or_add(mesh, c);
                    vertex[i] = Some(id);
                    id
                }
            };
            ids.push(id);
        }
        let n = ids.len();
        match how {
            CellFan::Corner(k) => {
                for i in 1..n - 1 {
                    mesh.add_face([ids[k], ids[(k + i) % n], ids[(k + i + 1) % n]]);
                }
            }
            CellFan::Barycentre(c) => {
                let cid = mesh.add_vertex_q(c, VertexTag::default());
                for i in 0..n {
                    mesh.add_face([cid, ids[i], ids[(i + 1) % n]]);
                }
                barycentres += 1;
            }
        }
    }
    barycentres
}

/// `-0.0` and `0.0` are the same point.
fn key(p: kurbo::Point) -> (u64, u64) {
    ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits())
}

/// Compare the x (or y, unless `along_x`) coordinates of two vertices exactly:
/// by their rounded positions when those differ (rounding to nearest is
/// monotone), else in rationals.
fn cmp_coordinate(mesh: &TriMesh, along_x: bool, p: VertexId, q: VertexId) -> Ordering {
    let (pp, pq) = (mesh.position(p), mesh.position(q));
    let (cp, cq) = if along_x { (pp.x, pq.x) } else { (pp.y, pq.y) };
    if cp != cq {
        cp.total_cmp(&cq)
    } else if mesh.is_rational(p) || mesh.is_rational(q) {
        let (dx, dy) = if along_x { (1.0, 0.0) } else { (0.0, 1.0) };
        mesh.point_q_ref(p).cmp_along(&mesh.point_q_ref(q), dx, dy)
    } else {
        Ordering::Equal
    }
}

/// Segments walked (in parallel) between two checks of the deadline in
/// [`tag_segments`], and rational vertices decided between two checks in
/// [`round_vertices`]: a few milliseconds of work each on a large drawing.
pub(super) const CHECK_EVERY: usize = 1 << 12;

/// Walk every segment from `a` to `b` along mesh edges and tag them.
///
/// # Errors
/// [`Error::Meshing`] if a segment is not a chain of mesh edges (a bug);
/// the deadline's error when it is passed (checked every [`CHECK_EVERY`]
/// segments).
pub(super) fn tag_segments(
    mesh: &mut TriMesh,
    input: &BspInput,
    deadline: &Deadline,
) -> Result<()> {
    let by_pos: HashMap<(u64, u64), VertexId> = mesh
        .vertices()
        .filter(|&v| !mesh.is_rational(v) && mesh.vertex_tag(v).segment_endpoint)
        .map(|v| (key(mesh.position(v)), v))
        .collect();
    let not_conforming = |what: &str| {
        Error::meshing(
            Stage::Bsp,
            format!("internal: segment is not a chain of mesh edges ({what})"),
        )
    };
    // Each segment's walk reads the mesh only (tags play no part in it): the
    // walks run in parallel, and their tags go on in segment order.
    let mesh_ref: &TriMesh = mesh;
    let walk = |seg: &BspSegment| -> Result<Vec<(VertexId, VertexId, FeatureOn)>> {
        let mesh = mesh_ref;
        let mut tags = Vec::new();
        let (Some(&va), Some(&vb)) = (by_pos.get(&key(seg.a)), by_pos.get(&key(seg.b))) else {
            return Err(not_conforming("missing endpoint vertex"));
        };
        if va == vb {
            return Ok(tags);
        }
        let d = seg.b - seg.a;
        let len2 = d.hypot2();
        let param = |p: kurbo::Point| {
            if len2 > 0.0 && len2.is_finite() {
                ((p - seg.a).dot(d) / len2).clamp(0.0, 1.0)
            } else {
                0.5
            }
        };
        // Points of the segment's line are ordered along it as their dominant
        // coordinate is (its exact delta is non-zero: a != b). Rounding to
        // nearest is monotone, so distinct rounded coordinates decide; equal
        // ones fall back to the exact comparison.
        let along_x = d.x.abs() >= d.y.abs();
        let ascending = if along_x { d.x > 0.0 } else { d.y > 0.0 };
        let cmp = |mesh: &TriMesh, p: VertexId, q: VertexId| {
            let o = cmp_coordinate(mesh, along_x, p, q);
            if ascending { o } else { o.reverse() }
        };
        let mut u = va;
        let mut s_u = 0.0;
        let mut faces: Vec<FaceId> = Vec::new();
        let mut ring: Vec<VertexId> = Vec::new();
        for _ in 0..=mesh.num_vertices() {
            if u == vb {
                break;
            }
            // The next vertex is the nearest one of u's neighbours ahead of u
            // (not past vb) on the segment's line. The order tests read
            // rounded coordinates and come first; the collinearity test, exact
            // for the rational neighbours, is asked only of a neighbour
            // nearer than the best one so far, once per neighbour.
            mesh.incident_faces_into(u, &mut faces);
            ring.clear();
            for &f in &faces {
                for w in mesh.face(f) {
                    if w != u && !ring.contains(&w) {
                        ring.push(w);
                    }
                }
            }
            let mut best: Option<VertexId> = None;
            for &w in &ring {
                if cmp(mesh, w, u) != Ordering::Greater || cmp(mesh, w, vb) == Ordering::Greater {
                    continue;
                }
                if best.is_some_and(|b| cmp(mesh, w, b) != Ordering::Less) {
                    continue;
                }
                let at_w = match mesh.exact(w) {
                    None => PointRef::F64(mesh.position(w)),
                    Some(qw) => PointRef::Q(qw),
                };
                let on_line = orient2d_mixed(PointRef::F64(seg.a), PointRef::F64(seg.b), at_w);
                if on_line == Orientation::Collinear {
                    best = Some(w);
                }
            }
            let Some(w) = best else {
                return Err(not_conforming("no next edge"));
            };
            let s_w = if w == vb {
                1.0
            } else {
                param(mesh.position(w))
            };
            let tag = match seg.tag {
                SegmentTag::Primary { section, t } => FeatureOn::Primary {
                    section,
                    t: [t[0] + (t[1] - t[0]) * s_u, t[0] + (t[1] - t[0]) * s_w],
                },
                SegmentTag::Secondary { polyline } => FeatureOn::Secondary { polyline },
            };
            tags.push((u, w, tag));
            u = w;
            s_u = s_w;
        }
        if u != vb {
            return Err(not_conforming("walk budget exhausted"));
        }
        Ok(tags)
    };
    // The walks of a chunk run in parallel; the chunks, and the tags within
    // each, go on in segment order, so the tags are the same for any number
    // of threads or chunk size.
    let mut walks: Vec<Result<Vec<(VertexId, VertexId, FeatureOn)>>> = Vec::new();
    for chunk in input.segments.chunks(CHECK_EVERY) {
        check_deadline(deadline, Stage::Bsp)?;
        walks.extend(chunk.par_iter().map(walk).collect::<Vec<_>>());
    }
    for (i, tags) in walks.into_iter().enumerate() {
        if i % CHECK_EVERY == 0 {
            check_deadline(deadline, Stage::Bsp)?;
        }
        for (u, w, tag) in tags? {
            mesh.add_edge_tag(u, w, tag);
        }
    }
    Ok(())
}

/// How many ulps away from the nearest `f64` coordinate rounding may look when
/// the nearest point would invert a triangle.
const ROUND_ULPS: i32 = 2;

/// The next `f64` above `x` (`f64::next_up` needs a newer Rust than the MSRV).
fn next_up(x: f64) -> f64 {
    if x.is_nan() || x == f64::INFINITY {
        x
    } else if x == 0.0 {
        f64::from_bits(1)
    } else if x > 0.0 {
        f64::from_bits(x.to_bits() + 1)
    } else {
        f64::from_bits(x.to_bits() - 1)
    }
}

/// `x` moved by `k` ulps (`k` may be negative).
fn step_ulps(x: f64, k: i32) -> f64 {
    let mut y = x;
    for _ in 0..k.unsigned_abs() {
        y = if k > 0 { next_up(y) } else { -next_up(-y) };
    }
    y
}

/// The `f64` points tried when rounding a vertex at exact position `q` whose
/// nearest `f64` point is `p`: `p` first, then points up to [`ROUND_ULPS`]
/// ulps away per coordinate, nearest (in ulps) first. A coordinate that is
/// exactly an `f64` (e.g. on a box side or an axis-parallel segment) is kept.
pub(super) fn round_candidates(p: kurbo::Point, exact: [bool; 2]) -> Vec<kurbo::Point> {
    let range = |e: bool| if e { 0..=0 } else { -ROUND_ULPS..=ROUND_ULPS };
    let mut offsets: Vec<(i32, i32)> = range(exact[0])
        .flat_map(|i| range(exact[1]).map(move |j| (i, j)))
        .collect();
    offsets.sort_by_key(|&(i, j)| (i.abs().max(j.abs()), i.abs() + j.abs()));
    offsets
        .into_iter()
        .map(|(i, j)| kurbo::Point::new(step_ulps(p.x, i), step_ulps(p.y, j)))
        .filter(|c| c.x.is_finite() && c.y.is_finite())
        .collect()
}

/// The faces of each rational vertex, in face order, in one array (one list
/// per vertex slot would be an allocation and a free per slot: hundreds of
/// thousands on a large BSP).
struct Stars {
    /// Where each vertex slot's faces start in `faces`; one entry more.
    start: Vec<usize>,
    faces: Vec<FaceId>,
}

impl Stars {
    fn of_rational(mesh: &TriMesh) -> Self {
        let mut start = vec![0usize; mesh.vertex_capacity() + 1];
        for f in mesh.faces() {
            for v in mesh.face(f) {
                if mesh.is_rational(v) {
                    start[v.index() + 1] += 1;
                }
            }
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut next = start.clone();
        let mut faces = vec![FaceId::from_index(0); start[start.len() - 1]];
        for f in mesh.faces() {
            for v in mesh.face(f) {
                if mesh.is_rational(v) {
                    faces[next[v.index()]] = f;
                    next[v.index()] += 1;
                }
            }
        }
        Stars { start, faces }
    }

    fn of(&self, v: VertexId) -> &[FaceId] {
        &self.faces[self.start[v.index()]..self.start[v.index() + 1]]
    }
}

/// Round every rational vertex to an `f64` point when all its incident
/// triangles stay exactly counter-clockwise: the nearest one, else one a few
/// ulps away ([`round_candidates`]); repeat up to `passes` times while
/// something changed.
///
/// A pass is Gauss–Seidel: the vertices in index order, each seeing the
/// earlier ones rounded. It runs in levels ([`rounding_levels`]) so that the
/// vertices of a level are decided in parallel with exactly the outcome of
/// the sequential order, for any number of threads.
///
/// # Errors
/// The deadline's error when it is passed (checked every [`CHECK_EVERY`]
/// vertices decided).
pub(super) fn round_vertices(mesh: &mut TriMesh, passes: u32, deadline: &Deadline) -> Result<()> {
    for _ in 0..passes {
        let star = Stars::of_rational(mesh);
        let rational: Vec<VertexId> = mesh.vertices().filter(|&v| mesh.is_rational(v)).collect();
        let mut changed = false;
        let mut decided = 0usize;
        for level in rounding_levels(mesh, &rational, &star) {
            // A level's vertices share no face: deciding it a chunk at a time
            // (each chunk's moves made before the next is decided) gives the
            // same moves as deciding it at once.
            for chunk in level.chunks(CHECK_EVERY) {
                if decided >= CHECK_EVERY {
                    check_deadline(deadline, Stage::Bsp)?;
                    decided = 0;
                }
                decided += chunk.len();
                let m: &TriMesh = mesh;
                let decide = |&v: &VertexId| (v, rounded(m, v, star.of(v)));
                let moves: Vec<(VertexId, Option<kurbo::Point>)> =
                    if chunk.len() >= PAR_ROUND_MIN && rayon::current_num_threads() > 1 {
                        chunk.par_iter().map(decide).collect()
                    } else {
                        chunk.iter().map(decide).collect()
                    };
                for (v, to) in moves {
                    if let Some(to) = to {
                        mesh.set_position(v, to);
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    Ok(())
}

/// The fewest vertices of a rounding level decided in parallel (fewer cost
/// more to hand out than to decide).
const PAR_ROUND_MIN: usize = 64;

/// The rational vertices (in index order) grouped in levels: a vertex's level
/// is one more than the highest level of the earlier rational vertices of its
/// star (0 without). Rounding reads only the vertices of a vertex's star, so
/// when the levels are rounded one after the other, each vertex sees the
/// earlier vertices of its star rounded (lower levels) and the later ones not
/// (higher levels), as in index order; the vertices of one level share no
/// face and are decided independently.
fn rounding_levels(mesh: &TriMesh, rational: &[VertexId], star: &Stars) -> Vec<Vec<VertexId>> {
    let mut order = vec![usize::MAX; mesh.vertex_capacity()];
    for (i, v) in rational.iter().enumerate() {
        order[v.index()] = i;
    }
    let mut level = vec![0usize; mesh.vertex_capacity()];
    let mut levels: Vec<Vec<VertexId>> = Vec::new();
    for &v in rational {
        let mine = order[v.index()];
        let lv = star
            .of(v)
            .iter()
            .flat_map(|&f| mesh.face(f))
            .filter(|w| order[w.index()] < mine)
            .map(|w| level[w.index()] + 1)
            .max()
            .unwrap_or(0);
        level[v.index()] = lv;
        if levels.len() <= lv {
            levels.resize_with(lv + 1, Vec::new);
        }
        levels[lv].push(v);
    }
    levels
}

/// Where [`round_vertices`] moves rational vertex `v` with faces `star`, on
/// the mesh as it is: its nearest `f64` point, else the first candidate that
/// keeps every face counter-clockwise; `None` for none.
fn rounded(mesh: &TriMesh, v: VertexId, star: &[FaceId]) -> Option<kurbo::Point> {
    let fits = |p: kurbo::Point| {
        star.iter()
            .all(|&f| mesh.orientation_if_moved(f, v, p) == Orientation::CounterClockwise)
    };
    let p = mesh.position(v);
    if fits(p) {
        return Some(p);
    }
    let exact = mesh
        .exact(v)
        .expect("internal: listed as rational")
        .coords_are_f64();
    round_candidates(p, exact)
        .into_iter()
        .skip(1)
        .find(|&c| fits(c))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vertex map keys on the nearest `f64` point but keeps apart exact
    /// points that round alike, and finds an `f64` vertex from an exact corner.
    #[test]
    fn the_vertex_map_tells_apart_points_that_round_alike() {
        let bary = |pts: [(f64, f64); 3]| {
            PointQ::barycentre(&pts.map(|(x, y)| PointQ::from_point(kurbo::Point::new(x, y))))
                .expect("three points")
        };
        let mut mesh = TriMesh::new();
        let mut vmap = VertexMap::default();
        let p = kurbo::Point::new(1.0, 2.0);
        let seed = mesh.add_vertex(p, VertexTag::default());
        vmap.insert_f64(p, seed);
        let third = bary([(0.0, 0.0), (3.0, 0.0), (0.0, 1.0)]);
        let near = bary([(0.0, 0.0), (3.0, 2f64.powi(-60)), (0.0, 1.0)]);
        let near_p = bary([(0.0, 2.0), (3.0, 2f64.powi(-55)), (0.0, 4.0)]);
        assert!(third != near);
        assert_eq!(third.to_f64(), (near.to_f64().0, false));
        assert_eq!(near_p.to_f64(), (p, false));
        let a = vmap.get_or_add(&mut mesh, Corner::new(third.clone()));
        let b = vmap.get_or_add(&mut mesh, Corner::new(near.clone()));
        let c = vmap.get_or_add(&mut mesh, Corner::new(near_p.clone()));
        assert!(a != b && a != c && b != c && c != seed);
        assert_eq!(vmap.get_or_add(&mut mesh, Corner::new(third.clone())), a);
        assert_eq!(vmap.get_or_add(&mut mesh, Corner::new(near.clone())), b);
        assert_eq!(vmap.get_or_add(&mut mesh, Corner::new(near_p)), c);
        assert_eq!(
            vmap.get_or_add(&mut mesh, Corner::new(PointQ::from_point(p))),
            seed
        );
        assert_eq!(mesh.num_vertices(), 4);
        assert!(mesh.exact(a) == Some(&third) && mesh.exact(b) == Some(&near));
    }

    #[test]
    fn candidates_start_at_the_nearest_point_and_keep_exact_coordinates() {
        let p = kurbo::Point::new(1.0, 3.0);
        let c = round_candidates(p, [false, false]);
        assert_eq!(c.len(), 25);
        assert_eq!(c[0], p);
        assert!(
            c[1..9]
                .iter()
                .all(|q| (q.x - p.x).abs() <= 2.3e-16 && (q.y - p.y).abs() <= 4.5e-16)
        );
        let c = round_candidates(p, [true, false]);
        assert_eq!(c.len(), 5);
        assert!(c.iter().all(|q| q.x == 1.0));
        assert_eq!(round_candidates(p, [true, true]), vec![p]);
    }
}
