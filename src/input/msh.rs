//! gmsh MSH reader: versions 2.x and 4.1, ASCII and binary (gmsh reference
//! manual, "MSH file format").
//!
//! Reads nodes (x, y; z is only measured) in node-tag order, triangles of order
//! 1-3 (gmsh types 2, 9, 21) and line elements (types 1, 8, 26) with their
//! entity and physical tag, the model of a 4.1 file (its `$Entities` with
//! physical and bounding tags, and the entity each node is listed under), and
//! counts every other element. Sections it does not need (`$NodeData`,
//! `$Periodic`, ...) are skipped. Never panics and never over-allocates on a
//! malformed file: counts are checked against the bytes left.

use crate::element::Order;
use crate::{Error, Result};
use kurbo::Point;
use std::collections::HashMap;
use std::path::Path;

/// The file's format line.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct MshFormat {
    /// Version as written (`"2.2"`, `"4.1"`, ...).
    pub version: String,
    /// Binary file.
    pub binary: bool,
}

/// Triangles of one order from one element block (4.1) or run of elements (2.x).
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleBlock {
    /// Element order.
    pub order: Order,
    /// First physical tag of the elements (2.x) or of their entity (4.1), if any.
    pub physical: Option<i32>,
    /// Elementary entity tag (2.x: the elements' second tag), if any.
    pub entity: Option<i32>,
    /// Flat node indices (into [`MshMesh::nodes`]), `order.triangle_nodes()` per triangle.
    pub nodes: Vec<u32>,
}

/// Line elements of one order from one element block (4.1) or run of elements (2.x).
#[derive(Clone, Debug, PartialEq)]
pub struct LineBlock {
    /// Nodes per line: 2 (type 1), 3 (type 8) or 4 (type 26); ends first, then
    /// the inner nodes along the line.
    pub nodes_per_line: usize,
    /// First physical tag of the elements (2.x) or of their entity (4.1), if any.
    pub physical: Option<i32>,
    /// Elementary entity tag (2.x: the elements' second tag), if any.
    pub entity: Option<i32>,
    /// Flat node indices (into [`MshMesh::nodes`]), `nodes_per_line` per line.
    pub nodes: Vec<u32>,
}

impl LineBlock {
    /// The node indices of each line.
    pub fn lines(&self) -> impl Iterator<Item = &[u32]> {
        self.nodes.chunks_exact(self.nodes_per_line.max(1))
    }
}

/// An elementary entity of a 4.1 file's `$Entities`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MshEntity {
    /// Dimension: 0 (point), 1 (curve), 2 (surface), 3 (volume).
    pub dim: i32,
    /// Tag (unique within its dimension).
    pub tag: i32,
    /// Physical tags.
    pub physicals: Vec<i32>,
    /// Signed tags of the bounding entities of dimension `dim - 1` (none for points).
    pub bounding: Vec<i32>,
}

/// A gmsh mesh as read.
#[derive(Clone, Debug, PartialEq)]
pub struct MshMesh {
    /// The format line.
    pub format: MshFormat,
    /// Node positions, in file order.
    pub nodes: Vec<Point>,
    /// Largest |z| of any node.
    pub max_abs_z: f64,
    /// Triangles by block.
    pub triangle_blocks: Vec<TriangleBlock>,
    /// Number of line elements (any order).
    pub lines: usize,
    /// Line elements of types 1, 8 and 26 by block (other line types are only counted).
    pub line_blocks: Vec<LineBlock>,
    /// The entities of a 4.1 file, in file order (empty for 2.x).
    pub entities: Vec<MshEntity>,
    /// (dimension, entity tag) of the node block each node is listed in (4.1;
    /// empty for 2.x), in [`MshMesh::nodes`] order.
    pub node_entities: Vec<(i32, i32)>,
    /// Number of 2D elements that are not triangles of order 1-3 (quadrangles,
    /// incomplete or higher-order triangles).
    pub unsupported_2d: usize,
    /// Number of point and 3D elements.
    pub other_elements: usize,
    /// Physical names: (dimension, tag, name).
    pub physical_names: Vec<(i32, i32, String)>,
    /// The `$NodeData` sections (a gmsh view's values per node), in file order.
    pub node_data: Vec<NodeData>,
}

/// One `$NodeData` section: the first component of each listed node's value.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeData {
    /// The view's name (the first string tag), empty without one.
    pub name: String,
    /// (node index in [`MshMesh::nodes`], value), in file order.
    pub values: Vec<(u32, f64)>,
}

impl MshMesh {
    /// Every triangle: its order and node indices.
    pub fn triangles(&self) -> impl Iterator<Item = (Order, &[u32])> + Clone {
        self.triangle_blocks.iter().flat_map(|b| {
            b.nodes
                .chunks_exact(b.order.triangle_nodes())
                .map(move |t| (b.order, t))
        })
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangle_blocks
            .iter()
            .map(|b| b.nodes.len() / b.order.triangle_nodes())
            .sum()
    }
}

/// Read a gmsh mesh file.
///
/// # Errors
/// [`Error::Read`] if the file cannot be read, [`Error::IsDirectory`] for a
/// directory, [`Error::BadMesh`] if it is not a mesh this reader understands.
pub fn read_msh_file(path: &Path) -> Result<MshMesh> {
    if path.is_dir() {
        return Err(Error::IsDirectory);
    }
    let bytes = std::fs::read(path).map_err(Error::Read)?;
    read_msh(&bytes)
}

/// Read a gmsh mesh from its bytes.
///
/// ```
/// use triwild::{Order, read_msh};
/// let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n\
///     $Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n\
///     $Elements\n1\n1 2 2 7 7 1 2 3\n$EndElements\n";
/// let mesh = read_msh(text.as_bytes())?;
/// let (order, nodes) = mesh.triangles().next().unwrap();
/// assert_eq!((order, nodes), (Order::Linear, &[0, 1, 2][..]));
/// assert_eq!(mesh.triangle_blocks[0].physical, Some(7));
/// assert!(read_msh(b"$MeshFormat\n2.2 0 8\n").is_err()); // truncated
/// # Ok::<(), triwild::Error>(())
/// ```
///
/// # Errors
/// [`Error::BadMesh`] naming what is wrong and where.
pub fn read_msh(bytes: &[u8]) -> Result<MshMesh> {
    Reader::new(bytes).read().map_err(Error::BadMesh)
}

/// (dimension, node count) of a gmsh element type.
fn element_shape(t: i32) -> Option<(i32, usize)> {
    Some(match t {
        15 => (0, 1),
        1 => (1, 2),
        8 => (1, 3),
        26 => (1, 4),
        27 => (1, 5),
        28 => (1, 6),
        2 => (2, 3),
        3 => (2, 4),
        9 => (2, 6),
        10 => (2, 9),
        16 => (2, 8),
        20 => (2, 9),
        21 => (2, 10),
        22 => (2, 12),
        23 | 24 => (2, 15),
        25 => (2, 21),
        36 => (2, 16),
        37 => (2, 25),
        38 => (2, 36),
        4 => (3, 4),
        5 => (3, 8),
        6 => (3, 6),
        7 => (3, 5),
        11 => (3, 10),
        12 => (3, 27),
        13 => (3, 18),
        14 => (3, 14),
        17 => (3, 20),
        18 => (3, 15),
        19 => (3, 13),
        29 => (3, 20),
        30 => (3, 35),
        31 => (3, 56),
        92 => (3, 64),
        93 => (3, 125),
        _ => return None,
    })
}

fn triangle_order(t: i32) -> Option<Order> {
    Order::from_gmsh_triangle_type(t)
}

/// Node count of the line types whose elements are kept (1, 8, 26).
fn line_nodes(t: i32) -> Option<usize> {
    match t {
        1 => Some(2),
        8 => Some(3),
        26 => Some(4),
        _ => None,
    }
}

type R<T> = std::result::Result<T, String>;

#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Ascii,
    Binary { swap: bool, size8: bool },
}

struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
    mode: Mode,
    /// Major version: 2 or 4.
    major: u8,
    section: &'static str,
}

/// Node tags → positions, then tags → indices.
struct Nodes {
    points: Vec<Point>,
    tags: Vec<u64>,
    entities: Vec<(i32, i32)>,
    index: HashMap<u64, u32>,
    max_abs_z: f64,
}

impl Nodes {
    fn push(&mut self, tag: u64, x: f64, y: f64, z: f64) -> R<()> {
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return Err(format!("node {tag} has a non-finite coordinate"));
        }
        let i = u32::try_from(self.points.len()).map_err(|_| "more than 2^32 nodes".to_owned())?;
        if self.index.insert(tag, i).is_some() {
            return Err(format!("node tag {tag} appears twice"));
        }
        self.points.push(Point::new(x, y));
        self.tags.push(tag);
        self.max_abs_z = self.max_abs_z.max(z.abs());
        Ok(())
    }
    /// Put the nodes in tag order (gmsh lists them by entity, not by tag).
    fn sort_by_tag(&mut self) {
        if self.tags.is_sorted() {
            return;
        }
        let mut order: Vec<usize> = (0..self.tags.len()).collect();
        order.sort_unstable_by_key(|&i| self.tags[i]);
        self.points = order.iter().map(|&i| self.points[i]).collect();
        if self.entities.len() == order.len() {
            self.entities = order.iter().map(|&i| self.entities[i]).collect();
        }
        self.tags = order.iter().map(|&i| self.tags[i]).collect();
        for (i, &t) in self.tags.iter().enumerate() {
            self.index.insert(t, i as u32);
        }
    }
    fn get(&self, tag: u64) -> R<u32> {
        self.index
            .get(&tag)
            .copied()
            .ok_or_else(|| format!("an element references node {tag}, which does not exist"))
    }
}

/// The physical tag and the entity of a block of elements.
type Owner = (Option<i32>, Option<i32>);

/// Elements as read, before node tags are resolved (nodes may come after elements
/// in principle; gmsh writes them first, but we do not rely on it).
#[derive(Default)]
struct Elements {
    /// (order, owner, node tags) per block.
    blocks: Vec<(Order, Owner, Vec<u64>)>,
    /// (nodes per line, owner, node tags) per block.
    line_blocks: Vec<(usize, Owner, Vec<u64>)>,
    lines: usize,
    unsupported_2d: usize,
    other: usize,
}

impl Elements {
    /// The block to append triangles of `order` / `physical` / `entity` to (the
    /// last one if it matches).
    fn block(&mut self, order: Order, physical: Option<i32>, entity: Option<i32>) -> &mut Vec<u64> {
        let same = matches!(self.blocks.last(), Some((o, w, _)) if *o == order && *w == (physical, entity));
        if !same {
            self.blocks.push((order, (physical, entity), Vec::new()));
        }
        &mut self.blocks.last_mut().expect("internal: just pushed").2
    }
    /// The block to append lines of `nn` nodes / `physical` / `entity` to (the
    /// last one if it matches); the line is counted.
    fn line_block(
        &mut self,
        nn: usize,
        physical: Option<i32>,
        entity: Option<i32>,
    ) -> &mut Vec<u64> {
        self.lines += 1;
        let same = matches!(self.line_blocks.last(), Some((n, w, _)) if *n == nn && *w == (physical, entity));
        if !same {
            self.line_blocks.push((nn, (physical, entity), Vec::new()));
        }
        &mut self
            .line_blocks
            .last_mut()
            .expect("internal: just pushed")
            .2
    }
    fn count(&mut self, dim: i32, etype: i32) {
        match dim {
            1 => self.lines += 1,
            2 if triangle_order(etype).is_none() => self.unsupported_2d += 1,
            _ => self.other += 1,
        }
    }
}

impl<'a> Reader<'a> {
    fn new(b: &'a [u8]) -> Self {
        Reader {
            b,
            pos: 0,
            mode: Mode::Ascii,
            major: 0,
            section: "header",
        }
    }

    fn err<T>(&self, msg: impl std::fmt::Display) -> R<T> {
        Err(format!("{msg} (in {}, at byte {})", self.section, self.pos))
    }

    fn left(&self) -> usize {
        self.b.len() - self.pos
    }

    fn skip_ws(&mut self) {
        while self.pos < self.b.len() && self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    /// The next line (without its end of line), skipping blank lines; `None` at the end.
    fn line(&mut self) -> Option<&'a str> {
        self.skip_ws();
        if self.pos >= self.b.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < self.b.len() && self.b[self.pos] != b'\n' {
            self.pos += 1;
        }
        let raw = &self.b[start..self.pos];
        if self.pos < self.b.len() {
            self.pos += 1;
        }
        Some(std::str::from_utf8(raw).unwrap_or("\u{fffd}").trim_end())
    }

    fn token(&mut self) -> R<&'a str> {
        self.skip_ws();
        let start = self.pos;
        while self.pos < self.b.len() && !self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return self.err("unexpected end of file");
        }
        match std::str::from_utf8(&self.b[start..self.pos]) {
            Ok(s) => Ok(s),
            Err(_) => self.err("binary data where text was expected"),
        }
    }

    fn parse<T: std::str::FromStr>(&mut self, what: &str) -> R<T> {
        let t = self.token()?;
        match t.parse() {
            Ok(v) => Ok(v),
            Err(_) => self.err(format!("bad {what} {t:?}")),
        }
    }

    fn bytes<const N: usize>(&mut self) -> R<[u8; N]> {
        if self.left() < N {
            return self.err("unexpected end of file");
        }
        let mut a = [0u8; N];
        a.copy_from_slice(&self.b[self.pos..self.pos + N]);
        self.pos += N;
        Ok(a)
    }

    fn int(&mut self) -> R<i32> {
        match self.mode {
            Mode::Ascii => self.parse("integer"),
            Mode::Binary { swap, .. } => {
                let v = i32::from_le_bytes(self.bytes::<4>()?);
                Ok(if swap { v.swap_bytes() } else { v })
            }
        }
    }

    fn size(&mut self) -> R<u64> {
        match self.mode {
            Mode::Ascii => self.parse("count"),
            Mode::Binary { swap, size8: true } => {
                let v = u64::from_le_bytes(self.bytes::<8>()?);
                Ok(if swap { v.swap_bytes() } else { v })
            }
            Mode::Binary { swap, size8: false } => {
                let v = u32::from_le_bytes(self.bytes::<4>()?);
                Ok(u64::from(if swap { v.swap_bytes() } else { v }))
            }
        }
    }

    fn float(&mut self) -> R<f64> {
        match self.mode {
            Mode::Ascii => self.parse("number"),
            Mode::Binary { swap, .. } => {
                let v = u64::from_le_bytes(self.bytes::<8>()?);
                Ok(f64::from_bits(if swap { v.swap_bytes() } else { v }))
            }
        }
    }

    /// A non-negative 2.x count / tag written as an int.
    fn int_count(&mut self, what: &str) -> R<u64> {
        let v = self.int()?;
        u64::try_from(v).or_else(|_| self.err(format!("negative {what} {v}")))
    }

    /// A capacity no larger than the bytes left could hold (`min_bytes` per item).
    fn cap(&self, n: u64, min_bytes: usize) -> usize {
        usize::try_from(n)
            .unwrap_or(usize::MAX)
            .min(self.left() / min_bytes.max(1) + 1)
    }

    /// Expect `$End<name>` next.
    fn end(&mut self, name: &str) -> R<()> {
        let want = format!("$End{name}");
        match self.line() {
            Some(l) if l.trim() == want => Ok(()),
            Some(l) => self.err(format!("expected {want}, found {:?}", truncate(l))),
            None => self.err(format!("missing {want}")),
        }
    }

    /// Skip to just after the line `$End<name>`.
    fn skip_section(&mut self, name: &str) -> R<()> {
        let want = format!("$End{name}");
        let w = want.as_bytes();
        let mut i = self.pos;
        while i + w.len() <= self.b.len() {
            if &self.b[i..i + w.len()] == w && (i == 0 || self.b[i - 1] == b'\n') {
                self.pos = i + w.len();
                return Ok(());
            }
            i += 1;
        }
        self.err(format!("missing {want}"))
    }

    fn read(mut self) -> R<MshMesh> {
        // Header.
        match self.line() {
            Some("$MeshFormat") => {}
            Some(l) => return self.err(format!("not a gmsh file: starts with {:?}", truncate(l))),
            None => return self.err("empty file"),
        }
        self.section = "$MeshFormat";
        let Some(fmt) = self.line() else {
            return self.err("missing format line");
        };
        let f: Vec<&str> = fmt.split_whitespace().collect();
        if f.len() < 3 {
            return self.err(format!("bad format line {:?}", truncate(fmt)));
        }
        let version = f[0].to_owned();
        self.major = match version.as_str() {
            "2" | "2.0" | "2.1" | "2.2" => 2,
            "4.1" => 4,
            v => {
                return self.err(format!(
                    "MSH version {v} is not supported (2.2 and 4.1 are)"
                ));
            }
        };
        let binary = match f[1] {
            "0" => false,
            "1" => true,
            t => return self.err(format!("bad file type {t:?}")),
        };
        let data_size: usize = f[2].parse().or_else(|_| self.err("bad data size"))?;
        if binary {
            // Endianness marker: the int 1 right after the format line.
            let m = self.bytes::<4>()?;
            let swap = match (i32::from_le_bytes(m), i32::from_be_bytes(m)) {
                (1, _) => false,
                (_, 1) => true,
                _ => return self.err("bad endianness marker"),
            };
            let size8 = match (self.major, data_size) {
                (4, 4) => false,
                (_, 8) => true,
                _ => return self.err(format!("unsupported data size {data_size}")),
            };
            self.mode = Mode::Binary { swap, size8 };
        }
        self.end("MeshFormat")?;

        let mut nodes = Nodes {
            points: Vec::new(),
            tags: Vec::new(),
            entities: Vec::new(),
            index: HashMap::new(),
            max_abs_z: 0.0,
        };
        let mut elems = Elements::default();
        let mut names = Vec::new();
        let mut entity_physical: HashMap<(i32, i32), i32> = HashMap::new();
        let mut entities = Vec::new();
        let mut node_data: Vec<(String, Vec<(u64, f64)>)> = Vec::new();
        let (mut saw_nodes, mut saw_elements) = (false, false);
        while let Some(l) = self.line() {
            let Some(name) = l.strip_prefix('$') else {
                return self.err(format!("expected a section, found {:?}", truncate(l)));
            };
            let name = name.trim();
            match name {
                "PhysicalNames" => {
                    self.section = "$PhysicalNames";
                    self.physical_names(&mut names)?;
                    self.end(name)?;
                }
                "Entities" if self.major == 4 => {
                    self.section = "$Entities";
                    self.entities(&mut entity_physical, &mut entities)?;
                    self.end(name)?;
                }
                "Nodes" => {
                    if saw_nodes {
                        return self.err("two $Nodes sections");
                    }
                    saw_nodes = true;
                    self.section = "$Nodes";
                    if self.major == 4 {
                        self.nodes_v4(&mut nodes)?;
                    } else {
                        self.nodes_v2(&mut nodes)?;
                    }
                    self.end(name)?;
                }
                "Elements" => {
                    if saw_elements {
                        return self.err("two $Elements sections");
                    }
                    saw_elements = true;
                    self.section = "$Elements";
                    if self.major == 4 {
                        self.elements_v4(&mut elems, &entity_physical)?;
                    } else {
                        self.elements_v2(&mut elems)?;
                    }
                    self.end(name)?;
                }
                "NodeData" => {
                    self.section = "$NodeData";
                    node_data.push(self.node_data()?);
                    self.end(name)?;
                }
                _ if name.starts_with("End") => {
                    return self.err(format!("unexpected {}", truncate(l)));
                }
                _ => {
                    self.section = "an unknown section";
                    self.skip_section(name)?;
                }
            }
        }
        if !saw_nodes {
            return self.err("no $Nodes section");
        }
        if !saw_elements {
            return self.err("no $Elements section");
        }
        nodes.sort_by_tag();
        let mut triangle_blocks = Vec::with_capacity(elems.blocks.len());
        for (order, (physical, entity), tags) in elems.blocks {
            let idx = tags
                .iter()
                .map(|&t| nodes.get(t))
                .collect::<R<Vec<u32>>>()?;
            triangle_blocks.push(TriangleBlock {
                order,
                physical,
                entity,
                nodes: idx,
            });
        }
        let mut line_blocks = Vec::with_capacity(elems.line_blocks.len());
        for (nodes_per_line, (physical, entity), tags) in elems.line_blocks {
            let idx = tags
                .iter()
                .map(|&t| nodes.get(t))
                .collect::<R<Vec<u32>>>()?;
            line_blocks.push(LineBlock {
                nodes_per_line,
                physical,
                entity,
                nodes: idx,
            });
        }
        let node_data = node_data
            .into_iter()
            .map(|(name, values)| {
                let values = values
                    .into_iter()
                    .map(|(t, v)| {
                        Ok((
                            nodes.get(t).map_err(|_| {
                                format!("$NodeData lists node {t}, which does not exist")
                            })?,
                            v,
                        ))
                    })
                    .collect::<R<Vec<(u32, f64)>>>()?;
                Ok(NodeData { name, values })
            })
            .collect::<R<Vec<NodeData>>>()?;
        Ok(MshMesh {
            format: MshFormat { version, binary },
            nodes: nodes.points,
            max_abs_z: nodes.max_abs_z,
            triangle_blocks,
            lines: elems.lines,
            line_blocks,
            entities,
            node_entities: nodes.entities,
            unsupported_2d: elems.unsupported_2d,
            other_elements: elems.other,
            physical_names: names,
            node_data,
        })
    }

    /// A `$NodeData` section after its header line: string, real and integer
    /// tags (always ASCII), then per node its tag and values (ASCII or binary).
    fn node_data(&mut self) -> R<(String, Vec<(u64, f64)>)> {
        let ascii_count = |r: &mut Self, what: &str| -> R<u64> {
            match r.line() {
                Some(l) => l
                    .trim()
                    .parse()
                    .or_else(|_| r.err(format!("bad {what} {:?}", truncate(l)))),
                None => r.err("unexpected end of file"),
            }
        };
        let n_strings = ascii_count(self, "string tag count")?;
        let mut name = String::new();
        for i in 0..n_strings {
            let Some(l) = self.line() else {
                return self.err("unexpected end of file");
            };
            if i == 0 {
                name = l.trim().trim_matches('"').to_owned();
            }
        }
        let n_reals = ascii_count(self, "real tag count")?;
        for _ in 0..n_reals {
            if self.line().is_none() {
                return self.err("unexpected end of file");
            }
        }
        let n_ints = ascii_count(self, "integer tag count")?;
        let mut ints = Vec::new();
        for _ in 0..n_ints {
            ints.push(ascii_count(self, "integer tag")?);
        }
        let components = ints.get(1).copied().unwrap_or(1);
        let count = ints.get(2).copied().unwrap_or(0);
        if components == 0 || components > 9 {
            return self.err(format!("{components} components per node"));
        }
        let per = 4 + 8 * components as usize;
        let mut values = Vec::with_capacity(self.cap(count, per));
        for _ in 0..count {
            let tag = match self.mode {
                Mode::Ascii => self.parse("node tag")?,
                Mode::Binary { .. } if self.major == 4 => self.size()?,
                Mode::Binary { .. } => self.int_count("node tag")?,
            };
            let first = self.float()?;
            for _ in 1..components {
                self.float()?;
            }
            values.push((tag, first));
        }
        Ok((name, values))
    }

    fn physical_names(&mut self, out: &mut Vec<(i32, i32, String)>) -> R<()> {
        // Always ASCII, one name per line.
        let n: u64 = self.parse("count")?;
        for _ in 0..n {
            let Some(l) = self.line() else {
                return self.err("unexpected end of file");
            };
            let mut it = l.splitn(3, char::is_whitespace);
            let (Some(d), Some(t)) = (it.next(), it.next()) else {
                return self.err(format!("bad physical name line {:?}", truncate(l)));
            };
            let (Ok(d), Ok(t)) = (d.parse(), t.parse()) else {
                return self.err(format!("bad physical name line {:?}", truncate(l)));
            };
            let name = it.next().unwrap_or("").trim().trim_matches('"').to_owned();
            out.push((d, t, name));
        }
        Ok(())
    }

    fn entities(&mut self, phys: &mut HashMap<(i32, i32), i32>, out: &mut Vec<MshEntity>) -> R<()> {
        let counts = [self.size()?, self.size()?, self.size()?, self.size()?];
        for (dim, &n) in counts.iter().enumerate() {
            let dim = dim as i32;
            for _ in 0..n {
                let tag = self.int()?;
                let nb = if dim == 0 { 3 } else { 6 };
                for _ in 0..nb {
                    self.float()?;
                }
                let np = self.size()?;
                let mut physicals = Vec::with_capacity(self.cap(np, 4));
                for _ in 0..np {
                    physicals.push(self.int()?);
                }
                if let Some(&p) = physicals.first() {
                    phys.insert((dim, tag), p);
                }
                let mut bounding = Vec::new();
                if dim > 0 {
                    let nbound = self.size()?;
                    bounding.reserve(self.cap(nbound, 4));
                    for _ in 0..nbound {
                        bounding.push(self.int()?);
                    }
                }
                out.push(MshEntity {
                    dim,
                    tag,
                    physicals,
                    bounding,
                });
            }
        }
        Ok(())
    }

    fn nodes_v4(&mut self, nodes: &mut Nodes) -> R<()> {
        let blocks = self.size()?;
        let total = self.size()?;
        self.size()?;
        self.size()?;
        nodes.points.reserve(self.cap(total, 24));
        for _ in 0..blocks {
            let dim = self.int()?;
            let entity = self.int()?;
            let parametric = self.int()? != 0;
            let n = self.size()?;
            let mut tags = Vec::with_capacity(self.cap(n, 8));
            for _ in 0..n {
                tags.push(self.size()?);
            }
            let extra = if parametric {
                dim.clamp(0, 3) as usize
            } else {
                0
            };
            for tag in tags {
                let (x, y, z) = (self.float()?, self.float()?, self.float()?);
                for _ in 0..extra {
                    self.float()?;
                }
                nodes.push(tag, x, y, z).or_else(|e| self.err(e))?;
                nodes.entities.push((dim, entity));
            }
        }
        Ok(())
    }

    fn nodes_v2(&mut self, nodes: &mut Nodes) -> R<()> {
        // The count is an ASCII line even in binary files.
        let n: u64 = self.ascii_count()?;
        nodes.points.reserve(self.cap(n, 28));
        for _ in 0..n {
            let tag = self.int_count("node tag")?;
            let (x, y, z) = (self.float()?, self.float()?, self.float()?);
            nodes.push(tag, x, y, z).or_else(|e| self.err(e))?;
        }
        Ok(())
    }

    /// A count on its own ASCII line (2.x sections, also in binary files).
    fn ascii_count(&mut self) -> R<u64> {
        let Some(l) = self.line() else {
            return self.err("unexpected end of file");
        };
        l.trim()
            .parse()
            .or_else(|_| self.err(format!("bad count {:?}", truncate(l))))
    }

    fn elements_v4(&mut self, elems: &mut Elements, phys: &HashMap<(i32, i32), i32>) -> R<()> {
        let blocks = self.size()?;
        for _ in 0..3 {
            self.size()?;
        }
        for _ in 0..blocks {
            let dim = self.int()?;
            let entity = self.int()?;
            let etype = self.int()?;
            let n = self.size()?;
            let Some((_, nn)) = element_shape(etype) else {
                return self.err(format!("unknown element type {etype}"));
            };
            let order = triangle_order(etype);
            let physical = phys.get(&(dim, entity)).copied();
            let is_line = dim == 1 && line_nodes(etype).is_some();
            for _ in 0..n {
                self.size()?; // element tag
                match order {
                    Some(o) if dim == 2 => {
                        let mut v = [0u64; 10];
                        for t in v.iter_mut().take(nn) {
                            *t = self.size()?;
                        }
                        elems
                            .block(o, physical, Some(entity))
                            .extend_from_slice(&v[..nn]);
                    }
                    _ if is_line => {
                        let mut v = [0u64; 4];
                        for t in v.iter_mut().take(nn) {
                            *t = self.size()?;
                        }
                        elems
                            .line_block(nn, physical, Some(entity))
                            .extend_from_slice(&v[..nn]);
                    }
                    _ => {
                        for _ in 0..nn {
                            self.size()?;
                        }
                        elems.count(dim, etype);
                    }
                }
            }
        }
        Ok(())
    }

    fn elements_v2(&mut self, elems: &mut Elements) -> R<()> {
        let total: u64 = self.ascii_count()?;
        let mut read = 0u64;
        while read < total {
            // Binary files group elements under a header (type, count, tag count);
            // ASCII files repeat type and tag count on every line.
            let (etype, follow, ntags) = match self.mode {
                Mode::Binary { .. } => {
                    let t = self.int()?;
                    let f = self.int_count("element count")?;
                    let nt = self.int_count("tag count")?;
                    (t, f, Some(nt))
                }
                Mode::Ascii => (0, 1, None),
            };
            if follow == 0 || follow > total - read {
                return self.err(format!(
                    "element group of {follow} exceeds the declared count"
                ));
            }
            for _ in 0..follow {
                self.int()?; // element tag
                let (etype, ntags) = match ntags {
                    Some(nt) => (etype, nt),
                    None => {
                        let t = self.int()?;
                        (t, self.int_count("tag count")?)
                    }
                };
                let Some((dim, nn)) = element_shape(etype) else {
                    return self.err(format!("unknown element type {etype}"));
                };
                let (mut physical, mut entity) = (None, None);
                for k in 0..ntags {
                    let t = self.int()?;
                    match k {
                        0 => physical = Some(t),
                        1 => entity = Some(t),
                        _ => {}
                    }
                }
                match triangle_order(etype) {
                    Some(o) => {
                        let mut v = [0u64; 10];
                        for t in v.iter_mut().take(nn) {
                            *t = self.int_count("node tag")?;
                        }
                        elems.block(o, physical, entity).extend_from_slice(&v[..nn]);
                    }
                    None if line_nodes(etype).is_some() => {
                        let mut v = [0u64; 4];
                        for t in v.iter_mut().take(nn) {
                            *t = self.int_count("node tag")?;
                        }
                        elems
                            .line_block(nn, physical, entity)
                            .extend_from_slice(&v[..nn]);
                    }
                    None => {
                        for _ in 0..nn {
                            self.int()?;
                        }
                        elems.count(dim, etype);
                    }
                }
            }
            read += follow;
        }
        Ok(())
    }
}

fn truncate(s: &str) -> String {
    s.chars().take(40).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixture(name: &str) -> Vec<u8> {
        let p = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures")
            .join(name);
        std::fs::read(p).expect("fixture")
    }

    #[test]
    fn gmsh_fixtures_read_alike() {
        let mut first: Option<MshMesh> = None;
        for f in [
            "gmsh-disk-p3-v22-ascii.msh",
            "gmsh-disk-p3-v22-binary.msh",
            "gmsh-disk-p3-v41-ascii.msh",
            "gmsh-disk-p3-v41-binary.msh",
        ] {
            let m = read_msh(&fixture(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
            assert!(m.triangle_count() > 0, "{f}");
            assert!(m.triangles().all(|(o, _)| o == Order::Cubic), "{f}");
            assert!(m.lines > 0, "{f}");
            if let Some(a) = &first {
                assert_eq!(a.nodes.len(), m.nodes.len(), "{f}");
                assert_eq!(a.triangle_count(), m.triangle_count(), "{f}");
                let pa: Vec<Point> = a
                    .triangles()
                    .flat_map(|(_, t)| t.iter().map(|&i| a.nodes[i as usize]))
                    .collect();
                let pm: Vec<Point> = m
                    .triangles()
                    .flat_map(|(_, t)| t.iter().map(|&i| m.nodes[i as usize]))
                    .collect();
                assert_eq!(pa.len(), pm.len(), "{f}");
                // gmsh's ASCII files print 16 significant digits
                let worst = pa
                    .iter()
                    .zip(&pm)
                    .map(|(a, b)| (*a - *b).hypot())
                    .fold(0.0, f64::max);
                assert!(worst < 1e-13, "{f}: nodes differ by {worst}");
            } else {
                first = Some(m);
            }
        }
    }

    #[test]
    fn unknown_sections_and_other_elements() {
        let text = b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Comments\nhi $Nodes\n$EndComments\n\
            $Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n$EndNodes\n\
            $Elements\n3\n1 15 2 0 1 1\n2 3 2 5 5 1 2 3 4\n3 2 2 7 7 1 2 3\n$EndElements\n";
        let m = read_msh(text).expect("read");
        assert_eq!(
            (m.other_elements, m.unsupported_2d, m.triangle_count()),
            (1, 1, 1)
        );
        assert_eq!(m.triangle_blocks[0].physical, Some(7));
    }
}
