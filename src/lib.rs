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
//! use triwild::{Length, LoadOptions, MshOptions, Order, Params, RegionOptions};
//!
//! let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="100" height="100">
//!     <rect id="plate" x="10" y="10" width="80" height="80" fill="grey"/>
//!     <circle id="hole" cx="50" cy="50" r="20" fill="white"/>
//! </svg>"#;
//! let params = Params::DEFAULT.with_l(Length::Rel(0.1));
//! // the parameters' units, scale, budgets and hairline width
//! let drawing = triwild::load_bytes(svg.as_bytes(), &LoadOptions::from_params(&params)?)?;
//! let meshed = triwild::mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT)?;
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

mod baseline;
pub mod batch;
mod bsp;
mod budget;
mod curve;
pub mod element;
mod error;
mod exact;
mod features;
mod fem;
mod input;
mod mesh;
mod ops;
mod optimize;
mod output;
mod params;
mod periodic;
mod pipeline;
mod quality;
mod regions;
mod sizing;
mod stage;
mod svg;
mod units;

// The command line (`src/main.rs` and the Python package's `triwild` command
// run it); not API. Its modules name the library `triwild::…` as the binary's
// did, and `crate::exit_code`.
#[cfg(feature = "cli")]
extern crate self as triwild;
#[cfg(feature = "cli")]
#[doc(hidden)]
#[allow(
    clippy::print_stdout,
    clippy::print_stderr,
    reason = "the command line talks to the user"
)]
pub mod cli;
#[cfg(feature = "cli")]
use cli::exit_code;

pub use curve::certify::{FileCheck, MeshCheck, certify_fem, certify_mesh, check_msh};
pub use element::{CertifyOptions, Order};
pub use error::{Error, ErrorKind, Result};
pub use fem::{BOUNDARY, FeatureEdge, FemMesh, LineKind, LinearMesh, PeriodicPair, Periodicity};
pub use input::msh::{
    LineBlock, MshEntity, MshFormat, MshMesh, NodeData, TriangleBlock, read_msh, read_msh_file,
};
pub use output::{
    MeshFormat, MshOptions, MshVersion, PreviewOptions, check_writable, remove_temporaries,
    write_file, write_msh, write_msh_to, write_preview, write_vtu, write_vtu_to,
};
pub use params::{
    BackgroundMesh, BoxSize, Length, Mesher, NearSize, OptimizerParams, Params, Periodic,
    PeriodicAxes, RegionSize, SizeFn, SizeFnSignature, SizeSpec, defaults,
};
pub use periodic::PeriodicReport;
pub use pipeline::{FeatureAnalysis, Meshed, Report, RunOptions, mesh_drawing, run_file};
pub use regions::select::{RegionMode, RegionOptions, RegionStat};
pub use sizing::{EdgeMatch, HISTOGRAM_BOUNDS, SizingReport};
pub use stage::Stage;
pub use svg::drawing::{
    Clip, ClipPart, Conic, Drawing, Feature, FeatureGeom, FeatureSource, FillRule, PaintCounts,
    PathPrecision, Segment, Shape, ShapeId, ShapeKind, ShapePaint, Subpath,
};
pub use svg::{LoadOptions, PaintOptions, StrokeMode, load_bytes, load_file};
pub use units::Units;

/// Not part of the API (hidden, no stability promise): the internals that the
/// criterion benchmarks in `benches/` time directly, the exact kernel and the BSP.
#[doc(hidden)]
pub mod __bench {
    pub use crate::bsp::BspStats;
    pub use crate::exact::predicates::{
        Orientation, orient2d, orient2d_q, orient2d_q_exact, orient2d_q_filter,
    };
    pub use crate::exact::rational::PointQ;

    /// The BSP mesh (§2.3.1) of secondary segments inside `bbox`, with the default
    /// options: its statistics (the mesh itself is dropped).
    ///
    /// # Errors
    /// As the BSP stage: a cell that cannot be fanned, a vertex that cannot be rounded.
    pub fn bsp_of_segments(
        segments: &[(kurbo::Point, kurbo::Point)],
        bbox: kurbo::Rect,
    ) -> crate::Result<BspStats> {
        use crate::bsp::{BspInput, BspOptions, BspSegment, SegmentTag};
        let input = BspInput {
            segments: segments
                .iter()
                .enumerate()
                .map(|(i, &(a, b))| BspSegment {
                    a,
                    b,
                    tag: SegmentTag::Secondary {
                        polyline: u32::try_from(i).expect("segment count fits u32"),
                    },
                })
                .collect(),
            ..BspInput::default()
        };
        crate::bsp::build(&input, bbox, &BspOptions::DEFAULT).map(|(_, stats)| stats)
    }

    /// The size field of `drawing` under `params` (default region names), as
    /// the pipeline builds it, for timing its construction and its lookups.
    pub struct SizeFieldProbe(crate::sizing::SizeField);

    impl SizeFieldProbe {
        /// Build the field.
        ///
        /// # Errors
        /// As the pipeline: a size field naming no region, a bad formula.
        pub fn build(drawing: &crate::Drawing, params: &crate::Params) -> crate::Result<Self> {
            crate::pipeline::default_field(drawing, params, crate::budget::Deadline::NONE)
                .map(SizeFieldProbe)
        }

        /// h at `p`.
        pub fn at(&self, p: kurbo::Point) -> f64 {
            self.0.at(p)
        }
    }
}
