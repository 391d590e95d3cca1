//! What the size field reports (`--stats` `sizing`): the fields applied, the
//! grading, and how well the mesh's edges match the field.

use super::SizeField;
use kurbo::Point;

/// The `sizing` entry of `--stats`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SizingReport {
    /// The fields applied beside `l`: `strokes` (thin strokes meshed as
    /// areas), `feature-size`, `size`, `size-near`, `size-box`, `size-expr`,
    /// `size-from`, `size-fn`. Empty: the size is `l` everywhere.
    pub fields: Vec<String>,
    /// The grading: the largest growth of the size from one element to the next.
    pub grading: f64,
    /// The largest size, `l` (output units).
    pub l: f64,
    /// The smallest size the field may give, `l_min` (output units).
    pub l_min: f64,
    /// The smallest size the field gives.
    pub min_size: f64,
    /// The smallest size the user's fields asked for before the clamp to
    /// `[l_min, l]` (at the field's own sample points: the quadtree's corners
    /// and centres, the outline fields' sources); below `l_min` the field is
    /// clamped there and the run warns.
    pub asked_min: f64,
    /// Source points on outlines (thin strokes, outline fields, feature size).
    pub sources: usize,
    /// Leaves of the background quadtree.
    pub leaves: usize,
    /// Whether the quadtree stopped refining at its budget (twice the vertex
    /// budget `--max-vertices` in leaves): the field asks for finer elements
    /// than a mesh within the vertex budget can have, and is resolved only
    /// as far as that budget.
    pub capped: bool,
    /// How well the delivered mesh's edges match the field.
    pub edges: Option<EdgeMatch>,
}

impl SizingReport {
    pub(super) fn uniform(l: f64) -> SizingReport {
        SizingReport {
            fields: Vec::new(),
            grading: crate::defaults::GRADING,
            l,
            l_min: l,
            min_size: l,
            asked_min: l,
            sources: 0,
            leaves: 1,
            capped: false,
            edges: None,
        }
    }
}

/// Bounds of the edge-length histogram, as edge / h.
pub const HISTOGRAM_BOUNDS: [f64; 7] = [0.25, 0.5, 0.8, 4.0 / 3.0, 2.0, 4.0, f64::INFINITY];

/// How well a mesh's edges match the size field h: each edge's length over h
/// at its midpoint.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct EdgeMatch {
    /// Edges measured (the edges the optimizer refined below the field, around
    /// elements it could not improve at the field's size, are left out).
    pub edges: usize,
    /// Edges left out as refined below the field by the optimizer.
    pub refined: usize,
    /// Share of the measured edges with length within [4/5, 4/3] of h.
    pub matched: f64,
    /// Median of edge / h.
    pub median_ratio: f64,
    /// Edge counts by edge / h: below 1/4, [1/4, 1/2), [1/2, 4/5), [4/5, 4/3),
    /// [4/3, 2), [2, 4), 4 and above (bounds: [`HISTOGRAM_BOUNDS`]).
    pub histogram: [usize; 7],
}

/// The match of `edges` (end points) against `field`; `refined(a, b)` says
/// whether the optimizer refined the edge below the field. The ratios are
/// computed and sorted in parallel (the counts and the median do not depend
/// on the order).
pub(crate) fn edge_match(
    field: &SizeField,
    edges: &[(Point, Point)],
    refined: impl Fn(Point, Point) -> bool + Sync,
) -> EdgeMatch {
    use rayon::prelude::*;
    let mut ratios: Vec<f64> = edges
        .par_iter()
        .filter(|&&(a, b)| !refined(a, b))
        .map(|&(a, b)| a.distance(b) / field.at_mid(a, b))
        .collect();
    let left_out = edges.len() - ratios.len();
    let mut histogram = [0usize; 7];
    let mut matched = 0usize;
    for &r in &ratios {
        let bin = HISTOGRAM_BOUNDS.iter().position(|&b| r < b).unwrap_or(6);
        histogram[bin] += 1;
        if (0.8..=4.0 / 3.0).contains(&r) {
            matched += 1;
        }
    }
    // (values equal under `total_cmp` are the same bits: any sort gives one order)
    ratios.par_sort_unstable_by(f64::total_cmp);
    let median_ratio = if ratios.is_empty() {
        0.0
    } else {
        ratios[ratios.len() / 2]
    };
    EdgeMatch {
        edges: ratios.len(),
        refined: left_out,
        matched: if ratios.is_empty() {
            0.0
        } else {
            matched as f64 / ratios.len() as f64
        },
        median_ratio,
        histogram,
    }
}
