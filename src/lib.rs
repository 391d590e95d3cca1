//! # triwild
//!
//! Robust curved triangle meshing of SVG drawings "from the wild", after TriWild
//! (Hu et al., SIGGRAPH 2019): gaps, self-intersections, open and degenerate curves
//! are all accepted, and every drawing gets a valid mesh or a clear error.
//!
//! ```text
//! SVG ──svg──▶ Drawing ──features──▶ FeatureSet ──bsp──▶ TriMesh ──optimize──▶ TriMesh
//!                 │                                                              │
//!                 └──────baseline (spade CDT)──────▶ LinearMesh ◀────────────────┘
//!                                                        │
//!                                  regions / curve ──▶ FemMesh ──output──▶ .msh, preview
//! ```
//!
//! ```no_run
//! use triwild::{pipeline, Params};
//! let opts = pipeline::RunOptions::new(Params::DEFAULT);
//! let report = pipeline::run_file("drawing.svg".as_ref(), "drawing.msh".as_ref(), &opts)?;
//! println!("{} triangles", report.output.triangles);
//! # Ok::<(), triwild::Error>(())
//! ```

pub mod baseline;
pub mod batch;
pub mod bsp;
pub mod curve;
pub mod element;
pub mod error;
pub mod exact;
pub mod features;
pub mod fem;
pub mod input;
pub mod mesh;
pub mod ops;
pub mod optimize;
pub mod output;
pub mod params;
pub mod pipeline;
pub mod quality;
pub mod regions;
pub mod svg;

pub use error::{Error, ErrorKind, Result};
pub use fem::{FemMesh, LinearMesh};
pub use params::{Length, Mesher, Params, Stage};
pub use svg::Drawing;
