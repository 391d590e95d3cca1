//! The geometric order of Lagrange elements and its gmsh element type numbers
//! (the one place that names them: the writers in `output` and the reader in
//! `input` both ask [`Order`]).

/// Geometric order of the elements (1 linear, 2 quadratic, 3 cubic).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Order {
    /// Straight 3-node triangles (gmsh type 2) and 2-node lines (type 1).
    Linear = 1,
    /// 6-node triangles (type 9) and 3-node lines (type 8).
    Quadratic = 2,
    /// 10-node triangles (type 21) and 4-node lines (type 26).
    Cubic = 3,
}

impl Order {
    /// Nodes per triangle.
    pub fn triangle_nodes(self) -> usize {
        match self {
            Order::Linear => 3,
            Order::Quadratic => 6,
            Order::Cubic => 10,
        }
    }
    /// Nodes per line element.
    pub fn line_nodes(self) -> usize {
        self as usize + 1
    }

    /// gmsh element type number of a triangle of this order (2, 9, 21).
    pub fn gmsh_triangle_type(self) -> i32 {
        match self {
            Order::Linear => 2,
            Order::Quadratic => 9,
            Order::Cubic => 21,
        }
    }

    /// gmsh element type number of a line of this order (1, 8, 26).
    pub fn gmsh_line_type(self) -> i32 {
        match self {
            Order::Linear => 1,
            Order::Quadratic => 8,
            Order::Cubic => 26,
        }
    }

    /// The order of a gmsh triangle type (2, 9 or 21; `None` for any other type).
    ///
    /// ```
    /// use triwild::Order;
    /// assert_eq!(Order::from_gmsh_triangle_type(21), Some(Order::Cubic));
    /// assert_eq!(Order::Cubic.triangle_nodes(), 10);
    /// assert_eq!(Order::from_gmsh_triangle_type(3), None); // a quadrangle
    /// ```
    pub fn from_gmsh_triangle_type(t: i32) -> Option<Order> {
        [Order::Linear, Order::Quadratic, Order::Cubic]
            .into_iter()
            .find(|o| o.gmsh_triangle_type() == t)
    }
}
