//! The VTK XML unstructured grid (`.vtu`) writer, for ParaView and the `vtk`
//! package: the mesh's triangles as VTK Lagrange triangles and its physical
//! curves as VTK Lagrange curves, each cell tagged with its physical group.
//!
//! Layout (ASCII, one piece):
//! - points: the nodes in the .msh file's order (point `i` is node tag `i + 1`),
//!   with z = 0, written to the last bit (shortest round-trip decimal);
//! - cells: every triangle (`VTK_LAGRANGE_TRIANGLE` = 69, 3, 6 or 10 points)
//!   in the .msh file's element order (by region), so cell `j` below the
//!   triangle count is element tag `j + 1`; then the line elements of the
//!   physical curves (`VTK_LAGRANGE_CURVE` = 68, 2, 3 or 4 points) grouped by
//!   curve, one cell per line and per physical curve it belongs to (as MSH 2.2
//!   writes them);
//! - node order: VTK's Lagrange triangle numbers the corners, then each edge's
//!   inner points from its first corner to its second (edges 0-1, 1-2, 2-0),
//!   then the inner point: for 3, 6 and 10 nodes that is gmsh's order (VTK's
//!   parametric coordinates of a 10-point triangle are (0,0) (1,0) (0,1)
//!   (1/3,0) (2/3,0) (2/3,1/3) (1/3,2/3) (0,2/3) (0,1/3) (1/3,1/3), gmsh's
//!   too; the orders part from order 4 on, which triwild does not write), so
//!   the connectivity is the mesh's own. A Lagrange curve lists its two ends,
//!   then its inner points in order: gmsh's line order;
//! - cell data `region` (Int32): a triangle's physical surface tag (1-based,
//!   as in the .msh file), 0 on lines; `curve` (Int32): a line's physical curve
//!   tag, 0 on triangles;
//! - field data: one Int32 array per physical group with elements, named as
//!   the .msh file names it, holding `[tag, dim]` (the layout of meshio's
//!   `field_data` for gmsh files).

use crate::FemMesh;
use std::fmt::Write as _;
use std::io::{self, Write};

/// `VTK_LAGRANGE_TRIANGLE`.
pub(crate) const VTK_LAGRANGE_TRIANGLE: u8 = 69;
/// `VTK_LAGRANGE_CURVE`.
pub(crate) const VTK_LAGRANGE_CURVE: u8 = 68;

/// `name` with the five XML special characters escaped, for an attribute.
fn xml_attr(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    for c in name.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Write a list of numbers as the text of a `DataArray`, a few per line.
fn numbers<T: std::fmt::Display>(
    w: &mut impl Write,
    values: impl IntoIterator<Item = T>,
) -> io::Result<()> {
    let mut line = String::new();
    for (i, v) in values.into_iter().enumerate() {
        if i > 0 {
            line.push(if i % 12 == 0 { '\n' } else { ' ' });
        }
        let _ = write!(line, "{v}");
        if line.len() > 4096 {
            w.write_all(line.as_bytes())?;
            line.clear();
        }
    }
    line.push('\n');
    w.write_all(line.as_bytes())
}

/// Write a validated `mesh` as a VTK XML unstructured grid.
pub(crate) fn write_vtu(w: &mut impl Write, mesh: &FemMesh) -> io::Result<()> {
    let order = mesh.order();
    let (tn, ln) = (order.triangle_nodes(), order.line_nodes());
    let (nt, nl) = (mesh.triangle_count(), mesh.line_count());
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">"
    )?;
    writeln!(w, "<UnstructuredGrid>")?;
    writeln!(w, "<FieldData>")?;
    for (dim, tag, name) in super::msh::group_names(mesh) {
        writeln!(
            w,
            "<DataArray type=\"Int32\" Name=\"{}\" NumberOfTuples=\"2\" format=\"ascii\">{tag} {dim}</DataArray>",
            xml_attr(&name)
        )?;
    }
    writeln!(w, "</FieldData>")?;
    writeln!(
        w,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        mesh.nodes.len(),
        nt + nl
    )?;
    writeln!(w, "<Points>")?;
    writeln!(
        w,
        "<DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">"
    )?;
    numbers(w, mesh.nodes.iter().flat_map(|p| [p.x, p.y, 0.0]))?;
    writeln!(w, "</DataArray>")?;
    writeln!(w, "</Points>")?;
    writeln!(w, "<Cells>")?;
    writeln!(
        w,
        "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    )?;
    let triangles: Vec<u32> = super::msh::bucket(&mesh.triangle_group, mesh.surfaces.len())
        .into_iter()
        .flat_map(|(_, members)| members)
        .collect();
    let lines: Vec<u32> = super::msh::bucket(&mesh.line_group, mesh.curves.len())
        .into_iter()
        .flat_map(|(_, members)| members)
        .collect();
    let triangle_nodes = triangles.iter().flat_map(|&t| mesh.triangle(t as usize));
    let line_nodes = lines.iter().flat_map(|&l| mesh.line(l as usize));
    numbers(w, triangle_nodes.chain(line_nodes))?;
    writeln!(w, "</DataArray>")?;
    writeln!(
        w,
        "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">"
    )?;
    let offsets = (1..=nt)
        .map(|t| t * tn)
        .chain((1..=nl).map(|l| nt * tn + l * ln));
    numbers(w, offsets)?;
    writeln!(w, "</DataArray>")?;
    writeln!(
        w,
        "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">"
    )?;
    numbers(
        w,
        std::iter::repeat_n(VTK_LAGRANGE_TRIANGLE, nt)
            .chain(std::iter::repeat_n(VTK_LAGRANGE_CURVE, nl)),
    )?;
    writeln!(w, "</DataArray>")?;
    writeln!(w, "</Cells>")?;
    writeln!(w, "<CellData Scalars=\"region\">")?;
    writeln!(
        w,
        "<DataArray type=\"Int32\" Name=\"region\" format=\"ascii\">"
    )?;
    let region = triangles
        .iter()
        .map(|&t| mesh.triangle_group[t as usize] + 1);
    numbers(w, region.chain(std::iter::repeat_n(0, nl)))?;
    writeln!(w, "</DataArray>")?;
    writeln!(
        w,
        "<DataArray type=\"Int32\" Name=\"curve\" format=\"ascii\">"
    )?;
    let curve = lines.iter().map(|&l| mesh.line_group[l as usize] + 1);
    numbers(w, std::iter::repeat_n(0, nt).chain(curve))?;
    writeln!(w, "</DataArray>")?;
    writeln!(w, "</CellData>")?;
    writeln!(w, "</Piece>")?;
    writeln!(w, "</UnstructuredGrid>")?;
    writeln!(w, "</VTKFile>")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Order;
    use kurbo::Point;

    #[test]
    fn names_are_escaped_and_cells_are_counted() {
        let mesh = FemMesh {
            order: Some(Order::Linear),
            nodes: vec![
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(0.0, 1.0),
            ],
            triangles: vec![0, 1, 2],
            triangle_group: vec![1],
            surfaces: vec!["unused".into(), "a<b\"".into()],
            lines: vec![0, 1],
            line_group: vec![0],
            line_kind: vec![crate::LineKind::Boundary],
            curves: vec!["boundary".into()],
            periodic: None,
        };
        let mut out = Vec::new();
        write_vtu(&mut out, &mesh).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("Name=\"a&lt;b&apos;\" NumberOfTuples=\"2\" format=\"ascii\">2 2<"));
        assert!(!text.contains("unused"), "{text}");
        assert!(text.contains("Name=\"boundary\" NumberOfTuples=\"2\" format=\"ascii\">1 1<"));
        assert!(text.contains("NumberOfPoints=\"3\" NumberOfCells=\"2\""));
        assert!(
            text.contains("format=\"ascii\">\n69 68\n</DataArray>"),
            "{text}"
        );
        assert!(text.contains("Name=\"offsets\" format=\"ascii\">\n3 5\n"));
        assert!(text.contains("Name=\"region\" format=\"ascii\">\n2 0\n"));
        assert!(text.contains("Name=\"curve\" format=\"ascii\">\n0 1\n"));
    }
}
