//! The mesh as delivered to a solver: nodes, elements of one order, physical groups.
//!
//! Every mesher's result is turned into a [`FemMesh`] before output; the writers
//! (`output`) and the region tagging (`regions`) work on it and nothing else.
//! Node ordering of elements follows gmsh: triangles list their corners
//! counter-clockwise, then the high-order nodes (type 9: edge 0→1, 1→2, 2→0
//! midpoints; type 21: two nodes per edge at 1/3 and 2/3 in that edge order, then
//! the centre). Lines list their two ends, then interior nodes in order along the line
//! (gmsh type 8: end, end, middle; type 26: end, end, 1/3, 2/3).

use crate::element::Order;
use crate::mesh::{EdgeKey, FeatureOn, TriMesh, VertexId};
use crate::stage::Stage;
use crate::{Error, Result};
use kurbo::Point;

/// What kind of feature a line element lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LineKind {
    /// A primary feature (curved in curved output).
    Primary,
    /// A secondary feature (approximated within ε).
    Secondary,
    /// A constrained edge of the CDT baseline (flattened input).
    Constraint,
    /// An edge of the meshed domain's boundary (the padded box, the outline
    /// left by `--cut-outside`, the rim of a dropped region), in the physical
    /// curve [`BOUNDARY`].
    Boundary,
}

/// Name of the physical curve that holds every edge of the meshed domain's
/// boundary, oriented with the domain on its left (the writers give it this
/// name before any other, so a drawing element with this id is renamed).
pub const BOUNDARY: &str = "boundary";

/// A mesh ready for output.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FemMesh {
    /// Element order; `triangles` has `order.triangle_nodes()` entries per element.
    pub order: Option<Order>,
    /// All nodes (corners and high-order nodes).
    pub nodes: Vec<Point>,
    /// Flat triangle connectivity, `order.triangle_nodes()` node indices per triangle.
    pub triangles: Vec<u32>,
    /// Physical surface of each triangle: an index into `surfaces`.
    pub triangle_group: Vec<u32>,
    /// Physical surface names (each becomes a gmsh physical group of dimension 2).
    pub surfaces: Vec<String>,
    /// Flat line connectivity, `order.line_nodes()` node indices per line.
    pub lines: Vec<u32>,
    /// Physical curve of each line: an index into `curves`.
    pub line_group: Vec<u32>,
    /// Kind of each line (for previews and statistics).
    pub line_kind: Vec<LineKind>,
    /// Physical curve names (each becomes a gmsh physical group of dimension 1).
    pub curves: Vec<String>,
    /// The periodic match of a periodic cell's mesh (`--periodic`), else `None`.
    pub periodic: Option<Periodicity>,
}

/// The periodic match of a mesh that covers a cell: node pairs across
/// opposite sides (gmsh's `$Periodic`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Periodicity {
    /// The cell `[x0, y0, x1, y1]`.
    pub cell: [f64; 4],
    /// Left and right sides match (period `x1 - x0` along x).
    pub x: bool,
    /// Bottom and top sides match (period `y1 - y0` along y).
    pub y: bool,
    /// Every node of the right side with its partner on the left (axis 0), and
    /// every node of the top side with its partner on the bottom (axis 1):
    /// the same coordinate along the side, bit for bit. A corner of the cell
    /// is in a pair for each axis it is a slave of.
    pub pairs: Vec<PeriodicPair>,
}

/// One node pair of a [`Periodicity`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PeriodicPair {
    /// The node on the right (top) side, an index into [`FemMesh::nodes`].
    pub node: u32,
    /// Its partner on the left (bottom) side: `node` is `master` translated by
    /// the period.
    pub master: u32,
    /// 0: the period along x; 1: along y.
    pub axis: u8,
}

impl FemMesh {
    /// The element order (linear when unset).
    pub fn order(&self) -> Order {
        self.order.unwrap_or(Order::Linear)
    }
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len() / self.order().triangle_nodes()
    }
    /// Number of line elements.
    pub fn line_count(&self) -> usize {
        self.lines.len() / self.order().line_nodes()
    }
    /// Node indices of triangle `i`.
    pub fn triangle(&self, i: usize) -> &[u32] {
        let n = self.order().triangle_nodes();
        &self.triangles[i * n..(i + 1) * n]
    }
    /// Node indices of line `i`.
    pub fn line(&self, i: usize) -> &[u32] {
        let n = self.order().line_nodes();
        &self.lines[i * n..(i + 1) * n]
    }
    /// Reverse the direction of line `i`: its two ends swap and its inner
    /// nodes run the other way (gmsh order: end, end, then inner nodes along
    /// the line).
    pub fn reverse_line(&mut self, i: usize) {
        let n = self.order().line_nodes();
        let line = &mut self.lines[i * n..(i + 1) * n];
        line.swap(0, 1);
        line[2..].reverse();
    }
    /// The three corner positions of triangle `i`.
    pub fn corners(&self, i: usize) -> [Point; 3] {
        let t = self.triangle(i);
        [
            self.nodes[t[0] as usize],
            self.nodes[t[1] as usize],
            self.nodes[t[2] as usize],
        ]
    }
}

/// Positions, within a triangle's node list, of the inner nodes of its edge `k`
/// (0: corner 0→1, 1: 1→2, 2: 2→0), in order from the edge's start.
pub(crate) fn triangle_edge_inner(order: Order, k: usize) -> &'static [usize] {
    match (order, k) {
        (Order::Linear, _) => &[],
        (Order::Quadratic, 0) => &[3],
        (Order::Quadratic, 1) => &[4],
        (Order::Quadratic, _) => &[5],
        (Order::Cubic, 0) => &[3, 4],
        (Order::Cubic, 1) => &[5, 6],
        (Order::Cubic, _) => &[7, 8],
    }
}

/// A constrained edge of a linear mesh: a chain piece of some input feature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatureEdge {
    /// The two vertices (indices into [`LinearMesh::vertices`]).
    pub v: [u32; 2],
    /// The shape the feature came from.
    pub shape: crate::svg::ShapeId,
    /// What kind of feature it is.
    pub kind: LineKind,
}

/// The common product of every linear mesher: straight triangles and the feature
/// edges they conform to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinearMesh {
    /// Vertex positions.
    pub vertices: Vec<Point>,
    /// Counter-clockwise triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Feature edges; each is an edge of the triangulation.
    pub edges: Vec<FeatureEdge>,
}

impl LinearMesh {
    /// The delivered form of a [`TriMesh`]: live vertices numbered compactly in
    /// id order ([`VertexNumbers`]), its (counter-clockwise) triangles, and one
    /// [`FeatureEdge`] per tagged edge and distinct `(shape, kind)` that
    /// `feature` assigns to its tags, in edge order ([`feature_lines`]). The
    /// curved mesh (`curve`) numbers its vertices and writes its lines through
    /// the same two.
    ///
    /// # Errors
    /// [`Error::Meshing`] in `stage` if some vertex still has a rational position
    /// (docs/design.md "Exactness": such a mesh is never written).
    pub(crate) fn from_trimesh<I: IntoIterator<Item = (crate::svg::ShapeId, LineKind)>>(
        mesh: &TriMesh,
        stage: Stage,
        feature: impl Fn(&FeatureOn) -> I,
    ) -> Result<LinearMesh> {
        require_f64(mesh, stage)?;
        let (numbers, vertices) = VertexNumbers::of(mesh);
        let triangles = mesh
            .faces()
            .map(|f| mesh.face(f).map(|v| numbers.get(v)))
            .collect();
        let edges = feature_lines(mesh, feature)
            .into_iter()
            .map(|(k, (shape, kind))| FeatureEdge {
                v: [numbers.get(k.lo), numbers.get(k.hi)],
                shape,
                kind,
            })
            .collect();
        Ok(LinearMesh {
            vertices,
            triangles,
            edges,
        })
    }
}

/// The check every mesh delivered from a [`TriMesh`] passes first: no vertex
/// still has a rational position (docs/design.md "Exactness": such a mesh is never
/// written).
///
/// # Errors
/// [`Error::Meshing`] in `stage` if some vertex is still rational.
pub(crate) fn require_f64(mesh: &TriMesh, stage: Stage) -> Result<()> {
    let rational = mesh.vertices().filter(|&v| mesh.is_rational(v)).count();
    if rational > 0 {
        return Err(Error::meshing(
            stage,
            format!("{rational} vertices could not be rounded to f64 without inverting a triangle"),
        ));
    }
    Ok(())
}

/// The node numbers of a [`TriMesh`]'s live vertices: compact, in id order.
/// Every mesh delivered from a `TriMesh` (linear, BSP and curved) numbers its
/// vertices this way, before any high-order node.
#[derive(Clone, Debug)]
pub(crate) struct VertexNumbers(Vec<u32>);

impl VertexNumbers {
    /// The numbers of `mesh`'s live vertices, and their positions in that order.
    pub(crate) fn of(mesh: &TriMesh) -> (VertexNumbers, Vec<Point>) {
        let mut index = vec![u32::MAX; mesh.vertex_capacity()];
        let mut positions = Vec::with_capacity(mesh.num_vertices());
        for v in mesh.vertices() {
            index[v.index()] =
                u32::try_from(positions.len()).expect("internal: vertex count fits u32");
            positions.push(mesh.position(v));
        }
        (VertexNumbers(index), positions)
    }

    /// The number of the live vertex `v`.
    pub(crate) fn get(&self, v: VertexId) -> u32 {
        let i = self.0[v.index()];
        debug_assert!(
            i != u32::MAX,
            "internal: face refers to a dead vertex {v:?}"
        );
        i
    }
}

/// The feature lines of a [`TriMesh`]: one per tagged edge and distinct
/// `(shape, kind)` that `feature` assigns to its tags (in tag order; a tag
/// may stand for several shapes' outlines, `features::coincide`), edges in
/// key order. Every mesh delivered from a `TriMesh` writes its lines in this
/// order.
pub(crate) fn feature_lines<I: IntoIterator<Item = (crate::svg::ShapeId, LineKind)>>(
    mesh: &TriMesh,
    feature: impl Fn(&FeatureOn) -> I,
) -> Vec<(EdgeKey, (crate::svg::ShapeId, LineKind))> {
    let mut tagged: Vec<_> = mesh.tagged_edges().collect();
    tagged.sort_unstable_by_key(|(k, _)| *k);
    let mut lines: Vec<(EdgeKey, (crate::svg::ShapeId, LineKind))> =
        Vec::with_capacity(tagged.len());
    for (k, tags) in tagged {
        let first = lines.len();
        for t in tags {
            for f in feature(t) {
                let line = (k, f);
                if !lines[first..].contains(&line) {
                    lines.push(line);
                }
            }
        }
    }
    lines
}

impl FemMesh {
    /// A FemMesh of `order` with one physical surface `surface` and one physical
    /// curve per shape that has feature lines (named with `shape_name`, numbered in
    /// order of first appearance): `lines` holds `order.line_nodes()` node indices per
    /// line and `line_features` each line's shape and kind. Every mesher's output
    /// (linear, BSP, curved) is delivered through here.
    pub fn assemble(
        order: Order,
        nodes: Vec<Point>,
        triangles: Vec<u32>,
        lines: Vec<u32>,
        line_features: impl ExactSizeIterator<Item = (crate::svg::ShapeId, LineKind)>,
        surface: &str,
        shape_name: impl Fn(crate::svg::ShapeId) -> String,
    ) -> FemMesh {
        let mut curves: Vec<String> = Vec::new();
        let mut curve_of: std::collections::HashMap<crate::svg::ShapeId, u32> =
            std::collections::HashMap::new();
        let mut line_group = Vec::with_capacity(line_features.len());
        let mut line_kind = Vec::with_capacity(line_features.len());
        for (shape, kind) in line_features {
            let g = *curve_of.entry(shape).or_insert_with(|| {
                curves.push(shape_name(shape));
                (curves.len() - 1) as u32
            });
            line_group.push(g);
            line_kind.push(kind);
        }
        let count = triangles.len() / order.triangle_nodes();
        FemMesh {
            order: Some(order),
            nodes,
            triangles,
            triangle_group: vec![0; count],
            surfaces: vec![surface.to_owned()],
            lines,
            line_group,
            line_kind,
            curves,
            periodic: None,
        }
    }

    /// A linear FemMesh with one physical surface `surface` and one physical curve
    /// per shape that has feature edges (named with `shape_name`).
    pub fn from_linear(
        mesh: &LinearMesh,
        surface: &str,
        shape_name: impl Fn(crate::svg::ShapeId) -> String,
    ) -> FemMesh {
        FemMesh::assemble(
            Order::Linear,
            mesh.vertices.clone(),
            mesh.triangles.iter().flatten().copied().collect(),
            mesh.edges.iter().flat_map(|e| e.v).collect(),
            mesh.edges.iter().map(|e| (e.shape, e.kind)),
            surface,
            shape_name,
        )
    }
}
