//! The bounded work pool: heavy work runs on tokio's blocking threads, at
//! most `workers` at a time, with at most `queue_depth` more waiting; past
//! that the request is refused at once with 503 and `Retry-After`. Each
//! call has a time limit; work that outlives it keeps its slot until it
//! ends (a blocking thread cannot be cancelled), so capacity stays bounded.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use tokio::sync::Semaphore;
use tracing::Instrument;

use super::problem::Problem;

/// Knobs of the pool.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoolOptions {
    /// Work items running at once (count). Default: the number of CPUs.
    pub workers: usize,
    /// Work items waiting beyond those (count). Default 16.
    pub queue_depth: usize,
    /// Seconds a caller is told to wait when the queue is full. Default 5.
    pub retry_after_s: u64,
}

impl Default for PoolOptions {
    fn default() -> Self {
        Self { workers: std::thread::available_parallelism().map_or(2, |n| n.get()), queue_depth: 16, retry_after_s: 5 }
    }
}

/// The pool (cheap to clone).
#[derive(Debug, Clone)]
pub struct WorkPool {
    opts: PoolOptions,
    permits: Arc<Semaphore>,
    /// Admitted and not finished (running + waiting).
    admitted: Arc<AtomicUsize>,
}

struct Admission(Arc<AtomicUsize>);

impl Drop for Admission {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

impl WorkPool {
    /// A pool with `opts` (at least one worker).
    pub fn new(opts: PoolOptions) -> Self {
        let opts = PoolOptions { workers: opts.workers.max(1), ..opts };
        Self { opts, permits: Arc::new(Semaphore::new(opts.workers)), admitted: Arc::new(AtomicUsize::new(0)) }
    }

    /// Work items admitted and not finished.
    pub fn depth(&self) -> usize {
        self.admitted.load(Ordering::Acquire)
    }

    /// Runs `f` on a blocking thread within the current tracing span.
    ///
    /// # Errors
    /// 503 `busy` when the queue is full, 503 `timeout` past `limit`, 500
    /// when `f` panicked (logged).
    pub async fn run<T: Send + 'static>(
        &self,
        limit: Duration,
        f: impl FnOnce() -> T + Send + 'static,
    ) -> Result<T, Problem> {
        let cap = self.opts.workers + self.opts.queue_depth;
        if self.admitted.fetch_add(1, Ordering::AcqRel) >= cap {
            self.admitted.fetch_sub(1, Ordering::AcqRel);
            return Err(Problem::busy(self.opts.retry_after_s));
        }
        let admission = Admission(Arc::clone(&self.admitted));
        let span = tracing::Span::current();
        let permits = Arc::clone(&self.permits);
        let work = async move {
            let permit = permits.acquire_owned().await.map_err(|_| Problem::internal())?;
            let handle = tokio::task::spawn_blocking(move || {
                let _permit = permit;
                let _admission = admission;
                span.in_scope(f)
            });
            handle.await.map_err(|e| {
                tracing::error!(error = %e, "work item panicked");
                Problem::internal()
            })
        };
        match tokio::time::timeout(limit, work.in_current_span()).await {
            Ok(r) => r,
            Err(_) => Err(Problem::timeout(limit, self.opts.retry_after_s)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_full_queue_answers_busy_and_drains() {
        let pool = WorkPool::new(PoolOptions { workers: 1, queue_depth: 1, retry_after_s: 7 });
        let (tx, rx) = std::sync::mpsc::channel::<()>();
        let rx = Arc::new(std::sync::Mutex::new(rx));
        let mut running = Vec::new();
        for _ in 0..2 {
            let (p, rx) = (pool.clone(), Arc::clone(&rx));
            running.push(tokio::spawn(async move {
                p.run(Duration::from_secs(30), move || rx.lock().unwrap().recv().is_ok()).await
            }));
        }
        while pool.depth() < 2 {
            tokio::task::yield_now().await;
        }
        let refused = pool.run(Duration::from_secs(1), || true).await.unwrap_err();
        assert_eq!(refused.status, 503);
        assert_eq!(refused.retry_after_s, Some(7));
        tx.send(()).unwrap();
        tx.send(()).unwrap();
        for r in running {
            assert!(r.await.unwrap().unwrap());
        }
        assert_eq!(pool.depth(), 0);
        assert!(pool.run(Duration::from_secs(1), || true).await.unwrap());
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_panic_is_a_500_and_the_slot_comes_back() {
        let pool = WorkPool::new(PoolOptions { workers: 1, queue_depth: 0, retry_after_s: 1 });
        let e = pool.run(Duration::from_secs(5), || -> u8 { panic!("planted") }).await.unwrap_err();
        assert_eq!(e.status, 500);
        assert_eq!(pool.depth(), 0);
        assert_eq!(pool.run(Duration::from_secs(5), || 3).await.unwrap(), 3);
    }
}
