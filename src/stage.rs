//! The stages of the pipeline, by name: where meshing may stop (`--stop-after`)
//! and where a meshing error happened (the error's `stage`).

/// A stage of the meshing pipeline (docs/design.md "Data flow").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Stage {
    /// The size field (`sizing`): built before the features from the drawing
    /// and the size parameters.
    Sizing,
    /// Feature preprocessing: primary and secondary features (§4.3.1, §4.4).
    Features,
    /// The exact BSP mesh: every vertex rounded to `f64` or an error, no
    /// optimization (§2.3.1).
    Bsp,
    /// The optimized linear mesh: all `f64`, primary vertices on their curves, no
    /// curving (`--linear`; §2.3.2, §4.4.1).
    Optimize,
    /// Curving: certified Lagrange elements of order 2 or 3 (§4.4.2).
    Curve,
    /// The CDT baseline mesher (`--mesher cdt`).
    Baseline,
    /// Regions: each triangle classified by the fills (winding numbers on the
    /// input curves) and tagged (docs/design.md "regions").
    Regions,
}

impl Stage {
    /// The stage's lower-case name, as in messages, `--stats` and `--stop-after`.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Sizing => "sizing",
            Stage::Features => "features",
            Stage::Bsp => "bsp",
            Stage::Optimize => "optimize",
            Stage::Curve => "curve",
            Stage::Baseline => "baseline",
            Stage::Regions => "regions",
        }
    }

    /// Whether a mesh can be delivered after this stage (`--stop-after`): the BSP
    /// mesh and the optimized linear mesh (both need the TriWild mesher).
    pub fn can_stop_after(self) -> bool {
        matches!(self, Stage::Bsp | Stage::Optimize)
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
