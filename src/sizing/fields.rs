//! The fields given pointwise: per-region sizes inside their regions, boxes,
//! the formula (`--size-expr`, parsed by exmex), the background mesh
//! (`--size-from`) and the caller's function, evaluated at batches of points
//! (`∞` where none sets a size).

use super::FieldInput;
use crate::svg::winding::Painting;
use crate::{Error, Result};
use exmex::prelude::*;
use kurbo::{Point, Rect};

/// The bucket of coordinate `x` on an axis from `lo` of width `w` in `n` buckets.
fn cell(x: f64, lo: f64, w: f64, n: usize) -> usize {
    (((x - lo) / w.max(f64::MIN_POSITIVE) * n as f64)
        .floor()
        .max(0.0) as usize)
        .min(n - 1)
}

/// A triangle mesh with one value per node, located through a bucket grid.
pub(super) struct Background {
    nodes: Vec<Point>,
    values: Vec<f64>,
    triangles: Vec<[u32; 3]>,
    grid: Rect,
    nx: usize,
    ny: usize,
    buckets: Vec<Vec<u32>>,
}

impl Background {
    /// Read `path`: a gmsh triangle mesh (2.2 or 4.1, any order: its corners
    /// are used) with one `$NodeData` value per node.
    pub(super) fn read(path: &std::path::Path) -> Result<Background> {
        let what = |e: String| Error::InvalidParams(format!("--size-from {}: {e}", path.display()));
        let mesh = crate::input::msh::read_msh_file(path).map_err(|e| what(e.to_string()))?;
        let data = mesh.node_data.first().ok_or_else(|| {
            what("no $NodeData section (write a view, e.g. gmsh.view.write)".into())
        })?;
        let mut values = vec![f64::NAN; mesh.nodes.len()];
        for &(node, v) in &data.values {
            if let Some(slot) = values.get_mut(node as usize) {
                *slot = v;
            }
        }
        let triangles: Vec<[u32; 3]> = mesh
            .triangles()
            .map(|(_, nodes)| [nodes[0], nodes[1], nodes[2]])
            .collect();
        if triangles.is_empty() {
            return Err(what("no triangles".into()));
        }
        for t in &triangles {
            for &n in t {
                let v = values[n as usize];
                if !(v.is_finite() && v > 0.0) {
                    let p = mesh.nodes[n as usize];
                    return Err(what(format!(
                        "the size at node ({}, {}) is {v}, not a positive finite number",
                        p.x, p.y
                    )));
                }
            }
        }
        Ok(Background::new(mesh.nodes, values, triangles))
    }

    /// The mesh the caller holds in memory (`size_from`): its indices in
    /// range and a positive finite size at every node a triangle uses.
    pub(super) fn from_memory(m: &crate::params::BackgroundMesh) -> Result<Background> {
        let what = |e: String| Error::InvalidParams(format!("size_from: {e}"));
        if m.h.len() != m.points.len() {
            return Err(what(format!(
                "{} sizes for {} points (one per point)",
                m.h.len(),
                m.points.len()
            )));
        }
        if m.triangles.is_empty() {
            return Err(what("no triangles".into()));
        }
        for t in &m.triangles {
            for &n in t {
                let Some(&v) = m.h.get(n as usize) else {
                    return Err(what(format!(
                        "a triangle uses point {n}, but there are {} points",
                        m.points.len()
                    )));
                };
                let [x, y] = m.points[n as usize];
                if !(x.is_finite() && y.is_finite()) {
                    return Err(what(format!("point {n} is ({x}, {y}), not finite")));
                }
                if !(v.is_finite() && v > 0.0) {
                    return Err(what(format!(
                        "the size at point {n} ({x}, {y}) is {v}, not a positive finite number"
                    )));
                }
            }
        }
        let nodes = m.points.iter().map(|&[x, y]| Point::new(x, y)).collect();
        Ok(Background::new(nodes, m.h.clone(), m.triangles.clone()))
    }

    fn new(nodes: Vec<Point>, values: Vec<f64>, triangles: Vec<[u32; 3]>) -> Background {
        let tri_box = |t: &[u32; 3]| {
            let [a, b, c] = t.map(|i| nodes[i as usize]);
            Rect::from_points(a, b).union_pt(c)
        };
        let grid = triangles
            .iter()
            .map(tri_box)
            .reduce(|a, b| a.union(b))
            .unwrap_or_default();
        let side = (triangles.len() as f64).sqrt().ceil().clamp(1.0, 1024.0) as usize;
        let (nx, ny) = (side, side);
        let mut buckets = vec![Vec::new(); nx * ny];
        for (k, t) in triangles.iter().enumerate() {
            let b = tri_box(t);
            let (i0, i1) = (
                cell(b.x0, grid.x0, grid.width(), nx),
                cell(b.x1, grid.x0, grid.width(), nx),
            );
            let (j0, j1) = (
                cell(b.y0, grid.y0, grid.height(), ny),
                cell(b.y1, grid.y0, grid.height(), ny),
            );
            for j in j0..=j1 {
                for i in i0..=i1 {
                    buckets[j * nx + i].push(k as u32);
                }
            }
        }
        Background {
            nodes,
            values,
            triangles,
            grid,
            nx,
            ny,
            buckets,
        }
    }

    /// The interpolated value at `p`, `None` outside the mesh.
    pub(super) fn at(&self, p: Point) -> Option<f64> {
        let slack = 1e-9 * self.grid.width().hypot(self.grid.height());
        if !self.grid.inflate(slack, slack).contains(p) {
            return None;
        }
        let i = cell(p.x, self.grid.x0, self.grid.width(), self.nx);
        let j = cell(p.y, self.grid.y0, self.grid.height(), self.ny);
        let tol = 1e-9;
        for &k in &self.buckets[j * self.nx + i] {
            let t = self.triangles[k as usize];
            let [a, b, c] = t.map(|n| self.nodes[n as usize]);
            let det = (b - a).cross(c - a);
            if det == 0.0 {
                continue;
            }
            let l1 = (b - p).cross(c - p) / det;
            let l2 = (c - p).cross(a - p) / det;
            let l3 = 1.0 - l1 - l2;
            if l1 >= -tol && l2 >= -tol && l3 >= -tol {
                let [va, vb, vc] = t.map(|n| self.values[n as usize]);
                return Some(l1 * va + l2 * vb + l3 * vc);
            }
        }
        None
    }
}

/// exmex's number literals with an exponent too (`1e-3`, `2.5E+2`): its own
/// matcher takes digits and one dot only, so `1e-3` read as `1`, a variable
/// `e`, `-` and `3`, and failed with the parser's internal message.
#[derive(Clone, Debug)]
struct Number;

impl exmex::MatchLiteral for Number {
    fn is_literal(text: &str) -> Option<&str> {
        let b = text.as_bytes();
        let digits = |from: usize| b[from..].iter().take_while(|c| c.is_ascii_digit()).count();
        let whole = digits(0);
        let mut end = whole;
        let mut n_digits = whole;
        if b.get(end) == Some(&b'.') {
            let frac = digits(end + 1);
            end += 1 + frac;
            n_digits += frac;
        }
        if n_digits == 0 {
            return None;
        }
        if matches!(b.get(end), Some(b'e' | b'E')) {
            let sign = usize::from(matches!(b.get(end + 1), Some(b'+' | b'-')));
            let exp = digits(end + 1 + sign);
            if exp > 0 {
                end += 1 + sign + exp;
            }
        }
        Some(&text[..end])
    }
}

/// A parsed formula in `x` and `y`.
struct Formula {
    text: String,
    expr: FlatEx<f64, exmex::FloatOpsFactory<f64>, Number>,
    /// For each of the formula's variables (alphabetical): 0 for x, 1 for y.
    vars: Vec<usize>,
}

impl Formula {
    fn parse(text: &str) -> Result<Formula> {
        let bad = |why: String| Error::InvalidParams(format!("--size-expr '{text}': {why}"));
        let expr =
            FlatEx::<f64, exmex::FloatOpsFactory<f64>, Number>::parse(text).map_err(|e| {
                let why = e.to_string();
                // exmex's words for two operands in a row are about its internals
                bad(if why.contains("one more node than op") {
                    "an operator is missing between two values (write 2*x, not 2x)".to_owned()
                } else {
                    why
                })
            })?;
        let vars = expr
            .var_names()
            .iter()
            .map(|v| match v.as_str() {
                "x" => Ok(0),
                "y" => Ok(1),
                other => Err(bad(format!(
                    "unknown variable '{other}' (the formula may use x and y, output coordinates)"
                ))),
            })
            .collect::<Result<Vec<usize>>>()?;
        Ok(Formula {
            text: text.to_owned(),
            expr,
            vars,
        })
    }

    fn at(&self, p: Point) -> Result<f64> {
        let xy = [p.x, p.y];
        let args: Vec<f64> = self.vars.iter().map(|&i| xy[i]).collect();
        let v = self.expr.eval(&args).map_err(|e| {
            Error::InvalidParams(format!(
                "--size-expr '{}' at ({}, {}): {e}",
                self.text, p.x, p.y
            ))
        })?;
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(Error::InvalidParams(format!(
                "--size-expr '{}' at ({}, {}) is {v}, not a positive finite size",
                self.text, p.x, p.y
            )))
        }
    }
}

/// The pointwise fields of one run.
pub(super) struct PointFields<'a> {
    /// `(box, size)`.
    boxes: Vec<(Rect, f64)>,
    /// Per shape: the size its region asks for inside it (`∞`: none).
    region_size: Vec<f64>,
    /// The background's size (`∞`: none).
    background_size: f64,
    painting: Option<Painting>,
    /// How near an outline a point may be and still be inside (eps_m).
    eps: f64,
    formula: Option<Formula>,
    /// The background meshes, each with the name its errors give
    /// (`--size-from`, `size_from`).
    meshes: Vec<(Background, &'static str)>,
    /// Where the background mesh must cover: the drawing's extent.
    extent: Rect,
    function: Option<&'a crate::params::SizeFn>,
}

impl<'a> PointFields<'a> {
    pub(super) fn new(input: &FieldInput<'a>) -> Result<PointFields<'a>> {
        let spec = input.spec;
        let d = input.resolved.d;
        let boxes = spec
            .boxes
            .iter()
            .map(|b| {
                let [x0, y0, x1, y1] = b.corners;
                (Rect::new(x0, y0, x1, y1).abs(), b.size.resolve(d))
            })
            .collect();
        let mut region_size = vec![f64::INFINITY; input.drawing.shapes.len()];
        let mut background_size = f64::INFINITY;
        for r in &spec.regions {
            let size = r.size.resolve(d);
            let shapes = super::sources::shapes_named(input, &r.name, "--size")?;
            if r.name == super::sources::BACKGROUND {
                background_size = background_size.min(size);
            }
            for s in shapes {
                region_size[s.index()] = region_size[s.index()].min(size);
            }
        }
        let painting = (!spec.regions.is_empty()).then(|| Painting::new(input.drawing));
        let eps = input.resolved.eps_m;
        let formula = spec.expr.as_deref().map(Formula::parse).transpose()?;
        let mut meshes = Vec::new();
        if let Some(path) = spec.background.as_deref() {
            meshes.push((Background::read(path)?, "--size-from"));
        }
        if let Some(m) = spec.background_mesh.as_deref() {
            meshes.push((Background::from_memory(m)?, "size_from"));
        }
        Ok(PointFields {
            boxes,
            region_size,
            background_size,
            painting,
            eps,
            formula,
            meshes,
            extent: input.drawing.extent(),
            function: spec.function.as_ref(),
        })
    }

    /// The names of the fields given, for the report.
    pub(super) fn names(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.painting.is_some() {
            out.push("size".into());
        }
        if !self.boxes.is_empty() {
            out.push("size-box".into());
        }
        if self.formula.is_some() {
            out.push("size-expr".into());
        }
        if !self.meshes.is_empty() {
            out.push("size-from".into());
        }
        if self.function.is_some() {
            out.push("size-fn".into());
        }
        out
    }

    /// The sizes at `pts` (`∞` where no field sets one).
    pub(super) fn eval(&mut self, pts: &[Point]) -> Result<Vec<f64>> {
        let mut out = vec![f64::INFINITY; pts.len()];
        for (h, &p) in out.iter_mut().zip(pts) {
            for &(b, size) in &self.boxes {
                if b.contains(p) {
                    *h = h.min(size);
                }
            }
            if let Some(painting) = &self.painting {
                let size = match painting.owner_at(p, self.eps).0 {
                    Some(s) => self.region_size[s.index()],
                    None => self.background_size,
                };
                *h = h.min(size);
            }
            if let Some(f) = &self.formula {
                *h = h.min(f.at(p)?);
            }
            for (m, name) in &self.meshes {
                match m.at(p) {
                    Some(v) => *h = h.min(v),
                    None if self.extent.contains(p) => {
                        return Err(Error::InvalidParams(format!(
                            "{name}: the background mesh does not cover the drawing: \
                             no triangle holds ({}, {})",
                            p.x, p.y
                        )));
                    }
                    None => {}
                }
            }
        }
        if let Some(f) = self.function {
            let xs: Vec<f64> = pts.iter().map(|p| p.x).collect();
            let ys: Vec<f64> = pts.iter().map(|p| p.y).collect();
            // The function answers for a whole batch: a failure of the batch
            // names its first point (a value's failure names its own point).
            let batch = || match pts.first() {
                Some(p) => format!(
                    "a batch of {} points (the first at ({}, {}))",
                    pts.len(),
                    p.x,
                    p.y
                ),
                None => "no points".to_owned(),
            };
            let vals = (f.0)(&xs, &ys).map_err(|e| {
                Error::InvalidParams(format!("the size function failed on {}: {e}", batch()))
            })?;
            if vals.len() != pts.len() {
                return Err(Error::InvalidParams(format!(
                    "the size function returned {} values for {}",
                    vals.len(),
                    batch()
                )));
            }
            for ((h, v), p) in out.iter_mut().zip(vals).zip(pts) {
                if !(v.is_finite() && v > 0.0) {
                    return Err(Error::InvalidParams(format!(
                        "the size function gave {v} at ({}, {}), not a positive finite size",
                        p.x, p.y
                    )));
                }
                *h = h.min(v);
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use exmex::MatchLiteral;

    #[test]
    fn a_formula_reads_x_and_y_and_refuses_other_names() {
        let f = Formula::parse("0.5 + 0.05*x + 0*y").unwrap();
        assert!((f.at(Point::new(10.0, 3.0)).unwrap() - 1.0).abs() < 1e-12);
        let only_y = Formula::parse("1 + y").unwrap();
        assert_eq!(only_y.at(Point::new(7.0, 2.0)).unwrap(), 3.0);
        assert!(Formula::parse("0.5 + z").is_err());
        assert!(Formula::parse("0.5 +* x").is_err());
        let e = Formula::parse("x - 1").unwrap().at(Point::new(0.5, 0.0));
        let msg = e.unwrap_err().to_string();
        assert!(msg.contains("(0.5, 0)"), "{msg}");
    }

    /// Numbers with an exponent, as gmsh's MathEval and every language read
    /// them; two values in a row are refused in the user's words.
    #[test]
    fn a_formula_reads_numbers_with_an_exponent() {
        let at = |text: &str| {
            Formula::parse(text)
                .unwrap()
                .at(Point::new(2.0, 0.0))
                .unwrap()
        };
        assert_eq!(at("1e-3"), 1e-3);
        assert_eq!(at("2.5E+1"), 25.0);
        assert_eq!(at(".5e1 + 0*x"), 5.0);
        assert_eq!(at("5."), 5.0);
        assert_eq!(at("1e1*x"), 20.0);
        assert_eq!(at("x^1e0"), 2.0);
        // `e` alone is exmex's constant, not an exponent
        assert!((at("2*e") - 2.0 * std::f64::consts::E).abs() < 1e-12);
        for bad in ["2e", "1e+", "2x"] {
            let msg = Formula::parse(bad)
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            assert!(msg.contains(&format!("'{bad}'")), "{bad}: {msg}");
            assert!(!msg.contains("node"), "{bad}: {msg}");
        }
        assert_eq!(Number::is_literal("1e-3*x"), Some("1e-3"));
        assert_eq!(Number::is_literal("12.5e"), Some("12.5"));
        assert_eq!(Number::is_literal(".e1"), None);
        assert_eq!(Number::is_literal("x"), None);
    }

    #[test]
    fn a_background_mesh_interpolates_linearly_and_knows_its_cover() {
        let nodes = vec![
            Point::new(0.0, 0.0),
            Point::new(2.0, 0.0),
            Point::new(2.0, 2.0),
            Point::new(0.0, 2.0),
        ];
        let values = vec![1.0, 3.0, 5.0, 3.0]; // 1 + x + y
        let bg = Background::new(nodes, values, vec![[0, 1, 2], [0, 2, 3]]);
        for p in [(0.5, 0.25), (1.5, 1.0), (0.2, 1.9), (2.0, 2.0)] {
            let p = Point::new(p.0, p.1);
            assert!((bg.at(p).unwrap() - (1.0 + p.x + p.y)).abs() < 1e-12);
        }
        assert_eq!(bg.at(Point::new(2.5, 1.0)), None);
    }

    #[test]
    fn a_background_mesh_in_memory_is_checked_then_interpolated() {
        let mesh = |h: Vec<f64>, t: [u32; 3]| crate::params::BackgroundMesh {
            points: vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]],
            triangles: vec![[0, 1, 2], t],
            h,
        };
        let bg = Background::from_memory(&mesh(vec![1.0, 3.0, 5.0, 3.0], [0, 2, 3])).unwrap();
        assert!((bg.at(Point::new(0.5, 1.5)).unwrap() - 3.0).abs() < 1e-12);
        let err = |m| Background::from_memory(&m).err().unwrap().to_string();
        assert!(err(mesh(vec![1.0; 3], [0, 2, 3])).contains("3 sizes for 4 points"));
        assert!(err(mesh(vec![1.0; 4], [0, 2, 4])).contains("point 4"));
        let zero = err(mesh(vec![1.0, 1.0, 1.0, 0.0], [0, 2, 3]));
        assert!(zero.contains("size_from: the size at point 3"), "{zero}");
    }
}
