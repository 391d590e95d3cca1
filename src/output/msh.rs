//! gmsh MSH writers: 4.1 and 2.2, ASCII and binary.
//!
//! Layout shared by both versions (gmsh reference manual, "MSH file format"):
//! - one physical surface per used `FemMesh::surfaces` entry (physical tag = index + 1),
//!   one physical curve per used `FemMesh::curves` entry (physical tag = index + 1);
//!   groups without elements are not written;
//! - physical names are unique within a file, across dimensions (meshio keys its
//!   `field_data` by name alone): a surface keeps its name, a curve whose name is
//!   taken is written as `<name>-curve` (then `-curve-2`, …); see `physical_names_of`;
//! - one elementary entity per physical group, with the same tag, holding elements
//!   of one type only (gmsh's API shows one element type per entity);
//! - node tags 1..=N in `FemMesh::nodes` order; element tags 1..=M, triangles
//!   first (by surface), then lines (by curve);
//! - coordinates in ASCII are shortest round-trip decimal (`{:?}`), so they read
//!   back bit-exactly; binary uses native byte order with gmsh's endianness marker.

use crate::FemMesh;
use crate::element::Order;
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

/// One elementary entity = one physical group = one element block.
struct Entity {
    /// 1 (curve) or 2 (surface).
    dim: i32,
    /// Entity tag and physical tag (group index + 1); `None` physical for the
    /// fallback entity that only carries nodes.
    tag: i32,
    physical: Option<i32>,
    /// gmsh element type.
    etype: i32,
    /// Element indices (into triangles or lines) in this entity.
    elems: Vec<u32>,
    bbox: BBox,
}

/// The entities of a mesh and its element numbering.
struct Layout {
    entities: Vec<Entity>,
    /// Index of the entity that holds all nodes.
    node_entity: Option<usize>,
}

/// Group element indices by group (stable counting sort); only non-empty groups.
fn bucket(groups: &[u32], count: usize) -> Vec<(u32, Vec<u32>)> {
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

impl Layout {
    fn new(mesh: &FemMesh) -> Layout {
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
                physical: Some(tag),
                etype: ttype,
                elems,
                bbox,
            });
        }
        for (g, elems) in bucket(&mesh.line_group, mesh.curves.len()) {
            let bbox = BBox::of(
                mesh,
                elems
                    .iter()
                    .flat_map(|&l| mesh.line(l as usize).iter().copied()),
            );
            let tag = g as i32 + 1;
            entities.push(Entity {
                dim: 1,
                tag,
                physical: Some(tag),
                etype: ltype,
                elems,
                bbox,
            });
        }
        let node_entity = if !entities.is_empty() {
            Some(0)
        } else if !mesh.nodes.is_empty() {
            // Nodes but no elements: a bare surface entity keeps them readable.
            entities.push(Entity {
                dim: 2,
                tag: 1,
                physical: None,
                etype: ttype,
                elems: Vec::new(),
                bbox: BBox::of(mesh, 0..mesh.nodes.len() as u32),
            });
            Some(0)
        } else {
            None
        };
        Layout {
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

/// The name written for each physical entity of `layout` (`None` for an entity
/// without a physical group): the group's cleaned name, made unique within the
/// file. meshio (and any reader that maps names to groups) keeps one group per
/// name, so a surface and a curve of the same name (in `--regions shape`, a
/// shape's surface and its feature edges) would lose one. Surfaces are named
/// first and keep their names; a name already taken gets `-surface` / `-curve`,
/// then `-2`, `-3`, … until it is free.
fn physical_names_of(mesh: &FemMesh, layout: &Layout) -> Vec<Option<String>> {
    let mut taken = std::collections::HashSet::new();
    let mut out = vec![None; layout.entities.len()];
    let mut order: Vec<usize> = (0..layout.entities.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(layout.entities[i].dim));
    for i in order {
        let e = &layout.entities[i];
        let Some(tag) = e.physical else { continue };
        let (names, kind) = if e.dim == 2 {
            (&mesh.surfaces, "-surface")
        } else {
            (&mesh.curves, "-curve")
        };
        let base = clean_name(&names[(tag - 1) as usize]);
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
        out[i] = Some(name);
    }
    out
}

fn physical_names<W: Write>(w: &mut W, mesh: &FemMesh, layout: &Layout) -> io::Result<()> {
    let names = physical_names_of(mesh, layout);
    let named: Vec<(&Entity, String)> = layout
        .entities
        .iter()
        .zip(names)
        .filter_map(|(e, n)| Some((e, n?)))
        .collect();
    if named.is_empty() {
        return Ok(());
    }
    writeln!(w, "$PhysicalNames\n{}", named.len())?;
    for (e, name) in named {
        let tag = e.physical.expect("internal: named entities are physical");
        writeln!(w, "{} {tag} \"{name}\"", e.dim)?;
    }
    w.write_all(b"$EndPhysicalNames\n")
}

/// Write MSH 4.1.
pub(crate) fn write_v41<W: Write>(w: &mut W, mesh: &FemMesh, binary: bool) -> io::Result<()> {
    let layout = Layout::new(mesh);
    header(w, "4.1", binary)?;
    physical_names(w, mesh, &layout)?;

    // $Entities: curves then surfaces (gmsh's order: points, curves, surfaces, volumes).
    w.write_all(b"$Entities\n")?;
    let count = |d: i32| layout.entities.iter().filter(|e| e.dim == d).count() as u64;
    let mut o = Out {
        w: &mut *w,
        binary,
        sep: false,
    };
    o.size(0)?;
    o.size(count(1))?;
    o.size(count(2))?;
    o.size(0)?;
    o.eol()?;
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
            match e.physical {
                Some(p) => {
                    o.size(1)?;
                    o.int(p)?;
                }
                None => o.size(0)?,
            }
            o.size(0)?; // no bounding points / curves
            o.eol()?;
        }
    }
    o.end_data()?;
    w.write_all(b"$EndEntities\n")?;

    // $Nodes: one block with every node, on the first entity.
    w.write_all(b"$Nodes\n")?;
    let n = mesh.nodes.len() as u64;
    let mut o = Out {
        w: &mut *w,
        binary,
        sep: false,
    };
    match layout.node_entity {
        Some(ei) => {
            let e = &layout.entities[ei];
            for v in [1, n, 1, n] {
                o.size(v)?;
            }
            o.eol()?;
            o.int(e.dim)?;
            o.int(e.tag)?;
            o.int(0)?;
            o.size(n)?;
            o.eol()?;
            for t in 1..=n {
                o.size(t)?;
                o.eol()?;
            }
            for p in &mesh.nodes {
                o.float(p.x)?;
                o.float(p.y)?;
                o.float(0.0)?;
                o.eol()?;
            }
        }
        None => {
            for _ in 0..4 {
                o.size(0)?;
            }
            o.eol()?;
        }
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
    w.write_all(b"$EndElements\n")
}

/// Write MSH 2.2.
pub(crate) fn write_v22<W: Write>(w: &mut W, mesh: &FemMesh, binary: bool) -> io::Result<()> {
    let layout = Layout::new(mesh);
    header(w, "2.2", binary)?;
    physical_names(w, mesh, &layout)?;

    writeln!(w, "$Nodes\n{}", mesh.nodes.len())?;
    let mut o = Out {
        w: &mut *w,
        binary,
        sep: false,
    };
    for (i, p) in mesh.nodes.iter().enumerate() {
        o.int(i as i32 + 1)?;
        o.float(p.x)?;
        o.float(p.y)?;
        o.float(0.0)?;
        o.eol()?;
    }
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
        let physical = e.physical.unwrap_or(0);
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
    w.write_all(b"$EndElements\n")
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
        }
    }

    #[test]
    fn v41_ascii_text() {
        let mut buf = Vec::new();
        write_v41(&mut buf, &square(), false).expect("write");
        let text = String::from_utf8(buf).expect("utf8");
        let expected = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n\
            $PhysicalNames\n2\n2 1 \"inside\"\n1 1 \"bottom\"\n$EndPhysicalNames\n\
            $Entities\n0 1 1 0\n1 0.0 0.0 0.0 1.0 0.0 0.0 1 1 0\n\
            1 0.0 0.0 0.0 1.0 1.0 0.0 1 1 0\n$EndEntities\n\
            $Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0.0 0.0 0.0\n1.0 0.0 0.0\n\
            1.0 1.0 0.0\n0.0 1.0 0.0\n$EndNodes\n\
            $Elements\n2 3 1 3\n2 1 2 2\n1 1 2 3\n2 1 3 4\n1 1 1 1\n3 1 2\n$EndElements\n";
        assert_eq!(text, expected);
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
