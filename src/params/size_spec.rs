//! What the size field is made of (the `sizing` stage builds it): the inputs a
//! user gives beside the global edge length `l`, as gmsh's mesh size fields and
//! Triangle's area constraints offer them. Pure data and range checks; names and
//! files are resolved against the drawing when the field is built.

use super::{Length, defaults};
use crate::{Error, Result};
use std::path::PathBuf;
use std::sync::Arc;

/// `h ≤ size` inside one region (`--size NAME=L`): a region as the .msh names
/// it (a shape's id, `shape-N`, `fill-#rrggbb` under `--regions colour`,
/// `background`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RegionSize {
    /// The region's name.
    pub name: String,
    /// The largest size inside it.
    pub size: Length,
}

/// `h = size` on a region's outline, growing linearly to the ambient size over
/// `distance` (`--size-near NAME=L[:DIST]`; gmsh's Distance + Threshold). Without a
/// distance the size grows at the field's grading.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct NearSize {
    /// The region whose outline it follows.
    pub name: String,
    /// The size on the outline.
    pub size: Length,
    /// Over how far the size grows back to the ambient size (`None`: the grading).
    pub distance: Option<Length>,
}

/// `h ≤ size` inside an axis-parallel box in output coordinates
/// (`--size-box X0,Y0,X1,Y1=L`; gmsh's Box field).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BoxSize {
    /// Corners `[x0, y0, x1, y1]`, output coordinates (any order).
    pub corners: [f64; 4],
    /// The largest size inside it.
    pub size: Length,
}

/// The signature of a size function: `h` at a batch of points (output
/// coordinates `xs[i]`, `ys[i]`), or a message saying why not.
pub type SizeFnSignature =
    dyn Fn(&[f64], &[f64]) -> std::result::Result<Vec<f64>, String> + Send + Sync;

/// A size given by the caller's code (the Python package's `size_fn`), called in
/// batches of points. Values are absolute lengths in output units.
#[derive(Clone)]
pub struct SizeFn(pub Arc<SizeFnSignature>);

impl SizeFn {
    /// Wrap a function of batches of points.
    pub fn new(
        f: impl Fn(&[f64], &[f64]) -> std::result::Result<Vec<f64>, String> + Send + Sync + 'static,
    ) -> Self {
        SizeFn(Arc::new(f))
    }
}

impl std::fmt::Debug for SizeFn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("SizeFn(..)")
    }
}

impl PartialEq for SizeFn {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl serde::Serialize for SizeFn {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str("function")
    }
}

/// A background mesh held in memory (the Python package's `size_from`): the
/// field of `--size-from` without a file. Node `i` is at `points[i]` with size
/// `h[i]` (absolute, output units); `triangles` index `points`; the size is
/// interpolated linearly over each triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct BackgroundMesh {
    /// Node coordinates (output coordinates, y up).
    pub points: Vec<[f64; 2]>,
    /// Triangles as three node indices each.
    pub triangles: Vec<[u32; 3]>,
    /// The size at each node.
    pub h: Vec<f64>,
}

impl serde::Serialize for BackgroundMesh {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&format!(
            "{} nodes, {} triangles",
            self.points.len(),
            self.triangles.len()
        ))
    }
}

/// `SizeSpec::background_mesh` in the report: its counts.
fn serialize_background_mesh<S: serde::Serializer>(
    mesh: &Option<Arc<BackgroundMesh>>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    match mesh {
        Some(m) => serde::Serialize::serialize(m.as_ref(), s),
        None => s.serialize_none(),
    }
}

/// The inputs of the size field h(x): every field is a bound on the size, they
/// combine by minimum with the global `l` (the largest size), are clamped to
/// `[l_min, l]` and graded so that h grows by at most [`SizeSpec::grading`] from
/// one element to the next. Lengths follow [`Length`]: relative to `d` or
/// absolute in output units.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[non_exhaustive]
pub struct SizeSpec {
    /// `--size NAME=L`.
    pub regions: Vec<RegionSize>,
    /// `--size-near NAME=L[:DIST]`.
    pub near: Vec<NearSize>,
    /// `--size-box X0,Y0,X1,Y1=L`.
    pub boxes: Vec<BoxSize>,
    /// `--size-expr EXPR`: h as a formula in `x` and `y` (output coordinates),
    /// absolute output units.
    pub expr: Option<String>,
    /// `--size-from FILE.msh`: a triangle mesh with one `$NodeData` value per
    /// node (what gmsh writes for a view), interpolated linearly; absolute output units.
    pub background: Option<PathBuf>,
    /// A background mesh in memory (the Python package's `size_from`),
    /// interpolated as `background` is; absolute output units.
    #[serde(
        skip_serializing_if = "Option::is_none",
        serialize_with = "serialize_background_mesh"
    )]
    pub background_mesh: Option<Arc<BackgroundMesh>>,
    /// A size function (the Python package's `size_fn`); absolute output units.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub function: Option<SizeFn>,
    /// The automatic local feature size: narrow gaps and thin parts get
    /// elements that fit them. Default [`defaults::FEATURE_SIZE`].
    pub feature_size: bool,
    /// Largest growth of the size from one element to the next (≥ 1). Default
    /// [`defaults::GRADING`].
    pub grading: f64,
}

impl SizeSpec {
    /// No field beside `l`; the automatic feature size and grading at their defaults.
    pub const DEFAULT: SizeSpec = SizeSpec {
        regions: Vec::new(),
        near: Vec::new(),
        boxes: Vec::new(),
        expr: None,
        background: None,
        background_mesh: None,
        function: None,
        feature_size: defaults::FEATURE_SIZE,
        grading: defaults::GRADING,
    };

    /// Add a per-region size.
    pub fn with_region(mut self, name: impl Into<String>, size: Length) -> Self {
        self.regions.push(RegionSize {
            name: name.into(),
            size,
        });
        self
    }
    /// Add a size near a region's outline.
    pub fn with_near(
        mut self,
        name: impl Into<String>,
        size: Length,
        distance: Option<Length>,
    ) -> Self {
        self.near.push(NearSize {
            name: name.into(),
            size,
            distance,
        });
        self
    }
    /// Add a box.
    pub fn with_box(mut self, corners: [f64; 4], size: Length) -> Self {
        self.boxes.push(BoxSize { corners, size });
        self
    }
    /// Set the formula.
    pub fn with_expr(mut self, expr: impl Into<String>) -> Self {
        self.expr = Some(expr.into());
        self
    }
    /// Set the background mesh file.
    pub fn with_background(mut self, path: impl Into<PathBuf>) -> Self {
        self.background = Some(path.into());
        self
    }
    /// Set the background mesh held in memory.
    pub fn with_background_mesh(mut self, mesh: BackgroundMesh) -> Self {
        self.background_mesh = Some(Arc::new(mesh));
        self
    }
    /// Set the size function.
    pub fn with_function(mut self, f: SizeFn) -> Self {
        self.function = Some(f);
        self
    }
    /// Turn the automatic feature size on or off.
    pub fn with_feature_size(mut self, on: bool) -> Self {
        self.feature_size = on;
        self
    }
    /// Set the grading.
    pub fn with_grading(mut self, grading: f64) -> Self {
        self.grading = grading;
        self
    }

    /// Whether any field beside `l` and the automatic ones is given.
    pub fn has_user_fields(&self) -> bool {
        !(self.regions.is_empty()
            && self.near.is_empty()
            && self.boxes.is_empty()
            && self.expr.is_none()
            && self.background.is_none()
            && self.background_mesh.is_none()
            && self.function.is_none())
    }

    /// Check the ranges (names, formulas and files are checked against the
    /// drawing when the field is built).
    ///
    /// # Errors
    /// [`Error::InvalidParams`] naming the first bad value.
    pub fn validate(&self) -> Result<()> {
        let positive = |what: String, len: Length| {
            let v = len.value();
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::InvalidParams(format!(
                    "{what}: the size must be a positive finite number, got {v}"
                )))
            }
        };
        for r in &self.regions {
            positive(format!("--size {}", r.name), r.size)?;
        }
        for n in &self.near {
            positive(format!("--size-near {}", n.name), n.size)?;
            if let Some(dist) = n.distance {
                positive(format!("--size-near {} (distance)", n.name), dist)?;
            }
        }
        for b in &self.boxes {
            let [x0, y0, x1, y1] = b.corners;
            // (`{:?}`: a huge corner as written, 1e300, not as 301 digits)
            positive(format!("--size-box {x0:?},{y0:?},{x1:?},{y1:?}"), b.size)?;
            if !b.corners.iter().all(|c| c.is_finite()) || x0 == x1 || y0 == y1 {
                return Err(Error::InvalidParams(format!(
                    "--size-box {x0:?},{y0:?},{x1:?},{y1:?}: the corners must be finite and span a box"
                )));
            }
        }
        if !(self.grading.is_finite() && self.grading >= 1.0) {
            return Err(Error::InvalidParams(format!(
                "--grading must be a finite number of at least 1 (the size may grow by this \
                 factor per element), got {}",
                self.grading
            )));
        }
        Ok(())
    }
}

impl Default for SizeSpec {
    fn default() -> Self {
        SizeSpec::DEFAULT
    }
}
