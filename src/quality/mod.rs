//! Mesh quality metrics: corner angles, the 2D conformal AMIPS energy, areas.
//!
//! Owns the numbers every mesher is judged by (the `--stats` report, docs/design.md
//! "Outputs a user can check"). Angles and energies are measured on the straight
//! triangle spanned by each element's three corners, whatever the element order;
//! the area and the Jacobian ratio are those of the elements as written (curved
//! or not), the numbers `triwild check` reads back from the file.
//!
//! The AMIPS energy is the 2D conformal one the optimizer minimises (thesis §2.3.2,
//! §4.4.1): with `J` the affine map from the equilateral reference triangle onto the
//! element, `E = tr(JᵀJ) / (2 det J)`. It is 1 exactly for equilateral triangles,
//! grows without bound as a triangle degenerates, and is `+∞` for degenerate and
//! inverted (clockwise) triangles.

use crate::FemMesh;
use crate::element::CertifyOptions;
use crate::element::jacobian;
use crate::mesh::corner_angles;
use kurbo::Point;

/// Quality summary of a mesh (corner triangles).
///
/// For a mesh without triangles every field is 0.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Quality {
    /// Smallest corner angle, degrees.
    pub min_angle_deg: f64,
    /// Largest corner angle, degrees.
    pub max_angle_deg: f64,
    /// Largest 2D AMIPS energy (1 for equilateral, `+∞` if any triangle is degenerate
    /// or clockwise).
    pub max_amips: f64,
    /// Mean 2D AMIPS energy (`+∞` if any triangle is degenerate or clockwise).
    pub mean_amips: f64,
    /// Total signed area of the elements as written, the exact integral of
    /// `det J` (curved edges included; clockwise elements count negative).
    pub area: f64,
    /// Smallest certified lower bound of `min det J / max det J` over the
    /// elements as written (1 when all are straight; ≤ 0 if one is invalid):
    /// `triwild check`'s `min_detj_ratio` of the written file.
    pub min_jacobian_ratio: f64,
    /// The same numbers left to the optimizer: over the corners and elements
    /// the drawing does not force (the TriWild mesher only, `None`
    /// for the CDT baseline). See [`Unforced`].
    pub unforced: Option<Unforced>,
}

/// Quality over what the drawing does not force. A corner is forced when the
/// input features leave no room for a good angle there (a wedge between two
/// features meeting below α, or a feature closer to another than the sizes
/// resolve; the pipeline decides it from the input, never from the mesh's
/// angles); an element is forced when one of its corners is.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Unforced {
    /// Smallest angle over the unforced corners, degrees (180 if every corner
    /// is forced).
    pub min_angle_deg: f64,
    /// Smallest certified Jacobian ratio over the unforced elements (1 if
    /// there is none).
    pub min_jacobian_ratio: f64,
    /// Unforced corners below α.
    pub below_alpha: usize,
    /// Unforced elements whose certified Jacobian ratio is below 0.1 (curved
    /// elements bent or parametrized too unevenly for their size).
    pub below_ratio_floor: usize,
    /// Forced corners.
    pub forced_corners: usize,
    /// Of those, forced by a wedge between features meeting below α (the one
    /// rule: see `optimize::forced`).
    pub forced_by_angle: usize,
    /// All corners (three per triangle).
    pub corners: usize,
    /// Forced elements.
    pub forced_elements: usize,
    /// The unforced element with the smallest angle, if any.
    pub worst: Option<WorstElement>,
    /// The unforced element with the smallest Jacobian ratio, if any.
    pub worst_ratio: Option<WorstElement>,
}

/// The smallest certified Jacobian ratio an unforced element should have
/// ([`Unforced::below_ratio_floor`]: 0.1 at orders 2 and 3, where a solver's
/// conditioning still holds).
pub(crate) const RATIO_FLOOR: f64 = 0.1;

/// Where the worst unforced element is and how bad.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct WorstElement {
    /// Its index among the written triangles.
    pub element: usize,
    /// Centroid of its corners, x (the mesh's coordinates, y up as written).
    pub x: f64,
    /// Centroid of its corners, y.
    pub y: f64,
    /// Its smallest angle, degrees.
    pub min_angle_deg: f64,
    /// Its certified Jacobian ratio.
    pub jacobian_ratio: f64,
}

/// Bits of a triangle's forced-corner mask ([`Quality::of_classified`]):
/// corner `k` forced by a wedge sets `FORCED_BY_ANGLE << k`.
pub(crate) const FORCED_BY_ANGLE: u8 = 1;

impl Quality {
    /// The summary of a mesh without triangles.
    pub const EMPTY: Quality = Quality {
        min_angle_deg: 0.0,
        max_angle_deg: 0.0,
        max_amips: 0.0,
        mean_amips: 0.0,
        area: 0.0,
        min_jacobian_ratio: 0.0,
        unforced: None,
    };

    /// Measure `mesh`'s elements: angles and energies of the straight triangles
    /// spanned by their corners, area and certified Jacobian ratio of the
    /// elements themselves (curved or not).
    pub fn of(mesh: &FemMesh) -> Quality {
        Quality::measure(mesh).0
    }

    /// [`Quality::of`] plus [`Quality::unforced`]: `forced[i]` is triangle
    /// `i`'s mask of forced corners ([`FORCED_BY_ANGLE`]; a missing entry:
    /// none), `alpha_deg` the α the
    /// corners below it are counted against.
    pub(crate) fn of_classified(mesh: &FemMesh, forced: &[u8], alpha_deg: f64) -> Quality {
        let (mut q, ratios) = Quality::measure(mesh);
        let mut u = Unforced {
            min_angle_deg: 180.0,
            min_jacobian_ratio: 1.0,
            below_alpha: 0,
            below_ratio_floor: 0,
            forced_corners: 0,
            forced_by_angle: 0,
            corners: 3 * mesh.triangle_count(),
            forced_elements: 0,
            worst: None,
            worst_ratio: None,
        };
        for (i, &ratio) in ratios.iter().enumerate() {
            let m = forced.get(i).copied().unwrap_or(0);
            let corners = mesh.corners(i);
            let angles = corner_angles(corners).map(f64::to_degrees);
            let mut element_forced = false;
            for (k, &a) in angles.iter().enumerate() {
                if m & (FORCED_BY_ANGLE << k) != 0 {
                    element_forced = true;
                    u.forced_corners += 1;
                    u.forced_by_angle += 1;
                } else {
                    u.min_angle_deg = u.min_angle_deg.min(a);
                    u.below_alpha += usize::from(a < alpha_deg);
                }
            }
            if element_forced {
                u.forced_elements += 1;
                continue;
            }
            u.min_jacobian_ratio = u.min_jacobian_ratio.min(ratio);
            u.below_ratio_floor += usize::from(ratio < RATIO_FLOOR);
            let min = angles.iter().copied().fold(f64::INFINITY, f64::min);
            let [a, b, c] = corners;
            let element = WorstElement {
                element: i,
                x: (a.x + b.x + c.x) / 3.0,
                y: (a.y + b.y + c.y) / 3.0,
                min_angle_deg: min,
                jacobian_ratio: ratio,
            };
            if u.worst.is_none_or(|w| min < w.min_angle_deg) {
                u.worst = Some(element);
            }
            if u.worst_ratio.is_none_or(|w| ratio < w.jacobian_ratio) {
                u.worst_ratio = Some(element);
            }
        }
        q.unforced = Some(u);
        q
    }

    /// The summary and each element's certified Jacobian ratio.
    fn measure(mesh: &FemMesh) -> (Quality, Vec<f64>) {
        let mut q = Quality::of_triangles((0..mesh.triangle_count()).map(|i| mesh.corners(i)));
        if mesh.triangle_count() == 0 {
            return (q, Vec::new());
        }
        let order = mesh.order();
        let opts = CertifyOptions::DEFAULT;
        let mut pts = Vec::with_capacity(order.triangle_nodes());
        let mut ratios = Vec::with_capacity(mesh.triangle_count());
        q.area = 0.0;
        q.min_jacobian_ratio = f64::INFINITY;
        for i in 0..mesh.triangle_count() {
            pts.clear();
            pts.extend(mesh.triangle(i).iter().map(|&v| mesh.nodes[v as usize]));
            let Some(det) = jacobian::det_lagrange(order, &pts) else {
                q.min_jacobian_ratio = f64::NEG_INFINITY;
                ratios.push(f64::NEG_INFINITY);
                continue;
            };
            q.area += jacobian::area(&det);
            let cert = jacobian::certify(&det, jacobian::zero_abs(&pts, opts.zero_rel), &opts);
            q.min_jacobian_ratio = q.min_jacobian_ratio.min(cert.ratio());
            ratios.push(cert.ratio());
        }
        (q, ratios)
    }

    /// Measure a set of straight triangles given by their corners
    /// (counter-clockwise); a straight triangle's Jacobian ratio is 1.
    pub fn of_triangles(triangles: impl IntoIterator<Item = [Point; 3]>) -> Quality {
        let mut n = 0usize;
        let mut q = Quality {
            min_angle_deg: f64::INFINITY,
            max_angle_deg: f64::NEG_INFINITY,
            max_amips: f64::NEG_INFINITY,
            mean_amips: 0.0,
            area: 0.0,
            min_jacobian_ratio: 1.0,
            unforced: None,
        };
        let mut amips_sum = 0.0;
        for corners in triangles {
            let t = TriangleQuality::of(corners);
            n += 1;
            q.min_angle_deg = q.min_angle_deg.min(t.min_angle_deg);
            q.max_angle_deg = q.max_angle_deg.max(t.max_angle_deg);
            q.max_amips = q.max_amips.max(t.amips);
            amips_sum += t.amips;
            q.area += t.area;
            // A straight triangle's det J is constant: its ratio is its sign.
            let ratio = if t.area > 0.0 {
                1.0
            } else if t.area < 0.0 {
                -1.0
            } else {
                0.0
            };
            q.min_jacobian_ratio = q.min_jacobian_ratio.min(ratio);
        }
        if n == 0 {
            return Quality::EMPTY;
        }
        q.mean_amips = amips_sum / n as f64;
        q
    }

    /// The quality of each triangle of `mesh`, in element order.
    pub fn per_triangle(mesh: &FemMesh) -> Vec<TriangleQuality> {
        (0..mesh.triangle_count())
            .map(|i| TriangleQuality::of(mesh.corners(i)))
            .collect()
    }
}

/// Quality of one straight triangle.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TriangleQuality {
    /// Smallest corner angle, degrees (0 for a degenerate triangle).
    pub min_angle_deg: f64,
    /// Largest corner angle, degrees.
    pub max_angle_deg: f64,
    /// 2D conformal AMIPS energy: 1 for equilateral, `+∞` when degenerate or clockwise.
    pub amips: f64,
    /// Signed area (positive when counter-clockwise).
    pub area: f64,
}

impl TriangleQuality {
    /// Measure the triangle `corners` (expected counter-clockwise).
    pub fn of(corners: [Point; 3]) -> TriangleQuality {
        let [a, b, c] = corners;
        let angles = corner_angles(corners);
        let min_angle_deg = angles
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .to_degrees();
        let max_angle_deg = angles.iter().copied().fold(0.0, f64::max).to_degrees();
        TriangleQuality {
            min_angle_deg,
            max_angle_deg,
            amips: amips(corners),
            area: 0.5 * (b - a).cross(c - a),
        }
    }
}

/// The 2D conformal AMIPS energy `tr(JᵀJ) / (2 det J)` of the affine map `J` taking the
/// equilateral reference triangle `(0,0), (1,0), (1/2, √3/2)` onto `corners`;
/// `+∞` when `det J ≤ 0` (degenerate or clockwise) or not finite.
pub(crate) fn amips(corners: [Point; 3]) -> f64 {
    // One definition of the energy for measuring and for optimizing.
    let [a, b, c] = corners;
    crate::element::energy::amips(a, b, c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::Order;
    use crate::fem::LinearMesh;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
    }

    #[test]
    fn equilateral_has_unit_energy_and_sixty_degrees() {
        let h = 3f64.sqrt() / 2.0;
        let t = TriangleQuality::of([
            Point::new(2.0, 1.0),
            Point::new(5.0, 1.0),
            Point::new(3.5, 1.0 + 3.0 * h),
        ]);
        assert!(close(t.amips, 1.0), "{t:?}");
        assert!(
            close(t.min_angle_deg, 60.0) && close(t.max_angle_deg, 60.0),
            "{t:?}"
        );
        assert!(close(t.area, 9.0 * h / 2.0), "{t:?}");
        // Rotated equilateral: still 1.
        let r = kurbo::Affine::rotate(0.7);
        let t = TriangleQuality::of([
            r * Point::ZERO,
            r * Point::new(1.0, 0.0),
            r * Point::new(0.5, h),
        ]);
        assert!(close(t.amips, 1.0), "{t:?}");
    }

    #[test]
    fn right_isoceles_known_values() {
        // Legs 1: (a² + b² + c²) / (4√3 A) = 4 / (2√3) = 2/√3.
        let t = TriangleQuality::of([Point::ZERO, Point::new(1.0, 0.0), Point::new(0.0, 1.0)]);
        assert!(close(t.amips, 2.0 / 3f64.sqrt()), "{t:?}");
        assert!(close(t.min_angle_deg, 45.0), "{t:?}");
        assert!(close(t.max_angle_deg, 90.0), "{t:?}");
        assert!(close(t.area, 0.5), "{t:?}");
        // Energy is invariant under scaling.
        let s = TriangleQuality::of([Point::ZERO, Point::new(1e-7, 0.0), Point::new(0.0, 1e-7)]);
        assert!(close(s.amips, t.amips), "{s:?}");
    }

    #[test]
    fn degenerate_and_clockwise_are_infinite() {
        let flat = TriangleQuality::of([Point::ZERO, Point::new(1.0, 0.0), Point::new(2.0, 0.0)]);
        assert_eq!(flat.amips, f64::INFINITY);
        assert_eq!(flat.min_angle_deg, 0.0);
        assert!(close(flat.max_angle_deg, 180.0), "{flat:?}");
        let point = TriangleQuality::of([Point::ZERO; 3]);
        assert_eq!(point.amips, f64::INFINITY);
        let cw = TriangleQuality::of([Point::ZERO, Point::new(0.0, 1.0), Point::new(1.0, 0.0)]);
        assert_eq!(cw.amips, f64::INFINITY);
        assert!(close(cw.area, -0.5), "{cw:?}");
    }

    #[test]
    fn summary_over_a_mesh() {
        let linear = LinearMesh {
            vertices: vec![
                Point::ZERO,
                Point::new(1.0, 0.0),
                Point::new(1.0, 1.0),
                Point::new(0.0, 1.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            edges: vec![],
        };
        let mesh = FemMesh::from_linear(&linear, "domain", |_| String::new());
        assert_eq!(mesh.order(), Order::Linear);
        let q = Quality::of(&mesh);
        assert!(
            close(q.min_angle_deg, 45.0) && close(q.max_angle_deg, 90.0),
            "{q:?}"
        );
        assert!(
            close(q.max_amips, 2.0 / 3f64.sqrt()) && close(q.mean_amips, 2.0 / 3f64.sqrt()),
            "{q:?}"
        );
        assert!(close(q.area, 1.0), "{q:?}");
        assert_eq!(Quality::per_triangle(&mesh).len(), 2);
    }

    #[test]
    fn forced_corners_are_left_out_of_the_unforced_summary() {
        // A sliver (corner 0 about 1.1°) beside a right triangle.
        let linear = LinearMesh {
            vertices: vec![
                Point::ZERO,
                Point::new(1.0, 0.0),
                Point::new(1.0, 0.02),
                Point::new(1.0, 1.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            edges: vec![],
        };
        let mesh = FemMesh::from_linear(&linear, "domain", |_| String::new());
        let none = Quality::of_classified(&mesh, &[], 10.0);
        let u = none.unforced.expect("classified");
        assert_eq!((u.forced_corners, u.corners, u.forced_elements), (0, 6, 0));
        assert!(close(u.min_angle_deg, none.min_angle_deg), "{u:?}");
        assert_eq!(u.below_alpha, 1);
        assert_eq!(u.worst.map(|w| w.element), Some(0));
        // Corner 0 of the sliver forced by a wedge: the sliver's other corners
        // still count, the element does not; the worst is the other one.
        let q = Quality::of_classified(&mesh, &[FORCED_BY_ANGLE], 10.0);
        let u = q.unforced.expect("classified");
        assert_eq!((u.forced_corners, u.forced_by_angle), (1, 1));
        assert_eq!((u.forced_elements, u.below_alpha), (1, 0));
        assert!(u.min_angle_deg > 10.0 && q.min_angle_deg < 2.0, "{q:?}");
        let w = u.worst.expect("an unforced element");
        assert_eq!(w.element, 1);
        assert!(close(w.x, 2.0 / 3.0) && close(w.y, 1.02 / 3.0), "{w:?}");
        assert!(close(w.jacobian_ratio, 1.0), "{w:?}");
        assert_eq!(Quality::of(&mesh).unforced, None);
    }

    #[test]
    fn curved_elements_count_with_their_exact_area_and_ratio() {
        // A quadratic triangle whose edge 0→1 bulges down to (0.5, -0.25): the
        // parabola adds 2/3 · 1 · 0.25 to the straight area 1/2 (not the
        // straight-sided area).
        let mesh = FemMesh {
            order: Some(Order::Quadratic),
            nodes: vec![
                Point::new(0.0, 0.0),
                Point::new(1.0, 0.0),
                Point::new(0.5, 1.0),
                Point::new(0.5, -0.25),
                Point::new(0.75, 0.5),
                Point::new(0.25, 0.5),
            ],
            triangles: (0..6).collect(),
            triangle_group: vec![0],
            surfaces: vec!["s".into()],
            ..FemMesh::default()
        };
        let q = Quality::of(&mesh);
        assert!(close(q.area, 0.5 + 1.0 / 6.0), "{q:?}");
        let check = crate::element::jacobian::certify_element(
            Order::Quadratic,
            &mesh.nodes,
            &CertifyOptions::DEFAULT,
        )
        .expect("six nodes");
        assert_eq!(q.min_jacobian_ratio, check.ratio());
        assert!(
            q.min_jacobian_ratio > 0.0 && q.min_jacobian_ratio < 1.0,
            "{q:?}"
        );
        // Straight: ratio 1.
        let mut straight = mesh.clone();
        straight.nodes[3] = Point::new(0.5, 0.0);
        assert_eq!(Quality::of(&straight).min_jacobian_ratio, 1.0);
        // The mid-edge node slid toward a corner: still straight and valid, but
        // det J along the edge runs from 0.08 to 1.92 of its mean.
        let mut slid = straight.clone();
        slid.nodes[3] = Point::new(0.27, 0.0);
        let u = Quality::of_classified(&slid, &[], 10.0)
            .unforced
            .expect("classified");
        assert!(
            u.min_jacobian_ratio > 0.0 && u.min_jacobian_ratio < RATIO_FLOOR,
            "{u:?}"
        );
        assert_eq!(u.below_ratio_floor, 1);
        let w = u.worst_ratio.expect("an unforced element");
        assert_eq!((w.element, w.jacobian_ratio), (0, u.min_jacobian_ratio));
        let u = Quality::of_classified(&straight, &[], 10.0)
            .unforced
            .expect("classified");
        assert_eq!(u.below_ratio_floor, 0);
    }

    #[test]
    fn empty_mesh_is_all_zero() {
        assert_eq!(Quality::of(&FemMesh::default()), Quality::EMPTY);
        assert!(Quality::per_triangle(&FemMesh::default()).is_empty());
    }
}
