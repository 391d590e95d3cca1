//! gmsh MSH writers: 4.1 and 2.2, ASCII and binary.
//!
//! Layout shared by both versions (gmsh reference manual, "MSH file format"):
//! - one physical surface per used `FemMesh::surfaces` entry (physical tag = index + 1),
//!   one physical curve per used `FemMesh::curves` entry (physical tag = index + 1);
//!   groups without elements are not written;
//! - physical names are unique within a file, across dimensions (meshio keys its
//!   `field_data` by name alone): the domain's boundary keeps `boundary`, a surface
//!   keeps its name, a curve whose name is taken is written as `<name>-curve` (then
//!   `-curve-2`, …); see `physical_names_of`;
//! - the entities of a discrete gmsh model ([`Layout`]): points where curves meet,
//!   curve entities per connected piece of edges on the same physical curves (an
//!   edge on several physical curves, such as an outline that is also the
//!   domain's boundary, is one line element in one entity that each of those
//!   physical curves lists), one surface entity per
//!   physical surface (tag = its physical tag) bounded by its curves, each entity
//!   holding elements of one type only (gmsh's API shows one element type per
//!   entity); 4.1 writes `$Entities` and lists each node under the entity of lowest
//!   dimension it lies on, 2.2 writes the same elementary tags;
//! - node tags 1..=N in `FemMesh::nodes` order; element tags 1..=M, triangles
//!   first (by surface), then lines (by curve entity); no two line elements join
//!   the same two nodes in 4.1. MSH 2.2 gives each element one physical tag, so
//!   there a line on several physical curves is written once per curve, in an
//!   entity per curve (gmsh's own `refine()` rejects such shared nodes: use 4.1);
//! - coordinates in ASCII are shortest round-trip decimal (`{:?}`), so they read
//!   back bit-exactly; binary uses native byte order with gmsh's endianness marker.

use crate::FemMesh;
use crate::element::Order;
use crate::fem::LineKind;
use rayon::prelude::*;
use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};
use std::io::{self, Write};

/// gmsh element type numbers of (triangle, line) for an element order.
fn element_types(order: Order) -> (i32, i32) {
    (order.gmsh_triangle_type(), order.gmsh_line_type())
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("malformed mesh: {msg}"),
    )
}

/// Check everything the writers rely on, so they never index out of bounds.
pub(crate) fn validate(mesh: &FemMesh) -> io::Result<()> {
    let order = mesh.order();
    let (tn, ln) = (order.triangle_nodes(), order.line_nodes());
    if mesh.triangles.len() % tn != 0 {
        return Err(invalid(format!(
            "{} triangle indices is not a multiple of {tn}",
            mesh.triangles.len()
        )));
    }
    if mesh.lines.len() % ln != 0 {
        return Err(invalid(format!(
            "{} line indices is not a multiple of {ln}",
            mesh.lines.len()
        )));
    }
    if mesh.triangle_group.len() != mesh.triangle_count() {
        return Err(invalid(format!(
            "{} triangle groups for {} triangles",
            mesh.triangle_group.len(),
            mesh.triangle_count()
        )));
    }
    if mesh.line_group.len() != mesh.line_count() {
        return Err(invalid(format!(
            "{} line groups for {} lines",
            mesh.line_group.len(),
            mesh.line_count()
        )));
    }
    if let Some(g) = mesh
        .triangle_group
        .iter()
        .find(|&&g| g as usize >= mesh.surfaces.len())
    {
        return Err(invalid(format!(
            "surface group {g} of {}",
            mesh.surfaces.len()
        )));
    }
    if let Some(g) = mesh
        .line_group
        .iter()
        .find(|&&g| g as usize >= mesh.curves.len())
    {
        return Err(invalid(format!("curve group {g} of {}", mesh.curves.len())));
    }
    let n = mesh.nodes.len();
    if let Some(i) = mesh
        .triangles
        .iter()
        .chain(&mesh.lines)
        .find(|&&i| i as usize >= n)
    {
        return Err(invalid(format!("node index {i} of {n} nodes")));
    }
    if let Some(p) = mesh
        .nodes
        .iter()
        .find(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(invalid(format!("non-finite node {p:?}")));
    }
    // gmsh reads tags as C `int` in several places (2.2 everywhere, 4.1 entity tags).
    let max = i32::MAX as usize;
    if n > max || mesh.triangle_count() + mesh.line_count() > max {
        return Err(invalid(
            "more than 2^31 nodes or elements; gmsh cannot read that".to_owned(),
        ));
    }
    Ok(())
}

/// Axis-aligned box of some nodes, as gmsh's entity bounding box.
#[derive(Clone, Copy)]
struct BBox {
    min: [f64; 2],
    max: [f64; 2],
}

impl BBox {
    fn of(mesh: &FemMesh, nodes: impl Iterator<Item = u32>) -> BBox {
        let mut b = BBox {
            min: [f64::INFINITY; 2],
            max: [f64::NEG_INFINITY; 2],
        };
        for i in nodes {
            let p = mesh.nodes[i as usize];
            b.min = [b.min[0].min(p.x), b.min[1].min(p.y)];
            b.max = [b.max[0].max(p.x), b.max[1].max(p.y)];
        }
        if b.min[0] > b.max[0] {
            b = BBox {
                min: [0.0; 2],
                max: [0.0; 2],
            };
        }
        b
    }
}

/// One elementary entity of dimension 1 or 2: one element block.
struct Entity {
    /// 1 (curve) or 2 (surface).
    dim: i32,
    /// Entity tag: a surface's is its physical tag (group index + 1); curves
    /// are numbered 1.. in order (pieces of physical curves).
    tag: i32,
    /// Physical tags (group index + 1), ascending; empty for the fallback
    /// entity that only carries nodes.
    physical: Vec<i32>,
    /// gmsh element type.
    etype: i32,
    /// Element indices (into triangles or lines) in this entity.
    elems: Vec<u32>,
    bbox: BBox,
    /// Signed tags of the bounding entities (one dimension lower): a curve's
    /// points (positive where it starts, negative where it ends), a surface's
    /// curves (positive when the curve runs with the surface on its left).
    bounding: Vec<i32>,
}

/// The discrete gmsh model of a mesh: its entities and where each node lies.
///
/// - Points: one at every corner where curves meet (a node where the line
///   elements' distinct edges are not exactly two of the same physical
///   curves: ends, branches, crossings, a change of curves), and one on each
///   closed curve that has none (its smallest node).
/// - Curves: the distinct edges of the line elements, grouped by the set of
///   physical curves on them and cut at the points into connected pieces, one
///   entity each, listed by every physical curve of its set. An edge on
///   several physical curves (an outline that is also the domain's boundary,
///   the outline two shapes share) is one element, written in the direction
///   of the boundary's line if it is on the boundary, else of the line of the
///   lowest curve: along a piece, one curve's consistent direction.
/// - Surfaces: one per physical surface, bounded by the curve entities along
///   which it meets another surface or nothing.
/// - Each node is classified on the entity of lowest dimension it lies on
///   (the first such curve when pieces coincide); a node no element uses goes
///   to the first surface (or curve).
struct Layout {
    /// Point entities: (tag, node index); tags 1.. in node order.
    points: Vec<(i32, u32)>,
    /// Surfaces (tag order), then curves (tag order).
    entities: Vec<Entity>,
    /// (dimension, entity tag) of each node; empty for a mesh without nodes.
    node_entity: Vec<(i32, i32)>,
}

/// Group element indices by group (stable counting sort); only non-empty groups.
pub(super) fn bucket(groups: &[u32], count: usize) -> Vec<(u32, Vec<u32>)> {
    let mut sizes = vec![0usize; count];
    for &g in groups {
        sizes[g as usize] += 1;
    }
    let mut out: Vec<(u32, Vec<u32>)> = Vec::new();
    let mut slot = vec![usize::MAX; count];
    for (g, &s) in sizes.iter().enumerate() {
        if s > 0 {
            slot[g] = out.len();
            out.push((g as u32, Vec::with_capacity(s)));
        }
    }
    for (i, &g) in groups.iter().enumerate() {
        out[slot[g as usize]].1.push(i as u32);
    }
    out
}

/// An undirected edge between two corner nodes.
fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Union-find root with path halving.
fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        parent[i as usize] = parent[parent[i as usize] as usize];
        i = parent[i as usize];
    }
    i
}

/// The distinct edges of a mesh's line elements: for each, the line element
/// that stands for it (the boundary's, else the lowest physical curve's, else
/// the first) and the physical curves on it (group indices, ascending), in
/// order of the standing line. Unless `shared` (MSH 2.2, one physical tag per
/// element): then every line element stands for itself, on its own curve.
fn distinct_edges(mesh: &FemMesh, shared: bool) -> Vec<(u32, Vec<u32>)> {
    if !shared {
        // MSH 2.2: every line stands for itself, on its own curve
        return (0..mesh.line_count())
            .map(|l| (l as u32, vec![mesh.line_group[l]]))
            .collect();
    }
    let rank = |l: usize| {
        (
            mesh.line_kind.get(l) != Some(&LineKind::Boundary),
            mesh.line_group[l],
            l,
        )
    };
    let mut index: HashMap<(u32, u32), usize> = HashMap::default();
    let mut edges: Vec<(u32, Vec<u32>)> = Vec::new();
    for l in 0..mesh.line_count() {
        let line = mesh.line(l);
        let g = mesh.line_group[l];
        let k = *index.entry(edge_key(line[0], line[1])).or_insert_with(|| {
            edges.push((l as u32, Vec::new()));
            edges.len() - 1
        });
        let (rep, groups) = &mut edges[k];
        if rank(l) < rank(*rep as usize) {
            *rep = l as u32;
        }
        if !groups.contains(&g) {
            groups.push(g);
        }
    }
    for (_, groups) in &mut edges {
        groups.sort_unstable();
    }
    edges.sort_unstable_by_key(|e| e.0);
    edges
}

/// The corner nodes where curves meet (see [`Layout`]), from the distinct
/// edges and their curves.
fn corner_nodes(mesh: &FemMesh, edges: &[(u32, Vec<u32>)]) -> HashSet<u32> {
    let mut at: HashMap<u32, Vec<usize>> = HashMap::default();
    for (k, (rep, _)) in edges.iter().enumerate() {
        let line = mesh.line(*rep as usize);
        at.entry(line[0]).or_default().push(k);
        at.entry(line[1]).or_default().push(k);
    }
    at.into_iter()
        .filter(|(_, ks)| ks.len() != 2 || edges[ks[0]].1 != edges[ks[1]].1)
        .map(|(v, _)| v)
        .collect()
}

impl Layout {
    /// The layout of `mesh`; `shared`: an edge on several physical curves is
    /// one element in one entity they all list (MSH 4.1), else one element and
    /// entity per curve (MSH 2.2, where an element has one physical tag).
    fn new(mesh: &FemMesh, shared: bool) -> Layout {
        let (ttype, ltype) = element_types(mesh.order());
        let mut entities = Vec::new();
        for (g, elems) in bucket(&mesh.triangle_group, mesh.surfaces.len()) {
            let bbox = BBox::of(
                mesh,
                elems
                    .iter()
                    .flat_map(|&t| mesh.triangle(t as usize).iter().copied()),
            );
            let tag = g as i32 + 1;
            entities.push(Entity {
                dim: 2,
                tag,
                physical: vec![tag],
                etype: ttype,
                elems,
                bbox,
                bounding: Vec::new(),
            });
        }
        let surface_count = entities.len();

        // Curves: the distinct edges by the curves on them, cut at the corners
        // into pieces.
        let edges = distinct_edges(mesh, shared);
        let mut corners = corner_nodes(mesh, &edges);
        if let Some(p) = &mesh.periodic {
            // a corner on one side is one on its partner side too, so the
            // sides are cut into partner pieces (twice: a cell corner's
            // partners chain through both axes)
            for _ in 0..2 {
                for pair in &p.pairs {
                    if corners.contains(&pair.node) || corners.contains(&pair.master) {
                        corners.insert(pair.node);
                        corners.insert(pair.master);
                    }
                }
            }
        }
        let mut point_of: HashMap<u32, i32> = HashMap::default();
        let mut loop_points: Vec<u32> = Vec::new();
        let mut pieces: Vec<(Vec<u32>, Vec<u32>)> = Vec::new();
        let mut parent: Vec<u32> = (0..mesh.line_count() as u32).collect();
        let mut by_curves: Vec<(Vec<u32>, Vec<u32>)> = Vec::new();
        {
            let mut slot: HashMap<&[u32], usize> = HashMap::default();
            for (rep, groups) in &edges {
                let k = *slot.entry(groups.as_slice()).or_insert_with(|| {
                    by_curves.push((groups.clone(), Vec::new()));
                    by_curves.len() - 1
                });
                by_curves[k].1.push(*rep);
            }
        }
        by_curves.sort_unstable_by(|a, b| a.0.cmp(&b.0));
        for (g, elems) in by_curves {
            let mut through: HashMap<u32, u32> = HashMap::default();
            for &l in &elems {
                for &v in &mesh.line(l as usize)[..2] {
                    if corners.contains(&v) {
                        continue;
                    }
                    match through.get(&v) {
                        Some(&other) => {
                            let (a, b) = (find(&mut parent, l), find(&mut parent, other));
                            parent[a.max(b) as usize] = a.min(b);
                        }
                        None => {
                            through.insert(v, l);
                        }
                    }
                }
            }
            let mut piece_of: HashMap<u32, usize> = HashMap::default();
            for &l in &elems {
                let root = find(&mut parent, l);
                let k = *piece_of.entry(root).or_insert_with(|| {
                    pieces.push((g.clone(), Vec::new()));
                    pieces.len() - 1
                });
                pieces[k].1.push(l);
            }
        }
        // A closed piece without a corner gets a point at its smallest node.
        for (_, elems) in &pieces {
            let ends = elems.iter().flat_map(|&l| &mesh.line(l as usize)[..2]);
            if !ends.clone().any(|v| corners.contains(v)) {
                if let Some(&v) = ends.min() {
                    loop_points.push(v);
                }
            }
        }
        let mut point_nodes: Vec<u32> = corners.iter().copied().chain(loop_points).collect();
        point_nodes.sort_unstable();
        point_nodes.dedup();
        let points: Vec<(i32, u32)> = point_nodes
            .iter()
            .enumerate()
            .map(|(i, &v)| (i as i32 + 1, v))
            .collect();
        for &(tag, v) in &points {
            point_of.insert(v, tag);
        }
        for (k, (g, elems)) in pieces.into_iter().enumerate() {
            let bbox = BBox::of(
                mesh,
                elems
                    .iter()
                    .flat_map(|&l| mesh.line(l as usize).iter().copied()),
            );
            // Bounding points: where the piece starts (+) and ends (-).
            let mut bounding = Vec::new();
            for (slot, sign) in [(0usize, 1i32), (1, -1)] {
                let mut seen: Vec<i32> = Vec::new();
                for &l in &elems {
                    if let Some(&p) = point_of.get(&mesh.line(l as usize)[slot]) {
                        if !seen.contains(&p) {
                            seen.push(p);
                            bounding.push(sign * p);
                        }
                    }
                }
            }
            entities.push(Entity {
                dim: 1,
                tag: k as i32 + 1,
                physical: g.iter().map(|&g| g as i32 + 1).collect(),
                etype: ltype,
                elems,
                bbox,
                bounding,
            });
        }

        // Surfaces' bounding curves: the pieces along which a surface meets
        // another surface or nothing, signed by which side it is on.
        // Every triangle side by its edge, then in triangle order (3 t + e):
        // an edge's sides are one run, in the order the triangles come.
        // (Sorted once: a map of small vectors would take most of the
        // writer's time on a large mesh.)
        let side = |order: u32| {
            let (t, e) = ((order / 3) as usize, (order % 3) as usize);
            let c = mesh.triangle(t);
            (edge_key(c[e], c[(e + 1) % 3]), order)
        };
        let mut sides: Vec<((u32, u32), u32)> =
            (0..3 * mesh.triangle_count() as u32).map(side).collect();
        sides.sort_unstable();
        let sides_of = |k: (u32, u32)| -> Vec<(u32, u32)> {
            let from = sides.partition_point(|s| s.0 < k);
            sides[from..]
                .iter()
                .take_while(|s| s.0 == k)
                .map(|&(_, order)| {
                    let (t, e) = ((order / 3) as usize, (order % 3) as usize);
                    (mesh.triangle_group[t], mesh.triangle(t)[e])
                })
                .collect()
        };
        let surface_index: HashMap<i32, usize> = entities[..surface_count]
            .iter()
            .enumerate()
            .map(|(i, e)| (e.tag, i))
            .collect();
        for ci in surface_count..entities.len() {
            let mut bounds: Vec<(usize, i32)> = Vec::new();
            for &l in &entities[ci].elems {
                let line = mesh.line(l as usize);
                let adjacent = sides_of(edge_key(line[0], line[1]));
                for &(g, start) in &adjacent {
                    let on_boundary = adjacent.len() == 1 || adjacent.iter().any(|s| s.0 != g);
                    let Some(&si) = surface_index.get(&(g as i32 + 1)) else {
                        continue;
                    };
                    if on_boundary && !bounds.iter().any(|b| b.0 == si) {
                        let sign = if start == line[0] { 1 } else { -1 };
                        bounds.push((si, sign * entities[ci].tag));
                    }
                }
            }
            for (si, signed) in bounds {
                entities[si].bounding.push(signed);
            }
        }

        // Nodes on the entity of lowest dimension they lie on.
        let mut node_entity = vec![(0i32, 0i32); mesh.nodes.len()];
        for &(tag, v) in &points {
            node_entity[v as usize] = (0, tag);
        }
        for e in entities[surface_count..]
            .iter()
            .chain(&entities[..surface_count])
        {
            for &i in &e.elems {
                for &v in element_nodes(mesh, e, i) {
                    if node_entity[v as usize].1 == 0 {
                        node_entity[v as usize] = (e.dim, e.tag);
                    }
                }
            }
        }
        let fallback = entities.first().map(|e| (e.dim, e.tag)).unwrap_or((2, 1));
        if entities.is_empty() && !mesh.nodes.is_empty() {
            // Nodes but no elements: a bare surface entity keeps them readable.
            entities.push(Entity {
                dim: 2,
                tag: 1,
                physical: Vec::new(),
                etype: ttype,
                elems: Vec::new(),
                bbox: BBox::of(mesh, 0..mesh.nodes.len() as u32),
                bounding: Vec::new(),
            });
        }
        for ne in &mut node_entity {
            if ne.1 == 0 {
                *ne = fallback;
            }
        }
        Layout {
            points,
            entities,
            node_entity,
        }
    }

    fn element_count(&self) -> usize {
        self.entities.iter().map(|e| e.elems.len()).sum()
    }

    fn blocks(&self) -> impl Iterator<Item = &Entity> {
        self.entities.iter().filter(|e| !e.elems.is_empty())
    }

    /// The node blocks of MSH 4.1: (dim, tag, node indices in order), points,
    /// then curves, then surfaces, each in tag order.
    fn node_blocks(&self) -> Vec<((i32, i32), Vec<u32>)> {
        let mut blocks: HashMap<(i32, i32), Vec<u32>> = HashMap::default();
        for (v, &e) in self.node_entity.iter().enumerate() {
            blocks.entry(e).or_default().push(v as u32);
        }
        let mut out: Vec<((i32, i32), Vec<u32>)> = blocks.into_iter().collect();
        out.sort_unstable_by_key(|(e, _)| *e);
        out
    }
}

/// Node indices of element `i` of an entity.
fn element_nodes<'m>(mesh: &'m FemMesh, e: &Entity, i: u32) -> &'m [u32] {
    if e.dim == 2 {
        mesh.triangle(i as usize)
    } else {
        mesh.line(i as usize)
    }
}

/// Writes numbers as ASCII text or native-endian binary.
struct Out<'w, W: Write> {
    w: &'w mut W,
    binary: bool,
    /// Separator pending before the next ASCII value.
    sep: bool,
}

impl<W: Write> Out<'_, W> {
    fn ascii_sep(&mut self) -> io::Result<()> {
        if self.sep {
            self.w.write_all(b" ")?;
        }
        self.sep = true;
        Ok(())
    }
    fn uint(&mut self, v: u64) -> io::Result<()> {
        self.ascii_sep()?;
        let mut buf = [0u8; 20];
        let mut i = buf.len();
        let mut v = v;
        loop {
            i -= 1;
            buf[i] = b'0' + (v % 10) as u8;
            v /= 10;
            if v == 0 {
                break;
            }
        }
        self.w.write_all(&buf[i..])
    }
    /// A C `int` (gmsh "int" fields).
    fn int(&mut self, v: i32) -> io::Result<()> {
        if self.binary {
            return self.w.write_all(&v.to_ne_bytes());
        }
        if v < 0 {
            self.ascii_sep()?;
            self.sep = false;
            self.w.write_all(b"-")?;
        }
        self.uint(u64::from(v.unsigned_abs()))
    }
    /// A `size_t` (gmsh 4.1 "size_t" fields; data-size 8).
    fn size(&mut self, v: u64) -> io::Result<()> {
        if self.binary {
            return self.w.write_all(&v.to_ne_bytes());
        }
        self.uint(v)
    }
    fn float(&mut self, v: f64) -> io::Result<()> {
        if self.binary {
            return self.w.write_all(&v.to_ne_bytes());
        }
        self.ascii_sep()?;
        if v == 0.0 && v.is_sign_positive() {
            // Every node's z: what `{:?}` prints, without the formatter.
            return self.w.write_all(b"0.0");
        }
        write!(self.w, "{v:?}")
    }
    /// End of an ASCII line (nothing in binary).
    fn eol(&mut self) -> io::Result<()> {
        self.sep = false;
        if self.binary {
            Ok(())
        } else {
            self.w.write_all(b"\n")
        }
    }
    /// End of a section's data: binary data is followed by a newline.
    fn end_data(&mut self) -> io::Result<()> {
        self.sep = false;
        if self.binary {
            self.w.write_all(b"\n")
        } else {
            Ok(())
        }
    }
}

/// Write a line for each of `items` through `o` (`line` writes one, ending
/// it), formatted in parallel chunks and written in order: the bytes of
/// writing them one by one. Formatting the node coordinates was the most of
/// the writer's time, and the writer runs after the mesher, alone.
fn lines_in_parallel<W: Write, T: Sync>(
    o: &mut Out<'_, W>,
    items: &[T],
    line: impl Fn(&mut Out<'_, Vec<u8>>, &T) -> io::Result<()> + Sync,
) -> io::Result<()> {
    /// Lines formatted by one job.
    const CHUNK: usize = 4096;
    /// Chunks held at once (a bound on the memory of the formatted text).
    const WINDOW: usize = 64;
    debug_assert!(!o.sep, "lines start after an end of line");
    let binary = o.binary;
    for window in items.chunks(CHUNK * WINDOW) {
        let texts: Vec<io::Result<Vec<u8>>> = window
            .par_chunks(CHUNK)
            .map(|chunk| {
                let mut text = Vec::with_capacity(chunk.len() * 64);
                let mut c = Out {
                    w: &mut text,
                    binary,
                    sep: false,
                };
                for item in chunk {
                    line(&mut c, item)?;
                }
                Ok(text)
            })
            .collect();
        for text in texts {
            o.w.write_all(&text?)?;
        }
    }
    Ok(())
}

fn header<W: Write>(w: &mut W, version: &str, binary: bool) -> io::Result<()> {
    writeln!(w, "$MeshFormat\n{version} {} 8", u8::from(binary))?;
    if binary {
        w.write_all(&1i32.to_ne_bytes())?;
        w.write_all(b"\n")?;
    }
    w.write_all(b"$EndMeshFormat\n")
}

/// Longest physical name gmsh documents (longer ones may not read back).
const MAX_NAME_CHARS: usize = 127;

/// A name as gmsh reads it (without its quotes): on one line, no double quote,
/// at most [`MAX_NAME_CHARS`] characters.
fn clean_name(name: &str) -> String {
    name.chars()
        .take(MAX_NAME_CHARS)
        .map(|c| match c {
            '"' => '\'',
            c if c.is_control() => ' ',
            c => c,
        })
        .collect()
}

/// `base` shortened so that `base + suffix` fits in [`MAX_NAME_CHARS`].
fn with_suffix(base: &str, suffix: &str) -> String {
    let keep = MAX_NAME_CHARS.saturating_sub(suffix.chars().count());
    let mut s: String = base.chars().take(keep).collect();
    s.push_str(suffix);
    s
}

/// The physical groups of `layout`, as (dimension, tag, name written): the
/// group's cleaned name, made unique within the file. meshio (and any reader
/// that maps names to groups) keeps one group per name, so a surface and a
/// curve of the same name (in `--regions shape`, a shape's surface and its
/// feature edges) would lose one. The domain's boundary (the curves of
/// [`LineKind::Boundary`] lines, named [`crate::fem::BOUNDARY`]) is named
/// first, then surfaces, then the other curves; a name already taken gets
/// `-surface` / `-curve`, then `-2`, `-3`, … until it is free. Listed surfaces
/// first, then curves, each in tag order.
fn physical_names_of(mesh: &FemMesh, layout: &Layout) -> Vec<(i32, i32, String)> {
    let groups: Vec<(i32, i32)> = layout
        .entities
        .iter()
        .flat_map(|e| e.physical.iter().map(|&p| (e.dim, p)))
        .collect();
    names_of_groups(mesh, groups)
}

/// The physical names of the groups with elements (as [`physical_names_of`]),
/// found from the element lists alone: what the .vtu writer names its groups.
pub(crate) fn group_names(mesh: &FemMesh) -> Vec<(i32, i32, String)> {
    let tag = |g: u32| i32::try_from(g).unwrap_or(i32::MAX - 1) + 1;
    let groups = (mesh.triangle_group.iter().map(|&g| (2, tag(g))))
        .chain(mesh.line_group.iter().map(|&g| (1, tag(g))))
        .collect();
    names_of_groups(mesh, groups)
}

/// Name `groups` (`(dim, tag)`, any order, repeats allowed) as
/// [`physical_names_of`] says.
fn names_of_groups(mesh: &FemMesh, mut groups: Vec<(i32, i32)>) -> Vec<(i32, i32, String)> {
    groups.sort_unstable_by_key(|&(dim, tag)| (std::cmp::Reverse(dim), tag));
    groups.dedup();
    let mut is_boundary = vec![false; mesh.curves.len()];
    for (i, &g) in mesh.line_group.iter().enumerate() {
        if mesh.line_kind.get(i) == Some(&LineKind::Boundary) {
            is_boundary[g as usize] = true;
        }
    }
    let priority = |&(dim, tag): &(i32, i32)| match dim {
        1 if is_boundary[(tag - 1) as usize] => 0,
        2 => 1,
        _ => 2,
    };
    let mut naming: Vec<usize> = (0..groups.len()).collect();
    naming.sort_by_key(|&i| priority(&groups[i]));
    let mut taken = HashSet::default();
    let mut names = vec![String::new(); groups.len()];
    for i in naming {
        let (dim, tag) = groups[i];
        let (all, kind) = if dim == 2 {
            (&mesh.surfaces, "-surface")
        } else {
            (&mesh.curves, "-curve")
        };
        let base = clean_name(&all[(tag - 1) as usize]);
        let mut name = base.clone();
        if taken.contains(&name) {
            name = with_suffix(&base, kind);
        }
        let mut n = 2u64;
        while taken.contains(&name) {
            name = with_suffix(&base, &format!("{kind}-{n}"));
            n += 1;
        }
        taken.insert(name.clone());
        names[i] = name;
    }
    groups
        .into_iter()
        .zip(names)
        .map(|((dim, tag), name)| (dim, tag, name))
        .collect()
}

fn physical_names<W: Write>(w: &mut W, mesh: &FemMesh, layout: &Layout) -> io::Result<()> {
    let named = physical_names_of(mesh, layout);
    if named.is_empty() {
        return Ok(());
    }
    writeln!(w, "$PhysicalNames\n{}", named.len())?;
    for (dim, tag, name) in named {
        writeln!(w, "{dim} {tag} \"{name}\"")?;
    }
    w.write_all(b"$EndPhysicalNames\n")
}

/// Write MSH 4.1.
pub(crate) fn write_v41<W: Write>(w: &mut W, mesh: &FemMesh, binary: bool) -> io::Result<()> {
    let layout = Layout::new(mesh, true);
    header(w, "4.1", binary)?;
    physical_names(w, mesh, &layout)?;

    // $Entities: points, curves, surfaces (gmsh's order; no volumes).
    w.write_all(b"$Entities\n")?;
    let count = |d: i32| layout.entities.iter().filter(|e| e.dim == d).count() as u64;
    let mut o = Out {
        w: &mut *w,
        binary,
        sep: false,
    };
    o.size(layout.points.len() as u64)?;
    o.size(count(1))?;
    o.size(count(2))?;
    o.size(0)?;
    o.eol()?;
    for &(tag, v) in &layout.points {
        let p = mesh.nodes[v as usize];
        o.int(tag)?;
        o.float(p.x)?;
        o.float(p.y)?;
        o.float(0.0)?;
        o.size(0)?; // no physical points
        o.eol()?;
    }
    for dim in [1, 2] {
        for e in layout.entities.iter().filter(|e| e.dim == dim) {
            o.int(e.tag)?;
            for v in [
                e.bbox.min[0],
                e.bbox.min[1],
                0.0,
                e.bbox.max[0],
                e.bbox.max[1],
                0.0,
            ] {
                o.float(v)?;
            }
            o.size(e.physical.len() as u64)?;
            for &p in &e.physical {
                o.int(p)?;
            }
            o.size(e.bounding.len() as u64)?;
            for &b in &e.bounding {
                o.int(b)?;
            }
            o.eol()?;
        }
    }
    o.end_data()?;
    w.write_all(b"$EndEntities\n")?;

    // $Nodes: one block per entity that holds nodes, in node order within it.
    w.write_all(b"$Nodes\n")?;
    let n = mesh.nodes.len() as u64;
    let blocks = layout.node_blocks();
    let mut o = Out {
        w: &mut *w,
        binary,
        sep: false,
    };
    o.size(blocks.len() as u64)?;
    o.size(n)?;
    o.size(u64::from(n > 0))?;
    o.size(n)?;
    o.eol()?;
    for ((dim, tag), nodes) in &blocks {
        o.int(*dim)?;
        o.int(*tag)?;
        o.int(0)?;
        o.size(nodes.len() as u64)?;
        o.eol()?;
        for &v in nodes {
            o.size(u64::from(v) + 1)?;
            o.eol()?;
        }
        lines_in_parallel(&mut o, nodes, |o, &v| {
            let p = mesh.nodes[v as usize];
            o.float(p.x)?;
            o.float(p.y)?;
            o.float(0.0)?;
            o.eol()
        })?;
    }
    o.end_data()?;
    w.write_all(b"$EndNodes\n")?;

    // $Elements: one block per entity.
    w.write_all(b"$Elements\n")?;
    let m = layout.element_count() as u64;
    let mut o = Out {
        w: &mut *w,
        binary,
        sep: false,
    };
    o.size(layout.blocks().count() as u64)?;
    o.size(m)?;
    o.size(u64::from(m > 0))?;
    o.size(m)?;
    o.eol()?;
    let mut tag = 0u64;
    for e in layout.blocks() {
        o.int(e.dim)?;
        o.int(e.tag)?;
        o.int(e.etype)?;
        o.size(e.elems.len() as u64)?;
        o.eol()?;
        for &i in &e.elems {
            tag += 1;
            o.size(tag)?;
            for &v in element_nodes(mesh, e, i) {
                o.size(u64::from(v) + 1)?;
            }
            o.eol()?;
        }
    }
    o.end_data()?;
    w.write_all(b"$EndElements\n")?;
    periodic_v41(w, mesh, &layout, binary)
}

/// One entry of `$Periodic`: an entity, its master, the translation from
/// the master to it, and node pairs (node, master node).
struct PeriodicLink {
    dim: i32,
    tag: i32,
    master: i32,
    translation: [f64; 2],
    nodes: Vec<(u32, u32)>,
}

/// The `$Periodic` links of a periodic mesh: each curve entity of the right
/// (top) side with the left (bottom) entity its nodes' partners span, and
/// (`points`) each point entity on those sides with the point its partners
/// lead to (the four corners: one class, the bottom-left corner their master).
fn periodic_links(mesh: &FemMesh, layout: &Layout, points: bool) -> Vec<PeriodicLink> {
    let Some(p) = &mesh.periodic else {
        return Vec::new();
    };
    let mut master: [HashMap<u32, u32>; 2] = Default::default();
    for pair in &p.pairs {
        master[pair.axis as usize].insert(pair.node, pair.master);
    }
    let period = [p.cell[2] - p.cell[0], p.cell[3] - p.cell[1]];
    let mut links = Vec::new();
    // master curve entities by the corner nodes of their elements
    let mut entity_of_edge: HashMap<(u32, u32), i32> = HashMap::default();
    for e in layout.entities.iter().filter(|e| e.dim == 1) {
        for &l in &e.elems {
            let line = mesh.line(l as usize);
            entity_of_edge.insert(edge_key(line[0], line[1]), e.tag);
        }
    }
    for (axis, map) in master.iter().enumerate() {
        if map.is_empty() {
            continue;
        }
        let translation = if axis == 0 {
            [period[0], 0.0]
        } else {
            [0.0, period[1]]
        };
        for e in layout.entities.iter().filter(|e| e.dim == 1) {
            let nodes: Vec<u32> = {
                let mut v: Vec<u32> = e
                    .elems
                    .iter()
                    .flat_map(|&l| mesh.line(l as usize).iter().copied())
                    .collect();
                v.sort_unstable();
                v.dedup();
                v
            };
            if nodes.is_empty() || !nodes.iter().all(|n| map.contains_key(n)) {
                continue;
            }
            let first = mesh.line(e.elems[0] as usize);
            let Some(&m) = entity_of_edge.get(&edge_key(map[&first[0]], map[&first[1]])) else {
                continue;
            };
            links.push(PeriodicLink {
                dim: 1,
                tag: e.tag,
                master: m,
                translation,
                nodes: nodes.iter().map(|&n| (n, map[&n])).collect(),
            });
        }
    }
    if points {
        let point_of: HashMap<u32, i32> = layout.points.iter().map(|&(t, v)| (v, t)).collect();
        for &(tag, v) in &layout.points {
            let (mut m, mut t) = (v, [0.0, 0.0]);
            for _ in 0..4 {
                if let Some(&n) = master[0].get(&m) {
                    m = n;
                    t[0] += period[0];
                } else if let Some(&n) = master[1].get(&m) {
                    m = n;
                    t[1] += period[1];
                } else {
                    break;
                }
            }
            if m == v {
                continue;
            }
            if let Some(&mt) = point_of.get(&m) {
                links.push(PeriodicLink {
                    dim: 0,
                    tag,
                    master: mt,
                    translation: t,
                    nodes: vec![(v, m)],
                });
            }
        }
    }
    links
}

/// gmsh's affine map of a translation: a 4×4 matrix, row by row.
fn affine(t: [f64; 2]) -> [f64; 16] {
    [
        1.0, 0.0, 0.0, t[0], 0.0, 1.0, 0.0, t[1], 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ]
}

/// `$Periodic` of MSH 4.1 (nothing for a mesh that is not periodic).
fn periodic_v41<W: Write>(
    w: &mut W,
    mesh: &FemMesh,
    layout: &Layout,
    binary: bool,
) -> io::Result<()> {
    let links = periodic_links(mesh, layout, true);
    if mesh.periodic.is_none() {
        return Ok(());
    }
    w.write_all(b"$Periodic\n")?;
    let mut o = Out {
        w: &mut *w,
        binary,
        sep: false,
    };
    o.size(links.len() as u64)?;
    o.eol()?;
    for l in &links {
        o.int(l.dim)?;
        o.int(l.tag)?;
        o.int(l.master)?;
        o.eol()?;
        o.size(16)?;
        for v in affine(l.translation) {
            o.float(v)?;
        }
        o.eol()?;
        o.size(l.nodes.len() as u64)?;
        o.eol()?;
        for &(n, m) in &l.nodes {
            o.size(u64::from(n) + 1)?;
            o.size(u64::from(m) + 1)?;
            o.eol()?;
        }
    }
    o.end_data()?;
    w.write_all(b"$EndPeriodic\n")
}

/// `$Periodic` of MSH 2.2 (curves only: 2.2 has no point entities without
/// point elements; each curve's list holds its end nodes too).
fn periodic_v22<W: Write>(
    w: &mut W,
    mesh: &FemMesh,
    layout: &Layout,
    binary: bool,
) -> io::Result<()> {
    if mesh.periodic.is_none() {
        return Ok(());
    }
    let links = periodic_links(mesh, layout, false);
    // gmsh reads this section as text in either encoding
    let _ = binary;
    writeln!(w, "$Periodic\n{}", links.len())?;
    for l in &links {
        writeln!(w, "{} {} {}", l.dim, l.tag, l.master)?;
        let a = affine(l.translation).map(|v| format!("{v:?}"));
        writeln!(w, "Affine {}", a.join(" "))?;
        writeln!(w, "{}", l.nodes.len())?;
        for &(n, m) in &l.nodes {
            writeln!(w, "{} {}", n + 1, m + 1)?;
        }
    }
    w.write_all(b"$EndPeriodic\n")
}

/// Write MSH 2.2.
pub(crate) fn write_v22<W: Write>(w: &mut W, mesh: &FemMesh, binary: bool) -> io::Result<()> {
    let layout = Layout::new(mesh, false);
    header(w, "2.2", binary)?;
    physical_names(w, mesh, &layout)?;

    writeln!(w, "$Nodes\n{}", mesh.nodes.len())?;
    let mut o = Out {
        w: &mut *w,
        binary,
        sep: false,
    };
    let numbered: Vec<(i32, kurbo::Point)> = (1..).zip(mesh.nodes.iter().copied()).collect();
    lines_in_parallel(&mut o, &numbered, |o, &(tag, p)| {
        o.int(tag)?;
        o.float(p.x)?;
        o.float(p.y)?;
        o.float(0.0)?;
        o.eol()
    })?;
    o.end_data()?;
    w.write_all(b"$EndNodes\n")?;

    writeln!(w, "$Elements\n{}", layout.element_count())?;
    let mut o = Out {
        w: &mut *w,
        binary,
        sep: false,
    };
    let mut tag = 0i32;
    for e in layout.blocks() {
        // at most one physical group per entity in this layout (0: none)
        let physical = e.physical.first().copied().unwrap_or(0);
        if binary {
            // Element header: type, number of elements that follow, number of tags.
            o.int(e.etype)?;
            o.int(e.elems.len() as i32)?;
            o.int(2)?;
        }
        for &i in &e.elems {
            tag += 1;
            o.int(tag)?;
            if !binary {
                o.int(e.etype)?;
                o.int(2)?;
            }
            o.int(physical)?;
            o.int(e.tag)?;
            for &v in element_nodes(mesh, e, i) {
                o.int(v as i32 + 1)?;
            }
            o.eol()?;
        }
    }
    o.end_data()?;
    w.write_all(b"$EndElements\n")?;
    periodic_v22(w, mesh, &layout, binary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{MshOptions, MshVersion, write_msh};
    use kurbo::Point;

    fn square() -> FemMesh {
        FemMesh {
            order: Some(Order::Linear),
            nodes: vec![
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(1.0, 1.0),
                Point::new(0.0, 1.0),
            ],
            triangles: vec![0, 1, 2, 0, 2, 3],
            triangle_group: vec![0, 0],
            surfaces: vec!["inside".into(), "unused".into()],
            lines: vec![0, 1],
            line_group: vec![0],
            line_kind: vec![crate::fem::LineKind::Primary],
            curves: vec!["bottom".into()],
            periodic: None,
        }
    }

    /// The model of `square()`: the bottom line's ends are points 1 and 2,
    /// the line is curve 1 from point 1 to point 2, and the surface has it on
    /// its boundary (running with the surface on its left); nodes 1 and 2 are
    /// listed under the points, 3 and 4 under the surface.
    #[test]
    fn v41_ascii_text() {
        let mut buf = Vec::new();
        write_v41(&mut buf, &square(), false).expect("write");
        let text = String::from_utf8(buf).expect("utf8");
        let expected = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n\
            $PhysicalNames\n2\n2 1 \"inside\"\n1 1 \"bottom\"\n$EndPhysicalNames\n\
            $Entities\n2 1 1 0\n1 0.0 0.0 0.0 0\n2 1.0 0.0 0.0 0\n\
            1 0.0 0.0 0.0 1.0 0.0 0.0 1 1 2 1 -2\n\
            1 0.0 0.0 0.0 1.0 1.0 0.0 1 1 1 1\n$EndEntities\n\
            $Nodes\n3 4 1 4\n0 1 0 1\n1\n0.0 0.0 0.0\n0 2 0 1\n2\n1.0 0.0 0.0\n\
            2 1 0 2\n3\n4\n1.0 1.0 0.0\n0.0 1.0 0.0\n$EndNodes\n\
            $Elements\n2 3 1 3\n2 1 2 2\n1 1 2 3\n2 1 3 4\n1 1 1 1\n3 1 2\n$EndElements\n";
        assert_eq!(text, expected);
    }

    /// A unit square fanned from its centre (node 4), with its outline twice
    /// (the domain's boundary and a shape's outline, both counter-clockwise),
    /// and a shape named `boundary` whose curve runs from corner 0 to the centre.
    fn fan() -> FemMesh {
        use crate::fem::LineKind::{Boundary, Primary};
        FemMesh {
            order: Some(Order::Linear),
            nodes: vec![
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(1.0, 1.0),
                Point::new(0.0, 1.0),
                Point::new(0.5, 0.5),
            ],
            triangles: vec![0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4],
            triangle_group: vec![0; 4],
            surfaces: vec!["plate".into()],
            lines: vec![0, 1, 1, 2, 2, 3, 3, 0, 0, 1, 1, 2, 2, 3, 3, 0, 0, 4],
            line_group: vec![0, 0, 0, 0, 1, 1, 1, 1, 2],
            line_kind: vec![
                Primary, Primary, Primary, Primary, Boundary, Boundary, Boundary, Boundary, Primary,
            ],
            curves: vec!["outline".into(), "boundary".into(), "boundary".into()],
            periodic: None,
        }
    }

    #[test]
    fn the_model_reads_back_in_every_format() {
        let m = fan();
        for version in [MshVersion::V41, MshVersion::V22] {
            for binary in [false, true] {
                let mut bytes = Vec::new();
                crate::write_msh_to(&m, &mut bytes, MshOptions { version, binary }).expect("write");
                let r = crate::read_msh(&bytes).expect("read");
                assert_eq!(r.nodes, m.nodes);
                // The domain's boundary keeps its name; the shape's curve is renamed.
                let mut names = r.physical_names.clone();
                names.sort();
                assert_eq!(
                    names,
                    [
                        (1, 1, "outline".to_owned()),
                        (1, 2, "boundary".to_owned()),
                        (1, 3, "boundary-curve".to_owned()),
                        (2, 1, "plate".to_owned()),
                    ]
                );
                // Lines as written, with their physical tags and directions:
                // in 2.2 one copy per physical curve; in 4.1 one element per
                // edge, its entity listed by every curve on the edge.
                let physicals_of = |b: &crate::LineBlock| -> Vec<i32> {
                    match b.entity {
                        Some(e) if version == MshVersion::V41 => r
                            .entities
                            .iter()
                            .find(|c| c.dim == 1 && c.tag == e)
                            .expect("the line's entity exists")
                            .physicals
                            .clone(),
                        _ => b.physical.into_iter().collect(),
                    }
                };
                let lines: Vec<(Vec<i32>, Vec<u32>)> = r
                    .line_blocks
                    .iter()
                    .flat_map(|b| {
                        let p = physicals_of(b);
                        b.lines().map(move |l| (p.clone(), l.to_vec()))
                    })
                    .collect();
                let expected = if version == MshVersion::V22 { 9 } else { 5 };
                assert_eq!(lines.len(), expected, "{version:?}");
                for (i, l) in (0..m.line_count()).map(|i| m.line(i)).enumerate() {
                    let g = m.line_group[i] as i32 + 1;
                    assert!(
                        lines.iter().any(|(p, n)| p.contains(&g) && n == l),
                        "{l:?} of curve {g}"
                    );
                }
                if version == MshVersion::V22 {
                    assert!(r.entities.is_empty() && r.node_entities.is_empty());
                    continue;
                }
                // No two elements join the same two nodes.
                let mut seen = HashSet::default();
                for (_, l) in &lines {
                    assert!(seen.insert(edge_key(l[0], l[1])), "{l:?} twice");
                }
                // Points at node 0 (three edges meet) and at the centre (an end).
                let points: Vec<&crate::MshEntity> =
                    r.entities.iter().filter(|e| e.dim == 0).collect();
                assert_eq!(points.len(), 2);
                assert_eq!(r.node_entities[0], (0, 1));
                assert_eq!(r.node_entities[4], (0, 2));
                // Curves: the loop from and to point 1, on the outline and the
                // boundary; the spoke from 1 to 2.
                let curves: Vec<&crate::MshEntity> =
                    r.entities.iter().filter(|e| e.dim == 1).collect();
                assert_eq!(curves.len(), 2);
                assert_eq!(curves[0].bounding, [1, -1]);
                assert_eq!(curves[0].physicals, [1, 2]);
                assert_eq!(curves[1].bounding, [1, -2]);
                assert_eq!(curves[1].physicals, [3]);
                // Nodes 1-3 lie on the loop; the surface is bounded by it.
                assert!(r.node_entities[1..4].iter().all(|&e| e == (1, 1)));
                let surface = r.entities.iter().find(|e| e.dim == 2).expect("a surface");
                assert_eq!(
                    (surface.physicals.as_slice(), surface.bounding.as_slice()),
                    (&[1][..], &[1][..])
                );
                // Every element sits on an entity that exists.
                for b in &r.line_blocks {
                    let e = b.entity.expect("entity");
                    assert!(
                        curves
                            .iter()
                            .any(|c| c.tag == e && c.physicals.first() == b.physical.as_ref())
                    );
                }
            }
        }
    }

    #[test]
    fn v22_ascii_text() {
        let mut buf = Vec::new();
        write_v22(&mut buf, &square(), false).expect("write");
        let text = String::from_utf8(buf).expect("utf8");
        let expected = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n\
            $PhysicalNames\n2\n2 1 \"inside\"\n1 1 \"bottom\"\n$EndPhysicalNames\n\
            $Nodes\n4\n1 0.0 0.0 0.0\n2 1.0 0.0 0.0\n3 1.0 1.0 0.0\n4 0.0 1.0 0.0\n$EndNodes\n\
            $Elements\n3\n1 2 2 1 1 1 2 3\n2 2 2 1 1 1 3 4\n3 1 2 1 1 1 2\n$EndElements\n";
        assert_eq!(text, expected);
    }

    #[test]
    fn validate_rejects_malformed() {
        let mut m = square();
        m.triangles[5] = 9;
        assert!(validate(&m).is_err());
        let mut m = square();
        m.triangle_group[0] = 2;
        assert!(validate(&m).is_err());
        let mut m = square();
        m.nodes[1].x = f64::NAN;
        assert!(validate(&m).is_err());
        let mut m = square();
        m.line_group.clear();
        assert!(validate(&m).is_err());
        let mut m = square();
        m.triangles.pop();
        assert!(validate(&m).is_err());
        assert!(validate(&square()).is_ok());
    }

    #[test]
    fn empty_mesh_is_written() {
        let m = FemMesh::default();
        for binary in [false, true] {
            let mut buf = Vec::new();
            write_v41(&mut buf, &m, binary).expect("write");
            let mut buf = Vec::new();
            write_v22(&mut buf, &m, binary).expect("write");
        }
    }

    #[test]
    fn names_are_cleaned() {
        assert_eq!(clean_name("a\"b\nc"), "a'b c");
        assert_eq!(clean_name(&"é".repeat(200)).chars().count(), MAX_NAME_CHARS);
    }

    /// The `$PhysicalNames` lines of a v2.2 file, as (dim, tag, name).
    fn written_names(mesh: &FemMesh) -> Vec<(i32, i32, String)> {
        let mut buf = Vec::new();
        write_v22(&mut buf, mesh, false).expect("write");
        let text = String::from_utf8(buf).expect("utf8");
        let section = text
            .split("$PhysicalNames\n")
            .nth(1)
            .and_then(|s| s.split("$EndPhysicalNames").next())
            .expect("a $PhysicalNames section");
        section
            .lines()
            .skip(1)
            .map(|l| {
                let mut it = l.splitn(3, ' ');
                let dim = it.next().expect("dim").parse().expect("int");
                let tag = it.next().expect("tag").parse().expect("int");
                let name = it.next().expect("name").trim_matches('"').to_owned();
                (dim, tag, name)
            })
            .collect()
    }

    #[test]
    fn a_curve_named_like_a_surface_gets_a_distinct_name() {
        let mut m = square();
        m.curves = vec!["inside".into()];
        assert_eq!(
            written_names(&m),
            [(2, 1, "inside".into()), (1, 1, "inside-curve".into())]
        );
        // A taken name gets the suffix, then a number: never a duplicate.
        m.lines = vec![0, 1, 1, 2, 2, 3];
        m.line_group = vec![0, 1, 2];
        m.line_kind = vec![crate::fem::LineKind::Primary; 3];
        m.curves = vec!["inside".into(), "inside-curve".into(), "inside".into()];
        assert_eq!(
            written_names(&m),
            [
                (2, 1, "inside".into()),
                (1, 1, "inside-curve".into()),
                (1, 2, "inside-curve-curve".into()),
                (1, 3, "inside-curve-2".into()),
            ]
        );
    }

    #[test]
    fn names_equal_after_truncation_stay_distinct_and_short() {
        let mut m = square();
        let long = "x".repeat(200);
        m.surfaces = vec![format!("{long}1")];
        m.curves = vec![format!("{long}2")];
        let names = written_names(&m);
        assert_eq!(names[0].2, "x".repeat(MAX_NAME_CHARS));
        assert_eq!(
            names[1].2,
            format!("{}-curve", "x".repeat(MAX_NAME_CHARS - 6))
        );
        assert!(names.iter().all(|n| n.2.chars().count() <= MAX_NAME_CHARS));
    }

    /// Reading back what the writer wrote (the reader is `crate::input`, below
    /// the writers: these tests live with the writer so `input` imports nothing above it).
    fn two_orders() -> FemMesh {
        let nodes = vec![
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(0.0, 1.0),
            Point::new(0.5, -0.1),
            Point::new(0.5, 0.5),
            Point::new(0.0, 0.5),
        ];
        FemMesh {
            order: Some(Order::Quadratic),
            nodes,
            triangles: vec![0, 1, 2, 3, 4, 5],
            triangle_group: vec![0],
            surfaces: vec!["s".into()],
            lines: vec![0, 1, 3],
            line_group: vec![0],
            line_kind: vec![crate::fem::LineKind::Primary],
            curves: vec!["c".into()],
            periodic: None,
        }
    }

    #[test]
    fn writer_round_trips_in_every_format() {
        let m = two_orders();
        let dir = tempfile::tempdir().expect("tempdir");
        for version in [MshVersion::V22, MshVersion::V41] {
            for binary in [false, true] {
                let p = dir.path().join("m.msh");
                write_msh(&m, &p, MshOptions { version, binary }).expect("write");
                let r = crate::read_msh_file(&p).expect("read");
                assert_eq!(r.format.binary, binary);
                assert_eq!(r.nodes, m.nodes);
                assert_eq!(r.triangle_blocks.len(), 1);
                assert_eq!(r.triangle_blocks[0].order, Order::Quadratic);
                assert_eq!(r.triangle_blocks[0].nodes, m.triangles);
                assert_eq!(r.triangle_blocks[0].physical, Some(1));
                assert_eq!(r.lines, 1);
                assert_eq!(r.physical_names.len(), 2);
            }
        }
    }

    /// A grid of `n` × `n` nodes in two triangles per cell, its coordinates
    /// of every kind `{:?}` prints differently (zeros of both signs, tiny,
    /// huge, long fractions).
    fn grid(n: usize) -> FemMesh {
        let odd = [0.0, -0.0, 1e-300, 3.5e17, -2.0 / 3.0, 123.456];
        let nodes = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64, (i / n) as f64 * 0.1);
                match i % 7 {
                    0 => Point::new(odd[(i / 7) % odd.len()], y),
                    1 => Point::new(x, odd[(i / 7) % odd.len()]),
                    _ => Point::new(x, y),
                }
            })
            .collect();
        let mut triangles = Vec::new();
        for r in 0..n - 1 {
            for c in 0..n - 1 {
                let v = (r * n + c) as u32;
                let n = n as u32;
                triangles.extend([v, v + 1, v + n + 1, v, v + n + 1, v + n]);
            }
        }
        FemMesh {
            order: Some(Order::Linear),
            nodes,
            triangle_group: vec![0; triangles.len() / 3],
            triangles,
            surfaces: vec!["s".into()],
            ..FemMesh::default()
        }
    }

    /// Node lines formatted in parallel chunks come out in order, as `{:?}`
    /// prints each coordinate, and the bytes do not depend on the threads.
    #[test]
    fn node_lines_formatted_in_parallel_are_written_in_order() {
        let m = grid(101); // 10 201 nodes: more than two chunks
        let bytes = |threads: usize, version: MshVersion, binary: bool| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let mut out = Vec::new();
            pool.install(|| {
                crate::output::write_msh_to(&m, &mut out, MshOptions { version, binary })
            })
            .expect("write");
            out
        };
        for version in [MshVersion::V22, MshVersion::V41] {
            for binary in [false, true] {
                let one = bytes(1, version, binary);
                assert_eq!(
                    one,
                    bytes(3, version, binary),
                    "{version:?} binary {binary}"
                );
                let back = crate::read_msh(&one).expect("read");
                assert_eq!(back.nodes.len(), m.nodes.len());
                for (a, b) in back.nodes.iter().zip(&m.nodes) {
                    assert_eq!(a.x.to_bits(), b.x.to_bits());
                    assert_eq!(a.y.to_bits(), b.y.to_bits());
                }
            }
        }
        // MSH 2.2's node lines, against the formatter itself.
        let text = String::from_utf8(bytes(2, MshVersion::V22, false)).expect("ascii");
        let lines: Vec<&str> = text
            .lines()
            .skip_while(|l| *l != "$Nodes")
            .skip(2)
            .take(m.nodes.len())
            .collect();
        for (i, (line, p)) in lines.iter().zip(&m.nodes).enumerate() {
            assert_eq!(*line, format!("{} {:?} {:?} {:?}", i + 1, p.x, p.y, 0.0));
        }
    }

    #[test]
    fn malformed_files_are_errors() {
        let good = {
            let dir = tempfile::tempdir().expect("tempdir");
            let p = dir.path().join("m.msh");
            write_msh(
                &two_orders(),
                &p,
                MshOptions {
                    version: MshVersion::V41,
                    binary: true,
                },
            )
            .expect("write");
            std::fs::read(p).expect("read")
        };
        // every truncation is an error, never a panic
        for n in 0..good.len() {
            let _ = crate::read_msh(&good[..n]);
        }
        assert!(crate::read_msh(&good[..good.len() / 2]).is_err());
        // flipping bytes never panics
        for i in 0..good.len() {
            let mut b = good.clone();
            b[i] ^= 0x5a;
            let _ = crate::read_msh(&b);
        }
        for bad in [
            &b""[..],
            b"hello",
            b"$MeshFormat\n4.0 0 8\n$EndMeshFormat\n",
            b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n1\n1 2 0 1 2 3\n$EndElements\n",
            b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 nan 0 0\n$EndNodes\n",
            b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n99999999999\n$EndNodes\n",
        ] {
            assert!(matches!(crate::read_msh(bad), Err(crate::Error::BadMesh(_))), "{:?}", String::from_utf8_lossy(bad));
        }
    }
}
