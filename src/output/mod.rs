//! Output: gmsh .msh writers (4.1 and 2.2, ASCII and binary) and the SVG preview
//! (docs/design.md "Data flow", last stage; "Curved elements" for the node order).
//!
//! Owns the file formats. Guarantees:
//! - every file is written to a temporary file in the target directory and renamed,
//!   so no partial file ever appears and a failed write leaves an existing file as it was;
//! - a malformed [`FemMesh`] (index out of range, group lists of the wrong length,
//!   non-finite coordinates) is an [`crate::Error::Write`], never a panic;
//! - coordinates read back bit-exactly (binary) or to the last bit (ASCII, shortest
//!   round-trip decimal);
//! - one physical group per used surface / curve name; in 4.1 a discrete gmsh model
//!   (point entities where curves meet, curve entities per piece of a physical curve,
//!   one surface entity per physical surface with its bounding curves, each node on
//!   the entity of lowest dimension it lies on), one element type per entity; 2.2
//!   carries the same elementary tags (see `msh.rs` for the layout);
//! - the VTK XML unstructured grid (`.vtu`) holds the same nodes, triangles and
//!   physical lines as Lagrange cells, tagged by physical group (see `vtu.rs`).

mod atomic;
mod msh;
mod preview;
mod vtu;

use crate::{Error, FemMesh, Result};
pub use atomic::remove_temporaries;
pub(crate) use preview::PreviewMarks;
use std::path::Path;

/// gmsh file format version.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum MshVersion {
    /// MSH 4.1 (default).
    V41,
    /// MSH 2.2 (legacy readers).
    V22,
}

/// The file format of a mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum MeshFormat {
    /// gmsh .msh, as [`MshOptions`] say (default).
    #[default]
    Msh,
    /// VTK XML unstructured grid (`.vtu`) of Lagrange cells ([`write_vtu`]).
    Vtu,
}

/// How to write a .msh file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MshOptions {
    /// Format version.
    pub version: MshVersion,
    /// Binary instead of ASCII.
    pub binary: bool,
}

impl MshOptions {
    /// MSH 4.1 ASCII.
    pub const DEFAULT: MshOptions = MshOptions {
        version: MshVersion::V41,
        binary: false,
    };
}

impl Default for MshOptions {
    fn default() -> Self {
        MshOptions::DEFAULT
    }
}

/// Write `mesh` as a gmsh file at `path` (atomically).
///
/// # Errors
/// [`crate::Error::Write`] when the directory is missing or not writable, `path`
/// is a directory, writing fails, or `mesh` is malformed (an index out of range,
/// group lists that do not match the elements, a non-finite coordinate, more
/// than 2^31 nodes or elements). On error nothing is created and an existing file
/// at `path` is left untouched.
pub fn write_msh(mesh: &FemMesh, path: &Path, opts: MshOptions) -> Result<()> {
    msh::validate(mesh).map_err(Error::Write)?;
    let _span = tracing::debug_span!("write_msh", path = %path.display()).entered();
    atomic::write_atomic(path, |w| write_format(w, mesh, opts))
}

/// Write `mesh` in gmsh format to any writer (a buffer, a socket): the bytes
/// [`write_msh`] puts in a file.
///
/// ```
/// use triwild::{FemMesh, MshOptions, Order, read_msh, write_msh_to};
/// use kurbo::Point;
///
/// // One straight triangle in one physical surface.
/// let mesh = FemMesh {
///     order: Some(Order::Linear),
///     nodes: vec![Point::new(0.0, 0.0), Point::new(1.0, 0.0), Point::new(0.0, 1.0)],
///     triangles: vec![0, 1, 2],
///     triangle_group: vec![0],
///     surfaces: vec!["plate".into()],
///     ..FemMesh::default()
/// };
/// let mut bytes = Vec::new();
/// write_msh_to(&mesh, &mut bytes, MshOptions::DEFAULT)?;
/// assert!(bytes.starts_with(b"$MeshFormat\n4.1 0 8"));
/// let back = read_msh(&bytes)?;
/// assert_eq!(back.nodes, mesh.nodes);
/// assert_eq!(back.triangle_count(), 1);
/// # Ok::<(), triwild::Error>(())
/// ```
///
/// # Errors
/// [`crate::Error::Write`] when `mesh` is malformed (as [`write_msh`]) or the writer fails.
pub fn write_msh_to(mesh: &FemMesh, w: &mut impl std::io::Write, opts: MshOptions) -> Result<()> {
    msh::validate(mesh).map_err(Error::Write)?;
    let mut w = std::io::BufWriter::new(w);
    write_format(&mut w, mesh, opts)
        .and_then(|()| std::io::Write::flush(&mut w))
        .map_err(Error::Write)
}

/// Write `mesh` as a VTK XML unstructured grid at `path` (atomically): the
/// triangles as VTK Lagrange triangles (type 69) of the mesh's order, the
/// physical curves' line elements as Lagrange curves (type 68), cell data
/// `region` and `curve` (the physical tags of the .msh file, 0 where a cell
/// has none) and one field data array `[tag, dim]` per physical name.
///
/// # Errors
/// As [`write_msh`].
pub fn write_vtu(mesh: &FemMesh, path: &Path) -> Result<()> {
    msh::validate(mesh).map_err(Error::Write)?;
    let _span = tracing::debug_span!("write_vtu", path = %path.display()).entered();
    atomic::write_atomic(path, |w| vtu::write_vtu(w, mesh))
}

/// [`write_vtu`] to any writer.
///
/// # Errors
/// [`crate::Error::Write`] when `mesh` is malformed (as [`write_msh`]) or the writer fails.
pub fn write_vtu_to(mesh: &FemMesh, w: &mut impl std::io::Write) -> Result<()> {
    msh::validate(mesh).map_err(Error::Write)?;
    let mut w = std::io::BufWriter::new(w);
    vtu::write_vtu(&mut w, mesh)
        .and_then(|()| std::io::Write::flush(&mut w))
        .map_err(Error::Write)
}

/// The gmsh bytes of a validated `mesh` in `opts`' format.
fn write_format(
    w: &mut impl std::io::Write,
    mesh: &FemMesh,
    opts: MshOptions,
) -> std::io::Result<()> {
    match opts.version {
        MshVersion::V41 => msh::write_v41(w, mesh, opts.binary),
        MshVersion::V22 => msh::write_v22(w, mesh, opts.binary),
    }
}

/// How [`write_preview`] draws a mesh: triangle outlines only
/// ([`PreviewOptions::DEFAULT`]), or filled with the colour of their physical
/// surface.
#[derive(Clone, Copy)]
#[non_exhaustive]
pub struct PreviewOptions<'a> {
    /// `colours[s]`, a CSS colour (`#rrggbb`, `#rrggbbaa`), fills the
    /// triangles of physical surface `s` (a missing entry or `None` leaves
    /// them unfilled), so the picture can be compared with the drawing at a
    /// glance (the `colour` of each region in `--stats`). Default empty.
    pub colours: &'a [Option<String>],
    /// Marks drawn over the mesh (`--preview`: forced corners, the worst
    /// unforced element). Default none.
    pub(crate) marks: Option<&'a PreviewMarks>,
    /// The size field h: each triangle filled by how its size matches it
    /// (`--preview-size`), instead of by colour. Default none.
    pub(crate) size: Option<&'a dyn Fn(kurbo::Point) -> f64>,
}

impl<'a> PreviewOptions<'a> {
    /// Triangle outlines and feature lines, no fill, no marks.
    pub const DEFAULT: PreviewOptions<'a> = PreviewOptions {
        colours: &[],
        marks: None,
        size: None,
    };

    /// Fill each physical surface's triangles with its colour (see
    /// [`PreviewOptions::colours`]).
    pub fn with_colours(mut self, colours: &'a [Option<String>]) -> Self {
        self.colours = colours;
        self
    }

    /// Draw `marks` over the mesh.
    pub(crate) fn with_marks(mut self, marks: &'a PreviewMarks) -> Self {
        self.marks = Some(marks);
        self
    }

    /// Fill each triangle by how its size matches the size field `h`: its
    /// mean edge length over h at its centroid, blue below 4/5, neutral
    /// within [4/5, 4/3], red above, with a legend.
    pub(crate) fn with_size_field(mut self, h: &'a dyn Fn(kurbo::Point) -> f64) -> Self {
        self.size = Some(h);
        self
    }
}

impl Default for PreviewOptions<'_> {
    fn default() -> Self {
        PreviewOptions::DEFAULT
    }
}

impl std::fmt::Debug for PreviewOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PreviewOptions")
            .field("colours", &self.colours)
            .field("marks", &self.marks)
            .field("size", &self.size.map(|_| "h(x)"))
            .finish()
    }
}

/// Write an SVG preview of `mesh` at `path` (atomically), drawn as `opts`
/// says: grey triangle outlines (curved edges drawn as the Bézier curves
/// they are), feature lines coloured by [`crate::fem::LineKind`] (primary
/// red, secondary green, constraint blue, boundary black), y flipped back so
/// it looks like the input.
///
/// # Errors
/// As [`write_msh`].
pub fn write_preview(mesh: &FemMesh, path: &Path, opts: &PreviewOptions<'_>) -> Result<()> {
    msh::validate(mesh).map_err(Error::Write)?;
    let no_marks = PreviewMarks::default();
    let marks = opts.marks.unwrap_or(&no_marks);
    atomic::write_atomic(path, |w| {
        preview::write_svg(w, mesh, opts.colours, opts.size, marks)
    })
}

/// Check that a file can be created at `path` (its directory exists and is
/// writable, and `path` is not a directory), without leaving anything behind:
/// a temporary file is created in the directory and removed.
///
/// # Errors
/// [`crate::Error::Write`] saying "directory X does not exist", "X is not a
/// directory", "X is a directory" or "directory X is not writable: cause".
pub fn check_writable(path: &Path) -> Result<()> {
    atomic::check_writable(path)
}

/// Write `bytes` to `path` atomically (temporary file in the same directory, then
/// rename): for the small text outputs (JSON, previews) of other commands.
///
/// # Errors
/// [`crate::Error::Write`].
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    atomic::write_atomic(path, |w| std::io::Write::write_all(w, bytes))
}
