//! `triwild._triwild`: the native half of the Python package `triwild`.
//!
//! Meshing goes through the library's public API with the command line's own
//! flag parser (`triwild::cli::mesh_options`), so a keyword argument means what
//! the flag of the same name means, with the same default. The mesh comes back
//! in the numbering of the .msh file the command line writes: it is written to
//! memory (MSH 2.2 binary: nodes in tag order) and read back with the library's
//! reader. Arrays cross as little-endian bytes; the Python layer wraps them in
//! numpy. The GIL is released while meshing, writing and checking, and a Rust
//! panic becomes a `triwild.Error`, never an abort. A size function (`size_fn`)
//! is called back in batches of points, with the GIL taken again for each call.

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::collections::HashMap;
use std::ffi::OsString;
use std::io::Write;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use triwild::{ErrorKind, FemMesh, MshOptions, MshVersion, SizeFn};

create_exception!(
    triwild,
    Error,
    PyException,
    "Base class of triwild's errors."
);
create_exception!(
    triwild,
    BadInput,
    Error,
    "The input is not a drawing triwild can mesh (missing, not SVG, no geometry, bad flag): exit code 2 of the command line."
);
create_exception!(
    triwild,
    MeshingError,
    Error,
    "Meshing failed: exit code 3 of the command line."
);
create_exception!(
    triwild,
    IoError,
    Error,
    "Reading the input or writing an output failed: exit code 4 of the command line."
);

/// The exception for a library error, with the command line's message
/// (`path: message` when a file is concerned, as `error: ` lines say).
fn to_py(err: &triwild::Error, file: Option<&Path>) -> PyErr {
    let msg = match file {
        Some(f) => format!("{}: {err}", f.display()),
        None => err.to_string(),
    };
    match err.kind() {
        ErrorKind::BadInput => BadInput::new_err(msg),
        ErrorKind::Meshing => MeshingError::new_err(msg),
        ErrorKind::Io => IoError::new_err(msg),
    }
}

/// Why a failure happened, before it becomes a Python exception (built
/// without the GIL).
enum Failure {
    /// A library error, and the file it is about.
    Lib(triwild::Error, Option<PathBuf>),
    /// A keyword argument the flag parser rejected.
    Flag(String),
    /// A panic inside the library: a bug, reported as such.
    Panic(String),
}

impl Failure {
    fn into_py(self) -> PyErr {
        match self {
            Failure::Lib(e, f) => to_py(&e, f.as_deref()),
            Failure::Flag(m) => BadInput::new_err(m),
            Failure::Panic(m) => Error::new_err(format!("internal error (a bug in triwild): {m}")),
        }
    }
}

/// Run `f`, turning a panic into a [`Failure::Panic`].
fn guarded<T>(f: impl FnOnce() -> Result<T, Failure>) -> Result<T, Failure> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".to_owned());
            Err(Failure::Panic(msg))
        }
    }
}

/// A mesh made by [`mesh`]: the library's mesh, its statistics and the arrays
/// of the .msh file the command line writes for it.
#[pyclass(frozen, module = "triwild._triwild")]
struct MeshData {
    mesh: FemMesh,
    stats: String,
    arrays: Arrays,
}

/// The mesh as the .msh file holds it.
struct Arrays {
    /// x, y per node, node `i` is the file's node tag `i + 1`.
    points: Vec<f64>,
    /// Node indices of the triangles, file order.
    triangles: Vec<i64>,
    /// Region (physical surface tag - 1) per triangle.
    region: Vec<i32>,
    /// The physical surface names, by tag - 1.
    region_names: Vec<String>,
    /// Node indices of the line elements, file order.
    lines: Vec<i64>,
    /// Physical curve tag - 1 per line.
    line_tags: Vec<i32>,
    /// Elementary curve (entity) tag per line: the pieces a physical curve is
    /// cut into at its corners.
    line_entity: Vec<i32>,
    /// The physical curve names, by tag - 1.
    line_names: Vec<String>,
}

fn le_bytes<T: Copy, const N: usize>(v: &[T], f: impl Fn(T) -> [u8; N]) -> Vec<u8> {
    v.iter().flat_map(|&x| f(x)).collect()
}

impl Arrays {
    /// Write `mesh` as the command line would (MSH 2.2 binary keeps nodes in
    /// tag order) and read it back with the library's reader.
    fn of(mesh: &FemMesh) -> Result<Arrays, Failure> {
        let mut buf = Vec::new();
        let opts = MshOptions {
            version: MshVersion::V22,
            binary: true,
        };
        triwild::write_msh_to(mesh, &mut buf, opts).map_err(|e| Failure::Lib(e, None))?;
        let msh = triwild::read_msh(&buf).map_err(|e| Failure::Lib(e, None))?;
        let names: HashMap<(i32, i32), &str> = msh
            .physical_names
            .iter()
            .map(|(d, t, n)| ((*d, *t), n.as_str()))
            .collect();
        let named = |dim: i32, raw: &[String]| -> Vec<String> {
            raw.iter()
                .enumerate()
                .map(|(i, n)| {
                    let tag = i32::try_from(i + 1).unwrap_or(i32::MAX);
                    names
                        .get(&(dim, tag))
                        .map_or_else(|| n.clone(), |s| (*s).to_owned())
                })
                .collect()
        };
        let mut a = Arrays {
            points: msh.nodes.iter().flat_map(|p| [p.x, p.y]).collect(),
            triangles: Vec::new(),
            region: Vec::new(),
            region_names: named(2, &mesh.surfaces),
            lines: Vec::new(),
            line_tags: Vec::new(),
            line_entity: Vec::new(),
            line_names: named(1, &mesh.curves),
        };
        for b in &msh.triangle_blocks {
            let per = b.order.triangle_nodes();
            a.triangles.extend(b.nodes.iter().map(|&v| i64::from(v)));
            let tag = b.physical.unwrap_or(0) - 1;
            a.region
                .extend(std::iter::repeat_n(tag, b.nodes.len() / per));
        }
        for b in &msh.line_blocks {
            a.lines.extend(b.nodes.iter().map(|&v| i64::from(v)));
            let n = b.lines().count();
            let tag = b.physical.unwrap_or(0) - 1;
            a.line_tags.extend(std::iter::repeat_n(tag, n));
            a.line_entity
                .extend(std::iter::repeat_n(b.entity.unwrap_or(0), n));
        }
        Ok(a)
    }
}

#[pymethods]
impl MeshData {
    /// The arrays as a dict of little-endian bytes, counts and names.
    fn arrays<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let a = &self.arrays;
        let d = PyDict::new(py);
        d.set_item(
            "points",
            PyBytes::new(py, &le_bytes(&a.points, f64::to_le_bytes)),
        )?;
        d.set_item(
            "triangles",
            PyBytes::new(py, &le_bytes(&a.triangles, i64::to_le_bytes)),
        )?;
        d.set_item(
            "region",
            PyBytes::new(py, &le_bytes(&a.region, i32::to_le_bytes)),
        )?;
        d.set_item("region_names", a.region_names.clone())?;
        d.set_item(
            "lines",
            PyBytes::new(py, &le_bytes(&a.lines, i64::to_le_bytes)),
        )?;
        d.set_item(
            "line_tags",
            PyBytes::new(py, &le_bytes(&a.line_tags, i32::to_le_bytes)),
        )?;
        d.set_item(
            "line_entity",
            PyBytes::new(py, &le_bytes(&a.line_entity, i32::to_le_bytes)),
        )?;
        d.set_item("line_names", a.line_names.clone())?;
        // (node, partner) of a periodic cell's sides, node indices of `points`
        let pairs = self
            .mesh
            .periodic
            .as_ref()
            .map_or(&[][..], |p| &p.pairs[..]);
        let flat: Vec<i64> = pairs
            .iter()
            .flat_map(|p| [i64::from(p.node), i64::from(p.master)])
            .collect();
        d.set_item(
            "periodic_pairs",
            PyBytes::new(py, &le_bytes(&flat, i64::to_le_bytes)),
        )?;
        let axis: Vec<u8> = pairs.iter().map(|p| p.axis).collect();
        d.set_item("periodic_axis", PyBytes::new(py, &axis))?;
        d.set_item("order", self.mesh.order() as u8)?;
        d.set_item("triangle_nodes", self.mesh.order().triangle_nodes())?;
        d.set_item("line_nodes", self.mesh.order().line_nodes())?;
        Ok(d)
    }

    /// The `--stats` JSON of the run.
    #[getter]
    fn stats(&self) -> &str {
        &self.stats
    }

    /// Write the mesh to `path` as the command line does (atomically).
    fn write(&self, py: Python<'_>, path: PathBuf, version: &str, binary: bool) -> PyResult<()> {
        let version = match version {
            "4.1" | "4" => MshVersion::V41,
            "2.2" | "2" => MshVersion::V22,
            other => {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "unknown .msh version {other:?}: use \"4.1\" or \"2.2\""
                )));
            }
        };
        let opts = MshOptions { version, binary };
        py.detach(|| {
            guarded(|| {
                triwild::write_msh(&self.mesh, &path, opts)
                    .map_err(|e| Failure::Lib(e, Some(path.clone())))
            })
        })
        .map_err(Failure::into_py)
    }

    /// Write the mesh to `path` as a VTK XML unstructured grid, as the
    /// command line's `--format vtu` does (atomically).
    fn write_vtu(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| {
            guarded(|| {
                triwild::write_vtu(&self.mesh, &path)
                    .map_err(|e| Failure::Lib(e, Some(path.clone())))
            })
        })
        .map_err(Failure::into_py)
    }
}

/// The first exception a size function raised, kept to become the cause of
/// the `triwild.Error` the failed run raises.
type Raised = Arc<Mutex<Option<PyErr>>>;

/// The library's size function over `call`, a Python callable taking a batch's
/// x and y as little-endian float64 bytes and returning the sizes the same way
/// (the package's wrapper around the user's `size_fn`). It runs while meshing,
/// without the GIL, so each call takes the GIL again. An exception becomes the
/// library's error message (one line) and is kept in `raised`.
fn size_function(call: Py<PyAny>, raised: Raised) -> SizeFn {
    SizeFn::new(move |xs: &[f64], ys: &[f64]| {
        Python::attach(|py| {
            let x = PyBytes::new(py, &le_bytes(xs, f64::to_le_bytes));
            let y = PyBytes::new(py, &le_bytes(ys, f64::to_le_bytes));
            let answer = call.call1(py, (x, y)).and_then(|h| {
                let h = h.bind(py).cast::<PyBytes>().map_err(PyErr::from)?;
                Ok(h.as_bytes()
                    .chunks_exact(8)
                    .map(|c| f64::from_le_bytes(c.try_into().expect("internal: 8 bytes")))
                    .collect::<Vec<f64>>())
            });
            answer.map_err(|e| {
                let msg = e.to_string().replace(['\r', '\n'], " ");
                let mut first = raised.lock().unwrap_or_else(|p| p.into_inner());
                first.get_or_insert(e);
                msg
            })
        })
    })
}

/// The background mesh of `size_from`: points (x, y float64), triangles (three
/// uint32 node indices each) and one float64 size per point, as little-endian
/// bytes.
fn background_mesh(points: &[u8], triangles: &[u8], h: &[u8]) -> triwild::BackgroundMesh {
    let f64s = |b: &[u8]| -> Vec<f64> {
        b.chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("internal: 8 bytes")))
            .collect()
    };
    let xy = f64s(points);
    triwild::BackgroundMesh {
        points: xy.chunks_exact(2).map(|p| [p[0], p[1]]).collect(),
        triangles: triangles
            .chunks_exact(12)
            .map(|t| {
                let n = |k: usize| {
                    u32::from_le_bytes(t[k..k + 4].try_into().expect("internal: 4 bytes"))
                };
                [n(0), n(4), n(8)]
            })
            .collect(),
        h: f64s(h),
    }
}

/// Mesh the SVG file `path` or the SVG document `data` with the single-file
/// command's `flags` (`--edge-length 0.05`, …) and, if given, the size
/// function `size_fn` (see [`size_function`]) and the background mesh
/// `size_from` (see [`background_mesh`]).
#[pyfunction]
#[pyo3(signature = (path, data, flags, size_fn=None, size_from=None))]
fn mesh(
    py: Python<'_>,
    path: Option<PathBuf>,
    data: Option<&Bound<'_, PyBytes>>,
    flags: Vec<String>,
    size_fn: Option<Py<PyAny>>,
    size_from: Option<(Vec<u8>, Vec<u8>, Vec<u8>)>,
) -> PyResult<MeshData> {
    let data: Option<Vec<u8>> = data.map(|b| b.as_bytes().to_vec());
    let raised = Raised::default();
    let function = size_fn.map(|f| size_function(f, Arc::clone(&raised)));
    let background = size_from.map(|(p, t, h)| background_mesh(&p, &t, &h));
    let result = py.detach(move || {
        guarded(|| {
            let t0 = Instant::now();
            let (mut params, regions, paint) =
                triwild::cli::mesh_options(flags.into_iter().map(OsString::from))
                    .map_err(Failure::Flag)?;
            if let Some(f) = function {
                let size = params.size.clone().with_function(f);
                params = params.with_size(size);
            }
            if let Some(m) = background {
                let size = params.size.clone().with_background_mesh(m);
                params = params.with_size(size);
            }
            let opts = triwild::LoadOptions::from_params(&params)
                .map_err(|e| Failure::Lib(e, None))?
                .with_paint(paint);
            let drawing = match (&path, &data) {
                (Some(p), _) => triwild::load_file(p, &opts),
                (None, Some(d)) => triwild::load_bytes(d, &opts),
                (None, None) => return Err(Failure::Flag("no SVG given".to_owned())),
            }
            .map_err(|e| Failure::Lib(e, path.clone()))?;
            let t_load = t0.elapsed().as_secs_f64();
            let mut meshed = triwild::mesh_drawing(&drawing, &params, &regions)
                .map_err(|e| Failure::Lib(e, path.clone()))?;
            let arrays = Arrays::of(&meshed.mesh)?;
            meshed.report.times.insert("load", t_load);
            meshed
                .report
                .times
                .insert("total", t0.elapsed().as_secs_f64());
            let stats = serde_json::to_string(&meshed.report)
                .map_err(|e| Failure::Panic(format!("cannot format statistics: {e}")))?;
            Ok(MeshData {
                mesh: meshed.mesh,
                stats,
                arrays,
            })
        })
    });
    result.map_err(|failure| {
        let err = failure.into_py();
        // the size function's exception, as the cause of the error it led to
        let cause = raised.lock().unwrap_or_else(|p| p.into_inner()).take();
        if let Some(cause) = cause {
            err.set_cause(py, Some(cause));
        }
        err
    })
}

/// The long names of the flags `mesh` takes.
#[pyfunction]
fn mesh_flags() -> Vec<String> {
    triwild::cli::mesh_option_names()
}

/// `triwild check`'s verdict on the .msh file at `path`, as JSON.
#[pyfunction]
fn check(py: Python<'_>, path: PathBuf) -> PyResult<String> {
    py.detach(|| {
        guarded(|| {
            let mesh =
                triwild::read_msh_file(&path).map_err(|e| Failure::Lib(e, Some(path.clone())))?;
            let r = triwild::check_msh(&mesh, &triwild::CertifyOptions::DEFAULT);
            serde_json::to_string(&r)
                .map_err(|e| Failure::Panic(format!("cannot format the check: {e}")))
        })
    })
    .map_err(Failure::into_py)
}

/// Run the command line on `argv` (program name first); `triwild batch` runs
/// `child` (a program and its leading arguments) once per file. Returns the
/// exit code.
#[pyfunction]
fn cli(py: Python<'_>, argv: Vec<OsString>, child: Vec<OsString>) -> u8 {
    py.detach(|| {
        let code = triwild::cli::main_with(argv, Some(&child));
        let _ = std::io::stdout().flush();
        code
    })
}

/// The native module of the `triwild` package.
#[pymodule]
fn _triwild(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    // this module's own panic hook (each extension has its own std): quiet
    // about the spade panics the cdt mesher catches, as the command line is
    triwild::cli::install_panic_hook();
    m.add("Error", py.get_type::<Error>())?;
    m.add("BadInput", py.get_type::<BadInput>())?;
    m.add("MeshingError", py.get_type::<MeshingError>())?;
    m.add("IoError", py.get_type::<IoError>())?;
    m.add_class::<MeshData>()?;
    m.add_function(wrap_pyfunction!(mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_flags, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(cli, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
