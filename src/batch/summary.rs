//! The closing summary of a batch: files ok and failed by cause, time
//! percentiles, triangle counts and the worst quality, as a plain-text table.

use super::report::{Cause, Row, Status};
use std::collections::BTreeMap;
use std::fmt;

/// Percentiles of a sample (nearest rank).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Percentiles {
    /// Median.
    pub p50: f64,
    /// 90th percentile.
    pub p90: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Maximum.
    pub max: f64,
    /// Sum.
    pub sum: f64,
}

impl Percentiles {
    /// The percentiles of `values`; `None` if empty.
    pub fn of(mut values: Vec<f64>) -> Option<Self> {
        if values.is_empty() {
            return None;
        }
        values.sort_by(f64::total_cmp);
        let at = |p: f64| {
            let rank = (p * values.len() as f64).ceil() as usize;
            values[rank.clamp(1, values.len()) - 1]
        };
        Some(Percentiles {
            p50: at(0.5),
            p90: at(0.9),
            p99: at(0.99),
            max: values[values.len() - 1],
            sum: values.iter().sum(),
        })
    }
}

/// A value and the file it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Extreme {
    /// The value.
    pub value: f64,
    /// The file's key.
    pub file: String,
}

/// What a batch did, over its report rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Summary {
    /// Files in the batch.
    pub files: usize,
    /// Files meshed.
    pub ok: usize,
    /// Failed files per cause.
    pub failed: BTreeMap<Cause, usize>,
    /// Child wall times of all files, seconds.
    pub wall: Option<Percentiles>,
    /// Triangles per meshed file.
    pub triangles: Option<Percentiles>,
    /// The smallest minimum angle (degrees) of any mesh.
    pub worst_min_angle: Option<Extreme>,
    /// The largest maximum AMIPS energy of any mesh.
    pub worst_amips: Option<Extreme>,
    /// Wall-clock time of the whole batch, seconds, if known.
    pub batch_wall: Option<f64>,
}

impl Summary {
    /// Summarize `rows` (one per file).
    pub fn of(rows: &[Row]) -> Self {
        let mut s = Summary {
            files: rows.len(),
            ..Default::default()
        };
        let worse = |slot: &mut Option<Extreme>, value: Option<f64>, file: &str, lower: bool| {
            let Some(v) = value.filter(|v| v.is_finite()) else {
                return;
            };
            let better = slot
                .as_ref()
                .is_some_and(|e| if lower { e.value <= v } else { e.value >= v });
            if !better {
                *slot = Some(Extreme {
                    value: v,
                    file: file.to_string(),
                });
            }
        };
        let mut angle = None;
        let mut amips = None;
        for r in rows {
            match r.status {
                Status::Ok => {
                    s.ok += 1;
                    worse(&mut angle, r.stat("/quality/min_angle_deg"), &r.file, true);
                    worse(&mut amips, r.stat("/quality/max_amips"), &r.file, false);
                }
                Status::Failed => {
                    *s.failed
                        .entry(r.cause.unwrap_or(Cause::Internal))
                        .or_default() += 1;
                }
            }
        }
        s.worst_min_angle = angle;
        s.worst_amips = amips;
        s.wall = Percentiles::of(rows.iter().map(|r| r.wall).collect());
        s.triangles = Percentiles::of(
            rows.iter()
                .filter_map(|r| r.triangles().map(|t| t as f64))
                .collect(),
        );
        s
    }

    /// Failed files in all.
    pub fn failed_total(&self) -> usize {
        self.failed.values().sum()
    }

    /// Record the batch's wall-clock time.
    pub fn with_batch_wall(mut self, secs: f64) -> Self {
        self.batch_wall = Some(secs);
        self
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "files      {:>8}", self.files)?;
        writeln!(f, "ok         {:>8}", self.ok)?;
        writeln!(f, "failed     {:>8}", self.failed_total())?;
        for c in Cause::ALL {
            if let Some(n) = self.failed.get(&c) {
                writeln!(f, "  {:<9}{n:>8}", c.name())?;
            }
        }
        if let Some(w) = self.batch_wall {
            writeln!(f, "wall time  {w:>8.2} s (batch)")?;
        }
        if let Some(p) = self.wall {
            writeln!(
                f,
                "per file   p50 {:.3} s  p90 {:.3} s  p99 {:.3} s  max {:.3} s  sum {:.2} s",
                p.p50, p.p90, p.p99, p.max, p.sum
            )?;
        }
        if let Some(p) = self.triangles {
            writeln!(
                f,
                "triangles  p50 {:.0}  p90 {:.0}  p99 {:.0}  max {:.0}  total {:.0}",
                p.p50, p.p90, p.p99, p.max, p.sum
            )?;
        }
        if let Some(e) = &self.worst_min_angle {
            writeln!(f, "worst min angle  {:.2}°  ({})", e.value, e.file)?;
        }
        if let Some(e) = &self.worst_amips {
            writeln!(f, "worst max AMIPS  {:.3}  ({})", e.value, e.file)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(file: &str, cause: Option<Cause>, wall: f64, tris: u64, angle: f64) -> Row {
        Row {
            file: file.into(),
            input: file.into(),
            status: if cause.is_some() {
                Status::Failed
            } else {
                Status::Ok
            },
            cause,
            message: None,
            exit_code: None,
            signal: None,
            output: None,
            wall,
            peak_rss: None,
            stats: cause.is_none().then(|| {
                serde_json::json!({"output": {"triangles": tris},
                    "quality": {"min_angle_deg": angle, "max_amips": 100.0 / angle}})
            }),
            flags: Vec::new(),
            build: None,
        }
    }

    #[test]
    fn percentiles() {
        let p = Percentiles::of((1..=100).map(f64::from).collect()).expect("nonempty");
        assert_eq!(
            (p.p50, p.p90, p.p99, p.max, p.sum),
            (50.0, 90.0, 99.0, 100.0, 5050.0)
        );
        let p = Percentiles::of(vec![3.0]).expect("nonempty");
        assert_eq!((p.p50, p.max), (3.0, 3.0));
        assert!(Percentiles::of(vec![]).is_none());
    }

    #[test]
    fn summary_counts() {
        let rows = [
            row("a", None, 1.0, 10, 30.0),
            row("b", None, 2.0, 30, 20.0),
            row("c", Some(Cause::Timeout), 9.0, 0, 0.0),
            row("d", Some(Cause::Panic), 0.5, 0, 0.0),
            row("e", Some(Cause::Timeout), 9.0, 0, 0.0),
        ];
        let s = Summary::of(&rows);
        assert_eq!((s.files, s.ok, s.failed_total()), (5, 2, 3));
        assert_eq!(s.failed.get(&Cause::Timeout), Some(&2));
        assert_eq!(s.triangles.expect("tris").sum, 40.0);
        assert_eq!(s.worst_min_angle.as_ref().expect("angle").file, "b");
        assert_eq!(s.worst_amips.as_ref().expect("amips").file, "b");
        let text = s.to_string();
        assert!(text.contains("timeout         2"), "{text}");
        assert!(text.contains("worst min angle  20.00°  (b)"), "{text}");
    }
}
