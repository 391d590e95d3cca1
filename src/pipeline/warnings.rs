//! The run's warnings, each worded from what a stage measured: what went
//! wrong, where, and the flag that changes it.

use super::stages::{Front, StageOptions};
use crate::features::FeatureCounts;
use crate::fem::FemMesh;
use crate::optimize::OptimizeStats;
use crate::params::{Params, Resolved};
use crate::periodic::PeriodicReport;
use crate::svg::Drawing;

/// The warning for outline pieces near a periodic cell's sides that were
/// meshed within ε instead of exactly.
pub(super) fn near_cell_sides_warning(
    counts: &FeatureCounts,
    resolved: &Resolved,
) -> Option<String> {
    (counts.near_cell_sides > 0).then(|| {
        format!(
            "--periodic: {} outline piece(s) within mu = {:.3e} of the cell's sides \
             (a shape touching or grazing a side) meshed within eps = {:.3e}, not \
             exact, so the elements between them and the side keep their shape; \
             --mu-abs {:.3e} keeps more of them exact",
            counts.near_cell_sides,
            resolved.mu,
            resolved.eps,
            0.25 * resolved.mu,
        )
    })
}

/// The optimizer's warnings, in this order: primary vertices left off their
/// curves, the vertex budget reached (by the optimizer, the field, or the
/// features), corners left below α.
pub(super) fn optimize_warnings(
    stats: &OptimizeStats,
    front: &Front,
    opts: &StageOptions,
) -> Vec<String> {
    let mut out = Vec::new();
    if stats.off_curve_left > 0 {
        out.push(format!(
            "{} primary vertices could not be moved onto their curves",
            stats.off_curve_left
        ));
    }
    if stats.vertex_budget_reached
        || front.field.report().capped
        || front.features.counts.unrefined_over_budget > 0
    {
        out.push(vertex_budget_warning(opts.params.max_vertices));
    }
    if stats.bad_corners_left > 0 {
        out.push(bad_corners_warning(
            stats.bad_corners_left,
            opts.resolved.alpha,
            stats.stop,
        ));
    }
    out
}

/// The warning for a periodic mesh whose side nodes do not all pair up.
pub(super) fn periodic_warning(r: &PeriodicReport) -> Option<String> {
    (r.unpaired > 0 || r.max_mismatch > 0.0).then(|| {
        format!(
            "--periodic: {} side node(s) without a partner, largest mismatch {:e}",
            r.unpaired, r.max_mismatch
        )
    })
}

/// The warning for shapes whose regions the mesh lost (see
/// [`crate::regions::RegionReport::lost_shapes`]), naming the first few. When
/// every one is thinner (its mean width, [`crate::svg::Shape::mean_width`])
/// than the feature envelope μ or the minimal edge length l_min, it says so,
/// names the transform that thinned them if one did, and gives the values of
/// `--mu-abs` and `--min-edge-length-abs` that keep them: a quarter of the
/// narrowest mean width, rounded down to one digit, for each of the two that
/// is larger; or, when that is below the numerical tolerance ε_m, that no
/// flag keeps them.
pub(super) fn lost_regions_warning(
    drawing: &Drawing,
    lost: &[crate::svg::ShapeId],
    resolved: &Resolved,
) -> String {
    const NAMED: usize = 5;
    let (mu, l_min, eps_m) = (resolved.mu, resolved.l_min, resolved.eps_m);
    let shapes: Vec<&crate::svg::Shape> = lost.iter().map(|s| &drawing.shapes[s.index()]).collect();
    let names: Vec<String> = shapes.iter().take(NAMED).map(|s| s.name()).collect();
    let more = if lost.len() > NAMED { ", ..." } else { "" };
    let widths: Vec<f64> = shapes.iter().map(|s| s.mean_width()).collect();
    let narrowest = widths.iter().copied().fold(f64::INFINITY, f64::min);
    let widest = widths.iter().copied().fold(0.0, f64::max);
    if narrowest > 0.0 && widest < mu.max(l_min) {
        let under = shapes
            .iter()
            .find_map(|s| s.paint.stretched_by.as_deref())
            .map_or_else(String::new, |t| format!(" under {t}"));
        let value = narrowest / 4.0;
        let shown = crate::svg::one_digit_below(value);
        let mut limits = Vec::new();
        let mut flags = Vec::new();
        for (limit, name, flag) in [
            (mu, "the feature envelope mu", "--mu-abs"),
            (
                l_min,
                "the minimal edge length l_min",
                "--min-edge-length-abs",
            ),
        ] {
            if widest < limit {
                limits.push(format!("{name} = {limit:.3e}"));
            }
            if value < limit {
                flags.push(format!("{flag} {shown}"));
            }
        }
        let remedy = if value < eps_m {
            format!(
                "thinner than the numerical tolerance eps_m = {eps_m:.3e} as well: no flag \
                 keeps them beside the rest of the drawing"
            )
        } else {
            format!("they are kept with {}", flags.join(" "))
        };
        return format!(
            "{} painted shape(s){under} thinner than {} (mean width {narrowest:.2e} and up) \
             have no region in the mesh: their outlines are not kept apart ({remedy}): \
             {}{more}",
            lost.len(),
            limits.join(" and "),
            names.join(", ")
        );
    }
    format!(
        "{} painted shape(s) show in the picture but have no region in the mesh: their \
         outlines did not become mesh edges (outlines closer together than the feature \
         envelope mu = {mu:.3e} are not kept apart; a smaller --mu keeps more): {}{more}",
        lost.len(),
        names.join(", ")
    )
}

/// One warning naming the regions whose area on the mesh differs from their
/// drawn area by more than the tolerance, with the cause the mesh shows and
/// the flag that keeps them.
pub(super) fn area_warning(
    report: &crate::regions::RegionReport,
    mesh: &FemMesh,
    params: &Params,
    resolved: &Resolved,
) -> Option<String> {
    const NAMED: usize = 3;
    let floor = 1e-9 * resolved.d * resolved.d;
    let secondary = crate::regions::secondary_lengths(mesh);
    let mut off: Vec<(f64, &crate::regions::RegionStat, f64)> = report
        .surfaces
        .iter()
        .zip(&secondary)
        .filter_map(|(s, &sec)| {
            let (drawn, err) = (s.drawn_area?, s.area_error?);
            let allowed = (params.area_tolerance * drawn.abs()).max(floor) + report.drawn_unsure;
            (err.abs() > allowed).then_some((err.abs() / allowed, s, sec))
        })
        .collect();
    if off.is_empty() {
        return None;
    }
    off.sort_by(|a, b| b.0.total_cmp(&a.0));
    let named: Vec<String> = off
        .iter()
        .take(NAMED)
        .map(|(_, s, _)| {
            let drawn = s.drawn_area.unwrap_or(0.0);
            let rel = if drawn != 0.0 {
                format!(" ({:+.2} %)", 100.0 * (s.area - drawn) / drawn.abs())
            } else {
                String::new()
            };
            format!(
                "{} {:.6e} on the mesh against {:.6e} drawn{rel}",
                s.name, s.area, drawn
            )
        })
        .collect();
    let more = if off.len() > NAMED { ", ..." } else { "" };
    let with_secondary = off.iter().filter(|o| o.2 > 0.0).count();
    let cause = if with_secondary > 0 {
        format!(
            "{with_secondary} of them border outlines meshed within eps = {:.3e} (outlines \
             closer than mu = {:.3e} to another are secondary features); --mu-abs {:.3e} \
             keeps more outlines exact",
            resolved.eps,
            resolved.mu,
            resolved.mu / 4.0
        )
    } else {
        "their outlines are exact on the mesh: a region's triangles were given to a \
         neighbour (see regions.lost_shapes and relabelled)"
            .to_owned()
    };
    Some(format!(
        "{} region(s) {} by more than --area-tolerance {:e} (or 1e-9*d^2): {}{more}; {cause}",
        off.len(),
        crate::regions::AREA_WARNING,
        params.area_tolerance,
        named.join(", ")
    ))
}

/// The warning for unforced elements whose certified Jacobian ratio is below
/// [`crate::quality::RATIO_FLOOR`], `None` when there is none: how
/// many, the worst and where. The curving stage repairs only elements that it
/// cannot certify, then fits those it still cannot (to a ratio of at least
/// 0.01), so such an element is a fitted one or a valid one bent too far for
/// its size.
pub(super) fn low_ratio_warning(u: &crate::quality::Unforced) -> Option<String> {
    let w = u.worst_ratio.filter(|_| u.below_ratio_floor > 0)?;
    Some(format!(
        "{} unforced element(s) with a certified Jacobian ratio below {} left by the curving \
         stage (its repair splits only elements it cannot certify); the worst, {:.3}, at \
         ({:.6}, {:.6}); --stats quality.unforced.worst_ratio",
        u.below_ratio_floor,
        crate::quality::RATIO_FLOOR,
        w.jacobian_ratio,
        w.x,
        w.y
    ))
}

/// The warning for size fields that ask below the minimal edge length l_min:
/// the field is clamped there, and the flag that follows them.
pub(super) fn size_clamp_warning(report: &crate::sizing::SizingReport) -> Option<String> {
    (report.asked_min < report.l_min).then(|| {
        format!(
            "the size fields ask for sizes below the minimal edge length l_min = {:.3e} \
             (down to {:.3e} where the field was sampled): sizes are clamped to l_min; \
             --min-edge-length-abs {:.3e} or smaller follows them",
            report.l_min, report.asked_min, report.asked_min
        )
    })
}

/// The warning for a mesh that the vertex budget kept coarser than the size
/// field asks (the optimizer's splits stopped at it, or the field itself was
/// resolved only as far as it allows).
pub(super) fn vertex_budget_warning(max_vertices: u32) -> String {
    format!(
        "the vertex budget of {max_vertices} (--max-vertices) stopped refinement: the mesh is \
         coarser than the size asked (-l, --size*); --stats sizing.edges says by how much; \
         raise --max-vertices or ask for larger sizes"
    )
}

/// The warning for corners below α that the worst-element phase left where
/// the drawing leaves room: how many, and why it stopped.
pub(super) fn bad_corners_warning(
    n: usize,
    alpha: f64,
    stop: crate::optimize::schedule::StopReason,
) -> String {
    let why = if stop == crate::optimize::schedule::StopReason::TimeLimit {
        "the time limit"
    } else {
        "its rounds ran out"
    };
    format!(
        "{n} corner(s) below alpha = {:.1} degrees left where the features leave room \
         (the worst-element phase stopped: {why}); --stats quality.unforced gives the worst",
        alpha.to_degrees()
    )
}
