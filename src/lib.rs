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
//! Mesh a drawing held in memory and get the gmsh file's bytes:
//!
//! ```
//! use triwild::{Length, MshOptions, Order, Params};
//!
//! let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="100" height="100">
//!     <rect id="plate" x="10" y="10" width="80" height="80" fill="grey"/>
//!     <circle id="hole" cx="50" cy="50" r="20" fill="white"/>
//! </svg>"#;
//! let params = Params::DEFAULT.with_l(Length::Rel(0.1));
//! let meshed = triwild::mesh_svg(svg.as_bytes(), &params)?;
//! assert_eq!(meshed.mesh.order(), Order::Cubic); // curved 10-node triangles by default
//! assert!(meshed.mesh.surfaces.iter().any(|s| s == "hole"));
//! let mut msh = Vec::new();
//! triwild::write_msh_to(&meshed.mesh, &mut msh, MshOptions::DEFAULT)?;
//! # Ok::<(), triwild::Error>(())
//! ```
//!
//! Or file to file, as the command line does (`triwild drawing.svg -o drawing.msh`):
//!
//! ```no_run
//! use triwild::{Params, RunOptions};
//! let report = triwild::run_file("drawing.svg".as_ref(), "drawing.msh".as_ref(),
//!     &RunOptions::new(Params::DEFAULT))?;
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

pub use curve::{FileCheck, MeshCheck, certify_fem, check_msh};
pub use element::{CertifyOptions, Order};
pub use error::{Error, ErrorKind, Result};
pub use fem::{FeatureEdge, FemMesh, LineKind, LinearMesh};
pub use input::{MshFormat, MshMesh, TriangleBlock, read_msh, read_msh_file};
pub use output::{
    MshOptions, MshVersion, check_writable, write_file, write_msh, write_msh_to, write_preview,
};
pub use params::{Length, Mesher, Params, Stage};
pub use pipeline::{
    Meshed, Report, RunOptions, mesh_drawing, mesh_drawing_with, mesh_svg, run_file,
};
pub use regions::{RegionMode, RegionOptions, RegionStat};
pub use svg::{Drawing, load_bytes, load_file};
