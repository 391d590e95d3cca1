//! Resource budgets of one run: the input size limits the loader checks before
//! usvg builds its tree ([`Limits`]), and the wall-clock [`Deadline`] the
//! pipeline's loops check cooperatively (issue 17: a huge input fails with one
//! clear line instead of exhausting memory or running for hours).
//!
//! The values come from `Params` (`--max-segments`, `--max-shapes`,
//! `--max-memory`, `--time-limit`; defaults in `params::defaults`).

use std::time::{Duration, Instant};

/// Input size limits: checked on the XML text before usvg builds its tree, and
/// again on the loaded drawing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Limits {
    /// Most path segments (path commands' segments, polygon / polyline points,
    /// basic shapes' sides), `<use>` copies included.
    pub(crate) max_segments: u64,
    /// Most drawable elements (paths and basic shapes), `<use>` copies included.
    pub(crate) max_shapes: u64,
    /// Most memory, MiB, that the run is estimated to need (see
    /// [`Limits::estimate_mb`]); also bounds the document's text after XML
    /// entity expansion.
    pub(crate) max_memory_mb: u64,
}

/// Bytes of peak memory per input segment the estimate assumes: the feature
/// soup, the BSP's exact vertices and the optimized mesh it grows into
/// (measured: 1-3 KiB per segment at the default `-l`, e.g. 28 MB peak for
/// the dev set's largest drawing, 16 896 segments; 260 MB in the BSP of a
/// 100 000-segment path).
pub(crate) const BYTES_PER_SEGMENT: u64 = 4 << 10;
/// Bytes per drawable element (usvg node, source match, shape record).
pub(crate) const BYTES_PER_SHAPE: u64 = 4 << 10;
/// Memory of a run on a tiny drawing: fonts, code, the thread stacks in use.
pub(crate) const BASE_BYTES: u64 = 64 << 20;

impl Limits {
    /// No budget at all (the loader's public functions without `Params`).
    pub(crate) const NONE: Limits = Limits {
        max_segments: u64::MAX,
        max_shapes: u64::MAX,
        max_memory_mb: u64::MAX,
    };

    /// The estimated peak memory, MiB, of a run on `text_bytes` of XML text
    /// holding `segments` segments in `shapes` elements.
    pub(crate) fn estimate_mb(text_bytes: u64, segments: u64, shapes: u64) -> u64 {
        let bytes = BASE_BYTES
            .saturating_add(text_bytes.saturating_mul(4))
            .saturating_add(segments.saturating_mul(BYTES_PER_SEGMENT))
            .saturating_add(shapes.saturating_mul(BYTES_PER_SHAPE));
        bytes.div_ceil(1 << 20)
    }
}

/// A wall-clock limit: when it has passed, the next check in the pipeline's
/// loops stops the run with a time-limit error (nothing is written).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Deadline {
    at: Option<Instant>,
    seconds: f64,
}

impl Deadline {
    /// No limit.
    pub(crate) const NONE: Deadline = Deadline {
        at: None,
        seconds: f64::INFINITY,
    };

    /// `seconds` from now (`None`: no limit).
    pub(crate) fn after(seconds: Option<f64>) -> Deadline {
        match seconds.and_then(|s| Duration::try_from_secs_f64(s).ok()) {
            Some(d) => Deadline {
                at: Instant::now().checked_add(d),
                seconds: d.as_secs_f64(),
            },
            None => Deadline::NONE,
        }
    }

    /// Whether the limit has passed.
    pub(crate) fn expired(&self) -> bool {
        self.at.is_some_and(|at| Instant::now() >= at)
    }

    /// The limit as given, seconds (infinite without one).
    pub(crate) fn seconds(&self) -> f64 {
        self.seconds
    }
}

/// The process's peak resident memory so far, in MiB (`VmHWM` of
/// `/proc/self/status`); `None` where the system does not report it (not
/// Linux). For `--stats` and the benches: a whole process's high-water mark,
/// the Python interpreter's own included when triwild runs inside it.
pub(crate) fn peak_memory_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_vm_hwm(&status)
}

/// `VmHWM` (kB) of a `/proc/<pid>/status` text, in MiB.
fn parse_vm_hwm(status: &str) -> Option<f64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let mut words = line["VmHWM:".len()..].split_whitespace();
    let kb: f64 = words.next()?.parse().ok()?;
    (words.next() == Some("kB") && kb.is_finite()).then_some(kb / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deadlines_expire_and_none_never_does() {
        assert!(!Deadline::NONE.expired());
        assert!(!Deadline::after(None).expired());
        assert!(!Deadline::after(Some(3600.0)).expired());
        assert!(Deadline::after(Some(0.0)).expired());
        assert_eq!(Deadline::after(Some(2.5)).seconds(), 2.5);
        // not representable: no limit rather than a panic
        assert!(!Deadline::after(Some(f64::INFINITY)).expired());
    }

    #[test]
    fn estimate_grows_with_counts() {
        let small = Limits::estimate_mb(1000, 10, 1);
        assert!((64..80).contains(&small), "{small}");
        let big = Limits::estimate_mb(120 << 20, 10_000_000, 1);
        assert!(big > 30_000, "{big}");
        assert_eq!(
            Limits::estimate_mb(u64::MAX, u64::MAX, u64::MAX),
            u64::MAX.div_ceil(1 << 20)
        );
    }

    #[test]
    fn vm_hwm_is_read_in_mib() {
        let status =
            "Name:\ttriwild\nVmPeak:\t  300000 kB\nVmHWM:\t   10240 kB\nVmRSS:\t 5000 kB\n";
        assert_eq!(parse_vm_hwm(status), Some(10.0));
        assert_eq!(parse_vm_hwm("VmHWM:\t 12 MB\n"), None);
        assert_eq!(parse_vm_hwm("Name: x\n"), None);
        if cfg!(target_os = "linux") {
            let mb = peak_memory_mb().expect("Linux reports VmHWM");
            assert!(mb > 0.1 && mb < 1e6, "{mb}");
        }
    }
}
