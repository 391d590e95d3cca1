//! Geometry of one FEM element given by its nodes (gmsh order, see [`crate::fem`]):
//! a point at barycentric coordinates of the reference triangle, and the exact area.
//! Works for straight and curved (Lagrange P2, P3) triangles alike.

use crate::element::{Order, lagrange};
use kurbo::{CubicBez, Line, ParamCurveArea, Point, QuadBez};

/// The image of the reference point with barycentric coordinates `l` under the
/// element's Lagrange map. `nodes` holds `order.triangle_nodes()` points.
pub(crate) fn element_point(order: Order, nodes: &[Point], l: [f64; 3]) -> Point {
    let [a, b, c] = l;
    let weights: Vec<f64> = match order {
        Order::Linear => vec![a, b, c],
        Order::Quadratic => vec![
            a * (2.0 * a - 1.0),
            b * (2.0 * b - 1.0),
            c * (2.0 * c - 1.0),
            4.0 * a * b,
            4.0 * b * c,
            4.0 * c * a,
        ],
        Order::Cubic => {
            let corner = |x: f64| 0.5 * x * (3.0 * x - 1.0) * (3.0 * x - 2.0);
            let edge = |x: f64, y: f64| 4.5 * x * y * (3.0 * x - 1.0);
            vec![
                corner(a),
                corner(b),
                corner(c),
                edge(a, b),
                edge(b, a),
                edge(b, c),
                edge(c, b),
                edge(c, a),
                edge(a, c),
                27.0 * a * b * c,
            ]
        }
    };
    let (mut x, mut y) = (0.0, 0.0);
    for (w, p) in weights.iter().zip(nodes) {
        x += w * p.x;
        y += w * p.y;
    }
    Point::new(x, y)
}

/// The signed area of the element (positive when counter-clockwise), exact for
/// polynomial edges: Green's theorem along the three edges, each the Bézier
/// curve through its nodes.
pub(crate) fn element_area(order: Order, nodes: &[Point]) -> f64 {
    let c = [nodes[0], nodes[1], nodes[2]];
    (0..3)
        .map(|e| {
            let (p, q) = (c[e], c[(e + 1) % 3]);
            match order {
                Order::Linear => Line::new(p, q).signed_area(),
                Order::Quadratic => {
                    let ctrl = lagrange::quadratic_edge_control(p, nodes[3 + e], q);
                    QuadBez::new(p, ctrl, q).signed_area()
                }
                Order::Cubic => {
                    let [c1, c2] =
                        lagrange::cubic_edge_controls(p, nodes[3 + 2 * e], nodes[4 + 2 * e], q);
                    CubicBez::new(p, c1, c2, q).signed_area()
                }
            }
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lerp(p: Point, q: Point, t: f64) -> Point {
        p.lerp(q, t)
    }

    /// The nodes of a straight element of `order` on the corners `c`.
    fn straight(order: Order, c: [Point; 3]) -> Vec<Point> {
        let mut v = c.to_vec();
        match order {
            Order::Linear => {}
            Order::Quadratic => {
                for e in 0..3 {
                    v.push(lerp(c[e], c[(e + 1) % 3], 0.5));
                }
            }
            Order::Cubic => {
                for e in 0..3 {
                    v.push(lerp(c[e], c[(e + 1) % 3], 1.0 / 3.0));
                    v.push(lerp(c[e], c[(e + 1) % 3], 2.0 / 3.0));
                }
                v.push(Point::new(
                    (c[0].x + c[1].x + c[2].x) / 3.0,
                    (c[0].y + c[1].y + c[2].y) / 3.0,
                ));
            }
        }
        v
    }

    #[test]
    fn straight_elements_agree_with_the_linear_map() {
        let c = [
            Point::new(0.0, 0.0),
            Point::new(3.0, 1.0),
            Point::new(1.0, 2.0),
        ];
        for order in [Order::Linear, Order::Quadratic, Order::Cubic] {
            let n = straight(order, c);
            assert!((element_area(order, &n) - 2.5).abs() < 1e-12, "{order:?}");
            for l in [[1.0, 0.0, 0.0], [0.2, 0.3, 0.5], [1.0 / 3.0; 3]] {
                let p = element_point(order, &n, l);
                let q = element_point(Order::Linear, &n, l);
                assert!((p - q).hypot() < 1e-12, "{order:?} {l:?}");
            }
        }
    }

    #[test]
    fn nodes_interpolate_and_curved_area_is_exact() {
        // A cubic element whose edge 0→1 bulges: x ↦ (x, -x(1-x)) on [0, 1].
        let c = [
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(0.5, 1.0),
        ];
        let mut n = straight(Order::Cubic, c);
        n[3].y = -(1.0 / 3.0) * (2.0 / 3.0);
        n[4].y = -(2.0 / 3.0) * (1.0 / 3.0);
        let area = 0.5 + 1.0 / 6.0;
        assert!((element_area(Order::Cubic, &n) - area).abs() < 1e-12);
        assert!(
            (element_point(Order::Cubic, &n, [2.0 / 3.0, 1.0 / 3.0, 0.0]) - n[3]).hypot() < 1e-12
        );
        assert!(
            (element_point(Order::Cubic, &n, [0.0, 2.0 / 3.0, 1.0 / 3.0]) - n[5]).hypot() < 1e-12
        );
        assert!(
            (element_point(Order::Cubic, &n, [1.0 / 3.0, 0.0, 2.0 / 3.0]) - n[7]).hypot() < 1e-12
        );
        assert!(
            (element_point(Order::Cubic, &n, [2.0 / 3.0, 0.0, 1.0 / 3.0]) - n[8]).hypot() < 1e-12
        );
        assert!((element_point(Order::Cubic, &n, [1.0 / 3.0; 3]) - n[9]).hypot() < 1e-12);
        // Same bulge as a quadratic element (the parabola is exact at P2).
        let mut q = straight(Order::Quadratic, c);
        q[3].y = -0.25;
        assert!((element_area(Order::Quadratic, &q) - area).abs() < 1e-12);
        let mid = element_point(Order::Quadratic, &q, [0.5, 0.5, 0.0]);
        assert!((mid - Point::new(0.5, -0.25)).hypot() < 1e-12);
    }
}
