//! The units of output coordinates (`--units`): shared by the parameters, which
//! choose them, and the SVG loader, which applies them.

/// The units of the output coordinates: what one unit of the mesh is.
///
/// An SVG document is drawn in the user units of its root `viewBox`; its
/// `width` and `height` say how large that box is shown (in CSS px at 96 dpi
/// once `mm`, `cm`, `in`, `pt` are converted). An Inkscape drawing
/// `<svg width="210mm" height="297mm" viewBox="0 0 210 297">` is drawn in
/// millimetres: a `<rect width="100" height="50">` in it is 100 × 50 user
/// units, but about 378 × 189 px.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Units {
    /// The user units of the root `viewBox`: the numbers written in the
    /// document (the root viewport mapping is undone; without a `viewBox` they
    /// are px). The default.
    User,
    /// CSS px of the root viewport (96 px per inch): the document as a browser
    /// sizes it, after the root `viewBox` → `width`/`height` mapping.
    Px,
}

impl Units {
    /// The lower-case name, as in `--units` and `--stats`.
    pub fn name(self) -> &'static str {
        match self {
            Units::User => "user",
            Units::Px => "px",
        }
    }
}

impl std::fmt::Display for Units {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
