//! From a classification to physical surfaces: naming (per shape, per colour,
//! or one domain), dropping regions (`--cut-outside`, `--keep`, `--hole`) and
//! compacting the mesh.

use super::DrawnAreas;
use super::classify::{RegionAssignment, edge_key};
use super::element::element_area;
use crate::exact::{Orientation, orient2d};
use crate::fem::FemMesh;
use crate::svg::{Drawing, Shape};
use crate::{Error, Result};
use kurbo::Point;
use std::collections::{HashMap, HashSet};

/// How triangles are grouped into physical surfaces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RegionMode {
    /// One surface per filled shape (its SVG id, else `shape-N`), plus `background`.
    Shape,
    /// One surface per distinct fill colour (`fill-#rrggbb`; a gradient or pattern
    /// fill is `fill-<shape name>`), plus `background`.
    Colour,
    /// One surface `domain` (painted and background alike, unless dropped).
    None,
}

/// What regions become surfaces and which are kept.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct RegionOptions {
    /// Grouping. Default [`RegionMode::Shape`].
    pub mode: RegionMode,
    /// Drop the background (triangles no filled shape covers). Default false.
    pub cut_outside: bool,
    /// Keep only the regions with these names (empty: keep all). With
    /// [`RegionMode::None`] the names are `domain` (painted) and `background`.
    pub keep: Vec<String>,
    /// Drop the region containing each of these points (output coordinates).
    pub holes: Vec<Point>,
}

impl RegionOptions {
    /// Per-shape surfaces, nothing dropped.
    pub const DEFAULT: RegionOptions = RegionOptions {
        mode: RegionMode::Shape,
        cut_outside: false,
        keep: Vec::new(),
        holes: Vec::new(),
    };
    /// Set the grouping.
    pub fn with_mode(mut self, mode: RegionMode) -> Self {
        self.mode = mode;
        self
    }
    /// Drop (or keep) the background.
    pub fn with_cut_outside(mut self, cut: bool) -> Self {
        self.cut_outside = cut;
        self
    }
    /// Keep only the named regions.
    pub fn with_keep(mut self, names: Vec<String>) -> Self {
        self.keep = names;
        self
    }
    /// Drop the regions containing these points.
    pub fn with_holes(mut self, holes: Vec<Point>) -> Self {
        self.holes = holes;
        self
    }
    /// Whether the triangles must be classified (anything but one plain domain).
    pub fn needs_classification(&self) -> bool {
        self.mode != RegionMode::None
            || self.cut_outside
            || !self.keep.is_empty()
            || !self.holes.is_empty()
    }
}

impl Default for RegionOptions {
    fn default() -> Self {
        RegionOptions::DEFAULT
    }
}

/// One physical surface of the output.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RegionStat {
    /// Surface name.
    pub name: String,
    /// Number of triangles.
    pub triangles: usize,
    /// Area (exact for the elements as written, straight or curved).
    pub area: f64,
    /// The colour the region is painted with, `#rrggbb` (`#rrggbbaa` when
    /// translucent; a gradient's average colour): the first shape's in paint
    /// order; `None` for the background, a pattern or a mesh without a drawing.
    pub colour: Option<String>,
    /// The region's area in the drawing: the paint model on the input curves
    /// (topmost painted shape, fill rules, clips, strokes as areas), never the
    /// mesh; exact for polygons and conics, to rounding for cubics. `None`
    /// where it was not computed (no drawing, or curves that overlap along a
    /// stretch without being equal).
    pub drawn_area: Option<f64>,
    /// `area − drawn_area`: what the mesh gained (positive) or lost.
    pub area_error: Option<f64>,
}

impl RegionStat {
    /// Set the drawn area, and the error against [`RegionStat::area`].
    pub(crate) fn set_drawn(&mut self, drawn: f64) {
        self.drawn_area = Some(drawn);
        self.area_error = Some(self.area - drawn);
    }
}

/// Name of the surface of triangles no filled shape covers.
pub(crate) const BACKGROUND: &str = "background";
/// Name of the single surface of [`RegionMode::None`].
pub(crate) const DOMAIN: &str = "domain";

/// The surface name of a shape under [`RegionMode::Colour`]: `fill-#rrggbb` for
/// an opaque colour (a stroke's area by its stroke colour), `fill-#rrggbbaa`
/// for a translucent one (CSS hex with alpha: the mesh carries no blending;
/// an opacity that rounds to alpha 255 is opaque, see [`hex_colour`]),
/// `fill-<gradient or pattern id>` for a paint server, else `fill-<shape name>`.
pub(crate) fn colour_name(s: &Shape) -> String {
    match (s.fill_colour, &s.paint.server) {
        (Some(rgb), _) => format!("fill-{}", hex_colour(rgb, s.paint.alpha)),
        (None, Some(server)) => format!("fill-{server}"),
        (None, None) => format!("fill-{}", s.name()),
    }
}

/// A colour as CSS hex: `#rrggbb`, or `#rrggbbaa` when the opacity as a byte
/// (rounded) is below 255. An opacity of 0.999 is written `#rrggbb`, the name
/// the same colour at opacity 1 has: one region, not two.
fn hex_colour([r, g, b]: [u8; 3], alpha: f32) -> String {
    // clamped and scaled: the rounded value is in 0..=255
    let a = (alpha.clamp(0.0, 1.0) * 255.0).round() as u8;
    if a == u8::MAX {
        format!("#{r:02x}{g:02x}{b:02x}")
    } else {
        format!("#{r:02x}{g:02x}{b:02x}{a:02x}")
    }
}

/// Per-triangle region labels and the label names (background is label 0).
fn labels(
    drawing: &Drawing,
    asg: &RegionAssignment,
    mode: RegionMode,
) -> (Vec<u32>, Vec<String>, Vec<Option<String>>, Vec<u32>) {
    let mut names = vec![BACKGROUND.to_owned()];
    let mut colours: Vec<Option<String>> = vec![None];
    let mut index: HashMap<String, u32> = HashMap::from([(BACKGROUND.to_owned(), 0)]);
    // Labels in paint order of the shapes, so the surface order is deterministic.
    let mut order: Vec<usize> = (0..drawing.shapes.len())
        .filter(|&i| drawing.shapes[i].filled)
        .collect();
    order.sort_by_key(|&i| (drawing.shapes[i].paint_order, i));
    let mut of_shape = vec![0u32; drawing.shapes.len()];
    for i in order {
        let s = &drawing.shapes[i];
        let name = match mode {
            RegionMode::Shape => {
                let n = s.name();
                if n == BACKGROUND {
                    format!("shape-{}", s.element_index)
                } else {
                    n
                }
            }
            RegionMode::Colour => colour_name(s),
            RegionMode::None => DOMAIN.to_owned(),
        };
        of_shape[i] = *index.entry(name.clone()).or_insert_with(|| {
            names.push(name);
            colours.push(css_colour(s));
            (names.len() - 1) as u32
        });
    }
    let tri = asg
        .owner
        .iter()
        .map(|o| o.map_or(0, |s| of_shape[s.index()]))
        .collect();
    (tri, names, colours, of_shape)
}

/// A shape's paint as a CSS colour (see [`RegionStat::colour`]).
fn css_colour(s: &Shape) -> Option<String> {
    let rgb = s.fill_colour.or(s.paint.average_colour)?;
    Some(hex_colour(rgb, s.paint.alpha))
}

/// The first triangle whose corner triangle contains `p` (exact test).
fn locate(mesh: &FemMesh, p: Point) -> Option<usize> {
    let left_or_on = |a: Point, b: Point| orient2d(a, b, p) != Orientation::Clockwise;
    (0..mesh.triangle_count()).find(|&t| {
        let [a, b, c] = mesh.corners(t);
        left_or_on(a, b) && left_or_on(b, c) && left_or_on(c, a)
    })
}

/// Turn a classification into physical surfaces, drop the regions `opts` asks
/// to drop, and compact the mesh (unused nodes removed, numbering contiguous
/// in the old order; line elements kept when a kept triangle has them as an
/// edge; empty physical groups removed). Every element of the result is in a
/// physical group.
///
/// # Errors
/// [`Error::InvalidParams`] when `--keep` names a region that does not exist,
/// a `--hole` point lies outside the mesh, or nothing is left.
pub(crate) fn apply(
    drawing: &Drawing,
    mesh: &FemMesh,
    asg: &RegionAssignment,
    opts: &RegionOptions,
    drawn: Option<&DrawnAreas>,
) -> Result<(FemMesh, Vec<RegionStat>)> {
    let n = mesh.triangle_count();
    debug_assert_eq!(asg.owner.len(), n, "internal: assignment of another mesh");
    let (tri_label, names, label_colours, of_shape) = labels(drawing, asg, opts.mode);
    let mut count = vec![0usize; names.len()];
    for &l in &tri_label {
        count[l as usize] += 1;
    }
    let present: Vec<&str> = (0..names.len())
        .filter(|&l| count[l] > 0)
        .map(|l| names[l].as_str())
        .collect();
    let mut keep = vec![true; names.len()];
    if opts.cut_outside {
        keep[0] = false;
    }
    if !opts.keep.is_empty() {
        for name in &opts.keep {
            if !present.contains(&name.as_str()) {
                return Err(Error::InvalidParams(format!(
                    "--keep: no region named `{name}`; the regions are: {}",
                    present.join(", ")
                )));
            }
        }
        for (l, k) in keep.iter_mut().enumerate() {
            *k &= opts.keep.contains(&names[l]);
        }
    }
    for &p in &opts.holes {
        let t = locate(mesh, p).ok_or_else(|| {
            // (`{:?}`: 1e300 as written, not as 301 digits)
            Error::InvalidParams(format!(
                "--hole {:?},{:?}: the point is outside the meshed box",
                p.x, p.y
            ))
        })?;
        keep[tri_label[t] as usize] = false;
    }
    let kept: Vec<usize> = (0..n).filter(|&t| keep[tri_label[t] as usize]).collect();
    if kept.is_empty() {
        return Err(Error::InvalidParams(format!(
            "regions: --cut-outside/--keep/--hole removed every triangle; the regions are: {}",
            present.join(", ")
        )));
    }

    // Surfaces: the kept labels with triangles, in label order; `none` merges them.
    let mut surfaces: Vec<String> = Vec::new();
    let mut surface_colours: Vec<Option<String>> = Vec::new();
    let mut surface_of = vec![u32::MAX; names.len()];
    for l in 0..names.len() {
        if keep[l] && count[l] > 0 {
            let name = if opts.mode == RegionMode::None {
                DOMAIN
            } else {
                &names[l]
            };
            surface_of[l] = match surfaces.iter().position(|s| s == name) {
                Some(i) => i as u32,
                None => {
                    surfaces.push(name.to_owned());
                    surface_colours.push(if opts.mode == RegionMode::None {
                        None
                    } else {
                        label_colours[l].clone()
                    });
                    (surfaces.len() - 1) as u32
                }
            };
        }
    }

    // Lines: kept when a kept triangle has them as an edge (all of them when
    // nothing was dropped).
    let all_kept = kept.len() == n;
    let mut kept_edges = HashSet::new();
    if !all_kept {
        for &t in &kept {
            let c = mesh.triangle(t);
            for e in 0..3 {
                kept_edges.insert(edge_key(c[e], c[(e + 1) % 3]));
            }
        }
    }
    let kept_lines: Vec<usize> = (0..mesh.line_count())
        .filter(|&i| all_kept || kept_edges.contains(&edge_key(mesh.line(i)[0], mesh.line(i)[1])))
        .collect();

    // Nodes, renumbered in their old order.
    let mut used = vec![false; mesh.nodes.len()];
    for &t in &kept {
        for &v in mesh.triangle(t) {
            used[v as usize] = true;
        }
    }
    for &i in &kept_lines {
        for &v in mesh.line(i) {
            used[v as usize] = true;
        }
    }
    let mut new_index = vec![u32::MAX; mesh.nodes.len()];
    let mut nodes = Vec::new();
    for (v, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        new_index[v] = nodes.len() as u32;
        nodes.push(mesh.nodes[v]);
    }

    // Physical curves that still have lines, in their old order.
    let mut has_line = vec![false; mesh.curves.len()];
    for &i in &kept_lines {
        has_line[mesh.line_group[i] as usize] = true;
    }
    let mut curve_of = vec![u32::MAX; mesh.curves.len()];
    let mut curves = Vec::new();
    for (g, _) in has_line.iter().enumerate().filter(|(_, h)| **h) {
        curve_of[g] = curves.len() as u32;
        curves.push(mesh.curves[g].clone());
    }

    let order = mesh.order();
    let mut out = FemMesh {
        order: mesh.order,
        nodes,
        triangles: Vec::with_capacity(kept.len() * order.triangle_nodes()),
        triangle_group: Vec::with_capacity(kept.len()),
        surfaces,
        lines: Vec::with_capacity(kept_lines.len() * order.line_nodes()),
        line_group: Vec::with_capacity(kept_lines.len()),
        line_kind: Vec::with_capacity(kept_lines.len()),
        curves,
        periodic: None,
    };
    let mut stats: Vec<RegionStat> = out
        .surfaces
        .iter()
        .zip(surface_colours)
        .map(|(name, colour)| RegionStat {
            name: name.clone(),
            triangles: 0,
            area: 0.0,
            colour,
            drawn_area: None,
            area_error: None,
        })
        .collect();
    for &t in &kept {
        let g = surface_of[tri_label[t] as usize];
        out.triangles
            .extend(mesh.triangle(t).iter().map(|&v| new_index[v as usize]));
        out.triangle_group.push(g);
        let pts: Vec<Point> = mesh
            .triangle(t)
            .iter()
            .map(|&v| mesh.nodes[v as usize])
            .collect();
        stats[g as usize].triangles += 1;
        stats[g as usize].area += element_area(order, &pts);
    }
    for &i in &kept_lines {
        out.lines
            .extend(mesh.line(i).iter().map(|&v| new_index[v as usize]));
        out.line_group.push(curve_of[mesh.line_group[i] as usize]);
        out.line_kind.push(mesh.line_kind[i]);
    }
    if let Some(drawn) = drawn.filter(|d| d.overlaps == 0) {
        // Each label's drawn area, then each surface's (the labels it merges).
        let mut by_label = vec![0.0; names.len()];
        by_label[0] = drawn.background;
        for (i, &l) in of_shape.iter().enumerate() {
            if drawing.shapes[i].filled {
                by_label[l as usize] += drawn.by_shape[i];
            }
        }
        let mut by_surface = vec![0.0; stats.len()];
        for (l, a) in by_label.iter().enumerate() {
            if let Some(s) = by_surface.get_mut(surface_of[l] as usize) {
                *s += a;
            }
        }
        for (s, a) in stats.iter_mut().zip(by_surface) {
            s.set_drawn(a);
        }
    }
    Ok((out, stats))
}

/// The surfaces of `mesh` as they are, with their triangle counts and areas.
pub(crate) fn stats_of(mesh: &FemMesh) -> Vec<RegionStat> {
    let mut stats: Vec<RegionStat> = mesh
        .surfaces
        .iter()
        .map(|name| RegionStat {
            name: name.clone(),
            triangles: 0,
            area: 0.0,
            colour: None,
            drawn_area: None,
            area_error: None,
        })
        .collect();
    let order = mesh.order();
    for t in 0..mesh.triangle_count() {
        let pts: Vec<Point> = mesh
            .triangle(t)
            .iter()
            .map(|&v| mesh.nodes[v as usize])
            .collect();
        if let Some(s) = stats.get_mut(mesh.triangle_group[t] as usize) {
            s.triangles += 1;
            s.area += element_area(order, &pts);
        }
    }
    stats
}

/// For each surface of `mesh`, the length of the secondary feature lines on
/// its rim (the outlines the mesh follows only within ε).
pub(crate) fn secondary_lengths(mesh: &FemMesh) -> Vec<f64> {
    let mut surfaces_of_edge: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for t in 0..mesh.triangle_count() {
        let c = mesh.triangle(t);
        for e in 0..3 {
            surfaces_of_edge
                .entry(edge_key(c[e], c[(e + 1) % 3]))
                .or_default()
                .push(mesh.triangle_group[t]);
        }
    }
    let mut out = vec![0.0; mesh.surfaces.len()];
    for i in 0..mesh.line_count() {
        if mesh.line_kind[i] != crate::fem::LineKind::Secondary {
            continue;
        }
        let l = mesh.line(i);
        let len = mesh.nodes[l[0] as usize].distance(mesh.nodes[l[1] as usize]);
        for &g in surfaces_of_edge
            .get(&edge_key(l[0], l[1]))
            .into_iter()
            .flatten()
        {
            out[g as usize] += len;
        }
    }
    out
}
