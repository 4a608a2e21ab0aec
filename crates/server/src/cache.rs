//! The PVS cache and its bounded worker pool.
//!
//! On-line PVS computation is the expensive part of a walkthrough (dual ray space paper,
//! §6: 12.5 s per 100 m cell on their machine). Requests for cells therefore go through
//! one [`PvsCache`]:
//! * a least-recently-used map keyed by cell id, bounded by the total number of ids it
//!   holds (so memory is bounded whatever the PVS sizes);
//! * one computation per cell at a time, however many sessions wait for it;
//! * a fixed number of worker threads (the only place methods run), taking jobs by
//!   priority — a client standing in a cell it has no PVS for ([`Priority::Demand`]),
//!   then the cell a client is heading into ([`Priority::Ahead`]), then the other cells it
//!   may enter next ([`Priority::Prefetch`]);
//! * stale work is dropped: a queued job whose every waiter has gone (the session moved on
//!   and cancelled its request, or disconnected) is skipped instead of computed;
//! * a bounded prefetch queue: when it is full new prefetches are refused (counted) rather
//!   than letting the backlog, and the latency of demands behind it, grow without bound.

use crate::grid::CellId;
use crate::source::{SharedSource, SourceError};
use serde::Serialize;
use std::collections::{BTreeMap, BinaryHeap, HashMap};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Instant;
use tokio::sync::oneshot;

/// A cell's PVS, shared between the cache and the sessions.
pub type Pvs = Arc<Vec<u32>>;

/// Who is waiting for a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Priority {
    /// A client is in the cell (or an HTTP query asks for it).
    Demand = 0,
    /// A client is heading into the cell: the neighbour its direction of motion reaches.
    Ahead = 1,
    /// A client may enter the cell next.
    Prefetch = 2,
}

/// Why a PVS could not be had.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum CacheError {
    #[error(transparent)]
    Source(#[from] SourceError),
    #[error("server busy: prefetch queue full")]
    Busy,
    #[error("server shutting down")]
    Shutdown,
}

/// Sizes of the cache and pool.
#[derive(Clone, Debug)]
pub struct CacheConfig {
    /// Worker threads computing PVS.
    pub workers: usize,
    /// Most object ids held by the cache over all cells.
    pub max_ids: usize,
    /// Most queued prefetch jobs.
    pub max_prefetch_queue: usize,
}

impl Default for CacheConfig {
    fn default() -> Self {
        CacheConfig {
            workers: std::thread::available_parallelism().map_or(2, |n| n.get()),
            max_ids: 32 << 20,
            max_prefetch_queue: 4096,
        }
    }
}

/// Counters, for `/api/stats` and the benchmarks.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CacheStats {
    pub hits: u64,
    pub misses: u64,
    pub computed: u64,
    pub refused: u64,
    /// Queued jobs dropped because nobody waited for them any more.
    pub cancelled: u64,
    pub errors: u64,
    pub compute_ms_total: f64,
    pub compute_ms_max: f64,
    pub cached_cells: usize,
    pub cached_ids: usize,
    pub queued: usize,
}

type Waiter = oneshot::Sender<Result<Pvs, CacheError>>;

struct InFlight {
    waiters: Vec<Waiter>,
    prio: Priority,
    running: bool,
}

#[derive(PartialEq, Eq)]
struct Job {
    prio: Priority,
    seq: u64,
    cell: CellId,
}

impl Ord for Job {
    // BinaryHeap is a max-heap: the best job is the lowest priority value, then the oldest.
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        o.prio.cmp(&self.prio).then(o.seq.cmp(&self.seq))
    }
}
impl PartialOrd for Job {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

/// Least-recently-used map bounded by the total number of ids.
#[derive(Default)]
struct Lru {
    map: HashMap<CellId, (Pvs, u64)>,
    order: BTreeMap<u64, CellId>,
    tick: u64,
    ids: usize,
}

impl Lru {
    fn get(&mut self, k: CellId) -> Option<Pvs> {
        let (v, t) = self.map.get_mut(&k)?;
        self.order.remove(t);
        self.tick += 1;
        *t = self.tick;
        self.order.insert(self.tick, k);
        Some(v.clone())
    }

    fn insert(&mut self, k: CellId, v: Pvs, max_ids: usize) {
        if let Some((old, t)) = self.map.remove(&k) {
            self.order.remove(&t);
            self.ids -= old.len() + 1;
        }
        // Every entry counts at least 1 so that empty sets are bounded too.
        while self.ids + v.len() + 1 > max_ids {
            let Some((_, victim)) = self.order.pop_first() else {
                break;
            };
            if let Some((old, _)) = self.map.remove(&victim) {
                self.ids -= old.len() + 1;
            }
        }
        self.tick += 1;
        self.ids += v.len() + 1;
        self.order.insert(self.tick, k);
        self.map.insert(k, (v, self.tick));
    }
}

#[derive(Default)]
struct Inner {
    lru: Lru,
    inflight: HashMap<CellId, InFlight>,
    queue: BinaryHeap<Job>,
    seq: u64,
    queued_prefetch: usize,
}

struct Shared {
    source: SharedSource,
    config: CacheConfig,
    inner: Mutex<Inner>,
    work: Condvar,
    stop: AtomicBool,
    hits: AtomicU64,
    misses: AtomicU64,
    computed: AtomicU64,
    refused: AtomicU64,
    cancelled: AtomicU64,
    errors: AtomicU64,
    compute_us_total: AtomicU64,
    compute_us_max: AtomicU64,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Inner> {
        // A worker never panics while holding the lock (source calls run unlocked), but
        // recover rather than cascade if it ever happens.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// The cache and worker pool in front of a [`crate::source::PvsSource`].
pub struct PvsCache {
    shared: Arc<Shared>,
    workers: Mutex<Vec<std::thread::JoinHandle<()>>>,
}

impl PvsCache {
    pub fn new(source: SharedSource, config: CacheConfig) -> Arc<Self> {
        let workers = config.workers.max(1);
        let shared = Arc::new(Shared {
            source,
            config,
            inner: Mutex::new(Inner::default()),
            work: Condvar::new(),
            stop: AtomicBool::new(false),
            hits: AtomicU64::new(0),
            misses: AtomicU64::new(0),
            computed: AtomicU64::new(0),
            refused: AtomicU64::new(0),
            cancelled: AtomicU64::new(0),
            errors: AtomicU64::new(0),
            compute_us_total: AtomicU64::new(0),
            compute_us_max: AtomicU64::new(0),
        });
        let handles = (0..workers)
            .filter_map(|i| {
                let s = shared.clone();
                std::thread::Builder::new()
                    .name(format!("pvs-worker-{i}"))
                    .spawn(move || worker(s))
                    .ok()
            })
            .collect();
        Arc::new(PvsCache {
            shared,
            workers: Mutex::new(handles),
        })
    }

    pub fn source(&self) -> &SharedSource {
        &self.shared.source
    }

    /// The PVS of `cell` if it is cached (counts as a hit, refreshes its age).
    pub fn peek(&self, cell: CellId) -> Option<Pvs> {
        self.shared.lock().lru.get(cell)
    }

    /// The PVS of `cell`, computing it if needed. Dropping the future before it is answered
    /// withdraws the request: a job nobody waits for any more is not computed.
    pub async fn get(&self, cell: CellId, prio: Priority) -> Result<Pvs, CacheError> {
        let rx = {
            let mut g = self.shared.lock();
            if let Some(v) = g.lru.get(cell) {
                self.shared.hits.fetch_add(1, Ordering::Relaxed);
                return Ok(v);
            }
            if self.shared.stop.load(Ordering::Relaxed) {
                return Err(CacheError::Shutdown);
            }
            let (tx, rx) = oneshot::channel();
            let inner = &mut *g;
            match inner.inflight.get_mut(&cell) {
                Some(f) => {
                    f.waiters.push(tx);
                    if prio < f.prio && !f.running {
                        // Promote: queue it again at the better priority; the stale entry
                        // is skipped when popped, so it no longer counts as a queued prefetch.
                        if f.prio == Priority::Prefetch {
                            inner.queued_prefetch -= 1;
                        }
                        f.prio = prio;
                        inner.seq += 1;
                        inner.queue.push(Job {
                            prio,
                            seq: inner.seq,
                            cell,
                        });
                        self.shared.work.notify_one();
                    }
                }
                None => {
                    if prio == Priority::Prefetch
                        && inner.queued_prefetch >= self.shared.config.max_prefetch_queue
                    {
                        self.shared.refused.fetch_add(1, Ordering::Relaxed);
                        return Err(CacheError::Busy);
                    }
                    if prio == Priority::Prefetch {
                        inner.queued_prefetch += 1;
                    }
                    self.shared.misses.fetch_add(1, Ordering::Relaxed);
                    inner.inflight.insert(
                        cell,
                        InFlight {
                            waiters: vec![tx],
                            prio,
                            running: false,
                        },
                    );
                    inner.seq += 1;
                    inner.queue.push(Job {
                        prio,
                        seq: inner.seq,
                        cell,
                    });
                    self.shared.work.notify_one();
                }
            }
            rx
        };
        rx.await.unwrap_or(Err(CacheError::Shutdown))
    }

    pub fn stats(&self) -> CacheStats {
        let s = &self.shared;
        let g = s.lock();
        CacheStats {
            hits: s.hits.load(Ordering::Relaxed),
            misses: s.misses.load(Ordering::Relaxed),
            computed: s.computed.load(Ordering::Relaxed),
            refused: s.refused.load(Ordering::Relaxed),
            cancelled: s.cancelled.load(Ordering::Relaxed),
            errors: s.errors.load(Ordering::Relaxed),
            compute_ms_total: s.compute_us_total.load(Ordering::Relaxed) as f64 / 1000.0,
            compute_ms_max: s.compute_us_max.load(Ordering::Relaxed) as f64 / 1000.0,
            cached_cells: g.lru.map.len(),
            cached_ids: g.lru.ids,
            queued: g.queue.len(),
        }
    }

    /// Stop the workers: queued jobs fail with [`CacheError::Shutdown`], running ones
    /// finish. Idempotent; also run on drop.
    pub fn shutdown(&self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        {
            let mut g = self.shared.lock();
            g.queue.clear();
            for (_, f) in g.inflight.drain() {
                for w in f.waiters {
                    let _ = w.send(Err(CacheError::Shutdown));
                }
            }
        }
        self.shared.work.notify_all();
        let handles = std::mem::take(&mut *self.workers.lock().unwrap_or_else(|p| p.into_inner()));
        for h in handles {
            let _ = h.join();
        }
    }
}

impl Drop for PvsCache {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn worker(s: Arc<Shared>) {
    loop {
        let cell = {
            let mut g = s.lock();
            loop {
                if s.stop.load(Ordering::SeqCst) {
                    return;
                }
                match g.queue.pop() {
                    Some(job) => {
                        let inner = &mut *g;
                        let Some(f) = inner.inflight.get_mut(&job.cell) else {
                            continue; // stale duplicate of a finished job
                        };
                        if f.running || f.prio != job.prio {
                            continue; // stale entry of a promoted job
                        }
                        if job.prio == Priority::Prefetch {
                            inner.queued_prefetch -= 1;
                        }
                        if f.waiters.iter().all(|w| w.is_closed()) {
                            // Every requester withdrew: drop the job.
                            inner.inflight.remove(&job.cell);
                            s.cancelled.fetch_add(1, Ordering::Relaxed);
                            continue;
                        }
                        f.running = true;
                        break job.cell;
                    }
                    None => g = s.work.wait(g).unwrap_or_else(|p| p.into_inner()),
                }
            }
        };
        let t = Instant::now();
        // A panicking method must not take the server down: it becomes an error answer.
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| s.source.pvs(cell)))
            .unwrap_or_else(|_| Err(SourceError::Method("the method panicked".into())));
        let us = t.elapsed().as_micros() as u64;
        s.compute_us_total.fetch_add(us, Ordering::Relaxed);
        s.compute_us_max.fetch_max(us, Ordering::Relaxed);
        let result = result.map(Arc::new).map_err(CacheError::from);
        let waiters = {
            let mut g = s.lock();
            let f = g.inflight.remove(&cell);
            match &result {
                Ok(v) => {
                    s.computed.fetch_add(1, Ordering::Relaxed);
                    let max = s.config.max_ids;
                    g.lru.insert(cell, v.clone(), max);
                }
                Err(_) => {
                    s.errors.fetch_add(1, Ordering::Relaxed);
                }
            }
            f.map(|f| f.waiters).unwrap_or_default()
        };
        for w in waiters {
            let _ = w.send(result.clone());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::CellGrid;
    use crate::source::{PvsSource, SourceInfo};
    use sightline_geom::{Aabb3, DVec3};
    use std::sync::atomic::AtomicUsize;

    /// A source that returns `[cell]` and counts its calls; cell 13 fails, 14 panics.
    struct Counting {
        grid: CellGrid,
        calls: AtomicUsize,
    }
    impl PvsSource for Counting {
        fn info(&self) -> SourceInfo {
            SourceInfo {
                kind: "online",
                method: "test".into(),
                conservative: true,
                params: vec![],
            }
        }
        fn layout(&self) -> crate::layout::Layout<'_> {
            crate::layout::Layout::Grid(&self.grid)
        }
        fn pvs(&self, id: CellId) -> Result<Vec<u32>, SourceError> {
            self.calls.fetch_add(1, Ordering::SeqCst);
            std::thread::sleep(std::time::Duration::from_millis(5));
            match id {
                13 => Err(SourceError::Method("boom".into())),
                14 => panic!("method bug"),
                _ => Ok(vec![id]),
            }
        }
    }

    fn cache(max_ids: usize, max_prefetch_queue: usize) -> (Arc<Counting>, Arc<PvsCache>) {
        let b = Aabb3::new(DVec3::ZERO, DVec3::new(100.0, 100.0, 10.0));
        let src = Arc::new(Counting {
            grid: CellGrid::cover(&b, 10.0).unwrap(),
            calls: AtomicUsize::new(0),
        });
        let c = PvsCache::new(
            src.clone(),
            CacheConfig {
                workers: 2,
                max_ids,
                max_prefetch_queue,
            },
        );
        (src, c)
    }

    #[tokio::test]
    async fn computes_each_cell_once_for_many_waiters() {
        let (src, c) = cache(1000, 100);
        let futs: Vec<_> = (0..20)
            .map(|i| {
                let c = c.clone();
                let prio = if i % 2 == 0 {
                    Priority::Prefetch
                } else {
                    Priority::Demand
                };
                tokio::spawn(async move { c.get(7, prio).await })
            })
            .collect();
        for f in futs {
            assert_eq!(*f.await.unwrap().unwrap(), vec![7]);
        }
        assert_eq!(src.calls.load(Ordering::SeqCst), 1);
        assert_eq!(*c.get(7, Priority::Demand).await.unwrap(), vec![7]);
        assert_eq!(src.calls.load(Ordering::SeqCst), 1);
        assert!(c.stats().hits >= 1);
    }

    #[tokio::test]
    async fn errors_and_panics_become_answers() {
        let (_src, c) = cache(1000, 100);
        assert!(matches!(
            c.get(13, Priority::Demand).await,
            Err(CacheError::Source(SourceError::Method(_)))
        ));
        assert!(matches!(
            c.get(14, Priority::Demand).await,
            Err(CacheError::Source(SourceError::Method(_)))
        ));
        // The pool still works afterwards.
        assert_eq!(*c.get(3, Priority::Demand).await.unwrap(), vec![3]);
        assert_eq!(c.stats().errors, 2);
    }

    #[tokio::test]
    async fn evicts_least_recently_used_within_the_id_budget() {
        let (src, c) = cache(6, 100); // 3 cells of 1 id (+1 each)
        for k in [1, 2, 3] {
            c.get(k, Priority::Demand).await.unwrap();
        }
        c.get(1, Priority::Demand).await.unwrap(); // 1 is now the most recent
        c.get(4, Priority::Demand).await.unwrap(); // evicts 2
        let s = c.stats();
        assert_eq!(s.cached_cells, 3);
        assert!(s.cached_ids <= 6);
        let before = src.calls.load(Ordering::SeqCst);
        c.get(1, Priority::Demand).await.unwrap();
        assert_eq!(src.calls.load(Ordering::SeqCst), before, "1 still cached");
        c.get(2, Priority::Demand).await.unwrap();
        assert_eq!(
            src.calls.load(Ordering::SeqCst),
            before + 1,
            "2 was evicted"
        );
    }

    #[tokio::test]
    async fn refuses_prefetch_beyond_the_queue_bound_but_never_demand() {
        let (_src, c) = cache(10_000, 2);
        let mut handles = vec![];
        for k in 20..40 {
            let c = c.clone();
            handles.push(tokio::spawn(
                async move { c.get(k, Priority::Prefetch).await },
            ));
        }
        let mut refused = 0;
        for h in handles {
            if h.await.unwrap() == Err(CacheError::Busy) {
                refused += 1;
            }
        }
        assert!(refused > 0);
        assert_eq!(c.stats().refused, refused);
        assert_eq!(*c.get(50, Priority::Demand).await.unwrap(), vec![50]);
    }

    #[tokio::test]
    async fn withdrawn_requests_are_not_computed() {
        let (src, c) = cache(1000, 100);
        // Keep both workers busy with demands, queue a request and withdraw it.
        let demands: Vec<_> = (1..=4)
            .map(|k| {
                let c = c.clone();
                tokio::spawn(async move { c.get(k, Priority::Demand).await })
            })
            .collect();
        tokio::time::sleep(std::time::Duration::from_millis(1)).await;
        let r = tokio::time::timeout(
            std::time::Duration::from_millis(0),
            c.get(30, Priority::Ahead),
        )
        .await;
        assert!(r.is_err(), "not answered yet: the workers are busy");
        for d in demands {
            d.await.unwrap().unwrap();
        }
        tokio::time::sleep(std::time::Duration::from_millis(30)).await;
        let s = c.stats();
        assert_eq!(s.cancelled, 1);
        assert_eq!(s.computed, 4);
        assert_eq!(src.calls.load(Ordering::SeqCst), 4);
        // Asked again, it is computed.
        assert_eq!(*c.get(30, Priority::Prefetch).await.unwrap(), vec![30]);
    }

    #[test]
    fn jobs_pop_demand_then_ahead_then_prefetch_oldest_first() {
        let mut q = BinaryHeap::new();
        for (seq, (cell, prio)) in [
            (40, Priority::Prefetch),
            (41, Priority::Ahead),
            (42, Priority::Prefetch),
            (43, Priority::Demand),
            (44, Priority::Ahead),
        ]
        .into_iter()
        .enumerate()
        {
            q.push(Job {
                prio,
                seq: seq as u64,
                cell,
            });
        }
        let order: Vec<CellId> = std::iter::from_fn(|| q.pop().map(|j| j.cell)).collect();
        assert_eq!(order, vec![43, 41, 44, 40, 42]);
    }

    #[tokio::test]
    async fn shutdown_fails_waiters_instead_of_hanging() {
        let (_src, c) = cache(1000, 100);
        c.shutdown();
        assert_eq!(c.get(5, Priority::Demand).await, Err(CacheError::Shutdown));
    }
}
