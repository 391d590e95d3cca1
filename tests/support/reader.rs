//! An independent gmsh reader (MSH 2.2 and 4.1, ASCII and binary) for the tests.
//!
//! Written from the gmsh reference manual's "MSH file format" chapter, sharing
//! nothing with `src/output`; it reads what it needs (format, physical names,
//! entities, nodes, elements) and skips other sections.

use std::collections::HashMap;
use std::path::Path;

/// One element as read.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Element {
    /// Element tag.
    pub(crate) tag: u64,
    /// gmsh element type.
    pub(crate) etype: i32,
    /// Elementary entity tag.
    pub(crate) entity: i32,
    /// Physical tags (2.2: the element's first tag; 4.1: its entity's physical tags).
    pub(crate) physical: Vec<i32>,
    /// Node tags.
    pub(crate) nodes: Vec<u64>,
}

/// A parsed .msh file.
#[derive(Clone, Debug, Default)]
pub(crate) struct Msh {
    /// "2.2" or "4.1".
    pub(crate) version: String,
    /// Binary file.
    pub(crate) binary: bool,
    /// Node tags and coordinates, in file order.
    pub(crate) nodes: Vec<(u64, [f64; 3])>,
    /// Elements in file order.
    pub(crate) elements: Vec<Element>,
    /// (dimension, physical tag) -> name.
    pub(crate) physical_names: HashMap<(i32, i32), String>,
}

impl Msh {
    /// Position of each node tag in `nodes`.
    pub(crate) fn node_index(&self) -> HashMap<u64, usize> {
        self.nodes
            .iter()
            .enumerate()
            .map(|(i, &(t, _))| (t, i))
            .collect()
    }
    /// Elements of one gmsh type.
    pub(crate) fn of_type(&self, etype: i32) -> impl Iterator<Item = &Element> {
        self.elements.iter().filter(move |e| e.etype == etype)
    }
}

/// Number of nodes and dimension of the element types we know.
pub(crate) fn type_info(etype: i32) -> Option<(usize, i32)> {
    Some(match etype {
        15 => (1, 0),
        1 => (2, 1),
        8 => (3, 1),
        26 => (4, 1),
        2 => (3, 2),
        9 => (6, 2),
        21 => (10, 2),
        _ => return None,
    })
}

struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    binary: bool,
}

type R<T> = Result<T, String>;

impl<'a> Cursor<'a> {
    fn line(&mut self) -> R<&'a str> {
        if self.pos >= self.data.len() {
            return Err("unexpected end of file".into());
        }
        let rest = &self.data[self.pos..];
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        self.pos += (end + 1).min(rest.len());
        std::str::from_utf8(&rest[..end])
            .map(|s| s.trim_end_matches('\r'))
            .map_err(|e| format!("non-UTF-8 text line: {e}"))
    }
    fn skip_ws(&mut self) {
        while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }
    fn token(&mut self) -> R<&'a str> {
        self.skip_ws();
        let start = self.pos;
        while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return Err("unexpected end of file".into());
        }
        std::str::from_utf8(&self.data[start..self.pos]).map_err(|e| e.to_string())
    }
    fn bytes<const N: usize>(&mut self) -> R<[u8; N]> {
        let b = self
            .data
            .get(self.pos..self.pos + N)
            .ok_or("unexpected end of binary data")?;
        self.pos += N;
        Ok(b.try_into().expect("slice of length N"))
    }
    fn parse<T: std::str::FromStr>(&mut self) -> R<T> {
        let t = self.token()?;
        t.parse().map_err(|_| format!("bad number {t:?}"))
    }
    fn int(&mut self) -> R<i32> {
        if self.binary {
            Ok(i32::from_le_bytes(self.bytes()?))
        } else {
            self.parse()
        }
    }
    fn size(&mut self) -> R<u64> {
        if self.binary {
            Ok(u64::from_le_bytes(self.bytes()?))
        } else {
            self.parse()
        }
    }
    fn float(&mut self) -> R<f64> {
        if self.binary {
            Ok(f64::from_le_bytes(self.bytes()?))
        } else {
            self.parse()
        }
    }
    /// The `$End...` line closing a section (after binary data, its newline).
    fn expect_end(&mut self, name: &str) -> R<()> {
        self.skip_ws();
        let l = self.line()?;
        if l.trim() == format!("$End{name}") {
            Ok(())
        } else {
            Err(format!("expected $End{name}, found {:?}", truncate(l)))
        }
    }
}

fn truncate(s: &str) -> String {
    s.chars().take(60).collect()
}

/// Read a .msh file.
pub(crate) fn read_msh(path: &Path) -> R<Msh> {
    let data = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    parse_msh(&data)
}

/// Parse the bytes of a .msh file.
pub(crate) fn parse_msh(data: &[u8]) -> R<Msh> {
    let mut c = Cursor {
        data,
        pos: 0,
        binary: false,
    };
    let mut msh = Msh::default();
    // (dim, entity tag) -> physical tags, from 4.1 $Entities.
    let mut entity_phys: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
    let mut seen_format = false;
    loop {
        c.skip_ws();
        if c.pos >= data.len() {
            break;
        }
        let head = c.line()?.trim().to_owned();
        let Some(name) = head.strip_prefix('$') else {
            return Err(format!("expected a section, found {:?}", truncate(&head)));
        };
        match name {
            "MeshFormat" => {
                let l = c.line()?;
                let f: Vec<&str> = l.split_whitespace().collect();
                if f.len() != 3 {
                    return Err(format!("bad format line {l:?}"));
                }
                msh.version = f[0].to_owned();
                msh.binary = f[1] == "1";
                if !matches!(f[0], "2.2" | "4.1") {
                    return Err(format!("unsupported version {}", f[0]));
                }
                if f[2] != "8" {
                    return Err(format!("unsupported data size {}", f[2]));
                }
                if msh.binary {
                    let one = i32::from_le_bytes(c.bytes()?);
                    if one != 1 {
                        return Err("binary file not little-endian".into());
                    }
                }
                c.expect_end(name)?;
                seen_format = true;
            }
            "PhysicalNames" => {
                let n: usize = c.line()?.trim().parse().map_err(|_| "bad count")?;
                for _ in 0..n {
                    let l = c.line()?;
                    let mut it = l.splitn(3, ' ');
                    let dim: i32 = it.next().and_then(|s| s.parse().ok()).ok_or("bad dim")?;
                    let tag: i32 = it.next().and_then(|s| s.parse().ok()).ok_or("bad tag")?;
                    let q = it.next().ok_or("missing name")?.trim();
                    let name = q
                        .strip_prefix('"')
                        .and_then(|q| q.strip_suffix('"'))
                        .ok_or_else(|| format!("unquoted name {q:?}"))?;
                    if msh
                        .physical_names
                        .insert((dim, tag), name.to_owned())
                        .is_some()
                    {
                        return Err(format!("physical ({dim}, {tag}) named twice"));
                    }
                }
                c.expect_end(name)?;
            }
            "Entities" | "Nodes" | "Elements" if !seen_format => {
                return Err(format!("${name} before $MeshFormat"));
            }
            "Entities" => {
                c.binary = msh.binary;
                let counts = [c.size()?, c.size()?, c.size()?, c.size()?];
                for (dim, &count) in counts.iter().enumerate() {
                    for _ in 0..count {
                        let tag = c.int()?;
                        let nbox = if dim == 0 { 3 } else { 6 };
                        for _ in 0..nbox {
                            c.float()?;
                        }
                        let np = c.size()?;
                        let mut phys = Vec::new();
                        for _ in 0..np {
                            phys.push(c.int()?);
                        }
                        if dim > 0 {
                            let nb = c.size()?;
                            for _ in 0..nb {
                                c.int()?;
                            }
                        }
                        entity_phys.insert((dim as i32, tag), phys);
                    }
                }
                c.binary = false;
                c.expect_end(name)?;
            }
            "Nodes" if msh.version == "4.1" => {
                c.binary = msh.binary;
                let (blocks, total, _min, _max) = (c.size()?, c.size()?, c.size()?, c.size()?);
                for _ in 0..blocks {
                    let (dim, _tag, parametric, n) = (c.int()?, c.int()?, c.int()?, c.size()?);
                    let mut tags = Vec::new();
                    for _ in 0..n {
                        tags.push(c.size()?);
                    }
                    for t in tags {
                        let xyz = [c.float()?, c.float()?, c.float()?];
                        if parametric == 1 {
                            for _ in 0..dim {
                                c.float()?;
                            }
                        }
                        msh.nodes.push((t, xyz));
                    }
                }
                if msh.nodes.len() as u64 != total {
                    return Err(format!("{} nodes, header says {total}", msh.nodes.len()));
                }
                c.binary = false;
                c.expect_end(name)?;
            }
            "Nodes" => {
                let n: u64 = c.line()?.trim().parse().map_err(|_| "bad node count")?;
                c.binary = msh.binary;
                for _ in 0..n {
                    let t = c.int()?;
                    let xyz = [c.float()?, c.float()?, c.float()?];
                    msh.nodes
                        .push((u64::try_from(t).map_err(|_| "negative tag")?, xyz));
                }
                c.binary = false;
                c.expect_end(name)?;
            }
            "Elements" if msh.version == "4.1" => {
                c.binary = msh.binary;
                let (blocks, total, _min, _max) = (c.size()?, c.size()?, c.size()?, c.size()?);
                for _ in 0..blocks {
                    let (dim, entity, etype, n) = (c.int()?, c.int()?, c.int()?, c.size()?);
                    let (nn, tdim) = type_info(etype).ok_or(format!("unknown type {etype}"))?;
                    if tdim != dim {
                        return Err(format!("type {etype} in a block of dimension {dim}"));
                    }
                    let physical = entity_phys
                        .get(&(dim, entity))
                        .cloned()
                        .ok_or(format!("block on undeclared entity ({dim}, {entity})"))?;
                    for _ in 0..n {
                        let tag = c.size()?;
                        let mut nodes = Vec::with_capacity(nn);
                        for _ in 0..nn {
                            nodes.push(c.size()?);
                        }
                        msh.elements.push(Element {
                            tag,
                            etype,
                            entity,
                            physical: physical.clone(),
                            nodes,
                        });
                    }
                }
                if msh.elements.len() as u64 != total {
                    return Err(format!(
                        "{} elements, header says {total}",
                        msh.elements.len()
                    ));
                }
                c.binary = false;
                c.expect_end(name)?;
            }
            "Elements" => {
                let n: usize = c.line()?.trim().parse().map_err(|_| "bad element count")?;
                let mut read = |c: &mut Cursor<'_>, tag: i32, etype: i32, ntags: i32| -> R<()> {
                    let (nn, _) = type_info(etype).ok_or(format!("unknown type {etype}"))?;
                    let mut tags = Vec::new();
                    for _ in 0..ntags {
                        tags.push(c.int()?);
                    }
                    let mut nodes = Vec::with_capacity(nn);
                    for _ in 0..nn {
                        nodes.push(u64::try_from(c.int()?).map_err(|_| "negative node")?);
                    }
                    msh.elements.push(Element {
                        tag: u64::try_from(tag).map_err(|_| "negative tag")?,
                        etype,
                        entity: tags.get(1).copied().unwrap_or(0),
                        physical: tags
                            .first()
                            .copied()
                            .filter(|&p| p != 0)
                            .into_iter()
                            .collect(),
                        nodes,
                    });
                    Ok(())
                };
                if msh.binary {
                    c.binary = true;
                    let mut done = 0;
                    while done < n {
                        let (etype, count, ntags) = (c.int()?, c.int()?, c.int()?);
                        if count <= 0 {
                            return Err("empty binary element block".into());
                        }
                        for _ in 0..count {
                            let tag = c.int()?;
                            read(&mut c, tag, etype, ntags)?;
                        }
                        done += count as usize;
                    }
                    c.binary = false;
                } else {
                    for _ in 0..n {
                        let (tag, etype, ntags) = (c.int()?, c.int()?, c.int()?);
                        read(&mut c, tag, etype, ntags)?;
                    }
                }
                c.expect_end(name)?;
            }
            other => {
                // Unknown ASCII section: skip to its end.
                let end = format!("$End{other}");
                while c.line()?.trim() != end {}
            }
        }
    }
    if !seen_format {
        return Err("no $MeshFormat".into());
    }
    Ok(msh)
}
