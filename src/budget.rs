//! Resource budgets of one run: the input size limits the loader checks before
//! usvg builds its tree ([`Limits`]), and the [`Deadline`] the pipeline's loops
//! check cooperatively: a wall-clock limit (`--time-limit`) and a memory limit
//! (`--max-memory`, and the limits set from outside the process: an
//! address-space rlimit, a cgroup's `memory.max`) on the process's memory as
//! the kernel reports it: a huge input fails with one clear line instead of
//! exhausting memory or running for hours.
//!
//! The memory check reads `/proc/self/status` at most once every
//! [`SAMPLE_INTERVAL`] (the loops ask far more often; a cached reading answers
//! in between), and [`reserve`] checks a large buffer against the limit before
//! it is allocated, and allocates it fallibly: a failed allocation is an
//! [`Overrun`], never an abort.
//!
//! The values come from `Params` (`--max-segments`, `--max-shapes`,
//! `--max-memory`, `--time-limit`; defaults in `params::defaults`).

use std::collections::TryReserveError;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};
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

/// The budget a run's loops check cooperatively: a wall-clock limit and a
/// memory limit. When either is passed, the next check in the pipeline's loops
/// stops the run with a time-limit or memory-limit error (nothing is written).
///
/// The memory limit is on the process's resident memory: its high-water mark
/// (`VmHWM`, which never goes down, so a stage that stopped early because of
/// it is still over the limit when the pipeline asks which limit it was),
/// unless the process was past the limit before the run began (an embedding
/// process that ran a larger job before); then its current resident memory.
/// Limits set from outside (`ulimit -v`, a cgroup) are checked with a margin
/// ([`OUTSIDE_MARGIN`]) so that the run stops before an allocation fails.
///
/// An overrun that a reading taken later might not show again (an address
/// space that shrank once a buffer was freed, a buffer [`reserve`] refused) is
/// latched for the run (its `run` number): every later check of the run sees
/// it, so a stage that stopped early because of it is never taken as complete.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Deadline {
    at: Option<Instant>,
    seconds: f64,
    memory: Option<MemoryLimit>,
    /// The run's number for the latch (0: none, nothing is latched).
    run: u64,
}

/// The memory limit of a run (see [`Deadline`]).
#[derive(Clone, Copy, Debug, PartialEq)]
struct MemoryLimit {
    /// `--max-memory`, KiB.
    max_kb: u64,
    /// Whether the process's high-water mark was within `max_kb` when the run
    /// began (then it is the measure; otherwise the current resident memory).
    by_peak: bool,
}

/// Which limit a run's memory reached.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MemorySource {
    /// `--max-memory` (resident memory).
    MaxMemory,
    /// The process's address-space limit (`ulimit -v`, `prlimit --as`).
    AddressSpace,
    /// The memory limit of the process's cgroup (`memory.max`: a container, a
    /// Slurm job).
    Cgroup,
}

impl MemorySource {
    /// How a message names the limit.
    pub(crate) fn flag(self) -> &'static str {
        match self {
            MemorySource::MaxMemory => "--max-memory",
            MemorySource::AddressSpace => "the address-space limit, ulimit -v",
            MemorySource::Cgroup => "the cgroup's memory.max",
        }
    }
}

/// Why a run must stop: what [`Deadline::check`] and [`reserve`] report; the
/// error module names the stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Overrun {
    /// The wall-clock limit (seconds) passed.
    Time {
        /// The limit, seconds.
        seconds: f64,
    },
    /// The process's memory reached a limit.
    Memory {
        /// The limit, MiB.
        limit_mb: u64,
        /// Which limit.
        source: MemorySource,
    },
    /// An allocation of `bytes` failed (the system had no more to give).
    Allocation {
        /// The size asked for.
        bytes: u64,
    },
}

/// How often, at most, the memory check reads `/proc/self/status`.
pub(crate) const SAMPLE_INTERVAL: Duration = Duration::from_millis(2);
/// The fraction of an outside limit (address space, cgroup) at which a run
/// stops: the rest is left for the allocations made between two checks and
/// for the error path.
pub(crate) const OUTSIDE_MARGIN: f64 = 0.85;

impl Deadline {
    /// No limit.
    pub(crate) const NONE: Deadline = Deadline {
        at: None,
        seconds: f64::INFINITY,
        memory: None,
        run: 0,
    };

    /// `seconds` from now (`None`: no limit), no memory limit.
    pub(crate) fn after(seconds: Option<f64>) -> Deadline {
        match seconds.and_then(|s| Duration::try_from_secs_f64(s).ok()) {
            Some(d) => Deadline {
                at: Instant::now().checked_add(d),
                seconds: d.as_secs_f64(),
                memory: None,
                run: 0,
            },
            None => Deadline::NONE,
        }
    }

    /// This deadline with a memory limit of `max_mb` MiB (`--max-memory`),
    /// the outside limits (address space, cgroup) checked with it.
    pub(crate) fn with_memory_mb(mut self, max_mb: u64) -> Deadline {
        let max_kb = max_mb.saturating_mul(1024);
        let by_peak = read_memory().is_none_or(|m| m.hwm_kb <= max_kb);
        self.memory = Some(MemoryLimit { max_kb, by_peak });
        self.run = NEXT_RUN.fetch_add(1, Ordering::Relaxed);
        self
    }

    /// Whether the run must stop: the time limit has passed or the memory
    /// limit is reached (a reading at most [`SAMPLE_INTERVAL`] old).
    pub(crate) fn expired(&self) -> bool {
        self.time_passed()
            || (self.memory.is_some()
                && (self.latched().is_some() || self.over_now(sample_memory())))
    }

    /// [`Self::expired`] for the inside of a stage's loops, asked every few
    /// dozen items: the time, and an overrun some other check has already
    /// latched, without a reading of the process's memory (one costs some
    /// 20 µs; the loops' passes and their large allocations read it).
    pub(crate) fn expired_in_loop(&self) -> bool {
        self.time_passed() || (self.memory.is_some() && self.latched().is_some())
    }

    /// Whether reading `m` is past a memory limit (latched if so).
    fn over_now(&self, m: Option<MemorySample>) -> bool {
        match self.memory_over(m) {
            Some(over) => {
                self.latch(over);
                true
            }
            None => false,
        }
    }

    /// What the run has overrun, if anything (a fresh memory reading).
    pub(crate) fn check(&self) -> Result<(), Overrun> {
        if self.memory.is_some() {
            if let Some(over) = self.latched() {
                return Err(over);
            }
            if let Some(over) = self.memory_over(read_memory().map(MemorySample::store)) {
                self.latch(over);
                return Err(over);
            }
        }
        if self.time_passed() {
            return Err(Overrun::Time {
                seconds: self.seconds,
            });
        }
        Ok(())
    }

    /// Whether `bytes` more would take the run past its memory limit (the
    /// memory in use now plus `bytes`): checked before a large allocation.
    pub(crate) fn check_room(&self, bytes: u64) -> Result<(), Overrun> {
        if self.memory.is_none() {
            return Ok(());
        }
        let Some(now) = read_memory().map(MemorySample::store) else {
            return Ok(());
        };
        let kb = bytes.div_ceil(1024);
        let after = MemorySample {
            rss_kb: now.rss_kb.saturating_add(kb),
            hwm_kb: now.hwm_kb.max(now.rss_kb.saturating_add(kb)),
            vm_kb: now.vm_kb.saturating_add(kb),
        };
        match self.memory_over(Some(after)) {
            Some(over) => {
                self.latch(over);
                Err(over)
            }
            None => Ok(()),
        }
    }

    /// Keep `over` as this run's overrun (the first one stays).
    fn latch(&self, over: Overrun) {
        if self.run == 0 {
            return;
        }
        let mut latched = LATCHED.lock().unwrap_or_else(|e| e.into_inner());
        if !latched.iter().any(|&(run, _)| run == self.run) {
            latched.push((self.run, over));
            ANY_LATCHED.store(true, Ordering::Release);
        }
    }

    /// This run's latched overrun, if any.
    fn latched(&self) -> Option<Overrun> {
        if self.run == 0 || !ANY_LATCHED.load(Ordering::Acquire) {
            return None;
        }
        let latched = LATCHED.lock().unwrap_or_else(|e| e.into_inner());
        latched
            .iter()
            .find(|&&(run, _)| run == self.run)
            .map(|&(_, over)| over)
    }

    /// Forget this run's latched overrun: the run is over (the pipeline calls
    /// it once the run's result is known, so the latch does not grow).
    pub(crate) fn finish(&self) {
        if self.run == 0 || !ANY_LATCHED.load(Ordering::Acquire) {
            return;
        }
        let mut latched = LATCHED.lock().unwrap_or_else(|e| e.into_inner());
        latched.retain(|&(run, _)| run != self.run);
        ANY_LATCHED.store(!latched.is_empty(), Ordering::Release);
    }

    fn time_passed(&self) -> bool {
        self.at.is_some_and(|at| Instant::now() >= at)
    }

    /// The limit `m` is past, if any.
    fn memory_over(&self, m: Option<MemorySample>) -> Option<Overrun> {
        let limit = self.memory?;
        let m = m?;
        let used_kb = if limit.by_peak { m.hwm_kb } else { m.rss_kb };
        if used_kb > limit.max_kb {
            return Some(Overrun::Memory {
                limit_mb: limit.max_kb / 1024,
                source: MemorySource::MaxMemory,
            });
        }
        let outside = outside_limits();
        let past = |used_kb: u64, limit_kb: Option<u64>| {
            limit_kb.is_some_and(|l| used_kb as f64 > l as f64 * OUTSIDE_MARGIN)
        };
        if past(m.vm_kb, outside.address_space_kb) {
            return Some(Overrun::Memory {
                limit_mb: outside.address_space_kb.unwrap_or(0) / 1024,
                source: MemorySource::AddressSpace,
            });
        }
        if past(m.rss_kb, outside.cgroup_kb) {
            return Some(Overrun::Memory {
                limit_mb: outside.cgroup_kb.unwrap_or(0) / 1024,
                source: MemorySource::Cgroup,
            });
        }
        None
    }
}

/// Drop `value` on a thread of its own (inline if no thread can be started).
/// For the large structures a stage holds when it stops at its budget: the
/// error goes out at once instead of after their teardown (5.3 s of frees
/// after the deadline on a BSP of 4.3 million exact vertices). The
/// command line exits without waiting for that thread; an embedding process
/// gets the memory back when it is done.
pub(crate) fn dispose<T: Send + 'static>(value: T) {
    let spawned = std::thread::Builder::new()
        .name("triwild-dispose".into())
        .spawn(move || drop(value));
    // A thread that could not be started dropped `value` already.
    drop(spawned);
}

/// Make room for `additional` more elements in `v` within `deadline`'s memory
/// limit, fallibly: a buffer that would take the run past its limit, or that
/// the system cannot give, is an [`Overrun`] (the allocation is not tried in
/// the first case), never an abort; the overrun is latched, so the stage's
/// loops stop at their next check and the pipeline reports it. For the large
/// buffers of the stages (meshes, feature soups, crossing lists); small ones
/// are left to the loops' checks. Without a memory limit (no run to latch
/// for) a failed allocation aborts as [`Vec::reserve`] does.
pub(crate) fn reserve<T>(
    v: &mut Vec<T>,
    additional: usize,
    deadline: &Deadline,
) -> Result<(), Overrun> {
    let free = v.capacity() - v.len();
    if additional <= free {
        return Ok(());
    }
    let bytes = (additional as u64).saturating_mul(size_of::<T>() as u64);
    if bytes >= LARGE_BYTES {
        deadline.check_room(bytes)?;
    }
    if deadline.run == 0 {
        v.reserve(additional);
        return Ok(());
    }
    v.try_reserve(additional).map_err(|e: TryReserveError| {
        tracing::debug!("allocation of {bytes} bytes failed: {e}");
        let over = Overrun::Allocation { bytes };
        deadline.latch(over);
        over
    })
}

/// The next run number (see [`Deadline`]'s latch).
static NEXT_RUN: AtomicU64 = AtomicU64::new(1);
/// The overruns latched, by run; [`Deadline::finish`] forgets a run's.
static LATCHED: Mutex<Vec<(u64, Overrun)>> = Mutex::new(Vec::new());
/// Whether [`LATCHED`] holds anything (the loops' checks skip the lock).
static ANY_LATCHED: AtomicBool = AtomicBool::new(false);

/// A buffer at least this large is checked against the memory limit before
/// [`reserve`] allocates it.
pub(crate) const LARGE_BYTES: u64 = 1 << 20;

/// One reading of the process's memory, KiB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct MemorySample {
    /// Resident now (`VmRSS`).
    rss_kb: u64,
    /// Resident at most so far (`VmHWM`).
    hwm_kb: u64,
    /// Address space (`VmSize`).
    vm_kb: u64,
}

/// The last reading, shared by every thread: when it was taken (nanoseconds
/// after [`epoch`], 0 for never) and its values.
static LAST_AT_NS: AtomicU64 = AtomicU64::new(0);
static LAST_RSS_KB: AtomicU64 = AtomicU64::new(0);
static LAST_HWM_KB: AtomicU64 = AtomicU64::new(0);
static LAST_VM_KB: AtomicU64 = AtomicU64::new(0);

/// The instant readings are timed from.
fn epoch() -> Instant {
    static EPOCH: OnceLock<Instant> = OnceLock::new();
    *EPOCH.get_or_init(Instant::now)
}

impl MemorySample {
    /// Keep `self` as the last reading; returns it.
    fn store(self) -> MemorySample {
        LAST_RSS_KB.store(self.rss_kb, Ordering::Relaxed);
        LAST_HWM_KB.store(self.hwm_kb, Ordering::Relaxed);
        LAST_VM_KB.store(self.vm_kb, Ordering::Relaxed);
        let ns = u64::try_from(epoch().elapsed().as_nanos()).unwrap_or(u64::MAX);
        LAST_AT_NS.store(ns.max(1), Ordering::Release);
        self
    }
}

/// A reading at most [`SAMPLE_INTERVAL`] old (the cached one, or a new one).
fn sample_memory() -> Option<MemorySample> {
    let at = LAST_AT_NS.load(Ordering::Acquire);
    let now = u64::try_from(epoch().elapsed().as_nanos()).unwrap_or(u64::MAX);
    if at != 0 && now.saturating_sub(at) < SAMPLE_INTERVAL.as_nanos() as u64 {
        return Some(MemorySample {
            rss_kb: LAST_RSS_KB.load(Ordering::Relaxed),
            hwm_kb: LAST_HWM_KB.load(Ordering::Relaxed),
            vm_kb: LAST_VM_KB.load(Ordering::Relaxed),
        });
    }
    read_memory().map(MemorySample::store)
}

/// A fresh reading of `/proc/self/status`; `None` where the system has none.
fn read_memory() -> Option<MemorySample> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_memory(&status)
}

/// `VmRSS`, `VmHWM` and `VmSize` of a `/proc/<pid>/status` text.
fn parse_memory(status: &str) -> Option<MemorySample> {
    Some(MemorySample {
        rss_kb: status_kb(status, "VmRSS:")?,
        hwm_kb: status_kb(status, "VmHWM:")?,
        vm_kb: status_kb(status, "VmSize:")?,
    })
}

/// The value of the `key` line of a `/proc/<pid>/status` text, KiB.
fn status_kb(status: &str, key: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with(key))?;
    let mut words = line[key.len()..].split_whitespace();
    let kb: u64 = words.next()?.parse().ok()?;
    (words.next() == Some("kB")).then_some(kb)
}

/// The memory limits set from outside the process, KiB; read once.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct OutsideLimits {
    /// The soft address-space rlimit (`Max address space` of
    /// `/proc/self/limits`).
    address_space_kb: Option<u64>,
    /// The `memory.max` of the process's cgroup (v2).
    cgroup_kb: Option<u64>,
}

fn outside_limits() -> OutsideLimits {
    static LIMITS: OnceLock<OutsideLimits> = OnceLock::new();
    *LIMITS.get_or_init(|| OutsideLimits {
        address_space_kb: std::fs::read_to_string("/proc/self/limits")
            .ok()
            .and_then(|t| parse_address_space_kb(&t)),
        cgroup_kb: cgroup_memory_max_kb(),
    })
}

/// The soft `Max address space` of a `/proc/<pid>/limits` text, KiB
/// (`None`: unlimited or not there).
fn parse_address_space_kb(limits: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft = line["Max address space".len()..]
        .split_whitespace()
        .next()?;
    soft.parse::<u64>().ok().map(|bytes| bytes / 1024)
}

/// The `memory.max` of this process's cgroup (v2), KiB; `None` for `max` or
/// when there is none.
fn cgroup_memory_max_kb() -> Option<u64> {
    let cgroup = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = cgroup.lines().find_map(|l| l.strip_prefix("0::"))?;
    let max = std::fs::read_to_string(format!("/sys/fs/cgroup{}/memory.max", path.trim())).ok()?;
    max.trim().parse::<u64>().ok().map(|bytes| bytes / 1024)
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

    /// What [`dispose`] is given is dropped, off the caller's thread.
    #[test]
    fn disposed_values_are_dropped_on_another_thread() {
        struct Tell(std::sync::mpsc::Sender<std::thread::ThreadId>);
        impl Drop for Tell {
            fn drop(&mut self) {
                let _ = self.0.send(std::thread::current().id());
            }
        }
        let (tx, rx) = std::sync::mpsc::channel();
        dispose(Tell(tx));
        let dropped_on = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("dropped within a minute");
        assert_ne!(dropped_on, std::thread::current().id());
    }

    #[test]
    fn deadlines_expire_and_none_never_does() {
        assert!(!Deadline::NONE.expired());
        assert!(!Deadline::after(None).expired());
        assert!(!Deadline::after(Some(3600.0)).expired());
        assert!(Deadline::after(Some(0.0)).expired());
        assert_eq!(
            Deadline::after(Some(0.0)).check(),
            Err(Overrun::Time { seconds: 0.0 })
        );
        // not representable: no limit rather than a panic
        assert!(!Deadline::after(Some(f64::INFINITY)).expired());
    }

    #[test]
    fn memory_readings_are_parsed_in_kib() {
        let status = "Name:\ttriwild\nVmPeak:\t  300000 kB\nVmSize:\t  250000 kB\n\
                      VmHWM:\t   10240 kB\nVmRSS:\t 5000 kB\n";
        assert_eq!(
            parse_memory(status),
            Some(MemorySample {
                rss_kb: 5000,
                hwm_kb: 10240,
                vm_kb: 250000
            })
        );
        assert_eq!(
            parse_memory("VmRSS:\t 12 MB\nVmHWM: 1 kB\nVmSize: 1 kB\n"),
            None
        );
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max cpu time              unlimited            unlimited            seconds\n\
                      Max address space         2147483648           unlimited            bytes\n";
        assert_eq!(parse_address_space_kb(limits), Some(2 << 20));
        let unlimited =
            "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(parse_address_space_kb(unlimited), None);
    }

    #[test]
    fn memory_limit_stops_a_run_past_it_and_not_within_it() {
        if read_memory().is_none() {
            return; // not Linux: no reading, no memory check
        }
        // Far above anything a test process uses: never expired.
        let roomy = Deadline::NONE.with_memory_mb(1 << 30);
        assert!(!roomy.expired());
        assert_eq!(roomy.check(), Ok(()));
        assert_eq!(roomy.check_room(1 << 20), Ok(()));
        // 1 MiB: every test process is past it.
        let tiny = Deadline::NONE.with_memory_mb(1);
        assert!(tiny.expired());
        match tiny.check() {
            Err(Overrun::Memory { limit_mb, source }) => {
                assert_eq!((limit_mb, source), (1, MemorySource::MaxMemory));
            }
            other => panic!("{other:?}"),
        }
        tiny.finish();
        // A buffer that would not fit is refused before it is allocated, and
        // the refusal is latched until the run finishes.
        let used_mb = read_memory().map_or(0, |m| m.hwm_kb.max(m.rss_kb) / 1024);
        let run = Deadline::NONE.with_memory_mb(used_mb + 512);
        let mut v: Vec<u8> = Vec::new();
        assert_eq!(reserve(&mut v, 1 << 10, &run), Ok(()));
        assert!(v.capacity() >= 1 << 10);
        let mut big: Vec<u64> = Vec::new();
        assert!(matches!(
            reserve(&mut big, 1 << 28, &run),
            Err(Overrun::Memory { .. })
        ));
        assert_eq!(big.capacity(), 0, "nothing allocated");
        assert!(run.expired(), "latched");
        assert!(run.check().is_err());
        run.finish();
        assert!(!run.expired());
        // Another run is not affected by this one's latch.
        let other = Deadline::NONE.with_memory_mb(used_mb + 512);
        let _ = reserve(&mut big, 1 << 28, &other);
        assert!(!run.expired());
        other.finish();
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
