//! Periodic cells (`--periodic`): the drawing is the tile of a pattern, and
//! the mesh covers the cell exactly with matching opposite sides.
//!
//! - [`Cell::of`]: the cell (the root `viewBox` or the parameters' own), or a
//!   one-line error;
//! - [`Cell::tile`] (`tile.rs`): the drawing translated by the periods and
//!   clipped to the cell, a region's pieces on both sides still one shape;
//! - [`Cell::side_points`]: the vertices of the cell's sides for the BSP: every
//!   feature end on a side and its partner on the opposite side, the gaps
//!   resampled to the size field once for both partner sides, so the two
//!   sides carry the same coordinates along them bit for bit;
//! - [`Cell::fix_sides`]: the sides' vertices never move and the sides' edges
//!   are never split (with `Context::fixed_boundary`), so the match the BSP
//!   makes is the one delivered;
//! - [`Cell::finish`]: the delivered mesh's sides as the physical curves
//!   `left`, `right`, `bottom`, `top` and its node pairs
//!   ([`crate::fem::Periodicity`]), measured.

mod tile;

use crate::fem::{FemMesh, LineKind, PeriodicPair, Periodicity};
use crate::mesh::TriMesh;
use crate::params::Periodic;
use crate::sizing::SizeField;
use crate::svg::Drawing;
use crate::{Error, Result};
use kurbo::{Point, Rect};

/// The names of the cell's sides as physical curves: left, right, bottom, top.
pub(crate) const SIDES: [&str; 4] = ["left", "right", "bottom", "top"];

/// A periodic cell in output coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Cell {
    /// The cell.
    pub rect: Rect,
    /// Left and right sides match.
    pub x: bool,
    /// Bottom and top sides match.
    pub y: bool,
}

/// What `--stats` says about the periodic match.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PeriodicReport {
    /// The repeating directions (`x`, `y` or `xy`).
    pub axes: String,
    /// The cell `[x0, y0, x1, y1]`.
    pub cell: [f64; 4],
    /// Node pairs (a node on the right or top side with its partner on the left
    /// or bottom side; high-order nodes included).
    pub pairs: usize,
    /// Nodes on a periodic side without a partner (0 for a valid periodic mesh).
    pub unpaired: usize,
    /// The largest mismatch of a pair as written: the difference of their
    /// coordinates along the side plus each one's distance from its side (0
    /// for a valid periodic mesh).
    pub max_mismatch: f64,
    /// The largest distance a high-order node on a side moved onto its
    /// partner's translate (edge nodes are computed per triangle, in its own
    /// direction along the edge: they agree to rounding).
    pub max_node_snap: f64,
}

impl Cell {
    /// The cell of `periodic` for `drawing`: its own, else the drawing's root
    /// `viewBox`.
    ///
    /// # Errors
    /// [`Error::InvalidParams`] when the drawing has no viewBox and no cell is
    /// given, or the cell has no area.
    pub(crate) fn of(drawing: &Drawing, periodic: &Periodic) -> Result<Cell> {
        let rect = match periodic.cell {
            Some([x0, y0, x1, y1]) => Rect::new(x0, y0, x1, y1),
            None => drawing.view_box.ok_or_else(|| {
                Error::InvalidParams(
                    "--periodic: the drawing has no viewBox to be the cell; give --cell X0,Y0,X1,Y1"
                        .into(),
                )
            })?,
        };
        let ok = [rect.x0, rect.y0, rect.x1, rect.y1]
            .iter()
            .all(|v| v.is_finite())
            && rect.x1 > rect.x0
            && rect.y1 > rect.y0;
        if !ok {
            return Err(Error::InvalidParams(format!(
                "--periodic: the cell {},{},{},{} has no area",
                rect.x0, rect.y0, rect.x1, rect.y1
            )));
        }
        Ok(Cell {
            rect,
            x: periodic.axes.x(),
            y: periodic.axes.y(),
        })
    }

    /// The cell of a drawing [`Cell::tile`] made, with the parameters' axes.
    pub(crate) fn of_tile(drawing: &Drawing, params: &crate::params::Params) -> Option<Cell> {
        let (rect, p) = (drawing.cell?, params.periodic?);
        Some(Cell {
            rect,
            x: p.axes.x(),
            y: p.axes.y(),
        })
    }

    /// The drawing as the pattern's tile in this cell (see `tile.rs`); a
    /// feature end within `snap` of a side is moved onto it, a piece within
    /// `snap` along a side is the side.
    ///
    /// # Errors
    /// [`Error::NoGeometry`] when nothing of the drawing reaches the cell.
    pub(crate) fn tile(&self, drawing: &Drawing, snap: f64) -> Result<Drawing> {
        let tiled = tile::Tiler::new(self, snap).tile(drawing, self.rect);
        if tiled.features.is_empty() {
            return Err(Error::NoGeometry(
                " (nothing of the drawing lies in the periodic cell)".into(),
            ));
        }
        Ok(tiled)
    }

    /// The points the BSP puts on the cell's sides, beside `ends` (the
    /// features' vertices): see the module doc. A gap between two side
    /// points is halved while it is longer than the size field there or
    /// than 1.2 times its distance from the nearest of `segments` (the
    /// features' chords) that does not end on the side (the triangles
    /// between a feature and a side it runs close to stay near
    /// equilateral), down to `l_min`. Corners are not
    /// listed (the box has them).
    pub(crate) fn side_points(
        &self,
        ends: &[Point],
        segments: &[kurbo::Line],
        field: &SizeField,
        l_min: f64,
    ) -> Vec<Point> {
        let r = self.rect;
        let mut out = Vec::new();
        // the distance from a side point to the chords that do not end on
        // that side (a chord ending on it meets it: its triangles there are
        // shaped by the crossing, not by a gap)
        let gap_to = |p: Point, on_side: &dyn Fn(Point) -> bool| {
            segments
                .iter()
                .filter(|l| !on_side(l.p0) && !on_side(l.p1))
                .map(|l| kurbo::ParamCurveNearest::nearest(l, p, 0.0).distance_sq)
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        };
        for axis in 0..2 {
            // axis 0: the left and right sides (x fixed, y along)
            let (lo, hi, a0, a1, periodic) = if axis == 0 {
                (r.x0, r.x1, r.y0, r.y1, self.x)
            } else {
                (r.y0, r.y1, r.x0, r.x1, self.y)
            };
            let along = |p: &Point| if axis == 0 { p.y } else { p.x };
            let across = |p: &Point| if axis == 0 { p.x } else { p.y };
            let at = |side: f64, v: f64| {
                if axis == 0 {
                    Point::new(side, v)
                } else {
                    Point::new(v, side)
                }
            };
            let mut sets: [Vec<f64>; 2] = [vec![a0, a1], vec![a0, a1]];
            for p in ends {
                let v = along(p);
                if v <= a0 || v >= a1 {
                    continue;
                }
                if across(p) == lo {
                    sets[0].push(v);
                } else if across(p) == hi {
                    sets[1].push(v);
                }
            }
            if periodic {
                let both: Vec<f64> = sets.iter().flatten().copied().collect();
                sets = [both.clone(), both];
            }
            let mut first: Option<Vec<f64>> = None;
            for (k, side) in [lo, hi].into_iter().enumerate() {
                if let (true, Some(all)) = (periodic, &first) {
                    // the partner side: the same coordinates along, bit for bit
                    out.extend(
                        all.iter()
                            .filter(|&&v| v > a0 && v < a1)
                            .map(|&v| at(side, v)),
                    );
                    continue;
                }
                let mut vs = std::mem::take(&mut sets[k]);
                vs.sort_by(f64::total_cmp);
                vs.dedup();
                // the sides a gap's length answers to: its own, and its partner
                let sides: &[f64] = if periodic { &[lo, hi] } else { &[side] };
                let target = |v: f64| {
                    sides
                        .iter()
                        .map(|&s| {
                            let q = at(s, v);
                            let on = |p: Point| across(&p) == s;
                            field.at(q).min(1.2 * gap_to(q, &on))
                        })
                        .fold(f64::INFINITY, f64::min)
                        .max(l_min)
                };
                let mut all = vs.clone();
                let mut stack: Vec<(f64, f64)> = vs.windows(2).map(|w| (w[0], w[1])).collect();
                while let Some((a, b)) = stack.pop() {
                    let m = 0.5 * (a + b);
                    if b - a > target(m) && m > a && m < b && out.len() + all.len() < 1_000_000 {
                        all.push(m);
                        stack.push((a, m));
                        stack.push((m, b));
                    }
                }
                out.extend(
                    all.iter()
                        .filter(|&&v| v > a0 && v < a1)
                        .map(|&v| at(side, v)),
                );
                first = Some(all);
            }
        }
        // the ends are BSP vertices already
        let have: std::collections::HashSet<(u64, u64)> = ends
            .iter()
            .map(|p| (p.x.to_bits(), p.y.to_bits()))
            .collect();
        out.retain(|p| !have.contains(&(p.x.to_bits(), p.y.to_bits())));
        out.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        out.dedup();
        out
    }

    /// Fix every vertex on the mesh's boundary (the cell's sides): tagged as
    /// the box's corners are, so no operation moves or removes it.
    pub(crate) fn fix_sides(mesh: &mut TriMesh) {
        let boundary: Vec<_> = mesh
            .vertices()
            .filter(|&v| mesh.vertex_ring(v).boundary)
            .collect();
        for v in boundary {
            let mut tag = mesh.vertex_tag(v);
            tag.box_corner = true;
            mesh.set_vertex_tag(v, tag);
        }
    }

    /// The delivered mesh's sides: its boundary lines on the cell's sides move
    /// from [`crate::fem::BOUNDARY`] to the physical curves [`SIDES`]; the
    /// nodes of the right (top) side are paired with those of the left
    /// (bottom) side (high-order nodes moved onto their partner's translate,
    /// at most rounding away); the pairs go into `mesh.periodic`.
    pub(crate) fn finish(&self, mesh: &mut FemMesh) -> PeriodicReport {
        let r = self.rect;
        let mut side_group = [0u32; 4];
        for (k, name) in SIDES.iter().enumerate() {
            side_group[k] = match mesh.curves.iter().position(|c| c == name) {
                Some(g) => g as u32,
                None => {
                    mesh.curves.push((*name).to_owned());
                    (mesh.curves.len() - 1) as u32
                }
            };
        }
        // the side of each boundary line, by both its ends
        let mut on_side: [Vec<u32>; 4] = Default::default();
        for l in 0..mesh.line_count() {
            if mesh.line_kind.get(l) != Some(&LineKind::Boundary) {
                continue;
            }
            let line = mesh.line(l).to_vec();
            let (a, b) = (mesh.nodes[line[0] as usize], mesh.nodes[line[1] as usize]);
            let side = (0..4).find(|&s| match s {
                0 => a.x == r.x0 && b.x == r.x0,
                1 => a.x == r.x1 && b.x == r.x1,
                2 => a.y == r.y0 && b.y == r.y0,
                _ => a.y == r.y1 && b.y == r.y1,
            });
            if let Some(s) = side {
                mesh.line_group[l] = side_group[s];
                on_side[s].extend_from_slice(&line);
            }
        }
        let mut report = PeriodicReport {
            axes: match (self.x, self.y) {
                (true, true) => "xy",
                (true, false) => "x",
                _ => "y",
            }
            .to_owned(),
            cell: [r.x0, r.y0, r.x1, r.y1],
            ..PeriodicReport::default()
        };
        let tol = 1e-9 * r.width().hypot(r.height());
        let vertices: std::collections::HashSet<u32> = mesh
            .triangles
            .chunks(mesh.order().triangle_nodes())
            .flat_map(|t| t[..3].iter().copied())
            .collect();
        let mut pairs: Vec<PeriodicPair> = Vec::new();
        for (axis, periodic) in [(0usize, self.x), (1, self.y)] {
            if !periodic {
                continue;
            }
            let (master_side, slave_side) = if axis == 0 { (0, 1) } else { (2, 3) };
            let along = |p: Point| if axis == 0 { p.y } else { p.x };
            let mut nodes = |s: usize| {
                let mut v = std::mem::take(&mut on_side[s]);
                v.sort_unstable();
                v.dedup();
                v.sort_by(|&a, &b| {
                    along(mesh.nodes[a as usize]).total_cmp(&along(mesh.nodes[b as usize]))
                });
                v
            };
            let masters = nodes(master_side);
            let slaves = nodes(slave_side);
            on_side[master_side].clone_from(&masters);
            on_side[slave_side].clone_from(&slaves);
            let mut j = 0usize;
            for &s in &slaves {
                let vs = along(mesh.nodes[s as usize]);
                while j + 1 < masters.len() && along(mesh.nodes[masters[j + 1] as usize]) <= vs {
                    j += 1;
                }
                // the nearest master along the side
                let best = [j, j + 1]
                    .into_iter()
                    .filter(|&k| k < masters.len())
                    .min_by(|&a, &b| {
                        let da = (along(mesh.nodes[masters[a] as usize]) - vs).abs();
                        let db = (along(mesh.nodes[masters[b] as usize]) - vs).abs();
                        da.total_cmp(&db)
                    });
                let Some(k) = best else {
                    report.unpaired += 1;
                    continue;
                };
                let m = masters[k];
                let gap = (along(mesh.nodes[m as usize]) - vs).abs();
                if gap > tol {
                    report.unpaired += 1;
                    continue;
                }
                if gap > 0.0 {
                    // a high-order node (corner vertices are fixed and match
                    // exactly by construction; a corner vertex off is left so
                    // the mismatch shows it)
                    if !vertices.contains(&s) {
                        let mp = mesh.nodes[m as usize];
                        let p = &mut mesh.nodes[s as usize];
                        if axis == 0 {
                            p.y = mp.y;
                        } else {
                            p.x = mp.x;
                        }
                        report.max_node_snap = report.max_node_snap.max(gap);
                    }
                }
                pairs.push(PeriodicPair {
                    node: s,
                    master: m,
                    axis: axis as u8,
                });
            }
            report.unpaired += masters.len().saturating_sub(slaves.len());
        }
        for p in &pairs {
            let (a, b) = (mesh.nodes[p.node as usize], mesh.nodes[p.master as usize]);
            // the same coordinate along the side, each exactly on its side
            let d = if p.axis == 0 {
                (a.y - b.y).abs() + (a.x - r.x1).abs() + (b.x - r.x0).abs()
            } else {
                (a.x - b.x).abs() + (a.y - r.y1).abs() + (b.y - r.y0).abs()
            };
            report.max_mismatch = report.max_mismatch.max(d);
        }
        report.pairs = pairs.len();
        mesh.periodic = Some(Periodicity {
            cell: [r.x0, r.y0, r.x1, r.y1],
            x: self.x,
            y: self.y,
            pairs,
        });
        report
    }
}
