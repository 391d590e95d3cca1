//! The passes' queues: the collapse round's shortest-first edge queue
//! ([`ShortestFirst`], with batches of the edges queued again staged to be
//! planned together) and the plans made ahead in parallel for the next items
//! of a pass ([`PlanAhead`]). A plan made ahead is used only while what it
//! read is unchanged, so a pass does the same for any number of threads.

use super::{PLAN_AHEAD, SUMMARY_STEP, SUMMARY_TOP};
use crate::mesh::EdgeKey;
use dary_heap::QuaternaryHeap;
use rayon::prelude::*;
use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// How long the pool's other threads wait, spinning, for a pass's next
/// window of plans ([`KeepAwake`]) before they go to sleep.
const SPIN_FOR: Duration = Duration::from_micros(500);

/// The collapse round's queue: edges by the bits of their length (which order
/// like the lengths), then by key. The edges short at the start of the round
/// are sorted once (cheaper than a heap of all of them); the edges queued
/// again after a collapse go to a heap; with more than one thread, the
/// smallest of those are taken from the heap a batch at a time
/// ([`ShortestFirst::stage`]) to be planned together, each batch kept in order
/// with its plans. `pop` takes the smallest of the three heads, so the order
/// is that of one heap holding them all.
pub(super) struct ShortestFirst<P = ()> {
    pub(super) sorted: Vec<(u64, EdgeKey)>,
    next: usize,
    /// Summaries of `sorted`, made by [`Self::sort`]: `summary[0]` holds
    /// every [`SUMMARY_STEP`]-th entry of `sorted` (from its first), each
    /// further level every [`SUMMARY_STEP`]-th entry of the one below, up to
    /// one of at most [`SUMMARY_TOP`] entries. [`Self::is_ahead`] searches
    /// the top level, then one block of each level below and of `sorted`.
    summary: Vec<Vec<(u64, EdgeKey)>>,
    /// A 4-ary heap: the same pops as a binary one (the order of the keys
    /// decides them), with half its levels, so a pop misses the cache at
    /// fewer levels (a binary heap's pops were some 5 % of a large run).
    pub(super) again: QuaternaryHeap<std::cmp::Reverse<(u64, EdgeKey)>>,
    /// Edges taken from `again` in order, each with its plan made ahead.
    staged: VecDeque<(u64, EdgeKey, Option<P>)>,
}

impl<P> Default for ShortestFirst<P> {
    fn default() -> Self {
        ShortestFirst {
            sorted: Vec::new(),
            next: 0,
            summary: Vec::new(),
            again: QuaternaryHeap::new(),
            staged: VecDeque::new(),
        }
    }
}

/// Sort `v`, in parallel when the pool has more than one thread (a
/// parallel sort on one thread only costs more).
pub(super) fn sort_unstable<T: Ord + Send>(v: &mut [T]) {
    sort_unstable_by(v, T::cmp);
}

/// [`sort_unstable`] by `compare`.
pub(super) fn sort_unstable_by<T: Send>(
    v: &mut [T],
    compare: impl Fn(&T, &T) -> std::cmp::Ordering + Sync,
) {
    if rayon::current_num_threads() > 1 {
        v.par_sort_unstable_by(compare);
    } else {
        v.sort_unstable_by(compare);
    }
}

/// Where [`ShortestFirst::pop_indexed`] took an edge from.
pub(super) enum Popped<P> {
    /// `sorted`, at this index.
    Sorted(usize),
    /// `staged`, with its plan.
    Staged(Option<P>),
    /// `again`: not planned.
    Again,
}

/// The number of entries of `sorted` below `key`, found through its
/// summaries (`summary[0]` every [`SUMMARY_STEP`]-th entry of `sorted`, each
/// further level every [`SUMMARY_STEP`]-th entry of the one below).
fn place_in(
    summary: &[Vec<(u64, EdgeKey)>],
    sorted: &[(u64, EdgeKey)],
    key: (u64, EdgeKey),
) -> usize {
    // At each level, `j` entries are below `key`; with level[i] =
    // below[i · step], below[(j - 1) · step] < key <= below[j · step] (where
    // those exist): the count in the level below lies in between.
    let mut levels = summary.iter().rev().map(Vec::as_slice).chain([sorted]);
    let Some(top) = levels.next() else {
        return 0;
    };
    let mut j = top.partition_point(|s| *s < key);
    for below in levels {
        let lo = if j == 0 {
            0
        } else {
            (j - 1) * SUMMARY_STEP + 1
        };
        let hi = (j * SUMMARY_STEP).min(below.len());
        j = lo + below[lo..hi].partition_point(|s| *s < key);
    }
    j
}

impl<P> ShortestFirst<P> {
    pub(super) fn sort(&mut self) {
        sort_unstable(&mut self.sorted);
        self.next = 0;
        self.summary.clear();
        let mut below: &[(u64, EdgeKey)] = &self.sorted;
        while below.len() > SUMMARY_TOP {
            let level: Vec<_> = below.iter().step_by(SUMMARY_STEP).copied().collect();
            self.summary.push(level);
            below = self.summary.last().map_or(&[], Vec::as_slice);
        }
    }

    /// Whether `key` is in `sorted[next..]`. A binary search of all of
    /// `sorted` (megabytes on a large drawing) misses the cache at most of its
    /// steps, on the pipeline's thread, for every edge queued again. Below
    /// the head nothing is ahead (most of the edges queued again that are not
    /// duplicates); otherwise the summaries' searches, top level first,
    /// narrow `key`'s place down to a block of each level below, so each
    /// search stays within a few cache lines.
    fn is_ahead(&self, key: (u64, EdgeKey)) -> bool {
        match self.sorted.get(self.next) {
            Some(&head) if head <= key => {}
            _ => return false,
        }
        let at = place_in(&self.summary, &self.sorted, key);
        at >= self.next && self.sorted.get(at) == Some(&key)
    }

    /// Which head is the smallest: 0 `sorted`, 1 `staged`, 2 `again` (on a tie
    /// the first; equal heads are the same edge). On every pop: compared by
    /// hand, not through a `min_by_key` over three options.
    fn smallest(&self) -> Option<usize> {
        let heads = [
            self.sorted.get(self.next).copied(),
            self.staged.front().map(|&(b, k, _)| (b, k)),
            self.again.peek().map(|r| r.0),
        ];
        let mut which = None;
        let mut best = None;
        for (i, head) in heads.into_iter().enumerate() {
            if let Some(h) = head
                && best.is_none_or(|b| h < b)
            {
                (which, best) = (Some(i), Some(h));
            }
        }
        which
    }

    /// Whether the next edge comes from `again`: the moment to
    /// [`Self::stage`] a batch (before what is staged already: a collapse
    /// queues the short edges at its vertex, shorter than the staged ones
    /// more often than not; waiting until the staged batch ran out would leave
    /// hundreds of thousands of edges queued again on a large drawing to be
    /// planned one by one on the pipeline's thread).
    pub(super) fn next_is_unstaged(&self) -> bool {
        self.smallest() == Some(2)
    }

    /// Take the `n` smallest edges of `again` (fewer if it holds fewer, and
    /// only those before the first staged edge), in order, for the caller to
    /// plan and [`Self::push_staged`].
    pub(super) fn stage(&mut self, n: usize) -> Vec<(u64, EdgeKey)> {
        let bound = self.staged.front().map(|&(b, k, _)| (b, k));
        let mut batch = Vec::new();
        while batch.len() < n
            && let Some(r) = self.again.peek()
            && bound.is_none_or(|b| r.0 < b)
        {
            batch.push(r.0);
            self.again.pop();
        }
        batch
    }

    /// Queue `key` again, unless it is still ahead in `sorted`: that copy
    /// comes first (on a tie `sorted` wins) and the copy queued again would
    /// come right after it, with nothing changed in between, only to be
    /// skipped. About half the edges queued again after a collapse are such
    /// duplicates: the round's positions do
    /// not change, so an edge of u's ring kept its length and its key.
    pub(super) fn push_again(&mut self, key: (u64, EdgeKey)) {
        if !self.is_ahead(key) {
            self.again.push(std::cmp::Reverse(key));
        }
    }

    /// Put staged edges (the output of [`Self::stage`], in its order) with
    /// their plans before those staged already.
    pub(super) fn push_staged(
        &mut self,
        batch: impl IntoIterator<Item = (u64, EdgeKey, Option<P>)>,
    ) {
        let batch: Vec<_> = batch.into_iter().collect();
        for item in batch.into_iter().rev() {
            self.staged.push_front(item);
        }
    }

    /// The next edge, with where it came from.
    pub(super) fn pop_indexed(&mut self) -> Option<(u64, EdgeKey, Popped<P>)> {
        match self.smallest()? {
            0 => {
                self.next += 1;
                let (b, k) = self.sorted[self.next - 1];
                Some((b, k, Popped::Sorted(self.next - 1)))
            }
            1 => self
                .staged
                .pop_front()
                .map(|(b, k, plan)| (b, k, Popped::Staged(plan))),
            _ => self.again.pop().map(|r| (r.0.0, r.0.1, Popped::Again)),
        }
    }
}

/// Keeps the pool's other threads awake between a pass's windows of plans.
///
/// A pass plans a window in parallel, then applies it on the pipeline's
/// thread alone, and the other threads, finding no work, go to sleep within
/// some tens of microseconds; waking one for the next window costs some ten
/// microseconds more, on every window (measured here: a 210 µs window took
/// 120 µs on two threads, 108 µs with the second one kept awake; the ten
/// slowest dev drawings plan some 100 000 windows at two threads). So after
/// each window the other threads are handed a job that spins until the next
/// window starts (or [`SPIN_FOR`] has passed, after which they sleep). It
/// touches no data: the plans, and so the meshes, are the same.
struct KeepAwake {
    /// Bumped when a window starts (and when the pass ends): the spinning
    /// jobs of an older value return.
    epoch: Arc<AtomicU64>,
    /// The pool's other threads.
    others: usize,
    /// [`SPIN_FOR`] (tests: longer).
    spin_for: Duration,
    /// Tests: how many spinning jobs returned because a window started or the
    /// pass ended (not because their time was up).
    #[cfg(test)]
    stopped: Arc<std::sync::atomic::AtomicUsize>,
}

impl KeepAwake {
    fn new() -> Self {
        KeepAwake {
            epoch: Arc::new(AtomicU64::new(0)),
            others: rayon::current_num_threads().saturating_sub(1),
            spin_for: SPIN_FOR,
            #[cfg(test)]
            stopped: Arc::default(),
        }
    }

    /// Run `window` (a parallel section) with the spinning jobs stopped
    /// first, then hand the other threads new ones.
    fn window<R>(&self, window: impl FnOnce() -> R) -> R {
        let e = self.epoch.fetch_add(1, Ordering::SeqCst) + 1;
        let out = window();
        for _ in 0..self.others {
            let epoch = Arc::clone(&self.epoch);
            let spin_for = self.spin_for;
            #[cfg(test)]
            let stopped = Arc::clone(&self.stopped);
            rayon::spawn(move || {
                let _by_epoch = spin(&epoch, e, spin_for);
                #[cfg(test)]
                if _by_epoch {
                    stopped.fetch_add(1, Ordering::SeqCst);
                }
            });
        }
        out
    }
}

/// Spin while `epoch` holds `e`, for `spin_for` at most; whether it stopped
/// because `epoch` changed. Work that reaches the pool meanwhile (a parallel
/// section other than a window) is taken on the way, so it never waits for
/// the spinning to end.
fn spin(epoch: &AtomicU64, e: u64, spin_for: Duration) -> bool {
    let start = Instant::now();
    // (the clock read every 64 turns: a read costs some 20 ns)
    let mut turns = 0u32;
    loop {
        if epoch.load(Ordering::Relaxed) != e {
            return true;
        }
        if rayon::yield_now() != Some(rayon::Yield::Executed) {
            std::hint::spin_loop();
        }
        turns = turns.wrapping_add(1);
        if turns % 64 == 0 && start.elapsed() > spin_for {
            return false;
        }
    }
}

impl Drop for KeepAwake {
    fn drop(&mut self) {
        // The parallel sections after the pass's windows (its statistics)
        // must not wait for a spinning thread.
        self.epoch.fetch_add(1, Ordering::SeqCst);
    }
}

/// Plans made ahead, in parallel, for the next [`PLAN_AHEAD`] items of a
/// pass's queue (see [`Schedule::collapse_round`](super::Schedule::collapse_round)); none with one thread.
pub(super) struct PlanAhead<T> {
    pub(super) parallel: bool,
    /// The queue index of `plans[0]`.
    from: usize,
    plans: Vec<Option<T>>,
    /// With more than one thread.
    awake: Option<KeepAwake>,
}

impl<T: Send> PlanAhead<T> {
    pub(super) fn new() -> Self {
        let parallel = rayon::current_num_threads() > 1;
        PlanAhead {
            parallel,
            from: 0,
            plans: Vec::new(),
            awake: parallel.then(KeepAwake::new),
        }
    }

    /// Run the parallel section `window` (a batch of plans), keeping the
    /// pool's other threads awake for the next one ([`KeepAwake`]).
    pub(super) fn window<R>(&self, window: impl FnOnce() -> R) -> R {
        match &self.awake {
            Some(awake) => awake.window(window),
            None => window(),
        }
    }

    /// The plan of `items[n]`, planning `items[n..n + PLAN_AHEAD]` at once
    /// first when `n` is past the window planned; `None` with one thread
    /// (and where `plan` made none).
    pub(super) fn take<I: Sync>(
        &mut self,
        n: usize,
        items: &[I],
        plan: impl Fn(&I) -> Option<T> + Sync + Send,
    ) -> Option<T> {
        if !self.parallel {
            return None;
        }
        if n >= self.from + self.plans.len() {
            let end = (n + PLAN_AHEAD).min(items.len());
            // Into the same buffer: a large drawing plans thousands of windows.
            let mut plans = std::mem::take(&mut self.plans);
            plans.clear();
            self.window(|| plans.par_extend(items[n..end].par_iter().map(plan)));
            self.plans = plans;
            self.from = n;
        }
        self.plans.get_mut(n - self.from).and_then(Option::take)
    }
}

#[cfg(test)]
mod queue_tests {
    use super::*;
    use crate::mesh::VertexId;
    use proptest::prelude::*;
    use std::collections::BinaryHeap;

    /// A spinning job returns once the epoch moves, and only then (or when
    /// its time is up).
    #[test]
    fn spinning_stops_when_the_epoch_moves() {
        let epoch = Arc::new(AtomicU64::new(7));
        let e2 = Arc::clone(&epoch);
        let spinner = std::thread::spawn(move || spin(&e2, 7, Duration::from_secs(60)));
        std::thread::sleep(Duration::from_millis(20));
        assert!(!spinner.is_finished(), "returned with the epoch unchanged");
        epoch.fetch_add(1, Ordering::SeqCst);
        assert!(
            spinner.join().unwrap(),
            "returned by its time, not the epoch"
        );
        // Time up: returns, not stopped by the epoch.
        assert!(!spin(&epoch, 8, Duration::from_millis(1)));
    }

    /// On two threads every window hands the other thread a spinning job; the
    /// next window stops it, and the end of the pass stops the last (none of
    /// them runs until its time is up, here a minute). With one thread there
    /// is none.
    #[test]
    fn windows_stop_the_spinning_jobs_before_them_and_the_pass_the_last() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let stopped = pool.install(|| {
            let mut awake = KeepAwake::new();
            awake.spin_for = Duration::from_secs(60);
            let stopped = Arc::clone(&awake.stopped);
            let mut sums = Vec::new();
            for w in 0..5u64 {
                sums.push(awake.window(|| (0..1000 * w).into_par_iter().sum::<u64>()));
            }
            let want: Vec<u64> = (0..5u64).map(|w| (0..1000 * w).sum()).collect();
            assert_eq!(sums, want);
            drop(awake);
            stopped
        });
        // The pool's threads end their jobs before it is gone; wait for the
        // five counts (a broken stop would take five minutes and fail).
        let start = Instant::now();
        while stopped.load(Ordering::SeqCst) < 5 && start.elapsed() < Duration::from_secs(30) {
            std::thread::sleep(Duration::from_millis(5));
        }
        assert_eq!(stopped.load(Ordering::SeqCst), 5);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        one.install(|| {
            let ahead = PlanAhead::<u32>::new();
            assert!(ahead.awake.is_none() && !ahead.parallel);
        });
    }

    fn key(a: usize, b: usize) -> EdgeKey {
        EdgeKey::new(VertexId::from_index(a), VertexId::from_index(b + 100))
    }

    proptest! {
        /// The collapse round's queue pops what one min-heap holding all its
        /// parts would, pushes during the pops included (duplicates too), and
        /// batches staged from the heap at any step.
        #[test]
        fn the_queue_pops_like_one_heap(
            start in prop::collection::vec((0u64..20, 0usize..5, 0usize..5), 0..40),
            pushes in prop::collection::vec((0usize..60, 0u64..20, 0usize..5, 0usize..5), 0..30),
            stages in prop::collection::vec((0usize..60, 1usize..6), 0..10),
        ) {
            let mut q = ShortestFirst::<u64>::default();
            let mut heap = BinaryHeap::new();
            for &(bits, a, b) in &start {
                q.sorted.push((bits, key(a, b)));
                heap.push(std::cmp::Reverse((bits, key(a, b))));
            }
            q.sort();
            let mut step = 0;
            loop {
                for &(at, bits, a, b) in &pushes {
                    if at == step {
                        q.again.push(std::cmp::Reverse((bits, key(a, b))));
                        heap.push(std::cmp::Reverse((bits, key(a, b))));
                    }
                }
                for &(at, n) in &stages {
                    if at == step && q.next_is_unstaged() {
                        // The plan of a staged edge is its bits: it must come
                        // back with its own edge.
                        let batch = q.stage(n);
                        q.push_staged(batch.into_iter().map(|(b, k)| (b, k, Some(b))));
                    }
                }
                let popped = q.pop_indexed();
                if let Some((b, _, Popped::Staged(plan))) = &popped {
                    prop_assert_eq!(*plan, Some(*b));
                }
                let (x, y) = (popped.map(|(b, k, _)| (b, k)), heap.pop().map(|r| r.0));
                prop_assert_eq!(x, y);
                if x.is_none() && step > 60 {
                    break;
                }
                step += 1;
            }
        }

        /// Queued with `push_again`, an edge still ahead in `sorted` is not
        /// queued at all; anything else is, as in one heap: the queue pops
        /// what one min-heap would with that rule applied to each push (its
        /// own record of the sorted edges not yet popped), batches staged at
        /// any step included.
        #[test]
        fn pushing_again_skips_the_edges_still_ahead_in_sorted(
            start in prop::collection::vec((0u64..20, 0usize..5, 0usize..5), 0..40),
            pushes in prop::collection::vec((0usize..60, 0u64..20, 0usize..5, 0usize..5), 0..30),
            stages in prop::collection::vec((0usize..60, 1usize..6), 0..10),
        ) {
            // The round's sorted edges are distinct.
            let start: std::collections::BTreeSet<(u64, EdgeKey)> =
                start.iter().map(|&(bits, a, b)| (bits, key(a, b))).collect();
            let mut q = ShortestFirst::<u64>::default();
            let mut heap = BinaryHeap::new();
            let mut ahead = start.clone();
            for &k in &start {
                q.sorted.push(k);
                heap.push(std::cmp::Reverse((k, true)));
            }
            q.sort();
            for step in 0..200 {
                for &(at, bits, a, b) in &pushes {
                    if at == step {
                        let k = (bits, key(a, b));
                        q.push_again(k);
                        if !ahead.contains(&k) {
                            heap.push(std::cmp::Reverse((k, false)));
                        }
                    }
                }
                for &(at, n) in &stages {
                    if at == step && q.next_is_unstaged() {
                        let batch = q.stage(n);
                        q.push_staged(batch.into_iter().map(|(b, k)| (b, k, Some(b))));
                    }
                }
                let x = q.pop_indexed().map(|(b, k, _)| (b, k));
                let y = heap.pop().map(|r| {
                    if r.0.1 {
                        ahead.remove(&r.0.0);
                    }
                    r.0.0
                });
                prop_assert_eq!(x, y);
            }
        }
    }

    proptest! {
        /// `is_ahead` (the summary, then a block) answers what a search of
        /// `sorted[next..]` does, on lists of many blocks, with runs of
        /// equal bits, for keys in the list, between its entries and beyond
        /// both ends, at any `next`.
        #[test]
        fn is_ahead_finds_what_a_search_of_the_rest_finds(
            start in prop::collection::btree_set((0u64..400, 0usize..8, 0usize..8), 0..700),
            next_at in 0.0f64..1.0,
            probes in prop::collection::vec((0u64..420, 0usize..8, 0usize..8), 1..60),
            from_list in prop::collection::vec(any::<prop::sample::Index>(), 0..60),
        ) {
            let mut q = ShortestFirst::<u64> {
                sorted: start.iter().map(|&(bits, a, b)| (bits, key(a, b))).collect(),
                ..ShortestFirst::default()
            };
            q.sort();
            let n = q.sorted.len();
            q.next = ((n as f64) * next_at) as usize;
            let mut keys: Vec<(u64, EdgeKey)> =
                probes.iter().map(|&(bits, a, b)| (bits, key(a, b))).collect();
            if n > 0 {
                keys.extend(from_list.iter().map(|i| q.sorted[i.index(n)]));
            }
            for k in keys {
                prop_assert_eq!(
                    q.is_ahead(k),
                    q.sorted[q.next..].binary_search(&k).is_ok(),
                    "{:?} with next {} of {}", k, q.next, n
                );
            }
        }
    }

    /// The summaries' search finds the place a plain binary search of
    /// `sorted` finds, with no summary, one level and several (a sorted list
    /// of 300 000 edges has three levels above it), for keys present,
    /// absent, between blocks and past both ends.
    #[test]
    fn the_summaries_find_the_place_a_binary_search_finds() {
        for n in [0usize, 1, 2, 17, 1024, 1025, 16 * 1024 + 1, 300_000] {
            // even bits, some repeated with other keys: every odd bits value
            // is absent, and equal bits order by the key
            let mut q = ShortestFirst::<u64> {
                sorted: (0..n)
                    .map(|i| ((i / 3 * 2) as u64, key(i % 3, 0)))
                    .collect(),
                ..ShortestFirst::default()
            };
            q.sort();
            let levels = q.summary.len();
            assert!(n <= SUMMARY_TOP || levels > 0, "{n}: no summary");
            assert!(q.summary.last().is_none_or(|t| t.len() <= SUMMARY_TOP));
            let probes = (0..n.min(5_000))
                .chain((0..200).map(|i| i * n.max(1) / 200))
                .chain([n, n + 1]);
            for i in probes {
                let b = (i / 3 * 2) as u64;
                for k in [
                    (b, key(i % 3, 0)),
                    (b + 1, key(0, 0)),
                    (b, key(4, 4)),
                    (b.wrapping_sub(1), key(4, 4)),
                    (u64::MAX, key(4, 4)),
                ] {
                    assert_eq!(
                        place_in(&q.summary, &q.sorted, k),
                        q.sorted.partition_point(|s| *s < k),
                        "{k:?} in {n} with {levels} levels"
                    );
                }
            }
        }
    }

    /// The rule of `push_again` itself: an edge still ahead in `sorted` is
    /// not queued; one popped already is, and so is one never sorted.
    #[test]
    fn an_edge_still_ahead_is_not_queued_again() {
        let mut q = ShortestFirst::<u64> {
            sorted: vec![(1, key(0, 0)), (2, key(1, 1))],
            ..ShortestFirst::default()
        };
        q.sort();
        q.push_again((2, key(1, 1)));
        assert!(q.again.is_empty());
        assert_eq!(
            q.pop_indexed().map(|(b, k, _)| (b, k)),
            Some((1, key(0, 0)))
        );
        q.push_again((1, key(0, 0)));
        q.push_again((2, key(0, 0)));
        assert_eq!(q.again.len(), 2);
    }
}

#[cfg(test)]
mod plan_ahead_tests {
    use crate::mesh::TriMesh;
    use crate::ops::{Context, Objective};
    use crate::optimize::schedule::driver::mesh_bounds;
    use crate::optimize::schedule::scope::Scope;
    use crate::optimize::schedule::stats::measure;
    use crate::optimize::schedule::{COARSEN_FACTOR, Schedule, test_meshes, test_options};
    use crate::sizing::SizeField;

    /// The passes with their plans made ahead on two threads do exactly what
    /// they do on one (same mesh, same tallies), and the plans were used and
    /// some found stale (else the check would be vacuous).
    #[test]
    fn planning_ahead_on_two_threads_changes_nothing() {
        let meshes: Vec<_> = test_meshes(3, 2).collect();
        let opts = test_options();
        let run = |threads: usize, mesh: &TriMesh, ctx: &Context| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            pool.install(|| {
                let (mut mesh, mut ctx) = (mesh.clone(), ctx.clone());
                let field = SizeField::uniform(opts.limits.l, mesh_bounds(&mesh));
                let mut s = Schedule::new(&mut mesh, &mut ctx, &opts, 7, &field);
                let whole = &mut Scope::Whole;
                for pass in 0..6 {
                    s.split_pass(whole);
                    s.collapse_pass(whole, if pass < 3 { 0.8 } else { COARSEN_FACTOR });
                    s.swap_pass(whole);
                    s.smooth_pass(whole);
                    s.smooth_pass_with(whole, Objective::MinMax);
                    let worst = measure(s.mesh).max_energy;
                    s.update_sizing(worst);
                }
                let (stats, tally) = (s.stats().clone(), (s.tally.ahead, s.tally.staged));
                (mesh, stats, tally)
            })
        };
        let (mut used, mut stale, mut staged) = (0, 0, 0);
        for (i, (mesh, ctx)) in meshes.iter().enumerate() {
            let (one, stats_one, tally_one) = run(1, mesh, ctx);
            let (two, stats_two, tally_two) = run(2, mesh, ctx);
            assert!(one == two, "mesh {i}: two threads made another mesh");
            assert_eq!(stats_one, stats_two, "mesh {i}");
            assert_eq!(
                tally_one,
                ((0, 0), 0),
                "mesh {i}: one thread plans nothing ahead"
            );
            used += tally_two.0.0;
            stale += tally_two.0.1;
            staged += tally_two.1;
        }
        assert!(
            used > 1000 && stale > 10 && staged > 100,
            "{used} plans used, {stale} stale, {staged} staged"
        );
    }
}
