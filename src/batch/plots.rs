//! The report page's plots, drawn with plotters' SVG backend: histograms of
//! one figure per file, and a figure against input size (log-log) with the
//! median and p95 per size bucket and the fitted exponent.
//!
//! Guarantees: every function returns a piece of HTML (an inline `<svg>`, or
//! a one-line notice when there is nothing to draw or drawing failed); none
//! panics on empty, constant or non-finite data. Logarithmic axes are drawn
//! as linear axes in log10 of the value, labelled with the values.

use plotters::prelude::*;
use std::error::Error as StdError;

/// Width and height of a plot, pixels.
const SIZE: (u32, u32) = (440, 280);
/// The bars' and points' colour.
const INK: RGBColor = RGBColor(49, 104, 181);
/// The median line's colour.
const MEDIAN: RGBColor = RGBColor(200, 40, 40);
/// The p95 line's colour.
const P95: RGBColor = RGBColor(230, 140, 20);

type Drawn = std::result::Result<(), Box<dyn StdError>>;

/// How a histogram's x axis runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Axis {
    /// Linear over a fixed range (values outside it fall in the end bins).
    Fixed(f64, f64),
    /// Logarithmic over the data's range (values ≤ 0 are left out).
    Log,
}

/// A number as an axis label: two significant digits (the ticks of a
/// logarithmic axis fall between round numbers), `k` and `M` for thousands
/// and millions, no trailing zeros.
pub(crate) fn short(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() {
        return if a == 0.0 { "0".into() } else { format!("{v}") };
    }
    let digits = a.log10().floor() as i32;
    let unit = 10f64.powi(digits - 1);
    let r = (v / unit).round() * unit;
    if a >= 1e6 {
        format!("{}M", trim(format!("{:.1}", r / 1e6)))
    } else if a >= 1e4 {
        format!("{}k", trim(format!("{:.1}", r / 1e3)))
    } else if digits >= 1 {
        format!("{r:.0}")
    } else if digits >= -4 {
        trim(format!("{r:.*}", (1 - digits) as usize))
    } else {
        format!("{r:.1e}")
    }
}

fn trim(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A notice in place of a plot.
fn notice(title: &str, why: &str) -> String {
    format!(
        "<div class=\"noplot\"><b>{}</b><br>{}</div>",
        super::page::esc(title),
        super::page::esc(why)
    )
}

/// `lo..hi` widened when it is empty.
fn span(lo: f64, hi: f64, pad: f64) -> (f64, f64) {
    if hi - lo > 1e-12 * (lo.abs() + hi.abs()).max(1e-300) {
        (lo, hi)
    } else {
        (lo - pad, hi + pad)
    }
}

/// Counts of `values` in `bins` equal bins over `lo..hi` (in axis units).
fn bin(values: &[f64], lo: f64, hi: f64, bins: usize) -> Vec<u32> {
    let mut counts = vec![0u32; bins];
    for &v in values {
        let i = ((v - lo) / (hi - lo) * bins as f64).floor();
        let i = if i.is_nan() { 0.0 } else { i };
        counts[(i.max(0.0) as usize).min(bins - 1)] += 1;
    }
    counts
}

/// A histogram of `values` (one per file) titled `title`, x described by `x_desc`.
pub(crate) fn histogram(title: &str, x_desc: &str, values: &[f64], axis: Axis) -> String {
    let log = axis == Axis::Log;
    let t: Vec<f64> = values
        .iter()
        .filter(|v| v.is_finite() && (!log || **v > 0.0))
        .map(|&v| if log { v.log10() } else { v })
        .collect();
    if t.is_empty() {
        return notice(title, "no data (no file meshed)");
    }
    let (lo, hi) = match axis {
        Axis::Fixed(lo, hi) => (lo, hi),
        _ => {
            let lo = t.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            span(lo, hi, 0.25)
        }
    };
    let bins = 24;
    let counts = bin(&t, lo, hi, bins);
    let top = counts.iter().copied().max().unwrap_or(1).max(1);
    let mut svg = String::new();
    let drawn = draw_histogram(&mut svg, title, x_desc, lo, hi, &counts, top, log);
    match drawn {
        Ok(()) => svg,
        Err(e) => notice(title, &format!("cannot draw: {e}")),
    }
}

#[allow(
    clippy::too_many_arguments,
    reason = "one private drawing routine; a struct would only rename the arguments"
)]
fn draw_histogram(
    svg: &mut String,
    title: &str,
    x_desc: &str,
    lo: f64,
    hi: f64,
    counts: &[u32],
    top: u32,
    log: bool,
) -> Drawn {
    let root = SVGBackend::with_string(svg, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(44)
        .build_cartesian_2d(lo..hi, 0u32..top + top / 10 + 1)?;
    let fmt = |v: &f64| short(if log { 10f64.powf(*v) } else { *v });
    chart
        .configure_mesh()
        .disable_x_mesh()
        .light_line_style(WHITE)
        .x_desc(x_desc)
        .y_desc("files")
        .x_labels(6)
        .y_labels(5)
        .x_label_formatter(&fmt)
        .draw()?;
    let w = (hi - lo) / counts.len() as f64;
    chart.draw_series(
        counts
            .iter()
            .enumerate()
            .filter(|(_, c)| **c > 0)
            .map(|(i, &c)| {
                let a = lo + i as f64 * w;
                Rectangle::new([(a, 0u32), (a + w, c)], INK.mix(0.75).filled())
            }),
    )?;
    root.present()?;
    Ok(())
}

/// A least-squares fit `y = c · x^k` on log-log data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Fit {
    /// The exponent `k`.
    pub(crate) k: f64,
    /// log10 of `c`.
    pub(crate) log_c: f64,
}

/// The least-squares line through `(log10 x, log10 y)`; `None` with fewer
/// than two distinct `x`.
pub(crate) fn fit(points: &[(f64, f64)]) -> Option<Fit> {
    let p: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.log10(), y.log10()))
        .collect();
    let n = p.len() as f64;
    if p.len() < 2 {
        return None;
    }
    let mx = p.iter().map(|q| q.0).sum::<f64>() / n;
    let my = p.iter().map(|q| q.1).sum::<f64>() / n;
    let sxx: f64 = p.iter().map(|q| (q.0 - mx).powi(2)).sum();
    let sxy: f64 = p.iter().map(|q| (q.0 - mx) * (q.1 - my)).sum();
    if sxx <= 1e-12 {
        return None;
    }
    let k = sxy / sxx;
    Some(Fit {
        k,
        log_c: my - k * mx,
    })
}

/// Nearest-rank percentile `p` (0..=1) of sorted `v` (non-empty).
pub(crate) fn percentile(v: &[f64], p: f64) -> f64 {
    let rank = (p * v.len() as f64).ceil() as usize;
    v[rank.clamp(1, v.len()) - 1]
}

/// One size bucket: sizes in `[2^b, 2^(b+1))`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Bucket {
    /// The bucket's lower bound, a power of two.
    pub(crate) from: f64,
    /// Points in it.
    pub(crate) count: usize,
    /// The median size of its points.
    pub(crate) x: f64,
    /// The median of y.
    pub(crate) median: f64,
    /// The 95th percentile of y.
    pub(crate) p95: f64,
}

/// The points grouped by size in powers of two.
pub(crate) fn buckets(points: &[(f64, f64)]) -> Vec<Bucket> {
    let mut by: std::collections::BTreeMap<i64, (Vec<f64>, Vec<f64>)> = Default::default();
    for &(x, y) in points {
        if x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite() {
            let e = by.entry(x.log2().floor() as i64).or_default();
            e.0.push(x);
            e.1.push(y);
        }
    }
    by.into_iter()
        .map(|(b, (mut xs, mut ys))| {
            xs.sort_by(f64::total_cmp);
            ys.sort_by(f64::total_cmp);
            Bucket {
                from: 2f64.powi(b as i32),
                count: ys.len(),
                x: percentile(&xs, 0.5),
                median: percentile(&ys, 0.5),
                p95: percentile(&ys, 0.95),
            }
        })
        .collect()
}

/// `points` (x: input size, y: a figure) on log-log axes, with the median
/// and p95 per size bucket and the fitted line when `trend`.
pub(crate) fn scatter(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    points: &[(f64, f64)],
    trend: bool,
) -> String {
    let p: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.log10(), y.log10()))
        .collect();
    if p.is_empty() {
        return notice(title, "no data (no file meshed)");
    }
    let mut svg = String::new();
    match draw_scatter(&mut svg, title, x_desc, y_desc, &p, points, trend) {
        Ok(()) => svg,
        Err(e) => notice(title, &format!("cannot draw: {e}")),
    }
}

fn draw_scatter(
    svg: &mut String,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    logp: &[(f64, f64)],
    points: &[(f64, f64)],
    trend: bool,
) -> Drawn {
    let min = |f: fn(&(f64, f64)) -> f64| logp.iter().map(f).fold(f64::INFINITY, f64::min);
    let max = |f: fn(&(f64, f64)) -> f64| logp.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
    let (x0, x1) = span(min(|q| q.0), max(|q| q.0), 0.25);
    let (y0, y1) = span(min(|q| q.1), max(|q| q.1), 0.25);
    let (px, py) = (0.03 * (x1 - x0), 0.05 * (y1 - y0));
    let root = SVGBackend::with_string(svg, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(50)
        .build_cartesian_2d(x0 - px..x1 + px, y0 - py..y1 + py)?;
    let fmt = |v: &f64| short(10f64.powf(*v));
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(6)
        .y_labels(6)
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .light_line_style(WHITE)
        .draw()?;
    chart.draw_series(
        logp.iter()
            .map(|&(x, y)| Circle::new((x, y), 3, INK.mix(0.5).filled())),
    )?;
    if trend {
        let b = buckets(points);
        let line = |f: fn(&Bucket) -> f64| -> Vec<(f64, f64)> {
            b.iter().map(|q| (q.x.log10(), f(q).log10())).collect()
        };
        chart
            .draw_series(LineSeries::new(line(|q| q.median), MEDIAN.stroke_width(2)))?
            .label("median per bucket")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], MEDIAN.stroke_width(2)));
        chart
            .draw_series(LineSeries::new(line(|q| q.p95), P95.stroke_width(2)))?
            .label("p95 per bucket")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], P95.stroke_width(2)));
        if let Some(f) = fit(points) {
            let ends = [x0, x1].map(|x| (x, f.log_c + f.k * x));
            chart
                .draw_series(LineSeries::new(ends, BLACK.mix(0.6)))?
                .label(format!("fit: exponent {:.2}", f.k))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLACK.mix(0.6)));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK.mix(0.3))
            .label_font(("sans-serif", 12))
            .draw()?;
    }
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_a_power_law() {
        let pts: Vec<(f64, f64)> = (1..50)
            .map(|i| {
                let x = f64::from(i) * 10.0;
                (x, 0.002 * x.powf(1.5))
            })
            .collect();
        let f = fit(&pts).expect("fit");
        assert!((f.k - 1.5).abs() < 1e-9, "{f:?}");
        assert!((f.log_c - 0.002f64.log10()).abs() < 1e-9, "{f:?}");
        assert!(fit(&[(3.0, 1.0), (3.0, 2.0)]).is_none());
        assert!(fit(&[]).is_none());
    }

    #[test]
    fn buckets_by_powers_of_two() {
        let pts = [(1.0, 1.0), (3.0, 5.0), (2.0, 3.0), (100.0, 7.0), (0.0, 1.0)];
        let b = buckets(&pts);
        assert_eq!(b.len(), 3, "{b:?}");
        assert_eq!(
            (b[1].from, b[1].count, b[1].median, b[1].p95),
            (2.0, 2, 3.0, 5.0)
        );
        assert_eq!(b[2].from, 64.0);
    }

    #[test]
    fn plots_draw_or_say_why() {
        let h = histogram("time", "s", &[0.1, 0.2, 0.2, 5.0], Axis::Log);
        assert!(h.starts_with("<svg") && h.contains("<rect"), "{h}");
        let c = histogram("one", "x", &[3.0], Axis::Log);
        assert!(c.starts_with("<svg"), "a constant sample still draws");
        let e = histogram("none", "x", &[f64::NAN], Axis::Log);
        assert!(e.contains("no data"), "{e}");
        let s = scatter("t vs n", "n", "t", &[(10.0, 0.1), (100.0, 1.0)], true);
        assert!(s.starts_with("<svg") && s.contains("exponent 1.00"), "{s}");
        let s = scatter("t vs n", "n", "t", &[], true);
        assert!(s.contains("no data"));
        assert_eq!(bin(&[0.0, 1.0, 0.5, -3.0, 9.0], 0.0, 1.0, 2), vec![2, 3]);
    }

    #[test]
    fn short_labels() {
        assert_eq!(short(0.0), "0");
        assert_eq!(short(1500.0), "1500");
        assert_eq!(short(631.0), "630");
        assert_eq!(short(25000.0), "25k");
        assert_eq!(short(2_500_000.0), "2.5M");
        assert_eq!(short(2.5), "2.5");
        assert_eq!(short(3.98), "4");
        assert_eq!(short(0.0316), "0.032");
        assert_eq!(short(0.15849), "0.16");
    }
}
